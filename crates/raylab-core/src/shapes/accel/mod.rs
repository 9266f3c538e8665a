//! Acceleration structures: what answers a [`crate::shapes::scene::Scene`]'s closest-hit and shadow
//! queries without testing every triangle.
//!
//! * [`bvh`]: a binary BVH, binned SAH build, and the readable scalar traversal (the reference).
//! * [`wide`]: the fast path — an 8-wide BVH collapsed from it, triangles in 8-wide packets —
//!   and the flat packet list (a SIMD loop over every triangle).
//! * [`simd`]: the box and triangle kernels, AVX2 with a scalar twin.
//! * [`packet`]: coherent rays (a camera's, the shadow rays to a point light) through the wide
//!   BVH as packets, one SIMD lane a ray: sixteen at a time with AVX-512, eight with AVX2 and
//!   the portable set.
//! * [`portable`]: the kernel set every CPU runs — the same packets, culling and batches,
//!   eight lanes in two four-lane registers (SSE2 on x86-64, NEON on aarch64).
//! * [`cull`]: a batch of camera rays, or of shadow rays to a point light, bounded by a cone:
//!   the flat list skips the triangles outside it for the whole batch.
//! * [`calibrate`]: which kernel set is fastest on this CPU, measured at start-up.
//!
//! [`Accel::build`] picks per scene ([`AccelKind::Auto`]): the flat list for tiny scenes (the
//! 30-triangle Cornell box, where it beats any tree: PERFORMANCE.md, "Design choices and what each buys"), the wide BVH
//! otherwise, with the few triangles that are large next to the scene (the box's walls) set
//! apart in one packet tested first; and the kernels measured fastest on this CPU
//! ([`Isa::best_with`]), or forced with `--isa`.
//! Every kind returns exactly what [`crate::shapes::intersect::closest_intersection_brute_force`]
//! returns, ties included.
//!
//! ```
//! use glam::Vec3;
//! use raylab_core::shapes::accel::{Accel, AccelKind, Isa};
//! use raylab_core::base::geometry::Ray;
//! use raylab_core::shapes::intersect::closest_intersection_brute_force;
//! use raylab_core::shapes::scene::{SceneChoice, cornell_box};
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
pub mod calibrate;
pub mod cull;
pub mod kernels;
pub mod lane_io;
pub mod packet;
pub mod portable;
pub mod simd;
pub mod wide;
#[cfg(target_arch = "x86_64")]
mod x86_lanes;

use std::sync::OnceLock;
use std::time::{Duration, Instant};

use crate::base::geometry::{Ray, Triangle};
use crate::base::lanes::compiled;
use crate::base::named::named_enum;
use crate::shapes::intersect;

use self::bvh::Bvh;
use self::calibrate::Calibration;
use self::cull::Cone;
use self::portable::Portable;
use self::simd::RayK;
use self::simd::{Avx2, Avx512, Scalar};
use self::wide::{Bvh8Big, Flat, KernelSet};

/// Scenes with at most this many triangles use the flat packet list. The flat loop tests every
/// triangle for every ray with no nodes to walk: it beats the 8-wide BVH on the 30-triangle
/// Cornell box and loses far behind it on the 1,022-triangle teapot. The crossover lies in
/// between; 64 (four 16-wide packets) is on the safe side (PERFORMANCE.md, "Design choices and what each buys").
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

/// The closest hits of up to sixteen rays side by side, one lane a ray (structure of arrays):
/// lane `i` holds ray `i`'s [`Hit`], its `index` [`HitLanes::MISS`] where the ray met nothing.
/// What [`Accel::closest_lanes`] hands back, so that an integrator can read sixteen hits'
/// triangles at once ([`HitLanes::get`] gives one).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct HitLanes {
    pub t: [f32; 16],
    pub index: [u32; 16],
    pub u: [f32; 16],
    pub v: [f32; 16],
}

impl HitLanes {
    /// A lane's `index` where its ray met nothing.
    pub const MISS: u32 = u32::MAX;

    /// No hit in any lane, `t` at `t_max` (the limit a traversal compares against).
    #[inline(always)]
    pub fn new(t_max: f32) -> Self {
        Self {
            t: [t_max; 16],
            index: [Self::MISS; 16],
            u: [0.0; 16],
            v: [0.0; 16],
        }
    }

    /// Lane `i` holds `hits[i]` (at most sixteen); the lanes of misses, and those past the
    /// hits, none (`t` at `t_max`, as [`HitLanes::new`] leaves them).
    #[inline(always)]
    pub fn of(hits: &[Option<Hit>], t_max: f32) -> Self {
        debug_assert!(hits.len() <= 16);
        let mut lanes = Self::new(t_max);
        for (lane, &hit) in hits.iter().enumerate() {
            if hit.is_some() {
                lanes.set(lane, hit);
            }
        }
        lanes
    }

    /// Lane `lane`'s hit, if its ray met something.
    #[inline(always)]
    pub fn get(&self, lane: usize) -> Option<Hit> {
        (self.index[lane] != Self::MISS).then(|| Hit {
            index: self.index[lane],
            t: self.t[lane],
            u: self.u[lane],
            v: self.v[lane],
        })
    }

    /// Puts `hit` in lane `lane` (a miss: `None`).
    #[inline(always)]
    pub fn set(&mut self, lane: usize, hit: Option<Hit>) {
        let h = hit.unwrap_or(Hit {
            index: Self::MISS,
            t: f32::INFINITY,
            u: 0.0,
            v: 0.0,
        });
        self.t[lane] = h.t;
        self.index[lane] = h.index;
        self.u[lane] = h.u;
        self.v[lane] = h.v;
    }

