//! Headless tests of the workbench window (egui_kittest, no display needed).
//!
//! Controls are found by their labels, as a screen reader would. The app renders on its real
//! controller; [`settle`] steps UI frames until the newest job has reached its sample target on
//! screen, with a deadline, so no test can hang.

use std::path::Path;
use std::time::{Duration, Instant};

use eframe::egui::{self, Key, Modifiers};
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT as _, Queryable as _};
use glam::Vec3;
use raylab_core::shading::light::{approach_at_edge, direct_light, shadow_ray};
use raylab_core::shapes::scene::in_shadow;
use raylab_core::shapes::scene::{SceneChoice, cornell_box};
use raylab_core::transport::render::render;
use raylab_core::{Image, MaterialPreset, RenderSettings, Shading, Stage};

use super::persistence::{WorkbenchState, lab_defaults};
use super::*;

mod caustics_ui;
mod check_ui;
mod denoise_ui;
mod equations_ui;
mod files_ui;
mod inspector_ui;
mod materials_ui;
mod panels_ui;
mod relief_ui;
mod steps_ui;
mod top_ui;
mod water_ui;

const DEADLINE: Duration = Duration::from_secs(90);

/// A small image and one sample, so each test renders in milliseconds.
fn small_state() -> WorkbenchState {
    let mut state = WorkbenchState::default();
    state.settings.camera = state.settings.camera.with_resolution(128, 96);
    state.settings.samples_per_pixel = 1;
    state.render_threads = 2;
    // The tests measure the traced image itself; the denoiser's own test turns it on.
    state.denoise = false;
    state
}

fn harness(state: WorkbenchState) -> Harness<'static, WorkbenchApp> {
    let mut h = Harness::builder()
        .with_size([1400.0, 2400.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    settle(&mut h);
    h
}

/// Steps frames until the newest render is final on screen (or fails after [`DEADLINE`]).
fn settle(h: &mut Harness<'_, WorkbenchApp>) {
    let start = Instant::now();
    // At least one frame, so queued input is handled and any change submitted.
    h.step();
    while !h.state().is_settled() {
        assert!(
            start.elapsed() < DEADLINE,
            "the render did not finish within {DEADLINE:?}"
        );
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
}

fn shown(h: &Harness<'_, WorkbenchApp>) -> Shown {
    h.state().shown.clone().expect("an image is shown")
}

fn settings(h: &Harness<'_, WorkbenchApp>) -> RenderSettings {
    h.state().state.settings.clone()
}

fn status(h: &Harness<'_, WorkbenchApp>) -> (String, StatusKind) {
    let s = h.state().status.clone().expect("a status line");
    (s.text, s.kind)
}

fn changed(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() > 1e-6
}

#[test]
fn opens_on_figure_7_and_stops_repainting_when_done() {
    let mut h = harness(small_state());
    let frame = shown(&h);
    assert_eq!(frame.settings, small_state().settings);
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
    assert_eq!(frame.settings.shading.stage, Stage::Lab);
    // The texture on screen is the render, at full resolution.
    assert_eq!(h.state().viewport.image_size(), Some([128, 96]));
    // The target is reached: the app asks for no more frames, so `run` returns.
    assert!(h.try_run().is_ok(), "still repainting after the target");
}

#[test]
fn focal_length_slider_zooms_in() {
    let mut h = harness(small_state());
    let before = shown(&h);
    let f = settings(&h).camera.focal_length;
    h.get_by_role_and_label(Role::Slider, "Focal length")
        .set_value_accesskit(f64::from(2.0 * f));
    settle(&mut h);
    let after = shown(&h);
    assert_eq!(after.settings.camera.focal_length, 2.0 * f);
    assert_eq!(*after.image, render(&cornell_box(), &after.settings));

    // Twice the focal length shows the middle half of the view: the back wall fills the width
    // and the purple and yellow side walls leave the picture; the centre stays the back wall.
    let side_walls = |image: &Image| {
        image
            .pixels
            .iter()
            .filter(|p| {
                let purple = p.x > 2.0 * p.y && p.z > 2.0 * p.y;
                let yellow = p.x > 2.0 * p.z && p.y > 2.0 * p.z;
                purple || yellow
            })
            .count()
    };
    assert!(
        side_walls(&before.image) > 1000,
        "{}",
        side_walls(&before.image)
    );
    assert!(
        side_walls(&after.image) < 50,
        "{}",
        side_walls(&after.image)
    );
    let centre = |image: &Image| image.get(64, 48);
    assert!(
        (centre(&before.image) - centre(&after.image))
            .abs()
            .max_element()
            < 0.02
    );
}

#[test]
fn shadows_switch_changes_only_pixels_a_shadow_can_reach() {
    let mut h = harness(small_state());
    let with_shadows = shown(&h);
    assert!(with_shadows.settings.shading.shadows);
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    settle(&mut h);
    let without = shown(&h);
    assert!(!without.settings.shading.shadows);

    // The oracle: a pixel can change only where its surface point faces the light and the
    // shadow ray is blocked.
    let scene = cornell_box();
    let s = &without.settings;
    let (w, h_px) = (s.camera.width, s.camera.height);
    let mut by_blocks = 0;
    for y in 0..h_px {
        for x in 0..w {
            let ray = s.camera.pixel_ray(x, y);
            let hit = scene.closest_intersection(&ray, f32::INFINITY);
            let at_edge = |hit: &raylab_core::shapes::intersect::Intersection| {
                let t = &scene.triangles[hit.triangle_index];
                approach_at_edge(t, hit.u, hit.v, ray.direction)
            };
            let shadowed = hit.as_ref().is_some_and(|hit| {
                let n = scene.triangles[hit.triangle_index].normal;
                direct_light(&s.light, hit.position, n) != Vec3::ZERO
                    && in_shadow(&scene, &s.light, hit.position, n, at_edge(hit))
            });
            let differs = changed(with_shadows.image.get(x, y), without.image.get(x, y));
            assert_eq!(differs, shadowed, "pixel ({x}, {y})");
            let Some(hit) = hit.filter(|_| differs) else {
                continue;
            };
            // What blocks the light must be one of the two blocks (triangles 10..30): the room's
            // walls face the light, which hangs inside the box, and never shadow each other.
            let n = scene.triangles[hit.triangle_index].normal;
            let (shadow_ray, t_max) = shadow_ray(&s.light, hit.position, n, at_edge(&hit))
                .expect("a lit-facing point has a shadow ray");
            let blocker = scene
                .closest_intersection(&shadow_ray, t_max)
                .expect("a shadowed point has a blocker");
            assert!(
                blocker.triangle_index >= 10,
                "pixel ({x}, {y}) shadowed by wall triangle {}",
                blocker.triangle_index
            );
            by_blocks += 1;
            // The light hangs below the ceiling and above the blocks: the blocks can't shadow
            // the top third of the picture (ceiling and upper walls).
            assert!(y > h_px / 3, "pixel ({x}, {y}) shadowed by a block");
        }
    }
    let differing = by_blocks;
    // The shadows of the two blocks on the floor and walls.
    assert!(differing > 200, "{differing}");
}

#[test]
fn flat_stage_shows_only_the_seven_reflectances() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::ComboBox, "Stage").click();
    h.run_steps(2);
    h.get_by_label("Flat colour (figure 2)").click();
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(frame.settings.shading, Shading::for_stage(Stage::Flat));
    assert_eq!(frame.samples, 1);
    let scene = cornell_box();
    let reflectances: Vec<Vec3> = scene.materials.iter().map(|m| m.reflectance).collect();
    assert_eq!(reflectances.len(), 7);
    for p in &frame.image.pixels {
        assert!(
            reflectances.contains(p) || *p == Vec3::ZERO,
            "{p} is not a reflectance"
        );
    }
    for rho in &reflectances {
        assert!(frame.image.pixels.contains(rho), "{rho} missing");
    }
    // Every stage is offered, named with its figure.
    h.get_by_role_and_label(Role::ComboBox, "Stage").click();
    h.run_steps(2);
    for label in [
        "(figure 3)",
        "(figure 5)",
        "(figure 6)",
        "(figure 7)",
        "Path tracing (real light)",
    ] {
        assert!(h.query_by_label_contains(label).is_some(), "{label}");
    }
}

