//! The options that determine an image (`RenderOptions`, shared by `render`, `inspect` and
//! `check`) and the [`RenderSettings`] they make, checked; a settings file read in their place.

use std::path::PathBuf;

use super::parse::{
    Bounces, Indirect, parse_bounces, parse_colour, parse_degrees, parse_exposure, parse_finite,
    parse_indirect, parse_non_negative, parse_on_off, parse_part_material, parse_positive,
    parse_samples, parse_side, parse_vec3, part_material_help,
};
use super::terminal::print_error_line;
use clap::Args;
use glam::Vec3;
use raylab_core::shading::light::{LightKind, LightShape, ParamValue};
use raylab_core::shading::material::TexturePreset;
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::shapes::scene::spec::PartMaterial;
use raylab_core::transport::display::{Display, DisplayTransform};
use raylab_core::transport::integrator::{DEFAULT_SPECULAR_DEPTH, MAX_SPECULAR_DEPTH};
use raylab_core::transport::settings::{Caustics, DEFAULT_PHOTONS, MAX_PHOTONS};
use raylab_core::{Camera, MaterialPreset, RenderSettings, Shading, Stage};

/// The image's width and height when not given: the lab's 512 × 512 figures.
pub(super) const DEFAULT_SIDE: u32 = 512;

/// The options that set what a file given with `--settings` or `--scene-file` holds: either
/// file takes them all, so none combines with it.
pub(super) const SETTINGS_OPTIONS: [&str; 39] = [
    "scene",
    "obj",
    "stage",
    "width",
    "height",
    "focal",
    "camera",
    "yaw",
    "pitch",
    "light",
    "light_power",
    "indirect",
    "shadows",
    "samples",
    "seed",
    "bounces",
    "material_preset",
    "roughness",
    "material",
    "specular_depth",
    "caustics",
    "photons",
    "texture_preset",
    "smooth",
    "parallax_shadows",
    "light_radius",
    "light_shape",
    "light_size",
    "light_colour",
    "light_aim",
    "spot_cutoff",
    "spot_beam",
    "light_kind",
    "aperture",
    "focus_distance",
    "display",
    "exposure",
    "water_waves",
    "water_time",
];

