//! CSV tables through the `csv` crate: typed rows (`#[derive(Serialize)]`, the field names
//! are the header) or dynamic ones; fields quoted only where RFC 4180 needs it, numbers
//! with round-trip precision ([`RoundTrip`]).

use super::{write_atomic, OutputError};
use serde::{Serialize, Serializer};
use std::path::Path;

/// Formats a float so that it parses back to the same value (shortest round-trip
/// digits); plain notation for moderate magnitudes, scientific otherwise.
pub fn fmt_f64(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e15).contains(&a) || !v.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A float serialised as [`fmt_f64`] writes it (the `csv` crate's own float format would
/// write `1.0` for `1` and plain digits for `1e300`): the number type of CSV rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundTrip(pub f64);

impl Serialize for RoundTrip {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&fmt_f64(self.0))
    }
}

/// A CSV writer into memory: comma-separated, `\n`-terminated, quoting only fields with a
/// comma, quote or line break.
fn writer(headers: bool) -> ::csv::Writer<Vec<u8>> {
    ::csv::WriterBuilder::new()
        .has_headers(headers)
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new())
}

/// The bytes written so far by `w`, or an error about `path`.
fn finish(path: &Path, w: ::csv::Writer<Vec<u8>>) -> Result<Vec<u8>, OutputError> {
    w.into_inner()
        .map_err(|e| OutputError::data(path, format!("CSV encoding failed: {}", e.error())))
}

/// Maps a `csv` crate error to an [`OutputError`] about `path`.
fn csv_error(path: &Path) -> impl Fn(::csv::Error) -> OutputError + '_ {
    move |e| OutputError::data(path, format!("CSV encoding failed: {e}"))
}

/// Writes typed rows as CSV: the header row holds the field names of `R`, each row one
/// record (numbers as [`RoundTrip`] keep the round-trip format). The header is taken from
/// the first row, so with no rows the file is empty.
pub fn write_rows<R: Serialize>(path: &Path, rows: &[R]) -> Result<(), OutputError> {
    let mut w = writer(true);
    rows.iter()
        .try_for_each(|r| w.serialize(r))
        .map_err(csv_error(path))?;
    write_atomic(path, &finish(path, w)?)
}

/// Writes a header record and records of already-formatted fields.
fn write_records<S: AsRef<[u8]>, R: IntoIterator<Item: AsRef<[u8]>>>(
    path: &Path,
    headers: &[S],
    records: impl Iterator<Item = R>,
) -> Result<(), OutputError> {
    let mut w = writer(false);
    w.write_record(headers).map_err(csv_error(path))?;
    for r in records {
        w.write_record(r).map_err(csv_error(path))?;
    }
    write_atomic(path, &finish(path, w)?)
}

/// Writes numeric columns as CSV with a header row. All columns must have the same
/// length and there must be one header per column. Values are written with
/// round-trip precision; NaN and infinities as `NaN`, `inf`, `-inf`.
pub fn write_csv(path: &Path, headers: &[&str], columns: &[&[f64]]) -> Result<(), OutputError> {
    if headers.len() != columns.len() {
        return Err(OutputError::data(
            path,
            format!("{} headers for {} columns", headers.len(), columns.len()),
        ));
    }
    let rows = columns.first().map_or(0, |c| c.len());
    if let Some(i) = columns.iter().position(|c| c.len() != rows) {
        return Err(OutputError::data(
            path,
            format!(
                "column {:?} has {} values but column {:?} has {rows}",
                headers[i],
                columns[i].len(),
                headers[0]
            ),
        ));
    }
    let records = (0..rows).map(|r| columns.iter().map(move |c| fmt_f64(c[r])));
    write_records(path, headers, records)
}

/// Writes a table of already-formatted fields (mixed text and numbers) as CSV.
/// Every row must have one field per header.
pub fn write_csv_rows(
    path: &Path,
    headers: &[String],
    rows: &[Vec<String>],
) -> Result<(), OutputError> {
    if let Some(i) = rows.iter().position(|r| r.len() != headers.len()) {
        return Err(OutputError::data(
            path,
            format!(
                "row {i} has {} fields but there are {} headers",
                rows[i].len(),
                headers.len()
            ),
        ));
    }
    write_records(path, headers, rows.iter())
}
