//! Loading OBJ models (with the tobj crate) and standing them in the Cornell box.
//!
//! A model is triangulated, mirrored from the usual y-up of OBJ files into raylab's y-down,
//! turned about the vertical, scaled to a height and stood on the floor at a spot of the box
//! ([`Placement`]). Face normals follow the lab's convention (`normalize(e2 × e1)`) and are
//! oriented outwards: by the file's vertex normals when it has them, else by the sign of the
//! mesh's volume (counter-clockwise faces seen from outside, the OBJ convention).

use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};

use super::{Material, Scene, SceneError, cornell_box};
use crate::geometry::Triangle;

/// The Stanford bunny (public domain; see assets/models/README.md).
pub const BUNNY_OBJ: &str = include_str!("../../assets/models/bunny.obj");
/// The Utah teapot (public domain; see assets/models/README.md).
pub const TEAPOT_OBJ: &str = include_str!("../../assets/models/teapot.obj");

/// A triangle mesh as read from a file, in the file's coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Per vertex, when the file gives normals.
    pub normals: Option<Vec<Vec3>>,
    /// Three vertex indices per triangle.
    pub indices: Vec<[u32; 3]>,
}

/// Where and how a model stands in the box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Height of the model in scene units (the box is 2 high); the scale follows from it.
    pub height: f32,
    /// Where the centre of the model's footprint stands on the floor: (x, z).
    pub floor_position: [f32; 2],
    /// Turn about the vertical axis, in radians; positive turns the model's +z towards +x.
    pub yaw: f32,
    /// The model's diffuse reflectance ρ.
    pub reflectance: Vec3,
}

impl Placement {
    /// In front of the tall blue block and left of the short red one, well lit and in full
    /// view of the default camera.
    pub const FRONT_LEFT: Placement = Placement {
        height: 0.75,
        floor_position: [-0.5, -0.5],
        yaw: 0.0,
        reflectance: Vec3::new(0.75, 0.75, 0.75),
    };
    /// The teapot: turned so its spout points at the camera's right, a warm white.
    pub const TEAPOT: Placement = Placement {
        height: 0.75,
        floor_position: [-0.5, -0.5],
        yaw: 0.5,
        reflectance: Vec3::new(0.8, 0.75, 0.6),
    };
    /// Largest horizontal extent a placed model may have: it must stay clear of the blocks.
    pub const MAX_WIDTH: f32 = 0.7;
}

/// Parses OBJ text; `path` names the source in errors.
pub fn parse_obj(text: &[u8], path: &Path) -> Result<Mesh, SceneError> {
    // The struct update keeps this compiling whichever optional tobj features are enabled.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = BufReader::new(text);
    // raylab gives the model one reflectance: material libraries are not read.
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| SceneError::Obj {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    let mut all_have_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if m.normals.len() == m.positions.len() {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        } else {
            all_have_normals = false;
        }
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|f| [base + f[0], base + f[1], base + f[2]]),
        );
    }
    if let Some(bad) = mesh.positions.iter().find(|p| !p.is_finite()) {
        return Err(SceneError::Obj {
            path: path.to_path_buf(),
            reason: format!("vertex {bad} is not finite"),
        });
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::EmptyMesh {
            path: path.to_path_buf(),
        });
    }
    if all_have_normals && !normals.is_empty() {
        mesh.normals = Some(normals);
    }
    Ok(mesh)
}

/// Reads and parses an OBJ file.
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    let text = std::fs::read(path).map_err(|e| SceneError::Read {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    parse_obj(&text, path)
}

/// The mesh's triangles placed in the box, with material `material`.
pub fn place(mesh: &Mesh, placement: &Placement, material: u32) -> Vec<Triangle> {
    // Mirror y (OBJ is y-up, raylab y-down), then turn about the vertical.
    let (s, c) = placement.yaw.sin_cos();
    let turn = Mat3::from_cols(Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c));
    let linear = turn * Mat3::from_diagonal(Vec3::new(1.0, -1.0, 1.0));
    let turned: Vec<Vec3> = mesh.positions.iter().map(|&p| linear * p).collect();
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &p in &turned {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let size = hi - lo;
    // Scale to the height, but never wider than the free floor allows.
    let mut scale = placement.height / size.y.max(f32::MIN_POSITIVE);
    let width = size.x.max(size.z) * scale;
    if width > Placement::MAX_WIDTH {
        scale *= Placement::MAX_WIDTH / width;
    }
    // The lowest point (largest y) rests on the floor at y = 1.
    let [fx, fz] = placement.floor_position;
    let anchor = Vec3::new(0.5 * (lo.x + hi.x), hi.y, 0.5 * (lo.z + hi.z));
    let to_scene = |p: Vec3| (p - anchor) * scale + Vec3::new(fx, 1.0, fz);
    let scene_points: Vec<Vec3> = turned.iter().map(|&p| to_scene(p)).collect();

    // Which way faces point: the file's normals, else the sign of the enclosed volume (for
    // counter-clockwise faces seen from outside, Σ v0·(v1 × v2) > 0).
    let volume: f32 = mesh
        .indices
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| mesh.positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum();
    // The mirror reverses handedness: outward e1 × e2 in the file becomes e2 × e1 here, which
    // is the lab's normal. A clockwise file needs the opposite.
    let flip_all = volume < 0.0;
    let normal_matrix = linear; // a rotation times a mirror: its own inverse transpose
    mesh.indices
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| scene_points[i as usize]);
            let mut t = Triangle::new(a, b, c, material);
            let flip = match &mesh.normals {
                Some(normals) => {
                    let n: Vec3 = f.iter().map(|&i| normals[i as usize]).sum();
                    t.normal.dot(normal_matrix * n) < 0.0
                }
                None => flip_all,
            };
            if flip {
                t = Triangle::new(a, c, b, material);
            }
            t
        })
        .collect()
}

