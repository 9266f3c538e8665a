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

use std::cell::RefCell;

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use crate::base::camera::ImagePoints;
use crate::base::geometry::Ray;
use crate::base::lanes::compiled;
use crate::base::memory::{AllocError, with_thread_memory};
use crate::base::sampling::{Rng, concentric_disk, pixel_offset, pixel_sample};
use crate::shapes::accel::Isa;
#[cfg(target_arch = "x86_64")]
use crate::shapes::accel::simd::Avx512;
use crate::shapes::scene::Scene;
use crate::transport::film::{Film, Image, Seen, rows_per_job};
use crate::transport::integrator::{BATCH, PATH_BATCH, Scratch, Tracer};
use crate::transport::settings::RenderSettings;

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
    // The view direction (the ray through the image's centre) meets the scene's bounds: the
    // camera faces the box, and its rays pass beside it (slab test).
    let forward = camera
        .primary_ray(camera.width as f32 / 2.0, camera.height as f32 / 2.0)
        .direction;
    let (near, far) = ((lo - p) / forward, (hi - p) / forward);
    let enter = near.min(far).max_element();
    let leave = near.max(far).min_element();
    let facing = enter <= leave && leave > 0.0;
    Some(if inside {
        "the camera sees nothing: every ray leaves the scene (the box's open front is behind it)"
            .to_owned()
    } else if facing {
        format!(
            "the camera sees nothing: it is outside the box, at ({:.2}, {:.2}, {:.2}), facing \
             it, but every ray misses the box's open front (a field of view of {:.1}° × {:.1}° \
             at {}×{} pixels: the pixels' rays pass beside the opening)",
            p.x,
            p.y,
            p.z,
            camera.horizontal_fov_degrees(),
            camera.vertical_fov_degrees(),
            camera.width,
            camera.height
        )
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
    // The image is written row by row on the pool, once, into memory not filled first:
    // filling it with zeros first, on the calling thread alone, would be a serial step
    // before every pass (PERFORMANCE.md, "Design choices and what each buys": shared working memory).
    let len = width as usize * height as usize;
    let mut pixels: Vec<Vec3> = Vec::with_capacity(len);
    pixels.spare_capacity_mut()[..len]
        .par_chunks_mut(width as usize)
        .enumerate()
        .with_max_len(rows_per_job())
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

/// What tracing a row needs, made once a pass (or once for all the samples of a render).
struct Rows<'a> {
    tracer: &'a Tracer<'a>,
    settings: &'a RenderSettings,
    rotation: Mat3,
    sample: u32,
    /// Nothing random and a pinhole (the lab's stages as the lab sets them): each image point
    /// is its pixel's offset alone, with no generator and no lens point, in a loop the
    /// compiler can keep simple (a loop asking both per pixel would spend instructions on
    /// every pixel of the lab pass).
    points_only: bool,
}

/// The working memory of a row's batches: which samples they are (pixel `x[i]`, sample
/// `sample[i]`), their image points, generators and values, and the tracer's [`Scratch`].
/// Room for the longest batch ([`Tracer::batch_len`]).
struct Batch {
    x: [u32; PATH_BATCH],
    sample: [u32; PATH_BATCH],
    px: [f32; PATH_BATCH],
    py: [f32; PATH_BATCH],
    lens_x: [f32; PATH_BATCH],
    lens_y: [f32; PATH_BATCH],
    rngs: [Rng; PATH_BATCH],
    values: [Vec3; PATH_BATCH],
    scratch: Scratch,
}

thread_local! {
    /// Each thread's [`Batch`], made at its first row and reused for every row after: it has
    /// room for the path tracer's batches, far more memory than a row of the lab pass traces,
    /// so zeroing it for each row would be a share of that pass.
    static BATCH_MEMORY: RefCell<Option<Box<Batch>>> = const { RefCell::new(None) };
}

impl Batch {
    /// `work` with this thread's batch memory ([`BATCH_MEMORY`]), or with a fresh one if
    /// it is in use (never, unless a row were traced inside another's tracing).
    #[inline(always)]
    fn with<T>(work: impl FnOnce(&mut Batch) -> T) -> T {
        with_thread_memory(
            &BATCH_MEMORY,
            || None,
            |memory| work(memory.get_or_insert_with(Batch::boxed)),
        )
    }

    /// A new batch memory on the heap. Out of line, so that the row loop, inlined into
    /// rayon's splitting (a frame a level, nine levels for 512 rows a job each), never holds
    /// room for one in its own stack frame: a [`Batch`] in each level's frame would bring a
    /// tall image's levels near the end of a rayon thread's stack
    /// (`a_tall_image_fits_in_a_small_stack`).
    #[cold]
    #[inline(never)]
    fn boxed() -> Box<Batch> {
        Box::new(Batch::new())
    }

    fn new() -> Self {
        Self {
            x: [0; PATH_BATCH],
            sample: [0; PATH_BATCH],
            px: [0.0; PATH_BATCH],
            py: [0.0; PATH_BATCH],
            lens_x: [0.0; PATH_BATCH],
            lens_y: [0.0; PATH_BATCH],
            rngs: [Rng::UNUSED; PATH_BATCH],
            values: [Vec3::ZERO; PATH_BATCH],
            scratch: Scratch::new(),
        }
    }
}

impl<'a> Rows<'a> {
    fn new(tracer: &'a Tracer<'a>, settings: &'a RenderSettings, sample: u32) -> Self {
        Self {
            tracer,
            settings,
            rotation: settings.camera.rotation(),
            sample,
            points_only: !tracer.uses_random_numbers() && settings.camera.aperture <= 0.0,
        }
    }

    /// Traces row `y` of this pass in batches, hands each pixel of `row` its value (`put`,
    /// once for every slot of `row`: [`render_pass`] relies on it), and puts what each sample
    /// saw into `seen` if it is not empty.
    #[inline(always)]
    fn trace<P>(
        &self,
        y: u32,
        row: &mut [P],
        seen: &mut [Option<Seen>],
        mut put: impl FnMut(&mut P, Vec3),
    ) {
        let len = self.tracer.batch_len();
        Batch::with(|b| {
            for (c, chunk) in row.chunks_mut(len).enumerate() {
                let n = chunk.len();
                let first = (c * len) as u32;
                for (i, (x, sample)) in b.x[..n].iter_mut().zip(&mut b.sample[..n]).enumerate() {
                    (*x, *sample) = (first + i as u32, self.sample);
                }
                let seen = match seen.is_empty() {
                    true => &mut [],
                    false => &mut seen[first as usize..first as usize + n],
                };
                self.trace_batch(y, b, n, self.sample == 0, seen);
                for (pixel, value) in chunk.iter_mut().zip(&b.values[..n]) {
                    put(pixel, *value);
                }
            }
        })
    }

    /// Samples `0..samples` of every pixel of row `y`, added into `row` in sample order: the
    /// same sums, bit for bit, as [`Rows::trace`] pass after pass, each pass added. But each
    /// batch holds a few neighbouring pixels' samples (16 samples of 4 pixels, or all 8 of 8
    /// pixels, …; eight times as many pixels in the path tracer's longer batches): rays through
    /// one pixel are as alike as rays get, so each batch's culling keeps fewer triangles, for
    /// the camera rays and the shadow rays alike.
    #[inline(always)]
    fn trace_samples(&self, y: u32, row: &mut [Vec3], samples: u32) {
        // Each batch: `pixels` pixels, up to `each` samples of each, a pixel's one after
        // another. Its sums are `pixels` chains of additions, each waiting on the one before:
        // side by side they wait together (one pixel's 64 samples a batch would be one chain
        // of 64 additions, each waiting).
        let each = samples.clamp(1, (BATCH / 4) as u32) as usize;
        let pixels = self.tracer.batch_len() / each;
        Batch::with(|b| {
            for (c, row) in row.chunks_mut(pixels).enumerate() {
                let first = (c * pixels) as u32;
                for start in (0..samples).step_by(each) {
                    let k = (samples - start).min(each as u32) as usize;
                    let n = row.len() * k;
                    for (p, (x, sample)) in b.x[..n]
                        .chunks_mut(k)
                        .zip(b.sample[..n].chunks_mut(k))
                        .enumerate()
                    {
                        x.fill(first + p as u32);
                        for (i, sample) in sample.iter_mut().enumerate() {
                            *sample = start + i as u32;
                        }
                    }
                    self.trace_batch(y, b, n, samples == 1, &mut []);
                    for (pixel, values) in row.iter_mut().zip(b.values[..n].chunks(k)) {
                        let mut sum = *pixel;
                        for value in values {
                            sum += *value;
                        }
                        *pixel = sum;
                    }
                }
            }
        })
    }

    /// Traces the batch's first `n` samples (pixel `b.x[i]` of row `y`, sample `b.sample[i]`):
    /// their image points found here, the rays made by the tracer
    /// ([`Tracer::trace_camera`]), their values into `b.values`, what each saw into `seen` if
    /// it is not empty. `centres`: every sample is sample 0, each pixel's centre.
    #[inline(always)]
    fn trace_batch(
        &self,
        y: u32,
        b: &mut Batch,
        n: usize,
        centres: bool,
        seen: &mut [Option<Seen>],
    ) {
        let seed = self.settings.seed;
        let (px, py) = (&mut b.px[..n], &mut b.py[..n]);
        if self.points_only && centres {
            let centre = pixel_offset(seed, 0, y, 0);
            for (&x, (px, py)) in b.x[..n].iter().zip(px.iter_mut().zip(py.iter_mut())) {
                (*px, *py) = image_plane_point(x, y, centre);
            }
        } else if self.points_only {
            let isa = self.tracer.scene.accel().isa();
            jittered_points(isa, seed, y, (&b.x[..n], &b.sample[..n]), px, py, &mut []);
        } else if self.settings.camera.aperture <= 0.0 {
            // A pinhole: the points and each sample's generator, as `image_point` makes them.
            let isa = self.tracer.scene.accel().isa();
            let rngs = &mut b.rngs[..n];
            jittered_points(isa, seed, y, (&b.x[..n], &b.sample[..n]), px, py, rngs);
        } else {
            for i in 0..n {
                let (x, sample) = (b.x[i], b.sample[i]);
                let ((x, y), lens) =
                    image_point(self.tracer, self.settings, x, y, sample, &mut b.rngs[i]);
                (b.px[i], b.py[i]) = (x, y);
                let lens = lens.unwrap_or_default();
                (b.lens_x[i], b.lens_y[i]) = (lens.x, lens.y);
            }
        }
        // A pinhole ignores the lens points (and they may be empty).
        let lens = if self.settings.camera.aperture > 0.0 {
            n
        } else {
            0
        };
        let points = ImagePoints {
            camera: &self.settings.camera,
            rotation: &self.rotation,
            px: &b.px[..n],
            py: &b.py[..n],
            lens_x: &b.lens_x[..lens],
            lens_y: &b.lens_y[..lens],
        };
        let (rngs, values) = (&mut b.rngs[..n], &mut b.values[..n]);
        self.tracer
            .trace_camera(&points, rngs, values, seen, &mut b.scratch);
    }
}

/// The jittered image points of samples `samples.1[i]` of pixels `samples.0[i]` of row `y`,
/// one per slot of `px` and `py`: [`image_plane_point`] at [`pixel_offset`], sample by sample;
/// and, if `rngs` is not empty, each sample's generator as [`pixel_sample`] leaves it (the
/// path tracer's bounces draw from it). The offsets are integer hashing (64-bit multiplies),
/// a large part of a jittered lab pass's work one pixel at a time; compiled for
/// AVX-512 the same loop is done sixteen samples at once (the same bits: the hashing is
/// integer arithmetic and each float is made by the same conversion;
/// `jittered_points_are_the_same_on_every_isa`).
#[inline(always)]
fn jittered_points(
    isa: Isa,
    seed: u64,
    y: u32,
    samples: (&[u32], &[u32]),
    px: &mut [f32],
    py: &mut [f32],
    rngs: &mut [Rng],
) {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512(k) => {
            // SAFETY: `k` proves the CPU has AVX-512 F, DQ and VL, AVX2 and FMA.
            unsafe { jittered_points_avx512(k, seed, y, samples, px, py, rngs) }
        }
        _ => jittered_points_portable(seed, y, samples, px, py, rngs),
    }
}

