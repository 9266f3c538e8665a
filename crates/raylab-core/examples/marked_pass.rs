//! One render pass between two marks, for `scripts/count-instructions.sh`: the pass's
//! instructions and taken branches are counted by single-stepping the thread that runs it
//! between two `getpid` calls (the marks), which nothing else in the pass makes.
//!
//! ```text
//! cargo run --release --example marked_pass -- [lab|path] [width] [height] [sample]
//! ```
//!
//! The Cornell box, the lab's default settings (or the `path` stage) at `width` × `height`
//! (default 512 × 32: a strip through the middle of the lab's view, whose rows are as long as
//! the full image's, so that its batches of 64 pixels are the same stretches of a row), one
//! thread. A first pass, unmarked, warms everything up; the marked one is pass `sample`
//! (default 0: the pixel centres, as `raylab bench` traces them).

use raylab_core::transport::integrator::{Shading, Stage};
use raylab_core::transport::render::render_pass;
use raylab_core::transport::settings::RenderSettings;

fn main() {
    let mut args = std::env::args().skip(1);
    let stage = args.next().unwrap_or_else(|| "lab".to_owned());
    let mut number = |default: u32| args.next().and_then(|s| s.parse().ok()).unwrap_or(default);
    let (width, height, sample) = (number(512), number(32), number(0));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let scene = raylab_core::shapes::scene::cornell_box();
    let mut settings = RenderSettings::default();
    if stage == "path" {
        settings.shading = Shading::for_stage(Stage::Path);
    }
    settings.camera = settings.camera.with_resolution(width, height);
    pool.install(|| {
        let warm_up = render_pass(&scene, &settings, sample, &|| false);
        std::hint::black_box(&warm_up);
        // The marks: `std::process::id` is a `getpid` system call each time.
        std::hint::black_box(std::process::id());
        let image = render_pass(&scene, &settings, sample, &|| false);
        std::hint::black_box(&image);
        std::hint::black_box(std::process::id());
    });
}
