//! Figures: line plots, stacked panels, heatmaps and mesh field snapshots, as PNG or SVG.
//!
//! The backend is picked from the file extension (`.png` or `.svg`). Figures are rendered
//! to a temporary sibling file and renamed over the target, so a failed render never
//! leaves a partial figure. Text uses an embedded DejaVu Sans, so rendering needs no
//! system fonts. Bad data (empty or non-finite series, non-positive values on a log
//! axis, inconsistent shapes) is reported as a [`PlotError`], never a panic.

use crate::io::OutputError;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
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

/// Draws `series` as lines (and optional point markers) on one pair of axes.
/// Size 1000 x 700; legend shown when there is more than one series.
pub fn line_plot(
    path: &Path,
    axes: &Axes,
    series: &[Series],
    markers: bool,
) -> Result<(), PlotError> {
    check_series_set(path, series, "the series list", axes.x_scale, axes.y_scale)?;
    render(
        path,
        &LineFig {
            axes,
            series,
            markers,
        },
    )
}

/// Stacked panels sharing the x axis, like the report's Figs 15/16/18 (one panel per receiver).
/// Linear axes; size 1000 x (220 per panel + title and axis bands).
pub fn stacked_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    panels: &[Panel],
) -> Result<(), PlotError> {
    if panels.is_empty() {
        return Err(empty(path, "the panel list"));
    }
    for p in panels {
        let what = format!("panel {:?}", p.title);
        check_series_set(path, &p.series, &what, Scale::Linear, Scale::Linear)?;
    }
    render(
        path,
        &StackedFig {
            title,
            x_label,
            y_label,
            panels,
        },
    )
}

/// Heatmap of values on a rectilinear grid (values[iy][ix]), with a colour bar labelled colorbar_label.
/// `x` and `y` are cell centres, strictly increasing; cell edges lie half-way between them.
pub fn heatmap(
    path: &Path,
    axes: &Axes,
    x: &[f64],
    y: &[f64],
    values: &[Vec<f64>],
    colorbar_label: &str,
) -> Result<(), PlotError> {
    let fig = HeatFig::new(path, axes, x, y, values, colorbar_label)?;
    render(path, &fig)
}

/// A scalar field on a triangle mesh (like the report's Fig. 19: u_y displacement), rasterised onto an image
/// grid by barycentric interpolation, diverging colour map symmetric about 0, with overlay polylines (layer interfaces thin grey, crack thick black)
///
/// Axes must be linear; x and y are drawn to the same scale (the figure height follows
/// the mesh's aspect ratio, within 350..900 px). Pixels outside the mesh stay white.
pub fn field_plot(
    path: &Path,
    axes: &Axes,
    nodes: &[[f64; 2]],
    triangles: &[[usize; 3]],
    values: &[f64],
    overlays: &[Overlay],
    colorbar_label: &str,
) -> Result<(), PlotError> {
    let fig = FieldFig::new(
        path,
        axes,
        nodes,
        triangles,
        values,
        overlays,
        colorbar_label,
    )?;
    render(path, &fig)
}

// ---------------------------------------------------------------- layout and style

/// Font family name under which the embedded font is registered.
const FONT: &str = "sans-serif";
/// Title, axis-label, tick-label and legend font sizes (px).
const TITLE_PX: u32 = 24;
const LABEL_PX: u32 = 18;
const TICK_PX: u32 = 15;
const LEGEND_PX: u32 = 16;
/// Default figure size (px).
const FIG_W: u32 = 1000;
const FIG_H: u32 = 700;
/// Height of one stacked panel (px).
const PANEL_H: u32 = 220;
/// Chart margin, x-label band and y-label band (px).
const MARGIN: u32 = 15;
const X_AREA: u32 = 60;
const Y_AREA: u32 = 110;
/// Width of the colour-bar strip to the right of heatmaps and fields (px).
const CBAR_W: u32 = 150;
/// Number of colour levels in colour bars and mesh-field rasters.
const LEVELS: usize = 128;

/// Line colours (matplotlib's tab10), cycled.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Sequential colour map (viridis), nine equally spaced stops.
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// Diverging colour map (blue - white - red, ColorBrewer RdBu reversed), nine stops.
const DIVERGING: [(u8, u8, u8); 9] = [
    (5, 48, 97),
    (33, 102, 172),
    (67, 147, 195),
    (146, 197, 222),
    (247, 247, 247),
    (244, 165, 130),
    (214, 96, 77),
    (178, 24, 43),
    (103, 0, 31),
];

