//! A binary bounding volume hierarchy: binned SAH build and the readable scalar traversal.
//!
//! This is the reference the fast path ([`super::wide`]) is collapsed from and tested against.
//! The build sorts triangles into axis-aligned boxes top-down, choosing at every node the split
//! with the lowest surface-area-heuristic cost among 16 bins per axis; big nodes build their two
//! halves in parallel. The nodes are stored flattened, depth first: an interior node's left
//! child follows it, its right child's index is stored.
//!
//! **Conservative boxes.** Every triangle's box is padded a little more than
//! [`EDGE_TOLERANCE`] lets a hit lie beyond the triangle's edges, plus a rounding margin, so a
//! ray the triangle test accepts always enters every box around it: the tree never opens a
//! crack the brute-force loop does not have.
//!
//! **Degenerate input.** Triangles no ray can hit (zero area) are left out, and so are exact
//! copies of another triangle, which can never be the answer (the lower index wins ties);
//! centroids that coincide, which no split can separate, are halved at the median. So a
//! million copies of one triangle build in milliseconds into a one-leaf tree, and the build
//! stays O(n log n) whatever the input (tests/faults.rs).

use glam::{Vec3, Vec3A};

use crate::base::geometry::{Ray, Triangle};
use crate::shapes::intersect::{EDGE_TOLERANCE, intersect_triangle};

use super::{Hit, TraversalCost};

/// Bins per axis of the SAH build.
const BINS: usize = 16;
/// The most triangles a leaf holds: one 8-wide packet of the fast path.
pub const MAX_LEAF: usize = 8;
/// Nodes with at least this many triangles build their halves on two threads.
const PARALLEL_MIN: usize = 16_384;
/// Below this depth the SAH decides; deeper nodes split at the median, which bounds the
/// depth of any tree (and so the traversal stack) by about `MAX_SAH_DEPTH + log2(n)`.
const MAX_SAH_DEPTH: u32 = 40;
/// SAH cost of visiting a node, relative to testing one triangle.
const COST_TRAVERSAL: f32 = 1.0;
/// SAH cost of a triangle in a leaf: triangles are tested eight at a time, so each costs less
/// than a node visit (the value chosen by measuring: PERFORMANCE.md, "Design choices and what
/// each buys").
const COST_LEAF_TRIANGLE: f32 = 0.25;
/// Relative padding of boxes against rounding, on top of the edge tolerance.
const BOX_PAD_RELATIVE: f32 = 8e-6;
/// Boxes are tested against `t_limit · BOX_T_SLACK`, so a box that starts exactly at the best
/// hit so far is still opened (exact ties must reach the triangle test).
pub const BOX_T_SLACK: f32 = 1.0 + 1e-5;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: growing it by anything gives that thing.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    pub fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// Half the surface area (the SAH only compares areas).
    pub fn half_area(&self) -> f32 {
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    pub fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// The padded box of a triangle, or `None` when a vertex is not finite (such a triangle
    /// can never be hit, see [`intersect_triangle`], and is left out of the tree).
    pub fn of_triangle(t: &Triangle) -> Option<Aabb> {
        if !(t.v0.is_finite() && t.v1.is_finite() && t.v2.is_finite()) {
            return Self::of_non_finite_triangle(t);
        }
        // Finite corners: min and max are exact, so SIMD registers give the very same box.
        let [a, b, c] = [t.v0, t.v1, t.v2].map(Vec3A::from);
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let extent = (max - min).max_element();
        let magnitude = min.abs().max(max.abs()).max_element();
        let pad =
            Vec3A::splat(4.0 * EDGE_TOLERANCE * extent + BOX_PAD_RELATIVE * magnitude + 1e-30);
        Some(Aabb {
            min: (min - pad).into(),
            max: (max + pad).into(),
        })
    }

    /// [`Aabb::of_triangle`] when a corner is not finite: `f32::min` and `max` pass over NaN,
    /// so the box is that of the other corners when they are finite (the triangle is still
    /// never hit).
    #[cold]
    fn of_non_finite_triangle(t: &Triangle) -> Option<Aabb> {
        let min = t.v0.min(t.v1).min(t.v2);
        let max = t.v0.max(t.v1).max(t.v2);
        if !(min.is_finite() && max.is_finite()) {
            return None;
        }
        let extent = (max - min).max_element();
        let magnitude = min.abs().max(max.abs()).max_element();
        let pad = 4.0 * EDGE_TOLERANCE * extent + BOX_PAD_RELATIVE * magnitude + 1e-30;
        Some(Aabb {
            min: min - Vec3::splat(pad),
            max: max + Vec3::splat(pad),
        })
    }
}

