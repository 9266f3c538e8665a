//! A scene described by its parts: the lab's room and blocks, models standing in the box, a
//! terrain on its floor. Every scene raylab traces is assembled here ([`assemble`]), the
//! built-in ones included ([`super::SceneChoice::spec`]), so a scene file that names the same
//! parts gives the same triangles, bit for bit.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::obj::{self, Mesh, Placement};
use super::terrain::{self, TerrainSpec};
use super::water::{self, WaterSpec};
use super::{Material, MaterialKind, Scene, SceneError, cornell_box};
use crate::base::inputs::Input;
use crate::base::invalid::SettingsError;
use crate::shading::relief::{Decoding, HeightMap, NormalMap, Relief};
use crate::shading::texture::TextureImage;
use std::sync::Arc;

/// The lab's room: the first ten triangles of [`cornell_box`] (floor, walls, ceiling).
pub const ROOM_TRIANGLES: usize = 10;

/// The parts of a scene. `PartialEq` compares every field, so two specs that are equal build
/// the same scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneSpec {
    /// What the scene is called in the workbench and in messages.
    pub name: String,
    /// The lab's room: floor, left, right and back walls, ceiling (its open side faces the
    /// camera).
    pub room: bool,
    /// The lab's two blocks, the short red one and the tall blue one.
    pub blocks: bool,
    /// Models standing on the box's floor, in order.
    pub models: Vec<ModelSpec>,
    /// A fractal terrain covering the floor.
    pub terrain: Option<TerrainSpec>,
    /// Normal and height maps for parts of the box.
    #[serde(default)]
    pub surfaces: Vec<PartRelief>,
    /// Water over the floor ([`water`]).
    #[serde(default)]
    pub water: Option<WaterSpec>,
}

/// A model standing in the box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelSpec {
    /// A model built into raylab (`bunny`, `teapot`, `textured-teapot`) or the path of an OBJ
    /// file. A scene file's relative paths are resolved against its own folder when it is read.
    pub file: PathBuf,
    /// Where and how it stands; its `reflectance` is the model's ρ.
    pub height: f32,
    /// The centre of its footprint on the floor, (x, z).
    pub floor_position: [f32; 2],
    /// Turn about the vertical axis, in radians (degrees in a scene file).
    pub yaw: f32,
    /// Its diffuse reflectance ρ (kept for mirror and glass too, as the blocks' is).
    pub reflectance: Vec3,
    /// Diffuse (the default, textured if its material library names a texture), mirror or
    /// glass.
    pub kind: MaterialKind,
    /// Its normal and height maps, if the scene file gives them (they replace a normal map its
    /// material library names).
    #[serde(default)]
    pub relief: ReliefSpec,
}

/// Normal and height maps a scene file gives a surface ([`crate::shading::relief`]): `normal_map`,
/// `normal_strength` (1 unless given), `height_map` and `height_scale` (scene units deep per
/// unit of height, [`DEFAULT_HEIGHT_SCALE`] unless given). Paths are relative to the scene
/// file, as model paths are.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReliefSpec {
    pub normal_map: Option<PathBuf>,
    pub normal_strength: f32,
    pub height_map: Option<PathBuf>,
    pub height_scale: f32,
}

/// How deep a height map carves unless the scene file says: 0.02 scene units (the box is 2
/// wide) per unit of height.
pub const DEFAULT_HEIGHT_SCALE: f32 = 0.02;

impl Default for ReliefSpec {
    fn default() -> Self {
        Self {
            normal_map: None,
            normal_strength: 1.0,
            height_map: None,
            height_scale: DEFAULT_HEIGHT_SCALE,
        }
    }
}

impl ReliefSpec {
    /// The maps' files.
    fn files_mut(&mut self) -> impl Iterator<Item = &mut PathBuf> {
        self.normal_map.iter_mut().chain(self.height_map.iter_mut())
    }

