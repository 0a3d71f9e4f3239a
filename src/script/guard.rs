//! The host's last line of defence: a panic hook that records where a panic happened without
//! printing it while a script runs (the host turns it into a one-line error instead).

use std::cell::{Cell, RefCell};
use std::sync::Once;

thread_local! {
    /// Guarded script runs on this thread (a panic here is then recorded, not printed).
    static GUARDED: Cell<usize> = const { Cell::new(0) };
    /// Where the last panic on this thread happened, while guarded (hosts on other threads
    /// keep their own).
    static LOCATION: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Where the last recorded panic on this thread happened (Rust source file:line:column).
pub fn panic_location() -> Option<String> {
    LOCATION.with(|l| l.borrow().clone())
}

/// Clears the panic location before a run, and installs the panic hook once.
pub fn reset() {
    LOCATION.with(|l| *l.borrow_mut() = None);
    static HOOK: Once = Once::new();
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
