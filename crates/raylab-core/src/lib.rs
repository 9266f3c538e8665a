//! raylab: the tracer behind a raytracing workbench for learning, built around a university
//! raytracing lab (COMS30115 coursework 1) and its Cornell box.
//!
//! The library reads like the lab: [`shapes::scene`] → [`base::camera`] →
//! [`base::geometry::Ray`] → [`shapes::intersect`] (`closest_intersection`) →
//! [`transport::integrator`] (the lab's stages with [`shading::light::direct_light`], its
//! equation 27, and the path tracer; [`shading::material`] for mirror and glass) →
//! [`transport::film`]. [`transport::render`] runs that for every pixel, in parallel and
//! cancellably.
//!
//! Its folders are the rungs of a ladder, each using only those before it: [`base`] (rays,
//! lanes, sampling, the camera), [`shading`] (BSDFs, materials, textures, lights), [`shapes`]
//! (triangles, the BVH, the scenes), [`transport`] (settings, integrators, film, denoiser,
//! rendering), [`teaching`] (check my lab, the inspector, the sandbox) and [`files`] (scene
//! files and settings). [`bench`] measures, and [`test_support`] holds the fixtures tests
//! share.
//!
//! ```
//! use raylab_core::{RenderSettings, transport::render, shapes::scene::cornell_box};
//!
//! // Figure 7 of the lab, small: ρ ∗ (D + N) with shadows.
//! let mut settings = RenderSettings::default();
//! settings.camera = settings.camera.with_resolution(32, 32);
//! let image = render::render(&cornell_box(), &settings);
//! // The centre pixel sees the white back wall, lit.
//! let centre = image.get(16, 16);
//! assert!(centre.x > 0.4 && (centre.x - centre.z).abs() < 1e-6);
//! ```

pub mod base;

pub mod shading;

pub mod shapes;

pub mod transport;

pub mod teaching;

pub mod files;

pub mod bench;

pub mod test_support;

pub use base::camera::Camera;
pub use shading::light::LightSpec;
pub use shading::material::{Material, MaterialKind, MaterialPreset};
pub use transport::film::Image;
pub use transport::integrator::{Shading, Stage};
pub use transport::settings::RenderSettings;
