//! Data-file outputs: CSV, JSON, NPY and VTU (ParaView), all written atomically.
//!
//! Every writer builds the file contents in memory and hands them to [`write_atomic`],
//! which writes a temporary sibling file and renames it over the target, so a reader
//! never sees a half-written file and an interrupted run never leaves a truncated one.

use serde::Serialize;
use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// Failure to write an output file; every variant names the path and the cause.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An operating-system call failed (`op` says which, e.g. "create directory").
    #[error("cannot {op} {path}: {source}", path = .path.display())]
    Io {
        /// What was being done.
        op: &'static str,
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The data handed to a writer is inconsistent (lengths, shapes, indices, values).
    #[error("cannot write {path}: {message}", path = .path.display())]
    Data {
        /// The target file.
        path: PathBuf,
        /// What is wrong with the data.
        message: String,
    },
    /// The path leads out of the active output root (given outside it, or through a symlink).
    #[error("output path {path} leads outside the output directory {root} (through a symlink, or not under it); refused", path = .path.display(), root = .root.display())]
    Outside {
        /// The path as given.
        path: PathBuf,
        /// The output root.
        root: PathBuf,
    },
    /// Serialising to JSON failed.
    #[error("cannot write {path}: JSON serialisation failed: {source}", path = .path.display())]
    Json {
        /// The target file.
        path: PathBuf,
        /// The underlying error.
        source: serde_json::Error,
    },
}

impl OutputError {
    /// Shorthand for an [`OutputError::Data`] about `path`.
    fn data(path: &Path, message: impl Into<String>) -> Self {
        OutputError::Data {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    /// Shorthand for an [`OutputError::Io`] about `path`.
    fn io(op: &'static str, path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            op,
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Creates the parent directory of `path` (and its ancestors) if missing.
pub fn ensure_parent_dir(path: &Path) -> Result<(), OutputError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            fs::create_dir_all(dir).map_err(|e| OutputError::io("create directory", dir, e))
        }
        _ => Ok(()),
    }
}

/// An output directory opened once. Writes through it are resolved beneath it by cap-std's
/// openat-style lookups (every component, symlinks included, is followed relative to the open
/// directory handle), so a symlink that leads out of it is refused at the moment of use: no
/// check-then-use race, even when a link is swapped while a script runs.
#[derive(Clone, Debug)]
pub struct OutputRoot {
    dir: Arc<cap_std::fs::Dir>,
    path: PathBuf,
}

impl OutputRoot {
    /// Creates `path` if missing and opens it as the root of every write made within it.
    pub fn open(path: &Path) -> Result<OutputRoot, OutputError> {
        fs::create_dir_all(path).map_err(|e| OutputError::io("create directory", path, e))?;
        let dir = cap_std::fs::Dir::open_ambient_dir(path, cap_std::ambient_authority())
            .map_err(|e| OutputError::io("open output directory", path, e))?;
        Ok(OutputRoot {
            dir: Arc::new(dir),
            path: path.to_path_buf(),
        })
    }

    /// The directory as given when opened.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Runs `f` with this root active on the current thread: every path a writer of this
    /// crate is given must then lie under [`OutputRoot::path`] and is written beneath the open
    /// directory (see [`write_atomic`]). The previous root is restored afterwards, also on panic.
    pub fn within<T>(&self, f: impl FnOnce() -> T) -> T {
        struct Restore(Option<OutputRoot>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let old = self.0.take();
                ACTIVE_ROOT.with(|r| *r.borrow_mut() = old);
            }
        }
        let old = ACTIVE_ROOT.with(|r| r.borrow_mut().replace(self.clone()));
        let _restore = Restore(old);
        f()
    }

