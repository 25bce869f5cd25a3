//! Issue 36 §1: the modules point one way, as DESIGN.md §10 draws the layers. Every
//! `crate::<module>` path in the library's non-test code (a file's `#[cfg(test)] mod
//! tests` block and comments stripped; `use crate::{a, b}` groups read too) must name a
//! module on a lower layer than the file's own, or its own. Before issue 36 two edges
//! ran up: `scene → study` (the `[sweep]` table's type) and `run → scene` (the entry
//! points and the checkpoint's source, now in `app/`). Any upward edge fails this test
//! with its file.
//!
//! Issue 49 §3 adds two rules of the files (below the layer test): no cycle between the
//! files of a crate (`no_cycle_between_files`, with [`KNOWN_CYCLES`]), and no library file
//! over 600 non-blank lines outside its tests (`no_library_file_over_the_line_limit`, with
//! [`KNOWN_LONG`]). Both lists only shrink: an entry that no longer holds fails the test.

use std::collections::BTreeSet;
use std::path::Path;

/// The layers, lowest first: a module may use its own layer's modules only if it is
/// one of them (a layer with two modules lists the lower one first, and the later one
/// may use it).
const LAYERS: &[&str] = &[
    "error",
    "limits",
    "analytic",
    "linalg",
    "solvers",
    "assembly",
    "model",
    "contact",
    "delassus",
    "integrators",
    "io",
    // above `io`: the plots read a history back with `io`'s one reader
    "plot",
    "run",
    "scene",
    "app",
    "study",
];

/// Upward edges still in the code, each with its reason (none since issue 36 moved the
/// entry points to `app/`; an entry here must be met, or the test says to remove it).
const KNOWN_UPWARD: &[(&str, &str)] = &[];

fn rank(module: &str) -> Option<usize> {
    LAYERS.iter().position(|&m| m == module)
}

