//! The experiment scripts on lab data (docs/src/guide/lab-data.md): `scripts/sweep_delays.rhai`,
//! `trnews_focus.rhai` and `pulse_inversion.rhai` at the smoke resolution, each run
//!
//! - on recorded responses (`channel = recorded`): the script starts on an empty lab
//!   directory and stops at each phase with the drives still to record; "the lab" is the
//!   simulated cracked smoke scene ([`Responder::respond`]), which answers each listed drive,
//!   writes the recording in the lab format and reruns, until the script completes. Its CSV
//!   must equal the cracked rows of the same script on the simulated scene bit for bit: a
//!   recorded channel answers with the samples the scene computed for the same drive (a
//!   causal simulation's first n steps do not depend on how long it runs; .npy and the CSV
//!   writer keep every float64 bit). Only the run diagnostics (energy residual, dt/dt_crit)
//!   are empty: a recording has no run report.
//! - on the uncracked smoke scene's impulse response read from .npy (`channel = impulse`):
//!   its CSV matches the uncracked rows to 1e-9 relative (focus times to the sample): the
//!   scene answers B * (h * (B * s)), the channel (B * h * B) * s, the same in exact
//!   arithmetic; the summation orders differ (round-off, measured 2.2e-13 in
//!   tests/channel.rs). Delayed misfits and PI residuals are round-off on both (< 1e-9).

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;
use trnews::lab::{
    RecordingFiles, ToRecordManifest, LAB_MANIFEST, TO_RECORD_DIR, TO_RECORD_MANIFEST,
};
use trnews::scene::{Resolution, Scene, SceneSpec};
use trnews::signal::Signal;
use trnews::trnews::Responder;

const BIN: &str = env!("CARGO_BIN_EXE_trnews-script");

/// Runs `scripts/<name>.rhai` at the smoke resolution with `--out out` and `extra`:
/// Ok(stderr) when it succeeds, Err(stderr) when it fails.
fn run(name: &str, out: &Path, extra: &[String]) -> Result<String, String> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scripts/{name}.rhai"));
    let o = Command::new(BIN)
        .arg(script)
        .args(["--set", "resolution=smoke", "--quiet", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .expect("run trnews-script");
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{name} panicked: {stderr}");
    if o.status.success() {
        Ok(stderr)
    } else {
        Err(stderr)
    }
}

/// A CSV file as its header and rows of fields (no field of these tables holds a comma).
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>());
    let header = lines.next().expect("header");
    (header, lines.collect())
}

/// The rows of `path` whose column `column` is `value`.
fn rows_where(path: &Path, column: usize, value: &str) -> Vec<Vec<String>> {
    csv(path)
        .1
        .into_iter()
        .filter(|r| r[column] == value)
        .collect()
}

/// The channel parameters shared by the lab runs: the scene's step, drive peak and band, so
/// that the chirp is the scene's, and the sample named `sample`.
fn channel_args(sim: &Responder, data: &Path, channel: &[&str], sample: &str) -> Vec<String> {
    let mut args = vec!["--data".to_string(), data.display().to_string()];
    let settings = [
        format!("dt_s={:?}", sim.dt_s()),
        format!("peak_drive={:?}", sim.peak_drive()),
        format!("band={}", sim.band()),
        format!("sample={sample}"),
    ];
    for s in channel.iter().map(|s| s.to_string()).chain(settings) {
        args.push("--set".into());
        args.push(s);
    }
    args
}

/// "The lab": the simulated cracked smoke scene, recording into a lab directory.
struct Lab {
    sim: Responder,
    dir: PathBuf,
    recordings: Vec<RecordingFiles>,
}

/// The cracked smoke scene, simulating every drive.
fn cracked_smoke() -> Responder {
    let scene = Scene::build(&SceneSpec::preset(Resolution::Smoke)).expect("cracked smoke scene");
    Responder::simulating(Arc::new(scene))
}

