//! "Check my lab": a student's render compared with the exact figure, and the classic mistake
//! that explains how it differs.
//!
//! [`check`] renders the lab's figure for the student's settings at the image's size (one
//! sample through each pixel's centre, the lab's display: exactly what `raylab render` writes
//! as PNG), measures how much of the image is within 2/255 of it ([`compare`]), then renders
//! the figure as each classic mistake would ([`mistakes`]) and measures how much of the image
//! each explains. The verdict:
//!
//! * `none` when the image matches the figure on at least [`RIGHT`] of its pixels, or matches
//!   it everywhere but along edges, where its pixels are blends of their neighbours'
//!   (anti-aliasing: a note says so), if the image is large enough to tell ([`MIN_SIDE`]) and
//!   matches exactly on at least [`MIN_EXACT`] of its pixels (otherwise a note says why the
//!   allowance is not made);
//! * the mistake whose figure explains the most pixels, when it explains at least [`WELL`] of
//!   them and more than the exact figure does;
//! * `unknown` otherwise: no single classic mistake explains the image, and a guess would
//!   mislead more than it helps.
//!
//! Mirror and glass (the material presets, a scene file's models, the pool's water) are
//! followed as the lab stages follow them, Whitted-style: every diffuse hit along a pixel's
//! branches is recombined with the mistake ([`mistakes::formula_figures`]).
//!
//! A class's images are checked at once by [`class`] (the figures rendered once for each
//! settings, [`Figures`]), and written up for a teacher by [`report`].

pub mod class;
pub mod compare;
pub mod csv;
pub mod mistakes;
pub mod report;
pub mod ssim;
pub mod student;

use serde::{Serialize, Serializer};

pub use compare::{Rgb8, WorstBlock};
pub use mistakes::{Kind, Mistake};
pub use student::{LOSSY_NOTE, ReadError, lossy_note, read_image};

use crate::integrator::Stage;
use crate::scene::Scene;
use crate::settings::{RenderSettings, SettingsError};
use compare::{share, share_within, within_any};
use mistakes::Recombined;

/// The share of pixels within 2/255 of the exact figure at which an image is right: 99 %.
pub const RIGHT: f64 = 0.99;

/// The share of pixels a mistake's figure must explain to be named: 90 %. Below it, `unknown`.
/// A mistake changes a good part of the figure (all of the lit surfaces, or every pixel), so
/// an image that has it matches its figure nearly everywhere; an image with two mistakes, or
/// one not in the catalogue, leaves a tenth or more unexplained.
pub const WELL: f64 = 0.90;

/// The smallest side, in pixels, of an image whose anti-aliasing can be told from a wrong
/// image. Along an edge any blend of the neighbours' colours is allowed for; on an image a few
/// pixels across, each pixel spans several degrees of the view and its 3 × 3 neighbourhood
/// several surfaces, so nearly any colour would pass.
pub const MIN_SIDE: u32 = 16;

/// The share of pixels that must match the figure exactly for the anti-aliasing allowance to
/// be made: a half. Anti-aliasing changes only the pixels an edge crosses; the allowance is
/// evidence of the exact figure only where the others, inside surfaces, match it exactly.
pub const MIN_EXACT: f64 = 0.5;

/// For shadow acne: the share of lit pixels that must show each outcome, lit and in shadow,
/// for the image to count as speckled ([`speckled`]).
pub const SPECKLED: f64 = 0.05;

/// For shadow acne: the share of neighbouring lit pixels whose outcomes must differ for the
/// image to count as speckled: 10 % ([`speckled`]). A random speckle of a share p of the pixels
/// makes neighbours differ in 2p(1 − p) of their pairs (18 % at p = 10 %); the border of a
/// shadow region, in a few per cent.
pub const SPECKLED_NEIGHBOURS: f64 = 0.10;

/// Why an image cannot be checked against these settings.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The settings describe something the lab's figures do not: a stage or extension beyond
    /// them.
    #[error("check compares with the lab's figures: {0}")]
    NotTheLab(String),
    /// The image is not the size the figure is rendered at.
    #[error(
        "the image is {image_width}×{image_height} but the figure was asked at {width}×{height}"
    )]
    Size {
        image_width: u32,
        image_height: u32,
        width: u32,
        height: u32,
    },
}

