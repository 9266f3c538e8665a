//! Denoising: a clean image from few samples, for the path stage and any other noisy image
//! (soft shadows, depth of field).
//!
//! The filter is the edge-avoiding à-trous wavelet transform (Dammertz et al., "Edge-Avoiding
//! À-Trous Wavelet Transform for fast Global Illumination Filtering", 2010), steered as SVGF
//! steers it (Schied et al., "Spatiotemporal Variance-Guided Filtering", 2017):
//!
//! 1. The light is separated from the surfaces: each pixel's colour is divided by its albedo
//!    ([`Features::albedo`]), the filter smooths what is left (the light arriving), and the
//!    albedo multiplies it back. A texture's or an edge's detail is in the albedo, so it is
//!    never blurred.
//! 2. Three passes of a 5 × 5 B3-spline kernel, its taps 1, 2 and 4 pixels apart (a 29 pixel
//!    wide filter for 25 taps a pass; on the path-traced box a fourth pass, 8 apart, blurred
//!    the light's changes near corners and silhouettes more than it removed noise, from 16
//!    samples on). A tap weighs less the more its pixel differs from the centre's: in normal
//!    (`exp(−σn·(1 − n·n'))`), in depth relative to the centre's depth slope, and in the
//!    light's luminance relative to how noisy it still is (σl times its standard deviation,
//!    from the film's per-pixel variance blurred 5 × 5, itself filtered along).
//!    Noise is what differs by about a standard deviation; an edge of a shadow differs by
//!    many, and as samples accumulate the standard deviation falls and the filter lets go.
//!    In the first pass, whose input is the raw light, a neighbour is held against mostly the
//!    3 × 3 mean around the centre ([`CENTRE_MEAN`]) rather than the centre's own noisy value:
//!    against its own value, the neighbours that happen to share its noise weigh most, and
//!    the filter keeps part of the noise it should remove.
//! 3. A pixel whose feature samples saw two surfaces (on a silhouette or a crease) has a
//!    shorter averaged normal n̄, and every neighbour, on either surface, rejects it and is
//!    rejected by it: it would keep its noise. In the first pass its normal weight is
//!    exp(−σn·(|n̄|² − n̄·n')) instead, which is 1 for a neighbour on either surface (n̄ =
//!    (n₁ + n₂)/2 gives n̄·n₁ = n̄·n₂ = |n̄|²), so it is averaged with its nearest neighbours
//!    on both sides. Only the first: in wider passes it pulled the pixel's mix toward light
//!    from farther on each surface once the noise was low.
//! 4. Each pass takes, instead of its taps' weighted mean, the value at the pixel of a plane
//!    fitted to them (the light as a linear function of the tap's offset, by weighted least
//!    squares). Where the edge-stopping weights cut the kernel on one side (beside a corner, a
//!    silhouette, a shadow's edge) the weighted mean is the light at the weights' centroid, off
//!    the pixel, biased by the light's slope between the two; the plane's value at the pixel
//!    is not. Where the kernel is whole the centroid is the pixel and the two agree. A ridge
//!    added to the offsets' spread keeps the fit from extrapolating far from a few taps on a
//!    line, and grows with the light's relative noise ([`SLOPE_RIDGE_NOISE`]): a slope fitted
//!    to noisy taps is mostly noise, and the taps' weights favour those near the centre's own
//!    noisy value, so with little ridge the fit extrapolated noise and moved the mean.
//!
//! 5. Before the passes, a pixel whose brightest sample is an outlier (a firefly: far brighter
//!    than its other samples, which the luminance weights would keep apart; from 32 samples
//!    on, any sample 3 standard deviations above the others, most pixels' brightest) is taken
//!    apart: the filter denoises the mean of its other samples, with looser normal and depth
//!    weights ([`Denoiser::judged_sigma_normal`]), and the outlier's share of the mean is
//!    given back after the passes, spread over the pixels of its surface around it, whole
//!    ([`Noisy`], `outliers.rs`). The image's light is kept; only the brightest samples' light
//!    moves, by up to [`SPREAD_RADIUS`] pixels.
//!
//! Through mirrors and glass the features are those of the surface seen there
//! ([`Features`]), so a reflection or what is seen through glass is filtered as that surface
//! is, and its edges kept.
//!
//! The result depends only on the inputs (no random numbers, each pixel computed on its own),
//! so it is the same on any thread count. The film's linear mean is never changed: the
//! denoised image is a second image made from it.

mod features;
mod outliers;
pub mod quality;

use glam::Vec3;
use rayon::prelude::*;

pub use features::{FEATURE_SAMPLES, Features};
pub use outliers::{Noisy, OUTLIER_DEVIATIONS, OUTLIER_MIN_SAMPLES, SPREAD_RADIUS};

use crate::shapes::accel::Isa;
use crate::shapes::accel::set::{Compiled, InstructionSet};
use crate::shapes::scene::Scene;
use crate::transport::film::{Film, Image};
use crate::transport::integrator::Tracer;
use crate::transport::render::{Cancelled, accumulate_pass, render};
use crate::transport::settings::RenderSettings;

