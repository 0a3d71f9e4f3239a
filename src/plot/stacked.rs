//! Stacked panels sharing the x axis, one per receiver.

use super::*;

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

/// The figure drawn by [`stacked_plot`].
pub(super) struct StackedFig<'a> {
    pub(super) title: &'a str,
    pub(super) x_label: &'a str,
    pub(super) y_label: &'a str,
    pub(super) panels: &'a [Panel],
}

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
