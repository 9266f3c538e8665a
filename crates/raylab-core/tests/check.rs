//! `check`: a student's image against the exact figure and the classic mistakes. Each mistake's
//! figure, written as a file as a student's tracer would write it and read back, is named as
//! the mistake; the exact figure is `none`, anti-aliased too; noise is `unknown`.

#[path = "common/class_folder.rs"]
mod class_folder;
mod common;

use std::path::Path;

use common::{assert_same_image, settings};
use glam::Vec3;
use image::ImageFormat;
use raylab_core::shapes::scene::{Scene, cornell_box};
use raylab_core::teaching::check::mistakes::{Recombined, formula_figures, looks};
use raylab_core::teaching::check::{self, Mistake, Report, Rgb8, read_image};
use raylab_core::transport::render::render;
use raylab_core::{RenderSettings, Stage};

/// Writes `image` to `dir/name` in `format` (JPEG at quality 95), as a student's program
/// would save it, and reads it back as `check` does.
fn written(image: &Rgb8, dir: &Path, name: &str, format: ImageFormat) -> Rgb8 {
    let path = dir.join(name);
    std::fs::write(&path, class_folder::encoded(image, format)).unwrap();
    read_image(&path).unwrap()
}

fn report(scene: &Scene, s: &RenderSettings, image: &Rgb8) -> Report {
    check::check(scene, s, image).unwrap().report
}

/// The settings where `mistake` shows, at 96² (or 120 × 90 where the image must not be
/// square): the lab's figure 7, but for the cosine (the light behind the blocks, shadows off,
/// so their fronts face away from it and only N lights them) and the yaw (15°).
fn where_it_shows(mistake: Mistake) -> RenderSettings {
    let mut s = settings(Stage::Lab, 96);
    match mistake {
        Mistake::UnclampedCos => {
            s.shading.shadows = false;
            s.light.position = Vec3::new(0.0, -0.5, 0.9);
        }
        Mistake::YawSign => s.camera.yaw = 15f32.to_radians(),
        Mistake::Eq24Typo => s.camera = s.camera.with_resolution(120, 90),
        _ => {}
    }
    s
}

/// Mistake `none`, through the recombination of the recorded terms, is the renderer's image
/// bit for bit, in every lab stage with shadows and N on and off, square or not, turned.
#[test]
fn no_mistake_is_the_render_bit_for_bit() {
    let scene = cornell_box();
    for stage in Stage::LAB {
        for (shadows, indirect) in [(false, false), (true, true), (true, false)] {
            let mut s = settings(stage, 48);
            s.camera = s.camera.with_resolution(61, 47);
            s.camera.yaw = 0.3;
            s.shading.shadows = shadows;
            s.shading.indirect = indirect;
            let got = formula_figures(&scene, &s, &[Recombined::Mistake(Mistake::None)]);
            let want = render(&scene, &s);
            assert_same_image(&got[0], &want, format!("{stage} {shadows} {indirect}"));
            assert_eq!(Rgb8::from_linear(&got[0]).data, want.to_rgb8());
        }
    }
}

/// Each mistake's figure, written as PNG (a few as BMP and PPM), is named as that mistake,
/// explaining all of it, with the lab's equation and a fix.
#[test]
fn each_mistake_is_named() {
    let scene = cornell_box();
    let dir = tempfile::tempdir().unwrap();
    for mistake in Mistake::catalogue() {
        let s = where_it_shows(mistake);
        assert!(mistake.applies(&s), "{mistake}");
        let format = match mistake {
            Mistake::No4Pi | Mistake::ShadowAcne => ImageFormat::Bmp,
            Mistake::Gamma | Mistake::FocalHalf => ImageFormat::Pnm,
            _ => ImageFormat::Png,
        };
        for (k, look) in looks(&scene, &s, mistake).iter().enumerate() {
            let image = written(look, dir.path(), &format!("{mistake}-{k}"), format);
            assert_eq!(&image, look, "{mistake}: the file holds the figure");
            let r = report(&scene, &s, &image);
            assert_eq!(r.best.mistake, mistake.name(), "{mistake} look {k}: {r:?}");
            assert_eq!(r.best.explains, 1.0, "{mistake}");
            assert_eq!(r.candidates[0].mistake, mistake);
            assert!(r.match_share < check::RIGHT, "{mistake} changes the figure");
            assert!(!r.best.equation.is_empty() && !r.best.fix.is_empty());
        }
    }
}

