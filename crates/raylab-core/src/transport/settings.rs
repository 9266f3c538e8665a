//! Everything that determines an image, in one serialisable value.
//!
//! The command line, the workbench's panels and saved screenshots all describe a render with a
//! [`RenderSettings`]; the renderer takes nothing else. `#[serde(default)]` everywhere means an
//! older or partial settings file still loads, with the lab's values for what it lacks.

mod equations;
mod stage;
mod view_choice;

pub use equations::EquationTexts;

pub use stage::{
    Caustics, DEFAULT_PHOTONS, DEFAULT_SPECULAR_DEPTH, Integrator, MAX_PHOTONS, MAX_SPECULAR_DEPTH,
    Shading, Stage,
};
pub use view_choice::View;

use glam::Vec3;
use serde::{Deserialize, Serialize};

pub use crate::base::invalid::SettingsError;
use crate::base::invalid::check_path;

use crate::base::camera::Camera;
use crate::shading::light::{LightSpec, ParamType, ParamValue};
use crate::shading::material::{DEFAULT_ROUGHNESS, MIN_ROUGHNESS, MaterialPreset, TexturePreset};
use crate::shapes::scene::SceneChoice;
use crate::shapes::scene::spec::PartMaterial;
use crate::transport::display::Display;

/// The largest image side raylab renders: 16384 px (a 16384² float image is 3 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// The longest focal length, in pixels: a field of view of a 10,000th of a degree on a
/// 16384-pixel image. Far beyond it, the squared length of a primary ray's direction
/// overflows `f32` and every ray is lost (a black image).
pub const MAX_FOCAL_LENGTH: f32 = 1e7;

/// The shortest focal length, in pixels: a field of view within a hair of 180°. Every primary
/// ray's direction is at least (0, 0, f) long, and normalising it divides by its length: far
/// below this, f² underflows `f32` (at f = 1e−23 it is 0) and the centre ray has no direction
/// (a black pixel). At 1e−3, f² = 1e−6 is an ordinary `f32` with its full precision, and so is
/// it for the workbench's preview at an eighth of the width.
pub const MIN_FOCAL_LENGTH: f32 = 1e-3;

/// The farthest a camera or light may stand from the origin, per coordinate, in scene units:
/// a million times the lab's box (2 across). Far beyond it, squared distances (r² in equation
/// 27, the ray–box and ray–triangle products) overflow `f32` and a render is silently black.
pub const MAX_COORDINATE: f32 = 1e6;

/// The longest focus distance, in scene units: a million times the lab's box, as good as
/// infinitely far. The lens ray aims at `d · F / f` (`Camera::lens_ray_rotated`); far beyond
/// this, with the shortest focal length, that point overflows `f32` and every ray is lost.
pub const MAX_FOCUS_DISTANCE: f32 = 1e6;

/// The widest lens aperture (radius), in scene units: a thousand times the lab's box. A lens
/// wider than the scene blurs everything alike; far beyond it, lens points overflow `f32`.
pub const MAX_APERTURE: f32 = 1e3;

/// The smallest size an area light may have, in scene units (a sphere's radius, a square's
/// side): the point light's nearest distance,
/// [`MIN_LIGHT_DISTANCE`](crate::shading::light::MIN_LIGHT_DISTANCE). A sphere of radius R is as
/// bright at its surface as the point light at the distance R, and no brighter light is
/// allowed; a smaller light is the point light (size 0). The derivation is in
/// [`RenderSettings::validate`].
pub const MIN_LIGHT_SIZE: f32 = crate::shading::light::MIN_LIGHT_DISTANCE;

/// The largest size an area light may have, in scene units: a million times the lab's box,
/// as [`MAX_COORDINATE`]. Far beyond it the area (4πR², S²) overflows `f32` and the light's
/// radiance is 0: a black image.
pub const MAX_LIGHT_SIZE: f32 = 1e6;

/// The largest exposure, either way, in stops.
pub const MAX_EXPOSURE: f32 = 20.0;

/// The most samples per pixel a render may ask for.
pub const MAX_SAMPLES: u32 = 1 << 16;

/// The most light power, in watts: 71,000 times the lab's 14 W. With [`MAX_LIGHT_COLOUR`] and
/// [`MAX_INDIRECT_LIGHT`] it keeps every value a render makes finite (the derivation is in
/// [`RenderSettings::validate`]); brighter images are what the exposure is for.
pub const MAX_LIGHT_POWER: f32 = 1e6;

/// The largest channel of the light's colour (the lab's white is 1, 1, 1): each channel's
/// power is the power times it.
pub const MAX_LIGHT_COLOUR: f32 = 1e3;

/// The largest constant indirect light N, per channel (the lab's is 0.5).
pub const MAX_INDIRECT_LIGHT: f32 = 1e6;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RenderSettings {
    /// The scene to trace: the lab's Cornell box by default.
    pub scene: SceneChoice,
    /// The camera, including the image size.
    pub camera: Camera,
    pub light: LightSpec,
    pub shading: Shading,
    /// Mirror, glass or rough metal for the Cornell box's blocks (none: the lab's diffuse box).
    pub material_preset: MaterialPreset,
    /// The GGX roughness α of the rough preset's metal (0.2 by default; in (0, 1]).
    pub roughness: f32,
    /// Parts of the box given materials of their own, over the preset's (`--material`, the
    /// workbench's material editor). Written only when there are some.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub part_materials: Vec<PartMaterial>,
    /// Textures for the Cornell box's floor and walls (none: the lab's plain colours).
    pub texture_preset: TexturePreset,
    /// How linear values are shown and written to PNG (the lab's clamp by default). Changing
    /// it never re-traces: the renderer ignores it.
    pub display: Display,
    /// What the workbench shows: the shaded image (the default) or a debug view of the same
    /// scene and camera ([`crate::transport::view`]). `render` ignores it; the command line's `--view`
    /// chooses.
    pub view: View,
    /// Samples per pixel to accumulate; 1 traces each pixel's centre (the lab's image), more
    /// jitter inside the pixel and average (anti-aliasing).
    pub samples_per_pixel: u32,
    /// Seed of every random choice; the same seed gives the same image.
    pub seed: u64,
    /// Whether the image is the denoiser's ([`crate::transport::denoise`]) rather than the accumulated
    /// mean: [`crate::transport::render::render`] ignores it; the command line's `render` writes the
    /// denoised image when it is set (`--denoise on`), and a workbench screenshot of a denoised
    /// image carries it, so that its settings reproduce what was saved. Written only when set.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub denoise: bool,
    /// A student's own equations (the equation sandbox, [`crate::teaching::sandbox`]), each quantity's
    /// text in place of the lab's: the command line's `render` renders them when given, and
    /// screenshots and scene files carry them. [`crate::transport::render::render`] ignores them.
    /// Written only when there are some.
    #[serde(skip_serializing_if = "EquationTexts::is_empty")]
    pub equations: EquationTexts,
}

impl Default for RenderSettings {
    /// Figure 7 of the lab at 512 × 512.
    fn default() -> Self {
        Self {
            scene: SceneChoice::Cornell,
            camera: Camera::default(),
            light: LightSpec::default(),
            shading: Shading::default(),
            material_preset: MaterialPreset::None,
            roughness: DEFAULT_ROUGHNESS,
            part_materials: Vec::new(),
            texture_preset: TexturePreset::None,
            display: Display::default(),
            view: View::Shaded,
            samples_per_pixel: 1,
            seed: 0,
            denoise: false,
            equations: EquationTexts::default(),
        }
    }
}

