//! Coherent rays traced together (ray packets: 16 rays with AVX-512, 8 with AVX2) against the
//! brute-force oracle: every camera ray of the default view and every shadow ray the lab stage
//! casts from their hits (at 256², 512² for the Cornell box), through the batched queries the integrators use, for every structure
//! and kernel set this CPU runs. The answers must be exactly the brute-force loop's (same
//! triangle, `t`, `u`, `v`); and a lab image is the same bit for bit whichever kernels made it.

mod common;

use common::assert_same_image;
use raylab_core::base::geometry::Ray;
use raylab_core::shapes::accel::{AccelKind, Isa};
use raylab_core::shapes::intersect::{closest_intersection_brute_force, occluded_brute_force};
use raylab_core::shapes::scene::{Scene, SceneChoice, terrain};
use raylab_core::test_support::{lab_settings, primary_rays, shadow_rays};
use raylab_core::transport::render::render_pass;
use rayon::prelude::*;

/// [`check_view`] on the default view at `size`², which looks into the closed box.
fn check_every_configuration(scene: &Scene, size: u32) {
    let settings = lab_settings(size, size);
    let (primary, shadow, want_hits, want_blocked) = check_view(scene, &settings);
    // The view looks into the closed box: every camera ray hits, most hits see the light.
    assert!(want_hits.iter().all(Option::is_some));
    assert!(shadow.len() > primary.len() / 2, "{}", shadow.len());
    assert!(want_blocked.iter().any(|&b| b) && !want_blocked.iter().all(|&b| b));
}

type View = (
    Vec<Ray>,
    Vec<(Ray, f32)>,
    Vec<Option<raylab_core::shapes::intersect::Intersection>>,
    Vec<bool>,
);

/// The batched queries of `scene` on the camera rays of `settings` and the shadow rays the lab
/// stage casts from their hits, for every structure and kernel set, against the brute-force
/// loop; returns the rays and the oracle's answers.
fn check_view(scene: &Scene, settings: &raylab_core::RenderSettings) -> View {
    let primary = primary_rays(&settings.camera);
    let shadow = shadow_rays(scene, &settings.light, &primary);
    let want_hits: Vec<_> = primary
        .par_iter()
        .map(|ray| closest_intersection_brute_force(ray, &scene.triangles, f32::INFINITY))
        .collect();
    let want_blocked: Vec<bool> = shadow
        .par_iter()
        .map(|(ray, t_max)| occluded_brute_force(ray, &scene.triangles, *t_max))
        .collect();
    for isa in Isa::available_for_tests("packets: check_view") {
        for kind in [AccelKind::Bvh8, AccelKind::Flat] {
            if kind == AccelKind::Flat && scene.triangles.len() > 5_000 {
                continue; // the flat loop is for tiny scenes
            }
            let scene = scene.clone().rebuilt(kind, isa);
            let name = format!("{kind} {}", isa.name());
            let mut got = vec![None; primary.len()];
            // 64 at a time, as the integrators ask (the batch splits them into packets).
            for (rays, out) in primary.chunks(64).zip(got.chunks_mut(64)) {
                scene.closest_intersections(rays, f32::INFINITY, out);
            }
            for ((ray, got), want) in primary.iter().zip(&got).zip(&want_hits) {
                assert_eq!(got, want, "{name}: camera ray {ray:?}");
            }
            let mut blocked = vec![false; shadow.len()];
            for (rays, out) in shadow.chunks(64).zip(blocked.chunks_mut(64)) {
                scene.occluded_many(rays, out);
            }
            for (((ray, t_max), got), want) in shadow.iter().zip(&blocked).zip(&want_blocked) {
                assert_eq!(got, want, "{name}: shadow ray {ray:?} (t_max {t_max})");
            }
        }
    }
    (primary, shadow, want_hits, want_blocked)
}

