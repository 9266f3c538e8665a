//! The fast path: an 8-wide BVH collapsed from the binary one, with triangles in 8-wide
//! packets, traversed with the single-ray [`super::kernels`] — and the flat packet list that
//! beats any tree on a scene as small as the Cornell box.
//!
//! A child reference is a `u32`: a node index, or [`LEAF`] | packet index (a leaf is exactly one
//! packet of up to eight triangles), or [`EMPTY`].
//!
//! Closest-hit traversal visits children front to back (a small sorted stack) and skips boxes
//! beyond the best hit; shadow rays stop at the first hit. Ties at the same `t` go to the lowest
//! triangle index, so results equal the brute-force loop's exactly.

use glam::Vec3;

use crate::base::geometry::{Ray, Triangle};

use super::bvh::{BOX_T_SLACK, Bvh};
use super::kernels;
use super::set::InstructionSet;
use super::simd::{LANES, LaneHit, Node8, Packet8, Packet16, RayK};
use super::{Hit, TraversalCost};

pub const LEAF: u32 = 1 << 31;
pub const EMPTY: u32 = u32::MAX;

/// Stack entries that fit in the fixed-size traversal stack; deeper trees use a heap one.
pub(super) const STACK_INLINE: usize = 64;
/// The stack of shallow trees.
const STACK_SMALL: usize = 24;

impl Node8 {
    const fn empty() -> Self {
        Self {
            bounds: [
                [f32::INFINITY; LANES],
                [f32::INFINITY; LANES],
                [f32::INFINITY; LANES],
                [f32::NEG_INFINITY; LANES],
                [f32::NEG_INFINITY; LANES],
                [f32::NEG_INFINITY; LANES],
            ],
            child: [EMPTY; LANES],
        }
    }
}

/// Packs triangles `indices` (at most eight, in ascending order) into a packet.
pub fn packet(triangles: &[Triangle], indices: &[u32]) -> Packet8 {
    Packet8::new(triangles, indices)
}

/// Every triangle in packets, in index order: the SIMD brute-force loop. Kept both 8 and 16
/// wide (a small scene: the copies cost nothing), for the AVX2 and the AVX-512 kernels.
#[derive(Clone, Debug, Default)]
pub struct Flat {
    pub packets: Vec<Packet8>,
    pub packets16: Vec<Packet16>,
    /// The triangles' corners, sixteen a group in list order: what a batch's [`super::cull::Cone`] is
    /// checked against ([`super::cull::kept`]).
    pub corners: Vec<Corners>,
    /// Triangles in the list.
    pub count: usize,
}

/// The most triangles a list may hold to be culled per batch: what a batch keeps is a bit a
/// triangle in a `u64` ([`super::cull::kept`]).
pub const CULL_MAX_TRIANGLES: usize = 64;

/// A triangle's size for [`super::cull::Cone::may_hit`]: its longest edge extent along an axis.
pub fn triangle_size(v0: Vec3, v1: Vec3, v2: Vec3) -> f32 {
    (v1 - v0)
        .abs()
        .max_element()
        .max((v2 - v0).abs().max_element())
}

/// The corners of up to sixteen triangles, structure of arrays (corner, axis, lane), and their
/// sizes: what `Cone::may_hit_lanes` ([`super::cull`]) tests a lane at a time.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Corners {
    pub at: [[[f32; 16]; 3]; 3],
    pub size: [f32; 16],
}

impl Corners {
    /// The corners of `triangles` (at most sixteen); unused lanes repeat the last.
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        debug_assert!(!triangles.is_empty() && triangles.len() <= 16);
        let mut c = Corners {
            at: [[[0.0; 16]; 3]; 3],
            size: [0.0; 16],
        };
        for lane in 0..16 {
            let t = triangles[lane.min(triangles.len() - 1)];
            for (corner, v) in t.iter().enumerate() {
                for axis in 0..3 {
                    c.at[corner][axis][lane] = v[axis];
                }
            }
            c.size[lane] = triangle_size(t[0], t[1], t[2]);
        }
        c
    }
}

