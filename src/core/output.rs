//! Output files that are either complete or absent, singly and as a set.
//!
//! **Single files.** Every writer in the crate goes through [`write_atomic`] (or
//! [`write_atomic_via_path`] for encoders that need a path): the content is written to a
//! temporary file in the destination directory and renamed over the destination only when the
//! writer succeeded, so an error never leaves a half-written CSV, PNG or table behind. Results
//! are created `0644` like any other tool's (temporary files start private).
//!
//! **Sets of files: [`OutputSet`].** A command writes several files (a table, its plots, a JSON
//! sidecar); they must appear together or not at all. A command adopts this with three calls:
//!
//! ```text
//! let mut out = OutputSet::in_dir(&args.out_dir, "--out-dir")?;   // before any computation:
//!                                         // refuses an --out-dir that is a file or not writable
//! ... compute ...
//! write_string_atomic(&out.path("table.csv")?, &text)?;            // staged, not yet visible
//! heatmap(&out.path("map.png")?, ...)?;                             // (same for every file)
//! let written = out.commit()?;                                      // all appear, or none
//! ```
//!
//! or, for explicit file names (`-o a.npy -o a.png`), `OutputSet::for_files(&paths, "--out")`
//! and `out.file(&target)`. Files are staged in a hidden directory `.asperity-staging-*` beside
//! their targets (same file system) and renamed into place by [`OutputSet::commit`], which
//! restores the previous files if any rename fails. Dropping an uncommitted set (an error, a
//! `?`) removes everything staged. The same target twice (e.g. a sidecar that would overwrite
//! its data file) is refused when it is staged.
//!
//! **Inputs are never outputs.** A command declares every file it reads with
//! [`OutputSet::input`] (a model file and every file it names, each topography with its
//! sidecar); no file of the set may be one of them, nor may the cleanup below remove one. Files
//! are compared by identity — canonical path (links and `..` resolved) and, on Unix, device and
//! inode, so a hard link is caught too; a file not yet existing by its nearest existing
//! directory — when an input or an output becomes known (an input among the
//! [`OutputSet::writes`] names or the owned files of the directory is refused before any
//! computation), when a file is staged, and for every file again at the commit, before the
//! first rename. The error names both paths and the input's role; nothing is written.
//!
//! **Files of earlier runs.** A command whose file names depend on its input (one plot per
//! level or per pressure) declares them with [`OutputSet::owns`]: after a commit, the files of
//! the output directory that match such a name and that this run did not write are removed —
//! otherwise a run with two levels would leave a three-level run's `predict-3.png` beside its
//! own report. No other file of the directory is touched.
//!
//! **Interrupts.** [`install_interrupt_handler`] (called once by the CLI) handles SIGINT,
//! SIGTERM and SIGHUP: it waits for a commit in progress to finish (and lets no other start),
//! removes every staging directory and temporary file of the process, and reports what
//! happened:
//!
//! | when | message | exit status |
//! |---|---|---|
//! | before the output set was moved into place (or its commit failed and was undone) | `interrupted before writing: previous files untouched` | 130 ([`EXIT_INTERRUPTED_BEFORE_WRITING`]) |
//! | after the output set was complete | `interrupted after the new set was complete: new files in place` | 3 ([`EXIT_INTERRUPTED_AFTER_WRITING`]) |
//!
//! So an interrupt leaves either the complete previous outputs or the complete new ones, and
//! no temporary files, and says which. An error the interrupted work runs into while its
//! staged files are removed (a writer finding its directory gone) is not reported: the CLI
//! checks [`interrupted`] before printing an error. (A SIGKILL or power loss during the few
//! renames of a commit can still leave a mix; staging directories left by a killed process are
//! hidden and named `.asperity-staging-*`.)

use crate::core::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Paths (staging directories and temporary files) to remove if the process is interrupted.
static CLEANUP: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Held while an [`OutputSet`] moves its files into place; the interrupt handler waits for it.
static COMMIT: Mutex<()> = Mutex::new(());
/// Set when an [`OutputSet`] of this process has been moved into place.
static COMMITTED: AtomicBool = AtomicBool::new(false);
/// Set as soon as an interrupt arrives.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Exit status of an interrupt that arrived before the outputs were moved into place: the
/// previous files are untouched (128 + SIGINT, as a shell reports it).
pub const EXIT_INTERRUPTED_BEFORE_WRITING: i32 = 130;

/// Exit status of an interrupt that arrived after the command's new output set was complete:
/// the new files are in place (the rest of the command, e.g. its summary, did not run).
pub const EXIT_INTERRUPTED_AFTER_WRITING: i32 = 3;

