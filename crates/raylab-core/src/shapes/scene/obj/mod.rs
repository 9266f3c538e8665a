//! Loading OBJ models (with the tobj crate) and standing them in the Cornell box.
//!
//! A model is triangulated, mirrored from the usual y-up of OBJ files into raylab's y-down,
//! turned about the vertical, scaled to a height and stood on the floor at a spot of the box
//! ([`Placement`]). Face normals follow the lab's convention (`normalize(e2 × e1)`) and are
//! oriented outwards: by the file's vertex normals when it has them, else by the sign of the
//! mesh's volume (counter-clockwise faces seen from outside, the OBJ convention).
//!
//! A placed model also carries what smooth shading and textures need, per triangle corner:
//! a normal (the file's `vn`, else [`smooth_normals`] of the faces around the corner) and,
//! when the file has `vt`, texture coordinates. A model read from disk ([`obj_scene`](super::spec::obj_scene)) takes
//! the diffuse texture (`map_Kd`) of its material library; a missing or broken library or
//! image is a warning, not an error ([`obj_scene_with_warnings`](super::spec::obj_scene_with_warnings)): the model is still worth
//! seeing untextured.

//!
//! Three files: this one reads and checks the OBJ text ([`parse_obj`], [`load_obj`]),
//! [`library`] the material libraries and the maps they name (and what a model's files weigh),
//! [`placement`] stands the mesh in the box with its normals.

use std::cell::RefCell;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::SceneError;
use crate::base::inputs::{self, MAX_OBJ_BYTES};

mod library;
mod placement;
#[cfg(test)]
mod tests;

pub use library::*;
pub use placement::*;

/// The Stanford bunny (public domain; see assets/models/README.md).
pub const BUNNY_OBJ: &str = include_str!("../../../../../../assets/models/bunny.obj");
/// The Utah teapot (public domain; see assets/models/README.md).
pub const TEAPOT_OBJ: &str = include_str!("../../../../../../assets/models/teapot.obj");

/// The Utah teapot with texture coordinates (made by scripts/assets/make_textured_teapot.py).
pub const TEXTURED_TEAPOT_OBJ: &str =
    include_str!("../../../../../../assets/models/teapot-textured.obj");
/// Its material library, naming the texture.
pub const TEXTURED_TEAPOT_MTL: &str =
    include_str!("../../../../../../assets/models/teapot-textured.mtl");
/// Its porcelain texture.
pub const TEXTURED_TEAPOT_PNG: &[u8] =
    include_bytes!("../../../../../../assets/models/teapot-porcelain.png");

/// A triangle mesh as read from a file, in the file's coordinates.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Per vertex, when the file gives normals.
    pub normals: Option<Vec<Vec3>>,
    /// Per vertex, when the file gives texture coordinates (`vt`), as written there (v = 0 at
    /// the bottom of the image, the OBJ convention).
    pub uvs: Option<Vec<Vec2>>,
    /// Three vertex indices per triangle.
    pub indices: Vec<[u32; 3]>,
}

/// Parses OBJ text; `path` names the source in errors. Material libraries are not read (see
/// [`obj_scene_with_warnings`](super::spec::obj_scene_with_warnings) for a model with its texture).
pub fn parse_obj(text: &[u8], path: &Path) -> Result<Mesh, SceneError> {
    let parsed = parse_with_materials(text, path, |_| Err(tobj::LoadError::OpenFileFailed))?;
    Ok(parsed.mesh)
}

/// A parsed OBJ with what its material libraries said.
struct Parsed {
    mesh: Mesh,
    /// The materials of all libraries that could be read.
    materials: Vec<tobj::Material>,
    /// Indices into `materials` that faces use, in order of first use.
    used: Vec<usize>,
    /// The faces left out.
    dropped: DroppedFaces,
}

