//! Scenes: triangles plus the materials they reference.
//!
//! The built-in scene is the lab's Cornell box ([`cornell_box`]); OBJ models standing in it
//! ([`obj`]) and a fractal terrain ([`terrain`]) produce the same [`Scene`] value. A
//! [`SceneChoice`] names any of them (`cornell`, `bunny`, `teapot`, `terrain`, or an OBJ file).

mod calibration;
mod cornell;
pub mod obj;
pub mod spec;
pub mod terrain;
pub mod water;

pub use calibration::{best_isa, calibration, workloads as calibration_workloads};
pub use cornell::{CORNELL_TRIANGLES, cornell_box, cornell_triangles};
pub use spec::{ModelSpec, SceneSpec};

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use glam::{Vec2, Vec3};

use crate::base::geometry::{Ray, Triangle};
use crate::shading::light;
pub use crate::shading::material::{Material, MaterialKind};
use crate::shading::relief::TangentFrame;
use crate::shading::texture::planar_uv;
use crate::shapes::accel::{Accel, AccelKind, Hit, HitLanes, Isa, SegmentLanes};
use crate::shapes::intersect::{self, Intersection};

/// Geometry and materials to trace. Every triangle's `material` indexes `materials`.
///
/// [`Scene::new`] builds the acceleration structure ([`Accel`]) that answers
/// [`Scene::closest_intersection`] and [`Scene::occluded`]. The fields stay public for reading;
/// to change the geometry, make a new scene (a scene whose triangle count no longer matches its
/// structure falls back to the brute-force loop rather than answer wrongly).
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    /// Per triangle, the normals at its three vertices that smooth shading interpolates
    /// ([`Scene::shading_normal`]), or `None` for a flat triangle (the lab's box). Empty when no
    /// triangle has them; else one entry per triangle.
    pub vertex_normals: Vec<Option<[Vec3; 3]>>,
    /// Per triangle, the texture coordinates of its three vertices ([`Scene::uv`]), or `None`.
    /// Empty when no triangle has them; else one entry per triangle.
    pub uvs: Vec<Option<[Vec2; 3]>>,
    accel: Accel,
    /// Per triangle, its [`crate::shading::light::edge_zones`], for [`Scene::approach_at_edge`].
    edge_zones: Vec<[f32; 3]>,
}

impl Scene {
    /// A scene with the acceleration structure that suits it (see [`Accel::new`]), built on the
    /// current rayon pool.
    pub fn new(triangles: Vec<Triangle>, materials: Vec<Material>) -> Self {
        Self::with_accel(triangles, materials, AccelKind::Auto, best_isa())
    }

    /// A scene with a chosen acceleration structure and kernels (benchmarks and tests compare
    /// them).
    pub fn with_accel(
        triangles: Vec<Triangle>,
        materials: Vec<Material>,
        kind: AccelKind,
        isa: Isa,
    ) -> Self {
        debug_assert!(
            triangles
                .iter()
                .all(|t| (t.material as usize) < materials.len())
        );
        let accel = Accel::build(&triangles, kind, isa);
        let edge_zones = triangles.iter().map(light::edge_zones).collect();
        Self {
            triangles,
            materials,
            vertex_normals: Vec::new(),
            uvs: Vec::new(),
            accel,
            edge_zones,
        }
    }

    /// [`light::approach_at_edge`] for a hit of triangle `index` at barycentric `(u, v)`, with
    /// the triangle's edge zones made once (it is asked at every diffuse hit).
    #[inline(always)]
    pub fn approach_at_edge(&self, index: usize, u: f32, v: f32, incoming: Vec3) -> Option<Vec3> {
        light::near_an_edge(self.edge_zones(index), u, v).then_some(incoming)
    }

    /// Triangle `index`'s [`light::edge_zones`], made once when the scene was.
    #[inline(always)]
    pub fn edge_zones(&self, index: usize) -> [f32; 3] {
        match self.edge_zones.get(index) {
            Some(zones) => *zones,
            None => self.edge_zones_of_a_new_triangle(index),
        }
    }

    /// [`Scene::edge_zones`] for a triangle added since the scene was made.
    #[cold]
    fn edge_zones_of_a_new_triangle(&self, index: usize) -> [f32; 3] {
        light::edge_zones(&self.triangles[index])
    }

