//! Relief: normal maps and parallax occlusion mapping, the lab's extension "textures for
//! color/reflectance and/or normalmaps, and/or parallax mapping" (section 6).
//!
//! Both change what a hit looks like, never where it is: the ray still meets the flat
//! triangle, its shadow ray still leaves from there and the geometric normal still decides
//! which side is lit ([`crate::shading::bsdf`]'s rules).
//!
//! * A **normal map** changes the shading normal: its texel is a direction in the surface's
//!   tangent frame ([`TangentFrame`]: x along increasing u, y along increasing v, z the
//!   normal), decoded as [`Decoding::Normal`] says and filtered as colour textures are
//!   (bilinear, repeating). The lab's equation 27 then takes the perturbed normal's cosine, so
//!   a bumpy wall shows its relief under the point light.
//! * A **height map** carves the surface: its highest texel is the triangle's plane and the
//!   rest lies below it, `scale · (top − h)` deep (scene units). Parallax occlusion mapping
//!   (Tatarchuk, "Dynamic parallax occlusion mapping with approximate soft shadows", 2006)
//!   follows the viewing ray into that height field in tangent space, a linear search over
//!   depth layers and then one secant step between the last two, and shifts the texture
//!   coordinates that colour and normal lookups use to where the ray meets it. A constant map
//!   is its own top: nothing is carved, nothing moves. With self-shadowing on, the same search
//!   goes up from that point toward the light ([`HeightMap::lit`]): where the height field
//!   rises across the way, the carved point is in the shadow of its own relief (a groove's
//!   wall shadows its floor) and gets no direct light.
//!
//! The tangent frame is made in one place, [`TangentFrame::new`], from a triangle's corners and
//! texture coordinates; [`Relief::at`] is the one place a hit's coordinates and normal are
//! changed, for every integrator ([`crate::transport::integrator::Tracer::surface`]).

use std::sync::Arc;

use glam::{Vec2, Vec3};

pub use crate::shading::texture::Decoding;
use crate::shading::texture::TextureImage;

/// A triangle's tangent frame at a hit: `t` along increasing u, `b` along increasing v (both
/// unit, in the surface), `n` the shading normal, orthonormal; and the gradients of u and v
/// over the triangle's plane, which turn a displacement along the surface into one of the
/// texture coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentFrame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
    /// ∇u: for a displacement δ in the triangle's plane, u changes by δ·∇u.
    pub grad_u: Vec3,
    /// ∇v, likewise.
    pub grad_v: Vec3,
}

impl TangentFrame {
    /// The frame of a triangle with corners `p` and texture coordinates `uv` at a point whose
    /// shading normal is `n` (unit):
    ///
    /// * with e₁ = p₁ − p₀, e₂ = p₂ − p₀ and (Δu₁, Δv₁), (Δu₂, Δv₂) their changes in (u, v),
    ///   dP/du = (Δv₂ e₁ − Δv₁ e₂)/det and dP/dv = (Δu₁ e₂ − Δu₂ e₁)/det with
    ///   det = Δu₁ Δv₂ − Δu₂ Δv₁ (the inverse of the 2×2 map from (u, v) to the plane);
    /// * t = dP/du made perpendicular to n (Gram–Schmidt) and unit;
    /// * b = ±(n × t), the sign that of (n × t)·dP/dv: the handedness of the UV layout (a
    ///   mirrored layout flips it), so b points along increasing v either way;
    /// * ∇u = (Δu₁ (e₂ × m) + Δu₂ (m × e₁))/|m|², m = e₁ × e₂, and ∇v the same with Δv: the
    ///   vectors in the plane whose dot products with e₁ and e₂ are Δu₁ and Δu₂ (Δv₁, Δv₂).
    ///
    /// A layout that gives no direction (all three coordinates on a line, a zero-area
    /// triangle, or dP/du along n) falls back to an arbitrary orthonormal frame about n and
    /// zero gradients: a normal map still reads, parallax does not shift.
    pub fn new(p: [Vec3; 3], uv: [Vec2; 3], n: Vec3) -> Self {
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
        let det = d1.x * d2.y - d2.x * d1.y;
        let m = e1.cross(e2);
        let m2 = m.length_squared();
        let fallback = || {
            let (t, b) = crate::base::sampling::orthonormal_basis(n);
            Self {
                t,
                b,
                n,
                grad_u: Vec3::ZERO,
                grad_v: Vec3::ZERO,
            }
        };
        if !(det.is_finite() && det != 0.0 && m2 > 0.0 && m2.is_finite()) {
            return fallback();
        }
        let dp_du = (d2.y * e1 - d1.y * e2) / det;
        let dp_dv = (d1.x * e2 - d2.x * e1) / det;
        let Some(t) = (dp_du - n * n.dot(dp_du)).try_normalize() else {
            return fallback();
        };
        let b = n.cross(t);
        let b = if b.dot(dp_dv) < 0.0 { -b } else { b };
        let (a, c) = (e2.cross(m), m.cross(e1));
        Self {
            t,
            b,
            n,
            grad_u: (d1.x * a + d2.x * c) / m2,
            grad_v: (d1.y * a + d2.y * c) / m2,
        }
    }

