//! Path tracing: real light where the lab adds the constant N. The one path tracer: any
//! material, any light, multiple importance sampling and caustic photons, a batch of paths at
//! a time, each vertex computed by [`super::path_mis`]'s steps, the same path one at a time
//! (its reference, which the tests compare with this one on the same random numbers).
//!
//! A path starts with the camera ray. At every vertex ([`super::path_mis`] says each step) it
//! adds the light it sees directly (a light sample, weighted by MIS against BSDF sampling),
//! the caustic photons there if the pass has a photon map, and the light its ray meets; then
//! it continues along a direction drawn from the BSDF, and β, its throughput, is multiplied
//! by the sample's weight (π × radiance units, see [`crate::shading::material`]).
//!
//! Under the lab's point light a diffuse vertex's light sample is the lab's direct term, ρ·D
//! with the shadow ray ([`super::HitTerms`]), and its bounce a cosine-weighted direction of
//! weight ρ. So with no bounces the value is ρ·D with shadows, the `shadows` stage exactly;
//! each bounce adds ρ₁·ρ₂·D₂, then ρ₁·ρ₂·ρ₃·D₃, …, the series that the lab's constant N
//! approximates. A point light is never seen in a perfect mirror: without photons, caustics
//! are missing.
//!
//! Surfaces are two-sided: at every vertex the normal is turned to face the arriving ray.
//! After [`ROULETTE_DEPTH`] vertices a path continues with probability q = min(max β, 0.95)
//! and β is divided by q (Russian roulette), which ends paths without bias. A path of
//! [`MAX_DEPTH`] vertices is ended anyway, a guard against rays trapped between facing mirrors.
//!
//! Paths run in batches of [`PATH_BATCH`], phase by phase, as the lab stages do: every path's
//! closest hit in one batch query, every vertex's shadow ray in batch queries, and what is the
//! same arithmetic for every path sixteen paths at a time, a path a lane ([`crate::base::lanes`]):
//! Russian roulette and the next rays ([`departure_points`]) at every vertex, and at the
//! diffuse vertices under the point light their whole light sample and bounce (the lab's own
//! code, [`DiffuseHits::light`], and [`hemisphere_around`]: the same values as
//! [`super::path_mis::sample_light`] and [`super::path_mis::scatter`] up to rounding, and the
//! same random numbers). Every other vertex (any other BSDF or light, or with photons) runs
//! [`super::path_mis`]'s steps one path at a time, its shadow ray asked with the others'.
//!
//! Each path draws only from its own generator, in the same order whatever the batch: a pixel
//! computed alone is the same as in an image, and with the bounces capped at B the first B
//! bounces draw the same numbers as with more, so adding bounces only ever adds light.
//!
//! [`DiffuseHits::light`]: super::hits::DiffuseHits::light

use glam::Vec3;

use super::path_mis::{
    Carried, LightSample, PathState, PathVertex, gather_photons, light_met, roulette, sample_light,
    scatter,
};
use super::{
    BATCH, HitScratch, PATH_BATCH, PATH_GROUPS, Recorder, Seen, Stage, Tracer, departure_points,
    shaded_value,
};
use crate::base::geometry::Ray;
use crate::base::lanes::{LANES, M16, Mask, Vec3x16, Vector};
use crate::base::sampling::{
    Rng, Rng16, Uniform, cosine_hemisphere_by_rejection, hemisphere_around,
};
use crate::shading::bsdf::{Bsdf, ShadingFrame};
use crate::shading::material::{Material, Scatter, facing};
use crate::shapes::intersect::Intersection;
use crate::transport::photon_map::Gathered;

pub use super::path_mis::{MAX_DEPTH, ROULETTE_DEPTH, ROULETTE_MAX_SURVIVAL};

/// The path tracer's working memory ([`super::Scratch`]'s part for it): its hits in lanes
/// and the light at them, and its paths.
pub(crate) struct PathScratch {
    pub(super) hits: HitScratch<PATH_GROUPS>,
    memory: Box<PathMemory>,
}

impl PathScratch {
    pub fn new() -> Self {
        Self {
            hits: HitScratch::new(),
            memory: Box::new(PathMemory {
                paths: [PathState::START; PATH_BATCH],
                carried: [Carried::START; PATH_BATCH],
                alive: [0; PATH_BATCH],
                rays_alive: [Ray {
                    origin: Vec3::ZERO,
                    direction: Vec3::ZERO,
                }; PATH_BATCH],
                hits: [None; PATH_BATCH],
                others: [Departures::NONE; PATH_GROUPS],
                arriving: [Vec3x16::ZERO; PATH_GROUPS],
                lit: [Lit::NONE; PATH_BATCH],
                shadows: [(
                    Ray {
                        origin: Vec3::ZERO,
                        direction: Vec3::ZERO,
                    },
                    0.0,
                ); PATH_BATCH],
                blocked: [false; PATH_BATCH],
            }),
        }
    }
}

