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
//!   them and more than the exact figure does; besides the catalogue of classic mistakes, the
//!   lab's other stages and switches ([`stages`]: figure 6 checked as figure 7, shadows left
//!   off; verdict [`OTHER_STAGE`]) and the exact figure times a factor in each channel
//!   ([`factor`]: a wrong light power; verdict [`FACTOR`]) are candidates too;
//! * `unknown` otherwise: no single classic mistake explains the image, and a guess would
//!   mislead more than it helps.
//!
//! A JPEG (lossy: [`Encoding`]) is compared by its 8 × 8 blocks' mean colours ([`lossy`]),
//! which its compression keeps, instead of pixel by pixel.
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
pub mod factor;
pub mod lossy;
pub mod mistakes;
pub mod report;
pub mod ssim;
pub mod stages;
pub mod student;

use serde::{Serialize, Serializer};

pub use compare::{Rgb8, WorstBlock};
pub use factor::FactorCandidate;
pub use lossy::Encoding;
pub use mistakes::{Kind, Mistake};
pub use stages::StageSwitches;
pub use student::{ReadError, read_image, read_image_encoded};

use crate::shapes::scene::Scene;
use crate::transport::film::Image;
use crate::transport::integrator::Stage;
use crate::transport::render::render;
use crate::transport::settings::{RenderSettings, SettingsError};
use compare::{share, within_any};
use mistakes::Recombined;

/// The verdict when the image is the lab's figure at another stage or with a switch the other
/// way ([`stages`]): [`Best::stage`] says which.
pub const OTHER_STAGE: &str = "other-stage";

/// The verdict when the image is the exact figure times a constant in each channel
/// ([`factor`]): [`Best::factor`] says which.
pub const FACTOR: &str = "factor";

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
    /// The shadows and indirect switches of the figure checked against.
    pub shadows: bool,
    pub indirect: bool,
    /// What the figure checked against computes, with its switches as they are
    /// ([`crate::transport::settings::Shading::description`]).
    pub computes: String,
    /// The image's size, [W, H].
    pub size: [u32; 2],
    /// How the image was stored, which decides how it is compared ([`Encoding`]).
    pub encoding: Encoding,
    /// The share of pixels within 2/255 of the exact figure, every channel (for a JPEG: in
    /// blocks whose mean is within [`lossy::JPEG_TOLERANCE`]).
    #[serde(rename = "match")]
    pub match_share: f64,
    /// The verdict: a mistake, `none` or `unknown`.
    pub best: Best,
    /// Every mistake that changes this figure, best first: the share of the image's pixels
    /// its figure explains.
    pub candidates: Vec<Candidate>,
    /// The lab's other stages and switches that change this figure, best first: the share of
    /// pixels each explains.
    pub stages: Vec<StageCandidate>,
    /// The factor in each channel that best maps the exact figure onto the image, and the
    /// share it explains; `None` where it would change nothing (a factor of 1).
    pub factor: Option<FactorCandidate>,
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
    /// For [`OTHER_STAGE`]: the stage and switches the image is.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stage: Option<StageCandidate>,
    /// For [`FACTOR`]: the factor in R, G, B.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor: Option<[f64; 3]>,
}

impl Best {
    /// What the verdict is, in a line: the mistake's [`Mistake::what`], the stage the image is
    /// and how it differs, the factor; "" for `none` and `unknown`.
    pub fn what(&self) -> String {
        if let Some(s) = &self.stage {
            format!("this is {}: {}", s.name, s.differs)
        } else if let Some(f) = self.factor {
            format!("the exact figure {}", factor::describe(f))
        } else {
            self.mistake
                .parse::<Mistake>()
                .map_or_else(|_| String::new(), |m| m.what().to_owned())
        }
    }
}

