//! Reading settings from the files raylab writes: a screenshot's `.json` sidecar (or a bare
//! settings object), a screenshot PNG (which carries the same JSON in an `iTXt` chunk), and a
//! scene file ([`crate::files::scene_file`]). [`read_file`] tells them apart, so the command line's
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

use std::io::{BufRead, Read, Seek};
use std::path::{Path, PathBuf};

use crate::base::inputs::{self, MAX_SCENE_FILE_BYTES, MAX_SETTINGS_TEXT_BYTES};
use crate::transport::settings::RenderSettings;
pub use crate::transport::settings::{Loaded, from_json};

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
    SceneFile(#[from] crate::files::scene_file::SceneFileError),
}

/// Reads settings from a scene file (`.toml`), a raylab screenshot (a PNG, recognised by its
/// signature whatever its name) or settings JSON (anything else). Only a regular file is read
/// ([`crate::base::inputs`]); JSON of more than [`MAX_SCENE_FILE_BYTES`] is refused. Model paths
/// relative to the file's folder, as raylab writes them ([`RenderSettings::relative_to`]), are
/// resolved against it.
pub fn read_file(path: &Path) -> Result<Loaded, ReadError> {
    let is_scene_file = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(crate::files::scene_file::EXTENSION));
    if is_scene_file {
        let settings = crate::files::scene_file::load(path)?;
        return Ok(Loaded {
            settings,
            warnings: Vec::new(),
        });
    }
    let unreadable = |reason: String| ReadError::Read {
        path: path.to_path_buf(),
        reason,
    };
    let invalid = |message: String| ReadError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let (file, len) = inputs::open_regular(path).map_err(unreadable)?;
    // A screenshot may be hundreds of megabytes: only its chunks' headers are read, and the
    // text (the workbench opens files on its UI thread).
    let mut file = std::io::BufReader::new(file);
    let is_png = file
        .fill_buf()
        .map_err(|e| unreadable(e.to_string()))?
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
        let bytes = inputs::read_open(file, len, MAX_SCENE_FILE_BYTES, "a settings file")
            .map_err(unreadable)?;
        String::from_utf8(bytes).map_err(|e| {
            invalid(format!(
                "byte {}: not UTF-8 text",
                e.utf8_error().valid_up_to()
            ))
        })?
    };
    let mut loaded = from_json(&json).map_err(invalid)?;
    // The equations compile, or the error names the quantity, its line and column.
    crate::teaching::sandbox::carried::compile_texts(&loaded.settings.equations)
        .map_err(|e| invalid(e.to_string()))?;
    loaded
        .settings
        .resolve_paths(path.parent().unwrap_or(Path::new("")));
    Ok(loaded)
}

/// The text a PNG carries its settings as ([`crate::transport::film::Image::save_with_text`] under
/// [`PNG_KEYWORD`]): their JSON, what [`read_file`] reads back. Model paths are written as they
/// are: [`RenderSettings::relative_to`] makes them relative to the PNG's folder first. Fails
/// only for a path that is not UTF-8, which [`RenderSettings::validate`] refuses.
pub fn settings_text(settings: &RenderSettings) -> Result<String, String> {
    serde_json::to_string(settings).map_err(|e| format!("the settings cannot be written: {e}"))
}

