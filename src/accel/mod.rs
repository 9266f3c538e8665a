//! Acceleration structures: what answers a [`crate::scene::Scene`]'s closest-hit and shadow
//! queries without testing every triangle.
//!
//! * [`bvh`]: a binary BVH, binned SAH build, and the readable scalar traversal (the reference).
//! * [`wide`]: the fast path — an 8-wide BVH collapsed from it, triangles in 8-wide packets —
//!   and the flat packet list (a SIMD loop over every triangle).
//! * [`simd`]: the box and triangle kernels, AVX2 with a scalar twin.
//!
//! [`Accel::build`] picks per scene ([`AccelKind::Auto`]): the flat list for tiny scenes (the
//! 30-triangle Cornell box, where it beats any tree: see PERFORMANCE.md), the wide BVH
//! otherwise, with the few triangles that are large next to the scene (the box's walls) set
//! apart in one packet tested first; and the widest kernels the CPU has ([`Isa::best`]).
//! Every kind returns exactly what [`crate::intersect::closest_intersection_brute_force`]
//! returns, ties included.
//!
//! ```
//! use glam::Vec3;
//! use raylab::accel::{Accel, AccelKind, Isa};
//! use raylab::geometry::Ray;
//! use raylab::intersect::closest_intersection_brute_force;
//! use raylab::scene::{SceneChoice, cornell_box};
//!
//! // The scene builds its structure itself: flat for the Cornell box, a BVH for the bunny.
//! assert_eq!(cornell_box().accel().kind(), AccelKind::Flat);
//! let bunny = SceneChoice::Bunny.load().unwrap();
//! assert_eq!(bunny.accel().kind(), AccelKind::Bvh8);
//!
//! // Any structure, any kernels: the brute-force loop's answer, bit for bit.
//! let ray = Ray::new(Vec3::new(0.0, 0.0, -3.001), Vec3::new(-0.1, 0.3, 1.0));
//! let want = closest_intersection_brute_force(&ray, &bunny.triangles, f32::INFINITY).unwrap();
//! for isa in Isa::available() {
//!     let accel = Accel::build(&bunny.triangles, AccelKind::Bvh8, isa);
//!     let hit = accel.closest(&bunny.triangles, &ray, f32::INFINITY).unwrap();
//!     assert_eq!((hit.index as usize, hit.t), (want.triangle_index, want.distance));
//! }
//! ```

pub mod bvh;
pub mod simd;
pub mod wide;

use std::fmt;
use std::str::FromStr;
use std::time::{Duration, Instant};

use crate::geometry::{Ray, Triangle};
use crate::intersect;

use self::bvh::Bvh;
use self::simd::RayK;
use self::simd::{Avx2, Avx512, Scalar};
use self::wide::{Bvh8Big, Flat};

/// Scenes with at most this many triangles use the flat packet list. Measured (PERFORMANCE.md,
/// 512×512 lab pass, 2 threads): on the 30-triangle Cornell box the flat AVX-512 loop takes
/// 7.9 ms against 10.8 ms for the 8-wide BVH; on the 1,022-triangle teapot it takes 91 ms
/// against 10.6 ms. The crossover lies in between; 64 (four 16-wide packets) is on the safe side.
pub const FLAT_MAX_TRIANGLES: usize = 64;

/// A closest hit: the triangle's index in the scene and `t`, `u`, `v` exactly as
/// [`intersect::intersect_triangle`] computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub index: u32,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Which structure to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AccelKind {
    /// Flat for tiny scenes, the 8-wide BVH otherwise.
    #[default]
    Auto,
    /// The lab's loop over every triangle, one at a time.
    BruteForce,
    /// Every triangle in 8-wide packets, tested in order.
    Flat,
    /// The binary BVH with the scalar reference traversal.
    Bvh2,
    /// The 8-wide BVH.
    Bvh8,
}

impl AccelKind {
    pub const ALL: [AccelKind; 5] = [
        AccelKind::Auto,
        AccelKind::BruteForce,
        AccelKind::Flat,
        AccelKind::Bvh2,
        AccelKind::Bvh8,
    ];

    pub fn name(self) -> &'static str {
        match self {
            AccelKind::Auto => "auto",
            AccelKind::BruteForce => "brute",
            AccelKind::Flat => "flat",
            AccelKind::Bvh2 => "bvh2",
            AccelKind::Bvh8 => "bvh8",
        }
    }
}

impl fmt::Display for AccelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for AccelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        AccelKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown accelerator '{s}' (expected auto, brute, flat, bvh2 or bvh8)")
            })
    }
}

