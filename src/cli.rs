//! The command line: `raylab render` writes an image, `raylab inspect` explains one pixel of
//! it, `raylab bench` measures the tracer; with no command, `raylab` starts the workbench.
//!
//! A thin layer over the library: arguments become a [`RenderSettings`], which is validated,
//! rendered and saved. Every bad value ends the program with one line naming it and a non-zero
//! exit code, before anything is written.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};
use glam::Vec3;
use raylab_core::bench::{BenchConfig, bench_scene};
use raylab_core::shading::light::{LightKind, LightShape, SpotCone};
use raylab_core::shading::material::{MaterialKind, TexturePreset};
use raylab_core::shapes::accel::{AccelKind, Isa};
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::shapes::scene::spec::{BoxPart, PartMaterial};
use raylab_core::teaching::inspect::{InspectError, inspect_pixel};
use raylab_core::transport::display::{Display, DisplayTransform};
use raylab_core::transport::film::OutputFormat;
use raylab_core::transport::integrator::{DEFAULT_SPECULAR_DEPTH, MAX_SPECULAR_DEPTH};
use raylab_core::transport::render::try_render;
use raylab_core::transport::settings::{
    Caustics, DEFAULT_PHOTONS, MAX_EXPOSURE, MAX_IMAGE_SIDE, MAX_PHOTONS, MAX_SAMPLES,
};
use raylab_core::transport::view::View;
use raylab_core::{Camera, MaterialPreset, RenderSettings, Shading, Stage};

mod class;
mod equations;

#[derive(Debug, Parser)]
#[command(
    name = "raylab",
    version,
    about = "A raytracing workbench for learning"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Kernels: best (the fastest measured on this CPU at start-up), avx512, avx2 or scalar.
    /// Every set gives the same image; this changes only the speed. Also RAYLAB_ISA.
    #[arg(long, global = true, default_value = "best", value_name = "ISA")]
    pub isa: String,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render an image of the scene to a PNG or EXR file (defaults: the lab's figure 7, 512×512).
    Render(RenderArgs),
    /// Explain one pixel of the render: each step of its computation beside the lab equation
    /// it evaluates, with the numbers (sample 0: the pixel's centre).
    Inspect(InspectArgs),
    /// Measure the tracer per scene: BVH build time, Mrays/s of primary and shadow rays, and
    /// the milliseconds of one lab pass (medians over repeated passes).
    Bench(BenchArgs),
    /// Check your own render of the lab against the exact figure: how much of it matches,
    /// where it differs most, and the classic mistake that explains the difference (or none,
    /// or unknown). The figure is rendered at the image's size, with the lab's focal length
    /// (the image's width) unless --focal says otherwise.
    Check(CheckArgs),
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene to measure: cornell, bunny, teapot or terrain [default: all four].
    #[arg(long, value_name = "NAME", conflicts_with = "obj")]
    pub scene: Option<SceneChoice>,
    /// Measure an OBJ file standing in the Cornell box instead.
    #[arg(long, value_name = "FILE")]
    pub obj: Option<PathBuf>,
    /// Image width in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "W")]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "H")]
    pub height: u32,
    /// Threads [default: one per core].
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024), value_name = "N")]
    pub threads: Option<u16>,
    /// Timed passes per figure; the median is reported.
    #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u32).range(1..=10_000), value_name = "N")]
    pub passes: u32,
    /// Acceleration structure: auto, brute, flat, bvh2 or bvh8 (to compare them).
    #[arg(long, default_value = "auto", value_name = "KIND")]
    pub accel: AccelKind,
    /// Print one JSON object per scene (one per line) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// lab: the figures above; path: also one pass of the path stage (unlimited bounces), as
    /// camera paths per second; denoise: the denoiser on the path-traced Cornell box, its time
    /// at W×H (16 samples) and its quality at 256² against a converged reference (about a
    /// minute: see --reference-samples; with mirror and glass, a few).
    #[arg(long, default_value = "lab", value_parser = ["lab", "path", "denoise"], value_name = "STAGE")]
    pub stage: String,
    /// With --stage denoise: samples per pixel of the reference the quality is measured
    /// against.
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(1..=1_000_000), value_name = "N")]
    pub reference_samples: u32,
    /// With --stage denoise: the box's materials, as render's --material-preset: none (the
    /// lab's diffuse box), mirror, glass, both (a mirror and a glass block) or rough.
    #[arg(long, value_name = "PRESET")]
    pub material_preset: Option<MaterialPreset>,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Output file: .png (the lab's display: clamped, no gamma) or .exr (linear floats).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Write a debug view instead of the shaded image: normals, depth, barycentric, triangle,
    /// bvh-cost, shadow, or variance (of each pixel's mean; needs --samples 2 or more). Its
    /// legend is printed after the summary. Views are saved with the lab's display whatever
    /// --display says, so their colours are the legend's. Combines with --settings.
    /// [default: shaded, or the view a screenshot given to --settings was made with]
    #[arg(long, value_name = "VIEW")]
    pub view: Option<raylab_core::transport::view::View>,
    /// Also write the render's settings as a scene file (.toml), to open in the workbench or
    /// render again with --scene-file.
    #[arg(long, value_name = "FILE.toml")]
    pub save_scene: Option<PathBuf>,
    /// on: write the denoised image, for a noisy render (the path stage, soft shadows, depth
    /// of field; elsewhere there is no noise, and the image is written as it is). off: the
    /// unbiased estimate, as an EXR should hold it. Settings given with --settings that were
    /// a denoised image's (a screenshot of the denoised image) are denoised either way.
    #[arg(long, default_value = "off", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub denoise: bool,
    /// Your own equations, in place of the lab's: a text file of `NAME = EXPRESSION` lines
    /// (and `let NAME = …` lines) for d (the ray direction, equation 24), shadowStart,
    /// shadowed (section 5.1), D (equation 27, DirectLight) and R (equations 28 and 30), in
    /// the lab's C++ style. Prints how many pixels match the exact figure and, for each
    /// quantity written, how it differs from the lab's. The lab's stages only.
    #[arg(long, value_name = "FILE")]
    pub equations: Option<PathBuf>,
    #[command(flatten)]
    pub options: RenderOptions,
}

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The pixel to explain, from the top-left corner: 0 ≤ X < width, 0 ≤ Y < height.
    #[arg(long, value_parser = parse_pixel, value_name = "X,Y", allow_hyphen_values = true)]
    pub pixel: Pixel,
    /// Print one JSON object (every value the tracer computed) instead of the explanation.
    #[arg(long)]
    pub json: bool,
    /// on: also the pixel's denoised value (the whole image is rendered and denoised, as
    /// `render --denoise on` writes it), printed beside the traced one.
    #[arg(long, default_value = "off", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub denoise: bool,
    /// Your own equations (see render's --equations): also the pixel of the image they render,
    /// each quantity's value beside the lab's and every part of your text with its value there.
    #[arg(long, value_name = "FILE", conflicts_with = "denoise")]
    pub equations: Option<PathBuf>,
    #[command(flatten)]
    pub options: RenderOptions,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Your render: PNG, BMP (what SDL saves), PPM or JPEG, 8 bits a channel, any size. Or a
    /// class: a folder of renders (its subfolders too: a folder a student) or several files,
    /// each checked, a line each; see --report.
    #[arg(value_name = "IMAGE|FOLDER", required_unless_present = "equations", num_args = 1..)]
    pub images: Vec<PathBuf>,
    /// Check your own equations instead of an image: the image they render (see render's
    /// --equations) is checked against the exact figure, naming the classic mistake that
    /// explains it, and each quantity written is judged against the lab's at random inputs.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["images", "report", "csv", "screenshot_settings", "diff_out"])]
    pub equations: Option<PathBuf>,
    /// Print one JSON object (the match, the verdict and every candidate mistake, best first)
    /// instead of the report; for a class, report.json's.
    #[arg(long)]
    pub json: bool,
    /// Also write the difference picture: |yours − figure| per channel, amplified 8×, black
    /// where they agree (a PNG). One image only.
    #[arg(long, value_name = "FILE.png")]
    pub diff_out: Option<PathBuf>,
    /// A class: write its report to this folder (made if needed): index.html, a page to open
    /// in the browser (a row a submission, the verdicts' histogram, filters, a detail view a
    /// student with an A/B wipe), report.csv, report.json and the images they show.
    #[arg(long, value_name = "FOLDER")]
    pub report: Option<PathBuf>,
    /// With --report: also Gradescope's results.json for each student, in
    /// gradescope/STUDENT/ (a test an image, scored when it is the exact figure).
    #[arg(long, requires = "report")]
    pub gradescope: bool,
    /// A class: what each submission is checked against, from a CSV list: a header line with
    /// `file` (its name below the folder) and any options of this command without `--`
    /// (stage, yaw, light, shadows, indirect, width, height, settings, …), then a line a
    /// submission; an empty cell is the option's default. A file not listed is not checked.
    #[arg(long, value_name = "FILE.csv", conflicts_with_all = SETTINGS_OPTIONS, conflicts_with = "settings", conflicts_with = "scene_file")]
    pub csv: Option<PathBuf>,
    /// A class: each PNG carrying a workbench screenshot's settings is checked against them;
    /// the others against the options given.
    #[arg(long)]
    pub screenshot_settings: bool,
    /// The settings your image was rendered with: the stage, camera, light, --shadows and
    /// --indirect as for render. --width and --height are the image's.
    #[command(flatten)]
    pub options: RenderOptions,
}

