//! Check my image in the window: a student's render dropped on the window or opened by its
//! typed path is held against the exact figure for the settings in force, which the camera
//! takes the image's size for; the diagnosis follows the settings; the wipe, the difference
//! picture and the inspector show the two images; what cannot be checked says why.

use raylab_core::teaching::check::{self as core_check, Mistake, Rgb8};

use crate::app::check::{StudentCheck, figure_settings};

use super::files_ui::{click, drop_file, type_path};
use super::*;

/// The figure for `settings` as the lab writes it, with `mistake` applied (its first look).
fn mistaken(settings: &RenderSettings, mistake: Mistake) -> Rgb8 {
    core_check::mistakes::looks(&cornell_box(), settings, mistake).swap_remove(0)
}

/// Writes `image` as `name` (its format from the extension) in `dir`.
fn write(image: &Rgb8, dir: &Path, name: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    image::RgbImage::from_raw(image.width, image.height, image.data.clone())
        .unwrap()
        .save(&path)
        .unwrap();
    path
}

fn checking<'a>(h: &'a Harness<'_, WorkbenchApp>) -> &'a StudentCheck {
    h.state().check.as_ref().expect("checking an image")
}

/// The verdict in the panel, once the check is settled.
fn verdict(h: &Harness<'_, WorkbenchApp>) -> String {
    let s = settings(h);
    match checking(h).checked(&s) {
        Some(Ok(c)) => c.report.best.mistake.clone(),
        other => panic!("no diagnosis: {:?}", other.map(|r| r.as_ref().err())),
    }
}

/// The direct stage's figure upside down, 96 × 72 (the window renders 128 × 96), saved as SDL
/// saves it, dropped on the window: the camera takes the image's size with the same field of
/// view; at the lab stage no classic mistake explains it; at the direct stage, the one it was
/// made with, the panel names `upside-down`. The wipe shows both images, the difference
/// picture is |yours − figure|, and the inspector gives both pixels.
#[test]
fn a_dropped_image_is_diagnosed_and_the_diagnosis_follows_the_settings() {
    let dir = tempfile::tempdir().unwrap();
    let mut figure_settings = small_state().settings;
    figure_settings.camera = figure_settings.camera.with_resolution(96, 72);
    figure_settings.shading = Shading::for_stage(Stage::Direct);
    let image = mistaken(&figure_settings, Mistake::UpsideDown);
    let path = write(&image, dir.path(), "my-render.bmp");

    let mut h = harness(small_state());
    let fov_before = {
        let c = settings(&h).camera;
        c.width as f32 / c.focal_length
    };
    drop_file(&mut h, &path);
    settle(&mut h);
    let camera = settings(&h).camera;
    assert_eq!((camera.width, camera.height), (96, 72));
    assert_eq!(camera.width as f32 / camera.focal_length, fov_before);
    assert_eq!(checking(&h).image(), Some(&image));
    let (text, _) = status(&h);
    assert!(
        text.starts_with("Checking my-render.bmp (96 × 72)"),
        "{text}"
    );
    assert_ne!(
        verdict(&h),
        "upside-down",
        "the lab stage is not the image's"
    );

    choose(&mut h, "Stage", "Direct light (figure 5)");
    settle(&mut h);
    assert_eq!(verdict(&h), "upside-down");
    assert!(h.query_by_label_contains("Verdict: upside-down").is_some());
    assert!(h.query_by_label_contains("Fix: Write pixel").is_some());
    let s = settings(&h);
    let Some(Ok(checked)) = checking(&h).checked(&s) else {
        panic!("no diagnosis")
    };
    // The figure is the library's, at one sample a pixel, whatever the window's target.
    let mut one_sample = s.clone();
    one_sample.samples_per_pixel = 1;
    assert_eq!(
        checked.figure,
        Rgb8::from_linear(&render(&cornell_box(), &one_sample))
    );
    let figure = checked.figure.clone();

    // The difference picture: |yours − figure| × 8 per channel, on the texture.
    h.get_by_role_and_label(Role::CheckBox, "Difference |yours − figure|")
        .click();
    h.run_steps(2);
    assert!(checking(&h).difference);
    let want: Vec<u8> = core_check::compare::difference_picture(&image, &figure)
        .data
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    assert_eq!(checking(&h).difference_rgba(), Some(want));

    // The inspector: both pixels, the student's and the figure's.
    h.key_press(Key::I);
    h.run_steps(2);
    h.state_mut().state.pinned = Some([10, 60]);
    h.run_steps(2);
    let (a, b) = (image.get(10, 60), figure.get(10, 60));
    let line = format!(
        "Your image: ({}, {}, {}) · exact figure: ({}, {}, {})",
        a[0], a[1], a[2], b[0], b[1], b[2]
    );
    assert!(h.query_by_label_contains(&line).is_some(), "{line}");

    // Stop checking: back to the live image, and the check's status line goes with it.
    assert!(status(&h).0.starts_with("Checking "), "{}", status(&h).0);
    click(&mut h, "Stop checking");
    assert!(h.state().check.is_none());
    settle(&mut h);
    assert!(h.state().status.is_none(), "{:?}", status(&h));
}