/// What the check found (its JSON is `raylab check --json`'s output; docs/check.md).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    pub stage: Stage,
    /// The image's size, [W, H].
    pub size: [u32; 2],
    /// The share of pixels within 2/255 of the exact figure, every channel.
    #[serde(rename = "match")]
    pub match_share: f64,
    /// The verdict: a mistake, `none` or `unknown`.
    pub best: Best,
    /// Every mistake that changes this figure, best first: the share of the image's pixels
    /// its figure explains.
    pub candidates: Vec<Candidate>,
    /// Where the image and the exact figure differ most; `None` for an empty image.
    pub worst_block: Option<WorstBlock>,
    /// The share of pixels the exact figure explains once anti-aliased edges are allowed for
    /// ([`compare::share_explained_with_edges`]).
    pub with_edges: f64,
    /// Remarks that are no mistake: anti-aliasing, mistakes whose figures tie.
    pub notes: Vec<String>,
}

/// The verdict.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Best {
    /// A mistake's name, `none` or `unknown`.
    pub mistake: String,
    /// The share of pixels the verdict explains: the mistake's figure's, the exact figure's
    /// for `none` (with edges, when anti-aliased), the best candidate's for `unknown`.
    pub explains: f64,
    /// The lab's equation or section concerned ("" for `none` and `unknown`).
    pub equation: String,
    /// How to fix it, in a sentence.
    pub fix: String,
}

/// A mistake and the share of pixels its figure explains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Candidate {
    #[serde(serialize_with = "by_name")]
    pub mistake: Mistake,
    pub explains: f64,
}

fn by_name<S: Serializer>(m: &Mistake, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(m.name())
}

/// The check's report and the exact figure it compared with.
#[derive(Clone, Debug)]
pub struct Checked {
    pub report: Report,
    /// The exact figure as `raylab render` writes it.
    pub figure: Rgb8,
}

/// Refuses settings beyond the lab's figures: the path stage, area lights, a lens or texture
/// presets. A check compares pixel for pixel with one deterministic sample. Mirror, glass and
/// the rough metal are checked as the lab stages render them.
pub fn check_settings(settings: &RenderSettings) -> Result<(), CheckError> {
    settings.validate()?;
    let not = |what: &str| Err(CheckError::NotTheLab(what.to_owned()));
    if !Stage::LAB.contains(&settings.shading.stage) {
        return not("the path stage is not one of them (flat, incoming, direct, shadows or lab)");
    }
    if settings.light.is_area() {
        return not("its light is the lab's point light, not an area light");
    }
    if settings.camera.aperture > 0.0 {
        return not("its camera is a pinhole, with no aperture");
    }
    if settings.texture_preset != crate::material::TexturePreset::None {
        return not("its surfaces are the lab's plain colours, with no texture preset");
    }
    if settings.samples_per_pixel != 1 {
        return not("each is one sample a pixel, at its centre");
    }
    Ok(())
}

/// The memory a check of a `width × height` image needs at its peak, in bytes: the figures of
/// every formula mistake as linear images (12 bytes a pixel, with their rows, twice), the
/// [`Figures`] (every mistake's looks, two for gamma, the shadowed figure and the margin) and
/// the student's image at 3 bytes a pixel, a linear render; plus the program.
pub fn memory_estimate(width: u32, height: u32) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    let formulas = Mistake::ALL
        .iter()
        .filter(|m| m.kind() == Kind::Formula)
        .count() as u64
        + 1;
    let looks = Mistake::ALL.len() as u64 + 4;
    pixels * (formulas * 24 + looks * 3 + 12) + crate::settings::BASE_MEMORY
}

/// Compares `image` with the lab's figure for `settings` (whose camera is the image's size:
/// [`figure_settings`]) and with the figure of each mistake that could change it:
/// [`Figures::render`], then [`Figures::judge`].
pub fn check(
    scene: &Scene,
    settings: &RenderSettings,
    image: &Rgb8,
) -> Result<Checked, CheckError> {
    check_settings(settings)?;
    // Refused before anything is rendered.
    same_size(settings, image)?;
    let figures = Figures::render(scene, settings)?;
    let report = figures.judge(image)?;
    Ok(Checked {
        report,
        figure: figures.figure,
    })
}

/// An image not the size of the figure `settings` render is refused ([`CheckError::Size`]).
fn same_size(settings: &RenderSettings, image: &Rgb8) -> Result<(), CheckError> {
    size_is(settings.camera.width, settings.camera.height, image)
}

