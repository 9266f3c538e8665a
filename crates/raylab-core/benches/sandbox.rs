//! `cargo bench --bench sandbox`: the equation sandbox at the lab's 512 × 512, what a student
//! waits for while typing (re-evaluation, a keystroke to pixels, a re-trace, compiling).
//!
//! * `evaluate/D_R/{1,2}_threads`: a student's `D` and `R` evaluated again over a recording of
//!   the whole image (the lab stage, figure 7), sixteen hits at a time: what changing `D` or
//!   `R` costs. Target: at most 5 ms on 2 threads.
//! * `compile`: the student's text (their `D`, `R` and two values of their own) compiled.
//! * `keystroke/2_threads`: what a keystroke in an editor of `D` or `R` costs before the
//!   window uploads the new image: compile, evaluate over the recording, and the conversion to
//!   the display's 8-bit pixels (`Display::to_rgba8`, what the window shows). Target: the new
//!   image on screen within 50 ms.
//! * `record/2_threads`: tracing the recording again, what a change of `d` or `shadowStart`
//!   costs on top.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use raylab_core::shapes::scene::cornell_box;
use raylab_core::teaching::sandbox::{self, Equations, compile};
use raylab_core::test_support::lab_settings;
use raylab_core::transport::display::Display;

/// The lab's `DirectLight` and pixel value as a student types them.
const D_AND_R: &str = "\
vec3 r = lightPos - position; // from the surface to the light
float r2 = dot(r, r);
D = shadowed ? vec3(0) : lightColor * max(dot(r / sqrt(r2), normal), 0.0f) / (4 * M_PI * r2)
R = color * (D + indirectLight)
";

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn sandbox(c: &mut Criterion) {
    let scene = cornell_box();
    let settings = lab_settings(512, 512);
    let equations = compile(D_AND_R).expect("the lab's D and R compile");
    let recording = pool(2).install(|| sandbox::record(&scene, &settings, &Equations::lab()));
    assert!(recording.fits(&equations));
    let display = Display::default();

    let mut group = c.benchmark_group("sandbox");
    group
        .sample_size(50)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Elements(512 * 512));
    for threads in [1, 2] {
        let pool = pool(threads);
        group.bench_function(format!("evaluate/D_R/{threads}_threads"), |b| {
            b.iter(|| pool.install(|| recording.evaluate(black_box(&equations))))
        });
    }
    let two = pool(2);
    group.bench_function("keystroke/2_threads", |b| {
        b.iter(|| {
            two.install(|| {
                let equations = compile(black_box(D_AND_R)).expect("compiles");
                let rendered = recording.evaluate(&equations);
                display.to_rgba8(&rendered.image.pixels)
            })
        })
    });
    group.bench_function("record/2_threads", |b| {
        b.iter(|| two.install(|| sandbox::record(&scene, &settings, black_box(&equations))))
    });
    group.throughput(Throughput::Bytes(D_AND_R.len() as u64));
    group.bench_function("compile", |b| b.iter(|| compile(black_box(D_AND_R))));
    group.finish();
}

criterion_group!(benches, sandbox);
criterion_main!(benches);
