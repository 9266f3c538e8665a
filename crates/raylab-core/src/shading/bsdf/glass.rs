//! A smooth dielectric interface ([`Bsdf::Glass`]): the exact Fresnel equations choose between
//! its two delta lobes, reflection and refraction by Snell's law.

use glam::Vec3;

use super::{BsdfSample, reflect_local};

#[cfg(doc)]
use super::Bsdf;

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
pub(super) fn sample(wo: Vec3, ior: f32, tint: Vec3, uc: f32) -> BsdfSample {
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

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::super::checks::{close, close3, dir};
    use super::super::{Bsdf, flip_z};
    use super::*;

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

    /// White furnace: outside and inside, below and past the critical angle,
    /// F·w_r + (1 − F)·w_t = 1 to 1e-6 (the two lobes' pdfs are F and 1 − F) and the mean
    /// weight over 1000 stratified `uc` is 1; with a tint the mean is F + (1 − F)·tint to 1e-3.
    #[test]
    fn glass_white_furnace() {
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
}
