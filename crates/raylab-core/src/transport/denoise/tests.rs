use glam::Vec3;

use super::*;
use crate::base::sampling::Rng;

/// An image of `width × height` whose pixel `(x, y)` is `f(x, y)`.
fn image(width: u32, height: u32, f: impl Fn(u32, u32) -> Vec3) -> Image {
    let mut image = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            image.pixels[(y * width + x) as usize] = f(x, y);
        }
    }
    image
}

/// Gaussian noise of standard deviation `sigma` (Box–Muller), seeded per pixel.
fn noise(seed: u64, x: u32, y: u32, sigma: f32) -> f32 {
    let mut rng = Rng::for_pixel_sample(seed, x, y, 0);
    let (u1, u2) = (rng.next_f32().max(1e-7), rng.next_f32());
    sigma * (-2.0 * u1.ln()).sqrt() * (std::f32::consts::TAU * u2).cos()
}

fn mean(image: &Image) -> Vec3 {
    image.pixels.iter().copied().sum::<Vec3>() / image.pixels.len() as f32
}

#[test]
fn exp_neg_is_e_to_the_minus_x_within_1e_5() {
    for i in 0..=10_000 {
        let x = i as f32 * 0.01;
        let exact = (-x).exp();
        let fast = exp_neg(x);
        assert!(
            (fast - exact).abs() <= 1e-5 * exact + 1e-37,
            "x = {x}: {fast} vs {exact}"
        );
    }
    assert_eq!(exp_neg(0.0), 1.0);
    assert_eq!(exp_neg(f32::NAN), 0.0);
    assert_eq!(exp_neg(f32::INFINITY), 0.0);
    assert_eq!(exp_neg(1e30), 0.0);
    // Below 0 (rounding) is taken as 0.
    assert_eq!(exp_neg(-1e-7), 1.0);
}

/// A constant image is a fixed point of every normalised filter: each output is a weighted
/// mean of equal values.
#[test]
fn a_constant_image_comes_back_unchanged() {
    let colour = image(40, 30, |_, _| Vec3::new(0.3, 0.5, 0.7));
    let features = Features::uniform(40, 30, Vec3::new(0.6, 0.6, 0.6), Vec3::Z, 2.0);
    let variance = vec![0.01; 40 * 30];
    for variance in [Some(&variance[..]), None] {
        let out = Denoiser::default().denoise(&colour, variance, &features);
        for (o, c) in out.pixels.iter().zip(&colour.pixels) {
            assert!((*o - *c).abs().max_element() < 1e-6, "{o} vs {c}");
        }
    }
}

/// Flat noisy light on two surfaces, red (ρ = 0.8, 0.1, 0.1) left and grey (0.2) right: the
/// noise goes, and the edge between them stays sharp, because the albedo is divided out
/// before the filter and multiplied back after.
#[test]
fn a_sharp_albedo_edge_is_kept_and_the_noise_removed() {
    let (w, h) = (64u32, 48u32);
    let red = Vec3::new(0.8, 0.1, 0.1);
    let grey = Vec3::splat(0.2);
    let albedo = |x: u32| if x < w / 2 { red } else { grey };
    let sigma = 0.2f32;
    let colour = image(w, h, |x, y| albedo(x) * (1.0 + noise(7, x, y, sigma)));
    let mut features = Features::uniform(w, h, Vec3::ZERO, Vec3::Z, 3.0);
    for y in 0..h {
        for x in 0..w {
            features.albedo[(y * w + x) as usize] = albedo(x);
        }
    }
    // The variance of each pixel's value, as a film of one-sample-wide spread would give.
    let variance: Vec<f32> = (0..w * h)
        .map(|i| {
            let a = albedo(i % w);
            let m = (a.x + a.y + a.z) / 3.0;
            (m * sigma) * (m * sigma)
        })
        .collect();
    let out = Denoiser::default().denoise(&colour, Some(&variance), &features);
    let row = h / 2;
    for x in [0, w / 2 - 1, w / 2, w - 1] {
        let expected = albedo(x);
        let got = out.get(x, row);
        assert!(
            (got - expected).abs().max_element() < 0.05 * expected.max_element(),
            "pixel {x}: {got} vs {expected}"
        );
    }
    // The light's relative spread falls from 20 % to under 2 %.
    let spread = |image: &Image| {
        let values: Vec<f32> = (0..w * h)
            .map(|i| image.pixels[i as usize].x / albedo(i % w).x - 1.0)
            .collect();
        (values.iter().map(|v| v * v).sum::<f32>() / values.len() as f32).sqrt()
    };
    assert!(spread(&colour) > 0.18, "{}", spread(&colour));
    assert!(spread(&out) < 0.02, "{}", spread(&out));
    // The mean stays.
    let (before, after) = (mean(&colour), mean(&out));
    assert!(
        ((after - before) / before).abs().max_element() < 0.005,
        "{after} vs {before}"
    );
}

