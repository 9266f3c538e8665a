//! `raylab bench`: the tracer's speed per scene (BVH build, Mrays/s, a lab pass) and the
//! denoiser's time.

use std::io::Write as _;
use std::path::PathBuf;

use super::options::DEFAULT_SIDE;
use super::parse::parse_side;
use super::pool::thread_pool;
use clap::Args;
use raylab_core::bench::{BenchConfig, bench_scene};
use raylab_core::shapes::accel::AccelKind;
use raylab_core::shapes::scene::SceneChoice;
use raylab_core::{MaterialPreset, RenderSettings};

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene to measure: cornell, bunny, teapot or terrain [default: all four].
    #[arg(long, value_name = "NAME", conflicts_with = "obj")]
    pub scene: Option<SceneChoice>,
    /// Measure an OBJ file standing in the Cornell box instead.
    #[arg(long, value_name = "FILE")]
    pub obj: Option<PathBuf>,
    /// Image width in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "W")]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = DEFAULT_SIDE, value_parser = parse_side, value_name = "H")]
    pub height: u32,
    /// Threads [default: one per core].
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024), value_name = "N")]
    pub threads: Option<u16>,
    /// Timed passes per figure; the median is reported.
    #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u32).range(1..=10_000), value_name = "N")]
    pub passes: u32,
    /// Acceleration structure: auto, brute, flat, bvh2 or bvh8 (to compare them).
    #[arg(long, default_value = "auto", value_name = "KIND")]
    pub accel: AccelKind,
    /// Print one JSON object per scene (one per line) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// lab: the figures above; path: also one pass of the path stage (unlimited bounces), as
    /// camera paths per second; denoise: the denoiser on the path-traced Cornell box, its time
    /// at W×H (16 samples) and its quality at 256² against a converged reference (about a
    /// minute: see --reference-samples; with mirror and glass, a few).
    #[arg(long, default_value = "lab", value_parser = ["lab", "path", "denoise"], value_name = "STAGE")]
    pub stage: String,
    /// With --stage denoise: samples per pixel of the reference the quality is measured
    /// against.
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(1..=1_000_000), value_name = "N")]
    pub reference_samples: u32,
    /// With --stage denoise: the box's materials, as render's --material-preset: none (the
    /// lab's diffuse box), mirror, glass, both (a mirror and a glass block) or rough.
    #[arg(long, value_name = "PRESET")]
    pub material_preset: Option<MaterialPreset>,
}

