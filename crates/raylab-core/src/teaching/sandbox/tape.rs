//! A compiled quantity: a flat list of scalar operations (a "tape"), each writing its own
//! slot, run over one pixel (`N = 1`) or sixteen side by side (`N = 16`).
//!
//! vec3 operations are taken apart into their components when compiling, in glam's order of
//! operations (`dot` is `(x·x′ + y·y′) + z·z′`, `normalize` multiplies by `1/length`): the
//! tape's values are the bits the renderer's own glam code gives. Every operation is the
//! `f32` one done lane by lane, with no fused multiply-add, so the sixteen-lane form and the
//! one-pixel form give the same bits (tested); the loops over `[f32; 16]` are what the
//! compiler vectorises. Booleans are 1.0 (true) and 0.0 (false).

/// One operation; operands are earlier slots (an operation's slot is its index).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    Const(f32),
    /// Component `k` of the inputs ([`super::Input::offset`]).
    Input(u16),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Neg(u32),
    Sqrt(u32),
    Abs(u32),
    /// `f32::max`, `f32::min` (a NaN gives the other value).
    Max(u32, u32),
    Min(u32, u32),
    Pow(u32, u32),
    Lt(u32, u32),
    Le(u32, u32),
    Eq(u32, u32),
    Ne(u32, u32),
    And(u32, u32),
    Or(u32, u32),
    Not(u32),
    /// `c ? a : b`.
    Select(u32, u32, u32),
}

/// What a value is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ty {
    Number,
    Vec3,
    Bool,
}

impl Ty {
    /// As the messages name it: "a number", "vec3", "a bool".
    pub fn describe(self) -> &'static str {
        match self {
            Ty::Number => "a number",
            Ty::Vec3 => "vec3",
            Ty::Bool => "a bool",
        }
    }

    pub fn width(self) -> usize {
        match self {
            Ty::Vec3 => 3,
            Ty::Number | Ty::Bool => 1,
        }
    }
}

/// A compiled expression: its operations and the slots of its value (one, or three for a
/// vec3).
#[derive(Clone, Debug, PartialEq)]
pub struct Tape {
    pub ops: Vec<Op>,
    pub result: Vec<u32>,
    pub ty: Ty,
}

impl Tape {
    /// Runs the tape over `N` lanes: `inputs[k]` holds input component `k`'s lanes. `slots` is
    /// scratch space, reused between calls. Returns the value's components (one or three).
    pub fn run<const N: usize>(
        &self,
        inputs: &[[f32; N]],
        slots: &mut Vec<[f32; N]>,
    ) -> [[f32; N]; 3] {
        slots.clear();
        slots.reserve(self.ops.len());
        for op in &self.ops {
            let s = |i: u32| slots[i as usize];
            let v = match *op {
                Op::Const(c) => [c; N],
                Op::Input(k) => inputs.get(usize::from(k)).copied().unwrap_or([f32::NAN; N]),
                Op::Add(a, b) => zip(s(a), s(b), |a, b| a + b),
                Op::Sub(a, b) => zip(s(a), s(b), |a, b| a - b),
                Op::Mul(a, b) => zip(s(a), s(b), |a, b| a * b),
                Op::Div(a, b) => zip(s(a), s(b), |a, b| a / b),
                Op::Neg(a) => s(a).map(|a| -a),
                Op::Sqrt(a) => s(a).map(f32::sqrt),
                Op::Abs(a) => s(a).map(f32::abs),
                Op::Max(a, b) => zip(s(a), s(b), f32::max),
                Op::Min(a, b) => zip(s(a), s(b), f32::min),
                Op::Pow(a, b) => zip(s(a), s(b), f32::powf),
                Op::Lt(a, b) => zip(s(a), s(b), |a, b| truth(a < b)),
                Op::Le(a, b) => zip(s(a), s(b), |a, b| truth(a <= b)),
                Op::Eq(a, b) => zip(s(a), s(b), |a, b| truth(a == b)),
                Op::Ne(a, b) => zip(s(a), s(b), |a, b| truth(a != b)),
                Op::And(a, b) => zip(s(a), s(b), |a, b| truth(a != 0.0 && b != 0.0)),
                Op::Or(a, b) => zip(s(a), s(b), |a, b| truth(a != 0.0 || b != 0.0)),
                Op::Not(a) => s(a).map(|a| truth(a == 0.0)),
                Op::Select(c, a, b) => {
                    let (c, a, b) = (s(c), s(a), s(b));
                    std::array::from_fn(|i| if c[i] != 0.0 { a[i] } else { b[i] })
                }
            };
            slots.push(v);
        }
        self.value_in(slots)
    }

    /// The value's components in `slots`, as [`Tape::run`] left them (one component repeated
    /// for a number or a bool).
    pub fn value_in<const N: usize>(&self, slots: &[[f32; N]]) -> [[f32; N]; 3] {
        let get = |k: usize| {
            self.result
                .get(k)
                .or(self.result.first())
                .and_then(|&i| slots.get(i as usize).copied())
                .unwrap_or([f32::NAN; N])
        };
        [get(0), get(1), get(2)]
    }

    /// [`Tape::run`] for one pixel.
    pub fn run_one(&self, inputs: &[f32], slots: &mut Vec<[f32; 1]>) -> [f32; 3] {
        let lanes: Vec<[f32; 1]> = inputs.iter().map(|&v| [v]).collect();
        self.run::<1>(&lanes, slots).map(|[v]| v)
    }
}

fn truth(b: bool) -> f32 {
    if b { 1.0 } else { 0.0 }
}

#[inline(always)]
fn zip<const N: usize>(a: [f32; N], b: [f32; N], f: impl Fn(f32, f32) -> f32) -> [f32; N] {
    std::array::from_fn(|i| f(a[i], b[i]))
}
