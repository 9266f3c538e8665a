//! The lab's Cornell box test model (`TestModel.h`): 30 triangles, seven reflectances.
//!
//! The vertices are given in the original box's units (side `L = 555`) and transformed exactly
//! as the lab's helper does: scaled into [-1, 1]³ and mirrored in x and y, so **y points down**.
//! docs/rendering.md ("The lab's stages") lists the constants this scene comes with.

use glam::Vec3;

use super::{Material, Scene};
use crate::base::geometry::Triangle;

/// Side length of the original Cornell box.
const L: f32 = 555.0;

/// Number of triangles in the lab's test model.
pub const CORNELL_TRIANGLES: usize = 30;

// Material indices, in the order of `materials()`.
const RED: u32 = 0;
const YELLOW: u32 = 1;
const GREEN: u32 = 2;
const CYAN: u32 = 3;
const BLUE: u32 = 4;
const PURPLE: u32 = 5;
const WHITE: u32 = 6;

fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("red", Vec3::new(0.75, 0.15, 0.15)),
        Material::diffuse("yellow", Vec3::new(0.75, 0.75, 0.15)),
        Material::diffuse("green", Vec3::new(0.15, 0.75, 0.15)),
        Material::diffuse("cyan", Vec3::new(0.15, 0.75, 0.75)),
        Material::diffuse("blue", Vec3::new(0.15, 0.15, 0.75)),
        Material::diffuse("purple", Vec3::new(0.75, 0.15, 0.75)),
        Material::diffuse("white", Vec3::new(0.75, 0.75, 0.75)),
    ]
}

/// The lab's transform from box units to the scene: `p·2/L − 1`, then `x = −x`, `y = −y`.
///
/// `(p * 2) / L` is evaluated in that order so that 0 and 555 map to exactly −1 and 1: the
/// walls are then exactly the planes |x|, |y|, |z| = 1.
fn to_scene(p: Vec3) -> Vec3 {
    let q = p * 2.0 / L - Vec3::ONE;
    Vec3::new(-q.x, -q.y, q.z)
}

/// The ten triangles of a box-shaped block, in the order of the lab's helper.
fn block(corners: [Vec3; 8], material: u32, out: &mut Vec<Triangle>) {
    let [a, b, c, d, e, f, g, h] = corners.map(to_scene);
    for (v0, v1, v2) in [
        (e, b, a),
        (e, f, b),
        (f, d, b),
        (f, h, d),
        (h, c, d),
        (h, g, c),
        (g, e, c),
        (e, a, c),
        (g, f, e),
        (g, h, f),
    ] {
        out.push(Triangle::new(v0, v1, v2, material));
    }
}

/// The Cornell box of the lab, exactly as its `LoadTestModel` builds it.
///
/// Triangles 0–9 are the room (floor, left wall, right wall, ceiling, back wall), 10–19 the
/// short red block and 20–29 the tall blue block.
pub fn cornell_box() -> Scene {
    Scene::new(cornell_triangles(), materials())
}

/// The Cornell box's 30 triangles alone (materials 0–6 as [`cornell_box`] numbers them), for
/// work that needs the geometry without a scene, such as measuring the kernels before any
/// scene is built ([`crate::shapes::accel::calibrate`]).
pub fn cornell_triangles() -> Vec<Triangle> {
    let v = Vec3::new;
    let mut tris = Vec::with_capacity(CORNELL_TRIANGLES);

    // Room corners.
    let a = v(L, 0.0, 0.0);
    let b = v(0.0, 0.0, 0.0);
    let c = v(L, 0.0, L);
    let d = v(0.0, 0.0, L);
    let e = v(L, L, 0.0);
    let f = v(0.0, L, 0.0);
    let g = v(L, L, L);
    let h = v(0.0, L, L);
    let room = [
        (c, b, a, GREEN), // floor
        (c, d, b, GREEN),
        (a, e, c, PURPLE), // left wall
        (c, e, g, PURPLE),
        (f, b, d, YELLOW), // right wall
        (h, f, d, YELLOW),
        (e, f, g, CYAN), // ceiling
        (f, h, g, CYAN),
        (g, d, c, WHITE), // back wall
        (g, h, d, WHITE),
    ];
    for (v0, v1, v2, m) in room {
        tris.push(Triangle::new(to_scene(v0), to_scene(v1), to_scene(v2), m));
    }

    // Short block.
    block(
        [
            v(290.0, 0.0, 114.0),
            v(130.0, 0.0, 65.0),
            v(240.0, 0.0, 272.0),
            v(82.0, 0.0, 225.0),
            v(290.0, 165.0, 114.0),
            v(130.0, 165.0, 65.0),
            v(240.0, 165.0, 272.0),
            v(82.0, 165.0, 225.0),
        ],
        RED,
        &mut tris,
    );
    // Tall block.
    block(
        [
            v(423.0, 0.0, 247.0),
            v(265.0, 0.0, 296.0),
            v(472.0, 0.0, 406.0),
            v(314.0, 0.0, 456.0),
            v(423.0, 330.0, 247.0),
            v(265.0, 330.0, 296.0),
            v(472.0, 330.0, 406.0),
            v(314.0, 330.0, 456.0),
        ],
        BLUE,
        &mut tris,
    );
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thirty_triangles_seven_materials() {
        let s = cornell_box();
        assert_eq!(s.triangles.len(), 30);
        assert_eq!(s.materials.len(), 7);
        assert_eq!(s.material_of(0).name, "green");
        assert_eq!(s.material_of(10).reflectance, Vec3::new(0.75, 0.15, 0.15));
        assert_eq!(s.material_of(29).name, "blue");
    }

    #[test]
    fn transform_maps_the_box_onto_the_unit_cube_exactly() {
        assert_eq!(to_scene(Vec3::ZERO), Vec3::new(1.0, 1.0, -1.0));
        assert_eq!(to_scene(Vec3::splat(L)), Vec3::new(-1.0, -1.0, 1.0));
        for t in cornell_box().triangles {
            for p in [t.v0, t.v1, t.v2] {
                assert!(p.abs().max_element() <= 1.0, "{p} outside the cube");
            }
        }
    }

    #[test]
    fn room_normals_point_into_the_room() {
        let s = cornell_box();
        let expect = [
            Vec3::new(0.0, -1.0, 0.0), // floor (y = +1) faces up, i.e. −y
            Vec3::new(1.0, 0.0, 0.0),  // left wall (x = −1) faces +x
            Vec3::new(-1.0, 0.0, 0.0), // right wall (x = +1) faces −x
            Vec3::new(0.0, 1.0, 0.0),  // ceiling (y = −1) faces down, +y
            Vec3::new(0.0, 0.0, -1.0), // back wall (z = +1) faces the camera
        ];
        for (i, n) in expect.iter().enumerate() {
            for t in &s.triangles[2 * i..2 * i + 2] {
                assert!((t.normal - *n).length() < 1e-6, "{i}: {}", t.normal);
            }
        }
    }

    #[test]
    fn block_normals_point_out_of_the_block() {
        let s = cornell_box();
        for blk in [&s.triangles[10..20], &s.triangles[20..30]] {
            let centre = blk.iter().map(|t| t.centroid()).sum::<Vec3>() / 10.0;
            for t in blk {
                assert!(t.normal.dot(t.centroid() - centre) > 0.0);
            }
        }
    }
}
