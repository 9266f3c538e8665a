//! The A/B wipe: two renders side by side in one image, split by a draggable divider.
//!
//! "Freeze as A" keeps the current settings and scene as A and starts a second
//! [`Controller`] for them (its own worker and pool, as many threads as B's), which renders A
//! once, progressively, and then idles. B is the app's own controller, following the live
//! settings, so any change (the stage, shadows, samples, the display…) shows against A at once.
//! Each side's pixels come through its own display: A keeps the one it was frozen with, so
//! "lab vs sRGB display" is a comparison like any other.
//!
//! The viewport draws A left of the divider and B right of it, fitted into B's image rect
//! ([`Compare::paint`]); a drag that starts on the divider moves it instead of turning the
//! camera ([`Overlay::divider_input`]). "Difference |A − B|" shows instead the per-channel
//! absolute difference of the two *linear* images, scaled so the largest maps to white. It is
//! computed on a short-lived thread, at most one at a time, whenever either side has a new
//! frame: a large image's difference takes longer than a UI frame.
//!
//! The app's side is a handful of hooks: [`WorkbenchApp::freeze_a`], [`WorkbenchApp::receive_compare`]
//! once a frame, the viewport's and the panel's `compare` argument, and one line in
//! `is_settled`.

use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};

use eframe::egui;
use raylab_core::shading::light::LightSpec;
use raylab_core::shapes::scene::Scene;
use raylab_core::transport::progressive::{
    Controller, ControllerError, Frame, WorkerError, catch_panic,
};
use raylab_core::{Camera, Image, RenderSettings, Shading};

use super::stats::Stats;
use super::viewport::{Overlay, filter_for};
use super::{Command, Shown, StatusKind, WorkbenchApp};

/// A drag that starts this close to the divider, in points, moves it.
pub const DIVIDER_GRAB: f32 = 6.0;

/// The divider's position when a comparison starts: half and half.
pub const DEFAULT_DIVIDER: f32 = 0.5;

/// The newest frame of A, without its display pixels (those went to the texture).
#[derive(Clone, Debug)]
pub struct SideFrame {
    /// Read by `is_settled`, which only the tests use.
    #[cfg_attr(not(test), allow(dead_code))]
    pub generation: u64,
    pub image: Arc<Image>,
    pub samples: u32,
    pub target: u32,
    pub is_preview: bool,
}

impl SideFrame {
    #[cfg(test)]
    pub fn is_final(&self) -> bool {
        !self.is_preview && self.samples >= self.target
    }
}

/// What the comparison knows of B: the app's newest frame.
struct BSide {
    image: Arc<Image>,
    is_preview: bool,
    /// The full resolution B renders at (a preview's image is smaller).
    size: (u32, u32),
}

/// A texture and the pixels it was last given, so the filter can change without a new frame.
#[derive(Default)]
pub(super) struct Texture {
    handle: Option<egui::TextureHandle>,
    pixels: Option<Arc<egui::ColorImage>>,
    options: egui::TextureOptions,
}

impl Texture {
    pub(super) fn set(&mut self, ctx: &egui::Context, name: &str, image: egui::ColorImage) {
        let image = Arc::new(image);
        match &mut self.handle {
            Some(handle) => handle.set(Arc::clone(&image), self.options),
            None => {
                self.handle = Some(ctx.load_texture(name, Arc::clone(&image), self.options));
            }
        }
        self.pixels = Some(image);
    }

    /// The texture to draw into `rect`, with nearest filtering when magnified as the viewport
    /// does for B, so both sides of the divider show pixels alike.
    pub(super) fn id_for(
        &mut self,
        rect: egui::Rect,
        pixels_per_point: f32,
    ) -> Option<egui::TextureId> {
        let (handle, pixels) = (self.handle.as_mut()?, self.pixels.as_ref()?);
        let wanted = filter_for(rect, pixels_per_point, pixels.size[0]);
        if wanted != self.options {
            self.options = wanted;
            handle.set(Arc::clone(pixels), wanted);
        }
        Some(handle.id())
    }

    #[cfg(test)]
    pub(super) fn rgba(&self) -> Option<Vec<u8>> {
        self.pixels
            .as_ref()
            .map(|p| p.pixels.iter().flat_map(|c| c.to_array()).collect())
    }
}

