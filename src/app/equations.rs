//! "Your equations": the student types the lab's quantities (`d`, `shadowStart`, `shadowed`,
//! `D`, `R`) in an editor each, and sees the image they make beside the exact figure, the
//! share of pixels within 2/255, and how each quantity differs from the lab's
//! ([`raylab_core::teaching::sandbox`], the same as `raylab render --equations`).
//!
//! Each keystroke compiles the texts on the UI thread (microseconds); the image is made on a
//! worker thread of its own, which takes only the newest job when it is free, so stale work is
//! skipped. A change to `shadowed`, `D` or `R` evaluates the recorded hits again
//! ([`Recording::evaluate`]); a change to `d` or `shadowStart`, or to the settings, traces
//! again ([`sandbox::record`]). While a text does not compile, the last good image stays,
//! marked stale, and the error is underlined in its editor.

use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::time::Instant;

use eframe::egui;
use egui::text::{LayoutJob, TextFormat};
use raylab_core::shading::light::LightKind;
use raylab_core::shapes::scene::Scene;
use raylab_core::teaching::check::mistakes::Mistake;
use raylab_core::teaching::check::{self, Rgb8};
use raylab_core::teaching::sandbox::{
    self, Equations, Quantity, Recording, SandboxError, carried, examples, lex,
};
use raylab_core::transport::film::Image;
use raylab_core::transport::progressive::catch_panic;
use raylab_core::transport::settings::EquationTexts;
use raylab_core::{RenderSettings, Stage};

use super::check::{color_image, figure_settings};
use super::compare::{Divider, Texture, paint_wipe, tag};
use super::viewport::Overlay;

/// What the worker makes of a job.
struct Job {
    generation: u64,
    scene: Arc<Scene>,
    settings: RenderSettings,
    equations: Equations,
}

/// The student's image, the exact figure and how they compare, for one job.
pub struct Evaluated {
    generation: u64,
    /// The student's image, linear (NaN or infinite pixels magenta).
    pub image: Arc<Image>,
    pub student: Rgb8,
    pub figure: Rgb8,
    pub difference: Rgb8,
    pub difference_gain: f64,
    /// The share of pixels within 2/255 of the exact figure.
    pub share: f64,
    /// Pixels that came out NaN or infinite.
    pub non_finite: usize,
    /// Each written quantity's verdict, as [`sandbox::judge`] words it.
    pub verdicts: Vec<(Quantity, String)>,
    /// Whether the camera and shadow rays were traced again (else only evaluated).
    pub retraced: bool,
    /// What the image was evaluated from, for the inspector's explanation of a pixel.
    pub recording: Arc<Recording>,
    pub equations: Equations,
    pub ms: f64,
}

/// The panel's state: the editors' texts, what they compile to, and the newest image.
pub struct YourEquations {
    /// Each quantity's text, in [`Quantity::ALL`]'s order.
    texts: [String; 5],
    /// Whether the student wrote it; if not, its editor shows the lab's for the settings in
    /// force and the lab's own is used (bit for bit).
    written: [bool; 5],
    /// Each text's errors, as last compiled.
    errors: [Vec<SandboxError>; 5],
    /// The texts and switches last compiled (a keystroke compiles again).
    compiled_for: Option<([String; 5], [bool; 5])>,
    /// The equations of the texts, when every one compiles.
    equations: Option<Equations>,
    /// Each written text compiled on its own, when it compiles.
    compiled_one: [Option<Equations>; 5],
    /// The newest job sent: its generation, settings and equations.
    sent: Option<(u64, RenderSettings, Equations)>,
    jobs: Option<Sender<Job>>,
    results: Option<Receiver<Result<Evaluated, (u64, String)>>>,
    /// The newest result, and the settings and equations it was made for.
    done: Option<(RenderSettings, Equations, Result<Evaluated, String>)>,
    student: Texture,
    figure: Texture,
    difference_picture: Texture,
    pub divider: Divider,
    /// Show the difference picture instead of the wipe.
    pub difference: bool,
    /// Whether the image shown is stale, as of this frame's [`YourEquations::update`].
    stale_mark: bool,
}

