//! Measuring the tracer: what `raylab bench` and the criterion benchmarks report.
//!
//! For one scene at one resolution, on the current rayon pool:
//!
//! * `build_ms`: building the acceleration structure (median of a few builds);
//! * `primary_mrays_per_s`: closest hits of the default camera's rays through every pixel
//!   centre (rays made beforehand; only the tracing is timed);
//! * `shadow_mrays_per_s`: any-hit queries of the shadow rays the `lab` stage casts from those
//!   hits towards the light (the same rays as [`crate::shapes::scene::in_shadow`] casts);
//! * `lab_pass_ms`: one full [`render_pass`] of the `lab` stage (figure 7: primary rays,
//!   shadow rays and shading);
//! * with [`BenchConfig::path`]: `path_pass_ms` and `path_samples_per_s`, one full pass of the
//!   `path` stage (unlimited bounces with Russian roulette: camera paths per second), each
//!   timed pass a new sample index, so the paths differ from pass to pass.
//!
//! Every figure is the median over repeated passes, after a warm-up pass.

use std::time::{Duration, Instant};

use rayon::prelude::*;
use serde::Serialize;

use crate::base::geometry::Ray;
use crate::base::memory::AllocError;
use crate::shapes::accel::{Accel, AccelKind, Isa};
use crate::shapes::scene::Scene;
use crate::test_support::{lab_settings, path_settings, try_primary_rays, try_shadow_rays};
use crate::transport::integrator::BATCH;
use crate::transport::render::render_pass;
use crate::transport::settings::BASE_MEMORY;

/// What to measure.
#[derive(Clone, Copy, Debug)]
pub struct BenchConfig {
    pub width: u32,
    pub height: u32,
    /// Timed passes per figure (the median is reported).
    pub passes: usize,
    /// Also measure the path stage.
    pub path: bool,
}

impl Default for BenchConfig {
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            passes: 15,
            path: false,
        }
    }
}

/// The figures for one scene; serialised as `raylab bench --json` prints them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchReport {
    pub scene: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    /// The kernels measured (`avx512`, `avx2` or `scalar`).
    pub isa: String,
    pub build_ms: f64,
    pub primary_mrays_per_s: f64,
    pub shadow_mrays_per_s: f64,
    pub lab_pass_ms: f64,
    /// One pass of the path stage (with [`BenchConfig::path`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_pass_ms: Option<f64>,
    /// Camera paths per second of the path stage (with [`BenchConfig::path`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_samples_per_s: Option<f64>,
}

/// The median of some durations, in milliseconds.
pub fn median_ms(mut times: Vec<Duration>) -> f64 {
    if times.is_empty() {
        return 0.0;
    }
    times.sort_unstable();
    let n = times.len();
    let mid = if n % 2 == 1 {
        times[n / 2]
    } else {
        (times[n / 2 - 1] + times[n / 2]) / 2
    };
    mid.as_secs_f64() * 1e3
}

fn time<T>(f: impl FnOnce() -> T) -> (Duration, T) {
    let start = Instant::now();
    let out = f();
    (start.elapsed(), out)
}

/// The memory [`bench_scene`] needs at its peak, in bytes, besides the scene: the camera's rays
/// (24 bytes a pixel) and the shadow rays cast from their hits (28 bytes each, at most one a
/// pixel), which are made once and kept through every timed pass, and one pass's image (12
/// bytes a pixel): 64 bytes a pixel, plus [`BASE_MEMORY`]. At 16384 × 16384: 16.1 GiB.
pub fn memory_estimate(config: &BenchConfig) -> u64 {
    let pixels = u64::from(config.width) * u64::from(config.height);
    let per_pixel = (size_of::<Ray>() + size_of::<(Ray, f32)>() + size_of::<glam::Vec3>()) as u64;
    pixels * per_pixel + BASE_MEMORY
}

