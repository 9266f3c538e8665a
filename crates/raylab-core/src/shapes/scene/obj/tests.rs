use super::*;
use crate::base::geometry::Triangle;
use crate::shading::texture::TextureImage;
use crate::shapes::scene::spec::{
    builtin_textured, model_in_box, obj_scene, obj_scene_with_warnings,
};
use crate::shapes::scene::{Scene, SceneChoice};

#[test]
fn the_built_in_models_load() {
    let bunny = builtin(BUNNY_OBJ, "bunny").unwrap();
    assert_eq!(bunny.indices.len(), 3674);
    let teapot = builtin(TEAPOT_OBJ, "teapot").unwrap();
    assert_eq!(teapot.indices.len(), 992);
}

#[test]
fn a_placed_model_stands_on_the_floor_clear_of_the_blocks() {
    let mesh = builtin(BUNNY_OBJ, "bunny").unwrap();
    let tris = place(&mesh, &Placement::FRONT_LEFT, 7);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in &tris {
        for p in [t.v0, t.v1, t.v2] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    assert!((hi.y - 1.0).abs() < 1e-6, "rests on the floor: {hi}");
    let height = hi.y - lo.y;
    assert!(height > 0.5 && height <= 0.75 + 1e-4, "{height} high");
    assert!((hi.x - lo.x).max(hi.z - lo.z) <= Placement::MAX_WIDTH + 1e-4);
    // The short block starts at x = −0.05 (z < −0.02), the tall one at z = −0.11.
    assert!(
        hi.x < -0.1 && hi.z < -0.12 && lo.x > -1.0 && lo.z > -1.0,
        "{lo} {hi}"
    );
}

#[test]
fn faces_point_outwards() {
    // Most of a closed model's faces point away from its centre.
    for (text, name) in [(BUNNY_OBJ, "bunny"), (TEAPOT_OBJ, "teapot")] {
        let mesh = builtin(text, name).unwrap();
        let tris = place(&mesh, &Placement::FRONT_LEFT, 0);
        let centre: Vec3 = tris.iter().map(|t| t.centroid()).sum::<Vec3>() / tris.len() as f32;
        let out = tris
            .iter()
            .filter(|t| t.normal.dot(t.centroid() - centre) > 0.0)
            .count();
        assert!(out > tris.len() * 3 / 4, "{name}: {out} of {}", tris.len());
    }
}

#[test]
fn normals_in_the_file_orient_the_faces() {
    // One triangle, clockwise seen from +z, with normals saying it faces +z.
    let text = b"v 0 0 0\nv 0 1 0\nv 1 0 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
    let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
    assert!(mesh.normals.is_some());
    let tris = place(&mesh, &Placement::FRONT_LEFT, 0);
    assert!(tris[0].normal.z > 0.99, "{}", tris[0].normal);
}

#[test]
fn bad_files_are_errors_naming_the_file() {
    let p = Path::new("models/broken.obj");
    for text in [
        &b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"[..],
        b"v 0 zero 0\n",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
    ] {
        let e = parse_obj(text, p).unwrap_err();
        assert!(e.to_string().contains("broken.obj"), "{e}");
    }
    let e = parse_obj(b"# nothing\nv 0 0 0\n", p).unwrap_err();
    assert!(matches!(e, SceneError::EmptyMesh { .. }), "{e}");
    assert!(e.to_string().contains("broken.obj") && e.to_string().contains("no triangles"));
    let e = load_obj(Path::new("/no/such/model.obj")).unwrap_err();
    assert!(e.to_string().contains("/no/such/model.obj"), "{e}");
    let e = parse_obj(b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", p).unwrap_err();
    assert!(e.to_string().contains("not finite"), "{e}");
}

#[test]
fn element_indices_tobj_cannot_take_are_errors() {
    let p = Path::new("models/broken.obj");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nvn 0 1 0\n";
    // Relative indices before the first texture coordinate or normal (tobj multiplies the
    // wrapped index, a panic with overflow checks), and a normal index so large that
    // 3 × index wraps past 2⁶⁴.
    for (face, message) in [
        (
            "f 1/-2 2/1 3/1",
            "line 7: texture coordinate index -2 is out of range (1 read",
        ),
        (
            "f 1//-3 2//1 3//1",
            "line 7: normal index -3 is out of range (2 read",
        ),
        (
            "f 1//6148914691236517206 2//1 3//1",
            "normal index 6148914691236517206",
        ),
        ("l 1/-9 2/1", "texture coordinate index -9"),
    ] {
        let e = parse_obj(format!("{tri}{face}\n").as_bytes(), p).unwrap_err();
        assert!(e.to_string().contains("broken.obj"), "{e}");
        assert!(e.to_string().contains(message), "{e}");
    }
    // The last one of each, relative, is fine: -1 is the newest.
    let mesh = parse_obj(format!("{tri}f 1/-1/-2 2/-1/-1 3/1/1\n").as_bytes(), p).unwrap();
    assert_eq!(mesh.indices.len(), 1);
    assert_eq!(mesh.normals.unwrap()[0], Vec3::Z);
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-6
}

/// The model's triangles of a scene from [`model_in_box`] (after the box's 30).
const BOX: usize = 30;

#[test]
fn a_flat_mesh_shades_with_its_face_normal_everywhere() {
    // A 2 × 2 subdivided square in the tilted plane z = x/2 + y/4, without normals.
    let mut text = String::new();
    for y in 0..3 {
        for x in 0..3 {
            let z = 0.5 * x as f32 + 0.25 * y as f32;
            text += &format!("v {x} {y} {z}\n");
        }
    }
    for y in 0..2 {
        for x in 0..2 {
            let a = 1 + x + 3 * y;
            let (b, c, d) = (a + 1, a + 3, a + 4);
            text += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    let mesh = parse_obj(text.as_bytes(), Path::new("square.obj")).unwrap();
    assert!(mesh.normals.is_none() && mesh.uvs.is_none());
    let scene = model_in_box(&mesh, &Placement::FRONT_LEFT, "square");
    assert_eq!(scene.triangles.len(), BOX + 8);
    assert!(scene.uvs.is_empty(), "no vt: no coordinates at all");
    // The box stays flat.
    for i in 0..BOX {
        assert_eq!(scene.vertex_normals[i], None);
        let flat = scene.triangles[i].normal;
        assert_eq!(scene.shading_normal(i, 0.3, 0.3, true), flat);
    }
    let face = scene.triangles[BOX].normal;
    for i in BOX..scene.triangles.len() {
        assert!(close(scene.triangles[i].normal, face));
        for n in scene.vertex_normals[i].unwrap() {
            assert!(close(n, face), "{n} against {face}");
        }
        for (u, v) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.2, 0.7),
            (1.0 / 3.0, 0.25),
        ] {
            let n = scene.shading_normal(i, u, v, true);
            assert!(close(n, face), "{n} at ({u}, {v})");
        }
    }
}

/// The cube [−1, 1]³ as 8 shared vertices and 12 triangles, each ordered so that the lab's
/// normal points outwards; its face normals.
fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<Vec3>) {
    let positions: Vec<Vec3> = (0..8)
        .map(|i| {
            let s = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
            Vec3::new(s(1), s(2), s(4))
        })
        .collect();
    // Each face as a quad of corners in order around it, split along one diagonal.
    let quads = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let mut triangles = Vec::new();
    for [a, b, c, d] in quads {
        for mut t in [[a, b, c], [a, c, d]] {
            let [p, q, r] = t.map(|i: u32| positions[i as usize]);
            if Triangle::new(p, q, r, 0).normal.dot(p + q + r) < 0.0 {
                t.swap(1, 2);
            }
            triangles.push(t);
        }
    }
    let normals = triangles
        .iter()
        .map(|t| {
            let [p, q, r] = t.map(|i| positions[i as usize]);
            Triangle::new(p, q, r, 0).normal
        })
        .collect();
    (positions, triangles, normals)
}

#[test]
fn a_cube_keeps_its_edges_below_the_crease_angle_and_rounds_them_above() {
    let (positions, triangles, faces) = cube();
    // 90° edges are sharper than 60°: only the two triangles of a face meet at a corner.
    let sharp = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
    for (corners, face) in sharp.iter().zip(&faces) {
        for n in corners {
            assert!(close(*n, *face), "{n} against {face}");
        }
    }
    // With 100°, the three faces at a cube corner are averaged. Each face meets the corner
    // with a total angle of 90°: one triangle's right angle, or two triangles' 45° each
    // where the face's diagonal ends there. So the weights are equal,
    // Σ = π/2·(±x̂) + π/2·(±ŷ) + π/2·(±ẑ), and normalised that is (±1, ±1, ±1)/√3, the
    // corner's own position over √3 (1/√3 = 0.5773503).
    let round = smooth_normals(&positions, &triangles, &faces, 100f32.to_radians());
    for (corners, t) in round.iter().zip(&triangles) {
        for (n, &i) in corners.iter().zip(t) {
            let expected = positions[i as usize] * 0.577_350_3;
            assert!(close(*n, expected), "{n} against {expected}");
        }
    }
}

#[test]
fn faces_at_a_small_angle_are_averaged_by_their_angles_at_the_vertex() {
    // Two triangles share only the origin. A lies in z = 0 with a 45° angle there; B is
    // tilted by 20° about the y axis, normal (sin 20°, 0, cos 20°), with a 90° angle there
    // (its edges (0, 1, 0) and (−1, 0, tan 20°) are perpendicular).
    let t20 = 20f32.to_radians().tan();
    let positions = [
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-1.0, 0.0, t20),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let triangles = [[0, 1, 2], [0, 3, 4]];
    let (sin20, cos20) = (0.342_020_1, 0.939_692_6);
    let faces = [Vec3::Z, Vec3::new(sin20, 0.0, cos20)];
    for (t, face) in triangles.iter().zip(&faces) {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        assert!(close(Triangle::new(a, b, c, 0).normal, *face));
    }
    let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
    // At the origin: π/4·(0, 0, 1) + π/2·(sin 20°, 0, cos 20°) ∝ (2 sin 20°, 0, 1 + 2 cos 20°)
    // = (0.6840403, 0, 2.8793852), of length 2.9595220: (0.2311320, 0, 0.9729224), 13.4°
    // from A's normal (an unweighted mean would be 10°).
    let expected = Vec3::new(0.231_132, 0.0, 0.972_922_4);
    assert!(close(normals[0][0], expected), "{}", normals[0][0]);
    assert!(close(normals[1][0], expected), "{}", normals[1][0]);
    // Elsewhere each face is alone.
    for (corners, face) in normals.iter().zip(&faces) {
        assert!(close(corners[1], *face) && close(corners[2], *face));
    }
    // Below 20° the faces no longer meet smoothly.
    let apart = smooth_normals(&positions, &triangles, &faces, 15f32.to_radians());
    assert!(close(apart[0][0], faces[0]) && close(apart[1][0], faces[1]));
}

#[test]
fn degenerate_faces_contribute_nothing() {
    let positions = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(2.0, 0.0, 0.0), // on the x axis: 0, 1, 3 is a line
    ];
    let triangles = [[0, 1, 2], [0, 1, 3]];
    let faces = [Vec3::Z, Vec3::ZERO];
    let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
    assert_eq!(normals[0], [Vec3::Z; 3]);
    assert_eq!(normals[1], [Vec3::ZERO; 3]);
}

