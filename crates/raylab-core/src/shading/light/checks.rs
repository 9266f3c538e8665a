//! Checks every area light's tests run: Monte Carlo estimates of what a light delivers through
//! [`Light`]'s methods, to compare with closed forms, and the agreement of its methods with one
//! another.

use std::f64::consts::PI;

use glam::{Vec2, Vec3};

use super::Light;
use crate::base::geometry::Ray;
use crate::base::sampling::{Rng, orthonormal_basis, uniform_cone};

/// How many standard errors an estimate may lie from its closed form in the lights' tests,
/// as in the BSDFs'. Their means of 200,000 samples or more are normal to well within the
/// tails used, so a correct light fails a comparison with probability 2·(1 − Φ(4)) = 6.3·10⁻⁵,
/// and the seven comparisons of the sphere and the quad together 4.4·10⁻⁴ (at 3 standard
/// errors: 2.7·10⁻³ each, 1.9 % for the seven), over the choice of seeds; a light whose
/// estimate is off by more than 4 standard errors (0.2–0.5 % here) fails.
pub const AGREEMENT: f64 = 4.0;

/// A Monte Carlo estimate: the mean and its standard error.
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    pub mean: f64,
    pub standard_error: f64,
}

impl Estimate {
    /// The mean and standard error of `samples` values.
    fn of(values: impl Iterator<Item = f64>) -> Self {
        let (mut n, mut sum, mut sum2) = (0u64, 0.0, 0.0);
        for v in values {
            n += 1;
            sum += v;
            sum2 += v * v;
        }
        let n = n as f64;
        let mean = sum / n;
        let variance = (sum2 / n - mean * mean).max(0.0) * n / (n - 1.0);
        Self {
            mean,
            standard_error: (variance / n).sqrt(),
        }
    }

    /// Whether `expected` lies within `k` standard errors of the mean. The lights' tests ask
    /// [`AGREEMENT`] of them.
    pub fn agrees_with(&self, expected: f64, k: f64) -> bool {
        (self.mean - expected).abs() <= k * self.standard_error
    }
}

/// The irradiance the light's first channel gives the point `p` with unit normal `n`, in the
/// lab's D terms (physical irradiance; the lab's ρ·D is ρ times it), estimated from `samples`
/// of [`Light::sample_li`]: the mean of `(1/π) · Li · max(cos θ, 0) / pdf`, Li being π ×
/// radiance. A sample of `None` counts as 0.
pub fn irradiance(light: &dyn Light, p: Vec3, n: Vec3, samples: usize, seed: u64) -> Estimate {
    let mut rng = Rng::new(seed);
    Estimate::of((0..samples).map(|_| {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        match light.sample_li(p, u) {
            Some(s) => {
                let cos = f64::from(s.wi.dot(n).max(0.0));
                f64::from(s.li.x) * cos / f64::from(s.pdf) / PI
            }
            None => 0.0,
        }
    }))
}