#[test]
fn cornell_views_from_every_side_equal_brute_force() {
    // The flat list culls per batch (`accel::cull`): cameras looking along every axis, from
    // inside the box and from outside it, and lights in its corners, so the cones open along
    // each axis both ways and the shadow rays fan out every way.
    use glam::Vec3;
    use std::f32::consts::FRAC_PI_2;
    let scene = SceneChoice::Cornell.load().unwrap();
    let views = [
        (
            Vec3::new(0.0, 0.0, -3.001),
            0.0,
            0.0,
            Vec3::new(0.0, -0.5, -0.7),
        ),
        (
            Vec3::new(0.2, 0.1, 0.0),
            FRAC_PI_2,
            0.0,
            Vec3::new(0.9, -0.9, 0.9),
        ),
        (
            Vec3::new(-0.3, 0.0, 0.2),
            -FRAC_PI_2,
            0.3,
            Vec3::new(-0.9, 0.9, -0.9),
        ),
        (
            Vec3::new(0.0, 0.5, 0.0),
            0.4,
            FRAC_PI_2 * 0.9,
            Vec3::new(0.5, -0.99, 0.5),
        ),
        (
            Vec3::new(0.1, -0.2, 0.5),
            3.0,
            -FRAC_PI_2 * 0.9,
            Vec3::new(0.0, 0.99, 0.0),
        ),
        (
            Vec3::new(0.0, 0.0, 3.0),
            3.1,
            0.05,
            Vec3::new(0.3, 0.0, 0.0),
        ),
    ];
    for (position, yaw, pitch, light) in views {
        let mut settings = lab_settings(96, 96);
        settings.camera.position = position;
        settings.camera.yaw = yaw;
        settings.camera.pitch = pitch;
        settings.light.position = light;
        let (_, shadow, hits, _) = check_view(&scene, &settings);
        assert!(hits.iter().any(Option::is_some) && !shadow.is_empty());
    }
}

#[test]
fn bunny_default_view_equals_brute_force() {
    check_every_configuration(&SceneChoice::Bunny.load().unwrap(), 256);
}

#[test]
fn teapot_default_view_equals_brute_force() {
    check_every_configuration(&SceneChoice::Teapot.load().unwrap(), 256);
}

#[test]
fn cornell_default_view_equals_brute_force() {
    check_every_configuration(&SceneChoice::Cornell.load().unwrap(), 512);
}

#[test]
fn small_terrain_default_view_equals_brute_force() {
    // The full terrain's generator at 20,000 triangles (the brute-force loop over a million
    // triangles for every pixel would take hours).
    let scene = raylab_core::shapes::scene::spec::terrain_scene(&terrain::TerrainSpec {
        grid: 100,
        ..terrain::TerrainSpec::default()
    });
    check_every_configuration(&scene, 128);
}

#[test]
fn packets_of_every_size_and_mixed_directions_equal_single_rays() {
    // Batches of 1 to 64 rays, coherent or not: the same answer as each ray alone (packets
    // in the bunny's tree; the Cornell box's flat list culled per batch).
    for choice in [SceneChoice::Bunny, SceneChoice::Cornell] {
        batches_equal_single_rays(&choice.load().unwrap());
    }
}

fn batches_equal_single_rays(scene: &Scene) {
    let settings = lab_settings(64, 64);
    let primary = primary_rays(&settings.camera);
    let mut rng = raylab_core::base::sampling::Rng::new(7);
    for len in 1..=64 {
        let start = (rng.next_u32() as usize) % (primary.len() - len);
        let mut rays: Vec<Ray> = primary[start..start + len].to_vec();
        if len % 3 == 0 {
            // One ray turned around: the batch is no longer coherent.
            let r = rays[len / 2];
            rays[len / 2] = Ray::new(r.origin, -r.direction);
        }
        let mut got = vec![None; len];
        scene.closest_intersections(&rays, f32::INFINITY, &mut got);
        for (ray, got) in rays.iter().zip(&got) {
            assert_eq!(
                *got,
                scene.closest_intersection(ray, f32::INFINITY),
                "{len}"
            );
        }
        let t_max: Vec<(Ray, f32)> = rays.iter().map(|r| (*r, 2.0)).collect();
        let mut blocked = vec![false; len];
        scene.occluded_many(&t_max, &mut blocked);
        for ((ray, t), got) in t_max.iter().zip(&blocked) {
            assert_eq!(*got, scene.occluded(ray, *t), "{len}");
        }
    }
}

