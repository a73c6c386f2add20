//! Sharded sweeps: split a sweep of independent units over the jobs of a cluster scheduler
//! (`--shard i/n`, e.g. a Slurm job array) and merge their results into exactly the table a
//! single run writes.
//!
//! # The contract
//! A sweep is a list of **units** whose results do not depend on each other (one surface with
//! its whole warm-started load sweep, one calibration realisation, ...). The single run and
//! every shard compute unit `k` by the same code from the same configuration, and every solver
//! of the crate is thread-count independent, so a unit's result is the same bit for bit
//! wherever it runs. The flow is
//!
//! ```text
//! single run:  units 0..N            ─────────────────────────────► write_outputs(config, units)
//! shard i/n:   units of shard i ─► <kind>.shard-i-of-n.json ─┐
//!                                                             ├─ merge ─► write_outputs(config, units)
//! shard j/n:   units of shard j ─► <kind>.shard-j-of-n.json ─┘
//! ```
//!
//! Shard files are JSON; `f64` values are written by the shortest round-trip representation and
//! parsed with correct rounding (serde_json's `float_roundtrip`), so the merged results equal
//! the computed ones exactly and the merged table is byte-identical to the single run's.
//!
//! # Assignment
//! Shard `i` of `n` (1-based) holds the contiguous block of units
//! `[(i−1)·N/n, i·N/n)` (integer division): blocks differ in size by at most one unit, and a
//! shard beyond the number of units holds none (it still writes its file, so the merge can
//! check that every shard ran).
//!
//! # Checks at merge ([`merge`])
//! Every file must parse, be of the expected kind and format ([`FORMAT`]; files of the format
//! v1, which recorded no build, are refused), carry a configuration whose SHA-256 matches the
//! one it records, have been written by the same build as every other file ([`BuildId`]: crate
//! version, git commit and uncommitted changes, source hash, compiler, target, profile — a
//! unit's result is bit-identical only for the same code), share the configuration hash with
//! every other file (same inputs, same crate version), agree on `n`, and hold exactly its block
//! of units with the expected labels; every shard `1..=n` must be present exactly once; every
//! unit's result must pass the sweep's own check ([`ShardedSweep::check_unit`]: physical, and
//! computed from what the configuration prescribes for that unit). Each failure names the
//! files. Nothing is written unless all checks pass. The build of the shards is returned
//! ([`Merged::build`]); the merge itself may run another build (the CLI warns).
//!
//! # Adding a sharded sweep
//! Implement [`ShardedSweep`] for the sweep's configuration (serialisable, with one label per
//! unit and a check of one unit's result), give the CLI command a `--shard` flag that runs
//! [`run_units`] on the shard's block and [`write_shard`]s it (the single run calls
//! [`run_units`] with [`Shard::WHOLE`] and its output writer), and add the kind to `asperity
//! merge`, which calls [`merge`] and the same output writer.

use crate::core::build_info::BuildId;
use crate::core::error::{Error, Result};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Format tag written into every shard file. v2 records the build ([`ShardFile::build`]);
/// v1 files recorded only the crate version.
pub const FORMAT: &str = "asperity-shard-v2";

/// The previous format, refused with its own message (it cannot say which build wrote it).
const FORMAT_V1: &str = "asperity-shard-v1";

/// A sweep whose units can be computed independently.
pub trait ShardedSweep: Serialize + DeserializeOwned {
    /// Name of the sweep kind in shard files (e.g. `contact-normal`); also the file name prefix.
    const KIND: &'static str;
    /// The result of one unit (stored losslessly in shard files).
    type Unit: Serialize + DeserializeOwned;
    /// One label per unit, in unit order (e.g. `seed-3`); unique.
    fn unit_labels(&self) -> Vec<String>;
    /// Check one unit's result as read back from a shard file: the configuration is protected
    /// by its hash, the results are not, so an edited result (a negative stiffness, an area
    /// ratio above 1) would otherwise be merged as if computed. Where the result records what
    /// it was computed from (a seed, a grid, a surface source), that must be what the
    /// configuration prescribes for unit `unit.id`: results moved between units (their labels
    /// kept) are refused. The message names the field; [`merge`] adds the file and the unit.
    fn check_unit(&self, unit: &UnitRecord<Self::Unit>) -> std::result::Result<(), String>;
}

