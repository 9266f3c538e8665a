//! Reading a student's render: PNG, BMP (what SDL's `SDL_SaveBMP` writes), PPM/PGM (what a
//! tracer writing its own files often writes) or JPEG, 8 bits a channel.
//!
//! As every input raylab reads ([`crate::base::inputs`]): a regular file only, under a cap on its
//! size; the image's sides are read from its header and checked before anything is decoded,
//! and its channel depth too, so a 16-bit PNG is refused by name rather than quietly rounded
//! (its values would not be the 8-bit figure's).

use std::io::Cursor;
use std::path::Path;

use image::{ColorType, ImageDecoder as _, ImageFormat};

use super::compare::Rgb8;
use super::lossy::Encoding;

/// The largest image file read: 256 MiB, beyond a 4096² BMP (48 MiB) or a PPM written as text.
pub const MAX_IMAGE_FILE_BYTES: u64 = 256 << 20;

/// The largest side of an image checked, in pixels. A check renders a dozen figures at the
/// image's size, each held as 8 bits a channel: at 4096² that is 50 MiB a figure.
pub const MAX_SIDE: u32 = 4096;

/// Why a student's image cannot be checked: one line, naming the file.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("could not check '{path}': {reason}")]
pub struct ReadError {
    pub path: String,
    pub reason: String,
}

/// The image at `path`, as 8-bit RGB (grey images made RGB, alpha dropped: SDL's 32-bit BMPs
/// carry an unused fourth byte).
pub fn read_image(path: &Path) -> Result<Rgb8, ReadError> {
    read_image_encoded(path).map(|(image, _)| image)
}

/// The image at `path` as [`read_image`] reads it, and how it was stored (JPEG is lossy:
/// [`Encoding`]), from its contents, whatever its name.
pub fn read_image_encoded(path: &Path) -> Result<(Rgb8, Encoding), ReadError> {
    let error = |reason: String| ReadError {
        path: path.display().to_string(),
        reason,
    };
    let bytes = crate::base::inputs::read_capped(path, MAX_IMAGE_FILE_BYTES, "an image to check")
        .map_err(error)?;
    decode_encoded(&bytes).map_err(error)
}

/// An image file's bytes as 8-bit RGB; the error is the reason alone.
pub fn decode(bytes: &[u8]) -> Result<Rgb8, String> {
    decode_encoded(bytes).map(|(image, _)| image)
}

/// An image file's bytes as 8-bit RGB, and how they were stored.
pub fn decode_encoded(bytes: &[u8]) -> Result<(Rgb8, Encoding), String> {
    if bytes.is_empty() {
        return Err("the file is empty (0 bytes)".into());
    }
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let encoding = match reader.format() {
        Some(ImageFormat::Jpeg) => Encoding::Jpeg,
        Some(ImageFormat::Png | ImageFormat::Bmp | ImageFormat::Pnm) => Encoding::Lossless,
        Some(other) => {
            return Err(format!(
                "it is a {other:?} image; check reads PNG, BMP, PPM or JPEG"
            ));
        }
        None => return Err("it is not a PNG, BMP, PPM or JPEG image".into()),
    };
    let mut decoder = reader.into_decoder().map_err(|e| e.to_string())?;
    let (width, height) = decoder.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("the image is empty ({width}×{height})"));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "the image is {width}×{height}, larger than the {MAX_SIDE}×{MAX_SIDE} check takes"
        ));
    }
    match decoder.color_type() {
        ColorType::L8 | ColorType::La8 | ColorType::Rgb8 | ColorType::Rgba8 => {}
        other => {
            let bits = other.bits_per_pixel() / u16::from(other.channel_count());
            return Err(format!(
                "it has {bits} bits a channel ({other:?}); check compares 8-bit images, as SDL \
                 saves them: save it with 8 bits a channel"
            ));
        }
    }
    // The sides were checked: what decoding takes is bounded by them (at most 4096² × 4 bytes).
    let mut limits = image::Limits::no_limits();
    limits.max_alloc = Some(u64::from(width) * u64::from(height) * 8 + (1 << 20));
    decoder.set_limits(limits).map_err(|e| e.to_string())?;
    let rgb = image::DynamicImage::from_decoder(decoder)
        .map_err(decoding_failed)?
        .into_rgb8();
    let image = Rgb8 {
        width: rgb.width(),
        height: rgb.height(),
        data: rgb.into_raw(),
    };
    Ok((image, encoding))
}

