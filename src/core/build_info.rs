//! The identity of the build that is running ([`BuildId::current`]), embedded by `build.rs`:
//! crate version, git commit with a flag for uncommitted changes to the build inputs, a SHA-256
//! of the build inputs (`src/`, `build.rs`, `Cargo.toml`, `Cargo.lock`), compiler, target and
//! profile.
//!
//! Every shard file of a sharded sweep records it and [`crate::core::shard::merge`] refuses shards of
//! different builds: a unit's result is the same bit for bit only when computed by the same
//! code, and the crate version has stayed the same across many commits. Without git (a build
//! from a tarball) the commit is absent and the source hash still tells two builds apart; two
//! builds are the same when every field is equal.

use serde::{Deserialize, Serialize};

/// Which build computed a result. Two builds are the same when all fields are equal.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildId {
    /// Version of the crate (`Cargo.toml`).
    pub crate_version: String,
    /// `git rev-parse HEAD` of the checkout the crate was built from; `None` without git (a
    /// tarball, a vendored copy).
    pub git_commit: Option<String>,
    /// Whether the build inputs differed from that commit (uncommitted changes); `None`
    /// without git.
    pub git_dirty: Option<bool>,
    /// SHA-256 over the build inputs (every file under `src/`, `build.rs`, `Cargo.toml`,
    /// `Cargo.lock`; see `build.rs`).
    pub source_sha256: String,
    /// `rustc --version` of the compiler.
    pub rustc: String,
    /// Target triple.
    pub target: String,
    /// Cargo profile (`release`, `debug`).
    pub profile: String,
}

impl BuildId {
    /// The build of this binary.
    pub fn current() -> Self {
        let commit = env!("ASPERITY_BUILD_GIT_COMMIT");
        Self {
            crate_version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: (!commit.is_empty()).then(|| commit.to_string()),
            git_dirty: match env!("ASPERITY_BUILD_GIT_DIRTY") {
                "1" => Some(true),
                "0" => Some(false),
                _ => None,
            },
            source_sha256: env!("ASPERITY_BUILD_SOURCE_SHA256").to_string(),
            rustc: env!("ASPERITY_BUILD_RUSTC").to_string(),
            target: env!("ASPERITY_BUILD_TARGET").to_string(),
            profile: env!("ASPERITY_BUILD_PROFILE").to_string(),
        }
    }

    /// One line for messages, e.g. `asperity 0.1.0, commit 8dfc5e3a1b2c (uncommitted changes),
    /// sources 3f2a…, rustc 1.95.0 (59807616e 2026-04-14), x86_64-unknown-linux-gnu, release`.
    pub fn describe(&self) -> String {
        let git = match (&self.git_commit, self.git_dirty) {
            (Some(c), Some(true)) => format!("commit {} (uncommitted changes)", short(c)),
            (Some(c), _) => format!("commit {}", short(c)),
            (None, _) => "no git commit".to_string(),
        };
        format!(
            "asperity {}, {git}, sources {}, {}, {}, {}",
            self.crate_version,
            short(&self.source_sha256),
            self.rustc,
            self.target,
            self.profile
        )
    }
}

/// The first 12 characters of a hash.
fn short(hash: &str) -> &str {
    hash.get(..12).unwrap_or(hash)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_current_build_is_identified() {
        let b = BuildId::current();
        assert_eq!(b.crate_version, env!("CARGO_PKG_VERSION"));
        assert_eq!(b.source_sha256.len(), 64, "{b:?}");
        assert!(b.source_sha256.chars().all(|c| c.is_ascii_hexdigit()));
        assert_eq!(b.git_commit.is_some(), b.git_dirty.is_some(), "{b:?}");
        if let Some(c) = &b.git_commit {
            assert!(
                c.len() >= 40 && c.chars().all(|c| c.is_ascii_hexdigit()),
                "{c}"
            );
        }
        assert!(!b.target.is_empty() && !b.profile.is_empty(), "{b:?}");
        let d = b.describe();
        assert!(
            d.contains(&b.source_sha256[..12]) && d.contains(&b.target),
            "{d}"
        );
        // Round trip through a shard file's JSON.
        let back: BuildId = serde_json::from_str(&serde_json::to_string(&b).unwrap()).unwrap();
        assert_eq!(back, b);
    }

    #[test]
    fn descriptions_tell_builds_apart() {
        let b = BuildId {
            crate_version: "0.1.0".into(),
            git_commit: Some("8dfc5e3a1b2c3d4e5f60718293a4b5c6d7e8f901".into()),
            git_dirty: Some(true),
            source_sha256: "ab".repeat(32),
            rustc: "rustc 1.95.0".into(),
            target: "x86_64-unknown-linux-gnu".into(),
            profile: "release".into(),
        };
        assert_eq!(
            b.describe(),
            "asperity 0.1.0, commit 8dfc5e3a1b2c (uncommitted changes), sources abababababab, \
             rustc 1.95.0, x86_64-unknown-linux-gnu, release"
        );
        let tarball = BuildId {
            git_commit: None,
            git_dirty: None,
            ..b
        };
        assert!(tarball.describe().contains("no git commit"));
    }
}