/// Colour at `t` in [0, 1] of a map given by equally spaced stops (linear interpolation).
fn colormap(stops: &[(u8, u8, u8); 9], t: f64) -> RGBColor {
    let s = t.clamp(0.0, 1.0) * 8.0;
    let k = (s.floor() as usize).min(7);
    let f = s - k as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (stops[k], stops[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Colour of quantised level `k` of `LEVELS`.
fn level_color(stops: &[(u8, u8, u8); 9], k: usize) -> RGBColor {
    colormap(stops, k as f64 / (LEVELS - 1) as f64)
}

/// Quantises `t` in [0, 1] to a colour level.
fn level_of(t: f64) -> usize {
    (t.clamp(0.0, 1.0) * (LEVELS - 1) as f64).round() as usize
}

/// Tick label: four significant digits, scientific notation for very small or large values.
fn tick_label(v: &f64) -> String {
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(*v);
    let a = rounded.abs();
    if rounded == 0.0 {
        "0".to_string()
    } else if (1e-3..1e4).contains(&a) {
        format!("{rounded}")
    } else {
        format!("{rounded:e}")
    }
}

/// A tick formatter for an axis over `range`: on a linear axis, values within
/// 1e-9 of the span from zero (rounding noise such as -5.551e-17) print as "0".
fn snapped_labels(range: Range<f64>, scale: Scale) -> impl Fn(&f64) -> String {
    let tol = match scale {
        Scale::Linear => 1e-9 * (range.end - range.start).abs(),
        Scale::Log10 => 0.0,
    };
    move |v: &f64| {
        if v.abs() < tol {
            "0".to_string()
        } else {
            tick_label(v)
        }
    }
}

/// Converts any displayable backend error to a message.
fn draw_err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

// ---------------------------------------------------------------- validation

/// An [`PlotError::Empty`] about `what`.
fn empty(path: &Path, what: &str) -> PlotError {
    PlotError::Empty {
        path: path.to_path_buf(),
        what: what.to_string(),
    }
}

/// An [`PlotError::Invalid`] with `message`.
fn invalid(path: &Path, message: String) -> PlotError {
    PlotError::Invalid {
        path: path.to_path_buf(),
        message,
    }
}

/// Checks that `values` are finite, and positive when on a log axis.
fn check_values(
    path: &Path,
    what: &str,
    axis: &'static str,
    values: &[f64],
    scale: Scale,
) -> Result<(), PlotError> {
    if let Some(index) = values.iter().position(|v| !v.is_finite()) {
        return Err(PlotError::NonFinite {
            path: path.to_path_buf(),
            what: what.to_string(),
            axis,
            index,
        });
    }
    if scale == Scale::Log10 {
        if let Some(index) = values.iter().position(|&v| v <= 0.0) {
            return Err(PlotError::NonPositiveLog {
                path: path.to_path_buf(),
                what: what.to_string(),
                axis,
                value: values[index],
                index,
            });
        }
    }
    // Ranges that overflow once padded, or log ranges of hundreds of decades, make the axis
    // code spin or assert: refuse them with the values that cause it.
    let (lo, hi) = min_max(values.iter().copied());
    if !values.is_empty() && (lo.abs() > MAX_AXIS_VALUE || hi.abs() > MAX_AXIS_VALUE) {
        return Err(invalid(
            path,
            format!(
                "{what}: {axis} values from {lo:e} to {hi:e} exceed the plottable magnitude {MAX_AXIS_VALUE:e}"
            ),
        ));
    }
    if scale == Scale::Log10 && !values.is_empty() && (hi / lo).log10() > MAX_LOG_DECADES {
        return Err(invalid(
            path,
            format!(
                "{what}: {axis} values from {lo:e} to {hi:e} span more than {MAX_LOG_DECADES} decades on a log axis"
            ),
        ));
    }
    Ok(())
}

/// Largest magnitude a plotted value may have (padding the range must not overflow).
const MAX_AXIS_VALUE: f64 = 1e300;
/// Most decades a log axis may span.
const MAX_LOG_DECADES: f64 = 100.0;

/// Checks one series: equal non-zero lengths, finite values, positive on log axes.
fn check_series(path: &Path, s: &Series, xs: Scale, ys: Scale) -> Result<(), PlotError> {
    let what = format!("series {:?}", s.label);
    if s.x.len() != s.y.len() {
        let msg = format!(
            "{what} has {} x values but {} y values",
            s.x.len(),
            s.y.len()
        );
        return Err(invalid(path, msg));
    }
    if s.x.is_empty() {
        return Err(empty(path, &what));
    }
    check_values(path, &what, "x", &s.x, xs)?;
    check_values(path, &what, "y", &s.y, ys)
}

/// Checks a non-empty set of series (`what` names the set in the error if empty).
fn check_series_set(
    path: &Path,
    series: &[Series],
    what: &str,
    xs: Scale,
    ys: Scale,
) -> Result<(), PlotError> {
    if series.is_empty() {
        return Err(empty(path, what));
    }
    series
        .iter()
        .try_for_each(|s| check_series(path, s, xs, ys))
}

/// Checks that grid coordinates are finite, strictly increasing and fit the scale.
fn check_grid_axis(path: &Path, what: &str, v: &[f64], scale: Scale) -> Result<(), PlotError> {
    if v.is_empty() {
        return Err(empty(path, what));
    }
    let axis = if what.starts_with('x') { "x" } else { "y" };
    check_values(path, what, axis, v, scale)?;
    if let Some(i) = v.windows(2).position(|w| w[1] <= w[0]) {
        return Err(invalid(
            path,
            format!("{what} is not strictly increasing at index {}", i + 1),
        ));
    }
    Ok(())
}

// ---------------------------------------------------------------- ranges

/// Smallest and largest of `values` (assumed finite and non-empty).
fn min_max(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// A linear axis range around [lo, hi], widened if empty, padded by `pad` of its span.
fn linear_range(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    if hi <= lo {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d)..(hi + d);
    }
    let p = pad * (hi - lo);
    (lo - p)..(hi + p)
}

/// A log axis range covering [lo, hi] (both > 0), rounded out to whole decades and
/// widened by a hair so that plotters' tick search keeps the end decades.
fn log_range(lo: f64, hi: f64) -> Range<f64> {
    let a = 10f64.powf(lo.log10().floor());
    let b = 10f64.powf(hi.log10().ceil()).max(a * 10.0);
    (a * (1.0 - 1e-6))..(b * (1.0 + 1e-6))
}

/// Axis range for data in [lo, hi] on `scale` (linear ranges padded by `pad`).
fn axis_range(lo: f64, hi: f64, scale: Scale, pad: f64) -> Range<f64> {
    match scale {
        Scale::Linear => linear_range(lo, hi, pad),
        Scale::Log10 => log_range(lo, hi),
    }
}

/// Cell edges around strictly increasing centres: half-way between neighbours
/// (geometric mean on a log axis), ends extended by half a spacing.
fn cell_edges(centres: &[f64], scale: Scale) -> Vec<f64> {
    type Map = fn(f64) -> f64;
    let (fwd, back): (Map, Map) = match scale {
        Scale::Linear => (|v| v, |v| v),
        Scale::Log10 => (f64::log10, |v| 10f64.powf(v)),
    };
    let c: Vec<f64> = centres.iter().map(|&v| fwd(v)).collect();
    let n = c.len();
    let half = |i: usize| if n > 1 { 0.5 * (c[i + 1] - c[i]) } else { 0.5 };
    let mut e = Vec::with_capacity(n + 1);
    e.push(c[0] - half(0));
    e.extend(c.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    e.push(c[n - 1] + half(n.saturating_sub(2)));
    e.into_iter().map(back).collect()
}

// ---------------------------------------------------------------- rendering

/// A figure that can draw itself on any plotters backend.
trait Figure {
    /// Pixel size of the whole figure.
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Output format chosen from the file extension.
#[derive(Clone, Copy)]
enum Format {
    Png,
    Svg,
}

/// The format for `path`'s extension, or an error naming it.
fn format_of(path: &Path) -> Result<Format, PlotError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "png" => Ok(Format::Png),
        "svg" => Ok(Format::Svg),
        _ => Err(PlotError::UnknownExtension {
            path: path.to_path_buf(),
            ext,
        }),
    }
}

/// Registers the embedded font with plotters once per process.
fn ensure_font(path: &Path) -> Result<(), PlotError> {
    static FONT_BYTES: &[u8] = include_bytes!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/fonts/DejaVuSans.ttf"
    ));
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font {
            path: path.to_path_buf(),
        })
    }
}