/// The top-level modules a source text refers to through `crate::`.
fn references(text: &str) -> BTreeSet<String> {
    let code = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    let code: String = code
        .lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n");
    let mut out = BTreeSet::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_lowercase() || *c == '_' || c.is_ascii_digit())
            .collect()
    };
    for (i, _) in code.match_indices("crate::") {
        let rest = &code[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let group = &group[..group.find('}').unwrap_or(group.len())];
            for item in group.split(',') {
                let name = ident(item.trim_start());
                if !name.is_empty() {
                    out.insert(name);
                }
            }
        } else {
            let name = ident(rest);
            if !name.is_empty() {
                out.insert(name);
            }
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut upward = Vec::new();
    let mut known_seen = BTreeSet::new();
    let mut checked = 0;
    for file in &files {
        let rel = file.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        // the crate roots, and the binary's modules (`cli/`, under `main.rs`: they reach
        // the library as `signorini::`, never as `crate::`)
        if module == "lib" || module == "main" || module == "cli" {
            continue;
        }
        let own = rank(&module)
            .unwrap_or_else(|| panic!("{}: module {module} is on no layer", rel.display()));
        let text = std::fs::read_to_string(file).unwrap();
        for target in references(&text) {
            if target == module {
                continue;
            }
            let Some(theirs) = rank(&target) else {
                panic!("{}: crate::{target} is on no layer", rel.display());
            };
            checked += 1;
            if theirs > own {
                if KNOWN_UPWARD.contains(&(module.as_str(), target.as_str())) {
                    known_seen.insert((module.clone(), target.clone()));
                } else {
                    upward.push(format!("{} -> crate::{target}", rel.display()));
                }
            }
        }
    }
    // the scan read the crate: every layer but the lowest uses a lower one somewhere
    assert!(
        checked > 40,
        "only {checked} edges read: the scan is broken"
    );
    assert!(
        upward.is_empty(),
        "imports that run up the layers: {upward:#?}"
    );
    // a known edge that disappeared must leave the list (so the list stays true)
    for (m, t) in KNOWN_UPWARD {
        assert!(
            known_seen.contains(&(m.to_string(), t.to_string())),
            "{m} -> {t} is gone: remove it from KNOWN_UPWARD"
        );
    }
}

/// The scanner itself: groups, nested paths and comments.
#[test]
fn references_reads_groups_paths_and_skips_comments_and_tests() {
    let text = "use crate::{linalg::X, error::Error};\nfn f() { crate::model::g(); }\n// crate::study\n#[cfg(test)]\nmod tests { use crate::scene; }\n";
    let refs: Vec<String> = references(text).into_iter().collect();
    assert_eq!(refs, ["error", "linalg", "model"]);
}

// ---------------------------------------------------------------------------------------
// Issue 49 §3: no cycle between files, and no library file over 600 lines.
//
// The module-level test above reads `crate::` paths only, so it cannot see two sibling
// files that import each other through `use super::*` (the review of 2026-12-07 found six
// such cycles). The scan below reads every file's imports (`use` trees with groups,
// aliases and `self`, `pub use` re-exports, globs, and the `crate::`/`super::`/`self::`
// and alias paths written inline in code), resolves each name to the file that defines
// it (following re-exports and globs through the module tree), and builds the edge list
// file → file. Edges between a file and its ancestors (`mod.rs` of a directory above it,
// the crate root) are left out: a directory module and its children always see each
// other through `use super::*` and `pub use child::*`. What is left must have no cycle.
//
// The resolution is lexical, not the compiler's: comments, string literals and the
// `#[cfg(test)] mod tests` blocks are blanked first; a name reached through a glob counts
// as a use only where it reads as one (a type or constant anywhere, a function where it is
// called, a module where a path continues through it), and a name after `.` (a field or a
// method) never does; a method defined in another file's `impl` block is no edge.
// ---------------------------------------------------------------------------------------

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::PathBuf;

/// The line rule: non-blank lines of a library file outside its `#[cfg(test)] mod tests`
/// block (doc comments and comments count; blank lines do not).
const MAX_LINES: usize = 600;

/// Files over [`MAX_LINES`] when this list was written, with their reason (paths from the
/// repository root). An entry that is no longer over the limit fails the test, so the list
/// only shrinks.
const KNOWN_LONG: &[(&str, &str)] = &[];

/// File cycles still in the code, each as its files (paths under the crate's source
/// directory, any order) with the reason. An entry whose files no longer form exactly that
/// cycle (a strongly connected set of files) fails the test, so the list only shrinks.
const KNOWN_CYCLES: &[(&[&str], &str)] = &[];

/// One crate of the repository whose files the cycle and line rules read.
struct CrateSrc {
    /// What the messages call it.
    name: &'static str,
    /// The directory module paths are relative to.
    dir: PathBuf,
    /// The crate root (`lib.rs`, `main.rs`).
    root: &'static str,
    /// Top-level entries of `dir` that belong to another crate rooted there.
    skip: &'static [&'static str],
}

fn crates() -> Vec<CrateSrc> {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    vec![
        CrateSrc {
            name: "signorini",
            dir: here.join("src"),
            root: "lib.rs",
            skip: &["main.rs", "cli"],
        },
        CrateSrc {
            name: "signorini (binary)",
            dir: here.join("src"),
            root: "main.rs",
            skip: &["lib.rs"],
        },
        CrateSrc {
            name: "signorini-python",
            dir: here.join("python").join("src"),
            root: "lib.rs",
            skip: &[],
        },
    ]
}

