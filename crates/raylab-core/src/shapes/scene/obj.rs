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

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::SceneError;
use crate::base::geometry::Triangle;
use crate::base::inputs::{self, Input, MAX_MTL_BYTES, MAX_OBJ_BYTES};
use crate::shading::relief::{NormalMap, Relief};
use crate::shading::texture::{Decoding, Texture, TextureError, TextureImage};

/// The Stanford bunny (public domain; see assets/models/README.md).
pub const BUNNY_OBJ: &str = include_str!("../../../../../assets/models/bunny.obj");
/// The Utah teapot (public domain; see assets/models/README.md).
pub const TEAPOT_OBJ: &str = include_str!("../../../../../assets/models/teapot.obj");

/// The crease angle for normals computed from the faces, in degrees: at a corner, only the
/// faces whose normal is within 60° of the corner's own face are smoothed together.
///
/// Curved surfaces tessellated as finely as the bunny or the teapot turn by far less than that
/// from one face to the next (a cylinder of 12 facets, by 30°), while deliberate edges — a
/// cube's 90°, the teapot's lid on its body — turn by more, and stay sharp.
pub const CREASE_ANGLE_DEGREES: f32 = 60.0;

/// The Utah teapot with texture coordinates (made by scripts/assets/make_textured_teapot.py).
pub const TEXTURED_TEAPOT_OBJ: &str =
    include_str!("../../../../../assets/models/teapot-textured.obj");
/// Its material library, naming the texture.
pub const TEXTURED_TEAPOT_MTL: &str =
    include_str!("../../../../../assets/models/teapot-textured.mtl");
/// Its porcelain texture.
pub const TEXTURED_TEAPOT_PNG: &[u8] =
    include_bytes!("../../../../../assets/models/teapot-porcelain.png");

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
/// candidate for every ray that reaches one: a file of a million copies of one triangle took
/// minutes to load and would take as long to trace.
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

/// The memory loading an OBJ file takes, a byte of its text: a face of some 40 bytes becomes a
/// triangle, its corners' normals and texture coordinates and its share of the structure, some
/// 300 bytes.
pub const OBJ_BYTES_FACTOR: u64 = 8;

/// Roughly the most memory loading the OBJ file at `path` with its material libraries and
/// texture takes, in bytes ([`load_textured`]), read from the files without loading them:
///
/// * [`OBJ_BYTES_FACTOR`] bytes a byte of the OBJ file;
/// * each material library its `mtllib` lines name, once however often it is named
///   ([`library_bytes`]);
/// * the largest texture those libraries name, as its header gives its size:
///   [`TextureImage::decoding_bytes`] and the file itself (only one texture is decoded), and
///   likewise the largest normal map (`norm`, `map_Bump`, `bump`; one is decoded beside it).
///
/// 0 for a file that cannot be read or is too large to be: loading it fails anyway. The OBJ
/// file is read through once, looking only at its `mtllib` lines.
pub fn memory_estimate(path: &Path) -> u64 {
    let Some(named) = named_by(path) else {
        return 0;
    };
    let mut total = OBJ_BYTES_FACTOR * named.obj_bytes;
    for library in &named.libraries {
        if let Some((bytes, materials)) = library.read {
            total += library_bytes(bytes, materials);
        }
    }
    let mut largest_texture = 0;
    let mut largest_normal_map = 0;
    for (texture, normal) in &named.textures {
        if let Some((w, h)) = TextureImage::dimensions(texture) {
            let file = std::fs::metadata(texture).map_or(0, |m| m.len());
            let bytes = TextureImage::decoding_bytes(w, h) + file;
            let largest = if *normal {
                &mut largest_normal_map
            } else {
                &mut largest_texture
            };
            *largest = (*largest).max(bytes);
        }
    }
    total + largest_texture + largest_normal_map
}

/// The files an OBJ file reads beside itself — its material libraries and the textures and
/// normal maps they name — with the file itself first, as [`Input`]s: what no output of a
/// render of it may replace. Read as [`memory_estimate`] reads them, without loading anything;
/// a library that cannot be read is listed all the same (it is the user's file).
pub fn files_read(path: &Path) -> Vec<Input> {
    let mut files = vec![Input::new(path, "a model")];
    if let Some(named) = named_by(path) {
        files.extend(
            named
                .libraries
                .into_iter()
                .map(|l| Input::new(&l.path, "a material library")),
        );
        files.extend(named.textures.into_iter().map(|(texture, normal)| {
            Input::new(
                &texture,
                if normal {
                    "a normal map of a model"
                } else {
                    "a texture of a model"
                },
            )
        }));
    }
    files
}

/// What an OBJ file names beside itself, read from its `mtllib` lines and its libraries' map
/// statements.
struct Named {
    /// The OBJ file's length.
    obj_bytes: u64,
    /// Each library its `mtllib` lines name, once.
    libraries: Vec<NamedLibrary>,
    /// Each texture (`false`) and normal map (`true`) the libraries name, once.
    textures: Vec<(PathBuf, bool)>,
}

struct NamedLibrary {
    path: PathBuf,
    /// Its length and material count, if it could be read.
    read: Option<(u64, u64)>,
}

/// [`Named`] for the OBJ file at `path`; `None` for a file that cannot be read or is too
/// large to be. The OBJ file is read through once, looking only at its `mtllib` lines; a
/// texture's name is taken relative to the library that names it.
fn named_by(path: &Path) -> Option<Named> {
    let (file, len) = inputs::open_regular(path).ok()?;
    if len > MAX_OBJ_BYTES {
        return None;
    }
    let folder = path.parent().unwrap_or(Path::new(""));
    let mut named = Named {
        obj_bytes: len,
        libraries: Vec::new(),
        textures: Vec::new(),
    };
    let mut seen = std::collections::HashSet::new();
    let libraries = library_names(std::io::BufReader::new(file)).unwrap_or_default();
    for library in libraries {
        let library_path = folder.join(&library);
        let Ok(bytes) = inputs::read_capped(&library_path, MAX_MTL_BYTES, "") else {
            named.libraries.push(NamedLibrary {
                path: library_path,
                read: None,
            });
            continue;
        };
        let (materials, names, normal_names) = scan_library(&bytes);
        named.libraries.push(NamedLibrary {
            path: library_path,
            read: Some((bytes.len() as u64, materials)),
        });
        let beside = Path::new(&library).parent().unwrap_or(Path::new(""));
        for (name, normal) in names
            .into_iter()
            .map(|n| (n, false))
            .chain(normal_names.into_iter().map(|n| (n, true)))
        {
            let texture = folder.join(beside).join(name);
            if seen.insert((texture.clone(), normal)) {
                named.textures.push((texture, normal));
            }
        }
    }
    Some(named)
}

/// The memory a material library of `bytes` bytes and `materials` materials takes loaded: each
/// material's record ([`tobj::Material`]) and its entry in the table by name, 128 bytes, and
/// four times the text for the strings it holds (names, texture names, unknown parameters).
pub fn library_bytes(bytes: u64, materials: u64) -> u64 {
    4 * bytes + materials * (std::mem::size_of::<tobj::Material>() as u64 + 128)
}

