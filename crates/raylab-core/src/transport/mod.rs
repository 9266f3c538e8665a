//! Light transport, from settings to a finished image: what to render
//! ([`settings`]), the integrators ([`integrator`]: the lab's stages and the path tracer), photon
//! maps, the film and the display transform, the denoiser, [`render`] over every pixel,
//! progressive refinement and the debug views.

pub mod denoise;
pub mod display;
pub mod film;
pub mod integrator;
pub mod photon_map;
pub mod progressive;
pub mod render;
pub mod settings;
pub mod view;
