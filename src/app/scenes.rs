//! The scene on screen: loaded off the UI thread (with progress and Cancel), kept in a cache of
//! the last few for switching back, and the settings put back when a load fails.

use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::Instant;

use eframe::egui;
use raylab_core::shapes::scene::{Scene, SceneChoice};
use raylab_core::transport::progressive::catch_panic;

use super::WorkbenchApp;
use super::sampled::Sampled;
use super::status::StatusKind;

/// How many scenes besides the one on screen stay loaded for switching back.
pub const SCENE_CACHE: usize = 4;

/// A scene being loaded off the UI thread.
pub(super) struct SceneLoad {
    pub(super) choice: SceneChoice,
    started: Instant,
    result: Receiver<Result<(Scene, Vec<String>), String>>,
    /// What the loader is doing, for the status line.
    progress: Arc<std::sync::Mutex<String>>,
    /// Set by Cancel: the loader stops at its next step.
    cancel: Arc<std::sync::atomic::AtomicBool>,
}

impl WorkbenchApp {
    /// Starts loading the scene the settings ask for, unless it is loaded, kept from before
    /// (then it is swapped in at once), or on its way.
    pub(super) fn sync_scene(&mut self, ctx: &egui::Context) {
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
    pub(super) fn swap_in_scene(&mut self, choice: SceneChoice, scene: Arc<Scene>) {
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
    pub(super) fn loading_status(&mut self) {
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
    pub(super) fn cancel_loading(&mut self) {
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
    pub(super) fn put_back_settings(&mut self, failed: &SceneChoice) {
        if let Some(old) = self.restore_on_failure.take() {
            self.state.settings = old;
            self.sampled = Sampled::of(&self.state.settings);
        } else if self.state.settings.scene == *failed {
            self.state.settings.scene = self.scene_choice.clone();
        }
    }

    /// Takes a finished scene load: the new scene, or an error that puts the old one back.
    pub(super) fn receive_scene(&mut self) {
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
}
