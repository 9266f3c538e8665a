//! The feature buffers that steer the denoiser: what the camera sees at each pixel, apart from
//! the light. Per pixel, the albedo (the reflectance the light is multiplied by), the shading
//! normal and the distance to the surface, each averaged over [`FEATURE_SAMPLES`] camera rays.
//!
//! The path tracer records them as it traces, from every sample of the image at no extra ray
//! ([`Features::recorded`], from a [`Film::with_features`]): those of 64 samples steer the
//! denoiser at least as well as features traced apart (PERFORMANCE.md, "The denoiser", gives
//! the quality). For the other integrators they are traced apart ([`Features::trace`]),
//! from the render's own first camera samples ([`crate::transport::render`]'s `camera_sample`: the pixel
//! centre, then jittered points and, with an aperture, points of the lens). Either way a
//! feature blurred by depth of field or shared by two surfaces at an edge is blurred as the
//! image is. Through a mirror or glass the features are those of the first surface that is not
//! a perfect specular one ([`Seen`]), its albedo times the tints on the way and its distance
//! the length of the whole path, as Open Image Denoise asks of its auxiliary images: a mirror
//! then shows the features of what it reflects, and the filter keeps its edges. At glass both
//! branches are followed, with Fresnel's weights ([`Tracer::seen_through_specular`]), traced
//! apart and recorded alike: the features are those the samples see on average, without the
//! noise of the lobe each sample took, which is in step with the colour's and which the filter
//! could not tell from detail.

use glam::Vec3;
use rayon::prelude::*;

use crate::base::geometry::Ray;
use crate::base::sampling::Rng;
use crate::shading::bsdf::Bsdf;
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::Scene;
use crate::transport::film::{Film, Seen, SeenSum};
use crate::transport::integrator::{BATCH, Tracer};
use crate::transport::render::{Cancelled, camera_sample};
use crate::transport::settings::RenderSettings;

/// Camera rays per pixel the features average: enough to give an edge pixel the mix of the two
/// surfaces it shows, few enough to cost a fraction of one path-traced pass.
pub const FEATURE_SAMPLES: u32 = 16;

/// The per-pixel features of one view, rows top to bottom as in [`crate::transport::film::Image`].
#[derive(Clone, Debug, PartialEq)]
pub struct Features {
    pub width: u32,
    pub height: u32,
    /// The reflectance ρ of the surface seen (times the tints of mirrors and glass before it),
    /// averaged; 0 where nothing is hit.
    pub albedo: Vec<Vec3>,
    /// The shading normal (smooth, normal-mapped) facing the viewer, averaged over the samples
    /// that hit (not renormalised: an edge pixel's is shorter); 0 where nothing is hit.
    pub normal: Vec<Vec3>,
    /// The distance along the path to the surface seen, averaged over the samples that hit; 0
    /// where nothing is hit.
    pub depth: Vec<f32>,
}

impl Features {
    /// The features of `settings`' view of `scene`, traced on the current rayon pool, a row at
    /// a time; [`Cancelled`] as soon as `cancelled()` says so.
    pub fn trace(
        scene: &Scene,
        settings: &RenderSettings,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<Features, Cancelled> {
        Self::trace_samples(scene, settings, FEATURE_SAMPLES, cancelled)
    }

    /// [`Features::trace`] averaging `samples` camera rays a pixel (at least 1).
    pub fn trace_samples(
        scene: &Scene,
        settings: &RenderSettings,
        samples: u32,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<Features, Cancelled> {
        let samples = samples.max(1);
        let (width, height) = (settings.camera.width, settings.camera.height);
        let tracer = Tracer::new(scene, settings);
        let rotation = settings.camera.rotation();
        let len = width as usize * height as usize;
        let mut albedo = vec![Vec3::ZERO; len];
        let mut normal = vec![Vec3::ZERO; len];
        let mut depth = vec![0.0f32; len];
        let row = width.max(1) as usize;
        albedo
            .par_chunks_mut(row)
            .zip(normal.par_chunks_mut(row))
            .zip(depth.par_chunks_mut(row))
            .enumerate()
            .try_for_each(|(y, ((albedo, normal), depth))| {
                if cancelled() {
                    return Err(Cancelled);
                }
                let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); BATCH];
                let mut first: [Option<Intersection>; BATCH] = [None; BATCH];
                // A stretch of the row at a time, sample by sample: its camera rays are traced
                // together (neighbouring rays from one point, which the flat list culls for);
                // each pixel still sums its samples in their order.
                for x0 in (0..albedo.len()).step_by(BATCH) {
                    let n = (albedo.len() - x0).min(BATCH);
                    let mut sums = [SeenSum::default(); BATCH];
                    for sample in 0..samples {
                        for (k, ray) in rays[..n].iter_mut().enumerate() {
                            let mut rng = Rng::UNUSED;
                            let (x, y) = ((x0 + k) as u32, y as u32);
                            camera_sample(
                                &tracer, settings, &rotation, x, y, sample, ray, &mut rng,
                            );
                        }
                        scene.closest_intersections(&rays[..n], f32::INFINITY, &mut first[..n]);
                        for k in 0..n {
                            sums[k].add(see(&tracer, rays[k], first[k]));
                        }
                    }
                    for (k, sum) in sums[..n].iter().enumerate() {
                        let x = x0 + k;
                        (albedo[x], normal[x], depth[x]) = average(sum, samples);
                    }
                }
                Ok(())
            })?;
        Ok(Features {
            width,
            height,
            albedo,
            normal,
            depth,
        })
    }

