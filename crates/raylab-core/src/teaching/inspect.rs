//! The pixel inspector: why a pixel has its colour, line by line, each line beside the lab
//! equation it evaluates, with the numbers substituted and their units.
//!
//! [`inspect_pixel`] recomputes sample 0 of one pixel through the renderer's own code: it makes
//! the pixel's camera ray as the renderer does (the pixel centre, or for the path stage and the
//! other random extensions the stream of (seed, x, y, 0)) and runs it through
//! [`Tracer::trace_recorded`] with a recording [`Recorder`]. The integrators tell the recording
//! each step as they take it (closest hits, mirror and glass branches, every hit's
//! [`HitTerms`] once its shadow ray is answered, every path vertex), so each number reported is
//! one the tracer computed, and [`Inspection::r`] is [`crate::transport::render::trace_pixel`]'s value
//! bit for bit. There is no second copy of the shading formulas here.
//!
//! Two things are worked out here because the renderer never needs them:
//!
//! * the parts of D (equation 27): the vector r to the light, its length, r̂·n̂ and 4πr², by
//!   [`direct_light`](crate::shading::light::direct_light)'s own expression on the tracer's hit point and normal (the tests check
//!   that they give the tracer's D bit for bit);
//! * what blocks a shadow ray: the renderer only asks *whether* something does (§5.1);
//!   [`Scene::closest_intersection`] along the very same shadow ray says which triangle, and
//!   how far along.
//!
//! The inspector runs the portable build of the integrators, one ray at a time; the renderer's
//! AVX2 and AVX-512 builds and its batches give the same bits (tested in [`crate::transport::integrator`]).
//!
//! Units: lengths in scene units (the box is 2 units wide), the light's power P in watts, D in
//! watts per unit area. `·` stands for the lab's element-wise product `∗`.

use std::fmt::Write as _;

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::base::geometry::Ray;
use crate::base::sampling::Rng;
use crate::shading::light::{DirectLight, LightKind, LightSpec};
use crate::shading::material::{Material, MaterialKind, Scatter};
use crate::shapes::intersect::Intersection;
use crate::shapes::scene::Scene;
use crate::transport::display::Display;
use crate::transport::integrator::{HitTerms, Recorder, Stage, Tracer, path, path_mis};
use crate::transport::settings::{RenderSettings, SettingsError};

/// Why a pixel can't be inspected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InspectError {
    /// The pixel is not in the image.
    #[error(
        "pixel ({x}, {y}) is outside the {width}×{height} image (x below {width}, y below {height})"
    )]
    OutsideImage {
        x: u32,
        y: u32,
        width: u32,
        height: u32,
    },
    /// The settings can't be rendered (the same check a render makes).
    #[error(transparent)]
    Settings(#[from] SettingsError),
}

/// Everything the tracer computed for sample 0 of one pixel, and the lab's words for it
/// ([`Inspection::lines`]).
///
/// The fields from `triangle` to `shading_normal` describe the camera ray's first hit. The
/// lab's terms (`rho` to `blocker`, flattened from [`LightTerms`]) are those of the first
/// diffuse hit whose light was computed: the first hit itself, or, when that is a mirror or
/// glass, the diffuse hit its first branch reaches (`specular_chain` says how), or the path's
/// first diffuse vertex. `shaded` lists every diffuse hit that adds to R.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Inspection {
    /// The pixel, [x, y] from the top-left corner.
    pub pixel: [u32; 2],
    pub stage: Stage,
    /// What the stage computes with its switches as they are ([`crate::Shading::description`]).
    pub computes: String,
    /// Whether shadow rays are cast (§5.1).
    pub shadows: bool,
    /// The image size, [W, H], and the focal length f in pixels (equation 24).
    pub image: [u32; 2],
    pub focal_length: f32,
    /// The point of the image plane the ray goes through, in pixels: the pixel's centre.
    pub image_point: [f32; 2],
    /// The point of the lens the ray leaves from, on the unit disk (`None`: the lab's pinhole).
    pub lens_point: Option<Vec2>,
    /// The camera ray (equation 24): origin s and unit direction d̂.
    pub origin: Vec3,
    pub direction: Vec3,
    /// The triangle the camera ray hits first (equations 7–9, 12), or `None`: nothing is hit.
    pub triangle: Option<usize>,
    /// Its material's name and kind (diffuse, mirror or glass).
    pub surface: Option<String>,
    pub kind: Option<&'static str>,
    /// The distance t along the ray and the barycentric coordinates u, v of the hit.
    pub t: Option<f32>,
    pub u: Option<f32>,
    pub v: Option<f32>,
    /// The hit point s + t·d̂.
    pub position: Option<Vec3>,
    /// The triangle's own normal n̂.
    pub normal: Option<Vec3>,
    /// Whether the ray meets the triangle's back (d̂·n̂ > 0).
    pub back_facing: Option<bool>,
    /// The normal D was computed with at the first hit, where it differs from `normal`: the
    /// interpolated vertex normals (smooth shading) or, in the path stage, the normal turned to
    /// face the ray (surfaces are two-sided there), or a normal map's tilt of either.
    pub shading_normal: Option<Vec3>,
    /// Whether the first hit's material has a normal map ([`crate::shading::relief`]): its normal for
    /// the light is the map's.
    #[serde(default)]
    pub normal_mapped: bool,
    /// The light.
    pub light: LightSpec,
    /// The lab's terms at the first diffuse hit shaded (see above).
    #[serde(flatten)]
    pub terms: LightTerms,
    /// N, the constant indirect light in force (0 with indirect off, and in the path stage,
    /// where bounces bring real indirect light instead).
    #[serde(rename = "N")]
    pub n: Vec3,
    /// R, the pixel's value: exactly what the renderer puts in the image for one sample.
    #[serde(rename = "R")]
    pub r: Vec3,
    /// Lab stages: every mirror and glass branch followed, in the order they were traced.
    pub specular_chain: Vec<SpecularStep>,
    /// Lab stages: specular branches that left the scene (they add nothing).
    pub escaped: Vec<EscapedBranch>,
    /// Every diffuse hit whose value was added to R, with what it was multiplied by.
    pub shaded: Vec<ShadedHit>,
    /// Path stage: the path's vertices.
    pub bounces: Vec<PathVertex>,
}

/// The lab's terms at one diffuse hit, as the tracer computed them. `None` where the stage
/// computes no light (the flat stage) or the hit does not exist.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LightTerms {
    /// ρ, the diffuse reflectance at the hit (the texture's value there, if textured).
    pub rho: Option<Vec3>,
    /// Whether ρ came from a texture.
    pub textured: bool,
    /// At a glossy hit (the rough metal, the plastic) in the lab's stages, where `rho` is π·f
    /// toward the light's centre: f's parts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub glossy: Option<GlossyTerms>,
    /// r, the vector from the hit to the light's centre.
    pub to_light: Option<Vec3>,
    /// |r| (at least [`crate::shading::light::MIN_LIGHT_DISTANCE`]).
    pub light_distance: Option<f32>,
    /// r², as equation 27 divides by it.
    pub light_distance_squared: Option<f32>,
    /// r̂·n̂, the cosine of the light's angle to the normal (before max(…, 0)).
    pub cos_theta: Option<f32>,
    /// P, the light's power per channel: power · colour, in watts.
    #[serde(rename = "P")]
    pub power: Option<Vec3>,
    /// 4πr², the area of the sphere of radius |r| the power is spread over.
    pub four_pi_r2: Option<f32>,
    /// A spot light's falloff toward the point (1 within its beam, 0 beyond its cutoff).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub falloff: Option<f32>,
    /// D = P·max(r̂·n̂, 0)/(4πr²) (equation 27), in watts per unit area, before shadows.
    #[serde(rename = "D")]
    pub d: Option<Vec3>,
    /// Smooth shading: the smooth normal faces the light but the surface itself does not, so
    /// D is 0 (a smooth normal never lets light through a surface).
    pub light_behind_surface: bool,
    /// Parallax self-shadowing: the surface's own relief (its height map) hides the light, so
    /// D is 0.
    #[serde(default)]
    pub relief_shadowed: bool,
    /// The shadow ray cast (§5.1), or `None` when none was (shadows off, or no light to block).
    pub shadow_ray: Option<ShadowRay>,
    /// Whether the shadow ray was blocked: D counts as 0.
    pub shadow_blocked: bool,
    /// What blocks it.
    pub blocker: Option<Blocker>,
}

