//! Acceleration structures: what answers a [`crate::shapes::scene::Scene`]'s closest-hit and shadow
//! queries without testing every triangle.
//!
//! * [`bvh`]: a binary BVH, binned SAH build, and the readable scalar traversal (the reference).
//! * [`wide`]: the fast path — an 8-wide BVH collapsed from it, triangles in 8-wide packets —
//!   and the flat packet list (a SIMD loop over every triangle).
//! * [`simd`]: the kernels' data (nodes, triangle packets, rays), the readable scalar twin of
//!   the kernels, and the proof types of the x86 sets.
//! * [`set`]: an instruction set as generic code sees it ([`set::InstructionSet`]) and a
//!   function written once for every set ([`set::Compiled`]); [`Isa::call`] dispatches to it.
//! * [`kernels`]: one ray against eight boxes or a packet of triangles, in lanes.
//! * [`packet`]: coherent rays (a camera's, the shadow rays to a point light) through the wide
//!   BVH as packets, one SIMD lane a ray: sixteen at a time with AVX-512, eight with AVX2 and
//!   the portable set.
//! * [`portable`]: the kernel set every CPU runs — the same packets, culling and batches,
//!   eight lanes in two four-lane registers (SSE2 on x86-64, NEON on aarch64).
//! * [`cull`]: a batch of camera rays, or of shadow rays to a point light, bounded by a cone:
//!   the flat list skips the triangles outside it for the whole batch.
//! * [`isa`]: the kernel sets by name ([`Isa`]); [`choice`]: the one every structure uses,
//!   forced or measured ([`calibrate`]: which is fastest on this CPU, at start-up).
//! * [`batches`]: the batch queries, written once for every set.
//! * [`hit`]: what the queries answer ([`Hit`], [`HitLanes`], [`TraversalCost`]);
//!   [`segments`]: shadow rays given as lanes ([`SegmentLanes`]).
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

pub mod batches;
pub mod bvh;
pub mod calibrate;
pub mod choice;
pub mod cull;
pub mod hit;
pub mod isa;
pub mod kernels;
pub mod lane_io;
pub mod packet;
pub mod portable;
pub mod segments;
pub mod set;
pub mod simd;
pub mod wide;
#[cfg(target_arch = "x86_64")]
mod x86_lanes;

use std::time::{Duration, Instant};

use crate::base::geometry::{Ray, Triangle};
use crate::base::named::named_enum;

pub use self::batches::BATCH_OF_LANES;
pub use self::hit::{Hit, HitLanes, TraversalCost};
pub use self::isa::{Isa, skip_unless_required};
pub use self::segments::SegmentLanes;

use self::bvh::Bvh;
use self::set::{Compiled, InstructionSet};
use self::simd::RayK;
use self::wide::{Bvh8Big, Flat};

/// Scenes with at most this many triangles use the flat packet list. The flat loop tests every
/// triangle for every ray with no nodes to walk: it beats the 8-wide BVH on the 30-triangle
/// Cornell box and loses far behind it on the 1,022-triangle teapot. The crossover lies in
/// between; 64 (four 16-wide packets) is on the safe side (PERFORMANCE.md, "Design choices and what each buys").
pub const FLAT_MAX_TRIANGLES: usize = 64;

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
    ///   same culling. It is slower than [`Accel::closest`] (counters, a heap stack): for
    ///   views and teaching, not for rendering.
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
                let mut cost = every(b.big.triangle_count());
                let hit = isa.call(Counting {
                    b,
                    ray,
                    t_max,
                    cost: &mut cost,
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

/// [`Accel::closest_counting`] in the wide BVH, compiled for the set: as the fast path
/// ([`Bvh8Big::closest_with`]), with counters in the tree.
struct Counting<'a> {
    b: &'a Bvh8Big,
    ray: &'a Ray,
    t_max: f32,
    cost: &'a mut TraversalCost,
}

impl Compiled for Counting<'_> {
    type Output = Option<Hit>;
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) -> Option<Hit> {
        let r = RayK::new(self.ray);
        let best = self.b.big.closest(k, &r, self.t_max);
        self.b
            .tree
            .closest_counting(k.tree(), &r, self.t_max, best, self.cost)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

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