/// Whether an interrupt has arrived: an error then is a consequence of the interrupt's cleanup,
/// not something to report (the handler reports what happened and exits).
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn register(path: &Path) {
    lock(&CLEANUP).push(path.to_path_buf());
}

fn deregister(path: &Path) {
    lock(&CLEANUP).retain(|p| p != path);
}

fn remove_path(p: &Path) {
    // A writer may still be creating files in a staging directory: retry a few times.
    for _ in 0..5 {
        let r = if p.is_dir() {
            std::fs::remove_dir_all(p)
        } else {
            std::fs::remove_file(p)
        };
        if r.is_ok() || !p.exists() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Remove every staging directory and temporary file registered so far.
fn remove_registered() {
    let paths: Vec<PathBuf> = std::mem::take(&mut *lock(&CLEANUP));
    for p in paths.iter().rev() {
        remove_path(p);
    }
}

/// Remove every staging directory and temporary file of this process. Waits for a commit in
/// progress.
pub fn remove_partial_outputs() {
    let _commit = lock(&COMMIT);
    remove_registered();
}

/// What an interrupt found: the report and the exit status (module documentation).
pub fn interrupt_report(new_set_in_place: bool) -> (&'static str, i32) {
    if new_set_in_place {
        (
            "interrupted after the new set was complete: new files in place",
            EXIT_INTERRUPTED_AFTER_WRITING,
        )
    } else {
        (
            "interrupted before writing: previous files untouched",
            EXIT_INTERRUPTED_BEFORE_WRITING,
        )
    }
}

/// Handle SIGINT, SIGTERM and SIGHUP: wait for a commit in progress, remove partial outputs,
/// report which set is in place and exit (see the module documentation). Call once, at the
/// start of `main`.
/// Part of the `cli` feature (a host process such as Python owns its signals).
#[cfg(feature = "cli")]
pub fn install_interrupt_handler() {
    let r = ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        // Held until the exit (`process::exit` runs no destructors): no commit starts after
        // this point.
        let _commit = lock(&COMMIT);
        remove_registered();
        let (message, code) = interrupt_report(COMMITTED.load(Ordering::SeqCst));
        eprintln!("{message}");
        std::process::exit(code);
    });
    if let Err(e) = r {
        eprintln!("warning: cannot install the interrupt handler: {e}");
    }
}

/// Write `path` atomically: `fill` writes into a temporary file beside `path`, which is renamed
/// onto `path` only if `fill` returns `Ok`. Parent directories are created as needed.
pub fn write_atomic<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut tmp = tempfile::Builder::new()
        .prefix(".asperity-tmp-")
        .tempfile_in(&dir)
        .map_err(|e| Error::io(&dir, e))?;
    let tmp_path = tmp.path().to_path_buf();
    register(&tmp_path);
    let result = (|| {
        {
            let mut buf = std::io::BufWriter::new(tmp.as_file_mut());
            fill(&mut buf)?;
            buf.flush().map_err(|e| Error::io(path, e))?;
        }
        make_readable(tmp.path(), path)?;
        tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
        Ok(())
    })();
    deregister(&tmp_path);
    result
}

/// Temporary files are created private (0600); results are ordinary files (0644), as any
/// other tool would write them. Errors name the destination, not the temporary file.
fn make_readable(tmp: &Path, dest: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(tmp, std::fs::Permissions::from_mode(0o644))
            .map_err(|e| Error::io(dest, e))?;
    }
    #[cfg(not(unix))]
    let _ = (tmp, dest);
    Ok(())
}

/// Atomically write a string.
pub fn write_string_atomic(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| Error::io(path, e))
    })
}

/// Atomically produce a file with a writer that needs a real path (e.g. image encoders, plotters):
/// `fill` receives a temporary path in the destination directory carrying the same extension.
pub fn write_atomic_via_path<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&Path) -> Result<()>,
{
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let tmp = tempfile::Builder::new()
        .prefix(".asperity-tmp-")
        .suffix(&ext)
        .tempfile_in(&dir)
        .map_err(|e| Error::io(&dir, e))?;
    let tmp_path = tmp.into_temp_path();
    let registered = tmp_path.to_path_buf();
    register(&registered);
    let result = (|| {
        // Errors of the encoder name the destination, not the temporary file.
        let tmp_name = tmp_path.display().to_string();
        fill(&tmp_path).map_err(|e| rename_in_error(e, &tmp_name, path))?;
        make_readable(&tmp_path, path)?;
        tmp_path
            .persist(path)
            .map_err(|e| Error::io(path, e.error))?;
        Ok(())
    })();
    deregister(&registered);
    result
}