/// What [`RenderSettings::memory_estimate`] allows for the program itself: its code, its
/// threads' stacks and its allocator's first reserves (a small render runs well within it).
pub const BASE_MEMORY: u64 = 64 << 20;

impl RenderSettings {
    /// Whether anything draws random numbers: the path tracer, a spherical or quad light's soft
    /// shadows, a thin lens's aperture. Each pass is then a noisy estimate, and the denoiser
    /// ([`crate::transport::denoise`]) has something to remove; otherwise passes differ only in where
    /// in the pixel they look (anti-aliasing).
    pub fn is_stochastic(&self) -> bool {
        self.shading.stage.integrator() == Integrator::Path
            || self.light.is_area()
            || self.camera.aperture > 0.0
    }

    /// The memory a render of these settings needs at its peak, in bytes, as the command line
    /// makes it: the shaded image (`view` [`View::Shaded`], whatever the sample count) or a
    /// debug view. A rough upper bound, for refusing early what cannot fit
    /// ([`crate::base::memory::check`]), counted as:
    ///
    /// * per pixel, what lives together at the peak: the shaded image is one linear float
    ///   image, 12 bytes a pixel, which the passes are summed into row by row
    ///   ([`crate::transport::render::try_render`]) and which PNG and EXR files are encoded from a band
    ///   of rows at a time ([`crate::transport::film::Image::save_with`]); a debug view holds its raw
    ///   values beside its image ([`View::bytes_per_pixel`]);
    /// * the scene ([`SceneChoice::memory_estimate`]);
    /// * [`BASE_MEMORY`] for the program.
    ///
    /// A 16384 × 16384 render: 268,435,456 pixels × 12 bytes = 3.0 GiB, plus 64 MiB: 3.1 GiB.
    pub fn memory_estimate(&self, view: View) -> u64 {
        let pixels = u64::from(self.camera.width) * u64::from(self.camera.height);
        pixels * view.bytes_per_pixel() + self.scene.memory_estimate() + BASE_MEMORY
    }

    /// Whether `other` renders the same linear image: equal but perhaps for the display
    /// transform and exposure, which change only how the image is shown.
    pub fn renders_like(&self, other: &RenderSettings) -> bool {
        let mut same_display = self.clone();
        same_display.display = other.display;
        same_display == *other
    }

    /// Reads settings from JSON text: a workbench screenshot's sidecar (whose `settings` field
    /// holds them) or a bare settings object. Missing fields take the lab's defaults. The values
    /// are not checked: call [`RenderSettings::validate`] before rendering.
    ///
    /// Here rather than in the command line so the settings-file fuzz target
    /// (`fuzz/fuzz_targets/settings_json.rs`) runs exactly what `--settings FILE` runs.
    pub fn from_json(text: &str) -> Result<Self, String> {
        from_json(text).map(|loaded| loaded.settings)
    }

    /// The settings as a file written into `folder` holds them (a screenshot's text, its
    /// `.json`, a scene file): each model's path relative to `folder`
    /// ([`crate::shapes::scene::spec::path_relative_to`]), so the file names the same models wherever
    /// it is read from ([`RenderSettings::resolve_paths`]).
    pub fn relative_to(&self, folder: &std::path::Path) -> RenderSettings {
        let mut settings = self.clone();
        match &mut settings.scene {
            SceneChoice::Obj(path) => {
                *path = crate::shapes::scene::spec::path_relative_to(path, folder);
            }
            SceneChoice::Custom(spec) => crate::shapes::scene::spec::relative_models(spec, folder),
            _ => {}
        }
        settings
    }

    /// Settings read from a file in `folder`: relative model paths are taken from that folder
    /// (the inverse of [`RenderSettings::relative_to`]).
    pub fn resolve_paths(&mut self, folder: &std::path::Path) {
        match &mut self.scene {
            SceneChoice::Obj(path) => {
                *path = crate::shapes::scene::spec::resolve_path(path, folder)
            }
            SceneChoice::Custom(spec) => crate::shapes::scene::spec::resolve_models(spec, folder),
            _ => {}
        }
    }

    /// One line naming what most often explains a render: the scene, stage and switches,
    /// resolution, camera, light, samples and seed. For error reports (a render that panicked
    /// says which settings did it); the JSON (`serde_json::to_string`) has everything.
    pub fn summary(&self) -> String {
        let (c, l, s) = (&self.camera, &self.light, &self.shading);
        let on = |b: bool| if b { "on" } else { "off" };
        let v = |v: Vec3| format!("({}, {}, {})", v.x, v.y, v.z);
        format!(
            "scene {}, stage {} (shadows {}, indirect {}), {}×{}, camera {} yaw {}° pitch {}° \
             f {} px, light {} {} W, {} spp, seed {}",
            self.scene,
            s.stage,
            on(s.shadows),
            on(s.indirect),
            c.width,
            c.height,
            v(c.position),
            crate::base::camera::degrees(c.yaw),
            crate::base::camera::degrees(c.pitch),
            c.focal_length,
            v(l.position),
            l.power,
            self.samples_per_pixel,
            self.seed,
        )
    }

    /// What a render of these settings computes: the stage and its switches in the lab's
    /// terms ([`Shading::description`]), then one short clause for each extension that changes
    /// it: textures (where ρ is used), an area light (the lab stages soften their shadows with
    /// it; the path tracer sees it whole), a coloured light, depth of field, and the lab stages'
    /// anti-aliasing over more than one sample. An extension that does nothing in the stage
    /// (the light in the flat stage, ρ in the incoming-light stage) is not named.
    pub fn description(&self) -> String {
        let s = &self.shading;
        let mut text = s.description(self.material_preset);
        let lit = s.stage != Stage::Flat;
        let mut add = |clause: String| {
            text.push_str(" · ");
            text.push_str(&clause);
        };
        if let Some(water) = self.scene.spec().water
            && s.stage != Stage::Flat
        {
            add(if water.waves > 0.0 {
                "water: Fresnel reflection and refraction about fractal waves".to_owned()
            } else {
                "water: Fresnel reflection and refraction".to_owned()
            });
        }
        match self.texture_preset {
            TexturePreset::None => {}
            // A normal changes the light (equation 27), so even the incoming-light stage.
            TexturePreset::BumpyWalls if lit => add("normal-mapped walls".to_owned()),
            // Shifts ρ's coordinates and tilts the normal: something in every stage.
            TexturePreset::ParallaxFloor => add(if lit && s.parallax_shadows {
                "parallax-mapped floor, self-shadowed".to_owned()
            } else {
                "parallax-mapped floor".to_owned()
            }),
            TexturePreset::Clouds if s.stage != Stage::Incoming => {
                add("ρ of fBm clouds on the ceiling".to_owned())
            }
            TexturePreset::CheckerFloor | TexturePreset::GridWalls | TexturePreset::Both
                if s.stage != Stage::Incoming =>
            {
                add("textured ρ".to_owned())
            }
            _ => {}
        }
        // The light's kind and parameters, as `light_kinds!` names them.
        let light = format!(
            "a {} light with {}",
            self.light.kind.name(),
            self.light
                .kind
                .params_and_values()
                .map(|(p, value)| {
                    let shown = match (p.ty, value) {
                        (ParamType::Angle, ParamValue::Number(a)) => {
                            format!("{}°", short(crate::base::camera::degrees(a) as f32))
                        }
                        (_, ParamValue::Number(x)) => short(x),
                        (_, ParamValue::Point(v)) => {
                            format!("({}, {}, {})", short(v.x), short(v.y), short(v.z))
                        }
                    };
                    format!("{} {shown}", p.name)
                })
                .collect::<Vec<_>>()
                .join(", ")
        );
        if lit && self.light.is_area() {
            if s.stage == Stage::Path {
                add(format!("{light}, seen and sampled"));
            } else if s.shadows {
                add(format!("soft shadows from {light}"));
            }
        } else if lit
            && self.light.kind.size_param().is_none()
            && !self.light.kind.params().is_empty()
        {
            // A kind with parameters but no size (the spot) changes the light wherever it is.
            add(light);
        }
        if lit && self.light.colour != Vec3::ONE {
            add("coloured light".to_owned());
        }
        if self.camera.aperture > 0.0 {
            add(format!(
                "depth of field (aperture {})",
                short(self.camera.aperture)
            ));
        }
        if s.photon_caustics() {
            add("caustics by photon mapping".to_owned());
        }
        if self.samples_per_pixel > 1 && s.stage != Stage::Path {
            add(format!(
                "anti-aliased over {} samples",
                self.samples_per_pixel
            ));
        }
        text
    }

