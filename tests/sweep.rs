//! Sweeps as resumable work units (`src/sweep.rs`), on `scripts/sweep_delays.rhai` at the
//! smoke resolution (6 convolved and 6 simulated delayed TR-NEWS points, about 3 s):
//! a sweep killed with SIGKILL resumes computing only its unfinished points; shards 1/3,
//! 2/3, 3/3 and a merge give the bytes of one run; corrupt and truncated point files are
//! recomputed; failed points are recorded and named; a merge names missing points.
//!
//! "The same outputs" means byte-identical figures and CSV tables. The one file that
//! differs between any two runs is `sweep_delays_run_times.csv`: measured wall times.

use std::collections::BTreeMap;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_trnews-script");

fn script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/sweep_delays.rhai")
}

fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("trnews-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn sweep_command(out: &Path, extra: &[&str]) -> Command {
    let mut c = Command::new(BIN);
    c.arg(script())
        .args(["--set", "resolution=smoke", "--quiet", "--out"])
        .arg(out)
        .args(extra);
    c
}

/// Runs the smoke sweep; panics with its stderr when it fails.
fn run(out: &Path, extra: &[&str]) -> String {
    let o = sweep_command(out, extra).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{extra:?} failed: {err}");
    err
}

/// Every figure and table under `out/plots`, except the run times.
fn outputs(out: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(out.join("plots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.ends_with("sweep_delays_run_times.csv"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect()
}

/// The outputs of one uninterrupted run in a directory of its own, computed once.
fn reference() -> &'static BTreeMap<String, Vec<u8>> {
    static REFERENCE: OnceLock<BTreeMap<String, Vec<u8>>> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let dir = fresh_dir("reference");
        run(&dir, &[]);
        let files = outputs(&dir);
        let _ = std::fs::remove_dir_all(&dir);
        files
    })
}

fn assert_same_outputs(out: &Path) {
    let got = outputs(out);
    let want = reference();
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>()
    );
    assert!(want.len() >= 5, "{:?}", want.keys());
    for (name, bytes) in want {
        assert!(
            got[name] == *bytes,
            "{name} differs from the uninterrupted run"
        );
    }
}

/// The finished point files of `kind` (hidden temporary files of a killed writer excluded),
/// with their inode numbers.
fn point_files(out: &Path, kind: &str) -> BTreeMap<PathBuf, u64> {
    let Ok(dir) = std::fs::read_dir(out.join("points").join(kind)) else {
        return BTreeMap::new();
    };
    dir.map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension().is_some_and(|e| e == "point")
                && !p.file_name().unwrap().to_string_lossy().starts_with('.')
        })
        .map(|p| {
            let ino = std::fs::metadata(&p).unwrap().ino();
            (p, ino)
        })
        .collect()
}

/// The "computed here" count of the summary line of the sweep named `which`
/// ("convolved or recorded" or "simulated").
fn computed(stderr: &str, which: &str) -> usize {
    let line = stderr
        .lines()
        .find(|l| l.contains(&format!("({which}): ")) && l.contains("computed here"))
        .unwrap_or_else(|| panic!("no {which} summary in: {stderr}"));
    let before = line.split(" computed here").next().unwrap();
    before.rsplit(' ').next().unwrap().parse().unwrap()
}

