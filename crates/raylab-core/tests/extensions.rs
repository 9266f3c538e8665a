//! The lab's extensions beyond the path tracer: textures, soft shadows, depth of field and a
//! coloured light, checked on rendered images against what a hand computation says.
//!
//! Each extension is off by default (no texture, light radius 0, aperture 0, white light), and
//! then the lab's images are unchanged: the stage tests (tests/stages.rs) keep passing.

mod common;

use common::{assert_renders, assert_same_image, bits, settings};
use glam::Vec3;
use raylab_core::base::geometry::Triangle;
use raylab_core::shading::material::{
    DEFAULT_ROUGHNESS, MaterialPreset, PRESET_TEXTURE_SCALE, ROUGH_FRONT_BRIGHT_FROM, TALL_BLOCK,
    TexturePreset,
};
use raylab_core::shapes::scene::{Scene, SceneChoice, cornell_box};
use raylab_core::transport::render::render;
use raylab_core::{Camera, Image, Material, RenderSettings, Stage};

/// The checkerboard floor: every pixel that sees the floor shows the colour of the square its
/// hit falls in, computed by hand from the hit position. The floor is the plane y = 1; its
/// texture coordinates are the planar projection (x, z), and the square is
/// (⌊4x⌋, ⌊4z⌋): green where their sum is even, light grey where it is odd. At (0.1, 1, 0.1),
/// ⌊0.4⌋ + ⌊0.4⌋ = 0: green; at (0.3, 1, 0.1), 1 + 0 = 1: grey.
#[test]
fn checkerboard_squares_land_where_the_mapping_puts_them() {
    let scene = cornell_box();
    let mut s = settings(Stage::Flat, 96);
    s.texture_preset = TexturePreset::CheckerFloor;
    let image = render(&scene, &s);
    let green = Vec3::new(0.15, 0.75, 0.15);
    let grey = Vec3::splat(0.8);
    let (mut seen_green, mut seen_grey) = (0, 0);
    for y in 0..96 {
        for x in 0..96 {
            let ray = s.camera.pixel_ray(x, y);
            let Some(hit) = scene.closest_intersection(&ray, f32::INFINITY) else {
                continue;
            };
            if scene.material_of(hit.triangle_index).name != "green" {
                continue;
            }
            let p = hit.position;
            let square =
                (p.x * PRESET_TEXTURE_SCALE).floor() + (p.z * PRESET_TEXTURE_SCALE).floor();
            let expected = if square.rem_euclid(2.0) < 1.0 {
                seen_green += 1;
                green
            } else {
                seen_grey += 1;
                grey
            };
            assert_eq!(image.get(x, y), expected, "pixel ({x}, {y}) at {p}");
        }
    }
    assert!(
        seen_green > 100 && seen_grey > 100,
        "{seen_green} {seen_grey}"
    );
}

/// The lab stages and the path tracer read the texture: the flat stage shows ρ itself, and
/// each other stage multiplies the same ρ into its value, so at every pixel the textured
/// value is the plain one scaled by the textured ρ over the plain ρ (both read from the flat
/// stage). The path tracer with no bounces (its value ρ·D at the first hit, figure 6) obeys
/// the same rule. The grid's lines darken ρ, so the rule is tested on many pixels whose ρ
/// changed.
#[test]
fn every_stage_reads_the_texture() {
    let scene = cornell_box();
    let flat = |texture| {
        let mut s = settings(Stage::Flat, 48);
        s.texture_preset = texture;
        render(&scene, &s)
    };
    let (rho_plain, rho_textured) = (flat(TexturePreset::None), flat(TexturePreset::Both));
    let changed = rho_plain
        .pixels
        .iter()
        .zip(&rho_textured.pixels)
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 200, "{changed} pixels of ρ changed");
    for stage in [
        Stage::Incoming,
        Stage::Direct,
        Stage::Shadows,
        Stage::Lab,
        Stage::Path,
    ] {
        let mut s = settings(stage, 48);
        s.shading.bounces = Some(0);
        let plain = render(&scene, &s);
        s.texture_preset = TexturePreset::Both;
        let textured = render(&scene, &s);
        for i in 0..plain.pixels.len() {
            let (p, t) = (plain.pixels[i], textured.pixels[i]);
            let want = if stage == Stage::Incoming {
                // D alone: no ρ, so no texture.
                p
            } else {
                p / rho_plain.pixels[i] * rho_textured.pixels[i]
            };
            let close = (t - want).abs().max_element() <= 1e-5 * want.abs().max_element().max(1.0);
            assert!(close, "{stage}, pixel {i}: {t} against {want}");
        }
    }
}

