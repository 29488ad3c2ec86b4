//! The library's modules import one way. Each top-level module of `src/` belongs to a layer,
//! and a module may use only modules of the layers below its own (docs/architecture.md
//! draws them); and no two source files reach each other through their imports (a file
//! circle), inside a layer either.
//!
//! An import is any path `crate::a::b…` or `super::…` in a file's code (not in its comments
//! nor its unit tests), `use` trees with braces expanded; it points at the file that defines
//! the module it names (`src/a/b.rs`, `src/a/b/mod.rs`, or the nearest parent that exists).
//! Both checks are shown to reject a deliberately wrong tree of their own.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The layers, top first: a module may use the modules of later layers only. The binary's
/// `cli/` sits above them all.
const LAYERS: &[&[&str]] = &[
    &["check", "report"],
    &["shard"],
    &["integrators"],
    &["genetic"],
    &["guiding"],
    &["film"],
    &["path"],
    &["sampling"],
    &["scene"],
    &["accel"],
    &["math"],
    &["image"],
    &["progress", "settings_table"],
];

/// A crate's source files: path relative to `src/` (with `/`), and text.
type Files = BTreeMap<String, String>;

fn read_tree(dir: &Path, prefix: &str, files: &mut Files) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            read_tree(&path, &format!("{prefix}{name}/"), files);
        } else if name.ends_with(".rs") {
            files.insert(
                format!("{prefix}{name}"),
                std::fs::read_to_string(&path).unwrap(),
            );
        }
    }
}

/// The library's files (the binary's `main.rs` and `cli/` are above every layer).
fn library() -> Files {
    let mut files = Files::new();
    read_tree(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        "",
        &mut files,
    );
    files.retain(|f, _| f != "main.rs" && !f.starts_with("cli/"));
    files
}

/// The module path of file `file` (`a/b.rs` and `a/b/mod.rs` are `[a, b]`).
fn module_of(file: &str) -> Vec<String> {
    let mut parts: Vec<String> = file
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

/// Every path that starts with `crate` or `super` in `text`, `use` trees expanded, as
/// segments (`["crate", "a", "b"]`).
fn paths(text: &str) -> Vec<Vec<String>> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let boundary = i == 0
            || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_' || chars[i - 1] == ':');
        let starts = ["crate::", "super::"].iter().any(|s| text_at(&chars, i, s));
        if boundary && starts {
            let (mut found, end) = tree(&chars, i, Vec::new());
            out.append(&mut found);
            i = end.max(i + 1);
        } else {
            i += 1;
        }
    }
    out
}

fn text_at(chars: &[char], i: usize, s: &str) -> bool {
    s.chars()
        .enumerate()
        .all(|(k, c)| chars.get(i + k) == Some(&c))
}

/// The paths of the use tree at `chars[i..]` under `prefix`, and where it ends.
fn tree(chars: &[char], mut i: usize, mut prefix: Vec<String>) -> (Vec<Vec<String>>, usize) {
    loop {
        let start = i;
        while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
            i += 1;
        }
        if i > start {
            prefix.push(chars[start..i].iter().collect());
        }
        if text_at(chars, i, "::{") {
            let mut found = Vec::new();
            i += 3;
            loop {
                while i < chars.len() && (chars[i].is_whitespace() || chars[i] == ',') {
                    i += 1;
                }
                if i >= chars.len() || chars[i] == '}' {
                    break;
                }
                let (mut inner, end) = tree(chars, i, prefix.clone());
                found.append(&mut inner);
                i = end;
            }
            if found.is_empty() {
                found.push(prefix);
            }
            return (found, i + 1);
        }
        if text_at(chars, i, "::") {
            i += 2;
            continue;
        }
        // `self` in a group names the prefix itself.
        if prefix.last().is_some_and(|s| s == "self") {
            prefix.pop();
        }
        return (vec![prefix], i);
    }
}

/// The module a path in the file of module `here` names, from the crate's root.
fn resolve(here: &[String], path: &[String]) -> Option<Vec<String>> {
    let (mut base, rest) = match path.first()?.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "super" => {
            let mut base = here.to_vec();
            let mut rest = path;
            while rest.first().is_some_and(|s| s == "super") {
                base.pop()?;
                rest = &rest[1..];
            }
            (base, rest)
        }
        _ => return None,
    };
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The file that defines module `module` or its nearest parent that has one.
fn file_of(modules: &BTreeMap<Vec<String>, String>, module: &[String]) -> Option<String> {
    (1..=module.len())
        .rev()
        .find_map(|n| modules.get(&module[..n]).cloned())
}

