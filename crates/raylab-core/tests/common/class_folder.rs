//! A class's folder of submissions, made for `raylab check FOLDER`: every mistake of the
//! catalogue, right images (PNG, BMP, PPM), an anti-aliased one, a JPEG, a truncated PNG, an
//! empty file, a text file, an image of the wrong size, a file the list leaves out, identical
//! images from two students and from one, with the list (`list.csv`) of what each is checked
//! against and what its row should say. Shared by the class report's test (`tests/class.rs`)
//! and the example that makes a large class to measure (`examples/class_folder.rs`).
#![allow(dead_code)]

use std::io::Cursor;
use std::path::{Path, PathBuf};

use image::ImageFormat;
use raylab_core::shapes::scene::cornell_box;
use raylab_core::teaching::check::{Mistake, Rgb8, mistakes::looks};
use raylab_core::transport::render::render;
use raylab_core::{Camera, RenderSettings, Shading, Stage};

/// What a submission's row should say.
#[derive(Clone, Debug)]
pub struct Expected {
    /// Its name below the folder.
    pub file: String,
    /// The verdicts it may get.
    pub verdicts: Vec<&'static str>,
    /// What the reason of a refused one holds.
    pub reason: Option<&'static str>,
    /// What one of its notes holds.
    pub note: Option<&'static str>,
    /// The other students' files with the same pixels.
    pub identical_to: Vec<String>,
}

/// A submission to make: its file, its bytes, its line of the list.
struct Made {
    file: String,
    bytes: Vec<u8>,
    /// The list's cells after `file` (stage, width, height, yaw, light, shadows), or `None`
    /// for a file left out of the list.
    line: Option<[String; 6]>,
    expected: Expected,
}

/// The list's header.
pub const HEADER: &str = "file,stage,width,height,yaw,light,shadows";

/// The settings where `mistake` shows at `side`² (or `side` × ¾`side` where the image must
/// not be square), as the list's line says them: the lab's figure 7, but for the cosine (the
/// light behind the blocks, shadows off) and the yaw (15°).
fn where_it_shows(mistake: Mistake, side: u32) -> (RenderSettings, [String; 6]) {
    let height = if mistake == Mistake::Eq24Typo {
        side * 3 / 4
    } else {
        side
    };
    let mut s = RenderSettings {
        camera: Camera::default_for(side, height),
        shading: Shading::for_stage(Stage::Lab),
        ..RenderSettings::default()
    };
    let mut line = [
        "lab".to_owned(),
        side.to_string(),
        height.to_string(),
        String::new(),
        String::new(),
        String::new(),
    ];
    match mistake {
        Mistake::UnclampedCos => {
            s.shading.shadows = false;
            s.light.position = glam::Vec3::new(0.0, -0.5, 0.9);
            line[4] = "0,-0.5,0.9".to_owned();
            line[5] = "off".to_owned();
        }
        Mistake::YawSign => {
            s.camera.yaw = 15f32.to_radians();
            line[3] = "15".to_owned();
        }
        _ => {}
    }
    (s, line)
}

/// The settings of `stage` at `side`², and their line.
fn stage_at(stage: Stage, side: u32) -> (RenderSettings, [String; 6]) {
    let s = RenderSettings {
        camera: Camera::default_for(side, side),
        shading: Shading::for_stage(stage),
        ..RenderSettings::default()
    };
    let line = [
        stage.to_string(),
        side.to_string(),
        side.to_string(),
        String::new(),
        String::new(),
        String::new(),
    ];
    (s, line)
}

/// `image` encoded as `format` (JPEG at quality 95), as a student's program would save it.
pub fn encoded(image: &Rgb8, format: ImageFormat) -> Vec<u8> {
    let rgb = image::RgbImage::from_raw(image.width, image.height, image.data.clone()).unwrap();
    let mut bytes = Cursor::new(Vec::new());
    if format == ImageFormat::Jpeg {
        let encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95);
        rgb.write_with_encoder(encoder).unwrap();
    } else {
        rgb.write_to(&mut bytes, format).unwrap();
    }
    bytes.into_inner()
}

/// `image` with one level added to or taken from some pixels' channels (within the 2/255 the
/// check allows: the same verdict), chosen by `seed`: the same picture, but not the same
/// pixels as another copy.
fn jittered(image: &Rgb8, seed: u64) -> Rgb8 {
    if seed == 0 {
        return image.clone();
    }
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut out = image.clone();
    for b in &mut out.data {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        match state % 8 {
            0 => *b = b.saturating_add(1),
            1 => *b = b.saturating_sub(1),
            _ => {}
        }
    }
    out
}