impl Flat {
    pub fn build(triangles: &[Triangle]) -> Self {
        let indices: Vec<u32> = (0..triangles.len() as u32).collect();
        Self::of(triangles, &indices)
    }

    /// The triangles `indices` (ascending) only.
    pub fn of(triangles: &[Triangle], indices: &[u32]) -> Self {
        Self {
            packets: indices
                .chunks(LANES)
                .map(|c| Packet8::new(triangles, c))
                .collect(),
            packets16: indices
                .chunks(16)
                .map(|c| Packet16::new(triangles, c))
                .collect(),
            corners: indices
                .chunks(16)
                .map(|c| {
                    let corners: Vec<[Vec3; 3]> = c
                        .iter()
                        .map(|&i| {
                            let t = &triangles[i as usize];
                            [t.v0, t.v1, t.v2]
                        })
                        .collect();
                    Corners::new(&corners)
                })
                .collect(),
            count: indices.len(),
        }
    }

    /// How many triangles the list holds: what every closest-hit query tests (the loop skips
    /// none, whatever it has found).
    pub fn triangle_count(&self) -> u32 {
        self.packets.iter().map(|p| real_triangles(&p.index)).sum()
    }

    /// Whether the list is short enough to be culled per batch.
    pub fn cullable(&self) -> bool {
        self.count <= CULL_MAX_TRIANGLES
    }

    /// One ray's closest hit, lowest index among equal `t`: every packet at the set's width
    /// (sixteen triangles a packet for AVX-512, eight otherwise).
    #[inline(always)]
    pub fn closest<S: InstructionSet>(&self, k: S, r: &RayK, t_max: f32) -> Option<Hit> {
        // Packets and lanes are in index order and the first of equal hits wins, as in the
        // brute-force loop.
        if S::WIDTH == 16 {
            let (p, h) = kernels::nearest_among(k, &self.packets16, r, t_max)?;
            Some(scene_hit(&self.packets16[p].index, h))
        } else {
            let (p, h) = kernels::nearest_among(k, &self.packets, r, t_max)?;
            Some(scene_hit(&self.packets[p].index, h))
        }
    }

    /// Whether one ray hits anything: every packet at the set's width.
    #[inline(always)]
    pub fn occluded<S: InstructionSet>(&self, k: S, r: &RayK, t_max: f32) -> bool {
        // Plain loops, no closures: a closure is a function of its own, which the compiler may
        // leave out of line, compiled without the set's instructions.
        if S::WIDTH == 16 {
            for p in &self.packets16 {
                if kernels::any(k, p, r, t_max) {
                    return true;
                }
            }
        } else {
            for p in &self.packets {
                if kernels::any(k, p, r, t_max) {
                    return true;
                }
            }
        }
        false
    }
}

/// A packet's hit `h` as the scene's: its lane's triangle, from the packet's `index`.
#[inline(always)]
fn scene_hit<const N: usize>(index: &[u32; N], h: LaneHit) -> Hit {
    Hit {
        index: index[h.lane],
        t: h.t,
        u: h.u,
        v: h.v,
    }
}

/// How many of a packet's lanes hold a triangle (the others are [`Packet8::EMPTY`]'s padding).
pub fn real_triangles(index: &[u32]) -> u32 {
    index.iter().filter(|&&i| i != u32::MAX).count() as u32
}

/// What a traversal counts as it goes: nothing for rendering (`()`), its nodes and triangles
/// for the BVH-cost view ([`TraversalCost`]). One traversal serves both.
pub trait CountWork {
    fn node(&mut self);
    fn leaf(&mut self, index: &[u32]);
}

impl CountWork for () {
    #[inline(always)]
    fn node(&mut self) {}
    #[inline(always)]
    fn leaf(&mut self, _index: &[u32]) {}
}

