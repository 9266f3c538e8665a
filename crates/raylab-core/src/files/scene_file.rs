//! Scene files: a whole setup — the scene's parts, the camera, the light and every render
//! setting — as a TOML text a teacher can write by hand, send, and a student can open to the
//! same image (`raylab render --scene-file FILE`, or Open in the workbench).
//!
//! Why TOML: it is read and written by people (comments, one `key = value` a line, sections
//! that match the panels), it is what Cargo uses so a Rust student has seen it, and its parser
//! reports the line of every mistake. (RON would mirror Rust's types more closely, but its
//! nesting of parentheses is harder to edit by hand, and JSON, which raylab's screenshot
//! sidecars use, has no comments.)
//!
//! The format is versioned and strict, unlike the lenient settings JSON: `version = 2` first,
//! every field present (but a scene's `models` list and its optional `terrain`), no unknown
//! field, every value checked ([`RenderSettings::validate`], [`SceneSpec::validate`]); an error
//! names the field and its line. The file's structs below are version 2 itself, kept apart
//! from raylab's in-memory types so those can change without changing what old files mean.
//!
//! Angles (the camera's yaw and pitch, a model's yaw) are in degrees, as the workbench and the
//! command line take them. Version 1, the same but for its angles in radians, is still read
//! with its meaning; raylab writes version 2. Each angle is written as the shortest decimal
//! that reads back to the same `f32` ([`camera::degrees`]), so a file round-trips exactly.
//! The settings JSON (screenshots, `--settings`) keeps radians: written by raylab, not typed,
//! and without a version, it could not tell an old screenshot's radians from degrees.
//!
//! An example, the lab's figure 7 (`assets/scenes/figure7.toml`):
//!
//! ```toml
//! version = 2
//!
//! [scene]
//! name = "figure 7"
//! room = true
//! blocks = true
//! material_preset = "none"
//! texture_preset = "none"
//!
//! [camera]
//! position = [0.0, 0.0, -3.001]
//! yaw = 0.0
//! pitch = 0.0
//! focal_length = 512.0
//! width = 512
//! height = 512
//! aperture = 0.0
//! focus_distance = 3.001
//!
//! [light]
//! position = [0.0, -0.5, -0.7]
//! power = 14.0
//! colour = [1.0, 1.0, 1.0]
//! shape = "point"
//!
//! [shading]
//! stage = "lab"
//! shadows = true
//! indirect = true
//! indirect_light = [0.5, 0.5, 0.5]
//! bounces = "unlimited"
//! specular_depth = 6
//! smooth = true
//! parallax_shadows = true
//! caustics = "off"
//! photons = 100000
//!
//! [display]
//! transform = "lab"
//! exposure = 0.0
//!
//! [render]
//! samples_per_pixel = 1
//! seed = 0
//! ```

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::base::camera::{self, Camera};
use crate::shading::light::{
    LightKind, LightShape, LightSpec, ParamType, ParamValue, RawParam, ReadError,
};
use crate::shading::material::{MaterialKind, MaterialPreset, TexturePreset};
use crate::shapes::scene::SceneChoice;
use crate::shapes::scene::spec::{
    self, BoxPart, ModelSpec, PartMaterial, PartRelief, ReliefSpec, SceneSpec,
};
use crate::shapes::scene::terrain::TerrainSpec;
use crate::shapes::scene::water::WaterSpec;
use crate::transport::display::{Display, DisplayTransform};
use crate::transport::integrator::{Shading, Stage};
use crate::transport::settings::{Caustics, DEFAULT_PHOTONS, EquationTexts, RenderSettings};
use crate::transport::view::View;

/// The version this raylab writes (and reads, with version 1).
pub const VERSION: u32 = 2;

/// Version 1: angles in radians.
const VERSION_RADIANS: u32 = 1;

/// The extension of scene files.
pub const EXTENSION: &str = "toml";

/// Why a scene file could not be read or written. Every message names the file; a parse or
/// value error also names the field and its line.
#[derive(Debug, thiserror::Error)]
pub enum SceneFileError {
    #[error("could not read scene file '{}': {reason}", path.display())]
    Read { path: PathBuf, reason: String },
    #[error("could not write scene file '{}': {reason}", path.display())]
    Write { path: PathBuf, reason: String },
    #[error("scene file '{}', {message}", path.display())]
    Invalid { path: PathBuf, message: String },
}

/// Reads a scene file: the settings it describes, with model paths resolved against the
/// file's folder. Only a regular file of at most [`crate::base::inputs::MAX_SCENE_FILE_BYTES`] is
/// read.
pub fn load(path: &Path) -> Result<RenderSettings, SceneFileError> {
    let bytes = crate::base::inputs::read_capped(
        path,
        crate::base::inputs::MAX_SCENE_FILE_BYTES,
        "a scene file",
    )
    .map_err(|reason| SceneFileError::Read {
        path: path.to_path_buf(),
        reason,
    })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| SceneFileError::Invalid {
        path: path.to_path_buf(),
        message: format!("byte {}: not UTF-8 text", e.valid_up_to()),
    })?;
    let folder = path.parent().unwrap_or(Path::new(""));
    parse(text, folder).map_err(|message| SceneFileError::Invalid {
        path: path.to_path_buf(),
        message,
    })
}

/// Parses scene-file text; relative model paths are taken from `folder`. The error is
/// `line L (the line's text): what is wrong`, or without a line where none applies.
pub fn parse(text: &str, folder: &Path) -> Result<RenderSettings, String> {
    // A byte-order mark, as some Windows editors write, is not part of the text.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    #[derive(Deserialize)]
    struct Versioned {
        version: Option<toml::Value>,
    }
    let versioned: Versioned = toml::from_str(text).map_err(|e| toml_error(text, &e))?;
    match versioned.version {
        None => {
            return Err(format!(
                "line 1: missing field `version` (this raylab reads versions \
                 {VERSION_RADIANS} and {VERSION}: write `version = {VERSION}` first, angles in \
                 degrees)"
            ));
        }
        Some(toml::Value::Integer(v))
            if v == i64::from(VERSION) || v == i64::from(VERSION_RADIANS) => {}
        Some(other) => {
            return Err(at_key(
                text,
                &["version"],
                &format!(
                    "version {other} is not one this raylab reads (it reads versions \
                     {VERSION_RADIANS}, angles in radians, and {VERSION}, angles in degrees)"
                ),
            ));
        }
    }
    let file: FileV2 = toml::from_str(text).map_err(|e| toml_error(text, &e))?;
    let kind = file.light.kind(Angles::of_version(file.version), text)?;
    // Where an error about the light's parameters points: a sphere's `radius`, a square's
    // `side` (or in older files its `radius`), the spot's `aim`, …
    let light_keys: Vec<(&str, Vec<String>)> = kind
        .params()
        .iter()
        .filter_map(|p| Some((p.noun, file.light.key_of(&kind, p.noun)?)))
        .collect();
    let settings = file.into_settings(folder, kind);
    PartMaterial::validate(&settings.part_materials, |i, f| match f {
        "part" => format!("scene.materials[{i}].part"),
        f => format!("scene.materials[{i}].material.{f}"),
    })
    .map_err(|e| at_key(text, &key_path(&e.name), &e.to_string()))?;
    // The scene's parts are checked too (`SceneSpec::validate`).
    settings.validate().map_err(|e| {
        let path = match light_keys.iter().find(|(noun, _)| *noun == e.name) {
            Some((_, path)) => path.clone(),
            None => key_path(&e.name),
        };
        at_key(text, &path, &e.to_string())
    })?;
    // The equations compile, or the error names the quantity, its line and column.
    crate::teaching::sandbox::carried::compile_texts(&settings.equations)
        .map_err(|e| at_key(text, &["equations", e.quantity.name()], &e.to_string()))?;
    Ok(settings)
}

/// The text of a scene file for `settings`, to be written into `folder` (model paths inside it
/// are written relative to it). Fails only for a seed above 2⁶³ − 1, which TOML's integers
/// cannot hold.
pub fn to_text(settings: &RenderSettings, folder: &Path) -> Result<String, String> {
    let file = FileV2::from_settings(settings, folder)?;
    let body = toml::to_string(&file).map_err(|e| e.to_string())?;
    Ok(format!(
        "# A raylab scene file: open it in the workbench, or `raylab render --scene-file FILE`.\n\
         # Angles are in degrees, lengths in scene units (the box spans \
         −1 to 1), sizes and focal length in pixels.\n{body}"
    ))
}

