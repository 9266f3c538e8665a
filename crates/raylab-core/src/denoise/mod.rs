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
//! 2. Four passes of a 5 × 5 B3-spline kernel, its taps 1, 2, 4 and 8 pixels apart (a 61
//!    pixel wide filter for 25 taps a pass; a fifth pass, 16 apart, blurred the light's
//!    changes near corners more than it removed noise, on the path-traced box). A tap weighs less the more its pixel differs from
//!    the centre's: in normal (`exp(−σn·(1 − n·n'))`), in depth relative to the centre's depth
//!    slope, and in the light's luminance relative to how noisy it still is (σl times its
//!    standard deviation, from the film's per-pixel variance, itself filtered along).
//!    Noise is what differs by about a standard deviation; an edge of a shadow differs by
//!    many, and as samples accumulate the standard deviation falls and the filter lets go.
//!
//! The result depends only on the inputs (no random numbers, each pixel computed on its own),
//! so it is the same on any thread count. The film's linear mean is never changed: the
//! denoised image is a second image made from it.

mod features;
pub mod quality;

use glam::Vec3;
use rayon::prelude::*;

pub use features::{FEATURE_SAMPLES, Features};

use crate::film::{Film, Image};
use crate::render::{Cancelled, render, render_pass};
use crate::scene::Scene;
use crate::settings::RenderSettings;

/// The B3-spline's weights: the 5 × 5 kernel is their outer product.
const B3: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// Below this, an albedo channel is taken as 1: nothing to divide out (a black surface, the
/// background), and the colour is filtered as it is.
const ALBEDO_FLOOR: f32 = 1e-3;

/// The filter's settings. The defaults are SVGF's σs, with the passes tuned on the path-traced
/// Cornell box (PERFORMANCE.md gives the quality they reach).
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
}

impl Default for Denoiser {
    fn default() -> Self {
        Self {
            passes: 4,
            sigma_luminance: 4.0,
            sigma_normal: 128.0,
            sigma_depth: 1.0,
        }
    }
}

/// Planes of per-pixel values: the light (colour over albedo) and its variance.
#[derive(Clone)]
struct Light {
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
    variance: Vec<f32>,
}

/// The features as the filter reads them, a plane each.
struct Guide {
    nx: Vec<f32>,
    ny: Vec<f32>,
    nz: Vec<f32>,
    depth: Vec<f32>,
    /// σz times the depth's change per pixel at the pixel (the smaller one-sided difference
    /// of each axis, the larger axis).
    depth_slope: Vec<f32>,
    /// A floor under the depth tolerance: a thousandth of the depth.
    depth_floor: Vec<f32>,
}

impl Denoiser {
    /// The denoised `colour`: `variance` is the per-pixel variance of its mean (the film's,
    /// [`crate::film::Film::variance`]), or `None` for a single sample, whose noise is then
    /// estimated from its neighbourhood. `colour`, `variance` and `features` must be of one
    /// size.
    pub fn denoise(&self, colour: &Image, variance: Option<&[f32]>, features: &Features) -> Image {
        self.denoise_with(Isa::best(), colour, variance, features)
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
        let albedo: Vec<Vec3> = features.albedo.par_iter().map(|a| effective(*a)).collect();
        let mut light = demodulate(colour, &albedo);
        match variance {
            Some(variance) => {
                assert_eq!(variance.len(), width * height);
                light
                    .variance
                    .par_iter_mut()
                    .zip(variance)
                    .zip(&albedo)
                    .for_each(|((v, s), a)| {
                        let a = (a.x + a.y + a.z) / 3.0;
                        *v = s / (a * a);
                    });
            }
            None => light.variance = spatial_variance(&light, width, height),
        }
        let guide = self.guide(features);
        let mut next = light.clone();
        for pass in 0..self.passes {
            let step = 1usize << pass;
            if step >= width.max(height) {
                break;
            }
            self.pass(isa, step, width, height, &light, &guide, &mut next);
            std::mem::swap(&mut light, &mut next);
        }
        Image {
            width: colour.width,
            height: colour.height,
            pixels: albedo
                .par_iter()
                .enumerate()
                .map(|(i, a)| *a * Vec3::new(light.r[i], light.g[i], light.b[i]))
                .collect(),
        }
    }