    /// The same scene with per-vertex normals and texture coordinates (each empty, or one
    /// entry per triangle). They do not change the acceleration structure.
    pub fn with_surface(
        mut self,
        vertex_normals: Vec<Option<[Vec3; 3]>>,
        uvs: Vec<Option<[Vec2; 3]>>,
    ) -> Self {
        let n = self.triangles.len();
        assert!(vertex_normals.is_empty() || vertex_normals.len() == n);
        assert!(uvs.is_empty() || uvs.len() == n);
        self.vertex_normals = vertex_normals;
        self.uvs = uvs;
        self
    }

    /// The same geometry with another acceleration structure.
    pub fn rebuilt(self, kind: AccelKind, isa: Isa) -> Self {
        let (normals, uvs) = (self.vertex_normals, self.uvs);
        Self::with_accel(self.triangles, self.materials, kind, isa).with_surface(normals, uvs)
    }

    /// The normal to shade with at barycentric `(u, v)` of triangle `index`: the vertex normals
    /// interpolated, `normalize((1 − u − v)·n₀ + u·n₁ + v·n₂)` (smooth shading), when `smooth`
    /// and the triangle has them; else the triangle's own normal, exactly (the lab's flat
    /// shading).
    #[inline(always)]
    pub fn shading_normal(&self, index: usize, u: f32, v: f32, smooth: bool) -> Vec3 {
        let flat = self.triangles[index].normal;
        if !smooth {
            return flat;
        }
        match self.vertex_normals.get(index) {
            Some(Some([n0, n1, n2])) => {
                let n = (1.0 - u - v) * *n0 + u * *n1 + v * *n2;
                n.try_normalize().unwrap_or(flat)
            }
            _ => flat,
        }
    }

    /// The texture coordinates at barycentric `(u, v)` of triangle `index`, interpolated from
    /// its vertices', or `None` where it has none.
    #[inline(always)]
    pub fn uv(&self, index: usize, u: f32, v: f32) -> Option<Vec2> {
        match self.uvs.get(index) {
            Some(Some([t0, t1, t2])) => Some((1.0 - u - v) * *t0 + u * *t1 + v * *t2),
            _ => None,
        }
    }

    /// The tangent frame of triangle `index` about the shading normal `normal`
    /// ([`TangentFrame::new`]), from its corners' texture coordinates, or for a triangle
    /// without them, the planar projection [`planar_uv`] of its corners: the coordinates its
    /// hits are textured with either way.
    #[inline]
    pub fn tangent_frame(&self, index: usize, normal: Vec3) -> TangentFrame {
        let t = &self.triangles[index];
        let corners = [t.v0, t.v1, t.v2];
        let uvs = match self.uvs.get(index) {
            Some(Some(uvs)) => *uvs,
            _ => corners.map(|p| planar_uv(p, t.normal)),
        };
        TangentFrame::new(corners, uvs, normal)
    }

    /// The acceleration structure.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// The material of triangle `index`.
    pub fn material_of(&self, triangle_index: usize) -> &Material {
        &self.materials[self.triangles[triangle_index].material as usize]
    }

    /// The closest hit along `ray` with `t < t_max` (the lab's `ClosestIntersection`).
    ///
    /// Equal to [`intersect::closest_intersection_brute_force`], the lowest index winning ties.
    #[inline(always)]
    pub fn closest_intersection(&self, ray: &Ray, t_max: f32) -> Option<Intersection> {
        if !self.accel.built_for(self.triangles.len()) {
            return intersect::closest_intersection_brute_force(ray, &self.triangles, t_max);
        }
        let hit = self.accel.closest(&self.triangles, ray, t_max)?;
        Some(intersection(ray, hit))
    }