/// The distinct material libraries an OBJ text's `mtllib` lines name, in order, read as tobj
/// reads them (the first word `mtllib`, the name the rest of the line, trimmed). Only lines'
/// first 4 KiB are looked at, so a file of one endless line is read through in constant
/// memory.
fn library_names(mut obj: impl std::io::BufRead) -> std::io::Result<Vec<String>> {
    use std::io::{BufRead as _, Read as _};
    const LOOKED_AT: u64 = 4096;
    let mut names = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut line = Vec::new();
    loop {
        line.clear();
        let n = (&mut obj).take(LOOKED_AT).read_until(b'\n', &mut line)?;
        if n == 0 {
            return Ok(names);
        }
        if line.last() != Some(&b'\n') && n as u64 == LOOKED_AT {
            // The rest of a long line.
            loop {
                let buffer = obj.fill_buf()?;
                if buffer.is_empty() {
                    break;
                }
                match buffer.iter().position(|&b| b == b'\n') {
                    Some(i) => {
                        obj.consume(i + 1);
                        break;
                    }
                    None => {
                        let all = buffer.len();
                        obj.consume(all);
                    }
                }
            }
        }
        let Ok(text) = std::str::from_utf8(&line) else {
            continue;
        };
        if text.split_whitespace().next() == Some("mtllib")
            && let Some((_, name)) = text.split_once(' ')
        {
            let name = name.trim();
            if !name.is_empty() && seen.insert(name.to_owned()) {
                names.push(name.to_owned());
            }
        }
    }
}

/// A material library's material count (`newmtl` lines), the texture files its `map_Kd`
/// lines name and the normal maps its `norm`, `map_Bump` and `bump` lines name (their
/// options left out, [`map_options`]), read as tobj reads them.
fn scan_library(bytes: &[u8]) -> (u64, Vec<String>, Vec<String>) {
    let text = String::from_utf8_lossy(bytes);
    let mut materials = 0;
    let mut textures = Vec::new();
    let mut normal_maps = Vec::new();
    for line in text.lines().map(str::trim) {
        let keyword = line.split_whitespace().next();
        match keyword {
            Some("newmtl") => materials += 1,
            Some("map_Kd") => {
                if let Some(name) = line.get(6..).map(str::trim).filter(|n| !n.is_empty()) {
                    textures.push(name.to_owned());
                }
            }
            Some(k @ ("norm" | "map_Bump" | "map_bump" | "bump")) => {
                let (file, _) = map_options(line.get(k.len()..).unwrap_or(""));
                if !file.is_empty() {
                    normal_maps.push(file);
                }
            }
            _ => {}
        }
    }
    (materials, textures, normal_maps)
}

/// A mesh placed in the box: its triangles and, per triangle, what its three corners carry,
/// in the triangle's vertex order (`v0`, `v1`, `v2`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedModel {
    pub triangles: Vec<Triangle>,
    /// Unit normals for smooth shading, each on the outward side of its triangle.
    pub normals: Vec<[Vec3; 3]>,
    /// Texture coordinates, when the file has them.
    pub uvs: Option<Vec<[Vec2; 3]>>,
}

/// The mesh's triangles placed in the box, with material `material`.
pub fn place(mesh: &Mesh, placement: &Placement, material: u32) -> Vec<Triangle> {
    place_model(mesh, placement, material).triangles
}

/// The mesh placed in the box, with material `material`, its corners' normals and texture
/// coordinates.
pub fn place_model(mesh: &Mesh, placement: &Placement, material: u32) -> PlacedModel {
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
    // Normals transform by the inverse transpose of the positions' linear map. That map is
    // a rotation times a mirror times a uniform scale: its inverse transpose is the rotation
    // times the mirror divided by the scale, and the scale goes with normalising.
    let normal_matrix = linear;
    // Each triangle's vertex indices in the order its scene triangle has them.
    let (triangles, corners): (Vec<Triangle>, Vec<[u32; 3]>) = mesh
        .indices
        .iter()
        .map(|&f| {
            let [a, b, c] = f.map(|i| scene_points[i as usize]);
            let t = Triangle::new(a, b, c, material);
            let flip = match &mesh.normals {
                Some(normals) => {
                    let n: Vec3 = f.iter().map(|&i| normals[i as usize]).sum();
                    t.normal.dot(normal_matrix * n) < 0.0
                }
                None => flip_all,
            };
            if flip {
                (Triangle::new(a, c, b, material), [f[0], f[2], f[1]])
            } else {
                (t, f)
            }
        })
        .unzip();
    let normals = match &mesh.normals {
        Some(file) => corners
            .iter()
            .zip(&triangles)
            .map(|(corner, t)| {
                corner.map(|i| {
                    let n = (normal_matrix * file[i as usize])
                        .try_normalize()
                        .unwrap_or(t.normal);
                    // A shading normal behind its face would light the face as if from
                    // behind; the face's side is the outward one decided above.
                    if n.dot(t.normal) < 0.0 { -n } else { n }
                })
            })
            .collect(),
        None => {
            let face_normals: Vec<Vec3> = triangles.iter().map(|t| t.normal).collect();
            smooth_normals(
                &scene_points,
                &corners,
                &face_normals,
                CREASE_ANGLE_DEGREES.to_radians(),
            )
        }
    };
    let uvs = mesh.uvs.as_ref().map(|uvs| {
        corners
            .iter()
            .map(|corner| corner.map(|i| uvs[i as usize]))
            .collect()
    });
    PlacedModel {
        triangles,
        normals,
        uvs,
    }
}

/// Per triangle corner, a unit normal for smooth shading, computed from the faces around it.
///
/// `face_normals` are the triangles' unit normals (zero for a degenerate triangle, which then
/// contributes nothing). At a corner, the faces that touch the same **position** — welded by
/// exact equality, because OBJ files repeat a vertex wherever its texture coordinates or
/// normals differ, as along a texture seam — are summed, each weighted by its angle at that
/// position, but only those whose normal is within `crease_angle` (radians) of this corner's
/// own face: a sharper edge stays sharp. Weighting by angle makes the result depend on the
/// shape, not on how it was cut into triangles (a square face split in two still counts as one
/// 90° corner). A corner with nothing to average (a degenerate face) keeps its face's normal.
/// The time is linear in the number of faces: where more than [`MAX_FAN`] faces meet at one
/// position, equal normals are summed once, and more than that many distinct normals are
/// averaged whole (see [`MAX_FAN`]).
pub fn smooth_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    face_normals: &[Vec3],
    crease_angle: f32,
) -> Vec<[Vec3; 3]> {
    debug_assert_eq!(triangles.len(), face_normals.len());
    // Weld: one id per distinct position (−0 read as +0, which is the same point).
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let weld: Vec<u32> = positions
        .iter()
        .map(|&p| {
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = ids.len() as u32;
            *ids.entry(key).or_insert(next)
        })
        .collect();
    let welded = |i: u32| weld[i as usize] as usize;
    let degenerate = |f: usize| {
        let n = face_normals[f];
        !(n.length_squared() > 0.0) || !n.is_finite()
    };
    // The faces around each welded position, with their angle there (compressed rows: those
    // of position w are `around[start[w]..start[w + 1]]`).
    let mut start = vec![0usize; ids.len() + 1];
    for (f, tri) in triangles.iter().enumerate() {
        if !degenerate(f) {
            for &i in tri {
                start[welded(i) + 1] += 1;
            }
        }
    }
    for w in 0..ids.len() {
        start[w + 1] += start[w];
    }
    let mut fill = start.clone();
    let mut around = vec![(0u32, 0.0f32); start[ids.len()]];
    for (f, tri) in triangles.iter().enumerate() {
        if degenerate(f) {
            continue;
        }
        let p = tri.map(|i| positions[i as usize]);
        for k in 0..3 {
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            // atan2 of |sin| and cos: accurate for small and near-straight angles alike.
            let angle = e1.cross(e2).length().atan2(e1.dot(e2));
            let w = welded(tri[k]);
            around[fill[w]] = (f as u32, angle);
            fill[w] += 1;
        }
    }
    let cos_crease = crease_angle.cos();
    // Positions with more than `MAX_FAN` faces around them: their faces grouped by normal
    // (so that each corner there costs the number of distinct normals, not of faces).
    let fans: HashMap<usize, Fan> = (0..ids.len())
        .filter(|&w| start[w + 1] - start[w] > MAX_FAN)
        .map(|w| (w, Fan::of(&around[start[w]..start[w + 1]], face_normals)))
        .collect();
    triangles
        .par_iter()
        .enumerate()
        .map(|(f, tri)| {
            let own = face_normals[f];
            if degenerate(f) {
                return [own; 3];
            }
            let within_crease = |n: Vec3, angle: f32| {
                if n.dot(own) >= cos_crease {
                    angle * n
                } else {
                    Vec3::ZERO
                }
            };
            tri.map(|i| {
                let w = welded(i);
                let sum: Vec3 = match fans.get(&w) {
                    None => around[start[w]..start[w + 1]]
                        .iter()
                        .map(|&(g, angle)| within_crease(face_normals[g as usize], angle))
                        .sum(),
                    Some(Fan::Grouped(groups)) => groups
                        .iter()
                        .map(|&(n, angle)| within_crease(n, angle))
                        .sum(),
                    Some(Fan::Whole(sum)) => *sum,
                };
                sum.try_normalize().unwrap_or(own)
            })
        })
        .collect()
}

