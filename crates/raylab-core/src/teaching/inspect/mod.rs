//! The pixel inspector: why a pixel has its colour, line by line, each line beside the lab
//! equation it evaluates, with the numbers substituted and their units.
//!
//! [`inspect_pixel`] recomputes sample 0 of one pixel through the renderer's own code: it makes
//! the pixel's camera ray as the renderer does (the pixel centre, or for the path stage and the
//! other random extensions the stream of (seed, x, y, 0)) and runs it through
//! [`Tracer::trace_recorded`] with a recording [`Recorder`]. The integrators tell the recording
//! each step as they take it (closest hits, mirror and glass branches, every hit's
//! [`HitTerms`] once its shadow ray is answered, every path vertex), so each number reported is
//! one the tracer computed, and [`Inspection::r`] is [`crate::transport::render::trace_pixel`]'s value
//! bit for bit. There is no second copy of the shading formulas here.
//!
//! Two things are worked out here because the renderer never needs them:
//!
//! * the parts of D (equation 27): the vector r to the light, its length, r̂·n̂ and 4πr², by
//!   [`direct_light`](crate::shading::light::direct_light)'s own expression on the tracer's hit point and normal (the tests check
//!   that they give the tracer's D bit for bit);
//! * what blocks a shadow ray: the renderer only asks *whether* something does (§5.1);
//!   [`Scene::closest_intersection`] along the very same shadow ray says which triangle, and
//!   how far along.
//!
//! The inspector runs the portable build of the integrators, one ray at a time; the renderer's
//! AVX2 and AVX-512 builds and its batches give the same bits (tested in [`crate::transport::integrator`]).
//!
//! Units: lengths in scene units (the box is 2 units wide), the light's power P in watts, D in
//! watts per unit area. `·` stands for the lab's element-wise product `∗`.

mod lines;
mod parts;
mod recording;
#[cfg(test)]
mod tests;

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::base::geometry::Ray;
use crate::base::sampling::Rng;
use crate::shading::light::{LightKind, LightSpec};
use crate::shapes::scene::Scene;
use crate::transport::integrator::{Stage, Tracer};
use crate::transport::settings::{RenderSettings, SettingsError};

pub use lines::lines_text;
pub(crate) use lines::{num, vector};
pub use parts::*;
use recording::Recording;

/// Why a pixel can't be inspected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InspectError {
    /// The pixel is not in the image.
    #[error(
        "pixel ({x}, {y}) is outside the {width}×{height} image (x below {width}, y below {height})"
    )]
    OutsideImage {
        x: u32,
        y: u32,
        width: u32,
        height: u32,
    },
    /// The settings can't be rendered (the same check a render makes).
    #[error(transparent)]
    Settings(#[from] SettingsError),
}
/// Everything the tracer computed for sample 0 of one pixel, and the lab's words for it
/// ([`Inspection::lines`]).
///
/// The fields from `triangle` to `shading_normal` describe the camera ray's first hit. The
/// lab's terms (`rho` to `blocker`, flattened from [`LightTerms`]) are those of the first
/// diffuse hit whose light was computed: the first hit itself, or, when that is a mirror or
/// glass, the diffuse hit its first branch reaches (`specular_chain` says how), or the path's
/// first diffuse vertex. `shaded` lists every diffuse hit that adds to R.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Inspection {
    /// The pixel, [x, y] from the top-left corner.
    pub pixel: [u32; 2],
    pub stage: Stage,
    /// What the stage computes with its switches as they are ([`crate::Shading::description`]).
    pub computes: String,
    /// Whether shadow rays are cast (§5.1).
    pub shadows: bool,
    /// The image size, [W, H], and the focal length f in pixels (equation 24).
    pub image: [u32; 2],
    pub focal_length: f32,
    /// The point of the image plane the ray goes through, in pixels: the pixel's centre.
    pub image_point: [f32; 2],
    /// The point of the lens the ray leaves from, on the unit disk (`None`: the lab's pinhole).
    pub lens_point: Option<Vec2>,
    /// The camera ray (equation 24): origin s and unit direction d̂.
    pub origin: Vec3,
    pub direction: Vec3,
    /// The triangle the camera ray hits first (equations 7–9, 12), or `None`: nothing is hit.
    pub triangle: Option<usize>,
    /// Its material's name and kind (diffuse, mirror or glass).
    pub surface: Option<String>,
    pub kind: Option<&'static str>,
    /// The distance t along the ray and the barycentric coordinates u, v of the hit.
    pub t: Option<f32>,
    pub u: Option<f32>,
    pub v: Option<f32>,
    /// The hit point s + t·d̂.
    pub position: Option<Vec3>,
    /// The triangle's own normal n̂.
    pub normal: Option<Vec3>,
    /// Whether the ray meets the triangle's back (d̂·n̂ > 0).
    pub back_facing: Option<bool>,
    /// The normal D was computed with at the first hit, where it differs from `normal`: the
    /// interpolated vertex normals (smooth shading) or, in the path stage, the normal turned to
    /// face the ray (surfaces are two-sided there), or a normal map's tilt of either.
    pub shading_normal: Option<Vec3>,
    /// Whether the first hit's material has a normal map ([`crate::shading::relief`]): its normal for
    /// the light is the map's.
    #[serde(default)]
    pub normal_mapped: bool,
    /// The light.
    pub light: LightSpec,
    /// The lab's terms at the first diffuse hit shaded (see above).
    #[serde(flatten)]
    pub terms: LightTerms,
    /// N, the constant indirect light in force (0 with indirect off, and in the path stage,
    /// where bounces bring real indirect light instead).
    #[serde(rename = "N")]
    pub n: Vec3,
    /// R, the pixel's value: exactly what the renderer puts in the image for one sample.
    #[serde(rename = "R")]
    pub r: Vec3,
    /// Lab stages: every mirror and glass branch followed, in the order they were traced.
    pub specular_chain: Vec<SpecularStep>,
    /// Lab stages: specular branches that left the scene (they add nothing).
    pub escaped: Vec<EscapedBranch>,
    /// Every diffuse hit whose value was added to R, with what it was multiplied by.
    pub shaded: Vec<ShadedHit>,
    /// Path stage: the path's vertices.
    pub bounces: Vec<PathVertex>,
}

