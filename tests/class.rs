//! `raylab check FOLDER`: a class checked at once, as a teacher runs it. A class folder made
//! here (every catalogue mistake, right and anti-aliased images, a JPEG, a truncated PNG, an
//! empty file, a text file, the wrong size, a file left out of the list, identical images)
//! gives the expected row for each in report.json and report.csv; the page is well formed and
//! links only to files in the report folder; the Gradescope files follow their schema.

mod common;

#[path = "../crates/raylab-core/tests/common/class_folder.rs"]
mod class_folder;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use common::{raylab, stderr};
use serde_json::Value;

/// The elements that have no end tag.
const VOID: [&str; 6] = ["meta", "img", "input", "br", "hr", "link"];

/// A small HTML reader: the document is one tree (every element closed in order, void ones
/// excepted, SVG's `<x/>` allowed), attributes quoted, every `&` an entity, no id twice.
/// Returns each element's attributes, in order.
fn elements(html: &str) -> Vec<(String, BTreeMap<String, String>)> {
    let mut found = Vec::new();
    let mut open: Vec<String> = Vec::new();
    let mut rest = html;
    let mut ids = BTreeSet::new();
    let entity = |text: &str| {
        let mut t = text;
        while let Some(i) = t.find('&') {
            t = &t[i + 1..];
            let end = t.find(';').expect("an entity ends with ;");
            let name = &t[..end];
            assert!(
                name.chars().all(|c| c.is_ascii_alphanumeric() || c == '#') && !name.is_empty(),
                "a bare & before '{}'",
                &t[..end.min(20)]
            );
        }
    };
    while let Some(i) = rest.find('<') {
        entity(&rest[..i]);
        rest = &rest[i..];
        if let Some(r) = rest.strip_prefix("<!DOCTYPE html>") {
            rest = r;
            continue;
        }
        if let Some(r) = rest.strip_prefix("</") {
            let end = r.find('>').expect("an end tag closes");
            let name = &r[..end];
            assert_eq!(
                open.pop().as_deref(),
                Some(name),
                "</{name}> closes what is open"
            );
            rest = &r[end + 1..];
            continue;
        }
        let tag_end = rest.find('>').expect("a tag closes");
        let tag = &rest[1..tag_end];
        let self_closing = tag.ends_with('/');
        let tag = tag.trim_end_matches('/');
        let name_end = tag.find(char::is_whitespace).unwrap_or(tag.len());
        let name = &tag[..name_end];
        assert!(
            !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric()),
            "a tag's name: '{name}'"
        );
        let mut attributes = BTreeMap::new();
        let mut a = tag[name_end..].trim();
        while !a.is_empty() {
            let key_end = a.find(['=', ' ']).unwrap_or(a.len());
            let key = &a[..key_end];
            a = &a[key_end..];
            let value = if let Some(v) = a.strip_prefix("=\"") {
                let close = v.find('"').expect("a quoted value closes");
                let value = &v[..close];
                entity(value);
                a = &v[close + 1..];
                value.to_owned()
            } else {
                String::new()
            };
            assert!(!attributes.contains_key(key), "<{name}> has {key} twice");
            attributes.insert(key.to_owned(), value);
            a = a.trim_start();
        }
        if let Some(id) = attributes.get("id") {
            assert!(ids.insert(id.clone()), "id {id} twice");
        }
        found.push((name.to_owned(), attributes));
        rest = &rest[tag_end + 1..];
        if name == "style" || name == "script" {
            let end = rest.find(&format!("</{name}>")).expect("raw text ends");
            rest = &rest[end + name.len() + 3..];
        } else if !self_closing && !VOID.contains(&name) {
            open.push(name.to_owned());
        }
    }
    entity(rest);
    assert!(open.is_empty(), "left open: {open:?}");
    found
}

/// Every link of the page leads to a place in it or a file in the report folder.
fn assert_links_inside(html: &str, folder: &Path) {
    let elements = elements(html);
    let ids: BTreeSet<&str> = elements
        .iter()
        .filter_map(|(_, a)| a.get("id").map(String::as_str))
        .collect();
    let mut files = 0;
    for (name, attributes) in &elements {
        for key in ["href", "src", "for"] {
            let Some(link) = attributes.get(key) else {
                continue;
            };
            if key == "for" {
                assert!(ids.contains(link.as_str()), "<label for={link}>");
            } else if let Some(id) = link.strip_prefix('#') {
                assert!(ids.contains(id), "<{name} {key}={link}>: no such id");
            } else {
                assert!(
                    !link.contains(':') && !link.starts_with('/') && !link.contains(".."),
                    "<{name} {key}={link}> leaves the folder"
                );
                assert!(folder.join(link).is_file(), "{link} is in the folder");
                files += 1;
            }
        }
    }
    assert!(files > 0);
    assert!(
        !elements.iter().any(|(n, _)| n == "link"),
        "no style sheet from elsewhere"
    );
}

