//! Validation of figure data (finite, positive on log axes, consistent shapes) and axis ranges.

use super::*;

/// An [`PlotError::Empty`] about `what`.
pub(super) fn empty(path: &Path, what: &str) -> PlotError {
    PlotError::Empty {
        path: path.to_path_buf(),
        what: what.to_string(),
    }
}

/// An [`PlotError::Invalid`] with `message`.
pub(super) fn invalid(path: &Path, message: String) -> PlotError {
    PlotError::Invalid {
        path: path.to_path_buf(),
        message,
    }
}

/// Checks that `values` are finite, and positive when on a log axis.
pub(super) fn check_values(
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
pub(super) const MAX_AXIS_VALUE: f64 = 1e300;
/// Most decades a log axis may span.
pub(super) const MAX_LOG_DECADES: f64 = 100.0;

/// Checks one series: equal non-zero lengths, finite values, positive on log axes.
pub(super) fn check_series(path: &Path, s: &Series, xs: Scale, ys: Scale) -> Result<(), PlotError> {
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
pub(super) fn check_series_set(
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
pub(super) fn check_grid_axis(
    path: &Path,
    what: &str,
    v: &[f64],
    scale: Scale,
) -> Result<(), PlotError> {
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
pub(super) fn min_max(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// A linear axis range around [lo, hi], widened if empty, padded by `pad` of its span.
pub(super) fn linear_range(lo: f64, hi: f64, pad: f64) -> Range<f64> {
    if hi <= lo {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - d)..(hi + d);
    }
    let p = pad * (hi - lo);
    (lo - p)..(hi + p)
}

/// A log axis range covering [lo, hi] (both > 0), rounded out to whole decades and
/// widened by a hair so that plotters' tick search keeps the end decades.
pub(super) fn log_range(lo: f64, hi: f64) -> Range<f64> {
    let a = 10f64.powf(lo.log10().floor());
    let b = 10f64.powf(hi.log10().ceil()).max(a * 10.0);
    (a * (1.0 - 1e-6))..(b * (1.0 + 1e-6))
}

/// Axis range for data in [lo, hi] on `scale` (linear ranges padded by `pad`).
pub(super) fn axis_range(lo: f64, hi: f64, scale: Scale, pad: f64) -> Range<f64> {
    match scale {
        Scale::Linear => linear_range(lo, hi, pad),
        Scale::Log10 => log_range(lo, hi),
    }
}

/// Cell edges around strictly increasing centres: half-way between neighbours
/// (geometric mean on a log axis), ends extended by half a spacing.
pub(super) fn cell_edges(centres: &[f64], scale: Scale) -> Vec<f64> {
    pub(super) type Map = fn(f64) -> f64;
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