/// A batch's paths: each path's state, the paths still going and their next rays and hits,
/// the vertices taken one at a time and the light they found, and β of each diffuse hit's
/// path as it arrives. Kept off the stack: as the batch's own arrays they would swell the
/// stack frame of the code compiled for the CPU, which the lab's batches share, and slow the
/// lab pass. A batch takes only what it wrote: the entries of its paths are set when they
/// start, and lanes left from earlier vertices or batches are computed with, never taken (as
/// [`super::Scratch`]'s).
struct PathMemory {
    paths: [PathState; PATH_BATCH],
    /// What the paths carry for an area light and photons, read only without the point
    /// light's lanes (`Tracer::lane_light`), and set at a batch's start only then.
    carried: [Carried; PATH_BATCH],
    alive: [u16; PATH_BATCH],
    rays_alive: [Ray; PATH_BATCH],
    hits: [Option<Intersection>; PATH_BATCH],
    /// The vertices sampled one at a time ([`super::path_mis`]'s steps), going on.
    others: [Departures; PATH_GROUPS],
    arriving: [Vec3x16; PATH_GROUPS],
    /// The light samples and photons of the vertices taken one at a time.
    lit: [Lit; PATH_BATCH],
    /// Their shadow rays, and the answers.
    shadows: [(Ray, f32); PATH_BATCH],
    blocked: [bool; PATH_BATCH],
}

/// What a vertex taken one at a time found before its shadow ray is answered: its light
/// sample, its photons, and what the pixel inspector is told of it.
#[derive(Clone, Copy)]
struct Lit {
    /// The path.
    owner: u16,
    light: Option<LightSample>,
    /// Where its shadow ray is in the batch's (if it casts one).
    shadow: u16,
    photons: Option<Gathered>,
    position: Vec3,
    bsdf: Bsdf,
}

impl Lit {
    const NONE: Self = Self {
        owner: 0,
        light: None,
        shadow: 0,
        photons: None,
        position: Vec3::ZERO,
        bsdf: Bsdf::Lambertian { rho: Vec3::ZERO },
    };
}

/// The value of every ray (π × radiance), into `out`; what each ray sees into `seen` if it is
/// not empty ([`Seen`], one per ray); each step told to `rec` ([`Recorder`]). The batches
/// work in `scratch`.
#[inline(always)]
pub(super) fn trace<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    seen: &mut [Option<Seen>],
    scratch: &mut PathScratch,
    rec: &mut R,
) {
    for (c, ((rays, rngs), out)) in rays
        .chunks(PATH_BATCH)
        .zip(rngs.chunks_mut(PATH_BATCH))
        .zip(out.chunks_mut(PATH_BATCH))
        .enumerate()
    {
        let seen = match seen.is_empty() {
            true => &mut [],
            false => &mut seen[c * PATH_BATCH..c * PATH_BATCH + out.len()],
        };
        batch(tracer, rays, rngs, out, seen, scratch, rec);
    }
}

/// What the camera samples see ([`Seen`]), from their rays and first hits: nothing where the
/// ray leaves the scene; a surface that is not a mirror or glass as it is; through a mirror or
/// glass, what every specular branch reaches ([`Tracer::seen_through_specular`]), the same at
/// every sample of the ray, where the lobe the path takes would make the features as noisy as
/// its colour.
///
/// Out of the path vertex's own loop, and called only at the first hits: recorded inside it,
/// the features would weigh on every vertex of every path. A diffuse hit's surface is found
/// here a second time.
#[inline(never)]
fn look(tracer: &Tracer, rays: &[Ray], hits: &[Option<Intersection>], seen: &mut [Option<Seen>]) {
    for ((ray, hit), seen) in rays.iter().zip(hits).zip(seen) {
        let Some(hit) = hit else {
            continue;
        };
        let material = tracer.material_of(hit.triangle_index);
        *seen = if material.is_specular() {
            tracer.seen_through_specular(*ray, *hit)
        } else {
            let incoming = ray.direction;
            let at_edge = tracer
                .scene
                .approach_at_edge(hit.triangle_index, hit.u, hit.v, incoming);
            let surface = tracer.surface_with(hit, material, incoming, at_edge);
            let wo = -incoming;
            let normal = ShadingFrame::seen_normal(surface.normal, surface.geometric, wo);
            Some(Seen::at(Vec3::ONE, surface.rho, normal, wo, hit.distance))
        };
    }
}

/// Up to sixteen path vertices that go on, a path a lane: where each leaves from, along which
/// direction, and what its throughput becomes.
#[derive(Clone, Copy)]
struct Departures {
    position: Vec3x16,
    /// The triangle's normal (either side): the ray leaves on the side it goes to.
    normal: Vec3x16,
    /// Where the vertex lies at an edge of its triangle, and the arriving ray's direction
    /// there ([`crate::shapes::scene::Scene::approach_at_edge`], as in [`super::Surfaces`]).
    near_edge: M16,
    incoming: Vec3x16,
    direction: Vec3x16,
    /// β before the vertex, and the scattering's weight it is multiplied by.
    beta: Vec3x16,
    weight: Vec3x16,
    /// The path in each lane (an index into the batch's paths).
    owner: [u16; LANES],
    /// The lanes that hold a vertex.
    active: M16,
}

