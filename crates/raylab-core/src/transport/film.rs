//! The film: linear float images, sample accumulation, the lab's display transform, and PNG and
//! EXR output.
//!
//! Pixels stay linear floats until the very end. The lab's display transform ([`to_display_u8`])
//! clamps each channel to [0, 1], times 255, rounded, with no gamma curve, so a saved PNG shows
//! the lab's figures exactly; it is the default [`Display`], and the other displays (exposure,
//! sRGB, filmic) live in [`crate::transport::display`]. EXR keeps the unclamped linear values whatever the
//! display.

use std::cell::RefCell;
use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::base::memory::{AllocError, try_vec, with_thread_memory};
use crate::transport::display::Display;
pub use crate::transport::display::to_display_u8;

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

    /// [`Image::new`], reserved with `try_reserve_exact`: an image the allocator will not give
    /// (a 16384² one is 3 GiB) is an error naming its size, not an abort.
    pub fn try_new(width: u32, height: u32) -> Result<Self, AllocError> {
        let len = (width as usize).saturating_mul(height as usize);
        let pixels = try_vec(Vec3::ZERO, len, || format!("the {width}×{height} image"))?;
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// The lab's display transform, as 8-bit RGB: see [`to_display_u8`]. The default
    /// [`Display`]'s [`Display::to_rgb8`], so there is one conversion in the code base.
    pub fn to_rgb8(&self) -> Vec<u8> {
        Display::default().to_rgb8(&self.pixels)
    }

    /// The lab's display transform, as 8-bit RGBA with opaque alpha (what textures take).
    pub fn to_rgba8(&self) -> Vec<u8> {
        Display::default().to_rgba8(&self.pixels)
    }

    /// Writes the image to `path`, as PNG or EXR by its extension (see [`OutputFormat`]),
    /// through the lab's display: [`Image::save_with`] the default [`Display`].
    pub fn save(&self, path: &Path) -> Result<(), SaveError> {
        self.save_with(path, &Display::default())
    }

    /// Writes the image to `path`, as PNG or EXR by its extension (see [`OutputFormat`]). A PNG
    /// goes through `display`; an EXR ignores it and keeps the linear values, before exposure
    /// and curve (the display is a way of looking at the image, not part of it).
    ///
    /// The file is written under a temporary name in the same folder and renamed into place, so
    /// a failed write never leaves a half-written image, and an existing file is replaced
    /// whole or not at all.
    ///
    /// Both formats are encoded straight into the file from the image, a band of rows at a
    /// time: no full-size copy is made, neither an 8-bit one nor one of the floats, nor of the
    /// encoded file (for a 16384² image those were 0.75, 3 and up to 3 GiB more).
    pub fn save_with(&self, path: &Path, display: &Display) -> Result<(), SaveError> {
        self.save_with_text(path, display, None)
    }

    /// [`Image::save_with`], a PNG also carrying `text`, `(keyword, text)`, in an uncompressed
    /// `iTXt` chunk before the image data (readers find it without decoding the image: see
    /// [`crate::files::settings_file::png_text`]). An EXR carries no text.
    pub fn save_with_text(
        &self,
        path: &Path,
        display: &Display,
        text: Option<(&str, &str)>,
    ) -> Result<(), SaveError> {
        let format = OutputFormat::from_path(path)?;
        write_atomically_with(path, |file| {
            self.encode_to(format, display, text, file, path)
        })
    }

    /// Encodes the image in memory, a PNG through the lab's display.
    pub fn encode(&self, format: OutputFormat) -> Result<Vec<u8>, image::ImageError> {
        self.encode_with(format, &Display::default())
    }

    /// Encodes the image in memory: a PNG through `display`, an EXR as linear values (before
    /// exposure and curve: `display` is not used). The bytes [`Image::save_with`] writes.
    pub fn encode_with(
        &self,
        format: OutputFormat,
        display: &Display,
    ) -> Result<Vec<u8>, image::ImageError> {
        self.encode_with_text(format, display, None)
    }

    /// [`Image::encode_with`], a PNG carrying `text` as [`Image::save_with_text`] writes it.
    pub fn encode_with_text(
        &self,
        format: OutputFormat,
        display: &Display,
        text: Option<(&str, &str)>,
    ) -> Result<Vec<u8>, image::ImageError> {
        let mut bytes = io::Cursor::new(Vec::new());
        self.encode_to(format, display, text, &mut bytes, Path::new("memory"))
            .map_err(|e| image::ImageError::IoError(io::Error::other(e.to_string())))?;
        Ok(bytes.into_inner())
    }

    /// Encodes the image into `out` (`path` names it in errors), a PNG with `text`.
    fn encode_to<W: Write + io::Seek>(
        &self,
        format: OutputFormat,
        display: &Display,
        text: Option<(&str, &str)>,
        out: &mut W,
        path: &Path,
    ) -> Result<(), SaveError> {
        let encode = |message: String| SaveError::Encode {
            path: path.to_owned(),
            message,
        };
        let write = |reason| SaveError::Write {
            path: path.to_owned(),
            reason,
        };
        let (width, height) = (self.width as usize, self.height as usize);
        match format {
            OutputFormat::Png => {
                let png_error = |e: png::EncodingError| match e {
                    png::EncodingError::IoError(e) => write(e),
                    e => encode(e.to_string()),
                };
                // As the `image` crate encodes an RGB8 PNG: its default compression and
                // adaptive filtering.
                let mut encoder = png::Encoder::new(out, self.width, self.height);
                encoder.set_color(png::ColorType::Rgb);
                encoder.set_depth(png::BitDepth::Eight);
                encoder.set_compression(png::Compression::Balanced);
                encoder.set_filter(png::Filter::Adaptive);
                if let Some((keyword, text)) = text {
                    encoder
                        .add_itxt_chunk(keyword.to_owned(), text.to_owned())
                        .map_err(png_error)?;
                }
                let mut writer = encoder.write_header().map_err(png_error)?;
                let mut stream = writer.stream_writer().map_err(png_error)?;
                // Bands of about a megapixel (a few MiB of 8-bit rows), converted in parallel.
                let rows = (PNG_BAND_PIXELS / width.max(1)).max(1);
                let mut band = Vec::new();
                for pixels in self.pixels.chunks(rows * width.max(1)) {
                    band.resize(pixels.len() * 3, 0);
                    display.rgb8_into(pixels, &mut band);
                    stream.write_all(&band).map_err(write)?;
                }
                stream.finish().map_err(png_error)?;
                writer.finish().map_err(png_error)
            }
            OutputFormat::Exr => {
                use exr::prelude::{SpecificChannels, Vec2, WritableImage};
                // As the `image` crate writes an RGB 32-bit float EXR, reading the pixels
                // where they are.
                let channels = SpecificChannels::rgb(|at: Vec2<usize>| {
                    let p = self.pixels[at.y() * width + at.x()];
                    (p.x, p.y, p.z)
                });
                exr::image::Image::from_channels((width, height), channels)
                    .write()
                    .to_buffered(out)
                    .map_err(|e| match e {
                        exr::error::Error::Io(e) => write(e),
                        e => encode(e.to_string()),
                    })
            }
        }
    }
}

