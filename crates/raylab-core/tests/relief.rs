//! Normal maps and parallax occlusion mapping (the lab's section 6 extension) on rendered
//! images: a flat map and a constant height map are no relief, a normal tilted toward the light
//! brightens a pixel by the ratio of the cosines (equation 27), scene files name their maps.

mod common;

use std::io::Cursor;
use std::sync::Arc;

use common::{assert_same_image, settings};
use glam::Vec3;
use raylab_core::shading::material::TexturePreset;
use raylab_core::shading::relief::{Decoding, HeightMap, NormalMap, Relief};
use raylab_core::shading::texture::TextureImage;
use raylab_core::shapes::scene::spec::{BoxPart, PartRelief, ReliefSpec};
use raylab_core::shapes::scene::{Scene, SceneChoice, SceneSpec, cornell_box};
use raylab_core::transport::render::render;
use raylab_core::{Image, RenderSettings, Stage};

/// A PNG of `width × height` pixels, all `rgb`.
fn png(width: u32, height: u32, rgb: [u8; 3]) -> Vec<u8> {
    let image = image::RgbImage::from_pixel(width, height, image::Rgb(rgb));
    let mut bytes = Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).unwrap();
    bytes.into_inner()
}

/// A normal map of one colour, read from a PNG as a file would be.
fn normal_map(rgb: [u8; 3]) -> NormalMap {
    let image = TextureImage::from_encoded_as(&png(4, 4, rgb), "map.png", Decoding::Normal);
    NormalMap {
        image: Arc::new(image.unwrap()),
        strength: 1.0,
    }
}

/// The Cornell box with `relief` on the materials named.
fn box_with(relief: Relief, names: &[&str]) -> Scene {
    let mut scene = cornell_box();
    let relief = Arc::new(relief);
    for m in &mut scene.materials {
        if names.contains(&m.name.as_str()) {
            m.relief = Some(relief.clone());
        }
    }
    scene
}

const EVERY_SURFACE: [&str; 7] = ["red", "yellow", "green", "cyan", "blue", "purple", "white"];

/// The largest difference between two images' channels, relative to the brightest.
fn max_difference(a: &Image, b: &Image) -> f32 {
    let top = a.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max);
    let worst = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (*p - *q).abs().max_element())
        .fold(0.0, f32::max);
    worst / top
}

/// Every texel (128, 128, 255) decodes to (0, 0, 1): the shading normal is the triangle's
/// own normal up to the rounding of one normalisation, in every lab stage and in the path
/// stage (with bounces), so the image is the plain one up to float rounding.
#[test]
fn a_flat_normal_map_is_no_normal_map() {
    let plain = cornell_box();
    let flat = Relief {
        normal: Some(normal_map([128, 128, 255])),
        height: None,
        uv_scale: 1.0,
    };
    let mapped = box_with(flat, &EVERY_SURFACE);
    for stage in [
        Stage::Flat,
        Stage::Incoming,
        Stage::Direct,
        Stage::Shadows,
        Stage::Lab,
        Stage::Path,
    ] {
        let mut s = settings(stage, 48);
        if stage == Stage::Path {
            s.shading.bounces = Some(3);
            s.samples_per_pixel = 4;
        }
        let want = render(&plain, &s);
        let got = render(&mapped, &s);
        let d = max_difference(&want, &got);
        assert!(d < 1e-5, "{stage}: images differ by {d} of the brightest");
    }
    // On the textured teapot (its own coordinates, smooth normals that are not axis-aligned,
    // so the tilt's normalisation rounds): within 1e-5 too.
    let plain = SceneChoice::TexturedTeapot.load().unwrap();
    let mut mapped = plain.clone();
    let flat = Arc::new(Relief {
        normal: Some(normal_map([128, 128, 255])),
        height: None,
        uv_scale: 1.0,
    });
    for m in &mut mapped.materials {
        m.relief = Some(flat.clone());
    }
    for stage in [Stage::Lab, Stage::Path] {
        let mut s = settings(stage, 48);
        s.shading.bounces = Some(2);
        let d = max_difference(&render(&plain, &s), &render(&mapped, &s));
        assert!(
            d < 1e-5,
            "teapot, {stage}: images differ by {d} of the brightest"
        );
    }
}