/// An image not `width × height` is refused ([`CheckError::Size`]).
fn size_is(width: u32, height: u32, image: &Rgb8) -> Result<(), CheckError> {
    if (width, height) != (image.width, image.height) {
        return Err(CheckError::Size {
            image_width: image.width,
            image_height: image.height,
            width,
            height,
        });
    }
    Ok(())
}

/// Everything an image is compared with, rendered once for a stage and its settings: the exact
/// figure, the looks of each mistake that changes it, and what telling shadow acne and
/// anti-aliasing apart needs. Many images checked against the same settings (a class:
/// [`class`]) share one.
#[derive(Clone, Debug)]
pub struct Figures {
    stage: Stage,
    /// The exact figure as `raylab render` writes it.
    pub figure: Rgb8,
    /// Each mistake whose figure differs from the exact one, in the catalogue's order, with
    /// its looks (any of which explains a pixel).
    looks: Vec<(Mistake, Vec<Rgb8>)>,
    /// The figure with every shadow ray blocked, when shadow acne applies.
    shadowed: Option<Rgb8>,
    /// The exact figure with a pixel more on every side ([`mistakes::figure_with_margin`]).
    margin: Rgb8,
}

impl Figures {
    /// Renders the exact figure for `settings` (whose camera is the images' size) and the
    /// figure of each mistake that applies: one pass of the integrator for the exact figure
    /// and every formula mistake, a render for each settings mistake, the picture mistakes
    /// from the figure.
    pub fn render(scene: &Scene, settings: &RenderSettings) -> Result<Figures, CheckError> {
        check_settings(settings)?;
        let applies: Vec<Mistake> = Mistake::ALL
            .into_iter()
            .filter(|m| m.applies(settings))
            .collect();
        let mut wanted: Vec<Recombined> = applies
            .iter()
            .filter(|m| m.kind() == Kind::Formula)
            .map(|m| Recombined::Mistake(*m))
            .collect();
        if applies.contains(&Mistake::ShadowAcne) {
            wanted.push(Recombined::EveryShadowRayBlocked);
        }
        let linear = mistakes::formula_figures(scene, settings, &wanted);
        let figure_of = |r: Recombined| {
            wanted
                .iter()
                .position(|w| *w == r)
                .map(|i| Rgb8::from_linear(&linear[i]))
        };
        let exact_linear = &linear[0];
        let figure = Rgb8::from_linear(exact_linear);
        let mut looks = Vec::new();
        for &mistake in applies.iter().filter(|m| **m != Mistake::None) {
            let these: Vec<Rgb8> = match mistake.kind() {
                Kind::Formula => figure_of(Recombined::Mistake(mistake))
                    .into_iter()
                    .collect(),
                Kind::Settings => vec![Rgb8::from_linear(&mistakes::settings_figure(
                    scene, settings, mistake,
                ))],
                Kind::Picture => mistakes::picture_looks(mistake, exact_linear, &figure),
            };
            // Offered only if it changes the figure.
            if these.iter().any(|l| compare::differs(l, &figure)) {
                looks.push((mistake, these));
            }
        }
        let shadowed = figure_of(Recombined::EveryShadowRayBlocked);
        let margin = Rgb8::from_linear(&mistakes::figure_with_margin(scene, settings));
        Ok(Figures {
            stage: settings.shading.stage,
            figure,
            looks,
            shadowed,
            margin,
        })
    }

    /// What `image` (of the figure's size) is: how much of it matches the exact figure, each
    /// mistake's share, the verdict (see the module docs).
    pub fn judge(&self, image: &Rgb8) -> Result<Report, CheckError> {
        let figure = &self.figure;
        size_is(figure.width, figure.height, image)?;
        let match_share = share_within(image, figure);
        let mut candidates: Vec<Candidate> = self
            .looks
            .iter()
            .map(|(mistake, looks)| {
                let explains = if *mistake == Mistake::ShadowAcne {
                    acne_explains(
                        image,
                        figure,
                        &looks[0],
                        self.shadowed.as_ref().unwrap_or(figure),
                    )
                } else {
                    let looks: Vec<&Rgb8> = looks.iter().collect();
                    share(&within_any(image, &looks))
                };
                Candidate {
                    mistake: *mistake,
                    explains,
                }
            })
            .collect();
        // Best first; equal shares in the catalogue's order (the sort is stable).
        candidates.sort_by(|a, b| b.explains.total_cmp(&a.explains));
        let with_edges = compare::share_explained_with_edges(image, figure, &self.margin);
        let worst_block = compare::worst_block(image, figure);
        let (best, notes) = verdict(
            [image.width, image.height],
            match_share,
            with_edges,
            &candidates,
        );
        Ok(Report {
            stage: self.stage,
            size: [image.width, image.height],
            match_share,
            best,
            candidates,
            worst_block,
            with_edges,
            notes,
        })
    }
}