/// The pixels of a band of rows a PNG is written from, at most (unless one row is longer).
const PNG_BAND_PIXELS: usize = 1 << 20;

/// Image file formats raylab writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit RGB through a display transform (the lab's unless another is given).
    Png,
    /// 32-bit float linear RGB, unclamped, whatever the display (channels R, G, B).
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
    /// The OS's reason is in the message and is not also the error's source, so a chain of
    /// errors printed whole says it once.
    #[error("could not write '{}': {reason}", path.display())]
    Write { path: PathBuf, reason: io::Error },
}

/// Checks, before any work, that an image could be written to `path`: its format is known,
/// it does not name a folder, and a file can be created in its folder (created and removed
/// again). A render that could not be saved is refused before it starts.
pub fn check_writable(path: &Path) -> Result<(), SaveError> {
    OutputFormat::from_path(path)?;
    check_file_destination(path)
}

/// [`check_writable`] for any file: `path` does not name a folder, and a file can be created
/// in its folder (a temporary one, created exclusively under a random name and removed again).
pub fn check_file_destination(path: &Path) -> Result<(), SaveError> {
    let fail = |reason| SaveError::Write {
        path: path.to_owned(),
        reason,
    };
    if path.is_dir() {
        return Err(fail(io::Error::new(
            io::ErrorKind::IsADirectory,
            "it is a folder",
        )));
    }
    let probe = temporary_beside(path, ".check").map_err(fail)?;
    drop(probe);
    Ok(())
}

/// The longest file name the temporary files are given, in bytes: the limit of Linux's file
/// systems and macOS's (`NAME_MAX`), whatever the name of the file they become.
const MAX_NAME_BYTES: usize = 255;

/// The random part of a temporary file's name: `XXXXXX`.
const RANDOM_CHARS: usize = 6;

/// A new, empty file in `path`'s folder named `.NAME.XXXXXX{suffix}` (`XXXXXX` random),
/// created exclusively: never through a symbolic link, never an existing file. It is removed
/// when dropped unless persisted. Its permissions are those `File::create` gives (0666 less
/// the umask), so the file it becomes is like any other the user writes.
///
/// `NAME` is cut short, at a character's end, where the whole would pass [`MAX_NAME_BYTES`]:
/// a destination's name may take all 255 bytes. The name stays unique by its random part and
/// the file stays in the destination's folder, so the rename into place is still atomic.
fn temporary_beside(path: &Path, suffix: &str) -> io::Result<tempfile::NamedTempFile> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no file name"))?;
    let folder = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let room = MAX_NAME_BYTES - ".".len() - ".".len() - RANDOM_CHARS - suffix.len();
    let mut prefix = std::ffi::OsString::from(".");
    prefix.push(name_cut_to(name, room));
    prefix.push(".");
    let mut builder = tempfile::Builder::new();
    builder
        .prefix(&prefix)
        .rand_bytes(RANDOM_CHARS)
        .suffix(suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        builder.permissions(fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(folder)
}

/// `name`'s first `bytes` bytes at most, ending where a character ends when it is UTF-8.
fn name_cut_to(name: &std::ffi::OsStr, bytes: usize) -> std::ffi::OsString {
    let whole = name.as_encoded_bytes();
    if whole.len() <= bytes {
        return name.to_owned();
    }
    let end = match name.to_str() {
        Some(text) => text.floor_char_boundary(bytes),
        None => bytes,
    };
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt as _;
        std::ffi::OsStr::from_bytes(&whole[..end]).to_owned()
    }
    #[cfg(not(unix))]
    {
        // Elsewhere names are Unicode: a name that is not is left as it is.
        match name.to_str() {
            Some(text) => text[..end].into(),
            None => name.to_owned(),
        }
    }
}

/// Writes `bytes` to a temporary file beside `path`, then renames it to `path`.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), SaveError> {
    write_atomically_with(path, |file| {
        file.write_all(bytes).map_err(|reason| SaveError::Write {
            path: path.to_owned(),
            reason,
        })
    })
}

/// Has `write` write a temporary file beside `path` (buffered), then renames it to `path`; the
/// temporary file is removed if anything fails. The temporary file is made by
/// [`temporary_beside`]: a random name, created exclusively, so a file or link planted beside
/// the destination is never written through. While it exists it is on the program's list of
/// files to remove if a signal stops the program ([`crate::base::temp_files`]).
pub fn write_atomically_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&fs::File>) -> Result<(), SaveError>,
) -> Result<(), SaveError> {
    let wrap = |reason| SaveError::Write {
        path: path.to_owned(),
        reason,
    };
    let tmp = temporary_beside(path, ".tmp").map_err(wrap)?;
    let _registered = crate::base::temp_files::register(tmp.path());
    {
        let mut file = BufWriter::new(tmp.as_file());
        write(&mut file)?;
        file.flush().map_err(wrap)?;
    }
    pause_for_tests();
    tmp.as_file().sync_all().map_err(wrap)?;
    // On failure the temporary file comes back in the error, and is removed when dropped.
    tmp.persist(path).map_err(|e| wrap(e.error))?;
    Ok(())
}