#[test]
fn indirect_switch_and_sample_target() {
    let mut h = harness(small_state());
    let before = shown(&h);
    h.get_by_role_and_label(Role::CheckBox, "Indirect light")
        .click();
    h.get_by_role_and_label(Role::Slider, "Sample target")
        .set_value_accesskit(4.0);
    settle(&mut h);
    let after = shown(&h);
    assert!(!after.settings.shading.indirect);
    assert_eq!((after.samples, after.target), (4, 4));
    // Without N every pixel is darker or equal (ρ ∗ D instead of ρ ∗ (D + N)) — compared at
    // sample 0, the pixel centres, where both images trace the same rays.
    let mut one = after.settings.clone();
    one.samples_per_pixel = 1;
    let centres = render(&cornell_box(), &one);
    assert!(
        centres
            .pixels
            .iter()
            .zip(&before.image.pixels)
            .all(|(a, b)| a.cmple(*b + Vec3::splat(1e-6)).all())
    );
    assert_eq!(*after.image, render(&cornell_box(), &after.settings));
}

fn pngs_in(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    v.sort();
    v
}

#[test]
fn screenshot_button_and_ctrl_s_write_pngs_of_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().to_owned();
    let mut h = harness(state);
    h.get_by_role_and_label(Role::Button, "Save screenshot")
        .click();
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info, "{text}");
    let pngs = pngs_in(dir.path());
    assert_eq!(pngs.len(), 1);
    assert!(text.contains(&*pngs[0].file_name().unwrap().to_string_lossy()));
    let name = pngs[0].file_name().unwrap().to_string_lossy().into_owned();
    assert!(name.starts_with("raylab-") && name.len() == "raylab-YYYYMMDD-HHMMSS.png".len());
    let png = image::open(&pngs[0]).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (128, 96));
    assert_eq!(png.into_raw(), shown(&h).image.to_rgb8());
    let sidecar: screenshot::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(pngs[0].with_extension("json")).unwrap())
            .unwrap();
    assert_eq!(sidecar.settings, settings(&h));

    // Ctrl+S saves another, under a new name, while the keys' S does not move the light.
    let light = settings(&h).light.position;
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    settle(&mut h);
    assert_eq!(pngs_in(dir.path()).len(), 2);
    assert_eq!(settings(&h).light.position, light);
}

#[test]
fn screenshot_into_a_missing_folder_shows_an_error_and_the_app_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().join("missing");
    let mut h = harness(state);
    h.get_by_role_and_label(Role::Button, "Save screenshot")
        .click();
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(text.contains("does not exist"), "{text}");
    // The error is on screen, in the status line.
    assert!(h.query_by_label_contains("does not exist").is_some());
    // And the workbench still works.
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    settle(&mut h);
    assert!(!shown(&h).settings.shading.shadows);
    // Once the folder exists the red line goes: the problem is fixed.
    std::fs::create_dir(dir.path().join("missing")).unwrap();
    h.step();
    assert!(h.state().status.is_none(), "{:?}", h.state().status);
}

#[test]
fn reset_restores_the_lab_defaults() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::Slider, "Light x")
        .set_value_accesskit(0.5);
    h.step();
    assert_eq!(settings(&h).light.position.x, 0.5);
    h.get_by_role_and_label(Role::Button, "Reset to lab defaults")
        .click();
    h.step();
    assert_eq!(settings(&h), lab_defaults());
    // Render a few frames of the 512² default, not the whole target: enough to see it start.
    let start = Instant::now();
    while h
        .state()
        .shown
        .as_ref()
        .is_none_or(|s| s.settings != lab_defaults())
    {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
}

#[test]
fn the_labs_keys_move_camera_and_light() {
    let mut h = harness(small_state());
    let s0 = settings(&h);
    h.key_press(Key::ArrowUp);
    h.key_press(Key::ArrowLeft);
    h.key_press(Key::W);
    h.key_press(Key::Q);
    h.key_press(Key::D);
    h.step();
    let s1 = settings(&h);
    assert!((s1.camera.position.z - (s0.camera.position.z + 0.1)).abs() < 1e-6);
    assert!((s1.camera.yaw - (-5f32).to_radians()).abs() < 1e-6);
    // The camera turned left before the light moved: "forward" and "right" follow it.
    let turn = glam::Mat3::from_rotation_y(s1.camera.yaw);
    let expected = s0.light.position + 0.1 * (turn.z_axis + turn.x_axis - Vec3::Y);
    assert!((s1.light.position - expected).length() < 1e-5);

    // While a text field has focus, keys type instead.
    h.get_by_label("Screenshot folder").click();
    let text_field = h.get_by_role_and_label(Role::TextInput, "Screenshot folder");
    text_field.focus();
    h.step();
    h.key_press(Key::ArrowUp);
    h.key_press(Key::W);
    h.step();
    assert_eq!(settings(&h).camera.position, s1.camera.position);
    assert_eq!(settings(&h).light.position, s1.light.position);
    settle(&mut h);
}

#[test]
fn f1_opens_the_help_listing_the_keys() {
    let mut h = harness(small_state());
    assert!(h.query_by_label("Up / Down").is_none());
    h.key_press(Key::F1);
    h.step();
    h.step();
    for keys in [
        "Up / Down",
        "Left / Right",
        "W / S",
        "A / D",
        "Q / E",
        "Ctrl+S",
        "F1",
    ] {
        assert!(h.query_by_label(keys).is_some(), "{keys}");
    }
    h.get_by_role_and_label(Role::Button, "Help").click();
    h.step();
    h.step();
    assert!(h.query_by_label("Up / Down").is_none());
}

#[test]
fn dragging_on_the_image_turns_and_the_wheel_zooms() {
    let mut h = harness(small_state());
    let s0 = settings(&h);
    // The image sits in the middle of the central panel, right of the side panel.
    let centre = egui::pos2(900.0, 700.0);
    h.drag_at(centre);
    h.step();
    h.hover_at(centre + egui::vec2(40.0, 0.0));
    h.step();
    h.drop_at(centre + egui::vec2(40.0, 0.0));
    h.step();
    let s1 = settings(&h);
    assert!(
        s1.camera.yaw > s0.camera.yaw,
        "{} {}",
        s1.camera.yaw,
        s0.camera.yaw
    );
    h.hover_at(centre);
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, 50.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Unknown,
        modifiers: Modifiers::default(),
    });
    for _ in 0..10 {
        h.step();
    }
    assert!(settings(&h).camera.focal_length > s1.camera.focal_length);
    settle(&mut h);
}