/// Replace the temporary file's name by the destination's in an error.
fn rename_in_error(e: Error, tmp_name: &str, dest: &Path) -> Error {
    let dest_name = dest.display().to_string();
    match e {
        Error::Io { source, .. } => Error::io(dest, source),
        Error::Parse { line, message, .. } => {
            Error::parse(dest, line, message.replace(tmp_name, &dest_name))
        }
        Error::Data(m) => Error::Data(m.replace(tmp_name, &dest_name)),
        other => other,
    }
}

/// A set of output files that appear together or not at all (see the module documentation).
#[derive(Debug, Default)]
pub struct OutputSet {
    /// Output directory of [`OutputSet::in_dir`] and the flag naming it.
    dir: Option<(PathBuf, String)>,
    /// `(existing directory, staging directory inside it)`.
    stagings: Vec<(PathBuf, PathBuf)>,
    /// Targets staged so far (as given), with the flag or role that named them.
    targets: Vec<(PathBuf, String)>,
    /// File-name patterns `(prefix, suffix)` of the output directory that belong to this
    /// command ([`OutputSet::owns`]).
    owned: Vec<(String, String)>,
    /// Fixed file names of the output directory this command writes ([`OutputSet::writes`]).
    names: Vec<String>,
    /// Files announced by [`OutputSet::for_files`] (staged later), with their flag.
    planned: Vec<(PathBuf, String)>,
    /// The command's input files ([`OutputSet::input`]): none may be written or removed.
    inputs: Vec<Input>,
    committed: bool,
}

/// An input file of a command: the path as given, the flag or role naming it, its identity.
#[derive(Debug, Clone)]
struct Input {
    path: PathBuf,
    role: String,
    id: FileIdentity,
}

/// Which file a path names: its canonical path (links and `..` resolved) and, on Unix, its
/// device and inode, so that a hard link (another name of the same file) is recognised too.
/// A path that does not exist yet is named by its nearest existing ancestor, canonical, and the
/// rest of the path (`..` taken lexically: the directories to be created are no links).
#[derive(Debug, Clone, PartialEq)]
struct FileIdentity {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

impl FileIdentity {
    /// The identity of `p`, or `None` when no ancestor of it can be resolved.
    fn of(p: &Path) -> Option<Self> {
        if let Ok(path) = std::fs::canonicalize(p) {
            let inode = std::fs::metadata(&path).ok().and_then(|m| inode_of(&m));
            return Some(Self { path, inode });
        }
        for a in p.ancestors().skip(1) {
            let base = if a.as_os_str().is_empty() {
                Path::new(".")
            } else {
                a
            };
            let Ok(mut path) = std::fs::canonicalize(base) else {
                continue;
            };
            for c in p.strip_prefix(a).ok()?.components() {
                match c {
                    std::path::Component::Normal(n) => path.push(n),
                    std::path::Component::ParentDir => {
                        path.pop();
                    }
                    _ => {}
                }
            }
            return Some(Self { path, inode: None });
        }
        None
    }