    /// A tangent-space direction (x along t, y along b, z along n) in world space.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        v.x * self.t + v.y * self.b + v.z * self.n
    }

    /// How the texture coordinates change for a world displacement `d` along the surface.
    #[inline]
    pub fn uv_change(&self, d: Vec3) -> Vec2 {
        Vec2::new(d.dot(self.grad_u), d.dot(self.grad_v))
    }
}

/// A tangent-space normal map and how strongly it tilts the normal.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// Texels decoded as [`Decoding::Normal`]: tangent-space directions.
    pub image: Arc<TextureImage>,
    /// Multiplies the tangent components (x, y) before normalising: 0 is no map, 1 the map
    /// as drawn (the MTL's `-bm`, a scene file's `normal_strength`).
    pub strength: f32,
}

impl NormalMap {
    /// Why `image` (decoded as [`Decoding::Normal`]) cannot be a normal map, if it cannot:
    /// a grey image (every texel's three channels equal) is a bump map of heights, which an
    /// MTL's `map_Bump` also names, not a normal map; read as one, it would tilt every normal
    /// toward one corner. The one rule for every normal map: a model's material library's (a
    /// warning, the map left out) and a scene file's (an error).
    pub fn refusal(image: &TextureImage) -> Option<&'static str> {
        image
            .texels
            .iter()
            .all(|t| t.x == t.y && t.y == t.z)
            .then_some("is grey: a bump map of heights, not a normal map")
    }

    /// The tangent-space normal at `uv`: the texels filtered bilinearly, (x, y) scaled by the
    /// strength, normalised; (0, 0, 1) where that leaves nothing (opposite texels averaging
    /// to zero, a non-finite `uv`).
    #[inline]
    pub fn tangent_normal(&self, uv: Vec2) -> Vec3 {
        let m = self.image.bilinear(uv);
        Vec3::new(self.strength * m.x, self.strength * m.y, m.z)
            .try_normalize()
            .unwrap_or(Vec3::Z)
    }
}

/// A height map for parallax occlusion mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightMap {
    /// Texels decoded as [`Decoding::Height`]; the red channel is the height, in [0, 1].
    pub image: Arc<TextureImage>,
    /// How deep a height difference of 1 is, in scene units (a scene file's `height_scale`).
    pub scale: f32,
    /// The highest and lowest heights of the image: the highest is the triangle's plane.
    top: f32,
    bottom: f32,
}

