//! The workbench window: the render beside parameter panels, re-traced live.
//!
//! The app is thin. Panels ([`panels`]), keys and the mouse ([`input`]) edit one
//! [`RenderSettings`] value in [`WorkbenchState`]; actions come back as [`Command`]s, handled in
//! [`WorkbenchApp::handle`]. Once a frame, [`WorkbenchApp::sync_render`] — the one place a
//! change becomes a render job — compares the settings with the last submitted ones and hands
//! any change to the [`Controller`], which renders on its own threads. The UI thread only polls
//! for finished frames and never waits on the renderer.

mod check;
mod compare;
mod equations;
mod files;
mod input;
mod material_editor;
mod panels;
mod persistence;
mod screenshot;
mod stats;
#[cfg(test)]
mod tests;
mod viewport;

use std::io::Write as _;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::Instant;

use eframe::egui;
use raylab_core::shading::light::LightKind;
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::transport::progressive::{Controller, Frame, WorkerError, catch_panic};
use raylab_core::{Camera, Image, RenderSettings, Shading, Stage};

use persistence::WorkbenchState;
use stats::Stats;
use viewport::Viewport;

/// The window title (scripts find the window by it).
pub const TITLE: &str = "raylab";

/// The least sample target the path stage gets when chosen: a path-traced image is noisy
/// until about this many samples are averaged.
pub const PATH_SAMPLE_TARGET: u32 = 1024;

/// The least sample target the lab stages get when soft shadows or depth of field are turned
/// on: both are averages over random points (of the light, of the lens), grainy at the 16
/// samples that anti-alias the lab's image.
pub const SOFT_SAMPLE_TARGET: u32 = 256;

/// A UI action, handled in one place ([`WorkbenchApp::handle`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    ResetCamera,
    LookAtBoxCentre,
    /// Switch stage, with the shadows and indirect switches its figure uses.
    SetStage(Stage),
    /// Switch to a stage with these switches: the one Check found the image to be.
    SetStageSwitches(raylab_core::teaching::check::StageSwitches),
    ResetToLabDefaults,
    SaveScreenshot,
    ToggleHelp,
    /// Go to step `n` of the lab walk-through (`None`: leave it).
    WalkTo(Option<usize>),
    /// Inspect pixels on or off.
    ToggleInspector,
    /// Move the inspected pixel by (dx, dy).
    MovePinned([i32; 2]),
    /// Compare A/B: freeze the current settings and scene as A ([`compare`]).
    FreezeA,
    /// Open the file whose path is typed in the File field.
    OpenTyped,
    /// Save the setup as a scene file at the path typed in the File field.
    SaveSceneTyped,
    /// Show the Open dialog (Ctrl+O), or the one for screenshots.
    ShowOpenDialog,
    ShowScreenshotDialog,
    /// Show the Save scene dialog (Ctrl+Shift+S).
    ShowSaveSceneDialog,
    /// Give up loading a scene: the scene on screen stays.
    CancelLoading,
    /// Compare A/B: drop A and its renderer.
    StopComparing,
    /// Check my image: show the dialog for a student's render ([`check`]).
    ShowCheckDialog,
    /// Check the image whose path is typed in the File field.
    CheckTyped,
    /// Stop checking: back to the live image.
    StopChecking,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StatusKind {
    Info,
    Notice,
    Error,
}

/// The status line at the bottom of the window.
#[derive(Clone, Debug)]
pub struct Status {
    pub text: String,
    pub kind: StatusKind,
    /// For an error whose condition can go away: what to check, so the message goes when the
    /// condition does.
    pub cause: Option<Cause>,
    /// More than fits on the line, offered by a "Copy details" button: for a render that
    /// panicked, its settings as JSON, to reproduce it with `raylab render --settings FILE`.
    pub details: Option<String>,
}

/// A condition a message reports, checked every frame ([`WorkbenchApp::clear_fixed_error`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Cause {
    /// Compare A/B is on (what to do while comparing): taken down when comparing stops.
    Comparing,
    /// Check my image is on (reading the image, what to set while checking): taken down when
    /// the check stops.
    Checking,
    /// The text typed into the number field of this name could not be used as it stood:
    /// taken down when a good number is typed there ([`panels::Typed`]).
    TypedNumber(String),
    /// The settings could not be rendered.
    InvalidSettings,
    /// The screenshot folder did not exist.
    MissingFolder(std::path::PathBuf),
    /// The camera sees nothing (a notice, taken down by the next render that sees something).
    CameraSeesNothing,
    /// A render job panicked. Taken down by the first frame of a job submitted after the error
    /// reached the screen (a generation above `submitted`, the newest then): a change made once
    /// the user could read it. Frames of jobs already on their way then don't hide it at once.
    RenderFailed { submitted: u64 },
}

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
    fn is_final(&self) -> bool {
        !self.is_preview && self.samples >= self.target
    }
}

