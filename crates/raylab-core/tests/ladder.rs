//! The modules form a ladder: no module of either crate uses, directly or through others, a
//! sibling that uses it back (ARCHITECTURE.md, "The ladder"): the crates' top-level modules,
//! and the children of every module with a folder (`accel/`, `scene/`, `app/`, …).
//!
//! Read as text, as a reader would. A file's module comes from its path (`accel/cull.rs` is
//! `accel::cull`, `scene/mod.rs` is `scene`), an inline `mod x { … }` is a module inside it.
//! Comments and the contents of string and character literals are left out, and so are the
//! bodies of `#[cfg(test)] mod …` modules (found by matching their braces, wherever they are
//! in the file) and the files of those declared `#[cfg(test)] mod …;`. Every path that starts
//! `crate::`, `self::` or `super::` (any number of them), and every `use` of a child module, is
//! resolved to the module it names, through the names modules import (`crate::Camera`, which
//! the root re-exports from `camera`, is `camera`; `super::Light` in `light/quad.rs` is
//! `light::interface`). A path from module `a::b::…` to `a::c::…` is an edge from `b` to `c`
//! among the children of `a`. Then any strongly connected set of more than one module is a
//! circle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;
type Module = Vec<String>;

/// Circles known and accepted, each with the reason it is not broken: none.
const KNOWN_CIRCLES: &[(&str, &[&str])] = &[];

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

/// The module of the file at `rel` in a crate's `src`: `lib.rs`/`main.rs` the root (`[]`),
/// `a/mod.rs` and `a.rs` module `a`, `a/b.rs` module `a::b`.
fn module_of(rel: &Path, root: &str) -> Module {
    let mut parts: Module = rel
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if !(stem == "mod" || (parts.is_empty() && last == root)) {
        parts.push(stem.to_owned());
    }
    parts
}

