//! Path tracing with any material and any light: next-event estimation combined with BSDF
//! sampling by multiple importance sampling.
//!
//! This is the general path tracer, one path at a time, written to be read beside pbrt-v4's
//! `PathIntegrator`. At each vertex a path
//!
//! 1. adds the light it sees directly: a point of the light is drawn ([`Light::sample_li`]),
//!    the BSDF is evaluated toward it ([`ShadingFrame::eval_world`]) and, if the shadow ray
//!    is not blocked, `β · f · Li · |cos θ| / p_light` is added, weighted by the power
//!    heuristic against the chance that BSDF sampling would have found the same direction;
//! 2. draws its next direction from the BSDF ([`ShadingFrame::sample_world`]) and multiplies β by
//!    `f · |cos θ| / p_bsdf`;
//! 3. if that ray meets the light before any surface, adds the light's radiance
//!    ([`Light::le`]), weighted by the power heuristic the other way round. Camera rays and rays
//!    leaving a mirror or glass (delta BSDFs, which next-event estimation cannot sample) take
//!    the light at full weight; a point light (a delta light) is found only by step 1.
//!
//! So each way a path can reach the light is counted once: the two weights of one direction
//! sum to 1 ([`power_heuristic`]). Glass under an area light shows its caustic: a path through
//! the glass meets the light by step 3.
//!
//! Units are the lab's (π × radiance, see [`crate::transport::integrator`]): lights give their radiance
//! in those units and BSDFs are the physical ones (ρ/π for a diffuse surface), so under the
//! lab's point light step 1 at a diffuse hit is exactly ρ·D (equation 28), and the sixteen-lane
//! path tracer ([`super::path`]), which computes just that, is this integrator specialised to
//! diffuse, mirror and glass surfaces under a point light (the tests compare the two).
//!
//! **Caustics from photons.** With a caustic photon map ([`Tracer::photon_map`]) every
//! non-delta vertex of a path where it may scatter adds the map's density estimate
//! ([`PhotonMap::gather`]) times β: the light that reached that point from the light through
//! one or more mirror or glass surfaces (L S+ D). The path tracer must then not count that
//! light a second time: a path leaving a non-delta vertex and reaching an area light through
//! one or more delta BSDFs (… → diffuse → specular+ → emitter) adds no emission. Everything
//! else is still the path tracer's: the light sample at each vertex (direct light, which
//! photons are not stored for), a BSDF sample from it straight to the light, and caustics seen
//! directly (camera → specular+ → light: no diffuse vertex yet). Gathering at every vertex,
//! not only the first, matters under the lab's point light: the caustic's light bounced once
//! more (the walls lit by the floor under the glass block) is otherwise lost, as no path finds
//! a point light through glass.
//!
//! Bounces, Russian roulette and the depth guard follow [`super::path`]: a scattering from a
//! non-delta BSDF counts as a bounce, and a path stops after [`Shading::max_bounces`] of them;
//! after [`ROULETTE_DEPTH`] vertices it survives with probability min(max β, 0.95).
//!
//! [`Shading::max_bounces`]: crate::transport::settings::Shading::max_bounces

use glam::{Vec2, Vec3};
use serde::Serialize;

use super::{Recorder, Scattering, Tracer, continue_ray};
use crate::base::geometry::Ray;
use crate::base::lanes::{MaskOf, Real, Vector};
use crate::base::sampling::{Rng, cosine_hemisphere_by_rejection, hemisphere_around};
use crate::shading::bsdf::{Bsdf, BsdfSample, ShadingFrame};
use crate::shading::light::{Light, shadow_ray_to};
use crate::shading::material::{Scatter, facing};
use crate::transport::photon_map::{Gathered, PhotonMap};

/// The vertex from which Russian roulette may end a path: the fifth, as in Mitsuba 3's path
/// tracer (`rr_depth` = 5), so that at equal samples the two are equally noisy. Starting
/// earlier makes a sample cheaper and the image noisier by about as much: the same variance ×
/// time, but a noisier image a sample (PERFORMANCE.md, "Design choices and what each buys").
pub const ROULETTE_DEPTH: u32 = 5;

