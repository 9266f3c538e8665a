//! Textures: a reflectance ρ that varies over a surface (one of the lab's extensions).
//!
//! A diffuse [`crate::Material`] may carry a [`Texture`]; where it does, ρ at a hit is the
//! texture's value at the hit's texture coordinates instead of the material's constant
//! reflectance. Coordinates come from the mesh (an OBJ's `vt`, interpolated by the hit's
//! barycentric u, v) or, for surfaces without them such as the Cornell box's walls, from a
//! planar projection of the hit position ([`planar_uv`]).
//!
//! Texture coordinates follow OBJ files: u goes right across an image and v goes **up**, so
//! v = 0 is the image's bottom row and v = 1 its top. Every texture repeats with period 1 in
//! both directions, so any finite (u, v) has a value; a non-finite one gets a fixed value
//! rather than a panic, since one bad hit must not stop a render.

use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::base::noise::Fbm;

/// A reflectance that varies with the texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// Squares of side `1/scale` in texture space, alternating between two colours: the
    /// square holding (u, v) is (⌊u·scale⌋, ⌊v·scale⌋), `colours[0]` where the sum of those
    /// two integers is even and `colours[1]` where it is odd.
    Checker { scale: f32, colours: [Vec3; 2] },
    /// Lines every `1/scale` in u and in v, each centred on a multiple of `1/scale` and
    /// `line_width` wide (as a fraction of a cell), on a background.
    Grid {
        scale: f32,
        line_width: f32,
        background: Vec3,
        line: Vec3,
    },
    /// An image, looked up with bilinear filtering and wrapping ([`TextureImage::bilinear`]).
    Image(Arc<TextureImage>),
    /// Clouds: fBm noise at `uv · scale`, taken from [−1, 1] to [0, 1], blends from `sky` to
    /// `cloud` over [`cover`, `cover` + 0.3] (a larger cover, fewer clouds).
    Clouds {
        noise: Fbm,
        scale: f32,
        sky: Vec3,
        cloud: Vec3,
        cover: f32,
    },
    /// A landscape's colours by height and slope ([`terrain_colour`]): grass, rock where
    /// steep, snow up high, their borders broken up by fBm `noise`. Looked up by position and
    /// normal, not texture coordinates.
    Terrain {
        /// The y of the ground the heights are measured from (raylab's y points down).
        floor: f32,
        /// The height that counts as the top.
        height: f32,
        noise: Fbm,
    },
}

/// The terrain's grass, rock and snow (linear reflectances).
pub const GRASS: Vec3 = Vec3::new(0.18, 0.38, 0.10);
pub const ROCK: Vec3 = Vec3::new(0.42, 0.38, 0.33);
pub const SNOW: Vec3 = Vec3::new(0.85, 0.87, 0.90);

/// 0 below `a`, 1 above `b`, and 3t² − 2t³ between.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The colour of a landscape at `position` with unit normal `normal`: its altitude
/// a = (floor − y)/height (0 on the ground, 1 at the top) and steepness s = 1 − |n_y| (0 flat,
/// 1 a cliff), the noise n ∈ [−1, 1] at the point's (x, z) moving each border a little:
/// rock takes over from grass for s from 0.3 to 0.5 (+ 0.08·n), and snow lies above
/// a = 0.4 (+ 0.08·n) where s is under about 0.5.
pub fn terrain_colour(floor: f32, height: f32, noise: &Fbm, position: Vec3, normal: Vec3) -> Vec3 {
    let altitude = ((floor - position.y) / height).clamp(0.0, 1.0);
    let steep = 1.0 - normal.y.abs().min(1.0);
    let n = noise.at(Vec2::new(position.x, position.z) * 6.0);
    let rock = smoothstep(0.3, 0.5, steep + 0.08 * n);
    let snow_line = 0.4 + 0.08 * n;
    let snow = smoothstep(snow_line - 0.04, snow_line + 0.04, altitude)
        * (1.0 - smoothstep(0.45, 0.6, steep));
    let ground = GRASS + (ROCK - GRASS) * rock;
    ground + (SNOW - ground) * snow
}

impl Texture {
    /// ρ at texture coordinates `uv`.
    ///
    /// A non-finite `uv` gives `colours[1]` for a checker (the parity test fails on NaN), the
    /// background for a grid and black for an image: a fixed value, never a panic.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Checker { scale, colours } => {
                let p = (uv * *scale).floor();
                // rem_euclid, not %: the cell left of u = 0 is −1, which is odd.
                let parity = (p.x + p.y).rem_euclid(2.0);
                if parity < 1.0 { colours[0] } else { colours[1] }
            }
            Texture::Grid {
                scale,
                line_width,
                background,
                line,
            } => {
                // Where in its cell (u, v) lies, in [0, 1] also for negative coordinates.
                let f = (uv * *scale).fract_gl();
                let half = 0.5 * line_width;
                let on_line = f.x < half || f.x > 1.0 - half || f.y < half || f.y > 1.0 - half;
                if on_line { *line } else { *background }
            }
            Texture::Image(image) => image.bilinear(uv),
            Texture::Clouds {
                noise,
                scale,
                sky,
                cloud,
                cover,
            } => {
                let n = 0.5 * noise.at(uv * *scale) + 0.5;
                *sky + (*cloud - *sky) * smoothstep(*cover, *cover + 0.3, n)
            }
            // Without a position: the ground's colour.
            Texture::Terrain { .. } => GRASS,
        }
    }

    /// ρ at a hit: at `position` with unit `normal`, and texture coordinates `uv` (computed
    /// only for the textures that use them).
    #[inline]
    pub fn at(&self, uv: impl FnOnce() -> Vec2, position: Vec3, normal: Vec3) -> Vec3 {
        match self {
            Texture::Terrain {
                floor,
                height,
                noise,
            } => terrain_colour(*floor, *height, noise, position, normal),
            _ => self.eval(uv()),
        }
    }
}