/// The crate's files with their module paths (`lib.rs` → `[]`, `a/mod.rs` → `[a]`,
/// `a/b.rs` → `[a, b]`). The binary crate holds its root and the directories its root
/// declares (`cli/`); the library everything else.
fn crate_files(c: &CrateSrc) -> Vec<(Vec<String>, PathBuf)> {
    let mut files = Vec::new();
    rust_files(&c.dir, &mut files);
    let mut out = Vec::new();
    for f in files {
        let rel = f.strip_prefix(&c.dir).unwrap();
        let parts: Vec<String> = rel
            .components()
            .map(|p| p.as_os_str().to_string_lossy().into_owned())
            .collect();
        if c.skip.contains(&parts[0].as_str()) {
            continue;
        }
        if c.root == "main.rs" && parts.len() == 1 && parts[0] != "main.rs" {
            continue;
        }
        if c.root == "main.rs" && parts.len() > 1 && parts[0] != "cli" {
            continue;
        }
        let mut module: Vec<String> = parts.clone();
        let last = module.pop().unwrap();
        if parts.len() == 1 && last == c.root {
            // the crate root
        } else if last != "mod.rs" {
            module.push(last.trim_end_matches(".rs").to_string());
        }
        out.push((module, f));
    }
    out
}

/// The text with comments and the contents of string and character literals replaced by
/// spaces (newlines kept, so line numbers hold).
fn blank_comments_and_literals(text: &str) -> String {
    let c: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    // every blanked character keeps its byte length, so offsets match the text's
    let blank = |out: &mut String, ch: char| {
        if ch == '\n' {
            out.push('\n');
        } else {
            out.extend(std::iter::repeat_n(' ', ch.len_utf8()));
        }
    };
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (next == Some('"') || next == Some('#'))
            && (i == 0 || !(c[i - 1].is_alphanumeric() || c[i - 1] == '_'))
        {
            // a raw string r"…" or r#"…"#
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
            out.push('r');
            for _ in i + 1..=j {
                out.push(' ');
            }
            i = j + 1;
            while i < c.len() {
                if c[i] == '"' && (0..hashes).all(|h| c.get(i + 1 + h) == Some(&'#')) {
                    for _ in 0..=hashes {
                        out.push(' ');
                    }
                    i += 1 + hashes;
                    break;
                }
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    blank(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' && next == Some('\\') {
            // an escaped character literal '\n', '\u{…}'
            out.push(' ');
            i += 2;
            while i < c.len() && c[i] != '\'' {
                blank(&mut out, c[i]);
                i += 1;
            }
            out.push(' ');
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' && c.get(i + 2) == Some(&'\'') {
            out.push_str("  ");
            blank(&mut out, c[i + 1]);
            i += 3;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// The byte ranges of the `#[cfg(test)] mod NAME { … }` blocks of a blanked text.
fn test_blocks(code: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    for (at, _) in code.match_indices("#[cfg(test)]") {
        let mut rest = code[at + "#[cfg(test)]".len()..].trim_start();
        // a visibility: `pub`, `pub(crate)`, `pub(super)`, `pub(in …)`
        if let Some(r) = rest.strip_prefix("pub") {
            rest = r.trim_start();
            if rest.starts_with('(') {
                rest = rest[rest.find(')').map_or(rest.len(), |k| k + 1)..].trim_start();
            }
        }
        let Some(after_mod) = rest.strip_prefix("mod ") else {
            continue;
        };
        let head = after_mod.find(['{', ';']).unwrap_or(after_mod.len());
        if after_mod.as_bytes().get(head) != Some(&b'{') {
            continue;
        }
        let open = code.len() - after_mod.len() + head;
        let mut depth = 0usize;
        let mut end = code.len();
        for (k, &b) in bytes.iter().enumerate().skip(open) {
            if b == b'{' {
                depth += 1;
            } else if b == b'}' {
                depth -= 1;
                if depth == 0 {
                    end = k + 1;
                    break;
                }
            }
        }
        out.push((at, end));
    }
    out
}

/// Non-blank lines of `text` outside its `#[cfg(test)] mod tests` block.
fn non_test_lines(text: &str) -> usize {
    let code = blank_comments_and_literals(text);
    let blocks: Vec<(usize, usize)> = test_blocks(&code)
        .into_iter()
        .filter(|&(a, _)| {
            code[a..]
                .trim_start_matches("#[cfg(test)]")
                .trim_start()
                .starts_with("mod tests")
        })
        .collect();
    let mut count = 0;
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let inside = blocks.iter().any(|&(a, b)| offset >= a && offset < b);
        if !inside && !line.trim().is_empty() {
            count += 1;
        }
        offset += line.len();
    }
    count
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

fn tokens(code: &str) -> Vec<Tok> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if c[i].is_alphabetic() || c[i] == '_' {
            let s = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let word: String = c[s..i].iter().collect();
            // `r#ident`
            out.push(Tok::Ident(word));
        } else if c[i].is_ascii_digit() {
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                if c[i] == '.' && !c.get(i + 1).is_some_and(|d| d.is_ascii_digit()) {
                    break;
                }
                i += 1;
            }
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push(Tok::PathSep);
            i += 2;
        } else if c[i].is_whitespace() {
            i += 1;
        } else if c[i] == '\'' {
            // a lifetime or label: skip its name
            i += 1;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
        } else {
            out.push(Tok::Punct(c[i]));
            i += 1;
        }
    }
    out
}

/// What a top-level item is, for how a glob-imported name may be read.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Fn,
    Type,
    Value,
}

