//! Water in the box (the lab's extensions "specular materials: for example you could simulate
//! water with normal maps" and "fractals … for water"): the floor under clear water `depth`
//! deep, its surface one flat quad of a dielectric (index 1.33) whose shading normal comes
//! from a normal map of fractal waves ([`wave_relief`]).
//!
//! One surface is enough: whether a ray enters or leaves the water is decided at the surface by
//! the side it arrives from (the glass BSDF's rule), and below it the floor, the walls and the
//! blocks are what a ray under water meets, as in a pool. The waves move nothing: they tilt the
//! surface's normal, so reflections and refraction ripple while the geometry stays one quad.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::base::geometry::Triangle;
use crate::base::invalid::SettingsError;
use crate::base::noise::Fbm;
use crate::shading::material::{Material, MaterialKind};
use crate::shading::relief::{NormalMap, Relief, normal_map_of_heights};

/// The pool's water.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WaterSpec {
    /// How deep the water is over the floor, in scene units (the box is 2 high).
    pub depth: f32,
    /// Its index of refraction (1.33: water).
    pub ior: f32,
    /// The waves' amplitude: the heights of the wave field are within ± this, in scene units;
    /// 0 is a still, flat surface.
    pub waves: f32,
    /// The time the waves are seen at, in seconds: each octave of the wave field drifts its
    /// own way as it grows.
    pub time: f32,
}

impl Default for WaterSpec {
    fn default() -> Self {
        Self {
            depth: 0.3,
            ior: 1.33,
            waves: DEFAULT_WAVES,
            time: 0.0,
        }
    }
}

/// The default waves' amplitude: ripples a hundredth of the box's half-width high.
pub const DEFAULT_WAVES: f32 = 0.01;
/// The largest amplitude allowed.
pub const MAX_WAVES: f32 = 0.1;
/// The largest time allowed (the drift is periodic in nothing, but f32 time keeps its
/// precision to well under a frame up to here).
pub const MAX_TIME: f32 = 1e4;

/// The wave field's tile: this many scene units a side, repeated across the surface.
pub const WAVE_PERIOD: f32 = 1.0;
/// Texels a side of the wave normal map.
pub const WAVE_MAP_SIZE: u32 = 256;
/// The wave field: fBm of 5 octaves, the largest 4 waves across a tile.
const WAVE_NOISE: Fbm = Fbm {
    seed: 11,
    octaves: 5,
    lacunarity: 2.0,
    gain: 0.5,
};
const WAVE_CELLS: u32 = 4;
/// Each octave's drift, in tiles a second, along its own direction.
const WAVE_DRIFT: [Vec2; 4] = [
    Vec2::new(0.031, 0.017),
    Vec2::new(-0.023, 0.041),
    Vec2::new(0.053, -0.029),
    Vec2::new(-0.047, -0.037),
];

impl WaterSpec {
    /// Checks the values a scene file or the command line may give; errors name the field.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let bad = |name: &'static str, value: f32, reason: &'static str| SettingsError {
            name: name.into(),
            value: value.to_string(),
            reason,
        };
        if !(self.depth.is_finite() && self.depth > 0.0 && self.depth < 2.0) {
            return Err(bad("scene.water.depth", self.depth, "must be in (0, 2)"));
        }
        if !(self.ior.is_finite() && (1.0..=4.0).contains(&self.ior)) {
            return Err(bad(
                "scene.water.ior",
                self.ior,
                "an index of refraction must be in [1, 4]",
            ));
        }
        if !(self.waves.is_finite() && (0.0..=MAX_WAVES).contains(&self.waves)) {
            return Err(bad("scene.water.waves", self.waves, "must be in [0, 0.1]"));
        }
        if !(self.time.is_finite() && (0.0..=MAX_TIME).contains(&self.time)) {
            return Err(bad(
                "scene.water.time",
                self.time,
                "must be in [0, 10000] seconds",
            ));
        }
        Ok(())
    }

    /// The y of the water's surface: `depth` above the floor (y = 1; raylab's y points down).
    pub fn surface_y(&self) -> f32 {
        1.0 - self.depth
    }
}

/// The water's height field at `p` (in tiles) at `time`, in [−1, 1]: a tile of fBm whose
/// octaves drift ([`Fbm::tile_at`]), so the surface repeats without a seam.
pub fn wave_height(p: Vec2, time: f32) -> f32 {
    WAVE_NOISE.tile_at(p, WAVE_CELLS, time, WAVE_DRIFT)
}

/// The water surface's relief: the normal map of the wave heights at `time`, `amplitude` scene
/// units high ([`normal_map_of_heights`]), tiled every [`WAVE_PERIOD`]. A zero amplitude is a
/// map of (0, 0, 1) everywhere: the flat surface.
pub fn wave_relief(amplitude: f32, time: f32) -> Relief {
    let size = WAVE_MAP_SIZE;
    let at = |i: u32| (i as f32 + 0.5) / size as f32;
    let heights = |i: u32, j: u32| wave_height(Vec2::new(at(i), at(j)), time);
    let image = normal_map_of_heights("waves", size, WAVE_PERIOD, amplitude, &heights);
    Relief {
        normal: Some(NormalMap {
            image: Arc::new(image),
            strength: 1.0,
        }),
        height: None,
        uv_scale: 1.0 / WAVE_PERIOD,
    }
}

