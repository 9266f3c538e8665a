//! Helpers for the tests that run the `raylab` binary as a user does.
// Each test binary that includes this module uses only some of it.
#![allow(dead_code)]

pub mod rays;

use std::ffi::OsString;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `raylab ARGS…` and waits for it.
pub fn raylab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .output()
        .expect("run raylab")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The names of the entries of a folder (to check no temporary file was left behind).
pub fn files_in(dir: &Path) -> Vec<OsString> {
    std::fs::read_dir(dir)
        .expect("read the folder")
        .map(|e| e.expect("a folder entry").file_name())
        .collect()
}

/// The default settings (figure 7's scene, light and camera) at `side × side` with `stage` and
/// its figure's switches: what the image tests start from.
pub fn settings(stage: raylab::Stage, side: u32) -> raylab::RenderSettings {
    let mut s = raylab::RenderSettings::default();
    s.camera = s.camera.with_resolution(side, side);
    s.shading = raylab::Shading::for_stage(stage);
    s
}

/// An image's pixels as bits, to compare images exactly.
pub fn bits(image: &raylab::Image) -> Vec<[u32; 3]> {
    image
        .pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}
