//! Rhai module `study`: the work-precision study (error against run time on a problem with a
//! known answer), and `study::sweep`, a resumable, shardable map over parameter points.
//! Type: `WorkPrecision`.

use crate::io::csv::RoundTrip;
use crate::study::WorkPrecisionPoint;
use rhai::plugin::*;
use rhai::{Array, Dynamic, Engine, Map, Module, NativeCallContext, INT};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// A plain script value: what a `study::sweep` point, its inputs and its result may be.
/// Stored bit-exactly (floats as their 8 bytes) and keyed canonically (maps sorted).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum Plain {
    /// `()`.
    Unit,
    /// A bool.
    Bool(bool),
    /// An integer.
    Int(INT),
    /// A float.
    Float(f64),
    /// A string.
    Text(String),
    /// An array.
    List(Vec<Plain>),
    /// An object map.
    Map(BTreeMap<String, Plain>),
}

impl Plain {
    /// `value` as plain data; `what` names it in the error for anything else (a Signal, a
    /// Scene: results that cannot be stored are refused, not dropped).
    pub fn of(value: &Dynamic, what: &str) -> Result<Plain, String> {
        if value.is_unit() {
            Ok(Plain::Unit)
        } else if let Ok(b) = value.as_bool() {
            Ok(Plain::Bool(b))
        } else if let Ok(i) = value.as_int() {
            Ok(Plain::Int(i))
        } else if let Ok(f) = value.as_float() {
            Ok(Plain::Float(f))
        } else if value.is_string() {
            Ok(Plain::Text(value.to_string()))
        } else if let Some(list) = value.read_lock::<Array>() {
            list.iter()
                .enumerate()
                .map(|(i, v)| Plain::of(v, &format!("{what}[{i}]")))
                .collect::<Result<_, _>>()
                .map(Plain::List)
        } else if let Some(map) = value.read_lock::<Map>() {
            map.iter()
                .map(|(k, v)| Ok((k.to_string(), Plain::of(v, &format!("{what}.{k}"))?)))
                .collect::<Result<_, String>>()
                .map(Plain::Map)
        } else {
            Err(format!(
                "{what} is a {}: a sweep stores plain values only (numbers, strings, bools, \
                 arrays, maps); return e.g. a summary map instead",
                value.type_name().rsplit("::").next().unwrap_or_default()
            ))
        }
    }

    /// Back to a script value.
    pub fn into_dynamic(self) -> Dynamic {
        match self {
            Plain::Unit => Dynamic::UNIT,
            Plain::Bool(b) => b.into(),
            Plain::Int(i) => i.into(),
            Plain::Float(f) => f.into(),
            Plain::Text(t) => t.into(),
            Plain::List(l) => l
                .into_iter()
                .map(Plain::into_dynamic)
                .collect::<Array>()
                .into(),
            Plain::Map(m) => m
                .into_iter()
                .map(|(k, v)| (k.into(), v.into_dynamic()))
                .collect::<Map>()
                .into(),
        }
    }
}

/// `study::sweep`: calls `f` on each point this run computes (in order; native work inside
/// `f` runs in parallel as usual), recording each result or error; see [`crate::sweep`].
fn sweep(
    ctx: &NativeCallContext,
    name: &str,
    inputs: &Dynamic,
    points: &Array,
    f: &rhai::FnPtr,
) -> Result<Array, Box<rhai::EvalAltResult>> {
    use crate::script::convert::error;
    use crate::sweep::{Key, PointSpec, Sweep};
    let inputs = Plain::of(inputs, "inputs").map_err(|e| error(ctx, e))?;
    let specs = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let point = Plain::of(p, &format!("points[{i}]")).map_err(|e| error(ctx, e))?;
            Ok(PointSpec {
                key: Key::of("sweep", &(name, &inputs, &point)).map_err(|e| error(ctx, e))?,
                label: p.to_string(),
                sharded: true,
            })
        })
        .collect::<Result<Vec<_>, Box<rhai::EvalAltResult>>>()?;
    let sweep = Sweep::start(&format!("sweep '{name}'"), "sweep", specs);
    for &i in sweep.pending() {
        let start = std::time::Instant::now();
        let outcome = match f.call_within_context::<Dynamic>(ctx, (points[i].clone(),)) {
            Ok(value) => Plain::of(&value, &format!("the result of points[{i}]"))
                .map_err(crate::Error::Named),
            // Time limit, operation limit, Ctrl-C, a finished shard: stop the sweep.
            Err(e) if !e.is_catchable() => return Err(e),
            Err(e) => Err(crate::Error::Named(e.to_string())),
        };
        sweep
            .record(i, outcome, start.elapsed().as_secs_f64(), "")
            .map_err(|e| error(ctx, e))?;
    }
    let values: Vec<Plain> = sweep
        .finish()
        .map_err(|e| crate::script::sweep_error(ctx, e))?;
    Ok(values.into_iter().map(Plain::into_dynamic).collect())
}

