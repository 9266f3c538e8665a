//! "Check my image": a student's own render of the lab, dropped on the window or opened with
//! "Check an image…", held against the exact figure for the current settings
//! ([`raylab_core::teaching::check`], the same check as `raylab check`).
//!
//! Reading the image and each check run on a short-lived thread (a check renders a dozen
//! figures at the image's size, too long for the UI thread), at most
//! one at a time; a settings change starts a new check once the running one is back, so the
//! diagnosis follows the stage, camera and light as the student sets them to what their image
//! was made with. While checking, the viewport shows the student's image (left) against the
//! exact figure (right) at a divider, or the difference picture; the side panel shows the
//! diagnosis; the inspector shows the pinned pixel of both.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};

use eframe::egui;
use raylab_core::RenderSettings;
use raylab_core::shapes::scene::Scene;
use raylab_core::teaching::check::{self, Checked, Encoding, Rgb8};
use raylab_core::transport::display::Display;
use raylab_core::transport::progressive::catch_panic;

use super::Command;
use super::WorkbenchApp;
use super::compare::{Divider, Texture, paint_wipe, tag};
use super::status::{Cause, StatusKind};
use super::viewport::Overlay;

/// What [`StudentCheck::update`] tells the app.
#[derive(Debug, PartialEq)]
pub enum Event {
    /// The image was read: it is `width × height`, which the camera must render.
    Read { width: u32, height: u32 },
    /// The image could not be read: the check is over.
    Unreadable(String),
}

/// A check in progress: the student's image, the newest diagnosis and the views of both.
pub struct StudentCheck {
    pub path: PathBuf,
    image: Option<Arc<Rgb8>>,
    /// How the image was stored (a JPEG is compared by its blocks).
    encoding: Encoding,
    reading: Option<Receiver<Result<(Rgb8, Encoding), String>>>,
    /// The check running, and the settings it was started for.
    running: Option<(RenderSettings, Receiver<Result<Checked, String>>)>,
    /// The newest check's result and the settings it was made for.
    done: Option<(RenderSettings, Result<Checked, String>)>,
    student: Texture,
    figure: Texture,
    difference_picture: Texture,
    /// How much the difference picture amplifies |yours − figure|.
    difference_gain: f64,
    pub divider: Divider,
    /// Show the difference picture instead of the wipe.
    pub difference: bool,
}

/// The settings of the exact figure the image is held against: the live ones with one sample
/// a pixel at its centre (the lab's figures; the window's own render may take more), in the
/// lab's display (the figure is written as the lab writes it, whatever the window shows).
pub fn figure_settings(live: &RenderSettings) -> RenderSettings {
    RenderSettings {
        samples_per_pixel: 1,
        seed: 0,
        display: Display::default(),
        ..live.clone()
    }
}

impl StudentCheck {
    /// Starts reading the image at `path` (off the UI thread: a large file takes a while).
    pub fn start(ctx: &egui::Context, path: PathBuf) -> Self {
        let (tx, rx) = mpsc::channel();
        let (file, repaint) = (path.clone(), ctx.clone());
        std::thread::spawn(move || {
            let read = catch_panic(|| check::read_image_encoded(&file).map_err(|e| e.to_string()))
                .and_then(|r| r);
            let _ = tx.send(read);
            repaint.request_repaint();
        });
        Self {
            path,
            image: None,
            encoding: Encoding::Lossless,
            reading: Some(rx),
            running: None,
            done: None,
            student: Texture::default(),
            figure: Texture::default(),
            difference_picture: Texture::default(),
            difference_gain: f64::from(check::compare::DIFF_GAIN),
            divider: Divider::default(),
            difference: false,
        }
    }