#[test]
fn render_threads_rebuild_the_pool() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::Slider, "Render threads")
        .set_value_accesskit(1.0);
    settle(&mut h);
    assert_eq!(
        h.state().controller.as_ref().map(Controller::threads),
        Some(1)
    );
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
}

#[test]
fn a_corrupt_settings_file_shows_a_notice_and_starts_on_the_defaults() {
    #[derive(Default)]
    struct Corrupt;
    impl eframe::Storage for Corrupt {
        fn get_string(&self, _key: &str) -> Option<String> {
            Some("{\"version\": 1, \"settings\": {\"camera\": [".to_owned())
        }
        fn set_string(&mut self, _key: &str, _value: String) {}
        fn remove_string(&mut self, _key: &str) {}
        fn flush(&mut self) {}
    }
    let (mut state, notice) = persistence::load(Some(&Corrupt));
    assert_eq!(state, WorkbenchState::default());
    // Small, so the test is quick; the notice is what matters here.
    state.settings.camera = state.settings.camera.with_resolution(64, 48);
    let mut h = Harness::builder()
        .with_size([1400.0, 2400.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, notice));
    settle(&mut h);
    assert_eq!(status(&h).1, StatusKind::Notice);
    assert!(
        h.query_by_label_contains("Saved settings ignored")
            .is_some()
    );
    assert!(h.query_by_label_contains("lab's defaults").is_some());
}

#[test]
fn after_using_a_slider_with_the_mouse_the_arrows_move_the_camera() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::Slider, "Light x").click();
    h.step();
    let z = settings(&h).camera.position.z;
    h.key_press(Key::ArrowUp);
    h.step();
    assert!((settings(&h).camera.position.z - (z + 0.1)).abs() < 1e-6);
    settle(&mut h);
}

#[test]
fn the_scene_selector_loads_a_model_off_the_ui_thread() {
    let mut h = harness(small_state());
    let cornell = shown(&h);
    assert_eq!(cornell.settings.scene, SceneChoice::Cornell);
    h.get_by_role_and_label(Role::ComboBox, "Scene").click();
    h.run_steps(2);
    h.get_by_label("Stanford bunny").click();
    settle(&mut h);
    let bunny = shown(&h);
    assert_eq!(bunny.settings.scene, SceneChoice::Bunny);
    assert!(h.state().scene.triangles.len() > 3_000);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info);
    assert!(text.contains("bunny"), "{text}");
    // The bunny stands on the floor in front of the back wall: some pixels change, and the
    // walls at the image's edges do not.
    let differing = (0..bunny.image.pixels.len())
        .filter(|&i| changed(bunny.image.pixels[i], cornell.image.pixels[i]))
        .count();
    assert!(differing > 300, "{differing}");
    assert!(!changed(bunny.image.get(1, 48), cornell.image.get(1, 48)));
}

#[test]
fn a_missing_obj_file_shows_an_error_and_keeps_the_scene() {
    let mut h = harness(small_state());
    let before = shown(&h);
    let missing = "/no/such/model.obj";
    let field = h.get_by_role_and_label(Role::TextInput, "File");
    field.focus();
    h.step();
    h.get_by_role_and_label(Role::TextInput, "File")
        .type_text(missing);
    h.run_steps(2);
    assert_eq!(h.state().state.obj_path, missing);
    h.get_by_role_and_label(Role::Button, "Open").click();
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(text.contains("model.obj"), "{text}");
    assert_eq!(settings(&h).scene, SceneChoice::Cornell);
    assert_eq!(shown(&h).image, before.image);
    // The app goes on: a change still re-renders.
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    settle(&mut h);
    assert!(!shown(&h).settings.shading.shadows);
}

/// An OBJ file with faces left out (a copy of a face, a face on a line)
/// loads, and the status line says what was left out, as a notice.
#[test]
fn an_obj_with_faces_left_out_loads_with_a_notice_saying_so() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("copies.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 3\nf 1 2 4\n",
    )
    .unwrap();
    let path = obj.to_str().unwrap();
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::TextInput, "File").focus();
    h.step();
    h.get_by_role_and_label(Role::TextInput, "File")
        .type_text(path);
    h.run_steps(2);
    h.get_by_role_and_label(Role::Button, "Open").click();
    settle(&mut h);
    assert_eq!(settings(&h).scene, SceneChoice::Obj(path.into()));
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice, "{text}");
    assert!(
        text.starts_with("Loaded the copies.obj scene: 31 triangles"),
        "{text}"
    );
    assert!(
        text.ends_with(
            "copies.obj: left out 2 faces that can never be seen: 1 degenerate (zero area), 1 \
             exact duplicate of an earlier face)"
        ),
        "{text}"
    );
}

#[test]
fn non_finite_values_never_reach_the_renderer() {
    let mut h = harness(small_state());
    let before = shown(&h);
    for (label, value) in [
        ("Light x", f64::NAN),
        ("Camera z", f64::INFINITY),
        ("Focal length", f64::NAN),
        ("Light power", f64::NEG_INFINITY),
    ] {
        h.get_by_role_and_label(Role::Slider, label)
            .set_value_accesskit(value);
        settle(&mut h);
        let s = settings(&h);
        assert!(s.validate().is_ok(), "{label} = {value}: {s:?}");
        assert!(shown(&h).image.pixels.iter().all(|p| p.is_finite()));
    }
    // Still rendering, and still the box.
    assert_eq!(shown(&h).image.width, before.image.width);
}

/// A tiny image, so the path tracer's samples take milliseconds.
fn tiny_state() -> WorkbenchState {
    let mut state = small_state();
    state.settings.camera = state.settings.camera.with_resolution(32, 24);
    state
}

/// Picks `label` in the combo box labelled `combo`.
fn choose(h: &mut Harness<'_, WorkbenchApp>, combo: &str, label: &str) {
    h.get_by_role_and_label(Role::ComboBox, combo).click();
    h.run_steps(2);
    h.get_by_label(label).click();
    // One frame handles the click, the next shows its result.
    h.run_steps(2);
}

/// Sets the sample target through its slider.
fn set_target(h: &mut Harness<'_, WorkbenchApp>, target: u32) {
    h.get_by_role_and_label(Role::Slider, "Sample target")
        .set_value_accesskit(f64::from(target));
    h.step();
    assert_eq!(settings(h).samples_per_pixel, target);
}

#[test]
fn the_path_stage_raises_the_sample_target_and_renders_what_the_library_renders() {
    let mut h = harness(tiny_state());
    choose(&mut h, "Stage", "Path tracing (real light)");
    let s = settings(&h);
    assert_eq!(s.shading.stage, Stage::Path);
    assert!(s.samples_per_pixel >= PATH_SAMPLE_TARGET);
    assert_eq!(s.samples_per_pixel, 1024);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info);
    assert!(text.contains("1024"), "{text}");
    // The indirect N is not the path tracer's: its slider is disabled there.
    assert!(
        h.get_by_role_and_label(Role::Slider, "Indirect N")
            .accesskit_node()
            .is_disabled()
    );
    // Down to a few samples, to keep the test quick; the same image as the library's.
    set_target(&mut h, 8);
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(frame.settings.shading.stage, Stage::Path);
    assert_eq!((frame.samples, frame.target), (8, 8));
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
    // Back to a lab stage: the target stays as it is.
    choose(&mut h, "Stage", "Lab (figure 7)");
    assert_eq!(settings(&h).samples_per_pixel, 8);
    settle(&mut h);
}

