//! The denoiser on real renders: what it gains against more samples, what it keeps (the mean,
//! a texture's edges, the unbiased image beside it), and that its features see what the camera
//! sees.

mod common;

use raylab_core::shading::material::TexturePreset;
use raylab_core::shapes::scene::cornell_box;
use raylab_core::transport::denoise::quality::{mean, measure, relative_mse};
use raylab_core::transport::denoise::{Denoiser, Features, render_denoised};
use raylab_core::transport::render::render;
use raylab_core::{RenderSettings, Stage};

use common::{assert_same_image, on_threads, settings};

/// The path-traced box at 64², 16 samples denoised: closer to a 2,048-sample reference than 32
/// raw samples, under the 16 raw samples' error over 2.5, its mean the raw image's within
/// 0.5 %. A 64² box is mostly edges; at 256², `raylab bench --stage denoise` measures the gain
/// that matters (PERFORMANCE.md, "The denoiser").
#[test]
fn sixteen_denoised_samples_beat_32_raw_ones() {
    let scene = cornell_box();
    let s = settings(Stage::Path, 64);
    let rows = on_threads(2, || {
        measure(&scene, &s, &[16, 32], 2048, &Denoiser::default())
    });
    let (sixteen, raw_32) = (rows[0], rows[1]);
    assert!(
        sixteen.denoised_relative_mse < raw_32.raw_relative_mse,
        "denoised 16: {:.3e}, raw 32: {:.3e}",
        sixteen.denoised_relative_mse,
        raw_32.raw_relative_mse
    );
    assert!(
        sixteen.denoised_relative_mse < sixteen.raw_relative_mse / 2.5,
        "{sixteen:?}"
    );
    assert!(sixteen.denoised_mean_change < 0.005, "{sixteen:?}");
}

/// `render_denoised` gives the render itself bit for bit beside the denoised image, on any
/// thread count, and the denoised image is the same on any thread count too.
#[test]
fn the_raw_image_is_the_render_and_both_are_deterministic() {
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 40);
    s.samples_per_pixel = 4;
    let want = render(&scene, &s);
    let (raw_1, denoised_1) = on_threads(1, || render_denoised(&scene, &s));
    let (raw_3, denoised_3) = on_threads(3, || render_denoised(&scene, &s));
    assert_same_image(&raw_1, &want, "raw image, 1 thread");
    assert_same_image(&raw_3, &want, "raw image, 3 threads");
    let (d1, d3) = (denoised_1.unwrap(), denoised_3.unwrap());
    assert_same_image(&d3, &d1, "denoised image, 3 threads against 1");
    assert_ne!(d1, want, "the denoised image differs from the raw one");
}

/// The lab's stages with a point light and a pinhole are not noisy: nothing to denoise.
#[test]
fn noiseless_renders_are_left_alone() {
    let scene = cornell_box();
    for stage in [Stage::Flat, Stage::Direct, Stage::Shadows, Stage::Lab] {
        let s = settings(stage, 24);
        assert!(!s.is_stochastic());
        let (raw, denoised) = render_denoised(&scene, &s);
        assert!(denoised.is_none(), "{stage}");
        assert_same_image(&raw, &render(&scene, &s), stage);
    }
}

