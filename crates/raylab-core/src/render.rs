//! Rendering: one sample per pixel of a whole image, traced in parallel and cancellable.
//!
//! [`trace_pixel`] is the lab's `Draw` loop body for one pixel: camera ray → integrator.
//! [`render_pass`] does the same for every pixel, rows in parallel on the current rayon pool,
//! in batches ([`Tracer::trace`]), and gives up between rows as soon as `cancelled()` says so —
//! that is what lets the workbench drop stale work at once. [`render`] accumulates
//! `samples_per_pixel` passes into a [`Film`].
//!
//! Each sample's jitter and random numbers depend only on (seed, pixel, sample index), so the
//! image is the same whatever the thread count, and any pixel can be recomputed on its own.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use crate::accel::Isa;
#[cfg(target_arch = "x86_64")]
use crate::accel::simd::Avx512;
use crate::camera::ImagePoints;
use crate::film::{Film, Image, Seen};
use crate::geometry::Ray;
use crate::integrator::{BATCH, Scratch, Tracer};
use crate::memory::AllocError;
use crate::sampling::{Rng, concentric_disk, pixel_offset, pixel_sample};
use crate::scene::Scene;
use crate::settings::RenderSettings;

/// Returned when a render stops because its caller no longer wants it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("render cancelled")]
pub struct Cancelled;

/// The value of sample `sample` of pixel `(x, y)`: exactly what [`render_pass`] puts there.
pub fn trace_pixel(scene: &Scene, settings: &RenderSettings, x: u32, y: u32, sample: u32) -> Vec3 {
    let tracer = Tracer::for_pass(scene, settings, sample);
    let rotation = settings.camera.rotation();
    let mut ray = [Ray::new(Vec3::ZERO, Vec3::Z)];
    let mut rng = [Rng::UNUSED];
    camera_sample(
        &tracer,
        settings,
        &rotation,
        x,
        y,
        sample,
        &mut ray[0],
        &mut rng[0],
    );
    let mut out = [Vec3::ZERO];
    tracer.trace(&ray, &mut rng, &mut out);
    out[0]
}

/// The camera ray of sample `sample` of pixel `(x, y)` (equation 24, jittered after sample 0;
/// through a point of the lens when the camera has an aperture) and, if anything draws random
/// numbers, the generator the integrator continues with.
///
/// Returns the image point the ray goes through and the lens point, if any (the pixel
/// inspector shows them).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn camera_sample(
    tracer: &Tracer,
    settings: &RenderSettings,
    rotation: &Mat3,
    x: u32,
    y: u32,
    sample: u32,
    ray: &mut Ray,
    rng: &mut Rng,
) -> ((f32, f32), Option<glam::Vec2>) {
    let ((px, py), lens) = image_point(tracer, settings, x, y, sample, rng);
    let camera = &settings.camera;
    *ray = match lens {
        Some(lens) => camera.lens_ray_rotated(rotation, px, py, lens),
        None => camera.primary_ray_rotated(rotation, px, py),
    };
    ((px, py), lens)
}

/// Where sample `sample` of pixel `(x, y)` crosses the image plane (the pixel's centre for
/// sample 0, else jittered) and the lens (when the camera has an aperture; drawn from the
/// sample's stream), and, if anything draws random numbers, the generator the integrator
/// continues with: [`camera_sample`] before its ray is made.
#[inline(always)]
fn image_point(
    tracer: &Tracer,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sample: u32,
    rng: &mut Rng,
) -> ((f32, f32), Option<glam::Vec2>) {
    let (dx, dy) = if tracer.uses_random_numbers() {
        let (offset, stream) = pixel_sample(settings.seed, x, y, sample);
        *rng = stream;
        offset
    } else {
        pixel_offset(settings.seed, x, y, sample)
    };
    let point = image_plane_point(x, y, (dx, dy));
    if settings.camera.aperture > 0.0 {
        // Depth of field: a point of the lens, from the sample's own stream.
        (point, Some(concentric_disk(rng.next_f32(), rng.next_f32())))
    } else {
        (point, None)
    }
}