/// Shard `index` of `count` (1-based), as given by `--shard index/count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// The whole sweep as one shard (a single run).
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Check `1 ≤ index ≤ count`.
    pub fn new(index: usize, count: usize) -> Result<Self> {
        if count == 0 || index == 0 || index > count {
            return Err(Error::param(
                "shard",
                format!("must be i/n with 1 ≤ i ≤ n, got {index}/{count}"),
            ));
        }
        Ok(Self { index, count })
    }

    /// The units `[(i−1)·N/n, i·N/n)` of this shard among `total` units.
    pub fn units(&self, total: usize) -> Range<usize> {
        (self.index - 1) * total / self.count..self.index * total / self.count
    }

    /// Refuse more shards than `total` units: a shard would hold no unit (its file would be
    /// empty, and the run would do nothing). `what` names the units (e.g. `realisations`).
    /// With `count ≤ total` every shard holds at least one unit.
    pub fn check_units(&self, total: usize, what: &str) -> Result<()> {
        if self.count > total {
            return Err(Error::param(
                "shard",
                format!(
                    "{self}: {total} {what} cannot be split into {} shards (every shard needs \
                     one at least): at most {total}/{total}",
                    self.count
                ),
            ));
        }
        Ok(())
    }

    /// File name of this shard's results for sweeps of `kind`: `<kind>.shard-<i>-of-<n>.json`.
    pub fn file_name(&self, kind: &str) -> String {
        format!("{kind}.shard-{}-of-{}.json", self.index, self.count)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for Shard {
    type Err = Error;
    /// Parse `i/n` (e.g. `3/8`).
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            Error::param(
                "shard",
                format!("expected i/n with 1 ≤ i ≤ n (e.g. 3/8), got `{s}`"),
            )
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let i = i.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        Shard::new(i, n)
    }
}

/// One unit's result with its identity and the wall time it took (timings are reported but are
/// not part of the reproducible table).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnitRecord<R> {
    /// 0-based unit index.
    pub id: usize,
    /// Unit label (see [`ShardedSweep::unit_labels`]).
    pub label: String,
    /// Wall time of the unit (s).
    pub wall_time_s: f64,
    /// The unit's result.
    pub result: R,
}

/// The content of a shard file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardFile<C, R> {
    /// [`FORMAT`].
    pub format: String,
    /// [`ShardedSweep::KIND`].
    pub kind: String,
    /// The build that computed the results ([`BuildId::current`] of the shard's process).
    pub build: BuildId,
    /// [`config_sha256`] of `config`.
    pub config_sha256: String,
    /// Which shard this is.
    pub shard: Shard,
    /// Number of units of the whole sweep.
    pub units_total: usize,
    /// The configuration of the whole sweep.
    pub config: C,
    /// The results of this shard's units ([`UnitRecord`]s), in unit order.
    pub units: Vec<R>,
}

/// SHA-256 (hex) identifying a sweep: its kind, the crate version and the configuration's JSON.
/// Two shards with the same hash computed the same sweep with the same code version.
pub fn config_sha256<S: ShardedSweep>(config: &S) -> Result<String> {
    let json = serde_json::to_string(&serde_json::json!({
        "kind": S::KIND,
        "crate_version": env!("CARGO_PKG_VERSION"),
        "config": config,
    }))
    .map_err(|e| Error::Data(format!("cannot serialise the sweep configuration: {e}")))?;
    Ok(format!("{:x}", Sha256::digest(json.as_bytes())))
}

/// Check that the unit labels are unique (a label names one unit in every output).
pub fn check_labels(labels: &[String]) -> Result<()> {
    if labels.is_empty() {
        return Err(Error::param("units", "the sweep has no unit"));
    }
    let mut seen = std::collections::HashSet::new();
    for l in labels {
        if !seen.insert(l) {
            return Err(Error::param("units", format!("unit `{l}` given twice")));
        }
    }
    Ok(())
}

