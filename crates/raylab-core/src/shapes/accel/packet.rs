//! Coherent rays together: a packet of rays through the 8-wide BVH, one SIMD lane a ray —
//! sixteen rays with AVX-512, eight with AVX2 and the portable set.
//!
//! Camera rays through neighbouring pixels, and the shadow rays from their hits towards the
//! point light, meet the same nodes in the same order. Ray by ray, each of them loads a node's
//! eight boxes and tests them eight lanes wide. As a packet, the node is loaded once and each
//! child box is tested against all the packet's rays in one step: for a node every ray of the
//! packet enters, far fewer instructions (PERFORMANCE.md, "Design choices and what each buys", gives what it
//! buys).
//!
//! The traversal is written once, generic over [`InstructionSet`]: the lane width, a lane type
//! with the arithmetic, comparisons and masks of [`crate::base::lanes`] (`Real`, `Mask`), and the
//! few operations a packet needs beyond (loads and stores of lanes, a masked horizontal
//! minimum, the gather of the rays), implemented by the AVX-512 and the AVX2 kernel proof
//! types (in [`super::x86_lanes`]) and by the portable set ([`super::portable`]). Every
//! function of it is `#[inline(always)]`, so it is compiled inside each set's entry points
//! ([`InstructionSet::call`]), where the intrinsics inline.
//!
//! Each lane computes exactly what [`super::kernels::boxes`] computes for its ray (the
//! same planes, the same [`InstructionSet::plane_distance`], the same order of `max` and `min`), against
//! its own best hit; leaves are tested a triangle at a time against every lane by the single
//! ray's triangle test itself ([`crate::shapes::intersect::intersect_lanes`], a lane per ray), with
//! the same rule for ties. So a packet returns exactly what each ray returns alone (tests/packets.rs checks
//! it against the brute-force loop), whatever order the packet visits the nodes in.
//!
//! When few rays of a packet are left in a subtree (they diverged, or most of them found
//! nearer hits), each goes on alone from that node with the single-ray traversal: a packet's
//! step costs the same for one ray as for all of them. Rays that point in very different
//! directions (the path tracer's bounces) never form a packet: see [`coherent`].

use glam::Vec3;

use super::Hit;
use super::bvh::BOX_T_SLACK;
use super::bvh::INV_HUGE;
use super::set::{InstructionSet, MAX_WIDTH};
use super::simd::{Node8, Packet, Packet16, RayK};
use super::wide::{Bvh8, Bvh8Big, EMPTY, LEAF, STACK_INLINE};
use crate::base::geometry::Ray;
use crate::base::lanes::{Mask, Real, Vec3x, Vector};
use crate::shapes::intersect::intersect_lanes_giving_up;

/// A ray is six `f32` (origin, direction): lane i gathers floats 6i + c.
pub(super) const RAY_FLOATS: i32 = (size_of::<Ray>() / size_of::<f32>()) as i32;
const _: () = assert!(RAY_FLOATS == 6 && align_of::<Ray>() == align_of::<f32>());
const _: () = assert!(std::mem::offset_of!(Ray, direction) == 12);
/// A shadow ray and its `t_max` are seven `f32`, the ray's six first: lane i gathers 7i + c.
pub(super) const SEGMENT_FLOATS: i32 = (size_of::<(Ray, f32)>() / size_of::<f32>()) as i32;
const _: () = assert!(
    SEGMENT_FLOATS == 7
        && std::mem::offset_of!((Ray, f32), 0) == 0
        && std::mem::offset_of!((Ray, f32), 1) == 24
);

/// A packet with at most this many rays left in a subtree lets each go on alone: below it a
/// packet's shared node loads no longer pay for its masks. Small values (1, 2, 4) trace the
/// bunny and terrain equally fast; 2 sits between.
const ALONE: u32 = 2;

/// Directions within about 18° of the first ray's (cosine 0.95) travel together.
const COHERENT_COS: f32 = 0.95;

/// Stack entries of a packet traversal: a tree whose single-ray traversal needs at most
/// [`STACK_INLINE`] ([`Bvh8::max_stack`]) needs no more as a packet, since at every node both
/// push at most the children they enter and pop one before going on; deeper trees are traced
/// ray by ray.
const STACK: usize = STACK_INLINE;

/// Whether `rays` point nearly the same way, so that they are worth tracing as a packet:
/// every direction within about 18° of the first (directions are unit vectors).
pub fn coherent(rays: &[Ray]) -> bool {
    directions_agree(rays.iter().map(|r| r.direction))
}

/// [`coherent`] for shadow rays (each with its `t_max`).
pub fn coherent_shadows(rays: &[(Ray, f32)]) -> bool {
    directions_agree(rays.iter().map(|(r, _)| r.direction))
}

