//! A whole class checked at once: every submission of a folder (or a list of files) checked
//! as [`super::check`] checks one, each against its own settings.
//!
//! [`run`] goes over the submissions twice. First, in parallel, each is read and decoded, the
//! hash of its pixels taken (identical images handed in by different students are flagged)
//! and the settings it is checked against found. Then, for each distinct settings in turn, the
//! figures ([`Figures`]: the exact one and every mistake's) are rendered once, and the
//! submissions against them are read again and judged in parallel: a class of two hundred
//! against one figure renders it once, and holds no more than the figures and an image a
//! thread. Nothing a submission is stops the run: an unreadable, empty, truncated, wrong-size
//! or non-image file becomes a row with its reason.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::compare::Rgb8;
use super::{Figures, Report, check_settings, read_image, read_image_encoded, ssim};
use crate::shapes::scene::{Scene, SceneChoice};
use crate::transport::settings::RenderSettings;

/// A file handed in.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Submission {
    pub path: PathBuf,
    /// Its name in the report: its path below the folder given (`/` between the parts), or
    /// the path as given.
    pub name: String,
    /// Who handed it in: below a folder, the first part of its name (a student's folder, or
    /// a file's name without its extension); a file given alone, its name without extension.
    pub student: String,
}

/// The submissions in `paths`: each folder's files, found in its subfolders too (hidden
/// entries, those starting with `.`, and `leave_out` skipped: the report's own folder, the
/// list of submissions), and each other path as it is (if it cannot be read, its row says
/// so). Sorted by name. A folder that cannot be listed is an error.
pub fn submissions(paths: &[PathBuf], leave_out: &[PathBuf]) -> Result<Vec<Submission>, String> {
    let leave_out: Vec<PathBuf> = leave_out
        .iter()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    let mut found = Vec::new();
    for path in paths {
        if path.is_dir() {
            let before = found.len();
            walk(path, path, &leave_out, &mut found)?;
            if found.len() == before {
                return Err(format!("'{}' holds no files to check", path.display()));
            }
        } else {
            let student = stem(path);
            found.push(Submission {
                path: path.clone(),
                name: path.display().to_string(),
                student,
            });
        }
    }
    found.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(found)
}

/// A file's name without its extension.
fn stem(path: &Path) -> String {
    path.file_stem().map_or_else(
        || path.display().to_string(),
        |s| s.to_string_lossy().into(),
    )
}

fn walk(
    root: &Path,
    folder: &Path,
    leave_out: &[PathBuf],
    found: &mut Vec<Submission>,
) -> Result<(), String> {
    let entries = std::fs::read_dir(folder)
        .map_err(|e| format!("could not list folder '{}': {e}", folder.display()))?;
    for entry in entries {
        let entry =
            entry.map_err(|e| format!("could not list folder '{}': {e}", folder.display()))?;
        let path = entry.path();
        if entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        if std::fs::canonicalize(&path).is_ok_and(|p| leave_out.contains(&p)) {
            continue;
        }
        // A link to a folder is not followed (it could lead back up).
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir {
            walk(root, &path, leave_out, found)?;
            continue;
        }
        let below = path.strip_prefix(root).unwrap_or(&path);
        let parts: Vec<String> = below
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let student = if parts.len() > 1 {
            parts[0].clone()
        } else {
            stem(below)
        };
        found.push(Submission {
            path,
            name: parts.join("/"),
            student,
        });
    }
    Ok(())
}

/// What a submission is checked against: the settings for a submission whose image is
/// `width × height`, or the reason there are none (a line of a list that cannot be read,
/// sides that are not the image's).
pub type Against<'a> = dyn Fn(&Submission, u32, u32) -> Result<RenderSettings, String> + Sync + 'a;

/// What became of a submission.
#[derive(Clone, Debug)]
pub struct Row {
    pub submission: Submission,
    /// The settings it was checked against: an index into [`Class::against`].
    pub against: Option<usize>,
    /// The check, or why there is none.
    pub result: Result<Judged, String>,
    /// The names of the other students' submissions whose pixels are the same as its own.
    pub identical_to: Vec<String>,
}

/// A submission's check.
#[derive(Clone, Debug)]
pub struct Judged {
    /// As `raylab check --json` reports it.
    pub report: Report,
    /// How visible its difference from the exact figure is: the SSIM of the two
    /// ([`ssim::ssim`]), 1 for no difference.
    pub ssim: f64,
}