/// The B3-spline's weights: the 5 × 5 kernel is their outer product.
const B3: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// The least an albedo channel is taken as. Where a pixel's samples saw almost nothing (a
/// mirror facing the void, the edge of a surface against it), the albedo is near 0 and its
/// colour too: divided by the floor, its light stays small, so its neighbours do not take it
/// for a bright one, and multiplied back by the floor, the light it takes from them stays
/// small too. Taken as 1 (the colour filtered as it is) such a pixel took its neighbours' light
/// unscaled and shone in the mirror's black face. Below any albedo the Cornell box has.
const ALBEDO_FLOOR: f32 = 0.03;

/// In the first pass, the share of the 3 × 3 mean in the luminance a neighbour's is held
/// against (module docs, point 2); the rest is the centre's own. A little of its own keeps a
/// centre that truly differs from its neighbours (a pixel-sized highlight) a little apart.
const CENTRE_MEAN: f32 = 0.7;

/// The ridge of each pass's plane fit (module docs, point 4), added to the variance of the
/// weighted taps' offsets along x and y (in steps: the whole kernel's is 1 along each), plus
/// [`SLOPE_RIDGE_NOISE`] times the centre's relative variance (the light's blurred variance
/// over the taps' mean luminance squared). Chosen on the path-traced box: a smaller ridge
/// removes more of the bias at 64 and 256 samples, but moves the mean of the 64² box at 16
/// samples by more than the 0.5 % the denoiser's tests allow.
const SLOPE_RIDGE: f32 = 0.1;
const SLOPE_RIDGE_NOISE: f32 = 300.0;

/// The filter's settings. The defaults started from SVGF's (σl 4, σn 128, σz 1, five passes)
/// and were swept on the path-traced Cornell box at 4 to 256 samples (PERFORMANCE.md, "The
/// denoiser", gives the quality they reach): fewer passes and a looser normal weight lower the
/// error at every sample count.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Denoiser {
    /// À-trous passes; the kernel spans 1 + 4·(2^passes − 1) pixels.
    pub passes: u32,
    /// σl: how many standard deviations of a pixel's noise a neighbour's luminance may differ
    /// by and still weigh e^−1.
    pub sigma_luminance: f32,
    /// σn: the normal weight is exp(−σn·(1 − n·n')), about (n·n')^σn.
    pub sigma_normal: f32,
    /// σz: how many depth slopes (the centre's depth change per pixel, times the distance) a
    /// neighbour's depth may differ by and still weigh e^−1.
    pub sigma_depth: f32,
    /// σn and σz for an image whose pixels' brightest samples were judged and the outliers
    /// taken apart ([`Noisy::judged`], from [`OUTLIER_MIN_SAMPLES`] samples on):
    /// looser. Without its pixels' brightest samples the colour has no heavy tail, and the
    /// luminance weight keeps what the normal and depth weights let through apart where the
    /// light differs. They lower the mirror-and-glass box's error; used without the split (at
    /// 16 samples) they would move the box's denoised mean more than the denoiser's tests
    /// allow.
    pub judged_sigma_normal: f32,
    /// σz for such an image ([`Denoiser::judged_sigma_normal`]).
    pub judged_sigma_depth: f32,
}

impl Default for Denoiser {
    fn default() -> Self {
        Self {
            passes: 3,
            sigma_luminance: 4.0,
            sigma_normal: 16.0,
            sigma_depth: 1.5,
            judged_sigma_normal: 4.0,
            judged_sigma_depth: 2.5,
        }
    }
}

/// Where the planes' values are: each plane is the image with a border of `pad` pixels on each
/// side (wider on the right, to a whole number of sixteen-pixel blocks), so every tap of every
/// pass reads sixteen neighbours in place, without a test. The border is outside the image: its
/// depth is infinite, so a tap there weighs exactly 0, and its other values are 0.
#[derive(Clone, Copy, Debug)]
struct Layout {
    width: usize,
    height: usize,
    pad: usize,
    /// Values from one row to the next: `pad`, the image's width rounded up to whole blocks,
    /// `pad`.
    stride: usize,
}

impl Layout {
    /// The layout for the passes that run on `width × height` (taps up to two steps away).
    fn new(width: usize, height: usize, steps: &[usize]) -> Layout {
        let pad = 2 * steps.iter().copied().max().unwrap_or(1);
        Layout {
            width,
            height,
            pad,
            stride: pad + width.div_ceil(LANES) * LANES + pad,
        }
    }

    fn len(&self) -> usize {
        self.stride * (self.height + 2 * self.pad)
    }

    /// Where pixel `(0, y)` is.
    fn row(&self, y: usize) -> usize {
        (y + self.pad) * self.stride + self.pad
    }

    /// The image's rows of a padded plane, for writing.
    fn rows_mut<'a>(&self, plane: &'a mut [f32]) -> &'a mut [f32] {
        &mut plane[self.pad * self.stride..(self.pad + self.height) * self.stride]
    }

    /// `values` (`width × height`) with the border: `outside` there (a plane from
    /// [`SPARE_PLANES`] where one is kept).
    fn padded(&self, values: impl Fn(usize) -> f32 + Sync, outside: f32) -> Vec<f32> {
        let mut plane = take_plane(self.len(), outside);
        self.rows_mut(&mut plane)
            .par_chunks_mut(self.stride)
            .enumerate()
            .for_each(|(y, row)| {
                let row = &mut row[self.pad..self.pad + self.width];
                for (x, out) in row.iter_mut().enumerate() {
                    *out = values(y * self.width + x);
                }
            });
        plane
    }
}