/// π·f at a glossy hit, toward the viewer and the light's centre, in its two parts
/// ([`Tracer::glossy_parts`]): the lab's stages use it as ρ.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GlossyTerms {
    /// π·f_s: the coating's (the metal's) microfacet reflection, the highlight.
    pub specular: Vec3,
    /// π·f_d: the plastic's diffuse base seen through its coating (0 for the metal).
    pub diffuse: Vec3,
}

/// A shadow ray (§5.1): from just off the surface toward a point of the light, stopping
/// `length` along.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ShadowRay {
    pub origin: Vec3,
    pub direction: Vec3,
    pub length: f32,
}

/// The first triangle along a blocked shadow ray.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Blocker {
    pub triangle: usize,
    pub surface: String,
    /// Along the shadow ray, in scene units.
    pub distance: f32,
}

/// One branch leaving a mirror or glass hit (lab stages, Whitted-style).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpecularStep {
    /// Mirror and glass hits before this one along the branch.
    pub depth: u32,
    pub triangle: usize,
    pub surface: String,
    pub kind: &'static str,
    pub position: Vec3,
    /// "reflection", "refraction", "total internal reflection" (glass past the critical
    /// angle), or "given up" (the specular depth is reached: black).
    pub branch: &'static str,
    /// The direction out (`None` when given up).
    pub direction: Option<Vec3>,
    /// This branch's weight: the mirror's tint, Fresnel's F, or (1 − F)·tint.
    pub weight: Vec3,
    /// What the branch's value is multiplied by: the weights along the chain.
    pub total_weight: Vec3,
}

/// A specular branch that hits nothing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EscapedBranch {
    pub depth: u32,
    pub weight: Vec3,
}

/// A diffuse hit that adds to R: where, its terms, and what it adds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShadedHit {
    /// Lab: mirror and glass hits before it; path: the vertex's index.
    pub depth: u32,
    pub triangle: usize,
    pub surface: String,
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub position: Vec3,
    /// The normal D was computed with.
    pub normal: Vec3,
    #[serde(flatten)]
    pub terms: LightTerms,
    /// N as the value used it.
    #[serde(rename = "N")]
    pub n: Vec3,
    /// The hit's value as the stage says (ρ, D + N, ρ·(D + N); equations 27–30).
    pub value: Vec3,
    /// What the value is multiplied by: specular weights (lab) or the throughput β (path).
    pub weight: Vec3,
    /// weight · value, added to R.
    pub contribution: Vec3,
}

/// A vertex of the path (path stage).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathVertex {
    /// Vertices before it.
    pub depth: u32,
    pub triangle: usize,
    pub surface: String,
    pub kind: &'static str,
    pub position: Vec3,
    /// β, the throughput the light found here is multiplied by.
    pub beta: Vec3,
    /// β·ρ·D (with shadows), added to R; 0 at mirror and glass.
    pub light_added: Vec3,
    /// Where the path goes next, how ("cosine-weighted bounce", "reflection", "refraction"),
    /// and the sample's weight (ρ for a diffuse bounce, the tint for a mirror or a refraction,
    /// 1 for a reflection off glass), or `None` when the path ends here.
    pub direction_out: Option<Vec3>,
    pub scatter: Option<&'static str>,
    pub scatter_weight: Option<Vec3>,
    /// Russian roulette's survival probability q (1 before its depth) and β after the
    /// bounce and the roulette.
    pub survival: Option<f32>,
    pub beta_after: Option<Vec3>,
    /// Why the path ends here, if it does.
    pub ends: Option<String>,
    /// The general path tracer (area lights, the rough metal): its light sample here, with the
    /// BSDF's value, both densities and the MIS weight.
    pub light_sample: Option<NextEvent>,
    /// Caustics by photons: the photon map's gather at this diffuse vertex (how
    /// many photons it found, within which radius, and what it added to R, β included).
    pub photons: Option<PhotonGather>,
}

/// The caustic photon map's gather at a vertex ([`crate::transport::photon_map::Gathered`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhotonGather {
    /// Photons within the radius, on the same surface.
    pub photons: u32,
    /// The gather radius of this pass.
    pub radius: f32,
    /// β · Σ f·Φ / r², added to R.
    pub added: Vec3,
}

/// Next-event estimation at a path vertex, as the general path tracer computed it
/// ([`crate::transport::integrator::path_mis::LightTerms`]).
pub use crate::transport::integrator::path_mis::LightTerms as NextEvent;

/// One line of the explanation: the equation it evaluates and the text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct InspectLine {
    /// The lab's equation or section, e.g. "eq. 27", "§5.1", "fig. 7"; or what the step is.
    pub equation: String,
    /// The step with numbers substituted, e.g. "D = P·max(r̂·n̂, 0)/(4πr²) = 14 W × 0.906 /
    /// (4π × 2.740 units²) = 0.368 W per unit area".
    pub text: String,
}

/// What the screen shows at the inspected pixel: the value of the image on screen there, and
/// what that image is. With one sample it is [`Inspection::r`] itself; with more it is their
/// mean (the film's), or the denoised image's value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ShownPixel {
    /// The pixel's linear value in the image on screen.
    pub value: Vec3,
    /// The samples the image on screen averages (so far).
    pub samples: u32,
    /// Whether the image on screen is the denoised one, made from those samples.
    pub denoised: bool,
}

/// Recomputes sample 0 of pixel `(x, y)` as the renderer does and records every step.
///
/// `Inspection::r` equals [`crate::transport::render::trace_pixel`]`(scene, settings, x, y, 0)` bit for
/// bit, in every stage and with every preset. Errors for a pixel outside the image or settings
/// that can't be rendered.
pub fn inspect_pixel(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
) -> Result<Inspection, InspectError> {
    settings.validate()?;
    let camera = &settings.camera;
    if x >= camera.width || y >= camera.height {
        return Err(InspectError::OutsideImage {
            x,
            y,
            width: camera.width,
            height: camera.height,
        });
    }
    let tracer = Tracer::for_pass(scene, settings, 0);
    let (ray, rng, image_point, lens_point) = camera_sample_0(&tracer, settings, x, y);
    let mut recording = Recording::default();
    let mut out = [Vec3::ZERO];
    tracer.trace_recorded(&[ray], &mut [rng], &mut out, &mut recording);
    Ok(Inspection::from_recording(
        &tracer,
        settings,
        [x, y],
        image_point,
        lens_point,
        ray,
        &recording.events,
        out[0],
    ))
}

