//! Rays and triangles: the two primitives the lab's tracer is built from (section 1 and 2.2).

use glam::Vec3;

/// A ray `r = s + t·d` (lab equation 10), restricted to `t ≥ 0` (equation 11).
///
/// raylab keeps `direction` normalised, so `t` is a distance in scene units and
/// [`crate::shapes::intersect::Intersection::distance`] means what it says.
///
/// `repr(C)`: the SIMD packets gather a batch's rays as six floats each, origin first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along `direction`, which is normalised here.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction: direction.normalize_or_zero(),
        }
    }

    /// The point at parameter `t` (equation 10).
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// A triangle as in the lab's `struct Triangle`: three vertices, a precomputed unit normal, and
/// an index into the scene's materials (the lab stores a colour; a material index leaves room
/// for mirrors and glass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub v0: Vec3,
    pub v1: Vec3,
    pub v2: Vec3,
    /// Unit normal, `normalize(cross(e2, e1))` (the lab's test model convention); zero for a
    /// degenerate (zero-area) triangle.
    pub normal: Vec3,
    pub material: u32,
}

impl Triangle {
    /// A triangle with its normal computed from the vertex order, as the lab's `TestModel.h`
    /// does: `n = normalize(e2 × e1)` with `e1 = v1 − v0`, `e2 = v2 − v0`.
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3, material: u32) -> Self {
        let normal = (v2 - v0).cross(v1 - v0).normalize_or_zero();
        Self {
            v0,
            v1,
            v2,
            normal,
            material,
        }
    }

    /// Edge vectors `e1 = v1 − v0` and `e2 = v2 − v0` (equations 4 and 5).
    pub fn edges(&self) -> (Vec3, Vec3) {
        (self.v1 - self.v0, self.v2 - self.v0)
    }

    /// The point with barycentric coordinates `(u, v)`: `v0 + u·e1 + v·e2` (equation 6).
    pub fn point_at(&self, u: f32, v: f32) -> Vec3 {
        let (e1, e2) = self.edges();
        self.v0 + u * e1 + v * e2
    }

    pub fn centroid(&self) -> Vec3 {
        (self.v0 + self.v1 + self.v2) / 3.0
    }

    pub fn area(&self) -> f32 {
        let (e1, e2) = self.edges();
        0.5 * e1.cross(e2).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_follows_the_labs_winding() {
        // e1 = (1,0,0), e2 = (0,1,0): cross(e2, e1) = (0,0,-1).
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
        assert_eq!(t.normal, Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(t.area(), 0.5);
        assert_eq!(t.point_at(0.25, 0.5), Vec3::new(0.25, 0.5, 0.0));
    }

    #[test]
    fn degenerate_triangle_has_zero_normal_not_nan() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, 2.0 * Vec3::X, 0);
        assert_eq!(t.normal, Vec3::ZERO);
        assert_eq!(t.area(), 0.0);
    }

    #[test]
    fn ray_direction_is_normalised() {
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, 3.0, 4.0));
        assert!((r.direction.length() - 1.0).abs() < 1e-6);
        assert_eq!(r.at(5.0), Vec3::new(0.0, 3.0, 4.0));
    }
}
