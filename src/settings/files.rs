//! Reading settings from the files raylab writes: a screenshot's `.json` sidecar (or a bare
//! settings object), a screenshot PNG (which carries the same JSON in an `iTXt` chunk), and a
//! scene file ([`crate::scene_file`]). [`read_file`] tells them apart, so the command line's
//! `--settings` and the workbench's Open and drag-and-drop take any of them.
//!
//! The JSON is lenient where the scene file is strict: it is what raylab itself wrote, perhaps
//! by an older or newer version, so a missing field takes the lab's value and an unknown one is
//! ignored — but each unknown field is reported as a warning, not dropped silently. Two rules
//! make a partial file mean what the same request means on the command line:
//! - a camera that gives its `width` but no `focal_length` keeps the lab's field of view
//!   (`focal_length = width`, 53.13°), as `--width` does, rather than the 512 px of a
//!   512-wide image;
//! - a UTF-8 byte-order mark before the text is ignored.

use std::io::{BufRead, Read as _, Seek};
use std::path::{Path, PathBuf};

use super::RenderSettings;

/// The PNG text keyword under which a screenshot carries its settings (as the sidecar's JSON).
pub const PNG_KEYWORD: &str = "raylab-settings";

/// Why settings could not be read from a file; the message names it.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("could not read settings file '{}': {reason}", path.display())]
    Read { path: PathBuf, reason: String },
    #[error("settings file '{}' is not valid: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error("'{}' carries no raylab settings (it is not a raylab screenshot)", path.display())]
    NoSettings { path: PathBuf },
    #[error(transparent)]
    SceneFile(#[from] crate::scene_file::SceneFileError),
}

/// Settings read from a file, and what in it was not understood.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    pub settings: RenderSettings,
    /// One line per thing ignored (an unknown field).
    pub warnings: Vec<String>,
}

/// Reads settings from a scene file (`.toml`), a raylab screenshot (a PNG, recognised by its
/// signature whatever its name) or settings JSON (anything else).
pub fn read_file(path: &Path) -> Result<Loaded, ReadError> {
    let is_scene_file = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(crate::scene_file::EXTENSION));
    if is_scene_file {
        let settings = crate::scene_file::load(path)?;
        return Ok(Loaded {
            settings,
            warnings: Vec::new(),
        });
    }
    let unreadable = |e: std::io::Error| ReadError::Read {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let invalid = |message: String| ReadError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    // A screenshot may be hundreds of megabytes: only its first chunks are read, up to the
    // text (the workbench opens files on its UI thread).
    let mut file = std::io::BufReader::new(std::fs::File::open(path).map_err(unreadable)?);
    let is_png = file
        .fill_buf()
        .map_err(unreadable)?
        .starts_with(PNG_SIGNATURE);
    let json = if is_png {
        match png_text(file, PNG_KEYWORD).map_err(invalid)? {
            Some(text) => text,
            None => {
                return Err(ReadError::NoSettings {
                    path: path.to_path_buf(),
                });
            }
        }
    } else {
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes).map_err(unreadable)?;
        String::from_utf8(bytes).map_err(|e| {
            invalid(format!(
                "byte {}: not UTF-8 text",
                e.utf8_error().valid_up_to()
            ))
        })?
    };
    from_json(&json).map_err(invalid)
}

/// Parses settings JSON: a screenshot sidecar (whose `settings` field holds them) or a bare
/// settings object. See the module docs for what is lenient.
pub fn from_json(text: &str) -> Result<Loaded, String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut value: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    if let Some(inner) = value.get_mut("settings") {
        value = inner.take();
    }
    if let Some(camera) = value.get_mut("camera").and_then(|c| c.as_object_mut())
        && !camera.contains_key("focal_length")
        && let Some(width) = camera.get("width").and_then(serde_json::Value::as_u64)
    {
        // `Camera::default_for(width, …)`: f = W, the lab's 53.13° across.
        camera.insert("focal_length".to_owned(), serde_json::json!(width as f32));
    }
    let mut warnings = Vec::new();
    let settings = serde_ignored::deserialize(value, |path| {
        warnings.push(format!("unknown field `{path}` ignored"));
    })
    .map_err(|e: serde_json::Error| e.to_string())?;
    Ok(Loaded { settings, warnings })
}