/// More than [`ALONE`] directions, each within [`COHERENT_COS`] of the first.
fn directions_agree(mut directions: impl ExactSizeIterator<Item = glam::Vec3>) -> bool {
    let n = directions.len();
    let Some(first) = directions.next() else {
        return false;
    };
    n > ALONE as usize && directions.all(|d| d.dot(first) >= COHERENT_COS)
}

/// The packet's rays, one per lane: what the box test needs (as in [`RayK`]).
struct Lanes<P: InstructionSet> {
    k: P,
    origin: [P::F; 3],
    direction: [P::F; 3],
    inv: [P::F; 3],
    origin_inv: [P::F; 3],
    /// Per axis, the lanes whose ray goes towards negative coordinates (near plane = max).
    negative: [P::Mask; 3],
}

impl<P: InstructionSet> Lanes<P> {
    /// The rays' origins and directions, one lane each (lanes past `rays.len()` repeat the
    /// last ray and are never active), and what the box test needs, computed as
    /// [`RayK::new`] computes it, a packet at a time: the same divisions, so the same bits.
    #[inline(always)]
    fn new(k: P, rays: &[Ray]) -> Self {
        let [ox, oy, oz, dx, dy, dz] = k.rays(rays);
        let (x, y, z) = (axis(k, ox, dx), axis(k, oy, dy), axis(k, oz, dz));
        let origin = [ox, oy, oz];
        let direction = [dx, dy, dz];
        let inv = [x.0, y.0, z.0];
        let origin_inv = [x.1, y.1, z.1];
        let negative = [x.2, y.2, z.2];
        Self {
            k,
            origin,
            direction,
            inv,
            origin_inv,
            negative,
        }
    }

    /// Lanes for the triangle tests alone (origins and directions as gathered), without what
    /// the box test needs: its divisions would be wasted on a list of triangles.
    #[inline(always)]
    fn for_triangles(k: P, [ox, oy, oz, dx, dy, dz]: [P::F; 6]) -> Self {
        let zero = k.splat(0.0);
        let none = P::Mask::from_bitmask(0);
        Self {
            k,
            origin: [ox, oy, oz],
            direction: [dx, dy, dz],
            inv: [zero; 3],
            origin_inv: [zero; 3],
            negative: [none; 3],
        }
    }

    /// Child `slot`'s box against the lanes of `active`, each up to its own `limit`: the lanes
    /// that enter it (as [`kernels::boxes`] decides for each ray alone) and the nearest of
    /// their entry distances.
    ///
    /// [`kernels::boxes`]: super::kernels::boxes
    #[inline(always)]
    fn enter(&self, node: &Node8, slot: usize, active: P::Mask, limit: P::F) -> (u32, f32) {
        let k = self.k;
        let mut t0 = k.splat(0.0);
        let mut t1 = limit;
        for axis in 0..3 {
            let min = k.splat(node.bounds[axis][slot]);
            let max = k.splat(node.bounds[axis + 3][slot]);
            let near_plane = P::F::select(self.negative[axis], max, min);
            let far_plane = P::F::select(self.negative[axis], min, max);
            let (o, inv, o_inv) = (self.origin[axis], self.inv[axis], self.origin_inv[axis]);
            let near = k.plane_distance(near_plane, o, inv, o_inv);
            let far = k.plane_distance(far_plane, o, inv, o_inv);
            t0 = t0.max_or_other(near);
            t1 = t1.min_or_other(far);
        }
        let entered = active & t0.simd_le(t1);
        let bits = entered.bitmask();
        if bits == 0 {
            return (0, 0.0);
        }
        (bits, k.min_of(entered, t0))
    }

    /// Triangle `tri` of a leaf against every lane: `t`, `u`, `v` per lane (meaningless where
    /// missed) and the lanes of `active` that hit it with `0 < t < limit`:
    /// [`intersect_lanes`], a lane per ray, so each lane has the single ray's bits.
    #[inline(always)]
    fn triangle<T: PacketTriangle>(
        &self,
        p: &T,
        tri: usize,
        active: P::Mask,
        limit: P::F,
    ) -> ([P::F; 3], P::Mask) {
        self.triangle_or_give_up(p, tri, active, limit, false)
    }