/// Above this many faces around one position, [`smooth_normals`] groups them by normal; above
/// this many distinct normals, it averages them all, without the crease test. Averaging each
/// corner over every face around its position costs the square of their number: a file of a
/// million copies of one triangle (a million faces around each of three positions) took
/// minutes. No real surface has more than a few dozen differently facing faces meeting at a
/// point (a 64-sided cone's apex is one), so real models are smoothed exactly as described.
pub const MAX_FAN: usize = 64;

/// The faces around a position with more than [`MAX_FAN`] of them.
enum Fan {
    /// Each distinct normal once, with the sum of the angles of the faces that have it.
    Grouped(Vec<(Vec3, f32)>),
    /// More than [`MAX_FAN`] distinct normals: the sum of every face's angle × normal, which
    /// every corner there takes whole (a point where so many directions meet has no edge to
    /// keep sharp).
    Whole(Vec3),
}

impl Fan {
    fn of(around: &[(u32, f32)], face_normals: &[Vec3]) -> Fan {
        let mut faces: Vec<(Vec3, f32)> = around
            .iter()
            .map(|&(g, angle)| (face_normals[g as usize], angle))
            .collect();
        let key = |n: Vec3| n.to_array().map(f32::to_bits);
        faces.sort_unstable_by_key(|&(n, _)| key(n));
        let mut groups: Vec<(Vec3, f32)> = Vec::new();
        for (n, angle) in faces {
            match groups.last_mut() {
                Some((m, sum)) if key(*m) == key(n) => *sum += angle,
                _ => groups.push((n, angle)),
            }
        }
        if groups.len() <= MAX_FAN {
            Fan::Grouped(groups)
        } else {
            Fan::Whole(groups.iter().map(|&(n, angle)| angle * n).sum())
        }
    }
}

/// An OBJ file's mesh and the diffuse texture its material library names, with a warning for
/// each library or image that could not be used (see [`obj_scene_with_warnings`](super::spec::obj_scene_with_warnings)).
///
/// Each material library is read once, however many `mtllib` lines name it (a file naming one
/// library of thousands of materials thousands of times would otherwise ask for gigabytes),
/// and a texture's name is taken
/// relative to the library that names it. Libraries that cannot be read are warned of by name,
/// the first [`LISTED_LIBRARY_FAILURES`] of them, then counted: a file naming 100,000 missing
/// libraries makes four warnings, not 100,000. A texture too large for the memory there is
/// (its size read from its header) is a warning too, and the model is untextured.
pub fn load_textured(path: &Path) -> Result<(Mesh, Maps, Vec<String>), SceneError> {
    let folder = path.parent().unwrap_or(Path::new(""));
    let source = path.display().to_string();
    let (parsed, mut warnings) = parse_file(path)?;
    let texture = texture_name(&parsed, &source, &mut warnings)
        .and_then(|file| image_or_warning(TextureImage::load(&folder.join(file)), &mut warnings));
    let relief = normal_map_of(&parsed).and_then(|(file, strength)| {
        let image = TextureImage::load_as(&folder.join(&file), Decoding::Normal);
        normal_map_or_warning(image, strength, &mut warnings)
    });
    Ok((parsed.mesh, Maps { texture, relief }, warnings))
}

/// What a model's material library gives its surface beside the mesh: the diffuse texture
/// (`map_Kd`) and a relief from its normal map (`norm`, or `map_Bump`/`bump` as Blender
/// writes its normal maps).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Maps {
    pub texture: Option<Texture>,
    pub relief: Option<Arc<Relief>>,
}

/// The normal map named by the first material the model's faces use, with its strength:
/// `norm FILE` first, else `map_Bump`/`bump` (which tobj reads into `normal_texture`), each
/// with its options ([`map_options`]; `-bm` is the strength, 1 if absent).
fn normal_map_of(parsed: &Parsed) -> Option<(String, f32)> {
    let first = &parsed.materials[*parsed.used.first()?];
    let spec = first
        .unknown_param
        .get("norm")
        .or(first.normal_texture.as_ref())?;
    let (file, strength) = map_options(spec);
    (!file.is_empty()).then_some((file, strength.unwrap_or(1.0)))
}

/// A material library's map statement after its keyword, `[-option values…] FILE`: the file
/// (the words after the options, joined by single spaces) and the `-bm` value if there is
/// one. The MTL options are skipped with their values (`-o`, `-s`, `-t` take up to three
/// numbers; `-mm` two; `-blendu`, `-blendv`, `-clamp`, `-cc`, `-boost`, `-texres`,
/// `-imfchan`, `-bm` one); a word that is none of them starts the file name.
pub fn map_options(spec: &str) -> (String, Option<f32>) {
    let words: Vec<&str> = spec.split_whitespace().collect();
    let mut bm = None;
    let mut i = 0;
    while i < words.len() {
        let (at_most, exactly) = match words[i] {
            "-o" | "-s" | "-t" => (3, false),
            "-mm" => (2, true),
            "-bm" | "-blendu" | "-blendv" | "-clamp" | "-cc" | "-boost" | "-texres"
            | "-imfchan" => (1, true),
            _ => break,
        };
        if words[i] == "-bm" {
            bm = words.get(i + 1).and_then(|w| w.parse::<f32>().ok());
        }
        i += 1;
        let mut taken = 0;
        while taken < at_most
            && i < words.len()
            && (exactly || words[i].parse::<f32>().is_ok())
            && i + 1 < words.len()
        {
            i += 1;
            taken += 1;
        }
    }
    (words[i.min(words.len())..].join(" "), bm)
}

