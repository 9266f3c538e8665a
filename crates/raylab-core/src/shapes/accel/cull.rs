//! Culling for a whole batch: the triangles that no ray of a batch can reach, found once and
//! skipped by every ray of it.
//!
//! The flat loop ([`super::wide::Flat`]) tests every triangle for every ray, yet a batch of 64
//! neighbouring camera rays (a stretch of one image row) sees only the few triangles its thin
//! fan of directions crosses, and the shadow rays of those pixels all run to one point, the
//! light. Such a batch fits in a [`Cone`]: an apex and a box of slopes about one axis. A
//! triangle wholly outside the cone cannot be hit by any ray of the batch, so the batch is
//! traced against the others alone — in the Cornell box one 16-wide packet instead of two.
//!
//! The cone is conservative by a margin far above rounding, and the rays are then tested with
//! the very kernels as before, in the same triangle order, so each ray's hit is the brute-force
//! loop's bit for bit (the tests below check culled triangles against
//! [`crate::shapes::intersect::intersect_triangle`]; `tests/packets.rs` checks whole views).
//!
//! How a batch is bounded:
//!
//! * **Rays from one point** (a pinhole camera's): the apex is the common origin and each ray
//!   lies in the cone of the directions.
//! * **Segments to one point** (the shadow rays to a point light): each ends within a small
//!   distance δ of the first one's end, the apex. The cone of the directions from the apex to
//!   the starts holds every start, and every end lies within δ of the apex, so each segment
//!   lies within δ of the cone (the set of points within δ of a convex cone is convex): a
//!   triangle must lie more than δ outside to be culled.
//!
//! Anything else (the path tracer's scattered bounces, a thin lens's rays) gets no cone and is
//! traced against every triangle, as before.

use glam::Vec3;

use crate::base::geometry::Ray;

/// Rays below which a batch is not worth bounding: the cone costs about what testing a few
/// rays against one more packet would.
pub const MIN_RAYS: usize = 4;

/// The widest a cone may open, as a slope (tan of the half angle) about its axis: a wider
/// batch culls little, and a nearly flat cone bounds badly.
const MAX_SLOPE: f32 = 2.0;

/// Relative margin on every test: rounding in the cone and in the ray–triangle test (whose
/// triangles are widened by [`crate::shapes::intersect::EDGE_TOLERANCE`] of their size) is below 1e-5
/// of the distances involved; 1e-4 keeps a tenfold reserve and still culls what a batch of
/// neighbouring pixels cannot see.
const MARGIN: f32 = 1e-4;

/// Ends of segments farther than this share of the starts' distance from the apex are not
/// treated as meeting at one point.
const MAX_END_SPREAD: f32 = 1e-2;

/// Every ray (or segment) of a batch, bounded: the points `apex + s·(x, y, z)` in the axis's
/// frame with `s ≥ 0`, `z = 1` along the axis and `(x, y)` in the slope box, widened by
/// `delta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    apex: Vec3,
    /// The axis (0, 1, 2) the cone opens along, and its direction along it (±1).
    axis: usize,
    sign: f32,
    /// Slope boxes: `x / z` within `x_range`, `y / z` within `y_range`, where `x` and `y` are
    /// the coordinates after the axis (`axis + 1`, `axis + 2`, cyclically).
    x_range: (f32, f32),
    y_range: (f32, f32),
    /// How far outside the cone a segment may reach (0 for rays from the apex).
    delta: f32,
}

/// The slopes of directions in a cone's frame, accumulated: the readable loop of
/// [`Cone::around_rays`] and the lanes of the SIMD one both feed this.
#[derive(Clone, Copy, Debug)]
struct Slopes {
    x: (f32, f32),
    y: (f32, f32),
}

impl Slopes {
    const NONE: Slopes = Slopes {
        x: (f32::INFINITY, f32::NEG_INFINITY),
        y: (f32::INFINITY, f32::NEG_INFINITY),
    };
}

