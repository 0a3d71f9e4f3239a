//! Tests of the writers: atomic replacement, CSV, JSON and NPY.

use super::*;
use serde::Serialize;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A fresh, empty directory under the system temp dir, removed on drop (the library's unit
/// tests share it).
pub(crate) struct TempDir(PathBuf);

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

pub(crate) fn temp_dir(tag: &str) -> TempDir {
    static N: AtomicU64 = AtomicU64::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let name = format!("trnews-unit-{tag}-{}-{n}", std::process::id());
    let dir = std::env::temp_dir().join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    TempDir(dir)
}

/// Names of the entries of `dir`.
pub(super) fn entries(dir: &Path) -> Vec<String> {
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

/// A symlink where the target goes is replaced by the file, never followed: the file it
/// points to (outside, say) keeps its bytes. Written with and without an output root.
#[cfg(unix)]
#[test]
fn atomic_write_replaces_a_symlink_and_never_writes_through_it() {
    let dir = temp_dir("atomic-link");
    let victim = dir.join("victim.txt");
    fs::write(&victim, b"precious").expect("victim");
    let inside = dir.join("out");
    fs::create_dir_all(&inside).expect("out");
    for (i, root) in [None, Some(OutputRoot::open(&inside).expect("root"))]
        .into_iter()
        .enumerate()
    {
        let link = inside.join(format!("x{i}.csv"));
        std::os::unix::fs::symlink(&victim, &link).expect("link");
        let write = || write_atomic(&link, b"new");
        match &root {
            Some(r) => r.within(write),
            None => write(),
        }
        .expect("write");
        assert!(!link.is_symlink(), "the link was not replaced");
        assert_eq!(fs::read(&link).expect("read"), b"new");
        assert_eq!(fs::read(&victim).expect("victim"), b"precious");
    }
}

/// Two temporary names of one target differ, keep the extension and hide the file.
#[test]
fn temporary_names_are_random_hidden_siblings() {
    let a = super::atomic::temp_name(Path::new("fig.svg"));
    let b = super::atomic::temp_name(Path::new("fig.svg"));
    assert_ne!(a, b);
    for t in [&a, &b] {
        assert!(t.starts_with(".fig.tmp-") && t.ends_with(".svg"), "{t}");
        assert_eq!(t.len(), ".fig.tmp-".len() + 16 + ".svg".len(), "{t}");
    }
}

/// The stale sweep removes only what it can prove dead: an hour-old temporary file whose lock
/// is free. A locked one (a live writer, on this host or another sharing the file system), a
/// fresh one (a writer whose locks this host may not see), a FIFO and a symlink under a
/// temporary name all stay, and nothing blocks.
#[cfg(unix)]
#[test]
fn stale_sweep_removes_only_old_unlocked_temporaries() {
    let dir = temp_dir("atomic-stale");
    let old = std::time::SystemTime::now() - std::time::Duration::from_secs(7200);
    let make = |name: &str, aged: bool| {
        let p = dir.join(name);
        fs::write(&p, b"half").expect("temp");
        let f = fs::File::options().write(true).open(&p).expect("open");
        if aged {
            f.set_modified(old).expect("age");
        }
        f
    };
    drop(make(".x.tmp-0123456789abcdef.csv", true));
    let live = make(".x.tmp-1111111111111111.csv", true);
    live.lock().expect("a live writer's lock");
    drop(make(".x.tmp-2222222222222222.csv", false));
    drop(make(".x.tmp-777-3.csv", true));
    drop(make(".y.tmp-3333333333333333.csv", true));
    let fifo = dir.join(".x.tmp-4444444444444444.csv");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    std::os::unix::fs::symlink(dir.join("nowhere"), dir.join(".x.tmp-5555555555555555.csv"))
        .expect("link");
    write_atomic(&dir.join("x.csv"), b"whole").expect("write");
    let mut left = entries(&dir);
    left.retain(|n| n != "x.csv");
    let mut expected = vec![
        ".x.tmp-1111111111111111.csv",
        ".x.tmp-2222222222222222.csv",
        ".x.tmp-5555555555555555.csv",
        ".y.tmp-3333333333333333.csv",
    ];
    if made.is_ok_and(|s| s.success()) {
        expected.push(".x.tmp-4444444444444444.csv");
    }
    expected.sort();
    assert_eq!(left, expected);
    drop(live);
}

#[test]
fn atomic_write_error_names_path() {
    let dir = temp_dir("atomic-err");
    let blocker = dir.join("file");
    write_atomic(&blocker, b"x").expect("write");
    let err = write_atomic(&blocker.join("child.txt"), b"y").expect_err("must fail");
    assert!(err.to_string().contains("file"), "{err}");
}

#[cfg(feature = "io")]
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

#[cfg(feature = "io")]
#[test]
fn csv_unequal_columns_error_names_column() {
    let dir = temp_dir("csv-bad");
    let err = write_csv(&dir.join("t.csv"), &["a", "bee"], &[&[1.0, 2.0], &[1.0]])
        .expect_err("must fail");
    let msg = err.to_string();
    assert!(msg.contains("bee") && msg.contains("t.csv"), "{msg}");
    assert!(entries(&dir).is_empty());
}

#[cfg(feature = "io")]
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

/// Typed rows: the header from the field names, floats in the round-trip format (as the
/// dynamic writers write them), integers and text as they are.
#[cfg(feature = "io")]
#[test]
fn csv_typed_rows_match_dynamic_rows() {
    use super::csv::{write_rows, RoundTrip};
    #[derive(Serialize)]
    struct Row<'a> {
        integrator: &'a str,
        dt_s: RoundTrip,
        steps: usize,
    }
    let dir = temp_dir("csv-typed");
    let (typed, dynamic) = (dir.join("typed.csv"), dir.join("dynamic.csv"));
    let rows = [
        Row {
            integrator: "explicit, lumped",
            dt_s: RoundTrip(1e-9),
            steps: 3,
        },
        Row {
            integrator: "newmark",
            dt_s: RoundTrip(1.0),
            steps: 40,
        },
    ];
    write_rows(&typed, &rows).expect("typed");
    let headers = ["integrator", "dt_s", "steps"].map(String::from).to_vec();
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.integrator.to_string(),
                fmt_f64(r.dt_s.0),
                r.steps.to_string(),
            ]
        })
        .collect();
    write_csv_rows(&dynamic, &headers, &table).expect("dynamic");
    let text = fs::read_to_string(&typed).expect("read");
    assert_eq!(
        text,
        "integrator,dt_s,steps\n\"explicit, lumped\",1e-9,3\nnewmark,1,40\n"
    );
    assert_eq!(text, fs::read_to_string(&dynamic).expect("read"));
}