impl CountWork for TraversalCost {
    #[inline(always)]
    fn node(&mut self) {
        self.nodes += 1;
    }
    #[inline(always)]
    fn leaf(&mut self, index: &[u32]) {
        self.triangles += real_triangles(index);
    }
}

/// A subtree of a binary [`Bvh`]: its root node, and the position of its first leaf among the
/// binary tree's leaves (in the order of [`Bvh::nodes`]).
#[derive(Clone, Copy, Debug)]
struct Subtree {
    index: usize,
    first_leaf: u32,
}

impl Subtree {
    /// The two children of an interior node. The left child's subtree is nodes
    /// `index + 1..right`, and a binary tree of `2k − 1` nodes has `k` leaves: so the right
    /// child's leaves start `(right − index) / 2` after the left child's.
    fn children(self, bvh: &Bvh) -> [Subtree; 2] {
        let right = bvh.nodes[self.index].first_or_right as usize;
        [
            Subtree {
                index: self.index + 1,
                first_leaf: self.first_leaf,
            },
            Subtree {
                index: right,
                first_leaf: self.first_leaf + ((right - self.index) / 2) as u32,
            },
        ]
    }
}

/// An 8-wide BVH.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    pub nodes: Vec<Node8>,
    pub packets: Vec<Packet8>,
    /// The root reference ([`EMPTY`] for an empty scene).
    pub root: u32,
    /// The most stack entries a traversal can need.
    pub max_stack: usize,
}

impl Default for Bvh8 {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            packets: Vec::new(),
            root: EMPTY,
            max_stack: 1,
        }
    }
}

impl Bvh8 {
    /// Collapses a binary BVH: each wide node takes its binary node's two children and keeps
    /// opening the interior child with the largest surface area until it has eight.
    pub fn from_binary(bvh: &Bvh, triangles: &[Triangle]) -> Self {
        Self::collapsed(bvh, triangles)
    }

    /// The collapse in two parts that run side by side: the wide nodes, on one thread (a
    /// small part of the work: ~68,000 nodes for the terrain's million triangles), and the
    /// packets, the bulk of the work and of the memory (a gather of every triangle), in
    /// parallel. They need not wait for each other because packet `i` is the binary tree's
    /// `i`-th leaf (in the order of [`Bvh::nodes`], depth first), which the nodes can name
    /// without the packets being made. Both come out the same whatever the number of threads.
    fn collapsed(bvh: &Bvh, triangles: &[Triangle]) -> Self {
        use rayon::prelude::*;
        if bvh.nodes.is_empty() {
            return Self::default();
        }
        let ((nodes, root, need), packets) = rayon::join(
            || {
                let mut nodes = Vec::with_capacity(bvh.nodes.len() / 4 + 1);
                let whole = Subtree {
                    index: 0,
                    first_leaf: 0,
                };
                let (root, need) = Self::collapse(bvh, whole, &mut nodes);
                (nodes, root, need)
            },
            || {
                let leaves: Vec<&super::bvh::Node> =
                    bvh.nodes.iter().filter(|n| n.is_leaf()).collect();
                leaves
                    .par_iter()
                    .map(|leaf| {
                        let ids = bvh.leaf_indices(leaf);
                        let mut sorted = [0u32; LANES];
                        let sorted = &mut sorted[..ids.len()];
                        sorted.copy_from_slice(ids);
                        sorted.sort_unstable();
                        packet(triangles, sorted)
                    })
                    .collect()
            },
        );
        Self {
            nodes,
            packets,
            root,
            max_stack: need + 1,
        }
    }

