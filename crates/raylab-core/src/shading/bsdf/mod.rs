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

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};

use crate::base::sampling::{concentric_disk, cosine_hemisphere, orthonormal_basis};

mod plastic;
pub use plastic::{Coating, PlasticParts, RoughPlastic};

/// The smallest cos θ_o a [`ShadingFrame`] leaves between `wo` and its shading normal: a bent
/// normal keeps `wo` at least this far above the shading hemisphere (about 0.06° from
/// grazing), so BSDFs never see `wo` on or below their horizon.
pub const MIN_SHADING_COS: f32 = 1e-3;

/// The smallest GGX α [`Ggx::new`] accepts. Below it D(h) = 1/(πα²) at the peak approaches
/// the f32 range and the lobe is narrower than float directions resolve; a smoother surface
/// is a [`Bsdf::Mirror`].
pub const MIN_ALPHA: f32 = 1e-4;

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

/// The fraction of unpolarised light a smooth dielectric interface reflects: the exact Fresnel
/// equations (as pbrt's `FrDielectric`), the mean of the s- and p-polarised reflectances,
///
/// r_∥ = (η cos θ_i − cos θ_t)/(η cos θ_i + cos θ_t), r_⊥ = (cos θ_i − η cos θ_t)/(cos θ_i +
/// η cos θ_t), F = (r_∥² + r_⊥²)/2, with sin²θ_t = sin²θ_i/η² (Snell).
///
/// `cos_i` is the cosine of the angle of incidence (≥ 0), `eta` the ratio of the index on the
/// far side to the index on the near side. Returns 1 past the critical angle (total internal
/// reflection).
#[inline(always)]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// An orthonormal, right-handed frame (s × t = n): the local coordinates a [`Bsdf`] works in,
/// with `n` as z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// The first tangent, local x.
    pub s: Vec3,
    /// The second tangent, local y.
    pub t: Vec3,
    /// The normal, local z.
    pub n: Vec3,
}

impl Frame {
    /// The frame around the unit normal `n`, its tangents from Duff et al.'s branchless basis
    /// ([`orthonormal_basis`]). The tangents' azimuth is arbitrary, which suits the isotropic
    /// BSDFs here.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let (s, t) = orthonormal_basis(n);
        Self { s, t, n }
    }

    /// `v` (world) in local coordinates: its dot products with s, t and n.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// `v` (local) in world coordinates: x·s + y·t + z·n. The inverse of [`Frame::to_local`]
    /// (the frame is orthonormal, so the inverse is the transpose).
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.s + v.y * self.t + v.z * self.n
    }
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

impl Bsdf {
    /// Whether every direction this BSDF scatters into comes from a delta lobe (then
    /// [`Bsdf::eval`] and [`Bsdf::pdf`] are 0 everywhere and only [`Bsdf::sample`] says
    /// anything).
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Bsdf::Mirror { .. } | Bsdf::Glass { .. })
    }

    /// The BSDF f(wo, wi) in 1/sr, local frame, both directions unit and pointing away from
    /// the surface; 0 for delta lobes.
    ///
    /// * Lambertian: ρ/π where wo and wi are on the same side, else 0.
    /// * RoughConductor (Walter et al., "Microfacet Models for Refraction through Rough
    ///   Surfaces", 2007, eq. 20 with F = 1): with h = normalize(wo + wi),
    ///   f = tint · D(h) · G1(wo) · G1(wi) / (4 cos θ_o cos θ_i) for wo and wi on the same
    ///   side, else 0 ([`Ggx`] for D and G1). This is Mitsuba 3's `roughconductor` with
    ///   `distribution="ggx"`, `material="none"`, whose `eval` returns this times cos θ_i.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Bsdf::Lambertian { rho } => {
                if same_hemisphere(wo, wi) {
                    rho * FRAC_1_PI
                } else {
                    Vec3::ZERO
                }
            }
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => Vec3::ZERO,
            Bsdf::RoughConductor { alpha, tint } => {
                let (wo, wi, _) = to_upper(wo, wi);
                if !(wo.z > 0.0 && wi.z > 0.0) {
                    return Vec3::ZERO;
                }
                let h = (wo + wi).normalize();
                let ggx = Ggx::new(alpha);
                tint * (ggx.d(h) * ggx.g1(wo) * ggx.g1(wi) / (4.0 * wo.z * wi.z))
            }
            Bsdf::Plastic(plastic) => {
                let (wo, wi, _) = to_upper(wo, wi);
                plastic.eval(wo, wi)
            }
        }
    }

    /// The solid-angle density (1/sr) with which [`Bsdf::sample`] draws `wi` given `wo`; 0
    /// for delta lobes and for directions `sample` never returns.
    ///
    /// * Lambertian: |cos θ_i|/π on the side of `wo`.
    /// * RoughConductor: the visible-normal density of h times the Jacobian of reflection,
    ///   dω_h/dω_i = 1/(4 |wo·h|) (Walter et al. 2007, eq. 14):
    ///   pdf = G1(wo)·|wo·h|·D(h)/cos θ_o · 1/(4 |wo·h|) = G1(wo)·D(h)/(4 cos θ_o), for `wi`
    ///   above the surface (Mitsuba 3's `roughconductor` with `sample_visible=true`). Over the
    ///   upper hemisphere this integrates to less than 1 by exactly the chance that the
    ///   mirror direction of a sampled normal falls below the horizon (then `sample` returns
    ///   `None`).
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Bsdf::Lambertian { .. } => {
                if same_hemisphere(wo, wi) {
                    wi.z.abs() * FRAC_1_PI
                } else {
                    0.0
                }
            }
            Bsdf::Mirror { .. } | Bsdf::Glass { .. } => 0.0,
            Bsdf::RoughConductor { alpha, .. } => {
                let (wo, wi, _) = to_upper(wo, wi);
                if !(wo.z > 0.0 && wi.z > 0.0) {
                    return 0.0;
                }
                let h = (wo + wi).normalize();
                let ggx = Ggx::new(alpha);
                ggx.g1(wo) * ggx.d(h) / (4.0 * wo.z)
            }
            Bsdf::Plastic(plastic) => {
                let (wo, wi, _) = to_upper(wo, wi);
                plastic.pdf(wo, wi)
            }
        }
    }

    /// Draws an incident direction `wi` (local) for `wo` from the uniform numbers `uc` (which
    /// lobe, used by the glass only) and `u` (where in it), both in [0, 1). `None` when there
    /// is nothing to sample (wo in the surface plane, or a microfacet reflection that would
    /// leave below the horizon).
    ///
    /// * Lambertian: cosine-weighted on the side of `wo` ([`cosine_hemisphere`], Malley's
    ///   method), pdf |cos θ_i|/π, weight (ρ/π)·|cos θ_i| / (|cos θ_i|/π) = ρ exactly.
    /// * Mirror: `wi` = [`reflect_local`]`(wo)`, weight `tint`, pdf 1, delta.
    /// * Glass: F = [`fresnel_dielectric`]`(|cos θ_o|, η)` with η = ior when `wo` is outside
    ///   (wo.z > 0) and 1/ior inside; with probability F (`uc < F`) the reflection with weight
    ///   1, else the refraction by Snell's law with weight `tint` (pdf F or 1 − F, delta).
    ///   The delta lobes are f_r = F·δ(wi − R(wo))/|cos θ_i| and
    ///   f_t = (1 − F)·tint·δ(wi − T(wo))/|cos θ_i|, so each weight f·|cos θ_i|/pdf is 1 or
    ///   tint and their expectation F + (1 − F)·tint is the Whitted branches' sum. These are
    ///   [`crate::shading::material`]'s `Material::sample` physics, in the local frame.
    /// * RoughConductor: a microfacet normal h from the distribution of normals visible from
    ///   `wo` ([`Ggx::sample_visible`], Heitz 2018), `wi` = wo reflected about h; weight
    ///   f·cos θ_i/pdf = tint·G1(wi), pdf as [`Bsdf::pdf`].
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        match *self {
            Bsdf::Lambertian { rho } => {
                if wo.z == 0.0 {
                    return None;
                }
                let mut wi = cosine_hemisphere(u.x, u.y);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                let pdf = wi.z.abs() * FRAC_1_PI;
                (pdf > 0.0).then_some(BsdfSample {
                    wi,
                    weight: rho,
                    pdf,
                    is_delta: false,
                })
            }
            Bsdf::Mirror { tint } => Some(BsdfSample {
                wi: reflect_local(wo),
                weight: tint,
                pdf: 1.0,
                is_delta: true,
            }),
            Bsdf::Glass { ior, tint } => Some(sample_glass(wo, ior, tint, uc)),
            Bsdf::RoughConductor { alpha, tint } => {
                let (wo, _, flipped) = to_upper(wo, Vec3::ZERO);
                if !(wo.z > 0.0) {
                    return None;
                }
                let ggx = Ggx::new(alpha);
                let h = ggx.sample_visible(wo, u);
                let wo_h = wo.dot(h);
                let wi = 2.0 * wo_h * h - wo;
                let pdf = ggx.g1(wo) * ggx.d(h) / (4.0 * wo.z);
                if !(wi.z > 0.0 && wo_h > 0.0 && pdf > 0.0 && pdf.is_finite()) {
                    return None;
                }
                Some(BsdfSample {
                    wi: if flipped { flip_z(wi) } else { wi },
                    weight: tint * ggx.g1(wi),
                    pdf,
                    is_delta: false,
                })
            }
            Bsdf::Plastic(plastic) => {
                let (wo, _, flipped) = to_upper(wo, Vec3::ZERO);
                let s = plastic.sample(wo, uc, u)?;
                Some(BsdfSample {
                    wi: if flipped { flip_z(s.wi) } else { s.wi },
                    ..s
                })
            }
        }
    }
}

