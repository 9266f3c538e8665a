//! Fireflies taken apart before the filter, and their light given back after it.
//!
//! A firefly is one sample far brighter than the pixel's others: a path that found, by a rare
//! direction, a lot of light (a diffuse bounce into a mirror or through glass onto an area
//! light, a photon estimate's spike). The à-trous filter cannot remove it: its neighbours
//! differ from it by many standard deviations of their noise and reject it, and it keeps most
//! of its own value. So the film keeps each pixel's brightest sample
//! ([`Film::with_largest`]), and where that sample is an outlier — brighter than the mean of
//! the pixel's other samples by more than [`OUTLIER_DEVIATIONS`] of their standard deviations
//! — the pixel's colour is split in two:
//!
//! - its mean over the other samples, (Σ − m)/(n − 1), with their variance, which the filter
//!   denoises as any other pixel's colour;
//! - the rest, the outlier's excess over that mean divided by n, so that the two add up to the
//!   pixel's mean exactly: Σ/n = (Σ − m)/(n − 1) + (m − (Σ − m)/(n − 1))/n.
//!
//! The excess is not dropped (clamping would darken the image for good: the bright rare paths
//! are real light, a caustic's) but spread over the pixels around it that show the same
//! surface ([`spread`]): three à-trous passes of a 3 × 3 binomial kernel (a blur of about 3
//! pixels' standard deviation, reaching [`SPREAD_RADIUS`]) times the filter's normal and depth
//! weights, times each receiving pixel's albedo, normalised so each pixel's excess is given
//! back whole, per channel. The image's light is kept exactly (to rounding): the split adds no
//! bias to the mean, only moves a pixel's brightest sample's share of light up to
//! [`SPREAD_RADIUS`] pixels within its surface, a blur of what is rare, which converges as its
//! samples do.
//!
//! The threshold is low ([`OUTLIER_DEVIATIONS`]): at 64 samples most pixels of the path-traced
//! box lose their brightest sample to the spread. What the filter then denoises has no heavy
//! tail (no pixel's own rare bright sample for the luminance weights to hold on to), and the
//! brightest samples' light, the noisiest part, is blurred without a luminance weight. On the
//! mirror-and-glass box at 256² and 64 samples this lowered the denoised error from
//! 6.3·10⁻⁴ (only fireflies of 16 deviations taken apart) to 5.8·10⁻⁴; with the looser
//! normal and depth weights the filter then allows ([`super::Denoiser::judged_sigma_normal`]),
//! to 5.5·10⁻⁴.

use glam::Vec3;

use super::{BINOMIAL, Features, effective, exp_neg};
use crate::shapes::accel::Isa;
use crate::shapes::accel::set::{Compiled, InstructionSet};
use crate::transport::film::{Film, FilmSums, Image, channel_mean, mean_and_variance_of_mean};

/// How many standard deviations of a pixel's other samples its brightest may lie above their
/// mean before it is taken apart (module docs). A well-behaved pixel's largest of 64 samples
/// lies a few deviations above; a firefly, tens to thousands. 3 takes most pixels' brightest
/// apart: on the mirror-and-glass box 3 to 4 gave the lowest error, 16 (fireflies only) the
/// highest.
pub const OUTLIER_DEVIATIONS: f64 = 3.0;

/// The samples a pixel needs before its brightest can be judged against the others: with
/// fewer, their spread is too uncertain: split at 16 samples, the box's denoised mean moves
/// by more than the denoiser's tests allow (0.5 %).
pub const OUTLIER_MIN_SAMPLES: u32 = 32;

/// The spread's à-trous steps: three passes of the 3 × 3 binomial kernel, taps 1, 2 and 4
/// pixels apart, a blur of variance (1 + 4 + 16)/2 pixels² (σ ≈ 3.2). The 5 × 5 B3-spline's
/// (σ ≈ 4.6) gave the same error for twice the time; steps 1, 2, 3, 4 or 1, 2, 4, 8, more.
const SPREAD_STEPS: [usize; 3] = [1, 2, 4];

