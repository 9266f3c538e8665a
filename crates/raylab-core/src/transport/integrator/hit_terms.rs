//! A hit as the light sees it and the lab's terms there: `Surface`, `HitTerms` (equations
//! 27–30 at one hit), `Lighting` (the same for sixteen hits), `shaded_value`, and the rays
//! that leave a surface (`continue_ray`, `departure_points`).

use glam::Vec3;

use super::*;
use crate::base::geometry::Ray;
use crate::base::lanes::{F32x16, M16, Mask, MaskOf, Real, Vec3x16, Vector, select_lazy};
use crate::base::sampling::Rng;
use crate::shading::bsdf::ShadingFrame;
use crate::shading::light::{DirectLight, LightSpec, SHADOW_OFFSET, ShadowRays, shadow_rays_to};
use crate::shapes::accel::SegmentLanes;

/// A hit ready to scatter ([`Tracer::scattering`]).
#[derive(Clone, Copy, Debug)]
pub struct Scattering {
    pub surface: Surface,
    pub bsdf: crate::shading::bsdf::Bsdf,
    pub frame: ShadingFrame,
    /// Toward where the ray came from.
    pub wo: Vec3,
}

/// A diffuse hit as the light sees it, before any light is computed ([`Tracer::surface`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    pub position: Vec3,
    /// The normal the light is computed with: the triangle's own (flat shading, the lab's) or
    /// the interpolated vertex normals (smooth shading).
    pub normal: Vec3,
    /// The triangle's own normal. It decides which side of the surface is lit and which side
    /// shadow rays leave from: a smooth normal only changes how much light arrives, never lets
    /// light through a surface.
    pub geometric: Vec3,
    /// ρ, the diffuse reflectance: the material's, or its texture's value at the hit.
    pub rho: Vec3,
    /// The direction of the ray that found the hit when the hit lies near an edge of its
    /// triangle, where its shadow ray starts differently
    /// ([`crate::shapes::scene::Scene::approach_at_edge`], [`crate::shading::light::shadow_ray`]); `None`
    /// elsewhere, or when no shadow ray is cast.
    pub at_edge: Option<Vec3>,
    /// The share of the light's centre the surface's own relief leaves it: 0 where a height
    /// map's field hides the light (parallax self-shadowing, [`crate::shading::relief::HeightMap::lit`]),
    /// else 1. D and the path tracers' light samples are multiplied by it.
    pub relief_visibility: f32,
}

/// The terms of the lab's equations at one diffuse hit: the one place they are computed.
///
/// [`HitTerms::at`] evaluates D (equation 27) and makes the shadow ray (section 5.1); whoever
/// traces the shadow ray records the answer in `blocked`; [`HitTerms::value`] combines them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitTerms {
    pub position: Vec3,
    /// The normal the light is computed with: the lab's for the lab stages, turned to face
    /// the ray for the path tracer (two-sided surfaces).
    pub normal: Vec3,
    /// ρ, the diffuse reflectance.
    pub rho: Vec3,
    /// D, the light arriving from the point light ignoring anything in between (equation 27),
    /// 0 where the surface's own relief hides the light ([`Surface::relief_visibility`]).
    pub d: Vec3,
    /// Whether the surface's own relief hides the light (parallax self-shadowing).
    pub relief_shadowed: bool,
    /// The shadow ray to cast and its length, or `None` when none is needed (shadows off, no
    /// light arriving, or the flat stage).
    pub shadow_ray: Option<(Ray, f32)>,
    /// Whether the shadow ray was blocked: the point is in shadow and D counts as 0.
    pub blocked: bool,
}

impl HitTerms {
    /// A placeholder, for arrays filled as hits come.
    pub const NONE: HitTerms = HitTerms {
        position: Vec3::ZERO,
        normal: Vec3::ZERO,
        rho: Vec3::ZERO,
        d: Vec3::ZERO,
        relief_shadowed: false,
        shadow_ray: None,
        blocked: false,
    };

    /// The terms at a diffuse hit: [`Lighting::at`] for one hit (see there). The flat stage
    /// needs only ρ: D is left 0 and no shadow ray is made.
    ///
    /// `light_point(position)` is the point of the light the shadow ray goes to
    /// ([`light_point`]), called only when a shadow ray is cast.
    #[inline(always)]
    pub fn at(
        light: &LightSpec,
        stage: Stage,
        shadows: bool,
        surface: Surface,
        light_point: impl FnOnce(Vec3) -> Vec3,
    ) -> Self {
        let lit = Lighting::at(light, stage, shadows, &Surfaces::from(surface), |p, _| {
            light_point(p)
        });
        Self {
            position: surface.position,
            normal: surface.normal,
            rho: surface.rho,
            d: lit.d,
            relief_shadowed: surface.relief_visibility == 0.0 && stage != Stage::Flat,
            shadow_ray: lit.shadow.cast.then_some((
                Ray {
                    origin: lit.shadow.origin,
                    direction: lit.shadow.direction,
                },
                lit.shadow.t_max,
            )),
            blocked: false,
        }
    }

