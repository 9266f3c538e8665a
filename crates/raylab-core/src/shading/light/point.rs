//! The lab's point light behind the [`Light`] interface.

use glam::{Vec2, Vec3};

use super::{Light, LightSample, MIN_LIGHT_DISTANCE};
use crate::base::geometry::Ray;
use crate::base::sampling::uniform_sphere;

/// The lab's light as a point at `position` emitting the total power `power` per channel
/// (`P · colour`). It sends `I = P / (4π)` watts per steradian in every direction,
/// so at distance `r` it gives the radiance-like `I / r²` along its single direction; in lab
/// units (π ×) that is `Li = π · I / r² = P · colour / (4 r²)`, and a diffuse surface's
/// `(ρ/π) · Li · cos θ` is exactly the lab's `ρ · D` of equation 27 ([`super::direct_light`]).
/// Closer than [`MIN_LIGHT_DISTANCE`], `Li` is as at that distance, as in equation 27.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    /// Total emitted power per channel, `P · colour`, in watts.
    pub power: Vec3,
}

impl Light for PointLight {
    /// The one direction toward the point, with `pdf` 1. `None` for `p` exactly at the light
    /// (or not finite): there is no direction.
    #[inline]
    fn sample_li(&self, p: Vec3, _u: Vec2) -> Option<LightSample> {
        let to_light = self.position - p;
        let r2 = to_light.length_squared();
        if !(r2 > 0.0 && r2 < f32::INFINITY) {
            return None;
        }
        let distance = r2.sqrt();
        let clamped_r2 = r2.max(MIN_LIGHT_DISTANCE * MIN_LIGHT_DISTANCE);
        Some(LightSample {
            wi: to_light / distance,
            li: self.power / (4.0 * clamped_r2),
            pdf: 1.0,
            distance,
            point: self.position,
            is_delta: true,
        })
    }

    /// 0: a direction drawn from a continuous distribution hits the point with probability 0.
    #[inline]
    fn pdf_li(&self, _p: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    /// `None`: a point has no area for a ray to hit.
    #[inline]
    fn intersect(&self, _ray: &Ray, _t_max: f32) -> Option<f32> {
        None
    }

    /// 0: no ray sees the point.
    #[inline]
    fn le(&self, _ray_direction: Vec3) -> Vec3 {
        Vec3::ZERO
    }

    #[inline]
    fn is_delta(&self) -> bool {
        true
    }

    #[inline]
    fn power(&self) -> Vec3 {
        self.power
    }

    /// From the point, a direction uniform over the sphere: the point light sends the same
    /// intensity P/(4π) every way.
    #[inline]
    fn sample_le(&self, _u_point: Vec2, u_direction: Vec2) -> Option<Ray> {
        self.position.is_finite().then(|| Ray {
            origin: self.position,
            direction: uniform_sphere(u_direction.x, u_direction.y),
        })
    }
}

#[cfg(test)]
mod tests {
    use std::f32::consts::PI;

    use super::*;
    use crate::base::sampling::Rng;
    use crate::shading::light::{LightSpec, direct_light};

    /// `(ρ/π) · Li · cos θ / pdf` from the sample equals the lab's `ρ · D` ([`direct_light`])
    /// to float rounding, at random points and normals around the lab's light, including points
    /// closer than [`MIN_LIGHT_DISTANCE`] at normal incidence (where both clamp r).
    #[test]
    fn point_light_gives_the_labs_d() {
        let spec = LightSpec {
            colour: Vec3::new(1.0, 0.6, 0.25),
            ..LightSpec::default()
        };
        let light = PointLight {
            position: spec.position,
            power: spec.channel_power(),
        };
        let rho = Vec3::new(0.75, 0.5, 0.25);
        let mut rng = Rng::new(6);
        let mut worst = 0.0f32;
        for i in 0..10_000 {
            let p = Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            );
            let n = Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            )
            .normalize();
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            // Every tenth point very near the light, with the normal facing it.
            let (p, n) = if i % 10 == 0 {
                let offset = 1e-4 * n;
                (light.position - offset, n)
            } else {
                (p, n)
            };
            let s = light.sample_li(p, u).unwrap();
            assert!(s.is_delta && s.pdf == 1.0 && s.point == light.position);
            assert!((s.wi.length() - 1.0).abs() < 1e-6);
            assert!((s.distance - (light.position - p).length()).abs() <= 1e-6 * s.distance);
            let ours = rho / PI * s.li * s.wi.dot(n).max(0.0) / s.pdf;
            let labs = rho * direct_light(&spec, p, n);
            let scale = labs.max_element().max(1e-30);
            worst = worst.max((ours - labs).abs().max_element() / scale);
        }
        assert!(worst < 1e-6, "largest relative difference {worst}");
        // By hand at the lab's floor centre (direct_light_at_the_labs_floor_centre): r² = 2.74,
        // Li = 14 / (4 · 2.74) = 1.277372 per white channel.
        let s = LightSpec::default()
            .emitter()
            .sample_li(Vec3::new(0.0, 1.0, 0.0), Vec2::ZERO)
            .unwrap();
        assert!(
            (s.li - Vec3::splat(1.277_372)).abs().max_element() < 1e-6,
            "{}",
            s.li
        );
    }

    /// The point light is a delta light: no density, nothing to hit, nothing seen, and no
    /// direction from the point itself.
    #[test]
    fn point_light_is_a_delta_light() {
        let spec = LightSpec::default();
        let light = PointLight {
            position: spec.position,
            power: spec.channel_power(),
        };
        assert_eq!(
            spec.emitter(),
            crate::shading::light::AnyLight::Point(light)
        );
        assert!(light.is_delta());
        assert_eq!(light.power(), Vec3::splat(14.0));
        let p = Vec3::new(0.0, 1.0, 0.0);
        let wi = (light.position - p).normalize();
        assert_eq!(light.pdf_li(p, wi), 0.0);
        assert_eq!(light.intersect(&Ray::new(p, wi), f32::INFINITY), None);
        assert_eq!(light.le(wi), Vec3::ZERO);
        assert_eq!(light.sample_li(light.position, Vec2::ZERO), None);
    }
}