/// Sample 0's camera ray and generator, made by the renderer's own
/// [`crate::transport::render::camera_sample`]: the pixel's centre (sample 0 is never jittered), through a
/// point of the lens drawn from the sample's stream when the camera has an aperture.
fn camera_sample_0(
    tracer: &Tracer,
    settings: &RenderSettings,
    x: u32,
    y: u32,
) -> (Ray, Rng, [f32; 2], Option<Vec2>) {
    let mut ray = Ray::new(Vec3::ZERO, Vec3::Z);
    let mut rng = Rng::UNUSED;
    let rotation = settings.camera.rotation();
    let ((px, py), lens) = crate::transport::render::camera_sample(
        tracer, settings, &rotation, x, y, 0, &mut ray, &mut rng,
    );
    (ray, rng, [px, py], lens)
}

/// A step the integrator took, as told to [`Recording`].
#[derive(Clone, Debug)]
enum Event {
    Hit {
        ray: Ray,
        hit: Option<Intersection>,
        weight: Vec3,
        depth: u32,
    },
    Specular {
        hit: Intersection,
        weight: Vec3,
        depth: u32,
        branches: Vec<(Vec3, Vec3)>,
    },
    Shaded {
        terms: HitTerms,
        n: Vec3,
        value: Vec3,
        weight: Vec3,
    },
    Scattered {
        scatter: Scatter,
        survival: f32,
        beta: Vec3,
        survives: bool,
    },
    Vertex(path_mis::PathVertex),
}

/// The inspector's [`Recorder`]: every step, in order.
#[derive(Debug, Default)]
struct Recording {
    events: Vec<Event>,
}

impl Recorder for Recording {
    const ENABLED: bool = true;

    fn closest_hit(&mut self, ray: &Ray, hit: Option<&Intersection>, weight: Vec3, depth: u32) {
        self.events.push(Event::Hit {
            ray: *ray,
            hit: hit.copied(),
            weight,
            depth,
        });
    }

    fn specular_hit(
        &mut self,
        hit: &Intersection,
        weight: Vec3,
        depth: u32,
        branches: &[(Vec3, Vec3)],
    ) {
        self.events.push(Event::Specular {
            hit: *hit,
            weight,
            depth,
            branches: branches.to_vec(),
        });
    }

    fn shaded(&mut self, terms: &HitTerms, n: Vec3, value: Vec3, weight: Vec3) {
        self.events.push(Event::Shaded {
            terms: *terms,
            n,
            value,
            weight,
        });
    }

    fn scattered(&mut self, scatter: &Scatter, survival: f32, beta: Vec3, survives: bool) {
        self.events.push(Event::Scattered {
            scatter: *scatter,
            survival,
            beta,
            survives,
        });
    }

    fn path_vertex(&mut self, vertex: &path_mis::PathVertex) {
        self.events.push(Event::Vertex(*vertex));
    }
}

/// How a ray arriving along `incoming` left a surface of `kind` along `outgoing`: a diffuse
/// bounce, a reflection (back to the side it came from) or a refraction (through).
fn scatter_kind(kind: &MaterialKind, incoming: Vec3, outgoing: Vec3, normal: Vec3) -> &'static str {
    if matches!(kind, MaterialKind::Diffuse) {
        "cosine-weighted bounce"
    } else if outgoing.dot(normal) * incoming.dot(normal) < 0.0 {
        "reflection"
    } else {
        "refraction"
    }
}

impl LightTerms {
    /// The terms of a hit as the tracer left them, with the parts of D and the blocker.
    fn of(
        tracer: &Tracer,
        stage: Stage,
        terms: &HitTerms,
        material: &Material,
        glossy: Option<GlossyTerms>,
    ) -> Self {
        let mut out = LightTerms {
            rho: Some(terms.rho),
            textured: material.texture.is_some(),
            glossy,
            ..LightTerms::default()
        };
        if stage == Stage::Flat {
            return out;
        }
        let light = &tracer.light;
        let parts = DirectLight::at(light, terms.position, terms.normal);
        out.to_light = Some(parts.to_light);
        out.light_distance = Some(parts.distance());
        out.light_distance_squared = Some(parts.r2);
        out.cos_theta = Some(parts.cos);
        out.power = Some(light.channel_power());
        out.four_pi_r2 = Some(parts.four_pi_r2);
        out.falloff = light.spot().map(|_| parts.falloff);
        out.d = Some(terms.d);
        out.relief_shadowed = terms.relief_shadowed;
        out.light_behind_surface =
            terms.d == Vec3::ZERO && parts.d != Vec3::ZERO && !terms.relief_shadowed;
        if let Some((ray, length)) = terms.shadow_ray {
            out.shadow_ray = Some(ShadowRay {
                origin: ray.origin,
                direction: ray.direction,
                length,
            });
        }
        out.shadow_blocked = terms.blocked;
        if terms.blocked {
            out.blocker = terms.shadow_ray.and_then(|(ray, length)| {
                let hit = tracer.scene.closest_intersection(&ray, length)?;
                Some(Blocker {
                    triangle: hit.triangle_index,
                    surface: tracer.material_of(hit.triangle_index).name.clone(),
                    distance: hit.distance,
                })
            });
        }
        out
    }
}

