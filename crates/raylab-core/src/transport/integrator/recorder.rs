//! The `Recorder` hooks: each step an integrator takes, told to whoever watches (the pixel
//! inspector), compiled away for `()`.

use glam::Vec3;

use super::*;
use crate::base::geometry::Ray;
use crate::shading::material::Scatter;
use crate::shapes::intersect::Intersection;

/// Told each step of a ray's computation, as the integrators take it: what the pixel inspector
/// ([`crate::teaching::inspect`]) records to explain a pixel with the very values the renderer used.
///
/// Normal rendering passes `()`: its hooks are empty and [`Recorder::ENABLED`] is false, and
/// every hook is called inside `if R::ENABLED`, so the hooks and the work of preparing their
/// arguments vanish when the integrators are monomorphised for `()`: watching costs the
/// renderer nothing.
///
/// The order of the calls is the integrators' order: in a wave of rays (lab) or a step of the
/// paths (path), [`Recorder::closest_hit`] for each ray, with [`Recorder::specular_hit`] right
/// after a hit's own (lab); then [`Recorder::scattered`] for the hits whose paths go on (path,
/// sixteen at a time: the diffuse hits first, then mirror and glass); then
/// [`Recorder::shaded`] for the diffuse hits of that wave, in the order of their
/// `closest_hit` calls. For one ray (the inspector's), a step is: its hit, how it scattered,
/// its light.
pub trait Recorder {
    /// Whether anything is recorded; the hooks are called only when it is true.
    const ENABLED: bool;

    /// A ray's closest hit, or `None` when the ray leaves the scene. `weight` is what its
    /// value is multiplied by (1 for a camera ray; the product of the specular weights along a
    /// Whitted branch; a path's throughput β); `depth` counts the mirror and glass hits before
    /// it (lab) or the path's vertices before it (path).
    fn closest_hit(&mut self, ray: &Ray, hit: Option<&Intersection>, weight: Vec3, depth: u32);

    /// Lab stages: a mirror or glass hit and the branches it spawns, each (direction, weight)
    /// ([`Material::specular_branches`]); empty when [`Shading::specular_depth`] is reached and
    /// the branch is given up (black). `weight` and `depth` are the arriving ray's.
    fn specular_hit(
        &mut self,
        hit: &Intersection,
        weight: Vec3,
        depth: u32,
        branches: &[(Vec3, Vec3)],
    );

    /// A diffuse hit's terms, its shadow ray answered (`terms.blocked`); `n` is the N it was
    /// valued with, `value` = [`HitTerms::value`], and the pixel gets `weight · value`.
    fn shaded(&mut self, terms: &HitTerms, n: Vec3, value: Vec3, weight: Vec3);

    /// Path stage: where the path goes from its latest hit (a cosine-weighted bounce of
    /// weight ρ, or [`Material::sample`] for mirror and glass), Russian
    /// roulette's survival probability (1 before [`path::ROULETTE_DEPTH`]), β after both, and
    /// whether the path goes on. Not called when the bounce cap ends the path at that hit.
    fn scattered(&mut self, scatter: &Scatter, survival: f32, beta: Vec3, survives: bool);

    /// General path tracer ([`path_mis`]): what a vertex computed, its BSDF and its
    /// next-event estimation with both densities and the MIS weight.
    fn path_vertex(&mut self, _vertex: &path_mis::PathVertex) {}
}

/// Normal rendering: records nothing, costs nothing.
impl Recorder for () {
    const ENABLED: bool = false;

    #[inline(always)]
    fn closest_hit(&mut self, _: &Ray, _: Option<&Intersection>, _: Vec3, _: u32) {}

    #[inline(always)]
    fn specular_hit(&mut self, _: &Intersection, _: Vec3, _: u32, _: &[(Vec3, Vec3)]) {}

    #[inline(always)]
    fn shaded(&mut self, _: &HitTerms, _: Vec3, _: Vec3, _: Vec3) {}

    #[inline(always)]
    fn scattered(&mut self, _: &Scatter, _: f32, _: Vec3, _: bool) {}
}
