//! Rhai module `plot`: line, stacked, heatmap and spectrum figures (PNG or SVG by extension),
//! every path resolved under the output dir. Series accept Signals directly.

use crate::plot::{Axes, Scale, Series};
use crate::script::convert::{error, floats, ScriptResult};
use crate::signal::{Signal, Spectrum};
use rhai::plugin::*;
use rhai::{Dynamic, Map, Module, NativeCallContext};
use serde::{Deserialize, Serialize};

/// The `plot` module.
pub fn module() -> Module {
    exported_module!(plot_api)
}

/// Figure options shared by the plot functions (unset fields keep their defaults).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct FigureOptions {
    title: String,
    x_label: String,
    y_label: String,
    log_x: bool,
    log_y: bool,
    markers: bool,
    /// Unit of Signal times on x: "s", "ms", "us" or "ns".
    time_unit: String,
    /// Unit of spectrum frequencies on x: "Hz", "kHz" or "MHz".
    freq_unit: String,
    /// Highest frequency shown by `plot::spectrum` (Hz); 0 shows all.
    f_max_hz: f64,
    /// Lowest level shown by `plot::spectrum` (dB below the largest PSD).
    floor_db: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions {
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            log_x: false,
            log_y: false,
            markers: false,
            time_unit: "us".into(),
            freq_unit: "MHz".into(),
            f_max_hz: 0.0,
            floor_db: -120.0,
        }
    }
}

impl FigureOptions {
    fn parse(ctx: &NativeCallContext, map: Map) -> ScriptResult<Self> {
        crate::script::convert::options(ctx, map, &FigureOptions::default(), "options")
    }

    fn axes(&self, default_x_label: String) -> Axes {
        let scale = |log| if log { Scale::Log10 } else { Scale::Linear };
        Axes {
            title: self.title.clone(),
            x_label: if self.x_label.is_empty() {
                default_x_label
            } else {
                self.x_label.clone()
            },
            y_label: self.y_label.clone(),
            x_scale: scale(self.log_x),
            y_scale: scale(self.log_y),
        }
    }

    /// Seconds -> chosen time unit: (factor, label).
    fn time_scale(&self, ctx: &NativeCallContext) -> ScriptResult<(f64, &'static str)> {
        match self.time_unit.as_str() {
            "s" => Ok((1.0, "s")),
            "ms" => Ok((1e3, "ms")),
            "us" | "µs" => Ok((1e6, "µs")),
            "ns" => Ok((1e9, "ns")),
            u => Err(error(
                ctx,
                format!("time_unit '{u}' must be s, ms, us or ns"),
            )),
        }
    }

    /// Hz -> chosen frequency unit: (factor, label).
    fn freq_scale(&self, ctx: &NativeCallContext) -> ScriptResult<(f64, &'static str)> {
        match self.freq_unit.as_str() {
            "Hz" => Ok((1.0, "Hz")),
            "kHz" => Ok((1e-3, "kHz")),
            "MHz" => Ok((1e-6, "MHz")),
            u => Err(error(
                ctx,
                format!("freq_unit '{u}' must be Hz, kHz or MHz"),
            )),
        }
    }
}

/// The map at `items[i]`, with only the allowed keys.
fn entry(
    ctx: &NativeCallContext,
    item: &Dynamic,
    what: &str,
    allowed: &[&str],
) -> ScriptResult<Map> {
    let map = item.clone().try_cast::<Map>().ok_or_else(|| {
        error(
            ctx,
            format!("{what} must be a map, got {}", item.type_name()),
        )
    })?;
    if let Some(k) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
        return Err(error(
            ctx,
            format!(
                "{what} has unknown key '{k}' (allowed: {})",
                allowed.join(", ")
            ),
        ));
    }
    Ok(map)
}