pub struct WorkbenchApp {
    state: WorkbenchState,
    /// The loaded scene, and which choice it is.
    scene: Arc<Scene>,
    scene_choice: SceneChoice,
    /// A scene being built on a loader thread (the terrain takes about half a second).
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

/// The lab stages' effects that average random points, and so need many samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Sampled {
    /// Shadows from an area light: each sample's shadow ray goes to a random point of it.
    soft_shadows: bool,
    /// A lens of some aperture: each sample's ray leaves from a random point of it.
    depth_of_field: bool,
}

impl Sampled {
    /// Those `settings` use. The path stage samples everything anyway, at its own target
    /// ([`PATH_SAMPLE_TARGET`]); the flat stage computes no light.
    fn of(settings: &RenderSettings) -> Self {
        let stage = settings.shading.stage;
        if stage == Stage::Path {
            return Self::default();
        }
        Self {
            soft_shadows: stage != Stage::Flat
                && settings.shading.shadows
                && settings.light.is_area(),
            depth_of_field: settings.camera.aperture > 0.0,
        }
    }

    /// What the user calls them, those of `self` that are on.
    fn name(self) -> Option<&'static str> {
        match (self.soft_shadows, self.depth_of_field) {
            (true, true) => Some("Soft shadows and depth of field"),
            (true, false) => Some("Soft shadows"),
            (false, true) => Some("Depth of field"),
            (false, false) => None,
        }
    }
}

/// The inspector panel's width when there is room (an equation's line then wraps over two or
/// three rows), the least it opens at when the window cannot make that room (the image gives
/// up the rest), and the least it can be dragged to.
const INSPECTOR_WIDTH: f32 = 520.0;
const INSPECTOR_OPEN_MIN_WIDTH: f32 = 320.0;
const INSPECTOR_MIN_WIDTH: f32 = 200.0;

/// The central panel's margins either side of the image, and the panels' separator.
const CENTRAL_MARGINS: f32 = 20.0;

/// The render worker's notify: one repaint for each frame it publishes. egui's
/// `request_repaint` runs two UI frames for each request (to let layout settle); the second
/// one redraws the same picture, and under a software renderer each UI frame takes CPU from
/// the render threads. A request with a delay runs one; a millisecond is not seen.
fn repaint_for_frames(ctx: &egui::Context) -> raylab_core::transport::progressive::Notify {
    let ctx = ctx.clone();
    Box::new(move || ctx.request_repaint_after(std::time::Duration::from_millis(1)))
}

/// The window's title for `settings`: raylab, then the figure shown, or the stage when the
/// settings are not a lab figure's ([`panels::figure_heading`]).
pub fn window_title(settings: &RenderSettings) -> String {
    format!("{TITLE} — {}", panels::figure_heading(settings))
}

/// How many scenes besides the one on screen stay loaded for switching back.
pub const SCENE_CACHE: usize = 4;

/// A scene being loaded off the UI thread.
struct SceneLoad {
    choice: SceneChoice,
    started: Instant,
    result: Receiver<Result<(Scene, Vec<String>), String>>,
    /// What the loader is doing, for the status line.
    progress: Arc<std::sync::Mutex<String>>,
    /// Set by Cancel: the loader stops at its next step.
    cancel: Arc<std::sync::atomic::AtomicBool>,
}

/// An inspection as the inspector panel shows it: its lines, and the same as text to copy.
struct Inspected {
    inspection: raylab_core::teaching::inspect::Inspection,
    lines: Vec<raylab_core::teaching::inspect::InspectLine>,
}

/// Where the light appears in the image, as a fraction of its width and height, or `None` when
/// it is behind the camera (the viewport also hides it off the image).
pub fn light_marker(settings: &RenderSettings) -> Option<egui::Vec2> {
    let camera = &settings.camera;
    let (px, py, _) = camera.project(settings.light.position)?;
    Some(egui::vec2(
        px / camera.width as f32,
        py / camera.height as f32,
    ))
}

