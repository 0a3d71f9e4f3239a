//! Rhai module `figure`: the report's figures from results (PNG or SVG by extension).

use crate::script::convert::{error, ScriptResult};
use crate::script::HostContext;
use rhai::plugin::*;
use rhai::{Array, Module, NativeCallContext};
use std::path::PathBuf;

/// The `figure` module.
pub fn module() -> Module {
    exported_module!(figure_api)
}

/// The output path under the host's output directory.
fn output(ctx: &NativeCallContext, path: &str) -> ScriptResult<PathBuf> {
    HostContext::of(ctx)?
        .resolve_output(path)
        .map_err(|e| error(ctx, e))
}

/// Pairs [label, T] from an array of two-element arrays.
fn labelled<T: Clone + 'static>(
    ctx: &NativeCallContext,
    list: &Array,
    what: &str,
) -> ScriptResult<Vec<(String, T)>> {
    list.iter()
        .enumerate()
        .map(|(i, item)| {
            let pair = item
                .read_lock::<Array>()
                .filter(|a| a.len() == 2)
                .ok_or_else(|| error(ctx, format!("{what}[{i}] must be [label, value]")))?;
            let label = pair[0]
                .clone()
                .into_string()
                .map_err(|t| error(ctx, format!("{what}[{i}][0] must be a string, got {t}")))?;
            let value = pair[1].read_lock::<T>().map(|v| v.clone()).ok_or_else(|| {
                error(
                    ctx,
                    format!("{what}[{i}][1] has the wrong type {}", pair[1].type_name()),
                )
            })?;
            Ok((label, value))
        })
        .collect()
}

#[export_module]
mod figure_api {
    use super::{labelled, output};
    use crate::figures;
    use crate::script::convert::WithPosition;
    use crate::script::scene::{index, RunRef, SceneRef};
    use crate::script::study::WorkPrecision;
    use crate::script::trnews::TrNewsRef;
    use crate::signal::Signal;
    use crate::trnews::Delayed;
    use rhai::{Array, NativeCallContext, FLOAT, INT};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// TR-NEWS focusing, one panel per focused receiver, one curve per [label, TrNews] (report Figs 15, 18).
    #[rhai_fn(return_raw)]
    pub fn focusing(ctx: NativeCallContext, path: &str, title: &str, results: Array) -> Res<()> {
        let results = labelled::<TrNewsRef>(&ctx, &results, "results")?;
        let refs: Vec<(&str, &crate::trnews::TrNews)> = results
            .iter()
            .map(|(l, t)| (l.as_str(), t.as_ref()))
            .collect();
        figures::focusing(&output(&ctx, path)?, title, &refs).at(&ctx)
    }

    /// Focused signals with their pulse-inversion sums per receiver (Fig. 16) and, in envelope_path, the PI envelopes (Fig. 17).
    #[rhai_fn(return_raw)]
    pub fn pulse_inversion(
        ctx: NativeCallContext,
        path: &str,
        envelope_path: &str,
        tr: TrNewsRef,
    ) -> Res<()> {
        figures::pulse_inversion(
            &output(&ctx, path)?,
            Some(&output(&ctx, envelope_path)?),
            &tr,
        )
        .at(&ctx)
    }

    /// Welch spectra in dB of [label, Signal] pairs up to max_mhz (Figs 20, 21).
    #[rhai_fn(return_raw)]
    pub fn spectra(
        ctx: NativeCallContext,
        path: &str,
        title: &str,
        signals: Array,
        max_mhz: FLOAT,
    ) -> Res<()> {
        let signals = labelled::<Signal>(&ctx, &signals, "signals")?;
        let refs: Vec<(&str, &Signal)> = signals.iter().map(|(l, s)| (l.as_str(), s)).collect();
        figures::spectra(&output(&ctx, path)?, title, &refs, max_mhz).at(&ctx)
    }

    /// Delayed TR-NEWS: linear prediction vs simulation over the focus window (Fig. 22).
    #[rhai_fn(return_raw)]
    pub fn delayed(ctx: NativeCallContext, path: &str, title: &str, d: Delayed) -> Res<()> {
        figures::delayed(&output(&ctx, path)?, title, &d).at(&ctx)
    }

    /// Snapshot `k` (1-based) of a run of `scene`: displacement component (0 = u_x, 1 = u_y) with layer interfaces and the crack (Fig. 19).
    #[rhai_fn(return_raw)]
    pub fn snapshot(
        ctx: NativeCallContext,
        path: &str,
        scene: SceneRef,
        run: RunRef,
        k: INT,
        component: INT,
    ) -> Res<()> {
        let snap = &run.snapshots[index(&ctx, k, run.snapshots.len(), "snapshot")?];
        figures::snapshot(
            &output(&ctx, path)?,
            &scene,
            snap,
            usize::from(component == 1),
        )
        .at(&ctx)
    }

    /// The field scattered by the crack (Fig. 19, the crack as a new source): snapshot `k` of a run of the cracked `scene` minus snapshot `k` of the same transmission on its crack-tied companion (`scene.uncracked()`: same mesh and step), component 0 = u_x, 1 = u_y.
    #[rhai_fn(return_raw)]
    pub fn scattered_snapshot(
        ctx: NativeCallContext,
        path: &str,
        scene: SceneRef,
        cracked_run: RunRef,
        tied_run: RunRef,
        k: INT,
        component: INT,
    ) -> Res<()> {
        let snap = &cracked_run.snapshots[index(&ctx, k, cracked_run.snapshots.len(), "snapshot")?];
        let tied = &tied_run.snapshots[index(&ctx, k, tied_run.snapshots.len(), "snapshot")?];
        figures::scattered_snapshot(
            &output(&ctx, path)?,
            &scene,
            snap,
            tied,
            usize::from(component == 1),
        )
        .at(&ctx)
    }

    /// Error against run time on log-log axes from a work-precision study.
    #[rhai_fn(return_raw)]
    pub fn work_precision(ctx: NativeCallContext, path: &str, wp: WorkPrecision) -> Res<()> {
        figures::work_precision(&output(&ctx, path)?, &wp).at(&ctx)
    }

    /// The energy ledger of a run over time.
    #[rhai_fn(return_raw)]
    pub fn ledger(ctx: NativeCallContext, path: &str, title: &str, run: RunRef) -> Res<()> {
        figures::ledger(&output(&ctx, path)?, title, &run.ledger).at(&ctx)
    }
}