    /// Checks every value before a render: sizes in 1..=16384, finite numbers, a positive focal
    /// length, light power, colour and indirect light from 0 to their maxima, 1..=65536
    /// samples.
    ///
    /// **Why the light has a maximum.** Finite is not enough: a light of 1e38 W, or N = 1e38,
    /// made infinite pixels (written to EXR files as ∞). The bounds keep every value a render
    /// makes below `f32::MAX` (3.4e38), with room to spare:
    ///
    /// * D (equation 27) is at most P · c / (4π r²) with r never below
    ///   [`MIN_LIGHT_DISTANCE`](crate::shading::light::MIN_LIGHT_DISTANCE) (1e−3): at most
    ///   1e6 W · 1000 / (4π · 1e−6) = 8.0e13 with the largest power and colour.
    /// * Every reflectance ρ is at most 1, so a lab stage's value, ρ·(D + N) or D + N, is at
    ///   most 8.0e13 + 1e6; mirror and glass branches split a weight of at most 1.
    /// * The path tracer adds ρ·D at each of at most
    ///   [`MAX_DEPTH`](crate::transport::integrator::path::MAX_DEPTH) = 256 vertices, weighted by a
    ///   throughput that Russian roulette raises by at most 1/0.95 a vertex: at most
    ///   256 · 0.95^−253 · 8.0e13 ≈ 9e21.
    /// * A pixel sums up to 65,536 samples before dividing: at most 6e26. The display
    ///   multiplies by at most 2^20 (+20 EV) and its curves take any finite value.
    ///
    /// **Why an area light has a smallest size.** A sphere of radius R has the radiance
    /// `π L = P·c / (4π R²)` (lab units), a square of side S `π L = P·c / S²`
    /// (`light/sphere.rs`, `quad.rs`). With R = S = [`MIN_LIGHT_SIZE`] = 1e−3 and the largest
    /// power and colour:
    ///
    /// * the sphere's `π L` is at most 1e9 / (4π · 1e−6) = 8.0e13, the point light's largest
    ///   D above (a sphere is as bright at its surface as the point light at distance R); the
    ///   square's is at most 1e9 / 1e−6 = 1e15;
    /// * the sphere's sampling density (`SphereLight::cone_pdf`) is `1 / (2π (1 − cos θmax))`
    ///   with `sin² θmax = R² / d²`: at least 1/(2π), so a light sample `li · cos θ / pdf` is
    ///   at most 2π · 8.0e13 = 5.0e14; with d at most 2√3 · 1e6 (positions within 1e6),
    ///   `sin² θmax` is at least 1e−6 / 1.2e13 = 8.3e−20, a normal `f32`, and the density
    ///   at most 1/(π · 8.3e−20) = 3.8e18, whose square (the power heuristic) is 1.5e37;
    /// * the square's density `d² / (S² cos θ)` (`QuadLight::solid_angle_pdf`) is at most
    ///   1.2e19 / cos θ, and its light sample `li · cos θ / pdf = P·c cos θ cos θ' / d²`
    ///   does not depend on S; where a grazing cos θ makes the density ∞ the sample is 0 and
    ///   the power heuristic gives that strategy all of the weight (`power_heuristic`);
    /// * a path's value is then at most 256 · 0.95^−253 · 1e15 ≈ 1.1e23 a sample, 7.4e27
    ///   summed over 65,536 samples: finite.
    ///
    /// Far below 1e−3 it fails: the sphere's radiance overflows to ∞ below R ≈ 5e−16 with the
    /// largest power (with the lab's 14 W between 1e−19 and 5e−20), and for a far light
    /// `R² / d²` is 0 (the density ∞) below R ≈ 1e−16; either makes ∞ · 0, NaN pixels. A
    /// light that small is the point light (size 0).
    ///
    /// So the image, its sums and the EXR file are always finite; outputs are not clamped.
    pub fn validate(&self) -> Result<(), SettingsError> {
        match &self.scene {
            SceneChoice::Custom(spec) => spec.validate()?,
            SceneChoice::Obj(path) => check_path("model path", path)?,
            _ => {}
        }
        let c = &self.camera;
        check_side("width", c.width)?;
        check_side("height", c.height)?;
        check_position("camera position", c.position)?;
        check_finite("yaw", c.yaw)?;
        check_finite("pitch", c.pitch)?;
        check_finite("focal length", c.focal_length)?;
        if c.focal_length <= 0.0 {
            return Err(err("focal length", c.focal_length, "must be > 0"));
        }
        if c.focal_length < MIN_FOCAL_LENGTH {
            let f = number(c.focal_length);
            return Err(err("focal length", f, "must be at least 0.001 px"));
        }
        if c.focal_length > MAX_FOCAL_LENGTH {
            let f = c.focal_length;
            return Err(err("focal length", f, "must be at most 1e7 px"));
        }
        check_position("light position", self.light.position)?;
        check_finite("aperture", c.aperture)?;
        if c.aperture < 0.0 {
            return Err(err("aperture", c.aperture, "must be ≥ 0"));
        }
        if c.aperture > MAX_APERTURE {
            let a = number(c.aperture);
            return Err(err("aperture", a, "must be at most 1000 (scene units)"));
        }
        check_finite("focus distance", c.focus_distance)?;
        if c.focus_distance <= 0.0 {
            return Err(err("focus distance", c.focus_distance, "must be > 0"));
        }
        if c.focus_distance > MAX_FOCUS_DISTANCE {
            let d = number(c.focus_distance);
            return Err(err(
                "focus distance",
                d,
                "must be at most 1e6 (scene units)",
            ));
        }
        let light = &self.light;
        check_finite("light power", light.power)?;
        if light.power < 0.0 {
            return Err(err("light power", light.power, "must be ≥ 0"));
        }
        if light.power > MAX_LIGHT_POWER {
            let p = number(light.power);
            return Err(err(
                "light power",
                p,
                "must be at most 1e6 W (--light-power ≤ 1e6)",
            ));
        }
        check_vec("light colour", light.colour)?;
        if light.colour.min_element() < 0.0 {
            return Err(err("light colour", light.colour, "must be ≥ 0"));
        }
        if light.colour.max_element() > MAX_LIGHT_COLOUR {
            let c = vector(light.colour);
            return Err(err("light colour", c, "each channel must be at most 1000"));
        }
        check_light_size(light)?;
        check_roughness("roughness", self.roughness)?;
        let parts = &self.part_materials;
        PartMaterial::validate(parts, |i, f| format!("{} material's {f}", parts[i].part))?;
        check_finite("exposure", self.display.exposure)?;
        if self.display.exposure.abs() > MAX_EXPOSURE {
            return Err(err(
                "exposure",
                self.display.exposure,
                "must be between −20 and 20 stops",
            ));
        }
        check_vec("indirect light", self.shading.indirect_light)?;
        if self.shading.indirect_light.min_element() < 0.0 {
            let n = self.shading.indirect_light;
            return Err(err("indirect light", n, "must be ≥ 0"));
        }
        if self.shading.indirect_light.max_element() > MAX_INDIRECT_LIGHT {
            let n = vector(self.shading.indirect_light);
            return Err(err(
                "indirect light",
                n,
                "must be at most 1e6 (--indirect ≤ 1e6)",
            ));
        }
        if self.shading.specular_depth > MAX_SPECULAR_DEPTH {
            let d = self.shading.specular_depth;
            return Err(err("specular depth", d, "must be at most 12"));
        }
        if !(1..=MAX_PHOTONS).contains(&self.shading.photons) {
            let n = self.shading.photons;
            return Err(err(
                "photons per pass",
                n,
                "must be between 1 and 10000000 (--photons)",
            ));
        }
        if !(1..=MAX_SAMPLES).contains(&self.samples_per_pixel) {
            let s = self.samples_per_pixel;
            return Err(err("samples per pixel", s, "must be between 1 and 65536"));
        }
        Ok(())
    }
}

