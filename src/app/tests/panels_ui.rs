//! What the panels say and allow: the "Computes" line names the extensions in force, controls
//! that do nothing in a stage are disabled with the reason, messages go when their cause does,
//! the walk-through gives back the settings it found, the inspector leaves the image at 1:1,
//! sampled effects raise the sample target, and a mirror's dark front face is explained.

use super::files_ui::type_number;
use super::*;

/// The text of the node labelled `label` with role `role`: its value (a text field's text).
fn value_of(h: &Harness<'_, WorkbenchApp>, role: Role, label: &str) -> String {
    let node = h.get_by_role_and_label(role, label).accesskit_node();
    node.value().unwrap_or_default()
}

#[test]
fn the_computes_line_names_the_extensions_in_force() {
    let mut h = harness(small_state());
    let lab = "ρ·(D + N) (eq. 30) with shadows (§5.1)";
    assert!(h.query_by_label(lab).is_some());
    choose(&mut h, "Textures", "Checkerboard floor");
    h.get_by_role_and_label(Role::Slider, "Light radius")
        .set_value_accesskit(0.15);
    h.get_by_role_and_label(Role::Slider, "Aperture")
        .set_value_accesskit(0.1);
    // The colour picker is a popup of its own: the colour is set as it would leave it.
    h.state_mut().state.settings.light.colour = Vec3::new(1.0, 0.6, 0.3);
    h.run_steps(3);
    // Soft shadows and depth of field raised the target to 256 samples: anti-aliased too.
    let expected = format!(
        "{lab} · textured ρ · soft shadows from a sphere light with radius 0.15 · coloured light · \
         depth of field (aperture 0.1) · anti-aliased over {SOFT_SAMPLE_TARGET} samples"
    );
    assert!(
        h.query_by_label(&expected).is_some(),
        "{expected} not found; the settings say {}",
        settings(&h).description()
    );
    // Back to the lab's light and lens, one sample: the lab's words again.
    h.state_mut().state.settings.light.colour = Vec3::ONE;
    h.get_by_role_and_label(Role::Slider, "Light radius")
        .set_value_accesskit(0.0);
    h.get_by_role_and_label(Role::Slider, "Aperture")
        .set_value_accesskit(0.0);
    choose(&mut h, "Textures", "None (the lab)");
    set_target(&mut h, 1);
    h.run_steps(2);
    assert!(h.query_by_label(lab).is_some());
    settle(&mut h);
}

#[test]
fn the_flat_stage_disables_the_switches_it_ignores() {
    let mut h = harness(small_state());
    let disabled = |h: &Harness<'_, WorkbenchApp>, role: Role, label: &str| {
        h.get_by_role_and_label(role, label)
            .accesskit_node()
            .is_disabled()
    };
    assert!(!disabled(&h, Role::CheckBox, "Shadows"));
    assert!(!disabled(&h, Role::CheckBox, "Indirect light"));
    choose(&mut h, "Stage", "Flat colour (figure 2)");
    assert!(disabled(&h, Role::CheckBox, "Shadows"));
    assert!(disabled(&h, Role::CheckBox, "Indirect light"));
    assert!(disabled(&h, Role::Slider, "Indirect N"));
    // Hovering says why.
    h.get_by_role_and_label(Role::CheckBox, "Shadows").hover();
    let why = "The flat stage shows the reflectance ρ alone";
    // The tooltip shows after egui's hover delay.
    for _ in 0..120 {
        if h.query_by_label_contains(why).is_some() {
            break;
        }
        h.step();
    }
    assert!(h.query_by_label_contains(why).is_some());
    choose(&mut h, "Stage", "Lab (figure 7)");
    assert!(!disabled(&h, Role::CheckBox, "Shadows"));
    assert!(!disabled(&h, Role::CheckBox, "Indirect light"));
    settle(&mut h);
}

/// After the last step (path tracing, mirror and glass), "Leave" gives back the stage,
/// materials and samples the walk started from; the camera moved meanwhile stays moved.
#[test]
fn leaving_the_walkthrough_puts_back_the_settings_it_found() {
    let mut state = small_state();
    state.settings.shading = Shading::for_stage(Stage::Shadows);
    state.settings.material_preset = MaterialPreset::Glass;
    state.settings.samples_per_pixel = 3;
    let mut h = harness(state);
    let user = settings(&h);
    h.get_by_label("Lab walk-through").click();
    h.step();
    h.get_by_role_and_label(Role::Button, "Start the walk-through")
        .click();
    h.run_steps(2);
    for _ in 1..raylab_core::teaching::walkthrough::STEPS.len() {
        h.get_by_role_and_label(Role::Button, "Next").click();
        h.run_steps(2);
    }
    let of = raylab_core::teaching::walkthrough::STEPS.len();
    assert!(
        h.query_by_label_contains(&format!("Step {of} of {of}"))
            .is_some()
    );
    let walked = settings(&h);
    assert_eq!(walked.shading.stage, Stage::Path);
    assert_eq!(walked.material_preset, MaterialPreset::Glass);
    assert_eq!(
        walked.shading.caustics,
        raylab_core::transport::settings::Caustics::Photons
    );
    h.get_by_role_and_label(Role::Slider, "Camera x")
        .set_value_accesskit(0.25);
    h.step();
    h.get_by_role_and_label(Role::Button, "Leave").click();
    h.run_steps(2);
    assert_eq!(h.state().state.walk_step, None);
    let mut expected = user.clone();
    expected.camera.position.x = 0.25;
    assert_eq!(settings(&h), expected);
    assert!(status(&h).0.starts_with("Left the walk-through"));
    settle(&mut h);
    assert_eq!(*shown(&h).image, render(&cornell_box(), &expected));
}

