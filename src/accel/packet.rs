//! Coherent rays together: up to sixteen rays through the 8-wide BVH as one packet, one
//! AVX-512 lane a ray.
//!
//! Camera rays through neighbouring pixels, and the shadow rays from their hits towards the
//! point light, meet the same nodes in the same order. Ray by ray, each of them loads a node's
//! eight boxes and tests them eight lanes wide. As a packet, the node is loaded once and each
//! child box is tested against sixteen rays in one step: for a node every ray of the packet
//! enters, a third of the instructions (PERFORMANCE.md measures what it buys).
//!
//! Each lane computes exactly what [`super::simd::Kernels::boxes`] computes for its ray (the
//! same planes, the same fused multiply-subtract, the same order of `max` and `min`), against
//! its own best hit; leaves are tested ray by ray with the same triangle kernel as the single
//! ray's traversal, with the same rule for ties. So a packet returns exactly what each ray
//! returns alone (tests/bvh.rs checks it against the brute-force loop), whatever order the
//! packet visits the nodes in.
//!
//! When few rays of a packet are left in a subtree (they diverged, or most of them found
//! nearer hits), each goes on alone from that node with the single-ray traversal: a packet's
//! step costs the same for one ray as for sixteen. Rays that point in very different
//! directions (the path tracer's bounces) never form a packet: see [`coherent`].

use std::arch::x86_64::*;

use super::Hit;
use super::bvh::BOX_T_SLACK;
use super::bvh::INV_HUGE;
use super::simd::{Avx512, Node8, Packet, RayK};
use super::wide::{Bvh8, Bvh8Big, EMPTY, LEAF, STACK_INLINE};
use crate::geometry::Ray;
use crate::intersect::EDGE_TOLERANCE;

/// Rays in a packet: one AVX-512 register of `f32`.
pub const PACKET: usize = 16;
const _: () = assert!(PACKET == super::PACKET);

/// A packet with at most this many rays left in a subtree lets each go on alone. Measured
/// (whole `raylab bench --threads 1` runs, bunny and terrain, alternating binaries): 1, 2 and 4
/// are level within 1 %.
const ALONE: u32 = 2;

/// Directions within about 18° of the first ray's (cosine 0.95) travel together.
const COHERENT_COS: f32 = 0.95;

/// Stack entries of a packet traversal: the same bound as a single ray's
/// ([`Bvh8::max_stack`]), since a node pushes at most its eight children either way.
const STACK: usize = 2 * STACK_INLINE;

/// Whether `rays` point nearly the same way, so that they are worth tracing as a packet:
/// every direction within about 18° of the first (directions are unit vectors).
pub fn coherent(rays: &[Ray]) -> bool {
    let Some(first) = rays.first() else {
        return false;
    };
    rays.len() > ALONE as usize
        && rays
            .iter()
            .all(|r| r.direction.dot(first.direction) >= COHERENT_COS)
}

/// [`coherent`] for shadow rays (each with its `t_max`).
pub fn coherent_shadows(rays: &[(Ray, f32)]) -> bool {
    let Some((first, _)) = rays.first() else {
        return false;
    };
    rays.len() > ALONE as usize
        && rays
            .iter()
            .all(|(r, _)| r.direction.dot(first.direction) >= COHERENT_COS)
}

/// The packet's rays, one per lane: what the box test needs (as in [`RayK`]).
struct Lanes {
    origin: [__m512; 3],
    direction: [__m512; 3],
    inv: [__m512; 3],
    origin_inv: [__m512; 3],
    /// Per axis, the lanes whose ray goes towards negative coordinates (near plane = max).
    negative: [__mmask16; 3],
}

