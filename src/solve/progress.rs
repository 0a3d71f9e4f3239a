//! Progress of time loops as a callback: the loops report the steps they have taken, and the
//! program that runs them decides how to show it (the script host draws terminal bars; a
//! library user who installs nothing sees nothing).

use std::sync::{Arc, RwLock};

/// Shows the progress of runs. Installed by the program that displays it ([`set_reporter`]).
pub trait ProgressReporter: Send + Sync {
    /// A run of `steps` steps begins. The returned callback receives the number of steps done
    /// (every [`REPORT_EVERY`] steps) and is dropped when the run ends, however it ends.
    fn start(&self, steps: usize) -> Box<dyn FnMut(usize) + Send>;
}

/// Steps between two progress reports.
pub const REPORT_EVERY: usize = 1024;

static REPORTER: RwLock<Option<Arc<dyn ProgressReporter>>> = RwLock::new(None);

/// Installs the reporter every later run with `progress` on reports to (`None`: runs are silent).
pub fn set_reporter(reporter: Option<Arc<dyn ProgressReporter>>) {
    if let Ok(mut r) = REPORTER.write() {
        *r = reporter;
    }
}

/// The progress callback of a run of `steps` steps: the installed reporter's when `show`,
/// otherwise one that does nothing.
pub(crate) fn start(show: bool, steps: usize) -> Box<dyn FnMut(usize) + Send> {
    let reporter = REPORTER.read().ok().and_then(|r| r.clone());
    match reporter {
        Some(r) if show => r.start(steps),
        _ => Box::new(|_| {}),
    }
}