/// Snell's law: cos θ_t = √(1 − sin²θ_i / η²) for light meeting a surface at cos θ_i, η the
/// far side's index over the near side's (0 past the critical angle, where Fresnel's F is 1
/// and nothing is refracted).
#[inline(always)]
pub fn snell_cos_t(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    (1.0 - sin2_t).max(0.0).sqrt()
}

/// [`Bsdf::sample`] for the glass: Fresnel's F picks reflection (`uc < F`) or refraction.
/// `wo.z > 0` is outside (η = ior, the far side's index over the near side's), `wo.z < 0`
/// inside (η = 1/ior); at wo.z = 0, F = 1.
#[inline(always)]
fn sample_glass(wo: Vec3, ior: f32, tint: Vec3, uc: f32) -> BsdfSample {
    let outside = wo.z > 0.0;
    let eta = if outside { ior } else { 1.0 / ior };
    let cos_i = wo.z.abs();
    let fresnel = fresnel_dielectric(cos_i, eta);
    if uc < fresnel {
        return BsdfSample {
            wi: reflect_local(wo),
            weight: Vec3::ONE,
            pdf: fresnel,
            is_delta: true,
        };
    }
    // Snell's law in vector form (pbrt's `Refract`): the tangential part shrinks by 1/η, the
    // normal part is cos θ_t on the far side.
    let cos_t = snell_cos_t(cos_i, eta);
    let z = if outside { -cos_t } else { cos_t };
    BsdfSample {
        wi: Vec3::new(-wo.x / eta, -wo.y / eta, z).normalize(),
        weight: tint,
        pdf: 1.0 - fresnel,
        is_delta: true,
    }
}

/// The isotropic GGX (Trowbridge–Reitz) microfacet distribution with Smith masking, in the
/// local frame (z = the macro-surface normal): the pieces of [`Bsdf::RoughConductor`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// The width α, GGX's own parameter used as given (not squared or remapped from a
    /// "roughness"): roughly the tangent of the angle the microfacet normals spread over
    /// (for small α, D(h) falls to half its peak at tan θ_h ≈ 0.64 α).
    pub alpha: f32,
}

impl Ggx {
    /// The distribution of width `alpha`, clamped to at least [`MIN_ALPHA`].
    #[inline]
    pub fn new(alpha: f32) -> Self {
        Self {
            alpha: alpha.max(MIN_ALPHA),
        }
    }

    /// The density of microfacet normals h per unit solid angle, normalised so that
    /// ∫ D(h) cos θ_h dω_h = 1 (Walter et al. 2007, eq. 33):
    ///
    /// D(h) = 1 / (π α² cos⁴θ_h (1 + tan²θ_h/α²)²) = 1 / (π α² ((h_x² + h_y²)/α² + h_z²)²),
    ///
    /// 0 for h at or below the horizon.
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        if !(h.z > 0.0) {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
        1.0 / (PI * a2 * t * t)
    }

    /// Smith's Λ for GGX (Heitz, "Understanding the Masking-Shadowing Function in
    /// Microfacet-Based BRDFs", 2014, eq. 72): Λ(v) = (−1 + √(1 + α² tan²θ_v))/2.
    #[inline]
    pub fn lambda(&self, v: Vec3) -> f32 {
        let z2 = v.z * v.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let a2_tan2 = self.alpha * self.alpha * (v.x * v.x + v.y * v.y) / z2;
        0.5 * ((1.0 + a2_tan2).sqrt() - 1.0)
    }

    /// Smith's masking function, the fraction of the microsurface seen from `v` that is not
    /// hidden by other microfacets: G1(v) = 1/(1 + Λ(v)) = 2/(1 + √(1 + α² tan²θ_v)). 1 at
    /// normal incidence, 0 at grazing. The masking-shadowing of a pair is the separable
    /// product G1(wo)·G1(wi).
    #[inline]
    pub fn g1(&self, v: Vec3) -> f32 {
        let z2 = v.z * v.z;
        if z2 == 0.0 {
            return 0.0;
        }
        let a2_tan2 = self.alpha * self.alpha * (v.x * v.x + v.y * v.y) / z2;
        2.0 / (1.0 + (1.0 + a2_tan2).sqrt())
    }

    /// The density of the normals visible from `v` (Heitz 2018, eq. 3):
    /// D_v(h) = G1(v)·max(0, v·h)·D(h)/cos θ_v, a normalised density over h (v above the
    /// surface).
    #[inline]
    pub fn visible_pdf(&self, v: Vec3, h: Vec3) -> f32 {
        if !(v.z > 0.0) {
            return 0.0;
        }
        self.g1(v) * v.dot(h).max(0.0) * self.d(h) / v.z
    }

    /// A microfacet normal drawn with density [`Ggx::visible_pdf`] for `v` (above the
    /// surface), from two uniform numbers: Heitz, "Sampling the GGX Distribution of Visible
    /// Normals", JCGT 7(4), 2018. Stretch `v` to the configuration where α = 1 (where the
    /// microsurface is a hemisphere), sample a point uniformly on the disk the hemisphere
    /// projects to seen from `v` (the concentric map, [`concentric_disk`], warped towards the
    /// visible half), lift it onto the hemisphere and unstretch the normal there.
    #[inline]
    pub fn sample_visible(&self, v: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha;
        // Section 3.2: the view direction in the hemisphere configuration.
        let vh = Vec3::new(a * v.x, a * v.y, v.z).normalize();
        // Section 4.1: a basis around it (any tangent at normal incidence).
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // Section 4.2: a uniform point on the projected disk, its lower half squeezed into the
        // visible part of the ellipse.
        let p = concentric_disk(u.x, u.y);
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p.x * p.x).max(0.0).sqrt() + s * p.y;
        // Section 4.3: back onto the hemisphere.
        let nh = p.x * t1 + p2 * t2 + (1.0 - p.x * p.x - p2 * p2).max(0.0).sqrt() * vh;
        // Section 3.4: the normal in the ellipsoid configuration.
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(0.0)).normalize()
    }
}

/// The shading frame at a hit, with the geometric normal's rules (see the module's
/// documentation): built once per hit by [`ShadingFrame::new`], the one place those rules
/// live.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingFrame {
    /// The shading frame, its normal on the side of `wo` and bent so that cos θ_o ≥
    /// [`MIN_SHADING_COS`] where possible.
    frame: Frame,
    /// The geometric normal, flipped to the side of `wo`.
    geometric: Vec3,
    /// Whether `wo` was on the side the geometric normal as given points to (outside a glass
    /// object whose normals point out).
    front: bool,
}

