//! Path tracing: real light where the lab adds the constant N.
//!
//! A path starts with the camera ray. At every diffuse vertex it adds the lab's direct term,
//! ρ·D with the shadow ray (next-event estimation to the point light, [`super::HitTerms`]), times the
//! path's throughput β; then it continues in a cosine-weighted direction and β is multiplied by
//! ρ (the sample's weight in π × radiance units, see [`crate::material`]). Mirror and glass
//! vertices pick their reflected or refracted direction and add no direct light: a point light
//! is never seen in a perfect mirror, so, as in any path tracer with a point light, caustics
//! are missing.
//!
//! So with no bounces the value is ρ·D with shadows, the `shadows` stage exactly; each bounce
//! adds ρ₁·ρ₂·D₂, then ρ₁·ρ₂·ρ₃·D₃, …, the series that the lab's constant N approximates.
//!
//! Surfaces are two-sided: at every vertex the normal is turned to face the arriving ray.
//! After [`ROULETTE_DEPTH`] vertices a path continues with probability q = min(max β, 0.95)
//! and β is divided by q (Russian roulette), which ends paths without bias. A path of
//! [`MAX_DEPTH`] vertices is ended anyway, a guard against rays trapped between facing mirrors.
//!
//! Paths run in batches of [`PATH_BATCH`], phase by phase, as the lab stages do, and each phase
//! of a vertex runs sixteen paths at a time, a path a lane ([`crate::lanes`]): the direct term
//! ([`DiffuseHits::light`], the lab's own code), the diffuse bounce's direction
//! ([`hemisphere_around`]), the throughput, Russian roulette and the next ray
//! ([`departure_points`]). Only what differs from path to path in control flow stays one path
//! at a time: the hit's material, the random numbers (drawn by rejection), and mirror and glass
//! sampling ([`crate::material::Material::sample`]).
//!
//! Each path draws only from its own generator, in the same order whatever the batch: a pixel
//! computed alone is the same as in an image, and with the bounces capped at B the first B
//! bounces draw the same numbers as with more, so adding bounces only ever adds light.

use glam::Vec3;

use super::{
    BATCH, HitScratch, PATH_BATCH, PATH_GROUPS, Recorder, Seen, Stage, Tracer, departure_points,
    shaded_value,
};
use crate::bsdf::ShadingFrame;
use crate::geometry::Ray;
use crate::intersect::Intersection;
use crate::lanes::{F32x16, LANES, M16, Mask, Real, Vec3x16, Vector};
use crate::material::{Scatter, facing};
use crate::sampling::{Rng, Rng16, Uniform, cosine_hemisphere_by_rejection, hemisphere_around};

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
                alive: [0; PATH_BATCH],
                rays_alive: [Ray {
                    origin: Vec3::ZERO,
                    direction: Vec3::ZERO,
                }; PATH_BATCH],
                hits: [None; PATH_BATCH],
                specular: [Departures::NONE; PATH_GROUPS],
                arriving: [Vec3x16::ZERO; PATH_GROUPS],
            }),
        }
    }
}

/// A batch's paths: each path's state, the paths still going and their next rays and hits, the
/// mirror and glass vertices, and β of each diffuse hit's path as it arrives. Kept off the
/// stack: as the batch's own arrays they would swell the stack frame of the code compiled for
/// the CPU, which the lab's batches share, and slow the lab pass. A batch takes only what it
/// wrote: the entries of its paths are set when they start, and lanes left from
/// earlier vertices or batches are computed with, never taken (as [`super::Scratch`]'s).
struct PathMemory {
    paths: [PathState; PATH_BATCH],
    alive: [u16; PATH_BATCH],
    rays_alive: [Ray; PATH_BATCH],
    hits: [Option<Intersection>; PATH_BATCH],
    /// Mirror and glass vertices, sampled one at a time.
    specular: [Departures; PATH_GROUPS],
    arriving: [Vec3x16; PATH_GROUPS],
}

#[derive(Clone, Copy, Debug)]
struct PathState {
    /// β, the throughput: what light found at the next vertex is multiplied by.
    beta: Vec3,
    /// Diffuse bounces made.
    bounces: u32,
    /// Vertices visited.
    depth: u32,
}