    fn guide(&self, features: &Features) -> Guide {
        let (width, height) = (features.width as usize, features.height as usize);
        let depth = &features.depth;
        let at = |x: usize, y: usize| depth[y * width + x];
        let mut depth_slope = vec![0.0; width * height];
        depth_slope
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, slope) in row.iter_mut().enumerate() {
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
                    *slope = self.sigma_depth * gx.max(gy);
                }
            });
        Guide {
            nx: features.normal.iter().map(|n| n.x).collect(),
            ny: features.normal.iter().map(|n| n.y).collect(),
            nz: features.normal.iter().map(|n| n.z).collect(),
            depth_floor: depth.iter().map(|z| 1e-3 * z + 1e-6).collect(),
            depth: depth.clone(),
            depth_slope,
        }
    }

    /// One à-trous pass with taps `step` pixels apart, from `src` into `dst`.
    #[allow(clippy::too_many_arguments)]
    fn pass(
        &self,
        isa: Isa,
        step: usize,
        width: usize,
        height: usize,
        src: &Light,
        guide: &Guide,
        dst: &mut Light,
    ) {
        // The luminance's tolerance at each pixel: σl times the standard deviation of its
        // noise, from the variance blurred over 3 × 3 (a pixel's own estimate is noisy).
        let blurred = blur3(&src.variance, width, height);
        let inverse_tolerance: Vec<f32> = blurred
            .par_iter()
            .map(|v| 1.0 / (self.sigma_luminance * v.max(0.0).sqrt() + 1e-4))
            .collect();
        let luminance: Vec<f32> = (0..width * height)
            .into_par_iter()
            .map(|i| (src.r[i] + src.g[i] + src.b[i]) * (1.0 / 3.0))
            .collect();
        let sigma_normal = self.sigma_normal;
        dst.r
            .par_chunks_mut(width)
            .zip(dst.g.par_chunks_mut(width))
            .zip(dst.b.par_chunks_mut(width))
            .zip(dst.variance.par_chunks_mut(width))
            .enumerate()
            .for_each(|(y, (((r, g), b), v))| {
                let row = Row {
                    y,
                    step,
                    width,
                    height,
                    src,
                    guide,
                    luminance: &luminance,
                    inverse_tolerance: &inverse_tolerance,
                    sigma_normal,
                };
                row.filter(isa, r, g, b, v);
            });
    }
}

/// One output row of an à-trous pass.
struct Row<'a> {
    y: usize,
    step: usize,
    width: usize,
    height: usize,
    src: &'a Light,
    guide: &'a Guide,
    luminance: &'a [f32],
    inverse_tolerance: &'a [f32],
    sigma_normal: f32,
}

/// The instruction sets the filter's row loop is compiled for, the widest the CPU has chosen
/// at run time. Each is the same code ([`Row::filter_portable`]) and gives the same bits: Rust
/// never fuses a multiply and an add, whatever the instruction set (a test compares them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Isa {
    Portable,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Isa {
    fn best() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Isa::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Isa::Avx2;
            }
        }
        Isa::Portable
    }
}