/// Pixel `(x, y)`'s point at `offset` (in [0, 1)² from its top-left corner), in pixels.
#[inline(always)]
fn image_plane_point(x: u32, y: u32, (dx, dy): (f32, f32)) -> (f32, f32) {
    (x as f32 + dx, y as f32 + dy)
}

/// The depth (distance along the view direction, [`crate::Camera::depth_of`]) of what the
/// pinhole ray through image point `(px, py)` hits first, or `None` if it hits nothing: the
/// focus distance that makes that point sharp. The workbench's "click to focus" asks this.
pub fn focus_depth(scene: &Scene, settings: &RenderSettings, px: f32, py: f32) -> Option<f32> {
    let camera = &settings.camera;
    let ray = camera.primary_ray(px, py);
    let hit = scene.closest_intersection(&ray, f32::INFINITY)?;
    Some(camera.depth_of(hit.position)).filter(|d| *d > 0.0 && d.is_finite())
}

/// Why the camera sees nothing at all, if it does not: a note for a uniformly black image that
/// the camera, not the light, is to blame for. The pixel centres of a 16 × 16 grid over the
/// image are traced; if none hits a surface, the camera is outside the scene looking away from
/// it, or beyond it.
pub fn camera_sees_nothing(scene: &Scene, settings: &RenderSettings) -> Option<String> {
    let camera = &settings.camera;
    const GRID: u32 = 16;
    let any_hit = (0..GRID).any(|j| {
        (0..GRID).any(|i| {
            let px = (i as f32 + 0.5) / GRID as f32 * camera.width as f32;
            let py = (j as f32 + 0.5) / GRID as f32 * camera.height as f32;
            let ray = camera.primary_ray(px, py);
            scene.closest_intersection(&ray, f32::INFINITY).is_some()
        })
    });
    if any_hit {
        return None;
    }
    let (lo, hi) = scene.triangles.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), t| {
            (
                lo.min(t.v0.min(t.v1.min(t.v2))),
                hi.max(t.v0.max(t.v1.max(t.v2))),
            )
        },
    );
    let p = camera.position;
    let inside = p.cmpge(lo).all() && p.cmple(hi).all();
    Some(if inside {
        "the camera sees nothing: every ray leaves the scene (the box's open front is behind it)"
            .to_owned()
    } else {
        format!(
            "the camera sees nothing: it is outside the box, at ({:.2}, {:.2}, {:.2}), looking \
             away from it",
            p.x, p.y, p.z
        )
    })
}