/// The Cornell box with `mesh` standing in it.
pub fn model_in_box(mesh: &Mesh, placement: &Placement, name: &str) -> Scene {
    let scene = cornell_box();
    let mut triangles = scene.triangles;
    let mut materials = scene.materials;
    materials.push(Material::diffuse(name, placement.reflectance));
    let material = (materials.len() - 1) as u32;
    triangles.extend(place(mesh, placement, material));
    Scene::new(triangles, materials)
}

/// An OBJ file standing in the box at [`Placement::FRONT_LEFT`].
pub fn obj_scene(path: &Path) -> Result<Scene, SceneError> {
    let mesh = load_obj(path)?;
    let name = path
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    Ok(model_in_box(&mesh, &Placement::FRONT_LEFT, &name))
}

/// A built-in model by file name.
pub(super) fn builtin(text: &str, name: &str) -> Result<Mesh, SceneError> {
    parse_obj(
        text.as_bytes(),
        &PathBuf::from(format!("assets/models/{name}.obj")),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_models_load() {
        let bunny = builtin(BUNNY_OBJ, "bunny").unwrap();
        assert_eq!(bunny.indices.len(), 3674);
        let teapot = builtin(TEAPOT_OBJ, "teapot").unwrap();
        assert_eq!(teapot.indices.len(), 992);
    }

    #[test]
    fn a_placed_model_stands_on_the_floor_clear_of_the_blocks() {
        let mesh = builtin(BUNNY_OBJ, "bunny").unwrap();
        let tris = place(&mesh, &Placement::FRONT_LEFT, 7);
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for t in &tris {
            for p in [t.v0, t.v1, t.v2] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        assert!((hi.y - 1.0).abs() < 1e-6, "rests on the floor: {hi}");
        let height = hi.y - lo.y;
        assert!(height > 0.5 && height <= 0.75 + 1e-4, "{height} high");
        assert!((hi.x - lo.x).max(hi.z - lo.z) <= Placement::MAX_WIDTH + 1e-4);
        // The short block starts at x = −0.05 (z < −0.02), the tall one at z = −0.11.
        assert!(
            hi.x < -0.1 && hi.z < -0.12 && lo.x > -1.0 && lo.z > -1.0,
            "{lo} {hi}"
        );
    }

    #[test]
    fn faces_point_outwards() {
        // Most of a closed model's faces point away from its centre.
        for (text, name) in [(BUNNY_OBJ, "bunny"), (TEAPOT_OBJ, "teapot")] {
            let mesh = builtin(text, name).unwrap();
            let tris = place(&mesh, &Placement::FRONT_LEFT, 0);
            let centre: Vec3 = tris.iter().map(|t| t.centroid()).sum::<Vec3>() / tris.len() as f32;
            let out = tris
                .iter()
                .filter(|t| t.normal.dot(t.centroid() - centre) > 0.0)
                .count();
            assert!(out > tris.len() * 3 / 4, "{name}: {out} of {}", tris.len());
        }
    }

    #[test]
    fn normals_in_the_file_orient_the_faces() {
        // One triangle, clockwise seen from +z, with normals saying it faces +z.
        let text = b"v 0 0 0\nv 0 1 0\nv 1 0 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
        let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
        assert!(mesh.normals.is_some());
        let tris = place(&mesh, &Placement::FRONT_LEFT, 0);
        assert!(tris[0].normal.z > 0.99, "{}", tris[0].normal);
    }

    #[test]
    fn bad_files_are_errors_naming_the_file() {
        let p = Path::new("models/broken.obj");
        for text in [
            &b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"[..],
            b"v 0 zero 0\n",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
        ] {
            let e = parse_obj(text, p).unwrap_err();
            assert!(e.to_string().contains("broken.obj"), "{e}");
        }
        let e = parse_obj(b"# nothing\nv 0 0 0\n", p).unwrap_err();
        assert!(matches!(e, SceneError::EmptyMesh { .. }), "{e}");
        assert!(e.to_string().contains("broken.obj") && e.to_string().contains("no triangles"));
        let e = load_obj(Path::new("/no/such/model.obj")).unwrap_err();
        assert!(e.to_string().contains("/no/such/model.obj"), "{e}");
        let e = parse_obj(b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", p).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }
}
