//! The sandbox language's grammar: statements (`NAME = …`, `let NAME = …`, C++ declarations
//! such as `vec3 r = …;`) of expressions with C's precedence, each node with its span.
//!
//! ```text
//! statement  = ("let" NAME | ["const"] TYPE NAME | NAME) "=" expression [";"]
//! expression = or ["?" expression ":" expression]
//! or         = and {"||" and}            and = equality {"&&" equality}
//! equality   = compare {("==" | "!=") compare}
//! compare    = sum {("<" | "<=" | ">" | ">=") sum}
//! sum        = product {("+" | "-") product}
//! product    = unary {("*" | "/") unary}
//! unary      = ("-" | "+" | "!") unary | postfix
//! postfix    = primary {"." NAME}
//! primary    = NUMBER | NAME | NAME "(" [expression {"," expression}] ")" | "(" expression ")"
//! ```
//!
//! A statement ends at `;` or at the end of its line; inside parentheses, or after an
//! operator, a line end is only a space.

use super::error::{SandboxError, Span};
use super::lex::{Tok, Token};

/// How deeply expressions may nest: deeper is refused, never a stack overflow.
pub const MAX_DEPTH: usize = 64;

/// The most nodes one statement's expression may have.
pub const MAX_NODES: usize = 2_000;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnOp {
    Neg,
    Not,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
}

impl BinOp {
    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::And => "&&",
            BinOp::Or => "||",
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    Num(f32),
    Bool(bool),
    Name(String),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// `c ? a : b`.
    Choose(Box<Expr>, Box<Expr>, Box<Expr>),
    Call {
        name: String,
        name_span: Span,
        args: Vec<Expr>,
    },
    /// `v.x` (0), `.y` (1), `.z` (2).
    Component(Box<Expr>, usize),
}

/// The type a C++ declaration names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Declared {
    Number,
    Vec3,
    Bool,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// `let`, or a C++ declaration: a local value, or (for a quantity's name) the quantity.
    pub declared: Option<Option<Declared>>,
    pub name: String,
    pub name_span: Span,
    pub expr: Expr,
}

/// The statements of `tokens`, or every statement's first error (parsing goes on after an
/// error at the next statement).
pub fn parse(source: &str, tokens: &[Token]) -> Result<Vec<Stmt>, Vec<SandboxError>> {
    let mut p = Parser {
        source,
        tokens,
        pos: 0,
        parens: 0,
        depth: 0,
        nodes: 0,
    };
    let mut stmts = Vec::new();
    let mut errors = Vec::new();
    loop {
        while matches!(p.tokens[p.pos].tok, Tok::Newline | Tok::Punct(";")) {
            p.pos += 1;
        }
        if p.tokens[p.pos].tok == Tok::End {
            break;
        }
        match p.statement() {
            Ok(s) => stmts.push(s),
            Err(e) => {
                errors.push(e);
                p.recover();
            }
        }
    }
    if errors.is_empty() {
        Ok(stmts)
    } else {
        Err(errors)
    }
}

struct Parser<'a> {
    source: &'a str,
    tokens: &'a [Token],
    pos: usize,
    /// Open parentheses: inside them line ends are spaces.
    parens: usize,
    depth: usize,
    nodes: usize,
}

type Parsed<T> = Result<T, SandboxError>;

/// C++ type names a declaration may start with.
fn declared_type(name: &str) -> Option<Option<Declared>> {
    match name {
        "vec3" => Some(Some(Declared::Vec3)),
        "float" | "double" => Some(Some(Declared::Number)),
        "bool" => Some(Some(Declared::Bool)),
        "auto" | "let" => Some(None),
        _ => None,
    }
}

