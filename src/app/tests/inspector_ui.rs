//! The inspector beside the image: it opens without shrinking the image (the window makes
//! room), its equations get the width to read in a few rows, and it says what the screen
//! shows of the pixel: R in 8 bits, and with anti-aliasing that R is sample 0's, beside the
//! mean of the samples on screen.

use raylab_core::teaching::inspect::{ShownPixel, inspect_pixel};

use super::*;

/// At the window's default size the lab's 512² image is shown 720 points tall; opening the
/// inspector and pinning a pixel leaves it so, and the camera ray's equation wraps over at most
/// three rows (in a narrow column it would take twice as many).
#[test]
fn the_inspector_opens_beside_the_image_keeping_its_size_and_its_lines_readable() {
    let mut state = WorkbenchState::default();
    state.render_threads = 2;
    state.denoise = false;
    assert_eq!(state.settings.samples_per_pixel, 16);
    let mut h = Harness::builder()
        .with_size([1180.0, 760.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    settle(&mut h);
    let before = h.state().viewport.shown_rect().unwrap();
    assert!(before.width() > 700.0, "{before:?}");
    h.key_press(Key::I);
    h.run_steps(3);
    let rect = h.state().viewport.shown_rect().unwrap();
    let pos = rect.min + egui::vec2(0.3, 0.8) * rect.size();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_steps(3);
    let [x, y] = h.state().state.pinned.expect("a pinned pixel");
    let after = h.state().viewport.shown_rect().unwrap();
    assert!(
        (after.width() - before.width()).abs() < 0.5,
        "the image went from {before:?} to {after:?}"
    );
    // One row of text, and the camera ray's line.
    let row = h
        .get_by_label("Shift + arrows move the pixel by one.")
        .rect()
        .height();
    let camera_ray = h
        .get_by_label_contains("camera ray through image point")
        .rect();
    let camera_ray = camera_ray.height();
    assert!(
        camera_ray <= 3.0 * row + 1.0,
        "the camera ray's line is {camera_ray} points tall, a row {row}"
    );

    // R is sample 0's; the pixel on screen is the mean of the 16 samples: both in 8 bits.
    let s = settings(&h);
    let frame = shown(&h);
    let mean = frame.image.get(x, y);
    let inspection = inspect_pixel(&cornell_box(), &s, x, y).unwrap();
    let lines = inspection.display_lines(
        &s.display,
        Some(ShownPixel {
            value: mean,
            samples: 16,
            denoised: false,
        }),
    );
    assert_eq!(lines.len(), 2);
    assert!(lines[0].text.starts_with("R above is sample 0's alone"));
    let [r, g, b] = s.display.encode(mean);
    assert!(
        lines[1].text.contains("the mean of its 16 samples")
            && lines[1]
                .text
                .ends_with(&format!("shown as ({r}, {g}, {b}) in 8 bits")),
        "{}",
        lines[1].text
    );
    for line in &lines {
        assert!(
            h.query_by_label_contains(&line.text).is_some(),
            "not in the inspector: {}",
            line.text
        );
    }
    settle(&mut h);
}

/// With one sample, the pixel on screen is R: one line gives its 8 bits through the display,
/// exposure included.
#[test]
fn with_one_sample_the_inspector_gives_rs_8_bits_through_the_display() {
    let mut state = small_state();
    state.settings.display.exposure = 1.0;
    let mut h = harness(state);
    h.key_press(Key::I);
    h.run_steps(3);
    let rect = h.state().viewport.shown_rect().unwrap();
    let pos = rect.min + egui::vec2(40.5 / 128.0, 70.5 / 96.0) * rect.size();
    h.drag_at(pos);
    h.step();
    h.drop_at(pos);
    h.run_steps(3);
    assert_eq!(h.state().state.pinned, Some([40, 70]));
    let s = settings(&h);
    let r = inspect_pixel(&cornell_box(), &s, 40, 70).unwrap().r;
    assert_eq!(r, shown(&h).image.get(40, 70));
    let [r8, g8, b8] = s.display.encode(r);
    // Twice the floor's value: not the lab's ×255 of R.
    assert_ne!(r8, raylab_core::transport::display::to_display_u8(r.x));
    let eight_bit = if r8 == g8 && g8 == b8 {
        format!("{r8}")
    } else {
        format!("({r8}, {g8}, {b8})")
    };
    let wanted = format!("shown as {eight_bit} in 8 bits through the display");
    assert!(
        h.query_by_label_contains(&wanted).is_some(),
        "no line with {wanted}"
    );
    assert!(h.query_by_label_contains("exposure +1 EV").is_some());
    assert!(h.query_by_label_contains("sample 0's alone").is_none());
    settle(&mut h);
}

/// A smaller resolution keeps the inspected pixel on the same spot, not at its old coordinates
/// (outside the smaller image).
#[test]
fn a_new_resolution_keeps_the_inspected_pixel_on_its_spot() {
    let mut state = WorkbenchState::default();
    state.render_threads = 2;
    state.inspect_mode = true;
    state.pinned = Some([301, 283]);
    assert_eq!(
        (state.settings.camera.width, state.settings.camera.height),
        (512, 512)
    );
    let mut h = Harness::builder()
        .with_size([1180.0, 760.0])
        .build_eframe(move |cc| WorkbenchApp::with_state(&cc.egui_ctx, state, None));
    settle(&mut h);
    h.state_mut().state.settings.camera.width = 256;
    h.state_mut().state.settings.camera.height = 256;
    settle(&mut h);
    assert_eq!(h.state().state.pinned, Some([150, 141]));
    assert!(h.query_by_label_contains("is outside the").is_none());
    assert!(
        h.query_all_by_label_contains("pixel (150, 141)")
            .next()
            .is_some()
    );
}

/// The same spot at another size: the pixel's centre scaled (halving and doubling give each
/// other back), kept inside the image.
#[test]
fn the_same_spot_at_another_size() {
    assert_eq!(same_spot([301, 283], [512, 512], [256, 256]), [150, 141]);
    assert_eq!(same_spot([150, 141], [256, 256], [512, 512]), [301, 283]);
    assert_eq!(same_spot([0, 0], [512, 512], [256, 256]), [0, 0]);
    assert_eq!(same_spot([511, 511], [512, 512], [256, 256]), [255, 255]);
    assert_eq!(same_spot([10, 5], [20, 10], [40, 10]), [21, 5]);
    assert_eq!(same_spot([7, 7], [8, 8], [1, 1]), [0, 0]);
}