/// What determines an image, shared by `render` and `inspect` (which explains a pixel of the
/// very image `render` would write with the same options).
#[derive(Clone, Debug, Args)]
pub struct RenderOptions {
    /// Take every setting from a file: a workbench screenshot (its .png, which carries them,
    /// or the .json beside it, either reproducing the screenshot exactly), a bare settings
    /// JSON object, or a scene file (.toml). Only --out, --pixel, --json, --threads, --view
    /// and --save-scene combine with it.
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with = "scene_file",
        conflicts_with_all = SETTINGS_OPTIONS
    )]
    pub settings: Option<PathBuf>,
    /// Take the scene and every setting from a scene file (.toml; see assets/scenes/). Only
    /// --out, --pixel, --json, --threads, --view and --save-scene combine with it.
    #[arg(
        long,
        value_name = "FILE.toml",
        conflicts_with_all = SETTINGS_OPTIONS
    )]
    pub scene_file: Option<PathBuf>,
    /// Scene: cornell, bunny, teapot, textured-teapot, terrain or pool.
    #[arg(
        long,
        default_value = "cornell",
        value_name = "NAME",
        conflicts_with = "obj"
    )]
    pub scene: SceneChoice,
    /// An OBJ file to stand in the Cornell box instead of a built-in scene.
    #[arg(long, value_name = "FILE")]
    pub obj: Option<PathBuf>,
    /// Stage: flat (fig. 2), incoming (fig. 3), direct (fig. 5), shadows (fig. 6), lab (fig. 7),
    /// or path (path tracing: real indirect light in place of N).
    #[arg(long, default_value = "lab", value_name = "STAGE")]
    pub stage: Stage,
    /// Path stage: the most diffuse bounces per path, or "unlimited" (Russian roulette ends
    /// paths); 0 is direct light only.
    #[arg(long, default_value = "unlimited", value_parser = parse_bounces, value_name = "B|unlimited")]
    pub bounces: Bounces,
    /// Mirror, glass, rough metal and plastic: none (the lab's diffuse box), mirror (the tall
    /// block is a mirror of reflectance 0.9), glass (the short block is clear glass, index 1.5),
    /// both, rough (the tall block is a rough metal of reflectance 0.9, roughness --roughness)
    /// or plastic (the tall block is a glossy plastic: its blue under a clear coating of index
    /// 1.5, roughness --roughness).
    #[arg(long, default_value = "none", value_name = "PRESET")]
    pub material_preset: MaterialPreset,
    /// The rough metal's or the plastic coating's GGX roughness α, from 0.01 (nearly a mirror)
    /// to 1 [default: 0.2 for the metal, 0.1 for the plastic].
    #[arg(long, value_parser = parse_finite, value_name = "A", allow_hyphen_values = true)]
    pub roughness: Option<f32>,
    /// A part of the box given a material of its own, over --material-preset (repeatable):
    /// PART=KIND[:FIELD=VALUE,…], e.g. tall=plastic:alpha=0.2,int_ior=1.5
    #[arg(
        long,
        value_parser = parse_part_material,
        value_name = "PART=KIND[:FIELD=V,…]",
        long_help = part_material_help()
    )]
    pub material: Vec<PartMaterial>,
    /// Textures: none (the lab's plain colours), checker-floor (a checkerboard floor),
    /// grid-walls (grid lines on the walls and ceiling), both, clouds (fBm clouds on the
    /// ceiling), bumpy-walls (a normal map of rounded bricks on the back and side walls) or
    /// parallax-floor (checkerboard tiles with grout, carved by parallax occlusion mapping).
    #[arg(long, default_value = "none", value_name = "PRESET")]
    pub texture_preset: TexturePreset,
    /// The pool's waves: their amplitude in scene units (0: still water) [default: 0.01].
    /// Needs a scene with water (--scene pool, or a scene file's [scene.water]).
    #[arg(long, value_parser = parse_non_negative, value_name = "A", allow_hyphen_values = true)]
    pub water_waves: Option<f32>,
    /// The pool's waves at time T, in seconds (each octave drifts its own way) [default: 0].
    #[arg(long, value_parser = parse_non_negative, value_name = "T", allow_hyphen_values = true)]
    pub water_time: Option<f32>,
    /// Smooth shading of models (interpolated vertex normals); the box stays flat either way.
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub smooth: bool,
    /// Parallax self-shadowing: where a height map carves a surface (--texture-preset
    /// parallax-floor, a scene file's height_map), its relief hides the light from the points
    /// behind it. Off: the carved surface is lit as if nothing stood in the way.
    #[arg(long, default_value = "on", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub parallax_shadows: bool,
    /// Lab stages: how many mirror and glass hits in a row are followed (Whitted-style).
    #[arg(long, default_value_t = DEFAULT_SPECULAR_DEPTH, value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_SPECULAR_DEPTH)), value_name = "D")]
    pub specular_depth: u32,
    /// Path stage: caustics (light through mirror and glass onto diffuse surfaces) by a photon
    /// map each pass (photons), or the path tracer alone (off), which never finds the lab's
    /// point light through mirror or glass.
    #[arg(long, default_value = "off", value_name = "off|photons")]
    pub caustics: Caustics,
    /// Path stage with --caustics photons: photons shot from the light each pass
    /// [default: 100000].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_PHOTONS)), value_name = "N")]
    pub photons: Option<u32>,
    /// Image width in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "W")]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "H")]
    pub height: u32,
    /// Focal length in pixels [default: the width, a 53.13° horizontal field of view].
    #[arg(long, value_parser = parse_positive, value_name = "F", allow_hyphen_values = true)]
    pub focal: Option<f32>,
    /// Camera position [default: 0,0,-3.001].
    #[arg(long, value_parser = parse_vec3, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub camera: Option<Vec3>,
    /// Camera yaw in degrees; positive turns right.
    #[arg(long, default_value_t = 0.0, value_parser = parse_degrees, value_name = "DEG", allow_hyphen_values = true)]
    pub yaw: f64,
    /// Camera pitch in degrees; positive looks up.
    #[arg(long, default_value_t = 0.0, value_parser = parse_degrees, value_name = "DEG", allow_hyphen_values = true)]
    pub pitch: f64,
    /// Light position [default: 0,-0.5,-0.7].
    #[arg(long, value_parser = parse_vec3, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub light: Option<Vec3>,
    /// Light power in watts [default: 14]; each channel gets the power times the colour.
    #[arg(long, value_parser = parse_non_negative, value_name = "P", allow_hyphen_values = true)]
    pub light_power: Option<f32>,
    /// Light colour, each channel ≥ 0 [default: 1,1,1, white].
    #[arg(long, value_parser = parse_colour, value_name = "R,G,B", allow_hyphen_values = true)]
    pub light_colour: Option<Vec3>,
    /// Light shape: point (the lab's), sphere (radius --light-size), quad (a square of side
    /// --light-size under the light's position, facing the floor), each of the same power; or
    /// spot (the point light's intensity P/4π inside a cone: --light-aim, --spot-cutoff,
    /// --spot-beam).
    #[arg(long, value_name = "point|sphere|quad|spot")]
    pub light_shape: Option<LightShape>,
    /// The point a spot light is aimed at (--light-shape spot) [default: 0,1,-0.2, the floor
    /// in front of the blocks].
    #[arg(long, value_parser = parse_vec3, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub light_aim: Option<Vec3>,
    /// A spot light's cutoff angle in degrees, from its axis: no light beyond it; above 0 and
    /// below 90 [default: 25].
    #[arg(long, value_parser = parse_degrees, value_name = "DEG", allow_hyphen_values = true)]
    pub spot_cutoff: Option<f64>,
    /// A spot light's beam width in degrees: full intensity within it, falling linearly in
    /// the angle to 0 at the cutoff; from 0 to the cutoff [default: 15].
    #[arg(long, value_parser = parse_degrees, value_name = "DEG", allow_hyphen_values = true)]
    pub spot_beam: Option<f64>,
    /// The area light's size: the sphere's radius or the quad's side [default: 0.1 for a
    /// sphere, 0.5 for a quad].
    #[arg(long, value_parser = parse_non_negative, value_name = "S", allow_hyphen_values = true, conflicts_with = "light_radius")]
    pub light_size: Option<f32>,
    /// A sphere light of radius R (--light-shape sphere --light-size R), for soft shadows; 0 is
    /// the lab's point light.
    #[arg(long, value_parser = parse_non_negative, value_name = "R", allow_hyphen_values = true, conflicts_with = "light_shape")]
    pub light_radius: Option<f32>,
    /// The light's kind and its parameters in one: KIND, then optionally `:` and FIELD=V
    /// pairs, a point's three coordinates separated by commas, angles in degrees (`--light-kind
    /// sphere:radius=0.2`, `--light-kind spot:aim=0,1,0,cutoff=30,beam=20`); fields not given
    /// keep their defaults. In place of --light-shape and the flags of its parameters.
    #[arg(long, value_parser = LightKind::parse, value_name = "KIND:FIELD=V,…", conflicts_with_all = ["light_shape", "light_size", "light_radius", "light_aim", "spot_cutoff", "spot_beam"])]
    pub light_kind: Option<LightKind>,
    /// Lens aperture radius, for depth of field; 0 is the lab's pinhole (all sharp).
    #[arg(long, default_value_t = 0.0, value_parser = parse_non_negative, value_name = "A", allow_hyphen_values = true)]
    pub aperture: f32,
    /// Distance to the plane in focus, along the view direction [default: 3.001, the box's
    /// centre from the default camera].
    #[arg(long, value_parser = parse_positive, value_name = "D", allow_hyphen_values = true)]
    pub focus_distance: Option<f32>,
    /// Display transform for PNG output: lab (clamp, no gamma: the lab's figures), srgb, or
    /// filmic (ACES fit, highlights roll off). EXR output is linear whatever it is.
    #[arg(long, default_value = "lab", value_name = "lab|srgb|filmic")]
    pub display: DisplayTransform,
    /// Exposure in stops, before the display transform (PNG only): +1 doubles every value.
    #[arg(long, default_value_t = 0.0, value_parser = parse_exposure, value_name = "EV", allow_hyphen_values = true)]
    pub exposure: f32,
    /// Constant indirect light N, or "off" [default: 0.5 for the lab stage, off for the others].
    #[arg(long, value_parser = parse_indirect, value_name = "N|off", allow_hyphen_values = true)]
    pub indirect: Option<Indirect>,
    /// Shadow rays [default: on for the shadows and lab stages].
    #[arg(long, value_parser = parse_on_off, value_name = "on|off")]
    pub shadows: Option<bool>,
    /// Samples per pixel; more than 1 jitters within the pixel (anti-aliasing).
    #[arg(long, default_value_t = 1, value_parser = parse_samples)]
    pub samples: u32,
    /// Seed for the sample jitter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Render threads, 1 to 1024 [default: one per core, or RAYON_NUM_THREADS up to 4 a
    /// core].
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024), value_name = "N")]
    pub threads: Option<u16>,
}

