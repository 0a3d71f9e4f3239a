//! Hostile input (issue 11): the issue's reproducers, the output sandbox with symlinks, the
//! memory limit, and a seeded fuzz run over scene maps, run options, signal, plot and io calls.
//! Every case must end in `Ok` or a one-line error at `file:line:col`: no panic, no hang past
//! the budget, nothing written outside the output root, no non-finite file.
//!
//! Elapsed-time bounds here detect hangs, not speed: they are generous (30 s for work that
//! takes ~1 s alone) because the suite runs its tests in parallel on small machines.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use trnews::script::{Host, HostOptions};

mod common;

use common::TempDir;

fn host(out: &Path, time_limit_s: f64) -> Host {
    Host::new(host_options(out, time_limit_s)).expect("host")
}

/// The options of [`host`].
fn host_options(out: &Path, time_limit_s: f64) -> HostOptions {
    HostOptions {
        out_dir: out.to_path_buf(),
        quiet: true,
        max_operations: 20_000_000,
        time_limit: Some(Duration::from_secs_f64(time_limit_s)),
        ..HostOptions::default()
    }
}

/// Runs `script`; returns the error text, or None when it ran.
fn run(out: &Path, script: &str) -> Option<String> {
    host(out, 20.0)
        .run_str("t.rhai", script)
        .err()
        .map(|e| e.to_string())
}

