//! What the workbench remembers between runs: one serde value, [`WorkbenchState`], kept as JSON
//! in eframe's storage under [`STORAGE_KEY`].
//!
//! A settings file that does not parse, comes from another version of the format, or holds
//! values the renderer refuses falls back to the lab's defaults, with a notice that says why.

use std::path::PathBuf;

use raylab_core::RenderSettings;
use serde::{Deserialize, Serialize};

/// The key in eframe's storage.
pub const STORAGE_KEY: &str = "raylab-workbench";

/// The version of [`WorkbenchState`]'s format; a file with another version is not trusted.
pub const STATE_VERSION: u32 = 1;

/// The workbench's sample target: the lab's image (sample 0, the pixel centres) first, then
/// jittered samples averaged up to this many (anti-aliased edges).
pub const DEFAULT_SAMPLE_TARGET: u32 = 16;

/// The bounce count offered when "Unlimited bounces" is first unticked.
pub const DEFAULT_LIMITED_BOUNCES: u32 = 4;

/// Everything the workbench persists.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct WorkbenchState {
    /// The format version, [`STATE_VERSION`] when written by this build.
    pub version: u32,
    /// The one settings value the panels, keys and mouse edit.
    pub settings: RenderSettings,
    /// Threads in the render pool.
    pub render_threads: usize,
    /// Where screenshots go.
    pub screenshot_folder: PathBuf,
    /// The path typed in the Scene panel's File field (a scene file, screenshot or OBJ model).
    pub obj_path: String,
    /// The path tracer's bounce count while "Unlimited bounces" is ticked, for when it is
    /// unticked again.
    pub limited_bounces: u32,
    /// "Click to focus": a click on the image sets the focus distance.
    pub focus_mode: bool,
    /// The lab walk-through's current step, if it is open.
    pub walk_step: Option<usize>,
    /// The settings when the walk-through started: what its steps change is put back from
    /// them on leaving ([`raylab_core::teaching::walkthrough::restore`]).
    pub walk_restore: Option<RenderSettings>,
    /// Inspect pixels: a click on the image pins a pixel, the inspector explains it.
    pub inspect_mode: bool,
    /// The inspected pixel.
    pub pinned: Option<[u32; 2]>,
    /// "Denoise": noisy images (the path stage, soft shadows, depth of field) are shown
    /// denoised; the accumulated image itself is never changed.
    pub denoise: bool,
}

impl Default for WorkbenchState {
    fn default() -> Self {
        Self {
            version: STATE_VERSION,
            settings: lab_defaults(),
            render_threads: raylab_core::transport::progressive::default_threads(),
            screenshot_folder: PathBuf::from("."),
            obj_path: String::new(),
            limited_bounces: DEFAULT_LIMITED_BOUNCES,
            focus_mode: false,
            walk_step: None,
            walk_restore: None,
            inspect_mode: false,
            pinned: None,
            denoise: true,
        }
    }
}

/// The lab's figure 7 at 512 × 512, accumulated to [`DEFAULT_SAMPLE_TARGET`] samples.
pub fn lab_defaults() -> RenderSettings {
    RenderSettings {
        samples_per_pixel: DEFAULT_SAMPLE_TARGET,
        ..RenderSettings::default()
    }
}

impl WorkbenchState {
    pub fn to_json(&self) -> String {
        // A struct of numbers, strings and paths: serialising can't fail short of a non-UTF-8
        // path, which then is saved as the default folder and the Cornell box.
        serde_json::to_string_pretty(self).unwrap_or_else(|_| {
            let fallback = Self {
                screenshot_folder: PathBuf::from("."),
                settings: RenderSettings {
                    scene: raylab_core::shapes::scene::SceneChoice::Cornell,
                    ..self.settings.clone()
                },
                ..self.clone()
            };
            serde_json::to_string_pretty(&fallback).unwrap_or_default()
        })
    }

    /// Reads a saved state, or says why it can't be used.
    pub fn from_json(json: &str) -> Result<Self, String> {
        let value: serde_json::Value =
            serde_json::from_str(json).map_err(|e| format!("it is not valid JSON ({e})"))?;
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        if version != Some(u64::from(STATE_VERSION)) {
            let found = version.map_or("none".to_owned(), |v| v.to_string());
            return Err(format!(
                "it is from another version of raylab (format {found}, expected {STATE_VERSION})"
            ));
        }
        let mut state: Self =
            serde_json::from_value(value).map_err(|e| format!("it does not fit ({e})"))?;
        state
            .settings
            .validate()
            .map_err(|e| format!("it holds an {e}"))?;
        // Settings to put back that could not be rendered are dropped: leaving the walk-through
        // then keeps the settings on screen, which are valid.
        if state
            .walk_restore
            .as_ref()
            .is_some_and(|s| s.validate().is_err())
        {
            state.walk_restore = None;
        }
        if state.render_threads == 0 {
            return Err("it asks for 0 render threads".to_owned());
        }
        if state.render_threads > raylab_core::transport::progressive::MAX_THREADS {
            return Err(format!(
                "it asks for {} render threads (at most {})",
                state.render_threads,
                raylab_core::transport::progressive::MAX_THREADS
            ));
        }
        Ok(state)
    }
}

