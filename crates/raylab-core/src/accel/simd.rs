//! The two inner loops of tracing, eight lanes at a time: a ray against the eight boxes of a
//! wide node, and a ray against a packet of eight triangles.
//!
//! Each kernel has a scalar twin ([`Scalar`]) — plain loops over the lanes, the readable
//! definition — and an AVX2 version ([`Avx2`]) chosen at run time when the CPU has AVX2 and
//! FMA (and sixteen-wide AVX-512 ones for the flat list, [`Avx512`]). The triangle kernels are
//! the scalar test's own source, [`crate::intersect::intersect_lanes`], a lane per triangle
//! (no fused multiply-add), so every lane's `t`, `u`, `v` are bit-identical to
//! [`crate::intersect::intersect_triangle`]'s: the fast path accepts the very same edges and
//! returns the very same hits as the brute-force loop.

use glam::Vec3;

use crate::intersect::intersect_lanes;

use super::bvh::RayBoxData;

/// Lanes per node and per triangle packet.
pub const LANES: usize = 8;

/// `N` triangles, structure of arrays: `v0`, `e1 = v1 − v0`, `e2 = v2 − v0` per axis, and the
/// scene index of each (`u32::MAX` for an unused lane, whose zero edges can never be hit).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Packet<const N: usize> {
    pub v0: [[f32; N]; 3],
    pub e1: [[f32; N]; 3],
    pub e2: [[f32; N]; 3],
    pub index: [u32; N],
}

/// The packet of the wide BVH's leaves and the AVX2 kernels.
pub type Packet8 = Packet<LANES>;
/// The packet of the AVX-512 flat loop: sixteen triangles and their normals `n = e1 × e2`.
///
/// `n` depends on the triangle alone, so the flat loop (which tests every triangle for every
/// ray) stores it rather than computing it per ray: computed by the same expression as
/// `intersect_triangle`'s `e1.cross(e2)`, it has the same bits, and a cross product less per
/// ray and triangle. The BVH's 8-wide leaves do not store it: for a large scene such as the
/// terrain the larger leaves cost more in memory traffic than they save.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Packet16 {
    pub triangles: Packet<16>,
    pub n: [[f32; 16]; 3],
}

impl Packet16 {
    /// Packs triangles `indices` (at most 16, in ascending order).
    pub fn new(triangles: &[crate::geometry::Triangle], indices: &[u32]) -> Self {
        let packet = Packet::<16>::new(triangles, indices);
        let mut n = [[0.0; 16]; 3];
        for (lane, &i) in indices.iter().enumerate() {
            let (e1, e2) = triangles[i as usize].edges();
            let cross = e1.cross(e2);
            for axis in 0..3 {
                n[axis][lane] = cross[axis];
            }
        }
        Self {
            triangles: packet,
            n,
        }
    }
}

impl std::ops::Deref for Packet16 {
    type Target = Packet<16>;

    /// The triangles, for what does not need the normals (the scalar twin, the indices).
    fn deref(&self) -> &Packet<16> {
        &self.triangles
    }
}

impl<const N: usize> Packet<N> {
    pub const EMPTY: Self = Self {
        v0: [[0.0; N]; 3],
        e1: [[0.0; N]; 3],
        e2: [[0.0; N]; 3],
        index: [u32::MAX; N],
    };

    /// Packs triangles `indices` (at most `N`, in ascending order).
    pub fn new(triangles: &[crate::geometry::Triangle], indices: &[u32]) -> Self {
        debug_assert!(indices.len() <= N);
        let mut p = Self::EMPTY;
        for (lane, &i) in indices.iter().enumerate() {
            let t = &triangles[i as usize];
            let (e1, e2) = t.edges();
            for axis in 0..3 {
                p.v0[axis][lane] = t.v0[axis];
                p.e1[axis][lane] = e1[axis];
                p.e2[axis][lane] = e2[axis];
            }
            p.index[lane] = i;
        }
        p
    }

    /// Copies lane `from` of this packet into lane `to` of `other`.
    #[inline(always)]
    pub fn copy_lane<const M: usize>(&self, from: usize, other: &mut Packet<M>, to: usize) {
        for axis in 0..3 {
            other.v0[axis][to] = self.v0[axis][from];
            other.e1[axis][to] = self.e1[axis][from];
            other.e2[axis][to] = self.e2[axis][from];
        }
        other.index[to] = self.index[from];
    }

    /// The scalar twin of the packet kernels: the nearest hit, lowest lane among equal `t`.
    #[inline(always)]
    pub fn nearest_scalar(&self, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        let mut best = None;
        let mut limit = t_limit;
        for lane in 0..N {
            if let Some((t, u, v)) = lane_hit(self, lane, r, limit) {
                best = Some(LaneHit { lane, t, u, v });
                limit = t;
            }
        }
        best
    }

