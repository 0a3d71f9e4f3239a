//! Process-wide stop conditions for long native work: a wall-clock deadline and a cancel flag
//! (set by Ctrl-C in `trnews-script`). Solvers and long loops call [`check`] now and then
//! (cheap: one atomic load, and one clock read when a deadline is set) and stop with
//! [`crate::Error::Stopped`], so a script's time limit and Ctrl-C also stop a native run
//! cleanly, between steps, with its outputs either complete or not written.
//!
//! Memory and work are metered from the process's counting allocator when the host installs
//! one ([`install_heap_meter`]; `trnews-script` does): the script host then stops a script
//! whose live heap (script values and native buffers together) exceeds the memory limit, and
//! charges native work to the operation budget at one operation per KiB allocated
//! ([`check_script`]). Requests that allocate much at once (meshes, runs, signals) are
//! estimated before they allocate ([`check_memory`]).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

static CANCELLED: AtomicBool = AtomicBool::new(false);

// The deadline and the memory limit belong to the thread that runs a script, so that hosts on
// different threads do not share them; work it hands to other threads carries them there
// (`Limits`, `crate::parallel`).
thread_local! {
    /// Deadline as nanoseconds after [`epoch`], plus one; 0 means no deadline.
    static DEADLINE_NS: AtomicU64 = const { AtomicU64::new(0) };
    /// The time limit as set, in milliseconds (for messages).
    static LIMIT_MS: AtomicU64 = const { AtomicU64::new(0) };
    static MEMORY_LIMIT: AtomicU64 = const { AtomicU64::new(DEFAULT_MEMORY_LIMIT) };
    /// Bytes the process had allocated when the budget started (see [`start`]).
    static ALLOCATED_AT_START: AtomicU64 = const { AtomicU64::new(0) };
}

/// Heap bytes as counted by the process's allocator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeapUse {
    /// Bytes allocated and not yet freed.
    pub live: u64,
    /// Bytes allocated since the process started, freed or not.
    pub allocated: u64,
}

static HEAP_METER: OnceLock<fn() -> HeapUse> = OnceLock::new();

/// Installs the reading of the process's counting allocator (once; later calls are ignored).
/// Without a meter, only the estimates of [`check_memory`] limit memory and the operation
/// budget counts script operations alone.
pub fn install_heap_meter(meter: fn() -> HeapUse) {
    let _ = HEAP_METER.set(meter);
}

/// The heap now, if a meter is installed.
pub fn heap_use() -> Option<HeapUse> {
    HEAP_METER.get().map(|meter| meter())
}

/// The check between two script operations: [`check`], then the live heap against the memory
/// limit, then `script_operations` plus native work (one per KiB allocated since [`start`])
/// against `max_operations`. Native work is metered by allocation because it is the one
/// measure every native call shares: the signal functions allocate their outputs and FFT
/// buffers in proportion to the samples they process; time stepping allocates nothing per
/// step and is bounded by its own estimates, the time limit and Ctrl-C.
pub fn check_script(script_operations: u64, max_operations: u64) -> Result<(), Stop> {
    check()?;
    let Some(heap) = heap_use() else {
        return within_operations(script_operations, 0, max_operations);
    };
    let limit = memory_limit();
    if heap.live > limit {
        return Err(Stop::MemoryLimit {
            in_use: heap.live,
            limit,
        });
    }
    let start = ALLOCATED_AT_START.with(|a| a.load(Ordering::Relaxed));
    let native_kib = heap.allocated.saturating_sub(start) >> 10;
    within_operations(script_operations, native_kib, max_operations)
}

