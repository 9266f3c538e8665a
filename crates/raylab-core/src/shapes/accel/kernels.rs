//! The single-ray kernels, written once over the lanes of an instruction set
//! ([`InstructionSet`]): one ray, in every lane, against a lane per box of a wide node
//! ([`boxes`]) or a lane per triangle of a packet ([`nearest`], [`nearest_among`], [`any`]).
//! The AVX2 and portable sets run them eight lanes wide (the wide BVH and the flat list),
//! AVX-512 sixteen wide on the flat list's [`Packet16`]s.
//!
//! The triangle test is [`intersect_lanes`], the scalar test's own source, so every lane's `t`,
//! `u`, `v` are [`crate::shapes::intersect::intersect_triangle`]'s bit for bit; the nearest of several
//! equal hits is the lowest lane's, and across packets the first packet's, as in the
//! brute-force loop.
//!
//! **Compiled per set.** The functions are `#[inline(always)]`: they are compiled inside the
//! function each set's entry point makes ([`InstructionSet::call`]: the batches of
//! [`super::batches`]).

use glam::Vec3;

use super::set::{Compiled, InstructionSet, MAX_WIDTH};
use super::simd::{LANES, LaneHit, Node8, Packet, Packet16, RayK};
use crate::base::lanes::{Mask, Real, Vec3x};
use crate::shapes::intersect::intersect_lanes;

/// A packet of triangles as lanes: `v0`, `e1`, `e2` and the normal `n = e1 × e2` (stored by
/// [`Packet16`], computed for the 8-wide packets, by the same expression: the same bits).
pub(super) trait TriangleLanes {
    fn lanes<P: InstructionSet>(&self, k: P) -> [Vec3x<P::F>; 4];
}

/// Rows of x, y and z as lanes.
#[inline(always)]
fn rows<P: InstructionSet, const N: usize>(k: P, rows: &[[f32; N]; 3]) -> Vec3x<P::F> {
    Vec3x {
        x: k.load_lanes(&rows[0]),
        y: k.load_lanes(&rows[1]),
        z: k.load_lanes(&rows[2]),
    }
}

impl TriangleLanes for Packet<LANES> {
    #[inline(always)]
    fn lanes<P: InstructionSet>(&self, k: P) -> [Vec3x<P::F>; 4] {
        let (e1, e2) = (rows(k, &self.e1), rows(k, &self.e2));
        [
            rows(k, &self.v0),
            e1,
            e2,
            crate::base::lanes::Vector::cross(e1, e2),
        ]
    }
}

impl TriangleLanes for Packet16 {
    #[inline(always)]
    fn lanes<P: InstructionSet>(&self, k: P) -> [Vec3x<P::F>; 4] {
        [
            rows(k, &self.v0),
            rows(k, &self.e1),
            rows(k, &self.e2),
            rows(k, &self.n),
        ]
    }
}

/// `t`, `u`, `v` of every lane (meaningless for a miss) and the mask of hits.
#[inline(always)]
fn hits<P: InstructionSet, T: TriangleLanes>(
    k: P,
    p: &T,
    r: &RayK,
    t_limit: f32,
) -> ([P::F; 3], P::Mask) {
    let [v0, e1, e2, n] = p.lanes(k);
    let origin = crate::base::lanes::Vector::splat(Vec3::from(r.origin));
    let direction = crate::base::lanes::Vector::splat(Vec3::from(r.direction));
    let h = intersect_lanes(origin, direction, v0, e1, e2, n, k.splat(t_limit));
    ([h.t, h.u, h.v], h.hit)
}

/// Bit `i` set when the ray enters child box `i` within `[0, t_limit]`, and each box's entry
/// distance ([`super::simd::Scalar::boxes`] is the readable form).
#[inline(always)]
pub(super) fn boxes<P: InstructionSet>(
    k: P,
    node: &Node8,
    r: &RayK,
    t_limit: f32,
) -> (u32, [f32; 8]) {
    debug_assert_eq!(P::WIDTH, LANES);
    let mut t0 = k.splat(0.0);
    let mut t1 = k.splat(t_limit);
    for axis in 0..3 {
        let o = k.splat(r.origin[axis]);
        let inv = k.splat(r.inv[axis]);
        let o_inv = k.splat(r.origin_inv[axis]);
        let near = k.plane_distance(k.load_lanes(&node.bounds[r.near[axis]]), o, inv, o_inv);
        let far = k.plane_distance(k.load_lanes(&node.bounds[r.far[axis]]), o, inv, o_inv);
        t0 = t0.max_or_other(near);
        t1 = t1.min_or_other(far);
    }
    let mut t_near = [0.0f32; MAX_WIDTH];
    k.store(&mut t_near, t0);
    let t_near = *t_near.first_chunk().expect("sixteen floats hold eight");
    (t0.simd_le(t1).bitmask(), t_near)
}

