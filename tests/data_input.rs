//! Scripts reading data files (`io::read_npy`, `io::read_csv`, `io::read_json`): the data
//! directory sandbox (absolute paths, `..`, symlinks leading out), the size limit tied to
//! `--max-memory`, malformed files (clear errors, never panics) and round trips of what the
//! writers wrote.

mod common;

use common::TempDir;
use std::path::Path;
use trnews::script::{Host, HostOptions};

fn host(out: &Path, data: &Path, max_memory: u64) -> Host {
    Host::new(HostOptions {
        out_dir: out.to_path_buf(),
        data_dir: Some(data.to_path_buf()),
        quiet: true,
        max_memory,
        ..HostOptions::default()
    })
    .expect("host")
}

/// The error of running `script`, which must fail.
fn failure(h: &Host, script: &str) -> String {
    h.run_str("t.rhai", script)
        .expect_err("the script must fail")
        .to_string()
}

#[test]
fn written_files_read_back_as_arrays_and_signals() {
    let dir = TempDir::new("round-trip");
    let h = host(&dir.0, &dir.0, 1 << 30);
    h.run_str(
        "t.rhai",
        r#"
        let s = signal::from_array(1e-8, 0.0, [0.5, -1.25, 3.0e-9, 7.0]);
        io::write_npy("a.npy", s);
        io::write_npy("m.npy", [[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]);
        io::write_csv("c.csv", ["t_s", "u"], [[0.0, 1e-8, 2e-8, 3e-8], s]);
        // the last value's nearest neighbours are one bit away: read back, it must be itself
        io::write_json("j.json", #{ name: "probe", values: [1, 2.5, 0.10920210679944317], nested: #{ ok: true } });

        let a = io::read_npy("a.npy");
        assert(type_of(a) == "array" && a.len() == 4 && a[1] == -1.25, `npy 1-D ${a}`);
        let sig = io::read_npy("a.npy", #{ dt_s: 1e-8, t0_s: 2e-6 });
        assert(sig.relative_l2(signal::from_array(1e-8, 2e-6, [0.5, -1.25, 3.0e-9, 7.0])) == 0.0, "npy as Signal");
        let m = io::read_npy("m.npy");
        assert(m.len() == 3 && m[2][1] == 6.0, `npy 2-D ${m}`);
        let rows = io::read_npy("m.npy", #{ dt_s: 1e-6 });
        assert(rows.len() == 3 && type_of(rows[0]) == "Signal" && rows[1].max_abs() == 4.0, "rows as Signals");

        let c = io::read_csv("c.csv");
        assert(c.u[3] == 7.0 && c.t_s.len() == 4, `csv ${c}`);
        let cs = io::read_csv("c.csv", #{ time_column: "t_s" });
        assert(cs.keys() == ["u"] && cs.u.relative_l2(s) == 0.0 && abs(cs.u.dt - 1e-8) < 1e-20, "csv time column");
        let cd = io::read_csv("c.csv", #{ dt_s: 2e-8 });
        assert(cd.t_s.dt == 2e-8, "csv with dt_s");

        let j = io::read_json("j.json");
        assert(j.name == "probe" && j.values[1] == 2.5 && j.nested.ok, `json ${j}`);
        assert(j.values[2] == 0.10920210679944317, `json float ${j.values[2]}`);
        "#,
    )
    .expect("round trip");
}

#[test]
fn paths_outside_the_data_directory_are_refused() {
    let base = TempDir::new("sandbox");
    let (data, out, secret) = (
        base.0.join("data"),
        base.0.join("out"),
        base.0.join("secret"),
    );
    for d in [&data, &out, &secret] {
        std::fs::create_dir_all(d).expect("dir");
    }
    std::fs::write(secret.join("s.json"), "{\"key\": 1}").expect("secret");
    std::fs::write(data.join("ok.json"), "{\"key\": 2}").expect("ok");
    std::fs::create_dir_all(data.join("inner")).expect("inner");
    std::os::unix::fs::symlink(secret.join("s.json"), data.join("file_out.json")).expect("link");
    std::os::unix::fs::symlink(&secret, data.join("dir_out")).expect("link");
    std::os::unix::fs::symlink("../ok.json", data.join("inner/up.json")).expect("link");
    std::os::unix::fs::symlink("../../secret/s.json", data.join("inner/far.json")).expect("link");
    let h = host(&out, &data, 1 << 30);
    // a symlink that stays inside is followed
    h.run_str(
        "t.rhai",
        r#"assert(io::read_json("inner/up.json").key == 2, "inside link");"#,
    )
    .expect("a link inside the data directory is followed");
    let abs = secret.join("s.json").display().to_string();
    for (path, why) in [
        ("../secret/s.json", "'..' is not allowed"),
        (abs.as_str(), "relative to the data directory"),
        ("file_out.json", "through a symlink"),
        ("dir_out/s.json", "through a symlink"),
        ("inner/far.json", "through a symlink"),
    ] {
        let e = failure(&h, &format!("io::read_json({path:?});"));
        assert!(
            e.contains(path) && e.contains(why) && e.contains("outside the data directory"),
            "{path}: {e}"
        );
    }
    // io::exists answers inside the data directory only: true for a file (through a link that
    // stays inside), false for a directory, a missing file and every path leading out
    let outside = format!(
        "for p in [\"../secret/s.json\", {abs:?}, \"file_out.json\", \"dir_out/s.json\", \
         \"inner/far.json\"] {{ assert(!io::exists(p), p); }}"
    );
    h.run_str(
        "t.rhai",
        &format!(
            "{}{outside}",
            r#"
            assert(io::exists("ok.json") && io::exists("inner/up.json"), "inside");
            assert(!io::exists("inner") && !io::exists("nope.json"), "not files");
            "#
        ),
    )
    .expect("exists stays inside the data directory");
    // a link swapped to point out after the host opened the root is refused at use
    std::fs::remove_file(data.join("inner/up.json")).expect("unlink");
    std::os::unix::fs::symlink(secret.join("s.json"), data.join("inner/up.json")).expect("relink");
    let e = failure(&h, r#"io::read_json("inner/up.json");"#);
    assert!(e.contains("through a symlink"), "{e}");
    // a missing file names the path
    let e = failure(&h, r#"io::read_csv("nope.csv");"#);
    assert!(e.contains("nope.csv"), "{e}");
}

#[test]
fn the_data_directory_defaults_to_the_script_directory() {
    let base = TempDir::new("default");
    let (scripts, out) = (base.0.join("scripts"), base.0.join("out"));
    std::fs::create_dir_all(&scripts).expect("dir");
    std::fs::write(scripts.join("table.csv"), "a,b\n1,2\n").expect("csv");
    std::fs::write(
        scripts.join("read.rhai"),
        r#"assert(io::read_csv("table.csv").b[0] == 2.0, "beside the script");"#,
    )
    .expect("script");
    let h = Host::new(HostOptions {
        out_dir: out,
        quiet: true,
        ..HostOptions::default()
    })
    .expect("host");
    h.run_file(&scripts.join("read.rhai"))
        .expect("reads beside the script");
    let fresh = Host::new(HostOptions {
        out_dir: base.0.join("out"),
        quiet: true,
        ..HostOptions::default()
    })
    .expect("host");
    let e = fresh
        .run_str("t.rhai", r#"io::read_csv("table.csv");"#)
        .expect_err("text scripts have no data directory without --data");
    assert!(e.to_string().contains("--data"), "{e}");
}

#[test]
fn files_above_a_share_of_the_memory_limit_are_refused_with_their_size() {
    let dir = TempDir::new("size");
    // 1 MiB limit: CSV up to 1/32 (32 KiB), NPY up to 1/4 (256 KiB), JSON up to 1/64
    std::fs::write(dir.0.join("big.csv"), vec![b'1'; 100 << 10]).expect("file");
    std::fs::write(dir.0.join("big.npy"), vec![b'1'; 300 << 10]).expect("file");
    std::fs::write(dir.0.join("big.json"), vec![b'1'; 40 << 10]).expect("file");
    let h = host(&dir.0, &dir.0, 1 << 20);
    for (call, size, limit) in [
        (r#"io::read_csv("big.csv")"#, "100.000 KiB", "32.000 KiB"),
        (r#"io::read_npy("big.npy")"#, "300.000 KiB", "256.000 KiB"),
        (r#"io::read_json("big.json")"#, "40.000 KiB", "16.000 KiB"),
    ] {
        let e = failure(&h, &format!("{call};"));
        assert!(
            e.contains(size) && e.contains(limit) && e.contains("--max-memory"),
            "{e}"
        );
    }
}

#[test]
fn malformed_files_give_clear_errors() {
    let dir = TempDir::new("malformed");
    let files: [(&str, &[u8]); 7] = [
        ("text.npy", b"hello"),
        ("ragged.csv", b"a,b\n1,2\n3\n"),
        ("word.csv", b"a,b\n1,2\n3,four\n"),
        ("empty.csv", b""),
        ("bad.json", b"{\"a\": [1, 2"),
        ("deep.json", &[b'['; 10_000]),
        ("binary.csv", b"\x00\xff\xfe\n\x01"),
    ];
    for (name, bytes) in files {
        std::fs::write(dir.0.join(name), bytes).expect("file");
    }
    let mut header = b"\x93NUMPY\x01\x00".to_vec();
    let dict = b"{'descr': '<U4', 'fortran_order': False, 'shape': (2,), }";
    header.extend_from_slice(&(dict.len() as u16 + 1).to_le_bytes());
    header.extend_from_slice(dict);
    header.push(b'\n');
    header.extend_from_slice(&[0u8; 32]);
    std::fs::write(dir.0.join("strings.npy"), header).expect("file");
    std::fs::write(dir.0.join("jitter.csv"), "t,u\n0,1\n1,2\n2.5,3\n3,4\n").expect("file");
    let h = host(&dir.0, &dir.0, 1 << 30);
    for (call, expected) in [
        (r#"io::read_npy("text.npy")"#, "not an .npy file"),
        (r#"io::read_npy("strings.npy")"#, "expected float64"),
        (r#"io::read_csv("ragged.csv")"#, "ragged.csv"),
        (
            r#"io::read_csv("word.csv")"#,
            "line 3, column 'b': 'four' is not a number",
        ),
        (r#"io::read_csv("empty.csv")"#, "no header row"),
        (r#"io::read_json("bad.json")"#, "JSON"),
        (r#"io::read_json("deep.json")"#, "recursion limit"),
        (r#"io::read_csv("binary.csv")"#, "binary.csv"),
        (
            r#"io::read_csv("jitter.csv", #{ time_column: "c" })"#,
            "no such column",
        ),
        (
            r#"io::read_csv("jitter.csv", #{ dt_s: 1e-8, time_column: "t" })"#,
            "not both",
        ),
        (r#"io::read_csv("word.csv", #{ dtt: 1 })"#, "dtt"),
        (
            r#"io::read_npy("text.npy", #{ dt_s: -1 })"#,
            "not an .npy file",
        ),
    ] {
        let e = failure(&h, &format!("{call};"));
        assert!(e.contains(expected), "{call}: {e}");
        assert!(!e.contains("internal error"), "{call} panicked: {e}");
    }
    let e = failure(&h, r#"io::read_csv("jitter.csv", #{ time_column: "t" });"#);
    assert!(
        e.contains("not uniformly spaced") && e.contains("row 3"),
        "{e}"
    );
    let e = failure(
        &h,
        r#"io::write_npy("v.npy", [1.0, 2.0]); io::read_npy("v.npy", #{ dt_s: 0.0 });"#,
    );
    assert!(e.contains("dt"), "{e}");
}