/// Acne from another tracer speckles differently: here a third of the lit pixels, chosen at
/// random, take their in-shadow value. Still shadow acne; while shadows in the wrong places
/// (the shadow ray blocked beyond the light: regions, not speckles) are not.
#[test]
fn acne_from_another_tracer_is_acne() {
    let scene = cornell_box();
    let s = settings(Stage::Lab, 96);
    let f = formula_figures(
        &scene,
        &s,
        &[
            Recombined::Mistake(Mistake::None),
            Recombined::EveryShadowRayBlocked,
        ],
    );
    let (figure, dark) = (Rgb8::from_linear(&f[0]), Rgb8::from_linear(&f[1]));
    let mut image = figure.clone();
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for i in 0..image.pixels() {
        // xorshift: a third of the pixels.
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        if state.is_multiple_of(3) {
            image.data[3 * i..3 * i + 3].copy_from_slice(&dark.data[3 * i..3 * i + 3]);
        }
    }
    let r = report(&scene, &s, &image);
    assert_eq!(r.best.mistake, "shadow-acne", "{r:?}");
    assert!(r.match_share < 0.9, "{}", r.match_share);
    assert!(check::speckled(&image, &figure, &dark));
    let beyond = &looks(&scene, &s, Mistake::ShadowBeyondLight)[0];
    assert!(!check::speckled(beyond, &figure, &dark));
}

/// The exact figure is `none`, as PNG and as BMP, and as JPEG (lossy: compared by its blocks'
/// means, with a note).
#[test]
fn the_exact_figure_is_none() {
    let scene = cornell_box();
    let dir = tempfile::tempdir().unwrap();
    for stage in [Stage::Flat, Stage::Direct, Stage::Lab] {
        let s = settings(stage, 96);
        let figure = Rgb8::from_linear(&render(&scene, &s));
        for format in [ImageFormat::Png, ImageFormat::Bmp] {
            let r = report(&scene, &s, &written(&figure, dir.path(), "f", format));
            assert_eq!((r.best.mistake.as_str(), r.match_share), ("none", 1.0));
            assert!(r.notes.is_empty(), "{:?}", r.notes);
        }
        // JPEG's 8×8 blocks blur the edges and ring beside them, but keep each block's mean.
        let path = dir.path().join("f.jpg");
        std::fs::write(&path, class_folder::encoded(&figure, ImageFormat::Jpeg)).unwrap();
        let (jpeg, encoding) = check::read_image_encoded(&path).unwrap();
        assert_eq!(encoding, check::Encoding::Jpeg);
        let r = check::check_encoded(&scene, &s, &jpeg, encoding)
            .unwrap()
            .report;
        assert_eq!(r.best.mistake, "none", "{stage}: {r:?}");
        assert!(
            r.notes[0].starts_with("the image is a JPEG"),
            "{:?}",
            r.notes
        );
    }
}

/// A correct image anti-aliased with 16 samples a pixel is `none`, with a note saying it is
/// anti-aliased, never a mistake.
#[test]
fn an_anti_aliased_figure_is_none_with_a_note() {
    let scene = cornell_box();
    for (stage, side) in [(Stage::Lab, 96), (Stage::Direct, 80)] {
        let s = settings(stage, side);
        let mut many = s.clone();
        many.samples_per_pixel = 16;
        many.seed = 7;
        let image = Rgb8::from_linear(&render(&scene, &many));
        let r = report(&scene, &s, &image);
        assert!(
            r.match_share < check::RIGHT,
            "edges differ: {}",
            r.match_share
        );
        assert_eq!(r.best.mistake, "none", "{r:?}");
        assert!(r.with_edges >= check::RIGHT);
        assert!(r.notes[0].starts_with("anti-aliased"), "{:?}", r.notes);
    }
}

