//! Integrators: what a camera ray is worth.
//!
//! Two integrators share everything below the choice of what to compute:
//!
//! * [`lab`]: the lab's stages (figures 2, 3, 5, 6 and 7), with mirror and glass followed
//!   Whitted-style: every specular branch is traced to a diffuse hit, which is then shaded as the
//!   stage says. Deterministic: sample 0 is the lab's image.
//! * [`path`]: Monte Carlo path tracing: the lab's direct term at every diffuse vertex plus real
//!   indirect light from cosine-weighted bounces, where the lab adds the constant N.
//!
//! **Units.** The lab's value of a diffuse hit is R = ρ·D (equation 28), where D is the
//! irradiance from the point light (equation 27). The radiance a diffuse surface reflects is
//! (ρ/π)·D, so the lab's image is π × radiance. The path tracer keeps those units: its image is
//! π × radiance too, so with no bounces it *is* the `shadows` stage, and each bounce adds the
//! real indirect light that the lab's N stands in for.
//!
//! **One computation at a hit.** Both integrators evaluate a diffuse hit with the same code:
//! [`Lighting::at`] computes D (equation 27) and the shadow ray (section 5.1), the caller casts
//! the shadow rays of a whole batch together and records whether each was blocked, and
//! [`shaded_value`] combines ρ, D and N as equations 28–30 say. That code is generic over a
//! lane type ([`crate::base::lanes`]): both integrators take it sixteen hits at a time through
//! `DiffuseHits` (the same operations in every lane, so the same bits; with the divisions and
//! square roots of a hit no longer one after another; PERFORMANCE.md, "Design choices and
//! what each buys"), and [`HitTerms`] ([`HitTerms::at`], [`HitTerms::value`]) is the same
//! code for one hit, which the tests and the pixel inspector's record of a hit use.
//! The one-ray path ([`Tracer::trace`] with one ray) is the batched path with a batch of one.
//!
//! **Watching a pixel.** Both integrators are generic over a [`Recorder`], told each step as it
//! happens (every closest hit, every mirror or glass branch, every hit's terms once its shadow
//! ray is answered, every path vertex's scattering). The renderer passes `()`, which records
//! nothing and compiles away; the pixel inspector ([`crate::teaching::inspect`]) passes a recording, so
//! what it explains is what the renderer computed, not a second copy of the formulas.

mod hit_terms;
mod hits;
pub mod lab;
pub mod path;
pub mod path_mis;
pub mod photons;
mod recorder;
mod scratch;
mod tracer;

use crate::transport::film::Seen;

/// How many rays the integrators take through each phase together. Phases (all closest hits,
/// then the light at every hit, then all shadow rays, then the sums) are loops of independent
/// queries, which the CPU overlaps; ray by ray, every pixel's long chain of dependent divisions
/// and square roots runs alone (PERFORMANCE.md, "Design choices and what each buys": phase
/// batching).
pub const BATCH: usize = 64;

/// How many paths the sixteen-lane path tracer takes through each phase together: eight
/// batches of camera rays. Paths end at different vertices and each vertex's phases run in
/// whole groups of sixteen lanes, so at each vertex a batch's last group is partly empty: the
/// more paths a batch holds, the smaller that share, and the more paths share each phase's
/// own costs (calls, the kernels' set-up). 512 is where larger batches stop paying: a
/// thread's working memory still fits in its core's L2 cache (the images are the same at
/// any size; PERFORMANCE.md, "Design choices and what each buys" and "Tried and not kept
/// (details in git)"). The camera rays' first hits and their shadow rays are still bounded
/// by cones a batch of [`BATCH`] at a time (`accel::cull`: a wider fan keeps more
/// triangles). At most 65,536: a path's index in its batch is a `u16`.
pub const PATH_BATCH: usize = 512;
const _: () = assert!(PATH_BATCH.is_multiple_of(BATCH) && PATH_BATCH <= 1 << 16);

pub use crate::transport::settings::{
    DEFAULT_SPECULAR_DEPTH, Integrator, MAX_SPECULAR_DEPTH, Shading, Stage,
};
use hits::HitScratch;
pub(crate) use hits::{GROUPS, PATH_GROUPS};

/// The mirror and glass bounces a camera sample's features follow before they settle on what
/// was reached ([`Seen`]).
pub const FEATURE_SPECULAR_BOUNCES: u32 = 4;

pub use hit_terms::*;
pub use recorder::Recorder;
pub use scratch::Scratch;
use scratch::Working;
pub use tracer::Tracer;

#[cfg(test)]
mod tests;
