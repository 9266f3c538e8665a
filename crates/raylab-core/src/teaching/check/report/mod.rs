//! A checked class as a folder a teacher opens: `index.html` (the page, [`html`]), `report.csv`,
//! `report.json`, the images the page shows (`images/`: each submission, its difference from
//! the exact figure amplified [`DIFF_GAIN`](super::compare::DIFF_GAIN) times, thumbnails of
//! both, the figures) and, when asked, a Gradescope `results.json` for each student
//! ([`gradescope`]). Every file is written under a temporary name and renamed into place
//! ([`crate::transport::film::write_atomically`]); the page links only to files in the folder.

pub mod gradescope;
pub mod html;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde_json::{Value, json};

use super::class::{Class, Keep, REFUSED, Row};
use super::compare::{Rgb8, TOLERANCE, difference_picture};
use super::{Figures, RIGHT, WELL};
use crate::transport::film::{SaveError, write_atomically, write_atomically_with};

/// The longest side of a thumbnail, in pixels.
pub const THUMBNAIL: u32 = 96;

/// The folder the report is written to, which keeps each image as the class is checked
/// ([`Keep`]).
pub struct ReportFolder {
    root: PathBuf,
    /// The first image that could not be written: the report is not complete.
    failed: Mutex<Option<String>>,
}

/// The names of a row's images in the report folder.
pub struct RowFiles {
    pub image: String,
    pub thumbnail: String,
    pub difference: String,
    pub difference_thumbnail: String,
}

/// Row `row`'s id in the page and its files' names: `s001`, `s002`, …
pub fn row_id(row: usize) -> String {
    format!("s{:03}", row + 1)
}

/// The names of row `row`'s images.
pub fn row_files(row: usize) -> RowFiles {
    let id = row_id(row);
    RowFiles {
        image: format!("images/{id}.png"),
        thumbnail: format!("images/{id}-thumb.png"),
        difference: format!("images/{id}-diff.png"),
        difference_thumbnail: format!("images/{id}-diff-thumb.png"),
    }
}

/// The names of the figure of [`Class::against`]`[k]` and its thumbnail.
pub fn figure_files(k: usize) -> (String, String) {
    (
        format!("images/figure-{}.png", k + 1),
        format!("images/figure-{}-thumb.png", k + 1),
    )
}

/// `image` shrunk to at most [`THUMBNAIL`] pixels a side by a whole factor, each pixel the mean
/// of the block it stands for (the blocks at the right and bottom edges may be narrower); an
/// image that small already is kept as it is.
pub fn thumbnail(image: &Rgb8) -> Rgb8 {
    let factor = image.width.max(image.height).div_ceil(THUMBNAIL).max(1);
    if factor == 1 {
        return image.clone();
    }
    let (w, h) = (image.width.div_ceil(factor), image.height.div_ceil(factor));
    let mut data = Vec::with_capacity(3 * (w * h) as usize);
    for ty in 0..h {
        for tx in 0..w {
            let (x0, y0) = (tx * factor, ty * factor);
            let (x1, y1) = (
                (x0 + factor).min(image.width),
                (y0 + factor).min(image.height),
            );
            let mut sum = [0u32; 3];
            for y in y0..y1 {
                for x in x0..x1 {
                    let p = image.get(x, y);
                    for c in 0..3 {
                        sum[c] += u32::from(p[c]);
                    }
                }
            }
            let n = (x1 - x0) * (y1 - y0);
            data.extend(sum.map(|s| ((s + n / 2) / n) as u8));
        }
    }
    Rgb8 {
        width: w,
        height: h,
        data,
    }
}