impl Default for YourEquations {
    fn default() -> Self {
        Self {
            texts: Default::default(),
            written: [false; 5],
            errors: Default::default(),
            compiled_for: None,
            equations: Some(Equations::lab()),
            compiled_one: Default::default(),
            sent: None,
            jobs: None,
            results: None,
            done: None,
            student: Texture::default(),
            figure: Texture::default(),
            difference_picture: Texture::default(),
            divider: Divider::default(),
            difference: false,
            stale_mark: false,
        }
    }
}

/// Why the sandbox cannot render these settings, if it cannot: it computes the lab's loop
/// (the lab's stages, a point light, the shaded image).
pub fn unsupported(live: &RenderSettings) -> Option<&'static str> {
    if !Stage::LAB.contains(&live.shading.stage) {
        return Some("Your equations compute the lab's stages: choose one of figures 2 to 7.");
    }
    if !matches!(live.light.kind, LightKind::Point) {
        return Some("Your equations use the lab's point light: choose the point light.");
    }
    if live.view != raylab_core::transport::view::View::Shaded {
        return Some("Your equations make the shaded image: choose the shaded view.");
    }
    None
}

impl YourEquations {
    /// Whether any quantity is the student's.
    pub fn any_written(&self) -> bool {
        self.written.iter().any(|w| *w)
    }

    /// Whether the overlay (the student's image against the figure) is shown.
    pub fn active(&self, live: &RenderSettings) -> bool {
        self.any_written() && unsupported(live).is_none()
    }

    /// Quantity `q`'s text in its editor.
    #[cfg(test)]
    pub fn text(&self, q: Quantity) -> &str {
        &self.texts[q as usize]
    }

    /// Sets quantity `q`'s text, as typing it would.
    pub fn set_text(&mut self, q: Quantity, text: &str, live: &RenderSettings) {
        self.texts[q as usize] = text.to_owned();
        self.written[q as usize] = text != examples::lab_text(q, &live.shading);
    }

    /// Quantity `q` back to the lab's own.
    pub fn reset(&mut self, q: Quantity) {
        self.written[q as usize] = false;
    }

    /// The texts the settings carry: those the student wrote.
    pub fn carried(&self) -> EquationTexts {
        let mut texts = EquationTexts::default();
        for q in Quantity::ALL
            .into_iter()
            .filter(|q| self.written[*q as usize])
        {
            *carried::text_mut(&mut texts, q) = Some(self.texts[q as usize].clone());
        }
        texts
    }

    /// Takes the texts a file carried (a screenshot, a scene file); the others are the lab's.
    pub fn load(&mut self, texts: &EquationTexts) {
        for q in Quantity::ALL {
            match carried::text_of(texts, q) {
                Some(text) => {
                    self.texts[q as usize] = text.to_owned();
                    self.written[q as usize] = true;
                }
                None => self.written[q as usize] = false,
            }
        }
    }

    /// The settings and equations the image should be made for now.
    fn wanted(&self, live: &RenderSettings) -> Option<(RenderSettings, Equations)> {
        Some((figure_settings(live), self.equations.clone()?))
    }

    /// The newest result, if it is for the settings and equations in force.
    pub fn fresh(&self, live: &RenderSettings) -> Option<&Evaluated> {
        let (settings, equations) = self.wanted(live)?;
        match &self.done {
            Some((s, e, Ok(evaluated))) if *s == settings && *e == equations => Some(evaluated),
            _ => None,
        }
    }

    /// The student's pixel (`x`, `y`) explained, each part of their text with its value there
    /// beside the lab's terms ([`Recording::explain`]), when their image of the settings in
    /// force is on screen.
    pub fn explained(
        &self,
        live: &RenderSettings,
        x: u32,
        y: u32,
    ) -> Option<Vec<raylab_core::teaching::inspect::InspectLine>> {
        let evaluated = self.fresh(live)?;
        Some(
            evaluated
                .recording
                .explain(&evaluated.equations, x, y)?
                .lines(),
        )
    }

    /// Quantity `q`'s verdict, if the newest image made judged the text in its editor now
    /// (for the stage in force): a verdict stays while another text is being fixed.
    pub fn verdict(&self, q: Quantity, live: &RenderSettings) -> Option<&str> {
        let one = self.compiled_one[q as usize].as_ref()?;
        let (settings, equations, Ok(evaluated)) = self.done.as_ref()? else {
            return None;
        };
        if settings.shading.stage != live.shading.stage || equations.tape(q) != one.tape(q) {
            return None;
        }
        evaluated
            .verdicts
            .iter()
            .find(|(v, _)| *v == q)
            .map(|(_, text)| text.as_str())
    }