/// A length for a sentence: at most three decimals, without trailing zeros (0.15, 0.1, 2).
fn short(v: f32) -> String {
    let text = format!("{v:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_owned()
    } else {
        text.to_owned()
    }
}

/// The GGX roughness α a rough metal may have: from [`MIN_ROUGHNESS`] (nearly a mirror; below
/// it the microfacet distribution's peak exceeds what `f32` evaluates well) to 1.
pub fn check_roughness(name: &'static str, alpha: f32) -> Result<(), SettingsError> {
    if !(MIN_ROUGHNESS..=1.0).contains(&alpha) {
        return Err(err(name, alpha, "must be between 0.01 and 1"));
    }
    Ok(())
}

fn err(name: &'static str, value: impl std::fmt::Display, reason: &'static str) -> SettingsError {
    SettingsError {
        name: name.into(),
        value: value.to_string(),
        reason,
    }
}

/// A number as a person would write it: 1e38, not 100000000000000000000000000000000000000,
/// and 1e-23, not 0.00000000000000000000001.
fn number(x: f32) -> String {
    if x.abs() >= 1e7 || (x != 0.0 && x.abs() < 1e-4) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

/// A vector as [`number`] writes its components.
fn vector(v: Vec3) -> String {
    format!("({}, {}, {})", number(v.x), number(v.y), number(v.z))
}

fn check_side(name: &'static str, side: u32) -> Result<(), SettingsError> {
    if (1..=MAX_IMAGE_SIDE).contains(&side) {
        Ok(())
    } else {
        Err(err(name, side, "must be between 1 and 16384"))
    }
}

fn check_finite(name: &'static str, x: f32) -> Result<(), SettingsError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(err(name, x, "must be a finite number"))
    }
}

fn check_vec(name: &'static str, v: Vec3) -> Result<(), SettingsError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(err(name, v, "must be finite"))
    }
}

/// The light's parameters (`light_kinds!`), each by its type and bounds, then the rules
/// between them ([`crate::shading::light::LightKind::check_rules`]). A size (a sphere's radius, a square's side): 0
/// (the lab's point light) or from [`MIN_LIGHT_SIZE`] to [`MAX_LIGHT_SIZE`]. A point (a spot's
/// aim): finite and within [`MAX_COORDINATE`]. An angle: finite and within its bounds (a
/// spot's cutoff above 0 and below 90°).
fn check_light_size(light: &LightSpec) -> Result<(), SettingsError> {
    for (p, value) in light.kind.params_and_values() {
        match (p.ty, value) {
            (ParamType::Size, ParamValue::Number(size)) => check_size(p.noun, size)?,
            (ParamType::Angle, ParamValue::Number(a)) if !a.is_finite() => {
                return Err(err(p.noun, a, "must be a finite number"));
            }
            (_, ParamValue::Point(v)) => check_position(p.noun, v)?,
            (ParamType::Angle | ParamType::Point, ParamValue::Number(_)) => {}
        }
        p.check_bounds(value)?;
    }
    light.kind.check_rules(light.position)
}

/// An area light's size, called `name` in errors (see [`check_light_size`]).
fn check_size(name: &'static str, size: f32) -> Result<(), SettingsError> {
    check_finite(name, size)?;
    if size < 0.0 {
        return Err(err(name, number(size), "must be ≥ 0"));
    }
    if size == 0.0 {
        return Ok(());
    }
    if !(MIN_LIGHT_SIZE..=MAX_LIGHT_SIZE).contains(&size) {
        return Err(err(
            name,
            number(size),
            "must be 0 (the point light) or between 0.001 and 1e6 (scene units): a smaller \
             sphere or square is brighter than the light's bounds allow; for a light that \
             small use the point light (--light-shape point)",
        ));
    }
    Ok(())
}

/// A camera's or light's position: finite and within [`MAX_COORDINATE`] on each axis.
fn check_position(name: &'static str, v: Vec3) -> Result<(), SettingsError> {
    check_vec(name, v)?;
    if v.abs().max_element() > MAX_COORDINATE {
        return Err(err(
            name,
            vector(v),
            "must lie within 1e6 of the origin on each axis",
        ));
    }
    Ok(())
}

/// Settings read from a file, and what in it was not understood.
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    pub settings: RenderSettings,
    /// One line per thing ignored (an unknown field).
    pub warnings: Vec<String>,
}

/// Parses settings JSON: a screenshot sidecar (whose `settings` field holds them) or a bare
/// settings object. Lenient where a scene file is strict
/// ([`crate::files::settings_file`]'s module docs say how).
pub fn from_json(text: &str) -> Result<Loaded, String> {
    use serde::de::DeserializeSeed as _;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut json = serde_json::Deserializer::from_str(text);
    let mut value = UniqueKeys(String::new())
        .deserialize(&mut json)
        .and_then(|value| json.end().map(|()| value))
        .map_err(|e| e.to_string())?;
    if let Some(inner) = value.get_mut("settings") {
        value = inner.take();
    }
    if let Some(camera) = value.get_mut("camera").and_then(|c| c.as_object_mut())
        && !camera.contains_key("focal_length")
        && let Some(width) = camera.get("width").and_then(serde_json::Value::as_u64)
    {
        // `Camera::default_for(width, …)`: f = W, the lab's 53.13° across.
        camera.insert("focal_length".to_owned(), serde_json::json!(width as f32));
    }
    let mut warnings = Vec::new();
    let settings = serde_ignored::deserialize(value, |path| {
        warnings.push(format!("unknown field `{path}` ignored"));
    })
    .map_err(|e: serde_json::Error| e.to_string())?;
    Ok(Loaded { settings, warnings })
}

/// JSON read as a [`serde_json::Value`], but an object that gives a key twice is refused,
/// naming the key by its path (`camera.width`): serde_json keeps the last silently, where a
/// scene file (TOML) refuses a key given twice. `.0` is the path to the value read.
struct UniqueKeys(String);

