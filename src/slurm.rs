//! `trnews-script slurm SCRIPT --array N`: a sweep as a Slurm job array, one shard per task
//! (each task's run reads its shard from `SLURM_ARRAY_TASK_ID` / `SLURM_ARRAY_TASK_COUNT`),
//! plus a merge job that starts when every task has succeeded (`afterok`) and assembles the
//! figures and tables from the point files (see [`crate::sweep`]).

use clap::Parser;
use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// Write (and with --submit, submit) a Slurm job array that computes SCRIPT's sweep points in
/// N shards, and a merge job that runs after it (afterok).
#[derive(Debug, Parser)]
#[command(name = "trnews-script slurm", bin_name = "trnews-script slurm")]
pub struct SlurmArgs {
    /// The script, e.g. scripts/sweep_delays.rhai.
    script: PathBuf,
    /// Number of array tasks (shards of every sweep).
    #[arg(long, value_name = "N")]
    array: usize,
    /// Partition to run on (default: the cluster's default partition).
    #[arg(long, value_name = "P")]
    partition: Option<String>,
    /// Time limit of each task and of the merge, in Slurm's format (e.g. 4:00:00).
    #[arg(long, value_name = "T")]
    time: Option<String>,
    /// CPUs per task; each run uses that many threads.
    #[arg(long, value_name = "C", default_value_t = 2)]
    cpus: usize,
    /// Output directory, on a file system every node sees (points, figures, logs).
    #[arg(long, default_value = crate::script::DEFAULT_OUT_DIR)]
    out: PathBuf,
    /// Script parameter NAME=VALUE, passed to every run.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Submit both jobs with sbatch (otherwise print the commands).
    #[arg(long)]
    submit: bool,
}

/// Runs the `slurm` command; `args` starts with "slurm".
pub fn main(args: impl IntoIterator<Item = OsString>) -> Result<(), String> {
    let args = match SlurmArgs::try_parse_from(args) {
        Ok(args) => args,
        // --help: clap's text on stdout, not an error
        Err(e) if !e.use_stderr() => {
            print!("{e}");
            return Ok(());
        }
        Err(e) => {
            let text = e.to_string();
            return Err(text.trim_start_matches("error: ").trim_end().to_string());
        }
    };
    let jobs = Jobs::new(&args)?;
    jobs.write()?;
    println!(
        "wrote {} and {}",
        jobs.array_file.display(),
        jobs.merge_file.display()
    );
    if !args.submit {
        println!(
            "submit with:\n  id=$(sbatch --parsable {})\n  sbatch --kill-on-invalid-dep=yes \
             --dependency=afterok:${{id%%;*}} {}",
            jobs.array_file.display(),
            jobs.merge_file.display()
        );
        return Ok(());
    }
    let array_id = sbatch(&[], &jobs.array_file, &jobs.array_text)?;
    let dependency = format!("--dependency=afterok:{array_id}");
    let merge_id = sbatch(
        &["--kill-on-invalid-dep=yes", dependency.as_str()],
        &jobs.merge_file,
        &jobs.merge_text,
    )?;
    println!(
        "submitted array job {array_id} ({} tasks) and merge job {merge_id} (starts when \
         every task has succeeded); logs in {}",
        args.array,
        jobs.log_dir.display()
    );
    Ok(())
}

/// The two batch scripts of a sweep.
struct Jobs {
    array_file: PathBuf,
    merge_file: PathBuf,
    log_dir: PathBuf,
    array_text: String,
    merge_text: String,
}

impl Jobs {
    fn new(args: &SlurmArgs) -> Result<Jobs, String> {
        if args.array == 0 {
            return Err("--array 0: give the number of array tasks, at least 1".into());
        }
        if args.cpus == 0 {
            return Err("--cpus 0: give at least 1 CPU per task".into());
        }
        for (flag, value) in [("--partition", &args.partition), ("--time", &args.time)] {
            if let Some(v) = value {
                sbatch_word(flag, v)?;
            }
        }
        if let Some(bad) = args.set.iter().find(|s| !s.contains('=')) {
            return Err(format!("--set '{bad}' is not NAME=VALUE"));
        }
        for s in &args.set {
            one_line("--set", s)?;
        }
        one_line("the script's path", &args.script.to_string_lossy())?;
        let script = args
            .script
            .canonicalize()
            .map_err(|e| format!("cannot read script {}: {e}", args.script.display()))?;
        one_line("the script's path", &script.to_string_lossy())?;
        one_line("--out", &args.out.to_string_lossy())?;
        std::fs::create_dir_all(&args.out)
            .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
        let out = args
            .out
            .canonicalize()
            .map_err(|e| format!("cannot open {}: {e}", args.out.display()))?;
        sbatch_word("--out", &out.to_string_lossy())?;
        let binary = std::env::current_exe()
            .map_err(|e| format!("cannot find the trnews-script binary: {e}"))?;
        one_line("the trnews-script binary's path", &binary.to_string_lossy())?;
        let stem = job_stem(&script);
        let log_dir = out.join("slurm");
        let mut run = vec![
            binary.display().to_string(),
            script.display().to_string(),
            "--out".into(),
            out.display().to_string(),
            "--quiet".into(),
            "--threads".into(),
            args.cpus.to_string(),
        ];
        for s in &args.set {
            run.extend(["--set".to_string(), s.clone()]);
        }
        let header = |name: &str, log: &str, extra: &str| {
            let mut h = format!(
                "#!/bin/bash\n#SBATCH --job-name={name}\n#SBATCH --cpus-per-task={}\n\
                 #SBATCH --output={}\n",
                args.cpus,
                log_dir.join(log).display()
            );
            h.push_str(extra);
            if let Some(p) = &args.partition {
                h.push_str(&format!("#SBATCH --partition={p}\n"));
            }
            if let Some(t) = &args.time {
                h.push_str(&format!("#SBATCH --time={t}\n"));
            }
            h
        };
        let array_text = format!(
            "{}# Task SLURM_ARRAY_TASK_ID computes that shard of every sweep of {} (written by \
             trnews-script slurm).\nset -euo pipefail\nexec {}\n",
            header(
                &format!("trnews-{stem}"),
                &format!("{stem}-%A_%a.log"),
                &format!("#SBATCH --array=0-{}\n", args.array - 1)
            ),
            script.display(),
            shell_words(&run)
        );
        let mut merge = run.clone();
        merge.push("--merge".into());
        let merge_text =
            format!(
            "{}# Assembles the figures and tables of {} from the point files of the array job, \
             computing none; fails naming missing or failed points.\nset -euo pipefail\nexec {}\n",
            header(&format!("trnews-{stem}-merge"), &format!("{stem}-merge-%j.log"), ""),
            script.display(),
            shell_words(&merge)
        );
        Ok(Jobs {
            array_file: log_dir.join(format!("{stem}-array.sbatch")),
            merge_file: log_dir.join(format!("{stem}-merge.sbatch")),
            log_dir,
            array_text,
            merge_text,
        })
    }