    /// Reads the maps: `None` if there are none; a map that cannot be read (missing, not a
    /// PNG or JPEG, too large) is an error naming its file.
    pub fn load(&self) -> Result<Option<Arc<Relief>>, SceneError> {
        if self.normal_map.is_none() && self.height_map.is_none() {
            return Ok(None);
        }
        let load = |file: &Path, decoding| {
            TextureImage::load_as(file, decoding)
                .map(Arc::new)
                .map_err(|e| SceneError::map(decoding, e))
        };
        let normal = match &self.normal_map {
            Some(file) => {
                let image = load(file, Decoding::Normal)?;
                if let Some(reason) = NormalMap::refusal(&image) {
                    return Err(SceneError::Map {
                        what: Decoding::Normal.what(),
                        name: image.name.clone(),
                        reason: reason.to_owned(),
                    });
                }
                Some(NormalMap {
                    image,
                    strength: self.normal_strength,
                })
            }
            None => None,
        };
        let height = match &self.height_map {
            Some(file) => Some(HeightMap::new(
                load(file, Decoding::Height)?,
                self.height_scale,
            )),
            None => None,
        };
        Ok(Some(Arc::new(Relief {
            normal,
            height,
            uv_scale: 1.0,
        })))
    }

    /// Checks the strength (0 to 10), the depth (0 to 0.5) and the files' paths; errors name
    /// the field as `field` makes it.
    fn validate(&self, field: impl Fn(&str) -> String) -> Result<(), SettingsError> {
        for (name, file) in [
            ("normal_map", &self.normal_map),
            ("height_map", &self.height_map),
        ] {
            if let Some(file) = file {
                crate::base::invalid::check_path(field(name), file)?;
            }
        }
        let bad = |name: &str, value: f32, reason| SettingsError {
            name: field(name).into(),
            value: value.to_string(),
            reason,
        };
        if !(0.0..=10.0).contains(&self.normal_strength) {
            return Err(bad(
                "normal_strength",
                self.normal_strength,
                "must be in [0, 10]",
            ));
        }
        if !(0.0..=0.5).contains(&self.height_scale) {
            return Err(bad(
                "height_scale",
                self.height_scale,
                "must be in [0, 0.5]",
            ));
        }
        Ok(())
    }

    /// The maps' files, each with what it is (`normal`, `height`).
    fn files_read(&self, normal: &'static str, height: &'static str) -> Vec<Input> {
        let normal = self.normal_map.iter().map(|f| Input::new(f, normal));
        let height = self.height_map.iter().map(|f| Input::new(f, height));
        normal.chain(height).collect()
    }

    /// The memory decoding the maps takes, as their headers give their sizes (0 for a file
    /// that cannot be read: loading it fails anyway).
    fn memory_estimate(&self) -> u64 {
        self.normal_map
            .iter()
            .chain(&self.height_map)
            .filter_map(|file| {
                let (w, h) = TextureImage::dimensions(file)?;
                let bytes = std::fs::metadata(file).map_or(0, |m| m.len());
                Some(TextureImage::decoding_bytes(w, h) + bytes)
            })
            .sum()
    }
}

/// A part of the lab's box, by what it is: the surface a scene file's `[[scene.surfaces]]`
/// gives maps to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoxPart {
    Floor,
    LeftWall,
    RightWall,
    BackWall,
    Ceiling,
    ShortBlock,
    TallBlock,
}

crate::base::named::named_enum!(BoxPart as "box part" {
    Floor => "floor";
    LeftWall => "left-wall";
    RightWall => "right-wall";
    BackWall => "back-wall";
    Ceiling => "ceiling";
    ShortBlock => "short-block";
    TallBlock => "tall-block";
});

impl BoxPart {
    /// Whether the part is one of the two blocks (else the room's: floor, walls, ceiling).
    pub fn is_block(self) -> bool {
        matches!(self, BoxPart::ShortBlock | BoxPart::TallBlock)
    }

    /// The name of the part's material in [`cornell_box`].
    pub fn material(self) -> &'static str {
        match self {
            BoxPart::Floor => "green",
            BoxPart::LeftWall => "purple",
            BoxPart::RightWall => "yellow",
            BoxPart::BackWall => "white",
            BoxPart::Ceiling => "cyan",
            BoxPart::ShortBlock => "red",
            BoxPart::TallBlock => "blue",
        }
    }
}

/// Maps for a part of the box. The box has no texture coordinates of its own: the maps are
/// laid on its planar ones ([`crate::shading::texture::planar_uv`]), one image per scene unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartRelief {
    pub part: BoxPart,
    pub relief: ReliefSpec,
}