    /// [`Lanes::triangle`], giving up before `u` and `v` where `give_up` is set and no lane's
    /// `t` is in range ([`intersect_lanes_giving_up`]).
    #[inline(always)]
    fn triangle_or_give_up<T: PacketTriangle>(
        &self,
        p: &T,
        tri: usize,
        active: P::Mask,
        limit: P::F,
        give_up: bool,
    ) -> ([P::F; 3], P::Mask) {
        let [v0, e1, e2, n] = p.corner_edges_normal(tri);
        let [ox, oy, oz] = self.origin;
        let [dx, dy, dz] = self.direction;
        let h = intersect_lanes_giving_up(
            Vec3x::new(ox, oy, oz),
            Vec3x::new(dx, dy, dz),
            Vec3x::splat(v0),
            Vec3x::splat(e1),
            Vec3x::splat(e2),
            Vec3x::splat(n),
            limit,
            give_up,
        );
        ([h.t, h.u, h.v], active & h.hit)
    }

    /// A leaf's triangles against the `active` lanes, one triangle at a time: each lane keeps
    /// the nearest hit, the lowest triangle index among equal `t` (as the brute-force loop).
    #[inline(always)]
    fn leaf_nearest<const N: usize>(&self, p: &Packet<N>, active: u32, b: &mut Best, t_max: f32) {
        let triangles = (0..N)
            .filter(|&tri| p.index[tri] != u32::MAX)
            .map(|tri| (p, tri));
        self.nearest_among(triangles, active, b, t_max);
    }

