//! The debug views against the queries they show: every traced view's raw values are checked
//! pixel by pixel against `Scene::closest_intersection` and `light::in_shadow`, and the
//! BVH-cost view's counting traversal against the real one (same hit, bit for bit, on 100,000
//! rays per scene and kernel set).

mod common;

use std::collections::HashMap;

use glam::Vec3;
use raylab_core::base::geometry::Ray;
use raylab_core::shading::light::approach_at_edge;
use raylab_core::shapes::accel::{Accel, AccelKind, Hit, Isa, TraversalCost};
use raylab_core::shapes::scene::in_shadow;
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::transport::render::{Cancelled, render};
use raylab_core::transport::view::{
    DEPTH_NO_HIT, SHADOW_BLOCKED, SHADOW_FACES_AWAY, SHADOW_LIT, ShadowState, View, ViewImage,
    ViewValues, render_view, triangle_colour,
};
use raylab_core::{RenderSettings, Shading, Stage};

use common::rays::rays;

fn settings(width: u32, height: u32) -> RenderSettings {
    let mut s = RenderSettings::default();
    s.camera = s.camera.with_resolution(width, height);
    s
}

fn view(scene: &Scene, settings: &RenderSettings, view: View) -> ViewImage {
    render_view(scene, settings, view, &|| false).expect("not cancelled")
}

/// Each pixel's centre ray, row by row: what the traced views follow.
fn centre_rays(settings: &RenderSettings) -> Vec<Ray> {
    let c = &settings.camera;
    (0..c.height)
        .flat_map(|y| (0..c.width).map(move |x| c.pixel_ray(x, y)))
        .collect()
}

fn bunny() -> Scene {
    SceneChoice::Bunny.load().unwrap()
}

// ---- The counting traversal equals the real one. ----

/// On every kernel set, the scene's own structure (and the wide BVH, the binary BVH too, over
/// any scene): `closest_counting`'s hit is `closest`'s, bit for bit, and the counts are
/// plausible. Returns the mean cost per ray of the scene's own structure, best kernels.
fn counting_equals_closest(scene: &Scene, seed: u64) -> f64 {
    let triangles = &scene.triangles;
    let rays = rays(triangles, 100_000, seed);
    let mut kinds = vec![
        (AccelKind::Auto, Isa::Scalar),
        (AccelKind::Bvh2, Isa::Scalar),
    ];
    for isa in Isa::available_for_tests("views: counting_equals_closest") {
        kinds.push((AccelKind::Auto, isa));
        kinds.push((AccelKind::Bvh8, isa));
    }
    let mut mean = 0.0;
    for (kind, isa) in kinds {
        let accel = Accel::build(triangles, kind, isa);
        let mut total = 0u64;
        let mut hits = 0;
        for (ray, t_max) in &rays {
            let (hit, cost) = accel.closest_counting(triangles, ray, *t_max);
            let bits = |h: Option<Hit>| h.map(|h| (h.index, [h.t, h.u, h.v].map(f32::to_bits)));
            assert_eq!(
                bits(hit),
                bits(accel.closest(triangles, ray, *t_max)),
                "{} {}: {ray:?} (t_max {t_max})",
                accel.kind(),
                isa.name()
            );
            assert!(cost.triangles as usize <= triangles.len(), "{cost:?}");
            if hit.is_some() {
                // A hit was tested, and in the wide BVH reached through at least the root.
                assert!(cost.triangles >= 1, "{cost:?}");
            }
            hits += usize::from(hit.is_some());
            total += u64::from(cost.total());
        }
        assert!(hits > 50_000, "{hits}");
        if kind == AccelKind::Auto {
            mean = total as f64 / rays.len() as f64;
        }
    }
    mean
}

#[test]
fn cornell_counting_traversal_equals_closest_on_100k_rays() {
    let mean = counting_equals_closest(&cornell_box(), 11);
    // The flat loop: every triangle for every ray.
    assert_eq!(mean, 30.0);
}

#[test]
fn bunny_counting_traversal_equals_closest_on_100k_rays() {
    let mean = counting_equals_closest(&bunny(), 12);
    // A tree: far fewer than the 3,674 triangles + the walls per ray.
    assert!(mean > 1.0 && mean < 200.0, "{mean}");
}

#[test]
fn teapot_counting_traversal_equals_closest_on_100k_rays() {
    let mean = counting_equals_closest(&SceneChoice::Teapot.load().unwrap(), 13);
    assert!(mean > 1.0 && mean < 200.0, "{mean}");
}

// ---- The views, pixel by pixel. ----