    /// The same file: the same canonical path, or the same device and inode.
    fn same(&self, other: &Self) -> bool {
        self.path == other.path || (self.inode.is_some() && self.inode == other.inode)
    }
}

#[cfg(unix)]
fn inode_of(m: &std::fs::Metadata) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    Some((m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode_of(_: &std::fs::Metadata) -> Option<(u64, u64)> {
    None
}

/// What would happen to an input: it would be written over, removed as a stale output, or
/// either (an owned name of the output directory, before the run knows which it writes).
#[derive(Clone, Copy)]
enum Clash {
    Overwritten,
    Removed,
    Owned,
}

/// The refusal of an output `target` (named by `flag`) that is the input `input`.
fn clash_error(
    target: &Path,
    flag: &str,
    input: &Input,
    target_id: &FileIdentity,
    how: Clash,
) -> Error {
    // The target's own name (its directory resolved, not the file): another name than the
    // input's means a symbolic or a hard link.
    let own_name = target
        .parent()
        .map(|d| {
            if d.as_os_str().is_empty() {
                Path::new(".")
            } else {
                d
            }
        })
        .and_then(|d| std::fs::canonicalize(d).ok())
        .zip(target.file_name())
        .map(|(d, n)| d.join(n));
    let link = if target_id.path != input.id.path || own_name.is_some_and(|n| n != input.id.path) {
        " (the same file under another name: a link)"
    } else {
        ""
    };
    let what = match how {
        Clash::Overwritten => "it would be overwritten",
        Clash::Removed => "it would be removed as a file of an earlier run",
        Clash::Owned => {
            "its name is one this command writes into the output directory: it would be \
             overwritten, or removed as a file of an earlier run"
        }
    };
    Error::param(
        flag,
        format!(
            "the output `{}` is the input `{}` ({}){link}: {what}; nothing was written, give the \
             output another path",
            target.display(),
            input.path.display(),
            input.role
        ),
    )
}

/// A relative `path` with an explicit leading `./` (so that it lies below the anchor `.`).
fn with_dir(path: &Path) -> PathBuf {
    if path.is_relative() && !path.starts_with(".") {
        Path::new(".").join(path)
    } else {
        path.to_path_buf()
    }
}

/// The nearest existing ancestor directory of `dir` (`dir` itself if it exists); an error
/// naming `flag` when `dir` or an ancestor exists but is not a directory.
fn existing_ancestor(dir: &Path, flag: &str) -> Result<PathBuf> {
    for a in dir.ancestors() {
        let a = if a.as_os_str().is_empty() {
            Path::new(".")
        } else {
            a
        };
        match std::fs::metadata(a) {
            Ok(m) if m.is_dir() => return Ok(a.to_path_buf()),
            Ok(_) => {
                return Err(Error::param(
                    flag,
                    format!(
                        "`{}` cannot be created: `{}` exists and is not a directory",
                        dir.display(),
                        a.display()
                    ),
                ))
            }
            Err(_) => continue,
        }
    }
    Ok(PathBuf::from("."))
}

impl OutputSet {
    /// An empty set; add targets with [`OutputSet::file`].
    pub fn new() -> Self {
        Self::default()
    }

    /// A set of files in the output directory `dir` (named by `flag` in errors). Checks now,
    /// before any computation, that `dir` is (or can be created as) a writable directory.
    pub fn in_dir(dir: &Path, flag: &str) -> Result<Self> {
        let mut set = Self::new();
        if dir.exists() && !dir.is_dir() {
            return Err(Error::param(
                flag,
                format!("`{}` exists and is not a directory", dir.display()),
            ));
        }
        set.staging_for(&with_dir(&dir.join("x")), flag)?;
        set.dir = Some((dir.to_path_buf(), flag.to_string()));
        Ok(set)
    }

    /// Declare the files of the output directory named `prefix…suffix` as this command's (one
    /// per level, pressure, …): those of an earlier run that this commit does not write are
    /// removed after it (module documentation). Only for a set made by [`OutputSet::in_dir`].
    /// An owned file that is one of the command's inputs is refused (now, and again at the
    /// commit): it would be overwritten or removed.
    pub fn owns(&mut self, prefix: &str, suffix: &str) -> Result<()> {
        debug_assert!(self.dir.is_some(), "owns() needs an output directory");
        self.owned.push((prefix.to_string(), suffix.to_string()));
        self.check_inputs()
    }

    /// Declare fixed file names this command writes into the output directory of
    /// [`OutputSet::in_dir`], so that an input among them is refused now, before the
    /// computation, rather than when the file is staged.
    pub fn writes(&mut self, names: &[&str]) -> Result<()> {
        debug_assert!(self.dir.is_some(), "writes() needs an output directory");
        self.names.extend(names.iter().map(|n| n.to_string()));
        self.check_inputs()
    }

    /// Declare an input file of the command (named by `role`, a flag or a description, in
    /// errors). No output of this set may be that file — compared by identity: canonical path,
    /// and device and inode, so a link is caught too — and no stale-file cleanup may remove it.
    /// Checked now against what is already known (staged files, [`OutputSet::writes`] names,
    /// owned files of the directory), and again for every file at staging and at the commit.
    /// An input that does not exist is ignored here (its reader reports it).
    pub fn input(&mut self, path: &Path, role: &str) -> Result<()> {
        if let Some(id) = std::fs::metadata(path).ok().and(FileIdentity::of(path)) {
            self.inputs.push(Input {
                path: path.to_path_buf(),
                role: role.to_string(),
                id,
            });
        }
        self.check_inputs()
    }

    /// [`OutputSet::input`] for several files of one role.
    pub fn inputs<P: AsRef<Path>>(
        &mut self,
        paths: impl IntoIterator<Item = P>,
        role: &str,
    ) -> Result<()> {
        for p in paths {
            self.input(p.as_ref(), role)?;
        }
        Ok(())
    }

    /// The input that `target` is, if any.
    fn input_at(&self, target: &Path) -> Option<(&Input, FileIdentity)> {
        if self.inputs.is_empty() {
            return None;
        }
        let id = FileIdentity::of(target)?;
        self.inputs.iter().find(|i| i.id.same(&id)).map(|i| (i, id))
    }

    /// Files of the output directory matching an owned pattern (candidates for removal).
    fn owned_files(&self) -> Vec<PathBuf> {
        let Some((dir, _)) = &self.dir else {
            return Vec::new();
        };
        if self.owned.is_empty() {
            return Vec::new();
        }
        let Ok(entries) = std::fs::read_dir(dir) else {
            return Vec::new();
        };
        entries
            .flatten()
            .filter(|e| {
                e.file_name().to_str().is_some_and(|text| {
                    self.owned.iter().any(|(pre, suf)| {
                        text.len() >= pre.len() + suf.len()
                            && text.starts_with(pre.as_str())
                            && text.ends_with(suf.as_str())
                    })
                })
            })
            .map(|e| e.path())
            .collect()
    }

    /// Refuse any known output (staged target, declared name, owned file of the directory)
    /// that is an input.
    fn check_inputs(&self) -> Result<()> {
        if self.inputs.is_empty() {
            return Ok(());
        }
        for (t, flag) in self.targets.iter().chain(&self.planned) {
            if let Some((i, id)) = self.input_at(t) {
                return Err(clash_error(t, flag, i, &id, Clash::Overwritten));
            }
        }
        if let Some((dir, flag)) = &self.dir {
            for name in &self.names {
                let t = dir.join(name);
                if let Some((i, id)) = self.input_at(&t) {
                    return Err(clash_error(&t, flag, i, &id, Clash::Overwritten));
                }
            }
            for t in self.owned_files() {
                if let Some((i, id)) = self.input_at(&t) {
                    return Err(clash_error(&t, flag, i, &id, Clash::Owned));
                }
            }
        }
        Ok(())
    }

    /// The owned files of the output directory that are not among `written` (removed after
    /// the commit).
    fn stale_files(&self, written: &[PathBuf]) -> Vec<PathBuf> {
        let Some((dir, _)) = &self.dir else {
            return Vec::new();
        };
        let Ok(dir) = dir.canonicalize() else {
            return Vec::new();
        };
        let fresh: std::collections::HashSet<std::ffi::OsString> = written
            .iter()
            .filter(|w| {
                w.parent()
                    .and_then(|p| p.canonicalize().ok())
                    .is_some_and(|p| p == dir)
            })
            .filter_map(|w| w.file_name().map(|n| n.to_os_string()))
            .collect();
        self.owned_files()
            .into_iter()
            .filter(|p| p.file_name().is_some_and(|n| !fresh.contains(n)) && p.is_file())
            .collect()
    }

    /// A set of explicitly named files (named by `flag` in errors), all checked now: none is an
    /// existing directory, none is given twice, and each one's directory is writable.
    pub fn for_files(paths: &[PathBuf], flag: &str) -> Result<Self> {
        let mut set = Self::new();
        for p in paths {
            set.stage(p, flag)?;
        }
        set.planned = std::mem::take(&mut set.targets);
        Ok(set)
    }

    /// The staging directory for files whose final directory lies below the existing
    /// ancestor of `target`'s directory; created (and checked writable) on first use.
    fn staging_for(&mut self, target: &Path, flag: &str) -> Result<(PathBuf, PathBuf)> {
        let parent = target.parent().unwrap_or(Path::new("."));
        let anchor = existing_ancestor(parent, flag)?;
        if let Some((a, s)) = self.stagings.iter().find(|(a, _)| *a == anchor) {
            return Ok((a.clone(), s.clone()));
        }
        let staging = tempfile::Builder::new()
            .prefix(".asperity-staging-")
            .tempdir_in(&anchor)
            .map_err(|e| {
                Error::param(
                    flag,
                    format!("cannot write into `{}`: {e}", anchor.display()),
                )
            })?
            .keep();
        register(&staging);
        self.stagings.push((anchor.clone(), staging.clone()));
        Ok((anchor, staging))
    }

    /// Stage `target` (named by `flag` in errors): returns the path to write it to now; it
    /// appears at `target` on [`OutputSet::commit`]. Refuses a target that is an existing
    /// directory or was already staged (e.g. a sidecar that would overwrite its data file).
    pub fn stage(&mut self, target: &Path, flag: &str) -> Result<PathBuf> {
        if target.is_dir() {
            return Err(Error::param(
                flag,
                format!("`{}` is a directory, not a file", target.display()),
            ));
        }
        let t = with_dir(target);
        if let Some((_, other)) = self.targets.iter().find(|(p, _)| with_dir(p) == t) {
            return Err(Error::param(
                flag,
                format!(
                    "`{}` would be written twice (also as {other}): one output would overwrite \
                     another",
                    target.display()
                ),
            ));
        }
        if let Some((i, id)) = self.input_at(target) {
            return Err(clash_error(target, flag, i, &id, Clash::Overwritten));
        }
        let (anchor, staging) = self.staging_for(&t, flag)?;
        let rel = t
            .strip_prefix(&anchor)
            .map_err(|_| Error::param(flag, format!("cannot stage `{}`", target.display())))?;
        self.targets.push((target.to_path_buf(), flag.to_string()));
        Ok(staging.join(rel))
    }

    /// Stage `target` (see [`OutputSet::stage`]) under the role `role` (used in errors).
    pub fn file(&mut self, target: &Path, role: &str) -> Result<PathBuf> {
        self.stage(target, role)
    }

    /// Stage the file `name` of the output directory of [`OutputSet::in_dir`].
    pub fn path(&mut self, name: &str) -> Result<PathBuf> {
        let (dir, flag) = self
            .dir
            .clone()
            .ok_or_else(|| Error::Data("output set has no directory".into()))?;
        self.stage(&dir.join(name), &format!("{flag} file `{name}`"))
    }

    /// The staging directory standing for the output directory of [`OutputSet::in_dir`], for
    /// library functions that write a set of files into a directory: everything written below
    /// it appears in the output directory on [`OutputSet::commit`].
    pub fn staging_dir(&mut self) -> Result<PathBuf> {
        let (dir, flag) = self
            .dir
            .clone()
            .ok_or_else(|| Error::Data("output set has no directory".into()))?;
        let marker = with_dir(&dir.join("x"));
        let (anchor, staging) = self.staging_for(&marker, &flag)?;
        let rel = with_dir(&dir)
            .strip_prefix(&anchor)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let staged = staging.join(rel);
        std::fs::create_dir_all(&staged).map_err(|e| Error::io(&dir, e))?;
        Ok(staged)
    }

    /// Where a staged file will appear (for messages written before the commit).
    pub fn final_path(&self, staged: &Path) -> PathBuf {
        for (anchor, staging) in &self.stagings {
            if let Ok(rel) = staged.strip_prefix(staging) {
                return anchor.join(rel);
            }
        }
        staged.to_path_buf()
    }

    /// Move every staged file into place, all or none: on a failed rename the files already
    /// moved are taken back and the previous files restored. Returns the final paths, sorted.
    pub fn commit(mut self) -> Result<Vec<PathBuf>> {
        let _commit = lock(&COMMIT);
        let mut moves: Vec<(PathBuf, PathBuf)> = Vec::new();
        for (anchor, staging) in &self.stagings {
            for f in files_below(staging) {
                let rel = f.strip_prefix(staging).expect("file below its staging dir");
                moves.push((f.clone(), anchor.join(rel)));
            }
        }
        moves.sort_by(|a, b| a.1.cmp(&b.1));
        // No input is written over or removed, whichever way the file came to be staged (a
        // library writer may have added a sidecar): checked before the first rename.
        let written: Vec<PathBuf> = moves.iter().map(|m| m.1.clone()).collect();
        let stale = self.stale_files(&written);
        let flag = |t: &Path| {
            self.targets
                .iter()
                .find(|(p, _)| with_dir(p) == with_dir(t))
                .map(|(_, f)| f.clone())
                .or_else(|| self.dir.as_ref().map(|(_, f)| f.clone()))
                .unwrap_or_else(|| "output".to_string())
        };
        for (t, how) in written
            .iter()
            .map(|t| (t, Clash::Overwritten))
            .chain(stale.iter().map(|t| (t, Clash::Removed)))
        {
            if let Some((i, id)) = self.input_at(t) {
                return Err(clash_error(t, &flag(t), i, &id, how));
            }
        }
        // (staged, target, backup of the previous target, directories created)
        let mut done: Vec<(PathBuf, PathBuf, Option<PathBuf>)> = Vec::new();
        let mut created: Vec<PathBuf> = Vec::new();
        let mut failure = None;
        for (k, (staged, target)) in moves.iter().enumerate() {
            let mut step = || -> Result<Option<PathBuf>> {
                if let Some(parent) = target.parent() {
                    for a in parent.ancestors().collect::<Vec<_>>().into_iter().rev() {
                        if !a.as_os_str().is_empty() && !a.exists() {
                            std::fs::create_dir(a).map_err(|e| Error::io(a, e))?;
                            created.push(a.to_path_buf());
                        }
                    }
                }
                let backup = if target.is_dir() {
                    return Err(Error::Data(format!(
                        "{}: is a directory; not replaced by an output file",
                        target.display()
                    )));
                } else if target.exists() {
                    let b = staged.with_file_name(format!(".asperity-previous-{k}"));
                    std::fs::rename(target, &b).map_err(|e| Error::io(target, e))?;
                    Some(b)
                } else {
                    None
                };
                if let Err(e) = std::fs::rename(staged, target) {
                    if let Some(b) = &backup {
                        let _ = std::fs::rename(b, target);
                    }
                    return Err(Error::io(target, e));
                }
                Ok(backup)
            };
            match step() {
                Ok(backup) => done.push((staged.clone(), target.clone(), backup)),
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
        }
        if let Some(e) = failure {
            for (staged, target, backup) in done.into_iter().rev() {
                let _ = std::fs::rename(&target, &staged);
                if let Some(b) = backup {
                    let _ = std::fs::rename(&b, &target);
                }
            }
            for d in created.iter().rev() {
                let _ = std::fs::remove_dir(d);
            }
            return Err(e);
        }
        self.committed = true;
        COMMITTED.store(true, Ordering::SeqCst);
        for (_, staging) in &self.stagings {
            remove_path(staging);
            deregister(staging);
        }
        for p in stale {
            let _ = std::fs::remove_file(p);
        }
        Ok(written)
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.committed {
            for (_, staging) in &self.stagings {
                remove_path(staging);
                deregister(staging);
            }
        }
    }
}

/// Every file below `dir` (recursively), sorted.
fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        if let Ok(rd) = std::fs::read_dir(&d) {
            for e in rd.flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    out.push(p);
                }
            }
        }
    }
    out.sort();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_writer_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.csv");
        let r = write_atomic(&p, |w| {
            w.write_all(b"half").unwrap();
            Err(Error::Data("boom".into()))
        });
        assert!(r.is_err());
        assert!(!p.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn an_output_set_appears_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("old.csv"), "previous").unwrap();
        std::fs::write(out.join("a.csv"), "previous a").unwrap();
        // An error before the commit: nothing new appears, the old files stay, nothing staged
        // is left over.
        {
            let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
            write_string_atomic(&set.path("a.csv").unwrap(), "new a").unwrap();
            write_string_atomic(&set.path("b.csv").unwrap(), "new b").unwrap();
        }
        let names = |d: &Path| {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        assert_eq!(names(&out), vec!["a.csv", "old.csv"]);
        assert_eq!(
            std::fs::read_to_string(out.join("a.csv")).unwrap(),
            "previous a"
        );
        // A commit: both appear.
        let mut set = OutputSet::in_dir(&out.join("sub"), "--out-dir").unwrap();
        write_string_atomic(&set.path("a.csv").unwrap(), "new a").unwrap();
        write_string_atomic(&set.path("b.csv").unwrap(), "new b").unwrap();
        let written = set.commit().unwrap();
        assert_eq!(written.len(), 2);
        assert_eq!(names(&out.join("sub")), vec!["a.csv", "b.csv"]);
        assert_eq!(names(&out), vec!["a.csv", "old.csv", "sub"]);
        // The same target twice is refused when staged.
        let mut set = OutputSet::new();
        set.file(&out.join("x.json"), "--out").unwrap();
        let e = set.file(&out.join("x.json"), "sidecar").unwrap_err();
        assert!(e.to_string().contains("written twice"), "{e}");
        // An --out-dir that is a file is refused before anything is computed.
        let e = OutputSet::in_dir(&out.join("old.csv"), "--out-dir").unwrap_err();
        assert!(e.to_string().contains("--out-dir"), "{e}");
        let e = OutputSet::in_dir(&out.join("old.csv").join("deeper"), "--out-dir").unwrap_err();
        assert!(e.to_string().contains("not a directory"), "{e}");
    }

