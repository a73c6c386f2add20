//! The library's modules follow the data flow: a stage uses only the stages before it and the
//! core layer, and the core layer uses no stage.
//!
//! Order (rank): core (0) · surface (1) · halfspace (2) · contact (3) · element (4) ·
//! calibrate (5) · film (6) · elements (7) · dynamics (8) · identify and diagnose (9, siblings:
//! neither uses the other). Every `crate::<module>` path in the library's code (comments and
//! doc comments excluded, test modules included) is checked against that order. The command
//! line (`src/main.rs`, `src/cli/`) may use everything and is not checked.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Rank of a top-level module in the data flow; `None` for a name that is not a module.
fn rank(module: &str) -> Option<u32> {
    Some(match module {
        "core" => 0,
        "surface" => 1,
        "halfspace" => 2,
        "contact" => 3,
        "element" => 4,
        "calibrate" => 5,
        "film" => 6,
        "elements" => 7,
        "dynamics" => 8,
        "identify" | "diagnose" => 9,
        _ => return None,
    })
}

/// The crate root's re-exports of core items (`crate::Error`, `crate::Result`, `crate::Grid2`).
const ROOT_REEXPORTS: [&str; 3] = ["Error", "Result", "Grid2"];

/// May code in module `from` use module `to`?
fn allowed(from: &str, to: &str) -> bool {
    if from == to || to == "core" {
        return true;
    }
    match (rank(from), rank(to)) {
        (Some(a), Some(b)) => b < a && a > 0,
        _ => false,
    }
}

/// The source with `//` comments (doc comments included) and `/* */` blocks removed, string
/// literals kept (a path inside a string is not a dependency, but no string here spells one).
fn strip_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let (mut i, mut in_str) = (0, false);
    while i < b.len() {
        if in_str {
            if b[i] == b'\\' && i + 1 < b.len() {
                i += 2;
                continue;
            }
            if b[i] == b'"' {
                in_str = false;
            }
            i += 1;
            continue;
        }
        match (b[i], b.get(i + 1)) {
            (b'"', _) if i == 0 || b[i - 1] != b'\'' => {
                in_str = true;
                i += 1;
            }
            (b'/', Some(b'/')) => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            (b'/', Some(b'*')) => {
                let mut depth = 0;
                while i < b.len() {
                    if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                        depth += 1;
                        i += 2;
                    } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            _ => {
                out.push(b[i] as char);
                i += 1;
            }
        }
    }
    out
}

/// Every module named after `crate::` in `code`, including the members of a grouped
/// `use crate::{a::…, b::…}`.
fn crate_paths(code: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut found = Vec::new();
    for (pos, _) in code.match_indices("crate::") {
        // `asperity::crate::` cannot occur; skip `$crate::` in macros.
        if pos > 0 && code.as_bytes()[pos - 1] == b'$' {
            continue;
        }
        let rest = &code[pos + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name = ident(item.trim());
                if !name.is_empty() {
                    found.push(name);
                }
            }
        } else {
            found.push(ident(rest));
        }
    }
    found
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The top-level module a library file belongs to (`src/contact/normal.rs` → `contact`,
/// `src/elements.rs` → `elements`); `None` for the crate root and the command line.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    let name = first.strip_suffix(".rs").unwrap_or(&first).to_string();
    match name.as_str() {
        "lib" | "main" | "cli" => None,
        _ => Some(name),
    }
}

/// `(file, from, to)` for every use of a module the order forbids.
fn violations(src: &Path) -> Vec<(String, String, String)> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let mut bad = BTreeSet::new();
    for f in &files {
        let Some(from) = module_of(src, f) else {
            continue;
        };
        assert!(
            rank(&from).is_some(),
            "{}: module `{from}` has no place in the data flow; add it to `rank` in {}",
            f.display(),
            file!()
        );
        let code = strip_comments(&std::fs::read_to_string(f).unwrap());
        for to in crate_paths(&code) {
            let to = if ROOT_REEXPORTS.contains(&to.as_str()) {
                "core".to_string()
            } else {
                to
            };
            if !allowed(&from, &to) {
                let rel = f.strip_prefix(src).unwrap().display().to_string();
                bad.insert((rel, from.clone(), to));
            }
        }
    }
    bad.into_iter().collect()
}

#[test]
fn stages_use_only_earlier_stages_and_core() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let bad = violations(&src);
    assert!(
        bad.is_empty(),
        "uses against the data flow (file: module → module it uses):\n{}",
        bad.iter()
            .map(|(f, a, b)| format!("  {f}: {a} → {b}"))
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The checker finds what it must: a later stage, a sibling, core using a stage, grouped
/// imports and unknown modules; comments and doc comments are not code.
#[test]
fn the_checker_catches_every_kind_of_violation() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    let write = |rel: &str, text: &str| {
        let p = src.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    };
    write("core/grid.rs", "use crate::surface::stats;\n");
    write(
        "surface/stats.rs",
        "use crate::core::fft::FftPlan;\nuse crate::Grid2;\n",
    );
    write(
        "contact/normal.rs",
        "//! see [`crate::dynamics`]\n/* crate::identify */\nuse crate::{halfspace::x, elements::y};\nfn f() { let s = \"crate::film\"; }\n",
    );
    write(
        "identify/fit.rs",
        "fn g() { crate::diagnose::noise::median(&[]); }\n",
    );
    write("element/valanis.rs", "use crate::nowhere::x;\n");
    write("cli/mod.rs", "use crate::identify::x;\n");
    let got = violations(src);
    let want = [
        ("contact/normal.rs", "contact", "elements"),
        ("core/grid.rs", "core", "surface"),
        ("element/valanis.rs", "element", "nowhere"),
        ("identify/fit.rs", "identify", "diagnose"),
    ];
    let got: Vec<(&str, &str, &str)> = got
        .iter()
        .map(|(f, a, b)| (f.as_str(), a.as_str(), b.as_str()))
        .collect();
    assert_eq!(got, want);
}
