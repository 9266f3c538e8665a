//! The `raylab render` command, run as a user runs it.

mod common;

use std::path::Path;

use common::{files_in, raylab, settings, stderr};
use raylab_core::Stage;
use raylab_core::shapes::scene::cornell_box;

#[test]
fn renders_a_png_and_an_exr_of_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("fig7.png");
    let exr = dir.path().join("fig7.exr");
    for (path, w, h) in [(&png, "64", "48"), (&exr, "40", "30")] {
        let out = raylab(&[
            "render",
            "--out",
            path.to_str().unwrap(),
            "--width",
            w,
            "--height",
            h,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains(" ms "), "prints the render time: {stdout}");
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
    assert_eq!(img.color(), image::ColorType::Rgb8);
    let img = image::open(&exr).unwrap();
    assert_eq!((img.width(), img.height()), (40, 30));
    // Linear floats: the centre is the white back wall, lit and grey (r = g = b).
    let rgb = img.to_rgb32f();
    let c = rgb.get_pixel(20, 12);
    assert!(c[0] > 0.3 && (c[0] - c[2]).abs() < 1e-6, "{c:?}");
    // No temporary files are left behind.
    let names = files_in(dir.path());
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn the_png_is_the_labs_display_of_the_exr() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("a.png");
    let exr = dir.path().join("a.exr");
    for path in [&png, &exr] {
        let out = raylab(&[
            "render",
            "--out",
            path.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
            "--light-power",
            "60",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let png = image::open(&png).unwrap().to_rgb8();
    let exr = image::open(&exr).unwrap().to_rgb32f();
    let mut above_one = 0;
    for (p, e) in png.pixels().zip(exr.pixels()) {
        for c in 0..3 {
            let want = (e[c].clamp(0.0, 1.0) * 255.0).round() as u8;
            assert_eq!(p[c], want);
            above_one += usize::from(e[c] > 1.0);
        }
    }
    assert!(
        above_one > 0,
        "a 60 W light overexposes some pixels, kept unclamped in the EXR"
    );
}

/// The library's render of `settings` on the scene they name, as an EXR holds it: R, G, B
/// floats, rows top to bottom.
fn library_exr(settings: &raylab_core::RenderSettings) -> Vec<f32> {
    let scene = settings.scene.load().unwrap();
    raylab_core::transport::render::render(&scene, settings)
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .collect()
}

fn assert_refused(args: &[&str], names: &str, out_path: &Path) {
    let out = raylab(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = stderr(&out);
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "one line for {args:?}: {err}"
    );
    assert!(
        err.contains(names),
        "{args:?}: '{err}' should name '{names}'"
    );
    assert!(!out_path.exists(), "{args:?} left a file");
}

#[test]
fn bad_arguments_exit_non_zero_with_one_line_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = out.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["render", "--out", o, "--width", "0"], "--width"),
        (&["render", "--out", o, "--height", "16385"], "--height"),
        (&["render", "--out", o, "--focal", "-3"], "--focal"),
        (&["render", "--out", o, "--focal", "0"], "--focal"),
        (&["render", "--out", o, "--yaw", "NaN"], "--yaw"),
        (&["render", "--out", o, "--pitch", "inf"], "--pitch"),
        (&["render", "--out", o, "--pitch", "1e39"], "--pitch"),
        (&["render", "--out", o, "--camera", "0,inf,0"], "--camera"),
        (&["render", "--out", o, "--light", "a,b,c"], "--light"),
        (&["render", "--out", o, "--stage", "phong"], "phong"),
        (&["render", "--out", o, "--shadows", "yes"], "--shadows"),
        (&["render", "--out", o, "--threads", "0"], "--threads"),
    ];
    for (args, names) in cases {
        assert_refused(args, names, &out);
    }
    let jpg = dir.path().join("x.jpg");
    assert_refused(&["render", "--out", jpg.to_str().unwrap()], "x.jpg", &jpg);
    let missing = dir.path().join("no/such/folder/x.png");
    assert_refused(
        &["render", "--out", missing.to_str().unwrap()],
        "does not exist",
        &missing,
    );
}

#[test]
fn an_unwritable_folder_is_reported_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // A path whose "folder" is a file: no user, root included, can create anything in it.
    let file = dir.path().join("file");
    std::fs::write(&file, b"x").unwrap();
    let out = file.join("x.png");
    assert_refused(
        &[
            "render",
            "--out",
            out.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
        ],
        "x.png",
        &out,
    );
    // Writing onto a directory's name fails at the rename and leaves no temporary file.
    let target = dir.path().join("taken.png");
    std::fs::create_dir(&target).unwrap();
    let r = raylab(&[
        "render",
        "--out",
        target.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
    ]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("taken.png"), "{}", stderr(&r));
    let names = files_in(dir.path());
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn settings_from_a_json_file_reproduce_the_render() {
    let dir = tempfile::tempdir().unwrap();
    let direct = dir.path().join("direct.exr");
    let args = [
        "--width",
        "40",
        "--height",
        "30",
        "--stage",
        "shadows",
        "--yaw",
        "12",
        "--light",
        "0.2,-0.4,-0.5",
        "--samples",
        "3",
        "--seed",
        "9",
    ];
    let mut argv = vec!["render", "--out", direct.to_str().unwrap()];
    argv.extend_from_slice(&args);
    assert!(raylab(&argv).status.success());

    // The same settings as a workbench screenshot's sidecar would hold them.
    let json = dir.path().join("shot.json");
    std::fs::write(
        &json,
        r#"{"image": "shot.png", "sample_target": 16, "settings": {
            "camera": {"position": [0, 0, -3.001], "yaw": 0.20943952, "focal_length": 40,
                       "width": 40, "height": 30},
            "light": {"position": [0.2, -0.4, -0.5]},
            "shading": {"stage": "shadows", "shadows": true, "indirect": false},
            "samples_per_pixel": 3, "seed": 9}}"#,
    )
    .unwrap();
    let from_json = dir.path().join("from-json.exr");
    let out = raylab(&[
        "render",
        "--out",
        from_json.to_str().unwrap(),
        "--settings",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let a = image::open(&direct).unwrap().to_rgb32f();
    let b = image::open(&from_json).unwrap().to_rgb32f();
    assert_eq!(a.as_raw(), b.as_raw());

    // --settings takes everything from the file: other settings are refused.
    let r = raylab(&[
        "render",
        "--out",
        "x.png",
        "--settings",
        json.to_str().unwrap(),
        "--width",
        "8",
    ]);
    assert!(!r.status.success());
    // A malformed file is named.
    std::fs::write(&json, "{ not json").unwrap();
    let r = raylab(&[
        "render",
        "--out",
        from_json.to_str().unwrap(),
        "--settings",
        json.to_str().unwrap(),
    ]);
    assert!(!r.status.success());
    assert!(stderr(&r).contains("shot.json"), "{}", stderr(&r));
}

/// `--stage path --bounces 0` is the `shadows` stage (figure 6), bit for bit; with bounces the
/// image is brighter (real indirect light), the same for the same seed, and a preset changes it.
#[test]
fn the_path_stage_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let path = dir.path().join(name);
        let mut args = vec![
            "render",
            "--out",
            path.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "32",
        ];
        args.extend_from_slice(extra);
        let out = raylab(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        image::open(&path).unwrap().to_rgb32f()
    };
    let shadows = render("shadows.exr", &["--stage", "shadows"]);
    let direct_only = render("p0.exr", &["--stage", "path", "--bounces", "0"]);
    assert_eq!(shadows.as_raw(), direct_only.as_raw());
    let path = ["--stage", "path", "--samples", "4", "--seed", "3"];
    let a = render("a.exr", &path);
    let b = render("b.exr", &path);
    assert_eq!(a.as_raw(), b.as_raw(), "same seed, same image");
    let sum = |img: &image::Rgb32FImage| img.as_raw().iter().map(|&v| f64::from(v)).sum::<f64>();
    assert!(sum(&a) > 1.2 * sum(&shadows), "indirect light adds");
    let both = render(
        "both.exr",
        &[&path[..], &["--material-preset", "both"]].concat(),
    );
    // The library's render of the same settings, float for float: the flags reach it.
    let mut settings = settings(Stage::Path, 32);
    settings.samples_per_pixel = 4;
    settings.seed = 3;
    assert_eq!(a.as_raw(), &library_exr(&settings));
    settings.material_preset = raylab_core::MaterialPreset::Both;
    assert_eq!(both.as_raw(), &library_exr(&settings));
    for bad in [
        &["--material-preset", "gold"][..],
        &["--bounces", "many"],
        &["--stage", "photon"],
    ] {
        let mut args = vec!["render", "--out", "x.png"];
        args.extend_from_slice(bad);
        let out = raylab(&args);
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
        let err = stderr(&out);
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(err.contains(bad[1]), "{err}");
    }
}