/// The water's material: clear glass of the water's index, shaded by its waves.
pub fn water_material(spec: &WaterSpec) -> Material {
    Material {
        kind: MaterialKind::Glass {
            ior: spec.ior,
            tint: Vec3::ONE,
        },
        relief: Some(Arc::new(wave_relief(spec.waves, spec.time))),
        ..Material::diffuse("water", Vec3::ZERO)
    }
}

/// The water's surface: a square over the whole floor at [`WaterSpec::surface_y`], facing up
/// (−y), in two triangles.
pub fn water_triangles(spec: &WaterSpec, material: u32) -> [Triangle; 2] {
    let y = spec.surface_y();
    let (a, b) = (Vec3::new(-1.0, y, -1.0), Vec3::new(1.0, y, -1.0));
    let (c, d) = (Vec3::new(1.0, y, 1.0), Vec3::new(-1.0, y, 1.0));
    let up = |t: Triangle| {
        if t.normal.y < 0.0 {
            t
        } else {
            Triangle::new(t.v0, t.v2, t.v1, material)
        }
    };
    [
        up(Triangle::new(a, b, c, material)),
        up(Triangle::new(a, c, d, material)),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The surface faces up, 0.3 above the floor, and covers it.
    #[test]
    fn the_surface_covers_the_floor_facing_up() {
        let spec = WaterSpec::default();
        let t = water_triangles(&spec, 7);
        for tri in &t {
            assert_eq!(tri.normal, Vec3::new(0.0, -1.0, 0.0));
            assert_eq!(tri.material, 7);
            for v in [tri.v0, tri.v1, tri.v2] {
                assert_eq!(v.y, 0.7);
            }
        }
        let area: f32 = t
            .iter()
            .map(|t| 0.5 * t.edges().0.cross(t.edges().1).length())
            .sum();
        assert_eq!(area, 4.0);
    }

    /// Still water is flat: every texel of the map is (0, 0, 1).
    #[test]
    fn still_water_has_a_flat_map() {
        let relief = wave_relief(0.0, 3.0);
        let map = relief.normal.unwrap();
        for k in 0..50 {
            let uv = Vec2::new(k as f32 * 0.0731, k as f32 * 0.0173);
            assert_eq!(map.tangent_normal(uv), Vec3::Z, "{uv}");
        }
    }

    /// Waves tilt the normal by the slope of the height field: a texel's normal is
    /// (−A·∂h/∂x, −A·∂h/∂y, 1) normalised, the slope by central differences two texels apart;
    /// doubling the amplitude doubles the tilt's tangent. They change with time.
    #[test]
    fn waves_tilt_the_normal_by_their_slope() {
        let (amplitude, time) = (0.004, 1.5);
        let map = wave_relief(amplitude, time).normal.unwrap();
        let n = WAVE_MAP_SIZE;
        let (i, j) = (37u32, 201u32);
        let at = |k: u32| (k as f32 + 0.5) / n as f32;
        let h = |i: u32, j: u32| wave_height(Vec2::new(at(i), at(j)), time);
        let span = 2.0 * WAVE_PERIOD / n as f32;
        let dx = amplitude * (h(i + 1, j) - h(i - 1, j)) / span;
        let dy = amplitude * (h(i, j + 1) - h(i, j - 1)) / span;
        let want = Vec3::new(-dx, -dy, 1.0).normalize();
        // The texel's centre, where the bilinear lookup is the texel itself.
        let got = map.tangent_normal(Vec2::new(at(i), at(j)));
        assert!((got - want).abs().max_element() < 1e-5, "{got} {want}");
        assert!(want.z < 1.0, "the waves tilt it");
        let twice = wave_relief(2.0 * amplitude, time).normal.unwrap();
        let g2 = twice.tangent_normal(Vec2::new(at(i), at(j)));
        assert!(((g2.x / g2.z) - 2.0 * (got.x / got.z)).abs() < 1e-4);
        let later = wave_relief(amplitude, time + 1.0).normal.unwrap();
        assert_ne!(later.tangent_normal(Vec2::new(at(i), at(j))), got);
    }

    #[test]
    fn bad_values_are_refused_by_name() {
        for (spec, field) in [
            (
                WaterSpec {
                    depth: 0.0,
                    ..Default::default()
                },
                "scene.water.depth",
            ),
            (
                WaterSpec {
                    ior: f32::NAN,
                    ..Default::default()
                },
                "scene.water.ior",
            ),
            (
                WaterSpec {
                    waves: -0.1,
                    ..Default::default()
                },
                "scene.water.waves",
            ),
            (
                WaterSpec {
                    time: f32::INFINITY,
                    ..Default::default()
                },
                "scene.water.time",
            ),
        ] {
            let e = spec.validate().unwrap_err();
            assert_eq!(e.name, field);
        }
        assert!(WaterSpec::default().validate().is_ok());
    }
}