/// Soft shadows: with a light of radius 0.15, every pixel of the `shadows` stage lies between
/// the umbra (0) and full light (the `direct` stage: no shadow rays), and the pixels strictly
/// between, the penumbra, lie along the hard shadow's edges.
#[test]
fn a_soft_shadow_lies_between_umbra_and_full_light() {
    let scene = cornell_box();
    let side = 64;
    let full = render(&scene, &settings(Stage::Direct, side));
    let hard = render(&scene, &settings(Stage::Shadows, side));
    let mut s = settings(Stage::Shadows, side);
    s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.15 };
    s.samples_per_pixel = 64;
    let soft = render(&scene, &s);
    // The same jitter without the sphere: the hard shadow anti-aliased alike.
    let mut h = settings(Stage::Shadows, side);
    h.samples_per_pixel = 64;
    let hard_aa = render(&scene, &h);
    let mut full_aa_s = settings(Stage::Direct, side);
    full_aa_s.samples_per_pixel = 64;
    let full_aa = render(&scene, &full_aa_s);
    let mut penumbra = 0;
    for i in 0..soft.pixels.len() {
        let (v, top) = (soft.pixels[i], full_aa.pixels[i]);
        for c in 0..3 {
            assert!(
                v[c] >= 0.0 && v[c] <= top[c] * (1.0 + 1e-5) + 1e-7,
                "pixel {i}: {v} above full light {top}"
            );
        }
        let share = if top.x > 1e-4 { v.x / top.x } else { 1.0 };
        let hard_share = if top.x > 1e-4 {
            hard_aa.pixels[i].x / top.x
        } else {
            1.0
        };
        if share > 0.05 && share < 0.95 && !(0.02..=0.98).contains(&hard_share) {
            // Strictly between where the hard shadow is all or nothing: the penumbra. It must
            // be near the hard shadow's edge. Its width on a surface is the light's diameter
            // times (occluder to surface) / (light to occluder): at most 0.3 · 1.5 / 0.6 =
            // 0.75 scene units here, 12 pixels of this 64-pixel view at the back of the box.
            penumbra += 1;
            let (x, y) = ((i % side as usize) as i64, (i / side as usize) as i64);
            let near_edge = (-12..=12).any(|dy: i64| {
                (-12..=12).any(|dx: i64| {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= side as i64 || ny >= side as i64 {
                        return false;
                    }
                    let j = (ny * side as i64 + nx) as usize;
                    let lit = |img: &Image, k: usize| img.pixels[k].x > 0.5 * full.pixels[k].x;
                    lit(&hard, j) != lit(&hard, i)
                })
            });
            assert!(
                near_edge,
                "penumbra pixel ({x}, {y}) far from any hard shadow edge"
            );
        }
    }
    assert!(penumbra > 20, "{penumbra} penumbra pixels");
}

/// Radius 0 is the lab's point light and draws no random numbers: the image is the hard one bit
/// for bit, whatever the sample count.
#[test]
fn radius_zero_and_aperture_zero_are_the_labs_images() {
    let scene = cornell_box();
    for stage in Stage::ALL {
        let mut s = settings(stage, 40);
        s.samples_per_pixel = 3;
        let lab = render(&scene, &s);
        s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.0 };
        s.camera.aperture = 0.0;
        s.camera.focus_distance = 1.234;
        s.texture_preset = TexturePreset::None;
        s.shading.smooth = false;
        assert_renders(&scene, &s, &lab, stage);
    }
}

/// Flat shading ignores the vertex normals exactly: the bunny with smooth shading off is the
/// bunny without vertex normals, bit for bit; with it on, the image changes.
#[test]
fn flat_shading_is_the_faceted_image() {
    let scene = SceneChoice::Bunny.load().unwrap();
    let mut s = settings(Stage::Lab, 64);
    s.scene = SceneChoice::Bunny;
    s.shading.smooth = false;
    let flat = render(&scene, &s);
    let faceted = scene.clone().with_surface(Vec::new(), Vec::new());
    assert_renders(&faceted, &s, &flat, "without vertex normals");
    s.shading.smooth = true;
    let smooth = render(&scene, &s);
    if scene.vertex_normals.is_empty() {
        // Without vertex normals smooth is flat.
        assert_same_image(&smooth, &flat, "smooth without vertex normals");
    } else {
        assert_ne!(bits(&smooth), bits(&flat));
    }
}

