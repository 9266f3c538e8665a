//! Files in the workbench: opening a scene file (`.toml`), a screenshot (its `.png`, which
//! carries its settings, or the `.json` beside it) or an OBJ model, and saving the setup as a
//! scene file — from a typed path, drag-and-drop onto the window, or the Open / Save dialog
//! (Ctrl+O, Ctrl+Shift+S).
//!
//! The dialog is the workbench's own (a folder's listing in an egui window), not the desktop's:
//! it works wherever the window does, under Xvfb and in the UI tests included, and needs no
//! portal service or GTK.

use std::path::{Path, PathBuf};

use eframe::egui;
use raylab_core::RenderSettings;
use raylab_core::files::settings_file::{self, Loaded};
use raylab_core::shapes::scene::SceneChoice;

use super::WorkbenchApp;
use super::sampled::Sampled;
use super::status::StatusKind;

/// What a file holds, once read.
#[derive(Debug)]
pub enum Opened {
    /// Settings (a scene file, a screenshot or its JSON), checked and valid.
    Settings(Box<Loaded>),
    /// An OBJ model, to stand in the box (it is read by the scene loader, off this thread).
    Model(PathBuf),
    /// An image that is no raylab screenshot (a BMP, PPM or JPEG, or a PNG without settings):
    /// a student's render, to check against the exact figure.
    StudentImage(PathBuf),
}

/// The extensions of the images `raylab check` reads besides PNG.
pub const CHECKED_IMAGES: [&str; 6] = ["bmp", "ppm", "pgm", "pnm", "jpg", "jpeg"];

/// Whether `path` names an image (by its extension): what Check reads, a PNG screenshot
/// included.
pub fn is_image(path: &Path) -> bool {
    path.extension().is_some_and(|e| {
        let e = e.to_string_lossy().to_ascii_lowercase();
        e == "png" || CHECKED_IMAGES.contains(&e.as_str())
    })
}

/// Reads what `path` holds. Settings are validated here, so a file with a bad value changes
/// nothing: the error names the file and the value.
pub fn open(path: &Path) -> Result<Opened, String> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if extension.as_deref() == Some("obj") {
        // Only a regular file: a FIFO would keep the scene loader waiting for ever.
        raylab_core::base::inputs::open_regular(path)
            .map_err(|reason| format!("could not open '{}': {reason}", path.display()))?;
        return Ok(Opened::Model(path.to_path_buf()));
    }
    if extension
        .as_deref()
        .is_some_and(|e| CHECKED_IMAGES.contains(&e))
    {
        return Ok(Opened::StudentImage(path.to_path_buf()));
    }
    let loaded = match settings_file::read_file(path) {
        Ok(loaded) => loaded,
        // A PNG that carries no settings: the student's own render.
        Err(settings_file::ReadError::NoSettings { .. }) => {
            return Ok(Opened::StudentImage(path.to_path_buf()));
        }
        Err(e) => return Err(e.to_string()),
    };
    loaded
        .settings
        .validate()
        .map_err(|e| format!("'{}' was not opened: {e}", path.display()))?;
    Ok(Opened::Settings(Box::new(loaded)))
}

/// The scene file a typed or chosen `path` names: `.toml` added when it has no extension;
/// another extension is refused.
pub fn scene_path(path: &Path) -> Result<PathBuf, String> {
    match path.extension() {
        None => Ok(path.with_extension(raylab_core::files::scene_file::EXTENSION)),
        Some(e) if e == raylab_core::files::scene_file::EXTENSION => Ok(path.to_path_buf()),
        Some(_) => Err(format!(
            "not saved: a scene file's name ends in .toml ('{}')",
            path.display()
        )),
    }
}