    /// [`Scene::closest_intersection`] for many rays at once: `out[i]` for `rays[i]`, the same
    /// answers, faster (see [`Accel::closest_batch`]). Inlined, so that the path tracer's
    /// vertex, compiled for the CPU, makes the `Intersection`s with its instruction set.
    #[inline]
    pub fn closest_intersections(
        &self,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Intersection>],
    ) {
        debug_assert_eq!(rays.len(), out.len());
        // Not through `closest_hits`: written that way, the path tracer's step (which calls
        // this) runs more instructions (count-instructions.sh path), the compiler no longer
        // fitting it together the same way. Same answers either way (tested).
        if !self.accel.built_for(self.triangles.len()) {
            for (ray, hit) in rays.iter().zip(out) {
                *hit = intersect::closest_intersection_brute_force(ray, &self.triangles, t_max);
            }
            return;
        }
        let mut hits = [None; 64];
        for (rays, out) in rays.chunks(64).zip(out.chunks_mut(64)) {
            let hits = &mut hits[..rays.len()];
            self.accel.closest_batch(&self.triangles, rays, t_max, hits);
            for ((ray, hit), o) in rays.iter().zip(hits.iter()).zip(out) {
                *o = hit.map(|hit| intersection(ray, hit));
            }
        }
    }

    /// [`Scene::closest_intersections`] as the structure answers, a [`Hit`] per ray (`t`, `u`,
    /// `v` and the triangle), each made an [`Intersection`] only where it is used
    /// ([`intersection`]). The lab's wave takes them in lanes instead
    /// ([`Scene::closest_hit_lanes`]).
    #[inline]
    pub fn closest_hits(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        debug_assert_eq!(rays.len(), out.len());
        if !self.accel.built_for(self.triangles.len()) {
            for (ray, hit) in rays.iter().zip(out) {
                *hit = intersect::closest_intersection_brute_force(ray, &self.triangles, t_max)
                    .map(|i| Hit {
                        index: i.triangle_index as u32,
                        t: i.distance,
                        u: i.u,
                        v: i.v,
                    });
            }
            return;
        }
        self.accel.closest_batch(&self.triangles, rays, t_max, out);
    }

    /// [`Scene::closest_hits`] into lanes ([`Accel::closest_lanes`]): lane `i` of `out[g]` is
    /// `rays[16g + i]`'s hit.
    pub fn closest_hit_lanes(&self, rays: &[Ray], t_max: f32, out: &mut [HitLanes]) {
        debug_assert_eq!(rays.len().div_ceil(16), out.len());
        if !self.accel.built_for(self.triangles.len()) {
            // Triangles added since the structure was built: `closest_hits`' loop over them.
            let mut hits = [None; 16];
            for (rays, out) in rays.chunks(16).zip(out) {
                let hits = &mut hits[..rays.len()];
                self.closest_hits(rays, t_max, hits);
                *out = HitLanes::of(hits, t_max);
            }
            return;
        }
        self.accel.closest_lanes(&self.triangles, rays, t_max, out);
    }

    /// [`Scene::occluded_many`] for shadow rays given as lanes, sixteen a group (as the lab's
    /// shading makes them): bit `i` of `blocked[g]` set when lane `i` of `groups[g]` is cast
    /// and blocked. The same answers, without copying the rays into an array first where the
    /// structure can take lanes ([`Accel::occluded_lanes`], which says what `neighbours` is).
    pub fn occluded_lanes(&self, groups: &[SegmentLanes], neighbours: bool, blocked: &mut [u16]) {
        if !self.accel.built_for(self.triangles.len()) {
            for (g, blocked) in groups.iter().zip(blocked) {
                *blocked = 0;
                for i in (0..16).filter(|&i| g.cast & (1 << i) != 0) {
                    let (ray, t_max) = g.ray(i);
                    if intersect::occluded_brute_force(&ray, &self.triangles, t_max) {
                        *blocked |= 1 << i;
                    }
                }
            }
            return;
        }
        self.accel
            .occluded_lanes(&self.triangles, groups, neighbours, blocked);
    }

    /// [`Scene::occluded`] for many shadow rays at once, each with its own `t_max`.
    pub fn occluded_many(&self, rays: &[(Ray, f32)], out: &mut [bool]) {
        if !self.accel.built_for(self.triangles.len()) {
            for ((ray, t_max), blocked) in rays.iter().zip(out) {
                *blocked = intersect::occluded_brute_force(ray, &self.triangles, *t_max);
            }
            return;
        }
        self.accel.occluded_batch(&self.triangles, rays, out);
    }

    /// Whether anything lies along `ray` with `t < t_max` (a shadow ray's question).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if !self.accel.built_for(self.triangles.len()) {
            return intersect::occluded_brute_force(ray, &self.triangles, t_max);
        }
        self.accel.occluded(&self.triangles, ray, t_max)
    }
}