pub(super) fn run_bench(args: &BenchArgs) -> anyhow::Result<()> {
    if args.material_preset.is_some() && args.stage != "denoise" {
        anyhow::bail!(
            "--material-preset is measured by --stage denoise only (the denoiser's quality with \
             mirror and glass); the lab and path figures are of the scenes' own materials"
        );
    }
    let pool = thread_pool("bench", args.threads)?;
    if args.stage == "denoise" {
        return run_denoise_bench(args, &pool);
    }
    let scenes: Vec<SceneChoice> = match (&args.obj, &args.scene) {
        (Some(path), _) => vec![SceneChoice::Obj(path.clone())],
        (None, Some(choice)) => vec![choice.clone()],
        // The textured teapot is the teapot's geometry again: not measured twice.
        (None, None) => SceneChoice::BUILT_IN
            .into_iter()
            .filter(|c| *c != SceneChoice::TexturedTeapot)
            .collect(),
    };
    let isa = raylab_core::shapes::scene::best_isa();
    let config = BenchConfig {
        width: args.width,
        height: args.height,
        passes: args.passes as usize,
        path: args.stage == "path",
    };
    // Refused before any work if it cannot fit: the scenes are measured one after the other.
    let largest_scene = scenes.iter().map(SceneChoice::memory_estimate).max();
    raylab_core::base::memory::check(
        format!("a {}×{} bench", args.width, args.height),
        raylab_core::bench::memory_estimate(&config) + largest_scene.unwrap_or(0),
    )?;
    // Written with `writeln!` so that a closed pipe (`raylab bench | head`) is an error, not a
    // panic.
    let mut out = std::io::stdout().lock();
    if !args.json {
        write!(
            out,
            "{:<10} {:>9} {:>6} {:>6} {:>10} {:>12} {:>12} {:>10}",
            "scene",
            "triangles",
            "accel",
            "isa",
            "build ms",
            "primary Mr/s",
            "shadow Mr/s",
            "lab ms"
        )?;
        if config.path {
            writeln!(out, " {:>10} {:>10}", "path ms", "Mpaths/s")?;
        } else {
            writeln!(out)?;
        }
    }
    for choice in scenes {
        let report = pool.install(|| -> anyhow::Result<_> {
            let scene = choice.load()?.rebuilt(args.accel, isa);
            let kind = scene.accel().kind();
            let report = bench_scene(&choice.name(), &scene, args.accel, isa, &config)?;
            Ok((report, kind))
        })?;
        let (r, kind) = report;
        if args.json {
            writeln!(out, "{}", serde_json::to_string(&r)?)?;
        } else {
            write!(
                out,
                "{:<10} {:>9} {:>6} {:>6} {:>10.2} {:>12.1} {:>12.1} {:>10.2}",
                raylab_core::base::inputs::escape_control(&r.scene),
                r.triangles,
                kind.name(),
                isa.name(),
                r.build_ms,
                r.primary_mrays_per_s,
                r.shadow_mrays_per_s,
                r.lab_pass_ms
            )?;
            match (r.path_pass_ms, r.path_samples_per_s) {
                (Some(ms), Some(per_s)) => writeln!(out, " {ms:>10.2} {:>10.2}", per_s / 1e6)?,
                _ => writeln!(out)?,
            }
        }
    }
    if !args.json {
        writeln!(
            out,
            "{}×{}, {} threads, medians of {} passes; kernels {}",
            args.width,
            args.height,
            pool.current_num_threads(),
            args.passes,
            raylab_core::shapes::scene::calibration().map_or_else(
                || format!("{} (forced)", isa.name()),
                |c| format!("{}, the fastest measured here", c.summary())
            )
        )?;
    }
    Ok(())
}