/// Parses OBJ text, asking `material_library` for each `mtllib` it names (a library it cannot
/// give is left out, and the faces using its materials get none).
fn parse_with_materials(
    text: &[u8],
    path: &Path,
    material_library: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Result<Parsed, SceneError> {
    // The struct update keeps this compiling whichever optional tobj features are enabled.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    check_element_indices(text).map_err(|reason| SceneError::Obj {
        path: path.to_path_buf(),
        reason,
    })?;
    let mut reader = BufReader::new(text);
    let (models, materials) =
        tobj::load_obj_buf(&mut reader, &options, material_library).map_err(|e| {
            SceneError::Obj {
                path: path.to_path_buf(),
                reason: e.to_string(),
            }
        })?;
    // A library that failed has already been reported by `material_library`.
    let materials = materials.unwrap_or_default();
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let (mut all_have_normals, mut all_have_uvs) = (true, true);
    let mut used = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        // With `single_index`, a model's normals and coordinates are per position or absent.
        if m.normals.len() == 3 * count {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2])),
            );
        } else {
            all_have_normals = false;
        }
        if m.texcoords.len() == 2 * count {
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], t[1])));
        } else {
            all_have_uvs = false;
        }
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|f| [base + f[0], base + f[1], base + f[2]]),
        );
        if let Some(id) = m.material_id
            && id < materials.len()
            && !m.indices.is_empty()
            && !used.contains(&id)
        {
            used.push(id);
        }
    }
    let not_finite = |what: &str, value: String| SceneError::Obj {
        path: path.to_path_buf(),
        reason: format!("{what} {value} is not finite"),
    };
    if let Some(bad) = mesh.positions.iter().find(|p| !p.is_finite()) {
        return Err(not_finite("vertex", bad.to_string()));
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::EmptyMesh {
            path: path.to_path_buf(),
        });
    }
    let dropped = drop_unseen_faces(&mut mesh);
    if mesh.indices.is_empty() {
        return Err(SceneError::Obj {
            path: path.to_path_buf(),
            reason: format!(
                "all of its {} faces are degenerate (no area: their corners coincide or lie on \
                 a line)",
                dropped.degenerate
            ),
        });
    }
    if all_have_normals && !normals.is_empty() {
        if let Some(bad) = normals.iter().find(|n| !n.is_finite()) {
            return Err(not_finite("normal", bad.to_string()));
        }
        mesh.normals = Some(normals);
    }
    if all_have_uvs && !uvs.is_empty() {
        if let Some(bad) = uvs.iter().find(|t| !t.is_finite()) {
            return Err(not_finite("texture coordinate", bad.to_string()));
        }
        mesh.uvs = Some(uvs);
    }
    Ok(Parsed {
        mesh,
        materials,
        used,
        dropped,
    })
}

/// Faces of a file that loading leaves out because they could never be seen
/// ([`drop_unseen_faces`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DroppedFaces {
    /// Faces of zero area: corners that coincide or lie on one line. No ray can hit them.
    pub degenerate: usize,
    /// Faces at exactly the positions of an earlier face, with the same winding: the earlier
    /// face hides them (ties go to the lower index), so they only cost time.
    pub duplicate: usize,
}

impl DroppedFaces {
    /// The loader's warning, or `None` when nothing was left out. `source` names the file.
    pub fn warning(&self, source: &str) -> Option<String> {
        let duplicates = if self.duplicate == 1 {
            "exact duplicate of an earlier face"
        } else {
            "exact duplicates of earlier faces"
        };
        let parts: Vec<String> = [
            (self.degenerate, "degenerate (zero area)"),
            (self.duplicate, duplicates),
        ]
        .iter()
        .filter(|(n, _)| *n > 0)
        .map(|(n, what)| format!("{n} {what}"))
        .collect();
        (!parts.is_empty()).then(|| {
            format!(
                "{source}: left out {} face{} that can never be seen: {}",
                self.degenerate + self.duplicate,
                if self.degenerate + self.duplicate == 1 {
                    ""
                } else {
                    "s"
                },
                parts.join(", ")
            )
        })
    }
}

/// Removes the faces that could never be seen from `mesh.indices` (keeping the order of the
/// others) and counts them:
///
/// * degenerate faces, whose edge vectors' cross product is exactly zero in the file's
///   coordinates (computed in `f64`, where the products of `f32` coordinates are exact): the
///   corners coincide or lie on one line;
/// * exact duplicates: the same three positions (bit for bit, −0 as +0) in the same cyclic
///   order as an earlier face. The first is kept; a face with the opposite winding is a
///   different face (its other side) and is kept too.
///
/// Besides costing memory, copies of a face meet at the same positions, and every copy is a
/// candidate for every ray that reaches one: a file of many copies of one triangle would be
/// slow to load and as slow to trace.
pub fn drop_unseen_faces(mesh: &mut Mesh) -> DroppedFaces {
    use std::collections::HashSet;
    let key = |i: u32| {
        (mesh.positions[i as usize] + Vec3::ZERO)
            .to_array()
            .map(f32::to_bits)
    };
    let mut seen: HashSet<[[u32; 3]; 3]> = HashSet::with_capacity(mesh.indices.len());
    let mut dropped = DroppedFaces::default();
    let positions = &mesh.positions;
    mesh.indices.retain(|face| {
        let [a, b, c] = face.map(|i| positions[i as usize].as_dvec3());
        if (b - a).cross(c - a) == glam::DVec3::ZERO {
            dropped.degenerate += 1;
            return false;
        }
        // The same cycle whichever corner it is read from: start at the smallest key.
        let keys = face.map(key);
        let first = (0..3).min_by_key(|&k| keys[k]).unwrap_or(0);
        let cycle = [0, 1, 2].map(|k| keys[(first + k) % 3]);
        if seen.insert(cycle) {
            true
        } else {
            dropped.duplicate += 1;
            false
        }
    });
    dropped
}

