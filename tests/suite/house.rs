//! The source tree keeps its shape: no file in `src/` over [`MAX_LINES`] lines, and no two
//! files in `src/` that import each other. A file's imports are the `crate::`, `super::` and
//! `self::` paths in its code (comment lines and its `#[cfg(test)] mod tests` block left
//! out; test-only files, `*tests.rs`, left out), each resolved to the file of the longest
//! module it names (the crate's root, which re-exports, counts as none); a module and its own
//! submodules may refer to each other. Fails with one line per offence.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a source file may be.
const MAX_LINES: usize = 1200;

fn src() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The module a file holds: `a/b.rs` and `a/b/mod.rs` hold `[a, b]`; `lib.rs` and `main.rs`
/// the crate's root, `[]`.
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// The `crate::`, `super::` and `self::` paths in `text`'s code: comment lines and the
/// `#[cfg(test)] mod tests` block (to the end of the file) left out.
fn paths(text: &str) -> Vec<String> {
    let code = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
    let mut out = Vec::new();
    for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
        let bytes = line.as_bytes();
        for start in ["crate::", "super::", "self::"].iter().flat_map(|k| line.match_indices(k).map(|(i, _)| i)) {
            // A whole word only (not `my_crate::`).
            if start > 0 && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_') {
                continue;
            }
            let end = line[start..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .map_or(line.len(), |e| start + e);
            out.push(line[start..end].trim_end_matches(':').to_string());
        }
    }
    out
}

/// The module of `modules` that `path`, written in module `cur`, names: the longest prefix
/// of the path that is a file's module.
fn resolve(cur: &[String], path: &str, modules: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    let mut parts = path.split("::").filter(|p| !p.is_empty());
    let mut full: Vec<String> = match parts.next()? {
        "crate" => Vec::new(),
        "self" => cur.to_vec(),
        "super" => cur[..cur.len().saturating_sub(1)].to_vec(),
        _ => return None,
    };
    let mut rest: Vec<&str> = parts.collect();
    while rest.first() == Some(&"super") {
        full.pop();
        rest.remove(0);
    }
    full.extend(rest.iter().map(|p| p.to_string()));
    (0..=full.len()).rev().map(|k| full[..k].to_vec()).find(|m| modules.contains(m))
}

#[test]
fn source_files_stay_short_and_import_no_cycles() {
    let root = src();
    let mut files = Vec::new();
    crate::docs::files_under(&root, &["rs"], &mut files);
    files.sort();
    assert!(files.len() > 100, "src/ read: {} files", files.len());
    let mut problems = Vec::new();
    let mut modules = BTreeMap::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("a readable source file");
        let rel = f.strip_prefix(&root).expect("under src/").to_path_buf();
        let lines = text.lines().count();
        if lines > MAX_LINES {
            problems.push(format!("src/{}: {lines} lines, more than {MAX_LINES}", rel.display()));
        }
        // Test-only files are left out, and so is the binary's root (the library's is `lib.rs`).
        if !rel.to_string_lossy().ends_with("tests.rs") && rel != Path::new("main.rs") {
            modules.insert(module_of(&rel), (rel, text));
        }
    }
    let names: BTreeSet<Vec<String>> = modules.keys().cloned().collect();
    let mut imports: BTreeMap<&Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (m, (_, text)) in &modules {
        for p in paths(text) {
            // The crate's root re-exports; naming it is no import of a file's code.
            if let Some(t) = resolve(m, &p, &names).filter(|t| t != m && !t.is_empty()) {
                imports.entry(m).or_default().insert(t);
            }
        }
    }
    for (a, targets) in &imports {
        for b in targets.iter().filter(|b| a < b) {
            let nested = a.starts_with(b) || b.starts_with(a);
            if !nested && imports.get(b).is_some_and(|back| back.contains(*a)) {
                problems.push(format!(
                    "src/{} and src/{} import each other",
                    modules[*a].0.display(),
                    modules[b].0.display()
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The check sees an import in each direction, resolves `super::` and `self::`, and leaves
/// out comments, test blocks and a module's own submodules.
#[test]
fn the_check_reads_paths_as_modules() {
    let names: BTreeSet<Vec<String>> =
        [vec![], vec!["a".into()], vec!["a".into(), "b".into()], vec!["c".into()]].into_iter().collect();
    let m = |s: &[&str]| s.iter().map(|p| p.to_string()).collect::<Vec<_>>();
    let text = "use crate::c::X;\n// use crate::a::Y;\nfn f() { super::g(); self::b::h(); }\n#[cfg(test)]\nmod tests { use crate::a::Z; }\n";
    assert_eq!(paths(text), vec!["crate::c::X", "super::g", "self::b::h"]);
    assert_eq!(resolve(&m(&["a"]), "crate::c::X", &names), Some(m(&["c"])));
    assert_eq!(resolve(&m(&["a", "b"]), "super::super::c::X", &names), Some(m(&["c"])));
    assert_eq!(resolve(&m(&["a"]), "self::b::h", &names), Some(m(&["a", "b"])));
    assert_eq!(resolve(&m(&["a"]), "crate::nowhere::f", &names), Some(m(&[])));
    assert_eq!(module_of(Path::new("a/b/mod.rs")), m(&["a", "b"]));
    assert_eq!(module_of(Path::new("lib.rs")), m(&[]));
}
