//! The acceleration structures against the brute-force oracle: every kind and both kernel sets
//! must return exactly what `closest_intersection_brute_force` and `occluded_brute_force` return
//! (same triangle, same t, same u and v — the kernels are bit-identical to the scalar test, and
//! ties go to the lowest index in both), including on degenerate input.

mod common;

use common::rays::{random_dir, rays};
use glam::Vec3;
use raylab_core::base::geometry::{Ray, Triangle};
use raylab_core::base::sampling::Rng;
use raylab_core::shapes::accel::{Accel, AccelKind, Isa};
use raylab_core::shapes::intersect::{closest_intersection_brute_force, occluded_brute_force};
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box, terrain};

/// Every structure that is not the brute-force loop, with every kernel set this CPU runs.
fn configurations() -> Vec<(AccelKind, Isa)> {
    let mut out = vec![(AccelKind::Bvh2, Isa::Scalar)];
    for isa in Isa::available_for_tests("bvh configurations") {
        out.push((AccelKind::Flat, isa));
        out.push((AccelKind::Bvh8, isa));
    }
    out
}

/// Checks every configuration against the oracle on `count` rays; returns the number of hits.
fn check_against_brute_force(triangles: &[Triangle], count: usize, seed: u64) -> usize {
    let rays = rays(triangles, count, seed);
    let expected: Vec<_> = rays
        .iter()
        .map(|(r, t)| {
            (
                closest_intersection_brute_force(r, triangles, *t),
                occluded_brute_force(r, triangles, *t),
            )
        })
        .collect();
    let materials = vec![raylab_core::shapes::scene::Material::diffuse(
        "m",
        Vec3::ONE,
    )];
    let tris: Vec<Triangle> = triangles
        .iter()
        .map(|t| Triangle { material: 0, ..*t })
        .collect();
    for (kind, isa) in configurations() {
        let scene = Scene::with_accel(tris.clone(), materials.clone(), kind, isa);
        assert_eq!(scene.accel().kind(), kind);
        for ((ray, t_max), (closest, occluded)) in rays.iter().zip(&expected) {
            let got = scene.closest_intersection(ray, *t_max);
            // Bit for bit: same triangle, t, u, v and position.
            assert_eq!(
                got,
                *closest,
                "{kind} {}: closest hit of {ray:?} (t_max {t_max})",
                isa.name()
            );
            assert_eq!(
                scene.occluded(ray, *t_max),
                *occluded,
                "{kind} {}: occlusion of {ray:?} (t_max {t_max})",
                isa.name()
            );
        }
    }
    expected.iter().filter(|e| e.0.is_some()).count()
}

#[test]
fn cornell_box_equals_brute_force_on_100k_rays() {
    let hits = check_against_brute_force(&cornell_box().triangles, 100_000, 1);
    assert!(hits > 50_000, "{hits}");
}

#[test]
fn bunny_equals_brute_force_on_100k_rays() {
    let scene = SceneChoice::Bunny.load().unwrap();
    let hits = check_against_brute_force(&scene.triangles, 100_000, 2);
    assert!(hits > 50_000, "{hits}");
}

#[test]
fn teapot_equals_brute_force_on_100k_rays() {
    let scene = SceneChoice::Teapot.load().unwrap();
    let hits = check_against_brute_force(&scene.triangles, 100_000, 3);
    assert!(hits > 50_000, "{hits}");
}

#[test]
fn small_terrain_equals_brute_force() {
    // The same generator as the full terrain, ~20,000 triangles.
    let scene = raylab_core::shapes::scene::spec::terrain_scene(&terrain::TerrainSpec {
        grid: 100,
        ..terrain::TerrainSpec::default()
    });
    assert!(scene.triangles.len() > 20_000);
    let hits = check_against_brute_force(&scene.triangles, 20_000, 4);
    assert!(hits > 10_000, "{hits}");
}

#[test]
fn full_terrain_bvh_equals_brute_force_on_a_few_rays() {
    let scene = SceneChoice::Terrain.load().unwrap();
    assert!(scene.triangles.len() > 900_000);
    assert_eq!(scene.accel().kind(), AccelKind::Bvh8);
    for (ray, t_max) in rays(&scene.triangles, 200, 5) {
        let want = closest_intersection_brute_force(&ray, &scene.triangles, t_max);
        assert_eq!(scene.closest_intersection(&ray, t_max), want, "{ray:?}");
        let want = occluded_brute_force(&ray, &scene.triangles, t_max);
        assert_eq!(scene.occluded(&ray, t_max), want, "{ray:?}");
    }
}

fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
    Triangle::new(Vec3::from(a), Vec3::from(b), Vec3::from(c), 0)
}

#[test]
fn empty_scene_builds_and_misses() {
    for (kind, isa) in configurations() {
        let accel = Accel::build(&[], kind, isa);
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(accel.closest(&[], &r, f32::INFINITY), None);
        assert!(!accel.occluded(&[], &r, f32::INFINITY));
    }
}