/// Test hook: where the environment variable `RAYLAB_TEST_PAUSE_WRITE` names a file, a write
/// stops once its bytes are in the temporary file, before the rename: it creates that file
/// (the sign a test waits for) and sleeps for a minute. So `tests/interrupt.rs` stops a write
/// in progress every time, not when a sleep happens to land in it.
fn pause_for_tests() {
    if let Some(sign) = std::env::var_os("RAYLAB_TEST_PAUSE_WRITE") {
        let _ = fs::write(sign, b"");
        std::thread::sleep(std::time::Duration::from_secs(60));
    }
}

/// Writes `bytes` to a file that did not exist: at `path`, or, if something is there, at the
/// first free name `STEM-1.EXT`, `STEM-2.EXT`, … beside it (as screenshots are named); nothing
/// is ever replaced. The text is written once to a temporary file, then linked to the first
/// free name atomically (no other program can take the name in between, and a name taken by
/// a link is never written through). Returns the path written.
pub fn write_to_free_name(path: &Path, bytes: &[u8]) -> Result<PathBuf, SaveError> {
    let wrap = |at: &Path, reason| SaveError::Write {
        path: at.to_owned(),
        reason,
    };
    let mut tmp = temporary_beside(path, ".tmp").map_err(|e| wrap(path, e))?;
    let registered = crate::base::temp_files::register(tmp.path());
    tmp.write_all(bytes).map_err(|e| wrap(path, e))?;
    tmp.as_file().sync_all().map_err(|e| wrap(path, e))?;
    let stem = path.file_stem().unwrap_or_default();
    let extension = path.extension();
    for n in 0..10_000u32 {
        let candidate = if n == 0 {
            path.to_path_buf()
        } else {
            let mut name = stem.to_owned();
            name.push(format!("-{n}"));
            if let Some(e) = extension {
                name.push(".");
                name.push(e);
            }
            path.with_file_name(name)
        };
        match tmp.persist_noclobber(&candidate) {
            Ok(_) => {
                drop(registered);
                return Ok(candidate);
            }
            Err(e) if e.error.kind() == io::ErrorKind::AlreadyExists => tmp = e.file,
            Err(e) => return Err(wrap(&candidate, e.error)),
        }
    }
    Err(wrap(
        path,
        io::Error::new(
            io::ErrorKind::AlreadyExists,
            "no free name like it (-1 to -9999) beside it",
        ),
    ))
}

/// What one camera sample sees, apart from the light: the denoiser's features
/// ([`crate::transport::denoise::Features`] averages them per pixel). The first surface that is not a
/// perfect specular one, or the one reached after
/// [`crate::transport::integrator::FEATURE_SPECULAR_BOUNCES`] mirror and glass bounces, with the tints of
/// those before it, as Open Image Denoise asks of its auxiliary images: a mirror shows the
/// features of what it reflects.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Seen {
    /// The reflectance seen (each channel at most 1), times the tints on the way.
    pub albedo: Vec3,
    /// The shading normal, turned to the side the viewer is on: a wall seen from behind and
    /// from the front are one surface to the filter.
    pub normal: Vec3,
    /// The distance along the path to the surface.
    pub depth: f32,
}

impl Seen {
    /// A surface of reflectance `albedo` and shading normal `normal`, reached along the
    /// direction `-wo` after `depth` of path whose mirrors and glass tinted it by `tint`.
    #[inline]
    pub fn at(tint: Vec3, albedo: Vec3, normal: Vec3, wo: Vec3, depth: f32) -> Seen {
        Seen {
            albedo: tint * albedo.min(Vec3::ONE),
            normal: if normal.dot(wo) < 0.0 {
                -normal
            } else {
                normal
            },
            depth,
        }
    }
}

/// A pixel's sums of what its samples saw ([`Seen`]), added in the order of the samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SeenSum {
    /// Over every sample (one that left the scene adds 0).
    pub albedo: Vec3,
    /// Over the samples that hit something, as `depth`.
    pub normal: Vec3,
    pub depth: f32,
    /// The samples that hit something.
    pub hits: u32,
}

impl SeenSum {
    /// Adds what one sample saw (`None`: nothing).
    #[inline]
    pub fn add(&mut self, seen: Option<Seen>) {
        if let Some(seen) = seen {
            self.albedo += seen.albedo;
            self.normal += seen.normal;
            self.depth += seen.depth;
            self.hits += 1;
        }
    }
}

/// Accumulates passes of one view into a running mean (progressive refinement), and, if asked,
/// the sum of squares that estimates how noisy that mean still is ([`Film::noise`]) and the
/// sums of what the samples saw, the denoiser's features ([`Film::with_features`]).
#[derive(Clone, Debug)]
pub struct Film {
    sum: Image,
    /// Per pixel, the sum of the squared sample values (the mean of the three channels), when
    /// the noise is tracked.
    sum_sq: Option<Vec<f32>>,
    /// Per pixel, what its first samples saw, when the features are recorded.
    seen: Option<Vec<SeenSum>>,
    /// Per pixel, its brightest sample so far (the largest mean of the three channels; the
    /// first of equals), when the film keeps it ([`Film::with_largest`]).
    largest: Option<Vec<Vec3>>,
    /// The samples `seen` sums, up to [`FEATURE_SAMPLES_RECORDED`].
    seen_samples: u32,
    samples: u32,
}

/// A film's per-pixel sums ([`Film::sums`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmSums<'a> {
    pub sum: &'a [Vec3],
    pub sum_sq: Option<&'a [f32]>,
    pub largest: Option<&'a [Vec3]>,
    pub samples: u32,
}

/// The samples whose features a film records ([`Film::with_features`]), the first of its
/// passes. Recording costs a path pass a second look at each camera ray's first surface
/// (PERFORMANCE.md); the features of the first 64 samples are what the denoiser needs (its
/// tests and PERFORMANCE.md, "The denoiser"), and later samples would add little.
pub const FEATURE_SAMPLES_RECORDED: u32 = 64;

