//! The documents hold together: every relative link in README.md, CHANGELOG.md, BENCHMARKS.md and
//! docs/*.md resolves to an existing file (and an `#anchor` to a heading of that file, with
//! GitHub's heading slugs); README.md stays short (≤ 250 lines) and carries no dated notes (history
//! goes to CHANGELOG.md), nor do the user guides; and every subcommand that `asperity --help` lists
//! has a guide, `docs/<name>.md` or a row of docs/README.md that links one.
//!
//! The checker is plain Markdown scanning: fenced code blocks and inline code spans are skipped,
//! external links (`http:`, `https:`, `mailto:`) are not followed.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documents whose links are checked: the top-level three and every Markdown file in docs/.
fn documents(root: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["README.md", "CHANGELOG.md", "BENCHMARKS.md"]
        .iter()
        .map(|f| root.join(f))
        .collect();
    let mut guides: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    guides.sort();
    files.extend(guides);
    files
}

/// The lines of `text` outside fenced code blocks, with inline code spans blanked out.
fn prose_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("```") || t.starts_with("~~~") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        out.push((i + 1, strip_code_spans(line)));
    }
    out
}

/// `line` with every inline code span (`` `…` ``, any number of backticks) replaced by spaces.
fn strip_code_spans(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::with_capacity(line.len());
    let mut i = 0;
    while i < chars.len() {
        if chars[i] == '`' {
            let mut n = 0;
            while i + n < chars.len() && chars[i + n] == '`' {
                n += 1;
            }
            // Find the closing run of exactly n backticks.
            let mut j = i + n;
            let mut close = None;
            while j < chars.len() {
                if chars[j] == '`' {
                    let mut m = 0;
                    while j + m < chars.len() && chars[j + m] == '`' {
                        m += 1;
                    }
                    if m == n {
                        close = Some(j);
                        break;
                    }
                    j += m;
                } else {
                    j += 1;
                }
            }
            match close {
                Some(c) => {
                    out.extend(std::iter::repeat_n(' ', c + n - i));
                    i = c + n;
                }
                None => {
                    out.extend(std::iter::repeat_n('`', n));
                    i += n;
                }
            }
        } else {
            out.push(chars[i]);
            i += 1;
        }
    }
    out
}

/// Link targets `(…)` of inline links and images `[text](target)` / `![alt](target)` on a line.
fn link_targets(line: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = line;
    while let Some(p) = rest.find("](") {
        let after = &rest[p + 2..];
        // The target ends at the matching ')' (targets here hold no nested parentheses).
        let Some(end) = after.find(')') else { break };
        let target = after[..end].trim();
        // An optional title: `(path "title")`.
        let target = target.split_whitespace().next().unwrap_or("").to_string();
        targets.push(target);
        rest = &after[end + 1..];
    }
    targets
}