/// A part of the box given a material of its own, over the scene's and the material preset's:
/// what `--material tall=plastic:alpha=0.2`, a scene file's `[[scene.materials]]` and the
/// workbench's material editor set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartMaterial {
    pub part: BoxPart,
    pub kind: MaterialKind,
}

impl PartMaterial {
    /// The box's `materials` (the first of a scene's, in the order of [`cornell_box`]) with
    /// each of `parts` given its kind, found by the part's material name.
    pub fn apply(parts: &[PartMaterial], materials: &mut [Material]) {
        let box_materials = cornell_box().materials.len().min(materials.len());
        for p in parts {
            let name = p.part.material();
            if let Some(m) = materials[..box_materials]
                .iter_mut()
                .find(|m| m.name == name)
            {
                m.kind = p.kind;
            }
        }
    }

    /// Checks each part's parameters against their ranges ([`MaterialKind::check`]) and
    /// that no part is given twice; `field(i, name)` names the `i`th part's field `name` in
    /// the error (`part` for the part itself).
    pub fn validate(
        parts: &[PartMaterial],
        field: impl Fn(usize, &str) -> String,
    ) -> Result<(), SettingsError> {
        for (i, p) in parts.iter().enumerate() {
            p.kind.check(|f| field(i, f))?;
            if parts[..i].iter().any(|q| q.part == p.part) {
                return Err(SettingsError {
                    name: field(i, "part").into(),
                    value: format!("\"{}\"", p.part),
                    reason: "has a material already: give each part one",
                });
            }
        }
        Ok(())
    }
}

/// The models compiled into raylab, by the name a [`ModelSpec::file`] gives them.
pub const BUILT_IN_MODELS: [&str; 3] = ["bunny", "teapot", "textured-teapot"];

impl ModelSpec {
    /// A diffuse model at `placement`.
    pub fn new(file: impl Into<PathBuf>, placement: &Placement) -> Self {
        Self {
            file: file.into(),
            height: placement.height,
            floor_position: placement.floor_position,
            yaw: placement.yaw,
            reflectance: placement.reflectance,
            kind: MaterialKind::Diffuse,
            relief: ReliefSpec::default(),
        }
    }

    pub fn placement(&self) -> Placement {
        Placement {
            height: self.height,
            floor_position: self.floor_position,
            yaw: self.yaw,
            reflectance: self.reflectance,
        }
    }

    /// The built-in model this names, if any.
    pub fn built_in(&self) -> Option<&'static str> {
        let name = self.file.to_str()?;
        BUILT_IN_MODELS.into_iter().find(|b| *b == name)
    }

    /// The model's name: the built-in's, or the file's stem.
    pub fn name(&self) -> String {
        match self.built_in() {
            Some(name) => name.to_owned(),
            None => self
                .file
                .file_stem()
                .map_or_else(|| "model".to_owned(), |s| s.to_string_lossy().into_owned()),
        }
    }

    /// Reads the mesh and its maps: a warning for each part that could not be used.
    fn load(&self) -> Result<(Mesh, obj::Maps, Vec<String>), SceneError> {
        let none = obj::Maps::default();
        match self.built_in() {
            Some("bunny") => Ok((obj::builtin(obj::BUNNY_OBJ, "bunny")?, none, Vec::new())),
            Some("teapot") => Ok((obj::builtin(obj::TEAPOT_OBJ, "teapot")?, none, Vec::new())),
            Some(_) => obj::builtin_textured_mesh(
                obj::TEXTURED_TEAPOT_OBJ,
                obj::TEXTURED_TEAPOT_MTL,
                obj::TEXTURED_TEAPOT_PNG,
                "textured-teapot",
            ),
            None => obj::load_textured(&self.file),
        }
    }
}

/// What a scene load is doing, for a progress line.
pub type Progress<'a> = &'a (dyn Fn(&str) + Sync);

