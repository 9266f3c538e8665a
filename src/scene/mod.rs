//! Scenes: triangles plus the materials they reference.
//!
//! The built-in scene is the lab's Cornell box ([`cornell_box`]); later sources of geometry
//! (OBJ models, generated terrain) produce the same [`Scene`] value.

mod cornell;

pub use cornell::{CORNELL_TRIANGLES, cornell_box};

use glam::Vec3;

use crate::geometry::{Ray, Triangle};
use crate::intersect::{self, Intersection};

/// How a surface scatters light. The lab models every surface as ideally diffuse (figure 4,
/// left); specular kinds are a road-map extension and get their own variants.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MaterialKind {
    #[default]
    Diffuse,
}

/// A material: the lab's per-triangle `color`, which it uses as the diffuse reflectance ρ.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// ρ, the fraction of incoming light reflected per colour channel (section 5).
    pub reflectance: Vec3,
    pub kind: MaterialKind,
}

impl Material {
    pub fn diffuse(name: impl Into<String>, reflectance: Vec3) -> Self {
        Self {
            name: name.into(),
            reflectance,
            kind: MaterialKind::Diffuse,
        }
    }
}

/// Geometry and materials to trace. Every triangle's `material` indexes `materials`.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
}

impl Scene {
    pub fn new(triangles: Vec<Triangle>, materials: Vec<Material>) -> Self {
        debug_assert!(
            triangles
                .iter()
                .all(|t| (t.material as usize) < materials.len())
        );
        Self {
            triangles,
            materials,
        }
    }

    /// The material of triangle `index`.
    pub fn material_of(&self, triangle_index: usize) -> &Material {
        &self.materials[self.triangles[triangle_index].material as usize]
    }

    /// The closest hit along `ray` with `t < t_max` (the lab's `ClosestIntersection`).
    pub fn closest_intersection(&self, ray: &Ray, t_max: f32) -> Option<Intersection> {
        intersect::closest_intersection_brute_force(ray, &self.triangles, t_max)
    }

    /// Whether anything lies along `ray` with `t < t_max` (a shadow ray's question).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        intersect::occluded_brute_force(ray, &self.triangles, t_max)
    }
}
