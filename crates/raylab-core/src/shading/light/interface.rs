//! The interface every light offers an integrator (pbrt-v4's `Light`: `SampleLi`, `PDF_Li`,
//! `L`), in the lab's units.

use glam::{Vec2, Vec3};

use crate::base::geometry::Ray;

/// One direction toward a light, drawn by [`Light::sample_li`] for a surface point.
///
/// An integrator turns it into direct light with the usual Monte Carlo estimate
/// `f(wo, wi) · li · |cos θ| / pdf` (`f` the physical BSDF, ρ/π for a diffuse surface), after
/// checking with a shadow ray toward `point` (or `distance` along `wi`) that nothing is in
/// between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the surface point toward the light.
    pub wi: Vec3,
    /// Incident radiance arriving along `wi`, in lab units (π × radiance, see [`Light`]).
    pub li: Vec3,
    /// Probability density of having drawn `wi`, per unit solid angle; 1 for a delta light (a
    /// point), which has exactly one direction.
    pub pdf: f32,
    /// Distance from the surface point to `point`: how far a shadow ray must stay clear.
    pub distance: f32,
    /// The point of the light the sample reaches.
    pub point: Vec3,
    /// Whether the light is a delta light ([`Light::is_delta`]): its `pdf` is not a density,
    /// and no ray leaving a surface can ever hit it.
    pub is_delta: bool,
}

impl LightSample {
    /// The sample of `point`, a point of an area light, seen from `p`: the unit direction and
    /// distance toward it, the radiance `li` arriving from it, and its density per solid angle,
    /// `pdf(distance)`.
    #[inline(always)]
    pub fn area(p: Vec3, point: Vec3, li: Vec3, pdf: impl FnOnce(f32) -> f32) -> Self {
        let to_point = point - p;
        let distance = to_point.length();
        LightSample {
            wi: to_point / distance,
            li,
            pdf: pdf(distance),
            distance,
            point,
            is_delta: false,
        }
    }
}

/// A light, as an integrator sees it: where light arrives from, with what radiance, and how
/// likely each direction is to be drawn.
///
/// **Units.** raylab's images are in *lab units*: π × radiance. The lab computes the value of
/// a diffuse hit as ρ·D, with D the irradiance of its equation 27; the outgoing radiance of
/// that surface is (ρ/π)·D, so a pixel of value ρ·D holds π × radiance. Lights return incident
/// radiance in the same units (`π·L`), so that an integrator computing
/// `f(wo, wi) · Li · |cos θ| / pdf` with the physical BSDF `f` (ρ/π for a diffuse surface) gets
/// exactly the lab's ρ·D from the lab's point light. Every light emits a total power `P` per
/// channel ([`Light::power`], the lab's `P · colour`).
///
/// **Conventions.** Directions are unit vectors in the scene's space, where +y points down
/// toward the floor. `wi` points from the surface toward the light; a ray meeting the light
/// travels from the viewer toward it ([`Light::le`]). Nothing here allocates.
///
/// Object safe: `&dyn Light` works, though [`crate::shading::light::AnyLight`] (an enum) is the cheaper
/// way to hold one of the lab's lights.
pub trait Light {
    /// Draws a direction toward the light for the surface point `p` from `u`, two uniform
    /// numbers in [0, 1): the direction, the radiance arriving along it and its density.
    /// `None` when no light can arrive at `p` (behind a one-sided light, inside a sphere, or
    /// `p` at the point light itself).
    fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample>;

    /// The density, per unit solid angle, with which [`Light::sample_li`] at `p` draws the
    /// unit direction `wi`: 0 for directions that miss the light and for delta lights (whose
    /// single direction is drawn with probability 1, not with a density). Integrators weigh
    /// light samples against BSDF samples with it (multiple importance sampling).
    fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32;

    /// Where `ray` (unit direction) meets the light's emitting side first, as the distance
    /// `t` along the ray with `0 < t < t_max`; `None` if it does not, and always `None` for a
    /// point light, which no ray can hit.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32>;

    /// The radiance (lab units) a viewer sees along a ray that hits the light, given the ray's
    /// unit direction (from the viewer toward the light): what a path that hits an emitter
    /// adds. 0 from behind a one-sided light, and for a point light.
    fn le(&self, ray_direction: Vec3) -> Vec3;

    /// Whether the light is a delta light: a point, with one direction per surface point and
    /// no area a ray could hit.
    fn is_delta(&self) -> bool;

    /// The total power the light emits per channel, `P · colour`, in watts.
    fn power(&self) -> Vec3;

    /// A ray leaving the light, from `u_point` (where on the light) and `u_direction` (which
    /// way), two pairs of uniform numbers in [0, 1): pbrt-v4's `SampleLe`, for photon
    /// tracing. The ray is drawn in proportion to the light the emitter sends out (a point:
    /// uniform over the sphere of directions; an area light: uniform over its area, then
    /// cosine-weighted about its emitting normal), so every ray carries the same share of
    /// [`Light::power`]: N rays carry P/N each. `None` where no ray can be made (a light of
    /// no size, or not finite).
    fn sample_le(&self, u_point: Vec2, u_direction: Vec2) -> Option<Ray>;
}