/// Writes `settings` as a scene file at `path` (through a temporary file, so a failed write
/// leaves any earlier file whole).
pub fn save(settings: &RenderSettings, path: &Path) -> Result<(), SceneFileError> {
    let folder = path.parent().unwrap_or(Path::new(""));
    let text = to_text(settings, folder).map_err(|reason| SceneFileError::Write {
        path: path.to_path_buf(),
        reason,
    })?;
    crate::transport::film::write_atomically(path, text.as_bytes()).map_err(|e| {
        SceneFileError::Write {
            path: path.to_path_buf(),
            reason: match e {
                crate::transport::film::SaveError::Write { reason, .. } => reason.to_string(),
                other => other.to_string(),
            },
        }
    })
}

/// A toml error as `line L (text): message`.
fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim().to_owned();
    match e.span() {
        Some(span) => format!("{}: {message}", line_of(text, span.start)),
        None => message,
    }
}

/// `line L (the line's text, shortened)` for a byte offset.
fn line_of(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    let line = text[..offset].matches('\n').count() + 1;
    let content = text.lines().nth(line - 1).unwrap_or("").trim();
    let content: String = content.chars().take(60).collect();
    if content.is_empty() {
        format!("line {line}")
    } else {
        format!("line {line} ({content})")
    }
}

/// The TOML key path of a value [`RenderSettings::validate`] or [`SceneSpec::validate`] names.
fn key_path(name: &str) -> Vec<String> {
    let path: &[&str] = match name {
        "width" => &["camera", "width"],
        "height" => &["camera", "height"],
        "camera position" => &["camera", "position"],
        "yaw" => &["camera", "yaw"],
        "pitch" => &["camera", "pitch"],
        "focal length" => &["camera", "focal_length"],
        "aperture" => &["camera", "aperture"],
        "focus distance" => &["camera", "focus_distance"],
        "light position" => &["light", "position"],
        "light power" => &["light", "power"],
        "light colour" => &["light", "colour"],
        "roughness" => &["scene", "roughness"],
        "exposure" => &["display", "exposure"],
        "indirect light" => &["shading", "indirect_light"],
        "specular depth" => &["shading", "specular_depth"],
        "photons per pass" => &["shading", "photons"],
        "samples per pixel" => &["render", "samples_per_pixel"],
        // `scene.models[0].height` and the like.
        other => {
            return other
                .split('.')
                .flat_map(|part| match part.split_once('[') {
                    Some((key, index)) => {
                        vec![key.to_owned(), index.trim_end_matches(']').to_owned()]
                    }
                    None => vec![part.to_owned()],
                })
                .collect();
        }
    };
    path.iter().map(|s| (*s).to_owned()).collect()
}

/// `message`, after the line where `path` is set in `text` when it can be found.
fn at_key(text: &str, path: &[impl AsRef<str>], message: &str) -> String {
    let Ok(root) = toml::de::DeTable::parse(text) else {
        return message.to_owned();
    };
    let mut span = None;
    let mut table = Some(root.get_ref());
    let mut value: Option<&toml::Spanned<toml::de::DeValue<'_>>> = None;
    for part in path {
        let part = part.as_ref();
        let next = match (table, value.map(|v| v.get_ref())) {
            (Some(t), _) => t.get(part),
            (None, Some(toml::de::DeValue::Array(items))) => {
                part.parse::<usize>().ok().and_then(|i| items.get(i))
            }
            _ => None,
        };
        let Some(next) = next else {
            break;
        };
        span = Some(next.span());
        value = Some(next);
        table = match next.get_ref() {
            toml::de::DeValue::Table(t) => Some(t),
            _ => None,
        };
    }
    match span {
        Some(span) => format!("{}: {message}", line_of(text, span.start)),
        None => message.to_owned(),
    }
}

// Version 2 of the format. Every field is required (but `models` and `terrain`), none unknown.
// Version 1 has the same fields, its angles in radians: each angle is read as an `f64` (what
// TOML holds) and turned into the in-memory radians by `Angles`.

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileV2 {
    version: u32,
    scene: SceneV2,
    camera: CameraV2,
    light: LightV2,
    shading: ShadingV2,
    display: DisplayV2,
    render: RenderV2,
    /// A student's own equations (`d`, `shadowStart`, `shadowed`, `D`, `R`), a text each:
    /// written only when there are some.
    #[serde(default, skip_serializing_if = "EquationTexts::is_empty")]
    equations: EquationTexts,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneV2 {
    /// Shown in the workbench's scene list.
    name: String,
    /// The lab's room: floor, walls, ceiling.
    room: bool,
    /// The lab's two blocks.
    blocks: bool,
    /// Mirror, glass, rough metal or plastic for the blocks: none, mirror, glass, both, rough, plastic.
    material_preset: MaterialPreset,
    /// The rough metal's or the plastic coating's GGX roughness α (0.2 if the file does not say).
    #[serde(default = "default_roughness")]
    roughness: f32,
    /// Textures for the floor and walls: none, checker-floor, grid-walls, both.
    texture_preset: TexturePreset,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    models: Vec<ModelV2>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    terrain: Option<TerrainV2>,
    /// Normal and height maps for parts of the box, `[[scene.surfaces]]` with `part =
    /// "back-wall"` (floor, left-wall, right-wall, back-wall, ceiling, short-block,
    /// tall-block) and the maps' fields as a model has them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    surfaces: Vec<SurfaceV2>,
    /// Water over the floor, `[scene.water]`: depth, ior, waves (amplitude), time (seconds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    water: Option<WaterV2>,
    /// Parts of the box with materials of their own over the preset's, `[[scene.materials]]`
    /// with `part = "tall-block"` and `material = { kind = "plastic", … }` as a model's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    materials: Vec<PartMaterialV2>,
}

/// A part of the box and its material.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PartMaterialV2 {
    part: BoxPart,
    material: MaterialKind,
}

fn default_roughness() -> f32 {
    crate::shading::material::DEFAULT_ROUGHNESS
}

fn default_strength() -> f32 {
    1.0
}

fn is_default_strength(v: &f32) -> bool {
    *v == default_strength()
}

fn default_height_scale() -> f32 {
    spec::DEFAULT_HEIGHT_SCALE
}

fn is_default_height_scale(v: &f32) -> bool {
    *v == default_height_scale()
}

/// A part of the box and its maps.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceV2 {
    part: BoxPart,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normal_map: Option<PathBuf>,
    #[serde(
        default = "default_strength",
        skip_serializing_if = "is_default_strength"
    )]
    normal_strength: f32,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    height_map: Option<PathBuf>,
    #[serde(
        default = "default_height_scale",
        skip_serializing_if = "is_default_height_scale"
    )]
    height_scale: f32,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelV2 {
    /// `bunny`, `teapot`, `textured-teapot`, or an OBJ file's path (relative to the scene file).
    file: PathBuf,
    height: f32,
    floor_position: Floats<2>,
    /// Degrees (radians in version 1).
    yaw: f64,
    reflectance: Floats<3>,
    /// `{ kind = "diffuse" }`, `{ kind = "mirror", tint = [r, g, b] }`, …: the kind and
    /// exactly its fields, as [`MaterialKind`]'s table lists them.
    material: MaterialKind,
    /// A tangent-space normal map (PNG or JPEG, +Y up), relative to the scene file; replaces
    /// one the model's material library names. Optional, as are the three below.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normal_map: Option<PathBuf>,
    /// How strongly the normal map tilts the normal (1 unless given).
    #[serde(
        default = "default_strength",
        skip_serializing_if = "is_default_strength"
    )]
    normal_strength: f32,
    /// A height map for parallax occlusion mapping (white is high).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    height_map: Option<PathBuf>,
    /// How deep a height difference of 1 is, in scene units (0.02 unless given).
    #[serde(
        default = "default_height_scale",
        skip_serializing_if = "is_default_height_scale"
    )]
    height_scale: f32,
}