/// The eight bytes every PNG starts with.
pub const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The UTF-8 text a PNG carries under `keyword`, if any, found by walking its chunks: the
/// image data is skipped over, never read or decoded, and the text may come before or after
/// it. The text is an `iTXt` chunk, as raylab writes it (uncompressed), or compressed; a `tEXt`
/// or `zTXt` chunk (Latin-1) is read too. The error says what is wrong:
///
/// * not a PNG, or one cut short (no `IEND` chunk) or with a chunk of impossible length;
/// * the chunk under `keyword` damaged (its CRC does not match), its text not UTF-8, or
///   larger than [`MAX_SETTINGS_TEXT_BYTES`] (compressed text is inflated no further than
///   that: a few kilobytes cannot become gigabytes);
/// * two chunks under `keyword` (which one made the image would be a guess).
pub fn png_text(mut png: impl Read + Seek, keyword: &str) -> Result<Option<String>, String> {
    let mut signature = [0u8; 8];
    png.read_exact(&mut signature)
        .map_err(|_| "not a PNG: it is shorter than a PNG's signature".to_owned())?;
    if signature != PNG_SIGNATURE {
        return Err("not a PNG: it does not start with a PNG's signature".to_owned());
    }
    let mut found: Option<String> = None;
    let mut offset = 8u64;
    for index in 0u64.. {
        let mut header = [0u8; 8];
        match png.read_exact(&mut header) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                return Err(format!(
                    "the PNG is cut short at byte {offset}: it has no end (IEND) chunk"
                ));
            }
            Err(e) => return Err(e.to_string()),
        }
        let length = u32::from_be_bytes([header[0], header[1], header[2], header[3]]);
        let kind = [header[4], header[5], header[6], header[7]];
        let name = String::from_utf8_lossy(&kind).into_owned();
        if length > 0x7fff_ffff {
            return Err(format!(
                "not a readable PNG: its chunk at byte {offset} has an impossible length"
            ));
        }
        if index == 0 && &kind != b"IHDR" {
            return Err("not a readable PNG: it does not begin with its header (IHDR)".into());
        }
        let length = u64::from(length);
        let mut read = 0u64;
        if matches!(&kind, b"iTXt" | b"tEXt" | b"zTXt") {
            // The keyword comes first: 1 to 79 bytes and a NUL.
            let mut head = vec![0u8; length.min(80) as usize];
            png.read_exact(&mut head)
                .map_err(|e| cut_short(e, offset))?;
            read = head.len() as u64;
            let ours = head.split(|&b| b == 0).next() == Some(keyword.as_bytes())
                && head.len() > keyword.len();
            if ours {
                if found.is_some() {
                    return Err(format!(
                        "it carries two {keyword} texts (which one made the image is unclear)"
                    ));
                }
                if length > MAX_SETTINGS_TEXT_BYTES {
                    return Err(format!(
                        "its {keyword} chunk is {}, more than the {} settings may be",
                        inputs::exact_size(length),
                        inputs::exact_size(MAX_SETTINGS_TEXT_BYTES)
                    ));
                }
                let mut data = head;
                data.resize(length as usize, 0);
                png.read_exact(&mut data[read as usize..])
                    .map_err(|e| cut_short(e, offset))?;
                let mut crc = [0u8; 4];
                png.read_exact(&mut crc).map_err(|e| cut_short(e, offset))?;
                let mut hasher = crc32fast::Hasher::new();
                hasher.update(&kind);
                hasher.update(&data);
                if hasher.finalize() != u32::from_be_bytes(crc) {
                    return Err(format!(
                        "its {keyword} chunk ({name}, at byte {offset}) is damaged: its CRC \
                         does not match"
                    ));
                }
                let text = text_chunk(&kind, &data[keyword.len() + 1..])
                    .map_err(|e| format!("its {keyword} text ({name}) {e}"))?;
                found = Some(text);
                offset += 12 + length;
                continue;
            }
        }
        if &kind == b"IEND" {
            return Ok(found);
        }
        skip(&mut png, length - read + 4).map_err(|e| e.to_string())?;
        offset += 12 + length;
    }
    unreachable!("the chunks are counted without end")
}

