//! The Rhai scripting host: a sandboxed [`rhai::Engine`] with one static module per library
//! domain, and the rendering of every script error as `file:line:column: message`.
//!
//! Bindings are thin: each function in `src/script/<module>.rs` converts its arguments,
//! calls the library and converts the result back. To bind a new library module, add a file
//! with an `#[export_module]` and a `pub fn module() -> Module`, then one line in
//! [`MODULES`]. Host state a binding needs (output directory, `--set` parameters, progress
//! display) is reached through [`HostContext::of`].
//!
//! Rhai names exposed here: `accuracy`, `signal`, `plot`, `io`, `material`, `laminate`, `scene`, `trnews`,
//! `study`, `figure`, `fmt`, `test`, `host`.

mod accuracy;
mod channel;
mod convert;
mod experiment;
mod figure;
mod format;
mod host;
mod io;
mod laminate;
mod material;
mod plot;
mod progress;
mod scene;
mod signal;
mod study;
mod test;
mod trnews;

pub use convert::{ScriptResult, WithPosition};

use rhai::module_resolvers::DummyModuleResolver;
use rhai::{Dynamic, Engine, EvalAltResult, Module, ParseError, Position, Scope, AST};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, RwLock};
use std::time::Duration;

/// Builds one Rhai module from its `#[export_module]`.
type ModuleBuilder = fn() -> Module;

/// Every Rhai module of the host: its name in scripts and its builder.
/// Adding a binding (e.g. `scene`) is one entry here plus its file.
const MODULES: &[(&str, ModuleBuilder)] = &[
    ("accuracy", accuracy::module),
    ("signal", signal::module),
    ("plot", plot::module),
    ("io", io::module),
    ("material", material::module),
    ("laminate", laminate::module),
    ("scene", scene::module),
    ("trnews", trnews::module),
    ("experiment", experiment::module),
    ("study", study::module),
    ("figure", figure::module),
    ("fmt", format::module),
    ("test", test::module),
    ("host", host::module),
];

/// Default operation budget of a script run (`--max-operations`): script operations plus
/// native work at one operation per KiB allocated (see [`crate::budget::check_script`]).
pub const DEFAULT_MAX_OPERATIONS: u64 = 1_000_000_000;
/// Default output directory of a script run (`--out`): git-ignored in this repository, so a
/// run leaves a checkout clean; the committed gallery is written with `--out .`.
pub const DEFAULT_OUT_DIR: &str = "out";
/// Deepest script function call nesting allowed.
pub const MAX_CALL_LEVELS: usize = 64;

/// How a [`Host`] is set up.
#[derive(Clone, Debug)]
pub struct HostOptions {
    /// Directory every output path is resolved under (created if missing).
    pub out_dir: PathBuf,
    /// `--set NAME=VALUE` parameters: readable with `param(name, default)` and as constants.
    pub params: BTreeMap<String, Dynamic>,
    /// Operation budget (script operations plus native work, one per KiB allocated); a script
    /// exceeding it stops with an error naming the limit.
    pub max_operations: u64,
    /// Hide progress display (script `print` output is still shown).
    pub quiet: bool,
    /// Wall-clock limit of a script run, native work included (`--time-limit`); `None`: none.
    pub time_limit: Option<Duration>,
    /// Memory limit in bytes (`--max-memory`): the live heap of the run, when the process
    /// meters its heap, and every request's estimate (a scene, a run, a signal) on top of it.
    pub max_memory: u64,
    /// What the run does with sweep points not stored yet: all, a shard's share, or none
    /// (`--shard`, `--merge`; see [`crate::sweep`]).
    pub sweep: crate::sweep::Role,
    /// Directory every data path read by a script is resolved under (`--data`); `None`: the
    /// directory of the script file ([`Host::run_file`]).
    pub data_dir: Option<PathBuf>,
}

impl Default for HostOptions {
    fn default() -> Self {
        HostOptions {
            out_dir: PathBuf::from(DEFAULT_OUT_DIR),
            params: BTreeMap::new(),
            max_operations: DEFAULT_MAX_OPERATIONS,
            quiet: false,
            time_limit: None,
            max_memory: crate::budget::DEFAULT_MEMORY_LIMIT,
            sweep: crate::sweep::Role::Whole,
            data_dir: None,
        }
    }
}

