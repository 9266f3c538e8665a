//! The fixtures that tests and benchmarks share: the lab's and the path stage's settings at a
//! size, the camera's rays through every pixel ([`primary_rays`]) and the shadow rays the lab
//! stage casts from their hits ([`shadow_rays`]). Tests at every rung use them, so they live here
//! and not in [`crate::bench`], which measures.

use rayon::prelude::*;

pub use crate::base::camera::{primary_rays, try_primary_rays};
use crate::base::geometry::Ray;
use crate::base::memory::{AllocError, try_with_capacity};
use crate::shading::light::LightSpec;
use crate::shapes::scene::Scene;
use crate::transport::integrator::{HitTerms, Surface};
use crate::transport::settings::RenderSettings;
use crate::{Camera, Shading, Stage};
/// The lab stage at `width × height` from the default camera.
pub fn lab_settings(width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        camera: Camera::default_for(width, height),
        shading: Shading::for_stage(Stage::Lab),
        ..RenderSettings::default()
    }
}

/// The path stage at `width × height` from the default camera: what `--stage path` and
/// `--stage denoise` measure.
pub fn path_settings(width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        shading: Shading::for_stage(Stage::Path),
        ..lab_settings(width, height)
    }
}
/// The shadow rays the lab stage casts for these primary rays: from every hit that receives
/// light, [`crate::shading::light::shadow_ray`] towards the light, with its `t_max`.
pub fn shadow_rays(scene: &Scene, light: &LightSpec, primary: &[Ray]) -> Vec<(Ray, f32)> {
    primary
        .par_iter()
        .filter_map(|ray| shadow_ray_of(scene, light, ray))
        .collect()
}

/// [`shadow_rays`], reserved fallibly (room for one a primary ray), made a slice of rays at a
/// time so that no second full-size buffer is needed.
pub fn try_shadow_rays(
    scene: &Scene,
    light: &LightSpec,
    primary: &[Ray],
) -> Result<Vec<(Ray, f32)>, AllocError> {
    let mut rays = try_with_capacity(primary.len(), || {
        format!("the shadow rays of {} pixels", primary.len())
    })?;
    for slice in primary.chunks(1 << 16) {
        let part: Vec<(Ray, f32)> = slice
            .par_iter()
            .filter_map(|ray| shadow_ray_of(scene, light, ray))
            .collect();
        rays.extend(part);
    }
    Ok(rays)
}

/// The lab stage's shadow ray from where `ray` hits, if it hits a point the light reaches.
fn shadow_ray_of(scene: &Scene, light: &LightSpec, ray: &Ray) -> Option<(Ray, f32)> {
    let hit = scene.closest_intersection(ray, f32::INFINITY)?;
    let triangle = &scene.triangles[hit.triangle_index];
    let surface = Surface {
        position: hit.position,
        normal: triangle.normal,
        geometric: triangle.normal,
        rho: scene.material_of(hit.triangle_index).reflectance,
        at_edge: scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, ray.direction),
        relief_visibility: 1.0,
    };
    HitTerms::at(light, Stage::Lab, true, surface, |_| light.position).shadow_ray
}
