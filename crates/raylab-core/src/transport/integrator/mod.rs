//! Integrators: what a camera ray is worth.
//!
//! Two integrators share everything below the choice of what to compute:
//!
//! * [`lab`]: the lab's stages (figures 2, 3, 5, 6 and 7), with mirror and glass followed
//!   Whitted-style: every specular branch is traced to a diffuse hit, which is then shaded as the
//!   stage says. Deterministic: sample 0 is the lab's image.
//! * [`path`]: Monte Carlo path tracing: the lab's direct term at every diffuse vertex plus real
//!   indirect light from cosine-weighted bounces, where the lab adds the constant N.
//!
//! **Units.** The lab's value of a diffuse hit is R = ρ·D (equation 28), where D is the
//! irradiance from the point light (equation 27). The radiance a diffuse surface reflects is
//! (ρ/π)·D, so the lab's image is π × radiance. The path tracer keeps those units: its image is
//! π × radiance too, so with no bounces it *is* the `shadows` stage, and each bounce adds the
//! real indirect light that the lab's N stands in for.
//!
//! **One computation at a hit.** Both integrators evaluate a diffuse hit with the same code:
//! [`Lighting::at`] computes D (equation 27) and the shadow ray (section 5.1), the caller casts
//! the shadow rays of a whole batch together and records whether each was blocked, and
//! [`shaded_value`] combines ρ, D and N as equations 28–30 say. That code is generic over a
//! lane type ([`crate::base::lanes`]): both integrators take it sixteen hits at a time through
//! `DiffuseHits` (the same operations in every lane, so the same bits; with the divisions and
//! square roots of a hit no longer one after another; PERFORMANCE.md, "Design choices and
//! what each buys"), and [`HitTerms`] ([`HitTerms::at`], [`HitTerms::value`]) is the same
//! code for one hit, which the tests and the pixel inspector's record of a hit use.
//! The one-ray path ([`Tracer::trace`] with one ray) is the batched path with a batch of one.
//!
//! **Watching a pixel.** Both integrators are generic over a [`Recorder`], told each step as it
//! happens (every closest hit, every mirror or glass branch, every hit's terms once its shadow
//! ray is answered, every path vertex's scattering). The renderer passes `()`, which records
//! nothing and compiles away; the pixel inspector ([`crate::teaching::inspect`]) passes a recording, so
//! what it explains is what the renderer computed, not a second copy of the formulas.

mod hits;
pub mod lab;
pub mod path;
pub mod path_mis;
pub mod photons;

use std::borrow::Cow;
use std::cell::RefCell;

use glam::Vec3;

use crate::base::camera::ImagePoints;
use crate::base::geometry::Ray;
use crate::base::lanes::{F32x16, M16, Mask, MaskOf, Real, Vec3x16, Vector, select_lazy};
use crate::base::memory::with_thread_memory;
use crate::base::sampling::Rng;
use crate::shading::bsdf::{Bsdf, ShadingFrame};
use crate::shading::light::{
    AnyLight, DirectLight, LightSpec, SHADOW_OFFSET, ShadowRays, shadow_rays_to,
};
use crate::shading::material::{Material, MaterialPreset, Scatter, TexturePreset};
use crate::shading::texture::planar_uv;
use crate::shapes::accel::SegmentLanes;
use crate::shapes::accel::set::{Compiled, InstructionSet};
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::Scene;
use crate::shapes::scene::spec::PartMaterial;
use crate::transport::film::Seen;
use crate::transport::photon_map::PhotonMap;
use crate::transport::settings::RenderSettings;

/// How many rays the integrators take through each phase together. Phases (all closest hits,
/// then the light at every hit, then all shadow rays, then the sums) are loops of independent
/// queries, which the CPU overlaps; ray by ray, every pixel's long chain of dependent divisions
/// and square roots runs alone (PERFORMANCE.md, "Design choices and what each buys": phase
/// batching).
pub const BATCH: usize = 64;

/// How many paths the sixteen-lane path tracer takes through each phase together: eight
/// batches of camera rays. Paths end at different vertices and each vertex's phases run in
/// whole groups of sixteen lanes, so at each vertex a batch's last group is partly empty: the
/// more paths a batch holds, the smaller that share, and the more paths share each phase's
/// own costs (calls, the kernels' set-up). 512 is where larger batches stop paying: a
/// thread's working memory still fits in its core's L2 cache (the images are the same at
/// any size; PERFORMANCE.md, "Design choices and what each buys" and "Tried and not kept
/// (details in git)"). The camera rays' first hits and their shadow rays are still bounded
/// by cones a batch of [`BATCH`] at a time (`accel::cull`: a wider fan keeps more
/// triangles). At most 65,536: a path's index in its batch is a `u16`.
pub const PATH_BATCH: usize = 512;
const _: () = assert!(PATH_BATCH.is_multiple_of(BATCH) && PATH_BATCH <= 1 << 16);

pub use crate::transport::settings::{
    DEFAULT_SPECULAR_DEPTH, Integrator, MAX_SPECULAR_DEPTH, Shading, Stage,
};
use hits::HitScratch;
pub(crate) use hits::{GROUPS, PATH_GROUPS};
use path::PathScratch;

/// The working memory of the sixteen-lane integrators' batches (the lab's waves, the path
/// tracer's vertices): the camera rays, the diffuse hits in lanes and the light at them, and
/// the path tracer's paths, here and the path batch's larger arrays on the heap
/// (`PathScratch`). Made once for a thread's rows and reused batch after batch: made afresh
/// for every batch of 64 rays, its zeroing (a `memset`) would be a share of the lab pass
/// (PERFORMANCE.md, "Design choices and what each buys": shared working memory).
pub struct Scratch {
    /// The lab's batches' hits, [`GROUPS`] groups.
    lab: HitScratch<GROUPS>,
    /// The path tracer's hits ([`PATH_GROUPS`] groups) and paths.
    path: PathScratch,
    /// A batch's camera rays, made from their image points.
    rays: [Ray; PATH_BATCH],
}