impl UniqueKeys {
    fn inner(&self, key: impl std::fmt::Display) -> UniqueKeys {
        UniqueKeys(if self.0.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.0)
        })
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for UniqueKeys {
    type Value = serde_json::Value;

    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for UniqueKeys {
    type Value = serde_json::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_i64<E>(self, v: i64) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_u64<E>(self, v: u64) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_f64<E>(self, v: f64) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_str<E>(self, v: &str) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(item) =
            seq.next_element_seed(UniqueKeys(format!("{}[{}]", self.0, items.len())))?
        {
            items.push(item);
        }
        Ok(serde_json::Value::Array(items))
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut object = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            let inner = self.inner(&key);
            if object.contains_key(&key) {
                return Err(serde::de::Error::custom(format_args!(
                    "duplicate key `{}`: each setting may be given once",
                    inner.0
                )));
            }
            let value = map.next_value_seed(inner)?;
            object.insert(key, value);
        }
        Ok(serde_json::Value::Object(object))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::light::LightKind;

    /// The description names each extension in force, once, and none that does nothing in
    /// the stage.
    /// The Computes line gives a dragged spot's aim and angles to three decimals, not every
    /// digit of the f32 the drag left.
    #[test]
    fn the_spot_in_the_description_is_rounded() {
        use crate::shading::light::SpotCone;
        let mut s = RenderSettings::default();
        s.light.kind = LightKind::Spot(SpotCone {
            aim: Vec3::new(0.370_090_34, 0.995_348_4, -0.200_000_05),
            cutoff: crate::base::camera::radians(25.346_7),
            beam: crate::base::camera::radians(15.0),
        });
        let text = s.description();
        assert!(
            text.contains("a spot light with aim (0.37, 0.995, -0.2), cutoff 25.347°, beam 15°"),
            "{text}"
        );
    }

    #[test]
    fn the_description_names_the_extensions() {
        let mut s = RenderSettings::default();
        assert_eq!(s.description(), "ρ·(D + N) (eq. 30) with shadows (§5.1)");
        s.texture_preset = TexturePreset::CheckerFloor;
        s.light.kind = LightKind::Sphere { radius: 0.15 };
        s.camera.aperture = 0.1;
        s.light.colour = Vec3::new(1.0, 0.5, 0.2);
        s.samples_per_pixel = 16;
        assert_eq!(
            s.description(),
            "ρ·(D + N) (eq. 30) with shadows (§5.1) · textured ρ · soft shadows from a sphere \
             light with radius 0.15 · coloured light · depth of field (aperture 0.1) · anti-aliased over 16 \
             samples"
        );
        // Without shadows the lab stages take the light from its centre: its size does nothing.
        s.shading.shadows = false;
        assert!(!s.description().contains("radius"), "{}", s.description());
        // The flat stage computes no light; the incoming light no ρ.
        s.shading = Shading::for_stage(Stage::Flat);
        assert_eq!(
            s.description(),
            "ρ, the reflectance · textured ρ · depth of field (aperture 0.1) · anti-aliased \
             over 16 samples"
        );
        s.shading = Shading::for_stage(Stage::Incoming);
        assert!(!s.description().contains("textured"), "{}", s.description());
        // The path tracer sees the area light itself; its samples are not anti-aliasing alone.
        s.shading = Shading::for_stage(Stage::Path);
        s.light.kind = LightKind::Quad { side: 0.15 };
        let path = s.description();
        assert!(
            path.contains("· a quad light with side 0.15, seen and sampled"),
            "{path}"
        );
        assert!(!path.contains("anti-aliased"), "{path}");
        s.material_preset = MaterialPreset::Mirror;
        assert!(s.description().contains("; mirror tall block sampled"));
        s.shading = Shading::for_stage(Stage::Lab);
        assert!(
            s.description()
                .contains("; mirror tall block followed up to 6 deep (Whitted)")
        );
        s.material_preset = MaterialPreset::Rough;
        assert!(s.description().contains("GGX highlight"));
        // The relief presets: a normal changes D, so the incoming-light stage names it; the
        // flat stage shows ρ alone, which a normal map does not change but parallax moves.
        let mut s = RenderSettings {
            texture_preset: TexturePreset::BumpyWalls,
            ..RenderSettings::default()
        };
        assert_eq!(
            s.description(),
            "ρ·(D + N) (eq. 30) with shadows (§5.1) · normal-mapped walls"
        );
        s.shading = Shading::for_stage(Stage::Incoming);
        assert!(s.description().ends_with(" · normal-mapped walls"));
        s.shading = Shading::for_stage(Stage::Flat);
        assert!(!s.description().contains("normal"), "{}", s.description());
        s.texture_preset = TexturePreset::ParallaxFloor;
        assert!(s.description().ends_with(" · parallax-mapped floor"));
    }

    #[test]
    fn defaults_are_valid_and_round_trip_through_json() {
        let s = RenderSettings::default();
        s.validate().unwrap();
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<RenderSettings>(&json).unwrap(), s);
        // A partial file keeps the defaults for what it lacks.
        let partial: RenderSettings =
            serde_json::from_str(r#"{"light": {"position": [0.5, 0.0, 0.0]}}"#).unwrap();
        assert_eq!(partial.light.position, Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(partial.light.channel_power(), Vec3::splat(14.0));
        assert_eq!(partial.camera, Camera::default());
    }

    #[test]
    fn json_text_is_a_sidecar_or_bare_settings() {
        let mut s = RenderSettings::default();
        s.seed = 7;
        s.camera = s.camera.with_resolution(64, 32);
        let bare = serde_json::to_string(&s).unwrap();
        assert_eq!(RenderSettings::from_json(&bare).unwrap(), s);
        let sidecar = format!(r#"{{"png": "x.png", "settings": {bare}}}"#);
        assert_eq!(RenderSettings::from_json(&sidecar).unwrap(), s);
        assert_eq!(
            RenderSettings::from_json("{}").unwrap(),
            RenderSettings::default()
        );
        assert!(RenderSettings::from_json("{").is_err());
        assert!(RenderSettings::from_json(r#"{"samples_per_pixel": -1}"#).is_err());
        assert!(RenderSettings::from_json("[1, 2]").is_err());
    }

    #[test]
    fn the_summary_names_what_explains_a_render() {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(128, 96);
        s.seed = 3;
        assert_eq!(
            s.summary(),
            "scene cornell, stage lab (shadows on, indirect on), 128×96, camera (0, 0, -3.001) \
             yaw 0° pitch 0° f 128 px, light (0, -0.5, -0.7) 14 W, 1 spp, seed 3"
        );
        // Angles as they were typed (15°, not the f32's 15.000001°).
        s.camera.yaw = 15f32.to_radians();
        s.camera.pitch = crate::base::camera::radians(-2.5);
        assert!(
            s.summary().contains("yaw 15° pitch -2.5° "),
            "{}",
            s.summary()
        );
    }

    #[test]
    fn the_display_does_not_change_the_render() {
        let a = RenderSettings::default();
        let mut b = a.clone();
        b.display.exposure = 2.0;
        b.display.transform = crate::transport::display::DisplayTransform::Filmic;
        assert!(a.renders_like(&b) && b.renders_like(&a));
        b.light.kind = LightKind::Sphere { radius: 0.1 };
        assert!(!a.renders_like(&b));
    }

    #[test]
    fn bad_values_are_named() {
        let mut s = RenderSettings::default();
        s.camera.width = 0;
        assert_eq!(s.validate().unwrap_err().name, "width");
        let mut s = RenderSettings::default();
        s.camera.height = 16_385;
        assert_eq!(s.validate().unwrap_err().name, "height");
        let mut s = RenderSettings::default();
        s.camera.focal_length = -1.0;
        assert_eq!(s.validate().unwrap_err().name, "focal length");
        // 2e19 px would overflow the rays' squared length: refused, not a black image.
        s.camera.focal_length = 2e19;
        assert_eq!(s.validate().unwrap_err().name, "focal length");
        // 1e−23 px would underflow it: the centre ray of an odd-sized image, (0, 0, f), has a
        // squared length of 0 in f32, so it cannot be normalised (it was a black pixel).
        s.camera = Camera::default_for(5, 5);
        s.camera.focal_length = 1e-23;
        let centre = s.camera.pixel_ray(2, 2);
        assert!(!centre.direction.is_normalized(), "{centre:?}");
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid focal length 1e-23: must be at least 0.001 px"
        );
        s.camera.focal_length = MIN_FOCAL_LENGTH;
        s.validate().unwrap();
        let centre = s.camera.pixel_ray(2, 2);
        assert!(centre.direction.is_normalized(), "{centre:?}");
        assert_eq!(centre.direction, glam::Vec3::Z);
        let mut s = RenderSettings::default();
        s.light.position.y = f32::NAN;
        let e = s.validate().unwrap_err();
        assert_eq!(e.name, "light position");
        assert!(e.to_string().contains("NaN"), "{e}");
        let mut s = RenderSettings::default();
        s.camera.yaw = f32::INFINITY;
        assert_eq!(s.validate().unwrap_err().name, "yaw");
    }

    /// A focus distance, aperture or position far enough out to overflow `f32` in the lens ray
    /// or in r² is refused (each made a silently black image); each bound itself renders.
    #[test]
    fn lens_and_positions_beyond_their_bounds_are_refused() {
        let msg = |f: &dyn Fn(&mut RenderSettings)| {
            let mut s = RenderSettings::default();
            f(&mut s);
            s.validate().map_err(|e| e.to_string())
        };
        assert_eq!(
            msg(&|s| s.camera.focus_distance = 1e38),
            Err("invalid focus distance 1e38: must be at most 1e6 (scene units)".into())
        );
        assert_eq!(
            msg(&|s| s.camera.aperture = 1e30),
            Err("invalid aperture 1e30: must be at most 1000 (scene units)".into())
        );
        assert_eq!(
            msg(&|s| s.camera.position.x = -3e38),
            Err(
                "invalid camera position (-3e38, 0, -3.001): must lie within 1e6 of the \
                 origin on each axis"
                    .into()
            )
        );
        assert_eq!(
            msg(&|s| s.light.position.z = 1e20),
            Err(
                "invalid light position (0, -0.5, 1e20): must lie within 1e6 of the origin \
                 on each axis"
                    .into()
            )
        );
        // The bounds themselves, with the shortest focal length (the lens ray's aim point is
        // d·F/f, largest there): every pixel's lens ray is finite and normalised.
        let mut s = RenderSettings::default();
        s.camera = Camera::default_for(9, 9);
        s.camera.focus_distance = MAX_FOCUS_DISTANCE;
        s.camera.aperture = MAX_APERTURE;
        s.camera.focal_length = MIN_FOCAL_LENGTH;
        s.camera.position = glam::Vec3::splat(-MAX_COORDINATE);
        s.light.position = glam::Vec3::splat(MAX_COORDINATE);
        s.validate().unwrap();
        let rotation = s.camera.rotation();
        for (px, py) in [(0.0, 0.0), (9.0, 9.0), (4.5, 0.0)] {
            let ray = s
                .camera
                .lens_ray_rotated(&rotation, px, py, glam::Vec2::new(1.0, 0.0));
            assert!(ray.direction.is_normalized(), "{ray:?}");
            assert!(ray.origin.is_finite(), "{ray:?}");
        }
    }

    /// Huge but finite light is refused above its bound, naming the field and the bound
    /// (without them 1e38 W and N = 1e38 wrote ∞ to EXR files); the bounds themselves
    /// are allowed.
    #[test]
    fn light_beyond_its_bounds_is_refused_naming_the_bound() {
        let mut s = RenderSettings::default();
        s.light.power = 1e38;
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid light power 1e38: must be at most 1e6 W (--light-power ≤ 1e6)"
        );
        s.light.power = MAX_LIGHT_POWER;
        s.light.colour = Vec3::new(1.0, 2e3, 0.0);
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid light colour (1, 2000, 0): each channel must be at most 1000"
        );
        s.light.colour = Vec3::splat(MAX_LIGHT_COLOUR);
        s.shading.indirect_light = Vec3::splat(1e38);
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid indirect light (1e38, 1e38, 1e38): must be at most 1e6 (--indirect ≤ 1e6)"
        );
        s.shading.indirect_light = Vec3::splat(MAX_INDIRECT_LIGHT);
        s.validate().unwrap();
    }

    /// An area light too small for its radiance or sampling density to be an `f32` is
    /// refused, naming the bound, for both shapes (a sphere of 1e−30 made 1,713 of a 24²
    /// image's 1,728 values NaN; 1e−19 to 5e−20 made them ∞); so is one too large for its
    /// area. Size 0 and the bounds themselves are allowed.
    #[test]
    fn an_area_light_too_small_or_too_large_is_refused() {
        use crate::shading::light::LightShape;
        for shape in [LightShape::Sphere, LightShape::Quad] {
            for size in [1e-30, 5e-20, 1e-19, 1e-16, 1e-8, 9.9e-4, 1.1e6, 1e30] {
                let mut s = RenderSettings::default();
                s.light.kind = LightKind::sized(shape, size);
                let e = s.validate().unwrap_err();
                assert_eq!(e.name, "light size", "{shape} {size}");
                assert_eq!(e.value, number(size));
                assert!(
                    e.reason.starts_with(
                        "must be 0 (the point light) or between 0.001 and 1e6 (scene units)"
                    ),
                    "{e}"
                );
            }
            for size in [0.0, MIN_LIGHT_SIZE, 0.1, MAX_LIGHT_SIZE] {
                let mut s = RenderSettings::default();
                s.light.kind = LightKind::sized(shape, size);
                s.validate().unwrap();
            }
        }
        let mut s = RenderSettings::default();
        s.light.kind = LightKind::Sphere { radius: 1e-30 };
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid light size 1e-30: must be 0 (the point light) or between 0.001 and 1e6 \
             (scene units): a smaller sphere or square is brighter than the light's bounds \
             allow; for a light that small use the point light (--light-shape point)"
        );
    }

    /// A size given to a point light is refused with what to do instead (it silently made a
    /// sphere, and a saved scene said `shape = "point"` with `radius = 0.3`); size 0 is the
    /// point light itself. A file written before lights had shapes means a sphere by a
    /// radius: still read so.
    #[test]
    fn a_point_light_with_a_size_is_refused() {
        let old = from_json(r#"{"light": {"radius": 0.3}}"#).unwrap().settings;
        assert_eq!(old.light.kind, LightKind::Sphere { radius: 0.3 });
        old.validate().unwrap();
        let e = from_json(r#"{"light": {"radius": 0.3, "shape": "point"}}"#).unwrap_err();
        assert!(
            e.to_string().contains(
                "a point light has no size: for an area light of this size choose the shape \
                 sphere or quad (--light-shape), or give the size 0"
            ),
            "{e}"
        );
        let zero = from_json(r#"{"light": {"radius": 0, "shape": "point"}}"#).unwrap();
        assert_eq!(zero.settings.light.kind, LightKind::Point);
    }

    /// A spot light's cone is checked with errors naming the field, in degrees: aimed at its
    /// own position, a cutoff of 0 or of 90° and more, a beam wider than the cutoff, a
    /// coordinate that is not finite. The lab's spot passes.
    #[test]
    fn a_spot_light_out_of_bounds_is_refused() {
        use crate::shading::light::SpotCone;
        let spot = |cone: SpotCone| {
            let mut s = RenderSettings::default();
            s.light.kind = LightKind::Spot(cone);
            s.validate().map_err(|e| e.to_string())
        };
        let lab = SpotCone::default();
        assert_eq!(spot(lab), Ok(()));
        let aim = LightSpec::default().position;
        assert_eq!(
            spot(SpotCone { aim, ..lab }).unwrap_err(),
            "invalid light aim (0, -0.5, -0.7): must be at least 0.001 from the light's \
             position: a spot aimed at itself has no direction (--light-aim)"
        );
        let deg = |d: f64| crate::base::camera::radians(d);
        assert_eq!(
            spot(SpotCone {
                cutoff: deg(90.0),
                ..lab
            })
            .unwrap_err(),
            "invalid spot cutoff 90°: must be above 0° and below 90° (--spot-cutoff)"
        );
        assert!(
            spot(SpotCone {
                cutoff: 0.0,
                beam: 0.0,
                ..lab
            })
            .is_err()
        );
        assert_eq!(
            spot(SpotCone {
                beam: deg(30.0),
                ..lab
            })
            .unwrap_err(),
            "invalid spot beam 30° (cutoff 25°): must be from 0° to the cutoff (--spot-beam, \
             --spot-cutoff)"
        );
        assert!(
            spot(SpotCone {
                aim: Vec3::NAN,
                ..lab
            })
            .is_err()
        );
        assert!(
            spot(SpotCone {
                beam: f32::NAN,
                ..lab
            })
            .is_err()
        );
        assert_eq!(
            spot(SpotCone {
                beam: lab.cutoff,
                ..lab
            }),
            Ok(())
        );
        assert_eq!(spot(SpotCone { beam: 0.0, ..lab }), Ok(()));
    }

    /// The smallest allowed area light with the largest power and colour, a few millimetres
    /// from the floor: every stage (the lab's and the path tracer, its light samples and the
    /// light seen directly), raw and denoised, gives finite pixels. The sphere is as bright at
    /// its surface as the point light is allowed to be (8.0e13 in lab units), the square
    /// 12.6 times that.
    #[test]
    fn the_smallest_allowed_area_light_gives_a_finite_image() {
        use crate::shading::light::LightShape;
        let scene = crate::shapes::scene::cornell_box();
        for shape in [LightShape::Sphere, LightShape::Quad] {
            let mut s = RenderSettings::default();
            s.camera = s.camera.with_resolution(12, 12);
            s.light.position = Vec3::new(0.5, 0.995, 0.3);
            s.light.power = MAX_LIGHT_POWER;
            s.light.colour = Vec3::splat(MAX_LIGHT_COLOUR);
            s.light.kind = LightKind::sized(shape, MIN_LIGHT_SIZE);
            for stage in crate::Stage::ALL {
                s.shading = crate::Shading::for_stage(stage);
                s.shading.indirect = true;
                s.samples_per_pixel = 8;
                s.denoise = true;
                s.validate().unwrap();
                let (raw, denoised) = crate::transport::denoise::render_denoised(&scene, &s);
                let finite = |image: &crate::transport::film::Image| {
                    image.pixels.iter().all(|p| p.is_finite())
                };
                assert!(finite(&raw), "{shape} {stage}: {:?}", raw.pixels);
                let denoised = denoised.expect("an area light is noisy: denoised");
                assert!(finite(&denoised), "{shape} {stage}: {:?}", denoised.pixels);
                if stage != crate::Stage::Flat {
                    let brightest = raw.pixels.iter().map(|p| p.max_element());
                    assert!(brightest.fold(0.0, f32::max) > 1e6, "{shape} {stage}");
                }
            }
        }
    }

    /// The estimate by hand: 16384² pixels × 12 bytes + 64 MiB = 3,288,334,336 bytes for the
    /// Cornell box's shaded image; the normals view adds 16 bytes a pixel (an optional vector);
    /// the terrain adds its 320 MiB.
    #[test]
    fn memory_estimates_by_hand() {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(MAX_IMAGE_SIDE, MAX_IMAGE_SIDE);
        let pixels = 16_384u64 * 16_384;
        assert_eq!(s.memory_estimate(View::Shaded), 3_288_334_336);
        s.samples_per_pixel = 1000;
        assert_eq!(
            s.memory_estimate(View::Shaded),
            3_288_334_336,
            "summed in place"
        );
        assert_eq!(s.memory_estimate(View::Normals), pixels * 28 + BASE_MEMORY);
        s.scene = SceneChoice::Terrain;
        s.camera = s.camera.with_resolution(512, 512);
        assert_eq!(
            s.memory_estimate(View::Shaded),
            512 * 512 * 12 + (320 << 20) + BASE_MEMORY
        );
    }

    /// The largest light and N the bounds allow, the light on a surface (where D is largest:
    /// r counts as 1 mm), the most samples: every pixel and every sum finite, in every stage.
    /// The brightest pixel is the one below the light: D = 1e9 / (4π · 1e−6) = 7.96e13.
    #[test]
    fn the_largest_allowed_light_gives_a_finite_image() {
        let scene = crate::shapes::scene::cornell_box();
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(9, 9);
        // On the floor, clear of both blocks.
        s.light.position = Vec3::new(0.5, 1.0, 0.3);
        s.light.power = MAX_LIGHT_POWER;
        s.light.colour = Vec3::splat(MAX_LIGHT_COLOUR);
        for stage in crate::Stage::ALL {
            // Indirect light on: N in the lab stages, bounces in the path stage.
            s.shading = crate::Shading::for_stage(stage);
            s.shading.indirect = true;
            s.shading.indirect_light = Vec3::splat(MAX_INDIRECT_LIGHT);
            s.samples_per_pixel = if stage == crate::Stage::Path { 64 } else { 1 };
            s.validate().unwrap();
            let image = crate::transport::render::render(&scene, &s);
            assert!(
                image.pixels.iter().all(|p| p.is_finite()),
                "{stage}: {:?}",
                image.pixels
            );
            let brightest = image
                .pixels
                .iter()
                .map(|p| p.max_element())
                .fold(0.0, f32::max);
            if stage != crate::Stage::Flat {
                assert!(brightest > 1e6, "{stage}: {brightest}");
            }
        }
        // The incoming stage (D, no ρ) on a 1 × 1 image looking at (0, −0.8, 1) on the back
        // wall, above both blocks: its one sample's ray (the pixel's centre) meets the wall
        // there. r = (0.5, 1.8, −0.7), r² = 3.98, r̂·n̂ = 0.7/√3.98 = 0.35088,
        // D = 1e9 · 0.35088 / (4π · 3.98) = 7.0156e6.
        s.shading = crate::Shading::for_stage(crate::Stage::Incoming);
        s.camera = s.camera.with_resolution(1, 1);
        s.camera.look_at(Vec3::new(0.0, -0.8, 1.0));
        s.samples_per_pixel = 1;
        let one = crate::transport::render::render(&scene, &s).pixels[0];
        let d = 1e9 * (0.7 / 3.98f64.sqrt()) / (4.0 * std::f64::consts::PI * 3.98);
        assert!(
            (f64::from(one.x) / d - 1.0).abs() < 1e-4,
            "{one} against {d}"
        );
        assert_eq!(one, Vec3::splat(one.x), "white light");
        // Summed over the most samples (jittered across the whole view, each D at most the
        // 8.0e13 derived in `validate`): finite, and a mean of values within that bound.
        s.samples_per_pixel = MAX_SAMPLES;
        let many = crate::transport::render::render(&scene, &s);
        assert!(many.pixels[0].is_finite(), "{}", many.pixels[0]);
        assert!(
            many.pixels[0].min_element() > 0.0 && many.pixels[0].max_element() <= 8.0e13,
            "{}",
            many.pixels[0]
        );
    }

    /// A model path written into a file in another folder is written relative to that folder
    /// (`../m.obj`, not the working folder's `m.obj`), and read back relative to it: the same
    /// file, whichever folder reads it. Paths with nothing but the root in common stay
    /// absolute; built-in models stay names.
    #[test]
    fn model_paths_are_relative_to_the_file_that_names_them() {
        use std::path::{Path, PathBuf};
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::create_dir_all(root.join("models")).unwrap();
        std::fs::write(root.join("models/m.obj"), "").unwrap();
        let model = root.join("models/m.obj");
        let s = RenderSettings {
            scene: SceneChoice::Obj(model.clone()),
            ..RenderSettings::default()
        };
        let written = s.relative_to(&root.join("sub"));
        assert_eq!(
            written.scene,
            SceneChoice::Obj(PathBuf::from("../models/m.obj"))
        );
        let mut read = written.clone();
        read.resolve_paths(&root.join("sub"));
        let SceneChoice::Obj(path) = &read.scene else {
            panic!("{:?}", read.scene)
        };
        assert_eq!(path.canonicalize().unwrap(), model);
        // Inside the folder: plain; a missing model is compared as written.
        assert_eq!(
            crate::shapes::scene::spec::path_relative_to(&model, &root),
            Path::new("models/m.obj")
        );
        assert_eq!(
            crate::shapes::scene::spec::path_relative_to(
                &root.join("gone/x.obj"),
                &root.join("sub")
            ),
            Path::new("../gone/x.obj")
        );
        // Only the root in common: absolute.
        assert_eq!(
            crate::shapes::scene::spec::path_relative_to(Path::new("/nowhere-a/x.obj"), &root),
            Path::new("/nowhere-a/x.obj")
        );
        let mut custom = SceneChoice::Bunny.spec();
        custom.models.push(crate::shapes::scene::ModelSpec::new(
            model.clone(),
            &crate::shapes::scene::obj::Placement::TEAPOT,
        ));
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(custom)),
            ..RenderSettings::default()
        };
        let SceneChoice::Custom(spec) = s.relative_to(&root.join("sub")).scene else {
            panic!()
        };
        assert_eq!(spec.models[0].file, Path::new("bunny"));
        assert_eq!(spec.models[1].file, Path::new("../models/m.obj"));
    }

    /// A model path that is not UTF-8 is refused before anything is rendered: the settings
    /// that carry it could not be written into a screenshot or a scene file (it panicked
    /// there, after the whole render, writing nothing).
    #[cfg(unix)]
    #[test]
    fn a_model_path_that_is_not_utf8_is_refused() {
        use std::os::unix::ffi::OsStrExt as _;
        let path = std::path::PathBuf::from(std::ffi::OsStr::from_bytes(b"models/m\xff.obj"));
        let s = RenderSettings {
            scene: SceneChoice::Obj(path.clone()),
            ..RenderSettings::default()
        };
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid model path 'models/m\u{fffd}.obj': is not UTF-8 text, and raylab writes \
             the paths of its settings as text (rename the file or its folder)"
        );
        let mut spec = SceneChoice::Bunny.spec();
        spec.models[0].file = path;
        let s = RenderSettings {
            scene: SceneChoice::Custom(Box::new(spec)),
            ..RenderSettings::default()
        };
        assert_eq!(s.validate().unwrap_err().name, "scene.models[0].file");
        assert!(
            crate::files::settings_file::settings_text(&s).is_err(),
            "no panic"
        );
    }

    #[test]
    fn a_camera_with_only_a_width_keeps_the_labs_field_of_view() {
        let loaded = from_json(r#"{"camera": {"width": 256, "height": 128}}"#).unwrap();
        let c = loaded.settings.camera;
        assert_eq!((c.width, c.height, c.focal_length), (256, 128, 256.0));
        // 2·atan(W / 2f) = 2·atan(1/2) = 53.13°, as `--width 256 --height 128` gives.
        assert!((c.horizontal_fov_degrees() - 53.130_1).abs() < 1e-3);
        assert!(loaded.warnings.is_empty());
        // A focal length that is given stays.
        let c = from_json(r#"{"camera": {"width": 256, "focal_length": 100}}"#).unwrap();
        assert_eq!(c.settings.camera.focal_length, 100.0);
    }

    /// A key given twice in settings JSON is refused, naming it by its path and its place,
    /// at any depth and in a screenshot's sidecar too (the last one was used silently, where
    /// a scene file refuses it); the same key in two objects is no duplicate.
    #[test]
    fn a_key_given_twice_is_refused_naming_it() {
        for (json, says) in [
            (r#"{"seed": 1, "seed": 2}"#, "duplicate key `seed`"),
            (
                r#"{"camera": {"width": 8, "width": 9}}"#,
                "duplicate key `camera.width`",
            ),
            (
                r#"{"settings": {"light": {"power": 14, "power": 1e6}}}"#,
                "duplicate key `settings.light.power`",
            ),
            (
                r#"{"scene": {"Custom": {"models": [{"file": "a", "file": "b"}]}}}"#,
                "duplicate key `scene.Custom.models[0].file`",
            ),
            (
                r#"{"saved_at": "x", "saved_at": "y"}"#,
                "duplicate key `saved_at`",
            ),
        ] {
            let e = from_json(json).unwrap_err();
            assert!(e.starts_with(says), "{json}: {e}");
            assert!(
                e.contains("each setting may be given once at line 1 column"),
                "{e}"
            );
        }
        let two = from_json(
            r#"{"camera": {"width": 8}, "light": {"position": [0, 0, 0]}, "x": {"width": 1}}"#,
        )
        .unwrap();
        assert_eq!(two.settings.camera.width, 8);
        assert!(
            from_json(r#"{"seed": 1} {"seed": 2}"#).is_err(),
            "trailing text"
        );
        assert!(from_json(r#"{"seed": 1}  "#).is_ok());
    }

    #[test]
    fn unknown_fields_are_warned_of_and_a_byte_order_mark_is_ignored() {
        let loaded =
            from_json("\u{feff}{\"seed\": 3, \"colour\": 1, \"light\": {\"watts\": 2}}").unwrap();
        assert_eq!(loaded.settings.seed, 3);
        assert_eq!(
            loaded.warnings,
            [
                "unknown field `colour` ignored",
                "unknown field `light.watts` ignored"
            ]
        );
        let sidecar = from_json(r#"{"settings": {"seed": 4}, "saved_at": "x"}"#).unwrap();
        assert_eq!(sidecar.settings.seed, 4);
        assert!(sidecar.warnings.is_empty());
        assert!(from_json("{\"seed\": -1}").is_err());
    }
}
