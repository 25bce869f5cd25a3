//! Issue 36 §1: the modules point one way, as DESIGN.md §10 draws the layers. Every
//! `crate::<module>` path in the library's non-test code (a file's `#[cfg(test)] mod
//! tests` block and comments stripped; `use crate::{a, b}` groups read too) must name a
//! module on a lower layer than the file's own, or its own. Before issue 36 two edges
//! ran up: `scene → study` (the `[sweep]` table's type) and `run → scene` (the entry
//! points and the checkpoint's source, now in `app/`). Any upward edge fails this test
//! with its file.

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
