//! The sandbox language's tokens: numbers (`14`, `0.5`, `1e-4`, C++'s `14.f`), names (with
//! C++'s `glm::` and `std::` prefixes dropped), operators, `;` and line ends, with their byte
//! spans in the student's text. `//` and `/* … */` comments are skipped.

use super::error::{SandboxError, Span};

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    Num(f32),
    Name(String),
    /// An operator or punctuation: `+ - * / ( ) , . ? : ; = == != < <= > >= && || !`.
    Punct(&'static str),
    /// The end of a line: ends a statement, unless inside parentheses.
    Newline,
    End,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    pub tok: Tok,
    pub span: Span,
}

/// The operators, longest first so that `<=` is not read as `<` then `=`.
const PUNCTS: [&str; 22] = [
    "==", "!=", "<=", ">=", "&&", "||", "+", "-", "*", "/", "(", ")", ",", ".", "?", ":", ";", "=",
    "<", ">", "!", "&",
];

/// The namespaces a pasted C++ line may name, dropped: `glm::dot` is `dot`.
const PREFIXES: [&str; 2] = ["glm", "std"];

/// `source` as tokens, ending with [`Tok::End`].
pub fn lex(source: &str) -> Result<Vec<Token>, SandboxError> {
    let bytes = source.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        if c == b'\n' {
            out.push(Token {
                tok: Tok::Newline,
                span: Span::new(i, i + 1),
            });
            i += 1;
        } else if c.is_ascii_whitespace() {
            i += 1;
        } else if source[i..].starts_with("//") {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
        } else if source[i..].starts_with("/*") {
            let Some(end) = source[i + 2..].find("*/") else {
                return Err(SandboxError::at(
                    source,
                    Span::new(i, i + 2),
                    "this `/*` comment is never closed: end it with `*/`",
                ));
            };
            // Line ends inside the comment still end statements, as the student sees lines.
            for (k, b) in source[i..i + 2 + end].bytes().enumerate() {
                if b == b'\n' {
                    out.push(Token {
                        tok: Tok::Newline,
                        span: Span::new(i + k, i + k + 1),
                    });
                }
            }
            i += 2 + end + 2;
        } else if c.is_ascii_digit()
            || (c == b'.' && bytes.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            i = number_end(bytes, i);
            let text = &source[start..i];
            let digits = text.trim_end_matches(['f', 'F']);
            let digits = digits.strip_suffix('.').unwrap_or(digits);
            let value: f32 = digits.parse().map_err(|_| {
                SandboxError::at(
                    source,
                    Span::new(start, i),
                    format!("`{text}` is not a number: write it as 14, 0.5, 1e-4 or 14.f"),
                )
            })?;
            out.push(Token {
                tok: Tok::Num(value),
                span: Span::new(start, i),
            });
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let mut name_start = i;
            i = name_end(bytes, i);
            // `glm::` and `std::` are dropped, the span kept on the whole name.
            while PREFIXES.contains(&&source[name_start..i])
                && source[i..].starts_with("::")
                && bytes
                    .get(i + 2)
                    .is_some_and(|b| b.is_ascii_alphabetic() || *b == b'_')
            {
                name_start = i + 2;
                i = name_end(bytes, name_start);
            }
            out.push(Token {
                tok: Tok::Name(source[name_start..i].to_owned()),
                span: Span::new(start, i),
            });
        } else if let Some(p) = PUNCTS.iter().find(|p| source[i..].starts_with(**p)) {
            if *p == "&" {
                return Err(SandboxError::at(
                    source,
                    Span::new(i, i + 1),
                    "`&` is not an operator here: write `&&` for \"and\"",
                ));
            }
            i += p.len();
            out.push(Token {
                tok: Tok::Punct(p),
                span: Span::new(start, i),
            });
        } else {
            let ch = source[i..].chars().next().unwrap_or('?');
            let end = i + ch.len_utf8();
            let hint = match ch {
                '|' => ": write `||` for \"or\"",
                '{' | '}' => {
                    ": no blocks here, one expression a line (use `c ? a : b` for a choice)"
                }
                '[' | ']' => ": no arrays; use `.x`, `.y`, `.z` for a vec3's parts",
                '#' => ": no preprocessor lines; paste only the formula",
                '%' | '^' => ": no such operator; use `pow(a, b)` for powers",
                _ => "",
            };
            return Err(SandboxError::at(
                source,
                Span::new(i, end),
                format!("unexpected character `{ch}`{hint}"),
            ));
        }
    }
    out.push(Token {
        tok: Tok::End,
        span: Span::new(bytes.len(), bytes.len()),
    });
    Ok(out)
}

fn name_end(bytes: &[u8], mut i: usize) -> usize {
    while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
        i += 1;
    }
    i
}

/// The end of a number starting at `i`: digits, a fraction, an exponent, an `f` suffix.
fn number_end(bytes: &[u8], mut i: usize) -> usize {
    let digits = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    i = digits(i);
    // A `.` followed by a name is a component (`1.x` is not a number anyone writes; `14.f` is
    // C++'s float literal).
    if bytes.get(i) == Some(&b'.')
        && !bytes
            .get(i + 1)
            .is_some_and(|b| b.is_ascii_alphabetic() && *b != b'f' && *b != b'F' && *b != b'e')
    {
        i = digits(i + 1);
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
        if bytes.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
            i = digits(i + 1 + sign);
        }
    }
    if matches!(bytes.get(i), Some(b'f' | b'F')) {
        i += 1;
    }
    i
}
