//! raylab: the tracer behind a raytracing workbench for learning, built around a university
//! raytracing lab (COMS30115 coursework 1) and its Cornell box.
//!
//! The library reads like the lab: [`scene`] → [`camera`] → [`geometry::Ray`] →
//! [`intersect`] (`closest_intersection`) → [`integrator`] (the lab's stages with
//! [`light::direct_light`], its equation 27, and the path tracer; [`material`] for mirror and
//! glass) → [`film`]. [`render`] runs that for every pixel, in parallel and cancellably.
//!
//! ```
//! use raylab_core::{RenderSettings, render, scene::cornell_box};
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
pub mod bsdf;
pub mod camera;
pub mod check;
pub mod denoise;
pub mod display;
pub mod film;
pub mod geometry;
pub mod inputs;
pub mod inspect;
pub mod integrator;
pub mod intersect;
pub mod invalid;
pub mod lanes;
pub mod light;
pub mod material;
pub mod memory;
pub mod named;
pub mod noise;
pub mod photon_map;
pub mod progressive;
pub mod relief;
pub mod render;
pub mod sampling;
pub mod sandbox;
pub mod scene;
pub mod scene_file;
pub mod settings;
pub mod settings_file;
pub mod temp_files;
pub mod texture;
pub mod view;
pub mod walkthrough;

pub use camera::Camera;
pub use film::Image;
pub use integrator::{Shading, Stage};
pub use light::LightSpec;
pub use material::{Material, MaterialKind, MaterialPreset};
pub use settings::RenderSettings;