/// A height map of one value carves nothing: its top is everywhere. The checkerboard floor
/// with it is the checkerboard floor, bit for bit (the coordinates are not touched); the
/// tiles' map does move the squares.
#[test]
fn a_constant_height_map_is_no_height_map() {
    let level =
        TextureImage::from_encoded_as(&png(8, 8, [150, 150, 150]), "h.png", Decoding::Height);
    let constant = Relief {
        normal: None,
        height: Some(HeightMap::new(Arc::new(level.unwrap()), 0.1)),
        uv_scale: 4.0,
    };
    let plain = cornell_box();
    let carved = box_with(constant, &["green"]);
    for stage in [Stage::Flat, Stage::Lab, Stage::Path] {
        let mut s = settings(stage, 64);
        s.texture_preset = TexturePreset::CheckerFloor;
        if stage == Stage::Path {
            s.shading.bounces = Some(2);
        }
        assert_same_image(&render(&carved, &s), &render(&plain, &s), stage);
    }
    // The preset's tiles carve: the floor's pixels change.
    let mut s = settings(Stage::Flat, 64);
    s.texture_preset = TexturePreset::CheckerFloor;
    let checker = render(&plain, &s);
    s.texture_preset = TexturePreset::ParallaxFloor;
    let tiles = render(&plain, &s);
    let moved = checker
        .pixels
        .iter()
        .zip(&tiles.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 50, "{moved} pixels moved");
}

/// Equation 27 with the perturbed normal: D = P·max(0, n̂·r̂)/(4πr²). On the back wall
/// (geometric normal (0, 0, −1), planar coordinates (x, y), so the tangent is +x) the texel
/// (192, 128, 255) decodes to (64/127, 0, 1) = (0.503937, 0, 1): the normal
/// n̂' = (0.503937, 0, −1)/1.119800, tilted 26.75° toward +x. Where the light (0, −0.5, −0.7)
/// lies to the right (x < 0 on the wall), D grows by (n̂'·r̂)/(n̂·r̂) =
/// (0.503937·r_x − r_z)/(1.119800·(−r_z)), and so does the pixel (ρ·D, the direct stage). At
/// (−0.9, −0.5, 1), r = (0.9, 0, −1.7): (0.453543 + 1.7)/(1.119800·1.7) = 1.131264; wherever
/// r_x > 0.8 the ratio exceeds (0.403150 + 1.7)/(1.119800·1.7) = 1.104799.
#[test]
fn a_normal_tilted_toward_the_light_brightens_by_the_cosine_ratio() {
    let plain = cornell_box();
    assert_eq!(plain.triangles[8].normal, Vec3::new(0.0, 0.0, -1.0));
    let tilted = Relief {
        normal: Some(normal_map([192, 128, 255])),
        height: None,
        uv_scale: 1.0,
    };
    let mapped = box_with(tilted, &["white"]);
    let s = settings(Stage::Direct, 64);
    let (want, got) = (render(&plain, &s), render(&mapped, &s));
    let ratio = |r: Vec3| (0.503_937 * r.x - r.z) / (1.119_8 * -r.z);
    let r = Vec3::new(0.9, 0.0, -1.7);
    assert!((ratio(r) - 1.131_264).abs() < 1e-6, "{}", ratio(r));
    let mut brighter = 0;
    for y in 0..64 {
        for x in 0..64 {
            let ray = s.camera.pixel_ray(x, y);
            let Some(hit) = plain.closest_intersection(&ray, f32::INFINITY) else {
                continue;
            };
            if plain.material_of(hit.triangle_index).name != "white" {
                continue;
            }
            let r = s.light.position - hit.position;
            let (p, q) = (want.get(x, y), got.get(x, y));
            let expected = p * ratio(r);
            assert!(
                (q - expected).abs().max_element() <= 1e-5 * expected.max_element(),
                "pixel ({x}, {y}) at {}: {q} against {expected}",
                hit.position
            );
            if r.x > 0.8 {
                assert!(q.x > 1.05 * p.x, "({x}, {y}) is brighter");
                brighter += 1;
            }
        }
    }
    assert!(brighter > 50, "{brighter}");
}