impl Departures {
    const NONE: Self = Self {
        position: Vec3x16::ZERO,
        normal: Vec3x16::ZERO,
        near_edge: M16::NONE,
        incoming: Vec3x16::ZERO,
        direction: Vec3x16::ZERO,
        beta: Vec3x16::ZERO,
        weight: Vec3x16::ZERO,
        owner: [0; LANES],
        active: M16::NONE,
    };

    /// Puts a vertex already sampled one at a time in lane `i`: the path `owner` leaving
    /// `from` (its hit's position, the triangle's normal and `at_edge`,
    /// [`crate::shapes::scene::Scene::approach_at_edge`]), with β before the vertex and the
    /// scattering drawn.
    #[inline(always)]
    fn set(
        &mut self,
        i: usize,
        owner: usize,
        from: (Vec3, Vec3, Option<Vec3>),
        beta: Vec3,
        scatter: Scatter,
    ) {
        let (position, normal, at_edge) = from;
        self.position.set_lane(i, position);
        self.normal.set_lane(i, normal);
        self.beta.set_lane(i, beta);
        self.owner[i] = owner as u16;
        self.active.0[i] = true;
        self.near_edge.0[i] = at_edge.is_some();
        self.incoming.set_lane(i, at_edge.unwrap_or(Vec3::ZERO));
        self.direction.set_lane(i, scatter.direction);
        self.weight.set_lane(i, scatter.weight);
    }
}

/// The vertices of `d` go on: Russian roulette ([`roulette`], sixteen at a time), the next
/// ray; the paths that survive are appended to `alive[..*still]`, their next rays to
/// `rays[..*still]`.
///
/// Roulette's number is drawn at every vertex, used or not, and the outcome is computed
/// without branches: whether a path survives is a coin toss the processor cannot predict. A
/// path that lost all its throughput (a black surface) ends at the roulette, where its
/// survival is 0; before it, it may go on a vertex or two adding nothing.
#[inline(always)]
fn go_on<R: Recorder>(
    d: &Departures,
    paths: &mut [PathState; PATH_BATCH],
    rng: &mut Rng16,
    next: (&mut [u16; PATH_BATCH], &mut [Ray; PATH_BATCH]),
    still: &mut usize,
    rec: &mut R,
) {
    let (alive, rays) = next;
    let mut depth = [0u32; LANES];
    let mut at_depth = M16::NONE;
    for lane in 0..LANES {
        if d.active.0[lane] {
            depth[lane] = paths[d.owner[lane] as usize].depth + 1;
            at_depth.0[lane] = depth[lane] >= ROULETTE_DEPTH;
        }
    }
    let u = rng.draw(d.active);
    let (beta, survival, lucky) = roulette(d.beta, d.weight, at_depth, u);
    let origin = departure_points(d.position, d.normal, d.direction, d.near_edge, d.incoming);
    for lane in (0..LANES).filter(|&lane| d.active.0[lane]) {
        let i = d.owner[lane] as usize;
        let path = &mut paths[i];
        rays[*still] = Ray {
            origin: origin.lane(lane),
            direction: d.direction.lane(lane),
        };
        path.beta = beta.lane(lane);
        path.depth = depth[lane];
        let keep = (path.depth < MAX_DEPTH) & lucky.0[lane];
        if R::ENABLED {
            let scatter = Scatter {
                direction: d.direction.lane(lane),
                weight: d.weight.lane(lane),
            };
            rec.scattered(&scatter, survival.0[lane], path.beta, keep);
        }
        alive[*still] = i as u16;
        *still += usize::from(keep);
    }
}

/// The generators of `d`'s paths, side by side.
#[inline(always)]
fn take_rngs(d: &Departures, rngs: &[Rng]) -> Rng16 {
    let mut rng = Rng16::UNUSED;
    for lane in (0..LANES).filter(|&lane| d.active.0[lane]) {
        rng.set(lane, &rngs[d.owner[lane] as usize]);
    }
    rng
}

/// The generators of `d`'s paths, as far as they have drawn, back to `rngs`.
#[inline(always)]
fn give_back(d: &Departures, rng: &Rng16, rngs: &mut [Rng]) {
    for lane in (0..LANES).filter(|&lane| d.active.0[lane]) {
        rngs[d.owner[lane] as usize] = rng.get(lane);
    }
}