/// The nearest hit in the packet with `0 < t < t_limit`, the lowest lane among equal `t`.
#[inline(always)]
pub(super) fn nearest<P: InstructionSet, T: TriangleLanes>(
    k: P,
    p: &T,
    r: &RayK,
    t_limit: f32,
) -> Option<LaneHit> {
    let ([t, u, v], hit) = hits(k, p, r, t_limit);
    if hit.bitmask() == 0 {
        return None;
    }
    let m = k.min_of(hit, t);
    let at_min = (hit & t.simd_eq(k.splat(m))).bitmask();
    let lane = at_min.trailing_zeros() as usize & (P::WIDTH - 1);
    // The lane's u and v moved to lane 0 in registers where the set can: storing the vectors
    // and reading one float back would stall on the store (store forwarding).
    Some(LaneHit {
        lane,
        t: m,
        u: k.lane(u, lane),
        v: k.lane(v, lane),
    })
}

/// The nearest hit among `packets`: the packet's position in the slice, and the hit. The same
/// answer as [`super::simd::nearest_packet_by_packet`], bit for bit: among equal `t`, the first
/// packet's, then its lowest lane's.
///
/// Each lane keeps its own nearest `t`, `u`, `v` and packet from packet to packet, and the lanes
/// are reduced to one only at the end. Packet by packet, every packet with a hit reduced its
/// lanes to one at once, a chain of dependent instructions that the next packet's limit waited
/// for: most of the closest-hit time of the path tracer's bounce rays, which each meet two
/// packets of the Cornell box.
#[inline(always)]
pub(super) fn nearest_among<P: InstructionSet, T: TriangleLanes>(
    k: P,
    packets: &[T],
    r: &RayK,
    t_limit: f32,
) -> Option<(usize, LaneHit)> {
    let mut t_best = k.splat(f32::INFINITY);
    let (mut u_best, mut v_best) = (k.splat(0.0), k.splat(0.0));
    let mut packet_best = k.splat_u32(0);
    let mut hit_any = P::Mask::from_bitmask(0);
    for (i, p) in packets.iter().enumerate() {
        let ([t, u, v], hit) = hits(k, p, r, t_limit);
        // Strictly nearer: a lane keeps its first packet's hit among equal `t`.
        let nearer = hit & t.simd_lt(t_best);
        t_best = P::F::select(nearer, t, t_best);
        u_best = P::F::select(nearer, u, u_best);
        v_best = P::F::select(nearer, v, v_best);
        packet_best = k.blend_u32(nearer, packet_best, k.splat_u32(i as u32));
        hit_any = hit_any | hit;
    }
    if hit_any.bitmask() == 0 {
        return None;
    }
    // Lanes without a hit hold +∞: the least of all lanes is the least hit.
    let m = k.min_of(P::Mask::splat(true), t_best);
    let at_min = (hit_any & t_best.simd_eq(k.splat(m))).bitmask();
    let mut lane = at_min.trailing_zeros() as usize & (P::WIDTH - 1);
    let mut packet = k.lane_u32(packet_best, lane);
    if at_min.count_ones() > 1 {
        // Equal `t` in several lanes (rare): the first packet among them, then the lowest lane.
        for other in lane + 1..P::WIDTH {
            if at_min & (1 << other) != 0 {
                let other_packet = k.lane_u32(packet_best, other);
                if other_packet < packet {
                    (lane, packet) = (other, other_packet);
                }
            }
        }
    }
    Some((
        packet as usize,
        LaneHit {
            lane,
            t: m,
            u: k.lane(u_best, lane),
            v: k.lane(v_best, lane),
        },
    ))
}

/// Whether any triangle of the packet is hit with `0 < t < t_limit`.
#[inline(always)]
pub(super) fn any<P: InstructionSet, T: TriangleLanes>(
    k: P,
    p: &T,
    r: &RayK,
    t_limit: f32,
) -> bool {
    hits(k, p, r, t_limit).1.any()
}

/// [`boxes`] as its own function compiled for the set ([`InstructionSet::call`]), for the wide
/// BVH's single-ray traversal: its loop over nodes and leaves stays small where the compiler
/// keeps the kernels out of line.
pub(super) struct Boxes<'a> {
    pub node: &'a Node8,
    pub r: &'a RayK,
    pub t_limit: f32,
}

impl Compiled for Boxes<'_> {
    type Output = (u32, [f32; 8]);
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) -> (u32, [f32; 8]) {
        boxes(k, self.node, self.r, self.t_limit)
    }
}

/// [`nearest`] in an eight-wide leaf, compiled for the set, as [`Boxes`].
pub(super) struct Nearest<'a> {
    pub p: &'a Packet<LANES>,
    pub r: &'a RayK,
    pub t_limit: f32,
}

impl Compiled for Nearest<'_> {
    type Output = Option<LaneHit>;
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) -> Option<LaneHit> {
        nearest(k, self.p, self.r, self.t_limit)
    }
}

/// [`any`] in an eight-wide leaf, compiled for the set, as [`Boxes`].
pub(super) struct Any<'a> {
    pub p: &'a Packet<LANES>,
    pub r: &'a RayK,
    pub t_limit: f32,
}

impl Compiled for Any<'_> {
    type Output = bool;
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) -> bool {
        any(k, self.p, self.r, self.t_limit)
    }
}
