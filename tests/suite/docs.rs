//! The documentation's cross-references resolve. Fails with one line per problem, naming
//! the file, the line and the broken reference, when
//! - a relative markdown link in `README.md` or `docs/**/*.md` points to a file that does
//!   not exist, or its `#anchor` is not a heading of the target (GitHub's slugs);
//! - a doc, a source comment, a test or a scene (`README.md`, `docs/`, `src/`, `tests/`,
//!   `benches/`, `examples/`, `scenarios/`) names a project file (`docs/x.md`,
//!   `src/x.rs`, `tests/x.rs`, `scenarios/x.toml`, ...) that does not exist, or cites a
//!   section of a doc that is not one of its headings. Sections are cited as
//!   `docs/x.md#anchor`, `docs/x.md, "Heading"` (the quotes may wrap onto the next comment
//!   line) or `docs/x.md, section Heading` (the name runs to the next `)`, `;`, `,`, `:` or
//!   full stop);
//! - the specification outside this repository is named (its file name is the project's
//!   model document's in capitals, see `SPEC` below): the project's own is `docs/model.md`.
//!   `docs/model.md` alone may name it, in the marked form `SPEC_MARKED`;
//! - a markdown file (`README.md`, `docs/`) cites the project's history instead of stating
//!   what is true now: an issue number (`issue 11`, `issue #5`, `#5`), a commit hash (7 to
//!   40 hexadecimal digits with a digit and a letter other than `e`, so that no decimal
//!   exponent qualifies) or a branch name (`h-` and a word). The history is `CHANGELOG.md`,
//!   which is not scanned.
//!
//! ATX headings (`# Heading`) outside fenced code count; a heading's anchor is GitHub's
//! slug of its text (inline code and emphasis marks removed, lower case, punctuation other
//! than `-` and `_` dropped, spaces to `-`, `-1`, `-2`, ... on repeats). This file is not
//! scanned itself (it spells broken references on purpose).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The external specification's file name (written in two pieces so that this file holds
/// no reference to it).
const SPEC: &str = concat!("MODEL", ".md");
/// The one form `docs/model.md` may use to name it.
const SPEC_MARKED: &str = concat!("`MODEL", ".md` (outside this repository)");
/// Directories whose files are scanned for references, and the extensions scanned.
const SCANNED: &[(&str, &[&str])] = &[
    ("docs", &["md"]),
    ("src", &["rs"]),
    ("tests", &["rs"]),
    ("benches", &["rs"]),
    ("examples", &["rs"]),
    ("scenarios", &["toml"]),
];
/// Directories of the project whose files may be named in references.
const ROOTS: &[&str] = &["docs", "src", "tests", "benches", "examples", "scenarios"];
/// Extensions of named files that are checked.
const NAMED_EXTENSIONS: &[&str] = &["md", "rs", "toml"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir` (recursively) whose extension is one of `exts`, appended to `out`
/// (an unreadable directory adds none). Also the source tree's check (`house`).
pub(crate) fn files_under(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files_under(&p, exts, out);
        } else if p.extension().and_then(|x| x.to_str()).is_some_and(|x| exts.contains(&x)) {
            out.push(p);
        }
    }
}

/// The files scanned, relative to the root: `README.md`, then every file under
/// [`SCANNED`], sorted.
fn scanned_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![root.join("README.md")];
    for (dir, exts) in SCANNED {
        files_under(&root.join(dir), exts, &mut files);
    }
    let this = root.join(file!());
    let mut rel: Vec<PathBuf> =
        files.into_iter().filter(|p| *p != this).map(|p| p.strip_prefix(root).unwrap().to_path_buf()).collect();
    rel.sort();
    rel
}

/// One problem: where, and what.
struct Problem {
    file: PathBuf,
    line: usize,
    what: String,
}

/// The text of a file with a line number for every byte offset.
struct Text {
    text: String,
    /// Byte offset of the start of each line.
    starts: Vec<usize>,
}

impl Text {
    fn new(text: String) -> Self {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        Text { text, starts }
    }
    /// 1-based line of byte offset `at`.
    fn line(&self, at: usize) -> usize {
        self.starts.partition_point(|&s| s <= at)
    }
}

/// Lines of a markdown file outside fenced code blocks, with their 1-based numbers.
fn prose_lines(md: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<&str> = None;
    let mut out = Vec::new();
    for (i, line) in md.lines().enumerate() {
        let t = line.trim_start();
        let marker = ["```", "~~~"].into_iter().find(|m| t.starts_with(m));
        match (fence, marker) {
            (None, Some(m)) => fence = Some(m),
            (Some(f), Some(m)) if f == m => fence = None,
            (None, None) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// `text` with inline code spans' backticks removed (their content kept) and emphasis
/// marks (`*`) outside code dropped: the text GitHub renders, for slugs.
fn rendered(text: &str) -> String {
    let mut out = String::new();
    let mut in_code = false;
    for c in text.chars() {
        match c {
            '`' => in_code = !in_code,
            '*' if !in_code => {}
            c => out.push(c),
        }
    }
    // Links render as their text.
    let mut s = String::new();
    let mut rest = out.as_str();
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find("](").map(|c| open + c) else { break };
        let Some(end) = rest[close..].find(')').map(|e| close + e) else { break };
        s.push_str(&rest[..open]);
        s.push_str(&rest[open + 1..close]);
        rest = &rest[end + 1..];
    }
    s.push_str(rest);
    s
}

/// GitHub's anchor for a heading's text (before de-duplication).
fn slug(heading: &str) -> String {
    rendered(heading.trim())
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The headings of a markdown text: (text, anchor) in order, anchors de-duplicated.
fn headings(md: &str) -> Vec<(String, String)> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = Vec::new();
    for (_, line) in prose_lines(md) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with([' ', '\t']) {
            continue;
        }
        let text = line[hashes..].trim().trim_end_matches('#').trim().to_string();
        let base = slug(&text);
        let n = seen.entry(base.clone()).or_insert(0);
        let anchor = if *n == 0 { base.clone() } else { format!("{base}-{n}") };
        *n += 1;
        out.push((text, anchor));
    }
    out
}

