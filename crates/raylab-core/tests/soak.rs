//! Soak: thousands of random setting changes thrown at the render [`Controller`] as fast as the
//! loop can make them — far faster than a user can drag a slider — with the UI's polling in
//! between. Nothing may panic or report an error, the frames taken must come in generation
//! order and match what they claim to be, the last frame shown must be exactly the direct
//! `render` of the last settings, and memory must not grow.
//!
//! `cargo test --test soak` runs 1,000 changes (a few seconds in the debug build);
//! `cargo test --release --test soak -- --ignored --nocapture` runs the full 10,000 and prints
//! the figures (docs/testing.md, "Soak").

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use raylab_core::base::sampling::Rng;
use raylab_core::shapes::scene::{Scene, cornell_box};
use raylab_core::transport::display::{Display, DisplayTransform};
use raylab_core::transport::progressive::{Controller, Frame};
use raylab_core::transport::render::render;
use raylab_core::{MaterialPreset, RenderSettings, Shading, Stage};

/// How long the worker may take to finish the last job: far more than a 128² path-traced image
/// of a few samples needs, even in the debug build.
const TIMEOUT: Duration = Duration::from_secs(120);

/// The most the resident set may grow from the first third of the run to the last: a leak of
/// a frame per change (≥ 8·8·12 bytes of linear image alone) over 10,000 changes, or of the
/// queued jobs, would pass it; allocator noise and rayon's thread stacks do not.
const RSS_GROWTH_BOUND: u64 = 32 << 20;

/// The smallest and largest image side the changes choose: small, so the run is about the
/// controller, not the tracer.
const SIDES: (u32, u32) = (8, 128);

/// What a run measured.
#[derive(Debug)]
struct Report {
    changes: usize,
    elapsed: Duration,
    /// Jobs submitted (changes that re-trace) and display-only changes.
    submitted: u64,
    display_only: u64,
    /// Times the loop waited for a frame of the newest job, or for it to finish.
    waits: u64,
    /// Frames the polling loop took, and the passes the worker traced.
    frames_taken: u64,
    passes: u64,
    abandoned: u64,
    /// The resident set, in bytes, after every tenth of the changes.
    rss: Vec<u64>,
}

/// The resident set size from `/proc/self/statm` (its second field, in pages of 4 KiB, the
/// page size on x86-64 and arm64 Linux), or `None` where there is no /proc.
fn rss_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

fn below(rng: &mut Rng, n: u32) -> u32 {
    rng.next_u32() % n
}

fn coin(rng: &mut Rng) -> bool {
    rng.next_u32() & 1 == 1
}

/// One random change to `s`, as one control of the workbench would make it.
fn change(rng: &mut Rng, s: &mut RenderSettings) {
    match below(rng, 13) {
        0 => {
            let c = &mut s.camera.position;
            c.x = rng.uniform(-0.9, 0.9);
            c.y = rng.uniform(-0.9, 0.9);
            c.z = rng.uniform(-3.5, 0.5);
        }
        1 => s.camera.yaw = rng.uniform(-3.2, 3.2),
        2 => s.camera.focal_length = s.camera.width as f32 * rng.uniform(0.25, 4.0),
        3 => {
            let l = &mut s.light.position;
            l.x = rng.uniform(-0.95, 0.95);
            l.y = rng.uniform(-0.95, 0.95);
            l.z = rng.uniform(-0.95, 0.95);
        }
        4 => s.light.power = rng.uniform(0.0, 60.0),
        5 => {
            // As the stage selector does: the figure's switches, N and the bounces kept.
            let stage = Stage::ALL[below(rng, Stage::ALL.len() as u32) as usize];
            s.shading = Shading {
                indirect_light: s.shading.indirect_light,
                bounces: s.shading.bounces,
                ..Shading::for_stage(stage)
            };
        }
        6 => s.shading.shadows = !s.shading.shadows,
        7 => s.shading.indirect = !s.shading.indirect,
        8 => s.samples_per_pixel = 1 + below(rng, 4),
        9 => {
            let side = |rng: &mut Rng| SIDES.0 + below(rng, SIDES.1 - SIDES.0 + 1);
            let (w, h) = (side(rng), side(rng));
            s.camera = s.camera.with_resolution(w, h);
        }
        10 => {
            let transforms = [
                DisplayTransform::Lab,
                DisplayTransform::Srgb,
                DisplayTransform::Filmic,
            ];
            s.display = Display {
                transform: transforms[below(rng, 3) as usize],
                exposure: if coin(rng) {
                    rng.uniform(-3.0, 3.0)
                } else {
                    0.0
                },
            };
        }
        11 => s.seed = (u64::from(rng.next_u32()) << 32) | u64::from(rng.next_u32()),
        _ => {
            let presets = [
                MaterialPreset::None,
                MaterialPreset::Mirror,
                MaterialPreset::Glass,
                MaterialPreset::Both,
            ];
            s.material_preset = presets[below(rng, 4) as usize];
        }
    }
}

