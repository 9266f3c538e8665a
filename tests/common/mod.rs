//! Helpers for the tests that run the `raylab` binary as a user does.
// Each test binary that includes this module uses only some of it.
#![allow(dead_code)]

// The core's helpers (settings, bits, rays), shared with its own tests.
#[path = "../../crates/raylab-core/tests/common/mod.rs"]
mod core_helpers;
#[allow(unused_imports)]
pub use core_helpers::*;

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