/// The largest survival probability of Russian roulette: even a path that keeps all its
/// throughput (clear glass) ends after about 20 more vertices on average.
pub const ROULETTE_MAX_SURVIVAL: f32 = 0.95;

/// Vertices after which a path is ended whatever its throughput.
pub const MAX_DEPTH: u32 = 256;

/// The power heuristic with exponent 2 (Veach's thesis, §9.2.4): the weight of a sample drawn
/// with density `pdf_f` when the other strategy would have drawn it with density `pdf_g`.
/// `power_heuristic(a, b) + power_heuristic(b, a) == 1` for any densities not both 0.
#[inline]
pub fn power_heuristic(pdf_f: f32, pdf_g: f32) -> f32 {
    let (f2, g2) = (pdf_f * pdf_f, pdf_g * pdf_g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 == 0.0 {
        return 0.0;
    }
    f2 / (f2 + g2)
}

/// What one vertex of a path computed, for the pixel inspector ([`Recorder::path_vertex`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathVertex {
    /// The hit.
    pub position: Vec3,
    /// The BSDF there.
    pub bsdf: Bsdf,
    /// Next-event estimation, if it was done (not at a delta BSDF): the direction to the
    /// light's point, f toward it, both densities of that direction, its MIS weight, whether
    /// the shadow ray was blocked, and what it added to the pixel (β included).
    pub light: Option<LightTerms>,
    /// The caustic photon map's gather, at a non-delta vertex where the path scatters, when
    /// there is a map: how many photons it found, within which radius, and what it added (β
    /// included).
    pub photons: Option<Gathered>,
}

/// Next-event estimation at a vertex (see [`PathVertex`]); the inspector shows it as it is.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LightTerms {
    /// The direction toward the light's sampled point.
    pub wi: Vec3,
    /// f(wo, wi), the BSDF's value toward it.
    pub f: Vec3,
    /// The light's density of `wi` (solid angle; 1 for a point light).
    pub pdf_light: f32,
    /// The BSDF's density of `wi` (0 for a delta light: BSDF sampling never finds it).
    pub pdf_bsdf: f32,
    /// The power heuristic's weight of the light sample, p_light²/(p_light² + p_bsdf²) (1 for
    /// a point light).
    pub mis_weight: f32,
    /// Whether the shadow ray toward the sampled point is blocked.
    pub blocked: bool,
    /// β · f · Li · |cos θ| / p_light · weight, added to R; 0 when blocked.
    pub added: Vec3,
}

/// How the path reached its current ray: what step 3 needs to weight a light it meets.
#[derive(Clone, Copy, Debug)]
enum Arrival {
    /// A camera ray, or a ray from a delta BSDF: the light counts in full.
    Delta,
    /// A ray drawn from a BSDF with this density, from this point, where the surface's own
    /// relief let this share of the light through ([`super::Surface::relief_visibility`]: the
    /// light samples there were weighed by it, so the light found this way is too).
    Sampled {
        pdf: f32,
        from: Vec3,
        relief_visibility: f32,
    },
}

/// What a path carries from one vertex to the next, in both forms of the path tracer: its
/// throughput and counts here, what only area lights and photons read in [`Carried`].
#[derive(Clone, Copy, Debug)]
pub(super) struct PathState {
    /// β, the throughput: what light found at the next vertex is multiplied by.
    pub beta: Vec3,
    /// Scatterings from non-delta BSDFs made (the bounces [`Shading::max_bounces`] caps).
    pub bounces: u32,
    /// Vertices the path went on from.
    pub depth: u32,
}

impl PathState {
    /// A path at the camera: full throughput, no vertex yet.
    pub const START: Self = Self {
        beta: Vec3::ONE,
        bounces: 0,
        depth: 0,
    };
}

