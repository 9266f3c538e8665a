//! Each lab stage, checked pixel by pixel against the lab's formulas evaluated here, with the
//! lab's own matrix-inverse intersection and no code from the renderer's shading path.

use std::f32::consts::PI;

use glam::Vec3;
use raylab::geometry::Ray;
use raylab::intersect::intersect_triangle_matrix_inverse;
use raylab::render::render;
use raylab::scene::{Scene, cornell_box};
use raylab::{RenderSettings, Shading, Stage};

const W: u32 = 96;
const H: u32 = 96;

/// The lab's `ClosestIntersection` with `x = A⁻¹ b`: (t, triangle index).
fn closest(scene: &Scene, ray: &Ray) -> Option<(f32, usize)> {
    let mut best: Option<(f32, usize)> = None;
    for (i, tri) in scene.triangles.iter().enumerate() {
        if let Some((t, _, _)) = intersect_triangle_matrix_inverse(ray, tri, f32::INFINITY)
            && best.is_none_or(|(bt, _)| t < bt)
        {
            best = Some((t, i));
        }
    }
    best
}

/// The pixel's value by the lab's equations: 24 (ray), 27 (D), 28 and 30 (R), shadows by §5.1.
fn expected(scene: &Scene, stage: Stage, shadows: bool, indirect: bool, x: u32, y: u32) -> Vec3 {
    let f = W as f32; // the default focal length
    let s = Vec3::new(0.0, 0.0, -3.001);
    let d = Vec3::new(
        x as f32 + 0.5 - W as f32 / 2.0,
        y as f32 + 0.5 - H as f32 / 2.0,
        f,
    );
    let ray = Ray::new(s, d);
    let Some((t, i)) = closest(scene, &ray) else {
        return Vec3::ZERO;
    };
    let tri = &scene.triangles[i];
    let rho = scene.materials[tri.material as usize].reflectance;
    if stage == Stage::Flat {
        return rho;
    }
    let p = s + t * ray.direction;
    let light_pos = Vec3::new(0.0, -0.5, -0.7);
    let power = Vec3::splat(14.0);
    let r = light_pos - p;
    let mut dl = power * (r.normalize().dot(tri.normal)).max(0.0) / (4.0 * PI * r.length_squared());
    if shadows && dl != Vec3::ZERO {
        // Shadow ray from just off the surface toward the light.
        let origin = p + 1e-4 * tri.normal;
        let to_light = light_pos - origin;
        if let Some((ts, _)) = closest(scene, &Ray::new(origin, to_light))
            && ts < to_light.length() - 1e-4
        {
            dl = Vec3::ZERO;
        }
    }
    let n = if indirect {
        Vec3::splat(0.5)
    } else {
        Vec3::ZERO
    };
    match stage {
        Stage::Incoming => dl + n,
        _ => rho * (dl + n),
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
    let mut compared = 0;
    // A grid of pixels over the whole image, plus a few chosen ones: under the blocks, on them.
    let mut pixels: Vec<(u32, u32)> = (0..W)
        .step_by(7)
        .flat_map(|x| (0..H).step_by(5).map(move |y| (x, y)))
        .collect();
    pixels.extend([(30, 80), (60, 70), (48, 48), (20, 65), (75, 60)]);
    for (x, y) in pixels {
        let want = expected(&scene, stage, shadows, indirect, x, y);
        let got = image.get(x, y);
        // Pixels right at a shadow's edge may flip between the two shadow-ray set-ups.
        let tol = 1e-4 * want.max_element().max(1.0);
        if (got - want).abs().max_element() > tol {
            let lit = expected(&scene, stage, false, indirect, x, y);
            assert!(
                shadows && (got - lit).abs().max_element() <= tol || got == want * 0.0,
                "{stage} shadows={shadows} indirect={indirect} pixel ({x},{y}): got {got}, want {want}"
            );
        }
        compared += 1;
    }
    assert!(compared > 250);
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
