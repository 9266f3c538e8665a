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
//! 2. Five passes of a 5 × 5 B3-spline kernel, its taps 1, 2, 4, 8 and 16 pixels apart (a 125
//!    pixel wide filter for 25 taps a pass). A tap weighs less the more its pixel differs from
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

use crate::film::Image;

/// The B3-spline's weights: the 5 × 5 kernel is their outer product.
const B3: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// Below this, an albedo channel is taken as 1: nothing to divide out (a black surface, the
/// background), and the colour is filtered as it is.
const ALBEDO_FLOOR: f32 = 1e-3;

/// The filter's settings. The defaults are SVGF's, tuned on the path-traced Cornell box
/// (PERFORMANCE.md gives the quality they reach).
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
            passes: 5,
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
        let (width, height) = (colour.width as usize, colour.height as usize);
        assert_eq!(
            (features.width, features.height),
            (colour.width, colour.height)
        );
        if width == 0 || height == 0 {
            return colour.clone();
        }
        let albedo: Vec<Vec3> = features.albedo.iter().map(|a| effective(*a)).collect();
        let mut light = demodulate(colour, &albedo);
        match variance {
            Some(variance) => {
                assert_eq!(variance.len(), width * height);
                for ((v, s), a) in light.variance.iter_mut().zip(variance).zip(&albedo) {
                    let a = (a.x + a.y + a.z) / 3.0;
                    *v = s / (a * a);
                }
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
            self.pass(step, width, height, &light, &guide, &mut next);
            std::mem::swap(&mut light, &mut next);
        }
        Image {
            width: colour.width,
            height: colour.height,
            pixels: albedo
                .iter()
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
        for y in 0..height {
            for x in 0..width {
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
                depth_slope[y * width + x] = self.sigma_depth * gx.max(gy);
            }
        }
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
    fn pass(
        &self,
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
            .iter()
            .map(|v| 1.0 / (self.sigma_luminance * v.max(0.0).sqrt() + 1e-4))
            .collect();
        let luminance: Vec<f32> = (0..width * height)
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
                row.filter(r, g, b, v);
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

impl Row<'_> {
    #[inline(never)]
    fn filter(&self, r: &mut [f32], g: &mut [f32], b: &mut [f32], v: &mut [f32]) {
        let (width, step) = (self.width, self.step);
        let centre = self.y * width..(self.y + 1) * width;
        let src = self.src;
        // The centre tap weighs its kernel weight alone.
        let h0 = B3[2] * B3[2];
        let mut sum_w = vec![h0; width];
        let mut sum_r: Vec<f32> = src.r[centre.clone()].iter().map(|c| h0 * c).collect();
        let mut sum_g: Vec<f32> = src.g[centre.clone()].iter().map(|c| h0 * c).collect();
        let mut sum_b: Vec<f32> = src.b[centre.clone()].iter().map(|c| h0 * c).collect();
        let mut sum_v: Vec<f32> = src.variance[centre.clone()]
            .iter()
            .map(|c| h0 * h0 * c)
            .collect();
        let guide = self.guide;
        for (j, ky) in B3.iter().enumerate() {
            let dy = (j as isize - 2) * step as isize;
            let yq = self.y as isize + dy;
            if yq < 0 || yq >= self.height as isize {
                continue;
            }
            for (i, kx) in B3.iter().enumerate() {
                let dx = (i as isize - 2) * step as isize;
                if (dx == 0 && dy == 0) || dx.unsigned_abs() >= width {
                    continue;
                }
                let h = kx * ky;
                let distance = (i.abs_diff(2).max(j.abs_diff(2)) * step) as f32;
                // The pixels x whose neighbour x + dx is in the image.
                let lo = (-dx).max(0) as usize;
                let hi = (width as isize - dx.max(0)).max(lo as isize) as usize;
                let p = centre.start + lo..centre.start + hi;
                let q0 = (yq as usize * width) as isize + lo as isize + dx;
                let q = q0 as usize..q0 as usize + (hi - lo);
                let taps = Taps {
                    lum_p: &self.luminance[p.clone()],
                    lum_q: &self.luminance[q.clone()],
                    tolerance: &self.inverse_tolerance[p.clone()],
                    z_p: &guide.depth[p.clone()],
                    z_q: &guide.depth[q.clone()],
                    slope: &guide.depth_slope[p.clone()],
                    floor: &guide.depth_floor[p.clone()],
                    nx_p: &guide.nx[p.clone()],
                    ny_p: &guide.ny[p.clone()],
                    nz_p: &guide.nz[p.clone()],
                    nx_q: &guide.nx[q.clone()],
                    ny_q: &guide.ny[q.clone()],
                    nz_q: &guide.nz[q.clone()],
                    r_q: &src.r[q.clone()],
                    g_q: &src.g[q.clone()],
                    b_q: &src.b[q.clone()],
                    v_q: &src.variance[q],
                };
                taps.add(
                    h,
                    distance,
                    self.sigma_normal,
                    &mut Sums {
                        w: &mut sum_w[lo..hi],
                        r: &mut sum_r[lo..hi],
                        g: &mut sum_g[lo..hi],
                        b: &mut sum_b[lo..hi],
                        v: &mut sum_v[lo..hi],
                    },
                );
            }
        }
        for x in 0..width {
            let inverse = 1.0 / sum_w[x];
            r[x] = sum_r[x] * inverse;
            g[x] = sum_g[x] * inverse;
            b[x] = sum_b[x] * inverse;
            v[x] = sum_v[x] * inverse * inverse;
        }
    }
}

/// One tap offset's inputs along a run of a row: the centre pixels (`_p`) and their neighbours
/// at the offset (`_q`), as slices of one length.
struct Taps<'a> {
    lum_p: &'a [f32],
    lum_q: &'a [f32],
    tolerance: &'a [f32],
    z_p: &'a [f32],
    z_q: &'a [f32],
    slope: &'a [f32],
    floor: &'a [f32],
    nx_p: &'a [f32],
    ny_p: &'a [f32],
    nz_p: &'a [f32],
    nx_q: &'a [f32],
    ny_q: &'a [f32],
    nz_q: &'a [f32],
    r_q: &'a [f32],
    g_q: &'a [f32],
    b_q: &'a [f32],
    v_q: &'a [f32],
}

/// The running weighted sums of a row's run.
struct Sums<'a> {
    w: &'a mut [f32],
    r: &'a mut [f32],
    g: &'a mut [f32],
    b: &'a mut [f32],
    v: &'a mut [f32],
}