/// `text` with comments blanked and the contents of string and character literals dropped
/// (`"…"` becomes `""`), lines kept: what is left is code, whose braces match.
fn code(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if c[i] == '\n' {
                        out.push('\n');
                    }
                    i += 1;
                }
            }
            out.push(' ');
        } else if c[i] == 'r'
            && (next == Some('"') || next == Some('#'))
            && !(i > 0 && ident(c[i - 1]))
        {
            // A raw string: r"…", r#"…"#, …
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                if c[j] == '\n' {
                    out.push('\n');
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                if c.get(i) == Some(&'\n') {
                    out.push('\n');
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else if c[i] == '\'' {
            // A character literal ('x', '\n', '\u{1F600}'), or a lifetime ('a), left as it is.
            if next == Some('\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push_str("' '");
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
                out.push_str("' '");
            } else {
                out.push('\'');
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The index just past the `}` matching the `{` at `open`.
fn matching_brace(text: &str, open: usize) -> usize {
    let mut depth = 0;
    for (i, ch) in text[open..].char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return open + i + 1;
                }
            }
            _ => {}
        }
    }
    text.len()
}

/// A module declaration at `at` in `text`: `mod NAME {` or `mod NAME;` (after `pub`, `pub(…)`
/// or attributes), as its name, where its body's `{` is (if inline) and where it ends.
fn module_declaration(text: &str, at: usize) -> Option<(String, Option<usize>, usize)> {
    let rest = &text[at..];
    let rest_trimmed = rest.strip_prefix("mod")?;
    if !rest_trimmed.starts_with(char::is_whitespace) {
        return None;
    }
    let name_start = at + 3 + (rest_trimmed.len() - rest_trimmed.trim_start().len());
    let name: String = text[name_start..]
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    let after = name_start + name.len();
    let tail = text[after..].trim_start();
    let at_tail = text.len() - tail.len();
    if tail.starts_with('{') {
        Some((name, Some(at_tail), matching_brace(text, at_tail)))
    } else if tail.starts_with(';') {
        Some((name, None, at_tail + 1))
    } else {
        None
    }
}

/// Whether `text[..at]` ends with the attribute `#[cfg(test)]`, perhaps followed by other
/// attributes and a visibility.
fn after_cfg_test(text: &str, at: usize) -> bool {
    let mut before = text[..at].trim_end();
    for visibility in ["pub(crate)", "pub(super)", "pub"] {
        if let Some(b) = before.strip_suffix(visibility) {
            before = b.trim_end();
            break;
        }
    }
    // Attributes, last first: `#[…]`.
    while before.ends_with(']') {
        let Some(open) = before.rfind("#[") else {
            return false;
        };
        if before[open..].replace(char::is_whitespace, "") == "#[cfg(test)]" {
            return true;
        }
        before = before[..open].trim_end();
    }
    false
}

/// The code of one module, apart from its inline child modules and its test modules, whose
/// bodies are blanked.
struct ModuleCode {
    module: Module,
    code: String,
}

/// Splits the code of the file module `module` into its own code and that of its inline
/// modules (each a [`ModuleCode`] of its own), leaving out `#[cfg(test)]` modules: their
/// bodies, and the names of those that are files (returned).
fn split_modules(text: &str, module: &Module, out: &mut Vec<ModuleCode>) -> Vec<Module> {
    let mut own = String::with_capacity(text.len());
    let mut test_files = Vec::new();
    let mut i = 0;
    let bytes = text.as_bytes();
    while i < text.len() {
        let at_word = i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        if at_word && let Some((name, body, end)) = module_declaration(text, i) {
            let mut child = module.clone();
            child.push(name);
            let is_test = after_cfg_test(text, i);
            match body {
                Some(open) if !is_test => {
                    let inner = &text[open + 1..end - 1];
                    test_files.extend(split_modules(inner, &child, out));
                }
                None if is_test => test_files.push(child),
                _ => {}
            }
            // Blanked, its lines kept.
            own.extend(text[i..end].chars().filter(|c| *c == '\n'));
            i = end;
            continue;
        }
        let ch = text[i..].chars().next().unwrap();
        own.push(ch);
        i += ch.len_utf8();
    }
    out.push(ModuleCode {
        module: module.clone(),
        code: own,
    });
    test_files
}

/// The paths of a use tree or path starting at `rest`: `a::b::c`, `a::{b, c::{d, e}}`, each
/// as its segments (`self` in a group names the group's own path, `*` is left out), with the
/// name it is imported under (its last segment, or what follows `as`).
fn tree_paths(rest: &str) -> Vec<(Vec<String>, String)> {
    fn parse(s: &str, prefix: &[String], out: &mut Vec<(Vec<String>, String)>) -> usize {
        let mut path = prefix.to_vec();
        let mut i = 0;
        loop {
            let skip = s[i..].len() - s[i..].trim_start().len();
            i += skip;
            if s[i..].starts_with('{') {
                i += 1;
                loop {
                    let skip = s[i..].len() - s[i..].trim_start().len();
                    i += skip;
                    if s[i..].starts_with('}') {
                        return i + 1;
                    }
                    if i >= s.len() {
                        return i;
                    }
                    i += parse(&s[i..], &path, out);
                    let skip = s[i..].len() - s[i..].trim_start().len();
                    i += skip;
                    if s[i..].starts_with(',') {
                        i += 1;
                    }
                }
            }
            let name: String = s[i..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '*')
                .collect();
            i += name.len();
            if name.is_empty() || name == "*" {
                // `path::*`, or a path followed by `::<…>`: the path so far.
                if path.len() > prefix.len() {
                    out.push((path, name));
                }
                return i;
            }
            if name != "self" || path.is_empty() {
                path.push(name);
            }
            let tail = &s[i..];
            if let Some(more) = tail.trim_start().strip_prefix("::") {
                i = s.len() - more.len();
                continue;
            }
            let mut alias = path.last().cloned().unwrap_or_default();
            if let Some(after_as) = tail.trim_start().strip_prefix("as ") {
                let a: String = after_as
                    .trim_start()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                i = s.len() - after_as.trim_start().len() + a.len();
                alias = a;
            }
            out.push((path, alias));
            return i;
        }
    }
    let mut out = Vec::new();
    parse(rest, &[], &mut out);
    out
}

/// Every path in a module's code that starts `crate::`, `self::` or `super::`, and the paths
/// of its `use` declarations, with whether each came from a `use` (an import, with the name
/// it is imported under).
fn paths_in(code: &str) -> Vec<(Vec<String>, Option<String>)> {
    let mut found = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let at_word = i == 0 || {
            let b = bytes[i - 1];
            !(b.is_ascii_alphanumeric() || b == b'_' || b == b'$' || b == b':')
        };
        if !at_word || !code.is_char_boundary(i) {
            i += 1;
            continue;
        }
        let rest = &code[i..];
        if let Some(tree) = rest.strip_prefix("use ") {
            let end = tree.find(';').unwrap_or(tree.len());
            for (path, alias) in tree_paths(&tree[..end]) {
                found.push((path, Some(alias)));
            }
            i += 4 + end;
            continue;
        }
        if ["crate::", "self::", "super::"]
            .iter()
            .any(|p| rest.starts_with(p))
        {
            let paths = tree_paths(rest);
            let consumed = paths
                .iter()
                .map(|(p, _)| p.iter().map(String::len).sum::<usize>())
                .max()
                .unwrap_or(1);
            found.extend(paths.into_iter().map(|(p, _)| (p, None)));
            i += consumed.max(1);
            continue;
        }
        i += 1;
    }
    found
}