/// A texture image in linear RGB (decoded from sRGB when loaded from a PNG or JPEG).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    /// The file it came from, for messages.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Linear RGB, rows top to bottom (as stored in image files), `width × height` of them.
    pub texels: Vec<Vec3>,
}

/// Why a texture image could not be loaded; the message names the file.
#[derive(Debug, thiserror::Error)]
#[error("could not load texture '{name}': {reason}")]
pub struct TextureError {
    pub name: String,
    pub reason: String,
}

/// What an image's 8-bit values stand for, and so how they are decoded into texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decoding {
    /// A colour (a reflectance ρ): sRGB, decoded to linear RGB with the exact curve.
    Colour,
    /// A tangent-space normal map, RGB = (n + 1)/2 as OpenGL and Blender write them: each
    /// channel c becomes (c − 128)/127, clamped to [−1, 1] (the 8-bit signed-normalised
    /// reading), so the 128 a flat map is written with is exactly 0 and a flat texel
    /// (128, 128, 255) is exactly (0, 0, 1). Not sRGB: a direction is not a colour.
    Normal,
    /// A height map: c/255 in each channel (its red channel is the height; a grey image has
    /// the same in all three).
    Height,
}

impl Decoding {
    /// What the image is, for messages.
    pub fn what(self) -> &'static str {
        match self {
            Decoding::Colour => "texture",
            Decoding::Normal => "normal map",
            Decoding::Height => "height map",
        }
    }

    /// The value of each 8-bit channel value.
    fn table(self) -> [f32; 256] {
        match self {
            Decoding::Colour => srgb8_to_linear_table(),
            Decoding::Normal => std::array::from_fn(|c| ((c as f32 - 128.0) / 127.0).max(-1.0)),
            Decoding::Height => std::array::from_fn(|c| c as f32 / 255.0),
        }
    }

    /// The value of a 16-bit channel value: the same readings with 65535 for 255 (the sRGB
    /// curve at c/65535; (c − 32768)/32767, so that 32768 is exactly 0; c/65535).
    fn value16(self, c: u16) -> f32 {
        match self {
            Decoding::Colour => srgb_to_linear(f64::from(c) / 65535.0),
            Decoding::Normal => ((f32::from(c) - 32768.0) / 32767.0).max(-1.0),
            Decoding::Height => f32::from(c) / 65535.0,
        }
    }
}

impl TextureImage {
    /// The largest width or height accepted. A texture is held as 12-byte linear texels, so
    /// even this is 3 GiB at full size; the limit stops a corrupt or hostile header from
    /// asking for far more before anything is decoded.
    pub const MAX_SIDE: u32 = 16384;

    /// The most memory decoding a texture takes, per texel: the linear texels (12 bytes)
    /// beside the RGB copy they are made from (3 bytes, or 6 at 16 bits a channel); before
    /// that, the decoded image (at most 8 bytes: 16-bit RGBA) beside that copy. At most 18 at
    /// any moment, so 20.
    pub const DECODING_BYTES_PER_TEXEL: u64 = 20;

    /// The memory decoding a `width × height` texture takes at most, not counting its file.
    pub fn decoding_bytes(width: u32, height: u32) -> u64 {
        u64::from(width) * u64::from(height) * Self::DECODING_BYTES_PER_TEXEL
    }

    /// Loads a PNG or JPEG file (a regular file of at most
    /// [`crate::base::inputs::MAX_TEXTURE_FILE_BYTES`]).
    pub fn load(path: &Path) -> Result<Self, TextureError> {
        Self::load_as(path, Decoding::Colour)
    }

    /// [`Self::load`] with the file's values decoded as `decoding` says (a colour, a normal
    /// map's directions or a height map's heights).
    pub fn load_as(path: &Path, decoding: Decoding) -> Result<Self, TextureError> {
        let name = path.display().to_string();
        let bytes = crate::base::inputs::read_capped(
            path,
            crate::base::inputs::MAX_TEXTURE_FILE_BYTES,
            "a texture",
        )
        .map_err(|reason| TextureError {
            name: name.clone(),
            reason,
        })?;
        Self::from_encoded_as(&bytes, &name, decoding)
    }