/// A shadow's edge is in the light, not in the features: a step from 1 to 0.2 with noise of
/// 2 % is kept, because it is 40 standard deviations tall.
#[test]
fn a_shadow_edge_taller_than_the_noise_is_kept() {
    let (w, h) = (64u32, 32u32);
    let light = |x: u32| if x < w / 2 { 1.0 } else { 0.2 };
    let sigma = 0.02f32;
    let colour = image(w, h, |x, y| Vec3::splat(light(x) + noise(3, x, y, sigma)));
    let features = Features::uniform(w, h, Vec3::ONE, Vec3::Z, 3.0);
    let variance = vec![sigma * sigma; (w * h) as usize];
    let out = Denoiser::default().denoise(&colour, Some(&variance), &features);
    for x in [w / 2 - 2, w / 2 - 1, w / 2, w / 2 + 1] {
        let got = out.get(x, h / 2).x;
        assert!(
            (got - light(x)).abs() < 0.03,
            "pixel {x}: {got} vs {}",
            light(x)
        );
    }
}

/// Two surfaces of one albedo and one light level but facing different ways (a corner) do
/// not mix, and neither do two at different depths: each half keeps its own (different)
/// noise-free light.
#[test]
fn normals_and_depths_keep_surfaces_apart() {
    let (w, h) = (48u32, 24u32);
    let colour = image(w, h, |x, _| Vec3::splat(if x < w / 2 { 0.9 } else { 0.1 }));
    // Noise is claimed everywhere, so only the features can keep the halves apart.
    let variance = vec![0.25; (w * h) as usize];
    let mut by_normal = Features::uniform(w, h, Vec3::ONE, Vec3::Z, 3.0);
    let mut by_depth = by_normal.clone();
    for y in 0..h {
        for x in w / 2..w {
            by_normal.normal[(y * w + x) as usize] = Vec3::X;
            by_depth.depth[(y * w + x) as usize] = 6.0;
        }
    }
    for features in [by_normal, by_depth] {
        let out = Denoiser::default().denoise(&colour, Some(&variance), &features);
        assert!((out.get(w / 2 - 1, h / 2).x - 0.9).abs() < 1e-3);
        assert!((out.get(w / 2, h / 2).x - 0.1).abs() < 1e-3);
    }
}

/// Each pixel is computed on its own from the inputs: the same image on 1, 2 and 3 threads.
#[test]
fn the_result_is_the_same_on_any_thread_count() {
    let (w, h) = (37u32, 29u32);
    let colour = image(w, h, |x, y| Vec3::splat(0.5 + noise(11, x, y, 0.3)));
    let mut features = Features::uniform(w, h, Vec3::splat(0.7), Vec3::Y, 2.0);
    for (i, z) in features.depth.iter_mut().enumerate() {
        *z = 2.0 + (i % 7) as f32 * 0.01;
    }
    let variance = vec![0.09; (w * h) as usize];
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            (
                Denoiser::default().denoise(&colour, Some(&variance), &features),
                Denoiser::default().denoise(&colour, None, &features),
            )
        })
    };
    let one = run(1);
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

