//! A square area light, level with the ceiling, facing the floor.

use glam::{Vec2, Vec3};

use super::{Light, LightSample};
use crate::base::geometry::Ray;
use crate::base::sampling::{cosine_hemisphere, hemisphere_around};

/// A square of side `side` (above 0), horizontal (in the plane `y = centre.y`) and centred at
/// `centre`, its edges along x and z, emitting the total power `power` (per channel,
/// `P · colour`) uniformly from its area toward +y only: in the lab's space +y points down,
/// so it shines on the floor, like the panel in a Cornell box's ceiling.
///
/// Every point of its front sends the same radiance `L = P / (π S²)` into every direction
/// with y > 0 (its exitance `π L` times its area `S²` is `P`); its back is dark and opaque. In lab units
/// (π ×) a viewer in front sees `Li = π L = P / S²`. Only points with `y > centre.y` are lit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadLight {
    pub centre: Vec3,
    /// Side length in scene units, above 0 (see [`crate::shading::light::emitter`] for size 0).
    pub side: f32,
    /// Total emitted power per channel, `P · colour`, in watts.
    pub power: Vec3,
}

impl QuadLight {
    /// The radiance of its front in lab units, `π L = P / S²`.
    #[inline]
    pub fn radiance(&self) -> Vec3 {
        self.power / (self.side * self.side)
    }

    /// Whether the point `p` is in front of the light (`y > centre.y`), where light from it
    /// arrives.
    #[inline]
    pub fn lights(&self, p: Vec3) -> bool {
        p.y > self.centre.y
    }

    /// The point of the square at `u` (in [0, 1)², across x and z): uniform over its area.
    #[inline]
    fn point_at(&self, u: Vec2) -> Vec3 {
        self.centre + Vec3::new((u.x - 0.5) * self.side, 0.0, (u.y - 0.5) * self.side)
    }

    /// The density per solid angle, seen from `p`, of a point drawn uniformly from the area
    /// at `distance` along a direction making the angle θ with the light's normal
    /// (`cos_light` = cos θ): `distance² / (S² · cos θ)`, the area density `1 / S²` turned
    /// into a density per solid angle (a patch `dA` covers `dA · cos θ / distance²`).
    #[inline]
    fn solid_angle_pdf(&self, distance: f32, cos_light: f32) -> f32 {
        distance * distance / (self.side * self.side * cos_light)
    }
}

