//! Which kernels are fastest on this CPU, measured once at start-up.
//!
//! The widest instruction set is not the fastest everywhere. AMD's Zen 4 executes a 512-bit
//! instruction in two 256-bit halves, so its AVX-512 kernels may lose to AVX2 ones that test the
//! same triangles in two 8-wide steps; Zen 5 and Intel's AVX-512 cores run 512 bits at once. A
//! table by CPU model would be wrong for the next model, so raylab measures: [`calibrate`]
//! traces a small, fixed workload like the renderer's (camera rays in batches, then the shadow
//! rays from their hits towards the light) with every kernel set this CPU runs, a few rounds in
//! turn, and [`super::Isa::best`] uses the fastest. It takes a few milliseconds, once per
//! process. Every kernel set returns the same hits bit for bit (tests/bvh.rs, tests/packets.rs),
//! so the choice changes the speed, never the image. `--isa` (or `RAYLAB_ISA`) forces one.

use std::time::{Duration, Instant};

use glam::Vec3;

use super::{Accel, AccelKind, Hit, Isa};
use crate::bench::primary_rays;
use crate::camera::Camera;
use crate::geometry::{Ray, Triangle};
use crate::light::{PointLight, shadow_ray};
use crate::scene::cornell_triangles;

/// What [`calibrate`] measured: the best time of each kernel set on the workload, and the one
/// chosen.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub timings: Vec<(Isa, Duration)>,
    pub chosen: Isa,
}

impl Calibration {
    /// One line for people: "avx512 (avx512 1.9 ms, avx2 2.6 ms, scalar 9.1 ms)".
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
/// The camera's resolution for the workload: 96 × 96 rays.
const SIDE: u32 = 96;
/// Two kernel sets within this fraction of each other are a tie, which goes to the wider
/// (earlier in [`candidates`]): the difference is noise.
const TIE: f64 = 0.03;

/// The kernel sets worth measuring, widest first: every SIMD set this CPU runs (scalar only if
/// there is none).
fn candidates() -> Vec<Isa> {
    let mut sets: Vec<Isa> = Isa::available().into_iter().rev().collect();
    if sets.len() > 1 {
        sets.retain(|isa| !matches!(isa, Isa::Scalar));
    }
    sets
}

/// Measures every kernel set on the workload and returns the fastest.
pub fn calibrate() -> Calibration {
    let sets = candidates();
    if sets.len() == 1 {
        return Calibration {
            timings: vec![(sets[0], Duration::ZERO)],
            chosen: sets[0],
        };
    }
    let workloads = [
        Workload::new(cornell_triangles()),
        Workload::new(ball_in_box()),
    ];
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

/// A scene and the rays the renderer would cast in it: the default camera's rays through every
/// pixel centre, and the shadow rays from their hits to the lab's light.
struct Workload {
    triangles: Vec<Triangle>,
    primary: Vec<Ray>,
    shadow: Vec<(Ray, f32)>,
}

impl Workload {
    fn new(triangles: Vec<Triangle>) -> Self {
        let primary = primary_rays(&Camera::default_for(SIDE, SIDE));
        let reference = Accel::build(&triangles, AccelKind::Bvh2, Isa::Scalar);
        // The lab's shadow rays (`light::shadow_ray`), from the hits of the reference
        // traversal (no kernel set is chosen yet).
        let light = PointLight::default();
        let shadow = primary
            .iter()
            .filter_map(|ray| {
                let hit = reference.closest(&triangles, ray, f32::INFINITY)?;
                let normal = triangles[hit.index as usize].normal;
                shadow_ray(&light, ray.at(hit.t), normal, None)
            })
            .collect();
        Self {
            triangles,
            primary,
            shadow,
        }
    }

    /// Traces every ray with `accel`, 64 at a time as the integrators do; returns a count so
    /// the work is not optimised away.
    fn trace(&self, accel: &Accel) -> usize {
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

/// The Cornell box with a ball of 1,152 triangles on its floor: enough triangles for the wide
/// BVH (the bunny's and teapot's structure), few enough to build in a fraction of a millisecond.
fn ball_in_box() -> Vec<Triangle> {
    let mut triangles = cornell_triangles();
    let (centre, radius) = (Vec3::new(-0.3, 0.6, -0.2), 0.4);
    let (rings, segments) = (24, 24);
    let point = |ring: u32, segment: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * segment as f32 / segments as f32;
        centre
            + radius
                * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
    };
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (point(ring, segment), point(ring, segment + 1));
            let (c, d) = (point(ring + 1, segment), point(ring + 1, segment + 1));
            triangles.push(Triangle::new(a, b, c, 0));
            triangles.push(Triangle::new(b, d, c, 0));
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chosen_set_is_one_measured_and_within_the_tie_of_the_fastest() {
        let c = calibrate();
        let fastest = c.timings.iter().map(|t| t.1).min().unwrap();
        let chosen = c
            .timings
            .iter()
            .find(|(isa, _)| isa.name() == c.chosen.name())
            .expect("the chosen set was measured");
        assert!(chosen.1.as_secs_f64() <= fastest.as_secs_f64() * (1.0 + TIE));
        assert!(c.summary().starts_with(c.chosen.name()), "{}", c.summary());
        // Never the scalar loop when the CPU has SIMD kernels.
        if Isa::available().len() > 1 {
            assert!(!matches!(c.chosen, Isa::Scalar));
        }
    }

    #[test]
    fn the_workload_uses_both_structures_and_casts_shadow_rays() {
        let room = Workload::new(cornell_triangles());
        let ball = Workload::new(ball_in_box());
        assert_eq!(ball.triangles.len(), 30 + 2 * 24 * 24);
        let flat = Accel::build(&room.triangles, AccelKind::Auto, Isa::Scalar);
        let tree = Accel::build(&ball.triangles, AccelKind::Auto, Isa::Scalar);
        assert_eq!(
            (flat.kind(), tree.kind()),
            (AccelKind::Flat, AccelKind::Bvh8)
        );
        for w in [&room, &ball] {
            assert_eq!(w.primary.len(), (SIDE * SIDE) as usize);
            // Every camera ray hits the closed box; most hits see the light.
            assert!(w.shadow.len() > w.primary.len() / 2);
        }
    }
}