impl SurfaceV2 {
    fn relief(&self) -> ReliefSpec {
        ReliefSpec {
            normal_map: self.normal_map.clone(),
            normal_strength: self.normal_strength,
            height_map: self.height_map.clone(),
            height_scale: self.height_scale,
        }
    }
}

/// Exactly `N` numbers, `[x, y, z]`: an array of any other length is refused (not cut to
/// `N`), naming the length it has; reading stops at the first element too many, however long
/// the array.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Floats<const N: usize>([f32; N]);

impl From<Vec3> for Floats<3> {
    fn from(v: Vec3) -> Self {
        Floats(v.to_array())
    }
}

impl From<Floats<3>> for Vec3 {
    fn from(v: Floats<3>) -> Self {
        Vec3::from_array(v.0)
    }
}

impl<const N: usize> Serialize for Floats<N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq as _;
        let mut seq = s.serialize_seq(Some(N))?;
        for x in &self.0 {
            seq.serialize_element(x)?;
        }
        seq.end()
    }
}

impl<'de, const N: usize> Deserialize<'de> for Floats<N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor<const N: usize>;
        impl<'de, const N: usize> serde::de::Visitor<'de> for Visitor<N> {
            type Value = Floats<N>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "an array of exactly {N} numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Floats<N>, A::Error> {
                let mut out = [0.0; N];
                for (i, x) in out.iter_mut().enumerate() {
                    *x = seq
                        .next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(serde::de::Error::custom(format_args!(
                        "invalid length: more than {N} elements, expected an array of exactly \
                         {N} numbers"
                    )));
                }
                Ok(Floats(out))
            }
        }
        d.deserialize_seq(Visitor::<N>)
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TerrainV2 {
    seed: u64,
    grid: u32,
    height: f32,
    octaves: u32,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WaterV2 {
    depth: f32,
    ior: f32,
    waves: f32,
    time: f32,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraV2 {
    position: Floats<3>,
    /// Degrees (radians in version 1); positive turns right.
    yaw: f64,
    /// Degrees (radians in version 1); positive looks up.
    pitch: f64,
    focal_length: f32,
    width: u32,
    height: u32,
    aperture: f32,
    focus_distance: f32,
}

/// The `[light]` table: `position`, `power`, `colour`, the kind's name as `shape` and the
/// kind's parameters, named as `light_kinds!` names them (angles in degrees; radians in
/// version 1). A file without `shape` means a sphere by any `radius` above 0, else the point
/// light; a square's side may be its `radius` (files written before `side`).
struct LightV2 {
    position: Floats<3>,
    power: f32,
    colour: Floats<3>,
    shape: Option<LightShape>,
    /// The parameters as read, by name.
    params: Vec<(String, RawParam)>,
    /// The kind written (its parameters in the table's order).
    written: Option<LightKind>,
}

impl Serialize for LightV2 {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap as _;
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("position", &self.position)?;
        map.serialize_entry("power", &self.power)?;
        map.serialize_entry("colour", &self.colour)?;
        if let Some(shape) = self.shape {
            map.serialize_entry("shape", &shape)?;
        }
        for (p, value) in self.written.iter().flat_map(LightKind::params_and_values) {
            match (p.ty, value) {
                (ParamType::Angle, ParamValue::Number(x)) => {
                    map.serialize_entry(p.name, &p.shown(x))?
                }
                (ParamType::Size | ParamType::Point, ParamValue::Number(x)) => {
                    map.serialize_entry(p.name, &x)?
                }
                (_, ParamValue::Point(v)) => map.serialize_entry(p.name, &Floats::from(v))?,
            }
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for LightV2 {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = LightV2;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(
                    f,
                    "the light: its position, power, colour, shape and parameters"
                )
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<LightV2, A::Error> {
                use serde::de::Error as _;
                let (mut position, mut power, mut colour, mut shape) = (None, None, None, None);
                let mut params: Vec<(String, RawParam)> = Vec::new();
                while let Some(key) = map.next_key_seed(LightKey)? {
                    let duplicate = || A::Error::custom(format_args!("duplicate key `{key}`"));
                    match key.as_str() {
                        "position" if position.is_none() => position = Some(map.next_value()?),
                        "power" if power.is_none() => power = Some(map.next_value()?),
                        "colour" if colour.is_none() => colour = Some(map.next_value()?),
                        "shape" if shape.is_none() => shape = Some(map.next_value()?),
                        "position" | "power" | "colour" | "shape" => return Err(duplicate()),
                        _ if params.iter().any(|(k, _)| *k == key) => return Err(duplicate()),
                        _ => {
                            let value = map.next_value()?;
                            params.push((key, value));
                        }
                    }
                }
                Ok(LightV2 {
                    position: position.ok_or_else(|| A::Error::missing_field("position"))?,
                    power: power.ok_or_else(|| A::Error::missing_field("power"))?,
                    colour: colour.ok_or_else(|| A::Error::missing_field("colour"))?,
                    shape,
                    params,
                    written: None,
                })
            }
        }
        d.deserialize_map(Visitor)
    }
}

/// A key of the `[light]` table: one of [`light_keys`], or an error at its line naming the
/// unknown field.
struct LightKey;

impl<'de> serde::de::DeserializeSeed<'de> for LightKey {
    type Value = String;

    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<String, D::Error> {
        let key = String::deserialize(d)?;
        match light_keys().contains(&key.as_str()) {
            true => Ok(key),
            false => Err(serde::de::Error::unknown_field(&key, light_keys())),
        }
    }
}

/// The keys a `[light]` table may hold: its position, power, colour and shape, and every
/// light kind's parameters (`light_kinds!`).
fn light_keys() -> &'static [&'static str] {
    static KEYS: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();
    KEYS.get_or_init(|| {
        let mut keys = vec!["position", "power", "colour", "shape"];
        for shape in LightShape::ALL {
            for p in LightKind::of_shape(shape).params() {
                if !keys.contains(&p.name) {
                    keys.push(p.name);
                }
            }
        }
        keys
    })
}

impl LightV2 {
    /// The file's light as written: its kind's own fields and none of another's (a field of
    /// another kind is refused at its line, a missing one at the `[light]` table's).
    fn of(l: &LightSpec) -> Self {
        LightV2 {
            position: l.position.into(),
            power: l.power,
            colour: l.colour.into(),
            shape: Some(l.kind.shape()),
            params: Vec::new(),
            written: Some(l.kind),
        }
    }

    fn given(&self, field: &str) -> Option<&RawParam> {
        self.params.iter().find(|(k, _)| k == field).map(|(_, v)| v)
    }

    /// Whether a square's side is given as its `radius` (files written before `side`).
    fn side_as_radius(&self) -> bool {
        self.shape == Some(LightShape::Quad) && self.given("side").is_none()
    }

    /// The light's kind, its fields checked against its shape; errors name the line and field.
    fn kind(&self, angle: Angles, text: &str) -> Result<LightKind, String> {
        let shape = self.shape;
        let name = shape.map_or("point".to_owned(), |s| s.name().to_owned());
        let refused = |field: &str, own: &str| {
            at_key(
                text,
                &["light", field],
                &format!("light.{field}: a {name} light has no `{field}` (its fields: {own})"),
            )
        };
        let missing = |field: &str| {
            at_key(
                text,
                &["light"],
                &format!("missing field `{field}` in [light]: a {name} light needs it"),
            )
        };
        let radius = || match self.given("radius") {
            Some(RawParam::Number(r)) => Ok(Some(*r as f32)),
            Some(RawParam::Array(_)) => Err(at_key(
                text,
                &["light", "radius"],
                "light.radius: must be a number",
            )),
            None => Ok(None),
        };
        // The forms written before every kind had its own fields: no shape (a sphere by any
        // radius above 0, else the point), a point's `radius` of 0.
        if matches!(shape, None | Some(LightShape::Point)) {
            if let Some((field, _)) = self.params.iter().find(|(k, _)| k != "radius") {
                return Err(refused(field, "radius"));
            }
            return match (shape, radius()?) {
                (None, None) => Err(missing("radius")),
                (None, Some(r)) if r > 0.0 => Ok(LightKind::Sphere { radius: r }),
                (_, None | Some(0.0)) | (None, Some(_)) => Ok(LightKind::Point),
                (_, Some(r)) => Err(at_key(
                    text,
                    &["light", "radius"],
                    &format!(
                        "invalid light size {r}: a point light has no size: for an area light \
                         of this size choose the shape sphere or quad (--light-shape), or give \
                         the size 0"
                    ),
                )),
            };
        }
        let shape = shape.unwrap_or_default();
        let mut params = self.params.clone();
        if shape == LightShape::Quad {
            match (self.given("side"), self.given("radius")) {
                (Some(_), Some(_)) => {
                    let why = "light.radius: a quad light's size is its `side`, given already";
                    return Err(at_key(text, &["light", "radius"], why));
                }
                // Before a square had its side, `radius` held it.
                (None, Some(_)) => {
                    for (key, _) in &mut params {
                        if key == "radius" {
                            *key = "side".to_owned();
                        }
                    }
                }
                (Some(_), None) | (None, None) => {}
            }
        }
        let degrees = matches!(angle, Angles::Degrees);
        LightKind::read(shape, &params, degrees).map_err(|e| match e {
            ReadError::Unknown(field) => {
                let own: Vec<&str> = LightKind::of_shape(shape)
                    .params()
                    .iter()
                    .map(|p| p.name)
                    .collect();
                refused(&field, &own.join(", "))
            }
            ReadError::Missing(field) => missing(field),
            ReadError::WrongType(field, what) => at_key(
                text,
                &["light", &field],
                &format!("light.{field}: must be {what}"),
            ),
        })
    }

    /// The key in the file of the light's parameter that errors call `noun` (`light aim`),
    /// if it is one.
    fn key_of(&self, kind: &LightKind, noun: &str) -> Option<Vec<String>> {
        let p = kind.params().iter().find(|p| p.noun == noun)?;
        let key = match (p.name, self.side_as_radius()) {
            ("side", true) => "radius",
            (name, _) => name,
        };
        Some(vec!["light".to_owned(), key.to_owned()])
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ShadingV2 {
    stage: Stage,
    shadows: bool,
    indirect: bool,
    indirect_light: Floats<3>,
    bounces: Bounces,
    specular_depth: u32,
    smooth: bool,
    /// Parallax self-shadowing; a file without it has it on.
    #[serde(default = "default_true")]
    parallax_shadows: bool,
    /// `off` or `photons`; a file without it has caustics off.
    #[serde(default)]
    caustics: Caustics,
    /// Photons per pass; a file without it has the default.
    #[serde(default = "default_photons")]
    photons: u32,
}

fn default_photons() -> u32 {
    DEFAULT_PHOTONS
}

fn default_true() -> bool {
    true
}

/// The path tracer's bounce limit: a number, or `"unlimited"` (TOML has no null).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounces(Option<u32>);

impl Serialize for Bounces {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            Some(n) => s.serialize_u32(n),
            None => s.serialize_str("unlimited"),
        }
    }
}

impl<'de> Deserialize<'de> for Bounces {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Bounces;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number of bounces (0 or more) or \"unlimited\"")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Bounces, E> {
                u32::try_from(v)
                    .map(|n| Bounces(Some(n)))
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Bounces, E> {
                u32::try_from(v)
                    .map(|n| Bounces(Some(n)))
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Bounces, E> {
                if v == "unlimited" {
                    Ok(Bounces(None))
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct DisplayV2 {
    transform: DisplayTransform,
    exposure: f32,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderV2 {
    samples_per_pixel: u32,
    seed: u64,
    /// Write the denoised image (`render --denoise on`); written only when true.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    denoise: bool,
}

impl FileV2 {
    fn from_settings(s: &RenderSettings, folder: &Path) -> Result<Self, String> {
        if s.seed > i64::MAX as u64 {
            return Err(format!(
                "seed {} is above 2^63 − 1, the largest integer a TOML file holds",
                s.seed
            ));
        }
        let mut spec = s.scene.spec();
        spec::relative_models(&mut spec, folder);
        let c = &s.camera;
        let l = &s.light;
        let sh = &s.shading;
        Ok(Self {
            version: VERSION,
            scene: SceneV2 {
                name: spec.name,
                room: spec.room,
                blocks: spec.blocks,
                material_preset: s.material_preset,
                roughness: s.roughness,
                texture_preset: s.texture_preset,
                models: spec
                    .models
                    .into_iter()
                    .map(|m| ModelV2 {
                        file: m.file,
                        height: m.height,
                        floor_position: Floats(m.floor_position),
                        yaw: camera::degrees(m.yaw),
                        reflectance: m.reflectance.into(),
                        material: m.kind,
                        normal_map: m.relief.normal_map,
                        normal_strength: m.relief.normal_strength,
                        height_map: m.relief.height_map,
                        height_scale: m.relief.height_scale,
                    })
                    .collect(),
                surfaces: spec
                    .surfaces
                    .into_iter()
                    .map(|p| SurfaceV2 {
                        part: p.part,
                        normal_map: p.relief.normal_map,
                        normal_strength: p.relief.normal_strength,
                        height_map: p.relief.height_map,
                        height_scale: p.relief.height_scale,
                    })
                    .collect(),
                terrain: spec.terrain.map(|t| TerrainV2 {
                    seed: t.seed,
                    grid: t.grid,
                    height: t.height,
                    octaves: t.octaves,
                }),
                water: spec.water.map(|w| WaterV2 {
                    depth: w.depth,
                    ior: w.ior,
                    waves: w.waves,
                    time: w.time,
                }),
                materials: s
                    .part_materials
                    .iter()
                    .map(|p| PartMaterialV2 {
                        part: p.part,
                        material: p.kind,
                    })
                    .collect(),
            },
            camera: CameraV2 {
                position: c.position.into(),
                yaw: camera::degrees(c.yaw),
                pitch: camera::degrees(c.pitch),
                focal_length: c.focal_length,
                width: c.width,
                height: c.height,
                aperture: c.aperture,
                focus_distance: c.focus_distance,
            },
            light: LightV2::of(l),
            shading: ShadingV2 {
                stage: sh.stage,
                shadows: sh.shadows,
                indirect: sh.indirect,
                indirect_light: sh.indirect_light.into(),
                bounces: Bounces(sh.bounces),
                specular_depth: sh.specular_depth,
                smooth: sh.smooth,
                parallax_shadows: sh.parallax_shadows,
                caustics: sh.caustics,
                photons: sh.photons,
            },
            display: DisplayV2 {
                transform: s.display.transform,
                exposure: s.display.exposure,
            },
            render: RenderV2 {
                samples_per_pixel: s.samples_per_pixel,
                seed: s.seed,
                denoise: s.denoise,
            },
            equations: s.equations.clone(),
        })
    }

    /// The settings the file describes, its models' relative paths taken from `folder`.
    fn into_settings(self, folder: &Path, kind: LightKind) -> RenderSettings {
        let angle = Angles::of_version(self.version);
        let scene = self.scene;
        let mut spec = SceneSpec {
            name: scene.name,
            room: scene.room,
            blocks: scene.blocks,
            models: scene
                .models
                .into_iter()
                .map(|m| ModelSpec {
                    file: m.file,
                    height: m.height,
                    floor_position: m.floor_position.0,
                    yaw: angle.radians(m.yaw),
                    reflectance: m.reflectance.into(),
                    kind: m.material,
                    relief: ReliefSpec {
                        normal_map: m.normal_map,
                        normal_strength: m.normal_strength,
                        height_map: m.height_map,
                        height_scale: m.height_scale,
                    },
                })
                .collect(),
            surfaces: scene
                .surfaces
                .iter()
                .map(|p| PartRelief {
                    part: p.part,
                    relief: p.relief(),
                })
                .collect(),
            terrain: scene.terrain.map(|t| TerrainSpec {
                seed: t.seed,
                grid: t.grid,
                height: t.height,
                octaves: t.octaves,
            }),
            water: scene.water.map(|w| WaterSpec {
                depth: w.depth,
                ior: w.ior,
                waves: w.waves,
                time: w.time,
            }),
        };
        spec::resolve_models(&mut spec, folder);
        let c = self.camera;
        let l = self.light;
        let sh = self.shading;
        RenderSettings {
            scene: SceneChoice::from_spec(spec),
            camera: Camera {
                position: c.position.into(),
                yaw: angle.radians(c.yaw),
                pitch: angle.radians(c.pitch),
                focal_length: c.focal_length,
                width: c.width,
                height: c.height,
                aperture: c.aperture,
                focus_distance: c.focus_distance,
            },
            light: LightSpec {
                position: l.position.into(),
                power: l.power,
                colour: l.colour.into(),
                kind,
            },
            shading: Shading {
                stage: sh.stage,
                shadows: sh.shadows,
                indirect: sh.indirect,
                indirect_light: sh.indirect_light.into(),
                bounces: sh.bounces.0,
                specular_depth: sh.specular_depth,
                smooth: sh.smooth,
                parallax_shadows: sh.parallax_shadows,
                caustics: sh.caustics,
                photons: sh.photons,
            },
            material_preset: scene.material_preset,
            roughness: scene.roughness,
            part_materials: scene
                .materials
                .iter()
                .map(|p| PartMaterial {
                    part: p.part,
                    kind: p.material,
                })
                .collect(),
            texture_preset: scene.texture_preset,
            display: Display {
                transform: self.display.transform,
                exposure: self.display.exposure,
            },
            view: View::Shaded,
            samples_per_pixel: self.render.samples_per_pixel,
            seed: self.render.seed,
            denoise: self.render.denoise,
            equations: self.equations,
        }
    }
}

/// The unit of a file's angles, by its version.
#[derive(Clone, Copy)]
enum Angles {
    /// Version 1.
    Radians,
    /// Version 2.
    Degrees,
}

impl Angles {
    fn of_version(version: u32) -> Self {
        if version == VERSION_RADIANS {
            Angles::Radians
        } else {
            Angles::Degrees
        }
    }

    /// The in-memory angle (radians) of a value in the file. A version-1 value becomes the
    /// `f32` nearest it, exactly as version 1 was always read.
    fn radians(self, value: f64) -> f32 {
        match self {
            Angles::Radians => value as f32,
            Angles::Degrees => camera::radians(value),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::light::SpotCone;

    fn round_trip(settings: &RenderSettings) -> RenderSettings {
        let text = to_text(settings, Path::new("/scenes")).unwrap();
        parse(&text, Path::new("/scenes")).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    #[test]
    fn every_setting_round_trips_exactly() {
        let mut s = RenderSettings::default();
        s.camera.position = Vec3::new(0.1, -0.2, -2.7);
        s.camera.yaw = 0.1;
        s.camera.pitch = -0.05;
        s.camera.focal_length = 333.3;
        s.camera.width = 320;
        s.camera.height = 200;
        s.camera.aperture = 0.02;
        s.camera.focus_distance = 2.5;
        s.light.position = Vec3::new(0.3, -0.7, 0.1);
        s.light.power = 21.5;
        s.light.colour = Vec3::new(1.0, 0.8, 0.6);
        s.light.kind = LightKind::Sphere { radius: 0.05 };
        s.shading = Shading::for_stage(Stage::Path);
        s.shading.bounces = Some(3);
        s.shading.indirect_light = Vec3::new(0.1, 0.2, 0.3);
        s.shading.smooth = false;
        s.shading.caustics = Caustics::Photons;
        s.shading.photons = 25_000;
        s.material_preset = MaterialPreset::Both;
        s.texture_preset = TexturePreset::CheckerFloor;
        s.display = Display {
            transform: DisplayTransform::Filmic,
            exposure: 1.5,
        };
        s.samples_per_pixel = 64;
        s.seed = 12345;
        assert_eq!(round_trip(&s), s);
        for scene in SceneChoice::BUILT_IN {
            let s = RenderSettings {
                scene,
                ..RenderSettings::default()
            };
            assert_eq!(round_trip(&s), s);
        }
    }

    /// Settings with a model: the camera's yaw and pitch and the model's yaw are the file's
    /// three angles.
    fn with_angles(yaw: f32, pitch: f32, model_yaw: f32) -> RenderSettings {
        let mut spec = SceneSpec::cornell("angles");
        let mut model = ModelSpec::new("teapot", &crate::shapes::scene::obj::Placement::TEAPOT);
        model.yaw = model_yaw;
        spec.models.push(model);
        let mut s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            ..RenderSettings::default()
        };
        s.camera.yaw = yaw;
        s.camera.pitch = pitch;
        s
    }

    /// The three angles' bits.
    fn angle_bits(s: &RenderSettings) -> [u32; 3] {
        let SceneChoice::Custom(spec) = &s.scene else {
            panic!("{:?}", s.scene)
        };
        [s.camera.yaw, s.camera.pitch, spec.models[0].yaw].map(f32::to_bits)
    }

    /// Angles are written in degrees, as typed in the workbench and on the command line: an
    /// angle set as 12.5° is written `12.5`, and a file's degrees are read as such.
    #[test]
    fn angles_are_in_degrees() {
        let s = with_angles(
            camera::radians(12.5),
            camera::radians(-30.0),
            camera::radians(90.0),
        );
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert!(text.starts_with("# A raylab scene file") && text.contains("\nversion = 2\n"));
        assert!(text.contains("Angles are in degrees"), "{text}");
        assert!(text.contains("yaw = 12.5\npitch = -30.0\n"), "{text}");
        assert!(text.contains("yaw = 90.0\n"), "{text}");
        let read = parse(&text, Path::new("/x")).unwrap();
        assert_eq!(angle_bits(&read), angle_bits(&s));
        assert!((read.camera.yaw - 12.5f32.to_radians()).abs() < 1e-7);
        assert!((read.camera.pitch + std::f32::consts::FRAC_PI_6).abs() < 1e-7);
    }

    /// Saving then loading gives every angle back bit for bit, though a degree's decimal is not
    /// the radian's: on many random angles — uniform over a few turns, typed degrees with a
    /// decimal or two, and any finite `f32` — the file's decimal reads back to the same `f32`,
    /// and is no longer than the degrees typed.
    #[test]
    fn angles_round_trip_bit_for_bit_through_degrees() {
        let mut bits = crate::base::sampling::Rng::new(42);
        let mut finite = || loop {
            let x = f32::from_bits(bits.next_u32());
            if x.is_finite() {
                return x;
            }
        };
        let mut rng = crate::base::sampling::Rng::new(7);
        let mut angles: Vec<f32> = Vec::new();
        for i in 0..30_000 {
            angles.push(match i % 3 {
                0 => rng.uniform(-4.0 * std::f32::consts::TAU, 4.0 * std::f32::consts::TAU),
                1 => camera::radians(f64::from(rng.next_u32() % 72_001) / 100.0 - 360.0),
                _ => finite(),
            });
        }
        angles.extend([0.0, -0.0, f32::MIN_POSITIVE, 1e-45, f32::MAX, -f32::MAX]);
        for &a in &angles {
            assert_eq!(
                camera::radians(camera::degrees(a)).to_bits(),
                a.to_bits(),
                "{a:e}"
            );
        }
        // Degrees typed with two decimals come back as typed, never longer.
        for hundredths in -36_000..=36_000 {
            let typed = f64::from(hundredths) / 100.0;
            let written = camera::degrees(camera::radians(typed));
            assert!(
                written.to_string().len() <= typed.to_string().len(),
                "{typed} written as {written}"
            );
        }
        // Through whole files, three angles a file.
        for three in angles.chunks_exact(3).step_by(5) {
            let s = with_angles(three[0], three[1], three[2]);
            let read = round_trip(&s);
            assert_eq!(angle_bits(&read), angle_bits(&s), "{three:?}");
            assert_eq!(read, s);
        }
    }

    /// A version-1 file (radians) keeps its meaning: its angles are the radians it holds,
    /// exactly as before; saved again it is version 2 in degrees, and reads back the same.
    #[test]
    fn a_version_1_file_is_read_in_radians() {
        let v2 = to_text(&with_angles(0.0, 0.0, 0.5), Path::new("/x")).unwrap();
        let model_yaw = format!("yaw = {}\n", camera::degrees(0.5));
        assert!(v2.contains(&model_yaw), "{v2}");
        let v1 = v2
            .replace("version = 2", "version = 1")
            .replace("yaw = 0.0\npitch = 0.0", "yaw = 0.3\npitch = -0.05")
            .replace(&model_yaw, "yaw = -0.6\n");
        let read = parse(&v1, Path::new("/x")).unwrap();
        assert_eq!(angle_bits(&read), [0.3f32, -0.05, -0.6].map(f32::to_bits));
        let saved = to_text(&read, Path::new("/x")).unwrap();
        assert!(saved.contains("version = 2"), "{saved}");
        assert!(
            saved.contains(&format!(
                "yaw = {}\npitch = {}\n",
                camera::degrees(0.3),
                camera::degrees(-0.05)
            )),
            "{saved}"
        );
        assert!((camera::degrees(0.3) - 17.188_733).abs() < 1e-5);
        let again = parse(&saved, Path::new("/x")).unwrap();
        assert_eq!(angle_bits(&again), angle_bits(&read));
        assert_eq!(again, read);
        // The same numbers in a version-2 file are degrees.
        let as_degrees = parse(&v1.replace("version = 1", "version = 2"), Path::new("/x")).unwrap();
        assert_eq!(as_degrees.camera.yaw, camera::radians(0.3));
    }

    /// The shipped gallery, rewritten in degrees, holds the radians its version-1 text held
    /// (its models' yaws 0.3, 0 and −0.6), bit for bit.
    #[test]
    fn the_shipped_gallery_kept_its_angles() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
        let text = std::fs::read_to_string(folder.join("gallery.toml")).unwrap();
        assert!(text.contains("\nversion = 2\n"), "{text}");
        let SceneChoice::Custom(spec) = parse(&text, &folder).unwrap().scene else {
            panic!("{text}")
        };
        let yaws: Vec<u32> = spec.models.iter().map(|m| m.yaw.to_bits()).collect();
        assert_eq!(yaws, [0.3f32, 0.0, -0.6].map(f32::to_bits));
    }

    /// A file written before caustics existed (no `caustics`, no `photons`) reads with
    /// caustics off and the default photon count; a count beyond the bound names its line.
    #[test]
    fn caustics_are_optional_in_a_file_and_checked() {
        let mut s = RenderSettings::default();
        s.shading.caustics = Caustics::Photons;
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert!(
            text.contains("caustics = \"photons\"\nphotons = 100000"),
            "{text}"
        );
        let old = text.replace("caustics = \"photons\"\nphotons = 100000\n", "");
        let read = parse(&old, Path::new("/x")).unwrap();
        assert_eq!(read.shading.caustics, Caustics::Off);
        assert_eq!(read.shading.photons, DEFAULT_PHOTONS);
        let error = parse(
            &text.replace("photons = 100000", "photons = 20000000"),
            Path::new("/x"),
        )
        .unwrap_err()
        .to_string();
        assert!(error.contains("photons"), "{error}");
    }

    #[test]
    fn a_custom_scene_round_trips_with_its_models_relative_to_the_file() {
        let mut spec = SceneSpec::cornell("two models");
        spec.blocks = false;
        spec.models.push(ModelSpec::new(
            "bunny",
            &crate::shapes::scene::obj::Placement::FRONT_LEFT,
        ));
        let mut dragon = ModelSpec::new(
            "/scenes/models/dragon.obj",
            &crate::shapes::scene::obj::Placement::TEAPOT,
        );
        dragon.kind = MaterialKind::Glass {
            ior: 1.5,
            tint: Vec3::ONE,
        };
        spec.models.push(dragon);
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/scenes")).unwrap();
        assert!(text.contains("file = \"models/dragon.obj\""), "{text}");
        assert!(text.contains("kind = \"glass\""), "{text}");
        assert_eq!(parse(&text, Path::new("/scenes")).unwrap(), s);
    }

    /// Normal and height maps on a model and on a part of the box: written relative to the
    /// file, with their strength and depth, and read back exactly; the defaults are left out.
    #[test]
    fn maps_round_trip_relative_to_the_file() {
        let mut spec = SceneSpec::cornell("maps");
        let mut model = ModelSpec::new(
            "/scenes/models/statue.obj",
            &crate::shapes::scene::obj::Placement::TEAPOT,
        );
        model.relief = ReliefSpec {
            normal_map: Some("/scenes/maps/statue-normal.png".into()),
            normal_strength: 0.5,
            height_map: Some("/scenes/maps/statue-height.png".into()),
            height_scale: 0.05,
        };
        spec.models.push(model);
        spec.surfaces.push(PartRelief {
            part: BoxPart::Floor,
            relief: ReliefSpec {
                height_map: Some("/scenes/maps/tiles.png".into()),
                ..ReliefSpec::default()
            },
        });
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/scenes")).unwrap();
        for line in [
            "normal_map = \"maps/statue-normal.png\"",
            "normal_strength = 0.5",
            "height_map = \"maps/statue-height.png\"",
            "height_scale = 0.05",
            "[[scene.surfaces]]",
            "part = \"floor\"",
            "height_map = \"maps/tiles.png\"",
        ] {
            assert!(text.contains(line), "{line}:\n{text}");
        }
        assert_eq!(text.matches("height_scale").count(), 1, "{text}");
        assert_eq!(parse(&text, Path::new("/scenes")).unwrap(), s);
        // A depth out of range names its field.
        let bad = text.replace("height_scale = 0.05", "height_scale = 2.0");
        let e = parse(&bad, Path::new("/scenes")).unwrap_err();
        assert!(e.contains("scene.models[0].height_scale"), "{e}");
    }

    #[test]
    fn a_built_in_scene_read_from_a_file_is_that_scene() {
        let s = RenderSettings {
            scene: SceneChoice::Bunny,
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/x"))
            .unwrap()
            .replace("name = \"bunny\"", "name = \"my bunny\"");
        assert_eq!(
            parse(&text, Path::new("/x")).unwrap().scene,
            SceneChoice::Bunny
        );
    }

    fn error_of(edit: impl Fn(String) -> String) -> String {
        let text = edit(to_text(&RenderSettings::default(), Path::new("/x")).unwrap());
        parse(&text, Path::new("/x")).unwrap_err()
    }

    #[test]
    fn errors_name_the_field_and_the_line() {
        // The default file: comments on lines 1–2, then `version = 2` on 3.
        let text = to_text(&RenderSettings::default(), Path::new("/x")).unwrap();
        let line = |key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;

        let e = error_of(|t| t.replace("power = 14.0", "power = -1.0"));
        assert_eq!(
            e,
            format!(
                "line {} (power = -1.0): invalid light power -1: must be ≥ 0",
                line("power")
            )
        );
        let e = error_of(|t| t.replace("power = 14.0", "power = nan"));
        assert!(
            e.starts_with(&format!(
                "line {} (power = nan): invalid light power NaN",
                line("power")
            )),
            "{e}"
        );
        let e = error_of(|t| t.replace("power = 14.0", "power = 14.0\nwatts = 3"));
        assert!(
            e.starts_with(&format!(
                "line {} (watts = 3): unknown field `watts`",
                line("power") + 1
            )),
            "{e}"
        );
        let e = error_of(|t| t.replace("power = 14.0\n", ""));
        assert!(e.contains("missing field `power`"), "{e}");
        assert!(e.contains("[light]"), "{e}");
        let e = error_of(|t| t.replace("width = 512", "width = 0"));
        assert!(
            e.starts_with(&format!(
                "line {} (width = 0): invalid width 0",
                line("width")
            )),
            "{e}"
        );
        let e = error_of(|t| t.replace("stage = \"lab\"", "stage = \"lap\""));
        assert!(e.contains("line") && e.contains("lap"), "{e}");
    }

    /// Arrays of three numbers take exactly three: a fourth (or a million more) is refused,
    /// not dropped, and so is a missing one; each error names the line.
    #[test]
    fn arrays_take_exactly_their_length() {
        let text = to_text(&RenderSettings::default(), Path::new("/x")).unwrap();
        let line = |key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
        let position = "position = [0.0, 0.0, -3.001]";
        assert!(text.contains(position), "{text}");
        let e = error_of(|t| t.replace(position, "position = [0, 0, -3.001, 99]"));
        assert!(
            e.starts_with(&format!("line {}", line("position")))
                && e.contains("more than 3 elements"),
            "{e}"
        );
        let million = format!("position = [{}]", vec!["0"; 1_000_000].join(", "));
        let e = error_of(|t| t.replace(position, &million));
        assert!(
            e.contains("more than 3 elements"),
            "{}",
            &e[..200.min(e.len())]
        );
        let e = error_of(|t| t.replace(position, "position = [0, 0]"));
        assert!(
            e.contains("invalid length 2") && e.contains("exactly 3"),
            "{e}"
        );
        let e = error_of(|t| t.replace("colour = [1.0, 1.0, 1.0]", "colour = [1, 1, 1, 1]"));
        assert!(e.contains("more than 3 elements"), "{e}");
    }

    /// A model's material has its kind's fields and no others: a mirror with an index of
    /// refraction, or a diffuse material with a tint, is refused naming the field.
    #[test]
    fn a_material_takes_only_its_kinds_fields() {
        let mut spec = SceneSpec::cornell("m");
        let mut mirror = ModelSpec::new("bunny", &crate::shapes::scene::obj::Placement::FRONT_LEFT);
        mirror.kind = MaterialKind::Mirror {
            tint: Vec3::splat(0.9),
        };
        spec.models.push(mirror);
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert_eq!(parse(&text, Path::new("/x")).unwrap(), s);
        let kind = "kind = \"mirror\"";
        assert!(text.contains(kind), "{text}");
        for (edit, field) in [
            (format!("{kind}\nior = 1.5"), "ior"),
            (format!("{kind}\ncolour = 1"), "colour"),
            ("kind = \"diffuse\"".to_owned(), "tint"),
        ] {
            let e = parse(&text.replace(kind, &edit), Path::new("/x")).unwrap_err();
            assert!(
                e.contains(&format!("unknown field `{field}`")),
                "{edit}: {e}"
            );
            assert!(e.starts_with("line "), "{e}");
        }
        let e = parse(
            &text.replace("tint = [0.9, 0.9, 0.9]", "tint = [0.9, 0.9, 0.9, 0.9]"),
            Path::new("/x"),
        )
        .unwrap_err();
        assert!(e.contains("more than 3 elements"), "{e}");
    }

    /// A part of the box with a material of its own is written as `[[scene.materials]]`, read
    /// back the same, and a value out of its range or a part given twice is refused at its
    /// line.
    #[test]
    fn a_part_material_round_trips_and_is_checked_at_its_line() {
        let s = RenderSettings {
            part_materials: vec![PartMaterial {
                part: BoxPart::TallBlock,
                kind: MaterialKind::Rough {
                    alpha: 0.3,
                    tint: Vec3::new(0.9, 0.8, 0.7),
                },
            }],
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert_eq!(parse(&text, Path::new("/x")).unwrap(), s);
        for line in [
            "[[scene.materials]]",
            "part = \"tall-block\"",
            "kind = \"rough\"",
            "alpha = 0.3",
        ] {
            assert!(text.contains(line), "{line}: {text}");
        }
        let e = parse(&text.replace("alpha = 0.3", "alpha = 1.5"), Path::new("/x")).unwrap_err();
        assert!(
            e.starts_with("line ")
                && e.contains(
                    "invalid scene.materials[0].material.alpha 1.5: must be in [0.01, 1]"
                ),
            "{e}"
        );
        let twice = format!(
            "{text}\n[[scene.materials]]\npart = \"tall-block\"\n\n[scene.materials.material]\nkind = \"diffuse\"\n"
        );
        let e = parse(&twice, Path::new("/x")).unwrap_err();
        assert!(
            e.starts_with("line ")
                && e.contains("invalid scene.materials[1].part \"tall-block\": has a material"),
            "{e}"
        );
    }

    /// A plastic model and the plastic preset are written and read back as they were, the
    /// plastic's fields by name; a bad index or roughness is refused naming the field.
    #[test]
    fn a_plastic_material_round_trips() {
        let mut spec = SceneSpec::cornell("p");
        let mut model = ModelSpec::new("bunny", &crate::shapes::scene::obj::Placement::FRONT_LEFT);
        model.kind = MaterialKind::Plastic {
            alpha: 0.25,
            int_ior: 1.4,
            ext_ior: 1.0,
            specular: Vec3::new(1.0, 0.9, 0.8),
        };
        spec.models.push(model);
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            material_preset: crate::shading::material::MaterialPreset::Plastic,
            roughness: 0.1,
            ..RenderSettings::default()
        };
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert_eq!(parse(&text, Path::new("/x")).unwrap(), s);
        for line in [
            "kind = \"plastic\"",
            "alpha = 0.25",
            "int_ior = 1.4",
            "ext_ior = 1.0",
            "specular = [1.0, 0.9, 0.8]",
            "material_preset = \"plastic\"",
            "roughness = 0.1",
        ] {
            assert!(text.contains(line), "{line}: {text}");
        }
        let e = parse(
            &text.replace("int_ior = 1.4", "int_ior = 1.0"),
            Path::new("/x"),
        )
        .unwrap_err();
        assert!(e.contains("material") && e.contains("differ"), "{e}");
        let e = parse(
            &text.replace("alpha = 0.25", "alpha = 2.0"),
            Path::new("/x"),
        )
        .unwrap_err();
        assert!(e.contains("material.alpha 2: must be in [0.01, 1]"), "{e}");
        let e = parse(
            &text.replace("ext_ior = 1.0", "ext_ior = 1.0\ntint = 1"),
            Path::new("/x"),
        )
        .unwrap_err();
        assert!(
            e.starts_with("line ") && e.contains("unknown field `tint`"),
            "{e}"
        );
    }

    #[test]
    fn the_version_is_checked_first() {
        let e = error_of(|t| t.replace("version = 2", "version = 3"));
        assert_eq!(
            e,
            "line 3 (version = 3): version 3 is not one this raylab reads (it reads versions \
             1, angles in radians, and 2, angles in degrees)"
        );
        let e = error_of(|t| t.replace("version = 2\n", ""));
        assert!(e.starts_with("line 1: missing field `version`"), "{e}");
        let e = parse("not toml [", Path::new("/x")).unwrap_err();
        assert!(e.starts_with("line 1 (not toml [)"), "{e}");
    }

    #[test]
    fn a_byte_order_mark_is_ignored() {
        let text = format!(
            "\u{feff}{}",
            to_text(&RenderSettings::default(), Path::new("/x")).unwrap()
        );
        assert_eq!(
            parse(&text, Path::new("/x")).unwrap(),
            RenderSettings::default()
        );
    }

    #[test]
    fn bad_model_values_name_the_model() {
        let mut s = RenderSettings {
            scene: SceneChoice::Bunny,
            ..RenderSettings::default()
        };
        s.scene = SceneChoice::Custom(Box::new(SceneSpec {
            name: "x".into(),
            ..s.scene.spec()
        }));
        let text = to_text(&s, Path::new("/x"))
            .unwrap()
            .replace("height = 0.75", "height = -2.0");
        let e = parse(&text, Path::new("/x")).unwrap_err();
        assert!(
            e.contains("(height = -2.0): invalid scene.models[0].height -2: must be in (0, 2]"),
            "{e}"
        );
    }

    /// The default file with `[[scene.surfaces]]` for `parts` appended (each with a normal
    /// map of its own), after `edit`.
    fn with_surfaces(parts: &[&str], edit: impl Fn(String) -> String) -> String {
        let mut text = edit(to_text(&RenderSettings::default(), Path::new("/x")).unwrap());
        for (i, part) in parts.iter().enumerate() {
            text.push_str(&format!(
                "\n[[scene.surfaces]]\npart = \"{part}\"\nnormal_map = \"map{i}.png\"\n"
            ));
        }
        text
    }

    /// The line of `text` that is `line`, counted from 1; the last if there are several.
    fn line_number(text: &str, line: &str) -> usize {
        text.lines()
            .enumerate()
            .filter(|(_, l)| *l == line)
            .last()
            .unwrap()
            .0
            + 1
    }

    /// Two `[[scene.surfaces]]` for one part are refused at the second's line (the first was
    /// dropped without a word); two parts, one entry each, are read.
    #[test]
    fn a_part_given_maps_twice_is_refused_at_its_line() {
        let text = with_surfaces(&["back-wall", "floor", "back-wall"], |t| t);
        let e = parse(&text, Path::new("/x")).unwrap_err();
        assert_eq!(
            e,
            format!(
                "line {} (part = \"back-wall\"): invalid scene.surfaces[2].part \"back-wall\": \
                 has maps from an earlier [[scene.surfaces]] already: give each part one entry, \
                 with all its maps",
                line_number(&text, "part = \"back-wall\"")
            )
        );
        let text = with_surfaces(&["back-wall", "floor"], |t| t);
        let SceneChoice::Custom(spec) = parse(&text, Path::new("/x")).unwrap().scene else {
            panic!("{text}")
        };
        assert_eq!(spec.surfaces.len(), 2);
    }

    /// A surface for a part the scene leaves out (a block with `blocks = false`, a wall with
    /// `room = false`) is refused at its line; it was ignored without a word.
    #[test]
    fn a_surface_for_an_absent_part_is_refused_at_its_line() {
        let text = with_surfaces(&["floor", "short-block"], |t| {
            t.replace("blocks = true", "blocks = false")
        });
        let e = parse(&text, Path::new("/x")).unwrap_err();
        assert_eq!(
            e,
            format!(
                "line {} (part = \"short-block\"): invalid scene.surfaces[1].part \
                 \"short-block\": is not in the scene: `blocks = false` leaves the blocks out \
                 (set `blocks = true`, or remove this surface)",
                line_number(&text, "part = \"short-block\"")
            )
        );
        let text = with_surfaces(&["tall-block", "left-wall"], |t| {
            t.replace("room = true", "room = false")
        });
        let e = parse(&text, Path::new("/x")).unwrap_err();
        assert!(
            e.starts_with(&format!(
                "line {} (part = \"left-wall\"): invalid scene.surfaces[1].part \"left-wall\": \
                 is not in the scene: `room = false` leaves the room out",
                line_number(&text, "part = \"left-wall\"")
            )),
            "{e}"
        );
        // The blocks without the room may have maps; so may the room without the blocks.
        let text = with_surfaces(&["tall-block"], |t| {
            t.replace("room = true", "room = false")
        });
        parse(&text, Path::new("/x")).unwrap();
        let text = with_surfaces(&["ceiling"], |t| {
            t.replace("blocks = true", "blocks = false")
        });
        parse(&text, Path::new("/x")).unwrap();
    }

    /// A point light given a size, and an area light too small for its radiance to be an
    /// `f32`, are refused at the radius's (or side's) line, saying what to use instead.
    #[test]
    fn a_point_light_with_a_size_or_a_tiny_area_light_is_refused_at_its_line() {
        let text = to_text(&RenderSettings::default(), Path::new("/x")).unwrap();
        assert!(text.contains("shape = \"point\"\n"), "{text}");
        assert!(!text.contains("radius"), "{text}");
        let point = "shape = \"point\"";
        let line = line_number(&text, point) + 1;
        let e = error_of(|t| t.replace(point, "shape = \"point\"\nradius = 0.3"));
        assert_eq!(
            e,
            format!(
                "line {line} (radius = 0.3): invalid light size 0.3: a point light has no size: \
                 for an area light of this size choose the shape sphere or quad \
                 (--light-shape), or give the size 0"
            )
        );
        for (shape, field) in [("sphere", "radius"), ("quad", "side"), ("quad", "radius")] {
            let e =
                error_of(|t| t.replace(point, &format!("shape = \"{shape}\"\n{field} = 1e-30")));
            assert!(
                e.starts_with(&format!(
                    "line {line} ({field} = 1e-30): invalid light size 1e-30: must be 0 (the \
                     point light) or between 0.001 and 1e6 (scene units)"
                )),
                "{e}"
            );
        }
    }

    /// Files written when a light was a `radius` and a `shape` still load as the same light:
    /// a square's side given as its radius, no shape with a radius (a sphere) or radius 0 (the
    /// point).
    #[test]
    fn old_lights_load_as_the_same_light() {
        let point = "shape = \"point\"";
        let read = |with: &str| {
            let text = to_text(&RenderSettings::default(), Path::new("/x")).unwrap();
            parse(&text.replace(point, with), Path::new("/x")).map(|s| s.light.kind)
        };
        assert_eq!(
            read("radius = 0.5\nshape = \"quad\""),
            Ok(LightKind::Quad { side: 0.5 })
        );
        assert_eq!(read("radius = 0.2"), Ok(LightKind::Sphere { radius: 0.2 }));
        assert_eq!(read("radius = 0.0"), Ok(LightKind::Point));
        assert_eq!(
            read("radius = 0.0\nshape = \"point\""),
            Ok(LightKind::Point)
        );
        // The scene files in the repository, written before, load.
        for name in ["figure7", "gallery", "mirror"] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../assets/scenes")
                .join(format!("{name}.toml"));
            let settings = load(&path).unwrap();
            assert!(!settings.light.is_area() || name == "gallery", "{name}");
        }
    }

    /// A spot light's fields: written in degrees and read back exactly; each missing one named
    /// at the `[light]` table's line, one of another kind (a spot's `radius`, a sphere's `aim`)
    /// at its own, values out of bounds at theirs with the settings' own reasons; version 1
    /// reads the angles in radians.
    #[test]
    fn a_spot_light_in_a_scene_file() {
        let mut s = RenderSettings::default();
        s.light.kind = LightKind::Spot(SpotCone::default());
        let text = to_text(&s, Path::new("/x")).unwrap();
        assert!(
            text.contains("shape = \"spot\"\naim = [0.0, 1.0, -0.2]\ncutoff = 25.0\nbeam = 15.0\n"),
            "{text}"
        );
        assert_eq!(parse(&text, Path::new("/x")).unwrap(), s);
        let at = |line: &str| line_number(&text, line);
        let edit =
            |from: &str, to: &str| parse(&text.replace(from, to), Path::new("/x")).unwrap_err();
        let table = at("[light]");
        assert_eq!(
            edit("cutoff = 25.0\n", ""),
            format!(
                "line {table} ([light]): missing field `cutoff` in [light]: a spot light needs it"
            )
        );
        assert_eq!(
            edit("beam = 15.0", "beam = 15.0\nradius = 0.1"),
            format!(
                "line {} (radius = 0.1): light.radius: a spot light has no `radius` (its fields: \
                 aim, cutoff, beam)",
                at("beam = 15.0") + 1
            )
        );
        assert_eq!(
            edit("beam = 15.0", "beam = 30.0"),
            format!(
                "line {} (beam = 30.0): invalid spot beam 30° (cutoff 25°): must be from 0° to \
                 the cutoff (--spot-beam, --spot-cutoff)",
                at("beam = 15.0")
            )
        );
        assert_eq!(
            edit("cutoff = 25.0", "cutoff = 90.0"),
            format!(
                "line {} (cutoff = 90.0): invalid spot cutoff 90°: must be above 0° and below \
                 90° (--spot-cutoff)",
                at("cutoff = 25.0")
            )
        );
        assert!(
            edit("aim = [0.0, 1.0, -0.2]", "aim = [0.0, -0.5, -0.7]").starts_with(&format!(
                "line {} (aim = [0.0, -0.5, -0.7]): invalid light aim",
                at("aim = [0.0, 1.0, -0.2]")
            )),
        );
        let sphere = text.replace("shape = \"spot\"", "shape = \"sphere\"\nradius = 0.1");
        assert!(
            parse(&sphere, Path::new("/x"))
                .unwrap_err()
                .contains("light.aim: a sphere light has no `aim`")
        );
        let v1 = text
            .replace("version = 2", "version = 1")
            .replace("cutoff = 25.0", "cutoff = 0.5")
            .replace("beam = 15.0", "beam = 0.25");
        assert_eq!(
            parse(&v1, Path::new("/x")).unwrap().light.kind,
            LightKind::Spot(SpotCone {
                cutoff: 0.5,
                beam: 0.25,
                ..SpotCone::default()
            })
        );
    }
}