impl Inspection {
    #[allow(clippy::too_many_arguments)]
    fn from_recording(
        tracer: &Tracer,
        settings: &RenderSettings,
        pixel: [u32; 2],
        image_point: [f32; 2],
        lens_point: Option<Vec2>,
        camera_ray: Ray,
        events: &[Event],
        r: Vec3,
    ) -> Self {
        let scene = tracer.scene;
        let shading = &tracer.shading;
        let stage = shading.stage;
        let camera = &settings.camera;
        let mut inspection = Inspection {
            pixel,
            stage,
            computes: shading.description(settings.material_preset),
            shadows: shading.shadows && stage != Stage::Flat,
            image: [camera.width, camera.height],
            focal_length: camera.focal_length,
            image_point,
            lens_point,
            origin: camera_ray.origin,
            direction: camera_ray.direction,
            triangle: None,
            surface: None,
            kind: None,
            t: None,
            u: None,
            v: None,
            position: None,
            normal: None,
            back_facing: None,
            shading_normal: None,
            normal_mapped: false,
            light: tracer.light,
            terms: LightTerms::default(),
            n: shading.indirect_term(),
            r,
            specular_chain: Vec::new(),
            escaped: Vec::new(),
            shaded: Vec::new(),
            bounces: Vec::new(),
        };
        // The diffuse hits waiting for their terms, in the order the integrator shades them,
        // and the latest hit (a specular hit's or a path scattering's own).
        let mut waiting: std::collections::VecDeque<(Ray, Intersection, u32)> = Default::default();
        let mut latest: Option<(Ray, Intersection)> = None;
        for (index, event) in events.iter().enumerate() {
            match event {
                Event::Hit {
                    ray,
                    hit,
                    weight,
                    depth,
                } => {
                    let first = index == 0;
                    let Some(hit) = hit else {
                        if stage == Stage::Path {
                            if let Some(last) = inspection.bounces.last_mut() {
                                last.ends = Some("the next ray leaves the scene".to_owned());
                            }
                        } else if !first {
                            inspection.escaped.push(EscapedBranch {
                                depth: *depth,
                                weight: *weight,
                            });
                        }
                        continue;
                    };
                    let material = tracer.material_of(hit.triangle_index);
                    let geometric = scene.triangles[hit.triangle_index].normal;
                    if first {
                        inspection.triangle = Some(hit.triangle_index);
                        inspection.surface = Some(material.name.clone());
                        inspection.kind = Some(material.kind.name());
                        inspection.t = Some(hit.distance);
                        inspection.u = Some(hit.u);
                        inspection.v = Some(hit.v);
                        inspection.position = Some(hit.position);
                        inspection.normal = Some(geometric);
                        inspection.back_facing = Some(ray.direction.dot(geometric) > 0.0);
                        inspection.normal_mapped =
                            material.relief.as_ref().is_some_and(|r| r.normal.is_some());
                    }
                    if stage == Stage::Path {
                        inspection.bounces.push(PathVertex {
                            depth: *depth,
                            triangle: hit.triangle_index,
                            surface: material.name.clone(),
                            kind: material.kind.name(),
                            position: hit.position,
                            beta: *weight,
                            light_added: Vec3::ZERO,
                            direction_out: None,
                            scatter: None,
                            scatter_weight: None,
                            survival: None,
                            beta_after: None,
                            ends: None,
                            light_sample: None,
                            photons: None,
                        });
                    }
                    // Diffuse hits and, in the lab's stages, glossy ones are shaded; the path
                    // tracer tells the others' light as a vertex.
                    if !material.is_specular() && (stage != Stage::Path || material.is_diffuse()) {
                        waiting.push_back((*ray, *hit, *depth));
                    }
                    latest = Some((*ray, *hit));
                }
                Event::Specular {
                    hit,
                    weight,
                    depth,
                    branches,
                } => {
                    let material = tracer.material_of(hit.triangle_index);
                    let normal = scene.triangles[hit.triangle_index].normal;
                    let incoming = latest.map_or(camera_ray.direction, |(ray, _)| ray.direction);
                    let step = |branch, direction, w: Vec3| SpecularStep {
                        depth: *depth,
                        triangle: hit.triangle_index,
                        surface: material.name.clone(),
                        kind: material.kind.name(),
                        position: hit.position,
                        branch,
                        direction,
                        weight: w,
                        total_weight: *weight * w,
                    };
                    if branches.is_empty() {
                        inspection
                            .specular_chain
                            .push(step("given up", None, Vec3::ZERO));
                    }
                    for &(direction, w) in branches {
                        let kind = match scatter_kind(&material.kind, incoming, direction, normal) {
                            "reflection"
                                if branches.len() == 1
                                    && matches!(material.kind, MaterialKind::Glass { .. }) =>
                            {
                                "total internal reflection"
                            }
                            kind => kind,
                        };
                        inspection
                            .specular_chain
                            .push(step(kind, Some(direction), w));
                    }
                }
                Event::Shaded {
                    terms,
                    n,
                    value,
                    weight,
                } => {
                    let Some((ray, hit, depth)) = waiting.pop_front() else {
                        continue;
                    };
                    let material = tracer.material_of(hit.triangle_index);
                    let glossy = (!material.is_diffuse()).then(|| {
                        let surface = tracer.surface(&hit, material, ray.direction);
                        let (specular, diffuse) =
                            tracer.glossy_parts(material, &surface, ray.direction);
                        GlossyTerms { specular, diffuse }
                    });
                    let contribution = *weight * *value;
                    let shaded = ShadedHit {
                        depth,
                        triangle: hit.triangle_index,
                        surface: material.name.clone(),
                        t: hit.distance,
                        u: hit.u,
                        v: hit.v,
                        position: terms.position,
                        normal: terms.normal,
                        terms: LightTerms::of(tracer, stage, terms, material, glossy),
                        n: *n,
                        value: *value,
                        weight: *weight,
                        contribution,
                    };
                    if stage == Stage::Path
                        && let Some(vertex) = inspection
                            .bounces
                            .iter_mut()
                            .rev()
                            .find(|v| v.position == terms.position)
                    {
                        vertex.light_added = contribution;
                    }
                    if inspection.shaded.is_empty() {
                        inspection.terms = shaded.terms.clone();
                        if inspection.triangle == Some(hit.triangle_index)
                            && inspection.position == Some(terms.position)
                            && inspection.normal != Some(terms.normal)
                        {
                            inspection.shading_normal = Some(terms.normal);
                        }
                    }
                    inspection.shaded.push(shaded);
                }
                Event::Vertex(v) => {
                    if let (Some(vertex), Some(l)) = (inspection.bounces.last_mut(), v.light) {
                        vertex.light_added = l.added;
                        vertex.light_sample = Some(l);
                    }
                    if let (Some(vertex), Some(g)) = (inspection.bounces.last_mut(), v.photons) {
                        vertex.photons = Some(PhotonGather {
                            photons: g.photons,
                            radius: g.radius,
                            added: g.value,
                        });
                    }
                }
                Event::Scattered {
                    scatter,
                    survival,
                    beta,
                    survives,
                } => {
                    if let (Some(vertex), Some((ray, hit))) =
                        (inspection.bounces.last_mut(), latest)
                    {
                        let (incoming, hit) = (ray.direction, hit.triangle_index);
                        vertex.scatter = Some(scatter_kind(
                            &tracer.material_of(hit).kind,
                            incoming,
                            scatter.direction,
                            scene.triangles[hit].normal,
                        ));
                        vertex.direction_out = Some(scatter.direction);
                        vertex.scatter_weight = Some(scatter.weight);
                        vertex.survival = Some(*survival);
                        vertex.beta_after = Some(*beta);
                        if !survives {
                            vertex.ends = Some(if vertex.depth + 1 >= path::MAX_DEPTH {
                                format!("{} vertices, the most a path makes", path::MAX_DEPTH)
                            } else {
                                "Russian roulette ends the path".to_owned()
                            });
                        }
                    }
                }
            }
        }
        if stage == Stage::Path
            && let Some(last) = inspection.bounces.last_mut()
            && last.ends.is_none()
            && last.direction_out.is_none()
        {
            last.ends = Some(match shading.max_bounces() {
                0 => "no bounces (indirect off or bounces 0): direct light only".to_owned(),
                n => format!("the bounce cap ({n}) is reached"),
            });
        }
        inspection
    }

    /// The explanation, one line per step, each beside the lab equation it evaluates.
    pub fn lines(&self) -> Vec<InspectLine> {
        let mut lines = Lines::default();
        let stage = self.stage;
        let figure = match stage.figure() {
            Some(f) => format!("fig. {f}"),
            None => "path".to_owned(),
        };
        lines.push(
            &figure,
            format!(
                "pixel ({}, {}), stage {stage}: {}",
                self.pixel[0], self.pixel[1], self.computes
            ),
        );
        self.camera_lines(&mut lines);
        let Some(triangle) = self.triangle else {
            lines.push(
                "eqs. 7–9, 12",
                "closest intersection: none, the ray leaves the box (nothing is hit)".to_owned(),
            );
            lines.push(
                final_equation(stage, self.n),
                format!("R = {} (black: no surface, no light)", colour(self.r)),
            );
            return lines.0;
        };
        lines.push(
            "eqs. 7–9, 12",
            format!(
                "closest hit: triangle {triangle} ({}, {}) at t = {} units, u = {}, v = {} \
                 (u ≥ 0, v ≥ 0, u + v ≤ 1); point s + t·d̂ = {}",
                self.surface.as_deref().unwrap_or("?"),
                self.kind.unwrap_or("?"),
                num(self.t.unwrap_or(f32::NAN)),
                num(self.u.unwrap_or(f32::NAN)),
                num(self.v.unwrap_or(f32::NAN)),
                vector(self.position.unwrap_or(Vec3::NAN)),
            ),
        );
        if let Some(normal) = self.normal {
            let mut text = format!("surface normal n̂ = {}", vector(normal));
            if self.back_facing == Some(true) {
                text.push_str(&format!(
                    "; the ray meets its back (d̂·n̂ = {} > 0)",
                    num(self.direction.dot(normal))
                ));
            }
            lines.push("", text);
        }
        if let Some(n) = self.shading_normal {
            let why = if stage == Stage::Path && self.normal == Some(-n) {
                "turned to face the ray (two-sided surfaces)"
            } else if self.normal_mapped {
                "tilted by the normal map in the hit's tangent frame (lab §6)"
            } else {
                "smooth shading, interpolated from the vertex normals"
            };
            lines.push("", format!("normal for the light: {} ({why})", vector(n)));
        }
        if stage == Stage::Path {
            self.path_lines(&mut lines);
        } else {
            self.lab_lines(&mut lines);
        }
        lines.0
    }