/// Planes kept from one call of the filter to the next, up to [`SPARE_BYTES`]: a fresh
/// megabyte-sized allocation comes from the system as untouched pages, and the page faults of
/// the filter's sixteen planes can cost as much as its passes. What a plane held never
/// matters: each is filled before it is read.
static SPARE_PLANES: std::sync::Mutex<Vec<Vec<f32>>> = std::sync::Mutex::new(Vec::new());

/// At most this many bytes of planes are kept (a 1,024² image's planes fit).
const SPARE_BYTES: usize = 96 << 20;

/// A plane of `len` values, each `fill`.
fn take_plane(len: usize, fill: f32) -> Vec<f32> {
    let spare = SPARE_PLANES
        .lock()
        .ok()
        .and_then(|mut spare| spare.pop())
        .unwrap_or_default();
    let mut plane = spare;
    plane.clear();
    plane.resize(len, fill);
    plane
}

/// Keeps `planes` for later calls, as many as fit in [`SPARE_BYTES`].
fn give_back(planes: impl IntoIterator<Item = Vec<f32>>) {
    let Ok(mut spare) = SPARE_PLANES.lock() else {
        return;
    };
    let mut bytes: usize = spare.iter().map(|p| p.capacity() * 4).sum();
    for plane in planes {
        if bytes + plane.capacity() * 4 > SPARE_BYTES {
            break;
        }
        bytes += plane.capacity() * 4;
        spare.push(plane);
    }
}

/// Padded planes ([`Layout`]) of per-pixel values: the light (colour over albedo), its
/// luminance and its variance.
#[derive(Clone)]
struct Light {
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
    lum: Vec<f32>,
    variance: Vec<f32>,
}

/// The features as the filter reads them, a padded plane each ([`Layout`]).
struct Guide {
    nx: Vec<f32>,
    ny: Vec<f32>,
    nz: Vec<f32>,
    /// Infinite outside the image: a tap there weighs 0.
    depth: Vec<f32>,
    /// σz times the depth's change per pixel at the pixel (the smaller one-sided difference
    /// of each axis, the larger axis).
    depth_slope: Vec<f32>,
    /// Per column (padded as a row is), 1 over the 3 × 3 binomial's weight inside the image
    /// along x, and the same for the 5 × 5 B3-spline: the first pass's 3 × 3 mean of the
    /// luminance and the variance's 5 × 5 blur are renormalised at the image's edges.
    mean_x: Vec<f32>,
    blur_x: Vec<f32>,
}

impl Denoiser {
    /// The denoised `colour`: `variance` is the per-pixel variance of its mean (the film's,
    /// [`crate::transport::film::Film::variance`]), or `None` for a single sample, whose noise is then
    /// estimated from its neighbourhood. `colour`, `variance` and `features` must be of one
    /// size.
    pub fn denoise(&self, colour: &Image, variance: Option<&[f32]>, features: &Features) -> Image {
        self.denoise_with(Isa::widest(), colour, variance, features)
    }

    /// The denoised `noisy` image: its colour without the outliers denoised, and their excess
    /// given back spread over their surfaces ([`Noisy`]); with the looser normal and depth
    /// weights where its outliers were judged ([`Denoiser::judged_sigma_normal`]).
    pub fn denoise_noisy(&self, noisy: &Noisy, features: &Features) -> Image {
        let denoiser = if noisy.judged {
            Denoiser {
                sigma_normal: self.judged_sigma_normal,
                sigma_depth: self.judged_sigma_depth,
                ..*self
            }
        } else {
            *self
        };
        let mut image = denoiser.denoise(&noisy.colour, noisy.variance.as_deref(), features);
        outliers::spread(
            &mut image,
            &noisy.excess,
            features,
            denoiser.sigma_normal,
            denoiser.sigma_depth,
        );
        image
    }

