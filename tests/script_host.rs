//! The scripting host as users meet it: every regression script in tests/scripts passes,
//! and the `trnews-script` binary fails with one clear line naming file, line and column.

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use trnews::script::{Host, HostOptions};

fn scripts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scripts")
}

/// Runs one regression script through the host with `out` as output dir.
fn run_script(path: &Path, out: &Path) -> Result<(), String> {
    let host = Host::new(HostOptions {
        out_dir: out.to_path_buf(),
        quiet: true,
        ..HostOptions::default()
    })
    .map_err(|e| e.to_string())?;
    host.run_file(path).map_err(|e| e.to_string())
}

#[test]
fn every_regression_script_passes() {
    let mut scripts: Vec<PathBuf> = std::fs::read_dir(scripts_dir())
        .expect("tests/scripts exists")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    scripts.sort();
    assert!(
        scripts.len() >= 4,
        "expected the regression scripts, found {scripts:?}"
    );
    let failures: Vec<String> = scripts
        .iter()
        .filter_map(|s| {
            let name = s.file_stem().unwrap().to_string_lossy().to_string();
            let out = TempDir::new(&format!("regression-{name}"));
            run_script(s, out.path()).err()
        })
        .collect();
    assert!(
        failures.is_empty(),
        "failing scripts:\n{}",
        failures.join("\n")
    );
}

#[test]
fn plotting_script_writes_png_svg_and_data() {
    let out = TempDir::new("plotting-outputs");
    run_script(&scripts_dir().join("plotting.rhai"), out.path()).expect("plotting.rhai runs");
    let read = |p: &str| std::fs::read(out.path().join(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    for png in ["plots/chirp.png", "plots/heat.png", "plots/stacked_s.png"] {
        assert!(
            read(png).starts_with(b"\x89PNG\r\n\x1a\n"),
            "{png} is not a PNG"
        );
    }
    for svg in [
        "plots/chirp.svg",
        "plots/stacked.svg",
        "plots/spectrum.svg",
        "plots/loglog.svg",
    ] {
        let text = String::from_utf8(read(svg)).expect("SVG is UTF-8");
        assert!(
            text.contains("<svg") && text.contains("<text"),
            "{svg} has no text"
        );
    }
    let csv = String::from_utf8(read("data/chirp.csv")).expect("CSV is UTF-8");
    assert!(csv.starts_with("t_s,x\n"), "CSV header: {}", &csv[..20]);
    assert_eq!(csv.lines().count(), 4001, "header + 4000 samples");
    let json: serde_json::Value =
        serde_json::from_slice(&read("data/summary.json")).expect("valid JSON");
    assert_eq!(json["n"], 4000);
    assert_eq!(json["head"]["samples"].as_array().map(Vec::len), Some(3));
    assert!(json["peak"]["time_s"].is_f64());
    for npy in ["data/chirp.npy", "data/grid.npy"] {
        assert!(read(npy).starts_with(b"\x93NUMPY"), "{npy} is not .npy");
    }
    let grid = read("data/grid.npy");
    let header = String::from_utf8_lossy(&grid[..128.min(grid.len())]).to_string();
    assert!(
        header.contains("(2, 3, )") || header.contains("(2, 3)"),
        "grid shape in header: {header}"
    );
}

#[test]
fn every_registered_function_has_a_description() {
    let out = TempDir::new("api");
    let host = Host::new(HostOptions {
        out_dir: out.path().to_path_buf(),
        ..HostOptions::default()
    })
    .expect("host");
    let api = host.api();
    assert!(api.len() > 50, "only {} functions listed", api.len());
    let missing: Vec<String> = api
        .iter()
        .filter(|f| f.description.trim().is_empty())
        .map(|f| format!("{}: {}", f.module, f.signature))
        .collect();
    assert!(
        missing.is_empty(),
        "functions without description:\n{}",
        missing.join("\n")
    );
    for module in [
        "signal", "plot", "io", "material", "laminate", "test", "host",
    ] {
        assert!(
            api.iter().any(|f| f.module == module),
            "module {module} missing"
        );
    }
}

// ------------------------------------------------------------------ the binary

/// Runs the binary with `args`, output dir `out`, quietly.
fn cli(out: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_trnews-script"))
        .arg("--quiet")
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .expect("run trnews-script")
}

/// Asserts failure with exactly one stderr line `error: FILE:LINE:COL: ...` containing `needle`.
fn assert_one_line_error(o: &Output, file: &Path, line_col: &str, needle: &str) {
    assert!(!o.status.success(), "expected failure");
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line expected:\n{err}");
    let prefix = format!("error: {}:{line_col}: ", file.display());
    assert!(
        lines[0].starts_with(&prefix),
        "expected prefix {prefix:?}:\n{err}"
    );
    assert!(lines[0].contains(needle), "expected {needle:?} in:\n{err}");
}

#[test]
fn syntax_error_names_file_line_and_column() {
    let dir = TempDir::new("cli-syntax");
    let s = dir.script("bad.rhai", "let a = 1;\nlet b = ;\n");
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "2:9", "syntax error");
}

#[test]
fn library_error_surfaces_at_the_namespaced_call() {
    let dir = TempDir::new("cli-runtime");
    let s = dir.script(
        "bad.rhai",
        "let a = 1;\n  let c = signal::chirp(#{ dt_s: -1.0 });\n",
    );
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "2:19", "dt_s must be positive and finite, got -1");
}