/// Faces by hand: 1 2 3 is kept; 2 3 1 is the same face read from another corner and
/// 3 2 1 its other side (kept); 1 2 4 has its corners on the x axis and 1 1 2 two in one
/// place (degenerate); 5 2 3 repeats 1 2 3 through vertex 5, written at 1's position as
/// −0 (a duplicate); the last 1 2 3 is a duplicate too.
#[test]
fn degenerate_and_duplicate_faces_are_left_out_and_counted() {
    let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv -0 0 -0\n\
                 f 1 2 3\nf 2 3 1\nf 3 2 1\nf 1 2 4\nf 1 1 2\nf 5 2 3\nf 1 2 3\n";
    let mesh = parse_obj(text, Path::new("faces.obj")).unwrap();
    assert_eq!(mesh.indices, [[0, 1, 2], [2, 1, 0]]);
    let mut again = Mesh {
        indices: vec![
            [0, 1, 2],
            [1, 2, 0],
            [2, 1, 0],
            [0, 1, 3],
            [0, 0, 1],
            [4, 1, 2],
        ],
        ..mesh
    };
    let dropped = drop_unseen_faces(&mut again);
    assert_eq!(
        dropped,
        DroppedFaces {
            degenerate: 2,
            duplicate: 2
        }
    );
    assert_eq!(
        dropped.warning("faces.obj").unwrap(),
        "faces.obj: left out 4 faces that can never be seen: 2 degenerate (zero area), 2 \
         exact duplicates of earlier faces"
    );
    assert_eq!(DroppedFaces::default().warning("x"), None);
    // A file of nothing but degenerate faces is refused, saying why.
    let err = parse_obj(
        b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        Path::new("line.obj"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("line.obj") && err.contains("degenerate"),
        "{err}"
    );
}

/// Around a position with more than `MAX_FAN` faces: copies of two faces give each corner
/// the normal the two faces alone give it (equal normals grouped, their angles summed), and
/// a fan of many different faces is averaged whole. Each corner there costs the number of
/// distinct normals, not of faces, which keeps the whole linear: the copies make two groups,
/// the fan one sum. How fast it runs is
/// the `degenerate` benchmark's to measure (benches/trace.rs), not a time limit here.
#[test]
fn many_faces_around_one_position_are_smoothed_in_linear_time() {
    // Two faces meeting at 30° along the y axis, as in the test above, then copied.
    let positions = [
        Vec3::ZERO,
        Vec3::Y,
        Vec3::X,
        Vec3::new(-(30f32.to_radians().cos()), 0.0, 30f32.to_radians().sin()),
    ];
    let faces = [[0, 1, 2], [0, 3, 1]];
    let face_normals: Vec<Vec3> = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i: u32| positions[i as usize]);
            (c - a).cross(b - a).normalize()
        })
        .collect();
    let crease = 60f32.to_radians();
    let two = smooth_normals(&positions, &faces, &face_normals, crease);
    let copies = 100_000;
    let many_faces: Vec<[u32; 3]> = (0..copies).map(|i| faces[i % 2]).collect();
    let many_normals: Vec<Vec3> = (0..copies).map(|i| face_normals[i % 2]).collect();
    let many = smooth_normals(&positions, &many_faces, &many_normals, crease);
    let around: Vec<(u32, f32)> = (0..copies as u32).map(|f| (f, 1.0)).collect();
    match Fan::of(&around, &many_normals) {
        Fan::Grouped(groups) => assert_eq!(groups.len(), 2),
        Fan::Whole(_) => panic!("two distinct normals are grouped"),
    }
    for (i, corners) in many.iter().enumerate() {
        for (a, b) in corners.iter().zip(&two[i % 2]) {
            assert!((*a - *b).length() < 1e-5, "face {i}: {a} against {b}");
        }
    }
    // A fan of 100,000 faces around the origin, each turned a little further about the
    // z axis and tilted up: more distinct normals than MAX_FAN, so averaged whole. The fan
    // is symmetric about the z axis, so the apex's normal is the z axis.
    let n = 100_000;
    let mut fan_positions = vec![Vec3::ZERO];
    let mut fan_faces = Vec::new();
    for k in 0..n {
        let angle = |k: usize| std::f32::consts::TAU * k as f32 / n as f32;
        let ring = |a: f32| Vec3::new(a.cos(), a.sin(), -1.0);
        fan_positions.push(ring(angle(k)));
        fan_faces.push([0, 1 + k as u32, 1 + ((k + 1) % n) as u32]);
    }
    let fan_normals: Vec<Vec3> = fan_faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i: u32| fan_positions[i as usize]);
            (b - a).cross(c - a).normalize()
        })
        .collect();
    let fan = smooth_normals(&fan_positions, &fan_faces, &fan_normals, crease);
    let around: Vec<(u32, f32)> = (0..n as u32).map(|f| (f, 1.0)).collect();
    assert!(matches!(Fan::of(&around, &fan_normals), Fan::Whole(_)));
    assert!((fan[0][0] - Vec3::Z).length() < 1e-3, "{}", fan[0][0]);
}

