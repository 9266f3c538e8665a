//! `cargo bench`: per scene, the acceleration structure's build, closest hits of the default
//! camera's primary rays, any-hit shadow rays, one full pass of the lab stage (figure 7) and,
//! for the Cornell box, of the path stage — the figures `raylab bench` reports, measured by
//! criterion. 512×512 on the default rayon pool
//! (all cores); set RAYON_NUM_THREADS=2 to match PERFORMANCE.md.
//!
//! `cargo bench -- cornell` runs one scene's group.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylab_core::accel::{Accel, AccelKind};
use raylab_core::bench::{lab_settings, primary_rays, shadow_rays, trace_primary, trace_shadow};
use raylab_core::render::render_pass;
use raylab_core::scene::SceneChoice;
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
                    raylab_core::scene::best_isa(),
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

criterion_group!(benches, scenes);
criterion_main!(benches);