/// One name a `use` brings in: the path it names and the name it takes (`None`: a glob).
#[derive(Clone, Debug)]
struct UseItem {
    path: Vec<String>,
    alias: Option<String>,
}

/// What one file defines and imports, read from its tokens.
struct FileScan {
    module: Vec<String>,
    file: PathBuf,
    defs: HashMap<String, Kind>,
    uses: Vec<UseItem>,
    /// Paths written in code outside `use` declarations: segments, and the token after
    /// the path.
    paths: Vec<(Vec<String>, Option<Tok>)>,
}

fn ident(t: Option<&Tok>) -> Option<&str> {
    match t {
        Some(Tok::Ident(s)) => Some(s),
        _ => None,
    }
}

/// Parses a use tree at `toks[*i..]` with the path `prefix` before it.
fn use_tree(toks: &[Tok], i: &mut usize, prefix: Vec<String>, out: &mut Vec<UseItem>) {
    let mut path = prefix;
    loop {
        match toks.get(*i) {
            Some(Tok::PathSep) => *i += 1,
            Some(Tok::Punct('*')) => {
                *i += 1;
                out.push(UseItem { path, alias: None });
                return;
            }
            Some(Tok::Punct('{')) => {
                *i += 1;
                loop {
                    match toks.get(*i) {
                        Some(Tok::Punct('}')) => {
                            *i += 1;
                            return;
                        }
                        Some(Tok::Punct(',')) => *i += 1,
                        None => return,
                        _ => use_tree(toks, i, path.clone(), out),
                    }
                }
            }
            Some(Tok::Ident(s)) => {
                let s = s.clone();
                *i += 1;
                if toks.get(*i) == Some(&Tok::PathSep) {
                    path.push(s);
                    continue;
                }
                let mut name = s.clone();
                if s != "self" {
                    path.push(s);
                } else {
                    name = path.last().cloned().unwrap_or_default();
                }
                if ident(toks.get(*i)) == Some("as") {
                    name = ident(toks.get(*i + 1)).unwrap_or("_").to_string();
                    *i += 2;
                }
                out.push(UseItem {
                    path,
                    alias: Some(name),
                });
                return;
            }
            _ => return,
        }
    }
}

const ITEM_KEYWORDS: &[(&str, Kind)] = &[
    ("fn", Kind::Fn),
    ("struct", Kind::Type),
    ("enum", Kind::Type),
    ("trait", Kind::Type),
    ("type", Kind::Type),
    ("union", Kind::Type),
    ("const", Kind::Value),
    ("static", Kind::Value),
];