#[test]
fn vertices_repeated_at_a_seam_are_welded() {
    // The square of two triangles, its diagonal's vertices written twice (as at a texture
    // seam), folded by 30° along the diagonal: the diagonal's corners are averaged anyway.
    let s = 30f32.to_radians().sin();
    let positions = [
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::ZERO,
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, s),
    ];
    let triangles = [[0, 1, 2], [3, 5, 4]];
    let faces: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            Triangle::new(a, b, c, 0).normal
        })
        .collect();
    assert!(faces[0].dot(faces[1]) > 0.8 && faces[0].dot(faces[1]) < 0.99);
    let normals = smooth_normals(&positions, &triangles, &faces, 60f32.to_radians());
    assert!(close(normals[0][0], normals[1][0]) && close(normals[0][1], normals[1][2]));
    assert!(!close(normals[0][0], faces[0]));
}

#[test]
fn the_built_in_models_get_smooth_normals_near_their_faces() {
    for scene in [SceneChoice::Bunny, SceneChoice::Teapot].map(|c| c.load().unwrap()) {
        assert!(scene.uvs.is_empty());
        let mut smoothed = 0;
        for (i, t) in scene.triangles.iter().enumerate().skip(BOX) {
            for n in scene.vertex_normals[i].unwrap() {
                assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
                // A weighted mean of normals within 60° of the face stays within 60°.
                assert!(n.dot(t.normal) >= 0.5 - 1e-5, "{n} on {}", t.normal);
                smoothed += usize::from(n.dot(t.normal) < 0.9999);
            }
        }
        assert!(
            smoothed > scene.triangles.len(),
            "{smoothed} smoothed corners"
        );
    }
}