/// The image's width and height when not given: the lab's 512 × 512 figures.
const DEFAULT_SIDE: u32 = 512;

/// The `--pixel` value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pixel(pub u32, pub u32);

/// The options that set what a file given with `--settings` or `--scene-file` holds: either
/// file takes them all, so none combines with it.
const SETTINGS_OPTIONS: [&str; 38] = [
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

/// The `--bounces` value: a cap, or unlimited.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounces(pub Option<u32>);

/// The `--indirect` value: a constant N, or off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Indirect {
    Off,
    Constant(f32),
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
            (Some(radius), _) => LightKind::Sphere { radius },
            (None, Some(shape)) => match self.light_size {
                Some(size) => LightKind::sized(shape, size),
                None => LightKind::of_shape(shape),
            },
            (None, None) => match self.light_size {
                Some(radius) => LightKind::Sphere { radius },
                None => LightKind::Point,
            },
        };
        if let LightKind::Spot(cone) = &mut settings.light.kind {
            let default = SpotCone::default();
            *cone = SpotCone {
                aim: self.light_aim.unwrap_or(default.aim),
                cutoff: self
                    .spot_cutoff
                    .map_or(default.cutoff, raylab_core::base::camera::radians),
                beam: self
                    .spot_beam
                    .map_or(default.beam, raylab_core::base::camera::radians),
            };
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

/// `--isa NAME`: the kernels of every structure this process builds (`best`: measured).
fn choose_kernels(name: &str) -> anyhow::Result<()> {
    if name == "best" {
        return Ok(());
    }
    let isa = Isa::by_name(name).with_context(|| {
        format!(
            "kernels '{name}' are unknown or not supported by this CPU (expected best, avx512, avx2 or scalar)"
        )
    })?;
    isa.force().map_err(anyhow::Error::msg)
}

/// Parses the arguments and runs the command; the one place errors become exit codes.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // --help and --version: a success only if the text was written (not to a full
            // disk, `> /dev/full`).
            let mut out = std::io::stdout();
            let text = e.render();
            let printed = if std::io::IsTerminal::is_terminal(&out) {
                write!(out, "{}", text.ansi())
            } else {
                write!(out, "{text}")
            }
            .and_then(|()| out.flush());
            return match printed {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
                Err(_) => ExitCode::FAILURE,
            };
        }
        Err(e) => {
            // Nothing here may panic on a stderr that cannot be written (`2> /dev/full`):
            // the exit code says what happened.
            print_error_line(&one_line(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    if matches!(cli.command, Some(Command::Render(_))) {
        // First: the threads started below inherit the signals it blocks.
        crate::signals::remove_temporary_files_when_stopped();
    } else {
        // `main` blocked them; other commands are stopped by them as by default.
        crate::signals::unblock();
    }
    // Whatever runs outside the commands' own pools (the kernels' calibration, for one) runs
    // on rayon's global pool: its thread count is given too, so `RAYON_NUM_THREADS` cannot
    // ask for more than the cap.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(raylab_core::transport::progressive::default_threads())
        .thread_name(|i| format!("raylab-{i}"))
        .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
        .build_global();
    if cli.isa == "best"
        && let Some(note) = Isa::environment_note()
    {
        print_error_line(&format!("warning: {note}"));
    }
    let result = match choose_kernels(&cli.isa) {
        Err(e) => Err(e),
        Ok(()) => match cli.command {
            Some(Command::Render(args)) => run_render(&args),
            Some(Command::Inspect(args)) => run_inspect(&args),
            Some(Command::Bench(args)) => run_bench(&args),
            Some(Command::Check(args)) => run_check(&args),
            None => crate::start_workbench(),
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            match e.downcast_ref::<equations::CompileErrors>() {
                // A compiler's errors: a location and message, the line and a caret, each.
                Some(errors) => eprint!("{}", printable_lines(&errors.0)),
                None => print_error_line(&format!("error: {e:#}")),
            }
            // A pixel outside the image is a bad argument, as clap's refusals are.
            let bad_argument = e
                .downcast_ref::<InspectError>()
                .is_some_and(|e| matches!(e, InspectError::OutsideImage { .. }));
            if bad_argument {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

/// Writes one line to stderr: `text`, with what came from files (a scene's name, a model's
/// file name, a line of a scene file) made safe for a terminal
/// ([`raylab_core::base::inputs::escape_control`]: control characters escaped, a line break
/// included, so the message stays one line). A stderr that cannot be written (`2> /dev/full`)
/// is no panic: the exit code still says what happened.
fn print_error_line(text: &str) {
    let _ = writeln!(
        std::io::stderr(),
        "{}",
        raylab_core::base::inputs::escape_control(text)
    );
}

/// `text` of several lines made safe for a terminal line by line (see [`print_error_line`]).
fn printable_lines(text: &str) -> String {
    text.lines()
        .map(|line| format!("{}\n", raylab_core::base::inputs::escape_control(line)))
        .collect()
}

/// clap's message as one line: its first, with what it lists after a colon ("the following
/// required arguments were not provided: --pixel <X,Y>").
fn one_line(text: &str) -> String {
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("error: bad arguments");
    if !first.ends_with(':') {
        return first.to_owned();
    }
    let listed: Vec<&str> = lines
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .collect();
    format!("{first} {}", listed.join(", "))
}

fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    // Refuse what can't be written before spending time on the render.
    OutputFormat::from_path(&args.out)?;
    if let Some(path) = &args.save_scene {
        check_scene_destination(path)?;
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        anyhow::bail!(
            "could not write '{}': folder '{}' does not exist",
            args.out.display(),
            dir.display()
        );
    }
    raylab_core::transport::film::check_writable(&args.out)?;
    let mut settings = args.options.resolve_settings()?;
    settings.validate()?;
    refuse_output_onto(
        "--out",
        &args.out,
        "the render",
        files_read(&args.options, &settings),
    )?;
    // Denoised when asked, or when the settings given were those of a denoised image.
    settings.denoise |= args.denoise;
    // A screenshot made with a debug view is that view again, unless --view says otherwise.
    let view = args.view.unwrap_or(settings.view);
    // The student's equations: a file's (then carried by the PNG), or those a screenshot or
    // scene file carries.
    if let Some(path) = &args.equations {
        settings.equations = equations::read_texts(path)?;
    }
    let equations = if settings.equations.is_empty() {
        None
    } else {
        let written = raylab_core::teaching::sandbox::carried::compile_texts(&settings.equations)?;
        equations::refuse_unless_lab(&settings, view)?;
        Some(written)
    };
    // Refused before any work if it cannot fit (a 16384² image alone is 3 GiB).
    let c = &settings.camera;
    // Denoising holds a film with its variance, brightest samples and its samples' features'
    // sums, the features, the colour without outliers and the filter's planes beside the
    // image: under 52 floats a pixel more.
    let denoise_memory = if settings.denoise {
        208 * u64::from(c.width) * u64::from(c.height)
    } else {
        0
    };
    raylab_core::base::memory::check(
        format!("a {}×{} render", c.width, c.height),
        settings
            .memory_estimate(view)
            .saturating_add(denoise_memory),
    )?;
    if view == raylab_core::transport::view::View::Variance && settings.samples_per_pixel < 2 {
        anyhow::bail!(
            "the variance view needs 2 or more samples per pixel (--samples 2 or more): it \
             measures the spread between a pixel's samples"
        );
    }
    // What the PNG carries and the scene file says are made now: what cannot be written
    // (a seed a scene file cannot hold) is refused before the render, not after it.
    let out_folder = args.out.parent().unwrap_or(std::path::Path::new(""));
    let mut carried = settings.relative_to(out_folder);
    carried.view = view;
    let text =
        raylab_core::files::settings_file::settings_text(&carried).map_err(anyhow::Error::msg)?;
    let scene_text = match &args.save_scene {
        Some(path) => {
            let folder = path.parent().unwrap_or(std::path::Path::new(""));
            let text = raylab_core::files::scene_file::to_text(&settings, folder)
                .map_err(|reason| anyhow::anyhow!("--save-scene '{}': {reason}", path.display()))?;
            Some((path, text))
        }
        None => None,
    };
    let pool = thread_pool("render", args.options.threads)?;

    let choice = &settings.scene;
    let (scene, warnings) = pool.install(|| choice.load_with_warnings())?;
    for warning in warnings {
        print_error_line(&format!("warning: {warning}"));
    }
    let start = Instant::now();
    let mut denoised_note = None;
    // With --equations: the pixels that came out NaN or infinite, and the share of pixels
    // within 2/255 of the exact figure.
    let mut sandbox_figures = None;
    let (image, display, legend) = if let Some(written) = &equations {
        let yours =
            pool.install(|| raylab_core::teaching::sandbox::render(&scene, &settings, written));
        let figure = pool.install(|| try_render(&scene, &settings))?;
        let share = raylab_core::teaching::check::compare::share_within(
            &raylab_core::teaching::check::Rgb8::from_linear(&yours.image),
            &raylab_core::teaching::check::Rgb8::from_linear(&figure),
        );
        sandbox_figures = Some((yours.non_finite, share));
        (yours.image, settings.display, None)
    } else {
        match view {
            raylab_core::transport::view::View::Shaded if settings.denoise => {
                let (raw, denoised) = pool.install(|| {
                    raylab_core::transport::denoise::render_denoised(&scene, &settings)
                });
                denoised_note = Some(if denoised.is_some() {
                    "denoised (the accumulated image filtered by the denoiser; --denoise off writes \
                 the unbiased estimate)"
                } else {
                    "not denoised: nothing in this render is noisy (no path tracing, soft shadows \
                 or depth of field)"
                });
                (denoised.unwrap_or(raw), settings.display, None)
            }
            raylab_core::transport::view::View::Shaded => (
                pool.install(|| try_render(&scene, &settings))?,
                settings.display,
                None,
            ),
            view @ (View::Normals
            | View::Depth
            | View::Barycentric
            | View::Triangle
            | View::BvhCost
            | View::Shadow
            | View::Variance
            | View::Photons) => {
                let v = pool.install(|| {
                    raylab_core::transport::view::render_view(&scene, &settings, view, &|| false)
                })?;
                (v.image, Display::default(), Some(v.legend))
            }
        }
    };
    let elapsed = start.elapsed();
    // A PNG carries its settings, so the image alone reopens to the same render.
    let keyword = raylab_core::files::settings_file::PNG_KEYWORD;
    image.save_with_text(&args.out, &display, Some((keyword, &text)))?;
    let saved_scene = match scene_text {
        Some((path, text)) => Some(save_scene_file(path, &text)?),
        None => None,
    };
    if let Some(note) = raylab_core::transport::render::camera_sees_nothing(&scene, &settings) {
        // A black image the camera is to blame for: say so (the image is written all the same).
        print_error_line(&format!("note: {note}"));
    }

    let c = &settings.camera;
    let summary = format!(
        "rendered {} {}×{} (field of view {:.1}° × {:.1}°, {}{}, {} spp) in {:.1} ms on {} threads → {}",
        choice,
        c.width,
        c.height,
        c.horizontal_fov_degrees(),
        c.vertical_fov_degrees(),
        settings.shading.stage,
        match settings.material_preset {
            MaterialPreset::None => String::new(),
            preset => format!(", {preset} preset"),
        },
        settings.samples_per_pixel,
        elapsed.as_secs_f64() * 1e3,
        pool.current_num_threads(),
        args.out.display()
    );
    let mut text = summary + "\n";
    if let Some(note) = denoised_note {
        text += &format!("{note}\n");
    }
    if let Some((path, asked)) = &saved_scene
        && path != asked
    {
        text += &format!(
            "scene file → {} ('{}' exists, and is left as it is)\n",
            path.display(),
            asked.display()
        );
    }
    if let (Some((non_finite, share)), Some(written)) = (sandbox_figures, &equations) {
        text += &equations_text(written, settings.shading.stage, non_finite, share);
    }
    if let Some(legend) = legend {
        text += &format!("{} view:\n", legend.title);
        for line in &legend.lines {
            text += &format!("  {line}\n");
        }
    }
    // The image is written: a reader that went away (`| head`, `| true`) is no failure, and
    // nothing may panic on a stdout that cannot be written (`> /dev/full`).
    let text = printable_lines(&text);
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(anyhow::anyhow!(
            "wrote '{}', but could not print the summary: {e}",
            args.out.display()
        )),
    }
}

/// What `--equations` found, a line each: the match with the exact figure, the pixels that
/// came out NaN or infinite (magenta), and each written quantity's verdict.
fn equations_text(
    written: &raylab_core::teaching::sandbox::Equations,
    stage: Stage,
    non_finite: usize,
    share: f64,
) -> String {
    let mut text = format!(
        "your equations: {:.1} % of pixels within 2/255 of the exact figure\n",
        share * 100.0
    );
    if non_finite > 0 {
        text += &format!("{non_finite} pixels came out NaN or infinite (shown magenta)\n");
    }
    let verdicts = equations::verdicts(written, stage);
    if verdicts.is_empty() {
        text += "no quantity written: the image is the lab's own\n";
    }
    for (quantity, verdict) in verdicts {
        text += &format!("{}: {verdict}\n", quantity.name());
    }
    text
}

/// `check --equations FILE`: the image the student's equations render, checked as their
/// image would be, and each quantity judged.
fn check_equations(args: &CheckArgs, path: &std::path::Path) -> anyhow::Result<()> {
    use raylab_core::teaching::check;
    let written = equations::read(path)?;
    let settings = args.options.resolve_settings()?;
    equations::refuse_unless_lab(&settings, View::Shaded)?;
    check::check_settings(&settings)?;
    let c = &settings.camera;
    raylab_core::base::memory::check(
        format!("checking a {}×{} image", c.width, c.height),
        check::memory_estimate(c.width, c.height) + settings.scene.memory_estimate(),
    )?;
    let pool = thread_pool("check", args.options.threads)?;
    let (checked, rendered) = pool.install(|| -> anyhow::Result<_> {
        let scene = settings.scene.load()?;
        let rendered = raylab_core::teaching::sandbox::render(&scene, &settings, &written);
        let image = check::Rgb8::from_linear(&rendered.image);
        Ok((check::check(&scene, &settings, &image)?, rendered))
    })?;
    let verdicts = equations::verdicts(&written, settings.shading.stage);
    let mut out = std::io::stdout().lock();
    if args.json {
        let quantities: serde_json::Map<String, serde_json::Value> = verdicts
            .iter()
            .map(|(q, v)| (q.name().to_string(), serde_json::Value::from(v.as_str())))
            .collect();
        let json = serde_json::json!({
            "check": checked.report,
            "non_finite_pixels": rendered.non_finite,
            "quantities": quantities,
        });
        writeln!(out, "{json}")?;
    } else {
        write!(out, "{}", printable_lines(&checked.report.to_text()))?;
        if rendered.non_finite > 0 {
            writeln!(
                out,
                "{} pixels came out NaN or infinite (shown magenta)",
                rendered.non_finite
            )?;
        }
        for (quantity, verdict) in verdicts {
            writeln!(out, "{}: {}", quantity.name(), printable_lines(&verdict))?;
        }
    }
    Ok(())
}

/// The files a command given `options` reads, beside the image it checks: the file given to
/// `--settings` or `--scene-file`, and every file its scene reads.
fn files_read(
    options: &RenderOptions,
    settings: &RenderSettings,
) -> Vec<raylab_core::base::inputs::Input> {
    let given = [
        (&options.settings, "the --settings file"),
        (&options.scene_file, "the --scene-file file"),
    ];
    let mut files: Vec<_> = given
        .into_iter()
        .filter_map(|(path, what)| {
            let path = path.as_deref()?;
            Some(raylab_core::base::inputs::Input::new(path, what))
        })
        .collect();
    files.extend(settings.scene.files_read());
    files
}

/// Refuses an output (`option`'s `path`) that would replace one of the `files` `reader` reads
/// ([`raylab_core::base::inputs::refuse_output_onto`]), before any work. `--save-scene` needs no
/// such check: it never replaces a file ([`save_scene_file`]).
fn refuse_output_onto(
    option: &str,
    path: &std::path::Path,
    reader: &str,
    files: Vec<raylab_core::base::inputs::Input>,
) -> anyhow::Result<()> {
    raylab_core::base::inputs::refuse_output_onto(option, path, reader, &files)
        .map_err(anyhow::Error::msg)
}

/// Writes `--save-scene`'s text at `path`, or, if a file is there (the scene file the render
/// was read from, or any other), at the first free name `NAME-1.toml`, `NAME-2.toml`, … as
/// screenshots are named: an existing file is never replaced. Returns the path written and
/// the one asked for.
fn save_scene_file(
    path: &std::path::Path,
    text: &str,
) -> anyhow::Result<(std::path::PathBuf, std::path::PathBuf)> {
    let written = raylab_core::transport::film::write_to_free_name(path, text.as_bytes()).map_err(
        |e| match e {
            raylab_core::transport::film::SaveError::Write { path, reason } => {
                anyhow::anyhow!("could not write scene file '{}': {reason}", path.display())
            }
            other => anyhow::Error::new(other),
        },
    )?;
    Ok((written, path.to_path_buf()))
}

/// `--save-scene`'s file: a `.toml` in a folder that exists and takes new files (checked by
/// creating one). A file already there is not replaced ([`save_scene_file`] picks a free name).
fn check_scene_destination(path: &std::path::Path) -> anyhow::Result<()> {
    let toml = path
        .extension()
        .is_some_and(|e| e == raylab_core::files::scene_file::EXTENSION);
    if !toml {
        anyhow::bail!(
            "--save-scene '{}': a scene file's name ends in .toml",
            path.display()
        );
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        anyhow::bail!(
            "could not write scene file '{}': folder '{}' does not exist",
            path.display(),
            dir.display()
        );
    }
    raylab_core::transport::film::check_file_destination(path).map_err(|e| match e {
        raylab_core::transport::film::SaveError::Write { reason, .. } => {
            anyhow::anyhow!("could not write scene file '{}': {reason}", path.display())
        }
        other => anyhow::Error::new(other),
    })
}

fn run_inspect(args: &InspectArgs) -> anyhow::Result<()> {
    let written = args.equations.as_deref().map(equations::read).transpose()?;
    let settings = args.options.resolve_settings()?;
    settings.validate()?;
    if written.is_some() {
        equations::refuse_unless_lab(&settings, View::Shaded)?;
    }
    let Pixel(x, y) = args.pixel;
    let (width, height) = (settings.camera.width, settings.camera.height);
    // Refused before the scene is loaded (a large model takes a while).
    if x >= width || y >= height {
        return Err(anyhow::Error::new(InspectError::OutsideImage {
            x,
            y,
            width,
            height,
        })
        .context(format!("--pixel {x},{y}")));
    }
    // Refused before the scene is loaded if it cannot fit: inspecting holds the scene (its
    // models and textures), not the image.
    raylab_core::base::memory::check(
        format!("inspecting a pixel of {}", settings.scene.name()),
        settings.scene.memory_estimate() + raylab_core::transport::settings::BASE_MEMORY,
    )?;
    let pool = thread_pool("inspect", args.options.threads)?;
    let scene = pool.install(|| settings.scene.load())?;
    let inspection =
        inspect_pixel(&scene, &settings, x, y).with_context(|| format!("--pixel {x},{y}"))?;
    // Inside the image (checked above), so explained wherever equations are given.
    let explained = written
        .as_ref()
        .and_then(|w| pool.install(|| equations::explain(&scene, &settings, w, x, y)));
    // The denoised value needs the whole image, rendered and denoised as `render --denoise
    // on` writes it (`None` where nothing is noisy).
    let denoised = if args.denoise || settings.denoise {
        let c = &settings.camera;
        raylab_core::base::memory::check(
            format!("denoising a {}×{} render", c.width, c.height),
            settings
                .memory_estimate(raylab_core::transport::view::View::Shaded)
                .saturating_add(208 * u64::from(c.width) * u64::from(c.height)),
        )?;
        let (_, denoised) =
            pool.install(|| raylab_core::transport::denoise::render_denoised(&scene, &settings));
        Some(denoised.map(|d| d.get(x, y)))
    } else {
        None
    };
    // Written with `write!` so that a closed pipe is an error, not a panic.
    let mut out = std::io::stdout().lock();
    if args.json {
        let mut json = serde_json::to_value(&inspection)?;
        if let (Some(denoised), Some(object)) = (denoised, json.as_object_mut()) {
            object.insert(
                "denoised".to_owned(),
                denoised.map_or(serde_json::Value::Null, |d| {
                    serde_json::json!([d.x, d.y, d.z])
                }),
            );
        }
        if let (Some(explained), Some(object)) = (&explained, json.as_object_mut()) {
            object.insert("equations".to_owned(), serde_json::to_value(explained)?);
        }
        writeln!(out, "{json}")?;
    } else {
        write!(out, "{}", printable_lines(&inspection.to_text()))?;
        if let Some(explained) = &explained {
            writeln!(out, "\nYour equations at this pixel:")?;
            write!(out, "{}", printable_lines(&explained.to_text()))?;
        }
        match denoised {
            Some(Some(d)) => writeln!(
                out,
                "denoised: ({:.6}, {:.6}, {:.6}) (the whole image denoised, as render --denoise \
                 on writes it; the value above is the traced one)",
                d.x, d.y, d.z
            )?,
            Some(None) => writeln!(
                out,
                "denoised: the same (nothing in this render is noisy: no path tracing, soft \
                 shadows or depth of field)"
            )?,
            None => {}
        }
    }
    Ok(())
}

fn run_check(args: &CheckArgs) -> anyhow::Result<()> {
    use raylab_core::teaching::check;
    if let Some(path) = &args.equations {
        return check_equations(args, path);
    }
    if class::is_class(args) {
        return class::run(args);
    }
    let path = &args.images[0];
    if let Some(path) = &args.diff_out {
        if OutputFormat::from_path(path)? != OutputFormat::Png {
            anyhow::bail!(
                "--diff-out '{}': the difference picture is written as PNG (.png)",
                path.display()
            );
        }
        raylab_core::transport::film::check_file_destination(path)?;
    }
    let (image, encoding) = check::read_image_encoded(path)?;
    // The figure at the image's size: settings from a file keep their own camera (a size
    // that differs is refused by name), the arguments get the image's width and height.
    let settings = if args.options.settings.is_some() || args.options.scene_file.is_some() {
        args.options.resolve_settings()?
    } else {
        settings_at_image_size(&args.options, path, image.width, image.height)?
    };
    if let Some(path) = &args.diff_out {
        let mut files = files_read(&args.options, &settings);
        files.push(raylab_core::base::inputs::Input::new(
            &args.images[0],
            "the image to check",
        ));
        refuse_output_onto("--diff-out", path, "the check", files)?;
    }
    check::check_settings(&settings)?;
    raylab_core::base::memory::check(
        format!("checking a {}×{} image", image.width, image.height),
        check::memory_estimate(image.width, image.height) + settings.scene.memory_estimate(),
    )?;
    let pool = thread_pool("check", args.options.threads)?;
    let checked = pool.install(|| -> anyhow::Result<check::Checked> {
        let scene = settings.scene.load()?;
        Ok(check::check_encoded(&scene, &settings, &image, encoding)?)
    })?;
    let gain = check::compare::difference_gain(&image, &checked.figure);
    if let Some(path) = &args.diff_out {
        check::compare::difference_picture_with_gain(&image, &checked.figure, gain)
            .to_image()
            .save(path)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string(&checked.report)?)?;
    } else {
        write!(out, "{}", printable_lines(&checked.report.to_text()))?;
        if let Some(path) = &args.diff_out {
            writeln!(
                out,
                "difference picture: {} (|image − figure| × {gain:.1})",
                path.display()
            )?;
        }
    }
    Ok(())
}

/// The settings `options` (with no settings file) describe for the image at `path`, of
/// `width × height`: theirs at the image's size. Given sides other than the default must be
/// the image's (the default cannot be told from a typed 512, so it is taken as "the
/// image's").
fn settings_at_image_size(
    options: &RenderOptions,
    path: &std::path::Path,
    width: u32,
    height: u32,
) -> anyhow::Result<RenderSettings> {
    for (name, given, actual) in [
        ("--width", options.width, width),
        ("--height", options.height, height),
    ] {
        if given != DEFAULT_SIDE && given != actual {
            anyhow::bail!(
                "{name} {given}: the image '{}' is {width}×{height}; the figure is rendered at \
                 the image's size, so --width and --height can be left out",
                path.display(),
            );
        }
    }
    // Resolved and validated as render and inspect resolve them: the same options mean the
    // same (waves asked of a scene with no water are refused).
    RenderOptions {
        width,
        height,
        ..options.clone()
    }
    .resolve_settings()
}

fn run_bench(args: &BenchArgs) -> anyhow::Result<()> {
    if args.material_preset.is_some() && args.stage != "denoise" {
        anyhow::bail!(
            "--material-preset is measured by --stage denoise only (the denoiser's quality with \
             mirror and glass); the lab and path figures are of the scenes' own materials"
        );
    }
    let pool = thread_pool("bench", args.threads)?;
    if args.stage == "denoise" {
        return run_denoise_bench(args, &pool);
    }
    let scenes: Vec<SceneChoice> = match (&args.obj, &args.scene) {
        (Some(path), _) => vec![SceneChoice::Obj(path.clone())],
        (None, Some(choice)) => vec![choice.clone()],
        // The textured teapot is the teapot's geometry again: not measured twice.
        (None, None) => SceneChoice::BUILT_IN
            .into_iter()
            .filter(|c| *c != SceneChoice::TexturedTeapot)
            .collect(),
    };
    let isa = raylab_core::shapes::scene::best_isa();
    let config = BenchConfig {
        width: args.width,
        height: args.height,
        passes: args.passes as usize,
        path: args.stage == "path",
    };
    // Refused before any work if it cannot fit: the scenes are measured one after the other.
    let largest_scene = scenes.iter().map(SceneChoice::memory_estimate).max();
    raylab_core::base::memory::check(
        format!("a {}×{} bench", args.width, args.height),
        raylab_core::bench::memory_estimate(&config) + largest_scene.unwrap_or(0),
    )?;
    // Written with `writeln!` so that a closed pipe (`raylab bench | head`) is an error, not a
    // panic.
    let mut out = std::io::stdout().lock();
    if !args.json {
        write!(
            out,
            "{:<10} {:>9} {:>6} {:>6} {:>10} {:>12} {:>12} {:>10}",
            "scene",
            "triangles",
            "accel",
            "isa",
            "build ms",
            "primary Mr/s",
            "shadow Mr/s",
            "lab ms"
        )?;
        if config.path {
            writeln!(out, " {:>10} {:>10}", "path ms", "Mpaths/s")?;
        } else {
            writeln!(out)?;
        }
    }
    for choice in scenes {
        let report = pool.install(|| -> anyhow::Result<_> {
            let scene = choice.load()?.rebuilt(args.accel, isa);
            let kind = scene.accel().kind();
            let report = bench_scene(&choice.name(), &scene, args.accel, isa, &config)?;
            Ok((report, kind))
        })?;
        let (r, kind) = report;
        if args.json {
            writeln!(out, "{}", serde_json::to_string(&r)?)?;
        } else {
            write!(
                out,
                "{:<10} {:>9} {:>6} {:>6} {:>10.2} {:>12.1} {:>12.1} {:>10.2}",
                raylab_core::base::inputs::escape_control(&r.scene),
                r.triangles,
                kind.name(),
                isa.name(),
                r.build_ms,
                r.primary_mrays_per_s,
                r.shadow_mrays_per_s,
                r.lab_pass_ms
            )?;
            match (r.path_pass_ms, r.path_samples_per_s) {
                (Some(ms), Some(per_s)) => writeln!(out, " {ms:>10.2} {:>10.2}", per_s / 1e6)?,
                _ => writeln!(out)?,
            }
        }
    }
    if !args.json {
        writeln!(
            out,
            "{}×{}, {} threads, medians of {} passes; kernels {}",
            args.width,
            args.height,
            pool.current_num_threads(),
            args.passes,
            raylab_core::shapes::scene::calibration().map_or_else(
                || format!("{} (forced)", isa.name()),
                |c| format!("{}, the fastest measured here", c.summary())
            )
        )?;
    }
    Ok(())
}

/// `raylab bench --stage denoise`: the denoiser's time (features and filter, medians of
/// `--passes`) on a 16-sample path-traced Cornell box at W×H (its materials
/// `--material-preset`'s), then its quality at 256²: relative MSE raw and denoised at 4 to
/// 1,024 samples against `--reference-samples` ([`raylab_core::transport::denoise::quality`]).
fn run_denoise_bench(args: &BenchArgs, pool: &rayon::ThreadPool) -> anyhow::Result<()> {
    use raylab_core::test_support::path_settings;
    use raylab_core::transport::denoise::{Denoiser, Noisy, denoising_film, features_of, quality};
    use raylab_core::transport::film::Film;
    raylab_core::base::memory::check(
        format!("a {}×{} denoise bench", args.width, args.height),
        // A film (sum, squares, brightest samples, the features' sums), the features, the
        // colour without outliers and the filter's planes: under 52 floats a pixel.
        208 * u64::from(args.width) * u64::from(args.height),
    )?;
    let scene = raylab_core::shapes::scene::cornell_box();
    let preset = args.material_preset.unwrap_or_default();
    let with_preset = |width: u32, height: u32| RenderSettings {
        material_preset: preset,
        ..path_settings(width, height)
    };
    let denoiser = Denoiser::default();
    let mut out = std::io::stdout().lock();
    let never = || false;
    let (timing, rows) = pool.install(|| -> anyhow::Result<_> {
        let settings = with_preset(args.width, args.height);
        // The path tracer records the features as it traces (`denoising_film`): their time
        // here is averaging the film's sums. What recording costs the passes: the same 16
        // passes into a film that records none, alternating with them.
        let mut film = denoising_film(&scene, &settings);
        let mut plain = Film::with_noise(args.width, args.height);
        let (mut recording, mut not_recording) = (Vec::new(), Vec::new());
        for sample in 0..16 {
            for (film, times) in [
                (&mut film, &mut recording),
                (&mut plain, &mut not_recording),
            ] {
                let start = std::time::Instant::now();
                raylab_core::transport::render::accumulate_pass(
                    &scene, &settings, sample, film, &never,
                )?;
                times.push(start.elapsed());
            }
        }
        let pass_ms = (
            raylab_core::bench::median_ms(recording),
            raylab_core::bench::median_ms(not_recording),
        );
        let (mut feature_times, mut filter_times) = (Vec::new(), Vec::new());
        for _ in 0..=args.passes {
            let start = std::time::Instant::now();
            let features = features_of(&film, &scene, &settings, &never)?;
            feature_times.push(start.elapsed());
            // The filter's time includes taking the film's outliers apart and giving them back.
            let start = std::time::Instant::now();
            let noisy = Noisy::of_film(&film);
            std::hint::black_box(denoiser.denoise_noisy(&noisy, &features));
            filter_times.push(start.elapsed());
        }
        // The first of each is the warm-up.
        let (features_ms, filter_ms) = (
            raylab_core::bench::median_ms(feature_times.split_off(1)),
            raylab_core::bench::median_ms(filter_times.split_off(1)),
        );
        let rows = quality::measure(
            &scene,
            &with_preset(256, 256),
            &[4, 16, 64, 256, 1024],
            args.reference_samples,
            &denoiser,
        );
        Ok(((features_ms, filter_ms, pass_ms), rows))
    })?;
    let threads = pool.current_num_threads();
    if args.json {
        let json = serde_json::json!({
            "width": args.width,
            "height": args.height,
            "threads": threads,
            "material_preset": preset.name(),
            "features_ms": timing.0,
            "filter_ms": timing.1,
            "path_pass_ms_recording_features": timing.2.0,
            "path_pass_ms": timing.2.1,
            "quality_side": 256,
            "reference_samples": args.reference_samples,
            "quality": rows,
        });
        writeln!(out, "{json}")?;
        return Ok(());
    }
    writeln!(
        out,
        "denoiser, Cornell box{}, path stage at 16 samples, {}×{}, {threads} threads: \
         features {:.2} ms + filter {:.2} ms = {:.2} ms (medians of {} passes)",
        match preset {
            MaterialPreset::None => String::new(),
            preset => format!(" ({preset} preset: {})", preset.label()),
        },
        args.width,
        args.height,
        timing.0,
        timing.1,
        timing.0 + timing.1,
        args.passes
    )?;
    writeln!(
        out,
        "a path pass recording the features {:.2} ms, recording none {:.2} ms (medians of 16, \
         alternating)",
        timing.2.0, timing.2.1
    )?;
    writeln!(
        out,
        "quality at 256×256 against {} samples (relative MSE; equal raw: the raw samples of \
         the same error, from raw error ∝ 1/samples at 1,024):",
        args.reference_samples
    )?;
    writeln!(
        out,
        "{:>8} {:>12} {:>12} {:>10} {:>12}",
        "samples", "raw", "denoised", "equal raw", "mean change"
    )?;
    let last = rows.last().copied();
    for r in &rows {
        let equal = last.map_or(0.0, |l| {
            f64::from(l.samples) * l.raw_relative_mse / r.denoised_relative_mse.max(1e-300)
        });
        writeln!(
            out,
            "{:>8} {:>12.3e} {:>12.3e} {:>10.0} {:>11.3}%",
            r.samples,
            r.raw_relative_mse,
            r.denoised_relative_mse,
            equal,
            100.0 * r.denoised_mean_change
        )?;
    }
    Ok(())
}

/// A pool of `threads` threads named `raylab-{what}-N`, or by default
/// [`raylab_core::transport::progressive::default_threads`] (`RAYON_NUM_THREADS` up to four threads a
/// core, else one per core; a value beyond it is warned of). The count is always given
/// explicitly, so rayon never reads `RAYON_NUM_THREADS` itself.
fn thread_pool(what: &'static str, threads: Option<u16>) -> anyhow::Result<rayon::ThreadPool> {
    let threads = match threads {
        Some(n) => usize::from(n),
        None => {
            if let Some(note) = raylab_core::transport::progressive::default_threads_note() {
                print_error_line(&format!("warning: {note}"));
            }
            raylab_core::transport::progressive::default_threads()
        }
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(move |i| format!("raylab-{what}-{i}"))
        .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
        .build()
        .with_context(|| format!("could not start the {what} threads"))
}

fn parse_finite(s: &str) -> Result<f32, String> {
    finite(s)
}

/// `--material`'s long help: the kinds and their fields as the kinds' table lists them.
fn part_material_help() -> String {
    let kinds: Vec<String> = MaterialKind::DEFAULTS
        .iter()
        .map(|k| {
            let fields: Vec<String> = k
                .fields()
                .iter()
                .map(|f| {
                    let [lo, hi] = f.range;
                    format!("{} in [{lo}, {hi}]: {}", f.name, f.what)
                })
                .collect();
            match fields.is_empty() {
                true => format!("  {}: no fields", k.name()),
                false => format!("  {}: {}", k.name(), fields.join("; ")),
            }
        })
        .collect();
    format!(
        "A part of the box given a material of its own, over --material-preset: PART=KIND, \
         then optionally :FIELD=VALUE,… (a colour's three channels separated by commas too, or \
         one number for a grey); fields left out keep their defaults. Repeat for more parts. \
         PART: tall (the tall block), short, floor, left-wall, right-wall, back-wall, ceiling. \
         KIND and its fields:\n{}\nFor example --material tall=plastic:alpha=0.2,int_ior=1.5 \
         --material short=mirror:tint=0.9,0.8,0.7",
        kinds.join("\n")
    )
}

/// `--material PART=KIND[:FIELD=VALUE,…]`: the part by its name (`tall` and `short` for the
/// blocks), the material through its kind's table ([`MaterialKind::parse`]).
fn parse_part_material(s: &str) -> Result<PartMaterial, String> {
    let Some((part, material)) = s.split_once('=') else {
        return Err(format!(
            "'{s}': give the part and its material as PART=KIND, e.g. tall=plastic:alpha=0.2"
        ));
    };
    let part = match part.trim() {
        "tall" => BoxPart::TallBlock,
        "short" => BoxPart::ShortBlock,
        other => other
            .parse::<BoxPart>()
            .map_err(|e| format!("{e}; or tall, short for the blocks"))?,
    };
    let kind = MaterialKind::parse(material)?;
    Ok(PartMaterial { part, kind })
}

/// An angle in degrees (`--yaw`, `--pitch`), read as an `f64`: the same number gives the same
/// radians as in a scene file (`camera::radians`).
fn parse_degrees(s: &str) -> Result<f64, String> {
    finite(s)
}

/// A number that is finite as an `f32`.
fn finite<T: std::str::FromStr + Into<f64> + Copy>(s: &str) -> Result<T, String> {
    let x: T = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if (x.into() as f32).is_finite() {
        Ok(x)
    } else {
        Err(format!("{s} is not a finite number"))
    }
}

fn parse_positive(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be > 0"))
    }
}

fn parse_non_negative(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be ≥ 0"))
    }
}

fn parse_side(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=MAX_IMAGE_SIDE).contains(&n) => Ok(n),
        _ => Err(format!(
            "{s} must be a whole number of pixels from 1 to {MAX_IMAGE_SIDE}"
        )),
    }
}