#[test]
fn the_mirror_preset_changes_the_image_as_the_library_renders_it() {
    let mut h = harness(small_state());
    let diffuse = shown(&h);
    assert_eq!(diffuse.settings.material_preset, MaterialPreset::None);
    choose(&mut h, "Materials", "Mirror tall block");
    settle(&mut h);
    let mirror = shown(&h);
    assert_eq!(mirror.settings.material_preset, MaterialPreset::Mirror);
    assert_eq!(*mirror.image, render(&cornell_box(), &mirror.settings));
    let differing = (0..mirror.image.pixels.len())
        .filter(|&i| changed(mirror.image.pixels[i], diffuse.image.pixels[i]))
        .count();
    assert!(differing > 300, "{differing}");
    // The description says the mirror is followed, and how deep.
    assert!(
        h.query_by_label_contains("mirror tall block followed up to 6 deep")
            .is_some()
    );
    // The specular depth slider works on it.
    h.get_by_role_and_label(Role::Slider, "Specular depth")
        .set_value_accesskit(0.0);
    settle(&mut h);
    let depth_0 = shown(&h);
    assert_eq!(depth_0.settings.shading.specular_depth, 0);
    assert_ne!(depth_0.image, mirror.image);
    assert_eq!(*depth_0.image, render(&cornell_box(), &depth_0.settings));
}

#[test]
fn the_description_follows_the_switches() {
    let mut h = harness(small_state());
    assert!(
        h.query_by_label("ρ·(D + N) (eq. 30) with shadows (§5.1)")
            .is_some()
    );
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    h.run_steps(2);
    assert!(h.query_by_label("ρ·(D + N) (eq. 30)").is_some());
    h.get_by_role_and_label(Role::CheckBox, "Indirect light")
        .click();
    h.run_steps(2);
    assert!(h.query_by_label("ρ·D (eq. 28)").is_some());
    settle(&mut h);
}

#[test]
fn the_path_stage_with_no_bounces_is_the_shadows_stage_bit_for_bit() {
    let mut h = harness(tiny_state());
    choose(&mut h, "Stage", "Path tracing (real light)");
    set_target(&mut h, 4);
    assert!(
        h.get_by_role_and_label(Role::Slider, "Bounces")
            .accesskit_node()
            .is_disabled()
    );
    h.get_by_role_and_label(Role::CheckBox, "Unlimited bounces")
        .click();
    h.step();
    assert!(settings(&h).shading.bounces.is_some());
    h.get_by_role_and_label(Role::Slider, "Bounces")
        .set_value_accesskit(0.0);
    settle(&mut h);
    let path = shown(&h);
    assert_eq!(path.settings.shading.stage, Stage::Path);
    assert_eq!(path.settings.shading.bounces, Some(0));
    assert_eq!((path.samples, path.target), (4, 4));
    assert!(
        h.query_by_label_contains("no bounces: direct light only")
            .is_some()
    );
    let mut shadows = path.settings.clone();
    shadows.shading = Shading::for_stage(Stage::Shadows);
    let bits = |image: &Image| -> Vec<[u32; 3]> {
        image
            .pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&path.image), bits(&render(&cornell_box(), &shadows)));
    // Ticking "Unlimited bounces" again brings back the real indirect light; unticking it
    // remembers the 0.
    h.get_by_role_and_label(Role::CheckBox, "Unlimited bounces")
        .click();
    h.step();
    assert_eq!(settings(&h).shading.bounces, None);
    h.get_by_role_and_label(Role::CheckBox, "Unlimited bounces")
        .click();
    h.step();
    assert_eq!(settings(&h).shading.bounces, Some(0));
    settle(&mut h);
}

#[test]
fn the_stats_show_the_noise_of_a_path_traced_image() {
    let mut h = harness(tiny_state());
    // One sample: no spread to estimate the noise from yet.
    assert!(h.query_by_label_contains("Noise:").is_none());
    choose(&mut h, "Stage", "Path tracing (real light)");
    set_target(&mut h, 4);
    settle(&mut h);
    let frame = shown(&h);
    assert!(frame.samples >= 2);
    let noise = h.state().stats.noise.expect("a noise estimate");
    // The estimate of the film the library accumulates from the same passes, exactly.
    let mut film = raylab_core::transport::film::Film::with_noise(
        frame.settings.camera.width,
        frame.settings.camera.height,
    );
    for sample in 0..frame.samples {
        let pass = raylab_core::transport::render::render_pass(
            &cornell_box(),
            &frame.settings,
            sample,
            &|| false,
        )
        .unwrap();
        film.add_pass(&pass);
    }
    assert_eq!(Some(noise), film.noise());
    assert!(
        noise.relative_rms_error > 0.0,
        "a path-traced image is noisy"
    );
    // The image's relative RMS error, and what reaching 1 % takes: at 4 samples of a path-
    // traced image, more samples than the target.
    let error = format!(
        "Noise: ±{} (RMS over the image)",
        stats::percent(noise.relative_rms_error)
    );
    assert!(h.query_by_label(&error).is_some(), "{error}");
    let needed = noise.samples_to_reach(
        frame.samples,
        raylab_core::transport::film::CLEAN_RELATIVE_ERROR,
    );
    assert!(needed > 4.0, "{needed}");
    let advice =
        format!("1 % (clean) needs about {needed:.0} samples: raise the sample target (now 4)");
    assert!(h.query_by_label(&advice).is_some(), "{advice}");
    // And in the status bar's summary, which stays in view; no share of pixels any more.
    let summary = format!(
        "noise ±{}, 1 % at ~{needed:.0} spp",
        stats::percent(noise.relative_rms_error)
    );
    assert!(h.query_by_label_contains(&summary).is_some(), "{summary}");
    assert!(h.query_by_label_contains("px > 1 %").is_none());
}

#[test]
fn the_extensions_controls_are_found_by_label_and_render_what_the_library_renders() {
    let mut h = harness(small_state());
    for label in ["Aperture", "Light radius", "Exposure", "Light power"] {
        h.get_by_role_and_label(Role::Slider, label);
    }
    for label in ["Smooth shading", "Click to focus"] {
        h.get_by_role_and_label(Role::CheckBox, label);
    }
    h.get_by_label("Textures");
    h.get_by_label("Display transform");
    h.get_by_label("Light colour");

    h.get_by_role_and_label(Role::Slider, "Light radius")
        .set_value_accesskit(0.2);
    h.get_by_role_and_label(Role::Slider, "Aperture")
        .set_value_accesskit(0.05);
    h.get_by_role_and_label(Role::CheckBox, "Smooth shading")
        .click();
    h.step();
    // Soft shadows raised the target; a few samples keep the test quick.
    assert_eq!(settings(&h).samples_per_pixel, SOFT_SAMPLE_TARGET);
    set_target(&mut h, 2);
    settle(&mut h);
    let s = settings(&h);
    assert_eq!(
        s.light.kind,
        raylab_core::shading::light::LightKind::Sphere { radius: 0.2 }
    );
    assert_eq!(s.camera.aperture, 0.05);
    assert!(!s.shading.smooth);
    let frame = shown(&h);
    assert_eq!(frame.settings, s);
    assert_eq!(*frame.image, render(&cornell_box(), &s));
}