    /// The width and height a texture file's header gives, without decoding it; `None` if it
    /// is not a regular file or not a PNG or JPEG whose header can be read. For the memory
    /// estimate ([`crate::shapes::scene::SceneSpec::memory_estimate`]).
    pub fn dimensions(path: &Path) -> Option<(u32, u32)> {
        let (file, _) = crate::base::inputs::open_regular(path).ok()?;
        let reader = image::ImageReader::new(std::io::BufReader::new(file))
            .with_guessed_format()
            .ok()?;
        match reader.format() {
            Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => {
                reader.into_dimensions().ok()
            }
            _ => None,
        }
    }

    /// Decodes a PNG or JPEG held in memory; `name` names it in errors.
    ///
    /// The file's values are taken as sRGB (8 or 16 bits a channel, each read at its own
    /// precision) and turned into linear RGB with the exact sRGB decoding curve, since ρ multiplies light
    /// and light adds linearly. Alpha is ignored: a texture here is a reflectance, not a cut-out.
    /// The size is read from the header and checked (1 to [`Self::MAX_SIDE`] a side) before
    /// the pixels are decoded, and so is the memory decoding takes
    /// ([`Self::decoding_bytes`], against [`crate::base::memory::available`]).
    pub fn from_encoded(bytes: &[u8], name: &str) -> Result<Self, TextureError> {
        Self::from_encoded_as(bytes, name, Decoding::Colour)
    }

    /// [`Self::from_encoded`] with the values decoded as `decoding` says.
    pub fn from_encoded_as(
        bytes: &[u8],
        name: &str,
        decoding: Decoding,
    ) -> Result<Self, TextureError> {
        Self::from_encoded_within(bytes, name, crate::base::memory::available(), decoding)
    }

    /// [`Self::from_encoded_as`] with the memory there is given.
    fn from_encoded_within(
        bytes: &[u8],
        name: &str,
        available: Option<crate::base::memory::Available>,
        decoding: Decoding,
    ) -> Result<Self, TextureError> {
        let error = |reason: String| TextureError {
            name: name.to_owned(),
            reason,
        };
        let reader = || {
            let reader = image::ImageReader::new(Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| error(e.to_string()))?;
            match reader.format() {
                Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => Ok(reader),
                Some(other) => Err(error(format!(
                    "{other:?} images are not supported (PNG or JPEG only)"
                ))),
                None => Err(error("not a PNG or JPEG image".into())),
            }
        };
        let (width, height) = reader()?
            .into_dimensions()
            .map_err(|e| error(e.to_string()))?;
        check_size(width, height).map_err(error)?;
        // What decoding takes is known from the header: refused before it is asked of the
        // allocator (a 782 KB PNG of 16384² decodes to 4 GiB), rather than aborting.
        crate::base::memory::check_against(
            format!("decoding the {width}×{height} texture"),
            Self::decoding_bytes(width, height),
            available,
        )
        .map_err(|e| error(e.to_string()))?;

        let mut decoder = reader()?;
        // The size was checked above; the decoder's default 512 MiB cap would otherwise
        // refuse large textures within it. Its allocations are still bounded by the memory
        // the process may use, so one it cannot have is an error, not an abort.
        let mut limits = image::Limits::no_limits();
        limits.max_alloc = available.map(|a| a.bytes);
        decoder.limits(limits);
        let decoded = decoder.decode().map_err(|e| error(e.to_string()))?;
        let colour = decoded.color();
        let texel_count = width as usize * height as usize;
        let allocate = || {
            crate::base::memory::try_with_capacity(texel_count, || {
                format!("the {width}×{height} texture's texels")
            })
            .map_err(|e| error(e.to_string()))
        };
        // 16 bits a channel are read at 16 bits (the precision a map is saved with them for),
        // 8 bits through a table. The decoded image is gone before the texels are made.
        let texels = if colour.bytes_per_pixel() > colour.channel_count() {
            let rgb = decoded.into_rgb16();
            let mut texels: Vec<Vec3> = allocate()?;
            texels.extend(rgb.pixels().map(|p| {
                Vec3::new(
                    decoding.value16(p[0]),
                    decoding.value16(p[1]),
                    decoding.value16(p[2]),
                )
            }));
            texels
        } else {
            let rgb = decoded.into_rgb8();
            let table = decoding.table();
            let mut texels: Vec<Vec3> = allocate()?;
            texels.extend(rgb.pixels().map(|p| {
                Vec3::new(
                    table[p[0] as usize],
                    table[p[1] as usize],
                    table[p[2] as usize],
                )
            }));
            texels
        };
        Self::from_linear(name, width, height, texels)
    }

    /// An image from linear RGB texels, rows top to bottom; refused unless there are exactly
    /// `width × height` of them and each side is 1 to [`Self::MAX_SIDE`].
    pub fn from_linear(
        name: &str,
        width: u32,
        height: u32,
        texels: Vec<Vec3>,
    ) -> Result<Self, TextureError> {
        let error = |reason: String| TextureError {
            name: name.to_owned(),
            reason,
        };
        check_size(width, height).map_err(error)?;
        let expected = width as usize * height as usize;
        if texels.len() != expected {
            return Err(error(format!(
                "{} texels for a {width}×{height} image (expected {expected})",
                texels.len()
            )));
        }
        Ok(Self {
            name: name.to_owned(),
            width,
            height,
            texels,
        })
    }