/// Closest hits of all `rays`, in parallel, in batches of [`BATCH`] as the integrators ask
/// (so coherent rays go as packets where the CPU traces packets); returns how many hit (so the
/// work is not optimised away).
pub fn trace_primary(scene: &Scene, rays: &[Ray]) -> usize {
    rays.par_chunks(1024)
        .map(|c| {
            let mut hits = [None; BATCH];
            c.chunks(BATCH)
                .map(|batch| {
                    let hits = &mut hits[..batch.len()];
                    scene.closest_intersections(batch, f32::INFINITY, hits);
                    hits.iter().filter(|h| h.is_some()).count()
                })
                .sum::<usize>()
        })
        .sum()
}

/// Any-hit queries of all `rays`, in parallel, in batches of [`BATCH`] as the integrators ask;
/// returns how many are blocked.
pub fn trace_shadow(scene: &Scene, rays: &[(Ray, f32)]) -> usize {
    rays.par_chunks(1024)
        .map(|c| {
            let mut blocked = [false; BATCH];
            c.chunks(BATCH)
                .map(|batch| {
                    let blocked = &mut blocked[..batch.len()];
                    scene.occluded_many(batch, blocked);
                    blocked.iter().filter(|&&b| b).count()
                })
                .sum::<usize>()
        })
        .sum()
}

/// Measures `scene` (whose structure was built with `kind` and `isa`) on the current rayon pool.
/// The rays it keeps are reserved fallibly: too large a `config` for the memory is an error
/// (see [`memory_estimate`]).
pub fn bench_scene(
    name: &str,
    scene: &Scene,
    kind: AccelKind,
    isa: Isa,
    config: &BenchConfig,
) -> Result<BenchReport, AllocError> {
    let passes = config.passes.max(1);
    let builds = if scene.triangles.len() > 100_000 {
        3
    } else {
        passes
    };
    let build_times: Vec<Duration> = (0..builds)
        .map(|_| Accel::build(&scene.triangles, kind, isa).build_time())
        .collect();

    let settings = lab_settings(config.width, config.height);
    let primary = try_primary_rays(&settings.camera)?;
    let shadow = try_shadow_rays(scene, &settings.light, &primary)?;
    let repeat = |f: &dyn Fn() -> usize| -> f64 {
        std::hint::black_box(f());
        median_ms(
            (0..passes)
                .map(|_| time(|| std::hint::black_box(f())).0)
                .collect(),
        )
    };
    let primary_ms = repeat(&|| trace_primary(scene, &primary));
    let shadow_ms = repeat(&|| trace_shadow(scene, &shadow));
    let lab_ms = repeat(&|| {
        render_pass(scene, &settings, 0, &|| false).map_or(0, |image| image.pixels.len())
    });
    let mrays = |n: usize, ms: f64| if ms > 0.0 { n as f64 / ms / 1e3 } else { 0.0 };
    let path_ms = config.path.then(|| {
        let path = path_settings(config.width, config.height);
        let pass = |sample: u32| {
            render_pass(scene, &path, sample, &|| false).map_or(0, |image| image.pixels.len())
        };
        std::hint::black_box(pass(1));
        median_ms(
            (0..passes)
                .map(|i| time(|| std::hint::black_box(pass(2 + i as u32))).0)
                .collect(),
        )
    });
    let pixels = config.width as usize * config.height as usize;
    Ok(BenchReport {
        scene: name.to_string(),
        triangles: scene.triangles.len(),
        width: config.width,
        height: config.height,
        threads: rayon::current_num_threads(),
        isa: isa.name().to_string(),
        build_ms: median_ms(build_times),
        primary_mrays_per_s: mrays(primary.len(), primary_ms),
        shadow_mrays_per_s: mrays(shadow.len(), shadow_ms),
        lab_pass_ms: lab_ms,
        path_pass_ms: path_ms,
        path_samples_per_s: path_ms.map(|ms| mrays(pixels, ms) * 1e6),
    })
}

// Incoherent rays: what the path tracer casts after the first bounce, for the peer benchmark
// (`cargo bench --bench peers`), which traces them with raylab and with another BVH library.