/// The saved state, or the defaults and a notice saying why the saved one was not used.
pub fn load(storage: Option<&dyn eframe::Storage>) -> (WorkbenchState, Option<String>) {
    let Some(json) = storage.and_then(|s| s.get_string(STORAGE_KEY)) else {
        return (WorkbenchState::default(), None);
    };
    match WorkbenchState::from_json(&json) {
        Ok(state) => (state, None),
        Err(why) => (
            WorkbenchState::default(),
            Some(format!(
                "Saved settings ignored: {why}. Using the lab's defaults."
            )),
        ),
    }
}

/// The most of eframe's state file that is read: raylab's state is a few KiB.
pub const MAX_STATE_BYTES: u64 = 16 << 20;

/// The file eframe should keep the state in, given its folder (`eframe::storage_dir`): `None`
/// for its own choice, `app.ron` there, when that is a regular file of at most
/// [`MAX_STATE_BYTES`] (or absent). Otherwise eframe would wait for ever on a FIFO, or read a
/// device without end: then the state is kept in `app.ron.fallback` beside it (or, if that is
/// no better, a file of this run's own in the temporary folder), the original is neither read
/// nor replaced, and the notice says so.
pub fn state_file(folder: Option<&std::path::Path>) -> (Option<PathBuf>, Option<String>) {
    let Some(folder) = folder else {
        return (None, None);
    };
    let usable = |path: &std::path::Path| match std::fs::metadata(path) {
        Err(_) => Ok(()),
        Ok(m) if !m.is_file() => Err("it is not a regular file".to_owned()),
        Ok(m) if m.len() > MAX_STATE_BYTES => Err(format!(
            "it is {}, more than the {} saved settings may be",
            raylab_core::base::inputs::exact_size(m.len()),
            raylab_core::base::inputs::exact_size(MAX_STATE_BYTES)
        )),
        Ok(_) => Ok(()),
    };
    let file = folder.join("app.ron");
    let Err(why) = usable(&file) else {
        return (None, None);
    };
    let fallback = folder.join("app.ron.fallback");
    let fallback = if usable(&fallback).is_ok() {
        fallback
    } else {
        std::env::temp_dir().join(format!("raylab-state-{}.ron", std::process::id()))
    };
    let notice = format!(
        "Saved settings ignored: '{}' was not read ({why}). Using the lab's defaults; this \
         session's settings are kept in '{}'.",
        file.display(),
        fallback.display()
    );
    (Some(fallback), Some(notice))
}