/// The Cornell box uses the flat loop: every primary ray tests all 30 triangles and no node,
/// so the heat map is one colour (the maximum, white) and the legend's mean and maximum are 30.
#[test]
fn cornell_box_costs_exactly_30_triangles_per_ray() {
    let scene = cornell_box();
    assert_eq!(scene.accel().kind(), AccelKind::Flat);
    let v = view(&scene, &settings(40, 30), View::BvhCost);
    let ViewValues::BvhCost(costs) = &v.values else {
        panic!("{:?}", v.values)
    };
    assert_eq!(costs.len(), 40 * 30);
    let want = TraversalCost {
        nodes: 0,
        triangles: 30,
    };
    assert!(costs.iter().all(|c| *c == want));
    assert!(v.image.pixels.iter().all(|p| *p == Vec3::ONE));
    assert_eq!(v.legend.range, Some((0.0, 30.0)));
    let text = v.legend.lines.join("\n");
    assert!(
        text.contains("mean 30.0 per ray: 0.0 nodes + 30.0 triangles"),
        "{text}"
    );
    assert!(text.contains("flat"), "{text}");
}

/// The bunny's costs are the counting traversal's on each pixel's centre ray; the heat map's
/// maximum is the largest of them.
#[test]
fn bunny_cost_view_is_the_counting_traversal_per_pixel() {
    let scene = bunny();
    let s = settings(32, 32);
    let v = view(&scene, &s, View::BvhCost);
    let ViewValues::BvhCost(costs) = &v.values else {
        panic!()
    };
    for (ray, cost) in centre_rays(&s).iter().zip(costs) {
        let (_, want) = scene
            .accel()
            .closest_counting(&scene.triangles, ray, f32::INFINITY);
        assert_eq!(*cost, want);
    }
    let max = costs.iter().map(|c| c.total()).max().unwrap();
    assert_eq!(v.legend.range, Some((0.0, max as f32)));
    assert!(costs.iter().any(|c| c.nodes > 0));
    // The most expensive pixel is white, and a cheaper one is not.
    let brightest = costs.iter().position(|c| c.total() == max).unwrap();
    assert_eq!(v.image.pixels[brightest], Vec3::ONE);
    let cheapest = costs.iter().map(|c| c.total()).min().unwrap();
    assert!(cheapest < max);
}

/// One colour per triangle: every pixel's id is `closest_intersection`'s triangle, its colour
/// is that triangle's, and different triangles have different colours.
#[test]
fn triangle_view_matches_closest_intersection_per_pixel() {
    for (scene, s) in [
        (cornell_box(), settings(64, 48)),
        (bunny(), settings(48, 48)),
    ] {
        let v = view(&scene, &s, View::Triangle);
        let ViewValues::Triangle(ids) = &v.values else {
            panic!()
        };
        let mut colour_of: HashMap<u32, Vec3> = HashMap::new();
        for ((ray, id), pixel) in centre_rays(&s).iter().zip(ids).zip(&v.image.pixels) {
            let want = scene.closest_intersection(ray, f32::INFINITY);
            assert_eq!(*id, want.map(|h| h.triangle_index as u32));
            match id {
                Some(i) => {
                    assert_eq!(*pixel, triangle_colour(*i));
                    assert_eq!(*colour_of.entry(*i).or_insert(*pixel), *pixel);
                }
                None => assert_eq!(*pixel, Vec3::ZERO),
            }
        }
        let mut colours: Vec<[u32; 3]> = colour_of
            .values()
            .map(|c| c.to_array().map(f32::to_bits))
            .collect();
        colours.sort();
        colours.dedup();
        assert_eq!(
            colours.len(),
            colour_of.len(),
            "two triangles share a colour"
        );
        assert!(colour_of.len() > 10, "{}", colour_of.len());
        assert!(v.legend.lines[1].contains(&format!("{} of the scene's", colour_of.len())));
    }
    // The box fills the default view: no pixel is black.
    let v = view(&cornell_box(), &settings(64, 48), View::Triangle);
    assert!(v.image.pixels.iter().all(|p| *p != Vec3::ZERO));
}