impl Lab {
    fn new(sim: Responder, dir: PathBuf) -> Lab {
        std::fs::create_dir_all(&dir).expect("lab directory");
        Lab {
            sim,
            dir,
            recordings: Vec::new(),
        }
    }

    /// Plays every drive the last run listed under `out`, records each for its record_s and
    /// adds the recordings to the lab manifest; returns how many drives it played.
    fn record(&mut self, out: &Path) -> usize {
        let list_dir = out.join(TO_RECORD_DIR);
        let text = std::fs::read_to_string(list_dir.join(TO_RECORD_MANIFEST)).expect("list");
        let list: ToRecordManifest = serde_json::from_str(&text).expect("to_record.json");
        for d in &list.drives {
            let file = list_dir.join(&d.sent);
            let table = trnews::input::parse_npy(&file, &std::fs::read(&file).expect("drive"))
                .expect("drive .npy");
            assert_eq!(table.shape, vec![d.samples], "{}", d.sent);
            let drive = Signal::new(d.dt_s, 0.0, table.values).expect("drive");
            let traces = self.sim.respond(&drive, d.record_s).expect("play").traces;
            assert_eq!(traces[0].len(), d.record_samples, "record length");
            let values: Vec<f64> = traces.iter().flat_map(|t| t.samples.clone()).collect();
            let shape = [traces.len(), traces[0].len()];
            std::fs::copy(&file, self.dir.join(&d.sent)).expect("copy drive");
            trnews::io::write_npy(&self.dir.join(&d.received), &values, &shape).expect("npy");
            self.recordings.push(RecordingFiles {
                sent: d.sent.clone(),
                received: d.received.clone(),
            });
        }
        let manifest = serde_json::json!({ "recordings": self.recordings });
        trnews::io::write_json(&self.dir.join(LAB_MANIFEST), &manifest).expect("manifest");
        list.drives.len()
    }
}

/// Runs script `name` on recorded responses from an empty lab directory, the lab answering
/// each phase's drives, until it completes; returns its output directory (in `tmp`) and the
/// number of drives of each phase.
fn lab_workflow(name: &str, sim: &Responder, tmp: &TempDir) -> (PathBuf, Vec<usize>) {
    let data = tmp.path().join("data");
    let out = tmp.path().join("lab_out");
    let mut lab = Lab::new(sim.clone(), data.join("lab"));
    let args = channel_args(
        &lab.sim,
        &data,
        &["channel=recorded", "recordings=lab"],
        "cracked",
    );
    let mut phases = Vec::new();
    while let Err(stderr) = run(name, &out, &args) {
        assert!(
            stderr.contains("not recorded yet") && stderr.contains(TO_RECORD_MANIFEST),
            "{name} failed otherwise: {stderr}"
        );
        assert!(phases.len() < 5, "{name}: no end after {phases:?}");
        phases.push(lab.record(&out));
    }
    let text = std::fs::read_to_string(out.join(TO_RECORD_DIR).join(TO_RECORD_MANIFEST));
    let list: ToRecordManifest = serde_json::from_str(&text.expect("list")).expect("json");
    assert!(list.drives.is_empty(), "a completed run lists no drive");
    (out, phases)
}

/// Writes the uncracked smoke scene's impulse response (40 us, transducers included) as
/// `data/h.npy`, one row per receiver.
fn write_impulse(sim: &Responder, data: &Path) {
    let scene =
        Scene::build(&SceneSpec::preset(Resolution::Smoke).uncracked()).expect("uncracked scene");
    let linear = Responder::new(Arc::new(scene), 40e-6).expect("impulse response");
    let unit = Signal::new(sim.dt_s(), 0.0, vec![1.0]).expect("unit");
    let h = linear.respond(&unit, 40e-6).expect("h").traces;
    let values: Vec<f64> = h.iter().flat_map(|t| t.samples.clone()).collect();
    trnews::io::write_npy(&data.join("h.npy"), &values, &[h.len(), h[0].len()]).expect("h.npy");
}

