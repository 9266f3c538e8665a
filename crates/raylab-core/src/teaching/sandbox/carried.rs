//! The equations as the settings carry them ([`EquationTexts`]: a text per quantity, in
//! screenshots and scene files): each text compiled on its own, the quantities put together,
//! and a student's file of several quantities split into texts.

use std::fmt;

use super::error::{SandboxError, Span};
use super::lex::{Tok, lex};
use super::parse::parse;
use super::{Equations, Quantity, compile};
use crate::transport::settings::EquationTexts;

/// The text of quantity `q` in `texts`.
pub fn text_of(texts: &EquationTexts, q: Quantity) -> Option<&str> {
    texts.texts()[q as usize].1
}

/// The text of quantity `q` in `texts`, to set.
pub fn text_mut(texts: &mut EquationTexts, q: Quantity) -> &mut Option<String> {
    texts
        .text_mut(q.name())
        .expect("every quantity has a text in the settings")
}

/// Compiles `text`, quantity `q`'s own: it must write `q` and no other quantity.
pub fn compile_one(q: Quantity, text: &str) -> Result<Equations, Vec<SandboxError>> {
    let equations = compile(text)?;
    let name = q.name();
    let others: Vec<SandboxError> = equations
        .written()
        .filter(|w| *w != q)
        .filter_map(|w| {
            let span = equations.span(w)?;
            Some(SandboxError::at(
                text,
                span,
                format!(
                    "this is `{name}`'s text: write `{}` ({}) in its own",
                    w.name(),
                    w.what()
                ),
            ))
        })
        .collect();
    if !others.is_empty() {
        return Err(others);
    }
    if equations.tape(q).is_none() {
        let end = text.trim_end().len();
        return Err(vec![SandboxError::at(
            text,
            Span::new(end, end),
            format!("write `{name} = …`, {}", q.what()),
        )]);
    }
    Ok(equations)
}

/// A text of the settings that does not compile: its quantity and first error.
#[derive(Clone, Debug, PartialEq)]
pub struct TextError {
    pub quantity: Quantity,
    pub error: SandboxError,
}

impl fmt::Display for TextError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "equation `{}`, line {}, column {}: {}",
            self.quantity.name(),
            self.error.line,
            self.error.column,
            self.error.message
        )
    }
}

impl std::error::Error for TextError {}

/// Every quantity `texts` gives, compiled (the lab's for the others); or the first error.
pub fn compile_texts(texts: &EquationTexts) -> Result<Equations, TextError> {
    let mut out = Equations::lab();
    for q in Quantity::ALL {
        if let Some(text) = text_of(texts, q) {
            let one = compile_one(q, text).map_err(|errors| TextError {
                quantity: q,
                error: errors.into_iter().next().expect("an error at least"),
            })?;
            out.take(q, &one);
        }
    }
    Ok(out)
}