/// The pixel inspector prints the normal the light was computed with: on a bumpy wall the
/// map's, said to be so; it is the normal of equation 27 in the inspection's terms.
#[test]
fn the_inspector_shows_the_perturbed_normal() {
    let scene = cornell_box();
    let mut s = settings(Stage::Lab, 64);
    s.texture_preset = TexturePreset::BumpyWalls;
    // Column 8 sees the left wall (geometric normal (1, 0, 0)); the brick faces are flat, the
    // bevels by the mortar tilted.
    let tilted = (10..54).find_map(|y| {
        let i = raylab_core::teaching::inspect::inspect_pixel(&scene, &s, 8, y).unwrap();
        assert_eq!(i.surface.as_deref(), Some("purple"), "pixel (8, {y})");
        assert!(i.normal_mapped);
        i.shading_normal.is_some().then_some(i)
    });
    let i = tilted.expect("a bevel in the column");
    let n = i.shading_normal.unwrap();
    assert_ne!(Some(n), i.normal);
    assert!((n.length() - 1.0).abs() < 1e-6 && n.x > 0.0, "{n}");
    assert_eq!(i.shaded[0].normal, n);
    let text = i.to_text();
    assert!(text.contains("tilted by the normal map"), "{text}");
}

/// The normals view shows the normal the integrators shade with: the bricks' on the walls,
/// the plain normal elsewhere (the floor, the blocks), pixel for pixel.
#[test]
fn the_normals_view_shows_the_normal_map() {
    let scene = cornell_box();
    let never = || false;
    let mut s = settings(Stage::Lab, 64);
    let view = |s: &RenderSettings| {
        raylab_core::transport::view::render_view(
            &scene,
            s,
            raylab_core::transport::view::View::Normals,
            &never,
        )
        .unwrap()
        .image
    };
    let plain = view(&s);
    s.texture_preset = TexturePreset::BumpyWalls;
    let bumpy = view(&s);
    let (mut walls_changed, mut others) = (0, 0);
    for y in 0..64 {
        for x in 0..64 {
            let Some(hit) = scene.closest_intersection(&s.camera.pixel_ray(x, y), f32::INFINITY)
            else {
                continue;
            };
            let name = &scene.material_of(hit.triangle_index).name;
            if ["purple", "yellow", "white"].contains(&name.as_str()) {
                walls_changed += usize::from(plain.get(x, y) != bumpy.get(x, y));
            } else {
                assert_eq!(plain.get(x, y), bumpy.get(x, y), "({x}, {y}) on {name}");
                others += 1;
            }
        }
    }
    assert!(
        walls_changed > 300 && others > 300,
        "{walls_changed} {others}"
    );
}

/// A map tilting the normal the whole way along the surface ((255, 128, 128) and (0, 128, 128):
/// ±t, at 90°) is held to the shading frame's rules: at every pixel of the box the normal
/// shaded with stays on the viewer's side of the surface (cos θ_o ≥ 1e-3, no black patches)
/// and on the side of the triangle's own normal, unit.
#[test]
fn an_extreme_normal_map_keeps_the_normal_toward_the_viewer() {
    for rgb in [[255, 128, 128], [0, 128, 128], [128, 0, 128]] {
        let extreme = Relief {
            normal: Some(normal_map(rgb)),
            height: None,
            uv_scale: 1.0,
        };
        let scene = box_with(extreme, &EVERY_SURFACE);
        let s = settings(Stage::Lab, 48);
        let tracer = raylab_core::transport::integrator::Tracer::new(&scene, &s);
        let mut tilted = 0;
        for y in 0..48 {
            for x in 0..48 {
                let ray = s.camera.pixel_ray(x, y);
                let hit = scene.closest_intersection(&ray, f32::INFINITY).unwrap();
                let material = tracer.material_of(hit.triangle_index);
                let surface = tracer.surface(&hit, material, ray.direction);
                let n = surface.normal;
                assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
                assert!(
                    n.dot(-ray.direction) >= 0.999e-3,
                    "({x}, {y}): {n} faces away"
                );
                assert!(n.dot(surface.geometric) >= 0.0, "({x}, {y}): {n} crosses");
                tilted += usize::from(n != surface.geometric);
            }
        }
        assert!(tilted > 2000, "{rgb:?}: {tilted}");
    }
}

