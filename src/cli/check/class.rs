//! `raylab check FOLDER` (or several files): a class checked at once
//! ([`raylab_core::teaching::check::class`]), a line a submission on stdout, and with `--report OUT` the
//! report folder a teacher opens in the browser ([`raylab_core::teaching::check::report`]).
//!
//! What each submission is checked against, in turn: its line of `--csv FILE` (whose columns
//! are the check's own options), the settings its PNG carries (`--screenshot-settings`, for a
//! workbench screenshot), or the options given (or `--settings`) for all.

use std::collections::HashMap;
use std::io::{IsTerminal as _, Write as _};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use clap::{CommandFactory as _, Parser};
use raylab_core::RenderSettings;
use raylab_core::teaching::check::class::{self, Class, Submission};
use raylab_core::teaching::check::report::ReportFolder;

use super::{CheckArgs, settings_at_image_size};
use crate::cli::options::RenderOptions;
use crate::cli::pool::thread_pool;
use crate::cli::terminal::{one_line, printable_lines};

/// The options a line of `--csv` gives, parsed as the command line's are.
#[derive(Debug, Parser)]
#[command(name = "a line of the list")]
struct Listed {
    #[command(flatten)]
    options: RenderOptions,
}

/// The options that are no column of `--csv`: `threads` is the whole run's.
const NOT_LISTED: [&str; 2] = ["help", "threads"];

/// `--csv`: each listed file's options (its line's number and its cells), by name.
struct List {
    path: PathBuf,
    lines: HashMap<String, (usize, Vec<String>)>,
}

impl List {
    /// Reads the list: a header line with `file` and option names (as on the command line,
    /// without `--`), then a line a submission. An unknown column, a file listed twice or no
    /// `file` column is an error naming it.
    fn read(path: &Path) -> anyhow::Result<List> {
        let bytes = raylab_core::base::inputs::read_capped(
            path,
            raylab_core::base::inputs::MAX_SCENE_FILE_BYTES,
            "a list of submissions",
        )
        .map_err(|reason| anyhow::anyhow!("could not read '{}': {reason}", path.display()))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| anyhow::anyhow!("'{}' is not UTF-8 text", path.display()))?;
        let records = raylab_core::teaching::check::csv::parse(&text)
            .map_err(|e| anyhow::anyhow!("'{}': {e}", path.display()))?;
        let Some((header, rows)) = records.split_first() else {
            anyhow::bail!("'{}' is empty: it needs a header line", path.display());
        };
        let header: Vec<String> = header.iter().map(|h| h.trim().to_owned()).collect();
        let Some(file_column) = header.iter().position(|h| h == "file") else {
            anyhow::bail!(
                "'{}': its header has no 'file' column (the submission's name below the \
                 folder)",
                path.display()
            );
        };
        let known: Vec<String> = Listed::command()
            .get_arguments()
            .filter_map(|a| a.get_long().map(str::to_owned))
            .filter(|l| !NOT_LISTED.contains(&l.as_str()))
            .collect();
        for (i, h) in header.iter().enumerate() {
            if i != file_column && !known.contains(h) {
                anyhow::bail!(
                    "'{}': column '{h}' is not an option of a submission (the columns are file \
                     and any of: {})",
                    path.display(),
                    known.join(", ")
                );
            }
        }
        let mut lines = HashMap::new();
        for (k, cells) in rows.iter().enumerate() {
            let number = k + 2;
            let Some(file) = cells.get(file_column).map(|f| normal_name(f)) else {
                continue;
            };
            if file.is_empty() {
                anyhow::bail!("'{}' line {number}: no file named", path.display());
            }
            if lines.contains_key(&file) {
                anyhow::bail!(
                    "'{}' line {number}: '{file}' is listed twice",
                    path.display()
                );
            }
            let mut args = vec!["line".to_owned()];
            for (i, cell) in cells.iter().enumerate() {
                let cell = cell.trim();
                if i == file_column || cell.is_empty() || i >= header.len() {
                    continue;
                }
                let column = &header[i];
                // A settings file's path is relative to the list's folder.
                let value = if matches!(column.as_str(), "settings" | "scene-file" | "obj") {
                    let folder = path.parent().unwrap_or(Path::new(""));
                    folder.join(cell).display().to_string()
                } else {
                    cell.to_owned()
                };
                args.push(format!("--{column}={value}"));
            }
            lines.insert(file, (number, args));
        }
        Ok(List {
            path: path.to_path_buf(),
            lines,
        })
    }

    /// The options of the line of `submission`, or why there are none.
    fn options(&self, submission: &Submission) -> Result<RenderOptions, String> {
        let Some((number, args)) = self.lines.get(&normal_name(&submission.name)) else {
            return Err(format!("it is not listed in '{}'", self.path.display()));
        };
        Listed::try_parse_from(args)
            .map(|l| l.options)
            .map_err(|e| {
                let message = one_line(&e.render().to_string());
                let message = message.strip_prefix("error: ").unwrap_or(&message);
                format!("'{}' line {number}: {message}", self.path.display())
            })
    }
}

/// A file's name as listed: `\` as `/`, no leading `./`, no spaces around.
fn normal_name(name: &str) -> String {
    let name = name.trim().replace('\\', "/");
    name.strip_prefix("./").unwrap_or(&name).to_owned()
}

/// Whether `args` asks for a class rather than one image.
pub(super) fn is_class(args: &CheckArgs) -> bool {
    args.images.len() > 1
        || args.images[0].is_dir()
        || args.report.is_some()
        || args.csv.is_some()
        || args.screenshot_settings
}