/// [`jittered_points`], one sample at a time as the compiler makes it for any CPU.
#[inline(always)]
fn jittered_points_portable(
    seed: u64,
    y: u32,
    (xs, samples): (&[u32], &[u32]),
    px: &mut [f32],
    py: &mut [f32],
    rngs: &mut [Rng],
) {
    let n = px.len().min(py.len()).min(xs.len()).min(samples.len());
    if rngs.is_empty() {
        for i in 0..n {
            let (x, sample) = (xs[i], samples[i]);
            (px[i], py[i]) = image_plane_point(x, y, pixel_offset(seed, x, y, sample));
        }
    } else {
        for (i, rng) in rngs.iter_mut().enumerate().take(n) {
            let (x, sample) = (xs[i], samples[i]);
            let (offset, stream) = pixel_sample(seed, x, y, sample);
            *rng = stream;
            (px[i], py[i]) = image_plane_point(x, y, offset);
        }
    }
}

compiled!(Avx512:
/// [`jittered_points_portable`] compiled with AVX-512 (64-bit multiplies and rotates sixteen
/// lanes wide).
fn jittered_points_avx512(
    _proof: Avx512,
    seed: u64,
    y: u32,
    samples: (&[u32], &[u32]),
    px: &mut [f32],
    py: &mut [f32],
    rngs: &mut [Rng],
) {
    jittered_points_portable(seed, y, samples, px, py, rngs);
});

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