/// Fills `root` white, draws `fig` and flushes the backend.
fn paint<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    fig: &impl Figure,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(draw_err)?;
    fig.draw(&root)?;
    root.present().map_err(draw_err)
}

/// Renders `fig` in memory with the backend for `format`; returns the file's bytes.
/// (In memory so that the file itself goes through [`crate::io::write_atomic`], the one
/// place that writes, and stays inside an active output root.)
fn render_bytes(format: Format, fig: &impl Figure) -> Result<Vec<u8>, String> {
    let (w, h) = fig.size();
    match format {
        Format::Png => {
            let len = (w as usize)
                .checked_mul(h as usize)
                .and_then(|n| n.checked_mul(3))
                .ok_or_else(|| format!("image size {w} x {h} is too large"))?;
            let mut rgb = vec![0u8; len];
            paint(
                BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area(),
                fig,
            )?;
            let mut bytes = Vec::new();
            let mut encoder = png::Encoder::new(&mut bytes, w, h);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder
                .write_header()
                .and_then(|mut writer| writer.write_image_data(&rgb))
                .map_err(|e| format!("PNG encoding failed: {e}"))?;
            Ok(bytes)
        }
        Format::Svg => {
            let mut text = String::new();
            paint(
                SVGBackend::with_string(&mut text, (w, h)).into_drawing_area(),
                fig,
            )?;
            Ok(text.into_bytes())
        }
    }
}

/// Renders `fig` to `path` atomically (see [`crate::io::write_atomic`]).
fn render(path: &Path, fig: &impl Figure) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font(path)?;
    let bytes = render_bytes(format, fig).map_err(|message| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(crate::io::write_atomic(path, &bytes)?)
}

/// Draws the figure title at the top of `root`; returns the area below it.
fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, String> {
    root.margin(8, 0, 0, 0)
        .titled(title, (FONT, TITLE_PX))
        .map_err(draw_err)
}

/// Texts and label band of one chart.
struct Frame<'a> {
    caption: &'a str,
    x_desc: &'a str,
    y_desc: &'a str,
    /// Height of the x tick-label band; 0 hides the x tick labels.
    x_area: u32,
    /// Scales of the x and y axes (tick labels near 0 are snapped on linear axes).
    scales: (Scale, Scale),
}

/// A chart builder on `area` with the standard margins and label bands.
fn builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    frame: &Frame<'b>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin(MARGIN)
        .x_label_area_size(frame.x_area)
        .y_label_area_size(Y_AREA);
    if !frame.caption.is_empty() {
        b.caption(frame.caption, (FONT, LABEL_PX));
    }
    b
}

/// Draws axes, tick labels, axis descriptions and (optionally) grid lines.
fn draw_mesh<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    frame: &Frame,
    grid: bool,
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let x_fmt = snapped_labels(chart.x_range(), frame.scales.0);
    let y_fmt = snapped_labels(chart.y_range(), frame.scales.1);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(frame.x_desc)
        .y_desc(frame.y_desc)
        .label_style((FONT, TICK_PX))
        .axis_desc_style((FONT, LABEL_PX))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_labels(8)
        .y_labels(6)
        .bold_line_style(RGBColor(215, 215, 215))
        .light_line_style(RGBColor(240, 240, 240));
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(draw_err)
}

/// Draws `series` as lines on a chart with the given ranges (linear or log).
fn draw_lines<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    frame: &Frame,
    series: &[Series],
    markers: bool,
    (xr, yr): (X, Y),
) -> Result<(), String>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = builder(area, frame)
        .build_cartesian_2d(xr, yr)
        .map_err(draw_err)?;
    draw_mesh(&mut chart, frame, true)?;
    for (i, s) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let points = || s.x.iter().copied().zip(s.y.iter().copied());
        chart
            .draw_series(LineSeries::new(points(), color.stroke_width(2)))
            .map_err(draw_err)?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
        if markers {
            let dots = points().map(|p| Circle::new(p, 4, color.filled()));
            chart.draw_series(dots).map_err(draw_err)?;
        }
    }
    if series.len() > 1 {
        chart
            .configure_series_labels()
            .background_style(WHITE)
            .border_style(BLACK)
            .label_font((FONT, LEGEND_PX))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(draw_err)?;
    }
    Ok(())
}

/// Calls `draw_lines` with linear or log coordinates as the scales ask.
fn draw_lines_scaled<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frame: &Frame,
    series: &[Series],
    markers: bool,
    (xr, yr): (Range<f64>, Range<f64>),
    (xs, ys): (Scale, Scale),
) -> Result<(), String> {
    use Scale::{Linear, Log10};
    match (xs, ys) {
        (Linear, Linear) => draw_lines(area, frame, series, markers, (xr, yr)),
        (Linear, Log10) => draw_lines(area, frame, series, markers, (xr, yr.log_scale())),
        (Log10, Linear) => draw_lines(area, frame, series, markers, (xr.log_scale(), yr)),
        (Log10, Log10) => draw_lines(
            area,
            frame,
            series,
            markers,
            (xr.log_scale(), yr.log_scale()),
        ),
    }
}

/// Data range of all series on x (unpadded) and y (padded 5 %).
fn series_ranges(series: &[Series], xs: Scale, ys: Scale) -> (Range<f64>, Range<f64>) {
    let (xlo, xhi) = min_max(series.iter().flat_map(|s| s.x.iter().copied()));
    let (ylo, yhi) = min_max(series.iter().flat_map(|s| s.y.iter().copied()));
    (
        axis_range(xlo, xhi, xs, 0.0),
        axis_range(ylo, yhi, ys, 0.05),
    )
}

