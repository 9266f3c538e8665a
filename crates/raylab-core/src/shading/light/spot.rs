//! A spot light: the lab's point light given a direction (Mitsuba 3's `spot`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::params::KindRules;
use super::{Light, LightSample, MIN_LIGHT_DISTANCE};
use crate::base::camera::{degrees, radians};
use crate::base::geometry::Ray;
use crate::base::invalid::SettingsError;
use crate::base::lanes::Real;
use crate::base::sampling::orthonormal_basis;

/// A spot light's cone, its parameters in `light_kinds!` (which gives its defaults: aimed from
/// the lab's light at (0, 1, −0.2) on the floor, cutoff 25°, beam width 15°): the point it is
/// aimed at, the cutoff angle beyond which it sends nothing and the beam width within which it
/// sends its full intensity (radians, measured from the axis; 0 ≤ beam ≤ cutoff < 90°).
/// Between the two its intensity falls linearly in the angle (Mitsuba 3's `spot`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// The point the spot is aimed at (its axis runs from the light's position to it).
    pub aim: Vec3,
    /// The cutoff angle, in radians.
    pub cutoff: f32,
    /// The beam width, in radians.
    pub beam: f32,
}

/// The smallest cutoff the workbench leaves after an edit, in degrees (the cutoff must be
/// above 0).
const MIN_TIDY_CUTOFF: f64 = 0.5;

impl KindRules for SpotCone {
    /// The aim at least [`MIN_LIGHT_DISTANCE`] from the light (aimed at itself a spot has no
    /// direction), the beam width within the cutoff.
    fn check(&self, position: Vec3) -> Result<(), SettingsError> {
        if !((self.aim - position).length() >= MIN_LIGHT_DISTANCE) {
            let a = self.aim;
            return Err(SettingsError {
                name: "light aim".into(),
                value: format!("({}, {}, {})", a.x, a.y, a.z),
                reason: "must be at least 0.001 from the light's position: a spot aimed at \
                         itself has no direction (--light-aim)",
            });
        }
        if !(self.beam <= self.cutoff) {
            let deg = |a: f32| format!("{}°", degrees(a));
            return Err(SettingsError {
                name: "spot beam".into(),
                value: format!("{} (cutoff {})", deg(self.beam), deg(self.cutoff)),
                reason: "must be from 0° to the cutoff (--spot-beam, --spot-cutoff)",
            });
        }
        Ok(())
    }

    /// The cutoff above 0, the beam never wider than the cutoff.
    fn tidy(&mut self) {
        if self.cutoff <= 0.0 {
            self.cutoff = radians(MIN_TIDY_CUTOFF);
        }
        self.beam = self.beam.min(self.cutoff);
    }
}

/// A point at `position` sending the radiant intensity `intensity · falloff(θ)` (watts per
/// steradian, per channel) in the direction at the angle θ from its `axis`.
///
/// The falloff is Mitsuba 3's: 1 within the beam width β, falling linearly in the angle to 0 at
/// the cutoff γ, `(γ − θ) / (γ − β)`, and 0 beyond ([`SpotLight::falloff`]). The intensity is the
/// lab's omni light's, `I = P · colour / (4π)`, so within the beam the spot lights a surface
/// exactly as the point light of the same `P` does: at distance `r`, in lab units (π ×),
/// `Li = π · I · falloff / r² = P · colour · falloff / (4 r²)`, and a diffuse surface's
/// `(ρ/π) · Li · cos θ` is `ρ · D` with equation 27's `D = I(θ) · max(r̂·n̂, 0) / r²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    /// The unit direction the spot points in (0 for a spot aimed at its own position, which
    /// then lights nothing; [`crate::transport::settings::RenderSettings::validate`] refuses it).
    pub axis: Vec3,
    /// The intensity on the axis, per channel, in W/sr.
    pub intensity: Vec3,
    /// The cutoff angle γ and the beam width β, in radians (0 ≤ β ≤ γ < π/2).
    pub cutoff: f32,
    pub beam: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    /// 1 / (γ − β), or 0 when the two are equal (no falloff zone).
    inv_transition: f32,
}