    /// The scalar twin of the packet kernels: whether any lane is hit.
    #[inline(always)]
    pub fn any_scalar(&self, r: &RayK, t_limit: f32) -> bool {
        (0..N).any(|lane| lane_hit(self, lane, r, t_limit).is_some())
    }
}

/// A node of the wide tree: the boxes of up to eight children, per axis, and what each child is
/// (see [`super::wide`]). Unused slots have an empty box (min +∞, max −∞) that no ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node8 {
    /// min x, min y, min z, max x, max y, max z.
    pub bounds: [[f32; LANES]; 6],
    pub child: [u32; LANES],
}

/// A ray prepared for the kernels.
#[derive(Clone, Copy, Debug)]
pub struct RayK {
    pub origin: [f32; 3],
    pub direction: [f32; 3],
    pub inv: [f32; 3],
    pub origin_inv: [f32; 3],
    /// Per axis, the row of [`Node8::bounds`] holding the near plane, and the far one.
    pub near: [usize; 3],
    pub far: [usize; 3],
}

impl RayK {
    /// For the triangle kernels only (the flat loop): no box data, none of its divisions.
    pub fn for_triangles(ray: &crate::geometry::Ray) -> Self {
        Self {
            origin: ray.origin.to_array(),
            direction: ray.direction.to_array(),
            inv: [0.0; 3],
            origin_inv: [0.0; 3],
            near: [0, 1, 2],
            far: [3, 4, 5],
        }
    }

    pub fn new(ray: &crate::geometry::Ray) -> Self {
        let b = RayBoxData::new(ray);
        let near = [0, 1, 2].map(|a| if b.negative[a] { a + 3 } else { a });
        let far = [0, 1, 2].map(|a| if b.negative[a] { a } else { a + 3 });
        Self {
            origin: ray.origin.to_array(),
            direction: ray.direction.to_array(),
            inv: b.inv.to_array(),
            origin_inv: b.origin_inv.to_array(),
            near,
            far,
        }
    }
}

/// The kernels the traversals are written against.
pub trait Kernels: Copy {
    /// Bit `i` set when the ray enters child box `i` within `[0, t_limit]`, and each box's
    /// entry distance.
    fn boxes(self, node: &Node8, ray: &RayK, t_limit: f32) -> (u32, [f32; LANES]);
    /// The nearest hit in the packet with `0 < t < t_limit`, the lowest lane among equal `t`.
    fn nearest(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> Option<LaneHit>;
    /// The nearest hit among `packets`: the packet's position in the slice, and the hit; among
    /// equal `t`, the first packet's, then its lowest lane's. Unless a kernel set keeps each
    /// lane's nearest across the packets (as [`Avx512::nearest16_among`] does), the packets one
    /// after another, each with the limit of the nearest hit so far.
    #[inline(always)]
    fn nearest_among(
        self,
        packets: &[Packet8],
        ray: &RayK,
        t_limit: f32,
    ) -> Option<(usize, LaneHit)> {
        nearest_packet_by_packet(packets, t_limit, |p, limit| self.nearest(p, ray, limit))
    }
    /// Whether any triangle of the packet is hit with `0 < t < t_limit`.
    fn any(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> bool;
}

/// A hit in a packet: the lane, and `t`, `u`, `v` as `intersect_triangle` computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaneHit {
    pub lane: usize,
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// The scalar twin: one lane at a time.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scalar;

/// `intersect_triangle` on one lane: [`intersect_lanes`] at `Vec3`.
#[inline(always)]
fn lane_hit<const N: usize>(
    p: &Packet<N>,
    i: usize,
    r: &RayK,
    t_limit: f32,
) -> Option<(f32, f32, f32)> {
    let lane = |rows: &[[f32; N]; 3]| Vec3::new(rows[0][i], rows[1][i], rows[2][i]);
    let (e1, e2) = (lane(&p.e1), lane(&p.e2));
    let (origin, direction) = (Vec3::from(r.origin), Vec3::from(r.direction));
    let h = intersect_lanes(
        origin,
        direction,
        lane(&p.v0),
        e1,
        e2,
        e1.cross(e2),
        t_limit,
    );
    h.hit.then_some((h.t, h.u, h.v))
}

impl Kernels for Scalar {
    #[inline(always)]
    fn boxes(self, node: &Node8, r: &RayK, t_limit: f32) -> (u32, [f32; LANES]) {
        let mut mask = 0;
        let mut t_near = [0.0; LANES];
        for (i, t_out) in t_near.iter_mut().enumerate() {
            let mut t0 = 0.0f32;
            let mut t1 = t_limit;
            for axis in 0..3 {
                let near = node.bounds[r.near[axis]][i];
                let far = node.bounds[r.far[axis]][i];
                t0 = t0.max((near - r.origin[axis]) * r.inv[axis]);
                t1 = t1.min((far - r.origin[axis]) * r.inv[axis]);
            }
            *t_out = t0;
            if t0 <= t1 {
                mask |= 1 << i;
            }
        }
        (mask, t_near)
    }

    #[inline(always)]
    fn nearest(self, p: &Packet8, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        p.nearest_scalar(r, t_limit)
    }

    #[inline(always)]
    fn any(self, p: &Packet8, r: &RayK, t_limit: f32) -> bool {
        p.any_scalar(r, t_limit)
    }
}

/// The AVX2 kernels. A value of this type exists only on a CPU with AVX2 and FMA.
#[derive(Clone, Copy, Debug)]
pub struct Avx2 {
    _proof: (),
}

impl Avx2 {
    /// The AVX2 kernels if this CPU runs them.
    pub fn detect() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return Some(Self { _proof: () });
        }
        None
    }
}