/// The relief of a normal map read from a model's material library, or a warning: the map
/// could not be read, or it is grey (every texel's three channels equal: a bump map of
/// heights, which `map_Bump` also names, not a normal map). A strength that is not a finite
/// number in [0, 10] is a warning too, and 1 is used.
fn normal_map_or_warning(
    image: Result<TextureImage, TextureError>,
    strength: f32,
    warnings: &mut Vec<String>,
) -> Option<Arc<Relief>> {
    let image = match image {
        Ok(image) => image,
        Err(e) => {
            warnings.push(format!("{e}; the model has no normal map"));
            return None;
        }
    };
    if let Some(reason) = NormalMap::refusal(&image) {
        warnings.push(format!("'{}' {reason}; it is not used", image.name));
        return None;
    }
    let strength = if (0.0..=10.0).contains(&strength) {
        strength
    } else {
        warnings.push(format!(
            "the normal map '{}' has strength -bm {strength}; 1 is used (0 to 10)",
            image.name
        ));
        1.0
    };
    Some(Arc::new(Relief {
        normal: Some(NormalMap {
            image: Arc::new(image),
            strength,
        }),
        height: None,
        uv_scale: 1.0,
    }))
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

/// How many unreadable material libraries a model's warnings name; the rest are counted.
pub const LISTED_LIBRARY_FAILURES: usize = 3;

/// The material libraries an OBJ file names, as its loader meets them.
#[derive(Default)]
struct Libraries {
    /// Each library's path, read or not, so that it is read once.
    seen: std::collections::HashSet<PathBuf>,
    /// The first [`LISTED_LIBRARY_FAILURES`] libraries that could not be read, and why.
    listed: Vec<String>,
    /// How many could not be read in all.
    failures: usize,
}

impl Libraries {
    fn failed(&mut self, file: &Path, reason: &str) {
        self.failures += 1;
        if self.listed.len() < LISTED_LIBRARY_FAILURES {
            self.listed.push(format!(
                "could not read material library '{}': {reason}; its materials are not used",
                file.display()
            ));
        }
    }

    fn warnings(self, source: &str) -> Vec<String> {
        let mut warnings = self.listed;
        let more = self.failures - warnings.len();
        if more > 0 {
            warnings.push(format!(
                "{source}: {more} more material librar{} could not be read either; their \
                 materials are not used",
                if more == 1 { "y" } else { "ies" }
            ));
        }
        warnings
    }
}

/// A material library's materials, read from `file` (named `library` in the OBJ file): a
/// regular file of at most [`MAX_MTL_BYTES`]. Texture names are made relative to the OBJ
/// file's folder, as the library's own folder gives them.
fn read_library(file: &Path, library: &Path) -> Result<Vec<tobj::Material>, String> {
    let bytes = inputs::read_capped(file, MAX_MTL_BYTES, "a material library")?;
    let (mut materials, _) = tobj::load_mtl_buf(&mut &bytes[..]).map_err(|e| e.to_string())?;
    let beside = library.parent().unwrap_or(Path::new(""));
    if !beside.as_os_str().is_empty() {
        for m in &mut materials {
            if let Some(texture) = &mut m.diffuse_texture {
                *texture = beside.join(&*texture).to_string_lossy().into_owned();
            }
            // Normal maps keep their options: only the file is made relative.
            let normal_maps = m.normal_texture.iter_mut();
            for spec in normal_maps.chain(m.unknown_param.get_mut("norm")) {
                let (file, bm) = map_options(spec);
                let file = beside.join(file).to_string_lossy().into_owned();
                *spec = match bm {
                    Some(bm) => format!("-bm {bm} {file}"),
                    None => file,
                };
            }
        }
    }
    Ok(materials)
}

/// The mesh and texture of [`builtin_textured`](super::spec::builtin_textured), before it is
/// placed.
pub fn builtin_textured_mesh(
    obj_text: &str,
    mtl_text: &str,
    texture_png: &[u8],
    name: &str,
) -> Result<(Mesh, Maps, Vec<String>), SceneError> {
    let path = builtin_path(name);
    let warnings = RefCell::new(Vec::new());
    let parsed = parse_with_materials(obj_text.as_bytes(), &path, |library| {
        tobj::load_mtl_buf(&mut mtl_text.as_bytes()).inspect_err(|e| {
            warnings.borrow_mut().push(format!(
                "could not read the material library '{}' of {}: {e}; the model is untextured",
                library.display(),
                path.display()
            ));
        })
    })?;
    let mut warnings = warnings.into_inner();
    warnings.extend(parsed.dropped.warning(&path.display().to_string()));
    let texture = match texture_name(&parsed, &path.display().to_string(), &mut warnings) {
        Some(file) => image_or_warning(
            TextureImage::from_encoded(texture_png, &format!("assets/models/{file}")),
            &mut warnings,
        ),
        None => {
            warnings.push(format!(
                "{} names no texture (map_Kd) in a material it uses; the model is untextured",
                path.display()
            ));
            None
        }
    };
    let maps = Maps {
        texture,
        relief: None,
    };
    Ok((parsed.mesh, maps, warnings))
}

/// The diffuse texture file named by the first material the model's faces use, if any;
/// `source` names the OBJ in warnings.
fn texture_name(parsed: &Parsed, source: &str, warnings: &mut Vec<String>) -> Option<String> {
    let first = &parsed.materials[*parsed.used.first()?];
    if parsed.used.len() > 1 {
        warnings.push(format!(
            "{source} uses {} materials; raylab gives a model one, so only the first ('{}') is \
             used",
            parsed.used.len(),
            first.name
        ));
    }
    let file = first.diffuse_texture.clone()?;
    if parsed.mesh.uvs.is_none() {
        warnings.push(format!(
            "{source} has no texture coordinates (vt), so its texture '{file}' is projected \
             instead of wrapped"
        ));
    }
    Some(file)
}

fn image_or_warning(
    image: Result<TextureImage, TextureError>,
    warnings: &mut Vec<String>,
) -> Option<Texture> {
    match image {
        Ok(image) => Some(Texture::Image(Arc::new(image))),
        Err(e) => {
            warnings.push(format!("{e}; the model is untextured"));
            None
        }
    }
}

fn builtin_path(name: &str) -> PathBuf {
    PathBuf::from(format!("assets/models/{name}.obj"))
}

/// A built-in model by file name.
pub fn builtin(text: &str, name: &str) -> Result<Mesh, SceneError> {
    parse_obj(text.as_bytes(), &builtin_path(name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::spec::{
        builtin_textured, model_in_box, obj_scene, obj_scene_with_warnings,
    };
    use crate::shapes::scene::{Scene, SceneChoice};

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

    #[test]
    fn element_indices_tobj_cannot_take_are_errors() {
        let p = Path::new("models/broken.obj");
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nvn 0 1 0\n";
        // Relative indices before the first texture coordinate or normal (tobj multiplies the
        // wrapped index, a panic with overflow checks), and a normal index so large that
        // 3 × index wraps past 2⁶⁴.
        for (face, message) in [
            (
                "f 1/-2 2/1 3/1",
                "line 7: texture coordinate index -2 is out of range (1 read",
            ),
            (
                "f 1//-3 2//1 3//1",
                "line 7: normal index -3 is out of range (2 read",
            ),
            (
                "f 1//6148914691236517206 2//1 3//1",
                "normal index 6148914691236517206",
            ),
            ("l 1/-9 2/1", "texture coordinate index -9"),
        ] {
            let e = parse_obj(format!("{tri}{face}\n").as_bytes(), p).unwrap_err();
            assert!(e.to_string().contains("broken.obj"), "{e}");
            assert!(e.to_string().contains(message), "{e}");
        }
        // The last one of each, relative, is fine: -1 is the newest.
        let mesh = parse_obj(format!("{tri}f 1/-1/-2 2/-1/-1 3/1/1\n").as_bytes(), p).unwrap();
        assert_eq!(mesh.indices.len(), 1);
        assert_eq!(mesh.normals.unwrap()[0], Vec3::Z);
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-6
    }

    /// The model's triangles of a scene from [`model_in_box`] (after the box's 30).
    const BOX: usize = 30;

    #[test]
    fn a_flat_mesh_shades_with_its_face_normal_everywhere() {
        // A 2 × 2 subdivided square in the tilted plane z = x/2 + y/4, without normals.
        let mut text = String::new();
        for y in 0..3 {
            for x in 0..3 {
                let z = 0.5 * x as f32 + 0.25 * y as f32;
                text += &format!("v {x} {y} {z}\n");
            }
        }
        for y in 0..2 {
            for x in 0..2 {
                let a = 1 + x + 3 * y;
                let (b, c, d) = (a + 1, a + 3, a + 4);
                text += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
            }
        }
        let mesh = parse_obj(text.as_bytes(), Path::new("square.obj")).unwrap();
        assert!(mesh.normals.is_none() && mesh.uvs.is_none());
        let scene = model_in_box(&mesh, &Placement::FRONT_LEFT, "square");
        assert_eq!(scene.triangles.len(), BOX + 8);
        assert!(scene.uvs.is_empty(), "no vt: no coordinates at all");
        // The box stays flat.
        for i in 0..BOX {
            assert_eq!(scene.vertex_normals[i], None);
            let flat = scene.triangles[i].normal;
            assert_eq!(scene.shading_normal(i, 0.3, 0.3, true), flat);
        }
        let face = scene.triangles[BOX].normal;
        for i in BOX..scene.triangles.len() {
            assert!(close(scene.triangles[i].normal, face));
            for n in scene.vertex_normals[i].unwrap() {
                assert!(close(n, face), "{n} against {face}");
            }
            for (u, v) in [
                (0.0, 0.0),
                (1.0, 0.0),
                (0.0, 1.0),
                (0.2, 0.7),
                (1.0 / 3.0, 0.25),
            ] {
                let n = scene.shading_normal(i, u, v, true);
                assert!(close(n, face), "{n} at ({u}, {v})");
            }
        }
    }

    /// The cube [−1, 1]³ as 8 shared vertices and 12 triangles, each ordered so that the lab's
    /// normal points outwards; its face normals.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<Vec3>) {
        let positions: Vec<Vec3> = (0..8)
            .map(|i| {
                let s = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
                Vec3::new(s(1), s(2), s(4))
            })
            .collect();
        // Each face as a quad of corners in order around it, split along one diagonal.
        let quads = [
            [0, 1, 3, 2],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 3, 7, 6],
            [0, 2, 6, 4],
            [1, 3, 7, 5],
        ];
        let mut triangles = Vec::new();
        for [a, b, c, d] in quads {
            for mut t in [[a, b, c], [a, c, d]] {
                let [p, q, r] = t.map(|i: u32| positions[i as usize]);
                if Triangle::new(p, q, r, 0).normal.dot(p + q + r) < 0.0 {
                    t.swap(1, 2);
                }
                triangles.push(t);
            }
        }
        let normals = triangles
            .iter()
            .map(|t| {
                let [p, q, r] = t.map(|i| positions[i as usize]);
                Triangle::new(p, q, r, 0).normal
            })
            .collect();
        (positions, triangles, normals)
    }

    #[test]
    fn a_cube_keeps_its_edges_below_the_crease_angle_and_rounds_them_above() {
        let (positions, triangles, faces) = cube();
        // 90° edges are sharper than 60°: only the two triangles of a face meet at a corner.
        let sharp = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
        for (corners, face) in sharp.iter().zip(&faces) {
            for n in corners {
                assert!(close(*n, *face), "{n} against {face}");
            }
        }
        // With 100°, the three faces at a cube corner are averaged. Each face meets the corner
        // with a total angle of 90°: one triangle's right angle, or two triangles' 45° each
        // where the face's diagonal ends there. So the weights are equal,
        // Σ = π/2·(±x̂) + π/2·(±ŷ) + π/2·(±ẑ), and normalised that is (±1, ±1, ±1)/√3, the
        // corner's own position over √3 (1/√3 = 0.5773503).
        let round = smooth_normals(&positions, &triangles, &faces, 100f32.to_radians());
        for (corners, t) in round.iter().zip(&triangles) {
            for (n, &i) in corners.iter().zip(t) {
                let expected = positions[i as usize] * 0.577_350_3;
                assert!(close(*n, expected), "{n} against {expected}");
            }
        }
    }

    #[test]
    fn faces_at_a_small_angle_are_averaged_by_their_angles_at_the_vertex() {
        // Two triangles share only the origin. A lies in z = 0 with a 45° angle there; B is
        // tilted by 20° about the y axis, normal (sin 20°, 0, cos 20°), with a 90° angle there
        // (its edges (0, 1, 0) and (−1, 0, tan 20°) are perpendicular).
        let t20 = 20f32.to_radians().tan();
        let positions = [
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.0, t20),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let triangles = [[0, 1, 2], [0, 3, 4]];
        let (sin20, cos20) = (0.342_020_1, 0.939_692_6);
        let faces = [Vec3::Z, Vec3::new(sin20, 0.0, cos20)];
        for (t, face) in triangles.iter().zip(&faces) {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            assert!(close(Triangle::new(a, b, c, 0).normal, *face));
        }
        let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
        // At the origin: π/4·(0, 0, 1) + π/2·(sin 20°, 0, cos 20°) ∝ (2 sin 20°, 0, 1 + 2 cos 20°)
        // = (0.6840403, 0, 2.8793852), of length 2.9595220: (0.2311320, 0, 0.9729224), 13.4°
        // from A's normal (an unweighted mean would be 10°).
        let expected = Vec3::new(0.231_132, 0.0, 0.972_922_4);
        assert!(close(normals[0][0], expected), "{}", normals[0][0]);
        assert!(close(normals[1][0], expected), "{}", normals[1][0]);
        // Elsewhere each face is alone.
        for (corners, face) in normals.iter().zip(&faces) {
            assert!(close(corners[1], *face) && close(corners[2], *face));
        }
        // Below 20° the faces no longer meet smoothly.
        let apart = smooth_normals(&positions, &triangles, &faces, 15f32.to_radians());
        assert!(close(apart[0][0], faces[0]) && close(apart[1][0], faces[1]));
    }

    #[test]
    fn degenerate_faces_contribute_nothing() {
        let positions = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(2.0, 0.0, 0.0), // on the x axis: 0, 1, 3 is a line
        ];
        let triangles = [[0, 1, 2], [0, 1, 3]];
        let faces = [Vec3::Z, Vec3::ZERO];
        let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
        assert_eq!(normals[0], [Vec3::Z; 3]);
        assert_eq!(normals[1], [Vec3::ZERO; 3]);
    }

    /// Faces by hand: 1 2 3 is kept; 2 3 1 is the same face read from another corner and
    /// 3 2 1 its other side (kept); 1 2 4 has its corners on the x axis and 1 1 2 two in one
    /// place (degenerate); 5 2 3 repeats 1 2 3 through vertex 5, written at 1's position as
    /// −0 (a duplicate); the last 1 2 3 is a duplicate too.
    #[test]
    fn degenerate_and_duplicate_faces_are_left_out_and_counted() {
        let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv -0 0 -0\n\
                     f 1 2 3\nf 2 3 1\nf 3 2 1\nf 1 2 4\nf 1 1 2\nf 5 2 3\nf 1 2 3\n";
        let mesh = parse_obj(text, Path::new("faces.obj")).unwrap();
        assert_eq!(mesh.indices, [[0, 1, 2], [2, 1, 0]]);
        let mut again = Mesh {
            indices: vec![
                [0, 1, 2],
                [1, 2, 0],
                [2, 1, 0],
                [0, 1, 3],
                [0, 0, 1],
                [4, 1, 2],
            ],
            ..mesh
        };
        let dropped = drop_unseen_faces(&mut again);
        assert_eq!(
            dropped,
            DroppedFaces {
                degenerate: 2,
                duplicate: 2
            }
        );
        assert_eq!(
            dropped.warning("faces.obj").unwrap(),
            "faces.obj: left out 4 faces that can never be seen: 2 degenerate (zero area), 2 \
             exact duplicates of earlier faces"
        );
        assert_eq!(DroppedFaces::default().warning("x"), None);
        // A file of nothing but degenerate faces is refused, saying why.
        let err = parse_obj(
            b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
            Path::new("line.obj"),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("line.obj") && err.contains("degenerate"),
            "{err}"
        );
    }

    /// Around a position with more than `MAX_FAN` faces: copies of two faces give each corner
    /// the normal the two faces alone give it (equal normals grouped, their angles summed), and
    /// a fan of many different faces is averaged whole. Each corner there costs the number of
    /// distinct normals, not of faces, which keeps the whole linear (a million faces around one
    /// position took minutes): the copies make two groups, the fan one sum. How fast it runs is
    /// the `degenerate` benchmark's to measure (benches/trace.rs), not a time limit here.
    #[test]
    fn many_faces_around_one_position_are_smoothed_in_linear_time() {
        // Two faces meeting at 30° along the y axis, as in the test above, then copied.
        let positions = [
            Vec3::ZERO,
            Vec3::Y,
            Vec3::X,
            Vec3::new(-(30f32.to_radians().cos()), 0.0, 30f32.to_radians().sin()),
        ];
        let faces = [[0, 1, 2], [0, 3, 1]];
        let face_normals: Vec<Vec3> = faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i: u32| positions[i as usize]);
                (c - a).cross(b - a).normalize()
            })
            .collect();
        let crease = 60f32.to_radians();
        let two = smooth_normals(&positions, &faces, &face_normals, crease);
        let copies = 100_000;
        let many_faces: Vec<[u32; 3]> = (0..copies).map(|i| faces[i % 2]).collect();
        let many_normals: Vec<Vec3> = (0..copies).map(|i| face_normals[i % 2]).collect();
        let many = smooth_normals(&positions, &many_faces, &many_normals, crease);
        let around: Vec<(u32, f32)> = (0..copies as u32).map(|f| (f, 1.0)).collect();
        match Fan::of(&around, &many_normals) {
            Fan::Grouped(groups) => assert_eq!(groups.len(), 2),
            Fan::Whole(_) => panic!("two distinct normals are grouped"),
        }
        for (i, corners) in many.iter().enumerate() {
            for (a, b) in corners.iter().zip(&two[i % 2]) {
                assert!((*a - *b).length() < 1e-5, "face {i}: {a} against {b}");
            }
        }
        // A fan of 100,000 faces around the origin, each turned a little further about the
        // z axis and tilted up: more distinct normals than MAX_FAN, so averaged whole. The fan
        // is symmetric about the z axis, so the apex's normal is the z axis.
        let n = 100_000;
        let mut fan_positions = vec![Vec3::ZERO];
        let mut fan_faces = Vec::new();
        for k in 0..n {
            let angle = |k: usize| std::f32::consts::TAU * k as f32 / n as f32;
            let ring = |a: f32| Vec3::new(a.cos(), a.sin(), -1.0);
            fan_positions.push(ring(angle(k)));
            fan_faces.push([0, 1 + k as u32, 1 + ((k + 1) % n) as u32]);
        }
        let fan_normals: Vec<Vec3> = fan_faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i: u32| fan_positions[i as usize]);
                (b - a).cross(c - a).normalize()
            })
            .collect();
        let fan = smooth_normals(&fan_positions, &fan_faces, &fan_normals, crease);
        let around: Vec<(u32, f32)> = (0..n as u32).map(|f| (f, 1.0)).collect();
        assert!(matches!(Fan::of(&around, &fan_normals), Fan::Whole(_)));
        assert!((fan[0][0] - Vec3::Z).length() < 1e-3, "{}", fan[0][0]);
    }

    #[test]
    fn vertices_repeated_at_a_seam_are_welded() {
        // The square of two triangles, its diagonal's vertices written twice (as at a texture
        // seam), folded by 30° along the diagonal: the diagonal's corners are averaged anyway.
        let s = 30f32.to_radians().sin();
        let positions = [
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, s),
        ];
        let triangles = [[0, 1, 2], [3, 5, 4]];
        let faces: Vec<Vec3> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                Triangle::new(a, b, c, 0).normal
            })
            .collect();
        assert!(faces[0].dot(faces[1]) > 0.8 && faces[0].dot(faces[1]) < 0.99);
        let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
        assert!(close(normals[0][0], normals[1][0]) && close(normals[0][1], normals[1][2]));
        assert!(!close(normals[0][0], faces[0]));
    }

    #[test]
    fn the_built_in_models_get_smooth_normals_near_their_faces() {
        for scene in [SceneChoice::Bunny, SceneChoice::Teapot].map(|c| c.load().unwrap()) {
            assert!(scene.uvs.is_empty());
            let mut smoothed = 0;
            for (i, t) in scene.triangles.iter().enumerate().skip(BOX) {
                for n in scene.vertex_normals[i].unwrap() {
                    assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
                    // A weighted mean of normals within 60° of the face stays within 60°.
                    assert!(n.dot(t.normal) >= 0.5 - 1e-5, "{n} on {}", t.normal);
                    smoothed += usize::from(n.dot(t.normal) < 0.9999);
                }
            }
            assert!(
                smoothed > scene.triangles.len(),
                "{smoothed} smoothed corners"
            );
        }
    }

    /// The scene triangle's corners as indices into a file triangle whose three vertices have
    /// distinct heights (file y, which the mirror turns into scene −y whatever the yaw).
    fn file_corners(t: &Triangle, file_ys: [f32; 3]) -> [usize; 3] {
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| file_ys[a].total_cmp(&file_ys[b]));
        let scene_y = [t.v0.y, t.v1.y, t.v2.y];
        let mut by_height = [0, 1, 2];
        by_height.sort_by(|&a, &b| scene_y[b].total_cmp(&scene_y[a]));
        let mut corners = [0; 3];
        for (k, f) in by_height.into_iter().zip(order) {
            corners[k] = f;
        }
        corners
    }

    #[test]
    fn normals_from_the_file_are_transformed_and_oriented_outwards() {
        // Counter-clockwise seen from +z, so facing +z, with a normal per vertex.
        let text = b"v 0 0 0\nv 1 0.5 0\nv 0 1 0\n\
                     vn 0 0.6 0.8\nvn 0.6 0 0.8\nvn 0 -0.6 -0.8\n\
                     f 1//1 2//2 3//3\n";
        let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
        // Turned a quarter: the file's +z becomes +x and its +x becomes −z; y is mirrored.
        let placement = Placement {
            yaw: std::f32::consts::FRAC_PI_2,
            ..Placement::FRONT_LEFT
        };
        let scene = model_in_box(&mesh, &placement, "t");
        let t = scene.triangles[BOX];
        assert!(close(t.normal, Vec3::X), "{}", t.normal);
        // (0, 0.6, 0.8) → mirrored (0, −0.6, 0.8) → turned (0.8, −0.6, 0);
        // (0.6, 0, 0.8) → (0.6, 0, 0.8) → (0.8, 0, −0.6);
        // (0, −0.6, −0.8) → (0, 0.6, −0.8) → (−0.8, 0.6, 0), behind the face: negated.
        let expected = [
            Vec3::new(0.8, -0.6, 0.0),
            Vec3::new(0.8, 0.0, -0.6),
            Vec3::new(0.8, -0.6, 0.0),
        ];
        let corners = file_corners(&t, [0.0, 0.5, 1.0]);
        let normals = scene.vertex_normals[BOX].unwrap();
        for k in 0..3 {
            let e = expected[corners[k]];
            assert!(
                close(normals[k], e),
                "corner {k}: {} against {e}",
                normals[k]
            );
        }
        // Wound the other way, the file's normals still turn the face (and its corners) to +x.
        let text = b"v 0 0 0\nv 1 0.5 0\nv 0 1 0\n\
                     vn 0 0.6 0.8\nvn 0.6 0 0.8\nvn 0 -0.6 -0.8\n\
                     f 1//1 3//3 2//2\n";
        let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
        let scene = model_in_box(&mesh, &placement, "t");
        let t = scene.triangles[BOX];
        assert!(close(t.normal, Vec3::X), "{}", t.normal);
        let corners = file_corners(&t, [0.0, 0.5, 1.0]);
        let normals = scene.vertex_normals[BOX].unwrap();
        for k in 0..3 {
            assert!(close(normals[k], expected[corners[k]]), "corner {k}");
        }
    }

    #[test]
    fn texture_coordinates_come_from_the_file() {
        for face in ["f 1/1 2/2 3/3\n", "f 1/1 3/3 2/2\n"] {
            let text =
                format!("v 0 0 0\nv 1 0.5 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.9 0.3\nvt 0.4 0.8\n{face}");
            let mesh = parse_obj(text.as_bytes(), Path::new("t.obj")).unwrap();
            let vt = [
                Vec2::new(0.1, 0.2),
                Vec2::new(0.9, 0.3),
                Vec2::new(0.4, 0.8),
            ];
            // tobj numbers vertices in the order the faces first use them.
            assert_eq!(mesh.uvs.as_ref().map(Vec::len), Some(3));
            let scene = model_in_box(&mesh, &Placement::TEAPOT, "t");
            assert_eq!(scene.uvs.len(), BOX + 1);
            assert_eq!(scene.uv(0, 0.2, 0.2), None, "the box has none");
            let corners = file_corners(&scene.triangles[BOX], [0.0, 0.5, 1.0]);
            // Barycentric (0, 0), (1, 0), (0, 1) are v0, v1, v2.
            for (k, (u, v)) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].into_iter().enumerate() {
                assert_eq!(scene.uv(BOX, u, v), Some(vt[corners[k]]), "{face}");
            }
            // The centroid: ((0.1 + 0.9 + 0.4)/3, (0.2 + 0.3 + 0.8)/3) = (0.4666667, 0.4333333).
            let mid = scene.uv(BOX, 1.0 / 3.0, 1.0 / 3.0).unwrap();
            assert!(
                (mid - Vec2::new(0.466_666_7, 0.433_333_3))
                    .abs()
                    .max_element()
                    < 1e-6
            );
        }
    }

    #[test]
    fn non_finite_normals_or_coordinates_are_errors() {
        let e = parse_obj(
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nf 1//1 2//1 3//1\n",
            Path::new("n.obj"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("n.obj") && e.to_string().contains("normal"));
        let e = parse_obj(
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt nan 0\nf 1/1 2/1 3/1\n",
            Path::new("t.obj"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("texture coordinate"), "{e}");
    }

    const TRIANGLE: &str = "v 0 0 0\nv 1 0.5 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                            usemtl glaze\nf 1/1 2/2 3/3\n";

    /// The model's material and the warnings, from an OBJ written to a temporary folder with
    /// the other `files`.
    fn load_from_folder(files: &[(&str, &[u8])]) -> (Scene, Vec<String>) {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in files {
            std::fs::write(dir.path().join(name), bytes).unwrap();
        }
        let path = dir.path().join("model.obj");
        let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
        // The wrapper gives the same scene.
        let plain = obj_scene(&path).unwrap();
        assert_eq!(plain.triangles, scene.triangles);
        (scene, warnings)
    }

    /// A PNG of one colour, 2×2.
    fn png_of(rgb: [u8; 3]) -> Vec<u8> {
        let image = image::RgbImage::from_pixel(2, 2, image::Rgb(rgb));
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
        bytes.into_inner()
    }

    /// The MTL's map statements: the options skipped with their values, `-bm` kept.
    #[test]
    fn map_options_give_the_file_and_the_bump_multiplier() {
        assert_eq!(
            map_options("-bm 0.5 file.png"),
            ("file.png".into(), Some(0.5))
        );
        assert_eq!(map_options("file.png"), ("file.png".into(), None));
        assert_eq!(
            map_options("-s 2 2 1 -o 0.5 -bm 0.25 -clamp on maps/n m.png"),
            ("maps/n m.png".into(), Some(0.25))
        );
        // `-s` with one number, then the file (a number is not taken past the last word).
        assert_eq!(map_options("-s 2 3.png"), ("3.png".into(), None));
        assert_eq!(map_options(""), (String::new(), None));
    }

    /// `map_Bump -bm 0.5 file.png` (as Blender writes a normal map) gives the model a normal map
    /// of strength 0.5, found beside the library; `norm file.png` is read as a normal map too,
    /// and wins over `map_Bump`. The memory estimate counts the normal map beside the texture.
    #[test]
    fn a_material_librarys_normal_map_is_read() {
        let obj = format!("mtllib model.mtl\n{TRIANGLE}");
        let tilted = png_of([192, 128, 255]);
        let flat = png_of([128, 128, 255]);
        let blender = b"newmtl glaze\nKd 0.9 0.9 0.9\nmap_Bump -bm 0.5 bumps.png\n";
        let (scene, warnings) = load_from_folder(&[
            ("model.obj", obj.as_bytes()),
            ("model.mtl", blender),
            ("bumps.png", &tilted),
        ]);
        assert!(warnings.is_empty(), "{warnings:?}");
        let relief = scene.material_of(BOX).relief.clone().unwrap();
        let map = relief.normal.as_ref().unwrap();
        assert_eq!(map.strength, 0.5);
        assert!(map.image.name.ends_with("bumps.png"), "{}", map.image.name);
        assert_eq!(map.image.texels[0], Vec3::new(64.0 / 127.0, 0.0, 1.0));
        assert!(relief.height.is_none());

        let both = b"newmtl glaze\nmap_Bump bumps.png\nnorm flat.png\n";
        let (scene, _) = load_from_folder(&[
            ("model.obj", obj.as_bytes()),
            ("model.mtl", both),
            ("bumps.png", &tilted),
            ("flat.png", &flat),
        ]);
        let relief = scene.material_of(BOX).relief.clone().unwrap();
        let map = relief.normal.as_ref().unwrap();
        assert_eq!((map.strength, map.image.texels[0]), (1.0, Vec3::Z));

        // A library in a folder: the map's name is relative to it.
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("lib")).unwrap();
        std::fs::write(dir.path().join("lib/model.mtl"), blender).unwrap();
        std::fs::write(dir.path().join("lib/bumps.png"), &tilted).unwrap();
        let path = dir.path().join("model.obj");
        std::fs::write(&path, format!("mtllib lib/model.mtl\n{TRIANGLE}")).unwrap();
        let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        let relief = scene.material_of(BOX).relief.clone().unwrap();
        assert_eq!(relief.normal.as_ref().unwrap().strength, 0.5);
        let (_, _, normal_maps) = scan_library(blender);
        assert_eq!(normal_maps, ["bumps.png"]);
        let obj_len = std::fs::metadata(&path).unwrap().len();
        let png_len = tilted.len() as u64;
        assert_eq!(
            memory_estimate(&path),
            OBJ_BYTES_FACTOR * obj_len
                + library_bytes(blender.len() as u64, 1)
                + TextureImage::decoding_bytes(2, 2)
                + png_len
        );
    }

    /// A grey `map_Bump` is a bump map of heights, not a normal map: a warning, no map. A
    /// missing or broken one is a warning too; the model loads either way.
    #[test]
    fn a_grey_or_missing_bump_map_is_a_warning() {
        let obj = format!("mtllib model.mtl\n{TRIANGLE}");
        let mtl = b"newmtl glaze\nmap_Bump bumps.png\n";
        let grey = png_of([90, 90, 90]);
        for (file, says) in [
            (Some(grey.as_slice()), "is grey: a bump map of heights"),
            (None, "bumps.png"),
            (Some(b"not a PNG".as_slice()), "not a PNG or JPEG"),
        ] {
            let mut files = vec![("model.obj", obj.as_bytes()), ("model.mtl", mtl.as_slice())];
            files.extend(file.map(|f| ("bumps.png", f)));
            let (scene, warnings) = load_from_folder(&files);
            assert!(scene.material_of(BOX).relief.is_none());
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(warnings[0].contains(says), "{warnings:?}");
        }
    }

    #[test]
    fn a_missing_or_broken_material_library_or_texture_is_a_warning() {
        let obj = format!("mtllib model.mtl\n{TRIANGLE}");
        let mtl = b"newmtl glaze\nKd 0.9 0.9 0.9\nmap_Kd porcelain.png\n";
        for (files, names) in [
            (vec![("model.obj", obj.as_bytes())], "model.mtl"),
            (
                vec![("model.obj", obj.as_bytes()), ("model.mtl", b"Kd 1 x 1\n")],
                "model.mtl",
            ),
            (
                vec![("model.obj", obj.as_bytes()), ("model.mtl", mtl)],
                "porcelain.png",
            ),
            (
                vec![
                    ("model.obj", obj.as_bytes()),
                    ("model.mtl", mtl),
                    ("porcelain.png", b"not a PNG"),
                ],
                "porcelain.png",
            ),
        ] {
            let (scene, warnings) = load_from_folder(&files);
            assert_eq!(scene.triangles.len(), BOX + 1);
            let model = scene.material_of(BOX);
            assert_eq!(model.name, "model");
            assert!(model.texture.is_none());
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(warnings[0].contains(names), "{warnings:?}");
            // The coordinates are there all the same.
            assert!(scene.uv(BOX, 0.0, 0.0).is_some());
        }
        // Without a library, or with one whose material has no texture: nothing to say.
        let plain = format!("mtllib model.mtl\n{TRIANGLE}");
        for files in [
            vec![("model.obj", TRIANGLE.as_bytes())],
            vec![
                ("model.obj", plain.as_bytes()),
                ("model.mtl", b"newmtl glaze\nKd 1 1 1\n"),
            ],
        ] {
            let (scene, warnings) = load_from_folder(&files);
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(scene.material_of(BOX).texture.is_none());
        }
    }

    /// One library of 2,000 materials named by 8,000 `mtllib` lines (read once a line, it
    /// would ask for gigabytes): read once, its 2,000 materials in once, and the estimate
    /// counts it once.
    #[test]
    fn a_library_named_many_times_is_read_once() {
        let dir = tempfile::tempdir().unwrap();
        let mtl: String = (0..2000)
            .map(|i| format!("newmtl m{i}\nKd 1 1 1\n"))
            .collect();
        std::fs::write(dir.path().join("lib.mtl"), &mtl).unwrap();
        let obj = format!("{}usemtl m7\n{TRIANGLE}", "mtllib lib.mtl\n".repeat(8000));
        let path = dir.path().join("model.obj");
        std::fs::write(&path, &obj).unwrap();
        let (parsed, warnings) = parse_file(&path).unwrap();
        assert_eq!(parsed.materials.len(), 2000);
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(
            memory_estimate(&path),
            OBJ_BYTES_FACTOR * obj.len() as u64 + library_bytes(mtl.len() as u64, 2000)
        );
        let (scene, _) = obj_scene_with_warnings(&path).unwrap();
        assert_eq!(scene.triangles.len(), BOX + 1);
    }

    /// 100,000 missing libraries: three warnings name the first three, a fourth counts the
    /// rest (not megabytes of warnings, one a library). A FIFO named as a library is
    /// refused at once, not waited on.
    #[test]
    fn many_missing_libraries_are_summarised() {
        let dir = tempfile::tempdir().unwrap();
        let obj: String = (0..100_000)
            .map(|i| format!("mtllib missing-{i}.mtl\n"))
            .chain([TRIANGLE.to_owned()])
            .collect();
        let (_, warnings) = load_from_folder(&[("model.obj", obj.as_bytes())]);
        assert_eq!(warnings.len(), LISTED_LIBRARY_FAILURES + 1, "{warnings:?}");
        assert!(warnings[0].contains("missing-0.mtl"), "{warnings:?}");
        assert!(warnings[2].contains("missing-2.mtl"), "{warnings:?}");
        assert!(
            warnings[3].ends_with(
                "model.obj: 99997 more material libraries could not be read either; their \
                 materials are not used"
            ),
            "{warnings:?}"
        );
        #[cfg(unix)]
        {
            crate::base::inputs::make_fifo(&dir.path().join("fifo.mtl"));
            let path = dir.path().join("fifo.obj");
            std::fs::write(&path, format!("mtllib fifo.mtl\n{TRIANGLE}")).unwrap();
            let (_, warnings) = obj_scene_with_warnings(&path).unwrap();
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(
                warnings[0].contains("not a regular file (a FIFO)"),
                "{warnings:?}"
            );
        }
    }

    /// A library in a sub-folder names its texture relative to itself, as MTL files do: the
    /// texture beside the library is found, not one beside the OBJ file.
    #[test]
    fn a_texture_is_found_beside_the_library_that_names_it() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("materials")).unwrap();
        let mtl = "newmtl glaze\nmap_Kd porcelain.png\n";
        std::fs::write(dir.path().join("materials/lib.mtl"), mtl).unwrap();
        let mut png = Vec::new();
        let image = crate::transport::film::Image::new(2, 2);
        png.extend(
            image
                .encode(crate::transport::film::OutputFormat::Png)
                .unwrap(),
        );
        std::fs::write(dir.path().join("materials/porcelain.png"), &png).unwrap();
        let path = dir.path().join("model.obj");
        std::fs::write(&path, format!("mtllib materials/lib.mtl\n{TRIANGLE}")).unwrap();
        let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!(scene.material_of(BOX).texture.is_some());
        // The estimate finds the same texture: its 2×2 texels and its file.
        let obj_len = std::fs::metadata(&path).unwrap().len();
        assert_eq!(
            memory_estimate(&path),
            OBJ_BYTES_FACTOR * obj_len
                + library_bytes(mtl.len() as u64, 1)
                + TextureImage::decoding_bytes(2, 2)
                + png.len() as u64
        );
    }

    #[test]
    fn a_texture_without_coordinates_and_several_materials_are_warned_about() {
        let obj = "mtllib model.mtl\nv 0 0 0\nv 1 0.5 0\nv 0 1 0\nv 0 0 1\n\
                   usemtl glaze\nf 1 2 3\nusemtl matt\nf 1 3 4\n";
        let mtl = b"newmtl glaze\nmap_Kd porcelain.png\nnewmtl matt\nKd 1 1 1\n";
        let (_, warnings) = load_from_folder(&[("model.obj", obj.as_bytes()), ("model.mtl", mtl)]);
        assert_eq!(warnings.len(), 3, "{warnings:?}");
        assert!(warnings[0].contains("2 materials") && warnings[0].contains("'glaze'"));
        assert!(warnings[1].contains("no texture coordinates"));
        assert!(warnings[2].contains("porcelain.png"));
    }

    #[test]
    fn a_built_in_textured_model_with_an_undecodable_image_is_untextured_with_a_warning() {
        let obj = format!("mtllib teapot-textured.mtl\n{TRIANGLE}");
        let mtl = "newmtl glaze\nmap_Kd teapot-porcelain.png\n";
        let (scene, warnings) =
            builtin_textured(&obj, mtl, b"\x89PNG broken", "teapot", &Placement::TEAPOT).unwrap();
        assert_eq!(scene.triangles.len(), BOX + 1);
        assert!(scene.material_of(BOX).texture.is_none());
        assert_eq!(scene.material_of(BOX).name, "teapot");
        assert!(scene.uv(BOX, 0.0, 0.0).is_some());
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("assets/models/teapot-porcelain.png"));
        // A library naming no texture is said too; bad OBJ text is an error naming the model.
        let (_, warnings) =
            builtin_textured(&obj, "newmtl glaze\n", &[], "teapot", &Placement::TEAPOT).unwrap();
        assert!(warnings[0].contains("no texture"), "{warnings:?}");
        let e = builtin_textured("v 0 0 0\n", mtl, &[], "teapot", &Placement::TEAPOT).unwrap_err();
        assert!(e.to_string().contains("assets/models/teapot.obj"), "{e}");
    }
}
