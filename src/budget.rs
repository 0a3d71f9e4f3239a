//! Process-wide stop conditions for long native work: a wall-clock deadline and a cancel flag
//! (set by Ctrl-C in `trnews-script`). Solvers and long loops call [`check`] now and then
//! (cheap: one atomic load, and one clock read when a deadline is set) and stop with
//! [`crate::Error::Stopped`], so a script's time limit and Ctrl-C also stop a native run
//! cleanly, between steps, with its outputs either complete or not written.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

static CANCELLED: AtomicBool = AtomicBool::new(false);

// The deadline and the memory limit belong to the thread that runs a script (the solvers'
// step loops run on it too), so that hosts on different threads do not share them.
thread_local! {
    /// Deadline as nanoseconds after [`epoch`], plus one; 0 means no deadline.
    static DEADLINE_NS: AtomicU64 = const { AtomicU64::new(0) };
    /// The time limit as set, in milliseconds (for messages).
    static LIMIT_MS: AtomicU64 = const { AtomicU64::new(0) };
    static MEMORY_LIMIT: AtomicU64 = const { AtomicU64::new(DEFAULT_MEMORY_LIMIT) };
}

fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

/// Why work was stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stop {
    /// Ctrl-C (or [`cancel`]).
    Interrupted,
    /// The wall-clock limit (seconds) was reached.
    TimeLimit(f64),
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Interrupted => write!(f, "interrupted (Ctrl-C)"),
            Stop::TimeLimit(s) => {
                write!(f, "time limit {s} s reached (raise it with --time-limit)")
            }
        }
    }
}

/// Starts a budget: clears the cancel flag and sets the deadline `limit` from now (none if `None`).
pub fn start(limit: Option<Duration>) {
    CANCELLED.store(false, Ordering::SeqCst);
    match limit {
        Some(d) => {
            let at = (Instant::now() + d).saturating_duration_since(epoch());
            let ns = u64::try_from(at.as_nanos()).unwrap_or(u64::MAX - 1);
            LIMIT_MS
                .with(|l| l.store(d.as_millis().min(u64::MAX as u128) as u64, Ordering::SeqCst));
            DEADLINE_NS.with(|l| l.store(ns.saturating_add(1), Ordering::SeqCst));
        }
        None => DEADLINE_NS.with(|l| l.store(0, Ordering::SeqCst)),
    }
}

/// Removes the deadline (the cancel flag stays as it is).
pub fn clear() {
    DEADLINE_NS.with(|l| l.store(0, Ordering::SeqCst));
}

/// Asks running work to stop at its next [`check`] (Ctrl-C handler).
pub fn cancel() {
    CANCELLED.store(true, Ordering::SeqCst);
}

/// True once [`cancel`] was called (until the next [`start`]).
pub fn cancelled() -> bool {
    CANCELLED.load(Ordering::Relaxed)
}

/// `Err` when work must stop: cancelled, or past the deadline.
pub fn check() -> Result<(), Stop> {
    if CANCELLED.load(Ordering::Relaxed) {
        return Err(Stop::Interrupted);
    }
    let d = DEADLINE_NS.with(|l| l.load(Ordering::Relaxed));
    if d != 0 && epoch().elapsed().as_nanos() as u64 >= d - 1 {
        return Err(Stop::TimeLimit(
            LIMIT_MS.with(|l| l.load(Ordering::Relaxed)) as f64 / 1000.0,
        ));
    }
    Ok(())
}

/// Default memory limit of one request (scene, run, signal): 8 GiB.
pub const DEFAULT_MEMORY_LIMIT: u64 = 8 << 30;

/// Sets the memory limit (bytes, on this thread) that [`check_memory`] compares estimates against.
pub fn set_memory_limit(bytes: u64) {
    MEMORY_LIMIT.with(|l| l.store(bytes.max(1), Ordering::SeqCst));
}

/// The memory limit in bytes (on this thread).
pub fn memory_limit() -> u64 {
    MEMORY_LIMIT.with(|l| l.load(Ordering::Relaxed))
}

/// Bytes as `12.3 GiB` (binary prefixes; enormous estimates in scientific notation).
pub fn format_bytes(bytes: f64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    if !bytes.is_finite() || bytes >= 1024f64.powi(5) {
        return format!("{bytes:.2e} B");
    }
    let mut v = bytes;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.3} {}", UNITS[u])
}

/// Refuses a request whose estimated memory `bytes` (computed in floating point, so that it
/// cannot overflow) exceeds the limit: the error names `field` with `value` and says `hint`.
pub fn check_memory(
    field: &str,
    value: impl std::fmt::Display,
    bytes: f64,
    hint: &str,
) -> crate::Result<()> {
    let limit = memory_limit();
    if bytes.is_finite() && bytes <= limit as f64 {
        return Ok(());
    }
    Err(crate::Error::TooLarge {
        field: field.to_string(),
        value: value.to_string(),
        estimate: format_bytes(bytes),
        limit: format_bytes(limit as f64),
        hint: hint.to_string(),
    })
}
