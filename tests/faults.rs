//! Inputs that once crashed the program, overwrote or lost a file, or gave a wrong answer
//! silently, run as a user runs them: each test checks the message a user gets, that nothing
//! crashed, and that nothing was written that should not have been.
//!
//! * Coincident and degenerate geometry (a million copies of one triangle) loads and builds,
//!   and the structures still answer as the brute-force loop does.
//! * A render or bench too large for the memory the process may use, or a texture too large
//!   to decode, is refused at once, saying how much it needs and how much there is.
//! * Huge but finite light is refused, naming the bound, instead of writing infinite pixels.
//! * A light outside the box does not leak in along its edges; a camera on a wall sees the
//!   room.
//! * Files: paths that are not UTF-8, FIFOs and devices, oversized or damaged screenshots,
//!   text with control characters, scene files saved over their input or out of range.
//! * The process: signals during a write, a full stderr or stdout, thread counts and kernel
//!   names from the environment.

mod common;

use glam::Vec3;
use raylab_core::base::geometry::{Ray, Triangle};
use raylab_core::base::sampling::Rng;
use raylab_core::shapes::accel::AccelKind;
use raylab_core::shapes::intersect::{closest_intersection_brute_force, occluded_brute_force};
use raylab_core::shapes::scene::{Material, Scene};

use common::rays::random_dir;
use common::{raylab, stderr};

// ---------------------------------------------------------------------------------------------
// Many copies of one triangle.

/// How many copies the big-input tests use: a million in release builds, where it takes well
/// under a second; 200,000 in the tests' debug builds, to stay quick there (the fault took
/// minutes at 300,000).
const COPIES: usize = if cfg!(debug_assertions) {
    200_000
} else {
    1_000_000
};

/// The triangle the copies are of: (−1, −1, 2), (1, −1, 2), (0, 1, 2), facing the origin.
fn the_triangle() -> Triangle {
    Triangle::new(
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
        0,
    )
}

/// Rays from random points of the cube [−3, 3]³, half aimed at a random point of a random
/// triangle (so that they hit, or pass its edge closely), half in random directions.
fn rays_at(triangles: &[Triangle], count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|i| {
            let o = Vec3::new(
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
                rng.uniform(-3.0, 3.0),
            );
            if i % 2 == 0 {
                let t = &triangles[rng.next_u32() as usize % triangles.len()];
                let (u, v) = (rng.next_f32(), rng.next_f32());
                let (u, v) = if u + v > 1.0 {
                    (1.0 - u, 1.0 - v)
                } else {
                    (u, v)
                };
                Ray::new(o, t.point_at(u, v) - o)
            } else {
                Ray::new(o, random_dir(&mut rng))
            }
        })
        .collect()
}

/// Builds `triangles` into each kind of structure (with the best kernels) and checks every
/// answer on `rays` against the brute-force loop, bit for bit. Returns how many rays hit.
fn build_and_compare(triangles: &[Triangle], rays: &[Ray]) -> usize {
    let materials = vec![Material::diffuse("m", Vec3::ONE)];
    let expected: Vec<_> = rays
        .iter()
        .map(|r| {
            (
                closest_intersection_brute_force(r, triangles, f32::INFINITY),
                occluded_brute_force(r, triangles, 5.0),
            )
        })
        .collect();
    for kind in [AccelKind::Bvh2, AccelKind::Bvh8] {
        let scene = Scene::with_accel(
            triangles.to_vec(),
            materials.clone(),
            kind,
            raylab_core::shapes::scene::best_isa(),
        );
        for (ray, (closest, occluded)) in rays.iter().zip(&expected) {
            assert_eq!(
                scene.closest_intersection(ray, f32::INFINITY),
                *closest,
                "{kind}: {ray:?}"
            );
            assert_eq!(scene.occluded(ray, 5.0), *occluded, "{kind}: {ray:?}");
        }
    }
    expected.iter().filter(|e| e.0.is_some()).count()
}

/// A million copies of one triangle (an OBJ file of them, built directly): the copies leave the
/// tree (a ray tests one triangle, not a million), and every answer is the brute-force loop's:
/// the first copy, index 0. How fast it builds is measured by the `degenerate` benchmark
/// (`benches/trace.rs`), not here: a busy machine would fail a time limit by chance.
#[test]
fn a_million_copies_of_one_triangle_build_quickly_and_answer_as_brute_force() {
    let triangles = vec![the_triangle(); COPIES];
    let rays = rays_at(&triangles, 40, 31);
    let hits = build_and_compare(&triangles, &rays);
    assert!(hits >= 15, "{hits} of 40 rays hit");
    let bvh = raylab_core::shapes::accel::bvh::Bvh::build(&triangles);
    assert_eq!(bvh.nodes.len(), 1, "one leaf");
    assert_eq!(bvh.indices, [0], "the first copy is the one kept");
    let hit = Scene::new(triangles, vec![Material::diffuse("m", Vec3::ONE)])
        .closest_intersection(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY)
        .unwrap();
    assert_eq!((hit.triangle_index, hit.distance), (0, 2.0));
}

/// Different triangles whose centroids all coincide: no split can separate them, the build
/// halves them at the median, its depth stays logarithmic, and the answers are the brute-force
/// loop's. (The build's centroid is the centre of a triangle's box: with corners a, −a and a
/// point b inside the box they span, it is exactly the origin for every triangle.)
#[test]
fn triangles_with_one_centroid_build_a_shallow_tree_and_answer_as_brute_force() {
    let mut rng = Rng::new(32);
    let n = COPIES / 10;
    let triangles: Vec<Triangle> = (0..n)
        .map(|_| {
            let a = random_dir(&mut rng);
            let inside = Vec3::new(
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            );
            Triangle::new(a, -a, a * inside, 0)
        })
        .collect();
    for t in &triangles {
        let b = raylab_core::shapes::accel::bvh::Aabb::of_triangle(t).unwrap();
        assert_eq!(b.centre(), Vec3::ZERO);
    }
    let bvh = raylab_core::shapes::accel::bvh::Bvh::build(&triangles);
    let log2 = (n as f64).log2().ceil() as usize;
    assert!(bvh.depth() <= log2 + 42, "depth {} for {n}", bvh.depth());
    let rays = rays_at(&triangles, 200, 33);
    let hits = build_and_compare(&triangles, &rays);
    assert!(hits >= 100, "{hits} of 200 rays hit");
}

/// A million triangles all in one point (zero area): no ray can hit them, so the tree is
/// empty, and nothing is hit.
#[test]
fn a_million_triangles_in_one_point_build_an_empty_tree() {
    let p = Vec3::new(0.25, 0.5, 2.0);
    let triangles = vec![Triangle::new(p, p, p, 0); COPIES];
    let bvh = raylab_core::shapes::accel::bvh::Bvh::build(&triangles);
    assert!(bvh.nodes.is_empty() && bvh.indices.is_empty());
    let mut rays = rays_at(&triangles, 20, 34);
    rays.push(Ray::new(Vec3::ZERO, p));
    let hits = build_and_compare(&triangles, &rays);
    assert_eq!(hits, 0);
}