pub fn save(storage: &mut dyn eframe::Storage, state: &WorkbenchState) {
    storage.set_string(STORAGE_KEY, state.to_json());
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

    #[derive(Default)]
    struct MemoryStorage(HashMap<String, String>);

    impl eframe::Storage for MemoryStorage {
        fn get_string(&self, key: &str) -> Option<String> {
            self.0.get(key).cloned()
        }
        fn set_string(&mut self, key: &str, value: String) {
            self.0.insert(key.to_owned(), value);
        }
        fn remove_string(&mut self, key: &str) {
            self.0.remove(key);
        }
        fn flush(&mut self) {}
    }

    fn stored(json: &str) -> MemoryStorage {
        let mut s = MemoryStorage::default();
        eframe::Storage::set_string(&mut s, STORAGE_KEY, json.to_owned());
        s
    }

    #[test]
    fn state_round_trips_through_storage() {
        let mut state = WorkbenchState::default();
        state.settings.light.position.x = 0.25;
        state.render_threads = 3;
        state.screenshot_folder = PathBuf::from("/tmp/shots");
        let mut storage = MemoryStorage::default();
        save(&mut storage, &state);
        assert_eq!(load(Some(&storage)), (state, None));
    }

    #[test]
    fn nothing_saved_gives_the_defaults_quietly() {
        assert_eq!(load(None), (WorkbenchState::default(), None));
        let empty = MemoryStorage::default();
        assert_eq!(load(Some(&empty)), (WorkbenchState::default(), None));
        assert_eq!(WorkbenchState::default().settings, lab_defaults());
    }

    #[test]
    fn corrupt_outdated_or_invalid_files_fall_back_with_a_notice() {
        for (json, says) in [
            ("{not json", "not valid JSON"),
            (r#"{"settings": {}}"#, "another version"),
            (r#"{"version": 99}"#, "another version"),
            (
                r#"{"version": 1, "settings": {"samples_per_pixel": "many"}}"#,
                "does not fit",
            ),
            (
                r#"{"version": 1, "settings": {"camera": {"focal_length": -5}}}"#,
                "focal length",
            ),
            (r#"{"version": 1, "render_threads": 0}"#, "0 render threads"),
        ] {
            let (state, notice) = load(Some(&stored(json)));
            assert_eq!(state, WorkbenchState::default(), "{json}");
            let notice = notice.unwrap_or_default();
            assert!(notice.contains(says), "{json}: {notice}");
        }
    }

    /// eframe's state file is read only when it is a regular file of a sensible size: a FIFO
    /// (which would keep the window from ever appearing) or a device is left alone, and the
    /// state kept beside it, with a notice; an ordinary file, or none, is eframe's to read.
    #[test]
    fn a_state_file_that_is_not_a_regular_file_is_not_read() {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(state_file(None), (None, None));
        assert_eq!(state_file(Some(dir.path())), (None, None), "no file yet");
        let file = dir.path().join("app.ron");
        std::fs::write(&file, "()").unwrap();
        assert_eq!(state_file(Some(dir.path())), (None, None));
        std::fs::remove_file(&file).unwrap();
        raylab_core::base::inputs::make_fifo(&file);
        let (path, notice) = state_file(Some(dir.path()));
        assert_eq!(path, Some(dir.path().join("app.ron.fallback")));
        let notice = notice.unwrap();
        assert!(
            notice.contains("not a regular file") && notice.contains("app.ron"),
            "{notice}"
        );
        // A fallback that is no better either: a file of this run's own.
        raylab_core::base::inputs::make_fifo(&dir.path().join("app.ron.fallback"));
        let (path, _) = state_file(Some(dir.path()));
        assert!(path.unwrap().starts_with(std::env::temp_dir()));
        assert_eq!(
            WorkbenchState::from_json(r#"{"version": 1, "render_threads": 2000}"#).unwrap_err(),
            "it asks for 2000 render threads (at most 1024)"
        );
    }

    #[test]
    fn a_partial_current_file_keeps_defaults_for_the_rest() {
        let (state, notice) = load(Some(&stored(
            r#"{"version": 1, "settings": {"light": {"position": [0.5, 0.0, 0.0]}}}"#,
        )));
        assert_eq!(notice, None);
        assert_eq!(state.settings.light.position.x, 0.5);
        assert_eq!(state.settings.camera, raylab_core::Camera::default());
    }

    /// A file saved before the path tracer and the materials existed: no `bounces`,
    /// `specular_depth`, `material_preset` or `limited_bounces`. It loads quietly, the new fields
    /// at their defaults.
    #[test]
    fn a_file_from_before_the_path_tracer_still_loads() {
        let old = r#"{
          "version": 1,
          "settings": {
            "scene": "cornell",
            "camera": {"position": [0.0, 0.0, -3.001], "yaw": 0.0, "pitch": 0.0,
                       "focal_length": 256.0, "width": 256, "height": 256},
            "light": {"position": [0.0, -0.5, -0.7], "power": [14.0, 14.0, 14.0]},
            "shading": {"stage": "shadows", "shadows": true, "indirect": false,
                        "indirect_light": [0.25, 0.25, 0.25]},
            "samples_per_pixel": 16,
            "seed": 0
          },
          "render_threads": 2,
          "screenshot_folder": "/tmp/shots",
          "obj_path": ""
        }"#;
        let (state, notice) = load(Some(&stored(old)));
        assert_eq!(notice, None);
        let shading = state.settings.shading;
        assert_eq!(shading.stage, raylab_core::Stage::Shadows);
        assert_eq!(shading.indirect_light, glam::Vec3::splat(0.25));
        assert_eq!(shading.bounces, None);
        assert_eq!(
            shading.specular_depth,
            raylab_core::transport::integrator::DEFAULT_SPECULAR_DEPTH
        );
        assert_eq!(
            state.settings.material_preset,
            raylab_core::MaterialPreset::None
        );
        assert_eq!(state.settings.camera.width, 256);
        assert_eq!(state.limited_bounces, DEFAULT_LIMITED_BOUNCES);
        assert_eq!(state.screenshot_folder, PathBuf::from("/tmp/shots"));
    }

    #[test]
    fn the_path_stage_and_materials_round_trip() {
        let mut state = WorkbenchState::default();
        state.settings.shading = raylab_core::Shading::for_stage(raylab_core::Stage::Path);
        state.settings.shading.bounces = Some(3);
        state.settings.shading.specular_depth = 2;
        state.settings.material_preset = raylab_core::MaterialPreset::Both;
        state.settings.samples_per_pixel = 1024;
        state.limited_bounces = 3;
        let mut storage = MemoryStorage::default();
        save(&mut storage, &state);
        assert_eq!(load(Some(&storage)), (state, None));
    }
}
