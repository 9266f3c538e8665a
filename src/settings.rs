//! Everything that determines an image, in one serialisable value.
//!
//! The command line, the workbench's panels and saved screenshots all describe a render with a
//! [`RenderSettings`]; the renderer takes nothing else. `#[serde(default)]` everywhere means an
//! older or partial settings file still loads, with the lab's values for what it lacks.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::camera::Camera;
use crate::display::Display;
use crate::integrator::{MAX_SPECULAR_DEPTH, Shading};
use crate::light::PointLight;
use crate::material::{MaterialPreset, TexturePreset};
use crate::scene::SceneChoice;
use crate::view::View;

/// The largest image side raylab renders: 16384 px (a 16384² float image is 3 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// The longest focal length, in pixels: a field of view of a 10,000th of a degree on a
/// 16384-pixel image. Far beyond it, the squared length of a primary ray's direction
/// overflows `f32` and every ray is lost (a black image).
pub const MAX_FOCAL_LENGTH: f32 = 1e7;

/// The largest exposure, either way, in stops.
pub const MAX_EXPOSURE: f32 = 20.0;

/// The most samples per pixel a render may ask for.
pub const MAX_SAMPLES: u32 = 1 << 16;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RenderSettings {
    /// The scene to trace: the lab's Cornell box by default.
    pub scene: SceneChoice,
    /// The camera, including the image size.
    pub camera: Camera,
    pub light: PointLight,
    pub shading: Shading,
    /// Mirror and glass for the Cornell box's blocks (none: the lab's diffuse box).
    pub material_preset: MaterialPreset,
    /// Textures for the Cornell box's floor and walls (none: the lab's plain colours).
    pub texture_preset: TexturePreset,
    /// How linear values are shown and written to PNG (the lab's clamp by default). Changing
    /// it never re-traces: the renderer ignores it.
    pub display: Display,
    /// What the workbench shows: the shaded image (the default) or a debug view of the same
    /// scene and camera ([`crate::view`]). `render` ignores it; the command line's `--view`
    /// chooses.
    pub view: View,
    /// Samples per pixel to accumulate; 1 traces each pixel's centre (the lab's image), more
    /// jitter inside the pixel and average (anti-aliasing).
    pub samples_per_pixel: u32,
    /// Seed of every random choice; the same seed gives the same image.
    pub seed: u64,
}

impl Default for RenderSettings {
    /// Figure 7 of the lab at 512 × 512.
    fn default() -> Self {
        Self {
            scene: SceneChoice::Cornell,
            camera: Camera::default(),
            light: PointLight::default(),
            shading: Shading::default(),
            material_preset: MaterialPreset::None,
            texture_preset: TexturePreset::None,
            display: Display::default(),
            view: View::Shaded,
            samples_per_pixel: 1,
            seed: 0,
        }
    }
}

/// A value the renderer can't use; the message names it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("invalid {name} {value}: {reason}")]
pub struct SettingsError {
    pub name: &'static str,
    pub value: String,
    pub reason: &'static str,
}

impl RenderSettings {
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
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        let mut value: serde_json::Value = serde_json::from_str(text)?;
        if let Some(inner) = value.get_mut("settings") {
            value = inner.take();
        }
        serde_json::from_value(value)
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
            c.yaw.to_degrees(),
            c.pitch.to_degrees(),
            c.focal_length,
            v(l.position),
            l.power,
            self.samples_per_pixel,
            self.seed,
        )
    }

    /// Checks every value before a render: sizes in 1..=16384, finite numbers, a positive focal
    /// length, non-negative light power and indirect light, 1..=65536 samples.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let c = &self.camera;
        check_side("width", c.width)?;
        check_side("height", c.height)?;
        check_vec("camera position", c.position)?;
        check_finite("yaw", c.yaw)?;
        check_finite("pitch", c.pitch)?;
        check_finite("focal length", c.focal_length)?;
        if c.focal_length <= 0.0 {
            return Err(err("focal length", c.focal_length, "must be > 0"));
        }
        if c.focal_length > MAX_FOCAL_LENGTH {
            let f = c.focal_length;
            return Err(err("focal length", f, "must be at most 1e7 px"));
        }
        check_vec("light position", self.light.position)?;
        check_finite("aperture", c.aperture)?;
        if c.aperture < 0.0 {
            return Err(err("aperture", c.aperture, "must be ≥ 0"));
        }
        check_finite("focus distance", c.focus_distance)?;
        if c.focus_distance <= 0.0 {
            return Err(err("focus distance", c.focus_distance, "must be > 0"));
        }
        let light = &self.light;
        check_finite("light power", light.power)?;
        if light.power < 0.0 {
            return Err(err("light power", light.power, "must be ≥ 0"));
        }
        check_vec("light colour", light.colour)?;
        if light.colour.min_element() < 0.0 {
            return Err(err("light colour", light.colour, "must be ≥ 0"));
        }
        check_finite("light radius", light.radius)?;
        if light.radius < 0.0 {
            return Err(err("light radius", light.radius, "must be ≥ 0"));
        }
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
        if self.shading.specular_depth > MAX_SPECULAR_DEPTH {
            let d = self.shading.specular_depth;
            return Err(err("specular depth", d, "must be at most 12"));
        }
        if !(1..=MAX_SAMPLES).contains(&self.samples_per_pixel) {
            let s = self.samples_per_pixel;
            return Err(err("samples per pixel", s, "must be between 1 and 65536"));
        }
        Ok(())
    }
}

fn err(name: &'static str, value: impl std::fmt::Display, reason: &'static str) -> SettingsError {
    SettingsError {
        name,
        value: value.to_string(),
        reason,
    }
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

#[cfg(test)]
mod tests {
    use super::*;

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
    }

    #[test]
    fn the_display_does_not_change_the_render() {
        let a = RenderSettings::default();
        let mut b = a.clone();
        b.display.exposure = 2.0;
        b.display.transform = crate::display::DisplayTransform::Filmic;
        assert!(a.renders_like(&b) && b.renders_like(&a));
        b.light.radius = 0.1;
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
        let mut s = RenderSettings::default();
        s.light.position.y = f32::NAN;
        let e = s.validate().unwrap_err();
        assert_eq!(e.name, "light position");
        assert!(e.to_string().contains("NaN"), "{e}");
        let mut s = RenderSettings::default();
        s.camera.yaw = f32::INFINITY;
        assert_eq!(s.validate().unwrap_err().name, "yaw");
    }
}