/// A script failure, rendered once at the edge as `file:line:column: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScriptError {
    /// The script as named on the command line (or the host's name for it).
    pub file: String,
    /// 1-based line and column of the failing expression, when known.
    pub position: Option<(usize, usize)>,
    /// One-line description of the cause.
    pub message: String,
}

impl fmt::Display for ScriptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some((line, col)) => write!(f, "{}:{line}:{col}: {}", self.file, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for ScriptError {}

impl ScriptError {
    /// An error without a position (unreadable file, bad host option).
    pub fn new(file: impl Into<String>, message: impl Into<String>) -> Self {
        ScriptError {
            file: file.into(),
            position: None,
            message: one_line(&message.into()),
        }
    }

    fn at(file: &str, pos: Position, message: &str) -> Self {
        ScriptError {
            position: pos.line().map(|l| (l, pos.position().unwrap_or(1))),
            ..ScriptError::new(file, message)
        }
    }
}

/// Joins the lines of a message so that every error prints on one line.
fn one_line(message: &str) -> String {
    message.trim().lines().collect::<Vec<_>>().join("; ")
}

/// Host state shared with native functions through the engine's tag.
#[derive(Debug)]
pub struct HostContext {
    out_dir: PathBuf,
    root: Option<crate::io::OutputRoot>,
    /// The input root of `io::read_*`: `--data`, or the running script's directory.
    data: RwLock<Option<crate::input::InputRoot>>,
    params: BTreeMap<String, Dynamic>,
    /// The `--set` parameters the script has asked for, given or not (see [`Host::unread_params`]).
    asked: RwLock<BTreeSet<String>>,
    quiet: bool,
    script: RwLock<String>,
    progress: RwLock<Option<indicatif::ProgressBar>>,
}

impl HostContext {
    /// The context of the host running the current call.
    pub fn of(ctx: &rhai::NativeCallContext) -> ScriptResult<Arc<HostContext>> {
        ctx.tag()
            .and_then(|t| t.read_lock::<Arc<HostContext>>().map(|c| Arc::clone(&c)))
            .ok_or_else(|| convert::error(ctx, "no host context: engine not built by Host"))
    }

    /// The output directory every written file lies under.
    pub fn out_dir(&self) -> &Path {
        &self.out_dir
    }

    /// The `--set` value of parameter `name`, if given; the script has now asked for it.
    pub fn param(&self, name: &str) -> Option<&Dynamic> {
        if let Ok(mut asked) = self.asked.write() {
            if !asked.contains(name) {
                asked.insert(name.to_string());
            }
        }
        self.params.get(name)
    }

    /// The `--set` value of parameter `name`, if given, without marking it asked for: for a
    /// binding that validates a setup at once and marks each parameter as the script uses it.
    pub fn given(&self, name: &str) -> Option<&Dynamic> {
        self.params.get(name)
    }

    /// True when progress display is off (`--quiet`).
    pub fn quiet(&self) -> bool {
        self.quiet
    }

    /// Resolves a script-given output path under the output directory. Absolute paths and
    /// `..` components are rejected, naming the path. Directories are created when the file
    /// is written, beneath the output root opened by the host: a symlink that leads out of it
    /// is refused then (see [`crate::io::OutputRoot`]).
    pub fn resolve_output(&self, path: &str) -> Result<PathBuf, String> {
        let rel = Path::new(path);
        if path.is_empty() {
            return Err("output path is empty".into());
        }
        if rel.has_root() || rel.is_absolute() {
            return Err(format!(
                "output path '{path}' is absolute; give a path relative to the output directory {}",
                self.out_dir.display()
            ));
        }
        if rel
            .components()
            .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
        {
            return Err(format!(
                "output path '{path}' leaves the output directory ('..' is not allowed)"
            ));
        }
        if rel.file_name().is_none() {
            return Err(format!("output path '{path}' names no file"));
        }
        Ok(self.out_dir.join(rel))
    }

    /// The input directory every data file is read beneath, or an error saying how to set one.
    pub fn data_root(&self) -> Result<crate::input::InputRoot, String> {
        self.data
            .read()
            .ok()
            .and_then(|d| d.clone())
            .ok_or_else(|| {
                "no data directory: run the script from a file or pass --data DIR".into()
            })
    }

    /// Reads an input file a script names (a Gmsh mesh) beneath the data root, like
    /// `io::read_*` (see [`crate::input::InputRoot::read`]); a file above a quarter of the
    /// memory limit is refused before it is read (a mesh takes a few times its file).
    pub fn read_input(&self, path: &str) -> Result<Vec<u8>, String> {
        self.data_root()?
            .read(
                path,
                crate::budget::memory_limit() / 4,
                "a quarter of --max-memory",
            )
            .map_err(|e| e.to_string())
    }

    /// Prints a script message to stderr, prefixed with the script name, without
    /// tearing an active progress display.
    pub fn print(&self, text: &str) {
        let line = format!(
            "[{}] {text}",
            self.script.read().map(|s| s.clone()).unwrap_or_default()
        );
        match self
            .progress
            .read()
            .ok()
            .as_deref()
            .and_then(Option::as_ref)
        {
            Some(_) => progress::group().suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    /// Starts the spinner shown while a script runs (unless quiet).
    fn start(&self, script: &str) {
        if let Ok(mut s) = self.script.write() {
            *s = script.to_string();
        }
        if self.quiet {
            return;
        }
        let spinner =
            indicatif::ProgressBar::new_spinner().with_message(format!("running {script}"));
        let bar = progress::group().add(spinner);
        bar.enable_steady_tick(Duration::from_millis(200));
        if let Ok(mut p) = self.progress.write() {
            *p = Some(bar);
        }
    }

    /// Removes the spinner.
    fn finish(&self) {
        if let Some(bar) = self.progress.write().ok().and_then(|mut p| p.take()) {
            bar.finish_and_clear();
        }
    }
}

/// The scripting host: a sandboxed engine with the trnews modules registered.
pub struct Host {
    engine: Engine,
    context: Arc<HostContext>,
    time_limit: Option<Duration>,
    max_memory: u64,
    sweep: crate::sweep::Role,
    /// True when `--data` was given; otherwise each script file's directory is its data root.
    data_fixed: bool,
}

/// The token of a shard run that has computed its share of a sweep: the script stops there,
/// and the run succeeds (see [`crate::sweep::SweepError::ShardDone`]).
#[derive(Clone, Debug)]
struct ShardDone(String);

/// A sweep's failure as a script error: a finished shard ends the script successfully
/// (an uncatchable termination the host recognises), anything else is an error at `ctx`.
pub(crate) fn sweep_error(
    ctx: &rhai::NativeCallContext,
    e: crate::sweep::SweepError,
) -> Box<EvalAltResult> {
    match e {
        crate::sweep::SweepError::ShardDone(message) => {
            EvalAltResult::ErrorTerminated(Dynamic::from(ShardDone(message)), ctx.call_position())
                .into()
        }
        other => convert::error(ctx, other),
    }
}

impl Host {
    /// Builds the engine, its sandbox limits and modules; creates the output directory.
    pub fn new(options: HostOptions) -> Result<Host, ScriptError> {
        for name in options.params.keys() {
            check_param_name(name).map_err(|m| ScriptError::new("--set", m))?;
        }
        if options.max_operations == 0 {
            // 0 would stop every script at its first operation; "unlimited" is not offered.
            return Err(ScriptError::new(
                "--max-operations",
                "0 is not a limit; give a positive operation budget",
            ));
        }
        if let Some(t) = options.time_limit.filter(|t| t.is_zero()) {
            return Err(ScriptError::new(
                "--time-limit",
                format!(
                    "{} s is not a limit; give a positive number of seconds",
                    t.as_secs_f64()
                ),
            ));
        }
        if options.max_memory == 0 {
            return Err(ScriptError::new(
                "--max-memory",
                "0 is not a limit; give a positive size",
            ));
        }

        let root = crate::io::OutputRoot::open(&options.out_dir)
            .map_err(|e| ScriptError::new(options.out_dir.display().to_string(), e.to_string()))?;
        let data = options
            .data_dir
            .as_deref()
            .map(crate::input::InputRoot::open)
            .transpose()
            .map_err(|e| ScriptError::new("--data", e.to_string()))?;
        crate::solve::progress::set_reporter(if options.quiet {
            None
        } else {
            Some(Arc::new(progress::TerminalBars))
        });
        let context = Arc::new(HostContext {
            out_dir: options.out_dir,
            root: Some(root),
            data: RwLock::new(data),
            params: options.params,
            asked: RwLock::new(BTreeSet::new()),
            quiet: options.quiet,
            script: RwLock::new(String::new()),
            progress: RwLock::new(None),
        });
        let engine = build_engine(&context, options.max_operations);
        Ok(Host {
            engine,
            context,
            time_limit: options.time_limit,
            max_memory: options.max_memory,
            sweep: options.sweep,
            data_fixed: options.data_dir.is_some(),
        })
    }

    /// The underlying engine (for metadata).
    pub fn engine(&self) -> &Engine {
        &self.engine
    }

    /// Adds a module of an embedding application's own functions under `name`; the sandbox,
    /// the budgets and the panic guard apply to them as to the built-in modules.
    pub fn register_module(&mut self, name: &str, module: Module) {
        self.engine.register_static_module(name, module.into());
    }

    /// Compiles the script at `path` without running it.
    pub fn check_file(&self, path: &Path) -> Result<(), ScriptError> {
        let (name, text) = read_script(path)?;
        self.compile(&name, &text).map(|_| ())
    }

    /// Compiles and runs the script at `path`. Without `--data`, data files are read beneath
    /// the script's own directory, opened now.
    pub fn run_file(&self, path: &Path) -> Result<(), ScriptError> {
        let (name, text) = read_script(path)?;
        if !self.data_fixed {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            let root = crate::input::InputRoot::open(dir)
                .map_err(|e| ScriptError::new(&name, e.to_string()))?;
            if let Ok(mut d) = self.context.data.write() {
                *d = Some(root);
            }
        }
        self.run_str(&name, &text)
    }

    /// Compiles and runs script text; `name` is used in messages.
    pub fn run_str(&self, name: &str, text: &str) -> Result<(), ScriptError> {
        let ast = self.compile(name, text)?;
        let mut scope = self.scope();
        self.context.start(name);
        crate::budget::start(self.time_limit);
        crate::budget::set_memory_limit(self.max_memory);
        let printer = Arc::clone(&self.context);
        let store = Arc::new(crate::sweep::Store::new(
            &self.context.out_dir,
            self.context.root.clone(),
            self.sweep,
            move |line| printer.print(line),
        ));
        let result = self.guarded(name, || {
            let mut run = || store.within(|| self.engine.run_ast_with_scope(&mut scope, &ast));
            match &self.context.root {
                Some(root) => root.within(run),
                None => run(),
            }
        });
        self.context.finish();
        crate::budget::clear();
        match result? {
            Ok(()) => Ok(()),
            Err(e) => match Self::shard_done(&e) {
                Some(message) => {
                    self.context.print(&message);
                    Ok(())
                }
                None => Err(self.render(name, &e)),
            },
        }
    }

    /// The `--set` parameters no script run by this host has asked for (with `param` or a
    /// binding that reads parameters, such as `trnews::channel`): a misspelt name would
    /// otherwise leave the script on its default without a word.
    pub fn unread_params(&self) -> Vec<String> {
        let asked = self
            .context
            .asked
            .read()
            .map(|a| a.clone())
            .unwrap_or_default();
        self.context
            .params
            .keys()
            .filter(|name| !asked.contains(*name))
            .cloned()
            .collect()
    }

    /// The message of a shard that finished its share, when `err` is that stop.
    fn shard_done(err: &EvalAltResult) -> Option<String> {
        match err.unwrap_inner() {
            EvalAltResult::ErrorTerminated(token, _) => {
                token.read_lock::<ShardDone>().map(|s| s.0.clone())
            }
            _ => None,
        }
    }

    /// Runs `f`, turning a panic that escaped a native function into a [`ScriptError`] naming
    /// the script and the Rust location (no input should get there: this is the last line of
    /// defence, and the message says it is a bug). The script's line is not tracked: a
    /// statement-level debugger hook made every script operation about 17x slower (measured
    /// on a loop of 2 million additions: 216 s against 12.6 s).
    fn guarded<T>(&self, name: &str, f: impl FnOnce() -> T) -> Result<T, ScriptError> {
        crate::guard::reset();
        let _guarded = crate::guard::Guarded::start();
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|payload| {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            let message = format!(
                "internal error (a bug, please report it): {what}{}",
                crate::guard::panic_location()
                    .map(|l| format!(" at {l}"))
                    .unwrap_or_default()
            );
            ScriptError::new(name, message)
        })
    }

    /// The function list of `--api`, grouped by module.
    pub fn api(&self) -> Vec<ApiFunction> {
        api_listing(&self.engine)
    }

    /// Writes Rhai definition files (`.d.rhai`) of the whole API into `dir` (`--definitions`):
    /// one per module (`scene.d.rhai`, ...), the global functions and types
    /// (`__static__.d.rhai`), Rhai's built-ins, and the `--set` parameters
    /// (`__scope__.d.rhai`). The Rhai language server reads them to complete and check
    /// scripts. Returns the files written.
    pub fn write_definitions(&self, dir: &Path) -> Result<Vec<PathBuf>, ScriptError> {
        let scope = self.scope();
        // Rhai yields the scope's file once per item: keep each file once.
        let files: BTreeMap<String, String> = self
            .engine
            .definitions_with_scope(&scope)
            .iter_files()
            .collect();
        files
            .into_iter()
            .map(|(name, text)| {
                let file = dir.join(name);
                crate::io::write_atomic(&file, definition_types(&text).as_bytes())
                    .map(|()| file)
                    .map_err(|e| ScriptError::new("--definitions", e.to_string()))
            })
            .collect()
    }

    fn compile(&self, name: &str, text: &str) -> Result<AST, ScriptError> {
        let mut ast = self
            .engine
            .compile_with_scope(&self.scope(), text)
            .map_err(|e| parse_error(name, &e))?;
        ast.set_source(name);
        Ok(ast)
    }

    /// A scope holding the `--set` parameters as constants.
    fn scope(&self) -> Scope<'static> {
        let mut scope = Scope::new();
        for (name, value) in &self.context.params {
            scope.push_constant_dynamic(name.clone(), value.clone());
        }
        scope
    }

    fn render(&self, file: &str, err: &EvalAltResult) -> ScriptError {
        let pos = deepest_position(err);
        ScriptError::at(file, pos, &self.message(err))
    }

    /// One-line message for the innermost cause, naming the script functions it passed through.
    fn message(&self, err: &EvalAltResult) -> String {
        let inner = err.unwrap_inner();
        let base = match inner {
            EvalAltResult::ErrorRuntime(value, _) => value.to_string(),
            EvalAltResult::ErrorTerminated(token, _) => token.to_string(),
            EvalAltResult::ErrorStackOverflow(_) => {
                format!("call depth limit {MAX_CALL_LEVELS} exceeded (runaway recursion?)")
            }
            other => {
                let text = other.to_string();
                let suffix = format!(" ({})", other.position());
                text.strip_suffix(&suffix).unwrap_or(&text).to_string()
            }
        };
        let functions = called_functions(err);
        if functions.is_empty() {
            base
        } else {
            format!("{base} (in function {})", functions.join(" <- "))
        }
    }
}

/// Reads a script file; the name used in messages is the path as given.
fn read_script(path: &Path) -> Result<(String, String), ScriptError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| ScriptError::new(&name, format!("cannot read script: {e}")))?;
    Ok((name, text))
}