/// How far the accumulated image may still be from the converged one, estimated from the
/// spread of each pixel's samples (the sample variance s², over n samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseEstimate {
    /// The standard error of the image's mean value over its mean value:
    /// √(Σᵢ sᵢ²/n) / Σᵢ mᵢ, pixels taken as independent.
    pub relative_error_of_mean: f64,
    /// The share of pixels whose own relative standard error, sᵢ/√n / mᵢ, is above 1% (a pixel
    /// that is black with no spread counts as converged; black with spread, as above).
    pub share_of_pixels_above_1_percent: f64,
    /// The relative error of the image as a whole: the RMS over pixels of each pixel's
    /// standard error over the RMS of the pixel values, √(Σᵢ sᵢ²/n / Σᵢ mᵢ²). What a user
    /// sees as grain, relative to the image's brightness; dark pixels, whose own relative error
    /// is large however little they show, do not dominate it as they would an RMS of sᵢ/mᵢ.
    /// It falls as 1/√n, so it says how many more samples a clean image needs
    /// ([`NoiseEstimate::samples_to_reach`], [`NoiseEstimate::seconds_to_reach`]): on the
    /// path-traced box its prediction holds from the first few samples on, while the share of
    /// pixels above 1 % still reads high when the image as a whole is there.
    pub relative_rms_error: f64,
}

/// The pixels [`Film::noise`] sums in one block (64 KiB of sums).
const NOISE_BLOCK: usize = 1 << 12;

/// The relative RMS error at which an image looks clean: grain of 1 % is below what the eye
/// picks out of a rendered image's own texture.
pub const CLEAN_RELATIVE_ERROR: f64 = 0.01;

impl NoiseEstimate {
    /// The samples per pixel at which [`NoiseEstimate::relative_rms_error`] falls to `goal`,
    /// from `samples` now: the error falls as 1/√n, so n·(error/goal)² (`samples` if it is
    /// there already).
    pub fn samples_to_reach(&self, samples: u32, goal: f64) -> f64 {
        let ratio = self.relative_rms_error / goal;
        f64::from(samples) * (ratio * ratio).max(1.0)
    }

