//! Scene files and screenshots reopen to the same image, on the command line: save → load →
//! same settings → same pixels. And what a bad file gets: an error naming the field and its
//! line, nothing written.

mod common;

use std::path::Path;

use common::{files_in, raylab, stderr};
use raylab_core::RenderSettings;
use raylab_core::shapes::scene::SceneChoice;

fn render(args: &[&str]) -> std::process::Output {
    let out = raylab(&[&["render"], args].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    out
}

fn pixels(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn a_saved_scene_file_renders_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, scene) = (
        dir.path().join("a.png"),
        dir.path().join("b.png"),
        dir.path().join("setup.toml"),
    );
    let options = [
        "--width",
        "48",
        "--height",
        "40",
        "--focal",
        "40",
        "--camera",
        "0.1,-0.1,-2.5",
        "--yaw",
        "4",
        "--light",
        "0.2,-0.6,-0.5",
        "--light-power",
        "20",
        "--indirect",
        "0.25",
        "--samples",
        "3",
        "--seed",
        "9",
        "--material-preset",
        "mirror",
    ];
    let a_out = a.to_str().unwrap();
    let s = scene.to_str().unwrap();
    render(&[&["--out", a_out, "--save-scene", s], &options[..]].concat());
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("version = 2") && text.contains("material_preset = \"mirror\""));
    render(&["--scene-file", s, "--out", b.to_str().unwrap()]);
    // The same settings, so the same bytes: pixels and the settings the PNG carries.
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn a_screenshot_png_reopens_to_its_render() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    render(&[
        "--out",
        a.to_str().unwrap(),
        "--width",
        "40",
        "--height",
        "30",
        "--stage",
        "shadows",
        "--light",
        "-0.3,-0.5,-0.6",
    ]);
    let loaded = raylab_core::files::settings_file::read_file(&a).unwrap();
    assert_eq!(loaded.settings.camera.width, 40);
    assert_eq!(loaded.settings.shading.stage, raylab_core::Stage::Shadows);
    assert!(loaded.warnings.is_empty());
    render(&[
        "--settings",
        a.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert_eq!(pixels(&a), pixels(&b));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn a_png_without_settings_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.png");
    image::RgbImage::new(2, 2).save(&plain).unwrap();
    let out = dir.path().join("out.png");
    let result = raylab(&[
        "render",
        "--settings",
        plain.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(result.status.code(), Some(1));
    let e = stderr(&result);
    assert!(
        e.contains("carries no raylab settings") && e.contains("plain.png"),
        "{e}"
    );
    assert!(!out.exists());
}

#[test]
fn every_shipped_scene_file_loads_and_is_valid() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let mut names: Vec<String> = files_in(&folder)
        .into_iter()
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "bunny.toml",
            "figure7.toml",
            "gallery.toml",
            "glass.toml",
            "mirror.toml",
            "terrain.toml"
        ]
    );
    for name in &names {
        let settings = raylab_core::files::scene_file::load(&folder.join(name))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        settings.validate().unwrap();
    }
    // Figure 7 is exactly the lab's defaults; the presets are the built-ins.
    let load = |n: &str| raylab_core::files::scene_file::load(&folder.join(n)).unwrap();
    assert_eq!(load("figure7.toml"), RenderSettings::default());
    assert_eq!(load("bunny.toml").scene, SceneChoice::Bunny);
    assert_eq!(load("terrain.toml").scene, SceneChoice::Terrain);
    assert_eq!(
        load("mirror.toml").material_preset,
        raylab_core::MaterialPreset::Mirror
    );
    assert_eq!(
        load("glass.toml").material_preset,
        raylab_core::MaterialPreset::Glass
    );
    let gallery = load("gallery.toml").scene.spec();
    assert_eq!(gallery.models.len(), 3);
    assert!(!gallery.blocks);
}

#[test]
fn figure_7_from_its_scene_file_is_the_default_render() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let f7 = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/figure7.toml");
    render(&["--out", a.to_str().unwrap()]);
    render(&[
        "--scene-file",
        f7.to_str().unwrap(),
        "--out",
        b.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn a_bad_scene_file_names_the_field_and_the_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let f7 = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/figure7.toml");
    let good = std::fs::read_to_string(f7).unwrap();
    let line = |key: &str| good.lines().position(|l| l.starts_with(key)).unwrap() + 1;
    let cases = [
        (
            good.replace("power = 14.0", "power = nan"),
            format!(
                "line {} (power = nan): invalid light power NaN",
                line("power")
            ),
        ),
        (
            good.replace("radius = 0.0", "radius = 0.0\nglow = 1"),
            format!(
                "line {} (glow = 1): unknown field `glow`",
                line("radius") + 1
            ),
        ),
        (
            good.replace("seed = 0\n", ""),
            "missing field `seed`".to_owned(),
        ),
        (
            good.replace("version = 2", "version = 7"),
            format!("line {}", line("version")),
        ),
        (
            good.replace("stage = \"lab\"", "stage = 3"),
            format!("line {} (stage = 3)", line("stage")),
        ),
    ];
    for (i, (text, expected)) in cases.iter().enumerate() {
        let file = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&file, text).unwrap();
        let out = dir.path().join(format!("out{i}.png"));
        let result = raylab(&[
            "render",
            "--scene-file",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(result.status.code(), Some(1), "case {i}");
        let e = stderr(&result);
        assert!(e.contains(expected.as_str()), "case {i}: {e}");
        assert!(e.contains(&format!("bad{i}.toml")), "names the file: {e}");
        assert_eq!(e.lines().count(), 1, "one line: {e}");
        assert!(!out.exists(), "case {i}: nothing written");
    }
}

#[test]
fn a_settings_file_with_only_a_size_means_what_width_and_height_mean() {
    // `camera.width`/`height` alone once kept a 512 px focal length (7.2°).
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("size.json");
    // With a byte-order mark and a field raylab does not know.
    std::fs::write(
        &json,
        "\u{feff}{\"camera\": {\"width\": 64, \"height\": 48}, \"lens_flare\": true}",
    )
    .unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let out = render(&[
        "--settings",
        json.to_str().unwrap(),
        "--out",
        a.to_str().unwrap(),
    ]);
    let e = stderr(&out);
    assert!(
        e.contains("warning:") && e.contains("unknown field `lens_flare` ignored"),
        "{e}"
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("64×48 (field of view 53.1°"), "{summary}");
    render(&[
        "--width",
        "64",
        "--height",
        "48",
        "--out",
        b.to_str().unwrap(),
    ]);
    assert_eq!(pixels(&a), pixels(&b));
}

#[test]
fn save_scene_is_checked_before_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    for (scene, expected) in [
        ("setup.json", "a scene file's name ends in .toml"),
        (
            "/no/such/folder/s.toml",
            "folder '/no/such/folder' does not exist",
        ),
    ] {
        let result = raylab(&[
            "render",
            "--out",
            out.to_str().unwrap(),
            "--save-scene",
            scene,
            "--width",
            "8",
            "--height",
            "8",
        ]);
        assert_eq!(result.status.code(), Some(1));
        assert!(stderr(&result).contains(expected), "{}", stderr(&result));
        assert!(!out.exists());
    }
}