/// The scene triangle's corners as indices into a file triangle whose three vertices have
/// distinct heights (file y, which the mirror turns into scene −y whatever the yaw).
fn file_corners(t: &Triangle, file_ys: [f32; 3]) -> [usize; 3] {
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| file_ys[a].total_cmp(&file_ys[b]));
    let scene_y = [t.v0.y, t.v1.y, t.v2.y];
    let mut by_height = [0, 1, 2];
    by_height.sort_by(|&a, &b| scene_y[b].total_cmp(&scene_y[a]));
    let mut corners = [0; 3];
    for (k, f) in by_height.into_iter().zip(order) {
        corners[k] = f;
    }
    corners
}

#[test]
fn normals_from_the_file_are_transformed_and_oriented_outwards() {
    // Counter-clockwise seen from +z, so facing +z, with a normal per vertex.
    let text = b"v 0 0 0\nv 1 0.5 0\nv 0 1 0\n\
                 vn 0 0.6 0.8\nvn 0.6 0 0.8\nvn 0 -0.6 -0.8\n\
                 f 1//1 2//2 3//3\n";
    let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
    // Turned a quarter: the file's +z becomes +x and its +x becomes −z; y is mirrored.
    let placement = Placement {
        yaw: std::f32::consts::FRAC_PI_2,
        ..Placement::FRONT_LEFT
    };
    let scene = model_in_box(&mesh, &placement, "t");
    let t = scene.triangles[BOX];
    assert!(close(t.normal, Vec3::X), "{}", t.normal);
    // (0, 0.6, 0.8) → mirrored (0, −0.6, 0.8) → turned (0.8, −0.6, 0);
    // (0.6, 0, 0.8) → (0.6, 0, 0.8) → (0.8, 0, −0.6);
    // (0, −0.6, −0.8) → (0, 0.6, −0.8) → (−0.8, 0.6, 0), behind the face: negated.
    let expected = [
        Vec3::new(0.8, -0.6, 0.0),
        Vec3::new(0.8, 0.0, -0.6),
        Vec3::new(0.8, -0.6, 0.0),
    ];
    let corners = file_corners(&t, [0.0, 0.5, 1.0]);
    let normals = scene.vertex_normals[BOX].unwrap();
    for k in 0..3 {
        let e = expected[corners[k]];
        assert!(
            close(normals[k], e),
            "corner {k}: {} against {e}",
            normals[k]
        );
    }
    // Wound the other way, the file's normals still turn the face (and its corners) to +x.
    let text = b"v 0 0 0\nv 1 0.5 0\nv 0 1 0\n\
                 vn 0 0.6 0.8\nvn 0.6 0 0.8\nvn 0 -0.6 -0.8\n\
                 f 1//1 3//3 2//2\n";
    let mesh = parse_obj(text, Path::new("t.obj")).unwrap();
    let scene = model_in_box(&mesh, &placement, "t");
    let t = scene.triangles[BOX];
    assert!(close(t.normal, Vec3::X), "{}", t.normal);
    let corners = file_corners(&t, [0.0, 0.5, 1.0]);
    let normals = scene.vertex_normals[BOX].unwrap();
    for k in 0..3 {
        assert!(close(normals[k], expected[corners[k]]), "corner {k}");
    }
}

