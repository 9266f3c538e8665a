//! raylab: the tracer behind a raytracing workbench for learning, built around a university
//! raytracing lab (COMS30115 coursework 1) and its Cornell box.
//!
//! The library reads like the lab: [`scene`] → [`camera`] → [`geometry::Ray`] →
//! [`intersect`] (`closest_intersection`) → [`shading`] (with [`light::direct_light`], the lab's
//! equation 27) → [`film`]. [`render`] runs that for every pixel, in parallel and cancellably.
//!
//! ```
//! use raylab::{RenderSettings, render, scene::cornell_box};
//!
//! // Figure 7 of the lab, small: ρ ∗ (D + N) with shadows.
//! let mut settings = RenderSettings::default();
//! settings.camera = settings.camera.with_resolution(32, 32);
//! let image = render::render(&cornell_box(), &settings);
//! // The centre pixel sees the white back wall, lit.
//! let centre = image.get(16, 16);
//! assert!(centre.x > 0.4 && (centre.x - centre.z).abs() < 1e-6);
//! ```

pub mod accel;
pub mod bench;
pub mod camera;
pub mod film;
pub mod geometry;
pub mod intersect;
pub mod light;
pub mod progressive;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod shading;

pub use camera::Camera;
pub use film::Image;
pub use light::PointLight;
pub use settings::RenderSettings;
pub use shading::{Shading, Stage};