/// What a box test needs of a ray, computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct RayBoxData {
    pub origin: Vec3,
    /// `1 / direction`, with zero components replaced by a huge finite value of the same sign
    /// so that no `0 · ∞` NaN can appear.
    pub inv: Vec3,
    /// `origin · inv`, for the fused multiply-subtract form.
    pub origin_inv: Vec3,
    /// Per axis, whether the ray goes towards negative coordinates (then the box's max is its
    /// near plane).
    pub negative: [bool; 3],
}

/// Stand-in for `1/0`: large, but `o · INV_HUGE` stays finite for coordinates up to 1e18.
pub(super) const INV_HUGE: f32 = 1e20;

impl RayBoxData {
    pub fn new(ray: &Ray) -> Self {
        let inv = Vec3::from_array(ray.direction.to_array().map(|d| {
            if d.abs() > 1.0 / INV_HUGE {
                1.0 / d
            } else {
                INV_HUGE.copysign(d)
            }
        }));
        Self {
            origin: ray.origin,
            inv,
            origin_inv: ray.origin * inv,
            negative: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }

    /// The slab test: the entry distance if the ray meets `b` within `[0, t_limit]`.
    pub fn hit(&self, b: &Aabb, t_limit: f32) -> Option<f32> {
        let mut t_near = 0.0f32;
        let mut t_far = t_limit;
        for axis in 0..3 {
            let (near, far) = if self.negative[axis] {
                (b.max[axis], b.min[axis])
            } else {
                (b.min[axis], b.max[axis])
            };
            let t0 = (near - self.origin[axis]) * self.inv[axis];
            let t1 = (far - self.origin[axis]) * self.inv[axis];
            t_near = t_near.max(t0);
            t_far = t_far.min(t1);
        }
        (t_near <= t_far).then_some(t_near)
    }
}

/// A node of the flattened binary tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    pub bounds: Aabb,
    /// Leaf: index of its first entry in [`Bvh::indices`]. Interior: index of the right child
    /// (the left child is the next node).
    pub first_or_right: u32,
    /// Number of triangles; 0 for an interior node.
    pub count: u32,
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A binary BVH over a triangle list. Empty for a scene without (finite) triangles.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    /// Triangle indices, leaf by leaf.
    pub indices: Vec<u32>,
}

impl Bvh {
    /// Builds the tree with binned SAH, in parallel on the current rayon pool.
    pub fn build(triangles: &[Triangle]) -> Self {
        Self::build_except(triangles, &[])
    }

    /// [`Bvh::build`] over every triangle but those in `excluded` (sorted indices).
    pub fn build_except(triangles: &[Triangle], excluded: &[u32]) -> Self {
        Self::build_prims(triangles, prims_of(triangles, excluded))
    }

    /// [`Bvh::build`] over every triangle but the largest: at most `most` of those whose box's
    /// surface area is at least `fraction` of the whole scene's box's (the largest first, ties
    /// to the lower index). Returns the tree and the triangles set apart (ascending).
    pub fn build_apart(triangles: &[Triangle], most: usize, fraction: f32) -> (Self, Vec<u32>) {
        let mut prims = prims_of(triangles, &[]);
        let apart = largest(&prims, most, fraction);
        for &i in &apart {
            prims[i as usize].index = LEFT_OUT;
        }
        (Self::build_prims(triangles, prims), apart)
    }

    /// The tree over the `prims` not [`LEFT_OUT`].
    fn build_prims(triangles: &[Triangle], mut prims: Vec<Prim>) -> Self {
        use rayon::prelude::*;
        // Usually none is left out, and this is one read of the list.
        prims.retain(|p| p.index != LEFT_OUT);
        if prims.is_empty() {
            return Self::default();
        }
        // Min and max are exact, so the chunks may combine in any order: the same boxes on
        // any number of threads.
        let (bounds, centroids) = prims.par_chunks(PARALLEL_MIN).map(bounds_of).reduce(
            || (BuildBox::EMPTY, BuildBox::EMPTY),
            |(b0, c0), (b1, c1)| (b0.union(&b1), c0.union(&c1)),
        );
        let builder = Builder { triangles };
        let root = builder.part(&mut prims, 0, 0, bounds, centroids);
        let placeholder = Node {
            bounds: Aabb::EMPTY,
            first_or_right: 0,
            count: 0,
        };
        let mut nodes = vec![placeholder; root.len()];
        root.place(&mut nodes, 0);
        let indices = leaf_order_indices(&mut nodes, &prims);
        Bvh { nodes, indices }
    }

    /// The triangle indices of a leaf.
    pub fn leaf_indices(&self, node: &Node) -> &[u32] {
        let first = node.first_or_right as usize;
        &self.indices[first..first + node.count as usize]
    }

    /// The children of an interior node.
    pub fn children(&self, index: usize) -> [usize; 2] {
        [index + 1, self.nodes[index].first_or_right as usize]
    }