/// Run the units of `shard` in order: `run_unit(k)` computes unit `k`; `progress(done, total)`
/// is called after each unit of the shard.
pub fn run_units<S: ShardedSweep>(
    sweep: &S,
    shard: Shard,
    mut run_unit: impl FnMut(usize) -> Result<S::Unit>,
) -> Result<Vec<UnitRecord<S::Unit>>> {
    let labels = sweep.unit_labels();
    check_labels(&labels)?;
    shard
        .units(labels.len())
        .map(|k| {
            let start = std::time::Instant::now();
            let result = run_unit(k)?;
            Ok(UnitRecord {
                id: k,
                label: labels[k].clone(),
                wall_time_s: start.elapsed().as_secs_f64(),
                result,
            })
        })
        .collect()
}

/// Write the results of `shard` to `dir/<kind>.shard-<i>-of-<n>.json` (atomically) and return
/// the path. `units` must be exactly the shard's block (as [`run_units`] returns it).
pub fn write_shard<S: ShardedSweep>(
    dir: &Path,
    sweep: &S,
    shard: Shard,
    units: &[UnitRecord<S::Unit>],
) -> Result<PathBuf> {
    let total = sweep.unit_labels().len();
    let expected: Vec<usize> = shard.units(total).collect();
    let got: Vec<usize> = units.iter().map(|u| u.id).collect();
    if got != expected {
        return Err(Error::Data(format!(
            "shard {shard} must hold units {expected:?}, got {got:?}"
        )));
    }
    let file = ShardFile {
        format: FORMAT.to_string(),
        kind: S::KIND.to_string(),
        build: BuildId::current(),
        config_sha256: config_sha256(sweep)?,
        shard,
        units_total: total,
        config: sweep,
        units: units.iter().collect(),
    };
    let path = dir.join(shard.file_name(S::KIND));
    let text = serde_json::to_string_pretty(&file).map_err(|e| {
        Error::Data(format!(
            "{}: cannot serialise the shard (non-finite result?): {e}",
            path.display()
        ))
    })? + "\n";
    crate::core::output::write_string_atomic(&path, &text)?;
    Ok(path)
}

/// The header of a shard file (everything but the configuration and the results), for
/// dispatching on the kind and for the checks.
#[derive(Debug, Clone, Deserialize)]
struct ShardHeader {
    format: String,
    kind: String,
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::io(path, e))
}

/// The sweep kind recorded in a shard file (to choose the merge).
pub fn read_kind(path: &Path) -> Result<String> {
    let h: ShardHeader = serde_json::from_str(&read_text(path)?)
        .map_err(|e| Error::parse(path, e.line(), format!("not an asperity shard file: {e}")))?;
    if h.format == FORMAT_V1 {
        return Err(Error::parse(
            path,
            0,
            format!(
                "shard format `{FORMAT_V1}` records no build identity, so this asperity \
                 (format `{FORMAT}`) cannot check that all shards were computed by one build; \
                 rerun the shards with this binary"
            ),
        ));
    }
    if h.format != FORMAT {
        return Err(Error::parse(
            path,
            0,
            format!("shard format `{}`, expected `{FORMAT}`", h.format),
        ));
    }
    Ok(h.kind)
}

/// A shard file as read back.
type StoredShard<S> = ShardFile<S, UnitRecord<<S as ShardedSweep>::Unit>>;

/// The merged sweep: its configuration and every unit's result in unit order.
#[derive(Debug, Clone)]
pub struct Merged<S: ShardedSweep> {
    /// The sweep's configuration (the same in every shard).
    pub config: S,
    /// SHA-256 of the canonical configuration (hex), checked to agree across shards.
    pub config_sha256: String,
    /// The build that computed every shard (they agree).
    pub build: BuildId,
    /// Number of shard files merged.
    pub shards: usize,
    /// Every unit's result, in unit order.
    pub units: Vec<UnitRecord<S::Unit>>,
}