    /// The newest image made, fresh or not.
    pub fn last(&self) -> Option<&Evaluated> {
        self.done.as_ref().and_then(|(_, _, r)| r.as_ref().ok())
    }

    /// Whether the image shown is not that of the texts and settings in force: a text does not
    /// compile, or the newest is still being made.
    pub fn is_stale(&self, live: &RenderSettings) -> bool {
        self.fresh(live).is_none()
    }

    /// Whether nothing is being made and the image is up to date (or nothing is to be made).
    #[cfg(test)]
    pub fn is_settled(&self, live: &RenderSettings) -> bool {
        if !self.active(live) {
            return true;
        }
        self.equations.is_none()
            || self.fresh(live).is_some()
            || matches!(&self.done, Some((s, e, Err(_)))
                if Some((s.clone(), e.clone())) == self.wanted(live))
    }

    /// What a screenshot saves while the student's image is shown: that image, with the
    /// settings that make it again (one ray through each pixel's centre, the equations).
    pub fn screenshot(&self, live: &RenderSettings) -> Option<(Arc<Image>, RenderSettings)> {
        if !self.active(live) {
            return None;
        }
        let evaluated = self.fresh(live)?;
        let mut settings = figure_settings(live);
        settings.display = live.display;
        settings.equations = self.carried();
        Some((Arc::clone(&evaluated.image), settings))
    }

    /// Once a UI frame: the lab's texts follow the settings, a change compiles, a finished
    /// image is taken, and a job is sent when the texts or settings changed. Never waits.
    pub fn update(
        &mut self,
        ctx: &egui::Context,
        live: &RenderSettings,
        scene: &Arc<Scene>,
        scene_ready: bool,
    ) {
        for q in Quantity::ALL {
            if !self.written[q as usize] {
                let lab = examples::lab_text(q, &live.shading);
                if self.texts[q as usize] != lab {
                    lab.clone_into(&mut self.texts[q as usize]);
                }
            }
        }
        self.compile();
        self.receive(ctx);
        self.stale_mark = self.is_stale(live);
        let Some((settings, equations)) = self.wanted(live) else {
            return;
        };
        let sent = self
            .sent
            .as_ref()
            .is_some_and(|(_, s, e)| *s == settings && *e == equations);
        if self.active(live) && scene_ready && !sent {
            let generation = self.sent.as_ref().map_or(1, |(g, _, _)| g + 1);
            let job = Job {
                generation,
                scene: Arc::clone(scene),
                settings: settings.clone(),
                equations: equations.clone(),
            };
            let sender = self.jobs.get_or_insert_with(|| {
                let (jobs, job_rx) = mpsc::channel();
                let (result_tx, results) = mpsc::channel();
                let repaint = ctx.clone();
                // The thread ends when the panel (its sender) goes.
                let _ = std::thread::Builder::new()
                    .name("raylab-equations".to_owned())
                    .stack_size(raylab_core::base::memory::WORKER_STACK_BYTES)
                    .spawn(move || work(&job_rx, &result_tx, &repaint));
                self.results = Some(results);
                jobs
            });
            if sender.send(job).is_err() {
                self.done = Some((
                    settings.clone(),
                    equations.clone(),
                    Err("the equations' worker stopped".to_owned()),
                ));
            }
            self.sent = Some((generation, settings, equations));
        }
    }

    /// Compiles the texts if they changed: each written one on its own, its errors kept.
    fn compile(&mut self) {
        let now = (self.texts.clone(), self.written);
        if self.compiled_for.as_ref() == Some(&now) {
            return;
        }
        let mut equations = Equations::lab();
        let mut ok = true;
        for q in Quantity::ALL {
            self.errors[q as usize].clear();
            self.compiled_one[q as usize] = None;
            if !self.written[q as usize] {
                continue;
            }
            match carried::compile_one(q, &self.texts[q as usize]) {
                Ok(one) => {
                    equations.take(q, &one);
                    self.compiled_one[q as usize] = Some(one);
                }
                Err(errors) => {
                    self.errors[q as usize] = errors;
                    ok = false;
                }
            }
        }
        self.equations = ok.then_some(equations);
        self.compiled_for = Some(now);
    }