    /// Appends the wide nodes of binary subtree `sub` to `nodes`, depth first; returns the
    /// reference to its root (a leaf is a reference to its packet) and the stack entries its
    /// subtree needs.
    fn collapse(bvh: &Bvh, sub: Subtree, nodes: &mut Vec<Node8>) -> (u32, usize) {
        if bvh.nodes[sub.index].is_leaf() {
            return (LEAF | sub.first_leaf, 0);
        }
        // The children, with the area of each interior one (`None` for a leaf).
        let area = |s: Subtree| {
            let n = &bvh.nodes[s.index];
            (!n.is_leaf()).then(|| n.bounds.half_area())
        };
        let mut kids = [(sub, None); LANES];
        let mut len = 0;
        for s in sub.children(bvh) {
            kids[len] = (s, area(s));
            len += 1;
        }
        while len < LANES {
            let widest = kids[..len]
                .iter()
                .enumerate()
                .filter_map(|(slot, &(_, a))| a.map(|a| (slot, a)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(slot, _)| slot);
            let Some(slot) = widest else { break };
            let [a, b] = kids[slot].0.children(bvh);
            kids[slot] = (a, area(a));
            kids[len] = (b, area(b));
            len += 1;
        }
        let at = nodes.len();
        nodes.push(Node8::empty());
        let mut need = 0;
        for (slot, &(k, _)) in kids[..len].iter().enumerate() {
            let (reference, child_need) = Self::collapse(bvh, k, nodes);
            need = need.max(child_need);
            let b = bvh.nodes[k.index].bounds;
            let n = &mut nodes[at];
            for axis in 0..3 {
                n.bounds[axis][slot] = b.min[axis];
                n.bounds[axis + 3][slot] = b.max[axis];
            }
            n.child[slot] = reference;
        }
        (at as u32, need + len)
    }

    /// Asks the processor to start loading `item` (a node or a leaf's packet) into its cache,
    /// for a traversal that will visit it after others: incoherent rays through a large tree
    /// wait on memory more than they compute.
    #[inline(always)]
    fn prefetch(&self, item: u32) {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = item;
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let (start, bytes) = if item & LEAF != 0 {
                let p = self.packets.as_ptr().wrapping_add((item & !LEAF) as usize);
                (p.cast::<i8>(), std::mem::size_of::<Packet8>())
            } else {
                let n = self.nodes.as_ptr().wrapping_add(item as usize);
                (n.cast::<i8>(), std::mem::size_of::<Node8>())
            };
            for offset in (0..bytes).step_by(64) {
                // SAFETY: a prefetch is a hint: it never faults and reads nothing the program
                // sees, whatever the address.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
            }
        }
    }

    /// The closest hit `(triangle index, t)` with `t < t_max`, lowest index among ties.
    #[inline(always)]
    ///
    /// `best` is a hit found elsewhere (or `None`): the result is the better of it and the
    /// tree's closest hit.
    pub fn closest<K: InstructionSet>(
        &self,
        k: K,
        r: &RayK,
        t_max: f32,
        best: Option<Hit>,
    ) -> Option<Hit> {
        if self.root == EMPTY {
            return best;
        }
        // A stack on the stack, as small as the tree allows (it is cleared for every ray).
        if self.max_stack <= STACK_SMALL {
            let mut stack = [(0u32, 0f32); STACK_SMALL];
            self.closest_on(k, r, t_max, best, self.root, &mut stack, &mut ())
        } else if self.max_stack <= STACK_INLINE {
            let mut stack = [(0u32, 0f32); STACK_INLINE];
            self.closest_on(k, r, t_max, best, self.root, &mut stack, &mut ())
        } else {
            let mut stack = vec![(0u32, 0f32); self.max_stack];
            self.closest_on(k, r, t_max, best, self.root, &mut stack, &mut ())
        }
    }