/// A crate read as modules: each module's paths, and the names each imports.
struct Crate {
    modules: BTreeSet<Module>,
    paths: BTreeMap<Module, Vec<Module>>,
    imports: BTreeMap<Module, BTreeMap<String, Module>>,
}

impl Crate {
    fn read(src: &Path, root: &str) -> Self {
        let mut files = Vec::new();
        rust_files(src, &mut files);
        let mut parts = Vec::new();
        let mut test_modules = Vec::new();
        for file in &files {
            let rel = file.strip_prefix(src).unwrap();
            let module = module_of(rel, root);
            let text = code(&std::fs::read_to_string(file).unwrap());
            test_modules.extend(split_modules(&text, &module, &mut parts));
        }
        // The files of test modules, and what is below them, are left out.
        parts.retain(|p| !test_modules.iter().any(|t| p.module.starts_with(t)));
        let modules: BTreeSet<Module> = parts.iter().map(|p| p.module.clone()).collect();
        let mut raw = BTreeMap::new();
        for part in &parts {
            raw.insert(part.module.clone(), paths_in(&part.code));
        }
        let mut krate = Crate {
            modules,
            paths: BTreeMap::new(),
            imports: BTreeMap::new(),
        };
        // Absolute paths first, then the names imported.
        let mut absolute = BTreeMap::new();
        for (module, paths) in &raw {
            let mut list = Vec::new();
            for (path, import) in paths {
                let Some(abs) = krate.absolute(module, path, import.is_some()) else {
                    continue;
                };
                if let Some(alias) = import.as_ref().filter(|a| !a.is_empty() && *a != "*") {
                    krate
                        .imports
                        .entry(module.clone())
                        .or_default()
                        .insert(alias.clone(), abs.clone());
                }
                list.push(abs);
            }
            absolute.insert(module.clone(), list);
        }
        for (module, list) in absolute {
            let targets = list.iter().map(|p| krate.target(p, 0)).collect();
            krate.paths.insert(module, targets);
        }
        krate
    }

