//! Text → the equation sandbox's lexer, parser and compiler → what compiles evaluated and
//! explained over an 8 × 8 recording of the lab's box ([`checks::sandbox`]).
#![no_main]

use libfuzzer_sys::fuzz_target;

// Each target uses one of its checks.
#[allow(dead_code)]
#[path = "../checks.rs"]
mod checks;

fuzz_target!(|data: &[u8]| checks::sandbox(data));