    /// The file's name, for the panel and the status line.
    pub fn name(&self) -> String {
        self.path.file_name().map_or_else(
            || self.path.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    }

    /// Once a UI frame: takes the image once read and a finished check, and starts a check
    /// when the settings (`live`, on `scene` once `scene_ready`) differ from the last one's.
    /// Never waits.
    pub fn update(
        &mut self,
        ctx: &egui::Context,
        live: &RenderSettings,
        scene: &Arc<Scene>,
        scene_ready: bool,
    ) -> Option<Event> {
        let mut event = None;
        if let Some(rx) = &self.reading {
            let read = match rx.try_recv() {
                Ok(read) => Some(read),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => Some(Err("reading stopped".to_owned())),
            };
            match read {
                None => {}
                Some(Ok((image, encoding))) => {
                    self.reading = None;
                    self.encoding = encoding;
                    self.student
                        .set(ctx, "raylab-check-student", color_image(&image));
                    event = Some(Event::Read {
                        width: image.width,
                        height: image.height,
                    });
                    self.image = Some(Arc::new(image));
                }
                Some(Err(e)) => {
                    self.reading = None;
                    return Some(Event::Unreadable(e));
                }
            }
        }
        if let Some((settings, rx)) = &self.running {
            let result = match rx.try_recv() {
                Ok(result) => Some(result),
                Err(TryRecvError::Empty) => None,
                Err(TryRecvError::Disconnected) => Some(Err("the check stopped".to_owned())),
            };
            if let Some(result) = result {
                if let (Ok(checked), Some(image)) = (&result, &self.image) {
                    self.figure
                        .set(ctx, "raylab-check-figure", color_image(&checked.figure));
                    self.difference_gain = check::compare::difference_gain(image, &checked.figure);
                    let picture = check::compare::difference_picture_with_gain(
                        image,
                        &checked.figure,
                        self.difference_gain,
                    );
                    self.difference_picture.set(
                        ctx,
                        "raylab-check-difference",
                        color_image(&picture),
                    );
                }
                self.done = Some((settings.clone(), result));
                self.running = None;
            }
        }
        let wanted = figure_settings(live);
        let stale = self.done.as_ref().is_none_or(|(s, _)| *s != wanted);
        if let Some(image) = &self.image
            && self.running.is_none()
            && scene_ready
            && stale
        {
            let (tx, rx) = mpsc::channel();
            let (scene, image, settings) = (Arc::clone(scene), Arc::clone(image), wanted.clone());
            let (repaint, encoding) = (ctx.clone(), self.encoding);
            std::thread::spawn(move || {
                let result = catch_panic(|| {
                    check::check_encoded(&scene, &settings, &image, encoding)
                        .map_err(|e| e.to_string())
                })
                .and_then(|r| r);
                let _ = tx.send(result);
                repaint.request_repaint();
            });
            self.running = Some((wanted, rx));
        }
        event
    }

    /// The newest diagnosis, if it is for the settings in force (`live`).
    pub fn checked(&self, live: &RenderSettings) -> Option<&Result<Checked, String>> {
        let wanted = figure_settings(live);
        self.done
            .as_ref()
            .filter(|(s, _)| *s == wanted)
            .map(|(_, r)| r)
    }

    /// The student's image, once read.
    pub fn image(&self) -> Option<&Rgb8> {
        self.image.as_deref()
    }

    /// Whether the image is read and the diagnosis is up to date with `live`.
    #[cfg(test)]
    pub fn is_settled(&self, live: &RenderSettings) -> bool {
        self.reading.is_none() && self.running.is_none() && self.checked(live).is_some()
    }

    /// The difference picture's texture pixels, RGBA.
    #[cfg(test)]
    pub fn difference_rgba(&self) -> Option<Vec<u8>> {
        self.difference_picture.rgba()
    }

    /// Draws the student's image left of the divider and the exact figure right of it, fitted
    /// into `rect`; or the difference picture.
    pub fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect) {
        let painter = ui.painter().with_clip_rect(rect);
        let ppp = ui.ctx().pixels_per_point();
        let figure_ready = self
            .done
            .as_ref()
            .is_some_and(|(_, r)| r.is_ok() && self.running.is_none());
        if self.difference
            && figure_ready
            && let Some(id) = self.difference_picture.id_for(rect, ppp)
        {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(id, rect, uv, egui::Color32::WHITE);
            tag(
                &painter,
                rect.left_top(),
                egui::Align2::LEFT_TOP,
                &format!("|yours − figure| × {:.1}", self.difference_gain),
            );
            return;
        }
        let student = self.student.id_for(rect, ppp);
        let figure = if figure_ready {
            self.figure.id_for(rect, ppp)
        } else {
            None
        };
        let x = self.divider.x(rect);
        paint_wipe(
            &painter,
            rect,
            x,
            [student, figure],
            ["yours", "exact figure"],
            true,
        );
        if !figure_ready {
            let why = match self.done.as_ref().filter(|_| self.running.is_none()) {
                Some((_, Err(e))) => e.clone(),
                _ => "checking…".to_owned(),
            };
            tag(
                &painter,
                rect.center_bottom(),
                egui::Align2::CENTER_BOTTOM,
                &why,
            );
        }
    }