#[test]
fn stop_comparing_takes_down_the_advice_for_comparing() {
    let mut h = harness(small_state());
    freeze_a(&mut h);
    assert!(status(&h).0.starts_with("Frozen as A"));
    assert!(h.query_by_label_contains("Frozen as A").is_some());
    h.get_by_role_and_label(Role::Button, "Stop comparing")
        .click();
    h.run_steps(2);
    assert!(h.state().status.is_none(), "{:?}", h.state().status);
    assert!(h.query_by_label_contains("Frozen as A").is_none());
    assert!(h.query_by_label_contains("Ready.").is_some());
}

/// Text that is not a number says so, in place of an older message about the field; a good
/// number typed there takes the message down.
#[test]
fn a_typed_non_number_says_so_and_a_good_number_clears_the_message() {
    let mut h = harness(small_state());
    let before = settings(&h);
    type_number(&mut h, "Light power", "150");
    assert!(status(&h).0.contains("150 is outside"), "{}", status(&h).0);
    type_number(&mut h, "Light power", "abc");
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice);
    assert_eq!(
        text,
        "Light power: \"abc\" is not a number, so the value was kept"
    );
    assert!(h.query_by_label_contains("is not a number").is_some());
    assert_eq!(settings(&h).light.power, 100.0, "kept the clamped 150");
    type_number(&mut h, "Light x", "NaN");
    assert_eq!(
        status(&h).0,
        "Light x: \"NaN\" is not a finite number, so the value was kept"
    );
    assert_eq!(settings(&h).light.position, before.light.position);
    // A good number in another field leaves the message alone; in its own field, takes it down.
    type_number(&mut h, "Light power", "20");
    assert!(status(&h).0.starts_with("Light x:"), "{}", status(&h).0);
    type_number(&mut h, "Light x", "0.1");
    assert!(h.state().status.is_none(), "{:?}", h.state().status);
    assert!(h.query_by_label_contains("is not a").is_none());
    assert_eq!(settings(&h).light.power, 20.0);
    settle(&mut h);
}

/// The File field names the scene's file: after a built-in scene is chosen it is empty, not
/// the model opened before.
#[test]
fn the_file_field_follows_the_scene() {
    let mut h = harness(small_state());
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/models/teapot.obj");
    h.get_by_role_and_label(Role::TextInput, "File").focus();
    h.step();
    h.get_by_role_and_label(Role::TextInput, "File")
        .type_text(path);
    h.step();
    h.get_by_role_and_label(Role::Button, "Open").click();
    settle(&mut h);
    assert_eq!(settings(&h).scene, SceneChoice::Obj(path.into()));
    assert_eq!(value_of(&h, Role::TextInput, "File"), path);
    choose(&mut h, "Scene", "Stanford bunny");
    settle(&mut h);
    assert_eq!(shown(&h).settings.scene, SceneChoice::Bunny);
    assert_eq!(h.state().state.obj_path, "");
    assert_eq!(value_of(&h, Role::TextInput, "File"), "");
}

/// "Reset to lab defaults" also unticks "Click to focus": a click on the image turns the
/// camera again, as in the lab.
#[test]
fn reset_unticks_click_to_focus() {
    let mut h = harness(small_state());
    h.get_by_role_and_label(Role::CheckBox, "Click to focus")
        .click();
    h.step();
    assert!(h.state().state.focus_mode);
    h.get_by_role_and_label(Role::Button, "Reset to lab defaults")
        .click();
    h.run_steps(2);
    assert!(!h.state().state.focus_mode);
    let node = h
        .get_by_role_and_label(Role::CheckBox, "Click to focus")
        .accesskit_node();
    assert_eq!(node.toggled(), Some(egui::accesskit::Toggled::False));
    assert_eq!(settings(&h), lab_defaults());
}