impl Cone {
    /// The frame of a cone from `apex` opening toward `middle` (the sum of the first and the
    /// last direction: the middle of a fan, for a stretch of an image row): the axis of its
    /// largest coordinate and its sign.
    fn frame(apex: Vec3, middle: Vec3, delta: f32) -> Cone {
        let axis = middle.abs().max_position();
        Cone {
            apex,
            axis,
            sign: if middle[axis] >= 0.0 { 1.0 } else { -1.0 },
            x_range: (0.0, 0.0),
            y_range: (0.0, 0.0),
            delta,
        }
    }

    /// The apex and frame of the cone of segments whose first is `first` and whose last starts
    /// at `last_start`: the apex is the first one's end, the frame opens toward the middle of
    /// the starts ([`Cone::frame`]).
    fn segments_frame((first, t_first): (Ray, f32), last_start: Vec3) -> (Vec3, Cone) {
        let apex = first.at(t_first);
        let middle = (first.origin - apex) + (last_start - apex);
        (apex, Self::frame(apex, middle, 0.0))
    }

    /// The cone of rays that all start at one point, or `None` if they do not, or open too
    /// wide. The readable form; the renderer's batches use the SIMD one, the same operations
    /// a ray per lane ([`Cone::around_rays_simd`]).
    pub fn around_rays(rays: &[Ray]) -> Option<Cone> {
        let first = rays.first()?;
        if rays.len() < MIN_RAYS || rays.iter().any(|r| r.origin != first.origin) {
            return None;
        }
        let last = rays[rays.len() - 1].direction;
        let cone = Self::frame(first.origin, first.direction + last, 0.0);
        let mut slopes = Slopes::NONE;
        for r in rays {
            let (x, y, z) = cone.local(r.direction);
            let (sx, sy) = (x / z, y / z);
            // NaN fails too.
            if !(z > 0.0 && sx.abs() <= MAX_SLOPE && sy.abs() <= MAX_SLOPE) {
                return None;
            }
            slopes.x = (slopes.x.0.min(sx), slopes.x.1.max(sx));
            slopes.y = (slopes.y.0.min(sy), slopes.y.1.max(sy));
        }
        Some(cone.with(slopes))
    }

    /// The cone of segments `(ray, t_max)` (from `ray.origin` to `ray.at(t_max)`) that all end
    /// near one point — within a hundredth of the distance to their starts — such as the
    /// shadow rays to a point light; or `None`. The apex is the first one's end.
    pub fn around_segments(segments: &[(Ray, f32)]) -> Option<Cone> {
        let first = *segments.first()?;
        if segments.len() < MIN_RAYS {
            return None;
        }
        let (apex, mut cone) = Self::segments_frame(first, segments[segments.len() - 1].0.origin);
        let (mut spread2, mut near2) = (0.0f32, f32::INFINITY);
        let mut slopes = Slopes::NONE;
        for (r, t) in segments {
            let end = r.origin + *t * r.direction;
            spread2 = spread2.max((end - apex).length_squared());
            let start = r.origin - apex;
            near2 = near2.min(start.length_squared());
            let (x, y, z) = cone.local(start);
            let (sx, sy) = (x / z, y / z);
            if !(z > 0.0 && sx.abs() <= MAX_SLOPE && sy.abs() <= MAX_SLOPE) {
                return None;
            }
            slopes.x = (slopes.x.0.min(sx), slopes.x.1.max(sx));
            slopes.y = (slopes.y.0.min(sy), slopes.y.1.max(sy));
        }
        cone.delta = Self::spread_delta(spread2, near2)?;
        Some(cone.with(slopes))
    }

    /// δ for ends spread over `√spread2` around the apex, starts at least `√near2` from it:
    /// a little more than the spread (the ends were computed with rounding too), or `None`
    /// when the ends do not meet closely enough.
    fn spread_delta(spread2: f32, near2: f32) -> Option<f32> {
        // NaN fails too.
        if !(spread2 <= MAX_END_SPREAD * MAX_END_SPREAD * near2) {
            return None;
        }
        Some(spread2.sqrt() * (1.0 + MARGIN) + MARGIN * MARGIN * near2.sqrt())
    }