impl Scratch {
    /// Working memory for any batch: a batch takes only what it wrote into it (the lanes it
    /// left are computed with, never taken; `a_reused_scratch_gives_the_values_of_a_fresh_one`).
    pub fn new() -> Self {
        Self {
            lab: HitScratch::new(),
            path: PathScratch::new(),
            rays: [Ray {
                origin: glam::Vec3::ZERO,
                direction: glam::Vec3::ZERO,
            }; PATH_BATCH],
        }
    }
}

impl Default for Scratch {
    fn default() -> Self {
        Self::new()
    }
}

thread_local! {
    /// The working memory of this thread's single calls ([`Tracer::trace`],
    /// [`Tracer::trace_recorded`]), made at the first: a [`Scratch`] is far more memory to fill
    /// than a call on one pixel (the inspector's) traces through.
    static CALL_SCRATCH: RefCell<Option<Box<Scratch>>> = const { RefCell::new(None) };
}

impl Scratch {
    /// `work` with this thread's [`CALL_SCRATCH`], or a fresh one if it is in use (a call
    /// inside another's recorder).
    fn with_thread<T>(work: impl FnOnce(&mut Scratch) -> T) -> T {
        with_thread_memory(
            &CALL_SCRATCH,
            || None,
            |scratch| work(scratch.get_or_insert_with(Scratch::boxed)),
        )
    }

    /// A new working memory on the heap, made out of line: inlined, the whole [`Scratch`] would
    /// go into the callers' stack frames.
    #[cold]
    #[inline(never)]
    fn boxed() -> Box<Scratch> {
        Box::new(Scratch::new())
    }
}

/// The integrators' working memory ([`Scratch`]'s parts for the lab and the path tracer).
type Working<'a> = (&'a mut HitScratch<GROUPS>, &'a mut PathScratch);

/// The mirror and glass bounces a camera sample's features follow before they settle on what
/// was reached ([`Seen`]).
pub const FEATURE_SPECULAR_BOUNCES: u32 = 4;

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

/// What a batch of rays starts from, handed to the code compiled for the CPU as data.
#[derive(Clone, Copy)]
enum Primary<'a> {
    Rays(&'a [Ray]),
    /// Camera rays, made from their image points ([`ImagePoints::rays`]).
    Camera(&'a ImagePoints<'a>),
}

/// [`Tracer::trace_primary`] compiled for each instruction set ([`Compiled`]): with AVX-512's
/// 32 vector registers instead of 16, the long body of a path vertex spills less; with AVX2
/// and FMA, or the portable baseline. (A closure handed to the compiled function would stay
/// out of line, compiled without the set; so the camera rays come as data, [`Primary`].)
struct TracePrimary<'t, 'a> {
    tracer: &'t Tracer<'a>,
    primary: Primary<'t>,
    rngs: &'t mut [Rng],
    out: &'t mut [Vec3],
    seen: &'t mut [Option<Seen>],
    scratch: &'t mut Scratch,
}

impl Compiled for TracePrimary<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<S: InstructionSet>(self, _set: S) {
        let t = self.tracer;
        t.trace_primary(self.primary, self.rngs, self.out, self.seen, self.scratch);
    }
}

/// Everything an integrator needs for one pass: the scene, its materials with the preset
/// applied, the light and the shading switches.
#[derive(Debug)]
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub materials: Cow<'a, [Material]>,
    pub light: LightSpec,
    /// The light as an emitter ([`Light`]): what the general path tracer samples and sees.
    emitter: AnyLight,
    /// Whether the path tracer takes its diffuse vertices sixteen at a time with the lab's
    /// direct term ([`path`]): under a point light (the lab's, or a sphere or square of size
    /// 0), without a photon map.
    lane_light: bool,
    pub shading: Shading,
    /// Whether anything draws random numbers: the path tracer, a spherical light's soft
    /// shadows, a thin lens's aperture.
    random: bool,
    /// No texture and no smooth normal anywhere: every surface is the lab's (flat, constant ρ).
    plain: bool,
    /// Every material diffuse (no mirror, glass or rough metal).
    all_diffuse: bool,
    /// A plain scene's triangles as tables, if it has at most 32 ([`hits::TriangleTable`]).
    triangle_table: Option<hits::TriangleTable>,
    /// The pass's caustic photon map, when the path stage gathers caustics from photons
    /// ([`Tracer::for_pass`]).
    photons: Option<PhotonMap>,
}

impl<'a> Tracer<'a> {
    pub fn new(scene: &'a Scene, settings: &RenderSettings) -> Self {
        let mut materials = match settings.material_preset {
            MaterialPreset::None => Cow::Borrowed(scene.materials.as_slice()),
            preset => Cow::Owned(preset.apply(&scene.materials, settings.roughness)),
        };
        if !settings.part_materials.is_empty() {
            let mut own = materials.into_owned();
            PartMaterial::apply(&settings.part_materials, &mut own);
            materials = Cow::Owned(own);
        }
        if settings.texture_preset != TexturePreset::None {
            materials = Cow::Owned(settings.texture_preset.apply(&materials));
        }
        let random = settings.is_stochastic();
        // The lab's direct term in lanes is the light sample of a point light; a photon map
        // is gathered at the diffuse vertices one at a time.
        let point_light = matches!(settings.light.emitter(), AnyLight::Point(_));
        let lane_light = point_light && !settings.shading.photon_caustics();
        let plain = materials
            .iter()
            .all(|m| m.texture.is_none() && m.relief.is_none())
            && (scene.vertex_normals.is_empty() || !settings.shading.smooth);
        let all_diffuse = materials.iter().all(Material::is_diffuse);
        let triangle_table = match plain {
            true => hits::TriangleTable::new(scene, &materials),
            false => None,
        };
        Self {
            scene,
            materials,
            light: settings.light,
            emitter: settings.light.emitter(),
            lane_light,
            shading: settings.shading,
            random,
            plain,
            all_diffuse,
            triangle_table,
            photons: None,
        }
    }