/// An OBJ file of one triangle, then `f 1 2 3` over and over (8 MB for a million): the copies
/// are left out with a warning saying how many, and the command line renders it, printing that
/// warning. (How fast: the `degenerate` benchmark times it.)
#[test]
fn an_obj_of_many_copies_of_one_face_loads_quickly_and_says_what_it_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("copies.obj");
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n");
    text.push_str(&"f 1 2 3\n".repeat(COPIES));
    // A face with its corners on a line, and a copy read from another corner (the same face).
    text.push_str("f 1 2 4\nf 3 1 2\n");
    std::fs::write(&obj, &text).unwrap();

    let (scene, warnings) =
        raylab_core::shapes::scene::spec::obj_scene_with_warnings(&obj).unwrap();
    // The box's 30 triangles and the one face.
    assert_eq!(
        scene.triangles.len(),
        raylab_core::shapes::scene::CORNELL_TRIANGLES + 1
    );
    let want = format!(
        "{}: left out {} faces that can never be seen: 1 degenerate (zero area), {} exact \
         duplicates of earlier faces",
        obj.display(),
        COPIES + 1,
        COPIES
    );
    assert_eq!(warnings, std::slice::from_ref(&want));

    let png = dir.path().join("copies.png");
    let out = raylab(&[
        "render",
        "--obj",
        obj.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stderr(&out), format!("warning: {want}\n"));
    assert_eq!(image::open(&png).unwrap().width(), 32);
}

// ---------------------------------------------------------------------------------------------
// Huge but finite light.

/// `raylab render ARGS… --out DIR/x.exr`, which must be refused: exit code 1, one line naming
/// `names`, and no file (nor a temporary one) left in the folder.
fn assert_render_refused(args: &[&str], names: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("x.exr");
    let mut argv = vec!["render", "--out", exr.to_str().unwrap()];
    argv.extend_from_slice(args);
    let out = raylab(&argv);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    for name in names {
        assert!(err.contains(name), "{args:?}: '{err}' should say '{name}'");
    }
    assert!(
        common::files_in(dir.path()).is_empty(),
        "{args:?} wrote a file"
    );
}

/// Light beyond its bounds would write ∞ into the EXR; it is refused, saying which value and
/// what its bound is.
#[test]
fn huge_light_and_indirect_light_are_refused_with_their_bound() {
    assert_render_refused(
        &["--light", "0,0.999,0", "--light-power", "1e38"],
        &["invalid light power 1e38", "at most 1e6 W"],
    );
    assert_render_refused(
        &["--indirect", "1e38"],
        &["invalid indirect light (1e38, 1e38, 1e38)", "at most 1e6"],
    );
    assert_render_refused(
        &["--light-colour", "1,1e30,1"],
        &["invalid light colour", "at most 1000"],
    );
}