    /// D after shadows: 0 where the shadow ray was blocked.
    #[inline]
    pub fn d_after_shadows(&self) -> Vec3 {
        after_shadows(self.d, self.blocked)
    }

    /// The value of the hit (`n` is N, the constant indirect term, or 0):
    ///
    /// * flat: `ρ`
    /// * incoming: `D + N` (equation 27, or T of equation 29)
    /// * direct, shadows, lab, and the path tracer's direct term: `ρ ∗ (D + N)` (equation 30,
    ///   which is equation 28 for N = 0)
    #[inline(always)]
    pub fn value(&self, stage: Stage, n: Vec3) -> Vec3 {
        shaded_value(stage, self.rho, self.d, self.blocked, n)
    }
}

/// D after shadows, for one hit or a lane of hits: 0 where the shadow ray was blocked.
#[inline(always)]
pub fn after_shadows<V: Vector>(d: V, blocked: MaskOf<V>) -> V {
    V::select(blocked, V::ZERO, d)
}

/// [`HitTerms::value`] for one hit or a lane of hits: ρ, D, whether the shadow ray was blocked
/// and N as equations 28–30 combine them.
#[inline(always)]
pub fn shaded_value<V: Vector>(stage: Stage, rho: V, d: V, blocked: MaskOf<V>, n: V) -> V {
    let d = after_shadows(d, blocked);
    match stage {
        Stage::Flat => rho,
        Stage::Incoming => d + n,
        Stage::Direct | Stage::Shadows | Stage::Lab | Stage::Path => rho * (d + n),
    }
}

/// [`Surface`]s for [`Lighting::at`]: one (`Surfaces<Vec3>`, from a [`Surface`]) or sixteen
/// side by side (`Surfaces<Vec3x16>`, filled a lane at a time by [`Surfaces::set`]).
/// `at_edge` is split into whether it is `Some` and the direction it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surfaces<V: Vector> {
    pub position: V,
    pub normal: V,
    pub geometric: V,
    pub rho: V,
    /// `at_edge.is_some()`.
    pub near_edge: MaskOf<V>,
    /// What `at_edge` holds (0 where it is `None`).
    pub incoming: V,
    pub relief_visibility: V::Real,
}

impl From<Surface> for Surfaces<Vec3> {
    #[inline(always)]
    fn from(s: Surface) -> Self {
        Self {
            position: s.position,
            normal: s.normal,
            geometric: s.geometric,
            rho: s.rho,
            near_edge: s.at_edge.is_some(),
            incoming: s.at_edge.unwrap_or(Vec3::ZERO),
            relief_visibility: s.relief_visibility,
        }
    }
}

impl Surfaces<Vec3x16> {
    /// All lanes 0, none near an edge.
    pub const ZERO: Self = Self {
        position: Vec3x16::ZERO,
        normal: Vec3x16::ZERO,
        geometric: Vec3x16::ZERO,
        rho: Vec3x16::ZERO,
        near_edge: M16::NONE,
        incoming: Vec3x16::ZERO,
        relief_visibility: F32x16::ZERO,
    };

    /// Puts `s` in lane `i`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, s: Surface) {
        self.position.set_lane(i, s.position);
        self.normal.set_lane(i, s.normal);
        self.geometric.set_lane(i, s.geometric);
        self.rho.set_lane(i, s.rho);
        self.near_edge.0[i] = s.at_edge.is_some();
        self.incoming.set_lane(i, s.at_edge.unwrap_or(Vec3::ZERO));
        self.relief_visibility.0[i] = s.relief_visibility;
    }
}

/// The light at one diffuse hit or at a lane of them: D (equation 27) and the shadow rays
/// (section 5.1). The one place they are computed: [`HitTerms::at`] is this at `Vec3`, the
/// lab's stages take it sixteen hits at a time ([`crate::base::lanes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting<V: Vector> {
    /// D, the light arriving ignoring anything in between (0 in the flat stage).
    pub d: V,
    /// The shadow rays, cast where `shadow.cast` holds: shadows on and light arriving.
    pub shadow: ShadowRays<V>,
}