/// Noise, and two mistakes at once, are `unknown`: no single mistake explains them.
#[test]
fn noise_and_two_mistakes_are_unknown() {
    let scene = cornell_box();
    let s = settings(Stage::Lab, 96);
    let mut noise = Rgb8::from_linear(&render(&scene, &s));
    let mut state = 99u64;
    for b in &mut noise.data {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        *b = (state >> 56) as u8;
    }
    let r = report(&scene, &s, &noise);
    assert_eq!(r.best.mistake, "unknown", "{r:?}");
    assert!(r.best.explains < check::WELL && r.best.equation.is_empty());
    assert!(r.best.fix.contains("raylab inspect"));
    // The 4π forgotten, and upside down.
    let no_4pi = &looks(&scene, &s, Mistake::No4Pi)[0];
    let rows = no_4pi.data.chunks_exact(3 * 96).rev();
    let both = Rgb8 {
        data: rows.flatten().copied().collect(),
        ..no_4pi.clone()
    };
    assert_eq!(report(&scene, &s, &both).best.mistake, "unknown");
}

/// Only mistakes that change the figure are offered: none of the light's in the flat stage
/// (ρ alone), none of the shadows' without shadows, no yaw's sign at yaw 0, no equation 24
/// typo on a square image, no red–blue swap on a grey figure.
#[test]
fn only_mistakes_that_change_the_figure_are_offered() {
    let scene = cornell_box();
    let offered = |s: &RenderSettings| -> Vec<Mistake> {
        let figure = Rgb8::from_linear(&render(&scene, s));
        let mut names: Vec<Mistake> = report(&scene, s, &figure)
            .candidates
            .iter()
            .map(|c| c.mistake)
            .collect();
        names.sort_by_key(|m| Mistake::ALL.iter().position(|a| a == m));
        names
    };
    use Mistake::*;
    assert_eq!(
        offered(&settings(Stage::Flat, 48)),
        [FocalHalf, PixelCorner, UpsideDown, Gamma, Bgr]
    );
    // The incoming stage is grey (D + N, white light): red and blue are the same.
    assert_eq!(
        offered(&settings(Stage::Incoming, 48)),
        [
            No4Pi,
            InverseR,
            FlippedNormal,
            FocalHalf,
            LightYFlipped,
            PixelCorner,
            UpsideDown,
            Gamma
        ]
    );
    assert_eq!(
        offered(&settings(Stage::Lab, 48)),
        [
            No4Pi,
            InverseR,
            FlippedNormal,
            NoRho,
            IndirectOutsideRho,
            ShadowAcne,
            ShadowBeyondLight,
            ShadowDropsIndirect,
            FocalHalf,
            LightYFlipped,
            PixelCorner,
            UpsideDown,
            Gamma,
            Bgr
        ]
    );
}

/// The report's JSON: the documented fields, candidates best first.
#[test]
fn the_report_as_json() {
    let scene = cornell_box();
    let s = settings(Stage::Shadows, 64);
    let image = &looks(&scene, &s, Mistake::InverseR)[0];
    let json = serde_json::to_value(report(&scene, &s, image)).unwrap();
    assert_eq!(json["stage"], "shadows");
    assert_eq!(json["size"], serde_json::json!([64, 64]));
    assert!(json["match"].as_f64().unwrap() < 0.9);
    assert_eq!(json["best"]["mistake"], "inverse-r");
    assert_eq!(json["best"]["explains"], 1.0);
    assert!(json["best"]["equation"].as_str().unwrap().contains("27"));
    let shares: Vec<f64> = json["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["explains"].as_f64().unwrap())
        .collect();
    assert!(shares.windows(2).all(|w| w[0] >= w[1]), "{shares:?}");
    assert_eq!(json["candidates"][0]["mistake"], "inverse-r");
    assert!(json["worst_block"]["mean_difference"].as_f64().unwrap() > 0.0);
}

/// Settings beyond the lab's figures, and an image of another size, are refused.
#[test]
fn what_check_refuses() {
    let scene = cornell_box();
    let s = settings(Stage::Lab, 32);
    let figure = Rgb8::from_linear(&render(&scene, &s));
    let mut path = s.clone();
    path.shading.stage = Stage::Path;
    let mut area = s.clone();
    area.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.1 };
    let mut nan = s.clone();
    nan.camera.yaw = f32::NAN;
    for bad in [path, area, nan] {
        assert!(check::check(&scene, &bad, &figure).is_err());
    }
    let small = settings(Stage::Lab, 16);
    let e = check::check(&scene, &small, &figure)
        .unwrap_err()
        .to_string();
    assert!(e.contains("32×32") && e.contains("16×16"), "{e}");
}