/// A file's code: without its comments (a doc link is no import), and without its unit
/// tests (`#[cfg(test)] mod tests { … }`, which end the file: they are not part of the
/// module, and their `super::` names the file itself).
fn code(text: &str) -> String {
    let end = text.match_indices("#[cfg(test)]").find_map(|(i, tag)| {
        let next = text[i + tag.len()..].trim_start();
        let next = next
            .strip_prefix("pub(crate) ")
            .or(next.strip_prefix("pub "))
            .unwrap_or(next);
        next.starts_with("mod ").then_some(i)
    });
    let lines = text[..end.unwrap_or(text.len())].lines();
    lines
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every import edge between different files of `files`.
fn edges(files: &Files) -> BTreeSet<(String, String)> {
    let modules: BTreeMap<Vec<String>, String> =
        files.keys().map(|f| (module_of(f), f.clone())).collect();
    let mut out = BTreeSet::new();
    for (file, text) in files {
        let here = module_of(file);
        for path in paths(&code(text)) {
            let target = resolve(&here, &path).and_then(|m| file_of(&modules, &m));
            if let Some(target) = target.filter(|t| t != file) {
                out.insert((file.clone(), target));
            }
        }
    }
    out
}

/// The top-level module of a file (`a/b.rs` and `a.rs`: `a`).
fn top(file: &str) -> &str {
    file.split('/')
        .next()
        .unwrap_or(file)
        .trim_end_matches(".rs")
}

/// Edges that go up or sideways between the layers of [`LAYERS`], and edges from or to a
/// module that no layer names.
fn against_the_layers(edges: &BTreeSet<(String, String)>) -> Vec<String> {
    let layer = |m: &str| LAYERS.iter().position(|l| l.contains(&m));
    let mut out = Vec::new();
    for (a, b) in edges {
        let (ma, mb) = (top(a), top(b));
        if ma == mb || ma == "lib" {
            continue;
        }
        match (layer(ma), layer(mb)) {
            (Some(la), Some(lb)) if lb > la => {}
            (Some(_), Some(_)) => out.push(format!("{a} -> {b}: `{ma}` may not use `{mb}`")),
            _ => out.push(format!(
                "{a} -> {b}: a module in no layer (add it to LAYERS)"
            )),
        }
    }
    out
}

/// The groups of two or more files that reach each other (Tarjan's strongly connected
/// components), each sorted.
fn circles(edges: &BTreeSet<(String, String)>) -> Vec<Vec<String>> {
    let mut next: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
        next.entry(b).or_default();
    }
    let nodes: Vec<&str> = next.keys().copied().collect();
    let index_of: BTreeMap<&str, usize> = nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let n = nodes.len();
    let (mut index, mut low, mut on) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut counter, mut out) = (Vec::new(), 0, Vec::new());
    // Iterative Tarjan: (node, next successor to visit).
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        let mut work = vec![(root, 0)];
        while let Some(&mut (v, ref mut k)) = work.last_mut() {
            if *k == 0 && index[v] == usize::MAX {
                index[v] = counter;
                low[v] = counter;
                counter += 1;
                stack.push(v);
                on[v] = true;
            }
            let succ = &next[nodes[v]];
            if *k < succ.len() {
                let w = index_of[succ[*k]];
                *k += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(parent, _)) = work.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut group = Vec::new();
                while let Some(w) = stack.pop() {
                    on[w] = false;
                    group.push(nodes[w].to_string());
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 {
                    group.sort();
                    out.push(group);
                }
            }
        }
    }
    out
}

#[test]
fn modules_import_one_way() {
    let files = library();
    assert!(files.len() > 50, "read only {} files", files.len());
    let edges = edges(&files);
    assert!(edges.len() > 100, "found only {} imports", edges.len());
    let wrong = against_the_layers(&edges);
    assert!(
        wrong.is_empty(),
        "imports against the layers:\n{}",
        wrong.join("\n")
    );
    let found = circles(&edges);
    let tied: Vec<_> = (edges.iter())
        .filter(|(a, b)| found.iter().any(|c| c.contains(a) && c.contains(b)))
        .collect();
    assert!(
        found.is_empty(),
        "file circles:\n{found:#?}\nby:\n{tied:#?}"
    );
}

/// The must-reject twin: a tree with an upward import and file circles, written with brace
/// groups, `super::` and a path in code; a doc link and a unit test's `super::` are no
/// imports.
#[test]
fn a_wrong_tree_is_rejected() {
    let files: Files = [
        ("lib.rs", "pub mod film;\npub mod scene;\npub mod image;"),
        (
            "film/mod.rs",
            "mod render;\nuse crate::scene::{Camera, camera::ray};",
        ),
        ("film/render.rs", "use super::{Film, render2::X};"),
        (
            "film/render2.rs",
            "/// See [`super::render::Z`].\nfn f() { super::render::Y }",
        ),
        ("film/other.rs", "//! [`super::render::Y`]\nfn f() {}"),
        ("scene/mod.rs", "pub mod camera;"),
        ("scene/camera.rs", "use crate::film::Film;"),
        ("image/mod.rs", "fn g() { crate::image::h(); }"),
        (
            "image/png.rs",
            "#[cfg(test)]\nmod tests {\n    use super::super::Image;\n}",
        ),
    ]
    .into_iter()
    .map(|(f, t)| (f.to_string(), t.to_string()))
    .collect();
    let edges = edges(&files);
    assert!(
        edges.contains(&("film/mod.rs".into(), "scene/camera.rs".into())),
        "{edges:?}"
    );
    let wrong = against_the_layers(&edges);
    assert_eq!(
        wrong,
        ["scene/camera.rs -> film/mod.rs: `scene` may not use `film`"],
        "{edges:?}"
    );
    let found = circles(&edges);
    assert!(
        found.contains(&vec![
            "film/render.rs".to_string(),
            "film/render2.rs".to_string()
        ]),
        "{found:?}"
    );
    assert!(
        found
            .iter()
            .any(|c| c.contains(&"scene/camera.rs".to_string())),
        "{found:?}"
    );
}
