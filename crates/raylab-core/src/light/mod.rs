//! The lab's omni light (section 5): a point that sends power `P` equally in all directions.

use std::f32::consts::PI;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geometry::{Ray, Triangle};
use crate::lanes::{Mask, MaskOf, Real, Vector, select_lazy};
use crate::named::named_enum;
use crate::sampling::{orthonormal_basis, uniform_cone};

#[cfg(test)]
mod checks;
mod interface;
mod point;
mod quad;
mod shape;
mod sphere;

pub use interface::{Light, LightSample};
pub use quad::QuadLight;
pub use shape::{AnyLight, emitter};
pub use sphere::SphereLight;

/// The shape of the emitter the lab's light is turned into by [`emitter`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightShape {
    /// The lab's point light (hard shadows). The default.
    #[default]
    Point,
    /// A sphere emitting from its surface ([`SphereLight`]): soft shadows from every side.
    Sphere,
    /// A square panel facing the floor ([`QuadLight`]): a Cornell box's ceiling light.
    Quad,
}

named_enum!(LightShape as "light shape" {
    Point => "point", "Point (the lab)";
    Sphere => "sphere", "Sphere";
    Quad => "quad", "Square (quad)";
});

/// The sphere light's radius when only its shape is chosen.
pub const DEFAULT_SPHERE_RADIUS: f32 = 0.1;
/// The quad light's side when only its shape is chosen: the lab-sized ceiling light.
pub const DEFAULT_QUAD_SIDE: f32 = 0.5;

/// Distances below this (in scene units) count as this far when dividing by `4πr²`: a light
/// exactly on a surface then gives a large but finite value, never ∞ or NaN.
pub const MIN_LIGHT_DISTANCE: f32 = 1e-3;

/// How far a shadow ray starts off the surface, along the normal: enough that rounding in the
/// hit point can't make the surface shadow itself ("shadow acne"), far below a pixel's size.
pub const SHADOW_OFFSET: f32 = 1e-4;

/// The lab's light: a point at `position` sending `power` watts equally in all directions, in
/// the colour `colour` (so `power · colour` per channel, the lab's `lightColor = 14·(1, 1, 1)`).
///
/// Its `shape` may make it an area light of the same total power: a sphere of radius `radius`
/// or a square of side `radius` facing the floor ([`emitter`] makes the [`Light`] each is). The
/// lab's stages keep equation 27 from the centre for every shape and aim the shadow rays at
/// points of the shape ([`PointLight::shadow_target`]); the path tracer sees the real emitter.
///
/// With a `radius` above 0 it is a sphere of that radius, emitting the same total power
/// uniformly from its surface (soft shadows, one of the lab's extensions); the sphere is not
/// drawn, only its light is seen. Radius 0 is the lab's point light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "LightFields")]
pub struct PointLight {
    pub position: Vec3,
    /// Total emitted power P, in watts.
    pub power: f32,
    /// The light's colour: the power per channel is `power · colour`.
    pub colour: Vec3,
    /// The size of an area light in scene units: the sphere's radius or the square's side
    /// (0 makes any shape the lab's point light; a point with a radius is a sphere).
    pub radius: f32,
    /// The light's shape: the lab's point, a sphere or a square.
    pub shape: LightShape,
}

impl Default for PointLight {
    /// The lab's light: at (0, −0.5, −0.7), 14 W, white, a point.
    fn default() -> Self {
        Self {
            position: Vec3::new(0.0, -0.5, -0.7),
            power: 14.0,
            colour: Vec3::ONE,
            radius: 0.0,
            shape: LightShape::Point,
        }
    }
}

impl PointLight {
    /// The power per colour channel, `P · colour`, in watts: the lab's `lightColor`.
    #[inline(always)]
    pub fn channel_power(&self) -> Vec3 {
        self.colour * self.power
    }

    /// Whether the light is an area light, not the lab's point: any size above 0 (a point
    /// given a radius is the sphere of that radius, as the lab's extension had it).
    #[inline]
    pub fn is_area(&self) -> bool {
        self.radius > 0.0
    }