#[test]
fn error_inside_a_script_function_points_into_it() {
    let dir = TempDir::new("cli-fn");
    let text = "fn f(s) {\n    s.lowpass(1e12, 2)\n}\nf(signal::chirp(#{}));\n";
    let s = dir.script("bad.rhai", text);
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "2:7", "Nyquist");
}

#[test]
fn writing_outside_the_output_dir_is_refused() {
    let dir = TempDir::new("cli-escape");
    let line = "plot::line(\"../x.png\", #{}, [#{ y: signal::chirp(#{}) }]);\n";
    let s = dir.script("up.rhai", line);
    let o = cli(&dir.path().join("out"), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "1:7", "'../x.png' leaves the output directory");
    assert!(!dir.path().join("x.png").exists());

    let abs = dir.path().join("abs.png");
    let line = format!("io::write_npy(\"{}\", [1.0]);\n", abs.display());
    let s = dir.script("abs.rhai", &line);
    let o = cli(&dir.path().join("out"), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "1:5", "is absolute");
    assert!(!abs.exists());
}

#[test]
fn endless_loop_stops_at_the_operation_limit() {
    let dir = TempDir::new("cli-loop");
    let s = dir.script("loop.rhai", "let x = 0;\nloop {\n    x += 1;\n}\n");
    let o = cli(
        dir.path(),
        &["--max-operations", "10000", s.to_str().unwrap()],
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("operation limit 10000 exceeded"), "{err}");
    assert!(
        err.starts_with(&format!("error: {}:", s.display())),
        "{err}"
    );
}