    /// What the display makes of the pixel, to follow [`Inspection::lines`]: R through
    /// `display` (its exposure and curve) as the 8-bit value a screen or PNG shows; and when the
    /// pixel on screen is not sample 0 alone (`shown`: several samples, or denoised), that R is
    /// sample 0's, and the value shown with its own 8 bits. `shown` is `None` while no image of
    /// these settings is on screen.
    pub fn display_lines(&self, display: &Display, shown: Option<ShownPixel>) -> Vec<InspectLine> {
        let mut lines = Lines::default();
        let curve = match display.exposure {
            0.0 => format!("display {}", display.transform.label()),
            stops => format!(
                "display {}, exposure {stops:+} EV",
                display.transform.label()
            ),
        };
        let eight_bit = |v: Vec3| {
            let [r, g, b] = display.encode(v);
            if r == g && g == b {
                format!("{r}")
            } else {
                format!("({r}, {g}, {b})")
            }
        };
        match shown {
            Some(shown) if shown.samples > 1 || shown.denoised => {
                let origin = if self.lens_point.is_some() {
                    "through the pixel's centre and one point of the lens"
                } else {
                    "through the pixel's centre"
                };
                lines.push(
                    "sample 0",
                    format!(
                        "R above is sample 0's alone (the ray {origin}), {} in 8 bits through the \
                         {curve}: not the pixel on screen",
                        eight_bit(self.r)
                    ),
                );
                let what = if shown.denoised {
                    format!(
                        "the denoised image's value, filtered from the mean of {} samples",
                        shown.samples
                    )
                } else {
                    format!(
                        "the mean of its {} samples (each through another point of the pixel)",
                        shown.samples
                    )
                };
                lines.push(
                    "on screen",
                    format!(
                        "the pixel shown is {what}: {}, shown as {} in 8 bits",
                        colour(shown.value),
                        eight_bit(shown.value)
                    ),
                );
            }
            _ => lines.push(
                "on screen",
                format!(
                    "R = {}, shown as {} in 8 bits through the {curve}",
                    colour(self.r),
                    eight_bit(self.r)
                ),
            ),
        }
        lines.0
    }

    /// [`Inspection::lines`] joined, one per line: the equation, then the text.
    pub fn to_text(&self) -> String {
        lines_text(&self.lines())
    }

    fn camera_lines(&self, lines: &mut Lines) {
        let [px, py] = self.image_point;
        let [w, h] = self.image;
        match self.lens_point {
            None => lines.push(
                "eq. 24",
                format!(
                    "camera ray through image point ({}, {}) of {w}×{h}, f = {} px: d = R·(x − W/2, \
                     y − H/2, f) = R·({}, {}, {}), d̂ = {}, from s = {}",
                    num(px),
                    num(py),
                    num(self.focal_length),
                    num(px - w as f32 / 2.0),
                    num(py - h as f32 / 2.0),
                    num(self.focal_length),
                    vector(self.direction),
                    vector(self.origin),
                ),
            ),
            Some(lens) => lines.push(
                "eq. 24",
                format!(
                    "thin-lens camera ray for image point ({}, {}) of {w}×{h}, f = {} px, from lens \
                     point ({}, {}) of the unit disk: s = {}, d̂ = {}",
                    num(px),
                    num(py),
                    num(self.focal_length),
                    num(lens.x),
                    num(lens.y),
                    vector(self.origin),
                    vector(self.direction),
                ),
            ),
        }
    }

    /// The lab stages: the specular chain, then each diffuse hit's terms and value, then R.
    fn lab_lines(&self, lines: &mut Lines) {
        for step in &self.specular_chain {
            let what = match step.branch {
                "given up" => format!(
                    "depth {}: triangle {} ({}, {}) at {}: the specular depth is reached, the \
                     branch is given up (black)",
                    step.depth + 1,
                    step.triangle,
                    step.surface,
                    step.kind,
                    vector(step.position)
                ),
                branch => {
                    let weight = match (step.kind, branch) {
                        ("glass", "reflection") => "Fresnel's F",
                        ("glass", _) => "(1 − F)·tint",
                        _ => "the tint",
                    };
                    format!(
                        "depth {}: triangle {} ({}, {}) at {}: {branch} along {}, weight {} \
                         ({weight}); the branch carries {}",
                        step.depth + 1,
                        step.triangle,
                        step.surface,
                        step.kind,
                        vector(step.position),
                        vector(step.direction.unwrap_or(Vec3::NAN)),
                        colour(step.weight),
                        colour(step.total_weight),
                    )
                }
            };
            lines.push(step.kind, what);
        }
        for escaped in &self.escaped {
            lines.push(
                "",
                format!(
                    "a branch (weight {}) leaves the box after {} mirror or glass hit(s): it adds 0",
                    colour(escaped.weight),
                    escaped.depth
                ),
            );
        }
        let branched = !self.specular_chain.is_empty();
        for hit in &self.shaded {
            if branched {
                lines.push(
                    "eqs. 7–9, 12",
                    format!(
                        "a branch (weight {}) reaches triangle {} ({}) at t = {} units: point {}, \
                         normal {}",
                        colour(hit.weight),
                        hit.triangle,
                        hit.surface,
                        num(hit.t),
                        vector(hit.position),
                        vector(hit.normal)
                    ),
                );
            }
            self.terms_lines(lines, hit, "");
            let value = self.value_line(hit, if branched { "value" } else { "R" });
            lines.push(value.0, value.1);
            if branched {
                lines.push(
                    "",
                    format!(
                        "× the branch's weight {} = {} added to R",
                        colour(hit.weight),
                        colour(hit.contribution)
                    ),
                );
            }
        }
        if branched || self.shaded.is_empty() {
            let how = if self.shaded.is_empty() {
                "no diffuse surface is reached"
            } else {
                "the sum of what the branches add"
            };
            lines.push(
                final_equation(self.stage, self.n),
                format!("R = {} ({how})", colour(self.r)),
            );
        }
    }

