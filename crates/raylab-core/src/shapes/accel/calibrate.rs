//! Which kernels are fastest on this CPU, measured once at start-up.
//!
//! The widest instruction set is not the fastest everywhere: a CPU may execute a 512-bit
//! instruction as two 256-bit halves, and then its AVX-512 kernels may lose to AVX2 ones that
//! test the same triangles in two 8-wide steps. A table by CPU model would be wrong for the
//! next model, so raylab measures: [`calibrate`] traces the [`Workload`]s it is handed (a
//! scene's triangles, camera rays in batches, then the shadow rays from their hits towards the
//! light: the scene module makes them) with every kernel set this CPU runs, a few rounds in
//! turn, and [`super::Isa::best_with`] uses the fastest. It takes a few milliseconds, once per
//! process. Every kernel set returns the same hits bit for bit (tests/bvh.rs,
//! tests/packets.rs), so the choice changes the speed, never the image. `--isa` (or
//! `RAYLAB_ISA`) forces one.

use std::time::{Duration, Instant};

use super::{Accel, AccelKind, Hit, Isa};
use crate::base::geometry::{Ray, Triangle};

/// What [`calibrate`] measured: the best time of each kernel set on the workload, and the one
/// chosen.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub timings: Vec<(Isa, Duration)>,
    pub chosen: Isa,
}

impl Calibration {
    /// One line for people: the set chosen, then each set's best time, as
    /// "avx512 (avx512 … ms, avx2 … ms)".
    pub fn summary(&self) -> String {
        let times: Vec<String> = self
            .timings
            .iter()
            .map(|(isa, t)| format!("{} {:.2} ms", isa.name(), t.as_secs_f64() * 1e3))
            .collect();
        format!("{} ({})", self.chosen.name(), times.join(", "))
    }
}

/// Rounds of the workload per kernel set, in turn; the best round counts.
const ROUNDS: usize = 3;
/// Two kernel sets within this fraction of each other are a tie, which goes to the wider
/// (earlier in [`candidates`]): the difference is noise.
pub const TIE: f64 = 0.03;

/// The kernel sets worth measuring, widest first: every SIMD set this CPU runs (scalar only if
/// there is none).
fn candidates() -> Vec<Isa> {
    let mut sets: Vec<Isa> = Isa::available().into_iter().rev().collect();
    if sets.len() > 1 {
        sets.retain(|isa| !matches!(isa, Isa::Scalar));
    }
    sets
}

/// Measures every kernel set on `workloads` and returns the fastest.
pub fn calibrate(workloads: &[Workload]) -> Calibration {
    let sets = candidates();
    if sets.len() == 1 {
        return Calibration {
            timings: vec![(sets[0], Duration::ZERO)],
            chosen: sets[0],
        };
    }
    let built: Vec<Vec<Accel>> = sets
        .iter()
        .map(|&isa| {
            workloads
                .iter()
                .map(|w| Accel::build(&w.triangles, AccelKind::Auto, isa))
                .collect()
        })
        .collect();
    let mut best = vec![Duration::MAX; sets.len()];
    for _ in 0..ROUNDS {
        for (accels, best) in built.iter().zip(&mut best) {
            let start = Instant::now();
            for (w, accel) in workloads.iter().zip(accels) {
                std::hint::black_box(w.trace(accel));
            }
            *best = (*best).min(start.elapsed());
        }
    }
    let fastest = best.iter().min().copied().unwrap_or_default();
    let chosen = sets
        .iter()
        .zip(&best)
        .find(|(_, t)| t.as_secs_f64() <= fastest.as_secs_f64() * (1.0 + TIE))
        .map_or(sets[0], |(isa, _)| *isa);
    Calibration {
        timings: sets.into_iter().zip(best).collect(),
        chosen,
    }
}

/// A scene and the rays the renderer would cast in it: camera rays, and the shadow rays from
/// their hits towards a light (with the length up to the light).
pub struct Workload {
    pub triangles: Vec<Triangle>,
    pub primary: Vec<Ray>,
    pub shadow: Vec<(Ray, f32)>,
}

impl Workload {
    /// Traces every ray with `accel`, 64 at a time as the integrators do; returns a count so
    /// the work is not optimised away.
    pub fn trace(&self, accel: &Accel) -> usize {
        let mut hits = [None::<Hit>; 64];
        let mut blocked = [false; 64];
        let mut count = 0;
        for rays in self.primary.chunks(64) {
            let hits = &mut hits[..rays.len()];
            accel.closest_batch(&self.triangles, rays, f32::INFINITY, hits);
            count += hits.iter().filter(|h| h.is_some()).count();
        }
        for rays in self.shadow.chunks(64) {
            let blocked = &mut blocked[..rays.len()];
            accel.occluded_batch(&self.triangles, rays, blocked);
            count += blocked.iter().filter(|&&b| b).count();
        }
        count
    }
}
