//! `raylab render`: the image (PNG or EXR) of the settings the options give, its `--save-scene`
//! file and `--equations`' verdicts.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use super::equations;
use super::options::RenderOptions;
use super::overwrite::{files_read, refuse_output_onto};
use super::parse::parse_on_off;
use super::pool::thread_pool;
use super::terminal::{print_error_line, printable_lines};
use clap::Args;
use raylab_core::transport::display::Display;
use raylab_core::transport::film::OutputFormat;
use raylab_core::transport::render::try_render;
use raylab_core::transport::view::View;
use raylab_core::{MaterialPreset, Stage};

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Output file: .png (the lab's display: clamped, no gamma) or .exr (linear floats).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Write a debug view instead of the shaded image: normals, depth, barycentric, triangle,
    /// bvh-cost, shadow, or variance (of each pixel's mean; needs --samples 2 or more). Its
    /// legend is printed after the summary. Views are saved with the lab's display whatever
    /// --display says, so their colours are the legend's. Combines with --settings.
    /// [default: shaded, or the view a screenshot given to --settings was made with]
    #[arg(long, value_name = "VIEW")]
    pub view: Option<raylab_core::transport::view::View>,
    /// Also write the render's settings as a scene file (.toml), to open in the workbench or
    /// render again with --scene-file.
    #[arg(long, value_name = "FILE.toml")]
    pub save_scene: Option<PathBuf>,
    /// on: write the denoised image, for a noisy render (the path stage, soft shadows, depth
    /// of field; elsewhere there is no noise, and the image is written as it is). off: the
    /// unbiased estimate, as an EXR should hold it. Settings given with --settings that were
    /// a denoised image's (a screenshot of the denoised image) are denoised either way.
    #[arg(long, default_value = "off", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub denoise: bool,
    /// Your own equations, in place of the lab's: a text file of `NAME = EXPRESSION` lines
    /// (and `let NAME = …` lines) for d (the ray direction, equation 24), shadowStart,
    /// shadowed (section 5.1), D (equation 27, DirectLight) and R (equations 28 and 30), in
    /// the lab's C++ style. Prints how many pixels match the exact figure and, for each
    /// quantity written, how it differs from the lab's. The lab's stages only.
    #[arg(long, value_name = "FILE")]
    pub equations: Option<PathBuf>,
    #[command(flatten)]
    pub options: RenderOptions,
}

