//! Helpers the tests share: the image tests' starting settings and exact comparison, random
//! rays.
// Each test binary that includes this module uses only some of it.
#![allow(dead_code)]

pub mod rays;

/// The default settings (figure 7's scene, light and camera) at `side × side` with `stage` and
/// its figure's switches: what the image tests start from.
pub fn settings(stage: raylab_core::Stage, side: u32) -> raylab_core::RenderSettings {
    let mut s = raylab_core::RenderSettings::default();
    s.camera = s.camera.with_resolution(side, side);
    s.shading = raylab_core::Shading::for_stage(stage);
    s
}

/// An image's pixels as bits, to compare images exactly.
pub fn bits(image: &raylab_core::Image) -> Vec<[u32; 3]> {
    image
        .pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}