impl SpotLight {
    /// The spot at `position` aimed as `cone` says, with the omni light's intensity for the
    /// power per channel `power` (`P · colour`): `I = power / (4π)`.
    pub fn new(position: Vec3, power: Vec3, cone: SpotCone) -> Self {
        let transition = cone.cutoff - cone.beam;
        Self {
            position,
            axis: (cone.aim - position).normalize_or_zero(),
            intensity: power / (4.0 * PI),
            cutoff: cone.cutoff,
            beam: cone.beam,
            cos_cutoff: cone.cutoff.cos(),
            cos_beam: cone.beam.cos(),
            inv_transition: if transition > 0.0 {
                1.0 / transition
            } else {
                0.0
            },
        }
    }

    /// The falloff at `cos_theta`, the cosine of the angle θ between the axis and the
    /// direction from the light (one value or sixteen): 1 where `cos θ ≥ cos β`, else
    /// `(γ − acos(cos θ)) / (γ − β)` where `cos θ > cos γ`, else 0.
    #[inline(always)]
    pub fn falloff<R: Real>(&self, cos_theta: R) -> R {
        let (zero, one) = (R::splat(0.0), R::splat(1.0));
        let angle = acos(cos_theta.simd_min(one).simd_max(-one));
        let ramp = (R::splat(self.cutoff) - angle) * R::splat(self.inv_transition);
        let in_beam = cos_theta.simd_ge(R::splat(self.cos_beam));
        let in_cone = cos_theta.simd_gt(R::splat(self.cos_cutoff));
        let ramp = ramp.simd_min(one).simd_max(zero);
        R::select(in_cone, R::select(in_beam, one, ramp), zero)
    }

    /// The falloff toward the point `p` ([`SpotLight::falloff`] of the direction from the
    /// light to `p`); 1 at the light's position itself.
    #[inline]
    pub fn falloff_toward(&self, p: Vec3) -> f32 {
        let from_light = p - self.position;
        let r = from_light.length();
        if !(r > 0.0) {
            return 1.0;
        }
        self.falloff(from_light.dot(self.axis) / r)
    }

    /// `∫ falloff(θ) dω` over the sphere: `2π ∫₀^γ falloff(θ) sin θ dθ`. Within the beam
    /// `∫₀^β sin θ dθ = 1 − cos β`; in the falloff zone, by parts,
    /// `∫_β^γ (γ − θ) sin θ dθ / (γ − β) = cos β − (sin γ − sin β) / (γ − β)`; together
    /// `2π (1 − (sin γ − sin β) / (γ − β))`, which is `2π (1 − cos γ)` when β = γ.
    pub fn solid_angle(&self) -> f64 {
        let (c, b) = (f64::from(self.cutoff), f64::from(self.beam));
        let share = if c - b > 1e-6 {
            1.0 - (c.sin() - b.sin()) / (c - b)
        } else {
            1.0 - c.cos()
        };
        2.0 * std::f64::consts::PI * share
    }

    /// The unnormalised distribution of θ that photons leave in, `∫₀^θ falloff(t) sin t dt`
    /// ([`SpotLight::solid_angle`]'s integral, stopped at θ).
    fn emitted_below(&self, theta: f64) -> f64 {
        let (c, b) = (f64::from(self.cutoff), f64::from(self.beam));
        let theta = theta.min(c);
        if theta <= b || c - b <= 1e-6 {
            return 1.0 - theta.cos();
        }
        1.0 - b.cos()
            + ((c - b) * b.cos() - (c - theta) * theta.cos() - theta.sin() + b.sin()) / (c - b)
    }
}

/// `acos x` for x in [−1, 1] from + − × ÷ and √ alone (Cephes' `acosf`: `asin`'s polynomial
/// after the half-angle reduction for |x| > ½), within 3e−7 rad of the exact value: the same
/// bits for one value or sixteen.
#[inline(always)]
pub fn acos<R: Real>(x: R) -> R {
    let (one, half) = (R::splat(1.0), R::splat(0.5));
    let a = x.copysign(one);
    let big = a.simd_gt(half);
    // |x| > ½: acos |x| = 2 asin √((1 − |x|)/2); else acos x = π/2 − asin x.
    let z_big = half * (one - a);
    let s = R::select(big, z_big.sqrt(), a);
    let z = R::select(big, z_big, a * a);
    let poly =
        (((R::splat(4.216_32e-2) * z + R::splat(2.418_131e-2)) * z + R::splat(4.547_002_6e-2)) * z
            + R::splat(7.495_300_3e-2))
            * z
            + R::splat(1.666_675_2e-1);
    let asin_s = poly * z * s + s;
    let twice = asin_s + asin_s;
    let negative = x.simd_lt(R::ZERO);
    let big_side = R::select(negative, R::splat(PI) - twice, twice);
    let small_side = R::splat(std::f32::consts::FRAC_PI_2) - asin_s.copysign(x);
    R::select(big, big_side, small_side)
}

