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
use crate::film::{Film, Image};
use crate::render::accumulate_pass;
use crate::scene::Scene;
use crate::settings::RenderSettings;

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