/// The project's markdown files' headings, read on demand.
struct Docs {
    root: PathBuf,
    cache: BTreeMap<PathBuf, Option<Vec<(String, String)>>>,
}

impl Docs {
    /// The headings of `path` (relative to the root), or `None` if it is not a file.
    fn headings(&mut self, path: &Path) -> Option<&[(String, String)]> {
        let root = &self.root;
        self.cache
            .entry(path.to_path_buf())
            .or_insert_with(|| std::fs::read_to_string(root.join(path)).ok().map(|t| headings(&t)))
            .as_deref()
    }

    /// Checks that `doc` has a heading with anchor `anchor`; returns the problem if not.
    fn anchor_problem(&mut self, doc: &Path, anchor: &str) -> Option<String> {
        let hs = self.headings(doc)?;
        if hs.iter().any(|(_, a)| a == anchor) {
            return None;
        }
        let list: Vec<String> = hs.iter().map(|(_, a)| format!("#{a}")).collect();
        Some(format!("{} has no heading with anchor #{anchor} (its anchors: {})", doc.display(), list.join(" ")))
    }

    /// Checks that `doc` has the heading `title` (compared by anchor).
    fn section_problem(&mut self, doc: &Path, title: &str) -> Option<String> {
        let hs = self.headings(doc)?;
        let want = slug(title);
        if hs.iter().any(|(t, _)| slug(t) == want) {
            return None;
        }
        let list: Vec<String> = hs.iter().map(|(t, _)| format!("\"{t}\"")).collect();
        Some(format!("{} has no heading \"{title}\" (its headings: {})", doc.display(), list.join(", ")))
    }
}

/// Normalises `a/./b/../c` to `a/c` (no file-system access); `None` if it leaves the root.
fn normalise(p: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            c => out.push(c),
        }
    }
    Some(out)
}