    /// Takes the newest finished image, if any, onto the textures.
    fn receive(&mut self, ctx: &egui::Context) {
        let Some(results) = &self.results else {
            return;
        };
        let mut newest = None;
        loop {
            match results.try_recv() {
                Ok(result) => newest = Some(result),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    let generation = self.sent.as_ref().map_or(0, |(g, _, _)| *g);
                    newest = Some(Err((generation, "the equations' worker stopped".into())));
                    self.jobs = None;
                    self.results = None;
                    break;
                }
            }
        }
        let Some(result) = newest else {
            return;
        };
        let generation = match &result {
            Ok(e) => e.generation,
            Err((g, _)) => *g,
        };
        // Only the newest job's result is for the settings and equations it was sent with.
        let Some((sent, settings, equations)) = self.sent.clone() else {
            return;
        };
        if generation != sent {
            return;
        }
        let result = result.map_err(|(_, e)| e);
        if let Ok(e) = &result {
            self.student
                .set(ctx, "raylab-equations-yours", color_image(&e.student));
            self.figure
                .set(ctx, "raylab-equations-figure", color_image(&e.figure));
            self.difference_picture.set(
                ctx,
                "raylab-equations-difference",
                color_image(&e.difference),
            );
        }
        self.done = Some((settings, equations, result));
    }

    /// The student's image left of the divider and the exact figure right of it, or the
    /// difference picture; the stale mark and the NaN count on the image.
    fn paint_overlay(&mut self, ui: &egui::Ui, rect: egui::Rect, stale: bool) {
        let painter = ui.painter().with_clip_rect(rect);
        let ppp = ui.ctx().pixels_per_point();
        let Some(last) = self.last() else {
            painter.rect_filled(rect, 0.0, egui::Color32::from_gray(20));
            tag(
                &painter,
                rect.center_bottom(),
                egui::Align2::CENTER_BOTTOM,
                "rendering your equations…",
            );
            return;
        };
        let (gain, non_finite, share) = (last.difference_gain, last.non_finite, last.share);
        if self.difference
            && let Some(id) = self.difference_picture.id_for(rect, ppp)
        {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            painter.image(id, rect, uv, egui::Color32::WHITE);
            tag(
                &painter,
                rect.left_top(),
                egui::Align2::LEFT_TOP,
                &format!("|yours − figure| × {gain:.1}"),
            );
        } else {
            let sides = [
                self.student.id_for(rect, ppp),
                self.figure.id_for(rect, ppp),
            ];
            let x = self.divider.x(rect);
            paint_wipe(&painter, rect, x, sides, ["yours", "exact figure"], true);
        }
        let mut line = format!("{:.1} % of pixels within 2/255", 100.0 * share);
        if non_finite > 0 {
            line += &format!(" · {non_finite} NaN/∞ pixels (magenta)");
        }
        tag(
            &painter,
            rect.left_bottom(),
            egui::Align2::LEFT_BOTTOM,
            &line,
        );
        if stale {
            let what = if self.equations.is_none() {
                "STALE: a text does not compile; this is the last image that did"
            } else {
                "STALE: rendering…"
            };
            let plate = egui::Rect::from_min_size(rect.min, egui::vec2(rect.width(), 4.0));
            painter.rect_filled(plate, 0.0, egui::Color32::from_rgb(230, 60, 40));
            tag(&painter, rect.center_top(), egui::Align2::CENTER_TOP, what);
        }
    }
}

/// The worker: takes the newest job waiting, makes its image (tracing again only when the
/// settings, `d` or `shadowStart` changed), the exact figure (once per settings) and their
/// comparison, and sends them back.
fn work(
    jobs: &Receiver<Job>,
    results: &Sender<Result<Evaluated, (u64, String)>>,
    repaint: &egui::Context,
) {
    let mut recording: Option<(Arc<Scene>, RenderSettings, Arc<Recording>)> = None;
    let mut figure: Option<(Arc<Scene>, RenderSettings, Rgb8)> = None;
    while let Ok(mut job) = jobs.recv() {
        // Older jobs waiting are stale: only the newest is made.
        while let Ok(newer) = jobs.try_recv() {
            job = newer;
        }
        let generation = job.generation;
        let made = catch_panic(|| make(&job, &mut recording, &mut figure));
        if made.is_err() {
            recording = None;
            figure = None;
        }
        let sent = results.send(made.map_err(|e| (generation, e)));
        repaint.request_repaint();
        if sent.is_err() {
            return;
        }
    }
}