fn parse_error(file: &str, err: &ParseError) -> ScriptError {
    ScriptError::at(file, err.1, &format!("syntax error: {}", err.0))
}

/// The position of the innermost error in a chain of script function calls that has one.
fn deepest_position(err: &EvalAltResult) -> Position {
    let inner_pos = match err {
        EvalAltResult::ErrorInFunctionCall(.., inner, _)
        | EvalAltResult::ErrorInModule(.., inner, _) => deepest_position(inner),
        _ => Position::NONE,
    };
    if inner_pos.is_none() {
        err.position()
    } else {
        inner_pos
    }
}

/// Names of the script functions an error passed through, innermost first.
fn called_functions(err: &EvalAltResult) -> Vec<String> {
    match err {
        EvalAltResult::ErrorInFunctionCall(name, _, inner, _) => {
            let mut names = called_functions(inner);
            names.push(format!("'{name}'"));
            names
        }
        EvalAltResult::ErrorInModule(_, inner, _) => called_functions(inner),
        _ => Vec::new(),
    }
}

/// The sandboxed engine: limits, no `import` of files, no `eval` (its errors would have no
/// file position), print and debug routed to stderr.
///
/// Operations, memory, time and Ctrl-C are checked by the host between operations
/// ([`crate::budget::check_script`]), not by Rhai's own limits: Rhai's size limits on strings,
/// arrays and maps walk the whole value after each change (building an array by `push`
/// becomes quadratic, so no limit ever trips), and its operation count cannot include native
/// work. The live heap covers every script value instead.
fn build_engine(context: &Arc<HostContext>, max_operations: u64) -> Engine {
    let mut engine = Engine::new();
    engine
        .set_max_call_levels(MAX_CALL_LEVELS)
        .set_module_resolver(DummyModuleResolver::new())
        .set_default_tag(Dynamic::from(Arc::clone(context)))
        .disable_symbol("eval");
    engine.on_progress(move |operations| {
        crate::budget::check_script(operations, max_operations)
            .err()
            .map(|stop| Dynamic::from(stop.to_string()))
    });
    let printer = Arc::clone(context);
    engine.on_print(move |text| printer.print(text));
    let debugger = Arc::clone(context);
    engine.on_debug(move |text, _source, pos| {
        let at = pos.line().map_or(String::new(), |l| {
            format!("{l}:{}: ", pos.position().unwrap_or(1))
        });
        debugger.print(&format!("{at}{text}"))
    });
    exact_float_comparisons(&mut engine);
    accuracy::register_types(&mut engine);
    signal::register_types(&mut engine);
    laminate::register_types(&mut engine);
    scene::register_types(&mut engine);
    trnews::register_types(&mut engine);
    experiment::register_types(&mut engine);
    study::register_types(&mut engine);
    for (name, build) in MODULES {
        engine.register_static_module(*name, build().into());
    }
    engine
}