/// The inline links `[text](target)` and images of a line (outside code spans), and the
/// target of a reference definition `[label]: target`.
fn link_targets(line: &str) -> Vec<String> {
    let mut code_free = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
            code_free.push('`');
        } else {
            code_free.push(if in_code { 'x' } else { c });
        }
    }
    let mut out = Vec::new();
    let t = code_free.trim_start();
    if t.starts_with('[') {
        if let Some(i) = t.find("]:") {
            if !t[..i].contains("](") {
                out.push(t[i + 2..].split_whitespace().next().unwrap_or("").to_string());
                return out;
            }
        }
    }
    let mut rest = code_free.as_str();
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        // The target runs to the matching parenthesis; a title follows a space.
        let mut depth = 0usize;
        let mut end = after.len();
        for (j, c) in after.char_indices() {
            match c {
                '(' => depth += 1,
                ')' if depth == 0 => {
                    end = j;
                    break;
                }
                ')' => depth -= 1,
                _ => {}
            }
        }
        let target = after[..end].split_whitespace().next().unwrap_or("");
        out.push(target.trim_start_matches('<').trim_end_matches('>').to_string());
        rest = &after[end.min(after.len())..];
    }
    out
}

/// Minimal percent-decoding of a link target (`%20` and the like).
fn percent_decoded(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&s[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Links of the markdown files.
fn check_links(file: &Path, text: &str, docs: &mut Docs, problems: &mut Vec<Problem>) {
    let dir = file.parent().unwrap_or(Path::new(""));
    for (line, content) in prose_lines(text) {
        for target in link_targets(content) {
            let mut problem = |what: String| problems.push(Problem { file: file.to_path_buf(), line, what });
            if target.is_empty() {
                problem("a link with an empty target".into());
                continue;
            }
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() {
                Some(file.to_path_buf())
            } else if path.starts_with('/') {
                normalise(Path::new(path.trim_start_matches('/')))
            } else {
                normalise(&dir.join(percent_decoded(path)))
            };
            let Some(resolved) = resolved.filter(|p| docs.root.join(p).exists()) else {
                problem(format!("link ({target}): {} does not exist", dir.join(path).display()));
                continue;
            };
            let Some(anchor) = anchor else { continue };
            if resolved.extension().is_some_and(|e| e == "md") {
                if let Some(p) = docs.anchor_problem(&resolved, &percent_decoded(anchor)) {
                    problem(format!("link ({target}): {p}"));
                }
            } else if !is_line_anchor(anchor) {
                problem(format!(
                    "link ({target}): #{anchor} is not a line anchor (#L12 or #L12-L20) of a non-markdown file"
                ));
            }
        }
    }
}

fn is_line_anchor(a: &str) -> bool {
    let line = |s: &str| s.strip_prefix('L').is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
    match a.split_once('-') {
        Some((x, y)) => line(x) && line(y),
        None => line(a),
    }
}

/// Skips whitespace and comment markers (`//!`, `///`, `//`, `#`) at line starts.
fn skip_layout(s: &str) -> &str {
    let mut s = s;
    loop {
        let t = s.trim_start_matches([' ', '\t']);
        if let Some(after) = t.strip_prefix('\n') {
            let after = after.trim_start_matches([' ', '\t']);
            s = after
                .strip_prefix("//!")
                .or_else(|| after.strip_prefix("///"))
                .or_else(|| after.strip_prefix("//"))
                .or_else(|| after.strip_prefix('#'))
                .unwrap_or(after);
            continue;
        }
        return t;
    }
}

/// `s` with line breaks and the comment markers after them turned into single spaces.
fn joined(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while let Some(i) = rest.find('\n') {
        out.push_str(rest[..i].trim_end());
        out.push(' ');
        rest = skip_layout(&rest[i..]);
    }
    out.push_str(rest);
    out
}

/// The section cited right after a doc path, if any: `#anchor` (given separately), then
/// `, "Heading"`, `, section "Heading"` or `, section Heading` (the comma optional before
/// `section`).
fn cited_section(after: &str) -> Option<String> {
    let s = after.strip_prefix('`').unwrap_or(after);
    let (s, comma) = match s.strip_prefix(',') {
        Some(rest) => (rest, true),
        None => (s, false),
    };
    let s = skip_layout(s);
    let (s, keyword) = match s.strip_prefix("section ") {
        Some(rest) => (skip_layout(rest), true),
        None => (s, false),
    };
    if !(comma || keyword) {
        return None;
    }
    if let Some(q) = s.strip_prefix('"') {
        let end = q.find('"')?;
        return Some(joined(&q[..end]));
    }
    if !keyword {
        return None;
    }
    // An unquoted name: to the next `)`, `;`, `,`, `:`, a full stop before a space or the
    // end of the line.
    let line = s.lines().next().unwrap_or("");
    let mut end = line.len();
    for (i, c) in line.char_indices() {
        let stop = match c {
            ')' | ';' | ',' | ':' => true,
            '.' => line[i + 1..].starts_with(' ') || i + 1 == line.len(),
            _ => false,
        };
        if stop {
            end = i;
            break;
        }
    }
    Some(line[..end].trim().trim_matches('`').to_string())
}

/// Paths of project files named in `text`, with the text that follows each.
fn named_paths(text: &str) -> Vec<(usize, &str, &str)> {
    let mut out = Vec::new();
    for root in ROOTS {
        let needle = format!("{root}/");
        for (at, _) in text.match_indices(&needle) {
            // A path of the project, not part of a longer path or word.
            let before = text[..at].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || matches!(c, '/' | '.' | '_' | '-' | '$' | '{')) {
                continue;
            }
            // A markdown link's target is checked as a link.
            if text[..at].ends_with("](") {
                continue;
            }
            let len = text[at..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '/' | '.' | '_' | '-')))
                .unwrap_or(text.len() - at);
            let path = text[at..at + len].trim_end_matches('.');
            out.push((at, path, &text[at + path.len()..]));
        }
    }
    out.sort_by_key(|&(at, _, _)| at);
    out
}

