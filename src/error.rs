//! The library's error types: every variant names the field, value or place that caused it.

use std::path::{Path, PathBuf};

/// Everything that can go wrong while building or running a scene.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene or function argument is out of its admissible range.
    #[error("invalid {field} = {value}: {reason}")]
    InvalidInput {
        /// Dotted path of the offending field, e.g. `laminate.pairs`.
        field: String,
        /// The offending value as written.
        value: String,
        /// Why it was rejected.
        reason: String,
    },
    /// A material whose plane elasticity matrix is not positive definite, or whose constants are inadmissible.
    #[error("material '{name}' rejected: {reason}")]
    Material {
        /// Material name.
        name: String,
        /// Why it was rejected.
        reason: String,
    },
    /// Mesh construction or mesh-quality failure.
    #[error("mesh: {0}")]
    Mesh(String),
    /// The requested explicit time step exceeds the stability limit.
    #[error("time step dt_s = {dt_s:.4e} s exceeds the explicit stability limit dt_crit = {dt_crit_s:.4e} s (dt/dt_crit = {ratio:.3}); lower dt or force the run")]
    StepTooLarge {
        /// Requested step.
        dt_s: f64,
        /// Estimated critical step.
        dt_crit_s: f64,
        /// dt / dt_crit.
        ratio: f64,
    },
    /// A run blew up; it was stopped before writing non-finite results.
    #[error("run unstable at step {step} (t = {time_s:.4e} s): {reason}; dt = {dt_s:.4e} s, dt_crit = {dt_crit_s:.4e} s")]
    Unstable {
        /// Step at which the blow-up was detected.
        step: usize,
        /// Time of that step.
        time_s: f64,
        /// What was detected.
        reason: String,
        /// The run's step.
        dt_s: f64,
        /// The estimated critical step.
        dt_crit_s: f64,
    },
    /// The contact algorithm failed (for example an augmented-Lagrangian penalty above its stable bound).
    #[error("contact: {0}")]
    Contact(String),
    /// Work stopped by the time limit or Ctrl-C (see [`crate::budget`]).
    #[error("stopped: {0}")]
    Stopped(crate::budget::Stop),
    /// The estimated memory of a request exceeds the limit (see [`crate::scene::memory_limit`]).
    #[error("{field} = {value} would need about {estimate}, above the limit of {limit} (set with --max-memory); {hint}")]
    TooLarge {
        /// The field the user wrote.
        field: String,
        /// Its value.
        value: String,
        /// The estimate, formatted (e.g. "12.3 GiB of memory", with the heap in use if metered).
        estimate: String,
        /// The limit, formatted.
        limit: String,
        /// What to change.
        hint: String,
    },
    /// An error already worded in the user's field names (e.g. a TR-NEWS spec's).
    #[error("{0}")]
    Named(String),
    /// Signal processing error.
    #[error(transparent)]
    Signal(#[from] crate::signal::SignalError),
    /// Writing an output file failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl From<crate::budget::Stop> for Error {
    fn from(s: crate::budget::Stop) -> Self {
        Error::Stopped(s)
    }
}

/// Library result type.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for [`Error::InvalidInput`].
    pub fn invalid(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Error::InvalidInput {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}

/// Checks that `value` is finite and strictly positive, naming `field` otherwise.
pub fn require_positive(field: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(field, value, "must be finite and > 0"))
    }
}

/// Checks that `value` lies in the physical range `[lo, hi]` (`unit` after the bounds; `why`
/// the range), naming `field`, the value and the range otherwise. Ranges bound finite values
/// that no experiment has (an angle of 1e300 degrees, a modulus of 1e30 Pa), so that they are
/// refused as input rather than carried into overflowing or meaningless arithmetic.
pub fn require_within(
    field: &str,
    value: f64,
    lo: f64,
    hi: f64,
    unit: &str,
    why: &str,
) -> Result<f64> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(Error::invalid(
            field,
            value,
            format!("must be within [{lo:e}, {hi:e}] {unit} ({why})"),
        ))
    }
}

/// Checks that `value` is finite, naming `field` otherwise.
pub fn require_finite(field: &str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(field, value, "must be finite"))
    }
}

/// Failure to write an output file; every variant names the path and the cause.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An operating-system call failed (`op` says which, e.g. "create directory").
    #[error("cannot {op} {path}: {source}", path = .path.display())]
    Io {
        /// What was being done.
        op: &'static str,
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The data handed to a writer is inconsistent (lengths, shapes, indices, values).
    #[error("cannot write {path}: {message}", path = .path.display())]
    Data {
        /// The target file.
        path: PathBuf,
        /// What is wrong with the data.
        message: String,
    },
    /// The path leads out of the active output root (given outside it, or through a symlink).
    #[error("output path {path} leads outside the output directory {root} (through a symlink, or not under it); refused", path = .path.display(), root = .root.display())]
    Outside {
        /// The path as given.
        path: PathBuf,
        /// The output root.
        root: PathBuf,
    },
    /// Serialising to JSON failed.
    #[error("cannot write {path}: JSON serialisation failed: {source}", path = .path.display())]
    Json {
        /// The target file.
        path: PathBuf,
        /// The underlying error.
        source: serde_json::Error,
    },
}

impl OutputError {
    /// Shorthand for an [`OutputError::Data`] about `path`.
    pub(crate) fn data(path: &Path, message: impl Into<String>) -> Self {
        OutputError::Data {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }

    /// Shorthand for an [`OutputError::Io`] about `path`.
    pub(crate) fn io(op: &'static str, path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            op,
            path: path.to_path_buf(),
            source,
        }
    }
}
