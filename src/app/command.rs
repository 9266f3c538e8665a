//! The UI's actions ([`Command`]): what the panels, keys and buttons ask for, handled in one
//! place ([`WorkbenchApp::handle`]).

use eframe::egui;
use raylab_core::{Camera, Shading, Stage};

use super::sampled::{PATH_SAMPLE_TARGET, Sampled};
use super::status::StatusKind;
use super::{WorkbenchApp, files, persistence};

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
    /// Compare A/B: freeze the current settings and scene as A ([`super::compare`]).
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
    /// Check my image: show the dialog for a student's render ([`super::check`]).
    ShowCheckDialog,
    /// Check the image whose path is typed in the File field.
    CheckTyped,
    /// Stop checking: back to the live image.
    StopChecking,
}

impl WorkbenchApp {
    pub(super) fn handle(&mut self, command: Command, ctx: &egui::Context) {
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
}