/// Which kernels run the flat list and the wide BVH.
#[derive(Clone, Copy, Debug)]
pub enum Isa {
    Scalar,
    /// AVX2 + FMA: 8-wide everything.
    Avx2(Avx2),
    /// AVX-512: the flat list 16 wide; the 8-wide BVH keeps its AVX2 kernels.
    Avx512(Avx512),
}

impl Isa {
    /// The widest kernels this CPU runs: AVX-512, else AVX2 + FMA, else scalar.
    pub fn best() -> Self {
        match (Avx512::detect(), Avx2::detect()) {
            (Some(k), _) => Isa::Avx512(k),
            (None, Some(k)) => Isa::Avx2(k),
            (None, None) => Isa::Scalar,
        }
    }

    /// Every kernel set this CPU runs, scalar first.
    pub fn available() -> Vec<Isa> {
        let mut out = vec![Isa::Scalar];
        out.extend(Avx2::detect().map(Isa::Avx2));
        out.extend(Avx512::detect().map(Isa::Avx512));
        out
    }

    /// The named kernel set, if this CPU runs it: `scalar`, `avx2`, `avx512` or `best`.
    pub fn by_name(name: &str) -> Option<Isa> {
        match name {
            "best" => Some(Isa::best()),
            "scalar" => Some(Isa::Scalar),
            "avx2" => Avx2::detect().map(Isa::Avx2),
            "avx512" => Avx512::detect().map(Isa::Avx512),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Avx2(_) => "avx2",
            Isa::Avx512(_) => "avx512",
        }
    }
}

#[derive(Clone, Debug, Default)]
enum Structure {
    #[default]
    BruteForce,
    Flat(Flat),
    Bvh2(Bvh),
    Bvh8(Bvh8Big),
}

/// A built acceleration structure over one triangle list.
#[derive(Clone, Debug)]
pub struct Accel {
    structure: Structure,
    isa: Isa,
    /// How many triangles it was built over (a guard against a changed triangle list).
    triangles: usize,
    build_time: Duration,
}

impl Default for Accel {
    fn default() -> Self {
        Self {
            structure: Structure::BruteForce,
            isa: Isa::Scalar,
            triangles: 0,
            build_time: Duration::ZERO,
        }
    }
}

impl Accel {
    /// The structure [`AccelKind::Auto`] picks, with the best kernels of this CPU.
    pub fn new(triangles: &[Triangle]) -> Self {
        Self::build(triangles, AccelKind::Auto, Isa::best())
    }

    /// Builds `kind` over `triangles` (on the current rayon pool) using `isa`'s kernels.
    pub fn build(triangles: &[Triangle], kind: AccelKind, isa: Isa) -> Self {
        let start = Instant::now();
        let kind = match kind {
            AccelKind::Auto if triangles.len() <= FLAT_MAX_TRIANGLES => AccelKind::Flat,
            AccelKind::Auto => AccelKind::Bvh8,
            k => k,
        };
        let structure = match kind {
            AccelKind::Auto | AccelKind::BruteForce => Structure::BruteForce,
            AccelKind::Flat => Structure::Flat(Flat::build(triangles)),
            AccelKind::Bvh2 => Structure::Bvh2(Bvh::build(triangles)),
            AccelKind::Bvh8 => Structure::Bvh8(Bvh8Big::build(triangles)),
        };
        Self {
            structure,
            isa,
            triangles: triangles.len(),
            build_time: start.elapsed(),
        }
    }

    /// The kind actually built (never `Auto`).
    pub fn kind(&self) -> AccelKind {
        match self.structure {
            Structure::BruteForce => AccelKind::BruteForce,
            Structure::Flat(_) => AccelKind::Flat,
            Structure::Bvh2(_) => AccelKind::Bvh2,
            Structure::Bvh8(_) => AccelKind::Bvh8,
        }
    }

    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// How long [`Accel::build`] took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Whether this was built over a list of `n` triangles.
    pub fn built_for(&self, n: usize) -> bool {
        self.triangles == n
    }