/// Gradescope's results.json: `tests` of `name`, `score`, `max_score`, `output` and
/// `visibility`, nothing else; a top-level `output`.
fn assert_gradescope(results: &Value) {
    let object = results.as_object().expect("an object");
    for key in object.keys() {
        assert!(
            ["tests", "output", "score"].contains(&key.as_str()),
            "{key}"
        );
    }
    assert!(object["output"].is_string());
    let tests = object["tests"].as_array().expect("tests");
    assert!(!tests.is_empty());
    for t in tests {
        let t = t.as_object().expect("a test is an object");
        for key in t.keys() {
            assert!(
                ["name", "score", "max_score", "output", "visibility"].contains(&key.as_str()),
                "{key}"
            );
        }
        assert!(!t["name"].as_str().unwrap().is_empty());
        let (score, max) = (
            t["score"].as_f64().unwrap(),
            t["max_score"].as_f64().unwrap(),
        );
        assert!(score == 0.0 || score == max, "{score} of {max}");
        assert!(max > 0.0);
        assert!(!t["output"].as_str().unwrap().is_empty());
        assert!(
            ["hidden", "after_due_date", "after_published", "visible"]
                .contains(&t["visibility"].as_str().unwrap())
        );
    }
}

#[test]
fn a_class_folder_gives_a_row_for_each_submission() {
    let dir = tempfile::tempdir().unwrap();
    let (folder, list, expected) = class_folder::make_class(dir.path(), 64, None);
    let out = dir.path().join("report");
    let run = raylab(&[
        "check",
        folder.to_str().unwrap(),
        "--csv",
        list.to_str().unwrap(),
        "--report",
        out.to_str().unwrap(),
        "--gradescope",
        "--threads",
        "2",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stdout = String::from_utf8(run.stdout).unwrap();

    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let rows = json["submissions"].as_array().unwrap();
    assert_eq!(rows.len(), expected.len(), "a row a submission");
    let csv_text = std::fs::read_to_string(out.join("report.csv")).unwrap();
    let csv = raylab_core::teaching::check::csv::parse(&csv_text).unwrap();
    assert_eq!(csv[0], raylab_core::teaching::check::report::CSV_COLUMNS);
    assert_eq!(csv.len(), rows.len() + 1);
    let column = |name: &str| csv[0].iter().position(|c| c == name).unwrap();
    for e in &expected {
        let row = rows
            .iter()
            .find(|r| r["file"] == e.file.as_str())
            .unwrap_or_else(|| panic!("{} has a row", e.file));
        let verdict = row["verdict"].as_str().unwrap();
        assert!(e.verdicts.contains(&verdict), "{}: {row:#}", e.file);
        let identical: Vec<&str> = row["identical_to"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert_eq!(identical, e.identical_to, "{}", e.file);
        let line = csv.iter().find(|l| l[0] == e.file).unwrap();
        assert_eq!(line[column("verdict")], verdict, "{}", e.file);
        assert_eq!(line[column("identical_to")], e.identical_to.join("; "));
        match e.reason {
            Some(reason) => {
                let said = row["reason"].as_str().unwrap();
                assert!(said.contains(reason), "{}: {said}", e.file);
                // A cell starting with `-` is written after a `'`, so no spreadsheet takes it
                // for a formula.
                assert_eq!(line[column("reason")].trim_start_matches('\''), said);
                assert!(row.get("check").is_none());
            }
            None => {
                let check = &row["check"];
                assert_eq!(check["best"]["mistake"], verdict);
                let share = check["match"].as_f64().unwrap();
                assert_eq!(line[column("match")], share.to_string());
                let ssim = row["ssim"].as_f64().unwrap();
                assert!((0.0..=1.0).contains(&ssim), "{ssim}");
                if check["worst_block"]["mean_difference"] == 0.0 {
                    assert_eq!(ssim, 1.0, "{}: the same pixels", e.file);
                }
                if verdict != "none" && verdict != "unknown" {
                    assert!(!check["best"]["fix"].as_str().unwrap().is_empty());
                    assert!(ssim < 1.0, "{}: a mistake shows ({ssim})", e.file);
                }
                for image in row["images"].as_object().unwrap().values() {
                    assert!(out.join(image.as_str().unwrap()).is_file());
                }
            }
        }
        if let Some(note) = e.note {
            let notes = row["check"]["notes"].to_string();
            assert!(notes.contains(note), "{}: {notes}", e.file);
        }
        assert!(stdout.contains(&e.file), "{stdout}");
    }
    // Every mistake of the catalogue was named.
    let counts = json["verdicts"].as_object().unwrap();
    for m in raylab_core::teaching::check::Mistake::catalogue() {
        assert!(counts.contains_key(m.name()), "{m}: {counts:?}");
    }

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert_links_inside(&html, &out);
    for e in &expected {
        assert!(
            html.contains(&format!("data-name=\"{}\"", e.file)),
            "{}",
            e.file
        );
    }
    assert!(html.contains("<svg"), "the histogram");

    // A results.json a student, each test an image of theirs.
    let students: BTreeSet<String> = rows
        .iter()
        .map(|r| r["student"].as_str().unwrap().to_owned())
        .collect();
    for student in &students {
        let path = out.join("gradescope").join(student).join("results.json");
        let results: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_gradescope(&results);
        let tests = results["tests"].as_array().unwrap();
        let theirs = rows.iter().filter(|r| r["student"] == student.as_str());
        assert_eq!(tests.len(), theirs.clone().count(), "{student}");
        for (t, r) in tests.iter().zip(theirs) {
            let right = r["verdict"] == "none";
            assert_eq!(t["score"].as_f64() == Some(1.0), right, "{student}: {t}");
            if r["verdict"] == "no-4pi" {
                assert!(t["output"].as_str().unwrap().contains("4πr²"), "{t}");
            }
        }
    }
    // No temporary file was left behind.
    for name in common::files_in(&out) {
        assert!(!name.to_string_lossy().starts_with('.'), "{name:?}");
    }
}

/// With --screenshot-settings, a PNG carrying a workbench screenshot's settings is checked
/// against them; without, against the options, like the others.
#[test]
fn screenshots_carry_their_own_settings() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("class");
    std::fs::create_dir(&folder).unwrap();
    let shot = folder.join("direct.png");
    let render = raylab(&[
        "render",
        "--stage",
        "direct",
        "--width",
        "40",
        "--height",
        "40",
        "--out",
        shot.to_str().unwrap(),
    ]);
    assert!(render.status.success(), "{}", stderr(&render));
    // The same stage written by a student's tracer: no settings in it.
    let plain = image::open(&shot).unwrap().to_rgb8();
    plain.save(folder.join("plain.png")).unwrap();
    let verdict = |extra: &[&str]| -> BTreeMap<String, String> {
        let mut args = vec!["check", folder.to_str().unwrap(), "--json"];
        args.extend(extra);
        let run = raylab(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        let json: Value = serde_json::from_slice(&run.stdout).unwrap();
        json["submissions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                (
                    r["file"].as_str().unwrap().to_owned(),
                    r["verdict"].as_str().unwrap().to_owned(),
                )
            })
            .collect()
    };
    let with = verdict(&["--screenshot-settings"]);
    assert_eq!(with["direct.png"], "none");
    assert_ne!(with["plain.png"], "none", "checked against figure 7");
    let all_direct = verdict(&["--stage", "direct"]);
    assert_eq!(all_direct["plain.png"], "none");
    assert_eq!(all_direct["direct.png"], "none");
    let without = verdict(&[]);
    assert_ne!(without["direct.png"], "none");
}

/// What stops a class before it starts: a folder with nothing in it, a list with an unknown
/// column; a bad line only refuses its own file.
#[test]
fn bad_lists_and_empty_folders_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let run = raylab(&["check", empty.to_str().unwrap()]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("holds no files"), "{}", stderr(&run));

    let folder = dir.path().join("class");
    std::fs::create_dir(&folder).unwrap();
    let image = folder.join("a.png");
    let render = raylab(&[
        "render",
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        image.to_str().unwrap(),
    ]);
    assert!(render.status.success());
    std::fs::copy(&image, folder.join("b.png")).unwrap();
    let list = dir.path().join("list.csv");
    std::fs::write(&list, "file,colour\na.png,red\n").unwrap();
    let run = raylab(&[
        "check",
        folder.to_str().unwrap(),
        "--csv",
        list.to_str().unwrap(),
    ]);
    assert!(!run.status.success());
    assert!(
        stderr(&run).contains("column 'colour' is not an option"),
        "{}",
        stderr(&run)
    );
    std::fs::write(&list, "file,stage\na.png,lab\nb.png,sepia\n").unwrap();
    let run = raylab(&[
        "check",
        folder.to_str().unwrap(),
        "--csv",
        list.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let stdout = String::from_utf8(run.stdout).unwrap();
    assert!(
        stdout.contains("a.png") && stdout.contains("none"),
        "{stdout}"
    );
    assert!(
        stdout.contains("b.png") && stdout.contains("list.csv' line 3") && stdout.contains("sepia"),
        "{stdout}"
    );
    // --diff-out is for one image.
    let run = raylab(&["check", folder.to_str().unwrap(), "--diff-out", "d.png"]);
    assert!(!run.status.success());
}