    /// The cone with the slope box `slopes`, widened by far more than their rounding.
    fn with(mut self, slopes: Slopes) -> Cone {
        let widen = |(lo, hi): (f32, f32)| {
            (
                lo - MARGIN * (1.0 + lo.abs()),
                hi + MARGIN * (1.0 + hi.abs()),
            )
        };
        self.x_range = widen(slopes.x);
        self.y_range = widen(slopes.y);
        self
    }

    /// `v` in the cone's frame: (x, y, z) with z along the axis, toward where the cone opens.
    #[inline(always)]
    fn local(&self, v: Vec3) -> (f32, f32, f32) {
        let a = self.axis;
        (v[(a + 1) % 3], v[(a + 2) % 3], self.sign * v[a])
    }

    /// The cone's sides as `(slope, across, norm)`: the cone lies where
    /// `across · (c − slope·z) ≤ 0` for `c` the coordinate `x` (first two) or `y` (last two),
    /// and `norm = |(1, slope)|` turns that value into a distance.
    fn sides(&self) -> [(f32, f32, f32); 4] {
        let norm = |s: f32| (1.0 + s * s).sqrt();
        let (x_lo, x_hi) = self.x_range;
        let (y_lo, y_hi) = self.y_range;
        [
            (x_hi, 1.0, norm(x_hi)),
            (x_lo, -1.0, norm(x_lo)),
            (y_hi, 1.0, norm(y_hi)),
            (y_lo, -1.0, norm(y_lo)),
        ]
    }

    /// Whether a ray of the batch may hit the triangle with corners `corners` and size `size`
    /// (its longest edge along an axis, [`super::wide::triangle_size`]); `false` only when all three
    /// corners lie beyond one side of the cone (or behind its apex) by more than δ and the
    /// margins. The readable form of the SIMD test ([`Cone::may_hit_lanes`]).
    pub fn may_hit(&self, corners: [Vec3; 3], size: f32) -> bool {
        let sides = self.sides();
        let mut outside = [true; 5];
        for corner in corners {
            let (x, y, z) = self.local(corner - self.apex);
            // How far past a side the corner must be: δ, and MARGIN of its distance and of
            // the triangle's size (the ray test widens triangles by EDGE_TOLERANCE of it).
            let base = self.delta + MARGIN * (size + ((x.abs() + y.abs()) + z.abs()));
            for (k, &(slope, across, norm)) in sides.iter().enumerate() {
                let c = if k < 2 { x } else { y };
                outside[k] &= across * (c - slope * z) > base * norm;
            }
            outside[4] &= -z > base;
        }
        !outside.iter().any(|&o| o)
    }
}

mod lanes {
    use super::super::set::{InstructionSet, MAX_WIDTH};
    use crate::base::lanes::{Mask, Real};

    use super::super::SegmentLanes;
    use super::super::wide::Corners;
    use super::{Cone, MARGIN, MAX_SLOPE, MIN_RAYS, Slopes};
    use crate::base::geometry::Ray;

    /// Lane-wise slope bounds: `lo`/`hi` of x and y, and whether every lane so far is valid.
    struct Acc<P: InstructionSet> {
        x_lo: P::F,
        x_hi: P::F,
        y_lo: P::F,
        y_hi: P::F,
        bad: u32,
    }

    impl<P: InstructionSet> Acc<P> {
        #[inline(always)]
        fn new(k: P) -> Self {
            Acc {
                x_lo: k.splat(f32::INFINITY),
                x_hi: k.splat(f32::NEG_INFINITY),
                y_lo: k.splat(f32::INFINITY),
                y_hi: k.splat(f32::NEG_INFINITY),
                bad: 0,
            }
        }

        /// The same tests and slopes as the readable loops, a direction `(x, y, z)` per lane.
        #[inline(always)]
        fn add(&mut self, k: P, direction: (P::F, P::F, P::F)) {
            self.add_lanes(k, direction, (1 << P::WIDTH) - 1);
        }

