//! Each lab stage, checked pixel by pixel against the lab's formulas evaluated here, with the
//! lab's own matrix-inverse intersection and no code from the renderer's shading path.

use std::f32::consts::PI;

use glam::Vec3;
use raylab_core::base::geometry::Ray;
use raylab_core::shapes::intersect::intersect_triangle_matrix_inverse;
use raylab_core::shapes::scene::{Scene, cornell_box};
use raylab_core::transport::render::render;
use raylab_core::{RenderSettings, Shading, Stage};

const W: u32 = 96;
const H: u32 = 96;

/// The lab's `ClosestIntersection` with `x = A⁻¹ b`: (t, triangle index).
fn closest(scene: &Scene, ray: &Ray) -> Option<(f32, usize)> {
    closest_from(scene, ray, 0.0)
}

/// The closest hit with `t ≥ t_min`.
fn closest_from(scene: &Scene, ray: &Ray, t_min: f32) -> Option<(f32, usize)> {
    let mut best: Option<(f32, usize)> = None;
    for (i, tri) in scene.triangles.iter().enumerate() {
        if let Some((t, _, _)) = intersect_triangle_matrix_inverse(ray, tri, f32::INFINITY)
            && t >= t_min
            && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, i));
        }
    }
    best
}

/// A pixel by the lab's equations: the value, and what it would be lit and in shadow.
struct Expected {
    value: Vec3,
    lit: Vec3,
    shadowed: Vec3,
}

/// The pixel's value by the lab's equations: 24 (ray), 27 (D), 28 and 30 (R), shadows by §5.1.
fn expected(
    scene: &Scene,
    stage: Stage,
    shadows: bool,
    indirect: bool,
    x: u32,
    y: u32,
) -> Expected {
    let f = W as f32; // the default focal length
    let s = Vec3::new(0.0, 0.0, -3.001);
    let d = Vec3::new(
        x as f32 + 0.5 - W as f32 / 2.0,
        y as f32 + 0.5 - H as f32 / 2.0,
        f,
    );
    let ray = Ray::new(s, d);
    let same = |v| Expected {
        value: v,
        lit: v,
        shadowed: v,
    };
    let Some((t, i)) = closest(scene, &ray) else {
        return same(Vec3::ZERO);
    };
    let tri = &scene.triangles[i];
    let rho = scene.materials[tri.material as usize].reflectance;
    if stage == Stage::Flat {
        return same(rho);
    }
    let p = s + t * ray.direction;
    let light_pos = Vec3::new(0.0, -0.5, -0.7);
    let power = Vec3::splat(14.0);
    let r = light_pos - p;
    let dl = power * (r.normalize().dot(tri.normal)).max(0.0) / (4.0 * PI * r.length_squared());
    let mut blocked = false;
    if shadows && dl != Vec3::ZERO {
        // Shadow ray from just off the surface toward the light; a blocker counts when it lies
        // between the first and the last 1e-4 of the way (the offsets that keep a surface, or
        // the wall it meets at a corner, from shadowing itself). The tracer starts the ray a
        // little back toward the camera instead at a point within 2e-4 of its triangle's edge
        // (`light::shadow_ray`, so that no light outside the box leaks in along its edges); with
        // the lab's light inside the box both rules give the same images, which this test
        // checks pixel for pixel.
        let origin = p + 1e-4 * tri.normal;
        let to_light = light_pos - origin;
        blocked = closest_from(scene, &Ray::new(origin, to_light), 1e-4)
            .is_some_and(|(ts, _)| ts < to_light.length() - 1e-4);
    }
    let n = if indirect {
        Vec3::splat(0.5)
    } else {
        Vec3::ZERO
    };
    let reflect = |incoming: Vec3| match stage {
        Stage::Incoming => incoming,
        Stage::Direct | Stage::Shadows | Stage::Lab => rho * incoming,
        Stage::Flat | Stage::Path => {
            unreachable!("{stage:?}: flat returns above, path is not a lab figure")
        }
    };
    let (lit, shadowed) = (reflect(dl + n), reflect(n));
    Expected {
        value: if blocked { shadowed } else { lit },
        lit,
        shadowed,
    }
}

fn check(stage: Stage, shadows: bool, indirect: bool) {
    let scene = cornell_box();
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(W, H);
    settings.shading = Shading {
        stage,
        shadows,
        indirect,
        ..Shading::for_stage(stage)
    };
    let image = render(&scene, &settings);
    // Every pixel. The renderer and this test decide shadows with different intersection code
    // (Cramer's rule against A⁻¹b), so a shadow ray grazing a block's edge may go either way:
    // such a pixel must then be exactly lit or exactly shadowed, and such pixels must be rare.
    let mut shadow_edge_flips = 0;
    for y in 0..H {
        for x in 0..W {
            let want = expected(&scene, stage, shadows, indirect, x, y);
            let got = image.get(x, y);
            let tol = 1e-4 * want.value.max_element().max(1.0);
            let near = |v: Vec3| (got - v).abs().max_element() <= tol;
            if near(want.value) {
                continue;
            }
            assert!(
                shadows && (near(want.lit) || near(want.shadowed)),
                "{stage} shadows={shadows} indirect={indirect} pixel ({x},{y}): got {got}, want {}",
                want.value
            );
            shadow_edge_flips += 1;
        }
    }
    assert!(
        shadow_edge_flips <= 10,
        "{shadow_edge_flips} pixels differ at shadow edges"
    );
}

#[test]
fn flat_is_rho() {
    check(Stage::Flat, false, false);
}

#[test]
fn incoming_is_d() {
    check(Stage::Incoming, false, false);
}

#[test]
fn incoming_with_indirect_is_t() {
    check(Stage::Incoming, false, true);
}

#[test]
fn direct_is_rho_times_d() {
    check(Stage::Direct, false, false);
}

#[test]
fn shadows_stage_blocks_d() {
    check(Stage::Shadows, true, false);
}

#[test]
fn lab_is_rho_times_d_plus_n() {
    check(Stage::Lab, true, true);
}

#[test]
fn lab_without_shadows() {
    check(Stage::Lab, false, true);
}

/// Figure 7 at one pixel, by hand. A 1×1 image's only ray points exactly forward. From the
/// camera moved to (0.5, −0.5, −3.001) it passes above both blocks and meets the white back wall
/// (ρ = 0.75, n = (0, 0, −1)) at p = (0.5, −0.5, 1).
/// r = light − p = (0, −0.5, −0.7) − (0.5, −0.5, 1) = (−0.5, 0, −1.7);
/// r² = 0.25 + 2.89 = 3.14, r = 1.772005; r̂·n̂ = 1.7 / 1.772005 = 0.959365.
/// D = 14 · 0.959365 / (4π · 3.14) = 13.431110 / 39.458404 = 0.340386 (equation 27).
/// The shadow ray stays at y = −0.5, above both block tops (y = −0.19 and 0.41; y points down),
/// so p is lit. R = ρ ∗ (D + N) = 0.75 · (0.340386 + 0.5) = 0.630290 (equation 30).
#[test]
fn figure_7_pixel_by_hand() {
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(1, 1);
    settings.camera.position = Vec3::new(0.5, -0.5, -3.001);
    let image = render(&cornell_box(), &settings);
    let got = image.get(0, 0);
    assert!(
        (got - Vec3::splat(0.630_290)).abs().max_element() < 1e-5,
        "{got}"
    );
}