/// Draws a vertical colour bar for values in `range` on `area`, aligned with a chart
/// drawn with the standard margins and an x-label band of `x_area`.
fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    range: Range<f64>,
    label: &str,
    stops: &[(u8, u8, u8); 9],
    x_area: u32,
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .margin_bottom(MARGIN + x_area)
        .margin_left(10)
        .right_y_label_area_size(CBAR_W - 50)
        .build_cartesian_2d(0.0..1.0, range.clone())
        .map_err(draw_err)?;
    let step = (range.end - range.start) / LEVELS as f64;
    let bands = (0..LEVELS).map(|k| {
        let y0 = range.start + k as f64 * step;
        Rectangle::new(
            [(0.0, y0), (1.0, y0 + step)],
            level_color(stops, k).filled(),
        )
    });
    chart.draw_series(bands).map_err(draw_err)?;
    let y_fmt = snapped_labels(range, Scale::Linear);
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .set_tick_mark_size(LabelAreaPosition::Right, 6)
        .y_desc(label)
        .label_style((FONT, TICK_PX))
        .axis_desc_style((FONT, LABEL_PX))
        .y_label_formatter(&y_fmt)
        .y_labels(6)
        .draw()
        .map_err(draw_err)
}

// ---------------------------------------------------------------- line and stacked plots

/// The figure drawn by [`line_plot`].
struct LineFig<'a> {
    axes: &'a Axes,
    series: &'a [Series],
    markers: bool,
}

impl Figure for LineFig<'_> {
    fn size(&self) -> (u32, u32) {
        (FIG_W, FIG_H)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let a = self.axes;
        let body = titled(root, &a.title)?;
        let frame = Frame {
            caption: "",
            x_desc: &a.x_label,
            y_desc: &a.y_label,
            x_area: X_AREA,
            scales: (a.x_scale, a.y_scale),
        };
        let ranges = series_ranges(self.series, a.x_scale, a.y_scale);
        let scales = (a.x_scale, a.y_scale);
        draw_lines_scaled(&body, &frame, self.series, self.markers, ranges, scales)
    }
}

/// The figure drawn by [`stacked_plot`].
struct StackedFig<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    panels: &'a [Panel],
}

/// Height of the title band of stacked and field figures (px).
const TITLE_H: u32 = 50;

impl Figure for StackedFig<'_> {
    fn size(&self) -> (u32, u32) {
        let n = self.panels.len() as u32;
        (FIG_W, TITLE_H + n * PANEL_H + X_AREA)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let (top, body) = root.split_vertically(TITLE_H);
        titled(&top, self.title)?;
        let breaks: Vec<u32> = (1..self.panels.len() as u32).map(|k| k * PANEL_H).collect();
        let areas = body.split_by_breakpoints(Vec::<u32>::new(), breaks);
        let all: Vec<Series> = self.panels.iter().flat_map(|p| p.series.clone()).collect();
        let (xr, _) = series_ranges(&all, Scale::Linear, Scale::Linear);
        let last = self.panels.len() - 1;
        for (i, (panel, area)) in self.panels.iter().zip(&areas).enumerate() {
            let frame = Frame {
                caption: &panel.title,
                x_desc: if i == last { self.x_label } else { "" },
                y_desc: self.y_label,
                x_area: if i == last { X_AREA } else { 0 },
                scales: (Scale::Linear, Scale::Linear),
            };
            let (_, yr) = series_ranges(&panel.series, Scale::Linear, Scale::Linear);
            draw_lines(area, &frame, &panel.series, false, (xr.clone(), yr))?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------- heatmap

/// The figure drawn by [`heatmap`], with validated data and precomputed cell edges.
struct HeatFig<'a> {
    axes: &'a Axes,
    x_edges: Vec<f64>,
    y_edges: Vec<f64>,
    values: &'a [Vec<f64>],
    range: Range<f64>,
    label: &'a str,
}

impl<'a> HeatFig<'a> {
    /// Validates the grid and values and prepares the figure.
    fn new(
        path: &Path,
        axes: &'a Axes,
        x: &[f64],
        y: &[f64],
        values: &'a [Vec<f64>],
        label: &'a str,
    ) -> Result<Self, PlotError> {
        check_grid_axis(path, "x grid", x, axes.x_scale)?;
        check_grid_axis(path, "y grid", y, axes.y_scale)?;
        if values.len() != y.len() {
            let msg = format!(
                "heatmap has {} rows but y has {} values",
                values.len(),
                y.len()
            );
            return Err(invalid(path, msg));
        }
        for (iy, row) in values.iter().enumerate() {
            if row.len() != x.len() {
                let msg = format!(
                    "heatmap row {iy} has {} values but x has {}",
                    row.len(),
                    x.len()
                );
                return Err(invalid(path, msg));
            }
            check_values(
                path,
                &format!("heatmap row {iy}"),
                "value",
                row,
                Scale::Linear,
            )?;
        }
        let (lo, hi) = min_max(values.iter().flatten().copied());
        Ok(HeatFig {
            axes,
            x_edges: cell_edges(x, axes.x_scale),
            y_edges: cell_edges(y, axes.y_scale),
            values,
            range: linear_range(lo, hi, 0.0),
            label,
        })
    }

    /// Colour of a value: viridis over the colour-bar range.
    fn color(&self, v: f64) -> RGBColor {
        let t = (v - self.range.start) / (self.range.end - self.range.start);
        level_color(&VIRIDIS, level_of(t))
    }

    /// Draws the cells and axes on a chart with the given coordinates.
    fn draw_cells<DB, X, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (xr, yr): (X, Y),
    ) -> Result<(), String>
    where
        DB: DrawingBackend,
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let frame = Frame {
            caption: "",
            x_desc: &self.axes.x_label,
            y_desc: &self.axes.y_label,
            x_area: X_AREA,
            scales: (self.axes.x_scale, self.axes.y_scale),
        };
        let mut chart = builder(area, &frame)
            .build_cartesian_2d(xr, yr)
            .map_err(draw_err)?;
        let (xe, ye) = (&self.x_edges, &self.y_edges);
        let cells = self.values.iter().enumerate().flat_map(|(iy, row)| {
            row.iter().enumerate().map(move |(ix, &v)| {
                let corners = [(xe[ix], ye[iy]), (xe[ix + 1], ye[iy + 1])];
                Rectangle::new(corners, self.color(v).filled())
            })
        });
        chart.draw_series(cells).map_err(draw_err)?;
        draw_mesh(&mut chart, &frame, false)
    }
}