impl Lanes {
    /// The rays' origins and directions, one lane each (lanes past `rays.len()` repeat the
    /// first ray and are never active), and what the box test needs, computed as
    /// [`RayK::new`] computes it, sixteen rays at a time: the same divisions, so the same bits.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn new(rays: &[Ray]) -> Self {
        debug_assert!(!rays.is_empty() && rays.len() <= PACKET);
        // A ray is six f32 (origin, direction): lane i reads floats 6i + c.
        const FLOATS: i32 = (size_of::<Ray>() / size_of::<f32>()) as i32;
        const _: () = assert!(FLOATS == 6 && align_of::<Ray>() == align_of::<f32>());
        let last = rays.len() as i32 - 1;
        let lane = _mm512_min_epi32(
            _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
            _mm512_set1_epi32(last),
        );
        let lane = _mm512_mullo_epi32(lane, _mm512_set1_epi32(FLOATS));
        let base = rays.as_ptr().cast::<f32>();
        let gather = |c: i32| {
            // SAFETY: every index is 6i + c for a ray i < rays.len() and c < 6: a float of
            // `rays`, which is a slice of `Ray`s, each six `f32` (checked above).
            unsafe { _mm512_i32gather_ps::<4>(_mm512_add_epi32(lane, _mm512_set1_epi32(c)), base) }
        };
        let origin = [gather(0), gather(1), gather(2)];
        let direction = [gather(3), gather(4), gather(5)];
        let mut inv = [_mm512_setzero_ps(); 3];
        let mut origin_inv = [_mm512_setzero_ps(); 3];
        let mut negative = [0; 3];
        for axis in 0..3 {
            // `RayBoxData::new`: 1/d, or ±INV_HUGE where |d| ≤ 1/INV_HUGE.
            let d = direction[axis];
            let huge = _mm512_or_ps(
                _mm512_set1_ps(INV_HUGE),
                _mm512_and_ps(d, _mm512_set1_ps(-0.0)),
            );
            let small =
                _mm512_cmp_ps_mask::<_CMP_NGT_UQ>(_mm512_abs_ps(d), _mm512_set1_ps(1.0 / INV_HUGE));
            inv[axis] = _mm512_mask_mov_ps(_mm512_div_ps(_mm512_set1_ps(1.0), d), small, huge);
            origin_inv[axis] = _mm512_mul_ps(origin[axis], inv[axis]);
            negative[axis] = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(inv[axis], _mm512_setzero_ps());
        }
        Self {
            origin,
            direction,
            inv,
            origin_inv,
            negative,
        }
    }

    /// Child `slot`'s box against the `active` lanes, each up to its own `limit`: the lanes
    /// that enter it (as [`Kernels::boxes`] decides for each ray alone) and the nearest of
    /// their entry distances.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn enter(&self, node: &Node8, slot: usize, active: u16, limit: __m512) -> (u16, f32) {
        let mut t0 = _mm512_setzero_ps();
        let mut t1 = limit;
        for axis in 0..3 {
            let min = _mm512_set1_ps(node.bounds[axis][slot]);
            let max = _mm512_set1_ps(node.bounds[axis + 3][slot]);
            let near_plane = _mm512_mask_blend_ps(self.negative[axis], min, max);
            let far_plane = _mm512_mask_blend_ps(self.negative[axis], max, min);
            let near = _mm512_fmsub_ps(near_plane, self.inv[axis], self.origin_inv[axis]);
            let far = _mm512_fmsub_ps(far_plane, self.inv[axis], self.origin_inv[axis]);
            t0 = _mm512_max_ps(t0, near);
            t1 = _mm512_min_ps(t1, far);
        }
        let entered = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(active, t0, t1);
        if entered == 0 {
            return (0, 0.0);
        }
        (entered, _mm512_mask_reduce_min_ps(entered, t0))
    }

    /// Triangle `tri` of a leaf against every lane: `t`, `u`, `v` per lane (meaningless where
    /// missed) and the lanes of `active` that hit it with `0 < t < limit`. Each lane does
    /// exactly [`crate::intersect::intersect_triangle`]'s operations in its order, as the
    /// 8-lane kernel does (no fused multiply-add), so the same bits.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn triangle<const N: usize>(
        &self,
        p: &Packet<N>,
        tri: usize,
        active: u16,
        limit: __m512,
    ) -> ([__m512; 3], u16) {
        let set = |x: f32| _mm512_set1_ps(x);
        let [ox, oy, oz] = self.origin;
        let [dx, dy, dz] = self.direction;
        let (e1x, e1y, e1z) = (set(p.e1[0][tri]), set(p.e1[1][tri]), set(p.e1[2][tri]));
        let (e2x, e2y, e2z) = (set(p.e2[0][tri]), set(p.e2[1][tri]), set(p.e2[2][tri]));
        let mul = |a, b| _mm512_mul_ps(a, b);
        let sub = |a, b| _mm512_sub_ps(a, b);
        let add = |a, b| _mm512_add_ps(a, b);
        let nx = sub(mul(e1y, e2z), mul(e2y, e1z));
        let ny = sub(mul(e1z, e2x), mul(e2z, e1x));
        let nz = sub(mul(e1x, e2y), mul(e2x, e1y));
        let bx = sub(ox, set(p.v0[0][tri]));
        let by = sub(oy, set(p.v0[1][tri]));
        let bz = sub(oz, set(p.v0[2][tri]));
        let sign = set(-0.0);
        let det = add(add(mul(dx, nx), mul(dy, ny)), mul(dz, nz));
        let inv_det = _mm512_div_ps(set(1.0), _mm512_xor_ps(det, sign));
        let t = mul(add(add(mul(bx, nx), mul(by, ny)), mul(bz, nz)), inv_det);
        let mx = sub(mul(by, dz), mul(dy, bz));
        let my = sub(mul(bz, dx), mul(dz, bx));
        let mz = sub(mul(bx, dy), mul(dx, by));
        let u = mul(add(add(mul(e2x, mx), mul(e2y, my)), mul(e2z, mz)), inv_det);
        let e1m = add(add(mul(e1x, mx), mul(e1y, my)), mul(e1z, mz));
        let v = mul(_mm512_xor_ps(e1m, sign), inv_det);
        let lo = set(-EDGE_TOLERANCE);
        let mut hit = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(active, t, _mm512_setzero_ps());
        hit &= _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, limit);
        hit &= _mm512_cmp_ps_mask::<_CMP_GE_OQ>(u, lo);
        hit &= _mm512_cmp_ps_mask::<_CMP_GE_OQ>(v, lo);
        hit &= _mm512_cmp_ps_mask::<_CMP_LE_OQ>(add(u, v), set(1.0 + EDGE_TOLERANCE));
        ([t, u, v], hit)
    }

    /// A leaf's triangles against the `active` lanes, one triangle at a time: each lane keeps
    /// the nearest hit, the lowest triangle index among equal `t` (as the brute-force loop).
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn leaf_nearest<const N: usize>(&self, p: &Packet<N>, active: u16, b: &mut Best, t_max: f32) {
        let limit = _mm512_set1_ps(t_max);
        // SAFETY: each row of `b` is sixteen readable f32 or u32.
        let (mut best_t, mut best_i, mut best_u, mut best_v) = unsafe {
            (
                _mm512_loadu_ps(b.t.as_ptr()),
                _mm512_loadu_si512(b.index.as_ptr().cast()),
                _mm512_loadu_ps(b.u.as_ptr()),
                _mm512_loadu_ps(b.v.as_ptr()),
            )
        };
        for (tri, &index) in p.index.iter().enumerate() {
            if index == u32::MAX {
                continue; // an unused lane of the packet
            }
            let ([t, u, v], hit) = self.triangle(p, tri, active, limit);
            if hit == 0 {
                continue;
            }
            let index_v = _mm512_set1_epi32(index as i32);
            // Nearer, or as near with a lower index (a lane without a hit has best_t = t_max,
            // which no hit reaches, so the index test only ever compares real hits).
            let nearer = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(hit, t, best_t);
            let tie = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(hit, t, best_t)
                & _mm512_cmplt_epu32_mask(index_v, best_i);
            let better = nearer | tie;
            best_t = _mm512_mask_mov_ps(best_t, better, t);
            best_i = _mm512_mask_mov_epi32(best_i, better, index_v);
            best_u = _mm512_mask_mov_ps(best_u, better, u);
            best_v = _mm512_mask_mov_ps(best_v, better, v);
        }
        // SAFETY: each row of `b` is sixteen writable f32 or u32.
        unsafe {
            _mm512_storeu_ps(b.t.as_mut_ptr(), best_t);
            _mm512_storeu_si512(b.index.as_mut_ptr().cast(), best_i);
            _mm512_storeu_ps(b.u.as_mut_ptr(), best_u);
            _mm512_storeu_ps(b.v.as_mut_ptr(), best_v);
        }
    }

    /// The lanes of `active` that hit any triangle of a leaf with `0 < t < limit` (per lane).
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn leaf_any<const N: usize>(&self, p: &Packet<N>, active: u16, limit: __m512) -> u16 {
        let mut blocked = 0;
        for (tri, &index) in p.index.iter().enumerate() {
            if index == u32::MAX || blocked == active {
                continue;
            }
            blocked |= self.triangle(p, tri, active & !blocked, limit).1;
        }
        blocked
    }
}

