//! Gradescope's autograder results (`results.json`): for each student, a test for each image
//! they handed in, worth [`MAX_SCORE`], scored in full when the image is the exact figure
//! (verdict `none`) and 0 otherwise, with the check's report as its output (the mistake named,
//! its equation and its fix), so the student reads why.
//!
//! The format: `{"output": text, "tests": [{"name", "score", "max_score", "output",
//! "visibility"}]}`; with no top-level `score`, Gradescope adds up the tests'.

use serde_json::{Value, json};

use crate::teaching::check::class::{Class, Row};

/// What one image is worth.
pub const MAX_SCORE: f64 = 1.0;

/// A student's name as a folder's: letters, digits, `.`, `-` and `_` kept, anything else `_`;
/// never empty, `.` or `..`.
pub fn folder_name(student: &str) -> String {
    let name: String = student
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') {
                c
            } else {
                '_'
            }
        })
        .collect();
    if name.is_empty() || name.chars().all(|c| c == '.') {
        format!("_{name}")
    } else {
        name
    }
}

/// The test of one row.
fn test(row: &Row, class: &Class) -> Value {
    let file = &row.submission.name;
    let (name, score, mut output) = match &row.result {
        Ok(j) => {
            let stage = class.against[row.against.unwrap_or(0)].shading.stage;
            let figure = stage
                .figure()
                .map_or(String::new(), |f| format!("figure {f}, "));
            let right = j.report.best.mistake == "none";
            (
                format!("{file}: the exact figure ({figure}stage {stage})"),
                if right { MAX_SCORE } else { 0.0 },
                j.report.to_text(),
            )
        }
        Err(reason) => (
            format!("{file}: a render to check"),
            0.0,
            format!("could not be checked: {reason}\n"),
        ),
    };
    if !row.identical_to.is_empty() {
        output += &format!(
            "note: its pixels are identical to {}'s\n",
            row.identical_to.join(", ")
        );
    }
    json!({
        "name": name,
        "score": score,
        "max_score": MAX_SCORE,
        "output": output,
        "visibility": "visible",
    })
}

/// Each student's folder name and results, in order of name.
pub fn results(class: &Class) -> Vec<(String, Value)> {
    let mut students: Vec<&str> = class
        .rows
        .iter()
        .map(|r| r.submission.student.as_str())
        .collect();
    students.sort_unstable();
    students.dedup();
    let mut used = std::collections::HashSet::new();
    students
        .into_iter()
        .map(|student| {
            // Two students whose names make the same folder name: the second gets `-2`, …
            let mut folder = folder_name(student);
            let base = folder.clone();
            for n in 2.. {
                if used.insert(folder.clone()) {
                    break;
                }
                folder = format!("{base}-{n}");
            }
            let tests: Vec<Value> = class
                .rows
                .iter()
                .filter(|r| r.submission.student == student)
                .map(|r| test(r, class))
                .collect();
            let right = tests.iter().filter(|t| t["score"] == MAX_SCORE).count();
            let output = format!(
                "raylab check: {right} of {} images are the exact figure (within 2/255 on 99 % \
                 of pixels)",
                tests.len()
            );
            (folder, json!({ "output": output, "tests": tests }))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_folders_are_safe_names() {
        assert_eq!(folder_name("alice"), "alice");
        assert_eq!(folder_name("Émile O'Neil"), "_mile_O_Neil");
        assert_eq!(folder_name(".."), "_..");
        assert_eq!(folder_name(""), "_");
        assert_eq!(folder_name("a/b"), "a_b");
    }
}
