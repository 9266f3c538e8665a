//! How good the denoiser is: images at a few sample counts, raw and denoised, held against a
//! converged reference. What `raylab bench --stage denoise` prints and the tests assert.
//!
//! The error measure is the relative mean squared error, as denoising papers and Open Image
//! Denoise's reports use it: the mean over pixels and channels of (x − r)² / (r² + 0.01), r the
//! reference; the 0.01 keeps black pixels from dominating. The reference is traced with another
//! seed than the images it judges, so its own remaining noise is independent of theirs (it
//! adds its variance, 1/4096 of a sample's, to every figure alike).

use glam::Vec3;

use super::{Denoiser, Noisy, denoising_film, features_of};
use crate::shapes::scene::Scene;
use crate::transport::film::{Film, Image};
use crate::transport::render::accumulate_pass;
use crate::transport::settings::RenderSettings;

/// The relative MSE of `image` against `reference` (see the module's text).
pub fn relative_mse(image: &Image, reference: &Image) -> f64 {
    assert_eq!(
        (image.width, image.height),
        (reference.width, reference.height)
    );
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(x, r)| {
            let (d, r) = ((*x - *r).as_dvec3(), r.as_dvec3());
            (d * d / (r * r + 0.01)).element_sum()
        })
        .sum();
    sum / (3.0 * image.pixels.len().max(1) as f64)
}

/// The denoised image's estimated error, relative as the raw image's noise is
/// ([`crate::transport::film::NoiseEstimate::relative_rms_error`]: the RMS over pixels of the error of
/// each pixel's channel mean, over the RMS of the pixel values), from what the denoiser was
/// given: `raw`, the mean of the samples, `variance`, the variance of each pixel's mean
/// ([`Film::variance`]), `denoised`, the filter's output, and `denoise`, the same filter
/// (with the same features and variance) to run once more. No reference is needed.
///
/// It is Stein's unbiased risk estimate (SURE; as Li, Sen and Zwicker use it to steer a
/// renderer's reconstruction, "SURE-based optimization for adaptive sampling and
/// reconstruction", 2012): for D a filtering of R = T + noise of variance v, the expected
/// squared error E(D − T)² = E(D − R)² − v + 2v·∂D/∂R, summed over the pixels. It counts the
/// bias the filter adds (a blurred shadow's edge is far from R however clean it is), which a
/// variance carried through the filter's passes would not. The derivative of each pixel's
/// output by its own input (the filter's own weight, larger than its kernel's centre because
/// the edge-stopping weights follow the pixel's own noise) is found as Ramani, Blu and Unser's
/// Monte Carlo SURE finds it ("Monte-Carlo SURE", 2008): the raw image is filtered again with
/// each pixel moved by ±ε·√v (signs from a fixed hash), and the change of the output, times
/// the sign, over the move, is the derivative. Summed over the image, the pixels' own
/// fluctuations average out; a sum at or below zero gives 0.
pub fn estimated_error(
    raw: &Image,
    variance: &[f32],
    denoised: &Image,
    denoise: impl FnOnce(&Image) -> Image,
) -> f64 {
    assert_eq!(raw.pixels.len(), variance.len());
    assert_eq!(raw.pixels.len(), denoised.pixels.len());
    let y = |p: Vec3| f64::from(p.x + p.y + p.z) / 3.0;
    let moves: Vec<f32> = variance
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let sign = if hash_bit(i as u64) { 1.0 } else { -1.0 };
            sign * SURE_STEP * v.max(0.0).sqrt()
        })
        .collect();
    let moved = Image {
        pixels: raw
            .pixels
            .iter()
            .zip(&moves)
            .map(|(p, m)| *p + Vec3::splat(*m))
            .collect(),
        ..raw.clone()
    };
    let moved = denoise(&moved);
    let (mut error, mut signal) = (0.0f64, 0.0f64);
    for (i, ((r, d), v)) in raw
        .pixels
        .iter()
        .zip(&denoised.pixels)
        .zip(variance)
        .enumerate()
    {
        let (r, d, v) = (y(*r), y(*d), f64::from(*v));
        let derivative = if moves[i] != 0.0 {
            (y(moved.pixels[i]) - d) / f64::from(moves[i])
        } else {
            0.0
        };
        error += (d - r) * (d - r) - v + 2.0 * v * derivative;
        signal += d * d;
    }
    if signal > 0.0 {
        (error.max(0.0) / signal).sqrt()
    } else {
        0.0
    }
}

/// The move of [`estimated_error`]'s second filtering, in standard deviations of each pixel's
/// mean.
const SURE_STEP: f32 = 0.1;

/// A fixed pseudo-random bit of `i` (SplitMix64's finaliser).
fn hash_bit(i: u64) -> bool {
    let mut z = i.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) & 1 == 1
}

/// The RMS of `image`'s error against `reference` as [`estimated_error`] measures it: of
/// each pixel's channel mean, over the RMS of the reference's, less `reference_variance`
/// (the variance of each of the reference's pixels, if it has noise of its own).
pub fn relative_rms_error(image: &Image, reference: &Image, reference_variance: &[f32]) -> f64 {
    let y = |p: Vec3| f64::from(p.x + p.y + p.z) / 3.0;
    let (mut error, mut signal) = (0.0f64, 0.0f64);
    for (i, (x, r)) in image.pixels.iter().zip(&reference.pixels).enumerate() {
        let (x, r) = (y(*x), y(*r));
        error += (x - r) * (x - r) - reference_variance.get(i).map_or(0.0, |v| f64::from(*v));
        signal += r * r;
    }
    (error.max(0.0) / signal.max(1e-300)).sqrt()
}

