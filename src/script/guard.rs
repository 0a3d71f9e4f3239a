//! The host's last line of defence: a panic hook that records where a panic happened without
//! printing it while a script runs (the host turns it into a one-line error instead).

use std::cell::Cell;
use std::sync::{Mutex, Once};

thread_local! {
    /// Guarded script runs on this thread (a panic here is then recorded, not printed).
    static GUARDED: Cell<usize> = const { Cell::new(0) };
}
static LOCATION: Mutex<Option<String>> = Mutex::new(None);

/// Where the last recorded panic happened (Rust source file:line).
pub fn panic_location() -> Option<String> {
    LOCATION.lock().ok().and_then(|l| l.clone())
}

/// Clears the panic location before a run, and installs the panic hook once.
pub fn reset() {
    if let Ok(mut l) = LOCATION.lock() {
        *l = None;
    }
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if GUARDED.with(Cell::get) > 0 {
                if let Ok(mut l) = LOCATION.lock() {
                    *l = info
                        .location()
                        .map(|l| format!("{}:{}:{}", l.file(), l.line(), l.column()));
                }
            } else {
                previous(info);
            }
        }));
    });
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
