//! Ray–triangle intersection (lab section 2.3) and the lab's `ClosestIntersection`.
//!
//! The fast form solves the lab's system `(−d e1 e2)·(t u v)ᵀ = s − v0` (equation 15) in closed
//! form by Cramer's rule, computing `t` first and giving up as soon as it is out of range: the
//! lab's optional exercise. [`intersect_triangle_matrix_inverse`] keeps the lab's own
//! `inverse(A)·b` form (equation 23) as a test oracle.
//!
//! **Edges count as inside.** The lab writes strict inequalities `0 < u`, `0 < v`, `u + v < 1`
//! (equations 7–9); taken literally, a ray through the diagonal shared by a wall's two triangles
//! hits neither and the image shows a crack. raylab accepts `u, v ≥ −EDGE_TOLERANCE` and
//! `u + v ≤ 1 + EDGE_TOLERANCE`, so rounding can never open a gap between neighbours.
//!
//! **A ray does not hit what it starts on.** A hit needs `t > 0`, strictly (the lab's
//! equation 11 says `0 ≤ t`). A ray starting exactly on a surface would otherwise meet that
//! surface at `t = 0` whichever way it goes: a camera standing exactly on a wall of the box (or
//! in a corner) saw that wall in every pixel, one uniform colour. Now it sees what lies in front
//! of it; rays that leave through the surface it stands on go on beyond it (out of the box:
//! black). Nothing else changes: rays from the camera and from surfaces (lifted off them, see
//! [`crate::shading::light::shadow_ray_to`]) start off every surface.

use glam::{Mat3, Vec3};

use crate::base::geometry::{Ray, Triangle};
use crate::base::lanes::{Mask, Real, Vector};

/// How far outside `[0, 1]` a barycentric coordinate may round and still count as on the edge.
/// It widens each triangle by 1e-5 of its edge length: invisible, and far larger than the
/// rounding error of `f32` Cramer's rule on the scenes raylab traces.
pub const EDGE_TOLERANCE: f32 = 1e-5;

/// The lab's `struct Intersection`, plus the barycentric coordinates of the hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intersection {
    /// The hit point `s + t·d`.
    pub position: Vec3,
    /// `t`, the distance from the ray's origin (rays are normalised).
    pub distance: f32,
    /// Index of the hit triangle in the scene.
    pub triangle_index: usize,
    /// Barycentric coordinates: `position = v0 + u·e1 + v·e2` (equation 6).
    pub u: f32,
    pub v: f32,
}

/// Whether barycentric `(u, v)` lies in the triangle, edges included (equations 7–9, closed):
/// one value (`bool`) or each lane's.
#[inline(always)]
pub fn inside_triangle<R: Real>(u: R, v: R) -> R::Mask {
    // Written so that NaN fails every comparison and is rejected.
    let lo = R::splat(-EDGE_TOLERANCE);
    u.simd_ge(lo) & v.simd_ge(lo) & (u + v).simd_le(R::splat(1.0 + EDGE_TOLERANCE))
}

/// Whether `0 < t < t_max` (equation 11, `t = 0` left out: see the module docs), one value or
/// each lane's; NaN is out.
#[inline(always)]
fn in_range<R: Real>(t: R, t_max: R) -> R::Mask {
    t.simd_gt(R::ZERO) & t.simd_lt(t_max)
}

/// Intersects `ray` with `tri`, returning `(t, u, v)` when the hit has `0 < t < t_max` and lies
/// in the triangle (edges included): [`intersect_lanes`] for one ray and one triangle.
#[inline]
pub fn intersect_triangle(ray: &Ray, tri: &Triangle, t_max: f32) -> Option<(f32, f32, f32)> {
    let (e1, e2) = tri.edges();
    let h = intersect_lanes(
        ray.origin,
        ray.direction,
        tri.v0,
        e1,
        e2,
        e1.cross(e2),
        t_max,
    );
    h.hit.then_some((h.t, h.u, h.v))
}

/// What [`intersect_lanes`] finds in each lane: `t`, `u`, `v` (meaningless where the lane
/// misses) and whether the lane hits.
#[derive(Clone, Copy, Debug)]
pub struct Hits<R: Real> {
    pub t: R,
    pub u: R,
    pub v: R,
    pub hit: R::Mask,
}