impl Taps<'_> {
    /// Adds each neighbour, weighted by the kernel weight `h` and the edge-stopping weights,
    /// to its centre's sums. Written as one flat loop over equal-length slices, which the
    /// compiler turns into vector code.
    #[inline(always)]
    fn add(&self, h: f32, distance: f32, sigma_normal: f32, sums: &mut Sums) {
        let n = self.lum_p.len();
        // Every slice cut to one length up front: the loop's indexing then needs no bounds
        // checks, which would keep it scalar.
        let (lum_p, lum_q, tolerance) = (&self.lum_p[..n], &self.lum_q[..n], &self.tolerance[..n]);
        let (z_p, z_q) = (&self.z_p[..n], &self.z_q[..n]);
        let (slope, floor) = (&self.slope[..n], &self.floor[..n]);
        let (nx_p, ny_p, nz_p) = (&self.nx_p[..n], &self.ny_p[..n], &self.nz_p[..n]);
        let (nx_q, ny_q, nz_q) = (&self.nx_q[..n], &self.ny_q[..n], &self.nz_q[..n]);
        let (r_q, g_q, b_q, v_q) = (
            &self.r_q[..n],
            &self.g_q[..n],
            &self.b_q[..n],
            &self.v_q[..n],
        );
        let (sum_w, sum_r, sum_g) = (&mut sums.w[..n], &mut sums.r[..n], &mut sums.g[..n]);
        let (sum_b, sum_v) = (&mut sums.b[..n], &mut sums.v[..n]);
        // Sixteen taps at a time through fixed-size arrays, which the compiler keeps in vector
        // registers; the rest one at a time. Both through `tap_weight`.
        let mut k = 0;
        while k + 16 <= n {
            macro_rules! block {
                ($s:expr) => {
                    <&[f32; 16]>::try_from(&$s[k..k + 16]).expect("16 values")
                };
            }
            let (lp, lq, tol) = (block!(lum_p), block!(lum_q), block!(tolerance));
            let (zp, zq, sl, fl) = (block!(z_p), block!(z_q), block!(slope), block!(floor));
            let (xp, yp, wp) = (block!(nx_p), block!(ny_p), block!(nz_p));
            let (xq, yq, wq) = (block!(nx_q), block!(ny_q), block!(nz_q));
            let mut w = [0.0f32; 16];
            for l in 0..16 {
                w[l] = tap_weight(
                    h,
                    sigma_normal,
                    distance,
                    [lp[l], lq[l], tol[l]],
                    [zp[l], zq[l], sl[l], fl[l]],
                    [xp[l], yp[l], wp[l]],
                    [xq[l], yq[l], wq[l]],
                );
            }
            let (r, g, b, v) = (block!(r_q), block!(g_q), block!(b_q), block!(v_q));
            for l in 0..16 {
                let w = w[l];
                sum_w[k + l] += w;
                sum_r[k + l] += w * r[l];
                sum_g[k + l] += w * g[l];
                sum_b[k + l] += w * b[l];
                sum_v[k + l] += w * w * v[l];
            }
            k += 16;
        }
        for k in k..n {
            let w = tap_weight(
                h,
                sigma_normal,
                distance,
                [lum_p[k], lum_q[k], tolerance[k]],
                [z_p[k], z_q[k], slope[k], floor[k]],
                [nx_p[k], ny_p[k], nz_p[k]],
                [nx_q[k], ny_q[k], nz_q[k]],
            );
            sum_w[k] += w;
            sum_r[k] += w * r_q[k];
            sum_g[k] += w * g_q[k];
            sum_b[k] += w * b_q[k];
            sum_v[k] += w * w * v_q[k];
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
        .iter()
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

#[cfg(test)]
mod tests;