impl Row {
    /// The verdict: a mistake's name, `none` or `unknown`; `refused` for a submission that
    /// could not be checked.
    pub fn verdict(&self) -> &str {
        match &self.result {
            Ok(j) => &j.report.best.mistake,
            Err(_) => REFUSED,
        }
    }
}

/// The verdict of a submission that could not be checked.
pub const REFUSED: &str = "refused";

/// A class checked: a row for each submission, in order of name, and the distinct settings
/// they were checked against.
#[derive(Clone, Debug)]
pub struct Class {
    pub rows: Vec<Row>,
    pub against: Vec<RenderSettings>,
}

/// What is kept of a class as it is checked, beyond its rows: the report's images. Called from
/// the checking threads, and only while the images are in memory.
pub trait Keep: Sync {
    /// The figures for [`Class::against`]`[against]`, once rendered.
    fn figures(&self, against: usize, figures: &Figures);
    /// The image of row `row`, once judged against `figures`.
    fn image(&self, row: usize, image: &Rgb8, figures: &Figures);
}

/// Keeps nothing.
impl Keep for () {
    fn figures(&self, _: usize, _: &Figures) {}
    fn image(&self, _: usize, _: &Rgb8, _: &Figures) {}
}

/// The hash of an image's decoded pixels (and its size): equal images, whatever their files'
/// formats, hash the same. 64 bits: two different images among a class of thousands share
/// one with a chance near 10⁻¹³.
fn pixel_hash(image: &Rgb8) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (image.width, image.height).hash(&mut h);
    image.data.hash(&mut h);
    h.finish()
}