fn scan_file(module: Vec<String>, file: PathBuf) -> FileScan {
    let text = std::fs::read_to_string(&file).unwrap();
    let mut code = blank_comments_and_literals(&text);
    for (a, b) in test_blocks(&code) {
        let blanked: String = code[a..b]
            .chars()
            .flat_map(|c| {
                let n = if c == '\n' { 0 } else { c.len_utf8() };
                (c == '\n')
                    .then_some('\n')
                    .into_iter()
                    .chain(std::iter::repeat_n(' ', n))
            })
            .collect();
        code.replace_range(a..b, &blanked);
    }
    let toks = tokens(&code);
    let mut scan = FileScan {
        module,
        file,
        defs: HashMap::new(),
        uses: Vec::new(),
        paths: Vec::new(),
    };
    let mut depth = 0usize;
    let mut i = 0;
    while i < toks.len() {
        match &toks[i] {
            Tok::Punct('{') => depth += 1,
            Tok::Punct('}') => depth = depth.saturating_sub(1),
            Tok::Ident(w) if w == "use" => {
                i += 1;
                use_tree(&toks, &mut i, Vec::new(), &mut scan.uses);
                continue;
            }
            Tok::Ident(w) if depth == 0 && ITEM_KEYWORDS.iter().any(|(k, _)| k == w) => {
                let kind = ITEM_KEYWORDS.iter().find(|(k, _)| k == w).unwrap().1;
                if let Some(name) = ident(toks.get(i + 1)) {
                    // `const fn f`, `unsafe fn` read at their `fn`
                    if name != "fn" && name != "_" {
                        scan.defs.insert(name.to_string(), kind);
                    }
                }
            }
            Tok::Ident(w) => {
                let starts = i == 0 || !matches!(toks[i - 1], Tok::Punct('.') | Tok::PathSep);
                if starts {
                    let mut segs = vec![w.clone()];
                    let mut j = i + 1;
                    while toks.get(j) == Some(&Tok::PathSep) {
                        match ident(toks.get(j + 1)) {
                            Some(s) => {
                                segs.push(s.to_string());
                                j += 2;
                            }
                            None => break,
                        }
                    }
                    scan.paths.push((segs, toks.get(j).cloned()));
                    i = j;
                    continue;
                }
            }
            _ => {}
        }
        i += 1;
    }
    scan
}

/// Where a name resolves: an item of a file, or a module.
#[derive(Clone, Debug)]
enum Target {
    Item(usize, Kind),
    Module(Vec<String>),
}

/// A crate's files, scanned, and the resolution of names between them.
struct Graph {
    files: Vec<FileScan>,
    by_module: HashMap<Vec<String>, usize>,
}

impl Graph {
    fn new(files: Vec<(Vec<String>, PathBuf)>) -> Self {
        let files: Vec<FileScan> = files.into_iter().map(|(m, f)| scan_file(m, f)).collect();
        let by_module = files
            .iter()
            .enumerate()
            .map(|(k, f)| (f.module.clone(), k))
            .collect();
        Graph { files, by_module }
    }

    fn child(&self, module: &[String], name: &str) -> Option<Vec<String>> {
        let mut m = module.to_vec();
        m.push(name.to_string());
        self.by_module.contains_key(&m).then_some(m)
    }

    /// `name` as the module `module` sees it (its definitions, children, imports, globs).
    /// `seen` holds the lookups in progress, so that globs that reach each other (a parent's
    /// `use child::*` and the child's `use super::*`) end.
    fn lookup(
        &self,
        module: &[String],
        name: &str,
        seen: &mut HashSet<(Vec<String>, String)>,
    ) -> Option<Target> {
        let key = (module.to_vec(), name.to_string());
        if !seen.insert(key.clone()) {
            return None;
        }
        let found = self.lookup_in(module, name, seen);
        seen.remove(&key);
        found
    }

    fn lookup_in(
        &self,
        module: &[String],
        name: &str,
        seen: &mut HashSet<(Vec<String>, String)>,
    ) -> Option<Target> {
        let &f = self.by_module.get(module)?;
        if let Some(&kind) = self.files[f].defs.get(name) {
            return Some(Target::Item(f, kind));
        }
        if let Some(m) = self.child(module, name) {
            return Some(Target::Module(m));
        }
        for u in &self.files[f].uses {
            if u.alias.as_deref() == Some(name)
                && let Some(t) = self.resolve(module, &u.path, seen)
            {
                return Some(t);
            }
        }
        for u in self.files[f].uses.iter().filter(|u| u.alias.is_none()) {
            if let Some(Target::Module(g)) = self.resolve(module, &u.path, seen)
                && let Some(t) = self.lookup(&g, name, seen)
            {
                return Some(t);
            }
        }
        None
    }