/// At the bounds the image is written, and every value in the EXR is finite.
#[test]
fn the_largest_allowed_light_writes_a_finite_exr() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("bright.exr");
    let out = raylab(&[
        "render",
        "--out",
        exr.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--light",
        "0,0.999,0",
        "--light-power",
        "1e6",
        "--light-colour",
        "1000,1000,1000",
        "--indirect",
        "1e6",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let pixels = image::open(&exr).unwrap().to_rgb32f().into_raw();
    assert!(pixels.iter().all(|v| v.is_finite()), "{pixels:?}");
    // A kilowatt-scale light a millimetre above the floor: the walls near it are lit at
    // D = 1e9 · cos / (4π r²), hundreds of millions for r of a few tenths.
    let brightest = pixels.iter().copied().fold(0.0, f32::max);
    assert!(brightest > 1e8, "{brightest}");
}

// ---------------------------------------------------------------------------------------------
// Light through the box's edges; a camera on a wall.

/// The `shadows` stage (figure 6: ρ·D with shadows, no indirect term) of the box from the
/// default camera, with the light at `light`.
fn shadows_stage(light: Vec3, side: u32) -> raylab_core::Image {
    let mut s = common::settings(raylab_core::Stage::Shadows, side);
    s.light.position = light;
    raylab_core::transport::render::render(&raylab_core::shapes::scene::cornell_box(), &s)
}

/// A light outside the box (which spans −1..1) lights nothing inside it: the walls stand in the
/// way. The fault: at (1.5, 0, 0), 32 pixels of a 128 × 128 image along the floor's edge with
/// the right wall were lit, their shadow rays slipping out through the corner. The default
/// camera sees no surface facing such a light from outside, so every pixel is black; the same
/// from the left, above (y points down), below and behind.
#[test]
fn a_light_outside_the_box_lights_nothing_inside() {
    for light in [
        Vec3::new(1.5, 0.0, 0.0),
        Vec3::new(-1.5, 0.3, 0.2),
        Vec3::new(0.2, -1.5, 0.0),
        Vec3::new(0.0, 1.5, 0.3),
        Vec3::new(0.0, 0.0, 1.5),
    ] {
        for side in [128, 96, 255] {
            let image = shadows_stage(light, side);
            let lit = image.pixels.iter().filter(|p| **p != Vec3::ZERO).count();
            assert_eq!(lit, 0, "light at {light}, {side}²: {lit} pixels lit");
        }
    }
    // The command as a user runs it (the lab stage: with N, so not black; the floor's
    // edge pixels must be ρ·N exactly, not ρ·(D + N)).
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("outside.png");
    let out = raylab(&[
        "render",
        "--light",
        "1.5,0,0",
        "--width",
        "128",
        "--height",
        "128",
        "--stage",
        "shadows",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let rgb = image::open(&png).unwrap().to_rgb8();
    assert!(
        rgb.pixels().all(|p| p.0 == [0, 0, 0]),
        "lit pixels in the PNG"
    );
}

/// The corner pixels themselves, where the fault lit the floor: the pixel centres on the image's
/// diagonal from (96, 96) to (127, 127) see the edge where the floor meets the right wall
/// (x = y = 1: the ray through (i + ½, i + ½) runs along x = y). From outside all are dark.
/// From inside (the lab's light) each is lit exactly when the segment from its point to the
/// light crosses neither block: derived here from the geometry, the point found and the
/// segment tested against the blocks' twenty triangles by the reference intersection
/// (Cramer's rule, one triangle at a time), not by the renderer's shadow rays.
#[test]
fn the_floor_edge_is_lit_from_inside_and_dark_from_outside() {
    use raylab_core::shapes::intersect::{closest_intersection_brute_force, intersect_triangle};
    let light = raylab_core::LightSpec::default().position;
    let inside = shadows_stage(light, 128);
    let outside = shadows_stage(Vec3::new(1.5, 0.0, 0.0), 128);
    let scene = raylab_core::shapes::scene::cornell_box();
    let camera = common::settings(raylab_core::Stage::Shadows, 128).camera;
    let mut shadowed = Vec::new();
    for i in 96..128 {
        let ray = camera.pixel_ray(i, i);
        let hit = closest_intersection_brute_force(&ray, &scene.triangles, f32::INFINITY)
            .expect("the edge is hit");
        let p = hit.position;
        assert!(
            (p.x - 1.0).abs() < 1e-5 && (p.y - 1.0).abs() < 1e-5,
            "({i}, {i}) sees {p}, not the edge"
        );
        let to_light = light - p;
        let segment = Ray::new(p, to_light);
        let blocked = scene.triangles[10..30]
            .iter()
            .any(|t| intersect_triangle(&segment, t, to_light.length()).is_some());
        let lit = inside.get(i, i).y > 0.05;
        assert_eq!(lit, !blocked, "({i}, {i}) at {p}: {}", inside.get(i, i));
        if blocked {
            shadowed.push(i);
        }
        assert_eq!(outside.get(i, i), Vec3::ZERO, "({i}, {i})");
    }
    // Both cases occur along the edge (the short block's shadow falls across it), so the
    // comparison above tests something.
    assert!(
        !shadowed.is_empty() && shadowed.len() < 32,
        "shadowed: {shadowed:?}"
    );
}

/// A camera exactly in the box's top-left front corner (−1, −1, −1), looking along +z, stands
/// on the left wall and the ceiling. It used to see that wall in every pixel (its rays met it at
/// t = 0); now it sees what lies in front of it. By hand, on 16 × 16 pixels (focal length 16):
/// pixel (x, y)'s ray goes along (x + ½ − 8, y + ½ − 8, 16), so only the rays of the bottom-right
/// quarter (x, y ≥ 8) go into the box; they meet the white back wall (z = 1) at
/// (−1 + (x − 7.5)/8, −1 + (y − 7.5)/8), above the blocks (flat stage: ρ = 0.75). The others
/// leave through the walls the camera stands on and see nothing: black.
#[test]
fn a_camera_in_a_corner_sees_the_room_in_front_of_it() {
    let mut s = common::settings(raylab_core::Stage::Flat, 16);
    s.camera.position = Vec3::new(-1.0, -1.0, -1.0);
    let image =
        raylab_core::transport::render::render(&raylab_core::shapes::scene::cornell_box(), &s);
    for y in 0..16 {
        for x in 0..16 {
            let want = if x >= 8 && y >= 8 {
                Vec3::splat(0.75)
            } else {
                Vec3::ZERO
            };
            assert_eq!(image.get(x, y), want, "pixel ({x}, {y})");
        }
    }
}

/// A camera exactly on the back wall (z = 1) looking into the box sees the room as a camera a
/// hair in front of the wall does, not the wall (the fault: one colour everywhere), whatever
/// the stage.
#[test]
fn a_camera_on_a_wall_sees_what_is_in_front_of_it() {
    let scene = raylab_core::shapes::scene::cornell_box();
    for stage in [raylab_core::Stage::Flat, raylab_core::Stage::Lab] {
        let mut on = common::settings(stage, 48);
        on.camera.position = Vec3::new(0.0, 0.0, 1.0);
        on.camera.yaw = std::f32::consts::PI;
        let mut before = on.clone();
        before.camera.position.z = 1.0 - 1e-3;
        let (a, b) = (
            raylab_core::transport::render::render(&scene, &on),
            raylab_core::transport::render::render(&scene, &before),
        );
        // The blue and red blocks and the open front (black) at least, not one colour.
        let colours: std::collections::HashSet<[u32; 3]> = common::bits(&a).into_iter().collect();
        assert!(colours.len() >= 3, "{stage}: {} colours", colours.len());
        // Only where a pixel's ray passes an edge within the millimetre may they differ.
        let differ = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(p, q)| (**p - **q).abs().max_element() > 1e-2)
            .count();
        assert!(differ <= 48, "{stage}: {differ} pixels differ");
    }
}

// ---------------------------------------------------------------------------------------------
// The largest images under a memory limit.

/// Runs `raylab ARGS…` under `ulimit -v KIB` (an address-space limit): its output.
fn raylab_limited(kib: u32, args: &[&str]) -> std::process::Output {
    std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .output()
        .expect("run raylab under sh")
}

/// Refused before any work: exit code 1, one line saying what is needed and what the limit
/// leaves, and no image nor temporary file. (Had the render started, the image's allocation
/// would have failed under the limit with another message, "could not allocate …".)
fn assert_refused_for_memory(kib: u32, args: &[&str], out: &str, needs: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(out);
    let mut argv = args.to_vec();
    if args[0] == "render" {
        argv.extend(["--out", out.to_str().unwrap()]);
    }
    let out = raylab_limited(kib, &argv);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with(&format!("error: {needs} but only ")),
        "{args:?}: {err}"
    );
    assert!(
        err.trim_end()
            .ends_with(" GiB is available (address-space limit: ulimit -v)"),
        "{args:?}: {err}"
    );
    assert!(
        common::files_in(dir.path()).is_empty(),
        "{args:?} wrote a file"
    );
}

/// A 16384 × 16384 render must not abort after rendering ("memory allocation … failed", exit
/// code 134) for want of memory to write its PNG or EXR: it needs one image, 3 GiB, plus
/// 64 MiB for the program: 3.1 GiB. That fits under `ulimit -v 4000000` (3.8 GiB),
/// so here the limit is 3,000,000 KiB (2.9 GiB, less what the program already uses): refused.
/// Under the 4 GB limit, what still does not fit is refused as well: the variance view
/// (32 bytes a pixel: 8.1 GiB), and the bench (its rays, 64 bytes a pixel: 16.4 GiB).
#[test]
fn a_render_too_large_for_the_memory_is_refused_at_once() {
    let side = ["--width", "16384", "--height", "16384"];
    for out in ["X.png", "X.exr"] {
        assert_refused_for_memory(
            3_000_000,
            &[&["render"][..], &side].concat(),
            out,
            "a 16384×16384 render needs about 3.1 GiB",
        );
    }
    assert_refused_for_memory(
        4_000_000,
        &[
            &["render", "--view", "variance", "--samples", "2"][..],
            &side,
        ]
        .concat(),
        "X.png",
        "a 16384×16384 render needs about 8.1 GiB",
    );
    assert_refused_for_memory(
        4_000_000,
        &[&["bench", "--scene", "cornell"][..], &side].concat(),
        "",
        "a 16384×16384 bench needs about 16.1 GiB",
    );
}

// ---------------------------------------------------------------------------------------------
// Files: names, kinds, sizes and contents raylab must not trust.

/// `raylab ARGS…` run in `dir`, killed and failed if it has not finished after a minute: for
/// inputs that used to make it wait for ever (a FIFO). The minute is not a speed limit, only
/// the line between "finished" and "waiting".
fn raylab_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run raylab");
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            panic!("raylab {args:?} was still waiting after a minute");
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.wait_with_output().unwrap()
}

/// A one-line error (exit code 1, no panic) containing every one of `says`.
fn assert_one_line_error(out: &std::process::Output, says: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for s in says {
        assert!(err.contains(s), "'{err}' should say '{s}'");
    }
}

const TETRAHEDRON: &str =
    "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