pub(super) fn run_render(args: &RenderArgs) -> anyhow::Result<()> {
    // Refuse what can't be written before spending time on the render.
    OutputFormat::from_path(&args.out)?;
    if let Some(path) = &args.save_scene {
        check_scene_destination(path)?;
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        anyhow::bail!(
            "could not write '{}': folder '{}' does not exist",
            args.out.display(),
            dir.display()
        );
    }
    raylab_core::transport::film::check_writable(&args.out)?;
    let mut settings = args.options.resolve_settings()?;
    settings.validate()?;
    refuse_output_onto(
        "--out",
        &args.out,
        "the render",
        files_read(&args.options, &settings),
    )?;
    // Denoised when asked, or when the settings given were those of a denoised image.
    settings.denoise |= args.denoise;
    // A screenshot made with a debug view is that view again, unless --view says otherwise.
    let view = args.view.unwrap_or(settings.view);
    // The student's equations: a file's (then carried by the PNG), or those a screenshot or
    // scene file carries.
    if let Some(path) = &args.equations {
        settings.equations = equations::read_texts(path)?;
    }
    let equations = if settings.equations.is_empty() {
        None
    } else {
        let written = raylab_core::teaching::sandbox::carried::compile_texts(&settings.equations)?;
        equations::refuse_unless_lab(&settings, view)?;
        Some(written)
    };
    // Refused before any work if it cannot fit (a 16384² image alone is 3 GiB).
    let c = &settings.camera;
    // Denoising holds a film with its variance, brightest samples and its samples' features'
    // sums, the features, the colour without outliers and the filter's planes beside the
    // image: under 52 floats a pixel more.
    let denoise_memory = if settings.denoise {
        208 * u64::from(c.width) * u64::from(c.height)
    } else {
        0
    };
    raylab_core::base::memory::check(
        format!("a {}×{} render", c.width, c.height),
        settings
            .memory_estimate(view)
            .saturating_add(denoise_memory),
    )?;
    if view == raylab_core::transport::view::View::Variance && settings.samples_per_pixel < 2 {
        anyhow::bail!(
            "the variance view needs 2 or more samples per pixel (--samples 2 or more): it \
             measures the spread between a pixel's samples"
        );
    }
    // What the PNG carries and the scene file says are made now: what cannot be written
    // (a seed a scene file cannot hold) is refused before the render, not after it.
    let out_folder = args.out.parent().unwrap_or(std::path::Path::new(""));
    let mut carried = settings.relative_to(out_folder);
    carried.view = view;
    let text =
        raylab_core::files::settings_file::settings_text(&carried).map_err(anyhow::Error::msg)?;
    let scene_text = match &args.save_scene {
        Some(path) => {
            let folder = path.parent().unwrap_or(std::path::Path::new(""));
            let text = raylab_core::files::scene_file::to_text(&settings, folder)
                .map_err(|reason| anyhow::anyhow!("--save-scene '{}': {reason}", path.display()))?;
            Some((path, text))
        }
        None => None,
    };
    let pool = thread_pool("render", args.options.threads)?;

    let choice = &settings.scene;
    let (scene, warnings) = pool.install(|| choice.load_with_warnings())?;
    for warning in warnings {
        print_error_line(&format!("warning: {warning}"));
    }
    let start = Instant::now();
    let mut denoised_note = None;
    // With --equations: the pixels that came out NaN or infinite, and the share of pixels
    // within 2/255 of the exact figure.
    let mut sandbox_figures = None;
    let (image, display, legend) = if let Some(written) = &equations {
        let yours =
            pool.install(|| raylab_core::teaching::sandbox::render(&scene, &settings, written));
        let figure = pool.install(|| try_render(&scene, &settings))?;
        let share = raylab_core::teaching::check::compare::share_within(
            &raylab_core::teaching::check::Rgb8::from_linear(&yours.image),
            &raylab_core::teaching::check::Rgb8::from_linear(&figure),
        );
        sandbox_figures = Some((yours.non_finite, share));
        (yours.image, settings.display, None)
    } else {
        match view {
            raylab_core::transport::view::View::Shaded if settings.denoise => {
                let (raw, denoised) = pool.install(|| {
                    raylab_core::transport::denoise::render_denoised(&scene, &settings)
                });
                denoised_note = Some(if denoised.is_some() {
                    "denoised (the accumulated image filtered by the denoiser; --denoise off writes \
                 the unbiased estimate)"
                } else {
                    "not denoised: nothing in this render is noisy (no path tracing, soft shadows \
                 or depth of field)"
                });
                (denoised.unwrap_or(raw), settings.display, None)
            }
            raylab_core::transport::view::View::Shaded => (
                pool.install(|| try_render(&scene, &settings))?,
                settings.display,
                None,
            ),
            view @ (View::Normals
            | View::Depth
            | View::Barycentric
            | View::Triangle
            | View::BvhCost
            | View::Shadow
            | View::Variance
            | View::Photons) => {
                let v = pool.install(|| {
                    raylab_core::transport::view::render_view(&scene, &settings, view, &|| false)
                })?;
                (v.image, Display::default(), Some(v.legend))
            }
        }
    };
    let elapsed = start.elapsed();
    // A PNG carries its settings, so the image alone reopens to the same render.
    let keyword = raylab_core::files::settings_file::PNG_KEYWORD;
    image.save_with_text(&args.out, &display, Some((keyword, &text)))?;
    let saved_scene = match scene_text {
        Some((path, text)) => Some(save_scene_file(path, &text)?),
        None => None,
    };
    if let Some(note) = raylab_core::transport::render::camera_sees_nothing(&scene, &settings) {
        // A black image the camera is to blame for: say so (the image is written all the same).
        print_error_line(&format!("note: {note}"));
    }

    let c = &settings.camera;
    let summary = format!(
        "rendered {} {}×{} (field of view {:.1}° × {:.1}°, {}{}, {} spp) in {:.1} ms on {} threads → {}",
        choice,
        c.width,
        c.height,
        c.horizontal_fov_degrees(),
        c.vertical_fov_degrees(),
        settings.shading.stage,
        match settings.material_preset {
            MaterialPreset::None => String::new(),
            preset => format!(", {preset} preset"),
        },
        settings.samples_per_pixel,
        elapsed.as_secs_f64() * 1e3,
        pool.current_num_threads(),
        args.out.display()
    );
    let mut text = summary + "\n";
    if let Some(note) = denoised_note {
        text += &format!("{note}\n");
    }
    if let Some((path, asked)) = &saved_scene
        && path != asked
    {
        text += &format!(
            "scene file → {} ('{}' exists, and is left as it is)\n",
            path.display(),
            asked.display()
        );
    }
    if let (Some((non_finite, share)), Some(written)) = (sandbox_figures, &equations) {
        text += &equations_text(written, settings.shading.stage, non_finite, share);
    }
    if let Some(legend) = legend {
        text += &format!("{} view:\n", legend.title);
        for line in &legend.lines {
            text += &format!("  {line}\n");
        }
    }
    // The image is written: a reader that went away (`| head`, `| true`) is no failure, and
    // nothing may panic on a stdout that cannot be written (`> /dev/full`).
    let text = printable_lines(&text);
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(anyhow::anyhow!(
            "wrote '{}', but could not print the summary: {e}",
            args.out.display()
        )),
    }
}