/// The presets render in every stage, the same image on one thread as on four
/// (deterministic), and with relief where the maps lie.
#[test]
fn the_presets_render_alike_on_any_thread_count() {
    let scene = cornell_box();
    for preset in [TexturePreset::BumpyWalls, TexturePreset::ParallaxFloor] {
        for stage in [Stage::Lab, Stage::Path] {
            let mut s = settings(stage, 48);
            s.texture_preset = preset;
            s.shading.bounces = Some(2);
            let one = common::on_threads(1, || render(&scene, &s));
            let four = common::on_threads(4, || render(&scene, &s));
            assert_same_image(&one, &four, format!("{preset} {stage}"));
            s.texture_preset = TexturePreset::None;
            let plain = render(&scene, &s);
            assert!(max_difference(&plain, &one) > 0.01, "{preset} {stage}");
        }
    }
}

/// A scene file's `[[scene.surfaces]]` gives the back wall a normal map relative to the file:
/// it loads, renders with relief, round-trips; a missing map is an error naming the file.
#[test]
fn a_scene_file_names_its_normal_map() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("maps")).unwrap();
    std::fs::write(dir.path().join("maps/tilt.png"), png(4, 4, [192, 128, 255])).unwrap();
    let mut spec = SceneSpec::cornell("tilted wall");
    spec.surfaces.push(PartRelief {
        part: BoxPart::BackWall,
        relief: ReliefSpec {
            normal_map: Some(dir.path().join("maps/tilt.png")),
            ..ReliefSpec::default()
        },
    });
    let mut s = settings(Stage::Direct, 32);
    s.scene = SceneChoice::Custom(Box::new(spec));
    let file = dir.path().join("wall.toml");
    raylab_core::files::scene_file::save(&s, &file).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.contains("[[scene.surfaces]]"), "{text}");
    assert!(text.contains("part = \"back-wall\""), "{text}");
    assert!(text.contains("normal_map = \"maps/tilt.png\""), "{text}");
    assert!(
        !text.contains("normal_strength"),
        "the default is left out: {text}"
    );
    let read: RenderSettings = raylab_core::files::scene_file::load(&file).unwrap();
    assert_eq!(read, s);
    // The memory estimate counts the map as a texture is counted: its decoding and its file.
    let file_bytes = std::fs::metadata(dir.path().join("maps/tilt.png"))
        .unwrap()
        .len();
    assert_eq!(
        read.scene.memory_estimate(),
        TextureImage::decoding_bytes(4, 4) + file_bytes
    );
    let scene = read.scene.load().unwrap();
    let plain = render(&cornell_box(), &s);
    assert!(max_difference(&plain, &render(&scene, &s)) > 0.01);

    // The map gone: an error naming it.
    std::fs::remove_file(dir.path().join("maps/tilt.png")).unwrap();
    let e = raylab_core::files::scene_file::load(&file)
        .unwrap()
        .scene
        .load()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("could not load the normal map") && e.contains("maps/tilt.png"),
        "{e}"
    );

    // A strength out of range is refused when the file is read, naming the field.
    let bad = text.replace(
        "part = \"back-wall\"",
        "part = \"back-wall\"\nnormal_strength = -1.0",
    );
    std::fs::write(&file, bad).unwrap();
    let e = raylab_core::files::scene_file::load(&file)
        .unwrap_err()
        .to_string();
    assert!(e.contains("scene.surfaces[0].normal_strength"), "{e}");
    // An unknown field too.
    let bad = text.replace("part = \"back-wall\"", "part = \"back-wall\"\nbump = 1");
    std::fs::write(&file, bad).unwrap();
    let e = raylab_core::files::scene_file::load(&file)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bump"), "{e}");
}

