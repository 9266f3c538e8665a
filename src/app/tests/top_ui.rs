//! What a student sees first and what stays in place: the figure shown at the top of the panel
//! and in the window's title, an image typed while checking is checked (never opened as a
//! screenshot under the check), a long status line cut short beside the stats, and the
//! walk-through's buttons fixed as its text changes, with a status line that follows the step.

use crate::app::check::StudentCheck;

use super::files_ui::{click, drop_file, type_path};
use super::*;

/// The title the app asked the window for in the last frame, if it asked.
fn title_sent(h: &Harness<'_, WorkbenchApp>) -> Option<String> {
    h.output()
        .viewport_output
        .values()
        .flat_map(|v| &v.commands)
        .find_map(|c| match c {
            egui::ViewportCommand::Title(t) => Some(t.clone()),
            _ => None,
        })
}

fn top(h: &Harness<'_, WorkbenchApp>, role: Role, label: &str) -> f32 {
    h.get_by_role_and_label(role, label).rect().min.y
}

/// The stage selector, the figure and what is computed come first in the panel, above the
/// buttons and the Scene group; the window's title names the figure, and once the switches
/// leave the figure's, the stage without claiming a figure.
#[test]
fn the_figure_and_the_stage_are_at_the_top_and_in_the_title() {
    let mut h = harness(small_state());
    // The first frame's title went before the harness handed the app over.
    assert_eq!(
        h.state().window_title,
        "raylab — Figure 7: ρ·(D + N) with shadows (eq. 30)"
    );

    let heading = "Figure 7: ρ·(D + N) with shadows (eq. 30)";
    let stage = top(&h, Role::ComboBox, "Stage");
    let first_button = top(&h, Role::Button, "Save screenshot");
    assert!(h.get_by_label(heading).rect().min.y < stage);
    assert!(stage < first_button, "{stage} vs {first_button}");
    let computes = h.get_by_label("Computes").rect().min.y;
    assert!(stage < computes && computes < first_button, "{computes}");
    assert!(stage < top(&h, Role::ComboBox, "Scene"));
    assert!(stage < h.get_by_label("Lab walk-through").rect().min.y);
    // Within the first rows of the window, with no scrolling.
    assert!(stage < 80.0, "{stage}");

    // Shadows off: still the lab stage, no longer figure 7.
    h.get_by_role_and_label(Role::CheckBox, "Shadows").click();
    h.step();
    let changed = "Lab stage, not figure 7: shadows off";
    assert_eq!(title_sent(&h), Some(format!("raylab — {changed}")));
    settle(&mut h);
    assert!(h.query_by_label(changed).is_some());
    assert!(h.query_by_label_contains("Figure 7").is_none());

    // The figure 6 stage chosen at the top: its figure, in the panel and the title.
    h.get_by_role_and_label(Role::ComboBox, "Stage").click();
    h.run_steps(2);
    h.get_by_label("Shadows (figure 6)").click();
    h.step();
    let six = "Figure 6: ρ·D with shadows (eq. 28, §5.1)";
    assert_eq!(title_sent(&h), Some(format!("raylab — {six}")));
    settle(&mut h);
    assert!(h.query_by_label(six).is_some());
    assert_eq!(settings(&h).shading, Shading::for_stage(Stage::Shadows));
}

/// The lab's light made a spot is not the lab's figure: the heading says so, as it does for an
/// area light.
#[test]
fn a_spot_light_is_not_the_figure() {
    use raylab_core::shading::light::{LightKind, SpotCone};
    let mut settings = small_state().settings;
    let heading = crate::app::panels::figure_heading;
    assert_eq!(
        heading(&settings),
        "Figure 7: ρ·(D + N) with shadows (eq. 30)"
    );
    settings.light.kind = LightKind::Spot(SpotCone::default());
    assert_eq!(heading(&settings), "Lab stage, not figure 7: a spot light");
    settings.light.kind = LightKind::Sphere { radius: 0.1 };
    assert_eq!(heading(&settings), "Lab stage, not figure 7: an area light");
}