/// One job's image and comparison.
fn make(
    job: &Job,
    recording: &mut Option<(Arc<Scene>, RenderSettings, Arc<Recording>)>,
    figure: &mut Option<(Arc<Scene>, RenderSettings, Rgb8)>,
) -> Evaluated {
    let start = Instant::now();
    let same = |scene: &Arc<Scene>, settings: &RenderSettings| {
        Arc::ptr_eq(scene, &job.scene) && *settings == job.settings
    };
    let retraced = !recording
        .as_ref()
        .is_some_and(|(scene, s, r)| same(scene, s) && r.fits(&job.equations));
    if retraced {
        let traced = sandbox::record(&job.scene, &job.settings, &job.equations);
        *recording = Some((
            Arc::clone(&job.scene),
            job.settings.clone(),
            Arc::new(traced),
        ));
    }
    if !figure.as_ref().is_some_and(|(scene, s, _)| same(scene, s)) {
        let image = raylab_core::transport::render::render(&job.scene, &job.settings);
        *figure = Some((
            Arc::clone(&job.scene),
            job.settings.clone(),
            Rgb8::from_linear(&image),
        ));
    }
    let (Some((_, _, recorded)), Some((_, _, exact))) = (recording.as_ref(), figure.as_ref())
    else {
        unreachable!("both made above");
    };
    let rendered = recorded.evaluate(&job.equations);
    let student = Rgb8::from_linear(&rendered.image);
    let share = check::compare::share_within(&student, exact);
    let difference_gain = check::compare::difference_gain(&student, exact);
    let difference = check::compare::difference_picture_with_gain(&student, exact, difference_gain);
    let stage = job.settings.shading.stage;
    let verdicts = job
        .equations
        .written()
        .filter_map(|q| Some((q, sandbox::judge(&job.equations, q, stage)?.to_string())))
        .collect();
    Evaluated {
        generation: job.generation,
        image: Arc::new(rendered.image),
        student,
        figure: exact.clone(),
        difference,
        difference_gain,
        share,
        non_finite: rendered.non_finite,
        verdicts,
        retraced,
        recording: Arc::clone(recorded),
        equations: job.equations.clone(),
        ms: start.elapsed().as_secs_f64() * 1e3,
    }
}

impl Overlay for YourEquations {
    fn paint(&mut self, ui: &egui::Ui, rect: egui::Rect, _live: egui::TextureId) {
        // The stale mark is decided by the caller, which knows the settings in force.
        let stale = self.stale_mark;
        self.paint_overlay(ui, rect, stale);
    }

    fn divider_input(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        on_marker: bool,
    ) -> bool {
        self.divider
            .input(ui, response, rect, on_marker, !self.difference)
    }
}

/// How a piece of the text is coloured.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Plain,
    /// A quantity's name (`d`, `D`, `R`, …).
    Quantity,
    /// One of the lab's inputs (`lightPos`, `normal`, …).
    Input,
    Function,
    /// A number or a named constant (`pi`).
    Number,
    /// `let`, a C++ type, `true`, `false`.
    Keyword,
    Comment,
}

const KEYWORDS: [&str; 10] = [
    "let", "const", "vec3", "float", "double", "bool", "int", "auto", "true", "false",
];