/// The display transform and exposure change only what is shown: the accumulation goes on
/// (the same job, its sample count still growing) and the texture is the linear image through
/// the new display.
#[test]
fn changing_the_display_never_restarts_the_accumulation() {
    let mut state = small_state();
    state.settings.samples_per_pixel = 3000;
    let mut h = Harness::builder()
        .with_size([1400.0, 2400.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    let start = Instant::now();
    // Wait for some samples, well before the target.
    while h.state().shown.as_ref().is_none_or(|s| s.samples < 3) {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
    let generation = h.state().submitted_generation;
    let samples_before = shown(&h).samples;
    h.get_by_role_and_label(Role::Slider, "Exposure")
        .set_value_accesskit(1.0);
    let mut seen = Vec::new();
    while !h.state().is_settled() {
        assert!(start.elapsed() < DEADLINE, "did not finish");
        std::thread::sleep(Duration::from_millis(2));
        h.step();
        seen.push(shown(&h).samples);
    }
    assert_eq!(
        h.state().submitted_generation,
        generation,
        "a new job was started"
    );
    assert!(
        seen.iter().all(|&n| n >= samples_before),
        "{samples_before} then {seen:?}"
    );
    assert!(
        seen.windows(2).all(|w| w[0] <= w[1]),
        "the count went back: {seen:?}"
    );
    let frame = shown(&h);
    assert_eq!(frame.samples, 3000);
    let display = settings(&h).display;
    assert_eq!(display.exposure, 1.0);
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        display.to_rgba8(&frame.image.pixels),
        "the texture is the image through the new exposure"
    );
}

/// "Click to focus": a click on the image sets the focus distance to the depth of the surface
/// under the pointer, as `render::focus_depth` computes it.
#[test]
fn click_to_focus_sets_the_focus_distance() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::CheckBox, "Click to focus")
        .click();
    h.step();
    let rect = h.state().viewport.shown_rect().unwrap();
    // A point on the back wall, above the blocks (as in render::focus_depth's test).
    let at = egui::vec2(0.5, 0.3);
    let pos = rect.min + at * rect.size();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.step();
    let s = settings(&h);
    let (px, py) = (at.x * 128.0, at.y * 96.0);
    let expected = raylab_core::transport::render::focus_depth(&cornell_box(), &s, px, py).unwrap();
    assert!(
        (s.camera.focus_distance - expected).abs() < 0.02,
        "{} vs {expected}",
        s.camera.focus_distance
    );
    assert!((s.camera.focus_distance - 4.001).abs() < 1e-3);
    assert!(status(&h).0.contains("Focus distance"), "{}", status(&h).0);
    settle(&mut h);
}

/// The light is drawn where the camera sees it; dragging its marker moves the light in the
/// image plane at its depth (the camera does not turn), and it lands where the pointer is.
#[test]
fn dragging_the_light_marker_moves_the_light() {
    let mut h = harness(small_state());
    let s0 = settings(&h);
    let rect = h.state().viewport.shown_rect().unwrap();
    let marker = light_marker(&s0).unwrap();
    let start = rect.min + marker * rect.size();
    let to = start + egui::vec2(30.0, 10.0);
    h.drag_at(start);
    h.step();
    for k in 1..=5 {
        h.hover_at(start + (to - start) * (k as f32 / 5.0));
        h.step();
    }
    h.drop_at(to);
    h.step();
    let s1 = settings(&h);
    assert_eq!(s1.camera, s0.camera, "the camera must not turn");
    assert!(
        s1.light.position.x > s0.light.position.x + 0.05,
        "{}",
        s1.light.position
    );
    // At the same depth, under the pointer.
    let (_, _, z0) = s0.camera.project(s0.light.position).unwrap();
    let (px, py, z1) = s1.camera.project(s1.light.position).unwrap();
    assert!((z1 - z0).abs() < 1e-4);
    let landed = rect.min + egui::vec2(px / 128.0, py / 96.0) * rect.size();
    assert!(landed.distance(to) < 1.0, "{landed:?} vs {to:?}");
    settle(&mut h);
    // Behind the camera the light has no marker.
    let mut behind = s1.clone();
    behind.light.position.z = behind.camera.position.z - 1.0;
    assert_eq!(light_marker(&behind), None);
}

/// The walk-through steps through the lab's figures in order, each rendering exactly its stage,
/// and leaves the user's camera and light alone.
#[test]
fn the_walkthrough_steps_through_the_figures() {
    let mut state = small_state();
    state.settings.camera.position.x = 0.1;
    state.settings.light.position.x = 0.3;
    let mut h = harness(state);
    let user = settings(&h);
    h.get_by_label("Lab walk-through").click();
    h.step();
    h.get_by_role_and_label(Role::Button, "Start the walk-through")
        .click();
    settle(&mut h);
    let of = raylab_core::teaching::walkthrough::STEPS.len();
    assert!(
        h.query_by_label_contains(&format!("Step 1 of {of}"))
            .is_some()
    );
    assert_eq!(settings(&h).shading.stage, Stage::Flat);
    for stage in [Stage::Incoming, Stage::Direct, Stage::Shadows, Stage::Lab] {
        h.get_by_role_and_label(Role::Button, "Next").click();
        settle(&mut h);
        let s = settings(&h);
        assert_eq!(s.shading, Shading::for_stage(stage));
        assert_eq!(
            (s.camera, s.light.position),
            (user.camera, user.light.position)
        );
        assert_eq!(*shown(&h).image, render(&cornell_box(), &s));
    }
    assert!(
        h.query_by_label(&format!("Step 5 of {of}: Indirect light (figure 7)"))
            .is_some()
    );
    h.get_by_role_and_label(Role::Button, "Previous").click();
    settle(&mut h);
    assert_eq!(settings(&h).shading.stage, Stage::Shadows);
    h.get_by_role_and_label(Role::Button, "Leave").click();
    h.step();
    assert_eq!(h.state().state.walk_step, None);
    settle(&mut h);
}

/// A window of `size` saving screenshots into `dir`, at 2 of its 4000 samples: a screenshot
/// taken now is saved long before the target.
fn early_screenshot_harness(
    dir: &std::path::Path,
    size: [f32; 2],
) -> (Harness<'static, WorkbenchApp>, Instant) {
    let mut state = small_state();
    state.screenshot_folder = dir.to_owned();
    state.settings.samples_per_pixel = 4000;
    let mut h = Harness::builder()
        .with_size(size)
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    let start = Instant::now();
    while h.state().last_full.as_ref().is_none_or(|s| s.samples < 2) {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
    (h, start)
}

/// Steps `h` until the screenshot asked for is written into `dir`.
fn until_saved(h: &mut Harness<'_, WorkbenchApp>, dir: &std::path::Path, start: Instant) {
    while pngs_in(dir).is_empty() || !h.state().screenshots_saving.is_empty() {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
}

/// A screenshot saved before the sample target says at how many samples it was taken.
#[test]
fn a_screenshot_before_the_target_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (mut h, start) = early_screenshot_harness(dir.path(), [1400.0, 2400.0]);
    h.get_by_role_and_label(Role::Button, "Save screenshot")
        .click();
    until_saved(&mut h, dir.path(), start);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice, "{text}");
    assert!(text.contains("/4000 samples"), "{text}");
}

