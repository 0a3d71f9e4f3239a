//! Data-file inputs: NPY, CSV and JSON, read beneath an input directory opened once.
//!
//! An [`InputRoot`] is the read-side twin of [`crate::io::OutputRoot`]: the directory is opened
//! once with cap-std, and every file is opened relative to that handle with openat-style
//! lookups, so a symlink leading out of it (even one swapped while a script runs) is refused
//! at the moment of use. Files are bounded: one larger than the caller's limit is refused
//! before it is read, naming its size. The parsers refuse malformed files with the file, the
//! place (row, column, header field) and what was found; non-finite numbers are refused too.

mod npy_header;

use std::io::Read as _;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// Failure to read a data file; every variant names the path.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// An operating-system call failed (`op` says which).
    #[error("cannot {op} {path}: {source}", path = .path.display())]
    Io {
        /// What was being done.
        op: &'static str,
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The path is absolute, has `..`, or leads out of the input directory through a symlink.
    #[error("data path '{path}' leads outside the data directory {root} ({why}); refused", root = .root.display())]
    Outside {
        /// The path as given.
        path: String,
        /// The input root.
        root: PathBuf,
        /// Why: absolute, `..`, or a symlink.
        why: &'static str,
    },
    /// The file is larger than the read limit.
    #[error("data file {path} is {size}, above the read limit {limit} ({why})", path = .path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size, formatted.
        size: String,
        /// The limit, formatted.
        limit: String,
        /// Where the limit comes from.
        why: String,
    },
    /// The contents are not a valid file of the expected format.
    #[error("cannot read {path}: {message}", path = .path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where.
        message: String,
    },
}