/// Every file under `dir` (recursively).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() && !p.is_symlink() {
                out.extend(files(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

const SMOKE: &str = "scene::preset(\"smoke\", #{crack: ()})";

/// The reproducers of issue 11: each must be a clean error naming the field (or run cleanly).
#[test]
fn issue_11_reproducers_are_errors_naming_the_field() {
    let dir = TempDir::new("hostile-repro");
    let cases: Vec<(String, &str)> = vec![
        (format!("{SMOKE}.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{{duration_s: 1e-6, snapshot_every: 0}});"), "snapshot_every"),
        (format!("{SMOKE}.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{{duration_s: 1e10}});"), "duration_s"),
        (format!("trnews::responder({SMOKE}, 1e10);"), "duration_s"),
        ("scene::preset(\"smoke\", #{crack: (), receivers: #{x_m: []}});".into(), "receivers.x_m"),
        ("scene::preset(\"smoke\", #{crack: 0.0/0.0});".into(), "scene.crack = NaN"),
        ("scene::preset(\"smoke\", #{crack: #{contact: 1.0/0.0}});".into(), "scene.crack.contact = inf"),
        ("scene::preset(\"smoke\", #{crack: []});".into(), "scene.crack = []"),
        ("scene::preset(\"smoke\", #{transmitter: [1.0]});".into(), "scene.transmitter"),
        ("scene::preset(\"smoke\", #{absorbing: [\"bottom\", \"bottom\"]});".into(), "absorbing"),
        ("scene::preset(\"smoke\", #{element_size_x_m: 1e-12});".into(), "element_size_x_m"),
        ("scene::preset(\"smoke\", #{width_m: 1e6});".into(), "width_m"),
        ("scene::preset(\"smoke\", #{element_size_x_m: 1.0});".into(), "element_size_x_m = 1 m"),
        ("scene::preset(\"smoke\", #{laminate: #{min_epoxy_m: 1e30}});".into(), "min_epoxy_m"),
        ("scene::preset(\"smoke\", #{transmitter: #{peak_pa: 0.0}});".into(), "transmitter.peak_pa"),
        ("scene::preset(\"smoke\", #{crack: #{contact: #{method: #{kind: \"augmented_lagrangian\", max_iterations: 1000000000, tolerance_m: 1e-300}}}});".into(), "max_iterations"),
        ("scene::preset(\"smoke\", #{crack: #{contact: #{method: #{kind: \"exact\", bogus: 1}}}});".into(), "bogus"),
        ("scene::preset(\"smoke\", #{crack: #{contact: #{friction: -0.5}}});".into(), "contact.friction = -0.5"),
        ("scene::preset(\"smoke\", #{crack: #{contact: #{normal_stress_lag_s: -1e-9}}});".into(), "contact.normal_stress_lag_s"),
        ("plot::line(\"a.png\", #{}, [#{x: [0.0, 1.0], y: [-1e308, 1e308]}]);".into(), "exceed the plottable magnitude"),
        ("plot::heatmap(\"h.png\", #{}, [0.0, 1.0], [0.0], [[-1e308, 1e308]], \"v\");".into(), "exceed the plottable magnitude"),
        ("plot::line(\"l.png\", #{log_y: true}, [#{x: [1.0, 2.0], y: [1e-300, 1e300]}]);".into(), "decades"),
        ("io::write_npy(\"a.npy\", [1.0, 1.0/0.0]);".into(), "data[1] = inf"),
        ("io::write_json(\"a.json\", #{a: 0.0/0.0});".into(), "value.a = NaN"),
        ("io::write_csv(\"a.csv\", [\"x\"], [[0.0/0.0]]);".into(), "columns[0][0] = NaN"),
        ("io::write_csv_rows(\"r.csv\", [\"a\", \"b\"], [[\"x\", 1.0/0.0]]);".into(), "rows[0][1] = inf"),
    ];
    for (script, needle) in &cases {
        let t = Instant::now();
        let err = run(&dir.0, script).unwrap_or_else(|| panic!("ran without error: {script}"));
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        assert!(
            err.contains(needle),
            "{script}\n  -> {err}\n  (expected {needle:?})"
        );
        assert!(!err.contains("internal error"), "{err}");
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "{script} took {:?}",
            t.elapsed()
        );
    }
    // periodogram peaks with an absurd count: clean result, no abort
    assert_eq!(
        run(&dir.0, "let s = signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8); s.periodogram().peaks(10000000000, 1.0);"),
        None
    );
    // written files are all finite (nothing was written by the refused calls)
    assert!(files(&dir.0).is_empty(), "{:?}", files(&dir.0));
}

/// Sources, receivers, edge conditions and Gmsh scenes: bad input is an error naming the
/// field and the value written.
#[test]
fn open_scene_inputs_are_errors_naming_the_field() {
    let dir = TempDir::new("hostile-open-scene");
    let cases: Vec<(&str, &str)> = vec![
        (
            "#{sources: [#{kind: \"normal\", edge: \"left\", x_m: [0.0, 1e-3]}]}",
            "sources[0].x_m",
        ),
        (
            "#{sources: [#{kind: \"normal\", edge: \"top\", x_m: [2e-3, 1e-3]}]}",
            "sources[0].x_m = [0.002, 0.001]",
        ),
        (
            "#{sources: [#{kind: \"normal\", edge: \"top\", x_m: [1e-3, 1.01e-3]}]}",
            "fewer than two mesh nodes",
        ),
        ("#{sources: [#{kind: \"laser\", edge: \"top\"}]}", "laser"),
        (
            "#{sources: [#{kind: \"shear\", edge: \"middle\"}]}",
            "middle",
        ),
        (
            "#{sources: [#{kind: \"traction\", edge: \"top\"}]}",
            "angle_deg",
        ),
        (
            "#{sources: [#{kind: \"point\", x_m: 1.0, y_m: 0.0, angle_deg: 0.0}]}",
            "sources[0] = x_m = 1",
        ),
        (
            "#{sources: [#{kind: \"normal\", edge: \"top\", scale: 0.0}]}",
            "sources[0].scale = 0",
        ),
        (
            "#{sources: [#{kind: \"normal\", edge: \"top\", force: 1.0}]}",
            "force",
        ),
        (
            "#{transmitter: #{angle_deg: 90.0}, sources: [#{kind: \"normal\", edge: \"top\"}]}",
            "transmitter.angle_deg = 90",
        ),
        ("#{receivers: #{at: [#{x_m: 1e-3}]}}", "receivers.at[0]"),
        (
            "#{receivers: #{at: [#{edge: \"left\", x_m: 1e-3}]}}",
            "needs depth_m alone",
        ),
        (
            "#{receivers: #{at: [#{x_m: 1e-3, y_m: 1.0}]}}",
            "receivers.at[0] = x_m = 0.001, y_m = 1",
        ),
        ("#{receivers: #{at: [#{x_m: 1e-3, z_m: 1.0}]}}", "z_m"),
        ("#{edges: #{left: \"periodic\"}}", "edges.left = periodic"),
        ("#{edges: #{top: \"periodic\"}}", "edges.top = periodic"),
        ("#{edges: #{left: \"sticky\"}}", "sticky"),
        ("#{edges: #{front: \"free\"}}", "front"),
        (
            "#{gmsh: #{path: \"plate.msh\", materials: #{}}, crack: ()}",
            "no data directory",
        ),
    ];
    // Every case on both discretisations, but for a source segment between two nodes: spectral
    // elements integrate their polynomials over any part of a side exactly, so there it is a
    // valid load.
    let on_both = cases
        .iter()
        .flat_map(|c| ["t3", "sem"].map(|kind| (kind, c)));
    for (kind, (overrides, needle)) in on_both {
        if kind == "sem" && *needle == "fewer than two mesh nodes" {
            continue;
        }
        let script = format!("scene::preset(\"smoke\", \"{kind}\", {overrides});");
        let err = run(&dir.0, &script).unwrap_or_else(|| panic!("ran without error: {script}"));
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        assert!(
            err.contains(needle),
            "{script}\n  -> {err}\n  (expected {needle:?})"
        );
        assert!(!err.contains("internal error"), "{err}");
    }
}

/// A Gmsh scene reads its file beneath the script's directory: a symlink that leads out of
/// it is refused.
#[cfg(unix)]
#[test]
fn gmsh_files_are_read_inside_the_script_directory_symlinks_included() {
    let dir = TempDir::new("hostile-gmsh-link");
    let outside = TempDir::new("hostile-gmsh-outside");
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/gmsh_plate.msh");
    std::fs::copy(&mesh, outside.0.join("plate.msh")).unwrap();
    std::os::unix::fs::symlink(outside.0.join("plate.msh"), dir.0.join("link.msh")).unwrap();
    std::fs::copy(&mesh, dir.0.join("plate.msh")).unwrap();
    let script = |path: &str| {
        format!(
            "scene::build(#{{gmsh: #{{path: \"{path}\", materials: #{{\"1\": \"epoxy\", \"2\": \"epoxy\"}}}}, crack: (), receivers: #{{x_m: [1e-3]}}, sources: [#{{kind: \"normal\", edge: \"top\"}}]}});"
        )
    };
    let out = TempDir::new("hostile-gmsh-out");
    let run_file = |name: &str, text: &str| {
        let file = dir.0.join(name);
        std::fs::write(&file, text).unwrap();
        host(&out.0, 20.0)
            .run_file(&file)
            .err()
            .map(|e| e.to_string())
    };
    assert_eq!(run_file("inside.rhai", &script("plate.msh")), None);
    let err = run_file("link.rhai", &script("link.msh")).expect("the symlink is refused");
    assert!(err.contains("link.msh") && err.contains("outside"), "{err}");
}

/// A host reading data files beneath `data` (`--data`), with the memory limit `max_memory`.
fn data_host(out: &Path, data: &Path, max_memory: u64) -> Host {
    Host::new(HostOptions {
        out_dir: out.to_path_buf(),
        data_dir: Some(data.to_path_buf()),
        quiet: true,
        max_operations: 20_000_000,
        max_memory,
        time_limit: Some(Duration::from_secs(20)),
        ..HostOptions::default()
    })
    .expect("host")
}

/// Runs `script` on a thread and returns its error text, failing the test when the script
/// runs without error or takes more than `seconds` (a blocking open would hang the thread).
fn error_within(host: Host, script: &str, seconds: u64) -> String {
    let (tx, rx) = std::sync::mpsc::channel();
    let text = script.to_string();
    std::thread::spawn(move || {
        let _ = tx.send(host.run_str("t.rhai", &text).err().map(|e| e.to_string()));
    });
    rx.recv_timeout(Duration::from_secs(seconds))
        .unwrap_or_else(|_| panic!("no answer within {seconds} s: {script}"))
        .unwrap_or_else(|| panic!("ran without error: {script}"))
}

/// Issue 26: a FIFO in place of a data file (a Gmsh mesh too), directly or through a symlink,
/// is refused before it is opened (opening a FIFO for reading waits for a writer), within
/// seconds, naming the file.
#[cfg(unix)]
#[test]
fn a_fifo_in_place_of_a_data_file_is_refused_without_blocking() {
    let dir = TempDir::new("hostile-fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(dir.0.join("pipe.npy"))
        .status()
        .expect("mkfifo");
    assert!(made.success());
    std::os::unix::fs::symlink("pipe.npy", dir.0.join("link.csv")).expect("link");
    let out = TempDir::new("hostile-fifo-out");
    let cases = [
        (r#"io::read_npy("pipe.npy");"#, "pipe.npy"),
        (r#"io::read_csv("link.csv");"#, "link.csv"),
        (r#"io::read_json("pipe.npy");"#, "pipe.npy"),
        (
            r#"scene::build(#{gmsh: #{path: "pipe.npy", materials: #{"1": "epoxy"}}, crack: ()});"#,
            "pipe.npy",
        ),
    ];
    for (script, file) in cases {
        let t = Instant::now();
        let err = error_within(data_host(&out.0, &dir.0, 1 << 30), script, 10);
        assert!(
            err.starts_with("t.rhai:1:") && err.contains(file) && err.contains("FIFO"),
            "{script}\n  -> {err}"
        );
        assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
    }
}

/// Writes the data files crafted against the parsers into `dir`: `nested.npy` (a structured
/// dtype nested 40 deep), `extra.npy` and `twice.npy` (an unknown and a repeated header key),
/// `max.msh` and `billion.msh` (Gmsh counts of 2^64 - 1 and 10^9), `quote.csv` (a quote never
/// closed) and `dup.json` (a key twice in one object).
fn write_hostile_files(dir: &Path) {
    let npy = |name: &str, header: &str| {
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(&[0; 8]);
        std::fs::write(dir.join(name), b).expect("npy");
    };
    let nested = (0..40).fold("'<f8'".to_string(), |inner, k| {
        format!("[('f{k}', {inner})]")
    });
    npy(
        "nested.npy",
        &format!("{{'descr': {nested}, 'fortran_order': False, 'shape': (1,), }}\n"),
    );
    npy(
        "extra.npy",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'bogus': 1}\n",
    );
    npy(
        "twice.npy",
        "{'descr': '<f8', 'shape': (1,), 'fortran_order': False, 'shape': (1,)}\n",
    );
    let plate = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/gmsh_plate.msh"),
    )
    .expect("plate");
    for (name, from, to) in [
        ("max.msh", "\n0 9 0 1\n", "\n0 9 0 18446744073709551615\n"),
        (
            "billion.msh",
            "$Elements\n3 505 1 505\n",
            "$Elements\n1000000000 505 1 505\n",
        ),
    ] {
        assert!(plate.contains(from), "{from}");
        std::fs::write(dir.join(name), plate.replacen(from, to, 1)).expect("msh");
    }
    std::fs::write(dir.join("quote.csv"), "t_s,\"u\n0,1\n1,2\n").expect("csv");
    std::fs::write(dir.join("dup.json"), "{\"gain\": 1,\n \"gain\": 2}").expect("json");
}

/// Issue 26: data files crafted against the parsers are errors naming the file and what was
/// found, in linear time: an `.npy` header with a deeply nested structured dtype (exponential
/// in npyz's header parser), unknown and repeated header keys, Gmsh counts that cannot fit in
/// the file (mshio preallocates from them: 2^64 - 1 panicked, 10^9 aborted), a CSV quote never
/// closed (read as one header cell), and a JSON key repeated in one object (the last value was
/// kept silently).
#[test]
fn hostile_data_files_are_errors_naming_the_file() {
    let dir = TempDir::new("hostile-data-files");
    write_hostile_files(&dir.0);
    let gmsh = |path: &str| {
        format!("scene::build(#{{gmsh: #{{path: \"{path}\", materials: #{{\"1\": \"epoxy\", \"2\": \"epoxy\"}}}}, crack: ()}});")
    };
    let cases = [
        (
            "io::read_npy(\"nested.npy\");".to_string(),
            vec!["nested.npy", "structured dtype"],
        ),
        (
            "io::read_npy(\"extra.npy\");".into(),
            vec!["extra.npy", "unknown header key 'bogus'"],
        ),
        (
            "io::read_npy(\"twice.npy\");".into(),
            vec!["twice.npy", "'shape' appears twice"],
        ),
        (
            gmsh("max.msh"),
            vec![
                "max.msh",
                "$Nodes",
                "numNodesInBlock = 18446744073709551615",
            ],
        ),
        (
            gmsh("billion.msh"),
            vec!["billion.msh", "$Elements", "numEntityBlocks = 1000000000"],
        ),
        (
            "io::read_csv(\"quote.csv\");".into(),
            vec!["quote.csv", "line 1", "never closed"],
        ),
        (
            "io::read_json(\"dup.json\");".into(),
            vec!["dup.json", "key \"gain\" appears twice", "line 2"],
        ),
    ];
    let out = TempDir::new("hostile-data-files-out");
    for (script, needles) in &cases {
        let t = Instant::now();
        let err = error_within(data_host(&out.0, &dir.0, 1 << 30), script, 20);
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        for needle in needles {
            assert!(
                err.contains(needle),
                "{script}\n  -> {err}\n  (expected {needle:?})"
            );
        }
        assert!(!err.contains("internal error"), "{err}");
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "{script}: {:?}",
            t.elapsed()
        );
    }
}

/// Issue 26: sizes that come from input are estimated against the memory limit before
/// anything is allocated, the error naming the field and the value: a laminate of 10^9 pairs
/// (directly and in a scene), a signal's samples and times copied into script arrays (a
/// `Dynamic` a number), the FFT buffers of an envelope and of a cross-correlation, and the
/// rows of a `.npy` file expanding ~23x into script arrays (the expansion is charged, not the
/// file: `--max-memory` was overshot 5.7x).
#[test]
fn sizes_from_input_are_estimated_before_allocating() {
    let dir = TempDir::new("hostile-sizes");
    // 4 Mi rows of one int32: a 16 MiB file, within the read limit (a quarter of 256 MiB), that
    // becomes 4 Mi one-number arrays of ~88 bytes each
    let rows = 1 << 22;
    let header = format!("{{'descr': '<i4', 'fortran_order': False, 'shape': ({rows}, 1), }}");
    let header = format!("{header:<118}\n");
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
    npy.extend_from_slice(header.as_bytes());
    npy.resize(npy.len() + 4 * rows, 0);
    std::fs::write(dir.0.join("rows.npy"), npy).expect("npy");
    let big = "signal::zeros(1e-8, 0.0, 20000000)";
    let half = "signal::zeros(1e-8, 0.0, 8388608)";
    let cases = [
        (
            "laminate::stochastic(#{pairs: 1000000000});".to_string(),
            "laminate.pairs = 1000000000 would need about",
        ),
        (
            "scene::preset(\"smoke\", #{laminate: #{pairs: 1000000000}});".into(),
            "laminate.pairs = 1000000000 would need about",
        ),
        (
            format!("{big}.samples();"),
            "samples = 20000000 samples would need about",
        ),
        (
            format!("{big}.times();"),
            "times = 20000000 samples would need about",
        ),
        (
            format!("{big}.envelope();"),
            "analytic signal = 20000000 samples would need about",
        ),
        (
            format!("{half}.xcorr({half}, 0.0, 1e-6);"),
            "cross-correlation = 16777216 samples would need about",
        ),
        (
            "io::read_npy(\"rows.npy\");".into(),
            "rows.npy = 4194304 values in 4194304 rows would need about",
        ),
    ];
    let out = TempDir::new("hostile-sizes-out");
    for (script, needle) in &cases {
        let t = Instant::now();
        let err = error_within(data_host(&out.0, &dir.0, 256 << 20), script, 30);
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        assert!(
            err.contains(needle) && err.contains("256.000 MiB"),
            "{script}\n  -> {err}\n  (expected {needle:?})"
        );
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "{script}: {:?}",
            t.elapsed()
        );
    }
    // read as Signals, each of the 4 Mi rows is still a script value: refused too
    let err = error_within(
        data_host(&out.0, &dir.0, 256 << 20),
        "io::read_npy(\"rows.npy\", #{dt_s: 1e-8});",
        30,
    );
    assert!(err.contains("rows.npy = 4194304 values"), "{err}");
}

/// Issue 26: finite values outside any experiment's physical range are errors naming the
/// field, the value written and the range: a negative or specimen-wide aperture, angles of
/// 1e300 degrees, a friction coefficient of 9e18, tractions and moduli of 1e30 Pa, a density
/// of 1e6 kg/m^3, ellipse axes of metres.
#[test]
fn physical_ranges_are_errors_naming_the_field_and_value() {
    let dir = TempDir::new("hostile-ranges");
    let material = |field: &str, value: &str| {
        let constants = [
            ("e1_pa", "3.7e9"),
            ("e2_pa", "3.7e9"),
            ("e3_pa", "3.7e9"),
            ("g12_pa", "1.3e9"),
            ("nu12", "0.4"),
            ("nu13", "0.4"),
            ("nu23", "0.4"),
            ("density_kg_m3", "1200.0"),
        ]
        .map(|(f, v)| format!("{f}: {}", if f == field { value } else { v }))
        .join(", ");
        format!("#{{laminate: #{{kind: \"homogeneous\", thickness_m: 4e-3, material: #{{name: \"m\", {constants}}}}}}}")
    };
    let cases: Vec<(String, String)> = vec![
        (
            "#{receivers: #{aperture_m: -1e-3}}".into(),
            "receivers.aperture_m = -0.001: must be within [0e0, ".into(),
        ),
        (
            "#{receivers: #{aperture_m: 1.0}}".into(),
            "receivers.aperture_m = 1: must be within".into(),
        ),
        (
            "#{transmitter: #{angle_deg: 1e300}}".into(),
            format!(
                "transmitter.angle_deg = {}: must be within [-3.6e2, 3.6e2] degrees",
                1e300
            ),
        ),
        (
            "#{sources: [#{kind: \"traction\", edge: \"top\", angle_deg: -1e300}]}".into(),
            format!("sources[0].angle_deg = {}: must be within", -1e300),
        ),
        (
            "#{crack: #{contact: #{friction: 9e18}}}".into(),
            "contact.friction = 9000000000000000000: must be within [0e0, 1e1]".into(),
        ),
        (
            "#{transmitter: #{peak_pa: 1e30}}".into(),
            "transmitter.peak_pa = 1000000000000000000000000000000: must be within (0, 1e10] Pa"
                .into(),
        ),
        (
            material("e1_pa", "1e30"),
            "e1_pa = 1000000000000000000000000000000 must be within (0, 1e13] Pa".into(),
        ),
        (
            material("density_kg_m3", "1e6"),
            "density_kg_m3 = 1000000 must be within [1e0, 1e5] kg/m^3".into(),
        ),
        (
            "#{laminate: #{b_std_m: 1.0}}".into(),
            "laminate.b_std_m = 1: must be within [0e0, 1e-1] m".into(),
        ),
    ];
    for (overrides, needle) in &cases {
        let script = format!("scene::preset(\"smoke\", {overrides});");
        let err = run(&dir.0, &script).unwrap_or_else(|| panic!("ran without error: {script}"));
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        assert!(
            err.contains(needle.as_str()),
            "{script}\n  -> {err}\n  (expected {needle:?})"
        );
    }
}

/// Issue 26: fields that cannot apply are refused rather than ignored: the layered
/// rectangle's fields next to `gmsh` (whose mesh, materials and size are the file's), a
/// snapshot directory without snapshots (nothing is created), and contact options for a run
/// of a scene without a crack.
#[test]
fn fields_that_cannot_apply_are_refused() {
    let dir = TempDir::new("hostile-unused");
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/gmsh_plate.msh");
    std::fs::copy(&mesh, dir.0.join("plate.msh")).expect("mesh");
    let gmsh = |extra: &str| {
        format!("scene::build(#{{gmsh: #{{path: \"plate.msh\", materials: #{{\"1\": \"epoxy\", \"2\": \"epoxy\"}}}}, crack: (), receivers: #{{x_m: [1e-3]}}, sources: [#{{kind: \"normal\", edge: \"top\"}}]{extra}}});")
    };
    let run_of = |options: &str| {
        format!("scene::preset(\"smoke\", #{{crack: ()}}).transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{{duration_s: 2e-7, {options}}});")
    };
    let cases = [
        (
            gmsh(", width_m: 0.02"),
            "scene.width_m = 0.02 is not used with `gmsh`",
        ),
        (
            gmsh(", element_size_x_m: 1e-4"),
            "scene.element_size_x_m = 0.0001 is not used with `gmsh`",
        ),
        (
            gmsh(", laminate: #{pairs: 3}"),
            "scene.laminate = #{\"pairs\": 3} is not used with `gmsh`",
        ),
        (run_of("snapshot_dir: \"snaps\""), "snapshot_dir = "),
        (
            run_of("contact: #{friction: 0.5}"),
            "run.contact = #{\"friction\": 0.5} cannot apply",
        ),
    ];
    let out = TempDir::new("hostile-unused-out");
    assert_eq!(
        data_host(&out.0, &dir.0, 1 << 30)
            .run_str("t.rhai", &gmsh(""))
            .err()
            .map(|e| e.to_string()),
        None
    );
    for (script, needle) in &cases {
        let err = error_within(data_host(&out.0, &dir.0, 1 << 30), script, 30);
        assert!(err.starts_with("t.rhai:1:"), "no position: {err}");
        assert!(
            err.contains(needle),
            "{script}\n  -> {err}\n  (expected {needle:?})"
        );
    }
    assert!(
        !out.0.join("snaps").exists(),
        "the refused run created its snapshot directory"
    );
}

/// The operation limit 0 is refused; the time limit stops a script loop and a simulation.
#[test]
fn budgets_stop_runaway_scripts() {
    let dir = TempDir::new("hostile-budget");
    let zero = Host::new(HostOptions {
        out_dir: dir.0.clone(),
        max_operations: 0,
        ..HostOptions::default()
    });
    assert!(zero
        .err()
        .expect("refused")
        .to_string()
        .contains("--max-operations"));
    let h = Host::new(HostOptions {
        out_dir: dir.0.clone(),
        quiet: true,
        time_limit: Some(Duration::from_millis(1500)),
        ..HostOptions::default()
    })
    .expect("host");
    let t = Instant::now();
    let err = h
        .run_str("t.rhai", "let a = []; loop { a.push(a.len()); }")
        .expect_err("stops");
    assert!(t.elapsed() < Duration::from_secs(30), "{:?}", t.elapsed());
    let msg = err.to_string();
    assert!(msg.contains("time limit"), "{msg}");
    // native work: a long simulation stops at the time limit too
    let t = Instant::now();
    let err = h
        .run_str(
            "t.rhai",
            "let s = scene::preset(\"smoke\", #{crack: ()}); s.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{duration_s: 1e-3});",
        )
        .expect_err("stops");
    assert!(err.to_string().contains("time limit"), "{err}");
    assert!(t.elapsed() < Duration::from_secs(30), "{:?}", t.elapsed());
}

/// Runs `trnews-script` with `args` on `script` (written to `dir`); returns the error text
/// and the elapsed time. The binary meters its own heap (the in-process hosts of the other
/// tests share one process and so one heap, which would blur a heap limit).
fn run_binary(dir: &Path, script: &str, args: &[&str]) -> (String, Duration) {
    let path = dir.join("t.rhai");
    std::fs::write(&path, script).expect("script");
    let t = Instant::now();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_trnews-script"))
        .args(["--quiet", "--out"])
        .arg(dir.join("out"))
        .args(args)
        .arg(&path)
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    (
        String::from_utf8_lossy(&out.stderr).trim().to_string(),
        t.elapsed(),
    )
}

/// Without a time limit, native work counts against the operation budget and script values
/// against the memory limit: the issue's "1000 envelopes of a 4M-sample signal" with a budget
/// of 100,000 (previously past 60 s) and an array grown by `push` (previously quadratic, so
/// that no limit tripped) both stop with an error naming the limit, at the script position.
#[test]
fn native_work_and_script_values_are_metered() {
    let dir = TempDir::new("hostile-meter");
    let (err, elapsed) = run_binary(
        &dir.0,
        "let s = signal::zeros(1e-8, 0.0, 4000000);\nfor i in 0..1000 { let e = s.envelope(); }",
        &["--max-operations", "100000"],
    );
    assert!(
        err.contains("t.rhai:2:") && err.contains("operation limit 100000 exceeded"),
        "{err}"
    );
    assert!(err.contains("KiB allocated"), "{err}");
    // one envelope allocates ~300 MiB: the budget trips after the first
    assert!(elapsed < Duration::from_secs(30), "{elapsed:?}");

    let (err, elapsed) = run_binary(
        &dir.0,
        "let a = [];\nloop { a.push(a.len()); }",
        &["--max-memory", "0.25"],
    );
    assert!(
        err.contains("t.rhai:2:") && err.contains("above the limit of 256.000 MiB"),
        "{err}"
    );
    // 16 M pushes at ~0.4 us each
    assert!(elapsed < Duration::from_secs(60), "{elapsed:?}");

    // a request is refused on top of what the script holds: 200 MiB held, a 100 MiB signal asked
    let (err, _) = run_binary(
        &dir.0,
        "let held = signal::zeros(1e-8, 0.0, 26000000);\nlet more = signal::zeros(1e-8, 0.0, 13000000);",
        &["--max-memory", "0.25"],
    );
    assert!(err.contains("t.rhai:2:") && err.contains("in use"), "{err}");
}

/// A panic in a native function (none of the built-in ones is known to panic; this one is
/// registered to) ends the script with a one-line error naming the script and the Rust
/// location, and the host stays usable.
#[test]
fn a_panic_in_native_code_is_an_error() {
    let dir = TempDir::new("hostile-panic");
    let mut h = host(&dir.0, 20.0);
    let mut module = rhai::Module::new();
    module.set_native_fn("explode", || -> Result<(), Box<rhai::EvalAltResult>> {
        panic!("deliberate")
    });
    // The same on a rayon worker (parallel passes and delayed sweeps run there): recorded on
    // the worker, carried to the script's thread with its location.
    module.set_native_fn(
        "explode_in_parallel",
        || -> Result<(), Box<rhai::EvalAltResult>> {
            let _ = trnews::parallel::try_map(&[0, 1, 2, 3], |&i| -> Result<(), ()> {
                assert!(i != 2, "deliberate on a worker");
                Ok(())
            });
            Ok(())
        },
    );
    h.register_module("embedded", module);
    for (call, what) in [
        ("explode", "deliberate"),
        ("explode_in_parallel", "deliberate on a worker"),
    ] {
        let err = h
            .run_str("t.rhai", &format!("let x = 1;\nembedded::{call}();"))
            .expect_err("caught")
            .to_string();
        assert!(
            err.starts_with(&format!(
                "t.rhai: internal error (a bug, please report it): {what} at tests/hostile.rs:"
            )),
            "{err}"
        );
    }
    h.run_str("t.rhai", "let x = 1 + 1;")
        .expect("host still usable");
}

/// Ctrl-C (SIGINT) stops a script loop and a native simulation cleanly: exit status 1, an
/// "interrupted" error at the script position, nothing written after the interrupted call.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_scripts_and_native_runs() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let dir = TempDir::new("hostile-sigint");
    let cases = [
        (
            "loop.rhai",
            "print(\"ready\");\nlet x = 0;\nloop { x += 1; }",
        ),
        (
            "native.rhai",
            "let s = scene::preset(\"smoke\", #{crack: ()});\nprint(\"ready\");\n\
             let r = s.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{duration_s: 1e-3});\n\
             io::write_csv(\"after.csv\", [\"t\"], [[1.0]]);",
        ),
        (
            // Two simulations run in parallel on the pool's workers.
            "parallel.rhai",
            "let r = trnews::simulating(scene::preset(\"smoke\", #{crack: ()})); let c = \
             signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8);\nprint(\"ready\");\n\
             let rs = r.respond_all([c, c.scale(-1.0)], 1e-3);\n\
             io::write_csv(\"after.csv\", [\"t\"], [[1.0]]);",
        ),
    ];
    for (name, script) in cases {
        let path = dir.0.join(name);
        std::fs::write(&path, script).expect("script");
        let out = dir.0.join(format!("out-{name}"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .args(["--quiet", "--threads", "2", "--out"])
            .arg(&out)
            .arg(&path)
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        let mut lines = BufReader::new(child.stderr.take().expect("stderr")).lines();
        let first = lines.next().expect("a line").expect("text");
        assert!(first.contains("ready"), "{first}");
        std::thread::sleep(Duration::from_millis(500));
        let t = Instant::now();
        let killed = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .expect("kill");
        assert!(killed.success());
        let rest: Vec<String> = lines.map_while(Result::ok).collect();
        let status = child.wait().expect("wait");
        assert!(
            t.elapsed() < Duration::from_secs(30),
            "{name}: {:?}",
            t.elapsed()
        );
        assert_eq!(status.code(), Some(1), "{name}: {rest:?}");
        let message = rest.join("\n");
        assert!(
            message.contains(&format!("{name}:3:")) && message.contains("interrupted (Ctrl-C)"),
            "{name}: {message}"
        );
        assert!(files(&out).is_empty(), "{name}: {:?}", files(&out));
    }
}

/// A scene above the memory limit is refused in under a second, with the estimate.
#[test]
fn memory_limit_refuses_large_scenes_quickly() {
    let dir = TempDir::new("hostile-mem");
    let h = Host::new(HostOptions {
        out_dir: dir.0.clone(),
        quiet: true,
        max_memory: 64 << 20,
        ..HostOptions::default()
    })
    .expect("host");
    let t = Instant::now();
    let err = h
        .run_str(
            "t.rhai",
            "scene::build(#{element_size_x_m: 5e-6, element_size_y_m: 5e-6});",
        )
        .expect_err("refused")
        .to_string();
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    assert!(
        err.contains("would need about") && err.contains("GiB"),
        "{err}"
    );
    assert!(
        err.contains("element_size_x_m") && err.contains("64.000 MiB"),
        "{err}"
    );
    trnews::budget::set_memory_limit(trnews::budget::DEFAULT_MEMORY_LIMIT);
}

#[cfg(unix)]
#[test]
fn sandbox_symlinks_never_lead_out() {
    use std::os::unix::fs::symlink;
    let base = TempDir::new("hostile-sandbox");
    let out = base.0.join("out");
    let outside = base.0.join("outside");
    std::fs::create_dir_all(out.join("inner")).expect("dirs");
    std::fs::create_dir_all(&outside).expect("dirs");
    symlink(&outside, out.join("link")).expect("link");
    symlink("../link", out.join("inner/nested")).expect("nested link");
    symlink("inner", out.join("inside")).expect("inside link");
    let writes = [
        "io::write_csv(\"link/x.csv\", [\"a\"], [[1.0]]);",
        "io::write_npy(\"link/sub/x.npy\", [1.0]);",
        "io::write_json(\"inner/nested/x.json\", #{a: 1});",
        "plot::line(\"link/p.png\", #{}, [#{x: [0.0, 1.0], y: [1.0, 2.0]}]);",
        "plot::line(\"link/p.svg\", #{}, [#{x: [0.0, 1.0], y: [1.0, 2.0]}]);",
        "let s = scene::preset(\"smoke\", #{crack: ()}); s.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{duration_s: 2e-7, snapshot_every: 5, snapshot_dir: \"link/snaps\"});",
    ];
    for w in writes {
        let err = run(&out, w).unwrap_or_else(|| panic!("wrote through the link: {w}"));
        assert!(
            err.contains("leads outside the output directory"),
            "{w}: {err}"
        );
    }
    // a link that stays inside is fine
    assert_eq!(
        run(&out, "io::write_csv(\"inside/ok.csv\", [\"a\"], [[1.0]]);"),
        None
    );
    assert!(out.join("inner/ok.csv").is_file());
    // swapped while a script writes: a thread flips `flip` between inside and outside
    let flip = out.join("flip");
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flipper = {
        let (flip, outside, stop) = (flip.clone(), outside.clone(), stop.clone());
        std::thread::spawn(move || {
            let mut k = 0u64;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let tmp = flip.with_file_name(format!("flip.tmp{k}"));
                let target: &Path = if k.is_multiple_of(2) {
                    Path::new("inner")
                } else {
                    &outside
                };
                let _ = symlink(target, &tmp);
                let _ = std::fs::rename(&tmp, &flip);
                k += 1;
            }
        })
    };
    let _ = run(
        &out,
        "for i in 0..400 { try { io::write_csv(`flip/f${i}.csv`, [\"a\"], [[1.0]]); } catch {} }",
    );
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    flipper.join().expect("flipper");
    assert!(
        files(&outside).is_empty(),
        "written outside: {:?}",
        files(&outside)
    );
    assert!(
        files(&out.join("inner")).len() > 1,
        "some writes went through the inside link"
    );
}

#[test]
fn stale_temp_files_of_dead_writers_are_removed() {
    let dir = TempDir::new("hostile-stale");
    // An hour and a minute old, its lock free: its writer is gone.
    let stale = dir.0.join(".x.tmp-00ff00ff00ff00ff.csv");
    std::fs::write(&stale, "half").expect("stale");
    let old = std::time::SystemTime::now() - Duration::from_secs(3660);
    std::fs::File::options()
        .write(true)
        .open(&stale)
        .and_then(|f| f.set_modified(old))
        .expect("age");
    assert_eq!(
        run(&dir.0, "io::write_csv(\"x.csv\", [\"a\"], [[1.0]]);"),
        None
    );
    assert!(!stale.exists(), "stale temp file left");
    assert!(dir.0.join("x.csv").is_file());
}

/// The time limit stops simulations that run on rayon's workers: a parallel TR-NEWS pass of two
/// 2 ms transmissions (tens of seconds of work) and a delayed sweep whose points each simulate
/// 0.39 ms of delay beyond a 0.4 ms focus (the delay fits within after_focus_s, as delayed
/// TR-NEWS requires), its first pass read back from the store of a previous run. Each must stop
/// at its limit, not when the workers finish.
#[test]
fn time_limit_stops_parallel_passes_and_delayed_sweeps() {
    let dir = TempDir::new("hostile-parallel-limit");
    let script = "let r = trnews::simulating(scene::preset(\"smoke\", #{}));\n\
        let c = signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8);\n\
        if param(\"pass\", false) { r.respond_all([c, c.scale(-1.0)], 2e-3); }\n\
        let spec = trnews::preset_spec(\"smoke\");\n\
        spec.after_focus_s = 4e-4;\n\
        let tr = trnews::tr_news(r, spec);\n\
        let points = [];\n\
        for i in 0..param(\"points\", 0) { points.push(#{delays: [0.0, 3.9e-4], amplitudes: [1.0, -1.0 * i]}); }\n\
        if points.len() > 0 { trnews::delayed(r, tr, 3, points, 3e-6); }\n";
    let (err, elapsed) = run_binary(
        &dir.0,
        script,
        &["--threads", "2", "--time-limit", "1", "--set", "pass=true"],
    );
    assert!(
        err.contains("t.rhai:3:") && err.contains("time limit 1 s"),
        "{err}"
    );
    assert!(
        elapsed < Duration::from_secs(10),
        "the pass ran on: {elapsed:?}"
    );
    // The first pass, stored; then the delayed sweep under a limit.
    let stored = std::process::Command::new(env!("CARGO_BIN_EXE_trnews-script"))
        .args(["--quiet", "--threads", "2", "--out"])
        .arg(dir.0.join("out"))
        .arg(dir.0.join("t.rhai"))
        .status()
        .expect("first pass");
    assert!(stored.success());
    let (err, elapsed) = run_binary(
        &dir.0,
        script,
        &["--threads", "2", "--time-limit", "2", "--set", "points=4"],
    );
    assert!(
        err.contains("t.rhai:9:") && err.contains("time limit 2 s"),
        "{err}"
    );
    assert!(
        elapsed < Duration::from_secs(12),
        "the sweep ran on: {elapsed:?}"
    );
}

/// `trnews-script slurm` on scripts whose names carry shell syntax (quotes, `$(...)`,
/// backticks, `;`) and `--set` values that do: the batch file, run by bash as a Slurm task
/// would run it, runs the script by its name and executes nothing from a name. Names with a
/// newline (which would end a `#SBATCH` line or a comment and start a command) are refused,
/// naming the field, and no batch file is written.
#[test]
fn slurm_batch_files_execute_nothing_from_names() {
    let dir = TempDir::new("hostile-slurm");
    let marker = dir.0.join("PWNED");
    let hostile = [
        "a$(touch PWNED).rhai",
        "b`touch PWNED`.rhai",
        "c';touch PWNED;'.rhai",
        "d\"$(touch PWNED)\".rhai",
        "e%A $HOME \\ x.rhai",
    ];
    let value = "tag=x'$(touch PWNED)`touch PWNED`";
    for name in hostile {
        let script = dir.script(name, "print(`ran ${param(\"tag\", \"\")}`);");
        let out = dir.0.join("out");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .current_dir(&dir.0)
            .arg("slurm")
            .arg(&script)
            .args(["--array", "1", "--set", value, "--out"])
            .arg(&out)
            .output()
            .expect("slurm");
        assert!(o.status.success(), "{name}: {o:?}");
        let batch = files(&out.join("slurm"))
            .into_iter()
            .find(|p| p.to_string_lossy().ends_with("-array.sbatch"))
            .expect("array batch file");
        let text = std::fs::read_to_string(&batch).expect("batch");
        assert!(
            text.lines().filter(|l| l.starts_with("#SBATCH")).count() >= 4,
            "{name}: {text}"
        );
        let ran = std::process::Command::new("bash")
            .arg(&batch)
            .current_dir(&dir.0)
            .env("SLURM_ARRAY_TASK_ID", "0")
            .env("SLURM_ARRAY_TASK_COUNT", "1")
            .output()
            .expect("bash");
        let said = String::from_utf8_lossy(&ran.stderr) + String::from_utf8_lossy(&ran.stdout);
        assert!(
            ran.status.success() && said.contains("] ran x'$(touch PWNED)`touch PWNED`"),
            "{name}: {ran:?}\n{text}"
        );
        assert!(
            !marker.exists(),
            "{name}: a command ran from a name:\n{text}"
        );
        std::fs::remove_dir_all(&out).expect("clean");
    }
    for (args, field) in [
        (vec!["x\ntouch PWNED\n.rhai"], "the script's path"),
        (vec!["ok.rhai", "--set", "a=1\ntouch PWNED"], "--set"),
        (
            vec!["ok.rhai", "--partition", "p\n#SBATCH --x"],
            "--partition",
        ),
        (vec!["ok.rhai", "--time", "1:00 $(touch PWNED)"], "--time"),
    ] {
        dir.script(args[0], "print(1);");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .current_dir(&dir.0)
            .arg("slurm")
            .args(&args)
            .args(["--array", "2", "--out", "refused"])
            .output()
            .expect("slurm");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(field),
            "{args:?}: {err}"
        );
        assert!(
            !dir.0.join("refused/slurm").exists(),
            "{args:?}: files written"
        );
    }
    assert!(!marker.exists());
}