/// The share of `image` that shadow acne explains. Acne speckles: the points a student's
/// shadow ray leaves with no offset find their own surface in the way or not as rounding falls,
/// which differs between any two tracers pixel by pixel. So where the image is speckled on the
/// lit surfaces ([`speckled`]), a pixel is explained by either outcome, lit (`figure`) or in
/// shadow (`shadowed`), or by raylab's own acne (`acne`); otherwise only raylab's acne explains.
pub fn acne_explains(image: &Rgb8, figure: &Rgb8, acne: &Rgb8, shadowed: &Rgb8) -> f64 {
    if speckled(image, figure, shadowed) {
        share(&within_any(image, &[acne, figure, shadowed]))
    } else {
        share(&within_any(image, &[acne]))
    }
}

/// Whether `image` is speckled with shadow where the figure is lit: among the pixels a shadow
/// would change (where `shadowed` differs from `figure`), each outcome, lit or in shadow, is
/// seen on at least [`SPECKLED`] of them, and neighbours (to the right and below, both
/// changed) disagree in at least [`SPECKLED_NEIGHBOURS`] of their pairs. Shadows in the wrong
/// place, however wrong, are regions: their neighbours disagree only along their borders.
pub fn speckled(image: &Rgb8, figure: &Rgb8, shadowed: &Rgb8) -> bool {
    let unchanged = within_any(shadowed, &[figure]);
    let on_figure = within_any(image, &[figure]);
    let on_shadowed = within_any(image, &[shadowed]);
    // Each pixel's outcome where a shadow changes it: lit, dark, or neither.
    let outcome: Vec<Option<bool>> = (0..unchanged.len())
        .map(|i| match (unchanged[i], on_figure[i], on_shadowed[i]) {
            (true, _, _) => None,
            (false, true, _) => Some(true),
            (false, false, true) => Some(false),
            _ => None,
        })
        .collect();
    let changed = unchanged.iter().filter(|u| !**u).count();
    let lit = outcome.iter().filter(|o| **o == Some(true)).count();
    let dark = outcome.iter().filter(|o| **o == Some(false)).count();
    let (w, h) = (image.width as usize, image.height as usize);
    let (mut pairs, mut disagree) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            let Some(a) = outcome[y * w + x] else {
                continue;
            };
            let right = (x + 1 < w).then(|| outcome[y * w + x + 1]).flatten();
            let below = (y + 1 < h).then(|| outcome[(y + 1) * w + x]).flatten();
            for b in [right, below].into_iter().flatten() {
                pairs += 1;
                disagree += usize::from(a != b);
            }
        }
    }
    let enough = |n: usize, of: usize, share: f64| of > 0 && n as f64 >= share * of as f64;
    enough(lit, changed, SPECKLED)
        && enough(dark, changed, SPECKLED)
        && enough(disagree, pairs, SPECKLED_NEIGHBOURS)
}

