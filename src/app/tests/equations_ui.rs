//! Your equations in the window: a mistake typed into an editor is rendered beside the exact
//! figure and named; a text that does not compile shows its error and keeps the last image,
//! marked stale; Reset gives the lab's image back; a screenshot carries the equations and
//! opening it gives them back to the panel.

use raylab_core::files::settings_file;
use raylab_core::teaching::sandbox::{self, Quantity, carried};

use super::files_ui::{click, drop_file};
use super::*;
use crate::app::check::figure_settings;
use crate::app::equations::Evaluated;

/// D with the 4π of equation 27 forgotten, as a student types it.
const NO_4PI: &str = "vec3 r = lightPos - position; D = shadowed ? vec3(0) : lightColor * \
                      max(dot(normalize(r), normal), 0.0) / dot(r, r)";

/// The harness with the Your equations group open.
fn with_panel(state: WorkbenchState) -> Harness<'static, WorkbenchApp> {
    let mut h = harness(state);
    h.get_by_label("Your equations").click();
    h.run_steps(2);
    h
}

/// Replaces the text of quantity `name`'s editor by `text`, typed.
fn type_into(h: &mut Harness<'_, WorkbenchApp>, name: &str, text: &str) {
    h.get_by_role_and_label(Role::MultilineTextInput, name)
        .focus();
    h.step();
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.get_by_role_and_label(Role::MultilineTextInput, name)
        .type_text(text);
    h.step();
}

fn fresh<'a>(h: &'a Harness<'_, WorkbenchApp>) -> &'a Evaluated {
    let app = h.state();
    app.equations
        .fresh(&app.state.settings)
        .expect("the image of the equations in force")
}

/// `text` of `q` rendered by the library, for the window's settings.
fn library_image(h: &Harness<'_, WorkbenchApp>, q: Quantity, text: &str) -> Image {
    let mut equations = sandbox::Equations::lab();
    equations.take(q, &carried::compile_one(q, text).unwrap());
    let s = figure_settings(&settings(h));
    sandbox::render(&cornell_box(), &s, &equations).image
}

/// D typed with the 4π forgotten: the verdict under the editor names the classic mistake, the
/// image is the library's for those equations and no longer the figure, and fewer pixels are
/// within 2/255 of it.
#[test]
fn a_typed_mistake_is_named_and_changes_the_image() {
    let mut h = with_panel(small_state());
    assert!(!h.state().equations.active(&settings(&h)));
    type_into(&mut h, "D", NO_4PI);
    settle(&mut h);
    assert_eq!(h.state().equations.text(Quantity::Direct), NO_4PI);
    assert!(
        h.query_by_label_contains("Verdict: the classic mistake no-4pi")
            .is_some(),
        "the verdict names the mistake"
    );
    let evaluated = fresh(&h);
    let figure = render(&cornell_box(), &figure_settings(&settings(&h)));
    assert_ne!(*evaluated.image, figure);
    assert_eq!(
        *evaluated.image,
        library_image(&h, Quantity::Direct, NO_4PI)
    );
    assert!(evaluated.share < 0.9, "{}", evaluated.share);
    assert!(
        h.query_by_label_contains("of pixels within 2/255 of the exact figure")
            .is_some()
    );
    // Only R changes next: evaluated again over the recorded hits, not traced.
    type_into(&mut h, "R", "R = D + indirectLight");
    settle(&mut h);
    assert!(!fresh(&h).retraced);
    assert!(
        h.query_by_label_contains("Verdict: the classic mistake no-rho")
            .is_some()
    );
}

/// A text that does not compile: its message with line and column under the editor, the last
/// good image kept and marked stale; fixed, the image follows again.
#[test]
fn an_error_shows_its_message_and_the_last_image_stays() {
    let mut h = with_panel(small_state());
    type_into(&mut h, "D", NO_4PI);
    settle(&mut h);
    let before = Arc::clone(&fresh(&h).image);
    type_into(&mut h, "D", "D = lightpos * 2.0");
    settle(&mut h);
    h.run_steps(2);
    assert!(
        h.query_by_label_contains(
            "line 1, column 5: unknown name `lightpos`: did you mean `lightPos`?"
        )
        .is_some(),
        "the error is shown"
    );
    let app = h.state();
    let live = &app.state.settings;
    assert!(app.equations.is_stale(live));
    assert!(app.equations.active(live));
    assert!(Arc::ptr_eq(&app.equations.last().unwrap().image, &before));
    assert!(
        h.query_by_label_contains("Stale: a text below does not compile")
            .is_some()
    );
    type_into(&mut h, "D", "D = lightColor * 2.0");
    settle(&mut h);
    assert_eq!(
        *fresh(&h).image,
        library_image(&h, Quantity::Direct, "D = lightColor * 2.0")
    );
}