/// Read and check the shard files of one sweep (see the module documentation for the checks,
/// and [`ShardedSweep::check_unit`] on every unit read) and return every unit in order. Errors
/// name the files concerned and, for a result, the unit.
pub fn merge<S: ShardedSweep>(paths: &[PathBuf]) -> Result<Merged<S>> {
    if paths.is_empty() {
        return Err(Error::param("shards", "no shard file given"));
    }
    let mut files: Vec<(PathBuf, StoredShard<S>)> = Vec::with_capacity(paths.len());
    for path in paths {
        let kind = read_kind(path)?;
        if kind != S::KIND {
            return Err(Error::parse(
                path,
                0,
                format!("a `{kind}` shard, expected `{}`", S::KIND),
            ));
        }
        let file: StoredShard<S> = serde_json::from_str(&read_text(path)?)
            .map_err(|e| Error::parse(path, e.line(), format!("malformed shard file: {e}")))?;
        // The `shard` field is not covered by the configuration's hash: an edited i/n must not
        // index out of range (a panic) or size the shard table (a count of 1e15 aborted).
        Shard::new(file.shard.index, file.shard.count)
            .map_err(|e| Error::parse(path, 0, format!("`shard`: {e}")))?;
        let units = file.config.unit_labels().len();
        if file.shard.count > units.max(paths.len()) {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "`shard` {}: more shards than the sweep's {units} units and the {} file(s) \
                     given: the file was edited",
                    file.shard,
                    paths.len()
                ),
            ));
        }
        let recomputed = config_sha256(&file.config)?;
        if recomputed != file.config_sha256 {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "its configuration hashes to {recomputed}, not the recorded {} \
                     (edited or computed by another asperity version than this one, {})",
                    file.config_sha256,
                    env!("CARGO_PKG_VERSION")
                ),
            ));
        }
        files.push((path.clone(), file));
    }
    let (first_path, first) = &files[0];
    let count = first.shard.count;
    let labels = first.config.unit_labels();
    check_labels(&labels)?;
    let mut by_index: Vec<Option<usize>> = vec![None; count];
    for (f, (path, file)) in files.iter().enumerate() {
        if file.build != first.build {
            return Err(Error::Data(format!(
                "shards of different builds: {} was computed by {}; {} by {}. A unit's results \
                 are the same bit for bit only for the same code: rerun the shards with one \
                 binary (scripts/slurm/submit-sweep.sh copies it for the whole array)",
                first_path.display(),
                first.build.describe(),
                path.display(),
                file.build.describe()
            )));
        }
        if file.config_sha256 != first.config_sha256 {
            return Err(Error::Data(format!(
                "shards of different configurations: {} has configuration {} (asperity {}), {} has {} (asperity {}); rerun the shards with identical inputs",
                first_path.display(),
                &first.config_sha256[..12],
                first.build.crate_version,
                path.display(),
                &file.config_sha256[..12],
                file.build.crate_version
            )));
        }
        if file.shard.count != count {
            return Err(Error::Data(format!(
                "shards of different splits: {} is shard {}, {} is shard {}",
                first_path.display(),
                first.shard,
                path.display(),
                file.shard
            )));
        }
        let slot = &mut by_index[file.shard.index - 1];
        if let Some(other) = *slot {
            return Err(Error::Data(format!(
                "shard {} given twice: {} and {}",
                file.shard,
                files[other].0.display(),
                path.display()
            )));
        }
        *slot = Some(f);
        if file.units_total != labels.len() {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "records units_total = {}, but its configuration has {} units: the file \
                     was edited",
                    file.units_total,
                    labels.len()
                ),
            ));
        }
        let expected: Vec<usize> = file.shard.units(labels.len()).collect();
        let got: Vec<usize> = file.units.iter().map(|u| u.id).collect();
        if got != expected {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "shard {} of {} units must hold units {expected:?}, holds {got:?}",
                    file.shard,
                    labels.len()
                ),
            ));
        }
        if let Some(u) = file.units.iter().find(|u| u.label != labels[u.id]) {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "unit {} is labelled `{}`, the configuration says `{}`",
                    u.id, u.label, labels[u.id]
                ),
            ));
        }
        for u in &file.units {
            file.config.check_unit(u).map_err(|m| {
                Error::parse(path, 0, format!("unit {} (`{}`): {m}", u.id, u.label))
            })?;
        }
    }
    let missing: Vec<String> = by_index
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_none())
        .map(|(i, _)| {
            Shard {
                index: i + 1,
                count,
            }
            .file_name(S::KIND)
        })
        .collect();
    if !missing.is_empty() {
        return Err(Error::Data(format!(
            "{} of {count} shards missing: {} (given: {})",
            missing.len(),
            missing.join(", "),
            paths
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let config_sha256 = first.config_sha256.clone();
    let build = first.build.clone();
    files.sort_by_key(|(_, f)| f.shard.index);
    let mut units = Vec::with_capacity(labels.len());
    let mut config = None;
    for (_, file) in files {
        units.extend(file.units);
        config.get_or_insert(file.config);
    }
    Ok(Merged {
        config: config.expect("at least one shard"),
        config_sha256,
        build,
        shards: count,
        units,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A toy sweep: unit k squares `values[k]`.
    #[derive(Debug, Clone, Serialize, Deserialize)]
    struct Squares {
        values: Vec<f64>,
    }

    impl ShardedSweep for Squares {
        const KIND: &'static str = "squares";
        type Unit = f64;
        fn unit_labels(&self) -> Vec<String> {
            (0..self.values.len()).map(|k| format!("v{k}")).collect()
        }
        fn check_unit(&self, u: &UnitRecord<f64>) -> std::result::Result<(), String> {
            if u.result >= 0.0 {
                Ok(())
            } else {
                Err(format!("`result` = {} is a negative square", u.result))
            }
        }
    }

    fn run_shard(dir: &Path, sweep: &Squares, shard: Shard) -> PathBuf {
        let units = run_units(sweep, shard, |k| Ok(sweep.values[k] * sweep.values[k])).unwrap();
        write_shard(dir, sweep, shard, &units).unwrap()
    }

    #[test]
    fn parse_and_assignment() {
        assert_eq!("3/8".parse::<Shard>().unwrap(), Shard::new(3, 8).unwrap());
        for bad in ["0/4", "5/4", "1/0", "2", "a/b", "1/2/3", ""] {
            let e = bad.parse::<Shard>().unwrap_err().to_string();
            assert!(e.contains("shard"), "{bad}: {e}");
        }
        // Blocks cover 0..N once, sizes differ by at most one.
        for total in [0, 1, 5, 7, 16] {
            for count in 1..=9 {
                let blocks: Vec<Range<usize>> = (1..=count)
                    .map(|i| Shard::new(i, count).unwrap().units(total))
                    .collect();
                let flat: Vec<usize> = blocks.iter().flat_map(|r| r.clone()).collect();
                assert_eq!(flat, (0..total).collect::<Vec<_>>());
                let (lo, hi) = (
                    blocks.iter().map(|r| r.len()).min().unwrap(),
                    blocks.iter().map(|r| r.len()).max().unwrap(),
                );
                assert!(hi - lo <= 1, "{total} units over {count}");
            }
        }
    }

    /// Values whose decimal forms are awkward survive the shard file bit for bit.
    #[test]
    fn merge_restores_every_bit() {
        let dir = tempfile::tempdir().unwrap();
        let values = vec![
            0.1 + 0.2,
            1.0 / 3.0,
            f64::MIN_POSITIVE / 3.0, // subnormal after squaring → 0, before it is exact
            1e-300_f64.sqrt(),
            -2.718281828459045e-12,
            123456789.12345679,
            7.0,
        ];
        let sweep = Squares { values };
        let whole = run_units(&sweep, Shard::WHOLE, |k| Ok(sweep.values[k].powi(2))).unwrap();
        let paths: Vec<PathBuf> = (1..=3)
            .map(|i| run_shard(dir.path(), &sweep, Shard::new(i, 3).unwrap()))
            .rev()
            .collect();
        let merged = merge::<Squares>(&paths).unwrap();
        assert_eq!(merged.shards, 3);
        let a: Vec<u64> = whole.iter().map(|u| u.result.to_bits()).collect();
        let b: Vec<u64> = merged.units.iter().map(|u| u.result.to_bits()).collect();
        assert_eq!(a, b);
        assert_eq!(
            merged.units.iter().map(|u| u.id).collect::<Vec<_>>(),
            (0..7).collect::<Vec<_>>()
        );
    }

    #[test]
    fn missing_duplicate_and_foreign_shards_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = Squares {
            values: vec![1.0, 2.0, 3.0, 4.0],
        };
        let p: Vec<PathBuf> = (1..=3)
            .map(|i| run_shard(dir.path(), &sweep, Shard::new(i, 3).unwrap()))
            .collect();
        // Missing.
        let e = merge::<Squares>(&p[..2]).unwrap_err().to_string();
        assert!(
            e.contains("squares.shard-3-of-3.json") && e.contains("missing"),
            "{e}"
        );
        // Duplicated (a copy under another name).
        let copy = dir.path().join("copy.json");
        std::fs::copy(&p[1], &copy).unwrap();
        let e = merge::<Squares>(&[p[0].clone(), p[1].clone(), copy.clone(), p[2].clone()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("given twice") && e.contains("copy.json"), "{e}");
        // Another configuration.
        let other_dir = tempfile::tempdir().unwrap();
        let other = Squares {
            values: vec![1.0, 2.0, 3.0, 5.0],
        };
        let q = run_shard(other_dir.path(), &other, Shard::new(3, 3).unwrap());
        let e = merge::<Squares>(&[p[0].clone(), p[1].clone(), q.clone()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("different configurations"), "{e}");
        assert!(e.contains(&q.display().to_string()), "{e}");
        // Different split.
        let r = run_shard(other_dir.path(), &sweep, Shard::new(2, 2).unwrap());
        let e = merge::<Squares>(&[p[0].clone(), r])
            .unwrap_err()
            .to_string();
        assert!(e.contains("different splits"), "{e}");
        // An edited configuration is caught by its hash.
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&p[0]).unwrap()).unwrap();
        json["config"]["values"][0] = serde_json::json!(1.5);
        let edited = dir.path().join("edited.json");
        std::fs::write(&edited, json.to_string()).unwrap();
        let e = merge::<Squares>(&[edited, p[1].clone(), p[2].clone()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("edited.json") && e.contains("hashes to"), "{e}");
        // An edited `shard` field (not covered by the hash): refused naming the file, never
        // an out-of-range index or a table sized by a huge count.
        for (index, count) in [(0u64, 3u64), (5, 3), (1, 0), (1, 1_000_000_000_000_000)] {
            let mut json: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&p[0]).unwrap()).unwrap();
            json["shard"] = serde_json::json!({"index": index, "count": count});
            let edited = dir.path().join("shard-edited.json");
            std::fs::write(&edited, json.to_string()).unwrap();
            let e = merge::<Squares>(&[edited, p[1].clone(), p[2].clone()])
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("shard-edited.json") && e.contains("`shard`"),
                "{index}/{count}: {e}"
            );
        }
        // Not a shard file.
        let junk = dir.path().join("junk.json");
        std::fs::write(&junk, "{\"a\": 1}").unwrap();
        let e = merge::<Squares>(&[junk]).unwrap_err().to_string();
        assert!(
            e.contains("junk.json") && e.contains("not an asperity shard"),
            "{e}"
        );
    }

    /// An edited result is refused by the unit check, and an edited units_total says so.
    #[test]
    fn edited_results_are_refused_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = Squares {
            values: vec![1.0, 2.0, 3.0, 4.0],
        };
        let p: Vec<PathBuf> = (1..=2)
            .map(|i| run_shard(dir.path(), &sweep, Shard::new(i, 2).unwrap()))
            .collect();
        assert!(merge::<Squares>(&p).is_ok());
        let mut json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&p[1]).unwrap()).unwrap();
        json["units"][1]["result"] = serde_json::json!(-16.0);
        std::fs::write(&p[1], json.to_string()).unwrap();
        let e = merge::<Squares>(&p).unwrap_err().to_string();
        assert!(
            e.contains("squares.shard-2-of-2.json") && e.contains("unit 3 (`v3`)"),
            "{e}"
        );
        json["units"][1]["result"] = serde_json::json!(16.0);
        json["units_total"] = serde_json::json!(5);
        std::fs::write(&p[1], json.to_string()).unwrap();
        let e = merge::<Squares>(&p).unwrap_err().to_string();
        assert!(
            e.contains("units_total = 5") && e.contains("4 units") && !e.contains("holds"),
            "{e}"
        );
    }

    /// Shards of two builds (here: one file's build edited to another commit, as a rebuilt
    /// binary writes it) are refused naming both files and both builds; a v1 file (no build
    /// recorded) is refused saying so.
    #[test]
    fn shards_of_different_builds_and_v1_files_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = Squares {
            values: vec![1.0, 2.0, 3.0],
        };
        let p: Vec<PathBuf> = (1..=2)
            .map(|i| run_shard(dir.path(), &sweep, Shard::new(i, 2).unwrap()))
            .collect();
        let merged = merge::<Squares>(&p).unwrap();
        assert_eq!(merged.build, BuildId::current());
        let text = std::fs::read_to_string(&p[1]).unwrap();
        let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(json["format"], FORMAT);
        let ours = BuildId::current();
        let other = BuildId {
            git_commit: Some("0123456789abcdef0123456789abcdef01234567".into()),
            git_dirty: Some(false),
            source_sha256: "cd".repeat(32),
            ..ours.clone()
        };
        json["build"] = serde_json::to_value(&other).unwrap();
        let rebuilt = dir.path().join("rebuilt.json");
        std::fs::write(&rebuilt, json.to_string()).unwrap();
        let e = merge::<Squares>(&[p[0].clone(), rebuilt.clone()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("different builds"), "{e}");
        assert!(
            e.contains("squares.shard-1-of-2.json") && e.contains("rebuilt.json"),
            "{e}"
        );
        assert!(
            e.contains(&ours.describe()) && e.contains(&other.describe()),
            "{e}"
        );
        assert!(
            e.contains("0123456789ab") && e.contains("cdcdcdcdcdcd"),
            "{e}"
        );
        // Any field counts: the same commit built by another compiler is another build.
        json["build"] = serde_json::to_value(BuildId {
            rustc: "rustc 1.0.0".into(),
            ..ours.clone()
        })
        .unwrap();
        std::fs::write(&rebuilt, json.to_string()).unwrap();
        let e = merge::<Squares>(&[p[0].clone(), rebuilt.clone()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("different builds") && e.contains("rustc 1.0.0"),
            "{e}"
        );
        // A v1 file: the crate version where v2 has the build.
        let mut v1: serde_json::Value = serde_json::from_str(&text).unwrap();
        let obj = v1.as_object_mut().unwrap();
        obj.remove("build");
        obj.insert("crate_version".into(), serde_json::json!("0.1.0"));
        obj.insert("format".into(), serde_json::json!("asperity-shard-v1"));
        let old = dir.path().join("old.json");
        std::fs::write(&old, v1.to_string()).unwrap();
        let e = merge::<Squares>(&[p[0].clone(), old])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("old.json")
                && e.contains("asperity-shard-v1")
                && e.contains("no build")
                && e.contains("rerun the shards"),
            "{e}"
        );
    }

    #[test]
    fn empty_shards_are_written_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let sweep = Squares {
            values: vec![1.0, 2.0],
        };
        let p: Vec<PathBuf> = (1..=4)
            .map(|i| run_shard(dir.path(), &sweep, Shard::new(i, 4).unwrap()))
            .collect();
        let merged = merge::<Squares>(&p).unwrap();
        assert_eq!(
            merged.units.iter().map(|u| u.result).collect::<Vec<_>>(),
            vec![1.0, 4.0]
        );
    }
}
