//! Types checked, names resolved, each quantity compiled to a [`Tape`].
//!
//! Every statement names a quantity (`D = …`, or a C++ declaration of it, `vec3 D = …;`) or a
//! value of the student's own (`let r = …`, `vec3 r = …;`), visible to the statements below
//! it. A quantity's tape holds the values it uses, each once. A value may use only what the
//! quantity using it may (`shadowDistance` is unknown when computing `d`); a quantity may use
//! those computed before it (`R` uses `D`), never itself.

use std::collections::HashMap;
use std::f32::consts::PI;

use super::error::{SandboxError, Span, suggest};
use super::parse::{BinOp, Declared, Expr, ExprKind, Stmt, UnOp};
use super::tape::{Op, Tape, Ty};
use super::{INPUTS, MAX_SOURCE_BYTES, Quantity, input};

/// The most operations a quantity's tape may have.
pub const MAX_OPS: usize = 50_000;

/// The longest text a [`Part`] keeps, in bytes: a longer one ends in `…`.
pub const MAX_PART_TEXT: usize = 120;

/// The functions, as the messages list them.
const FUNCTIONS: [&str; 14] = [
    "dot",
    "cross",
    "length",
    "normalize",
    "max",
    "min",
    "abs",
    "sqrt",
    "pow",
    "clamp",
    "mix",
    "vec3",
    "float",
    "distance",
];

/// The named constants: `pi` and C's `M_PI`.
pub const CONSTANTS: [&str; 2] = ["pi", "M_PI"];

/// The student's quantities, compiled: a tape for each one written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Equations {
    tapes: [Option<Tape>; 5],
    spans: [Option<Span>; 5],
    parts: [Vec<Part>; 5],
}

/// A part of the student's text whose value the inspector shows: a value of their own (`let r
/// = …`, `vec3 r = …;`), the quantity itself, or an operation, call or `.x` inside either.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Where it is in the text (a statement's: from its name to the end of its value).
    pub span: Span,
    /// 1-based line and column (in characters) of the span's start.
    pub line: usize,
    pub column: usize,
    /// The name a statement defines (`r`, `D`); `None` for an expression inside one.
    pub name: Option<String>,
    /// Its text, each run of white space one space (a statement's: its value's text).
    pub text: String,
    pub ty: Ty,
    /// Its value's slots in the quantity's tape: one, or three for a vec3.
    pub slots: [u32; 3],
    /// The index of the statement it is in, among the text's statements.
    pub statement: usize,
}

impl Part {
    /// Its value, read from the slots of its quantity's tape run over one pixel.
    pub fn value(&self, slots: &[[f32; 1]]) -> [f32; 3] {
        self.slots
            .map(|s| slots.get(s as usize).map_or(f32::NAN, |v| v[0]))
    }
}

impl Equations {
    /// No quantity written: the lab's own everywhere.
    pub fn lab() -> Self {
        Self::default()
    }

    /// The tape of `q`, if the student wrote it.
    pub fn tape(&self, q: Quantity) -> Option<&Tape> {
        self.tapes[q as usize].as_ref()
    }

    /// Where `q`'s name is written in the text.
    pub fn span(&self, q: Quantity) -> Option<Span> {
        self.spans[q as usize]
    }

    /// The parts of the text `q`'s tape computes, statement by statement in the order of the
    /// text (the values of its own that it uses, then itself), each statement's parts in the
    /// order they are computed; empty where `q` is not written.
    pub fn parts(&self, q: Quantity) -> &[Part] {
        &self.parts[q as usize]
    }