/// Runs script `name` on the uncracked scene's impulse response read from .npy.
fn on_impulse(name: &str, sim: &Responder, tmp: &TempDir) -> PathBuf {
    let data = tmp.path().join("data");
    write_impulse(sim, &data);
    let out = tmp.path().join("impulse_out");
    let args = channel_args(
        sim,
        &data,
        &["channel=impulse", "impulse=h.npy"],
        "uncracked",
    );
    run(name, &out, &args).unwrap_or_else(|e| panic!("{name} on h.npy: {e}"));
    out
}

/// `a` and `b` as numbers agree to `rel` relative.
fn close(a: &str, b: &str, rel: f64) -> bool {
    let (x, y): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
    (x - y).abs() <= rel * x.abs().max(y.abs())
}

/// Rows of a recorded run and of the scene's run agree: every field equal, numbers to 1e-9
/// relative. The lab plays the drives on its own simulation of the scene; on spectral
/// elements the results differ from the scene channel's in the last digits (measured up to
/// 1e-11 relative), which round-off explains and a wrong recording (a drive, a receiver or a
/// sample off) would exceed by orders of magnitude.
fn same_rows(a: &[Vec<String>], b: &[Vec<String>]) -> bool {
    let field = |x: &String, y: &String| {
        x == y || (x.parse::<f64>().is_ok() && y.parse::<f64>().is_ok() && close(x, y, 1e-9))
    };
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(r, s)| r.len() == s.len() && r.iter().zip(s).all(|(x, y)| field(x, y)))
}

#[test]
fn sweep_delays_runs_on_recorded_lab_data_and_on_a_measured_impulse_response() {
    let tmp = TempDir::new("lab-sweep");
    let reference = tmp.path().join("scene_out");
    run("sweep_delays", &reference, &[]).expect("scene run");
    let table = |out: &Path| out.join("plots/sweep_delays.csv");

    let sim = cracked_smoke();
    let (out, phases) = lab_workflow("sweep_delays", &sim, &tmp);
    // the chirp; the focusing drive at receiver 3; the 6 delayed drives s(t) + a s(t - tau)
    assert_eq!(phases, vec![1, 1, 6]);
    assert_eq!(csv(&table(&out)).0, csv(&table(&reference)).0, "header");
    let scene = rows_where(&table(&reference), 0, "cracked");
    let recorded = csv(&table(&out)).1;
    assert_eq!(recorded.len(), 6);
    for (r, s) in recorded.iter().zip(&scene) {
        // energy_residual_peak and dt_over_dt_crit come from run reports: none recorded
        assert_eq!((r[6].as_str(), r[7].as_str()), ("", ""));
        let strip = |row: &Vec<String>| [&row[..6], &row[8..]].concat();
        assert!(
            same_rows(&[strip(r)], &[strip(s)]),
            "recorded point differs from the scene's: {r:?} vs {s:?}"
        );
    }

    let measured = on_impulse("sweep_delays", &sim, &tmp);
    let scene = rows_where(&table(&reference), 0, "uncracked");
    let rows = csv(&table(&measured)).1;
    assert_eq!(rows.len(), scene.len());
    for (m, s) in rows.iter().zip(&scene) {
        assert_eq!(m[..4], s[..4], "sample, band, tau, a");
        let misfits: Vec<f64> = [&m[4], &s[4]].iter().map(|v| v.parse().unwrap()).collect();
        assert!(
            misfits.iter().all(|x| *x < 1e-9),
            "linear misfits {misfits:?}"
        );
    }
}