/// A vertex that is not a diffuse one under the point light, by the single path's steps
/// ([`super::path_mis`]): its light sample, its photons, its scattering. `hit` is the hit with
/// its material, the arriving ray's direction and `at_edge`; `path` the path's index, state,
/// carried values and generator. What it found goes into `pending`'s [`Lit`], its shadow ray
/// into `pending`'s slot, whose index in the batch's shadow rays is given: whether each was
/// filled (the [`Lit`] also where `record`, for the pixel inspector). Returns those, and β
/// before the vertex with the scattering if the path goes on.
///
/// Out of line: inlined, it would make the loop over a batch's hits, which the lab's box
/// runs at every vertex, a larger function than the diffuse lanes alone need.
#[inline(never)]
#[allow(clippy::type_complexity)]
fn other_vertex(
    tracer: &Tracer,
    hit: (&Intersection, &Material, Vec3, Option<Vec3>),
    path: (usize, &mut PathState, &mut Carried, &mut Rng),
    pending: (&mut Lit, &mut (Ray, f32), usize),
    record: bool,
) -> (bool, bool, Option<(Vec3, Scatter)>) {
    let (hit, material, incoming, at_edge) = hit;
    let (owner, path, carried, rng) = path;
    let (lit, shadow, shadow_index) = pending;
    let v = tracer.scattering_with(hit, material, incoming, at_edge);
    let scatters = path.bounces < tracer.shading.max_bounces();
    let light = sample_light(tracer, &v, path.beta, scatters, rng);
    let photons = gather_photons(tracer, &v, path.beta, carried, scatters);
    let mut cast = false;
    let filled = record || light.is_some() || photons.is_some();
    if filled {
        if let Some(sample) = light.filter(LightSample::casts) {
            *shadow = sample.shadow.expect("a cast shadow ray");
            cast = true;
        }
        *lit = Lit {
            owner: owner as u16,
            light,
            shadow: shadow_index as u16,
            photons,
            position: hit.position,
            bsdf: v.bsdf,
        };
    }
    let beta = path.beta;
    let scattered = scatter(tracer, &v, path, carried, rng).map(|s| (beta, s));
    (filled, cast, scattered)
}