    /// The closest hit with `t < t_max`; among hits at the same `t`, the
    /// lowest index, exactly as [`crate::shapes::intersect::closest_intersection_brute_force`].
    ///
    /// The readable reference: nearer child first, boxes beyond the best hit skipped.
    pub fn closest(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> Option<Hit> {
        self.closest_counting(triangles, ray, t_max).0
    }

    /// [`Bvh::closest`] and what it cost: the interior nodes visited (each tests its two
    /// children's boxes; the root's own box test is not counted) and the triangles tested.
    /// One traversal serves both, so the counts are those of the reference itself.
    pub fn closest_counting(
        &self,
        triangles: &[Triangle],
        ray: &Ray,
        t_max: f32,
    ) -> (Option<Hit>, TraversalCost) {
        let mut cost = TraversalCost::default();
        let Some(root) = self.nodes.first() else {
            return (None, cost);
        };
        let rb = RayBoxData::new(ray);
        let mut best: Option<Hit> = None;
        let Some(t_root) = rb.hit(&root.bounds, t_max * BOX_T_SLACK) else {
            return (None, cost);
        };
        let mut stack = vec![(0usize, t_root)];
        while let Some((index, t_near)) = stack.pop() {
            let limit = best.map_or(t_max, |h| h.t);
            if t_near > limit * BOX_T_SLACK {
                continue;
            }
            let node = &self.nodes[index];
            if node.is_leaf() {
                cost.triangles += node.count;
                for &i in self.leaf_indices(node) {
                    // Candidates at the best distance too: the lower index wins a tie.
                    let limit = best.map_or(t_max, |h| h.t.next_up());
                    if let Some((t, u, v)) = intersect_triangle(ray, &triangles[i as usize], limit)
                        && best.is_none_or(|h| t < h.t || i < h.index)
                    {
                        best = Some(Hit { index: i, t, u, v });
                    }
                }
                continue;
            }
            cost.nodes += 1;
            let hits = self
                .children(index)
                .map(|c| (c, rb.hit(&self.nodes[c].bounds, limit * BOX_T_SLACK)));
            match hits {
                [(a, Some(ta)), (b, Some(tb))] => {
                    // Push the farther child first so the nearer one is visited first.
                    let (first, second) = if ta <= tb {
                        ((b, tb), (a, ta))
                    } else {
                        ((a, ta), (b, tb))
                    };
                    stack.push(first);
                    stack.push(second);
                }
                [(c, Some(t)), _] | [_, (c, Some(t))] => stack.push((c, t)),
                _ => {}
            }
        }
        (best, cost)
    }

    /// Whether any triangle is hit with `0 < t < t_max`; stops at the first hit.
    pub fn occluded(&self, triangles: &[Triangle], ray: &Ray, t_max: f32) -> bool {
        let Some(root) = self.nodes.first() else {
            return false;
        };
        let rb = RayBoxData::new(ray);
        let limit = t_max * BOX_T_SLACK;
        if rb.hit(&root.bounds, limit).is_none() {
            return false;
        }
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            if node.is_leaf() {
                if self
                    .leaf_indices(node)
                    .iter()
                    .any(|&i| intersect_triangle(ray, &triangles[i as usize], t_max).is_some())
                {
                    return true;
                }
                continue;
            }
            for c in self.children(index) {
                if rb.hit(&self.nodes[c].bounds, limit).is_some() {
                    stack.push(c);
                }
            }
        }
        false
    }

    /// Depth of the tree (a root leaf has depth 1).
    pub fn depth(&self) -> usize {
        fn go(bvh: &Bvh, i: usize) -> usize {
            if bvh.nodes[i].is_leaf() {
                1
            } else {
                let [a, b] = bvh.children(i);
                1 + go(bvh, a).max(go(bvh, b))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            go(self, 0)
        }
    }
}

/// Whether a ray can ever hit `t`: not when its edges' cross product is exactly zero (its
/// corners coincide or lie on a line), for then [`intersect_triangle`] (and every kernel, which
/// computes the same product) divides zero by zero and rejects the NaN. Such triangles are left
/// out of the tree: a million of them in one point would otherwise be a million candidates.
fn can_be_hit(t: &Triangle) -> bool {
    let (e1, e2) = t.edges();
    e1.cross(e2) != Vec3::ZERO
}

/// Keeps one of each set of bit-identical triangles among `prims`, the lowest index, at the
/// front (in no particular order); returns how many are kept. A copy can never be the closest
/// hit (it ties with the triangle it copies, and the lower index wins ties) nor change whether
/// a shadow ray is blocked, so leaving it out of the tree changes no answer; left in, every
/// ray reaching the triangle would test every copy.
fn keep_one_of_each_copy(triangles: &[Triangle], prims: &mut [Prim]) -> usize {
    let key = |p: &Prim| {
        let t = &triangles[p.index as usize];
        (
            [t.v0, t.v1, t.v2].map(|v| v.to_array().map(f32::to_bits)),
            p.index,
        )
    };
    prims.sort_unstable_by_key(key);
    let mut kept = 0;
    for i in 0..prims.len() {
        if kept == 0 || key(&prims[i]).0 != key(&prims[kept - 1]).0 {
            prims.swap(kept, i);
            kept += 1;
        }
    }
    kept
}

/// A box as the build computes with it: `Vec3A`s, one SSE register per corner, so growing a box
/// is one `minps` and one `maxps`. (Min and max are exact, so every box equals the [`Aabb`] the
/// same points would give.)
#[derive(Clone, Copy, Debug)]
struct BuildBox {
    min: Vec3A,
    max: Vec3A,
}

impl BuildBox {
    const EMPTY: BuildBox = BuildBox {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, min: Vec3A, max: Vec3A) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
    }