/// Each byte's colour kind: the language's own tokens ([`lex`]); what they skip and is not
/// white space is a comment; after a character the lexer refuses, plain.
fn kinds(text: &str) -> Vec<Kind> {
    let mut kinds = vec![Kind::Plain; text.len()];
    let (tokens, lexed) = match lex::lex(text) {
        Ok(tokens) => (tokens, text.len()),
        Err(e) => {
            let end = e.span.start.min(text.len());
            (lex::lex(&text[..end]).unwrap_or_default(), end)
        }
    };
    let mut covered = vec![false; lexed];
    for (i, token) in tokens.iter().enumerate() {
        let kind = match &token.tok {
            lex::Tok::Num(_) => Kind::Number,
            lex::Tok::Name(name) => {
                let called = tokens
                    .get(i + 1)
                    .is_some_and(|t| t.tok == lex::Tok::Punct("("));
                if KEYWORDS.contains(&name.as_str()) && !called {
                    Kind::Keyword
                } else if called {
                    Kind::Function
                } else if Quantity::by_name(name).is_some() {
                    Kind::Quantity
                } else if sandbox::input(name).is_some() {
                    Kind::Input
                } else if sandbox::compile::CONSTANTS.contains(&name.as_str()) {
                    Kind::Number
                } else {
                    Kind::Plain
                }
            }
            _ => Kind::Plain,
        };
        let (start, end) = (token.span.start.min(lexed), token.span.end.min(lexed));
        kinds[start..end].fill(kind);
        covered[start..end].fill(true);
    }
    for (i, b) in text.bytes().enumerate().take(lexed) {
        if !covered[i] && !b.is_ascii_whitespace() {
            kinds[i] = Kind::Comment;
        }
    }
    kinds
}

/// The editor's text coloured by [`kinds`], each error's span underlined in red (an error at
/// the end of the text marks its last character).
fn highlight(text: &str, errors: &[SandboxError], style: &egui::Style) -> LayoutJob {
    let dark = style.visuals.dark_mode;
    let font = egui::TextStyle::Monospace.resolve(style);
    let colour = |kind: Kind| match (kind, dark) {
        (Kind::Plain, _) => style.visuals.text_color(),
        (Kind::Quantity, true) => egui::Color32::from_rgb(255, 170, 90),
        (Kind::Quantity, false) => egui::Color32::from_rgb(190, 90, 0),
        (Kind::Input, true) => egui::Color32::from_rgb(120, 185, 255),
        (Kind::Input, false) => egui::Color32::from_rgb(20, 90, 190),
        (Kind::Function, true) => egui::Color32::from_rgb(230, 210, 110),
        (Kind::Function, false) => egui::Color32::from_rgb(140, 100, 0),
        (Kind::Number, true) => egui::Color32::from_rgb(140, 220, 140),
        (Kind::Number, false) => egui::Color32::from_rgb(20, 130, 40),
        (Kind::Keyword, true) => egui::Color32::from_rgb(200, 150, 255),
        (Kind::Keyword, false) => egui::Color32::from_rgb(120, 50, 180),
        (Kind::Comment, _) => egui::Color32::from_gray(130),
    };
    let kinds = kinds(text);
    let mut underlined = vec![false; text.len()];
    for e in errors {
        let end = e.span.end.min(text.len());
        let mut start = e.span.start.min(end);
        if start == end {
            // Nothing to underline: the character before, if any.
            start = text[..end]
                .char_indices()
                .next_back()
                .map_or(end, |(i, _)| i);
        }
        underlined[start..end].fill(true);
    }
    let mut job = LayoutJob::default();
    let mut chars = text.char_indices().peekable();
    while let Some((start, _)) = chars.next() {
        let key = (kinds[start], underlined[start]);
        let mut end = text.len();
        while let Some(&(i, _)) = chars.peek() {
            if (kinds[i], underlined[i]) != key {
                end = i;
                break;
            }
            chars.next();
        }
        let mut format = TextFormat {
            font_id: font.clone(),
            color: colour(key.0),
            italics: key.0 == Kind::Comment,
            ..Default::default()
        };
        if key.1 {
            format.underline = egui::Stroke::new(2.0, egui::Color32::from_rgb(240, 60, 50));
            format.background = egui::Color32::from_rgba_unmultiplied(240, 60, 50, 40);
        }
        job.append(&text[start..end], 0.0, format);
    }
    job
}