        /// [`Acc::add`] for the lanes of `active` only.
        #[inline(always)]
        fn add_lanes(&mut self, k: P, (x, y, z): (P::F, P::F, P::F), active: u32) {
            let (sx, sy) = (x / z, y / z);
            let max = k.splat(MAX_SLOPE);
            let good = z.simd_gt(k.splat(0.0)) & (sx.abs().simd_le(max) & sy.abs().simd_le(max));
            self.bad |= !good.bitmask() & active;
            let (m, inf) = (P::Mask::from_bitmask(active), k.splat(f32::INFINITY));
            let neg_inf = k.splat(f32::NEG_INFINITY);
            self.x_lo = self.x_lo.min_or_other(P::F::select(m, sx, inf));
            self.x_hi = self.x_hi.max_or_other(P::F::select(m, sx, neg_inf));
            self.y_lo = self.y_lo.min_or_other(P::F::select(m, sy, inf));
            self.y_hi = self.y_hi.max_or_other(P::F::select(m, sy, neg_inf));
        }

        /// The slopes over all lanes, or `None` if any lane failed.
        #[inline(always)]
        fn finish(self, k: P) -> Option<Slopes> {
            if self.bad != 0 {
                return None;
            }
            Some(Slopes {
                x: (least(k, self.x_lo), greatest(k, self.x_hi)),
                y: (least(k, self.y_lo), greatest(k, self.y_hi)),
            })
        }
    }

    // No closures below: a closure inside a `#[target_feature]` function is compiled without
    // the features, and the intrinsics it calls stay out of line.

    /// The least lane.
    #[inline(always)]
    fn least<P: InstructionSet>(k: P, v: P::F) -> f32 {
        k.min_of(P::Mask::from_bitmask((1 << P::WIDTH) - 1), v)
    }

    /// The greatest lane (exactly: −least(−v)).
    #[inline(always)]
    fn greatest<P: InstructionSet>(k: P, v: P::F) -> f32 {
        -least(k, -v)
    }