/// A student's file of quantities (`source`, which compiles to `all`) as a text per quantity:
/// each the file without the other quantities' statements (lines left empty by them dropped),
/// its `let` lines kept. Each text compiles to the file's own quantity (checked).
pub fn split(source: &str, all: &Equations) -> Result<EquationTexts, String> {
    let not_split = |why: &str| format!("the equations could not be taken apart: {why}");
    let tokens = lex(source).map_err(|e| not_split(&e.message))?;
    let stmts = parse(source, &tokens).map_err(|_| not_split("they do not parse"))?;
    // Each quantity's statement as a byte range: from its first token (`let`, a C++ type) to
    // the end of its expression and a `;` after it.
    let mut ranges = Vec::new();
    for stmt in &stmts {
        let Some(q) = Quantity::by_name(&stmt.name) else {
            continue;
        };
        let Some(at) = tokens.iter().position(|t| t.span == stmt.name_span) else {
            return Err(not_split("a statement was not found"));
        };
        let first = tokens[..at]
            .iter()
            .rposition(|t| matches!(t.tok, Tok::Newline | Tok::Punct(";")))
            .map_or(0, |i| i + 1);
        let mut end = stmt.expr.span.end;
        if let Some(next) = tokens.iter().find(|t| t.span.start >= end)
            && next.tok == Tok::Punct(";")
        {
            end = next.span.end;
        }
        ranges.push((q, tokens[first].span.start, end));
    }
    let mut texts = EquationTexts::default();
    for q in all.written() {
        let mut bytes = source.as_bytes().to_vec();
        for &(other, start, end) in &ranges {
            if other != q {
                for b in &mut bytes[start..end] {
                    if *b != b'\n' {
                        *b = b' ';
                    }
                }
            }
        }
        // Only ASCII was replaced, by ASCII: still UTF-8.
        let blanked = String::from_utf8(bytes).map_err(|_| not_split("not UTF-8"))?;
        let text: Vec<&str> = blanked
            .lines()
            .zip(source.lines())
            .filter(|(now, was)| !now.trim().is_empty() || was.trim().is_empty())
            .map(|(now, _)| now.trim_end())
            .collect();
        let text = text.join("\n");
        let own = compile_one(q, &text).map_err(|e| not_split(&e[0].message))?;
        if own.tape(q) != all.tape(q) {
            return Err(not_split(&format!("`{}` came out different", q.name())));
        }
        *text_mut(&mut texts, q) = Some(text);
    }
    Ok(texts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of several quantities splits into a text each, with its lets, each compiling
    /// to the file's own quantity; `compile_texts` puts them together again.
    #[test]
    fn a_file_splits_into_texts_that_compile_to_the_same() {
        let file = "// mine\nvec3 r = lightPos - position;\nfloat r2 = dot(r, r);\n\
                    D = lightColor * max(dot(normalize(r), normal), 0.0) / r2; // no 4π\n\
                    shadowed = false\nR = color * D; let k = 2\n";
        let all = compile(file).unwrap();
        let texts = split(file, &all).unwrap();
        let d = texts.direct.as_deref().unwrap();
        assert!(
            d.contains("vec3 r = lightPos - position;") && d.contains("D = "),
            "{d}"
        );
        assert!(!d.contains("shadowed =") && !d.contains("R ="), "{d}");
        let r = texts.value.as_deref().unwrap();
        assert!(r.contains("R = color * D;") && !r.contains("D = "), "{r}");
        assert!(texts.d.is_none() && texts.shadow_start.is_none());
        let together = compile_texts(&texts).unwrap();
        for q in Quantity::ALL {
            assert_eq!(together.tape(q), all.tape(q), "{}", q.name());
        }
    }

    /// A text writing another quantity, or not its own, is refused with its place.
    #[test]
    fn a_text_writes_its_own_quantity_only() {
        let e = compile_one(Quantity::Direct, "R = color").unwrap_err();
        assert!(e[0].message.contains("`D`'s text: write `R`"), "{e:?}");
        assert_eq!((e[0].line, e[0].column), (1, 1));
        let e = compile_one(Quantity::Direct, "let k = 1\n").unwrap_err();
        assert!(e[0].message.contains("write `D = …`"), "{e:?}");
        let mut texts = EquationTexts::default();
        texts.value = Some("R = colour".into());
        let e = compile_texts(&texts).unwrap_err();
        assert_eq!(e.quantity, Quantity::Value);
        assert!(
            e.to_string()
                .starts_with("equation `R`, line 1, column 5: unknown name `colour`"),
            "{e}"
        );
    }

    /// Scene files and settings JSON carry the equations and read them back the same; a text
    /// that does not compile is refused naming its quantity, line and column; with none, the
    /// files say nothing of them.
    #[test]
    fn scene_files_and_settings_carry_the_equations() {
        use crate::RenderSettings;
        let mut s = RenderSettings::default();
        let folder = std::path::Path::new("");
        let lab_file = crate::files::scene_file::to_text(&s, folder).unwrap();
        assert!(!lab_file.contains("equations"), "{lab_file}");
        let lab_json = crate::files::settings_file::settings_text(&s).unwrap();
        assert!(!lab_json.contains("equations"), "{lab_json}");

        s.equations.direct = Some(
            "vec3 r = lightPos - position; // to the light\n\
             D = lightColor * max(dot(normalize(r), normal), 0.0) / dot(r, r)"
                .into(),
        );
        s.equations.value = Some("R = color * D".into());
        let file = crate::files::scene_file::to_text(&s, folder).unwrap();
        assert!(file.contains("[equations]"), "{file}");
        assert_eq!(crate::files::scene_file::parse(&file, folder).unwrap(), s);
        let json = crate::files::settings_file::settings_text(&s).unwrap();
        assert_eq!(
            crate::files::settings_file::from_json(&json)
                .unwrap()
                .settings,
            s
        );

        let bad = file.replace("R = color * D", "R = colour * D");
        let e = crate::files::scene_file::parse(&bad, folder).unwrap_err();
        assert!(
            e.contains("equation `R`, line 1, column 5: unknown name `colour`"),
            "{e}"
        );
        assert!(e.starts_with("line "), "{e}");

        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.json");
        std::fs::write(&path, json.replace("R = color * D", "R = color * D +")).unwrap();
        let e = crate::files::settings_file::read_file(&path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("equation `R`, line 1, column"), "{e}");
    }
}
