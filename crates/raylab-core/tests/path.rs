//! The path tracer (`--stage path`): real light where the lab adds the constant N.
//!
//! Each test asserts numbers: the path tracer with no bounces is the lab's `shadows` stage bit
//! for bit; a closed box of uniform reflectance converges to the value that conservation of
//! energy gives; bounces only ever add light; two ways of sampling the hemisphere agree; the
//! image does not depend on the thread count.

mod common;

use common::{assert_pixels_trace_alone, assert_renders, assert_same_image, on_threads, settings};
use glam::Vec3;
use raylab_core::base::geometry::{Ray, Triangle};
use raylab_core::base::sampling::{Rng, cosine_hemisphere, orthonormal_basis, uniform_hemisphere};
use raylab_core::shapes::scene::{Scene, cornell_box};
use raylab_core::transport::integrator::Tracer;
use raylab_core::transport::render::{render, render_pass};
use raylab_core::{LightSpec, Material, MaterialPreset, Stage};

/// With 0 bounces a path is the camera ray and the lab's direct term: the `shadows` stage
/// (figure 6), bit for bit, at the pixel centres (sample 0).
#[test]
fn path_with_no_bounces_is_the_shadows_stage() {
    let scene = cornell_box();
    let shadows = render(&scene, &settings(Stage::Shadows, 128));
    let mut path = settings(Stage::Path, 128);
    path.shading.bounces = Some(0);
    assert_renders(&scene, &path, &shadows, "no bounces");
    // The indirect switch off means the same.
    let mut off = settings(Stage::Path, 128);
    off.shading.indirect = false;
    assert_renders(&scene, &off, &shadows, "indirect off");
}

/// The closed box for the furnace tests: the lab's room (blocks left out) with its open front
/// closed at z = −1, every surface of reflectance `a`, the light at the centre.
fn closed_box(a: f32) -> Scene {
    let room = cornell_box().triangles[..10].to_vec();
    let v = Vec3::new;
    let front = [
        Triangle::new(
            v(-1.0, -1.0, -1.0),
            v(1.0, 1.0, -1.0),
            v(1.0, -1.0, -1.0),
            0,
        ),
        Triangle::new(
            v(-1.0, -1.0, -1.0),
            v(-1.0, 1.0, -1.0),
            v(1.0, 1.0, -1.0),
            0,
        ),
    ];
    let triangles = room
        .into_iter()
        .map(|t| Triangle::new(t.v0, t.v1, t.v2, 0))
        .chain(front)
        .collect();
    Scene::new(triangles, vec![Material::diffuse("grey", Vec3::splat(a))])
}

/// The mean and standard error of some values.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A furnace test. In a closed box every watt the light emits lands on a wall, and each time
/// light lands, a fraction a is reflected and 1 − a absorbed. With P watts emitted the flux
/// arriving on the walls, summed over every bounce, is Φ = P + aP + a²P + … = P/(1 − a), and
/// the light a diffuse wall reflects, in the lab's units (π × radiance = ρ × irradiance), has
/// the area mean a·Φ/A. For the box of side 2 (A = 24), P = 14 W and a = 0.5:
/// 0.5 · 14 / (0.5 · 24) = 0.583333; for a = 0.8: 0.8 · 14 / (0.2 · 24) = 2.333333.
///
/// The path tracer's value at points spread uniformly over the walls (a ray arriving at each
/// point from inside) must average to that, within 4 standard errors and 1%.
#[test]
fn a_closed_furnace_converges_to_its_analytic_value() {
    for (a, expected, samples) in [(0.5f32, 0.583333f64, 120_000u32), (0.8, 2.333333, 120_000)] {
        let scene = closed_box(a);
        let mut s = settings(Stage::Path, 8);
        s.light = LightSpec {
            position: Vec3::ZERO,
            ..LightSpec::default()
        };
        let tracer = Tracer::new(&scene, &s);
        let mut rng = Rng::new(99);
        let mut values = Vec::with_capacity(samples as usize);
        let mut rays = Vec::new();
        let mut rngs = Vec::new();
        for i in 0..samples {
            // Every triangle has area 2: take them in turn, a uniform point on each.
            let t = &scene.triangles[i as usize % scene.triangles.len()];
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = t.v0 + u * (t.v1 - t.v0) + v * (t.v2 - t.v0);
            let inward = if t.normal.dot(-p) > 0.0 {
                t.normal
            } else {
                -t.normal
            };
            rays.push(Ray::new(p + 0.01 * inward, -inward));
            rngs.push(Rng::for_pixel_sample(7, i, 0, 0));
        }
        let mut out = vec![Vec3::ZERO; rays.len()];
        tracer.trace(&rays, &mut rngs, &mut out);
        values.extend(out.iter().map(|v| f64::from(v.x)));
        let (mean, error) = mean_and_error(&values);
        let off = (mean - expected).abs();
        eprintln!("furnace a = {a}: {mean:.5} ± {error:.5} (expected {expected:.5})");
        assert!(
            off < 4.0 * error && off < 0.01 * expected,
            "a = {a}: mean {mean:.5} ± {error:.5}, expected {expected:.5}"
        );
    }
}