impl Parser<'_> {
    fn error(&self, span: Span, message: impl Into<String>) -> SandboxError {
        SandboxError::at(self.source, span, message)
    }

    fn skip_newlines(&mut self) {
        while self.tokens[self.pos].tok == Tok::Newline {
            self.pos += 1;
        }
    }

    /// The next token, line ends skipped inside parentheses.
    fn peek(&mut self) -> &Token {
        if self.parens > 0 {
            self.skip_newlines();
        }
        &self.tokens[self.pos]
    }

    fn bump(&mut self) -> Token {
        let t = self.peek().clone();
        if t.tok != Tok::End {
            self.pos += 1;
        }
        t
    }

    fn is(&mut self, p: &str) -> bool {
        matches!(self.peek().tok, Tok::Punct(q) if q == p)
    }

    fn expect(&mut self, p: &str, what: &str) -> Parsed<Token> {
        if self.is(p) {
            return Ok(self.bump());
        }
        let t = self.peek().clone();
        Err(self.error(
            t.span,
            format!("expected `{p}` {what}, found {}", describe(&t.tok)),
        ))
    }

    /// Skips to the end of the statement an error was found in.
    fn recover(&mut self) {
        self.parens = 0;
        self.depth = 0;
        while !matches!(
            self.tokens[self.pos].tok,
            Tok::Newline | Tok::Punct(";") | Tok::End
        ) {
            self.pos += 1;
        }
    }

    fn statement(&mut self) -> Parsed<Stmt> {
        self.nodes = 0;
        let first = self.bump();
        let Tok::Name(word) = &first.tok else {
            return Err(self.error(
                first.span,
                format!(
                    "expected a quantity (`R = …`) or `let name = …`, found {}",
                    describe(&first.tok)
                ),
            ));
        };
        let mut word = word.clone();
        let mut word_span = first.span;
        if word == "const" {
            let t = self.bump();
            match t.tok {
                Tok::Name(w) => (word, word_span) = (w, t.span),
                other => {
                    return Err(self.error(
                        t.span,
                        format!("expected a type after `const`, found {}", describe(&other)),
                    ));
                }
            }
        }
        let (declared, name, name_span) = match declared_type(&word) {
            Some(declared) => {
                let t = self.bump();
                match t.tok {
                    Tok::Name(n) => (Some(declared), n, t.span),
                    other => {
                        return Err(self.error(
                            t.span,
                            format!("expected a name after `{word}`, found {}", describe(&other)),
                        ));
                    }
                }
            }
            None if matches!(
                word.as_str(),
                "int" | "unsigned" | "long" | "short" | "vec2" | "vec4"
            ) =>
            {
                return Err(self.error(
                    word_span,
                    format!(
                        "`{word}` is not a type here: use `float` for numbers, `vec3`, or `let`"
                    ),
                ));
            }
            None => (None, word, word_span),
        };
        if self.is("(") {
            return Err(self.error(
                name_span,
                format!("no functions can be defined here: write `{name} = …` with an expression"),
            ));
        }
        self.expect("=", &format!("after `{name}`"))?;
        let expr = self.expression()?;
        let end = self.tokens[self.pos].clone();
        match end.tok {
            Tok::Newline | Tok::Punct(";") | Tok::End => {}
            ref other => {
                return Err(self.error(
                    end.span,
                    format!(
                        "expected an operator or the end of the line, found {}",
                        describe(other)
                    ),
                ));
            }
        }
        let _ = word_span;
        Ok(Stmt {
            declared,
            name,
            name_span,
            expr,
        })
    }

    fn node(&mut self, kind: ExprKind, span: Span) -> Parsed<Expr> {
        self.nodes += 1;
        if self.nodes > MAX_NODES {
            return Err(self.error(
                span,
                format!(
                    "this expression is too long (over {MAX_NODES} parts): split it with `let`"
                ),
            ));
        }
        Ok(Expr { kind, span })
    }

    fn nest(&mut self, span: Span) -> Parsed<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error(
                span,
                format!("nested too deeply (over {MAX_DEPTH} levels): split it with `let`"),
            ));
        }
        Ok(())
    }

    fn expression(&mut self) -> Parsed<Expr> {
        let span = self.peek().span;
        self.nest(span)?;
        let c = self.binary(0)?;
        let e = if self.is("?") {
            self.bump();
            self.skip_newlines();
            let a = self.expression()?;
            self.skip_newlines();
            self.expect(":", "between the two choices of `c ? a : b`")?;
            self.skip_newlines();
            let b = self.expression()?;
            let span = c.span.to(b.span);
            self.node(
                ExprKind::Choose(Box::new(c), Box::new(a), Box::new(b)),
                span,
            )?
        } else {
            c
        };
        self.depth -= 1;
        Ok(e)
    }

    /// Left-associative binary operators, loosest (`||`, level 0) to tightest (`*`, level 5).
    fn binary(&mut self, level: usize) -> Parsed<Expr> {
        const LEVELS: [&[(&str, BinOp)]; 6] = [
            &[("||", BinOp::Or)],
            &[("&&", BinOp::And)],
            &[("==", BinOp::Eq), ("!=", BinOp::Ne)],
            &[
                ("<", BinOp::Lt),
                ("<=", BinOp::Le),
                (">", BinOp::Gt),
                (">=", BinOp::Ge),
            ],
            &[("+", BinOp::Add), ("-", BinOp::Sub)],
            &[("*", BinOp::Mul), ("/", BinOp::Div)],
        ];
        if level == LEVELS.len() {
            return self.unary();
        }
        let mut left = self.binary(level + 1)?;
        while let Tok::Punct(p) = self.peek().tok {
            let Some(&(_, op)) = LEVELS[level].iter().find(|(s, _)| *s == p) else {
                break;
            };
            self.bump();
            self.skip_newlines();
            let right = self.binary(level + 1)?;
            let span = left.span.to(right.span);
            left = self.node(ExprKind::Binary(op, Box::new(left), Box::new(right)), span)?;
        }
        Ok(left)
    }

    fn unary(&mut self) -> Parsed<Expr> {
        self.skip_newlines();
        let t = self.peek().clone();
        let op = match t.tok {
            Tok::Punct("-") => Some(UnOp::Neg),
            Tok::Punct("!") => Some(UnOp::Not),
            Tok::Punct("+") => None,
            _ => return self.postfix(),
        };
        self.bump();
        self.nest(t.span)?;
        let inner = self.unary()?;
        self.depth -= 1;
        let Some(op) = op else {
            return Ok(inner);
        };
        let span = t.span.to(inner.span);
        self.node(ExprKind::Unary(op, Box::new(inner)), span)
    }

    fn postfix(&mut self) -> Parsed<Expr> {
        let mut e = self.primary()?;
        while self.is(".") {
            let dot = self.bump();
            let t = self.bump();
            let index = match &t.tok {
                Tok::Name(n) => match n.as_str() {
                    "x" | "r" => Some(0),
                    "y" | "g" => Some(1),
                    "z" | "b" => Some(2),
                    _ => None,
                },
                _ => None,
            };
            let Some(index) = index else {
                return Err(self.error(
                    dot.span.to(t.span),
                    format!(
                        "a vec3's parts are `.x`, `.y` and `.z`, found `.{}`",
                        token_text(self.source, &t)
                    ),
                ));
            };
            let span = e.span.to(t.span);
            e = self.node(ExprKind::Component(Box::new(e), index), span)?;
        }
        Ok(e)
    }

    fn primary(&mut self) -> Parsed<Expr> {
        let t = self.bump();
        match t.tok {
            Tok::Num(v) => self.node(ExprKind::Num(v), t.span),
            Tok::Name(ref n) if n == "true" || n == "false" => {
                self.node(ExprKind::Bool(n == "true"), t.span)
            }
            Tok::Name(name) => {
                if !self.is("(") {
                    return self.node(ExprKind::Name(name), t.span);
                }
                self.bump();
                self.parens += 1;
                let mut args = Vec::new();
                if !self.is(")") {
                    loop {
                        args.push(self.expression()?);
                        if self.is(",") {
                            self.bump();
                            continue;
                        }
                        break;
                    }
                }
                let close = self.expect(")", &format!("to close `{name}(`"))?;
                self.parens -= 1;
                self.node(
                    ExprKind::Call {
                        name,
                        name_span: t.span,
                        args,
                    },
                    t.span.to(close.span),
                )
            }
            Tok::Punct("(") => {
                self.parens += 1;
                let inner = self.expression()?;
                let close = self.expect(")", "to close `(`")?;
                self.parens -= 1;
                // The parentheses are part of its text: `(a + b) * c` starts at `(`.
                Ok(Expr {
                    span: t.span.to(close.span),
                    ..inner
                })
            }
            other => Err(self.error(
                t.span,
                format!(
                    "expected a number, a name or `(`, found {}",
                    describe(&other)
                ),
            )),
        }
    }
}

fn token_text<'a>(source: &'a str, t: &Token) -> &'a str {
    source.get(t.span.start..t.span.end).unwrap_or("")
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("the number {v}"),
        Tok::Name(n) => format!("`{n}`"),
        Tok::Punct(p) => format!("`{p}`"),
        Tok::Newline => "the end of the line".to_owned(),
        Tok::End => "the end of the text".to_owned(),
    }
}