/// References in any scanned file: named files, cited sections, the external spec.
fn check_references(file: &Path, text: &Text, docs: &mut Docs, problems: &mut Vec<Problem>) {
    let t = &text.text;
    for (at, path, after) in named_paths(t) {
        let line = text.line(at);
        let mut problem = |what: String| problems.push(Problem { file: file.to_path_buf(), line, what });
        let ext = Path::new(path).extension().and_then(|e| e.to_str()).unwrap_or("");
        if !NAMED_EXTENSIONS.contains(&ext) || after.starts_with('{') || after.starts_with('*') {
            continue;
        }
        if !docs.root.join(path).is_file() {
            problem(format!("{path} does not exist"));
            continue;
        }
        if ext != "md" {
            continue;
        }
        let (anchor, after) = match after.strip_prefix('#') {
            Some(a) => {
                let len = a.find(|c: char| !(c.is_alphanumeric() || matches!(c, '-' | '_'))).unwrap_or(a.len());
                (Some(&a[..len]), &a[len..])
            }
            None => (None, after),
        };
        if let Some(a) = anchor {
            if let Some(p) = docs.anchor_problem(Path::new(path), a) {
                problem(format!("{path}#{a}: {p}"));
            }
        }
        if let Some(title) = cited_section(after) {
            if let Some(p) = docs.section_problem(Path::new(path), &title) {
                problem(format!("{path}, \"{title}\": {p}"));
            }
        }
    }
    let allowed = file == Path::new("docs/model.md");
    for (at, _) in t.match_indices(SPEC) {
        let marked = t[..at].ends_with('`') && t[at - 1..].starts_with(SPEC_MARKED);
        if !(allowed && marked) {
            problems.push(Problem {
                file: file.to_path_buf(),
                line: text.line(at),
                what: format!(
                    "{SPEC} is the specification outside this repository; cite docs/model.md (a heading: docs/model.md, \"Equations\")"
                ),
            });
        }
    }
}