/// The lanes set in `mask`, lowest first.
#[inline(always)]
fn lanes_of(mut mask: u16) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

/// All of the first `n` lanes.
fn first_lanes(n: usize) -> u16 {
    ((1u32 << n) - 1) as u16
}

/// Each lane's best hit so far, as the single-ray traversal keeps it.
struct Best {
    t: [f32; PACKET],
    index: [u32; PACKET],
    u: [f32; PACKET],
    v: [f32; PACKET],
}

impl Best {
    fn new(t_max: f32) -> Self {
        Self {
            t: [t_max; PACKET],
            index: [u32::MAX; PACKET],
            u: [0.0; PACKET],
            v: [0.0; PACKET],
        }
    }

    fn get(&self, lane: usize) -> Option<Hit> {
        (self.index[lane] != u32::MAX).then(|| Hit {
            index: self.index[lane],
            t: self.t[lane],
            u: self.u[lane],
            v: self.v[lane],
        })
    }

    fn set(&mut self, lane: usize, h: Hit) {
        self.t[lane] = h.t;
        self.index[lane] = h.index;
        self.u[lane] = h.u;
        self.v[lane] = h.v;
    }

    /// Each lane's box limit: its best `t` with the boxes' slack.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn box_limit(&self) -> __m512 {
        // SAFETY: `t` is sixteen readable f32.
        let t = unsafe { _mm512_loadu_ps(self.t.as_ptr()) };
        _mm512_mul_ps(t, _mm512_set1_ps(BOX_T_SLACK))
    }
}

