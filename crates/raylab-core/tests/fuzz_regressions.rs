//! Inputs the fuzz targets (FUZZING.md) once failed on, replayed through the very checks the
//! targets run (`fuzz/checks.rs`), so a fixed crash stays fixed in `cargo test`, without
//! nightly or libFuzzer.
//!
//! Each file in `tests/fuzz-regressions/TARGET/` is one input, named for what it found. An input
//! that made the library panic fails the test with that panic; one that hangs or exhausts
//! memory does not finish.

#[allow(dead_code)]
#[path = "../../../fuzz/checks.rs"]
mod checks;

use std::path::{Path, PathBuf};

/// The inputs saved for `target`, in name order. The folder must exist and hold at least one:
/// a folder that is missing or empty (a typo in its name, say) would replay nothing and pass.
fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-regressions")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a folder entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{} holds no input", dir.display());
    files
}

/// Runs `check` on every saved input of `target`, naming the file on the way; the number run.
fn replay(target: &str, check: fn(&[u8])) -> usize {
    let files = inputs(target);
    for file in &files {
        eprintln!("{target}: {}", file.display());
        check(&std::fs::read(file).expect("read the input"));
    }
    files.len()
}

#[test]
fn obj_inputs_that_once_failed() {
    assert!(replay("obj", checks::obj) >= 1);
}

/// Besides what the fuzzer found, each folder holds a valid input (from `fuzz/seeds`), so the
/// check's whole way — parse, validate, save, read back, render — is replayed, and inputs that
/// the hardening refuses now (a focal length whose rays cannot be normalised; a scene file's
/// array of four numbers, a mirror with an index of refraction).
#[test]
fn settings_json_inputs_that_once_failed() {
    assert!(replay("settings_json", checks::settings_json) >= 3);
    let valid = std::fs::read_to_string(
        inputs("settings_json")
            .into_iter()
            .find(|p| p.ends_with("valid-sidecar.json"))
            .unwrap(),
    )
    .unwrap();
    raylab_core::RenderSettings::from_json(&valid)
        .unwrap()
        .validate()
        .expect("the valid input is valid, so the check renders it");
}

#[test]
fn scene_file_inputs_that_once_failed() {
    assert!(replay("scene_file", checks::scene_file) >= 3);
    for file in inputs("scene_file") {
        let text = std::fs::read_to_string(&file).unwrap();
        let parsed =
            raylab_core::files::scene_file::parse(&text, Path::new("/nonexistent-fuzz-folder"));
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(
            parsed.is_ok(),
            name.starts_with("valid-"),
            "{name}: {parsed:?}"
        );
    }
}

/// The sandbox's inputs: each valid one (named `valid-…`) compiles, so the check evaluates and
/// explains it over a recording; any other is refused with errors.
#[test]
fn sandbox_inputs_that_once_failed() {
    assert!(replay("sandbox", checks::sandbox) >= 3);
    for file in inputs("sandbox") {
        let text = std::fs::read_to_string(&file).unwrap();
        let compiled = raylab_core::teaching::sandbox::compile(&text);
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(
            compiled.is_ok(),
            name.starts_with("valid-"),
            "{name}: {compiled:?}"
        );
    }
}

/// The scene-file check on every scene shipped in assets/scenes (the fuzz target's seeds): each
/// parses, saves and reads back to the same settings.
#[test]
fn the_shipped_scene_files_pass_the_scene_file_check() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read(&path).unwrap();
        // The check parses against a folder that does not exist: the shipped scenes name only
        // built-in models, so each must parse.
        let parsed = raylab_core::files::scene_file::parse(
            std::str::from_utf8(&text).unwrap(),
            Path::new("/nonexistent-fuzz-folder"),
        );
        assert!(parsed.is_ok(), "{}: {parsed:?}", path.display());
        checks::scene_file(&text);
        n += 1;
    }
    assert!(n >= 6);
}

/// The crash the `obj` target found: a texture coordinate index of −13 with 4 read. It is an
/// error naming the line now, not a panic inside tobj.
#[test]
fn a_relative_index_before_the_first_is_an_error_naming_it() {
    let path = inputs("obj")
        .into_iter()
        .find(|p| p.ends_with("relative-texcoord-index-before-the-first.obj"))
        .expect("the input is saved");
    let text = std::fs::read(&path).unwrap();
    let e = raylab_core::shapes::scene::obj::parse_obj(&text, Path::new("crash.obj")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "could not load OBJ file 'crash.obj': line 29: texture coordinate index -13 is out of \
         range (4 read so far)"
    );
}
