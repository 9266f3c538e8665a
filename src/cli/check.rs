//! `raylab check`: a student's render (or equations) against the exact figure, and the
//! classic mistake that explains the difference.

mod class;

use std::io::Write as _;
use std::path::PathBuf;

use super::equations;
use super::options::{DEFAULT_SIDE, RenderOptions, SETTINGS_OPTIONS};
use super::overwrite::{files_read, refuse_output_onto};
use super::pool::thread_pool;
use super::terminal::printable_lines;
use clap::Args;
use raylab_core::RenderSettings;
use raylab_core::transport::film::OutputFormat;
use raylab_core::transport::view::View;

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Your render: PNG, BMP (what SDL saves), PPM or JPEG, 8 bits a channel, any size. Or a
    /// class: a folder of renders (its subfolders too: a folder a student) or several files,
    /// each checked, a line each; see --report.
    #[arg(value_name = "IMAGE|FOLDER", required_unless_present = "equations", num_args = 1..)]
    pub images: Vec<PathBuf>,
    /// Check your own equations instead of an image: the image they render (see render's
    /// --equations) is checked against the exact figure, naming the classic mistake that
    /// explains it, and each quantity written is judged against the lab's at random inputs.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["images", "report", "csv", "screenshot_settings", "diff_out"])]
    pub equations: Option<PathBuf>,
    /// Print one JSON object (the match, the verdict and every candidate mistake, best first)
    /// instead of the report; for a class, report.json's.
    #[arg(long)]
    pub json: bool,
    /// Also write the difference picture: |yours − figure| per channel, amplified 8×, black
    /// where they agree (a PNG). One image only.
    #[arg(long, value_name = "FILE.png")]
    pub diff_out: Option<PathBuf>,
    /// A class: write its report to this folder (made if needed): index.html, a page to open
    /// in the browser (a row a submission, the verdicts' histogram, filters, a detail view a
    /// student with an A/B wipe), report.csv, report.json and the images they show.
    #[arg(long, value_name = "FOLDER")]
    pub report: Option<PathBuf>,
    /// With --report: also Gradescope's results.json for each student, in
    /// gradescope/STUDENT/ (a test an image, scored when it is the exact figure).
    #[arg(long, requires = "report")]
    pub gradescope: bool,
    /// A class: what each submission is checked against, from a CSV list: a header line with
    /// `file` (its name below the folder) and any options of this command without `--`
    /// (stage, yaw, light, shadows, indirect, width, height, settings, …), then a line a
    /// submission; an empty cell is the option's default. A file not listed is not checked.
    #[arg(long, value_name = "FILE.csv", conflicts_with_all = SETTINGS_OPTIONS, conflicts_with = "settings", conflicts_with = "scene_file")]
    pub csv: Option<PathBuf>,
    /// A class: each PNG carrying a workbench screenshot's settings is checked against them;
    /// the others against the options given.
    #[arg(long)]
    pub screenshot_settings: bool,
    /// The settings your image was rendered with: the stage, camera, light, --shadows and
    /// --indirect as for render. --width and --height are the image's.
    #[command(flatten)]
    pub options: RenderOptions,
}

/// `check --equations FILE`: the image the student's equations render, checked as their
/// image would be, and each quantity judged.
pub(super) fn check_equations(args: &CheckArgs, path: &std::path::Path) -> anyhow::Result<()> {
    use raylab_core::teaching::check;
    let written = equations::read(path)?;
    let settings = args.options.resolve_settings()?;
    equations::refuse_unless_lab(&settings, View::Shaded)?;
    check::check_settings(&settings)?;
    let c = &settings.camera;
    raylab_core::base::memory::check(
        format!("checking a {}×{} image", c.width, c.height),
        check::memory_estimate(c.width, c.height) + settings.scene.memory_estimate(),
    )?;
    let pool = thread_pool("check", args.options.threads)?;
    let (checked, rendered) = pool.install(|| -> anyhow::Result<_> {
        let scene = settings.scene.load()?;
        let rendered = raylab_core::teaching::sandbox::render(&scene, &settings, &written);
        let image = check::Rgb8::from_linear(&rendered.image);
        Ok((check::check(&scene, &settings, &image)?, rendered))
    })?;
    let verdicts = equations::verdicts(&written, settings.shading.stage);
    let mut out = std::io::stdout().lock();
    if args.json {
        let quantities: serde_json::Map<String, serde_json::Value> = verdicts
            .iter()
            .map(|(q, v)| (q.name().to_string(), serde_json::Value::from(v.as_str())))
            .collect();
        let json = serde_json::json!({
            "check": checked.report,
            "non_finite_pixels": rendered.non_finite,
            "quantities": quantities,
        });
        writeln!(out, "{json}")?;
    } else {
        write!(out, "{}", printable_lines(&checked.report.to_text()))?;
        if rendered.non_finite > 0 {
            writeln!(
                out,
                "{} pixels came out NaN or infinite (shown magenta)",
                rendered.non_finite
            )?;
        }
        for (quantity, verdict) in verdicts {
            writeln!(out, "{}: {}", quantity.name(), printable_lines(&verdict))?;
        }
    }
    Ok(())
}