    /// A path written in module `module`: `crate::…`, `super::…`, `self::…`, or from a
    /// name the module sees; `None` for a path outside the crate.
    fn resolve(
        &self,
        module: &[String],
        path: &[String],
        seen: &mut HashSet<(Vec<String>, String)>,
    ) -> Option<Target> {
        let (first, rest) = path.split_first()?;
        let mut cur = match first.as_str() {
            "crate" => Target::Module(Vec::new()),
            "self" => Target::Module(module.to_vec()),
            "super" => Target::Module(module[..module.len().checked_sub(1)?].to_vec()),
            name => self.lookup(module, name, seen)?,
        };
        for seg in rest {
            let Target::Module(m) = &cur else {
                break;
            };
            cur = match seg.as_str() {
                "super" => Target::Module(m[..m.len().checked_sub(1)?].to_vec()),
                "self" => continue,
                _ => self.lookup(m, seg, seen)?,
            };
        }
        Some(cur)
    }

    /// The edges file → file with the names behind each, ancestors left out.
    fn edges(&self) -> BTreeMap<(usize, usize), BTreeSet<String>> {
        let mut out: BTreeMap<(usize, usize), BTreeSet<String>> = BTreeMap::new();
        for (f, scan) in self.files.iter().enumerate() {
            let mut add = |target: Target, name: &str| {
                let to = match target {
                    Target::Item(t, _) => t,
                    Target::Module(m) => match self.by_module.get(&m) {
                        Some(&t) => t,
                        None => return,
                    },
                };
                let (a, b) = (&scan.module, &self.files[to].module);
                if to == f || a.starts_with(b) || b.starts_with(a) {
                    return;
                }
                out.entry((f, to)).or_default().insert(name.to_string());
            };
            for u in &scan.uses {
                if let Some(t) = self.resolve(&scan.module, &u.path, &mut HashSet::new()) {
                    let name = u.path.join("::");
                    match (&u.alias, t) {
                        // a glob makes an edge only through the names the file reads
                        (None, _) => {}
                        (Some(_), t) => add(t, &name),
                    }
                }
            }
            for (segs, after) in &scan.paths {
                let first = segs[0].as_str();
                if scan.defs.contains_key(first) {
                    continue;
                }
                let explicit = scan.uses.iter().any(|u| u.alias.as_deref() == Some(first));
                let special = matches!(first, "crate" | "super" | "self");
                let Some(t) = self.resolve(&scan.module, segs, &mut HashSet::new()) else {
                    continue;
                };
                if !explicit && !special && segs.len() == 1 {
                    // a single name reached through a glob or a child module
                    let reads_as_use = match &t {
                        Target::Item(_, Kind::Fn) => after == &Some(Tok::Punct('(')),
                        Target::Item(_, _) => true,
                        Target::Module(_) => false,
                    };
                    if !reads_as_use {
                        continue;
                    }
                }
                add(t, &segs.join("::"));
            }
        }
        out
    }
}

/// The strongly connected sets of more than one file (Tarjan).
fn cycles(n: usize, edges: &BTreeMap<(usize, usize), BTreeSet<String>>) -> Vec<Vec<usize>> {
    let mut adj = vec![Vec::new(); n];
    for &(a, b) in edges.keys() {
        adj[a].push(b);
    }
    struct T<'a> {
        adj: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(t: &mut T, v: usize) {
        t.index[v] = Some(t.next);
        t.low[v] = t.next;
        t.next += 1;
        t.stack.push(v);
        t.on[v] = true;
        for k in 0..t.adj[v].len() {
            let w = t.adj[v][k];
            match t.index[w] {
                None => {
                    visit(t, w);
                    t.low[v] = t.low[v].min(t.low[w]);
                }
                Some(iw) if t.on[w] => t.low[v] = t.low[v].min(iw),
                _ => {}
            }
        }
        if Some(t.low[v]) == t.index[v] {
            let mut set = Vec::new();
            loop {
                let w = t.stack.pop().unwrap();
                t.on[w] = false;
                set.push(w);
                if w == v {
                    break;
                }
            }
            if set.len() > 1 {
                set.sort();
                t.out.push(set);
            }
        }
    }
    let mut t = T {
        adj: &adj,
        index: vec![None; n],
        low: vec![0; n],
        on: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if t.index[v].is_none() {
            visit(&mut t, v);
        }
    }
    t.out
}