impl InputError {
    fn format(path: &Path, message: impl Into<String>) -> Self {
        InputError::Format {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// `rel` as a path to resolve beneath a root: relative and without `..` (None otherwise).
fn beneath(rel: &str) -> Option<&Path> {
    let p = Path::new(rel);
    let plain = p
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    (!p.has_root() && plain).then_some(p)
}

/// Opens `rel` beneath `dir` for reading without blocking: with `O_NONBLOCK` on Unix, so that
/// a FIFO put in place of a regular file opens at once (and is then refused by its
/// `fstat`) instead of waiting for a writer. Reads of a regular file ignore the flag.
fn open_regular(dir: &cap_std::fs::Dir, rel: &Path) -> std::io::Result<cap_std::fs::File> {
    let mut options = cap_std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use cap_std::fs::OpenOptionsExt as _;
        options.custom_flags(libc::O_NONBLOCK);
    }
    dir.open_with(rel, &options)
}

/// The refusal of a data path that is not a regular file, naming what it is.
fn not_regular(path: &Path, kind: &cap_std::fs::FileType) -> InputError {
    #[cfg(unix)]
    let fifo = {
        use cap_std::fs::FileTypeExt as _;
        kind.is_fifo()
    };
    #[cfg(not(unix))]
    let fifo = false;
    let what = if kind.is_dir() {
        "a directory"
    } else if fifo {
        "a FIFO (named pipe)"
    } else {
        "not a regular file (a device or a socket)"
    };
    InputError::format(
        path,
        format!("{what}: data files must be regular files; refused without reading"),
    )
}

/// An input directory opened once; every read is resolved beneath it.
#[derive(Clone, Debug)]
pub struct InputRoot {
    dir: Arc<cap_std::fs::Dir>,
    path: PathBuf,
}

impl InputRoot {
    /// Opens the existing directory `path` as the root of every read made through it.
    pub fn open(path: &Path) -> Result<InputRoot, InputError> {
        let dir = cap_std::fs::Dir::open_ambient_dir(path, cap_std::ambient_authority()).map_err(
            |source| InputError::Io {
                op: "open data directory",
                path: path.to_path_buf(),
                source,
            },
        )?;
        Ok(InputRoot {
            dir: Arc::new(dir),
            path: path.to_path_buf(),
        })
    }

    /// The directory as given when opened.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The bytes of the file at `rel` (relative, without `..`), opened beneath the root;
    /// refused above `limit_bytes` before reading, the message saying `why` that limit.
    pub fn read(&self, rel: &str, limit_bytes: u64, why: &str) -> Result<Vec<u8>, InputError> {
        let outside = |why| InputError::Outside {
            path: rel.to_string(),
            root: self.path.clone(),
            why,
        };
        let p = Path::new(rel);
        if rel.is_empty() || p.has_root() || p.is_absolute() {
            return Err(outside("give a path relative to the data directory"));
        }
        if p.components()
            .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
        {
            return Err(outside("'..' is not allowed"));
        }
        let full = self.path.join(p);
        // A FIFO, device or directory in place of a data file is refused before any open
        // (opening a FIFO for reading blocks until a writer comes); the open below re-checks
        // the handle, so a swap after this check cannot block either.
        if let Ok(meta) = self.dir.metadata(p) {
            if !meta.is_file() {
                return Err(not_regular(&full, &meta.file_type()));
            }
        }
        let file = open_regular(&self.dir, p).map_err(|source| {
            if source.to_string().contains("outside of the filesystem") || self.leads_outside(p) {
                outside("through a symlink")
            } else {
                InputError::Io {
                    op: "open",
                    path: full.clone(),
                    source,
                }
            }
        })?;
        let io = |op, source| InputError::Io {
            op,
            path: full.clone(),
            source,
        };
        let meta = file.metadata().map_err(|e| io("inspect", e))?;
        if !meta.is_file() {
            return Err(not_regular(&full, &meta.file_type()));
        }
        let too_large = |size: u64| InputError::TooLarge {
            path: full.clone(),
            size: crate::budget::format_bytes(size as f64),
            limit: crate::budget::format_bytes(limit_bytes as f64),
            why: why.to_string(),
        };
        if meta.len() > limit_bytes {
            return Err(too_large(meta.len()));
        }
        // Read at most one byte past the limit: a file that grew since it was measured is
        // refused too, never read without bound.
        let mut bytes = Vec::with_capacity(meta.len() as usize);
        file.take(limit_bytes.saturating_add(1))
            .read_to_end(&mut bytes)
            .map_err(|e| io("read", e))?;
        if bytes.len() as u64 > limit_bytes {
            return Err(too_large(bytes.len() as u64));
        }
        Ok(bytes)
    }

    /// True when `rel` (relative, without `..`) is a directory beneath the root; false when it
    /// is missing, not a directory, or leads out of the root.
    pub fn is_dir(&self, rel: &str) -> bool {
        beneath(rel).is_some_and(|p| self.dir.is_dir(p))
    }

    /// True when `rel` (relative, without `..`) is a regular file beneath the root; false when
    /// it is missing, not a file, or leads out of the root.
    pub fn is_file(&self, rel: &str) -> bool {
        beneath(rel).is_some_and(|p| self.dir.is_file(p))
    }

    /// True when the longest existing prefix of `rel` resolves outside the root (wording only:
    /// cap-std has already refused the open).
    fn leads_outside(&self, rel: &Path) -> bool {
        let Ok(root) = std::fs::canonicalize(&self.path) else {
            return false;
        };
        rel.ancestors()
            .filter(|a| !a.as_os_str().is_empty())
            .find_map(|a| std::fs::canonicalize(self.path.join(a)).ok())
            .is_some_and(|real| !real.starts_with(&root))
    }
}

/// A numeric array read from a file: values in row-major (C) order and the shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Values, row-major.
    pub values: Vec<f64>,
    /// The shape: `[n]` or `[rows, columns]`.
    pub shape: Vec<usize>,
}

/// Parses an `.npy` file of 1 or 2 dimensions with float64, float32, int64 or int32 values
/// (either byte order, C or Fortran order); `path` names it in errors.
pub fn parse_npy(path: &Path, bytes: &[u8]) -> Result<Table, InputError> {
    let bad = |m: String| InputError::format(path, m);
    npy_header::check(bytes).map_err(|m| bad(format!("not an .npy file the reader takes: {m}")))?;
    let mut data = bytes;
    let header = npyz::NpyHeader::from_reader(&mut data)
        .map_err(|e| bad(format!("not an .npy file: {e}")))?;
    let file = npyz::NpyFile::with_header(header, data);
    let shape: Vec<usize> = file
        .shape()
        .iter()
        .map(|&d| usize::try_from(d).map_err(|_| bad(format!("dimension {d} too large"))))
        .collect::<Result<_, _>>()?;
    if !(1..=2).contains(&shape.len()) {
        return Err(bad(format!(
            "shape {shape:?}: only 1-D and 2-D arrays are read"
        )));
    }
    let dtype = match file.dtype() {
        npyz::DType::Plain(t) => t.to_string(),
        other => other.descr(),
    };
    type Convert = fn(npyz::NpyFile<&[u8]>) -> std::io::Result<Vec<f64>>;
    let (width, convert): (usize, Convert) = match dtype.trim_start_matches(['<', '>', '|', '=']) {
        "f8" => (8, |f| f.into_vec::<f64>()),
        "f4" => (4, |f| {
            Ok(f.into_vec::<f32>()?.into_iter().map(f64::from).collect())
        }),
        "i8" => (8, |f| {
            Ok(f.into_vec::<i64>()?.into_iter().map(|v| v as f64).collect())
        }),
        "i4" => (4, |f| {
            Ok(f.into_vec::<i32>()?.into_iter().map(f64::from).collect())
        }),
        _ => {
            return Err(bad(format!(
                "dtype {dtype}: expected float64, float32, int64 or int32"
            )))
        }
    };
    // The header's shape must match the bytes that follow it: a forged header cannot make
    // the reader promise more values than the file holds.
    let count = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if count.and_then(|n| n.checked_mul(width)) != Some(data.len()) {
        return Err(bad(format!(
            "shape {shape:?} of {dtype} does not match the {} data bytes after the header",
            data.len()
        )));
    }
    let fortran = file.order() == npyz::Order::Fortran;
    let mut values = convert(file).map_err(|e| bad(format!("data: {e}")))?;
    if fortran && shape.len() == 2 {
        let (rows, cols) = (shape[0], shape[1]);
        values = (0..rows * cols)
            .map(|k| values[(k % cols) * rows + k / cols])
            .collect();
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(bad(format!("element {i} is {}: not finite", values[i])));
    }
    Ok(Table { values, shape })
}

/// Named numeric columns of a CSV file, in the file's order.
#[derive(Clone, Debug, PartialEq)]
pub struct Columns {
    /// Header names.
    pub headers: Vec<String>,
    /// One column of values per header.
    pub columns: Vec<Vec<f64>>,
}

/// Parses a CSV file with a header row and numeric cells (the `csv` crate: RFC 4180 quoting,
/// every row as long as the header). Errors name the line, the column's header and the text.
pub fn parse_csv(path: &Path, bytes: &[u8]) -> Result<Columns, InputError> {
    parse_csv_columns(path, bytes, None)
}

/// [`parse_csv`] keeping only the columns named in `wanted` (in the file's order), when given:
/// only their cells must be numbers, so a table with text columns (a verdict, a note) reads.
/// A wanted name the header lacks is an error listing the header.
pub fn parse_csv_columns(
    path: &Path,
    bytes: &[u8],
    wanted: Option<&[String]>,
) -> Result<Columns, InputError> {
    let bad = |m: String| InputError::format(path, m);
    if let Some(line) = unclosed_quote_line(bytes) {
        return Err(bad(format!(
            "line {line}: the quote opened here is never closed (the rest of the file would \
             be one cell)"
        )));
    }
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let headers: Vec<String> = reader
        .headers()
        .map_err(|e| bad(format!("header row: {e}")))?
        .iter()
        .map(str::to_string)
        .collect();
    if headers.is_empty() || headers.iter().all(String::is_empty) {
        return Err(bad(
            "no header row (the first line names the columns)".into()
        ));
    }
    if let Some(i) = headers.iter().position(String::is_empty) {
        return Err(bad(format!("column {} has an empty header", i + 1)));
    }
    if let Some((i, h)) = headers
        .iter()
        .enumerate()
        .find(|(i, h)| headers[..*i].contains(h))
    {
        return Err(bad(format!(
            "header '{h}' appears twice (column {})",
            i + 1
        )));
    }
    let keep: Vec<bool> = match wanted {
        None => vec![true; headers.len()],
        Some(names) => {
            if let Some(missing) = names.iter().find(|n| !headers.contains(n)) {
                return Err(bad(format!(
                    "no column '{missing}' (columns: {})",
                    headers.join(", ")
                )));
            }
            headers.iter().map(|h| names.contains(h)).collect()
        }
    };
    let mut columns = vec![Vec::new(); headers.len()];
    for record in reader.records() {
        let record = record.map_err(|e| bad(e.to_string()))?;
        let line = record.position().map_or(0, |p| p.line());
        let cells = record.iter().zip(&mut columns).zip(&headers).zip(&keep);
        for (((cell, column), header), _) in cells.filter(|(_, &k)| k) {
            let v: f64 = cell.parse().map_err(|_| {
                bad(format!(
                    "line {line}, column '{header}': '{cell}' is not a number"
                ))
            })?;
            if !v.is_finite() {
                return Err(bad(format!(
                    "line {line}, column '{header}': '{cell}' is not finite"
                )));
            }
            column.push(v);
        }
    }
    let (headers, columns) = headers
        .into_iter()
        .zip(columns)
        .zip(keep)
        .filter_map(|(hc, k)| k.then_some(hc))
        .unzip();
    Ok(Columns { headers, columns })
}

/// The line (1-based) where a quoted CSV field opens that the file never closes, if any: the
/// `csv` crate reads such a field to the end of the file, so a stray quote in the header would
/// turn every row into one header cell. The states follow RFC 4180 as the `csv` crate reads
/// it: a quote opens a field only at its start, and `""` inside a quoted field is a quote.
fn unclosed_quote_line(bytes: &[u8]) -> Option<usize> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        FieldStart,
        Unquoted,
        Quoted,
        QuoteInQuoted,
    }
    let (mut state, mut line, mut opened_at) = (State::FieldStart, 1, 1);
    for &b in bytes {
        let ends_field = matches!(b, b',' | b'\n' | b'\r');
        state = match (state, b) {
            (State::FieldStart, b'"') => {
                opened_at = line;
                State::Quoted
            }
            (State::Quoted, b'"') => State::QuoteInQuoted,
            (State::Quoted, _) => State::Quoted,
            (State::QuoteInQuoted, b'"') => State::Quoted,
            (_, _) if ends_field => State::FieldStart,
            _ => State::Unquoted,
        };
        if b == b'\n' {
            line += 1;
        }
    }
    (state == State::Quoted).then_some(opened_at)
}