    #[inline(always)]
    fn grow_point(&mut self, p: Vec3A) {
        self.grow(p, p);
    }

    #[inline(always)]
    fn union(&self, other: &BuildBox) -> BuildBox {
        let mut b = *self;
        b.grow(other.min, other.max);
        b
    }

    fn extent(&self) -> Vec3A {
        (self.max - self.min).max(Vec3A::ZERO)
    }

    /// [`Aabb::half_area`], the same operations in the same order.
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// The index of a prim whose triangle is left out of the tree (scenes have fewer triangles:
/// their indices are `u32`, and a hit's index is never `u32::MAX`).
const LEFT_OUT: u32 = u32::MAX;

/// A triangle as the build sees it: its padded box and its index.
#[derive(Clone, Copy)]
struct Prim {
    min: Vec3A,
    max: Vec3A,
    index: u32,
}

impl Prim {
    fn new(b: &Aabb, index: u32) -> Self {
        Self {
            min: b.min.into(),
            max: b.max.into(),
            index,
        }
    }

    /// [`Aabb::centre`] of its box, bit for bit.
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }
}

/// One prim per triangle, in order, collected in place (an indexed iterator: no chunks to
/// join). A triangle excluded or that no ray can hit is [`LEFT_OUT`]; one whose box is not
/// finite also has an empty box.
fn prims_of(triangles: &[Triangle], excluded: &[u32]) -> Vec<Prim> {
    use rayon::prelude::*;
    triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| match Aabb::of_triangle(t) {
            Some(b) => {
                let kept = excluded.binary_search(&(i as u32)).is_err() && can_be_hit(t);
                Prim::new(&b, if kept { i as u32 } else { LEFT_OUT })
            }
            None => Prim::new(&Aabb::EMPTY, LEFT_OUT),
        })
        .collect()
}

/// The indices (ascending) of at most `most` of the largest triangles among `prims` (one per
/// triangle, [`prims_of`]): those whose box has at least `fraction` of the surface area of the
/// box around every triangle's box, the largest first, ties to the lower index. Triangles no
/// ray can hit count too, as long as their box is finite.
fn largest(prims: &[Prim], most: usize, fraction: f32) -> Vec<u32> {
    use rayon::prelude::*;
    let finite = |p: &Prim| p.min.x <= p.max.x;
    // Min and max are exact: the same box whatever the split into chunks.
    let scene = prims
        .par_iter()
        .map(|p| BuildBox {
            min: p.min,
            max: p.max,
        })
        .reduce(|| BuildBox::EMPTY, |a, b| a.union(&b));
    let threshold = fraction * scene.half_area();
    let mut large: Vec<(f32, u32)> = prims
        .par_iter()
        .enumerate()
        .filter(|(_, p)| finite(p))
        .map(|(i, p)| {
            let b = BuildBox {
                min: p.min,
                max: p.max,
            };
            (b.half_area(), i as u32)
        })
        .filter(|&(a, _)| a >= threshold)
        .collect();
    large.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    large.truncate(most);
    let mut large: Vec<u32> = large.into_iter().map(|(_, i)| i).collect();
    large.sort_unstable();
    large
}

/// The box of `prims`' boxes and the box of their centroids.
fn bounds_of(prims: &[Prim]) -> (BuildBox, BuildBox) {
    let mut bounds = BuildBox::EMPTY;
    let mut centroids = BuildBox::EMPTY;
    for p in prims {
        bounds.grow(p.min, p.max);
        centroids.grow_point(p.centroid());
    }
    (bounds, centroids)
}

/// How a node is split, with what each half needs to be split in turn.
enum Split {
    /// A leaf of the first `count` prims (exact copies left out, see [`keep_one_of_each_copy`]).
    Leaf { count: usize },
    /// Prims `..mid` on the left, the rest on the right, each with its bounds and centroid
    /// bounds, known from the split (its bins and the partition) without another pass.
    Halves {
        mid: usize,
        left: (BuildBox, BuildBox),
        right: (BuildBox, BuildBox),
    },
}

