//! Build identity of the crate (`asperity::core::build_info::BuildId`), recorded in every shard file
//! of a sharded sweep so that `asperity merge` refuses shards computed by different builds: a
//! unit's results are bit-identical only for the same code, and the crate version alone does
//! not say which code that was.
//!
//! Emitted as `rustc-env` variables:
//! - `ASPERITY_BUILD_GIT_COMMIT`: `git rev-parse HEAD` when the crate is the top level of a git
//!   work tree and git runs, empty otherwise (a tarball, a vendored copy, no git installed);
//! - `ASPERITY_BUILD_GIT_DIRTY`: `1` when `git status --porcelain` lists a change to a build
//!   input (see below) against that commit, `0` when clean, empty without git;
//! - `ASPERITY_BUILD_SOURCE_SHA256`: SHA-256 over the build inputs — every file under `src/`
//!   except hidden ones (relative path and content, in path order), `build.rs`, `Cargo.toml`,
//!   `Cargo.lock` — so that a build from a tarball, or with uncommitted changes, is still
//!   identified by what it was built from;
//! - `ASPERITY_BUILD_RUSTC` (`$RUSTC --version`), `ASPERITY_BUILD_TARGET`,
//!   `ASPERITY_BUILD_PROFILE`.
//!
//! Rerun triggers: the build inputs (the `src` directory is scanned recursively by cargo), the
//! git `HEAD` file and the file of the branch it points to (plus `packed-refs`), so that a new
//! commit, a checkout or a change to the sources updates the identity.

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Files outside `src/` that go into the build (relative to the manifest directory).
const INPUTS: [&str; 3] = ["build.rs", "Cargo.toml", "Cargo.lock"];

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=src");
    for f in INPUTS {
        if root.join(f).exists() {
            println!("cargo:rerun-if-changed={f}");
        }
    }
    let (commit, dirty) = match git_state(&root) {
        Some((commit, dirty)) => (commit, if dirty { "1" } else { "0" }),
        None => (String::new(), ""),
    };
    println!("cargo:rustc-env=ASPERITY_BUILD_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=ASPERITY_BUILD_GIT_DIRTY={dirty}");
    println!(
        "cargo:rustc-env=ASPERITY_BUILD_SOURCE_SHA256={}",
        source_sha256(&root)
    );
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = run(Command::new(rustc).arg("--version")).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=ASPERITY_BUILD_RUSTC={version}");
    println!(
        "cargo:rustc-env=ASPERITY_BUILD_TARGET={}",
        std::env::var("TARGET").unwrap_or_default()
    );
    println!(
        "cargo:rustc-env=ASPERITY_BUILD_PROFILE={}",
        std::env::var("PROFILE").unwrap_or_default()
    );
}

/// Trimmed standard output of a successful command.
fn run(cmd: &mut Command) -> Option<String> {
    let out = cmd.output().ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

fn git(root: &Path, args: &[&str]) -> Option<String> {
    run(Command::new("git").arg("-C").arg(root).args(args))
}

/// `(commit, dirty)` when `root` is the top level of a git work tree, with the rerun triggers
/// of the commit; `None` otherwise (then the source hash alone identifies the build).
fn git_state(root: &Path) -> Option<(String, bool)> {
    let top = git(root, &["rev-parse", "--show-toplevel"])?;
    // A copy of the crate inside another repository (vendored) is not that repository's commit.
    if Path::new(&top).canonicalize().ok()? != root.canonicalize().ok()? {
        return None;
    }
    let commit = git(root, &["rev-parse", "HEAD"])?;
    // HEAD itself (checkout, detached HEAD) and, on a branch, the branch's ref (a commit);
    // `--git-path` resolves both for linked work trees too. A ref that is packed (no loose
    // file) is watched anyway: cargo then reruns this script on every build, which is cheap
    // and keeps the commit right.
    let watch = |p: &str| {
        if let Some(path) = git(root, &["rev-parse", "--git-path", p]) {
            println!("cargo:rerun-if-changed={}", root.join(path).display());
        }
    };
    watch("HEAD");
    if let Some(branch) = git(root, &["symbolic-ref", "-q", "HEAD"]) {
        watch(&branch);
        if let Some(packed) = git(root, &["rev-parse", "--git-path", "packed-refs"]) {
            if root.join(&packed).exists() {
                println!("cargo:rerun-if-changed={}", root.join(packed).display());
            }
        }
    }
    let mut status = vec![
        "status",
        "--porcelain",
        "--untracked-files=all",
        "--",
        "src",
    ];
    status.extend(INPUTS);
    let dirty = !git(root, &status)?.is_empty();
    Some((commit, dirty))
}

/// SHA-256 over the build inputs: for each file (sorted by relative path, `/`-separated), its
/// path, a NUL, its length (8 bytes little-endian) and its content.
fn source_sha256(root: &Path) -> String {
    let mut files = Vec::new();
    collect(root, Path::new("src"), &mut files);
    for f in INPUTS {
        if root.join(f).is_file() {
            files.push(PathBuf::from(f));
        }
    }
    let key = |p: &PathBuf| {
        p.components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/")
    };
    files.sort_by_key(key);
    let mut h = Sha256::new();
    for f in &files {
        let bytes = std::fs::read(root.join(f))
            .unwrap_or_else(|e| panic!("build.rs: cannot read {}: {e}", f.display()));
        h.update(key(f).as_bytes());
        h.update([0]);
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    format!("{:x}", h.finalize())
}

fn collect(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(root.join(dir))
        .unwrap_or_else(|e| panic!("build.rs: cannot list {}: {e}", dir.display()));
    for e in entries {
        let e = e.unwrap_or_else(|e| panic!("build.rs: cannot list {}: {e}", dir.display()));
        // Hidden files (editor swap files, `.DS_Store`) are not sources.
        if e.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        let rel = dir.join(e.file_name());
        let ty = e
            .file_type()
            .unwrap_or_else(|err| panic!("build.rs: {}: {err}", rel.display()));
        if ty.is_dir() {
            collect(root, &rel, out);
        } else if ty.is_file() {
            out.push(rel);
        }
    }
}