    /// The lanes whose ray met something: bit `i` for lane `i`.
    #[inline(always)]
    pub fn hits(&self) -> u16 {
        let mut bits = 0u16;
        for (lane, &index) in self.index.iter().enumerate() {
            bits |= u16::from(index != Self::MISS) << lane;
        }
        bits
    }
}

/// The work one closest-hit query did ([`Accel::closest_counting`]): what the workbench's
/// BVH-cost view shows per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TraversalCost {
    /// Interior nodes visited: each tests the boxes of all its children at once (eight for the
    /// wide BVH, two for the binary one). Leaves are not counted here but by their triangles.
    pub nodes: u32,
    /// Triangles tested: the real triangles of every leaf packet tested, not the packets'
    /// empty lanes (see [`wide::Bvh8::closest_counting`]); every triangle for the flat loop
    /// and the brute-force loop.
    pub triangles: u32,
}

impl TraversalCost {
    /// Nodes plus triangles, unweighted: the one number the cost view maps to colour. Plain
    /// counts can be checked by hand on a small tree; weighting them (the build's SAH takes a
    /// node visit as about four triangle tests, 1 against 0.25) would be a model of the time,
    /// not a count of the work.
    pub fn total(self) -> u32 {
        self.nodes + self.triangles
    }
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

named_enum!(AccelKind as "accelerator" {
    Auto => "auto";
    BruteForce => "brute";
    Flat => "flat";
    Bvh2 => "bvh2";
    Bvh8 => "bvh8";
});

/// Which kernels run the flat list and the wide BVH.
#[derive(Clone, Copy, Debug)]
pub enum Isa {
    /// The portable kernels ([`portable`], named `scalar` on the command line): the SIMD sets'
    /// packets, culling and batches, eight lanes wide in the registers every CPU of the
    /// architecture has (SSE2 on x86-64).
    Scalar,
    /// AVX2 + FMA: 8-wide everything.
    Avx2(Avx2),
    /// AVX-512: the flat list 16 wide; the 8-wide BVH keeps its AVX2 kernels for single rays
    /// and traces coherent batches as packets of 16 rays.
    Avx512(Avx512),
}

/// For tests of a kernel set this CPU does not run (`set`: `avx2` or `avx512`), which return
/// without checking it: says so on the terminal (past the test harness's capture of output, so
/// a passing run shows the skip), and fails instead when the `RAYLAB_REQUIRE_ISA` environment
/// variable names the set (a comma-separated list: CI names each set its CPU has, so a kernel
/// set it can test is never skipped unnoticed).
#[doc(hidden)]
pub fn skip_unless_required(set: &str, test: &str) {
    use std::io::Write as _;
    let required = std::env::var("RAYLAB_REQUIRE_ISA").unwrap_or_default();
    if names(&required, set) {
        panic!("{test}: RAYLAB_REQUIRE_ISA names {set}, but this CPU does not run it");
    }
    let _ = writeln!(
        std::io::stderr(),
        "note: {test}: the {set} kernels are not tested: this CPU does not run them"
    );
}

/// Whether the comma-separated `list` names `set`.
fn names(list: &str, set: &str) -> bool {
    list.split(',').map(str::trim).any(|r| r == set)
}

/// The kernels every structure uses unless told otherwise: forced ([`Isa::force`], the
/// `RAYLAB_ISA` variable) or measured ([`calibrate`]), once per process.
static CHOSEN: OnceLock<(Isa, Option<Calibration>)> = OnceLock::new();

impl Isa {
    /// The kernels to use on this CPU: the one forced by `--isa` ([`Isa::force`]) or the
    /// `RAYLAB_ISA` environment variable (`avx512`, `avx2` or `scalar`, if this CPU runs it),
    /// else the fastest on `workloads` ([`calibrate::calibrate`]: not always the widest; the
    /// renderer's workloads come from `scene::best_isa`). Decided once per process: later calls
    /// return the same set without calling `workloads`.
    pub fn best_with(workloads: impl FnOnce() -> Vec<calibrate::Workload>) -> Self {
        Self::chosen(workloads).0
    }

    /// What [`Isa::best_with`] measured, if it has measured (not when forced).
    pub fn calibration() -> Option<&'static Calibration> {
        CHOSEN.get().and_then(|(_, c)| c.as_ref())
    }

