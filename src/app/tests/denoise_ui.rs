//! The Denoise switch: on, the path stage's image on screen is the denoised one
//! (`render_denoised`'s, bit for bit) while the accumulated image stays the render; off, the
//! raw image is shown again at once, nothing traced.

use raylab_core::denoise::render_denoised;

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