    /// [`Lanes::leaf_nearest`] over any triangles, each a lane `tri` of a packet `p` (unused
    /// lanes left out): a leaf's, or those of a list that a batch's cone keeps
    /// ([`closest_in_list`]), read where they lie, not copied.
    #[inline(always)]
    fn nearest_among<'p, T: PacketTriangle + 'p>(
        &self,
        triangles: impl Iterator<Item = (&'p T, usize)>,
        active: u32,
        b: &mut Best,
        t_max: f32,
    ) {
        let k = self.k;
        let limit = k.splat(t_max);
        let active = P::Mask::from_bitmask(active);
        let mut best_t = k.load(&b.t);
        let mut best_i = k.load_u32(&b.index);
        let mut best_u = k.load(&b.u);
        let mut best_v = k.load(&b.v);
        for (p, tri) in triangles {
            let ([t, u, v], hit) = self.triangle(p, tri, active, limit);
            if hit.bitmask() == 0 {
                continue;
            }
            let index_v = k.splat_u32(p.index(tri));
            // Nearer, or as near with a lower index (a lane without a hit has best_t = t_max,
            // which no hit reaches, so the index test only ever compares real hits).
            let nearer = hit & t.simd_lt(best_t);
            let tie = hit & t.simd_eq(best_t);
            let tie = tie & k.lt_u32(index_v, best_i);
            let better = nearer | tie;
            best_t = P::F::select(better, t, best_t);
            best_i = k.blend_u32(better, best_i, index_v);
            best_u = P::F::select(better, u, best_u);
            best_v = P::F::select(better, v, best_v);
        }
        k.store(&mut b.t, best_t);
        k.store_u32(&mut b.index, best_i);
        k.store(&mut b.u, best_u);
        k.store(&mut b.v, best_v);
    }

    /// The lanes of `active` that hit any triangle of a leaf with `0 < t < limit` (per lane).
    /// A packet's rays are alike, so each triangle is given up as soon as none meets its
    /// plane within its segment, before the rest of its test.
    #[inline(always)]
    fn leaf_any<const N: usize>(&self, p: &Packet<N>, active: u32, limit: P::F) -> u32 {
        let triangles = (0..N)
            .filter(|&tri| p.index[tri] != u32::MAX)
            .map(|tri| (p, tri));
        self.any_among(triangles, active, limit, true)
    }

    /// [`Lanes::leaf_any`] over any triangles (see [`Lanes::nearest_among`]).
    #[inline(always)]
    fn any_among<'p, T: PacketTriangle + 'p>(
        &self,
        triangles: impl Iterator<Item = (&'p T, usize)>,
        active: u32,
        limit: P::F,
        give_up: bool,
    ) -> u32 {
        // The lanes not yet blocked, as bits and as a mask.
        let mut left = active;
        let mut left_mask = P::Mask::from_bitmask(left);
        for (p, tri) in triangles {
            if left == 0 {
                break;
            }
            let blocked = (self
                .triangle_or_give_up(p, tri, left_mask, limit, give_up)
                .1)
                .bitmask();
            if blocked != 0 {
                left &= !blocked;
                left_mask = P::Mask::from_bitmask(left);
            }
        }
        active & !left
    }
}

/// A triangle of a packet, by its lane: what [`Lanes::triangle`] tests it with.
trait PacketTriangle {
    /// Lane `tri`'s `v0`, `e1`, `e2` and normal `n = e1 × e2`: stored by [`Packet16`] (the
    /// flat list's), computed for the BVH's leaves by the same expression, so the same bits
    /// (a cross product less per triangle and packet of rays where it is stored).
    fn corner_edges_normal(&self, tri: usize) -> [Vec3; 4];
    /// Lane `tri`'s triangle index.
    fn index(&self, tri: usize) -> u32;
}

/// Lane `tri` of rows of x, y and z.
#[inline(always)]
fn lane<const N: usize>(rows: &[[f32; N]; 3], tri: usize) -> Vec3 {
    Vec3::new(rows[0][tri], rows[1][tri], rows[2][tri])
}

impl<const N: usize> PacketTriangle for Packet<N> {
    #[inline(always)]
    fn corner_edges_normal(&self, tri: usize) -> [Vec3; 4] {
        let (e1, e2) = (lane(&self.e1, tri), lane(&self.e2, tri));
        [lane(&self.v0, tri), e1, e2, e1.cross(e2)]
    }
    #[inline(always)]
    fn index(&self, tri: usize) -> u32 {
        self.index[tri]
    }
}

impl PacketTriangle for Packet16 {
    #[inline(always)]
    fn corner_edges_normal(&self, tri: usize) -> [Vec3; 4] {
        let p = &self.triangles;
        [
            lane(&p.v0, tri),
            lane(&p.e1, tri),
            lane(&p.e2, tri),
            lane(&self.n, tri),
        ]
    }
    #[inline(always)]
    fn index(&self, tri: usize) -> u32 {
        self.triangles.index[tri]
    }
}

/// Along one axis, from the origins `o` and directions `d`: the reciprocal direction as
/// `RayBoxData::new` computes it (1/d, or ±INV_HUGE where |d| ≤ 1/INV_HUGE), origin times it,
/// and the lanes going towards negative coordinates.
#[inline(always)]
fn axis<P: InstructionSet>(k: P, o: P::F, d: P::F) -> (P::F, P::F, P::Mask) {
    let huge = k.splat(INV_HUGE).copysign(d);
    let small = d.abs().simd_ngt(k.splat(1.0 / INV_HUGE));
    let inv = P::F::select(small, huge, k.splat(1.0) / d);
    (inv, o * inv, inv.simd_lt(k.splat(0.0)))
}

/// The lanes set in `mask`, lowest first.
#[inline(always)]
fn lanes_of(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

/// All of the first `n` lanes.
fn first_lanes(n: usize) -> u32 {
    ((1u64 << n) - 1) as u32
}

/// Each lane's best hit so far, as the single-ray traversal keeps it (the first
/// [`InstructionSet::WIDTH`] entries): the lanes a closest-hit query hands back
/// ([`super::HitLanes`]).
use super::HitLanes as Best;

impl Best {
    /// Each lane's box limit: its best `t` with the boxes' slack.
    #[inline(always)]
    fn box_limit<P: InstructionSet>(&self, k: P) -> P::F {
        k.load(&self.t) * k.splat(BOX_T_SLACK)
    }
}

impl Bvh8Big {
    /// [`Bvh8Big`]'s closest hits for up to [`InstructionSet::WIDTH`] rays at once, `out[i]` for
    /// `rays[i]`: the large triangles first (a triangle at a time against every ray), then the
    /// tree.
    #[inline(always)]
    pub(super) fn closest_packet<P: InstructionSet>(
        &self,
        k: P,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        debug_assert!(!rays.is_empty() && rays.len() <= P::WIDTH && rays.len() == out.len());
        let lanes = Lanes::new(k, rays);
        let all = first_lanes(rays.len());
        let mut b = Best::new(t_max);
        for p in &self.big.packets16 {
            lanes.leaf_nearest(&p.triangles, all, &mut b, t_max);
        }
        self.tree.closest_lanes(&lanes, rays, all, t_max, &mut b);
        for (lane, hit) in out.iter_mut().enumerate() {
            *hit = b.get(lane);
        }
    }

    /// [`Bvh8Big`]'s any-hit queries for up to [`InstructionSet::WIDTH`] rays at once, each with
    /// its own `t_max`: `blocked[i]` for `rays[i]`.
    #[inline(always)]
    pub(super) fn occluded_packet<P: InstructionSet>(
        &self,
        k: P,
        rays: &[(Ray, f32)],
        blocked: &mut [bool],
    ) {
        debug_assert!(!rays.is_empty() && rays.len() <= P::WIDTH && rays.len() == blocked.len());
        let mut only = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); MAX_WIDTH];
        let mut t_max = [0.0f32; MAX_WIDTH];
        for (lane, (ray, t)) in rays.iter().enumerate() {
            only[lane] = *ray;
            t_max[lane] = *t;
        }
        let only = &only[..rays.len()];
        let lanes = Lanes::new(k, only);
        let all = first_lanes(rays.len());
        let mut done = self.tree.occluded_lanes(&lanes, only, all, &t_max);
        let limit = k.load(&t_max);
        for p in &self.big.packets16 {
            if done == all {
                break;
            }
            done |= lanes.leaf_any(&p.triangles, all & !done, limit);
        }
        for (lane, out) in blocked.iter_mut().enumerate() {
            *out = done & (1 << lane) != 0;
        }
    }
}

/// Closest hits of up to [`InstructionSet::WIDTH`] rays against the triangles `kept` (bit `i` for
/// the triangle in lane `i % 16` of `packets[i / 16]`: the flat list, culled for a batch by
/// its cone, [`super::cull`]), a triangle at a time against every ray: `out[i]` for
/// `rays[i]`, as the brute-force loop finds it (lowest index among equal `t`). With a few
/// triangles this beats a ray at a time, whose sixteen-lane minimum and lane extraction are a
/// chain of dependent steps per ray.
#[inline(always)]
pub(super) fn closest_in_list<P: InstructionSet>(
    k: P,
    packets: &[Packet16],
    kept: u64,
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<Hit>],
) {
    debug_assert!(!rays.is_empty() && rays.len() <= P::WIDTH && rays.len() == out.len());
    let mut b = Best::new(t_max);
    nearest_in_list(k, packets, kept, rays, t_max, &mut b);
    for (lane, hit) in out.iter_mut().enumerate() {
        *hit = b.get(lane);
    }
}

