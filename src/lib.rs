//! trnews: 2D finite element simulation of elastic waves in a layered CFRP laminate with a
//! contacting crack, and the TR-NEWS signal processing of the report
//! "Simulation of defects in CFRP and delayed TR-NEWS analysis" (Mech 320/17).
//!
//! Data flows one way: [`laminate`] -> [`mesh`] -> [`fem`] -> [`solve`] -> [`signal`] /
//! [`trnews`] -> `plot` / [`io`]. [`scene`] describes a whole experiment setup.
//!
//! Cargo features, all on by default, add the edges around the numerical core:
//! `plot` (figures: `plot`, `figures`), `io` (CSV, VTU/PVD, data inputs: `input`),
//! `script` (the Rhai API: `script`) and `cli` (the `trnews-script` binary, `slurm`).
//! `cargo build --no-default-features` builds the numerics alone, writing NPY and JSON.

// Checks are written `!(x > 0.0)` on purpose: unlike `x <= 0.0` they also refuse NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accuracy;
pub mod attenuation;
pub mod budget;
pub mod contact;
pub mod error;
pub mod exact;
pub mod experiment;
pub mod fem;
#[cfg(feature = "plot")]
pub mod figures;
pub mod format;
pub(crate) mod guard;
#[cfg(feature = "io")]
pub mod input;
pub mod io;
pub mod lab;
pub mod laminate;
pub mod material;
pub mod mesh;
pub mod parallel;
#[cfg(feature = "plot")]
pub mod plot;
pub mod scene;
#[cfg(feature = "script")]
pub mod script;
pub mod sem;
pub mod signal;
#[cfg(feature = "cli")]
pub mod slurm;
pub mod solve;
pub mod study;
pub mod sweep;
pub mod transducer;
pub mod trnews;

pub use error::{Error, Result};
