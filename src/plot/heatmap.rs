//! Heatmaps of values on a rectilinear grid, with a colour bar.

use super::*;

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

/// The figure drawn by [`heatmap`], with validated data and precomputed cell edges.
pub(super) struct HeatFig<'a> {
    pub(super) axes: &'a Axes,
    pub(super) x_edges: Vec<f64>,
    pub(super) y_edges: Vec<f64>,
    pub(super) values: &'a [Vec<f64>],
    pub(super) range: Range<f64>,
    pub(super) label: &'a str,
}

impl<'a> HeatFig<'a> {
    /// Validates the grid and values and prepares the figure.
    pub(super) fn new(
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
    pub(super) fn color(&self, v: f64) -> RGBColor {
        let t = (v - self.range.start) / (self.range.end - self.range.start);
        level_color(&VIRIDIS, level_of(t))
    }

    /// Draws the cells and axes on a chart with the given coordinates.
    pub(super) fn draw_cells<DB, X, Y>(
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
        let frame = Frame::of(self.axes);
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
