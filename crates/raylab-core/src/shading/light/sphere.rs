//! A spherical light: the lab's soft-shadow sphere as an emitter with a size.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::{Light, LightSample, sphere_point};
use crate::base::geometry::Ray;
use crate::base::sampling::{cosine_hemisphere, hemisphere_around, uniform_sphere};

/// How far outside a sphere's silhouette a ray may pass and still count as touching it, as a
/// share of the squared distance `d²` from the ray's origin to the centre: a ray whose line
/// passes at `a` from the centre meets the sphere if `a² ≤ R² + GRAZING · d²`.
///
/// [`sphere_point`] computes its cone's directions in `f32` with `sin θ` from
/// `1 − cos² θ`, which near the cone's edge is off by about `ε · d² / R²` relative, so some of
/// its points lie where the ray from the surface point passes just outside the sphere (by up to
/// `0.15 ε · d²` in `a²` over 200,000 samples at 100 radii). Counting those as hits widens the
/// cone by a share of about `GRAZING · d² / R²` of its solid angle: 5 parts in 10⁵ at 20 radii,
/// 3 in 10⁴ at 50.
const GRAZING: f32 = f32::EPSILON;

/// A sphere of `radius` (above 0) centred at `centre`, emitting the total power `power` (per
/// channel, `P · colour`) uniformly from its surface, outward.
///
/// Every point of its surface sends the same radiance `L = P / (4π² R²)` into every outward
/// direction: its exitance `π L` times its area `4π R²` is `P`. In lab units (π ×) a viewer
/// sees `Li = π L = P / (4π R²)`. Seen from outside it lights a surface exactly as a point of
/// the same power at its centre would, as long as all of it is above the surface's horizon
/// (Lambert's result for a uniform sphere); near it the shadows it casts are soft.
///
/// It is seen from outside only: from a point inside (or on) the sphere, its surface faces
/// away, so nothing of it is seen there ([`Light::sample_li`] gives `None`, [`Light::intersect`]
/// `None`, [`Light::pdf_li`] 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    pub centre: Vec3,
    /// Radius in scene units, above 0 (see [`crate::shading::light::emitter`] for size 0).
    pub radius: f32,
    /// Total emitted power per channel, `P · colour`, in watts.
    pub power: Vec3,
}

impl SphereLight {
    /// The radiance of its surface in lab units, `π L = P / (4π R²)`.
    #[inline]
    pub fn radiance(&self) -> Vec3 {
        self.power / (4.0 * PI * self.radius * self.radius)
    }

    /// The density (per solid angle) of directions drawn uniformly from the cone the sphere
    /// fills as seen from `p`, `1 / (2π (1 − cos θmax))` with `sin² θmax = R² / d²`; `None`
    /// from inside or on the sphere (`d ≤ R`). `1 − cos θmax` is computed as
    /// `sin² θmax / (1 + cos θmax)`, which keeps its precision for a small, far sphere, where
    /// `1 − cos θmax` would cancel.
    #[inline]
    fn cone_pdf(&self, p: Vec3) -> Option<f32> {
        let d2 = (self.centre - p).length_squared();
        let r2 = self.radius * self.radius;
        if !(d2 > r2) {
            return None;
        }
        let sin2_max = r2 / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let one_minus_cos = sin2_max / (1.0 + cos_max);
        Some(1.0 / (2.0 * PI * one_minus_cos))
    }
}