/// Checks every submission (see the module docs), each against what `against` says, on the
/// current rayon pool. `progress(done, total)` is called as rows are finished.
pub fn run(
    submissions: Vec<Submission>,
    against: &Against,
    keep: &dyn Keep,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Class {
    let total = submissions.len();
    // First pass: read, hash, and the settings each is checked against.
    let first: Vec<Result<(u64, RenderSettings), String>> = submissions
        .par_iter()
        .map(|s| {
            let image = read_image(&s.path).map_err(|e| e.reason)?;
            let settings = against(s, image.width, image.height)?;
            check_settings(&settings).map_err(|e| e.to_string())?;
            super::same_size(&settings, &image).map_err(|e| e.to_string())?;
            Ok((pixel_hash(&image), settings))
        })
        .collect();
    let mut distinct: Vec<RenderSettings> = Vec::new();
    let mut rows: Vec<Row> = Vec::with_capacity(total);
    let mut hashes: Vec<Option<u64>> = Vec::with_capacity(total);
    for (submission, found) in submissions.into_iter().zip(first) {
        let (against, result, hash) = match found {
            Ok((hash, settings)) => {
                let k = match distinct.iter().position(|d| d.renders_like(&settings)) {
                    Some(k) => k,
                    None => {
                        distinct.push(settings);
                        distinct.len() - 1
                    }
                };
                (Some(k), Err(String::new()), Some(hash))
            }
            Err(reason) => (None, Err(reason), None),
        };
        rows.push(Row {
            submission,
            against,
            result,
            identical_to: Vec::new(),
        });
        hashes.push(hash);
    }
    flag_identical(&mut rows, &hashes);
    let done = AtomicUsize::new(rows.iter().filter(|r| r.against.is_none()).count());
    progress(done.load(Ordering::Relaxed), total);

    // Second pass: the figures of each settings once, and the submissions against them.
    let mut scene: Option<(SceneChoice, Result<Scene, String>)> = None;
    for (k, settings) in distinct.iter().enumerate() {
        let members: Vec<usize> = (0..rows.len())
            .filter(|&i| rows[i].against == Some(k))
            .collect();
        if scene.as_ref().is_none_or(|(c, _)| *c != settings.scene) {
            let loaded = settings.scene.load().map_err(|e| e.to_string());
            scene = Some((settings.scene.clone(), loaded));
        }
        let figures = match &scene {
            Some((_, Ok(scene))) => render_figures(scene, settings),
            Some((_, Err(e))) => Err(e.clone()),
            None => unreachable!("loaded above"),
        };
        let figures = match figures {
            Ok(f) => f,
            Err(reason) => {
                for &i in &members {
                    rows[i].result = Err(reason.clone());
                }
                done.fetch_add(members.len(), Ordering::Relaxed);
                progress(done.load(Ordering::Relaxed), total);
                continue;
            }
        };
        keep.figures(k, &figures);
        let judged: Vec<Result<Judged, String>> = members
            .par_iter()
            .map(|&i| {
                let result = judge(&rows[i].submission, &figures, i, keep);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                result
            })
            .collect();
        for (&i, result) in members.iter().zip(judged) {
            rows[i].result = result;
        }
    }
    Class {
        rows,
        against: distinct,
    }
}

/// The figures for `settings`, or why they cannot be rendered (the memory they need).
fn render_figures(scene: &Scene, settings: &RenderSettings) -> Result<Figures, String> {
    let c = &settings.camera;
    crate::base::memory::check(
        format!("checking {}×{} images", c.width, c.height),
        super::memory_estimate(c.width, c.height) + settings.scene.memory_estimate(),
    )
    .map_err(|e| e.to_string())?;
    Figures::render(scene, settings).map_err(|e| e.to_string())
}

/// A submission read again and judged against `figures`.
fn judge(
    submission: &Submission,
    figures: &Figures,
    row: usize,
    keep: &dyn Keep,
) -> Result<Judged, String> {
    let (image, encoding) = read_image_encoded(&submission.path).map_err(|e| e.reason)?;
    let report = figures
        .judge_encoded(&image, encoding)
        .map_err(|e| e.to_string())?;
    let ssim = ssim::ssim(&image, &figures.figure);
    keep.image(row, &image, figures);
    Ok(Judged { report, ssim })
}

/// Fills each row's [`Row::identical_to`]: the other students' submissions of the same hash.
fn flag_identical(rows: &mut [Row], hashes: &[Option<u64>]) {
    let mut by_hash: HashMap<u64, Vec<usize>> = HashMap::new();
    for (i, h) in hashes.iter().enumerate() {
        if let Some(h) = h {
            by_hash.entry(*h).or_default().push(i);
        }
    }
    for same in by_hash.values().filter(|s| s.len() > 1) {
        for &i in same {
            let others: Vec<String> = same
                .iter()
                .filter(|&&j| rows[j].submission.student != rows[i].submission.student)
                .map(|&j| rows[j].submission.name.clone())
                .collect();
            rows[i].identical_to = others;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder's files are found in its subfolders too, hidden ones and those left out
    /// skipped, named below the folder, each with its student.
    #[test]
    fn submissions_are_found_and_named() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(d.join("carol/out")).unwrap();
        std::fs::create_dir_all(d.join("report")).unwrap();
        for f in [
            "bob.png",
            "alice.bmp",
            ".DS_Store",
            "carol/out/a.png",
            "carol/b.ppm",
        ] {
            std::fs::write(d.join(f), b"x").unwrap();
        }
        std::fs::write(d.join("report/index.html"), b"x").unwrap();
        let found = submissions(&[d.to_path_buf()], &[d.join("report")]).unwrap();
        let named: Vec<(&str, &str)> = found
            .iter()
            .map(|s| (s.name.as_str(), s.student.as_str()))
            .collect();
        assert_eq!(
            named,
            [
                ("alice.bmp", "alice"),
                ("bob.png", "bob"),
                ("carol/b.ppm", "carol"),
                ("carol/out/a.png", "carol"),
            ]
        );
        let e = submissions(&[d.join("report")], &[d.join("report/index.html")]).unwrap_err();
        assert!(e.contains("holds no files"), "{e}");
        // A file given alone, whether or not it exists: its row will say.
        let alone = submissions(&[d.join("missing.png")], &[]).unwrap();
        assert_eq!(alone[0].student, "missing");
    }

    /// Identical pixels are flagged between students, not within one student's files.
    #[test]
    fn identical_images_of_different_students_are_flagged() {
        let row = |name: &str, student: &str| Row {
            submission: Submission {
                path: PathBuf::from(name),
                name: name.into(),
                student: student.into(),
            },
            against: Some(0),
            result: Err(String::new()),
            identical_to: Vec::new(),
        };
        let mut rows = vec![
            row("a.png", "a"),
            row("b.png", "b"),
            row("c/1.png", "c"),
            row("c/2.png", "c"),
            row("d.png", "d"),
        ];
        flag_identical(&mut rows, &[Some(1), Some(1), Some(2), Some(2), None]);
        let flagged: Vec<Vec<String>> = rows.iter().map(|r| r.identical_to.clone()).collect();
        assert_eq!(
            flagged,
            [vec!["b.png"], vec!["a.png"], vec![], vec![], vec![]]
        );
        let image = Rgb8 {
            width: 1,
            height: 2,
            data: vec![1, 2, 3, 4, 5, 6],
        };
        let other = Rgb8 {
            width: 2,
            height: 1,
            ..image.clone()
        };
        assert_ne!(pixel_hash(&image), pixel_hash(&other), "the size counts");
    }
}