/// The text of a text chunk of `kind` after its keyword and NUL, or what is wrong with it.
fn text_chunk(kind: &[u8; 4], rest: &[u8]) -> Result<String, String> {
    let limit = MAX_SETTINGS_TEXT_BYTES as usize;
    let inflate = |data: &[u8]| {
        fdeflate::decompress_to_vec_bounded(data, limit).map_err(|e| match e {
            fdeflate::BoundedDecompressionError::OutputTooLarge { .. } => format!(
                "inflates to more than the {} settings may be",
                inputs::exact_size(MAX_SETTINGS_TEXT_BYTES)
            ),
            fdeflate::BoundedDecompressionError::DecompressionError { .. } => {
                "is compressed but does not inflate (its data is damaged)".to_owned()
            }
        })
    };
    let latin1 = |bytes: &[u8]| bytes.iter().map(|&b| char::from(b)).collect::<String>();
    match kind {
        b"tEXt" => Ok(latin1(rest)),
        b"zTXt" => match rest.split_first() {
            Some((0, data)) => inflate(data).map(|t: Vec<u8>| latin1(&t)),
            _ => Err("has an unknown compression method".into()),
        },
        _ => {
            // iTXt: compression flag, method, language tag and NUL, translated keyword and NUL.
            let [flag, method, tail @ ..] = rest else {
                return Err("is cut short".into());
            };
            let mut parts = tail.splitn(3, |&b| b == 0);
            let (Some(_language), Some(_translated), Some(text)) =
                (parts.next(), parts.next(), parts.next())
            else {
                return Err("is cut short".into());
            };
            let bytes = match (flag, method) {
                (0, _) => text.to_vec(),
                (1, 0) => inflate(text)?,
                _ => return Err("has an unknown compression method".into()),
            };
            String::from_utf8(bytes)
                .map_err(|e| format!("is not UTF-8 (at byte {})", e.utf8_error().valid_up_to()))
        }
    }
}

/// An error reading a chunk's data: cut short when the file ends inside it.
fn cut_short(e: std::io::Error, offset: u64) -> String {
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        format!("the PNG is cut short in its chunk at byte {offset}")
    } else {
        e.to_string()
    }
}