/// Enter in the OBJ field loads the file, as the button does.
#[test]
fn enter_in_the_obj_field_loads_it() {
    let mut h = harness(small_state());
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/models/teapot.obj");
    h.get_by_role_and_label(Role::TextInput, "File").focus();
    h.step();
    h.get_by_role_and_label(Role::TextInput, "File")
        .type_text(path);
    h.step();
    h.key_press(Key::Enter);
    h.step();
    assert_eq!(settings(&h).scene, SceneChoice::Obj(path.into()));
    settle(&mut h);
}

#[test]
fn values_that_round_to_zero_show_without_a_sign() {
    use super::panels::fixed;
    assert_eq!(fixed(-0.0, 2), "0.00");
    assert_eq!(fixed(-0.001, 2), "0.00");
    assert_eq!(fixed(-0.04, 1), "0.0");
    assert_eq!(fixed(-0.05, 2), "-0.05");
    assert_eq!(fixed(1.234, 1), "1.2");
}

// Compare A/B.

/// The comparison in progress.
fn comparing<'a>(h: &'a Harness<'_, WorkbenchApp>) -> &'a compare::Compare {
    h.state().compare.as_ref().expect("comparing")
}

/// A's final frame on screen.
fn a_frame(h: &Harness<'_, WorkbenchApp>) -> compare::SideFrame {
    comparing(h).a().cloned().expect("A is shown")
}

/// Clicks "Freeze as A" and waits for both sides to finish.
fn freeze_a(h: &mut Harness<'_, WorkbenchApp>) {
    h.get_by_role_and_label(Role::Button, "Freeze as A").click();
    settle(h);
    assert!(h.state().compare.is_some(), "{:?}", h.state().status);
}

fn tick_difference(h: &mut Harness<'_, WorkbenchApp>) {
    h.get_by_role_and_label(Role::CheckBox, "Difference |A − B|")
        .click();
    settle(h);
    assert!(comparing(h).difference);
}

/// Frozen with nothing changed, A and B are one image: the wipe has no seam and the difference
/// is zero everywhere.
#[test]
fn compare_with_nothing_changed_shows_no_seam_and_no_difference() {
    let mut state = small_state();
    state.settings.samples_per_pixel = 3;
    let mut h = harness(state);
    freeze_a(&mut h);
    let (a, b) = (a_frame(&h), shown(&h));
    assert!(a.is_final() && b.is_final());
    assert_eq!(comparing(&h).settings(), &b.settings);
    assert_eq!(a.image, b.image);
    // The pixels uploaded for either side of the divider are the same.
    let a_rgba = comparing(&h).a_rgba().expect("A's texture");
    assert_eq!(Some(a_rgba), h.state().viewport.rgba());
    assert!(h.query_by_label("A and B: identical settings").is_some());
    // Both sides' figures in the Stats; the status bar still sums up B.
    for side in ["A: pass ", "B: pass "] {
        let node = h
            .query_by_label_contains(side)
            .unwrap_or_else(|| panic!("no {side} line"))
            .accesskit_node();
        let text = node.label().or_else(|| node.value()).unwrap_or_default();
        assert!(text.ends_with(" ms · 3/3 samples"), "{text}");
    }
    assert!(h.query_by_label_contains("3/3 spp").is_some());
    // A has B's threads.
    assert_eq!(
        comparing(&h).threads(),
        h.state().controller.as_ref().unwrap().threads()
    );

    tick_difference(&mut h);
    let compare = comparing(&h);
    let diff = compare.difference_shown().expect("a difference");
    assert_eq!(diff.max, 0.0);
    assert!(diff.image.pixels.iter().all(|p| *p == Vec3::ZERO));
    let rgba = compare.difference_rgba().unwrap();
    assert!(rgba.chunks(4).all(|p| p == [0, 0, 0, 255]));
    assert!(h.query_by_label("A and B are identical").is_some());
}

/// Shadows off for B: each side is exactly the library's render of its settings, and the
/// difference is nonzero exactly where the two renders differ.
#[test]
fn compare_shadows_off_for_b_differs_exactly_where_the_renders_do() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    tick_difference(&mut h);
    let scene = cornell_box();
    let a_settings = comparing(&h).settings().clone();
    let (a, b) = (a_frame(&h), shown(&h));
    assert!(a_settings.shading.shadows && !b.settings.shading.shadows);
    let a_render = render(&scene, &a_settings);
    let b_render = render(&scene, &b.settings);
    assert_eq!(*a.image, a_render);
    assert_eq!(*b.image, b_render);
    assert!(h.query_by_label("A and B differ in: shadows").is_some());
    // A keeps its own texture, B's is the live one.
    assert_eq!(
        comparing(&h).a_rgba().unwrap(),
        a_settings.display.to_rgba8(&a_render.pixels)
    );
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        b.settings.display.to_rgba8(&b_render.pixels)
    );

    let diff = comparing(&h).difference_shown().expect("a difference");
    let mut differing = 0;
    for (i, d) in diff.image.pixels.iter().enumerate() {
        let renders_differ = a_render.pixels[i] != b_render.pixels[i];
        assert_eq!(*d != Vec3::ZERO, renders_differ, "pixel {i}");
        assert_eq!(*d, (a_render.pixels[i] - b_render.pixels[i]).abs());
        differing += usize::from(renders_differ);
    }
    assert!(differing > 200, "{differing}");
    let max = diff
        .image
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max);
    assert_eq!(diff.max, max);
    assert!(max > 0.0);
    let scale = format!("white = |A − B| ≥ {}", compare::significant(max, 3));
    assert!(h.query_by_label(&scale).is_some(), "{scale}");
    // The brightest difference is white in the image shown.
    let rgba = comparing(&h).difference_rgba().unwrap();
    assert!(rgba.contains(&255) && rgba.chunks(4).any(|p| p[..3] == [0, 0, 0]));
}

/// A drag from the divider moves it (not the camera); a drag elsewhere still turns the camera,
/// and the light's marker still moves the light.
#[test]
fn compare_divider_drags_and_elsewhere_the_camera_turns() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    h.step();
    let rect = h.state().viewport.shown_rect().unwrap();
    assert_eq!(comparing(&h).divider.at, 0.5);
    let s0 = settings(&h);
    let drag = |h: &mut Harness<'_, WorkbenchApp>, from: egui::Pos2, to: egui::Pos2| {
        h.drag_at(from);
        h.step();
        for k in 1..=5 {
            h.hover_at(from + (to - from) * (k as f32 / 5.0));
            h.step();
        }
        h.drop_at(to);
        h.step();
    };
    // Low on the divider, away from the light's marker (near the top of the image).
    let on_divider = egui::pos2(rect.center().x + 4.0, rect.bottom() - 10.0);
    let marker = rect.min + light_marker(&s0).unwrap() * rect.size();
    assert!(marker.distance(on_divider) > 50.0);
    drag(
        &mut h,
        on_divider,
        egui::pos2(rect.left() + 0.25 * rect.width(), rect.bottom() - 40.0),
    );
    let divider = comparing(&h).divider.at;
    assert!((divider - 0.25).abs() < 0.01, "{divider}");
    assert_eq!(
        settings(&h),
        s0,
        "the divider's drag moved the camera or light"
    );

    // Elsewhere, the camera turns and the divider stays.
    let elsewhere = egui::pos2(rect.left() + 0.7 * rect.width(), rect.center().y);
    drag(&mut h, elsewhere, elsewhere + egui::vec2(40.0, 0.0));
    let s1 = settings(&h);
    assert!(
        s1.camera.yaw > s0.camera.yaw,
        "{} {}",
        s1.camera.yaw,
        s0.camera.yaw
    );
    assert_eq!(comparing(&h).divider.at, divider);
    settle(&mut h);

    // The light's marker, even on the divider, moves the light.
    comparing_mut(&mut h).divider.at = light_marker(&s1).unwrap().x;
    h.step();
    let rect = h.state().viewport.shown_rect().unwrap();
    let marker = rect.min + light_marker(&s1).unwrap() * rect.size();
    drag(&mut h, marker, marker + egui::vec2(30.0, 10.0));
    let s2 = settings(&h);
    assert_eq!(s2.camera, s1.camera);
    assert!(s2.light.position.x > s1.light.position.x + 0.05);
    assert_eq!(comparing(&h).divider.at, light_marker(&s1).unwrap().x);
    settle(&mut h);
}