/// A spot light's cone where the camera sees it ([`viewport::SpotMarker`]): its aim, and 24
/// points of the circle of the cutoff's radius about the aim, square to the spot's axis (each
/// left out when behind the camera); `None` for the other lights.
pub fn spot_marker(settings: &RenderSettings) -> Option<viewport::SpotMarker> {
    let LightKind::Spot(cone) = settings.light.kind else {
        return None;
    };
    let camera = &settings.camera;
    let fraction = |p| {
        let (px, py, _) = camera.project(p)?;
        Some(egui::vec2(
            px / camera.width as f32,
            py / camera.height as f32,
        ))
    };
    let to_aim = cone.aim - settings.light.position;
    let axis = to_aim.normalize_or_zero();
    let radius = to_aim.length() * cone.cutoff.tan();
    let (t1, t2) = raylab_core::base::sampling::orthonormal_basis(axis);
    let rim = (0..24)
        .filter_map(|k| {
            let a = k as f32 * std::f32::consts::TAU / 24.0;
            fraction(cone.aim + radius * (a.cos() * t1 + a.sin() * t2))
        })
        .collect();
    Some(viewport::SpotMarker {
        aim: fraction(cone.aim),
        rim,
    })
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

    fn set_status(&mut self, kind: StatusKind, text: impl Into<String>) {
        self.status = Some(Status {
            text: text.into(),
            kind,
            cause: None,
            details: None,
        });
    }

    /// A message that goes away by itself once `cause` no longer holds.
    fn set_status_while(&mut self, kind: StatusKind, cause: Cause, text: impl Into<String>) {
        self.status = Some(Status {
            text: text.into(),
            kind,
            cause: Some(cause),
            details: None,
        });
    }

    /// An error that goes away by itself once `cause` no longer holds.
    fn set_error(&mut self, cause: Cause, text: impl Into<String>) {
        self.status = Some(Status {
            text: text.into(),
            kind: StatusKind::Error,
            cause: Some(cause),
            details: None,
        });
    }

    /// A problem a render thread reported (`prefix` says whose: "" for the live image, "A: "
    /// for the frozen side), with the failed job's settings to copy. The live image's panic
    /// goes once a later change renders ([`Cause::RenderFailed`]); A is never re-rendered, so
    /// its error stays until another message replaces it.
    fn show_worker_error(&mut self, prefix: &str, error: WorkerError, cause: Option<Cause>) {
        self.status = Some(Status {
            text: format!("{prefix}{}", error.message),
            kind: StatusKind::Error,
            details: error.settings_json(),
            cause: cause.filter(|_| error.settings.is_some()),
        });
    }

    /// Takes down a message whose condition is fixed: a stale red line would send the user
    /// looking for a problem that is gone, and stale advice would ask for the impossible.
    fn clear_fixed_error(&mut self) {
        let fixed = match self.status.as_ref().and_then(|s| s.cause.as_ref()) {
            Some(Cause::InvalidSettings) => self.state.settings.validate().is_ok(),
            Some(Cause::Comparing) => self.compare.is_none(),
            Some(Cause::Checking) => self.check.is_none(),
            Some(Cause::TypedNumber(_)) => false,
            Some(Cause::MissingFolder(_)) => self.state.screenshot_folder.is_dir(),
            Some(Cause::CameraSeesNothing | Cause::RenderFailed { .. }) => false,
            None => false,
        };
        if fixed {
            self.status = None;
        }
    }

    /// Starts loading the scene the settings ask for, unless it is loaded, kept from before
    /// (then it is swapped in at once), or on its way.
    fn sync_scene(&mut self, ctx: &egui::Context) {
        let wanted = &self.state.settings.scene;
        if *wanted == self.scene_choice
            || self
                .scene_loading
                .as_ref()
                .is_some_and(|l| l.choice == *wanted)
        {
            return;
        }
        if let Some(i) = self.scene_cache.iter().position(|(c, _)| c == wanted) {
            let (choice, scene) = self.scene_cache.remove(i);
            if let Some(load) = self.scene_loading.take() {
                load.cancel.store(true, std::sync::atomic::Ordering::SeqCst);
            }
            self.set_status(
                StatusKind::Info,
                format!(
                    "Switched to the {choice} scene ({} triangles, kept loaded)",
                    scene.triangles.len()
                ),
            );
            self.swap_in_scene(choice, scene);
            return;
        }
        if self.scene_loading.is_some() {
            // One load at a time: the wanted scene starts when the running load ends.
            return;
        }
        let choice = wanted.clone();
        let (sender, receiver) = mpsc::channel();
        let repaint = ctx.clone();
        let job = choice.clone();
        let progress = Arc::new(std::sync::Mutex::new(String::from("starting")));
        let cancel = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (job_progress, job_cancel) = (Arc::clone(&progress), Arc::clone(&cancel));
        #[cfg(test)]
        let inject_panic = std::mem::take(&mut self.inject_loader_panic);
        let spawned = std::thread::Builder::new()
            .name("raylab-scene-loader".to_owned())
            .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
            .spawn(move || {
                let cancelled = || job_cancel.load(std::sync::atomic::Ordering::SeqCst);
                let report = |what: &str| {
                    if let Ok(mut p) = job_progress.lock() {
                        *p = what.to_owned();
                    }
                    repaint.request_repaint();
                };
                // A panic while building the scene (a bug, or a model the loader chokes on)
                // becomes the status line's error, and the scene on screen stays.
                let result = catch_panic(|| {
                    #[cfg(test)]
                    if inject_panic {
                        panic!("injected loader panic");
                    }
                    job.load_with(&cancelled, &report)
                })
                .map_err(|panic| format!("Loading the {job} scene panicked: {panic}"))
                .and_then(|loaded| loaded.map_err(|e| e.to_string()));
                let _ = sender.send(result);
                repaint.request_repaint();
            });
        match spawned {
            Ok(_) => {
                self.set_status(StatusKind::Info, format!("Loading the {choice} scene..."));
                self.scene_loading = Some(SceneLoad {
                    choice,
                    started: Instant::now(),
                    result: receiver,
                    progress,
                    cancel,
                });
            }
            Err(e) => {
                self.state.settings.scene = self.scene_choice.clone();
                self.set_status(StatusKind::Error, format!("Could not load {choice}: {e}"));
            }
        }
    }

    /// Puts `scene` on screen, keeping the one it replaces for switching back.
    fn swap_in_scene(&mut self, choice: SceneChoice, scene: Arc<Scene>) {
        let old_choice = std::mem::replace(&mut self.scene_choice, choice);
        let old_scene = std::mem::replace(&mut self.scene, scene);
        self.scene_cache.retain(|(c, _)| *c != old_choice);
        self.scene_cache.insert(0, (old_choice, old_scene));
        self.scene_cache.truncate(SCENE_CACHE);
        self.restore_on_failure = None;
        // Render the new scene even if nothing else changed.
        self.submitted = None;
    }

    /// The status line while a scene loads: what the loader is doing, and for how long.
    fn loading_status(&mut self) {
        let Some(load) = &self.scene_loading else {
            return;
        };
        let doing = load.progress.lock().map(|p| p.clone()).unwrap_or_default();
        let text = format!(
            "Loading the {} scene: {doing}... {:.1} s (Cancel keeps the scene on screen)",
            load.choice,
            load.started.elapsed().as_secs_f64()
        );
        self.set_status(StatusKind::Info, text);
    }

    /// Cancel: the load stops at its next step; the scene and settings on screen stay.
    fn cancel_loading(&mut self) {
        let Some(load) = self.scene_loading.take() else {
            return;
        };
        load.cancel.store(true, std::sync::atomic::Ordering::SeqCst);
        self.put_back_settings(&load.choice);
        self.set_status(
            StatusKind::Info,
            format!("Loading the {} scene was cancelled", load.choice),
        );
    }

    /// After a load that did not finish: the settings from before the file was opened, or at
    /// least the scene on screen.
    fn put_back_settings(&mut self, failed: &SceneChoice) {
        if let Some(old) = self.restore_on_failure.take() {
            self.state.settings = old;
            self.sampled = Sampled::of(&self.state.settings);
        } else if self.state.settings.scene == *failed {
            self.state.settings.scene = self.scene_choice.clone();
        }
    }

    /// Takes a finished scene load: the new scene, or an error that puts the old one back.
    fn receive_scene(&mut self) {
        let Some(load) = &self.scene_loading else {
            return;
        };
        let result = match load.result.try_recv() {
            Ok(result) => result,
            Err(TryRecvError::Empty) => {
                self.loading_status();
                return;
            }
            Err(TryRecvError::Disconnected) => Err("the loader thread stopped".to_owned()),
        };
        let Some(load) = self.scene_loading.take() else {
            return;
        };
        let saved = std::mem::take(&mut self.saved_scene_loading);
        match result {
            Ok((scene, warnings)) => {
                let ms = load.started.elapsed().as_secs_f64() * 1e3;
                let mut text = format!(
                    "Loaded the {} scene: {} triangles in {ms:.0} ms",
                    load.choice,
                    scene.triangles.len()
                );
                let kind = if warnings.is_empty() {
                    StatusKind::Info
                } else {
                    text += &format!(" ({})", warnings.join("; "));
                    StatusKind::Notice
                };
                self.set_status(kind, text);
                self.swap_in_scene(load.choice, Arc::new(scene));
            }
            Err(e) if saved => {
                // The saved state's scene (a model since moved, or one too large for this
                // machine): the window starts on the lab's box all the same.
                self.put_back_settings(&load.choice);
                self.set_status(
                    StatusKind::Notice,
                    format!(
                        "The saved scene could not be loaded ({e}); showing the {} scene",
                        self.scene_choice
                    ),
                );
            }
            Err(e) => {
                // Nothing is lost: the scene on screen stays, and so do its settings.
                self.put_back_settings(&load.choice);
                self.set_status(StatusKind::Error, e);
            }
        }
    }

    /// Opens a scene file, a screenshot (PNG or JSON) or an OBJ model: from the File field,
    /// the dialog or a drop on the window. A file that cannot be used changes nothing.
    fn open_path(&mut self, path: &std::path::Path, ctx: &egui::Context) {
        self.state.obj_path = path.display().to_string();
        match files::open(path) {
            Ok(files::Opened::StudentImage(image)) => self.start_check(ctx, image),
            Ok(files::Opened::Model(model)) => {
                self.state.settings.scene = SceneChoice::Obj(model);
            }
            Ok(files::Opened::Settings(mut loaded)) => {
                // A denoised image's settings turn the Denoise switch on (the switch is the
                // window's own, not among the settings it traces with).
                if std::mem::take(&mut loaded.settings.denoise) {
                    self.state.denoise = true;
                }
                // The equations go to the Your equations panel (the live render is the lab's).
                self.equations
                    .load(&std::mem::take(&mut loaded.settings.equations));
                let old = std::mem::replace(&mut self.state.settings, loaded.settings);
                if self.state.settings.scene != self.scene_choice {
                    self.restore_on_failure = Some(old);
                }
                self.state.walk_step = None;
                self.state.walk_restore = None;
                // The file's sample target is its own: not raised.
                self.sampled = Sampled::of(&self.state.settings);
                let name = path.file_name().map_or_else(
                    || path.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                );
                if loaded.warnings.is_empty() {
                    self.set_status(StatusKind::Info, format!("Opened {name}"));
                } else {
                    self.set_status(
                        StatusKind::Notice,
                        format!("Opened {name}: {}", loaded.warnings.join("; ")),
                    );
                }
            }
            Err(e) => self.set_status(StatusKind::Error, e),
        }
    }

    /// Saves the scene file at `path`; a file there is replaced only when `replace` (the Save
    /// dialog asked), otherwise the scene goes to the next free name, as the status says.
    fn save_scene_to(&mut self, path: &std::path::Path, replace: bool) {
        // The scene file carries the student's equations.
        let mut settings = self.state.settings.clone();
        settings.equations = self.equations.carried();
        match files::save_scene(&settings, path, replace) {
            Ok(written) => {
                self.state.obj_path = written.display().to_string();
                self.set_status(
                    StatusKind::Info,
                    format!("Saved the scene file {}", written.display()),
                );
            }
            Err(e) => self.set_status(StatusKind::Error, e),
        }
    }

    /// The dialog's folder: the typed path's, else the screenshot folder. Its name field starts
    /// empty (the Save dialog's suggests a name): the typed file's name there would be chosen
    /// by a press of Enter, though the user came to the dialog to pick another.
    fn dialog_folder(&self) -> std::path::PathBuf {
        let typed = std::path::Path::new(self.state.obj_path.trim());
        match typed.parent() {
            Some(dir) if typed.file_name().is_some() && dir.is_dir() => dir.to_path_buf(),
            _ => self.state.screenshot_folder.clone(),
        }
    }

    fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.file_dialog else {
            return;
        };
        let mode = dialog.mode;
        match dialog.ui(ctx) {
            files::DialogOutcome::Open => {}
            files::DialogOutcome::Cancelled => self.file_dialog = None,
            files::DialogOutcome::Chosen(path) => {
                self.file_dialog = None;
                if mode == files::DialogMode::SaveScene {
                    self.save_scene_to(&path, false);
                } else if mode == files::DialogMode::CheckImage {
                    self.start_check(ctx, path);
                } else {
                    self.open_path(&path, ctx);
                }
            }
            files::DialogOutcome::Replace(path) => {
                self.file_dialog = None;
                self.save_scene_to(&path, true);
            }
        }
    }

    /// Files dropped on the window are opened (the last, if several).
    fn receive_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(file) = dropped.last() {
            let path = file.path().to_path_buf();
            self.open_path(&path, ctx);
        }
    }

    /// The one place that turns a settings change into a render job.
    fn sync_render(&mut self) {
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

    /// A drag that starts on the light's marker moves the light in the image plane, at the
    /// depth it had when the drag started; one that starts on a spot light's aim moves the aim
    /// so (turning the spot); any other drag turns the camera.
    fn drag_light_or_camera(&mut self, pointer: &viewport::ViewportInput) {
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

    /// Inspect mode: pins the clicked pixel (`at`: a fraction of the image's width and height).
    fn pin_at(&mut self, at: egui::Vec2) {
        let camera = &self.state.settings.camera;
        let x = ((at.x * camera.width as f32) as u32).min(camera.width - 1);
        let y = ((at.y * camera.height as f32) as u32).min(camera.height - 1);
        self.state.pinned = Some([x, y]);
    }

    /// The pinned pixel's lines with the settings in force, recomputed only when either
    /// changes (one ray's worth of work, recorded step by step), not every UI frame.
    fn inspection(&mut self) -> Option<&Result<Inspected, String>> {
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
    fn make_room_for_inspector(&mut self, ctx: &egui::Context) {
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
    fn give_back_inspector_room(&mut self, ctx: &egui::Context) {
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
    fn shown_pixel(&self, [x, y]: [u32; 2]) -> Option<raylab_core::teaching::inspect::ShownPixel> {
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
    fn inspector_ui(&mut self, ui: &mut egui::Ui) {
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

    /// "Click to focus": sets the focus distance to the depth of what the clicked point of the
    /// image shows (`at`: a fraction of the image's width and height).
    fn focus_at(&mut self, at: egui::Vec2) {
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

    /// Takes the newest finished frame, if any, and shows it.
    fn receive_frames(&mut self, ctx: &egui::Context) {
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

    fn show_frame(&mut self, ctx: &egui::Context, frame: Frame) {
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
    fn current_full_frame(&self) -> Option<&Shown> {
        self.last_full
            .as_ref()
            .filter(|f| f.generation >= self.submitted_generation)
    }

    fn handle(&mut self, command: Command, ctx: &egui::Context) {
        let settings = &mut self.state.settings;
        match command {
            Command::ResetCamera => {
                settings.camera =
                    Camera::default_for(settings.camera.width, settings.camera.height);
            }
            Command::LookAtBoxCentre => settings.camera.look_at(glam::Vec3::ZERO),
            Command::SetStage(stage) => {
                // The figure's switches; N, the bounces and the specular depth stay as set.
                let old = settings.shading;
                settings.shading = Shading {
                    indirect_light: old.indirect_light,
                    bounces: old.bounces,
                    specular_depth: old.specular_depth,
                    caustics: old.caustics,
                    photons: old.photons,
                    ..Shading::for_stage(stage)
                };
                if stage == Stage::Path && settings.samples_per_pixel < PATH_SAMPLE_TARGET {
                    let from = settings.samples_per_pixel;
                    settings.samples_per_pixel = PATH_SAMPLE_TARGET;
                    self.set_status(
                        StatusKind::Info,
                        format!(
                            "Path tracing: sample target raised from {from} to \
                             {PATH_SAMPLE_TARGET} so the image converges (noise: see Stats)"
                        ),
                    );
                }
            }
            Command::SetStageSwitches(switches) => {
                settings.shading = switches.shading(&settings.shading);
                self.set_status(
                    StatusKind::Info,
                    format!(
                        "Switched to {}: {}",
                        switches.name(),
                        switches.stage.label()
                    ),
                );
            }
            Command::ResetToLabDefaults => {
                let scene_before = settings.scene.clone();
                *settings = persistence::lab_defaults();
                // A click on the image turns the camera again, as in the lab.
                self.state.focus_mode = false;
                if scene_before != self.state.settings.scene {
                    // The lab's box comes from no file.
                    self.state.obj_path.clear();
                }
                self.set_status(StatusKind::Info, "Reset to the lab's defaults (figure 7)");
            }
            Command::SaveScreenshot => {
                // Make sure a change made this very frame is rendered first.
                self.sync_render();
                if self.current_full_frame().is_some() {
                    self.start_screenshot(ctx);
                } else {
                    self.screenshot_wanted = true;
                    self.set_status(
                        StatusKind::Info,
                        "Saving the screenshot when the full-resolution image is ready...",
                    );
                }
            }
            Command::ToggleHelp => self.show_help = !self.show_help,
            Command::ToggleInspector => {
                self.state.inspect_mode = !self.state.inspect_mode;
                if self.state.inspect_mode {
                    self.state.focus_mode = false;
                    self.make_room_for_inspector(ctx);
                } else {
                    self.give_back_inspector_room(ctx);
                }
            }
            Command::MovePinned([dx, dy]) => {
                if let Some([x, y]) = self.state.pinned {
                    let camera = &self.state.settings.camera;
                    let x = (i64::from(x) + i64::from(dx)).clamp(0, i64::from(camera.width) - 1);
                    let y = (i64::from(y) + i64::from(dy)).clamp(0, i64::from(camera.height) - 1);
                    self.state.pinned = Some([x as u32, y as u32]);
                }
            }
            Command::WalkTo(step) => {
                let step = step.filter(|&n| n < raylab_core::teaching::walkthrough::STEPS.len());
                if self.state.walk_step.is_none() && step.is_some() {
                    // Starting: what the steps will change, to put back on leaving.
                    self.state.walk_restore = Some(self.state.settings.clone());
                }
                self.state.walk_step = step;
                match step {
                    Some(n) => {
                        let s = &raylab_core::teaching::walkthrough::STEPS[n];
                        s.apply(&mut self.state.settings);
                        // The status line follows the step: a message from before the walk (a
                        // reset, a save) no longer describes what is shown. An error stays.
                        if self
                            .status
                            .as_ref()
                            .is_none_or(|s| s.kind != StatusKind::Error)
                        {
                            let of = raylab_core::teaching::walkthrough::STEPS.len();
                            self.set_status(
                                StatusKind::Info,
                                format!("Walk-through, step {} of {of}: {}", n + 1, s.title),
                            );
                        }
                    }
                    None => {
                        if let Some(before) = self.state.walk_restore.take() {
                            raylab_core::teaching::walkthrough::restore(
                                &before,
                                &mut self.state.settings,
                            );
                            self.set_status(
                                StatusKind::Info,
                                "Left the walk-through: your stage, materials and samples are \
                                 back as they were",
                            );
                        }
                    }
                }
                // A step's sample target, or the user's put back, is chosen: not raised.
                self.sampled = Sampled::of(&self.state.settings);
            }
            Command::FreezeA => {
                // One overlay at a time: A/B or the check.
                self.check = None;
                self.freeze_a(ctx);
            }
            Command::StopComparing => {
                self.compare = None;
                // What to do while comparing goes with it.
                self.clear_fixed_error();
            }
            Command::OpenTyped => {
                let typed = self.state.obj_path.trim().to_owned();
                if typed.is_empty() {
                    self.set_status(StatusKind::Notice, "Type a file's path to open it");
                } else if self.check.is_some() && files::is_image(std::path::Path::new(&typed)) {
                    // While checking, an image typed is the next one to check: a screenshot's
                    // settings are never loaded under a check, which would change what the
                    // image on screen is held against.
                    self.start_check(ctx, typed.into());
                } else {
                    self.open_path(std::path::Path::new(&typed), ctx);
                }
            }
            Command::SaveSceneTyped => {
                let typed = self.state.obj_path.trim().to_owned();
                if typed.is_empty() {
                    self.set_status(StatusKind::Notice, "Type a path ending in .toml to save to");
                } else {
                    self.save_scene_to(std::path::Path::new(&typed), false);
                }
            }
            Command::ShowOpenDialog | Command::ShowScreenshotDialog => {
                let mode = if command == Command::ShowOpenDialog {
                    files::DialogMode::Open
                } else {
                    files::DialogMode::OpenScreenshot
                };
                let folder = if mode == files::DialogMode::OpenScreenshot {
                    self.state.screenshot_folder.clone()
                } else {
                    self.dialog_folder()
                };
                self.file_dialog = Some(files::FileDialog::new(mode, &folder, ""));
            }
            Command::ShowSaveSceneDialog => {
                let folder = self.dialog_folder();
                let name = format!("{}.toml", self.scene_choice.name().replace(' ', "-"));
                let dialog = files::FileDialog::new(files::DialogMode::SaveScene, &folder, &name);
                self.file_dialog = Some(dialog);
            }
            Command::CancelLoading => self.cancel_loading(),
            Command::ShowCheckDialog => {
                let folder = self.dialog_folder();
                self.file_dialog = Some(files::FileDialog::new(
                    files::DialogMode::CheckImage,
                    &folder,
                    "",
                ));
            }
            Command::CheckTyped => {
                let typed = self.state.obj_path.trim().to_owned();
                if typed.is_empty() {
                    self.set_status(
                        StatusKind::Notice,
                        "Type the path of your image in the File field to check it",
                    );
                } else {
                    self.start_check(ctx, typed.into());
                }
            }
            Command::StopChecking => self.check = None,
        }
    }

    /// Check my image: reads `path` and holds it against the exact figure for the current
    /// settings, in place of an A/B comparison.
    fn start_check(&mut self, ctx: &egui::Context, path: std::path::PathBuf) {
        self.compare = None;
        let check = check::StudentCheck::start(ctx, path);
        self.set_status_while(
            StatusKind::Info,
            Cause::Checking,
            format!("Reading {}…", check.name()),
        );
        self.check = Some(check);
    }

    /// Once a frame: the check's image once read (the camera then renders at its size, with
    /// the same field of view) and its diagnosis.
    fn receive_check(&mut self, ctx: &egui::Context) {
        let scene_ready = self.state.settings.scene == self.scene_choice;
        let Some(check) = &mut self.check else {
            return;
        };
        match check.update(ctx, &self.state.settings, &self.scene, scene_ready) {
            None => {}
            Some(check::Event::Read { width, height }) => {
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
            Some(check::Event::Unreadable(e)) => {
                self.check = None;
                self.set_status(StatusKind::Error, e);
            }
        }
    }

    /// Soft shadows or depth of field just turned on in a lab stage: they average random points
    /// of the light or the lens, grainy at the lab's 16 samples, so the sample target is raised
    /// to [`SOFT_SAMPLE_TARGET`] as the path stage raises its own, and the status line says so.
    /// Only on the change: a target the user lowers afterwards stays as set.
    fn refine_sampled_effects(&mut self) {
        let now = Sampled::of(&self.state.settings);
        let turned_on = Sampled {
            soft_shadows: now.soft_shadows && !self.sampled.soft_shadows,
            depth_of_field: now.depth_of_field && !self.sampled.depth_of_field,
        };
        self.sampled = now;
        let settings = &mut self.state.settings;
        let Some(what) = turned_on.name() else {
            return;
        };
        if settings.samples_per_pixel >= SOFT_SAMPLE_TARGET {
            return;
        }
        let from = settings.samples_per_pixel;
        settings.samples_per_pixel = SOFT_SAMPLE_TARGET;
        self.set_status(
            StatusKind::Info,
            format!(
                "{what}: refining to {SOFT_SAMPLE_TARGET} samples (the target was {from}), so \
                 the grain of random points averages out (noise: see Stats)"
            ),
        );
    }

    /// Saves the current full-resolution image on a short-lived thread (PNG encoding of a large
    /// image takes longer than a UI frame).
    fn start_screenshot(&mut self, ctx: &egui::Context) {
        let Some(full) = self.current_full_frame() else {
            return;
        };
        let mut settings = full.settings.clone();
        // What is on screen: the denoised image when there is one, and settings that say so
        // (with the samples it was made from), so that they reproduce it.
        let image = match &full.denoised {
            Some((denoised, samples)) => {
                settings.samples_per_pixel = *samples;
                settings.denoise = true;
                Arc::clone(denoised)
            }
            None => {
                settings.samples_per_pixel = full.samples;
                Arc::clone(&full.image)
            }
        };
        // The display in force now, which the screenshot's PNG is shown through.
        settings.display = self.state.settings.display;
        // While the student's equations are shown: their image, with the settings (and
        // equations) that make it again.
        let (image, settings) = self
            .equations
            .screenshot(&self.state.settings)
            .unwrap_or((image, settings));
        let request = screenshot::Request {
            folder: self.state.screenshot_folder.clone(),
            image,
            settings,
            sample_target: full.target,
            time: chrono::Local::now(),
        };
        let (sender, receiver) = mpsc::channel();
        let repaint = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("raylab-screenshot".to_owned())
            .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
            .spawn(move || {
                let result = screenshot::save(&request).map_err(|e| format!("{e:#}"));
                let _ = sender.send(result);
                repaint.request_repaint();
            });
        match spawned {
            Ok(_) => {
                self.screenshots_saving.push(receiver);
                self.set_status(StatusKind::Info, "Saving the screenshot...");
            }
            Err(e) => self.set_status(
                StatusKind::Error,
                format!("could not start saving the screenshot: {e}"),
            ),
        }
    }

    fn receive_screenshots(&mut self) {
        let mut results = Vec::new();
        self.screenshots_saving
            .retain(|receiver| match receiver.try_recv() {
                Ok(result) => {
                    results.push(result);
                    false
                }
                Err(TryRecvError::Empty) => true,
                Err(TryRecvError::Disconnected) => {
                    results.push(Err("the screenshot thread stopped".to_owned()));
                    false
                }
            });
        for result in results {
            match result {
                Ok(saved) => {
                    let shown = std::fs::canonicalize(&saved.png).unwrap_or(saved.png);
                    let (kind, early) = if saved.samples < saved.target {
                        (
                            StatusKind::Notice,
                            format!(
                                " at {}/{} samples, before the target: save again when the \
                                 progress bar is full for the converged image",
                                saved.samples, saved.target
                            ),
                        )
                    } else {
                        (StatusKind::Info, String::new())
                    };
                    self.set_status(
                        kind,
                        format!(
                            "Saved {}{early} (its settings inside it, and beside it as .json)",
                            shown.display()
                        ),
                    );
                }
                Err(e) if !self.state.screenshot_folder.is_dir() => {
                    let folder = self.state.screenshot_folder.clone();
                    self.set_error(Cause::MissingFolder(folder), e);
                }
                Err(e) => self.set_status(StatusKind::Error, e),
            }
        }
    }

    /// The bottom bar: the status on the left, the stats' summary on the right. The summary
    /// takes its width (at most half the bar), the status what is left; each is one line, cut
    /// with "…" when longer and whole in its tooltip, so neither is ever drawn over the other.
    fn status_ui(&self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                let room = egui::vec2(ui.available_width() / 2.0, ui.available_height());
                ui.allocate_ui_with_layout(room, *ui.layout(), |ui| {
                    ui.add(egui::Label::new(self.stats.summary()).truncate());
                });
                ui.with_layout(egui::Layout::left_to_right(egui::Align::Center), |ui| {
                    self.status_line_ui(ui);
                });
            });
        });
    }

    /// The status message, one line (see [`Self::status_ui`]).
    fn status_line_ui(&self, ui: &mut egui::Ui) {
        let Some(status) = &self.status else {
            ui.add(egui::Label::new("Ready. F1 lists the keys.").truncate());
            return;
        };
        let color = match status.kind {
            StatusKind::Info => ui.visuals().text_color(),
            StatusKind::Notice => ui.visuals().warn_fg_color,
            StatusKind::Error => ui.visuals().error_fg_color,
        };
        if let Some(details) = &status.details
            && ui
                .small_button("Copy details")
                .on_hover_text(
                    "Copy the settings of the render that failed, as JSON: \
                     `raylab render --settings FILE` reproduces it",
                )
                .clicked()
        {
            ui.ctx().copy_text(details.clone());
        }
        // A label cut short shows its whole text when hovered.
        ui.add(egui::Label::new(egui::RichText::new(&status.text).color(color)).truncate());
    }

    fn help_ui(&mut self, ctx: &egui::Context) {
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
                        for (keys, action) in input::HELP {
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
            // As wide as opening it made room for ([`WorkbenchApp::make_room_for_inspector`]).
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
        egui::CentralPanel::default_margins().show(ui, |ui| {
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
            let overlay: Option<&mut dyn viewport::Overlay> =
                match (&mut self.check, &mut self.compare) {
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
        });
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
            // One line a frame, for scripts: fields in a fixed order.
            let (change_ms, change_frames) = self.stats.change_to_image.unwrap_or((f64::NAN, 0));
            let _ = writeln!(
                std::io::stderr(),
                "raylab-frame ui_ms={:.2} frame_cpu_ms={:.2} samples={} target={} preview={} \
                 t_ms={:.1} change_to_image_ms={:.1} change_frames={} full_pass_ms={:.1} \
                 denoised={}",
                self.stats.ui_frame_ms,
                self.stats.frame_cpu_ms.unwrap_or(f64::NAN),
                self.stats.samples,
                self.stats.target,
                self.stats.is_preview,
                self.started.elapsed().as_secs_f64() * 1e3,
                change_ms,
                change_frames,
                self.stats.full_pass.map_or(f64::NAN, |(ms, _, _)| ms),
                self.stats.denoised.map_or(0, |(samples, _)| samples),
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

/// The pixel of a `to`-sized image on the same spot as `pixel` of a `from`-sized one: its
/// centre scaled, kept inside the image.
fn same_spot(pixel: [u32; 2], from: [u32; 2], to: [u32; 2]) -> [u32; 2] {
    std::array::from_fn(|i| {
        let centre = (f64::from(pixel[i]) + 0.5) / f64::from(from[i].max(1));
        ((centre * f64::from(to[i])) as u32).min(to[i].saturating_sub(1))
    })
}