/// Diffuse bounce rays from the hits of `primary`: from every ray that hits, one direction
/// drawn with density cos θ / π about the hit triangle's normal turned to face the ray (as the
/// path tracer's diffuse bounces, [`crate::base::sampling::cosine_hemisphere_by_rejection`]), started
/// where the path tracer would start it ([`crate::transport::integrator::continue_ray`]). Rays that miss
/// cast nothing, so there may be fewer bounce rays than primary rays.
///
/// Deterministic: ray `i`'s direction comes from its own generator, started from `seed` and `i`
/// alone, so the set is the same on any number of threads.
pub fn bounce_rays(scene: &Scene, primary: &[Ray], seed: u64) -> Vec<Ray> {
    use crate::base::sampling::{Rng, cosine_hemisphere_by_rejection, hemisphere_around};
    primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, ray)| {
            let hit = scene.closest_intersection(ray, f32::INFINITY)?;
            let mut normal = scene.triangles[hit.triangle_index].normal;
            if normal == glam::Vec3::ZERO {
                return None;
            }
            if normal.dot(ray.direction) > 0.0 {
                normal = -normal;
            }
            let mut rng = Rng::for_pixel_sample(seed, i as u32, (i >> 32) as u32, 0);
            let local = cosine_hemisphere_by_rejection(&mut rng, true);
            let direction = hemisphere_around(normal, local);
            let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, ray.direction);
            Some(crate::transport::integrator::continue_ray(
                hit.position,
                normal,
                direction,
                at_edge,
            ))
        })
        .collect()
}

/// The box around every triangle of `scene` (its room, for the built-in scenes), as its lowest
/// and highest corners; zero for an empty scene.
pub fn scene_bounds(scene: &Scene) -> (glam::Vec3, glam::Vec3) {
    let mut corners = scene.triangles.iter().flat_map(|t| [t.v0, t.v1, t.v2]);
    let Some(first) = corners.next() else {
        return (glam::Vec3::ZERO, glam::Vec3::ZERO);
    };
    corners.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)))
}