    /// A second run with fewer levels leaves none of the first run's per-level files, and
    /// touches nothing else in the directory.
    #[test]
    fn owned_files_of_an_earlier_run_are_removed_after_the_commit() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let run = |levels: usize| {
            let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
            set.owns("level-", ".png").unwrap();
            for i in 1..=levels {
                write_string_atomic(&set.path(&format!("level-{i}.png")).unwrap(), "png").unwrap();
            }
            write_string_atomic(&set.path("report.txt").unwrap(), "r").unwrap();
            set.commit().unwrap();
        };
        run(3);
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        std::fs::write(out.join("level-notes.txt"), "mine too").unwrap();
        run(2);
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            vec![
                "level-1.png",
                "level-2.png",
                "level-notes.txt",
                "notes.txt",
                "report.txt"
            ]
        );
        // An uncommitted set removes nothing.
        {
            let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
            set.owns("level-", ".png").unwrap();
        }
        assert!(out.join("level-2.png").exists());
    }

    /// An output that is an input — by the same path, by another spelling of it, through a
    /// symbolic or a hard link, or as an owned file of an earlier run that the commit would
    /// remove — is refused naming both, and the input is left as it was.
    #[test]
    fn an_input_is_never_written_over_or_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let input = d.join("p.csv");
        std::fs::write(&input, "measured").unwrap();
        let intact = || assert_eq!(std::fs::read_to_string(&input).unwrap(), "measured");
        // The same path, and another spelling of it, at staging or when declared after it.
        let mut set = OutputSet::new();
        set.input(&input, "the profile").unwrap();
        let e = set.file(&input, "--psd-out").unwrap_err().to_string();
        assert!(
            e.contains("--psd-out") && e.contains("p.csv") && e.contains("the profile"),
            "{e}"
        );
        let mut set = OutputSet::for_files(&[d.join("sub/../p.csv")], "--out").unwrap();
        let e = set.input(&input, "SURFACE1").unwrap_err().to_string();
        assert!(e.contains("SURFACE1") && e.contains("overwritten"), "{e}");
        // Links: another name of the same file.
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&input, d.join("sym.csv")).unwrap();
            std::fs::hard_link(&input, d.join("hard.csv")).unwrap();
            for link in ["sym.csv", "hard.csv"] {
                let mut set = OutputSet::new();
                set.input(&input, "the profile").unwrap();
                let e = set.file(&d.join(link), "--out").unwrap_err().to_string();
                assert!(e.contains(link) && e.contains("a link"), "{link}: {e}");
            }
        }
        // An owned file of the directory: refused when declared, whatever the order.
        let out = d.join("out");
        std::fs::create_dir(&out).unwrap();
        let table = out.join("elements_level_3.csv");
        std::fs::write(&table, "table").unwrap();
        let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
        set.owns("elements_level_", ".csv").unwrap();
        let e = set
            .input(&table, "contact 1 elements")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("removed") && e.contains("elements_level_3.csv"),
            "{e}"
        );
        drop(set);
        let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
        set.input(&table, "contact 1 elements").unwrap();
        assert!(set.owns("elements_level_", ".csv").is_err());
        drop(set);
        // A fixed name declared with writes().
        let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
        set.input(&table, "contact 1 elements").unwrap();
        assert!(set.writes(&["elements_level_3.csv"]).is_err());
        drop(set);
        // A file a library writer puts into the staging directory (not declared): refused at
        // the commit, before anything is moved.
        let mut set = OutputSet::in_dir(&out, "--out-dir").unwrap();
        set.input(&table, "contact 1 elements").unwrap();
        let staged = set.staging_dir().unwrap();
        std::fs::write(staged.join("new.csv"), "new").unwrap();
        std::fs::write(staged.join("elements_level_3.csv"), "peaks").unwrap();
        assert!(set.commit().is_err());
        assert_eq!(std::fs::read_to_string(&table).unwrap(), "table");
        assert!(!out.join("new.csv").exists());
        intact();
        let left: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left.len(), 1, "{left:?}");
    }

    #[test]
    fn a_failed_rename_restores_the_previous_files() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.csv"), "old a").unwrap();
        let mut set = OutputSet::in_dir(dir.path(), "--out-dir").unwrap();
        write_string_atomic(&set.path("a.csv").unwrap(), "new a").unwrap();
        write_string_atomic(&set.path("z.csv").unwrap(), "new z").unwrap();
        // z.csv becomes a directory after staging: its rename fails, a.csv is restored.
        std::fs::create_dir(dir.path().join("z.csv")).unwrap();
        assert!(set.commit().is_err());
        assert_eq!(
            std::fs::read_to_string(dir.path().join("a.csv")).unwrap(),
            "old a"
        );
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left.len(), 2, "{left:?}");
    }

    #[test]
    fn files_via_path_are_readable_by_others() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.bin");
        write_atomic_via_path(&p, |t| std::fs::write(t, b"x").map_err(|e| Error::io(t, e)))
            .unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o644);
        }
    }

    #[test]
    fn successful_writer_creates_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub").join("out.txt");
        write_string_atomic(&p, "hello").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "hello");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o644);
        }
    }
}