impl SceneSpec {
    /// The lab's Cornell box: room and blocks.
    pub fn cornell(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            room: true,
            blocks: true,
            models: Vec::new(),
            terrain: None,
            water: None,
            surfaces: Vec::new(),
        }
    }

    /// Checks the values a scene file may hold; errors name the field (`scene.models[0].height`).
    pub fn validate(&self) -> Result<(), SettingsError> {
        let bad = |name: String, value: String, reason: &'static str| SettingsError {
            name: name.into(),
            value,
            reason,
        };
        for (i, m) in self.models.iter().enumerate() {
            let field = |f: &str| format!("scene.models[{i}].{f}");
            crate::base::invalid::check_path(field("file"), &m.file)?;
            if !(m.height.is_finite() && m.height > 0.0 && m.height <= 2.0) {
                return Err(bad(
                    field("height"),
                    m.height.to_string(),
                    "must be in (0, 2]",
                ));
            }
            let [x, z] = m.floor_position;
            if !(x.abs() <= 1.0 && z.abs() <= 1.0) {
                let v = format!("[{x}, {z}]");
                return Err(bad(
                    field("floor_position"),
                    v,
                    "must be inside the box, in [−1, 1]",
                ));
            }
            if !m.yaw.is_finite() {
                return Err(bad(
                    field("yaw"),
                    m.yaw.to_string(),
                    "must be a finite number",
                ));
            }
            if !(m.reflectance.is_finite()
                && m.reflectance.min_element() >= 0.0
                && m.reflectance.max_element() <= 1.0)
            {
                let v = m.reflectance.to_string();
                return Err(bad(
                    field("reflectance"),
                    v,
                    "must be in [0, 1] in each channel",
                ));
            }
            m.kind.check(|f| field(&format!("material.{f}")))?;
            m.relief.validate(field)?;
        }
        for (i, part) in self.surfaces.iter().enumerate() {
            let field = |f: &str| format!("scene.surfaces[{i}].{f}");
            let name = format!("\"{}\"", part.part);
            if self.surfaces[..i].iter().any(|p| p.part == part.part) {
                return Err(bad(
                    field("part"),
                    name,
                    "has maps from an earlier [[scene.surfaces]] already: give each part one \
                     entry, with all its maps",
                ));
            }
            if !self.blocks && part.part.is_block() {
                return Err(bad(
                    field("part"),
                    name,
                    "is not in the scene: `blocks = false` leaves the blocks out (set \
                     `blocks = true`, or remove this surface)",
                ));
            }
            if !self.room && !part.part.is_block() {
                return Err(bad(
                    field("part"),
                    name,
                    "is not in the scene: `room = false` leaves the room out (set \
                     `room = true`, or remove this surface)",
                ));
            }
            part.relief.validate(field)?;
        }
        if let Some(w) = &self.water {
            w.validate()?;
        }
        if let Some(t) = &self.terrain {
            if !(1..=MAX_TERRAIN_GRID).contains(&t.grid) {
                return Err(bad(
                    "scene.terrain.grid".into(),
                    t.grid.to_string(),
                    "must be between 1 and 2048",
                ));
            }
            if !(t.height.is_finite() && t.height > 0.0 && t.height <= 2.0) {
                return Err(bad(
                    "scene.terrain.height".into(),
                    t.height.to_string(),
                    "must be in (0, 2]",
                ));
            }
            if !(1..=MAX_TERRAIN_OCTAVES).contains(&t.octaves) {
                return Err(bad(
                    "scene.terrain.octaves".into(),
                    t.octaves.to_string(),
                    "must be between 1 and 16",
                ));
            }
        }
        Ok(())
    }

    /// Roughly the most memory loading and building the scene takes, in bytes: nothing to
    /// speak of for the lab's box; 16 MiB a built-in model; for an OBJ file, 8 times its size,
    /// its material libraries and its largest texture ([`obj::memory_estimate`]), or 0 if it
    /// cannot be read (loading it fails anyway); 320 MiB for the default terrain's million
    /// triangles, in proportion to its triangle count for another grid. A file named by
    /// several models is counted once a model: each is loaded.
    pub fn memory_estimate(&self) -> u64 {
        let models: u64 = self
            .models
            .iter()
            .map(|m| match m.built_in() {
                Some(_) => 16 << 20,
                None => obj::memory_estimate(&m.file),
            } + m.relief.memory_estimate())
            .sum();
        let surfaces: u64 = self
            .surfaces
            .iter()
            .map(|s| s.relief.memory_estimate())
            .sum();
        let terrain = self.terrain.as_ref().map_or(0, |t| {
            let default = u64::from(TerrainSpec::default().grid).pow(2);
            (320u64 << 20) * u64::from(t.grid).pow(2) / default
        });
        models + surfaces + terrain
    }

    /// The files building the scene reads: each model's OBJ file with its material libraries
    /// and their textures ([`obj::files_read`]), and every normal and height map a model or a
    /// part of the box is given. What no output may replace
    /// ([`crate::base::inputs::refuse_output_onto`]).
    pub fn files_read(&self) -> Vec<Input> {
        let mut files = Vec::new();
        for m in &self.models {
            if m.built_in().is_none() {
                files.extend(obj::files_read(&m.file));
            }
            files.extend(
                m.relief
                    .files_read("a normal map of a model", "a height map of a model"),
            );
        }
        for s in &self.surfaces {
            files.extend(
                s.relief
                    .files_read("a normal map of the box", "a height map of the box"),
            );
        }
        files
    }

    /// Builds the scene and its acceleration structure (on the current rayon pool), with a
    /// warning for each model part that could not be used (a missing material library or
    /// texture). `cancelled` is asked between parts: a load given up returns
    /// [`SceneError::Cancelled`]. `progress` hears what is being done.
    pub fn build(
        &self,
        cancelled: &(dyn Fn() -> bool + Sync),
        progress: Progress<'_>,
    ) -> Result<(Scene, Vec<String>), SceneError> {
        let mut warnings = Vec::new();
        let mut models = Vec::with_capacity(self.models.len());
        for model in &self.models {
            if cancelled() {
                return Err(SceneError::Cancelled);
            }
            progress(&format!("reading {}", model.name()));
            let (mesh, maps, mut w) = model.load()?;
            warnings.append(&mut w);
            let mut material = Material::diffuse(model.name(), model.reflectance);
            material.kind = model.kind;
            if model.kind == MaterialKind::Diffuse {
                material.texture = maps.texture;
            }
            material.relief = match model.relief.load()? {
                Some(relief) => Some(relief),
                None => maps.relief,
            };
            models.push((mesh, model.placement(), material));
        }
        if cancelled() {
            return Err(SceneError::Cancelled);
        }
        if self.terrain.is_some() {
            progress("making the terrain");
        }
        let mut reliefs = Vec::with_capacity(self.surfaces.len());
        for part in &self.surfaces {
            reliefs.push((part.part.material(), part.relief.load()?));
        }
        let mut scene = assemble(
            self.room,
            self.blocks,
            &models,
            self.terrain.as_ref(),
            self.water.as_ref(),
            cancelled,
            progress,
        )?;
        // The box's materials come first, in the order of `cornell_box`.
        let box_materials = cornell_box().materials.len();
        for (name, relief) in reliefs {
            if let Some(m) = scene.materials[..box_materials]
                .iter_mut()
                .find(|m| m.name == name)
            {
                m.relief = relief;
            }
        }
        Ok((scene, warnings))
    }
}