    /// The time left until [`NoiseEstimate::relative_rms_error`] falls to `goal`, in the unit
    /// of `elapsed` (the time the samples so far took): each sample takes as long as the ones
    /// before, so elapsed·((error/goal)² − 1); 0 once there.
    pub fn seconds_to_reach(&self, goal: f64, elapsed: f64) -> f64 {
        let ratio = self.relative_rms_error / goal;
        elapsed * (ratio * ratio - 1.0).max(0.0)
    }
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            sum: Image::new(width, height),
            sum_sq: None,
            seen: None,
            largest: None,
            seen_samples: 0,
            samples: 0,
        }
    }

    /// This film, also summing what each of its first [`FEATURE_SAMPLES_RECORDED`] samples saw
    /// ([`Seen`]: 32 more bytes per pixel) as the passes added with [`Film::add_pass_rows`]
    /// tell it; [`Film::seen`] gives the sums.
    pub fn with_features(self) -> Self {
        let len = self.sum.pixels.len();
        Self {
            seen: Some(vec![SeenSum::default(); len]),
            ..self
        }
    }

    /// Per pixel, the sums of what its samples saw, and how many samples they sum, if the film
    /// records them ([`Film::with_features`]).
    pub fn seen(&self) -> Option<(&[SeenSum], u32)> {
        Some((self.seen.as_deref()?, self.seen_samples))
    }

    /// This film, also keeping each pixel's brightest sample (12 more bytes per pixel): what
    /// the denoiser takes apart as an outlier ([`crate::transport::denoise::Noisy`]).
    pub fn with_largest(self) -> Self {
        let len = self.sum.pixels.len();
        Self {
            largest: Some(vec![Vec3::ZERO; len]),
            ..self
        }
    }

    /// Per pixel, the sum of its samples, the sum of their squared channel means (if the film
    /// tracks the noise) and its brightest sample (if it keeps it), with the samples summed:
    /// what the denoiser's outlier test reads ([`crate::transport::denoise::Noisy`]).
    pub fn sums(&self) -> FilmSums<'_> {
        FilmSums {
            sum: &self.sum.pixels,
            sum_sq: self.sum_sq.as_deref(),
            largest: self.largest.as_deref(),
            samples: self.samples,
        }
    }

    /// Whether the next pass's samples are to tell what they saw ([`Film::add_pass_rows`]).
    pub fn records_seen(&self) -> bool {
        self.seen.is_some() && self.seen_samples < FEATURE_SAMPLES_RECORDED
    }

    /// A film that also tracks the spread of each pixel's samples, for [`Film::noise`] (four
    /// more bytes per pixel).
    pub fn with_noise(width: u32, height: u32) -> Self {
        Self {
            sum_sq: Some(vec![0.0; width as usize * height as usize]),
            ..Self::new(width, height)
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
        if let Some(sum_sq) = &mut self.sum_sq {
            for (s, p) in sum_sq.iter_mut().zip(&pass.pixels) {
                let y = channel_mean(*p);
                *s += y * y;
            }
        }
        if let Some(largest) = &mut self.largest {
            keep_largest(largest, &pass.pixels, self.samples == 0);
        }
        self.samples += 1;
    }

    /// Adds one pass traced a row at a time, rows in parallel on the current rayon pool:
    /// `trace(y, row, seen)` puts row `y`'s values in `row` (one image row long) and, if the
    /// film records this pass's features ([`Film::records_seen`]), what each pixel's sample
    /// saw in `seen` (as long as `row`; empty if it does not). The same sums as [`Film::add_pass`] of the image those rows make,
    /// without making that image (no full-size allocation a pass, and the adding done by the
    /// pool's threads while each row is still in cache). An error from `trace` stops the pass
    /// and is returned: the film then holds part of the pass, and is to be dropped.
    pub fn add_pass_rows<E: Send>(
        &mut self,
        trace: impl Fn(u32, &mut [Vec3], &mut [Option<Seen>]) -> Result<(), E> + Sync + Send,
    ) -> Result<(), E> {
        use rayon::prelude::*;
        let width = (self.sum.width as usize).max(1);
        let rows = self.sum.pixels.len().div_ceil(width);
        let recording = self.records_seen();
        let seen_width = if recording { width } else { 0 };
        // A sum the film does not track zips in as empty rows.
        let sum_sq = self.sum_sq.as_deref_mut().unwrap_or_default();
        let seen_sums = match recording {
            true => self.seen.as_deref_mut().unwrap_or_default(),
            false => Default::default(),
        };
        let largest = self.largest.as_deref_mut().unwrap_or_default();
        let first = self.samples == 0;
        self.sum
            .pixels
            .par_chunks_mut(width)
            .zip(par_rows(sum_sq, width, rows))
            .zip(par_rows(seen_sums, width, rows))
            .zip(par_rows(largest, width, rows))
            .enumerate()
            .with_max_len(rows_per_job())
            .try_for_each(|(y, (((sum, sum_sq), seen_sums), largest))| {
                with_row_buffers(width, seen_width, |row, seen| {
                    trace(y as u32, row, seen)?;
                    for (s, p) in sum.iter_mut().zip(row.iter()) {
                        *s += *p;
                    }
                    for (q, p) in sum_sq.iter_mut().zip(row.iter()) {
                        let y = channel_mean(*p);
                        *q += y * y;
                    }
                    for (sums, seen) in seen_sums.iter_mut().zip(seen.iter()) {
                        sums.add(*seen);
                    }
                    keep_largest(largest, row, first);
                    Ok(())
                })
            })?;
        self.samples += 1;
        self.seen_samples += u32::from(recording);
        Ok(())
    }

    /// The estimated remaining noise, from two samples on, if the film tracks it.
    pub fn noise(&self) -> Option<NoiseEstimate> {
        let sum_sq = self.sum_sq.as_ref()?;
        if self.samples < 2 {
            return None;
        }
        use rayon::prelude::*;
        // Summed in parallel on the current rayon pool, in blocks of a fixed size whose sums
        // are added in order: the same figures whatever the thread count.
        let partials: Vec<[f64; 4]> = self
            .sum
            .pixels
            .par_chunks(NOISE_BLOCK)
            .zip(sum_sq.par_chunks(NOISE_BLOCK))
            .map(|(sums, sum_sq)| {
                let mut block = [0.0f64; 4];
                for (s, &sq) in sums.iter().zip(sum_sq) {
                    let (mean, variance_of_mean) = mean_and_variance_of_mean(*s, sq, self.samples);
                    block[0] += mean;
                    block[1] += mean * mean;
                    block[2] += variance_of_mean;
                    let error = variance_of_mean.sqrt();
                    if error > 0.01 * mean.abs() && error > 1e-12 {
                        block[3] += 1.0;
                    }
                }
                block
            })
            .collect();
        let [sum_mean, sum_mean_sq, sum_var_of_mean, above] =
            partials.iter().fold([0.0f64; 4], |total, block| {
                std::array::from_fn(|i| total[i] + block[i])
            });
        let pixels = self.sum.pixels.len().max(1) as f64;
        Some(NoiseEstimate {
            relative_error_of_mean: if sum_mean > 0.0 {
                sum_var_of_mean.sqrt() / sum_mean
            } else {
                0.0
            },
            share_of_pixels_above_1_percent: above / pixels,
            relative_rms_error: if sum_mean_sq > 0.0 {
                (sum_var_of_mean / sum_mean_sq).sqrt()
            } else {
                0.0
            },
        })
    }

    /// Per pixel, the variance of its mean value (the mean of R, G and B): s²/n, where s² is
    /// the sample variance of its n samples. How far each pixel may still be from its converged
    /// value: where it is large, more samples help most. From two samples on, if the film
    /// tracks the noise ([`Film::with_noise`]).
    pub fn variance(&self) -> Option<Vec<f32>> {
        let sum_sq = self.sum_sq.as_ref()?;
        if self.samples < 2 {
            return None;
        }
        Some(
            self.sum
                .pixels
                .iter()
                .zip(sum_sq)
                .map(|(s, &sq)| mean_and_variance_of_mean(*s, sq, self.samples).1 as f32)
                .collect(),
        )
    }

    /// The mean of the passes so far (black before the first).
    pub fn resolve(&self) -> Image {
        let scale = if self.samples == 0 {
            0.0
        } else {
            1.0 / self.samples as f32
        };
        use rayon::prelude::*;
        // On the current rayon pool: the workbench resolves a frame on its render threads.
        Image {
            width: self.sum.width,
            height: self.sum.height,
            pixels: self.sum.pixels.par_iter().map(|p| *p * scale).collect(),
        }
    }
}

/// The image rows a job of the rayon pool traces at most: one when the pool has threads to
/// share them, so that a thread that runs out of rows takes the next one from another's
/// share. Left to rayon's own splitting, a pass is cut into a few long runs of rows, each
/// traced to its end by one thread; the path stage's rows differ in cost, so on two threads
/// one thread finishes first and waits while the other ends its run (PERFORMANCE.md,
/// "Design choices and what each buys"). On one thread there is no one to share with, and a job a
/// row only adds each job's own cost: there, rayon's own splitting.
pub(crate) fn rows_per_job() -> usize {
    match rayon::current_num_threads() {
        1 => usize::MAX,
        _ => 1,
    }
}

thread_local! {
    /// A thread's row and its samples' features, for [`Film::add_pass_rows`]: made once a
    /// thread, not once a job, which is a row on two threads.
    static ROW_BUFFERS: RefCell<(Vec<Vec3>, Vec<Option<Seen>>)> = const {
        RefCell::new((Vec::new(), Vec::new()))
    };
}

