//! Path tracing: real light where the lab adds the constant N.
//!
//! A path starts with the camera ray. At every diffuse vertex it adds the lab's direct term,
//! ρ·D with the shadow ray (next-event estimation to the point light, [`HitTerms`]), times the
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
//! Paths run in batches of [`BATCH`], phase by phase, as the lab stages do. Each path draws only
//! from its own generator, in the same order whatever the batch: a pixel computed alone is the
//! same as in an image, and with the bounces capped at B the first B bounces draw the same
//! numbers as with more, so adding bounces only ever adds light.

use glam::Vec3;

use super::{
    BATCH, HitTerms, Recorder, Stage, Tracer, cast_shadow_rays, continue_ray, light_point,
};
use crate::geometry::Ray;
use crate::intersect::Intersection;
use crate::material::facing;
use crate::sampling::Rng;

/// Vertices before Russian roulette may end a path.
pub const ROULETTE_DEPTH: u32 = 3;

/// The largest survival probability of Russian roulette: even a path that keeps all its
/// throughput (clear glass) ends after about 20 more vertices on average.
pub const ROULETTE_MAX_SURVIVAL: f32 = 0.95;

/// Vertices after which a path is ended whatever its throughput.
pub const MAX_DEPTH: u32 = 256;

#[derive(Clone, Copy, Debug)]
struct PathState {
    ray: Ray,
    /// β, the throughput: what light found at the next vertex is multiplied by.
    beta: Vec3,
    /// Diffuse bounces made.
    bounces: u32,
    /// Vertices visited.
    depth: u32,
}

/// The value of every ray (π × radiance), into `out`; each step told to `rec` ([`Recorder`]).
#[inline(always)]
pub(super) fn trace<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    rec: &mut R,
) {
    for ((rays, rngs), out) in rays
        .chunks(BATCH)
        .zip(rngs.chunks_mut(BATCH))
        .zip(out.chunks_mut(BATCH))
    {
        batch(tracer, rays, rngs, out, rec);
    }
}

#[inline(always)]
fn batch<R: Recorder>(
    tracer: &Tracer,
    rays: &[Ray],
    rngs: &mut [Rng],
    out: &mut [Vec3],
    rec: &mut R,
) {
    let scene = tracer.scene;
    let shading = &tracer.shading;
    let max_bounces = shading.max_bounces();
    let (triangles, materials) = (scene.triangles.as_slice(), &*tracer.materials);
    out.fill(Vec3::ZERO);
    let mut paths = [PathState {
        ray: rays[0],
        beta: Vec3::ONE,
        bounces: 0,
        depth: 0,
    }; BATCH];
    // The paths still going, by index.
    let mut alive = [0u8; BATCH];
    for (i, ray) in rays.iter().enumerate() {
        paths[i].ray = *ray;
        alive[i] = i as u8;
    }
    let mut n_alive = rays.len();
    let mut hits: [Option<Intersection>; BATCH] = [None; BATCH];
    let mut rays_alive = [rays[0]; BATCH];
    let mut terms = [HitTerms::NONE; BATCH];
    // For each term: the path it belongs to and the throughput it is seen with.
    let mut term_of = [(0u8, Vec3::ZERO); BATCH];

    while n_alive > 0 {
        for (ray, &i) in rays_alive.iter_mut().zip(&alive[..n_alive]) {
            *ray = paths[i as usize].ray;
        }
        scene.closest_intersections(&rays_alive[..n_alive], f32::INFINITY, &mut hits[..n_alive]);
        let mut n_terms = 0;
        let mut still = 0;
        for k in 0..n_alive {
            let i = alive[k] as usize;
            if R::ENABLED {
                let path = &paths[i];
                rec.closest_hit(&path.ray, hits[k].as_ref(), path.beta, path.depth);
            }
            let Some(hit) = hits[k] else { continue };
            let path = &mut paths[i];
            let rng = &mut rngs[i];
            let triangle = &triangles[hit.triangle_index];
            let material = &materials[triangle.material as usize];
            let geometric = triangle.normal;
            let incoming = path.ray.direction;
            if material.is_diffuse() {
                // Two-sided: both normals turned to face the arriving ray.
                let mut surface = tracer.surface(&hit, material, incoming);
                let turned = facing(geometric, incoming);
                if turned != geometric {
                    surface.geometric = turned;
                    surface.normal = -surface.normal;
                }
                terms[n_terms] =
                    HitTerms::at(&tracer.light, Stage::Path, shading.shadows, surface, |p| {
                        light_point(&tracer.light, p, rng)
                    });
                term_of[n_terms] = (i as u8, path.beta);
                n_terms += 1;
                if path.bounces >= max_bounces {
                    continue;
                }
                path.bounces += 1;
            }
            let scatter = material.sample(incoming, geometric, rng);
            path.beta *= scatter.weight;
            let at_edge = scene.approach_at_edge(hit.triangle_index, hit.u, hit.v, incoming);
            path.ray = continue_ray(hit.position, geometric, scatter.direction, at_edge);
            path.depth += 1;
            // Russian roulette from ROULETTE_DEPTH on. Its number is drawn at every vertex,
            // used or not, and the outcome is computed without branches: whether a path
            // survives is a coin toss the processor cannot predict.
            let u = rng.next_f32();
            let roulette = path.depth >= ROULETTE_DEPTH;
            let survival = if roulette {
                path.beta.max_element().min(ROULETTE_MAX_SURVIVAL)
            } else {
                1.0
            };
            path.beta *= survival.recip();
            // A path that lost all its throughput (a black surface) ends at the roulette, where
            // its survival is 0; before it, it may go on a vertex or two adding nothing.
            let keep = (path.depth < MAX_DEPTH) & (u < survival);
            if R::ENABLED {
                rec.scattered(&scatter, survival, path.beta, keep);
            }
            alive[still] = i as u8;
            still += usize::from(keep);
        }
        n_alive = still;
        cast_shadow_rays(scene, &mut terms[..n_terms]);
        for (t, &(i, beta)) in terms[..n_terms].iter().zip(&term_of) {
            let value = t.value(Stage::Path, Vec3::ZERO);
            if R::ENABLED {
                rec.shaded(t, Vec3::ZERO, value, beta);
            }
            out[i as usize] += beta * value;
        }
    }
}
