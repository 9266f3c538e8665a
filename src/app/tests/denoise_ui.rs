//! The Denoise switch: on, the path stage's image on screen is the denoised one
//! (`render_denoised`'s, bit for bit) while the accumulated image stays the render; off, the
//! raw image is shown again at once, nothing traced.

use raylab_core::transport::denoise::render_denoised;

use super::files_ui::drop_file;

use super::*;

#[test]
fn the_denoise_switch_shows_the_denoised_image_and_back() {
    let mut state = small_state();
    state.denoise = true;
    let mut h = harness(state);
    choose(&mut h, "Stage", "Path tracing (real light)");
    set_target(&mut h, 4);
    settle(&mut h);
    let on = shown(&h);
    let (raw, denoised) = render_denoised(&cornell_box(), &on.settings);
    let denoised = denoised.expect("the path stage is noisy");
    // The film is untouched; the screen shows the denoised image.
    assert_eq!(*on.image, raw);
    let display = on.settings.display;
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        display.to_rgba8(&denoised.pixels)
    );
    assert!(
        h.query_by_label_contains("Denoised from 4 samples")
            .is_some()
    );

    h.get_by_role_and_label(Role::CheckBox, "Denoise").click();
    settle(&mut h);
    assert!(!h.state().state.denoise);
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        display.to_rgba8(&raw.pixels)
    );
    assert!(h.query_by_label_contains("Denoised from").is_none());
    settle(&mut h);
}

/// A screenshot taken while the denoised image is on screen saves that image, with settings
/// that say so (`denoise`, and the samples it was made from): `render_denoised` of them gives
/// its pixels again, as `raylab render --settings SHOT.png` does. Dropped on the window with
/// the Denoise switch off, it turns the switch on and shows the same image.
#[test]
fn a_screenshot_of_the_denoised_image_saves_and_restores_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = small_state();
    state.denoise = true;
    state.screenshot_folder = dir.path().to_owned();
    let mut h = harness(state);
    choose(&mut h, "Stage", "Path tracing (real light)");
    set_target(&mut h, 4);
    settle(&mut h);
    let on = shown(&h);
    h.get_by_role_and_label(Role::Button, "Save screenshot")
        .click();
    settle(&mut h);
    let png = pngs_in(dir.path()).pop().expect("a screenshot");
    let sidecar: screenshot::Sidecar =
        serde_json::from_str(&std::fs::read_to_string(png.with_extension("json")).unwrap())
            .unwrap();
    assert!(sidecar.settings.denoise);
    assert_eq!(sidecar.settings.samples_per_pixel, 4);
    let (raw, denoised) = render_denoised(&cornell_box(), &sidecar.settings);
    let denoised = denoised.expect("the path stage is noisy");
    assert_eq!(raw, *on.image, "the film it was made from");
    let pixels = image::open(&png).unwrap().to_rgb8().into_raw();
    assert_eq!(
        pixels,
        denoised.to_rgb8(),
        "the PNG holds the denoised image"
    );
    assert_ne!(pixels, on.image.to_rgb8());

    h.get_by_role_and_label(Role::CheckBox, "Denoise").click();
    settle(&mut h);
    assert!(!h.state().state.denoise);
    drop_file(&mut h, &png);
    settle(&mut h);
    assert!(h.state().state.denoise, "the switch is on again");
    // The window's settings are those it traces with: the flag is not kept among them.
    assert!(!settings(&h).denoise);
    assert_eq!(
        h.state().viewport.rgba().unwrap(),
        on.settings.display.to_rgba8(&denoised.pixels)
    );
}
