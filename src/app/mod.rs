//! The workbench window: the render beside parameter panels, re-traced live.
//!
//! The app is thin. Panels ([`panels`]), keys and the mouse ([`input`], [`image_panel`]) edit one
//! [`RenderSettings`] value in [`WorkbenchState`]; actions come back as [`Command`]s, handled in
//! [`WorkbenchApp::handle`] ([`command`]). Once a frame, [`WorkbenchApp::sync_render`]
//! ([`render`]) — the one place a change becomes a render job — compares the settings with the
//! last submitted ones and hands any change to the [`Controller`], which renders on its own
//! threads. The UI thread only polls for finished frames and other background results (scenes
//! loaded, [`scenes`]; checks, screenshots, A/B) and never waits on them.
//!
//! This file holds the app's state and its frame; each concept it uses is a file of its own:
//! the status line ([`status`]), sample targets ([`sampled`]), the inspector ([`inspector`]).

mod check;
mod command;
mod compare;
mod equations;
mod files;
mod image_panel;
mod input;
mod inspector;
mod material_editor;
mod panels;
mod persistence;
mod render;
mod sampled;
mod scenes;
mod screenshot;
mod stats;
mod status;
#[cfg(test)]
mod tests;
mod viewport;

use std::io::Write as _;
use std::sync::Arc;
use std::sync::mpsc::Receiver;
use std::time::Instant;

use eframe::egui;
use raylab_core::RenderSettings;
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::transport::progressive::Controller;

pub use command::Command;
use inspector::{INSPECTOR_WIDTH, Inspected};
use persistence::WorkbenchState;
pub use render::{Shown, repaint_for_frames};
use sampled::Sampled;
use scenes::SceneLoad;
use stats::Stats;
pub use status::{Cause, Status, StatusKind};
use viewport::Viewport;

#[cfg(test)]
use inspector::same_spot;
#[cfg(test)]
use sampled::{PATH_SAMPLE_TARGET, SOFT_SAMPLE_TARGET};
#[cfg(test)]
use viewport::light_marker;

/// The window title (scripts find the window by it).
pub const TITLE: &str = "raylab";

/// The central panel's margins either side of the image, and the panels' separator.
const CENTRAL_MARGINS: f32 = 20.0;

pub struct WorkbenchApp {
    state: WorkbenchState,
    /// The loaded scene, and which choice it is.
    scene: Arc<Scene>,
    scene_choice: SceneChoice,
    /// A scene being built on a loader thread (a large one, as the terrain, takes a while).
    scene_loading: Option<SceneLoad>,
    controller: Option<Controller>,
    /// The settings of the newest job handed to the controller, and its generation.
    submitted: Option<RenderSettings>,
    submitted_generation: u64,
    viewport: Viewport,
    shown: Option<Shown>,
    /// The newest full-resolution frame (what a screenshot saves).
    last_full: Option<Shown>,
    stats: Stats,
    status: Option<Status>,
    show_help: bool,
    /// A screenshot was asked for before the full-resolution image was ready.
    screenshot_wanted: bool,
    screenshots_saving: Vec<Receiver<Result<screenshot::Saved, String>>>,
    /// The inspector's last result: the settings and pixel it is for.
    inspection: Option<(RenderSettings, [u32; 2], Result<Inspected, String>)>,
    /// The inspector's width as it opens ([`WorkbenchApp::make_room_for_inspector`]), and how
    /// often it was opened: each opening is a panel of its own id, which opens at that width
    /// (not at what the last one was dragged to).
    inspector_width: f32,
    inspector_opened: u32,
    /// What opening the inspector added to the window's width, and the width it made: given
    /// back on closing if the window still has it.
    inspector_grew: Option<(f32, f32)>,
    /// The central panel's width last frame, in points: the image and what it leaves.
    central_width: f32,
    /// While the light's marker is dragged: the light's depth when the drag started.
    dragging_light: Option<f32>,
    /// While a spot light's aim is dragged: the aim's depth when the drag started.
    dragging_aim: Option<f32>,
    /// When the newest job was submitted, and UI frames since.
    change: Option<(Instant, u32)>,
    log_frames: bool,
    started: Instant,
    /// Compare A/B: the frozen A and its renderer, while comparing ([`compare`]).
    compare: Option<compare::Compare>,
    /// Check my image: a student's render held against the exact figure ([`check`]).
    check: Option<check::StudentCheck>,
    /// Your equations: the student's own quantities rendered beside the exact figure
    /// ([`equations`]).
    equations: equations::YourEquations,
    /// The Open or Save scene dialog, while shown.
    file_dialog: Option<files::FileDialog>,
    /// Scenes loaded before, newest first, so switching back is instant (at most
    /// [`SCENE_CACHE`]).
    scene_cache: Vec<(SceneChoice, Arc<Scene>)>,
    /// The settings before a file was opened whose scene is still loading: put back if the
    /// scene cannot be loaded, so nothing is lost.
    restore_on_failure: Option<RenderSettings>,
    /// The scene of the saved state is the one loading (at start): if it cannot be loaded,
    /// the lab's box stays, and the notice says so.
    saved_scene_loading: bool,
    /// The effects in force that average random points ([`Sampled`]), as of the last frame:
    /// one turned on raises the sample target ([`WorkbenchApp::refine_sampled_effects`]).
    sampled: Sampled,
    /// The window's title as last sent: the figure or stage shown ([`window_title`]).
    window_title: String,
    /// Test hook: the next scene load panics on its thread.
    #[cfg(test)]
    inject_loader_panic: bool,
}