/// `raylab bench --stage denoise`: the denoiser's time (features and filter, medians of
/// `--passes`) on a 16-sample path-traced Cornell box at W×H (its materials
/// `--material-preset`'s), then its quality at 256²: relative MSE raw and denoised at 4 to
/// 1,024 samples against `--reference-samples` ([`raylab_core::transport::denoise::quality`]).
pub(super) fn run_denoise_bench(args: &BenchArgs, pool: &rayon::ThreadPool) -> anyhow::Result<()> {
    use raylab_core::test_support::path_settings;
    use raylab_core::transport::denoise::{Denoiser, Noisy, denoising_film, features_of, quality};
    use raylab_core::transport::film::Film;
    raylab_core::base::memory::check(
        format!("a {}×{} denoise bench", args.width, args.height),
        // A film (sum, squares, brightest samples, the features' sums), the features, the
        // colour without outliers and the filter's planes: under 52 floats a pixel.
        208 * u64::from(args.width) * u64::from(args.height),
    )?;
    let scene = raylab_core::shapes::scene::cornell_box();
    let preset = args.material_preset.unwrap_or_default();
    let with_preset = |width: u32, height: u32| RenderSettings {
        material_preset: preset,
        ..path_settings(width, height)
    };
    let denoiser = Denoiser::default();
    let mut out = std::io::stdout().lock();
    let never = || false;
    let (timing, rows) = pool.install(|| -> anyhow::Result<_> {
        let settings = with_preset(args.width, args.height);
        // The path tracer records the features as it traces (`denoising_film`): their time
        // here is averaging the film's sums. What recording costs the passes: the same 16
        // passes into a film that records none, alternating with them.
        let mut film = denoising_film(&scene, &settings);
        let mut plain = Film::with_noise(args.width, args.height);
        let (mut recording, mut not_recording) = (Vec::new(), Vec::new());
        for sample in 0..16 {
            for (film, times) in [
                (&mut film, &mut recording),
                (&mut plain, &mut not_recording),
            ] {
                let start = std::time::Instant::now();
                raylab_core::transport::render::accumulate_pass(
                    &scene, &settings, sample, film, &never,
                )?;
                times.push(start.elapsed());
            }
        }
        let pass_ms = (
            raylab_core::bench::median_ms(recording),
            raylab_core::bench::median_ms(not_recording),
        );
        let (mut feature_times, mut filter_times) = (Vec::new(), Vec::new());
        for _ in 0..=args.passes {
            let start = std::time::Instant::now();
            let features = features_of(&film, &scene, &settings, &never)?;
            feature_times.push(start.elapsed());
            // The filter's time includes taking the film's outliers apart and giving them back.
            let start = std::time::Instant::now();
            let noisy = Noisy::of_film(&film);
            std::hint::black_box(denoiser.denoise_noisy(&noisy, &features));
            filter_times.push(start.elapsed());
        }
        // The first of each is the warm-up.
        let (features_ms, filter_ms) = (
            raylab_core::bench::median_ms(feature_times.split_off(1)),
            raylab_core::bench::median_ms(filter_times.split_off(1)),
        );
        let rows = quality::measure(
            &scene,
            &with_preset(256, 256),
            &[4, 16, 64, 256, 1024],
            args.reference_samples,
            &denoiser,
        );
        Ok(((features_ms, filter_ms, pass_ms), rows))
    })?;
    let threads = pool.current_num_threads();
    if args.json {
        let json = serde_json::json!({
            "width": args.width,
            "height": args.height,
            "threads": threads,
            "material_preset": preset.name(),
            "features_ms": timing.0,
            "filter_ms": timing.1,
            "path_pass_ms_recording_features": timing.2.0,
            "path_pass_ms": timing.2.1,
            "quality_side": 256,
            "reference_samples": args.reference_samples,
            "quality": rows,
        });
        writeln!(out, "{json}")?;
        return Ok(());
    }
    writeln!(
        out,
        "denoiser, Cornell box{}, path stage at 16 samples, {}×{}, {threads} threads: \
         features {:.2} ms + filter {:.2} ms = {:.2} ms (medians of {} passes)",
        match preset {
            MaterialPreset::None => String::new(),
            preset => format!(" ({preset} preset: {})", preset.label()),
        },
        args.width,
        args.height,
        timing.0,
        timing.1,
        timing.0 + timing.1,
        args.passes
    )?;
    writeln!(
        out,
        "a path pass recording the features {:.2} ms, recording none {:.2} ms (medians of 16, \
         alternating)",
        timing.2.0, timing.2.1
    )?;
    writeln!(
        out,
        "quality at 256×256 against {} samples (relative MSE; equal raw: the raw samples of \
         the same error, from raw error ∝ 1/samples at 1,024):",
        args.reference_samples
    )?;
    writeln!(
        out,
        "{:>8} {:>12} {:>12} {:>10} {:>12}",
        "samples", "raw", "denoised", "equal raw", "mean change"
    )?;
    let last = rows.last().copied();
    for r in &rows {
        let equal = last.map_or(0.0, |l| {
            f64::from(l.samples) * l.raw_relative_mse / r.denoised_relative_mse.max(1e-300)
        });
        writeln!(
            out,
            "{:>8} {:>12.3e} {:>12.3e} {:>10.0} {:>11.3}%",
            r.samples,
            r.raw_relative_mse,
            r.denoised_relative_mse,
            equal,
            100.0 * r.denoised_mean_change
        )?;
    }
    Ok(())
}