impl HeightMap {
    /// The map of `image` (decoded as heights), `scale` scene units deep per unit of height.
    pub fn new(image: Arc<TextureImage>, scale: f32) -> Self {
        let (bottom, top) = image
            .texels
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| {
                (lo.min(t.x), hi.max(t.x))
            });
        Self {
            image,
            scale,
            top,
            bottom,
        }
    }

    /// How far below the triangle's plane the height field lies at `uv`, in units of height.
    #[inline]
    fn depth(&self, uv: Vec2) -> f32 {
        self.top - self.image.bilinear(uv).x
    }

    /// The fewest and most depth layers the linear search takes (looking straight down and
    /// along the surface; in between in proportion to the cosine, as in the classic POM).
    pub const LAYERS: (f32, f32) = (8.0, 32.0);

    /// Parallax occlusion mapping: where a ray arriving at `uv` from the direction `wo`
    /// (unit, toward the viewer) meets the height field, as texture coordinates of the
    /// map (`to_map` turns a change of the surface's coordinates into one of the map's).
    ///
    /// Layers of equal depth from the plane (depth 0) to the lowest point (`top − bottom`):
    /// at layer k the ray is `k·Δ` deep and has moved `−wo_t/wo_n` along the surface per unit
    /// of depth (wo_t the tangential part of wo, wo_n its cosine); the first layer where the
    /// ray is as deep as the field or deeper is its hit, refined by the secant between it and
    /// the layer before. `uv` unchanged where the ray does not come from above the surface,
    /// the map is flat, or the frame has no gradients.
    pub fn march(&self, frame: &TangentFrame, uv: Vec2, wo: Vec3, to_map: f32) -> Vec2 {
        let range = self.top - self.bottom;
        let cos = wo.dot(frame.n);
        if !(range > 0.0 && cos > 1e-3 && self.scale > 0.0) {
            return uv;
        }
        // The surface coordinates' change per unit of height the ray descends.
        let along = -(wo - cos * frame.n) / cos * self.scale;
        let step_uv = frame.uv_change(along);
        if step_uv == Vec2::ZERO || !step_uv.is_finite() {
            return uv;
        }
        let (fewest, most) = Self::LAYERS;
        let layers = (most + (fewest - most) * cos).ceil();
        let dz = range / layers;
        let mut prev = (uv, self.depth(uv * to_map), 0.0f32);
        if prev.1 <= 0.0 {
            return uv;
        }
        for k in 1..=layers as u32 {
            let z = k as f32 * dz;
            let at = uv + z * step_uv;
            let depth = self.depth(at * to_map);
            if depth <= z {
                // Above the field at the previous layer by a, below it here by −b: the secant
                // crosses it a/(a − b) of the way.
                let a = prev.1 - prev.2;
                let b = depth - z;
                let w = a / (a - b);
                return prev.0 + w * (at - prev.0);
            }
            prev = (at, depth, z);
        }
        prev.0
    }

    /// Parallax self-shadowing: whether the carved surface at `uv` (where [`HeightMap::march`]
    /// met it) sees along `wi` (unit, toward the light) out of the height field.
    ///
    /// The point lies `z₀` below the plane; going up toward the light the ray moves
    /// `wi_t/wi_n` along the surface per unit of height climbed. Layers of equal height, as
    /// many as [`HeightMap::march`] takes at that slope: at each the ray is `z` deep, and the
    /// field hides the light where it lies above the ray there (its depth less than `z`). Lit
    /// where the point is on top (nothing above it), the map is flat, the light is below the
    /// plane (the surface's own rules give no light there) or the frame has no gradients.
    pub fn lit(&self, frame: &TangentFrame, uv: Vec2, wi: Vec3, to_map: f32) -> bool {
        let range = self.top - self.bottom;
        let cos = wi.dot(frame.n);
        if !(range > 0.0 && cos > 1e-3 && self.scale > 0.0) {
            return true;
        }
        let z0 = self.depth(uv * to_map);
        if z0 <= 0.0 {
            return true;
        }
        let along = (wi - cos * frame.n) / cos * self.scale;
        let step_uv = frame.uv_change(along);
        if step_uv == Vec2::ZERO || !step_uv.is_finite() {
            return true;
        }
        let (fewest, most) = Self::LAYERS;
        let dz = range / (most + (fewest - most) * cos).ceil();
        // The field a hair above the ray is not in the way: the bilinear field around the
        // point itself, met at `z₀` by the secant, is within float rounding of it.
        let tolerance = 1e-4 * range;
        let mut climbed = dz;
        while climbed < z0 {
            let z = z0 - climbed;
            if self.depth((uv + climbed * step_uv) * to_map) < z - tolerance {
                return false;
            }
            climbed += dz;
        }
        true
    }
}