/// A different model, to catch a path resolved against the wrong folder.
const WEDGE: &str = "v 0 0 0\nv 2 0 0\nv 0 0 1\nv 0 3 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// A model whose path is not UTF-8 (`--obj $'m\xff.obj'`, or a scene file in such a folder)
/// is refused before the render, naming it; it used to panic after the whole render, writing
/// no image.
#[cfg(unix)]
#[test]
fn a_model_path_that_is_not_utf8_is_refused_before_the_render() {
    use std::os::unix::ffi::OsStrExt as _;
    let dir = tempfile::tempdir().unwrap();
    let name = std::ffi::OsStr::from_bytes(b"m\xff.obj");
    std::fs::write(dir.path().join(name), TETRAHEDRON).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--out", "x.png", "--obj"])
        .arg(name)
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_one_line_error(
        &out,
        &["invalid model path 'm\u{fffd}.obj'", "is not UTF-8 text"],
    );
    assert!(!dir.path().join("x.png").exists());
    // A scene file in a folder whose name is not UTF-8, naming a model beside it.
    let folder = dir.path().join(std::ffi::OsStr::from_bytes(b"scenes-\xfe"));
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(folder.join("m.obj"), TETRAHEDRON).unwrap();
    let mut spec = raylab_core::shapes::scene::SceneChoice::Bunny.spec();
    spec.models[0].file = folder.join("m.obj");
    let settings = raylab_core::RenderSettings {
        scene: raylab_core::shapes::scene::SceneChoice::Custom(Box::new(spec)),
        ..common::settings(raylab_core::Stage::Lab, 8)
    };
    // The file names the model beside it, `m.obj`, which is UTF-8; the folder is not.
    let text = raylab_core::files::scene_file::to_text(&settings, &folder).unwrap();
    assert!(text.contains("file = \"m.obj\""), "{text}");
    std::fs::write(folder.join("s.toml"), text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--out", "y.png", "--scene-file"])
        .arg(folder.join("s.toml"))
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_one_line_error(&out, &["scene.models[0].file", "is not UTF-8 text"]);
    assert!(!dir.path().join("y.png").exists());
}

/// A FIFO given as the model, the scene file, the settings file or a material library is
/// refused at once (it kept raylab waiting for ever), and /dev/zero (read until memory ran
/// out) likewise, each saying what it is.
#[cfg(unix)]
#[test]
fn fifos_and_devices_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    raylab_core::base::inputs::make_fifo(&fifo);
    let fifo = fifo.to_str().unwrap();
    for (flag, input) in [
        ("--obj", fifo),
        ("--scene-file", fifo),
        ("--settings", fifo),
        ("--obj", "/dev/zero"),
        ("--settings", "/dev/zero"),
    ] {
        let out = raylab_in(dir.path(), &["render", "--out", "x.png", flag, input]);
        let what = if input == fifo {
            "not a regular file (a FIFO)"
        } else {
            "not a regular file (a character device)"
        };
        assert_one_line_error(&out, &[what]);
        assert!(!dir.path().join("x.png").exists());
    }
    // A material library that is a FIFO: a warning, and the model renders.
    raylab_core::base::inputs::make_fifo(&dir.path().join("lib.mtl"));
    std::fs::write(
        dir.path().join("m.obj"),
        format!("mtllib lib.mtl\n{TETRAHEDRON}"),
    )
    .unwrap();
    let out = raylab_in(
        dir.path(),
        &[
            "render", "--out", "m.png", "--obj", "m.obj", "--width", "16", "--height", "16",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("'lib.mtl': it is not a regular file (a FIFO)"),
        "{}",
        stderr(&out)
    );
}

/// A screenshot whose settings text is compressed and inflates far beyond any settings (8 MiB
/// of spaces in a few kilobytes; 3 MB can hold 3 GiB, enough to abort
/// `render --settings`) is refused at once, saying so.
#[test]
fn a_screenshot_whose_settings_inflate_without_end_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("bomb.png");
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, 2, 2);
        encoder.set_color(png::ColorType::Rgb);
        let mut writer = encoder.write_header().unwrap();
        let mut chunk = png::text_metadata::ITXtChunk::new(
            raylab_core::files::settings_file::PNG_KEYWORD,
            " ".repeat(8 << 20),
        );
        chunk.compressed = true;
        writer.write_text_chunk(&chunk).unwrap();
        writer.write_image_data(&[0; 12]).unwrap();
        writer.finish().unwrap();
    }
    assert!(bytes.len() < 64 << 10, "{}", bytes.len());
    std::fs::write(&shot, &bytes).unwrap();
    let out = raylab(&[
        "render",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
        "--settings",
        shot.to_str().unwrap(),
    ]);
    assert_one_line_error(
        &out,
        &[
            "bomb.png",
            "raylab-settings text (iTXt) inflates to more than the 1,048,576 bytes (1 MiB) settings may be",
        ],
    );
}

/// Text from files reaches the terminal escaped: a scene's name with an ANSI sequence in the
/// summary line, a material library's name in a warning. No escape byte is printed.
#[test]
fn control_characters_from_files_are_escaped_in_what_is_printed() {
    let dir = tempfile::tempdir().unwrap();
    let mut settings = common::settings(raylab_core::Stage::Lab, 8);
    let mut spec = raylab_core::shapes::scene::SceneChoice::Cornell.spec();
    spec.name = "\u{1b}[31mred\u{1b}[0m\ttab".into();
    spec.blocks = false;
    settings.scene = raylab_core::shapes::scene::SceneChoice::Custom(Box::new(spec));
    let text = raylab_core::files::scene_file::to_text(&settings, dir.path()).unwrap();
    std::fs::write(dir.path().join("s.toml"), text).unwrap();
    let out = raylab_in(
        dir.path(),
        &["render", "--out", "x.png", "--scene-file", "s.toml"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.starts_with("rendered \\u{1b}[31mred\\u{1b}[0m\\u{9}tab 8×8"),
        "{stdout}"
    );
    std::fs::write(
        dir.path().join("m.obj"),
        format!("mtllib \u{1b}]0;title\u{7}.mtl\n{TETRAHEDRON}"),
    )
    .unwrap();
    let out = raylab_in(
        dir.path(),
        &[
            "render", "--out", "m.png", "--obj", "m.obj", "--width", "8", "--height", "8",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("\\u{1b}]0;title\\u{7}.mtl"), "{err}");
    assert!(!out.stdout.contains(&0x1b) && !out.stderr.contains(&0x1b));
}

/// A texture whose header says 16384² (782 KB of PNG whose decoding takes about 5 GiB) is counted in
/// the memory estimate from its header: refused before the render under a 3 GB limit, rather
/// than aborting while it decodes.
#[test]
fn a_texture_too_large_for_the_memory_is_refused_before_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let mut header = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut header, 16384, 16384);
        encoder.set_color(png::ColorType::Rgb);
        let mut writer = encoder.write_header().unwrap();
        writer.write_chunk(png::chunk::IDAT, &[0; 8]).unwrap();
    }
    std::fs::write(dir.path().join("huge.png"), &header).unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl glaze\nmap_Kd huge.png\n").unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        format!("mtllib m.mtl\nusemtl glaze\n{TETRAHEDRON}"),
    )
    .unwrap();
    let obj = dir.path().join("m.obj");
    let out = raylab_limited(
        3_000_000,
        &[
            "render",
            "--obj",
            obj.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            dir.path().join("x.png").to_str().unwrap(),
        ],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("error: a 8×8 render needs about 5.1 GiB but only "),
        "{err}"
    );
    assert!(!dir.path().join("x.png").exists());
    // Inspecting a pixel loads the same scene: refused the same way.
    let out = raylab_limited(
        3_000_000,
        &["inspect", "--obj", obj.to_str().unwrap(), "--pixel", "4,4"],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("error: inspecting a pixel of m.obj needs about 5.1 GiB but only "),
        "{err}"
    );
}