    /// The tracer of pass (sample) `pass`: [`Tracer::new`], with the pass's caustic photon
    /// map shot when the path stage gathers caustics from photons ([`photons::shoot`], seeded
    /// by the settings' seed and `pass`).
    pub fn for_pass(scene: &'a Scene, settings: &RenderSettings, pass: u32) -> Self {
        let mut tracer = Self::new(scene, settings);
        if settings.shading.photon_caustics() {
            let map = photons::shoot(&tracer, settings.shading.photons, settings.seed, pass);
            tracer.photons = Some(map);
        }
        tracer
    }

    /// The pass's caustic photon map, if it has one ([`Tracer::for_pass`]).
    #[inline]
    pub fn photon_map(&self) -> Option<&PhotonMap> {
        self.photons.as_ref()
    }

    /// The surface at a diffuse hit found by a ray going along `incoming`: its shading normal
    /// (smooth or flat, as the switch and the mesh say), its own normal, ρ (textured: at the
    /// mesh's texture coordinates, or at a planar projection of the hit for surfaces without
    /// them, such as the box's walls), and whether it lies at an edge of its triangle (asked
    /// only when shadow rays are cast, which alone need it).
    #[inline(always)]
    pub fn surface(&self, hit: &Intersection, material: &Material, incoming: Vec3) -> Surface {
        let at_edge = if self.shading.shadows {
            let (index, u, v) = (hit.triangle_index, hit.u, hit.v);
            self.scene.approach_at_edge(index, u, v, incoming)
        } else {
            None
        };
        self.surface_with(hit, material, incoming, at_edge)
    }

