//! Figures: line plots, stacked panels, heatmaps and mesh field snapshots, as PNG or SVG.
//!
//! The backend is picked from the file extension (`.png` or `.svg`). Figures are rendered
//! to a temporary sibling file and renamed over the target, so a failed render never
//! leaves a partial figure. Text uses an embedded DejaVu Sans, so rendering needs no
//! system fonts. Bad data (empty or non-finite series, non-positive values on a log
//! axis, inconsistent shapes) is reported as a [`PlotError`], never a panic.

mod check;
mod colour;
mod field;
mod heatmap;
mod line;
mod raster;
mod render;
mod stacked;
#[cfg(test)]
mod tests;

pub use field::field_plot;
pub use heatmap::heatmap;
pub use line::line_plot;
pub use stacked::stacked_plot;

use crate::io::OutputError;
use check::*;
use colour::*;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use raster::*;
use render::*;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One curve: `x` and `y` of equal length, shown in the legend as `label`.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text (also used to name the series in errors).
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
}

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis; all values on it must be positive.
    Log10,
}

/// Title, axis labels (with units) and scales of a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Axes {
    /// Figure title.
    pub title: String,
    /// Label of the horizontal axis.
    pub x_label: String,
    /// Label of the vertical axis.
    pub y_label: String,
    /// Scale of the horizontal axis.
    pub x_scale: Scale,
    /// Scale of the vertical axis.
    pub y_scale: Scale,
}

/// One panel of a [`stacked_plot`].
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Panel caption, e.g. "Receiver 3".
    pub title: String,
    /// Curves drawn in this panel.
    pub series: Vec<Series>,
}

/// A polyline drawn over a [`field_plot`] (layer interface, crack faces, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct Overlay {
    /// Vertices in mesh coordinates.
    pub points: Vec<(f64, f64)>,
    /// Line colour.
    pub color: (u8, u8, u8),
    /// Line width in pixels.
    pub width: u32,
}

/// Failure to make a figure; every variant names the target path.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The extension selects no backend.
    #[error("cannot plot {path}: unsupported figure extension {ext:?} (use .png or .svg)", path = .path.display())]
    UnknownExtension {
        /// The target file.
        path: PathBuf,
        /// The extension found (empty if none).
        ext: String,
    },
    /// A series, panel or figure has nothing to draw.
    #[error("cannot plot {path}: {what} is empty", path = .path.display())]
    Empty {
        /// The target file.
        path: PathBuf,
        /// What is empty, e.g. `series "u_y"`.
        what: String,
    },
    /// A NaN or infinite value.
    #[error("cannot plot {path}: {what} has a non-finite {axis} value at index {index}", path = .path.display())]
    NonFinite {
        /// The target file.
        path: PathBuf,
        /// The offending series or array.
        what: String,
        /// "x", "y" or "value".
        axis: &'static str,
        /// Position of the first bad value.
        index: usize,
    },
    /// A value <= 0 on a logarithmic axis.
    #[error("cannot plot {path}: {what} has {axis} = {value} at index {index}, not allowed on a log axis", path = .path.display())]
    NonPositiveLog {
        /// The target file.
        path: PathBuf,
        /// The offending series or array.
        what: String,
        /// "x" or "y".
        axis: &'static str,
        /// The bad value.
        value: f64,
        /// Position of the first bad value.
        index: usize,
    },
    /// Inconsistent lengths, indices or options.
    #[error("cannot plot {path}: {message}", path = .path.display())]
    Invalid {
        /// The target file.
        path: PathBuf,
        /// What is inconsistent.
        message: String,
    },
    /// The plotting backend failed (including writing the image file).
    #[error("cannot draw {path}: {message}", path = .path.display())]
    Draw {
        /// The target file.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// The embedded font could not be registered with plotters.
    #[error("cannot plot {path}: the embedded DejaVu Sans font could not be registered", path = .path.display())]
    Font {
        /// The target file.
        path: PathBuf,
    },
    /// Creating the directory or moving the finished file into place failed.
    #[error(transparent)]
    Output(#[from] OutputError),
}