/// An OBJ naming one library of 2,000 materials 8,000 times (read once a line, it would ask
/// for gigabytes) renders
/// under a 2 GB address-space limit: the library is read once.
#[test]
fn a_library_named_thousands_of_times_is_read_once() {
    let dir = tempfile::tempdir().unwrap();
    let mtl: String = (0..2000)
        .map(|i| format!("newmtl m{i}\nKd 1 1 1\n"))
        .collect();
    std::fs::write(dir.path().join("lib.mtl"), mtl).unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        format!("{}{TETRAHEDRON}", "mtllib lib.mtl\n".repeat(8000)),
    )
    .unwrap();
    let out = raylab_limited(
        2_000_000,
        &[
            "render",
            "--obj",
            dir.path().join("m.obj").to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
            "--out",
            dir.path().join("x.png").to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(stderr(&out), "");
}

/// 100,000 missing material libraries: three warnings name the first three, one counts the
/// rest (not a warning a library).
#[test]
fn many_missing_libraries_make_a_few_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let obj: String = (0..100_000)
        .map(|i| format!("mtllib gone-{i}.mtl\n"))
        .chain([TETRAHEDRON.to_owned()])
        .collect();
    std::fs::write(dir.path().join("m.obj"), obj).unwrap();
    let out = raylab_in(
        dir.path(),
        &[
            "render", "--out", "x.png", "--obj", "m.obj", "--width", "8", "--height", "8",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 4, "{err}");
    assert!(
        err.lines().last().unwrap().ends_with(
            "m.obj: 99997 more material libraries could not be read either; their materials \
             are not used"
        ),
        "{err}"
    );
}

/// `--save-scene sub/s.toml` of an `--obj m.obj` render names the model relative to the scene
/// file (`../m.obj`): read from another folder, the scene file renders the same model, not
/// `sub/m.obj` (a different model planted there). A screenshot made in folder A and rendered
/// again with `--settings ../A/shot.png` from folder B loads A's model, not B's.
#[test]
fn model_paths_are_relative_to_the_file_that_names_them() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    for sub in ["A", "B", "A/sub"] {
        std::fs::create_dir(root.join(sub)).unwrap();
    }
    std::fs::write(root.join("A/m.obj"), TETRAHEDRON).unwrap();
    std::fs::write(root.join("A/sub/m.obj"), WEDGE).unwrap();
    std::fs::write(root.join("B/m.obj"), WEDGE).unwrap();
    let size = ["--width", "48", "--height", "48"];
    let out = raylab_in(
        &root.join("A"),
        &[
            &["render", "--obj", "m.obj", "--out", "shot.png"][..],
            &["--save-scene", "sub/s.toml"],
            &size,
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = std::fs::read_to_string(root.join("A/sub/s.toml")).unwrap();
    assert!(scene.contains("file = \"../m.obj\""), "{scene}");
    let shot = image::open(root.join("A/shot.png")).unwrap().to_rgb8();
    // From B, both files: the same image as the shot (A's tetrahedron).
    for (flag, file) in [
        ("--scene-file", "../A/sub/s.toml"),
        ("--settings", "../A/shot.png"),
    ] {
        let out = raylab_in(
            &root.join("B"),
            &["render", flag, file, "--out", "again.png"],
        );
        assert!(out.status.success(), "{flag}: {}", stderr(&out));
        let again = image::open(root.join("B/again.png")).unwrap().to_rgb8();
        assert_eq!(again, shot, "{flag} {file} rendered another model");
    }
    // The wedge does look different: the comparison above can fail.
    let out = raylab_in(
        &root.join("B"),
        &[
            &["render", "--obj", "m.obj", "--out", "wedge.png"][..],
            &size,
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert_ne!(
        image::open(root.join("B/wedge.png")).unwrap().to_rgb8(),
        shot
    );
}

/// A PNG written with `--view normals` carries that view, and `render --settings` of it draws
/// the normals again, pixel for pixel (it drew the shaded image); `--view` still overrides.
#[test]
fn a_debug_views_screenshot_renders_that_view_again() {
    let dir = tempfile::tempdir().unwrap();
    let size = ["--width", "40", "--height", "30"];
    let run = |args: &[&str]| {
        let out = raylab_in(dir.path(), args);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        image::open(dir.path().join(args[2])).unwrap().to_rgb8()
    };
    let normals = run(&[
        &["render", "--out", "n.png", "--view", "normals"][..],
        &size,
    ]
    .concat());
    let shaded = run(&[&["render", "--out", "s.png"][..], &size].concat());
    assert_ne!(normals, shaded);
    assert_eq!(
        run(&["render", "--out", "again.png", "--settings", "n.png"]),
        normals
    );
    assert_eq!(
        run(&[
            "render",
            "--out",
            "over.png",
            "--settings",
            "n.png",
            "--view",
            "shaded"
        ]),
        shaded
    );
}

/// `--save-scene` is checked before the render: a folder that refuses new files and a seed a
/// scene file cannot hold (above 2⁶³ − 1) are refused first (the OBJ named alongside, which
/// would fail to load, is never reached). Onto an existing file — the scene file being read,
/// or any other — it writes the first free name, `-1`, `-2`, …, and says so: nothing is
/// replaced.
#[test]
fn save_scene_never_replaces_a_file_and_is_checked_first() {
    let dir = tempfile::tempdir().unwrap();
    let missing = ["--obj", "missing.obj"];
    if std::path::Path::new("/sys").is_dir() {
        let out = raylab_in(
            dir.path(),
            &[
                &["render", "--out", "x.png", "--save-scene", "/sys/s.toml"][..],
                &missing,
            ]
            .concat(),
        );
        assert_one_line_error(&out, &["could not write scene file '/sys/s.toml'"]);
    }
    let out = raylab_in(
        dir.path(),
        &[
            &["render", "--out", "x.png", "--save-scene", "s.toml"][..],
            &["--seed", "9223372036854775808"],
            &missing,
        ]
        .concat(),
    );
    assert_one_line_error(&out, &["--save-scene 's.toml'", "seed 9223372036854775808"]);
    assert!(common::files_in(dir.path()).is_empty());

    // Onto the scene file it reads: a hand-written file, comments and all, stays.
    let settings = common::settings(raylab_core::Stage::Lab, 8);
    let hand = format!(
        "# my notes\n{}",
        raylab_core::files::scene_file::to_text(&settings, dir.path()).unwrap()
    );
    std::fs::write(dir.path().join("s.toml"), &hand).unwrap();
    let args = [
        "render",
        "--out",
        "x.png",
        "--scene-file",
        "s.toml",
        "--save-scene",
        "s.toml",
    ];
    for n in 1..=2 {
        let out = raylab_in(dir.path(), &args);
        assert!(out.status.success(), "{}", stderr(&out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains(&format!(
                "scene file → s-{n}.toml ('s.toml' exists, and is left as it is)"
            )),
            "{stdout}"
        );
        let saved = dir.path().join(format!("s-{n}.toml"));
        let again = raylab_core::files::scene_file::load(&saved).unwrap();
        assert_eq!(
            again,
            raylab_core::files::scene_file::load(&dir.path().join("s.toml")).unwrap()
        );
    }
    assert_eq!(
        std::fs::read_to_string(dir.path().join("s.toml")).unwrap(),
        hand
    );
}

// ---------------------------------------------------------------------------------------------
// Outputs that are inputs, and outputs with long names.

/// A 32² lab-stage render written to `name` in `dir` (a student's render to check).
fn render_into(dir: &std::path::Path, name: &str) {
    let out = raylab_in(
        dir,
        &["render", "--width", "32", "--height", "32", "--out", name],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

/// The refusal of an output that is one of the inputs: a one-line error naming both, and the
/// input left as it was.
fn assert_input_kept(
    out: &std::process::Output,
    says: &[&str],
    input: &std::path::Path,
    was: &[u8],
) {
    assert_one_line_error(out, says);
    assert_eq!(
        std::fs::read(input).unwrap(),
        was,
        "{} was replaced",
        input.display()
    );
}

/// `check mine.png --diff-out mine.png` replaced the student's render with the difference
/// picture (exit 0), and `--settings shot.png --diff-out shot.png` the screenshot. An output
/// that is one of the inputs — the same name, another spelling of it, a hard or symbolic link
/// to it — is refused before any work, and the input is kept.
#[test]
fn check_never_writes_its_difference_picture_over_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    render_into(d, "mine.png");
    let mine = std::fs::read(d.join("mine.png")).unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    std::fs::hard_link(d.join("mine.png"), d.join("hard.png")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("mine.png", d.join("soft.png")).unwrap();
    let mut names = vec!["mine.png", "./sub/../mine.png", "hard.png"];
    if cfg!(unix) {
        names.push("soft.png");
    }
    for name in names {
        let out = raylab_in(d, &["check", "mine.png", "--diff-out", name]);
        assert_input_kept(
            &out,
            &[&format!("--diff-out '{name}'"), "'mine.png'"],
            &d.join("mine.png"),
            &mine,
        );
    }
    // The image checked through a link, the picture onto its target.
    #[cfg(unix)]
    {
        let out = raylab_in(d, &["check", "soft.png", "--diff-out", "mine.png"]);
        assert_input_kept(&out, &["--diff-out 'mine.png'"], &d.join("mine.png"), &mine);
    }
    // The screenshot whose settings are checked against.
    std::fs::copy(d.join("mine.png"), d.join("shot.png")).unwrap();
    let out = raylab_in(
        d,
        &[
            "check",
            "mine.png",
            "--settings",
            "shot.png",
            "--diff-out",
            "shot.png",
        ],
    );
    assert_input_kept(
        &out,
        &["--diff-out 'shot.png'", "'shot.png'"],
        &d.join("shot.png"),
        &mine,
    );
    // Another name is written.
    let out = raylab_in(d, &["check", "mine.png", "--diff-out", "diff.png"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(d.join("diff.png").is_file());
    assert_eq!(std::fs::read(d.join("mine.png")).unwrap(), mine);
}

/// `render --scene-file s.toml --out nm.png` replaced the normal map the scene reads. No file a
/// render reads is its output: a scene file's maps, a model's material library and the
/// textures it names, the screenshot given to --settings.
#[test]
fn render_never_writes_over_a_file_its_scene_reads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A normal map tilting the back wall, as a PNG.
    let map = {
        let image = image::RgbImage::from_pixel(4, 4, image::Rgb([192, 128, 255]));
        let mut bytes = std::io::Cursor::new(Vec::new());
        image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
        bytes.into_inner()
    };
    std::fs::write(d.join("nm.png"), &map).unwrap();
    let mut spec = raylab_core::shapes::scene::SceneSpec::cornell("tilted wall");
    spec.surfaces
        .push(raylab_core::shapes::scene::spec::PartRelief {
            part: raylab_core::shapes::scene::spec::BoxPart::BackWall,
            relief: raylab_core::shapes::scene::spec::ReliefSpec {
                normal_map: Some(d.join("nm.png")),
                ..Default::default()
            },
        });
    let mut settings = common::settings(raylab_core::Stage::Lab, 16);
    settings.scene = raylab_core::shapes::scene::SceneChoice::Custom(Box::new(spec));
    raylab_core::files::scene_file::save(&settings, &d.join("s.toml")).unwrap();
    for out_name in ["nm.png", "./nm.png"] {
        let out = raylab_in(d, &["render", "--scene-file", "s.toml", "--out", out_name]);
        assert_input_kept(
            &out,
            &[&format!("--out '{out_name}'"), "normal map", "nm.png"],
            &d.join("nm.png"),
            &map,
        );
    }
    // A model's material library names its texture: --out onto the texture.
    std::fs::write(d.join("tex.png"), &map).unwrap();
    std::fs::write(d.join("m.mtl"), "newmtl glaze\nmap_Kd tex.png\n").unwrap();
    std::fs::write(
        d.join("m.obj"),
        format!("mtllib m.mtl\nusemtl glaze\n{TETRAHEDRON}"),
    )
    .unwrap();
    let out = raylab_in(
        d,
        &[
            "render", "--obj", "m.obj", "--width", "16", "--height", "16", "--out", "tex.png",
        ],
    );
    assert_input_kept(
        &out,
        &["--out 'tex.png'", "texture"],
        &d.join("tex.png"),
        &map,
    );
    // The screenshot whose settings are rendered again.
    render_into(d, "shot.png");
    let shot = std::fs::read(d.join("shot.png")).unwrap();
    let out = raylab_in(
        d,
        &["render", "--settings", "shot.png", "--out", "shot.png"],
    );
    assert_input_kept(
        &out,
        &["--out 'shot.png'", "--settings"],
        &d.join("shot.png"),
        &shot,
    );
    // Another name is written, and the scene's files are kept.
    let out = raylab_in(d, &["render", "--scene-file", "s.toml", "--out", "x.png"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(d.join("nm.png")).unwrap(), map);
}

/// The longest file names a folder takes (255 bytes) are written: the temporary file beside
/// them, `.NAME.XXXXXX.tmp`, made "File name too long" from a name of 250 bytes for --out and
/// 246 for --diff-out and --save-scene. Nothing temporary is left.
#[test]
fn outputs_with_the_longest_names_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    render_into(d, "mine.png");
    for length in [246, 250, 255] {
        let png = format!("{}.png", "p".repeat(length - 4));
        let toml = format!("{}.toml", "s".repeat(length - 5));
        let out = raylab_in(
            d,
            &[
                "render",
                "--width",
                "8",
                "--height",
                "8",
                "--out",
                &png,
                "--save-scene",
                &toml,
            ],
        );
        assert!(out.status.success(), "{length}: {}", stderr(&out));
        assert!(
            d.join(&png).is_file() && d.join(&toml).is_file(),
            "{length}"
        );
        let diff = format!("{}.png", "d".repeat(length - 4));
        let out = raylab_in(d, &["check", "mine.png", "--diff-out", &diff]);
        assert!(out.status.success(), "{length}: {}", stderr(&out));
        assert!(d.join(&diff).is_file(), "{length}");
        let hidden: Vec<_> = common::files_in(d)
            .into_iter()
            .filter(|n| n.to_string_lossy().starts_with('.'))
            .collect();
        assert!(hidden.is_empty(), "{length}: left {hidden:?}");
    }
}

/// A scene file 900 bytes over the 4 MiB cap is refused with the exact sizes, not as "4 MiB,
/// more than the 4 MiB a scene file may be".
#[test]
fn a_scene_file_over_its_cap_is_refused_with_the_exact_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let size = (4 << 20) + 900;
    std::fs::write(dir.path().join("big.toml"), vec![b'#'; size]).unwrap();
    let out = raylab_in(
        dir.path(),
        &["render", "--scene-file", "big.toml", "--out", "x.png"],
    );
    assert_one_line_error(
        &out,
        &[
            "big.toml",
            "4,195,204 bytes",
            "more than the 4,194,304 bytes (4 MiB) a scene file may be",
        ],
    );
}

/// Under `ulimit -s 64` (a 64 KiB stack for the main thread) every command overflowed its
/// stack (exit code 134), `--help` too. The work runs on threads whose stacks raylab sets:
/// the commands finish, and the window gets as far as looking for a display. The threads
/// rayon and std would size from `RUST_MIN_STACK` are given their size too.
#[cfg(unix)]
#[test]
fn a_small_stack_limit_is_no_overflow() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str], env: &[(&str, &str)]| {
        let mut command = std::process::Command::new("sh");
        command
            .arg("-c")
            .arg("ulimit -s 64; exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_raylab"))
            .args(args)
            .current_dir(dir.path())
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY");
        for (k, v) in env {
            command.env(k, v);
        }
        command.output().unwrap()
    };
    let side = ["--width", "16", "--height", "16"];
    for args in [
        &["--help"][..],
        &[&["render", "--out", "a.png"][..], &side].concat(),
        &[
            &[
                "render",
                "--stage",
                "path",
                "--samples",
                "2",
                "--out",
                "b.png",
            ][..],
            &side,
        ]
        .concat(),
        &[&["inspect", "--pixel", "3,4"][..], &side].concat(),
        &["check", "a.png"],
    ] {
        let out = run(args, &[]);
        assert!(
            out.status.success(),
            "{args:?}: {:?} {}",
            out.status,
            stderr(&out)
        );
        let out = run(args, &[("RUST_MIN_STACK", "16384")]);
        assert!(
            out.status.success(),
            "RUST_MIN_STACK {args:?}: {:?} {}",
            out.status,
            stderr(&out)
        );
    }
    // No display: the window's own error, not an overflow nor a panic.
    let out = run(&[], &[]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("could not open the workbench window"), "{err}");
}

/// Scene-file arrays take exactly their length on the command line too: a fourth number in the
/// camera's position is refused, naming the line.
#[test]
fn a_scene_file_array_of_four_numbers_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let settings = common::settings(raylab_core::Stage::Lab, 8);
    let text = raylab_core::files::scene_file::to_text(&settings, dir.path())
        .unwrap()
        .replace(
            "position = [0.0, 0.0, -3.001]",
            "position = [0.0, 0.0, -3.001, 99.0]",
        );
    std::fs::write(dir.path().join("s.toml"), text).unwrap();
    let out = raylab_in(
        dir.path(),
        &["render", "--out", "x.png", "--scene-file", "s.toml"],
    );
    assert_one_line_error(&out, &["s.toml", "line ", "more than 3 elements"]);
}

/// `--focal 1e-23` underflowed the centre ray's direction to (0, 0, 0), a black pixel
/// silently: refused, as a focal length above 1e7 is.
#[test]
fn a_focal_length_too_short_to_normalise_the_rays_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab_in(
        dir.path(),
        &[
            "render", "--out", "x.png", "--focal", "1e-23", "--width", "5",
        ],
    );
    assert_one_line_error(
        &out,
        &["invalid focal length 1e-23: must be at least 0.001 px"],
    );
}

/// A focus distance of 1e38 (or an aperture of 1e30) overflowed the lens rays: a black image,
/// silently. Refused before anything is rendered or written.
#[test]
fn a_lens_beyond_its_bounds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = raylab_in(
        dir.path(),
        &[
            "render",
            "--out",
            "x.png",
            "--focus-distance",
            "1e38",
            "--aperture",
            "0.1",
        ],
    );
    assert_one_line_error(
        &out,
        &["invalid focus distance 1e38: must be at most 1e6 (scene units)"],
    );
    assert!(!dir.path().join("x.png").exists());
}

// ---------------------------------------------------------------------------------------------
// The process: signals, full outputs, the environment.

/// Renders a 1200² EXR in `dir` and sends `signal` once the temporary file exists: the
/// program exits with 128 + the signal's number, saying so, and leaves no temporary file.
#[cfg(unix)]
fn stopped_by(signal: &str, number: i32) {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.exr");
    for _attempt in 0..5 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["render", "--width", "1200", "--height", "1200", "--out"])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        while !has_temporary_file(dir.path()) && child.try_wait().unwrap().is_none() {
            std::thread::sleep(std::time::Duration::from_micros(200));
        }
        let _ = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status();
        let output = child.wait_with_output().unwrap();
        assert!(
            !has_temporary_file(dir.path()),
            "SIG{signal}: {:?}",
            common::files_in(dir.path())
        );
        if output.status.code() == Some(0) {
            // The write finished before the signal came: try again.
            let _ = std::fs::remove_file(&out);
            continue;
        }
        let err = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(128 + number),
            "SIG{signal}: {err}"
        );
        assert!(
            err.contains(&format!(
                "stopped by SIG{signal}; its temporary files are removed"
            )),
            "{err}"
        );
        return;
    }
    panic!("SIG{signal} never arrived during a write in five tries");
}