    /// The path stage: every vertex with what it adds and where the path goes, then R.
    fn path_lines(&self, lines: &mut Lines) {
        let mut shaded = self.shaded.iter();
        for vertex in &self.bounces {
            lines.push(
                "path",
                format!(
                    "vertex {}: triangle {} ({}, {}) at {}, throughput β = {}",
                    vertex.depth,
                    vertex.triangle,
                    vertex.surface,
                    vertex.kind,
                    vector(vertex.position),
                    colour(vertex.beta)
                ),
            );
            if let Some(l) = &vertex.light_sample {
                lines.push(
                    "MIS",
                    format!(
                        "  light sample along {}: f = {}, p_light = {}, p_bsdf = {}, MIS weight \
                         p_light²/(p_light² + p_bsdf²) = {}; shadow ray {}; adds β·f·Li·cos θ/p_light·w = {}",
                        vector(l.wi),
                        colour(l.f),
                        num(l.pdf_light),
                        num(l.pdf_bsdf),
                        num(l.mis_weight),
                        if l.blocked { "blocked" } else { "unblocked" },
                        colour(l.added)
                    ),
                );
            } else if vertex.kind == "diffuse"
                && let Some(hit) = shaded.next()
            {
                self.terms_lines(lines, hit, "  ");
                let value = self.value_line(hit, "");
                lines.push(value.0, format!("  {}", value.1));
                lines.push(
                    "",
                    format!(
                        "  adds β·ρ·D = {} · {} = {}",
                        colour(hit.weight),
                        colour(hit.value),
                        colour(hit.contribution)
                    ),
                );
            } else {
                lines.push(
                    "",
                    "  adds nothing: a point light is never seen in a mirror or through glass"
                        .to_owned(),
                );
            }
            if let Some(g) = &vertex.photons {
                lines.push(
                    "photons",
                    format!(
                        "  caustic photons: {} found within r = {}; adds β·Σ f·Φ/r² = {}",
                        g.photons,
                        num(g.radius),
                        colour(g.added)
                    ),
                );
            }
            if let (Some(direction), Some(weight), Some(q), Some(after)) = (
                vertex.direction_out,
                vertex.scatter_weight,
                vertex.survival,
                vertex.beta_after,
            ) {
                let how = match (vertex.kind, vertex.scatter.unwrap_or("")) {
                    ("diffuse", _) => "a cosine-weighted bounce, weight ρ",
                    ("rough", _) => "a GGX visible-normal sample, weight tint·G1(wi)",
                    ("mirror", _) => "the mirror's reflection, weight the tint",
                    ("glass", "reflection") => "reflection off the glass (probability F), weight",
                    _ => "refraction through the glass (probability 1 − F), weight the tint",
                };
                let roulette = if q < 1.0 {
                    format!("; Russian roulette: it survives with q = {}, β ÷ q", num(q))
                } else {
                    String::new()
                };
                lines.push(
                    "",
                    format!(
                        "  continues along {}: {how} = {}{roulette}; β = {}",
                        vector(direction),
                        colour(weight),
                        colour(after)
                    ),
                );
            }
            if let Some(ends) = &vertex.ends {
                lines.push("", format!("  the path ends: {ends}"));
            }
        }
        lines.push(
            "path",
            format!(
                "R = Σ β·ρ·D over the vertices = {} (π × radiance; averaged over samples it \
                 converges)",
                colour(self.r)
            ),
        );
    }

    /// D (equation 27) with its parts, and the shadow ray (§5.1), at one diffuse hit.
    fn terms_lines(&self, lines: &mut Lines, hit: &ShadedHit, indent: &str) {
        let t = &hit.terms;
        let rho = t.rho.unwrap_or(Vec3::NAN);
        let from = if t.textured {
            format!("the {} texture at the hit", hit.surface)
        } else {
            format!("the reflectance of {}", hit.surface)
        };
        match t.glossy {
            None => lines.push("§5", format!("{indent}ρ = {} ({from})", colour(rho))),
            Some(g) => lines.push(
                "§5",
                format!(
                    "{indent}ρ = π·f(toward the viewer, toward the light) = π·f_s + π·f_d = {} \
                     (highlight) + {} (diffuse base) = {} (the glossy {}, in place of the lab's \
                     ρ)",
                    colour(g.specular),
                    colour(g.diffuse),
                    colour(rho),
                    hit.surface
                ),
            ),
        }
        let (Some(r), Some(dist), Some(r2), Some(cos), Some(p), Some(area), Some(d)) = (
            t.to_light,
            t.light_distance,
            t.light_distance_squared,
            t.cos_theta,
            t.power,
            t.four_pi_r2,
            t.d,
        ) else {
            return;
        };
        lines.push(
            "eq. 27",
            format!(
                "{indent}r = light − point = {} − {} = {}, |r| = {} units, r̂·n̂ = {}",
                vector(self.light.position),
                vector(hit.position),
                vector(r),
                num(dist),
                num(cos)
            ),
        );
        let watts = if self.light.colour == Vec3::ONE {
            format!("{} W", num(self.light.power))
        } else {
            format!(
                "{} W × {} = {} W",
                num(self.light.power),
                colour(self.light.colour),
                colour(p)
            )
        };
        // Where the relief hides the light, the equation's own value first, then why it is 0.
        let falloff = t.falloff.unwrap_or(1.0);
        let d = if t.relief_shadowed {
            p * (falloff * cos.max(0.0)) / area
        } else {
            d
        };
        let cos_text = if cos > 0.0 {
            num(cos)
        } else {
            format!("max({}, 0)", num(cos))
        };
        let (formula, falloff_text) = match (t.falloff, self.light.spot()) {
            (Some(f), Some(spot)) => {
                let deg = |a: f32| num(crate::base::camera::degrees(a) as f32);
                let theta = deg(crate::shading::light::acos(
                    -r.normalize_or_zero().dot(spot.axis),
                ));
                let why = if f == 1.0 {
                    format!("θ = {theta}° within the beam, {}°: 1", deg(spot.beam))
                } else if f == 0.0 {
                    format!("θ = {theta}° beyond the cutoff, {}°: 0", deg(spot.cutoff))
                } else {
                    let (c, b) = (deg(spot.cutoff), deg(spot.beam));
                    format!("θ = {theta}°: ({c}° − θ)/({c}° − {b}°) = {}", num(f))
                };
                lines.push(
                    "spot",
                    format!("{indent}the spot's falloff at θ from its axis, {why}"),
                );
                ("P·falloff·max(r̂·n̂, 0)/(4πr²)", format!(" × {}", num(f)))
            }
            _ => ("P·max(r̂·n̂, 0)/(4πr²)", String::new()),
        };
        lines.push(
            "eq. 27",
            format!(
                "{indent}D = {formula} = {watts}{falloff_text} × {cos_text} / (4π × {} units² = \
                 {} units²) = {} W per unit area",
                num(r2),
                num(area),
                colour(d)
            ),
        );
        if t.light_behind_surface {
            lines.push(
                "eq. 27",
                format!(
                    "{indent}but the light is behind the surface itself (its own normal): D = 0"
                ),
            );
        }
        if t.relief_shadowed {
            lines.push(
                "§6",
                format!(
                    "{indent}but the surface's own relief hides the light (parallax \
                     self-shadowing: its height field rises between the point and the light): \
                     D = 0"
                ),
            );
        }
        if !self.shadows {
            return;
        }
        match &t.shadow_ray {
            None => lines.push(
                "§5.1",
                format!("{indent}no shadow ray: no light arrives to be blocked"),
            ),
            Some(ray) => {
                let toward = match self.light.kind {
                    LightKind::Sphere { radius } if radius > 0.0 => format!(
                        "a random point of the light's sphere (radius {}), along {}",
                        num(radius),
                        vector(ray.direction)
                    ),
                    LightKind::Quad { side } if side > 0.0 => format!(
                        "a random point of the light's square (side {}), along {}",
                        num(side),
                        vector(ray.direction)
                    ),
                    LightKind::Point
                    | LightKind::Sphere { .. }
                    | LightKind::Quad { .. }
                    | LightKind::Spot(_) => "the light".to_owned(),
                };
                let answer = if t.shadow_blocked {
                    match &t.blocker {
                        Some(b) => format!(
                            "blocked by triangle {} ({}) at {} units: in shadow, D counts as 0",
                            b.triangle,
                            b.surface,
                            num(b.distance)
                        ),
                        None => "blocked: in shadow, D counts as 0".to_owned(),
                    }
                } else {
                    "nothing in the way: D counts in full".to_owned()
                };
                lines.push(
                    "§5.1",
                    format!(
                        "{indent}shadow ray from {} toward {toward}, {} units long: {answer}",
                        vector(ray.origin),
                        num(ray.length)
                    ),
                );
            }
        }
    }

