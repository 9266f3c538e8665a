//! The lab's stages, with mirror and glass followed Whitted-style.
//!
//! For each batch of camera rays: all closest hits; every diffuse hit is shaded as the stage
//! says, sixteen hits at a time ([`super::Lighting::at`], the code behind
//! [`super::HitTerms::at`], through [`DiffuseHits`]); every mirror or glass hit spawns its
//! specular branches ([`Material::specular_branches`]), each carrying its weight (the tint, or Fresnel's F and
//! 1 − F), which are traced the same way, up to [`Shading::specular_depth`] specular hits in a
//! row. A branch that goes deeper, or leaves the scene, adds nothing (black).
//!
//! A rough metal is shaded as a diffuse surface whose ρ is π·f(wo, wi) toward the light's
//! centre ([`super::Tracer::glossy_reflectance`]): its highlight under the lab's light.
//!
//! In the lab's all-diffuse box every camera ray ends at its first hit with weight 1, and the
//! value is exactly the lab's (1 · x = x, 0 + x = x): sample 0 is the lab's image bit for bit.
//!
//! [`Material::specular_branches`]: crate::shading::material::Material::specular_branches
//! [`Shading::specular_depth`]: super::Shading::specular_depth

use glam::Vec3;

use super::hits::lanes_of;
use super::{BATCH, GROUPS, HitScratch, Recorder, Tracer, continue_ray, shaded_value};
use crate::base::geometry::Ray;
use crate::base::lanes::{LANES, M16, Vec3x16, Vector};
use crate::base::sampling::Rng;
use crate::shapes::accel::HitLanes;
use crate::shapes::accel::lane_io::store_vec3s;
use crate::shapes::scene::intersection;

/// Where a specular branch's value goes and what it is multiplied by.
#[derive(Clone, Copy, Debug)]
struct Branch {
    /// Index of the output value (the camera ray) within the batch.
    pixel: u16,
    /// The product of the specular weights along the branch.
    weight: Vec3,
    /// Specular hits so far along the branch.
    depth: u32,
}

/// The camera rays of a batch, or specular branches with where their values go.
#[derive(Clone, Copy)]
enum Wave<'a> {
    /// Camera rays: ray `i` is pixel `i`, weight 1, depth 0.
    Camera,
    Branches(&'a [Branch]),
}

/// The value of every ray, into `out`; each step told to `rec` ([`Recorder`]). The batches
/// work in `scratch`.
#[inline(always)]
pub(super) fn trace<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    scratch: &mut HitScratch<GROUPS>,
    rec: &mut R,
) {
    let (mut rays_next, mut branches_next) = (Vec::new(), Vec::new());
    for (c, (rays, out)) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)).enumerate() {
        out.fill(Vec3::ZERO);
        // Each camera ray's generator (its branches draw from it too); none if nothing is
        // random.
        let start = (c * BATCH).min(rngs.len());
        let end = (start + BATCH).min(rngs.len());
        let rngs = &mut rngs[start..end];
        let next = (&mut rays_next, &mut branches_next);
        wave_for_light(tracer, rays, Wave::Camera, rngs, out, next, scratch, rec);
        // Mirror and glass: trace the branches, wave after wave, until none is left.
        while !rays_next.is_empty() {
            let rays = std::mem::take(&mut rays_next);
            let branches = std::mem::take(&mut branches_next);
            for (rays, branches) in rays.chunks(BATCH).zip(branches.chunks(BATCH)) {
                let next = (&mut rays_next, &mut branches_next);
                let wave = Wave::Branches(branches);
                wave_for_light(tracer, rays, wave, rngs, out, next, scratch, rec);
            }
        }
    }
}

/// [`wave`] for the scene's light: compiled apart for the lab's point light, whose loop then
/// carries no random numbers at all (drawing them is work the point light never needs).
#[inline(always)]
#[allow(clippy::too_many_arguments)] // `wave`'s
fn wave_for_light<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    wave_kind: Wave,
    rngs: &mut [Rng],
    out: &mut [Vec3],
    next: (&mut Vec<Ray>, &mut Vec<Branch>),
    scratch: &mut HitScratch<GROUPS>,
    rec: &mut R,
) {
    if tracer.light.is_area() {
        wave::<true, R>(tracer, rays, wave_kind, rngs, out, next, scratch, rec);
    } else {
        wave::<false, R>(tracer, rays, wave_kind, rngs, out, next, scratch, rec);
    }
}

