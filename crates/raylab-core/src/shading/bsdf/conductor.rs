//! A rough metal ([`Bsdf::RoughConductor`]): isotropic GGX microfacets ([`Ggx`]) with Smith's
//! separable masking-shadowing and Fresnel = 1, sampled by the normals visible from `wo`. This
//! is Mitsuba 3's `roughconductor` with `distribution="ggx"`, `material="none"`,
//! `sample_visible=true`, whose `eval` returns f times cos θ_i.
//!
//! Its functions take `wo` above the surface ([`Bsdf`] mirrors a pair from below first).

use glam::{Vec2, Vec3};

use super::{BsdfSample, Ggx};

#[cfg(doc)]
use super::Bsdf;

/// Walter et al., "Microfacet Models for Refraction through Rough Surfaces", 2007, eq. 20
/// with F = 1: with h = normalize(wo + wi),
/// f = tint · D(h) · G1(wo) · G1(wi) / (4 cos θ_o cos θ_i) for `wi` above the surface, else 0
/// ([`Ggx`] for D and G1).
#[inline(always)]
pub(super) fn eval(alpha: f32, tint: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if !(wo.z > 0.0 && wi.z > 0.0) {
        return Vec3::ZERO;
    }
    let h = (wo + wi).normalize();
    let ggx = Ggx::new(alpha);
    tint * (ggx.d(h) * ggx.g1(wo) * ggx.g1(wi) / (4.0 * wo.z * wi.z))
}

/// The visible-normal density of h times the Jacobian of reflection,
/// dω_h/dω_i = 1/(4 |wo·h|) (Walter et al. 2007, eq. 14):
/// pdf = G1(wo)·|wo·h|·D(h)/cos θ_o · 1/(4 |wo·h|) = G1(wo)·D(h)/(4 cos θ_o), for `wi` above
/// the surface. Over the upper hemisphere this integrates to less than 1 by exactly the chance
/// that the mirror direction of a sampled normal falls below the horizon (then [`sample`]
/// returns `None`).
#[inline(always)]
pub(super) fn pdf(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    if !(wo.z > 0.0 && wi.z > 0.0) {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    let ggx = Ggx::new(alpha);
    ggx.g1(wo) * ggx.d(h) / (4.0 * wo.z)
}

/// A microfacet normal h from the distribution of normals visible from `wo`
/// ([`Ggx::sample_visible`], Heitz 2018), `wi` = wo reflected about h; weight
/// f·cos θ_i/pdf = tint·G1(wi), pdf as [`pdf`]. `None` when the reflection leaves below the
/// horizon.
#[inline(always)]
pub(super) fn sample(alpha: f32, tint: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
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
        wi,
        weight: tint * ggx.g1(wi),
        pdf,
        is_delta: false,
    })
}

#[cfg(test)]
mod tests {
    use super::super::Bsdf;
    use super::super::checks::{
        COLOUR, assert_reciprocal, assert_sample_weights, assert_sampling_matches_pdf, dir,
        integrate, rough_albedo, u2,
    };
    use super::*;
    use crate::base::sampling::Rng;

    /// A rough conductor reflecting everything (the white furnace's).
    fn rough(alpha: f32) -> Bsdf {
        Bsdf::RoughConductor {
            alpha,
            tint: Vec3::ONE,
        }
    }

    /// Reciprocal ([`assert_reciprocal`]) from α 0.05 to 1.
    #[test]
    fn rough_conductor_is_reciprocal() {
        let mut rng = Rng::new(2);
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            assert_reciprocal(
                Bsdf::RoughConductor {
                    alpha,
                    tint: COLOUR,
                },
                &mut rng,
            );
        }
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

    /// Each sample's weight and pdf are what eval and pdf give ([`assert_sample_weights`]),
    /// α 0.05 to 1.
    #[test]
    fn rough_conductor_sample_weight_is_eval_times_cos_over_pdf() {
        let mut rng = Rng::new(3);
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            let bsdf = Bsdf::RoughConductor {
                alpha,
                tint: COLOUR,
            };
            assert_sample_weights(bsdf, &mut rng);
        }
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

    /// The pdf integrates as it should (midpoint quadrature, 2000 × 400):
    ///
    /// * at normal incidence, over the upper hemisphere to exactly 1/(1 + α²), because the
    ///   visible-normal pdf loses just the reflections that fall below the horizon: at normal
    ///   incidence h is distributed as D(h) cos θ_h, whose tan²θ_h = α² ξ/(1 − ξ) for uniform
    ///   ξ, and wi = (2 cos²θ_h − 1, ...) is below the horizon when tan²θ_h > 1, with
    ///   probability α²/(1 + α²); so 0.961538 for α = 0.2 and 0.8 for α = 0.5, to 1e-3;
    /// * normal and 60° incidence: the same density extended below the horizon
    ///   ([`reflected_visible_pdf`]) integrates to 1 over the sphere, to 1e-3, and
    ///   [`Bsdf::pdf`] over the hemisphere stays below that.
    #[test]
    fn rough_conductor_pdf_integrates_to_one_less_the_refusals() {
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

    /// White furnace, tint 1, α ∈ {0.05, 0.2, 0.5, 1}, wo at 0°, 30°, 60°, 80°, 89°: the
    /// albedo ([`rough_albedo`]) is at most 1 (+1e-3 for the quadrature) and above 0.3 (the
    /// separable Smith model only loses energy, most at grazing wo and large α), and the mean
    /// of 20,000 sample weights (refusals weigh 0, every weight is ≤ 1) estimates the same
    /// albedo to 4 standard errors + 2e-3 up to 80°. At 89° the cut where reflections leave
    /// below the horizon passes within 0.3° of the normal, and the midpoint rule, stepping
    /// across that edge, converges only with its step: there the two agree to 1.5e-2. At
    /// normal incidence and α = 0.05 nearly nothing is lost (albedo > 0.99).
    #[test]
    fn rough_conductor_white_furnace() {
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
}
