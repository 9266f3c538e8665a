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
//! surface ([`spread`]): a Gaussian of [`SPREAD_RADIUS`] times the filter's own normal and depth
//! weights, times each pixel's albedo, normalised so the excess is given back whole, per
//! channel. The image's light is kept exactly (to rounding): the split adds no bias to the
//! mean, only moves an outlier's light up to [`SPREAD_RADIUS`] pixels within its surface, a
//! blur of what is rare, which converges as its samples do (with more samples, more of them
//! are among the "others" and fewer are outliers).

use glam::Vec3;

use super::{Features, effective};
use crate::film::{Film, FilmSums, Image, channel_mean, mean_and_variance_of_mean};

/// How many standard deviations of a pixel's other samples its brightest may lie above their
/// mean before it is taken apart. A well-behaved pixel's largest of 64 samples lies a few
/// deviations above; a firefly, tens to thousands.
pub const OUTLIER_DEVIATIONS: f64 = 16.0;

/// The samples a pixel needs before its brightest can be judged against the others: with
/// fewer, their spread is too uncertain, and at 16 samples the split (from 8) moved the 64²
/// box's denoised mean by more than 0.5 %.
pub const OUTLIER_MIN_SAMPLES: u32 = 32;

/// How far, in pixels, an outlier's excess is spread (the Gaussian's reach; its standard
/// deviation is half of it).
pub const SPREAD_RADIUS: i32 = 8;

/// A noisy image as the filter takes it: the colour without its outliers, the variance of that
/// colour's mean per pixel, and the outliers' excess to give back after the filter.
#[derive(Clone, Debug, PartialEq)]
pub struct Noisy {
    pub colour: Image,
    /// `None` for a single sample (the filter estimates it from the neighbourhood).
    pub variance: Option<Vec<f32>>,
    /// The pixels whose brightest sample was an outlier, and its share of their mean.
    pub excess: Vec<(usize, Vec3)>,
}

impl Noisy {
    /// An image and its variance as they are: nothing taken apart.
    pub fn whole(colour: Image, variance: Option<Vec<f32>>) -> Noisy {
        Noisy {
            colour,
            variance,
            excess: Vec::new(),
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
        if n >= OUTLIER_MIN_SAMPLES {
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
/// within [`SPREAD_RADIUS`] of it that show the same surface (module docs), in proportion to
/// a Gaussian of the distance, the filter's normal and depth weights against the outlier's
/// pixel and each pixel's albedo: per channel, the shares add up to the excess. The shares
/// are computed in parallel and added in the outliers' order: the same on any thread count.
pub(super) fn spread(
    image: &mut Image,
    excess: &[(usize, Vec3)],
    features: &Features,
    sigma_normal: f32,
    sigma_depth: f32,
) {
    use rayon::prelude::*;
    let (width, height) = (image.width as i32, image.height as i32);
    let sigma = SPREAD_RADIUS as f32 / 2.0;
    let offsets: Vec<(i32, i32)> = (-SPREAD_RADIUS..=SPREAD_RADIUS)
        .flat_map(|dy| (-SPREAD_RADIUS..=SPREAD_RADIUS).map(move |dx| (dx, dy)))
        .collect();
    let shares: Vec<Vec<(usize, Vec3)>> = excess
        .par_iter()
        .map(|&(i, value)| {
            let (x0, y0) = ((i % width as usize) as i32, (i / width as usize) as i32);
            let (n0, z0) = (features.normal[i], features.depth[i]);
            // The depth tolerance grows with the distance, as the filter's does with its step.
            let z_scale = sigma_depth * (z0 * 0.02).max(1e-3);
            let mut weights = Vec::with_capacity(offsets.len());
            let mut total = Vec3::ZERO;
            for &(dx, dy) in &offsets {
                let (x, y) = (x0 + dx, y0 + dy);
                if x < 0 || y < 0 || x >= width || y >= height {
                    continue;
                }
                let j = (y * width + x) as usize;
                let r2 = (dx * dx + dy * dy) as f32;
                let normal = sigma_normal * (n0.length_squared() - n0.dot(features.normal[j]));
                let depth = (features.depth[j] - z0).abs() / (z_scale * r2.sqrt().max(1.0));
                let w = (-(r2 / (2.0 * sigma * sigma)) - normal.max(0.0) - depth).exp();
                let w = w * effective(features.albedo[j]);
                total += w;
                weights.push((j, w));
            }
            // The outlier's own pixel weighs its albedo: `total` is never 0.
            let share = value / total;
            weights.into_iter().map(|(j, w)| (j, w * share)).collect()
        })
        .collect();
    for (j, value) in shares.into_iter().flatten() {
        image.pixels[j] += value;
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
}