#[cfg(unix)]
fn has_temporary_file(dir: &std::path::Path) -> bool {
    common::files_in(dir)
        .iter()
        .any(|n| n.to_string_lossy().ends_with(".tmp"))
}

#[cfg(unix)]
#[test]
fn sigquit_sigusr1_and_sigalrm_during_a_write_leave_no_temporary_file() {
    stopped_by("QUIT", 3);
    stopped_by("USR1", 10);
    stopped_by("ALRM", 14);
}

/// A write past `ulimit -f` (SIGXFSZ) fails with "File too large" and leaves neither the image
/// nor its temporary file: the signal is ignored, so the write's error is handled.
#[cfg(unix)]
#[test]
fn a_write_past_the_file_size_limit_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("big.exr");
    // 1,000 blocks of 512 bytes (sh) at most: far less than a 1200² EXR's 17 MB.
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -f 1000; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--width", "1200", "--height", "1200", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("File too large"), "{err}");
    assert!(
        common::files_in(dir.path()).is_empty(),
        "{:?}",
        common::files_in(dir.path())
    );
}

/// Errors and warnings written to a full stderr panicked (exit code 101): now the exit code
/// says what happened. `--help` into a full stdout fails instead of exiting 0.
#[cfg(unix)]
#[test]
fn a_full_stderr_or_stdout_is_no_panic() {
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let run = |args: &[&str], stdout: std::fs::File, stderr: std::fs::File| {
        std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(args)
            .stdout(stdout)
            .stderr(stderr)
            .status()
            .unwrap()
    };
    let null = || std::fs::File::create("/dev/null").unwrap();
    assert_eq!(
        run(&["render", "--width", "0"], null(), full()).code(),
        Some(2)
    );
    assert_eq!(
        run(&["render", "--out", "x.jpg"], null(), full()).code(),
        Some(1)
    );
    let dir = tempfile::tempdir().unwrap();
    // A render whose warning cannot be printed still writes its image.
    let obj = dir.path().join("m.obj");
    std::fs::write(&obj, format!("mtllib gone.mtl\n{TETRAHEDRON}")).unwrap();
    let png = dir.path().join("x.png");
    let status = run(
        &[
            "render",
            "--obj",
            obj.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            png.to_str().unwrap(),
        ],
        null(),
        full(),
    );
    assert_eq!(status.code(), Some(0));
    assert!(png.exists());
    assert_eq!(run(&["--help"], full(), null()).code(), Some(1));
    assert_eq!(run(&["--version"], full(), null()).code(), Some(1));
    assert_eq!(run(&["--help"], null(), null()).code(), Some(0));
}

