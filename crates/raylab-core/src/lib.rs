//! raylab: the tracer behind a raytracing workbench for learning, built around a university
//! raytracing lab (COMS30115 coursework 1) and its Cornell box.
//!
//! The library reads like the lab: [`scene`] → [`camera`] → [`geometry::Ray`] →
//! [`intersect`] (`closest_intersection`) → [`integrator`] (the lab's stages with
//! [`light::direct_light`], its equation 27, and the path tracer; [`material`] for mirror and
//! glass) → [`film`]. [`render`] runs that for every pixel, in parallel and cancellably.
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

pub use base::camera::Camera;
pub use shading::light::LightSpec;
pub use shading::material::{Material, MaterialKind, MaterialPreset};
pub use transport::film::Image;
pub use transport::integrator::{Shading, Stage};
pub use transport::settings::RenderSettings;