/// Scenes with mirror and glass, checked against raylab's own one-sample render of them: the
/// pool (its water) in every lab stage, the box with each material preset, a scene with no
/// blocks and a mirror teapot, and one with a glass teapot standing in the pool.
fn specular_scenes(side: u32) -> Vec<(String, RenderSettings)> {
    use raylab_core::MaterialPreset;
    use raylab_core::shading::material::MaterialKind;
    use raylab_core::shapes::scene::obj::Placement;
    use raylab_core::shapes::scene::spec::{ModelSpec, SceneSpec};
    use raylab_core::shapes::scene::{SceneChoice, water::WaterSpec};
    let mut scenes = Vec::new();
    for stage in Stage::LAB {
        let mut s = settings(stage, side);
        s.scene = SceneChoice::Pool;
        scenes.push((format!("pool, {stage}"), s));
    }
    for preset in [
        MaterialPreset::Mirror,
        MaterialPreset::Glass,
        MaterialPreset::Both,
        MaterialPreset::Rough,
    ] {
        let mut s = settings(Stage::Lab, side);
        s.material_preset = preset;
        scenes.push((format!("{preset} preset"), s));
    }
    let teapot = |kind| ModelSpec {
        kind,
        ..ModelSpec::new("teapot", &Placement::TEAPOT)
    };
    let mut mirror = settings(Stage::Lab, side);
    mirror.scene = SceneChoice::from_spec(SceneSpec {
        blocks: false,
        models: vec![teapot(MaterialKind::Mirror {
            tint: Vec3::splat(0.9),
        })],
        ..SceneSpec::cornell("mirror teapot")
    });
    scenes.push(("mirror teapot".into(), mirror));
    let mut glass = settings(Stage::Shadows, side);
    glass.scene = SceneChoice::from_spec(SceneSpec {
        models: vec![teapot(MaterialKind::Glass {
            ior: 1.5,
            tint: Vec3::ONE,
        })],
        water: Some(WaterSpec::default()),
        ..SceneSpec::cornell("glass teapot in the pool")
    });
    scenes.push(("glass teapot in the pool".into(), glass));
    scenes
}

/// Mirror and glass are followed as the lab stages follow them: the recombination with no
/// mistake is the render bit for bit (the pixels behind a specular hit too), so raylab's own
/// render of a scene with water, glass or a mirror is `none` at a 100 % match, with no note.
#[test]
fn mirror_glass_and_water_are_checked_exactly() {
    for (name, s) in specular_scenes(40) {
        let scene = s.scene.load().unwrap();
        let want = render(&scene, &s);
        let got = formula_figures(&scene, &s, &[Recombined::Mistake(Mistake::None)]);
        assert_same_image(&got[0], &want, &name);
        let figure = Rgb8::from_linear(&want);
        let r = report(&scene, &s, &figure);
        assert_eq!(
            (r.best.mistake.as_str(), r.match_share),
            ("none", 1.0),
            "{name}"
        );
        assert!(r.notes.is_empty(), "{name}: {:?}", r.notes);
    }
}

/// The classic mistakes are still named where mirror and glass show them: each formula
/// mistake's figure of the pool (the floor under the water, the walls in it) and of the mirror
/// teapot is named as that mistake, explaining all of it.
#[test]
fn mistakes_seen_through_water_and_in_a_mirror_are_named() {
    let scenes = specular_scenes(48);
    for (name, s) in scenes
        .iter()
        .filter(|(n, _)| n == "pool, lab" || n == "mirror teapot")
    {
        let scene = s.scene.load().unwrap();
        for mistake in [
            Mistake::No4Pi,
            Mistake::FlippedNormal,
            Mistake::NoRho,
            Mistake::ShadowDropsIndirect,
        ] {
            let look = &looks(&scene, s, mistake)[0];
            let r = report(&scene, s, look);
            assert_eq!(r.best.mistake, mistake.name(), "{name}: {r:?}");
            assert_eq!(r.best.explains, 1.0, "{name}: {mistake}");
            assert!(r.match_share < check::RIGHT, "{name}: {mistake}");
        }
    }
}