/// One sample per pixel (sample index `sample`) of the whole image, or [`Cancelled`] if
/// `cancelled()` turned true before the last row was done.
pub fn render_pass(
    scene: &Scene,
    settings: &RenderSettings,
    sample: u32,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Result<Image, Cancelled> {
    let (width, height) = (settings.camera.width, settings.camera.height);
    let tracer = Tracer::for_pass(scene, settings, sample);
    let rows = Rows::new(&tracer, settings, sample);
    // The image is written row by row on the pool, once, into memory not filled first.
    // Filled with zeros first, on the calling thread alone, the Cornell box's lab pass at
    // 512² took 3.65 against 3.55 ms on one thread, 1.99 against 1.89 ms on two (Zen 5).
    let len = width as usize * height as usize;
    let mut pixels: Vec<Vec3> = Vec::with_capacity(len);
    pixels.spare_capacity_mut()[..len]
        .par_chunks_mut(width as usize)
        .enumerate()
        .try_for_each(|(y, row)| {
            if cancelled() {
                return Err(Cancelled);
            }
            rows.trace(y as u32, row, &mut [], |pixel, value| {
                pixel.write(value);
            });
            Ok(())
        })?;
    // SAFETY: every row of the first `len` slots was traced (a cancelled pass returned above,
    // its length still 0), and `Rows::trace` calls `put` on every slot of its row: all `len`
    // hold a value.
    unsafe { pixels.set_len(len) };
    Ok(Image {
        width,
        height,
        pixels,
    })
}

/// [`render_pass`] added into `film` as its next pass ([`Film::add_pass_rows`]): the same sums
/// as `film.add_pass(&render_pass(..)?)`, with no image of the pass made, and what each sample
/// saw if the film records features ([`Film::with_features`]) and the integrator tells it
/// ([`Tracer::records_features`]). If `cancelled()` turns true before the last row is done,
/// the film holds part of the pass and is to be dropped.
pub fn accumulate_pass(
    scene: &Scene,
    settings: &RenderSettings,
    sample: u32,
    film: &mut Film,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Result<(), Cancelled> {
    let (width, height) = (settings.camera.width, settings.camera.height);
    assert_eq!((film.width(), film.height()), (width, height));
    let tracer = Tracer::for_pass(scene, settings, sample);
    let rows = Rows::new(&tracer, settings, sample);
    let recorded = tracer.records_features();
    film.add_pass_rows(|y, row, seen| {
        if cancelled() {
            return Err(Cancelled);
        }
        let seen = if recorded { seen } else { &mut [] };
        rows.trace(y, row, seen, |pixel, value| *pixel = value);
        Ok(())
    })
}

/// What tracing a row of one pass needs, made once a pass.
struct Rows<'a> {
    tracer: &'a Tracer<'a>,
    settings: &'a RenderSettings,
    rotation: Mat3,
    sample: u32,
}

impl<'a> Rows<'a> {
    fn new(tracer: &'a Tracer<'a>, settings: &'a RenderSettings, sample: u32) -> Self {
        Self {
            tracer,
            settings,
            rotation: settings.camera.rotation(),
            sample,
        }
    }

    /// Traces row `y` in batches ([`Tracer::trace_camera`]: the image points are found here,
    /// the rays made by the tracer), hands each pixel of `row` its value (`put`, once for
    /// every slot of `row`: [`render_pass`] relies on it), and puts what each sample saw into
    /// `seen` if it is not empty.
    #[inline(always)]
    fn trace<P>(
        &self,
        y: u32,
        row: &mut [P],
        seen: &mut [Option<Seen>],
        mut put: impl FnMut(&mut P, Vec3),
    ) {
        let (mut px, mut py) = ([0.0; BATCH], [0.0; BATCH]);
        let (mut lens_x, mut lens_y) = ([0.0; BATCH], [0.0; BATCH]);
        let mut rngs = [Rng::UNUSED; BATCH];
        let mut values = [Vec3::ZERO; BATCH];
        let mut scratch = Scratch::new();
        // Nothing random and a pinhole (the lab's stages as the lab sets them): each image
        // point is its pixel's offset alone, with no generator and no lens point, in a loop
        // the compiler can keep simple (the loop below, asking both per pixel, took 8 % of the
        // lab pass's instructions: PERFORMANCE.md).
        let points_only =
            !self.tracer.uses_random_numbers() && self.settings.camera.aperture <= 0.0;
        let seed = self.settings.seed;
        for (c, chunk) in row.chunks_mut(BATCH).enumerate() {
            let n = chunk.len();
            let first = (c * BATCH) as u32;
            if points_only && self.sample == 0 {
                // Sample 0 is every pixel's centre: one offset for the whole row.
                let centre = pixel_offset(seed, first, y, 0);
                for (i, (px, py)) in px[..n].iter_mut().zip(&mut py[..n]).enumerate() {
                    (*px, *py) = image_plane_point(first + i as u32, y, centre);
                }
            } else if points_only {
                jittered_points(
                    self.tracer.scene.accel().isa(),
                    seed,
                    (first, y),
                    self.sample,
                    &mut px[..n],
                    &mut py[..n],
                );
            } else {
                for (i, rng) in rngs[..n].iter_mut().enumerate() {
                    let x = first + i as u32;
                    let ((x, y), lens) =
                        image_point(self.tracer, self.settings, x, y, self.sample, rng);
                    (px[i], py[i]) = (x, y);
                    let lens = lens.unwrap_or_default();
                    (lens_x[i], lens_y[i]) = (lens.x, lens.y);
                }
            }
            // A pinhole ignores the lens points (and they may be empty).
            let lens = if points_only { 0 } else { n };
            let points = ImagePoints {
                camera: &self.settings.camera,
                rotation: &self.rotation,
                px: &px[..n],
                py: &py[..n],
                lens_x: &lens_x[..lens],
                lens_y: &lens_y[..lens],
            };
            let seen = match seen.is_empty() {
                true => &mut [],
                false => &mut seen[first as usize..first as usize + n],
            };
            self.tracer.trace_camera(
                &points,
                &mut rngs[..n],
                &mut values[..n],
                seen,
                &mut scratch,
            );
            for (pixel, value) in chunk.iter_mut().zip(&values[..n]) {
                put(pixel, *value);
            }
        }
    }
}

/// The image points of sample `sample` (jittered: not 0) of pixels `first.0, first.0 + 1, …` of
/// row `first.1`, one per slot of `px` and `py`: [`image_plane_point`] at [`pixel_offset`],
/// pixel by pixel. The offsets are integer hashing (64-bit multiplies) and took a fifth of a
/// jittered lab pass's instructions one pixel at a time; compiled for AVX-512 the same loop is
/// done sixteen pixels at once (the same bits: the hashing is integer arithmetic and each float
/// is made by the same conversion; `jittered_points_are_the_same_on_every_isa`).
#[inline(always)]
fn jittered_points(
    isa: Isa,
    seed: u64,
    first: (u32, u32),
    sample: u32,
    px: &mut [f32],
    py: &mut [f32],
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512(k) => {
            // SAFETY: `k` proves the CPU has AVX-512 F, DQ and VL, AVX2 and FMA.
            unsafe { jittered_points_avx512(k, seed, first, sample, px, py) }
        }
        _ => jittered_points_portable(seed, first, sample, px, py),
    }
}

