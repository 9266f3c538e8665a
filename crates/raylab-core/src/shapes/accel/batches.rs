//! The batch queries: [`Accel::closest_batch`], [`Accel::closest_lanes`],
//! [`Accel::occluded_batch`] and [`Accel::occluded_lanes`]. Each is written once, generic over
//! the instruction set ([`InstructionSet`]), and entered through [`super::Isa::call`], so the
//! kernels, the packet traversal and the culling inline into one function per set. A single
//! query is a batch of one, so each is written once.

use super::bvh::Bvh;
use super::cull::{self, Cone};
use super::segments::SegmentLanes;
use super::set::{Compiled, InstructionSet};
use super::wide::Flat;
use super::{Accel, Hit, HitLanes, Structure, packet};
use crate::base::geometry::{Ray, Triangle};
use crate::shapes::intersect;

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
        self.isa.call(ClosestBatch {
            s: &self.structure,
            triangles,
            rays,
            t_max,
            out,
        })
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
        self.isa.call(ClosestLanes {
            s: &self.structure,
            triangles,
            rays,
            t_max,
            out,
        })
    }

    /// [`Accel::occluded`] for many rays, each with its own `t_max`: `out[i]` for `rays[i]`,
    /// the same answers, the choice of structure and kernels made once for the batch.
    #[inline(never)]
    pub fn occluded_batch(&self, triangles: &[Triangle], rays: &[(Ray, f32)], out: &mut [bool]) {
        debug_assert_eq!(rays.len(), out.len());
        self.isa.call(OccludedBatch {
            s: &self.structure,
            triangles,
            rays,
            out,
        })
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
            && self.isa.call(OccludedLanes {
                f,
                groups,
                neighbours,
                blocked,
            })
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

/// [`Accel::closest_batch`]'s body ([`closest_packets`]) for each set.
struct ClosestBatch<'a> {
    s: &'a Structure,
    triangles: &'a [Triangle],
    rays: &'a [Ray],
    t_max: f32,
    out: &'a mut [Option<Hit>],
}

impl Compiled for ClosestBatch<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) {
        closest_packets(k, self.s, self.triangles, self.rays, self.t_max, self.out)
    }
}

/// [`Accel::closest_lanes`]'s body ([`closest_lanes_packets`]) for each set.
struct ClosestLanes<'a> {
    s: &'a Structure,
    triangles: &'a [Triangle],
    rays: &'a [Ray],
    t_max: f32,
    out: &'a mut [HitLanes],
}

impl Compiled for ClosestLanes<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) {
        closest_lanes_packets(k, self.s, self.triangles, self.rays, self.t_max, self.out)
    }
}

/// [`Accel::occluded_batch`]'s body ([`occluded_packets`]) for each set.
struct OccludedBatch<'a> {
    s: &'a Structure,
    triangles: &'a [Triangle],
    rays: &'a [(Ray, f32)],
    out: &'a mut [bool],
}

impl Compiled for OccludedBatch<'_> {
    type Output = ();
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) {
        occluded_packets(k, self.s, self.triangles, self.rays, self.out)
    }
}

/// [`Accel::occluded_lanes`]'s body on the flat list ([`occluded_lanes_in`]) for each set.
struct OccludedLanes<'a, 'g> {
    f: &'a Flat,
    groups: &'a [SegmentLanes<'g>],
    neighbours: bool,
    blocked: &'a mut [u16],
}

impl Compiled for OccludedLanes<'_, '_> {
    type Output = bool;
    #[inline(always)]
    fn run<S: InstructionSet>(self, k: S) -> bool {
        occluded_lanes_in(k, self.f, self.groups, self.neighbours, self.blocked)
    }
}

/// The closest hits of the structures without kernels, a ray at a time: the brute-force loop,
/// or the binary BVH's readable traversal. Out of line, so that each set's batches hand these
/// structures over rather than compile them in.
#[inline(never)]
fn closest_without_kernels(
    bvh: Option<&Bvh>,
    triangles: &[Triangle],
    rays: &[Ray],
    t_max: f32,
    out: &mut [Option<Hit>],
) {
    for (ray, hit) in rays.iter().zip(out) {
        *hit = match bvh {
            Some(b) => b.closest(triangles, ray, t_max),
            None => {
                intersect::closest_intersection_brute_force(ray, triangles, t_max).map(|h| Hit {
                    index: h.triangle_index as u32,
                    t: h.distance,
                    u: h.u,
                    v: h.v,
                })
            }
        };
    }
}

/// [`closest_without_kernels`] for shadow rays.
#[inline(never)]
fn occluded_without_kernels(
    bvh: Option<&Bvh>,
    triangles: &[Triangle],
    rays: &[(Ray, f32)],
    out: &mut [bool],
) {
    for ((ray, t_max), blocked) in rays.iter().zip(out) {
        *blocked = match bvh {
            Some(b) => b.occluded(triangles, ray, *t_max),
            None => intersect::occluded_brute_force(ray, triangles, *t_max),
        };
    }
}

/// Closest hits of a batch with a SIMD kernel set: the flat list culled for the batch where
/// the batch has a cone, the wide BVH a packet of coherent rays at a time, the rest ray by ray.
#[inline(always)]
fn closest_packets<P: InstructionSet>(
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
        Structure::BruteForce => closest_without_kernels(None, triangles, rays, t_max, out),
        Structure::Bvh2(b) => closest_without_kernels(Some(b), triangles, rays, t_max, out),
    }
}

/// [`closest_packets`] into lanes ([`Accel::closest_lanes`]): a culled flat list's packets
/// keep their lanes; any other batch is answered by [`closest_packets`], sixteen rays at a time,
/// and its hits put in lanes.
#[inline(always)]
fn closest_lanes_packets<P: InstructionSet>(
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
fn occluded_packets<P: InstructionSet>(
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
        Structure::BruteForce => occluded_without_kernels(None, triangles, rays, out),
        Structure::Bvh2(b) => occluded_without_kernels(Some(b), triangles, rays, out),
    }
}

/// The flat list's culled closest hits for a batch of rays from one point ([`cull`]): the
/// triangles the batch's cone may reach, a triangle at a time against a packet of rays. False
/// (nothing done) when the list is too long to cull or the rays have no cone.
#[inline(always)]
fn flat_closest_culled<P: InstructionSet>(
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
fn flat_occluded_culled<P: InstructionSet>(
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
fn occluded_lanes_in<P: InstructionSet>(
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