#[test]
fn a_killed_sweep_resumes_computing_only_its_unfinished_points() {
    let out = fresh_dir("killed");
    // One thread: the simulated points run one after the other (about 0.5 s each), so
    // the kill lands between points or inside one.
    let mut child = sweep_command(&out, &["--threads", "1"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    // 6 convolved points come first; kill once 1 to 5 of the 6 simulated ones are stored.
    while point_files(&out, "delayed").len() < 7 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no point was stored"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the sweep ended before the kill"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let before = point_files(&out, "delayed");
    let simulated_before = before.len() - 6;
    assert!(
        (1..6).contains(&simulated_before),
        "killed with {simulated_before} of 6 simulated points stored: not part-way"
    );
    assert!(
        std::fs::metadata(out.join("plots/sweep_delays.csv")).is_err(),
        "the killed run wrote its table"
    );

    let stderr = run(&out, &[]);
    assert_eq!(computed(&stderr, "convolved or recorded"), 0, "{stderr}");
    assert_eq!(
        computed(&stderr, "simulated"),
        6 - simulated_before,
        "{stderr}"
    );
    // The finished points were read, not rewritten: their files are the same inodes.
    let after = point_files(&out, "delayed");
    assert_eq!(after.len(), 12);
    for (path, ino) in &before {
        assert_eq!(after[path], *ino, "{} was rewritten", path.display());
    }
    assert_same_outputs(&out);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn three_shards_and_a_merge_give_the_bytes_of_one_run() {
    let out = fresh_dir("shards");
    let mut simulated = 0;
    // Shards 1 and 2 run at the same time, as array tasks do: both compute the shared
    // first pass (equal signals, different wall times in its run reports) and write it.
    let concurrent: Vec<_> = (1..=2)
        .map(|i| {
            sweep_command(&out, &["--shard", &format!("{i}/3")])
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut logs: Vec<String> = concurrent
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr).into_owned();
            assert!(o.status.success(), "{err}");
            err
        })
        .collect();
    logs.push(run(&out, &["--shard", "3/3"]));
    for (i, stderr) in (1..=3).zip(logs) {
        // Convolved points cost a convolution: every run computes the ones it lacks.
        // Simulated points 1..6 go round-robin: shard i computes points i and i + 3.
        let n = computed(&stderr, "simulated");
        assert_eq!(n, 2, "shard {i}/3: {stderr}");
        simulated += n;
        if i < 3 {
            assert!(
                stderr.contains(&format!(
                    "shard {i}/3: delayed TR-NEWS at receiver 3 (simulated)"
                )),
                "{stderr}"
            );
        }
    }
    assert_eq!(simulated, 6);
    let stderr = run(&out, &["--merge"]);
    assert_eq!(computed(&stderr, "convolved or recorded"), 0, "{stderr}");
    assert_eq!(computed(&stderr, "simulated"), 0, "{stderr}");
    assert_same_outputs(&out);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_merge_names_missing_points_instead_of_plotting_a_partial_sweep() {
    let out = fresh_dir("partial");
    run(&out, &["--shard", "2/3"]);
    let o = sweep_command(&out, &["--merge"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains(
            "merge: delayed TR-NEWS at receiver 3 (simulated): 4 of 6 points are missing"
        ),
        "{stderr}"
    );
    for missing in [
        "1 [tau = [0.0, 5e-7] s, a = [1.0, 0.5]]",
        "6 [tau = [0.0, 2e-6] s, a = [1.0, 1.0]]",
    ] {
        assert!(stderr.contains(missing), "{missing} not named: {stderr}");
    }
    assert!(std::fs::metadata(out.join("plots/sweep_delays_misfit_cracked.png")).is_err());
    assert!(std::fs::metadata(out.join("plots/sweep_delays.csv")).is_err());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn corrupt_and_truncated_point_files_are_recomputed_never_merged() {
    let out = fresh_dir("corrupt");
    run(&out, &[]);
    let files: Vec<PathBuf> = point_files(&out, "delayed").into_keys().collect();
    let truncated = &files[0];
    let bytes = std::fs::read(truncated).unwrap();
    std::fs::write(truncated, &bytes[..bytes.len() / 2]).unwrap();
    // One flipped bit in the middle of a value: the checksum finds it.
    let flipped = &files[1];
    let mut bytes = std::fs::read(flipped).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x01;
    std::fs::write(flipped, bytes).unwrap();
    let first_pass: Vec<PathBuf> = point_files(&out, "tr_news").into_keys().collect();
    std::fs::write(&first_pass[0], b"").unwrap();

    // Each damaged file is reported and its point recomputed, to the same bytes.
    let stderr = run(&out, &[]);
    assert_eq!(stderr.matches("is corrupt").count(), 3, "{stderr}");
    assert!(
        stderr.contains("truncated") || stderr.contains("checksum mismatch"),
        "{stderr}"
    );
    let total = computed(&stderr, "convolved or recorded") + computed(&stderr, "simulated");
    assert_eq!(total, 2, "{stderr}");
    assert_same_outputs(&out);
    let _ = std::fs::remove_dir_all(&out);
}

/// A study::sweep whose point 3 fails while `fail` is true.
const SQUARES: &str = r#"
let fail = param("fail", true);
let results = study::sweep("squares", #{ version: 1 }, [1, 2, 3, 4], |x| {
    if x == 3 && fail { throw "point three refuses"; }
    #{ x: x, square: x * x, root: sqrt(x.to_float()) }
});
let rows = [];
for r in results { rows.push([`${r.x}`, `${r.square}`, `${r.root}`]); }
io::write_csv_rows("squares.csv", ["x", "square", "root"], rows);
"#;

fn squares(out: &Path, extra: &[&str]) -> Output {
    let file = out.join("squares.rhai");
    std::fs::write(&file, SQUARES).unwrap();
    Command::new(BIN)
        .arg(&file)
        .args(["--quiet", "--out"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn a_failed_point_is_recorded_named_and_does_not_stop_the_others() {
    let out = fresh_dir("failed");
    let o = squares(&out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("sweep 'squares': 1 of 4 points failed")
            && stderr.contains("3 [3]: ")
            && stderr.contains("point three refuses"),
        "{stderr}"
    );
    assert!(
        stderr.contains("point 4/4 [4] done"),
        "point 4 did not run: {stderr}"
    );
    assert_eq!(
        point_files(&out, "sweep").len(),
        4,
        "3 results and 1 failure"
    );
    assert!(std::fs::metadata(out.join("squares.csv")).is_err());

    let o = squares(&out, &["--merge"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("0 of 4 points are missing and 1 failed"),
        "{stderr}"
    );
    assert!(stderr.contains("point three refuses"), "{stderr}");

    // The cause gone, a rerun computes the failed point only.
    let o = squares(&out, &["--set", "fail=false"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("4 points, 3 stored before, 1 computed here, 0 failed"),
        "{stderr}"
    );
    let csv = std::fs::read_to_string(out.join("squares.csv")).unwrap();
    assert_eq!(
        csv,
        format!(
            "x,square,root\n1,1,1.0\n2,4,{}\n3,9,{}\n4,16,2.0\n",
            2f64.sqrt(),
            3f64.sqrt()
        )
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn sweep_results_must_be_plain_values() {
    let out = fresh_dir("plain");
    let file = out.join("signal.rhai");
    std::fs::write(
        &file,
        r#"study::sweep("s", #{}, [1], |x| signal::from_array(1e-6, 0.0, [1.0, 2.0]));"#,
    )
    .unwrap();
    let o = Command::new(BIN)
        .arg(&file)
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("the result of points[0] is a Signal: a sweep stores plain values only"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_shard_argument_is_checked() {
    let out = fresh_dir("badshard");
    for (args, says) in [
        (
            vec!["--shard", "4/3"],
            "--shard 4/3: expected I/N with 1 <= I <= N",
        ),
        (
            vec!["--shard", "1/2", "--merge"],
            "--shard and --merge exclude each other",
        ),
    ] {
        let o = sweep_command(&out, &args).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && stderr.contains(says), "{stderr}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_point_computed_alone_is_bit_identical_to_the_same_point_in_the_whole_sweep() {
    use std::sync::Arc;
    use trnews::scene::{Scene, SceneSpec};
    use trnews::trnews::{delayed_tr_news, delayed_tr_news_within, tr_news, Responder, TrNewsSpec};
    // Work units run over the sweep's longest delay, as the whole sweep does; the cracked
    // scene (simulated, contact active) is where a different run length would show.
    let scene = Arc::new(Scene::build(&SceneSpec::smoke()).unwrap());
    let spec = TrNewsSpec {
        receivers: vec![3],
        ..TrNewsSpec::smoke()
    };
    let r = Responder::new(scene, spec.focus_duration_s() + 3e-6).unwrap();
    let tr = tr_news(&r, &spec).unwrap();
    let points = vec![
        (vec![0.0, 0.5e-6], vec![1.0, 1.0]),
        (vec![0.0, 2e-6], vec![1.0, 0.5]),
    ];
    let whole = delayed_tr_news(&r, &tr, &tr.focus[0], &points, 5e-6).unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (i, w) in whole.iter().enumerate() {
        let alone =
            delayed_tr_news_within(&r, &tr, &tr.focus[0], &points[i..=i], 5e-6, 2e-6).unwrap();
        assert_eq!(alone[0].misfit.to_bits(), w.misfit.to_bits());
        assert_eq!(
            bits(&alone[0].simulation.samples),
            bits(&w.simulation.samples)
        );
        assert_eq!(
            bits(&alone[0].prediction.samples),
            bits(&w.prediction.samples)
        );
    }
}

#[test]
fn point_files_stay_inside_the_output_directory() {
    // points/ as a symlink leading out is refused on read and on write, as every output is.
    let out = fresh_dir("symlink");
    let outside = fresh_dir("symlink-target");
    std::os::unix::fs::symlink(&outside, out.join("points")).unwrap();
    let o = sweep_command(&out, &[]).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("leads outside the output directory"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(&outside).unwrap().count(),
        0,
        "wrote outside"
    );
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&outside);
}