/// What `--equations` found, a line each: the match with the exact figure, the pixels that
/// came out NaN or infinite (magenta), and each written quantity's verdict.
pub(super) fn equations_text(
    written: &raylab_core::teaching::sandbox::Equations,
    stage: Stage,
    non_finite: usize,
    share: f64,
) -> String {
    let mut text = format!(
        "your equations: {:.1} % of pixels within 2/255 of the exact figure\n",
        share * 100.0
    );
    if non_finite > 0 {
        text += &format!("{non_finite} pixels came out NaN or infinite (shown magenta)\n");
    }
    let verdicts = equations::verdicts(written, stage);
    if verdicts.is_empty() {
        text += "no quantity written: the image is the lab's own\n";
    }
    for (quantity, verdict) in verdicts {
        text += &format!("{}: {verdict}\n", quantity.name());
    }
    text
}

/// Writes `--save-scene`'s text at `path`, or, if a file is there (the scene file the render
/// was read from, or any other), at the first free name `NAME-1.toml`, `NAME-2.toml`, … as
/// screenshots are named: an existing file is never replaced. Returns the path written and
/// the one asked for.
pub(super) fn save_scene_file(
    path: &std::path::Path,
    text: &str,
) -> anyhow::Result<(std::path::PathBuf, std::path::PathBuf)> {
    let written = raylab_core::transport::film::write_to_free_name(path, text.as_bytes()).map_err(
        |e| match e {
            raylab_core::transport::film::SaveError::Write { path, reason } => {
                anyhow::anyhow!("could not write scene file '{}': {reason}", path.display())
            }
            other => anyhow::Error::new(other),
        },
    )?;
    Ok((written, path.to_path_buf()))
}

/// `--save-scene`'s file: a `.toml` in a folder that exists and takes new files (checked by
/// creating one). A file already there is not replaced ([`save_scene_file`] picks a free name).
pub(super) fn check_scene_destination(path: &std::path::Path) -> anyhow::Result<()> {
    let toml = path
        .extension()
        .is_some_and(|e| e == raylab_core::files::scene_file::EXTENSION);
    if !toml {
        anyhow::bail!(
            "--save-scene '{}': a scene file's name ends in .toml",
            path.display()
        );
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        anyhow::bail!(
            "could not write scene file '{}': folder '{}' does not exist",
            path.display(),
            dir.display()
        );
    }
    raylab_core::transport::film::check_file_destination(path).map_err(|e| match e {
        raylab_core::transport::film::SaveError::Write { reason, .. } => {
            anyhow::anyhow!("could not write scene file '{}': {reason}", path.display())
        }
        other => anyhow::Error::new(other),
    })
}