impl Light for SphereLight {
    /// A direction drawn uniformly from the cone the sphere fills as seen from `p`, and the
    /// point where it meets the sphere's near side: [`sphere_point`]'s point, the
    /// lab's own soft-shadow geometry, with `wi` the unit direction toward it. Every direction
    /// of the cone carries the same radiance, so `li · cos θ / pdf` varies only with cos θ.
    /// `None` from inside or on the sphere.
    #[inline]
    fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let pdf = self.cone_pdf(p)?;
        let point = sphere_point(self.centre, self.radius, p, u.x, u.y);
        Some(LightSample::area(p, point, self.radiance(), |_| pdf))
    }

    /// The cone's uniform density for a `wi` that meets the sphere, else 0.
    #[inline]
    fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        let ray = Ray {
            origin: p,
            direction: wi,
        };
        match self.cone_pdf(p) {
            Some(pdf) if self.intersect(&ray, f32::INFINITY).is_some() => pdf,
            _ => 0.0,
        }
    }

    /// The nearer crossing of the ray with the sphere, from an origin outside it. The distance
    /// from the centre to the ray's line is taken from the component of `origin − centre`
    /// across the ray (not from `b² − c`, which cancels for grazing rays), and the crossing as
    /// `c / (−b + √h)` (the two crossings multiply to `c`), which does not cancel either.
    ///
    /// A ray passing the silhouette within `GRAZING` counts as touching it: the directions
    /// [`Light::sample_li`] draws at the cone's edge can come out that far outside it through
    /// rounding, and must still meet the sphere.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let oc = ray.origin - self.centre;
        let d2 = oc.length_squared();
        let r2 = self.radius * self.radius;
        let c = d2 - r2;
        let b = oc.dot(ray.direction);
        // Inside or on the sphere, or heading away from it: no crossing of its outside.
        if !(c > 0.0) || !(b < 0.0) {
            return None;
        }
        let across = oc - b * ray.direction;
        let h = r2 - across.length_squared();
        if !(h >= -GRAZING * d2) {
            return None;
        }
        let t = c / (h.max(0.0).sqrt() - b);
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// The surface's radiance: the same from every outward direction.
    #[inline]
    fn le(&self, _ray_direction: Vec3) -> Vec3 {
        self.radiance()
    }

    #[inline]
    fn is_delta(&self) -> bool {
        false
    }

    #[inline]
    fn power(&self) -> Vec3 {
        self.power
    }

    /// A point uniform over the surface (every patch emits alike), and from it a direction
    /// cosine-weighted about the outward normal (a Lambertian emitter sends `L cos θ`).
    #[inline]
    fn sample_le(&self, u_point: Vec2, u_direction: Vec2) -> Option<Ray> {
        if !(self.radius > 0.0 && self.radius.is_finite() && self.centre.is_finite()) {
            return None;
        }
        let normal = uniform_sphere(u_point.x, u_point.y);
        let local = cosine_hemisphere(u_direction.x, u_direction.y);
        Some(Ray {
            origin: self.centre + self.radius * normal,
            direction: hemisphere_around(normal, local),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::sampling::Rng;
    use crate::shading::light::checks::{
        AGREEMENT, irradiance, pdf_integral, power_through_sphere, samples_agree,
    };
    use crate::shading::light::direct_light;

    /// The test's sphere: radius 0.25 at (0.1, −0.4, 0.2), 14 W in the colour (1, 0.5, 0.25).
    fn sphere() -> SphereLight {
        SphereLight {
            centre: Vec3::new(0.1, -0.4, 0.2),
            radius: 0.25,
            power: 14.0 * Vec3::new(1.0, 0.5, 0.25),
        }
    }

    /// Points at `ratio` radii from the sphere's centre, in a few directions.
    fn points_around(light: &SphereLight, ratio: f32) -> Vec<Vec3> {
        [
            Vec3::Y,
            -Vec3::Y,
            Vec3::new(0.6, 0.0, -0.8),
            Vec3::new(-0.3, 0.4, 0.5).normalize(),
        ]
        .map(|dir| light.centre + ratio * light.radius * dir)
        .to_vec()
    }

    /// Seen from outside, the sphere lights a surface as the lab's point light of the same
    /// power at its centre does ([`direct_light`], `D = P cos α / (4π d²)`), when all of it is
    /// above the surface's horizon: facing it at d = 1 (4 radii), `D = 14 / (4π) = 1.114085`,
    /// and with the normal turned 50° away, `D = 1.114085 · cos 50° = 0.716120`. 200,000
    /// samples, within `AGREEMENT` = 4 standard errors.
    #[test]
    fn sphere_lights_like_a_point_of_the_same_power() {
        let light = sphere();
        let point = crate::shading::light::LightSpec {
            position: light.centre,
            power: 14.0,
            colour: Vec3::ONE,
            kind: crate::shading::light::LightKind::Point,
        };
        let axis = Vec3::new(0.0, 0.6, 0.8);
        let p = light.centre + axis;
        let (t1, _) = crate::base::sampling::orthonormal_basis(-axis);
        let turned = -axis * 50f32.to_radians().cos() + t1 * 50f32.to_radians().sin();
        for (n, by_hand) in [(-axis, 1.114_085), (turned, 0.716_120)] {
            let d = f64::from(direct_light(&point, p, n).x);
            assert!((d - by_hand).abs() < 1e-5, "{d}");
            let e = irradiance(&light, p, n, 200_000, 21);
            assert!(
                e.agrees_with(d, AGREEMENT),
                "{e:?} against D = {d} ({:.2} standard errors)",
                (e.mean - d) / e.standard_error
            );
            eprintln!("sphere irradiance {e:?}, D = {d}");
        }
    }

    /// `pdf_li` integrates to 1 over the sphere of directions, from just outside the surface
    /// (nearly a hemisphere) to 50 radii away: 600 × 600 stratified directions over a cap a
    /// fifth wider than the sphere, 0 checked outside it.
    #[test]
    fn sphere_pdf_integrates_to_one() {
        let light = sphere();
        for ratio in [1.02, 2.0, 10.0, 50.0] {
            for (i, p) in points_around(&light, ratio).into_iter().enumerate() {
                let integral =
                    pdf_integral(&light, p, light.centre, 1.2 * light.radius, 600, i as u64);
                eprintln!("sphere pdf integral at {ratio} radii: {integral}");
                assert!((integral - 1.0).abs() < 2e-3, "{ratio} radii: {integral}");
            }
        }
    }

    /// Each sample's pdf is `pdf_li`'s for its direction, and the ray along it meets the
    /// sphere at the sample's distance, where `le` is its `li`.
    #[test]
    fn sphere_samples_agree_with_pdf_li_and_intersect() {
        let light = sphere();
        for ratio in [1.02, 2.0, 10.0, 50.0] {
            for (i, p) in points_around(&light, ratio).into_iter().enumerate() {
                let (pdf, distance) = samples_agree(&light, p, 20_000, 100 + i as u64);
                eprintln!("sphere at {ratio} radii: pdf {pdf:e}, distance {distance:e}");
                assert!(pdf == 0.0 && distance < 1e-3, "{ratio}: {pdf} {distance}");
            }
        }
    }

    /// The sphere emits its power: its exitance `π L` (`le`, lab units) times its area is `P`,
    /// and the power leaving an enclosing sphere of twice its radius, estimated from
    /// `intersect` and `le` alone (400,000 rays), is `P = 14` within `AGREEMENT` = 4
    /// standard errors.
    #[test]
    fn sphere_emits_its_power() {
        let light = sphere();
        // Φ = ∫∫ L cos θ dω dA: the exitance of the surface (π L, from `le`, the same at every
        // point and about every outward normal) times the area 4πR² is what `power()` says.
        let area = 4.0 * std::f64::consts::PI * f64::from(light.radius).powi(2);
        for normal in [Vec3::X, -Vec3::Y, Vec3::new(0.48, 0.6, -0.64)] {
            let m = crate::shading::light::checks::exitance(&light, normal, 64);
            for (c, p) in light.power().to_array().into_iter().enumerate() {
                let emitted = m[c] * area;
                let p = f64::from(p);
                assert!(
                    (emitted - p).abs() <= 1e-5 * p,
                    "{normal}, channel {c}: {emitted} {p}"
                );
            }
        }
        let e = power_through_sphere(&light, light.centre, 2.0 * light.radius, 400_000, 8);
        eprintln!("sphere power {e:?}");
        assert!(e.agrees_with(14.0, AGREEMENT), "{e:?}");
    }

    /// From inside or on the sphere nothing of it is seen; from outside, rays heading away or
    /// stopping short miss it.
    #[test]
    fn the_sphere_is_seen_from_outside_only() {
        let light = sphere();
        let inside = light.centre + Vec3::new(0.1, 0.0, 0.05);
        let on = light.centre + light.radius * Vec3::Y;
        let mut rng = Rng::new(4);
        for p in [inside, on, light.centre] {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            assert_eq!(light.sample_li(p, u), None);
            for wi in [Vec3::X, -Vec3::Y, Vec3::new(0.6, 0.0, 0.8)] {
                assert_eq!(light.pdf_li(p, wi), 0.0);
                assert_eq!(light.intersect(&Ray::new(p, wi), f32::INFINITY), None);
            }
        }
        let outside = light.centre + Vec3::new(0.0, 1.0, 0.0);
        let toward = Ray::new(outside, -Vec3::Y);
        assert_eq!(light.intersect(&toward, f32::INFINITY), Some(0.75));
        assert_eq!(light.intersect(&toward, 0.75), None);
        assert_eq!(
            light.intersect(&Ray::new(outside, Vec3::Y), f32::INFINITY),
            None
        );
        assert_eq!(light.pdf_li(outside, Vec3::Y), 0.0);
        assert!(!light.is_delta());
    }

    /// Crossings by hand: the unit sphere at the origin, rays from z = −3 along +z at a
    /// distance `a` from the axis cross it at `t = 3 − √(1 − a²)`: 2 on the axis, 3 − 0.6 = 2.4
    /// at a = 0.8, and none beyond a = 1. The cone from d = 3 has sin θmax = 1/3,
    /// `1 − cos θmax = 1 − √8/3 = 0.0571910`, pdf `1 / (2π · 0.0571910) = 2.782869`.
    #[test]
    fn sphere_crossings_by_hand() {
        let light = SphereLight {
            centre: Vec3::ZERO,
            radius: 1.0,
            power: Vec3::ONE,
        };
        let hit = |a: f32| light.intersect(&Ray::new(Vec3::new(a, 0.0, -3.0), Vec3::Z), 10.0);
        assert_eq!(hit(0.0), Some(2.0));
        assert!((hit(0.8).unwrap() - 2.4).abs() < 1e-6);
        assert_eq!(hit(1.01), None);
        let p = Vec3::new(0.0, 0.0, -3.0);
        let pdf = light.pdf_li(p, Vec3::Z);
        assert!((pdf - 2.782_869).abs() < 1e-5, "{pdf}");
        assert_eq!(light.pdf_li(p, Vec3::X), 0.0);
        // Li = P / (4π R²) = 1 / (4π) = 0.0795775.
        assert!((light.radiance().x - 0.079_577_5).abs() < 1e-7);
    }
}