    /// `a − b` per axis.
    #[inline(always)]
    fn sub3<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }

    /// `|v|²` as `Vec3::length_squared` computes it.
    #[inline(always)]
    fn length2<R: Real>(v: [R; 3]) -> R {
        v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    }

    #[inline(always)]
    fn splat3<P: InstructionSet>(k: P, v: glam::Vec3) -> [P::F; 3] {
        [k.splat(v.x), k.splat(v.y), k.splat(v.z)]
    }

    /// Lanes `offset..offset + WIDTH` of `a`.
    #[inline(always)]
    fn load_at<P: InstructionSet>(k: P, a: &[f32; 16], offset: usize) -> P::F {
        let mut row = [0.0f32; MAX_WIDTH];
        row[..P::WIDTH].copy_from_slice(&a[offset..offset + P::WIDTH]);
        k.load(&row)
    }

    /// Lanes `(a, b, c)` in the cone's frame, as [`Cone::local`].
    #[inline(always)]
    fn local<P: InstructionSet>(k: P, cone: &Cone, v: [P::F; 3]) -> (P::F, P::F, P::F) {
        let a = cone.axis;
        (v[(a + 1) % 3], v[(a + 2) % 3], k.splat(cone.sign) * v[a])
    }

    impl Cone {
        /// [`Cone::around_rays`], a ray per lane: the same cone, bit for bit.
        #[inline(always)]
        pub(in crate::shapes::accel) fn around_rays_simd<P: InstructionSet>(
            k: P,
            rays: &[Ray],
        ) -> Option<Cone> {
            let first = rays.first()?;
            if rays.len() < MIN_RAYS {
                return None;
            }
            let last = rays[rays.len() - 1].direction;
            let cone = Self::frame(first.origin, first.direction + last, 0.0);
            let apex = splat3(k, first.origin);
            let mut acc = Acc::new(k);
            for chunk in rays.chunks(P::WIDTH) {
                // Lanes past the end repeat the last ray: the bounds do not change.
                let [ox, oy, oz, dx, dy, dz] = k.rays(chunk);
                // Every origin the apex (`==` as `Vec3`'s: a NaN is never equal).
                let same = ox.simd_eq(apex[0]) & (oy.simd_eq(apex[1]) & oz.simd_eq(apex[2]));
                acc.bad |= !same.bitmask() & ((1 << P::WIDTH) - 1);
                acc.add(k, local(k, &cone, [dx, dy, dz]));
                if acc.bad != 0 {
                    return None;
                }
            }
            Some(cone.with(acc.finish(k)?))
        }

        /// [`Cone::around_segments`], a segment per lane: the same cone, bit for bit.
        #[inline(always)]
        pub(in crate::shapes::accel) fn around_segments_simd<P: InstructionSet>(
            k: P,
            segments: &[(Ray, f32)],
        ) -> Option<Cone> {
            let first = *segments.first()?;
            if segments.len() < MIN_RAYS {
                return None;
            }
            let (apex, mut cone) =
                Self::segments_frame(first, segments[segments.len() - 1].0.origin);
            // A few starts first, one at a time: scattered shadow rays (the path tracer's
            // after its first bounce) fail here, before a whole batch is gathered. Failing
            // here means failing below too: the same test on the same starts.
            for i in [
                0,
                segments.len() / 3,
                2 * segments.len() / 3,
                segments.len() - 1,
            ] {
                let (x, y, z) = cone.local(segments[i].0.origin - apex);
                let (sx, sy) = (x / z, y / z);
                if !(z > 0.0 && sx.abs() <= MAX_SLOPE && sy.abs() <= MAX_SLOPE) {
                    return None;
                }
            }
            let mut acc = Acc::new(k);
            let (mut spread2, mut near2) = (k.splat(0.0), k.splat(f32::INFINITY));
            let a = splat3(k, apex);
            for chunk in segments.chunks(P::WIDTH) {
                let [ox, oy, oz, dx, dy, dz, t] = k.segments(chunk);
                // end = origin + t·direction, as `Vec3` computes it: lane by lane.
                let end = [ox + t * dx, oy + t * dy, oz + t * dz];
                spread2 = spread2.max_or_other(length2(sub3(end, a)));
                let start = sub3([ox, oy, oz], a);
                near2 = near2.min_or_other(length2(start));
                acc.add(k, local(k, &cone, start));
                if acc.bad != 0 {
                    return None; // the path tracer's scattered shadow rays stop here
                }
            }
            cone.delta = Self::spread_delta(greatest(k, spread2), least(k, near2))?;
            Some(cone.with(acc.finish(k)?))
        }

        /// [`Cone::around_segments`] for shadow rays given as lanes ([`SegmentLanes`], the
        /// lanes of `cast` only): the apex is the first ray's end, the frame from the first and
        /// the last ray's starts, as for a slice of the same rays in the same order.
        #[inline(always)]
        pub(in crate::shapes::accel) fn around_segment_lanes<P: InstructionSet>(
            k: P,
            groups: &[SegmentLanes],
        ) -> Option<Cone> {
            let count: u32 = groups.iter().map(|g| g.cast.count_ones()).sum();
            if (count as usize) < MIN_RAYS {
                return None;
            }
            let first = groups.iter().find(|g| g.cast != 0)?;
            let last = groups.iter().rev().find(|g| g.cast != 0)?;
            let first = first.ray(first.cast.trailing_zeros() as usize);
            let last = last.ray(15 - last.cast.leading_zeros() as usize);
            let (apex, mut cone) = Self::segments_frame(first, last.0.origin);
            let mut acc = Acc::new(k);
            let (mut spread2, mut near2) = (k.splat(0.0), k.splat(f32::INFINITY));
            let a = splat3(k, apex);
            for g in groups {
                for offset in (0..16).step_by(P::WIDTH) {
                    let active = (u32::from(g.cast) >> offset) & ((1 << P::WIDTH) - 1);
                    if active == 0 {
                        continue;
                    }
                    let m = P::Mask::from_bitmask(active);
                    let ox = load_at(k, g.origin[0], offset);
                    let oy = load_at(k, g.origin[1], offset);
                    let oz = load_at(k, g.origin[2], offset);
                    let dx = load_at(k, g.direction[0], offset);
                    let dy = load_at(k, g.direction[1], offset);
                    let dz = load_at(k, g.direction[2], offset);
                    let t = load_at(k, g.t_max, offset);
                    let end = [ox + t * dx, oy + t * dy, oz + t * dz];
                    let s2 = length2(sub3(end, a));
                    spread2 = spread2.max_or_other(P::F::select(m, s2, k.splat(0.0)));
                    let start = sub3([ox, oy, oz], a);
                    let n2 = length2(start);
                    near2 = near2.min_or_other(P::F::select(m, n2, k.splat(f32::INFINITY)));
                    acc.add_lanes(k, local(k, &cone, start), active);
                    if acc.bad != 0 {
                        return None;
                    }
                }
            }
            cone.delta = Self::spread_delta(greatest(k, spread2), least(k, near2))?;
            Some(cone.with(acc.finish(k)?))
        }

        /// [`Cone::may_hit`] for the triangles of `corners` (lanes `offset..offset + WIDTH`),
        /// as a bit per lane: the same operations, so the same answers.
        #[inline(always)]
        pub(in crate::shapes::accel) fn may_hit_lanes<P: InstructionSet>(
            &self,
            k: P,
            corners: &Corners,
            offset: usize,
        ) -> u32 {
            let apex = splat3(k, self.apex);
            let sides = self.sides();
            let size = load_at(k, &corners.size, offset);
            let (delta, margin) = (k.splat(self.delta), k.splat(MARGIN));
            let none = P::Mask::from_bitmask(0);
            let mut outside = [P::Mask::from_bitmask((1 << P::WIDTH) - 1); 5];
            for corner in &corners.at {
                let v = [
                    load_at(k, &corner[0], offset),
                    load_at(k, &corner[1], offset),
                    load_at(k, &corner[2], offset),
                ];
                let (x, y, z) = local(k, self, sub3(v, apex));
                let distance = x.abs() + y.abs() + z.abs();
                let base = delta + margin * (size + distance);
                for (s, &(slope, across, norm)) in sides.iter().enumerate() {
                    let c = if s < 2 { x } else { y };
                    let value = k.splat(across) * (c - k.splat(slope) * z);
                    let past = value.simd_gt(base * k.splat(norm));
                    outside[s] = outside[s] & past;
                }
                let behind = (-z).simd_gt(base);
                outside[4] = outside[4] & behind;
            }
            let mut culled = none;
            for o in outside {
                culled = culled | o;
            }
            !culled.bitmask() & ((1 << P::WIDTH) - 1)
        }
    }

    /// Bit `i` set for each triangle `i` (of `count`, in groups of sixteen) that a ray of the
    /// cone may hit: [`Cone::may_hit_lanes`] over a whole list.
    #[inline(always)]
    pub(in crate::shapes::accel) fn kept<P: InstructionSet>(
        cone: &Cone,
        k: P,
        groups: &[Corners],
        count: usize,
    ) -> u64 {
        let mut kept = 0u64;
        for (g, corners) in groups.iter().enumerate() {
            for offset in (0..16).step_by(P::WIDTH) {
                let bits = u64::from(cone.may_hit_lanes(k, corners, offset));
                kept |= bits << (g * 16 + offset);
            }
        }
        kept & (u64::MAX >> (64 - count.max(1)))
    }
}

