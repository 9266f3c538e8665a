//! How far the mouse moves things: a point dragged on a slider's rail moves its value by a
//! fixed amount (not to where the pointer is on a short rail), Shift a tenth of it, on the
//! panel and on the image alike; a wheel's notch zooms a few percent.

use super::*;

/// Drags `points` to the right from the middle of the rail of the slider labelled `label`, in
/// five moves, with `modifiers` held; returns once the drag is released.
fn drag_rail(h: &mut Harness<'_, WorkbenchApp>, label: &str, points: f32, modifiers: Modifiers) {
    let start = h.get_by_role_and_label(Role::Slider, label).rect().center();
    h.event(egui::Event::ModifiersChanged(modifiers));
    h.hover_at(start);
    h.step();
    h.event(egui::Event::PointerButton {
        pos: start,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers,
    });
    h.step();
    for k in 1..=5 {
        h.hover_at(start + egui::vec2(points * k as f32 / 5.0, 0.0));
        h.step();
    }
    let end = start + egui::vec2(points, 0.0);
    h.event(egui::Event::PointerButton {
        pos: end,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers,
    });
    h.step();
    h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
    h.remove_cursor();
    h.step();
}

/// A 25-point drag on Yaw's rail turns the camera 12.5° (0.5° a point), with Shift 1.25°;
/// Camera x moves 0.125 units (0.005 a point), the focal length 13 % (0.5 % a point).
#[test]
fn a_drag_on_a_slider_moves_a_fixed_amount_a_point_and_shift_a_tenth() {
    let mut h = harness(small_state());
    let degrees = |h: &Harness<'_, WorkbenchApp>| f64::from(settings(h).camera.yaw.to_degrees());
    let near = |a: f64, b: f64, tolerance: f64| (a - b).abs() <= tolerance;

    let yaw = degrees(&h);
    drag_rail(&mut h, "Yaw", 25.0, Modifiers::NONE);
    let turned = degrees(&h) - yaw;
    assert!(near(turned, 12.5, 0.01), "25 points turned {turned}°");

    let yaw = degrees(&h);
    drag_rail(&mut h, "Yaw", 25.0, Modifiers::SHIFT);
    let turned = degrees(&h) - yaw;
    assert!(
        near(turned, 1.25, 0.01),
        "25 points with Shift turned {turned}°"
    );

    let x = f64::from(settings(&h).camera.position.x);
    drag_rail(&mut h, "Camera x", 25.0, Modifiers::NONE);
    let moved = f64::from(settings(&h).camera.position.x) - x;
    assert!(near(moved, 0.125, 1e-4), "25 points moved {moved} units");

    let f = f64::from(settings(&h).camera.focal_length);
    drag_rail(&mut h, "Focal length", 25.0, Modifiers::NONE);
    let factor = f64::from(settings(&h).camera.focal_length) / f;
    // The field keeps one decimal of a pixel: 145.0 for 128 × 1.1331.
    assert!(
        near(factor, (25.0 * 0.005f64).exp(), 1e-3),
        "25 points zoomed ×{factor}"
    );
    settle(&mut h);
}

/// One notch of the wheel over the image (as X11 reports it: two lines of egui's 40 points)
/// zooms 5 %, with Shift 0.5 %; a 40-point drag on the image turns 10°, with Shift 1°.
#[test]
fn a_wheel_notch_zooms_five_percent_and_shift_makes_the_image_controls_fine() {
    let mut h = harness(small_state());
    let centre = h.state().viewport.shown_rect().unwrap().center();
    let notch = |h: &mut Harness<'_, WorkbenchApp>, modifiers: Modifiers| {
        let f = settings(h).camera.focal_length;
        h.event(egui::Event::ModifiersChanged(modifiers));
        h.hover_at(centre);
        h.step();
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Line,
            delta: egui::vec2(0.0, 2.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Unknown,
            modifiers,
        });
        // egui spreads a wheel's scroll over a few frames.
        for _ in 0..30 {
            h.step();
            std::thread::sleep(Duration::from_millis(5));
        }
        h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
        h.step();
        f64::from(settings(h).camera.focal_length / f)
    };
    let zoom = notch(&mut h, Modifiers::NONE);
    assert!((zoom - 1.05).abs() < 0.002, "a notch zoomed ×{zoom}");
    let zoom = notch(&mut h, Modifiers::SHIFT);
    assert!(
        (zoom - 1.005).abs() < 0.0005,
        "a notch with Shift zoomed ×{zoom}"
    );

    let turn = |h: &mut Harness<'_, WorkbenchApp>, modifiers: Modifiers| {
        let yaw = settings(h).camera.yaw;
        h.event(egui::Event::ModifiersChanged(modifiers));
        h.drag_at(centre);
        h.step();
        for k in 1..=4 {
            h.hover_at(centre + egui::vec2(10.0 * k as f32, 0.0));
            h.step();
        }
        h.drop_at(centre + egui::vec2(40.0, 0.0));
        h.step();
        h.event(egui::Event::ModifiersChanged(Modifiers::NONE));
        h.step();
        f64::from((settings(h).camera.yaw - yaw).to_degrees())
    };
    let turned = turn(&mut h, Modifiers::NONE);
    assert!((turned - 10.0).abs() < 0.01, "40 points turned {turned}°");
    let turned = turn(&mut h, Modifiers::SHIFT);
    assert!(
        (turned - 1.0).abs() < 0.01,
        "40 points with Shift turned {turned}°"
    );
    settle(&mut h);
}