    /// The quantities written.
    pub fn written(&self) -> impl Iterator<Item = Quantity> + '_ {
        Quantity::ALL
            .into_iter()
            .filter(|q| self.tape(*q).is_some())
    }

    /// Forgets the quantities for which `keep` is false (the lab's then).
    pub fn keep_only(&mut self, keep: impl Fn(Quantity) -> bool) {
        for q in Quantity::ALL.into_iter().filter(|q| !keep(*q)) {
            self.tapes[q as usize] = None;
            self.spans[q as usize] = None;
            self.parts[q as usize].clear();
        }
    }

    /// Takes quantity `q` from `other` (its tape and where it is written there, or the lab's
    /// if `other` does not write it): equations put together from texts compiled apart.
    pub fn take(&mut self, q: Quantity, other: &Equations) {
        self.tapes[q as usize] = other.tapes[q as usize].clone();
        self.spans[q as usize] = other.spans[q as usize];
        self.parts[q as usize] = other.parts[q as usize].clone();
    }

    /// Whether going from `self` to `other` means tracing again (`d` or `shadowStart`
    /// changed), not only evaluating again.
    pub fn retraces_from(&self, other: &Equations) -> bool {
        Quantity::ALL
            .into_iter()
            .filter(|q| q.retraces())
            .any(|q| self.tape(q) != other.tape(q))
    }
}

/// Compiles `source`, a file of `NAME = EXPRESSION` and `let` lines: every quantity it writes,
/// or every error found (one a statement at most).
pub fn compile(source: &str) -> Result<Equations, Vec<SandboxError>> {
    if source.len() > MAX_SOURCE_BYTES {
        let mut start = MAX_SOURCE_BYTES;
        while !source.is_char_boundary(start) {
            start -= 1;
        }
        return Err(vec![SandboxError::at(
            source,
            Span::new(start, source.len()),
            format!(
                "the text is {} bytes long, over the {MAX_SOURCE_BYTES} allowed: the lab's \
                 quantities take a few lines",
                source.len()
            ),
        )]);
    }
    let tokens = super::lex::lex(source).map_err(|e| vec![e])?;
    let stmts = super::parse::parse(source, &tokens)?;
    Compiler::new(source, &stmts).run()
}

/// A value being compiled: its type and its slots (one, or three for a vec3).
#[derive(Clone, Copy, Debug)]
struct Val {
    ty: Ty,
    s: [u32; 3],
}

/// A tape being built.
#[derive(Default)]
struct Builder {
    ops: Vec<Op>,
    consts: HashMap<u32, u32>,
    inputs: HashMap<u16, u32>,
    /// The lets compiled so far, by their statement's index.
    lets: HashMap<usize, Val>,
    /// The parts computed, in the order they were.
    parts: Vec<Part>,
}

impl Builder {
    fn op(&mut self, op: Op) -> u32 {
        self.ops.push(op);
        (self.ops.len() - 1) as u32
    }

    fn constant(&mut self, v: f32) -> u32 {
        if let Some(&s) = self.consts.get(&v.to_bits()) {
            return s;
        }
        let s = self.op(Op::Const(v));
        self.consts.insert(v.to_bits(), s);
        s
    }

    fn input(&mut self, k: u16) -> u32 {
        if let Some(&s) = self.inputs.get(&k) {
            return s;
        }
        let s = self.op(Op::Input(k));
        self.inputs.insert(k, s);
        s
    }

    fn number(s: u32) -> Val {
        Val {
            ty: Ty::Number,
            s: [s; 3],
        }
    }

    fn boolean(s: u32) -> Val {
        Val {
            ty: Ty::Bool,
            s: [s; 3],
        }
    }

    fn vec(s: [u32; 3]) -> Val {
        Val { ty: Ty::Vec3, s }
    }

    /// `f` component by component; a number on either side counts as that number thrice (as
    /// GLM's `vec3 + float`).
    fn zip(&mut self, a: Val, b: Val, f: fn(u32, u32) -> Op) -> Val {
        if a.ty == Ty::Number && b.ty == Ty::Number {
            return Builder::number(self.op(f(a.s[0], b.s[0])));
        }
        Builder::vec([0, 1, 2].map(|i| self.op(f(a.s[i], b.s[i]))))
    }

    fn map(&mut self, a: Val, f: fn(u32) -> Op) -> Val {
        if a.ty == Ty::Vec3 {
            return Builder::vec([0, 1, 2].map(|i| self.op(f(a.s[i]))));
        }
        Val {
            ty: a.ty,
            s: [self.op(f(a.s[0])); 3],
        }
    }

