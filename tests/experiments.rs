//! Every experiment script in scripts/ runs end to end at the `smoke` resolution (a small
//! scene, seconds per run) and writes its figures and tables: the scripts are regression
//! tests of the whole pipeline, scene -> runs -> TR-NEWS -> figures.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scripts() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    v.sort();
    v
}

/// `scripts/<script>` at smoke, quiet, writing under `out`; the caller adds its own arguments.
fn at_smoke(script: &str, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_trnews-script"));
    c.arg(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scripts")
            .join(script),
    )
    .args(["--set", "resolution=smoke", "--quiet", "--out"])
    .arg(out);
    c
}

#[test]
fn experiment_scripts_run_at_smoke_resolution_and_write_their_outputs() {
    let scripts = scripts();
    assert!(scripts.len() >= 6, "{scripts:?}");
    let out = std::env::temp_dir().join(format!("trnews-experiments-{}", std::process::id()));
    let mut failures = Vec::new();
    // scan_sides.rhai combines two scans' tables: its own test below gives it them.
    for script in scripts.iter().filter(|s| !s.ends_with("scan_sides.rhai")) {
        let result = Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .arg(script)
            .args(["--set", "resolution=smoke", "--quiet", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        if !result.status.success() {
            failures.push(format!(
                "{}: {}",
                script.display(),
                String::from_utf8_lossy(&result.stderr)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    for file in [
        "sweep_delays_fig22.png",
        "sweep_delays_misfit_cracked.png",
        "sweep_delays.csv",
        "trnews_focus.png",
        "trnews_snapshot.png",
        "trnews_snapshot.vtu",
        "trnews_scattered.png",
        "pulse_inversion.png",
        "pulse_inversion_envelopes.png",
        "spectra_input_output.png",
        "spectra_defect.png",
        "work_precision.png",
        "work_precision.csv",
        "stability.csv",
        "convergence.csv",
        "convergence.png",
        "spectra_mean_frequency.csv",
        "measured_channel.csv",
        "measured_channel_fig22.png",
        "measured_channel_h.npy",
        "sem_target.csv",
        "sem_target.png",
        "sem_target_timing.csv",
        "sem_target_friction_lag.csv",
        "sem_target_lag_compare.csv",
        "sem_target_lag_estimate.csv",
        "sem_target_lag_measures.csv",
        "sem_target_lag_shift.csv",
        "sem_target_nonlinear.csv",
        "sem_target_friction_spread.csv",
        "sem_target_friction_spread_estimate.csv",
        "sem_target_friction_sensitivity.csv",
        "sem_target_contact_convergence.csv",
        "attenuation.csv",
        "attenuation.png",
        "quality.png",
        "losses_focus.png",
        "losses_focus.csv",
        "scan.csv",
        "scan.png",
        "scan_localisation.csv",
        "woven.csv",
        "woven_traces.png",
        "woven_snapshot.png",
        "bracket.csv",
        "bracket_traces.png",
        "bracket_scattered.png",
        "resonance.png",
        "resonance_spectra.png",
        "resonance.csv",
        "resonance_peaks.csv",
    ] {
        let path = out.join("plots").join(file);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(bytes.len() > 100, "{} is nearly empty", path.display());
    }
    let table = std::fs::read_to_string(out.join("plots/stability.csv")).unwrap();
    assert!(
        table.contains("refused") && table.contains("stopped: unstable") && table.contains("ran"),
        "{table}"
    );
    // Estimate columns are always written; "off" when the estimate was not asked for (at
    // smoke resolution the spectral elements' companions cost about 1.2x the main runs, above
    // "auto"'s 30%).
    let focus = std::fs::read_to_string(out.join("plots/trnews_focus.csv")).unwrap();
    assert!(
        focus.lines().next().unwrap().contains("focused_verdict"),
        "{focus}"
    );
    let convergence = std::fs::read_to_string(out.join("plots/convergence.csv")).unwrap();
    assert!(convergence.contains("cracked,0.5,") && convergence.contains("misfit"));
    losses_weaken_the_focus(&out.join("plots/losses_focus.csv"));
    tuned_trains_are_linear_without_the_crack(&out.join("plots/resonance.csv"));
    the_scan_locates_the_crack(&out.join("plots/scan_localisation.csv"));
    estimates_hold_against_the_reference(&out.join("plots/sem_target_estimate.csv"));
    nonlinear_errors_hold_against_the_reference(&out.join("plots/sem_target_nonlinear.csv"));
    the_default_friction_law_converges_and_its_estimates_hold(
        &out.join("plots/sem_target_lag_compare.csv"),
        &out.join("plots/sem_target_lag_estimate.csv"),
        &out.join("plots/sem_target_lag_measures.csv"),
    );
    the_spectral_shifts_estimate_holds_under_the_default_law(
        &out.join("plots/sem_target_lag_shift.csv"),
    );
    the_friction_response_time_narrows_the_spread(
        &out.join("plots/sem_target_friction_spread.csv"),
    );
    estimates_hold_with_the_friction_response_time(
        &out.join("plots/sem_target_friction_spread_estimate.csv"),
    );
    the_friction_response_time_makes_the_focus_smooth(
        &out.join("plots/sem_target_friction_sensitivity.csv"),
    );
    at_smoke_the_contact_measures_move_more_along_x_than_in_time(
        &out.join("plots/sem_target_contact_convergence.csv"),
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `scan.rhai` at smoke (21 positions 0.2 mm apart over the 6 mm scene, a 1.2 mm crack 0.8
/// mm deep): the PI residual map's half-height extent puts the crack's centre within 0.5 mm
/// and its length within 25%, the targets (measured -0.29 mm and +9%; -0.28 mm and
/// +6% with 41 positions). This is the pipeline's regression check on the one placement where
/// the method holds at smoke; a 2 mm crack and a 1.5 mm deep one miss the targets
/// (docs/src/guide/scan.md).
fn the_scan_locates_the_crack(table: &std::path::Path) {
    let text = std::fs::read_to_string(table).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = text
        .lines()
        .find(|l| l.starts_with("pi_residual,"))
        .unwrap()
        .split(',')
        .collect();
    let column = |name: &str| -> f64 {
        row[header.iter().position(|h| *h == name).unwrap()]
            .parse()
            .unwrap()
    };
    let (centre, length) = (column("centre_error_mm"), column("length_error_fraction"));
    println!("scan at smoke: centre off by {centre} mm, length off by {length}");
    assert!(centre.abs() < 0.5 && length.abs() < 0.25, "{text}");
}

/// `losses.rhai`: the literature's losses lower the focused amplitude (at smoke, 1.58 to
/// 1.51 nm: the paths are a few cm of lossy laminate), and both runs close their ledgers.
fn losses_weaken_the_focus(table: &std::path::Path) {
    let text = std::fs::read_to_string(table).unwrap();
    let rows: Vec<Vec<String>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    let amplitude = |r: &[String]| r[2].parse::<f64>().unwrap();
    assert!(amplitude(&rows[1]) < 0.99 * amplitude(&rows[0]), "{text}");
    for r in &rows {
        assert!(r[5].parse::<f64>().unwrap() < 1e-12, "{text}");
    }
}

/// A CSV table a script wrote: its text (quoted in failure messages), its header's columns
/// and its rows of cells.
struct Table {
    text: String,
}

impl Table {
    fn read(path: &Path) -> Table {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Table { text }
    }

    /// The index of column `name` in the header.
    fn column(&self, name: &str) -> usize {
        let header = self.text.lines().next().unwrap_or_default();
        header
            .split(',')
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}: {}", self.text))
    }

    /// The rows below the header, each split into its cells.
    fn rows(&self) -> Vec<Vec<&str>> {
        self.text
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect()
    }
}

/// The smallest and the largest of `values`.
fn extent(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// `resonance.rhai` at smoke: trains of both families tuned to the gap's resonances are
/// among the trains, every train's uncracked misfit is round-off (the linear prediction is
/// exact while the last delay keeps the first copy's y_TR in the misfit window; measured
/// 1.4e-15 to 3.9e-15) and its cracked misfit is not (measured 0.029 to 0.086).
fn tuned_trains_are_linear_without_the_crack(table: &std::path::Path) {
    let table = Table::read(table);
    let text = &table.text;
    let (family, tuned, misfit, uncracked) = (
        table.column("family"),
        table.column("tuned"),
        table.column("misfit"),
        table.column("misfit_uncracked"),
    );
    let rows = table.rows();
    for name in ["in phase", "half period"] {
        assert!(
            rows.iter().any(|r| r[family] == name && r[tuned] == "true"),
            "no {name} train tuned to a resonance: {text}"
        );
    }
    for r in &rows {
        let (m, u) = (
            r[misfit].parse::<f64>().unwrap(),
            r[uncracked].parse::<f64>().unwrap(),
        );
        assert!(u < 1e-12 && m > 1e-3, "{r:?}");
    }
}

/// The smoke preset's error estimate (companions along x and across, and for the cracked
/// traces at half the step) against the references of `sem_target.rhai`, which share no
/// element size, order or step with it: every trace, uncracked and cracked (where the error
/// along x falls slowly, the contact at GLL nodes), states an error within the factor
/// 2 of the true one (measured 0.74-1.40).
fn estimates_hold_against_the_reference(table: &std::path::Path) {
    let table = Table::read(table);
    let text = &table.text;
    let (trace, verdict, ratio, in_time) = (
        table.column("trace"),
        table.column("verdict"),
        table.column("estimate_vs_error"),
        table.column("difference_at_half_the_step"),
    );
    let rows = table.rows();
    assert_eq!(rows.len(), 4, "{text}");
    for row in rows {
        assert_eq!(row[verdict], "reliable", "{}: {text}", row[trace]);
        // the companion at half the step where the faces touch, and only there
        assert_eq!(
            row[in_time].is_empty(),
            row[trace].starts_with("uncracked"),
            "{text}"
        );
        let r: f64 = row[ratio].parse().unwrap();
        assert!(
            (0.5..=2.0).contains(&r),
            "{}: estimate / error = {r}",
            row[trace]
        );
    }
}

/// The cracked traces under the default friction law, a 20 ns response time
/// (`sem_target.rhai`'s piece `lag_compare`, smoke): both presets' discretisations are closer
/// to the reference that shares nothing with them than under the report's instantaneous law,
/// and the references closer to each other (measured 0.58%, 0.56%, 0.17%, 0.18% and 0.077%,
/// 0.079%, against 0.86%, 1.11%, 0.41%, 0.31% and 0.18%, 0.20%: the law's chatter is gone);
/// the smoke preset's estimate from its companions is "reliable" and within the issue's
/// factor 2 of its distance on both cracked traces (measured 0.66 and 0.55); and the paper
/// preset's cracked nonlinear measures are closer to their reference than the quick preset's
/// (PI residual, asymmetry, misfit: measured 2.6e-4, 1.3e-3, 1.5e-4 against 7.0e-4, 4.6e-3,
/// 7.2e-4).
fn the_default_friction_law_converges_and_its_estimates_hold(
    compare: &Path,
    estimate: &Path,
    measures: &Path,
) {
    let table = Table::read(compare);
    let (text, rows) = (&table.text, table.rows());
    assert_eq!(rows.len(), 8, "{text}");
    let (run, lagged, instantaneous) = (
        table.column("run"),
        table.column("error_vs_reference_lag20ns"),
        table.column("error_vs_reference_instantaneous"),
    );
    for row in &rows {
        let (lag, inst): (f64, f64) = (
            row[lagged].parse().unwrap(),
            row[instantaneous].parse().unwrap(),
        );
        // the triangles' faces do not chatter: their error is their mesh's under either law
        let chatters = !row[run].starts_with("t3");
        assert!(lag > 0.0 && (lag < inst || !chatters), "{row:?}: {text}");
    }
    let table = Table::read(estimate);
    let (text, rows) = (&table.text, table.rows());
    assert_eq!(rows.len(), 2, "{text}");
    let (verdict, ratio) = (table.column("verdict"), table.column("estimate_vs_error"));
    for row in &rows {
        assert_eq!(row[verdict], "reliable", "{text}");
        let r: f64 = row[ratio].parse().unwrap();
        assert!((0.5..=2.0).contains(&r), "estimate / error = {r}: {text}");
    }
    let table = Table::read(measures);
    let (text, rows) = (&table.text, table.rows());
    assert_eq!(rows.len(), 6, "{text}");
    let distance = table.column("distance");
    let (quick, paper) = rows.split_at(3);
    for (q, p) in quick.iter().zip(paper) {
        let (dq, dp): (f64, f64) = (q[distance].parse().unwrap(), p[distance].parse().unwrap());
        assert!(dp < dq, "{q:?} {p:?}: {text}");
    }
}

/// The crack's spectral shift under the default friction law (`sem_target.rhai`'s piece
/// `lag_compare`, smoke; the references' uncracked scenes rerun beside their cracked ones):
/// the smoke preset's estimate from its companions states an error within the issue's
/// factor 2 of its distance to the reference that shares nothing with it (measured 0.66:
/// 507 Hz against 767 Hz, the references 36 Hz apart), and the paper preset's discretisation
/// is closer (302 Hz).
fn the_spectral_shifts_estimate_holds_under_the_default_law(table: &Path) {
    let table = Table::read(table);
    let (text, rows) = (&table.text, table.rows());
    assert_eq!(rows.len(), 2, "{text}");
    let (verdict, ratio, distance) = (
        table.column("verdict"),
        table.column("stated_vs_distance"),
        table.column("distance"),
    );
    assert_eq!(rows[0][verdict], "reliable", "{text}");
    let r: f64 = rows[0][ratio].parse().unwrap();
    assert!((0.5..=2.0).contains(&r), "stated / distance = {r}: {text}");
    let (quick, paper): (f64, f64) = (
        rows[0][distance].parse().unwrap(),
        rows[1][distance].parse().unwrap(),
    );
    assert!(paper < quick, "{text}");
}

/// The nonlinear measures' stated errors on the smoke preset (the PI residual, the side-lobe
/// asymmetry, the delayed misfit and the spectral shift at receiver 3) against the references
/// of `sem_target.rhai` (piece `nonlinear`): never "refine"; an estimate within the issue's
/// factor 2 of the measure's distance to the reference that shares nothing with it (measured
/// 1.49 on the misfit, 1.68 on the shift), a bound at least that distance less the references'
/// distance to each other, the truth known no better (the PI residual's and the asymmetry's,
/// from their traces' errors, measured 4.4x and 5.3x the distance).
fn nonlinear_errors_hold_against_the_reference(table: &std::path::Path) {
    let table = Table::read(table);
    let (text, column, rows) = (&table.text, |name: &str| table.column(name), table.rows());
    assert_eq!(rows.len(), 4, "{text}");
    let number = |row: &[&str], name: &str| -> f64 { row[column(name)].parse().unwrap() };
    for row in &rows {
        let verdict = row[column("verdict")];
        assert!(
            ["reliable", "upper_bound", "propagated_bound"].contains(&verdict),
            "{} verdict {verdict}: {text}",
            row[column("measure")]
        );
        let (stated, truth) = (
            number(row, "stated_error"),
            number(row, "error_vs_reference"),
        );
        if verdict == "reliable" {
            let ratio = stated / truth;
            assert!(
                (0.5..=2.0).contains(&ratio),
                "stated / true = {ratio}: {text}"
            );
        } else {
            let floor = truth - number(row, "references_apart");
            assert!(stated >= floor, "bound {stated} below {floor}: {text}");
        }
    }
}

/// The cracked nonlinear measures (PI residual, side-lobe asymmetry, delayed misfit) over
/// the six discretisations of `sem_target.rhai`'s piece `friction_spread` (the smoke scene
/// with the quick preset's elements and other orders across and along x): a friction
/// response time of 20 ns narrows each measure's spread by at least 1.5x against the
/// instantaneous Coulomb law (measured 4.8x, 3.6x and 7.9x at smoke; 1.6x, 2.2x and 2.6x at
/// quick).
fn the_friction_response_time_narrows_the_spread(table: &std::path::Path) {
    let table = Table::read(table);
    let (text, column, rows) = (&table.text, |name: &str| table.column(name), table.rows());
    let spread = |law: &str, measure: &str| -> f64 {
        let values: Vec<f64> = rows
            .iter()
            .filter(|r| r[column("law")] == law && !r[column("run")].starts_with("ref_"))
            .map(|r| r[column(measure)].parse().unwrap())
            .collect();
        assert_eq!(values.len(), 6, "{law}: {text}");
        let (lo, hi) = extent(&values);
        hi - lo
    };
    for measure in ["pi_residual", "side_lobe_asymmetry", "misfit"] {
        let (instantaneous, lagged) =
            (spread("instantaneous", measure), spread("lag20ns", measure));
        assert!(
            instantaneous >= 1.5 * lagged,
            "{measure}: spread {instantaneous} instantaneous, {lagged} with 20 ns: {text}"
        );
    }
}

/// With a 20 ns friction response time the smoke scene's cracked PI residual, side-lobe
/// asymmetry and delayed misfit on the quick preset's discretisation converge over its
/// companions: each states an estimate ("reliable", where the instantaneous law leaves the
/// PI residual and the asymmetry with bounds from their traces), within a factor 2.5 of its
/// distance to the reference under the same law (measured 0.85, 0.51 and 0.72: below the
/// truth, since the contact's error along x falls slowly from order 7 on, which companions
/// at orders 6 and 5 do not see;
/// [`at_smoke_the_contact_measures_move_more_along_x_than_in_time`]). The paper preset's
/// companions state an estimate or an upper bound on each, within 1/2.5 to 3 of its distance
/// to the reference that shares nothing with it (measured 1.02 and 2.45 as bounds on the PI
/// residual and the misfit, 1.51 on the asymmetry).
fn estimates_hold_with_the_friction_response_time(table: &std::path::Path) {
    let table = Table::read(table);
    let (text, column) = (&table.text, |name: &str| table.column(name));
    let lagged = |run: &str| -> Vec<Vec<&str>> {
        table
            .rows()
            .into_iter()
            .filter(|r| r[column("run")] == run && r[column("law")] == "lag20ns")
            .collect()
    };
    let ratio = |row: &[&str]| -> f64 {
        let number = |name: &str| -> f64 { row[column(name)].parse().unwrap() };
        number("stated_error") / number("error_vs_reference")
    };
    let quick = lagged("sem7_0.5mm_across2-4");
    assert_eq!(quick.len(), 3, "{text}");
    for row in &quick {
        assert_eq!(row[column("verdict")], "reliable", "{text}");
        let r = ratio(row);
        assert!((1.0 / 2.5..=2.5).contains(&r), "{r}: {text}");
    }
    let paper = lagged("sem6_0.25mm_across3-6");
    assert_eq!(paper.len(), 3, "{text}");
    for row in &paper {
        assert!(
            ["reliable", "upper_bound"].contains(&row[column("verdict")]),
            "{text}"
        );
        let r = ratio(row);
        assert!((1.0 / 2.5..=3.0).contains(&r), "{r}: {text}");
    }
}

/// The cracked traces' change per relative change (1e-8, 1e-6, 1e-4) of the friction
/// coefficient and of the transmitter's angle, on the smoke scene with the quick preset's
/// elements (`sem_target.rhai`'s piece `friction_spread`): with every friction response time
/// (5 to 50 ns) it is the same at every size, within 5% (measured within 0.2%): the traces
/// depend smoothly on both. Under the instantaneous Coulomb law y_TR's does not (measured
/// 1.8x and 4.2x apart over the sizes), which this check must be able to see.
fn the_friction_response_time_makes_the_focus_smooth(table: &std::path::Path) {
    let table = Table::read(table);
    let (text, column, rows) = (&table.text, |name: &str| table.column(name), table.rows());
    // the largest over the smallest change per relative change over the three sizes
    let spread = |law: &str, direction: &str, trace: &str| -> f64 {
        let ratios: Vec<f64> = rows
            .iter()
            .filter(|r| r[column("law")] == law && r[column("direction")] == direction)
            .map(|r| r[column(trace)].parse().unwrap())
            .collect();
        assert_eq!(ratios.len(), 3, "{law}, {direction}: {text}");
        let (lo, hi) = extent(&ratios);
        hi / lo
    };
    let traces = [
        "response_per_relative_change",
        "focused_per_relative_change",
    ];
    for law in ["lag5ns", "lag10ns", "lag20ns", "lag50ns"] {
        for direction in ["friction", "angle"] {
            for trace in traces {
                let s = spread(law, direction, trace);
                assert!(s <= 1.05, "{law}, {direction}, {trace}: {s}: {text}");
            }
        }
    }
    let instantaneous = ["friction", "angle"].map(|d| spread("instantaneous", d, traces[1]));
    assert!(
        instantaneous.iter().any(|&s| s >= 1.5),
        "{instantaneous:?}: {text}"
    );
}

/// Under a 20 ns friction response time, the smoke scene's cracked PI residual, side-lobe
/// asymmetry and delayed misfit on the quick preset's elements (`sem_target.rhai`'s piece
/// `contact_convergence`): their error is along x, not in time. From order 7 to order 10
/// along x at one step they move by at least twice as much as the preset's order over 1 to
/// 1/8 of its step (measured 11x, 11x and 7x). On the quick scene it is the other way round
/// for the PI residual and the asymmetry, whose error is mostly the step's and the order
/// across's (docs/src/validation/default-experiment.md).
fn at_smoke_the_contact_measures_move_more_along_x_than_in_time(table: &std::path::Path) {
    let table = Table::read(table);
    let (text, column, rows) = (&table.text, |name: &str| table.column(name), table.rows());
    for measure in ["pi_residual", "side_lobe_asymmetry", "misfit"] {
        let value = |series: &str, order: &str| -> Vec<f64> {
            rows.iter()
                .filter(|r| r[column("series")] == series && r[column("order_x")] == order)
                .map(|r| r[column(measure)].parse().unwrap())
                .collect()
        };
        let steps = value("step", "7");
        assert_eq!(steps.len(), 4, "{text}");
        let (lo, hi) = extent(&steps);
        let in_time = hi - lo;
        let along_x = (value("along_x", "10")[0] - value("along_x", "7")[0]).abs();
        assert!(
            in_time <= 0.5 * along_x,
            "{measure}: {in_time} over the steps, {along_x} from order 7 to 10: {text}"
        );
    }
}

#[test]
fn error_estimate_on_fills_the_estimate_columns() {
    let out = std::env::temp_dir().join(format!("trnews-estimates-{}", std::process::id()));
    for script in [
        "trnews_focus.rhai",
        "sweep_delays.rhai",
        "pulse_inversion.rhai",
    ] {
        let result = Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .arg(std::path::Path::new("scripts").join(script))
            .args([
                "--set",
                "resolution=smoke",
                "--set",
                "error_estimate=true",
                "--quiet",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            result.status.success(),
            "{script}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
    }
    for table in [
        "trnews_focus.csv",
        "sweep_delays.csv",
        "pulse_inversion.csv",
    ] {
        let text = std::fs::read_to_string(out.join("plots").join(table)).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert!(
            !rows.is_empty() && rows.iter().all(|r| !r.contains(",off")),
            "{table}: {text}"
        );
        // a verdict of the companions' (under the default friction law every cracked PI
        // residual at smoke is a bound)
        let verdicts = ["reliable", "upper_bound", "propagated_bound", "refine"];
        assert!(
            rows.iter().any(|r| verdicts.iter().any(|v| r.contains(v))),
            "{table}: {text}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The experiments run on spectral elements with `--set discretisation=sem`: the focusing
/// script writes its figures, snapshot VTU and table from an SEM scene, and an unknown
/// discretisation is refused naming the parameter.
#[test]
fn experiments_run_on_spectral_elements() {
    let out = std::env::temp_dir().join(format!("trnews-sem-{}", std::process::id()));
    let run = |kind: &str| {
        Command::new(env!("CARGO_BIN_EXE_trnews-script"))
            .arg(Path::new("scripts").join("trnews_focus.rhai"))
            .args(["--set", "resolution=smoke", "--set"])
            .arg(format!("discretisation={kind}"))
            .args(["--quiet", "--out"])
            .arg(&out)
            .output()
            .unwrap()
    };
    let result = run("sem");
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    for file in [
        "trnews_focus.csv",
        "trnews_focus.png",
        "trnews_snapshot.vtu",
        "trnews_scattered.png",
    ] {
        let bytes = std::fs::read(out.join("plots").join(file)).unwrap();
        assert!(bytes.len() > 100, "{file} is nearly empty");
    }
    let table = std::fs::read_to_string(out.join("plots/trnews_focus.csv")).unwrap();
    assert_eq!(
        table.lines().count(),
        9,
        "header + 2 scenes x the smoke scene's 4 receivers: {table}"
    );
    let refused = run("q4");
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && message.contains("discretisation") && message.contains("q4"),
        "{message}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// The scan's line variant (`--set line=bottom`: the focal points on the bottom face, and
/// `--set line=1.2`: on the line 1.2 mm above the bottom edge, inside the body), 5 positions
/// at smoke: every position focuses, the uncracked baseline's PI residual and delayed misfit
/// are round-off and the cracked ones are not; a line outside the body or a word other than
/// top and bottom is an error naming `line` or the receiver.
#[test]
fn a_scan_runs_along_the_bottom_face_and_along_a_line_inside() {
    let out = std::env::temp_dir().join(format!("trnews-scan-line-{}", std::process::id()));
    let scan = |line: &str| {
        at_smoke("scan.rhai", &out.join(line))
            .args(["--set", "positions=5", "--set"])
            .arg(format!("line={line}"))
            .output()
            .unwrap()
    };
    for line in ["bottom", "1.2"] {
        let result = scan(line);
        assert!(
            result.status.success(),
            "{line}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let text = std::fs::read_to_string(out.join(line).join("plots/scan.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                let cells: Vec<&str> = l.split(',').collect();
                [
                    "pi_residual",
                    "pi_residual_uncracked",
                    "misfit",
                    "misfit_uncracked",
                ]
                .map(|c| cells[column(c)].parse::<f64>().unwrap())
                .to_vec()
            })
            .collect();
        assert_eq!(rows.len(), 5, "{text}");
        for r in &rows {
            assert!(
                r[0] > 1e-3 && r[1] < 1e-12 && r[2] > 1e-3 && r[3] < 1e-12,
                "{line}: {r:?}"
            );
        }
    }
    for (line, named) in [("middle", "line = \"middle\""), ("9", "receivers.at[0]")] {
        let result = scan(line);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(
            !result.status.success() && stderr.contains(named),
            "{line}: {stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The scan from the left (`--set transmitter=left`) is the mirror image of the scan from the
/// right of the mirrored crack: the laminate does not change along x, so with the crack at
/// 2.5 mm in the 6 mm smoke plate (tips snapped to 2-3 mm) and at 3.5 mm (3-4 mm) every map
/// agrees at mirrored positions to 1e-9 of its largest value (round-off in the mirrored
/// node coordinates). `scan_sides.rhai` then locates the crack from both views, the same from
/// the left scan as from the mirrored one, and names a table whose positions differ and a
/// side it does not know.
#[test]
fn a_scan_from_the_left_mirrors_the_mirrored_crack_and_both_views_locate_it() {
    let out = std::env::temp_dir().join(format!("trnews-scan-sides-{}", std::process::id()));
    let run = |script: &str, args: &[&str]| {
        at_smoke(script, &out)
            .arg("--data")
            .arg(&out)
            .args(args.iter().flat_map(|a| ["--set", a]))
            .output()
            .unwrap()
    };
    let scan = |name: &str, args: &[&str]| {
        let mut all = vec!["positions=9"];
        all.extend_from_slice(args);
        let result = run("scan.rhai", &all);
        assert!(
            result.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        for file in ["scan.csv", "scan_localisation.csv"] {
            let plots = out.join("plots");
            std::fs::create_dir_all(out.join(name)).unwrap();
            std::fs::rename(plots.join(file), out.join(name).join(file)).unwrap();
        }
    };
    scan("right", &["crack_x_mm=2.5"]);
    scan("left", &["crack_x_mm=2.5", "transmitter=left"]);
    scan("mirror", &["crack_x_mm=3.5"]);
    let maps = ["pi_residual", "asymmetry", "misfit", "spectral_shift_hz"];
    let read = |name: &str| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(out.join(name).join("scan.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        ["x_mm"]
            .iter()
            .chain(&maps)
            .map(|c| {
                let i = header.iter().position(|h| h == c).unwrap();
                rows.iter().map(|r| r[i].parse::<f64>().unwrap()).collect()
            })
            .collect()
    };
    let (left, mirror) = (read("left"), read("mirror"));
    for (k, name) in maps.iter().enumerate() {
        let (l, m) = (&left[k + 1], &mirror[k + 1]);
        let top = l.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..l.len() {
            let j = l.len() - 1 - i;
            assert!((left[0][i] - (6.0 - mirror[0][j])).abs() < 1e-9);
            assert!(
                (l[i] - m[j]).abs() <= 1e-9 * top,
                "{name} at {}: {} against {}",
                left[0][i],
                l[i],
                m[j]
            );
        }
    }
    let sides = |left: &str, extra: &[&str]| {
        let right = "right=right/scan.csv".to_string();
        let left = format!("left={left}/scan.csv");
        let mut args = vec![
            right.as_str(),
            left.as_str(),
            "truth=right/scan_localisation.csv",
        ];
        args.extend_from_slice(extra);
        run("scan_sides.rhai", &args)
    };
    let mut both = Vec::new();
    for (left, extra) in [("left", vec![]), ("mirror", vec!["left_mirrored=true"])] {
        let result = sides(left, &extra);
        assert!(
            result.status.success(),
            "{left}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let table = std::fs::read_to_string(out.join("plots/scan_sides.csv")).unwrap();
        assert!(out.join("plots/scan_sides.png").is_file());
        let rows: Vec<String> = table
            .lines()
            .filter(|l| l.contains(",both,"))
            .map(str::to_string)
            .collect();
        assert_eq!(rows.len(), 4, "{table}");
        both.push(rows);
    }
    let numbers =
        |row: &str| -> Vec<f64> { row.split(',').filter_map(|c| c.parse().ok()).collect() };
    for (a, b) in both[0].iter().zip(&both[1]) {
        for (x, y) in numbers(a).iter().zip(numbers(b)) {
            assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{a}\n{b}");
        }
    }
    let text = std::fs::read_to_string(out.join("left/scan.csv")).unwrap();
    std::fs::create_dir_all(out.join("short")).unwrap();
    let head: Vec<&str> = text.lines().take(4).collect();
    std::fs::write(out.join("short/scan.csv"), head.join("\n")).unwrap();
    let result = sides("short", &[]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        !result.status.success() && stderr.contains("right has 9 positions, left 3"),
        "{stderr}"
    );
    let result = run("scan.rhai", &["positions=3", "transmitter=middle"]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        !result.status.success() && stderr.contains("transmitter = \"middle\""),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// `scan.rhai` shared out as a Slurm array does (`--shard 1/2`, `--shard 2/2`, then
/// `--merge`) at smoke with 4 positions. Array tasks run at once, so neither may find the
/// other's positions stored: each must store the uncracked baseline's impulse response
/// before it stops after its share (a merge simulates nothing). Run alone, the first shard
/// leaves it stored; the merge computes nothing and writes the maps of one whole run.
#[test]
fn a_scan_in_two_shards_and_a_merge_gives_the_maps_of_one_run() {
    let out = std::env::temp_dir().join(format!("trnews-scan-shards-{}", std::process::id()));
    let run = |dir: &str, extra: &[&str]| {
        let result = at_smoke("scan.rhai", &out.join(dir))
            .args(["--set", "positions=4"])
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
        assert!(result.status.success(), "{dir} {extra:?}: {stderr}");
        stderr
    };
    run("whole", &[]);
    run("shared", &["--shard", "1/2"]);
    let baseline =
        std::fs::read_dir(out.join("shared/points/impulse_response")).map_or(0, |d| d.count());
    assert_eq!(
        baseline, 1,
        "the first shard left no impulse response stored"
    );
    run("shared", &["--shard", "2/2"]);
    let merged = run("shared", &["--merge"]);
    assert!(
        merged.contains("4 points, 4 stored before, 0 computed here"),
        "{merged}"
    );
    // Every column but the run time (measured) is the same, byte for byte.
    let maps = |dir: &str| -> Vec<String> {
        std::fs::read_to_string(out.join(dir).join("plots/scan.csv"))
            .unwrap()
            .lines()
            .map(|l| l.rsplit_once(',').unwrap().0.to_string())
            .collect()
    };
    assert_eq!(maps("whole"), maps("shared"));
    let _ = std::fs::remove_dir_all(&out);
}