/// [`closest_in_list`] into lanes: lane `i` of `out` (made [`HitLanes::new`] by the caller) is
/// `rays[i]`'s hit.
#[inline(always)]
pub(super) fn nearest_in_list<P: InstructionSet>(
    k: P,
    packets: &[Packet16],
    kept: u64,
    rays: &[Ray],
    t_max: f32,
    out: &mut Best,
) {
    debug_assert!(!rays.is_empty() && rays.len() <= P::WIDTH);
    let lanes = Lanes::for_triangles(k, k.rays(rays));
    let all = first_lanes(rays.len());
    lanes.nearest_among(kept_triangles(packets, kept), all, out, t_max);
}

/// Any-hit queries of up to [`InstructionSet::WIDTH`] rays, each with its own `t_max`, against the
/// triangles `kept` of `packets`, a triangle at a time (see [`closest_in_list`]).
#[inline(always)]
pub(super) fn occluded_in_list<P: InstructionSet>(
    k: P,
    packets: &[Packet16],
    kept: u64,
    rays: &[(Ray, f32)],
    blocked: &mut [bool],
) {
    debug_assert!(!rays.is_empty() && rays.len() <= P::WIDTH && rays.len() == blocked.len());
    let [ox, oy, oz, dx, dy, dz, limit] = k.segments(rays);
    let lanes = Lanes::for_triangles(k, [ox, oy, oz, dx, dy, dz]);
    let all = first_lanes(rays.len());
    let done = lanes.any_among(kept_triangles(packets, kept), all, limit, true);
    for (lane, out) in blocked.iter_mut().enumerate() {
        *out = done & (1 << lane) != 0;
    }
}

/// [`occluded_in_list`] for the cast lanes of a group of shadow rays given as lanes: bit `i`
/// set where lane `i` is cast and blocked. The lanes are loaded as they are; nothing is copied
/// into an array of rays. `give_up`: each triangle is given up as soon as no lane meets its
/// plane within its segment ([`Lanes::triangle_or_give_up`]), worth it where the lanes are
/// alike.
#[inline(always)]
pub(super) fn occluded_lanes_in_list<P: InstructionSet>(
    k: P,
    packets: &[Packet16],
    kept: u64,
    g: &super::SegmentLanes,
    give_up: bool,
) -> u16 {
    let mut blocked = 0u16;
    for offset in (0..16).step_by(P::WIDTH) {
        let active = (u32::from(g.cast) >> offset) & ((1 << P::WIDTH) - 1);
        if active == 0 {
            continue;
        }
        let lanes = Lanes::for_triangles(
            k,
            [
                load_at(k, g.origin[0], offset),
                load_at(k, g.origin[1], offset),
                load_at(k, g.origin[2], offset),
                load_at(k, g.direction[0], offset),
                load_at(k, g.direction[1], offset),
                load_at(k, g.direction[2], offset),
            ],
        );
        let limit = load_at(k, g.t_max, offset);
        let done = lanes.any_among(kept_triangles(packets, kept), active, limit, give_up);
        blocked |= (done << offset) as u16;
    }
    blocked
}

/// Lanes `offset..offset + WIDTH` of `a`.
#[inline(always)]
fn load_at<P: InstructionSet>(k: P, a: &[f32; 16], offset: usize) -> P::F {
    if offset == 0 {
        return k.load(a);
    }
    let mut row = [0.0f32; MAX_WIDTH];
    row[..P::WIDTH].copy_from_slice(&a[offset..offset + P::WIDTH]);
    k.load(&row)
}