/// A series from #{label, x, y}: x and y are arrays or Signals; without x, a Signal y is
/// drawn against its sample times scaled by `time_factor`.
fn series(
    ctx: &NativeCallContext,
    item: &Dynamic,
    i: usize,
    time_factor: f64,
) -> ScriptResult<Series> {
    let what = format!("series[{i}]");
    let map = entry(ctx, item, &what, &["label", "x", "y"])?;
    let label = map
        .get("label")
        .map_or_else(|| format!("series {i}"), Dynamic::to_string);
    let y_value = map
        .get("y")
        .ok_or_else(|| error(ctx, format!("{what} has no 'y'")))?;
    let y = floats(ctx, y_value, &format!("{what}.y"))?;
    let x = match (map.get("x"), y_value.read_lock::<Signal>()) {
        (Some(x), _) => floats(ctx, x, &format!("{what}.x"))?,
        (None, Some(s)) => s.times().iter().map(|t| t * time_factor).collect(),
        (None, None) => {
            return Err(error(
                ctx,
                format!("{what} has no 'x' and 'y' is not a Signal"),
            ))
        }
    };
    Ok(Series { label, x, y })
}

/// All series of an array of series maps.
fn series_list(
    ctx: &NativeCallContext,
    items: &rhai::Array,
    time_factor: f64,
) -> ScriptResult<Vec<Series>> {
    items
        .iter()
        .enumerate()
        .map(|(i, item)| series(ctx, item, i, time_factor))
        .collect()
}

/// A spectrum series from #{label, spectrum}: PSD in dB re `reference`, floored, cropped.
fn spectrum_series(
    ctx: &NativeCallContext,
    item: &Dynamic,
    i: usize,
    o: &FigureOptions,
    reference: f64,
) -> ScriptResult<Series> {
    let what = format!("series[{i}]");
    let map = entry(ctx, item, &what, &["label", "spectrum"])?;
    let label = map
        .get("label")
        .map_or_else(|| format!("series {i}"), Dynamic::to_string);
    let sp = spectrum_of(ctx, &map, &what)?;
    let (factor, _) = o.freq_scale(ctx)?;
    let db = sp.to_db(reference).map_err(|e| error(ctx, e))?;
    let keep = |f: f64| (o.f_max_hz <= 0.0 || f <= o.f_max_hz) && (!o.log_x || f > 0.0);
    let (x, y) = sp
        .freqs_hz
        .iter()
        .zip(db)
        .filter(|(f, _)| keep(**f))
        .map(|(f, d)| (f * factor, d.max(o.floor_db)))
        .unzip();
    Ok(Series { label, x, y })
}

/// The `spectrum` entry of a series map.
fn spectrum_of(ctx: &NativeCallContext, map: &Map, what: &str) -> ScriptResult<Spectrum> {
    map.get("spectrum")
        .and_then(|d| d.clone().try_cast::<Spectrum>())
        .ok_or_else(|| error(ctx, format!("{what}.spectrum must be a Spectrum")))
}

/// The largest PSD value over all spectra of the series maps (the 0 dB level).
fn largest_psd(ctx: &NativeCallContext, items: &rhai::Array) -> ScriptResult<f64> {
    let mut top = 0.0f64;
    for (i, item) in items.iter().enumerate() {
        let what = format!("series[{i}]");
        let map = entry(ctx, item, &what, &["label", "spectrum"])?;
        top = spectrum_of(ctx, &map, &what)?
            .psd
            .iter()
            .fold(top, |m, &p| m.max(p));
    }
    if top > 0.0 {
        Ok(top)
    } else {
        Err(error(ctx, "every spectrum is zero: nothing to draw in dB"))
    }
}