    /// The shape the light really has: a point with a radius is a sphere.
    pub fn effective_shape(&self) -> LightShape {
        match (self.is_area(), self.shape) {
            (false, _) => LightShape::Point,
            (true, LightShape::Point) => LightShape::Sphere,
            (true, shape) => shape,
        }
    }

    /// The emitter this light is, behind the [`Light`] interface.
    pub fn emitter(&self) -> AnyLight {
        emitter(self, self.effective_shape(), self.radius)
    }

    /// The point a lab-stage shadow ray from `position` aims at (`u1`, `u2` uniform in
    /// [0, 1)): the centre of the point light, a point of the sphere's near side
    /// ([`PointLight::sample_point`]) or a point drawn uniformly on the square. The share of
    /// such points a surface sees unblocked estimates how much of the light it sees.
    #[inline]
    pub fn shadow_target(&self, position: Vec3, u1: f32, u2: f32) -> Vec3 {
        match self.effective_shape() {
            LightShape::Sphere => self.sample_point(position, u1, u2),
            LightShape::Quad => self.position + self.radius * Vec3::new(u1 - 0.5, 0.0, u2 - 0.5),
            LightShape::Point => self.position,
        }
    }

    /// A point of the light for a shadow ray from `position`: the centre for the point light,
    /// else a point of the sphere's near side, in a direction drawn uniformly from the cone the
    /// sphere fills as seen from `position` (`u1`, `u2` uniform in [0, 1)). The share of such
    /// points a surface point sees unblocked estimates the fraction of the light it sees. Seen
    /// from inside the sphere, the centre.
    pub fn sample_point(&self, position: Vec3, u1: f32, u2: f32) -> Vec3 {
        let to_centre = self.position - position;
        let d2 = to_centre.length_squared();
        let r2 = self.radius * self.radius;
        if !(d2 > r2) {
            return self.position;
        }
        let d = d2.sqrt();
        let axis = to_centre / d;
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let local = uniform_cone(u1, u2, cos_max);
        let (t1, t2) = orthonormal_basis(axis);
        let direction = local.x * t1 + local.y * t2 + local.z * axis;
        // The nearer crossing of the sphere along `direction`.
        let cos = local.z;
        let sin2 = (1.0 - cos * cos).max(0.0);
        let t = d * cos - (r2 - d2 * sin2).max(0.0).sqrt();
        position + t * direction
    }
}