/// The mean of an image's pixels, per channel.
pub fn mean(image: &Image) -> Vec3 {
    let sum = image
        .pixels
        .iter()
        .fold(glam::DVec3::ZERO, |s, p| s + p.as_dvec3());
    (sum / image.pixels.len().max(1) as f64).as_vec3()
}

/// One sample count's figures.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct QualityRow {
    pub samples: u32,
    pub raw_relative_mse: f64,
    pub denoised_relative_mse: f64,
    /// The denoised image's mean over the raw image's, minus 1, largest channel.
    pub denoised_mean_change: f64,
}

/// The images of `settings` (its seed, its sample count ignored) at each count of `counts`
/// (ascending), raw and denoised, against a reference of `reference_samples` traced with
/// another seed. The passes of one film are snapshotted at each count, so the whole costs
/// `max(counts) + reference_samples` passes.
pub fn measure(
    scene: &Scene,
    settings: &RenderSettings,
    counts: &[u32],
    reference_samples: u32,
    denoiser: &Denoiser,
) -> Vec<QualityRow> {
    let never = || false;
    let trace = |settings: &RenderSettings, film: &mut Film, sample: u32| {
        accumulate_pass(scene, settings, sample, film, &never).expect("never cancelled");
    };
    let (width, height) = (settings.camera.width, settings.camera.height);
    let mut reference_settings = settings.clone();
    reference_settings.seed = settings.seed.wrapping_add(0x9e37_79b9);
    let mut reference = Film::new(width, height);
    for sample in 0..reference_samples {
        trace(&reference_settings, &mut reference, sample);
    }
    let reference = reference.resolve();
    let mut film = denoising_film(scene, settings);
    let mut rows = Vec::new();
    for &count in counts {
        while film.samples() < count {
            let sample = film.samples();
            trace(settings, &mut film, sample);
        }
        let raw = film.resolve();
        let features = features_of(&film, scene, settings, &never).expect("never cancelled");
        let denoised = denoiser.denoise_noisy(&Noisy::of_film(&film), &features);
        let (before, after) = (mean(&raw), mean(&denoised));
        let change = ((after - before) / before.max(Vec3::splat(1e-12))).abs();
        rows.push(QualityRow {
            samples: count,
            raw_relative_mse: relative_mse(&raw, &reference),
            denoised_relative_mse: relative_mse(&denoised, &reference),
            denoised_mean_change: f64::from(change.max_element()),
        });
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    /// By hand: pixel values 1.1 and 0 against 1 and 0.1 (all channels): (0.1²/1.01 +
    /// 0.1²/0.02) / 2 = (0.00990099 + 0.5) / 2 = 0.2549505.
    /// The estimate follows the denoised image's real error against a converged reference
    /// (its own noise taken out): the path-traced box at 48², from 4 to 64 samples, within
    /// a factor 1.5 either way, and falling as the samples grow, below the raw noise.
    #[test]
    fn the_estimated_error_of_a_denoised_image_tracks_its_real_error() {
        let scene = crate::shapes::scene::cornell_box();
        let mut settings = RenderSettings::default();
        settings.camera = settings.camera.with_resolution(48, 48);
        settings.shading.stage = crate::Stage::Path;
        let never = || false;
        let mut reference_settings = settings.clone();
        reference_settings.seed = settings.seed.wrapping_add(0x9e37_79b9);
        let mut reference = Film::with_noise(48, 48);
        for sample in 0..2048 {
            accumulate_pass(&scene, &reference_settings, sample, &mut reference, &never).unwrap();
        }
        let reference_variance = reference.variance().unwrap();
        let reference = reference.resolve();
        let mut film = denoising_film(&scene, &settings);
        let mut last = f64::INFINITY;
        for count in [4, 16, 64] {
            while film.samples() < count {
                let sample = film.samples();
                accumulate_pass(&scene, &settings, sample, &mut film, &never).unwrap();
            }
            let raw = film.resolve();
            let variance = film.variance().unwrap();
            let features = features_of(&film, &scene, &settings, &never).unwrap();
            let denoised = Denoiser::default().denoise(&raw, Some(&variance), &features);
            let estimate = estimated_error(&raw, &variance, &denoised, |moved| {
                Denoiser::default().denoise(moved, Some(&variance), &features)
            });
            let real = relative_rms_error(&denoised, &reference, &reference_variance);
            let raw_noise = film.noise().unwrap().relative_rms_error;
            assert!(
                estimate > real / 1.5 && estimate < real * 1.5,
                "{count} samples: estimated {estimate}, really {real}"
            );
            assert!(
                real < raw_noise,
                "{count} samples: {real} vs raw {raw_noise}"
            );
            assert!(estimate < last, "{count} samples: {estimate} after {last}");
            last = estimate;
        }
    }

    #[test]
    fn relative_mse_by_hand() {
        let image = Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::splat(1.1), Vec3::ZERO],
        };
        let reference = Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::ONE, Vec3::splat(0.1)],
        };
        let e = relative_mse(&image, &reference);
        assert!((e - 0.254_950_5).abs() < 1e-6, "{e}");
        assert_eq!(relative_mse(&reference, &reference), 0.0);
    }
}