/// The text a PNG carries its settings as ([`crate::film::Image::save_with_text`] under
/// [`PNG_KEYWORD`]): their JSON, what [`read_file`] reads back.
pub fn settings_text(settings: &RenderSettings) -> String {
    serde_json::to_string(settings).expect("settings always serialise")
}

/// The eight bytes every PNG starts with.
pub const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The UTF-8 text (`iTXt`) a PNG carries under `keyword`, if any. Text chunks written before
/// the image data, as raylab writes them, are found without decoding the image.
pub fn png_text(png: impl BufRead + Seek, keyword: &str) -> Result<Option<String>, String> {
    let decoder = png::Decoder::new(png);
    let reader = decoder
        .read_info()
        .map_err(|e| format!("not a readable PNG: {e}"))?;
    for chunk in &reader.info().utf8_text {
        if chunk.keyword == keyword {
            return chunk
                .get_text()
                .map(Some)
                .map_err(|e| format!("its {keyword} text is unreadable: {e}"));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    use crate::film::{Image, OutputFormat};

    #[test]
    fn a_camera_with_only_a_width_keeps_the_labs_field_of_view() {
        let loaded = from_json(r#"{"camera": {"width": 256, "height": 128}}"#).unwrap();
        let c = loaded.settings.camera;
        assert_eq!((c.width, c.height, c.focal_length), (256, 128, 256.0));
        // 2·atan(W / 2f) = 2·atan(1/2) = 53.13°, as `--width 256 --height 128` gives.
        assert!((c.horizontal_fov_degrees() - 53.130_1).abs() < 1e-3);
        assert!(loaded.warnings.is_empty());
        // A focal length that is given stays.
        let c = from_json(r#"{"camera": {"width": 256, "focal_length": 100}}"#).unwrap();
        assert_eq!(c.settings.camera.focal_length, 100.0);
    }

    #[test]
    fn unknown_fields_are_warned_of_and_a_byte_order_mark_is_ignored() {
        let loaded =
            from_json("\u{feff}{\"seed\": 3, \"colour\": 1, \"light\": {\"watts\": 2}}").unwrap();
        assert_eq!(loaded.settings.seed, 3);
        assert_eq!(
            loaded.warnings,
            [
                "unknown field `colour` ignored",
                "unknown field `light.watts` ignored"
            ]
        );
        let sidecar = from_json(r#"{"settings": {"seed": 4}, "saved_at": "x"}"#).unwrap();
        assert_eq!(sidecar.settings.seed, 4);
        assert!(sidecar.warnings.is_empty());
        assert!(from_json("{\"seed\": -1}").is_err());
    }

    #[test]
    fn a_png_carries_text_that_reads_back_and_still_decodes() {
        let mut image = Image::new(3, 2);
        image.pixels[4] = glam::Vec3::new(1.0, 0.5, 0.25);
        let png = image.encode(OutputFormat::Png).unwrap();
        let png_text = |bytes: &[u8], keyword| png_text(Cursor::new(bytes), keyword);
        assert_eq!(png_text(&png, PNG_KEYWORD).unwrap(), None);
        let text = "{\"seed\": 7, \"é\": \"ü\"}";
        let display = crate::display::Display::default();
        let tagged = image
            .encode_with_text(OutputFormat::Png, &display, Some((PNG_KEYWORD, text)))
            .unwrap();
        assert_eq!(
            png_text(&tagged, PNG_KEYWORD).unwrap().as_deref(),
            Some(text)
        );
        assert_eq!(png_text(&tagged, "other").unwrap(), None);
        // The pixels are untouched.
        let a = image::load_from_memory(&png).unwrap().to_rgb8();
        let b = image::load_from_memory(&tagged).unwrap().to_rgb8();
        assert_eq!(a, b);
        assert_eq!(b.get_pixel(1, 1).0, [255, 128, 64]);
    }
}
