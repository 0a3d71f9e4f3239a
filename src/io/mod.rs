//! Data-file outputs, all written atomically: NPY and JSON in the numerical core; CSV and
//! VTU/PVD (ParaView) with the `io` feature.
//!
//! Every writer builds the file contents in memory and hands them to [`write_atomic`],
//! which writes a temporary sibling file and renames it over the target, so a reader
//! never sees a half-written file and an interrupted run never leaves a truncated one.

mod atomic;
#[cfg(feature = "io")]
pub mod csv;
pub mod json;
pub mod npy;
#[cfg(feature = "io")]
pub mod pvd;
mod root;
#[cfg(test)]
pub(crate) mod tests;
#[cfg(feature = "io")]
pub mod vtu;

pub use atomic::{ensure_parent_dir, read_existing, write_atomic};
#[cfg(feature = "io")]
pub use csv::{fmt_f64, write_csv, write_csv_rows};
pub use json::write_json;
pub use npy::write_npy;
#[cfg(feature = "io")]
pub use pvd::write_pvd;
pub use root::{active_root, without_root, OutputRoot};
#[cfg(feature = "io")]
pub use vtu::write_vtu;

use std::path::{Path, PathBuf};

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