/// The "Your equations" group of the side panel: an editor per quantity, its error or verdict,
/// Reset, the classic mistakes to load, and how the image compares.
pub fn equations_ui(ui: &mut egui::Ui, eq: &mut YourEquations, live: &RenderSettings) {
    ui.label(
        "Write the lab's quantities yourself, as in your C++: your image is drawn beside the \
         exact figure (drag the divider), and each quantity is compared with the lab's.",
    );
    if let Some(why) = unsupported(live) {
        ui.colored_label(ui.visuals().warn_fg_color, why);
    }
    ui.horizontal_wrapped(|ui| {
        ui.menu_button("Load a classic mistake…", |ui| {
            for m in Mistake::catalogue() {
                let Some((q, text)) = examples::mistake_text(m) else {
                    continue;
                };
                if ui
                    .button(format!("{} ({})", m.name(), q.name()))
                    .on_hover_text(m.what())
                    .clicked()
                {
                    eq.set_text(q, text, live);
                    ui.close();
                }
            }
        });
        if eq.any_written() && ui.button("Reset all to the lab's").clicked() {
            for q in Quantity::ALL {
                eq.reset(q);
            }
        }
    });
    summary_ui(ui, eq, live);
    for q in Quantity::ALL {
        ui.separator();
        let label = ui.horizontal(|ui| {
            let label = ui.strong(q.name());
            ui.weak(q.what());
            if eq.written[q as usize] {
                ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                    if ui
                        .small_button("Reset to the lab's")
                        .on_hover_text(format!("{} as the lab computes it", q.name()))
                        .clicked()
                    {
                        eq.reset(q);
                    }
                });
            }
            label
        });
        let errors = eq.errors[q as usize].clone();
        let mut layouter = |ui: &egui::Ui, buf: &dyn egui::TextBuffer, wrap_width: f32| {
            let mut job = highlight(buf.as_str(), &errors, ui.style());
            job.wrap.max_width = wrap_width;
            ui.fonts_mut(|f| f.layout_job(job))
        };
        let response = ui.add(
            egui::TextEdit::multiline(&mut eq.texts[q as usize])
                .id_salt(("equation", q.name()))
                .code_editor()
                .desired_rows(2)
                .desired_width(f32::INFINITY)
                .layouter(&mut layouter),
        );
        let response = response.labelled_by(label.inner.id);
        let response = response.on_hover_text(format!("Your {} ({})", q.name(), q.what()));
        if response.changed() {
            let lab = examples::lab_text(q, &live.shading);
            eq.written[q as usize] = eq.texts[q as usize] != lab;
        }
        for e in &errors {
            ui.colored_label(
                ui.visuals().error_fg_color,
                format!("line {}, column {}: {}", e.line, e.column, e.message),
            );
        }
        if !eq.written[q as usize] {
            ui.weak("The lab's (edit to write your own)");
        } else if errors.is_empty() {
            match eq.verdict(q, live) {
                Some(verdict) => {
                    let equal = verdict.starts_with("equal to the lab's");
                    let text = format!("Verdict: {verdict}");
                    if equal {
                        ui.colored_label(egui::Color32::from_rgb(90, 190, 90), text);
                    } else {
                        ui.colored_label(ui.visuals().warn_fg_color, text);
                    }
                }
                None => {
                    ui.weak("Judging…");
                }
            }
        }
    }
}

/// How the image compares, and whether it is stale.
fn summary_ui(ui: &mut egui::Ui, eq: &mut YourEquations, live: &RenderSettings) {
    if !eq.any_written() {
        ui.weak("Every quantity is the lab's: the image is the exact figure.");
        return;
    }
    ui.checkbox(&mut eq.difference, "Difference |yours − figure|")
        .on_hover_text(
            "Where your image differs from the exact figure, amplified; black where they agree",
        );
    let stale = eq.is_stale(live);
    if let Some(e) = eq.last() {
        let share = format!(
            "Yours: {:.1} % of pixels within 2/255 of the exact figure",
            100.0 * e.share
        );
        ui.label(share);
        if e.non_finite > 0 {
            ui.colored_label(
                egui::Color32::from_rgb(255, 0, 255),
                format!("{} pixels came out NaN or infinite (magenta)", e.non_finite),
            );
        }
        if !stale {
            ui.weak(format!(
                "{} in {:.0} ms",
                if e.retraced {
                    "Traced and evaluated"
                } else {
                    "Evaluated again (no tracing)"
                },
                e.ms
            ));
        }
    }
    if let Some((_, _, Err(e))) = &eq.done {
        ui.colored_label(ui.visuals().error_fg_color, e);
    }
    if eq.equations.is_none() {
        ui.colored_label(
            ui.visuals().error_fg_color,
            "Stale: a text below does not compile; the image is the last one that did.",
        );
    } else if stale {
        ui.weak("Rendering…");
    }
}