    /// `path`, written in `module`, from the crate's root: `None` for another crate's.
    fn absolute(&self, module: &Module, path: &[String], is_use: bool) -> Option<Module> {
        let mut abs = module.clone();
        let mut rest = path;
        match path.first().map(String::as_str) {
            Some("crate") => {
                abs.clear();
                rest = &path[1..];
            }
            Some("self") => rest = &path[1..],
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    abs.pop()?;
                    rest = &rest[1..];
                }
            }
            // `use child::…` in a module with that child.
            Some(first) if is_use => {
                let mut child = module.clone();
                child.push(first.to_owned());
                if !self.modules.contains(&child) {
                    return None;
                }
            }
            _ => return None,
        }
        abs.extend(rest.iter().cloned());
        Some(abs)
    }

    /// The module an absolute path names: its longest prefix that is a module, followed
    /// through a name that module imports.
    fn target(&self, path: &[String], depth: usize) -> Module {
        let mut k = path.len();
        while !self.modules.contains(&path[..k]) {
            k -= 1;
        }
        let module = path[..k].to_vec();
        if depth < 8
            && let Some(name) = path.get(k)
            && let Some(imported) = self.imports.get(&module).and_then(|m| m.get(name))
        {
            let mut through = imported.clone();
            through.extend(path[k + 1..].iter().cloned());
            return self.target(&through, depth + 1);
        }
        module
    }

    /// The graph of each module's children (the root's: the top-level modules): an edge
    /// from child `b` to child `c` of `a` for every path from `a::b::…` to `a::c::…`.
    fn graphs(&self) -> BTreeMap<Module, Graph> {
        let mut graphs: BTreeMap<Module, Graph> = BTreeMap::new();
        for module in &self.modules {
            if let Some((name, parent)) = module.split_last() {
                graphs
                    .entry(parent.to_vec())
                    .or_default()
                    .entry(name.clone())
                    .or_default();
            }
        }
        for (from, targets) in &self.paths {
            for to in targets {
                let k = from.iter().zip(to).take_while(|(a, b)| a == b).count();
                if k < from.len() && k < to.len() {
                    graphs
                        .entry(from[..k].to_vec())
                        .or_default()
                        .entry(from[k].clone())
                        .or_default()
                        .insert(to[k].clone());
                }
            }
        }
        graphs
    }
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

/// A crate of the files `files` (path in `src`, text), read as [`Crate::read`] reads one.
fn crate_of(files: &[(&str, &str)]) -> Crate {
    let dir = tempfile::tempdir().unwrap();
    for (path, text) in files {
        let path = dir.path().join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    Crate::read(dir.path(), "lib.rs")
}

fn names(list: &[&str]) -> BTreeSet<String> {
    list.iter().map(|s| (*s).to_owned()).collect()
}

#[test]
fn the_reader_finds_a_circle_when_there_is_one() {
    let text = "use crate::{Camera, scene::{Scene, spec::X}};\nlet x = crate::accel::build();\n\
                // crate::view in a comment\n$crate::named::x; raylab_core::film::Image;\n\
                let s = \"crate::film in a string\"; let c = '{';";
    let paths: Vec<Vec<String>> = paths_in(&code(text)).into_iter().map(|p| p.0).collect();
    assert_eq!(
        paths,
        [
            vec!["crate", "Camera"],
            vec!["crate", "scene", "Scene"],
            vec!["crate", "scene", "spec", "X"],
            vec!["crate", "accel", "build"],
        ]
    );
    let mut g = Graph::new();
    for (a, b) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d"), ("d", "e")] {
        g.entry(a.into()).or_default().insert(b.into());
        g.entry(b.into()).or_default();
    }
    assert_eq!(circles(&g), vec![vec!["a", "b", "c"]]);
}