impl RenderOptions {
    /// The scene these arguments choose.
    pub fn scene_choice(&self) -> SceneChoice {
        match &self.obj {
            Some(path) => SceneChoice::Obj(path.clone()),
            None => self.scene.clone(),
        }
    }

    /// The settings to render: from `--settings FILE`, `--scene-file FILE.toml`, or from the
    /// other arguments. What a settings file held that raylab does not know is printed as a
    /// warning.
    pub fn resolve_settings(&self) -> anyhow::Result<RenderSettings> {
        if let Some(path) = &self.scene_file {
            return Ok(raylab_core::files::scene_file::load(path)?);
        }
        if (self.water_waves.is_some() || self.water_time.is_some())
            && self.scene_choice().spec().water.is_none()
        {
            anyhow::bail!(
                "--water-waves and --water-time need a scene with water (--scene pool, or a scene \
                 file with [scene.water]); '{}' has none",
                self.scene_choice().name()
            );
        }
        match &self.settings {
            Some(path) => read_settings_file(path),
            None => {
                self.check_caustics()?;
                self.check_light()?;
                Ok(self.settings())
            }
        }
    }

    /// The spot's options only with `--light-shape spot`, and a size only for a sphere or a
    /// square: elsewhere they would do nothing, without a word.
    fn check_light(&self) -> anyhow::Result<()> {
        let spot = self.light_shape == Some(LightShape::Spot);
        let given = [
            ("--light-aim", self.light_aim.is_some()),
            ("--spot-cutoff", self.spot_cutoff.is_some()),
            ("--spot-beam", self.spot_beam.is_some()),
        ];
        if let (false, Some((flag, _))) = (spot, given.iter().find(|(_, is)| *is)) {
            anyhow::bail!(
                "{flag} sets a spot light's cone: it needs --light-shape spot (the light is {})",
                self.light_shape.unwrap_or_default()
            );
        }
        if let (Some(shape @ (LightShape::Point | LightShape::Spot)), Some(size)) =
            (self.light_shape, self.light_size)
            && !(shape == LightShape::Point && size == 0.0)
        {
            anyhow::bail!(
                "--light-size {size}: a {shape} light has no size (--light-shape sphere or \
                 quad have one)"
            );
        }
        Ok(())
    }