/// Images too small for the wider passes, and empty ones, are handled.
#[test]
fn tiny_images() {
    for (w, h) in [(1u32, 1u32), (1, 5), (3, 2)] {
        let colour = image(w, h, |x, y| Vec3::splat((x + y) as f32));
        let features = Features::uniform(w, h, Vec3::ONE, Vec3::Z, 1.0);
        let out = Denoiser::default().denoise(&colour, None, &features);
        assert_eq!((out.width, out.height), (w, h));
        assert!(out.pixels.iter().all(|p| p.is_finite()));
    }
    let empty = Image::new(0, 0);
    let features = Features::uniform(0, 0, Vec3::ONE, Vec3::Z, 1.0);
    assert_eq!(Denoiser::default().denoise(&empty, None, &features), empty);
}

/// The row loop compiled for each instruction set gives the same bits as the portable one:
/// Rust never fuses a multiply and an add, whatever the target features. A set this CPU lacks
/// is skipped with a note, or fails the test where `RAYLAB_REQUIRE_ISA` names it (as the
/// kernels' tests do: [`crate::shapes::accel::skip_unless_required`]).
#[test]
fn every_instruction_set_gives_the_same_bits() {
    let (w, h) = (53u32, 41u32);
    let colour = image(w, h, |x, y| {
        Vec3::new(0.4, 0.5, 0.6) + Vec3::splat(noise(5, x, y, 0.2))
    });
    let mut features = Features::uniform(w, h, Vec3::new(0.7, 0.5, 0.3), Vec3::Z, 2.0);
    for (i, (z, n)) in features
        .depth
        .iter_mut()
        .zip(&mut features.normal)
        .enumerate()
    {
        *z = 2.0 + (i % 11) as f32 * 0.02;
        if i % 13 == 0 {
            *n = Vec3::X;
        }
    }
    let variance = vec![0.04; (w * h) as usize];
    let denoiser = Denoiser::default();
    let portable = denoiser.denoise_with(Isa::Scalar, &colour, Some(&variance), &features);
    for isa in Isa::available_for_tests("every_instruction_set_gives_the_same_bits") {
        let fast = denoiser.denoise_with(isa, &colour, Some(&variance), &features);
        assert_eq!(fast, portable, "{isa:?} against the portable loop");
    }
}

/// Features traced for one light serve the same view under a moved, brighter, tinted light
/// (they are what the camera sees, and the traced buffers are indeed the same), and not a moved
/// camera, another seed or a spherical light (whose soft shadows make the camera's samples
/// draw their jitter differently).
#[test]
fn features_serve_a_moved_light_but_not_a_moved_camera() {
    let scene = crate::shapes::scene::cornell_box();
    let never = || false;
    let mut settings = crate::test_support::path_settings(24, 18);
    settings.texture_preset = crate::shading::material::TexturePreset::CheckerFloor;
    let features = Features::trace(&scene, &settings, &never).unwrap();

    let mut relit = settings.clone();
    relit.light.position = Vec3::new(0.4, -0.2, 0.3);
    relit.light.power = 30.0;
    relit.light.colour = Vec3::new(1.0, 0.5, 0.25);
    relit.samples_per_pixel = 4096;
    assert!(Features::serve(&settings, &relit));
    assert_eq!(Features::trace(&scene, &relit, &never).unwrap(), features);

    let mut moved = settings.clone();
    moved.camera.position.x += 0.1;
    assert!(!Features::serve(&settings, &moved));
    assert_ne!(Features::trace(&scene, &moved, &never).unwrap(), features);
    let mut reseeded = settings.clone();
    reseeded.seed += 1;
    assert!(!Features::serve(&settings, &reseeded));
    let mut sphere = settings.clone();
    sphere.light.kind = crate::shading::light::LightKind::Sphere { radius: 0.1 };
    assert!(!Features::serve(&settings, &sphere));
}
