//! A fractal terrain in the box (the lab's "fractals" extension): a heightfield of fractional
//! Brownian motion — octaves of value noise, each twice as fine and half as high as the last —
//! covering the floor, deterministic from a seed. Its triangles carry smooth normals taken
//! from the grid ([`terrain_surface`]), so the hills shade as hills rather than as facets.

use glam::Vec3;
use rayon::prelude::*;

use crate::base::geometry::Triangle;
use crate::base::noise::{Fbm, value_noise};
use crate::shading::material::Material;
use crate::shading::texture::{GRASS, Texture};

/// The terrain's material: diffuse, coloured by height and slope ([`crate::shading::texture::terrain_colour`]) with
/// the borders between grass, rock and snow broken up by fBm noise of the terrain's seed.
pub fn terrain_material(spec: &TerrainSpec) -> Material {
    Material {
        texture: Some(Texture::Terrain {
            floor: FLOOR_Y,
            height: spec.height,
            noise: Fbm {
                seed: spec.seed ^ 0x7e55_a1e5_0c01_0a25,
                octaves: 5,
                ..Fbm::default()
            },
        }),
        ..Material::diffuse("terrain", GRASS)
    }
}

/// The floor's y (raylab's y points down: heights go towards −y).
pub const FLOOR_Y: f32 = 1.0;

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
    Heightfield::new(spec).triangles(material).collect()
}

/// [`terrain_triangles`] and, per triangle, the smooth normals at its corners (in its vertex
/// order): the surface's normal at each grid vertex, from central differences of the heights.
pub fn terrain_surface(spec: &TerrainSpec, material: u32) -> (Vec<Triangle>, Vec<[Vec3; 3]>) {
    let field = Heightfield::new(spec);
    let normals = field.vertex_normals();
    (
        field.triangles(material).collect(),
        field.corner_normals(&normals).collect(),
    )
}

/// Scene heights (y) at the vertices of a square grid of `n` × `n` quads over x, z in [−1, 1].
struct Heightfield {
    n: usize,
    /// Row by row (z), `n + 1` per row (x).
    heights: Vec<f32>,
}

impl Heightfield {
    /// The terrain of `spec`.
    fn new(spec: &TerrainSpec) -> Self {
        Self::from_fn(spec.grid.max(1) as usize, |x, z| {
            1.0 - spec.height * height_at(spec, x, z)
        })
    }

    /// Heights `y(x, z)` sampled on `n` × `n` quads.
    fn from_fn(n: usize, y: impl Fn(f32, f32) -> f32 + Sync) -> Self {
        let heights = (0..=n)
            .into_par_iter()
            .flat_map_iter(|j| {
                let y = &y;
                (0..=n).map(move |i| y(coord(n, i), coord(n, j)))
            })
            .collect();
        Self { n, heights }
    }

    fn point(&self, i: usize, j: usize) -> Vec3 {
        let n = self.n;
        Vec3::new(coord(n, i), self.heights[j * (n + 1) + i], coord(n, j))
    }

    /// The unit normal at grid vertex (i, j), facing up like the triangles. The surface is
    /// y = Y(x, z), so (∂Y/∂x, −1, ∂Y/∂z) is normal to it and points to −y; the slopes are
    /// central differences of the neighbouring heights (one-sided at the edges). Exact for a
    /// plane, and smooth across the triangles, whose face normals jump from one to the next.
    fn normal(&self, i: usize, j: usize) -> Vec3 {
        let n = self.n;
        let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n));
        let (j0, j1) = (j.saturating_sub(1), (j + 1).min(n));
        let h = |i: usize, j: usize| self.heights[j * (n + 1) + i];
        let dx = (h(i1, j) - h(i0, j)) / (coord(n, i1) - coord(n, i0));
        let dz = (h(i, j1) - h(i, j0)) / (coord(n, j1) - coord(n, j0));
        Vec3::new(dx, -1.0, dz).normalize()
    }

    /// [`Heightfield::normal`] at every grid vertex, in the order of `heights`.
    fn vertex_normals(&self) -> Vec<Vec3> {
        let n = self.n;
        (0..=n)
            .into_par_iter()
            .flat_map_iter(|j| (0..=n).map(move |i| self.normal(i, j)))
            .collect()
    }

    /// Two triangles per quad, quads row by row.
    fn triangles(&self, material: u32) -> impl ParallelIterator<Item = Triangle> + '_ {
        self.quads().flat_map_iter(move |(i, j)| {
            let (a, b) = (self.point(i, j), self.point(i + 1, j));
            let (c, d) = (self.point(i, j + 1), self.point(i + 1, j + 1));
            // Ordered so that the lab's normal e2 × e1 points up (−y).
            [
                Triangle::new(a, c, b, material),
                Triangle::new(b, c, d, material),
            ]
        })
    }

    /// The corners' normals of [`Heightfield::triangles`], in the same order, from
    /// [`Heightfield::vertex_normals`].
    fn corner_normals<'a>(
        &'a self,
        normals: &'a [Vec3],
    ) -> impl ParallelIterator<Item = [Vec3; 3]> + 'a {
        let n = self.n;
        self.quads().flat_map_iter(move |(i, j)| {
            let at = |i: usize, j: usize| normals[j * (n + 1) + i];
            let (a, b) = (at(i, j), at(i + 1, j));
            let (c, d) = (at(i, j + 1), at(i + 1, j + 1));
            [[a, c, b], [b, c, d]]
        })
    }

    /// The quads (i, j), row by row; rows in parallel.
    fn quads(&self) -> impl ParallelIterator<Item = (usize, usize)> {
        let n = self.n;
        (0..n)
            .into_par_iter()
            .flat_map_iter(move |j| (0..n).map(move |i| (i, j)))
    }
}