    /// The closest hit with `0 ≤ t < t_max`: the lowest index among hits at the same
    /// distance, exactly as the brute-force loop.
    #[inline(always)]
    pub fn closest(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> Option<Hit> {
        match (&self.structure, self.isa) {
            (Structure::BruteForce, _) => {
                intersect::closest_intersection_brute_force(ray, triangles, t_max).map(|h| Hit {
                    index: h.triangle_index as u32,
                    t: h.distance,
                    u: h.u,
                    v: h.v,
                })
            }
            (Structure::Bvh2(b), _) => b.closest(triangles, ray, t_max),
            (Structure::Flat(f), Isa::Scalar) => {
                f.closest(Scalar, &RayK::for_triangles(ray), t_max)
            }
            (Structure::Bvh8(b), Isa::Scalar) => {
                let r = RayK::new(ray);
                let best = b.big.closest(Scalar, &r, t_max);
                b.tree.closest(Scalar, &r, t_max, best)
            }
            (s, Isa::Avx512(k)) => closest_avx512(k, s, ray, t_max),
            (s, Isa::Avx2(k)) => closest_avx2(k, s, ray, t_max),
        }
    }

    /// Whether anything is hit with `0 ≤ t < t_max` (a shadow ray's any-hit query).
    #[inline(always)]
    pub fn occluded(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> bool {
        match (&self.structure, self.isa) {
            (Structure::BruteForce, _) => intersect::occluded_brute_force(ray, triangles, t_max),
            (Structure::Bvh2(b), _) => b.occluded(triangles, ray, t_max),
            (Structure::Flat(f), Isa::Scalar) => {
                f.occluded(Scalar, &RayK::for_triangles(ray), t_max)
            }
            (Structure::Bvh8(b), Isa::Scalar) => {
                let r = RayK::new(ray);
                b.tree.occluded(Scalar, &r, t_max) || b.big.occluded(Scalar, &r, t_max)
            }
            (s, Isa::Avx512(k)) => occluded_avx512(k, s, ray, t_max),
            (s, Isa::Avx2(k)) => occluded_avx2(k, s, ray, t_max),
        }
    }
}

impl Accel {
    /// [`Accel::closest`] for many rays, `out[i]` for `rays[i]`: the same answers, with the
    /// choice of structure and kernels made once for the batch instead of once per ray, and the
    /// loop over the rays compiled with the kernels' instruction set.
    pub fn closest_batch(
        &self,
        triangles: &[Triangle],
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        debug_assert_eq!(rays.len(), out.len());
        match (&self.structure, self.isa) {
            (s @ (Structure::Flat(_) | Structure::Bvh8(_)), Isa::Avx512(k)) => {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `k` proves the CPU has AVX-512 F and DQ, and AVX2 and FMA.
                unsafe {
                    closest_batch_avx512(k, s, rays, t_max, out)
                }
                #[cfg(not(target_arch = "x86_64"))]
                closest_batch_avx512(k, s, rays, t_max, out)
            }
            (s @ (Structure::Flat(_) | Structure::Bvh8(_)), Isa::Avx2(k)) => {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `k` proves the CPU has AVX2 and FMA.
                unsafe {
                    closest_batch_avx2(k, s, rays, t_max, out)
                }
                #[cfg(not(target_arch = "x86_64"))]
                closest_batch_avx2(k, s, rays, t_max, out)
            }
            _ => {
                for (ray, hit) in rays.iter().zip(out) {
                    *hit = self.closest(triangles, ray, t_max);
                }
            }
        }
    }

    /// [`Accel::occluded`] for many rays, each with its own `t_max`: `out[i]` for `rays[i]`,
    /// the same answers, the choice of structure and kernels made once for the batch.
    pub fn occluded_batch(&self, triangles: &[Triangle], rays: &[(Ray, f32)], out: &mut [bool]) {
        debug_assert_eq!(rays.len(), out.len());
        match (&self.structure, self.isa) {
            (s @ (Structure::Flat(_) | Structure::Bvh8(_)), Isa::Avx512(k)) => {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `closest_batch`.
                unsafe {
                    occluded_batch_avx512(k, s, rays, out)
                }
                #[cfg(not(target_arch = "x86_64"))]
                occluded_batch_avx512(k, s, rays, out)
            }
            (s @ (Structure::Flat(_) | Structure::Bvh8(_)), Isa::Avx2(k)) => {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `closest_batch`.
                unsafe {
                    occluded_batch_avx2(k, s, rays, out)
                }
                #[cfg(not(target_arch = "x86_64"))]
                occluded_batch_avx2(k, s, rays, out)
            }
            _ => {
                for ((ray, t_max), blocked) in rays.iter().zip(out) {
                    *blocked = self.occluded(triangles, ray, *t_max);
                }
            }
        }
    }
}

// The traversals compiled with the kernels' instruction set, so the kernels inline into them.
// Each takes a batch: the structure is matched once, and a single query is a batch of one
// (`closest_avx2` and friends), so each traversal is written once.

#[cfg_attr(
    target_arch = "x86_64",
    target_feature(enable = "avx512f,avx512dq,avx2,fma")
)]
fn closest_batch_avx512(
    k: Avx512,
    s: &Structure,
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<Hit>],
) {
    let rays_out = rays.iter().zip(out);
    match s {
        // The flat loop 16 wide; the tree with the AVX2 kernels, its large triangles 16 wide.
        Structure::Flat(f) => {
            for (ray, hit) in rays_out {
                *hit = f.closest16(k, &RayK::for_triangles(ray), t_max);
            }
        }
        Structure::Bvh8(b) => {
            for (ray, hit) in rays_out {
                let r = RayK::new(ray);
                let best = b.big.closest16(k, &r, t_max);
                *hit = b.tree.closest(k.avx2(), &r, t_max, best);
            }
        }
        Structure::BruteForce | Structure::Bvh2(_) => {}
    }
}