/// A subtree being built: its nodes flattened depth first. Below [`PARALLEL_MIN`] prims a
/// subtree is built on one thread into one `Vec` (`Nodes`; links to right children are
/// relative to its first node); above, its halves are built on two threads and stay apart
/// (`Joined`) until [`Part::place`] copies every node once into the final array.
enum Part {
    Nodes(Vec<Node>),
    Joined {
        bounds: Aabb,
        halves: Box<[Part; 2]>,
        len: usize,
    },
}

impl Part {
    fn len(&self) -> usize {
        match self {
            Part::Nodes(nodes) => nodes.len(),
            Part::Joined { len, .. } => *len,
        }
    }

    /// Copies the subtree into `out` (exactly [`Part::len`] nodes), which starts at node `base`
    /// of the whole tree.
    fn place(&self, out: &mut [Node], base: usize) {
        match self {
            Part::Nodes(nodes) => {
                for (o, n) in out.iter_mut().zip(nodes) {
                    *o = *n;
                    if !n.is_leaf() {
                        o.first_or_right += base as u32;
                    }
                }
            }
            Part::Joined { bounds, halves, .. } => {
                let (head, rest) = out.split_first_mut().expect("a joined part has its node");
                let left_len = halves[0].len();
                *head = Node {
                    bounds: *bounds,
                    first_or_right: (base + 1 + left_len) as u32,
                    count: 0,
                };
                let (left, right) = rest.split_at_mut(left_len);
                rayon::join(
                    || halves[0].place(left, base + 1),
                    || halves[1].place(right, base + 1 + left_len),
                );
            }
        }
    }
}

/// The build of one tree.
struct Builder<'a> {
    triangles: &'a [Triangle],
}

impl Builder<'_> {
    /// The subtree over `prims` (which start at `offset` of the whole list): in parallel down
    /// to [`PARALLEL_MIN`] prims, then [`Builder::serial`].
    fn part(
        &self,
        prims: &mut [Prim],
        offset: usize,
        depth: u32,
        bounds: BuildBox,
        centroids: BuildBox,
    ) -> Part {
        if prims.len() < PARALLEL_MIN {
            // About one node per two prims with leaves of up to eight.
            let mut nodes = Vec::with_capacity(prims.len() / 2 + 1);
            self.serial(prims, offset, depth, bounds, centroids, &mut nodes);
            return Part::Nodes(nodes);
        }
        match self.split(prims, depth, &bounds, &centroids) {
            Split::Leaf { count } => Part::Nodes(vec![Node {
                bounds: bounds.aabb(),
                first_or_right: offset as u32,
                count: count as u32,
            }]),
            Split::Halves { mid, left, right } => {
                let (l, r) = prims.split_at_mut(mid);
                let (a, b) = rayon::join(
                    || self.part(l, offset, depth + 1, left.0, left.1),
                    || self.part(r, offset + mid, depth + 1, right.0, right.1),
                );
                Part::Joined {
                    bounds: bounds.aabb(),
                    len: 1 + a.len() + b.len(),
                    halves: Box::new([a, b]),
                }
            }
        }
    }

    /// Appends the subtree over `prims` to `out`, depth first, on this thread.
    fn serial(
        &self,
        prims: &mut [Prim],
        offset: usize,
        depth: u32,
        bounds: BuildBox,
        centroids: BuildBox,
        out: &mut Vec<Node>,
    ) {
        let at = out.len();
        match self.split(prims, depth, &bounds, &centroids) {
            Split::Leaf { count } => out.push(Node {
                bounds: bounds.aabb(),
                first_or_right: offset as u32,
                count: count as u32,
            }),
            Split::Halves { mid, left, right } => {
                out.push(Node {
                    bounds: bounds.aabb(),
                    first_or_right: 0,
                    count: 0,
                });
                let (l, r) = prims.split_at_mut(mid);
                self.serial(l, offset, depth + 1, left.0, left.1, out);
                out[at].first_or_right = out.len() as u32;
                self.serial(r, offset + mid, depth + 1, right.0, right.1, out);
            }
        }
    }

    /// Decides a node over `prims` (with `bounds` and `centroids`, their boxes): a leaf, or a
    /// split with the prims partitioned.
    fn split(
        &self,
        prims: &mut [Prim],
        depth: u32,
        bounds: &BuildBox,
        centroids: &BuildBox,
    ) -> Split {
        // Copies of one triangle share their centroid, so binning keeps them together down to a
        // node whose centroids are all one point: here they are found (only here, where it
        // costs nothing on ordinary scenes) and all but one left out of the tree. The copies'
        // boxes are the kept one's, so `bounds` stays right. (Coincident centroids of different
        // triangles are then halved at the median below, which keeps the build O(n log n).)
        let n = if prims.len() > MAX_LEAF && centroids.extent() == Vec3A::ZERO {
            keep_one_of_each_copy(self.triangles, prims)
        } else {
            prims.len()
        };
        let prims = &mut prims[..n];
        if n <= 1 {
            return Split::Leaf { count: n };
        }
        let sah = if depth < MAX_SAH_DEPTH {
            sah_split(prims, bounds, centroids)
        } else {
            Sah::default()
        };
        if n <= MAX_LEAF && (sah.leaf_is_cheaper || sah.best.is_none()) {
            return Split::Leaf { count: n };
        }
        if let Some((axis, bin, scale)) = sah.best {
            // The prims binned at most `bin` on `axis`. A bin is the truncation of a value from 0
            // up, which is at most `bin` exactly when the value is below `bin + 1`: the same
            // operations as binning, compared without converting (on all three lanes at once,
            // the one of `axis` kept).
            let (lo, scale) = (centroids.min, Vec3A::splat(scale));
            let (end, lane) = (Vec3A::splat((bin + 1) as f32), 1 << axis);
            let (mid, left_centroids, right_centroids) = partition(prims, &|c| {
                ((c - lo) * scale).cmplt(end).bitmask() & lane != 0
            });
            if mid != 0 && mid != n {
                return Split::Halves {
                    mid,
                    left: (sah.left, left_centroids),
                    right: (sah.right, right_centroids),
                };
            }
        }
        // No SAH split (too deep, or all centroids in one place): halve at the median centroid
        // of the longest axis, which for coincident centroids is any half.
        let axis = Vec3::from(centroids.extent()).max_position();
        let mid = n / 2;
        prims.select_nth_unstable_by(mid, |a, b| {
            a.centroid()[axis].total_cmp(&b.centroid()[axis])
        });
        let (left, right) = prims.split_at(mid);
        Split::Halves {
            mid,
            left: bounds_of(left),
            right: bounds_of(right),
        }
    }
}