/// While an image is checked, Enter in the File field with another image checks that one: a
/// screenshot's settings (here its yaw of −10°) are not loaded under the check. The check
/// dialog's name field starts empty, not with the typed file's name.
#[test]
fn enter_while_checking_checks_the_typed_image_and_the_dialog_starts_empty() {
    let dir = tempfile::tempdir().unwrap();
    // A screenshot of another view: its PNG carries settings with a yaw of −10°.
    let mut other = small_state().settings;
    other.camera.yaw = (-10.0f32).to_radians();
    let saved = screenshot::save(&screenshot::Request {
        folder: dir.path().to_owned(),
        image: Arc::new(render(&cornell_box(), &other)),
        settings: other.clone(),
        sample_target: 1,
        time: chrono::Local::now(),
    })
    .unwrap();
    // The student's image: the lab's figure flipped, a PNG without settings.
    let figure = render(&cornell_box(), &small_state().settings);
    let mut rgb = image::RgbImage::from_raw(128, 96, figure.to_rgb8()).unwrap();
    image::imageops::flip_vertical_in_place(&mut rgb);
    let flip = dir.path().join("flip.png");
    rgb.save(&flip).unwrap();

    let mut h = harness(small_state());
    let yaw = settings(&h).camera.yaw;
    drop_file(&mut h, &flip);
    settle(&mut h);
    assert_eq!(
        h.state().check.as_ref().map(|c| c.name()).as_deref(),
        Some("flip.png")
    );

    type_path(&mut h, saved.png.to_str().unwrap());
    h.key_press(Key::Enter);
    h.step();
    settle(&mut h);
    let check: &StudentCheck = h.state().check.as_ref().expect("still checking");
    assert_eq!(check.path, saved.png, "the typed image is the one checked");
    assert_eq!(
        settings(&h).camera.yaw,
        yaw,
        "no screenshot's settings loaded"
    );
    let name = saved
        .png
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    assert!(
        h.query_by_label(&format!("Checking {name}")).is_some(),
        "the panel names the image checked"
    );
    let (text, _) = status(&h);
    assert!(text.starts_with(&format!("Checking {name}")), "{text}");

    // The dialog opens in the typed file's folder with its name field empty.
    click(&mut h, "Stop checking");
    h.run_steps(2);
    click(&mut h, "Check an image…");
    h.run_steps(2);
    assert!(h.query_by_label("Check an image").is_some(), "the dialog");
    let field = h.get_by_role_and_label(Role::TextInput, "File name");
    assert_eq!(field.value().as_deref(), Some(""));
    assert!(
        h.query_by_label("flip.png").is_some(),
        "the typed file's folder"
    );
}

/// A screenshot saved early leaves a long message: it is one line, cut before the stats on the
/// right (never drawn over them), with the whole text in its tooltip.
#[test]
fn a_long_status_is_cut_short_beside_the_stats_with_a_tooltip() {
    let dir = tempfile::tempdir().unwrap();
    let (mut h, start) = early_screenshot_harness(dir.path(), [1000.0, 900.0]);
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    until_saved(&mut h, dir.path(), start);
    h.step();
    let (text, kind) = status(&h);
    assert_eq!(kind, StatusKind::Notice);
    assert!(text.contains("before the target"), "{text}");

    let status_node = h.get_by_label(&text);
    let stats_node = h.get_by_label_contains(" spp");
    let (line, stats) = (status_node.rect(), stats_node.rect());
    let row = h.ctx.style_of(egui::Theme::Dark).text_styles[&egui::TextStyle::Body].size * 1.5;
    assert!(line.height() < row, "one line: {line:?}");
    assert!(
        line.max.x <= stats.min.x,
        "the status {line:?} runs into the stats {stats:?}"
    );
    assert!(
        line.min.y < stats.max.y && stats.min.y < line.max.y,
        "one row"
    );
    assert!(stats.max.x <= 1000.0, "{stats:?}");

    // Hovered, the status shows its whole text.
    status_node.hover();
    let shown = |h: &Harness<'_, WorkbenchApp>| h.query_all_by_label(&text).count();
    let mut steps = 0;
    while shown(&h) < 2 {
        steps += 1;
        assert!(steps < 200, "no tooltip with the whole message");
        h.step();
    }
}

/// The walk-through's Previous and Next stay where they are at every step, whatever the
/// length of the step's text, and the status line follows the step (a reset's message does
/// not stay).
#[test]
fn the_walkthrough_buttons_stay_in_place_and_the_status_follows_the_step() {
    let mut h = harness(tiny_state());
    click(&mut h, "Reset to lab defaults");
    // The reset's own resolution is large: keep the image tiny.
    h.state_mut().state.settings.camera = tiny_state().settings.camera;
    settle(&mut h);
    assert_eq!(status(&h).0, "Reset to the lab's defaults (figure 7)");
    h.get_by_label("Lab walk-through").click();
    h.step();
    click(&mut h, "Start the walk-through");
    let steps = raylab_core::teaching::walkthrough::STEPS;
    let mut places = Vec::new();
    for (n, step) in steps.iter().enumerate() {
        // The sample targets of the later steps are for a real image: one pass is enough here.
        h.state_mut().state.settings.samples_per_pixel = 1;
        settle(&mut h);
        let title = format!("Step {} of {}: {}", n + 1, steps.len(), step.title);
        assert!(h.query_by_label(&title).is_some(), "{title}");
        let (text, _) = status(&h);
        assert!(
            text.contains(&format!("step {} of {}", n + 1, steps.len()))
                && text.contains(step.title),
            "step {}: the status says {text:?}",
            n + 1
        );
        places.push((
            h.get_by_role_and_label(Role::Button, "Previous").rect(),
            h.get_by_role_and_label(Role::Button, "Next").rect(),
        ));
        if n + 1 < steps.len() {
            click(&mut h, "Next");
        }
    }
    for (n, place) in places.iter().enumerate() {
        assert_eq!(*place, places[0], "step {} moved the buttons", n + 1);
    }
}
