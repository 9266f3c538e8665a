//! The modules form a ladder: no top-level module of either crate uses, directly or through
//! others, a module that uses it back (ARCHITECTURE.md, "The ladder").
//!
//! Read as text, as a reader would: every `crate::X` path (and each name of a
//! `use crate::{X, Y::…}` group) in a module's files, outside its `#[cfg(test)] mod tests`
//! and comments, is an edge to module X; a name the crate root re-exports (`crate::Camera`)
//! is an edge to the module it comes from. Then any strongly connected set of more than one
//! module is a circle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The text that counts: comments and the inline test module dropped.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The names after `prefix` (`crate::`, or `super::` for a module's children) at each
/// occurrence: one, or those of a `{…}` group.
fn paths_after(text: &str, prefix: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().next_back();
        rest = &rest[i + prefix.len()..];
        // `raylab_core::` is another crate; `$crate` a macro's own.
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    names.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            names.push(name);
        }
    }
    names
}

/// The module graph of the crate whose sources are in `src` (root `root`: lib.rs or main.rs).
fn graph(src: &Path, root: &str) -> Graph {
    // Names the root re-exports: `pub use camera::Camera;`, `pub use m::{A, B};`.
    let mut reexports = BTreeMap::new();
    let root_text = std::fs::read_to_string(src.join(root)).unwrap();
    for line in root_text.lines() {
        let Some(rest) = line.trim().strip_prefix("pub use ") else {
            continue;
        };
        let (module, names) = rest.split_once("::").unwrap_or((rest, ""));
        let names = names
            .trim_end_matches(';')
            .trim_matches(|c| c == '{' || c == '}');
        for name in names.split(',') {
            let name = name.rsplit("::").next().unwrap_or("").trim();
            reexports.insert(name.to_owned(), module.to_owned());
        }
    }
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut graph = Graph::new();
    for file in files {
        let rel = file.strip_prefix(src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let top = top.trim_end_matches(".rs").to_owned();
        let is_test_file = rel.iter().any(|c| c == "tests") || rel.ends_with("tests.rs");
        if top == "lib" || top == "main" || is_test_file {
            continue;
        }
        let text = code(&std::fs::read_to_string(&file).unwrap());
        let edges = graph.entry(top.clone()).or_default();
        for name in paths_after(&text, "crate::") {
            let module = reexports.get(&name).cloned().unwrap_or(name);
            if module != top {
                edges.insert(module);
            }
        }
    }
    graph
}

/// The graph of the children of the module in folder `dir` (its `mod.rs` the parent): a child
/// file's `super::X` is an edge to sibling X. Its tests are left out.
fn children_graph(dir: &Path) -> Graph {
    let mut graph = Graph::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let Some(name) = path.file_stem().map(|n| n.to_string_lossy().into_owned()) else {
            continue;
        };
        if path.is_dir() || name == "mod" || name == "tests" {
            continue;
        }
        graph.entry(name.clone()).or_default();
        let text = code(&std::fs::read_to_string(&path).unwrap());
        for sibling in paths_after(&text, "super::") {
            let is_sibling = dir.join(format!("{sibling}.rs")).is_file()
                || dir.join(&sibling).join("mod.rs").is_file();
            if sibling != name && is_sibling {
                graph.get_mut(&name).unwrap().insert(sibling);
            }
        }
    }
    graph
}

/// The circles of `graph`: its strongly connected sets of more than one module (Tarjan).
fn circles(graph: &Graph) -> Vec<Vec<String>> {
    struct State<'g> {
        graph: &'g Graph,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        found: Vec<Vec<String>>,
    }
    fn visit<'g>(s: &mut State<'g>, v: &'g str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        for w in s.graph[v].iter().filter(|w| s.graph.contains_key(*w)) {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let lw = s.low[w.as_str()];
                s.low.insert(v, s.low[v].min(lw));
            } else if s.stack.contains(&w.as_str()) {
                let iw = s.index[w.as_str()];
                s.low.insert(v, s.low[v].min(iw));
            }
        }
        if s.low[v] == s.index[v] {
            let mut set = Vec::new();
            while let Some(w) = s.stack.pop() {
                set.push(w.to_owned());
                if w == v {
                    break;
                }
            }
            if set.len() > 1 {
                set.sort();
                s.found.push(set);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.found
}

#[test]
fn the_reader_finds_a_circle_when_there_is_one() {
    let text = "use crate::{Camera, scene::Scene};\nlet x = crate::accel::build();\n\
                // crate::view in a comment\n$crate::named::x; raylab_core::film::Image";
    assert_eq!(
        paths_after(&code(text), "crate::"),
        ["Camera", "scene", "accel"]
    );
    let mut g = Graph::new();
    for (a, b) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d"), ("d", "e")] {
        g.entry(a.into()).or_default().insert(b.into());
        g.entry(b.into()).or_default();
    }
    assert_eq!(circles(&g), vec![vec!["a", "b", "c"]]);
}

#[test]
fn no_module_uses_one_that_uses_it_back() {
    let core = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let app = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../src");
    for (src, root) in [(&core, "lib.rs"), (&app, "main.rs")] {
        let g = graph(src, root);
        assert!(g.len() >= 3, "{}: {g:?}", src.display());
        assert_eq!(circles(&g), Vec::<Vec<String>>::new(), "{}", src.display());
    }
    // The window's modules, siblings under `app`.
    let g = children_graph(&app.join("app"));
    assert!(g.len() > 8, "{g:?}");
    assert_eq!(circles(&g), Vec::<Vec<String>>::new(), "app: {g:?}");
    // The core's bottom rung knows nothing of what is built on it.
    let g = graph(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), "lib.rs");
    for high in ["bench", "scene", "light", "integrator", "render"] {
        assert!(!g["accel"].contains(high), "accel uses {high}");
    }
}