/// One phase-batched step for up to [`BATCH`] rays: closest hits, the lab's terms at the
/// diffuse hits (sixteen at a time), their shadow rays, the sums into `out`; the specular hits'
/// branches go to `next`. Each step is told to `rec` (nothing is, for `()`).
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the rays and what they are, their generators, where
// their values and next rays go, the working memory: each borrowed apart
fn wave<const SPHERE_LIGHT: bool, R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    wave: Wave,
    rngs: &mut [Rng],
    out: &mut [Vec3],
    next: (&mut Vec<Ray>, &mut Vec<Branch>),
    scratch: &mut HitScratch<GROUPS>,
    rec: &mut R,
) {
    debug_assert!(rays.len() <= BATCH);
    let scene = tracer.scene;
    let shading = &tracer.shading;
    // The structure's hits in lanes, each made an `Intersection` only where it is used.
    let groups = rays.len().div_ceil(LANES);
    let mut hits = [HitLanes::new(f32::INFINITY); GROUPS];
    scene.closest_hit_lanes(rays, f32::INFINITY, &mut hits[..groups]);
    let HitScratch { diffuse, lit } = scratch;
    diffuse.clear();
    // Where the tracer is plain, the diffuse hits' surfaces are made sixteen at a time; the
    // other hits (all of them when recording, or where surfaces are textured or smooth) one
    // at a time, below.
    let mut one_at_a_time = [u16::MAX; GROUPS];
    if tracer.plain && !R::ENABLED {
        for (g, lanes) in one_at_a_time.iter_mut().enumerate().take(groups) {
            let rays = &rays[g * LANES..rays.len().min((g + 1) * LANES)];
            *lanes = diffuse.fill_plain(g, tracer, shading.shadows, rays, &hits[g]);
        }
    }
    let one_at_a_time = one_at_a_time
        .iter()
        .enumerate()
        .take(groups)
        .flat_map(|(g, &lanes)| lanes_of(lanes).map(move |lane| g * LANES + lane))
        .take_while(|&i| i < rays.len());
    for i in one_at_a_time {
        let ray = &rays[i];
        let hit = hits[i / LANES]
            .get(i % LANES)
            .map(|hit| intersection(ray, hit));
        if R::ENABLED {
            let (weight, depth) = match wave {
                Wave::Camera => (Vec3::ONE, 0),
                Wave::Branches(b) => (b[i].weight, b[i].depth),
            };
            rec.closest_hit(ray, hit.as_ref(), weight, depth);
        }
        let Some(hit) = &hit else { continue };
        let material = tracer.material_of(hit.triangle_index);
        if material.is_diffuse() {
            diffuse.push(i, tracer.surface(hit, material, ray.direction), i);
            continue;
        }
        if !material.is_specular() {
            // A glossy surface (the rough metal): shaded as the lab shades a diffuse one,
            // with π·f toward the light's centre in place of ρ (ρ = π·f for a diffuse
            // surface), so equation 28 gives its highlight: π·f·D.
            let mut surface = tracer.surface(hit, material, ray.direction);
            surface.rho = tracer.glossy_reflectance(material, &surface, ray.direction);
            diffuse.push(i, surface, i);
            continue;
        }
        // Mirror and glass reflect about the triangle's own normal, or a relief's bent one (the
        // water's waves).
        let normal = tracer.specular_normal(hit, material, ray.direction);
        let branch = match wave {
            Wave::Camera => Branch {
                pixel: i as u16,
                weight: Vec3::ONE,
                depth: 0,
            },
            Wave::Branches(b) => b[i],
        };
        if branch.depth < shading.specular_depth {
            let d = ray.direction;
            let branches = material.specular_branches(d, normal);
            if R::ENABLED {
                rec.specular_hit(hit, branch.weight, branch.depth, branches.as_slice());
            }
            let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, d);
            for &(direction, weight) in branches.as_slice() {
                next.0
                    .push(continue_ray(hit.position, normal, direction, at_edge));
                next.1.push(Branch {
                    pixel: branch.pixel,
                    weight: branch.weight * weight,
                    depth: branch.depth + 1,
                });
            }
        } else if R::ENABLED {
            rec.specular_hit(hit, branch.weight, branch.depth, &[]);
        }
    }
    // The light at the diffuse hits, sixteen at a time, in the order of the hits (a spherical
    // light draws from each pixel's generator in that order), and their shadow rays, handed to
    // the tracer as the lanes they are in.
    let pixel_of = |i: u16| match wave {
        Wave::Camera => i as usize,
        Wave::Branches(b) => b[i as usize].pixel as usize,
    };
    diffuse.light::<SPHERE_LIGHT>(tracer, rngs, pixel_of, lit);
    // The hits of a wave are neighbouring pixels' (or their mirror images').
    let blocked = diffuse.blocked(scene, lit, true);
    let indirect = shading.indirect_term();
    let mut values = [Vec3x16::ZERO; BATCH / LANES];
    for (g, (_, surfaces)) in diffuse.groups().enumerate() {
        let blocked = M16::from_bits(blocked[g]);
        values[g] = shaded_value(
            shading.stage,
            surfaces.rho,
            lit[g].d,
            blocked,
            Vec3x16::splat(indirect),
        );
    }
    if let Wave::Camera = wave
        && !R::ENABLED
    {
        // Camera rays: each group's values straight into its sixteen pixels (0 where no
        // diffuse hit is: as `out` holds before the first wave), the last group's lane by lane
        // if the batch ends within it.
        let isa = scene.accel().isa();
        let mut pixels = out.chunks_exact_mut(LANES);
        for (g, pixels) in pixels.by_ref().enumerate() {
            let v = Vec3x16::select(M16::from_bits(diffuse.active[g]), values[g], Vec3x16::ZERO);
            let pixels: &mut [Vec3; LANES] = pixels.try_into().expect("sixteen pixels");
            store_vec3s(isa, &v.x.0, &v.y.0, &v.z.0, pixels);
        }
        let g = rays.len() / LANES;
        for (lane, pixel) in pixels.into_remainder().iter_mut().enumerate() {
            if diffuse.active[g] & (1 << lane) != 0 {
                *pixel = values[g].lane(lane);
            }
        }
        return;
    }
    let hits = (0..groups).flat_map(|g| diffuse.owners(g).map(move |(lane, i)| (g, lane, i)));
    for (g, lane, i) in hits {
        let value = values[g].lane(lane);
        // What the inspector is told: this hit's terms, as `HitTerms::at` gives them.
        let terms = || diffuse.terms(g, lane, &lit[g], blocked[g]);
        match wave {
            Wave::Camera => {
                if R::ENABLED {
                    rec.shaded(&terms(), indirect, value, Vec3::ONE);
                }
                out[i as usize] = value;
            }
            Wave::Branches(b) => {
                let b = &b[i as usize];
                if R::ENABLED {
                    rec.shaded(&terms(), indirect, value, b.weight);
                }
                out[b.pixel as usize] += b.weight * value;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RenderSettings;
    use crate::shading::material::MaterialPreset;
    use crate::shapes::scene::cornell_box;
    use crate::transport::render::render;
    use crate::{Shading, Stage};

    fn settings(stage: Stage, preset: MaterialPreset) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(64, 64);
        s.shading = Shading::for_stage(stage);
        s.material_preset = preset;
        s
    }

    /// The mirror preset in the flat stage: a mirror pixel shows 0.9 × the flat colour of what
    /// its reflected ray hits, found here by tracing that ray by hand.
    #[test]
    fn a_mirror_pixel_shows_its_reflection_times_its_tint() {
        let scene = cornell_box();
        let s = settings(Stage::Flat, MaterialPreset::Mirror);
        let image = render(&scene, &s);
        let mut mirror_pixels = 0;
        for y in 0..64 {
            for x in 0..64 {
                let ray = s.camera.pixel_ray(x, y);
                let Some(hit) = scene.closest_intersection(&ray, f32::INFINITY) else {
                    continue;
                };
                if scene.material_of(hit.triangle_index).name != "blue" {
                    continue;
                }
                mirror_pixels += 1;
                let n = scene.triangles[hit.triangle_index].normal;
                let at_edge =
                    scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, ray.direction);
                let reflected = crate::shading::material::reflect(ray.direction, n);
                let r = continue_ray(hit.position, n, reflected, at_edge);
                let seen = scene
                    .closest_intersection(&r, f32::INFINITY)
                    .map_or(Vec3::ZERO, |h| {
                        scene.material_of(h.triangle_index).reflectance
                    });
                let expected = Vec3::splat(0.9) * seen;
                assert_eq!(image.get(x, y), expected, "pixel ({x}, {y})");
            }
        }
        assert!(mirror_pixels > 200, "{mirror_pixels}");
    }

    /// Glass at depth 0 shows nothing (black); the default depth sees through it; the glass
    /// block's pixels are what the branches' weights make of the walls behind and around.
    #[test]
    fn specular_depth_bounds_the_branches() {
        let scene = cornell_box();
        let mut s = settings(Stage::Flat, MaterialPreset::Glass);
        s.shading.specular_depth = 0;
        let shallow = render(&scene, &s);
        s.shading.specular_depth = 6;
        let deep = render(&scene, &s);
        let lab = render(&scene, &settings(Stage::Flat, MaterialPreset::None));
        let mut glass = 0;
        for (i, ((a, b), l)) in shallow
            .pixels
            .iter()
            .zip(&deep.pixels)
            .zip(&lab.pixels)
            .enumerate()
        {
            if *l == Vec3::new(0.75, 0.15, 0.15) {
                // A red (glass) pixel: black at depth 0, lit by what is seen through it.
                glass += 1;
                assert_eq!(*a, Vec3::ZERO, "{i}");
                assert!(b.max_element() > 0.1, "{i}: {b}");
            } else {
                assert_eq!(a, l, "elsewhere nothing changes");
            }
        }
        assert!(glass > 100, "{glass}");
    }
}