fn within_operations(script: u64, native_kib: u64, limit: u64) -> Result<(), Stop> {
    if script.saturating_add(native_kib) > limit {
        Err(Stop::OperationLimit {
            limit,
            script,
            native_kib,
        })
    } else {
        Ok(())
    }
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
    /// The operation budget was spent: script operations plus native work (KiB allocated).
    OperationLimit {
        /// The budget (`--max-operations`).
        limit: u64,
        /// Script operations so far.
        script: u64,
        /// Native work so far, in KiB allocated.
        native_kib: u64,
    },
    /// The live heap (bytes) exceeds the memory limit (bytes).
    MemoryLimit {
        /// Bytes in use.
        in_use: u64,
        /// The limit.
        limit: u64,
    },
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::Interrupted => write!(f, "interrupted (Ctrl-C)"),
            Stop::TimeLimit(s) => {
                write!(f, "time limit {s} s reached (raise it with --time-limit)")
            }
            Stop::OperationLimit {
                limit,
                script,
                native_kib,
            } => write!(
                f,
                "operation limit {limit} exceeded: {script} script operations + {native_kib} KiB \
                 allocated (work counts one operation per KiB; endless loop? raise it with \
                 --max-operations)"
            ),
            Stop::MemoryLimit { in_use, limit } => write!(
                f,
                "memory in use {} is above the limit of {} (script values and native buffers \
                 together; raise it with --max-memory)",
                format_bytes(*in_use as f64),
                format_bytes(*limit as f64)
            ),
        }
    }
}

/// Starts a budget: clears the cancel flag, sets the deadline `limit` from now (none if
/// `None`) and starts counting native work.
pub fn start(limit: Option<Duration>) {
    CANCELLED.store(false, Ordering::SeqCst);
    let allocated = heap_use().map_or(0, |h| h.allocated);
    ALLOCATED_AT_START.with(|a| a.store(allocated, Ordering::SeqCst));
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

/// The limits of the current thread: its deadline, memory limit and the start of its native
/// work. Carried onto the threads that do its work in parallel ([`Limits::within`]), so that a
/// time limit or a memory limit set for a script also holds on rayon's workers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    deadline_ns: u64,
    limit_ms: u64,
    memory_limit: u64,
    allocated_at_start: u64,
}

impl Limits {
    /// The limits set on this thread.
    pub fn current() -> Limits {
        Limits {
            deadline_ns: DEADLINE_NS.with(|l| l.load(Ordering::Relaxed)),
            limit_ms: LIMIT_MS.with(|l| l.load(Ordering::Relaxed)),
            memory_limit: memory_limit(),
            allocated_at_start: ALLOCATED_AT_START.with(|a| a.load(Ordering::Relaxed)),
        }
    }

    /// Runs `f` with these limits on the current thread; the thread's own are restored
    /// afterwards, also on panic.
    pub fn within<T>(self, f: impl FnOnce() -> T) -> T {
        struct Restore(Limits);
        impl Drop for Restore {
            fn drop(&mut self) {
                self.0.set();
            }
        }
        let _restore = Restore(Limits::current());
        self.set();
        f()
    }

    fn set(self) {
        DEADLINE_NS.with(|l| l.store(self.deadline_ns, Ordering::SeqCst));
        LIMIT_MS.with(|l| l.store(self.limit_ms, Ordering::SeqCst));
        MEMORY_LIMIT.with(|l| l.store(self.memory_limit, Ordering::SeqCst));
        ALLOCATED_AT_START.with(|a| a.store(self.allocated_at_start, Ordering::SeqCst));
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

/// Default memory limit: 8 GiB (the live heap of a script run, and every request's estimate
/// on top of it).
pub const DEFAULT_MEMORY_LIMIT: u64 = 8 << 30;

/// Sets the memory limit (bytes, on this thread) of [`check_memory`] and [`check_script`].
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
/// cannot overflow), added to the live heap when a meter is installed, exceeds the limit: the
/// error names `field` with `value` and says `hint`.
pub fn check_memory(
    field: &str,
    value: impl std::fmt::Display,
    bytes: f64,
    hint: &str,
) -> crate::Result<()> {
    let limit = memory_limit();
    let in_use = heap_use().map_or(0, |h| h.live) as f64;
    if bytes.is_finite() && bytes + in_use <= limit as f64 {
        return Ok(());
    }
    let estimate = if in_use > 0.0 {
        format!(
            "{} of memory on top of {} in use",
            format_bytes(bytes),
            format_bytes(in_use)
        )
    } else {
        format!("{} of memory", format_bytes(bytes))
    };
    Err(crate::Error::TooLarge {
        field: field.to_string(),
        value: value.to_string(),
        estimate,
        limit: format_bytes(limit as f64),
        hint: hint.to_string(),
    })
}
