//! Standing a mesh in the box ([`Placement`]) and the normals smooth shading needs at its
//! corners ([`smooth_normals`], within [`CREASE_ANGLE_DEGREES`]).

use std::collections::HashMap;

use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::*;
use crate::base::geometry::Triangle;

/// The crease angle for normals computed from the faces, in degrees: at a corner, only the
/// faces whose normal is within 60° of the corner's own face are smoothed together.
///
/// Curved surfaces tessellated as finely as the bunny or the teapot turn by far less than that
/// from one face to the next (a cylinder of 12 facets, by 30°), while deliberate edges — a
/// cube's 90°, the teapot's lid on its body — turn by more, and stay sharp.
pub const CREASE_ANGLE_DEGREES: f32 = 60.0;

/// Where and how a model stands in the box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Height of the model in scene units (the box is 2 high); the scale follows from it.
    pub height: f32,
    /// Where the centre of the model's footprint stands on the floor: (x, z).
    pub floor_position: [f32; 2],
    /// Turn about the vertical axis, in radians; positive turns the model's +z towards +x.
    pub yaw: f32,
    /// The model's diffuse reflectance ρ.
    pub reflectance: Vec3,
}

impl Placement {
    /// In front of the tall blue block and left of the short red one, well lit and in full
    /// view of the default camera.
    pub const FRONT_LEFT: Placement = Placement {
        height: 0.75,
        floor_position: [-0.5, -0.5],
        yaw: 0.0,
        reflectance: Vec3::new(0.75, 0.75, 0.75),
    };
    /// The teapot: turned so its spout points at the camera's right, a warm white.
    pub const TEAPOT: Placement = Placement {
        height: 0.75,
        floor_position: [-0.5, -0.5],
        yaw: 0.5,
        reflectance: Vec3::new(0.8, 0.75, 0.6),
    };
    /// Largest horizontal extent a placed model may have: it must stay clear of the blocks.
    pub const MAX_WIDTH: f32 = 0.7;
}

/// A mesh placed in the box: its triangles and, per triangle, what its three corners carry,
/// in the triangle's vertex order (`v0`, `v1`, `v2`).
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedModel {
    pub triangles: Vec<Triangle>,
    /// Unit normals for smooth shading, each on the outward side of its triangle.
    pub normals: Vec<[Vec3; 3]>,
    /// Texture coordinates, when the file has them.
    pub uvs: Option<Vec<[Vec2; 3]>>,
}

/// The mesh's triangles placed in the box, with material `material`.
pub fn place(mesh: &Mesh, placement: &Placement, material: u32) -> Vec<Triangle> {
    place_model(mesh, placement, material).triangles
}