    /// [`Denoiser::denoise`] with the row loop compiled for `isa`, which the CPU must have.
    fn denoise_with(
        &self,
        isa: Isa,
        colour: &Image,
        variance: Option<&[f32]>,
        features: &Features,
    ) -> Image {
        let (width, height) = (colour.width as usize, colour.height as usize);
        assert_eq!(
            (features.width, features.height),
            (colour.width, colour.height)
        );
        if width == 0 || height == 0 {
            return colour.clone();
        }
        let steps: Vec<usize> = (0..self.passes)
            .map(|pass| 1usize << pass)
            .take_while(|step| *step < width.max(height))
            .collect();
        let layout = Layout::new(width, height, &steps);
        let albedo = |i: usize| effective(features.albedo[i]);
        let light = |i: usize| colour.pixels[i] / albedo(i);
        // For a single sample, the variance estimated from the neighbourhood.
        let spatial = match variance {
            Some(variance) => {
                assert_eq!(variance.len(), width * height);
                Vec::new()
            }
            None => {
                let light: Vec<Vec3> = (0..width * height).into_par_iter().map(light).collect();
                spatial_variance(&light, width, height)
            }
        };
        // The light's variance: the colour's over the albedo's mean squared.
        let variance = |i: usize| match variance {
            Some(variance) => {
                let a = albedo(i);
                let a = (a.x + a.y + a.z) / 3.0;
                variance[i] / (a * a)
            }
            None => spatial[i],
        };
        let mut light = Light {
            r: layout.padded(|i| light(i).x, 0.0),
            g: layout.padded(|i| light(i).y, 0.0),
            b: layout.padded(|i| light(i).z, 0.0),
            lum: layout.padded(
                |i| {
                    let l = light(i);
                    luminance(l.x, l.y, l.z)
                },
                0.0,
            ),
            variance: layout.padded(variance, 0.0),
        };
        let guide = self.guide(features, &layout);
        // The border of what the passes write stays 0.
        let mut next = Light {
            r: take_plane(layout.len(), 0.0),
            g: take_plane(layout.len(), 0.0),
            b: take_plane(layout.len(), 0.0),
            lum: take_plane(layout.len(), 0.0),
            variance: take_plane(layout.len(), 0.0),
        };
        for &step in &steps {
            self.pass(isa, step, &layout, &light, &guide, &mut next);
            std::mem::swap(&mut light, &mut next);
        }
        let image = Image {
            width: colour.width,
            height: colour.height,
            pixels: (0..width * height)
                .into_par_iter()
                .map(|i| {
                    let p = layout.row(i / width) + i % width;
                    albedo(i) * Vec3::new(light.r[p], light.g[p], light.b[p])
                })
                .collect(),
        };
        give_back(
            [light, next]
                .into_iter()
                .flat_map(|l| [l.r, l.g, l.b, l.lum, l.variance])
                .chain([guide.nx, guide.ny, guide.nz, guide.depth, guide.depth_slope]),
        );
        image
    }

    fn guide(&self, features: &Features, layout: &Layout) -> Guide {
        let (width, height) = (features.width as usize, features.height as usize);
        let depth = &features.depth;
        let at = |x: usize, y: usize| depth[y * width + x];
        let depth_slope = |i: usize| {
            let (x, y) = (i % width, i / width);
            let z = at(x, y);
            let one_sided = |a: Option<f32>, b: Option<f32>| {
                let d = |n: Option<f32>| n.map_or(f32::INFINITY, |n| (n - z).abs());
                let s = d(a).min(d(b));
                if s.is_finite() { s } else { 0.0 }
            };
            let gx = one_sided(
                x.checked_sub(1).map(|x| at(x, y)),
                (x + 1 < width).then(|| at(x + 1, y)),
            );
            let gy = one_sided(
                y.checked_sub(1).map(|y| at(x, y)),
                (y + 1 < height).then(|| at(x, y + 1)),
            );
            self.sigma_depth * gx.max(gy)
        };
        let normal = &features.normal;
        let inverse_weights = |kernel: &[f32]| {
            let mut plane = vec![0.0; layout.stride];
            for (x, b) in plane[layout.pad..layout.pad + width].iter_mut().enumerate() {
                *b = 1.0 / weight_inside(kernel, x, width);
            }
            plane
        };
        Guide {
            nx: layout.padded(|i| normal[i].x, 0.0),
            ny: layout.padded(|i| normal[i].y, 0.0),
            nz: layout.padded(|i| normal[i].z, 0.0),
            depth: layout.padded(|i| depth[i], f32::INFINITY),
            depth_slope: layout.padded(depth_slope, 0.0),
            mean_x: inverse_weights(&BINOMIAL),
            blur_x: inverse_weights(&B3),
        }
    }

    /// One à-trous pass with taps `step` pixels apart, from `src` into `dst` (the image's
    /// pixels; the border stays as it is).
    fn pass(
        &self,
        isa: Isa,
        step: usize,
        layout: &Layout,
        src: &Light,
        guide: &Guide,
        dst: &mut Light,
    ) {
        let stride = layout.stride;
        layout
            .rows_mut(&mut dst.r)
            .par_chunks_mut(stride)
            .zip(layout.rows_mut(&mut dst.g).par_chunks_mut(stride))
            .zip(layout.rows_mut(&mut dst.b).par_chunks_mut(stride))
            .zip(layout.rows_mut(&mut dst.lum).par_chunks_mut(stride))
            .zip(layout.rows_mut(&mut dst.variance).par_chunks_mut(stride))
            .enumerate()
            .for_each(|(y, ((((r, g), b), lum), v))| {
                let row = Row {
                    y,
                    step,
                    first: step == 1,
                    layout,
                    src,
                    guide,
                    sigma_luminance: self.sigma_luminance,
                    sigma_normal: self.sigma_normal,
                };
                let at = layout.pad..layout.pad + layout.width;
                let out = Out {
                    r: &mut r[at.clone()],
                    g: &mut g[at.clone()],
                    b: &mut b[at.clone()],
                    lum: &mut lum[at.clone()],
                    v: &mut v[at],
                };
                isa.call(Filter { row: &row, out });
            });
    }
}

/// The 3-tap binomial kernel (¼, ½, ¼): the 3 × 3 mean is its outer product.
const BINOMIAL: [f32; 3] = [0.25, 0.5, 0.25];