#[test]
fn the_lab_image_is_the_same_whatever_the_kernels() {
    // AVX-512 and AVX2 trace packets (16 and 8 rays), scalar ray by ray: the same image, bit
    // for bit. In the Cornell box AVX-512 and AVX2 also cull per batch (`accel::cull`) and
    // shade sixteen hits at a time, and the scalar set does neither; jittered samples too.
    for (choice, sample) in [
        (SceneChoice::Bunny, 0),
        (SceneChoice::Cornell, 0),
        (SceneChoice::Cornell, 3),
    ] {
        same_image_whatever_the_kernels(&choice.load().unwrap(), sample);
    }
}

fn same_image_whatever_the_kernels(scene: &Scene, sample: u32) {
    let settings = lab_settings(128, 128);
    let images: Vec<_> = Isa::available_for_tests("packets: same_image_whatever_the_kernels")
        .into_iter()
        .map(|isa| {
            let scene = scene.clone().rebuilt(AccelKind::Auto, isa);
            (
                isa.name(),
                render_pass(&scene, &settings, sample, &|| false).unwrap(),
            )
        })
        .collect();
    let (first_name, first) = &images[0];
    for (name, image) in &images[1..] {
        assert_same_image(image, first, format!("{name} against {first_name}"));
    }
}

#[test]
fn shadow_rays_given_as_lanes_equal_brute_force() {
    // The lab's shading hands its shadow rays over as lanes (`Scene::occluded_lanes`): the
    // Cornell box's flat list culls them by their cone straight from the lanes, other
    // structures copy them out. Every cast lane's answer is the brute-force loop's; lanes not
    // cast are never reported blocked. Groups of four as the lab's wave makes them, some lanes
    // left out.
    use raylab_core::shapes::accel::SegmentLanes;
    for choice in [SceneChoice::Cornell, SceneChoice::Bunny] {
        let scene = choice.load().unwrap();
        let settings = lab_settings(96, 96);
        let shadow = shadow_rays(&scene, &settings.light, &primary_rays(&settings.camera));
        let mut rng = raylab_core::base::sampling::Rng::new(17);
        for isa in Isa::available_for_tests("packets: shadow_rays_given_as_lanes") {
            let scene = scene.clone().rebuilt(AccelKind::Auto, isa);
            let mut checked = 0;
            for batch in shadow.chunks(64) {
                let mut soa = vec![[[0.0f32; 16]; 7]; batch.len().div_ceil(16)];
                let mut cast = vec![0u16; soa.len()];
                for (k, (ray, t_max)) in batch.iter().enumerate() {
                    let (g, i) = (k / 16, k % 16);
                    let floats = [
                        ray.origin.x,
                        ray.origin.y,
                        ray.origin.z,
                        ray.direction.x,
                        ray.direction.y,
                        ray.direction.z,
                        *t_max,
                    ];
                    for (row, v) in soa[g].iter_mut().zip(floats) {
                        row[i] = v;
                    }
                    if rng.next_f32() < 0.9 {
                        cast[g] |= 1 << i;
                    }
                }
                let groups: Vec<SegmentLanes> = soa
                    .iter()
                    .zip(&cast)
                    .map(|(s, &cast)| SegmentLanes {
                        origin: [&s[0], &s[1], &s[2]],
                        direction: [&s[3], &s[4], &s[5]],
                        t_max: &s[6],
                        cast,
                    })
                    .collect();
                // Told the rays are neighbours' (a group may have a cone where the batch has
                // none) or not: the same answers.
                for neighbours in [true, false] {
                    let mut blocked = vec![0u16; groups.len()];
                    scene.occluded_lanes(&groups, neighbours, &mut blocked);
                    for (k, (ray, t_max)) in batch.iter().enumerate() {
                        let (g, i) = (k / 16, k % 16);
                        let want = cast[g] & (1 << i) != 0
                            && occluded_brute_force(ray, &scene.triangles, *t_max);
                        assert_eq!(blocked[g] & (1 << i) != 0, want, "{} {ray:?}", isa.name());
                        checked += 1;
                    }
                }
            }
            assert!(checked > 5_000, "{checked}");
        }
    }
}