    fn chosen(
        workloads: impl FnOnce() -> Vec<calibrate::Workload>,
    ) -> &'static (Isa, Option<Calibration>) {
        CHOSEN.get_or_init(|| {
            let forced = std::env::var("RAYLAB_ISA").ok();
            match forced.as_deref().and_then(Isa::by_name) {
                Some(isa) => (isa, None),
                None => {
                    let c = calibrate::calibrate(&workloads());
                    (c.chosen, Some(c))
                }
            }
        })
    }

    /// Makes `self` the kernels of every structure built from now on (`--isa`). Fails if
    /// [`Isa::best_with`] has already decided on another set in this process.
    pub fn force(self) -> Result<(), String> {
        let (chosen, _) = CHOSEN.get_or_init(|| (self, None));
        if chosen.name() == self.name() {
            Ok(())
        } else {
            Err(format!(
                "the kernels were already chosen ({}) before --isa {}",
                chosen.name(),
                self.name()
            ))
        }
    }

    /// The widest kernels this CPU runs: AVX-512, else AVX2 + FMA, else scalar.
    pub fn widest() -> Self {
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

    /// The named kernel set, if this CPU runs it: `scalar`, `avx2` or `avx512`.
    /// For tests: every kernel set this CPU runs ([`Isa::available`]), each set it does not
    /// run reported by [`skip_unless_required`] under the name `test`.
    #[doc(hidden)]
    pub fn available_for_tests(test: &str) -> Vec<Isa> {
        if Avx2::detect().is_none() {
            skip_unless_required("avx2", test);
        }
        if Avx512::detect().is_none() {
            skip_unless_required("avx512", test);
        }
        Isa::available()
    }

    /// What is wrong with the `RAYLAB_ISA` environment variable, when it is set to something
    /// [`Isa::best_with`] cannot use and so does not (it measures, as if the variable were
    /// unset): for a warning naming the sets that are accepted. `None` when it is unset, `best`
    /// or a set this CPU runs.
    pub fn environment_note() -> Option<String> {
        let value = std::env::var_os("RAYLAB_ISA")?;
        let text = value.to_string_lossy();
        if text == "best" || Isa::by_name(&text).is_some() {
            return None;
        }
        let known = ["avx512", "avx2", "scalar"].contains(&&*text);
        let runs: Vec<&str> = Isa::available().iter().rev().map(|i| i.name()).collect();
        Some(format!(
            "RAYLAB_ISA={text:?} is {}: the kernels are chosen by measuring, as without it \
             (accepted: best, {})",
            if known {
                "a kernel set this CPU does not run"
            } else {
                "not a kernel set"
            },
            runs.join(", ")
        ))
    }

    pub fn by_name(name: &str) -> Option<Isa> {
        match name {
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

    /// The closest hit with `0 < t < t_max`: the lowest index among hits at the same
    /// distance, exactly as the brute-force loop. A batch of one ([`Accel::closest_batch`]).
    #[inline(always)]
    pub fn closest(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut hit = [None];
        self.closest_batch(triangles, std::slice::from_ref(ray), t_max, &mut hit);
        hit[0]
    }

    /// [`Accel::closest`] and what it cost ([`TraversalCost`]), counted by the traversal this
    /// structure really runs, not estimated:
    ///
    /// * the brute-force and flat loops test every triangle for every ray (the Cornell box:
    ///   30 whatever the ray), no nodes; the hit is [`Accel::closest`]'s own;
    /// * the binary BVH counts in its one (reference) traversal;
    /// * the 8-wide BVH tests its few large triangles first, exactly as the fast path does
    ///   (with the same kernels), then walks the tree with [`wide::Bvh8::closest_counting`]: the
    ///   fast traversal's loop with counters, in the same order and with the same kernels, so the
    ///   same culling. It is slower than [`Accel::closest`] (not compiled for the instruction
    ///   set, a heap stack): for views and teaching, not for rendering.
    ///
    /// The hit equals [`Accel::closest`]'s bit for bit (tests/views.rs checks it on 100,000
    /// rays per scene and kernel set), which is what makes the counts those of the real
    /// traversal.
    pub fn closest_counting(
        &self,
        triangles: &[Triangle],
        ray: &Ray,
        t_max: f32,
    ) -> (Option<Hit>, TraversalCost) {
        let every = |n: u32| TraversalCost {
            nodes: 0,
            triangles: n,
        };
        match (&self.structure, self.isa) {
            (Structure::BruteForce, _) => (
                self.closest(triangles, ray, t_max),
                every(triangles.len() as u32),
            ),
            (Structure::Flat(f), _) => (
                self.closest(triangles, ray, t_max),
                every(f.triangle_count()),
            ),
            (Structure::Bvh2(b), _) => b.closest_counting(triangles, ray, t_max),
            (Structure::Bvh8(b), isa) => {
                let r = RayK::new(ray);
                let mut cost = every(b.big.triangle_count());
                // As the fast path (`Bvh8Big::closest_with`), with counters in the tree.
                let hit = with_kernels!(isa, |k| {
                    let best = k.flat_closest(&b.big, &r, t_max);
                    b.tree
                        .closest_counting(k.tree(), &r, t_max, best, &mut cost)
                });
                (hit, cost)
            }
        }
    }

    /// Whether anything is hit with `0 < t < t_max` (a shadow ray's any-hit query). As
    /// [`Accel::closest`]: a batch of one ([`Accel::occluded_batch`]).
    #[inline(always)]
    pub fn occluded(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> bool {
        let mut blocked = [false];
        self.occluded_batch(triangles, &[(*ray, t_max)], &mut blocked);
        blocked[0]
    }
}

// The batch queries are calls, never inlined: inlined, they make the compiler inline their
// callers (the integrators' code, compiled for the instruction set) differently, running more
// instructions, whenever these grow or shrink (`scripts/count-instructions.sh` shows it).
impl Accel {
    /// [`Accel::closest`] for many rays, `out[i]` for `rays[i]`: the same answers, with the
    /// choice of structure and kernels made once for the batch instead of once per ray, and the
    /// loop over the rays compiled with the kernels' instruction set.
    #[inline(never)]
    pub fn closest_batch(
        &self,
        triangles: &[Triangle],
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        debug_assert_eq!(rays.len(), out.len());
        let (s, isa) = (&self.structure, self.isa);
        with_kernels!(isa, |k| k.closest_batch(s, triangles, rays, t_max, out))
    }

    /// [`Accel::closest_batch`] into lanes: lane `i` of `out[g]` is `rays[16g + i]`'s hit, the
    /// lanes past the last ray none. The same answers; a culled flat list hands its packets'
    /// lanes over as they are.
    #[inline(never)]
    pub fn closest_lanes(
        &self,
        triangles: &[Triangle],
        rays: &[Ray],
        t_max: f32,
        out: &mut [HitLanes],
    ) {
        debug_assert_eq!(rays.len().div_ceil(16), out.len());
        let (s, isa) = (&self.structure, self.isa);
        with_kernels!(isa, |k| k.closest_lanes(s, triangles, rays, t_max, out))
    }

    /// [`Accel::occluded`] for many rays, each with its own `t_max`: `out[i]` for `rays[i]`,
    /// the same answers, the choice of structure and kernels made once for the batch.
    #[inline(never)]
    pub fn occluded_batch(&self, triangles: &[Triangle], rays: &[(Ray, f32)], out: &mut [bool]) {
        debug_assert_eq!(rays.len(), out.len());
        let s = &self.structure;
        with_kernels!(self.isa, |k| k.occluded_batch(s, triangles, rays, out))
    }
}

/// Up to sixteen shadow rays as lanes (structure of arrays), as the lab's shading makes them:
/// origins, directions and lengths per lane, and `cast`, bit `i` set where lane `i` holds a ray.
/// [`Accel::occluded_lanes`] traces them without copying them into an array of rays first.
#[derive(Clone, Copy, Debug)]
pub struct SegmentLanes<'a> {
    pub origin: [&'a [f32; 16]; 3],
    pub direction: [&'a [f32; 16]; 3],
    pub t_max: &'a [f32; 16],
    pub cast: u16,
}

impl SegmentLanes<'_> {
    /// Lane `i`'s ray and length.
    pub fn ray(&self, i: usize) -> (Ray, f32) {
        let v = |a: [&[f32; 16]; 3]| glam::Vec3::new(a[0][i], a[1][i], a[2][i]);
        (
            Ray {
                origin: v(self.origin),
                direction: v(self.direction),
            },
            self.t_max[i],
        )
    }
}

/// How many groups of [`SegmentLanes`] [`Accel::occluded_lanes`] copies into one batch of rays
/// where it cannot take lanes: four, 64 rays, the integrators' batch.
pub const BATCH_OF_LANES: usize = 4;

impl Accel {
    /// [`Accel::occluded_batch`] for shadow rays given as lanes: bit `i` of `blocked[g]` set
    /// when lane `i` of `groups[g]` is cast and blocked. The same answers: a short flat list
    /// tests each group's lanes straight from the lanes, against the triangles the whole set's
    /// cone may reach ([`cull`]) or, without a cone, against all of them; anything else copies
    /// the rays into arrays of up to [`BATCH_OF_LANES`] groups and asks
    /// [`Accel::occluded_batch`]. `neighbours`: whether the rays of each group start at
    /// neighbouring points (the hits of neighbouring pixels' rays), so that a group may have a
    /// cone where the whole set has none.
    #[inline(never)]
    pub fn occluded_lanes(
        &self,
        triangles: &[Triangle],
        groups: &[SegmentLanes],
        neighbours: bool,
        blocked: &mut [u16],
    ) {
        debug_assert_eq!(groups.len(), blocked.len());
        if let Structure::Flat(f) = &self.structure
            && with_kernels!(self.isa, |k| k
                .occluded_lanes(f, groups, neighbours, blocked))
        {
            return;
        }
        // Elsewhere, the rays copied out, up to BATCH_OF_LANES groups' in one batch.
        const RAYS: usize = BATCH_OF_LANES * 16;
        let chunks = groups.chunks(BATCH_OF_LANES);
        for (groups, blocked) in chunks.zip(blocked.chunks_mut(BATCH_OF_LANES)) {
            let mut rays = [(Ray::new(glam::Vec3::ZERO, glam::Vec3::Z), 0.0); RAYS];
            let mut whose = [(0u8, 0u8); RAYS];
            let mut n = 0;
            for (g, group) in groups.iter().enumerate() {
                for i in (0..16).filter(|&i| group.cast & (1 << i) != 0) {
                    rays[n] = group.ray(i);
                    whose[n] = (g as u8, i as u8);
                    n += 1;
                }
            }
            let mut answers = [false; RAYS];
            self.occluded_batch(triangles, &rays[..n], &mut answers[..n]);
            blocked.fill(0);
            for (&(g, i), &b) in whose[..n].iter().zip(&answers[..n]) {
                blocked[g as usize] |= u16::from(b) << i;
            }
        }
    }
}

/// `$body` with `$k` the kernels of `$isa`: the same source instantiated for each set (`$k`
/// is an [`Avx512`], an [`Avx2`] or the [`Portable`] kernels; elsewhere than x86-64 the x86
/// sets are never detected, and only the portable arm is compiled).
macro_rules! with_kernels {
    ($isa:expr, |$k:ident| $body:expr) => {
        match $isa {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512($k) => $body,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2($k) => $body,
            _ => {
                let $k = Portable;
                $body
            }
        }
    };
}
use with_kernels;

/// A structure's queries for a batch of rays with one kernel set: by default a ray at a time
/// (the readable [`Scalar`] kernels, for the structures without kernels; kept out of line, so
/// that the other sets' batches hand those structures over to it rather than compile them in);
/// every kernel set runs them as packets ([`closest_packets`]), the SIMD sets compiled with
/// their instruction set ([`packet_batches!`]), so the kernels inline. A single query is a batch
/// of one, so each is written once.
trait Batches: KernelSet {
    #[inline(never)]
    fn closest_batch(
        self,
        s: &Structure,
        triangles: &[Triangle],
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        for (ray, hit) in rays.iter().zip(out) {
            *hit = s.closest_with(self, triangles, ray, t_max);
        }
    }

    #[inline(never)]
    fn closest_lanes(
        self,
        s: &Structure,
        triangles: &[Triangle],
        rays: &[Ray],
        t_max: f32,
        out: &mut [HitLanes],
    ) {
        let mut hits = [None; 16];
        for (rays, out) in rays.chunks(16).zip(out) {
            let hits = &mut hits[..rays.len()];
            self.closest_batch(s, triangles, rays, t_max, hits);
            *out = HitLanes::of(hits, t_max);
        }
    }

    #[inline(never)]
    fn occluded_batch(
        self,
        s: &Structure,
        triangles: &[Triangle],
        rays: &[(Ray, f32)],
        out: &mut [bool],
    ) {
        for ((ray, t_max), blocked) in rays.iter().zip(out) {
            *blocked = s.occluded_with(self, triangles, ray, *t_max);
        }
    }

    /// [`Accel::occluded_lanes`] on the flat list; false (nothing done) where it does not
    /// take lanes (a list too long to cull, or no SIMD).
    fn occluded_lanes(
        self,
        _f: &Flat,
        _groups: &[SegmentLanes],
        _neighbours: bool,
        _blocked: &mut [u16],
    ) -> bool {
        false
    }
}

impl Batches for Scalar {}

impl Structure {
    /// One ray's closest hit, with the kernels `k` where the structure has kernels.
    #[inline(always)]
    fn closest_with<K: KernelSet>(
        &self,
        k: K,
        triangles: &[Triangle],
        ray: &Ray,
        t_max: f32,
    ) -> Option<Hit> {
        match self {
            Structure::BruteForce => {
                intersect::closest_intersection_brute_force(ray, triangles, t_max).map(|h| Hit {
                    index: h.triangle_index as u32,
                    t: h.distance,
                    u: h.u,
                    v: h.v,
                })
            }
            Structure::Bvh2(b) => b.closest(triangles, ray, t_max),
            Structure::Flat(f) => f.closest_with(k, ray, t_max),
            Structure::Bvh8(b) => b.closest_with(k, ray, t_max),
        }
    }

    /// Whether one ray is blocked before `t_max`, with the kernels `k` where the structure has
    /// kernels.
    #[inline(always)]
    fn occluded_with<K: KernelSet>(
        &self,
        k: K,
        triangles: &[Triangle],
        ray: &Ray,
        t_max: f32,
    ) -> bool {
        match self {
            Structure::BruteForce => intersect::occluded_brute_force(ray, triangles, t_max),
            Structure::Bvh2(b) => b.occluded(triangles, ray, t_max),
            Structure::Flat(f) => f.occluded_with(k, ray, t_max),
            Structure::Bvh8(b) => b.occluded_with(k, ray, t_max),
        }
    }
}

/// The batch queries of a packet kernel set: [`closest_packets`], [`occluded_packets`] and
/// [`occluded_lanes_in`], each compiled for the set ([`compiled!`]), where the kernels and the
/// packet traversal inline.
macro_rules! packet_batches {
    ($isa:ident) => {
        // Without features, `compiled` is safe to call and the `unsafe` blocks are unused.
        #[allow(unused_unsafe)]
        impl Batches for $isa {
            fn closest_batch(
                self,
                s: &Structure,
                triangles: &[Triangle],
                rays: &[Ray],
                t_max: f32,
                out: &mut [Option<Hit>],
            ) {
                compiled!($isa: fn compiled(
                    k: $isa,
                    s: &Structure,
                    triangles: &[Triangle],
                    rays: &[Ray],
                    t_max: f32,
                    out: &mut [Option<Hit>],
                ) {
                    closest_packets(k, s, triangles, rays, t_max, out)
                });
                // SAFETY: a value of the kernel set proves that the CPU runs its features.
                unsafe { compiled(self, s, triangles, rays, t_max, out) }
            }

            fn closest_lanes(
                self,
                s: &Structure,
                triangles: &[Triangle],
                rays: &[Ray],
                t_max: f32,
                out: &mut [HitLanes],
            ) {
                compiled!($isa: fn compiled(
                    k: $isa,
                    s: &Structure,
                    triangles: &[Triangle],
                    rays: &[Ray],
                    t_max: f32,
                    out: &mut [HitLanes],
                ) {
                    closest_lanes_packets(k, s, triangles, rays, t_max, out)
                });
                // SAFETY: as above.
                unsafe { compiled(self, s, triangles, rays, t_max, out) }
            }

            fn occluded_batch(
                self,
                s: &Structure,
                triangles: &[Triangle],
                rays: &[(Ray, f32)],
                out: &mut [bool],
            ) {
                compiled!($isa: fn compiled(
                    k: $isa,
                    s: &Structure,
                    triangles: &[Triangle],
                    rays: &[(Ray, f32)],
                    out: &mut [bool],
                ) {
                    occluded_packets(k, s, triangles, rays, out)
                });
                // SAFETY: as above.
                unsafe { compiled(self, s, triangles, rays, out) }
            }

            fn occluded_lanes(
                self,
                f: &Flat,
                groups: &[SegmentLanes],
                neighbours: bool,
                blocked: &mut [u16],
            ) -> bool {
                compiled!($isa: fn compiled(
                    k: $isa,
                    f: &Flat,
                    groups: &[SegmentLanes],
                    neighbours: bool,
                    blocked: &mut [u16],
                ) -> bool {
                    occluded_lanes_in(k, f, groups, neighbours, blocked)
                });
                // SAFETY: as above.
                unsafe { compiled(self, f, groups, neighbours, blocked) }
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
packet_batches!(Avx512);
#[cfg(target_arch = "x86_64")]
packet_batches!(Avx2);
// The portable set: the same functions, compiled for the baseline every CPU runs.
packet_batches!(Portable);

/// Closest hits of a batch with a SIMD kernel set: the flat list culled for the batch where
/// the batch has a cone, the wide BVH a packet of coherent rays at a time, the rest ray by ray.
#[inline(always)]
fn closest_packets<P: packet::PacketIsa>(
    k: P,
    s: &Structure,
    triangles: &[Triangle],
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<Hit>],
) {
    match s {
        Structure::Flat(f) => {
            // A batch in a narrow cone (a stretch of camera rays) skips what it cannot see, and
            // goes through the few triangles left as packets of rays.
            if flat_closest_culled(k, f, rays, t_max, out) {
                return;
            }
            for (ray, hit) in rays.iter().zip(out) {
                *hit = f.closest_with(k, ray, t_max);
            }
        }
        Structure::Bvh8(b) => {
            for (rays, out) in rays.chunks(P::WIDTH).zip(out.chunks_mut(P::WIDTH)) {
                if packet::coherent(rays) {
                    b.closest_packet(k, rays, t_max, out);
                    continue;
                }
                for (ray, hit) in rays.iter().zip(out) {
                    *hit = b.closest_with(k, ray, t_max);
                }
            }
        }
        // No kernels: the scalar loop.
        Structure::BruteForce | Structure::Bvh2(_) => {
            Scalar.closest_batch(s, triangles, rays, t_max, out)
        }
    }
}

/// [`closest_packets`] into lanes ([`Accel::closest_lanes`]): a culled flat list's packets
/// keep their lanes; any other batch is answered by [`closest_packets`], sixteen rays at a time,
/// and its hits put in lanes.
#[inline(always)]
fn closest_lanes_packets<P: packet::PacketIsa>(
    k: P,
    s: &Structure,
    triangles: &[Triangle],
    rays: &[Ray],
    t_max: f32,
    out: &mut [HitLanes],
) {
    if let Structure::Flat(f) = s
        && f.cullable()
        && let Some(cone) = Cone::around_rays_simd(k, rays)
    {
        let kept = cull::kept(&cone, k, &f.corners, f.count);
        for (rays, out) in rays.chunks(16).zip(out) {
            *out = HitLanes::new(t_max);
            for (c, rays) in rays.chunks(P::WIDTH).enumerate() {
                if c == 0 {
                    packet::nearest_in_list(k, &f.packets16, kept, rays, t_max, out);
                    continue;
                }
                // AVX2's second packet of eight: its lanes moved up to where its rays are.
                let mut part = HitLanes::new(t_max);
                packet::nearest_in_list(k, &f.packets16, kept, rays, t_max, &mut part);
                let (from, to) = (0..rays.len(), c * P::WIDTH..c * P::WIDTH + rays.len());
                out.t[to.clone()].copy_from_slice(&part.t[from.clone()]);
                out.index[to.clone()].copy_from_slice(&part.index[from.clone()]);
                out.u[to.clone()].copy_from_slice(&part.u[from.clone()]);
                out.v[to].copy_from_slice(&part.v[from]);
            }
        }
        return;
    }
    let mut hits = [None; 16];
    for (rays, out) in rays.chunks(16).zip(out) {
        let hits = &mut hits[..rays.len()];
        closest_packets(k, s, triangles, rays, t_max, hits);
        *out = HitLanes::of(hits, t_max);
    }
}

/// [`closest_packets`] for shadow rays, each with its own `t_max`.
#[inline(always)]
fn occluded_packets<P: packet::PacketIsa>(
    k: P,
    s: &Structure,
    triangles: &[Triangle],
    rays: &[(Ray, f32)],
    out: &mut [bool],
) {
    match s {
        Structure::Flat(f) => {
            // Shadow rays to a point light skip what lies outside their cone.
            if flat_occluded_culled(k, f, rays, out) {
                return;
            }
            for ((ray, t_max), blocked) in rays.iter().zip(out) {
                *blocked = f.occluded_with(k, ray, *t_max);
            }
        }
        Structure::Bvh8(b) => {
            for (rays, out) in rays.chunks(P::WIDTH).zip(out.chunks_mut(P::WIDTH)) {
                if packet::coherent_shadows(rays) {
                    b.occluded_packet(k, rays, out);
                    continue;
                }
                for ((ray, t_max), blocked) in rays.iter().zip(out) {
                    *blocked = b.occluded_with(k, ray, *t_max);
                }
            }
        }
        Structure::BruteForce | Structure::Bvh2(_) => {
            Scalar.occluded_batch(s, triangles, rays, out)
        }
    }
}

/// The flat list's culled closest hits for a batch of rays from one point ([`cull`]): the
/// triangles the batch's cone may reach, a triangle at a time against a packet of rays. False
/// (nothing done) when the list is too long to cull or the rays have no cone.
#[inline(always)]
fn flat_closest_culled<P: packet::PacketIsa>(
    k: P,
    f: &Flat,
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<Hit>],
) -> bool {
    if !f.cullable() {
        return false;
    }
    let Some(cone) = Cone::around_rays_simd(k, rays) else {
        return false;
    };
    let kept = cull::kept(&cone, k, &f.corners, f.count);
    for (rays, out) in rays.chunks(P::WIDTH).zip(out.chunks_mut(P::WIDTH)) {
        packet::closest_in_list(k, &f.packets16, kept, rays, t_max, out);
    }
    true
}

/// [`flat_closest_culled`] for shadow rays ending near one point.
#[inline(always)]
fn flat_occluded_culled<P: packet::PacketIsa>(
    k: P,
    f: &Flat,
    rays: &[(Ray, f32)],
    out: &mut [bool],
) -> bool {
    if !f.cullable() {
        return false;
    }
    let Some(cone) = Cone::around_segments_simd(k, rays) else {
        return false;
    };
    let kept = cull::kept(&cone, k, &f.corners, f.count);
    for (rays, out) in rays.chunks(P::WIDTH).zip(out.chunks_mut(P::WIDTH)) {
        packet::occluded_in_list(k, &f.packets16, kept, rays, out);
    }
    true
}

/// [`flat_closest_culled`] for shadow rays given as lanes; unlike the batches of rays, lanes
/// without a cone are tested from the lanes too, against every triangle (the path tracer's
/// shadow rays: cheaper than copying them out of the lanes).
#[inline(always)]
fn occluded_lanes_in<P: packet::PacketIsa>(
    k: P,
    f: &Flat,
    groups: &[SegmentLanes],
    neighbours: bool,
    blocked: &mut [u16],
) -> bool {
    if !f.cullable() {
        return false;
    }
    if let Some(cone) = Cone::around_segment_lanes(k, groups) {
        let kept = cull::kept(&cone, k, &f.corners, f.count);
        for (g, blocked) in groups.iter().zip(blocked) {
            *blocked = packet::occluded_lanes_in_list(k, &f.packets16, kept, g, true);
        }
        return true;
    }
    // Without a cone for the whole set: a fan of neighbours' rays too wide for one (the lab's
    // rows that pass under the light) may still have one a group of sixteen, tried until a
    // group has none; rays from all over the scene (the path tracer's bounces) are not tried.
    // Either way, the groups without one are tested against every triangle, still straight
    // from the lanes. Only rays in a cone give up a triangle as soon as none of them meets
    // its plane within its length (`Lanes::triangle_or_give_up`, PERFORMANCE.md, "Design choices and what each buys":
    // culling cones); for rays from all over the scene that branch is a coin toss, and costs
    // more than it saves.
    let all = u64::MAX.checked_shr(64 - f.count as u32).unwrap_or(0);
    let mut coned = neighbours && groups.len() > 1;
    for (g, blocked) in groups.iter().zip(blocked) {
        let mut kept = all;
        if coned {
            match Cone::around_segment_lanes(k, std::slice::from_ref(g)) {
                Some(cone) => kept = cull::kept(&cone, k, &f.corners, f.count),
                None => coned = false,
            }
        }
        *blocked = packet::occluded_lanes_in_list(k, &f.packets16, kept, g, coned);
    }
    true
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    /// `RAYLAB_REQUIRE_ISA=avx2,avx512` turns the skip of either set into a failure; a set it
    /// does not name is skipped with a note.
    #[test]
    fn a_required_kernel_set_cannot_be_skipped() {
        assert!(names("avx2,avx512", "avx512") && names(" avx2 ", "avx2"));
        assert!(!names("avx2", "avx512") && !names("", "avx2"));
        let required = std::env::var("RAYLAB_REQUIRE_ISA").unwrap_or_default();
        if !names(&required, "made-up") {
            skip_unless_required("made-up", "a_required_kernel_set_cannot_be_skipped");
        }
    }

    #[test]
    fn kernel_sets_are_named_only_where_the_cpu_runs_them() {
        // A set the CPU lacks is not offered (so `--isa` refuses it) and never chosen: the
        // choice falls back to what the CPU has.
        assert_eq!(Isa::by_name("avx512").is_some(), Avx512::detect().is_some());
        assert_eq!(Isa::by_name("avx2").is_some(), Avx2::detect().is_some());
        assert!(Isa::by_name("scalar").is_some() && Isa::by_name("sse9").is_none());
        let available: Vec<&str> = Isa::available().into_iter().map(Isa::name).collect();
        assert!(
            available.contains(&crate::shapes::scene::best_isa().name()),
            "{available:?}"
        );
        assert!(available.contains(&Isa::widest().name()));
        // AVX-512 implies AVX2 (its kernels use both).
        if Avx512::detect().is_some() {
            assert!(available.contains(&"avx2"));
        }
        // Forcing the set already chosen is accepted; another one is refused.
        assert!(crate::shapes::scene::best_isa().force().is_ok());
        if let Some(other) = Isa::available()
            .into_iter()
            .find(|i| i.name() != crate::shapes::scene::best_isa().name())
        {
            assert!(other.force().is_err());
        }
    }

    /// Two layers of eight small triangles, one behind the other: triangle `i` of layer `z` has
    /// corners (i, 0, z), (i + ½, 0, z), (i, ½, z); indices 0–7 at z = 0, 8–15 at z = 1.
    ///
    /// The tree, by hand. Root (16): splitting the layers apart costs 2 · 8 · 3.75 = 60 (each
    /// layer's box is 7.5 × 0.5, flat), splitting in x at best 2 · 8 · 5.75 = 92 (four columns
    /// each side, 1 deep): the layers. A layer (8): two leaves of four cost 1 + 0.25 · (2 · 4 ·
    /// 1.75)/3.75 = 1.93 against a leaf's 0.25 · 8 = 2.0: split. Four: 1 + 0.25 · (2 · 2 ·
    /// 0.75)/1.75 = 1.43 against 1.0: a leaf. So the binary tree is root → two layers → two
    /// leaves each, and the 8-wide one a single node whose four children are the leaves
    /// {0–3}, {4–7}, {8–11}, {12–15}. No triangle is large (each 0.25 of the scene's 11.75).
    fn layers() -> Vec<Triangle> {
        let mut out = Vec::new();
        for z in [0.0, 1.0] {
            for i in 0..8 {
                let x = i as f32;
                out.push(Triangle::new(
                    Vec3::new(x, 0.0, z),
                    Vec3::new(x + 0.5, 0.0, z),
                    Vec3::new(x, 0.5, z),
                    0,
                ));
            }
        }
        out
    }

    fn cost(nodes: u32, triangles: u32) -> TraversalCost {
        TraversalCost { nodes, triangles }
    }

    #[test]
    fn the_layers_tree_is_as_worked_out_by_hand() {
        let triangles = layers();
        let accel = Accel::build(&triangles, AccelKind::Bvh8, Isa::Scalar);
        let Structure::Bvh8(b) = &accel.structure else {
            panic!("not a wide BVH");
        };
        assert_eq!(b.big.triangle_count(), 0);
        assert_eq!(b.tree.nodes.len(), 1);
        let mut leaves: Vec<Vec<u32>> = b
            .tree
            .packets
            .iter()
            .map(|p| p.index.iter().copied().filter(|&i| i != u32::MAX).collect())
            .collect();
        leaves.sort();
        let want: Vec<Vec<u32>> = (0..4).map(|l| (4 * l..4 * l + 4).collect()).collect();
        assert_eq!(leaves, want);
    }

    /// Rays along z through the layers, counted by hand on the tree above (every kernel set):
    ///
    /// * through triangle 5 at (5.1, 0.1): the root node (1) enters the leaves {4–7} (t ≈ 1)
    ///   and {12–15} (t ≈ 2); the nearer is tested (4 triangles), hits 5 at t = 1, and the
    ///   farther is then skipped (it starts beyond the hit): 1 node, 4 triangles;
    /// * the same from behind: hits 13, skips {4–7}: 1 + 4;
    /// * at (5.4, 0.4), inside both leaves' boxes but between the triangles (triangle i covers
    ///   x ∈ [i, i + 0.1] at y = 0.4): both leaves tested, nothing hit: 1 + 8;
    /// * at (5.1, 2), beside everything: the root's boxes only: 1 + 0;
    /// * along x in the plane z = 0: enters the two front leaves, parallel to every triangle
    ///   (no hit): 1 + 8.
    #[test]
    fn counts_equal_the_hand_count() {
        let triangles = layers();
        let along_z =
            |x: f32, y: f32, z: f32, dz: f32| Ray::new(Vec3::new(x, y, z), Vec3::new(0.0, 0.0, dz));
        let cases = [
            (along_z(5.1, 0.1, -1.0, 1.0), Some(5), cost(1, 4)),
            (along_z(5.1, 0.1, 2.0, -1.0), Some(13), cost(1, 4)),
            (along_z(5.4, 0.4, -1.0, 1.0), None, cost(1, 8)),
            (along_z(5.1, 2.0, -1.0, 1.0), None, cost(1, 0)),
            (
                Ray::new(Vec3::new(-1.0, 0.1, 0.0), Vec3::X),
                None,
                cost(1, 8),
            ),
        ];
        for isa in Isa::available() {
            let accel = Accel::build(&triangles, AccelKind::Bvh8, isa);
            for (ray, index, want) in &cases {
                let (hit, got) = accel.closest_counting(&triangles, ray, f32::INFINITY);
                assert_eq!(hit.map(|h| h.index), *index, "{} {ray:?}", isa.name());
                assert_eq!(hit, accel.closest(&triangles, ray, f32::INFINITY));
                assert_eq!(got, *want, "{} {ray:?}", isa.name());
                if let Some(h) = hit {
                    assert_eq!(h.t, 1.0);
                }
            }
        }
        // The binary tree for the first ray: the root (1), the front layer (2: the back layer
        // is pushed, then skipped), its leaf {4–7}.
        let bvh2 = Accel::build(&triangles, AccelKind::Bvh2, Isa::Scalar);
        assert_eq!(
            bvh2.closest_counting(&triangles, &cases[0].0, f32::INFINITY)
                .1,
            cost(2, 4)
        );
        // The flat and brute-force loops test all sixteen, whatever the ray.
        for kind in [AccelKind::Flat, AccelKind::BruteForce] {
            let accel = Accel::build(&triangles, kind, crate::shapes::scene::best_isa());
            for (ray, _, _) in &cases {
                assert_eq!(
                    accel.closest_counting(&triangles, ray, f32::INFINITY).1,
                    cost(0, 16)
                );
            }
        }
    }
}