/// [`jittered_points`], one pixel at a time as the compiler makes it for any CPU.
#[inline(always)]
fn jittered_points_portable(
    seed: u64,
    first: (u32, u32),
    sample: u32,
    px: &mut [f32],
    py: &mut [f32],
) {
    let (x0, y) = first;
    for (i, (px, py)) in px.iter_mut().zip(py.iter_mut()).enumerate() {
        let x = x0 + i as u32;
        (*px, *py) = image_plane_point(x, y, pixel_offset(seed, x, y, sample));
    }
}

/// [`jittered_points_portable`] compiled with AVX-512 (64-bit multiplies and rotates sixteen
/// lanes wide).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,fma")]
fn jittered_points_avx512(
    _proof: Avx512,
    seed: u64,
    first: (u32, u32),
    sample: u32,
    px: &mut [f32],
    py: &mut [f32],
) {
    jittered_points_portable(seed, first, sample, px, py);
}

/// The full image: `samples_per_pixel` passes averaged. Not cancellable; for the command line
/// and tests.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Image {
    let mut image = Image::new(settings.camera.width, settings.camera.height);
    accumulate(scene, settings, &mut image);
    image
}

/// [`render`], with the image reserved fallibly ([`Image::try_new`]): a 16384² image the
/// allocator will not give is an error, not an abort. The command line renders with this.
pub fn try_render(scene: &Scene, settings: &RenderSettings) -> Result<Image, AllocError> {
    let mut image = Image::try_new(settings.camera.width, settings.camera.height)?;
    accumulate(scene, settings, &mut image);
    Ok(image)
}