/// The points of a work-precision study.
pub type WorkPrecision = Arc<Vec<WorkPrecisionPoint>>;

/// Registers the display name of the custom type.
pub fn register_types(engine: &mut Engine) {
    engine.register_type_with_name::<WorkPrecision>("WorkPrecision");
}

/// The `study` module.
pub fn module() -> Module {
    exported_module!(study_api)
}

#[export_module]
mod study_api {
    use super::WorkPrecision;
    use crate::script::convert::{error, options, to_dynamic, WithPosition};
    use crate::script::HostContext;
    use crate::study::WorkPrecisionSpec;
    use rhai::{Array, Dynamic, FnPtr, Map, NativeCallContext};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Maps `f` over `points` as a resumable sweep: each point's result (a plain value: numbers, strings, bools, arrays, maps) is stored under points/sweep/, keyed by `name`, `inputs` (a map of everything else the results depend on: change `name` when `f` changes) and the point. A rerun computes only missing points, `--shard I/N` computes a share, `--merge` only assembles; a failing point is recorded with its error while the others go on, and the sweep then fails naming it.
    #[rhai_fn(name = "sweep", return_raw)]
    pub fn sweep_points(
        ctx: NativeCallContext,
        name: &str,
        inputs: Dynamic,
        points: Array,
        f: FnPtr,
    ) -> Res<Array> {
        super::sweep(&ctx, name, &inputs, &points, &f)
    }

    /// Calls `f` with no point store: the first passes it runs (impulse responses, TR-NEWS) are computed, never read from or written to points/, so that its run time is the computation's (for timing studies).
    #[rhai_fn(return_raw)]
    pub fn uncached(ctx: NativeCallContext, f: FnPtr) -> Res<Dynamic> {
        crate::sweep::without_store(|| f.call_within_context::<Dynamic>(&ctx, ()))
    }

    /// Default work-precision parameters #{element_sizes_m, explicit_fractions, newmark_multiples, depth_m, pulse_width_s}.
    #[rhai_fn(return_raw)]
    pub fn default_work_precision(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &WorkPrecisionSpec::default())
    }

    /// Runs the plane-P-wave work-precision study (explicit and Newmark over element sizes and steps) with options over the defaults.
    #[rhai_fn(return_raw)]
    pub fn work_precision(ctx: NativeCallContext, spec: Map) -> Res<WorkPrecision> {
        let spec: WorkPrecisionSpec =
            options(&ctx, spec, &WorkPrecisionSpec::default(), "work_precision")?;
        Ok(Arc::new(crate::study::work_precision(&spec).at(&ctx)?))
    }

    /// The study's points as maps #{discretisation, order, integrator, element_size_m, dt_s, stability_ratio, dofs, error, run_time_s, report}.
    #[rhai_fn(global, get = "points", pure, return_raw)]
    pub fn points(ctx: NativeCallContext, wp: &mut WorkPrecision) -> Res<Dynamic> {
        to_dynamic(&ctx, wp.as_ref())
    }

    /// Writes the study as CSV: discretisation (t3 or sem), order, integrator, element size, dt, dt/dt_crit, DOFs, steps, error, run time, energy residual.
    #[rhai_fn(global, return_raw)]
    pub fn write_csv(ctx: NativeCallContext, wp: WorkPrecision, path: &str) -> Res<()> {
        let file = HostContext::of(&ctx)?
            .resolve_output(path)
            .map_err(|e| error(&ctx, e))?;
        let rows: Vec<WorkPrecisionRow> = wp.iter().map(WorkPrecisionRow::of).collect();
        crate::io::csv::write_rows(&file, &rows).at(&ctx)
    }
}

/// One CSV row of a work-precision study; the field names are the column names.
#[derive(Serialize)]
struct WorkPrecisionRow<'a> {
    discretisation: &'a str,
    order: usize,
    integrator: &'a str,
    element_size_m: RoundTrip,
    dt_s: RoundTrip,
    dt_over_dt_crit: RoundTrip,
    dofs: usize,
    steps: usize,
    error: RoundTrip,
    run_time_s: RoundTrip,
    energy_residual_peak: RoundTrip,
}

impl<'a> WorkPrecisionRow<'a> {
    /// The row of point `p`.
    fn of(p: &'a WorkPrecisionPoint) -> Self {
        WorkPrecisionRow {
            discretisation: &p.discretisation,
            order: p.order,
            integrator: &p.integrator,
            element_size_m: RoundTrip(p.element_size_m),
            dt_s: RoundTrip(p.dt_s),
            dt_over_dt_crit: RoundTrip(p.stability_ratio),
            dofs: p.dofs,
            steps: p.report.steps,
            error: RoundTrip(p.error),
            run_time_s: RoundTrip(p.run_time_s),
            energy_residual_peak: RoundTrip(p.report.energy_residual_peak),
        }
    }
}