/// Issue numbers, commit hashes and branch names in `text`: `(byte offset, what)`.
fn history_marks(text: &str) -> Vec<(usize, String)> {
    let b = text.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts_token = i == 0 || !(word(b[i - 1]) || matches!(b[i - 1], b'-' | b'.' | b'/'));
        if !starts_token {
            i += 1;
            continue;
        }
        let token_len = b[i..].iter().take_while(|&&c| word(c)).count();
        // An ASCII word starts on a character boundary; anything else is no token.
        let token = if token_len > 0 { &text[i..i + token_len] } else { "" };
        let digits_after = |from: usize| b[from..].iter().take_while(|c| c.is_ascii_digit()).count();
        if token.eq_ignore_ascii_case("issue") || token.eq_ignore_ascii_case("issues") {
            let mut j = i + token_len;
            if b.get(j) == Some(&b' ') {
                j += 1;
            }
            if b.get(j) == Some(&b'#') {
                j += 1;
            }
            let n = digits_after(j);
            if n > 0 {
                out.push((i, format!("an issue number ({})", &text[i..j + n])));
                i = j + n;
                continue;
            }
        } else if b[i] == b'#' && i > 0 && matches!(b[i - 1], b' ' | b'(') {
            let n = digits_after(i + 1);
            // Not an anchor such as `#1-units`.
            if n > 0 && !b.get(i + 1 + n).is_some_and(|&c| word(c) || c == b'-') {
                out.push((i, format!("an issue number ({})", &text[i..i + 1 + n])));
            }
        } else if token == "h" && b.get(i + 1) == Some(&b'-') {
            let n = b[i + 2..].iter().take_while(|c| c.is_ascii_lowercase()).count();
            if n > 0 && !b.get(i + 2 + n).is_some_and(|&c| word(c)) {
                out.push((i, format!("a branch name ({})", &text[i..i + 2 + n])));
            }
        } else if (7..=40).contains(&token_len)
            && token.bytes().all(|c| matches!(c, b'0'..=b'9' | b'a'..=b'f'))
            && token.bytes().any(|c| c.is_ascii_digit())
            && token.bytes().any(|c| matches!(c, b'a'..=b'd' | b'f'))
            && !b.get(i + token_len).is_some_and(|&c| matches!(c, b'.' | b'-' | b'+'))
        {
            out.push((i, format!("a commit hash ({token})")));
        }
        i += token_len.max(1);
    }
    out
}

/// Every problem of the project's cross-references, sorted.
fn problems(root: &Path) -> Vec<Problem> {
    let mut docs = Docs { root: root.to_path_buf(), cache: BTreeMap::new() };
    let mut problems = Vec::new();
    for file in scanned_files(root) {
        let text = std::fs::read_to_string(root.join(&file)).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let text = Text::new(text);
        if file.extension().is_some_and(|e| e == "md") {
            check_links(&file, &text.text, &mut docs, &mut problems);
            for (at, what) in history_marks(&text.text) {
                let what = format!("{what}: history belongs in CHANGELOG.md, docs state what is true now");
                problems.push(Problem { file: file.clone(), line: text.line(at), what });
            }
        }
        check_references(&file, &text, &mut docs, &mut problems);
    }
    problems.sort_by(|a, b| (&a.file, a.line, &a.what).cmp(&(&b.file, b.line, &b.what)));
    problems
}

#[test]
fn every_cross_reference_resolves() {
    let problems = problems(&root());
    let report: Vec<String> = problems.iter().map(|p| format!("{}:{}: {}", p.file.display(), p.line, p.what)).collect();
    assert!(report.is_empty(), "{} broken cross-references:\n{}\n", report.len(), report.join("\n"));
}

// The checker's own pieces, against known answers.

#[test]
fn slugs_follow_github() {
    for (heading, anchor) in [
        ("The letter's fixed-step scheme", "the-letters-fixed-step-scheme"),
        ("Fig. 2: velocity sweep", "fig-2-velocity-sweep"),
        (
            "`[junctions]`: the junction population and its kinetics",
            "junctions-the-junction-population-and-its-kinetics",
        ),
        ("One step, from `t_n` to `t_{n+1} = (n + 1) dt`", "one-step-from-t_n-to-t_n1--n--1-dt"),
        ("Branch `Separated`: `M = 0`, or real roots", "branch-separated-m--0-or-real-roots"),
        ("Temperature trend (weak bonds)", "temperature-trend-weak-bonds"),
        ("**Bold** and [a link](x.md)", "bold-and-a-link"),
        ("Dormand–Prince 8(5,3)", "dormandprince-853"),
    ] {
        assert_eq!(slug(heading), anchor, "{heading}");
    }
    let hs = headings("# A\n\n## Notes\n```\n# not a heading\n```\n### Notes\n#nospace\n## Notes ##\n");
    let anchors: Vec<&str> = hs.iter().map(|(_, a)| a.as_str()).collect();
    assert_eq!(anchors, ["a", "notes", "notes-1", "notes-2"]);
}