// ------------------------------------------------------------------ fuzz

/// A small seeded generator (SplitMix64). Written by hand rather than with proptest: the
/// cases are Rhai source texts run by one shared host, where shrinking would not apply, and
/// the seed alone must reproduce a failure (`TRNEWS_FUZZ_SEED`, `TRNEWS_FUZZ_CASES`).
struct Gen(u64);
impl Gen {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn pick<'a>(&mut self, v: &[&'a str]) -> &'a str {
        v[(self.next() % v.len() as u64) as usize]
    }
    fn value(&mut self) -> String {
        self.pick(&[
            "0.0/0.0",
            "1.0/0.0",
            "-1.0/0.0",
            "()",
            "[]",
            "#{}",
            "[1.0]",
            "0",
            "-1",
            "0.0",
            "1e-300",
            "1e300",
            "1e30",
            "1e-12",
            "1.0",
            "1e10",
            "\"x\"",
            "true",
            "#{x: 1}",
            "9223372036854775807",
            "1e-18",
            "5e-7",
            "2e-3",
        ])
        .to_string()
    }
}

const SCENE_FIELDS: &[&str] = &[
    "width_m",
    "element_size_x_m",
    "element_size_y_m",
    "absorbing",
    "absorber",
    "transducer",
    "transmitter",
    "receivers",
    "crack",
    "laminate",
    "plane",
    "fix_bottom_corners",
    "transmitter.peak_pa",
    "transmitter.depth_top_m",
    "receivers.x_m",
    "crack.depth_m",
    "crack.contact",
    "crack.tied",
    "crack.contact.friction",
    "crack.contact.normal_stress_lag_s",
    "laminate.min_epoxy_m",
    "laminate.pairs",
    "absorber.kind",
    "sources",
    "edges",
    "edges.left",
    "receivers.at",
    "gmsh",
    "receivers.aperture_m",
    "transmitter.angle_deg",
    "laminate.b_std_m",
];
const RUN_FIELDS: &[&str] = &[
    "duration_s",
    "dt_s",
    "snapshot_every",
    "ledger_every",
    "integrator",
    "force",
    "bogus",
    "record_crack",
    "contact",
    "snapshot_dir",
];

