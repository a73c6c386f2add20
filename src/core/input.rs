//! Reading tabular input (CSV with a header row) with errors that name the file and line.
//!
//! Every CSV reader of the crate (calibration tables, contact nodes, preloads, measured
//! records) opens its file through [`csv_reader`] and turns each record into
//! `(record, line)` through [`csv_record`], so malformed input is always reported the same way:
//! `file:line: message`.

use crate::core::error::{Error, Result};
use std::path::Path;

/// Open a CSV file with a header row: fields trimmed, lines starting with `#` skipped, every
/// record with as many fields as the header (otherwise [`csv_record`] fails with
/// `file:line: expected N fields, found M`). A row with more fields is refused rather than read
/// by position: `79.55,0.44,7,6,-0.16` is a decimal comma (7.6), not a response of 7 and a
/// phase of 6 rad.
pub fn csv_reader(path: &Path) -> Result<csv::Reader<std::fs::File>> {
    builder(false)
        .from_path(path)
        .map_err(|e| csv_error(path, e))
}

/// [`csv_reader`] with records of any length, for a reader that checks the field count itself
/// (the calibration table, which also skips lines of blanks; the measured records of
/// `diagnose`, whose message names the mismatch its own way).
pub fn csv_reader_any_length(path: &Path) -> Result<csv::Reader<std::fs::File>> {
    builder(true)
        .from_path(path)
        .map_err(|e| csv_error(path, e))
}

fn builder(flexible: bool) -> csv::ReaderBuilder {
    let mut b = csv::ReaderBuilder::new();
    b.has_headers(true)
        .flexible(flexible)
        .trim(csv::Trim::All)
        .comment(Some(b'#'));
    b
}

/// The message of a row whose field count differs from the header's.
pub fn field_count_message(expected: usize, found: usize) -> String {
    format!(
        "expected {expected} fields, found {found}{}",
        if found > expected {
            " (decimal comma?)"
        } else {
            ""
        }
    )
}

/// A CSV error as an [`Error`] naming the file and, where known, the 1-based line.
pub fn csv_error(path: &Path, e: csv::Error) -> Error {
    let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
    match e.into_kind() {
        csv::ErrorKind::Io(io) => Error::io(path, io),
        kind => Error::parse(path, line, csv_kind_message(kind)),
    }
}

fn csv_kind_message(kind: csv::ErrorKind) -> String {
    match kind {
        csv::ErrorKind::Utf8 { err, .. } => format!("invalid UTF-8: {err}"),
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => field_count_message(expected_len as usize, len as usize),
        csv::ErrorKind::Deserialize { err, .. } => err.to_string(),
        other => format!("{other:?}"),
    }
}

/// A record with its 1-based line number, or the CSV error naming file and line.
pub fn csv_record(
    path: &Path,
    rec: std::result::Result<csv::StringRecord, csv::Error>,
) -> Result<(csv::StringRecord, usize)> {
    let rec = rec.map_err(|e| csv_error(path, e))?;
    let line = rec.position().map(|p| p.line() as usize).unwrap_or(0);
    Ok((rec, line))
}

/// A TOML deserialisation error as an [`Error`] naming the file and the line of the offending
/// span (0 when unknown).
pub fn toml_error(path: &Path, text: &str, e: toml::de::Error) -> Error {
    let line = e
        .span()
        .map(|s| text[..s.start.min(text.len())].lines().count().max(1))
        .unwrap_or(0);
    Error::parse(path, line, e.message().trim().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_counted_from_the_file_start() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, "# comment\na,b\n1,2\n3,4\n").unwrap();
        let mut rdr = csv_reader(&p).unwrap();
        let lines: Vec<usize> = rdr
            .records()
            .map(|r| csv_record(&p, r).unwrap().1)
            .collect();
        assert_eq!(lines, vec![3, 4]);
        // A row with more or fewer fields than the header: refused with its line.
        for (row, msg) in [
            (
                "79.55,0.44,7,6",
                "t.csv:4: expected 3 fields, found 4 (decimal comma?)",
            ),
            ("1", "t.csv:4: expected 3 fields, found 1"),
        ] {
            std::fs::write(&p, format!("# c\na,b,c\n1,2,3\n{row}\n4,5,6\n")).unwrap();
            let mut rdr = csv_reader(&p).unwrap();
            let e = rdr
                .records()
                .map(|r| csv_record(&p, r).map(|_| ()))
                .collect::<Result<Vec<()>>>()
                .unwrap_err()
                .to_string();
            assert!(e.ends_with(msg), "{e}");
            let mut any = csv_reader_any_length(&p).unwrap();
            assert_eq!(any.records().count(), 3);
        }
        let e = csv_reader(&dir.path().join("missing.csv")).unwrap_err();
        assert!(e.to_string().contains("missing.csv"), "{e}");
    }
}