    /// What a path or a photon scatters with at `hit`, reached along `direction`: the hit's
    /// surface (its relief applied, `at_edge` found), the material's BSDF for its ρ, and the
    /// shading frame toward `wo = −direction` ([`ShadingFrame::new`]).
    #[inline(always)]
    pub fn scattering(&self, hit: &Intersection, direction: Vec3) -> Scattering {
        let scene = self.scene;
        let material = self.material_of(hit.triangle_index);
        let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, direction);
        self.scattering_with(hit, material, direction, at_edge)
    }

    /// [`Tracer::scattering`] with the hit's `material` and `at_edge` given. A mirror or
    /// glass scatters about [`Tracer::specular_normal`] (a smooth normal could send its
    /// reflection below the surface), as the lab's stages follow it.
    #[inline(always)]
    pub fn scattering_with(
        &self,
        hit: &Intersection,
        material: &Material,
        direction: Vec3,
        at_edge: Option<Vec3>,
    ) -> Scattering {
        let mut surface = self.surface_with(hit, material, direction, at_edge);
        if material.is_specular() && material.relief.is_none() {
            surface.normal = surface.geometric;
        }
        let wo = -direction;
        Scattering {
            bsdf: material.bsdf(surface.rho),
            frame: ShadingFrame::new(surface.normal, surface.geometric, wo),
            surface,
            wo,
        }
    }

    /// [`Tracer::surface`] with `at_edge` given: the path tracer asks it of every hit anyway,
    /// for the ray that leaves it ([`continue_ray`]).
    ///
    /// A material with a relief ([`crate::shading::relief`]: a normal map, parallax occlusion mapping)
    /// changes the texture coordinates ρ is looked up at and the shading normal, here for
    /// every integrator. The map's tilt is held to the shading frame's rules toward the
    /// viewer, `-incoming` ([`ShadingFrame::bent_normal`]), with the normal it tilts (the
    /// triangle's own, or smooth shading's) in the geometric normal's place: the map never
    /// turns the normal further from the viewer than it was (no black patches), and a flat
    /// map leaves it as it was. The triangle's own normal then rules as it does for any
    /// smooth normal: [`Lighting::at`] gives no light from behind the surface, and the path
    /// tracers' [`ShadingFrame::new`] bends it again where needed (no light leaks).
    #[inline(always)]
    pub fn surface_with(
        &self,
        hit: &Intersection,
        material: &Material,
        incoming: Vec3,
        at_edge: Option<Vec3>,
    ) -> Surface {
        let (index, u, v) = (hit.triangle_index, hit.u, hit.v);
        let scene = self.scene;
        let geometric = scene.triangles[index].normal;
        if self.plain {
            // The same values as below (flat normal, constant ρ) without asking per hit, in the
            // lab pass's inner loop (PERFORMANCE.md, "Design choices and what each buys").
            return Surface {
                position: hit.position,
                normal: geometric,
                geometric,
                rho: material.reflectance,
                at_edge,
                relief_visibility: 1.0,
            };
        }
        let normal = scene.shading_normal(index, u, v, self.shading.smooth);
        let uv = || {
            scene
                .uv(index, u, v)
                .unwrap_or_else(|| planar_uv(hit.position, geometric))
        };
        let Some(relief) = &material.relief else {
            return Surface {
                position: hit.position,
                normal,
                geometric,
                rho: material.reflectance_at(uv, hit.position, normal),
                at_edge,
                relief_visibility: 1.0,
            };
        };
        let wo = -incoming;
        let frame = scene.tangent_frame(index, normal);
        let (uv, bumped) = relief.at(&frame, uv(), wo);
        let normal = if relief.normal.is_some() {
            ShadingFrame::bent_normal(bumped, normal, wo)
        } else {
            normal
        };
        // Parallax self-shadowing, toward the light's centre as D is (equation 27).
        let relief_visibility = if self.shading.parallax_shadows {
            let to_light = (self.light.position - hit.position).normalize_or_zero();
            relief.visibility(&frame, uv, to_light)
        } else {
            1.0
        };
        Surface {
            position: hit.position,
            normal,
            geometric,
            rho: material.reflectance_at(|| uv, hit.position, normal),
            at_edge,
            relief_visibility,
        }
    }

    /// The normal a mirror or glass `material` reflects and refracts about at `hit`, reached
    /// along `incoming`: the triangle's own (a smooth normal could send a reflection below the
    /// surface), or, where the material has a relief (a normal map, the water's waves), the
    /// relief's bent normal, [`Tracer::surface_with`]'s. The lab's stages and the sixteen-lane
    /// path tracer both ask it here; the general path tracer's [`Tracer::scattering`] holds
    /// the same bent normal in its frame.
    #[inline(always)]
    pub fn specular_normal(&self, hit: &Intersection, material: &Material, incoming: Vec3) -> Vec3 {
        match &material.relief {
            None => self.scene.triangles[hit.triangle_index].normal,
            Some(_) => self.surface_with(hit, material, incoming, None).normal,
        }
    }

    /// What the lab's stages use as ρ at a glossy hit (the rough metal): π·f(wo, wi), with wo
    /// toward the viewer and wi toward the light's centre, evaluated in the hit's shading
    /// frame ([`ShadingFrame::eval_world`]); for a diffuse surface this would be ρ itself.
    /// Multiplied by D (equation 27) it is the light the surface reflects toward the viewer.
    pub fn glossy_reflectance(
        &self,
        material: &Material,
        surface: &Surface,
        incoming: Vec3,
    ) -> Vec3 {
        let wo = -incoming;
        let wi = (self.light.position - surface.position).normalize_or_zero();
        let frame = ShadingFrame::new(surface.normal, surface.geometric, wo);
        let (f, _) = frame.eval_world(&material.bsdf(surface.rho), wo, wi);
        std::f32::consts::PI * f
    }

    /// [`Tracer::glossy_reflectance`]'s two parts, π·f_s (the microfacet highlight: a
    /// plastic's coating, all of a rough metal) and π·f_d (a plastic's diffuse base), each
    /// evaluated as the whole is: for the inspector.
    pub fn glossy_parts(
        &self,
        material: &Material,
        surface: &Surface,
        incoming: Vec3,
    ) -> (Vec3, Vec3) {
        let wo = -incoming;
        let wi = (self.light.position - surface.position).normalize_or_zero();
        let frame = ShadingFrame::new(surface.normal, surface.geometric, wo);
        let pi_f = |bsdf: &crate::shading::bsdf::Bsdf| {
            std::f32::consts::PI * frame.eval_world(bsdf, wo, wi).0
        };
        match material.bsdf(surface.rho) {
            crate::shading::bsdf::Bsdf::Plastic(plastic) => {
                let (coating, base) = plastic.lobes();
                (pi_f(&coating), pi_f(&base))
            }
            bsdf @ (crate::shading::bsdf::Bsdf::RoughConductor { .. }
            | crate::shading::bsdf::Bsdf::Lambertian { .. }
            | crate::shading::bsdf::Bsdf::Mirror { .. }
            | crate::shading::bsdf::Bsdf::Glass { .. }) => (pi_f(&bsdf), Vec3::ZERO),
        }
    }

    /// The scene's light as an emitter.
    #[inline]
    pub fn emitter(&self) -> &AnyLight {
        &self.emitter
    }

    /// The material of triangle `index`.
    #[inline]
    pub fn material_of(&self, triangle_index: usize) -> &Material {
        &self.materials[self.scene.triangles[triangle_index].material as usize]
    }

    /// What a camera ray whose first hit is `hit`, a mirror or glass, sees through it ([`Seen`]),
    /// the same for every sample along that ray: both specular branches are followed at each
    /// mirror and glass hit, Whitted-style with their weights ([`Material::specular_branches`],
    /// as the lab's stages trace them), to the first surface that is not a perfect specular one
    /// or the one reached after [`FEATURE_SPECULAR_BOUNCES`]. The albedo is the sum of those
    /// surfaces' reflectances times their branches' weights: the mean of what the path tracer's
    /// samples see along one lobe each, without its noise. The normal and the distance are
    /// the surfaces' averaged by their branches' weights; `None` if every branch leaves the
    /// scene.
    pub fn seen_through_specular(&self, ray: Ray, hit: Intersection) -> Option<Seen> {
        // Depth first: at most one pending branch a bounce, plus the one being followed.
        let mut stack =
            [(ray, hit, Vec3::ONE, 0u32, 0.0f32); FEATURE_SPECULAR_BOUNCES as usize + 2];
        let mut pending = 1;
        let (mut albedo, mut normal, mut depth, mut weights) = (Vec3::ZERO, Vec3::ZERO, 0.0, 0.0);
        while pending > 0 {
            pending -= 1;
            let (ray, hit, weight, bounces, travelled) = stack[pending];
            let travelled = travelled + hit.distance;
            let material = self.material_of(hit.triangle_index);
            if !material.is_specular() || bounces == FEATURE_SPECULAR_BOUNCES {
                let scattering = self.scattering(&hit, ray.direction);
                let rho = match scattering.bsdf {
                    Bsdf::RoughConductor { tint, .. } => tint,
                    Bsdf::Lambertian { .. }
                    | Bsdf::Mirror { .. }
                    | Bsdf::Glass { .. }
                    | Bsdf::Plastic(_) => scattering.surface.rho,
                };
                let normal_there = scattering.frame.shading_normal();
                let seen = Seen::at(weight, rho, normal_there, scattering.wo, travelled);
                let w = (weight.x + weight.y + weight.z) / 3.0;
                albedo += seen.albedo;
                normal += w * seen.normal;
                depth += w * seen.depth;
                weights += w;
                continue;
            }
            let d = ray.direction;
            let surface_normal = self.specular_normal(&hit, material, d);
            let at_edge = self
                .scene
                .approach_at_edge(hit.triangle_index, hit.u, hit.v, d);
            for &(direction, w) in material.specular_branches(d, surface_normal).as_slice() {
                let weight = weight * w;
                if weight.max_element() <= 0.0 {
                    continue;
                }
                let next = continue_ray(hit.position, surface_normal, direction, at_edge);
                if let Some(next_hit) = self.scene.closest_intersection(&next, f32::INFINITY) {
                    stack[pending] = (next, next_hit, weight, bounces + 1, travelled);
                    pending += 1;
                }
            }
        }
        if weights > 0.0 {
            Some(Seen {
                albedo,
                normal: normal / weights,
                depth: depth / weights,
            })
        } else {
            None
        }
    }

    /// Whether the integrator draws random numbers (and so needs each ray's generator).
    pub fn uses_random_numbers(&self) -> bool {
        self.random
    }

    /// Whether the integrator tells what each camera sample sees ([`Seen`]) as it traces it:
    /// the path tracer does, at no extra ray but those of the specular branches of a camera
    /// ray that meets a mirror or glass first. For the lab's stages the denoiser's features
    /// are traced apart ([`crate::transport::denoise::Features::trace`]).
    pub fn records_features(&self) -> bool {
        self.shading.stage.integrator() == Integrator::Path
    }

    /// How many camera rays to hand [`Tracer::trace_camera`] at a time: [`PATH_BATCH`] for
    /// the path tracer, [`BATCH`] for the lab's stages.
    pub fn batch_len(&self) -> usize {
        if self.records_features() {
            PATH_BATCH
        } else {
            BATCH
        }
    }

    /// The value of each ray, into `out`. `rngs` holds each ray's random stream (from
    /// [`crate::base::sampling::pixel_sample`]); where nothing is random
    /// ([`Tracer::uses_random_numbers`] is false) it may be empty.
    ///
    /// On a CPU with AVX2 and FMA, or AVX-512 (where the scene's kernels use them), the same
    /// code is compiled for that instruction set: the results are the same bit for bit (Rust never
    /// fuses a multiply and an add on its own, and every operation here is exactly rounded), and
    /// the path tracer runs faster (PERFORMANCE.md, "Design choices and what each buys").
    pub fn trace(&self, rays: &[Ray], rngs: &mut [Rng], out: &mut [Vec3]) {
        debug_assert_eq!(rays.len(), out.len());
        Scratch::with_thread(|scratch| {
            self.trace_for_cpu(Primary::Rays(rays), rngs, out, &mut [], scratch)
        });
    }

    /// [`Tracer::trace`] for the camera rays through `points`, made here
    /// ([`ImagePoints::rays`]) so that they too are made with the CPU's instruction set,
    /// sixteen at a time. The same rays as [`crate::Camera::primary_ray_rotated`] (or
    /// [`crate::Camera::lens_ray_rotated`]) makes one at a time, bit for bit.
    ///
    /// If `seen` is not empty (one per ray) and the integrator [records
    /// features](Tracer::records_features), each ray's [`Seen`] goes there (`None`: it left
    /// the scene); otherwise `seen` is left as it is. The batches work in `scratch`, which a
    /// caller tracing many batches (the rows of the image) makes once and hands to each.
    pub fn trace_camera(
        &self,
        points: &ImagePoints,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        debug_assert_eq!(points.len(), out.len());
        debug_assert!(seen.is_empty() || seen.len() == out.len());
        self.trace_for_cpu(Primary::Camera(points), rngs, out, seen, scratch);
    }

    /// [`Tracer::trace_primary`] in the code compiled for the CPU's instruction set
    /// ([`TracePrimary`]).
    #[inline(always)]
    fn trace_for_cpu(
        &self,
        primary: Primary,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        self.scene.accel().isa().call(TracePrimary {
            tracer: self,
            primary,
            rngs,
            out,
            seen,
            scratch,
        });
    }

    /// The rays of `primary`, made in batches of [`Tracer::batch_len`] if they come as image
    /// points, traced by [`Tracer::trace_seen`].
    #[inline(always)]
    fn trace_primary(
        &self,
        primary: Primary,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        match primary {
            Primary::Rays(rays) => {
                let working = (&mut scratch.lab, &mut scratch.path);
                self.trace_seen(rays, rngs, out, seen, working, &mut ())
            }
            // The batch's length a constant in each: as a run-time value the loops around it
            // compile less tightly.
            Primary::Camera(points) if self.batch_len() == PATH_BATCH => {
                self.camera_batches::<PATH_BATCH>(points, rngs, out, seen, scratch)
            }
            Primary::Camera(points) => {
                self.camera_batches::<BATCH>(points, rngs, out, seen, scratch)
            }
        }
    }

    /// The camera rays through `points` made and traced `LEN` at a time ([`Tracer::batch_len`]).
    #[inline(always)]
    fn camera_batches<const LEN: usize>(
        &self,
        points: &ImagePoints,
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        scratch: &mut Scratch,
    ) {
        let Scratch { lab, path, rays } = scratch;
        for (c, out) in out.chunks_mut(LEN).enumerate() {
            let rays = &mut rays[..out.len()];
            for (k, rays) in rays.chunks_mut(ImagePoints::MAX_RAYS).enumerate() {
                points.rays(c * LEN + k * ImagePoints::MAX_RAYS, rays);
            }
            // Each ray's generator (none if nothing is random) and features (none if not asked
            // for).
            let part = |all: usize| {
                let start = (c * LEN).min(all);
                start..(start + LEN).min(all)
            };
            let (r, s) = (part(rngs.len()), part(seen.len()));
            let (rngs, seen) = (&mut rngs[r], &mut seen[s]);
            self.trace_seen(rays, rngs, out, seen, (lab, path), &mut ());
        }
    }

    /// [`Tracer::trace`] for any CPU; inlined into the AVX2 version.
    #[inline(always)]
    pub fn trace_portable(&self, rays: &[Ray], rngs: &mut [Rng], out: &mut [Vec3]) {
        Scratch::with_thread(|Scratch { lab, path, .. }| {
            self.trace_seen(rays, rngs, out, &mut [], (lab, path), &mut ())
        });
    }

    /// [`Tracer::trace_portable`], telling `recorder` every step (see [`Recorder`]): what the
    /// pixel inspector runs. With `()` it is `trace_portable` itself.
    #[inline(always)]
    pub fn trace_recorded<R: Recorder>(
        &self,
        rays: &[Ray],
        rngs: &mut [Rng],
        out: &mut [Vec3],
        recorder: &mut R,
    ) {
        Scratch::with_thread(|Scratch { lab, path, .. }| {
            self.trace_seen(rays, rngs, out, &mut [], (lab, path), recorder)
        });
    }

    /// [`Tracer::trace_recorded`], and what each ray sees into `seen` as
    /// [`Tracer::trace_camera`] says.
    #[inline(always)]
    fn trace_seen<R: Recorder>(
        &self,
        rays: &[Ray],
        rngs: &mut [Rng],
        out: &mut [Vec3],
        seen: &mut [Option<Seen>],
        (lab, path): Working,
        recorder: &mut R,
    ) {
        match self.shading.stage.integrator() {
            Integrator::Lab => {
                assert!(
                    !self.random || rngs.len() == rays.len(),
                    "soft shadows and the lens need a generator per ray"
                );
                lab::trace(self, rays, rngs, out, lab, recorder);
            }
            Integrator::Path => {
                assert_eq!(
                    rngs.len(),
                    rays.len(),
                    "the path tracer needs a generator per ray"
                );
                path::trace(self, rays, rngs, out, seen, path, recorder);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Camera;
    use crate::base::lanes::LANES;
    use crate::shading::light::LightKind;
    use crate::shapes::scene::cornell_box;
    use crate::test_support::primary_rays;

    #[test]
    fn stages_parse_and_name_their_figures() {
        for stage in Stage::ALL {
            assert_eq!(stage.name().parse::<Stage>(), Ok(stage));
        }
        assert_eq!(
            Stage::LAB.map(|s| s.figure().unwrap()),
            [2, 3, 5, 6, 7],
            "the lab's figures"
        );
        assert_eq!(Stage::Path.figure(), None);
        assert!("phong".parse::<Stage>().unwrap_err().contains("phong"));
        assert_eq!(Shading::default().stage, Stage::Lab);
        assert!(Shading::default().shadows && Shading::default().indirect);
        assert_eq!(Shading::default().indirect_term(), Vec3::splat(0.5));
        // The path tracer replaces N by real bounces.
        assert_eq!(Shading::for_stage(Stage::Path).indirect_term(), Vec3::ZERO);
        assert_eq!(Shading::for_stage(Stage::Path).max_bounces(), u32::MAX);
    }

    #[test]
    fn descriptions_follow_the_switches() {
        let none = MaterialPreset::None;
        let mut s = Shading::for_stage(Stage::Lab);
        assert_eq!(
            s.description(none),
            "ρ·(D + N) (eq. 30) with shadows (§5.1)"
        );
        s.shadows = false;
        s.indirect = false;
        assert_eq!(s.description(none), "ρ·D (eq. 28)");
        let mut p = Shading::for_stage(Stage::Path);
        assert!(p.description(none).contains("Russian roulette"));
        p.bounces = Some(2);
        assert!(p.description(none).contains("up to 2 bounces"));
        p.indirect = false;
        assert!(p.description(none).contains("direct light only"));
        assert!(
            Shading::for_stage(Stage::Lab)
                .description(MaterialPreset::Glass)
                .contains("Whitted")
        );
    }

    /// Hand-computed terms at the floor's centre (0, 1, 0) under the lab's light at
    /// (0, −0.5, −0.7): r = (0, −1.5, −0.7), r² = 2.74, r̂·n̂ = 1.5/√2.74 = 0.906183, so
    /// D = 14 · 0.906183 / (4π · 2.74) = 0.368454; green ρ = (0.15, 0.75, 0.15) gives
    /// ρ·(D + N) = (0.130268, 0.651341, 0.130268).
    #[test]
    fn hit_terms_at_the_floor_centre() {
        let light = LightSpec::default();
        let floor = Vec3::new(0.0, -1.0, 0.0);
        let rho = Vec3::new(0.15, 0.75, 0.15);
        let p = Vec3::new(0.0, 1.0, 0.0);
        let surface = Surface {
            position: p,
            normal: floor,
            geometric: floor,
            rho,
            at_edge: None,
            relief_visibility: 1.0,
        };
        let t = HitTerms::at(&light, Stage::Lab, true, surface, |_| light.position);
        assert!(
            (t.d - Vec3::splat(0.368454)).abs().max_element() < 1e-6,
            "{}",
            t.d
        );
        assert!(t.shadow_ray.is_some());
        let v = t.value(Stage::Lab, Vec3::splat(0.5));
        assert!(
            (v - Vec3::new(0.130268, 0.651341, 0.130268))
                .abs()
                .max_element()
                < 1e-6
        );
        let blocked = HitTerms { blocked: true, ..t };
        assert_eq!(blocked.value(Stage::Lab, Vec3::splat(0.5)), rho * 0.5);
        assert_eq!(blocked.value(Stage::Incoming, Vec3::ZERO), Vec3::ZERO);
        // The flat stage computes no light at all.
        let flat = HitTerms::at(&light, Stage::Flat, true, surface, |_| light.position);
        assert_eq!((flat.d, flat.shadow_ray), (Vec3::ZERO, None));
        assert_eq!(flat.value(Stage::Flat, Vec3::ZERO), rho);
    }

    /// Hits of every kind the lanes must get right, each with its own lit point: anywhere in
    /// the box, smooth normals (on the lit side and the unlit one), zero normals, at edges of
    /// their triangles, the light within [`crate::shading::light::MIN_LIGHT_DISTANCE`] or exactly on the
    /// point, behind the surface, and at infinity.
    fn awkward_surfaces(light: &LightSpec) -> Vec<Surface> {
        let mut rng = Rng::for_pixel_sample(7, 3, 5, 0);
        let mut r = move || rng.next_f32() * 2.0 - 1.0;
        let mut surfaces = Vec::new();
        for i in 0..4096 {
            let mut position = Vec3::new(r(), r(), r());
            let geometric = Vec3::new(r(), r(), r()).normalize_or_zero();
            let mut normal = geometric;
            match i % 8 {
                // A smooth normal, sometimes turned far enough to face the light when the
                // surface itself does not.
                1 => normal = (geometric + Vec3::new(r(), r(), r())).normalize_or_zero(),
                // Within MIN_LIGHT_DISTANCE of the light, or on it.
                2 => position = light.position + 4e-4 * Vec3::new(r(), r(), r()),
                3 => position = light.position,
                // Just off the surface through the light, on either side.
                4 => position = light.position + 1e-4 * r() * geometric,
                5 => normal = Vec3::ZERO,
                6 if i % 64 == 6 => position = Vec3::new(f32::INFINITY, 0.0, r()),
                _ => {}
            }
            let at_edge = (i % 3 == 0).then(|| Vec3::new(r(), r(), r()).normalize_or_zero());
            surfaces.push(Surface {
                position,
                normal,
                geometric,
                rho: Vec3::new(r(), r(), r()).abs(),
                at_edge,
                relief_visibility: 1.0,
            });
        }
        surfaces
    }

    /// A stand-in for a spherical light's point ([`light_point`]) that depends on the hit, so
    /// that the lanes must hand each its own.
    fn sphere_point(light: &LightSpec, p: Vec3) -> Vec3 {
        light.position + 0.05 * p
    }

    /// [`Lighting::at`] sixteen at a time, with [`sphere_point`] for the lanes that want it.
    #[inline(always)]
    fn lit_lanes(
        light: &LightSpec,
        shading: &Shading,
        surfaces: &Surfaces<Vec3x16>,
        sphere: bool,
    ) -> (Lighting<Vec3x16>, M16) {
        let mut asked = M16::NONE;
        let lit = Lighting::at(
            light,
            shading.stage,
            shading.shadows,
            surfaces,
            |p, wanted| {
                asked = wanted;
                let mut target = Vec3x16::splat(light.position);
                if sphere {
                    for k in 0..LANES {
                        target.set_lane(k, sphere_point(light, p.lane(k)));
                    }
                }
                target
            },
        );
        (lit, asked)
    }

    /// [`lit_lanes`] compiled for each instruction set, as the lab's wave is.
    struct LitLanes<'a> {
        light: &'a LightSpec,
        shading: &'a Shading,
        surfaces: &'a Surfaces<Vec3x16>,
        sphere: bool,
    }

    impl Compiled for LitLanes<'_> {
        type Output = (Lighting<Vec3x16>, M16);
        #[inline(always)]
        fn run<S: InstructionSet>(self, _set: S) -> Self::Output {
            lit_lanes(self.light, self.shading, self.surfaces, self.sphere)
        }
    }

    /// The lab's terms sixteen hits at a time ([`Lighting::at`] at [`Vec3x16`], as the lab's
    /// wave computes them, compiled portably and for each instruction set the CPU has) equal
    /// [`HitTerms::at`] one hit at a time, bit for bit: D, the shadow ray (whether it is cast,
    /// its origin, direction and length), the value blocked or not, in every stage with shadows
    /// on and off, for the lab's light, a coloured one and a spot, with a point light and with a
    /// stand-in for a spherical one's points (asked for exactly where the one-hit code asks).
    #[test]
    fn sixteen_hits_at_a_time_equal_one_at_a_time() {
        let coloured = LightSpec {
            position: Vec3::new(0.3, 0.9, 0.2),
            power: 3.5,
            colour: Vec3::new(1.0, 0.25, 0.0),
            kind: LightKind::Point,
        };
        // A spot aimed so that the awkward surfaces lie in its beam, its falloff and outside.
        let spot = LightSpec {
            kind: LightKind::Spot(crate::shading::light::SpotCone {
                aim: Vec3::new(0.2, 1.0, 0.1),
                cutoff: 0.6,
                beam: 0.3,
            }),
            ..coloured
        };
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        // Every set this CPU runs, the portable one first.
        let builds = crate::shapes::accel::Isa::available_for_tests("sixteen_hits_at_a_time");
        let mut cast = 0;
        for light in [LightSpec::default(), coloured, spot] {
            let surfaces = awkward_surfaces(&light);
            for stage in Stage::LAB {
                for shadows in [false, true] {
                    let mut shading = Shading::for_stage(stage);
                    shading.shadows = shadows;
                    let n = shading.indirect_term();
                    for sphere in [false, true] {
                        for group in surfaces.chunks(LANES) {
                            let mut lanes = Surfaces::ZERO;
                            for (k, s) in group.iter().enumerate() {
                                lanes.set(k, *s);
                            }
                            for isa in &builds {
                                let build = isa.name();
                                let (lit, asked) = isa.call(LitLanes {
                                    light: &light,
                                    shading: &shading,
                                    surfaces: &lanes,
                                    sphere,
                                });
                                for (k, s) in group.iter().enumerate() {
                                    let mut one_asked = false;
                                    let one = HitTerms::at(&light, stage, shadows, *s, |p| {
                                        one_asked = true;
                                        if sphere {
                                            sphere_point(&light, p)
                                        } else {
                                            light.position
                                        }
                                    });
                                    let what = format!("{build} {stage} {shadows} {sphere} {s:?}");
                                    assert_eq!(bits(lit.d.lane(k)), bits(one.d), "D: {what}");
                                    let ray = lit.shadow.lane(k);
                                    let ray_bits = |r: Option<(Ray, f32)>| {
                                        r.map(|(r, t)| {
                                            (bits(r.origin), bits(r.direction), t.to_bits())
                                        })
                                    };
                                    assert_eq!(ray_bits(ray), ray_bits(one.shadow_ray), "{what}");
                                    assert_eq!(asked.0[k], one_asked, "asked: {what}");
                                    cast += usize::from(ray.is_some());
                                    for blocked in [false, true] {
                                        let mut b = M16::NONE;
                                        b.0[k] = blocked;
                                        let value = shaded_value(
                                            stage,
                                            lanes.rho,
                                            lit.d,
                                            b,
                                            Vec3x16::splat(n),
                                        );
                                        let one = HitTerms { blocked, ..one };
                                        assert_eq!(
                                            bits(value.lane(k)),
                                            bits(one.value(stage, n)),
                                            "value: {what} {blocked}"
                                        );
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(cast > 10_000, "{cast}");
    }

    /// The code compiled for the CPU (AVX2 and FMA, or AVX-512 where the kernels use it) gives
    /// bit for bit what the portable build gives, in every stage and with every preset (Rust
    /// never fuses a multiply-add on its own).
    #[test]
    fn the_builds_for_the_cpu_equal_the_portable_one() {
        let scene = cornell_box();
        let rays = primary_rays(&Camera::default_for(40, 30));
        for preset in MaterialPreset::ALL {
            for stage in Stage::ALL {
                let mut settings = RenderSettings::default();
                settings.shading = Shading::for_stage(stage);
                settings.material_preset = preset;
                let tracer = Tracer::new(&scene, &settings);
                let rngs = || -> Vec<Rng> {
                    (0..rays.len())
                        .map(|i| Rng::for_pixel_sample(4, i as u32, 1, 2))
                        .collect()
                };
                let mut fast = vec![Vec3::NAN; rays.len()];
                tracer.trace(&rays, &mut rngs(), &mut fast);
                let mut portable = vec![Vec3::NAN; rays.len()];
                tracer.trace_portable(&rays, &mut rngs(), &mut portable);
                let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                    v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
                };
                assert_eq!(bits(&fast), bits(&portable), "{stage} {preset}");
            }
        }
    }

    /// A [`Scratch`] reused batch after batch, as a row's batches reuse it, holds whatever the
    /// batches before left in it (other stages, other presets, more groups of hits than this
    /// batch has): the values are bit for bit those traced with a fresh one.
    #[test]
    fn a_reused_scratch_gives_the_values_of_a_fresh_one() {
        let scene = cornell_box();
        let rays = primary_rays(&Camera::default_for(53, 29));
        let mut reused = Scratch::new();
        let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
            v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
        };
        for preset in [MaterialPreset::Both, MaterialPreset::None] {
            for stage in Stage::ALL {
                let mut settings = RenderSettings::default();
                settings.shading = Shading::for_stage(stage);
                settings.material_preset = preset;
                let tracer = Tracer::new(&scene, &settings);
                // Batches of 64, then of fewer: later groups keep an earlier batch's hits.
                for (c, rays) in rays.chunks(BATCH).chain(rays.chunks(23)).enumerate() {
                    let rngs = || -> Vec<Rng> {
                        (0..rays.len())
                            .map(|i| Rng::for_pixel_sample(5, i as u32, c as u32, 1))
                            .collect()
                    };
                    let mut fresh = vec![Vec3::NAN; rays.len()];
                    let mut again = vec![Vec3::NAN; rays.len()];
                    let mut scratch = Scratch::new();
                    let primary = Primary::Rays(rays);
                    tracer.trace_for_cpu(primary, &mut rngs(), &mut fresh, &mut [], &mut scratch);
                    tracer.trace_for_cpu(primary, &mut rngs(), &mut again, &mut [], &mut reused);
                    assert_eq!(bits(&again), bits(&fresh), "{stage} {preset} batch {c}");
                }
            }
        }
    }

    /// One ray at a time gives bit for bit what a batch gives, in every stage, with and without
    /// mirror and glass.
    #[test]
    fn one_ray_at_a_time_equals_the_batch() {
        let scene = cornell_box();
        let rays = primary_rays(&Camera::default_for(61, 47));
        for preset in [MaterialPreset::None, MaterialPreset::Both] {
            for stage in Stage::ALL {
                for shadows in [false, true] {
                    let mut settings = RenderSettings::default();
                    settings.shading = Shading::for_stage(stage);
                    settings.shading.shadows = shadows;
                    settings.material_preset = preset;
                    let tracer = Tracer::new(&scene, &settings);
                    let rng = |i: usize| Rng::for_pixel_sample(1, i as u32, 0, 0);
                    let mut rngs: Vec<Rng> = (0..rays.len()).map(rng).collect();
                    let mut out = vec![Vec3::NAN; rays.len()];
                    tracer.trace(&rays, &mut rngs, &mut out);
                    for (i, (ray, got)) in rays.iter().zip(&out).enumerate() {
                        let mut one = [Vec3::NAN];
                        tracer.trace(&[*ray], &mut [rng(i)], &mut one);
                        assert_eq!(
                            got.to_array().map(f32::to_bits),
                            one[0].to_array().map(f32::to_bits),
                            "{stage} {preset} pixel {i}"
                        );
                    }
                }
            }
        }
    }
    /// Where rays leave surfaces, sixteen at a time, bit for bit [`continue_ray`] one at a
    /// time: on either side, at edges and not, and leaving along the surface itself.
    #[test]
    fn departures_sixteen_at_a_time_equal_one_at_a_time() {
        let light = LightSpec::default();
        let surfaces = awkward_surfaces(&light);
        let mut rng = Rng::new(31);
        for chunk in surfaces.chunks(LANES) {
            let mut lanes = Surfaces::<Vec3x16>::ZERO;
            let mut directions = Vec3x16::ZERO;
            let mut one_at_a_time = Vec::new();
            for (i, s) in chunk.iter().enumerate() {
                let random = Vec3::new(
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                    rng.uniform(-1.0, 1.0),
                )
                .normalize_or_zero();
                // Every fourth along the surface: `direction · normal` is 0.
                let direction = if i % 4 == 0 {
                    random.cross(s.geometric)
                } else {
                    random
                };
                lanes.set(i, *s);
                directions.set_lane(i, direction);
                one_at_a_time.push(continue_ray(s.position, s.geometric, direction, s.at_edge));
            }
            let origins = departure_points(
                lanes.position,
                lanes.geometric,
                directions,
                lanes.near_edge,
                lanes.incoming,
            );
            for (i, ray) in one_at_a_time.iter().enumerate() {
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(bits(origins.lane(i)), bits(ray.origin), "lane {i}");
                assert_eq!(bits(directions.lane(i)), bits(ray.direction));
            }
        }
    }
}