pub(super) fn run_check(args: &CheckArgs) -> anyhow::Result<()> {
    use raylab_core::teaching::check;
    if let Some(path) = &args.equations {
        return check_equations(args, path);
    }
    if class::is_class(args) {
        return class::run(args);
    }
    let path = &args.images[0];
    if let Some(path) = &args.diff_out {
        if OutputFormat::from_path(path)? != OutputFormat::Png {
            anyhow::bail!(
                "--diff-out '{}': the difference picture is written as PNG (.png)",
                path.display()
            );
        }
        raylab_core::transport::film::check_file_destination(path)?;
    }
    let (image, encoding) = check::read_image_encoded(path)?;
    // The figure at the image's size: settings from a file keep their own camera (a size
    // that differs is refused by name), the arguments get the image's width and height.
    let settings = if args.options.settings.is_some() || args.options.scene_file.is_some() {
        args.options.resolve_settings()?
    } else {
        settings_at_image_size(&args.options, path, image.width, image.height)?
    };
    if let Some(path) = &args.diff_out {
        let mut files = files_read(&args.options, &settings);
        files.push(raylab_core::base::inputs::Input::new(
            &args.images[0],
            "the image to check",
        ));
        refuse_output_onto("--diff-out", path, "the check", files)?;
    }
    check::check_settings(&settings)?;
    raylab_core::base::memory::check(
        format!("checking a {}×{} image", image.width, image.height),
        check::memory_estimate(image.width, image.height) + settings.scene.memory_estimate(),
    )?;
    let pool = thread_pool("check", args.options.threads)?;
    let checked = pool.install(|| -> anyhow::Result<check::Checked> {
        let scene = settings.scene.load()?;
        Ok(check::check_encoded(&scene, &settings, &image, encoding)?)
    })?;
    let gain = check::compare::difference_gain(&image, &checked.figure);
    if let Some(path) = &args.diff_out {
        check::compare::difference_picture_with_gain(&image, &checked.figure, gain)
            .to_image()
            .save(path)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        writeln!(out, "{}", serde_json::to_string(&checked.report)?)?;
    } else {
        write!(out, "{}", printable_lines(&checked.report.to_text()))?;
        if let Some(path) = &args.diff_out {
            writeln!(
                out,
                "difference picture: {} (|image − figure| × {gain:.1})",
                path.display()
            )?;
        }
    }
    Ok(())
}

/// The settings `options` (with no settings file) describe for the image at `path`, of
/// `width × height`: theirs at the image's size. Given sides other than the default must be
/// the image's (the default cannot be told from a typed 512, so it is taken as "the
/// image's").
pub(super) fn settings_at_image_size(
    options: &RenderOptions,
    path: &std::path::Path,
    width: u32,
    height: u32,
) -> anyhow::Result<RenderSettings> {
    for (name, given, actual) in [
        ("--width", options.width, width),
        ("--height", options.height, height),
    ] {
        if given != DEFAULT_SIDE && given != actual {
            anyhow::bail!(
                "{name} {given}: the image '{}' is {width}×{height}; the figure is rendered at \
                 the image's size, so --width and --height can be left out",
                path.display(),
            );
        }
    }
    // Resolved and validated as render and inspect resolve them: the same options mean the
    // same (waves asked of a scene with no water are refused).
    RenderOptions {
        width,
        height,
        ..options.clone()
    }
    .resolve_settings()
}