/// The soak's side of the controller: what it submitted and the frames it took.
struct Ui {
    scene: Arc<Scene>,
    controller: Controller,
    /// The newest job's generation and the settings it was submitted with.
    generation: u64,
    submitted: RenderSettings,
    /// The newest frame taken, and the newest generation seen.
    latest: Option<Frame>,
    newest_seen: u64,
    frames_taken: u64,
}

impl Ui {
    /// Takes the newest frame, if any, as the UI does once a frame, checking that it comes in
    /// order and is what it says it is.
    fn poll(&mut self) -> bool {
        let Some(frame) = self.controller.take_frame() else {
            return false;
        };
        assert!(
            frame.generation >= self.newest_seen,
            "an older frame came later"
        );
        assert!(
            frame.generation <= self.generation,
            "a frame from the future"
        );
        if frame.generation == self.generation {
            assert!(frame.settings.renders_like(&self.submitted));
        }
        let (w, h) = (frame.image.width, frame.image.height);
        assert_eq!(frame.image.pixels.len(), (w * h) as usize);
        assert_eq!(frame.rgba.len(), (w * h * 4) as usize);
        if !frame.is_preview {
            let s = &frame.settings.camera;
            assert_eq!((w, h), (s.width, s.height));
        }
        assert!(frame.samples <= frame.target);
        self.newest_seen = frame.generation;
        self.frames_taken += 1;
        self.latest = Some(frame);
        true
    }

    /// Polls until a frame of the newest job arrives (a UI repainting on the worker's notify).
    /// Only after a submission: a display-only change may publish nothing (the display in force
    /// set again, or the job's final frame already taken with it).
    fn wait_for_a_frame(&mut self) {
        let deadline = Instant::now() + TIMEOUT;
        while !self.poll() || self.newest_seen != self.generation {
            assert!(
                Instant::now() < deadline,
                "no frame of job {} (newest seen {})",
                self.generation,
                self.newest_seen
            );
            std::thread::sleep(Duration::from_micros(50));
        }
    }

    /// Waits until the newest job is done and its final frame, shown with `settings.display`,
    /// is taken (a display-only change is published by the idle worker after `wait_idle`
    /// returns); checks it is the direct `render` of `settings`, bit for bit.
    fn settle(&mut self, settings: &RenderSettings) {
        assert!(self.controller.wait_idle(TIMEOUT), "a job never finished");
        let deadline = Instant::now() + TIMEOUT;
        let (generation, display) = (self.generation, settings.display);
        let done = |f: &Frame| {
            f.generation == generation
                && f.is_final()
                && f.display.transform == display.transform
                && f.display.exposure.to_bits() == display.exposure.to_bits()
        };
        while !self.latest.as_ref().is_some_and(done) {
            assert!(
                Instant::now() < deadline,
                "no final frame of job {generation} with {display:?}; the latest taken: {:?}",
                self.latest
                    .as_ref()
                    .map(|f| (f.generation, f.samples, f.target, f.display))
            );
            if !self.poll() {
                std::thread::sleep(Duration::from_micros(50));
            }
        }
        let last = self.latest.as_ref().unwrap();
        assert!(last.settings.renders_like(settings));
        let direct = render(&self.scene, settings);
        common::assert_same_image(&last.image, &direct, "the last frame");
        assert_eq!(last.rgba, display.to_rgba8(&last.image.pixels));
    }
}