impl Light for SpotLight {
    /// The one direction toward the light, with `pdf` 1 and `Li = π · I · falloff / r²` (r at
    /// least [`MIN_LIGHT_DISTANCE`]). `None` for `p` at the light or outside the cutoff cone.
    #[inline]
    fn sample_li(&self, p: Vec3, _u: Vec2) -> Option<LightSample> {
        let to_light = self.position - p;
        let r2 = to_light.length_squared();
        if !(r2 > 0.0 && r2 < f32::INFINITY) {
            return None;
        }
        let distance = r2.sqrt();
        let wi = to_light / distance;
        let falloff = self.falloff(-wi.dot(self.axis));
        if !(falloff > 0.0) {
            return None;
        }
        let clamped_r2 = r2.max(MIN_LIGHT_DISTANCE * MIN_LIGHT_DISTANCE);
        Some(LightSample {
            wi,
            li: self.intensity * (PI * falloff / clamped_r2),
            pdf: 1.0,
            distance,
            point: self.position,
            is_delta: true,
        })
    }

    /// 0: a delta light has no density.
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

    /// `I · ∫ falloff dω` ([`SpotLight::solid_angle`]).
    #[inline]
    fn power(&self) -> Vec3 {
        self.intensity * self.solid_angle() as f32
    }