/// Another stage or switch of the lab, and the share of pixels its figure explains.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageCandidate {
    #[serde(flatten)]
    pub switches: StageSwitches,
    /// How a person names it: "figure 6", "figure 7 without shadows".
    pub name: String,
    /// How it differs from the figure checked against: "the constant indirect term N is
    /// missing".
    pub differs: String,
    pub explains: f64,
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
    if settings.texture_preset != crate::shading::material::TexturePreset::None {
        return not("its surfaces are the lab's plain colours, with no texture preset");
    }
    if settings.samples_per_pixel != 1 {
        return not("each is one sample a pixel, at its centre");
    }
    Ok(())
}

/// The memory a check of a `width × height` image needs at its peak, in bytes: the figures of
/// every formula mistake as linear images (12 bytes a pixel, with their rows, twice), the
/// [`Figures`] (every mistake's looks, two for gamma, the shadowed figure, the margin, the
/// other stages' figures and the factor's) and the student's image at 3 bytes a pixel, the
/// exact figure kept linear and a linear render; plus the program.
pub fn memory_estimate(width: u32, height: u32) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    let formulas = Mistake::ALL
        .iter()
        .filter(|m| m.kind() == Kind::Formula)
        .count() as u64
        + 1;
    let looks = Mistake::ALL.len() as u64 + 4 + MAX_OTHER_STAGES + 1;
    pixels * (formulas * 24 + looks * 3 + 2 * 12) + crate::transport::settings::BASE_MEMORY
}

/// The most other stages and switches a figure is compared with ([`stages::others`]): the
/// lab's five figures and the two switches turned.
const MAX_OTHER_STAGES: u64 = 7;

/// Compares `image` with the lab's figure for `settings` (whose camera is the image's size:
/// [`figure_settings`]) and with the figure of each mistake that could change it:
/// [`Figures::render`], then [`Figures::judge`].
pub fn check(
    scene: &Scene,
    settings: &RenderSettings,
    image: &Rgb8,
) -> Result<Checked, CheckError> {
    check_encoded(scene, settings, image, Encoding::Lossless)
}

