//! Files in the window: scene files and screenshots reopen to the same image (typed, through
//! the dialogs, dropped on the window); a bad file changes nothing; scene loads show progress,
//! can be cancelled, and scenes loaded before come back at once.

use std::sync::Arc;

use super::*;

/// Types `text` into the File field.
pub(super) fn type_path(h: &mut Harness<'_, WorkbenchApp>, text: &str) {
    h.get_by_role_and_label(Role::TextInput, "File").focus();
    h.step();
    // Select what is there, so the typing replaces it.
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.get_by_role_and_label(Role::TextInput, "File")
        .type_text(text);
    h.step();
    assert_eq!(h.state().state.obj_path, text);
}

pub(super) fn click(h: &mut Harness<'_, WorkbenchApp>, button: &str) {
    h.get_by_role_and_label(Role::Button, button).click();
    h.step();
}

/// A file dropped on the window, as winit hands it to egui.
#[derive(Debug)]
struct Dropped(std::path::PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

pub(super) fn drop_file(h: &mut Harness<'_, WorkbenchApp>, path: &Path) {
    h.input_mut()
        .dropped_files
        .push(Arc::new(Dropped(path.to_path_buf())));
}

/// Settings unlike the defaults in every group.
fn a_setup(h: &mut Harness<'_, WorkbenchApp>) {
    let s = &mut h.state_mut().state.settings;
    s.light.position = Vec3::new(0.3, -0.6, -0.4);
    s.light.power = 25.0;
    s.camera.yaw = 0.1;
    s.shading = Shading::for_stage(Stage::Shadows);
    s.material_preset = MaterialPreset::Mirror;
    s.samples_per_pixel = 2;
    s.seed = 5;
    settle(h);
}

#[test]
fn a_saved_scene_file_reopens_to_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(small_state());
    a_setup(&mut h);
    let saved = shown(&h);
    let path = dir.path().join("setup.toml");
    type_path(&mut h, path.to_str().unwrap());
    click(&mut h, "Save scene");
    assert!(path.is_file());
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info, "{text}");
    assert!(text.contains("setup.toml"), "{text}");

    click(&mut h, "Reset to lab defaults");
    settle(&mut h);
    assert_ne!(settings(&h), saved.settings);

    click(&mut h, "Open");
    settle(&mut h);
    assert_eq!(settings(&h), saved.settings);
    let reopened = shown(&h);
    assert_eq!(reopened.settings, saved.settings);
    assert_eq!(*reopened.image, *saved.image, "the same pixels");
    assert_eq!(status(&h).0, "Opened setup.toml");
}

#[test]
fn a_screenshot_dropped_on_the_window_restores_its_render() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().to_owned();
    let mut h = harness(state);
    a_setup(&mut h);
    let saved = shown(&h);
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    settle(&mut h);
    let png = pngs_in(dir.path()).pop().expect("a screenshot");
    let json = png.with_extension("json");

    for file in [&png, &json] {
        click(&mut h, "Reset to lab defaults");
        settle(&mut h);
        assert_ne!(settings(&h), saved.settings);
        drop_file(&mut h, file);
        settle(&mut h);
        assert_eq!(settings(&h), saved.settings, "{}", file.display());
        assert_eq!(*shown(&h).image, *saved.image);
    }
    // The PNG's own pixels are the restored render's.
    let pixels = image::open(&png).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels, shown(&h).image.to_rgb8());
}