/// The largest terrain grid a scene may ask for: 2 · 2048² ≈ 8.4 million triangles.
pub const MAX_TERRAIN_GRID: u32 = 2048;
/// The most octaves of terrain noise (finer ones are below a pixel at any allowed grid).
pub const MAX_TERRAIN_OCTAVES: u32 = 16;

/// The one place a scene's triangles are put together: the room (triangles 0–9 of
/// [`cornell_box`]), then the blocks (10–29), each model, the terrain and the water, with every material
/// of the box kept (so the room's material indices never change). Models and terrain carry
/// their corners' normals and texture coordinates; the room and blocks stay flat.
pub fn assemble(
    room: bool,
    blocks: bool,
    models: &[(Mesh, Placement, Material)],
    terrain: Option<&TerrainSpec>,
    water: Option<&WaterSpec>,
    cancelled: &(dyn Fn() -> bool + Sync),
    progress: Progress<'_>,
) -> Result<Scene, SceneError> {
    let lab = cornell_box();
    let mut materials = lab.materials;
    let mut triangles = Vec::new();
    if room {
        triangles.extend_from_slice(&lab.triangles[..ROOM_TRIANGLES]);
    }
    if blocks {
        triangles.extend_from_slice(&lab.triangles[ROOM_TRIANGLES..]);
    }
    let mut normals: Vec<Option<[Vec3; 3]>> = vec![None; triangles.len()];
    let mut uvs: Vec<Option<[Vec2; 3]>> = vec![None; triangles.len()];
    let mut any_uvs = false;
    for (mesh, placement, material) in models {
        materials.push(material.clone());
        let placed = obj::place_model(mesh, placement, (materials.len() - 1) as u32);
        let n = placed.triangles.len();
        triangles.extend(placed.triangles);
        normals.extend(placed.normals.into_iter().map(Some));
        match placed.uvs {
            Some(model_uvs) => {
                any_uvs = true;
                uvs.extend(model_uvs.into_iter().map(Some));
            }
            None => uvs.extend(std::iter::repeat_n(None, n)),
        }
    }
    if let Some(spec) = terrain {
        materials.push(terrain::terrain_material(spec));
        let material = (materials.len() - 1) as u32;
        terrain::extend_with_terrain(spec, material, &mut triangles, &mut normals);
        uvs.resize(triangles.len(), None);
    }
    if let Some(spec) = water {
        materials.push(water::water_material(spec));
        let material = (materials.len() - 1) as u32;
        triangles.extend(water::water_triangles(spec, material));
        normals.resize(triangles.len(), None);
        uvs.resize(triangles.len(), None);
    }
    if triangles.is_empty() {
        return Err(SceneError::Empty);
    }
    if cancelled() {
        return Err(SceneError::Cancelled);
    }
    progress(&format!(
        "building the BVH of {} triangles",
        triangles.len()
    ));
    let any_normals = normals.iter().any(Option::is_some);
    let normals = if any_normals { normals } else { Vec::new() };
    let uvs = if any_uvs { uvs } else { Vec::new() };
    Ok(Scene::new(triangles, materials).with_surface(normals, uvs))
}