/// The x or z of grid line `i` of `n` quads over [−1, 1].
fn coord(n: usize, i: usize) -> f32 {
    -1.0 + 2.0 * i as f32 / n as f32
}

/// Appends the terrain's triangles to `triangles` and their corners' normals to `normals`
/// (what [`terrain_surface`] returns, without a second copy of a million triangles).
pub(super) fn extend_with_terrain(
    spec: &TerrainSpec,
    material: u32,
    triangles: &mut Vec<Triangle>,
    normals: &mut Vec<Option<[Vec3; 3]>>,
) {
    let field = Heightfield::new(spec);
    triangles.par_extend(field.triangles(material));
    normals.par_extend(field.corner_normals(&field.vertex_normals()).map(Some));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::spec::terrain_scene;

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

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-6
    }

    #[test]
    fn a_flat_terrain_shades_with_its_face_normal() {
        let spec = TerrainSpec {
            grid: 6,
            height: 0.0,
            ..TerrainSpec::default()
        };
        let scene = terrain_scene(&spec);
        assert_eq!(scene.triangles.len(), 10 + 2 * 6 * 6);
        assert!(scene.uvs.is_empty());
        for (i, t) in scene.triangles.iter().enumerate() {
            if i < 10 {
                assert_eq!(scene.vertex_normals[i], None, "the room stays flat");
                continue;
            }
            assert!(close(t.normal, Vec3::NEG_Y), "{}", t.normal);
            assert_eq!(scene.vertex_normals[i], Some([Vec3::NEG_Y; 3]));
            for (u, v) in [(0.0, 0.0), (0.5, 0.5), (0.1, 0.7)] {
                assert!(close(scene.shading_normal(i, u, v, true), Vec3::NEG_Y));
            }
        }
    }

    #[test]
    fn on_a_sloped_plane_every_normal_is_the_planes() {
        // Heights a·(x + 1) + b·(z + 1) above the floor: y = 1 − a·(x + 1) − b·(z + 1), so
        // ∂y/∂x = −a, ∂y/∂z = −b and the upward normal is (−a, −1, −b)/√(1 + a² + b²).
        // a = 0.5, b = 0: (−0.5, −1, 0)/√1.25 = (−0.4472136, −0.8944272, 0).
        // a = 0.5, b = 0.25: (−0.5, −1, −0.25)/√1.3125 = (−0.4364358, −0.8728716, −0.2182179).
        for (a, b, expected) in [
            (0.5, 0.0, Vec3::new(-0.447_213_6, -0.894_427_2, 0.0)),
            (
                0.5,
                0.25,
                Vec3::new(-0.436_435_8, -0.872_871_6, -0.218_217_9),
            ),
        ] {
            let field = Heightfield::from_fn(8, |x, z| 1.0 - a * (x + 1.0) - b * (z + 1.0));
            let normals = field.vertex_normals();
            assert_eq!(normals.len(), 9 * 9);
            for n in &normals {
                assert!(close(*n, expected), "{n} against {expected}");
            }
            // The faces agree, so smooth shading looks exactly like flat shading here.
            let triangles: Vec<Triangle> = field.triangles(0).collect();
            let corners: Vec<[Vec3; 3]> = field.corner_normals(&normals).collect();
            assert_eq!(triangles.len(), corners.len());
            for (t, c) in triangles.iter().zip(&corners) {
                assert!(close(t.normal, expected), "{}", t.normal);
                assert!(c.iter().all(|n| close(*n, expected)));
            }
        }
    }

    #[test]
    fn corner_normals_belong_to_their_corners() {
        // A bump y = 1 − (x² + z²)/4 (a paraboloid): the normal at (x, z) is (−x/2, −1, −z/2)
        // normalised, and central differences are exact for a quadratic away from the edges.
        let field = Heightfield::from_fn(4, |x, z| 1.0 - 0.25 * (x * x + z * z));
        let normals = field.vertex_normals();
        let triangles: Vec<Triangle> = field.triangles(0).collect();
        let corners: Vec<[Vec3; 3]> = field.corner_normals(&normals).collect();
        for (t, c) in triangles.iter().zip(&corners) {
            for (p, n) in [t.v0, t.v1, t.v2].into_iter().zip(c) {
                if p.x.abs() < 1.0 && p.z.abs() < 1.0 {
                    let expected = Vec3::new(-0.5 * p.x, -1.0, -0.5 * p.z).normalize();
                    assert!(close(*n, expected), "{n} at {p}");
                }
                assert!(
                    n.dot(t.normal) > 0.9,
                    "faces the face's way: {n} {}",
                    t.normal
                );
            }
        }
    }

    #[test]
    fn the_surface_matches_the_triangles() {
        let spec = TerrainSpec {
            grid: 30,
            ..TerrainSpec::default()
        };
        let scene = terrain_scene(&spec);
        let material = scene.triangles[10].material;
        let (triangles, normals) = terrain_surface(&spec, material);
        assert!(triangles == terrain_triangles(&spec, material));
        assert_eq!(normals.len(), triangles.len());
        assert!(scene.triangles[10..] == triangles[..]);
        for (i, n) in normals.iter().enumerate() {
            assert_eq!(scene.vertex_normals[10 + i], Some(*n));
            for m in n {
                assert!(m.y < 0.0 && (m.length() - 1.0).abs() < 1e-6, "{m}");
            }
        }
    }
}