/// Why the image's data could not be decoded; a file that ends before its image does says so.
fn decoding_failed(e: image::ImageError) -> String {
    match &e {
        image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            format!("the file is cut short: it ends before its image does ({e})")
        }
        _ => e.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encoded(image: &image::DynamicImage, format: ImageFormat) -> Vec<u8> {
        let mut bytes = Cursor::new(Vec::new());
        image.write_to(&mut bytes, format).unwrap();
        bytes.into_inner()
    }

    /// The same 3 × 2 pixels written as PNG, BMP and PPM read back the same; grey becomes RGB.
    #[test]
    fn png_bmp_and_ppm_read_the_same_pixels() {
        let data: Vec<u8> = (0..18).map(|i| i * 14).collect();
        let rgb = image::RgbImage::from_raw(3, 2, data.clone()).unwrap();
        let image = image::DynamicImage::ImageRgb8(rgb);
        for format in [ImageFormat::Png, ImageFormat::Bmp, ImageFormat::Pnm] {
            let got = decode(&encoded(&image, format)).unwrap();
            assert_eq!(
                (got.width, got.height, &got.data),
                (3, 2, &data),
                "{format:?}"
            );
        }
        let grey =
            image::DynamicImage::ImageLuma8(image::GrayImage::from_raw(2, 1, vec![7, 9]).unwrap());
        let got = decode(&encoded(&grey, ImageFormat::Png)).unwrap();
        assert_eq!(got.data, [7, 7, 7, 9, 9, 9]);
        // A PPM written by hand, as a student's tracer might.
        let ppm = b"P3\n2 1\n255\n255 0 0  0 0 255\n";
        assert_eq!(decode(ppm).unwrap().data, [255, 0, 0, 0, 0, 255]);
    }

    #[test]
    fn what_cannot_be_checked_is_refused_with_its_reason() {
        let sixteen = image::DynamicImage::ImageRgb16(image::ImageBuffer::new(4, 4));
        let e = decode(&encoded(&sixteen, ImageFormat::Png)).unwrap_err();
        assert!(e.contains("16 bits a channel"), "{e}");
        assert!(
            decode(b"not an image at all")
                .unwrap_err()
                .contains("not a PNG")
        );
        let gif = b"GIF89a\x01\x00\x01\x00\x00\x00\x00;";
        assert!(decode(gif).unwrap_err().contains("Gif"), "named");
        // A PPM whose header says 5000 × 1: refused before its pixels are read.
        let e = decode(b"P6\n5000 1\n255\n").unwrap_err();
        assert!(e.contains("5000×1") && e.contains("4096"), "{e}");
        let e = decode(b"P6\n0 7\n255\n").unwrap_err();
        assert!(!e.is_empty(), "an empty image is refused: {e}");
        assert_eq!(decode(b"").unwrap_err(), "the file is empty (0 bytes)");
        // A 16-bit PPM (maxval above 255).
        let e = decode(b"P6\n1 1\n65535\n\x00\x01\x00\x02\x00\x03").unwrap_err();
        assert!(e.contains("16 bits"), "{e}");
        // Cut short.
        let png = encoded(
            &image::DynamicImage::ImageRgb8(image::RgbImage::new(8, 8)),
            ImageFormat::Png,
        );
        let e = decode(&png[..png.len() / 2]).unwrap_err();
        assert!(e.starts_with("the file is cut short"), "{e}");
    }

    #[test]
    fn files_are_read_as_every_input_is() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_image(dir.path()).unwrap_err();
        assert!(
            e.to_string().contains("not a regular file (a folder)"),
            "{e}"
        );
        let e = read_image(&dir.path().join("missing.png")).unwrap_err();
        assert!(e.to_string().starts_with("could not check '"), "{e}");
    }
}
