//! `cargo bench`: per scene, the acceleration structure's build, closest hits of the default
//! camera's primary rays, any-hit shadow rays, one full pass of the lab stage (figure 7) and,
//! for the Cornell box, of the path stage — the figures `raylab bench` reports, measured by
//! criterion. 512×512 on the default rayon pool
//! (all cores); set RAYON_NUM_THREADS=2 to match PERFORMANCE.md ("How to measure").
//!
//! `cargo bench -- cornell` runs one scene's group. The `degenerate` group times the inputs
//! whose cost must stay linear in their size (a million copies of one triangle, built and
//! loaded from an OBJ file; 100,000 faces around one vertex, smoothed). The tests check what
//! these inputs give, not how fast.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylab_core::bench::{trace_primary, trace_shadow};
use raylab_core::shapes::accel::{Accel, AccelKind};
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::test_support::{lab_settings, primary_rays, shadow_rays};
use raylab_core::transport::render::render_pass;
use raylab_core::{Shading, Stage};

fn scenes(c: &mut Criterion) {
    for choice in SceneChoice::BUILT_IN
        .into_iter()
        .filter(|c| *c != SceneChoice::TexturedTeapot)
    {
        let Ok(scene) = choice.load() else {
            eprintln!("could not load {choice}");
            continue;
        };
        let settings = lab_settings(512, 512);
        let primary = primary_rays(&settings.camera);
        let shadow = shadow_rays(&scene, &settings.light, &primary);
        let big = scene.triangles.len() > 100_000;

        let mut group = c.benchmark_group(choice.name());
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(if big { 6 } else { 2 }));
        group.bench_function("build", |b| {
            b.iter(|| {
                Accel::build(
                    black_box(&scene.triangles),
                    AccelKind::Auto,
                    raylab_core::shapes::scene::best_isa(),
                )
            })
        });
        group.throughput(Throughput::Elements(primary.len() as u64));
        group.bench_function("primary", |b| {
            b.iter(|| trace_primary(black_box(&scene), &primary))
        });
        group.throughput(Throughput::Elements(shadow.len() as u64));
        group.bench_function("shadow", |b| {
            b.iter(|| trace_shadow(black_box(&scene), &shadow))
        });
        group.throughput(Throughput::Elements(primary.len() as u64));
        group.bench_function("lab_pass", |b| {
            b.iter(|| render_pass(black_box(&scene), &settings, 0, &|| false))
        });
        if choice == SceneChoice::Cornell {
            // The path stage: camera paths per second (a new sample index each pass).
            let mut path = settings.clone();
            path.shading = Shading::for_stage(Stage::Path);
            let mut sample = 0;
            group.bench_function("path_pass", |b| {
                b.iter(|| {
                    sample += 1;
                    render_pass(black_box(&scene), &path, sample, &|| false)
                })
            });
        }
        group.finish();
    }
}

fn degenerate(c: &mut Criterion) {
    use glam::Vec3;
    use raylab_core::base::geometry::Triangle;
    use raylab_core::shapes::scene::obj;
    const COPIES: usize = 1_000_000;
    let mut group = c.benchmark_group("degenerate");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4));
    let triangle = Triangle::new(
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
        0,
    );
    let copies = vec![triangle; COPIES];
    group.bench_function("build_a_million_copies", |b| {
        b.iter(|| {
            Accel::build(
                black_box(&copies),
                AccelKind::Bvh8,
                raylab_core::shapes::scene::best_isa(),
            )
        })
    });
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    text.push_str(&"f 1 2 3\n".repeat(COPIES));
    group.bench_function("load_an_obj_of_a_million_copies", |b| {
        b.iter(|| {
            let mesh = obj::parse_obj(black_box(text.as_bytes()), std::path::Path::new("c.obj"));
            raylab_core::shapes::scene::spec::model_in_box(
                &mesh.unwrap(),
                &obj::Placement::FRONT_LEFT,
                "copies",
            )
        })
    });
    // A fan of 100,000 faces around the origin, each turned a little further.
    let n = 100_000;
    let mut positions = vec![Vec3::ZERO];
    let mut faces = Vec::new();
    for k in 0..n {
        let angle = std::f32::consts::TAU * k as f32 / n as f32;
        positions.push(Vec3::new(angle.cos(), angle.sin(), -1.0));
        faces.push([0, 1 + k as u32, 1 + ((k + 1) % n) as u32]);
    }
    let normals: Vec<Vec3> = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| positions[i as usize]);
            (b - a).cross(c - a).normalize()
        })
        .collect();
    group.bench_function("smooth_a_fan_of_100000_faces", |b| {
        b.iter(|| obj::smooth_normals(black_box(&positions), &faces, &normals, 1.0))
    });
    group.finish();
}

criterion_group!(benches, scenes, degenerate);
criterion_main!(benches);