/// The weight of `kernel` (an odd number of taps, centred on `x`) inside `0..n`.
fn weight_inside(kernel: &[f32], x: usize, n: usize) -> f32 {
    let r = kernel.len() / 2;
    kernel
        .iter()
        .enumerate()
        .filter(|(i, _)| (x + i).checked_sub(r).is_some_and(|q| q < n))
        .map(|(_, k)| k)
        .sum()
}

/// A pixel's luminance, the mean of its channels.
#[inline(always)]
fn luminance(r: f32, g: f32, b: f32) -> f32 {
    (r + g + b) * (1.0 / 3.0)
}

/// One output row of an à-trous pass.
struct Row<'a> {
    y: usize,
    step: usize,
    /// The first pass: its normal weight reaches as far as the centre's own normals spread.
    first: bool,
    layout: &'a Layout,
    src: &'a Light,
    guide: &'a Guide,
    sigma_luminance: f32,
    sigma_normal: f32,
}

/// The image's pixels of one row of the planes a pass writes.
struct Out<'a> {
    r: &'a mut [f32],
    g: &'a mut [f32],
    b: &'a mut [f32],
    lum: &'a mut [f32],
    v: &'a mut [f32],
}

/// A row of a pass ([`Row::filter_portable`]), compiled for each instruction set: the same
/// code and the same bits on each (Rust never fuses a multiply and an add, whatever the
/// instruction set; a test compares them), the widest set's registers for its arrays.
struct Filter<'a, 'b> {
    row: &'a Row<'b>,
    out: Out<'a>,
}

impl Compiled for Filter<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn run<S: InstructionSet>(self, _: S) {
        self.row.filter_portable(self.out)
    }
}