    fn write(&self) -> Result<(), String> {
        for (path, text) in [
            (&self.array_file, &self.array_text),
            (&self.merge_file, &self.merge_text),
        ] {
            crate::io::write_atomic(path, text.as_bytes()).map_err(|e| e.to_string())?;
        }
        Ok(())
    }
}

/// Refuses a value that cannot be carried on one line of a batch file: a control character (a
/// newline would end the line and start a shell command, or end the `#SBATCH` header).
fn one_line(field: &str, value: &str) -> Result<(), String> {
    match value.chars().find(|c| c.is_control()) {
        Some(c) => Err(format!(
            "{field} {value:?} holds the control character {c:?}, which a batch file cannot \
             carry; rename it"
        )),
        None => Ok(()),
    }
}

/// Refuses a value of an `#SBATCH` line that sbatch could read as anything but one literal
/// word: only letters, digits and `/ . _ - + : ,` pass (no white space, quotes, `$`, `\`, or
/// `%`, which sbatch expands in file names).
fn sbatch_word(field: &str, value: &str) -> Result<(), String> {
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-+:,".contains(c);
    match value.chars().find(|&c| !plain(c)) {
        _ if value.is_empty() => Err(format!("{field} is empty")),
        Some(c) => Err(format!(
            "{field} {value:?}: the character {c:?} cannot go on an #SBATCH line (letters, \
             digits and / . _ - + : , only); choose another"
        )),
        None => Ok(()),
    }
}

/// The stem that names the jobs, their batch files and logs: the script's file stem with every
/// character other than letters, digits, `.`, `_` and `-` written as `_` (the script itself
/// is run by its real path, quoted).
fn job_stem(script: &Path) -> String {
    let stem = script
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if stem.is_empty() {
        "sweep".into()
    } else {
        stem
    }
}

/// Words quoted for bash: each in single quotes, a quote inside written as '\''.
fn shell_words(words: &[String]) -> String {
    words
        .iter()
        .map(|w| format!("'{}'", w.replace('\'', r"'\''")))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Submits the batch script `text` (written to `file`) with `sbatch --parsable`, returning
/// the job id. sbatch reads `text` on its standard input, not the file: what runs is what was
/// generated, even if someone replaces the file between writing and submitting.
fn sbatch(options: &[&str], file: &Path, text: &str) -> Result<String, String> {
    let cannot =
        |e: std::io::Error| format!("cannot run sbatch (is Slurm's client installed?): {e}");
    let mut child = Command::new("sbatch")
        .arg("--parsable")
        .args(options)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(cannot)?;
    if let Some(mut stdin) = child.stdin.take() {
        stdin.write_all(text.as_bytes()).map_err(cannot)?;
    }
    let out = child.wait_with_output().map_err(cannot)?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(format!(
            "sbatch {} failed: {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    // --parsable prints "id" or "id;cluster".
    let id = stdout
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("sbatch printed '{}', not a job id", stdout.trim()));
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_scripts_run_shards_then_a_merge() {
        let dir = std::env::temp_dir().join(format!("trnews-slurm-unit-{}", std::process::id()));
        let script = dir.join("it's.rhai");
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&script, "print(1);").unwrap();
        let args = SlurmArgs::try_parse_from([
            "slurm",
            script.to_str().unwrap(),
            "--array",
            "4",
            "--time",
            "1:00:00",
            "--out",
            dir.join("out").to_str().unwrap(),
            "--set",
            "resolution=smoke",
        ])
        .unwrap();
        let jobs = Jobs::new(&args).unwrap();
        assert!(
            jobs.array_text.contains("#SBATCH --array=0-3\n"),
            "{}",
            jobs.array_text
        );
        assert!(jobs.array_text.contains("#SBATCH --time=1:00:00\n"));
        assert!(jobs.array_text.contains("'--set' 'resolution=smoke'"));
        assert!(
            jobs.array_text.contains(r"it'\''s.rhai'"),
            "{}",
            jobs.array_text
        );
        assert!(!jobs.array_text.contains("--merge"));
        assert!(
            jobs.merge_text.contains("'--merge'\n"),
            "{}",
            jobs.merge_text
        );
        assert!(!jobs.merge_text.contains("--array"));
        let zero =
            SlurmArgs::try_parse_from(["slurm", script.to_str().unwrap(), "--array", "0"]).unwrap();
        assert!(Jobs::new(&zero).err().unwrap().contains("--array 0"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