#[test]
fn trnews_focus_runs_on_recorded_lab_data_and_on_a_measured_impulse_response() {
    let tmp = TempDir::new("lab-focus");
    let reference = tmp.path().join("scene_out");
    run("trnews_focus", &reference, &[]).expect("scene run");
    let table = |out: &Path| out.join("plots/trnews_focus.csv");

    let sim = cracked_smoke();
    let (out, phases) = lab_workflow("trnews_focus", &sim, &tmp);
    assert_eq!(
        phases,
        vec![1, 4],
        "the chirp; the focusing drives at the 4 receivers"
    );
    assert_eq!(csv(&table(&out)).0, csv(&table(&reference)).0, "header");
    let (recorded, scene) = (
        csv(&table(&out)).1,
        rows_where(&table(&reference), 0, "cracked"),
    );
    assert!(same_rows(&recorded, &scene), "{recorded:?}\n vs {scene:?}");
    assert!(!out.join("plots/trnews_snapshot.png").exists(), "no field");

    let measured = on_impulse("trnews_focus", &sim, &tmp);
    let scene = rows_where(&table(&reference), 0, "uncracked");
    let rows = csv(&table(&measured)).1;
    assert_eq!(rows.len(), scene.len());
    for (m, s) in rows.iter().zip(&scene) {
        assert_eq!(m[..4], s[..4], "sample, receiver, band, focus time");
        for c in 4..7 {
            assert!(
                close(&m[c], &s[c], 1e-9),
                "column {c}: {} vs {}",
                m[c],
                s[c]
            );
        }
    }
}

#[test]
fn pulse_inversion_runs_on_recorded_lab_data_and_on_a_measured_impulse_response() {
    let tmp = TempDir::new("lab-pi");
    let reference = tmp.path().join("scene_out");
    run("pulse_inversion", &reference, &[]).expect("scene run");
    let table = |out: &Path| out.join("plots/pulse_inversion.csv");

    let sim = cracked_smoke();
    let (out, phases) = lab_workflow("pulse_inversion", &sim, &tmp);
    assert_eq!(
        phases,
        vec![1, 8],
        "the chirp; 4 focusing drives and their inverses"
    );
    let (header, rows) = csv(&table(&out));
    let (scene_header, scene_rows) = csv(&table(&reference));
    // the lab's columns are the cracked sample's columns of the scene's table
    let columns: Vec<usize> = header
        .iter()
        .map(|h| scene_header.iter().position(|s| s == h).expect(h))
        .collect();
    assert_eq!(header.len(), 7, "{header:?}");
    assert_eq!(rows.len(), scene_rows.len());
    for (r, s) in rows.iter().zip(&scene_rows) {
        let picked: Vec<String> = columns.iter().map(|&c| s[c].clone()).collect();
        assert!(
            same_rows(std::slice::from_ref(r), std::slice::from_ref(&picked)),
            "{r:?} vs {picked:?}"
        );
    }

    let measured = on_impulse("pulse_inversion", &sim, &tmp);
    let (header, rows) = csv(&table(&measured));
    assert_eq!(header[2], "pi_residual_uncracked");
    for r in &rows {
        let residual: f64 = r[2].parse().unwrap();
        assert!(
            residual < 1e-12,
            "a linear channel's PI residual {residual}"
        );
    }
}

