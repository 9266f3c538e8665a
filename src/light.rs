//! The lab's omni light (section 5): a point that sends power `P` equally in all directions.

use std::f32::consts::PI;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geometry::Ray;
use crate::scene::Scene;

/// Distances below this (in scene units) count as this far when dividing by `4πr²`: a light
/// exactly on a surface then gives a large but finite value, never ∞ or NaN.
pub const MIN_LIGHT_DISTANCE: f32 = 1e-3;

/// How far a shadow ray starts off the surface, along the normal: enough that rounding in the
/// hit point can't make the surface shadow itself ("shadow acne"), far below a pixel's size.
pub const SHADOW_OFFSET: f32 = 1e-4;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PointLight {
    pub position: Vec3,
    /// Emitted power per colour channel, in watts (the lab's `lightColor`).
    pub power: Vec3,
}

impl Default for PointLight {
    /// The lab's light: at (0, −0.5, −0.7) with power 14·(1, 1, 1) W.
    fn default() -> Self {
        Self {
            position: Vec3::new(0.0, -0.5, -0.7),
            power: Vec3::splat(14.0),
        }
    }
}

/// The power per area reaching a surface point from the light, ignoring anything in between
/// (lab equation 27):
///
/// `D = P · max(r̂ · n̂, 0) / (4π r²)`
///
/// where `r` is the distance to the light and `r̂` the unit direction toward it. A point facing
/// away from the light (or a zero normal) gets 0. For `r` below [`MIN_LIGHT_DISTANCE`] the
/// light is treated as that far away and straight above the surface.
#[inline]
pub fn direct_light(light: &PointLight, position: Vec3, normal: Vec3) -> Vec3 {
    let to_light = light.position - position;
    let r2 = to_light.length_squared();
    let min_r2 = MIN_LIGHT_DISTANCE * MIN_LIGHT_DISTANCE;
    let (r2, cos) = if r2 < min_r2 {
        (min_r2, normal.length())
    } else {
        (r2, (to_light / r2.sqrt()).dot(normal))
    };
    light.power * cos.max(0.0) / (4.0 * PI * r2)
}

/// The shadow ray from a surface point toward the light, and the distance to stop at (lab
/// section 5.1), or `None` when the light is on the surface (nothing can lie between).
///
/// The ray starts [`SHADOW_OFFSET`] off the surface on the side the light is on, so the surface
/// can't shadow itself, and skips its first [`SHADOW_OFFSET`] along the way: at a corner, the
/// offset point lies in the plane of the neighbouring wall, which would otherwise block it at
/// `t = 0`. It stops [`SHADOW_OFFSET`] short of the light, so a light touching a surface is not
/// hidden by that surface.
#[inline]
pub fn shadow_ray(light: &PointLight, position: Vec3, normal: Vec3) -> Option<(Ray, f32)> {
    let side = if (light.position - position).dot(normal) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let lifted = position + side * SHADOW_OFFSET * normal;
    let to_light = light.position - lifted;
    let distance = to_light.length();
    if !(distance > 3.0 * SHADOW_OFFSET) {
        // The light is at the surface, or a coordinate is not finite.
        return None;
    }
    let direction = to_light / distance;
    let ray = Ray {
        origin: lifted + SHADOW_OFFSET * direction,
        direction,
    };
    Some((ray, distance - 2.0 * SHADOW_OFFSET))
}