    /// `path` relative to the root, or an error when it does not lie under it.
    fn relative<'a>(&self, path: &'a Path) -> Result<&'a Path, OutputError> {
        path.strip_prefix(&self.path)
            .ok()
            .filter(|rel| {
                rel.components().all(|c| {
                    matches!(
                        c,
                        std::path::Component::Normal(_) | std::path::Component::CurDir
                    )
                })
            })
            .ok_or_else(|| OutputError::Outside {
                path: path.to_path_buf(),
                root: self.path.clone(),
            })
    }

    /// True when the longest existing prefix of `rel` resolves (symlinks followed) outside the
    /// root. Used only to word an error that cap-std already raised; the refusal itself does
    /// not depend on this check.
    fn leads_outside(&self, rel: &Path) -> bool {
        let Ok(root) = fs::canonicalize(&self.path) else {
            return false;
        };
        rel.ancestors()
            .filter(|a| !a.as_os_str().is_empty())
            .find_map(|a| fs::canonicalize(self.path.join(a)).ok())
            .is_some_and(|real| !real.starts_with(&root))
    }

    /// Writes `bytes` to `path` (under the root) atomically, beneath the open directory.
    fn write_atomic(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        let rel = self.relative(path)?;
        let escape = |e: std::io::Error, op: &'static str, at: &Path| {
            if e.to_string().contains("outside of the filesystem") || self.leads_outside(rel) {
                OutputError::Outside {
                    path: path.to_path_buf(),
                    root: self.path.clone(),
                }
            } else {
                OutputError::io(op, at, e)
            }
        };
        let name = rel
            .file_name()
            .ok_or_else(|| OutputError::data(path, "no file name"))?;
        let parent = rel.parent().filter(|p| !p.as_os_str().is_empty());
        let dir = match parent {
            Some(p) => {
                let full = self.path.join(p);
                self.dir
                    .create_dir_all(p)
                    .map_err(|e| escape(e, "create directory", &full))?;
                self.dir
                    .open_dir(p)
                    .map_err(|e| escape(e, "open directory", &full))?
            }
            None => self
                .dir
                .try_clone()
                .map_err(|e| escape(e, "open directory", &self.path))?,
        };
        remove_stale_temps(
            || {
                dir.entries()
                    .ok()
                    .into_iter()
                    .flatten()
                    .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            },
            Path::new(name),
            |stale| {
                let _ = dir.remove_file(stale);
            },
        );
        let tmp = temp_sibling(Path::new(name));
        let written = dir.create(&tmp).and_then(|mut f| f.write_all(bytes));
        if let Err(e) = written {
            let _ = dir.remove_file(&tmp);
            return Err(escape(e, "write", path));
        }
        dir.rename(&tmp, &dir, name).map_err(|e| {
            let _ = dir.remove_file(&tmp);
            escape(e, "rename temporary file onto", path)
        })
    }
}

thread_local! {
    /// The output root active on this thread (see [`OutputRoot::within`]).
    static ACTIVE_ROOT: std::cell::RefCell<Option<OutputRoot>> = const { std::cell::RefCell::new(None) };
}

/// Reads `path` whole, `Ok(None)` when it does not exist. While an [`OutputRoot`] is active
/// on this thread, `path` must lie under it and is read beneath its open directory (a
/// symlink leading out is refused), as writes are.
pub fn read_existing(path: &Path) -> Result<Option<Vec<u8>>, OutputError> {
    let read = match active_root() {
        Some(root) => {
            let rel = root.relative(path)?;
            root.dir.read(rel).map_err(|e| {
                if root.leads_outside(rel) {
                    std::io::Error::other("outside of the filesystem")
                } else {
                    e
                }
            })
        }
        None => fs::read(path),
    };
    match read {
        Ok(bytes) => Ok(Some(bytes)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) if e.to_string().contains("outside of the filesystem") => {
            Err(OutputError::Outside {
                path: path.to_path_buf(),
                root: active_root().map(|r| r.path.clone()).unwrap_or_default(),
            })
        }
        Err(e) => Err(OutputError::io("read", path, e)),
    }
}

/// The output root active on this thread, if any.
pub fn active_root() -> Option<OutputRoot> {
    ACTIVE_ROOT.with(|r| r.borrow().clone())
}

/// A unique temporary sibling of `path` that keeps its extension:
/// `dir/.name.tmp-<pid>-<counter>.ext`.
pub fn temp_sibling(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let (prefix, ext) = temp_parts(path);
    path.with_file_name(format!("{prefix}{}-{n}{ext}", std::process::id()))
}

/// The parts of a temporary name around `<pid>-<counter>`: `.stem.tmp-` and `.ext` (or "").
fn temp_parts(path: &Path) -> (String, String) {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (format!(".{stem}.tmp-"), ext)
}

