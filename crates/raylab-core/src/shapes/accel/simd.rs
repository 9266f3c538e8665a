//! The two inner loops of tracing, eight lanes at a time: a ray against the eight boxes of a
//! wide node, and a ray against a packet of eight triangles — their data ([`Node8`],
//! [`Packet`], [`RayK`]), the x86 sets' proof types ([`Avx2`], [`Avx512`]: a value exists only
//! on a CPU that runs the set) and the readable scalar twin of the kernels ([`Scalar`]): plain
//! loops over the lanes, the definition the tests compare every set with.
//!
//! The kernels every set runs are written once, generic over the set's lanes
//! ([`super::kernels`]). The triangle kernels are the scalar test's own source,
//! [`crate::shapes::intersect::intersect_lanes`], a lane per triangle (no fused multiply-add), so every
//! lane's `t`, `u`, `v` are bit-identical to [`crate::shapes::intersect::intersect_triangle`]'s: the
//! fast path accepts the very same edges and returns the very same hits as the brute-force loop.

use glam::Vec3;

use crate::shapes::intersect::intersect_lanes;

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

/// The packet of the wide BVH's leaves and the eight-lane kernels.
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
    pub fn new(triangles: &[crate::base::geometry::Triangle], indices: &[u32]) -> Self {
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
    pub fn new(triangles: &[crate::base::geometry::Triangle], indices: &[u32]) -> Self {
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
    pub fn for_triangles(ray: &crate::base::geometry::Ray) -> Self {
        Self {
            origin: ray.origin.to_array(),
            direction: ray.direction.to_array(),
            inv: [0.0; 3],
            origin_inv: [0.0; 3],
            near: [0, 1, 2],
            far: [3, 4, 5],
        }
    }

    pub fn new(ray: &crate::base::geometry::Ray) -> Self {
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

impl Scalar {
    /// Bit `i` set when the ray enters child box `i` within `[0, t_limit]`, and each box's
    /// entry distance.
    #[inline(always)]
    pub fn boxes(self, node: &Node8, r: &RayK, t_limit: f32) -> (u32, [f32; LANES]) {
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

    /// The nearest hit in the packet with `0 < t < t_limit`, the lowest lane among equal `t`.
    #[inline(always)]
    pub fn nearest(self, p: &Packet8, r: &RayK, t_limit: f32) -> Option<LaneHit> {
        p.nearest_scalar(r, t_limit)
    }

    /// The nearest hit among `packets`: the packet's position in the slice, and the hit; among
    /// equal `t`, the first packet's, then its lowest lane's.
    #[inline(always)]
    pub fn nearest_among(
        self,
        packets: &[Packet8],
        r: &RayK,
        t_limit: f32,
    ) -> Option<(usize, LaneHit)> {
        nearest_packet_by_packet(packets, t_limit, |p, limit| self.nearest(p, r, limit))
    }

    /// Whether any triangle of the packet is hit with `0 < t < t_limit`.
    #[inline(always)]
    pub fn any(self, p: &Packet8, r: &RayK, t_limit: f32) -> bool {
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
}

/// The nearest hit among `packets`, one packet after another, each tested by `nearest` with
/// the limit of the nearest hit so far (strict, so the first of equal hits wins): the readable
/// definition of [`super::kernels::nearest_among`].
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::kernels;
    use super::super::portable::Portable;
    use super::*;
    use crate::base::geometry::{Ray, Triangle};
    use crate::base::sampling::Rng;
    use crate::shapes::intersect::intersect_triangle;

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
            crate::shapes::accel::skip_unless_required("avx2", test);
        }
        if avx512.is_none() {
            crate::shapes::accel::skip_unless_required("avx512", test);
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
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = avx512 {
                assert_eq!(kernels::nearest(k, &p16, &r, limit), as_hit(want));
                assert_eq!(kernels::any(k, &p16, &r, limit), want.is_some());
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
            assert_eq!(kernels::nearest(Portable, &p8, &r, limit), as_hit(want8));
            assert_eq!(kernels::any(Portable, &p8, &r, limit), want8.is_some());
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = avx2 {
                assert_eq!(kernels::nearest(k, &p8, &r, limit), as_hit(want8));
                assert_eq!(kernels::any(k, &p8, &r, limit), want8.is_some());
            }
            hits += usize::from(want.is_some());
        }
        assert!(hits > 5_000, "{hits}");
    }

    /// The lanes' running nearest across packets gives exactly the packet-by-packet answer,
    /// ties included: the same triangles repeated in later packets and other lanes (equal `t`
    /// in several lanes and packets) must come back as their first copy.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn nearest_among_packets_equals_packet_by_packet() {
        let Some(k) = Avx512::detect() else {
            return crate::shapes::accel::skip_unless_required("avx512", "nearest_among_packets");
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
            let want =
                nearest_packet_by_packet(&packets, limit, |p, l| kernels::nearest(k, p, &r, l));
            let got = kernels::nearest_among(k, &packets, &r, limit);
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
            crate::shapes::accel::skip_unless_required("avx2", "nearest_among_8_wide_packets");
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
            assert_eq!(
                bits(kernels::nearest_among(Portable, &packets, &r, limit)),
                bits(want)
            );
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = avx2 {
                assert_eq!(
                    bits(kernels::nearest_among(k, &packets, &r, limit)),
                    bits(want)
                );
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
            crate::shapes::accel::skip_unless_required("avx2", "box_kernels_agree");
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
            let (mp, tp) = kernels::boxes(Portable, &node, &r, limit);
            assert_eq!(mp, ms);
            for i in (0..LANES).filter(|i| ms & (1 << i) != 0) {
                assert_eq!(tp[i].to_bits(), ts[i].to_bits());
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = avx2 {
                let (mv, tv) = kernels::boxes(k, &node, &r, limit);
                for i in 0..LANES {
                    if (ms ^ mv) & (1 << i) != 0 {
                        disagreements += 1;
                    } else if ms & (1 << i) != 0 {
                        assert!((ts[i] - tv[i]).abs() <= 1e-5 * ts[i].abs().max(1.0));
                    }
                }
            }
        }
        // The two forms round differently: they may differ only for a ray grazing a box.
        assert!(disagreements < 20, "{disagreements}");
    }
}