/// The triangle indices leaf by leaf, in the order of `nodes` (depth first), with the leaves'
/// `first` turned from offsets into the prims into offsets into the result. Leaves hold
/// contiguous runs of the prims in order, so this is the prims' own order, unless copies were
/// left out (then they are skipped).
fn leaf_order_indices(nodes: &mut [Node], prims: &[Prim]) -> Vec<u32> {
    use rayon::prelude::*;
    let in_leaves: usize = nodes.iter().map(|n| n.count as usize).sum();
    if in_leaves == prims.len() {
        return prims.par_iter().map(|p| p.index).collect();
    }
    let mut indices = Vec::with_capacity(in_leaves);
    for node in nodes.iter_mut().filter(|n| n.is_leaf()) {
        let first = node.first_or_right as usize;
        node.first_or_right = indices.len() as u32;
        indices.extend(
            prims[first..first + node.count as usize]
                .iter()
                .map(|p| p.index),
        );
    }
    indices
}

/// The outcome of binning a node.
#[derive(Clone, Copy)]
struct Sah {
    /// The cheapest split: axis, last bin on the left, bin scale.
    best: Option<(usize, usize, f32)>,
    /// Whether a leaf costs less than that split.
    leaf_is_cheaper: bool,
    /// The boxes of the prims left and right of the split (the union of their bins).
    left: BuildBox,
    right: BuildBox,
}

impl Default for Sah {
    fn default() -> Self {
        Self {
            best: None,
            leaf_is_cheaper: false,
            left: BuildBox::EMPTY,
            right: BuildBox::EMPTY,
        }
    }
}

/// The last bin, as a float: a centroid's position in bins is clamped to it, then truncated.
const LAST_BIN: f32 = (BINS - 1) as f32;

/// The three lanes of `v` truncated towards zero, as `as usize` does for the values binning
/// gives (from 0 to [`LAST_BIN`]), in one instruction for the three (`cvttps2dq`) instead of
/// three conversions that each check for overflow.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn truncate(v: Vec3A) -> [usize; 3] {
    use std::arch::x86_64::{_mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_shuffle_epi32};
    // SAFETY: register-only SSE2 instructions, which every x86-64 processor has.
    unsafe {
        let i = _mm_cvttps_epi32(v.into());
        [
            _mm_cvtsi128_si32(i) as usize,
            _mm_cvtsi128_si32(_mm_shuffle_epi32::<1>(i)) as usize,
            _mm_cvtsi128_si32(_mm_shuffle_epi32::<2>(i)) as usize,
        ]
    }
}

#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn truncate(v: Vec3A) -> [usize; 3] {
    v.to_array().map(|x| x as usize)
}

/// One bin of one axis: how many prims, and the box around them.
#[derive(Clone, Copy)]
struct Bin {
    bounds: BuildBox,
    count: u32,
}