#[test]
fn one_triangle() {
    let t = [tri([-1.0, -1.0, 2.0], [1.0, -1.0, 2.0], [0.0, 1.0, 2.0])];
    let hits = check_against_brute_force(&t, 5_000, 6);
    assert!(hits > 100, "{hits}");
}

#[test]
fn identical_triangles_give_the_lowest_index() {
    let t = tri([-1.0, -1.0, 2.0], [1.0, -1.0, 2.0], [0.0, 1.0, 2.0]);
    let tris = vec![t; 100];
    check_against_brute_force(&tris, 5_000, 7);
    for (kind, isa) in configurations() {
        let accel = Accel::build(&tris, kind, isa);
        let hit = accel.closest(&tris, &Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY);
        assert_eq!(hit.map(|h| (h.index, h.t)), Some((0, 2.0)), "{kind}");
    }
}

#[test]
fn zero_area_and_non_finite_triangles() {
    let mut tris = vec![
        tri([0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]),
        tri([0.5, 0.5, 1.0], [0.5, 0.5, 1.0], [0.5, 0.5, 1.0]),
        tri([f32::NAN, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]),
        tri([f32::INFINITY, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]),
    ];
    let mut rng = Rng::new(8);
    for _ in 0..300 {
        let c = Vec3::new(
            rng.uniform(-2.0, 2.0),
            rng.uniform(-2.0, 2.0),
            rng.uniform(-2.0, 2.0),
        );
        tris.push(Triangle::new(
            c,
            c + 0.3 * random_dir(&mut rng),
            c + 0.3 * random_dir(&mut rng),
            0,
        ));
        // A sliver and a point next to it.
        tris.push(Triangle::new(c, c + Vec3::X * 0.1, c + Vec3::X * 0.2, 0));
        tris.push(Triangle::new(c, c, c, 0));
    }
    check_against_brute_force(&tris, 20_000, 9);
}

#[test]
fn huge_coordinates() {
    for scale in [1e4f32, 1e8, 1e12] {
        let tris: Vec<Triangle> = cornell_box()
            .triangles
            .iter()
            .map(|t| Triangle::new(t.v0 * scale, t.v1 * scale, t.v2 * scale, 0))
            .collect();
        let hits = check_against_brute_force(&tris, 5_000, 10);
        assert!(hits > 1_000, "{scale}: {hits}");
    }
}

#[test]
fn wide_tree_over_many_small_triangles_is_shallow_and_fits_the_inline_stack() {
    let scene = raylab_core::shapes::scene::spec::terrain_scene(&terrain::TerrainSpec {
        grid: 100,
        ..terrain::TerrainSpec::default()
    });
    let bvh = raylab_core::shapes::accel::bvh::Bvh::build(&scene.triangles);
    assert!(bvh.depth() < 40, "{}", bvh.depth());
    let wide = raylab_core::shapes::accel::wide::Bvh8::from_binary(&bvh, &scene.triangles);
    assert!(wide.max_stack <= 64, "{}", wide.max_stack);
    // Every triangle is in exactly one packet.
    let mut seen = vec![0u8; scene.triangles.len()];
    for p in &wide.packets {
        for &i in p.index.iter().filter(|&&i| i != u32::MAX) {
            seen[i as usize] += 1;
        }
    }
    assert!(seen.iter().all(|&s| s == 1));
}

/// The trees are the same whatever the number of threads builds them: the build splits its
/// work between threads near the root and the collapse makes packets in parallel, but what is
/// built depends on the triangles alone (so images do not depend on the thread count either).
/// 80,000 triangles: the root and its children are split on several threads.
#[test]
fn trees_are_the_same_on_any_number_of_threads() {
    use raylab_core::shapes::accel::bvh::Bvh;
    use raylab_core::shapes::accel::wide::Bvh8Big;
    let scene = raylab_core::shapes::scene::spec::terrain_scene(&terrain::TerrainSpec {
        grid: 200,
        ..terrain::TerrainSpec::default()
    });
    let on = |threads: usize| {
        common::on_threads(threads, || {
            (
                Bvh::build(&scene.triangles),
                Bvh8Big::build(&scene.triangles),
            )
        })
    };
    let (bvh, wide) = on(1);
    assert!(
        wide.tree.packets.len() > 10_000,
        "{}",
        wide.tree.packets.len()
    );
    for threads in [2, 3] {
        let (b, w) = on(threads);
        assert!(
            b.nodes == bvh.nodes && b.indices == bvh.indices,
            "{threads} threads"
        );
        assert!(
            w.tree.nodes == wide.tree.nodes
                && w.tree.packets == wide.tree.packets
                && (w.tree.root, w.tree.max_stack) == (wide.tree.root, wide.tree.max_stack)
                && w.big.packets == wide.big.packets,
            "{threads} threads"
        );
    }
}
