//! Scalar fields on a triangle mesh (snapshots), rasterised, with overlays and a colour bar.

use super::*;

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

/// The figure drawn by [`field_plot`], with validated data.
pub(super) struct FieldFig<'a> {
    pub(super) axes: &'a Axes,
    pub(super) nodes: &'a [[f64; 2]],
    pub(super) triangles: &'a [[usize; 3]],
    pub(super) values: &'a [f64],
    pub(super) overlays: &'a [Overlay],
    pub(super) label: &'a str,
    /// Largest |value| (colour range is symmetric: -vmax..vmax).
    pub(super) vmax: f64,
    /// Mesh bounding box.
    pub(super) bbox: (Range<f64>, Range<f64>),
}

impl<'a> FieldFig<'a> {
    /// Validates mesh, values and overlays and prepares the figure.
    pub(super) fn new(
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
    pub(super) fn check_mesh(
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
    pub(super) fn check_overlay(path: &Path, i: usize, o: &Overlay) -> Result<(), PlotError> {
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
    pub(super) fn equal_aspect(&self, (pw, ph): (u32, u32)) -> (Range<f64>, Range<f64>) {
        let (xr, yr) = &self.bbox;
        let (pw, ph) = (f64::from(pw.max(1)), f64::from(ph.max(1)));
        let scale = ((xr.end - xr.start) / pw).max((yr.end - yr.start) / ph);
        let (cx, cy) = (0.5 * (xr.start + xr.end), 0.5 * (yr.start + yr.end));
        let (hx, hy) = (0.5 * scale * pw, 0.5 * scale * ph);
        ((cx - hx)..(cx + hx), (cy - hy)..(cy + hy))
    }

    /// Draws the rasterised field as horizontal runs of equal colour level (compact in SVG).
    pub(super) fn draw_raster<DB: DrawingBackend>(
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
    pub(super) fn draw_overlays<DB: DrawingBackend>(
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
        let frame = Frame::of(self.axes);
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