/// The mesh placed in the box, with material `material`, its corners' normals and texture
/// coordinates.
pub fn place_model(mesh: &Mesh, placement: &Placement, material: u32) -> PlacedModel {
    // Mirror y (OBJ is y-up, raylab y-down), then turn about the vertical.
    let (s, c) = placement.yaw.sin_cos();
    let turn = Mat3::from_cols(Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c));
    let linear = turn * Mat3::from_diagonal(Vec3::new(1.0, -1.0, 1.0));
    let turned: Vec<Vec3> = mesh.positions.iter().map(|&p| linear * p).collect();
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for &p in &turned {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let size = hi - lo;
    // Scale to the height, but never wider than the free floor allows.
    let mut scale = placement.height / size.y.max(f32::MIN_POSITIVE);
    let width = size.x.max(size.z) * scale;
    if width > Placement::MAX_WIDTH {
        scale *= Placement::MAX_WIDTH / width;
    }
    // The lowest point (largest y) rests on the floor at y = 1.
    let [fx, fz] = placement.floor_position;
    let anchor = Vec3::new(0.5 * (lo.x + hi.x), hi.y, 0.5 * (lo.z + hi.z));
    let to_scene = |p: Vec3| (p - anchor) * scale + Vec3::new(fx, 1.0, fz);
    let scene_points: Vec<Vec3> = turned.iter().map(|&p| to_scene(p)).collect();

    // Which way faces point: the file's normals, else the sign of the enclosed volume (for
    // counter-clockwise faces seen from outside, Σ v0·(v1 × v2) > 0).
    let volume: f32 = mesh
        .indices
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| mesh.positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum();
    // The mirror reverses handedness: outward e1 × e2 in the file becomes e2 × e1 here, which
    // is the lab's normal. A clockwise file needs the opposite.
    let flip_all = volume < 0.0;
    // Normals transform by the inverse transpose of the positions' linear map. That map is
    // a rotation times a mirror times a uniform scale: its inverse transpose is the rotation
    // times the mirror divided by the scale, and the scale goes with normalising.
    let normal_matrix = linear;
    // Each triangle's vertex indices in the order its scene triangle has them.
    let (triangles, corners): (Vec<Triangle>, Vec<[u32; 3]>) = mesh
        .indices
        .iter()
        .map(|&f| {
            let [a, b, c] = f.map(|i| scene_points[i as usize]);
            let t = Triangle::new(a, b, c, material);
            let flip = match &mesh.normals {
                Some(normals) => {
                    let n: Vec3 = f.iter().map(|&i| normals[i as usize]).sum();
                    t.normal.dot(normal_matrix * n) < 0.0
                }
                None => flip_all,
            };
            if flip {
                (Triangle::new(a, c, b, material), [f[0], f[2], f[1]])
            } else {
                (t, f)
            }
        })
        .unzip();
    let normals = match &mesh.normals {
        Some(file) => corners
            .iter()
            .zip(&triangles)
            .map(|(corner, t)| {
                corner.map(|i| {
                    let n = (normal_matrix * file[i as usize])
                        .try_normalize()
                        .unwrap_or(t.normal);
                    // A shading normal behind its face would light the face as if from
                    // behind; the face's side is the outward one decided above.
                    if n.dot(t.normal) < 0.0 { -n } else { n }
                })
            })
            .collect(),
        None => {
            let face_normals: Vec<Vec3> = triangles.iter().map(|t| t.normal).collect();
            smooth_normals(
                &scene_points,
                &corners,
                &face_normals,
                CREASE_ANGLE_DEGREES.to_radians(),
            )
        }
    };
    let uvs = mesh.uvs.as_ref().map(|uvs| {
        corners
            .iter()
            .map(|corner| corner.map(|i| uvs[i as usize]))
            .collect()
    });
    PlacedModel {
        triangles,
        normals,
        uvs,
    }
}