#[test]
fn check_compiles_without_running() {
    let dir = TempDir::new("cli-check");
    let s = dir.script("good.rhai", "print(\"ran\");\nthrow \"must not run\";\n");
    let o = cli(dir.path(), &["--check", s.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("ran"));
}

#[test]
fn api_lists_functions_with_descriptions() {
    let dir = TempDir::new("cli-api");
    let o = cli(dir.path(), &["--api"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("[signal]") && text.contains("[plot]"),
        "{text}"
    );
    assert!(
        text.contains("signal::chirp(opts: map) -> Signal"),
        "{text}"
    );
    assert!(
        text.contains("envelope(s: Signal) -> Signal\n      Hilbert envelope"),
        "{text}"
    );
}

#[test]
fn definitions_describe_the_api_for_editors() {
    let dir = TempDir::new("cli-definitions");
    let defs = dir.path().join("defs");
    let o = cli(
        dir.path(),
        &[
            "--set",
            "resolution=smoke",
            "--definitions",
            defs.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |name: &str| {
        std::fs::read_to_string(defs.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let scene = read("scene.d.rhai");
    assert!(scene.starts_with("module scene;"), "{scene}");
    assert!(
        scene.contains("fn preset(name: string, overrides: map) -> Scene;"),
        "{scene}"
    );
    assert!(scene.contains("fn write_pvd(path: string, scene: Scene, run: Run)"));
    let trnews = read("trnews.d.rhai");
    assert!(
        trnews.contains("fn tr_news(r: Responder, spec: map) -> TrNews;"),
        "{trnews}"
    );
    assert!(read("signal.d.rhai").contains("/// Hilbert envelope"));
    assert!(read("__scope__.d.rhai").contains("const resolution"));
    for name in [
        "__static__.d.rhai",
        "__builtin__.d.rhai",
        "plot.d.rhai",
        "io.d.rhai",
    ] {
        assert!(defs.join(name).is_file(), "{name} missing");
    }
    let all: String = ["scene", "trnews", "signal", "study"]
        .map(|m| read(&format!("{m}.d.rhai")))
        .concat();
    assert!(
        !all.contains("Res<") && !all.contains("SceneRef"),
        "Rust type names left"
    );
}

#[test]
fn set_values_reach_the_script() {
    let dir = TempDir::new("cli-set");
    let text = "assert(param(\"n\", 1) == 7, \"n\");\nassert(n == 7, \"constant\");\n\
                assert(param(\"f\", 1.0) == 2.0, \"int coerced to float\");\n\
                assert(param(\"mode\", \"quick\") == \"paper\", \"string\");\n\
                assert(param(\"unset\", 3) == 3, \"default\");\n";
    let s = dir.script("set.rhai", text);
    let o = cli(
        dir.path(),
        &[
            "--set",
            "n=7",
            "--set",
            "f=2",
            "--set",
            "mode=paper",
            s.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let s = dir.script("bad_set.rhai", "let n = param(\"n\", 1);\n");
    let o = cli(dir.path(), &["--set", "n=lots", s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "1:9", "parameter 'n' = lots is string");
}

#[test]
fn experiment_setup_reads_set_over_script_defaults_and_names_bad_values() {
    let dir = TempDir::new("cli-experiment");
    let text = "let ex = experiment::setup();\n\
                assert(ex.resolution == \"smoke\", \"resolution from --set\");\n\
                assert(ex.discretisation == \"sem\", \"library default\");\n\
                assert(ex.error_estimate == true, \"a tolerance turns the estimate on\");\n\
                assert(ex.tolerance == 0.05, \"tolerance\");\n\
                assert(ex.spec.chirp.t1_s == trnews::preset_spec(\"smoke\").chirp.t1_s, \"spec\");\n\
                let t3 = experiment::setup(#{ discretisation: \"t3\" });\n\
                assert(t3.discretisation == \"t3\", \"script default\");\n";
    let s = dir.script("setup.rhai", text);
    let args = ["--set", "resolution=smoke", "--set", "tolerance=0.05"];
    let o = cli(dir.path(), &[&args[..], &[s.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).is_empty(),
        "every parameter is read: {}",
        String::from_utf8_lossy(&o.stderr)
    );

    // A parameter of the setup the script never uses is named, not silently dropped.
    let s = dir.script("unused.rhai", "let r = experiment::setup().resolution;\n");
    let o = cli(
        dir.path(),
        &["--set", "error_estimate=true", s.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--set error_estimate") && err.contains("never asks"),
        "{err}"
    );

    let s = dir.script("bad.rhai", "let ex = experiment::setup();\n");
    for (set, needle) in [
        ("resolution=fast", "invalid resolution = fast"),
        ("discretisation=q4", "invalid discretisation = q4"),
        ("error_estimate=maybe", "invalid error_estimate = \"maybe\""),
        ("tolerance=2", "invalid tolerance = 2"),
    ] {
        let o = cli(dir.path(), &["--set", set, s.to_str().unwrap()]);
        assert_one_line_error(&o, &s, "1:22", needle);
    }
    let s = dir.script(
        "bad_default.rhai",
        "experiment::setup(#{ resolutoin: \"smoke\" });\n",
    );
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "1:13", "experiment.resolutoin");
}

#[test]
fn failed_assertion_shows_both_values() {
    let dir = TempDir::new("cli-assert");
    let s = dir.script("a.rhai", "\nassert_close(1.02, 1.0, 0.01, \"gain\");\n");
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(
        &o,
        &s,
        "2:1",
        "assert_close failed: actual 1.02 vs expected 1 (rel tol 0.01): gain",
    );
}

#[test]
fn unstable_time_step_is_refused_with_dt_and_dt_crit() {
    let dir = TempDir::new("cli-unstable");
    let text = "let s = scene::preset(\"smoke\", #{ crack: () });\nlet c = signal::chirp(#{ dt_s: 2.0 * s.dt_crit });\nlet run = s.transmit(c, #{ duration_s: 1e-6, dt_s: 2.0 * s.dt_crit });\n";
    let s = dir.script("unstable.rhai", text);
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(
        &o,
        &s,
        "3:13",
        "exceeds the explicit stability limit dt_crit",
    );
}

#[test]
fn receiver_outside_the_domain_is_an_error_naming_it() {
    let dir = TempDir::new("cli-receiver");
    let text = "let s = scene::preset(\"smoke\", #{ receivers: #{ x_m: [1e-3, 0.5] } });\n";
    let s = dir.script("receiver.rhai", text);
    let o = cli(dir.path(), &[s.to_str().unwrap()]);
    assert_one_line_error(&o, &s, "1:16", "receiver 'receiver 2'");
}