impl Figure for HeatFig<'_> {
    fn size(&self) -> (u32, u32) {
        (FIG_W, FIG_H)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        use Scale::{Linear, Log10};
        let body = titled(root, &self.axes.title)?;
        let (main, bar) = body.split_horizontally(FIG_W - CBAR_W);
        let xr = self.x_edges[0]..self.x_edges[self.x_edges.len() - 1];
        let yr = self.y_edges[0]..self.y_edges[self.y_edges.len() - 1];
        match (self.axes.x_scale, self.axes.y_scale) {
            (Linear, Linear) => self.draw_cells(&main, (xr, yr)),
            (Linear, Log10) => self.draw_cells(&main, (xr, yr.log_scale())),
            (Log10, Linear) => self.draw_cells(&main, (xr.log_scale(), yr)),
            (Log10, Log10) => self.draw_cells(&main, (xr.log_scale(), yr.log_scale())),
        }?;
        draw_colorbar(&bar, self.range.clone(), self.label, &VIRIDIS, X_AREA)
    }
}

// ---------------------------------------------------------------- mesh field

/// The figure drawn by [`field_plot`], with validated data.
struct FieldFig<'a> {
    axes: &'a Axes,
    nodes: &'a [[f64; 2]],
    triangles: &'a [[usize; 3]],
    values: &'a [f64],
    overlays: &'a [Overlay],
    label: &'a str,
    /// Largest |value| (colour range is symmetric: -vmax..vmax).
    vmax: f64,
    /// Mesh bounding box.
    bbox: (Range<f64>, Range<f64>),
}

impl<'a> FieldFig<'a> {
    /// Validates mesh, values and overlays and prepares the figure.
    fn new(
        path: &Path,
        axes: &'a Axes,
        nodes: &'a [[f64; 2]],
        triangles: &'a [[usize; 3]],
        values: &'a [f64],
        overlays: &'a [Overlay],
        label: &'a str,
    ) -> Result<Self, PlotError> {
        if axes.x_scale != Scale::Linear || axes.y_scale != Scale::Linear {
            return Err(invalid(path, "field plots need linear axes".to_string()));
        }
        Self::check_mesh(path, nodes, triangles, values)?;
        for (i, o) in overlays.iter().enumerate() {
            Self::check_overlay(path, i, o)?;
        }
        let (x0, x1) = min_max(nodes.iter().map(|p| p[0]));
        let (y0, y1) = min_max(nodes.iter().map(|p| p[1]));
        if x1 <= x0 || y1 <= y0 {
            return Err(invalid(
                path,
                "the mesh has zero extent in x or y".to_string(),
            ));
        }
        let vmax = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        Ok(FieldFig {
            axes,
            nodes,
            triangles,
            values,
            overlays,
            label,
            vmax: if vmax > 0.0 { vmax } else { 1.0 },
            bbox: (x0..x1, y0..y1),
        })
    }

    /// Checks node coordinates, nodal values and triangle indices.
    fn check_mesh(
        path: &Path,
        nodes: &[[f64; 2]],
        triangles: &[[usize; 3]],
        values: &[f64],
    ) -> Result<(), PlotError> {
        if triangles.is_empty() {
            return Err(empty(path, "the triangle list"));
        }
        if values.len() != nodes.len() {
            let msg = format!("{} field values for {} nodes", values.len(), nodes.len());
            return Err(invalid(path, msg));
        }
        let xs: Vec<f64> = nodes.iter().map(|p| p[0]).collect();
        let ys: Vec<f64> = nodes.iter().map(|p| p[1]).collect();
        check_values(path, "node coordinates", "x", &xs, Scale::Linear)?;
        check_values(path, "node coordinates", "y", &ys, Scale::Linear)?;
        check_values(path, "the field", "value", values, Scale::Linear)?;
        if let Some(t) = triangles
            .iter()
            .position(|t| t.iter().any(|&k| k >= nodes.len()))
        {
            let msg = format!("triangle {t} refers to a node >= {}", nodes.len());
            return Err(invalid(path, msg));
        }
        Ok(())
    }

    /// Checks that overlay `i` has at least two finite points and a non-zero width.
    fn check_overlay(path: &Path, i: usize, o: &Overlay) -> Result<(), PlotError> {
        if o.points.len() < 2 || o.width == 0 {
            let msg = format!("overlay {i} needs at least 2 points and a width > 0");
            return Err(invalid(path, msg));
        }
        let what = format!("overlay {i}");
        let xs: Vec<f64> = o.points.iter().map(|p| p.0).collect();
        let ys: Vec<f64> = o.points.iter().map(|p| p.1).collect();
        check_values(path, &what, "x", &xs, Scale::Linear)?;
        check_values(path, &what, "y", &ys, Scale::Linear)
    }

    /// Axis ranges containing the mesh with equal x and y scale on a `pw` x `ph` plot.
    fn equal_aspect(&self, (pw, ph): (u32, u32)) -> (Range<f64>, Range<f64>) {
        let (xr, yr) = &self.bbox;
        let (pw, ph) = (f64::from(pw.max(1)), f64::from(ph.max(1)));
        let scale = ((xr.end - xr.start) / pw).max((yr.end - yr.start) / ph);
        let (cx, cy) = (0.5 * (xr.start + xr.end), 0.5 * (yr.start + yr.end));
        let (hx, hy) = (0.5 * scale * pw, 0.5 * scale * ph);
        ((cx - hx)..(cx + hx), (cy - hy)..(cy + hy))
    }