/// IEEE comparisons of floats (and of a float with an integer) in scripts, in place of
/// Rhai's, which take two numbers within f64::EPSILON of each other as equal: relative to the
/// larger, but absolute where either is 0 or their product underflows. A script in SI units
/// compares displacements of 1e-20 m and times of 1e-17 s, which Rhai's `x > 0.0` calls 0
/// (`2e-25 > 0.0` is false there). Rhai's built-in operators skip registered ones unless
/// its fast-operator mode is off.
fn exact_float_comparisons(engine: &mut Engine) {
    use rhai::{FLOAT, INT};
    engine.set_fast_operators(false);
    macro_rules! exact {
        ($($op:tt),*) => {$(
            engine.register_fn(stringify!($op), |x: FLOAT, y: FLOAT| x $op y);
            engine.register_fn(stringify!($op), |x: FLOAT, y: INT| x $op y as FLOAT);
            engine.register_fn(stringify!($op), |x: INT, y: FLOAT| (x as FLOAT) $op y);
        )*};
    }
    exact!(==, !=, <, <=, >, >=);
}

/// Checks that a `--set` name is a valid Rhai identifier.
fn check_param_name(name: &str) -> Result<(), String> {
    let mut chars = name.chars();
    let first_ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if first_ok && chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        Ok(())
    } else {
        Err(format!(
            "parameter name '{name}' is not an identifier (letters, digits, '_')"
        ))
    }
}

