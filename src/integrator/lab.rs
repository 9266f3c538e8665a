//! The lab's stages, with mirror and glass followed Whitted-style.
//!
//! For each batch of camera rays: all closest hits; every diffuse hit is shaded as the stage
//! says ([`HitTerms`]); every mirror or glass hit spawns its specular branches
//! ([`Material::specular_branches`]), each carrying its weight (the tint, or Fresnel's F and
//! 1 − F), which are traced the same way, up to [`Shading::specular_depth`] specular hits in a
//! row. A branch that goes deeper, or leaves the scene, adds nothing (black).
//!
//! In the lab's all-diffuse box every camera ray ends at its first hit with weight 1, and the
//! value is exactly the lab's (1 · x = x, 0 + x = x): sample 0 is the lab's image bit for bit.
//!
//! [`Material::specular_branches`]: crate::material::Material::specular_branches
//! [`Shading::specular_depth`]: super::Shading::specular_depth

use glam::Vec3;

use super::{BATCH, HitTerms, Tracer, cast_shadow_rays};
use crate::geometry::Ray;
use crate::intersect::Intersection;
use crate::light::SHADOW_OFFSET;

/// A ray to trace and where its value goes.
#[derive(Clone, Copy, Debug)]
struct Item {
    ray: Ray,
    /// Index of the output value (the camera ray) within the batch.
    pixel: u16,
    /// What the value found is multiplied by: 1 for a camera ray, the product of the
    /// specular weights along a branch.
    weight: Vec3,
    /// Specular hits so far along this branch.
    depth: u32,
}

/// The value of every ray, into `out`.
pub(super) fn trace(tracer: &Tracer, rays: &[Ray], out: &mut [Vec3]) {
    let mut branches = Vec::new();
    for (rays, out) in rays.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
        out.fill(Vec3::ZERO);
        let mut items = [Item {
            ray: rays[0],
            pixel: 0,
            weight: Vec3::ONE,
            depth: 0,
        }; BATCH];
        for (i, (item, ray)) in items.iter_mut().zip(rays).enumerate() {
            item.ray = *ray;
            item.pixel = i as u16;
        }
        wave(tracer, &items[..rays.len()], out, &mut branches);
        // Mirror and glass: trace the branches, wave after wave, until none is left.
        while !branches.is_empty() {
            let current = std::mem::take(&mut branches);
            for chunk in current.chunks(BATCH) {
                wave(tracer, chunk, out, &mut branches);
            }
        }
    }
}

/// One phase-batched step for up to [`BATCH`] items: closest hits, the lab's terms at the
/// diffuse hits, their shadow rays, the sums into `out`; the specular hits' branches go to
/// `branches`.
fn wave(tracer: &Tracer, items: &[Item], out: &mut [Vec3], branches: &mut Vec<Item>) {
    debug_assert!(items.len() <= BATCH);
    let scene = tracer.scene;
    let shading = &tracer.shading;
    let mut hits: [Option<Intersection>; BATCH] = [None; BATCH];
    for (hit, item) in hits.iter_mut().zip(items) {
        *hit = scene.closest_intersection(&item.ray, f32::INFINITY);
    }
    // The diffuse hits' terms, and which item each belongs to.
    let mut terms = [HitTerms {
        position: Vec3::ZERO,
        normal: Vec3::ZERO,
        rho: Vec3::ZERO,
        d: Vec3::ZERO,
        shadow_ray: None,
        blocked: false,
    }; BATCH];
    let mut owner = [0u8; BATCH];
    let mut n = 0;
    for (i, (hit, item)) in hits.iter().zip(items).enumerate() {
        let Some(hit) = hit else { continue };
        let material = tracer.material_of(hit.triangle_index);
        let normal = scene.triangles[hit.triangle_index].normal;
        if material.is_diffuse() {
            terms[n] = HitTerms::at(
                &tracer.light,
                shading.stage,
                shading.shadows,
                hit.position,
                normal,
                material.reflectance,
            );
            owner[n] = i as u8;
            n += 1;
        } else if item.depth < shading.specular_depth {
            let d = item.ray.direction;
            for &(direction, weight) in material.specular_branches(d, normal).as_slice() {
                branches.push(Item {
                    ray: continue_ray(hit.position, normal, direction),
                    pixel: item.pixel,
                    weight: item.weight * weight,
                    depth: item.depth + 1,
                });
            }
        }
    }
    cast_shadow_rays(scene, &mut terms[..n]);
    let indirect = shading.indirect_term();
    for (t, &i) in terms[..n].iter().zip(&owner) {
        let item = &items[i as usize];
        out[item.pixel as usize] += item.weight * t.value(shading.stage, indirect);
    }
}

/// A ray leaving a surface point along `direction`, started [`SHADOW_OFFSET`] off the surface
/// on the side it leaves by, so it cannot hit the surface it leaves.
pub(crate) fn continue_ray(position: Vec3, normal: Vec3, direction: Vec3) -> Ray {
    let side = if direction.dot(normal) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    Ray {
        origin: position + side * SHADOW_OFFSET * normal,
        direction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RenderSettings;
    use crate::material::MaterialPreset;
    use crate::render::render;
    use crate::scene::cornell_box;
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
                let r = continue_ray(hit.position, n, crate::material::reflect(ray.direction, n));
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