/// `∫ pdf_li(p, ω) dω` over the sphere of directions at `p`, by stratified sampling
/// (`strata × strata` cells, one jittered direction each) of the cap of directions toward a
/// sphere `(bound_centre, bound_radius)` that encloses the light (all of the sphere of
/// directions if `p` is inside it); `pdf_li` is also checked to be 0 at `checks` random
/// directions outside that cap.
pub fn pdf_integral(
    light: &dyn Light,
    p: Vec3,
    bound_centre: Vec3,
    bound_radius: f32,
    strata: usize,
    seed: u64,
) -> f64 {
    let mut rng = Rng::new(seed);
    let to_bound = bound_centre - p;
    let d = to_bound.length();
    let axis = to_bound / d;
    let cos_cap = if d > bound_radius {
        let sin = bound_radius / d;
        (1.0 - sin * sin).sqrt()
    } else {
        -1.0
    };
    let (t1, t2) = orthonormal_basis(axis);
    let world = |local: Vec3| (local.x * t1 + local.y * t2 + local.z * axis).normalize();
    let cells = (strata * strata) as f64;
    let mut sum = 0.0f64;
    for i in 0..strata {
        for j in 0..strata {
            let u1 = (i as f32 + rng.next_f32()) / strata as f32;
            let u2 = (j as f32 + rng.next_f32()) / strata as f32;
            let wi = world(uniform_cone(u1, u2, cos_cap));
            sum += f64::from(light.pdf_li(p, wi));
        }
    }
    // Outside the cap: cos θ uniform in [−1, cos_cap), so the directions are uniform there.
    for _ in 0..10_000 {
        if cos_cap <= -1.0 {
            break;
        }
        let z = -1.0 + rng.next_f32() * (cos_cap + 1.0);
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * rng.next_f32();
        let wi = world(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        if wi.dot(axis) < cos_cap {
            assert_eq!(light.pdf_li(p, wi), 0.0, "{wi} outside the light's cap");
        }
    }
    sum / cells * 2.0 * PI * (1.0 - f64::from(cos_cap))
}

/// What [`Light::sample_li`] returns at `p` agrees with the light's other methods, for
/// `samples` samples: `wi` is a unit vector toward `point`, `distance` away; its `pdf` is
/// [`Light::pdf_li`]'s for `wi`; the ray from `p` along `wi` meets the light
/// ([`Light::intersect`]) at `distance`, where [`Light::le`] is the sample's `li`. Returns the
/// largest relative differences of pdf and distance seen.
pub fn samples_agree(light: &dyn Light, p: Vec3, samples: usize, seed: u64) -> (f32, f32) {
    let mut rng = Rng::new(seed);
    let (mut worst_pdf, mut worst_distance) = (0.0f32, 0.0f32);
    for _ in 0..samples {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let s = light.sample_li(p, u).expect("a sample");
        assert!(!s.is_delta && !light.is_delta());
        assert!((s.wi.length() - 1.0).abs() < 1e-5, "{}", s.wi);
        assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{}", s.pdf);
        let along = p + s.distance * s.wi;
        assert!(
            (along - s.point).length() <= 1e-5 * (1.0 + s.distance),
            "{along} {}",
            s.point
        );
        let pdf = light.pdf_li(p, s.wi);
        worst_pdf = worst_pdf.max((pdf - s.pdf).abs() / s.pdf);
        let ray = Ray {
            origin: p,
            direction: s.wi,
        };
        let t = light
            .intersect(&ray, f32::INFINITY)
            .unwrap_or_else(|| panic!("the ray toward {} misses the light", s.point));
        worst_distance = worst_distance.max((t - s.distance).abs() / s.distance);
        assert_eq!(light.le(s.wi), s.li);
        // A ray stopping short of the light does not reach it.
        assert_eq!(light.intersect(&ray, 0.99 * s.distance), None);
    }
    (worst_pdf, worst_distance)
}

/// The total power the light's first channel emits, estimated from [`Light::intersect`] and
/// [`Light::le`] alone as the power leaving a sphere `(centre, radius)` around it: points
/// uniform on that sphere, directions cosine-distributed about its inward normal, each adding
/// `(le/π) · cos θ / pdf` where the ray meets the light, that is `le · 4π radius²`. Every bit
/// of light crosses the enclosing sphere once, so this is `P`.
pub fn power_through_sphere(
    light: &dyn Light,
    centre: Vec3,
    radius: f32,
    samples: usize,
    seed: u64,
) -> Estimate {
    let mut rng = Rng::new(seed);
    let area = 4.0 * PI * f64::from(radius) * f64::from(radius);
    Estimate::of((0..samples).map(|_| {
        let outward = uniform_cone(rng.next_f32(), rng.next_f32(), -1.0);
        let origin = centre + radius * outward;
        let local = crate::base::sampling::cosine_hemisphere(rng.next_f32(), rng.next_f32());
        let direction = crate::base::sampling::hemisphere_around(-outward, local);
        let ray = Ray { origin, direction };
        match light.intersect(&ray, f32::INFINITY) {
            Some(_) => f64::from(light.le(direction).x) * area,
            None => 0.0,
        }
    }))
}

/// The light's exitance from a side of its surface whose outward normal is `normal` (physical
/// power per area, per channel), from [`Light::le`] alone: `∫ L(ω) cos θ dω` over the
/// hemisphere of directions ω leaving that side, `L = le / π` seen along `−ω` (a viewer
/// looking back at the surface). A midpoint rule over `strata × strata` cells even in cos θ
/// and φ: exact for a radiance the same in every direction (cos θ is linear in each cell), as
/// a Lambertian emitter's is.
pub fn exitance(light: &dyn Light, normal: Vec3, strata: usize) -> [f64; 3] {
    let (t1, t2) = orthonormal_basis(normal);
    let n = strata as f64;
    let cell = (1.0 / n) * (2.0 * PI / n);
    let mut sum = [0.0f64; 3];
    for i in 0..strata {
        let cos = (i as f64 + 0.5) / n;
        let sin = (1.0 - cos * cos).sqrt();
        for j in 0..strata {
            let phi = (j as f64 + 0.5) * 2.0 * PI / n;
            let local = Vec3::new(
                (sin * phi.cos()) as f32,
                (sin * phi.sin()) as f32,
                cos as f32,
            );
            let w = local.x * t1 + local.y * t2 + local.z * normal;
            let le = light.le(-w);
            for (s, c) in sum.iter_mut().zip([le.x, le.y, le.z]) {
                *s += f64::from(c) / PI * cos * cell;
            }
        }
    }
    sum
}
