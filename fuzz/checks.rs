//! What the `obj`, `settings_json` and `scene_file` fuzz targets check, in one place for the targets
//! (`fuzz/fuzz_targets/*.rs`) and the regression tests (`tests/fuzz_regressions.rs`), so an
//! input that once failed is replayed through exactly what found it. Depends only on the
//! library and serde_json, which the main package has too.

use std::path::Path;
use std::sync::OnceLock;

use raylab_core::render::render;
use raylab_core::scene::obj::{Placement, parse_obj};
use raylab_core::scene::spec::model_in_box;
use raylab_core::scene::{Scene, cornell_box};
use raylab_core::view::render_view;
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
/// [`MAX_SAMPLES`] samples) are rendered on the Cornell box, with their display and their debug
/// view, to find panics in the tracer for any values validation lets through.
pub fn settings_json(data: &[u8]) {
    static SCENE: OnceLock<Scene> = OnceLock::new();
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
    // The scene the settings name may be a file or the million-triangle terrain: the box
    // stands in for every one; the tracer is what is fuzzed.
    let scene = SCENE.get_or_init(cornell_box);
    let image = render(scene, &settings);
    assert_eq!(image.pixels.len(), (camera.width * camera.height) as usize);
    let rgba = settings.display.to_rgba8(&image.pixels);
    assert_eq!(rgba.len(), 4 * image.pixels.len());
    if settings.view.is_traced() {
        let _ = render_view(scene, &settings, settings.view, &|| false);
    }
}

/// Bytes → `raylab_core::scene_file::parse` (what `--scene-file FILE` and the workbench's Open read)
/// → settings that are valid, since the parser validates them. They must save and read back to
/// the same settings (a scene file round-trips exactly), and when small, render on the Cornell
/// box as [`settings_json`] does. Model paths resolve against a folder that does not exist, so
/// no file is read: a scene naming a model fails when loaded, never here.
pub fn scene_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let folder = Path::new("/nonexistent-fuzz-folder");
    let Ok(settings) = raylab_core::scene_file::parse(text, folder) else {
        return;
    };
    settings
        .validate()
        .expect("the parser validates what it returns");
    if let Ok(saved) = raylab_core::scene_file::to_text(&settings, folder) {
        let again = raylab_core::scene_file::parse(&saved, folder)
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
