//! An ideal mirror ([`Bsdf::Mirror`]): a delta lobe, so it is only sampled.

use glam::Vec3;

use super::{BsdfSample, reflect_local};

#[cfg(doc)]
use super::Bsdf;

/// `wi` = [`reflect_local`]`(wo)`, weight `tint`, pdf 1, delta.
#[inline(always)]
pub(super) fn sample(tint: Vec3, wo: Vec3) -> BsdfSample {
    BsdfSample {
        wi: reflect_local(wo),
        weight: tint,
        pdf: 1.0,
        is_delta: true,
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec2;

    use super::super::checks::{COLOUR, dir, white_samples};
    use super::super::{Bsdf, flip_z, reflect};
    use super::*;

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
        let rough = Bsdf::RoughConductor {
            alpha: 0.3,
            tint: Vec3::ONE,
        };
        assert!(!rough.is_delta() && !Bsdf::Lambertian { rho: COLOUR }.is_delta());
    }

    /// White furnace: with tint 1 every sample weight is exactly 1, pdf 1.
    #[test]
    fn mirror_white_furnace() {
        let mirror = Bsdf::Mirror { tint: Vec3::ONE };
        for below in [false, true] {
            for s in white_samples(mirror, below) {
                assert_eq!((s.weight, s.pdf, s.is_delta), (Vec3::ONE, 1.0, true));
            }
        }
    }
}
