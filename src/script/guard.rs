//! The host's last line of defence: the script position last reached (recorded by a
//! statement-level debugger hook, so a panic escaping a native function is reported at
//! `file:line:col`), and a panic hook that records where a panic happened without printing it
//! while a script runs (the host turns it into a one-line error instead).

use rhai::Position;
use std::cell::Cell;
use std::sync::{Mutex, Once};

thread_local! {
    static LAST: Cell<Position> = const { Cell::new(Position::NONE) };
    /// Guarded script runs on this thread (a panic here is then recorded, not printed).
    static GUARDED: Cell<usize> = const { Cell::new(0) };
}
static LOCATION: Mutex<Option<String>> = Mutex::new(None);

/// Records `pos` as the script position last reached on this thread.
pub fn note(pos: Position) {
    if !pos.is_none() {
        LAST.with(|l| l.set(pos));
    }
}

/// The script position last reached on this thread.
pub fn last_position() -> Option<Position> {
    let p = LAST.with(Cell::get);
    (!p.is_none()).then_some(p)
}

/// Where the last recorded panic happened (Rust source file:line).
pub fn panic_location() -> Option<String> {
    LOCATION.lock().ok().and_then(|l| l.clone())
}

/// Clears the position and panic location before a run, and installs the panic hook once.
pub fn reset() {
    LAST.with(|l| l.set(Position::NONE));
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
                        .map(|l| format!("{}:{}", l.file(), l.line()));
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