/// A finished difference image.
pub struct Difference {
    /// |A − B| per channel, linear.
    pub image: Arc<Image>,
    /// Its largest finite value: what white stands for.
    pub max: f32,
}

/// What the difference thread sends back.
struct Computed {
    image: Image,
    max: f32,
    pixels: egui::ColorImage,
}

/// The difference image and the thread computing the next one.
#[derive(Default)]
struct Diff {
    /// The images (A's, B's) the newest difference was started for: a new frame on either side
    /// makes them stale.
    started: Option<(Arc<Image>, Arc<Image>)>,
    running: Option<Receiver<Result<Computed, String>>>,
    shown: Option<Difference>,
    error: Option<String>,
    texture: Texture,
}

/// A comparison in progress: A's controller and frame, the divider and the difference.
pub struct Compare {
    /// A's settings as frozen, its display included.
    settings: RenderSettings,
    controller: Controller,
    a: Option<SideFrame>,
    /// A's last full-resolution pass time, in ms.
    a_pass_ms: Option<f64>,
    texture: Texture,
    b: Option<BSide>,
    pub divider: Divider,
    /// Show |A − B| instead of the wipe.
    pub difference: bool,
    diff: Diff,
}

impl Compare {
    /// Starts rendering A: `settings` on `scene`, on a controller of its own with `threads`
    /// render threads, shown through `settings.display` and denoised or not (`denoise`, the
    /// Denoise switch when A is frozen) for good.
    pub fn start(
        ctx: &egui::Context,
        scene: &Arc<Scene>,
        settings: &RenderSettings,
        threads: usize,
        denoise: bool,
    ) -> Result<Self, ControllerError> {
        let controller = Controller::new(threads, super::repaint_for_frames(ctx))?;
        // Before the job, so even its first frame is shown through A's display.
        controller.set_display(settings.display);
        controller.set_denoise(denoise);
        controller.submit(scene, settings)?;
        Ok(Self {
            settings: settings.clone(),
            controller,
            a: None,
            a_pass_ms: None,
            texture: Texture::default(),
            b: None,
            divider: Divider::default(),
            difference: false,
            diff: Diff::default(),
        })
    }