/// Turns a relative model path into one relative to `folder` (a scene file's), leaving built-in
/// names and absolute paths alone.
pub fn resolve_models(spec: &mut SceneSpec, folder: &Path) {
    for m in &mut spec.models {
        if m.built_in().is_none() {
            m.file = resolve_path(&m.file, folder);
        }
    }
    for file in map_files(spec) {
        *file = resolve_path(file, folder);
    }
}

/// Every normal and height map's file a scene names, on models and on parts of the box.
fn map_files(spec: &mut SceneSpec) -> impl Iterator<Item = &mut PathBuf> {
    let models = spec.models.iter_mut().map(|m| &mut m.relief);
    let parts = spec.surfaces.iter_mut().map(|p| &mut p.relief);
    models.chain(parts).flat_map(ReliefSpec::files_mut)
}

/// The inverse of [`resolve_models`] for writing a scene file into `folder`: each model's path
/// as [`path_relative_to`] makes it, so the file and its models can be sent together and the
/// file names the same models from wherever it is read.
pub fn relative_models(spec: &mut SceneSpec, folder: &Path) {
    for m in &mut spec.models {
        if m.built_in().is_none() {
            m.file = path_relative_to(&m.file, folder);
        }
    }
    for file in map_files(spec) {
        *file = path_relative_to(file, folder);
    }
}

/// A path read from a file in `folder`: a relative one is relative to that folder, not to the
/// working folder of whoever reads it.
pub fn resolve_path(path: &Path, folder: &Path) -> PathBuf {
    if path.is_relative() {
        folder.join(path)
    } else {
        path.to_path_buf()
    }
}

