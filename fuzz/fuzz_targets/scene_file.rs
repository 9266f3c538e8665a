//! Scene-file bytes → `raylab_core::files::scene_file::parse` → a saved copy that reads back the same → a
//! small render ([`checks::scene_file`]).
#![no_main]

use libfuzzer_sys::fuzz_target;

// Each target uses one of its checks.
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

fuzz_target!(|data: &[u8]| checks::scene_file(data));