/// `RAYON_NUM_THREADS` above four threads a core is capped, with a warning; a usable one is
/// taken as it is. `RAYLAB_ISA` naming no kernel set is warned of once, naming those accepted.
#[test]
fn thread_counts_and_kernel_names_from_the_environment() {
    let dir = tempfile::tempdir().unwrap();
    let run = |var: &str, value: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["render", "--out", "x.png", "--width", "8", "--height", "8"])
            .env(var, value)
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    // 2000 on a machine of a few cores would start far more threads than it has cores, each
    // a cost to the render: at most four a core.
    let cores = std::thread::available_parallelism().unwrap().get();
    let cap = raylab_core::transport::progressive::THREADS_PER_CORE * cores;
    let out = run("RAYON_NUM_THREADS", "2000");
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        format!(
            "warning: RAYON_NUM_THREADS=2000 is more than 4 threads a core: using {cap} ({cores} \
             core{})\n",
            if cores == 1 { "" } else { "s" }
        )
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!(" on {cap} threads ")));
    let out = run("RAYON_NUM_THREADS", "3");
    assert_eq!(stderr(&out), "");
    assert!(String::from_utf8_lossy(&out.stdout).contains(" on 3 threads "));
    let out = run("RAYLAB_ISA", "garbage");
    assert!(out.status.success(), "{}", stderr(&out));
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("warning: RAYLAB_ISA=\"garbage\" is not a kernel set")
            && err.contains("(accepted: best, ")
            && err.contains("scalar)"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// Light sizes, surfaces and keys that were taken without a word.

/// An area light too small for its radiance or sampling density to be an `f32` wrote NaN
/// pixels with exit 0 (a sphere of 1e−30: 1,713 of 1,728 values); it is refused in one line
/// naming the bound, from the command line, a settings JSON and a scene file; the smallest
/// allowed size writes finite values, denoised too.
#[test]
fn a_tiny_area_light_is_refused_and_the_smallest_allowed_is_finite() {
    let bound = "must be 0 (the point light) or between 0.001 and 1e6";
    for shape in ["sphere", "quad"] {
        for size in ["1e-30", "1e-19", "5e-20", "1e-9"] {
            assert_render_refused(
                &[
                    "--width",
                    "24",
                    "--height",
                    "24",
                    "--stage",
                    "path",
                    "--light-shape",
                    shape,
                    "--light-size",
                    size,
                ],
                &[&format!("invalid light size {size}"), bound],
            );
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("tiny.json");
    std::fs::write(
        &json,
        r#"{"light": {"radius": 1e-30, "shape": "quad"}, "camera": {"width": 8, "height": 8}}"#,
    )
    .unwrap();
    assert_render_refused(
        &["--settings", json.to_str().unwrap()],
        &["invalid light size 1e-30", bound],
    );
    let scene = dir.path().join("tiny.toml");
    let saved = raylab(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--light-shape",
        "sphere",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
        "--save-scene",
        scene.to_str().unwrap(),
    ]);
    assert!(saved.status.success(), "{}", stderr(&saved));
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("radius = 0.1", "radius = 1e-30")).unwrap();
    assert_render_refused(
        &["--scene-file", scene.to_str().unwrap()],
        &["radius = 1e-30", "invalid light size 1e-30", bound],
    );

    for shape in ["sphere", "quad"] {
        let exr = dir.path().join(format!("{shape}.exr"));
        let out = raylab(&[
            "render",
            "--width",
            "16",
            "--height",
            "16",
            "--stage",
            "path",
            "--samples",
            "4",
            "--light-shape",
            shape,
            "--light-size",
            "0.001",
            "--light-power",
            "1e6",
            "--light-colour",
            "1000,1000,1000",
            "--denoise",
            "on",
            "--out",
            exr.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let pixels = image::open(&exr).unwrap().to_rgb32f().into_raw();
        assert!(pixels.iter().all(|v| v.is_finite()), "{shape}: {pixels:?}");
    }
}

/// `--light-shape point` with a size rendered a sphere without a word, and `--save-scene`
/// wrote `shape = "point"` with the radius: refused in one line that says what to use
/// instead, with no image and no scene file written.
#[test]
fn a_point_light_with_a_size_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    let exr = dir.path().join("x.exr");
    let out = raylab(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--light-shape",
        "point",
        "--light-size",
        "0.3",
        "--out",
        exr.to_str().unwrap(),
        "--save-scene",
        scene.to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(
            "--light-size 0.3: a point light has no size (--light-shape sphere or quad have one)"
        ),
        "{err}"
    );
    assert!(
        common::files_in(dir.path()).is_empty(),
        "a file was written"
    );
    // `--light-size` alone is a sphere, as it always was.
    let out = raylab(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--light-size",
        "0.3",
        "--out",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// A key given twice in a settings JSON (or a screenshot's) was taken as its last value
/// without a word, where a scene file refuses it: refused in one line naming the key.
#[test]
fn a_key_given_twice_in_settings_json_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("twice.json");
    std::fs::write(
        &json,
        r#"{"camera": {"width": 8, "height": 8}, "seed": 1, "light": {"power": 14, "power": 1e6}}"#,
    )
    .unwrap();
    assert_render_refused(
        &["--settings", json.to_str().unwrap()],
        &["duplicate key `light.power`", "line 1 column"],
    );
}

/// Scene-file surfaces that were dropped without a word: a second entry for one part, and an
/// entry for a block the scene leaves out. Each is refused naming its line.
#[test]
fn surfaces_twice_or_for_an_absent_block_are_refused_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    let saved = raylab(&[
        "render",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
        "--save-scene",
        scene.to_str().unwrap(),
    ]);
    assert!(saved.status.success(), "{}", stderr(&saved));
    // A real map, so that only the surfaces themselves can be what is refused.
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 200, 200]))
        .save(dir.path().join("h.png"))
        .unwrap();
    let text = std::fs::read_to_string(&scene).unwrap();
    let surface =
        |part: &str| format!("\n[[scene.surfaces]]\npart = \"{part}\"\nheight_map = \"h.png\"\n");
    for (edited, part, says) in [
        (
            format!("{text}{}{}", surface("back-wall"), surface("back-wall")),
            "back-wall",
            "has maps from an earlier [[scene.surfaces]] already",
        ),
        (
            format!(
                "{}{}",
                text.replace("blocks = true", "blocks = false"),
                surface("short-block")
            ),
            "short-block",
            "is not in the scene: `blocks = false` leaves the blocks out",
        ),
    ] {
        std::fs::write(&scene, &edited).unwrap();
        let want = format!("part = \"{part}\"");
        let line = edited
            .lines()
            .enumerate()
            .filter(|(_, l)| *l == want)
            .last()
            .unwrap()
            .0
            + 1;
        assert_render_refused(
            &["--scene-file", scene.to_str().unwrap()],
            &[&format!("line {line} (part = \"{part}\")"), says],
        );
    }
}