impl Row<'_> {
    /// Sixteen pixels at a time: their own values and running sums stay in registers (fixed
    /// arrays the compiler keeps in vector registers) through all 25 taps, each tap reading
    /// its sixteen neighbours straight from the padded planes (those outside the image weigh
    /// 0 by their infinite depth).
    #[inline(always)]
    fn filter_portable(&self, out: Out) {
        let layout = self.layout;
        let (width, stride, step) = (layout.width, layout.stride as isize, self.step);
        let (src, guide) = (self.src, self.guide);
        // Every plane cut to one length, so one bounds test covers all nine reads of a tap.
        let len = src.r.len();
        let planes = Planes {
            lum: &src.lum[..len],
            z: &guide.depth[..len],
            n: [&guide.nx[..len], &guide.ny[..len], &guide.nz[..len]],
            r: &src.r[..len],
            g: &src.g[..len],
            b: &src.b[..len],
            v: &src.variance[..len],
        };
        let row = layout.row(self.y);
        let h0 = B3[2] * B3[2];
        // The luminance's 3 × 3 mean and the variance's 5 × 5 blur, renormalised at the top
        // and bottom rows.
        let mean_y = 1.0 / weight_inside(&BINOMIAL, self.y, layout.height);
        let blur_y = 1.0 / weight_inside(&B3, self.y, layout.height);
        let (near, far) = (step as f32, (2 * step) as f32);
        // The 24 taps (offset in the planes, kernel weight, offset in steps), those one step
        // away (their depth tolerance is the centre's at one step) apart from those two steps
        // away.
        let mut near_taps = [(0isize, 0.0f32, [0.0f32; 2]); 8];
        let mut far_taps = [(0isize, 0.0f32, [0.0f32; 2]); 16];
        let (mut n_near, mut n_far) = (0, 0);
        for (j, ky) in B3.iter().enumerate() {
            for (i, kx) in B3.iter().enumerate() {
                let tap = (
                    (j as isize - 2) * step as isize * stride + (i as isize - 2) * step as isize,
                    kx * ky,
                    // The offset in steps, for the plane fit.
                    [i as f32 - 2.0, j as f32 - 2.0],
                );
                match i.abs_diff(2).max(j.abs_diff(2)) {
                    0 => {}
                    1 => {
                        near_taps[n_near] = tap;
                        n_near += 1;
                    }
                    _ => {
                        far_taps[n_far] = tap;
                        n_far += 1;
                    }
                }
            }
        }
        let mut x0 = 0;
        while x0 < width {
            let c = row + x0;
            // The luminance's tolerance at each pixel: σl times the standard deviation of its
            // noise, from the variance blurred over 5 × 5 (a pixel's own estimate is noisy).
            let mut blurred = [0.0; LANES];
            for (j, ky) in B3.iter().enumerate() {
                for (i, kx) in B3.iter().enumerate() {
                    let q = (c as isize + (j as isize - 2) * stride + i as isize - 2) as usize;
                    let k = kx * ky;
                    let v = load(planes.v, q);
                    for l in 0..LANES {
                        blurred[l] += k * v[l];
                    }
                }
            }
            let blur_x = load(&guide.blur_x, layout.pad + x0);
            let mut tolerance = [0.0; LANES];
            // The same variance, for the plane fit's ridge.
            let mut noise = [0.0; LANES];
            for l in 0..LANES {
                let v = blurred[l] * (blur_x[l] * blur_y);
                noise[l] = v.max(0.0);
                tolerance[l] = 1.0 / (self.sigma_luminance * v.max(0.0).sqrt() + 1e-4);
            }
            // 1 over the depth's tolerance one and two steps away.
            let (slope, z) = (load(&guide.depth_slope, c), load(planes.z, c));
            let mut depth_near = [0.0; LANES];
            let mut depth_far = [0.0; LANES];
            for l in 0..LANES {
                // A floor under the tolerance: a thousandth of the depth.
                let floor = 1e-3 * z[l] + 1e-6;
                depth_near[l] = 1.0 / (slope[l] * near + floor);
                depth_far[l] = 1.0 / (slope[l] * far + floor);
            }
            let n = [
                load(planes.n[0], c),
                load(planes.n[1], c),
                load(planes.n[2], c),
            ];
            // The normal a neighbour's is held against: in the first pass, the length squared
            // of the centre's averaged normal, below 1 where its feature samples saw several
            // surfaces (a silhouette's or a crease's pixel); 1 after.
            let mut reach = [1.0; LANES];
            if self.first {
                for l in 0..LANES {
                    reach[l] = n[0][l] * n[0][l] + n[1][l] * n[1][l] + n[2][l] * n[2][l];
                }
            }
            // What a neighbour's luminance is held against: in the first pass mostly the 3 × 3
            // mean around the centre (module docs, point 2), after it the centre's own value
            // (already filtered).
            let mut lum = load(planes.lum, c);
            if self.first {
                let mut mean = [0.0; LANES];
                for (j, ky) in BINOMIAL.iter().enumerate() {
                    for (i, kx) in BINOMIAL.iter().enumerate() {
                        let q = (c as isize + (j as isize - 1) * stride + i as isize - 1) as usize;
                        let k = kx * ky;
                        let v = load(planes.lum, q);
                        for l in 0..LANES {
                            mean[l] += k * v[l];
                        }
                    }
                }
                let mean_x = load(&guide.mean_x, layout.pad + x0);
                for l in 0..LANES {
                    let mean = mean[l] * (mean_x[l] * mean_y);
                    lum[l] = CENTRE_MEAN * mean + (1.0 - CENTRE_MEAN) * lum[l];
                }
            }
            let centre = Centre {
                lum,
                tolerance,
                z,
                n,
                reach,
            };
            let mut sums = Sums {
                w: [h0; LANES],
                r: scaled(h0, load(planes.r, c)),
                g: scaled(h0, load(planes.g, c)),
                b: scaled(h0, load(planes.b, c)),
                v: scaled(h0 * h0, load(planes.v, c)),
                // The centre's offset is 0: it adds nothing to the moments.
                moments: [[0.0; LANES]; 11],
            };
            for (taps, inverse_depth) in
                [(&near_taps[..], &depth_near), (&far_taps[..], &depth_far)]
            {
                for &(offset, h, [dx, dy]) in taps.iter() {
                    let tap = Tap {
                        h,
                        dx,
                        dy,
                        sigma_normal: self.sigma_normal,
                    };
                    let q = (c as isize + offset) as usize;
                    tap.add(&centre, inverse_depth, &planes.at(q), &mut sums);
                }
            }
            let mut result = Sums {
                w: [0.0; LANES],
                r: [0.0; LANES],
                g: [0.0; LANES],
                b: [0.0; LANES],
                v: [0.0; LANES],
                moments: [[0.0; LANES]; 11],
            };
            for l in 0..LANES {
                let inverse = 1.0 / sums.w[l];
                let m = &sums.moments;
                // The plane fit (module docs, point 4): the weights' centroid (cx, cy), the
                // offsets' covariance with the ridge on its diagonal, and per channel the
                // offsets' covariance with the light, which give the slope (gx, gy); the value
                // at the pixel is the mean less the slope times the centroid.
                let (cx, cy) = (m[0][l] * inverse, m[1][l] * inverse);
                let mean_lum = luminance(sums.r[l], sums.g[l], sums.b[l]) * inverse;
                let ridge =
                    SLOPE_RIDGE + SLOPE_RIDGE_NOISE * noise[l] / (mean_lum * mean_lum + 1e-12);
                let cxx = m[2][l] * inverse - cx * cx + ridge;
                let cyy = m[3][l] * inverse - cy * cy + ridge;
                let cxy = m[4][l] * inverse - cx * cy;
                let inverse_det = 1.0 / (cxx * cyy - cxy * cxy);
                let at_pixel = |sum: f32, x_sum: f32, y_sum: f32| {
                    let mean = sum * inverse;
                    let xc = x_sum * inverse - cx * mean;
                    let yc = y_sum * inverse - cy * mean;
                    let gx = (cyy * xc - cxy * yc) * inverse_det;
                    let gy = (cxx * yc - cxy * xc) * inverse_det;
                    mean - gx * cx - gy * cy
                };
                result.r[l] = at_pixel(sums.r[l], m[5][l], m[8][l]);
                result.g[l] = at_pixel(sums.g[l], m[6][l], m[9][l]);
                result.b[l] = at_pixel(sums.b[l], m[7][l], m[10][l]);
                // The luminance of the pixel's result, for the next pass.
                result.w[l] = luminance(result.r[l], result.g[l], result.b[l]);
                // The weighted mean's variance (the fit's is a little larger where it moves
                // the value, beside an edge).
                result.v[l] = sums.v[l] * inverse * inverse;
            }
            let n = (width - x0).min(LANES);
            let at = x0..x0 + n;
            out.r[at.clone()].copy_from_slice(&result.r[..n]);
            out.g[at.clone()].copy_from_slice(&result.g[..n]);
            out.b[at.clone()].copy_from_slice(&result.b[..n]);
            out.lum[at.clone()].copy_from_slice(&result.w[..n]);
            out.v[at].copy_from_slice(&result.v[..n]);
            x0 += LANES;
        }
    }
}