/// A textured lab scene under a sphere light (soft shadows: noisy) at 4 samples: the texture's
/// edges stay as sharp as in a 512-sample reference: the checker floor's contrast (the summed
/// absolute difference of neighbouring pixels in the bottom third, where only the floor is) is
/// within 15 % of the reference's, where a blur would lower it. The noise is only in the
/// penumbrae, and the denoiser must take most of it out: its error against the reference at
/// most half the raw image's (a denoiser that returns its input has a ratio of 1; the bound
/// lies well above the ratio's spread over seeds, so a false failure is not expected). Only 4
/// samples: at 16 the raw image is as close as the denoised one, whose error is then the
/// filter's own smoothing of the texture.
#[test]
fn texture_detail_is_kept_under_soft_shadows() {
    let scene_settings = |samples: u32, seed: u64| {
        let mut s = settings(Stage::Lab, 96);
        s.texture_preset = TexturePreset::Both;
        s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.1 };
        s.samples_per_pixel = samples;
        s.seed = seed;
        s
    };
    let s = scene_settings(4, 1);
    assert!(s.is_stochastic());
    let scene = s.scene.load().unwrap();
    let (raw, denoised) = on_threads(2, || render_denoised(&scene, &s));
    let denoised = denoised.unwrap();
    let reference = on_threads(2, || render(&scene, &scene_settings(512, 2)));
    let (e_raw, e_denoised) = (
        relative_mse(&raw, &reference),
        relative_mse(&denoised, &reference),
    );
    eprintln!("relative MSE: raw {e_raw:.3e}, denoised {e_denoised:.3e}");
    assert!(
        e_denoised < 0.5 * e_raw,
        "{e_denoised:.3e} vs raw {e_raw:.3e}"
    );
    let contrast = |image: &raylab_core::Image| {
        let (w, h) = (image.width, image.height);
        let mut sum = 0.0f32;
        for y in 2 * h / 3..h {
            for x in 1..w {
                sum += (image.get(x, y) - image.get(x - 1, y)).abs().element_sum();
            }
        }
        sum
    };
    let (c_denoised, c_reference) = (contrast(&denoised), contrast(&reference));
    assert!(
        (c_denoised / c_reference - 1.0).abs() < 0.15,
        "floor contrast {c_denoised} vs reference {c_reference}"
    );
    let (m_raw, m_denoised) = (mean(&raw), mean(&denoised));
    assert!(((m_denoised - m_raw) / m_raw).abs().max_element() < 0.005);
}

/// The features at the image's centre are what its ray hits: its distance, its normal turned
/// toward the camera, the albedo of what it hits (the tall block's blue).
#[test]
fn features_see_the_surfaces() {
    let scene = cornell_box();
    let s = settings(Stage::Path, 33);
    let f = Features::trace_samples(&scene, &s, 1, &|| false).unwrap();
    let centre = (16 * 33 + 16) as usize;
    // Sample 0 is the pixel's centre: the features are what its ray hits.
    let hit = scene
        .closest_intersection(&s.camera.primary_ray(16.5, 16.5), f32::INFINITY)
        .unwrap();
    assert_eq!(f.depth[centre], hit.distance);
    let normal = scene.triangles[hit.triangle_index].normal;
    let facing = if normal.z > 0.0 { -normal } else { normal };
    assert!(
        (f.normal[centre] - facing).length() < 1e-5,
        "{}",
        f.normal[centre]
    );
    assert!(f.albedo[centre].max_element() > 0.5, "{}", f.albedo[centre]);
    // Everything the camera sees is hit (a closed box) with a unit normal.
    assert!(f.normal.iter().all(|n| (n.length() - 1.0).abs() < 1e-4));
}

/// Features average the render's own camera samples: with more of them, a pixel on a block's
/// silhouette mixes the block's and the wall's normals (shorter than 1), as its colour mixes
/// both.
#[test]
fn edge_pixels_mix_their_surfaces() {
    let scene = cornell_box();
    let s: RenderSettings = settings(Stage::Path, 64);
    let f = Features::trace_samples(&scene, &s, 16, &|| false).unwrap();
    let mixed = f.normal.iter().filter(|n| n.length() < 0.95).count();
    assert!(mixed > 20, "{mixed} edge pixels");
}

/// The path tracer records, sample by sample, the features that tracing them apart gives from
/// the same camera samples: bit for bit on the box as the lab builds it, and with a mirror and
/// a glass block, whose features both find by following every specular branch
/// (`Tracer::seen_through_specular`), not the lobe a path took: the features of a glass pixel
/// are the same at every sample along one camera ray.
#[test]
fn the_path_tracer_records_the_features_tracing_finds() {
    use raylab_core::shading::material::MaterialPreset;
    use raylab_core::transport::denoise::denoising_film;
    use raylab_core::transport::render::accumulate_pass;
    let scene = cornell_box();
    let never = || false;
    let record = |s: &RenderSettings, samples: u32| {
        let mut film = denoising_film(&scene, s);
        for sample in 0..samples {
            accumulate_pass(&scene, s, sample, &mut film, &never).unwrap();
        }
        Features::recorded(&film)
    };
    let s = settings(Stage::Path, 24);
    let recorded = record(&s, 5).expect("the path tracer records features");
    assert_eq!(
        recorded,
        Features::trace_samples(&scene, &s, 5, &never).unwrap()
    );

    let mut specular = s.clone();
    specular.material_preset = MaterialPreset::Both;
    let recorded = record(&specular, 5).unwrap();
    assert_eq!(
        recorded,
        Features::trace_samples(&scene, &specular, 5, &never).unwrap()
    );
    // Not trivially: where the blocks are a mirror and glass, the features are what they
    // reflect and what is seen through them, farther than the blocks.
    let plain = record(&s, 5).unwrap();
    let farther = recorded
        .depth
        .iter()
        .zip(&plain.depth)
        .filter(|(m, p)| m > p);
    assert!(farther.count() > 20);

    // The lab stages record none: their features are traced apart.
    assert!(record(&settings(Stage::Shadows, 8), 1).is_none());
}

