//! The pixel inspector's panel: the pinned pixel's lines beside the lab's equations
//! ([`raylab_core::teaching::inspect`]), recomputed only when the pixel or the settings change;
//! the room the panel takes, given back on closing.

use eframe::egui;

use super::status::StatusKind;
use super::{CENTRAL_MARGINS, WorkbenchApp};

/// The inspector panel's width when there is room (an equation's line then wraps over two or
/// three rows), the least it opens at when the window cannot make that room (the image gives
/// up the rest), and the least it can be dragged to.
pub(super) const INSPECTOR_WIDTH: f32 = 520.0;
pub(super) const INSPECTOR_OPEN_MIN_WIDTH: f32 = 320.0;
pub(super) const INSPECTOR_MIN_WIDTH: f32 = 200.0;

/// An inspection as the inspector panel shows it: its lines, and the same as text to copy.
pub(super) struct Inspected {
    inspection: raylab_core::teaching::inspect::Inspection,
    lines: Vec<raylab_core::teaching::inspect::InspectLine>,
}

impl WorkbenchApp {
    /// Inspect mode: pins the clicked pixel (`at`: a fraction of the image's width and height).
    pub(super) fn pin_at(&mut self, at: egui::Vec2) {
        let camera = &self.state.settings.camera;
        let x = ((at.x * camera.width as f32) as u32).min(camera.width - 1);
        let y = ((at.y * camera.height as f32) as u32).min(camera.height - 1);
        self.state.pinned = Some([x, y]);
    }

    /// The pinned pixel's lines with the settings in force, recomputed only when either
    /// changes (one ray's worth of work, recorded step by step), not every UI frame.
    pub(super) fn inspection(&mut self) -> Option<&Result<Inspected, String>> {
        let pixel = self.state.pinned?;
        if !self.state.inspect_mode || self.state.settings.scene != self.scene_choice {
            return None;
        }
        let fresh = self
            .inspection
            .as_ref()
            .is_some_and(|(s, p, _)| *p == pixel && *s == self.state.settings);
        if !fresh {
            let result = raylab_core::teaching::inspect::inspect_pixel(
                &self.scene,
                &self.state.settings,
                pixel[0],
                pixel[1],
            )
            .map(|inspection| Inspected {
                lines: inspection.lines(),
                inspection,
            })
            .map_err(|e| e.to_string());
            self.inspection = Some((self.state.settings.clone(), pixel, result));
        }
        self.inspection.as_ref().map(|(_, _, r)| r)
    }

