//! Screenshots: the render buffer (not a grab of the window) encoded as PNG, with the settings
//! that made it inside the PNG (an `iTXt` chunk) and in a `.json` file beside it, so the image
//! alone reproduces the render: open it (or drop it on the window) and the workbench restores
//! its settings; `raylab render --settings SHOT.png` renders it again. With the denoised image
//! on screen the screenshot is that image and its settings say `denoise`, which both honour.
//!
//! Files are named `raylab-YYYYMMDD-HHMMSS.png`; if that name (or its `.json`) is taken, `-1`,
//! `-2`, … is added. Files are created with `create_new`, so nothing is ever overwritten, even
//! by another program writing the same name at the same moment.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, TryRecvError};

use anyhow::Context as _;
use eframe::egui;
use raylab_core::transport::film::OutputFormat;
use raylab_core::{Image, RenderSettings};
use serde::{Deserialize, Serialize};

use super::WorkbenchApp;
use super::status::{Cause, StatusKind};

/// The paths a screenshot was written to.
#[derive(Clone, Debug, PartialEq)]
pub struct Saved {
    pub png: PathBuf,
    pub json: PathBuf,
    /// The samples the image had averaged, and the target it was heading for.
    pub samples: u32,
    pub target: u32,
}

/// The `.json` written beside each screenshot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    /// The PNG's file name.
    pub image: String,
    /// The version of raylab that rendered it.
    pub raylab_version: String,
    /// When it was saved (local time, RFC 3339).
    pub saved_at: String,
    /// The settings that reproduce the image exactly; `samples_per_pixel` is the number of
    /// samples the image had accumulated when it was saved.
    pub settings: RenderSettings,
    /// The sample target the workbench was heading for.
    pub sample_target: u32,
}

/// Everything a screenshot needs, owned, so it can be saved on another thread.
pub struct Request {
    pub folder: PathBuf,
    pub image: std::sync::Arc<Image>,
    /// The settings of the image, with `samples_per_pixel` set to the samples it holds.
    pub settings: RenderSettings,
    pub sample_target: u32,
    pub time: chrono::DateTime<chrono::Local>,
}

/// `raylab-YYYYMMDD-HHMMSS`, the name without suffix or extension.
pub fn base_name(time: &chrono::DateTime<chrono::Local>) -> String {
    time.format("raylab-%Y%m%d-%H%M%S").to_string()
}

/// Writes the PNG and its sidecar into `request.folder`.
pub fn save(request: &Request) -> anyhow::Result<Saved> {
    let folder = &request.folder;
    if !folder.is_dir() {
        anyhow::bail!(
            "could not save the screenshot: folder '{}' does not exist",
            folder.display()
        );
    }
    // Model paths relative to the folder, so the pair names the same models from wherever
    // it is opened.
    let settings = request.settings.relative_to(folder);
    let text = raylab_core::files::settings_file::settings_text(&settings)
        .map_err(|e| anyhow::anyhow!("could not save the screenshot: {e}"))?;
    let png_bytes = request
        .image
        .encode_with_text(
            OutputFormat::Png,
            &request.settings.display,
            Some((raylab_core::files::settings_file::PNG_KEYWORD, &text)),
        )
        .context("could not encode the screenshot as PNG")?;
    let base = base_name(&request.time);
    let (png_path, png_file, json_path, json_file) = reserve(folder, &base)?;
    let name = png_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let sidecar = Sidecar {
        image: name,
        raylab_version: env!("CARGO_PKG_VERSION").to_owned(),
        saved_at: request.time.to_rfc3339(),
        settings,
        sample_target: request.sample_target,
    };
    let json = serde_json::to_vec_pretty(&sidecar).context("could not describe the settings")?;
    let result = write_all(png_file, &png_bytes, &png_path)
        .and_then(|()| write_all(json_file, &json, &json_path));
    if let Err(e) = result {
        // Leave no half-written pair behind.
        let _ = fs::remove_file(&png_path);
        let _ = fs::remove_file(&json_path);
        return Err(e);
    }
    Ok(Saved {
        png: png_path,
        json: json_path,
        samples: request.settings.samples_per_pixel,
        target: request.sample_target,
    })
}