    /// The inspector's lines for pixel `(x, y)`: the student's value beside the figure's.
    pub fn pixel_line(&self, live: &RenderSettings, x: u32, y: u32) -> Option<String> {
        let image = self.image.as_ref()?;
        let Some(Ok(checked)) = self.checked(live) else {
            return None;
        };
        if x >= image.width || y >= image.height {
            return None;
        }
        let (a, b) = (image.get(x, y), checked.figure.get(x, y));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap_or(0);
        let verdict = if worst <= check::compare::TOLERANCE {
            "within 2/255".to_owned()
        } else {
            format!("differs by up to {worst}/255")
        };
        Some(format!(
            "Your image: ({}, {}, {}) · exact figure: ({}, {}, {}) · {verdict}",
            a[0], a[1], a[2], b[0], b[1], b[2]
        ))
    }
}

impl Overlay for StudentCheck {
    fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect, _live: egui::TextureId) {
        StudentCheck::paint(self, ui, rect);
    }

    fn divider_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        on_marker: bool,
    ) -> bool {
        // None while the difference picture is shown.
        self.divider
            .input(ui, response, rect, on_marker, !self.difference)
    }
}

/// An 8-bit RGB image as egui's texture pixels.
pub(super) fn color_image(image: &Rgb8) -> egui::ColorImage {
    egui::ColorImage::from_rgb([image.width as usize, image.height as usize], &image.data)
}

/// The "Check my image" group of the side panel: how to start, or the diagnosis.
pub fn check_ui(
    ui: &mut egui::Ui,
    check: Option<&mut StudentCheck>,
    live: &RenderSettings,
    commands: &mut Vec<Command>,
) {
    let Some(check) = check else {
        ui.label(
            "Drop your own render of the lab on the window (PNG, BMP, PPM or JPEG), or open it \
             here: it is held against the exact figure for the settings below, and the likely \
             mistake is named.",
        );
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Check an image…")
                .on_hover_text("Choose your render in a file dialog")
                .clicked()
            {
                commands.push(Command::ShowCheckDialog);
            }
            if ui
                .button("Check the typed file")
                .on_hover_text("Check the image whose path is in the File field (Scene group)")
                .clicked()
            {
                commands.push(Command::CheckTyped);
            }
        });
        return;
    };
    ui.horizontal_wrapped(|ui| {
        ui.label(format!("Checking {}", check.name()));
        if ui
            .button("Stop checking")
            .on_hover_text("Back to the live image")
            .clicked()
        {
            commands.push(Command::StopChecking);
        }
    });
    ui.checkbox(&mut check.difference, "Difference |yours − figure|")
        .on_hover_text(format!(
            "Where your image differs from the exact figure: |yours − figure| per channel, \
             {:.1}× brighter (less than {}× where that would be white nearly everywhere, so \
             the largest difference is white); black where they agree",
            check.difference_gain,
            check::compare::DIFF_GAIN
        ));
    ui.weak("Set the stage, camera and light your image was made with: the check follows them.");
    match check.checked(live) {
        None if check.image().is_none() => {
            ui.label("Reading the image…");
        }
        None => {
            ui.label("Checking…");
        }
        Some(Err(e)) => {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        Some(Ok(checked)) => report_ui(ui, &checked.report, commands),
    }
}