    /// A's frozen settings.
    #[cfg(test)]
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Once a UI frame: takes A's newest frame, notes B's (`b`, the app's frame on screen),
    /// keeps A's threads equal to B's (`threads`), and takes or starts the difference. Never
    /// waits. Returns a problem A's renderer met (a job that panicked among them), for the
    /// status line.
    pub fn update(
        &mut self,
        ctx: &egui::Context,
        b: Option<&Shown>,
        threads: usize,
    ) -> Option<WorkerError> {
        let mut error = self.controller.take_error();
        if let Some(frame) = self.controller.take_frame() {
            self.show_a(ctx, frame);
        }
        if threads != self.controller.threads()
            && let Err(e) = self.controller.set_threads(threads)
        {
            error = Some(WorkerError {
                message: e.to_string(),
                settings: None,
            });
        }
        self.b = b.map(|b| BSide {
            image: Arc::clone(&b.image),
            is_preview: b.is_preview,
            size: (b.settings.camera.width, b.settings.camera.height),
        });
        self.receive_difference(ctx);
        if self.difference && self.diff.running.is_none() {
            self.start_difference(ctx);
        }
        error
    }

    fn show_a(&mut self, ctx: &egui::Context, frame: Frame) {
        let size = [frame.image.width as usize, frame.image.height as usize];
        let pixels = egui::ColorImage::from_rgba_unmultiplied(size, &frame.rgba);
        self.texture.set(ctx, "raylab-compare-a", pixels);
        if !frame.is_preview {
            self.a_pass_ms = Some(frame.pass_ms);
        }
        self.a = Some(SideFrame {
            generation: frame.generation,
            image: frame.image,
            samples: frame.samples,
            target: frame.target,
            is_preview: frame.is_preview,
        });
    }

    /// A's newest frame.
    #[cfg(test)]
    pub fn a(&self) -> Option<&SideFrame> {
        self.a.as_ref()
    }

    /// The two images a difference should be computed for now: both at full resolution and of
    /// one size, else `None`.
    fn difference_inputs(&self) -> Option<(Arc<Image>, Arc<Image>)> {
        let a = self.a.as_ref().filter(|a| !a.is_preview)?;
        let b = self.b.as_ref().filter(|b| !b.is_preview)?;
        let same = a.image.width == b.image.width && a.image.height == b.image.height;
        same.then(|| (Arc::clone(&a.image), Arc::clone(&b.image)))
    }

    /// Whether a difference should be started: its inputs changed since the last one.
    fn difference_wanted(&self) -> Option<(Arc<Image>, Arc<Image>)> {
        let inputs = self.difference_inputs()?;
        let done = self
            .diff
            .started
            .as_ref()
            .is_some_and(|(a, b)| Arc::ptr_eq(a, &inputs.0) && Arc::ptr_eq(b, &inputs.1));
        (!done).then_some(inputs)
    }

    /// Starts computing the difference on a short-lived thread, if it is out of date.
    fn start_difference(&mut self, ctx: &egui::Context) {
        let Some((a, b)) = self.difference_wanted() else {
            return;
        };
        // Marked started even if the thread can't start, so a failure is reported once, not
        // retried every frame; the next new frame tries again.
        self.diff.started = Some((Arc::clone(&a), Arc::clone(&b)));
        let (sender, receiver) = mpsc::channel();
        let repaint = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("raylab-difference".to_owned())
            .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
            .spawn(move || {
                // A panic is sent as its message: the difference view says what went wrong
                // rather than that the thread stopped.
                let computed = catch_panic(|| {
                    let (image, max) = difference(&a, &b);
                    let rgba = difference_rgba(&image, max);
                    let size = [image.width as usize, image.height as usize];
                    let pixels = egui::ColorImage::from_rgba_unmultiplied(size, &rgba);
                    Computed { image, max, pixels }
                });
                let _ = sender.send(computed);
                repaint.request_repaint();
            });
        match spawned {
            Ok(_) => {
                self.diff.running = Some(receiver);
                self.diff.error = None;
            }
            Err(e) => self.diff.error = Some(format!("could not compute the difference: {e}")),
        }
    }

    fn receive_difference(&mut self, ctx: &egui::Context) {
        let Some(receiver) = &self.diff.running else {
            return;
        };
        match receiver.try_recv() {
            Ok(Err(panic)) => {
                self.diff.error = Some(format!("computing the difference panicked: {panic}"));
            }
            Ok(Ok(computed)) => {
                self.diff
                    .texture
                    .set(ctx, "raylab-compare-difference", computed.pixels);
                self.diff.shown = Some(Difference {
                    image: Arc::new(computed.image),
                    max: computed.max,
                });
            }
            Err(TryRecvError::Empty) => return,
            Err(TryRecvError::Disconnected) => {
                self.diff.error = Some("the difference thread stopped".to_owned());
            }
        }
        self.diff.running = None;
    }

    /// The difference on screen, if it fits the sizes A and B have now.
    pub fn difference_shown(&self) -> Option<&Difference> {
        let (w, h) = self.b.as_ref()?.size;
        let a = &self.settings.camera;
        self.diff
            .shown
            .as_ref()
            .filter(|d| (d.image.width, d.image.height) == (w, h) && (a.width, a.height) == (w, h))
    }

    /// What the difference view shows, in words: its scale, or why there is none yet.
    pub fn difference_text(&self) -> String {
        if let Some(b) = &self.b {
            let a = &self.settings.camera;
            if (a.width, a.height) != b.size {
                return format!(
                    "Difference needs the same resolution: A is {} × {}, B is {} × {}",
                    a.width, a.height, b.size.0, b.size.1
                );
            }
        }
        if let Some(error) = &self.diff.error {
            return error.clone();
        }
        match self.difference_shown() {
            Some(d) if d.max == 0.0 => "A and B are identical".to_owned(),
            Some(d) => format!("white = |A − B| ≥ {}", significant(d.max, 3)),
            None => "Computing the difference...".to_owned(),
        }
    }

    /// Whether A's job has reached its target on screen and the difference (when shown) is up
    /// to date with both sides.
    #[cfg(test)]
    pub fn is_settled(&self) -> bool {
        let a_final = self
            .a
            .as_ref()
            .is_some_and(|a| a.generation == self.controller.generation() && a.is_final());
        let difference_done =
            !self.difference || (self.diff.running.is_none() && self.difference_wanted().is_none());
        a_final && difference_done
    }

    /// Draws A left of the divider and B (`b`, the viewport's texture) right of it, both
    /// fitted into `rect` (B's image's rect); or, in difference mode, |A − B| over the whole
    /// rect. The divider, its handle and the side labels go on top.
    pub fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect, b: egui::TextureId) {
        let painter = ui.painter().with_clip_rect(rect);
        let ppp = ui.ctx().pixels_per_point();
        let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
        if self.difference {
            if self.difference_shown().is_some()
                && let Some(id) = self.diff.texture.id_for(rect, ppp)
            {
                painter.image(id, rect, uv, egui::Color32::WHITE);
                tag(&painter, rect.left_top(), egui::Align2::LEFT_TOP, "|A − B|");
            } else {
                // Nothing to show yet (or the sizes differ): the wipe, with the reason on top.
                self.paint_wipe(&painter, rect, b, ppp, false);
            }
            tag(
                &painter,
                rect.center_bottom(),
                egui::Align2::CENTER_BOTTOM,
                &self.difference_text(),
            );
            return;
        }
        self.paint_wipe(&painter, rect, b, ppp, true);
    }