/// Pixels filtered side by side.
const LANES: usize = 16;

/// `plane[start..start + 16]`.
#[inline(always)]
fn load(plane: &[f32], start: usize) -> [f32; LANES] {
    *<&[f32; LANES]>::try_from(&plane[start..start + LANES]).expect("16 values")
}

/// The planes a tap reads, all of one length.
struct Planes<'a> {
    lum: &'a [f32],
    z: &'a [f32],
    n: [&'a [f32]; 3],
    r: &'a [f32],
    g: &'a [f32],
    b: &'a [f32],
    v: &'a [f32],
}

impl Planes<'_> {
    /// The sixteen pixels from `q` on.
    #[inline(always)]
    fn at(&self, q: usize) -> Neighbours {
        Neighbours {
            lum: load(self.lum, q),
            z: load(self.z, q),
            n: [load(self.n[0], q), load(self.n[1], q), load(self.n[2], q)],
            r: load(self.r, q),
            g: load(self.g, q),
            b: load(self.b, q),
            v: load(self.v, q),
        }
    }
}

/// Each of `values` times `k`.
#[inline(always)]
fn scaled(k: f32, mut values: [f32; LANES]) -> [f32; LANES] {
    for v in &mut values {
        *v *= k;
    }
    values
}

/// Sixteen centre pixels' values.
struct Centre {
    lum: [f32; LANES],
    /// 1/(σl·standard deviation).
    tolerance: [f32; LANES],
    z: [f32; LANES],
    n: [[f32; LANES]; 3],
    /// What n·n' is held against ([`tap_weight`]).
    reach: [f32; LANES],
}

/// Their sixteen neighbours' at one tap.
struct Neighbours {
    lum: [f32; LANES],
    z: [f32; LANES],
    n: [[f32; LANES]; 3],
    r: [f32; LANES],
    g: [f32; LANES],
    b: [f32; LANES],
    v: [f32; LANES],
}

/// Their running weighted sums.
struct Sums {
    w: [f32; LANES],
    r: [f32; LANES],
    g: [f32; LANES],
    b: [f32; LANES],
    v: [f32; LANES],
    /// For the plane fit, the weighted sums of the offset in steps (x, y), of x², y², x·y,
    /// and of x and then y times the light (r, g, b).
    moments: [[f32; LANES]; 11],
}

/// One tap of the kernel.
struct Tap {
    /// The kernel's weight.
    h: f32,
    /// The offset in steps.
    dx: f32,
    dy: f32,
    sigma_normal: f32,
}

impl Tap {
    /// Adds each neighbour, weighted by the kernel weight and the edge-stopping weights, to
    /// its centre's sums; `inverse_depth` is 1 over each centre's depth tolerance at the tap's
    /// distance.
    #[inline(always)]
    #[allow(
        clippy::needless_range_loop,
        reason = "lane l of a dozen arrays at once: an index reads clearest"
    )]
    fn add(&self, p: &Centre, inverse_depth: &[f32; LANES], q: &Neighbours, sums: &mut Sums) {
        for l in 0..LANES {
            let w = tap_weight(
                self.h,
                self.sigma_normal,
                [p.lum[l], q.lum[l], p.tolerance[l]],
                [p.z[l], q.z[l], inverse_depth[l]],
                [p.n[0][l], p.n[1][l], p.n[2][l], p.reach[l]],
                [q.n[0][l], q.n[1][l], q.n[2][l]],
            );
            sums.w[l] += w;
            sums.r[l] += w * q.r[l];
            sums.g[l] += w * q.g[l];
            sums.b[l] += w * q.b[l];
            sums.v[l] += w * w * q.v[l];
            let (wx, wy) = (w * self.dx, w * self.dy);
            let m = &mut sums.moments;
            m[0][l] += wx;
            m[1][l] += wy;
            m[2][l] += wx * self.dx;
            m[3][l] += wy * self.dy;
            m[4][l] += wx * self.dy;
            m[5][l] += wx * q.r[l];
            m[6][l] += wx * q.g[l];
            m[7][l] += wx * q.b[l];
            m[8][l] += wy * q.r[l];
            m[9][l] += wy * q.g[l];
            m[10][l] += wy * q.b[l];
        }
    }
}

/// A tap's weight: the kernel's `h` times the edge-stopping weights, from the centre's and the
/// neighbour's luminance (`[centre, neighbour, 1/(σl·standard deviation)]`), depth (`[centre,
/// neighbour, 1/tolerance]`) and normals (the centre's with its reach, then the neighbour's:
/// exp(−σn·max(0, reach − n·n'))). A neighbour of infinite depth (outside the image) weighs 0.
#[inline(always)]
fn tap_weight(
    h: f32,
    sigma_normal: f32,
    [lum_p, lum_q, tolerance]: [f32; 3],
    [z_p, z_q, inverse_depth]: [f32; 3],
    [n_px, n_py, n_pz, reach]: [f32; 4],
    n_q: [f32; 3],
) -> f32 {
    let luminance = (lum_p - lum_q).abs() * tolerance;
    let depth = (z_p - z_q).abs() * inverse_depth;
    let cos = n_px * n_q[0] + n_py * n_q[1] + n_pz * n_q[2];
    let normal = sigma_normal * (reach - cos).max(0.0);
    h * exp_neg(luminance + depth + normal)
}

