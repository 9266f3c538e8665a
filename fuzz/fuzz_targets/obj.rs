//! OBJ bytes → the model standing in the box → an 8 × 8 image of it ([`checks::obj`]).
#![no_main]

use libfuzzer_sys::fuzz_target;

// Each target uses one of its checks.
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

fuzz_target!(|data: &[u8]| checks::obj(data));