/// Writes the settings as a scene file at `path` ([`scene_path`]). A file already there is
/// replaced only when `replace` says so (the Save dialog asked), and never when the scene
/// reads it (a model or a map whose name ends in `.toml`; the scene file it was opened from is
/// not one, and is saved over as any Save does); otherwise the scene goes to the first free
/// name `NAME-1.toml`, `NAME-2.toml`, … as the command line's `--save-scene` does, and nothing
/// is lost. Returns the path written.
pub fn save_scene(
    settings: &RenderSettings,
    path: &Path,
    replace: bool,
) -> Result<PathBuf, String> {
    let path = scene_path(path)?;
    if replace {
        let files = settings.scene.files_read();
        raylab_core::base::inputs::refuse_output_onto("not saved:", &path, "the scene", &files)?;
        raylab_core::files::scene_file::save(settings, &path).map_err(|e| e.to_string())?;
        return Ok(path);
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    let text = raylab_core::files::scene_file::to_text(settings, folder)
        .map_err(|reason| format!("could not write '{}': {reason}", path.display()))?;
    raylab_core::transport::film::write_to_free_name(&path, text.as_bytes())
        .map_err(|e| e.to_string())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DialogMode {
    /// Any file the workbench opens.
    Open,
    /// A screenshot's settings (PNG and JSON only).
    OpenScreenshot,
    SaveScene,
    /// A student's render to check against the exact figure.
    CheckImage,
}

/// What the dialog ended with this frame.
#[derive(Debug, PartialEq)]
pub enum DialogOutcome {
    Open,
    Cancelled,
    Chosen(PathBuf),
    /// A scene file to save over the one there, the user having said so.
    Replace(PathBuf),
}

/// The Open / Save dialog: a folder's sub-folders and the files of the kinds it offers.
pub struct FileDialog {
    pub mode: DialogMode,
    folder: PathBuf,
    /// The file name typed or clicked.
    name: String,
    /// Sub-folders, then files, by name.
    entries: Vec<(String, bool)>,
    error: Option<String>,
    /// The file a save would replace, while the dialog asks whether to.
    replacing: Option<PathBuf>,
}

impl FileDialog {
    pub fn new(mode: DialogMode, folder: &Path, name: &str) -> Self {
        let folder = std::fs::canonicalize(folder).unwrap_or_else(|_| folder.to_path_buf());
        let mut dialog = Self {
            mode,
            folder,
            name: name.to_owned(),
            entries: Vec::new(),
            error: None,
            replacing: None,
        };
        dialog.list();
        dialog
    }

    fn offers(&self, name: &str) -> bool {
        let lower = name.to_ascii_lowercase();
        let ends = |e: &[&str]| e.iter().any(|e| lower.ends_with(e));
        match self.mode {
            DialogMode::Open => ends(&[
                ".toml", ".png", ".json", ".obj", ".bmp", ".ppm", ".pgm", ".pnm", ".jpg", ".jpeg",
            ]),
            DialogMode::CheckImage => {
                ends(&[".png", ".bmp", ".ppm", ".pgm", ".pnm", ".jpg", ".jpeg"])
            }
            DialogMode::OpenScreenshot => ends(&[".png", ".json"]),
            DialogMode::SaveScene => ends(&[".toml"]),
        }
    }

    fn list(&mut self) {
        self.entries.clear();
        match std::fs::read_dir(&self.folder) {
            Ok(read) => {
                for entry in read.flatten() {
                    let name = entry.file_name().to_string_lossy().into_owned();
                    if name.starts_with('.') {
                        continue;
                    }
                    let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
                    if is_dir || self.offers(&name) {
                        self.entries.push((name, is_dir));
                    }
                }
                self.entries
                    .sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
                self.error = None;
            }
            Err(e) => self.error = Some(format!("could not list '{}': {e}", self.folder.display())),
        }
    }

    fn enter(&mut self, folder: PathBuf) {
        self.folder = folder;
        self.list();
    }

    pub fn title(&self) -> &'static str {
        match self.mode {
            DialogMode::Open => "Open",
            DialogMode::OpenScreenshot => "Open settings from screenshot",
            DialogMode::SaveScene => "Save scene as",
            DialogMode::CheckImage => "Check an image",
        }
    }

    pub fn ui(&mut self, ctx: &egui::Context) -> DialogOutcome {
        let mut outcome = DialogOutcome::Open;
        let mut open = true;
        egui::Window::new(self.title())
            .open(&mut open)
            .collapsible(false)
            .default_width(420.0)
            .pivot(egui::Align2::CENTER_CENTER)
            .default_pos(ctx.content_rect().center())
            .show(ctx, |ui| {
                ui.horizontal(|ui| {
                    if ui.button("Up").on_hover_text("The parent folder").clicked()
                        && let Some(parent) = self.folder.parent()
                    {
                        self.enter(parent.to_path_buf());
                    }
                    ui.label(self.folder.display().to_string());
                });
                if let Some(e) = &self.error {
                    ui.colored_label(ui.visuals().error_fg_color, e);
                }
                let mut enter = None;
                egui::ScrollArea::vertical()
                    .max_height(260.0)
                    .show(ui, |ui| {
                        for (name, is_dir) in &self.entries {
                            let label = if *is_dir {
                                format!("{name}/")
                            } else {
                                name.clone()
                            };
                            let selected = !is_dir && *name == self.name;
                            let response = ui.selectable_label(selected, label);
                            if response.clicked() {
                                if *is_dir {
                                    enter = Some(self.folder.join(name));
                                } else {
                                    self.name = name.clone();
                                }
                            }
                            if response.double_clicked() && !is_dir {
                                outcome = DialogOutcome::Chosen(self.folder.join(name));
                            }
                        }
                        if self.entries.is_empty() {
                            ui.weak("No folders or files of the kinds offered here.");
                        }
                    });
                if let Some(folder) = enter {
                    self.enter(folder);
                }
                ui.separator();
                ui.horizontal(|ui| {
                    let label = ui.label("File name");
                    let field = ui
                        .add(egui::TextEdit::singleline(&mut self.name).desired_width(220.0))
                        .labelled_by(label.id);
                    let entered =
                        field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    let action = if self.mode == DialogMode::SaveScene {
                        "Save file"
                    } else {
                        "Open file"
                    };
                    if field.changed() {
                        self.replacing = None;
                    }
                    if (ui.button(action).clicked() || entered) && !self.name.trim().is_empty() {
                        let chosen = self.folder.join(self.name.trim());
                        // Saving onto a file there asks first, as a desktop's dialog does.
                        match scene_path(&chosen) {
                            Ok(file) if self.mode == DialogMode::SaveScene && file.exists() => {
                                self.replacing = Some(file);
                            }
                            _ => outcome = DialogOutcome::Chosen(chosen),
                        }
                    }
                    if ui.button("Cancel").clicked() {
                        outcome = DialogOutcome::Cancelled;
                    }
                });
                if let Some(file) = self.replacing.clone() {
                    let name = file.file_name().unwrap_or_default().to_string_lossy();
                    ui.colored_label(
                        ui.visuals().warn_fg_color,
                        format!("'{name}' already exists. Replace it?"),
                    );
                    ui.horizontal(|ui| {
                        if ui.button("Replace").clicked() {
                            outcome = DialogOutcome::Replace(file);
                        }
                        if ui.button("Keep it").clicked() {
                            self.replacing = None;
                        }
                    });
                }
            });
        if !open {
            outcome = DialogOutcome::Cancelled;
        }
        outcome
    }
}

impl WorkbenchApp {
    /// Opens a scene file, a screenshot (PNG or JSON) or an OBJ model: from the File field,
    /// the dialog or a drop on the window. A file that cannot be used changes nothing.
    pub(super) fn open_path(&mut self, path: &std::path::Path, ctx: &egui::Context) {
        self.state.obj_path = path.display().to_string();
        match open(path) {
            Ok(Opened::StudentImage(image)) => self.start_check(ctx, image),
            Ok(Opened::Model(model)) => {
                self.state.settings.scene = SceneChoice::Obj(model);
            }
            Ok(Opened::Settings(mut loaded)) => {
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
    pub(super) fn save_scene_to(&mut self, path: &std::path::Path, replace: bool) {
        // The scene file carries the student's equations.
        let mut settings = self.state.settings.clone();
        settings.equations = self.equations.carried();
        match save_scene(&settings, path, replace) {
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
    pub(super) fn dialog_folder(&self) -> std::path::PathBuf {
        let typed = std::path::Path::new(self.state.obj_path.trim());
        match typed.parent() {
            Some(dir) if typed.file_name().is_some() && dir.is_dir() => dir.to_path_buf(),
            _ => self.state.screenshot_folder.clone(),
        }
    }

    pub(super) fn file_dialog_ui(&mut self, ctx: &egui::Context) {
        let Some(dialog) = &mut self.file_dialog else {
            return;
        };
        let mode = dialog.mode;
        match dialog.ui(ctx) {
            DialogOutcome::Open => {}
            DialogOutcome::Cancelled => self.file_dialog = None,
            DialogOutcome::Chosen(path) => {
                self.file_dialog = None;
                if mode == DialogMode::SaveScene {
                    self.save_scene_to(&path, false);
                } else if mode == DialogMode::CheckImage {
                    self.start_check(ctx, path);
                } else {
                    self.open_path(&path, ctx);
                }
            }
            DialogOutcome::Replace(path) => {
                self.file_dialog = None;
                self.save_scene_to(&path, true);
            }
        }
    }

    /// Files dropped on the window are opened (the last, if several).
    pub(super) fn receive_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(file) = dropped.last() {
            let path = file.path().to_path_buf();
            self.open_path(&path, ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_tells_the_kinds_apart_and_refuses_bad_values() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("m.obj");
        std::fs::write(&model, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(matches!(open(&model), Ok(Opened::Model(p)) if p == model));
        let missing = dir.path().join("gone.obj");
        assert!(open(&missing).unwrap_err().contains("gone.obj"));

        let json = dir.path().join("s.json");
        std::fs::write(&json, r#"{"seed": 5}"#).unwrap();
        match open(&json).unwrap() {
            Opened::Settings(loaded) => assert_eq!(loaded.settings.seed, 5),
            other => panic!("{other:?}"),
        }
        std::fs::write(&json, r#"{"light": {"power": -3}}"#).unwrap();
        let e = open(&json).unwrap_err();
        assert!(
            e.contains("s.json") && e.contains("invalid light power -3"),
            "{e}"
        );

        let saved =
            save_scene(&RenderSettings::default(), &dir.path().join("setup"), false).unwrap();
        assert_eq!(saved, dir.path().join("setup.toml"));
        match open(&saved).unwrap() {
            Opened::Settings(loaded) => assert_eq!(loaded.settings, RenderSettings::default()),
            other => panic!("{other:?}"),
        }
        let e = save_scene(&RenderSettings::default(), &dir.path().join("x.png"), false);
        assert!(e.unwrap_err().contains("ends in .toml"));
    }

    /// A file already there is kept unless the save replaces it: the scene goes to the next
    /// free name, and only `replace` writes over it.
    #[test]
    fn saving_keeps_a_file_already_there_unless_told_to_replace_it() {
        let dir = tempfile::tempdir().unwrap();
        let there = dir.path().join("mine.toml");
        std::fs::write(&there, "# my hand-written scene\n").unwrap();
        let mut other = RenderSettings::default();
        other.seed = 9;
        let saved = save_scene(&other, &there, false).unwrap();
        assert_eq!(saved, dir.path().join("mine-1.toml"));
        assert_eq!(
            std::fs::read_to_string(&there).unwrap(),
            "# my hand-written scene\n"
        );
        match open(&saved).unwrap() {
            Opened::Settings(loaded) => assert_eq!(loaded.settings.seed, 9),
            other => panic!("{other:?}"),
        }
        assert_eq!(save_scene(&other, &there, true).unwrap(), there);
        match open(&there).unwrap() {
            Opened::Settings(loaded) => assert_eq!(loaded.settings.seed, 9),
            other => panic!("{other:?}"),
        }
    }

    /// Save over a file is refused when the scene reads that file: a model whose name ends in
    /// `.toml` is kept, and saving over the scene file itself still replaces it.
    #[test]
    fn saving_never_replaces_a_file_the_scene_reads() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path().join("model.toml");
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        std::fs::write(&model, obj).unwrap();
        let mut settings = RenderSettings::default();
        settings.scene = raylab_core::shapes::scene::SceneChoice::Obj(model.clone());
        let e = save_scene(&settings, &model, true).unwrap_err();
        assert!(e.starts_with("not saved: "), "{e}");
        assert!(e.contains("(a model: "), "{e}");
        assert_eq!(std::fs::read_to_string(&model).unwrap(), obj);
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, "# the scene file opened\n").unwrap();
        assert_eq!(save_scene(&settings, &scene, true).unwrap(), scene);
        assert_ne!(
            std::fs::read_to_string(&scene).unwrap(),
            "# the scene file opened\n"
        );
    }
}