impl Row<'_> {
    /// The row, with the row loop compiled for `isa` (which the CPU must have: [`Isa::best`]).
    fn filter(&self, isa: Isa, r: &mut [f32], g: &mut [f32], b: &mut [f32], v: &mut [f32]) {
        match isa {
            Isa::Portable => self.filter_portable(r, g, b, v),
            // SAFETY: `isa` is Avx2 or Avx512 only where `Isa::best` found the CPU to have it.
            // Measured: 512² on one thread of a Zen 4, the filter takes 190 ms as SSE2 code
            // and NN ms as AVX-512 code.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { self.filter_avx2(r, g, b, v) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => unsafe { self.filter_avx512(r, g, b, v) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn filter_avx2(&self, r: &mut [f32], g: &mut [f32], b: &mut [f32], v: &mut [f32]) {
        self.filter_portable(r, g, b, v)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn filter_avx512(&self, r: &mut [f32], g: &mut [f32], b: &mut [f32], v: &mut [f32]) {
        self.filter_portable(r, g, b, v)
    }

    /// Sixteen pixels at a time: their own values and running sums stay in registers (fixed
    /// arrays the compiler keeps in vector registers) through all 25 taps, each tap reading
    /// its sixteen neighbours straight from the row they are on, or, near the image's left
    /// and right edges, one by one with those outside the image weighing 0.
    #[inline(always)]
    fn filter_portable(&self, r: &mut [f32], g: &mut [f32], b: &mut [f32], v: &mut [f32]) {
        let (width, step) = (self.width, self.step);
        let (src, guide) = (self.src, self.guide);
        let row = self.y * width;
        let h0 = B3[2] * B3[2];
        // The sixteen neighbours' values, each plane read by `load(plane, …)` or
        // `gather(plane, …)` (a macro, not a function taking a closure: a closure not inlined
        // is compiled without the caller's instruction set).
        macro_rules! neighbours {
            ($read:ident($($arg:expr),*)) => {
                Neighbours {
                    lum: $read(self.luminance, $($arg),*),
                    z: $read(&guide.depth, $($arg),*),
                    n: [
                        $read(&guide.nx, $($arg),*),
                        $read(&guide.ny, $($arg),*),
                        $read(&guide.nz, $($arg),*),
                    ],
                    r: $read(&src.r, $($arg),*),
                    g: $read(&src.g, $($arg),*),
                    b: $read(&src.b, $($arg),*),
                    v: $read(&src.variance, $($arg),*),
                }
            };
        }
        let mut x0 = 0;
        while x0 < width {
            let n = (width - x0).min(LANES);
            // Lanes past the row's end repeat its last pixel; they are never written.
            macro_rules! lanes {
                ($plane:expr) => {
                    gather($plane, row, x0 as isize, width)
                };
            }
            let centre = Centre {
                lum: lanes!(self.luminance),
                tolerance: lanes!(self.inverse_tolerance),
                z: lanes!(&guide.depth),
                slope: lanes!(&guide.depth_slope),
                floor: lanes!(&guide.depth_floor),
                n: [lanes!(&guide.nx), lanes!(&guide.ny), lanes!(&guide.nz)],
            };
            let mut sums = Sums {
                w: [h0; LANES],
                r: scaled(h0, lanes!(&src.r)),
                g: scaled(h0, lanes!(&src.g)),
                b: scaled(h0, lanes!(&src.b)),
                v: scaled(h0 * h0, lanes!(&src.variance)),
            };
            for (j, ky) in B3.iter().enumerate() {
                let dy = (j as isize - 2) * step as isize;
                let yq = self.y as isize + dy;
                if yq < 0 || yq >= self.height as isize {
                    continue;
                }
                let row_q = yq as usize * width;
                for (i, kx) in B3.iter().enumerate() {
                    let dx = (i as isize - 2) * step as isize;
                    if dx == 0 && dy == 0 {
                        continue;
                    }
                    let tap = Tap {
                        h: kx * ky,
                        distance: (i.abs_diff(2).max(j.abs_diff(2)) * step) as f32,
                        sigma_normal: self.sigma_normal,
                    };
                    let first = x0 as isize + dx;
                    if n == LANES && first >= 0 && first as usize + LANES <= width {
                        // All sixteen neighbours in the image: read in place.
                        let q = row_q + first as usize;
                        let neighbours = neighbours!(load(q));
                        tap.add(&centre, &neighbours, [true; LANES], &mut sums);
                    } else {
                        let mut inside = [false; LANES];
                        for (l, inside) in inside.iter_mut().enumerate() {
                            let xq = first + l as isize;
                            *inside = l < n && xq >= 0 && xq < width as isize;
                        }
                        let neighbours = neighbours!(gather(row_q, first, width));
                        tap.add(&centre, &neighbours, inside, &mut sums);
                    }
                }
            }
            for l in 0..n {
                let inverse = 1.0 / sums.w[l];
                r[x0 + l] = sums.r[l] * inverse;
                g[x0 + l] = sums.g[l] * inverse;
                b[x0 + l] = sums.b[l] * inverse;
                v[x0 + l] = sums.v[l] * inverse * inverse;
            }
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

/// The sixteen values of the row starting at `row` in `plane` at columns `first..first + 16`,
/// each column clamped into the row `0..width`.
#[inline(always)]
fn gather(plane: &[f32], row: usize, first: isize, width: usize) -> [f32; LANES] {
    let mut out = [0.0; LANES];
    for (l, out) in out.iter_mut().enumerate() {
        let x = (first + l as isize).clamp(0, width as isize - 1);
        *out = plane[row + x as usize];
    }
    out
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
    tolerance: [f32; LANES],
    z: [f32; LANES],
    slope: [f32; LANES],
    floor: [f32; LANES],
    n: [[f32; LANES]; 3],
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
}

/// One tap of the kernel.
struct Tap {
    /// The kernel's weight.
    h: f32,
    /// How far the neighbour is, in pixels along the farther axis (the depth's tolerance grows
    /// with it).
    distance: f32,
    sigma_normal: f32,
}

impl Tap {
    /// Adds each neighbour (those `inside` the image), weighted by the kernel weight and the
    /// edge-stopping weights, to its centre's sums.
    #[inline(always)]
    #[allow(
        clippy::needless_range_loop,
        reason = "lane l of a dozen arrays at once: an index reads clearest"
    )]
    fn add(&self, p: &Centre, q: &Neighbours, inside: [bool; LANES], sums: &mut Sums) {
        for l in 0..LANES {
            let w = tap_weight(
                self.h,
                self.sigma_normal,
                self.distance,
                [p.lum[l], q.lum[l], p.tolerance[l]],
                [p.z[l], q.z[l], p.slope[l], p.floor[l]],
                [p.n[0][l], p.n[1][l], p.n[2][l]],
                [q.n[0][l], q.n[1][l], q.n[2][l]],
            );
            let w = if inside[l] { w } else { 0.0 };
            sums.w[l] += w;
            sums.r[l] += w * q.r[l];
            sums.g[l] += w * q.g[l];
            sums.b[l] += w * q.b[l];
            sums.v[l] += w * w * q.v[l];
        }
    }
}

/// A tap's weight: the kernel's `h` times the edge-stopping weights, from the centre's and the
/// neighbour's luminance (`[centre, neighbour, 1/(σl·standard deviation)]`), depth (`[centre,
/// neighbour, σz·slope, floor]`; the tolerance grows with the tap's `distance`) and normals.
#[inline(always)]
fn tap_weight(
    h: f32,
    sigma_normal: f32,
    distance: f32,
    [lum_p, lum_q, tolerance]: [f32; 3],
    [z_p, z_q, slope, floor]: [f32; 4],
    n_p: [f32; 3],
    n_q: [f32; 3],
) -> f32 {
    let luminance = (lum_p - lum_q).abs() * tolerance;
    let depth = (z_p - z_q).abs() / (slope * distance + floor);
    let cos = n_p[0] * n_q[0] + n_p[1] * n_q[1] + n_p[2] * n_q[2];
    let normal = sigma_normal * (1.0 - cos).max(0.0);
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

/// The albedo a colour is divided by: each channel, or 1 where the channel is about black.
fn effective(albedo: Vec3) -> Vec3 {
    let pick = |a: f32| if a > ALBEDO_FLOOR { a } else { 1.0 };
    Vec3::new(pick(albedo.x), pick(albedo.y), pick(albedo.z))
}

/// The light at each pixel: its colour over its albedo (variance left 0).
fn demodulate(colour: &Image, albedo: &[Vec3]) -> Light {
    let light: Vec<Vec3> = colour
        .pixels
        .par_iter()
        .zip(albedo)
        .map(|(c, a)| *c / *a)
        .collect();
    Light {
        r: light.iter().map(|l| l.x).collect(),
        g: light.iter().map(|l| l.y).collect(),
        b: light.iter().map(|l| l.z).collect(),
        variance: vec![0.0; light.len()],
    }
}

/// For a single sample, whose spread is unknown: the variance of the light's luminance over
/// each pixel's 5 × 5 neighbourhood (within the image).
fn spatial_variance(light: &Light, width: usize, height: usize) -> Vec<f32> {
    let lum = |i: usize| (light.r[i] + light.g[i] + light.b[i]) * (1.0 / 3.0);
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

/// `values` blurred by the 3 × 3 binomial kernel (¼, ½, ¼)², renormalised at the image's edges.
fn blur3(values: &[f32], width: usize, height: usize) -> Vec<f32> {
    const K: [f32; 3] = [0.25, 0.5, 0.25];
    let mut out = vec![0.0; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let (mut sum, mut weight) = (0.0, 0.0);
            for (j, ky) in K.iter().enumerate() {
                let Some(yq) = (y + j).checked_sub(1).filter(|yq| *yq < height) else {
                    continue;
                };
                for (i, kx) in K.iter().enumerate() {
                    let Some(xq) = (x + i).checked_sub(1).filter(|xq| *xq < width) else {
                        continue;
                    };
                    sum += kx * ky * values[yq * width + xq];
                    weight += kx * ky;
                }
            }
            *o = sum / weight;
        }
    });
    out
}

/// `settings`' render (exactly [`render`]'s image) and, if it is noisy
/// ([`RenderSettings::is_stochastic`]), its denoised image: the passes are accumulated in a
/// film that tracks each pixel's variance, the features traced, and the default [`Denoiser`]
/// run. Where nothing is noisy there is nothing to denoise: `None`. On the current rayon pool.
pub fn render_denoised(scene: &Scene, settings: &RenderSettings) -> (Image, Option<Image>) {
    if !settings.is_stochastic() {
        return (render(scene, settings), None);
    }
    let (width, height) = (settings.camera.width, settings.camera.height);
    let never = || false;
    let mut film = Film::with_noise(width, height);
    for sample in 0..settings.samples_per_pixel.max(1) {
        let pass: Result<Image, Cancelled> = render_pass(scene, settings, sample, &never);
        film.add_pass(&pass.expect("never cancelled"));
    }
    let raw = film.resolve();
    let features = Features::trace(scene, settings, &never).expect("never cancelled");
    let denoised = Denoiser::default().denoise(&raw, film.variance().as_deref(), &features);
    (raw, Some(denoised))
}

#[cfg(test)]
mod tests;
