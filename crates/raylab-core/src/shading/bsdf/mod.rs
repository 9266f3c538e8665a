//! BSDFs: how a surface scatters light, written in a local shading frame in the style of
//! pbrt-v4's `BxDF` (Pharr, Jakob and Humphreys, *Physically Based Rendering*, 4th ed., ch. 9).
//!
//! # Conventions
//!
//! * **Local frame.** [`Bsdf`] works in a frame whose z axis is the shading normal ([`Frame`]):
//!   cos θ of a direction is its z component. [`ShadingFrame`] takes world directions there and
//!   back and applies the rules about the geometric normal.
//! * **Directions.** `wo` and `wi` are unit vectors pointing *away* from the surface: `wo`
//!   towards the viewer (where the path came from), `wi` towards where light arrives from. A
//!   camera ray's direction `d` gives `wo = −d`.
//! * **Units.** [`Bsdf::eval`] is the physical BSDF f(wo, wi) in 1/sr, so that the reflected
//!   radiance is L_o = ∫ f(wo, wi) L_i(wi) |cos θ_i| dω_i. raylab's images are in π × radiance
//!   (see [`crate::transport::integrator`]); that factor scales the radiance, not f, and cancels out of
//!   every sample weight f·|cos θ_i|/pdf.
//! * **pdf.** [`Bsdf::pdf`] is the solid-angle density (1/sr) with which [`Bsdf::sample`]
//!   draws `wi`. Delta lobes (the mirror, the smooth glass) have no density: `eval` and `pdf`
//!   return 0 for them, and the [`BsdfSample::pdf`] of a delta sample is the *discrete*
//!   probability of the lobe chosen (1 for the mirror, F or 1 − F for the glass); its
//!   [`BsdfSample::weight`] is the delta lobe's f·|cos θ_i|/pdf worked out analytically.
//! * **Transport.** Paths start at the camera. Light refracted into a medium of higher index
//!   is squeezed into a smaller solid angle, and its radiance grows by (η_t/η_i)² (pbrt-v4
//!   §9.5.2); importance does not. raylab leaves the factor out, as [`crate::shading::material`] always
//!   has: for a closed glass object lit from outside every path that enters also leaves, and
//!   the factors η² and 1/η² cancel.
//!
//! # The geometric normal
//!
//! A shading normal (interpolated or bump-mapped) differs from the true, geometric one, and
//! the two can disagree about which side of the surface a direction is on. All the rules about
//! that live in [`ShadingFrame::new`] and the two world-space helpers,
//! [`ShadingFrame::eval_world`] and [`ShadingFrame::sample_world`]:
//!
//! 1. **Two-sided.** The geometric normal is flipped to the side `wo` is on, and the shading
//!    normal is flipped to the geometric normal's side (pbrt-v4's `FaceForward` of the shading
//!    normal towards the geometric one): the geometric normal decides the side. Which side
//!    that was is kept ([`ShadingFrame::front_face`]): glass hit from inside sees the index
//!    ratio inverted ([`ShadingFrame::oriented`]).
//! 2. **Bent.** If `wo` is then below the shading hemisphere (or within [`MIN_SHADING_COS`] of
//!    it), the shading normal is blended towards the geometric normal just enough that
//!    cos θ_o ≥ [`MIN_SHADING_COS`] (a lite form of the normal corrections of Keller et al.,
//!    "The Iray Light Transport Simulation and Rendering System", 2017, and Schüssler et al.,
//!    "Microfacet-based Normal Mapping for Robust Monte Carlo Path Tracing", 2017). Every BSDF
//!    then sees a `wo` strictly above its frame, as Mitsuba 3's one-sided BSDFs require.
//! 3. **The geometric side decides reflection.** A `wi` on the other side of the *geometric*
//!    surface from `wo` is transmission, one on the same side reflection (pbrt-v3's `BSDF::f`;
//!    Veach's thesis, 1997, §5.3). Where the shading frame disagrees with that, the BSDF gives
//!    zero: reflection-only BSDFs give nothing below the geometric surface (no light leaks
//!    through it), and a transmitted direction must actually cross it.
//!
//! Rule 3 is the conservative choice: a direction above the geometric surface but below the
//! shading one gets nothing, so a strongly bent normal darkens slightly near its terminator
//! rather than leaking light.
//!
//! # Files
//!
//! Each BSDF is a file with its `eval`, `pdf` and `sample` and its tests: [`lambertian`],
//! [`mirror`], [`glass`], [`conductor`], [`plastic`]; [`Bsdf`] dispatches to them. [`ggx`] is
//! the microfacet distribution the rough ones share, [`frame`] the frames (`Frame`,
//! `ShadingFrame`); the tests' shared helpers are in `checks`.

