//! The integrators' working memory: a thread's batches reuse one `Scratch` rather than zero a
//! new one for every batch.

use std::cell::RefCell;

use hits::HitScratch;
use path::PathScratch;

use super::*;
use crate::base::geometry::Ray;
use crate::base::memory::with_thread_memory;

/// The working memory of the sixteen-lane integrators' batches (the lab's waves, the path
/// tracer's vertices): the camera rays, the diffuse hits in lanes and the light at them, and
/// the path tracer's paths, here and the path batch's larger arrays on the heap
/// (`PathScratch`). Made once for a thread's rows and reused batch after batch: made afresh
/// for every batch of 64 rays, its zeroing (a `memset`) would be a share of the lab pass
/// (PERFORMANCE.md, "Design choices and what each buys": shared working memory).
pub struct Scratch {
    /// The lab's batches' hits, [`GROUPS`] groups.
    pub(super) lab: HitScratch<GROUPS>,
    /// The path tracer's hits ([`PATH_GROUPS`] groups) and paths.
    pub(super) path: PathScratch,
    /// A batch's camera rays, made from their image points.
    pub(super) rays: [Ray; PATH_BATCH],
}

impl Scratch {
    /// Working memory for any batch: a batch takes only what it wrote into it (the lanes it
    /// left are computed with, never taken; `a_reused_scratch_gives_the_values_of_a_fresh_one`).
    pub fn new() -> Self {
        Self {
            lab: HitScratch::new(),
            path: PathScratch::new(),
            rays: [Ray {
                origin: glam::Vec3::ZERO,
                direction: glam::Vec3::ZERO,
            }; PATH_BATCH],
        }
    }
}

impl Default for Scratch {
    fn default() -> Self {
        Self::new()
    }
}

thread_local! {
    /// The working memory of this thread's single calls ([`Tracer::trace`],
    /// [`Tracer::trace_recorded`]), made at the first: a [`Scratch`] is far more memory to fill
    /// than a call on one pixel (the inspector's) traces through.
    static CALL_SCRATCH: RefCell<Option<Box<Scratch>>> = const { RefCell::new(None) };
}

impl Scratch {
    /// `work` with this thread's [`CALL_SCRATCH`], or a fresh one if it is in use (a call
    /// inside another's recorder).
    pub(super) fn with_thread<T>(work: impl FnOnce(&mut Scratch) -> T) -> T {
        with_thread_memory(
            &CALL_SCRATCH,
            || None,
            |scratch| work(scratch.get_or_insert_with(Scratch::boxed)),
        )
    }

    /// A new working memory on the heap, made out of line: inlined, the whole [`Scratch`] would
    /// go into the callers' stack frames.
    #[cold]
    #[inline(never)]
    pub(super) fn boxed() -> Box<Scratch> {
        Box::new(Scratch::new())
    }
}

/// The integrators' working memory ([`Scratch`]'s parts for the lab and the path tracer).
pub(super) type Working<'a> = (&'a mut HitScratch<GROUPS>, &'a mut PathScratch);