/// `work` with a row of `width` values and `seen_width` features to write into: this
/// thread's [`ROW_BUFFERS`], or fresh ones if they are in use (never, unless a row were
/// added inside another's tracing). The row holds what the last row left, for `work` to
/// overwrite; the features are all `None`, for those `work` does not tell.
fn with_row_buffers<T>(
    width: usize,
    seen_width: usize,
    work: impl FnOnce(&mut [Vec3], &mut [Option<Seen>]) -> T,
) -> T {
    with_thread_memory(&ROW_BUFFERS, Default::default, |(row, seen)| {
        row.resize(width, Vec3::ZERO);
        seen.clear();
        seen.resize(seen_width, None);
        work(&mut row[..width], &mut seen[..seen_width])
    })
}

/// `buffer`'s rows of `width` values in parallel, or `rows` empty rows if it is empty.
fn par_rows<T: Send>(
    buffer: &mut [T],
    width: usize,
    rows: usize,
) -> impl rayon::iter::IndexedParallelIterator<Item = &mut [T]> {
    use rayon::iter::{Either, IntoParallelIterator, ParallelIterator};
    use rayon::slice::ParallelSliceMut;
    if buffer.is_empty() {
        Either::Right((0..rows).into_par_iter().map(|_| <&mut [T]>::default()))
    } else {
        Either::Left(buffer.par_chunks_mut(width))
    }
}

/// A pixel's mean value and the variance of that mean, s²/n, from the sum of its `n` samples
/// and the sum of their squared channel means.
pub(crate) fn mean_and_variance_of_mean(sum: Vec3, sum_sq: f32, n: u32) -> (f64, f64) {
    let n = f64::from(n);
    let mean = f64::from(channel_mean(sum)) / n;
    // s² = (Σy² − n·m²)/(n − 1); rounding can make it slightly negative.
    let variance = ((f64::from(sum_sq) - n * mean * mean) / (n - 1.0)).max(0.0);
    (mean, variance / n)
}

/// Each of `largest` replaced by the sample of `pass` beside it where that is brighter (by
/// channel mean), or in any case for the `first` pass.
fn keep_largest(largest: &mut [Vec3], pass: &[Vec3], first: bool) {
    for (l, p) in largest.iter_mut().zip(pass) {
        if first || channel_mean(*p) > channel_mean(*l) {
            *l = *p;
        }
    }
}