use glam::{Vec2, Vec3};

#[cfg(test)]
mod checks;
mod conductor;
mod frame;
mod ggx;
mod glass;
mod lambertian;
mod mirror;
mod plastic;

pub use frame::{Frame, MIN_SHADING_COS, ShadingFrame};
pub use ggx::{Ggx, MIN_ALPHA};
pub use glass::{fresnel_dielectric, snell_cos_t};
pub use plastic::{Coating, PlasticParts, RoughPlastic};

/// The mirror direction of `direction` about the plane with normal `normal` (either side):
/// `d − 2 (d·n) n`. The angle to the normal is kept exactly up to rounding.
///
/// For an incoming ray direction `d` this is the reflected ray; in the BSDF convention, where
/// `wo` points away, the reflected `wi` is `reflect(−wo, n)` ([`reflect_local`] in the local
/// frame).
#[inline(always)]
pub fn reflect(direction: Vec3, normal: Vec3) -> Vec3 {
    direction - 2.0 * direction.dot(normal) * normal
}

/// The mirror reflection of `wo` about the local frame's normal (z): `(−x, −y, z)`, pbrt's
/// `Reflect(wo, n) = −wo + 2 (wo·n) n` with n = z, exact.
#[inline(always)]
pub fn reflect_local(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// One direction drawn by [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction, unit: local from [`Bsdf::sample`], world from
    /// [`ShadingFrame::sample_world`] (as pbrt-v4's `BxDF` and `BSDF` return theirs).
    pub wi: Vec3,
    /// What the sample multiplies a path's throughput by: f(wo, wi)·|cos θ_i| / pdf for a
    /// lobe with a density, the delta lobe's equivalent for a delta sample.
    pub weight: Vec3,
    /// The solid-angle density of `wi` (1/sr); for a delta lobe, the discrete probability that
    /// this lobe was chosen.
    pub pdf: f32,
    /// Whether `wi` comes from a delta lobe (a mirror or smooth glass): then no other
    /// technique could have produced it, and multiple importance sampling must not weigh it.
    pub is_delta: bool,
}

/// A surface's scattering at a point, in the local frame (z = shading normal): the
/// integrators evaluate and sample it there, through a [`ShadingFrame`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// The lab's ideal diffuse surface: f = ρ/π for `wi` on the side of `wo`.
    Lambertian {
        /// ρ, the fraction of light reflected, per colour channel.
        rho: Vec3,
    },
    /// An ideal mirror reflecting `tint` of the light.
    Mirror {
        /// The fraction reflected, per colour channel.
        tint: Vec3,
    },
    /// A smooth dielectric interface with the exact Fresnel equations; the outside (where the
    /// normal points) has index 1.
    Glass {
        /// The index of refraction inside.
        ior: f32,
        /// The transmitted fraction, per colour channel (reflection is untinted).
        tint: Vec3,
    },
    /// A rough metal: isotropic GGX microfacets with Smith's separable masking-shadowing and
    /// Fresnel = 1, reflecting `tint`.
    RoughConductor {
        /// The GGX α (the distribution's width parameter itself, not squared or remapped:
        /// α = 0.2 is the α in D(h) below). Clamped to at least [`MIN_ALPHA`].
        alpha: f32,
        /// The specular reflectance, per colour channel.
        tint: Vec3,
    },
    /// A glossy plastic, a diffuse base under a rough dielectric coating: Mitsuba 3's
    /// `roughplastic` ([`RoughPlastic`]).
    Plastic(RoughPlastic),
}