fn parse_samples(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n) if (1..=MAX_SAMPLES).contains(&n) => Ok(n),
        _ => Err(format!(
            "{s} must be a whole number from 1 to {MAX_SAMPLES}"
        )),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y, z] = parts[..] else {
        return Err(format!("'{s}' is not three numbers X,Y,Z"));
    };
    Ok(Vec3::new(
        parse_finite(x)?,
        parse_finite(y)?,
        parse_finite(z)?,
    ))
}

fn parse_colour(s: &str) -> Result<Vec3, String> {
    let c = parse_vec3(s)?;
    if c.min_element() >= 0.0 {
        Ok(c)
    } else {
        Err(format!("{s}: each channel must be ≥ 0"))
    }
}

fn parse_exposure(s: &str) -> Result<f32, String> {
    let x = parse_finite(s)?;
    if x.abs() <= MAX_EXPOSURE {
        Ok(x)
    } else {
        Err(format!(
            "{s} must be between -{MAX_EXPOSURE} and {MAX_EXPOSURE} stops"
        ))
    }
}

fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}

fn parse_pixel(s: &str) -> Result<Pixel, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let bad = || format!("'{s}' is not a pixel X,Y (two whole numbers ≥ 0)");
    let [x, y] = parts[..] else {
        return Err(bad());
    };
    match (x.trim().parse::<u32>(), y.trim().parse::<u32>()) {
        (Ok(x), Ok(y)) => Ok(Pixel(x, y)),
        _ => Err(bad()),
    }
}

