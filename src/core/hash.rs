//! SHA-256 digests of files and bytes, as lowercase hex: the provenance every output records
//! for its inputs (FIPS 180-4, through the `sha2` crate), and the provenance record itself
//! ([`InputFile`], [`provenance_json`]).

use crate::core::error::{Error, Result};
use sha2::{Digest, Sha256};
use std::fmt::Write;
use std::path::Path;

/// Hex SHA-256 of some bytes (64 lowercase hex digits).
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .fold(String::with_capacity(64), |mut s, b| {
            let _ = write!(s, "{b:02x}");
            s
        })
}

/// Hex SHA-256 of a file's bytes; an unreadable file is an error naming it.
pub fn sha256_file(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(sha256_hex(&bytes))
}

/// One input file in a provenance record.
#[derive(Debug, Clone, serde::Serialize)]
pub struct InputFile {
    /// What the file is to the command (e.g. "preload", "calibration_table", "image").
    pub role: String,
    /// Path as given.
    pub path: String,
    /// SHA-256 of the file's content (hex).
    pub sha256: String,
}

impl InputFile {
    /// Record `path` (hashing its content) under `role`.
    pub fn new(role: &str, path: &Path) -> Result<Self> {
        Ok(Self {
            role: role.to_string(),
            path: path.display().to_string(),
            sha256: sha256_file(path)?,
        })
    }
}

/// Provenance JSON written beside an output: tool, version, inputs with hashes, parameters and
/// a summary.
pub fn provenance_json(
    command: &str,
    inputs: &[InputFile],
    parameters: serde_json::Value,
    summary: serde_json::Value,
) -> serde_json::Value {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    serde_json::json!({
        "tool": "asperity",
        "crate_version": env!("CARGO_PKG_VERSION"),
        "command": command,
        "created_unix_s": now,
        "inputs": inputs,
        "parameters": parameters,
        "summary": summary,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FIPS 180-4 example: SHA-256("abc").
    #[test]
    fn digest_of_known_bytes() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
