//! Terminal progress display of the script host: a spinner while a script runs and a bar per
//! time loop, all in one display so that parallel runs and script output do not tear it.

use crate::solve::progress::ProgressReporter;

/// The progress display all bars belong to.
pub(crate) fn group() -> &'static indicatif::MultiProgress {
    static GROUP: std::sync::OnceLock<indicatif::MultiProgress> = std::sync::OnceLock::new();
    GROUP.get_or_init(indicatif::MultiProgress::new)
}

/// Draws a bar on stderr for each run when stderr is a terminal.
pub(crate) struct TerminalBars;

/// A run's bar, cleared when the run ends (the callback holding it is dropped).
struct Bar(indicatif::ProgressBar);

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

impl ProgressReporter for TerminalBars {
    fn start(&self, steps: usize) -> Box<dyn FnMut(usize) + Send> {
        use std::io::IsTerminal;
        if !std::io::stderr().is_terminal() {
            return Box::new(|_| {});
        }
        let bar = group().add(indicatif::ProgressBar::new(steps as u64));
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} steps ({eta} left)",
        ) {
            bar.set_style(style);
        }
        let bar = Bar(bar);
        Box::new(move |done| bar.0.set_position(done as u64))
    }
}