/// One line of the explanation: the equation it evaluates and the text.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct InspectLine {
    /// The lab's equation or section, e.g. "eq. 27", "§5.1", "fig. 7"; or what the step is.
    pub equation: String,
    /// The step with numbers substituted, e.g. "D = P·max(r̂·n̂, 0)/(4πr²) = 14 W × 0.906 /
    /// (4π × 2.740 units²) = 0.368 W per unit area".
    pub text: String,
}

/// What the screen shows at the inspected pixel: the value of the image on screen there, and
/// what that image is. With one sample it is [`Inspection::r`] itself; with more it is their
/// mean (the film's), or the denoised image's value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ShownPixel {
    /// The pixel's linear value in the image on screen.
    pub value: Vec3,
    /// The samples the image on screen averages (so far).
    pub samples: u32,
    /// Whether the image on screen is the denoised one, made from those samples.
    pub denoised: bool,
}

/// Recomputes sample 0 of pixel `(x, y)` as the renderer does and records every step.
///
/// `Inspection::r` equals [`crate::transport::render::trace_pixel`]`(scene, settings, x, y, 0)` bit for
/// bit, in every stage and with every preset. Errors for a pixel outside the image or settings
/// that can't be rendered.
pub fn inspect_pixel(
    scene: &Scene,
    settings: &RenderSettings,
    x: u32,
    y: u32,
) -> Result<Inspection, InspectError> {
    settings.validate()?;
    let camera = &settings.camera;
    if x >= camera.width || y >= camera.height {
        return Err(InspectError::OutsideImage {
            x,
            y,
            width: camera.width,
            height: camera.height,
        });
    }
    let tracer = Tracer::for_pass(scene, settings, 0);
    let (ray, rng, image_point, lens_point) = camera_sample_0(&tracer, settings, x, y);
    let mut recording = Recording::default();
    let mut out = [Vec3::ZERO];
    tracer.trace_recorded(&[ray], &mut [rng], &mut out, &mut recording);
    Ok(Inspection::from_recording(
        &tracer,
        settings,
        [x, y],
        image_point,
        lens_point,
        ray,
        &recording.events,
        out[0],
    ))
}

/// Sample 0's camera ray and generator, made by the renderer's own
/// [`crate::transport::render::camera_sample`]: the pixel's centre (sample 0 is never jittered), through a
/// point of the lens drawn from the sample's stream when the camera has an aperture.
fn camera_sample_0(
    tracer: &Tracer,
    settings: &RenderSettings,
    x: u32,
    y: u32,
) -> (Ray, Rng, [f32; 2], Option<Vec2>) {
    let mut ray = Ray::new(Vec3::ZERO, Vec3::Z);
    let mut rng = Rng::UNUSED;
    let rotation = settings.camera.rotation();
    let ((px, py), lens) = crate::transport::render::camera_sample(
        tracer, settings, &rotation, x, y, 0, &mut ray, &mut rng,
    );
    (ray, rng, [px, py], lens)
}
