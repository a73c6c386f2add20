//! SHA-256 digests of files and bytes, as lowercase hex: the provenance every output records
//! for its inputs (FIPS 180-4, through the `sha2` crate).

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