/// The box with a mirror and a glass block (`--material-preset both`) at 96²: `measure`'s
/// figures at `counts` samples, against a 512-sample reference.
fn mirror_and_glass(counts: &[u32]) -> Vec<raylab_core::transport::denoise::quality::QualityRow> {
    use raylab_core::shading::material::MaterialPreset;
    let scene = cornell_box();
    let mut s = settings(Stage::Path, 96);
    s.material_preset = MaterialPreset::Both;
    on_threads(2, || measure(&scene, &s, counts, 512, &Denoiser::default()))
}

/// Mirror and glass denoised at 64 samples come closer to the reference than 384 raw samples
/// (the reference's own noise is in each), the mean within 0.5 %. Each pixel's brightest
/// sample, where it lies 3 standard deviations above the others (most pixels), is taken apart
/// and its light spread over its surface, and the rest filtered with looser normal and depth
/// weights (`denoise::Noisy`): taking apart only the fireflies far above the rest, or features
/// that follow each sample's own lobe through the glass (noisy in step with its colour), fall
/// short of 384 raw samples.
#[test]
fn mirror_and_glass_denoised_beat_384_raw_samples() {
    let rows = mirror_and_glass(&[64, 384]);
    let (sixty_four, raw_384) = (rows[0], rows[1]);
    eprintln!("{rows:?}");
    assert!(
        sixty_four.denoised_relative_mse < raw_384.raw_relative_mse,
        "denoised 64: {:.3e}, raw 384: {:.3e}",
        sixty_four.denoised_relative_mse,
        raw_384.raw_relative_mse
    );
    assert!(sixty_four.denoised_mean_change < 0.005, "{sixty_four:?}");
}

/// No firefly survives denoising. The mirror-and-glass box under a sphere light (radius 0.1)
/// at 64², 64 samples: a diffuse bounce that meets the light in the mirror or through the
/// glass is a firefly (a rare path worth hundreds of ordinary ones: the general path tracer
/// finds the light there by the bounce's direction alone). The pixels the raw image has far
/// too bright (over 4 × the luminance of a 1,024-sample reference + 0.5) are, denoised,
/// within 2 × the reference's + 0.25, as every other pixel is.
#[test]
fn no_firefly_survives_denoising() {
    use raylab_core::shading::material::MaterialPreset;
    let scene = cornell_box();
    let side = 64u32;
    let mut s = settings(Stage::Path, side);
    s.material_preset = MaterialPreset::Both;
    s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.1 };
    s.samples_per_pixel = 64;
    let (raw, denoised) = on_threads(2, || render_denoised(&scene, &s));
    let denoised = denoised.unwrap();
    let mut reference_settings = s.clone();
    reference_settings.samples_per_pixel = 1024;
    reference_settings.seed += 1;
    let reference = on_threads(2, || render(&scene, &reference_settings));
    let lum = |p: glam::Vec3| (p.x + p.y + p.z) / 3.0;
    let too_bright = |image: &raylab_core::Image, i: usize, factor: f32, plus: f32| {
        lum(image.pixels[i]) > factor * lum(reference.pixels[i]) + plus
    };
    let fireflies: Vec<usize> = (0..raw.pixels.len())
        .filter(|&i| too_bright(&raw, i, 4.0, 0.5))
        .collect();
    eprintln!("{} fireflies: {fireflies:?}", fireflies.len());
    // How many there are is chance (a rare path per pixel); one is enough to show removed.
    assert!(
        !fireflies.is_empty(),
        "the raw image has fireflies to remove"
    );
    for i in 0..denoised.pixels.len() {
        assert!(
            !too_bright(&denoised, i, 2.0, 0.25),
            "pixel ({}, {}): denoised {} against the reference's {} (raw {}{})",
            i as u32 % side,
            i as u32 / side,
            lum(denoised.pixels[i]),
            lum(reference.pixels[i]),
            lum(raw.pixels[i]),
            if fireflies.contains(&i) {
                ", a firefly"
            } else {
                ""
            }
        );
    }
}