/// What the reader once missed: a `#[cfg(test)] mod tests;` near the top of a file (the code
/// after it was not read), `super::super::` paths, files in folders, names imported by a
/// parent, inline modules; and test code, which is not counted.
#[test]
fn the_reader_reads_whole_files_in_folders() {
    let krate = crate_of(&[
        (
            "lib.rs",
            "pub mod a;\npub mod b;\npub mod c;\npub mod d;\npub use c::Thing;\n",
        ),
        (
            "a/mod.rs",
            "mod one;\nmod three;\nmod two;\n#[cfg(test)]\nmod tests;\nuse crate::Thing;\n\
             pub use two::Item as Renamed;\n",
        ),
        ("a/tests.rs", "use crate::d::X;\n"),
        (
            "a/one.rs",
            "use super::Renamed;\nfn f() { super::super::b::g() }\n\
             #[cfg(test)]\nmod tests {\n    use crate::d::Y;\n    fn t() { let s = \"}\"; }\n}\n\
             mod inner {\n    use super::super::three::W;\n}\n",
        ),
        ("a/two.rs", "pub struct Item;\n"),
        ("a/three.rs", "pub struct W;\n"),
        ("b.rs", "pub fn g() {}\n"),
        ("c.rs", "pub struct Thing;\n"),
        ("d.rs", "pub struct X;\npub struct Y;\n"),
    ]);
    let graphs = krate.graphs();
    let root = &graphs[&Vec::new()];
    // `b` through `super::super::`, `c` after the test module's declaration, not `d`.
    assert_eq!(root["a"], names(&["b", "c"]), "{root:?}");
    assert!(root["b"].is_empty() && root["d"].is_empty(), "{root:?}");
    let a = &graphs[&vec!["a".to_owned()]];
    // `two` through the name `a` imports, `three` from the inline module.
    assert_eq!(a["one"], names(&["three", "two"]), "{a:?}");
    assert!(!a.contains_key("tests"), "{a:?}");
    // A circle among a folder's children is found.
    let krate = crate_of(&[
        ("lib.rs", "mod s;\n"),
        ("s/mod.rs", "mod x;\nmod y;\n"),
        ("s/x.rs", "use super::y::A;\n"),
        ("s/y.rs", "fn f() { super::x::B }\n"),
    ]);
    let s = &krate.graphs()[&vec!["s".to_owned()]];
    assert_eq!(circles(s), vec![vec!["x", "y"]]);
}

#[test]
fn no_module_uses_one_that_uses_it_back() {
    let core = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let app = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../src");
    for (src, root, folders) in [
        (
            &core,
            "lib.rs",
            &[
                "base",
                "shading",
                "shapes",
                "transport",
                "teaching",
                "files",
                "shading::light",
                "shapes::accel",
                "shapes::scene",
                "transport::integrator",
                "transport::denoise",
                "teaching::check",
                "teaching::sandbox",
            ][..],
        ),
        (&app, "main.rs", &["app"][..]),
    ] {
        let krate = Crate::read(src, root);
        let graphs = krate.graphs();
        assert!(graphs[&Vec::new()].len() >= 3, "{}", src.display());
        for folder in folders {
            let key: Vec<String> = folder.split("::").map(str::to_owned).collect();
            let g = &graphs[&key];
            assert!(g.len() >= 2, "{folder}: {g:?}");
        }
        let mut found = Vec::new();
        for (parent, graph) in &graphs {
            for circle in circles(graph) {
                let known = KNOWN_CIRCLES
                    .iter()
                    .any(|(p, c)| *p == parent.join("::") && *c == circle.as_slice());
                if !known {
                    found.push(format!("{}: {circle:?}", parent.join("::")));
                }
            }
        }
        assert_eq!(found, Vec::<String>::new(), "{}", src.display());
        if root == "lib.rs" {
            // The folders are the rungs, in this order: each uses only those before it.
            let top = &graphs[&Vec::new()];
            let rungs = [
                "base",
                "shading",
                "shapes",
                "transport",
                "teaching",
                "files",
            ];
            for (i, rung) in rungs.iter().enumerate() {
                for used in &top[*rung] {
                    assert!(rungs[..i].contains(&used.as_str()), "{rung} uses {used}");
                }
            }
        }
    }
}