fn comparing_mut<'a>(h: &'a mut Harness<'_, WorkbenchApp>) -> &'a mut compare::Compare {
    h.state_mut().compare.as_mut().expect("comparing")
}

/// "Stop comparing" drops A and its renderer; the live image goes on.
#[test]
fn stop_comparing_drops_a_and_its_controller() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    h.get_by_role_and_label(Role::Button, "Stop comparing")
        .click();
    h.step();
    assert!(h.state().compare.is_none());
    h.step();
    assert!(h.query_by_label("Difference |A − B|").is_none());
    assert!(h.query_by_label_contains("A: pass").is_none());
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    settle(&mut h);
    assert!(!shown(&h).settings.shading.shadows);
}

/// A and B at different resolutions: both drawn fitted into one rect, and the difference
/// explains why there is none.
#[test]
fn compare_at_different_resolutions_says_the_difference_needs_one() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    h.get_by_role_and_label(Role::SpinButton, "Width")
        .set_value_accesskit(64.0);
    tick_difference(&mut h);
    assert_eq!(shown(&h).image.width, 64);
    assert_eq!(a_frame(&h).image.width, 128);
    assert!(comparing(&h).difference_shown().is_none());
    assert!(
        h.query_by_label_contains("Difference needs the same resolution")
            .is_some()
    );
    assert!(h.query_by_label_contains("differ in: resolution").is_some());
}

/// "Lab vs sRGB display": A keeps the display it was frozen with, B shows the live one; the
/// linear images are the same, so the difference says so.
#[test]
fn compare_keeps_as_display_while_bs_changes() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    h.get_by_role_and_label(Role::Slider, "Exposure")
        .set_value_accesskit(1.0);
    tick_difference(&mut h);
    let (a, b) = (a_frame(&h), shown(&h));
    assert_eq!(a.image, b.image);
    let frozen = comparing(&h).settings().display;
    let live = settings(&h).display;
    assert_eq!((frozen.exposure, live.exposure), (0.0, 1.0));
    assert_eq!(
        comparing(&h).a_rgba().unwrap(),
        frozen.to_rgba8(&a.image.pixels)
    );
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        live.to_rgba8(&b.image.pixels)
    );
    assert!(h.query_by_label("A and B differ in: exposure").is_some());
    assert!(h.query_by_label("A and B are identical").is_some());
}

/// The inspector: I turns it on, a click pins a pixel, its R line is the pixel's displayed value
/// (one sample: the image is sample 0), Shift + arrows move the pixel, and it is outlined.
#[test]
fn the_inspector_explains_a_clicked_pixel() {
    let mut h = harness(small_state());
    h.key_press(Key::I);
    // The inspector's panel takes its place beside the image over a frame or two.
    h.run_steps(3);
    assert!(h.state().state.inspect_mode);
    let rect = h.state().viewport.shown_rect().unwrap();
    // The centre of pixel (40, 70): the floor, lit.
    let at = egui::vec2(40.5 / 128.0, 70.5 / 96.0);
    let pos = rect.min + at * rect.size();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_steps(2);
    assert_eq!(h.state().state.pinned, Some([40, 70]));
    assert!(
        h.query_by_label_contains("Inspector: pixel (40, 70)")
            .is_some()
    );
    assert!(
        h.query_by_label_contains("D = P·max(r̂·n̂, 0)/(4πr²)")
            .is_some()
    );
    assert!(h.query_by_label_contains("R = ρ·(D + N)").is_some());
    let s = settings(&h);
    let inspection =
        raylab_core::teaching::inspect::inspect_pixel(&cornell_box(), &s, 40, 70).unwrap();
    assert_eq!(inspection.r, shown(&h).image.get(40, 70));
    assert_eq!(
        h.state().viewport.pinned.map(|r| r.min),
        Some(egui::pos2(40.0 / 128.0, 70.0 / 96.0))
    );
    // Shift + Right moves it by one pixel and leaves the camera alone.
    h.key_press_modifiers(Modifiers::SHIFT, Key::ArrowRight);
    h.step();
    assert_eq!(h.state().state.pinned, Some([41, 70]));
    assert_eq!(settings(&h).camera, s.camera);
    h.get_by_role_and_label(Role::Button, "Copy as text");
    h.get_by_role_and_label(Role::Button, "Unpin").click();
    h.step();
    assert_eq!(h.state().state.pinned, None);
    settle(&mut h);
}

/// A debug view comes from the tracer, with its legend beside it: the depth view shows what
/// `view::render_view` computes, and its legend gives the range of t.
#[test]
fn the_view_selector_shows_a_debug_view_with_its_legend() {
    let mut h = harness(small_state());
    choose(&mut h, "View", "Depth t");
    settle(&mut h);
    let s = settings(&h);
    assert_eq!(s.view, raylab_core::transport::view::View::Depth);
    let expected =
        raylab_core::transport::view::render_view(&cornell_box(), &s, s.view, &|| false).unwrap();
    assert_eq!(*shown(&h).image, expected.image);
    assert_eq!(h.state().stats.legend.as_ref(), Some(&expected.legend));
    assert!(h.query_by_label_contains(&expected.legend.title).is_some());
    // The texture shows the view through the lab's display, whatever the display in force.
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        raylab_core::transport::display::Display::default().to_rgba8(&expected.image.pixels)
    );
    choose(&mut h, "View", "Shaded (the stage)");
    settle(&mut h);
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
    assert_eq!(h.state().stats.legend, None);
}

/// With the camera behind the box (z = 2) the image is black, and the
/// status line says why; back in front of the box, the note goes.
#[test]
fn a_camera_that_sees_nothing_says_why() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::Slider, "Camera z")
        .set_value_accesskit(2.0);
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice, "{text}");
    assert!(text.contains("outside the box"), "{text}");
    assert!(shown(&h).image.pixels.iter().all(|p| *p == Vec3::ZERO));
    h.get_by_role_and_label(Role::Button, "Reset camera")
        .click();
    settle(&mut h);
    assert!(h.state().status.is_none(), "{:?}", h.state().status);
}