/// A map literal setting dotted `field` to `value`.
fn nested(field: &str, value: &str) -> String {
    match field.split_once('.') {
        Some((a, rest)) => format!("#{{{a}: {}}}", nested(rest, value)),
        None => format!("#{{{field}: {value}}}"),
    }
}

fn case(g: &mut Gen) -> (String, String) {
    let v = g.value();
    match g.next() % 5 {
        0 => {
            let f = g.pick(SCENE_FIELDS);
            (
                format!("scene::preset(\"smoke\", {});", nested(f, &v)),
                f.to_string(),
            )
        }
        1 => {
            let f = g.pick(RUN_FIELDS);
            (format!("let s = scene::preset(\"smoke\", #{{crack: ()}}); s.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{{duration_s: 2e-7, {f}: {v}}});"), f.to_string())
        }
        2 => {
            let call = g.pick(&[
                "signal::chirp(V, 2e6, 5e-6, 5e-6, 1e-8)",
                "signal::chirp(2e5, 2e6, V, 5e-6, 1e-8)",
                "signal::chirp(2e5, 2e6, 5e-6, 5e-6, V)",
                "signal::chirp(#{dt_s: 1e-8, t1_s: 5e-6, total_s: 5e-6, amplitude: V})",
                "signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8).envelope().scale(V)",
                "signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8).periodogram().peaks(V, 1.0)",
                "signal::zeros(1e-8, 0.0, V).samples()",
                "signal::zeros(1e-8, 0.0, V).envelope()",
                "signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8).xcorr(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), -V, V)",
                "laminate::stochastic(#{pairs: V})",
            ]);
            (format!("{};", call.replace('V', &v)), String::new())
        }
        3 => {
            let call = g.pick(&[
                "plot::line(\"f.png\", #{}, [#{x: [0.0, 1.0], y: [V, 1.0]}])",
                "plot::line(\"f.png\", #{log_y: true}, [#{x: [1.0, 2.0], y: [1.0, V]}])",
                "plot::heatmap(\"h.png\", #{}, [0.0, 1.0], [0.0], [[V, 1.0]], \"v\")",
                "plot::line(\"f.png\", #{title: V}, [#{x: [0.0, 1.0], y: [1.0, 2.0]}])",
            ]);
            (format!("{};", call.replace('V', &v)), String::new())
        }
        _ => {
            let call = g.pick(&[
                "io::write_npy(\"a.npy\", [V])",
                "io::write_json(\"a.json\", #{a: V})",
                "io::write_csv(\"a.csv\", [\"x\"], [[V]])",
                "io::write_csv(V, [\"x\"], [[1.0]])",
                "io::read_npy(\"nested.npy\") + V",
                "io::read_csv(\"quote.csv\") + V",
                "io::read_json(\"dup.json\") + V",
                "scene::build(#{gmsh: #{path: \"max.msh\", materials: #{\"1\": \"epoxy\"}}, crack: (), width_m: V})",
            ]);
            (format!("{};", call.replace('V', &v)), String::new())
        }
    }
}

