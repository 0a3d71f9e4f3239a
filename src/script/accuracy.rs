//! Rhai module `accuracy`: discretisation error estimates (type `Estimate`), the ones the
//! TR-NEWS procedures attach with `error_estimate: true` and estimates of a script's own
//! quantities from runs on a scene and its companions (h, 2h, 4h on triangles; orders p,
//! p - 1, p - 2 along x, one more across and, with contact, half the step on spectral elements;
//! see [`crate::accuracy`]).
//! The overloads without a scene take three values at h, 2h, 4h on triangles.

use crate::accuracy::Estimate;
use rhai::plugin::*;
use rhai::{Engine, Module};

/// Registers the display name of `Estimate`.
pub fn register_types(engine: &mut Engine) {
    engine.register_type_with_name::<Estimate>("Estimate");
}

/// The `accuracy` module.
pub fn module() -> Module {
    exported_module!(accuracy_api)
}

#[export_module]
mod accuracy_api {
    use crate::accuracy::{Estimate, Refinement, Verdict};
    use crate::script::convert::{floats, WithPosition};
    use crate::script::scene::SceneRef;
    use crate::signal::Signal;
    use rhai::{Array, Dynamic, NativeCallContext, FLOAT};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Richardson estimate of a dimensional scalar from its values at element sizes h, 2h, 4h (T3 order 2).
    pub fn scalar(fine: FLOAT, medium: FLOAT, coarse: FLOAT) -> Estimate {
        Estimate::scalar(fine, medium, coarse, Refinement::ElementSizes)
    }

    /// Estimate of a dimensional scalar from its `values` on `scene` and on each of `scene.companions()`, in that order (2h and 4h on triangles; orders p - 1 and p - 2 along x, then one more across, then half the step where a crack's faces touch, on spectral elements).
    #[rhai_fn(name = "scalar", return_raw)]
    pub fn scalar_of(ctx: NativeCallContext, values: Array, scene: SceneRef) -> Res<Estimate> {
        let values = floats(&ctx, &values.into(), "values")?;
        Estimate::scalar_of(&values, scene.spec.refinement()).at(&ctx)
    }

    /// Richardson estimate of a dimensionless measure of order one (misfit, residual, asymmetry) at h, 2h, 4h; changes below 1e-10 are round-off.
    pub fn dimensionless(fine: FLOAT, medium: FLOAT, coarse: FLOAT) -> Estimate {
        Estimate::dimensionless(fine, medium, coarse, Refinement::ElementSizes)
    }

    /// Richardson estimate of the relative L2 error of the trace `fine` over t_start_s..t_end_s from the same trace at 2h (`medium`) and 4h (`coarse`), resampled to the fine step.
    #[rhai_fn(return_raw)]
    pub fn waveform(
        ctx: NativeCallContext,
        fine: Signal,
        medium: Signal,
        coarse: Signal,
        t_start_s: FLOAT,
        t_end_s: FLOAT,
    ) -> Res<Estimate> {
        Estimate::waveform(
            &fine,
            &medium,
            &coarse,
            (t_start_s, t_end_s),
            Refinement::ElementSizes,
        )
        .at(&ctx)
    }

    /// Estimate of a dimensionless measure of order one from its `values` on `scene` and on each of `scene.companions()`, in that order; changes below 1e-10 are round-off.
    #[rhai_fn(name = "dimensionless", return_raw)]
    pub fn dimensionless_of(
        ctx: NativeCallContext,
        values: Array,
        scene: SceneRef,
    ) -> Res<Estimate> {
        let values = floats(&ctx, &values.into(), "values")?;
        Estimate::dimensionless_of(&values, scene.spec.refinement()).at(&ctx)
    }

    /// Estimate of the relative L2 error over t_start_s..t_end_s of the first of `traces`, recorded on `scene`, from the same trace on each of `scene.companions()` (the rest of `traces`, in that order), resampled to the first's step.
    #[rhai_fn(name = "waveform", return_raw)]
    pub fn waveform_of(
        ctx: NativeCallContext,
        traces: Array,
        t_start_s: FLOAT,
        t_end_s: FLOAT,
        scene: SceneRef,
    ) -> Res<Estimate> {
        let traces = traces
            .into_iter()
            .map(|t| {
                t.try_cast::<Signal>().ok_or_else(|| {
                    crate::script::convert::error(
                        &ctx,
                        "accuracy::waveform: traces must be signals",
                    )
                })
            })
            .collect::<Res<Vec<Signal>>>()?;
        let traces: Vec<&Signal> = traces.iter().collect();
        let refinement = scene.spec.refinement();
        Estimate::waveform_of(&traces, (t_start_s, t_end_s), refinement).at(&ctx)
    }