/// A surface's relief: a normal map, a height map, or both, looked up at the surface's
/// texture coordinates times `uv_scale` (1 for a model's own coordinates; the presets tile the
/// box's planar coordinates with it).
#[derive(Clone, Debug, PartialEq)]
pub struct Relief {
    pub normal: Option<NormalMap>,
    pub height: Option<HeightMap>,
    pub uv_scale: f32,
}

impl Relief {
    /// The texture coordinates and shading normal at a hit with coordinates `uv`, seen from
    /// `wo` (unit, toward the viewer) in tangent frame `frame`: `uv` shifted by parallax
    /// occlusion mapping where there is a height map, and the frame's normal tilted by the
    /// normal map (looked up at the shifted coordinates) where there is one, else unchanged.
    /// The normal is not yet held to the geometric normal's rules: the caller does that
    /// ([`crate::shading::bsdf::ShadingFrame::bent_normal`]).
    #[inline]
    pub fn at(&self, frame: &TangentFrame, uv: Vec2, wo: Vec3) -> (Vec2, Vec3) {
        let uv = match &self.height {
            Some(h) => h.march(frame, uv, wo, self.uv_scale),
            None => uv,
        };
        let normal = match &self.normal {
            Some(m) => frame
                .to_world(m.tangent_normal(uv * self.uv_scale))
                .try_normalize()
                .unwrap_or(frame.n),
            None => frame.n,
        };
        (uv, normal)
    }

    /// The share of the light along `wi` (unit, toward the light) that reaches the hit with
    /// texture coordinates `uv` (as [`Relief::at`] returned them): 0 where the height field
    /// hides it ([`HeightMap::lit`], parallax self-shadowing), else 1; 1 without a height map.
    #[inline]
    pub fn visibility(&self, frame: &TangentFrame, uv: Vec2, wi: Vec3) -> f32 {
        match &self.height {
            Some(h) if !h.lit(frame, uv, wi, self.uv_scale) => 0.0,
            _ => 1.0,
        }
    }
}

/// A tangent-space normal map of a height field given on a `size × size` grid over one
/// period of texture space, for a surface where that period is `period` scene units a side and
/// a height difference of 1 is `depth` scene units: the normal (−∂z/∂x, −∂z/∂y, 1) normalised,
/// z = depth·h, the slopes by central differences with wrapping. Rows top to bottom as
/// [`TextureImage`] stores them; `height(i, j)` counts j from the bottom (v up).
pub fn normal_map_of_heights(
    name: &str,
    size: u32,
    period: f32,
    depth: f32,
    height: &dyn Fn(u32, u32) -> f32,
) -> TextureImage {
    let n = size;
    let h = |i: i64, j: i64| height(i.rem_euclid(n as i64) as u32, j.rem_euclid(n as i64) as u32);
    // Two texels apart, in scene units.
    let span = 2.0 * period / n as f32;
    let mut texels = Vec::with_capacity((n * n) as usize);
    for row in 0..n {
        let j = i64::from(n - 1 - row);
        for i in 0..i64::from(n) {
            let dx = depth * (h(i + 1, j) - h(i - 1, j)) / span;
            let dy = depth * (h(i, j + 1) - h(i, j - 1)) / span;
            texels.push(Vec3::new(-dx, -dy, 1.0).normalize());
        }
    }
    TextureImage::from_linear(name, n, n, texels).expect("the sizes match")
}

/// A height map's texels from `height(i, j)` (j from the bottom) on a `size × size` grid.
pub fn height_image(name: &str, size: u32, height: &dyn Fn(u32, u32) -> f32) -> TextureImage {
    let mut texels = Vec::with_capacity((size * size) as usize);
    for row in 0..size {
        for i in 0..size {
            texels.push(Vec3::splat(height(i, size - 1 - row)));
        }
    }
    TextureImage::from_linear(name, size, size, texels).expect("the sizes match")
}

/// The rounded profile of a bevel: 0 at the groove's edge, rising to 1 at `width` from it
/// with zero slope there, `1 − (1 − t)²`.
fn bevel(distance: f32, width: f32) -> f32 {
    let t = (distance / width).clamp(0.0, 1.0);
    1.0 - (1.0 - t) * (1.0 - t)
}

