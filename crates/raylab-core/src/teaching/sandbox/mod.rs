//! The equation sandbox: the lab's quantities as a student writes them, in a small
//! safe language that reads like the lab's C++, compiled and evaluated over the tracer's own
//! per-pixel terms.
//!
//! * The quantities ([`Quantity`]): `d` (the camera ray's direction, equation 24),
//!   `shadowStart` (the shadow ray's origin), `shadowed` (section 5.1), `D` (equation 27, the
//!   lab's `DirectLight`, shadow included) and `R` (equations 28 and 30). Each one given
//!   replaces the lab's own; the others stay the lab's.
//! * The language: [`lex`] → [`parse`] → [`compile`] (types checked, names resolved, vec3
//!   operations taken apart) → a [`tape::Tape`] per quantity, run over one pixel or sixteen.
//!   No loops, no recursion, no I/O; the text's length and each expression's size are capped.
//!   Errors ([`SandboxError`]) carry a byte span of the student's own text, its line and
//!   column, and a message naming the fix.
//! * [`render`] binds the quantities to the tracer: the camera rays (with the student's `d`)
//!   and their diffuse hits are recorded once ([`Recording`]), and `shadowed`, `D` and `R` are
//!   evaluated over the recorded terms without tracing again.

pub mod carried;
pub mod compile;
pub mod error;
pub mod examples;
pub mod explain;
pub mod judge;
pub mod lex;
pub mod parse;
pub mod tape;
mod trace;

#[cfg(test)]
mod tests;

pub use compile::{Equations, Part, compile};
pub use error::{SandboxError, Span};
pub use explain::Explanation;
pub use judge::{Verdict, judge};
pub use tape::{Tape, Ty};
pub use trace::{MAGENTA, Recording, Rendered, record, render};

/// The longest text accepted, in bytes.
pub const MAX_SOURCE_BYTES: usize = 16 * 1024;

/// A quantity the student can write, in the order they are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Quantity {
    /// `d`: the camera ray's direction through pixel (x, y) (equation 24 with the camera's
    /// rotation).
    Direction,
    /// `shadowStart`: where the shadow ray starts.
    ShadowStart,
    /// `shadowed`: whether the light is blocked (section 5.1).
    Shadowed,
    /// `D`: the direct light at a hit, shadow included (equation 27, `DirectLight`).
    Direct,
    /// `R`: the pixel's value (equations 28 and 30).
    Value,
}

impl Quantity {
    pub const ALL: [Quantity; 5] = [
        Quantity::Direction,
        Quantity::ShadowStart,
        Quantity::Shadowed,
        Quantity::Direct,
        Quantity::Value,
    ];

    /// The name it is written with.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Direction => "d",
            Quantity::ShadowStart => "shadowStart",
            Quantity::Shadowed => "shadowed",
            Quantity::Direct => "D",
            Quantity::Value => "R",
        }
    }

    pub fn ty(self) -> Ty {
        match self {
            Quantity::Shadowed => Ty::Bool,
            _ => Ty::Vec3,
        }
    }

    /// What it is, in a few words (for messages).
    pub fn what(self) -> &'static str {
        match self {
            Quantity::Direction => "the camera ray's direction",
            Quantity::ShadowStart => "the shadow ray's origin",
            Quantity::Shadowed => "whether the light is blocked",
            Quantity::Direct => "the direct light",
            Quantity::Value => "the pixel's value",
        }
    }

    pub fn by_name(name: &str) -> Option<Quantity> {
        Quantity::ALL.into_iter().find(|q| q.name() == name)
    }

    /// Whether changing it means tracing again (`d`, `shadowStart`), not only re-evaluating.
    pub fn retraces(self) -> bool {
        matches!(self, Quantity::Direction | Quantity::ShadowStart)
    }
}

/// A value the lab gives the student's expressions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Input {
    pub name: &'static str,
    pub ty: Ty,
    /// Its first component's index among the inputs ([`INPUT_COMPONENTS`] in all).
    pub offset: u16,
    /// The quantities that may use it: `from..=until`.
    pub from: Quantity,
    pub until: Quantity,
    pub what: &'static str,
}

impl Input {
    pub fn available_in(&self, q: Quantity) -> bool {
        (self.from..=self.until).contains(&q)
    }
}

macro_rules! inputs {
    ($($name:literal $ty:ident $from:ident..$until:ident $what:literal;)*) => {
        /// Every input, its components laid out one after the other in this order.
        pub const INPUTS: &[Input] = &{
            let mut list = [$(Input {
                name: $name,
                ty: Ty::$ty,
                offset: 0,
                from: Quantity::$from,
                until: Quantity::$until,
                what: $what,
            }),*];
            let mut i = 1;
            while i < list.len() {
                list[i].offset = list[i - 1].offset + match list[i - 1].ty {
                    Ty::Vec3 => 3,
                    _ => 1,
                };
                i += 1;
            }
            list
        };
    };
}

inputs! {
    "x" Number Direction..Direction "the pixel's column (0 at the left)";
    "y" Number Direction..Direction "the pixel's row (0 at the top)";
    "W" Number Direction..Value "the image's width in pixels";
    "H" Number Direction..Value "the image's height in pixels";
    "focalLength" Number Direction..Value "the focal length f, in pixels";
    "cameraPos" Vec3 Direction..Value "the camera's position";
    "right" Vec3 Direction..Value "the camera's right axis (R's first column)";
    "down" Vec3 Direction..Value "the camera's down axis (R's second column)";
    "forward" Vec3 Direction..Value "the camera's forward axis (R's third column)";
    "lightPos" Vec3 ShadowStart..Value "the light's position";
    "lightColor" Vec3 ShadowStart..Value "P, the light's power per channel";
    "position" Vec3 ShadowStart..Value "the hit's position";
    "normal" Vec3 ShadowStart..Value "the hit's normal, pointing out of the surface";
    "distance" Number ShadowStart..Value "the hit's distance along the ray that found it";
    "color" Vec3 ShadowStart..Value "ρ, the surface's reflectance";
    "indirectLight" Vec3 ShadowStart..Value "N, the constant indirect light (0 when off)";
    "shadowStart" Vec3 Shadowed..Value "where the shadow ray starts";
    "shadowDistance" Number Shadowed..Value "the distance from shadowStart toward the light to the nearest surface (infinity when none)";
    "shadowed" Bool Direct..Value "whether the light is blocked";
    "D" Vec3 Value..Value "the direct light, shadow included";
}

/// How many input components there are: the length of the inputs a tape runs over.
pub const INPUT_COMPONENTS: usize = {
    let last = INPUTS[INPUTS.len() - 1];
    last.offset as usize + if matches!(last.ty, Ty::Vec3) { 3 } else { 1 }
};

/// The input named `name`.
pub fn input(name: &str) -> Option<&'static Input> {
    INPUTS.iter().find(|i| i.name == name)
}

/// The component offset of input `name`, which must be one of [`INPUTS`]: called with the
/// names written in this module's code, in `const` blocks where it runs per pixel.
pub(crate) const fn offset(name: &str) -> usize {
    let mut i = 0;
    while i < INPUTS.len() {
        if same(INPUTS[i].name.as_bytes(), name.as_bytes()) {
            return INPUTS[i].offset as usize;
        }
        i += 1;
    }
    panic!("not an input's name")
}

const fn same(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}
