//! `--equations FILE` for `render` and `check`: a student's own quantities (`d`, `shadowStart`,
//! `shadowed`, `D`, `R`), written as `NAME = EXPRESSION` lines, rendered by the equation
//! sandbox in place of the lab's, compared with the exact figure and judged term by term.

use std::path::Path;

use raylab_core::shading::light::LightKind;
use raylab_core::shapes::scene::Scene;
use raylab_core::teaching::sandbox::{
    self, Equations, Explanation, MAX_SOURCE_BYTES, Quantity, SandboxError,
};
use raylab_core::transport::settings::EquationTexts;
use raylab_core::transport::view::View;
use raylab_core::{RenderSettings, Stage};

/// Reads and compiles the equations in `path`; a text that does not compile is refused with
/// every error as `FILE:LINE:COLUMN: message`, the line and a caret under the offending text.
pub fn read(path: &Path) -> anyhow::Result<Equations> {
    read_with_text(path).map(|(equations, _)| equations)
}

/// [`read`], with a text per quantity as the settings carry them (a screenshot, a scene file).
pub fn read_texts(path: &Path) -> anyhow::Result<EquationTexts> {
    let (equations, text) = read_with_text(path)?;
    sandbox::carried::split(&text, &equations)
        .map_err(|e| anyhow::anyhow!("--equations '{}': {e}", path.display()))
}

fn read_with_text(path: &Path) -> anyhow::Result<(Equations, String)> {
    let size = std::fs::metadata(path)
        .map_err(|e| anyhow::anyhow!("--equations '{}': {e}", path.display()))?
        .len();
    if size > MAX_SOURCE_BYTES as u64 {
        anyhow::bail!(
            "--equations '{}' is {size} bytes; equations are at most {MAX_SOURCE_BYTES} bytes",
            path.display()
        );
    }
    let bytes = std::fs::read(path)
        .map_err(|e| anyhow::anyhow!("--equations '{}': {e}", path.display()))?;
    let text = String::from_utf8(bytes).map_err(|_| {
        anyhow::anyhow!(
            "--equations '{}' is not UTF-8 text: save it as plain text",
            path.display()
        )
    })?;
    match sandbox::compile(&text) {
        Ok(equations) => Ok((equations, text)),
        Err(errors) => Err(CompileErrors(describe(path, &text, &errors)).into()),
    }
}

/// Equations that do not compile: every error with its line and caret, several lines of text
/// (printed line by line, each made safe for a terminal).
#[derive(Debug)]
pub struct CompileErrors(pub String);

impl std::fmt::Display for CompileErrors {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CompileErrors {}

/// The errors as a compiler prints them: a location, the message, the line and a caret.
fn describe(path: &Path, text: &str, errors: &[SandboxError]) -> String {
    let mut out = String::new();
    for (i, e) in errors.iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&format!(
            "error: {}:{}:{}: {}",
            path.display(),
            e.line,
            e.column,
            e.message
        ));
        // The caret runs under the span's characters on its first line (at least one).
        let Some(before_span) = text.get(..e.span.start.min(text.len())) else {
            continue;
        };
        let line_start = before_span.rfind('\n').map_or(0, |i| i + 1);
        let rest = &text[line_start..];
        let line = rest[..rest.find('\n').unwrap_or(rest.len())].trim_end_matches('\r');
        let start = (before_span.len() - line_start).min(line.len());
        let end = e
            .span
            .end
            .saturating_sub(line_start)
            .clamp(start, line.len());
        let before = line.get(..start).map_or(0, |s| s.chars().count());
        let under = line.get(start..end).map_or(1, |s| s.chars().count().max(1));
        out.push_str(&format!(
            "\n  {line}\n  {}{}",
            " ".repeat(before),
            "^".repeat(under)
        ));
    }
    out
}

/// Refuses what the sandbox does not compute: it is the lab's loop (one ray through each
/// pixel's centre, the lab's stages, a point light, the shaded image).
pub fn refuse_unless_lab(settings: &RenderSettings, view: View) -> anyhow::Result<()> {
    let stage = settings.shading.stage;
    if !Stage::LAB.contains(&stage) {
        anyhow::bail!(
            "--equations computes the lab's stages (figures 2, 3, 5, 6 and 7), not {stage}: \
             give --stage with one of them"
        );
    }
    if view != View::Shaded {
        anyhow::bail!("--equations writes the shaded image: leave out --view");
    }
    if settings.samples_per_pixel > 1 {
        anyhow::bail!(
            "--equations traces one ray through each pixel's centre, as the lab's loop does: \
             leave out --samples"
        );
    }
    // The lab's point light, and no other kind.
    if !matches!(settings.light.kind, LightKind::Point) {
        anyhow::bail!(
            "--equations uses the lab's point light (lightPos, lightColor): leave out \
             --light-shape"
        );
    }
    Ok(())
}

/// Each written quantity and how it compares with the lab's at random inputs, a line each.
pub fn verdicts(equations: &Equations, stage: Stage) -> Vec<(Quantity, String)> {
    Quantity::ALL
        .into_iter()
        .filter_map(|q| Some((q, sandbox::judge(equations, q, stage)?.to_string())))
        .collect()
}

/// Pixel `(x, y)` of the image `equations` render explained: each quantity's value beside the
/// lab's, every part of the text with its value (`None` outside the image).
pub fn explain(
    scene: &Scene,
    settings: &RenderSettings,
    equations: &Equations,
    x: u32,
    y: u32,
) -> Option<Explanation> {
    sandbox::record(scene, settings, equations).explain(equations, x, y)
}