/// What a path carries for the light its rays meet ([`light_met`]) and its photons
/// ([`gather_photons`]): read only under an area light or with a photon map.
#[derive(Clone, Copy, Debug)]
pub(super) struct Carried {
    arrival: Arrival,
    /// Whether the path has met a non-delta vertex: emission reached through delta BSDFs after
    /// one is the photon map's.
    after_diffuse: bool,
    /// The radiance factor (n_t/n_i)² of the refractions the camera path made, in the
    /// direction light flows (pbrt-v4's `etaScale`): 1/ior² for a path entering glass, ior²
    /// leaving it. The path tracer leaves these factors out on both sides of a closed glass
    /// object, where they cancel (see `crate::shading::bsdf`); a photon gather is the radiance at the
    /// diffuse point in its own medium, so it is scaled by them: the floor seen through the
    /// glass block gets 1/ior² of the photons' radiance under the block.
    eta_scale: f32,
}

impl Carried {
    /// A path at the camera.
    pub const START: Self = Self {
        arrival: Arrival::Delta,
        after_diffuse: false,
        eta_scale: 1.0,
    };
}

/// The value of every ray (π × radiance), into `out`, each path drawing from its own
/// generator; each vertex told to `rec`: the batched path tracer's reference, one path at a
/// time (its tests compare the two on the same random numbers).
#[inline(never)]
pub fn trace<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    rec: &mut R,
) {
    for ((ray, rng), out) in rays.iter().zip(rngs.iter_mut()).zip(out.iter_mut()) {
        *out = radiance(tracer, *ray, rng, rec);
    }
}

/// One path from `ray`: its value in π × radiance. Each step is one of the functions below,
/// which the batched path tracer ([`super::path`]) runs for its vertices too.
fn radiance<R: Recorder>(tracer: &Tracer, mut ray: Ray, rng: &mut Rng, rec: &mut R) -> Vec3 {
    let scene = tracer.scene;
    let mut value = Vec3::ZERO;
    let mut path = PathState::START;
    let mut carried = Carried::START;
    loop {
        let hit = scene.closest_intersection(&ray, f32::INFINITY);
        if R::ENABLED {
            rec.closest_hit(&ray, hit.as_ref(), path.beta, path.depth);
        }
        // Step 3: the light, if the ray meets it before any surface.
        let t_surface = hit.as_ref().map_or(f32::INFINITY, |h| h.distance);
        if let Some(added) = light_met(tracer, &ray, t_surface, path.beta, &carried) {
            value += added;
            break;
        }
        let Some(hit) = hit else { break };
        let v = tracer.scattering(&hit, ray.direction);
        // Step 1, then the photons.
        let scatters = path.bounces < tracer.shading.max_bounces();
        let mut light_terms = None;
        if let Some(sample) = sample_light(tracer, &v, path.beta, scatters, rng) {
            let blocked = sample
                .shadow
                .is_some_and(|(shadow, t_max)| scene.occluded(&shadow, t_max));
            let terms = sample.answered(blocked);
            value += terms.added;
            light_terms = Some(terms);
        }
        let gathered = gather_photons(tracer, &v, path.beta, &mut carried, scatters);
        if let Some(g) = gathered {
            value += g.value;
        }
        if R::ENABLED {
            rec.path_vertex(&PathVertex {
                position: hit.position,
                bsdf: v.bsdf,
                light: light_terms,
                photons: gathered,
            });
        }
        // Step 2: the next direction, from the BSDF; then Russian roulette.
        let Some(scatter) = scatter(tracer, &v, &mut path, &mut carried, rng) else {
            break;
        };
        let depth = path.depth + 1;
        let u = rng.next_f32();
        let (beta, survival, lucky) =
            roulette(path.beta, scatter.weight, depth >= ROULETTE_DEPTH, u);
        path.beta = beta;
        path.depth = depth;
        let survives = depth < MAX_DEPTH && lucky;
        if R::ENABLED {
            rec.scattered(&scatter, survival, path.beta, survives);
        }
        if !survives {
            break;
        }
        ray = continue_ray(
            hit.position,
            v.surface.geometric,
            scatter.direction,
            v.surface.at_edge,
        );
    }
    value
}