#[test]
fn texture_coordinates_come_from_the_file() {
    for face in ["f 1/1 2/2 3/3\n", "f 1/1 3/3 2/2\n"] {
        let text =
            format!("v 0 0 0\nv 1 0.5 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.9 0.3\nvt 0.4 0.8\n{face}");
        let mesh = parse_obj(text.as_bytes(), Path::new("t.obj")).unwrap();
        let vt = [
            Vec2::new(0.1, 0.2),
            Vec2::new(0.9, 0.3),
            Vec2::new(0.4, 0.8),
        ];
        // tobj numbers vertices in the order the faces first use them.
        assert_eq!(mesh.uvs.as_ref().map(Vec::len), Some(3));
        let scene = model_in_box(&mesh, &Placement::TEAPOT, "t");
        assert_eq!(scene.uvs.len(), BOX + 1);
        assert_eq!(scene.uv(0, 0.2, 0.2), None, "the box has none");
        let corners = file_corners(&scene.triangles[BOX], [0.0, 0.5, 1.0]);
        // Barycentric (0, 0), (1, 0), (0, 1) are v0, v1, v2.
        for (k, (u, v)) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].into_iter().enumerate() {
            assert_eq!(scene.uv(BOX, u, v), Some(vt[corners[k]]), "{face}");
        }
        // The centroid: ((0.1 + 0.9 + 0.4)/3, (0.2 + 0.3 + 0.8)/3) = (0.4666667, 0.4333333).
        let mid = scene.uv(BOX, 1.0 / 3.0, 1.0 / 3.0).unwrap();
        assert!(
            (mid - Vec2::new(0.466_666_7, 0.433_333_3))
                .abs()
                .max_element()
                < 1e-6
        );
    }
}