/// What a settings file may hold for the light: `power` as watts (`14`) or, as files written
/// before the light had a colour, as watts per channel (`[14, 14, 14]`), which is read as the
/// largest channel's power and the colour it makes.
#[derive(Deserialize)]
#[serde(default)]
struct LightFields {
    position: Vec3,
    power: PowerField,
    colour: Option<Vec3>,
    radius: f32,
    /// Files written before lights had shapes meant a sphere by any radius above 0.
    shape: Option<LightShape>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PowerField {
    Watts(f32),
    PerChannel(Vec3),
}

impl Default for LightFields {
    fn default() -> Self {
        let light = PointLight::default();
        Self {
            position: light.position,
            power: PowerField::Watts(light.power),
            colour: None,
            radius: light.radius,
            shape: None,
        }
    }
}

impl From<LightFields> for PointLight {
    fn from(f: LightFields) -> Self {
        let (power, colour) = match f.power {
            PowerField::Watts(p) => (p, f.colour.unwrap_or(Vec3::ONE)),
            PowerField::PerChannel(v) => {
                let p = v.max_element();
                let from_channels = if p > 0.0 { v / p } else { Vec3::ONE };
                (p, f.colour.unwrap_or(from_channels))
            }
        };
        Self {
            position: f.position,
            power,
            colour,
            radius: f.radius,
            shape: f.shape.unwrap_or(if f.radius > 0.0 {
                LightShape::Sphere
            } else {
                LightShape::Point
            }),
        }
    }
}

/// The power per area reaching a surface point from the light, ignoring anything in between
/// (lab equation 27):
///
/// `D = P · max(r̂ · n̂, 0) / (4π r²)`
///
/// where `r` is the distance to the light and `r̂` the unit direction toward it. A point facing
/// away from the light (or a zero normal) gets 0. For `r` below [`MIN_LIGHT_DISTANCE`] the
/// light is treated as that far away and straight above the surface.
#[inline(always)]
pub fn direct_light(light: &PointLight, position: Vec3, normal: Vec3) -> Vec3 {
    DirectLight::at(light, position, normal).d
}

/// Equation 27 with its parts, as [`direct_light`] computes them (it is this, keeping only
/// `d`): the pixel inspector shows r, r̂·n̂ and 4πr² from here.
///
/// Generic over [`Vector`]: `DirectLight` (at `Vec3`) is one hit's, `DirectLight<Vec3x16>`
/// sixteen hits' side by side, computed by the same code ([`DirectLight::at`]).
///
/// [`Vec3x16`]: crate::lanes::Vec3x16
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectLight<V: Vector = Vec3> {
    /// r, from the surface point to the light.
    pub to_light: V,
    /// r², or [`MIN_LIGHT_DISTANCE`]² for a light closer than that.
    pub r2: V::Real,
    /// r̂·n̂ (not yet clamped at 0).
    pub cos: V::Real,
    /// 4πr².
    pub four_pi_r2: V::Real,
    /// D.
    pub d: V,
}

impl DirectLight {
    /// |r|, the distance to the light (at least [`MIN_LIGHT_DISTANCE`]).
    pub fn distance(&self) -> f32 {
        self.r2.sqrt()
    }
}

impl<V: Vector> DirectLight<V> {
    /// Equation 27 at `position` (one point, or a lane of them) with the shading `normal`.
    /// Both sides of the [`MIN_LIGHT_DISTANCE`] test are computed and each lane takes its own
    /// (see [`crate::lanes`]): the same bits as a branch.
    #[inline(always)]
    pub fn at(light: &PointLight, position: V, normal: V) -> Self {
        let to_light = V::splat(light.position) - position;
        let r2 = to_light.length_squared();
        let min_r2 = V::Real::splat(MIN_LIGHT_DISTANCE * MIN_LIGHT_DISTANCE);
        let near = r2.simd_lt(min_r2);
        let cos = select_lazy!(
            Real: V::Real,
            near,
            normal.length(),
            (to_light / r2.sqrt()).dot(normal)
        );
        let r2 = V::Real::select(near, min_r2, r2);
        let four_pi_r2 = V::Real::splat(4.0 * PI) * r2;
        Self {
            to_light,
            r2,
            cos,
            four_pi_r2,
            d: V::splat(light.channel_power()) * cos.simd_max(V::Real::splat(0.0)) / four_pi_r2,
        }
    }
}

/// How near an edge of its triangle a surface point must be for its shadow ray to start the
/// way [`shadow_ray_to`] describes for edges: where another surface may meet this one (a
/// room's corner), within reach of the ray's first steps.
pub const EDGE_ZONE: f32 = 2.0 * SHADOW_OFFSET;

/// What a shadow ray from a hit needs to know of how the hit was found: `Some(incoming)`, the
/// direction of the ray that found it, when the hit lies within [`EDGE_ZONE`] of an edge of its
/// triangle (`u`, `v` its barycentric coordinates, as [`crate::intersect::intersect_triangle`]
/// gives them); `None` elsewhere, where it is not needed (see [`shadow_ray_to`]).
/// [`crate::scene::Scene::approach_at_edge`] answers the same from the scene's triangles'
/// [`edge_zones`], made once.
#[inline]
pub fn approach_at_edge(triangle: &Triangle, u: f32, v: f32, incoming: Vec3) -> Option<Vec3> {
    near_an_edge(edge_zones(triangle), u, v).then_some(incoming)
}

/// A triangle's [`EDGE_ZONE`] in barycentric terms, squared, for [`near_an_edge`]: the
/// distance from a point to the edge where v = 0 (along e1) is v times the height of v2 above
/// that edge, |e1 × e2| / |e1|; likewise u and |e2|, and 1 − u − v and |e2 − e1|. So a point is
/// within the zone of the first edge when v² < EDGE_ZONE² · |e1|² / |e1 × e2|², and so on.
pub fn edge_zones(triangle: &Triangle) -> [f32; 3] {
    let (e1, e2) = triangle.edges();
    let n2 = e1.cross(e2).length_squared();
    let zone2 = EDGE_ZONE * EDGE_ZONE;
    [e1, e2, e2 - e1].map(|e| zone2 * e.length_squared() / n2)
}

/// Whether barycentric `(u, v)` lies within a triangle's [`edge_zones`]: for one point, or
/// sixteen in lanes ([`crate::lanes`]).
#[inline(always)]
pub fn near_an_edge<R: Real>(zones: [R; 3], u: R, v: R) -> R::Mask {
    let w = R::splat(1.0) - u - v;
    // `|`, not `||`: three compares and no branch (the answer is nearly always no).
    (v * v).simd_lt(zones[0]) | (u * u).simd_lt(zones[1]) | (w * w).simd_lt(zones[2])
}

/// The shadow ray from a surface point toward the light, and the distance to stop at (lab
/// section 5.1), or `None` when the light is on the surface (nothing can lie between).
///
/// The ray starts [`SHADOW_OFFSET`] off the surface on the side the light is on, so the surface
/// can't shadow itself, and skips its first [`SHADOW_OFFSET`] along the way. It stops
/// [`SHADOW_OFFSET`] short of the light, so a light touching a surface is not hidden by that
/// surface.
///
/// **At an edge** (`at_edge` is [`approach_at_edge`]'s answer: the direction of the ray that
/// found the point, if the point lies near an edge of its triangle) another surface may meet
/// this one, as the box's walls meet in its corners, and then the point lifted off its own
/// surface still lies in the other surface's plane. A shadow ray from there meets that surface
/// at `t = 0` whichever way it goes, into the room toward a light inside (which must not block
/// it) or through the wall toward a light outside (which must). Skipping the ray's first
/// steps let the second slip through the wall: a light outside the box lit a line of pixels
/// along the floor's edge with the right wall. The ray that found the point
/// tells the two apart: it reached the point through free space. So at an edge the ray starts
/// [`SHADOW_OFFSET`] off the surface and [`SHADOW_OFFSET`] along it back toward where that ray
/// came from (its part along the surface, so the lift off the surface is unchanged), which is
/// off the other surface's plane on the free side, and skips nothing: a ray into the room
/// leaves the wall behind it, one through the wall toward a light outside crosses it at a `t`
/// above 0 and is blocked. It stops [`SHADOW_OFFSET`] short of the light there too.
///
/// (Elsewhere the ray is what it always was, so the lab's images are unchanged bit for bit: a
/// shadow ray grazing a block's edge may go either way, and moving its start would turn some.)
#[inline]
pub fn shadow_ray(
    light: &PointLight,
    position: Vec3,
    normal: Vec3,
    at_edge: Option<Vec3>,
) -> Option<(Ray, f32)> {
    shadow_ray_to(light.position, position, normal, at_edge)
}

/// [`shadow_ray`] toward any point `target` of the light (see [`PointLight::sample_point`]):
/// [`shadow_rays_to`] for one point.
#[inline]
pub fn shadow_ray_to(
    target: Vec3,
    position: Vec3,
    normal: Vec3,
    at_edge: Option<Vec3>,
) -> Option<(Ray, f32)> {
    let near_edge = at_edge.is_some();
    let rays = shadow_rays_to(
        target,
        position,
        normal,
        near_edge,
        at_edge.unwrap_or(Vec3::ZERO),
    );
    rays.cast.then_some((
        Ray {
            origin: rays.origin,
            direction: rays.direction,
        },
        rays.t_max,
    ))
}

/// Shadow rays of one point or a lane of points ([`shadow_rays_to`]): where each starts, its
/// direction and the distance it stops at, and whether it is cast at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRays<V: Vector> {
    pub origin: V,
    pub direction: V,
    pub t_max: V::Real,
    /// False where no ray is cast: the light is at the surface, or a coordinate is not
    /// finite (and, from [`crate::integrator::Lighting`], where there is no light to block).
    pub cast: MaskOf<V>,
}