/// The mean of a value's three channels: the scalar whose spread the noise estimate follows.
pub(crate) fn channel_mean(p: Vec3) -> f32 {
    (p.x + p.y + p.z) * (1.0 / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A film that keeps its brightest samples keeps, per pixel, the sample of the largest
    /// channel mean (the first of equals), whether a pass comes as an image or row by row.
    #[test]
    fn a_film_keeps_each_pixels_brightest_sample() {
        let passes = [
            [Vec3::new(0.3, 0.0, 0.0), Vec3::splat(2.0)],
            [Vec3::new(0.0, 0.2, 0.0), Vec3::new(9.0, 0.0, 0.0)],
            [Vec3::new(0.0, 0.0, 0.9), Vec3::splat(1.0)],
        ];
        let mut whole = Film::with_noise(2, 1).with_largest();
        let mut rows = Film::with_noise(2, 1).with_largest();
        for pass in passes {
            let image = Image {
                width: 2,
                height: 1,
                pixels: pass.to_vec(),
            };
            whole.add_pass(&image);
            let result: Result<(), ()> = rows.add_pass_rows(|_, row, _| {
                row.copy_from_slice(&pass);
                Ok(())
            });
            result.unwrap();
        }
        let sums = whole.sums();
        assert_eq!(sums.samples, 3);
        assert_eq!(
            sums.largest,
            Some(&[Vec3::new(0.0, 0.0, 0.9), Vec3::new(9.0, 0.0, 0.0)][..])
        );
        assert_eq!(rows.sums(), whole.sums());
        assert_eq!(Film::with_noise(2, 1).sums().largest, None);
    }

    /// A film with features sums what its first [`FEATURE_SAMPLES_RECORDED`] samples saw (a
    /// sample that saw nothing adds to the albedo's count only), and asks the later passes for
    /// nothing.
    #[test]
    fn a_film_sums_what_its_first_samples_saw() {
        let mut film = Film::new(2, 1).with_features();
        let asked = std::sync::atomic::AtomicU32::new(0);
        for pass in 0..FEATURE_SAMPLES_RECORDED + 6 {
            let result: Result<(), ()> = film.add_pass_rows(|_, row, seen| {
                row.fill(Vec3::ONE);
                if !seen.is_empty() {
                    asked.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    seen[0] = Some(Seen::at(
                        Vec3::ONE,
                        Vec3::splat(0.5),
                        -Vec3::Z,
                        Vec3::Z,
                        2.0,
                    ));
                    seen[1] = (pass % 2 == 0).then_some(seen[0].unwrap());
                }
                Ok(())
            });
            result.unwrap();
        }
        assert_eq!(asked.into_inner(), FEATURE_SAMPLES_RECORDED);
        let (sums, samples) = film.seen().unwrap();
        assert_eq!(samples, FEATURE_SAMPLES_RECORDED);
        let n = FEATURE_SAMPLES_RECORDED as f32;
        // The normal turned toward the viewer (+z); the second pixel saw something every
        // other sample.
        let all = SeenSum {
            albedo: Vec3::splat(0.5 * n),
            normal: Vec3::Z * n,
            depth: 2.0 * n,
            hits: FEATURE_SAMPLES_RECORDED,
        };
        assert_eq!(sums[0], all);
        assert_eq!(sums[1].hits, FEATURE_SAMPLES_RECORDED / 2);
        assert_eq!(sums[1].albedo, Vec3::splat(0.25 * n));
        assert_eq!(film.samples(), FEATURE_SAMPLES_RECORDED + 6);
        assert!(Film::new(2, 1).seen().is_none());
    }

    /// A sample whose row's trace tells nothing adds nothing, whatever the row traced before
    /// it on the same thread told, and every row is added once: on a pool of one thread (the
    /// rows in order, rayon's own splitting) and of two (a job a row). Row 0 saw a surface
    /// in both pixels, row 1 was not told.
    #[test]
    fn a_row_adds_only_what_its_own_trace_told() {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut film = Film::new(2, 8).with_features();
            let result: Result<(), ()> = pool.install(|| {
                film.add_pass_rows(|y, row, seen| {
                    row.fill(Vec3::splat(y as f32));
                    if y == 0 {
                        seen.fill(Some(Seen::at(Vec3::ONE, Vec3::ONE, Vec3::Z, Vec3::Z, 1.0)));
                    }
                    Ok(())
                })
            });
            result.unwrap();
            let (sums, _) = film.seen().unwrap();
            assert_eq!(sums[0].hits, 1, "{threads} thread(s)");
            assert_eq!(sums[1].hits, 1, "{threads} thread(s)");
            for (i, sum) in sums.iter().enumerate().skip(2) {
                assert_eq!(*sum, SeenSum::default(), "pixel {i}, {threads} thread(s)");
            }
            let image = film.resolve();
            for (i, pixel) in image.pixels.iter().enumerate() {
                assert_eq!(*pixel, Vec3::splat((i / 2) as f32), "pixel {i}");
            }
        }
    }

    /// Two pixels over four passes, by hand. Pixel 0 is constant 1: no spread. Pixel 1 takes
    /// 1, 3, 1, 3 (grey): mean 2, s² = (1+1+1+1)/3 = 4/3, its mean's variance s²/n = 1/3, so
    /// its relative error is √(1/3)/2 = 0.2887 (> 1%). The image mean's relative error is
    /// √(0 + 1/3) / (1 + 2) = 0.19245; half the pixels are above 1%. The image's relative RMS
    /// error is √((0 + 1/3) / (1² + 2²)) = √(1/15) = 0.258199: 1 % needs
    /// 4 · 25.8199² = 4 · 666.67 = 2666.7 samples, and if the 4 took 2 s, 1 % is
    /// 2 · (666.67 − 1) = 1331.3 s away.
    #[test]
    fn noise_estimate_by_hand() {
        let mut film = Film::with_noise(2, 1);
        assert_eq!(film.noise(), None, "nothing yet");
        for v in [1.0, 3.0, 1.0, 3.0] {
            let mut pass = Image::new(2, 1);
            pass.pixels = vec![Vec3::ONE, Vec3::splat(v)];
            film.add_pass(&pass);
        }
        let noise = film.noise().unwrap();
        assert!(
            (noise.relative_error_of_mean - 0.19245).abs() < 1e-5,
            "{noise:?}"
        );
        assert_eq!(noise.share_of_pixels_above_1_percent, 0.5);
        assert!(
            (noise.relative_rms_error - 0.258199).abs() < 1e-6,
            "{noise:?}"
        );
        let to_1_percent = noise.samples_to_reach(4, CLEAN_RELATIVE_ERROR);
        assert!((to_1_percent - 2666.67).abs() < 0.01, "{to_1_percent}");
        let seconds = noise.seconds_to_reach(CLEAN_RELATIVE_ERROR, 2.0);
        assert!((seconds - 1331.33).abs() < 0.01, "{seconds}");
        // Already below the goal: the samples so far, and no time left.
        assert_eq!(noise.samples_to_reach(4, 0.5), 4.0);
        assert_eq!(noise.seconds_to_reach(0.5, 2.0), 0.0);
        assert_eq!(Film::new(2, 1).noise(), None, "not tracked");
    }

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

    /// The rounding without `round` equals `round`: for every `f32` (4.3 billion values, some
    /// seconds in release: `cargo test --release -- --ignored every_f32`), and here for those
    /// whose scaled value sits at or next to a half.
    #[test]
    fn display_rounding_equals_round_at_every_half() {
        #[allow(clippy::manual_clamp)]
        let round = |x: f32| (x.max(0.0).min(1.0) * 255.0).round() as u8;
        for k in 0..=255u32 {
            let half = (k as f32 + 0.5) / 255.0;
            for bits in half.to_bits() - 3..=half.to_bits() + 3 {
                let x = f32::from_bits(bits);
                assert_eq!(to_display_u8(x), round(x), "{x}");
            }
        }
    }

    #[test]
    #[ignore]
    fn display_rounding_equals_round_for_every_f32() {
        use rayon::prelude::*;
        #[allow(clippy::manual_clamp)]
        let round = |x: f32| (x.max(0.0).min(1.0) * 255.0).round() as u8;
        let mismatches = (0..=u32::MAX)
            .into_par_iter()
            .filter(|&bits| to_display_u8(f32::from_bits(bits)) != round(f32::from_bits(bits)))
            .count();
        assert_eq!(mismatches, 0);
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

    /// An image too large to exist is an error naming it, not an abort.
    #[test]
    fn an_impossible_image_is_an_error() {
        let e = Image::try_new(u32::MAX, u32::MAX).unwrap_err();
        assert_eq!(
            e.to_string(),
            "could not allocate the 4294967295×4294967295 image: it is too large"
        );
        assert_eq!(Image::try_new(3, 2).unwrap(), Image::new(3, 2));
    }

    /// A PNG and an EXR written a band of rows at a time, of an image taller than one band
    /// (1500 × 800 pixels, a band is 1,048,576 / 1500 = 699 rows): the file holds the bytes
    /// `encode_with` gives, and decodes to the display's bytes and the linear values.
    #[test]
    fn images_are_written_band_by_band_whole() {
        let (w, h) = (1500u32, 800u32);
        let mut image = Image::new(w, h);
        for (i, p) in image.pixels.iter_mut().enumerate() {
            let (x, y) = ((i % w as usize) as f32, (i / w as usize) as f32);
            *p = Vec3::new(x / w as f32, y / h as f32, 1.5 - x / w as f32);
        }
        let dir = tempfile::tempdir().unwrap();
        let display = Display {
            transform: crate::transport::display::DisplayTransform::Srgb,
            exposure: 0.5,
        };
        let png = dir.path().join("bands.png");
        image.save_with(&png, &display).unwrap();
        let bytes = fs::read(&png).unwrap();
        assert_eq!(
            bytes,
            image.encode_with(OutputFormat::Png, &display).unwrap()
        );
        let decoded = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (w, h));
        assert_eq!(decoded.into_raw(), display.to_rgb8(&image.pixels));
        let exr = dir.path().join("bands.exr");
        image.save(&exr).unwrap();
        let back = image::open(&exr).unwrap().to_rgb32f().into_raw();
        let want: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
        assert_eq!(back, want);
        // Only the two images: no temporary file is left.
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    /// A destination whose name takes all 255 bytes a name may have gets a temporary file
    /// whose name fits too (its own name cut short at a character's end), and is written.
    #[test]
    fn the_temporary_name_fits_whatever_the_destinations_length() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            format!("{}.png", "a".repeat(251)),
            format!("{}.png", "é".repeat(125)),
            "x.png".to_owned(),
        ] {
            let out = dir.path().join(&name);
            for suffix in [".tmp", ".check"] {
                let tmp = temporary_beside(&out, suffix).unwrap();
                let made = tmp.path().file_name().unwrap().to_str().unwrap().to_owned();
                assert!(made.len() <= MAX_NAME_BYTES, "{} bytes", made.len());
                assert!(made.ends_with(suffix), "{made}");
                let kept = made.trim_start_matches('.').split('.').next().unwrap();
                assert!(name.starts_with(kept), "{made}");
            }
            write_atomically(&out, b"image").unwrap();
            assert_eq!(fs::read(&out).unwrap(), b"image");
        }
        assert_eq!(
            fs::read_dir(dir.path()).unwrap().count(),
            3,
            "no temporary file left"
        );
    }

    /// The temporary file an image is written to has a random name, made afresh for each
    /// write and created exclusively: a link planted where the old, predictable name
    /// (`.NAME.PID.tmp`) pointed is never written through, and nothing is left beside the
    /// image. Its permissions are an ordinary file's, not the 0600 of `tempfile`'s default.
    #[test]
    fn the_temporary_file_is_unpredictable_and_never_followed() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("x.png");
        let a = temporary_beside(&out, ".tmp").unwrap();
        let b = temporary_beside(&out, ".tmp").unwrap();
        assert_ne!(a.path(), b.path());
        for t in [&a, &b] {
            let name = t.path().file_name().unwrap().to_string_lossy().into_owned();
            assert!(
                name.starts_with(".x.png.") && name.ends_with(".tmp"),
                "{name}"
            );
            assert!(name.len() > ".x.png..tmp".len() + 5, "{name}");
        }
        drop((a, b));
        assert!(
            fs::read_dir(dir.path()).unwrap().next().is_none(),
            "removed when dropped"
        );

        let victim = dir.path().join("victim.txt");
        fs::write(&victim, "keep me").unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(
            &victim,
            dir.path()
                .join(format!(".x.png.{}.tmp", std::process::id())),
        )
        .unwrap();
        Image::new(4, 2).save(&out).unwrap();
        assert_eq!(fs::read_to_string(&victim).unwrap(), "keep me");
        assert_eq!(image::open(&out).unwrap().width(), 4);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            let mode = fs::metadata(&out).unwrap().permissions().mode() & 0o777;
            let plain = dir.path().join("plain");
            fs::File::create(&plain).unwrap();
            let plain_mode = fs::metadata(&plain).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, plain_mode, "{mode:o}");
        }
        // The image, the victim, the link (and the plain file): no temporary file.
        let left: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp") && !n.contains(&std::process::id().to_string()))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    /// A file written to a free name never replaces one: the second and third writes to one
    /// name go to `-1` and `-2`, a name held by a link (even a dangling one) is skipped, not
    /// written through, and no temporary file is left.
    #[test]
    fn a_free_name_is_found_and_nothing_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.toml");
        assert_eq!(write_to_free_name(&path, b"one").unwrap(), path);
        #[cfg(unix)]
        std::os::unix::fs::symlink(dir.path().join("elsewhere"), dir.path().join("s-1.toml"))
            .unwrap();
        let second = write_to_free_name(&path, b"two").unwrap();
        let third = write_to_free_name(&path, b"three").unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "one");
        if cfg!(unix) {
            assert_eq!(second, dir.path().join("s-2.toml"));
            assert_eq!(third, dir.path().join("s-3.toml"));
            assert!(
                !dir.path().join("elsewhere").exists(),
                "the link was not followed"
            );
        } else {
            assert_eq!(second, dir.path().join("s-1.toml"));
        }
        assert_eq!(fs::read_to_string(&second).unwrap(), "two");
        assert_eq!(fs::read_to_string(&third).unwrap(), "three");
        let names: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
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

    /// A PNG goes through the display given; an EXR keeps the linear values whatever it is.
    #[test]
    fn png_through_the_display_exr_linear() {
        use crate::transport::display::DisplayTransform;
        let mut image = Image::new(3, 1);
        image.pixels = vec![Vec3::new(0.25, 0.5, 2.0), Vec3::splat(0.18), Vec3::ZERO];
        // The default is the lab's display, byte for byte as before it was a `Display`.
        let lab: Vec<u8> = image
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(to_display_u8))
            .collect();
        assert_eq!(image.to_rgb8(), lab);
        assert_eq!(
            image.encode(OutputFormat::Png).unwrap(),
            image
                .encode_with(OutputFormat::Png, &Display::default())
                .unwrap()
        );
        let srgb = Display {
            transform: DisplayTransform::Srgb,
            exposure: 1.0,
        };
        let png = image.encode_with(OutputFormat::Png, &srgb).unwrap();
        let decoded = image::load_from_memory(&png).unwrap().to_rgb8().into_raw();
        // 0.25 and 0.5 at +1 EV: 0.5 → 188 and 1 → 255; 0.18 → 0.36 → 0.634253 → 161.73 → 162.
        assert_eq!(decoded, [188, 255, 255, 162, 162, 162, 0, 0, 0]);
        assert_eq!(decoded, srgb.to_rgb8(&image.pixels));
        let exr = image.encode_with(OutputFormat::Exr, &srgb).unwrap();
        assert_eq!(exr, image.encode(OutputFormat::Exr).unwrap());
        let back = image::load_from_memory(&exr)
            .unwrap()
            .to_rgb32f()
            .into_raw();
        assert_eq!(back[..3], [0.25, 0.5, 2.0]);
    }
}
