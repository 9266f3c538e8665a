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

use crate::settings::RenderSettings;
pub use crate::settings::{Loaded, from_json};

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