/// The exact figure at the window's own size, typed into the File field and checked: `none`.
/// Freezing A for a comparison ends the check (one overlay at a time).
#[test]
fn the_exact_figure_typed_in_is_none() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(small_state());
    let s = figure_settings(&settings(&h));
    let exact = Rgb8::from_linear(&render(&cornell_box(), &s));
    let path = write(&exact, dir.path(), "exact.png");
    type_path(&mut h, path.to_str().unwrap());
    h.get_by_label("Check my image").click();
    h.step();
    click(&mut h, "Check the typed file");
    settle(&mut h);
    assert_eq!(verdict(&h), "none");
    assert!(
        h.query_by_label_contains("Verdict: none — your image is the exact figure")
            .is_some()
    );
    assert!(h.query_by_label_contains("Match: 100.0 %").is_some());
    click(&mut h, "Freeze as A");
    assert!(h.state().check.is_none());
    assert!(h.state().compare.is_some());
    settle(&mut h);
}

/// What cannot be checked says why and the app goes on: a file that is not there, a text file
/// called .bmp, settings beyond the lab's figures (the path stage).
#[test]
fn what_cannot_be_checked_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(small_state());
    let missing = dir.path().join("missing.bmp");
    drop_file(&mut h, &missing);
    settle(&mut h);
    assert!(h.state().check.is_none());
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(text.contains("missing.bmp"), "{text}");

    let junk = dir.path().join("junk.bmp");
    std::fs::write(&junk, "not an image").unwrap();
    drop_file(&mut h, &junk);
    settle(&mut h);
    assert!(h.state().check.is_none());
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(text.contains("junk.bmp"), "{text}");

    // A good image, but the path stage is none of the lab's figures.
    let s = figure_settings(&settings(&h));
    let path = write(
        &Rgb8::from_linear(&render(&cornell_box(), &s)),
        dir.path(),
        "ok.ppm",
    );
    drop_file(&mut h, &path);
    settle(&mut h);
    choose(&mut h, "Stage", "Path tracing (real light)");
    settle(&mut h);
    let s = settings(&h);
    match checking(&h).checked(&s) {
        Some(Err(e)) => assert!(e.contains("path stage"), "{e}"),
        other => panic!("{:?}", other.map(|r| r.as_ref().map(|c| &c.report))),
    }
    assert!(h.query_by_label_contains("the path stage").is_some());
}

/// Raylab's own render of the pool (water: mirror and glass at once), dropped on the window
/// with the pool in it: the panel gives `none` at a 100 % match, as the command line does
/// (once the check panicked and the panel showed the panic's text).
#[test]
fn a_render_of_the_pool_is_the_exact_figure() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.settings.scene = raylab_core::shapes::scene::SceneChoice::Pool;
    let mut s = figure_settings(&state.settings);
    s.camera = s.camera.with_resolution(64, 48);
    let scene = s.scene.load().unwrap();
    let path = write(
        &Rgb8::from_linear(&render(&scene, &s)),
        dir.path(),
        "pool.png",
    );
    let mut h = harness(state);
    drop_file(&mut h, &path);
    settle(&mut h);
    assert_eq!(verdict(&h), "none");
    assert!(h.query_by_label_contains("Match: 100.0 %").is_some());
    assert!(
        h.query_by_label_contains("Verdict: none — your image is the exact figure")
            .is_some()
    );
}

/// A figure 6 render (no N) checked with the window at figure 7: the panel says it is figure
/// 6 with N missing and offers "Switch to figure 6", which sets the stage and its switches;
/// the check follows them to `none`.
#[test]
fn another_stage_is_named_and_offered_as_a_switch() {
    let dir = tempfile::tempdir().unwrap();
    let state = small_state();
    assert_eq!(state.settings.shading.stage, Stage::Lab);
    let mut six = figure_settings(&state.settings);
    six.shading = Shading::for_stage(Stage::Shadows);
    let path = write(
        &Rgb8::from_linear(&render(&cornell_box(), &six)),
        dir.path(),
        "figure6.png",
    );
    let mut h = harness(state);
    drop_file(&mut h, &path);
    settle(&mut h);
    assert_eq!(verdict(&h), core_check::OTHER_STAGE);
    assert!(
        h.query_by_label_contains("this is figure 6: the constant indirect term N is missing")
            .is_some()
    );
    click(&mut h, "Switch to figure 6");
    settle(&mut h);
    let shading = settings(&h).shading;
    assert_eq!(
        (shading.stage, shading.shadows, shading.indirect),
        (Stage::Shadows, true, false)
    );
    assert_eq!(verdict(&h), "none");
    assert!(h.query_by_label_contains("Switch to figure").is_none());
}
