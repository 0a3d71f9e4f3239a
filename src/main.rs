//! `trnews-script`: runs a Rhai experiment script against the trnews library.

use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use trnews::script::{
    parse_param_value, Host, HostOptions, ScriptError, DEFAULT_MAX_OPERATIONS, DEFAULT_OUT_DIR,
};

/// The heap, counted (live bytes and bytes allocated so far) so that the host can hold a
/// script's memory to `--max-memory` and charge native work to `--max-operations`. No cap is
/// set here: an allocation refused by the allocator would abort the process instead of
/// ending the script with an error.
#[global_allocator]
static HEAP: cap::Cap<std::alloc::System> = cap::Cap::new(std::alloc::System, usize::MAX);

fn heap_use() -> trnews::budget::HeapUse {
    trnews::budget::HeapUse {
        live: HEAP.allocated() as u64,
        allocated: HEAP.total_allocated() as u64,
    }
}

/// Run a trnews experiment script (Rhai): simulations, TR-NEWS processing, figures and data files.
#[derive(Debug, Parser)]
#[command(
    name = "trnews-script",
    version,
    about,
    after_help = "Sweeps on a Slurm cluster: trnews-script slurm SCRIPT --array N [--partition P] [--time T] [--cpus C] [--out DIR] [--set NAME=VALUE ...] [--submit] (see trnews-script slurm --help)"
)]
struct Cli {
    /// The script to run, e.g. scripts/sweep_delays.rhai.
    #[arg(required_unless_present_any = ["api", "definitions"])]
    script: Option<PathBuf>,
    /// Directory that every output path of the script is resolved under (`--out .` writes
    /// the committed gallery under plots/).
    #[arg(long, default_value = DEFAULT_OUT_DIR)]
    out: PathBuf,
    /// Directory that every data path the script reads (io::read_npy, read_csv, read_json) is resolved under (default: the script's directory).
    #[arg(long, value_name = "DIR")]
    data: Option<PathBuf>,
    /// Script parameter NAME=VALUE (int, float, bool or string), read with param("NAME", default).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_set)]
    set: Vec<(String, String)>,
    /// Number of worker threads for parallel numerics (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Hide progress display (script print output is still shown).
    #[arg(long)]
    quiet: bool,
    /// Operation budget: script operations plus native work (one per KiB allocated).
    #[arg(long, default_value_t = DEFAULT_MAX_OPERATIONS)]
    max_operations: u64,
    /// Wall-clock limit of the run in seconds, native work included (default: none).
    #[arg(long, value_name = "SECONDS")]
    time_limit: Option<f64>,
    /// Memory limit in GiB: the script stops when its heap exceeds it; scenes, runs and signals
    /// that would exceed it are refused before allocating.
    #[arg(long, value_name = "GIB", default_value_t = 8.0)]
    max_memory: f64,
    /// Only compile the script and report syntax errors.
    #[arg(long)]
    check: bool,
    /// List every function the scripting API offers, with descriptions, and exit; `--api
    /// markdown` writes the book's script reference (docs/src/reference.md).
    #[arg(long, value_name = "FORMAT", num_args = 0..=1, default_missing_value = "text")]
    api: Option<ApiFormat>,
    /// Write Rhai definition files (.d.rhai) of the whole API into DIR, for editors with the
    /// Rhai language server, and exit (see docs/src/guide/editor.md).
    #[arg(long, value_name = "DIR")]
    definitions: Option<PathBuf>,
    /// Compute only share I of N of every sweep's points, then stop (default inside a Slurm
    /// array job: SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT).
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Compute no sweep point: assemble figures and tables from the stored point files,
    /// naming missing or failed points.
    #[arg(long)]
    merge: bool,
}

/// How `--api` lists the API.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ApiFormat {
    /// Grouped by module, for a terminal.
    Text,
    /// The book's script reference page.
    Markdown,
}

/// Splits `NAME=VALUE`.
fn parse_set(text: &str) -> Result<(String, String), String> {
    text.split_once('=')
        .map(|(n, v)| (n.trim().to_string(), v.to_string()))
        .ok_or_else(|| format!("'{text}' is not NAME=VALUE"))
}