/// At the window's default size, with the inspector open, the lab's 512² image is shown at
/// 1:1: the inspector takes what is left, not its old 380 pt minimum.
#[test]
fn the_inspector_leaves_the_512_image_at_1_to_1_at_the_default_window_size() {
    let mut state = WorkbenchState::default();
    state.settings.samples_per_pixel = 1;
    state.render_threads = 2;
    assert_eq!(state.settings.camera.width, 512);
    let mut h = Harness::builder()
        .with_size([1180.0, 760.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    settle(&mut h);
    h.key_press(Key::I);
    h.run_steps(3);
    assert!(h.state().state.inspect_mode);
    assert!(
        h.query_by_label_contains("Click a pixel of the image")
            .is_some()
    );
    let rect = h.state().viewport.shown_rect().unwrap();
    assert!(rect.width() >= 512.0, "{rect:?}");
    // Pinning a pixel fills the inspector; the image keeps its size.
    let pos = rect.min + egui::vec2(0.3, 0.8) * rect.size();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_steps(3);
    assert!(h.state().state.pinned.is_some());
    let rect = h.state().viewport.shown_rect().unwrap();
    assert!(rect.width() >= 512.0, "{rect:?}");
    settle(&mut h);
}

/// Soft shadows and depth of field raise the lab stage's target as the path stage raises its
/// own, and the status line says so; a target lowered afterwards stays as set.
#[test]
fn soft_shadows_and_depth_of_field_raise_the_sample_target() {
    let mut state = small_state();
    state.settings.samples_per_pixel = 16;
    let mut h = harness(state);
    h.get_by_role_and_label(Role::Slider, "Light radius")
        .set_value_accesskit(0.15);
    h.run_steps(2);
    assert_eq!(settings(&h).samples_per_pixel, SOFT_SAMPLE_TARGET);
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Info);
    assert!(
        text.starts_with("Soft shadows: refining to 256 samples (the target was 16)"),
        "{text}"
    );
    assert!(
        h.query_by_label_contains("refining to 256 samples")
            .is_some()
    );
    // Lowered by hand, it stays lowered.
    set_target(&mut h, 8);
    h.run_steps(2);
    assert_eq!(settings(&h).samples_per_pixel, 8);
    h.get_by_role_and_label(Role::Slider, "Aperture")
        .set_value_accesskit(0.1);
    h.run_steps(2);
    assert_eq!(settings(&h).samples_per_pixel, SOFT_SAMPLE_TARGET);
    assert!(
        status(&h).0.starts_with("Depth of field: refining to 256"),
        "{}",
        status(&h).0
    );
    set_target(&mut h, 2);
    settle(&mut h);
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
}

/// With a mirror chosen, the Materials row says why its front face is black.
#[test]
fn a_mirror_preset_explains_its_black_front_face() {
    let mut h = harness(small_state());
    let hint = "it reflects the box's open front, the void behind the camera";
    assert!(h.query_by_label_contains(hint).is_none());
    choose(&mut h, "Materials", "Mirror tall block");
    assert!(h.query_by_label_contains(hint).is_some());
    choose(&mut h, "Materials", "Glass short block");
    assert!(h.query_by_label_contains(hint).is_none());
    choose(&mut h, "Materials", "Mirror and glass");
    assert!(h.query_by_label_contains(hint).is_some());
    settle(&mut h);
}

/// The light panel offers every kind of `light_kinds!` by its label, and for each its every
/// parameter by the table's label (a point as its x, y and z); a parameter set there reaches
/// the settings.
#[test]
fn the_light_panel_offers_every_kind_and_its_parameters() {
    use raylab_core::shading::light::{LightKind, LightShape, ParamType};
    let mut h = harness(tiny_state());
    // The first kind, the lab's point, is shown already: each other one is chosen.
    for (i, &shape) in LightShape::ALL.iter().enumerate() {
        if i > 0 {
            choose(&mut h, "Light shape", shape.label());
        }
        assert_eq!(settings(&h).light.kind.shape(), shape);
        for p in LightKind::of_shape(shape).params() {
            match p.ty {
                ParamType::Point => {
                    for axis in ["x", "y", "z"] {
                        h.get_by_role_and_label(Role::Slider, &format!("{} {axis}", p.label));
                    }
                }
                ParamType::Size | ParamType::Angle => {
                    h.get_by_role_and_label(Role::Slider, p.label);
                }
            }
        }
    }
    // The spot's aim's x set from the panel.
    if settings(&h).light.kind.shape() != LightShape::Spot {
        choose(&mut h, "Light shape", LightShape::Spot.label());
    }
    h.get_by_role_and_label(Role::Slider, "Aim x")
        .set_value_accesskit(0.25);
    h.run_steps(2);
    let LightKind::Spot(cone) = settings(&h).light.kind else {
        panic!("not a spot: {:?}", settings(&h).light.kind);
    };
    assert_eq!(cone.aim.x, 0.25);
}