/// The intersection an acceleration structure's hit stands for along `ray`: its point
/// `ray.at(t)`, the rest as the structure found it.
#[inline(always)]
pub fn intersection(ray: &Ray, hit: Hit) -> Intersection {
    Intersection {
        position: ray.at(hit.t),
        distance: hit.t,
        triangle_index: hit.index as usize,
        u: hit.u,
        v: hit.v,
    }
}

/// A scene by name: what the command line's `--scene`/`--obj` and the workbench's scene
/// selector choose from.
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SceneChoice {
    /// The lab's Cornell box (30 triangles).
    #[default]
    Cornell,
    /// The Stanford bunny (3,674 triangles) standing in the box.
    Bunny,
    /// The Utah teapot (992 triangles) standing in the box.
    Teapot,
    /// The Utah teapot with texture coordinates and a blue-and-white porcelain texture
    /// (assets/models/teapot-textured.obj), smooth-shaded.
    #[serde(rename = "textured-teapot")]
    TexturedTeapot,
    /// A fractal terrain of about a million triangles covering the box's floor.
    Terrain,
    /// The lab's box with its floor under clear water 0.3 deep, its surface rippled by
    /// fractal waves ([`water`]).
    Pool,
    /// Any OBJ file, standing in the box.
    Obj(PathBuf),
    /// A scene of its own parts, as a scene file describes it ([`crate::files::scene_file`]).
    Custom(Box<SceneSpec>),
}

impl SceneChoice {
    /// The built-in scenes, by name.
    pub const BUILT_IN: [SceneChoice; 6] = [
        SceneChoice::Cornell,
        SceneChoice::Bunny,
        SceneChoice::Teapot,
        SceneChoice::TexturedTeapot,
        SceneChoice::Terrain,
        SceneChoice::Pool,
    ];

    /// The name: `cornell`, `bunny`, `teapot`, `terrain`, the OBJ file's name, or a custom
    /// scene's.
    pub fn name(&self) -> String {
        match self {
            SceneChoice::Cornell => "cornell".into(),
            SceneChoice::Bunny => "bunny".into(),
            SceneChoice::Teapot => "teapot".into(),
            SceneChoice::TexturedTeapot => "textured-teapot".into(),
            SceneChoice::Terrain => "terrain".into(),
            SceneChoice::Pool => "pool".into(),
            SceneChoice::Obj(path) => path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            SceneChoice::Custom(spec) => spec.name.clone(),
        }
    }

    /// The label in the workbench's scene selector.
    pub fn label(&self) -> String {
        match self {
            SceneChoice::Cornell => "Cornell box (the lab)".to_owned(),
            SceneChoice::Bunny => "Stanford bunny".to_owned(),
            SceneChoice::Teapot => "Utah teapot".to_owned(),
            SceneChoice::TexturedTeapot => "Textured teapot (porcelain)".to_owned(),
            SceneChoice::Terrain => "Fractal terrain (1M triangles)".to_owned(),
            SceneChoice::Pool => "Pool of water (waves)".to_owned(),
            SceneChoice::Obj(_) => format!("OBJ: {self}"),
            SceneChoice::Custom(_) => format!("Scene: {self}"),
        }
    }

    /// The parts the scene is made of: every choice is built from its spec
    /// ([`SceneSpec::build`]).
    pub fn spec(&self) -> SceneSpec {
        let with_model = |name: &str, model: ModelSpec| SceneSpec {
            models: vec![model],
            ..SceneSpec::cornell(name)
        };
        match self {
            SceneChoice::Cornell => SceneSpec::cornell("cornell"),
            SceneChoice::Bunny => with_model(
                "bunny",
                ModelSpec::new("bunny", &obj::Placement::FRONT_LEFT),
            ),
            SceneChoice::Teapot => {
                with_model("teapot", ModelSpec::new("teapot", &obj::Placement::TEAPOT))
            }
            SceneChoice::TexturedTeapot => with_model(
                "textured-teapot",
                ModelSpec::new("textured-teapot", &obj::Placement::TEAPOT),
            ),
            SceneChoice::Terrain => SceneSpec {
                blocks: false,
                terrain: Some(terrain::TerrainSpec::default()),
                ..SceneSpec::cornell("terrain")
            },
            SceneChoice::Pool => SceneSpec {
                water: Some(water::WaterSpec::default()),
                ..SceneSpec::cornell("pool")
            },
            SceneChoice::Obj(path) => with_model(
                &self.name(),
                ModelSpec::new(path.clone(), &obj::Placement::FRONT_LEFT),
            ),
            SceneChoice::Custom(spec) => (**spec).clone(),
        }
    }