fn parse_bounces(s: &str) -> Result<Bounces, String> {
    if s == "unlimited" {
        return Ok(Bounces(None));
    }
    match s.trim().parse::<u32>() {
        Ok(n) => Ok(Bounces(Some(n))),
        _ => Err(format!(
            "'{s}' is neither a whole number of bounces nor unlimited"
        )),
    }
}

fn parse_indirect(s: &str) -> Result<Indirect, String> {
    if s == "off" {
        Ok(Indirect::Off)
    } else {
        parse_non_negative(s).map(Indirect::Constant)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> RenderOptions {
        let mut argv = vec!["raylab", "render", "--out", "x.png"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).unwrap().command {
            Some(Command::Render(a)) => a.options,
            _ => panic!("not render"),
        }
    }

    #[test]
    fn defaults_are_figure_7() {
        assert_eq!(args(&[]).settings(), RenderSettings::default());
    }

    #[test]
    fn switches_override_the_stage() {
        let s = args(&["--stage", "direct", "--shadows", "on", "--indirect", "0.25"]).settings();
        assert_eq!(s.shading.stage, Stage::Direct);
        assert!(s.shading.shadows && s.shading.indirect);
        assert_eq!(s.shading.indirect_light, Vec3::splat(0.25));
        let s = args(&["--indirect", "off", "--camera", "-0.5,0,-2", "--yaw", "-90"]).settings();
        assert!(!s.shading.indirect && s.shading.shadows);
        assert_eq!(s.camera.position, Vec3::new(-0.5, 0.0, -2.0));
        assert_eq!(s.camera.yaw, -std::f32::consts::FRAC_PI_2);
        assert_eq!(s.camera.pitch, 0.0);
        // Degrees, as the window's Pitch and a scene file's `pitch` take them.
        let s = args(&["--pitch", "-12.5", "--yaw", "30"]).settings();
        assert_eq!(s.camera.pitch, raylab_core::base::camera::radians(-12.5));
        assert_eq!(s.camera.yaw, raylab_core::base::camera::radians(30.0));
        assert!((s.camera.pitch + 12.5f32.to_radians()).abs() < 1e-7);
    }

    #[test]
    fn path_stage_bounces_and_presets() {
        let s = args(&[
            "--stage",
            "path",
            "--bounces",
            "3",
            "--material-preset",
            "both",
        ])
        .settings();
        assert_eq!(s.shading.stage, Stage::Path);
        assert_eq!(s.shading.bounces, Some(3));
        assert_eq!(s.material_preset, MaterialPreset::Both);
        let s = args(&["--stage", "path"]).settings();
        assert_eq!(
            (s.shading.bounces, s.material_preset),
            (None, MaterialPreset::None)
        );
        assert!(s.shading.shadows && s.shading.indirect);
        let s = args(&["--material-preset", "glass", "--specular-depth", "2"]).settings();
        assert_eq!(s.shading.specular_depth, 2);
        assert_eq!(
            (s.shading.caustics, s.shading.photons),
            (Caustics::Off, DEFAULT_PHOTONS)
        );
        let s = args(&[
            "--stage",
            "path",
            "--caustics",
            "photons",
            "--photons",
            "5000",
        ])
        .settings();
        assert_eq!(
            (s.shading.caustics, s.shading.photons),
            (Caustics::Photons, 5000)
        );
        assert!(
            s.description().ends_with(" · caustics by photon mapping"),
            "{}",
            s.description()
        );
        for bad in [
            &["--caustics", "yes"][..],
            &["--photons", "0"],
            &["--photons", "10000001"],
            &["--bounces", "-1"][..],
            &["--bounces", "lots"],
            &["--material-preset", "gold"],
            &["--specular-depth", "13"],
        ] {
            let mut argv = vec!["raylab", "render", "--out", "x.png"];
            argv.extend_from_slice(bad);
            assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn scenes_are_chosen_by_name_or_file() {
        assert_eq!(args(&[]).scene_choice(), SceneChoice::Cornell);
        assert_eq!(
            args(&["--scene", "bunny"]).scene_choice(),
            SceneChoice::Bunny
        );
        let a = args(&["--obj", "m/dragon.obj"]);
        assert_eq!(
            a.scene_choice(),
            SceneChoice::Obj(PathBuf::from("m/dragon.obj"))
        );
        for bad in [
            &["--scene", "dragon"][..],
            &["--scene", "bunny", "--obj", "x.obj"],
        ] {
            let mut argv = vec!["raylab", "render", "--out", "x.png"];
            argv.extend_from_slice(bad);
            assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn bench_arguments() {
        let parse = |extra: &[&str]| {
            let mut argv = vec!["raylab", "bench"];
            argv.extend_from_slice(extra);
            match Cli::try_parse_from(argv).map(|c| c.command) {
                Ok(Some(Command::Bench(b))) => Ok(b),
                Ok(_) => panic!("not bench"),
                Err(e) => Err(e),
            }
        };
        let b = parse(&[]).unwrap();
        assert_eq!(
            (b.scene, b.width, b.height, b.json),
            (None, 512, 512, false)
        );
        let b = parse(&[
            "--scene",
            "terrain",
            "--threads",
            "2",
            "--json",
            "--accel",
            "bvh2",
        ])
        .unwrap();
        assert_eq!(b.scene, Some(SceneChoice::Terrain));
        assert_eq!(
            (b.threads, b.json, b.accel),
            (Some(2), true, AccelKind::Bvh2)
        );
        for bad in [
            &["--width", "0"][..],
            &["--scene", "x"],
            &["--accel", "kd"],
            &["--passes", "0"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn inspect_takes_the_render_options() {
        let parse = |extra: &[&str]| {
            let mut argv = vec!["raylab", "inspect"];
            argv.extend_from_slice(extra);
            match Cli::try_parse_from(argv).map(|c| c.command) {
                Ok(Some(Command::Inspect(a))) => Ok(a),
                Ok(_) => panic!("not inspect"),
                Err(e) => Err(e),
            }
        };
        let a = parse(&["--pixel", "3,4", "--stage", "direct", "--json"]).unwrap();
        assert_eq!((a.pixel, a.json), (Pixel(3, 4), true));
        let render = args(&["--stage", "direct"]).settings();
        assert_eq!(a.options.settings(), render);
        assert!(!parse(&["--pixel", " 7 , 0 "]).unwrap().json);
        // --settings takes everything but the pixel, the output form and the threads.
        let file = ["--pixel", "1,1", "--settings", "x.json"];
        assert!(parse(&[&file[..], &["--json", "--threads", "2"]].concat()).is_ok());
        for bad in [
            &[&file[..], &["--width", "8"]].concat()[..],
            &["--pixel", "1"],
            &["--pixel", "a,b"],
            &["--pixel", "1,2,3"],
            &["--pixel", "-1,0"],
            &["--pixel", "1,1", "--out", "x.png"],
            &["--json"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn clap_messages_become_one_line() {
        let text = "error: the following required arguments were not provided:\n  \
                    --pixel <X,Y>\n\nUsage: raylab inspect --pixel <X,Y>\n\nFor more \
                    information, try '--help'.\n";
        assert_eq!(
            one_line(text),
            "error: the following required arguments were not provided: --pixel <X,Y>"
        );
        assert_eq!(
            one_line("error: unexpected argument '-q' found\n\nUsage: raylab"),
            "error: unexpected argument '-q' found"
        );
    }

    #[test]
    fn bad_values_are_refused() {
        for bad in [
            &["--width", "0"][..],
            &["--height", "16385"],
            &["--focal", "0"],
            &["--focal", "nan"],
            &["--camera", "1,2"],
            &["--light", "0,inf,0"],
            &["--stage", "phong"],
            &["--shadows", "maybe"],
            &["--light-power", "-1"],
            &["--threads", "0"],
        ] {
            let mut argv = vec!["raylab", "render", "--out", "x.png"];
            argv.extend_from_slice(bad);
            assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
        }
    }
}