#[export_module]
mod plot_api {
    use super::{entry, largest_psd, series_list, spectrum_series, FigureOptions};
    use crate::plot::{self, Panel};
    use crate::script::convert::{error, floats, rows, WithPosition};
    use crate::script::HostContext;
    use rhai::{Array, Map, NativeCallContext};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Line plot of series maps #{label, x, y} (x, y: arrays or Signals; a Signal y without x is drawn against time) with options #{title, x_label, y_label, log_x, log_y, markers, time_unit}.
    #[rhai_fn(return_raw)]
    pub fn line(ctx: NativeCallContext, path: &str, options: Map, series: Array) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let o = FigureOptions::parse(&ctx, options)?;
        let (factor, unit) = o.time_scale(&ctx)?;
        let list = series_list(&ctx, &series, factor)?;
        plot::line_plot(&file, &o.axes(format!("time ({unit})")), &list, o.markers).at(&ctx)
    }

    /// Stacked panels sharing the time axis in seconds; panels are maps #{title, series: [series maps]}.
    #[rhai_fn(name = "stacked", return_raw)]
    pub fn stacked_positional(
        ctx: NativeCallContext,
        path: &str,
        title: &str,
        x_label: &str,
        y_label: &str,
        panels: Array,
    ) -> Res<()> {
        let mut o = Map::new();
        o.insert("title".into(), title.into());
        o.insert("x_label".into(), x_label.into());
        o.insert("y_label".into(), y_label.into());
        o.insert("time_unit".into(), "s".into());
        stacked(ctx, path, o, panels)
    }

    /// Stacked panels sharing the x axis, options #{title, x_label, y_label, time_unit}; panels are maps #{title, series: [series maps]}.
    #[rhai_fn(return_raw)]
    pub fn stacked(ctx: NativeCallContext, path: &str, options: Map, panels: Array) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let o = FigureOptions::parse(&ctx, options)?;
        let (factor, unit) = o.time_scale(&ctx)?;
        let mut list = Vec::with_capacity(panels.len());
        for (i, p) in panels.iter().enumerate() {
            let map = entry(&ctx, p, &format!("panels[{i}]"), &["title", "series"])?;
            let title = map.get("title").map(|t| t.to_string()).unwrap_or_default();
            let series = map
                .get("series")
                .and_then(|s| s.clone().try_cast::<Array>())
                .ok_or_else(|| {
                    error(
                        &ctx,
                        format!("panels[{i}].series must be an array of series maps"),
                    )
                })?;
            list.push(Panel {
                title,
                series: series_list(&ctx, &series, factor)?,
            });
        }
        let axes = o.axes(format!("time ({unit})"));
        plot::stacked_plot(&file, &axes.title, &axes.x_label, &axes.y_label, &list).at(&ctx)
    }

    /// Heatmap of values_2d[iy][ix] at cell centres x, y (strictly increasing), options #{title, x_label, y_label, log_x, log_y}, with a labelled colour bar.
    #[rhai_fn(return_raw)]
    pub fn heatmap(
        ctx: NativeCallContext,
        path: &str,
        options: Map,
        x: Array,
        y: Array,
        values_2d: Array,
        colorbar_label: &str,
    ) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let o = FigureOptions::parse(&ctx, options)?;
        let x = floats(&ctx, &x.into(), "x")?;
        let y = floats(&ctx, &y.into(), "y")?;
        let values = rows(&ctx, &values_2d, "values_2d")?;
        plot::heatmap(
            &file,
            &o.axes(String::new()),
            &x,
            &y,
            &values,
            colorbar_label,
        )
        .at(&ctx)
    }

    /// Spectra #{label, spectrum} in dB relative to the largest PSD of all of them, options #{title, x_label, y_label, log_x, freq_unit, f_max_hz, floor_db}.
    #[rhai_fn(return_raw)]
    pub fn spectrum(ctx: NativeCallContext, path: &str, options: Map, series: Array) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let mut o = FigureOptions::parse(&ctx, options)?;
        let reference = largest_psd(&ctx, &series)?;
        let list = series
            .iter()
            .enumerate()
            .map(|(i, s)| spectrum_series(&ctx, s, i, &o, reference))
            .collect::<Res<Vec<_>>>()?;
        let (_, unit) = o.freq_scale(&ctx)?;
        if o.y_label.is_empty() {
            o.y_label = "PSD (dB re max)".into();
        }
        o.log_y = false;
        plot::line_plot(
            &file,
            &o.axes(format!("frequency ({unit})")),
            &list,
            o.markers,
        )
        .at(&ctx)
    }
}