impl ShadingFrame {
    /// The frame for a hit with unit `geometric_normal` (either orientation), a
    /// `shading_normal` (normalised here; zero or not finite means "none", the geometric one)
    /// and `wo_world` (unit, pointing away from the surface):
    ///
    /// 1. the geometric normal n_g is flipped to the side of `wo`, the shading normal n_s to
    ///    the side of n_g: the geometric normal decides the side;
    /// 2. if a = wo·n_s < ε = [`MIN_SHADING_COS`], n_s is blended towards n_g:
    ///    n_s ← normalize(n_s + t (n_g − n_s)) with t = (ε − a)/(b − a), b = wo·n_g. Then
    ///    wo·(n_s + t (n_g − n_s)) = ε, and since a blend of two unit vectors is at most unit
    ///    long, wo·n_s ≥ ε after normalising. The normal stays in the plane of the two and
    ///    moves no further than needed; if wo is itself within ε of the geometric surface
    ///    (b ≤ ε), n_s becomes n_g.
    ///
    /// Blending towards n_g, rather than rotating towards wo, keeps the mirror direction of a
    /// nearly grazing wo above the geometric surface.
    #[inline]
    pub fn new(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> ShadingFrame {
        let (ns, ng, front) = Self::normals(shading_normal, geometric_normal, wo_world);
        ShadingFrame {
            frame: Frame::from_normal(ns),
            geometric: ng,
            front,
        }
    }

    /// The shading normal [`ShadingFrame::new`] would use (rules 1 and 2: on the geometric
    /// side of `wo`, bent so that cos θ_o ≥ [`MIN_SHADING_COS`]), turned back to the side of
    /// `geometric_normal` as given. For a normal map's perturbed normal, which the lab's
    /// stages light by its cosine (equation 27) without a frame: the same rules, so the tilt
    /// never turns the normal away from the viewer (no black patches) nor across the surface
    /// it is measured against ([`crate::transport::integrator::Tracer::surface_with`]).
    #[inline]
    pub fn bent_normal(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> Vec3 {
        let (ns, _, front) = Self::normals(shading_normal, geometric_normal, wo_world);
        if front { ns } else { -ns }
    }

    /// The shading normal [`ShadingFrame::new`] would use (rules 1 and 2), on the side of
    /// `wo`: the normal a viewer from `wo` sees the surface with, as the denoiser's features
    /// record it ([`crate::transport::film::Seen`]).
    #[inline]
    pub fn seen_normal(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> Vec3 {
        Self::normals(shading_normal, geometric_normal, wo_world).0
    }

    /// Rules 1 and 2 of [`ShadingFrame::new`]: the shading normal and the geometric normal on
    /// the side of `wo`, the first bent, and whether `wo` is on the geometric normal's side.
    #[inline(always)]
    fn normals(shading_normal: Vec3, geometric_normal: Vec3, wo_world: Vec3) -> (Vec3, Vec3, bool) {
        let front = wo_world.dot(geometric_normal) > 0.0;
        let ng = if front {
            geometric_normal
        } else {
            -geometric_normal
        };
        let ns = shading_normal.normalize_or_zero();
        let mut ns = if ns == Vec3::ZERO {
            ng
        } else if ns.dot(ng) < 0.0 {
            -ns
        } else {
            ns
        };
        let a = wo_world.dot(ns);
        if a < MIN_SHADING_COS {
            let b = wo_world.dot(ng);
            ns = if b > MIN_SHADING_COS {
                let t = (MIN_SHADING_COS - a) / (b - a);
                (ns + t * (ng - ns)).normalize()
            } else {
                ng
            };
        }
        (ns, ng, front)
    }

    /// The (bent) shading frame: its normal is local z for the BSDFs.
    #[inline]
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// The shading normal as used, on the side of `wo`.
    #[inline]
    pub fn shading_normal(&self) -> Vec3 {
        self.frame.n
    }

    /// The geometric normal, flipped to the side of `wo`.
    #[inline]
    pub fn geometric_normal(&self) -> Vec3 {
        self.geometric
    }

    /// Whether `wo` is on the side the geometric normal as given points to: for glass whose
    /// normals point out, whether the path arrives from outside.
    #[inline]
    pub fn front_face(&self) -> bool {
        self.front
    }

    /// A world direction in the shading frame's local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        self.frame.to_local(v)
    }

    /// A local direction in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.frame.to_world(v)
    }

    /// Whether `wi_world` is on the same side of the *geometric* surface as `wo_world`:
    /// reflection if so, transmission if not (rule 3 of the module's documentation). A
    /// direction in the geometric plane counts as neither.
    #[inline]
    pub fn reflects(&self, wo_world: Vec3, wi_world: Vec3) -> bool {
        wo_world.dot(self.geometric) * wi_world.dot(self.geometric) > 0.0
    }

    /// `bsdf` as seen from the side of `wo`: the frame's normal always points to `wo`, so for
    /// a glass hit from inside (not [`ShadingFrame::front_face`]) the index ratio is inverted,
    /// ior → 1/ior; every other BSDF is two-sided and unchanged.
    #[inline]
    pub fn oriented(&self, bsdf: &Bsdf) -> Bsdf {
        match *bsdf {
            Bsdf::Glass { ior, tint } if !self.front => Bsdf::Glass {
                ior: 1.0 / ior,
                tint,
            },
            other => other,
        }
    }

    /// Whether the shading frame agrees with the geometric surface about `wi`: both call it
    /// reflection or both transmission.
    #[inline(always)]
    fn consistent(&self, wo_world: Vec3, wi_world: Vec3, wo_local: Vec3, wi_local: Vec3) -> bool {
        self.reflects(wo_world, wi_world) == same_hemisphere(wo_local, wi_local)
    }

    /// f(wo, wi) and the pdf with which [`ShadingFrame::sample_world`] draws `wi`, for world
    /// directions (unit, pointing away): the BSDF in the shading frame where the geometric
    /// surface and the shading frame agree whether `wi` is reflection or transmission, and
    /// `(0, 0)` where they disagree, so reflection-only BSDFs give nothing across the
    /// geometric surface and transmission must cross it.
    #[inline]
    pub fn eval_world(&self, bsdf: &Bsdf, wo_world: Vec3, wi_world: Vec3) -> (Vec3, f32) {
        let bsdf = self.oriented(bsdf);
        let wo = self.to_local(wo_world);
        let wi = self.to_local(wi_world);
        if !self.consistent(wo_world, wi_world, wo, wi) {
            return (Vec3::ZERO, 0.0);
        }
        (bsdf.eval(wo, wi), bsdf.pdf(wo, wi))
    }

    /// [`Bsdf::sample`] for a world `wo_world`, the sample's `wi` in world coordinates.
    /// `None` also where the sampled direction breaks rule 3 (a reflection below the
    /// geometric surface or a refraction that does not cross it): that light is absorbed, as
    /// [`ShadingFrame::eval_world`] gives it zero.
    #[inline]
    pub fn sample_world(
        &self,
        bsdf: &Bsdf,
        wo_world: Vec3,
        uc: f32,
        u: Vec2,
    ) -> Option<BsdfSample> {
        let bsdf = self.oriented(bsdf);
        let wo = self.to_local(wo_world);
        let s = bsdf.sample(wo, uc, u)?;
        let wi_world = self.to_world(s.wi);
        self.consistent(wo_world, wi_world, wo, s.wi)
            .then_some(BsdfSample { wi: wi_world, ..s })
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{FRAC_PI_2 as FRAC_PI_2_F64, TAU as TAU_F64};

    use super::*;
    use crate::base::sampling::{Rng, uniform_hemisphere};

    /// The unit direction at polar angle `theta` and azimuth `phi` (radians), local frame.
    pub(super) fn dir(theta: f32, phi: f32) -> Vec3 {
        let (sin_t, cos_t) = theta.sin_cos();
        let (sin_p, cos_p) = phi.sin_cos();
        Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
    }

    /// [`dir`] from angles in f64 (the quadratures' grids).
    fn dir64(theta: f64, phi: f64) -> Vec3 {
        dir(theta as f32, phi as f32)
    }

    /// Two uniform numbers for [`Bsdf::sample`]'s `u`.
    pub(super) fn u2(rng: &mut Rng) -> Vec2 {
        Vec2::new(rng.next_f32(), rng.next_f32())
    }

    /// A rough conductor reflecting everything (the white furnace's).
    fn rough(alpha: f32) -> Bsdf {
        Bsdf::RoughConductor {
            alpha,
            tint: Vec3::ONE,
        }
    }

    /// A colour with three different channels, to catch a channel mixed up.
    const COLOUR: Vec3 = Vec3::new(0.9, 0.6, 0.3);

    /// Whether `a` and `b` agree to `rel` relative to the larger (and 1e-12 absolute).
    pub(super) fn close(a: f32, b: f32, rel: f32) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-12
    }

    /// Whether every channel of `a` and `b` agrees to `rel` ([`close`]).
    pub(super) fn close3(a: Vec3, b: Vec3, rel: f32) -> bool {
        (0..3).all(|i| close(a[i], b[i], rel))
    }

    /// Reciprocity (Helmholtz): f(wo, wi) = f(wi, wo) for 20,000 random pairs a BSDF, a
    /// quarter of them on opposite sides (f = 0 both ways) and a quarter both below (the
    /// two-sided mirror image), to 1e-6 relative. Most pairs must be nonzero.
    #[test]
    fn lambertian_and_rough_conductor_are_reciprocal() {
        let mut rng = Rng::new(1);
        let bsdfs = [
            Bsdf::Lambertian { rho: COLOUR },
            Bsdf::RoughConductor {
                alpha: 0.05,
                tint: COLOUR,
            },
            Bsdf::RoughConductor {
                alpha: 0.2,
                tint: COLOUR,
            },
            Bsdf::RoughConductor {
                alpha: 0.5,
                tint: COLOUR,
            },
            Bsdf::RoughConductor {
                alpha: 1.0,
                tint: COLOUR,
            },
        ];
        for bsdf in bsdfs {
            let mut nonzero = 0;
            for k in 0..20_000 {
                let mut wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
                let mut wi = uniform_hemisphere(rng.next_f32(), rng.next_f32());
                match k % 4 {
                    0 => wi = flip_z(wi),
                    1 => (wo, wi) = (flip_z(wo), flip_z(wi)),
                    _ => {}
                }
                let (there, back) = (bsdf.eval(wo, wi), bsdf.eval(wi, wo));
                assert!(
                    close3(there, back, 1e-6),
                    "{bsdf:?} {wo} {wi}: {there} vs {back}"
                );
                assert!(there.is_finite() && there.min_element() >= 0.0);
                if k % 4 == 0 {
                    assert_eq!(there, Vec3::ZERO, "opposite sides");
                } else if there.max_element() > 0.0 {
                    nonzero += 1;
                }
            }
            assert!(nonzero > 14_000, "{bsdf:?}: {nonzero}");
        }
        // The Lambertian's value itself: ρ/π.
        let f = Bsdf::Lambertian { rho: COLOUR }.eval(dir(0.3, 0.0), dir(1.0, 2.0));
        assert!(close3(f, COLOUR / std::f32::consts::PI, 1e-7));
    }

    /// The 0.999 quantile of χ² with `k` degrees of freedom by Wilson and Hilferty's cube-root
    /// approximation (1931): χ²_p ≈ k (1 − 2/(9k) + z_p √(2/(9k)))³ with z_0.999 = 3.090232,
    /// the standard normal's 0.999 quantile. For k = 19 it gives 43.95 (exact 43.82), for
    /// k = 99 148.29 (exact 148.23).
    fn chi_square_quantile_999(k: usize) -> f64 {
        let k = k as f64;
        let c = 2.0 / (9.0 * k);
        k * (1.0 - c + 3.090_232 * c.sqrt()).powi(3)
    }

    /// Pearson's statistic Σ (O − E)²/E over `cells` of (expected, observed) counts, with the
    /// cells expected fewer than 5 pooled, smallest first, until each pool expects at least 5
    /// (as Nori's χ² test does); returns it and its degrees of freedom (cells − 1). A cell
    /// observed but expected exactly 0 fails at once.
    fn chi_square(mut cells: Vec<(f64, f64)>) -> (f64, usize) {
        for &(e, o) in &cells {
            assert!(
                !(e <= 0.0 && o > 0.0),
                "{o} samples where none were expected"
            );
        }
        cells.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut statistic, mut n) = (0.0, 0);
        let (mut pool_e, mut pool_o) = (0.0, 0.0);
        for (e, o) in cells {
            pool_e += e;
            pool_o += o;
            if pool_e >= 5.0 {
                statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                n += 1;
                (pool_e, pool_o) = (0.0, 0.0);
            }
        }
        if pool_e > 0.0 {
            statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
            n += 1;
        }
        (statistic, n - 1)
    }