impl Bvh8Big {
    /// [`Bvh8Big`]'s closest hits for up to [`PACKET`] rays at once, `out[i]` for `rays[i]`:
    /// the large triangles first (a triangle at a time against every ray), then the tree.
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    pub(super) fn closest_packet(
        &self,
        k: Avx512,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
        debug_assert!(!rays.is_empty() && rays.len() <= PACKET && rays.len() == out.len());
        let lanes = Lanes::new(rays);
        let all = first_lanes(rays.len());
        let mut b = Best::new(t_max);
        for p in &self.big.packets16 {
            lanes.leaf_nearest(&p.triangles, all, &mut b, t_max);
        }
        self.tree.closest_lanes(k, &lanes, rays, all, t_max, &mut b);
        for (lane, hit) in out.iter_mut().enumerate() {
            *hit = b.get(lane);
        }
    }

    /// [`Bvh8Big`]'s any-hit queries for up to [`PACKET`] rays at once, each with its own
    /// `t_max`: `blocked[i]` for `rays[i]`.
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    pub(super) fn occluded_packet(&self, k: Avx512, rays: &[(Ray, f32)], blocked: &mut [bool]) {
        debug_assert!(!rays.is_empty() && rays.len() <= PACKET && rays.len() == blocked.len());
        let mut only = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); PACKET];
        let mut t_max = [0.0f32; PACKET];
        for (lane, (ray, t)) in rays.iter().enumerate() {
            only[lane] = *ray;
            t_max[lane] = *t;
        }
        let only = &only[..rays.len()];
        let lanes = Lanes::new(only);
        let all = first_lanes(rays.len());
        let mut done = self.tree.occluded_lanes(k, &lanes, only, all, &t_max);
        // SAFETY: `t_max` is sixteen readable f32.
        let limit = unsafe { _mm512_loadu_ps(t_max.as_ptr()) };
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