    fn paint_wipe(
        &mut self,
        painter: &egui::Painter,
        rect: egui::Rect,
        b: egui::TextureId,
        ppp: f32,
        with_divider: bool,
    ) {
        let a = self.texture.id_for(rect, ppp);
        let x = self.divider.x(rect);
        paint_wipe(painter, rect, x, [a, Some(b)], ["A", "B"], with_divider);
    }

    /// The Stats lines while comparing: each side's pass time and samples (`b`: the app's).
    pub fn stats_ui(&self, ui: &mut egui::Ui, b: &Stats) {
        let a_line = match &self.a {
            Some(a) => side_line(self.a_pass_ms, a.is_preview, a.samples, a.target),
            None => "rendering...".to_owned(),
        };
        ui.label(format!("A: {a_line}"))
            .on_hover_text("The frozen settings: last full pass and samples so far");
        let b_pass = b.full_pass.map(|(ms, _, _)| ms);
        ui.label(format!(
            "B: {}",
            side_line(b_pass, b.is_preview, b.samples, b.target)
        ))
        .on_hover_text("The live settings: last full pass and samples so far");
    }

    #[cfg(test)]
    pub fn a_rgba(&self) -> Option<Vec<u8>> {
        self.texture.rgba()
    }

    #[cfg(test)]
    pub fn difference_rgba(&self) -> Option<Vec<u8>> {
        self.diff.texture.rgba()
    }

    #[cfg(test)]
    pub fn threads(&self) -> usize {
        self.controller.threads()
    }

    #[cfg(test)]
    pub fn inject_panic_on_next_pass(&self) {
        self.controller.inject_panic_on_next_pass();
    }
}

impl Overlay for Compare {
    fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect, live: egui::TextureId) {
        Compare::paint(self, ui, rect, live);
    }

    /// A drag on the divider moves it ([`Divider::input`]); none in difference mode.
    fn divider_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        on_marker: bool,
    ) -> bool {
        self.divider
            .input(ui, response, rect, on_marker, !self.difference)
    }
}

/// The wipe's divider: where it stands and whether a drag holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Divider {
    /// A fraction of the image's width from its left edge.
    pub at: f32,
    /// A drag that started on the divider is going on.
    dragging: bool,
}

impl Default for Divider {
    fn default() -> Self {
        Self {
            at: DEFAULT_DIVIDER,
            dragging: false,
        }
    }
}

impl Divider {
    /// Its x in `rect`, the image's rect.
    pub fn x(&self, rect: egui::Rect) -> f32 {
        rect.left() + self.at.clamp(0.0, 1.0) * rect.width()
    }