/// The bins of every axis.
type Bins = [[Bin; BINS]; 3];

const NO_BINS: Bins = [[Bin {
    bounds: BuildBox::EMPTY,
    count: 0,
}; BINS]; 3];

/// Sorts `prims` into bins by centroid: `(c − lo) · scale` clamped to the last bin and
/// truncated, on each axis. Large nodes (the few near the root, which would otherwise keep one
/// thread busy while the other waits) are binned in parallel chunks: counts add and boxes
/// unite exactly, so the bins are the same whatever the number of threads.
fn bin_prims(prims: &[Prim], lo: Vec3A, scale: Vec3A, bins: &mut Bins) {
    use rayon::prelude::*;
    if prims.len() >= 2 * PARALLEL_MIN {
        let chunks = prims
            .par_chunks(PARALLEL_MIN)
            .map(|chunk| {
                let mut bins = NO_BINS;
                bin_prims(chunk, lo, scale, &mut bins);
                bins
            })
            .reduce(
                || NO_BINS,
                |mut a, b| {
                    merge_bins(&mut a, &b);
                    a
                },
            );
        merge_bins(bins, &chunks);
        return;
    }
    let last = Vec3A::splat(LAST_BIN);
    for p in prims {
        // Three lanes at once. (`Builder::split` decides sides by the same arithmetic.)
        let at = truncate(((p.centroid() - lo) * scale).min(last));
        for (axis, bins) in bins.iter_mut().enumerate() {
            let bin = &mut bins[at[axis] & (BINS - 1)];
            bin.count += 1;
            bin.bounds.grow(p.min, p.max);
        }
    }
}

/// Adds the prims of bins `b` to bins `a`.
fn merge_bins(a: &mut Bins, b: &Bins) {
    for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        a.count += b.count;
        a.bounds = a.bounds.union(&b.bounds);
    }
}

/// The cheapest binned SAH split, and whether keeping the node whole is cheaper still. No
/// split when the centroids have no extent to bin.
fn sah_split(prims: &[Prim], bounds: &BuildBox, centroids: &BuildBox) -> Sah {
    let extent = centroids.extent();
    let scale = Vec3A::from_array(extent.to_array().map(|e| {
        if e > 0.0 {
            BINS as f32 * (1.0 - 1e-6) / e
        } else {
            0.0
        }
    }));
    if scale == Vec3A::ZERO || !scale.is_finite() {
        return Sah::default();
    }
    // (Filled in place: the bins are 2 kB, and small nodes are many.)
    let mut bins = NO_BINS;
    bin_prims(prims, centroids.min, scale, &mut bins);
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if scale[axis] == 0.0 {
            continue;
        }
        // Only the bins that hold prims: a split after an empty bin has the same two sides,
        // so the same cost, as the split after the last bin before it that holds any, and that
        // one comes first (ties go to the first). Small nodes fill few of the bins.
        let mut filled = [0; BINS];
        let mut len = 0;
        for (b, bin) in bins.iter().enumerate() {
            if bin.count > 0 {
                filled[len] = b;
                len += 1;
            }
        }
        // Right-to-left sweep: area × count of everything from each filled bin on.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = BuildBox::EMPTY;
        let mut count = 0u32;
        for j in (1..len).rev() {
            let bin = &bins[filled[j]];
            acc = acc.union(&bin.bounds);
            count += bin.count;
            right_cost[j] = acc.half_area() * count as f32;
        }
        // Left to right: a split after each filled bin but the last.
        let mut acc = BuildBox::EMPTY;
        let mut count = 0u32;
        for j in 0..len.saturating_sub(1) {
            let bin = &bins[filled[j]];
            acc = acc.union(&bin.bounds);
            count += bin.count;
            let cost = acc.half_area() * count as f32 + right_cost[j + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, filled[j]));
            }
        }
    }
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    let leaf_cost = COST_LEAF_TRIANGLE * prims.len() as f32;
    match best {
        Some((cost, axis, bin)) => {
            let union = |bins: &[Bin]| {
                bins.iter()
                    .fold(BuildBox::EMPTY, |acc, b| acc.union(&b.bounds))
            };
            Sah {
                best: Some((axis, bin, scale[axis])),
                leaf_is_cheaper: leaf_cost <= COST_TRAVERSAL + COST_LEAF_TRIANGLE * cost / area,
                left: union(&bins[axis][..=bin]),
                right: union(&bins[axis][bin + 1..]),
            }
        }
        None => Sah::default(),
    }
}