/// How far, in pixels, an outlier's excess is spread: the sum of [`SPREAD_STEPS`].
pub const SPREAD_RADIUS: i32 = 7;

/// A noisy image as the filter takes it: the colour without its outliers, the variance of that
/// colour's mean per pixel, and the outliers' excess to give back after the filter.
#[derive(Clone, Debug, PartialEq)]
pub struct Noisy {
    pub colour: Image,
    /// `None` for a single sample (the filter estimates it from the neighbourhood).
    pub variance: Option<Vec<f32>>,
    /// The pixels whose brightest sample was an outlier, and its share of their mean.
    pub excess: Vec<(usize, Vec3)>,
    /// Whether each pixel's brightest sample was judged (a film of [`OUTLIER_MIN_SAMPLES`]
    /// samples or more that kept them): then the filter uses its looser normal and depth
    /// weights ([`super::Denoiser::judged_sigma_normal`]).
    pub judged: bool,
}

impl Noisy {
    /// An image and its variance as they are: nothing taken apart.
    pub fn whole(colour: Image, variance: Option<Vec<f32>>) -> Noisy {
        Noisy {
            colour,
            variance,
            excess: Vec::new(),
            judged: false,
        }
    }

    /// `film`'s mean, its outliers taken apart (module docs) if it keeps its pixels' brightest
    /// samples and tracks their spread; else its mean and variance as they are.
    pub fn of_film(film: &Film) -> Noisy {
        let FilmSums {
            sum: sums,
            sum_sq,
            largest,
            samples: n,
        } = film.sums();
        let (Some(sum_sq), Some(largest)) = (sum_sq, largest) else {
            return Noisy::whole(film.resolve(), film.variance());
        };
        let mut colour = film.resolve();
        let Some(mut variance) = film.variance() else {
            return Noisy::whole(colour, None);
        };
        let mut excess = Vec::new();
        let judged = n >= OUTLIER_MIN_SAMPLES;
        if judged {
            for (i, ((sum, &sq), &m)) in sums.iter().zip(sum_sq).zip(largest).enumerate() {
                let Some((others, others_variance)) = without(*sum, sq, m, n) else {
                    continue;
                };
                colour.pixels[i] = others;
                variance[i] = others_variance;
                excess.push((i, (m - others) / n as f32));
            }
        }
        Noisy {
            colour,
            variance: Some(variance),
            excess,
            judged,
        }
    }
}

/// If `largest`, one of the `n` samples summing to `sum` (their squared channel means to
/// `sum_sq`), is an outlier: the mean of the other samples and the variance of that mean.
fn without(sum: Vec3, sum_sq: f32, largest: Vec3, n: u32) -> Option<(Vec3, f32)> {
    let others = n - 1;
    let (mean, variance_of_mean) = mean_and_variance_of_mean(
        sum - largest,
        sum_sq - channel_mean(largest) * channel_mean(largest),
        others,
    );
    let deviation = (variance_of_mean * f64::from(others)).sqrt();
    let bright = f64::from(channel_mean(largest));
    (bright > mean + OUTLIER_DEVIATIONS * deviation && bright > 0.0)
        .then(|| ((sum - largest) / others as f32, variance_of_mean as f32))
}