/// [`check`] for an image stored as `encoding` says (a JPEG is compared by its blocks:
/// [`lossy`]).
pub fn check_encoded(
    scene: &Scene,
    settings: &RenderSettings,
    image: &Rgb8,
    encoding: Encoding,
) -> Result<Checked, CheckError> {
    check_settings(settings)?;
    // Refused before anything is rendered.
    same_size(settings, image)?;
    let figures = Figures::render(scene, settings)?;
    let report = figures.judge_encoded(image, encoding)?;
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
/// figure, the looks of each mistake that changes it, the lab's other stages and switches, and
/// what telling shadow acne and anti-aliasing apart needs. Many images checked against the
/// same settings (a class: [`class`]) share one.
#[derive(Clone, Debug)]
pub struct Figures {
    /// The stage and switches checked against.
    own: StageSwitches,
    /// What they compute ([`crate::transport::settings::Shading::description`]).
    computes: String,
    /// The exact figure as `raylab render` writes it.
    pub figure: Rgb8,
    /// The exact figure, linear (before the display clamps it): what a factor multiplies.
    linear: Image,
    /// Each mistake whose figure differs from the exact one, in the catalogue's order, with
    /// its looks (any of which explains a pixel).
    looks: Vec<(Mistake, Vec<Rgb8>)>,
    /// The lab's other stages and switches whose figures differ from the exact one
    /// ([`stages::others`]), with their figures.
    stages: Vec<(StageSwitches, Rgb8)>,
    /// The figure with every shadow ray blocked, when shadow acne applies.
    shadowed: Option<Rgb8>,
    /// The exact figure with a pixel more on every side ([`mistakes::figure_with_margin`]).
    margin: Rgb8,
}

impl Figures {
    /// Renders the exact figure for `settings` (whose camera is the images' size) and the
    /// figure of each mistake that applies: one pass of the integrator for the exact figure
    /// and every formula mistake, a render for each settings mistake and each other stage or
    /// switch, the picture mistakes from the figure.
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
        let mut linear = mistakes::formula_figures(scene, settings, &wanted);
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
        let stages = stages::others(settings)
            .into_iter()
            .map(|other| {
                let look = render(scene, &stages::with_stage(settings, other));
                (other, Rgb8::from_linear(&look))
            })
            .filter(|(_, look)| compare::differs(look, &figure))
            .collect();
        let shadowed = figure_of(Recombined::EveryShadowRayBlocked);
        let margin = Rgb8::from_linear(&mistakes::figure_with_margin(scene, settings));
        Ok(Figures {
            own: StageSwitches::of(&settings.shading),
            computes: settings.shading.description(settings.material_preset),
            figure,
            linear: linear.swap_remove(0),
            looks,
            stages,
            shadowed,
            margin,
        })
    }

    /// What `image` (of the figure's size, stored losslessly) is: how much of it matches the
    /// exact figure, each mistake's share, the verdict (see the module docs).
    pub fn judge(&self, image: &Rgb8) -> Result<Report, CheckError> {
        self.judge_encoded(image, Encoding::Lossless)
    }

    /// [`Figures::judge`] for an image stored as `encoding` says: a JPEG is compared by its
    /// blocks ([`lossy`]), with a note saying so.
    pub fn judge_encoded(&self, image: &Rgb8, encoding: Encoding) -> Result<Report, CheckError> {
        let figure = &self.figure;
        size_is(figure.width, figure.height, image)?;
        // Which pixels of the image one of `looks` explains.
        let explained = |looks: &[&Rgb8]| match encoding {
            Encoding::Lossless => within_any(image, looks),
            Encoding::Jpeg => lossy::within_any_blocks(image, looks),
        };
        let explains = |looks: &[&Rgb8]| share(&explained(looks));
        let match_share = explains(&[figure]);
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
                        &explained,
                    )
                } else {
                    let looks: Vec<&Rgb8> = looks.iter().collect();
                    explains(&looks)
                };
                Candidate {
                    mistake: *mistake,
                    explains,
                }
            })
            .collect();
        // Best first; equal shares in the catalogue's order (the sort is stable).
        candidates.sort_by(|a, b| b.explains.total_cmp(&a.explains));
        let mut stages: Vec<StageCandidate> = self
            .stages
            .iter()
            .map(|(other, look)| StageCandidate {
                switches: *other,
                name: other.name(),
                differs: other.differences(self.own).0.join("; "),
                explains: explains(&[look]),
            })
            .collect();
        stages.sort_by(|a, b| b.explains.total_cmp(&a.explains));
        // Three free numbers fit any image of a pixel or two: a factor is looked for only on
        // an image large enough to tell ([`MIN_SIDE`]).
        let large = image.width.min(image.height) >= MIN_SIDE;
        let fitted = large.then(|| factor::fit(image, &self.linear)).flatten();
        let factor = fitted.and_then(|k| {
            let look = factor::scaled(&self.linear, k);
            compare::differs(&look, figure).then(|| FactorCandidate {
                factor: k
                    .to_array()
                    .map(|c| (f64::from(c) * 1000.0).round() / 1000.0),
                explains: explains(&[&look]),
            })
        });
        let with_edges = match encoding {
            Encoding::Lossless => compare::share_explained_with_edges(image, figure, &self.margin),
            // A JPEG's blocks are compared by their means, which anti-aliasing hardly moves.
            Encoding::Jpeg => match_share,
        };
        let worst_block = compare::worst_block(image, figure);
        let (best, mut notes) = verdict(
            [image.width, image.height],
            match_share,
            with_edges,
            &candidates,
            &stages,
            factor.as_ref(),
            self.own,
        );
        if encoding == Encoding::Jpeg {
            notes.push(lossy::JPEG_NOTE.to_owned());
        }
        Ok(Report {
            stage: self.own.stage,
            shadows: self.own.shadows,
            indirect: self.own.indirect,
            computes: self.computes.clone(),
            size: [image.width, image.height],
            encoding,
            match_share,
            best,
            candidates,
            stages,
            factor,
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
/// `explained` says which pixels some looks explain (pixel by pixel, or a JPEG's blocks).
pub fn acne_explains(
    image: &Rgb8,
    figure: &Rgb8,
    acne: &Rgb8,
    shadowed: &Rgb8,
    explained: &dyn Fn(&[&Rgb8]) -> Vec<bool>,
) -> f64 {
    if speckled(image, figure, shadowed) {
        share(&explained(&[acne, figure, shadowed]))
    } else {
        share(&explained(&[acne]))
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

/// An explanation the verdict may name: a classic mistake, another stage or switch, a factor.
enum Explanation<'a> {
    Mistake(Mistake),
    Stage(&'a StageCandidate),
    Factor(&'a FactorCandidate),
}

impl Explanation<'_> {
    fn name(&self) -> String {
        match self {
            Explanation::Mistake(m) => m.name().to_owned(),
            Explanation::Stage(s) => s.name.clone(),
            Explanation::Factor(f) => format!("the factor {}", factor::describe(f.factor)),
        }
    }

    /// The verdict that names it.
    fn best(&self, explains: f64, own: StageSwitches) -> Best {
        match self {
            Explanation::Mistake(m) => Best {
                mistake: m.name().into(),
                explains,
                equation: m.equation().into(),
                fix: m.fix().into(),
                stage: None,
                factor: None,
            },
            Explanation::Stage(s) => {
                let fixes = s.switches.differences(own).1;
                let fix = format!(
                    "Your image is {}: to finish {}, {}. If you meant {}, check it against that \
                     ({}).",
                    s.name,
                    own.name(),
                    fixes.join("; "),
                    s.name,
                    s.switches.options()
                );
                Best {
                    mistake: OTHER_STAGE.into(),
                    explains,
                    equation: format!(
                        "{} computes {}; {} computes {}",
                        s.name,
                        s.switches
                            .computes(crate::shading::material::MaterialPreset::None),
                        own.name(),
                        own.computes(crate::shading::material::MaterialPreset::None)
                    ),
                    fix,
                    stage: Some((*s).clone()),
                    factor: None,
                }
            }
            Explanation::Factor(f) => Best {
                mistake: FACTOR.into(),
                explains,
                equation: factor::EQUATION.into(),
                fix: factor::fix(f.factor),
                stage: None,
                factor: Some(f.factor),
            },
        }
    }
}

/// The verdict from the shares (see the module docs), and its notes. `own`: the stage and
/// switches checked against.
fn verdict(
    [width, height]: [u32; 2],
    match_share: f64,
    with_edges: f64,
    candidates: &[Candidate],
    stages: &[StageCandidate],
    factor: Option<&FactorCandidate>,
    own: StageSwitches,
) -> (Best, Vec<String>) {
    let mut notes = Vec::new();
    let percent = |s: f64| format!("{:.1} %", 100.0 * s);
    let none = |explains| Best {
        mistake: "none".into(),
        explains,
        equation: String::new(),
        fix: String::new(),
        stage: None,
        factor: None,
    };
    if match_share >= RIGHT {
        return (none(match_share), notes);
    }
    // Every explanation, best first; equal shares in the order mistakes, stages, factor.
    let mut ranked: Vec<(Explanation, f64)> = candidates
        .iter()
        .map(|c| (Explanation::Mistake(c.mistake), c.explains))
        .chain(stages.iter().map(|s| (Explanation::Stage(s), s.explains)))
        .chain(factor.map(|f| (Explanation::Factor(f), f.explains)))
        .collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    let best = ranked
        .first()
        .filter(|(_, explains)| *explains > match_share);
    let named = |(what, explains): &(Explanation, f64), notes: &mut Vec<String>| {
        let tied: Vec<String> = ranked[1..]
            .iter()
            .filter(|(_, e)| e == explains)
            .map(|(o, _)| o.name())
            .collect();
        if !tied.is_empty() {
            notes.push(format!(
                "{} explains the image exactly as well here: their figures are the same at these \
                 settings",
                tied.join(", ")
            ));
        }
        what.best(*explains, own)
    };
    if let Some(c) = best.filter(|(_, e)| *e >= RIGHT) {
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
    if let Some(c) = best.filter(|(_, e)| *e >= WELL) {
        return (named(c, &mut notes), notes);
    }
    let (name, explains) = ranked
        .first()
        .map_or((String::new(), 0.0), |(what, e)| (what.name(), *e));
    let why = if ranked.is_empty() {
        format!(
            "no mistake changes this figure, and the exact figure explains only {}",
            percent(match_share)
        )
    } else if explains >= WELL {
        // Enough of the image, but no more than the exact figure's own match.
        format!(
            "the best candidate, {name}, explains {}, but the exact figure itself explains {}: \
             no mistake explains it better, and the exact figure needs {} to be right",
            percent(explains),
            percent(match_share),
            percent(RIGHT)
        )
    } else {
        format!(
            "the best candidate, {name}, explains {} and the exact figure {}; a mistake is named \
             at {}",
            percent(explains),
            percent(match_share),
            percent(WELL)
        )
    };
    let unknown = Best {
        mistake: "unknown".into(),
        explains,
        equation: String::new(),
        fix: format!(
            "No classic mistake explains it ({why}): look at the worst region in the difference \
             picture, and explain a pixel there with raylab inspect."
        ),
        stage: None,
        factor: None,
    };
    (unknown, notes)
}

impl Report {
    /// What the figure checked against is called: "figure 7", "figure 7 without shadows".
    pub fn figure_name(&self) -> String {
        StageSwitches {
            stage: self.stage,
            shadows: self.shadows,
            indirect: self.indirect,
        }
        .name()
    }

    /// The report as lines for a terminal.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let percent = |s: f64| format!("{:.1} %", 100.0 * s);
        let mut t = String::new();
        let [w, h] = self.size;
        let _ = writeln!(
            t,
            "compared with the exact figure ({}, stage {}: {}), {w}×{h}",
            self.figure_name(),
            self.stage,
            self.computes
        );
        match self.encoding {
            Encoding::Lossless => {
                let _ = writeln!(
                    t,
                    "match: {} of pixels within 2/255 of the figure in every channel",
                    percent(self.match_share)
                );
            }
            Encoding::Jpeg => {
                let _ = writeln!(
                    t,
                    "match: {} of pixels in 8×8 blocks whose mean is within {}/255 of the \
                     figure's in every channel (a JPEG)",
                    percent(self.match_share),
                    lossy::JPEG_TOLERANCE
                );
            }
        }
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
                let _ = writeln!(
                    t,
                    "verdict: {name} — explains {} of pixels",
                    percent(self.best.explains)
                );
                let _ = writeln!(t, "  what: {}", self.best.what());
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
        if !self.stages.is_empty() {
            let _ = writeln!(t, "other stages and switches (share each figure explains):");
            for s in &self.stages {
                let _ = writeln!(t, "  {:<26} {:>6}", s.name, percent(s.explains));
            }
        }
        if let Some(f) = &self.factor {
            let _ = writeln!(
                t,
                "factor: the exact figure {} explains {}",
                factor::describe(f.factor),
                percent(f.explains)
            );
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::scene::cornell_box;
    use std::io::Cursor;

    fn settings(stage: Stage, side: u32) -> RenderSettings {
        let mut s = RenderSettings::default();
        s.camera = s.camera.with_resolution(side, side);
        s.shading = crate::transport::settings::Shading::for_stage(stage);
        s
    }

    fn rendered(scene: &Scene, s: &RenderSettings) -> Rgb8 {
        Rgb8::from_linear(&render(scene, s))
    }

    /// `image` saved as JPEG at `quality` by `image`'s encoder, and read back as check reads
    /// it.
    fn as_jpeg(image: &Rgb8, quality: u8) -> (Rgb8, Encoding) {
        let rgb = image::RgbImage::from_raw(image.width, image.height, image.data.clone());
        let mut bytes = Cursor::new(Vec::new());
        let encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality);
        rgb.unwrap().write_with_encoder(encoder).unwrap();
        student::decode_encoded(&bytes.into_inner()).unwrap()
    }

    /// A figure 6 render (no N) checked with the defaults (figure 7) is figure 6, N missing,
    /// with the fix and the options that check it as figure 6.
    #[test]
    fn figure_6_checked_as_figure_7_is_named() {
        let scene = cornell_box();
        let image = rendered(&scene, &settings(Stage::Shadows, 64));
        let r = check(&scene, &settings(Stage::Lab, 64), &image)
            .unwrap()
            .report;
        assert_eq!(r.best.mistake, OTHER_STAGE, "{r:?}");
        assert_eq!(r.best.explains, 1.0);
        let stage = r.best.stage.as_ref().unwrap();
        assert_eq!(stage.name, "figure 6");
        assert_eq!(
            (
                stage.switches.stage,
                stage.switches.shadows,
                stage.switches.indirect
            ),
            (Stage::Shadows, true, false)
        );
        assert!(r.best.fix.contains("R = ρ·(D + N)"), "{}", r.best.fix);
        assert!(r.best.fix.contains("--stage shadows"), "{}", r.best.fix);
        let text = r.to_text();
        assert!(
            text.contains("this is figure 6: the constant indirect term N is missing"),
            "{text}"
        );
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["best"]["mistake"], "other-stage");
        assert_eq!(json["best"]["stage"]["stage"], "shadows");
        assert_eq!(json["best"]["stage"]["name"], "figure 6");
    }

    /// Figure 7 rendered without shadows, checked with the defaults: shadows are missing.
    #[test]
    fn figure_7_without_shadows_is_named() {
        let scene = cornell_box();
        let mut no_shadows = settings(Stage::Lab, 64);
        no_shadows.shading.shadows = false;
        let image = rendered(&scene, &no_shadows);
        let r = check(&scene, &settings(Stage::Lab, 64), &image)
            .unwrap()
            .report;
        assert_eq!(r.best.mistake, OTHER_STAGE, "{r:?}");
        let stage = r.best.stage.as_ref().unwrap();
        assert_eq!(stage.name, "figure 7 without shadows");
        assert_eq!(stage.differs, "shadows are missing");
        assert!(r.best.fix.contains("shadow ray"), "{}", r.best.fix);
        assert!(r.best.fix.contains("--shadows off"), "{}", r.best.fix);
    }

    /// The exact figure × 0.6 is the factor 0.6 in every channel, said so; a factor per
    /// channel is given per channel. Its difference picture is not white all over.
    #[test]
    fn a_global_factor_is_found() {
        let scene = cornell_box();
        let s = settings(Stage::Lab, 64);
        let linear = render(&scene, &s);
        for (k, said) in [
            (glam::Vec3::splat(0.6), "× 0.60 everywhere"),
            (
                glam::Vec3::new(0.6, 0.5, 0.6),
                "× (0.60, 0.50, 0.60) in R, G, B",
            ),
        ] {
            let image = factor::scaled(&linear, k);
            let checked = check(&scene, &s, &image).unwrap();
            let r = &checked.report;
            assert_eq!(r.best.mistake, FACTOR, "{r:?}");
            assert_eq!(r.best.explains, 1.0);
            let got = r.best.factor.unwrap();
            for c in 0..3 {
                assert!((got[c] - f64::from(k[c])).abs() < 0.005, "{got:?}");
            }
            assert!(r.to_text().contains(said), "{}", r.to_text());
            assert!(r.best.fix.contains("power P"), "{}", r.best.fix);
            let picture = compare::difference_picture(&image, &checked.figure);
            let white = picture.data.iter().filter(|v| **v == 255).count();
            assert!(white * 10 < picture.data.len(), "{white} white");
        }
    }

    /// The header says what the figure checked against computes with its switches: without
    /// shadows no "with shadows", without N no N.
    #[test]
    fn the_header_follows_the_switches() {
        let scene = cornell_box();
        let header = |shadows: bool, indirect: bool| {
            let mut s = settings(Stage::Lab, 32);
            s.shading.shadows = shadows;
            s.shading.indirect = indirect;
            let image = rendered(&scene, &s);
            let r = check(&scene, &s, &image).unwrap().report;
            assert_eq!(r.best.mistake, "none");
            r.to_text().lines().next().unwrap().to_owned()
        };
        let all = header(true, true);
        assert!(
            all.contains("ρ·(D + N)") && all.contains("with shadows"),
            "{all}"
        );
        assert!(all.contains("figure 7,"), "{all}");
        let no_shadows = header(false, true);
        assert!(!no_shadows.contains("shadows (§"), "{no_shadows}");
        assert!(
            no_shadows.contains("figure 7 without shadows"),
            "{no_shadows}"
        );
        let no_n = header(true, false);
        assert!(!no_n.contains('N'), "{no_n}");
        assert!(no_n.contains("figure 6,"), "{no_n}");
    }

    /// A best candidate that explains enough but no more than the exact figure is not named,
    /// and the text says what was compared instead of contradicting itself.
    #[test]
    fn unknown_says_what_was_compared() {
        let own = StageSwitches::preset(Stage::Lab);
        let candidates = [Candidate {
            mistake: Mistake::PixelCorner,
            explains: 0.95,
        }];
        let (best, _) = verdict([64, 64], 0.96, 0.96, &candidates, &[], None, own);
        assert_eq!(best.mistake, "unknown");
        assert!(
            best.fix.contains(
                "pixel-corner, explains 95.0 %, but the exact figure itself explains 96.0 %"
            ),
            "{}",
            best.fix
        );
        assert!(
            best.fix.contains("no mistake explains it better"),
            "{}",
            best.fix
        );
        assert!(!best.fix.contains("90.0 % are needed"), "{}", best.fix);
    }

    /// The exact figure saved as JPEG at qualities 75 to 95 is `none`; a classic mistake, or
    /// another stage, saved as JPEG at quality 90 is still named.
    #[test]
    fn a_jpeg_is_judged_by_its_blocks() {
        let scene = cornell_box();
        for (stage, side) in [(Stage::Lab, 96), (Stage::Shadows, 128), (Stage::Direct, 96)] {
            let s = settings(stage, side);
            let figures = Figures::render(&scene, &s).unwrap();
            for quality in [75, 85, 90, 95] {
                let (jpeg, encoding) = as_jpeg(&figures.figure, quality);
                assert_eq!(encoding, Encoding::Jpeg);
                let r = figures.judge_encoded(&jpeg, encoding).unwrap();
                assert_eq!(r.best.mistake, "none", "{stage} q{quality}: {r:?}");
                assert!(r.notes.iter().any(|n| n.contains("JPEG")), "{:?}", r.notes);
                // Pixel by pixel, the same image is not the exact figure.
                let lossless = figures.judge(&jpeg).unwrap();
                assert_ne!(lossless.best.mistake, "none", "{stage} q{quality}");
            }
        }
        let s = settings(Stage::Lab, 96);
        let figures = Figures::render(&scene, &s).unwrap();
        for mistake in [
            Mistake::No4Pi,
            Mistake::FlippedNormal,
            Mistake::NoRho,
            Mistake::ShadowDropsIndirect,
            Mistake::UpsideDown,
        ] {
            let look = &mistakes::looks(&scene, &s, mistake)[0];
            let (jpeg, encoding) = as_jpeg(look, 90);
            let r = figures.judge_encoded(&jpeg, encoding).unwrap();
            assert_eq!(r.best.mistake, mistake.name(), "{r:?}");
        }
        let six = rendered(&scene, &settings(Stage::Shadows, 96));
        let (jpeg, encoding) = as_jpeg(&six, 90);
        let r = figures.judge_encoded(&jpeg, encoding).unwrap();
        assert_eq!(r.best.mistake, OTHER_STAGE, "{r:?}");
    }
}