/// Depth: `t` is `closest_intersection`'s distance exactly; the nearest pixel is white, the
/// farthest black, and the legend's range is theirs.
#[test]
fn depth_view_is_closest_intersection_t() {
    let scene = bunny();
    let mut s = settings(48, 40);
    // The camera stands in front of the box's open side: turned right, part of the view
    // misses the box, so both hits and misses are checked.
    s.camera.yaw = 0.9;
    let v = view(&scene, &s, View::Depth);
    let ViewValues::Depth(depths) = &v.values else {
        panic!()
    };
    for (ray, t) in centre_rays(&s).iter().zip(depths) {
        assert_eq!(
            *t,
            scene
                .closest_intersection(ray, f32::INFINITY)
                .map(|h| h.distance)
        );
    }
    let hits: Vec<f32> = depths.iter().flatten().copied().collect();
    assert!(
        !hits.is_empty() && hits.len() < depths.len(),
        "hits and misses"
    );
    let near = hits.iter().copied().fold(f32::INFINITY, f32::min);
    let far = hits.iter().copied().fold(0.0, f32::max);
    assert_eq!(v.legend.range, Some((near, far)));
    for (t, p) in depths.iter().zip(&v.image.pixels) {
        match t {
            None => assert_eq!(*p, DEPTH_NO_HIT),
            Some(t) if *t == near => assert_eq!(*p, Vec3::ONE),
            Some(t) if *t == far => assert_eq!(*p, Vec3::ZERO),
            Some(t) => {
                let want = 1.0 - (t - near) / (far - near);
                assert!((p.x - want).abs() < 1e-6 && p.x == p.y && p.y == p.z);
            }
        }
    }
    let text = v.legend.lines.join("\n");
    assert!(
        text.contains("(white)") && text.contains("dark blue"),
        "{text}"
    );
}

/// Depth of the default Cornell view, by hand: the centre pixel's ray goes straight along +z
/// from z = −3.001 to the back wall at z = 1: t = 4.001.
#[test]
fn depth_at_the_centre_of_the_box_by_hand() {
    let s = settings(64, 64);
    let v = view(&cornell_box(), &s, View::Depth);
    let ViewValues::Depth(depths) = &v.values else {
        panic!()
    };
    // Pixel (32, 20)'s centre ray: direction (0.5, −11.5, 64), above the blocks.
    let t = depths[20 * 64 + 32].unwrap();
    let d = Vec3::new(0.5, -11.5, 64.0).normalize();
    assert!((t - 4.001 / d.z).abs() < 1e-5, "{t}");
}

/// Barycentric: `(1 − u − v, u, v)` of `closest_intersection`, exactly, and its colour.
#[test]
fn barycentric_view_is_the_hits_coordinates() {
    let scene = bunny();
    let s = settings(40, 40);
    let v = view(&scene, &s, View::Barycentric);
    let ViewValues::Barycentric(coords) = &v.values else {
        panic!()
    };
    for ((ray, c), p) in centre_rays(&s).iter().zip(coords).zip(&v.image.pixels) {
        let want = scene
            .closest_intersection(ray, f32::INFINITY)
            .map(|h| Vec3::new(1.0 - h.u - h.v, h.u, h.v));
        assert_eq!(*c, want);
        assert_eq!(*p, want.unwrap_or(Vec3::ZERO));
        if let Some(c) = c {
            // They sum to 1 (up to rounding), each within the edge tolerance of [0, 1].
            assert!((c.x + c.y + c.z - 1.0).abs() < 1e-5 && c.min_element() > -1e-4);
        }
    }
}

/// Normals: the shading normal as (n + 1)/2; the floor (n = (0, −1, 0): y is down) is
/// (½, 0, ½) and the back wall (n = (0, 0, −1)) is (½, ½, 0).
#[test]
fn normals_view_by_hand_and_per_pixel() {
    let s = settings(64, 64);
    let v = view(&cornell_box(), &s, View::Normals);
    // Pixel (32, 62) looks down at the floor (y = 1 at z ≈ −0.9, in front of the blocks),
    // (32, 20) at the back wall above them (y ≈ −0.72 at z = 1).
    assert_eq!(v.image.get(32, 62), Vec3::new(0.5, 0.0, 0.5));
    assert_eq!(v.image.get(32, 20), Vec3::new(0.5, 0.5, 0.0));
    let scene = bunny();
    let v = view(&scene, &settings(32, 32), View::Normals);
    let ViewValues::Normals(normals) = &v.values else {
        panic!()
    };
    for (ray, n) in centre_rays(&settings(32, 32)).iter().zip(normals) {
        let want = scene
            .closest_intersection(ray, f32::INFINITY)
            .map(|h| scene.shading_normal(h.triangle_index, h.u, h.v, true));
        assert_eq!(*n, want);
    }
}

