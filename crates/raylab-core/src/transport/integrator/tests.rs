use glam::Vec3;

use super::tracer::Primary;
use super::*;
use crate::Camera;
use crate::base::geometry::Ray;
use crate::base::lanes::LANES;
use crate::base::lanes::{M16, Mask, Vec3x16, Vector};
use crate::base::sampling::Rng;
use crate::shading::light::LightKind;
use crate::shading::light::LightSpec;
use crate::shading::material::MaterialPreset;
use crate::shapes::accel::set::{Compiled, InstructionSet};
use crate::shapes::scene::cornell_box;
use crate::test_support::primary_rays;
use crate::transport::settings::RenderSettings;

#[test]
fn stages_parse_and_name_their_figures() {
    for stage in Stage::ALL {
        assert_eq!(stage.name().parse::<Stage>(), Ok(stage));
    }
    assert_eq!(
        Stage::LAB.map(|s| s.figure().unwrap()),
        [2, 3, 5, 6, 7],
        "the lab's figures"
    );
    assert_eq!(Stage::Path.figure(), None);
    assert!("phong".parse::<Stage>().unwrap_err().contains("phong"));
    assert_eq!(Shading::default().stage, Stage::Lab);
    assert!(Shading::default().shadows && Shading::default().indirect);
    assert_eq!(Shading::default().indirect_term(), Vec3::splat(0.5));
    // The path tracer replaces N by real bounces.
    assert_eq!(Shading::for_stage(Stage::Path).indirect_term(), Vec3::ZERO);
    assert_eq!(Shading::for_stage(Stage::Path).max_bounces(), u32::MAX);
}

#[test]
fn descriptions_follow_the_switches() {
    let none = MaterialPreset::None;
    let mut s = Shading::for_stage(Stage::Lab);
    assert_eq!(
        s.description(none),
        "ρ·(D + N) (eq. 30) with shadows (§5.1)"
    );
    s.shadows = false;
    s.indirect = false;
    assert_eq!(s.description(none), "ρ·D (eq. 28)");
    let mut p = Shading::for_stage(Stage::Path);
    assert!(p.description(none).contains("Russian roulette"));
    p.bounces = Some(2);
    assert!(p.description(none).contains("up to 2 bounces"));
    p.indirect = false;
    assert!(p.description(none).contains("direct light only"));
    assert!(
        Shading::for_stage(Stage::Lab)
            .description(MaterialPreset::Glass)
            .contains("Whitted")
    );
}

/// Hand-computed terms at the floor's centre (0, 1, 0) under the lab's light at
/// (0, −0.5, −0.7): r = (0, −1.5, −0.7), r² = 2.74, r̂·n̂ = 1.5/√2.74 = 0.906183, so
/// D = 14 · 0.906183 / (4π · 2.74) = 0.368454; green ρ = (0.15, 0.75, 0.15) gives
/// ρ·(D + N) = (0.130268, 0.651341, 0.130268).
#[test]
fn hit_terms_at_the_floor_centre() {
    let light = LightSpec::default();
    let floor = Vec3::new(0.0, -1.0, 0.0);
    let rho = Vec3::new(0.15, 0.75, 0.15);
    let p = Vec3::new(0.0, 1.0, 0.0);
    let surface = Surface {
        position: p,
        normal: floor,
        geometric: floor,
        rho,
        at_edge: None,
        relief_visibility: 1.0,
    };
    let t = HitTerms::at(&light, Stage::Lab, true, surface, |_| light.position);
    assert!(
        (t.d - Vec3::splat(0.368454)).abs().max_element() < 1e-6,
        "{}",
        t.d
    );
    assert!(t.shadow_ray.is_some());
    let v = t.value(Stage::Lab, Vec3::splat(0.5));
    assert!(
        (v - Vec3::new(0.130268, 0.651341, 0.130268))
            .abs()
            .max_element()
            < 1e-6
    );
    let blocked = HitTerms { blocked: true, ..t };
    assert_eq!(blocked.value(Stage::Lab, Vec3::splat(0.5)), rho * 0.5);
    assert_eq!(blocked.value(Stage::Incoming, Vec3::ZERO), Vec3::ZERO);
    // The flat stage computes no light at all.
    let flat = HitTerms::at(&light, Stage::Flat, true, surface, |_| light.position);
    assert_eq!((flat.d, flat.shadow_ray), (Vec3::ZERO, None));
    assert_eq!(flat.value(Stage::Flat, Vec3::ZERO), rho);
}

