//! Shared helpers of the text readers: decoding, line numbering, number parsing with errors
//! that name the file, the line and the column.

use crate::core::error::{Error, Result};
use std::path::Path;

/// Read a text file as UTF-8, falling back to Latin-1 (instrument exports often use it for `µ`).
/// Files above [`crate::core::limits::MAX_TEXT_FILE_BYTES`] are refused before they are read.
pub fn read_text(path: &Path) -> Result<String> {
    crate::core::limits::check_file_size(path, crate::core::limits::MAX_TEXT_FILE_BYTES)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}

/// Lines with their 1-based numbers (split at `\n`, trailing `\r`s removed).
pub fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
}

/// Split a data line at commas, semicolons, tabs or spaces (runs of blanks count once; empty
/// trailing fields after a comma are dropped).
pub fn fields(line: &str) -> Vec<&str> {
    let mut v: Vec<&str> = line
        .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
        .map(str::trim)
        .collect();
    v.retain(|f| !f.is_empty());
    v
}

/// Parse one numeric field; non-numbers and non-finite values are errors naming file, line and
/// column (1-based).
pub fn number(path: &Path, line: usize, col: usize, field: &str) -> Result<f64> {
    let v: f64 = field.parse().map_err(|_| {
        Error::parse(
            path,
            line,
            format!("column {col}: `{field}` is not a number"),
        )
    })?;
    if !v.is_finite() {
        return Err(Error::parse(
            path,
            line,
            format!("column {col}: non-finite value `{field}`"),
        ));
    }
    Ok(v)
}

/// Parse a height field that may be missing: `nan`/`NaN` (any case) is a missing point (NaN);
/// everything else as [`number`].
pub fn height_or_missing(path: &Path, line: usize, col: usize, field: &str) -> Result<f64> {
    if field.eq_ignore_ascii_case("nan") {
        Ok(f64::NAN)
    } else {
        number(path, line, col, field)
    }
}

/// The value of a `periodic:` header key: `true` or `false` (any case). Anything else (`yes`,
/// `1`, ...) is an error naming file and line, never silently read as false.
pub fn periodic_flag(path: &Path, line: usize, value: &str) -> Result<bool> {
    if value.eq_ignore_ascii_case("true") {
        Ok(true)
    } else if value.eq_ignore_ascii_case("false") {
        Ok(false)
    } else {
        Err(Error::parse(
            path,
            line,
            format!("`periodic: {value}`: expected `true` or `false`"),
        ))
    }
}

/// Whether every field of a line parses as a number.
pub fn is_numeric_line(line: &str) -> bool {
    let f = fields(line);
    !f.is_empty() && f.iter().all(|x| x.parse::<f64>().is_ok())
}

/// `key: value` pairs from a comment line (`# unit: m, dx_m: 1e-6`), keys lower-cased.
pub fn comment_pairs(line: &str) -> Vec<(String, String)> {
    let body = line.trim_start().trim_start_matches('#');
    body.split(',')
        .filter_map(|part| {
            let (k, v) = part.split_once(':').or_else(|| part.split_once('='))?;
            Some((k.trim().to_ascii_lowercase(), v.trim().to_string()))
        })
        .collect()
}