    /// The choice a spec is: a built-in scene or an OBJ model in the box when it is one of
    /// those exactly (whatever its name), else a custom scene.
    pub fn from_spec(spec: SceneSpec) -> SceneChoice {
        let same = |choice: &SceneChoice| {
            SceneSpec {
                name: spec.name.clone(),
                ..choice.spec()
            } == spec
        };
        if let Some(built_in) = SceneChoice::BUILT_IN.into_iter().find(same) {
            return built_in;
        }
        if let [model] = &spec.models[..]
            && model.built_in().is_none()
        {
            let obj = SceneChoice::Obj(model.file.clone());
            if same(&obj) && spec.name == obj.name() {
                return obj;
            }
        }
        SceneChoice::Custom(Box::new(spec))
    }

    /// Roughly the most memory loading and building the scene takes, in bytes
    /// ([`SceneSpec::memory_estimate`]).
    pub fn memory_estimate(&self) -> u64 {
        self.spec().memory_estimate()
    }

    /// The files loading the scene reads ([`SceneSpec::files_read`]).
    pub fn files_read(&self) -> Vec<crate::base::inputs::Input> {
        self.spec().files_read()
    }

    /// Builds the scene and its acceleration structure (on the current rayon pool).
    pub fn load(&self) -> Result<Scene, SceneError> {
        self.load_with_warnings().map(|(scene, _)| scene)
    }

    /// [`SceneChoice::load`], with what could not be used on the way (a model's missing
    /// texture).
    pub fn load_with_warnings(&self) -> Result<(Scene, Vec<String>), SceneError> {
        self.load_with(&|| false, &|_| {})
    }

    /// [`SceneChoice::load_with_warnings`], asking `cancelled` between the parts of the work
    /// and telling `progress` what is being done (the workbench's loading line and Cancel).
    pub fn load_with(
        &self,
        cancelled: &(dyn Fn() -> bool + Sync),
        progress: spec::Progress<'_>,
    ) -> Result<(Scene, Vec<String>), SceneError> {
        self.spec().build(cancelled, progress)
    }
}

impl fmt::Display for SceneChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl FromStr for SceneChoice {
    type Err = String;

    /// A built-in scene's name (an OBJ file is chosen with [`SceneChoice::Obj`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        SceneChoice::BUILT_IN
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                crate::base::named::unknown("scene", s, SceneChoice::BUILT_IN.map(|c| c.name()))
            })
    }
}

/// Why a scene could not be made; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("could not read OBJ file '{}': {reason}", path.display())]
    Read { path: PathBuf, reason: String },
    #[error("could not load OBJ file '{}': {reason}", path.display())]
    Obj { path: PathBuf, reason: String },
    #[error("OBJ file '{}' has no triangles", path.display())]
    EmptyMesh { path: PathBuf },
    #[error("the scene has no triangles (no room, blocks, model or terrain)")]
    Empty,
    #[error("loading the scene was cancelled")]
    Cancelled,
    /// A normal or height map a scene file names could not be read: `what` it is, the file,
    /// and why.
    #[error("could not load the {what} '{name}': {reason}")]
    Map {
        what: &'static str,
        name: String,
        reason: String,
    },
}

impl SceneError {
    /// The error of a map (`decoding` says which kind) that could not be loaded.
    pub fn map(
        decoding: crate::shading::texture::Decoding,
        e: crate::shading::texture::TextureError,
    ) -> Self {
        SceneError::Map {
            what: decoding.what(),
            name: e.name,
            reason: e.reason,
        }
    }
}