    /// glam's `dot`: `(x·x′ + y·y′) + z·z′`.
    fn dot(&mut self, a: Val, b: Val) -> u32 {
        let m = [0, 1, 2].map(|i| self.op(Op::Mul(a.s[i], b.s[i])));
        let xy = self.op(Op::Add(m[0], m[1]));
        self.op(Op::Add(xy, m[2]))
    }

    /// glam's `length`: `sqrt(dot(a, a))`.
    fn length(&mut self, a: Val) -> u32 {
        let d = self.dot(a, a);
        self.op(Op::Sqrt(d))
    }
}

/// Where a name is defined: a statement of the text.
struct Defined<'a> {
    index: usize,
    stmt: &'a Stmt,
}

struct Compiler<'a> {
    source: &'a str,
    /// Where each line of the source starts, in bytes.
    line_starts: Vec<usize>,
    stmts: &'a [Stmt],
    /// The student's own values, by name.
    lets: HashMap<&'a str, Defined<'a>>,
    errors: Vec<SandboxError>,
}

/// The context an expression is compiled in.
#[derive(Clone, Copy)]
struct Ctx {
    /// The quantity being computed; `None` for checking a value on its own (every input known).
    quantity: Option<Quantity>,
    /// The statement being compiled: the lets before it are visible.
    at: usize,
}

type Compiled<T> = Result<T, SandboxError>;