#[test]
fn ctrl_shift_s_and_ctrl_o_save_and_open_through_the_dialogs() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().to_owned();
    let mut h = harness(state);
    a_setup(&mut h);
    let saved = settings(&h);

    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::S);
    h.run_steps(2);
    assert!(
        h.query_by_label("Save scene as").is_some(),
        "the dialog is open"
    );
    // No screenshot was taken: Ctrl+Shift+S is not Ctrl+S.
    assert!(pngs_in(dir.path()).is_empty());
    click(&mut h, "Save file");
    h.run_steps(2);
    let file = dir.path().join("cornell.toml");
    assert!(file.is_file(), "{:?}", status(&h));
    assert!(
        h.query_by_label("Save scene as").is_none(),
        "the dialog closed"
    );

    click(&mut h, "Reset to lab defaults");
    settle(&mut h);
    h.key_press_modifiers(Modifiers::COMMAND, Key::O);
    h.run_steps(2);
    // The folder's scene file is listed; a click chooses it.
    h.get_by_label("cornell.toml").click();
    h.step();
    click(&mut h, "Open file");
    settle(&mut h);
    assert_eq!(settings(&h), saved);
}

#[test]
fn a_bad_file_says_why_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(small_state());
    let before = shown(&h);
    let bad = dir.path().join("bad.toml");
    let good = raylab_core::files::scene_file::to_text(&before.settings, dir.path()).unwrap();
    std::fs::write(&bad, good.replace("power = 14.0", "power = -2.0")).unwrap();
    type_path(&mut h, bad.to_str().unwrap());
    click(&mut h, "Open");
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(
        text.contains("bad.toml") && text.contains("(power = -2.0): invalid light power -2"),
        "{text}"
    );
    assert_eq!(settings(&h), before.settings);
    assert_eq!(*shown(&h).image, *before.image);

    // A dropped file of no known kind, and a missing one: the same.
    let other = dir.path().join("notes.txt");
    std::fs::write(&other, "hello").unwrap();
    drop_file(&mut h, &other);
    settle(&mut h);
    assert_eq!(status(&h).1, StatusKind::Error);
    assert!(status(&h).0.contains("notes.txt"), "{}", status(&h).0);
    assert_eq!(settings(&h), before.settings);
}

#[test]
fn a_scene_file_whose_model_is_missing_keeps_the_last_good_scene_and_settings() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(small_state());
    let before = shown(&h);
    let mut other = before.settings.clone();
    other.light.power = 3.0;
    let mut spec = SceneChoice::Bunny.spec();
    spec.name = "lost".into();
    spec.models[0].file = "missing/dragon.obj".into();
    other.scene = SceneChoice::Custom(Box::new(spec));
    let file = dir.path().join("lost.toml");
    std::fs::write(
        &file,
        raylab_core::files::scene_file::to_text(&other, dir.path()).unwrap(),
    )
    .unwrap();
    drop_file(&mut h, &file);
    settle(&mut h);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Error);
    assert!(text.contains("dragon.obj"), "{text}");
    // Every setting is back, not only the scene.
    assert_eq!(settings(&h), before.settings);
    assert_eq!(*shown(&h).image, *before.image);
}

#[test]
fn switching_back_to_a_scene_loaded_before_is_instant() {
    let mut h = harness(small_state());
    let cornell = shown(&h);
    h.state_mut().state.settings.scene = SceneChoice::Bunny;
    settle(&mut h);
    assert_eq!(h.state().scene_choice, SceneChoice::Bunny);
    h.state_mut().state.settings.scene = SceneChoice::Cornell;
    h.step();
    // In one frame, with no loader: the box was kept.
    assert_eq!(h.state().scene_choice, SceneChoice::Cornell);
    assert!(h.state().scene_loading.is_none());
    assert!(status(&h).0.contains("kept loaded"), "{}", status(&h).0);
    settle(&mut h);
    assert_eq!(*shown(&h).image, *cornell.image);
    h.state_mut().state.settings.scene = SceneChoice::Bunny;
    h.step();
    assert_eq!(h.state().scene_choice, SceneChoice::Bunny);
}