/// Step 3: what `ray` adds if it meets the light before `t_surface` (β and the MIS weight
/// included), and then the path ends there; `None` if it does not meet it. A ray from a delta
/// BSDF after a non-delta vertex carries light that reached that vertex through mirror or
/// glass: with a photon map, the map counted it there, so it adds nothing.
#[inline]
pub(super) fn light_met(
    tracer: &Tracer,
    ray: &Ray,
    t_surface: f32,
    beta: Vec3,
    carried: &Carried,
) -> Option<Vec3> {
    let light = tracer.emitter();
    light.intersect(ray, t_surface)?;
    let weight = match carried.arrival {
        Arrival::Delta if tracer.photon_map().is_some() && carried.after_diffuse => 0.0,
        Arrival::Delta => 1.0,
        Arrival::Sampled {
            pdf,
            from,
            relief_visibility,
        } => power_heuristic(pdf, light.pdf_li(from, ray.direction)) * relief_visibility,
    };
    Some(beta * light.le(ray.direction) * weight)
}

/// Step 1 drawn, its shadow ray still to answer ([`sample_light`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct LightSample {
    /// The terms, `blocked` and `added` still unset.
    terms: LightTerms,
    /// Whether the light sample can add anything (f and the light's density not 0): only then
    /// is its shadow ray asked.
    lights: bool,
    /// The shadow ray toward the light's point, and its length (`None`: nothing can block it).
    pub shadow: Option<(Ray, f32)>,
    /// What it adds if the shadow ray is not blocked.
    value: Vec3,
}

impl LightSample {
    /// The terms once the shadow ray is answered (`blocked`; ignored where none is cast).
    #[inline]
    pub fn answered(&self, blocked: bool) -> LightTerms {
        let mut terms = self.terms;
        if self.lights {
            terms.blocked = blocked && self.shadow.is_some();
            if !terms.blocked {
                terms.added = self.value;
            }
        }
        terms
    }

    /// Whether its shadow ray is to be cast.
    #[inline]
    pub fn casts(&self) -> bool {
        self.lights && self.shadow.is_some()
    }
}

/// Step 1, next-event estimation, where the BSDF is not a delta: a point of the light drawn
/// (two numbers from `rng`, unless the light is a delta light, whose point is fixed), f and
/// both densities toward it, its MIS weight. Where the path ends here (`scatters` false: its
/// bounces used up), BSDF sampling will not look for the light, so the light sample counts
/// in full.
#[inline]
pub(super) fn sample_light(
    tracer: &Tracer,
    v: &Scattering,
    beta: Vec3,
    scatters: bool,
    rng: &mut Rng,
) -> Option<LightSample> {
    if v.bsdf.is_delta() {
        return None;
    }
    let light = tracer.emitter();
    let position = v.surface.position;
    let u = match light.is_delta() {
        true => Vec2::ZERO,
        false => Vec2::new(rng.next_f32(), rng.next_f32()),
    };
    let sample = light.sample_li(position, u)?;
    let (f, pdf_bsdf) = v.frame.eval_world(&v.bsdf, v.wo, sample.wi);
    let cos = sample.wi.dot(v.frame.shading_normal()).abs();
    let terms = LightTerms {
        wi: sample.wi,
        f,
        pdf_light: sample.pdf,
        pdf_bsdf: if sample.is_delta { 0.0 } else { pdf_bsdf },
        mis_weight: if sample.is_delta || !scatters {
            1.0
        } else {
            power_heuristic(sample.pdf, pdf_bsdf)
        },
        blocked: false,
        added: Vec3::ZERO,
    };
    let lights = f != Vec3::ZERO && sample.pdf > 0.0;
    let surface = &v.surface;
    Some(LightSample {
        terms,
        lights,
        shadow: match lights {
            true => shadow_ray_to(sample.point, position, surface.geometric, surface.at_edge),
            false => None,
        },
        value: beta
            * f
            * sample.li
            * (cos * terms.mis_weight * surface.relief_visibility / sample.pdf),
    })
}

