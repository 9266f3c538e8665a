//! A model's material libraries (MTL) and the maps they name: the diffuse texture and the
//! normal map, read with warnings instead of errors; and the memory and files a model takes.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::*;
use crate::base::inputs::{self, Input, MAX_MTL_BYTES, MAX_OBJ_BYTES};
use crate::shading::relief::{NormalMap, Relief};
use crate::shading::texture::{Decoding, Texture, TextureError, TextureImage};
use crate::shapes::scene::SceneError;

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
pub(super) fn scan_library(bytes: &[u8]) -> (u64, Vec<String>, Vec<String>) {
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

/// How many unreadable material libraries a model's warnings name; the rest are counted.
pub const LISTED_LIBRARY_FAILURES: usize = 3;

/// The material libraries an OBJ file names, as its loader meets them.
#[derive(Default)]
pub(super) struct Libraries {
    /// Each library's path, read or not, so that it is read once.
    pub(super) seen: std::collections::HashSet<PathBuf>,
    /// The first [`LISTED_LIBRARY_FAILURES`] libraries that could not be read, and why.
    pub(super) listed: Vec<String>,
    /// How many could not be read in all.
    pub(super) failures: usize,
}

impl Libraries {
    pub(super) fn failed(&mut self, file: &Path, reason: &str) {
        self.failures += 1;
        if self.listed.len() < LISTED_LIBRARY_FAILURES {
            self.listed.push(format!(
                "could not read material library '{}': {reason}; its materials are not used",
                file.display()
            ));
        }
    }

    pub(super) fn warnings(self, source: &str) -> Vec<String> {
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
pub(super) fn read_library(file: &Path, library: &Path) -> Result<Vec<tobj::Material>, String> {
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