    /// The features the samples added to `film` saw (its first
    /// [`crate::transport::film::FEATURE_SAMPLES_RECORDED`]: [`Film::with_features`]), or `None` if it
    /// records none. The same averages as [`Features::trace_samples`] of as many samples,
    /// bit for bit.
    pub fn recorded(film: &Film) -> Option<Features> {
        let (sums, samples) = film.seen()?;
        let mut albedo = vec![Vec3::ZERO; sums.len()];
        let mut normal = vec![Vec3::ZERO; sums.len()];
        let mut depth = vec![0.0f32; sums.len()];
        albedo
            .par_iter_mut()
            .zip(&mut normal)
            .zip(&mut depth)
            .zip(sums)
            .for_each(|(((a, n), d), sum)| (*a, *n, *d) = average(sum, samples));
        Some(Features {
            width: film.width(),
            height: film.height(),
            albedo,
            normal,
            depth,
        })
    }

    /// Whether features traced for `traced_for` are those of `wanted` too, so a job can keep
    /// them: the two settings may differ only in what the features never look at — the
    /// light's position, power and colour (the features are what the camera sees, not how it
    /// is lit), the samples to take, the display and the denoise switch. Anything else (the
    /// camera, the seed, the materials, the light's shape, which decides whether the camera's
    /// samples draw from the path's generator) counts as a new view. Of the same scene: the
    /// caller compares the scenes.
    pub fn serve(traced_for: &RenderSettings, wanted: &RenderSettings) -> bool {
        let mut lit_alike = wanted.clone();
        lit_alike.light.position = traced_for.light.position;
        lit_alike.light.power = traced_for.light.power;
        lit_alike.light.colour = traced_for.light.colour;
        lit_alike.samples_per_pixel = traced_for.samples_per_pixel;
        lit_alike.display = traced_for.display;
        lit_alike.denoise = traced_for.denoise;
        lit_alike == *traced_for
    }

    /// Features of one value everywhere: for tests, and for images with nothing to trace.
    pub fn uniform(width: u32, height: u32, albedo: Vec3, normal: Vec3, depth: f32) -> Features {
        let len = width as usize * height as usize;
        Features {
            width,
            height,
            albedo: vec![albedo; len],
            normal: vec![normal; len],
            depth: vec![depth; len],
        }
    }
}

/// A pixel's features from the sums of `samples` samples: the albedo over every sample (0
/// where one hits nothing); the normal and depth over those that hit (0 if none did).
#[inline]
fn average(sum: &SeenSum, samples: u32) -> (Vec3, Vec3, f32) {
    let albedo = sum.albedo / samples.max(1) as f32;
    if sum.hits == 0 {
        return (albedo, Vec3::ZERO, 0.0);
    }
    let hits = sum.hits as f32;
    (albedo, sum.normal / hits, sum.depth / hits)
}

/// What the ray `ray` sees, `first` its own closest hit, found with its batch: the surface as
/// it is, or through a mirror or glass what every specular branch reaches
/// ([`Tracer::seen_through_specular`]); `None` if the ray leaves the scene.
fn see(tracer: &Tracer, ray: Ray, first: Option<Intersection>) -> Option<Seen> {
    let hit = first?;
    if tracer.material_of(hit.triangle_index).is_specular() {
        return tracer.seen_through_specular(ray, hit);
    }
    let scattering = tracer.scattering(&hit, ray.direction);
    let albedo = match scattering.bsdf {
        Bsdf::RoughConductor { tint, .. } => tint,
        Bsdf::Lambertian { .. } | Bsdf::Mirror { .. } | Bsdf::Glass { .. } | Bsdf::Plastic(_) => {
            scattering.surface.rho
        }
    };
    let normal = scattering.frame.shading_normal();
    Some(Seen::at(
        Vec3::ONE,
        albedo,
        normal,
        scattering.wo,
        hit.distance,
    ))
}