#[test]
fn non_finite_normals_or_coordinates_are_errors() {
    let e = parse_obj(
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nf 1//1 2//1 3//1\n",
        Path::new("n.obj"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("n.obj") && e.to_string().contains("normal"));
    let e = parse_obj(
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt nan 0\nf 1/1 2/1 3/1\n",
        Path::new("t.obj"),
    )
    .unwrap_err();
    assert!(e.to_string().contains("texture coordinate"), "{e}");
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0.5 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                        usemtl glaze\nf 1/1 2/2 3/3\n";

/// The model's material and the warnings, from an OBJ written to a temporary folder with
/// the other `files`.
fn load_from_folder(files: &[(&str, &[u8])]) -> (Scene, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let path = dir.path().join("model.obj");
    let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
    // The wrapper gives the same scene.
    let plain = obj_scene(&path).unwrap();
    assert_eq!(plain.triangles, scene.triangles);
    (scene, warnings)
}

/// A PNG of one colour, 2×2.
fn png_of(rgb: [u8; 3]) -> Vec<u8> {
    let image = image::RgbImage::from_pixel(2, 2, image::Rgb(rgb));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

/// The MTL's map statements: the options skipped with their values, `-bm` kept.
#[test]
fn map_options_give_the_file_and_the_bump_multiplier() {
    assert_eq!(
        map_options("-bm 0.5 file.png"),
        ("file.png".into(), Some(0.5))
    );
    assert_eq!(map_options("file.png"), ("file.png".into(), None));
    assert_eq!(
        map_options("-s 2 2 1 -o 0.5 -bm 0.25 -clamp on maps/n m.png"),
        ("maps/n m.png".into(), Some(0.25))
    );
    // `-s` with one number, then the file (a number is not taken past the last word).
    assert_eq!(map_options("-s 2 3.png"), ("3.png".into(), None));
    assert_eq!(map_options(""), (String::new(), None));
}

/// `map_Bump -bm 0.5 file.png` (as Blender writes a normal map) gives the model a normal map
/// of strength 0.5, found beside the library; `norm file.png` is read as a normal map too,
/// and wins over `map_Bump`. The memory estimate counts the normal map beside the texture.
#[test]
fn a_material_librarys_normal_map_is_read() {
    let obj = format!("mtllib model.mtl\n{TRIANGLE}");
    let tilted = png_of([192, 128, 255]);
    let flat = png_of([128, 128, 255]);
    let blender = b"newmtl glaze\nKd 0.9 0.9 0.9\nmap_Bump -bm 0.5 bumps.png\n";
    let (scene, warnings) = load_from_folder(&[
        ("model.obj", obj.as_bytes()),
        ("model.mtl", blender),
        ("bumps.png", &tilted),
    ]);
    assert!(warnings.is_empty(), "{warnings:?}");
    let relief = scene.material_of(BOX).relief.clone().unwrap();
    let map = relief.normal.as_ref().unwrap();
    assert_eq!(map.strength, 0.5);
    assert!(map.image.name.ends_with("bumps.png"), "{}", map.image.name);
    assert_eq!(map.image.texels[0], Vec3::new(64.0 / 127.0, 0.0, 1.0));
    assert!(relief.height.is_none());

    let both = b"newmtl glaze\nmap_Bump bumps.png\nnorm flat.png\n";
    let (scene, _) = load_from_folder(&[
        ("model.obj", obj.as_bytes()),
        ("model.mtl", both),
        ("bumps.png", &tilted),
        ("flat.png", &flat),
    ]);
    let relief = scene.material_of(BOX).relief.clone().unwrap();
    let map = relief.normal.as_ref().unwrap();
    assert_eq!((map.strength, map.image.texels[0]), (1.0, Vec3::Z));

    // A library in a folder: the map's name is relative to it.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("lib")).unwrap();
    std::fs::write(dir.path().join("lib/model.mtl"), blender).unwrap();
    std::fs::write(dir.path().join("lib/bumps.png"), &tilted).unwrap();
    let path = dir.path().join("model.obj");
    std::fs::write(&path, format!("mtllib lib/model.mtl\n{TRIANGLE}")).unwrap();
    let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let relief = scene.material_of(BOX).relief.clone().unwrap();
    assert_eq!(relief.normal.as_ref().unwrap().strength, 0.5);
    let (_, _, normal_maps) = scan_library(blender);
    assert_eq!(normal_maps, ["bumps.png"]);
    let obj_len = std::fs::metadata(&path).unwrap().len();
    let png_len = tilted.len() as u64;
    assert_eq!(
        memory_estimate(&path),
        OBJ_BYTES_FACTOR * obj_len
            + library_bytes(blender.len() as u64, 1)
            + TextureImage::decoding_bytes(2, 2)
            + png_len
    );
}

/// A grey `map_Bump` is a bump map of heights, not a normal map: a warning, no map. A
/// missing or broken one is a warning too; the model loads either way.
#[test]
fn a_grey_or_missing_bump_map_is_a_warning() {
    let obj = format!("mtllib model.mtl\n{TRIANGLE}");
    let mtl = b"newmtl glaze\nmap_Bump bumps.png\n";
    let grey = png_of([90, 90, 90]);
    for (file, says) in [
        (Some(grey.as_slice()), "is grey: a bump map of heights"),
        (None, "bumps.png"),
        (Some(b"not a PNG".as_slice()), "not a PNG or JPEG"),
    ] {
        let mut files = vec![("model.obj", obj.as_bytes()), ("model.mtl", mtl.as_slice())];
        files.extend(file.map(|f| ("bumps.png", f)));
        let (scene, warnings) = load_from_folder(&files);
        assert!(scene.material_of(BOX).relief.is_none());
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains(says), "{warnings:?}");
    }
}

#[test]
fn a_missing_or_broken_material_library_or_texture_is_a_warning() {
    let obj = format!("mtllib model.mtl\n{TRIANGLE}");
    let mtl = b"newmtl glaze\nKd 0.9 0.9 0.9\nmap_Kd porcelain.png\n";
    for (files, names) in [
        (vec![("model.obj", obj.as_bytes())], "model.mtl"),
        (
            vec![("model.obj", obj.as_bytes()), ("model.mtl", b"Kd 1 x 1\n")],
            "model.mtl",
        ),
        (
            vec![("model.obj", obj.as_bytes()), ("model.mtl", mtl)],
            "porcelain.png",
        ),
        (
            vec![
                ("model.obj", obj.as_bytes()),
                ("model.mtl", mtl),
                ("porcelain.png", b"not a PNG"),
            ],
            "porcelain.png",
        ),
    ] {
        let (scene, warnings) = load_from_folder(&files);
        assert_eq!(scene.triangles.len(), BOX + 1);
        let model = scene.material_of(BOX);
        assert_eq!(model.name, "model");
        assert!(model.texture.is_none());
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains(names), "{warnings:?}");
        // The coordinates are there all the same.
        assert!(scene.uv(BOX, 0.0, 0.0).is_some());
    }
    // Without a library, or with one whose material has no texture: nothing to say.
    let plain = format!("mtllib model.mtl\n{TRIANGLE}");
    for files in [
        vec![("model.obj", TRIANGLE.as_bytes())],
        vec![
            ("model.obj", plain.as_bytes()),
            ("model.mtl", b"newmtl glaze\nKd 1 1 1\n"),
        ],
    ] {
        let (scene, warnings) = load_from_folder(&files);
        assert!(warnings.is_empty(), "{warnings:?}");
        assert!(scene.material_of(BOX).texture.is_none());
    }
}

/// One library of 2,000 materials named by 8,000 `mtllib` lines (read once a line, it
/// would ask for gigabytes): read once, its 2,000 materials in once, and the estimate
/// counts it once.
#[test]
fn a_library_named_many_times_is_read_once() {
    let dir = tempfile::tempdir().unwrap();
    let mtl: String = (0..2000)
        .map(|i| format!("newmtl m{i}\nKd 1 1 1\n"))
        .collect();
    std::fs::write(dir.path().join("lib.mtl"), &mtl).unwrap();
    let obj = format!("{}usemtl m7\n{TRIANGLE}", "mtllib lib.mtl\n".repeat(8000));
    let path = dir.path().join("model.obj");
    std::fs::write(&path, &obj).unwrap();
    let (parsed, warnings) = parse_file(&path).unwrap();
    assert_eq!(parsed.materials.len(), 2000);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(
        memory_estimate(&path),
        OBJ_BYTES_FACTOR * obj.len() as u64 + library_bytes(mtl.len() as u64, 2000)
    );
    let (scene, _) = obj_scene_with_warnings(&path).unwrap();
    assert_eq!(scene.triangles.len(), BOX + 1);
}

/// 100,000 missing libraries: three warnings name the first three, a fourth counts the
/// rest (not megabytes of warnings, one a library). A FIFO named as a library is
/// refused at once, not waited on.
#[test]
fn many_missing_libraries_are_summarised() {
    let dir = tempfile::tempdir().unwrap();
    let obj: String = (0..100_000)
        .map(|i| format!("mtllib missing-{i}.mtl\n"))
        .chain([TRIANGLE.to_owned()])
        .collect();
    let (_, warnings) = load_from_folder(&[("model.obj", obj.as_bytes())]);
    assert_eq!(warnings.len(), LISTED_LIBRARY_FAILURES + 1, "{warnings:?}");
    assert!(warnings[0].contains("missing-0.mtl"), "{warnings:?}");
    assert!(warnings[2].contains("missing-2.mtl"), "{warnings:?}");
    assert!(
        warnings[3].ends_with(
            "model.obj: 99997 more material libraries could not be read either; their \
             materials are not used"
        ),
        "{warnings:?}"
    );
    #[cfg(unix)]
    {
        crate::base::inputs::make_fifo(&dir.path().join("fifo.mtl"));
        let path = dir.path().join("fifo.obj");
        std::fs::write(&path, format!("mtllib fifo.mtl\n{TRIANGLE}")).unwrap();
        let (_, warnings) = obj_scene_with_warnings(&path).unwrap();
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].contains("not a regular file (a FIFO)"),
            "{warnings:?}"
        );
    }
}