/// A tiny white square on a black background, its image's centroid variance per axis.
fn spread(settings: &RenderSettings, scene: &Scene) -> (f64, f64) {
    let image = render(scene, settings);
    let (mut mass, mut mx, mut mxx) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..image.height {
        for x in 0..image.width {
            let w = f64::from(image.get(x, y).x);
            let px = f64::from(x) + 0.5;
            mass += w;
            mx += w * px;
            mxx += w * px * px;
        }
    }
    let mean = mx / mass;
    (mass, mxx / mass - mean * mean)
}

/// Depth of field on a rendered image. A white square 0.05 wide stands at depth 4 in front of
/// a pinhole of focal length 64 px: its image is 64·0.05/4 = 0.8 px wide, a point.
///
/// Focused at its depth, the image does not spread: the lens's rays for each pixel meet on the
/// square's plane, so the image is the pinhole's, spread (standard deviation) well under a
/// pixel. Focused at F = 2 with aperture A = 0.25, each point of it spreads over the circle of
/// confusion of radius r = f·A·|1/F − 1/z| = 64 · 0.25 · (1/2 − 1/4) = 4 px (derived in
/// `Camera::lens_ray_rotated`). A uniform disk of radius r has variance r²/4 = 4 px² along each
/// axis; variances of independent spreads add, so the defocused image's variance exceeds the
/// focused one's by 4 px². The light gathered (the sum of the pixels) is the square's image
/// area, 0.8² = 0.64 px², either way: with 4096 samples per pixel about 0.64 · 4096 = 2621
/// samples hit it, so the sum is within 4/√2621 = 8 % of that.
#[test]
fn depth_of_field_spreads_by_the_circle_of_confusion() {
    let (h, z) = (0.025, 4.0);
    let square = vec![
        Triangle::new(
            Vec3::new(-h, -h, z),
            Vec3::new(h, -h, z),
            Vec3::new(h, h, z),
            0,
        ),
        Triangle::new(
            Vec3::new(-h, -h, z),
            Vec3::new(h, h, z),
            Vec3::new(-h, h, z),
            0,
        ),
    ];
    let scene = Scene::new(square, vec![Material::diffuse("white", Vec3::ONE)]);
    let mut s = settings(Stage::Flat, 64);
    s.camera = Camera {
        position: Vec3::ZERO,
        ..Camera::default_for(64, 64)
    };
    s.samples_per_pixel = 4096;
    s.camera.aperture = 0.25;
    s.camera.focus_distance = 4.0;
    let (mass_sharp, var_sharp) = spread(&s, &scene);
    assert!(
        var_sharp.sqrt() < 0.5,
        "in focus: spread {}",
        var_sharp.sqrt()
    );
    s.camera.focus_distance = 2.0;
    let (mass_blur, var_blur) = spread(&s, &scene);
    let grown = var_blur - var_sharp;
    assert!(
        (grown - 4.0).abs() < 0.25,
        "variance grew by {grown} px², expected 4"
    );
    for mass in [mass_sharp, mass_blur] {
        assert!((mass / 0.64 - 1.0).abs() < 0.08, "{mass} px² vs 0.64");
    }
}

/// A coloured light scales each channel of the light by its colour: with colour (1, 0.5, 0) the
/// `direct` stage (ρ·D, no N) has the white light's red channel, half its green and no blue.
#[test]
fn a_coloured_light_scales_each_channel() {
    let scene = cornell_box();
    let white = render(&scene, &settings(Stage::Direct, 32));
    let mut s = settings(Stage::Direct, 32);
    s.light.colour = Vec3::new(1.0, 0.5, 0.0);
    let orange = render(&scene, &s);
    for (w, o) in white.pixels.iter().zip(&orange.pixels) {
        assert_eq!(o.x, w.x);
        assert!((o.y - 0.5 * w.y).abs() <= 1e-6 * w.y, "{o} vs {w}");
        assert_eq!(o.z, 0.0);
    }
}

