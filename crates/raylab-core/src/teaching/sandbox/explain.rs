//! One pixel of the student's image explained: at each hit it is made of, the lab's terms and,
//! for every quantity, the student's value with each part of their text beside the lab's value
//! from the same inputs ([`Recording::explain`](super::Recording::explain) makes it).

use glam::Vec3;
use serde::Serialize;

use super::Quantity;
use super::compile::{Equations, Part};
use super::tape::Ty;
use crate::teaching::inspect::{InspectLine, lines_text, num, vector};

/// A value of the language: a number, a vec3 or a bool (JSON: a number, `[x, y, z]` or a
/// bool; NaN and infinity are `null`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    Number(f32),
    Vec3([f32; 3]),
    Bool(bool),
}

impl Value {
    /// A value of type `ty` from its components (a bool is 1.0 or 0.0; one component is read
    /// for a number or a bool).
    pub fn of(ty: Ty, c: [f32; 3]) -> Value {
        match ty {
            Ty::Number => Value::Number(c[0]),
            Ty::Vec3 => Value::Vec3(c),
            Ty::Bool => Value::Bool(c[0] != 0.0),
        }
    }

    /// As the inspector prints numbers: `0.906`, `(0, 1, 0)`, `true`.
    pub fn text(&self) -> String {
        match *self {
            Value::Number(x) => num(x),
            Value::Vec3(v) => vector(Vec3::from_array(v)),
            Value::Bool(b) => b.to_string(),
        }
    }
}

/// A part of the student's text and its value at the hit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartValue {
    /// 1-based line and column of the part in the text, and its bytes `start..end` there.
    pub line: usize,
    pub column: usize,
    pub start: usize,
    pub end: usize,
    /// The name a statement defines (`r`, `D`); `None` for an expression inside one.
    pub name: Option<String>,
    pub text: String,
    pub value: Value,
}

impl PartValue {
    /// `part`'s value read from the slots of its quantity's tape run over the hit.
    pub(super) fn new(part: &Part, slots: &[[f32; 1]]) -> Self {
        Self {
            line: part.line,
            column: part.column,
            start: part.span.start,
            end: part.span.end,
            name: part.name.clone(),
            text: part.text.clone(),
            value: Value::of(part.ty, part.value(slots)),
        }
    }
}

/// A quantity at a hit (or, for `d`, at the pixel).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QuantityValue {
    /// Its name: `d`, `shadowStart`, `shadowed`, `D` or `R`.
    pub name: &'static str,
    /// The student's value, where they wrote it (for `d`, the direction as written; the ray
    /// traced goes along it normalised).
    pub yours: Option<Value>,
    /// The lab's value from the same inputs: what the image uses where the student writes
    /// none (`d`: the lab's ray's unit direction through the pixel's centre; `D`: with the
    /// `shadowed` in force; `R`: with the `D` in force).
    pub lab: Value,
    /// Every part of the student's text it computes, statement by statement in the order of
    /// the text (empty where they did not write it).
    pub parts: Vec<PartValue>,
}

impl QuantityValue {
    /// Quantity `q`: the student's value and parts from `slots` (their tape run over one
    /// hit), or the lab's alone where they did not write it.
    pub(super) fn new(equations: &Equations, q: Quantity, slots: &[[f32; 1]], lab: Value) -> Self {
        let tape = equations.tape(q);
        Self {
            name: q.name(),
            yours: tape.map(|t| Value::of(t.ty, t.value_in(slots).map(|[v]| v))),
            lab,
            parts: equations
                .parts(q)
                .iter()
                .map(|p| PartValue::new(p, slots))
                .collect(),
        }
    }
}

/// A term the lab gives the student's expressions, and its value at the hit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Term {
    pub name: &'static str,
    pub value: Value,
}

/// One diffuse hit a pixel is made of.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HitValues {
    /// What the pixel gets this hit's R times (1 for the camera ray's own diffuse hit).
    pub weight: [f32; 3],
    /// The lab's terms at the hit (every input but `x`, `y`, `shadowed` and `D`).
    pub terms: Vec<Term>,
    /// `shadowStart`, `shadowed`, `D` and `R`, in the order they are computed.
    pub quantities: Vec<QuantityValue>,
}