    /// The value at texture coordinates `uv`, filtered bilinearly and repeating in both
    /// directions.
    ///
    /// u goes right and v goes **up**, as in OBJ files: v = 0 is the bottom row of the image
    /// and v = 1 the top. Texel (i, j), counting columns from the left and rows from the
    /// bottom, has its centre at ((i + 0.5)/width, (j + 0.5)/height); between centres the four
    /// nearest texels are mixed by distance, and past the edges the lookup wraps, so the
    /// left edge u = 0 is half the first column and half the last. Any finite `uv` works
    /// (negative, or many periods away); a non-finite one, or an image whose texels do not
    /// match its size (the fields are public), gives black.
    pub fn bilinear(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as usize, self.height as usize);
        if !uv.is_finite() || w == 0 || h == 0 || w.checked_mul(h) != Some(self.texels.len()) {
            return Vec3::ZERO;
        }
        let (i0, i1, fx) = wrap(uv.x, w);
        let (j0, j1, fy) = wrap(uv.y, h);
        // Row j counted from the bottom is row h − 1 − j of the stored, top-first rows.
        let at = |i: usize, j: usize| self.texels[(h - 1 - j) * w + i];
        let bottom = at(i0, j0).lerp(at(i1, j0), fx);
        let top = at(i0, j1).lerp(at(i1, j1), fx);
        bottom.lerp(top, fy)
    }
}

/// For coordinate `t` on an axis of `n` texels: the texel at or before `t`, the one after it
/// (wrapping), and how far `t` is from the first towards the second, in [0, 1).
fn wrap(t: f32, n: usize) -> (usize, usize, f32) {
    // The fraction in f64: exact for any f32, so t and t + k (k whole) wrap alike when the
    // f32 sum itself is exact.
    let t = f64::from(t);
    let x = (t - t.floor()) * n as f64 - 0.5; // texel centres at whole numbers; in [−0.5, n − 0.5]
    let x0 = x.floor();
    let i0 = (x0 as i64).rem_euclid(n as i64) as usize;
    (i0, (i0 + 1) % n, (x - x0) as f32)
}

/// Refuses an empty image or one over [`TextureImage::MAX_SIDE`] a side.
fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        Err(format!("the image is empty ({width}×{height})"))
    } else if width > TextureImage::MAX_SIDE || height > TextureImage::MAX_SIDE {
        Err(format!(
            "{width}×{height} is too large (at most {} pixels a side)",
            TextureImage::MAX_SIDE
        ))
    } else {
        Ok(())
    }
}

/// The sRGB decoding curve for each 8-bit value: c = value/255, then c/12.92 for
/// c ≤ 0.04045 and ((c + 0.055)/1.055)^2.4 above (computed in f64, rounded once to f32).
fn srgb8_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|i| srgb_to_linear(i as f64 / 255.0))
}

/// The exact sRGB decoding curve at `c` in [0, 1].
fn srgb_to_linear(c: f64) -> f32 {
    let linear = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    linear as f32
}