/// Moves the prims whose centroid satisfies `left` to the front; returns how many there are
/// and the boxes of the centroids on each side.
///
/// Large nodes are partitioned in parallel: each half on its own, then the right part of the
/// first half and the left part of the second trade places. The halves are cut by size alone,
/// so the order is the same whatever the number of threads.
fn partition(
    prims: &mut [Prim],
    left: &(impl Fn(Vec3A) -> bool + Sync),
) -> (usize, BuildBox, BuildBox) {
    if prims.len() < 2 * PARALLEL_MIN {
        return partition_serial(prims, left);
    }
    let half = prims.len() / 2;
    let (a, b) = prims.split_at_mut(half);
    let ((in_a, left_a, right_a), (in_b, left_b, right_b)) =
        rayon::join(|| partition(a, left), || partition(b, left));
    // [a's left | a's right | b's left | b's right]: swap the shorter of the middle two with
    // the far end of the other.
    let swapped = (half - in_a).min(in_b);
    let (front, back) = prims.split_at_mut(half + in_b - swapped);
    swap_slices(&mut front[in_a..in_a + swapped], &mut back[..swapped]);
    (in_a + in_b, left_a.union(&left_b), right_a.union(&right_b))
}

/// Swaps the contents of two slices of the same length, in parallel chunks.
fn swap_slices(a: &mut [Prim], b: &mut [Prim]) {
    use rayon::prelude::*;
    a.par_chunks_mut(PARALLEL_MIN)
        .zip(b.par_chunks_mut(PARALLEL_MIN))
        .for_each(|(a, b)| a.swap_with_slice(b));
}

/// [`partition`] on one thread: scans from both ends and swaps only the pairs on the wrong
/// sides.
fn partition_serial(
    prims: &mut [Prim],
    left: impl Fn(Vec3A) -> bool,
) -> (usize, BuildBox, BuildBox) {
    let mut left_centroids = BuildBox::EMPTY;
    let mut right_centroids = BuildBox::EMPTY;
    let mut i = 0;
    let mut j = prims.len();
    loop {
        while i < j {
            let c = prims[i].centroid();
            if !left(c) {
                break;
            }
            left_centroids.grow_point(c);
            i += 1;
        }
        while i < j {
            let c = prims[j - 1].centroid();
            if left(c) {
                break;
            }
            right_centroids.grow_point(c);
            j -= 1;
        }
        if i == j {
            return (i, left_centroids, right_centroids);
        }
        // `prims[i]` goes right and `prims[j - 1]` left.
        right_centroids.grow_point(prims[i].centroid());
        left_centroids.grow_point(prims[j - 1].centroid());
        prims.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::sampling::Rng;

    fn random_prims(n: usize, seed: u64) -> Vec<Prim> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|i| {
                let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let b = Aabb {
                    min: c - 0.01,
                    max: c + 0.02,
                };
                Prim::new(&b, i as u32)
            })
            .collect()
    }

    /// The parallel partition (nodes of 32,768 prims and more) against the plain definition:
    /// the same prims on each side and the same centroid boxes, at several sizes around where
    /// it starts splitting, with sides of every proportion.
    #[test]
    fn partition_puts_each_prim_on_its_side_and_bounds_each_side() {
        for (n, cut) in [
            (100, 0.5),
            (40_000, 0.5),
            (70_001, 0.1),
            (70_001, 0.97),
            (140_000, 0.0),
        ] {
            let mut prims = random_prims(n, n as u64);
            let left = |c: Vec3A| c.x < cut;
            let (mid, left_box, right_box) = partition(&mut prims, &left);
            assert!(prims[..mid].iter().all(|p| left(p.centroid())), "{n} {cut}");
            assert!(
                prims[mid..].iter().all(|p| !left(p.centroid())),
                "{n} {cut}"
            );
            let mut indices: Vec<u32> = prims.iter().map(|p| p.index).collect();
            indices.sort_unstable();
            assert!(indices.iter().enumerate().all(|(i, &j)| i as u32 == j));
            assert_eq!(
                bounds_of(&prims[..mid]).1.aabb(),
                left_box.aabb(),
                "{n} {cut}"
            );
            assert_eq!(
                bounds_of(&prims[mid..]).1.aabb(),
                right_box.aabb(),
                "{n} {cut}"
            );
        }
    }

    /// Binning in parallel chunks gives exactly the bins of one pass.
    #[test]
    fn parallel_binning_equals_one_pass() {
        let prims = random_prims(100_000, 7);
        let (lo, scale) = (Vec3A::ZERO, Vec3A::new(16.0, 8.0, 0.0));
        let mut parallel = NO_BINS;
        bin_prims(&prims, lo, scale, &mut parallel);
        let mut serial = NO_BINS;
        for chunk in prims.chunks(PARALLEL_MIN / 2) {
            bin_prims(chunk, lo, scale, &mut serial);
        }
        for (a, b) in parallel.iter().flatten().zip(serial.iter().flatten()) {
            assert_eq!((a.count, a.bounds.aabb()), (b.count, b.bounds.aabb()));
        }
        assert_eq!(parallel[2][0].count, 100_000);
    }
}