    /// `--caustics photons` only in the path stage, and `--photons` only with it: elsewhere
    /// they would do nothing, without a word.
    fn check_caustics(&self) -> anyhow::Result<()> {
        if self.caustics == Caustics::Photons && self.stage != Stage::Path {
            anyhow::bail!(
                "--caustics photons needs --stage path: the path tracer gathers the photons, \
                 while the lab's stage '{}' follows mirror and glass by Whitted's rule and \
                 shoots none",
                self.stage
            );
        }
        if self.photons.is_some() && self.caustics != Caustics::Photons {
            anyhow::bail!(
                "--photons sets how many photons --caustics photons shoots (with --stage path); \
                 without --caustics photons it does nothing"
            );
        }
        Ok(())
    }

    /// The settings the arguments other than `--settings` describe.
    pub fn settings(&self) -> RenderSettings {
        let mut camera = Camera::default_for(self.width, self.height);
        if let Some(f) = self.focal {
            camera.focal_length = f;
        }
        if let Some(p) = self.camera {
            camera.position = p;
        }
        camera.yaw = raylab_core::base::camera::radians(self.yaw);
        camera.pitch = raylab_core::base::camera::radians(self.pitch);
        camera.aperture = self.aperture;
        if let Some(d) = self.focus_distance {
            camera.focus_distance = d;
        }
        let mut scene = self.scene_choice();
        if self.water_waves.is_some() || self.water_time.is_some() {
            let mut spec = scene.spec();
            if let Some(water) = &mut spec.water {
                water.waves = self.water_waves.unwrap_or(water.waves);
                water.time = self.water_time.unwrap_or(water.time);
                scene = SceneChoice::from_spec(spec);
            }
        }
        let mut settings = RenderSettings {
            scene,
            camera,
            shading: Shading {
                bounces: self.bounces.0,
                specular_depth: self.specular_depth,
                smooth: self.smooth,
                parallax_shadows: self.parallax_shadows,
                caustics: self.caustics,
                photons: self.photons.unwrap_or(DEFAULT_PHOTONS),
                ..Shading::for_stage(self.stage)
            },
            material_preset: self.material_preset,
            roughness: self
                .roughness
                .unwrap_or(self.material_preset.default_roughness()),
            part_materials: self.material.clone(),
            texture_preset: self.texture_preset,
            display: Display {
                transform: self.display,
                exposure: self.exposure,
            },
            samples_per_pixel: self.samples,
            seed: self.seed,
            ..RenderSettings::default()
        };
        if let Some(p) = self.light {
            settings.light.position = p;
        }
        if let Some(p) = self.light_power {
            settings.light.power = p;
        }
        if let Some(c) = self.light_colour {
            settings.light.colour = c;
        }
        settings.light.kind = match (self.light_radius, self.light_shape) {
            (Some(radius), _) => LightKind::sized(LightShape::Sphere, radius),
            (None, Some(shape)) => match self.light_size {
                Some(size) => LightKind::sized(shape, size),
                None => LightKind::of_shape(shape),
            },
            // A size without a shape is the sphere it always meant.
            (None, None) => match self.light_size {
                Some(radius) => LightKind::sized(LightShape::Sphere, radius),
                None => LightKind::of_shape(LightShape::default()),
            },
        };
        // The spot's flags set its parameters by their names in `light_kinds!` (`check_light`
        // refuses them for another kind).
        let radians = raylab_core::base::camera::radians;
        for (field, value) in [
            ("aim", self.light_aim.map(ParamValue::Point)),
            (
                "cutoff",
                self.spot_cutoff.map(|d| ParamValue::Number(radians(d))),
            ),
            (
                "beam",
                self.spot_beam.map(|d| ParamValue::Number(radians(d))),
            ),
        ] {
            if let Some(value) = value {
                // A spot's flag for another kind is refused by `check_light` before.
                let _ = settings.light.kind.set(field, value);
            }
        }
        if let Some(kind) = self.light_kind {
            settings.light.kind = kind;
        }
        if let Some(shadows) = self.shadows {
            settings.shading.shadows = shadows;
        }
        match self.indirect {
            Some(Indirect::Constant(n)) => {
                settings.shading.indirect = true;
                settings.shading.indirect_light = Vec3::splat(n);
            }
            Some(Indirect::Off) => settings.shading.indirect = false,
            None => {}
        }
        settings
    }
}

/// Reads render settings from a file ([`raylab_core::files::settings_file::read_file`]): a scene file,
/// a screenshot PNG or its JSON, or a bare settings object. Unknown fields are warned of on
/// stderr.
pub fn read_settings_file(path: &std::path::Path) -> anyhow::Result<RenderSettings> {
    let loaded = raylab_core::files::settings_file::read_file(path)?;
    for warning in &loaded.warnings {
        print_error_line(&format!("warning: {}: {warning}", path.display()));
    }
    Ok(loaded.settings)
}