impl Light for QuadLight {
    /// A point drawn uniformly over the square (`u` its position across it), the direction
    /// toward it, and its density per solid angle. `None` for `p` behind or level with the
    /// light, which it does not light.
    #[inline]
    fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        if !self.lights(p) {
            return None;
        }
        let point = self.point_at(u);
        Some(LightSample::area(p, point, self.radiance(), |distance| {
            let cos_light = (p.y - self.centre.y) / distance;
            self.solid_angle_pdf(distance, cos_light)
        }))
    }

    /// The density of the point where `wi` meets the square, per solid angle; 0 for a `wi`
    /// that misses it or a `p` it does not light.
    #[inline]
    fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        if !self.lights(p) {
            return 0.0;
        }
        let ray = Ray {
            origin: p,
            direction: wi,
        };
        match self.intersect(&ray, f32::INFINITY) {
            Some(t) => self.solid_angle_pdf(t, -wi.y),
            None => 0.0,
        }
    }

    /// Where the ray crosses the square, from either side: the panel is opaque, its back dark
    /// ([`QuadLight::le`] is 0 there), as a real light's housing is; a path that meets it ends.
    #[inline]
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let t = (self.centre.y - ray.origin.y) / ray.direction.y;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let half = 0.5 * self.side;
        let hit = ray.at(t);
        ((hit.x - self.centre.x).abs() <= half && (hit.z - self.centre.z).abs() <= half)
            .then_some(t)
    }

    /// The front's radiance for a ray travelling toward −y (coming from the side the light
    /// faces), 0 for a ray that would see its back.
    #[inline]
    fn le(&self, ray_direction: Vec3) -> Vec3 {
        if ray_direction.y < 0.0 {
            self.radiance()
        } else {
            Vec3::ZERO
        }
    }

    #[inline]
    fn is_delta(&self) -> bool {
        false
    }

    #[inline]
    fn power(&self) -> Vec3 {
        self.power
    }

    /// A point uniform over the square ([`QuadLight::point_at`], as [`Light::sample_li`]
    /// draws them), and a direction cosine-weighted about +y, the side it shines to.
    #[inline]
    fn sample_le(&self, u_point: Vec2, u_direction: Vec2) -> Option<Ray> {
        if !(self.side > 0.0 && self.side.is_finite() && self.centre.is_finite()) {
            return None;
        }
        let local = cosine_hemisphere(u_direction.x, u_direction.y);
        Some(Ray {
            origin: self.point_at(u_point),
            direction: hemisphere_around(Vec3::Y, local),
        })
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::base::sampling::Rng;
    use crate::shading::light::checks::{
        AGREEMENT, irradiance, pdf_integral, power_through_sphere, samples_agree,
    };

    /// The test's light: side 0.5 at (0.1, −1, 0.2) (the lab's ceiling is y = −1), 14 W in
    /// the colour (1, 0.5, 0.25).
    fn quad(side: f32) -> QuadLight {
        QuadLight {
            centre: Vec3::new(0.1, -1.0, 0.2),
            side,
            power: 14.0 * Vec3::new(1.0, 0.5, 0.25),
        }
    }

    /// The form factor from a small patch to a parallel `a × b` rectangle with one corner
    /// straight above the patch at height `h` (the patch facing it):
    /// `F = 1/(2π) [X/√(1+X²) · atan(Y/√(1+X²)) + Y/√(1+Y²) · atan(X/√(1+Y²))]`, `X = a/h`,
    /// `Y = b/h`. The irradiance a Lambertian rectangle of radiance `L` gives the patch is
    /// `π L F`.
    fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
        let (x, y) = (a / h, b / h);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        ((x / sx) * (y / sx).atan() + (y / sy) * (x / sy).atan()) / (2.0 * PI)
    }

    /// A square of side `s` centred above the patch: four `s/2 × s/2` rectangles, each with a
    /// corner above it.
    fn centred_square_form_factor(s: f64, h: f64) -> f64 {
        4.0 * corner_form_factor(s / 2.0, s / 2.0, h)
    }

    /// The closed forms against numbers worked by hand.
    ///
    /// S = 0.5, h = 1.5: X = Y = 1/6, √(1 + X²) = √37/6, X/√(1 + X²) = 1/√37 = 0.1643990,
    /// atan(0.1643990) = 0.1629415, so each corner gives 2 · 0.1643990 · 0.1629415 / (2π) =
    /// 0.00852670 and the square F = 0.0341068.
    ///
    /// S = 2, h = 1: X = Y = 1, 1/√2 · atan(1/√2) = 0.7071068 · 0.6154797 = 0.4352099, a corner
    /// 2 · 0.4352099 / (2π) = 0.1385316, the square 0.5541264.
    #[test]
    fn square_form_factor_by_hand() {
        assert!((corner_form_factor(0.25, 0.25, 1.5) - 0.008_526_70).abs() < 1e-8);
        assert!((centred_square_form_factor(0.5, 1.5) - 0.034_106_8).abs() < 1e-7);
        assert!((corner_form_factor(1.0, 1.0, 1.0) - 0.138_531_6).abs() < 1e-7);
        assert!((centred_square_form_factor(2.0, 1.0) - 0.554_126_4).abs() < 1e-7);
        // Far away the square is a point source of intensity L·S² (cos θ = 1 straight below):
        // F → S² / (π h²).
        let far = centred_square_form_factor(0.01, 10.0);
        assert!((far / (1e-4 / (PI * 100.0)) - 1.0).abs() < 1e-4, "{far}");
    }

    /// The irradiance at a patch facing the light, estimated from 250,000 of `sample_li`'s
    /// samples, is the closed form `E = π L F = P F / S²` within `AGREEMENT` = 4 standard
    /// errors: straight below the centre of the 0.5 square at h = 1.5, `E = 14 · 0.0341068 / 0.25 = 1.909981`;
    /// below the centre of a 2 × 2 square at h = 1, `E = 14 · 0.5541264 / 4 = 1.939442`; and
    /// below a corner of the 0.5 square at h = 0.5, where only one `S × S` rectangle is above.
    #[test]
    fn quad_irradiance_matches_the_form_factor() {
        let up = -Vec3::Y;
        let cases = [
            (
                0.5f32,
                Vec2::ZERO,
                1.5f32,
                centred_square_form_factor(0.5, 1.5),
            ),
            (2.0, Vec2::ZERO, 1.0, centred_square_form_factor(2.0, 1.0)),
            (
                0.5,
                Vec2::splat(0.25),
                0.5,
                corner_form_factor(0.5, 0.5, 0.5),
            ),
        ];
        for (i, (side, offset, h, f)) in cases.into_iter().enumerate() {
            let light = quad(side);
            let p = light.centre + Vec3::new(offset.x, h, offset.y);
            let expected = 14.0 * f / f64::from(side * side);
            let e = irradiance(&light, p, up, 250_000, 30 + i as u64);
            eprintln!(
                "quad S = {side}, h = {h}: F = {f:.7}, E = {expected:.6}, estimate {e:?} \
                 ({:.2} standard errors)",
                (e.mean - expected) / e.standard_error
            );
            assert!(
                e.agrees_with(expected, AGREEMENT),
                "{e:?} against {expected}"
            );
        }
        assert!((14.0 * centred_square_form_factor(0.5, 1.5) / 0.25 - 1.909_981).abs() < 1e-6);
        assert!((14.0 * centred_square_form_factor(2.0, 1.0) / 4.0 - 1.939_442).abs() < 1e-6);
    }

    /// Points the light shines on: below its centre, far and near, off to the side, below its
    /// edge and nearly level with it.
    fn points_in_front(light: &QuadLight) -> [Vec3; 5] {
        let c = light.centre;
        [
            c + Vec3::new(0.0, 1.5, 0.0),
            c + Vec3::new(0.0, 0.05, 0.0),
            c + Vec3::new(0.7, 1.0, -0.4),
            c + Vec3::new(0.5 * light.side, 0.3, 0.1),
            c + Vec3::new(-0.9, 0.02, 0.3),
        ]
    }

    /// `pdf_li` integrates to 1 over the sphere of directions: 700 × 700 stratified directions
    /// over the cap around a sphere enclosing the square, 0 checked outside it.
    #[test]
    fn quad_pdf_integrates_to_one() {
        let light = quad(0.5);
        let bound = 0.75 * light.side;
        for (i, p) in points_in_front(&light).into_iter().enumerate() {
            let integral = pdf_integral(&light, p, light.centre, bound, 700, i as u64);
            eprintln!("quad pdf integral at {p}: {integral}");
            assert!((integral - 1.0).abs() < 2e-3, "{p}: {integral}");
        }
    }

    /// Each sample's pdf is `pdf_li`'s for its direction, and the ray along it meets the
    /// square at the sample's distance, where `le` is its `li`.
    #[test]
    fn quad_samples_agree_with_pdf_li_and_intersect() {
        let light = quad(0.5);
        for (i, p) in points_in_front(&light).into_iter().enumerate() {
            let (pdf, distance) = samples_agree(&light, p, 20_000, 200 + i as u64);
            eprintln!("quad at {p}: pdf {pdf:e}, distance {distance:e}");
            assert!(pdf < 1e-4 && distance < 1e-4, "{p}: {pdf} {distance}");
        }
    }

    /// The square emits its power: its exitance `π L` (`le`, lab units) times its area is `P`,
    /// and the power leaving an enclosing sphere, estimated from `intersect` and `le` alone
    /// (400,000 rays), is `P = 14` within `AGREEMENT` = 4 standard errors.
    #[test]
    fn quad_emits_its_power() {
        let light = quad(0.5);
        // Φ = ∫∫ L cos θ dω dA over both faces: each face's exitance (π L in front, nothing
        // behind), from `le`, times the area S², is what `power()` says.
        let checks = crate::shading::light::checks::exitance;
        let (front, back) = (checks(&light, Vec3::Y, 64), checks(&light, -Vec3::Y, 64));
        let area = f64::from(light.side).powi(2);
        for (c, p) in light.power().to_array().into_iter().enumerate() {
            let emitted = (front[c] + back[c]) * area;
            let p = f64::from(p);
            assert!(
                (emitted - p).abs() <= 1e-5 * p,
                "channel {c}: {emitted} {p}"
            );
        }
        let e = power_through_sphere(&light, light.centre, light.side, 400_000, 9);
        eprintln!("quad power {e:?}");
        assert!(e.agrees_with(14.0, AGREEMENT), "{e:?}");
    }

    /// The square shines toward +y (down, onto the floor) only. From a point below it (y
    /// greater than the light's), a ray looking up at it (direction with y < 0) sees its
    /// radiance `P / S² = 56`; from above it (on the ceiling's far side) or level with it
    /// nothing is drawn, no direction has a density, and a ray looking down at its back
    /// (y > 0) stops on it and sees nothing.
    #[test]
    fn the_quad_shines_on_the_floor_only() {
        let light = quad(0.5);
        let below = light.centre + Vec3::new(0.0, 1.0, 0.0);
        let s = light.sample_li(below, Vec2::splat(0.5)).unwrap();
        assert_eq!(s.wi, -Vec3::Y);
        assert_eq!(s.li, Vec3::new(56.0, 28.0, 14.0));
        assert_eq!(light.le(-Vec3::Y), Vec3::new(56.0, 28.0, 14.0));
        assert_eq!(
            light.le(Vec3::new(0.3, -0.1, 0.2).normalize()),
            light.radiance()
        );
        assert_eq!(light.intersect(&Ray::new(below, -Vec3::Y), 2.0), Some(1.0));

        let above = light.centre - Vec3::new(0.0, 1.0, 0.0);
        let level = light.centre + Vec3::new(1.0, 0.0, 0.0);
        let mut rng = Rng::new(3);
        for p in [above, level, light.centre] {
            for _ in 0..100 {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                assert_eq!(light.sample_li(p, u), None, "{p}");
            }
            let e = irradiance(&light, p, Vec3::Y, 1000, 1);
            assert_eq!(e.mean, 0.0);
        }
        assert_eq!(light.le(Vec3::Y), Vec3::ZERO);
        assert_eq!(light.le(Vec3::new(0.3, 0.1, 0.2).normalize()), Vec3::ZERO);
        assert_eq!(light.pdf_li(above, Vec3::Y), 0.0);
        // Its back is opaque and dark: a ray from above stops on it and sees nothing.
        assert_eq!(light.intersect(&Ray::new(above, Vec3::Y), 2.0), Some(1.0));
        assert_eq!(light.le(Vec3::Y), Vec3::ZERO);
    }

    /// Crossings and densities by hand: straight up from 1 below the centre the square is at
    /// t = 1, seen square on: pdf = 1² / (0.5² · 1) = 4. Toward a point 0.2 along x from the
    /// centre, distance √1.04, cos θ = 1/√1.04: pdf = 1.04^{3/2} / 0.25 = 4.242384. Past the
    /// edge (x = 0.25) nothing.
    #[test]
    fn quad_crossings_by_hand() {
        let light = quad(0.5);
        let p = light.centre + Vec3::Y;
        assert_eq!(light.pdf_li(p, -Vec3::Y), 4.0);
        let wi = Vec3::new(0.2, -1.0, 0.0).normalize();
        let pdf = light.pdf_li(p, wi);
        assert!((pdf - 4.242_384).abs() < 1e-5, "{pdf}");
        let t = light.intersect(&Ray::new(p, wi), 10.0).unwrap();
        assert!((t - 1.04f32.sqrt()).abs() < 1e-6, "{t}");
        let past = Vec3::new(0.26, -1.0, 0.0).normalize();
        assert_eq!(light.intersect(&Ray::new(p, past), 10.0), None);
        assert_eq!(light.pdf_li(p, past), 0.0);
        // Through the square's inside corner region, along z.
        let inside = Vec3::new(-0.24, -1.0, 0.24).normalize();
        assert!(light.intersect(&Ray::new(p, inside), 10.0).is_some());
        assert!(!light.is_delta());
    }
}