    /// The hit's value as its stage says, with the numbers; `lhs` names it ("R" when it is the
    /// pixel's value).
    fn value_line(&self, hit: &ShadedHit, lhs: &str) -> (&'static str, String) {
        let t = &hit.terms;
        let rho = colour(t.rho.unwrap_or(Vec3::NAN));
        let d = if t.shadow_blocked || t.light_behind_surface || t.relief_shadowed {
            Vec3::ZERO
        } else {
            t.d.unwrap_or(Vec3::ZERO)
        };
        let n = hit.n;
        let v = colour(hit.value);
        match self.stage {
            Stage::Flat => ("fig. 2", format!("{lhs} = ρ = {v}")),
            Stage::Incoming if n == Vec3::ZERO => ("eq. 27", format!("{lhs} = D = {v}")),
            Stage::Incoming => (
                "eq. 29",
                format!("{lhs} = T = D + N = {} + {} = {v}", colour(d), colour(n)),
            ),
            Stage::Path => ("eq. 28", format!("ρ·D = {rho} · {} = {v}", colour(d))),
            Stage::Direct | Stage::Shadows | Stage::Lab if n == Vec3::ZERO => (
                "eq. 28",
                format!("{lhs} = ρ·D = {rho} · {} = {v}", colour(d)),
            ),
            Stage::Direct | Stage::Shadows | Stage::Lab => (
                "eq. 30",
                format!(
                    "{lhs} = ρ·(D + N) = {rho} · ({} + {}) = {v}",
                    colour(d),
                    colour(n)
                ),
            ),
        }
    }
}

/// The equation a stage's pixel value is.
fn final_equation(stage: Stage, n: Vec3) -> &'static str {
    match stage {
        Stage::Flat => "fig. 2",
        Stage::Incoming if n == Vec3::ZERO => "eq. 27",
        Stage::Incoming => "eq. 29",
        Stage::Path => "path",
        Stage::Direct | Stage::Shadows | Stage::Lab if n == Vec3::ZERO => "eq. 28",
        Stage::Direct | Stage::Shadows | Stage::Lab => "eq. 30",
    }
}

/// Lines joined as [`Inspection::to_text`] joins them, one per line: the equation (padded to
/// the longest), then the text.
pub fn lines_text(lines: &[InspectLine]) -> String {
    let width = lines
        .iter()
        .map(|l| l.equation.chars().count())
        .max()
        .unwrap_or(0);
    let mut text = String::new();
    for line in lines {
        let pad = width - line.equation.chars().count();
        let _ = writeln!(text, "{}{}  {}", line.equation, " ".repeat(pad), line.text);
    }
    text
}

#[derive(Default)]
struct Lines(Vec<InspectLine>);

impl Lines {
    fn push(&mut self, equation: &str, text: String) {
        self.0.push(InspectLine {
            equation: equation.to_owned(),
            text,
        });
    }
}

/// A number as printed: three significant digits below 1, three decimals above (trailing
/// zeros dropped: 14, 0.5, 2.74), scientific notation when very small or large, 0 for zero.
pub(crate) fn num(x: f32) -> String {
    let a = x.abs();
    let text = if x == 0.0 {
        return "0".to_owned();
    } else if !x.is_finite() {
        return format!("{x}");
    } else if !(1e-3..1e5).contains(&a) {
        return format!("{x:.2e}");
    } else if a < 1.0 {
        // Three significant digits: 0.906, 0.0791, 0.00234.
        let decimals = 2 - a.log10().floor() as i32;
        format!("{x:.*}", decimals.clamp(2, 5) as usize)
    } else {
        format!("{x:.3}")
    };
    let trimmed = text.trim_end_matches('0').trim_end_matches('.');
    if trimmed == "-0" {
        "0".to_owned()
    } else {
        trimmed.to_owned()
    }
}