/// Gives each outlier's excess back to `image` (the denoised colour), spread over the pixels
/// around it that show the same surface (module docs). The excess is an image, spread by
/// [`SPREAD_STEPS`]' passes; in each, pixel p sends its excess E to each tap q in proportion to
/// w(p, q)·a(q): the kernel's weight times the surface test (the filter's normal and depth
/// weights, symmetric in p and q) times q's albedo, normalised per channel by their sum over
/// p's taps, T(p). Both sums are gathers of the same weights (T = Σ w·a, then each pixel
/// receives a(q)·Σ w·E/T), so per channel the pixels receive exactly what was sent (to
/// rounding). Each pixel is computed on its own: the same on any thread count.
pub(super) fn spread(
    image: &mut Image,
    excess: &[(usize, Vec3)],
    features: &Features,
    sigma_normal: f32,
    sigma_depth: f32,
) {
    if excess.is_empty() {
        return;
    }
    let (width, height) = (image.width as usize, image.height as usize);
    let len = width * height;
    let plane = |f: &dyn Fn(usize) -> f32| (0..len).map(f).collect::<Vec<f32>>();
    let albedo: [Vec<f32>; 3] =
        std::array::from_fn(|c| plane(&|i: usize| effective(features.albedo[i])[c]));
    let surface = Surface {
        width,
        height,
        n: std::array::from_fn(|c| plane(&|i: usize| features.normal[i][c])),
        z: features.depth.clone(),
        sigma_normal,
        sigma_depth,
    };
    let mut light: [Vec<f32>; 3] = std::array::from_fn(|_| vec![0.0; len]);
    for &(i, value) in excess {
        for (c, plane) in light.iter_mut().enumerate() {
            plane[i] += value[c];
        }
    }
    for step in SPREAD_STEPS {
        let totals = surface.gather(step, &albedo);
        for (plane, total) in light.iter_mut().zip(&totals) {
            for (e, t) in plane.iter_mut().zip(total) {
                *e /= t;
            }
        }
        let received = surface.gather(step, &light);
        for ((plane, received), albedo) in light.iter_mut().zip(&received).zip(&albedo) {
            for ((e, r), a) in plane.iter_mut().zip(received).zip(albedo) {
                *e = r * a;
            }
        }
    }
    for (i, p) in image.pixels.iter_mut().enumerate() {
        *p += Vec3::new(light[0][i], light[1][i], light[2][i]);
    }
}

/// The features the spread's surface test reads, a plane each.
struct Surface {
    width: usize,
    height: usize,
    n: [Vec<f32>; 3],
    z: Vec<f32>,
    sigma_normal: f32,
    sigma_depth: f32,
}

/// A row of [`Surface::gather`] ([`Surface::row`]), compiled for each instruction set: the same
/// code and bits on each.
struct GatherRow<'a> {
    surface: &'a Surface,
    y: usize,
    step: usize,
    x: &'a [Vec<f32>; 3],
    row: &'a mut [f32],
}

impl Compiled for GatherRow<'_> {
    type Output = ();

    #[inline(always)]
    fn run<S: InstructionSet>(self, _: S) {
        self.surface.row(self.y, self.step, self.x, self.row)
    }
}

impl Surface {
    /// Per channel, each pixel p's Σ over the 3 × 3 taps q, `step` apart and inside the image,
    /// of the binomial kernel's weight times s(p, q)·x(q), s the surface test: exp(−σn·|n − n'|²/2 − |z − z'|/(σz·the
    /// mean depth/50 (at least 10⁻³)·the distance in pixels)), 1 for p itself. |n − n'|²/2 is
    /// 1 − n·n' for unit normals, and symmetric for an edge pixel's shorter averaged one.
    fn gather(&self, step: usize, x: &[Vec<f32>; 3]) -> [Vec<f32>; 3] {
        use rayon::prelude::*;
        let width = self.width;
        let isa = Isa::widest();
        let mut out = vec![0.0f32; 3 * width * self.height];
        out.par_chunks_mut(3 * width)
            .enumerate()
            .for_each(|(y, row)| {
                isa.call(GatherRow {
                    surface: self,
                    y,
                    step,
                    x,
                    row,
                })
            });
        // Back to a plane per channel.
        std::array::from_fn(|c| {
            out.chunks_exact(3 * width)
                .flat_map(|row| &row[c * width..(c + 1) * width])
                .copied()
                .collect()
        })
    }