/// Adds `samples_per_pixel` passes into `sum` (all zeros), a row at a time, then divides by
/// their number: the mean of the passes in the one image, where a [`Film`] holds its sum and a
/// whole pass beside it and resolves into a third image (three full-size images at the peak;
/// one here). The same operations in the same order as [`Film::add_pass`] and
/// [`Film::resolve`], so the same image bit for bit (the workbench's, accumulated in a film,
/// equals this one: `progressive`'s tests).
fn accumulate(scene: &Scene, settings: &RenderSettings, sum: &mut Image) {
    let width = settings.camera.width as usize;
    let mut tracer = Tracer::new(scene, settings);
    let samples = settings.samples_per_pixel.max(1);
    for sample in 0..samples {
        // Each pass its own photon map, when caustics come from photons.
        if settings.shading.photon_caustics() {
            tracer = Tracer::for_pass(scene, settings, sample);
        }
        let rows = Rows::new(&tracer, settings, sample);
        sum.pixels
            .par_chunks_mut(width.max(1))
            .enumerate()
            .for_each(|(y, row)| rows.trace(y as u32, row, &mut [], |s, value| *s += value));
    }
    // `Film::resolve`'s scale.
    let scale = 1.0 / samples as f32;
    sum.pixels.par_iter_mut().for_each(|p| *p *= scale);
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::scene::cornell_box;

    fn small() -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(64, 48);
        s
    }

    /// The jittered image points compiled for AVX-512 are the portable loop's, bit for bit:
    /// rows of 1 to 100 pixels (whole and partial blocks of sixteen), anywhere in a large
    /// image, for several seeds and samples; and they are the pixels' jittered offsets.
    #[test]
    fn jittered_points_are_the_same_on_every_isa() {
        #[cfg(target_arch = "x86_64")]
        let Some(k) = crate::accel::simd::Avx512::detect() else {
            crate::accel::skip_unless_required(
                "avx512",
                "jittered_points_are_the_same_on_every_isa",
            );
            return;
        };
        for (seed, sample, first, n) in [
            (0, 1, (0, 0), 1),
            (7, 5, (3, 200), 16),
            (u64::MAX, 63, (100, 16_383), 100),
            (42, 4_000, (16_000, 9), 37),
        ] {
            let (mut px, mut py) = (vec![0.0; n], vec![0.0; n]);
            jittered_points_portable(seed, first, sample, &mut px, &mut py);
            for (i, (&x, &y)) in px.iter().zip(&py).enumerate() {
                let (dx, dy) = pixel_offset(seed, first.0 + i as u32, first.1, sample);
                assert_eq!(
                    (x, y),
                    ((first.0 + i as u32) as f32 + dx, first.1 as f32 + dy)
                );
                assert!(dx != 0.5 || dy != 0.5, "jittered");
            }
            #[cfg(target_arch = "x86_64")]
            {
                let (mut qx, mut qy) = (vec![0.0; n], vec![0.0; n]);
                // SAFETY: `k` proves the CPU has AVX-512.
                unsafe { jittered_points_avx512(k, seed, first, sample, &mut qx, &mut qy) };
                let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&qx), bits(&px), "seed {seed}, sample {sample}");
                assert_eq!(bits(&qy), bits(&py), "seed {seed}, sample {sample}");
            }
        }
    }

    /// The workbench adds each pass into its film row by row: the same sums, bit for bit, as
    /// adding whole passes, and the same noise figures.
    #[test]
    fn a_pass_added_row_by_row_sums_as_a_whole_pass() {
        let scene = cornell_box();
        let mut settings = small();
        settings.shading = crate::Shading::for_stage(crate::Stage::Path);
        let (w, h) = (settings.camera.width, settings.camera.height);
        let (mut whole, mut rows) = (Film::with_noise(w, h), Film::with_noise(w, h));
        for sample in 0..3 {
            whole.add_pass(&render_pass(&scene, &settings, sample, &|| false).unwrap());
            accumulate_pass(&scene, &settings, sample, &mut rows, &|| false).unwrap();
        }
        assert_eq!(rows.samples(), 3);
        assert_eq!(whole.resolve(), rows.resolve());
        assert_eq!(whole.variance(), rows.variance());
        assert_eq!(whole.noise(), rows.noise());
        // Cancelled before its first row: an error, and no sample counted.
        let mut film = Film::new(w, h);
        assert_eq!(
            accumulate_pass(&scene, &settings, 0, &mut film, &|| true),
            Err(Cancelled)
        );
        assert_eq!(film.samples(), 0);
    }

    #[test]
    fn same_image_whatever_the_thread_count() {
        let scene = cornell_box();
        let mut settings = small();
        settings.samples_per_pixel = 3;
        let images: Vec<Image> = [1, 2, 5]
            .into_iter()
            .map(|threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| render(&scene, &settings))
            })
            .collect();
        assert_eq!(images[0], images[1]);
        assert_eq!(images[0], images[2]);
    }

    #[test]
    fn a_cancelled_pass_stops_early() {
        let scene = cornell_box();
        let rows = AtomicUsize::new(0);
        // Cancel after a few rows have asked: the rest are never traced.
        let cancel = || rows.fetch_add(1, Ordering::Relaxed) >= 4;
        let result = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| render_pass(&scene, &small(), 0, &cancel));
        assert_eq!(result, Err(Cancelled));
        assert_eq!(rows.load(Ordering::Relaxed), 5);
    }

    #[test]
    fn extra_samples_soften_edges_but_not_flat_areas() {
        let scene = cornell_box();
        let mut settings = small();
        // The flat stage is piecewise constant: only pixels on an edge can change.
        settings.shading = crate::Shading::for_stage(crate::Stage::Flat);
        let one = render(&scene, &settings);
        settings.samples_per_pixel = 16;
        let many = render(&scene, &settings);
        let changed = one
            .pixels
            .iter()
            .zip(&many.pixels)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3)
            .count();
        // 64×48 = 3072 pixels; the edges of walls and blocks cross a few hundred.
        assert!(changed > 50 && changed < one.pixels.len() / 5, "{changed}");
    }

    /// Above the blocks, the default view sees the back wall (z = 1): depth 4.001 from the
    /// camera at z = −3.001, whatever the point's distance (the depth is along the view
    /// direction). The image point (32, 14) of a 64 × 48 view, f = 64, looks 10/64 up: it
    /// meets the back wall at y = −4.001·10/64 = −0.625, above both blocks.
    #[test]
    fn focus_depth_is_the_hit_depth_along_the_view() {
        let scene = cornell_box();
        let s = small();
        let wall = focus_depth(&scene, &s, 32.0, 14.0).unwrap();
        assert!((wall - 4.001).abs() < 1e-5, "{wall}");
        let off_centre = focus_depth(&scene, &s, 40.0, 10.0).unwrap();
        assert!((off_centre - 4.001).abs() < 1e-5, "{off_centre}");
        // The top-left corner sees the left wall or the ceiling, nearer than the back wall.
        let corner = focus_depth(&scene, &s, 0.5, 0.5).unwrap();
        assert!(corner < 4.001, "{corner}");
        // Looking away from the box, nothing is hit.
        let mut away = small();
        away.camera.position = glam::Vec3::new(0.0, 0.0, -3.0);
        away.camera.yaw = std::f32::consts::PI;
        assert_eq!(focus_depth(&scene, &away, 32.0, 24.0), None);
    }

    /// The default view sees the box; behind the box (z = 2, looking on along +z) or turned
    /// away from its open front, it sees nothing, and says why.
    #[test]
    fn a_camera_that_sees_nothing_says_so() {
        let scene = cornell_box();
        assert_eq!(camera_sees_nothing(&scene, &small()), None);
        let mut behind = small();
        behind.camera.position = glam::Vec3::new(0.0, 0.0, 2.0);
        let note = camera_sees_nothing(&scene, &behind).unwrap();
        assert!(note.contains("outside the box"), "{note}");
        let mut away = small();
        away.camera.yaw = std::f32::consts::PI;
        assert!(
            camera_sees_nothing(&scene, &away)
                .unwrap()
                .contains("outside the box")
        );
    }
}