/// Per triangle corner, a unit normal for smooth shading, computed from the faces around it.
///
/// `face_normals` are the triangles' unit normals (zero for a degenerate triangle, which then
/// contributes nothing). At a corner, the faces that touch the same **position** — welded by
/// exact equality, because OBJ files repeat a vertex wherever its texture coordinates or
/// normals differ, as along a texture seam — are summed, each weighted by its angle at that
/// position, but only those whose normal is within `crease_angle` (radians) of this corner's
/// own face: a sharper edge stays sharp. Weighting by angle makes the result depend on the
/// shape, not on how it was cut into triangles (a square face split in two still counts as one
/// 90° corner). A corner with nothing to average (a degenerate face) keeps its face's normal.
/// The time is linear in the number of faces: where more than [`MAX_FAN`] faces meet at one
/// position, equal normals are summed once, and more than that many distinct normals are
/// averaged whole (see [`MAX_FAN`]).
pub fn smooth_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    face_normals: &[Vec3],
    crease_angle: f32,
) -> Vec<[Vec3; 3]> {
    debug_assert_eq!(triangles.len(), face_normals.len());
    // Weld: one id per distinct position (−0 read as +0, which is the same point).
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let weld: Vec<u32> = positions
        .iter()
        .map(|&p| {
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = ids.len() as u32;
            *ids.entry(key).or_insert(next)
        })
        .collect();
    let welded = |i: u32| weld[i as usize] as usize;
    let degenerate = |f: usize| {
        let n = face_normals[f];
        !(n.length_squared() > 0.0) || !n.is_finite()
    };
    // The faces around each welded position, with their angle there (compressed rows: those
    // of position w are `around[start[w]..start[w + 1]]`).
    let mut start = vec![0usize; ids.len() + 1];
    for (f, tri) in triangles.iter().enumerate() {
        if !degenerate(f) {
            for &i in tri {
                start[welded(i) + 1] += 1;
            }
        }
    }
    for w in 0..ids.len() {
        start[w + 1] += start[w];
    }
    let mut fill = start.clone();
    let mut around = vec![(0u32, 0.0f32); start[ids.len()]];
    for (f, tri) in triangles.iter().enumerate() {
        if degenerate(f) {
            continue;
        }
        let p = tri.map(|i| positions[i as usize]);
        for k in 0..3 {
            let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            // atan2 of |sin| and cos: accurate for small and near-straight angles alike.
            let angle = e1.cross(e2).length().atan2(e1.dot(e2));
            let w = welded(tri[k]);
            around[fill[w]] = (f as u32, angle);
            fill[w] += 1;
        }
    }
    let cos_crease = crease_angle.cos();
    // Positions with more than `MAX_FAN` faces around them: their faces grouped by normal
    // (so that each corner there costs the number of distinct normals, not of faces).
    let fans: HashMap<usize, Fan> = (0..ids.len())
        .filter(|&w| start[w + 1] - start[w] > MAX_FAN)
        .map(|w| (w, Fan::of(&around[start[w]..start[w + 1]], face_normals)))
        .collect();
    triangles
        .par_iter()
        .enumerate()
        .map(|(f, tri)| {
            let own = face_normals[f];
            if degenerate(f) {
                return [own; 3];
            }
            let within_crease = |n: Vec3, angle: f32| {
                if n.dot(own) >= cos_crease {
                    angle * n
                } else {
                    Vec3::ZERO
                }
            };
            tri.map(|i| {
                let w = welded(i);
                let sum: Vec3 = match fans.get(&w) {
                    None => around[start[w]..start[w + 1]]
                        .iter()
                        .map(|&(g, angle)| within_crease(face_normals[g as usize], angle))
                        .sum(),
                    Some(Fan::Grouped(groups)) => groups
                        .iter()
                        .map(|&(n, angle)| within_crease(n, angle))
                        .sum(),
                    Some(Fan::Whole(sum)) => *sum,
                };
                sum.try_normalize().unwrap_or(own)
            })
        })
        .collect()
}

/// Above this many faces around one position, [`smooth_normals`] groups them by normal; above
/// this many distinct normals, it averages them all, without the crease test. Averaging each
/// corner over every face around its position costs the square of their number, out of reach
/// for a file of a million copies of one triangle (a million faces around each of three
/// positions). No real surface has more than a few dozen differently facing faces meeting at a
/// point (a 64-sided cone's apex is one), so real models are smoothed exactly as described.
pub const MAX_FAN: usize = 64;

/// The faces around a position with more than [`MAX_FAN`] of them.
pub(super) enum Fan {
    /// Each distinct normal once, with the sum of the angles of the faces that have it.
    Grouped(Vec<(Vec3, f32)>),
    /// More than [`MAX_FAN`] distinct normals: the sum of every face's angle × normal, which
    /// every corner there takes whole (a point where so many directions meet has no edge to
    /// keep sharp).
    Whole(Vec3),
}

impl Fan {
    pub(super) fn of(around: &[(u32, f32)], face_normals: &[Vec3]) -> Fan {
        let mut faces: Vec<(Vec3, f32)> = around
            .iter()
            .map(|&(g, angle)| (face_normals[g as usize], angle))
            .collect();
        let key = |n: Vec3| n.to_array().map(f32::to_bits);
        faces.sort_unstable_by_key(|&(n, _)| key(n));
        let mut groups: Vec<(Vec3, f32)> = Vec::new();
        for (n, angle) in faces {
            match groups.last_mut() {
                Some((m, sum)) if key(*m) == key(n) => *sum += angle,
                _ => groups.push((n, angle)),
            }
        }
        if groups.len() <= MAX_FAN {
            Fan::Grouped(groups)
        } else {
            Fan::Whole(groups.iter().map(|&(n, angle)| angle * n).sum())
        }
    }
}
