//! The workload that chooses the kernels ([`crate::shapes::accel::calibrate`]): the lab's box and the
//! box with a ball in it, with the default camera's rays and the shadow rays from their hits to
//! the lab's light. The scene module makes it because it knows scenes, cameras and lights; the
//! acceleration structures only trace what they are handed.

use glam::Vec3;

use super::cornell_triangles;
use crate::base::camera::{Camera, primary_rays};
use crate::base::geometry::Triangle;
use crate::shading::light::{LightSpec, shadow_ray};
use crate::shapes::accel::calibrate::{Calibration, Workload};
use crate::shapes::accel::{Accel, AccelKind, Isa};

/// The camera's resolution for the workload: 96 × 96 rays.
const SIDE: u32 = 96;

/// The kernels every structure uses unless told otherwise: the set forced by `--isa` or
/// `RAYLAB_ISA`, else the fastest on [`workloads`], measured once per process.
pub fn best_isa() -> Isa {
    Isa::best_with(workloads)
}

/// What [`best_isa`] measured, if it measured (not when forced).
pub fn calibration() -> Option<&'static Calibration> {
    Isa::calibration()
}

/// The scenes the kernels are timed on, each with its rays.
pub fn workloads() -> Vec<Workload> {
    vec![workload(cornell_triangles()), workload(ball_in_box())]
}

/// A scene and the rays the renderer would cast in it: the default camera's rays through every
/// pixel centre, and the shadow rays from their hits to the lab's light.
fn workload(triangles: Vec<Triangle>) -> Workload {
    let primary = primary_rays(&Camera::default_for(SIDE, SIDE));
    let reference = Accel::build(&triangles, AccelKind::Bvh2, Isa::Scalar);
    // The lab's shadow rays (`light::shadow_ray`), from the hits of the reference
    // traversal (no kernel set is chosen yet).
    let light = LightSpec::default();
    let shadow = primary
        .iter()
        .filter_map(|ray| {
            let hit = reference.closest(&triangles, ray, f32::INFINITY)?;
            let normal = triangles[hit.index as usize].normal;
            shadow_ray(&light, ray.at(hit.t), normal, None)
        })
        .collect();
    Workload {
        triangles,
        primary,
        shadow,
    }
}

/// The Cornell box with a ball of 1,152 triangles on its floor: enough triangles for the wide
/// BVH (the bunny's and teapot's structure), few enough to build in a fraction of a millisecond.
fn ball_in_box() -> Vec<Triangle> {
    let mut triangles = cornell_triangles();
    let (centre, radius) = (Vec3::new(-0.3, 0.6, -0.2), 0.4);
    let (rings, segments) = (24, 24);
    let point = |ring: u32, segment: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * segment as f32 / segments as f32;
        centre
            + radius
                * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
    };
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (point(ring, segment), point(ring, segment + 1));
            let (c, d) = (point(ring + 1, segment), point(ring + 1, segment + 1));
            triangles.push(Triangle::new(a, b, c, 0));
            triangles.push(Triangle::new(b, d, c, 0));
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::accel::calibrate::{TIE, calibrate};

    #[test]
    fn the_chosen_set_is_one_measured_and_within_the_tie_of_the_fastest() {
        let c = calibrate(&workloads());
        let fastest = c.timings.iter().map(|t| t.1).min().unwrap();
        let chosen = c
            .timings
            .iter()
            .find(|(isa, _)| isa.name() == c.chosen.name())
            .expect("the chosen set was measured");
        assert!(chosen.1.as_secs_f64() <= fastest.as_secs_f64() * (1.0 + TIE));
        assert!(c.summary().starts_with(c.chosen.name()), "{}", c.summary());
        // Never the scalar loop when the CPU has SIMD kernels.
        if Isa::available().len() > 1 {
            assert!(!matches!(c.chosen, Isa::Scalar));
        }
    }

    #[test]
    fn the_workload_uses_both_structures_and_casts_shadow_rays() {
        let [room, ball] = <[Workload; 2]>::try_from(workloads()).ok().unwrap();
        assert_eq!(ball.triangles.len(), 30 + 2 * 24 * 24);
        let flat = Accel::build(&room.triangles, AccelKind::Auto, Isa::Scalar);
        let tree = Accel::build(&ball.triangles, AccelKind::Auto, Isa::Scalar);
        assert_eq!(
            (flat.kind(), tree.kind()),
            (AccelKind::Flat, AccelKind::Bvh8)
        );
        for w in [&room, &ball] {
            assert_eq!(w.primary.len(), (SIDE * SIDE) as usize);
            // Every camera ray hits the closed box; most hits see the light.
            assert!(w.shadow.len() > w.primary.len() / 2);
        }
    }
}