    /// Draws the rasterised field as horizontal runs of equal colour level (compact in SVG).
    fn draw_raster<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Shift>,
        raster: &Raster,
    ) -> Result<(), String> {
        let level = |v: Option<f64>| v.map(|v| level_of(0.5 + 0.5 * v / self.vmax));
        for j in 0..raster.h {
            let row = &raster.cells[j * raster.w..(j + 1) * raster.w];
            let mut i = 0;
            while i < raster.w {
                let k = level(row[i]);
                let run = row[i..].iter().take_while(|&&v| level(v) == k).count();
                if let Some(k) = k {
                    let (x0, y0) = (i as i32, j as i32);
                    let corners = [(x0, y0), (x0 + run as i32, y0 + 1)];
                    let style = level_color(&DIVERGING, k).filled();
                    plot.draw(&Rectangle::new(corners, style))
                        .map_err(draw_err)?;
                }
                i += run;
            }
        }
        Ok(())
    }

    /// Draws the overlay polylines on the chart.
    fn draw_overlays<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> Result<(), String> {
        for o in self.overlays {
            let (r, g, b) = o.color;
            let style = RGBColor(r, g, b).stroke_width(o.width);
            chart
                .draw_series(LineSeries::new(o.points.iter().copied(), style))
                .map_err(draw_err)?;
        }
        Ok(())
    }
}

impl Figure for FieldFig<'_> {
    fn size(&self) -> (u32, u32) {
        let (xr, yr) = &self.bbox;
        let aspect = (yr.end - yr.start) / (xr.end - xr.start);
        let plot_w = f64::from(FIG_W - CBAR_W - Y_AREA - 2 * MARGIN);
        let overhead = f64::from(TITLE_H + X_AREA + 2 * MARGIN);
        (
            FIG_W,
            (overhead + plot_w * aspect).clamp(350.0, 900.0) as u32,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let body = titled(root, &self.axes.title)?;
        let (main, bar) = body.split_horizontally(FIG_W - CBAR_W);
        let frame = Frame {
            caption: "",
            x_desc: &self.axes.x_label,
            y_desc: &self.axes.y_label,
            x_area: X_AREA,
            scales: (self.axes.x_scale, self.axes.y_scale),
        };
        let probe = builder(&main, &frame)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(draw_err)?;
        let (xr, yr) = self.equal_aspect(probe.plotting_area().dim_in_pixel());
        let mut chart = builder(&main, &frame)
            .build_cartesian_2d(xr.clone(), yr.clone())
            .map_err(draw_err)?;
        let plot = chart.plotting_area().strip_coord_spec();
        let raster = Raster::sample(self, (&xr, &yr), plot.dim_in_pixel());
        self.draw_raster(&plot, &raster)?;
        self.draw_overlays(&mut chart)?;
        draw_mesh(&mut chart, &frame, false)?;
        draw_colorbar(&bar, -self.vmax..self.vmax, self.label, &DIVERGING, X_AREA)
    }
}

/// A field sampled at pixel centres (row 0 at the top); `None` outside the mesh.
struct Raster {
    w: usize,
    h: usize,
    cells: Vec<Option<f64>>,
}

impl Raster {
    /// Samples the piecewise-linear field of `fig` on a `pw` x `ph` pixel grid spanning
    /// the ranges, by barycentric interpolation inside each triangle.
    fn sample(fig: &FieldFig, (xr, yr): (&Range<f64>, &Range<f64>), (pw, ph): (u32, u32)) -> Self {
        let (w, h) = (pw as usize, ph as usize);
        let mut r = Raster {
            w,
            h,
            cells: vec![None; w * h],
        };
        if w == 0 || h == 0 {
            return r;
        }
        let sx = (xr.end - xr.start) / w as f64;
        let sy = (yr.end - yr.start) / h as f64;
        // Pixel (i, j) has its centre at (x0 + (i + 0.5) sx, y1 - (j + 0.5) sy).
        let to_px = move |x: f64, y: f64| ((x - xr.start) / sx - 0.5, (yr.end - y) / sy - 0.5);
        for t in fig.triangles {
            let p = t.map(|k| fig.nodes[k]);
            let v = t.map(|k| fig.values[k]);
            r.fill_triangle(p.map(|q| to_px(q[0], q[1])), v);
        }
        r
    }