/// Adds `samples_per_pixel` samples of every pixel into `sum` (all zeros), a row at a time,
/// then divides by their number: the mean of the passes in the one image, where a [`Film`]
/// holds its sum and a whole pass beside it and resolves into a third image (three full-size
/// images at the peak; one here). The same operations in the same order as
/// [`Film::add_pass`] and [`Film::resolve`], so the same image bit for bit (the workbench's,
/// accumulated in a film, equals this one: `progressive`'s tests). A row's samples are traced
/// pixel by pixel ([`Rows::trace_samples`]), but pass after pass when caustics come from
/// photons: each pass then has its own photon map.
fn accumulate(scene: &Scene, settings: &RenderSettings, sum: &mut Image) {
    let width = settings.camera.width as usize;
    let samples = settings.samples_per_pixel.max(1);
    if settings.shading.photon_caustics() {
        for sample in 0..samples {
            let tracer = Tracer::for_pass(scene, settings, sample);
            let rows = Rows::new(&tracer, settings, sample);
            sum.pixels
                .par_chunks_mut(width.max(1))
                .enumerate()
                .with_max_len(rows_per_job())
                .for_each(|(y, row)| rows.trace(y as u32, row, &mut [], |s, value| *s += value));
        }
    } else {
        let tracer = Tracer::new(scene, settings);
        // `trace_samples` names its samples itself: the pass's sample is not used. (Kept here
        // rather than passed to `Rows::trace` as an argument: that way the compiler fits the
        // row loop together less tightly.)
        let rows = Rows::new(&tracer, settings, 0);
        sum.pixels
            .par_chunks_mut(width.max(1))
            .enumerate()
            .with_max_len(rows_per_job())
            .for_each(|(y, row)| rows.trace_samples(y as u32, row, samples));
    }
    // `Film::resolve`'s scale.
    let scale = 1.0 / samples as f32;
    sum.pixels.par_iter_mut().for_each(|p| *p *= scale);
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::shapes::scene::cornell_box;

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
        let Some(k) = crate::shapes::accel::simd::Avx512::detect() else {
            crate::shapes::accel::skip_unless_required(
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
            // A pass's stretch of a row (one sample, pixel after pixel), then a pixel's samples
            // one after another (as a render traces them).
            for along_row in [true, false] {
                let xs: Vec<u32> = (0..n as u32)
                    .map(|i| {
                        if along_row {
                            first.0 + i
                        } else {
                            first.0 + i / 7
                        }
                    })
                    .collect();
                let samples: Vec<u32> = (0..n as u32)
                    .map(|i| if along_row { sample } else { sample + i % 7 })
                    .collect();
                let (mut px, mut py) = (vec![0.0; n], vec![0.0; n]);
                jittered_points_portable(seed, first.1, (&xs, &samples), &mut px, &mut py, &mut []);
                for (i, (&x, &y)) in px.iter().zip(&py).enumerate() {
                    let (dx, dy) = pixel_offset(seed, xs[i], first.1, samples[i]);
                    assert_eq!((x, y), (xs[i] as f32 + dx, first.1 as f32 + dy));
                    assert!(dx != 0.5 || dy != 0.5, "jittered");
                }
                #[cfg(target_arch = "x86_64")]
                {
                    let (mut qx, mut qy) = (vec![0.0; n], vec![0.0; n]);
                    let samples = (&xs[..], &samples[..]);
                    // SAFETY: `k` proves the CPU has AVX-512.
                    unsafe {
                        jittered_points_avx512(k, seed, first.1, samples, &mut qx, &mut qy, &mut [])
                    };
                    let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&qx), bits(&px), "seed {seed}, sample {sample}");
                    assert_eq!(bits(&qy), bits(&py), "seed {seed}, sample {sample}");
                }
                // With each sample's generator too: the same points, and the generators
                // `pixel_sample` leaves, on every kernel set.
                for isa in [Isa::Scalar, Isa::widest()] {
                    let mut rngs = vec![Rng::UNUSED; n];
                    let (mut rx, mut ry) = (vec![0.0; n], vec![0.0; n]);
                    let samples = (&xs[..], &samples[..]);
                    jittered_points(isa, seed, first.1, samples, &mut rx, &mut ry, &mut rngs);
                    assert_eq!((&rx, &ry), (&px, &py));
                    for (i, rng) in rngs.iter_mut().enumerate() {
                        let mut want = pixel_sample(seed, xs[i], first.1, samples.1[i]).1;
                        assert_eq!(rng.next_u32(), want.next_u32(), "seed {seed}, sample {i}");
                    }
                }
            }
        }
    }

    /// A render traces each row's samples a few pixels at a time, all their samples before
    /// the next pixels: the same image, bit for bit, as its passes rendered one after another
    /// and added in a film. Sample counts that fill the batches and that do not (the last
    /// round of a pixel's samples short), rows that do not end on a whole batch; the lab's
    /// jittered stages, the path tracer, soft shadows with a lens.
    #[test]
    fn a_render_pixel_by_pixel_equals_its_passes_added() {
        let scene = cornell_box();
        let mut settings = small();
        settings.camera = settings.camera.with_resolution(37, 5);
        for (stage, samples) in [
            (crate::Stage::Shadows, 1),
            (crate::Stage::Shadows, 70),
            (crate::Stage::Lab, 3),
            (crate::Stage::Path, 17),
            (crate::Stage::Path, 16),
        ] {
            for soft in [false, true] {
                settings.shading = crate::Shading::for_stage(stage);
                settings.samples_per_pixel = samples;
                (settings.light.kind, settings.camera.aperture) = if soft {
                    (
                        crate::shading::light::LightKind::Sphere { radius: 0.1 },
                        0.03,
                    )
                } else {
                    (crate::shading::light::LightKind::Point, 0.0)
                };
                let image = render(&scene, &settings);
                let mut film = Film::new(37, 5);
                for sample in 0..samples {
                    film.add_pass(&render_pass(&scene, &settings, sample, &|| false).unwrap());
                }
                let bits = |i: &Image| -> Vec<[u32; 3]> {
                    i.pixels
                        .iter()
                        .map(|p| p.to_array().map(f32::to_bits))
                        .collect()
                };
                assert_eq!(
                    bits(&image),
                    bits(&film.resolve()),
                    "{stage}, {samples}, {soft}"
                );
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

    /// The address of a local of this call: how deep the calling thread's stack is, for
    /// [`a_tall_image_fits_in_a_small_stack`].
    #[inline(never)]
    fn stack_address() -> usize {
        let here = 0u8;
        std::hint::black_box(&here) as *const u8 as usize
    }

    /// Rows a job each nest rayon's splitting a level a halving (thirteen for 8,192 rows), a
    /// stack frame a level, and a thread waiting on a job runs others on its stack: a tall
    /// image on two threads with half a mebibyte of stack each traces every row, in a pass, a
    /// film's pass and a render.
    ///
    /// Running out of stack depends on how the build inlines: a release build that keeps a row
    /// memory in each level's frame overflows here, where the test build, inlining less,
    /// passes. So the depth is also measured, in any build: the stack
    /// each row starts on (asked at every row's cancellation check, against the address its
    /// thread started at) must be under a quarter of the stack, leaving three quarters to
    /// the row's own tracing. That catches a level's frame growing (by a few kilobytes a
    /// level, in the profile the test runs in), not the tracing's own depth, nor what only
    /// another profile's inlining adds: that the release build's run of the test shows.
    #[test]
    fn a_tall_image_fits_in_a_small_stack() {
        thread_local! {
            static STARTED_AT: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
        }
        const STACK: usize = 512 * 1024;
        let scene = cornell_box();
        let mut settings = small();
        settings.shading = crate::Shading::for_stage(crate::Stage::Path);
        settings.camera = crate::Camera::default_for(2, 8192);
        settings.samples_per_pixel = 2;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .stack_size(STACK)
            .start_handler(|_| STARTED_AT.with(|s| s.set(stack_address())))
            .build()
            .unwrap();
        let deepest = AtomicUsize::new(0);
        let rows = AtomicUsize::new(0);
        let measure = || {
            let top = STARTED_AT.with(std::cell::Cell::get);
            assert_ne!(top, 0, "a row traced outside the pool");
            deepest.fetch_max(top - stack_address(), Ordering::Relaxed);
            rows.fetch_add(1, Ordering::Relaxed);
            false
        };
        let (pass, film, image) = pool.install(|| {
            let pass = render_pass(&scene, &settings, 0, &measure).unwrap();
            let mut film = Film::new(2, 8192);
            accumulate_pass(&scene, &settings, 0, &mut film, &measure).unwrap();
            (pass, film, render(&scene, &settings))
        });
        assert_eq!(pass.pixels.len(), 2 * 8192);
        assert_eq!(film.resolve(), pass);
        assert!(image.pixels.iter().all(|p| p.is_finite()));
        assert!(image.pixels.iter().any(|p| p.max_element() > 0.0));
        assert_eq!(rows.load(Ordering::Relaxed), 2 * 8192, "every row measured");
        let deepest = deepest.load(Ordering::Relaxed);
        eprintln!("rows start {deepest} bytes deep");
        assert!(
            deepest < STACK / 4,
            "rows start {deepest} bytes deep in a stack of {STACK}"
        );
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
        let note = camera_sees_nothing(&scene, &away).unwrap();
        assert!(note.contains("looking away from it"), "{note}");
        // One pixel wide and 64 high, the focal length the width: facing the box, every
        // row's ray is 26.6° or more off the view direction and passes above or below the
        // open front.
        let mut tall = small();
        tall.camera = tall.camera.with_resolution(1, 64);
        assert_eq!(render(&scene, &tall).pixels, vec![glam::Vec3::ZERO; 64]);
        let note = camera_sees_nothing(&scene, &tall).unwrap();
        assert!(
            note.contains("facing it") && note.contains("misses the box's open front"),
            "{note}"
        );
        assert!(!note.contains("looking away"), "{note}");
    }
}
