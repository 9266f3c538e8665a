//! Caustic photons: shot from the light, traced through mirror and glass, stored where they
//! land on a diffuse (non-delta) surface after at least one specular bounce — Heckbert's
//! L S+ D paths, the light a path tracer never finds through a mirror or glass from a point
//! light. The map they make ([`PhotonMap`]) is gathered by the path tracer ([`super::path_mis`])
//! at every diffuse hit of each camera path.
//!
//! **Emission.** Each photon leaves the light along [`Light::sample_le`], which draws rays in
//! proportion to the light's emission, so each of the N photons of a pass carries P/N per
//! channel ([`photon_power`]). At a mirror or glass surface the photon goes on along the
//! BSDF's own sample ([`ShadingFrame::sample_world`], the path tracer's code), its power
//! multiplied by the sample's weight: the mirror's tint, or glass's 1 (reflection, chosen with
//! probability F) or tint (refraction, with probability 1 − F). Glass's radiance factor η² is
//! not applied: it belongs to radiance, not to power (and raylab's glass leaves it out for
//! radiance too, see [`crate::shading::bsdf`]).
//!
//! **Determinism.** Photons are shot in chunks of [`CHUNK`], each chunk's numbers from its own
//! generator seeded by (seed, pass, chunk index), the chunks traced in parallel and
//! concatenated in chunk order: the same map whatever the thread count. The grid is built from
//! that order ([`crate::transport::photon_map::HashGrid`]).

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::{Scattering, Tracer, continue_ray};
use crate::base::geometry::Ray;
use crate::base::sampling::Rng;
use crate::shading::light::{AnyLight, Light};
use crate::shapes::scene::Scene;
use crate::transport::photon_map::{Photon, PhotonMap, radius_at_pass};

/// Photons shot from one generator: the unit of parallel work and of determinism.
pub const CHUNK: u32 = 4096;

/// The most mirror and glass hits a photon passes before it is given up (between two facing
/// mirrors it could bounce for ever).
pub const MAX_SPECULAR_HITS: u32 = 32;

/// Pass 0's gather radius as a share of the scene's bounding-box diagonal: 0.035 in the lab's
/// box (diagonal 2√3), a few pixels wide at 256², about a hundred caustic photons in a disc
/// under the glass block at 100,000 photons a pass.
pub const INITIAL_RADIUS_SHARE: f32 = 0.01;

/// The row index the photon generators take in [`Rng::for_pixel_sample`]'s (pixel, sample)
/// key: no image has a row this far down, so no photon stream is a pixel's.
const PHOTON_ROW: u32 = u32::MAX;

/// The power each of `count` photons carries when it leaves `light`: P/N per channel.
pub fn photon_power(light: &AnyLight, count: u32) -> Vec3 {
    light.power() / count.max(1) as f32
}

/// Pass 0's gather radius for `scene` ([`INITIAL_RADIUS_SHARE`] of its bounding-box
/// diagonal; the lab box's for an empty scene).
pub fn initial_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.triangles.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), t| {
            (
                lo.min(t.v0.min(t.v1.min(t.v2))),
                hi.max(t.v0.max(t.v1.max(t.v2))),
            )
        },
    );
    let diagonal = (hi - lo).length();
    let diagonal = if diagonal > 0.0 && diagonal.is_finite() {
        diagonal
    } else {
        2.0 * 3f32.sqrt()
    };
    INITIAL_RADIUS_SHARE * diagonal
}

/// The rays of chunk `chunk` of `count` photons of pass `pass`, each with the power it leaves
/// with, handed to `each` with the chunk's generator (which the photon's tracing continues
/// with).
pub fn emit_chunk(
    light: &AnyLight,
    count: u32,
    seed: u64,
    pass: u32,
    chunk: u32,
    mut each: impl FnMut(Ray, Vec3, &mut Rng),
) {
    let power = photon_power(light, count);
    let first = chunk.saturating_mul(CHUNK);
    let n = CHUNK.min(count.saturating_sub(first));
    let mut rng = Rng::for_pixel_sample(seed, chunk, PHOTON_ROW, pass);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let v = Vec2::new(rng.next_f32(), rng.next_f32());
        if let Some(ray) = light.sample_le(u, v) {
            each(ray, power, &mut rng);
        }
    }
}

/// Pass `pass`'s caustic photon map: `count` photons from the tracer's light with the render's
/// `seed`, gathered with [`radius_at_pass`] of [`initial_radius`].
pub fn shoot(tracer: &Tracer, count: u32, seed: u64, pass: u32) -> PhotonMap {
    let light = *tracer.emitter();
    let chunks = count.div_ceil(CHUNK);
    let stored: Vec<Vec<Photon>> = (0..chunks)
        .into_par_iter()
        .map(|chunk| {
            let mut out = Vec::new();
            emit_chunk(&light, count, seed, pass, chunk, |ray, power, rng| {
                trace_photon(tracer, ray, power, rng, &mut out);
            });
            out
        })
        .collect();
    let radius = radius_at_pass(initial_radius(tracer.scene), pass);
    PhotonMap::new(stored.concat(), u64::from(count), radius)
}