impl PathState {
    /// A path at the camera: full throughput, no vertex yet.
    const START: Self = Self {
        beta: Vec3::ONE,
        bounces: 0,
        depth: 0,
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
    /// there ([`crate::scene::Scene::approach_at_edge`], as in [`super::Surfaces`]).
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

    /// Puts a vertex already sampled one at a time (mirror or glass) in lane `i`.
    #[inline(always)]
    fn set(&mut self, i: usize, owner: usize, hit: &Intersection, normal: Vec3, beta: Vec3) {
        self.position.set_lane(i, hit.position);
        self.normal.set_lane(i, normal);
        self.beta.set_lane(i, beta);
        self.owner[i] = owner as u16;
        self.active.0[i] = true;
    }

    #[inline(always)]
    fn set_scatter(&mut self, i: usize, at_edge: Option<Vec3>, scatter: Scatter) {
        self.near_edge.0[i] = at_edge.is_some();
        self.incoming.set_lane(i, at_edge.unwrap_or(Vec3::ZERO));
        self.direction.set_lane(i, scatter.direction);
        self.weight.set_lane(i, scatter.weight);
    }
}

/// The vertices of `d` go on: β times the weight, Russian roulette from [`ROULETTE_DEPTH`] on,
/// the next ray; the paths that survive are appended to `alive[..*still]`, their next rays
/// to `rays[..*still]`.
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
    let mut roulette = M16::NONE;
    for lane in 0..LANES {
        if d.active.0[lane] {
            depth[lane] = paths[d.owner[lane] as usize].depth + 1;
            roulette.0[lane] = depth[lane] >= ROULETTE_DEPTH;
        }
    }
    let u = rng.draw(d.active);
    let beta = d.beta * d.weight;
    let survival = F32x16::select(
        roulette,
        beta.max_element()
            .simd_min(F32x16::splat(ROULETTE_MAX_SURVIVAL)),
        F32x16::splat(1.0),
    );
    let beta = beta * (F32x16::splat(1.0) / survival);
    let lucky = u.simd_lt(survival);
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
    let sphere_light = tracer.light.is_area();
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
        alive,
        rays_alive,
        hits,
        specular,
        arriving,
    } = &mut **memory;
    let HitScratch { diffuse, lit } = lanes;
    let n = rays.len();
    paths[..n].fill(PathState::START);
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
        // Each hit to its phase: the diffuse ones into lanes for their light and bounce, the
        // specular ones sampled here.
        diffuse.clear();
        // The diffuse hits in lanes one after another (lanes left empty would cost their
        // groups' light and shadow rays as much as full ones).
        let mut n_diffuse = 0;
        let mut n_specular = 0;
        for k in 0..n_alive {
            let (i, ray) = (alive[k] as usize, &rays_alive[k]);
            let path = &paths[i];
            if R::ENABLED {
                rec.closest_hit(ray, hits[k].as_ref(), path.beta, path.depth);
            }
            let Some(hit) = hits[k] else { continue };
            let triangle = &triangles[hit.triangle_index];
            let material = &materials[triangle.material as usize];
            let geometric = triangle.normal;
            let incoming = ray.direction;
            let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, incoming);
            if material.is_diffuse() {
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
            } else {
                // Mirror and glass scatter about the triangle's own normal, or a relief's bent
                // one (the water's waves), held to the geometric surface's rules as the
                // general path tracer holds it ([`ShadingFrame::new`]). A direction the
                // BSDF refuses (a reflection below the triangle or a refraction that does not
                // cross it: only about a bent normal) ends the path.
                let shading = tracer.specular_normal(&hit, material, incoming);
                let Some(scatter) = material.sample(incoming, shading, geometric, &mut rngs[i])
                else {
                    continue;
                };
                let (g, lane) = (n_specular / LANES, n_specular % LANES);
                if lane == 0 {
                    specular[g].active = M16::NONE;
                }
                specular[g].set(lane, i, &hit, geometric, path.beta);
                specular[g].set_scatter(lane, at_edge, scatter);
                n_specular += 1;
            }
        }
        let mut still = 0;
        // The direct term at the diffuse hits (drawing a spherical light's points first).
        if sphere_light {
            diffuse.light::<true>(tracer, rngs, |i| i as usize, lit);
        } else {
            diffuse.light::<false>(tracer, rngs, |i| i as usize, lit);
        }
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
        for d in &specular[..n_specular.div_ceil(LANES)] {
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::HitTerms;
    use crate::intersect::Intersection;
    use crate::material::{Material, MaterialPreset, TexturePreset};
    use crate::scene::cornell_box;
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
    fn path_tracer_for(scene: &crate::scene::Scene) -> Tracer<'_> {
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
        let mut spec = crate::scene::SceneChoice::Pool.spec();
        spec.water.as_mut().unwrap().waves = 0.0;
        let scene = crate::scene::SceneChoice::from_spec(spec).load().unwrap();
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
        use crate::geometry::Triangle;
        use crate::material::MaterialKind;
        use crate::relief::{NormalMap, Relief};
        use crate::texture::TextureImage;
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
            let scene = crate::scene::Scene::new(square.clone(), vec![material]);
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