    /// Pointer input, given the viewport's `response` over the image `rect`: a drag that starts
    /// within [`DIVIDER_GRAB`] of the divider (and not on the light's marker, `on_marker`, the
    /// smaller target) moves it; none while it is not `shown`. Returns whether the divider has
    /// the drag.
    pub fn input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        on_marker: bool,
        shown: bool,
    ) -> bool {
        if !shown {
            self.dragging = false;
            return false;
        }
        let x = self.x(rect);
        let near = |p: egui::Pos2| {
            (p.x - x).abs() <= DIVIDER_GRAB && (rect.min.y..=rect.max.y).contains(&p.y)
        };
        if response.drag_started() && !on_marker {
            // Where the button went down, not where the drag was recognised a few points on.
            let origin = ui
                .input(|i| i.pointer.press_origin())
                .or_else(|| response.interact_pointer_pos());
            self.dragging = origin.is_some_and(near);
        }
        if !response.dragged() {
            self.dragging = false;
        }
        if self.dragging {
            if let Some(p) = response.interact_pointer_pos()
                && rect.width() > 0.0
            {
                self.at = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
            }
            ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
        } else if response.hover_pos().is_some_and(near) {
            ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
        }
        self.dragging
    }
}

/// The wipe: `sides[0]` left of `x` and `sides[1]` right of it, each fitted into `rect` (a side
/// not there yet is a dark panel rather than the other side passing for it), with the divider
/// and its handle when `with_divider`, and `labels` in the top corners.
pub fn paint_wipe(
    painter: &egui::Painter,
    rect: egui::Rect,
    x: f32,
    sides: [Option<egui::TextureId>; 2],
    labels: [&str; 2],
    with_divider: bool,
) {
    let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
    let left = egui::Rect::from_min_max(rect.min, egui::pos2(x, rect.max.y));
    let right = egui::Rect::from_min_max(egui::pos2(x, rect.min.y), rect.max);
    for (side, part) in sides.into_iter().zip([left, right]) {
        match side {
            Some(id) => {
                painter
                    .with_clip_rect(part)
                    .image(id, rect, uv, egui::Color32::WHITE);
            }
            None => {
                painter.rect_filled(part, 0.0, egui::Color32::from_gray(20));
            }
        }
    }
    if with_divider {
        let top = egui::pos2(x, rect.min.y);
        let bottom = egui::pos2(x, rect.max.y);
        painter.line_segment([top, bottom], egui::Stroke::new(3.0, egui::Color32::BLACK));
        painter.line_segment([top, bottom], egui::Stroke::new(1.5, egui::Color32::WHITE));
        let handle = egui::Rect::from_center_size(
            egui::pos2(x, rect.center().y),
            egui::vec2(2.0 * DIVIDER_GRAB, 30.0),
        );
        painter.rect(
            handle,
            3.0,
            egui::Color32::WHITE,
            egui::Stroke::new(1.0, egui::Color32::BLACK),
            egui::StrokeKind::Outside,
        );
    }
    tag(painter, rect.left_top(), egui::Align2::LEFT_TOP, labels[0]);
    tag(
        painter,
        rect.right_top(),
        egui::Align2::RIGHT_TOP,
        labels[1],
    );
}

/// "pass 12.3 ms · 16/16 samples", or "preview" before the first full pass.
fn side_line(pass_ms: Option<f64>, is_preview: bool, samples: u32, target: u32) -> String {
    let pass = pass_ms.map_or_else(|| "pass -".to_owned(), |ms| format!("pass {ms:.1} ms"));
    if is_preview {
        format!("{pass} · preview")
    } else {
        format!("{pass} · {samples}/{target} samples")
    }
}

/// Text on a dark plate at an edge of the image (a little inside it), legible on light and
/// dark renders alike.
pub(super) fn tag(painter: &egui::Painter, pos: egui::Pos2, anchor: egui::Align2, text: &str) {
    let pos = pos - 4.0 * anchor.to_sign();
    let margin = egui::vec2(4.0, 2.0);
    let galley = painter.layout_no_wrap(
        text.to_owned(),
        egui::FontId::proportional(14.0),
        egui::Color32::WHITE,
    );
    let plate = anchor.anchor_size(pos, galley.size() + 2.0 * margin);
    painter.rect_filled(plate, 3.0, egui::Color32::from_black_alpha(170));
    painter.galley(plate.min + margin, galley, egui::Color32::WHITE);
}