/// Texture coordinates for a surface without its own: the hit position projected on the plane
/// the normal is most nearly perpendicular to, one scene unit to one unit of texture space.
///
/// | largest normal component | u | v |
/// |---|---|---|
/// | x (ties go to x) | z | y |
/// | y (ties with z go to y) | x | z |
/// | z | x | y |
///
/// The sign of the normal does not matter, so the two sides of a wall match. raylab's y points
/// down, so on the walls v grows downwards: an image texture there appears upside down, which
/// a repeating pattern such as [`Texture::Checker`] does not show.
pub fn planar_uv(position: Vec3, normal: Vec3) -> Vec2 {
    let a = normal.abs();
    if a.x >= a.y && a.x >= a.z {
        Vec2::new(position.z, position.y)
    } else if a.y >= a.z {
        Vec2::new(position.x, position.z)
    } else {
        Vec2::new(position.x, position.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The landscape's colours at the ends of its ramps, where the noise cannot move a border
    /// (it moves each by at most 0.08): flat ground on the floor is grass, a cliff low down is
    /// rock, flat ground at the top is snow, a cliff at the top is rock (snow does not hold
    /// there); between, a blend of the two.
    #[test]
    fn terrain_colours_by_height_and_slope() {
        let noise = Fbm::default();
        let at = |y: f32, normal: Vec3| {
            terrain_colour(
                1.0,
                0.9,
                &noise,
                Vec3::new(0.3, y, -0.2),
                normal.normalize(),
            )
        };
        let up = Vec3::new(0.0, -1.0, 0.0);
        let cliff = Vec3::new(1.0, 0.0, 0.0);
        assert_eq!(at(1.0, up), GRASS);
        assert_eq!(at(1.0, cliff), ROCK);
        assert_eq!(at(1.0 - 0.9, up), SNOW);
        assert_eq!(at(1.0 - 0.9, cliff), ROCK);
        // Half-way up a 45° slope: steepness 1 − cos 45° = 0.29, at most 0.37 with the noise,
        // so some rock in the grass, no snow at altitude 0.2.
        let c = at(1.0 - 0.18, Vec3::new(1.0, -1.0, 0.0));
        for k in 0..3 {
            let (lo, hi) = (GRASS[k].min(ROCK[k]), GRASS[k].max(ROCK[k]));
            assert!((lo..=hi).contains(&c[k]), "{c}");
        }
        // Looked up by position, whatever the texture coordinates.
        let t = Texture::Terrain {
            floor: 1.0,
            height: 0.9,
            noise,
        };
        assert_eq!(
            t.at(|| Vec2::new(9.0, 9.0), Vec3::new(0.0, 1.0, 0.0), up),
            GRASS
        );
    }

    /// Clouds are the sky where the noise (taken to [0, 1]) is under the cover, the cloud's
    /// colour where it is 0.3 above it, a blend between; the cover decides how much is sky.
    #[test]
    fn clouds_follow_the_noise() {
        let noise = Fbm::default();
        let (sky, cloud) = (Vec3::new(0.1, 0.7, 0.7), Vec3::splat(0.9));
        let t = Texture::Clouds {
            noise,
            scale: 2.0,
            sky,
            cloud,
            cover: 0.3,
        };
        let (mut skies, mut clouds) = (0, 0);
        for i in 0..2000 {
            let uv = Vec2::new(i as f32 * 0.0137, (i % 53) as f32 * 0.031);
            let n = 0.5 * noise.at(uv * 2.0) + 0.5;
            let got = t.eval(uv);
            if n <= 0.3 {
                assert_eq!(got, sky);
                skies += 1;
            } else if n >= 0.6 {
                assert_eq!(got, cloud);
                clouds += 1;
            } else {
                assert!(got.x > sky.x && got.x < cloud.x, "{got}");
            }
        }
        assert!(skies >= 10 && clouds >= 10, "{skies} {clouds}");
    }

    /// A PNG whose header says 16384² (782 KB of black can decode to 4 GiB
    /// of texels; the header alone is what is read before decoding). Decoding is refused
    /// when the memory is not there: an error saying both sizes (a warning when loading a
    /// model), never an abort. The estimate reads the same size from the file.
    #[test]
    fn a_texture_too_large_for_the_memory_is_refused_before_decoding() {
        let side = TextureImage::MAX_SIDE;
        let mut png = Vec::new();
        {
            let mut encoder = png::Encoder::new(&mut png, side, side);
            encoder.set_color(png::ColorType::Grayscale);
            // The header, a few bytes of image data (what is read before decoding stops at
            // its start), then (when the writer is dropped) the end.
            let mut writer = encoder.write_header().unwrap();
            writer.write_chunk(png::chunk::IDAT, &[0; 8]).unwrap();
            drop(writer);
        }
        let limit = crate::base::memory::Available {
            bytes: 3 << 30,
            limit: "address-space limit: ulimit -v",
        };
        let e = TextureImage::from_encoded_within(&png, "huge.png", Some(limit), Decoding::Colour)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "could not load texture 'huge.png': decoding the 16384×16384 texture needs about \
             5.0 GiB but only 3.0 GiB is available (address-space limit: ulimit -v)"
        );
        assert_eq!(TextureImage::decoding_bytes(side, side), 5 << 30);
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("huge.png");
        std::fs::write(&file, &png).unwrap();
        assert_eq!(TextureImage::dimensions(&file), Some((side, side)));
        assert_eq!(TextureImage::dimensions(dir.path()), None);
    }

    const BLACK: Vec3 = Vec3::ZERO;
    const WHITE: Vec3 = Vec3::ONE;

    fn grey(v: f32) -> Vec3 {
        Vec3::splat(v)
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    /// A 2×2 image of greys, rows top to bottom:
    ///
    /// ```text
    ///   top    (j = 1):  2  4     centres at v = 0.75
    ///   bottom (j = 0):  0  1     centres at v = 0.25
    ///                    ^  ^ centres at u = 0.25, 0.75
    /// ```
    fn two_by_two() -> TextureImage {
        let texels = [2.0, 4.0, 0.0, 1.0].map(grey).to_vec();
        TextureImage::from_linear("2x2", 2, 2, texels).unwrap()
    }

    fn encode(image: image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
        let mut bytes = Cursor::new(Vec::new());
        image.write_to(&mut bytes, format).unwrap();
        bytes.into_inner()
    }

    #[test]
    fn checker_squares_are_where_the_floor_puts_them() {
        let checker = Texture::Checker {
            scale: 4.0,
            colours: [BLACK, WHITE],
        };
        // Scale 4: squares 0.25 wide. (u, v) → (⌊4u⌋, ⌊4v⌋) → sum → colour.
        let cases = [
            ((0.1, 0.1), BLACK),   // (0, 0): 0, even
            ((0.3, 0.1), WHITE),   // (1, 0): 1, odd
            ((0.1, 0.3), WHITE),   // (0, 1): 1, odd
            ((0.3, 0.3), BLACK),   // (1, 1): 2, even
            ((0.6, 0.1), BLACK),   // (2, 0): 2, even
            ((-0.1, 0.1), WHITE),  // (−1, 0): −1, odd
            ((-0.1, -0.1), BLACK), // (−1, −1): −2, even
            ((-0.3, 0.1), BLACK),  // (−2, 0): −2, even
            ((0.25, 0.0), WHITE),  // on a corner: (1, 0), the square up and to the right
            ((10.1, 0.1), BLACK),  // 4 · 10.1 = 40.4: (40, 0), even
            ((10.3, 0.1), WHITE),  // 4 · 10.3 = 41.2: (41, 0), odd
        ];
        for ((u, v), want) in cases {
            assert_eq!(checker.eval(Vec2::new(u, v)), want, "uv ({u}, {v})");
        }
    }

    #[test]
    fn grid_lines_sit_on_the_cell_borders() {
        let grid = Texture::Grid {
            scale: 4.0,
            line_width: 0.1,
            background: BLACK,
            line: WHITE,
        };
        // Cells 0.25 wide; a line covers 0.05 of a cell either side of each border.
        // (0.01, 0.125): within the cell (0.04, 0.5): 0.04 < 0.05, on the line at u = 0.
        assert_eq!(grid.eval(Vec2::new(0.01, 0.125)), WHITE);
        // (0.125, 0.125): (0.5, 0.5), the middle of a cell.
        assert_eq!(grid.eval(Vec2::new(0.125, 0.125)), BLACK);
        // (−0.01, 0.125): 4 · −0.01 = −0.04 → 0.96 > 0.95, the same line from the other side.
        assert_eq!(grid.eval(Vec2::new(-0.01, 0.125)), WHITE);
        // (0.125, 0.74): (0.5, 0.96), the line at v = 0.75.
        assert_eq!(grid.eval(Vec2::new(0.125, 0.74)), WHITE);
    }

    #[test]
    fn bilinear_mixes_the_four_nearest_texels() {
        let image = two_by_two();
        // On a centre, that texel alone; v = 0.25 is the bottom row.
        assert_eq!(image.bilinear(Vec2::new(0.25, 0.25)), grey(0.0));
        assert_eq!(image.bilinear(Vec2::new(0.75, 0.25)), grey(1.0));
        assert_eq!(image.bilinear(Vec2::new(0.25, 0.75)), grey(2.0));
        assert_eq!(image.bilinear(Vec2::new(0.75, 0.75)), grey(4.0));
        // Midway between the four centres: (0 + 1 + 2 + 4)/4 = 1.75.
        assert_eq!(image.bilinear(Vec2::new(0.5, 0.5)), grey(1.75));
        // (0.375, 0.625): x = 0.375·2 − 0.5 = 0.25 of the way right, y = 0.625·2 − 0.5 = 0.75
        // of the way up. Weights 0.75·0.25 (bottom left, 0), 0.25·0.25 (bottom right, 1),
        // 0.75·0.75 (top left, 2), 0.25·0.75 (top right, 4):
        // 0 + 0.0625 + 1.125 + 0.75 = 1.9375.
        assert_eq!(image.bilinear(Vec2::new(0.375, 0.625)), grey(1.9375));
        // Through Texture::eval too.
        let texture = Texture::Image(Arc::new(image));
        assert_eq!(texture.eval(Vec2::new(0.375, 0.625)), grey(1.9375));
    }

    #[test]
    fn lookups_wrap_in_both_directions() {
        let image = two_by_two();
        // Dyadic coordinates: uv + (1, −2) is exact in f32, so the value is too.
        let uv = Vec2::new(0.375, 0.625);
        assert_eq!(
            image.bilinear(uv),
            image.bilinear(uv + Vec2::new(1.0, -2.0))
        );
        assert_eq!(
            image.bilinear(uv),
            image.bilinear(uv + Vec2::new(-7.0, 12.0))
        );
        // Others only as closely as f32 holds 1.3 and −1.3.
        let uv = Vec2::new(0.3, 0.7);
        let shifted = image.bilinear(uv + Vec2::new(1.0, -2.0));
        assert!(close(image.bilinear(uv), shifted, 1e-5));

        // One row of four: 0 1 2 3, centres at u = 0.125, 0.375, 0.625, 0.875.
        let row = TextureImage::from_linear("row", 4, 1, [0.0, 1.0, 2.0, 3.0].map(grey).to_vec())
            .unwrap();
        // u = 0 lies halfway between the last centre (0.875 − 1) and the first: (3 + 0)/2.
        assert_eq!(row.bilinear(Vec2::new(0.0, 0.5)), grey(1.5));
        assert_eq!(row.bilinear(Vec2::new(1.0, 0.5)), grey(1.5));
        assert_eq!(row.bilinear(Vec2::new(-3.0, 0.5)), grey(1.5));
        // u = 1/16: x = 0.25 − 0.5 = −0.25, 0.75 of the way from the last column to the first:
        // 3 + 0.75·(0 − 3) = 0.75.
        assert_eq!(row.bilinear(Vec2::new(0.0625, 0.5)), grey(0.75));
        // u = 15/16, from the other side: x = 3.25, 0.25 of the way from 3 to 0: 2.25.
        assert_eq!(row.bilinear(Vec2::new(0.9375, 0.5)), grey(2.25));
        // One row: every v reads it.
        assert_eq!(row.bilinear(Vec2::new(0.375, -5.3)), grey(1.0));
    }

    #[test]
    fn bad_coordinates_and_inconsistent_images_give_black() {
        let image = two_by_two();
        for uv in [
            Vec2::new(f32::NAN, 0.5),
            Vec2::new(0.5, f32::INFINITY),
            Vec2::splat(f32::NEG_INFINITY),
        ] {
            assert_eq!(image.bilinear(uv), BLACK);
        }
        // Huge but finite: wraps to the fraction 0, the blend of the corners, 1.75.
        assert_eq!(image.bilinear(Vec2::splat(1e30)), grey(1.75));
        // Fields edited past from_linear's checks.
        let mut broken = image.clone();
        broken.texels.pop();
        assert_eq!(broken.bilinear(Vec2::splat(0.5)), BLACK);
        broken.width = 0;
        assert_eq!(broken.bilinear(Vec2::splat(0.5)), BLACK);
        // Checker and grid do not panic either.
        let nan = Vec2::splat(f32::NAN);
        let checker = Texture::Checker {
            scale: 4.0,
            colours: [BLACK, WHITE],
        };
        assert_eq!(checker.eval(nan), WHITE);
        let grid = Texture::Grid {
            scale: 4.0,
            line_width: 0.1,
            background: BLACK,
            line: WHITE,
        };
        assert_eq!(grid.eval(nan), BLACK);
    }

    #[test]
    fn srgb_decoding_is_the_exact_curve() {
        let table = srgb8_to_linear_table();
        assert_eq!(table[0], 0.0);
        assert_eq!(table[255], 1.0);
        // 128/255 = 0.5019608; ((0.5019608 + 0.055)/1.055)^2.4 = 0.5279248^2.4 = 0.2158605.
        assert!((table[128] - 0.215_860_5).abs() < 1e-7);
        // 10/255 = 0.0392157 ≤ 0.04045, the straight segment: 0.0392157/12.92 = 0.0030353.
        assert!((table[10] - 0.003_035_27).abs() < 1e-8);
        // 11/255 = 0.0431373 > 0.04045, the curve: (0.0981373/1.055)^2.4 = 0.0033465.
        assert!((table[11] - 0.003_346_54).abs() < 1e-8);
        // Increasing throughout.
        assert!(table.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn a_png_decodes_to_linear_texels_in_file_order() {
        // 2×2, top row red and sRGB grey 128, bottom row black and white; alpha varies.
        let mut rgba = image::RgbaImage::new(2, 2);
        rgba.put_pixel(0, 0, image::Rgba([255, 0, 0, 255]));
        rgba.put_pixel(1, 0, image::Rgba([128, 128, 128, 0]));
        rgba.put_pixel(0, 1, image::Rgba([0, 0, 0, 10]));
        rgba.put_pixel(1, 1, image::Rgba([255, 255, 255, 128]));
        let png = encode(rgba.into(), image::ImageFormat::Png);
        let image = TextureImage::from_encoded(&png, "memory.png").unwrap();
        assert_eq!((image.width, image.height), (2, 2));
        assert_eq!(image.name, "memory.png");
        let mid = table_value(128);
        // Alpha ignored: the transparent grey keeps its colour.
        assert_eq!(image.texels, vec![Vec3::X, Vec3::splat(mid), BLACK, WHITE]);
        // The top row of the file is v = 0.75, the bottom v = 0.25.
        assert_eq!(image.bilinear(Vec2::new(0.25, 0.75)), Vec3::X);
        assert_eq!(image.bilinear(Vec2::new(0.25, 0.25)), BLACK);

        // A grey 16-bit PNG, read at 16 bits: 65535 is 1, and 32896 (128.5 of 255, between
        // two 8-bit values) is the curve at 32896/65535 = 0.501961 — 0.215861, not 8 bits'
        // 0.215861 at 128 or 0.219526 at 129.
        let mut grey16 =
            image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(3, 1, image::Luma([65535]));
        grey16.put_pixel(1, 0, image::Luma([32896]));
        let png = encode(grey16.into(), image::ImageFormat::Png);
        let image = TextureImage::from_encoded(&png, "grey16.png").unwrap();
        assert_eq!(image.texels[0], WHITE);
        assert_eq!(
            image.texels[1],
            Vec3::splat(srgb_to_linear(32896.0 / 65535.0))
        );
        assert!(
            (image.texels[1].x - 0.215_861).abs() < 1e-6,
            "{}",
            image.texels[1]
        );
    }

    fn table_value(v: u8) -> f32 {
        srgb8_to_linear_table()[v as usize]
    }

    #[test]
    fn a_jpeg_round_trip_stays_within_its_loss() {
        // 16×8: the left half sRGB (200, 100, 50), the right half (50, 100, 200); two blocks
        // of 8×8, so each half is one flat block and the colours survive up to rounding and
        // chroma subsampling.
        let rgb = image::RgbImage::from_fn(16, 8, |x, _| {
            if x < 8 {
                image::Rgb([200, 100, 50])
            } else {
                image::Rgb([50, 100, 200])
            }
        });
        let jpeg = encode(rgb.into(), image::ImageFormat::Jpeg);
        let image = TextureImage::from_encoded(&jpeg, "memory.jpg").unwrap();
        assert_eq!((image.width, image.height), (16, 8));
        // Linear values: 200 → 0.5775804, 100 → 0.1274377, 50 → 0.0318960. Four 8-bit steps
        // near 200 are about 0.018 in linear terms, so allow 0.03.
        let orange = Vec3::new(0.577_580_4, 0.127_437_7, 0.031_896_0);
        let blue = Vec3::new(0.031_896_0, 0.127_437_7, 0.577_580_4);
        let row = 4 * 16;
        assert!(
            close(image.texels[row + 2], orange, 0.03),
            "{}",
            image.texels[row + 2]
        );
        assert!(
            close(image.texels[row + 13], blue, 0.03),
            "{}",
            image.texels[row + 13]
        );
    }

    #[test]
    fn bad_input_is_an_error_naming_the_file() {
        let message = |r: Result<TextureImage, TextureError>| r.unwrap_err().to_string();

        let m = message(TextureImage::from_encoded(
            b"not an image at all",
            "wall.png",
        ));
        assert!(
            m.contains("wall.png") && m.contains("not a PNG or JPEG"),
            "{m}"
        );
        let m = message(TextureImage::from_encoded(&[], "empty.png"));
        assert!(m.contains("empty.png"), "{m}");

        // A real PNG cut short: the header reads, the pixels do not.
        let rgb = image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([x as u8, y as u8, 7]));
        let png = encode(rgb.into(), image::ImageFormat::Png);
        let m = message(TextureImage::from_encoded(&png[..png.len() / 2], "cut.png"));
        assert!(m.contains("cut.png"), "{m}");

        // A format the image crate knows but textures do not take.
        let bmp = [b"BM".as_slice(), &[0; 60]].concat();
        let m = message(TextureImage::from_encoded(&bmp, "old.bmp"));
        assert!(m.contains("old.bmp") && m.contains("not supported"), "{m}");

        // One pixel too wide: refused from the header.
        let wide = image::GrayImage::new(TextureImage::MAX_SIDE + 1, 1);
        let png = encode(wide.into(), image::ImageFormat::Png);
        let m = message(TextureImage::from_encoded(&png, "wide.png"));
        assert!(m.contains("wide.png") && m.contains("too large"), "{m}");

        let missing = Path::new("/nonexistent/raylab/brick.png");
        let m = message(TextureImage::load(missing));
        assert!(m.contains("/nonexistent/raylab/brick.png"), "{m}");

        // from_linear checks sizes and counts.
        let m = message(TextureImage::from_linear("zero", 0, 4, Vec::new()));
        assert!(m.contains("zero") && m.contains("empty"), "{m}");
        let m = message(TextureImage::from_linear("short", 2, 2, vec![BLACK; 3]));
        assert!(m.contains("short") && m.contains("expected 4"), "{m}");
        let m = message(TextureImage::from_linear(
            "huge",
            1,
            20000,
            vec![BLACK; 20000],
        ));
        assert!(m.contains("too large"), "{m}");
    }

    #[test]
    fn loading_a_file_names_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("tile.png");
        let rgb = image::RgbImage::from_pixel(3, 2, image::Rgb([128, 0, 255]));
        std::fs::write(&path, encode(rgb.into(), image::ImageFormat::Png)).unwrap();
        let image = TextureImage::load(&path).unwrap();
        assert_eq!(image.name, path.display().to_string());
        assert_eq!(image.texels, vec![Vec3::new(table_value(128), 0.0, 1.0); 6]);
    }

    #[test]
    fn the_teapot_texture_decodes() {
        let png = include_bytes!("../../../../assets/models/teapot-porcelain.png");
        let image = TextureImage::from_encoded(png, "teapot-porcelain.png").unwrap();
        assert_eq!((image.width, image.height), (512, 256));
        let luminance = |c: &Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        let (lo, hi) = image
            .texels
            .iter()
            .map(luminance)
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), l| {
                (lo.min(l), hi.max(l))
            });
        // Blue on white: a real pattern, not one colour.
        assert!(hi - lo > 0.5, "luminance from {lo} to {hi}");
        // Mostly white ground: bright even shown without a gamma curve.
        let mean = image.texels.iter().map(luminance).sum::<f32>() / image.texels.len() as f32;
        assert!(mean > 0.5, "mean luminance {mean}");
    }

    #[test]
    fn planar_uv_projects_along_the_largest_normal_component() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        // Walls facing ±x: (z, y).
        assert_eq!(planar_uv(p, Vec3::X), Vec2::new(3.0, 2.0));
        assert_eq!(planar_uv(p, Vec3::new(-0.9, 0.3, 0.3)), Vec2::new(3.0, 2.0));
        // Floor and ceiling, ±y: (x, z).
        assert_eq!(planar_uv(p, -Vec3::Y), Vec2::new(1.0, 3.0));
        // The back wall, ±z: (x, y).
        assert_eq!(
            planar_uv(p, Vec3::new(0.1, -0.2, -0.97)),
            Vec2::new(1.0, 2.0)
        );
        // Ties: x before y before z.
        assert_eq!(planar_uv(p, Vec3::new(1.0, 1.0, 1.0)), Vec2::new(3.0, 2.0));
        assert_eq!(planar_uv(p, Vec3::new(0.0, 1.0, 1.0)), Vec2::new(1.0, 3.0));
    }
}