/// Shadow: where a pixel's hit gets light, the view agrees with `light::in_shadow` (the shadow
/// ray from the triangle's side toward the light's centre), and with the integrator: the
/// shadows stage (figure 6, no indirect term: ρ·D after shadows) is black exactly where the
/// view is not white.
#[test]
fn shadow_view_agrees_with_in_shadow_and_the_shadows_stage() {
    for scene in [cornell_box(), bunny()] {
        let mut s = settings(48, 48);
        s.shading = Shading::for_stage(Stage::Shadows);
        let v = view(&scene, &s, View::Shadow);
        let ViewValues::Shadow(states) = &v.values else {
            panic!()
        };
        let shaded = render(&scene, &s);
        let mut seen = HashMap::new();
        for ((ray, state), (p, value)) in centre_rays(&s)
            .iter()
            .zip(states)
            .zip(v.image.pixels.iter().zip(&shaded.pixels))
        {
            *seen.entry(*state).or_insert(0) += 1;
            let hit = scene.closest_intersection(ray, f32::INFINITY);
            match (state, hit) {
                (ShadowState::NoHit, None) => assert_eq!(*p, Vec3::ZERO),
                (ShadowState::NoHit, Some(_)) | (_, None) => panic!("{state:?} for {hit:?}"),
                (ShadowState::FacesAway, Some(_)) => assert_eq!(*p, SHADOW_FACES_AWAY),
                (lit_or_blocked, Some(h)) => {
                    let n = scene.triangles[h.triangle_index].normal;
                    let t = &scene.triangles[h.triangle_index];
                    let at_edge = approach_at_edge(t, h.u, h.v, ray.direction);
                    let blocked = in_shadow(&scene, &s.light, h.position, n, at_edge);
                    assert_eq!(*lit_or_blocked == ShadowState::Blocked, blocked);
                    let colour = if blocked { SHADOW_BLOCKED } else { SHADOW_LIT };
                    assert_eq!(*p, colour);
                }
            }
            assert_eq!(
                *state == ShadowState::Lit,
                *value != Vec3::ZERO,
                "{state:?} {value}"
            );
        }
        // The box shows the blocks' shadows on the floor.
        assert!(
            seen.get(&ShadowState::Lit).is_some_and(|&n| n > 100),
            "{seen:?}"
        );
        assert!(
            seen.get(&ShadowState::Blocked).is_some_and(|&n| n > 20),
            "{seen:?}"
        );
    }
}

/// A light behind the back wall (z = 1.5): the back wall, whose normal points into the box
/// (−z), faces away from it; the floor, ceiling and side walls face it, but the back wall
/// stands between: in shadow. Nothing inside is lit.
#[test]
fn shadow_view_shows_surfaces_facing_away() {
    let mut s = settings(16, 16);
    s.light.position = Vec3::new(0.0, 0.0, 1.5);
    let v = view(&cornell_box(), &s, View::Shadow);
    let ViewValues::Shadow(states) = &v.values else {
        panic!()
    };
    assert_eq!(states[8 * 16 + 8], ShadowState::FacesAway, "the back wall");
    assert_eq!(states[15 * 16 + 8], ShadowState::Blocked, "the floor");
    assert!(!states.contains(&ShadowState::Lit));
}

/// The aperture is ignored: the views follow the pinhole ray through each pixel's centre.
#[test]
fn views_ignore_the_lens_and_the_thread_count() {
    let scene = cornell_box();
    let pinhole = settings(32, 24);
    let mut lens = pinhole.clone();
    lens.camera.aperture = 0.2;
    lens.camera.focus_distance = 2.0;
    for v in [View::Depth, View::Triangle, View::Shadow] {
        let a = view(&scene, &pinhole, v);
        let b = common::on_threads(3, || view(&scene, &lens, v));
        assert_eq!(a, b, "{v}");
    }
}

#[test]
fn a_cancelled_view_stops() {
    let r = render_view(&cornell_box(), &settings(32, 32), View::Depth, &|| true);
    assert_eq!(r, Err(Cancelled));
}

/// The shaded view is the renderer's image; the variance view needs at least two samples, and
/// a constant-colour stage (flat: ρ, at pixel centres and jittered alike inside one wall) has
/// none but at edges.
#[test]
fn shaded_and_variance_come_from_the_renderer() {
    let scene = cornell_box();
    let mut s = settings(32, 24);
    s.samples_per_pixel = 2;
    let v = view(&scene, &s, View::Shaded);
    common::assert_renders(&scene, &s, &v.image, "the shaded view");
    s.shading = Shading::for_stage(Stage::Flat);
    s.samples_per_pixel = 1;
    let v = view(&scene, &s, View::Variance);
    let ViewValues::Variance(values) = &v.values else {
        panic!("{:?}", v.values)
    };
    assert!(
        v.legend.lines[0].contains("n = 2 samples"),
        "{:?}",
        v.legend
    );
    // Equal samples leave only rounding (s² ~ 1e-8 of ρ²), edges a spread of order ρ².
    let zero = values.iter().filter(|&&x| x < 1e-6).count();
    assert!(zero > values.len() * 3 / 4 && zero < values.len(), "{zero}");
}

#[test]
fn empty_image_and_empty_scene_do_not_panic() {
    let empty = Scene::new(
        Vec::new(),
        vec![raylab_core::Material::diffuse("m", Vec3::ONE)],
    );
    for v in View::ALL.into_iter().filter(|v| v.is_traced()) {
        let out = view(&empty, &settings(8, 8), v);
        assert_eq!(out.image.pixels.len(), 64, "{v}");
        assert!(!out.legend.lines.is_empty());
    }
}