/// Pixel `(x, y)` of the student's image explained.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Explanation {
    pub pixel: [u32; 2],
    /// What it is made of: `miss` (nothing hit: black), `diffuse` (its camera ray's diffuse
    /// hit), `specular` (the diffuse hits its mirror and glass branches reach, weighted) or
    /// `bad ray` (the student's `d` is not finite, or 0).
    pub made_of: &'static str,
    /// The pixel's value, as the image has it before a NaN or infinite one is drawn magenta.
    pub value: [f32; 3],
    /// Whether it is finite (else the image shows magenta there and counts it).
    pub finite: bool,
    /// `d` at the pixel, with `x`, `y` and the other terms it reads.
    pub direction: QuantityValue,
    pub direction_terms: Vec<Term>,
    pub hits: Vec<HitValues>,
}

/// How many characters of a part's text the lines show.
const LINE_TEXT: usize = 60;

impl Explanation {
    /// The explanation a line each, as the inspector's lines: the equation column says which
    /// quantity or which line of the text, the text its value (the window shows these under
    /// the pixel inspector; [`Explanation::to_text`] joins them).
    pub fn lines(&self) -> Vec<InspectLine> {
        let mut lines = Vec::new();
        let mut push = |equation: String, text: String| lines.push(InspectLine { equation, text });
        let value = Value::Vec3(self.value).text();
        let made_of = match self.made_of {
            "miss" => "nothing hit",
            "diffuse" => "one diffuse hit",
            "specular" => "mirror or glass: its branches' diffuse hits, weighted",
            _ => "your d is not finite, or 0: no ray",
        };
        let finite = if self.finite {
            String::new()
        } else {
            " — not finite: shown magenta and counted".to_owned()
        };
        push(
            "your pixel".to_owned(),
            format!(
                "({}, {}) = {value}{finite} ({made_of})",
                self.pixel[0], self.pixel[1]
            ),
        );
        let terms = |terms: &[Term]| {
            terms
                .iter()
                .map(|t| format!("{} = {}", t.name, t.value.text()))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if self.direction.yours.is_some() {
            push("the lab's terms".to_owned(), terms(&self.direction_terms));
        }
        quantity_lines(&self.direction, &mut Vec::new(), &mut push);
        for (i, hit) in self.hits.iter().enumerate() {
            if self.made_of == "specular" {
                push(
                    format!("hit {} of {}", i + 1, self.hits.len()),
                    format!("its R is added times {}", Value::Vec3(hit.weight).text()),
                );
            }
            push("the lab's terms".to_owned(), terms(&hit.terms));
            let mut shown = Vec::new();
            for q in &hit.quantities {
                quantity_lines(q, &mut shown, &mut push);
            }
        }
        lines
    }

    /// [`Explanation::lines`] as text, a line each.
    pub fn to_text(&self) -> String {
        lines_text(&self.lines())
    }
}

/// A quantity's line (yours beside the lab's) and its parts' lines; a part shown once at a
/// hit (`shown`: the spans of those already shown), however many quantities use it.
fn quantity_lines(
    q: &QuantityValue,
    shown: &mut Vec<(usize, usize)>,
    push: &mut impl FnMut(String, String),
) {
    let lab = q.lab.text();
    let text = match q.yours {
        None => format!("{lab} (the lab's)"),
        Some(yours) => {
            let same = match (yours, q.lab) {
                _ if q.name == "d" => String::new(),
                (a, b) if a == b => " (equal)".to_owned(),
                _ => " (they differ)".to_owned(),
            };
            let unit = match yours {
                Value::Vec3(v) if q.name == "d" => format!(
                    ", as a unit vector {}",
                    vector(Vec3::from_array(v).normalize_or_zero())
                ),
                _ => String::new(),
            };
            format!("yours {}{unit}; the lab's {lab}{same}", yours.text())
        }
    };
    push(q.name.to_owned(), text);
    for p in &q.parts {
        let key = (p.start, p.end);
        if shown.contains(&key) {
            continue;
        }
        shown.push(key);
        let mut text: String = p.text.chars().take(LINE_TEXT).collect();
        if p.text.chars().count() > LINE_TEXT {
            text.push('…');
        }
        let text = match &p.name {
            Some(name) => format!("{name} = {text} = {}", p.value.text()),
            None => format!("{text} = {}", p.value.text()),
        };
        push(format!("  line {}:{}", p.line, p.column), text);
    }
}
