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

pub use crate::error::OutputError;
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