/// Parses a `--set` value: integer, then float, then `true`/`false`, else a string.
pub fn parse_param_value(text: &str) -> Dynamic {
    if let Ok(i) = text.parse::<rhai::INT>() {
        Dynamic::from_int(i)
    } else if let Some(f) = text.parse::<rhai::FLOAT>().ok().filter(|f| f.is_finite()) {
        // "nan" and "inf" stay strings: a parameter never smuggles in a non-finite number
        Dynamic::from_float(f)
    } else if let Ok(b) = text.parse::<bool>() {
        Dynamic::from_bool(b)
    } else {
        Dynamic::from(text.to_string())
    }
}

/// One registered function as listed by `--api`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ApiFunction {
    /// Rhai module the function is registered in.
    pub module: String,
    /// Signature with parameter names, types and return type.
    pub signature: String,
    /// First paragraph of its doc comment, on one line.
    pub description: String,
}

/// Lists every function of the host's modules from the engine's own metadata.
fn api_listing(engine: &Engine) -> Vec<ApiFunction> {
    let json = engine
        .gen_fn_metadata_to_json(false)
        .expect("function metadata serialises to JSON");
    let meta: serde_json::Value = serde_json::from_str(&json).expect("metadata is valid JSON");
    let mut out = Vec::new();
    if let Some(modules) = meta["modules"].as_object() {
        for (module, m) in modules {
            for f in m["functions"].as_array().into_iter().flatten() {
                out.push(api_function(module, f));
            }
        }
    }
    // the engine's metadata comes in hash order: sorted, the listing is the same every run
    out.sort_by(|a, b| (&a.module, &a.signature).cmp(&(&b.module, &b.signature)));
    out
}