    /// Nori-style χ² test of [`Bsdf::sample`] against [`Bsdf::pdf`] for `wo`: 200,000
    /// samples into 10 θ bins over wo's hemisphere × 20 φ bins, plus one cell for the samples
    /// refused (`None`). A bin's expected count is N × the pdf integrated over it by a 24 × 24
    /// midpoint rule in (θ, φ) with dω = sin θ dθ dφ; the refusals' is N × (1 − the sum).
    /// The statistic must be below the 0.999 quantile ([`chi_square_quantile_999`]).
    pub(super) fn assert_sampling_matches_pdf(bsdf: Bsdf, wo: Vec3, seed: u64) {
        const THETA: usize = 10;
        const PHI: usize = 20;
        const SUB: usize = 24;
        const N: usize = 200_000;
        let below = wo.z < 0.0;
        let mut observed = vec![0.0f64; THETA * PHI + 1];
        let mut rng = Rng::new(seed);
        for _ in 0..N {
            let uc = rng.next_f32();
            match bsdf.sample(wo, uc, u2(&mut rng)) {
                None => observed[THETA * PHI] += 1.0,
                Some(s) => {
                    assert!(!s.is_delta && s.pdf > 0.0);
                    assert!((s.wi.length() - 1.0).abs() < 1e-4, "{}", s.wi);
                    assert!(s.wi.z * wo.z > 0.0, "on the side of wo: {}", s.wi);
                    let w = if below { flip_z(s.wi) } else { s.wi };
                    let theta = f64::from(w.z.clamp(-1.0, 1.0)).acos();
                    let phi = f64::from(w.y).atan2(f64::from(w.x)).rem_euclid(TAU_F64);
                    let i = ((theta / FRAC_PI_2_F64 * THETA as f64) as usize).min(THETA - 1);
                    let j = ((phi / TAU_F64 * PHI as f64) as usize).min(PHI - 1);
                    observed[i * PHI + j] += 1.0;
                }
            }
        }
        let (d_theta, d_phi) = (FRAC_PI_2_F64 / THETA as f64, TAU_F64 / PHI as f64);
        let mut expected = vec![0.0f64; THETA * PHI + 1];
        for i in 0..THETA {
            for j in 0..PHI {
                let mut sum = 0.0;
                for a in 0..SUB {
                    let theta = (i as f64 + (a as f64 + 0.5) / SUB as f64) * d_theta;
                    for b in 0..SUB {
                        let phi = (j as f64 + (b as f64 + 0.5) / SUB as f64) * d_phi;
                        let w = dir64(theta, phi);
                        let w = if below { flip_z(w) } else { w };
                        sum += f64::from(bsdf.pdf(wo, w)) * theta.sin();
                    }
                }
                expected[i * PHI + j] = sum * (d_theta / SUB as f64) * (d_phi / SUB as f64);
            }
        }
        let inside: f64 = expected.iter().sum();
        expected[THETA * PHI] = (1.0 - inside).max(0.0);
        let cells = expected
            .iter()
            .zip(&observed)
            .map(|(&e, &o)| (e * N as f64, o))
            .collect();
        let (statistic, dof) = chi_square(cells);
        let limit = chi_square_quantile_999(dof);
        assert!(
            statistic < limit,
            "{bsdf:?} wo {wo}: χ² = {statistic:.1} with {dof} dof, limit {limit:.1}"
        );
    }

    /// χ² for the Lambertian's cosine-weighted sampling, wo at 20° and at 70° below the
    /// surface (the lobe follows wo to the other side).
    #[test]
    fn lambertian_sampling_follows_its_pdf_by_chi_squared() {
        let bsdf = Bsdf::Lambertian { rho: COLOUR };
        assert_sampling_matches_pdf(bsdf, dir(20f32.to_radians(), 0.4), 11);
        assert_sampling_matches_pdf(bsdf, flip_z(dir(70f32.to_radians(), 2.0)), 12);
    }

    /// χ² for the rough conductor's visible-normal sampling at α = 0.2 and 0.5, wo at 20°
    /// and 70°: the refusals (reflections below the horizon) are a cell of their own, so
    /// their rate is tested too.
    #[test]
    fn rough_conductor_sampling_follows_its_pdf_by_chi_squared() {
        let mut seed = 20;
        for alpha in [0.2, 0.5] {
            for (theta, phi) in [(20f32, 0.4), (70f32, 1.4)] {
                seed += 1;
                assert_sampling_matches_pdf(rough(alpha), dir(theta.to_radians(), phi), seed);
            }
        }
    }

