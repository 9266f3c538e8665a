//! The parts of an [`Inspection`]: the lab's terms at a shaded hit, the shadow ray and what
//! blocks it, the mirror and glass steps, the path's vertices.

use glam::Vec3;
use serde::Serialize;

use crate::shading::light::DirectLight;
use crate::shading::material::Material;
use crate::transport::integrator::{HitTerms, Stage, Tracer};

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

impl LightTerms {
    /// The terms of a hit as the tracer left them, with the parts of D and the blocker.
    pub(super) fn of(
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
