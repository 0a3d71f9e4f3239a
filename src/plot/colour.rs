//! Line palette, colour maps, colour levels and the colour bar.

use super::*;

/// Line colours (matplotlib's tab10), cycled.
pub(super) const PALETTE: [RGBColor; 10] = [
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
pub(super) const VIRIDIS: [(u8, u8, u8); 9] = [
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
pub(super) const DIVERGING: [(u8, u8, u8); 9] = [
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
pub(super) fn colormap(stops: &[(u8, u8, u8); 9], t: f64) -> RGBColor {
    let s = t.clamp(0.0, 1.0) * 8.0;
    let k = (s.floor() as usize).min(7);
    let f = s - k as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (stops[k], stops[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Colour of quantised level `k` of `LEVELS`.
pub(super) fn level_color(stops: &[(u8, u8, u8); 9], k: usize) -> RGBColor {
    colormap(stops, k as f64 / (LEVELS - 1) as f64)
}

/// Quantises `t` in [0, 1] to a colour level.
pub(super) fn level_of(t: f64) -> usize {
    (t.clamp(0.0, 1.0) * (LEVELS - 1) as f64).round() as usize
}

/// Draws a vertical colour bar for values in `range` on `area`, aligned with a chart
/// drawn with the standard margins and an x-label band of `x_area`.
pub(super) fn draw_colorbar<DB: DrawingBackend>(
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