    /// Every non-delta sample's weight is eval·|cos θ_i|/pdf and its pdf is [`Bsdf::pdf`]'s,
    /// to 1e-3 relative (the sampled microfacet normal and the one recomputed from wo + wi
    /// differ by rounding), for the Lambertian and rough conductors at α 0.05 to 1, wo from
    /// normal incidence to 89° and below the surface.
    #[test]
    fn sample_weight_is_eval_times_cos_over_pdf() {
        let mut rng = Rng::new(3);
        let mut bsdfs = vec![Bsdf::Lambertian { rho: COLOUR }];
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            bsdfs.push(Bsdf::RoughConductor {
                alpha,
                tint: COLOUR,
            });
        }
        let wos = [
            Vec3::Z,
            dir(0.5, 1.0),
            dir(1.3, 2.0),
            dir(89f32.to_radians(), 0.5),
            flip_z(dir(0.9, 3.0)),
        ];
        for bsdf in bsdfs {
            for wo in wos {
                let mut accepted = 0;
                for _ in 0..2_000 {
                    let uc = rng.next_f32();
                    let Some(s) = bsdf.sample(wo, uc, u2(&mut rng)) else {
                        continue;
                    };
                    accepted += 1;
                    assert!(!s.is_delta && s.wi.z * wo.z > 0.0);
                    let f = bsdf.eval(wo, s.wi);
                    let pdf = bsdf.pdf(wo, s.wi);
                    assert!(close(s.pdf, pdf, 1e-3), "{bsdf:?} {wo}: {} vs {pdf}", s.pdf);
                    let expected = f * s.wi.z.abs() / pdf;
                    assert!(
                        close3(s.weight, expected, 1e-3),
                        "{bsdf:?} {wo} {}: {} vs {expected}",
                        s.wi,
                        s.weight
                    );
                }
                // Reflections below the horizon are refused: at normal incidence a share
                // α²/(1 + α²) of them (see `pdfs_integrate_to_one`), half at α = 1.
                assert!(accepted > 900, "{bsdf:?} {wo}: {accepted}");
            }
        }
    }

    /// ∫ g(ω) dω over the sphere, or over the upper hemisphere with `upper_only`, by the
    /// midpoint rule in (θ, φ) with dω = sin θ dθ dφ, in f64.
    pub(super) fn integrate(
        g: impl Fn(Vec3) -> f64,
        upper_only: bool,
        n_theta: usize,
        n_phi: usize,
    ) -> f64 {
        let top = if upper_only {
            FRAC_PI_2_F64
        } else {
            std::f64::consts::PI
        };
        let (d_theta, d_phi) = (top / n_theta as f64, TAU_F64 / n_phi as f64);
        let mut sum = 0.0;
        for i in 0..n_theta {
            let theta = (i as f64 + 0.5) * d_theta;
            let mut ring = 0.0;
            for j in 0..n_phi {
                ring += g(dir64(theta, (j as f64 + 0.5) * d_phi));
            }
            sum += ring * theta.sin();
        }
        sum * d_theta * d_phi
    }

    /// The rough conductor's pdf for any `wi`, below the horizon too: the visible-normal
    /// density of h = normalize(wo + wi) times the reflection Jacobian 1/(4 wo·h). This is
    /// the density of the mirror direction of a visible normal before `sample` refuses the
    /// ones below the horizon.
    fn reflected_visible_pdf(ggx: Ggx, wo: Vec3, wi: Vec3) -> f64 {
        let sum = wo + wi;
        if sum.length_squared() < 1e-12 {
            return 0.0;
        }
        let h = sum.normalize();
        let wo_h = wo.dot(h);
        if wo_h <= 0.0 {
            return 0.0;
        }
        f64::from(ggx.visible_pdf(wo, h)) / (4.0 * f64::from(wo_h))
    }

    /// The pdfs integrate as they should (midpoint quadrature, 2000 × 400):
    ///
    /// * Lambertian: to 1 over the whole sphere (all of it on wo's side), to 1e-4;
    /// * rough conductor at normal incidence: over the upper hemisphere to exactly
    ///   1/(1 + α²), because the visible-normal pdf loses just the reflections that fall
    ///   below the horizon: at normal incidence h is distributed as D(h) cos θ_h, whose
    ///   tan²θ_h = α² ξ/(1 − ξ) for uniform ξ, and wi = (2 cos²θ_h − 1, ...) is below the
    ///   horizon when tan²θ_h > 1, with probability α²/(1 + α²); so 0.961538 for α = 0.2 and
    ///   0.8 for α = 0.5, to 1e-3;
    /// * rough conductor, normal and 60° incidence: the same density extended below the
    ///   horizon ([`reflected_visible_pdf`]) integrates to 1 over the sphere, to 1e-3, and
    ///   [`Bsdf::pdf`] over the hemisphere stays below that.
    #[test]
    fn pdfs_integrate_to_one() {
        let lambert = Bsdf::Lambertian { rho: COLOUR };
        for wo in [dir(0.3, 0.2), flip_z(dir(1.2, 1.0))] {
            let total = integrate(|w| f64::from(lambert.pdf(wo, w)), false, 2000, 400);
            assert!((total - 1.0).abs() < 1e-4, "{wo}: {total}");
        }
        for alpha in [0.2f32, 0.5] {
            let bsdf = rough(alpha);
            let ggx = Ggx::new(alpha);
            let upper = integrate(|w| f64::from(bsdf.pdf(Vec3::Z, w)), true, 2000, 400);
            let a2 = f64::from(alpha * alpha);
            assert!(
                (upper - 1.0 / (1.0 + a2)).abs() < 1e-3,
                "α {alpha}: {upper}"
            );
            for wo in [Vec3::Z, dir(60f32.to_radians(), 0.7)] {
                let full = integrate(|w| reflected_visible_pdf(ggx, wo, w), false, 2000, 400);
                assert!((full - 1.0).abs() < 1e-3, "α {alpha} {wo}: {full}");
                let upper = integrate(|w| f64::from(bsdf.pdf(wo, w)), true, 2000, 400);
                assert!(upper < full && upper > 0.5, "α {alpha} {wo}: {upper}");
            }
        }
    }

    /// The rough conductor's directional albedo ∫ f(wo, wi) cos θ_i dω_i over the upper
    /// hemisphere, integrated over microfacet normals rather than directions, where D's peak
    /// makes no trouble: with wi the mirror direction of wo about h, dω_i = 4 (wo·h) dω_h, and
    /// with ξ defined by tan²θ_h = α² ξ/(1 − ξ) (the GGX normals' own distribution),
    /// D(h) cos θ_h dω_h = dξ dφ/(2π). So the albedo is the mean over (ξ, φ) ∈ [0,1)×[0,2π)
    /// of f·cos θ_i·4 (wo·h)/(D(h) cos θ_h), by a 600 × 600 midpoint rule.
    pub(super) fn rough_albedo(bsdf: Bsdf, alpha: f32, wo: Vec3) -> f64 {
        const N: usize = 600;
        let ggx = Ggx::new(alpha);
        let a2 = f64::from(ggx.alpha * ggx.alpha);
        let mut sum = 0.0;
        for i in 0..N {
            let xi = (i as f64 + 0.5) / N as f64;
            let theta = (a2 * xi / (1.0 - xi)).sqrt().atan();
            for j in 0..N {
                let h = dir64(theta, (j as f64 + 0.5) / N as f64 * TAU_F64);
                let wo_h = wo.dot(h);
                let wi = 2.0 * wo_h * h - wo;
                if wo_h <= 0.0 || wi.z <= 0.0 {
                    continue;
                }
                let f = f64::from(bsdf.eval(wo, wi).x);
                let jacobian = 4.0 * f64::from(wo_h) / f64::from(ggx.d(h) * h.z);
                sum += f * f64::from(wi.z) * jacobian;
            }
        }
        sum / (N * N) as f64
    }

    /// White furnace, everything with tint 1:
    ///
    /// * rough conductor, α ∈ {0.05, 0.2, 0.5, 1}, wo at 0°, 30°, 60°, 80°, 89°: the albedo
    ///   ([`rough_albedo`]) is at most 1 (+1e-3 for the quadrature) and above 0.3 (the
    ///   separable Smith model only loses energy, most at grazing wo and large α), and the
    ///   mean of 20,000 sample weights (refusals weigh 0, every weight is ≤ 1) estimates the
    ///   same albedo to 4 standard errors + 2e-3 up to 80°. At 89° the cut where reflections
    ///   leave below the horizon passes within 0.3° of the normal, and the midpoint rule,
    ///   stepping across that edge, converges only with its step (α = 0.05: 0.893 at 600²,
    ///   0.898 at 4000², the sampled mean 0.902): there the two agree to 1.5e-2. At normal
    ///   incidence and α = 0.05 nearly nothing is lost (albedo > 0.99);
    /// * Lambertian ρ = 1: every sample weight is exactly 1;
    /// * mirror: every sample weight is exactly 1, pdf 1;
    /// * glass, outside and inside, below and past the critical angle: F·w_r + (1 − F)·w_t
    ///   = 1 to 1e-6 (the two lobes' pdfs are F and 1 − F) and the mean weight over 1000
    ///   stratified `uc` is 1; with a tint the mean is F + (1 − F)·tint to 1e-3.
    #[test]
    fn white_furnace() {
        let mut rng = Rng::new(5);
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            for degrees in [0f32, 30.0, 60.0, 80.0, 89.0] {
                let wo = dir(degrees.to_radians(), 0.3);
                let bsdf = rough(alpha);
                let albedo = rough_albedo(bsdf, alpha, wo);
                assert!(
                    albedo <= 1.0 + 1e-3 && albedo > 0.3,
                    "α {alpha} {degrees}°: {albedo}"
                );
                if degrees == 0.0 && alpha == 0.05 {
                    assert!(albedo > 0.99, "{albedo}");
                }
                let n = 20_000;
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for _ in 0..n {
                    let uc = rng.next_f32();
                    let w = bsdf
                        .sample(wo, uc, u2(&mut rng))
                        .map_or(0.0, |s| s.weight.x);
                    assert!(w <= 1.0);
                    sum += f64::from(w);
                    sum2 += f64::from(w * w);
                }
                let mean = sum / n as f64;
                let sd = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
                let quadrature_error = if degrees > 85.0 { 1.5e-2 } else { 2e-3 };
                assert!(
                    mean <= 1.0 && (mean - albedo).abs() <= 4.0 * sd + quadrature_error,
                    "α {alpha} {degrees}°: sampled {mean} vs quadrature {albedo}"
                );
            }
        }
        let lambert = Bsdf::Lambertian { rho: Vec3::ONE };
        let mirror = Bsdf::Mirror { tint: Vec3::ONE };
        for _ in 0..1000 {
            let wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
            let uc = rng.next_f32();
            let s = lambert.sample(wo, uc, u2(&mut rng)).unwrap();
            assert_eq!(s.weight, Vec3::ONE);
            let s = mirror.sample(flip_z(wo), uc, u2(&mut rng)).unwrap();
            assert_eq!((s.weight, s.pdf, s.is_delta), (Vec3::ONE, 1.0, true));
        }
        let tint = Vec3::new(0.5, 1.0, 0.25);
        for degrees in [0f32, 30.0, 41.0, 50.0, 70.0, 89.0] {
            for inside in [false, true] {
                let mut wo = dir(degrees.to_radians(), 1.1);
                if inside {
                    wo = flip_z(wo);
                }
                for t in [Vec3::ONE, tint] {
                    let glass = Bsdf::Glass { ior: 1.5, tint: t };
                    let r = glass.sample(wo, 0.0, Vec2::ZERO).unwrap();
                    let refracted = glass.sample(wo, 0.999_999, Vec2::ZERO).unwrap();
                    let f = r.pdf;
                    let expected = if f < 1.0 {
                        assert!((r.pdf + refracted.pdf - 1.0).abs() < 1e-6);
                        f * r.weight + (1.0 - f) * refracted.weight
                    } else {
                        r.weight
                    };
                    let sum_of_branches = Vec3::splat(f) + (1.0 - f) * t;
                    assert!(close3(expected, sum_of_branches, 1e-6));
                    let mut sum = Vec3::ZERO;
                    for k in 0..1000 {
                        let uc = (k as f32 + 0.5) / 1000.0;
                        sum += glass.sample(wo, uc, Vec2::ZERO).unwrap().weight;
                    }
                    let mean = sum / 1000.0;
                    if t == Vec3::ONE {
                        assert!((expected - Vec3::ONE).abs().max_element() < 1e-6);
                        assert!((mean - Vec3::ONE).abs().max_element() < 1e-5, "{mean}");
                    } else {
                        assert!((mean - expected).abs().max_element() < 1e-3, "{mean}");
                    }
                }
            }
        }
    }

    /// GGX by hand at α = 0.5, wo = (0.6, 0, 0.8), wi = (0, −0.28, 0.96):
    ///
    /// * wo + wi = (0.6, −0.28, 1.76), |wo + wi|² = 0.36 + 0.0784 + 3.0976 = 3.536, so
    ///   h = (0.6, −0.28, 1.76)/√3.536 = (0.319077, −0.148902, 0.935958);
    /// * D: (h_x² + h_y²)/α² + h_z² = (0.4384/0.25 + 3.0976)/3.536 = 4.8512/3.536 = 1.371946,
    ///   D = 1/(π · 0.25 · 1.371946²) = 0.676451;
    /// * G1(wo): tan²θ_o = 0.36/0.64 = 0.5625, α² tan²θ_o = 0.140625, √1.140625 = 1.068000,
    ///   G1 = 2/2.068000 = 0.967118 and Λ = 0.068000/2 = 0.034000;
    /// * G1(wi): tan²θ_i = 0.0784/0.9216 = 0.0850694, α² tan²θ_i = 0.0212674,
    ///   √1.0212674 = 1.010578, G1 = 2/2.010578 = 0.994739;
    /// * f = D G1(wo) G1(wi)/(4 · 0.8 · 0.96) = 0.676451 · 0.967118 · 0.994739/3.072
    ///   = 0.211838;
    /// * pdf = G1(wo) D/(4 · 0.8) = 0.967118 · 0.676451/3.2 = 0.204440, and the other way
    ///   round G1(wi) D/(4 · 0.96) = 0.175232 (the pdf is not reciprocal; f is);
    /// * the visible-normal density D_wo(h) = G1(wo)(wo·h) D/cos θ_o with
    ///   wo·h = (0.36 + 1.408)/√3.536 = 0.940213: 0.967118 · 0.940213 · 0.676451/0.8
    ///   = 0.768868.
    #[test]
    fn ggx_values_by_hand() {
        let (wo, wi) = (Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, -0.28, 0.96));
        let ggx = Ggx::new(0.5);
        let h = (wo + wi).normalize();
        let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
        assert!(near(h.x, 0.319_077) && near(h.y, -0.148_902) && near(h.z, 0.935_958));
        assert!(near(ggx.d(h), 0.676_451), "{}", ggx.d(h));
        assert!(near(ggx.g1(wo), 0.967_118), "{}", ggx.g1(wo));
        assert!(near(ggx.lambda(wo), 0.034_000), "{}", ggx.lambda(wo));
        assert!(near(ggx.g1(wi), 0.994_739), "{}", ggx.g1(wi));
        assert!(
            near(ggx.visible_pdf(wo, h), 0.768_868),
            "{}",
            ggx.visible_pdf(wo, h)
        );
        let tint = Vec3::new(1.0, 0.5, 0.25);
        let bsdf = Bsdf::RoughConductor { alpha: 0.5, tint };
        let f = bsdf.eval(wo, wi);
        assert!(
            near(f.x, 0.211_838) && near(f.y, 0.105_919) && near(f.z, 0.052_960),
            "{f}"
        );
        assert!(near(bsdf.pdf(wo, wi), 0.204_440), "{}", bsdf.pdf(wo, wi));
        assert!(near(bsdf.pdf(wi, wo), 0.175_232), "{}", bsdf.pdf(wi, wo));
        // At normal incidence nothing is masked and D peaks at 1/(πα²) = 1.273240.
        assert_eq!(ggx.g1(Vec3::Z), 1.0);
        assert!(near(ggx.d(Vec3::Z), 1.273_24));
        // Grazing: everything is masked.
        assert_eq!(ggx.g1(Vec3::X), 0.0);
    }

    /// The mirror: wi = (−x, −y, z) exactly (the world `reflect` of the incoming ray −wo
    /// about z), weight tint, pdf 1, delta; eval and pdf are 0 everywhere.
    #[test]
    fn mirror_reflects_its_tint() {
        let mirror = Bsdf::Mirror { tint: COLOUR };
        assert!(mirror.is_delta());
        for wo in [dir(0.4, 1.0), flip_z(dir(1.2, 4.0)), Vec3::Z] {
            let s = mirror.sample(wo, 0.7, Vec2::new(0.2, 0.9)).unwrap();
            assert_eq!(s.wi, Vec3::new(-wo.x, -wo.y, wo.z));
            assert!((s.wi - reflect(-wo, Vec3::Z)).length() < 1e-7);
            assert_eq!((s.weight, s.pdf, s.is_delta), (COLOUR, 1.0, true));
            assert_eq!(mirror.eval(wo, s.wi), Vec3::ZERO);
            assert_eq!(mirror.pdf(wo, s.wi), 0.0);
        }
        assert!(!rough(0.3).is_delta() && !Bsdf::Lambertian { rho: COLOUR }.is_delta());
    }

    /// The glass's physics, [`crate::shading::material`]'s in the local frame: 4 % reflected at normal
    /// incidence from either side ((n − 1)/(n + 1))², the refraction straight through;
    /// Brewster's angle F = 0.073964 (half r_s² with r_s = −0.38462); Snell's law entering
    /// (sin θ_t = sin θ_i/1.5) and leaving (sin θ_t = 1.5 sin θ_i), wi in the plane of
    /// incidence opposite wo; past the critical angle asin(1/1.5) = 41.81° from inside only
    /// the reflection, pdf 1, weight 1; eval and pdf 0.
    #[test]
    fn glass_follows_fresnel_and_snell() {
        let tint = Vec3::new(0.5, 1.0, 0.25);
        let glass = Bsdf::Glass { ior: 1.5, tint };
        assert!(glass.is_delta());
        for wo in [Vec3::Z, -Vec3::Z] {
            let r = glass.sample(wo, 0.0, Vec2::ZERO).unwrap();
            assert_eq!((r.wi, r.weight), (wo, Vec3::ONE));
            assert!((r.pdf - 0.04).abs() < 1e-6, "{}", r.pdf);
            let t = glass.sample(wo, 0.5, Vec2::ZERO).unwrap();
            assert!((t.wi + wo).length() < 1e-6, "straight through: {}", t.wi);
            assert_eq!(t.weight, tint);
            assert!((t.pdf - 0.96).abs() < 1e-6);
            assert_eq!(
                (glass.eval(wo, t.wi), glass.pdf(wo, t.wi)),
                (Vec3::ZERO, 0.0)
            );
        }
        let brewster = 1.5f32.atan();
        let r = glass.sample(dir(brewster, 0.0), 0.0, Vec2::ZERO).unwrap();
        assert!((r.pdf - 0.073_964).abs() < 1e-5, "{}", r.pdf);
        for theta in [0.1f32, 0.5, 1.0, 1.4] {
            let wo = dir(theta, 0.8);
            let t = glass.sample(wo, 0.999_999, Vec2::ZERO).unwrap();
            let sin_t = t.wi.truncate().length();
            assert!(
                t.wi.z < 0.0 && (sin_t - theta.sin() / 1.5).abs() < 1e-6,
                "{}",
                t.wi
            );
            assert!(t.wi.truncate().dot(wo.truncate()) < 0.0, "opposite azimuth");
            assert!(
                t.wi.truncate().perp_dot(wo.truncate()).abs() < 1e-6,
                "same plane"
            );
            let f = fresnel_dielectric(theta.cos(), 1.5);
            assert!((t.pdf - (1.0 - f)).abs() < 1e-6);
            let r = glass.sample(wo, f * 0.999, Vec2::ZERO).unwrap();
            assert_eq!((r.wi, r.weight), (reflect_local(wo), Vec3::ONE));
            assert!(close(r.pdf, f, 1e-5));
        }
        let critical = (1.0f32 / 1.5).asin();
        let inside = |theta: f32| flip_z(dir(theta, 2.5));
        let t = glass
            .sample(inside(critical - 0.01), 0.999, Vec2::ZERO)
            .unwrap();
        assert!(t.wi.z > 0.0 && t.weight == tint, "leaves the glass");
        let sin_t = t.wi.truncate().length();
        assert!(
            (sin_t - 1.5 * (critical - 0.01).sin()).abs() < 1e-4,
            "{}",
            t.wi
        );
        for theta in [critical + 0.01, 1.2, 1.5] {
            let s = glass.sample(inside(theta), 0.999_999, Vec2::ZERO).unwrap();
            assert_eq!(s.wi, reflect_local(inside(theta)));
            assert_eq!((s.pdf, s.weight), (1.0, Vec3::ONE));
        }
    }

    /// Frames are orthonormal and right-handed (s × t = n), to_world inverts to_local, and n
    /// is local z: for 1000 random normals and ±z, and for the frames [`ShadingFrame::new`]
    /// builds from random shading normals, geometric normals and wo.
    #[test]
    fn frames_are_orthonormal_and_right_handed() {
        let mut rng = Rng::new(8);
        let random_unit = |rng: &mut Rng| {
            Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize()
        };
        let check = |f: Frame| {
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-5, "{f:?}");
            }
            for v in [f.s, f.t, f.n] {
                assert!((v.length() - 1.0).abs() < 1e-5, "{f:?}");
            }
            assert!(
                (f.s.cross(f.t) - f.n).length() < 1e-5,
                "right-handed: {f:?}"
            );
            assert!((f.to_local(f.n) - Vec3::Z).length() < 1e-5);
            let v = Vec3::new(0.3, -0.5, 0.8);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        };
        check(Frame::from_normal(Vec3::Z));
        check(Frame::from_normal(-Vec3::Z));
        for _ in 0..1000 {
            check(Frame::from_normal(random_unit(&mut rng)));
            let (ns, ng, wo) = (
                random_unit(&mut rng),
                random_unit(&mut rng),
                random_unit(&mut rng),
            );
            let sf = ShadingFrame::new(ns, ng, wo);
            check(sf.frame());
            let g = sf.geometric_normal();
            assert!(wo.dot(g) >= 0.0 && (g - ng).length() * (g + ng).length() < 1e-6);
            assert!(sf.shading_normal().dot(g) >= 0.0, "on the geometric side");
            if wo.dot(g) > MIN_SHADING_COS {
                assert!(sf.to_local(wo).z >= MIN_SHADING_COS * (1.0 - 1e-3));
            }
        }
    }

    /// A shading normal tilted 53° (n_s = (0.8, 0, 0.6), geometric z) with wo = (−0.9, 0, 0.3)
    /// /|·| 18° above the geometric surface but below the shading one (wo·n_s = −0.54/0.949):
    /// the frame's normal is n_s blended towards z with t = (ε − a)/(b − a), leaving wo just
    /// above it (ε/|blend| = 1.107 ε), still tilted towards +x in the xz plane. The same with the geometric normal given as −z (two-sided), and with wo on the
    /// other side both normals flip to it. A shading normal with wo well above it is kept;
    /// one pointing against the geometric normal is flipped to its side.
    #[test]
    fn a_shading_normal_below_wo_is_bent_towards_the_geometric_one() {
        let ns = Vec3::new(0.8, 0.0, 0.6);
        let wo = Vec3::new(-0.9, 0.0, 0.3).normalize();
        let (a, b) = (wo.dot(ns), wo.dot(Vec3::Z));
        assert!(a < 0.0 && b > 0.0);
        let t = (MIN_SHADING_COS - a) / (b - a);
        let expected = (ns + t * (Vec3::Z - ns)).normalize();
        for ng in [Vec3::Z, -Vec3::Z] {
            let sf = ShadingFrame::new(ns, ng, wo);
            assert_eq!(sf.front_face(), ng == Vec3::Z);
            assert_eq!(sf.geometric_normal(), Vec3::Z);
            let n = sf.shading_normal();
            assert!((n - expected).length() < 1e-5, "{n} vs {expected}");
            // wo·n = ε/|n_s + t (n_g − n_s)|: the blend is shorter than unit (0.904 here),
            // so wo ends 1.107 ε above, no more.
            let cos_o = sf.to_local(wo).z;
            let blend = (ns + t * (Vec3::Z - ns)).length();
            assert!(close(cos_o, MIN_SHADING_COS / blend, 1e-3), "{cos_o}");
            assert!(
                (MIN_SHADING_COS..1.2 * MIN_SHADING_COS).contains(&cos_o),
                "{cos_o}"
            );
            // Bent from 53° to 18.4° off z (n = (0.315, 0, 0.949)): still towards +x.
            assert!(n.x > 0.3 && n.y.abs() < 1e-6 && n.z > 0.9, "{n}");
        }
        // The mirror image from behind: both normals flip to −wo's side, then bend the same.
        let back = ShadingFrame::new(ns, Vec3::Z, -wo);
        assert!(!back.front_face());
        assert_eq!(back.geometric_normal(), -Vec3::Z);
        assert!(
            (back.shading_normal() + expected).length() < 1e-5,
            "{back:?}"
        );
        assert!(back.to_local(-wo).z >= MIN_SHADING_COS * (1.0 - 1e-3));
        // wo well above: the shading normal is kept (normalised).
        let kept = ShadingFrame::new(2.0 * ns, Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert!((kept.shading_normal() - ns).length() < 1e-6);
        // A shading normal against the geometric one is turned to its side first.
        let turned = ShadingFrame::new(-ns, Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert!((turned.shading_normal() - ns).length() < 1e-6);
        // No shading normal: the geometric one.
        let none = ShadingFrame::new(Vec3::ZERO, Vec3::Z, -wo);
        assert_eq!(none.shading_normal(), -Vec3::Z);
    }

    /// With a tilted shading normal n_s = (0.5, 0, 1)/√1.25 over a geometric z and
    /// wo = 30° on the −x side: wi = (0.9, 0, −0.1)/|·| is above the shading surface but
    /// below the geometric one. In the shading frame alone the Lambertian and the rough
    /// conductor would give it light; [`ShadingFrame::eval_world`] gives (0, 0). wi = z,
    /// above both, gets ρ/π and pdf cos θ_i/π. Of 10,000 cosine samples through
    /// [`ShadingFrame::sample_world`] some are refused (the tilted lobe reaches below the
    /// geometric plane) and none returned is below it, each with the pdf eval_world gives.
    /// A mirror whose reflection about n_s would go below the geometric surface gives no
    /// sample.
    #[test]
    fn reflection_only_bsdfs_give_nothing_across_the_geometric_surface() {
        let ng = Vec3::Z;
        let ns = Vec3::new(0.5, 0.0, 1.0).normalize();
        let wo = dir(30f32.to_radians(), std::f32::consts::PI);
        let sf = ShadingFrame::new(ns, ng, wo);
        assert!((sf.shading_normal() - ns).length() < 1e-6, "not bent");
        let leak = Vec3::new(0.9, 0.0, -0.1).normalize();
        assert!(sf.to_local(leak).z > 0.0 && !sf.reflects(wo, leak));
        let lambert = Bsdf::Lambertian { rho: COLOUR };
        let metal = Bsdf::RoughConductor {
            alpha: 0.5,
            tint: COLOUR,
        };
        for bsdf in [lambert, metal] {
            let local = bsdf.eval(sf.to_local(wo), sf.to_local(leak));
            assert!(local.max_element() > 0.0, "the shading frame alone leaks");
            assert_eq!(sf.eval_world(&bsdf, wo, leak), (Vec3::ZERO, 0.0));
        }
        let (f, pdf) = sf.eval_world(&lambert, wo, Vec3::Z);
        assert!(close3(f, COLOUR / std::f32::consts::PI, 1e-6));
        assert!(close(pdf, ns.z / std::f32::consts::PI, 1e-5));
        // Above the geometric surface, below the shading one: zero as well.
        let shadowed = Vec3::new(-0.95, 0.0, 0.2).normalize();
        assert!(sf.reflects(wo, shadowed) && sf.to_local(shadowed).z < 0.0);
        assert_eq!(sf.eval_world(&lambert, wo, shadowed), (Vec3::ZERO, 0.0));

        let mut rng = Rng::new(4);
        let mut refused = 0;
        for _ in 0..10_000 {
            let uc = rng.next_f32();
            match sf.sample_world(&lambert, wo, uc, u2(&mut rng)) {
                None => refused += 1,
                Some(s) => {
                    assert!(s.wi.z > 0.0 && sf.reflects(wo, s.wi), "{}", s.wi);
                    let (_, pdf) = sf.eval_world(&lambert, wo, s.wi);
                    assert!(close(s.pdf, pdf, 1e-4));
                }
            }
        }
        // Cosine-weighted directions project to points uniform on the unit disk around n_s
        // (Malley). The geometric plane, tilted β = 26.57° from it, projects to half an
        // ellipse with semi-axes 1 and cos β, so the share below it is half the disk less half
        // the ellipse: (1 − cos β)/2 = 0.052786, 528 of 10,000 (binomial sd 22; 4.5 sd).
        assert!((428..628).contains(&refused), "{refused}");

        let mirror = Bsdf::Mirror { tint: COLOUR };
        let grazing = dir(60f32.to_radians(), std::f32::consts::PI);
        let sf = ShadingFrame::new(ns, ng, grazing);
        let r = sf.to_world(reflect_local(sf.to_local(grazing)));
        assert!(r.z < 0.0, "the shading reflection goes below: {r}");
        assert_eq!(sf.sample_world(&mirror, grazing, 0.5, Vec2::ZERO), None);
        let s = ShadingFrame::new(ng, ng, grazing)
            .sample_world(&mirror, grazing, 0.5, Vec2::ZERO)
            .unwrap();
        assert!((s.wi - reflect(-grazing, ng)).length() < 1e-6);
    }

    /// Glass through a [`ShadingFrame`] with its normal pointing out: from outside it bends
    /// towards the normal (sin θ_t = sin θ_i/1.5) into the other geometric side, from inside
    /// ([`ShadingFrame::front_face`] false, η inverted) away from it (sin θ_t = 1.5 sin θ_i),
    /// out. With a tilted shading normal, over wo on both sides and 200 `uc` each, every
    /// reflection (weight 1) stays on wo's geometric side and every refraction (weight tint)
    /// crosses the geometric surface.
    #[test]
    fn glass_through_a_shading_frame_crosses_the_geometric_surface() {
        let tint = Vec3::new(0.5, 0.7, 0.9);
        let glass = Bsdf::Glass { ior: 1.5, tint };
        let ng = Vec3::Z;
        let outside = dir(40f32.to_radians(), 0.3);
        let sf = ShadingFrame::new(ng, ng, outside);
        assert!(sf.front_face());
        let t = sf.sample_world(&glass, outside, 0.999, Vec2::ZERO).unwrap();
        assert!(t.wi.z < 0.0 && t.weight == tint);
        let sin_t = t.wi.truncate().length();
        assert!(
            (sin_t - 40f32.to_radians().sin() / 1.5).abs() < 1e-5,
            "{}",
            t.wi
        );
        let f = fresnel_dielectric(40f32.to_radians().cos(), 1.5);
        assert!((t.pdf - (1.0 - f)).abs() < 1e-6);
        let r = sf.sample_world(&glass, outside, 0.0, Vec2::ZERO).unwrap();
        assert!((r.wi - reflect(-outside, ng)).length() < 1e-6 && r.weight == Vec3::ONE);

        let inside = flip_z(dir(30f32.to_radians(), 0.3));
        let sf = ShadingFrame::new(ng, ng, inside);
        assert!(!sf.front_face());
        let t = sf.sample_world(&glass, inside, 0.999, Vec2::ZERO).unwrap();
        assert!(t.wi.z > 0.0 && t.weight == tint, "leaves: {}", t.wi);
        let sin_t = t.wi.truncate().length();
        assert!((sin_t - 0.75).abs() < 1e-5, "{}", t.wi);
        let f = fresnel_dielectric(30f32.to_radians().cos(), 1.0 / 1.5);
        assert!((t.pdf - (1.0 - f)).abs() < 1e-6);

        let ns = Vec3::new(0.3, 0.0, 1.0).normalize();
        let mut rng = Rng::new(6);
        let (mut reflected, mut refracted) = (0, 0);
        for k in 0..400 {
            let mut wo = uniform_hemisphere(rng.next_f32(), rng.next_f32());
            if k % 2 == 1 {
                wo = flip_z(wo);
            }
            let sf = ShadingFrame::new(ns, ng, wo);
            for i in 0..200 {
                let uc = (i as f32 + 0.5) / 200.0;
                let Some(s) = sf.sample_world(&glass, wo, uc, Vec2::ZERO) else {
                    continue;
                };
                if s.weight == Vec3::ONE {
                    reflected += 1;
                    assert!(sf.reflects(wo, s.wi) && s.wi.dot(wo.z.signum() * ng) > 0.0);
                } else {
                    refracted += 1;
                    assert!(!sf.reflects(wo, s.wi) && s.wi.dot(wo.z.signum() * ng) < 0.0);
                }
            }
        }
        assert!(
            reflected > 5_000 && refracted > 20_000,
            "{reflected} {refracted}"
        );
    }
}