fn expected(file: &str, verdicts: &[&'static str]) -> Expected {
    Expected {
        file: file.to_owned(),
        verdicts: verdicts.to_vec(),
        reason: None,
        note: None,
        identical_to: Vec::new(),
    }
}

fn refused(file: &str, reason: &'static str) -> Expected {
    Expected {
        reason: Some(reason),
        ..expected(file, &["refused"])
    }
}

/// One round of the class at `side`², its files' names starting with `prefix`; `seed` (0 for
/// none) makes its images' pixels differ by a level from another round's.
fn round(side: u32, prefix: &str, seed: u64) -> Vec<Made> {
    let scene = cornell_box();
    let mut made = Vec::new();
    let png = |image: &Rgb8| encoded(image, ImageFormat::Png);
    for mistake in Mistake::catalogue() {
        let (s, line) = where_it_shows(mistake, side);
        let look = jittered(&looks(&scene, &s, mistake)[0], seed);
        let file = format!("{prefix}{mistake}.png");
        made.push(Made {
            file: file.clone(),
            bytes: png(&look),
            line: Some(line),
            expected: expected(&file, &[mistake.name()]),
        });
    }
    // The 4π forgotten, handed in again by another student.
    let copy = made[0].bytes.clone();
    let first = made[0].file.clone();
    let file = format!("{prefix}copy-of-no-4pi.png");
    made[0].expected.identical_to = vec![file.clone()];
    made.push(Made {
        file: file.clone(),
        bytes: copy,
        line: made[0].line.clone(),
        expected: Expected {
            identical_to: vec![first],
            ..expected(&file, &["no-4pi"])
        },
    });
    let (lab, lab_line) = stage_at(Stage::Lab, side);
    let figure = jittered(&Rgb8::from_linear(&render(&scene, &lab)), seed);
    for (stage, format, ext) in [
        (Stage::Lab, ImageFormat::Png, "png"),
        (Stage::Direct, ImageFormat::Bmp, "bmp"),
        (Stage::Flat, ImageFormat::Pnm, "ppm"),
    ] {
        let (s, line) = stage_at(stage, side);
        let image = jittered(&Rgb8::from_linear(&render(&scene, &s)), seed);
        let file = format!("{prefix}right-{stage}.{ext}");
        made.push(Made {
            file: file.clone(),
            bytes: encoded(&image, format),
            line: Some(line),
            expected: expected(&file, &["none"]),
        });
    }
    // Anti-aliased: 16 samples a pixel.
    let mut many = lab.clone();
    many.samples_per_pixel = 16;
    many.seed = 7 + seed;
    let file = format!("{prefix}anti-aliased.png");
    made.push(Made {
        file: file.clone(),
        bytes: png(&Rgb8::from_linear(&render(&scene, &many))),
        line: Some(lab_line.clone()),
        expected: Expected {
            note: Some("anti-aliased"),
            ..expected(&file, &["none"])
        },
    });
    let file = format!("{prefix}jpeg.jpg");
    made.push(Made {
        file: file.clone(),
        bytes: encoded(&figure, ImageFormat::Jpeg),
        line: Some(lab_line.clone()),
        expected: Expected {
            note: Some("the image is a JPEG"),
            ..expected(&file, &["none"])
        },
    });
    // One student's two files, the same pixels (the shadows stage, which no one else hands
    // in): not flagged.
    let (shadows, shadows_line) = stage_at(Stage::Shadows, side);
    let twice = png(&jittered(
        &Rgb8::from_linear(&render(&scene, &shadows)),
        seed,
    ));
    for name in ["first.png", "second.png"] {
        let file = format!("{prefix}pair/{name}");
        made.push(Made {
            file: file.clone(),
            bytes: twice.clone(),
            line: Some(shadows_line.clone()),
            expected: expected(&file, &["none"]),
        });
    }
    let whole = png(&figure);
    let file = format!("{prefix}truncated.png");
    made.push(Made {
        file: file.clone(),
        bytes: whole[..whole.len() / 2].to_vec(),
        line: Some(lab_line.clone()),
        expected: refused(&file, "cut short"),
    });
    let file = format!("{prefix}empty.png");
    made.push(Made {
        file: file.clone(),
        bytes: Vec::new(),
        line: Some(lab_line.clone()),
        expected: refused(&file, "empty"),
    });
    let file = format!("{prefix}notes.txt");
    made.push(Made {
        file: file.clone(),
        bytes: b"my render is attached\n".to_vec(),
        line: Some(lab_line.clone()),
        expected: refused(&file, "not a PNG, BMP, PPM or JPEG"),
    });
    let small = side * 3 / 4;
    let (s, _) = stage_at(Stage::Lab, small);
    let file = format!("{prefix}wrong-size.png");
    made.push(Made {
        file: file.clone(),
        bytes: png(&Rgb8::from_linear(&render(&scene, &s))),
        line: Some(lab_line.clone()),
        expected: refused(&file, "the figure is rendered at the image's size"),
    });
    let file = format!("{prefix}unlisted.png");
    made.push(Made {
        file: file.clone(),
        bytes: whole,
        line: None,
        expected: refused(&file, "not listed"),
    });
    made
}

/// Makes `root/submissions/` with `count` submissions at `side`² (rounds of the set above,
/// each round's files prefixed `rN-` after the first and its pixels a level apart; one round
/// when `None`) and `root/list.csv`. Returns the folder, the list and what each row should
/// say.
pub fn make_class(
    root: &Path,
    side: u32,
    count: Option<usize>,
) -> (PathBuf, PathBuf, Vec<Expected>) {
    let folder = root.join("submissions");
    let mut list = format!("{HEADER}\n");
    let mut expected = Vec::new();
    for r in 0.. {
        if count.is_none_or(|c| expected.len() >= c) && r > 0 {
            break;
        }
        let count = count.unwrap_or(usize::MAX);
        let prefix = if r == 0 {
            String::new()
        } else {
            format!("r{r}-")
        };
        for m in round(side, &prefix, r)
            .into_iter()
            .take(count - expected.len())
        {
            let path = folder.join(&m.file);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &m.bytes).unwrap();
            if let Some(line) = &m.line {
                list += &format!("{},{}\n", m.file, quoted(line).join(","));
            }
            expected.push(m.expected);
        }
    }
    let list_path = root.join("list.csv");
    std::fs::write(&list_path, list).unwrap();
    (folder, list_path, expected)
}

/// Cells with commas quoted, as a spreadsheet writes them.
fn quoted(cells: &[String]) -> Vec<String> {
    cells
        .iter()
        .map(|c| {
            if c.contains(',') {
                format!("\"{c}\"")
            } else {
                c.clone()
            }
        })
        .collect()
}