/// The triangles of `kept` as (packet, lane), in index order.
#[inline(always)]
fn kept_triangles(packets: &[Packet16], mut kept: u64) -> impl Iterator<Item = (&Packet16, usize)> {
    std::iter::from_fn(move || {
        (kept != 0).then(|| {
            let i = kept.trailing_zeros() as usize;
            kept &= kept - 1;
            (&packets[i / 16], i % 16)
        })
    })
}

impl Bvh8 {
    /// The closest-hit traversal of a packet: lanes `active` of `lanes` (made of `rays`),
    /// each keeping its best hit in `b`.
    #[inline(always)]
    fn closest_lanes<P: InstructionSet>(
        &self,
        lanes: &Lanes<P>,
        rays: &[Ray],
        active: u32,
        t_max: f32,
        b: &mut Best,
    ) {
        if self.root == EMPTY {
            return;
        }
        let k = lanes.k;
        let k8 = k.tree();
        if self.max_stack > STACK_INLINE {
            for lane in lanes_of(active) {
                if let Some(h) = self.closest(k8, &RayK::new(&rays[lane]), t_max, b.get(lane)) {
                    b.set(lane, Some(h));
                }
            }
            return;
        }
        let mut stack = [(0u32, 0u32, 0f32); STACK];
        let mut alone = [(0u32, 0f32); STACK_INLINE];
        let mut sp = 0;
        let mut item = self.root;
        let mut active = active;
        'traversal: loop {
            if active.count_ones() <= ALONE {
                for lane in lanes_of(active) {
                    let r = RayK::new(&rays[lane]);
                    let found =
                        self.closest_on(k8, &r, t_max, b.get(lane), item, &mut alone, &mut ());
                    if let Some(h) = found {
                        b.set(lane, Some(h));
                    }
                }
            } else if item & LEAF != 0 {
                lanes.leaf_nearest(&self.packets[(item & !LEAF) as usize], active, b, t_max);
            } else {
                let node = &self.nodes[item as usize];
                let limit = b.box_limit(k);
                let active_mask = P::Mask::from_bitmask(active);
                // Push the entered children sorted so that the nearest is on top.
                let base = sp;
                for slot in 0..node.child.len() {
                    let child = node.child[slot];
                    if child == EMPTY {
                        break; // a node's children fill its first slots
                    }
                    let (entered, t_near) = lanes.enter(node, slot, active_mask, limit);
                    if entered == 0 {
                        continue;
                    }
                    let mut j = sp;
                    while j > base && stack[j - 1].2 < t_near {
                        stack[j] = stack[j - 1];
                        j -= 1;
                    }
                    stack[j] = (child, entered, t_near);
                    sp += 1;
                }
            }
            // Next: the nearest pending child, with the lanes that may still find a nearer hit
            // in it.
            loop {
                if sp == 0 {
                    break 'traversal;
                }
                sp -= 1;
                let (next, entered, t_near) = stack[sp];
                let still = entered & b.box_limit(k).simd_ge(k.splat(t_near)).bitmask();
                if still != 0 {
                    item = next;
                    active = still;
                    break;
                }
            }
        }
    }

    /// The any-hit traversal of a packet: the lanes of `active` blocked before their `t_max`.
    #[inline(always)]
    fn occluded_lanes<P: InstructionSet>(
        &self,
        lanes: &Lanes<P>,
        rays: &[Ray],
        active: u32,
        t_max: &[f32; MAX_WIDTH],
    ) -> u32 {
        if self.root == EMPTY {
            return 0;
        }
        let k = lanes.k;
        let k8 = k.tree();
        let mut done = 0;
        if self.max_stack > STACK_INLINE {
            for lane in lanes_of(active) {
                if self.occluded(k8, &RayK::new(&rays[lane]), t_max[lane]) {
                    done |= 1 << lane;
                }
            }
            return done;
        }
        let limit_t = k.load(t_max);
        let limit = limit_t * k.splat(BOX_T_SLACK);
        let mut stack = [(0u32, 0u32); STACK];
        let mut alone = [0u32; STACK_INLINE];
        let mut sp = 0;
        let mut item = self.root;
        let mut active = active;
        loop {
            if active.count_ones() <= ALONE {
                for lane in lanes_of(active) {
                    let r = RayK::new(&rays[lane]);
                    if self.occluded_on(k8, &r, t_max[lane], item, &mut alone) {
                        done |= 1 << lane;
                    }
                }
            } else if item & LEAF != 0 {
                done |= lanes.leaf_any(&self.packets[(item & !LEAF) as usize], active, limit_t);
            } else {
                let node = &self.nodes[item as usize];
                let active_mask = P::Mask::from_bitmask(active);
                for slot in 0..node.child.len() {
                    let child = node.child[slot];
                    if child == EMPTY {
                        break;
                    }
                    let (entered, _) = lanes.enter(node, slot, active_mask, limit);
                    if entered != 0 {
                        stack[sp] = (child, entered);
                        sp += 1;
                    }
                }
            }
            // Next: a pending child, with its lanes not yet blocked.
            loop {
                if sp == 0 {
                    return done;
                }
                sp -= 1;
                let (next, entered) = stack[sp];
                if entered & !done != 0 {
                    item = next;
                    active = entered & !done;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #[cfg(target_arch = "x86_64")]
    use super::super::simd::{Avx2, Avx512};
    #[cfg(target_arch = "x86_64")]
    use super::super::x86_lanes::Avx512F32;
    use super::*;
    #[cfg(target_arch = "x86_64")]
    use crate::shapes::accel::x86_lanes::gather16;

    /// A full packet's rays and shadow rays read by plain loads and rearranged
    /// (`transpose16`) equal the same read lane by lane (`gather16`), every float.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn transposed_packets_equal_gathered_ones() {
        let Some(k) = Avx512::detect() else {
            return crate::shapes::accel::skip_unless_required("avx512", "transposed_packets");
        };
        let mut rng = crate::base::sampling::Rng::new(3);
        let mut v = || glam::Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let rays: Vec<Ray> = (0..16).map(|_| Ray::new(v(), v())).collect();
        let segments: Vec<(Ray, f32)> = rays.iter().map(|r| (*r, r.origin.x + 1.0)).collect();
        let floats = |vs: &[Avx512F32]| -> Vec<[f32; MAX_WIDTH]> {
            vs.iter()
                .map(|&x| {
                    let mut a = [0.0; MAX_WIDTH];
                    k.store(&mut a, x);
                    a
                })
                .collect()
        };
        // SAFETY: AVX-512 F (detected); 16 records of RAY_FLOATS and SEGMENT_FLOATS floats.
        let (gathered, gathered_segments) = unsafe {
            (
                gather16::<6>(rays.as_ptr().cast(), RAY_FLOATS, 16).map(Avx512F32),
                gather16::<7>(segments.as_ptr().cast(), SEGMENT_FLOATS, 16).map(Avx512F32),
            )
        };
        assert_eq!(floats(&k.rays(&rays)), floats(&gathered));
        assert_eq!(floats(&k.segments(&segments)), floats(&gathered_segments));
        for (lane, r) in rays.iter().enumerate() {
            let x = floats(&gathered);
            assert_eq!([x[0][lane], x[4][lane]], [r.origin.x, r.direction.y]);
        }
    }

    /// AVX2's full packet of rays and shadow rays read by 128-bit loads and rearranged
    /// (`transpose8`, through [`InstructionSet::rays`] and [`InstructionSet::segments`]) equal the same
    /// read lane by lane (`gather8`), every float.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn transposed_eight_lane_packets_equal_gathered_ones() {
        use super::super::x86_lanes::{Avx2F32, gather8};
        let Some(k) = Avx2::detect() else {
            return crate::shapes::accel::skip_unless_required("avx2", "transposed_eight");
        };
        let mut rng = crate::base::sampling::Rng::new(5);
        let mut v = || glam::Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let rays: Vec<Ray> = (0..8).map(|_| Ray::new(v(), v())).collect();
        let segments: Vec<(Ray, f32)> = rays.iter().map(|r| (*r, r.origin.x + 1.0)).collect();
        let floats = |vs: &[Avx2F32]| -> Vec<[f32; MAX_WIDTH]> {
            vs.iter()
                .map(|&x| {
                    let mut a = [0.0; MAX_WIDTH];
                    k.store(&mut a, x);
                    a
                })
                .collect()
        };
        // SAFETY: AVX2 (detected); 8 records of RAY_FLOATS and SEGMENT_FLOATS floats.
        let (gathered, gathered_segments) = unsafe {
            (
                gather8::<6>(rays.as_ptr().cast(), RAY_FLOATS, 8).map(Avx2F32),
                gather8::<7>(segments.as_ptr().cast(), SEGMENT_FLOATS, 8).map(Avx2F32),
            )
        };
        assert_eq!(floats(&k.rays(&rays)), floats(&gathered));
        assert_eq!(floats(&k.segments(&segments)), floats(&gathered_segments));
        let x = floats(&gathered_segments);
        for (lane, (r, t)) in segments.iter().enumerate() {
            let want = [r.origin.x, r.origin.y, r.direction.x, r.direction.z, *t];
            assert_eq!(
                [x[0][lane], x[1][lane], x[3][lane], x[5][lane], x[6][lane]],
                want
            );
        }
    }

    /// The eight-lane masks (AVX2's and the portable set's): bits → lanes → bits is the
    /// identity, and a comparison's lanes are its bits; the unsigned comparison and the masked
    /// minimum lane by lane.
    #[test]
    fn eight_lane_masks_round_trip() {
        eight_lane_masks(super::super::portable::Portable);
        #[cfg(target_arch = "x86_64")]
        match Avx2::detect() {
            Some(k) => eight_lane_masks(k),
            None => {
                crate::shapes::accel::skip_unless_required("avx2", "eight_lane_masks_round_trip")
            }
        }
    }

    fn eight_lane_masks<P: InstructionSet>(k: P) {
        assert_eq!(P::WIDTH, 8);
        for bits in 0..256u32 {
            assert_eq!(P::Mask::from_bitmask(bits).bitmask(), bits);
        }
        let mut a = [0.0f32; MAX_WIDTH];
        let mut ua = [0u32; MAX_WIDTH];
        let mut ub = [0u32; MAX_WIDTH];
        let values = [3.0, -1.0, 0.0, -0.0, 7.5, f32::INFINITY, f32::NAN, 2.0];
        let unsigned = [0, 1, u32::MAX, 0x8000_0000, 0x7fff_ffff, 5, u32::MAX - 1, 9];
        for lane in 0..8 {
            a[lane] = values[lane];
            ua[lane] = unsigned[lane];
            ub[lane] = unsigned[7 - lane];
        }
        let v = k.load(&a);
        let lt = v.simd_lt(k.splat(2.5)).bitmask();
        let want: u32 = (0..8).filter(|&i| values[i] < 2.5).map(|i| 1 << i).sum();
        assert_eq!(lt, want);
        let ult = (k.lt_u32(k.load_u32(&ua), k.load_u32(&ub))).bitmask();
        let want: u32 = (0..8).filter(|&i| ua[i] < ub[i]).map(|i| 1 << i).sum();
        assert_eq!(ult, want);
        for bits in 1..256u32 {
            let want = (0..8)
                .filter(|&i| bits & (1 << i) != 0 && !values[i].is_nan())
                .map(|i| values[i])
                .fold(f32::INFINITY, f32::min);
            let got = k.min_of(P::Mask::from_bitmask(bits), v);
            if bits & (1 << 6) == 0 {
                assert_eq!(got, want, "{bits:08b}");
            }
        }
        // Blends: the second operand where the mask is set.
        let mut out = [0.0f32; MAX_WIDTH];
        k.store(
            &mut out,
            P::F::select(
                P::Mask::from_bitmask(0b1010_0101),
                k.splat(2.0),
                k.splat(1.0),
            ),
        );
        assert_eq!(&out[..8], &[2.0, 1.0, 2.0, 1.0, 1.0, 2.0, 1.0, 2.0]);
        let mut outu = [0u32; MAX_WIDTH];
        let blended = k.blend_u32(
            P::Mask::from_bitmask(0b0000_0011),
            k.splat_u32(4),
            k.splat_u32(9),
        );
        k.store_u32(&mut outu, blended);
        assert_eq!(&outu[..8], &[9, 9, 4, 4, 4, 4, 4, 4]);
    }

    /// Both widths gather the same rays into their lanes, repeating the last past the end.
    #[test]
    fn rays_gather_into_lanes() {
        use glam::Vec3;
        let rays: Vec<Ray> = (0..5)
            .map(|i| Ray::new(Vec3::new(i as f32, 1.0, 2.0), Vec3::new(1.0, i as f32, 0.5)))
            .collect();
        fn check<P: InstructionSet>(k: P, rays: &[Ray]) {
            for (c, v) in k.rays(rays).into_iter().enumerate() {
                let mut got = [0.0; MAX_WIDTH];
                k.store(&mut got, v);
                for (lane, got) in got[..P::WIDTH].iter().enumerate() {
                    let r = rays[lane.min(rays.len() - 1)];
                    let want = [r.origin, r.direction][c / 3][c % 3];
                    assert_eq!(got.to_bits(), want.to_bits(), "lane {lane}, float {c}");
                }
            }
        }
        check(super::super::portable::Portable, &rays);
        #[cfg(target_arch = "x86_64")]
        match Avx2::detect() {
            Some(k) => check(k, &rays),
            None => crate::shapes::accel::skip_unless_required("avx2", "rays_gather_into_lanes"),
        }
        #[cfg(target_arch = "x86_64")]
        match Avx512::detect() {
            Some(k) => check(k, &rays),
            None => crate::shapes::accel::skip_unless_required("avx512", "rays_gather_into_lanes"),
        }
    }
}