pub(crate) fn vector(v: Vec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// A colour: one number when its channels are equal (grey, as the lab's light is), else three.
fn colour(v: Vec3) -> String {
    if v.x == v.y && v.y == v.z {
        num(v.x)
    } else {
        vector(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::light::direct_light;
    use crate::shapes::scene::cornell_box;

    #[test]
    fn numbers_are_printed_short() {
        assert_eq!(num(14.0), "14");
        assert_eq!(num(2.74), "2.74");
        assert_eq!(num(0.906_183), "0.906");
        assert_eq!(num(0.368_454), "0.368");
        assert_eq!(num(0.078_6), "0.0786");
        assert_eq!(num(-0.5), "-0.5");
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(40.342_22), "40.342");
        assert_eq!(num(9.4e-4), "9.40e-4");
        assert_eq!(num(f32::NAN), "NaN");
        assert_eq!(colour(Vec3::splat(0.5)), "0.5");
        assert_eq!(colour(Vec3::new(0.75, 0.15, 0.15)), "(0.75, 0.15, 0.15)");
    }

    /// The display's lines: R's 8 bits through the display in force (×255 and rounded for the
    /// lab's; the sRGB curve's own), and with several samples, that R is sample 0's beside the
    /// value on screen with its 8 bits.
    #[test]
    fn the_display_lines_give_the_8_bits_shown() {
        let scene = cornell_box();
        let mut settings = RenderSettings::default();
        settings.camera = settings.camera.with_resolution(64, 64);
        let inspection = inspect_pixel(&scene, &settings, 20, 50).unwrap();
        let r = inspection.r;
        let lab = |v: f32| crate::transport::display::to_display_u8(v);
        let lines = inspection.display_lines(&settings.display, None);
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].equation, "on screen");
        let bits = format!("({}, {}, {})", lab(r.x), lab(r.y), lab(r.z));
        assert!(
            lines[0]
                .text
                .contains(&format!("shown as {bits} in 8 bits")),
            "{}",
            lines[0].text
        );
        let srgb = Display {
            transform: crate::transport::display::DisplayTransform::Srgb,
            exposure: 0.0,
        };
        let shown = ShownPixel {
            value: Vec3::new(0.25, 0.5, 0.75),
            samples: 16,
            denoised: false,
        };
        let lines = inspection.display_lines(&srgb, Some(shown));
        assert_eq!(lines.len(), 2);
        assert!(lines[0].text.starts_with("R above is sample 0's alone"));
        let [a, b, c] = srgb.encode(shown.value);
        assert_eq!((a, b, c), (137, 188, 225));
        assert_eq!(
            lines[1].text,
            "the pixel shown is the mean of its 16 samples (each through another point of the \
             pixel): (0.25, 0.5, 0.75), shown as (137, 188, 225) in 8 bits"
        );
        let denoised = ShownPixel {
            denoised: true,
            ..shown
        };
        let lines = inspection.display_lines(&srgb, Some(denoised));
        assert!(lines[1].text.contains("the denoised image's value"));
    }

    /// The parts of D at the lab's floor centre (0, 1, 0), by hand as in the integrator's
    /// test: r = (0, −1.5, −0.7), r² = 2.74, r̂·n̂ = 1.5/√2.74 = 0.906183,
    /// 4πr² = 34.431856, D = 14 × 0.906183 / 34.431856 = 0.368454, and the tracer's D exactly.
    #[test]
    fn the_parts_of_d_at_the_floor_centre() {
        let light = LightSpec::default();
        let (p, n) = (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
        let parts = DirectLight::at(&light, p, n);
        assert_eq!(parts.to_light, Vec3::new(0.0, -1.5, -0.7));
        assert!((parts.r2 - 2.74).abs() < 1e-6);
        assert!((parts.cos - 0.906_183).abs() < 1e-6);
        assert!((parts.four_pi_r2 - 34.431_856).abs() < 1e-4);
        assert!((parts.d.x - 0.368_454).abs() < 1e-6);
        assert_eq!(parts.d, direct_light(&light, p, n));
        // A light on the surface: the lab's guard, straight above at the least distance.
        let on = DirectLight::at(&light, light.position, n);
        assert_eq!(on.distance(), crate::shading::light::MIN_LIGHT_DISTANCE);
        assert_eq!(on.d, direct_light(&light, light.position, n));
    }

    /// The recorder sees the integrator's steps in order: one closest hit for the camera ray,
    /// then its terms.
    #[test]
    fn the_recording_follows_the_integrator() {
        let scene = cornell_box();
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(16, 16);
        let tracer = Tracer::new(&scene, &s);
        let (ray, rng, point, lens) = camera_sample_0(&tracer, &s, 8, 12);
        assert_eq!((point, lens), ([8.5, 12.5], None));
        let mut recording = Recording::default();
        let mut out = [Vec3::ZERO];
        tracer.trace_recorded(&[ray], &mut [rng], &mut out, &mut recording);
        let kinds: Vec<_> = recording
            .events
            .iter()
            .map(|e| match e {
                Event::Hit { .. } => "hit",
                Event::Specular { .. } => "specular",
                Event::Shaded { .. } => "shaded",
                Event::Scattered { .. } => "scattered",
                Event::Vertex(_) => "vertex",
            })
            .collect();
        assert_eq!(kinds, ["hit", "shaded"]);
        let Event::Shaded { value, weight, .. } = &recording.events[1] else {
            unreachable!()
        };
        assert_eq!((*value, *weight), (out[0], Vec3::ONE));
    }

    /// At the plastic tall block in the lab stage the inspector shows f's two parts: π·f_s
    /// (the coating's highlight) and π·f_d (the base) sum to the ρ the pixel was shaded
    /// with, R is the rendered pixel bit for bit, and where the light's highlight falls on the
    /// block's visible faces the coating adds at least a quarter of the base's red.
    #[test]
    fn the_inspector_shows_the_plastics_two_parts() {
        let scene = crate::shapes::scene::cornell_box();
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(48, 48);
        s.material_preset = crate::shading::material::MaterialPreset::Plastic;
        s.roughness = 0.1;
        let (mut on_block, mut highlight) = (0, 0);
        for y in 0..48 {
            for x in 0..48 {
                let i = inspect_pixel(&scene, &s, x, y).unwrap();
                let rendered = crate::transport::render::trace_pixel(&scene, &s, x, y, 0);
                assert_eq!(
                    i.r.to_array().map(f32::to_bits),
                    rendered.to_array().map(f32::to_bits)
                );
                let Some(g) = i.terms.glossy else { continue };
                assert_eq!(i.surface.as_deref(), Some("blue"));
                on_block += 1;
                let rho = i.terms.rho.unwrap();
                let sum = g.specular + g.diffuse;
                assert!(
                    (sum - rho).abs().max_element() <= 1e-5 * rho.max_element(),
                    "{g:?} {rho}"
                );
                // The coating is white, the base the block's blue.
                assert_eq!(g.specular.x, g.specular.z);
                assert!(g.diffuse.z >= 4.0 * g.diffuse.x);
                if g.specular.x > 0.25 * g.diffuse.x {
                    highlight += 1;
                    let text: Vec<String> = i.lines().into_iter().map(|l| l.text).collect();
                    assert!(text.iter().any(|l| l.contains("π·f_s + π·f_d")), "{text:?}");
                }
            }
        }
        assert!(on_block > 20 && highlight > 0, "{on_block} {highlight}");
    }

    /// Under the quad light every vertex runs the single path's steps, and the inspector shows each
    /// vertex's light sample with the BSDF's value, both densities and the MIS weight; R is
    /// still the rendered pixel bit for bit. The weight is the power heuristic of the two
    /// densities shown, p_L²/(p_L² + p_B²), computed here in f64 (within 1e-6: f32 rounding
    /// of the same formula); the balance heuristic p_L/(p_L + p_B), or no weight (1), differ
    /// from it wherever p_B > 0, so some vertices must have both densities well apart from 0
    /// and from each other's extremes (a weight in (0.05, 0.95)).
    #[test]
    fn a_path_vertex_under_an_area_light_shows_its_mis_weight() {
        let scene = crate::shapes::scene::cornell_box();
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(32, 32);
        s.shading = crate::transport::integrator::Shading::for_stage(Stage::Path);
        s.light.position = Vec3::new(0.0, -0.98, 0.0);
        // A square of side 1.5: large enough that, at vertices near it, BSDF samples find it
        // as readily as light samples do (at a side of 0.5 no weight of these pixels was within (0.05, 0.95)).
        s.light.kind = LightKind::Quad { side: 1.5 };
        s.material_preset = crate::shading::material::MaterialPreset::Rough;
        let (mut seen, mut shared) = (0, 0);
        // Every fourth pixel each way: the vertices of a few paths may all be far from or
        // near the light.
        for (x, y) in (0..64).map(|k| (1 + 4 * (k % 8), 1 + 4 * (k / 8))) {
            let i = inspect_pixel(&scene, &s, x, y).unwrap();
            let rendered = crate::transport::render::trace_pixel(&scene, &s, x, y, 0);
            assert_eq!(
                i.r.to_array().map(f32::to_bits),
                rendered.to_array().map(f32::to_bits)
            );
            // Every vertex below the light samples it (the ceiling, above it, cannot).
            for v in i.bounces.iter().filter(|v| v.position.y > -0.98) {
                let l = v.light_sample.expect("a vertex below the light samples it");
                assert!(l.pdf_light > 0.0, "{l:?}");
                let (p_l, p_b) = (f64::from(l.pdf_light), f64::from(l.pdf_bsdf));
                let power = p_l * p_l / (p_l * p_l + p_b * p_b);
                assert!(
                    (f64::from(l.mis_weight) - power).abs() < 1e-6,
                    "{l:?}: the power heuristic is {power}"
                );
                seen += 1;
                shared += usize::from((0.05..0.95).contains(&power));
            }
            let text: Vec<String> = i.lines().into_iter().map(|l| l.text).collect();
            // A vertex that sampled the light shows its weight (a path may see only the
            // ceiling, above the light, and end on the light's back).
            if i.bounces.iter().any(|v| v.light_sample.is_some()) {
                assert!(text.iter().any(|l| l.contains("MIS weight")), "{text:?}");
            }
        }
        assert!(seen > 0);
        assert!(
            shared > 0,
            "no vertex where the two strategies share the light"
        );
    }
}