/// GitHub's anchor of a heading: lower case, punctuation dropped (letters, digits, `-`, `_` and
/// spaces kept), spaces to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of every heading of a Markdown text, duplicates numbered `-1`, `-2`, … as GitHub
/// does.
fn anchors(text: &str) -> Vec<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("```") || t.starts_with("~~~") {
            fenced = !fenced;
            continue;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let title = line.trim_start_matches('#');
        if !title.starts_with(' ') {
            continue;
        }
        let base = slug(title);
        let n = seen.entry(base.clone()).or_insert(0);
        out.push(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

/// Every broken relative link of the Markdown file `file`, as `file:line: target (why)`.
fn broken_links(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let dir = file.parent().unwrap();
    let mut errors = Vec::new();
    for (line_no, line) in prose_lines(&text) {
        for target in link_targets(&line) {
            if target.is_empty()
                || target.starts_with("http://")
                || target.starts_with("https://")
                || target.starts_with("mailto:")
            {
                continue;
            }
            let (path, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if path.is_empty() {
                file.to_path_buf()
            } else {
                dir.join(path)
            };
            let at = format!("{}:{line_no}: {target}", file.display());
            if !resolved.exists() {
                errors.push(format!("{at} (no such file: {})", resolved.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                if resolved.is_dir() {
                    errors.push(format!("{at} (an anchor into a directory)"));
                    continue;
                }
                let target_text = std::fs::read_to_string(&resolved).unwrap();
                if !anchors(&target_text).iter().any(|a| a == anchor) {
                    errors.push(format!(
                        "{at} (no heading with anchor #{anchor} in {})",
                        resolved.display()
                    ));
                }
            }
        }
    }
    errors
}

/// The first `YYYY-MM-DD` date in `text`, with its line.
fn first_date(text: &str) -> Option<(usize, String)> {
    for (i, line) in text.lines().enumerate() {
        let b = line.as_bytes();
        for s in 0..b.len().saturating_sub(9) {
            let d = &b[s..s + 10];
            let digits = |r: std::ops::Range<usize>| r.into_iter().all(|k| d[k].is_ascii_digit());
            if digits(0..4) && d[4] == b'-' && digits(5..7) && d[7] == b'-' && digits(8..10) {
                return Some((i + 1, String::from_utf8_lossy(d).into_owned()));
            }
        }
    }
    None
}

#[test]
fn every_relative_link_resolves() {
    let root = root();
    let errors: Vec<String> = documents(&root)
        .iter()
        .flat_map(|f| broken_links(f))
        .collect();
    assert!(errors.is_empty(), "broken links:\n{}", errors.join("\n"));
}

#[test]
fn readme_is_short_and_undated() {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = text.lines().count();
    assert!(lines <= 250, "README.md has {lines} lines (at most 250)");
    if let Some((line, date)) = first_date(&text) {
        panic!("README.md:{line}: a dated note ({date}); history goes to CHANGELOG.md");
    }
}

#[test]
fn user_guides_carry_no_dated_history() {
    let root = root();
    for file in documents(&root) {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        // The benchmark log and today's table date their runs; the changelog is history.
        if file.parent() != Some(root.join("docs").as_path()) || name == "benchmarks-log.md" {
            continue;
        }
        let text = std::fs::read_to_string(&file).unwrap();
        if let Some((line, date)) = first_date(&text) {
            panic!(
                "{}:{line}: a dated note ({date}); history goes to CHANGELOG.md",
                file.display()
            );
        }
    }
}

/// The subcommands `asperity --help` lists (without clap's own `help`).
fn subcommands() -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_asperity"))
        .arg("--help")
        .output()
        .expect("run asperity --help");
    assert!(out.status.success());
    let help = String::from_utf8(out.stdout).unwrap();
    let section = help
        .split("Commands:")
        .nth(1)
        .expect("a Commands: section in --help")
        .split("\n\n")
        .next()
        .unwrap();
    let names: Vec<String> = section
        .lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|n| *n != "help")
        .map(str::to_string)
        .collect();
    assert!(names.len() >= 10, "subcommands from --help: {names:?}");
    names
}

#[test]
fn every_subcommand_has_a_guide() {
    let root = root();
    let docs = root.join("docs");
    let index = std::fs::read_to_string(docs.join("README.md")).unwrap();
    let mut missing = Vec::new();
    for name in subcommands() {
        if docs.join(format!("{name}.md")).exists() {
            continue;
        }
        // A row of the index naming `asperity <name>` with a link to an existing guide.
        let mapped = prose_lines(&index)
            .iter()
            .zip(index.lines())
            .any(|((_, prose), raw)| {
                (raw.contains(&format!("`asperity {name}`"))
                    || raw.contains(&format!("`asperity {name} ")))
                    && link_targets(prose)
                        .iter()
                        .any(|t| t.ends_with(".md") && docs.join(t).exists())
            });
        if !mapped {
            missing.push(name);
        }
    }
    assert!(
        missing.is_empty(),
        "subcommands without docs/<name>.md or a row of docs/README.md linking a guide: {missing:?}"
    );
}

/// The checker itself finds what it is meant to find: a link to a missing file, a missing
/// anchor and an anchor that exists (duplicates numbered), but not links inside code.
#[test]
fn the_checker_finds_broken_links_and_anchors() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(
        d.path().join("a.md"),
        "# Title\n\n## Same\n\n## Same\n\n## Levelling (`--detrend`)\n",
    )
    .unwrap();
    let b = d.path().join("b.md");
    std::fs::write(
        &b,
        "[ok](a.md) [ok](a.md#same-1) [ok](a.md#levelling---detrend) [ok](#here)\n\
         # Here\n\
         [gone](missing.md) [no anchor](a.md#nowhere) `[code](missing-in-code.md)`\n\
         ```\n[fenced](missing-in-fence.md)\n```\n",
    )
    .unwrap();
    let errors = broken_links(&b);
    assert_eq!(errors.len(), 2, "{errors:?}");
    assert!(errors[0].contains("missing.md") && errors[0].contains("no such file"));
    assert!(errors[1].contains("#nowhere"));
    assert_eq!(
        slug(" Multi-DOF reduced models (`asperity identify --structure`)"),
        "multi-dof-reduced-models-asperity-identify---structure"
    );
    assert_eq!(
        first_date("no date\nrun of 2026-11-27 here").unwrap(),
        (2, "2026-11-27".into())
    );
    assert!(first_date("1.2e-6 and 20 min").is_none());
}