    /// The closest-hit traversal of the subtree `start` (the root, or a node where a packet
    /// of rays leaves a ray to go on alone), counting its work into `count` (`()` counts
    /// nothing and compiles away; a [`TraversalCost`] counts, for the BVH-cost view).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn closest_on<K: InstructionSet, C: CountWork>(
        &self,
        k: K,
        r: &RayK,
        t_max: f32,
        best: Option<Hit>,
        start: u32,
        stack: &mut [(u32, f32)],
        count: &mut C,
    ) -> Option<Hit> {
        let (mut best_t, mut best_i, mut best_uv) = best
            .map_or((t_max, u32::MAX, (0.0, 0.0)), |h| {
                (h.t, h.index, (h.u, h.v))
            });
        let mut sp = 0;
        let mut item = start;
        'traversal: loop {
            if item & LEAF != 0 {
                let p = &self.packets[(item & !LEAF) as usize];
                count.leaf(&p.index);
                // Once there is a hit, candidates at its very distance count too (ties).
                let limit = if best_i == u32::MAX {
                    t_max
                } else {
                    best_t.next_up()
                };
                if let Some(h) = k.call(kernels::Nearest {
                    p,
                    r,
                    t_limit: limit,
                }) {
                    let i = p.index[h.lane];
                    if h.t < best_t || i < best_i {
                        best_t = h.t;
                        best_i = i;
                        best_uv = (h.u, h.v);
                    }
                }
            } else {
                let node = &self.nodes[item as usize];
                count.node();
                let (mut mask, t) = k.call(kernels::Boxes {
                    node,
                    r,
                    t_limit: best_t * BOX_T_SLACK,
                });
                if mask != 0 && mask & (mask - 1) == 0 {
                    // One child hit (the common case): go straight down.
                    item = node.child[mask.trailing_zeros() as usize];
                    continue;
                }
                // Push the hit children sorted so that the nearest is on top.
                let base = sp;
                while mask != 0 {
                    let slot = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let entry = (node.child[slot], t[slot]);
                    self.prefetch(entry.0);
                    let mut j = sp;
                    while j > base && stack[j - 1].1 < entry.1 {
                        stack[j] = stack[j - 1];
                        j -= 1;
                    }
                    stack[j] = entry;
                    sp += 1;
                }
            }
            // Next: the nearest pending child that may still hold a closer hit.
            loop {
                if sp == 0 {
                    break 'traversal;
                }
                sp -= 1;
                let (next, t_near) = stack[sp];
                if t_near <= best_t * BOX_T_SLACK {
                    item = next;
                    break;
                }
            }
        }
        (best_i != u32::MAX).then_some(Hit {
            index: best_i,
            t: best_t,
            u: best_uv.0,
            v: best_uv.1,
        })
    }

    /// [`Bvh8::closest`], counting its work into `cost`: the same traversal (`closest_on`)
    /// with the same kernels `k` (so the same box culling, bit for bit) and a counter that
    /// counts; the fast one is given `()`, which counts nothing and compiles away. The tests
    /// check that both return the same hit on every ray.
    ///
    /// What is counted, and why:
    /// * a node each time a wide node's eight child boxes are tested (one kernel call; the
    ///   empty slots are not counted apart, the kernel tests them in the same instruction);
    /// * the real triangles of each leaf packet tested: a leaf of 3 triangles counts 3, though
    ///   the 8-lane kernel computes all 8 lanes. That is the work the tree's shape decides
    ///   (a leaf with fewer triangles is cheaper in the SAH's eyes), where lanes would only
    ///   measure the packet width.
    ///
    /// Children whose boxes are skipped when popped (beyond the best hit) are not counted:
    /// the fast traversal never opens them.
    pub fn closest_counting<K: InstructionSet>(
        &self,
        k: K,
        r: &RayK,
        t_max: f32,
        best: Option<Hit>,
        cost: &mut TraversalCost,
    ) -> Option<Hit> {
        if self.root == EMPTY {
            return best;
        }
        let mut stack = vec![(0u32, 0f32); self.max_stack];
        self.closest_on(k, r, t_max, best, self.root, &mut stack, cost)
    }

    /// Whether any triangle is hit with `0 < t < t_max`; stops at the first.
    #[inline(always)]
    pub fn occluded<K: InstructionSet>(&self, k: K, r: &RayK, t_max: f32) -> bool {
        if self.root == EMPTY {
            return false;
        }
        if self.max_stack <= STACK_SMALL {
            let mut stack = [0u32; STACK_SMALL];
            self.occluded_on(k, r, t_max, self.root, &mut stack)
        } else if self.max_stack <= STACK_INLINE {
            let mut stack = [0u32; STACK_INLINE];
            self.occluded_on(k, r, t_max, self.root, &mut stack)
        } else {
            let mut stack = vec![0u32; self.max_stack];
            self.occluded_on(k, r, t_max, self.root, &mut stack)
        }
    }

    /// Whether anything in the subtree `start` is hit with `0 < t < t_max`.
    #[inline(always)]
    pub(super) fn occluded_on<K: InstructionSet>(
        &self,
        k: K,
        r: &RayK,
        t_max: f32,
        start: u32,
        stack: &mut [u32],
    ) -> bool {
        let box_limit = t_max * BOX_T_SLACK;
        let mut sp = 0;
        let mut item = start;
        loop {
            if item & LEAF != 0 {
                if k.call(kernels::Any {
                    p: &self.packets[(item & !LEAF) as usize],
                    r,
                    t_limit: t_max,
                }) {
                    return true;
                }
            } else {
                let node = &self.nodes[item as usize];
                let (mut mask, _) = k.call(kernels::Boxes {
                    node,
                    r,
                    t_limit: box_limit,
                });
                if mask != 0 {
                    // Descend into the first hit child, keep the others for later.
                    item = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack[sp] = node.child[mask.trailing_zeros() as usize];
                        sp += 1;
                        mask &= mask - 1;
                    }
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            item = stack[sp];
        }
    }

    /// Memory used by nodes and packets, in bytes.
    pub fn size_bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.packets.as_slice())
    }
}