/// The mean display values (the lab's clamp to [0, 1], Rec. 709 luminance) of the tall
/// block's front face, the face turned most toward the camera: of its upper half, its lower half
/// and the whole, over the pixels whose centre and four neighbours' centres see it (no edge
/// pixel, which anti-aliasing mixes with what lies beside).
fn front_face_means(scene: &Scene, s: &RenderSettings) -> [f32; 3] {
    let side = s.camera.width;
    let triangle = |x: u32, y: u32| {
        let hit = scene.closest_intersection(&s.camera.pixel_ray(x, y), f32::INFINITY)?;
        (scene.material_of(hit.triangle_index).name == TALL_BLOCK).then_some(hit.triangle_index)
    };
    let seen: Vec<Option<usize>> = (0..side * side)
        .map(|i| triangle(i % side, i / side))
        .collect();
    let facing = |t: usize| scene.triangles[t].normal.normalize().z.abs();
    let most = seen
        .iter()
        .flatten()
        .map(|&t| facing(t))
        .fold(0.0, f32::max);
    let on_front =
        |x: u32, y: u32| seen[(y * side + x) as usize].is_some_and(|t| facing(t) > most - 1e-3);
    let image = render(scene, s);
    let mut face = Vec::new();
    for y in 1..side - 1 {
        for x in 1..side - 1 {
            if [(x, y), (x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
                .iter()
                .all(|&(x, y)| on_front(x, y))
            {
                let v = image.get(x, y).clamp(Vec3::ZERO, Vec3::ONE);
                face.push((y, v.dot(Vec3::new(0.2126, 0.7152, 0.0722))));
            }
        }
    }
    assert!(
        face.len() > 100,
        "only {} pixels on the front face",
        face.len()
    );
    let (top, bottom) = (face[0].0, face[face.len() - 1].0);
    let mean = |rows: std::ops::RangeInclusive<u32>| {
        let values: Vec<f32> = face
            .iter()
            .filter(|(y, _)| rows.contains(y))
            .map(|&(_, v)| v)
            .collect();
        values.iter().sum::<f32>() / values.len() as f32
    };
    let middle = (top + bottom) / 2;
    [
        mean(top..=middle),
        mean(middle + 1..=bottom),
        mean(top..=bottom),
    ]
}

/// The Materials row's note on the tall block's front face (`front_face_note`) says what the
/// render shows: where it says black or dark above what the face shows of the floor and the
/// short block, the face's upper half has a mean display value below 0.1 and its lower half
/// more; where it says bright, the whole face's mean is above 0.2 — for the mirror presets in
/// both kinds of stage and the rough metal in the path stage over its roughness, either side
/// of α 0.05–0.1, where the face brightens gradually from one to the other. (The rough metal's
/// note said "dark" when its default α = 0.2 renders a bright silver face.)
#[test]
fn the_front_face_note_says_what_the_render_shows() {
    let scene = cornell_box();
    let mut cases = Vec::new();
    for stage in [Stage::Lab, Stage::Path] {
        for preset in [MaterialPreset::Mirror, MaterialPreset::Both] {
            cases.push((stage, preset, DEFAULT_ROUGHNESS));
        }
    }
    for alpha in [0.01, 0.03, 0.1, DEFAULT_ROUGHNESS, 0.5, 1.0] {
        cases.push((Stage::Path, MaterialPreset::Rough, alpha));
    }
    for (stage, preset, alpha) in cases {
        let path = stage == Stage::Path;
        let note = preset.front_face_note(path, alpha).unwrap();
        let mut s = settings(stage, 96);
        s.material_preset = preset;
        s.roughness = alpha;
        s.samples_per_pixel = if path { 32 } else { 1 };
        let [upper, lower, whole] = front_face_means(&scene, &s);
        let case = format!(
            "{stage} {preset} α {alpha}: means {upper:.3} above, {lower:.3} below, {whole:.3} \
             in all; note {note:?}"
        );
        if note.contains("front face is black above") || note.contains("front face is dark above") {
            assert!(upper < 0.1 && lower > upper, "{case}");
        } else {
            assert!(note.contains("front face is bright"), "{case}");
            assert!(whole > 0.2, "{case}");
        }
        if preset == MaterialPreset::Rough {
            // The roughness the note names is the one that chooses it.
            assert!(
                note.contains(&ROUGH_FRONT_BRIGHT_FROM.to_string()),
                "{case}"
            );
        }
    }
    // No note where the face is not a reflector's, or the lab's stages shade the metal by its
    // highlight alone.
    for preset in [MaterialPreset::None, MaterialPreset::Glass] {
        assert_eq!(preset.front_face_note(true, DEFAULT_ROUGHNESS), None);
    }
    assert_eq!(
        MaterialPreset::Rough.front_face_note(false, DEFAULT_ROUGHNESS),
        None
    );
}
