//! The command line's options as clap reads them.

use std::path::PathBuf;

use clap::Parser;
use glam::Vec3;
use raylab_core::shapes::accel::AccelKind;
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::transport::settings::{Caustics, DEFAULT_PHOTONS};
use raylab_core::{MaterialPreset, RenderSettings, Stage};

use super::options::*;
use super::parse::*;
use super::terminal::*;
use super::*;

fn args(extra: &[&str]) -> RenderOptions {
    let mut argv = vec!["raylab", "render", "--out", "x.png"];
    argv.extend_from_slice(extra);
    match Cli::try_parse_from(argv).unwrap().command {
        Some(Command::Render(a)) => a.options,
        _ => panic!("not render"),
    }
}

#[test]
fn defaults_are_figure_7() {
    assert_eq!(args(&[]).settings(), RenderSettings::default());
}

#[test]
fn switches_override_the_stage() {
    let s = args(&["--stage", "direct", "--shadows", "on", "--indirect", "0.25"]).settings();
    assert_eq!(s.shading.stage, Stage::Direct);
    assert!(s.shading.shadows && s.shading.indirect);
    assert_eq!(s.shading.indirect_light, Vec3::splat(0.25));
    let s = args(&["--indirect", "off", "--camera", "-0.5,0,-2", "--yaw", "-90"]).settings();
    assert!(!s.shading.indirect && s.shading.shadows);
    assert_eq!(s.camera.position, Vec3::new(-0.5, 0.0, -2.0));
    assert_eq!(s.camera.yaw, -std::f32::consts::FRAC_PI_2);
    assert_eq!(s.camera.pitch, 0.0);
    // Degrees, as the window's Pitch and a scene file's `pitch` take them.
    let s = args(&["--pitch", "-12.5", "--yaw", "30"]).settings();
    assert_eq!(s.camera.pitch, raylab_core::base::camera::radians(-12.5));
    assert_eq!(s.camera.yaw, raylab_core::base::camera::radians(30.0));
    assert!((s.camera.pitch + 12.5f32.to_radians()).abs() < 1e-7);
}

#[test]
fn path_stage_bounces_and_presets() {
    let s = args(&[
        "--stage",
        "path",
        "--bounces",
        "3",
        "--material-preset",
        "both",
    ])
    .settings();
    assert_eq!(s.shading.stage, Stage::Path);
    assert_eq!(s.shading.bounces, Some(3));
    assert_eq!(s.material_preset, MaterialPreset::Both);
    let s = args(&["--stage", "path"]).settings();
    assert_eq!(
        (s.shading.bounces, s.material_preset),
        (None, MaterialPreset::None)
    );
    assert!(s.shading.shadows && s.shading.indirect);
    let s = args(&["--material-preset", "glass", "--specular-depth", "2"]).settings();
    assert_eq!(s.shading.specular_depth, 2);
    assert_eq!(
        (s.shading.caustics, s.shading.photons),
        (Caustics::Off, DEFAULT_PHOTONS)
    );
    let s = args(&[
        "--stage",
        "path",
        "--caustics",
        "photons",
        "--photons",
        "5000",
    ])
    .settings();
    assert_eq!(
        (s.shading.caustics, s.shading.photons),
        (Caustics::Photons, 5000)
    );
    assert!(
        s.description().ends_with(" · caustics by photon mapping"),
        "{}",
        s.description()
    );
    for bad in [
        &["--caustics", "yes"][..],
        &["--photons", "0"],
        &["--photons", "10000001"],
        &["--bounces", "-1"][..],
        &["--bounces", "lots"],
        &["--material-preset", "gold"],
        &["--specular-depth", "13"],
    ] {
        let mut argv = vec!["raylab", "render", "--out", "x.png"];
        argv.extend_from_slice(bad);
        assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
    }
}

#[test]
fn scenes_are_chosen_by_name_or_file() {
    assert_eq!(args(&[]).scene_choice(), SceneChoice::Cornell);
    assert_eq!(
        args(&["--scene", "bunny"]).scene_choice(),
        SceneChoice::Bunny
    );
    let a = args(&["--obj", "m/dragon.obj"]);
    assert_eq!(
        a.scene_choice(),
        SceneChoice::Obj(PathBuf::from("m/dragon.obj"))
    );
    for bad in [
        &["--scene", "dragon"][..],
        &["--scene", "bunny", "--obj", "x.obj"],
    ] {
        let mut argv = vec!["raylab", "render", "--out", "x.png"];
        argv.extend_from_slice(bad);
        assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
    }
}