/// `x` with about `digits` significant digits: 0.123, 1.23, 12.3, 0.000456.
pub fn significant(x: f32, digits: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (digits - 1 - x.abs().log10().floor() as i32).clamp(0, 9) as usize;
    format!("{x:.decimals$}")
}

/// |A − B| per channel of two linear images of one size, and its largest finite value.
pub fn difference(a: &Image, b: &Image) -> (Image, f32) {
    debug_assert_eq!((a.width, a.height), (b.width, b.height));
    let pixels: Vec<_> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(a, b)| (*a - *b).abs())
        .collect();
    let max = pixels
        .iter()
        .flat_map(|p| p.to_array())
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max);
    let image = Image {
        width: a.width,
        height: a.height,
        pixels,
    };
    (image, max)
}

/// The difference as 8-bit RGBA, linearly scaled so `max` is white; a non-finite difference
/// (a NaN or infinity on either side) shows white too, as "at least the largest".
pub fn difference_rgba(diff: &Image, max: f32) -> Vec<u8> {
    let channel = |d: f32| -> u8 {
        if !d.is_finite() || (max > 0.0 && d >= max) {
            255
        } else if max > 0.0 {
            (d / max * 255.0).round() as u8
        } else {
            0
        }
    };
    diff.pixels
        .iter()
        .flat_map(|p| {
            let [r, g, b] = p.to_array().map(channel);
            [r, g, b, 255]
        })
        .collect()
}

/// The settings that differ between `a` and `b`, by name ("stage", "shadows", "samples",
/// "display"…), in the panel's order. The structs are taken apart field by field without `..`,
/// so a setting added later can't be forgotten here: it fails to compile until it is listed.
pub fn differences(a: &RenderSettings, b: &RenderSettings) -> Vec<&'static str> {
    let RenderSettings {
        scene,
        camera,
        light,
        shading,
        material_preset,
        roughness,
        part_materials,
        texture_preset,
        display,
        view,
        samples_per_pixel,
        seed,
        // The window's Denoise switch is its own (not among the settings it traces with).
        denoise: _,
        // The window's own equations are the Your equations panel's (not traced by A/B).
        equations: _,
    } = a;
    let mut out = Vec::new();
    let mut differ = |name, differs: bool| {
        if differs {
            out.push(name);
        }
    };
    differ("scene", *scene != b.scene);
    camera_differences(camera, &b.camera, &mut differ);
    let LightSpec {
        position,
        power,
        colour,
        kind,
    } = light;
    differ("light position", *position != b.light.position);
    differ("light power", *power != b.light.power);
    differ("light colour", *colour != b.light.colour);
    differ("light shape", kind.shape() != b.light.kind.shape());
    // The same kind: each parameter by the name errors give it (`light_kinds!`); another
    // kind is named above.
    if kind.shape() == b.light.kind.shape() {
        for ((p, value), other) in kind.params_and_values().zip(b.light.kind.values()) {
            differ(p.noun, value != other);
        }
    }
    let Shading {
        stage,
        shadows,
        indirect,
        indirect_light,
        bounces,
        specular_depth,
        smooth,
        parallax_shadows,
        caustics,
        photons,
    } = shading;
    let s = &b.shading;
    differ("stage", *stage != s.stage);
    differ("shadows", *shadows != s.shadows);
    differ("indirect light", *indirect != s.indirect);
    differ("N", *indirect_light != s.indirect_light);
    differ("bounces", *bounces != s.bounces);
    differ("specular depth", *specular_depth != s.specular_depth);
    differ("smooth shading", *smooth != s.smooth);
    differ(
        "parallax self-shadowing",
        *parallax_shadows != s.parallax_shadows,
    );
    differ("caustics", *caustics != s.caustics);
    differ("photons per pass", *photons != s.photons);
    differ("materials", *material_preset != b.material_preset);
    differ("roughness", *roughness != b.roughness);
    differ("part materials", *part_materials != b.part_materials);
    differ("textures", *texture_preset != b.texture_preset);
    differ("samples", *samples_per_pixel != b.samples_per_pixel);
    differ("seed", *seed != b.seed);
    differ("display", display.transform != b.display.transform);
    differ("exposure", display.exposure != b.display.exposure);
    differ("view", *view != b.view);
    out
}