/// The diagnosis, as `raylab check` prints it.
fn report_ui(ui: &mut egui::Ui, report: &check::Report, commands: &mut Vec<Command>) {
    let percent = |s: f64| format!("{:.1} %", 100.0 * s);
    ui.label(match report.encoding {
        Encoding::Lossless => format!(
            "Match: {} of pixels within 2/255 of the figure",
            percent(report.match_share)
        ),
        Encoding::Jpeg => format!(
            "Match: {} of pixels in 8×8 blocks whose mean is the figure's (a JPEG)",
            percent(report.match_share)
        ),
    });
    let best = &report.best;
    match best.mistake.as_str() {
        "none" => {
            ui.strong("Verdict: none — your image is the exact figure");
        }
        "unknown" => {
            ui.strong("Verdict: unknown");
            ui.label(&best.fix);
        }
        name => {
            ui.strong(format!(
                "Verdict: {name} — explains {} of pixels",
                percent(best.explains)
            ));
            ui.label(best.what());
            ui.label(format!("Lab: {}", best.equation));
            ui.label(format!("Fix: {}", best.fix));
            if let Some(stage) = &best.stage
                && ui
                    .button(format!("Switch to {}", stage.name))
                    .on_hover_text({
                        let on = |b: bool| if b { "on" } else { "off" };
                        let s = stage.switches;
                        format!(
                            "Set the stage to {}, shadows {}, indirect N {}: the settings your \
                             image was made with; the check follows them",
                            s.stage.label(),
                            on(s.shadows),
                            on(s.indirect)
                        )
                    })
                    .clicked()
            {
                commands.push(Command::SetStageSwitches(stage.switches));
            }
        }
    }
    if let Some(b) = &report.worst_block
        && b.mean_difference > 0.0
    {
        ui.label(format!(
            "Worst region: x {}–{}, y {}–{} (mean difference {:.1}/255)",
            b.x0,
            b.x1 - 1,
            b.y0,
            b.y1 - 1,
            b.mean_difference
        ));
    }
    for note in &report.notes {
        ui.weak(format!("Note: {note}"));
    }
    if !report.candidates.is_empty() {
        egui::CollapsingHeader::new("Candidates")
            .id_salt("check-candidates")
            .show(ui, |ui| {
                egui::Grid::new("check-candidates-grid")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for c in &report.candidates {
                            ui.label(c.mistake.name());
                            ui.label(percent(c.explains));
                            ui.end_row();
                        }
                    });
            });
    }
}

impl WorkbenchApp {
    /// Check my image: reads `path` and holds it against the exact figure for the current
    /// settings, in place of an A/B comparison.
    pub(super) fn start_check(&mut self, ctx: &egui::Context, path: std::path::PathBuf) {
        self.compare = None;
        let check = StudentCheck::start(ctx, path);
        self.set_status_while(
            StatusKind::Info,
            Cause::Checking,
            format!("Reading {}…", check.name()),
        );
        self.check = Some(check);
    }

    /// Once a frame: the check's image once read (the camera then renders at its size, with
    /// the same field of view) and its diagnosis.
    pub(super) fn receive_check(&mut self, ctx: &egui::Context) {
        let scene_ready = self.state.settings.scene == self.scene_choice;
        let Some(check) = &mut self.check else {
            return;
        };
        match check.update(ctx, &self.state.settings, &self.scene, scene_ready) {
            None => {}
            Some(Event::Read { width, height }) => {
                let name = check.name();
                let camera = &mut self.state.settings.camera;
                if (camera.width, camera.height) != (width, height) {
                    let scale = width as f32 / camera.width as f32;
                    camera.focal_length *= scale;
                    camera.width = width;
                    camera.height = height;
                }
                self.set_status_while(
                    StatusKind::Info,
                    Cause::Checking,
                    format!(
                        "Checking {name} ({width} × {height}) against the exact figure: set the \
                         stage, camera and light it was made with"
                    ),
                );
            }
            Some(Event::Unreadable(e)) => {
                self.check = None;
                self.set_status(StatusKind::Error, e);
            }
        }
    }
}