impl<'a> Compiler<'a> {
    fn new(source: &'a str, stmts: &'a [Stmt]) -> Self {
        let line_starts = std::iter::once(0)
            .chain(source.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        Self {
            source,
            line_starts,
            stmts,
            lets: HashMap::new(),
            errors: Vec::new(),
        }
    }

    fn error(&self, span: Span, message: impl Into<String>) -> SandboxError {
        SandboxError::at(self.source, span, message)
    }

    fn line_of(&self, span: Span) -> usize {
        SandboxError::at(self.source, span, "").line
    }

    fn run(mut self) -> Result<Equations, Vec<SandboxError>> {
        let mut equations = Equations::default();
        let mut quantities = Vec::new();
        for (index, stmt) in self.stmts.iter().enumerate() {
            if let Err(e) = self.declare(index, stmt, &mut equations, &mut quantities) {
                self.errors.push(e);
            }
        }
        // Each value checked once on its own, so that its errors show even when unused.
        for (index, stmt) in self.stmts.iter().enumerate() {
            if quantities.iter().any(|(i, _)| *i == index) || !self.is_let(index) {
                continue;
            }
            let ctx = Ctx {
                quantity: None,
                at: index,
            };
            let result = self
                .expr(&stmt.expr, ctx, &mut Builder::default())
                .and_then(|v| self.check_declared(stmt, v.ty));
            if let Err(e) = result {
                self.push_error(e);
            }
        }
        for &(index, q) in &quantities {
            match self.quantity(index, q) {
                Ok((tape, parts)) => {
                    equations.tapes[q as usize] = Some(tape);
                    equations.parts[q as usize] = parts;
                }
                Err(e) => self.push_error(e),
            }
        }
        if self.errors.is_empty() {
            Ok(equations)
        } else {
            self.errors.sort_by_key(|e| (e.span.start, e.span.end));
            Err(self.errors)
        }
    }

    fn is_let(&self, index: usize) -> bool {
        let name = self.stmts[index].name.as_str();
        self.lets.get(name).is_some_and(|d| d.index == index)
    }

    /// An error once, however many quantities a value's error shows in.
    fn push_error(&mut self, e: SandboxError) {
        if !self.errors.contains(&e) {
            self.errors.push(e);
        }
    }

    /// Records what statement `index` defines.
    fn declare(
        &mut self,
        index: usize,
        stmt: &'a Stmt,
        equations: &mut Equations,
        quantities: &mut Vec<(usize, Quantity)>,
    ) -> Compiled<()> {
        let name = stmt.name.as_str();
        if let Some(q) = Quantity::by_name(name) {
            if let Some(before) = equations.spans[q as usize] {
                return Err(self.error(
                    stmt.name_span,
                    format!(
                        "`{name}` is already written on line {}: write each quantity once",
                        self.line_of(before)
                    ),
                ));
            }
            equations.spans[q as usize] = Some(stmt.name_span);
            quantities.push((index, q));
            return Ok(());
        }
        if let Some(i) = input(name) {
            return Err(self.error(
                stmt.name_span,
                format!(
                    "`{name}` is the lab's input ({}), not yours to set: name your value \
                     something else",
                    i.what
                ),
            ));
        }
        if CONSTANTS.contains(&name) || FUNCTIONS.contains(&canonical(name)) {
            return Err(self.error(
                stmt.name_span,
                format!("`{name}` is already the language's: name your value something else"),
            ));
        }
        if stmt.declared.is_none() {
            let quantities = Quantity::ALL.map(Quantity::name);
            let hint = match suggest(name, quantities) {
                Some(q) => format!("did you mean `{q}`? For a value of your own"),
                None => format!(
                    "the quantities are {}; for a value of your own",
                    quantities.join(", ")
                ),
            };
            return Err(self.error(
                stmt.name_span,
                format!("`{name}` is not a quantity: {hint}, write `let {name} = …`"),
            ));
        }
        if let Some(before) = self.lets.get(name) {
            return Err(self.error(
                stmt.name_span,
                format!(
                    "`{name}` is already defined on line {}: give this value another name",
                    self.line_of(before.stmt.name_span)
                ),
            ));
        }
        self.lets.insert(name, Defined { index, stmt });
        Ok(())
    }

    /// Quantity `q`'s tape, from statement `index`, and the parts it computes.
    fn quantity(&self, index: usize, q: Quantity) -> Compiled<(Tape, Vec<Part>)> {
        let stmt = &self.stmts[index];
        let mut b = Builder::default();
        let ctx = Ctx {
            quantity: Some(q),
            at: index,
        };
        let v = self.expr(&stmt.expr, ctx, &mut b)?;
        self.statement_part(stmt, index, v, &mut b);
        self.check_declared(stmt, v.ty)?;
        if v.ty != q.ty() {
            let hint = match (q.ty(), v.ty) {
                (Ty::Vec3, Ty::Number) => ": write `vec3(…)` of it, or multiply it by a vec3",
                (Ty::Bool, Ty::Number) => ": compare it, e.g. `shadowDistance < …`",
                _ => "",
            };
            return Err(self.error(
                stmt.expr.span,
                format!(
                    "`{}` ({}) must be {}, got {}{hint}",
                    q.name(),
                    q.what(),
                    q.ty().describe(),
                    v.ty.describe()
                ),
            ));
        }
        if b.ops.len() > MAX_OPS {
            return Err(self.error(
                stmt.name_span,
                format!(
                    "`{}` takes {} operations, over the {MAX_OPS} allowed: simplify it",
                    q.name(),
                    b.ops.len()
                ),
            ));
        }
        let mut parts = b.parts;
        // Statement by statement (a stable sort: each one's parts stay in computing order).
        parts.sort_by_key(|p| p.statement);
        let tape = Tape {
            ops: b.ops,
            result: v.s[..v.ty.width()].to_vec(),
            ty: v.ty,
        };
        Ok((tape, parts))
    }

    /// A part for the expression at `span` in statement `statement`, with value `v`; its text
    /// is that of `text`.
    fn part(&self, span: Span, shown: Span, name: Option<&str>, statement: usize, v: Val) -> Part {
        let source = self.source;
        let start = span.start.min(source.len());
        let line = self.line_starts.partition_point(|&s| s <= start);
        let line_start = self.line_starts[line - 1];
        let column = source
            .get(line_start..start)
            .map_or(1, |s| s.chars().count() + 1);
        let mut text = String::new();
        for word in source
            .get(shown.start..shown.end)
            .unwrap_or("")
            .split_whitespace()
        {
            if !text.is_empty() {
                text.push(' ');
            }
            if text.len() + word.len() > MAX_PART_TEXT {
                text.push('…');
                break;
            }
            text.push_str(word);
        }
        Part {
            span,
            line,
            column,
            name: name.map(str::to_owned),
            text,
            ty: v.ty,
            slots: v.s,
            statement,
        }
    }

    /// The part of statement `index` as a whole, in place of its value's outermost expression
    /// (the same value, shown once).
    fn statement_part(&self, stmt: &Stmt, index: usize, v: Val, b: &mut Builder) {
        if b.parts.last().is_some_and(|p| p.span == stmt.expr.span) {
            b.parts.pop();
        }
        let span = stmt.name_span.to(stmt.expr.span);
        let part = self.part(span, stmt.expr.span, Some(&stmt.name), index, v);
        b.parts.push(part);
    }

    /// A C++ declaration's type against its value's.
    fn check_declared(&self, stmt: &Stmt, ty: Ty) -> Compiled<()> {
        let Some(Some(declared)) = stmt.declared else {
            return Ok(());
        };
        let (want, word) = match declared {
            Declared::Number => (Ty::Number, "float"),
            Declared::Vec3 => (Ty::Vec3, "vec3"),
            Declared::Bool => (Ty::Bool, "bool"),
        };
        if want == ty {
            return Ok(());
        }
        let fix = match ty {
            Ty::Number => "float",
            Ty::Vec3 => "vec3",
            Ty::Bool => "bool",
        };
        Err(self.error(
            stmt.expr.span,
            format!(
                "`{}` is declared {word} but its value is {}: declare it `{fix}`",
                stmt.name,
                ty.describe()
            ),
        ))
    }

    /// `e`'s value; an operation, call or `.x` is recorded as a part.
    fn expr(&self, e: &Expr, ctx: Ctx, b: &mut Builder) -> Compiled<Val> {
        let v = self.expr_value(e, ctx, b)?;
        if !matches!(
            e.kind,
            ExprKind::Num(_) | ExprKind::Bool(_) | ExprKind::Name(_)
        ) {
            b.parts.push(self.part(e.span, e.span, None, ctx.at, v));
        }
        Ok(v)
    }

    fn expr_value(&self, e: &Expr, ctx: Ctx, b: &mut Builder) -> Compiled<Val> {
        match &e.kind {
            ExprKind::Num(v) => Ok(Builder::number(b.constant(*v))),
            ExprKind::Bool(t) => Ok(Builder::boolean(b.constant(if *t { 1.0 } else { 0.0 }))),
            ExprKind::Name(n) => self.name(n, e.span, ctx, b),
            ExprKind::Unary(op, inner) => {
                let v = self.expr(inner, ctx, b)?;
                match (op, v.ty) {
                    (UnOp::Neg, Ty::Number | Ty::Vec3) => Ok(b.map(v, Op::Neg)),
                    (UnOp::Not, Ty::Bool) => Ok(b.map(v, Op::Not)),
                    (UnOp::Neg, _) => Err(self.error(
                        e.span,
                        format!("`-` takes a number or vec3, got {}", v.ty.describe()),
                    )),
                    (UnOp::Not, _) => Err(self.error(
                        e.span,
                        format!(
                            "`!` takes a bool, got {}: compare it first, e.g. `x > 0`",
                            v.ty.describe()
                        ),
                    )),
                }
            }
            ExprKind::Binary(op, l, r) => {
                let a = self.expr(l, ctx, b)?;
                let c = self.expr(r, ctx, b)?;
                self.binary(*op, a, c, e.span, b)
            }
            ExprKind::Choose(c, x, y) => {
                let cond = self.expr(c, ctx, b)?;
                if cond.ty != Ty::Bool {
                    return Err(self.error(
                        c.span,
                        format!(
                            "the condition of `c ? a : b` must be a bool, got {}: compare it, \
                             e.g. `x > 0`",
                            cond.ty.describe()
                        ),
                    ));
                }
                let (x, y) = (self.expr(x, ctx, b)?, self.expr(y, ctx, b)?);
                if x.ty != y.ty {
                    let hint = if x.ty == Ty::Vec3 || y.ty == Ty::Vec3 {
                        ": write `vec3(0)` for a vec3 of zeros"
                    } else {
                        ""
                    };
                    return Err(self.error(
                        e.span,
                        format!(
                            "the two choices of `c ? a : b` must be of one type, got {} and {}{hint}",
                            x.ty.describe(),
                            y.ty.describe()
                        ),
                    ));
                }
                let s = [0, 1, 2].map(|i| b.op(Op::Select(cond.s[0], x.s[i], y.s[i])));
                Ok(Val { ty: x.ty, s })
            }
            ExprKind::Component(v, k) => {
                let v = self.expr(v, ctx, b)?;
                if v.ty != Ty::Vec3 {
                    return Err(self.error(
                        e.span,
                        format!(
                            "`.{}` is a part of a vec3, got {}",
                            ["x", "y", "z"][*k],
                            v.ty.describe()
                        ),
                    ));
                }
                Ok(Builder::number(v.s[*k]))
            }
            ExprKind::Call {
                name,
                name_span,
                args,
            } => {
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.expr(a, ctx, b)?);
                }
                self.call(name, *name_span, e.span, &vals, b)
            }
        }
    }

    fn name(&self, n: &str, span: Span, ctx: Ctx, b: &mut Builder) -> Compiled<Val> {
        if CONSTANTS.contains(&n) {
            return Ok(Builder::number(b.constant(PI)));
        }
        if let Some(d) = self.lets.get(n) {
            if d.index >= ctx.at {
                return Err(self.error(
                    span,
                    format!(
                        "`{n}` is defined below, on line {}: move it above this line",
                        self.line_of(d.stmt.name_span)
                    ),
                ));
            }
            if let Some(v) = b.lets.get(&d.index) {
                return Ok(*v);
            }
            let v = self.expr(&d.stmt.expr, Ctx { at: d.index, ..ctx }, b)?;
            self.statement_part(d.stmt, d.index, v, b);
            b.lets.insert(d.index, v);
            return Ok(v);
        }
        if let Some(i) = input(n) {
            if let Some(q) = ctx.quantity
                && !i.available_in(q)
            {
                return Err(self.unavailable(n, span, q));
            }
            let s = [0, 1, 2].map(|k| b.input(i.offset + if i.ty == Ty::Vec3 { k } else { 0 }));
            return Ok(Val { ty: i.ty, s });
        }
        if let Some(q) = Quantity::by_name(n) {
            // `d` and `R` are no input: nothing is computed from them.
            let what = match q {
                Quantity::Direction => {
                    "only traces the camera ray: the other quantities work at the hit it finds"
                }
                _ => "is the last quantity computed: nothing uses it",
            };
            return Err(self.error(span, format!("`{n}` ({}) {what}", q.what())));
        }
        if FUNCTIONS.contains(&canonical(n)) {
            return Err(self.error(span, format!("`{n}` is a function: call it, as `{n}(…)`")));
        }
        let visible = self.visible_names(ctx);
        let message = match suggest(n, visible.iter().map(String::as_str)) {
            Some(s) => format!("unknown name `{n}`: did you mean `{s}`?"),
            None => format!(
                "unknown name `{n}`: the names here are {}",
                visible.join(", ")
            ),
        };
        Err(self.error(span, message))
    }

    /// The names an expression in `ctx` may use.
    fn visible_names(&self, ctx: Ctx) -> Vec<String> {
        let mut names: Vec<String> = INPUTS
            .iter()
            .filter(|i| ctx.quantity.is_none_or(|q| i.available_in(q)))
            .map(|i| i.name.to_owned())
            .collect();
        let mut lets: Vec<&Defined> = self.lets.values().filter(|d| d.index < ctx.at).collect();
        lets.sort_by_key(|d| d.index);
        names.extend(lets.iter().map(|d| d.stmt.name.clone()));
        names.push("pi".to_owned());
        names
    }

    /// The error for input `n` used where quantity `q` cannot know it.
    fn unavailable(&self, n: &str, span: Span, q: Quantity) -> SandboxError {
        let own = Quantity::by_name(n);
        let message = match own {
            Some(o) if o == q => {
                format!("`{n}` cannot use itself (no recursion): write it from the lab's inputs")
            }
            Some(o) if o > q => format!(
                "`{n}` is computed after `{}`: `{}` cannot use it",
                q.name(),
                q.name()
            ),
            _ => {
                let names: Vec<&str> = INPUTS
                    .iter()
                    .filter(|i| i.available_in(q))
                    .map(|i| i.name)
                    .collect();
                format!(
                    "`{n}` is not known when computing `{}` ({}): it may use {}",
                    q.name(),
                    q.what(),
                    names.join(", ")
                )
            }
        };
        self.error(span, message)
    }

    fn binary(&self, op: BinOp, a: Val, c: Val, span: Span, b: &mut Builder) -> Compiled<Val> {
        use Ty::*;
        let sym = op.symbol();
        let got = format!("got {} and {}", a.ty.describe(), c.ty.describe());
        match op {
            BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div => {
                if a.ty == Bool || c.ty == Bool {
                    return Err(self.error(
                        span,
                        format!("`{sym}` takes numbers or vec3 on both sides, {got}"),
                    ));
                }
                let f: fn(u32, u32) -> Op = match op {
                    BinOp::Add => Op::Add,
                    BinOp::Sub => Op::Sub,
                    BinOp::Mul => Op::Mul,
                    _ => Op::Div,
                };
                Ok(b.zip(a, c, f))
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                if a.ty != Number || c.ty != Number {
                    return Err(self.error(
                        span,
                        format!(
                            "`{sym}` compares two numbers, {got}: compare a part (`.x`) or a \
                             `length`"
                        ),
                    ));
                }
                let (x, y) = (a.s[0], c.s[0]);
                let s = match op {
                    BinOp::Lt => b.op(Op::Lt(x, y)),
                    BinOp::Le => b.op(Op::Le(x, y)),
                    BinOp::Gt => b.op(Op::Lt(y, x)),
                    _ => b.op(Op::Le(y, x)),
                };
                Ok(Builder::boolean(s))
            }
            BinOp::Eq | BinOp::Ne => {
                if a.ty != c.ty {
                    return Err(self.error(
                        span,
                        format!("`{sym}` compares two values of one type, {got}"),
                    ));
                }
                let eq = op == BinOp::Eq;
                let f: fn(u32, u32) -> Op = if eq { Op::Eq } else { Op::Ne };
                if a.ty != Vec3 {
                    return Ok(Builder::boolean(b.op(f(a.s[0], c.s[0]))));
                }
                // GLM: vectors are equal when every component is.
                let parts = [0, 1, 2].map(|i| b.op(f(a.s[i], c.s[i])));
                let join: fn(u32, u32) -> Op = if eq { Op::And } else { Op::Or };
                let xy = b.op(join(parts[0], parts[1]));
                Ok(Builder::boolean(b.op(join(xy, parts[2]))))
            }
            BinOp::And | BinOp::Or => {
                if a.ty != Bool || c.ty != Bool {
                    return Err(self.error(
                        span,
                        format!(
                            "`{sym}` takes two bools, {got}: compare numbers first, e.g. `x > 0`"
                        ),
                    ));
                }
                let f: fn(u32, u32) -> Op = if op == BinOp::And { Op::And } else { Op::Or };
                Ok(Builder::boolean(b.op(f(a.s[0], c.s[0]))))
            }
        }
    }

    fn call(
        &self,
        name: &str,
        name_span: Span,
        span: Span,
        args: &[Val],
        b: &mut Builder,
    ) -> Compiled<Val> {
        use Ty::*;
        let tys: Vec<Ty> = args.iter().map(|a| a.ty).collect();
        let f = canonical(name);
        let wrong = |takes: &str| {
            let got = match tys.len() {
                0 => "nothing".to_owned(),
                _ => tys
                    .iter()
                    .map(|t| t.describe())
                    .collect::<Vec<_>>()
                    .join(" and "),
            };
            self.error(span, format!("`{name}` takes {takes}, got {got}"))
        };
        match f {
            "dot" | "cross" | "distance" => {
                if tys != [Vec3, Vec3] {
                    return Err(wrong("two vec3"));
                }
                let (x, y) = (args[0], args[1]);
                Ok(match f {
                    "dot" => Builder::number(b.dot(x, y)),
                    "distance" => {
                        let d = b.zip(x, y, Op::Sub);
                        Builder::number(b.length(d))
                    }
                    _ => {
                        let m = |b: &mut Builder, i: usize, j: usize| {
                            let p = b.op(Op::Mul(x.s[i], y.s[j]));
                            let q = b.op(Op::Mul(y.s[i], x.s[j]));
                            b.op(Op::Sub(p, q))
                        };
                        Builder::vec([m(b, 1, 2), m(b, 2, 0), m(b, 0, 1)])
                    }
                })
            }
            "length" | "normalize" => {
                if tys != [Vec3] {
                    return Err(wrong("one vec3"));
                }
                let len = b.length(args[0]);
                if f == "length" {
                    return Ok(Builder::number(len));
                }
                // glam: v · (1/|v|).
                let one = b.constant(1.0);
                let inv = b.op(Op::Div(one, len));
                Ok(b.zip(args[0], Builder::number(inv), Op::Mul))
            }
            "max" | "min" => match tys.as_slice() {
                [Number, Number] | [Vec3, Vec3] | [Vec3, Number] => {
                    Ok(b.zip(args[0], args[1], if f == "max" { Op::Max } else { Op::Min }))
                }
                _ => Err(wrong("two numbers, two vec3, or a vec3 and a number")),
            },
            "abs" | "sqrt" => match tys.as_slice() {
                [Number | Vec3] => Ok(b.map(args[0], if f == "abs" { Op::Abs } else { Op::Sqrt })),
                _ => Err(wrong("one number or vec3")),
            },
            "pow" => match tys.as_slice() {
                [Number, Number] | [Vec3, Vec3] => Ok(b.zip(args[0], args[1], Op::Pow)),
                _ => Err(wrong("two numbers or two vec3")),
            },
            "clamp" => match tys.as_slice() {
                // GLM: min(max(x, lo), hi).
                [Number, Number, Number] | [Vec3, Number, Number] | [Vec3, Vec3, Vec3] => {
                    let lo = b.zip(args[0], args[1], Op::Max);
                    Ok(b.zip(lo, args[2], Op::Min))
                }
                _ => Err(wrong("a number or vec3 and two bounds (`clamp(x, 0, 1)`)")),
            },
            "mix" => match tys.as_slice() {
                // GLM: x·(1 − a) + y·a.
                [Number, Number, Number] | [Vec3, Vec3, Number] | [Vec3, Vec3, Vec3] => {
                    let one = Builder::number(b.constant(1.0));
                    let rest = b.zip(one, args[2], Op::Sub);
                    let p = b.zip(args[0], rest, Op::Mul);
                    let q = b.zip(args[1], args[2], Op::Mul);
                    Ok(b.zip(p, q, Op::Add))
                }
                _ => Err(wrong(
                    "two numbers or two vec3 and a weight (`mix(a, b, t)`)",
                )),
            },
            "vec3" => match tys.as_slice() {
                [Number] => Ok(Builder::vec([args[0].s[0]; 3])),
                [Vec3] => Ok(args[0]),
                [Number, Number, Number] => Ok(Builder::vec(args.map_s())),
                _ => Err(wrong("one number or three numbers")),
            },
            "float" => match tys.as_slice() {
                [Number] => Ok(args[0]),
                _ => Err(wrong("one number")),
            },
            _ => {
                let message = match suggest(name, FUNCTIONS) {
                    Some(s) => format!("unknown function `{name}`: did you mean `{s}`?"),
                    None => format!(
                        "unknown function `{name}`: the functions are {}",
                        FUNCTIONS.join(", ")
                    ),
                };
                Err(self.error(name_span, message))
            }
        }
    }
}

/// The first slot of each of three number arguments.
trait FirstSlots {
    fn map_s(&self) -> [u32; 3];
}

impl FirstSlots for [Val] {
    fn map_s(&self) -> [u32; 3] {
        [self[0].s[0], self[1].s[0], self[2].s[0]]
    }
}

/// C's and C++'s other names for the functions: `fabs`, `sqrtf`, `powf`, `fmax`, `double`.
fn canonical(name: &str) -> &str {
    match name {
        "fabs" | "fabsf" => "abs",
        "sqrtf" => "sqrt",
        "powf" => "pow",
        "fmax" | "fmaxf" => "max",
        "fmin" | "fminf" => "min",
        "double" => "float",
        other => other,
    }
}