/// Removes the temporary siblings of `target` left by writers that no longer run (a killed
/// process): names `.stem.tmp-<pid>-<n>.ext` whose pid is not ours and has no `/proc` entry.
/// Only on Linux, where a dead pid can be told from a live one; elsewhere they are ignored
/// (hidden names, never read).
fn remove_stale_temps<I: Iterator<Item = String>>(
    names: impl FnOnce() -> I,
    target: &Path,
    mut remove: impl FnMut(&str),
) {
    if !cfg!(target_os = "linux") {
        return;
    }
    let (prefix, ext) = temp_parts(target);
    for name in names() {
        let Some(middle) = name
            .strip_prefix(&prefix)
            .and_then(|m| m.strip_suffix(&ext))
        else {
            continue;
        };
        let Some((pid, n)) = middle.split_once('-') else {
            continue;
        };
        let (Ok(pid), true) = (pid.parse::<u32>(), n.bytes().all(|b| b.is_ascii_digit())) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            remove(&name);
        }
    }
}

/// Renames the finished temporary file `tmp` over `path`; removes `tmp` if that fails.
pub fn commit_temp(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    fs::rename(tmp, path).map_err(|e| {
        let _ = fs::remove_file(tmp);
        OutputError::io("rename temporary file onto", path, e)
    })
}

/// Writes `bytes` to `path` atomically: parent directories are created, the bytes go to
/// a temporary file in the same directory, which is then renamed over the target
/// (replacing an existing file). No fsync is done: outputs favour speed over
/// durability across a power cut, but are never seen half-written. Temporary files of
/// the same target left by a killed writer are removed first.
///
/// While an [`OutputRoot`] is active on this thread ([`OutputRoot::within`]), `path` must lie
/// under it and the write goes through the root's open directory: a symlink leading out of
/// it, or a path outside it, is refused with [`OutputError::Outside`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    if let Some(root) = active_root() {
        return root.write_atomic(path, bytes);
    }
    ensure_parent_dir(path)?;
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        remove_stale_temps(
            || {
                fs::read_dir(dir)
                    .ok()
                    .into_iter()
                    .flatten()
                    .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            },
            path,
            |stale| {
                let _ = fs::remove_file(dir.join(stale));
            },
        );
    }
    let tmp = temp_sibling(path);
    let written = fs::File::create(&tmp).and_then(|mut f| f.write_all(bytes));
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(OutputError::io("write", &tmp, e));
    }
    commit_temp(&tmp, path)
}

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

/// Quotes a CSV field if it contains a comma, quote or line break (RFC 4180).
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Appends one CSV record (fields joined by commas, newline-terminated).
fn push_record<S: AsRef<str>>(out: &mut String, fields: impl IntoIterator<Item = S>) {
    let line: Vec<String> = fields.into_iter().map(|f| csv_field(f.as_ref())).collect();
    out.push_str(&line.join(","));
    out.push('\n');
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
    let mut out = String::new();
    push_record(&mut out, headers.iter().copied());
    for r in 0..rows {
        push_record(&mut out, columns.iter().map(|c| fmt_f64(c[r])));
    }
    write_atomic(path, out.as_bytes())
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
    let mut out = String::new();
    push_record(&mut out, headers);
    for row in rows {
        push_record(&mut out, row);
    }
    write_atomic(path, out.as_bytes())
}

/// Writes `value` as pretty-printed JSON (with a trailing newline).
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), OutputError> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| OutputError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

/// Writes a little-endian float64 `.npy` array of the given shape, C (row-major) order.
/// `shape` may be empty for a scalar; its product must equal `data.len()`.
pub fn write_npy(path: &Path, data: &[f64], shape: &[usize]) -> Result<(), OutputError> {
    let count: usize = shape.iter().product();
    if count != data.len() {
        return Err(OutputError::data(
            path,
            format!(
                "shape {shape:?} holds {count} values but {} were given",
                data.len()
            ),
        ));
    }
    npy_bytes(data, shape)
        .map_err(|e| OutputError::io("encode .npy for", path, e))
        .and_then(|bytes| write_atomic(path, &bytes))
}

/// Encodes `data` with `shape` as the bytes of an `.npy` file.
fn npy_bytes(data: &[f64], shape: &[usize]) -> std::io::Result<Vec<u8>> {
    use npyz::WriterBuilder;
    let shape: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    let mut bytes = Vec::new();
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&shape)
        .writer(&mut bytes)
        .begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()?;
    Ok(bytes)
}