/// Creates (empty, with `create_new`) the first free pair `base[-n].png` + `base[-n].json`.
fn reserve(folder: &Path, base: &str) -> anyhow::Result<(PathBuf, File, PathBuf, File)> {
    for n in 0..10_000u32 {
        let stem = if n == 0 {
            base.to_owned()
        } else {
            format!("{base}-{n}")
        };
        let png = folder.join(format!("{stem}.png"));
        let json = folder.join(format!("{stem}.json"));
        let png_file = match create_new(&png) {
            Ok(f) => f,
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(write_error(&png, e)),
        };
        match create_new(&json) {
            Ok(json_file) => return Ok((png, png_file, json, json_file)),
            Err(e) => {
                drop(png_file);
                let _ = fs::remove_file(&png);
                if e.kind() != io::ErrorKind::AlreadyExists {
                    return Err(write_error(&json, e));
                }
            }
        }
    }
    anyhow::bail!(
        "could not save the screenshot: no free name like '{base}-N.png' in '{}'",
        folder.display()
    )
}

fn create_new(path: &Path) -> io::Result<File> {
    OpenOptions::new().write(true).create_new(true).open(path)
}

fn write_all(mut file: File, bytes: &[u8], path: &Path) -> anyhow::Result<()> {
    file.write_all(bytes)
        .and_then(|()| file.sync_all())
        .map_err(|e| write_error(path, e))
}

fn write_error(path: &Path, e: io::Error) -> anyhow::Error {
    anyhow::anyhow!("could not write '{}': {e}", path.display())
}

impl WorkbenchApp {
    /// Saves the current full-resolution image on a short-lived thread (PNG encoding of a large
    /// image takes longer than a UI frame).
    pub(super) fn start_screenshot(&mut self, ctx: &egui::Context) {
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
        let request = Request {
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
                let result = save(&request).map_err(|e| format!("{e:#}"));
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

    pub(super) fn receive_screenshots(&mut self) {
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
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use chrono::TimeZone as _;

    use super::*;

    fn request(folder: &Path) -> Request {
        let mut settings = RenderSettings::default();
        settings.camera = settings.camera.with_resolution(24, 16);
        let image = raylab_core::transport::render::render(
            &raylab_core::shapes::scene::cornell_box(),
            &settings,
        );
        Request {
            folder: folder.to_owned(),
            image: Arc::new(image),
            settings,
            sample_target: 16,
            time: chrono::Local
                .with_ymd_and_hms(2025, 3, 4, 5, 6, 7)
                .single()
                .unwrap(),
        }
    }

    #[test]
    fn saves_png_and_settings_and_never_overwrites() {
        let dir = tempfile::tempdir().unwrap();
        let req = request(dir.path());
        let first = save(&req).unwrap();
        assert_eq!(first.png, dir.path().join("raylab-20250304-050607.png"));
        let second = save(&req).unwrap();
        assert_eq!(second.png, dir.path().join("raylab-20250304-050607-1.png"));
        assert_eq!(
            second.json,
            dir.path().join("raylab-20250304-050607-1.json")
        );
        // A stray .json with the next name is not overwritten either: that name is skipped.
        fs::write(dir.path().join("raylab-20250304-050607-2.json"), "mine").unwrap();
        let third = save(&req).unwrap();
        assert_eq!(third.png, dir.path().join("raylab-20250304-050607-3.png"));
        assert_eq!(
            fs::read_to_string(dir.path().join("raylab-20250304-050607-2.json")).unwrap(),
            "mine"
        );
        assert!(!dir.path().join("raylab-20250304-050607-2.png").exists());

        // The PNG decodes to the render's size and pixels; the sidecar reproduces it.
        let png = image::open(&first.png).unwrap().to_rgb8();
        assert_eq!(png.dimensions(), (24, 16));
        assert_eq!(png.as_raw(), &req.image.to_rgb8());
        let sidecar: Sidecar =
            serde_json::from_str(&fs::read_to_string(&first.json).unwrap()).unwrap();
        assert_eq!(sidecar.image, "raylab-20250304-050607.png");
        assert_eq!(sidecar.sample_target, 16);
        let again = raylab_core::transport::render::render(
            &raylab_core::shapes::scene::cornell_box(),
            &sidecar.settings,
        );
        assert_eq!(again.to_rgb8(), png.into_raw());
    }

    #[test]
    fn a_missing_folder_is_an_error_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no/such/folder");
        let e = save(&request(&missing)).unwrap_err().to_string();
        assert!(e.contains("does not exist"), "{e}");
        assert!(!missing.exists());
    }

    /// `/proc` is a folder nobody can create files in, not even root (tests here run as root,
    /// which ignores permission bits).
    #[cfg(target_os = "linux")]
    #[test]
    fn an_unwritable_folder_is_an_error() {
        let e = save(&request(Path::new("/proc"))).unwrap_err().to_string();
        assert!(e.contains("could not write '/proc/raylab-"), "{e}");
    }
}
