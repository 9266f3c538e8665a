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

use glam::Vec3;

use crate::geometry::{Ray, Triangle};
use crate::intersect::{EDGE_TOLERANCE, intersect_triangle};

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
/// than a node visit.
const COST_LEAF_TRIANGLE: f32 = 0.35;
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

#[derive(Clone, Copy)]
struct Prim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

enum BuildNode {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[BuildNode; 2]>,
    },
}

impl Bvh {
    /// Builds the tree with binned SAH, in parallel on the current rayon pool.
    pub fn build(triangles: &[Triangle]) -> Self {
        Self::build_except(triangles, &[])
    }

    /// [`Bvh::build`] over every triangle but those in `excluded` (sorted indices).
    pub fn build_except(triangles: &[Triangle], excluded: &[u32]) -> Self {
        use rayon::prelude::*;
        let mut prims: Vec<Prim> = triangles
            .par_iter()
            .enumerate()
            .filter(|(i, _)| excluded.binary_search(&(*i as u32)).is_err())
            .filter(|(_, t)| can_be_hit(t))
            .filter_map(|(i, t)| {
                Aabb::of_triangle(t).map(|bounds| Prim {
                    bounds,
                    centroid: bounds.centre(),
                    index: i as u32,
                })
            })
            .collect();
        if prims.is_empty() {
            return Self::default();
        }
        let root = build_node(triangles, &mut prims, 0, 0);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * prims.len() / 3 + 1),
            indices: Vec::with_capacity(prims.len()),
        };
        bvh.flatten(&root, &prims);
        bvh
    }

    /// Appends `node`'s subtree, depth first; its leaves' triangles go to `indices` in leaf
    /// order (copies left out by the build are in no leaf, so not there either).
    fn flatten(&mut self, node: &BuildNode, prims: &[Prim]) -> usize {
        let at = self.nodes.len();
        match node {
            BuildNode::Leaf {
                bounds,
                first,
                count,
            } => {
                let start = self.indices.len() as u32;
                let range = *first as usize..(*first + *count) as usize;
                self.indices.extend(prims[range].iter().map(|p| p.index));
                self.nodes.push(Node {
                    bounds: *bounds,
                    first_or_right: start,
                    count: *count,
                });
            }
            BuildNode::Interior { bounds, children } => {
                self.nodes.push(Node {
                    bounds: *bounds,
                    first_or_right: 0,
                    count: 0,
                });
                self.flatten(&children[0], prims);
                let right = self.flatten(&children[1], prims);
                self.nodes[at].first_or_right = right as u32;
            }
        }
        at
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
    /// lowest index, exactly as [`crate::intersect::closest_intersection_brute_force`].
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

fn leaf(prims: &[Prim], offset: usize, bounds: Aabb) -> BuildNode {
    BuildNode::Leaf {
        bounds,
        first: offset as u32,
        count: prims.len() as u32,
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

fn build_node(triangles: &[Triangle], prims: &mut [Prim], offset: usize, depth: u32) -> BuildNode {
    let mut bounds = Aabb::EMPTY;
    let mut centroids = Aabb::EMPTY;
    for p in prims.iter() {
        bounds.grow(&p.bounds);
        centroids.grow_point(p.centroid);
    }
    // Copies of one triangle share their centroid, so binning keeps them together down to a
    // node whose centroids are all one point: here they are found (only here, where it costs
    // nothing on ordinary scenes) and all but one left out of the tree. The copies' boxes are
    // the kept one's, so `bounds` stays right. (Coincident centroids of different triangles are
    // then halved at the median below, which keeps the build O(n log n).)
    let prims = if prims.len() > MAX_LEAF && centroids.extent() == Vec3::ZERO {
        let kept = keep_one_of_each_copy(triangles, prims);
        &mut prims[..kept]
    } else {
        prims
    };
    let n = prims.len();
    if n <= 1 {
        return leaf(prims, offset, bounds);
    }
    let split = if depth < MAX_SAH_DEPTH {
        sah_split(prims, &bounds, &centroids)
    } else {
        Sah::default()
    };
    let can_be_leaf = n <= MAX_LEAF;
    if can_be_leaf && (split.leaf_is_cheaper || split.best.is_none()) {
        return leaf(prims, offset, bounds);
    }
    let mid = match split.best {
        Some((axis, bin, scale)) => {
            let lo = centroids.min[axis];
            partition(prims, |p| bin_of(p.centroid[axis], lo, scale) <= bin)
        }
        None => 0,
    };
    let mid = if mid == 0 || mid == n {
        // No SAH split (too deep, or all centroids in one place): halve at the median centroid
        // of the longest axis, which for coincident centroids is any half.
        let axis = centroids.extent().max_position();
        let mid = n / 2;
        prims.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        mid
    } else {
        mid
    };
    let (left, right) = prims.split_at_mut(mid);
    let (a, b) = if n >= PARALLEL_MIN {
        rayon::join(
            || build_node(triangles, left, offset, depth + 1),
            || build_node(triangles, right, offset + mid, depth + 1),
        )
    } else {
        (
            build_node(triangles, left, offset, depth + 1),
            build_node(triangles, right, offset + mid, depth + 1),
        )
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([a, b]),
    }
}

/// The outcome of binning a node.
#[derive(Clone, Copy, Default)]
struct Sah {
    /// The cheapest split: axis, last bin on the left, bin scale.
    best: Option<(usize, usize, f32)>,
    /// Whether a leaf costs less than that split.
    leaf_is_cheaper: bool,
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// The cheapest binned SAH split, and whether keeping the node whole is cheaper still. No
/// split when the centroids have no extent to bin.
fn sah_split(prims: &[Prim], bounds: &Aabb, centroids: &Aabb) -> Sah {
    let extent = centroids.extent();
    let scale = Vec3::from_array(extent.to_array().map(|e| {
        if e > 0.0 {
            BINS as f32 * (1.0 - 1e-6) / e
        } else {
            0.0
        }
    }));
    if scale == Vec3::ZERO || !scale.is_finite() {
        return Sah::default();
    }
    let mut counts = [[0u32; BINS]; 3];
    let mut boxes = [[Aabb::EMPTY; BINS]; 3];
    for p in prims {
        for axis in 0..3 {
            let b = bin_of(p.centroid[axis], centroids.min[axis], scale[axis]);
            counts[axis][b] += 1;
            boxes[axis][b].grow(&p.bounds);
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if scale[axis] == 0.0 {
            continue;
        }
        // Right-to-left sweep: area × count of everything right of each boundary.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for b in (1..BINS).rev() {
            acc.grow(&boxes[axis][b]);
            count += counts[axis][b];
            right_cost[b] = acc.half_area() * count as f32;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0u32;
        for b in 0..BINS - 1 {
            acc.grow(&boxes[axis][b]);
            count += counts[axis][b];
            if count == 0 || count as usize == prims.len() {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_cost[b + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    let leaf_cost = COST_LEAF_TRIANGLE * prims.len() as f32;
    match best {
        Some((cost, axis, bin)) => Sah {
            best: Some((axis, bin, scale[axis])),
            leaf_is_cheaper: leaf_cost <= COST_TRAVERSAL + COST_LEAF_TRIANGLE * cost / area,
        },
        None => Sah::default(),
    }
}

/// Moves the items satisfying `left` to the front; returns how many there are.
fn partition(prims: &mut [Prim], left: impl Fn(&Prim) -> bool) -> usize {
    let mut i = 0;
    let mut j = prims.len();
    while i < j {
        if left(&prims[i]) {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    i
}