/// The caustic photons at a non-delta vertex where the path may scatter (a caustic reaches
/// the eye by a scattering here, a bounce as the cap counts them), β included; `None` without
/// a photon map. Marks the path as past a non-delta vertex.
#[inline]
pub(super) fn gather_photons(
    tracer: &Tracer,
    v: &Scattering,
    beta: Vec3,
    carried: &mut Carried,
    scatters: bool,
) -> Option<Gathered> {
    if v.bsdf.is_delta() {
        return None;
    }
    carried.after_diffuse = true;
    let map = tracer.photon_map().filter(|_| scatters)?;
    let mut g = gather(map, &v.frame, &v.bsdf, v.surface.position, v.wo);
    g.value *= beta * carried.eta_scale;
    Some(g)
}

/// Step 2: the next direction, from the BSDF, and the weight β is multiplied by; `None` ends
/// the path (a non-delta BSDF with the bounces used up, nothing to sample, no weight). Counts
/// the bounce and keeps what the next vertex needs (how the ray was drawn, the refractions).
///
/// A diffuse surface scatters as the sixteen-lane vertices do ([`crate::shading::material::Material::sample`]):
/// a cosine-weighted direction drawn by rejection about its own normal turned to the arriving
/// ray, weight ρ, its density for MIS the shading frame's. Every other BSDF draws through its
/// shading frame ([`ShadingFrame::sample_world`]): one number for the lobe, two more where it
/// has a density.
#[inline]
pub(super) fn scatter(
    tracer: &Tracer,
    v: &Scattering,
    path: &mut PathState,
    carried: &mut Carried,
    rng: &mut Rng,
) -> Option<Scatter> {
    if !v.bsdf.is_delta() {
        if path.bounces >= tracer.shading.max_bounces() {
            return None;
        }
        path.bounces += 1;
    }
    let sample = match v.bsdf {
        Bsdf::Lambertian { rho } => {
            let local = cosine_hemisphere_by_rejection::<Vec3>(rng, true);
            let wi = hemisphere_around(facing(v.surface.geometric, -v.wo), local);
            // The density only MIS asks for, where BSDF samples may meet the light.
            let pdf = match tracer.emitter().is_delta() {
                true => 0.0,
                false => v.frame.eval_world(&v.bsdf, v.wo, wi).1,
            };
            BsdfSample {
                wi,
                weight: rho,
                pdf,
                is_delta: false,
            }
        }
        Bsdf::Mirror { .. }
        | Bsdf::Glass { .. }
        | Bsdf::RoughConductor { .. }
        | Bsdf::Plastic(_) => {
            let uc = rng.next_f32();
            let u = match v.bsdf.is_delta() {
                true => Vec2::ZERO,
                false => Vec2::new(rng.next_f32(), rng.next_f32()),
            };
            let sample = v.frame.sample_world(&v.bsdf, v.wo, uc, u)?;
            if sample.weight == Vec3::ZERO {
                return None;
            }
            sample
        }
    };
    let wi = sample.wi;
    if let Bsdf::Glass { ior, .. } = v.bsdf
        && !v.frame.reflects(v.wo, wi)
    {
        carried.eta_scale *= if v.frame.front_face() {
            1.0 / (ior * ior)
        } else {
            ior * ior
        };
    }
    carried.arrival = if sample.is_delta {
        Arrival::Delta
    } else {
        Arrival::Sampled {
            pdf: sample.pdf,
            from: v.surface.position,
            relief_visibility: v.surface.relief_visibility,
        }
    };
    Some(Scatter {
        direction: wi,
        weight: sample.weight,
    })
}