pub(super) use lanes::kept;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::geometry::Triangle;
    use crate::base::sampling::Rng;
    use crate::shapes::accel::wide::{Corners, triangle_size};
    use crate::shapes::intersect::intersect_triangle;
    use crate::shapes::scene::cornell_box;
    use crate::test_support::{lab_settings, primary_rays, shadow_rays};

    fn v(rng: &mut Rng, s: f32) -> Vec3 {
        Vec3::new(rng.uniform(-s, s), rng.uniform(-s, s), rng.uniform(-s, s))
    }

    /// The oracle: a triangle the cone culls is hit by no ray of the batch.
    fn check(cone: &Cone, segments: &[(Ray, f32)], triangles: &[Triangle]) -> usize {
        let mut culled = 0;
        for (i, t) in triangles.iter().enumerate() {
            if cone.may_hit([t.v0, t.v1, t.v2], triangle_size(t.v0, t.v1, t.v2)) {
                continue;
            }
            culled += 1;
            for (ray, t_max) in segments {
                assert!(
                    intersect_triangle(ray, t, *t_max).is_none(),
                    "triangle {i} culled but hit by {ray:?} (t_max {t_max})"
                );
            }
        }
        culled
    }

    /// Every camera ray and shadow ray of the lab's default view, in the renderer's batches of
    /// 64: nothing culled is hit, and most of the box is culled.
    #[test]
    fn the_default_view_culls_only_what_no_ray_hits() {
        let scene = cornell_box();
        let settings = lab_settings(256, 256);
        let rays = primary_rays(&settings.camera);
        let (mut culled, mut tested) = (0, 0);
        for batch in rays.chunks(64) {
            let cone = Cone::around_rays(batch).expect("camera rays share their origin");
            let segments: Vec<_> = batch.iter().map(|r| (*r, f32::INFINITY)).collect();
            culled += check(&cone, &segments, &scene.triangles);
            tested += scene.triangles.len();
        }
        // A stretch of one row sees a few of the 30 triangles.
        assert!(
            culled * 10 > tested * 6,
            "camera: {culled} of {tested} culled"
        );

        let shadows = shadow_rays(&scene, &settings.light, &rays);
        let (mut culled, mut tested, mut cones) = (0, 0, 0);
        for batch in shadows.chunks(64) {
            let Some(cone) = Cone::around_segments(batch) else {
                continue;
            };
            cones += 1;
            culled += check(&cone, batch, &scene.triangles);
            tested += scene.triangles.len();
        }
        // Rows that pass near the light make fans too wide for a cone.
        assert!(
            cones * 64 >= shadows.len() * 2 / 3,
            "{cones} cones of {}",
            shadows.len()
        );
        assert!(
            culled * 10 > tested * 5,
            "shadows: {culled} of {tested} culled"
        );
    }

    /// Random thin fans of rays and of segments to a point, against random triangles, many of
    /// them just outside the fan.
    #[test]
    fn random_batches_cull_only_what_no_ray_hits() {
        let mut rng = Rng::new(5);
        let (mut culled, mut cones) = (0, 0);
        for round in 0..2_000 {
            let apex = v(&mut rng, 2.0);
            let axis = v(&mut rng, 1.0).normalize();
            let spread = if round % 3 == 0 { 0.01 } else { 0.2 };
            let directions: Vec<Vec3> = (0..16)
                .map(|_| (axis + v(&mut rng, spread)).normalize())
                .collect();
            let triangles: Vec<Triangle> = (0..20)
                .map(|_| {
                    let d = (axis + v(&mut rng, spread * 1.5)).normalize();
                    let c = apex + rng.uniform(0.1, 5.0) * d;
                    let s = if rng.next_f32() < 0.3 { 1e-3 } else { 0.3 };
                    Triangle::new(
                        c + v(&mut rng, s),
                        c + v(&mut rng, s),
                        c + v(&mut rng, s),
                        0,
                    )
                })
                .collect();
            let segments: Vec<(Ray, f32)> = if round % 2 == 0 {
                let rays: Vec<Ray> = directions.iter().map(|&d| Ray::new(apex, d)).collect();
                // A fan along a diagonal may open too wide about every axis.
                let Some(cone) = Cone::around_rays(&rays) else {
                    continue;
                };
                cones += 1;
                let segments: Vec<_> = rays.iter().map(|r| (*r, f32::INFINITY)).collect();
                culled += check(&cone, &segments, &triangles);
                continue;
            } else {
                // Shadow-like: from points along the fan back to (near) the apex.
                directions
                    .iter()
                    .map(|&d| {
                        let start = apex + rng.uniform(0.5, 6.0) * d;
                        let to = apex - start;
                        let distance = to.length();
                        (Ray::new(start, to), distance - 2e-4)
                    })
                    .collect()
            };
            let Some(cone) = Cone::around_segments(&segments) else {
                continue;
            };
            cones += 1;
            culled += check(&cone, &segments, &triangles);
        }
        assert!(
            cones > 1_500 && culled > 5_000,
            "{cones} cones, {culled} culled"
        );
    }

    /// The SIMD cones and culls, for every kernel set this CPU has, equal the readable ones:
    /// the same cone bit for bit, the same triangles kept.
    #[test]
    fn the_simd_cone_equals_the_readable_one() {
        use super::super::portable::Portable;
        use super::super::set::InstructionSet;
        #[cfg(target_arch = "x86_64")]
        use super::super::simd::{Avx2, Avx512};

        fn same<P: InstructionSet>(k: P, rays: &[Ray], segments: &[(Ray, f32)], tris: &[Triangle]) {
            let cones = [
                (Cone::around_rays(rays), Cone::around_rays_simd(k, rays)),
                (
                    Cone::around_segments(segments),
                    Cone::around_segments_simd(k, segments),
                ),
            ];
            for (readable, simd) in cones {
                assert_eq!(readable, simd);
                let Some(cone) = readable else { continue };
                let corners: Vec<[Vec3; 3]> = tris.iter().map(|t| [t.v0, t.v1, t.v2]).collect();
                let groups: Vec<Corners> = corners.chunks(16).map(Corners::new).collect();
                let kept = kept(&cone, k, &groups, tris.len());
                for (i, t) in tris.iter().enumerate() {
                    let want = cone.may_hit([t.v0, t.v1, t.v2], triangle_size(t.v0, t.v1, t.v2));
                    assert_eq!(kept & (1 << i) != 0, want, "triangle {i}");
                }
            }
        }

        let scene = cornell_box();
        let settings = lab_settings(128, 128);
        let rays = primary_rays(&settings.camera);
        let shadows = shadow_rays(&scene, &settings.light, &rays);
        let mut rng = Rng::new(9);
        let mut batches = 0;
        for (i, (rays, segments)) in rays.chunks(64).zip(shadows.chunks(61)).enumerate() {
            // Odd sizes too: lanes past the end repeat the last ray.
            let n = 1 + i % 64;
            let (rays, segments) = (
                &rays[..n.min(rays.len())],
                &segments[..n.min(segments.len())],
            );
            same(Portable, rays, segments, &scene.triangles);
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = Avx512::detect() {
                same(k, rays, segments, &scene.triangles);
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = Avx2::detect() {
                same(k, rays, segments, &scene.triangles);
            }
            batches += 1;
        }
        // Random fans, and scattered rays (no cone).
        for _ in 0..500 {
            let apex = v(&mut rng, 2.0);
            let axis = v(&mut rng, 1.0).normalize();
            let spread = rng.uniform(0.0, 1.0);
            let rays: Vec<Ray> = (0..(4 + rng.next_u32() % 40))
                .map(|_| Ray::new(apex, axis + v(&mut rng, spread)))
                .collect();
            let segments: Vec<(Ray, f32)> = rays
                .iter()
                .map(|r| {
                    let start = apex + rng.uniform(0.5, 6.0) * r.direction;
                    let to = apex + v(&mut rng, 1e-3) - start;
                    (Ray::new(start, to), to.length() - 2e-4)
                })
                .collect();
            let tris: Vec<Triangle> = (0..40)
                .map(|_| Triangle::new(v(&mut rng, 4.0), v(&mut rng, 4.0), v(&mut rng, 4.0), 0))
                .collect();
            same(Portable, &rays, &segments, &tris);
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = Avx512::detect() {
                same(k, &rays, &segments, &tris);
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(k) = Avx2::detect() {
                same(k, &rays, &segments, &tris);
            }
        }
        assert!(batches > 100);
    }

    #[test]
    fn scattered_batches_get_no_cone() {
        let mut rng = Rng::new(6);
        let rays: Vec<Ray> = (0..16)
            .map(|_| Ray::new(v(&mut rng, 1.0), v(&mut rng, 1.0)))
            .collect();
        assert_eq!(Cone::around_rays(&rays), None);
        let segments: Vec<_> = rays.iter().map(|r| (*r, 1.0)).collect();
        assert_eq!(Cone::around_segments(&segments), None);
        // One origin but directions all around: too wide.
        let around: Vec<Ray> = (0..16)
            .map(|_| Ray::new(Vec3::ZERO, v(&mut rng, 1.0)))
            .collect();
        assert_eq!(Cone::around_rays(&around), None);
        // Too few to be worth it.
        assert_eq!(Cone::around_rays(&[Ray::new(Vec3::ZERO, Vec3::Z)]), None);
    }
}