/// Parses a JSON document; errors give the line and column. A key repeated in one object is
/// refused, naming the key and its position (serde_json would keep the last value silently).
pub fn parse_json(path: &Path, bytes: &[u8]) -> Result<serde_json::Value, InputError> {
    serde_json::from_slice::<UniqueKeys>(bytes)
        .map(|v| v.0)
        .map_err(|e| InputError::format(path, format!("JSON: {e}")))
}

/// A JSON value read with every object's keys checked for repeats.
struct UniqueKeys(serde_json::Value);

impl<'de> serde::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(UniqueKeysVisitor).map(UniqueKeys)
    }
}

/// Builds a [`serde_json::Value`] as serde_json's own visitor does, refusing repeated keys.
struct UniqueKeysVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueKeysVisitor {
    type Value = serde_json::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_i64<E>(self, v: i64) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_u64<E>(self, v: u64) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_f64<E>(self, v: f64) -> Result<Self::Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, Into::into))
    }

    fn visit_str<E>(self, v: &str) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_string<E>(self, v: String) -> Result<Self::Value, E> {
        Ok(v.into())
    }

    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        Ok(serde_json::Value::Null)
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(UniqueKeys(v)) = seq.next_element()? {
            items.push(v);
        }
        Ok(items.into())
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut object = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(serde::de::Error::custom(format!(
                    "key \"{key}\" appears twice in one object"
                )));
            }
            let UniqueKeys(value) = map.next_value()?;
            object.insert(key, value);
        }
        Ok(object.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("x")
    }

    #[test]
    fn npy_round_trips_the_writer_and_reads_other_dtypes_and_fortran_order() {
        let dir = std::env::temp_dir().join(format!("trnews-input-npy-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let file = dir.join("a.npy");
        crate::io::write_npy(&file, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.5], &[2, 3]).expect("write");
        let bytes = std::fs::read(&file).expect("read");
        let t = parse_npy(&file, &bytes).expect("parse");
        assert_eq!(t.shape, vec![2, 3]);
        assert_eq!(t.values, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.5]);
        // numpy: np.array([[1, 2, 3], [4, 5, 6]], dtype='<i4', order='F') saved with np.save
        use npyz::WriterBuilder;
        let mut f = Vec::new();
        let mut w = npyz::WriteOptions::<i32>::new()
            .default_dtype()
            .shape(&[2, 3])
            .order(npyz::Order::Fortran)
            .writer(&mut f)
            .begin_nd()
            .expect("writer");
        w.extend([1, 4, 2, 5, 3, 6]).expect("data");
        w.finish().expect("finish");
        let t = parse_npy(p(), &f).expect("parse i4 Fortran");
        assert_eq!(t.values, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn malformed_npy_is_an_error_naming_the_cause() {
        let e = parse_npy(p(), b"not numpy").unwrap_err().to_string();
        assert!(e.contains("not an .npy file"), "{e}");
        let mut good = Vec::new();
        {
            use npyz::WriterBuilder;
            let mut w = npyz::WriteOptions::<f64>::new()
                .default_dtype()
                .shape(&[4])
                .writer(&mut good)
                .begin_nd()
                .expect("writer");
            w.extend([1.0, 2.0, f64::NAN, 4.0]).expect("data");
            w.finish().expect("finish");
        }
        let e = parse_npy(p(), &good).unwrap_err().to_string();
        assert!(e.contains("element 2") && e.contains("not finite"), "{e}");
        let truncated = &good[..good.len() - 9];
        let e = parse_npy(p(), truncated).unwrap_err().to_string();
        assert!(e.contains("does not match"), "{e}");
        // a forged header claiming 1e15 values is refused before reading
        let header_end = good.len() - 32;
        let text =
            String::from_utf8_lossy(&good[..header_end]).replace("(4,)", "(999999999999999,)");
        let mut forged = text.into_bytes();
        forged.extend_from_slice(&good[header_end..]);
        assert!(parse_npy(p(), &forged).is_err());
    }

    #[test]
    fn csv_reads_columns_and_names_bad_cells() {
        let c = parse_csv(p(), b"t_s, a,\"b\"\n0,1,2\n1e-8,3.5,-4\n").expect("parse");
        assert_eq!(c.headers, vec!["t_s", "a", "b"]);
        assert_eq!(c.columns[1], vec![1.0, 3.5]);
        let e = parse_csv(p(), b"t,a\n0,1\n1,x\n").unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("'a'") && e.contains("'x'"),
            "{e}"
        );
        let e = parse_csv(p(), b"t,a\n0,1\n1\n").unwrap_err().to_string();
        assert!(e.contains("record") || e.contains("fields"), "{e}");
        let e = parse_csv(p(), b"t,a\n0,nan\n").unwrap_err().to_string();
        assert!(e.contains("not finite"), "{e}");
        let only = ["a".to_string()];
        let c = parse_csv_columns(p(), b"t,a,verdict\n0,1,off\n1,2,\n", Some(&only)).unwrap();
        assert_eq!(
            (c.headers, c.columns),
            (vec!["a".to_string()], vec![vec![1.0, 2.0]])
        );
        let e = parse_csv_columns(p(), b"t,a\n0,1\n", Some(&["b".to_string()]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no column 'b' (columns: t, a)"), "{e}");
        let e = parse_csv(p(), b"t,t\n0,1\n").unwrap_err().to_string();
        assert!(e.contains("twice"), "{e}");
        assert!(parse_csv(p(), b"").is_err());
        assert!(parse_csv(p(), b"\xff\xfe,\n").is_err());
    }

    #[test]
    fn mutated_files_never_panic() {
        // Seeded byte flips, truncations and insertions of valid files: every parser returns
        // Ok or an error, never a panic (a panic fails the test).
        let mut npy = Vec::new();
        {
            use npyz::WriterBuilder;
            let mut w = npyz::WriteOptions::<f64>::new()
                .default_dtype()
                .shape(&[3, 2])
                .writer(&mut npy)
                .begin_nd()
                .expect("writer");
            w.extend([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).expect("data");
            w.finish().expect("finish");
        }
        let csv = b"t_s,a,\"b c\"\n0,1.5,2\n1e-8,-3,4e2\n".to_vec();
        let json = br#"{"a": [1, 2.5, {"b": null}], "c": "x"}"#.to_vec();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for case in 0..3000 {
            let base = [&npy, &csv, &json][case % 3];
            let mut bytes = base.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % bytes.len().max(1) as u64) as usize;
                match next() % 3 {
                    0 if !bytes.is_empty() => bytes[i] = next() as u8,
                    1 => bytes.truncate(i),
                    _ => bytes.insert(i.min(bytes.len()), next() as u8),
                }
            }
            let _ = parse_npy(p(), &bytes);
            let _ = parse_csv(p(), &bytes);
            let _ = parse_json(p(), &bytes);
        }
    }

    #[test]
    fn csv_unterminated_quote_is_an_error_not_a_header() {
        let e = parse_csv(p(), b"t,\"a\n0,1\n1,2\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("never closed"), "{e}");
        let e = parse_csv(p(), b"t,a\n0,1\n\"1,2\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("never closed"), "{e}");
        // closed quotes, doubled quotes and a quote inside an unquoted field are fine
        let c = parse_csv(p(), b"\"t \"\"s\"\"\",a\"b\n0,1\n").expect("parse");
        assert_eq!(c.headers, vec!["t \"s\"", "a\"b"]);
    }

    #[test]
    fn json_duplicate_keys_are_named_with_their_position() {
        let e = parse_json(p(), b"{\"a\": 1,\n \"b\": {\"c\": 2, \"c\": 3}}")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("key \"c\" appears twice") && e.contains("line 2"),
            "{e}"
        );
        let v = parse_json(
            p(),
            br#"{"a": [1, -2, 2.5, "x", null, true], "b": {"a": 1}}"#,
        )
        .expect("same key in two objects is fine");
        assert_eq!(v["a"][2], 2.5);
        assert_eq!(v["a"][1], -2);
    }

    /// The open behind [`InputRoot::read`] never blocks on a FIFO, so that a FIFO swapped in
    /// after the check by name is refused by the check on the handle.
    #[cfg(unix)]
    #[test]
    fn a_fifo_opens_without_blocking_and_the_handle_says_what_it_is() {
        let dir = std::env::temp_dir().join(format!("trnews-input-fifo-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let made = std::process::Command::new("mkfifo")
            .arg(dir.join("pipe"))
            .status()
            .expect("mkfifo");
        assert!(made.success());
        let root =
            cap_std::fs::Dir::open_ambient_dir(&dir, cap_std::ambient_authority()).expect("root");
        let file = open_regular(&root, Path::new("pipe")).expect("opens at once");
        let kind = file.metadata().expect("fstat").file_type();
        let e = not_regular(Path::new("pipe"), &kind).to_string();
        assert!(e.contains("pipe") && e.contains("FIFO"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn json_errors_give_the_position() {
        let e = parse_json(p(), b"{\"a\": [1, 2,]}")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1"), "{e}");
    }
}