/// e^−x for x ≥ 0 (NaN and anything from 87 on give 0), within 10⁻⁵ relative: 2^t, t =
/// −x·log₂e, as 2^r·2^f with r the integer nearest t and f = t − r in [−½, ½], the second a
/// degree-5 Taylor polynomial of e^(f·ln 2). r is found by adding 1.5·2²³, which leaves it in
/// the sum's low mantissa bits, and 2^r is built from its bits: no float-to-integer
/// conversion, no branch, so the tap loop stays vector code on any instruction set; plain
/// float operations, so the same on every machine.
#[inline(always)]
fn exp_neg(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0; // 1.5·2²³
    // `!(x < 87)` also catches NaN; past 87, e^−x is below f32's normal range.
    let outside = !(x < 87.0);
    let x = if outside { 0.0 } else { x.max(0.0) };
    let t = -x * std::f32::consts::LOG2_E;
    let shifted = t + ROUND;
    let r = shifted - ROUND;
    let f = (t - r) * std::f32::consts::LN_2;
    let p = 1.0 + f * (1.0 + f * (0.5 + f * (1.0 / 6.0 + f * (1.0 / 24.0 + f * (1.0 / 120.0)))));
    // r in [−126, 0]: 2^r's exponent field is r + 127 ≥ 1.
    let whole = shifted.to_bits().wrapping_sub(ROUND.to_bits()) as i32;
    let scale = f32::from_bits(((whole + 127) as u32) << 23);
    if outside { 0.0 } else { scale * p }
}

/// The albedo a colour is divided by: each channel, at least [`ALBEDO_FLOOR`].
fn effective(albedo: Vec3) -> Vec3 {
    albedo.max(Vec3::splat(ALBEDO_FLOOR))
}

/// For a single sample, whose spread is unknown: the variance of the light's luminance over
/// each pixel's 5 × 5 neighbourhood (within the image).
fn spatial_variance(light: &[Vec3], width: usize, height: usize) -> Vec<f32> {
    let lum = |i: usize| luminance(light[i].x, light[i].y, light[i].z);
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, v) in row.iter_mut().enumerate() {
            let (mut n, mut sum, mut sum_sq) = (0.0f32, 0.0f32, 0.0f32);
            for yq in y.saturating_sub(2)..(y + 3).min(height) {
                for xq in x.saturating_sub(2)..(x + 3).min(width) {
                    let l = lum(yq * width + xq);
                    n += 1.0;
                    sum += l;
                    sum_sq += l * l;
                }
            }
            let mean = sum / n;
            *v = (sum_sq / n - mean * mean).max(0.0);
        }
    });
    out
}

/// A film for the passes of `settings`' view of `scene` that is to be denoised: it tracks each
/// pixel's variance and brightest sample (its outlier, [`Noisy`]) and, where the integrator
/// records them ([`Tracer::records_features`]), what the samples saw.
pub fn denoising_film(scene: &Scene, settings: &RenderSettings) -> Film {
    let film = Film::with_noise(settings.camera.width, settings.camera.height).with_largest();
    if Tracer::new(scene, settings).records_features() {
        film.with_features()
    } else {
        film
    }
}

/// The features to denoise `film`, the passes of `settings`' view of `scene`: those its samples
/// recorded ([`Features::recorded`]), or else traced ([`Features::trace`]).
pub fn features_of(
    film: &Film,
    scene: &Scene,
    settings: &RenderSettings,
    cancelled: &(dyn Fn() -> bool + Sync),
) -> Result<Features, Cancelled> {
    match Features::recorded(film) {
        Some(features) => Ok(features),
        None => Features::trace(scene, settings, cancelled),
    }
}

/// `settings`' render (exactly [`render`]'s image) and, if it is noisy
/// ([`RenderSettings::is_stochastic`]), its denoised image: the passes are accumulated in a
/// [`denoising_film`], and the default [`Denoiser`] run with [`features_of`] it. Where nothing
/// is noisy there is nothing to denoise: `None`. On the current rayon pool.
pub fn render_denoised(scene: &Scene, settings: &RenderSettings) -> (Image, Option<Image>) {
    if !settings.is_stochastic() {
        return (render(scene, settings), None);
    }
    let never = || false;
    let mut film = denoising_film(scene, settings);
    for sample in 0..settings.samples_per_pixel.max(1) {
        let pass = accumulate_pass(scene, settings, sample, &mut film, &never);
        pass.expect("never cancelled");
    }
    let raw = film.resolve();
    let features = features_of(&film, scene, settings, &never).expect("never cancelled");
    let denoised = Denoiser::default().denoise_noisy(&Noisy::of_film(&film), &features);
    (raw, Some(denoised))
}

#[cfg(test)]
mod tests;