impl<V: Vector> ShadowRays<V> {
    /// No ray cast in any lane.
    pub const NONE: Self = Self {
        origin: V::ZERO,
        direction: V::ZERO,
        t_max: <V::Real as Real>::ZERO,
        cast: <MaskOf<V> as Mask>::NONE,
    };
}

/// [`shadow_ray_to`] for one point or a lane of points: `near_edge` and `incoming` are its
/// `at_edge` (`Some(incoming)` where `near_edge` holds). Every lane computes both starts (off
/// an edge, at an edge) and takes its own.
#[inline(always)]
pub fn shadow_rays_to<V: Vector>(
    target: V,
    position: V,
    normal: V,
    near_edge: MaskOf<V>,
    incoming: V,
) -> ShadowRays<V> {
    let (zero, offset) = (V::Real::splat(0.0), V::Real::splat(SHADOW_OFFSET));
    let toward = (target - position).dot(normal).simd_ge(zero);
    let side = V::Real::select(toward, V::Real::splat(1.0), V::Real::splat(-1.0));
    let lifted = position + V::scale(side * offset, normal);
    // Off an edge the ray starts back toward the viewer and skips nothing; elsewhere it starts
    // at the lifted point and skips its first SHADOW_OFFSET.
    let start = select_lazy!(Vector: V, near_edge, edge_start(lifted, normal, incoming), lifted);
    let skip = V::Real::select(near_edge, zero, offset);
    let to_light = target - start;
    let distance = to_light.length();
    let direction = to_light / distance;
    ShadowRays {
        origin: start + V::scale(skip, direction),
        direction,
        // `skip + SHADOW_OFFSET` is exactly 2·SHADOW_OFFSET or SHADOW_OFFSET: the same stops as
        // before, bit for bit.
        t_max: distance - (skip + offset),
        // Not cast where the light is at the surface, or a coordinate is not finite.
        cast: distance.simd_gt(V::Real::splat(3.0 * SHADOW_OFFSET)),
    }
}