/// Writes a 2D triangle mesh with nodal fields as a VTK XML UnstructuredGrid (`.vtu`,
/// ASCII). Points get z = 0; triangles are VTK cell type 5. Each point field is
/// `(name, components, values)` with 1 (scalar) or 2 (vector, padded to 3 for
/// ParaView) components per point, values point-major. All numbers must be finite.
pub fn write_vtu(
    path: &Path,
    points: &[[f64; 2]],
    triangles: &[[usize; 3]],
    point_data: &[(&str, usize, &[f64])],
) -> Result<(), OutputError> {
    check_vtu(points, triangles, point_data).map_err(|m| OutputError::data(path, m))?;
    write_atomic(path, vtu_text(points, triangles, point_data).as_bytes())
}

/// Checks the inputs of [`write_vtu`]; returns a message naming the first problem.
fn check_vtu(
    points: &[[f64; 2]],
    triangles: &[[usize; 3]],
    point_data: &[(&str, usize, &[f64])],
) -> Result<(), String> {
    let n = points.len();
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(format!("point {i} has a non-finite coordinate"));
    }
    if let Some(t) = triangles.iter().position(|t| t.iter().any(|&k| k >= n)) {
        return Err(format!("triangle {t} refers to a point >= {n}"));
    }
    for &(name, comps, values) in point_data {
        if comps != 1 && comps != 2 {
            return Err(format!(
                "field {name:?} has {comps} components (1 or 2 allowed)"
            ));
        }
        if values.len() != comps * n {
            return Err(format!(
                "field {name:?} has {} values, expected {} ({comps} x {n} points)",
                values.len(),
                comps * n
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "field {name:?} has a non-finite value at index {i}"
            ));
        }
    }
    Ok(())
}

/// Escapes text for use inside an XML attribute value.
fn xml_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Appends an ASCII `<DataArray>` with the given attributes and values, `per_line` a line.
fn push_data_array(out: &mut String, attrs: &str, values: &[String], per_line: usize) {
    let _ = writeln!(out, "        <DataArray {attrs} format=\"ascii\">");
    for chunk in values.chunks(per_line.max(1)) {
        let _ = writeln!(out, "          {}", chunk.join(" "));
    }
    out.push_str("        </DataArray>\n");
}

/// Formats a point field as VTK values, padding 2-vectors with a zero z component.
fn field_values(comps: usize, values: &[f64]) -> Vec<String> {
    if comps == 1 {
        return values.iter().map(|&v| fmt_f64(v)).collect();
    }
    values
        .chunks(2)
        .flat_map(|c| [fmt_f64(c[0]), fmt_f64(c[1]), "0".to_string()])
        .collect()
}