/// Steps frames until the status line shows an error (or fails after [`DEADLINE`]).
fn until_error(h: &mut Harness<'_, WorkbenchApp>) -> String {
    let start = Instant::now();
    loop {
        h.step();
        if let Some(status) = h
            .state()
            .status
            .as_ref()
            .filter(|s| s.kind == StatusKind::Error)
        {
            return status.text.clone();
        }
        assert!(start.elapsed() < DEADLINE, "no error within {DEADLINE:?}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn a_render_that_panics_is_reported_and_the_next_change_renders() {
    let mut h = harness(small_state());
    let before = shown(&h);
    h.state()
        .controller
        .as_ref()
        .unwrap()
        .inject_panic_on_next_pass();
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    let text = until_error(&mut h);
    let failed = settings(&h);
    assert!(!failed.shading.shadows);
    assert_eq!(
        text,
        format!(
            "The render panicked: {} (settings: {})",
            raylab_core::transport::progressive::INJECTED_PANIC,
            failed.summary()
        )
    );
    assert!(text.contains("128×96"), "{text}");
    // On screen, with the failed settings to copy, as JSON.
    assert!(h.query_by_label_contains("The render panicked").is_some());
    assert!(h.query_by_label("Copy details").is_some());
    let details = h.state().status.clone().unwrap().details.unwrap();
    assert_eq!(
        serde_json::from_str::<RenderSettings>(&details).unwrap(),
        failed
    );
    // Nothing of the failed job was shown: the image is the one before it.
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
    assert_eq!(shown(&h).generation, before.generation);
    assert_eq!(
        status(&h).1,
        StatusKind::Error,
        "the error stays until a change"
    );

    // A change renders again, and the error goes with its first frame.
    h.get_by_role_and_label(Role::CheckBox, "Indirect light")
        .click();
    settle(&mut h);
    assert!(h.state().status.is_none(), "{:?}", h.state().status);
    let after = shown(&h);
    assert!(after.generation > before.generation + 1);
    assert_eq!(after.settings, settings(&h));
    assert!(!after.settings.shading.shadows && !after.settings.shading.indirect);
    assert_eq!(*after.image, render(&cornell_box(), &after.settings));
}

#[test]
fn a_scene_load_that_panics_is_reported_and_keeps_the_scene() {
    let mut h = harness(small_state());
    let before = shown(&h);
    h.state_mut().inject_loader_panic = true;
    choose(&mut h, "Scene", "Utah teapot");
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert_eq!(
        text,
        "Loading the teapot scene panicked: injected loader panic"
    );
    assert_eq!(settings(&h).scene, SceneChoice::Cornell);
    assert_eq!(shown(&h).image, before.image);
    // The next load works.
    choose(&mut h, "Scene", "Utah teapot");
    settle(&mut h);
    assert_eq!(shown(&h).settings.scene, SceneChoice::Teapot);
    assert_eq!(status(&h).1, StatusKind::Info);
}

#[test]
fn a_panic_rendering_a_is_reported_and_b_goes_on() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    comparing(&h).inject_panic_on_next_pass();
    // A thread change re-renders both sides: A's first pass panics, B renders.
    h.get_by_role_and_label(Role::Slider, "Render threads")
        .set_value_accesskit(1.0);
    let text = until_error(&mut h);
    let a = comparing(&h).settings().clone();
    assert_eq!(
        text,
        format!(
            "A: The render panicked: {} (settings: {})",
            raylab_core::transport::progressive::INJECTED_PANIC,
            a.summary()
        )
    );
    assert!(h.state().status.clone().unwrap().details.is_some());
    let start = Instant::now();
    while shown(&h).generation != h.state().controller.as_ref().unwrap().generation()
        || !shown(&h).is_final()
    {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
    // B's frames don't take A's error down: A will not render again by itself.
    assert_eq!(status(&h).1, StatusKind::Error);
}

/// The light's shape and the rough metal from the panels: a square light of the default side,
/// the rough preset with its roughness slider; the image is the library's for those settings.
#[test]
fn the_light_shape_and_the_rough_metal_are_chosen_in_the_panels() {
    let mut h = harness(tiny_state());
    choose(&mut h, "Light shape", "Square (quad)");
    let s = settings(&h);
    assert_eq!(
        s.light.kind,
        raylab_core::shading::light::LightKind::Quad {
            side: raylab_core::shading::light::DEFAULT_QUAD_SIDE
        }
    );
    // The size slider names what it sets.
    h.get_by_role_and_label(Role::Slider, "Light side");
    assert!(h.query_by_label("Roughness α").is_none());
    choose(&mut h, "Materials", "Rough metal tall block");
    h.get_by_role_and_label(Role::Slider, "Roughness α")
        .set_value_accesskit(0.5);
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(frame.settings.material_preset, MaterialPreset::Rough);
    assert_eq!(frame.settings.roughness, 0.5);
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
}

/// Choosing Spot in the light panel makes the lab's spot (aimed at (0, 1, −0.2), cutoff 25°,
/// beam 15°) and re-renders: the image shown is the library's for it, not the point light's;
/// the cutoff slider, in degrees, reaches the settings, and the beam follows a cutoff set
/// below it.
#[test]
fn choosing_the_spot_light_re_renders_with_its_cone() {
    use raylab_core::shading::light::{LightKind, SpotCone};
    let mut h = harness(tiny_state());
    settle(&mut h);
    let point = shown(&h).image.clone();
    choose(&mut h, "Light shape", "Spot");
    assert_eq!(
        settings(&h).light.kind,
        LightKind::Spot(SpotCone::default())
    );
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(
        frame.settings.light.kind,
        LightKind::Spot(SpotCone::default())
    );
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
    assert_ne!(*frame.image, *point);
    h.get_by_role_and_label(Role::Slider, "Spot cutoff")
        .set_value_accesskit(10.0);
    settle(&mut h);
    let LightKind::Spot(cone) = settings(&h).light.kind else {
        panic!("not a spot: {:?}", settings(&h).light.kind);
    };
    assert_eq!(cone.cutoff, raylab_core::base::camera::radians(10.0));
    assert_eq!(cone.beam, cone.cutoff);
    let frame = shown(&h);
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
}

/// The plastic from the Materials choice: its roughness slider starts at the coating's 0.1 and
/// sets α; the image is the library's for those settings, its tall block lit by a highlight
/// the diffuse block does not have.
#[test]
fn the_plastic_is_chosen_in_the_panels() {
    let mut h = harness(tiny_state());
    settle(&mut h);
    let diffuse = shown(&h);
    choose(&mut h, "Materials", "Glossy plastic tall block");
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(frame.settings.material_preset, MaterialPreset::Plastic);
    assert_eq!(frame.settings.roughness, 0.1);
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
    assert_ne!(*frame.image, *diffuse.image);
    h.get_by_role_and_label(Role::Slider, "Roughness α")
        .set_value_accesskit(0.3);
    settle(&mut h);
    let frame = shown(&h);
    assert_eq!(frame.settings.roughness, 0.3);
    assert_eq!(*frame.image, render(&cornell_box(), &frame.settings));
}

/// A saved state whose scene cannot be loaded (here a FIFO given as the model, which would
/// keep the loader waiting for ever) never keeps the window from starting: it opens on the
/// lab's box, and a notice says why.
#[test]
fn a_saved_scene_that_cannot_be_loaded_falls_back_to_the_labs_box() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("model.obj");
    raylab_core::base::inputs::make_fifo(&fifo);
    let mut state = small_state();
    state.settings.scene = SceneChoice::Obj(fifo);
    let h = harness(state);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice);
    assert!(
        text.starts_with("The saved scene could not be loaded")
            && text.contains("not a regular file (a FIFO)")
            && text.ends_with("showing the cornell scene"),
        "{text}"
    );
    assert_eq!(settings(&h).scene, SceneChoice::Cornell);
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
}