/// Every wrong or inapplicable channel parameter stops the script with an error naming the
/// parameter and the value written (before any scene is built), never a panic or a default.
#[test]
fn channel_parameters_are_checked_and_named() {
    let tmp = TempDir::new("lab-params");
    let data = tmp.path().join("data");
    std::fs::create_dir_all(data.join("lab")).expect("lab");
    std::fs::create_dir_all(data.join("typo")).expect("typo lab");
    std::fs::write(
        data.join("typo").join(LAB_MANIFEST),
        r#"{"recordings": [{"sent": "a.npy", "recieved": "b.npy"}]}"#,
    )
    .expect("manifest");
    let lab = ["--set", "channel=recorded", "--set", "recordings=lab"];
    let cases: &[(&[&str], &str)] = &[
        (
            &["--set", "channel=recordd"],
            r#"invalid channel = "recordd": expected scene, impulse or recorded"#,
        ),
        (
            &lab,
            "invalid dt_s = (not given): channel = recorded needs it",
        ),
        (
            &[&lab[..], &["--set", "dt_s=-1e-8", "--set", "peak_drive=1"]].concat(),
            "invalid dt_s = -0.00000001: must be finite and > 0",
        ),
        (
            &[
                &lab[..],
                &["--set", "dt_s=1e-8", "--set", "peak_drive=loud"],
            ]
            .concat(),
            "invalid peak_drive = loud: expected a number",
        ),
        (
            &[&lab[..], &["--set", "tolerance=0.05"]].concat(),
            "invalid tolerance = 0.05: does not apply to channel = recorded",
        ),
        (
            &[&lab[..], &["--set", "impulse=h.npy"]].concat(),
            "invalid impulse = h.npy: does not apply to channel = recorded",
        ),
        (
            &["--set", "recordings=lab"],
            "invalid recordings = lab: does not apply to channel = scene",
        ),
        (
            &[
                "--set",
                "channel=recorded",
                "--set",
                "recordings=nolab",
                "--set",
                "dt_s=1e-8",
                "--set",
                "peak_drive=1",
            ],
            "invalid recordings = nolab: is not a directory under the data directory",
        ),
        (
            &[
                "--set",
                "channel=recorded",
                "--set",
                "recordings=typo",
                "--set",
                "dt_s=1e-8",
                "--set",
                "peak_drive=1",
            ],
            "unknown field `recieved`",
        ),
        (
            &[
                "--set",
                "channel=impulse",
                "--set",
                "impulse=none.npy",
                "--set",
                "dt_s=1e-8",
                "--set",
                "peak_drive=1",
            ],
            "none.npy",
        ),
    ];
    for (i, (set, expected)) in cases.iter().enumerate() {
        let mut args = vec!["--data".to_string(), data.display().to_string()];
        args.extend(set.iter().map(|s| s.to_string()));
        let out = tmp.path().join(format!("out{i}"));
        let e = run("sweep_delays", &out, &args).expect_err(expected);
        assert!(e.contains(expected), "expected '{expected}' in: {e}");
    }
}

/// A lab channel answers a batch only when every drive is recorded: asked for three drives
/// of which two are new (one is a recorded drive with one more sample: another length never
/// matches), it lists both in one go, with their record length, and stops naming the count.
#[test]
fn a_lab_channel_lists_every_unrecorded_drive_of_a_batch() {
    let tmp = TempDir::new("lab-batch");
    let dt = 1e-8;
    let drive = Signal::new(dt, 0.0, vec![0.0, 1.0, -0.5]).expect("drive");
    let recording = trnews::trnews::Recording {
        sent: drive.clone(),
        received: vec![Signal::new(dt, 0.0, vec![0.25; 40]).expect("trace")],
    };
    let list = trnews::lab::ToRecord::new(tmp.path(), None, "LAB").expect("list");
    let lab = Responder::from_lab(vec![recording], dt, 1.0, "lab".into(), Arc::new(list))
        .expect("lab channel");
    let longer = Signal::new(dt, 0.0, vec![0.0, 1.0, -0.5, 0.0]).expect("padded");
    let other = drive.scale(-1.0).expect("inverse");
    let answered = lab
        .respond_all(std::slice::from_ref(&drive), 30.0 * dt)
        .expect("recorded");
    assert_eq!(answered[0].traces[0].samples, vec![0.25; 30]);
    let e = lab
        .respond_all(&[drive, longer, other], 30.0 * dt)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("lab: 2 drives are not recorded yet in 'LAB'"),
        "{e}"
    );
    let text = std::fs::read_to_string(tmp.path().join(TO_RECORD_DIR).join(TO_RECORD_MANIFEST));
    let listed: ToRecordManifest = serde_json::from_str(&text.expect("list")).expect("json");
    let mut samples: Vec<usize> = listed.drives.iter().map(|d| d.samples).collect();
    samples.sort();
    assert_eq!(samples, vec![3, 4]);
    assert!(listed
        .drives
        .iter()
        .all(|d| d.record_samples == 30 && d.dt_s == dt));
    for d in &listed.drives {
        assert!(
            tmp.path().join(TO_RECORD_DIR).join(&d.sent).exists(),
            "{}",
            d.sent
        );
    }
}