/// The verdict from the shares (see the module docs), and its notes.
fn verdict(
    [width, height]: [u32; 2],
    match_share: f64,
    with_edges: f64,
    candidates: &[Candidate],
) -> (Best, Vec<String>) {
    let mut notes = Vec::new();
    let percent = |s: f64| format!("{:.1} %", 100.0 * s);
    let none = |explains| Best {
        mistake: "none".into(),
        explains,
        equation: String::new(),
        fix: String::new(),
    };
    if match_share >= RIGHT {
        return (none(match_share), notes);
    }
    let best = candidates.first().filter(|c| c.explains > match_share);
    let named = |c: &Candidate, notes: &mut Vec<String>| {
        let tied: Vec<&str> = candidates[1..]
            .iter()
            .filter(|o| o.explains == c.explains)
            .map(|o| o.mistake.name())
            .collect();
        if !tied.is_empty() {
            notes.push(format!(
                "{} explains the image exactly as well here: their figures are the same at these \
                 settings",
                tied.join(", ")
            ));
        }
        Best {
            mistake: c.mistake.name().into(),
            explains: c.explains,
            equation: c.mistake.equation().into(),
            fix: c.mistake.fix().into(),
        }
    };
    if let Some(c) = best.filter(|c| c.explains >= RIGHT) {
        return (named(c, &mut notes), notes);
    }
    if with_edges >= RIGHT && width.min(height) < MIN_SIDE {
        notes.push(format!(
            "the image is too small to judge: at {width}×{height} a pixel's neighbours span \
             several surfaces, so anti-aliasing (a blend of the neighbours' colours along \
             edges) cannot be told from a wrong image; render it at least {MIN_SIDE} pixels \
             wide and high"
        ));
    } else if with_edges >= RIGHT && match_share < MIN_EXACT {
        notes.push(format!(
            "only {} of pixels match the figure exactly: too few to take the rest for \
             anti-aliasing (a blend of the neighbours' colours along edges), which leaves the \
             pixels inside surfaces as they are ({} are needed)",
            percent(match_share),
            percent(MIN_EXACT)
        ));
    } else if with_edges >= RIGHT {
        notes.push(format!(
            "anti-aliased: the image is the exact figure but along edges, where its pixels are \
             blends of their neighbours' colours ({} with edges allowed for, {} without): \
             several samples a pixel, which the lab's figures (one, at the centre) do not take",
            percent(with_edges),
            percent(match_share)
        ));
        return (none(with_edges), notes);
    }
    if let Some(c) = best.filter(|c| c.explains >= WELL) {
        return (named(c, &mut notes), notes);
    }
    let explains = candidates.first().map_or(0.0, |c| c.explains);
    let unknown = Best {
        mistake: "unknown".into(),
        explains,
        equation: String::new(),
        fix: format!(
            "No classic mistake explains it (the best, below, explains {}; {} are needed): look \
             at the worst region in the difference picture, and explain a pixel there with \
             raylab inspect.",
            percent(explains),
            percent(WELL)
        ),
    };
    (unknown, notes)
}

impl Report {
    /// The report as lines for a terminal.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let percent = |s: f64| format!("{:.1} %", 100.0 * s);
        let mut t = String::new();
        let [w, h] = self.size;
        let figure = self
            .stage
            .figure()
            .map_or(String::new(), |f| format!("figure {f}, "));
        let _ = writeln!(
            t,
            "compared with the exact figure ({figure}stage {}: {}), {w}×{h}",
            self.stage,
            self.stage.equation()
        );
        let _ = writeln!(
            t,
            "match: {} of pixels within 2/255 of the figure in every channel",
            percent(self.match_share)
        );
        if let Some(b) = &self.worst_block
            && b.mean_difference > 0.0
        {
            let _ = writeln!(
                t,
                "worst region: x {}–{}, y {}–{} (mean difference {:.1}/255); its centre is pixel \
                 {},{}",
                b.x0,
                b.x1 - 1,
                b.y0,
                b.y1 - 1,
                b.mean_difference,
                (b.x0 + b.x1) / 2,
                (b.y0 + b.y1) / 2
            );
        }
        match self.best.mistake.as_str() {
            "none" => {
                let _ = writeln!(t, "verdict: none — the image is the exact figure");
            }
            "unknown" => {
                let _ = writeln!(t, "verdict: unknown — {}", self.best.fix);
            }
            name => {
                let what = name.parse::<Mistake>().map_or("", |m| m.what());
                let _ = writeln!(
                    t,
                    "verdict: {name} — explains {} of pixels",
                    percent(self.best.explains)
                );
                let _ = writeln!(t, "  what: {what}");
                let _ = writeln!(t, "  lab:  {}", self.best.equation);
                let _ = writeln!(t, "  fix:  {}", self.best.fix);
            }
        }
        for note in &self.notes {
            let _ = writeln!(t, "note: {note}");
        }
        if !self.candidates.is_empty() {
            let _ = writeln!(
                t,
                "candidates (share of pixels each mistake's figure explains):"
            );
            for c in &self.candidates {
                let _ = writeln!(t, "  {:<22} {:>6}", c.mistake.name(), percent(c.explains));
            }
        }
        t
    }
}