    /// Opens the inspector beside the image without shrinking it, as far as the screen allows:
    /// the window grows by what the inspector needs beyond the room the image leaves (up to
    /// the screen's right edge); the inspector opens [`INSPECTOR_WIDTH`] wide, or as wide as
    /// that makes room for but at least [`INSPECTOR_OPEN_MIN_WIDTH`] (its equations readable;
    /// the image then gives up the difference).
    pub(super) fn make_room_for_inspector(&mut self, ctx: &egui::Context) {
        let image = self.viewport.shown_rect().map_or(0.0, |r| r.width());
        let free = (self.central_width - image - CENTRAL_MARGINS).max(0.0);
        let window = ctx.content_rect().size();
        let (monitor, outer) = ctx.input(|i| (i.viewport().monitor_size, i.viewport().outer_rect));
        // Unknown (no monitor reported): the window manager keeps the window on screen.
        let spare = monitor.map_or(f32::INFINITY, |m| {
            (m.x - outer.map_or(window.x, |o| o.max.x)).max(0.0)
        });
        let grow = (INSPECTOR_WIDTH - free).clamp(0.0, spare).floor();
        self.inspector_width = (free + grow).clamp(INSPECTOR_OPEN_MIN_WIDTH, INSPECTOR_WIDTH);
        self.inspector_opened = self.inspector_opened.wrapping_add(1);
        if grow > 0.0 {
            let size = window + egui::vec2(grow, 0.0);
            ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(size));
            self.inspector_grew = Some((grow, size.x));
        }
    }

    /// Closing the inspector gives back the width opening it added, unless the window was
    /// resized since.
    pub(super) fn give_back_inspector_room(&mut self, ctx: &egui::Context) {
        let Some((grew, width)) = self.inspector_grew.take() else {
            return;
        };
        let window = ctx.content_rect().size();
        if (window.x - width).abs() < 1.0 {
            let size = egui::vec2(window.x - grew, window.y);
            ctx.send_viewport_cmd(egui::ViewportCommand::InnerSize(size));
        }
    }

    /// What the screen shows at the pinned pixel, when an image of the settings in force is
    /// there: the denoised image's value, or the film's mean.
    pub(super) fn shown_pixel(
        &self,
        [x, y]: [u32; 2],
    ) -> Option<raylab_core::teaching::inspect::ShownPixel> {
        let shown = self
            .shown
            .as_ref()
            .filter(|s| !s.is_preview && s.settings.renders_like(&self.state.settings))?;
        let (image, samples, denoised) = match &shown.denoised {
            Some((image, samples)) => (image, *samples, true),
            None => (&shown.image, shown.samples, false),
        };
        (x < image.width && y < image.height).then(|| raylab_core::teaching::inspect::ShownPixel {
            value: image.get(x, y),
            samples,
            denoised,
        })
    }

    /// The inspector: the pinned pixel's lines, each beside the lab equation it evaluates.
    pub(super) fn inspector_ui(&mut self, ui: &mut egui::Ui) {
        let (mut copied, mut unpin) = (false, false);
        // While checking a student's image: its pixel beside the exact figure's.
        let check_line = match (&self.check, self.state.pinned) {
            (Some(check), Some([x, y])) => check.pixel_line(&self.state.settings, x, y),
            _ => None,
        };
        let shown = self.state.pinned.and_then(|pixel| self.shown_pixel(pixel));
        let display = self.state.settings.display;
        // With the student's equations on screen: their pixel, part by part.
        let explained = self
            .state
            .pinned
            .and_then(|[x, y]| self.equations.explained(&self.state.settings, x, y));
        match self.inspection() {
            None => {
                ui.label("Click a pixel of the image to see how its value is computed.");
            }
            Some(Err(e)) => {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            Some(Ok(inspected)) => {
                // The display's lines change as samples come in: made each frame (no tracing).
                let mut shown_lines = inspected.inspection.display_lines(&display, shown);
                shown_lines.extend(explained.into_iter().flatten());
                ui.horizontal(|ui| {
                    if ui
                        .button("Copy as text")
                        .on_hover_text("The lines below, for a report or a question")
                        .clicked()
                    {
                        let mut lines = inspected.lines.clone();
                        lines.extend(shown_lines.iter().cloned());
                        ui.ctx()
                            .copy_text(raylab_core::teaching::inspect::lines_text(&lines));
                        copied = true;
                    }
                    unpin = ui.button("Unpin").clicked();
                });
                ui.weak("Shift + arrows move the pixel by one.");
                if let Some(line) = check_line {
                    ui.strong(line);
                }
                // Each line's equation (dimmed) leads its text, which wraps under it across the
                // whole width: no column of equations narrows every line.
                let font = egui::TextStyle::Body.resolve(ui.style());
                let (weak, strong) = (ui.visuals().weak_text_color(), ui.visuals().text_color());
                egui::ScrollArea::vertical().show(ui, |ui| {
                    for line in inspected.lines.iter().chain(&shown_lines) {
                        let mut job = egui::text::LayoutJob::default();
                        let format = |color| egui::TextFormat::simple(font.clone(), color);
                        if !line.equation.is_empty() {
                            job.append(&line.equation, 0.0, format(weak));
                        }
                        job.append(&line.text, 8.0, format(strong));
                        ui.add(egui::Label::new(job).wrap());
                        ui.add_space(2.0);
                    }
                });
            }
        }
        if copied {
            self.set_status(StatusKind::Info, "Copied the inspector's lines");
        }
        if unpin {
            self.state.pinned = None;
        }
    }

    /// The inspector's side panel, while inspecting: as wide as opening it made room for
    /// ([`WorkbenchApp::make_room_for_inspector`]).
    pub(super) fn inspector_panel(&mut self, ui: &mut egui::Ui) {
        egui::Panel::right(("inspector", self.inspector_opened))
            .resizable(true)
            .min_size(INSPECTOR_MIN_WIDTH)
            .default_size(self.inspector_width)
            .show(ui, |ui| {
                let title = match self.state.pinned {
                    Some([x, y]) => format!("Inspector: pixel ({x}, {y})"),
                    None => "Inspector".to_owned(),
                };
                // The panel keeps its width (else it shrinks to its widest line).
                ui.set_min_width(ui.available_width());
                ui.heading(title);
                self.inspector_ui(ui);
            });
    }
}

/// The pixel of a `to`-sized image on the same spot as `pixel` of a `from`-sized one: its
/// centre scaled, kept inside the image.
pub(super) fn same_spot(pixel: [u32; 2], from: [u32; 2], to: [u32; 2]) -> [u32; 2] {
    std::array::from_fn(|i| {
        let centre = (f64::from(pixel[i]) + 0.5) / f64::from(from[i].max(1));
        ((centre * f64::from(to[i])) as u32).min(to[i].saturating_sub(1))
    })
}
