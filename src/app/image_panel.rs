//! The image in the central panel and what the mouse does on it: drags move the light, a spot
//! light's aim or the camera; a click pins the inspected pixel or sets the focus distance.

use eframe::egui;
use raylab_core::shading::light::LightKind;

use super::status::StatusKind;
use super::viewport::{self, light_marker, spot_marker};
use super::{CENTRAL_MARGINS, WorkbenchApp, input};

impl WorkbenchApp {
    /// The central panel: the render with the light's marker, the inspected pixel and the
    /// overlay in force (Check, Your equations or Compare A/B); a drag moves the light, the
    /// spot's aim or the camera, a click pins a pixel or focuses.
    pub(super) fn image_ui(&mut self, ui: &mut egui::Ui) {
        self.central_width = ui.available_width() + CENTRAL_MARGINS;
        self.viewport.pinned =
            self.state
                .pinned
                .filter(|_| self.state.inspect_mode)
                .map(|[x, y]| {
                    let c = &self.state.settings.camera;
                    let (w, h) = (c.width as f32, c.height as f32);
                    egui::Rect::from_min_size(
                        egui::pos2(x as f32 / w, y as f32 / h),
                        egui::vec2(1.0 / w, 1.0 / h),
                    )
                });
        let marker = light_marker(&self.state.settings);
        let equations_shown = self.equations.active(&self.state.settings);
        let overlay: Option<&mut dyn viewport::Overlay> = match (&mut self.check, &mut self.compare)
        {
            (Some(check), _) => Some(check),
            (None, _) if equations_shown => Some(&mut self.equations),
            (None, Some(compare)) => Some(compare),
            (None, None) => None,
        };
        let spot = spot_marker(&self.state.settings);
        let pointer = self
            .viewport
            .viewport_ui(ui, marker, spot.as_ref(), overlay);
        if pointer.pressed
            && let Some(id) = ui.memory(|m| m.focused())
        {
            // Clicking the image gives the keys back to the camera and light.
            ui.memory_mut(|m| m.surrender_focus(id));
        }
        // A drag on the A/B divider moves only the divider.
        if !pointer.on_divider {
            self.drag_light_or_camera(&pointer);
        }
        if let Some(at) = pointer.clicked_at {
            if self.state.inspect_mode {
                self.pin_at(at);
            } else if self.state.focus_mode {
                self.focus_at(at);
            }
        }
    }

    /// A drag that starts on the light's marker moves the light in the image plane, at the
    /// depth it had when the drag started; one that starts on a spot light's aim moves the aim
    /// so (turning the spot); any other drag turns the camera.
    pub(super) fn drag_light_or_camera(&mut self, pointer: &viewport::ViewportInput) {
        let settings = &mut self.state.settings;
        let depth_of = |p| settings.camera.project(p).map(|(_, _, depth)| depth);
        if pointer.drag_started_on_marker {
            self.dragging_light = depth_of(settings.light.position);
        } else if let (true, LightKind::Spot(cone)) =
            (pointer.drag_started_on_aim, settings.light.kind)
        {
            self.dragging_aim = depth_of(cone.aim);
        }
        let camera = &settings.camera;
        let under_pointer = |depth| {
            let at = pointer.pointer_at?;
            let (px, py) = (at.x * camera.width as f32, at.y * camera.height as f32);
            Some(camera.unproject(px, py, depth))
        };
        match (
            self.dragging_light,
            self.dragging_aim,
            &mut settings.light.kind,
        ) {
            (Some(depth), _, _) if pointer.dragging => {
                if let Some(p) = under_pointer(depth) {
                    settings.light.position = p;
                }
            }
            (None, Some(depth), LightKind::Spot(cone)) if pointer.dragging => {
                if let Some(p) = under_pointer(depth) {
                    cone.aim = p;
                }
            }
            _ => {
                self.dragging_light = None;
                self.dragging_aim = None;
                input::pointer(pointer, &mut settings.camera);
            }
        }
    }

    /// "Click to focus": sets the focus distance to the depth of what the clicked point of the
    /// image shows (`at`: a fraction of the image's width and height).
    pub(super) fn focus_at(&mut self, at: egui::Vec2) {
        let settings = &mut self.state.settings;
        let camera = &settings.camera;
        let (px, py) = (at.x * camera.width as f32, at.y * camera.height as f32);
        match raylab_core::transport::render::focus_depth(&self.scene, settings, px, py) {
            Some(depth) => {
                settings.camera.focus_distance = depth;
                let hint = if settings.camera.aperture > 0.0 {
                    ""
                } else {
                    " (set an aperture above 0 to see depth of field)"
                };
                self.set_status(
                    StatusKind::Info,
                    format!("Focus distance {depth:.3}: the clicked point is sharp{hint}"),
                );
            }
            None => self.set_status(
                StatusKind::Notice,
                "Nothing there to focus on: the clicked pixel sees no surface",
            ),
        }
    }
}
