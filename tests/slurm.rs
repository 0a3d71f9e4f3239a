//! Integration test on a real single-node Slurm cluster (`tests/slurm/run.sh`): the smoke
//! delayed TR-NEWS sweep as a 4-task job array plus its dependent merge job, written and
//! submitted by `trnews-script slurm`, gives the figures and tables of a local run, byte for
//! byte. The script installs Debian's slurmctld, slurmd and slurm-client when they are
//! missing, and starts and stops its daemons (auth/none, loopback only). Where they cannot be
//! installed (no root, no apt-get, no package registry) the test says SKIPPED and why; CI
//! (`.ci/run`) runs it with its output shown.

use std::path::Path;
use std::process::Command;

#[test]
fn slurm_job_array_and_merge_equal_a_local_run() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/run.sh");
    let o = Command::new("bash")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_trnews-script"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    match o.status.code() {
        Some(0) => {
            assert!(
                stdout.contains("PASSED: Slurm 4-task array + merge = local run"),
                "{stdout}"
            );
            println!("{stdout}");
        }
        Some(77) => {
            let reason = stdout
                .lines()
                .find(|l| l.starts_with("SKIPPED"))
                .unwrap_or("SKIPPED");
            println!("{reason}");
            eprintln!("{reason}");
        }
        _ => panic!("tests/slurm/run.sh failed:\n{stdout}\n{stderr}"),
    }
}