/// The settings `options` give an image of `width × height`: those of their settings file,
/// or theirs at the image's size.
fn settings_of(
    options: &RenderOptions,
    path: &Path,
    width: u32,
    height: u32,
) -> anyhow::Result<RenderSettings> {
    if options.settings.is_some() || options.scene_file.is_some() {
        options.resolve_settings()
    } else {
        settings_at_image_size(options, path, width, height)
    }
}

/// A progress bar on stderr when it is a terminal: `checked 37 of 200 [=====     ]`.
struct Progress {
    shown: Mutex<usize>,
    terminal: bool,
}

impl Progress {
    fn new() -> Progress {
        Progress {
            shown: Mutex::new(usize::MAX),
            terminal: std::io::stderr().is_terminal(),
        }
    }

    fn update(&self, done: usize, total: usize) {
        if !self.terminal {
            return;
        }
        const WIDTH: usize = 30;
        let filled = (WIDTH * done).checked_div(total).unwrap_or(WIDTH);
        let mut shown = self.shown.lock().unwrap_or_else(|e| e.into_inner());
        if *shown == done {
            return;
        }
        *shown = done;
        let _ = write!(
            std::io::stderr(),
            "\rchecked {done} of {total} [{}{}]",
            "=".repeat(filled),
            " ".repeat(WIDTH - filled)
        );
        if done == total {
            let _ = writeln!(std::io::stderr());
        }
    }
}

/// `raylab check` on a class.
pub(super) fn run(args: &CheckArgs) -> anyhow::Result<()> {
    if args.diff_out.is_some() {
        anyhow::bail!(
            "--diff-out is for one image; a class's difference pictures are in --report's \
             images/ folder"
        );
    }
    let list = args.csv.as_deref().map(List::read).transpose()?;
    // One settings file for all is read once.
    let common = if list.is_none()
        && (args.options.settings.is_some() || args.options.scene_file.is_some())
    {
        Some(args.options.resolve_settings()?)
    } else {
        None
    };
    let report = args
        .report
        .as_deref()
        .map(ReportFolder::create)
        .transpose()
        .map_err(anyhow::Error::msg)?;
    let mut leave_out: Vec<PathBuf> = args.report.iter().cloned().collect();
    leave_out.extend(args.csv.iter().cloned());
    let submissions = class::submissions(&args.images, &leave_out).map_err(anyhow::Error::msg)?;

    let against = |s: &Submission, width: u32, height: u32| -> Result<RenderSettings, String> {
        let failed = |e: anyhow::Error| format!("{e:#}");
        if let Some(list) = &list {
            let options = list.options(s)?;
            return settings_of(&options, &s.path, width, height).map_err(failed);
        }
        if args.screenshot_settings {
            use raylab_core::files::settings_file::{ReadError, read_file};
            match read_file(&s.path) {
                Ok(loaded) => return Ok(loaded.settings),
                Err(ReadError::NoSettings { .. }) => {}
                // Not a PNG at all (a BMP, a PPM): checked as the others are.
                Err(ReadError::Invalid { .. }) if !is_png(&s.path) => {}
                Err(e) => return Err(e.to_string()),
            }
        }
        match &common {
            Some(settings) => Ok(settings.clone()),
            None => settings_of(&args.options, &s.path, width, height).map_err(failed),
        }
    };
    let pool = thread_pool("check", args.options.threads)?;
    let progress = Progress::new();
    let keep: &dyn class::Keep = match &report {
        Some(folder) => folder,
        None => &(),
    };
    let class = pool.install(|| {
        class::run(submissions, &against, keep, &|done, total| {
            progress.update(done, total)
        })
    });
    let title = match args.images.as_slice() {
        [one] if one.is_dir() => format!("Class check: {}", one.display()),
        many => format!("Class check: {} files", many.len()),
    };
    if let Some(folder) = &report {
        folder
            .finish(&class, &title, args.gradescope)
            .map_err(anyhow::Error::msg)?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        let json = raylab_core::teaching::check::report::json_value(&class, &title);
        writeln!(out, "{json}")?;
    } else {
        write!(out, "{}", printable_lines(&summary(&class)))?;
        if let Some(folder) = &report {
            writeln!(
                out,
                "report: {}",
                folder.root().join("index.html").display()
            )?;
        }
    }
    Ok(())
}

/// Whether the file at `path` starts with a PNG's signature.
fn is_png(path: &Path) -> bool {
    use std::io::Read as _;
    let mut start = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut start))
        .is_ok_and(|()| start == *raylab_core::files::settings_file::PNG_SIGNATURE)
}

/// A line a submission (its name, verdict, match and SSIM, or why it was not checked), then
/// the count of each verdict.
fn summary(class: &Class) -> String {
    let mut t = String::new();
    let width = class
        .rows
        .iter()
        .map(|r| r.submission.name.chars().count())
        .max()
        .unwrap_or(0)
        .min(48);
    for row in &class.rows {
        let name = &row.submission.name;
        match &row.result {
            Ok(j) => {
                t += &format!(
                    "{name:<width$}  {:<22} match {:>5.1} %  ssim {:.3}",
                    row.verdict(),
                    100.0 * j.report.match_share,
                    j.ssim
                );
            }
            Err(reason) => t += &format!("{name:<width$}  not checked: {reason}"),
        }
        if !row.identical_to.is_empty() {
            t += &format!("  (identical to {})", row.identical_to.join(", "));
        }
        t.push('\n');
    }
    let counts: Vec<String> = raylab_core::teaching::check::report::verdict_counts(class)
        .into_iter()
        .map(|(v, n)| format!("{n} {v}"))
        .collect();
    t += &format!("{} submissions: {}\n", class.rows.len(), counts.join(", "));
    t
}