/// The largest element index accepted: a mesh's indices are `u32`, and a file with more
/// vertices than that would be gigabytes of text.
const MAX_ELEMENT_INDEX: i64 = u32::MAX as i64;

/// Refuses the face and line elements (`f`, `l`) whose texture-coordinate or normal indices
/// tobj cannot take: a relative (negative) index pointing before the first `vt` or `vn` read
/// so far, or an index beyond [`MAX_ELEMENT_INDEX`]. tobj 4.0.5 turns such an index into a
/// `usize` near 2⁶⁴ and multiplies it by 2 or 3 before its bounds check: a panic ("attempt to
/// multiply with overflow") where overflow checks are on, as in debug builds, and in release
/// a wrapped product that may pass the check and read the wrong normal. Found by the `obj`
/// fuzz target (tests/fuzz-regressions/obj).
///
/// Lines are read as tobj reads them: one statement a line, words split at whitespace, the
/// counts of `v`, `vt` and `vn` statements so far giving the base of relative indices.
fn check_element_indices(text: &[u8]) -> Result<(), String> {
    let mut counts = [0i64; 3];
    for (number, line) in text.split(|&b| b == b'\n').enumerate() {
        // tobj stops at text that is not UTF-8 with an error of its own.
        let Ok(line) = std::str::from_utf8(line) else {
            return Ok(());
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f" | "l") => {
                for vertex in words {
                    for (kind, index) in vertex.split('/').enumerate().skip(1).take(2) {
                        let Ok(index) = index.parse::<i64>() else {
                            // Empty (`1//3`) or not a number: tobj's to judge.
                            continue;
                        };
                        let name = ["", "texture coordinate", "normal"][kind];
                        if index > MAX_ELEMENT_INDEX || counts[kind] + index < 0 {
                            return Err(format!(
                                "line {}: {name} index {index} is out of range ({} read so \
                                 far)",
                                number + 1,
                                counts[kind]
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Reads and parses an OBJ file (without its material libraries).
pub fn load_obj(path: &Path) -> Result<Mesh, SceneError> {
    parse_obj(&read(path)?, path)
}

/// An OBJ file's bytes: a regular file of at most [`MAX_OBJ_BYTES`].
fn read(path: &Path) -> Result<Vec<u8>, SceneError> {
    inputs::read_capped(path, MAX_OBJ_BYTES, "an OBJ file").map_err(|reason| SceneError::Read {
        path: path.to_path_buf(),
        reason,
    })
}

/// Reads and parses an OBJ file with its material libraries, each read once (see
/// [`load_textured`]), and the warnings so far.
fn parse_file(path: &Path) -> Result<(Parsed, Vec<String>), SceneError> {
    let text = read(path)?;
    let folder = path.parent().unwrap_or(Path::new(""));
    let source = path.display().to_string();
    // tobj asks for libraries through a `Fn`, hence the cells.
    let libraries = RefCell::new(Libraries::default());
    let parsed = parse_with_materials(&text, path, |library| {
        let mut libraries = libraries.borrow_mut();
        let file = folder.join(library);
        if !libraries.seen.insert(file.clone()) {
            // Read already (or failed already): its materials are in, once.
            return Ok((Vec::new(), Default::default()));
        }
        match read_library(&file, library) {
            Ok(materials) => {
                // By name, the later of two of one name winning, as tobj's own map has them.
                let by_name = materials
                    .iter()
                    .enumerate()
                    .map(|(i, m)| (m.name.clone(), i))
                    .collect();
                Ok((materials, by_name))
            }
            Err(reason) => {
                libraries.failed(&file, &reason);
                // Not an error for tobj, which would drop the other libraries' materials too.
                Ok((Vec::new(), Default::default()))
            }
        }
    })?;
    let mut warnings = libraries.into_inner().warnings(&source);
    warnings.extend(parsed.dropped.warning(&source));
    Ok((parsed, warnings))
}

fn builtin_path(name: &str) -> PathBuf {
    PathBuf::from(format!("assets/models/{name}.obj"))
}

/// A built-in model by file name.
pub fn builtin(text: &str, name: &str) -> Result<Mesh, SceneError> {
    parse_obj(text.as_bytes(), &builtin_path(name))
}
