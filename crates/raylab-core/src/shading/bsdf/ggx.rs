//! The isotropic GGX (Trowbridge–Reitz) microfacet distribution with Smith masking and its
//! visible-normal sampling: the rough conductor's and the plastic's coating's microfacets.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::base::sampling::concentric_disk;

/// The smallest GGX α [`Ggx::new`] accepts. Below it D(h) = 1/(πα²) at the peak approaches
/// the f32 range and the lobe is narrower than float directions resolve; a smoother surface
/// is a [`Bsdf::Mirror`].
pub const MIN_ALPHA: f32 = 1e-4;

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