/// Moves `n` bytes on: read through for a short way (keeping a reader's buffer), sought past
/// for a long one (the image data).
fn skip(r: &mut (impl Read + Seek), n: u64) -> std::io::Result<()> {
    if n <= 64 << 10 {
        std::io::copy(&mut r.take(n), &mut std::io::sink())?;
    } else {
        r.seek(std::io::SeekFrom::Current(n as i64))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    use crate::transport::film::{Image, OutputFormat};

    /// A 4×2 PNG whose chunks are written by `chunks`, given the PNG writer after its header:
    /// text chunks before or after the image data, or both.
    fn png_with(chunks: impl FnOnce(&mut png::Writer<&mut Vec<u8>>)) -> Vec<u8> {
        let mut bytes = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut bytes, 4, 2);
            encoder.set_color(png::ColorType::Rgb);
            let mut writer = encoder.write_header().unwrap();
            chunks(&mut writer);
            writer.finish().unwrap();
        }
        bytes
    }

    fn itxt(text: &str, compressed: bool) -> png::text_metadata::ITXtChunk {
        let mut chunk = png::text_metadata::ITXtChunk::new(PNG_KEYWORD, text);
        chunk.compressed = compressed;
        chunk
    }

    fn text_of(png: &[u8]) -> Result<Option<String>, String> {
        png_text(Cursor::new(png), PNG_KEYWORD)
    }

    const DATA: [u8; 24] = [7; 24];

    /// The settings are found wherever they are (before or after the image data, compressed or
    /// not); what is wrong with them is said, not "not a raylab screenshot".
    #[test]
    fn a_screenshots_settings_are_found_or_what_is_wrong_is_said() {
        let json = "{\"seed\": 5}";
        let before = png_with(|w| {
            w.write_text_chunk(&itxt(json, false)).unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        assert_eq!(text_of(&before).unwrap().as_deref(), Some(json));
        let after = png_with(|w| {
            w.write_image_data(&DATA).unwrap();
            w.write_text_chunk(&itxt(json, true)).unwrap();
        });
        assert_eq!(text_of(&after).unwrap().as_deref(), Some(json));
        let ztxt = png_with(|w| {
            let mut z = png::text_metadata::ZTXtChunk::new(PNG_KEYWORD, json);
            z.compress_text().unwrap();
            w.write_text_chunk(&z).unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        assert_eq!(text_of(&ztxt).unwrap().as_deref(), Some(json));
        let none = png_with(|w| w.write_image_data(&DATA).unwrap());
        assert_eq!(text_of(&none).unwrap(), None);

        // Two settings chunks: which made the image is unclear.
        let two = png_with(|w| {
            w.write_text_chunk(&itxt(json, false)).unwrap();
            w.write_image_data(&DATA).unwrap();
            w.write_text_chunk(&itxt("{}", false)).unwrap();
        });
        assert_eq!(
            text_of(&two).unwrap_err(),
            "it carries two raylab-settings texts (which one made the image is unclear)"
        );
        // A byte of the text changed: its CRC no longer matches.
        let mut damaged = before.clone();
        let at = damaged.windows(4).position(|w| w == b"seed").unwrap();
        damaged[at] = b'z';
        let e = text_of(&damaged).unwrap_err();
        assert!(e.contains("is damaged: its CRC does not match"), "{e}");
        // Text that is not UTF-8 (its CRC made right).
        let latin = png_with(|w| {
            w.write_text_chunk(&itxt("{\"seed\": 5}", false)).unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        let mut bad = latin.clone();
        let at = bad.windows(4).position(|w| w == b"seed").unwrap();
        bad[at] = 0xff;
        fix_crc(&mut bad, b"iTXt");
        let e = text_of(&bad).unwrap_err();
        assert!(e.contains("is not UTF-8 (at byte 2)"), "{e}");
        // Cut short: no end.
        let e = text_of(&before[..before.len() - 12]).unwrap_err();
        assert!(
            e.contains("cut short") && e.contains("no end (IEND)"),
            "{e}"
        );
        assert!(text_of(b"GIF89a").unwrap_err().contains("not a PNG"));
    }

    /// Compressed settings are inflated no further than 1 MiB: a few kilobytes that inflate to
    /// 8 MiB (as 3 MB can inflate to 3 GiB) are refused at once, saying so, and so is an
    /// uncompressed chunk above the cap.
    #[test]
    fn compressed_settings_are_inflated_no_further_than_the_cap() {
        let bomb = " ".repeat(8 << 20);
        let png = png_with(|w| {
            w.write_text_chunk(&itxt(&bomb, true)).unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        assert!(png.len() < 64 << 10, "{} bytes", png.len());
        assert_eq!(
            text_of(&png).unwrap_err(),
            "its raylab-settings text (iTXt) inflates to more than the 1,048,576 bytes (1 MiB) settings may be"
        );
        let big = png_with(|w| {
            w.write_text_chunk(&itxt(&" ".repeat(2 << 20), false))
                .unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        assert!(
            text_of(&big)
                .unwrap_err()
                .contains("more than the 1,048,576 bytes (1 MiB)")
        );
        // Other text chunks of any size are skipped over.
        let other = png_with(|w| {
            let chunk = png::text_metadata::ITXtChunk::new("Comment", " ".repeat(2 << 20));
            w.write_text_chunk(&chunk).unwrap();
            w.write_image_data(&DATA).unwrap();
        });
        assert_eq!(text_of(&other).unwrap(), None);
    }

    /// Recomputes the CRC of the first chunk of `kind` in `png`.
    fn fix_crc(png: &mut [u8], kind: &[u8; 4]) {
        let at = png.windows(4).position(|w| w == kind).unwrap();
        let len = u32::from_be_bytes(png[at - 4..at].try_into().unwrap()) as usize;
        let crc = crc32fast::hash(&png[at..at + 4 + len]);
        png[at + 4 + len..at + 8 + len].copy_from_slice(&crc.to_be_bytes());
    }

    #[test]
    fn a_png_carries_text_that_reads_back_and_still_decodes() {
        let mut image = Image::new(3, 2);
        image.pixels[4] = glam::Vec3::new(1.0, 0.5, 0.25);
        let png = image.encode(OutputFormat::Png).unwrap();
        let png_text = |bytes: &[u8], keyword| png_text(Cursor::new(bytes), keyword);
        assert_eq!(png_text(&png, PNG_KEYWORD).unwrap(), None);
        let text = "{\"seed\": 7, \"é\": \"ü\"}";
        let display = crate::transport::display::Display::default();
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