/// A cycle: its files (relative to the crate's source directory) and the edges inside
/// it, one line each.
type Cycle = (Vec<String>, Vec<String>);

/// Every cycle of every crate, and how many file edges the scan read.
fn file_cycles() -> (Vec<Cycle>, usize) {
    let mut out = Vec::new();
    let mut edge_count = 0;
    for c in crates() {
        let g = Graph::new(crate_files(&c));
        let edges = g.edges();
        edge_count += edges.len();
        let rel = |k: usize| {
            g.files[k]
                .file
                .strip_prefix(&c.dir)
                .unwrap()
                .to_string_lossy()
                .into_owned()
        };
        for set in cycles(g.files.len(), &edges) {
            let mut files: Vec<String> = set.iter().map(|&k| rel(k)).collect();
            files.sort();
            let lines = edges
                .iter()
                .filter(|((a, b), _)| set.contains(a) && set.contains(b))
                .map(|((a, b), names)| {
                    let names: Vec<&str> = names.iter().map(String::as_str).collect();
                    format!(
                        "{}: {} -> {} ({})",
                        c.name,
                        rel(*a),
                        rel(*b),
                        names.join(", ")
                    )
                })
                .collect();
            out.push((files, lines));
        }
    }
    (out, edge_count)
}

#[test]
fn no_cycle_between_files() {
    let (found, edge_count) = file_cycles();
    // the scan read the crates: hundreds of file edges
    assert!(
        edge_count > 300,
        "only {edge_count} file edges read: the scan is broken"
    );
    let mut unknown = Vec::new();
    let mut known_seen = BTreeSet::new();
    for (files, lines) in &found {
        let known = KNOWN_CYCLES.iter().position(|(k, _)| {
            let mut k: Vec<&str> = k.to_vec();
            k.sort();
            k == files.iter().map(String::as_str).collect::<Vec<_>>()
        });
        match known {
            Some(k) => {
                known_seen.insert(k);
            }
            None => unknown.push(format!("cycle {files:?}:\n  {}", lines.join("\n  "))),
        }
    }
    assert!(
        unknown.is_empty(),
        "files that import each other (cut the edge: move the shared item to a leaf or to \
         the lower file):\n{}",
        unknown.join("\n")
    );
    for (k, (files, _)) in KNOWN_CYCLES.iter().enumerate() {
        assert!(
            known_seen.contains(&k),
            "the cycle {files:?} is gone or changed: remove or update it in KNOWN_CYCLES"
        );
    }
}

#[test]
fn no_library_file_over_the_line_limit() {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&here.join("src"), &mut files);
    rust_files(&here.join("python").join("src"), &mut files);
    assert!(files.len() > 100, "only {} files read", files.len());
    let mut long = Vec::new();
    let mut known_seen = BTreeSet::new();
    for f in &files {
        let rel = f.strip_prefix(here).unwrap().to_string_lossy().into_owned();
        let lines = non_test_lines(&std::fs::read_to_string(f).unwrap());
        if lines > MAX_LINES {
            match KNOWN_LONG.iter().position(|(k, _)| *k == rel) {
                Some(k) => {
                    known_seen.insert(k);
                }
                None => long.push(format!("{rel}: {lines} lines")),
            }
        }
    }
    assert!(
        long.is_empty(),
        "library files over {MAX_LINES} non-blank non-test lines (split by role): {long:#?}"
    );
    for (k, (f, _)) in KNOWN_LONG.iter().enumerate() {
        assert!(
            known_seen.contains(&k),
            "{f} is within {MAX_LINES} lines now: remove it from KNOWN_LONG"
        );
    }
}

