//! Line plots: curves on one pair of axes (linear or log).

use super::*;

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

/// The figure drawn by [`line_plot`].
pub(super) struct LineFig<'a> {
    pub(super) axes: &'a Axes,
    pub(super) series: &'a [Series],
    pub(super) markers: bool,
}

impl Figure for LineFig<'_> {
    fn size(&self) -> (u32, u32) {
        (FIG_W, FIG_H)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        let a = self.axes;
        let body = titled(root, &a.title)?;
        let frame = Frame::of(a);
        let ranges = series_ranges(self.series, a.x_scale, a.y_scale);
        let scales = (a.x_scale, a.y_scale);
        draw_lines_scaled(&body, &frame, self.series, self.markers, ranges, scales)
    }
}