/// `path` (as the program holds it: relative to the working folder, or absolute) as a file
/// written into `folder` holds it, so that [`resolve_path`] gives the same file back from
/// wherever the file is read: relative to `folder` when the two share more than the root
/// (`../models/m.obj`), else absolute.
///
/// Both are compared as the file system resolves them (symbolic links followed) when both
/// exist; otherwise as written, made absolute against the working folder (a model that is
/// missing stays missing, from the same place).
pub fn path_relative_to(path: &Path, folder: &Path) -> PathBuf {
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    let (path, folder) = match (std::fs::canonicalize(path), std::fs::canonicalize(folder)) {
        (Ok(p), Ok(f)) => (p, f),
        _ => match (std::path::absolute(path), std::path::absolute(folder)) {
            (Ok(p), Ok(f)) => (p, f),
            _ => return path.to_path_buf(),
        },
    };
    let p: Vec<_> = path.components().collect();
    let f: Vec<_> = folder.components().collect();
    let common = p.iter().zip(&f).take_while(|(a, b)| a == b).count();
    if common <= 1 || common == p.len() {
        // Nothing in common but the root, or the folder itself: as it is.
        return path;
    }
    let mut relative = PathBuf::new();
    for _ in common..f.len() {
        relative.push("..");
    }
    for c in &p[common..] {
        relative.push(c);
    }
    relative
}
// Scenes of one part: a model, or a terrain, in the lab's box. Here, above the parts' own
// modules, as every scene is put together by `assemble`.

/// The Cornell box with `mesh` standing in it. The model's triangles carry their corners'
/// normals and (when the file has them) texture coordinates; the box's own stay flat, the
/// lab's look.
pub fn model_in_box(mesh: &Mesh, placement: &Placement, name: &str) -> Scene {
    scene_with_model(
        mesh,
        placement,
        Material::diffuse(name, placement.reflectance),
    )
}

fn scene_with_model(mesh: &Mesh, placement: &Placement, material: Material) -> Scene {
    let models = [(mesh.clone(), *placement, material)];
    assemble(true, true, &models, None, None, &|| false, &|_| {}).expect("the box is never empty")
}

/// An OBJ file standing in the box at [`Placement::FRONT_LEFT`] (warnings dropped; see
/// [`obj_scene_with_warnings`]).
pub fn obj_scene(path: &Path) -> Result<Scene, SceneError> {
    obj_scene_with_warnings(path).map(|(scene, _)| scene)
}

/// An OBJ file standing in the box at [`Placement::FRONT_LEFT`], textured with its material's
/// diffuse texture (`map_Kd`) when it has one, and what went wrong on the way.
///
/// Material libraries and textures are found relative to the OBJ file's folder. A library or
/// image that cannot be read leaves the model untextured and adds a warning naming the file;
/// only the OBJ file itself failing is an error.
pub fn obj_scene_with_warnings(path: &Path) -> Result<(Scene, Vec<String>), SceneError> {
    let (mesh, maps, warnings) = obj::load_textured(path)?;
    let name = path
        .file_stem()
        .map_or_else(|| "model".to_string(), |s| s.to_string_lossy().into_owned());
    let scene = textured_scene(&mesh, &Placement::FRONT_LEFT, &name, maps);
    Ok((scene, warnings))
}

fn textured_scene(mesh: &Mesh, placement: &Placement, name: &str, maps: obj::Maps) -> Scene {
    let mut material = Material::diffuse(name, placement.reflectance);
    material.texture = maps.texture;
    material.relief = maps.relief;
    scene_with_model(mesh, placement, material)
}

/// A model compiled into the binary (`include_str!`/`include_bytes!`) standing in the box,
/// textured: its OBJ text, its material library's text (whatever name the OBJ's `mtllib`
/// gives), and the encoded image its material's `map_Kd` names. `name` names the model (its
/// material, and `assets/models/{name}.obj` in messages).
///
/// Like [`obj_scene_with_warnings`], an unusable library or image is a warning and the model
/// is untextured; bad OBJ text is an error.
pub fn builtin_textured(
    obj_text: &str,
    mtl_text: &str,
    texture_png: &[u8],
    name: &str,
    placement: &Placement,
) -> Result<(Scene, Vec<String>), SceneError> {
    let (mesh, maps, warnings) = obj::builtin_textured_mesh(obj_text, mtl_text, texture_png, name)?;
    Ok((textured_scene(&mesh, placement, name, maps), warnings))
}

/// The Cornell box with the blocks replaced by a terrain covering the floor, shaded smoothly
/// (the room's walls stay flat).
pub fn terrain_scene(spec: &TerrainSpec) -> Scene {
    let no = || false;
    assemble(true, false, &[], Some(spec), None, &no, &|_| {}).expect("the room alone is a scene")
}
