//! The render: a settings change becomes a job for the [`Controller`] ([`WorkbenchApp::sync_render`],
//! the one place), and its finished frames come back to the screen and the stats ([`Shown`]).

use std::sync::Arc;
use std::time::Instant;

use eframe::egui;
use raylab_core::transport::progressive::Frame;
use raylab_core::{Image, RenderSettings};

use super::WorkbenchApp;
use super::inspector::same_spot;
use super::status::{Cause, Status, StatusKind};

#[cfg(doc)]
use raylab_core::transport::progressive::Controller;

/// The frame on screen, without its display pixels (those went to the texture).
#[derive(Clone, Debug)]
pub struct Shown {
    pub generation: u64,
    pub settings: RenderSettings,
    pub image: Arc<Image>,
    pub samples: u32,
    pub target: u32,
    pub is_preview: bool,
    /// The display its pixels on screen were converted with: a display change shows the same
    /// frame again, converted anew.
    #[cfg_attr(
        not(test),
        expect(dead_code, reason = "tests wait for the display in force")
    )]
    pub display: raylab_core::transport::display::Display,
    /// Whether the denoiser was on when its pixels were converted.
    #[cfg_attr(
        not(test),
        expect(dead_code, reason = "tests wait for the denoiser's state in force")
    )]
    pub denoise: bool,
    /// The denoised image on screen, when the denoiser was on and had one, and the samples it
    /// was made from (what a screenshot then saves).
    pub denoised: Option<(Arc<Image>, u32)>,
}

impl Shown {
    #[cfg(test)]
    pub(super) fn is_final(&self) -> bool {
        !self.is_preview && self.samples >= self.target
    }
}

/// The render worker's notify: one repaint for each frame it publishes. egui's
/// `request_repaint` runs two UI frames for each request (to let layout settle); the second
/// one redraws the same picture, and under a software renderer each UI frame takes CPU from
/// the render threads. A request with a delay runs one; a millisecond is not seen.
pub fn repaint_for_frames(ctx: &egui::Context) -> raylab_core::transport::progressive::Notify {
    let ctx = ctx.clone();
    Box::new(move || ctx.request_repaint_after(std::time::Duration::from_millis(1)))
}

impl WorkbenchApp {
    /// The one place that turns a settings change into a render job.
    pub(super) fn sync_render(&mut self) {
        let Some(controller) = &mut self.controller else {
            return;
        };
        if self.state.settings.scene != self.scene_choice {
            // The scene is still loading: the image on screen stays until it is ready.
            return;
        }
        let mut restarted = None;
        if self.state.render_threads != controller.threads() {
            restarted = Some(controller.set_threads(self.state.render_threads));
        }
        // The display transform and exposure only change how the image is shown: the
        // controller re-displays what it has, without tracing again.
        if controller.display() != self.state.settings.display {
            controller.set_display(self.state.settings.display);
        }
        if controller.denoise() != self.state.denoise {
            controller.set_denoise(self.state.denoise);
        }
        let settings = &self.state.settings;
        if !self
            .submitted
            .as_ref()
            .is_some_and(|s| s.renders_like(settings))
        {
            // A new resolution keeps the inspected pixel on the same spot of the image.
            let size = |s: &RenderSettings| [s.camera.width, s.camera.height];
            if let (Some(old), Some(pinned)) = (&self.submitted, self.state.pinned) {
                self.state.pinned = Some(same_spot(pinned, size(old), size(settings)));
            }
            self.submitted = Some(settings.clone());
            restarted = Some(controller.submit(&self.scene, settings));
        }
        match restarted {
            Some(Ok(generation)) => {
                self.submitted_generation = generation;
                self.change = Some((Instant::now(), 0));
                self.stats.threads = controller.threads();
            }
            Some(Err(e)) => self.set_error(Cause::InvalidSettings, format!("Not rendered: {e}")),
            None => {}
        }
    }

    /// Takes the newest finished frame, if any, and shows it.
    pub(super) fn receive_frames(&mut self, ctx: &egui::Context) {
        let Some(controller) = &self.controller else {
            return;
        };
        let (error, frame) = (controller.take_error(), controller.take_frame());
        if let Some(error) = error {
            let submitted = self.submitted_generation;
            self.show_worker_error("", error, Some(Cause::RenderFailed { submitted }));
        }
        let Some(frame) = frame else {
            return;
        };
        // Frames come in generation order; this guard only documents it.
        if self
            .shown
            .as_ref()
            .is_some_and(|s| frame.generation < s.generation)
        {
            return;
        }
        self.show_frame(ctx, frame);
    }

    pub(super) fn show_frame(&mut self, ctx: &egui::Context, frame: Frame) {
        // A black image the camera is to blame for says so (the controller asked, off this
        // thread); the note goes with the first view that sees something again.
        let cause = self.status.as_ref().and_then(|s| s.cause.as_ref());
        let noted = cause == Some(&Cause::CameraSeesNothing);
        // A panic's error goes with the first frame of a change made after it was shown.
        let failure_passed = matches!(cause, Some(Cause::RenderFailed { submitted })
            if frame.generation > *submitted);
        match &frame.camera_note {
            Some(text) => {
                self.status = Some(Status {
                    text: format!("The image is black: {text}"),
                    kind: StatusKind::Notice,
                    cause: Some(Cause::CameraSeesNothing),
                    details: None,
                });
            }
            None if noted || failure_passed => self.status = None,
            None => {}
        }
        let (w, h) = (frame.image.width, frame.image.height);
        self.viewport.set_image(ctx, w, h, &frame.rgba);
        if frame.generation >= self.submitted_generation
            && let Some((start, frames)) = self.change.take()
        {
            self.stats.change_to_image = Some((start.elapsed().as_secs_f64() * 1e3, frames));
        }
        self.stats.samples = frame.samples;
        self.stats.target = frame.target;
        self.stats.is_preview = frame.is_preview;
        self.stats.noise = frame.noise;
        self.stats.denoised = (frame.denoise && frame.denoised.is_some())
            .then_some((frame.denoised_samples, frame.denoise_ms));
        self.stats.denoised_error = frame
            .denoised_error
            .filter(|_| self.stats.denoised.is_some());
        self.stats.stochastic = frame.settings.is_stochastic();
        self.stats.elapsed_ms = frame.since_submit_ms;
        self.stats.legend = frame.legend.clone();
        if !frame.is_preview {
            self.stats.full_pass = Some((frame.pass_ms, w, h));
            self.stats.mrays_per_s = Some(frame.mrays_per_s);
        }
        let shown = Shown {
            generation: frame.generation,
            settings: frame.settings,
            image: frame.image,
            samples: frame.samples,
            target: frame.target,
            is_preview: frame.is_preview,
            display: frame.display,
            denoise: frame.denoise,
            denoised: frame
                .denoised
                .filter(|_| frame.denoise)
                .map(|d| (d, frame.denoised_samples)),
        };
        if !shown.is_preview {
            self.last_full = Some(shown.clone());
        }
        self.shown = Some(shown);
        if self.screenshot_wanted && self.current_full_frame().is_some() {
            self.screenshot_wanted = false;
            self.start_screenshot(ctx);
        }
    }

    /// The newest full-resolution frame, if it belongs to the current settings.
    pub(super) fn current_full_frame(&self) -> Option<&Shown> {
        self.last_full
            .as_ref()
            .filter(|f| f.generation >= self.submitted_generation)
    }
}