/// The lab's extensions on the command line: `--display` and `--exposure` change the PNG as
/// the display transform says and leave the EXR linear; the light, lens, texture and shading
/// flags reach the render (each changes the image), and bad values are refused.
#[test]
fn the_extensions_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| -> std::path::PathBuf {
        let path = dir.path().join(name);
        let mut args = vec!["render", "--out", path.to_str().unwrap(), "--width", "48"];
        args.extend_from_slice(&["--height", "48"]);
        args.extend_from_slice(extra);
        let out = raylab(&args);
        assert!(out.status.success(), "{extra:?}: {}", stderr(&out));
        path
    };
    let exr = |p: &Path| image::open(p).unwrap().to_rgb32f().into_raw();
    let png = |p: &Path| image::open(p).unwrap().to_rgb8().into_raw();

    // Exposure +1 doubles each linear value before the lab's clamp: 255·min(2x, 1), rounded.
    let linear = exr(&run("lab.exr", &[]));
    let brighter = png(&run("plus1.png", &["--exposure", "1"]));
    for (x, p) in linear.iter().zip(&brighter) {
        assert_eq!(*p, ((2.0 * x).clamp(0.0, 1.0) * 255.0).round() as u8);
    }
    // sRGB lifts the mid-tones; the EXR stays linear whatever the display.
    let lab = png(&run("lab.png", &[]));
    let srgb = png(&run("srgb.png", &["--display", "srgb"]));
    assert!(srgb.iter().zip(&lab).all(|(s, l)| s >= l));
    assert!(srgb.iter().zip(&lab).filter(|(s, l)| s > l).count() > 1000);
    assert_eq!(
        exr(&run(
            "srgb.exr",
            &["--display", "filmic", "--exposure", "3"]
        )),
        linear
    );

    // Each flag reaches the render: the EXR is the library's render of the settings the flag
    // describes, float for float (and not the default image, so the comparison can fail).
    let lab = settings(Stage::Lab, 48);
    assert_eq!(linear, library_exr(&lab));
    let with = |change: &dyn Fn(&mut raylab_core::RenderSettings)| {
        let mut s = lab.clone();
        change(&mut s);
        s
    };
    let cases: Vec<(&str, Vec<&str>, raylab_core::RenderSettings)> = vec![
        (
            "colour.exr",
            vec!["--light-colour", "1,0.5,0.25"],
            with(&|s| s.light.colour = glam::Vec3::new(1.0, 0.5, 0.25)),
        ),
        (
            "radius.exr",
            vec!["--light-radius", "0.2", "--samples", "4"],
            with(&|s| {
                s.light.kind = raylab_core::shading::light::LightKind::Sphere { radius: 0.2 };
                s.samples_per_pixel = 4;
            }),
        ),
        (
            "lens.exr",
            vec![
                "--aperture",
                "0.1",
                "--focus-distance",
                "2",
                "--samples",
                "4",
            ],
            with(&|s| {
                s.camera.aperture = 0.1;
                s.camera.focus_distance = 2.0;
                s.samples_per_pixel = 4;
            }),
        ),
        (
            "texture.exr",
            vec!["--texture-preset", "checker-floor"],
            with(&|s| {
                s.texture_preset = raylab_core::shading::material::TexturePreset::CheckerFloor
            }),
        ),
        (
            "bunny.exr",
            vec!["--scene", "bunny"],
            with(&|s| s.scene = raylab_core::shapes::scene::SceneChoice::Bunny),
        ),
        // Smooth shading changes a model, never the box.
        (
            "flat.exr",
            vec!["--scene", "bunny", "--smooth", "off"],
            with(&|s| {
                s.scene = raylab_core::shapes::scene::SceneChoice::Bunny;
                s.shading.smooth = false;
            }),
        ),
    ];
    let mut images = vec![linear.clone()];
    for (name, extra, settings) in &cases {
        let image = exr(&run(name, extra));
        assert_eq!(image, library_exr(settings), "{name}");
        assert!(!images.contains(&image), "{name} is another case's image");
        images.push(image);
    }
    assert_eq!(exr(&run("box-flat.exr", &["--smooth", "off"])), linear);

    let out_path = dir.path().join("refused.png");
    for bad in [
        &["--light-colour", "1,-1,0"][..],
        &["--light-radius", "-0.1"][..],
        &["--aperture", "nan"][..],
        &["--focus-distance", "0"][..],
        &["--exposure", "50"][..],
        &["--display", "gamma"][..],
        &["--texture-preset", "marble"][..],
        &["--smooth", "yes"][..],
    ] {
        let mut args = vec!["render", "--out", out_path.to_str().unwrap()];
        args.extend_from_slice(bad);
        let out = raylab(&args);
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
        assert_eq!(stderr(&out).lines().count(), 1, "{bad:?}: {}", stderr(&out));
        assert!(!out_path.exists());
    }
}

/// A closed or full stdout after the image is written is not a panic. A
/// reader that went away (`| true`) is no failure at all; a full device (`> /dev/full`) is
/// reported in one line, the image kept.
#[test]
fn a_closed_or_full_stdout_does_not_panic() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("p.png");
    let mut child = Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--width", "64", "--height", "64", "--out"])
        .arg(&png)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the reading end before the render is done: its summary meets a broken pipe.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).is_empty(), "{}", stderr(&out));
    assert!(png.exists());

    if let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") {
        let png = dir.path().join("q.png");
        let out = Command::new(env!("CARGO_BIN_EXE_raylab"))
            .args(["render", "--width", "64", "--height", "64", "--out"])
            .arg(&png)
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        let e = stderr(&out);
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(e.contains("could not print the summary"), "{e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(png.exists());
    }
}