/// The camera's differences. A resolution change keeps the field of view (the focal length
/// follows the width), so the focal length is compared per pixel of width: the same view at
/// another size lists only "resolution".
fn camera_differences(a: &Camera, b: &Camera, differ: &mut impl FnMut(&'static str, bool)) {
    let Camera {
        position,
        yaw,
        pitch,
        focal_length,
        width,
        height,
        aperture,
        focus_distance,
    } = a;
    differ("resolution", (*width, *height) != (b.width, b.height));
    differ(
        "camera",
        *position != b.position || *yaw != b.yaw || *pitch != b.pitch,
    );
    let per_width = |f: f32, w: u32| f / w.max(1) as f32;
    let (fa, fb) = (
        per_width(*focal_length, *width),
        per_width(b.focal_length, b.width),
    );
    differ(
        "focal length",
        (fa - fb).abs() > 1e-5 * fa.abs().max(fb.abs()),
    );
    differ(
        "lens",
        *aperture != b.aperture || *focus_distance != b.focus_distance,
    );
}

/// The "Compare A/B" group of the side panel: freeze, stop, the difference switch, and what
/// differs between A and the live settings.
pub fn compare_ui(
    ui: &mut egui::Ui,
    compare: Option<&mut Compare>,
    live: &RenderSettings,
    commands: &mut Vec<Command>,
) {
    let Some(compare) = compare else {
        ui.label(
            "Freeze the current image as A, then change anything: the image splits into A \
             (left) and B, the live settings (right), at a divider you can drag.",
        );
        if ui
            .button("Freeze as A")
            .on_hover_text("Keep the current settings and scene as A, rendered on its own")
            .clicked()
        {
            commands.push(Command::FreezeA);
        }
        return;
    };
    ui.horizontal_wrapped(|ui| {
        if ui
            .button("Freeze as A")
            .on_hover_text("Freeze the current settings as A again, in place of the old A")
            .clicked()
        {
            commands.push(Command::FreezeA);
        }
        if ui
            .button("Stop comparing")
            .on_hover_text("Drop A and its renderer: back to the one live image")
            .clicked()
        {
            commands.push(Command::StopComparing);
        }
    });
    ui.checkbox(&mut compare.difference, "Difference |A − B|")
        .on_hover_text(
            "Show how far apart A and B are, per channel of the linear images, scaled so the \
             largest difference is white",
        );
    let differs = differences(&compare.settings, live);
    if differs.is_empty() {
        ui.label("A and B: identical settings");
    } else {
        ui.label(format!("A and B differ in: {}", differs.join(", ")));
    }
    if compare.difference {
        ui.label(compare.difference_text());
    }
}

impl WorkbenchApp {
    /// "Freeze as A": the current settings and scene become A, rendered on a controller of
    /// their own. Freezing again replaces A, keeping the divider and the difference switch.
    pub(super) fn freeze_a(&mut self, ctx: &egui::Context) {
        if self.state.settings.scene != self.scene_choice {
            self.set_status(
                StatusKind::Notice,
                "The scene is still loading: freeze A once it is on screen",
            );
            return;
        }
        let kept = self.compare.as_ref().map(|c| (c.divider, c.difference));
        // The old A stops before the new one starts: two cores are shared by all renders.
        self.compare = None;
        // A gets as many threads as B has, so their pass times compare.
        let threads = self
            .controller
            .as_ref()
            .map_or(self.state.render_threads, Controller::threads);
        let denoise = self.state.denoise;
        match Compare::start(ctx, &self.scene, &self.state.settings, threads, denoise) {
            Ok(mut compare) => {
                if let Some((divider, difference)) = kept {
                    compare.divider = divider;
                    compare.difference = difference;
                }
                self.compare = Some(compare);
                // Advice for while comparing: it goes when comparing stops.
                self.set_status_while(
                    StatusKind::Info,
                    super::Cause::Comparing,
                    "Frozen as A: change anything for B; drag the divider to compare",
                );
            }
            Err(e) => self.set_status(StatusKind::Error, format!("Could not freeze A: {e}")),
        }
    }

    /// Once a frame, after B's frames are taken: A's frames, and the difference.
    pub(super) fn receive_compare(&mut self, ctx: &egui::Context) {
        let threads = self.controller.as_ref().map(Controller::threads);
        let Some(compare) = &mut self.compare else {
            return;
        };
        let threads = threads.unwrap_or_else(|| compare.controller.threads());
        if let Some(error) = compare.update(ctx, self.shown.as_ref(), threads) {
            self.show_worker_error("A: ", error, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn the_difference_is_per_channel_and_scaled_to_its_largest() {
        let a = Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::new(1.0, 0.5, 0.0), Vec3::splat(0.25)],
        };
        let mut b = a.clone();
        b.pixels[1] = Vec3::new(0.25, 0.75, 0.0);
        let (d, max) = difference(&a, &b);
        assert_eq!(d.pixels, vec![Vec3::ZERO, Vec3::new(0.0, 0.5, 0.25)]);
        assert_eq!(max, 0.5);
        assert_eq!(
            difference_rgba(&d, max),
            vec![0, 0, 0, 255, 0, 255, 128, 255]
        );
        let (same, zero) = difference(&a, &a);
        assert_eq!(zero, 0.0);
        assert!(
            difference_rgba(&same, zero)
                .chunks(4)
                .all(|p| p == [0, 0, 0, 255])
        );
    }

    #[test]
    fn a_non_finite_pixel_shows_white_and_leaves_the_scale_alone() {
        let a = Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::new(f32::NAN, 0.0, 0.0), Vec3::splat(0.2)],
        };
        let b = Image {
            pixels: vec![Vec3::ZERO, Vec3::splat(0.1)],
            ..a.clone()
        };
        let (d, max) = difference(&a, &b);
        assert!((max - 0.1).abs() < 1e-6);
        assert_eq!(difference_rgba(&d, max)[..4], [255, 0, 0, 255]);
    }

    #[test]
    fn the_differences_are_named() {
        let a = RenderSettings::default();
        assert!(differences(&a, &a).is_empty());
        let mut b = a.clone();
        b.shading.shadows = false;
        b.samples_per_pixel = 16;
        b.display.transform = raylab_core::transport::display::DisplayTransform::Srgb;
        assert_eq!(differences(&a, &b), ["shadows", "samples", "display"]);
        // The same view at another size is only a resolution change.
        let mut c = a.clone();
        c.camera = c.camera.with_resolution(256, 256);
        assert_eq!(differences(&a, &c), ["resolution"]);
        c.camera.yaw = 0.1;
        assert_eq!(differences(&a, &c), ["resolution", "camera"]);
    }

    /// Each parameter of each light kind (`light_kinds!`) is noticed, by the name errors give
    /// it; another kind is "light shape".
    #[test]
    fn every_light_parameter_is_noticed() {
        use raylab_core::shading::light::{LightKind, LightShape, ParamValue};
        for shape in LightShape::ALL {
            let mut a = RenderSettings::default();
            a.light.kind = LightKind::of_shape(shape);
            if shape != LightShape::default() {
                assert_eq!(differences(&RenderSettings::default(), &a), ["light shape"]);
            }
            for (p, value) in a.light.kind.params_and_values() {
                let mut b = a.clone();
                let other = match value {
                    ParamValue::Number(x) => ParamValue::Number(x * 0.5),
                    ParamValue::Point(v) => ParamValue::Point(v + glam::Vec3::X * 0.1),
                };
                b.light.kind.set(p.name, other).unwrap();
                assert_eq!(differences(&a, &b), [p.noun], "{shape} {}", p.name);
            }
        }
    }

    #[test]
    fn scales_keep_three_significant_digits() {
        assert_eq!(significant(0.123_45, 3), "0.123");
        assert_eq!(significant(1.234_5, 3), "1.23");
        assert_eq!(significant(12.345, 3), "12.3");
        assert_eq!(significant(0.000_456_7, 3), "0.000457");
        assert_eq!(significant(1234.0, 3), "1234");
    }
}
