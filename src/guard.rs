//! The script host's last line of defence: a panic hook that records where a panic happened
//! without printing it while a script runs (the host turns it into a one-line error instead),
//! on the script's thread and on the workers its parallel loops use ([`crate::parallel`]).

use std::cell::{Cell, RefCell};

thread_local! {
    /// Guarded script runs on this thread (a panic here is then recorded, not printed).
    static GUARDED: Cell<usize> = const { Cell::new(0) };
    /// Where the last panic on this thread happened, while guarded (hosts on other threads
    /// keep their own).
    static LOCATION: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Where the last recorded panic on this thread happened (Rust source file:line:column).
#[cfg(feature = "script")]
pub fn panic_location() -> Option<String> {
    LOCATION.with(|l| l.borrow().clone())
}

/// Clears the panic location before a run, and installs the panic hook once.
#[cfg(feature = "script")]
pub fn reset() {
    LOCATION.with(|l| *l.borrow_mut() = None);
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if GUARDED.with(Cell::get) > 0 {
                let at = info
                    .location()
                    .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()));
                LOCATION.with(|l| *l.borrow_mut() = at);
            } else {
                previous(info);
            }
        }));
    });
}

/// True while a guarded run is on this thread.
pub fn is_guarded() -> bool {
    GUARDED.with(Cell::get) > 0
}

/// Runs `f` guarded on a worker thread of a guarded run: a panic in `f` is recorded, not
/// printed, and continues on its way to the run's thread (rayon carries it there) with its
/// location in the message, since the location is recorded on the thread that panicked.
pub fn on_worker<T>(f: impl FnOnce() -> T) -> T {
    let previous = LOCATION.with(|l| l.borrow_mut().take());
    let guarded = Guarded::start();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    drop(guarded);
    let at = LOCATION.with(|l| std::mem::replace(&mut *l.borrow_mut(), previous));
    result.unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        let at = at.map(|l| format!(" at {l}")).unwrap_or_default();
        std::panic::resume_unwind(Box::new(format!("{what}{at}")))
    })
}

/// Marks a guarded run for its lifetime.
pub struct Guarded;

impl Guarded {
    /// Starts a guarded run.
    pub fn start() -> Guarded {
        GUARDED.with(|g| g.set(g.get() + 1));
        Guarded
    }
}

impl Drop for Guarded {
    fn drop(&mut self) {
        GUARDED.with(|g| g.set(g.get().saturating_sub(1)));
    }
}
