//! The pool (`--scene pool`): the lab's box with its floor under water, a dielectric of index
//! 1.33 whose surface is shaded by a normal map of fractal waves.

mod common;

use common::settings;
use glam::Vec3;
use raylab_core::MaterialKind;
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::shapes::scene::water::{WaterSpec, water_triangles};
use raylab_core::transport::render::render;
use raylab_core::{RenderSettings, Stage};

fn pool(stage: Stage, waves: f32, time: f32) -> RenderSettings {
    let mut s = settings(stage, 64);
    let mut spec = SceneChoice::Pool.spec();
    let water = spec.water.as_mut().unwrap();
    water.waves = waves;
    water.time = time;
    s.scene = SceneChoice::from_spec(spec);
    s
}

/// The pool is the box, its blocks and one water surface of two triangles, clear glass of
/// index 1.33 with the waves' relief.
#[test]
fn the_pool_is_the_box_and_a_water_surface() {
    let scene = SceneChoice::Pool.load().unwrap();
    let box_triangles = SceneChoice::Cornell.load().unwrap().triangles.len();
    assert_eq!(scene.triangles.len(), box_triangles + 2);
    let water = scene.materials.last().unwrap();
    assert_eq!(water.name, "water");
    assert_eq!(
        water.kind,
        MaterialKind::Glass {
            ior: 1.33,
            tint: Vec3::ONE
        }
    );
    assert!(water.relief.is_some());
    assert_eq!(
        scene.triangles[box_triangles..],
        water_triangles(&WaterSpec::default(), (scene.materials.len() - 1) as u32)
    );
}

/// Still water (amplitude 0) is the flat surface: the same image as water with no relief at
/// all, up to float rounding, in the lab stage (Whitted reflection and refraction) and the
/// path stage. Both stages read the waves, so the equality is the flat limit's: water of
/// amplitude 0.02 changes more than a hundred of the pixels that see the water.
#[test]
fn still_water_is_a_flat_surface() {
    for stage in [Stage::Lab, Stage::Path] {
        let s = pool(stage, 0.0, 2.0);
        let still = s.scene.load().unwrap();
        let mut flat = still.clone();
        flat.materials.last_mut().unwrap().relief = None;
        let (a, b) = (render(&still, &s), render(&flat, &s));
        let worst = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| (*p - *q).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "{stage}: {worst}");
        let rippled = pool(stage, 0.02, 2.0);
        let c = render(&rippled.scene.load().unwrap(), &rippled);
        let changed = water_pixels(&s)
            .into_iter()
            .filter(|&i| c.pixels[i] != b.pixels[i])
            .count();
        assert!(changed > 100, "{stage}: the waves changed {changed} pixels");
    }
}

/// The pixels whose centre's camera ray meets the water first.
fn water_pixels(s: &RenderSettings) -> Vec<usize> {
    let scene = s.scene.load().unwrap();
    let (w, h) = (s.camera.width, s.camera.height);
    (0..w * h)
        .filter(|&i| {
            scene
                .closest_intersection(&s.camera.pixel_ray(i % w, i / w), f32::INFINITY)
                .is_some_and(|hit| scene.material_of(hit.triangle_index).name == "water")
        })
        .map(|i| i as usize)
        .collect()
}

/// The path stage's reflections and refractions bend with the waves (`raylab render --scene
/// pool --stage path --samples 4 --water-waves 0` against `0.05`): with the same seeds, at
/// least three quarters of the pixels whose centre sees the water change (a path stage that
/// ignored the waves would change none). The numbers of the bending are the path
/// tracer's own tests' (`integrator::path`: Snell's law into flat water, the mirror law and
/// Snell's law about a known tilted normal).
#[test]
fn the_path_stage_bends_with_the_waves() {
    let (mut still, mut waves) = (pool(Stage::Path, 0.0, 0.0), pool(Stage::Path, 0.05, 0.0));
    still.samples_per_pixel = 4;
    waves.samples_per_pixel = 4;
    let a = render(&still.scene.load().unwrap(), &still);
    let b = render(&waves.scene.load().unwrap(), &waves);
    let water = water_pixels(&still);
    assert!(water.len() > 200, "{} pixels see the water", water.len());
    let changed = water
        .iter()
        .filter(|&&i| a.pixels[i] != b.pixels[i])
        .count();
    assert!(
        changed * 4 >= water.len() * 3,
        "{changed} of the {} pixels that see the water changed",
        water.len()
    );
}

/// Waves change the image where the camera sees the water, and nowhere above it; they move
/// with time.
#[test]
fn waves_ripple_the_water_and_move_with_time() {
    let (still, rippled, later) = (
        pool(Stage::Lab, 0.0, 0.0),
        pool(Stage::Lab, 0.02, 0.0),
        pool(Stage::Lab, 0.02, 5.0),
    );
    let image = |s: &RenderSettings| render(&s.scene.load().unwrap(), s);
    let (a, b, c) = (image(&still), image(&rippled), image(&later));
    let w = a.width as usize;
    let changed = |x: &raylab_core::Image, y: &raylab_core::Image, rows: std::ops::Range<usize>| {
        rows.flat_map(|r| (0..w).map(move |c| r * w + c))
            .filter(|&i| x.pixels[i] != y.pixels[i])
            .count()
    };
    // The top third of the image sees the ceiling and walls: no water.
    assert_eq!(changed(&a, &b, 0..20), 0);
    let bottom = 48..64;
    assert!(
        changed(&a, &b, bottom.clone()) > 100,
        "{}",
        changed(&a, &b, bottom)
    );
    assert!(changed(&b, &c, 48..64) > 100);
}

/// The water refracts: below its surface, what the camera sees of the blocks and floor is not
/// what it sees without water (the blocks' edges shift), while the ceiling stays.
#[test]
fn the_water_refracts_what_lies_under_it() {
    let with = pool(Stage::Lab, 0.0, 0.0);
    let mut without = with.clone();
    without.scene = SceneChoice::Cornell;
    let a = render(&with.scene.load().unwrap(), &with);
    let b = render(&without.scene.load().unwrap(), &without);
    assert_eq!(a.pixels[..64 * 20], b.pixels[..64 * 20]);
    let differ = a.pixels[64 * 48..]
        .iter()
        .zip(&b.pixels[64 * 48..])
        .filter(|(p, q)| p != q)
        .count();
    assert!(differ > 64 * 8, "{differ}");
}

/// A scene file carries the water, and bad water is refused by name.
#[test]
fn scene_files_carry_the_water() {
    let s = pool(Stage::Path, 0.02, 1.5);
    let dir = tempfile::tempdir().unwrap();
    let text = raylab_core::files::scene_file::to_text(&s, dir.path()).unwrap();
    assert!(text.contains("[scene.water]"), "{text}");
    let back = raylab_core::files::scene_file::parse(&text, dir.path()).unwrap();
    assert_eq!(back, s);
    let bad = text.replace("waves = 0.02", "waves = 5.0");
    let e = raylab_core::files::scene_file::parse(&bad, dir.path()).unwrap_err();
    assert!(e.contains("scene.water.waves"), "{e}");
}