#[cfg_attr(
    target_arch = "x86_64",
    target_feature(enable = "avx512f,avx512dq,avx2,fma")
)]
fn occluded_batch_avx512(k: Avx512, s: &Structure, rays: &[(Ray, f32)], out: &mut [bool]) {
    let rays_out = rays.iter().zip(out);
    match s {
        Structure::Flat(f) => {
            for ((ray, t_max), blocked) in rays_out {
                // No boxes: the ray needs no reciprocal direction.
                *blocked = f.occluded16(k, &RayK::for_triangles(ray), *t_max);
            }
        }
        Structure::Bvh8(b) => {
            for ((ray, t_max), blocked) in rays_out {
                let r = RayK::new(ray);
                *blocked = b.tree.occluded(k.avx2(), &r, *t_max) || b.big.occluded16(k, &r, *t_max);
            }
        }
        Structure::BruteForce | Structure::Bvh2(_) => {}
    }
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
fn closest_batch_avx2(k: Avx2, s: &Structure, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
    let rays_out = rays.iter().zip(out);
    match s {
        Structure::Flat(f) => {
            for (ray, hit) in rays_out {
                *hit = f.closest(k, &RayK::for_triangles(ray), t_max);
            }
        }
        Structure::Bvh8(b) => {
            for (ray, hit) in rays_out {
                let r = RayK::new(ray);
                let best = b.big.closest(k, &r, t_max);
                *hit = b.tree.closest(k, &r, t_max, best);
            }
        }
        Structure::BruteForce | Structure::Bvh2(_) => {}
    }
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
fn occluded_batch_avx2(k: Avx2, s: &Structure, rays: &[(Ray, f32)], out: &mut [bool]) {
    let rays_out = rays.iter().zip(out);
    match s {
        Structure::Flat(f) => {
            for ((ray, t_max), blocked) in rays_out {
                *blocked = f.occluded(k, &RayK::for_triangles(ray), *t_max);
            }
        }
        Structure::Bvh8(b) => {
            for ((ray, t_max), blocked) in rays_out {
                let r = RayK::new(ray);
                *blocked = b.tree.occluded(k, &r, *t_max) || b.big.occluded(k, &r, *t_max);
            }
        }
        Structure::BruteForce | Structure::Bvh2(_) => {}
    }
}

fn closest_avx2(k: Avx2, s: &Structure, ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut hit = [None];
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `k` proves the CPU has AVX2 and FMA.
    unsafe {
        closest_batch_avx2(k, s, std::slice::from_ref(ray), t_max, &mut hit)
    };
    #[cfg(not(target_arch = "x86_64"))]
    closest_batch_avx2(k, s, std::slice::from_ref(ray), t_max, &mut hit);
    hit[0]
}

fn occluded_avx2(k: Avx2, s: &Structure, ray: &Ray, t_max: f32) -> bool {
    let mut blocked = [false];
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `k` proves the CPU has AVX2 and FMA.
    unsafe {
        occluded_batch_avx2(k, s, &[(*ray, t_max)], &mut blocked)
    };
    #[cfg(not(target_arch = "x86_64"))]
    occluded_batch_avx2(k, s, &[(*ray, t_max)], &mut blocked);
    blocked[0]
}

fn closest_avx512(k: Avx512, s: &Structure, ray: &Ray, t_max: f32) -> Option<Hit> {
    let mut hit = [None];
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `k` proves the CPU has AVX-512 F and DQ, and AVX2 and FMA.
    unsafe {
        closest_batch_avx512(k, s, std::slice::from_ref(ray), t_max, &mut hit)
    };
    #[cfg(not(target_arch = "x86_64"))]
    closest_batch_avx512(k, s, std::slice::from_ref(ray), t_max, &mut hit);
    hit[0]
}

fn occluded_avx512(k: Avx512, s: &Structure, ray: &Ray, t_max: f32) -> bool {
    let mut blocked = [false];
    #[cfg(target_arch = "x86_64")]
    // SAFETY: as above.
    unsafe {
        occluded_batch_avx512(k, s, &[(*ray, t_max)], &mut blocked)
    };
    #[cfg(not(target_arch = "x86_64"))]
    occluded_batch_avx512(k, s, &[(*ray, t_max)], &mut blocked);
    blocked[0]
}
