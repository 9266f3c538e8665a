//! What the `obj`, `settings_json` and `scene_file` fuzz targets check, in one place for the targets
//! (`fuzz/fuzz_targets/*.rs`) and the regression tests (`tests/fuzz_regressions.rs`), so an
//! input that once failed is replayed through exactly what found it. Depends only on the
//! library and serde_json, which the main package has too.

use std::path::Path;
use std::sync::{Arc, OnceLock};

use raylab_core::shapes::scene::obj::{Placement, parse_obj};
use raylab_core::shapes::scene::spec::model_in_box;
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::teaching::check::{self, Rgb8};
use raylab_core::transport::render::render;
use raylab_core::transport::view::render_view;
use raylab_core::{RenderSettings, Shading, Stage};

/// The largest image side and sample count `settings_json` renders: each run stays quick.
pub const MAX_SIDE: u32 = 16;
pub const MAX_SAMPLES: u32 = 4;

/// OBJ bytes → `parse_obj` → the model standing in the Cornell box, as `--obj FILE` and the
/// workbench's "Load OBJ" build it (`model_in_box`: what `obj_scene_with_warnings` does once
/// the file is read, the texture aside) → an 8 × 8 image of it through the lab stage,
/// smooth-shaded, so the BVH built over whatever the file holds is traversed too. Must never
/// panic, hang or take unbounded memory, whatever the bytes.
pub fn obj(data: &[u8]) {
    let Ok(mesh) = parse_obj(data, Path::new("fuzz.obj")) else {
        return;
    };
    let scene = model_in_box(&mesh, &Placement::FRONT_LEFT, "fuzz");
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(8, 8);
    settings.shading = Shading::for_stage(Stage::Lab);
    settings.shading.smooth = true;
    let image = render(&scene, &settings);
    assert_eq!(image.pixels.len(), 64);
}

/// Bytes → `RenderSettings::from_json` (what `raylab render --settings FILE` reads: a
/// screenshot's sidecar or a bare object) → `validate()`. Valid settings must survive the trip
/// through JSON that screenshots make; the small ones (at most [`MAX_SIDE`]² pixels and
/// [`MAX_SAMPLES`] samples) are rendered on the scene they name ([`scene_for`]: the pool's
/// water, a scene file's glass and mirror models), with their display and their debug view,
/// to find panics in the tracer for any values validation lets through. No pixel may be NaN.
/// Settings `check` takes are checked too, against their own render: exactly the figure, so a
/// 100 % match and the verdict `none`.
pub fn settings_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(settings) = RenderSettings::from_json(text) else {
        return;
    };
    if settings.validate().is_err() {
        return;
    }
    let _ = settings.summary();
    let json = serde_json::to_string(&settings).expect("valid settings serialise");
    let again = RenderSettings::from_json(&json).expect("serialised settings read back");
    assert_eq!(again, settings, "{json}");

    let camera = &settings.camera;
    if camera.width > MAX_SIDE
        || camera.height > MAX_SIDE
        || settings.samples_per_pixel > MAX_SAMPLES
    {
        return;
    }
    let scene = scene_for(&settings.scene);
    let image = render(&scene, &settings);
    assert_eq!(image.pixels.len(), (camera.width * camera.height) as usize);
    if let Some(i) = image.pixels.iter().position(|p| p.is_nan()) {
        panic!("pixel {i} is NaN: {}", settings.summary());
    }
    let rgba = settings.display.to_rgba8(&image.pixels);
    assert_eq!(rgba.len(), 4 * image.pixels.len());
    if settings.view.is_traced() {
        let _ = render_view(&scene, &settings, settings.view, &|| false);
    }
    if check::check_settings(&settings).is_ok() {
        // The lab's display, as `raylab render` writes the PNG a student would check.
        let figure = Rgb8::from_linear(&image);
        let checked = check::check(&scene, &settings, &figure)
            .unwrap_or_else(|e| panic!("{e}: {}", settings.summary()));
        let report = &checked.report;
        assert_eq!(checked.figure, figure, "{}", settings.summary());
        assert_eq!(
            (report.match_share, report.best.mistake.as_str()),
            (1.0, "none"),
            "{}",
            settings.summary()
        );
    }
}