/// Follows one photon from the light through mirror and glass; stores it in `out` where it
/// first meets a non-delta surface, if it passed at least one mirror or glass surface before
/// (a photon straight from the light is direct light, which the path tracer's light samples
/// already count).
pub fn trace_photon(
    tracer: &Tracer,
    mut ray: Ray,
    mut power: Vec3,
    rng: &mut Rng,
    out: &mut Vec<Photon>,
) {
    let scene = tracer.scene;
    let light = tracer.emitter();
    for specular_hits in 0..=MAX_SPECULAR_HITS {
        let Some(hit) = scene.closest_intersection(&ray, f32::INFINITY) else {
            return;
        };
        // After a bounce the photon may meet the emitter itself, which is opaque (as a path
        // meeting it ends). Its first ray leaves the emitter and cannot.
        if specular_hits > 0 && light.intersect(&ray, hit.distance).is_some() {
            return;
        }
        let Scattering {
            surface,
            bsdf,
            frame,
            wo,
        } = tracer.scattering(&hit, ray.direction);
        let at_edge = surface.at_edge;
        if !bsdf.is_delta() {
            if specular_hits > 0 {
                out.push(Photon {
                    position: hit.position,
                    wi: wo,
                    normal: frame.geometric_normal(),
                    power,
                });
            }
            return;
        }
        let uc = rng.next_f32();
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let Some(sample) = frame.sample_world(&bsdf, wo, uc, u) else {
            return;
        };
        power *= sample.weight;
        if power == Vec3::ZERO {
            return;
        }
        ray = continue_ray(hit.position, surface.geometric, sample.wi, at_edge);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::geometry::Triangle;
    use crate::shading::material::{Material, MaterialKind, MaterialPreset};
    use crate::shapes::scene::cornell_box;
    use crate::transport::settings::{Caustics, RenderSettings, Shading, Stage};

    fn caustic_settings(preset: MaterialPreset) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.shading = Shading {
            caustics: Caustics::Photons,
            ..Shading::for_stage(Stage::Path)
        };
        s.material_preset = preset;
        s
    }

    /// Before any bounce the photons of a pass carry the light's power between them: Σ Φ = P
    /// per channel (14 × the colour (1, 0.5, 0.25)) for each light shape, at a count that is
    /// not a whole number of chunks.
    #[test]
    fn the_photons_carry_the_lights_power() {
        let mut s = caustic_settings(MaterialPreset::Glass);
        s.light.colour = Vec3::new(1.0, 0.5, 0.25);
        use crate::shading::light::LightShape;
        for shape in LightShape::ALL {
            s.light.kind = crate::shading::light::LightKind::sized(shape, 0.2);
            let light = s.light.emitter();
            let count = 3 * CHUNK + 123;
            let (mut sum, mut n) = ([0f64; 3], 0u32);
            for chunk in 0..count.div_ceil(CHUNK) {
                emit_chunk(&light, count, 5, 2, chunk, |_, power, _| {
                    for (c, p) in sum.iter_mut().zip(power.to_array()) {
                        *c += f64::from(p);
                    }
                    n += 1;
                });
            }
            assert_eq!(n, count, "{shape}");
            // The spot sends its intensity into its cone only: its power is less than P.
            let expected = match shape {
                LightShape::Spot => light.power(),
                LightShape::Point | LightShape::Sphere | LightShape::Quad => {
                    Vec3::new(14.0, 7.0, 3.5)
                }
            };
            for (c, p) in sum.iter().zip(expected.to_array().map(f64::from)) {
                assert!((c - p).abs() < 1e-5 * p, "{shape}: {sum:?}");
            }
        }
    }

    /// A photon from the lab's point light meets a mirror floor (reflectance 0.9, the mirror
    /// preset's) and lands on a white diffuse ceiling: it is stored there with 0.9 of the
    /// power it left with, coming from below. Photons straight from the light onto the
    /// ceiling are not stored (direct light).
    #[test]
    fn a_photon_off_a_mirror_keeps_the_mirrors_reflectance() {
        let square = |y: f32, m: u32| {
            let (a, b, c, d) = (
                Vec3::new(-5.0, y, -5.0),
                Vec3::new(5.0, y, -5.0),
                Vec3::new(5.0, y, 5.0),
                Vec3::new(-5.0, y, 5.0),
            );
            [Triangle::new(a, b, c, m), Triangle::new(a, c, d, m)]
        };
        let mut triangles = square(1.0, 0).to_vec();
        triangles.extend(square(-1.0, 1));
        let mut mirror = Material::diffuse("mirror", Vec3::ONE);
        mirror.kind = MaterialKind::Mirror {
            tint: Vec3::splat(0.9),
        };
        let scene = Scene::new(
            triangles,
            vec![mirror, Material::diffuse("ceiling", Vec3::ONE)],
        );
        let s = caustic_settings(MaterialPreset::None);
        let tracer = Tracer::new(&scene, &s);
        let map = shoot(&tracer, 20_000, 1, 0);
        let leaving = photon_power(tracer.emitter(), 20_000);
        assert!(
            map.photons().len() > 4_000,
            "half go down, most onto the mirror: {}",
            map.photons().len()
        );
        for p in map.photons() {
            assert_eq!(p.power, leaving * 0.9);
            assert!((p.position.y + 1.0).abs() < 1e-4, "{}", p.position);
            assert!(p.wi.y > 0.0 && p.normal == Vec3::Y, "{p:?}");
        }
    }

    /// The same settings and seed make the same map on one thread and on two, photon for
    /// photon; another pass makes another.
    #[test]
    fn the_map_is_the_same_on_any_thread_count() {
        let scene = cornell_box();
        let s = caustic_settings(MaterialPreset::Both);
        let tracer = Tracer::new(&scene, &s);
        let maps: Vec<PhotonMap> = [1, 2]
            .into_iter()
            .map(|threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| shoot(&tracer, 30_000, 4, 3))
            })
            .collect();
        assert!(maps[0].photons().len() > 1_000, "{:?}", maps[0]);
        assert_eq!(maps[0].photons(), maps[1].photons());
        assert_ne!(shoot(&tracer, 30_000, 4, 4).photons(), maps[0].photons());
    }
}