/// No file written under `dir` holds a non-finite number (CSV text, JSON, NPY float64).
fn assert_finite_files(dir: &Path) {
    for f in files(dir) {
        let bytes = std::fs::read(&f).unwrap_or_default();
        let name = f.to_string_lossy().to_string();
        if name.ends_with(".npy") {
            let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
            for c in bytes[10 + hlen..].chunks_exact(8) {
                let v = f64::from_le_bytes(c.try_into().expect("8"));
                assert!(v.is_finite(), "{name} holds {v}");
            }
        } else if name.ends_with(".csv") || name.ends_with(".json") {
            let text = String::from_utf8_lossy(&bytes);
            assert!(
                !text.contains("NaN") && !text.contains("inf") && !text.contains("null"),
                "{name}: {text}"
            );
        }
    }
}

#[test]
fn fuzz_scene_run_signal_plot_and_io_calls() {
    let seed: u64 = std::env::var("TRNEWS_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(11);
    let cases: usize = std::env::var("TRNEWS_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300);
    let budget_s = 10.0;
    let dir = TempDir::new("hostile-fuzz");
    let data = TempDir::new("hostile-fuzz-data");
    write_hostile_files(&data.0);
    let h = Host::new(HostOptions {
        data_dir: Some(data.0.clone()),
        ..host_options(&dir.0, budget_s)
    })
    .expect("host");
    let mut g = Gen(seed);
    let start = Instant::now();
    let (mut ok, mut errors) = (0, 0);
    for i in 0..cases {
        let (script, field) = case(&mut g);
        let t = Instant::now();
        match h.run_str("fuzz.rhai", &script) {
            Ok(()) => ok += 1,
            Err(e) => {
                errors += 1;
                let msg = e.to_string();
                assert!(
                    !msg.contains("internal error"),
                    "case {i} (seed {seed}): {script}\n  -> {msg}"
                );
                assert!(
                    msg.starts_with("fuzz.rhai:1:"),
                    "case {i}: no position: {msg}"
                );
                if !field.is_empty() && !msg.contains("time limit") {
                    assert!(
                        field.split('.').any(|part| msg.contains(part)),
                        "case {i} (seed {seed}): the error does not name {field}: {script}\n  -> {msg}"
                    );
                }
            }
        }
        assert!(
            t.elapsed().as_secs_f64() < budget_s + 5.0,
            "case {i} hung: {script}"
        );
    }
    assert_finite_files(&dir.0);
    eprintln!(
        "fuzz: seed {seed}, {cases} cases ({ok} ran, {errors} errors) in {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

/// A mutation of `bytes`: flipped, cut, grown, or with a number made huge.
/// A point file whose payload is mutated and followed by its SHA-256 again: only the typed
/// checks after decoding stand between it and a run.
fn resigned(g: &mut Gen, point: &[u8]) -> Vec<u8> {
    use sha2::{Digest, Sha256};
    let body = &point[..point.len() - 32];
    let mut forged = match g.next() % 3 {
        0 => mutate(g, body),
        // A value's bytes changed in place: the layout stays valid more often.
        _ => {
            let mut b = body.to_vec();
            let i = body.len() / 2 + (g.next() % (body.len() / 2) as u64) as usize;
            b[i] = (g.next() % 256) as u8;
            b
        }
    };
    let sum = Sha256::digest(&forged);
    forged.extend_from_slice(&sum);
    forged
}

fn mutate(g: &mut Gen, bytes: &[u8]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let at = |g: &mut Gen, len: usize| (g.next() % len.max(1) as u64) as usize;
    match g.next() % 5 {
        0 => {
            for _ in 0..1 + g.next() % 8 {
                let i = at(g, b.len());
                if let Some(x) = b.get_mut(i) {
                    *x ^= 1 << (g.next() % 8);
                }
            }
        }
        1 => b.truncate(at(g, b.len())),
        2 => {
            let i = at(g, b.len());
            let junk = g.pick(&[
                "((((((((",
                "[[[[[[[[",
                "[('a', ",
                "\"",
                "\n",
                "\0",
                "{'a': 1, 'a': 2}",
            ]);
            b.splice(
                i..i,
                junk.bytes()
                    .cycle()
                    .take(junk.len() * (1 + (g.next() % 64) as usize)),
            );
        }
        3 => {
            // A number made huge: a count, a shape, a length.
            let digits: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
            if !digits.is_empty() {
                let i = digits[at(g, digits.len())];
                let huge = g.pick(&["18446744073709551615", "1000000000", "99999999999999999999"]);
                b.splice(i..i + 1, huge.bytes());
            }
        }
        _ => b.extend(std::iter::repeat_n(b'9', (g.next() % 4096) as usize)),
    }
    b
}

/// Valid files of every format a script reads, written by the library itself (and the Gmsh
/// mesh of the test scripts), as (name, bytes, the script line that reads it).
fn readable_files(dir: &Path) -> Vec<(String, Vec<u8>, String)> {
    let h = host(dir, 20.0);
    h.run_str(
        "w.rhai",
        "io::write_npy(\"a.npy\", [[1.0, 2.0], [3.0, 4.0]]); io::write_csv(\"a.csv\", [\"x\", \
         \"y\"], [[1.0], [2.0]]); io::write_json(\"a.json\", #{a: [1.0, 2.0], b: \"c\"});",
    )
    .expect("written");
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts/gmsh_plate.msh");
    let gmsh = "scene::build(#{gmsh: #{path: \"a.msh\", materials: #{\"1\": \"epoxy\", \"2\": \
                \"epoxy\"}}, crack: (), receivers: #{x_m: [1e-3]}, sources: [#{kind: \"normal\", \
                edge: \"top\"}]});";
    ["a.npy", "a.csv", "a.json"]
        .iter()
        .map(|n| {
            let read = format!("io::read_{}(\"{n}\");", &n[2..]);
            (
                n.to_string(),
                std::fs::read(dir.join(n)).expect("read"),
                read,
            )
        })
        .chain([(
            "a.msh".into(),
            std::fs::read(mesh).expect("mesh"),
            gmsh.into(),
        )])
        .collect()
}

/// A hostile name for `trnews-script slurm`'s script: shell syntax, control characters, `%`.
fn hostile_name(g: &mut Gen) -> String {
    let parts = [
        "a",
        "$(touch PWNED)",
        "`touch PWNED`",
        "'",
        "\"",
        ";",
        "\n",
        "\r",
        "%A",
        " ",
        "\\",
        "$HOME",
        "é",
        "#SBATCH --x",
        "&&",
        "|",
        ">x",
        "*",
    ];
    let mut name: String = (0..1 + g.next() % 4).map(|_| g.pick(&parts)).collect();
    name.push_str(".rhai");
    name.replace('/', "_")
}

/// The seeded fuzz run over the files and names a run reads or writes (issue 26): mutated
/// data files (NPY, CSV, JSON) and Gmsh meshes read by a script, mutated or replaced point
/// files of a stored sweep, and hostile script names given to `trnews-script slurm`. Each
/// case is `Ok` (a point file recomputed, a batch file that runs the script by its name) or a
/// one-line error at the script position, within the time budget; nothing runs from a name.
/// `TRNEWS_FUZZ_SEED` and `TRNEWS_FUZZ_CASES` set the run (docs/src/guide/sandbox.md gives a longer one).
#[test]
fn fuzz_data_point_gmsh_files_and_slurm_names() {
    let seed: u64 = std::env::var("TRNEWS_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(26);
    let cases: usize = std::env::var("TRNEWS_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(120);
    let budget_s = 10.0;
    let dir = TempDir::new("hostile-fuzz-files");
    let data = dir.0.join("data");
    std::fs::create_dir_all(&data).expect("data");
    let originals = readable_files(&data);
    let h = Host::new(HostOptions {
        out_dir: dir.0.join("out"),
        data_dir: Some(data.clone()),
        quiet: true,
        max_operations: 20_000_000,
        time_limit: Some(Duration::from_secs_f64(budget_s)),
        ..HostOptions::default()
    })
    .expect("host");
    // Point files of three kinds: a study sweep's values, a TR-NEWS first pass and a delayed
    // point (on a measured channel: two receivers' impulse responses made up in the script).
    let sweep = "let v = study::sweep(\"s\", #{}, [1, 2, 3], |p| #{x: p * 0.5, y: [p]}); \
                 if v[2].x != 1.5 || v[0].y[0] != 1 { throw \"wrong value read back\"; } \
                 let h = []; for r in 0..2 { let x = []; x.pad(4000, 0.0); x[100 + 50 * r] = 1.0; \
                 x[700] = -0.5; h.push(signal::from_array(1e-8, 0.0, x)); } \
                 let c = trnews::channel_from_impulse(h, #{peak_drive: 1.0}); \
                 let tr = trnews::tr_news(c, #{record_s: 15e-6, window_s: 15e-6, \
                 after_focus_s: 5e-6, chirp: #{t1_s: 8e-6, total_s: 10e-6}, receivers: [2]}); \
                 trnews::delayed(c, tr, 2, [#{delays: [0.0, 1e-6], amplitudes: [1.0, 0.5]}], 2e-6);";
    h.run_str("fuzz.rhai", sweep).expect("sweep stored");
    let points: Vec<PathBuf> = files(&dir.0.join("out/points"));
    assert_eq!(points.len(), 5, "{points:?}");
    let point_bytes: Vec<Vec<u8>> = points.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let marker = dir.0.join("PWNED");
    let mut g = Gen(seed);
    let start = Instant::now();
    let (mut ok, mut errors) = (0, 0);
    for i in 0..cases {
        let t = Instant::now();
        let (what, result) = match g.next() % 3 {
            0 => {
                let (name, bytes, read) = &originals[(g.next() % 4) as usize];
                std::fs::write(data.join(name), mutate(&mut g, bytes)).expect("mutated");
                let result = h.run_str("fuzz.rhai", read).map_err(|e| e.to_string());
                (format!("{name} mutated"), result)
            }
            1 => {
                let k = (g.next() % points.len() as u64) as usize;
                let _ = std::fs::remove_file(&points[k]);
                match g.next() % 4 {
                    0 => {
                        let made = std::process::Command::new("mkfifo")
                            .arg(&points[k])
                            .status();
                        assert!(made.is_ok_and(|s| s.success()), "mkfifo");
                    }
                    1 => {
                        std::fs::write(&points[k], mutate(&mut g, &point_bytes[k])).expect("point")
                    }
                    // A forgery: the payload mutated and signed again with a valid checksum.
                    _ => std::fs::write(&points[k], resigned(&mut g, &point_bytes[k]))
                        .expect("point"),
                }
                let result = h.run_str("fuzz.rhai", sweep).map_err(|e| e.to_string());
                ("a point file".into(), result)
            }
            _ => {
                let name = hostile_name(&mut g);
                let o = std::process::Command::new(env!("CARGO_BIN_EXE_trnews-script"))
                    .current_dir(&dir.0)
                    .arg("slurm")
                    .arg(dir.script(&name, "print(\"ran\");"))
                    .args(["--array", "1", "--out", "slurm-out"])
                    .output()
                    .expect("slurm");
                let batch = files(&dir.0.join("slurm-out/slurm"))
                    .into_iter()
                    .find(|p| p.to_string_lossy().ends_with("-array.sbatch"));
                let result = match (o.status.success(), batch) {
                    (true, Some(batch)) => {
                        let ran = std::process::Command::new("bash")
                            .arg(&batch)
                            .current_dir(&dir.0)
                            .env("SLURM_ARRAY_TASK_ID", "0")
                            .env("SLURM_ARRAY_TASK_COUNT", "1")
                            .output()
                            .expect("bash");
                        let said = String::from_utf8_lossy(&ran.stderr);
                        assert!(
                            ran.status.success() && said.contains("] ran"),
                            "case {i} (seed {seed}) {name:?}: {ran:?}"
                        );
                        Ok(())
                    }
                    (false, None) => {
                        let err = String::from_utf8_lossy(&o.stderr).into_owned();
                        assert!(err.contains("control character"), "{name:?}: {err}");
                        Err(err)
                    }
                    other => panic!("case {i} (seed {seed}) {name:?}: {o:?} {other:?}"),
                };
                let _ = std::fs::remove_dir_all(dir.0.join("slurm-out"));
                assert!(
                    !marker.exists(),
                    "case {i} (seed {seed}): a name ran: {name:?}"
                );
                (format!("slurm name {name:?}"), result)
            }
        };
        match result {
            Ok(()) => ok += 1,
            Err(msg) => {
                errors += 1;
                assert!(
                    !msg.contains("internal error") && !msg.contains("panicked"),
                    "case {i} (seed {seed}): {what}\n  -> {msg}"
                );
                assert!(
                    msg.starts_with("fuzz.rhai:1:") || what.starts_with("slurm"),
                    "case {i} (seed {seed}): {what}: no position: {msg}"
                );
            }
        }
        assert!(
            t.elapsed().as_secs_f64() < budget_s + 5.0,
            "case {i} (seed {seed}) hung: {what}"
        );
    }
    assert_finite_files(&dir.0.join("out"));
    eprintln!(
        "fuzz (files and names): seed {seed}, {cases} cases ({ok} ran, {errors} errors) in \
         {:.1} s",
        start.elapsed().as_secs_f64()
    );
}