    /// From the point, a direction drawn in proportion to `falloff(θ)`: θ by inverting
    /// `∫₀^θ falloff(t) sin t dt` (bisection in `f64`), φ uniform. Every ray then carries the
    /// same share of [`Light::power`].
    fn sample_le(&self, _u_point: Vec2, u_direction: Vec2) -> Option<Ray> {
        if !(self.position.is_finite() && self.axis.length_squared() > 0.5) {
            return None;
        }
        let target = f64::from(u_direction.x) * self.emitted_below(f64::from(self.cutoff));
        let (mut lo, mut hi) = (0.0f64, f64::from(self.cutoff));
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if self.emitted_below(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let theta = 0.5 * (lo + hi);
        let phi = 2.0 * std::f64::consts::PI * f64::from(u_direction.y);
        let (sin_t, cos_t) = (theta.sin() as f32, theta.cos() as f32);
        let (t1, t2) = orthonormal_basis(self.axis);
        let direction =
            (phi.cos() as f32 * sin_t) * t1 + (phi.sin() as f32 * sin_t) * t2 + cos_t * self.axis;
        Some(Ray {
            origin: self.position,
            direction: direction.normalize(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::camera::radians;
    use crate::base::lanes::F32x16;
    use crate::base::sampling::Rng;
    use crate::shading::light::{LightKind, LightSpec, direct_light};

    /// The spot: the lab's light at (0, −0.5, −0.7), 14 W, aimed at (0, 1, −0.2), cutoff
    /// 25°, beam width 15°: I = 14 / (4π) = 1.1140846 W/sr.
    fn lab_spot() -> LightSpec {
        LightSpec {
            kind: LightKind::Spot(SpotCone::default()),
            ..LightSpec::default()
        }
    }

    /// A point at angle `degrees` from the spot's axis, at distance `r`, with the normal facing
    /// the light.
    fn at_angle(spot: &SpotLight, degrees: f64, r: f32) -> (Vec3, Vec3) {
        let (t1, _) = orthonormal_basis(spot.axis);
        let a = radians(degrees);
        let dir = a.cos() * spot.axis + a.sin() * t1;
        (spot.position + r * dir, -dir)
    }

    #[test]
    fn acos_is_within_3e7_of_the_exact_one_for_one_value_or_sixteen() {
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -1.0 + 2.0 * i as f32 / 200_000.0;
            let ours = acos(x);
            worst = worst.max((f64::from(ours) - f64::from(x).acos()).abs());
            let lanes = acos(F32x16([x; 16]));
            assert!(lanes.0.iter().all(|l| l.to_bits() == ours.to_bits()), "{x}");
        }
        assert!(worst < 3e-7, "{worst}");
    }

    /// On the axis at distance r the irradiance is I/r² exactly: I = 14/(4π), r = 2 gives
    /// 14 / (16π) = 0.2785211 per channel; equation 27's D, and the interface's
    /// `Li · cos / π` too.
    #[test]
    fn on_the_axis_the_irradiance_is_i_over_r_squared() {
        let spec = lab_spot();
        let spot = spec.spot().unwrap();
        assert!((spot.intensity.x - 1.114_084_6).abs() < 1e-6);
        let (p, n) = at_angle(&spot, 0.0, 2.0);
        let d = direct_light(&spec, p, n);
        assert!(
            (d - Vec3::splat(0.278_521_1)).abs().max_element() < 1e-6,
            "{d}"
        );
        let s = spot.sample_li(p, Vec2::ZERO).unwrap();
        let e = s.li * s.wi.dot(n) / PI;
        assert!(
            (e - Vec3::splat(0.278_521_1)).abs().max_element() < 1e-6,
            "{e}"
        );
        // Inside the beam (10° off the axis) the same, and the same as the point light's D.
        let (p, n) = at_angle(&spot, 10.0, 2.0);
        assert!((direct_light(&spec, p, n).x - 0.278_521_1).abs() < 1e-6);
        let point = LightSpec::default();
        assert_eq!(direct_light(&spec, p, n), direct_light(&point, p, n));
    }

    /// Beyond the cutoff (25°) nothing arrives: D = 0 at 25.01°, 40° and behind the light, and
    /// the interface has no sample there.
    #[test]
    fn nothing_beyond_the_cutoff() {
        let spec = lab_spot();
        let spot = spec.spot().unwrap();
        for degrees in [25.01, 40.0, 90.0, 180.0] {
            let (p, n) = at_angle(&spot, degrees, 1.5);
            assert_eq!(direct_light(&spec, p, n), Vec3::ZERO, "{degrees}°");
            assert_eq!(spot.sample_li(p, Vec2::ZERO), None, "{degrees}°");
        }
        let (p, n) = at_angle(&spot, 24.9, 1.5);
        assert!(direct_light(&spec, p, n).x > 0.0);
    }

    /// Half-way through the falloff (20°, between 15° and 25°) the intensity is half: the
    /// irradiance at r = 1, facing the light, is I/2 = 0.5570423; at 17.5° three quarters.
    #[test]
    fn half_at_the_middle_angle_of_the_falloff() {
        let spec = lab_spot();
        let spot = spec.spot().unwrap();
        for (degrees, share) in [(20.0, 0.5), (17.5, 0.75), (22.5, 0.25)] {
            let (p, n) = at_angle(&spot, degrees, 1.0);
            let d = direct_light(&spec, p, n).x;
            assert!((d - 1.114_084_6 * share).abs() < 2e-6, "{degrees}°: {d}");
            let s = spot.sample_li(p, Vec2::ZERO).unwrap();
            let e = s.li.x * s.wi.dot(n) / PI;
            assert!((e - 1.114_084_6 * share).abs() < 2e-6, "{degrees}°: {e}");
            assert!((spot.falloff_toward(p) - share).abs() < 2e-6);
        }
    }

    /// `power()` equals the integral of I(θ) over the sphere, by the midpoint rule in θ (the
    /// falloff computed per angle, φ exactly 2π): for the lab's spot 2π I (1 − (sin 25° −
    /// sin 15°) / (10° in radians)) = 2π · 1.1140846 · 0.0614996 = 0.4304973 W per channel, and
    /// for a few other cones.
    #[test]
    fn power_is_the_integral_of_the_intensity() {
        let by_hand = 0.430_497_3;
        let p = lab_spot().spot().unwrap().power().x;
        assert!(
            (f64::from(p) - by_hand).abs() < 1e-5,
            "{p} against {by_hand}"
        );
        for (cutoff, beam) in [
            (25.0, 15.0),
            (60.0, 0.0),
            (30.0, 30.0),
            (80.0, 70.0),
            (5.0, 1.0),
        ] {
            let cone = SpotCone {
                aim: Vec3::new(0.3, 1.0, 0.2),
                cutoff: radians(cutoff),
                beam: radians(beam),
            };
            let spot = SpotLight::new(Vec3::ZERO, Vec3::splat(14.0), cone);
            let n = 200_000;
            let step = std::f64::consts::PI / n as f64;
            let integral: f64 = (0..n)
                .map(|i| {
                    let theta = (i as f64 + 0.5) * step;
                    f64::from(spot.falloff(theta.cos() as f32)) * theta.sin() * step
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
                * f64::from(spot.intensity.x);
            let power = f64::from(spot.power().x);
            assert!(
                (power - integral).abs() < 2e-5 * integral.max(1e-3),
                "{cutoff}°/{beam}°: {power} against {integral}"
            );
        }
    }

    /// Photon rays leave in proportion to I(θ): the histogram of their angles from the axis in
    /// 25 bins of 1° against each bin's share of `∫ falloff sin θ dθ` (χ², 24 degrees of
    /// freedom: below 51.2, the 0.1 % point); none beyond the cutoff; φ uniform (mean
    /// direction along the axis).
    #[test]
    fn photon_rays_follow_the_falloff() {
        let spot = lab_spot().spot().unwrap();
        let mut rng = Rng::new(9);
        let n = 200_000;
        let bins = 25;
        let mut counts = vec![0u32; bins];
        let mut mean = Vec3::ZERO;
        for _ in 0..n {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let ray = spot.sample_le(Vec2::ZERO, u).unwrap();
            assert_eq!(ray.origin, spot.position);
            assert!((ray.direction.length() - 1.0).abs() < 1e-5);
            let theta = f64::from(ray.direction.dot(spot.axis).min(1.0))
                .acos()
                .to_degrees();
            assert!(theta <= 25.0 + 1e-3, "{theta}");
            counts[(theta as usize).min(bins - 1)] += 1;
            mean += ray.direction / n as f32;
        }
        let total = spot.emitted_below(f64::from(spot.cutoff));
        let mut chi2 = 0.0;
        for (i, &c) in counts.iter().enumerate() {
            let share = (spot.emitted_below((i as f64 + 1.0).to_radians())
                - spot.emitted_below((i as f64).to_radians()))
                / total;
            let expected = share * n as f64;
            chi2 += (f64::from(c) - expected).powi(2) / expected;
        }
        assert!(chi2 < 51.2, "χ² = {chi2}: {counts:?}");
        let across = mean - mean.dot(spot.axis) * spot.axis;
        assert!(across.length() < 0.01, "{mean}");
    }

    /// The interface's `Li · cos / π` equals equation 27's D (with the falloff) at random points
    /// and normals, as the point light's does: the lab stages and the path tracer see the
    /// same light.
    #[test]
    fn the_interface_gives_the_lab_stages_d() {
        let spec = lab_spot();
        let spot = spec.spot().unwrap();
        let mut rng = Rng::new(4);
        let mut lit = 0;
        for _ in 0..20_000 {
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
            let d = direct_light(&spec, p, n);
            // The two find cos θ by different roundings; the falloff's slope (1/10° a radian)
            // makes that a few parts in a million of the point light's D.
            let point = direct_light(
                &LightSpec {
                    kind: LightKind::Point,
                    ..spec
                },
                p,
                n,
            );
            let ours = spot
                .sample_li(p, Vec2::ZERO)
                .map_or(Vec3::ZERO, |s| s.li * s.wi.dot(n).max(0.0) / PI);
            assert!(
                (ours - d).abs().max_element() <= 1e-5 * point.max_element().max(1e-3),
                "{p} {n}: {ours} against {d}"
            );
            lit += usize::from(d.x > 0.0);
        }
        assert!(lit > 100, "{lit}");
    }

    /// A spot aimed at its own position sends nothing and never a NaN (the settings refuse it).
    #[test]
    fn a_spot_aimed_at_itself_is_dark_not_nan() {
        let spec = LightSpec {
            kind: LightKind::Spot(SpotCone {
                aim: LightSpec::default().position,
                ..SpotCone::default()
            }),
            ..LightSpec::default()
        };
        let spot = spec.spot().unwrap();
        assert_eq!(spot.axis, Vec3::ZERO);
        let d = direct_light(&spec, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
        assert_eq!(d, Vec3::ZERO);
        assert_eq!(spot.sample_le(Vec2::ZERO, Vec2::splat(0.5)), None);
        assert!(spot.power().is_finite());
    }
}