impl Bvh8 {
    /// The closest-hit traversal of a packet: lanes `active` of `lanes` (made of `rays`),
    /// each keeping its best hit in `b`.
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn closest_lanes(
        &self,
        k: Avx512,
        lanes: &Lanes,
        rays: &[Ray],
        active: u16,
        t_max: f32,
        b: &mut Best,
    ) {
        if self.root == EMPTY {
            return;
        }
        let k8 = k.avx2();
        if self.max_stack > STACK_INLINE {
            for lane in lanes_of(active) {
                if let Some(h) = self.closest(k8, &RayK::new(&rays[lane]), t_max, b.get(lane)) {
                    b.set(lane, h);
                }
            }
            return;
        }
        let mut stack = [(0u32, 0u16, 0f32); STACK];
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
                        b.set(lane, h);
                    }
                }
            } else if item & LEAF != 0 {
                lanes.leaf_nearest(&self.packets[(item & !LEAF) as usize], active, b, t_max);
            } else {
                let node = &self.nodes[item as usize];
                let limit = b.box_limit();
                // Push the entered children sorted so that the nearest is on top.
                let base = sp;
                for slot in 0..node.child.len() {
                    let child = node.child[slot];
                    if child == EMPTY {
                        break; // a node's children fill its first slots
                    }
                    let (entered, t_near) = lanes.enter(node, slot, active, limit);
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
                let still = _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(
                    entered,
                    b.box_limit(),
                    _mm512_set1_ps(t_near),
                );
                if still != 0 {
                    item = next;
                    active = still;
                    break;
                }
            }
        }
    }

    /// The any-hit traversal of a packet: the lanes of `active` blocked before their `t_max`.
    #[target_feature(enable = "avx512f,avx512dq,avx2,fma")]
    fn occluded_lanes(
        &self,
        k: Avx512,
        lanes: &Lanes,
        rays: &[Ray],
        active: u16,
        t_max: &[f32; PACKET],
    ) -> u16 {
        if self.root == EMPTY {
            return 0;
        }
        let k8 = k.avx2();
        let mut done: u16 = 0;
        if self.max_stack > STACK_INLINE {
            for lane in lanes_of(active) {
                if self.occluded(k8, &RayK::new(&rays[lane]), t_max[lane]) {
                    done |= 1 << lane;
                }
            }
            return done;
        }
        // SAFETY: `t_max` is sixteen readable f32.
        let limit_t = unsafe { _mm512_loadu_ps(t_max.as_ptr()) };
        let limit = _mm512_mul_ps(limit_t, _mm512_set1_ps(BOX_T_SLACK));
        let mut stack = [(0u32, 0u16); STACK];
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
                for slot in 0..node.child.len() {
                    let child = node.child[slot];
                    if child == EMPTY {
                        break;
                    }
                    let (entered, _) = lanes.enter(node, slot, active, limit);
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