#[inline(always)]
fn batch<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    seen: &mut [Option<Seen>],
    scratch: &mut PathScratch,
    rec: &mut R,
) {
    let scene = tracer.scene;
    let max_bounces = tracer.shading.max_bounces();
    // Whether rays may meet the light (an area light; not a point or a spot).
    let light_seen = !tracer.lane_light;
    let (triangles, materials) = (scene.triangles.as_slice(), &*tracer.materials);
    out.fill(Vec3::ZERO);
    // What each camera sample sees, if asked: found at the camera rays' hits (`look`).
    seen.fill(None);
    let PathScratch {
        hits: lanes,
        memory,
    } = scratch;
    let PathMemory {
        paths,
        carried,
        alive,
        rays_alive,
        hits,
        others,
        arriving,
        lit: lit_one,
        shadows,
        blocked: blocked_one,
    } = &mut **memory;
    let HitScratch { diffuse, lit } = lanes;
    let n = rays.len();
    paths[..n].fill(PathState::START);
    if light_seen {
        carried[..n].fill(Carried::START);
    }
    // The paths still going, by index, and the ray each goes on with.
    for (i, ray) in rays.iter().enumerate() {
        alive[i] = i as u16;
        rays_alive[i] = *ray;
    }
    let mut n_alive = n;

    // Whether the paths' hits are the camera rays' (neighbouring pixels'): the first step.
    let mut first_step = true;
    while n_alive > 0 {
        // The camera rays a batch of BATCH at a time, each a cone's worth of neighbours
        // (`PATH_BATCH` notes why); the bounces, from all over the scene, have none.
        let each = if first_step { BATCH } else { PATH_BATCH };
        let asked = rays_alive[..n_alive].chunks(each);
        for (rays, hits) in asked.zip(hits[..n_alive].chunks_mut(each)) {
            scene.closest_intersections(rays, f32::INFINITY, hits);
        }
        if first_step && !seen.is_empty() {
            // The paths still going are the camera rays, in their order.
            look(tracer, &rays_alive[..n_alive], &hits[..n_alive], seen);
        }
        // Each hit to its phase: the diffuse ones under the point light into lanes for their
        // light and bounce, the others through the single path's steps here.
        diffuse.clear();
        // The diffuse hits in lanes one after another (lanes left empty would cost their
        // groups' light and shadow rays as much as full ones).
        let mut n_diffuse = 0;
        let (mut n_other, mut n_lit, mut n_shadows) = (0, 0, 0);
        for k in 0..n_alive {
            let (i, ray) = (alive[k] as usize, &rays_alive[k]);
            let path = &mut paths[i];
            if R::ENABLED {
                rec.closest_hit(ray, hits[k].as_ref(), path.beta, path.depth);
            }
            // Step 3: the light, if the ray meets it before any surface.
            if light_seen {
                let t_surface = hits[k].as_ref().map_or(f32::INFINITY, |h| h.distance);
                if let Some(added) = light_met(tracer, ray, t_surface, path.beta, &carried[i]) {
                    out[i] += added;
                    continue;
                }
            }
            let Some(hit) = hits[k] else { continue };
            let triangle = &triangles[hit.triangle_index];
            let material = &materials[triangle.material as usize];
            let geometric = triangle.normal;
            let incoming = ray.direction;
            let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, incoming);
            if tracer.lane_light && material.is_diffuse() {
                // Two-sided: both normals turned to face the arriving ray.
                let mut surface = tracer.surface_with(&hit, material, incoming, at_edge);
                let turned = facing(geometric, incoming);
                if turned != geometric {
                    surface.geometric = turned;
                    surface.normal = -surface.normal;
                }
                arriving[n_diffuse / LANES].set_lane(n_diffuse % LANES, path.beta);
                diffuse.push(n_diffuse, surface, i);
                n_diffuse += 1;
                continue;
            }
            // Any other vertex, by the single path's steps.
            let (lit, cast, scattered) = other_vertex(
                tracer,
                (&hit, material, incoming, at_edge),
                (i, path, &mut carried[i], &mut rngs[i]),
                (&mut lit_one[n_lit], &mut shadows[n_shadows], n_shadows),
                R::ENABLED,
            );
            n_lit += usize::from(lit);
            n_shadows += usize::from(cast);
            if let Some((beta, scattered)) = scattered {
                let (g, lane) = (n_other / LANES, n_other % LANES);
                if lane == 0 {
                    others[g].active = M16::NONE;
                }
                let from = (hit.position, geometric, at_edge);
                others[g].set(lane, i, from, beta, scattered);
                n_other += 1;
            }
        }
        let mut still = 0;
        // The direct term at the diffuse hits.
        diffuse.light::<false>(tracer, rngs, |i| i as usize, lit);
        // Their bounces: a cosine-weighted direction about the turned normal, weight ρ.
        for (g, (_, surfaces)) in diffuse.groups().enumerate() {
            let mut d = Departures {
                position: surfaces.position,
                normal: surfaces.geometric,
                near_edge: surfaces.near_edge,
                incoming: surfaces.incoming,
                direction: Vec3x16::ZERO,
                beta: arriving[g],
                weight: surfaces.rho,
                owner: [0; LANES],
                active: M16::NONE,
            };
            for (lane, i) in diffuse.owners(g) {
                let path = &mut paths[i as usize];
                if path.bounces < max_bounces {
                    path.bounces += 1;
                    d.owner[lane] = i;
                    d.active.0[lane] = true;
                }
            }
            if d.active.any() {
                let mut rng = take_rngs(&d, rngs);
                let local = cosine_hemisphere_by_rejection(&mut rng, d.active);
                d.direction = hemisphere_around(surfaces.geometric, local);
                let next = (&mut *alive, &mut *rays_alive);
                go_on(&d, paths, &mut rng, next, &mut still, rec);
                give_back(&d, &rng, rngs);
            }
        }
        for d in &others[..n_other.div_ceil(LANES)] {
            let mut rng = take_rngs(d, rngs);
            let next = (&mut *alive, &mut *rays_alive);
            go_on(d, paths, &mut rng, next, &mut still, rec);
            give_back(d, &rng, rngs);
        }
        n_alive = still;
        // The shadow rays, and the direct term times β into each path's pixel.
        let blocked = diffuse.blocked(scene, lit, first_step);
        first_step = false;
        for (g, (_, surfaces)) in diffuse.groups().enumerate() {
            let value = shaded_value(
                Stage::Path,
                surfaces.rho,
                lit[g].d,
                M16::from_bits(blocked[g]),
                Vec3x16::ZERO,
            );
            let seen = arriving[g] * value;
            for (lane, i) in diffuse.owners(g) {
                if R::ENABLED {
                    let terms = diffuse.terms(g, lane, &lit[g], blocked[g]);
                    rec.shaded(&terms, Vec3::ZERO, value.lane(lane), arriving[g].lane(lane));
                }
                out[i as usize] += seen.lane(lane);
            }
        }
        // The other vertices' shadow rays, and their light and photons into their pixels.
        if n_lit > 0 {
            scene.occluded_many(&shadows[..n_shadows], &mut blocked_one[..n_shadows]);
            for one in &lit_one[..n_lit] {
                let i = one.owner as usize;
                let light = one
                    .light
                    .map(|l| l.answered(l.casts() && blocked_one[one.shadow as usize]));
                if let Some(terms) = light {
                    out[i] += terms.added;
                }
                if let Some(g) = one.photons {
                    out[i] += g.value;
                }
                if R::ENABLED {
                    rec.path_vertex(&PathVertex {
                        position: one.position,
                        bsdf: one.bsdf,
                        light,
                        photons: one.photons,
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::material::{Material, MaterialPreset, TexturePreset};
    use crate::shapes::intersect::Intersection;
    use crate::shapes::scene::cornell_box;
    use crate::transport::integrator::HitTerms;
    use crate::{Camera, RenderSettings, Shading};

    /// Per path vertex: the bounce's weight, and the ρ its direct term was computed with.
    #[derive(Default)]
    struct Weights {
        scattered: Vec<Vec3>,
        shaded: Vec<Vec3>,
    }

    impl Recorder for Weights {
        const ENABLED: bool = true;
        fn closest_hit(&mut self, _: &Ray, _: Option<&Intersection>, _: Vec3, _: u32) {}
        fn specular_hit(&mut self, _: &Intersection, _: Vec3, _: u32, _: &[(Vec3, Vec3)]) {}
        fn shaded(&mut self, terms: &HitTerms, _: Vec3, _: Vec3, _: Vec3) {
            self.shaded.push(terms.rho);
        }
        fn scattered(&mut self, scatter: &Scatter, _: f32, _: Vec3, _: bool) {
            self.scattered.push(scatter.weight);
        }
    }

    /// A diffuse bounce off a textured surface is weighted by the texture's ρ at the hit, the
    /// same ρ as the hit's direct term: on the checker floor, both the floor's green and the
    /// checker's light grey squares pass on their own colour.
    #[test]
    fn a_textured_bounce_is_weighted_by_the_texture() {
        let scene = cornell_box();
        let mut settings = RenderSettings::default();
        settings.shading = Shading::for_stage(Stage::Path);
        settings.texture_preset = TexturePreset::CheckerFloor;
        settings.material_preset = MaterialPreset::None;
        let tracer = Tracer::new(&scene, &settings);
        let camera = Camera::default_for(24, 24);
        let mut colours = Vec::new();
        for y in 0..24 {
            for x in 0..24 {
                let mut rec = Weights::default();
                let mut rng = [Rng::for_pixel_sample(3, x, y, 0)];
                let mut out = [Vec3::ZERO];
                tracer.trace_recorded(&[camera.pixel_ray(x, y)], &mut rng, &mut out, &mut rec);
                // Each vertex's bounce is told before its direct term; a vertex where the
                // path ends by roulette has both, one ended by leaving the scene neither.
                for (weight, rho) in rec.scattered.iter().zip(&rec.shaded) {
                    assert_eq!(weight, rho, "pixel ({x}, {y})");
                    colours.push(*rho);
                }
            }
        }
        colours.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
        colours.dedup();
        let floor = scene.materials.iter().find(|m| m.name == "green").unwrap();
        assert!(colours.contains(&floor.reflectance), "{colours:?}");
        assert!(
            colours
                .iter()
                .any(|c| c.x == c.y && c.y == c.z && c.x > 0.5),
            "a light grey square passed on its own colour: {colours:?}"
        );
    }

    /// The first vertex's hit and the direction the path left it along.
    #[derive(Default)]
    struct FirstVertex {
        hit: Option<Intersection>,
        left_along: Option<Vec3>,
    }

    impl Recorder for FirstVertex {
        const ENABLED: bool = true;
        fn closest_hit(&mut self, _: &Ray, hit: Option<&Intersection>, _: Vec3, _: u32) {
            self.hit = self.hit.or(hit.copied());
        }
        fn specular_hit(&mut self, _: &Intersection, _: Vec3, _: u32, _: &[(Vec3, Vec3)]) {}
        fn shaded(&mut self, _: &HitTerms, _: Vec3, _: Vec3, _: Vec3) {}
        fn scattered(&mut self, scatter: &Scatter, _: f32, _: Vec3, _: bool) {
            self.left_along = self.left_along.or(Some(scatter.direction));
        }
    }

    /// The path stage's tracer of `scene` under the lab's light.
    fn path_tracer_for(scene: &crate::shapes::scene::Scene) -> Tracer<'_> {
        let mut settings = RenderSettings::default();
        settings.shading = Shading::for_stage(Stage::Path);
        Tracer::new(scene, &settings)
    }

    /// Where the path of `ray` went at its first vertex, with `seed`'s numbers: the hit and
    /// the direction it left along.
    fn first_vertex(tracer: &Tracer, ray: Ray, seed: u64) -> (Intersection, Vec3) {
        let mut rec = FirstVertex::default();
        let mut rng = [Rng::new(seed)];
        tracer.trace_recorded(&[ray], &mut rng, &mut [Vec3::ZERO], &mut rec);
        (
            rec.hit.expect("a hit"),
            rec.left_along.expect("a scattering"),
        )
    }

    /// Where `d` goes off a mirror of unit normal `n`: d − 2(d·n)n.
    fn mirrored(d: Vec3, n: Vec3) -> Vec3 {
        d - 2.0 * d.dot(n) * n
    }

    /// Checks that `t` is `d` refracted into a medium of index `ior` through a surface of unit
    /// normal `n` facing `d`'s origin, by Snell's law: sin θ_t = sin θ_i / ior, with t in
    /// the plane of d and n, across the surface and on d's side of n along it.
    #[track_caller]
    fn assert_refracted(d: Vec3, t: Vec3, n: Vec3, ior: f32, sin_t: f32) {
        let sin_i = d.cross(n).length();
        assert!((sin_i / ior - sin_t).abs() < 1e-6, "{sin_i} {sin_t}");
        assert!(
            (t.cross(n).length() - sin_t).abs() < 1e-5,
            "{t}: sin θ_t {sin_t}"
        );
        assert!(t.dot(n) < 0.0 && d.cross(n).dot(t).abs() < 1e-5, "{t}");
        assert!((d - d.dot(n) * n).dot(t - t.dot(n) * n) > 0.0, "{t}");
    }

    /// Into the pool's still water (waves 0: the flat surface) the path stage refracts by
    /// Snell's law about the surface's normal (0, −1, 0): a ray 40° from the vertical goes on
    /// at asin(sin 40° / 1.33) = 28.90°, sin θ_t = 0.483299; the Fresnel choice's other
    /// branch reflects it at 40°. A few seeds give both.
    #[test]
    fn the_path_stage_refracts_into_flat_water_by_snells_law() {
        let mut spec = crate::shapes::scene::SceneChoice::Pool.spec();
        spec.water.as_mut().unwrap().waves = 0.0;
        let scene = crate::shapes::scene::SceneChoice::from_spec(spec)
            .load()
            .unwrap();
        let tracer = path_tracer_for(&scene);
        let theta = 40f32.to_radians();
        let d = Vec3::new(theta.sin(), theta.cos(), 0.0);
        // Over the floor beside both blocks (the short one's x ≤ 0.705 at z ≤ −0.02, the
        // tall one's x ≤ 0.045).
        let target = Vec3::new(0.5, 0.7, 0.5);
        let ray = Ray::new(target - 0.5 * d, d);
        let n = Vec3::new(0.0, -1.0, 0.0);
        let (mut refracted, mut reflected) = (0, 0);
        for seed in 0..40 {
            let (hit, t) = first_vertex(&tracer, ray, seed);
            assert_eq!(tracer.material_of(hit.triangle_index).name, "water");
            assert!((hit.position - target).length() < 1e-5, "{}", hit.position);
            if t.y > 0.0 {
                assert_refracted(d, t, n, 1.33, 0.483_299);
                refracted += 1;
            } else {
                assert!((t - mirrored(d, n)).length() < 1e-5, "{t}");
                reflected += 1;
            }
        }
        assert!(refracted > 0 && reflected > 0, "{refracted} {reflected}");
    }

    /// The batched tracer and its reference, [`super::super::path_mis::trace`] (one path at
    /// a time), on the same random numbers follow the same paths: every configuration whose
    /// vertices all run the single path's steps (area and spot lights, the glossy presets
    /// beside the point light's diffuse lanes, photons) gives the same bits, pixel by pixel;
    /// under the lab's point light, where the diffuse vertices take the lab's direct term in
    /// lanes (ρ·D, where the reference computes f·Li·cos θ/p), the same values up to rounding.
    #[test]
    fn the_batch_equals_the_single_path_on_the_same_numbers() {
        use crate::shading::light::{LightKind, LightSpec, SpotCone};
        use crate::transport::settings::Caustics;
        let scene = cornell_box();
        let lights = [
            LightSpec::default(),
            LightSpec {
                kind: LightKind::Quad { side: 0.4 },
                ..LightSpec::default()
            },
            LightSpec {
                kind: LightKind::Sphere { radius: 0.1 },
                ..LightSpec::default()
            },
            LightSpec {
                kind: LightKind::Spot(SpotCone {
                    aim: Vec3::new(0.0, 1.0, -0.2),
                    cutoff: 25f32.to_radians(),
                    beam: 15f32.to_radians(),
                }),
                ..LightSpec::default()
            },
        ];
        let (mut exact, mut close) = (0, 0);
        for light in lights {
            for preset in MaterialPreset::ALL {
                for caustics in [Caustics::Off, Caustics::Photons] {
                    let mut settings = RenderSettings::default();
                    settings.shading = Shading::for_stage(Stage::Path);
                    settings.shading.caustics = caustics;
                    settings.shading.photons = 2000;
                    settings.material_preset = preset;
                    settings.light = light;
                    settings.camera = settings.camera.with_resolution(24, 24);
                    let tracer = Tracer::for_pass(&scene, &settings, 1);
                    let rays = crate::base::camera::primary_rays(&settings.camera);
                    let rngs = || -> Vec<Rng> {
                        (0..rays.len())
                            .map(|i| Rng::for_pixel_sample(9, i as u32, 2, 1))
                            .collect()
                    };
                    let mut batched = vec![Vec3::NAN; rays.len()];
                    tracer.trace(&rays, &mut rngs(), &mut batched);
                    let mut single = vec![Vec3::NAN; rays.len()];
                    super::super::path_mis::trace(
                        &tracer,
                        &rays,
                        &mut rngs(),
                        &mut single,
                        &mut (),
                    );
                    let what = format!("{light:?} {preset} {caustics}");
                    if tracer.lane_light {
                        for (a, b) in batched.iter().zip(&single) {
                            let scale = a.max_element().max(b.max_element()).max(1e-3);
                            assert!(
                                (*a - *b).abs().max_element() <= 1e-4 * scale,
                                "{what}: {a} {b}"
                            );
                        }
                        close += 1;
                    } else {
                        let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                            v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
                        };
                        assert_eq!(bits(&batched), bits(&single), "{what}");
                        exact += 1;
                    }
                    let lit = batched.iter().filter(|v| v.max_element() > 0.0).count();
                    assert!(lit > 40, "{what}: {lit} pixels lit");
                }
            }
        }
        assert!(exact > 0 && close > 0, "{exact} {close}");
    }

    /// The path-traced pool shows its waves: rendered with the same random numbers, the image
    /// with waves of 0.05 differs from the still water's over much of the picture (the water
    /// covers the floor, seen in most of the lower half), and still water gives the same image
    /// as still water. A path tracer that scattered about the water's flat triangle normal
    /// would give the same image for both.
    #[test]
    fn the_path_traced_pool_shows_its_waves() {
        let render = |waves: f32| {
            let mut spec = crate::shapes::scene::SceneChoice::Pool.spec();
            spec.water.as_mut().unwrap().waves = waves;
            let scene = crate::shapes::scene::SceneChoice::from_spec(spec)
                .load()
                .unwrap();
            let mut settings = RenderSettings::default();
            settings.shading = Shading::for_stage(Stage::Path);
            settings.camera = settings.camera.with_resolution(32, 32);
            settings.samples_per_pixel = 4;
            crate::transport::render::render(&scene, &settings)
        };
        let still = render(0.0);
        assert_eq!(still.pixels, render(0.0).pixels, "deterministic");
        let waves = render(0.05);
        let moved = still
            .pixels
            .iter()
            .zip(&waves.pixels)
            .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * a.max_element().max(0.1))
            .count();
        assert!(
            moved > still.pixels.len() / 5,
            "{moved} of {} pixels changed",
            still.pixels.len()
        );
    }

    /// Waves tilt the normal mirror and glass scatter about (`Tracer::specular_normal`, the
    /// lab stages' too). A square at y = 0 facing up (−y) with a one-texel normal map
    /// (sin 10°, 0, cos 10°) everywhere: with planar coordinates (u, v) = (x, z) its tangent
    /// frame is t = +x, b = n × t = +z, n = (0, −1, 0), so the tilted normal is
    /// (sin 10°, −cos 10°, 0). A ray 40° from the vertical, along +x, meets it at 50°:
    /// as a mirror it leaves along d − 2(d·n)n = (sin 60°, −cos 60°, 0), 20° from the flat
    /// surface's reflection (sin 40°, −cos 40°, 0); as glass of index 1.33 it also refracts by
    /// Snell's law about that normal, sin θ_t = sin 50° / 1.33 = 0.575973.
    #[test]
    fn the_path_stage_scatters_about_a_tilted_normal() {
        use crate::base::geometry::Triangle;
        use crate::shading::material::MaterialKind;
        use crate::shading::relief::{NormalMap, Relief};
        use crate::shading::texture::TextureImage;
        let tilt = 10f32.to_radians();
        let map = TextureImage {
            name: "tilt".into(),
            width: 1,
            height: 1,
            texels: vec![Vec3::new(tilt.sin(), 0.0, tilt.cos())],
        };
        let relief = Relief {
            normal: Some(NormalMap {
                image: std::sync::Arc::new(map),
                strength: 1.0,
            }),
            height: None,
            uv_scale: 1.0,
        };
        let facing_up = |t: Triangle| match t.normal.y < 0.0 {
            true => t,
            false => Triangle::new(t.v0, t.v2, t.v1, t.material),
        };
        let (a, b) = (Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 0.0, -5.0));
        let (c, e) = (Vec3::new(5.0, 0.0, 5.0), Vec3::new(-5.0, 0.0, 5.0));
        let square = vec![
            facing_up(Triangle::new(a, b, c, 0)),
            facing_up(Triangle::new(a, c, e, 0)),
        ];
        let n = Vec3::new(tilt.sin(), -tilt.cos(), 0.0);
        let theta = 40f32.to_radians();
        let d = Vec3::new(theta.sin(), theta.cos(), 0.0);
        let ray = Ray::new(Vec3::new(0.2, 0.0, 0.3) - d, d);
        let want = mirrored(d, n);
        assert!(
            (want - Vec3::new(0.866_025, -0.5, 0.0)).length() < 1e-5,
            "{want}"
        );
        let flat = mirrored(d, Vec3::new(0.0, -1.0, 0.0));
        assert!((want.dot(flat) - 20f32.to_radians().cos()).abs() < 1e-5);
        for kind in [
            MaterialKind::Mirror { tint: Vec3::ONE },
            MaterialKind::Glass {
                ior: 1.33,
                tint: Vec3::ONE,
            },
        ] {
            let material = Material {
                kind,
                relief: Some(std::sync::Arc::new(relief.clone())),
                ..Material::diffuse("tilted", Vec3::ZERO)
            };
            let scene = crate::shapes::scene::Scene::new(square.clone(), vec![material]);
            let tracer = path_tracer_for(&scene);
            let (mut refracted, mut reflected) = (0, 0);
            for seed in 0..40 {
                let (_, t) = first_vertex(&tracer, ray, seed);
                if t.y > 0.0 {
                    assert_refracted(d, t, n, 1.33, 0.575_973);
                    refracted += 1;
                } else {
                    assert!((t - want).length() < 1e-5, "{kind:?}: {t}, not {want}");
                    reflected += 1;
                }
            }
            assert!(reflected > 0, "{kind:?}");
            let glass = matches!(kind, MaterialKind::Glass { .. });
            assert_eq!(refracted > 0, glass, "{kind:?}: {refracted}");
        }
    }
}