/// Whether two local directions are strictly on the same side of the surface.
#[inline(always)]
fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// `v` mirrored through the surface plane: (x, y, −z).
#[inline(always)]
fn flip_z(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

/// The pair (wo, wi) mirrored through the surface plane if `wo` is below it, so that a
/// one-sided model (defined for wo.z > 0, as Mitsuba 3's BSDFs are) serves both sides; the
/// flag says whether it was mirrored, to mirror a sampled `wi` back.
#[inline(always)]
fn to_upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3, bool) {
    if wo.z < 0.0 {
        (flip_z(wo), flip_z(wi), true)
    } else {
        (wo, wi, false)
    }
}

/// A sample of a one-sided model (defined for wo.z > 0) for any `wo`: `sample` draws for `wo`
/// mirrored above the surface ([`to_upper`]), and its `wi` is mirrored back.
#[inline(always)]
fn sample_above(wo: Vec3, sample: impl FnOnce(Vec3) -> Option<BsdfSample>) -> Option<BsdfSample> {
    let (wo, _, flipped) = to_upper(wo, Vec3::ZERO);
    let s = sample(wo)?;
    Some(BsdfSample {
        wi: if flipped { flip_z(s.wi) } else { s.wi },
        ..s
    })
}

impl Bsdf {
    /// Whether every direction this BSDF scatters into comes from a delta lobe (then
    /// [`Bsdf::eval`] and [`Bsdf::pdf`] are 0 everywhere and only [`Bsdf::sample`] says
    /// anything).
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror { .. } | Bsdf::Glass { .. })
    }

    /// The BSDF f(wo, wi) in 1/sr, local frame, both directions unit and pointing away from
    /// the surface; 0 for delta lobes. Each BSDF's file gives its formula; the rough
    /// conductor and the plastic are one-sided models, given the pair mirrored above the
    /// surface when `wo` is below it.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Bsdf::Lambertian { rho } => lambertian::eval(rho, wo, wi),
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => Vec3::ZERO,
            Bsdf::RoughConductor { alpha, tint } => {
                let (wo, wi, _) = to_upper(wo, wi);
                conductor::eval(alpha, tint, wo, wi)
            }
            Bsdf::Plastic(plastic) => {
                let (wo, wi, _) = to_upper(wo, wi);
                plastic.eval(wo, wi)
            }
        }
    }

    /// The solid-angle density (1/sr) with which [`Bsdf::sample`] draws `wi` given `wo`; 0
    /// for delta lobes and for directions `sample` never returns.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Lambertian { .. } => lambertian::pdf(wo, wi),
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => 0.0,
            Bsdf::RoughConductor { alpha, .. } => {
                let (wo, wi, _) = to_upper(wo, wi);
                conductor::pdf(alpha, wo, wi)
            }
            Bsdf::Plastic(plastic) => {
                let (wo, wi, _) = to_upper(wo, wi);
                plastic.pdf(wo, wi)
            }
        }
    }

    /// Draws an incident direction `wi` (local) for `wo` from the uniform numbers `uc` (which
    /// lobe: the glass's and the plastic's) and `u` (where in it), both in [0, 1). `None` when
    /// there is nothing to sample (wo in the surface plane, or a microfacet reflection that
    /// would leave below the horizon).
    ///
    /// The glass's delta lobes are f_r = F·δ(wi − R(wo))/|cos θ_i| and
    /// f_t = (1 − F)·tint·δ(wi − T(wo))/|cos θ_i|, so each weight f·|cos θ_i|/pdf is 1 or tint
    /// and their expectation F + (1 − F)·tint is the Whitted branches' sum. These are
    /// [`crate::shading::material`]'s `Material::sample` physics, in the local frame.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        match *self {
            Bsdf::Lambertian { rho } => lambertian::sample(rho, wo, u),
            Bsdf::Mirror { tint } => Some(mirror::sample(tint, wo)),
            Bsdf::Glass { ior, tint } => Some(glass::sample(wo, ior, tint, uc)),
            Bsdf::RoughConductor { alpha, tint } => {
                sample_above(wo, |wo| conductor::sample(alpha, tint, wo, u))
            }
            Bsdf::Plastic(plastic) => sample_above(wo, |wo| plastic.sample(wo, uc, u)),
        }
    }
}