/// The 8-wide BVH plus, apart, the few triangles that are large next to the whole scene (the
/// walls of the Cornell box): tested first in one flat packet, they give nearly every ray a
/// close bound before the tree is entered, and they no longer swell the tree's boxes.
#[derive(Clone, Debug, Default)]
pub struct Bvh8Big {
    pub big: Flat,
    pub tree: Bvh8,
}

/// At most this many triangles are set apart as large (one 16-wide packet).
pub const MAX_BIG: usize = 16;
/// A triangle is large when its box's surface area is at least this fraction of the scene's.
pub const BIG_AREA_FRACTION: f32 = 0.15;

impl Flat {
    /// One ray's closest hit with the kernels `k`. (No boxes: the ray needs no reciprocal
    /// direction.)
    #[inline(always)]
    pub fn closest_with<K: InstructionSet>(&self, k: K, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.closest(k, &RayK::for_triangles(ray), t_max)
    }

    /// Whether one ray hits anything, with the kernels `k`.
    #[inline(always)]
    pub fn occluded_with<K: InstructionSet>(&self, k: K, ray: &Ray, t_max: f32) -> bool {
        self.occluded(k, &RayK::for_triangles(ray), t_max)
    }
}

impl Bvh8Big {
    /// One ray's closest hit with the kernels `k`: the large triangles first (their hit bounds
    /// the tree's), then the tree.
    #[inline(always)]
    pub fn closest_with<K: InstructionSet>(&self, k: K, ray: &Ray, t_max: f32) -> Option<Hit> {
        let r = RayK::new(ray);
        let best = self.big.closest(k, &r, t_max);
        self.tree.closest(k.tree(), &r, t_max, best)
    }

    /// Whether one ray hits anything, with the kernels `k`: the tree first, then the large
    /// triangles.
    #[inline(always)]
    pub fn occluded_with<K: InstructionSet>(&self, k: K, ray: &Ray, t_max: f32) -> bool {
        let r = RayK::new(ray);
        self.tree.occluded(k.tree(), &r, t_max) || self.big.occluded(k, &r, t_max)
    }

    pub fn build(triangles: &[Triangle]) -> Self {
        let (bvh, big) = Bvh::build_apart(triangles, MAX_BIG, BIG_AREA_FRACTION);
        let tree = Bvh8::collapsed(&bvh, triangles);
        Self {
            big: Flat::of(triangles, &big),
            tree,
        }
    }
}