/// Whether the segment from a surface point to the light is blocked (lab section 5.1): a shadow
/// ray is cast toward the light and any hit closer than the light shadows the point. `at_edge`:
/// see [`light::shadow_ray`].
pub fn in_shadow(
    scene: &Scene,
    light: &light::LightSpec,
    position: Vec3,
    normal: Vec3,
    at_edge: Option<Vec3>,
) -> bool {
    light::shadow_ray(light, position, normal, at_edge)
        .is_some_and(|(ray, t_max)| scene.occluded(&ray, t_max))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `scene` with a triangle added after its structure was built: its queries fall back on
    /// the brute-force loop.
    fn grown(scene: &Scene) -> Scene {
        let mut grown = scene.clone();
        grown.triangles.push(Triangle::new(
            Vec3::new(-0.2, -0.2, 0.0),
            Vec3::new(0.2, -0.2, 0.0),
            Vec3::new(0.0, 0.2, 0.0),
            0,
        ));
        grown
    }

    /// The hits in lanes are the hits one ray at a time, with the structure and, once
    /// triangles are added after it was built, without it; a partial last group's other lanes
    /// hold none.
    #[test]
    fn closest_hit_lanes_are_the_closest_hits() {
        let scene = cornell::cornell_box();
        let settings = crate::test_support::lab_settings(37, 29);
        let rays = crate::test_support::primary_rays(&settings.camera);
        let grown = grown(&scene);
        for scene in [&scene, &grown] {
            let mut hits = vec![None; rays.len()];
            scene.closest_hits(&rays, f32::INFINITY, &mut hits);
            for batch in 0..rays.len().div_ceil(64) {
                let rays = &rays[batch * 64..rays.len().min(batch * 64 + 64)];
                let hits = &hits[batch * 64..batch * 64 + rays.len()];
                let mut lanes = [HitLanes::new(0.0); 4];
                let lanes = &mut lanes[..rays.len().div_ceil(16)];
                scene.closest_hit_lanes(rays, f32::INFINITY, lanes);
                for (k, lane) in (0..16 * lanes.len()).map(|k| (k, &lanes[k / 16])) {
                    assert_eq!(lane.get(k % 16), hits.get(k).copied().flatten(), "{k}");
                }
            }
        }
    }

    /// The lab's wave takes the structure's hits and makes each `Intersection` itself: the
    /// same intersections, bit for bit, as `closest_intersection` one ray at a time, through
    /// the structure and through the brute-force loop a scene falls back on when triangles were
    /// added after it was built.
    #[test]
    fn closest_hits_make_the_intersections_closest_intersection_finds() {
        let scene = cornell::cornell_box();
        let settings = crate::test_support::lab_settings(64, 64);
        let rays = crate::test_support::primary_rays(&settings.camera);
        let grown = grown(&scene);
        assert!(!grown.accel.built_for(grown.triangles.len()));
        for scene in [&scene, &grown] {
            let mut hits = vec![None; rays.len()];
            scene.closest_hits(&rays, f32::INFINITY, &mut hits);
            let mut found = 0;
            for (ray, hit) in rays.iter().zip(&hits) {
                let one = scene.closest_intersection(ray, f32::INFINITY);
                assert_eq!(hit.map(|hit| intersection(ray, hit)), one);
                found += usize::from(one.is_some());
            }
            assert_eq!(
                found,
                rays.len(),
                "every ray of the default view hits the box"
            );
        }
    }

    #[test]
    fn scene_choices_parse_name_and_round_trip_through_json() {
        for c in SceneChoice::BUILT_IN {
            assert_eq!(c.name().parse::<SceneChoice>(), Ok(c.clone()));
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(serde_json::from_str::<SceneChoice>(&json).unwrap(), c);
        }
        assert!(
            "dragon"
                .parse::<SceneChoice>()
                .unwrap_err()
                .contains("dragon")
        );
        let obj = SceneChoice::Obj(PathBuf::from("/models/dragon.obj"));
        assert_eq!(obj.name(), "dragon.obj");
        let json = serde_json::to_string(&obj).unwrap();
        assert_eq!(serde_json::from_str::<SceneChoice>(&json).unwrap(), obj);
        assert_eq!(SceneChoice::default(), SceneChoice::Cornell);
    }

    #[test]
    fn a_missing_obj_file_is_an_error_naming_it() {
        let e = SceneChoice::Obj(PathBuf::from("/no/such/dir/x.obj"))
            .load()
            .unwrap_err();
        assert!(e.to_string().contains("/no/such/dir/x.obj"), "{e}");
    }
}