/// Builds the text of a VTU file from already-checked inputs.
fn vtu_text(
    points: &[[f64; 2]],
    triangles: &[[usize; 3]],
    point_data: &[(&str, usize, &[f64])],
) -> String {
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    out.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n",
    );
    out.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        points.len(),
        triangles.len()
    );
    out.push_str("      <PointData>\n");
    for &(name, comps, values) in point_data {
        let ncomp = if comps == 1 { 1 } else { 3 };
        let attrs = format!(
            "type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{ncomp}\"",
            xml_attr(name)
        );
        push_data_array(&mut out, &attrs, &field_values(comps, values), 3 * ncomp);
    }
    out.push_str("      </PointData>\n      <Points>\n");
    let coords: Vec<String> = points
        .iter()
        .flat_map(|p| [fmt_f64(p[0]), fmt_f64(p[1]), "0".to_string()])
        .collect();
    push_data_array(
        &mut out,
        "type=\"Float64\" NumberOfComponents=\"3\"",
        &coords,
        9,
    );
    out.push_str("      </Points>\n      <Cells>\n");
    let conn: Vec<String> = triangles.iter().flatten().map(|k| k.to_string()).collect();
    push_data_array(&mut out, "type=\"Int64\" Name=\"connectivity\"", &conn, 12);
    let offsets: Vec<String> = (1..=triangles.len()).map(|c| (3 * c).to_string()).collect();
    push_data_array(&mut out, "type=\"Int64\" Name=\"offsets\"", &offsets, 16);
    let types = vec!["5".to_string(); triangles.len()];
    push_data_array(&mut out, "type=\"UInt8\" Name=\"types\"", &types, 32);
    out.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn temp_dir(tag: &str) -> TempDir {
        static N: AtomicU64 = AtomicU64::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let name = format!("plotio-io-{tag}-{}-{n}", std::process::id());
        let dir = std::env::temp_dir().join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    /// Names of the entries of `dir`.
    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let dir = temp_dir("atomic");
        let p = dir.join("sub/deeper/out.txt");
        write_atomic(&p, b"first").expect("first write");
        write_atomic(&p, b"second").expect("second write");
        assert_eq!(fs::read(&p).expect("read"), b"second");
        assert_eq!(
            entries(&dir.join("sub/deeper")),
            vec!["out.txt".to_string()]
        );
    }

    #[test]
    fn atomic_write_error_names_path() {
        let dir = temp_dir("atomic-err");
        let blocker = dir.join("file");
        write_atomic(&blocker, b"x").expect("write");
        let err = write_atomic(&blocker.join("child.txt"), b"y").expect_err("must fail");
        assert!(err.to_string().contains("file"), "{err}");
    }

    #[test]
    fn csv_round_trip() {
        let dir = temp_dir("csv");
        let p = dir.join("t.csv");
        let a = [0.0, 1.0 / 3.0, -2.5e-12, 1e300, f64::NAN];
        let b = [1.0, 2.0, 3.0, 4.0, f64::INFINITY];
        write_csv(&p, &["time (s)", "u, m"], &[&a, &b]).expect("write csv");
        let text = fs::read_to_string(&p).expect("read");
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("time (s),\"u, m\""));
        for (i, line) in lines.enumerate() {
            let f: Vec<f64> = line.split(',').map(|s| s.parse().expect("float")).collect();
            assert!(f[0] == a[i] || (f[0].is_nan() && a[i].is_nan()), "{line}");
            assert_eq!(f[1], b[i]);
        }
    }

    #[test]
    fn csv_unequal_columns_error_names_column() {
        let dir = temp_dir("csv-bad");
        let err = write_csv(&dir.join("t.csv"), &["a", "bee"], &[&[1.0, 2.0], &[1.0]])
            .expect_err("must fail");
        let msg = err.to_string();
        assert!(msg.contains("bee") && msg.contains("t.csv"), "{msg}");
        assert!(entries(&dir).is_empty());
    }

    #[test]
    fn csv_rows_quotes_and_checks() {
        let dir = temp_dir("csv-rows");
        let p = dir.join("r.csv");
        let h = vec!["name".to_string(), "value".to_string()];
        let rows = vec![vec!["say \"hi\"".to_string(), "1".to_string()]];
        write_csv_rows(&p, &h, &rows).expect("write");
        assert_eq!(
            fs::read_to_string(&p).expect("read"),
            "name,value\n\"say \"\"hi\"\"\",1\n"
        );
        let bad = vec![vec!["only one".to_string()]];
        assert!(write_csv_rows(&p, &h, &bad).is_err());
    }

    #[test]
    fn json_pretty() {
        let dir = temp_dir("json");
        let p = dir.join("a.json");
        #[derive(Serialize)]
        struct S {
            n: u32,
            v: Vec<f64>,
        }
        write_json(&p, &S { n: 3, v: vec![0.5] }).expect("write json");
        let text = fs::read_to_string(&p).expect("read");
        assert!(text.contains("\"n\": 3"), "{text}");
        let back: serde_json::Value = serde_json::from_str(&text).expect("parse");
        assert_eq!(back["v"][0], 0.5);
    }

    #[test]
    fn npy_header_and_data() {
        let dir = temp_dir("npy");
        let p = dir.join("a.npy");
        let data: Vec<f64> = (0..6).map(f64::from).collect();
        write_npy(&p, &data, &[2, 3]).expect("write npy");
        let bytes = fs::read(&p).expect("read");
        assert_eq!(&bytes[..6], b"\x93NUMPY");
        let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
        let header = std::str::from_utf8(&bytes[10..10 + hlen]).expect("utf8 header");
        assert!(header.contains("'descr': '<f8'"), "{header}");
        assert!(header.contains("'fortran_order': False"), "{header}");
        assert!(header.contains("'shape': (2, 3,"), "{header}");
        assert_eq!((10 + hlen) % 64, 0, "header must be 64-byte aligned");
        let body = &bytes[10 + hlen..];
        assert_eq!(body.len(), 48);
        assert_eq!(
            f64::from_le_bytes(body[40..48].try_into().expect("8 bytes")),
            5.0
        );
        numpy_check(&p);
    }

    /// If python3 with numpy is present, load the file there too (skipped otherwise).
    fn numpy_check(p: &Path) {
        let code = format!(
            "import numpy as n; a=n.load(r'{}'); assert a.shape==(2,3) and a[1,2]==5.0",
            p.display()
        );
        let Ok(out) = std::process::Command::new("python3")
            .args(["-c", &code])
            .output()
        else {
            return;
        };
        let err = String::from_utf8_lossy(&out.stderr);
        if err.contains("No module named") {
            eprintln!("numpy not available; skipped the numpy load check");
            return;
        }
        assert!(out.status.success(), "numpy failed to load: {err}");
    }

    #[test]
    fn npy_bad_shape_errors() {
        let dir = temp_dir("npy-bad");
        let err = write_npy(&dir.join("a.npy"), &[1.0, 2.0, 3.0], &[2, 2]).expect_err("bad");
        assert!(err.to_string().contains("[2, 2]"), "{err}");
        assert!(entries(&dir).is_empty());
    }

    /// Checks that every tag in `xml` is closed in order; returns the element names seen.
    fn check_balanced(xml: &str) -> Vec<String> {
        let mut stack: Vec<String> = Vec::new();
        let mut seen = Vec::new();
        for tag in xml
            .split('<')
            .skip(1)
            .map(|s| &s[..s.find('>').expect("tag end")])
        {
            if tag.starts_with('?') {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(stack.pop().as_deref(), Some(name), "mismatched </{name}>");
            } else {
                let name = tag.split_whitespace().next().expect("name").to_string();
                seen.push(name.clone());
                if !tag.ends_with('/') {
                    stack.push(name);
                }
            }
        }
        assert!(stack.is_empty(), "unclosed: {stack:?}");
        seen
    }

    /// The whitespace-separated values of the DataArray whose attributes contain `key`.
    fn array_values<'a>(xml: &'a str, key: &str) -> Vec<&'a str> {
        let start = xml.find(key).expect("array present");
        let body = &xml[start..];
        let body =
            &body[body.find('>').expect("open end") + 1..body.find("</DataArray>").expect("close")];
        body.split_whitespace().collect()
    }

    #[test]
    fn vtu_well_formed_with_counts() {
        let dir = temp_dir("vtu");
        let p = dir.join("mesh.vtu");
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let s = [0.1, 0.2, 0.3, 0.4];
        let u = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        write_vtu(&p, &pts, &tris, &[("p<1>", 1, &s), ("u", 2, &u)]).expect("write vtu");
        let xml = fs::read_to_string(&p).expect("read");
        let names = check_balanced(&xml);
        assert_eq!(names.iter().filter(|n| *n == "DataArray").count(), 6);
        assert!(xml.contains("NumberOfPoints=\"4\" NumberOfCells=\"2\""));
        assert!(xml.contains("Name=\"p&lt;1&gt;\""));
        assert_eq!(
            array_values(&xml, "Name=\"u\""),
            ["1", "2", "0", "3", "4", "0", "5", "6", "0", "7", "8", "0"]
        );
        assert_eq!(
            array_values(&xml, "NumberOfComponents=\"3\" format").len(),
            12
        );
        assert_eq!(
            array_values(&xml, "connectivity"),
            ["0", "1", "2", "1", "3", "2"]
        );
        assert_eq!(array_values(&xml, "offsets"), ["3", "6"]);
        assert_eq!(array_values(&xml, "types"), ["5", "5"]);
    }

    #[test]
    fn vtu_bad_inputs_error() {
        let dir = temp_dir("vtu-bad");
        let p = dir.join("m.vtu");
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let err = write_vtu(&p, &pts, &[[0, 1, 3]], &[]).expect_err("index");
        assert!(err.to_string().contains("triangle 0"), "{err}");
        let err = write_vtu(&p, &pts, &[[0, 1, 2]], &[("ux", 1, &[1.0])]).expect_err("len");
        assert!(err.to_string().contains("ux"), "{err}");
        let err = write_vtu(&p, &pts, &[[0, 1, 2]], &[("w", 3, &[0.0; 9])]).expect_err("comps");
        assert!(err.to_string().contains("components"), "{err}");
        assert!(entries(&dir).is_empty());
    }
}