/// Russian roulette after a scattering of `weight`, for one path or sixteen: β times the
/// weight, the chance to go on (min(max β, [`ROULETTE_MAX_SURVIVAL`]) where `at_depth`, the
/// path's vertex being at least [`ROULETTE_DEPTH`], else 1), β divided by it, and whether the
/// uniform number `u` lets the path go on.
#[inline(always)]
pub(super) fn roulette<V: Vector>(
    beta: V,
    weight: V,
    at_depth: MaskOf<V>,
    u: V::Real,
) -> (V, V::Real, MaskOf<V>) {
    let beta = beta * weight;
    let survival = V::Real::select(
        at_depth,
        beta.max_element()
            .simd_min(V::Real::splat(ROULETTE_MAX_SURVIVAL)),
        V::Real::splat(1.0),
    );
    let beta = V::scale(V::Real::splat(1.0) / survival, beta);
    (beta, survival, u.simd_lt(survival))
}

/// The photon map's density estimate at a hit ([`PhotonMap::gather`]): f(wo, wi) for each
/// photon's `wi` from the BSDF in its shading frame, as the light samples evaluate it.
fn gather(
    map: &PhotonMap,
    frame: &ShadingFrame,
    bsdf: &Bsdf,
    position: Vec3,
    wo: Vec3,
) -> Gathered {
    map.gather(position, frame.geometric_normal(), |wi| {
        frame.eval_world(bsdf, wo, wi).0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::camera::primary_rays;
    use crate::base::geometry::Triangle;
    use crate::shading::light::{LightKind, LightSpec};
    use crate::shading::material::Material;
    use crate::shapes::scene::{Scene, cornell_box};
    use crate::transport::settings::{RenderSettings, Shading, Stage};

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        // By hand: equal densities share equally; 2 against 1 gives 4/(4 + 1).
        assert_eq!(power_heuristic(1.0, 1.0), 0.5);
        assert_eq!(power_heuristic(2.0, 1.0), 0.8);
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        let mut rng = Rng::new(7);
        for _ in 0..10_000 {
            let a = rng.next_f32() * 100.0;
            let b = rng.next_f32() * 0.01;
            let sum = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((sum - 1.0).abs() < 1e-6, "{a} {b} {sum}");
        }
    }

    fn path_settings(side: u32, bounces: Option<u32>) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(side, side);
        s.shading = Shading {
            bounces,
            ..Shading::for_stage(Stage::Path)
        };
        s
    }

    fn generators(n: usize, seed: u64) -> Vec<Rng> {
        (0..n as u64)
            .map(|i| Rng::new(seed * 1_000_003 + i))
            .collect()
    }

    /// Under the lab's point light, with no bounces, both path tracers compute ρ·D with the
    /// shadow ray at the first hit: the sixteen-lane one as equation 28, this one as
    /// f·Li·cos θ / pdf with f = ρ/π and Li = π·P/(4π r²). The same hits give the same values
    /// up to rounding.
    #[test]
    fn under_the_point_light_it_equals_the_lane_path_tracer_on_the_same_hits() {
        let scene = cornell_box();
        let settings = path_settings(40, Some(0));
        let tracer = Tracer::new(&scene, &settings);
        let rays = primary_rays(&settings.camera);
        let (mut lanes, mut general) = (vec![Vec3::ZERO; rays.len()], vec![Vec3::ZERO; rays.len()]);
        super::super::path::trace(
            &tracer,
            &rays,
            &mut generators(rays.len(), 1),
            &mut lanes,
            &mut [],
            &mut super::super::path::PathScratch::new(),
            &mut (),
        );
        trace(
            &tracer,
            &rays,
            &mut generators(rays.len(), 1),
            &mut general,
            &mut (),
        );
        let mut lit = 0;
        for (a, b) in lanes.iter().zip(&general) {
            assert!(
                (*a - *b).abs().max_element() <= 2e-6 * a.max_element().max(1.0),
                "{a} {b}"
            );
            lit += usize::from(a.max_element() > 0.0);
        }
        assert!(lit > rays.len() / 2, "most pixels are lit: {lit}");
    }

    /// With bounces the two draw different random numbers, but estimate the same light: the
    /// images' means agree within their noise. Each tracer renders 256 passes of 16² pixels,
    /// each pass from its own seeds, so its 256 pass means are independent draws; the
    /// standard error of a tracer's mean is their standard deviation over √256, and the two
    /// means may differ by at most 4 standard errors of their difference in each channel. A
    /// correct pair fails with probability at most 3 · 7·10⁻⁵ (Student's t with 255 degrees
    /// of freedom beyond 4, each channel), and a tracer off by a few times the difference's
    /// standard error in any channel fails.
    #[test]
    fn with_bounces_both_estimate_the_same_image() {
        let scene = cornell_box();
        let settings = path_settings(16, None);
        let tracer = Tracer::new(&scene, &settings);
        let camera_rays = primary_rays(&settings.camera);
        let passes = 256;
        // Each tracer's mean and the variance of that mean, per channel.
        let mut estimates = [(Vec3::ZERO, Vec3::ZERO); 2];
        for (which, estimate) in estimates.iter_mut().enumerate() {
            let mut pass_means = Vec::new();
            for pass in 0..passes {
                let mut rngs = generators(camera_rays.len(), 1 + pass * 2 + which as u64);
                let mut out = vec![Vec3::ZERO; camera_rays.len()];
                if which == 0 {
                    super::super::path::trace(
                        &tracer,
                        &camera_rays,
                        &mut rngs,
                        &mut out,
                        &mut [],
                        &mut super::super::path::PathScratch::new(),
                        &mut (),
                    );
                } else {
                    trace(&tracer, &camera_rays, &mut rngs, &mut out, &mut ());
                }
                let sum = out.iter().map(|v| v.as_dvec3()).sum::<glam::DVec3>();
                pass_means.push(sum / camera_rays.len() as f64);
            }
            let n = passes as f64;
            let mean = pass_means.iter().sum::<glam::DVec3>() / n;
            let variance = pass_means
                .iter()
                .map(|m| (*m - mean) * (*m - mean))
                .sum::<glam::DVec3>()
                / (n - 1.0);
            *estimate = (mean.as_vec3(), (variance / n).as_vec3());
        }
        let [(m0, v0), (m1, v1)] = estimates;
        let standard_error = (v0 + v1).map(f32::sqrt);
        let z = (m0 - m1) / standard_error;
        eprintln!(
            "means {m0} and {m1}, the difference's standard error {standard_error} \
             ({} of the mean), {z} standard errors apart",
            standard_error / m0
        );
        assert!(
            z.abs().max_element() < 4.0,
            "{m0} {m1}: {z} standard errors"
        );
    }

    fn quad_settings(position: Vec3, side: f32) -> RenderSettings {
        let mut s = path_settings(1, None);
        s.light = LightSpec {
            position,
            kind: LightKind::Quad { side },
            ..LightSpec::default()
        };
        s
    }

    /// The camera sees the quad light's own pixels at P/S² in the lab's units (π × radiance):
    /// 14 W over a side of 0.5 is 56, from below; from above, its back, nothing.
    #[test]
    fn the_camera_sees_a_quad_light_at_p_over_s_squared() {
        let scene = Scene::new(Vec::new(), Vec::new());
        let settings = quad_settings(Vec3::ZERO, 0.5);
        let tracer = Tracer::new(&scene, &settings);
        let rays = [
            Ray::new(Vec3::new(0.1, 1.0, -0.2), Vec3::new(0.0, -1.0, 0.0)),
            Ray::new(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)),
            Ray::new(Vec3::new(0.3, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0)),
        ];
        let mut out = [Vec3::ZERO; 3];
        trace(&tracer, &rays, &mut generators(3, 2), &mut out, &mut ());
        assert_eq!(out, [Vec3::splat(56.0), Vec3::ZERO, Vec3::ZERO]);
    }

    /// A white floor 1 below a square light of side 1.5 (14 W), seen straight below the
    /// light's centre: its value is ρ·E, the irradiance E = (P/S²)·F with F the square's form
    /// factor from a point on its axis, F = (4/π)·q·atan q with q = X/√(1 + X²), X = S/(2h)
    /// (`light::quad`'s tests check the formula): F = 0.4128501, so 2.568845.
    ///
    /// The light is large and near, so BSDF samples find it often and the two strategies share
    /// the work: where the light's solid-angle density p_L = r²/(A cos θ_L) meets the BSDF's
    /// cos θ/π. The expected value of each slip, relative to the closed form (by quadrature
    /// over the square): the light sample at full weight beside MIS-weighted BSDF hits 1.178;
    /// BSDF hits dropped 0.822; the balance heuristic on the light's side only 0.870, on the
    /// BSDF's side only 1.130; the area density 1/A in place of the solid-angle one in the
    /// BSDF hits' weight 1.109, in the light sample's weight 0.891, in the light sample's
    /// estimate 1.438 (1.496 with no bounces). So the estimate must be the closed form within 4 of its standard errors
    /// (computed from the samples), and those must be under 2 % of it, below every slip's
    /// 10.9 %: a correct tracer fails with probability 3 · 6.3·10⁻⁵ over its three
    /// configurations. The heuristic applied consistently (balance on both sides) is unbiased
    /// like the power heuristic, so no mean tells them apart: the inspector's test checks the
    /// weight itself (`inspect`'s `a_path_vertex_under_an_area_light_shows_its_mis_weight`).
    ///
    /// With no bounces the light samples alone find it; with one bounce BSDF samples that meet
    /// the light share the work by MIS; with unlimited bounces nothing changes either (the
    /// floor sees nothing but the light).
    #[test]
    fn a_floor_under_a_quad_light_gets_the_form_factor() {
        let (side, h) = (1.5f32, 1.0f32);
        let (a, b, c, d) = (
            Vec3::new(-20.0, h, -20.0),
            Vec3::new(20.0, h, -20.0),
            Vec3::new(20.0, h, 20.0),
            Vec3::new(-20.0, h, 20.0),
        );
        let floor = vec![Triangle::new(a, b, c, 0), Triangle::new(a, c, d, 0)];
        let scene = Scene::new(floor, vec![Material::diffuse("white", Vec3::ONE)]);
        let x = f64::from(side) / (2.0 * f64::from(h));
        let q = x / (1.0 + x * x).sqrt();
        let form_factor = 4.0 / std::f64::consts::PI * q * q.atan();
        assert!((form_factor - 0.412_850_1).abs() < 1e-7, "{form_factor}");
        let expected = 14.0 / f64::from(side * side) * form_factor;
        for bounces in [Some(0), Some(1), None] {
            let mut settings = quad_settings(Vec3::ZERO, side);
            settings.shading.bounces = bounces;
            let tracer = Tracer::new(&scene, &settings);
            let n = 40_000;
            let rays = vec![Ray::new(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.0, 1.0, 0.0)); n];
            let mut out = vec![Vec3::ZERO; n];
            trace(&tracer, &rays, &mut generators(n, 3), &mut out, &mut ());
            let values = out.iter().map(|v| f64::from(v.x));
            let mean = values.clone().sum::<f64>() / n as f64;
            let variance = values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n as f64 - 1.0);
            let standard_error = (variance / n as f64).sqrt();
            eprintln!(
                "bounces {bounces:?}: {mean} against {expected}, standard error {standard_error} \
                 ({:.2} of them apart)",
                (mean - expected) / standard_error
            );
            assert!(
                4.0 * standard_error < 0.02 * expected,
                "bounces {bounces:?}: too noisy to tell a slip ({standard_error})"
            );
            assert!(
                (mean - expected).abs() <= 4.0 * standard_error,
                "bounces {bounces:?}: {mean} against {expected}, standard error {standard_error}"
            );
        }
    }
}