/// The scene fuzzed settings are rendered on: the box, or the pool, or a scene of the box's
/// parts with built-in models, water and surfaces (a scene file's), as they name it. What
/// would read a file (an OBJ, a map) or take long (the million-triangle terrain) is the box:
/// the tracer is what is fuzzed.
fn scene_for(choice: &SceneChoice) -> Arc<Scene> {
    static BOX: OnceLock<Arc<Scene>> = OnceLock::new();
    static POOL: OnceLock<Arc<Scene>> = OnceLock::new();
    let the_box = || Arc::clone(BOX.get_or_init(|| Arc::new(cornell_box())));
    match choice {
        SceneChoice::Cornell => the_box(),
        SceneChoice::Pool => Arc::clone(
            POOL.get_or_init(|| Arc::new(SceneChoice::Pool.load().expect("the pool loads"))),
        ),
        SceneChoice::Custom(spec)
            if spec.terrain.is_none()
                && spec.models.iter().all(|m| m.built_in().is_some())
                && spec.models.len() <= 2 =>
        {
            choice.load().map_or_else(|_| the_box(), Arc::new)
        }
        _ => the_box(),
    }
}

/// Bytes → `raylab_core::files::scene_file::parse` (what `--scene-file FILE` and the workbench's Open read)
/// → settings that are valid, since the parser validates them. They must save and read back to
/// the same settings (a scene file round-trips exactly), and when small, render on the Cornell
/// box as [`settings_json`] does. Model paths resolve against a folder that does not exist, so
/// no file is read: a scene naming a model fails when loaded, never here.
pub fn scene_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let folder = Path::new("/nonexistent-fuzz-folder");
    let Ok(settings) = raylab_core::files::scene_file::parse(text, folder) else {
        return;
    };
    settings
        .validate()
        .expect("the parser validates what it returns");
    if let Ok(saved) = raylab_core::files::scene_file::to_text(&settings, folder) {
        let again = raylab_core::files::scene_file::parse(&saved, folder)
            .unwrap_or_else(|e| panic!("a saved scene file reads back: {e}\n{saved}"));
        assert_eq!(again, settings, "{saved}");
    }
    let _ = settings.scene.memory_estimate();
    settings_json(
        serde_json::to_string(&settings)
            .expect("valid settings serialise")
            .as_bytes(),
    );
}

/// Text → the equation sandbox's lexer, parser and compiler (`sandbox::compile`, what
/// `--equations FILE` and the window's editors run). Each error must lie in the text, on
/// character boundaries, with its line, column and message. What compiles is evaluated over an
/// 8 × 8 recording of the lab's box (traced again with its `d` and `shadowStart` where it
/// writes them): sixteen lanes and one give the same bits, the count of NaN and infinite
/// pixels is the magenta ones', and every pixel's explanation (`Recording::explain`, the
/// inspector's) has the image's value bit for bit and prints.
pub fn sandbox(data: &[u8]) {
    use raylab_core::teaching::sandbox::{self, MAGENTA, Recording, Rendered};
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let equations = match sandbox::compile(text) {
        Ok(equations) => equations,
        Err(errors) => {
            assert!(!errors.is_empty());
            for e in &errors {
                assert!(
                    e.span.start <= e.span.end && e.span.end <= text.len(),
                    "{e:?}"
                );
                assert!(text.is_char_boundary(e.span.start), "{e:?}");
                assert!(
                    e.line >= 1 && e.column >= 1 && !e.message.is_empty(),
                    "{e:?}"
                );
            }
            return;
        }
    };
    static SETTINGS: OnceLock<RenderSettings> = OnceLock::new();
    static LAB: OnceLock<Recording> = OnceLock::new();
    let settings = SETTINGS.get_or_init(|| {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(8, 8);
        s.shading = Shading::for_stage(Stage::Lab);
        s
    });
    let scene = scene_for(&SceneChoice::Cornell);
    let lab = LAB.get_or_init(|| sandbox::record(&scene, settings, &sandbox::Equations::lab()));
    let traced;
    let recording = if lab.fits(&equations) {
        lab
    } else {
        traced = sandbox::record(&scene, settings, &equations);
        &traced
    };
    let bits = |r: &Rendered| -> Vec<u32> {
        r.image
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    let sixteen = recording.evaluate_lanes::<16>(&equations);
    let one = recording.evaluate_lanes::<1>(&equations);
    assert_eq!(bits(&sixteen), bits(&one), "{text:?}");
    let magenta = sixteen
        .image
        .pixels
        .iter()
        .filter(|p| **p == MAGENTA)
        .count();
    assert!(sixteen.non_finite <= magenta, "{text:?}");
    for y in 0..8 {
        for x in 0..8 {
            let e = recording
                .explain(&equations, x, y)
                .expect("a pixel of the image");
            let pixel = sixteen.image.pixels[(y * 8 + x) as usize];
            if e.finite {
                assert_eq!(
                    e.value.map(f32::to_bits),
                    pixel.to_array().map(f32::to_bits)
                );
            } else {
                assert_eq!(pixel, MAGENTA, "{text:?}");
            }
            assert!(!e.to_text().is_empty());
            serde_json::to_string(&e).expect("an explanation serialises");
        }
    }
    assert!(recording.explain(&equations, 8, 0).is_none());
}
