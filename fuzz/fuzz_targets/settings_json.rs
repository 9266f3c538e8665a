//! Settings-file bytes → `RenderSettings::from_json` → `validate()` → a small render
//! ([`checks::settings_json`]).
#![no_main]

use libfuzzer_sys::fuzz_target;

// Each target uses one of its checks.
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

fuzz_target!(|data: &[u8]| checks::settings_json(data));