#[test]
fn a_long_load_shows_progress_and_can_be_cancelled() {
    let mut h = harness(small_state());
    let before = shown(&h);
    h.state_mut().state.settings.scene = SceneChoice::Terrain;
    h.run_steps(2);
    assert!(
        h.state().scene_loading.is_some(),
        "the terrain takes a while"
    );
    let (text, _) = status(&h);
    assert!(text.starts_with("Loading the terrain scene: "), "{text}");
    click(&mut h, "Cancel");
    assert!(h.state().scene_loading.is_none());
    assert_eq!(settings(&h).scene, SceneChoice::Cornell);
    assert_eq!(status(&h).0, "Loading the terrain scene was cancelled");
    settle(&mut h);
    assert_eq!(*shown(&h).image, *before.image);
    // The workbench goes on.
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    settle(&mut h);
    assert!(!shown(&h).settings.shading.shadows);
}

/// Types `text` into the value box of the number field labelled `label`, then Enter.
pub(super) fn type_number(h: &mut Harness<'_, WorkbenchApp>, label: &str, text: &str) {
    let node = h
        .query_all_by_label(label)
        .find(|n| n.accesskit_node().role() == Role::SpinButton)
        .unwrap_or_else(|| panic!("no value box labelled {label}"));
    node.click();
    h.run_steps(2);
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.step();
    for c in text.chars() {
        h.event(egui::Event::Text(c.to_string()));
        h.step();
    }
    h.key_press(Key::Enter);
    h.run_steps(2);
}

/// `NaN` typed into a number field once set it to its maximum.
#[test]
fn a_typed_non_number_changes_nothing_and_a_clamped_value_says_so() {
    let mut h = harness(small_state());
    let before = settings(&h);
    for label in [
        "Light x",
        "Light power",
        "Sample target",
        "Indirect N",
        "Yaw",
    ] {
        for text in ["NaN", "nan", "inf", "abc"] {
            type_number(&mut h, label, text);
            assert_eq!(settings(&h), before, "{label} = {text}");
        }
    }
    type_number(&mut h, "Width", "NaN");
    assert_eq!(settings(&h), before, "Width = NaN");
    settle(&mut h);
    assert_eq!(*shown(&h).image, render(&cornell_box(), &before));

    type_number(&mut h, "Light power", "150");
    assert_eq!(settings(&h).light.power, 100.0);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice);
    assert_eq!(
        text,
        "Light power: 150 is outside 0 to 100, so it was set to 100"
    );
    type_number(&mut h, "Light power", "20");
    assert_eq!(settings(&h).light.power, 20.0);
}

/// Saving onto a scene file already there asks first: "Keep it" leaves the file as it was,
/// "Replace" writes over it; the typed path never replaces, it saves beside (`NAME-1.toml`).
#[test]
fn saving_over_a_scene_file_asks_first_and_the_typed_path_never_replaces() {
    let dir = tempfile::tempdir().unwrap();
    let mine = dir.path().join("cornell.toml");
    let hand_written = "# my own scene, with comments\n";
    std::fs::write(&mine, hand_written).unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().to_owned();
    let mut h = harness(state);
    a_setup(&mut h);
    let saved = settings(&h);

    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::S);
    h.run_steps(2);
    h.get_by_label("cornell.toml").click();
    h.step();
    click(&mut h, "Save file");
    h.run_steps(2);
    assert!(
        h.query_by_label_contains("already exists. Replace it?")
            .is_some()
    );
    click(&mut h, "Keep it");
    h.run_steps(2);
    assert!(h.query_by_label_contains("Replace it?").is_none());
    assert!(h.query_by_label("Save scene as").is_some(), "still open");
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), hand_written);

    click(&mut h, "Save file");
    h.run_steps(2);
    click(&mut h, "Replace");
    h.run_steps(2);
    assert!(
        h.query_by_label("Save scene as").is_none(),
        "the dialog closed"
    );
    match files::open(&mine).unwrap() {
        files::Opened::Settings(loaded) => assert_eq!(loaded.settings, saved),
        other => panic!("{other:?}"),
    }

    // The File field's path, already there: saved beside it, the status naming where.
    type_path(&mut h, mine.to_str().unwrap());
    click(&mut h, "Save scene");
    let beside = dir.path().join("cornell-1.toml");
    assert!(beside.is_file());
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info, "{text}");
    assert!(text.contains("cornell-1.toml"), "{text}");
}