/// The window's title for `settings`: raylab, then the figure shown, or the stage when the
/// settings are not a lab figure's ([`panels::figure_heading`]).
pub fn window_title(settings: &RenderSettings) -> String {
    format!("{TITLE} — {}", panels::figure_heading(settings))
}

/// Opens the workbench window; returns when it is closed.
pub fn run() -> anyhow::Result<()> {
    // eframe reads its state file before the app starts, and would wait for ever on a FIFO:
    // one that is not a regular file of a sensible size is left alone.
    let (persistence_path, state_notice) =
        persistence::state_file(eframe::storage_dir(TITLE).as_deref());
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(TITLE)
            .with_app_id(TITLE)
            .with_inner_size([1180.0, 760.0])
            .with_min_inner_size([480.0, 320.0]),
        persistence_path,
        // `main` runs the program on a thread of its own, with a stack raylab sets: winit is
        // told the window's event loop may run there.
        #[cfg(target_os = "linux")]
        event_loop_builder: Some(Box::new(|builder| {
            use winit::platform::wayland::EventLoopBuilderExtWayland;
            use winit::platform::x11::EventLoopBuilderExtX11;
            EventLoopBuilderExtX11::with_any_thread(builder, true);
            EventLoopBuilderExtWayland::with_any_thread(builder, true);
        })),
        ..Default::default()
    };
    eframe::run_native(
        TITLE,
        options,
        Box::new(move |cc| {
            let mut app = WorkbenchApp::new(cc);
            if let Some(notice) = state_notice {
                app.set_status(StatusKind::Notice, notice);
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| {
        anyhow::anyhow!(
            "could not open the workbench window: {e}\n\
             (no display? run it under Xvfb: `xvfb-run -a raylab`, or use `raylab render --out image.png`)"
        )
    })
}

impl WorkbenchApp {
    pub fn new(cc: &eframe::CreationContext<'_>) -> Self {
        let (state, notice) = persistence::load(cc.storage);
        Self::with_state(&cc.egui_ctx, state, notice)
    }

    fn with_state(ctx: &egui::Context, state: WorkbenchState, notice: Option<String>) -> Self {
        let saved_scene = state.settings.scene != SceneChoice::Cornell;
        // The saved settings' sample target is the user's: only an effect turned on later
        // raises it.
        let sampled = Sampled::of(&state.settings);
        let (controller, error) =
            match Controller::new(state.render_threads, repaint_for_frames(ctx)) {
                Ok(c) => (Some(c), None),
                Err(e) => (None, Some(format!("The renderer could not start: {e}"))),
            };
        let status = match (error, notice) {
            (Some(text), _) => Some(Status {
                text,
                kind: StatusKind::Error,
                cause: None,
                details: None,
            }),
            (None, Some(text)) => Some(Status {
                text,
                kind: StatusKind::Notice,
                cause: None,
                details: None,
            }),
            (None, None) => None,
        };
        Self {
            state,
            scene: Arc::new(cornell_box()),
            scene_choice: SceneChoice::Cornell,
            scene_loading: None,
            controller,
            submitted: None,
            submitted_generation: 0,
            viewport: Viewport::default(),
            shown: None,
            last_full: None,
            stats: Stats::default(),
            status,
            show_help: false,
            screenshot_wanted: false,
            screenshots_saving: Vec::new(),
            dragging_light: None,
            dragging_aim: None,
            inspection: None,
            inspector_width: INSPECTOR_WIDTH,
            inspector_opened: 0,
            inspector_grew: None,
            central_width: 0.0,
            change: None,
            log_frames: std::env::var_os("RAYLAB_LOG_FRAMES").is_some(),
            started: Instant::now(),
            compare: None,
            check: None,
            equations: equations::YourEquations::default(),
            file_dialog: None,
            scene_cache: Vec::new(),
            restore_on_failure: None,
            saved_scene_loading: saved_scene,
            sampled,
            window_title: TITLE.to_owned(),
            #[cfg(test)]
            inject_loader_panic: false,
        }
    }

    /// Whether the newest job has reached its target on screen, shown with the display in
    /// force, and nothing else is pending.
    #[cfg(test)]
    pub fn is_settled(&self) -> bool {
        let generation = self.controller.as_ref().map_or(0, Controller::generation);
        let display = self.controller.as_ref().map(Controller::display);
        let denoise = self.controller.as_ref().map(Controller::denoise);
        self.submitted
            .as_ref()
            .is_some_and(|s| s.renders_like(&self.state.settings))
            && self.shown.as_ref().is_some_and(|s| {
                s.generation == generation
                    && s.is_final()
                    && display.is_none_or(|d| d == s.display)
                    && denoise.is_none_or(|d| d == s.denoise)
            })
            && !self.screenshot_wanted
            && self.screenshots_saving.is_empty()
            && self.scene_loading.is_none()
            && self
                .compare
                .as_ref()
                .is_none_or(compare::Compare::is_settled)
            && self
                .check
                .as_ref()
                .is_none_or(|c| c.is_settled(&self.state.settings))
            && self.equations.is_settled(&self.state.settings)
    }
}

impl eframe::App for WorkbenchApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let start = Instant::now();
        let ctx = ui.ctx().clone();
        // Frames since the last change, this one included.
        if let Some((_, frames)) = &mut self.change {
            *frames += 1;
        }
        self.receive_scene();
        self.receive_frames(&ctx);
        self.receive_compare(&ctx);
        self.receive_check(&ctx);
        let scene_ready = self.state.settings.scene == self.scene_choice;
        self.equations
            .update(&ctx, &self.state.settings, &self.scene, scene_ready);
        self.receive_screenshots();
        self.clear_fixed_error();

        let mut commands = input::keys(&ctx, &mut self.state.settings);

        egui::Panel::bottom("status").show(ui, |ui| self.status_ui(ui));
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                let loading = self.scene_loading.as_ref().map(|l| &l.choice);
                commands.extend(panels::controls_ui(
                    ui,
                    &mut self.state,
                    &self.stats,
                    loading,
                    self.compare.as_mut(),
                    self.check.as_mut(),
                    &mut self.equations,
                ));
            });
        if self.state.inspect_mode {
            self.inspector_panel(ui);
        }
        egui::CentralPanel::default_margins().show(ui, |ui| self.image_ui(ui));
        match panels::take_typed() {
            Some(panels::Typed::Problem { field, message }) => {
                self.set_status_while(StatusKind::Notice, Cause::TypedNumber(field), message);
            }
            Some(panels::Typed::Fine { field }) => {
                let stale = self
                    .status
                    .as_ref()
                    .is_some_and(|s| s.cause == Some(Cause::TypedNumber(field.clone())));
                if stale {
                    self.status = None;
                }
            }
            None => {}
        }
        for command in commands {
            self.handle(command, &ctx);
        }
        self.refine_sampled_effects();
        self.receive_dropped_files(&ctx);
        self.file_dialog_ui(&ctx);
        self.help_ui(&ctx);
        self.sync_scene(&ctx);
        self.sync_render();
        let title = window_title(&self.state.settings);
        if title != self.window_title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.window_title = title;
        }

        self.stats.ui_frame_ms = start.elapsed().as_secs_f64() * 1e3;
        self.stats.frame_cpu_ms = frame.info().cpu_usage.map(|s| f64::from(s) * 1e3);
        if self.log_frames {
            let since_start_ms = self.started.elapsed().as_secs_f64() * 1e3;
            let _ = writeln!(
                std::io::stderr(),
                "{}",
                self.stats.frame_log_line(since_start_ms)
            );
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        persistence::save(storage, &self.state);
    }

    /// Saved on close, and every few seconds in case the app is killed instead.
    fn auto_save_interval(&self) -> std::time::Duration {
        std::time::Duration::from_secs(5)
    }
}