fn main() -> ExitCode {
    // `trnews-script slurm SCRIPT --array N ...` writes (and submits) Slurm batch scripts.
    if std::env::args_os().nth(1).is_some_and(|a| a == "slurm") {
        return match trnews::slurm::main(std::env::args_os().skip(1)) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        };
    }
    let cli = Cli::parse();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Stack of the worker threads, the script's included: the 8 MiB a main thread has.
const WORKER_STACK_BYTES: usize = 8 << 20;

/// Runs the command on a thread of the worker pool (`--threads` of them, default one per
/// core), so that the script's own thread does its share of every parallel loop: with one
/// thread the loops run inline, with no hand-over to another thread at each step.
fn run(cli: &Cli) -> Result<(), ScriptError> {
    if cli.threads == Some(0) {
        return Err(ScriptError::new("--threads", "0: give at least 1 thread"));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(cli.threads.unwrap_or(0))
        .stack_size(WORKER_STACK_BYTES)
        .build()
        .map_err(|e| ScriptError::new("--threads", e.to_string()))?
        .install(|| run_in_pool(cli))
}

fn run_in_pool(cli: &Cli) -> Result<(), ScriptError> {
    trnews::budget::install_heap_meter(heap_use);
    let time_limit = match cli.time_limit {
        Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s.min(1e9))),
        Some(s) => {
            return Err(ScriptError::new(
                "--time-limit",
                format!("{s} is not a positive number of seconds"),
            ))
        }
        None => None,
    };
    if !(cli.max_memory.is_finite() && cli.max_memory > 0.0) {
        return Err(ScriptError::new(
            "--max-memory",
            format!("{} is not a positive number of GiB", cli.max_memory),
        ));
    }
    // Ctrl-C asks the running script and its native work to stop at the next check; a
    // second Ctrl-C ends the process at once.
    let _ = ctrlc::set_handler(|| {
        if trnews::budget::cancelled() {
            std::process::exit(130);
        }
        trnews::budget::cancel();
    });
    let host = Host::new(HostOptions {
        out_dir: cli.out.clone(),
        params: cli
            .set
            .iter()
            .map(|(n, v)| (n.clone(), parse_param_value(v)))
            .collect(),
        max_operations: cli.max_operations,
        quiet: cli.quiet,
        time_limit,
        max_memory: (cli.max_memory * (1u64 << 30) as f64).min(u64::MAX as f64) as u64,
        sweep: trnews::sweep::Role::from_cli(cli.shard.as_deref(), cli.merge, |v| {
            std::env::var(v).ok()
        })
        .map_err(|e| ScriptError::new("--shard", e))?,
        data_dir: cli.data.clone(),
    })?;
    if let Some(format) = cli.api {
        let listing = match format {
            ApiFormat::Text => api_text(&host),
            ApiFormat::Markdown => trnews::script::api_markdown(&host.api()),
        };
        return print_listing(&listing);
    }
    if let Some(dir) = &cli.definitions {
        let files = host.write_definitions(dir)?;
        if !cli.quiet {
            eprintln!(
                "{} definition files written to {}",
                files.len(),
                dir.display()
            );
        }
        return Ok(());
    }
    let Some(script) = &cli.script else {
        return Err(ScriptError::new("trnews-script", "no script given"));
    };
    if cli.check {
        host.check_file(script)?;
        if !cli.quiet {
            eprintln!("{}: ok", script.display());
        }
        return Ok(());
    }
    let start = Instant::now();
    host.run_file(script)?;
    for name in host.unread_params() {
        eprintln!(
            "warning: --set {name}: {} never asks for a parameter of that name (misspelt?)",
            script.display()
        );
    }
    if !cli.quiet {
        eprintln!(
            "{}: done in {:.2} s (outputs under {})",
            script.display(),
            start.elapsed().as_secs_f64(),
            cli.out.display()
        );
    }
    Ok(())
}

/// The API grouped by module: signature, then its description indented.
fn api_text(host: &Host) -> String {
    let mut out = String::new();
    let mut module = String::new();
    for f in host.api() {
        if f.module != module {
            out.push_str(&format!("\n[{}]\n", f.module));
            module = f.module.clone();
        }
        out.push_str(&format!("  {}\n      {}\n", f.signature, f.description));
    }
    out
}

/// Writes a listing to standard output; a reader that stops early (`| head`) is not an error.
fn print_listing(text: &str) -> Result<(), ScriptError> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(ScriptError::new(
            "--api",
            format!("cannot write the listing: {e}"),
        )),
        _ => Ok(()),
    }
}
