//! `raylab inspect`: one pixel's computation beside the lab's equations.

use std::io::Write as _;
use std::path::PathBuf;

use super::equations;
use super::options::RenderOptions;
use super::parse::{Pixel, parse_on_off, parse_pixel};
use super::pool::thread_pool;
use super::terminal::printable_lines;
use anyhow::Context as _;
use clap::Args;
use raylab_core::teaching::inspect::{InspectError, inspect_pixel};
use raylab_core::transport::view::View;

#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The pixel to explain, from the top-left corner: 0 ≤ X < width, 0 ≤ Y < height.
    #[arg(long, value_parser = parse_pixel, value_name = "X,Y", allow_hyphen_values = true)]
    pub pixel: Pixel,
    /// Print one JSON object (every value the tracer computed) instead of the explanation.
    #[arg(long)]
    pub json: bool,
    /// on: also the pixel's denoised value (the whole image is rendered and denoised, as
    /// `render --denoise on` writes it), printed beside the traced one.
    #[arg(long, default_value = "off", value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
    pub denoise: bool,
    /// Your own equations (see render's --equations): also the pixel of the image they render,
    /// each quantity's value beside the lab's and every part of your text with its value there.
    #[arg(long, value_name = "FILE", conflicts_with = "denoise")]
    pub equations: Option<PathBuf>,
    #[command(flatten)]
    pub options: RenderOptions,
}

pub(super) fn run_inspect(args: &InspectArgs) -> anyhow::Result<()> {
    let written = args.equations.as_deref().map(equations::read).transpose()?;
    let settings = args.options.resolve_settings()?;
    settings.validate()?;
    if written.is_some() {
        equations::refuse_unless_lab(&settings, View::Shaded)?;
    }
    let Pixel(x, y) = args.pixel;
    let (width, height) = (settings.camera.width, settings.camera.height);
    // Refused before the scene is loaded (a large model takes a while).
    if x >= width || y >= height {
        return Err(anyhow::Error::new(InspectError::OutsideImage {
            x,
            y,
            width,
            height,
        })
        .context(format!("--pixel {x},{y}")));
    }
    // Refused before the scene is loaded if it cannot fit: inspecting holds the scene (its
    // models and textures), not the image.
    raylab_core::base::memory::check(
        format!("inspecting a pixel of {}", settings.scene.name()),
        settings.scene.memory_estimate() + raylab_core::transport::settings::BASE_MEMORY,
    )?;
    let pool = thread_pool("inspect", args.options.threads)?;
    let scene = pool.install(|| settings.scene.load())?;
    let inspection =
        inspect_pixel(&scene, &settings, x, y).with_context(|| format!("--pixel {x},{y}"))?;
    // Inside the image (checked above), so explained wherever equations are given.
    let explained = written
        .as_ref()
        .and_then(|w| pool.install(|| equations::explain(&scene, &settings, w, x, y)));
    // The denoised value needs the whole image, rendered and denoised as `render --denoise
    // on` writes it (`None` where nothing is noisy).
    let denoised = if args.denoise || settings.denoise {
        let c = &settings.camera;
        raylab_core::base::memory::check(
            format!("denoising a {}×{} render", c.width, c.height),
            settings
                .memory_estimate(raylab_core::transport::view::View::Shaded)
                .saturating_add(208 * u64::from(c.width) * u64::from(c.height)),
        )?;
        let (_, denoised) =
            pool.install(|| raylab_core::transport::denoise::render_denoised(&scene, &settings));
        Some(denoised.map(|d| d.get(x, y)))
    } else {
        None
    };
    // Written with `write!` so that a closed pipe is an error, not a panic.
    let mut out = std::io::stdout().lock();
    if args.json {
        let mut json = serde_json::to_value(&inspection)?;
        if let (Some(denoised), Some(object)) = (denoised, json.as_object_mut()) {
            object.insert(
                "denoised".to_owned(),
                denoised.map_or(serde_json::Value::Null, |d| {
                    serde_json::json!([d.x, d.y, d.z])
                }),
            );
        }
        if let (Some(explained), Some(object)) = (&explained, json.as_object_mut()) {
            object.insert("equations".to_owned(), serde_json::to_value(explained)?);
        }
        writeln!(out, "{json}")?;
    } else {
        write!(out, "{}", printable_lines(&inspection.to_text()))?;
        if let Some(explained) = &explained {
            writeln!(out, "\nYour equations at this pixel:")?;
            write!(out, "{}", printable_lines(&explained.to_text()))?;
        }
        match denoised {
            Some(Some(d)) => writeln!(
                out,
                "denoised: ({:.6}, {:.6}, {:.6}) (the whole image denoised, as render --denoise \
                 on writes it; the value above is the traced one)",
                d.x, d.y, d.z
            )?,
            Some(None) => writeln!(
                out,
                "denoised: the same (nothing in this render is noisy: no path tracing, soft \
                 shadows or depth of field)"
            )?,
            None => {}
        }
    }
    Ok(())
}