/// The script reference of the book (`docs/src/reference.md`, `--api markdown`): every
/// function grouped by module, its signature and description.
pub fn api_markdown(functions: &[ApiFunction]) -> String {
    let mut out = String::from(
        "# Script reference\n\n\
         Every function the scripting API offers, grouped by module, as `trnews-script --api` \
         lists it. Generated: `cargo run --release -- --api markdown > docs/src/reference.md` \
         (the test suite fails when this page and the API differ).\n",
    );
    let mut module = "";
    for f in functions {
        if f.module != module {
            module = &f.module;
            out.push_str(&format!("\n## {module}\n\n"));
        }
        // the description is prose from doc comments: angle brackets kept literal
        let description = f.description.replace('<', "&lt;");
        out.push_str(&format!("- `{}`", f.signature));
        if !description.is_empty() {
            out.push_str(&format!("<br>\n  {description}"));
        }
        out.push('\n');
    }
    out
}

/// One [`ApiFunction`] from a function's metadata record.
fn api_function(module: &str, f: &serde_json::Value) -> ApiFunction {
    let docs: Vec<&str> = f["docComments"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|d| d.as_str())
        .collect();
    ApiFunction {
        module: module.to_string(),
        signature: signature(module, f),
        description: first_paragraph(&docs),
    }
}

