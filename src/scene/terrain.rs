//! A fractal terrain in the box (the lab's "fractals" extension): a heightfield of fractional
//! Brownian motion — octaves of value noise, each twice as fine and half as high as the last —
//! covering the floor, deterministic from a seed.

use glam::Vec3;
use rayon::prelude::*;

use super::{Material, Scene, cornell_box};
use crate::geometry::Triangle;

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainSpec {
    /// The noise's seed: the same seed gives the same terrain.
    pub seed: u64,
    /// Quads per side; the terrain has `2 · grid²` triangles.
    pub grid: u32,
    /// Height of the highest possible peak above the floor, in scene units (the box is 2 high).
    pub height: f32,
    /// Octaves of noise.
    pub octaves: u32,
}

impl Default for TerrainSpec {
    /// About a million triangles (2 · 707² = 999,698).
    fn default() -> Self {
        Self {
            seed: 1,
            grid: 707,
            height: 0.9,
            octaves: 9,
        }
    }
}

/// Uniform in [0, 1) from a lattice point: a hash, so any point can be evaluated alone.
fn lattice(seed: u64, x: i64, z: i64) -> f32 {
    let mut h = seed ^ (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    h ^= (z as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// Smoothly interpolated value noise in [0, 1).
fn value_noise(seed: u64, x: f32, z: f32) -> f32 {
    let (xf, zf) = (x.floor(), z.floor());
    let (xi, zi) = (xf as i64, zf as i64);
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sz) = (smooth(x - xf), smooth(z - zf));
    let a = lattice(seed, xi, zi);
    let b = lattice(seed, xi + 1, zi);
    let c = lattice(seed, xi, zi + 1);
    let d = lattice(seed, xi + 1, zi + 1);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sz
}

/// Fractional Brownian motion at `(x, z)` in [−1, 1]², normalised to [0, 1), faded to 0 at the
/// edges so the terrain meets the floor there (a ray from the open front would otherwise pass
/// under the sheet).
pub fn height_at(spec: &TerrainSpec, x: f32, z: f32) -> f32 {
    let edge = (1.0 - x.abs()).min(1.0 - z.abs()).max(0.0);
    let t = (edge / EDGE_FADE).min(1.0);
    fbm(spec, x, z) * t * t * (3.0 - 2.0 * t)
}

/// Width of the band along the walls over which the terrain sinks to the floor.
const EDGE_FADE: f32 = 0.3;

fn fbm(spec: &TerrainSpec, x: f32, z: f32) -> f32 {
    let mut sum = 0.0;
    let mut norm = 0.0;
    let mut amplitude = 1.0;
    let mut frequency = 2.0;
    for octave in 0..spec.octaves.max(1) {
        let seed = spec
            .seed
            .wrapping_add(u64::from(octave).wrapping_mul(0x632b_e59b_d9b4_e019));
        sum += amplitude * value_noise(seed, x * frequency + 17.0, z * frequency + 31.0);
        norm += amplitude;
        amplitude *= 0.5;
        frequency *= 2.0;
    }
    // Squaring flattens the valleys and sharpens the peaks.
    let h = sum / norm;
    h * h
}

/// The terrain's triangles over the floor (x, z in [−1, 1], floor at y = 1, heights upward,
/// i.e. towards −y), normals facing up.
pub fn terrain_triangles(spec: &TerrainSpec, material: u32) -> Vec<Triangle> {
    let n = spec.grid.max(1) as usize;
    let coord = |i: usize| -1.0 + 2.0 * i as f32 / n as f32;
    let heights: Vec<f32> = (0..=n)
        .into_par_iter()
        .flat_map_iter(|j| {
            (0..=n).map(move |i| 1.0 - spec.height * height_at(spec, coord(i), coord(j)))
        })
        .collect();
    let point = |i: usize, j: usize| Vec3::new(coord(i), heights[j * (n + 1) + i], coord(j));
    (0..n)
        .into_par_iter()
        .flat_map_iter(|j| {
            (0..n).flat_map(move |i| {
                let (a, b) = (point(i, j), point(i + 1, j));
                let (c, d) = (point(i, j + 1), point(i + 1, j + 1));
                // Ordered so that the lab's normal e2 × e1 points up (−y).
                [
                    Triangle::new(a, c, b, material),
                    Triangle::new(b, c, d, material),
                ]
            })
        })
        .collect()
}

/// The Cornell box with the blocks replaced by a terrain covering the floor.
pub fn terrain_scene(spec: &TerrainSpec) -> Scene {
    let scene = cornell_box();
    let mut materials = scene.materials;
    materials.push(Material::diffuse("terrain", Vec3::new(0.75, 0.65, 0.45)));
    let material = (materials.len() - 1) as u32;
    // The room is the first ten triangles; the blocks would stick out of the ground.
    let mut triangles = scene.triangles[..10].to_vec();
    triangles.extend(terrain_triangles(spec, material));
    Scene::new(triangles, materials)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_from_the_seed_and_inside_the_box() {
        let spec = TerrainSpec {
            grid: 40,
            ..TerrainSpec::default()
        };
        let a = terrain_triangles(&spec, 0);
        assert_eq!(a, terrain_triangles(&spec, 0));
        assert_eq!(a.len(), 2 * 40 * 40);
        let other = terrain_triangles(&TerrainSpec { seed: 2, ..spec }, 0);
        assert_ne!(a, other);
        for t in &a {
            for p in [t.v0, t.v1, t.v2] {
                assert!(p.abs().max_element() <= 1.0, "{p}");
                assert!(p.y >= 1.0 - spec.height, "{p}");
            }
            assert!(t.normal.y < 0.0, "faces up: {}", t.normal);
        }
        // Not flat: the heights spread over a good part of the range.
        let (lo, hi) = a.iter().fold((f32::MAX, f32::MIN), |(lo, hi), t| {
            (lo.min(t.v0.y), hi.max(t.v0.y))
        });
        assert!(hi - lo > 0.2, "{lo} {hi}");
    }

    #[test]
    fn the_default_has_about_a_million_triangles() {
        let n = TerrainSpec::default().grid as usize;
        assert!((2 * n * n).abs_diff(1_000_000) < 1_000);
    }
}