/// A library in a sub-folder names its texture relative to itself, as MTL files do: the
/// texture beside the library is found, not one beside the OBJ file.
#[test]
fn a_texture_is_found_beside_the_library_that_names_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("materials")).unwrap();
    let mtl = "newmtl glaze\nmap_Kd porcelain.png\n";
    std::fs::write(dir.path().join("materials/lib.mtl"), mtl).unwrap();
    let mut png = Vec::new();
    let image = crate::transport::film::Image::new(2, 2);
    png.extend(
        image
            .encode(crate::transport::film::OutputFormat::Png)
            .unwrap(),
    );
    std::fs::write(dir.path().join("materials/porcelain.png"), &png).unwrap();
    let path = dir.path().join("model.obj");
    std::fs::write(&path, format!("mtllib materials/lib.mtl\n{TRIANGLE}")).unwrap();
    let (scene, warnings) = obj_scene_with_warnings(&path).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(scene.material_of(BOX).texture.is_some());
    // The estimate finds the same texture: its 2×2 texels and its file.
    let obj_len = std::fs::metadata(&path).unwrap().len();
    assert_eq!(
        memory_estimate(&path),
        OBJ_BYTES_FACTOR * obj_len
            + library_bytes(mtl.len() as u64, 1)
            + TextureImage::decoding_bytes(2, 2)
            + png.len() as u64
    );
}