/// Where a ray leaving a point at an edge starts (see [`shadow_ray_to`]): the point `lifted`
/// off its surface, moved [`SHADOW_OFFSET`] along the surface back toward where the ray that
/// found it came from (`incoming`'s part along the surface, reversed).
#[inline(always)]
pub fn edge_start<V: Vector>(lifted: V, normal: V, incoming: V) -> V {
    let along = V::scale(incoming.dot(normal), normal) - incoming;
    lifted + V::scale(V::Real::splat(SHADOW_OFFSET), along)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::cornell_box;
    use crate::scene::{Scene, in_shadow};

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    /// The direction in which the default camera, at (0, 0, −3.001), sees `p`, for a point on
    /// an edge of its triangle (as [`approach_at_edge`] gives it there).
    fn seen(p: Vec3) -> Option<Vec3> {
        Some((p - Vec3::new(0.0, 0.0, -3.001)).normalize())
    }

    #[test]
    fn direct_light_straight_below_the_light() {
        // Light at (0,0,0) with P = 4π W per channel; a floor point 2 below, normal facing it:
        // r = 2, r̂·n̂ = 1, D = 4π·1 / (4π·2²) = 0.25.
        let light = PointLight {
            position: Vec3::ZERO,
            power: 4.0 * PI,
            ..PointLight::default()
        };
        let d = direct_light(&light, Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
        assert!(close(d, Vec3::splat(0.25), 1e-7), "{d}");
    }

    #[test]
    fn direct_light_at_the_labs_floor_centre() {
        // The lab's light (0, −0.5, −0.7), P = 14; the floor point (0, 1, 0) with n = (0, −1, 0).
        // r = (0, −1.5, −0.7), r² = 2.25 + 0.49 = 2.74, r = 1.655295.
        // r̂·n̂ = 1.5 / 1.655295 = 0.906183.
        // D = 14 · 0.906183 / (4π · 2.74) = 12.686562 / 34.431855 = 0.368454.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
        );
        assert!(close(d, Vec3::splat(0.368_454), 1e-5), "{d}");
    }

    #[test]
    fn direct_light_at_an_angle_on_the_back_wall() {
        // Light at (0, −0.5, −0.7), back wall point (0.5, 0, 1) with n = (0, 0, −1).
        // r = (−0.5, −0.5, −1.7), r² = 0.25 + 0.25 + 2.89 = 3.39, r = 1.841195.
        // r̂·n̂ = 1.7 / 1.841195 = 0.923314.
        // D = 14 · 0.923314 / (4π · 3.39) = 12.926396 / 42.599996 = 0.303437.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.5, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
        );
        assert!(close(d, Vec3::splat(0.303_437), 1e-5), "{d}");
    }

    #[test]
    fn back_facing_gets_nothing() {
        // The floor point below the light, with its normal reversed (facing down, away from the
        // light): r̂·n̂ = −0.906 < 0, so max(r̂·n̂, 0) = 0.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        );
        assert_eq!(d, Vec3::ZERO);
    }

    #[test]
    fn light_on_the_surface_is_finite() {
        let light = PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            ..PointLight::default()
        };
        let n = Vec3::new(0.0, -1.0, 0.0);
        for p in [Vec3::new(0.0, 1.0, 0.0), Vec3::new(1e-9, 1.0, 0.0)] {
            let d = direct_light(&light, p, n);
            assert!(d.is_finite() && d.x > 0.0, "{d}");
            // r is clamped to 1e-3: D = 14 / (4π · 1e-6) = 1.114085e6.
            assert!((d.x / 1.114_085e6 - 1.0).abs() < 1e-5, "{d}");
        }
        // A neighbour on the same plane is grazed: cos = 0, D = 0.
        assert_eq!(
            direct_light(&light, Vec3::new(0.5, 1.0, 0.0), n),
            Vec3::ZERO
        );
        let scene = cornell_box();
        assert!(!in_shadow(
            &scene,
            &light,
            Vec3::new(0.0, 1.0, 0.0),
            n,
            None
        ));
    }

    #[test]
    fn corners_do_not_shadow_themselves() {
        // Points on the edge where the left wall (x = −1) meets the ceiling (y = −1), lit from
        // inside the box: lifting off one wall leaves the point in the other wall's plane.
        let scene = cornell_box();
        let light = PointLight::default();
        for z in [-0.9, -0.248, 0.0, 0.5, 0.99] {
            let p = Vec3::new(-1.0, -1.0, z);
            for n in [Vec3::X, Vec3::Y] {
                assert!(
                    !in_shadow(&scene, &light, p, n, seen(p)),
                    "corner ({p}) with normal {n}"
                );
            }
        }
        // The floor's corner with the back wall, lit by a light in front of the blocks.
        let p = Vec3::new(0.9, 1.0, 1.0);
        assert!(!in_shadow(
            &scene,
            &light,
            p,
            Vec3::new(0.0, -1.0, 0.0),
            seen(p)
        ));
    }

    /// By hand, on the triangle (0, 0, 0), (1, 0, 0), (0, 1, 0) (|e1 × e2| = 1): the distance
    /// to the edge along e1 (v = 0) is v, to the edge along e2 (u = 0) is u, to the third edge
    /// (1 − u − v)/√2. EDGE_ZONE is 2e−4.
    #[test]
    fn approach_at_edge_by_hand() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
        let d = Vec3::Z;
        assert_eq!(approach_at_edge(&t, 0.3, 0.3, d), None);
        assert_eq!(approach_at_edge(&t, 0.5, 1.9e-4, d), Some(d));
        assert_eq!(approach_at_edge(&t, 0.5, 2.1e-4, d), None);
        assert_eq!(approach_at_edge(&t, 1.9e-4, 0.5, d), Some(d));
        // 1 − u − v = 2.5e−4: 1.77e−4 from the third edge; 3e−4: 2.12e−4.
        assert_eq!(approach_at_edge(&t, 0.5, 0.49975, d), Some(d));
        assert_eq!(approach_at_edge(&t, 0.5, 0.4997, d), None);
    }

    /// The same corners lit from outside the box: the wall the point
    /// touches stands between it and the light, whichever of the two walls' normals the point
    /// is shaded with. The floor's edge with the right wall (x = 1) under a light at
    /// (1.5, 0, 0), and the left wall's edge with the ceiling under a light above the box.
    #[test]
    fn corners_are_shadowed_by_the_wall_they_touch_from_a_light_outside() {
        let scene = cornell_box();
        let outside_right = PointLight {
            position: Vec3::new(1.5, 0.0, 0.0),
            ..PointLight::default()
        };
        let above = PointLight {
            position: Vec3::new(-0.5, -1.5, 0.0),
            ..PointLight::default()
        };
        for z in [-0.9, -0.248, 0.0, 0.5, 0.99] {
            // The floor's normal faces the light above it: D > 0, so only the shadow ray can
            // keep the light out.
            let p = Vec3::new(1.0, 1.0, z);
            let floor = Vec3::new(0.0, -1.0, 0.0);
            assert!(direct_light(&outside_right, p, floor).x > 0.0);
            assert!(in_shadow(&scene, &outside_right, p, floor, seen(p)), "{p}");
            let p = Vec3::new(-1.0, -1.0, z);
            assert!(direct_light(&above, p, Vec3::X).x > 0.0);
            assert!(in_shadow(&scene, &above, p, Vec3::X, seen(p)), "{p}");
        }
    }

    #[test]
    fn floor_in_the_tall_blocks_shadow() {
        // The tall (blue) block stands on x ∈ [−0.70, 0.05], z ∈ [−0.11, 0.64] with its top at
        // y = −0.19. The segment from the floor point (−0.45, 1, 0.9) to the light
        // (0, −0.5, −0.7) passes (−0.32, 0.55, 0.42) at 30% of the way: inside the block.
        let scene = cornell_box();
        let light = PointLight::default();
        let p = Vec3::new(-0.45, 1.0, 0.9);
        let n = Vec3::new(0.0, -1.0, 0.0);
        assert!(in_shadow(&scene, &light, p, n, None));
        // ...while a floor point in front of the blocks is lit.
        assert!(!in_shadow(
            &scene,
            &light,
            Vec3::new(0.0, 1.0, -0.8),
            n,
            None
        ));
        // The unshadowed D at p is positive: shadows, not orientation, make it dark.
        assert!(direct_light(&light, p, n).x > 0.0);
    }

    /// Points sampled on a spherical light lie on its surface, on the side facing the surface
    /// point; radius 0 gives the centre, the lab's point light.
    #[test]
    fn sampled_points_lie_on_the_near_side_of_the_sphere() {
        let mut light = PointLight::default();
        let p = Vec3::new(0.3, 1.0, 0.2);
        assert_eq!(light.sample_point(p, 0.4, 0.9), light.position);
        light.radius = 0.2;
        let mut rng = crate::sampling::Rng::new(5);
        for _ in 0..1000 {
            let q = light.sample_point(p, rng.next_f32(), rng.next_f32());
            assert!(((q - light.position).length() - 0.2).abs() < 1e-5, "{q}");
            // The near side: the sphere's normal at q faces p.
            assert!((q - light.position).dot(p - q) >= -1e-5, "{q}");
        }
        // Inside the sphere: the centre.
        assert_eq!(
            light.sample_point(light.position + 0.1 * Vec3::X, 0.5, 0.5),
            light.position
        );
    }

    /// The share of a spherical light seen past a straight edge converges to the analytic
    /// fraction.
    ///
    /// The surface point is at the origin, the light's centre at (0, 0, 2) with radius 0.5, so
    /// it fills the cone of half-angle α = asin(0.5/2) = 14.4775° around +z. A wall in the plane
    /// z = 1 covers x > h. A direction ω = (sin θ cos φ, sin θ sin φ, cos θ) crosses that plane at
    /// x = tan θ cos φ, so it is blocked when cos φ > h / tan θ = tan β / tan θ, where β = atan h
    /// is the angle between the light's centre and the wall's edge. At polar angle θ > β the
    /// blocked azimuths span 2·acos(tan β / tan θ); the cone's directions are sampled uniformly
    /// in solid angle, so the blocked fraction is
    ///
    /// `∫_β^α 2·acos(tan β / tan θ) sin θ dθ / (2π (1 − cos α))`
    ///
    /// and the fraction seen is one minus that. For h = 0 (the edge straight at the centre)
    /// acos(0) = π/2 and the fraction is exactly 1/2. The integral is evaluated here by
    /// Simpson's rule.
    #[test]
    fn the_fraction_of_a_sphere_seen_past_an_edge_matches_the_analytic_one() {
        let light = PointLight {
            position: Vec3::new(0.0, 0.0, 2.0),
            radius: 0.5,
            shape: LightShape::Point,
            ..PointLight::default()
        };
        let alpha = (0.5f64 / 2.0).asin();
        let analytic_seen = |h: f64| {
            let beta = h.atan();
            let n = 2000;
            let step = (alpha - beta) / n as f64;
            let f = |theta: f64| {
                let ratio = (beta.tan() / theta.tan()).min(1.0);
                2.0 * ratio.acos() * theta.sin()
            };
            let mut sum = f(beta) + f(alpha);
            for i in 1..n {
                let w = if i % 2 == 1 { 4.0 } else { 2.0 };
                sum += w * f(beta + i as f64 * step);
            }
            let blocked = sum * step / 3.0 / (2.0 * std::f64::consts::PI * (1.0 - alpha.cos()));
            1.0 - blocked
        };
        assert!((analytic_seen(0.0) - 0.5).abs() < 1e-9);
        let p = Vec3::ZERO;
        let n = Vec3::Z;
        for h in [0.0f32, 0.1, -0.15] {
            let wall = crate::geometry::Triangle::new(
                Vec3::new(h, -20.0, 1.0),
                Vec3::new(h, 20.0, 1.0),
                Vec3::new(40.0, 0.0, 1.0),
                0,
            );
            let scene = Scene::new(
                vec![wall],
                vec![crate::Material::diffuse("wall", Vec3::ONE)],
            );
            let mut rng = crate::sampling::Rng::new(11);
            let samples = 100_000;
            let mut seen = 0;
            for _ in 0..samples {
                let q = light.sample_point(p, rng.next_f32(), rng.next_f32());
                let (ray, t_max) = shadow_ray_to(q, p, n, None).unwrap();
                if !scene.occluded(&ray, t_max) {
                    seen += 1;
                }
            }
            let share = seen as f64 / samples as f64;
            // A negative h: the wall covers the centre; the analytic formula by symmetry.
            let expected = if h >= 0.0 {
                analytic_seen(h as f64)
            } else {
                1.0 - analytic_seen(-h as f64)
            };
            let sd = (expected * (1.0 - expected) / samples as f64).sqrt();
            assert!(
                (share - expected).abs() < 4.0 * sd,
                "h = {h}: seen {share}, analytic {expected}"
            );
            assert!(share > 0.05 && share < 0.95, "a real penumbra: {share}");
        }
    }

    #[test]
    fn old_settings_with_power_per_channel_still_load() {
        let old: PointLight =
            serde_json::from_str(r#"{"position": [0, 0, 0], "power": [14, 7, 0]}"#).unwrap();
        assert_eq!(old.power, 14.0);
        assert_eq!(old.colour, Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(old.channel_power(), Vec3::new(14.0, 7.0, 0.0));
        let new: PointLight =
            serde_json::from_str(r#"{"power": 20, "colour": [1, 0.5, 0.25], "radius": 0.1}"#)
                .unwrap();
        assert_eq!(new.position, PointLight::default().position);
        assert_eq!(new.channel_power(), Vec3::new(20.0, 10.0, 5.0));
        assert_eq!(new.radius, 0.1);
        let round: PointLight =
            serde_json::from_str(&serde_json::to_string(&new).unwrap()).unwrap();
        assert_eq!(round, new);
    }
}
