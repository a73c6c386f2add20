//! Locating the shared reference data (`../shared/data`) from tests.
//!
//! Tests find the folder through `ASPERITY_DATA_DIR` (default `../shared/data` relative to the
//! crate root). Where a file is missing the test prints a message and skips, unless
//! `ASPERITY_REQUIRE_DATA=1` (set by `.ci/run`), in which case it panics so CI fails.

use std::path::PathBuf;

/// The reference data directory.
pub fn data_dir() -> PathBuf {
    match std::env::var_os("ASPERITY_DATA_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    }
}

/// Path of a reference file such as `topography/dektak-1.csv`, or `None` (with a message) when it
/// is absent and data is not required. Panics when absent and `ASPERITY_REQUIRE_DATA=1`.
pub fn reference_file(relative: &str) -> Option<PathBuf> {
    let p = data_dir().join(relative);
    if p.exists() {
        return Some(p);
    }
    let required = std::env::var("ASPERITY_REQUIRE_DATA").is_ok_and(|v| v == "1");
    if required {
        panic!(
            "reference data file {} is missing and ASPERITY_REQUIRE_DATA=1",
            p.display()
        );
    }
    eprintln!(
        "SKIP: reference data file {} not found (set ASPERITY_DATA_DIR)",
        p.display()
    );
    None
}