/// Rounded bricks over one period of texture space (x, y in [0, 1), y up): four courses of two
/// bricks each, every other course offset by half a brick, mortar grooves `gap` wide (of the
/// period) and bevels `round` wide. Height 1 on a brick's face, 0 in the mortar.
pub fn bricks(x: f32, y: f32) -> f32 {
    const COURSES: f32 = 4.0;
    const PER_COURSE: f32 = 2.0;
    let (gap, round) = (0.012, 0.03);
    let course = (y * COURSES).floor();
    let shift = if course as i32 % 2 == 1 { 0.5 } else { 0.0 };
    let bx = x * PER_COURSE + shift;
    let bx = bx - bx.floor();
    let by = y * COURSES - course;
    // Distances to the brick's nearest vertical and horizontal edges, in units of the period.
    let ex = bx.min(1.0 - bx) / PER_COURSE;
    let ey = by.min(1.0 - by) / COURSES;
    bevel(ex.min(ey) - 0.5 * gap, round)
}

/// One square floor tile over one period of texture space (x, y in [0, 1)): a grout groove
/// `gap` wide around its border and a rounded bevel. Height 1 on the tile, 0 in the grout.
pub fn tile(x: f32, y: f32) -> f32 {
    let (gap, round) = (0.05, 0.06);
    let e = x.min(1.0 - x).min(y).min(1.0 - y);
    bevel(e - 0.5 * gap, round)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).abs().max_element() <= tol
    }

    fn one_texel(decoding: Decoding, rgb: [u8; 3]) -> Vec3 {
        let png = {
            let image = image::RgbImage::from_pixel(1, 1, image::Rgb(rgb));
            let mut bytes = std::io::Cursor::new(Vec::new());
            image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
            bytes.into_inner()
        };
        TextureImage::from_encoded_as(&png, "t.png", decoding)
            .unwrap()
            .texels[0]
    }

    /// The hand-made layout: the triangle (0,0,0), (2,0,0), (0,1,0) with coordinates (0,0),
    /// (1,0), (0,1): u runs along x at half a unit per scene unit, v along y. dP/du = (2,0,0),
    /// dP/dv = (0,1,0); the lab's winding gives the triangle normal e₂ × e₁ = −z.
    #[test]
    fn a_tangent_frame_is_orthonormal_and_follows_the_layout() {
        let p = [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::Y];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let n = -Vec3::Z;
        let f = TangentFrame::new(p, uv, n);
        assert_eq!((f.t, f.b, f.n), (Vec3::X, Vec3::Y, n));
        // Left-handed against n = −z (t × b = +z = −n): the layout's handedness, kept.
        assert_eq!(f.t.cross(f.b), -n);
        // ∇u = (0.5, 0, 0), ∇v = (0, 1, 0): 2 units along x is one period of u.
        assert_eq!(f.grad_u, Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(f.grad_v, Vec3::Y);
        assert_eq!(f.uv_change(Vec3::new(2.0, 3.0, 0.0)), Vec2::new(1.0, 3.0));

        // The layout mirrored in u: t turns to −x, b stays +y, the handedness flips.
        let mirrored = [Vec2::X, Vec2::ZERO, Vec2::new(1.0, 1.0)];
        let g = TangentFrame::new(p, mirrored, n);
        assert!(
            close(g.t, -Vec3::X, 1e-6) && close(g.b, Vec3::Y, 1e-6),
            "{g:?}"
        );
        assert!(close(g.t.cross(g.b), n, 1e-6));

        // A tilted shading normal: t is made perpendicular to it (Gram–Schmidt), all unit.
        let ns = Vec3::new(0.3, -0.2, -1.0).normalize();
        let h = TangentFrame::new(p, uv, ns);
        for (a, b) in [(h.t, h.b), (h.b, h.n), (h.t, h.n)] {
            assert!(a.dot(b).abs() < 1e-6);
        }
        for v in [h.t, h.b, h.n] {
            assert!((v.length() - 1.0).abs() < 1e-6);
        }
        // t stays in the plane of dP/du and n: (dP/du × n)·t = 0, and points along +x.
        assert!(Vec3::X.cross(ns).dot(h.t).abs() < 1e-6 && h.t.x > 0.9);
        assert!(h.b.y > 0.9, "b along increasing v: {}", h.b);

        // No layout (the coordinates on a line): an orthonormal frame about n, no gradients.
        let line = [Vec2::ZERO, Vec2::X, Vec2::new(2.0, 0.0)];
        let d = TangentFrame::new(p, line, n);
        assert_eq!((d.n, d.grad_u, d.grad_v), (n, Vec3::ZERO, Vec3::ZERO));
        assert!(d.t.dot(d.b).abs() < 1e-6 && d.t.dot(n).abs() < 1e-6);
    }

    /// Normal-map texels are read as signed values: c ↦ (c − 128)/127.
    #[test]
    fn normal_map_texels_decode_to_tangent_directions() {
        // Flat: exactly (0, 0, 1).
        assert_eq!(one_texel(Decoding::Normal, [128, 128, 255]), Vec3::Z);
        // (255, 128, 128): (1, 0, 0), tilted the whole way to +x (the tangent).
        assert_eq!(one_texel(Decoding::Normal, [255, 128, 128]), Vec3::X);
        // (255, 128, 255): (1, 0, 1), 45° toward +x once normalised.
        let m = one_texel(Decoding::Normal, [255, 128, 255]);
        assert_eq!(m, Vec3::new(1.0, 0.0, 1.0));
        // (192, 64, 255): x = 64/127 = 0.503937, y = −64/127; normalised by
        // √(2·0.253952 + 1) = √1.507904 = 1.227968: (0.410383, −0.410383, 0.814354).
        let m = one_texel(Decoding::Normal, [192, 64, 255]).normalize();
        assert!(
            close(m, Vec3::new(0.410_383, -0.410_383, 0.814_354), 1e-6),
            "{m}"
        );
        // 0 is clamped to −1 (not −128/127).
        assert_eq!(
            one_texel(Decoding::Normal, [0, 0, 255]),
            Vec3::new(-1.0, -1.0, 1.0)
        );
        // Heights: c/255.
        assert_eq!(one_texel(Decoding::Height, [51, 0, 0]).x, 0.2);

        // Through a frame: t = +x, b = +y, n = −z. (255, 128, 255) at strength 1 tilts the
        // normal 45° toward +x: (1, 0, −1)/√2; at strength 0.5, atan(0.5) = 26.57°:
        // (0.5, 0, −1)/√1.25 = (0.447214, 0, −0.894427).
        let frame = TangentFrame::new(
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec2::ZERO, Vec2::X, Vec2::Y],
            -Vec3::Z,
        );
        let image =
            Arc::new(TextureImage::from_linear("m", 1, 1, vec![Vec3::new(1.0, 0.0, 1.0)]).unwrap());
        let mut relief = Relief {
            normal: Some(NormalMap {
                image,
                strength: 1.0,
            }),
            height: None,
            uv_scale: 1.0,
        };
        let (_, n) = relief.at(&frame, Vec2::splat(0.3), Vec3::NEG_Z);
        assert!(close(n, Vec3::new(1.0, 0.0, -1.0).normalize(), 1e-6), "{n}");
        relief.normal.as_mut().unwrap().strength = 0.5;
        let (_, n) = relief.at(&frame, Vec2::splat(0.3), Vec3::NEG_Z);
        assert!(close(n, Vec3::new(0.447_214, 0.0, -0.894_427), 1e-6), "{n}");
    }

    /// Maps are checked as colour textures are: a non-image and a header too large are errors
    /// naming the file, never a panic. A 16-bit map is read at 16 bits: the flat normal
    /// (32768, 32768, 65535) is exactly (0, 0, 1), and a height of 32896 is 32896/65535
    /// (between two 8-bit heights).
    #[test]
    fn bad_maps_are_errors_naming_the_file() {
        let message = |bytes: &[u8], decoding| {
            TextureImage::from_encoded_as(bytes, "bumps.png", decoding)
                .unwrap_err()
                .to_string()
        };
        for decoding in [Decoding::Normal, Decoding::Height] {
            let m = message(b"this is no image", decoding);
            assert!(
                m.contains("bumps.png") && m.contains("not a PNG or JPEG"),
                "{m}"
            );
            let wide = image::GrayImage::new(TextureImage::MAX_SIDE + 1, 1);
            let mut png = std::io::Cursor::new(Vec::new());
            wide.write_to(&mut png, image::ImageFormat::Png).unwrap();
            let m = message(png.get_ref(), decoding);
            assert!(m.contains("too large"), "{m}");
        }
        let deep = |rgb: [u16; 3]| {
            let image = image::ImageBuffer::<image::Rgb<u16>, _>::from_pixel(2, 2, image::Rgb(rgb));
            let mut png = std::io::Cursor::new(Vec::new());
            image::DynamicImage::from(image)
                .write_to(&mut png, image::ImageFormat::Png)
                .unwrap();
            png.into_inner()
        };
        let flat =
            TextureImage::from_encoded_as(&deep([32768, 32768, 65535]), "n.png", Decoding::Normal);
        assert_eq!(flat.unwrap().texels, vec![Vec3::Z; 4]);
        let height =
            TextureImage::from_encoded_as(&deep([32896, 0, 0]), "h.png", Decoding::Height).unwrap();
        assert_eq!(height.texels[0].x, 32896.0 / 65535.0);
    }

    /// A flat map and a constant height map change nothing.
    #[test]
    fn flat_maps_are_no_relief() {
        let frame = TangentFrame::new(
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec2::ZERO, Vec2::X, Vec2::Y],
            -Vec3::Z,
        );
        let flat = Arc::new(TextureImage::from_linear("f", 2, 2, vec![Vec3::Z; 4]).unwrap());
        let level =
            Arc::new(TextureImage::from_linear("h", 2, 2, vec![Vec3::splat(0.4); 4]).unwrap());
        let relief = Relief {
            normal: Some(NormalMap {
                image: flat,
                strength: 1.0,
            }),
            height: Some(HeightMap::new(level, 0.1)),
            uv_scale: 3.0,
        };
        let wo = Vec3::new(0.5, 0.3, -0.8).normalize();
        let uv = Vec2::new(0.37, 0.81);
        assert_eq!(relief.at(&frame, uv, wo), (uv, -Vec3::Z));
    }

    /// The step of the two tests below: a height map of 64 texels across one unit of u (one
    /// row), the left half 1 and the right half 0.5, 0.2 units deep per unit; and the frame of
    /// the plane z = 0 with u = x, v = y and n = −z (toward the viewer).
    fn step() -> (HeightMap, TangentFrame) {
        let texels = (0..64)
            .map(|i| Vec3::splat(if i < 32 { 1.0 } else { 0.5 }))
            .collect();
        let image = Arc::new(TextureImage::from_linear("step", 64, 1, texels).unwrap());
        let frame = TangentFrame::new(
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec2::ZERO, Vec2::X, Vec2::Y],
            -Vec3::Z,
        );
        (HeightMap::new(image, 0.2), frame)
    }

    /// A step down: the left half of the map high (1), the right half 0.5 lower, 0.2 units
    /// deep per unit (so the step is 0.1 deep). A ray arriving at 45° in the x–z plane where
    /// the map is low sinks to the floor 0.1 below: it meets it 0.1 further along (the
    /// secant of a straight drop is exact up to the filtering at the step's edge).
    #[test]
    fn parallax_follows_the_ray_to_the_height_field() {
        let (height, frame) = step();
        // The viewer up and to the left: the ray goes down and to the right (+x).
        let wo = Vec3::new(-1.0, 0.0, -1.0).normalize();
        let uv = Vec2::new(0.7, 0.5);
        let hit = height.march(&frame, uv, wo, 1.0);
        assert!((hit.x - 0.8).abs() < 1e-3 && hit.y == 0.5, "{hit}");
        // Where the map is at its top the ray stops at once.
        let uv = Vec2::new(0.2, 0.5);
        assert_eq!(height.march(&frame, uv, wo, 1.0), uv);
        // Straight down: no shift. From below the surface: none.
        assert_eq!(
            height.march(&frame, Vec2::new(0.7, 0.5), -Vec3::Z, 1.0).x,
            0.7
        );
        assert_eq!(
            height.march(&frame, Vec2::new(0.7, 0.5), Vec3::Z, 1.0).x,
            0.7
        );
    }

    /// Self-shadowing in the step of [`parallax_follows_the_ray_to_the_height_field`]: on the
    /// low floor 0.05 right of the step (0.1 high), a light low on the left (30° above the
    /// plane: the ray climbs 0.1 in 0.173 along the surface) is hidden by the step's wall; a
    /// light 60° up (0.1 in 0.058) clears it, as does a light from the right, and the step's
    /// top is lit from every side. A constant map hides nothing.
    #[test]
    fn a_step_shadows_the_floor_beside_it() {
        let (height, frame) = step();
        let toward = |degrees_up: f32, from_left: bool| {
            let (s, c) = degrees_up.to_radians().sin_cos();
            Vec3::new(if from_left { -c } else { c }, 0.0, -s)
        };
        let floor = Vec2::new(0.55, 0.5);
        assert!(!height.lit(&frame, floor, toward(30.0, true), 1.0));
        assert!(height.lit(&frame, floor, toward(60.0, true), 1.0));
        assert!(height.lit(&frame, floor, toward(30.0, false), 1.0));
        assert!(height.lit(&frame, floor, toward(20.0, false), 1.0));
        // The map repeats: 10° from the right climbs 0.1 in 0.567, past u = 1, where the
        // next period's high half stands.
        assert!(!height.lit(&frame, floor, toward(10.0, false), 1.0));
        let top = Vec2::new(0.25, 0.5);
        for light in [toward(10.0, true), toward(10.0, false), -Vec3::Z] {
            assert!(height.lit(&frame, top, light, 1.0), "{light}");
        }
        // Further from the wall the low light reaches the floor again (0.25 > 0.173).
        assert!(height.lit(&frame, Vec2::new(0.75, 0.5), toward(30.0, true), 1.0));
        let level = Arc::new(TextureImage::from_linear("h", 1, 1, vec![Vec3::splat(0.3)]).unwrap());
        let relief = Relief {
            normal: None,
            height: Some(HeightMap::new(level, 0.2)),
            uv_scale: 1.0,
        };
        assert_eq!(relief.visibility(&frame, floor, toward(5.0, true)), 1.0);
    }

    /// The presets' patterns: a brick's face is high, the mortar low, the map's normals tilt
    /// away from the grooves.
    #[test]
    fn procedural_patterns_have_their_grooves_where_drawn() {
        assert_eq!(bricks(0.25, 0.125), 1.0);
        assert_eq!(bricks(0.0, 0.125), 0.0, "a vertical joint");
        assert_eq!(bricks(0.25, 0.25), 0.0, "a horizontal joint");
        assert_eq!(bricks(0.0, 0.375), 1.0, "the next course is offset");
        assert_eq!(tile(0.5, 0.5), 1.0);
        assert_eq!(tile(0.0, 0.5), 0.0);
        let size = 64;
        let map = normal_map_of_heights("tiles", size, 0.25, 0.02, &|i, j| {
            tile(
                (i as f32 + 0.5) / size as f32,
                (j as f32 + 0.5) / size as f32,
            )
        });
        // Just right of the left groove the surface rises to the right: its normal leans
        // left (−x); flat in the middle.
        let left = map.bilinear(Vec2::new(3.5 / 64.0, 0.5));
        assert!(left.x < -0.1 && left.y.abs() < 1e-6, "{left}");
        assert_eq!(map.bilinear(Vec2::new(0.5, 0.5)), Vec3::Z);
        // Just below the top groove the surface rises downward... i.e. toward −v: leans +y.
        let top = map.bilinear(Vec2::new(0.5, 60.5 / 64.0));
        assert!(top.y > 0.1, "{top}");
    }
}