/// Hits of every kind the lanes must get right, each with its own lit point: anywhere in
/// the box, smooth normals (on the lit side and the unlit one), zero normals, at edges of
/// their triangles, the light within [`crate::shading::light::MIN_LIGHT_DISTANCE`] or exactly on the
/// point, behind the surface, and at infinity.
fn awkward_surfaces(light: &LightSpec) -> Vec<Surface> {
    let mut rng = Rng::for_pixel_sample(7, 3, 5, 0);
    let mut r = move || rng.next_f32() * 2.0 - 1.0;
    let mut surfaces = Vec::new();
    for i in 0..4096 {
        let mut position = Vec3::new(r(), r(), r());
        let geometric = Vec3::new(r(), r(), r()).normalize_or_zero();
        let mut normal = geometric;
        match i % 8 {
            // A smooth normal, sometimes turned far enough to face the light when the
            // surface itself does not.
            1 => normal = (geometric + Vec3::new(r(), r(), r())).normalize_or_zero(),
            // Within MIN_LIGHT_DISTANCE of the light, or on it.
            2 => position = light.position + 4e-4 * Vec3::new(r(), r(), r()),
            3 => position = light.position,
            // Just off the surface through the light, on either side.
            4 => position = light.position + 1e-4 * r() * geometric,
            5 => normal = Vec3::ZERO,
            6 if i % 64 == 6 => position = Vec3::new(f32::INFINITY, 0.0, r()),
            _ => {}
        }
        let at_edge = (i % 3 == 0).then(|| Vec3::new(r(), r(), r()).normalize_or_zero());
        surfaces.push(Surface {
            position,
            normal,
            geometric,
            rho: Vec3::new(r(), r(), r()).abs(),
            at_edge,
            relief_visibility: 1.0,
        });
    }
    surfaces
}

/// A stand-in for a spherical light's point ([`light_point`]) that depends on the hit, so
/// that the lanes must hand each its own.
fn sphere_point(light: &LightSpec, p: Vec3) -> Vec3 {
    light.position + 0.05 * p
}

/// [`Lighting::at`] sixteen at a time, with [`sphere_point`] for the lanes that want it.
#[inline(always)]
fn lit_lanes(
    light: &LightSpec,
    shading: &Shading,
    surfaces: &Surfaces<Vec3x16>,
    sphere: bool,
) -> (Lighting<Vec3x16>, M16) {
    let mut asked = M16::NONE;
    let lit = Lighting::at(
        light,
        shading.stage,
        shading.shadows,
        surfaces,
        |p, wanted| {
            asked = wanted;
            let mut target = Vec3x16::splat(light.position);
            if sphere {
                for k in 0..LANES {
                    target.set_lane(k, sphere_point(light, p.lane(k)));
                }
            }
            target
        },
    );
    (lit, asked)
}

/// [`lit_lanes`] compiled for each instruction set, as the lab's wave is.
struct LitLanes<'a> {
    light: &'a LightSpec,
    shading: &'a Shading,
    surfaces: &'a Surfaces<Vec3x16>,
    sphere: bool,
}

impl Compiled for LitLanes<'_> {
    type Output = (Lighting<Vec3x16>, M16);
    #[inline(always)]
    fn run<S: InstructionSet>(self, _set: S) -> Self::Output {
        lit_lanes(self.light, self.shading, self.surfaces, self.sphere)
    }
}