/// A grey image named as a scene file's `normal_map` (a wall's or a model's) is refused as
/// the same image named by a material library is ("is grey: a bump map of heights, not a
/// normal map"): it tilted the wall's normals without a word. The same file as a height map
/// is what it is, and loads.
#[test]
fn a_grey_normal_map_in_a_scene_file_is_refused_as_in_a_material_library() {
    let dir = tempfile::tempdir().unwrap();
    let grey = dir.path().join("bumps.png");
    std::fs::write(&grey, png(4, 4, [90, 90, 90])).unwrap();
    let wall = |relief: ReliefSpec| {
        let mut spec = SceneSpec::cornell("grey wall");
        spec.surfaces.push(PartRelief {
            part: BoxPart::BackWall,
            relief,
        });
        spec
    };
    let mut model = SceneChoice::Teapot.spec();
    model.models[0].relief.normal_map = Some(grey.clone());
    for spec in [
        wall(ReliefSpec {
            normal_map: Some(grey.clone()),
            ..ReliefSpec::default()
        }),
        model,
    ] {
        let mut s = settings(Stage::Direct, 16);
        s.scene = SceneChoice::Custom(Box::new(spec));
        let file = dir.path().join("grey.toml");
        std::fs::remove_file(&file).ok();
        raylab_core::files::scene_file::save(&s, &file).unwrap();
        let e = raylab_core::files::scene_file::load(&file)
            .unwrap()
            .scene
            .load()
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!(
                "could not load the normal map '{}': is grey: a bump map of heights, not a \
                 normal map",
                grey.display()
            )
        );
    }
    let heights = wall(ReliefSpec {
        height_map: Some(grey.clone()),
        ..ReliefSpec::default()
    });
    SceneChoice::Custom(Box::new(heights)).load().unwrap();
}

/// Parallax self-shadowing on the parallax-floor preset (lab stage, 128²), under a light low
/// over the floor's far right corner, so that the tiles' shadows fall toward the camera (with
/// the lab's light, in front and above, they fall behind the tiles, where the camera cannot
/// see): only floor pixels change, and the ones that do lose D alone (what is left is ρ·N,
/// the lab's shadow, equation 30): 45 of them (the grout beside the tiles' edges).
#[test]
fn parallax_self_shadowing_darkens_the_grout_by_d() {
    let scene = cornell_box();
    let mut s = common::parallax_floor_under_a_low_light();
    let shadowed = render(&scene, &s);
    s.shading.parallax_shadows = false;
    let lit = render(&scene, &s);
    let mut no_n = s.clone();
    no_n.shading.indirect = false;
    let d_only = render(&scene, &no_n);
    let n = RenderSettings::default().shading.indirect_light;
    let mut darker = 0;
    for y in 0..128 {
        for x in 0..128 {
            let (a, b) = (shadowed.get(x, y), lit.get(x, y));
            if a == b {
                continue;
            }
            let ray = s.camera.pixel_ray(x, y);
            let hit = scene.closest_intersection(&ray, f32::INFINITY).unwrap();
            assert_eq!(scene.material_of(hit.triangle_index).name, "green");
            // ρ·N with ρ = (ρ·(D + N) − ρ·D)/N.
            let rho_n = b - d_only.get(x, y);
            assert!(
                (a - rho_n).abs().max_element() <= 1e-5,
                "({x}, {y}): {a} against ρ·N = {rho_n}"
            );
            assert!(rho_n.max_element() < b.max_element(), "N = {n}");
            darker += 1;
        }
    }
    eprintln!("{darker} floor pixels in the relief's shadow");
    assert!(darker >= 30, "{darker}");
}
