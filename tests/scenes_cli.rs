//! `raylab render --scene/--obj` and `raylab bench`, run as a user runs them.

mod common;

use common::{raylab, stderr};
use raylab_core::shapes::scene::SceneChoice;

/// Each scene the command line is given is the one rendered: the PNG is the library's render
/// of that scene (the lab's display of it), byte for byte, and no two scenes give the same
/// image (so a `--scene` or `--obj` that was ignored would fail).
#[test]
fn renders_the_built_in_models_and_an_obj_file() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("tetra.obj");
    std::fs::write(
        &obj,
        "v 0 0 0\nv 1 0 0\nv 0 0 1\nv 0 1 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let mut seen: Vec<Vec<u8>> = Vec::new();
    for (args, choice) in [
        (&["--scene", "cornell"][..], SceneChoice::Cornell),
        (&["--scene", "bunny"], SceneChoice::Bunny),
        (&["--scene", "teapot"], SceneChoice::Teapot),
        (
            &["--obj", obj.to_str().unwrap()],
            SceneChoice::Obj(obj.clone()),
        ),
    ] {
        let png = dir.path().join("out.png");
        let mut argv = vec![
            "render",
            "--out",
            png.to_str().unwrap(),
            "--width",
            "48",
            "--height",
            "48",
        ];
        argv.extend_from_slice(args);
        let out = raylab(&argv);
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        let written = image::open(&png).unwrap().to_rgb8().into_raw();
        let mut settings = common::settings(raylab_core::Stage::Lab, 48);
        settings.scene = choice;
        let scene = settings.scene.load().unwrap();
        let want = raylab_core::transport::render::render(&scene, &settings).to_rgb8();
        assert_eq!(written, want, "{args:?}");
        assert!(
            !seen.contains(&written),
            "{args:?} gave another scene's image"
        );
        seen.push(written);
    }
}

#[test]
fn obj_errors_name_the_file_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    let empty = dir.path().join("empty.obj");
    std::fs::write(&empty, "# nothing here\n").unwrap();
    let missing = dir.path().join("missing.obj");
    let png = dir.path().join("x.png");
    for (path, what) in [
        (&bad, "broken.obj"),
        (&empty, "no triangles"),
        (&missing, "missing.obj"),
    ] {
        let out = raylab(&[
            "render",
            "--out",
            png.to_str().unwrap(),
            "--obj",
            path.to_str().unwrap(),
        ]);
        assert!(!out.status.success());
        let err = stderr(&out);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(what) && !err.contains("panicked"), "{err}");
        assert!(!png.exists());
    }
}

#[test]
fn bench_prints_one_json_object_with_the_figures() {
    let out = raylab(&[
        "bench",
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "32",
        "--threads",
        "1",
        "--passes",
        "2",
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1, "{stdout}");
    let v: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(v["scene"], "cornell");
    assert_eq!(v["triangles"], 30);
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(32), Some(32))
    );
    assert_eq!(v["threads"], 1);
    for key in [
        "build_ms",
        "primary_mrays_per_s",
        "shadow_mrays_per_s",
        "lab_pass_ms",
    ] {
        assert!(v[key].as_f64().is_some_and(|x| x >= 0.0), "{key}: {v}");
    }
    let out = raylab(&["bench", "--scene", "cornell", "--isa", "sse9"]);
    assert!(!out.status.success() && stderr(&out).contains("sse9"));
    // The materials are the denoiser's bench's: elsewhere refused, in one line, as is a name
    // that is none of the presets.
    let out = raylab(&["bench", "--scene", "cornell", "--material-preset", "both"]);
    let err = stderr(&out);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("--stage denoise") && !err.contains("panicked"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let out = raylab(&["bench", "--stage", "denoise", "--material-preset", "gold"]);
    assert!(!out.status.success() && stderr(&out).contains("gold"));
}