/// The ray–triangle test, written once for every width: a ray from `origin` along `direction`
/// against the triangle `v0`, `e1 = v1 − v0`, `e2 = v2 − v0` with `n = e1 × e2`, a hit when
/// `0 < t < t_max` and `(u, v)` lies in the triangle (edges included).
///
/// Cramer's rule on `A = (−d e1 e2)`, `b = s − v0` (equations 16–17), with the scalar triple
/// product `det(a, b, c) = a · (b × c)`:
///
/// * `det A = −d · n`
/// * `t = det(b, e1, e2) / det A = (b · n) / det A` — computed first, the cheap early exit;
/// * `u = det(−d, b, e2) / det A = e2 · (b × d) / det A`;
/// * `v = det(−d, e1, b) / det A = −e1 · (b × d) / det A`.
///
/// A ray parallel to the plane or a zero-area triangle gives `det A = 0`, so `t` is ±∞ or NaN,
/// and the range test rejects both: no NaN hit ever comes out. A ray starting in the
/// triangle's plane gives `t = ±0`, rejected too (see the module docs).
///
/// At `Vec3` it is [`intersect_triangle`]; the kernels run it a lane per triangle of a packet
/// (one ray against eight or sixteen triangles, [`crate::shapes::accel::simd`]) or a lane per ray (a
/// packet of rays against one triangle, `accel::packet`). Every lane does the same operations
/// in the same order (no fused multiply-add), so the same bits as the scalar test: the fast
/// structures return exactly what the brute-force loop returns. `n` is a parameter because
/// the flat list's packets store it ([`crate::shapes::accel::simd::Packet16`]); computed as
/// `e1.cross(e2)`, it has the same bits.
#[inline(always)]
pub fn intersect_lanes<V: Vector>(
    origin: V,
    direction: V,
    v0: V,
    e1: V,
    e2: V,
    n: V,
    t_max: V::Real,
) -> Hits<V::Real> {
    intersect_lanes_giving_up(origin, direction, v0, e1, e2, n, t_max, V::Real::ONE)
}

/// [`intersect_lanes`], giving up after `t` where `give_up` is set and no lane's `t` is in
/// range (then `u` and `v` are not computed: they come back as `t`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn intersect_lanes_giving_up<V: Vector>(
    origin: V,
    direction: V,
    v0: V,
    e1: V,
    e2: V,
    n: V,
    t_max: V::Real,
    give_up: bool,
) -> Hits<V::Real> {
    let b = origin - v0;
    let inv_det = V::Real::splat(1.0) / -direction.dot(n);
    let t = b.dot(n) * inv_det;
    if give_up && !in_range(t, t_max).any() {
        // One ray gives up here, and lanes where asked to (alike rays, which mostly miss a
        // triangle's plane together). Otherwise lanes go on, and test `t` with `u` and `v` (a
        // mask kept from here would hold a register through the rest).
        return Hits {
            t,
            u: t,
            v: t,
            hit: <V::Real as Real>::Mask::NONE,
        };
    }
    let m = b.cross(direction);
    let u = e2.dot(m) * inv_det;
    let v = -e1.dot(m) * inv_det;
    Hits {
        t,
        u,
        v,
        hit: in_range(t, t_max) & inside_triangle(u, v),
    }
}

/// The lab's own form: `x = A⁻¹·b` with `A = (−d e1 e2)` (equations 16–23), then the checks
/// of equations 7–9 (closed, as above) and 11.
///
/// Slower and less robust than [`intersect_triangle`]; kept as the oracle the tests compare it
/// against.
pub fn intersect_triangle_matrix_inverse(
    ray: &Ray,
    tri: &Triangle,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let (e1, e2) = tri.edges();
    let a = Mat3::from_cols(-ray.direction, e1, e2);
    if a.determinant() == 0.0 {
        return None;
    }
    let x = a.inverse() * (ray.origin - tri.v0);
    let (t, u, v) = (x.x, x.y, x.z);
    (t > 0.0 && t < t_max && inside_triangle(u, v)).then_some((t, u, v))
}

/// The lab's `ClosestIntersection`: the nearest hit over every triangle, by brute force.
///
/// [`crate::shapes::scene::Scene::closest_intersection`] is what the renderer calls; this loop is its
/// reference implementation and the oracle for faster ones. Ties keep the lower index.
pub fn closest_intersection_brute_force(
    ray: &Ray,
    triangles: &[Triangle],
    t_max: f32,
) -> Option<Intersection> {
    let mut best: Option<Intersection> = None;
    let mut t_best = t_max;
    for (i, tri) in triangles.iter().enumerate() {
        if let Some((t, u, v)) = intersect_triangle(ray, tri, t_best) {
            t_best = t;
            best = Some(Intersection {
                position: ray.at(t),
                distance: t,
                triangle_index: i,
                u,
                v,
            });
        }
    }
    best
}