    /// Writes interpolated values into the pixels whose centres lie in the triangle
    /// with vertices `p` (in pixel-index coordinates) and vertex values `v`.
    fn fill_triangle(&mut self, p: [(f64, f64); 3], v: [f64; 3]) {
        let [(ax, ay), (bx, by), (cx, cy)] = p;
        let det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
        if det.abs() < 1e-12 {
            return;
        }
        let span = |lo: f64, hi: f64, n: usize| {
            let a = lo.ceil().max(0.0);
            let b = hi.floor().min(n as f64 - 1.0);
            (a as usize)..=(b.max(a - 1.0).max(0.0) as usize)
        };
        let (xlo, xhi) = (ax.min(bx).min(cx), ax.max(bx).max(cx));
        let (ylo, yhi) = (ay.min(by).min(cy), ay.max(by).max(cy));
        if xhi < 0.0 || yhi < 0.0 || xlo > self.w as f64 - 1.0 || ylo > self.h as f64 - 1.0 {
            return;
        }
        let tol = -1e-9;
        for j in span(ylo, yhi, self.h) {
            for i in span(xlo, xhi, self.w) {
                let (x, y) = (i as f64, j as f64);
                let l1 = ((bx - x) * (cy - y) - (cx - x) * (by - y)) / det;
                let l2 = ((cx - x) * (ay - y) - (ax - x) * (cy - y)) / det;
                let l3 = 1.0 - l1 - l2;
                if l1 >= tol && l2 >= tol && l3 >= tol {
                    self.cells[j * self.w + i] = Some(l1 * v[0] + l2 * v[1] + l3 * v[2]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A fresh, empty directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl std::ops::Deref for TempDir {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn temp_dir(tag: &str) -> TempDir {
        static N: AtomicU64 = AtomicU64::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let name = format!("plotio-plot-{tag}-{}-{n}", std::process::id());
        let dir = std::env::temp_dir().join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        TempDir(dir)
    }

    fn axes(title: &str, xs: Scale, ys: Scale) -> Axes {
        Axes {
            title: title.to_string(),
            x_label: "time (µs)".to_string(),
            y_label: "u_y (nm)".to_string(),
            x_scale: xs,
            y_scale: ys,
        }
    }

    fn wave(label: &str, f: f64) -> Series {
        let x: Vec<f64> = (0..400).map(|i| f64::from(i) * 0.05).collect();
        let y = x
            .iter()
            .map(|t| (f * t).sin() * (-(t - 10.0) * (t - 10.0) / 8.0).exp())
            .collect();
        Series {
            label: label.to_string(),
            x,
            y,
        }
    }

    /// A small rectangular mesh with a field varying in x and y.
    fn mesh() -> (Vec<[f64; 2]>, Vec<[usize; 3]>, Vec<f64>) {
        let (nx, ny) = (20, 6);
        let mut nodes = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([f64::from(i) * 2.0, f64::from(j)]);
            }
        }
        let id = |i: usize, j: usize| j * (nx as usize + 1) + i;
        let mut tris = Vec::new();
        for j in 0..ny as usize {
            for i in 0..nx as usize {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        let vals = nodes.iter().map(|p| (p[0] * 0.3).sin() * p[1]).collect();
        (nodes, tris, vals)
    }

    /// Renders `fig` into an RGB buffer; returns (buffer, width, height).
    fn to_buffer(fig: &impl Figure) -> (Vec<u8>, u32, u32) {
        ensure_font(Path::new("buffer")).expect("font");
        let (w, h) = fig.size();
        let mut buf = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            paint(root, fig).expect("draw into buffer");
        }
        (buf, w, h)
    }

    /// Number of dark pixels in rows `rows` of an RGB buffer of width `w`.
    fn dark_pixels(buf: &[u8], w: u32, rows: Range<u32>) -> usize {
        let row_bytes = (w * 3) as usize;
        buf[rows.start as usize * row_bytes..rows.end as usize * row_bytes]
            .chunks(3)
            .filter(|p| p.iter().all(|&c| c < 100))
            .count()
    }

    /// Asserts the file is a PNG of the given size (IHDR width and height).
    fn assert_png(path: &Path, (w, h): (u32, u32)) {
        let bytes = std::fs::read(path).expect("read png");
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&bytes[12..16], b"IHDR");
        let be = |o: usize| u32::from_be_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
        assert_eq!((be(16), be(20)), (w, h));
    }

    /// Asserts the SVG has text elements and contains `title`.
    fn assert_svg(path: &Path, title: &str) {
        let text = std::fs::read_to_string(path).expect("read svg");
        assert!(text.contains("<text"), "no text in {}", path.display());
        assert!(text.contains(title), "title missing in {}", path.display());
    }

    /// Checks buffer rendering (title pixels) and PNG/SVG files for a figure.
    fn check_figure(
        fig: &impl Figure,
        title: &str,
        write: impl Fn(&Path) -> Result<(), PlotError>,
    ) {
        let (buf, w, h) = to_buffer(fig);
        assert!(dark_pixels(&buf, w, 0..45) > 100, "title not rendered");
        assert!(
            dark_pixels(&buf, w, 45..h) > 1000,
            "no axes or labels rendered"
        );
        let dir = temp_dir("fig");
        let png = dir.join("a/fig.png");
        write(&png).expect("png");
        assert_png(&png, fig.size());
        let svg = dir.join("fig.svg");
        write(&svg).expect("svg");
        assert_svg(&svg, title);
        let mut names: Vec<_> = std::fs::read_dir(&*dir)
            .expect("dir")
            .map(|e| e.expect("e").file_name())
            .collect();
        names.sort();
        assert_eq!(names, ["a", "fig.svg"], "temporary files left behind");
    }

    #[test]
    fn line_plot_png_svg_buffer() {
        let a = axes("Focusing at receiver 3", Scale::Linear, Scale::Linear);
        let s = [wave("linear", 3.0), wave("cracked", 3.3)];
        let fig = LineFig {
            axes: &a,
            series: &s,
            markers: false,
        };
        check_figure(&fig, &a.title, |p| line_plot(p, &a, &s, false));
    }

    #[test]
    fn log_line_plot_with_markers() {
        let a = axes("Work-precision", Scale::Log10, Scale::Log10);
        let s = [Series {
            label: "central difference".into(),
            x: vec![0.1, 0.4, 2.0, 9.0],
            y: vec![1e-2, 3e-3, 4e-4, 1e-5],
        }];
        let fig = LineFig {
            axes: &a,
            series: &s,
            markers: true,
        };
        check_figure(&fig, &a.title, |p| line_plot(p, &a, &s, true));
    }

    #[test]
    fn stacked_plot_png_svg_buffer() {
        let panels: Vec<Panel> = (1..=3)
            .map(|r| Panel {
                title: format!("Receiver {r}"),
                series: vec![wave("sim", f64::from(r)), wave("pred", f64::from(r) + 0.2)],
            })
            .collect();
        let fig = StackedFig {
            title: "TR-NEWS focusing",
            x_label: "t (µs)",
            y_label: "u (nm)",
            panels: &panels,
        };
        assert_eq!(fig.size(), (1000, 50 + 3 * 220 + 60));
        check_figure(&fig, fig.title, |p| {
            stacked_plot(p, fig.title, "t (µs)", "u (nm)", &panels)
        });
    }

    #[test]
    fn heatmap_png_svg_buffer() {
        let a = axes(
            "Departure from linear prediction",
            Scale::Linear,
            Scale::Log10,
        );
        let x: Vec<f64> = (0..30).map(f64::from).collect();
        let y: Vec<f64> = (0..12).map(|k| 10f64.powf(f64::from(k) / 4.0)).collect();
        let v: Vec<Vec<f64>> = y
            .iter()
            .map(|yy| x.iter().map(|xx| (xx * 0.2).sin() * yy.ln()).collect())
            .collect();
        let fig = HeatFig::new(Path::new("t.png"), &a, &x, &y, &v, "error (dB)").expect("valid");
        check_figure(&fig, &a.title, |p| heatmap(p, &a, &x, &y, &v, "error (dB)"));
    }

    #[test]
    fn field_plot_png_svg_buffer() {
        let a = axes("u_y snapshot", Scale::Linear, Scale::Linear);
        let (n, t, v) = mesh();
        let ov = [
            Overlay {
                points: vec![(0.0, 3.0), (40.0, 3.0)],
                color: (128, 128, 128),
                width: 1,
            },
            Overlay {
                points: vec![(15.0, 2.0), (25.0, 2.0)],
                color: (0, 0, 0),
                width: 4,
            },
        ];
        let fig =
            FieldFig::new(Path::new("t.png"), &a, &n, &t, &v, &ov, "u_y (nm)").expect("valid");
        check_figure(&fig, &a.title, |p| {
            field_plot(p, &a, &n, &t, &v, &ov, "u_y (nm)")
        });
        let (buf, w, h) = to_buffer(&fig);
        let reds = buf.chunks(3).filter(|p| p[0] > 150 && p[2] < 110).count();
        let blues = buf.chunks(3).filter(|p| p[2] > 150 && p[0] < 110).count();
        assert!(
            reds > 1000 && blues > 1000,
            "diverging colours missing ({reds}, {blues}) in {w}x{h}"
        );
    }

    #[test]
    fn raster_interpolates_linear_field_exactly() {
        let a = axes("", Scale::Linear, Scale::Linear);
        let (n, t, _) = mesh();
        let v: Vec<f64> = n.iter().map(|p| 2.0 * p[0] - p[1]).collect();
        let fig = FieldFig::new(Path::new("t.png"), &a, &n, &t, &v, &[], "").expect("valid");
        let (xr, yr) = (0.0..40.0, 0.0..6.0);
        let r = Raster::sample(&fig, (&xr, &yr), (80, 12));
        assert!(
            r.cells.iter().all(Option::is_some),
            "pixels missed inside the mesh"
        );
        let (i, j) = (13, 5);
        let (x, y) = ((i as f64 + 0.5) * 0.5, 6.0 - (j as f64 + 0.5) * 0.5);
        let got = r.cells[j * 80 + i].expect("inside");
        assert!((got - (2.0 * x - y)).abs() < 1e-9, "{got}");
    }

    #[test]
    fn log_axis_with_zero_errors() {
        let a = axes("log", Scale::Linear, Scale::Log10);
        let s = [Series {
            label: "decay".into(),
            x: vec![1.0, 2.0],
            y: vec![1.0, 0.0],
        }];
        let dir = temp_dir("log0");
        let err = line_plot(&dir.join("f.png"), &a, &s, false).expect_err("must fail");
        assert!(
            matches!(
                err,
                PlotError::NonPositiveLog {
                    axis: "y",
                    index: 1,
                    ..
                }
            ),
            "{err}"
        );
        assert!(
            err.to_string().contains("decay") && err.to_string().contains("f.png"),
            "{err}"
        );
        assert!(std::fs::read_dir(&*dir).expect("dir").next().is_none());
    }

    #[test]
    fn nan_and_empty_error() {
        let a = axes("nan", Scale::Linear, Scale::Linear);
        let dir = temp_dir("nan");
        let s = [Series {
            label: "bad".into(),
            x: vec![1.0, 2.0],
            y: vec![f64::NAN, 0.0],
        }];
        let err = line_plot(&dir.join("f.svg"), &a, &s, false).expect_err("nan");
        assert!(
            matches!(err, PlotError::NonFinite { .. }) && err.to_string().contains("bad"),
            "{err}"
        );
        let e = [Series {
            label: "none".into(),
            x: vec![],
            y: vec![],
        }];
        assert!(matches!(
            line_plot(&dir.join("f.png"), &a, &e, false),
            Err(PlotError::Empty { .. })
        ));
        assert!(matches!(
            line_plot(&dir.join("f.png"), &a, &[], false),
            Err(PlotError::Empty { .. })
        ));
        assert!(matches!(
            stacked_plot(&dir.join("f.png"), "t", "x", "y", &[]),
            Err(PlotError::Empty { .. })
        ));
        let hv = vec![vec![1.0, f64::INFINITY]];
        let err = heatmap(&dir.join("h.png"), &a, &[0.0, 1.0], &[0.0], &hv, "c").expect_err("inf");
        assert!(err.to_string().contains("heatmap row 0"), "{err}");
    }

    #[test]
    fn unknown_extension_errors() {
        let a = axes("ext", Scale::Linear, Scale::Linear);
        let dir = temp_dir("ext");
        let err = line_plot(&dir.join("fig.jpg"), &a, &[wave("w", 1.0)], false).expect_err("jpg");
        assert!(
            matches!(&err, PlotError::UnknownExtension { ext, .. } if ext == "jpg"),
            "{err}"
        );
        assert!(err.to_string().contains("fig.jpg"), "{err}");
        assert!(std::fs::read_dir(&*dir).expect("dir").next().is_none());
    }

    #[test]
    fn bad_mesh_and_grid_error() {
        let a = axes("mesh", Scale::Linear, Scale::Linear);
        let (n, mut t, v) = mesh();
        t.push([0, 1, n.len()]);
        let err = field_plot(Path::new("/nonexistent/x.png"), &a, &n, &t, &v, &[], "")
            .expect_err("index");
        assert!(err.to_string().contains("triangle"), "{err}");
        let err = heatmap(
            Path::new("h.png"),
            &a,
            &[1.0, 0.5],
            &[0.0],
            &[vec![1.0, 2.0]],
            "",
        )
        .expect_err("order");
        assert!(err.to_string().contains("strictly increasing"), "{err}");
    }

    #[test]
    fn helpers_behave() {
        assert_eq!(tick_label(&0.30000000000000004), "0.3");
        assert_eq!(tick_label(&2.5e-6), "2.5e-6");
        assert_eq!(tick_label(&0.0), "0");
        let r = log_range(2.0, 3.0);
        assert!(
            (r.start - 1.0).abs() < 1e-5 && (r.end - 10.0).abs() < 1e-4,
            "{r:?}"
        );
        assert_eq!(
            cell_edges(&[0.0, 1.0, 3.0], Scale::Linear),
            vec![-0.5, 0.5, 2.0, 4.0]
        );
        let e = cell_edges(&[1.0, 100.0], Scale::Log10);
        assert!(
            (e[0] - 0.1).abs() < 1e-12
                && (e[1] - 10.0).abs() < 1e-9
                && (e[2] - 1000.0).abs() < 1e-6
        );
        assert_eq!(colormap(&DIVERGING, 0.5), RGBColor(247, 247, 247));
    }
}