/// The scanner of the file rules on texts of its own: use trees, blanking, the test
/// block, and a cycle through a glob in a small crate written to a temporary directory
/// (so that the cycle test is seen to fail on a cycle).
#[test]
fn the_file_scan_reads_uses_and_finds_a_glob_cycle() {
    let src = "use super::{self, a::{B, c as d}, e::*}; // use crate::x → ·\nlet s = \"use crate::y;\"; let c = '{';\n";
    let code = blank_comments_and_literals(src);
    // offsets hold: the blanked text has the source's bytes
    assert_eq!(code.len(), src.len());
    let mut uses = Vec::new();
    let toks = tokens(&code);
    let mut i = 1;
    use_tree(&toks, &mut i, Vec::new(), &mut uses);
    let read: Vec<(String, Option<String>)> = uses
        .iter()
        .map(|u| (u.path.join("::"), u.alias.clone()))
        .collect();
    assert_eq!(
        read,
        [
            ("super".into(), Some("super".into())),
            ("super::a::B".into(), Some("B".into())),
            ("super::a::c".into(), Some("d".into())),
            ("super::e".into(), None),
        ]
    );
    assert!(
        !code.contains("crate"),
        "comments and strings are blanked: {code}"
    );
    let text =
        "//! doc\n\nfn f() {}\n#[cfg(test)]\nmod tests {\n    fn g() { let _ = \"}\"; }\n}\n";
    assert_eq!(non_test_lines(text), 2);
    // other test-only modules are no imports, but only `mod tests` leaves the line count
    let grids = "#[cfg(test)]\npub(crate) mod grids {\n    use crate::x;\n}\n";
    assert_eq!(test_blocks(grids), [(0, grids.len() - 1)]);
    assert_eq!(non_test_lines(grids), 4);

    // a/mod.rs globs its children; x.rs reads y's type through `use super::*`, y.rs calls
    // x's function: a cycle, which the parent's globs alone do not make
    let dir = std::env::temp_dir().join(format!("module_layers_{}", std::process::id()));
    let a = dir.join("a");
    std::fs::create_dir_all(&a).unwrap();
    let write = |p: &str, t: &str| std::fs::write(dir.join(p), t).unwrap();
    write("lib.rs", "pub mod a;\n");
    write(
        "a/mod.rs",
        "mod x;\nmod y;\nuse x::*;\nuse y::*;\npub struct Top;\n",
    );
    write(
        "a/x.rs",
        "use super::*;\npub fn helper() -> Shared { Shared }\npub struct Own(Top);\n",
    );
    write(
        "a/y.rs",
        "use super::*;\npub struct Shared;\nfn f() { let helper = 1; }\n",
    );
    let scan = |dir: &Path| {
        let c = CrateSrc {
            name: "probe",
            dir: dir.to_path_buf(),
            root: "lib.rs",
            skip: &[],
        };
        let g = Graph::new(crate_files(&c));
        let edges = g.edges();
        let named: BTreeSet<(String, String)> = edges
            .keys()
            .map(|&(f, t)| {
                let rel = |k: usize| g.files[k].module.join("::");
                (rel(f), rel(t))
            })
            .collect();
        (named, cycles(g.files.len(), &edges).len())
    };
    // a variable named like a function is no call: no edge y → x yet
    let (edges, found) = scan(&dir);
    assert_eq!(edges, BTreeSet::from([("a::x".into(), "a::y".into())]));
    assert_eq!(found, 0);
    write(
        "a/y.rs",
        "use super::*;\npub struct Shared;\nfn f() { helper(); }\n",
    );
    let (edges, found) = scan(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(edges.len(), 2, "{edges:?}");
    assert_eq!(found, 1);
}