/// A script-facing signature: `module::name(p: type, ...) -> type` for namespaced functions,
/// `name(...)` for global ones (callable bare or as methods), `Type.prop -> type` for getters.
fn signature(module: &str, f: &serde_json::Value) -> String {
    let name = f["name"].as_str().unwrap_or_default();
    let params: Vec<(String, String)> = f["params"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|p| {
            let n = p["name"].as_str().unwrap_or("_").to_string();
            (n, script_type(p["type"].as_str().unwrap_or("?")))
        })
        .collect();
    let ret = script_type(f["returnType"].as_str().unwrap_or_default());
    let arrow = if ret.is_empty() {
        String::new()
    } else {
        format!(" -> {ret}")
    };
    if let (Some(prop), Some((_, owner))) = (name.strip_prefix("get$"), params.first()) {
        return format!("{owner}.{prop}{arrow}");
    }
    let list: Vec<String> = params.iter().map(|(n, t)| format!("{n}: {t}")).collect();
    let prefix = if f["namespace"] == "global" {
        String::new()
    } else {
        format!("{module}::")
    };
    format!("{prefix}{name}({}){arrow}", list.join(", "))
}

/// A Rust parameter or return type as scripts see it (`&mut Signal` -> `Signal`,
/// `Res<f64>` -> `float`, `()` -> empty).
fn script_type(rust: &str) -> String {
    let t: String = rust.chars().filter(|c| !c.is_whitespace()).collect();
    let t = t
        .trim_start_matches("rhai::")
        .trim_start_matches("&mut")
        .trim_start_matches('&');
    let t = t
        .strip_prefix("Res<")
        .and_then(|x| x.strip_suffix('>'))
        .unwrap_or(t);
    let t = t
        .strip_prefix("Result<")
        .and_then(|x| x.split_once(','))
        .map_or(t, |(ok, _)| ok);
    match t {
        "()" => "",
        "f64" | "FLOAT" => "float",
        "i64" | "INT" => "int",
        "str" | "String" | "ImmutableString" => "string",
        "Dynamic" => "any",
        other => SCRIPT_TYPE_NAMES
            .iter()
            .find(|(rust, _)| *rust == other)
            .map_or(other, |(_, script)| script),
    }
    .to_string()
}