/// The lab's terms sixteen hits at a time ([`Lighting::at`] at [`Vec3x16`], as the lab's
/// wave computes them, compiled portably and for each instruction set the CPU has) equal
/// [`HitTerms::at`] one hit at a time, bit for bit: D, the shadow ray (whether it is cast,
/// its origin, direction and length), the value blocked or not, in every stage with shadows
/// on and off, for the lab's light, a coloured one and a spot, with a point light and with a
/// stand-in for a spherical one's points (asked for exactly where the one-hit code asks).
#[test]
fn sixteen_hits_at_a_time_equal_one_at_a_time() {
    let coloured = LightSpec {
        position: Vec3::new(0.3, 0.9, 0.2),
        power: 3.5,
        colour: Vec3::new(1.0, 0.25, 0.0),
        kind: LightKind::Point,
    };
    // A spot aimed so that the awkward surfaces lie in its beam, its falloff and outside.
    let spot = LightSpec {
        kind: LightKind::Spot(crate::shading::light::SpotCone {
            aim: Vec3::new(0.2, 1.0, 0.1),
            cutoff: 0.6,
            beam: 0.3,
        }),
        ..coloured
    };
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    // Every set this CPU runs, the portable one first.
    let builds = crate::shapes::accel::Isa::available_for_tests("sixteen_hits_at_a_time");
    let mut cast = 0;
    for light in [LightSpec::default(), coloured, spot] {
        let surfaces = awkward_surfaces(&light);
        for stage in Stage::LAB {
            for shadows in [false, true] {
                let mut shading = Shading::for_stage(stage);
                shading.shadows = shadows;
                let n = shading.indirect_term();
                for sphere in [false, true] {
                    for group in surfaces.chunks(LANES) {
                        let mut lanes = Surfaces::ZERO;
                        for (k, s) in group.iter().enumerate() {
                            lanes.set(k, *s);
                        }
                        for isa in &builds {
                            let build = isa.name();
                            let (lit, asked) = isa.call(LitLanes {
                                light: &light,
                                shading: &shading,
                                surfaces: &lanes,
                                sphere,
                            });
                            for (k, s) in group.iter().enumerate() {
                                let mut one_asked = false;
                                let one = HitTerms::at(&light, stage, shadows, *s, |p| {
                                    one_asked = true;
                                    if sphere {
                                        sphere_point(&light, p)
                                    } else {
                                        light.position
                                    }
                                });
                                let what = format!("{build} {stage} {shadows} {sphere} {s:?}");
                                assert_eq!(bits(lit.d.lane(k)), bits(one.d), "D: {what}");
                                let ray = lit.shadow.lane(k);
                                let ray_bits = |r: Option<(Ray, f32)>| {
                                    r.map(|(r, t)| (bits(r.origin), bits(r.direction), t.to_bits()))
                                };
                                assert_eq!(ray_bits(ray), ray_bits(one.shadow_ray), "{what}");
                                assert_eq!(asked.0[k], one_asked, "asked: {what}");
                                cast += usize::from(ray.is_some());
                                for blocked in [false, true] {
                                    let mut b = M16::NONE;
                                    b.0[k] = blocked;
                                    let value =
                                        shaded_value(stage, lanes.rho, lit.d, b, Vec3x16::splat(n));
                                    let one = HitTerms { blocked, ..one };
                                    assert_eq!(
                                        bits(value.lane(k)),
                                        bits(one.value(stage, n)),
                                        "value: {what} {blocked}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(cast > 10_000, "{cast}");
}

/// The code compiled for the CPU (AVX2 and FMA, or AVX-512 where the kernels use it) gives
/// bit for bit what the portable build gives, in every stage and with every preset (Rust
/// never fuses a multiply-add on its own).
#[test]
fn the_builds_for_the_cpu_equal_the_portable_one() {
    let scene = cornell_box();
    let rays = primary_rays(&Camera::default_for(40, 30));
    for preset in MaterialPreset::ALL {
        for stage in Stage::ALL {
            let mut settings = RenderSettings::default();
            settings.shading = Shading::for_stage(stage);
            settings.material_preset = preset;
            let tracer = Tracer::new(&scene, &settings);
            let rngs = || -> Vec<Rng> {
                (0..rays.len())
                    .map(|i| Rng::for_pixel_sample(4, i as u32, 1, 2))
                    .collect()
            };
            let mut fast = vec![Vec3::NAN; rays.len()];
            tracer.trace(&rays, &mut rngs(), &mut fast);
            let mut portable = vec![Vec3::NAN; rays.len()];
            tracer.trace_portable(&rays, &mut rngs(), &mut portable);
            let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&fast), bits(&portable), "{stage} {preset}");
        }
    }
}

/// A [`Scratch`] reused batch after batch, as a row's batches reuse it, holds whatever the
/// batches before left in it (other stages, other presets, more groups of hits than this
/// batch has): the values are bit for bit those traced with a fresh one.
#[test]
fn a_reused_scratch_gives_the_values_of_a_fresh_one() {
    let scene = cornell_box();
    let rays = primary_rays(&Camera::default_for(53, 29));
    let mut reused = Scratch::new();
    let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
        v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
    };
    for preset in [MaterialPreset::Both, MaterialPreset::None] {
        for stage in Stage::ALL {
            let mut settings = RenderSettings::default();
            settings.shading = Shading::for_stage(stage);
            settings.material_preset = preset;
            let tracer = Tracer::new(&scene, &settings);
            // Batches of 64, then of fewer: later groups keep an earlier batch's hits.
            for (c, rays) in rays.chunks(BATCH).chain(rays.chunks(23)).enumerate() {
                let rngs = || -> Vec<Rng> {
                    (0..rays.len())
                        .map(|i| Rng::for_pixel_sample(5, i as u32, c as u32, 1))
                        .collect()
                };
                let mut fresh = vec![Vec3::NAN; rays.len()];
                let mut again = vec![Vec3::NAN; rays.len()];
                let mut scratch = Scratch::new();
                let primary = Primary::Rays(rays);
                tracer.trace_for_cpu(primary, &mut rngs(), &mut fresh, &mut [], &mut scratch);
                tracer.trace_for_cpu(primary, &mut rngs(), &mut again, &mut [], &mut reused);
                assert_eq!(bits(&again), bits(&fresh), "{stage} {preset} batch {c}");
            }
        }
    }
}

/// One ray at a time gives bit for bit what a batch gives, in every stage, with and without
/// mirror and glass.
#[test]
fn one_ray_at_a_time_equals_the_batch() {
    let scene = cornell_box();
    let rays = primary_rays(&Camera::default_for(61, 47));
    for preset in [MaterialPreset::None, MaterialPreset::Both] {
        for stage in Stage::ALL {
            for shadows in [false, true] {
                let mut settings = RenderSettings::default();
                settings.shading = Shading::for_stage(stage);
                settings.shading.shadows = shadows;
                settings.material_preset = preset;
                let tracer = Tracer::new(&scene, &settings);
                let rng = |i: usize| Rng::for_pixel_sample(1, i as u32, 0, 0);
                let mut rngs: Vec<Rng> = (0..rays.len()).map(rng).collect();
                let mut out = vec![Vec3::NAN; rays.len()];
                tracer.trace(&rays, &mut rngs, &mut out);
                for (i, (ray, got)) in rays.iter().zip(&out).enumerate() {
                    let mut one = [Vec3::NAN];
                    tracer.trace(&[*ray], &mut [rng(i)], &mut one);
                    assert_eq!(
                        got.to_array().map(f32::to_bits),
                        one[0].to_array().map(f32::to_bits),
                        "{stage} {preset} pixel {i}"
                    );
                }
            }
        }
    }
}
/// Where rays leave surfaces, sixteen at a time, bit for bit [`continue_ray`] one at a
/// time: on either side, at edges and not, and leaving along the surface itself.
#[test]
fn departures_sixteen_at_a_time_equal_one_at_a_time() {
    let light = LightSpec::default();
    let surfaces = awkward_surfaces(&light);
    let mut rng = Rng::new(31);
    for chunk in surfaces.chunks(LANES) {
        let mut lanes = Surfaces::<Vec3x16>::ZERO;
        let mut directions = Vec3x16::ZERO;
        let mut one_at_a_time = Vec::new();
        for (i, s) in chunk.iter().enumerate() {
            let random = Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize_or_zero();
            // Every fourth along the surface: `direction · normal` is 0.
            let direction = if i % 4 == 0 {
                random.cross(s.geometric)
            } else {
                random
            };
            lanes.set(i, *s);
            directions.set_lane(i, direction);
            one_at_a_time.push(continue_ray(s.position, s.geometric, direction, s.at_edge));
        }
        let origins = departure_points(
            lanes.position,
            lanes.geometric,
            directions,
            lanes.near_edge,
            lanes.incoming,
        );
        for (i, ray) in one_at_a_time.iter().enumerate() {
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(origins.lane(i)), bits(ray.origin), "lane {i}");
            assert_eq!(bits(directions.lane(i)), bits(ray.direction));
        }
    }
}
