//! The film: linear float images, sample accumulation, the lab's display transform, and PNG and
//! EXR output.
//!
//! Pixels stay linear floats until the very end. The display transform is the lab's: each channel
//! clamped to [0, 1], times 255, rounded, with no gamma curve, so a saved PNG shows the lab's
//! figures exactly. EXR keeps the unclamped linear values.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

/// A `width × height` image of linear RGB values, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// The lab's display transform, as 8-bit RGB: see [`to_display_u8`].
    pub fn to_rgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array().map(to_display_u8))
            .collect()
    }

    /// The lab's display transform, as 8-bit RGBA with opaque alpha (what textures take).
    pub fn to_rgba8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| {
                let [r, g, b] = p.to_array().map(to_display_u8);
                [r, g, b, 255]
            })
            .collect()
    }

    /// Writes the image to `path`, as PNG or EXR by its extension (see [`OutputFormat`]).
    ///
    /// The file is written under a temporary name in the same folder and renamed into place, so
    /// a failed write never leaves a half-written image, and an existing file is replaced
    /// whole or not at all.
    pub fn save(&self, path: &Path) -> Result<(), SaveError> {
        let format = OutputFormat::from_path(path)?;
        let bytes = self.encode(format).map_err(|e| SaveError::Encode {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        write_atomically(path, &bytes)
    }

    /// Encodes the image in memory.
    pub fn encode(&self, format: OutputFormat) -> Result<Vec<u8>, image::ImageError> {
        let mut bytes = io::Cursor::new(Vec::new());
        match format {
            OutputFormat::Png => {
                image::RgbImage::from_raw(self.width, self.height, self.to_rgb8())
                    .expect("buffer size matches the image size")
                    .write_to(&mut bytes, image::ImageFormat::Png)?;
            }
            OutputFormat::Exr => {
                let floats = self.pixels.iter().flat_map(|p| p.to_array()).collect();
                image::Rgb32FImage::from_raw(self.width, self.height, floats)
                    .expect("buffer size matches the image size")
                    .write_to(&mut bytes, image::ImageFormat::OpenExr)?;
            }
        }
        Ok(bytes.into_inner())
    }
}

/// The lab's display: clamp to [0, 1], scale to 255, round. NaN shows as 0.
#[allow(clippy::manual_clamp)]
pub fn to_display_u8(linear: f32) -> u8 {
    // `clamp` passes NaN through; `max` first turns it into 0.
    (linear.max(0.0).min(1.0) * 255.0).round() as u8
}

/// Image file formats raylab writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit RGB through the lab's display transform.
    Png,
    /// 32-bit float linear RGB, unclamped (channels R, G, B).
    Exr,
}

impl OutputFormat {
    /// The format named by a path's extension (`.png` or `.exr`, any case).
    pub fn from_path(path: &Path) -> Result<Self, SaveError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            _ => Err(SaveError::UnknownExtension(path.to_owned())),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    #[error("unknown image extension in '{}' (expected .png or .exr)", .0.display())]
    UnknownExtension(PathBuf),
    #[error("could not encode '{}': {message}", path.display())]
    Encode { path: PathBuf, message: String },
    #[error("could not write '{}': {source}", path.display())]
    Write { path: PathBuf, source: io::Error },
}

/// Writes `bytes` to a temporary file beside `path`, then renames it to `path`.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), SaveError> {
    let wrap = |source| SaveError::Write {
        path: path.to_owned(),
        source,
    };
    let name = path
        .file_name()
        .ok_or_else(|| wrap(io::Error::new(io::ErrorKind::InvalidInput, "no file name")))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = BufWriter::new(fs::File::create(&tmp)?);
        file.write_all(bytes)?;
        file.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(wrap)
}

/// Accumulates passes of one view into a running mean (progressive refinement).
#[derive(Clone, Debug)]
pub struct Film {
    sum: Image,
    samples: u32,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            sum: Image::new(width, height),
            samples: 0,
        }
    }

    pub fn width(&self) -> u32 {
        self.sum.width
    }

    pub fn height(&self) -> u32 {
        self.sum.height
    }

    /// Samples per pixel accumulated so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Adds one pass of one sample per pixel.
    pub fn add_pass(&mut self, pass: &Image) {
        assert_eq!((pass.width, pass.height), (self.sum.width, self.sum.height));
        for (s, p) in self.sum.pixels.iter_mut().zip(&pass.pixels) {
            *s += *p;
        }
        self.samples += 1;
    }

    /// The mean of the passes so far (black before the first).
    pub fn resolve(&self) -> Image {
        let scale = if self.samples == 0 {
            0.0
        } else {
            1.0 / self.samples as f32
        };
        Image {
            width: self.sum.width,
            height: self.sum.height,
            pixels: self.sum.pixels.iter().map(|p| *p * scale).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_transform_clamps_and_rounds_without_gamma() {
        assert_eq!(to_display_u8(0.0), 0);
        assert_eq!(to_display_u8(1.0), 255);
        assert_eq!(to_display_u8(7.5), 255);
        assert_eq!(to_display_u8(-2.0), 0);
        assert_eq!(to_display_u8(f32::NAN), 0);
        // 0.5 · 255 = 127.5 rounds to 128; 0.15 · 255 = 38.25 to 38 (no gamma: not 108).
        assert_eq!(to_display_u8(0.5), 128);
        assert_eq!(to_display_u8(0.15), 38);
        assert_eq!(to_display_u8(0.75), 191);
    }

    #[test]
    fn film_averages_passes() {
        let mut film = Film::new(2, 1);
        let mut a = Image::new(2, 1);
        a.pixels = vec![Vec3::splat(1.0), Vec3::ZERO];
        let mut b = Image::new(2, 1);
        b.pixels = vec![Vec3::splat(0.0), Vec3::new(0.5, 1.0, 2.0)];
        film.add_pass(&a);
        film.add_pass(&b);
        assert_eq!(film.samples(), 2);
        assert_eq!(
            film.resolve().pixels,
            vec![Vec3::splat(0.5), Vec3::new(0.25, 0.5, 1.0)]
        );
    }

    #[test]
    fn unknown_extension_is_refused() {
        let err = OutputFormat::from_path(Path::new("out.jpg")).unwrap_err();
        assert!(err.to_string().contains("out.jpg"));
        assert_eq!(
            OutputFormat::from_path(Path::new("A.PNG")).unwrap(),
            OutputFormat::Png
        );
    }
}
