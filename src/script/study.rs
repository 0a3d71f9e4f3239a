//! Rhai module `study`: the work-precision study (error against run time on a problem with a
//! known answer). Type: `WorkPrecision`.

use crate::study::WorkPrecisionPoint;
use rhai::plugin::*;
use rhai::{Engine, Module};
use std::sync::Arc;

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
    use rhai::{Dynamic, Map, NativeCallContext};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

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

    /// The study's points as maps #{integrator, element_size_m, dt_s, stability_ratio, dofs, error, run_time_s, report}.
    #[rhai_fn(global, get = "points", pure, return_raw)]
    pub fn points(ctx: NativeCallContext, wp: &mut WorkPrecision) -> Res<Dynamic> {
        to_dynamic(&ctx, wp.as_ref())
    }

    /// Writes the study as CSV: integrator, element size, dt, dt/dt_crit, DOFs, steps, error, run time, energy residual.
    #[rhai_fn(global, return_raw)]
    pub fn write_csv(ctx: NativeCallContext, wp: WorkPrecision, path: &str) -> Res<()> {
        let file = HostContext::of(&ctx)?
            .resolve_output(path)
            .map_err(|e| error(&ctx, e))?;
        let headers: Vec<String> = [
            "integrator",
            "element_size_m",
            "dt_s",
            "dt_over_dt_crit",
            "dofs",
            "steps",
            "error",
            "run_time_s",
            "energy_residual_peak",
        ]
        .map(String::from)
        .to_vec();
        let rows: Vec<Vec<String>> = wp
            .iter()
            .map(|p| {
                let f = crate::io::fmt_f64;
                vec![
                    p.integrator.clone(),
                    f(p.element_size_m),
                    f(p.dt_s),
                    f(p.stability_ratio),
                    p.dofs.to_string(),
                    p.report.steps.to_string(),
                    f(p.error),
                    f(p.run_time_s),
                    f(p.report.energy_residual_peak),
                ]
            })
            .collect();
        crate::io::write_csv_rows(&file, &headers, &rows).at(&ctx)
    }
}