/// Whether the segment from a surface point to the light is blocked (lab section 5.1): a shadow
/// ray is cast toward the light and any hit closer than the light shadows the point.
pub fn in_shadow(scene: &Scene, light: &PointLight, position: Vec3, normal: Vec3) -> bool {
    shadow_ray(light, position, normal).is_some_and(|(ray, t_max)| scene.occluded(&ray, t_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::cornell_box;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    #[test]
    fn direct_light_straight_below_the_light() {
        // Light at (0,0,0) with P = 4π W per channel; a floor point 2 below, normal facing it:
        // r = 2, r̂·n̂ = 1, D = 4π·1 / (4π·2²) = 0.25.
        let light = PointLight {
            position: Vec3::ZERO,
            power: Vec3::splat(4.0 * PI),
        };
        let d = direct_light(&light, Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, -1.0, 0.0));
        assert!(close(d, Vec3::splat(0.25), 1e-7), "{d}");
    }

    #[test]
    fn direct_light_at_the_labs_floor_centre() {
        // The lab's light (0, −0.5, −0.7), P = 14; the floor point (0, 1, 0) with n = (0, −1, 0).
        // r = (0, −1.5, −0.7), r² = 2.25 + 0.49 = 2.74, r = 1.655295.
        // r̂·n̂ = 1.5 / 1.655295 = 0.906183.
        // D = 14 · 0.906183 / (4π · 2.74) = 12.686562 / 34.431855 = 0.368454.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
        );
        assert!(close(d, Vec3::splat(0.368_454), 1e-5), "{d}");
    }

    #[test]
    fn direct_light_at_an_angle_on_the_back_wall() {
        // Light at (0, −0.5, −0.7), back wall point (0.5, 0, 1) with n = (0, 0, −1).
        // r = (−0.5, −0.5, −1.7), r² = 0.25 + 0.25 + 2.89 = 3.39, r = 1.841195.
        // r̂·n̂ = 1.7 / 1.841195 = 0.923314.
        // D = 14 · 0.923314 / (4π · 3.39) = 12.926396 / 42.599996 = 0.303437.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.5, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
        );
        assert!(close(d, Vec3::splat(0.303_437), 1e-5), "{d}");
    }

    #[test]
    fn back_facing_gets_nothing() {
        // The floor point below the light, with its normal reversed (facing down, away from the
        // light): r̂·n̂ = −0.906 < 0, so max(r̂·n̂, 0) = 0.
        let d = direct_light(
            &PointLight::default(),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        );
        assert_eq!(d, Vec3::ZERO);
    }

    #[test]
    fn light_on_the_surface_is_finite() {
        let light = PointLight {
            position: Vec3::new(0.0, 1.0, 0.0),
            power: Vec3::splat(14.0),
        };
        let n = Vec3::new(0.0, -1.0, 0.0);
        for p in [Vec3::new(0.0, 1.0, 0.0), Vec3::new(1e-9, 1.0, 0.0)] {
            let d = direct_light(&light, p, n);
            assert!(d.is_finite() && d.x > 0.0, "{d}");
            // r is clamped to 1e-3: D = 14 / (4π · 1e-6) = 1.114085e6.
            assert!((d.x / 1.114_085e6 - 1.0).abs() < 1e-5, "{d}");
        }
        // A neighbour on the same plane is grazed: cos = 0, D = 0.
        assert_eq!(
            direct_light(&light, Vec3::new(0.5, 1.0, 0.0), n),
            Vec3::ZERO
        );
        let scene = cornell_box();
        assert!(!in_shadow(&scene, &light, Vec3::new(0.0, 1.0, 0.0), n));
    }

    #[test]
    fn corners_do_not_shadow_themselves() {
        // Points on the edge where the left wall (x = −1) meets the ceiling (y = −1), lit from
        // inside the box: lifting off one wall leaves the point in the other wall's plane.
        let scene = cornell_box();
        let light = PointLight::default();
        for z in [-0.9, -0.248, 0.0, 0.5, 0.99] {
            let p = Vec3::new(-1.0, -1.0, z);
            for n in [Vec3::X, Vec3::Y] {
                assert!(
                    !in_shadow(&scene, &light, p, n),
                    "corner ({p}) with normal {n}"
                );
            }
        }
        // The floor's corner with the back wall, lit by a light in front of the blocks.
        let p = Vec3::new(0.9, 1.0, 1.0);
        assert!(!in_shadow(&scene, &light, p, Vec3::new(0.0, -1.0, 0.0)));
    }

    #[test]
    fn floor_in_the_tall_blocks_shadow() {
        // The tall (blue) block stands on x ∈ [−0.70, 0.05], z ∈ [−0.11, 0.64] with its top at
        // y = −0.19. The segment from the floor point (−0.45, 1, 0.9) to the light
        // (0, −0.5, −0.7) passes (−0.32, 0.55, 0.42) at 30% of the way: inside the block.
        let scene = cornell_box();
        let light = PointLight::default();
        let p = Vec3::new(-0.45, 1.0, 0.9);
        let n = Vec3::new(0.0, -1.0, 0.0);
        assert!(in_shadow(&scene, &light, p, n));
        // ...while a floor point in front of the blocks is lit.
        assert!(!in_shadow(&scene, &light, Vec3::new(0.0, 1.0, -0.8), n));
        // The unshadowed D at p is positive: shadows, not orientation, make it dark.
        assert!(direct_light(&light, p, n).x > 0.0);
    }
}
