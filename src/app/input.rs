//! The lab's keys and the mouse on the image, as edits of the one settings value.
//!
//! | input | action |
//! |---|---|
//! | Up / Down | camera forward / back ([`CAMERA_STEP`] a press) |
//! | Left / Right | turn the camera left / right ([`YAW_STEP_DEGREES`]) |
//! | W / S, A / D, Q / E | light forward / back, left / right, up / down ([`LIGHT_STEP`]) |
//! | drag on the image | turn the camera (yaw, and pitch) |
//! | wheel on the image | focal length (zoom) |
//! | Shift with a drag or the wheel | a tenth as far ([`FINE_POINTER`]) |
//! | F1 | help; Ctrl+S: screenshot; Ctrl+O: open; Ctrl+Shift+S: save scene |
//!
//! Each key press (and each auto-repeat while a key is held) is one step. Keys do nothing while
//! a text field has focus; the arrows also leave a focused slider alone, which uses them itself.

use eframe::egui::{self, Key, KeyboardShortcut, Modifiers};
use glam::{Mat3, Vec3};
use raylab_core::{Camera, RenderSettings};

use super::viewport::ViewportInput;
use super::{Command, WorkbenchApp};

/// Camera movement per Up/Down press, in scene units (the box is 2 units wide).
pub const CAMERA_STEP: f32 = 0.1;
/// Camera turn per Left/Right press.
pub const YAW_STEP_DEGREES: f32 = 5.0;
/// Light movement per W/S/A/D/Q/E press, in scene units.
pub const LIGHT_STEP: f32 = 0.1;
/// Camera turn per point dragged on the image.
pub const DRAG_DEGREES_PER_POINT: f32 = 0.25;
/// Focal length factor per point of wheel scroll: `f · exp(scroll · this)`. A wheel's notch
/// on X11 arrives as two lines of egui's `line_scroll_speed`, 40 points each (under Xvfb
/// `xdotool click 4` scrolls 80 points): ln(1.05)/80 zooms 5 % a notch (a platform that
/// reports one line a notch, 2.5 %).
pub const WHEEL_ZOOM_PER_POINT: f32 = 0.000_61;
/// Shift divides a drag's turn and the wheel's zoom on the image by this (fine control, as in
/// Blender; the panel's controls do the same).
pub const FINE_POINTER: f32 = 10.0;
/// Focal length limits, as multiples of the image width.
pub const FOCAL_RANGE_WIDTHS: (f32, f32) = (0.1, 10.0);

pub const SCREENSHOT_SHORTCUT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::S);
pub const OPEN_SHORTCUT: KeyboardShortcut = KeyboardShortcut::new(Modifiers::COMMAND, Key::O);
pub const SAVE_SCENE_SHORTCUT: KeyboardShortcut =
    KeyboardShortcut::new(Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::S);

/// Every key and mouse action, for the help window: (input, action).
pub const HELP: &[(&str, &str)] = &[
    ("Up / Down", "move the camera forward / back"),
    ("Left / Right", "turn the camera left / right"),
    ("W / S", "move the light forward / back"),
    ("A / D", "move the light left / right"),
    ("Q / E", "move the light up / down"),
    (
        "Drag on the image",
        "turn the camera (left/right: yaw, up/down: pitch)",
    ),
    ("Wheel on the image", "zoom (focal length), 5 % a notch"),
    (
        "Shift + drag or wheel",
        "a tenth as far: fine control (on the panel's sliders too)",
    ),
    (
        "I",
        "inspect pixels on / off: a click pins a pixel, its equations show on the right",
    ),
    ("Shift + arrows", "move the inspected pixel by one"),
    ("Ctrl+S", "save a screenshot"),
    ("Ctrl+O", "open a scene file, screenshot or OBJ model"),
    ("Ctrl+Shift+S", "save the setup as a scene file"),
    (
        "Drop a file",
        "open it (scene file, screenshot .png/.json, OBJ)",
    ),
    ("F1", "show / hide this help"),
    (
        "Esc",
        "leave a text field or slider (then the keys move again)",
    ),
];