#[test]
fn a_texture_without_coordinates_and_several_materials_are_warned_about() {
    let obj = "mtllib model.mtl\nv 0 0 0\nv 1 0.5 0\nv 0 1 0\nv 0 0 1\n\
               usemtl glaze\nf 1 2 3\nusemtl matt\nf 1 3 4\n";
    let mtl = b"newmtl glaze\nmap_Kd porcelain.png\nnewmtl matt\nKd 1 1 1\n";
    let (_, warnings) = load_from_folder(&[("model.obj", obj.as_bytes()), ("model.mtl", mtl)]);
    assert_eq!(warnings.len(), 3, "{warnings:?}");
    assert!(warnings[0].contains("2 materials") && warnings[0].contains("'glaze'"));
    assert!(warnings[1].contains("no texture coordinates"));
    assert!(warnings[2].contains("porcelain.png"));
}

#[test]
fn a_built_in_textured_model_with_an_undecodable_image_is_untextured_with_a_warning() {
    let obj = format!("mtllib teapot-textured.mtl\n{TRIANGLE}");
    let mtl = "newmtl glaze\nmap_Kd teapot-porcelain.png\n";
    let (scene, warnings) =
        builtin_textured(&obj, mtl, b"\x89PNG broken", "teapot", &Placement::TEAPOT).unwrap();
    assert_eq!(scene.triangles.len(), BOX + 1);
    assert!(scene.material_of(BOX).texture.is_none());
    assert_eq!(scene.material_of(BOX).name, "teapot");
    assert!(scene.uv(BOX, 0.0, 0.0).is_some());
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("assets/models/teapot-porcelain.png"));
    // A library naming no texture is said too; bad OBJ text is an error naming the model.
    let (_, warnings) =
        builtin_textured(&obj, "newmtl glaze\n", &[], "teapot", &Placement::TEAPOT).unwrap();
    assert!(warnings[0].contains("no texture"), "{warnings:?}");
    let e = builtin_textured("v 0 0 0\n", mtl, &[], "teapot", &Placement::TEAPOT).unwrap_err();
    assert!(e.to_string().contains("assets/models/teapot.obj"), "{e}");
}