#[test]
fn links_and_citations_are_found() {
    assert_eq!(
        link_targets("see [`a`](a.md#x), ![i](f/i.svg \"title\") and `[not](a link)`, [p](x(1).md)"),
        ["a.md#x", "f/i.svg", "x(1).md"]
    );
    assert_eq!(link_targets("[ref]: ../src/lib.rs"), ["../src/lib.rs"]);
    assert_eq!(cited_section(", \"Long runs\")"), Some("Long runs".into()));
    assert_eq!(cited_section("`, \"The fixed-step\n//! engine\"; more"), Some("The fixed-step engine".into()));
    assert_eq!(cited_section("`, section Observables): over"), Some("Observables".into()));
    assert_eq!(cited_section(", section `Regime criterion`."), Some("Regime criterion".into()));
    assert_eq!(cited_section("`, `tests/x.rs`"), None);
    assert_eq!(cited_section(") for the rest"), None);
    assert_eq!(cited_section("\", \"README.md\"]"), None, "a string literal's closing quote");
    assert_eq!(cited_section(" section Equations, item 6"), Some("Equations".into()));
    let text = "see docs/a.md#b, and (src/x/y.rs) but not ../src/z.rs or foo/docs/q.md; tests/{a,b}.rs";
    let found: Vec<&str> = named_paths(text).into_iter().map(|(_, p, _)| p).collect();
    assert_eq!(found, ["docs/a.md", "src/x/y.rs", "tests/"]);
}

#[test]
fn history_marks_are_found() {
    let text = "issue 11's scene; Issue #5 item 1; Dormand–Prince ±0.1 µs; see (#12) and #3, \
                commit `993d295` and 6c37857; branch h-plate, `h-engine`. Not: 1.0e-13, \
                9.094947017729282e-13, 1234567, deadbeef, [a](#fig-1), [b](#2-units), #L12, x#5, \
                abc1234def, issues, with-h-bar, 3e10000, f(#x)";
    let found: Vec<String> = history_marks(text).into_iter().map(|(_, w)| w).collect();
    assert_eq!(
        found,
        [
            "an issue number (issue 11)",
            "an issue number (Issue #5)",
            "an issue number (#12)",
            "an issue number (#3)",
            "a commit hash (993d295)",
            "a commit hash (6c37857)",
            "a branch name (h-plate)",
            "a branch name (h-engine)",
            "a commit hash (abc1234def)",
        ]
    );
}

#[test]
fn broken_references_are_reported_with_file_and_line() {
    // A small project with one of each problem: the check must find exactly these.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir_all(d.join("docs")).unwrap();
    std::fs::create_dir_all(d.join("src")).unwrap();
    let model = format!("# Model\n\nRead from {SPEC_MARKED}.\n\n## Equations\n\n```\n## Fenced\n```\n");
    std::fs::write(d.join("docs/model.md"), model).unwrap();
    std::fs::write(
        d.join("README.md"),
        "# R\n\n[ok](docs/model.md#equations) [bad anchor](docs/model.md#fenced)\n[gone](docs/none.md)\n\
         [self](#r) [self bad](#nope)\n```\n[in code](nowhere.md)\n```\n",
    )
    .unwrap();
    let lib = format!(
        "//! See docs/model.md, \"Equations\" and docs/model.md, \"No\n//! such\" and\n\
         //! docs/model.md#units and `docs/model.md`, section Equations: fine; src/gone.rs.\n\
         /// {SPEC} item 6.\n"
    );
    std::fs::write(d.join("src/lib.rs"), lib).unwrap();
    let found: Vec<String> =
        problems(d).iter().map(|p| format!("{}:{}: {}", p.file.display(), p.line, p.what)).collect();
    let expect = [
        "README.md:3: link (docs/model.md#fenced): docs/model.md has no heading with anchor #fenced (its anchors: #model #equations)",
        "README.md:4: link (docs/none.md): docs/none.md does not exist",
        "README.md:5: link (#nope): README.md has no heading with anchor #nope (its anchors: #r)",
        "src/lib.rs:1: docs/model.md, \"No such\": docs/model.md has no heading \"No such\" (its headings: \"Model\", \"Equations\")",
        "src/lib.rs:3: docs/model.md#units: docs/model.md has no heading with anchor #units (its anchors: #model #equations)",
        "src/lib.rs:3: src/gone.rs does not exist",
    ];
    let spec_line = format!(
        "src/lib.rs:4: {SPEC} is the specification outside this repository; cite docs/model.md (a heading: docs/model.md, \"Equations\")"
    );
    let mut expect: Vec<String> = expect.iter().map(|s| s.to_string()).collect();
    expect.push(spec_line);
    assert_eq!(found, expect);
}
