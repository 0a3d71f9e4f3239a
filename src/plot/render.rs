//! Layout and style, the PNG/SVG backends, atomic rendering, and the chart pieces shared by the figures.

use super::*;

// ---------------------------------------------------------------- layout and style

/// Font family name under which the embedded font is registered.
pub(super) const FONT: &str = "sans-serif";
/// Title, axis-label, tick-label and legend font sizes (px).
pub(super) const TITLE_PX: u32 = 24;
pub(super) const LABEL_PX: u32 = 18;
pub(super) const TICK_PX: u32 = 15;
pub(super) const LEGEND_PX: u32 = 16;
/// Default figure size (px).
pub(super) const FIG_W: u32 = 1000;
pub(super) const FIG_H: u32 = 700;
/// Height of one stacked panel (px).
pub(super) const PANEL_H: u32 = 220;
/// Chart margin, x-label band and y-label band (px).
pub(super) const MARGIN: u32 = 15;
pub(super) const X_AREA: u32 = 60;
pub(super) const Y_AREA: u32 = 110;
/// Width of the colour-bar strip to the right of heatmaps and fields (px).
pub(super) const CBAR_W: u32 = 150;
/// Number of colour levels in colour bars and mesh-field rasters.
pub(super) const LEVELS: usize = 128;

/// Height of the title band of stacked and field figures (px).
pub(super) const TITLE_H: u32 = 50;
/// Tick label: four significant digits, scientific notation for very small or large values.
pub(super) fn tick_label(v: &f64) -> String {
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
pub(super) fn snapped_labels(range: Range<f64>, scale: Scale) -> impl Fn(&f64) -> String {
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
pub(super) fn draw_err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

// ---------------------------------------------------------------- rendering

/// A figure that can draw itself on any plotters backend.
pub(super) trait Figure {
    /// Pixel size of the whole figure.
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
}

/// Output format chosen from the file extension.
#[derive(Clone, Copy)]
pub(super) enum Format {
    Png,
    Svg,
}

/// The format for `path`'s extension, or an error naming it.
pub(super) fn format_of(path: &Path) -> Result<Format, PlotError> {
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
pub(super) fn ensure_font(path: &Path) -> Result<(), PlotError> {
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
pub(super) fn paint<DB: DrawingBackend>(
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
pub(super) fn render_bytes(format: Format, fig: &impl Figure) -> Result<Vec<u8>, String> {
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
pub(super) fn render(path: &Path, fig: &impl Figure) -> Result<(), PlotError> {
    let format = format_of(path)?;
    ensure_font(path)?;
    let bytes = render_bytes(format, fig).map_err(|message| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(crate::io::write_atomic(path, &bytes)?)
}

/// Draws the figure title at the top of `root`; returns the area below it.
pub(super) fn titled<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<DrawingArea<DB, Shift>, String> {
    root.margin(8, 0, 0, 0)
        .titled(title, (FONT, TITLE_PX))
        .map_err(draw_err)
}

/// Texts and label band of one chart.
pub(super) struct Frame<'a> {
    pub(super) caption: &'a str,
    pub(super) x_desc: &'a str,
    pub(super) y_desc: &'a str,
    /// Height of the x tick-label band; 0 hides the x tick labels.
    pub(super) x_area: u32,
    /// Scales of the x and y axes (tick labels near 0 are snapped on linear axes).
    pub(super) scales: (Scale, Scale),
}

impl<'a> Frame<'a> {
    /// The frame of a figure's `axes`: no caption (the title is drawn above), axis labels,
    /// x tick labels shown, the axes' scales.
    pub(super) fn of(axes: &'a Axes) -> Frame<'a> {
        Frame {
            caption: "",
            x_desc: &axes.x_label,
            y_desc: &axes.y_label,
            x_area: X_AREA,
            scales: (axes.x_scale, axes.y_scale),
        }
    }
}

/// A chart builder on `area` with the standard margins and label bands.
pub(super) fn builder<'a, 'b, DB: DrawingBackend>(
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
pub(super) fn draw_mesh<DB, X, Y>(
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
pub(super) fn draw_lines<DB, X, Y>(
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
pub(super) fn draw_lines_scaled<DB: DrawingBackend>(
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
pub(super) fn series_ranges(series: &[Series], xs: Scale, ys: Scale) -> (Range<f64>, Range<f64>) {
    let (xlo, xhi) = min_max(series.iter().flat_map(|s| s.x.iter().copied()));
    let (ylo, yhi) = min_max(series.iter().flat_map(|s| s.y.iter().copied()));
    (
        axis_range(xlo, xhi, xs, 0.0),
        axis_range(ylo, yhi, ys, 0.05),
    )
}