/// Reset to the lab's: the quantity is the lab's own again, and with none written the image
/// shown is the exact figure bit for bit.
#[test]
fn reset_restores_the_labs_image() {
    let mut h = with_panel(small_state());
    type_into(&mut h, "R", "R = D + indirectLight");
    settle(&mut h);
    assert_ne!(
        *fresh(&h).image,
        render(&cornell_box(), &figure_settings(&settings(&h)))
    );
    click(&mut h, "Reset to the lab's");
    settle(&mut h);
    let app = h.state();
    assert!(!app.equations.any_written());
    assert!(app.equations.carried().is_empty());
    assert_eq!(
        app.equations.text(Quantity::Value),
        sandbox::examples::lab_text(Quantity::Value, &settings(&h).shading)
    );
    assert!(!app.equations.active(&settings(&h)));
    assert_eq!(*shown(&h).image, render(&cornell_box(), &settings(&h)));
}

/// A screenshot taken with a mistake typed carries the equations and the student's image;
/// dropped on a fresh window, the panel gets the equations back and shows that image again.
#[test]
fn a_screenshot_carries_the_equations_back_to_the_panel() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.screenshot_folder = dir.path().to_owned();
    let mut h = with_panel(state.clone());
    type_into(&mut h, "D", NO_4PI);
    settle(&mut h);
    let image = Arc::clone(&fresh(&h).image);
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    let start = Instant::now();
    while pngs_in(dir.path()).is_empty() || !h.state().screenshots_saving.is_empty() {
        assert!(start.elapsed() < DEADLINE);
        std::thread::sleep(Duration::from_millis(2));
        h.step();
    }
    let png = pngs_in(dir.path()).pop().expect("a screenshot");
    let loaded = settings_file::read_file(&png).unwrap();
    assert_eq!(loaded.settings.equations.direct.as_deref(), Some(NO_4PI));
    assert!(loaded.settings.equations.value.is_none());
    // The PNG's pixels are the student's image.
    let pixels = ::image::open(&png).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels, image.to_rgb8());

    let mut h = with_panel(state);
    drop_file(&mut h, &png);
    settle(&mut h);
    assert_eq!(h.state().equations.text(Quantity::Direct), NO_4PI);
    // The live settings stay without equations: the panel holds them.
    assert!(settings(&h).equations.is_empty());
    assert_eq!(*fresh(&h).image, *image);
}

/// With the student's image on screen the inspector explains their pixel too: its value, equal
/// to their image's, and each part of their text with its value there.
#[test]
fn the_inspector_explains_the_students_pixel_part_by_part() {
    let mut h = with_panel(small_state());
    type_into(&mut h, "D", NO_4PI);
    settle(&mut h);
    // The editor has the keyboard: the inspector is turned on as its key would.
    h.state_mut().state.inspect_mode = true;
    h.run_steps(3);
    h.state_mut().state.pinned = Some([40, 70]);
    h.run_steps(3);
    let value = fresh(&h).image.get(40, 70);
    let explained = h
        .state()
        .equations
        .explained(&settings(&h), 40, 70)
        .expect("the student's pixel explained");
    assert!(
        explained[0].text.starts_with("(40, 70) = "),
        "{explained:?}"
    );
    let shown = raylab_core::teaching::sandbox::explain::Value::Vec3(value.to_array()).text();
    assert!(explained[0].text.contains(&shown), "{shown}: {explained:?}");
    assert!(
        h.query_by_label_contains("Inspector: pixel (40, 70)")
            .is_some(),
        "inspector"
    );
    assert!(h.query_by_label_contains("(40, 70) = ").is_some());
    assert!(
        h.query_all_by_label_contains("dot(r, r) = ")
            .next()
            .is_some()
    );
}