impl ReportFolder {
    /// The report folder at `root`, made with its `images/` folder if they are not there
    /// (files of an earlier report in it are replaced as they are written again).
    pub fn create(root: &Path) -> Result<ReportFolder, String> {
        std::fs::create_dir_all(root.join("images"))
            .map_err(|e| format!("could not make the report folder '{}': {e}", root.display()))?;
        Ok(ReportFolder {
            root: root.to_path_buf(),
            failed: Mutex::new(None),
        })
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Saves `image` as `name`, a PNG written under a temporary name and renamed into place
    /// ([`write_atomically_with`]), remembering the first failure. Its bytes go to the encoder
    /// as they are, with fast compression: a class's report writes four images a submission.
    fn save(&self, name: &str, image: &Rgb8) {
        let path = self.root.join(name);
        let saved = write_atomically_with(&path, |file| {
            let failed = |e: png::EncodingError| match e {
                png::EncodingError::IoError(reason) => SaveError::Write {
                    path: path.clone(),
                    reason,
                },
                e => SaveError::Encode {
                    path: path.clone(),
                    message: e.to_string(),
                },
            };
            let mut encoder = png::Encoder::new(file, image.width, image.height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Fast);
            let mut writer = encoder.write_header().map_err(failed)?;
            writer.write_image_data(&image.data).map_err(failed)?;
            writer.finish().map_err(failed)
        });
        if let Err(e) = saved {
            let mut failed = self.failed.lock().unwrap_or_else(|e| e.into_inner());
            failed.get_or_insert(e.to_string());
        }
    }

    /// Writes the page, `report.csv`, `report.json` and, with `gradescope`, each student's
    /// `gradescope/STUDENT/results.json`; `title` names the class. Fails if any file, an image
    /// included, could not be written.
    pub fn finish(&self, class: &Class, title: &str, gradescope: bool) -> Result<(), String> {
        if let Some(e) = self.failed.lock().unwrap_or_else(|e| e.into_inner()).take() {
            return Err(e);
        }
        let write = |name: &str, bytes: &[u8]| {
            write_atomically(&self.root.join(name), bytes).map_err(|e| e.to_string())
        };
        write("index.html", html::page(class, title).as_bytes())?;
        write("report.csv", csv_text(class).as_bytes())?;
        let json = serde_json::to_string_pretty(&json_value(class, title))
            .map_err(|e| format!("could not write report.json: {e}"))?;
        write("report.json", json.as_bytes())?;
        if gradescope {
            for (student, results) in gradescope::results(class) {
                let folder = self.root.join("gradescope").join(&student);
                std::fs::create_dir_all(&folder).map_err(|e| {
                    format!("could not make the folder '{}': {e}", folder.display())
                })?;
                let text = serde_json::to_string_pretty(&results)
                    .map_err(|e| format!("could not write {student}'s results.json: {e}"))?;
                write_atomically(&folder.join("results.json"), text.as_bytes())
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    }
}

impl Keep for ReportFolder {
    fn figures(&self, against: usize, figures: &Figures) {
        let (full, thumb) = figure_files(against);
        self.save(&full, &figures.figure);
        self.save(&thumb, &thumbnail(&figures.figure));
    }

    fn image(&self, row: usize, image: &Rgb8, figures: &Figures) {
        let files = row_files(row);
        let difference = difference_picture(image, &figures.figure);
        self.save(&files.image, image);
        self.save(&files.thumbnail, &thumbnail(image));
        self.save(&files.difference, &difference);
        self.save(&files.difference_thumbnail, &thumbnail(&difference));
    }
}

/// Every verdict in the order the page shows and sorts them: right first, then the mistakes in
/// the catalogue's order, another stage, a factor, unknown, refused.
pub fn verdict_order() -> Vec<&'static str> {
    let mut order: Vec<&str> = vec!["none"];
    order.extend(super::Mistake::catalogue().map(|m| m.name()));
    order.extend([super::OTHER_STAGE, super::FACTOR, "unknown", REFUSED]);
    order
}

/// The verdicts of the class, in [`verdict_order`], with how many submissions got each; only
/// those some submission got.
pub fn verdict_counts(class: &Class) -> Vec<(String, usize)> {
    verdict_order()
        .into_iter()
        .map(|v| {
            let n = class.rows.iter().filter(|r| r.verdict() == v).count();
            (v.to_owned(), n)
        })
        .filter(|(_, n)| *n > 0)
        .collect()
}

/// The worst region as text: "x 32–63, y 0–31 (mean 12.5/255)"; "" where there is none or
/// the images agree.
pub fn worst_region(row: &Row) -> String {
    match &row.result {
        Ok(j) => match &j.report.worst_block {
            Some(b) if b.mean_difference > 0.0 => format!(
                "x {}–{}, y {}–{} (mean {:.1}/255)",
                b.x0,
                b.x1 - 1,
                b.y0,
                b.y1 - 1,
                b.mean_difference
            ),
            _ => String::new(),
        },
        Err(_) => String::new(),
    }
}

/// The columns of `report.csv`.
pub const CSV_COLUMNS: [&str; 15] = [
    "file",
    "student",
    "verdict",
    "explains",
    "match",
    "with_edges",
    "ssim",
    "worst_region",
    "identical_to",
    "stage",
    "width",
    "height",
    "fix",
    "reason",
    "notes",
];

/// `report.csv`: a header and a record a submission (shares as fractions, 1 = every pixel).
pub fn csv_text(class: &Class) -> String {
    let mut text = super::csv::record(CSV_COLUMNS);
    for row in &class.rows {
        let s = &row.submission;
        let identical = row.identical_to.join("; ");
        let region = worst_region(row);
        let fields: Vec<String> = match &row.result {
            Ok(j) => {
                let r = &j.report;
                vec![
                    s.name.clone(),
                    s.student.clone(),
                    r.best.mistake.clone(),
                    r.best.explains.to_string(),
                    r.match_share.to_string(),
                    r.with_edges.to_string(),
                    format!("{:.4}", j.ssim),
                    region,
                    identical,
                    r.stage.to_string(),
                    r.size[0].to_string(),
                    r.size[1].to_string(),
                    r.best.fix.clone(),
                    String::new(),
                    r.notes.join(" | "),
                ]
            }
            Err(reason) => {
                let mut f = vec![String::new(); CSV_COLUMNS.len()];
                f[0] = s.name.clone();
                f[1] = s.student.clone();
                f[2] = REFUSED.to_owned();
                f[8] = identical;
                f[13] = reason.clone();
                f
            }
        };
        text += &super::csv::record(fields.iter().map(String::as_str));
    }
    text
}

/// `report.json`: the criteria, each settings checked against (with its figure's file), the
/// verdicts' counts, and a record a submission holding `raylab check --json`'s report.
pub fn json_value(class: &Class, title: &str) -> Value {
    let against: Vec<Value> = class
        .against
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let (figure, thumbnail) = figure_files(k);
            json!({
                "id": k,
                "summary": s.summary(),
                "stage": s.shading.stage,
                "figure": figure,
                "figure_thumbnail": thumbnail,
                "settings": s,
            })
        })
        .collect();
    let submissions: Vec<Value> = class
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let s = &row.submission;
            let mut v = json!({
                "id": row_id(i),
                "file": s.name,
                "student": s.student,
                "verdict": row.verdict(),
                "against": row.against,
                "identical_to": row.identical_to,
            });
            match &row.result {
                Ok(j) => {
                    let files = row_files(i);
                    v["ssim"] = json!(j.ssim);
                    v["check"] = json!(j.report);
                    v["images"] = json!({
                        "image": files.image,
                        "thumbnail": files.thumbnail,
                        "difference": files.difference,
                        "difference_thumbnail": files.difference_thumbnail,
                    });
                }
                Err(reason) => v["reason"] = json!(reason),
            }
            v
        })
        .collect();
    let verdicts: serde_json::Map<String, Value> = verdict_counts(class)
        .into_iter()
        .map(|(v, n)| (v, json!(n)))
        .collect();
    json!({
        "title": title,
        "tolerance": TOLERANCE,
        "right": RIGHT,
        "well": WELL,
        "against": against,
        "verdicts": verdicts,
        "submissions": submissions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 200 × 100 shrinks by 3 (⌈200 / 96⌉) to 67 × 34; each pixel the mean of its block,
    /// the last column's blocks two pixels wide, the last row's one pixel high.
    #[test]
    fn thumbnails_average_their_blocks() {
        let image = Rgb8 {
            width: 200,
            height: 100,
            data: (0..200 * 100)
                .flat_map(|i| {
                    let (x, y) = (i % 200, i / 200);
                    [(x % 3) as u8 * 30, y as u8, 7]
                })
                .collect(),
        };
        let t = thumbnail(&image);
        assert_eq!((t.width, t.height), (67, 34));
        // Block (0, 0): x 0–2 gives 0, 30, 60 → 30; y 0–2 → 1.
        assert_eq!(t.get(0, 0), [30, 1, 7]);
        // The last column's blocks: x 198–199, which are 0 and 30 → 15.
        assert_eq!(t.get(66, 0), [15, 1, 7]);
        // The last row: y 99 alone.
        assert_eq!(t.get(0, 33), [30, 99, 7]);
        let small = Rgb8 {
            width: 64,
            height: 48,
            data: vec![9; 64 * 48 * 3],
        };
        assert_eq!(thumbnail(&small), small);
    }
}
