//! Helpers the tests share: the image tests' starting settings, exact comparison of images and
//! pixels (and renders against them), thread pools, random rays.
// Each test binary that includes this module uses only some of it.
#![allow(dead_code)]

pub mod rays;

use std::fmt::Display;

use glam::Vec3;
use raylab_core::shapes::scene::Scene;
use raylab_core::transport::render::{render, trace_pixel};
use raylab_core::{Image, RenderSettings};

/// The default settings (figure 7's scene, light and camera) at `side × side` with `stage` and
/// its figure's switches: what the image tests start from.
pub fn settings(stage: raylab_core::Stage, side: u32) -> RenderSettings {
    let mut s = RenderSettings::default();
    s.camera = s.camera.with_resolution(side, side);
    s.shading = raylab_core::Shading::for_stage(stage);
    s
}

/// The lab stage at 128² with the parallax floor under a light low over the floor's far right
/// corner, so that the tiles' self-shadows fall toward the camera (under the lab's light, in
/// front and above, they fall behind the tiles, out of the camera's sight).
pub fn parallax_floor_under_a_low_light() -> RenderSettings {
    let mut s = settings(raylab_core::Stage::Lab, 128);
    s.texture_preset = raylab_core::shading::material::TexturePreset::ParallaxFloor;
    s.light.position = Vec3::new(0.9, 0.7, 0.9);
    s
}

/// A pixel (or any `Vec3`) as bits, to compare exactly.
pub fn vec3_bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// An image's pixels as bits, to compare images exactly.
pub fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().copied().map(vec3_bits).collect()
}

/// Asserts that `got` is `want` bit for bit; a failure names `what` and the first pixel that
/// differs (not two whole images).
#[track_caller]
pub fn assert_same_image(got: &Image, want: &Image, what: impl Display) {
    assert_eq!(
        (got.width, got.height),
        (want.width, want.height),
        "{what}: size"
    );
    let differs = bits(got).iter().zip(&bits(want)).position(|(a, b)| a != b);
    if let Some(i) = differs {
        let (x, y) = (i as u32 % want.width, i as u32 / want.width);
        panic!(
            "{what}: pixel ({x}, {y}) is {} where {} was wanted",
            got.pixels[i], want.pixels[i]
        );
    }
}

/// Renders `settings` (every sample) and asserts that the image is `want` bit for bit.
#[track_caller]
pub fn assert_renders(scene: &Scene, settings: &RenderSettings, want: &Image, what: impl Display) {
    assert_same_image(&render(scene, settings), want, what);
}

/// Asserts that each of `pixels`, traced alone ([`trace_pixel`] at `sample`), is its pixel of
/// `image` (that sample's pass) bit for bit.
#[track_caller]
pub fn assert_pixels_trace_alone(
    scene: &Scene,
    settings: &RenderSettings,
    image: &Image,
    sample: u32,
    pixels: impl IntoIterator<Item = (u32, u32)>,
    what: impl Display,
) {
    for (x, y) in pixels {
        assert_eq!(
            vec3_bits(trace_pixel(scene, settings, x, y, sample)),
            vec3_bits(image.get(x, y)),
            "{what}: pixel ({x}, {y}), sample {sample}"
        );
    }
}

/// Every pixel of `settings`' image, row by row.
pub fn every_pixel(settings: &RenderSettings) -> impl Iterator<Item = (u32, u32)> + use<> {
    let (w, h) = (settings.camera.width, settings.camera.height);
    (0..h).flat_map(move |y| (0..w).map(move |x| (x, y)))
}

/// `f` run on a rayon pool of `threads` threads.
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}