    /// Row `y` of [`Surface::gather`], its three channels one after the other in `row`.
    #[inline(always)]
    fn row(&self, y: usize, step: usize, x: &[Vec<f32>; 3], row: &mut [f32]) {
        let (width, height) = (self.width, self.height);
        let (r, rest) = row.split_at_mut(width);
        let (g, b) = rest.split_at_mut(width);
        let p = y * width;
        for (j, ky) in BINOMIAL.iter().enumerate() {
            let oy = (j as isize - 1) * step as isize;
            let yq = y as isize + oy;
            if yq < 0 || yq >= height as isize {
                continue;
            }
            for (i, kx) in BINOMIAL.iter().enumerate() {
                let ox = (i as isize - 1) * step as isize;
                let h = kx * ky;
                // The columns whose tap is inside the image.
                let x0 = (-ox).max(0) as usize;
                let x1 = (width as isize - ox.max(0)).max(x0 as isize) as usize;
                let n = x1 - x0;
                let (out_r, out_g, out_b) = (&mut r[x0..x1], &mut g[x0..x1], &mut b[x0..x1]);
                let q = (yq * width as isize + x0 as isize + ox) as usize;
                let (xr, xg, xb) = (&x[0][q..q + n], &x[1][q..q + n], &x[2][q..q + n]);
                if ox == 0 && oy == 0 {
                    for k in 0..n {
                        out_r[k] += h * xr[k];
                        out_g[k] += h * xg[k];
                        out_b[k] += h * xb[k];
                    }
                    continue;
                }
                let distance = ((ox * ox + oy * oy) as f32).sqrt();
                let half_normal = 0.5 * self.sigma_normal;
                let depth_scale = 1.0 / (self.sigma_depth * distance);
                let s = p + x0;
                let (pnx, pny, pnz, pz) = (
                    &self.n[0][s..s + n],
                    &self.n[1][s..s + n],
                    &self.n[2][s..s + n],
                    &self.z[s..s + n],
                );
                let (qnx, qny, qnz, qz) = (
                    &self.n[0][q..q + n],
                    &self.n[1][q..q + n],
                    &self.n[2][q..q + n],
                    &self.z[q..q + n],
                );
                for k in 0..n {
                    let (dx, dy, dz) = (pnx[k] - qnx[k], pny[k] - qny[k], pnz[k] - qnz[k]);
                    let normal = half_normal * (dx * dx + dy * dy + dz * dz);
                    let tolerance = ((pz[k] + qz[k]) * 0.01).max(1e-3);
                    let depth = (pz[k] - qz[k]).abs() * depth_scale / tolerance;
                    let w = h * exp_neg(normal + depth);
                    out_r[k] += w * xr[k];
                    out_g[k] += w * xg[k];
                    out_b[k] += w * xb[k];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 9 × 9 film of 32 passes of 0.5 (0.4 and 0.6 in turn at odd pixels), one of whose
    /// samples at the centre is 50 instead.
    fn film_with_a_firefly() -> Film {
        let mut film = Film::with_noise(9, 9).with_largest();
        for pass in 0..32 {
            let mut image = Image::new(9, 9);
            for (i, p) in image.pixels.iter_mut().enumerate() {
                let wobble = if i % 2 == 1 {
                    0.1 - 0.2 * (pass % 2) as f32
                } else {
                    0.0
                };
                *p = Vec3::splat(0.5 + wobble);
            }
            if pass == 5 {
                image.pixels[40] = Vec3::splat(50.0);
            }
            film.add_pass(&image);
        }
        film
    }

    /// The firefly is taken apart: the centre's colour is its other samples' mean (0.5, with
    /// no spread), its excess (50 − 0.5)/32; no other pixel (whose samples spread by ±0.1) is
    /// touched. Given back over uniform features, the excess is whole, per channel, and
    /// spread: the centre keeps a small part of it.
    #[test]
    fn an_outlier_is_taken_apart_and_given_back_whole() {
        let film = film_with_a_firefly();
        let noisy = Noisy::of_film(&film);
        assert_eq!(noisy.excess.len(), 1, "{:?}", noisy.excess);
        let (i, excess) = noisy.excess[0];
        assert_eq!(i, 40);
        assert!((excess - Vec3::splat(49.5 / 32.0)).abs().max_element() < 1e-5);
        assert!(
            (noisy.colour.pixels[40] - Vec3::splat(0.5))
                .abs()
                .max_element()
                < 1e-6
        );
        let variance = noisy.variance.as_ref().unwrap();
        assert!(variance[40] < 1e-9, "{}", variance[40]);
        let whole = film.resolve();
        let film_variance = film.variance().unwrap();
        for j in (0..81).filter(|&j| j != 40) {
            assert_eq!(noisy.colour.pixels[j], whole.pixels[j]);
            assert_eq!(variance[j], film_variance[j]);
        }
        // The mean is kept: colour plus excess is the film's mean.
        let kept = noisy.colour.pixels[40] + excess;
        assert!((kept - whole.pixels[40]).abs().max_element() < 1e-5);

        let mut image = Image::new(9, 9);
        let features = Features::uniform(9, 9, Vec3::splat(0.7), Vec3::Z, 2.0);
        spread(&mut image, &noisy.excess, &features, 16.0, 1.5);
        let total: Vec3 = image.pixels.iter().copied().sum();
        assert!((total - excess).abs().max_element() < 1e-5, "{total}");
        assert!(image.pixels[40].x < 0.1 * excess.x, "{}", image.pixels[40]);
        assert!(image.pixels.iter().all(|p| p.x > 0.0));
    }

    /// A film that keeps no brightest samples, or has too few samples to judge them, is taken
    /// as it is.
    #[test]
    fn without_the_brightest_samples_nothing_is_taken_apart() {
        let mut plain = Film::with_noise(9, 9);
        let mut few = Film::with_noise(9, 9).with_largest();
        for pass in 0..OUTLIER_MIN_SAMPLES - 1 {
            let mut image = Image::new(9, 9);
            image.pixels[40] = Vec3::splat(if pass == 0 { 50.0 } else { 0.5 });
            plain.add_pass(&image);
            few.add_pass(&image);
        }
        for film in [plain, few] {
            assert_eq!(
                Noisy::of_film(&film),
                Noisy::whole(film.resolve(), film.variance())
            );
        }
    }
    /// Excess at each pixel of a wall, beside another wall meeting it at a crease, a nearer
    /// block and the void (a row of no hit): per channel, the spread gives back the whole of
    /// it, keeps it off the other wall, the block and the void, and gives the same bits on 1,
    /// 2 and 3 threads.
    #[test]
    fn the_spread_keeps_the_light_stays_on_its_surface_and_is_deterministic() {
        let (w, h) = (41u32, 23u32);
        let mut features = Features::uniform(w, h, Vec3::new(0.8, 0.3, 0.1), Vec3::Z, 3.0);
        let mut excess = Vec::new();
        for y in 0..h as usize {
            for x in 0..w as usize {
                let i = y * w as usize + x;
                if x >= 20 {
                    features.normal[i] = Vec3::X;
                }
                if (5..9).contains(&y) && (3..12).contains(&x) {
                    features.depth[i] = 1.5;
                }
                if y == 0 {
                    (features.albedo[i], features.normal[i], features.depth[i]) =
                        (Vec3::ZERO, Vec3::ZERO, 0.0);
                }
                // Only the left wall (outside the block) sends light.
                let sends = x < 20 && y > 0 && !(5..9).contains(&y);
                let value = if sends {
                    (i % 7) as f32 * 0.1 + 0.05
                } else {
                    0.0
                };
                excess.push((i, Vec3::new(value, 2.0 * value, 0.5 * value)));
            }
        }
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut image = Image::new(w, h);
            pool.install(|| spread(&mut image, &excess, &features, 16.0, 1.5));
            image
        };
        let image = run(1);
        assert_eq!(image, run(2));
        assert_eq!(image, run(3));
        let sent: Vec3 = excess.iter().map(|(_, v)| *v).sum();
        let total: Vec3 = image.pixels.iter().copied().sum();
        assert!(
            ((total - sent) / sent).abs().max_element() < 1e-5,
            "{total} vs {sent}"
        );
        // The other wall, the block and the void receive (almost) nothing.
        let elsewhere: Vec3 = image
            .pixels
            .iter()
            .enumerate()
            .filter(|(i, _)| {
                let (x, y) = (i % w as usize, i / w as usize);
                x >= 21 || y == 0 || ((6..8).contains(&y) && (4..11).contains(&x))
            })
            .map(|(_, p)| *p)
            .sum();
        assert!(
            elsewhere.max_element() < 1e-3 * sent.max_element(),
            "{elsewhere}"
        );
    }
}