/// Applies this frame's keys to `settings`; returns the commands they ask for.
pub fn keys(ctx: &egui::Context, settings: &mut RenderSettings) -> Vec<Command> {
    let mut commands = Vec::new();
    let text_focused = ctx.egui_wants_keyboard_input();
    let widget_focused = ctx.memory(|m| m.focused().is_some());
    ctx.input_mut(|i| {
        // Before Ctrl+S, which would also match Ctrl+Shift+S.
        if i.consume_shortcut(&SAVE_SCENE_SHORTCUT) {
            commands.push(Command::ShowSaveSceneDialog);
        }
        if i.consume_shortcut(&OPEN_SHORTCUT) {
            commands.push(Command::ShowOpenDialog);
        }
        if i.consume_shortcut(&SCREENSHOT_SHORTCUT) {
            commands.push(Command::SaveScreenshot);
        }
        if i.key_pressed(Key::F1) {
            commands.push(Command::ToggleHelp);
        }
    });
    if text_focused {
        return commands;
    }
    // Shift with the arrows moves the inspector's pinned pixel, not the camera; I toggles the
    // inspector.
    let (pixel_step, inspect) = ctx.input(|i| {
        let n = |key| i.num_presses(key) as i32;
        let step = if i.modifiers.shift_only() {
            [
                n(Key::ArrowRight) - n(Key::ArrowLeft),
                n(Key::ArrowDown) - n(Key::ArrowUp),
            ]
        } else {
            [0, 0]
        };
        (step, i.modifiers.is_none() && i.key_pressed(Key::I))
    });
    if inspect {
        commands.push(Command::ToggleInspector);
    }
    if pixel_step != [0, 0] {
        commands.push(Command::MovePinned(pixel_step));
        return commands;
    }
    let (presses, modifiers) = ctx.input(|i| {
        let n = |key| i.num_presses(key) as f32;
        (
            [
                n(Key::ArrowUp) - n(Key::ArrowDown),
                n(Key::ArrowRight) - n(Key::ArrowLeft),
                n(Key::W) - n(Key::S),
                n(Key::D) - n(Key::A),
                n(Key::E) - n(Key::Q),
            ],
            i.modifiers,
        )
    });
    // Ctrl/Alt/Cmd with a letter is somebody else's shortcut.
    if modifiers.ctrl || modifiers.alt || modifiers.command || modifiers.mac_cmd {
        return commands;
    }
    let [forward, turn, light_forward, light_right, light_down] = presses;
    if !widget_focused {
        let camera = &mut settings.camera;
        if forward != 0.0 {
            camera.move_forward(forward * CAMERA_STEP);
        }
        if turn != 0.0 {
            camera.yaw = wrap_angle(camera.yaw + (turn * YAW_STEP_DEGREES).to_radians());
        }
    }
    if light_forward != 0.0 || light_right != 0.0 || light_down != 0.0 {
        settings.light.position +=
            LIGHT_STEP * light_move(&settings.camera, light_forward, light_right, light_down);
    }
    commands
}

/// The light's movement for the W/S, A/D, Q/E counts: forward and right as the camera faces,
/// level with the floor; down is +y (the lab's y points down).
fn light_move(camera: &Camera, forward: f32, right: f32, down: f32) -> Vec3 {
    let turn = Mat3::from_rotation_y(camera.yaw);
    forward * turn.z_axis + right * turn.x_axis + down * Vec3::Y
}

/// Applies a drag and wheel on the image to the camera.
pub fn pointer(input: &ViewportInput, camera: &mut Camera) {
    let scale = if input.fine { 1.0 / FINE_POINTER } else { 1.0 };
    if input.drag_delta != egui::Vec2::ZERO {
        let d = input.drag_delta * DRAG_DEGREES_PER_POINT * scale;
        camera.yaw = wrap_angle(camera.yaw + d.x.to_radians());
        // Dragging up looks up (positive pitch), never past straight up or down.
        let limit = 89f32.to_radians();
        camera.pitch = (camera.pitch - d.y.to_radians()).clamp(-limit, limit);
    }
    if input.scroll_y != 0.0 {
        let w = camera.width as f32;
        let (lo, hi) = FOCAL_RANGE_WIDTHS;
        let zoom = (input.scroll_y * WHEEL_ZOOM_PER_POINT * scale).exp();
        camera.focal_length = (camera.focal_length * zoom).clamp(lo * w, hi * w);
    }
}

/// An angle in radians brought into (−π, π].
pub fn wrap_angle(radians: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    let a = radians.rem_euclid(TAU);
    if a > PI { a - TAU } else { a }
}

impl WorkbenchApp {
    pub(super) fn help_ui(&mut self, ctx: &egui::Context) {
        // Over the image, not the top of the side panel, whose buttons (Help among them)
        // stay within reach.
        egui::Window::new("Help")
            .open(&mut self.show_help)
            .resizable(false)
            .collapsible(false)
            .pivot(egui::Align2::CENTER_CENTER)
            .default_pos(ctx.content_rect().center())
            .show(ctx, |ui| {
                egui::Grid::new("help-keys")
                    .striped(true)
                    .num_columns(2)
                    .show(ui, |ui| {
                        for (keys, action) in HELP {
                            ui.strong(*keys);
                            ui.label(*action);
                            ui.end_row();
                        }
                    });
                ui.separator();
                ui.label(
                    "Keys act when no text field has focus. Every change re-traces at once: \
                     a coarse preview first, then full resolution, then more samples up to the \
                     sample target.",
                );
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_angle_stays_in_range() {
        assert!((wrap_angle(190f32.to_radians()) - (-170f32).to_radians()).abs() < 1e-5);
        assert!((wrap_angle(-5f32.to_radians()) - (-5f32).to_radians()).abs() < 1e-6);
        assert_eq!(wrap_angle(0.0), 0.0);
    }

    #[test]
    fn light_moves_relative_to_the_camera() {
        let mut camera = Camera::default();
        assert!((light_move(&camera, 1.0, 0.0, 0.0) - Vec3::Z).length() < 1e-6);
        assert!((light_move(&camera, 0.0, 1.0, 0.0) - Vec3::X).length() < 1e-6);
        // Q (up) is −y: the lab's y points down.
        assert_eq!(light_move(&camera, 0.0, 0.0, -1.0), -Vec3::Y);
        camera.yaw = 90f32.to_radians();
        assert!((light_move(&camera, 1.0, 0.0, 0.0) - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn wheel_zooms_within_limits() {
        let mut camera = Camera::default();
        let input = ViewportInput {
            scroll_y: 100.0,
            ..Default::default()
        };
        pointer(&input, &mut camera);
        assert!(camera.focal_length > 512.0);
        for _ in 0..1000 {
            pointer(&input, &mut camera);
        }
        assert_eq!(camera.focal_length, 5120.0);
    }
}