    /// The difference |Q - Q_across| (waveforms: relative L2) to the companion one order higher across; () without that companion.
    #[rhai_fn(global, get = "across", pure)]
    pub fn across(e: &mut Estimate) -> Dynamic {
        e.across.map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// The error across the layers, sqrt(2) times `across` (between 1 and 2 times it when an order across at least halves the error), included in `error`; () without the companion across.
    #[rhai_fn(global, get = "across_error", pure)]
    pub fn across_error(e: &mut Estimate) -> Dynamic {
        e.across_error().map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// The difference |Q - Q_dt/2| (waveforms: relative L2) to the companion at half the step (scenes with contact); () without that companion.
    #[rhai_fn(global, get = "step", pure)]
    pub fn step(e: &mut Estimate) -> Dynamic {
        e.step.map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// The error in time, sqrt(2) times `step` (within a factor 2 of the error at first or second order in the step, and of a value that scatters with it), included in `error`; () without the companion at half the step.
    #[rhai_fn(global, get = "step_error", pure)]
    pub fn step_error(e: &mut Estimate) -> Dynamic {
        e.step_error().map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// The largest source of the error, "along x", "across the layers" or "in time", when the estimate has a companion across or at half the step and states an error; () otherwise.
    #[rhai_fn(global, get = "dominant_source", pure)]
    pub fn dominant_source(e: &mut Estimate) -> Dynamic {
        e.dominant_source()
            .map_or(Dynamic::UNIT, |s| Dynamic::from(s.name().to_string()))
    }

    /// Value on the main discretisation (0 for a waveform, whose error is relative).
    #[rhai_fn(global, get = "value", pure)]
    pub fn value(e: &mut Estimate) -> FLOAT {
        e.value
    }

    /// Estimated |error| of the value (waveforms: relative L2) or its bound, or () when the verdict is "refine".
    #[rhai_fn(global, get = "error", pure)]
    pub fn error(e: &mut Estimate) -> Dynamic {
        e.error.map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// Observed order of convergence from the three discretisations, or ().
    #[rhai_fn(global, get = "observed_order", pure)]
    pub fn observed_order(e: &mut Estimate) -> Dynamic {
        e.observed_order.map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// Values on the refinement's two companions, [2h, 4h] or [order p - 1, order p - 2] (waveforms: relative differences [main vs first, first vs second]).
    #[rhai_fn(global, get = "companions", pure)]
    pub fn companions(e: &mut Estimate) -> Array {
        e.companions.iter().map(|&v| Dynamic::from(v)).collect()
    }

    /// "reliable", "upper_bound" (converging faster than the scheme's order: `error` bounds it), "propagated_bound" (a measure of traces, such as a misfit, PI residual, side-lobe asymmetry or spectral shift, whose own values do not converge: `error` bounds it through the errors of the traces it is computed from), "refine" (not in the asymptotic range: no error claimed) or "mesh_independent".
    #[rhai_fn(global, get = "verdict", pure)]
    pub fn verdict(e: &mut Estimate) -> String {
        match e.verdict {
            Verdict::Reliable => "reliable",
            Verdict::UpperBound => "upper_bound",
            Verdict::Propagated => "propagated_bound",
            Verdict::Refine => "refine",
            Verdict::MeshIndependent => "mesh_independent",
        }
        .into()
    }

    /// CSV columns [error, observed_order, verdict] of an estimate (empty strings where it has none), or ["", "", "off"] for () (no error estimate).
    #[rhai_fn(return_raw)]
    pub fn columns(ctx: NativeCallContext, e: Dynamic) -> Res<Array> {
        if e.is_unit() {
            return Ok(vec!["".into(), "".into(), "off".into()]);
        }
        let mut e = e.try_cast::<Estimate>().ok_or_else(|| {
            crate::script::convert::error(&ctx, "accuracy::columns needs an Estimate or ()")
        })?;
        let text = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
        Ok(vec![
            text(e.error).into(),
            text(e.observed_order).into(),
            verdict(&mut e).into(),
        ])
    }

    /// The check of a requested accuracy after a run: "met", "not met" or "unknown" with the estimate, for a relative `tolerance` (waveforms: relative L2 error; scalars: error relative to the value).
    pub fn check(e: Estimate, tolerance: FLOAT) -> String {
        let relative = |err: f64| {
            if e.waveform {
                err
            } else {
                err / e.value.abs()
            }
        };
        match (e.verdict, e.error) {
            (Verdict::MeshIndependent, _) => "met (unchanged between meshes)".to_string(),
            (Verdict::Reliable | Verdict::UpperBound | Verdict::Propagated, Some(err))
                if relative(err) <= tolerance =>
            {
                format!("met: {} <= {tolerance}", e.describe())
            }
            (Verdict::Reliable, Some(_)) => format!("not met: {} > {tolerance}", e.describe()),
            _ => format!("unknown: {}", e.describe()),
        }
    }

    /// A short form for figure titles, e.g. "0.138 (err ?, 2h: 1.3e-2)", or "err 3.1%" / "err ? (2h: 30%)" for a waveform.
    #[rhai_fn(global, get = "brief", pure)]
    pub fn brief(e: &mut Estimate) -> String {
        e.brief()
    }

    /// The estimate in words: value +- error with the observed order, or why no error is claimed.
    #[rhai_fn(global, name = "to_string", pure)]
    pub fn to_string(e: &mut Estimate) -> String {
        e.describe()
    }
}