/// Rust type names in function signatures and the names scripts know them by.
const SCRIPT_TYPE_NAMES: [(&str, &str); 6] = [
    ("Map", "map"),
    ("Array", "array"),
    ("SceneRef", "Scene"),
    ("RunRef", "Run"),
    ("TrNewsRef", "TrNews"),
    ("LaminateRef", "Laminate"),
];

/// A definition file with the script's type names: `Res<T >` (a fallible function) becomes
/// `T`, and the Rust aliases of [`SCRIPT_TYPE_NAMES`] their script names.
fn definition_types(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut open = Vec::new(); // for each '<' seen: whether it opened a `Res<`
    let mut rest = text;
    while let Some(c) = rest.chars().next() {
        if c.is_ascii_alphabetic() || c == '_' {
            let end = rest
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(rest.len());
            let word = &rest[..end];
            rest = &rest[end..];
            if word == "Res" && rest.starts_with('<') {
                open.push(true);
                rest = &rest[1..];
                continue;
            }
            let script = SCRIPT_TYPE_NAMES.iter().find(|(rust, _)| *rust == word);
            out.push_str(script.map_or(word, |(_, s)| s));
            continue;
        }
        rest = &rest[c.len_utf8()..];
        match c {
            '-' if rest.starts_with('>') => {
                out.push_str("->");
                rest = &rest[1..];
                continue;
            }
            '<' => open.push(false),
            '>' if open.pop() == Some(true) => {
                out.truncate(out.trim_end().len());
                continue;
            }
            _ => {}
        }
        out.push(c);
    }
    out
}

/// The first paragraph of doc comment lines, without `///` markers, joined on one line.
fn first_paragraph(docs: &[&str]) -> String {
    docs.iter()
        .flat_map(|d| d.lines())
        .map(|l| l.trim().trim_start_matches("///").trim())
        .take_while(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn context(dir: &Path) -> HostContext {
        HostContext {
            out_dir: dir.to_path_buf(),
            root: None,
            data: RwLock::new(None),
            params: BTreeMap::new(),
            asked: RwLock::new(BTreeSet::new()),
            quiet: true,
            script: RwLock::new(String::new()),
            progress: RwLock::new(None),
        }
    }

    #[test]
    fn output_paths_stay_under_the_output_dir() {
        let dir = std::env::temp_dir().join(format!("trnews-resolve-{}", std::process::id()));
        let ctx = context(&dir);
        let ok = ctx.resolve_output("plots/a/b.png").expect("relative path");
        assert_eq!(ok, dir.join("plots/a/b.png"));
        for bad in ["../x.png", "a/../../x.png", "/tmp/x.png", ""] {
            let e = ctx.resolve_output(bad).expect_err(bad);
            assert!(e.contains(&format!("'{bad}'")) || bad.is_empty(), "{e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn param_values_parse_as_int_float_bool_or_string() {
        assert_eq!(parse_param_value("12").as_int(), Ok(12));
        assert_eq!(parse_param_value("1e-3").as_float(), Ok(1e-3));
        assert_eq!(parse_param_value("true").as_bool(), Ok(true));
        assert_eq!(
            parse_param_value("paper").into_string().as_deref(),
            Ok("paper")
        );
    }

    #[test]
    fn param_names_must_be_identifiers() {
        assert!(check_param_name("resolution_2").is_ok());
        for bad in ["", "2x", "a-b", "a b"] {
            assert!(check_param_name(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn rust_types_read_as_script_types() {
        assert_eq!(script_type("&mut Signal"), "Signal");
        assert_eq!(script_type("Res<()>"), "");
        assert_eq!(
            script_type("Result<String, Box<rhai::EvalAltResult>>"),
            "string"
        );
        assert_eq!(script_type("f64"), "float");
        assert_eq!(script_type("&str"), "string");
    }

    #[test]
    fn doc_paragraph_is_joined_on_one_line() {
        let docs = ["/// First line", "/// continues.", "///", "/// Details."];
        assert_eq!(first_paragraph(&docs), "First line continues.");
    }
}