/// Runs `changes` random changes from `seed` and checks the end state; returns the figures.
///
/// No sleeps: changes come in bursts as fast as the loop can make them, and the loop waits
/// only for the worker — now and then for a frame of the newest job (after 7 submissions in
/// 64), or for the job to finish (after 1 change in 64, checked against `render` then too) — so previews, cancelled
/// passes, accumulation and display changes all happen along the way, not just submissions.
fn soak(changes: usize, seed: u64) -> Report {
    let scene: Arc<Scene> = Arc::new(cornell_box());
    let controller = Controller::new(2, Box::new(|| {})).expect("start the controller");
    let mut rng = Rng::new(seed);
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(64, 48);
    let generation = controller.submit(&scene, &settings).unwrap();
    let mut ui = Ui {
        scene: Arc::clone(&scene),
        controller,
        generation,
        submitted: settings.clone(),
        latest: None,
        newest_seen: 0,
        frames_taken: 0,
    };
    let mut report = Report {
        changes,
        elapsed: Duration::ZERO,
        submitted: 1,
        display_only: 0,
        waits: 0,
        frames_taken: 0,
        passes: 0,
        abandoned: 0,
        rss: Vec::new(),
    };
    let every = (changes / 10).max(1);
    let start = Instant::now();
    for i in 1..=changes {
        change(&mut rng, &mut settings);
        if below(&mut rng, 4) == 0 {
            // Now and then two controls in one frame.
            change(&mut rng, &mut settings);
        }
        settings
            .validate()
            .unwrap_or_else(|e| panic!("change {i} made bad settings: {e}"));
        // As the app's `sync_render`: the display alone never re-traces.
        ui.controller.set_display(settings.display);
        let display_only = settings.renders_like(&ui.submitted);
        if display_only {
            report.display_only += 1;
        } else {
            ui.generation = ui.controller.submit(&scene, &settings).unwrap();
            ui.submitted = settings.clone();
            report.submitted += 1;
        }
        let waited = match below(&mut rng, 64) {
            0 => {
                ui.settle(&settings);
                true
            }
            1..8 if !display_only => {
                ui.wait_for_a_frame();
                true
            }
            _ => {
                ui.poll();
                false
            }
        };
        report.waits += u64::from(waited);
        assert_eq!(ui.controller.take_error(), None, "after change {i}");
        if i % every == 0
            && let Some(rss) = rss_bytes()
        {
            report.rss.push(rss);
        }
    }
    report.elapsed = start.elapsed();

    // The last settings win.
    ui.settle(&settings);
    assert_eq!(ui.controller.generation(), ui.generation);
    assert_eq!(ui.controller.take_error(), None);
    // Nothing more comes: the worker is idle.
    std::thread::sleep(Duration::from_millis(20));
    assert!(ui.controller.take_frame().is_none());

    report.frames_taken = ui.frames_taken;
    report.passes = ui.controller.passes_traced();
    report.abandoned = ui.controller.abandoned_jobs();
    report
}

/// The resident set must not grow: the largest sample of the run's last third within
/// [`RSS_GROWTH_BOUND`] of the largest of its first third.
fn check_memory(report: &Report) {
    let rss = &report.rss;
    if rss.len() < 3 {
        eprintln!("soak: no /proc/self/statm here, memory not checked");
        return;
    }
    let third = rss.len() / 3;
    let first = *rss[..third].iter().max().unwrap();
    let last = *rss[rss.len() - third..].iter().max().unwrap();
    assert!(
        last <= first + RSS_GROWTH_BOUND,
        "the resident set grew from {} MiB to {} MiB: {:?}",
        first >> 20,
        last >> 20,
        rss.iter().map(|b| b >> 20).collect::<Vec<_>>()
    );
}

fn print(report: &Report) {
    let mib = |b: &u64| format!("{:.1}", *b as f64 / f64::from(1 << 20));
    eprintln!(
        "soak: {} changes in {:.2} s ({:.0} changes/s): {} jobs submitted, {} display-only, \
         {} waits, {} frames taken, {} passes traced, {} jobs abandoned; RSS MiB every {}: [{}]",
        report.changes,
        report.elapsed.as_secs_f64(),
        report.changes as f64 / report.elapsed.as_secs_f64(),
        report.submitted,
        report.display_only,
        report.waits,
        report.frames_taken,
        report.passes,
        report.abandoned,
        report.changes / 10,
        report.rss.iter().map(mib).collect::<Vec<_>>().join(", "),
    );
}

#[test]
fn a_thousand_random_changes_end_on_the_last_settings_exactly() {
    let report = soak(1_000, 0x5eed_0010);
    print(&report);
    check_memory(&report);
    // Most changes re-trace; the worker did real work along the way, finishing some jobs and
    // abandoning others.
    assert!(report.submitted > 800, "{report:?}");
    assert!(report.frames_taken >= report.waits, "{report:?}");
    assert!(report.abandoned > 0, "{report:?}");
}

/// The full soak (docs/testing.md, "Soak"): `cargo test --release --test soak -- --ignored --nocapture`.
/// `RAYLAB_SOAK_CHANGES=N` runs N changes instead (a million take about a minute in release).
#[test]
#[ignore = "10,000 changes: run in release with --ignored"]
fn ten_thousand_random_changes_end_on_the_last_settings_exactly() {
    let changes = std::env::var("RAYLAB_SOAK_CHANGES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(10_000);
    let report = soak(changes, 0x5eed_0010);
    print(&report);
    check_memory(&report);
    assert!(report.submitted as f64 > 0.8 * changes as f64, "{report:?}");
    assert!(report.frames_taken >= report.waits, "{report:?}");
    assert!(report.abandoned > 0, "{report:?}");
}