#[test]
fn bench_arguments() {
    let parse = |extra: &[&str]| {
        let mut argv = vec!["raylab", "bench"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).map(|c| c.command) {
            Ok(Some(Command::Bench(b))) => Ok(b),
            Ok(_) => panic!("not bench"),
            Err(e) => Err(e),
        }
    };
    let b = parse(&[]).unwrap();
    assert_eq!(
        (b.scene, b.width, b.height, b.json),
        (None, 512, 512, false)
    );
    let b = parse(&[
        "--scene",
        "terrain",
        "--threads",
        "2",
        "--json",
        "--accel",
        "bvh2",
    ])
    .unwrap();
    assert_eq!(b.scene, Some(SceneChoice::Terrain));
    assert_eq!(
        (b.threads, b.json, b.accel),
        (Some(2), true, AccelKind::Bvh2)
    );
    for bad in [
        &["--width", "0"][..],
        &["--scene", "x"],
        &["--accel", "kd"],
        &["--passes", "0"],
    ] {
        assert!(parse(bad).is_err(), "{bad:?} accepted");
    }
}

#[test]
fn inspect_takes_the_render_options() {
    let parse = |extra: &[&str]| {
        let mut argv = vec!["raylab", "inspect"];
        argv.extend_from_slice(extra);
        match Cli::try_parse_from(argv).map(|c| c.command) {
            Ok(Some(Command::Inspect(a))) => Ok(a),
            Ok(_) => panic!("not inspect"),
            Err(e) => Err(e),
        }
    };
    let a = parse(&["--pixel", "3,4", "--stage", "direct", "--json"]).unwrap();
    assert_eq!((a.pixel, a.json), (Pixel(3, 4), true));
    let render = args(&["--stage", "direct"]).settings();
    assert_eq!(a.options.settings(), render);
    assert!(!parse(&["--pixel", " 7 , 0 "]).unwrap().json);
    // --settings takes everything but the pixel, the output form and the threads.
    let file = ["--pixel", "1,1", "--settings", "x.json"];
    assert!(parse(&[&file[..], &["--json", "--threads", "2"]].concat()).is_ok());
    for bad in [
        &[&file[..], &["--width", "8"]].concat()[..],
        &["--pixel", "1"],
        &["--pixel", "a,b"],
        &["--pixel", "1,2,3"],
        &["--pixel", "-1,0"],
        &["--pixel", "1,1", "--out", "x.png"],
        &["--json"],
    ] {
        assert!(parse(bad).is_err(), "{bad:?} accepted");
    }
}

#[test]
fn clap_messages_become_one_line() {
    let text = "error: the following required arguments were not provided:\n  \
                --pixel <X,Y>\n\nUsage: raylab inspect --pixel <X,Y>\n\nFor more \
                information, try '--help'.\n";
    assert_eq!(
        one_line(text),
        "error: the following required arguments were not provided: --pixel <X,Y>"
    );
    assert_eq!(
        one_line("error: unexpected argument '-q' found\n\nUsage: raylab"),
        "error: unexpected argument '-q' found"
    );
}

#[test]
fn bad_values_are_refused() {
    for bad in [
        &["--width", "0"][..],
        &["--height", "16385"],
        &["--focal", "0"],
        &["--focal", "nan"],
        &["--camera", "1,2"],
        &["--light", "0,inf,0"],
        &["--stage", "phong"],
        &["--shadows", "maybe"],
        &["--light-power", "-1"],
        &["--threads", "0"],
    ] {
        let mut argv = vec!["raylab", "render", "--out", "x.png"];
        argv.extend_from_slice(bad);
        assert!(Cli::try_parse_from(&argv).is_err(), "{bad:?} accepted");
    }
}

/// `--light-kind KIND:FIELD=V,…` makes the light `--light-shape` and its flags make, and is
/// not combined with them.
#[test]
fn light_kind_is_the_shape_and_its_flags_in_one() {
    let flags = args(&[
        "--light-shape",
        "spot",
        "--light-aim",
        "0,1,0",
        "--spot-cutoff",
        "30",
        "--spot-beam",
        "20",
    ])
    .settings();
    let one = args(&["--light-kind", "spot:aim=0,1,0,cutoff=30,beam=20"]).settings();
    assert_eq!(one.light, flags.light);
    let sized = args(&["--light-shape", "sphere", "--light-size", "0.2"]).settings();
    let one = args(&["--light-kind", "sphere:radius=0.2"]).settings();
    assert_eq!(one.light, sized.light);
    let render = |extra: &[&str]| {
        let mut argv = vec!["raylab", "render", "--out", "x.png"];
        argv.extend_from_slice(extra);
        Cli::try_parse_from(argv).map(|_| ())
    };
    let e = render(&["--light-kind", "spot:cutoff=95"])
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid spot cutoff 95°"), "{e}");
    assert!(render(&["--light-kind", "spot", "--spot-cutoff", "30"]).is_err());
    assert!(render(&["--light-kind", "quad", "--light-shape", "quad"]).is_err());
}