/// The figure at `s` with each channel of each pixel moved to the end of its 3 × 3
/// neighbourhood's range (the figure's, [`check::mistakes::figure_with_margin`]) farther from
/// it: wrong wherever the neighbourhood is not one colour, yet within what the anti-aliasing
/// allowance takes everywhere.
fn pushed_to_its_neighbours(scene: &Scene, s: &RenderSettings) -> Rgb8 {
    let figure = Rgb8::from_linear(&render(scene, s));
    let margin = Rgb8::from_linear(&check::mistakes::figure_with_margin(scene, s));
    let mut image = figure.clone();
    for y in 0..figure.height {
        for x in 0..figure.width {
            let f = figure.get(x, y);
            for (c, fc) in f.into_iter().enumerate() {
                let around = (0..3).flat_map(|dy| (0..3).map(move |dx| (x + dx, y + dy)));
                let values: Vec<u8> = around.map(|(mx, my)| margin.get(mx, my)[c]).collect();
                let (lo, hi) = (*values.iter().min().unwrap(), *values.iter().max().unwrap());
                let far = if fc.abs_diff(lo) > fc.abs_diff(hi) {
                    lo
                } else {
                    hi
                };
                image.data[3 * (y * figure.width + x) as usize + c] = far;
            }
        }
    }
    image
}

/// The anti-aliasing allowance never makes a poor match the exact figure: a 1 × 1 image of
/// #123456, a 4 × 4 image and a blurred 4 × 3 render are too small to judge, and a note says
/// so; a 32 × 32 image off the figure wherever its neighbours differ (within what the
/// allowance takes, everywhere) matches too few pixels exactly, and a note says that. None is
/// `none`; the exact figure at each size is.
#[test]
fn a_poor_match_is_not_the_exact_figure_by_its_edges() {
    let scene = cornell_box();
    let at = |w: u32, h: u32| {
        let mut s = settings(Stage::Lab, w);
        s.camera = s.camera.with_resolution(w, h);
        s
    };
    let one = Rgb8 {
        width: 1,
        height: 1,
        data: vec![0x12, 0x34, 0x56],
    };
    let blurred = {
        let figure = Rgb8::from_linear(&render(&scene, &at(4, 3)));
        // A 3 × 3 box blur, clamped at the borders.
        let mut out = figure.clone();
        for y in 0..3i32 {
            for x in 0..4i32 {
                for c in 0..3 {
                    let (mut sum, mut n) = (0u32, 0u32);
                    for (dx, dy) in (-1..=1).flat_map(|dx| (-1..=1).map(move |dy| (dx, dy))) {
                        let (nx, ny) = (x + dx, y + dy);
                        if (0..4).contains(&nx) && (0..3).contains(&ny) {
                            sum += u32::from(figure.get(nx as u32, ny as u32)[c]);
                            n += 1;
                        }
                    }
                    out.data[3 * (y as usize * 4 + x as usize) + c] = (sum / n) as u8;
                }
            }
        }
        out
    };
    let cases = [
        (one, at(1, 1), "too small to judge"),
        (
            pushed_to_its_neighbours(&scene, &at(4, 4)),
            at(4, 4),
            "too small to judge",
        ),
        (blurred, at(4, 3), "too small to judge"),
        (
            pushed_to_its_neighbours(&scene, &at(32, 32)),
            at(32, 32),
            "match the figure exactly: too few",
        ),
    ];
    for (image, s, note) in &cases {
        let size = format!("{}×{}", image.width, image.height);
        let r = report(&scene, s, image);
        assert!(
            r.match_share < check::MIN_EXACT,
            "{size}: {}",
            r.match_share
        );
        assert!(
            r.with_edges >= check::RIGHT,
            "{size}: the allowance would take it"
        );
        assert_ne!(r.best.mistake, "none", "{size}: {r:?}");
        assert!(
            !r.to_text().contains("the image is the exact figure"),
            "{size}"
        );
        assert!(
            r.notes.iter().any(|n| n.contains(note)),
            "{size}: {:?}",
            r.notes
        );
        let exact = Rgb8::from_linear(&render(&scene, s));
        assert_eq!(report(&scene, s, &exact).best.mistake, "none", "{size}");
    }
}
