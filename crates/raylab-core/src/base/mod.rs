//! The bottom rung: what every other folder uses and which uses none of them. Rays and
//! vectors ([`geometry`]), sixteen-lane arithmetic ([`lanes`]), random numbers and sampling
//! ([`sampling`]), noise, the camera (equation 24's ray through a pixel, [`camera`]), and small
//! utilities: names, invalid-input errors, memory limits, temporary files, reading inputs.

pub mod camera;
pub mod geometry;
pub mod inputs;
pub mod invalid;
pub mod lanes;
pub mod memory;
pub mod named;
pub mod noise;
pub mod sampling;
pub mod temp_files;