/// A destination that cannot be written is refused before the render, a folder named as
/// `--out` likewise, the OS's reason is said once, and no probe or temporary file is left
/// behind. "Before": the request also names a model that does not exist, which loading (the
/// first step of the render) would have refused with its own message.
#[test]
fn an_unwritable_destination_is_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("looks-like.png");
    std::fs::create_dir(&folder).unwrap();
    let missing = dir.path().join("missing.obj");
    let out = raylab(&[
        "render",
        "--out",
        folder.to_str().unwrap(),
        "--obj",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let e = stderr(&out);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains("it is a folder"), "{e}");
    assert!(!e.contains("missing.obj"), "it loaded the scene first: {e}");
    assert_eq!(files_in(dir.path()).len(), 1, "{:?}", files_in(dir.path()));

    // /sys refuses new files even to root: the reason once, not twice.
    if Path::new("/sys").is_dir() {
        let out = raylab(&[
            "render",
            "--out",
            "/sys/raylab-test.png",
            "--obj",
            missing.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(1));
        let e = stderr(&out);
        assert_eq!(e.lines().count(), 1, "{e}");
        assert_eq!(e.matches("os error").count(), 1, "{e}");
        assert!(!e.contains("missing.obj"), "it loaded the scene first: {e}");
    }
}

/// A black image the camera is to blame for says so on stderr, and a focal
/// length so long that every ray would be lost is refused.
#[test]
fn a_camera_that_sees_nothing_is_noted_and_absurd_focal_lengths_refused() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("black.png");
    let out = raylab(&[
        "render",
        "--out",
        png.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--camera",
        "0,0,2",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("note: the camera sees nothing: it is outside the box"));
    let out = raylab(&["render", "--out", png.to_str().unwrap(), "--focal", "2e19"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("focal length"), "{}", stderr(&out));
}

#[test]
fn every_kernel_set_forced_with_isa_gives_the_same_image() {
    // `--isa` forces the kernels (the default measures which is fastest here); the bunny's
    // structure traces packets with AVX-512 and single rays otherwise, the same hits either
    // way, so the same pixels. A set this CPU lacks is refused with one line.
    let dir = tempfile::tempdir().unwrap();
    let available = raylab_core::shapes::accel::Isa::available();
    let mut images = Vec::new();
    for isa in ["best", "scalar", "avx2", "avx512"] {
        let path = dir.path().join(format!("{isa}.png"));
        let out = raylab(&[
            "render",
            "--scene",
            "bunny",
            "--isa",
            isa,
            "--width",
            "48",
            "--height",
            "40",
            "--out",
            path.to_str().unwrap(),
        ]);
        let runs = isa == "best" || available.iter().any(|a| a.name() == isa);
        if !runs {
            assert!(!out.status.success());
            assert!(
                stderr(&out).contains("not supported by this CPU"),
                "{}",
                stderr(&out)
            );
            continue;
        }
        assert!(out.status.success(), "{isa}: {}", stderr(&out));
        images.push((isa, image::open(&path).unwrap().to_rgb8()));
    }
    assert!(images.len() >= 2);
    for (isa, image) in &images[1..] {
        assert!(
            image.as_raw() == images[0].1.as_raw(),
            "{isa} differs from best"
        );
    }
    let out = raylab(&["render", "--isa", "sse9", "--out", "x.png"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("kernels 'sse9'"), "{}", stderr(&out));
}

// ---- The debug views from the command line. ----

#[test]
fn render_view_writes_the_view_and_prints_its_legend() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("depth.png");
    let run = raylab(&[
        "render",
        "--view",
        "depth",
        "--width",
        "32",
        "--height",
        "24",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stdout = String::from_utf8_lossy(&run.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines[0].starts_with("rendered cornell"), "{stdout}");
    assert!(
        stdout.contains("Depth") && stdout.contains("(white)"),
        "{stdout}"
    );
    // The file is the view: grey levels, white somewhere, not the lab's colours.
    let image = image::open(&out).unwrap().to_rgb8();
    assert!(image.pixels().all(|p| p[0] == p[1] && p[1] == p[2]));
    assert!(image.pixels().any(|p| p[0] == 255));

    let noisy = dir.path().join("variance.png");
    let once = raylab(&[
        "render",
        "--view",
        "variance",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        noisy.to_str().unwrap(),
    ]);
    assert!(!once.status.success());
    assert!(
        stderr(&once).contains("2 or more samples"),
        "{}",
        stderr(&once)
    );
    assert!(!noisy.exists());
    let twice = raylab(&[
        "render",
        "--view",
        "variance",
        "--samples",
        "2",
        "--stage",
        "path",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        noisy.to_str().unwrap(),
    ]);
    assert!(twice.status.success(), "{}", stderr(&twice));
    assert!(String::from_utf8_lossy(&twice.stdout).contains("n = 2 samples"));

    let bad = raylab(&["render", "--view", "bvh", "--out", out.to_str().unwrap()]);
    assert!(!bad.status.success());
    assert!(stderr(&bad).contains("bvh-cost"), "{}", stderr(&bad));
}

// ---- The pixel inspector from the command line. ----

/// `raylab inspect --pixel X,Y --json` prints one JSON object whose `t` is the closest hit of
/// the pixel's centre ray; the text names the lab's equations; bad pixels are one-line errors.
#[test]
fn the_inspect_command() {
    let size = ["--width", "40", "--height", "30"];
    let run = |extra: &[&str]| {
        let mut args = vec!["inspect"];
        args.extend_from_slice(&size);
        args.extend_from_slice(extra);
        raylab(&args)
    };
    let out = run(&["--pixel", "12,25", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.trim_end().lines().count(), 1, "one JSON object");
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let s = settings(Stage::Lab, 40).camera.with_resolution(40, 30);
    let hit = cornell_box()
        .closest_intersection(&s.pixel_ray(12, 25), f32::INFINITY)
        .unwrap();
    assert_eq!(json["t"].as_f64().unwrap() as f32, hit.distance);
    assert_eq!(json["triangle"].as_u64(), Some(hit.triangle_index as u64));
    assert_eq!(json["pixel"], serde_json::json!([12, 25]));
    assert_eq!(json["position"].as_array().unwrap().len(), 3);

    let text = run(&["--pixel", "12,25", "--stage", "direct"]);
    assert!(text.status.success(), "{}", stderr(&text));
    let text = String::from_utf8(text.stdout).unwrap();
    assert!(text.contains("eq. 27") && text.contains("eq. 28"), "{text}");

    // The same options as render: a settings file, a preset.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s.json");
    std::fs::write(
        &file,
        r#"{"camera": {"width": 40, "height": 30, "focal_length": 40},
            "shading": {"stage": "incoming", "shadows": false, "indirect": false}}"#,
    )
    .unwrap();
    let from_file = raylab(&[
        "inspect",
        "--settings",
        file.to_str().unwrap(),
        "--pixel",
        "12,25",
        "--json",
    ]);
    assert!(from_file.status.success(), "{}", stderr(&from_file));
    let from_file: serde_json::Value = serde_json::from_slice(&from_file.stdout).unwrap();
    assert_eq!(from_file["stage"], "incoming");
    assert_eq!(from_file["R"], from_file["D"]);

    for (bad, names) in [
        (&["--pixel", "40,0"][..], "40×30"),
        (&["--pixel", "0,30"], "--pixel 0,30"),
        (&["--pixel", "1,2,3"], "1,2,3"),
        (&["--pixel", "-1,2"], "-1,2"),
        (&["--pixel", "3,4", "--stage", "phong"], "phong"),
        (&[], "--pixel"),
    ] {
        let out = run(bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", stderr(&out));
        let err = stderr(&out);
        assert_eq!(err.trim_end().lines().count(), 1, "{bad:?}: {err}");
        assert!(err.contains(names), "{bad:?}: {err}");
        assert!(out.stdout.is_empty());
    }
}

// ---- Checking a student's image. ----

/// `raylab check IMAGE` on what a student's tracer would write: the exact figure (as
/// `raylab render` writes it) is `none`; the figure drawn upside down and saved as SDL does
/// (BMP) is `upside-down`, in text and in JSON, candidates best first; `--diff-out` writes
/// |image − figure| amplified; what cannot be checked is one line naming why.
#[test]
fn the_check_command() {
    use raylab_core::teaching::check::{self, Mistake, Rgb8};
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    // A non-square image and a turned camera: the figure follows the image's size and the
    // options.
    let exact = path("exact.png");
    let render = raylab(&[
        "render", "--stage", "direct", "--width", "48", "--height", "36", "--yaw", "10", "--out",
        &exact,
    ]);
    assert!(render.status.success(), "{}", stderr(&render));
    let out = raylab(&["check", &exact, "--stage", "direct", "--yaw", "10"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("match: 100.0 %"), "{text}");
    assert!(text.contains("verdict: none"), "{text}");
    assert!(
        text.contains("figure 5") && text.contains("48×36"),
        "{text}"
    );

    // The figure upside down, as a BMP.
    let mut s = settings(Stage::Direct, 48);
    s.camera = s.camera.with_resolution(48, 36);
    s.camera.yaw = raylab_core::base::camera::radians(10.0);
    let flipped = &check::mistakes::looks(&cornell_box(), &s, Mistake::UpsideDown)[0];
    let bmp = path("flipped.bmp");
    image::RgbImage::from_raw(48, 36, flipped.data.clone())
        .unwrap()
        .save(&bmp)
        .unwrap();
    let diff = path("diff.png");
    let out = raylab(&[
        "check",
        &bmp,
        "--stage",
        "direct",
        "--yaw",
        "10",
        "--json",
        "--diff-out",
        &diff,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["stage"], "direct");
    assert_eq!(json["best"]["mistake"], "upside-down");
    assert_eq!(json["best"]["explains"], 1.0);
    assert!(
        json["best"]["equation"]
            .as_str()
            .unwrap()
            .contains("equation 24")
    );
    assert!(!json["best"]["fix"].as_str().unwrap().is_empty());
    let share = json["match"].as_f64().unwrap();
    assert!(share < 0.5, "{share}");
    let candidates = json["candidates"].as_array().unwrap();
    assert_eq!(candidates[0]["mistake"], "upside-down");
    let explains: Vec<f64> = candidates
        .iter()
        .map(|c| c["explains"].as_f64().unwrap())
        .collect();
    assert!(explains.windows(2).all(|w| w[0] >= w[1]), "{explains:?}");
    // yaw-sign is offered: the camera is turned.
    assert!(candidates.iter().any(|c| c["mistake"] == "yaw-sign"));
    // The difference picture is |flipped − figure| × 8, clamped.
    let figure = Rgb8 {
        width: 48,
        height: 36,
        data: image::open(&exact).unwrap().to_rgb8().into_raw(),
    };
    let written = image::open(&diff).unwrap().to_rgb8().into_raw();
    assert_eq!(
        written,
        check::compare::difference_picture(flipped, &figure).data
    );

    for (args, names) in [
        (vec!["check", bmp.as_str(), "--stage", "path"], "path stage"),
        (vec!["check", bmp.as_str(), "--width", "100"], "48×36"),
        (vec!["check", bmp.as_str(), "--diff-out", "d.exr"], "PNG"),
        (vec!["check", "no-such-image.bmp"], "no-such-image.bmp"),
        (
            vec!["check", exact.as_str(), "--samples", "4"],
            "one sample",
        ),
    ] {
        let out = raylab(&args);
        assert!(!out.status.success(), "{args:?}");
        let err = stderr(&out);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(names), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

/// `raylab check` with the defaults (figure 7) on a figure 6 render says it is figure 6 with N
/// missing and how to check it as figure 6; on the figure × 0.6 it names the factor, and the
/// difference picture is scaled so that it is not white all over.
#[test]
fn check_names_another_stage_and_a_factor() {
    use raylab_core::teaching::check::Rgb8;
    use raylab_core::transport::film::Image;
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let six = path("six.png");
    let render = raylab(&[
        "render", "--stage", "shadows", "--width", "64", "--height", "48", "--out", &six,
    ]);
    assert!(render.status.success(), "{}", stderr(&render));
    let out = raylab(&["check", &six]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("verdict: other-stage"), "{text}");
    assert!(
        text.contains("this is figure 6: the constant indirect term N is missing"),
        "{text}"
    );
    assert!(text.contains("--stage shadows"), "{text}");
    let out = raylab(&["check", &six, "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["best"]["mistake"], "other-stage");
    assert_eq!(json["best"]["stage"]["name"], "figure 6");
    // With the stage it was made at, it is the exact figure.
    let out = raylab(&["check", &six, "--stage", "shadows"]);
    assert!(
        String::from_utf8(out.stdout)
            .unwrap()
            .contains("verdict: none")
    );

    // Figure 7 as linear light (EXR), × 0.6, written as the lab's display writes it.
    let exr = path("seven.exr");
    let render = raylab(&["render", "--width", "64", "--height", "48", "--out", &exr]);
    assert!(render.status.success(), "{}", stderr(&render));
    let linear = image::open(&exr).unwrap().to_rgb32f();
    let dimmed = Rgb8::from_linear(&Image {
        width: 64,
        height: 48,
        pixels: linear
            .pixels()
            .map(|p| glam::Vec3::from_array(p.0) * 0.6)
            .collect(),
    });
    let png = path("dimmed.png");
    image::RgbImage::from_raw(64, 48, dimmed.data.clone())
        .unwrap()
        .save(&png)
        .unwrap();
    let diff = path("diff.png");
    let out = raylab(&["check", &png, "--diff-out", &diff]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("verdict: factor"), "{text}");
    assert!(text.contains("× 0.60 everywhere"), "{text}");
    assert!(text.contains("power P"), "{text}");
    let written = image::open(&diff).unwrap().to_rgb8().into_raw();
    let white = written.iter().filter(|v| **v == 255).count();
    assert!(
        white * 10 < written.len(),
        "{white} of {} white",
        written.len()
    );
    assert!(
        written.iter().any(|v| *v > 100),
        "the difference is visible"
    );
}

/// `raylab check` on raylab's own renders of scenes with water and glass: the pool in every lab
/// stage, a scene file with `[scene.water]` and a glass model, and a pool screenshot given to
/// `--settings`; each is `none` at a 100 % match (once a panic in the figures' recombination).
#[test]
fn check_follows_water_and_glass() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let exact = |out: &std::process::Output| {
        assert!(out.status.success(), "{}", stderr(out));
        let text = String::from_utf8(out.stdout.clone()).unwrap();
        assert!(text.contains("match: 100.0 %"), "{text}");
        assert!(text.contains("verdict: none"), "{text}");
    };
    for stage in ["flat", "incoming", "direct", "shadows", "lab"] {
        let p = path(&format!("pool-{stage}.png"));
        let render = raylab(&[
            "render", "--scene", "pool", "--stage", stage, "--width", "24", "--height", "24",
            "--out", &p,
        ]);
        assert!(render.status.success(), "{}", stderr(&render));
        exact(&raylab(&["check", "--scene", "pool", "--stage", stage, &p]));
        if stage == "lab" {
            // The screenshot carries its settings.
            exact(&raylab(&["check", "--settings", &p, &p]));
        }
    }
    let mut s = settings(Stage::Shadows, 24);
    s.camera = s.camera.with_resolution(24, 20);
    let mut spec = raylab_core::shapes::scene::SceneChoice::Pool.spec();
    spec.models = vec![raylab_core::shapes::scene::spec::ModelSpec {
        kind: raylab_core::shading::material::MaterialKind::Glass {
            ior: 1.5,
            tint: glam::Vec3::ONE,
        },
        ..raylab_core::shapes::scene::spec::ModelSpec::new(
            "teapot",
            &raylab_core::shapes::scene::obj::Placement::TEAPOT,
        )
    }];
    s.scene = raylab_core::shapes::scene::SceneChoice::from_spec(spec);
    let toml = path("glass-pool.toml");
    let text = raylab_core::files::scene_file::to_text(&s, dir.path()).unwrap();
    assert!(
        text.contains("[scene.water]") && text.contains("glass"),
        "{text}"
    );
    std::fs::write(&toml, text).unwrap();
    let p = path("glass-pool.png");
    let render = raylab(&["render", "--scene-file", &toml, "--out", &p]);
    assert!(render.status.success(), "{}", stderr(&render));
    exact(&raylab(&["check", "--scene-file", &toml, &p]));
}

/// `check` takes the render options as `render` and `inspect` do: waves asked of a scene with
/// no water are refused by name, not ignored.
#[test]
fn check_refuses_waves_without_water_as_render_does() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("box.png");
    let p = p.to_str().unwrap();
    let render = raylab(&["render", "--width", "8", "--height", "8", "--out", p]);
    assert!(render.status.success(), "{}", stderr(&render));
    for flag in ["--water-waves", "--water-time"] {
        let out = raylab(&["check", flag, "0.05", p]);
        assert!(!out.status.success(), "{flag}");
        let err = stderr(&out);
        assert!(err.contains("need a scene with water"), "{flag}: {err}");
        assert!(out.stdout.is_empty(), "{flag}");
    }
}

/// The pool's waves from the command line: the image is the library's for the same water;
/// waves asked of a scene with no water are refused by name.
#[test]
fn the_pool_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pool.exr");
    let run = raylab(&[
        "render",
        "--scene",
        "pool",
        "--water-waves",
        "0.02",
        "--water-time",
        "1.5",
        "--width",
        "40",
        "--height",
        "30",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let mut s = settings(Stage::Lab, 40);
    s.camera = s.camera.with_resolution(40, 30);
    let mut spec = raylab_core::shapes::scene::SceneChoice::Pool.spec();
    let water = spec.water.as_mut().unwrap();
    water.waves = 0.02;
    water.time = 1.5;
    s.scene = raylab_core::shapes::scene::SceneChoice::from_spec(spec);
    let written = image::open(&out).unwrap().to_rgb32f().into_raw();
    assert_eq!(written, library_exr(&s));

    let refused = raylab(&[
        "render",
        "--water-waves",
        "0.02",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("need a scene with water"),
        "{}",
        stderr(&refused)
    );
}

/// `--denoise on` writes the library's denoised image (EXR, bit for bit) and says so; off, the
/// default, the render; a noiseless stage is written as it is, with a note. `inspect --denoise
/// on` gives the same pixel's denoised value in its JSON.
#[test]
fn denoise_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = settings(Stage::Path, 32);
    s.samples_per_pixel = 4;
    let path = [
        "--stage",
        "path",
        "--samples",
        "4",
        "--width",
        "32",
        "--height",
        "32",
    ];
    let render = |name: &str, denoise: &str| {
        let out_path = dir.path().join(name);
        let mut args = vec![
            "render",
            "--out",
            out_path.to_str().unwrap(),
            "--denoise",
            denoise,
        ];
        args.extend_from_slice(&path);
        let out = raylab(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        (
            image::open(&out_path).unwrap().to_rgb32f().into_raw(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    let (raw, raw_text) = render("raw.exr", "off");
    let (denoised, text) = render("denoised.exr", "on");
    assert_eq!(raw, library_exr(&s));
    assert!(!raw_text.contains("denoised"), "{raw_text}");
    let (_, want) = raylab_core::transport::denoise::render_denoised(&cornell_box(), &s);
    let want = want.unwrap();
    let want: Vec<f32> = want.pixels.iter().flat_map(|p| p.to_array()).collect();
    assert_eq!(denoised, want);
    assert!(text.contains("denoised (the accumulated image"), "{text}");

    let out = raylab(&[
        "render",
        "--out",
        dir.path().join("lab.png").to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--denoise",
        "on",
    ]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("not denoised: nothing"));

    let mut args = vec!["inspect", "--pixel", "5,20", "--json", "--denoise", "on"];
    args.extend_from_slice(&path);
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let i = (20 * 32 + 5) * 3;
    let value: Vec<f32> = json["denoised"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(value, want[i..i + 3]);

    // A denoised PNG carries settings that say so: rendered again from them (without
    // --denoise), the same image; the raw PNG's settings give the raw image.
    let again = |name: &str| {
        let shot = dir.path().join(name);
        let mut args = vec!["render", "--out", shot.to_str().unwrap()];
        args.extend_from_slice(&path);
        if name.starts_with("denoised") {
            args.extend_from_slice(&["--denoise", "on"]);
        }
        assert!(raylab(&args).status.success());
        let copy = dir.path().join(format!("again-{name}"));
        let out = raylab(&[
            "render",
            "--settings",
            shot.to_str().unwrap(),
            "--out",
            copy.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let bytes = |p: &std::path::Path| image::open(p).unwrap().to_rgb8().into_raw();
        (bytes(&shot), bytes(&copy))
    };
    let (shot, copy) = again("denoised.png");
    assert_eq!(copy, shot, "the denoised image again");
    let (raw_shot, raw_copy) = again("raw.png");
    assert_eq!(raw_copy, raw_shot);
    assert_ne!(raw_shot, shot);
}

/// `--caustics photons` outside the path stage, and `--photons` without it, did nothing
/// without a word: each is refused in one line, the same in `render`, `inspect` and `check`,
/// before any file is written; in the path stage with caustics they are taken.
#[test]
fn caustics_and_photons_where_they_do_nothing_are_refused_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("lab.png");
    let image = image.to_str().unwrap();
    let size = ["--width", "8", "--height", "8"];
    let mut render = vec!["render", "--out", image];
    render.extend_from_slice(&size);
    assert!(raylab(&render).status.success());
    let out = dir.path().join("out.png");
    for (extra, says) in [
        (
            &["--caustics", "photons"][..],
            "--caustics photons needs --stage path",
        ),
        (
            &[
                "--caustics",
                "photons",
                "--stage",
                "shadows",
                "--photons",
                "10",
            ],
            "the lab's stage 'shadows'",
        ),
        (
            &["--photons", "5000"],
            "without --caustics photons it does nothing",
        ),
        (
            &["--stage", "path", "--photons", "5000"],
            "without --caustics photons it does nothing",
        ),
    ] {
        for command in [
            vec!["render", "--out", out.to_str().unwrap()],
            vec!["inspect", "--pixel", "4,4"],
            vec!["check", image],
        ] {
            let mut args = command.clone();
            args.extend_from_slice(&size);
            args.extend_from_slice(extra);
            let run = raylab(&args);
            let err = stderr(&run);
            assert_eq!(run.status.code(), Some(1), "{args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
            assert!(err.contains(says), "{args:?}: '{err}' should say '{says}'");
            assert!(!out.exists(), "{args:?} wrote a file");
        }
    }
    let mut path = vec!["render", "--out", out.to_str().unwrap()];
    path.extend_from_slice(&size);
    path.extend_from_slice(&[
        "--stage",
        "path",
        "--caustics",
        "photons",
        "--photons",
        "50",
    ]);
    let ok = raylab(&path);
    assert!(ok.status.success(), "{}", stderr(&ok));
}

/// `--pitch DEG` turns the camera up, as the window's Pitch does: the image differs from the
/// level camera's and is, byte for byte, the render of a scene file whose pitch is the same
/// degrees; `check` and `inspect` take it too.
#[test]
fn pitch_reaches_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let size = ["--stage", "direct", "--width", "40", "--height", "32"];
    let render = |extra: &[&str]| {
        let out = raylab(&[&["render"], &size[..], extra].concat());
        assert!(out.status.success(), "{}", stderr(&out));
    };
    let (level, pitched, from_file) = (path("level.png"), path("pitched.png"), path("file.png"));
    let scene = path("level.toml");
    render(&["--out", &level, "--save-scene", &scene]);
    render(&["--out", &pitched, "--pitch", "12.5"]);
    let pixels = |p: &str| image::open(p).unwrap().to_rgb8().into_raw();
    assert_ne!(pixels(&level), pixels(&pitched));

    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(
        text.contains("version = 2\n") && text.contains("\npitch = 0.0\n"),
        "{text}"
    );
    std::fs::write(&scene, text.replace("\npitch = 0.0\n", "\npitch = 12.5\n")).unwrap();
    let out = raylab(&["render", "--scene-file", &scene, "--out", &from_file]);
    assert!(out.status.success(), "{}", stderr(&out));
    // The same settings, so the same bytes: pixels and the settings the PNG carries.
    assert_eq!(
        std::fs::read(&pitched).unwrap(),
        std::fs::read(&from_file).unwrap()
    );

    let check = |extra: &[&str]| {
        let out = raylab(&[&["check", &pitched], &size[..], extra].concat());
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8(out.stdout).unwrap()
    };
    let text = check(&["--pitch", "12.5"]);
    assert!(text.contains("match: 100.0 %"), "{text}");
    assert!(!check(&[]).contains("match: 100.0 %"));
    let out = raylab(
        &[
            &["inspect", "--pixel", "20,16"],
            &size[..],
            &["--pitch", "12.5"],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `--light-shape spot` with its cone (`--light-aim`, `--spot-cutoff`, `--spot-beam`, in
/// degrees): the EXR is the library's render of that spot, float for float; on the floor every
/// pixel outside the cutoff cone is black and those inside the beam are lit (but where a block
/// shadows them). The cone's options without the spot, a beam wider than the cutoff, a cutoff
/// of 90° and a spot aimed at its own position are refused with one line naming the option.
#[test]
fn a_spot_light_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spot.exr");
    let side = 64;
    let size = ["--width", "64", "--height", "64", "--stage", "shadows"];
    let mut args = vec!["render", "--out", path.to_str().unwrap()];
    args.extend_from_slice(&size);
    args.extend_from_slice(&[
        "--light-shape",
        "spot",
        "--light-aim",
        "0,1,-0.2",
        "--spot-cutoff",
        "25",
        "--spot-beam",
        "15",
    ]);
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let exr = image::open(&path).unwrap().to_rgb32f().into_raw();
    let mut s = settings(Stage::Shadows, side);
    s.light.kind = raylab_core::shading::light::LightKind::Spot(
        raylab_core::shading::light::SpotCone::default(),
    );
    assert_eq!(exr, library_exr(&s));
    let spot = s.light.spot().unwrap();
    let scene = cornell_box();
    let (mut outside, mut beam, mut beam_lit) = (0, 0, 0);
    for y in 0..side {
        for x in 0..side {
            let ray = s.camera.pixel_ray(x, y);
            let Some(hit) = scene.closest_intersection(&ray, f32::INFINITY) else {
                continue;
            };
            if hit.position.y < 0.999 {
                continue;
            }
            let value = exr[3 * (y * side + x) as usize];
            let falloff = spot.falloff_toward(hit.position);
            if falloff == 0.0 {
                outside += 1;
                assert_eq!(value, 0.0, "pixel ({x}, {y}) outside the cone");
            } else if falloff == 1.0 {
                beam += 1;
                beam_lit += usize::from(value > 0.0);
            }
        }
    }
    assert!(
        outside > 100 && beam > 30,
        "{outside} outside, {beam} in the beam"
    );
    assert!(
        beam_lit * 10 > beam * 8,
        "{beam_lit} of {beam} lit in the beam"
    );

    let refused = dir.path().join("refused.png");
    let base = ["render", "--out", refused.to_str().unwrap()];
    for (extra, says) in [
        (
            &["--light-aim", "0,1,0"][..],
            "--light-aim sets a spot light's cone: it needs --light-shape spot",
        ),
        (
            &["--light-shape", "sphere", "--spot-cutoff", "20"][..],
            "--spot-cutoff sets a spot light's cone",
        ),
        (
            &["--light-shape", "spot", "--spot-beam", "30"][..],
            "invalid spot beam 30° (cutoff 25°)",
        ),
        (
            &["--light-shape", "spot", "--spot-cutoff", "90"][..],
            "invalid spot cutoff 90°",
        ),
        (
            &["--light-shape", "spot", "--light-aim", "0,-0.5,-0.7"][..],
            "invalid light aim (0, -0.5, -0.7)",
        ),
        (
            &["--light-shape", "spot", "--light-size", "0.2"][..],
            "a spot light has no size",
        ),
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(&size);
        args.extend_from_slice(extra);
        assert_refused(&args, says, &refused);
    }
}

/// `--material-preset plastic` in the lab stage and the path stage: the image is the
/// library's for the plastic preset at α 0.1 (the preset's own roughness when `--roughness`
/// is not given). In the lab stage the tall block shows a white highlight from the light over
/// its blue: at its brightest pixel the red channel is well above the diffuse block's
/// 0.15·(D + N), and red equals green (the coating reflects every channel alike, and the
/// block's ρ is 0.15 in both). `--roughness` reaches the coating.
#[test]
fn the_plastic_preset_shows_a_highlight_on_the_tall_block() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let path = dir.path().join(name);
        let mut args = vec!["render", "--out", path.to_str().unwrap(), "--width", "48"];
        args.extend_from_slice(&["--height", "48"]);
        args.extend_from_slice(extra);
        let out = raylab(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        image::open(&path).unwrap().to_rgb32f()
    };
    for (stage, extra) in [
        (Stage::Lab, &[][..]),
        (Stage::Path, &["--samples", "4", "--seed", "2"][..]),
    ] {
        let mut args = vec!["--stage", stage.name()];
        args.extend_from_slice(extra);
        let diffuse = render("diffuse.exr", &args);
        args.extend_from_slice(&["--material-preset", "plastic"]);
        let plastic = render("plastic.exr", &args);
        let mut s = settings(stage, 48);
        if stage == Stage::Path {
            s.samples_per_pixel = 4;
            s.seed = 2;
        }
        s.material_preset = raylab_core::MaterialPreset::Plastic;
        s.roughness = 0.1;
        assert_eq!(plastic.as_raw(), &library_exr(&s), "{stage:?}");
        if stage == Stage::Path {
            // Through the coating the base's blue is dimmer and the coating reflects the
            // room: the block changes.
            assert_ne!(plastic.as_raw(), diffuse.as_raw());
            continue;
        }
        // The tall block: in the lab stage the only pixels that change.
        let (x, y, _) = diffuse
            .enumerate_pixels()
            .filter(|(x, y, p)| plastic.get_pixel(*x, *y) != *p)
            .max_by(|a, b| {
                let red = |(x, y, _): &(u32, u32, _)| plastic.get_pixel(*x, *y)[0];
                red(a).total_cmp(&red(b))
            })
            .unwrap();
        let (p, d) = (plastic.get_pixel(x, y), diffuse.get_pixel(x, y));
        // The base alone is dimmer than the diffuse block (through the coating, 0.9 of its
        // red at most pixels); the highlight lifts the brightest pixel's red above it: 0.373
        // against 0.302 at (18, 21).
        assert!(
            p[0] > 1.15 * d[0] && p[0] > 0.3,
            "({x}, {y}): {p:?} vs {d:?}"
        );
        // Under the white light red and green are alike.
        assert!((p[0] - p[1]).abs() <= 1e-6 * p[0], "{p:?}");
        args.extend_from_slice(&["--roughness", "0.3"]);
        let rougher = render("rougher.exr", &args);
        s.roughness = 0.3;
        assert_eq!(rougher.as_raw(), &library_exr(&s));
    }
}

/// `--material PART=KIND:FIELD=VALUE,…` gives a part of the box any material through the
/// kinds' table: the image is the library's with that part material, `--save-scene` writes
/// it, and a wrong kind, field or value is refused on one line naming it, with no file.
#[test]
fn a_part_material_on_the_command_line() {
    use raylab_core::shading::material::MaterialKind;
    use raylab_core::shapes::scene::spec::{BoxPart, PartMaterial};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.exr");
    let scene = dir.path().join("m.toml");
    let o = out.to_str().unwrap();
    let args = [
        "render",
        "--out",
        o,
        "--width",
        "48",
        "--height",
        "48",
        "--save-scene",
        scene.to_str().unwrap(),
        "--material",
        "tall=plastic:alpha=0.2,int_ior=1.6",
        "--material",
        "short=mirror:tint=0.9,0.8,0.7",
    ];
    let run = raylab(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    let mut s = settings(Stage::Lab, 48);
    s.part_materials = vec![
        PartMaterial {
            part: BoxPart::TallBlock,
            kind: MaterialKind::Plastic {
                alpha: 0.2,
                int_ior: 1.6,
                ext_ior: 1.0,
                specular: glam::Vec3::ONE,
            },
        },
        PartMaterial {
            part: BoxPart::ShortBlock,
            kind: MaterialKind::Mirror {
                tint: glam::Vec3::new(0.9, 0.8, 0.7),
            },
        },
    ];
    let image = image::open(&out).unwrap().to_rgb32f();
    assert_eq!(image.as_raw(), &library_exr(&s));
    let saved = raylab_core::files::scene_file::load(&scene).unwrap();
    assert_eq!(saved.part_materials, s.part_materials);
    std::fs::remove_file(&out).unwrap();
    for (material, names) in [
        ("tall=gold", "unknown material kind 'gold'"),
        (
            "tall=mirror:ior=1.5",
            "unknown field `ior` for a mirror material (its fields: tint)",
        ),
        (
            "tall=rough:alpha=3",
            "invalid material alpha 3: must be in [0.01, 1]",
        ),
        ("roof=mirror", "unknown box part 'roof'"),
        ("mirror", "give the part and its material as PART=KIND"),
    ] {
        assert_refused(&["render", "--out", o, "--material", material], names, &out);
    }
}

/// `render --equations`: the lab's D typed as a student types it gives the lab's own image
/// bit for bit; a formula mistake is named; NaN pixels are counted.
#[test]
fn render_with_the_students_equations() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_owned()
    };
    let lab = write(
        "lab.txt",
        "// DirectLight, pasted from C++\n\
         vec3 r = lightPos - position;\n\
         float r2 = glm::dot(r, r);\n\
         vec3 D = shadowed ? vec3(0) : lightColor * std::max(dot(normalize(r), normal), 0.f) / (4.f * M_PI * r2);\n",
    );
    let inverse_r = write(
        "inverse.txt",
        "let r = lightPos - position\n\
         D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / (4 * pi * length(r))\n",
    );
    let nan = write("nan.txt", "R = color * (D + indirectLight) * (0 / 0)\n");
    let size = ["--width", "48", "--height", "40"];
    let render = |equations: Option<&str>, out: &Path| {
        let mut args = vec!["render", "--out", out.to_str().unwrap()];
        args.extend(size);
        if let Some(e) = equations {
            args.extend(["--equations", e]);
        }
        let out = raylab(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let figure = dir.path().join("figure.png");
    render(None, &figure);
    let typed = dir.path().join("typed.png");
    let text = render(Some(&lab), &typed);
    assert!(
        text.contains("100.0 % of pixels within 2/255 of the exact figure"),
        "{text}"
    );
    assert!(text.contains("D: equal to the lab's"), "{text}");
    let pixels = |p: &Path| image::open(p).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels(&typed), pixels(&figure));

    let text = render(Some(&inverse_r), &dir.path().join("inverse.png"));
    assert!(text.contains("D: the classic mistake inverse-r"), "{text}");
    assert!(!text.contains("100.0 %"), "{text}");

    let text = render(Some(&nan), &dir.path().join("nan.png"));
    assert!(
        text.contains("1920 pixels came out NaN or infinite (shown magenta)"),
        "{text}"
    );
    let magenta = pixels(&dir.path().join("nan.png"));
    assert!(magenta.chunks(3).all(|p| p == [255, 0, 255]));
}

/// A render of the student's equations carries them in its PNG: `--settings` with that PNG
/// renders the same image again, as does the scene file `--save-scene` wrote; equations in a
/// settings file that do not compile are refused with their quantity, line and column, and
/// nothing is written.
#[test]
fn a_render_carries_the_equations_and_its_settings_render_it_again() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("mine.txt");
    std::fs::write(
        &file,
        "vec3 r = lightPos - position;\n\
         D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / dot(r, r)\n\
         R = D + indirectLight\n",
    )
    .unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_owned();
    let run = |args: &[&str]| {
        let out = raylab(args);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let (first, again, scene) = (path("first.png"), path("again.png"), path("mine.toml"));
    let text = run(&[
        "render",
        "--width",
        "40",
        "--height",
        "32",
        "--equations",
        file.to_str().unwrap(),
        "--out",
        &first,
        "--save-scene",
        &scene,
    ]);
    assert!(text.contains("D: the classic mistake no-4pi"), "{text}");
    let text = run(&["render", "--settings", &first, "--out", &again]);
    assert!(text.contains("D: the classic mistake no-4pi"), "{text}");
    assert!(text.contains("R: the classic mistake no-rho"), "{text}");
    let pixels = |p: &str| image::open(p).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels(&again), pixels(&first));
    let from_scene = path("scene.png");
    run(&["render", "--scene-file", &scene, "--out", &from_scene]);
    assert_eq!(pixels(&from_scene), pixels(&first));
    // The lab's figure differs: the equations made the image.
    let figure = path("figure.png");
    run(&[
        "render", "--width", "40", "--height", "32", "--out", &figure,
    ]);
    assert_ne!(pixels(&figure), pixels(&first));

    let settings = raylab_core::files::settings_file::read_file(std::path::Path::new(&first))
        .unwrap()
        .settings;
    let mut json = serde_json::to_value(&settings).unwrap();
    json["equations"]["R"] = serde_json::json!("// mine\nR = D + indirectlight");
    let bad = path("bad.json");
    std::fs::write(&bad, json.to_string()).unwrap();
    let out_png = path("never.png");
    let out = raylab(&["render", "--settings", &bad, "--out", &out_png]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("equation `R`, line 2, column 9: unknown name `indirectlight`"),
        "{err}"
    );
    assert!(!std::path::Path::new(&out_png).exists());
}

/// `check --equations`: the image the equations make is checked as a student's image is (the
/// mistake named), and each quantity is judged; text and JSON.
#[test]
fn check_the_students_equations() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("corner.txt");
    std::fs::write(
        &path,
        "d = right * (x - W / 2) + down * (y - H / 2) + forward * focalLength\n",
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let size = ["--width", "64", "--height", "64"];
    let mut args = vec!["check", "--equations", path];
    args.extend(size);
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("verdict: pixel-corner"), "{text}");
    assert!(
        text.contains("d: the classic mistake pixel-corner"),
        "{text}"
    );
    args.push("--json");
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["check"]["best"]["mistake"], "pixel-corner", "{json}");
    assert!(
        json["quantities"]["d"]
            .as_str()
            .is_some_and(|v| v.contains("pixel-corner")),
        "{json}"
    );
    assert_eq!(json["non_finite_pixels"], 0);
}

/// `inspect --pixel X,Y --equations FILE`: the inspector's explanation, then the student's
/// pixel with each quantity beside the lab's and every part of their text with its value at
/// the line and column where it is written; in JSON under `equations`, its value the pixel of
/// the image `render --equations` writes.
#[test]
fn inspect_with_the_students_equations() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no4pi.txt");
    std::fs::write(
        &path,
        "vec3 r = lightPos - position;\n\
         D = shadowed ? vec3(0) : lightColor * max(dot(normalize(r), normal), 0.0) / dot(r, r)\n",
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let size = ["--width", "32", "--height", "32"];
    let mut args = vec!["inspect", "--pixel", "8,28", "--equations", path];
    args.extend(size);
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("eq. 27"), "the inspector's own lines: {text}");
    let (_, yours) = text
        .split_once("Your equations at this pixel:")
        .unwrap_or_else(|| panic!("{text}"));
    let has = |start: &str, text: &str| {
        yours
            .lines()
            .any(|l| l.trim_start().starts_with(start) && l.contains(text))
    };
    assert!(has("your pixel", "(8, 28) = ("), "{yours}");
    assert!(has("the lab's terms", "lightPos = ("), "{yours}");
    assert!(has("D ", "(they differ)"), "{yours}");
    assert!(has("line 1:6 ", "r = lightPos - position = ("), "{yours}");
    assert!(has("line 2:77 ", "dot(r, r) = "), "{yours}");

    args.push("--json");
    let out = raylab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["pixel"], serde_json::json!([8, 28]));
    let e = &json["equations"];
    assert_eq!(e["made_of"], "diffuse", "{e}");
    let d = &e["hits"][0]["quantities"][2];
    assert_eq!(d["name"], "D", "{e}");
    let ratio = d["yours"][0].as_f64().unwrap() / d["lab"][0].as_f64().unwrap();
    assert!((ratio - 4.0 * std::f64::consts::PI).abs() < 1e-3, "{ratio}");
    assert_eq!(d["parts"][0]["text"], "lightPos - position");
    assert_eq!(d["parts"][0]["line"], 1);

    // Its value is the pixel of the image `render --equations` writes.
    let png = dir.path().join("no4pi.png");
    let exr = dir.path().join("no4pi.exr");
    for out in [&png, &exr] {
        let mut render = vec![
            "render",
            "--equations",
            path,
            "--out",
            out.to_str().unwrap(),
        ];
        render.extend(size);
        let out = raylab(&render);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let exr = image::open(&exr).unwrap().to_rgb32f();
    let pixel = exr.get_pixel(8, 28).0;
    let value: Vec<f32> = e["value"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(value, pixel, "{e}");

    // Equations that do not compile are refused before anything is traced.
    std::fs::write(dir.path().join("bad.txt"), "R = colr\n").unwrap();
    let bad = dir.path().join("bad.txt");
    let out = raylab(&[
        "inspect",
        "--pixel",
        "1,1",
        "--equations",
        bad.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("bad.txt:1:5: unknown name `colr`"),
        "{}",
        stderr(&out)
    );
}

/// Equations that do not compile are refused with each error's file, line and column, the
/// line and a caret under the offending text; nothing is written. What the sandbox does not
/// compute (the path stage) is refused by name.
#[test]
fn equations_that_do_not_compile_are_refused_where_they_are_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("typo.txt");
    std::fs::write(
        &path,
        "let r = lightpos - position\nD = lightColor * dot(normal, 2.0)\n",
    )
    .unwrap();
    let out_png = dir.path().join("out.png");
    let out = raylab(&[
        "render",
        "--equations",
        path.to_str().unwrap(),
        "--out",
        out_png.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = stderr(&out);
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        lines[0].ends_with("typo.txt:1:9: unknown name `lightpos`: did you mean `lightPos`?"),
        "{err}"
    );
    assert_eq!(lines[1], "  let r = lightpos - position", "{err}");
    assert_eq!(lines[2], "          ^^^^^^^^", "{err}");
    assert!(
        lines[3].ends_with("typo.txt:2:18: `dot` takes two vec3, got vec3 and a number"),
        "{err}"
    );
    assert!(!out_png.exists());

    std::fs::write(&path, "D = vec3(0)\n").unwrap();
    let out = raylab(&[
        "render",
        "--equations",
        path.to_str().unwrap(),
        "--stage",
        "path",
        "--out",
        out_png.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("--equations computes the lab's stages"),
        "{}",
        stderr(&out)
    );
}