impl<V: Vector> Lighting<V> {
    /// The light at `surface`. The flat stage needs only ρ: D is left 0 and no shadow ray is
    /// made.
    ///
    /// D is equation 27 with the light's centre. A spherical light (radius above 0) gives a
    /// point of the sphere an unoccluded point sees exactly the same irradiance as its centre
    /// would; what changes is how much of it is hidden, so the shadow ray goes to a point of
    /// the sphere, `light_point(positions, wanted)` ([`light_point`], for the lanes where
    /// `wanted` holds): averaged over samples, D is multiplied by the fraction of the light
    /// seen (soft shadows). It is called only when some shadow ray is cast. For the lab's point
    /// light it returns the light's position and draws nothing; the lab stages pass that alone,
    /// so their loop carries no random numbers (drawing them is work the point light never
    /// needs, in the lab's hottest loop).
    ///
    /// Where the scalar code would branch per hit (a smooth normal on the unlit side, no light
    /// to block), every lane computes both sides and takes its own: the same bits.
    #[inline(always)]
    pub fn at(
        light: &LightSpec,
        stage: Stage,
        shadows: bool,
        surface: &Surfaces<V>,
        light_point: impl FnOnce(V, MaskOf<V>) -> V,
    ) -> Self {
        let Surfaces {
            position,
            normal,
            geometric,
            near_edge,
            incoming,
            relief_visibility,
            ..
        } = *surface;
        if stage == Stage::Flat {
            return Self {
                d: V::ZERO,
                shadow: ShadowRays::NONE,
            };
        }
        // D is 0 where the surface's own relief hides the light (parallax self-shadowing).
        let d = DirectLight::at(light, position, normal).d * relief_visibility;
        // With a smooth normal, the surface itself still decides which side is lit.
        let unlit_side = normal.simd_ne(geometric)
            & (V::splat(light.position) - position)
                .dot(geometric)
                .simd_le(V::Real::ZERO);
        let d = V::select(unlit_side, V::ZERO, d);
        // A shadow ray only matters where there is light to block.
        let wanted = MaskOf::<V>::splat(shadows) & d.simd_ne(V::ZERO);
        if !wanted.any() {
            return Self {
                d,
                shadow: ShadowRays::NONE,
            };
        }
        let target = light_point(position, wanted);
        let mut shadow = shadow_rays_to(target, position, geometric, near_edge, incoming);
        shadow.cast = shadow.cast & wanted;
        Self { d, shadow }
    }
}

impl Lighting<Vec3x16> {
    /// No light in any lane.
    pub const NONE: Self = Self {
        d: Vec3x16::ZERO,
        shadow: ShadowRays::NONE,
    };
}

impl ShadowRays<Vec3x16> {
    /// Lane `i`'s shadow ray and its length, if it is cast.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Option<(Ray, f32)> {
        self.cast.0[i].then(|| {
            let ray = Ray {
                origin: self.origin.lane(i),
                direction: self.direction.lane(i),
            };
            (ray, self.t_max.0[i])
        })
    }

    /// The lanes of `lanes` (bit `i`: lane `i`), as the tracer takes shadow rays in lanes
    /// ([`crate::shapes::scene::Scene::occluded_lanes`]): the others are never cast.
    #[inline(always)]
    pub fn segment_lanes(&self, lanes: u16) -> SegmentLanes<'_> {
        SegmentLanes {
            origin: [&self.origin.x.0, &self.origin.y.0, &self.origin.z.0],
            direction: [
                &self.direction.x.0,
                &self.direction.y.0,
                &self.direction.z.0,
            ],
            t_max: &self.t_max.0,
            cast: self.cast.bits() & lanes,
        }
    }
}

/// The point of the light a shadow ray from `position` goes to: the centre of the lab's point
/// light, or a point of an area light drawn from `rng` ([`LightSpec::shadow_target`]).
#[inline(always)]
pub fn light_point(light: &LightSpec, position: Vec3, rng: &mut Rng) -> Vec3 {
    if light.is_area() {
        light.shadow_target(position, rng.next_f32(), rng.next_f32())
    } else {
        light.position
    }
}

/// A ray leaving a surface point along `direction`, started [`SHADOW_OFFSET`] off the surface
/// on the side it leaves by, so it cannot hit the surface it leaves.
///
/// `at_edge` is [`crate::shapes::scene::Scene::approach_at_edge`]'s answer for the point. At an edge
/// where another surface meets this one, the lifted point lies in that surface's plane, and a
/// ray leaving it would meet that surface at `t = 0`, which is no hit: it would slip through
/// it. So there, as a shadow ray does ([`crate::shading::light::shadow_ray`]), it starts
/// [`SHADOW_OFFSET`] along the surface back toward where the arriving ray came from: a ray into
/// the other surface then meets it just beyond its start, one away from it leaves it behind.
#[inline(always)]
pub fn continue_ray(position: Vec3, normal: Vec3, direction: Vec3, at_edge: Option<Vec3>) -> Ray {
    let origin = departure_points(
        position,
        normal,
        direction,
        at_edge.is_some(),
        at_edge.unwrap_or(Vec3::ZERO),
    );
    Ray { origin, direction }
}

/// Where rays leaving surface points start, for one point or sixteen: [`continue_ray`]'s
/// origin, with its `at_edge` split into whether it is `Some` (`near_edge`) and what it holds
/// (`incoming`), as in [`Surfaces`].
#[inline(always)]
pub fn departure_points<V: Vector>(
    position: V,
    normal: V,
    direction: V,
    near_edge: MaskOf<V>,
    incoming: V,
) -> V {
    let away = direction.dot(normal).simd_ge(V::Real::ZERO);
    let side = V::Real::select(away, V::Real::splat(1.0), V::Real::splat(-1.0));
    let lifted = position + V::scale(side * V::Real::splat(SHADOW_OFFSET), normal);
    select_lazy!(
        Vector: V,
        near_edge,
        crate::shading::light::edge_start(lifted, normal, incoming),
        lifted
    )
}