/// The AVX-512 kernels for 16-wide packets (the flat loop over a small scene). A value of this
/// type exists only on a CPU with AVX-512 F, DQ and VL (and AVX2 and FMA).
#[derive(Clone, Copy, Debug)]
pub struct Avx512 {
    avx2: Avx2,
}

impl Avx512 {
    /// The AVX-512 kernels if this CPU runs them.
    pub fn detect() -> Option<Self> {
        let avx2 = Avx2::detect()?;
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl")
        {
            return Some(Self { avx2 });
        }
        let _ = avx2;
        None
    }

    /// The AVX2 kernels (for the 8-wide BVH), which this CPU also has.
    pub fn avx2(self) -> Avx2 {
        self.avx2
    }

    /// The nearest hit in a 16-wide packet, lowest lane among equal `t`.
    #[inline(always)]
    pub fn nearest16(self, p: &Packet16, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: an `Avx512` value is only made by `detect`, after checking for AVX-512.
            unsafe { x86::nearest16(p, r, t_limit) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        p.nearest_scalar(r, t_limit)
    }

    /// The nearest hit among 16-wide `packets`: the packet's position in the slice, and the
    /// hit. The same answer as [`nearest_packet_by_packet`], bit for bit: among equal `t`,
    /// the first packet's, then its lowest lane's.
    ///
    /// Each lane keeps its own nearest `t`, `u`, `v` and packet from packet to packet, and the
    /// sixteen are reduced to one only at the end. Packet by packet, every packet with a hit
    /// reduced its lanes to one at once, a chain of about fifteen dependent instructions
    /// that the next packet's limit waited for: most of the closest-hit time of the path
    /// tracer's bounce rays, which each meet two packets of the Cornell box.
    #[inline(always)]
    pub fn nearest16_among(
        self,
        packets: &[Packet16],
        r: &RayK,
        t_limit: f32,
    ) -> Option<(usize, LaneHit)> {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as above.
            unsafe { x86::nearest16_among(packets, r, t_limit) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        nearest_packet_by_packet(packets, t_limit, |p, limit| self.nearest16(p, r, limit))
    }

    /// Whether any triangle of a 16-wide packet is hit.
    #[inline(always)]
    pub fn any16(self, p: &Packet16, r: &RayK, t_limit: f32) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: as above.
            unsafe { x86::any16(p, r, t_limit) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        p.any_scalar(r, t_limit)
    }
}

/// The nearest hit among `packets`, one packet after another, each tested by `nearest` with
/// the limit of the nearest hit so far (strict, so the first of equal hits wins): the readable
/// definition of [`Kernels::nearest_among`] and [`Avx512::nearest16_among`].
#[inline(always)]
pub fn nearest_packet_by_packet<P>(
    packets: &[P],
    t_limit: f32,
    nearest: impl Fn(&P, f32) -> Option<LaneHit>,
) -> Option<(usize, LaneHit)> {
    let mut best = None;
    let mut limit = t_limit;
    for (i, p) in packets.iter().enumerate() {
        if let Some(h) = nearest(p, limit) {
            best = Some((i, h));
            limit = h.t;
        }
    }
    best
}

#[cfg(target_arch = "x86_64")]
impl Kernels for Avx2 {
    #[inline(always)]
    fn boxes(self, node: &Node8, ray: &RayK, t_limit: f32) -> (u32, [f32; LANES]) {
        // SAFETY: an `Avx2` value is only made by `detect`, after checking for AVX2 and FMA.
        unsafe { x86::boxes(node, ray, t_limit) }
    }

    #[inline(always)]
    fn nearest(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> Option<LaneHit> {
        // SAFETY: as above.
        unsafe { x86::nearest(packet, ray, t_limit) }
    }

    #[inline(always)]
    fn nearest_among(
        self,
        packets: &[Packet8],
        ray: &RayK,
        t_limit: f32,
    ) -> Option<(usize, LaneHit)> {
        // SAFETY: as above.
        unsafe { x86::nearest_among(packets, ray, t_limit) }
    }

    #[inline(always)]
    fn any(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> bool {
        // SAFETY: as above.
        unsafe { x86::any(packet, ray, t_limit) }
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl Kernels for Avx2 {
    fn boxes(self, node: &Node8, ray: &RayK, t_limit: f32) -> (u32, [f32; LANES]) {
        Scalar.boxes(node, ray, t_limit)
    }
    fn nearest(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> Option<LaneHit> {
        Scalar.nearest(packet, ray, t_limit)
    }
    fn any(self, packet: &Packet8, ray: &RayK, t_limit: f32) -> bool {
        Scalar.any(packet, ray, t_limit)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use glam::Vec3;

    use super::super::x86_lanes::{Avx2F32, Avx512F32};
    use super::{LANES, LaneHit, Node8, Packet8, Packet16, RayK};
    use crate::intersect::{Hits, intersect_lanes};
    use crate::lanes::{Real, Vec3x, Vector};

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn load(a: &[f32; LANES]) -> __m256 {
        // SAFETY: `a` is a valid reference to eight f32, readable as 32 bytes.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub fn boxes(node: &Node8, r: &RayK, t_limit: f32) -> (u32, [f32; LANES]) {
        let mut t0 = _mm256_setzero_ps();
        let mut t1 = _mm256_set1_ps(t_limit);
        for axis in 0..3 {
            let inv = _mm256_set1_ps(r.inv[axis]);
            let oinv = _mm256_set1_ps(r.origin_inv[axis]);
            // (plane − o)·inv as plane·inv − o·inv in one rounding; the padding of the boxes
            // covers the difference from the scalar form.
            let near = _mm256_fmsub_ps(load(&node.bounds[r.near[axis]]), inv, oinv);
            let far = _mm256_fmsub_ps(load(&node.bounds[r.far[axis]]), inv, oinv);
            t0 = _mm256_max_ps(t0, near);
            t1 = _mm256_min_ps(t1, far);
        }
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32;
        let mut t_near = [0.0f32; LANES];
        // SAFETY: `t_near` is writable for eight f32.
        unsafe { _mm256_storeu_ps(t_near.as_mut_ptr(), t0) };
        (mask, t_near)
    }

    /// `t`, `u`, `v` of every lane (meaningless for a miss) and the mask of hits:
    /// [`intersect_lanes`], a lane per triangle.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn hits(p: &Packet8, r: &RayK, t_limit: f32) -> ([__m256; 3], __m256) {
        let (e1, e2) = (rows8(&p.e1), rows8(&p.e2));
        let n = e1.cross(e2);
        let h = ray_lanes(r, rows8(&p.v0), e1, e2, n, t_limit);
        ([h.t.0, h.u.0, h.v.0], h.hit.0)
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub fn nearest(p: &Packet8, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        let ([t, u, v], hit) = hits(p, r, t_limit);
        if _mm256_movemask_ps(hit) == 0 {
            return None;
        }
        let t = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), t, hit);
        let m = min_of_lanes(t);
        let at_min = _mm256_and_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(t, m), hit);
        let lane = (_mm256_movemask_ps(at_min) as u32).trailing_zeros() as usize;
        let mut uv = [[0.0f32; LANES]; 2];
        // SAFETY: each row of `uv` is writable for eight f32.
        unsafe {
            _mm256_storeu_ps(uv[0].as_mut_ptr(), u);
            _mm256_storeu_ps(uv[1].as_mut_ptr(), v);
        }
        Some(LaneHit {
            lane,
            t: _mm256_cvtss_f32(m),
            u: uv[0][lane & (LANES - 1)],
            v: uv[1][lane & (LANES - 1)],
        })
    }

    /// [`super::Kernels::nearest_among`]: each lane's nearest kept across the packets, as in
    /// `nearest16_among`, and reduced to one at the end.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub fn nearest_among(packets: &[Packet8], r: &RayK, t_limit: f32) -> Option<(usize, LaneHit)> {
        let mut t_best = _mm256_set1_ps(f32::INFINITY);
        let (mut u_best, mut v_best) = (_mm256_setzero_ps(), _mm256_setzero_ps());
        let mut packet_best = _mm256_setzero_ps();
        let mut hit_any = _mm256_setzero_ps();
        for (i, p) in packets.iter().enumerate() {
            let ([t, u, v], hit) = hits(p, r, t_limit);
            // Strictly nearer: a lane keeps its first packet's hit among equal `t`.
            let nearer = _mm256_and_ps(hit, _mm256_cmp_ps::<_CMP_LT_OQ>(t, t_best));
            t_best = _mm256_blendv_ps(t_best, t, nearer);
            u_best = _mm256_blendv_ps(u_best, u, nearer);
            v_best = _mm256_blendv_ps(v_best, v, nearer);
            let i = _mm256_castsi256_ps(_mm256_set1_epi32(i as i32));
            packet_best = _mm256_blendv_ps(packet_best, i, nearer);
            hit_any = _mm256_or_ps(hit_any, hit);
        }
        if _mm256_movemask_ps(hit_any) == 0 {
            return None;
        }
        let m = min_of_lanes(t_best);
        let at_min = _mm256_and_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(t_best, m), hit_any);
        let at_min = _mm256_movemask_ps(at_min) as u32;
        let mut lane = at_min.trailing_zeros() as usize & (LANES - 1);
        let mut packet = lane_of(packet_best, lane).to_bits();
        if at_min.count_ones() > 1 {
            // Equal `t` in several lanes (rare): the first packet among them, then the lowest
            // lane.
            for other in lane + 1..LANES {
                let other_packet = lane_of(packet_best, other).to_bits();
                if at_min & (1 << other) != 0 && other_packet < packet {
                    (lane, packet) = (other, other_packet);
                }
            }
        }
        Some((
            packet as usize,
            LaneHit {
                lane,
                t: _mm256_cvtss_f32(m),
                u: lane_of(u_best, lane),
                v: lane_of(v_best, lane),
            },
        ))
    }

    /// The smallest of `a`'s lanes, in every lane.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn min_of_lanes(a: __m256) -> __m256 {
        let m = _mm256_min_ps(a, _mm256_permute2f128_ps::<1>(a, a));
        let m = _mm256_min_ps(m, _mm256_permute_ps::<0b01_00_11_10>(m));
        _mm256_min_ps(m, _mm256_permute_ps::<0b10_11_00_01>(m))
    }

    /// Lane `lane` of `a`, moved to lane 0 in registers (see `nearest16`). (Not a closure: a
    /// closure inside a `#[target_feature]` function may be compiled without its features.)
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn lane_of(a: __m256, lane: usize) -> f32 {
        _mm256_cvtss_f32(_mm256_permutevar8x32_ps(a, _mm256_set1_epi32(lane as i32)))
    }

    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub fn any(p: &Packet8, r: &RayK, t_limit: f32) -> bool {
        let (_, hit) = hits(p, r, t_limit);
        _mm256_movemask_ps(hit) != 0
    }

    /// The AVX-512 form of `hits`: sixteen lanes, the normals read from the packet.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    fn hits16(p: &Packet16, r: &RayK, t_limit: f32) -> ([__m512; 3], __mmask16) {
        let h = ray_lanes(
            r,
            rows16(&p.v0),
            rows16(&p.e1),
            rows16(&p.e2),
            rows16(&p.n),
            t_limit,
        );
        ([h.t.0, h.u.0, h.v.0], h.hit.0)
    }

    /// A packet's rows of x, y and z as lanes. (Not closures: a closure inside a
    /// `#[target_feature]` function may be compiled without its features.)
    #[inline(always)]
    fn rows8(rows: &[[f32; LANES]; 3]) -> Vec3x<Avx2F32> {
        Vec3x::new(
            Avx2F32::load(&rows[0]),
            Avx2F32::load(&rows[1]),
            Avx2F32::load(&rows[2]),
        )
    }

    #[inline(always)]
    fn rows16(rows: &[[f32; 16]; 3]) -> Vec3x<Avx512F32> {
        Vec3x::new(
            Avx512F32::load(&rows[0]),
            Avx512F32::load(&rows[1]),
            Avx512F32::load(&rows[2]),
        )
    }

    /// One ray, in every lane, against a lane per triangle.
    #[inline(always)]
    fn ray_lanes<R: Real>(
        r: &RayK,
        v0: Vec3x<R>,
        e1: Vec3x<R>,
        e2: Vec3x<R>,
        n: Vec3x<R>,
        t_limit: f32,
    ) -> Hits<R> {
        let origin = Vec3x::splat(Vec3::from(r.origin));
        let direction = Vec3x::splat(Vec3::from(r.direction));
        intersect_lanes(origin, direction, v0, e1, e2, n, R::splat(t_limit))
    }

    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    pub fn nearest16(p: &Packet16, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        let ([t, u, v], hit) = hits16(p, r, t_limit);
        if hit == 0 {
            return None;
        }
        let t = _mm512_mask_blend_ps(hit, _mm512_set1_ps(f32::INFINITY), t);
        let m = _mm512_reduce_min_ps(t);
        let at_min = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(hit, t, _mm512_set1_ps(m));
        let lane = (at_min as u32).trailing_zeros() as usize & 15;
        // The lane's u and v moved to lane 0 in registers: storing the vectors and reading one
        // float back would stall on the store (store forwarding).
        let pick = _mm512_set1_epi32(lane as i32);
        Some(LaneHit {
            lane,
            t: m,
            u: _mm512_cvtss_f32(_mm512_permutexvar_ps(pick, u)),
            v: _mm512_cvtss_f32(_mm512_permutexvar_ps(pick, v)),
        })
    }

    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    pub fn nearest16_among(
        packets: &[Packet16],
        r: &RayK,
        t_limit: f32,
    ) -> Option<(usize, LaneHit)> {
        let mut t_best = _mm512_set1_ps(f32::INFINITY);
        let (mut u_best, mut v_best) = (_mm512_setzero_ps(), _mm512_setzero_ps());
        let mut packet_best = _mm512_setzero_si512();
        let mut hit_any: __mmask16 = 0;
        for (i, p) in packets.iter().enumerate() {
            let ([t, u, v], hit) = hits16(p, r, t_limit);
            // Strictly nearer: a lane keeps its first packet's hit among equal `t`.
            let nearer = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(hit, t, t_best);
            t_best = _mm512_mask_blend_ps(nearer, t_best, t);
            u_best = _mm512_mask_blend_ps(nearer, u_best, u);
            v_best = _mm512_mask_blend_ps(nearer, v_best, v);
            packet_best = _mm512_mask_blend_epi32(nearer, packet_best, _mm512_set1_epi32(i as i32));
            hit_any |= hit;
        }
        if hit_any == 0 {
            return None;
        }
        let m = _mm512_reduce_min_ps(t_best);
        let at_min = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(hit_any, t_best, _mm512_set1_ps(m));
        // Equal `t` in several lanes (rare): the first packet among them, then the lowest lane.
        let first = match at_min.count_ones() {
            1 => at_min,
            _ => {
                let p = _mm512_mask_reduce_min_epu32(at_min, packet_best);
                _mm512_mask_cmpeq_epi32_mask(at_min, packet_best, _mm512_set1_epi32(p as i32))
            }
        };
        let lane = (first as u32).trailing_zeros() as usize & 15;
        // Moved to lane 0 in registers (see `nearest16`).
        let pick = _mm512_set1_epi32(lane as i32);
        let packet = _mm512_permutexvar_epi32(pick, packet_best);
        Some((
            _mm_cvtsi128_si32(_mm512_castsi512_si128(packet)) as usize,
            LaneHit {
                lane,
                t: m,
                u: _mm512_cvtss_f32(_mm512_permutexvar_ps(pick, u_best)),
                v: _mm512_cvtss_f32(_mm512_permutexvar_ps(pick, v_best)),
            },
        ))
    }

    #[inline]
    #[target_feature(enable = "avx512f,avx512dq")]
    pub fn any16(p: &Packet16, r: &RayK, t_limit: f32) -> bool {
        hits16(p, r, t_limit).1 != 0
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::portable::Portable;
    use super::*;
    use crate::geometry::{Ray, Triangle};
    use crate::intersect::intersect_triangle;
    use crate::sampling::Rng;

    fn v(rng: &mut Rng, s: f32) -> Vec3 {
        Vec3::new(rng.uniform(-s, s), rng.uniform(-s, s), rng.uniform(-s, s))
    }

    /// Random triangles (some tiny, some degenerate) and rays aimed near them.
    fn case(rng: &mut Rng) -> (Vec<Triangle>, Ray) {
        let tris: Vec<Triangle> = (0..16)
            .map(|i| {
                let c = v(rng, 1.0);
                let s = if i % 5 == 0 { 1e-3 } else { 0.5 };
                let (a, b) = (c + v(rng, s), c + v(rng, s));
                let b = if i % 7 == 0 { a } else { b };
                Triangle::new(c, a, b, 0)
            })
            .collect();
        let target = tris[(rng.next_u32() % 16) as usize].centroid() + v(rng, 0.1);
        let origin = v(rng, 3.0);
        (tris, Ray::new(origin, target - origin))
    }

    #[test]
    fn packet_kernels_equal_intersect_triangle_lane_by_lane() {
        let mut rng = Rng::new(11);
        let avx2 = Avx2::detect();
        let avx512 = Avx512::detect();
        let test = "packet_kernels_equal_intersect_triangle";
        if avx2.is_none() {
            crate::accel::skip_unless_required("avx2", test);
        }
        if avx512.is_none() {
            crate::accel::skip_unless_required("avx512", test);
        }
        let mut hits = 0;
        for _ in 0..20_000 {
            let (tris, ray) = case(&mut rng);
            let r = RayK::new(&ray);
            let limit = if rng.next_f32() < 0.5 {
                f32::INFINITY
            } else {
                rng.uniform(0.0, 5.0)
            };
            let ids: Vec<u32> = (0..16).collect();
            // The reference: the scalar test, first of the nearest.
            let mut want: Option<(usize, (f32, f32, f32))> = None;
            for (i, t) in tris.iter().enumerate() {
                let lim = want.map_or(limit, |(_, h)| h.0);
                if let Some(h) = intersect_triangle(&ray, t, lim) {
                    want = Some((i, h));
                }
            }
            let as_hit = |w: Option<(usize, (f32, f32, f32))>| {
                w.map(|(lane, (t, u, v))| LaneHit { lane, t, u, v })
            };
            let p16 = Packet16::new(&tris, &ids);
            assert_eq!(p16.nearest_scalar(&r, limit), as_hit(want));
            assert_eq!(p16.any_scalar(&r, limit), want.is_some());
            if let Some(k) = avx512 {
                assert_eq!(k.nearest16(&p16, &r, limit), as_hit(want));
                assert_eq!(k.any16(&p16, &r, limit), want.is_some());
            }
            // The first eight in an 8-wide packet.
            let want8 = {
                let mut w: Option<(usize, (f32, f32, f32))> = None;
                for (i, t) in tris[..8].iter().enumerate() {
                    let lim = w.map_or(limit, |(_, h)| h.0);
                    if let Some(h) = intersect_triangle(&ray, t, lim) {
                        w = Some((i, h));
                    }
                }
                w
            };
            let p8 = Packet8::new(&tris, &ids[..8]);
            assert_eq!(Scalar.nearest(&p8, &r, limit), as_hit(want8));
            assert_eq!(Portable.nearest(&p8, &r, limit), as_hit(want8));
            assert_eq!(Portable.any(&p8, &r, limit), want8.is_some());
            if let Some(k) = avx2 {
                assert_eq!(k.nearest(&p8, &r, limit), as_hit(want8));
                assert_eq!(k.any(&p8, &r, limit), want8.is_some());
            }
            hits += usize::from(want.is_some());
        }
        assert!(hits > 5_000, "{hits}");
    }

    /// The lanes' running nearest across packets gives exactly the packet-by-packet answer,
    /// ties included: the same triangles repeated in later packets and other lanes (equal `t`
    /// in several lanes and packets) must come back as their first copy.
    #[test]
    fn nearest_among_packets_equals_packet_by_packet() {
        let Some(k) = Avx512::detect() else {
            return crate::accel::skip_unless_required("avx512", "nearest_among_packets");
        };
        let mut rng = Rng::new(13);
        let (mut hits, mut ties) = (0, 0);
        for _ in 0..20_000 {
            let (mut tris, ray) = case(&mut rng);
            let n_packets = 1 + (rng.next_u32() % 4) as usize;
            // Copies of earlier triangles, so that equal `t` occur across lanes and packets.
            for i in 16..16 * n_packets {
                let t = if rng.next_f32() < 0.3 {
                    tris[(rng.next_u32() as usize) % i]
                } else {
                    case(&mut rng).0[i % 16]
                };
                tris.push(t);
            }
            let ids: Vec<u32> = (0..tris.len() as u32).collect();
            let packets: Vec<Packet16> = ids.chunks(16).map(|c| Packet16::new(&tris, c)).collect();
            let r = RayK::new(&ray);
            let limit = if rng.next_f32() < 0.5 {
                f32::INFINITY
            } else {
                rng.uniform(0.0, 5.0)
            };
            let want = nearest_packet_by_packet(&packets, limit, |p, l| k.nearest16(p, &r, l));
            let got = k.nearest16_among(&packets, &r, limit);
            assert_eq!(
                got.map(|(p, h)| (p, h.lane, h.t.to_bits(), h.u.to_bits(), h.v.to_bits())),
                want.map(|(p, h)| (p, h.lane, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
            );
            if let Some((p, h)) = want {
                hits += 1;
                let equal = tris
                    .iter()
                    .filter_map(|t| intersect_triangle(&ray, t, limit))
                    .filter(|&(t, _, _)| t == h.t)
                    .count();
                ties += usize::from(equal > 1);
                // And the brute-force loop's first nearest triangle.
                let mut first = None;
                for (i, t) in tris.iter().enumerate() {
                    let lim = first.map_or(limit, |(_, t)| t);
                    if let Some((t, _, _)) = intersect_triangle(&ray, t, lim) {
                        first = Some((i, t));
                    }
                }
                assert_eq!(first.map(|(i, _)| i), Some(p * 16 + h.lane));
            }
        }
        assert!(hits > 5_000 && ties > 500, "{hits} hits, {ties} with ties");
    }

    /// The same for the 8-wide packets: the AVX2 set's running nearest, and the default
    /// (the scalar twin's), against the packets one after another.
    #[test]
    fn nearest_among_8_wide_packets_equals_packet_by_packet() {
        let avx2 = Avx2::detect();
        if avx2.is_none() {
            crate::accel::skip_unless_required("avx2", "nearest_among_8_wide_packets");
        }
        let mut rng = Rng::new(14);
        let mut ties = 0;
        for _ in 0..20_000 {
            let (mut tris, ray) = case(&mut rng);
            for i in 16..16 + 8 * (rng.next_u32() % 3) as usize {
                tris.push(tris[(rng.next_u32() as usize) % i]);
            }
            let ids: Vec<u32> = (0..tris.len() as u32).collect();
            let packets: Vec<Packet8> = ids.chunks(LANES).map(|c| Packet8::new(&tris, c)).collect();
            let r = RayK::new(&ray);
            let limit = if rng.next_f32() < 0.5 {
                f32::INFINITY
            } else {
                rng.uniform(0.0, 5.0)
            };
            let bits = |h: Option<(usize, LaneHit)>| {
                h.map(|(p, h)| (p, h.lane, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
            };
            let want = nearest_packet_by_packet(&packets, limit, |p, l| Scalar.nearest(p, &r, l));
            assert_eq!(bits(Scalar.nearest_among(&packets, &r, limit)), bits(want));
            assert_eq!(bits(Portable.nearest_among(&packets, &r, limit)), bits(want));
            if let Some(k) = avx2 {
                assert_eq!(bits(k.nearest_among(&packets, &r, limit)), bits(want));
            }
            if let Some((_, h)) = want {
                let equal = tris
                    .iter()
                    .filter_map(|t| intersect_triangle(&ray, t, limit));
                ties += usize::from(equal.filter(|&(t, _, _)| t == h.t).count() > 1);
            }
        }
        assert!(ties > 500, "{ties} with ties");
    }

    #[test]
    fn box_kernels_agree_with_the_scalar_twin() {
        let mut rng = Rng::new(12);
        let avx2 = Avx2::detect();
        if avx2.is_none() {
            crate::accel::skip_unless_required("avx2", "box_kernels_agree");
        }
        let mut disagreements = 0;
        for _ in 0..20_000 {
            let mut node = Node8 {
                bounds: [[0.0; LANES]; 6],
                child: [0; LANES],
            };
            for i in 0..LANES {
                let (a, b) = (v(&mut rng, 1.0), v(&mut rng, 1.0));
                let (lo, hi) = (a.min(b), a.max(b));
                for axis in 0..3 {
                    node.bounds[axis][i] = lo[axis];
                    node.bounds[axis + 3][i] = hi[axis];
                }
            }
            let mut d = v(&mut rng, 1.0);
            if rng.next_f32() < 0.2 {
                d.x = 0.0;
            }
            let r = RayK::new(&Ray::new(v(&mut rng, 2.0), d));
            let limit = rng.uniform(0.0, 4.0);
            let (ms, ts) = Scalar.boxes(&node, &r, limit);
            // The portable kernels compute the scalar twin's form: the same answers exactly.
            let (mp, tp) = Portable.boxes(&node, &r, limit);
            assert_eq!(mp, ms);
            for i in (0..LANES).filter(|i| ms & (1 << i) != 0) {
                assert_eq!(tp[i].to_bits(), ts[i].to_bits());
            }
            let Some(k) = avx2 else { continue };
            let (mv, tv) = k.boxes(&node, &r, limit);
            for i in 0..LANES {
                if (ms ^ mv) & (1 << i) != 0 {
                    disagreements += 1;
                } else if ms & (1 << i) != 0 {
                    assert!((ts[i] - tv[i]).abs() <= 1e-5 * ts[i].abs().max(1.0));
                }
            }
        }
        // The two forms round differently: they may differ only for a ray grazing a box.
        assert!(disagreements < 20, "{disagreements}");
    }
}
