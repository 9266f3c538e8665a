//! The lab's ideal diffuse surface ([`Bsdf::Lambertian`]): f = ρ/π on the side of `wo`,
//! sampled cosine-weighted.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::{BsdfSample, same_hemisphere};
use crate::base::sampling::cosine_hemisphere;

#[cfg(doc)]
use super::Bsdf;

/// f(wo, wi) = ρ/π where `wo` and `wi` are on the same side, else 0.
#[inline(always)]
pub(super) fn eval(rho: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if same_hemisphere(wo, wi) {
        rho * FRAC_1_PI
    } else {
        Vec3::ZERO
    }
}

/// |cos θ_i|/π on the side of `wo`, else 0.
#[inline(always)]
pub(super) fn pdf(wo: Vec3, wi: Vec3) -> f32 {
    if same_hemisphere(wo, wi) {
        wi.z.abs() * FRAC_1_PI
    } else {
        0.0
    }
}

/// Cosine-weighted on the side of `wo` ([`cosine_hemisphere`], Malley's method), pdf
/// |cos θ_i|/π, weight (ρ/π)·|cos θ_i| / (|cos θ_i|/π) = ρ exactly; `None` for `wo` in the
/// surface plane.
#[inline(always)]
pub(super) fn sample(rho: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
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

#[cfg(test)]
mod tests {
    use super::super::checks::{
        COLOUR, assert_reciprocal, assert_sample_weights, assert_sampling_matches_pdf, close3, dir,
        integrate, white_samples,
    };
    use super::super::{Bsdf, flip_z};
    use super::*;
    use crate::base::sampling::Rng;

    /// Reciprocal ([`assert_reciprocal`]), and its value is ρ/π.
    #[test]
    fn lambertian_is_reciprocal() {
        assert_reciprocal(Bsdf::Lambertian { rho: COLOUR }, &mut Rng::new(1));
        let f = Bsdf::Lambertian { rho: COLOUR }.eval(dir(0.3, 0.0), dir(1.0, 2.0));
        assert!(close3(f, COLOUR / std::f32::consts::PI, 1e-7));
    }

    /// χ² for the Lambertian's cosine-weighted sampling, wo at 20° and at 70° below the
    /// surface (the lobe follows wo to the other side).
    #[test]
    fn lambertian_sampling_follows_its_pdf_by_chi_squared() {
        let bsdf = Bsdf::Lambertian { rho: COLOUR };
        assert_sampling_matches_pdf(bsdf, dir(20f32.to_radians(), 0.4), 11);
        assert_sampling_matches_pdf(bsdf, flip_z(dir(70f32.to_radians(), 2.0)), 12);
    }

    /// Each sample's weight and pdf are what eval and pdf give ([`assert_sample_weights`]).
    #[test]
    fn lambertian_sample_weight_is_eval_times_cos_over_pdf() {
        assert_sample_weights(Bsdf::Lambertian { rho: COLOUR }, &mut Rng::new(3));
    }

    /// The pdf integrates to 1 over the whole sphere (all of it on wo's side), to 1e-4
    /// (midpoint quadrature, 2000 × 400).
    #[test]
    fn lambertian_pdf_integrates_to_one() {
        let lambert = Bsdf::Lambertian { rho: COLOUR };
        for wo in [dir(0.3, 0.2), flip_z(dir(1.2, 1.0))] {
            let total = integrate(|w| f64::from(lambert.pdf(wo, w)), false, 2000, 400);
            assert!((total - 1.0).abs() < 1e-4, "{wo}: {total}");
        }
    }

    /// White furnace: with ρ = 1 every sample weight is exactly 1.
    #[test]
    fn lambertian_white_furnace() {
        let lambert = Bsdf::Lambertian { rho: Vec3::ONE };
        for below in [false, true] {
            for s in white_samples(lambert, below) {
                assert_eq!(s.weight, Vec3::ONE);
            }
        }
    }
}