/// With the bounces capped at B a path makes the same random choices for its first B bounces
/// as with more, so each pixel's value can only grow with B: exactly, not just on average.
/// And where every surface but the back wall reflects nothing, bounces add nothing: a pixel
/// that sees the back wall is its direct light, as in the `shadows` stage.
#[test]
fn bounces_only_add_light_and_black_surfaces_add_none() {
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 48);
    s.samples_per_pixel = 1;
    let mut previous: Option<raylab_core::Image> = None;
    for bounces in [0, 1, 2, 3, 5, 8] {
        s.shading.bounces = Some(bounces);
        let image = render_pass(&scene, &s, 3, &|| false).unwrap();
        if let Some(previous) = &previous {
            for (a, b) in previous.pixels.iter().zip(&image.pixels) {
                assert!(b.cmpge(*a).all(), "{bounces} bounces: {b} < {a}");
            }
            let gain: f32 = image.pixels.iter().map(|p| p.x).sum::<f32>()
                - previous.pixels.iter().map(|p| p.x).sum::<f32>();
            assert!(gain > 0.0, "bounce {bounces} added light");
        }
        previous = Some(image);
    }

    // Every material black but the white back wall.
    let mut black = cornell_box();
    for m in &mut black.materials {
        if m.name != "white" {
            m.reflectance = Vec3::ZERO;
        }
    }
    let shadows = render(&black, &settings(Stage::Shadows, 64));
    assert_renders(&black, &settings(Stage::Path, 64), &shadows, "black walls");
}

/// Two estimators of one integral: the light arriving at the floor's centre, E = ∫ L(ω) cos θ
/// dω, where L is what the lab stage shows along ω (over π). Cosine-weighted sampling
/// estimates it as the mean of π·L, uniform sampling as the mean of 2π·L·cos θ; the two
/// must agree within 4 standard errors of their difference (a z-test).
#[test]
fn cosine_and_uniform_hemisphere_sampling_agree() {
    let scene = cornell_box();
    let lab = settings(Stage::Lab, 8);
    let tracer = Tracer::new(&scene, &lab);
    let position = Vec3::new(0.1, 1.0 - 1e-3, 0.2);
    let normal = Vec3::new(0.0, -1.0, 0.0);
    let (t, b) = orthonormal_basis(normal);
    let n = 40_000;
    let mut rng = Rng::new(3);
    let mut cosine_rays = Vec::new();
    let mut uniform_rays = Vec::new();
    let mut cosines = Vec::new();
    for _ in 0..n {
        let c = cosine_hemisphere(rng.next_f32(), rng.next_f32());
        cosine_rays.push(Ray::new(position, t * c.x + b * c.y + normal * c.z));
        let u = uniform_hemisphere(rng.next_f32(), rng.next_f32());
        uniform_rays.push(Ray::new(position, t * u.x + b * u.y + normal * u.z));
        cosines.push(f64::from(u.z));
    }
    let seen = |rays: &[Ray]| {
        let mut out = vec![Vec3::ZERO; rays.len()];
        tracer.trace(rays, &mut [], &mut out);
        out.iter().map(|v| f64::from(v.y)).collect::<Vec<f64>>()
    };
    // In the lab's units the seen value is π·L: E = mean(π·L) = mean(2π·L·cos θ) / ... (both
    // over π·L, so the estimators are mean(V) and mean(2·V·cos θ)).
    let by_cosine = seen(&cosine_rays);
    let by_uniform: Vec<f64> = seen(&uniform_rays)
        .iter()
        .zip(&cosines)
        .map(|(v, c)| 2.0 * v * c)
        .collect();
    let (m1, e1) = mean_and_error(&by_cosine);
    let (m2, e2) = mean_and_error(&by_uniform);
    let z = (m1 - m2) / (e1 * e1 + e2 * e2).sqrt();
    assert!(
        z.abs() < 4.0,
        "cosine {m1:.5} ± {e1:.5}, uniform {m2:.5} ± {e2:.5}, z = {z:.2}"
    );
    // Cosine sampling is the better estimator here: its error is smaller.
    assert!(e1 < e2, "{e1} vs {e2}");
}

/// Same settings and seed, same image, bit for bit, on 1 and 2 threads — with every preset.
#[test]
fn path_traced_images_do_not_depend_on_the_thread_count() {
    let scene = cornell_box();
    for preset in MaterialPreset::ALL {
        let mut s = settings(Stage::Path, 40);
        s.samples_per_pixel = 3;
        s.seed = 11;
        s.material_preset = preset;
        let one = on_threads(1, || render(&scene, &s));
        let two = on_threads(2, || render(&scene, &s));
        assert_same_image(&two, &one, preset);
    }
}

/// A pixel recomputed on its own is exactly the pixel of the image, at any sample.
#[test]
fn a_pixel_can_be_recomputed_alone() {
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 32);
    s.material_preset = MaterialPreset::Both;
    for sample in [0, 5] {
        let image = render_pass(&scene, &s, sample, &|| false).unwrap();
        let pixels = [(0, 0), (16, 16), (20, 25), (31, 31), (10, 28)];
        assert_pixels_trace_alone(&scene, &s, &image, sample, pixels, "path");
    }
}

/// Real indirect light does what the constant N cannot: colour bleeds from wall to wall. On the
/// white back wall (ρ equal in every channel) the purple left wall adds blue beside it, and the
/// yellow right wall adds green beside it; under the lab's constant N every channel of a white
/// pixel gets the same.
#[test]
fn indirect_light_bleeds_colour() {
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 64);
    s.samples_per_pixel = 256;
    let image = render(&scene, &s);
    // The back wall spans pixels 16 to 47 across; these are near its left and right edges,
    // above the blocks.
    let left = image.get(18, 24);
    let right = image.get(45, 24);
    assert!(
        left.z > left.y * 1.05,
        "purple bleeds onto the back wall's left: {left}"
    );
    assert!(
        right.y > right.z * 1.05,
        "yellow bleeds onto its right: {right}"
    );
    // The lab's constant N, by contrast, adds the same to every white pixel's channels.
    let lab = render(&scene, &settings(Stage::Lab, 64));
    let l = lab.get(18, 24);
    assert!((l.x - l.y).abs() < 1e-6 && (l.y - l.z).abs() < 1e-6);
}