/// Whether any triangle is hit with `0 < t < t_max`: a shadow ray's any-hit query, which may
/// stop at the first hit it finds.
pub fn occluded_brute_force(ray: &Ray, triangles: &[Triangle], t_max: f32) -> bool {
    triangles
        .iter()
        .any(|tri| intersect_triangle(ray, tri, t_max).is_some())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::camera::Camera;
    use crate::base::sampling::Rng;
    use crate::shapes::scene::cornell_box;

    /// The triangle (0,0,1), (2,0,1), (0,2,1) in the plane z = 1.
    fn tri() -> Triangle {
        Triangle::new(
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(0.0, 2.0, 1.0),
            0,
        )
    }

    fn hit(origin: Vec3, dir: Vec3) -> Option<(f32, f32, f32)> {
        intersect_triangle(&Ray::new(origin, dir), &tri(), f32::INFINITY)
    }

    #[test]
    fn hit_in_the_middle() {
        // From (0.5, 0.5, 0) straight along +z: t = 1, and (0.5, 0.5) = 0.25·e1 + 0.25·e2.
        let (t, u, v) = hit(Vec3::new(0.5, 0.5, 0.0), Vec3::Z).unwrap();
        assert_eq!((t, u, v), (1.0, 0.25, 0.25));
    }

    #[test]
    fn miss_outside() {
        // (1.5, 1.5) has u + v = 1.5 > 1.
        assert_eq!(hit(Vec3::new(1.5, 1.5, 0.0), Vec3::Z), None);
        // (-0.1, 0.5) has u = -0.05 < 0.
        assert_eq!(hit(Vec3::new(-0.1, 0.5, 0.0), Vec3::Z), None);
    }

    #[test]
    fn hits_on_an_edge_and_on_a_vertex() {
        // On the hypotenuse: (1, 1) is u = v = 0.5, u + v = 1 exactly.
        let (_, u, v) = hit(Vec3::new(1.0, 1.0, 0.0), Vec3::Z).unwrap();
        assert_eq!(u + v, 1.0);
        // On the edge v0–v1: v = 0.
        let (_, _, v) = hit(Vec3::new(1.0, 0.0, 0.0), Vec3::Z).unwrap();
        assert_eq!(v, 0.0);
        // On the vertex v2: (u, v) = (0, 1).
        let (_, u, v) = hit(Vec3::new(0.0, 2.0, 0.0), Vec3::Z).unwrap();
        assert_eq!((u, v), (0.0, 1.0));
        // On the vertex v0.
        assert!(hit(Vec3::new(0.0, 0.0, 0.0), Vec3::Z).is_some());
    }

    #[test]
    fn behind_the_origin_misses() {
        // The plane z = 1 is behind a ray from z = 2 going +z: t = -1 < 0 (equation 11).
        assert_eq!(hit(Vec3::new(0.5, 0.5, 2.0), Vec3::Z), None);
        // ...and t_max cuts hits beyond it.
        let r = Ray::new(Vec3::new(0.5, 0.5, 0.0), Vec3::Z);
        assert_eq!(intersect_triangle(&r, &tri(), 0.999), None);
    }

    #[test]
    fn parallel_ray_misses_without_nan() {
        // In the plane of the triangle and beside it: det A = 0.
        assert_eq!(hit(Vec3::new(-1.0, 0.5, 1.0), Vec3::X), None);
        assert_eq!(hit(Vec3::new(0.5, 0.5, 0.0), Vec3::X), None);
        let r = Ray::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::X);
        assert_eq!(
            intersect_triangle_matrix_inverse(&r, &tri(), f32::INFINITY),
            None
        );
    }

    #[test]
    fn zero_area_triangle_never_hits() {
        let flat = Triangle::new(
            Vec3::Z,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            0,
        );
        for dir in [Vec3::Z, Vec3::X, Vec3::new(1.0, 0.0, 1.0)] {
            let r = Ray::new(Vec3::new(0.5, 0.0, 0.0), dir);
            assert_eq!(intersect_triangle(&r, &flat, f32::INFINITY), None);
        }
    }

    #[test]
    fn the_nearest_of_several_triangles_wins() {
        let at_z = |z: f32, m| {
            Triangle::new(
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(3.0, -1.0, z),
                Vec3::new(-1.0, 3.0, z),
                m,
            )
        };
        let tris = [at_z(5.0, 0), at_z(2.0, 1), at_z(-1.0, 2), at_z(3.0, 3)];
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        let h = closest_intersection_brute_force(&r, &tris, f32::INFINITY).unwrap();
        assert_eq!(h.triangle_index, 1);
        assert_eq!(h.distance, 2.0);
        assert_eq!(h.position, Vec3::new(0.0, 0.0, 2.0));
        assert!(occluded_brute_force(&r, &tris, 2.5));
        assert!(!occluded_brute_force(&r, &tris, 1.5));
    }

    #[test]
    fn ray_through_the_back_walls_shared_diagonal_hits() {
        // The back wall (z = 1) is triangles 8 and 9; they share the diagonal from
        // G = (-1,-1,1) to D = (1,1,1). Every point (s, s, 1) lies on it.
        let scene = cornell_box();
        for s in [-0.9, -0.5, -0.123, 0.0, 0.31, 0.77] {
            let target = Vec3::new(s, s, 1.0);
            // From inside the box, behind both blocks (they end at z = 0.64).
            let origin = Vec3::new(0.1, -0.1, 0.8);
            let r = Ray::new(origin, target - origin);
            let h = scene.closest_intersection(&r, f32::INFINITY);
            let h = h.unwrap_or_else(|| panic!("ray through ({s}, {s}, 1) slipped through"));
            assert!(h.triangle_index == 8 || h.triangle_index == 9);
            assert!((h.position - target).length() < 1e-5);
        }
    }

    #[test]
    fn default_cameras_image_diagonal_hits_the_corner_edges() {
        // With f = W and the camera on the axis, the pixel (x, x) of a square image looks along
        // (k, k, f): x = y along the whole ray, so the rays whose offset k is between f/4 and f/2
        // hit the edges where two walls meet exactly (x = y = ±1). None may slip through.
        let scene = cornell_box();
        let cam = Camera::default_for(512, 512);
        for x in 0..512 {
            for (px, py) in [(x, x), (x, 511 - x)] {
                let r = cam.primary_ray(px as f32 + 0.5, py as f32 + 0.5);
                let h = scene.closest_intersection(&r, f32::INFINITY);
                assert!(
                    h.is_some(),
                    "pixel ({px}, {py}) on the image diagonal missed"
                );
            }
        }
        // One exact case: from (0, 0, −3.001), direction (−1, −1, 3) meets the edge x = y = −1
        // (left wall and ceiling) at t' = 1, z = −3.001 + 3 = −0.001.
        let r = Ray::new(cam.position, Vec3::new(-1.0, -1.0, 3.0));
        let h = scene.closest_intersection(&r, f32::INFINITY).unwrap();
        assert!((h.position - Vec3::new(-1.0, -1.0, -0.001)).length() < 1e-5);
        assert!(
            [2, 3, 6, 7].contains(&h.triangle_index),
            "{}",
            h.triangle_index
        );
    }

    #[test]
    fn agrees_with_the_matrix_inverse_oracle_on_random_rays() {
        let scene = cornell_box();
        let mut rng = Rng::new(7);
        let mut hits = 0;
        for _ in 0..10_000 {
            let origin = Vec3::new(
                rng.uniform(-0.99, 0.99),
                rng.uniform(-0.99, 0.99),
                rng.uniform(-0.99, 0.99),
            );
            let dir = Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            );
            let r = Ray::new(origin, dir);
            for tri in &scene.triangles {
                let fast = intersect_triangle(&r, tri, f32::INFINITY);
                let oracle = intersect_triangle_matrix_inverse(&r, tri, f32::INFINITY);
                match (fast, oracle) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a.0 - b.0).abs() <= 1e-4 * b.0.max(1.0), "t {a:?} vs {b:?}");
                        assert!((a.1 - b.1).abs() < 1e-4 && (a.2 - b.2).abs() < 1e-4);
                    }
                    (None, None) => {}
                    // The two forms round differently: they may disagree only for a hit on an edge.
                    (Some((_, u, v)), None) | (None, Some((_, u, v))) => {
                        let edge = u.abs().min(v.abs()).min((1.0 - u - v).abs());
                        assert!(edge < 1e-4, "disagree away from an edge: u={u} v={v}");
                    }
                }
            }
        }
        // Rays start inside the box, which is open only at the front (z = −1): most hit a wall.
        assert!(hits > 5_000, "only {hits} hits");
    }
}