/// `n` random rays inside the box from `lo` to `hi` (the room: [`scene_bounds`]): origins
/// uniform in the box shrunk by 1 % of its size on every side (so none starts on a wall),
/// directions uniform over the sphere. The most incoherent rays a scene can be asked about:
/// neighbours share neither origin nor direction. Deterministic in `seed`, whatever the threads.
pub fn random_rays_in_room(lo: glam::Vec3, hi: glam::Vec3, n: usize, seed: u64) -> Vec<Ray> {
    use crate::base::sampling::Rng;
    let margin = 0.01 * (hi - lo);
    let (lo, size) = (lo + margin, (hi - lo) - 2.0 * margin);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::for_pixel_sample(seed, i as u32, (i >> 32) as u32, 1);
            let origin =
                lo + size * glam::Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let z = 2.0 * rng.next_f32() - 1.0;
            let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (sin, cos) = phi.sin_cos();
            Ray::new(origin, glam::Vec3::new(r * cos, r * sin, z))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::cornell_box;
    use crate::test_support::{primary_rays, shadow_rays};

    #[test]
    fn medians() {
        let ms = |v: &[u64]| median_ms(v.iter().map(|&m| Duration::from_millis(m)).collect());
        assert_eq!(ms(&[5, 1, 3]), 3.0);
        assert_eq!(ms(&[4, 1, 3, 2]), 2.5);
        assert_eq!(ms(&[]), 0.0);
    }

    #[test]
    fn a_small_bench_reports_plausible_figures() {
        let scene = cornell_box();
        let config = BenchConfig {
            width: 32,
            height: 32,
            passes: 3,
            path: true,
        };
        let r = bench_scene(
            "cornell",
            &scene,
            AccelKind::Auto,
            crate::shapes::scene::best_isa(),
            &config,
        )
        .unwrap();
        assert_eq!(
            (r.scene.as_str(), r.triangles, r.width),
            ("cornell", 30, 32)
        );
        assert!(r.primary_mrays_per_s > 0.0 && r.shadow_mrays_per_s > 0.0);
        assert!(r.lab_pass_ms > 0.0 && r.build_ms >= 0.0);
        let path_ms = r.path_pass_ms.unwrap();
        let per_s = r.path_samples_per_s.unwrap();
        assert!((per_s - 1024.0 / (path_ms / 1e3)).abs() < 1e-6 * per_s);
        let json = serde_json::to_value(&r).unwrap();
        for key in [
            "scene",
            "triangles",
            "width",
            "height",
            "threads",
            "isa",
            "build_ms",
            "primary_mrays_per_s",
            "shadow_mrays_per_s",
            "lab_pass_ms",
            "path_pass_ms",
            "path_samples_per_s",
        ] {
            assert!(json.get(key).is_some(), "{key}");
        }
    }

    #[test]
    fn shadow_rays_match_the_lab_pass() {
        // Every shadow ray starts at a lit-facing hit and ends short of the light.
        let scene = cornell_box();
        let s = lab_settings(16, 16);
        let rays = shadow_rays(&scene, &s.light, &primary_rays(&s.camera));
        assert!(!rays.is_empty() && rays.len() <= 256);
        for (r, t) in rays {
            let end = r.at(t);
            assert!((end - s.light.position).length() < 1e-3);
        }
    }

    #[test]
    fn bounce_rays_leave_their_hits_cosine_distributed() {
        let scene = cornell_box();
        let s = lab_settings(32, 32);
        let primary = primary_rays(&s.camera);
        let rays = bounce_rays(&scene, &primary, 7);
        // Every camera ray hits the closed box, so each casts one bounce ray.
        assert_eq!(rays.len(), primary.len());
        assert_eq!(rays, bounce_rays(&scene, &primary, 7), "deterministic");
        assert_ne!(rays, bounce_rays(&scene, &primary, 8), "the seed matters");
        let (mut cos_sum, mut hits) = (0.0, 0);
        for (ray, camera_ray) in rays.iter().zip(&primary) {
            let hit = scene
                .closest_intersection(camera_ray, f32::INFINITY)
                .unwrap();
            let mut n = scene.triangles[hit.triangle_index].normal;
            if n.dot(camera_ray.direction) > 0.0 {
                n = -n;
            }
            assert!((ray.direction.length() - 1.0).abs() < 1e-5);
            let cos = ray.direction.dot(n);
            assert!(cos >= 0.0, "into the surface: {cos}");
            assert!((ray.origin - hit.position).length() < 1e-3);
            hits += usize::from(scene.closest_intersection(ray, f32::INFINITY).is_some());
            cos_sum += cos;
        }
        // The box is open only at the front, behind the camera: most bounces hit it.
        assert!(hits > rays.len() / 2, "{hits}");
        // E[cos θ] under the density cos θ / π is 2/3.
        let mean = cos_sum / rays.len() as f32;
        assert!((mean - 2.0 / 3.0).abs() < 0.03, "{mean}");
    }

    #[test]
    fn random_rays_start_inside_the_room_in_every_direction() {
        let scene = cornell_box();
        let (lo, hi) = scene_bounds(&scene);
        assert!(lo.cmplt(hi).all());
        let rays = random_rays_in_room(lo, hi, 4000, 3);
        assert_eq!(rays.len(), 4000);
        assert_eq!(rays, random_rays_in_room(lo, hi, 4000, 3), "deterministic");
        let (mut mean, mut hits) = (glam::Vec3::ZERO, 0);
        for ray in &rays {
            assert!(ray.origin.cmpgt(lo).all() && ray.origin.cmplt(hi).all());
            assert!((ray.direction.length() - 1.0).abs() < 1e-5);
            mean += ray.direction;
            hits += usize::from(scene.closest_intersection(ray, f32::INFINITY).is_some());
        }
        // Only the front of the box is open.
        assert!(hits > rays.len() / 2, "{hits}");
        // Uniform on the sphere: the mean direction is near zero (σ ≈ 0.009 per axis).
        assert!((mean / rays.len() as f32).length() < 0.05, "{mean}");
        assert_eq!(
            scene_bounds(&Scene::default()),
            (glam::Vec3::ZERO, glam::Vec3::ZERO)
        );
    }
}
