//! Rhai module `trnews`: the TR-NEWS procedure, delayed TR-NEWS, pulse inversion and scans.
//! Types: `Responder`, `TrNews`, `Focus`, `Delayed`, `Scan`.

use crate::accuracy::Estimate;
use crate::script::convert::{error, floats, ScriptResult};
use crate::trnews::{Delayed, Focus, Responder, TrNews};
use rhai::plugin::*;
use rhai::{Array, Dynamic, Engine, Map, Module, NativeCallContext};
use std::sync::Arc;

/// A TR-NEWS result shared by its focus and delayed objects.
pub type TrNewsRef = Arc<TrNews>;

/// A scan, shared by the script values that read it.
pub type ScanRef = Arc<crate::trnews::Scan>;

/// Options of `trnews::scan(responder, spec, options)`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScanOptions {
    /// The receivers scanned (1-based); empty = all.
    pub receivers: Vec<usize>,
    /// The delayed drive's delays (s).
    pub delays_s: Vec<f64>,
    /// The delayed drive's amplitudes, one per delay.
    pub amplitudes: Vec<f64>,
    /// The misfit window's half width around the focus times (s).
    pub half_window_s: f64,
    /// Focus at every position (true), or survey: the chirp run only, for the spectral
    /// shifts (false).
    pub focus: bool,
}

impl Default for ScanOptions {
    /// Every receiver; the delayed drive tau = [0, 1 us], a = [1, 1] (the report's Fig. 22
    /// point with the largest misfit), the delayed sweep's 5 us half window.
    fn default() -> Self {
        ScanOptions {
            receivers: Vec::new(),
            delays_s: vec![0.0, 1e-6],
            amplitudes: vec![1.0, 1.0],
            half_window_s: 5e-6,
            focus: true,
        }
    }
}

/// Registers the display names of the custom types.
pub fn register_types(engine: &mut Engine) {
    engine
        .register_type_with_name::<Responder>("Responder")
        .register_type_with_name::<TrNewsRef>("TrNews")
        .register_type_with_name::<Focus>("Focus")
        .register_type_with_name::<Delayed>("Delayed")
        .register_type_with_name::<ScanRef>("Scan");
}

/// Options of `trnews::responder(scene, duration_s, options)`.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ResponderOptions {
    /// Repeat every procedure on the scene's companions (2x and 4x the element sizes on
    /// triangles; on spectral elements one and two orders lower along x and one higher
    /// across) and report error estimates
    /// (see `accuracy`): true, false, or "auto" (on when the companions cost at most 30% of
    /// the main runs, [`crate::trnews::AUTO_ESTIMATE_MAX_COST`]).
    pub error_estimate: crate::trnews::ErrorEstimate,
    /// The time step as a fraction of the scene's dt_crit, in (0, 1]: below the default 0.9
    /// to measure or shrink the central-difference time error (O(dt^2)). Not given: the
    /// scene's step (its `time_step_s`, else 0.9 dt_crit).
    pub step_fraction: Option<f64>,
}

/// The companion scenes of an error estimate when `choice` asks for one
/// ([`Responder::estimate_decision`]), printing why not when "auto" finds them too costly.
pub(crate) fn companions_wanted(
    ctx: &NativeCallContext,
    r: &Responder,
    choice: crate::trnews::ErrorEstimate,
) -> ScriptResult<Option<Vec<Arc<crate::scene::Scene>>>> {
    use crate::script::WithPosition;
    use crate::trnews::{EstimateDecision, AUTO_ESTIMATE_MAX_COST};
    match r.estimate_decision(choice).at(ctx)? {
        EstimateDecision::Off => Ok(None),
        EstimateDecision::On(scenes) => Ok(Some(scenes)),
        EstimateDecision::TooCostly { cost } => {
            crate::script::HostContext::of(ctx)?.print(&format!(
                "error estimate off: the companions at {} would add {:.0}% to the run \
                 time (auto allows {:.0}%); results carry no discretisation error \
                 (error_estimate = true turns it on)",
                r.companions_named().at(ctx)?,
                100.0 * cost,
                100.0 * AUTO_ESTIMATE_MAX_COST
            ));
            Ok(None)
        }
    }
}

/// Options of `trnews::channel_from_impulse` and `trnews::channel_from_recordings`.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChannelOptions {
    /// Peak of the drive signals: the chirp's amplitude and the focusing signals' peak (in
    /// the drive's unit, e.g. Pa or V).
    pub peak_drive: f64,
    /// The band the traces were recorded in, for titles and printed results.
    pub band: String,
}

impl Default for ChannelOptions {
    fn default() -> Self {
        ChannelOptions {
            peak_drive: 1.0,
            band: "band as recorded".into(),
        }
    }
}

/// Signals from an array, naming `what[i]` when an element is not a Signal.
fn signal_list(
    ctx: &NativeCallContext,
    list: &Array,
    what: &str,
) -> ScriptResult<Vec<crate::signal::Signal>> {
    list.iter()
        .enumerate()
        .map(|(i, t)| {
            t.read_lock::<crate::signal::Signal>()
                .map(|s| s.clone())
                .ok_or_else(|| {
                    error(
                        ctx,
                        format!("{what}[{i}] must be a Signal, got {}", t.type_name()),
                    )
                })
        })
        .collect()
}

/// Recordings from an array of maps #{sent: Signal, received: [Signal]} (no other fields).
fn recordings(
    ctx: &NativeCallContext,
    list: &Array,
) -> ScriptResult<Vec<crate::trnews::Recording>> {
    list.iter()
        .enumerate()
        .map(|(i, item)| {
            let map = item.read_lock::<Map>().ok_or_else(|| {
                error(
                    ctx,
                    format!(
                        "recordings[{i}] must be a map #{{sent, received}}, got {}",
                        item.type_name()
                    ),
                )
            })?;
            if let Some(k) = map
                .keys()
                .find(|k| !["sent", "received"].contains(&k.as_str()))
            {
                return Err(error(
                    ctx,
                    format!("recordings[{i}].{k}: unknown field (expected sent, received)"),
                ));
            }
            let field = |name: &str| {
                map.get(name)
                    .ok_or_else(|| error(ctx, format!("recordings[{i}] has no field '{name}'")))
            };
            let sent = field("sent")?
                .read_lock::<crate::signal::Signal>()
                .map(|s| s.clone())
                .ok_or_else(|| error(ctx, format!("recordings[{i}].sent must be a Signal")))?;
            let received = field("received")?
                .read_lock::<Array>()
                .map(|a| a.clone())
                .ok_or_else(|| {
                    error(
                        ctx,
                        format!("recordings[{i}].received must be an array of Signals"),
                    )
                })?;
            Ok(crate::trnews::Recording {
                sent,
                received: signal_list(ctx, &received, &format!("recordings[{i}].received"))?,
            })
        })
        .collect()
}

/// A map of named estimates as Rhai values.
fn estimate_map(entries: Vec<(&str, Estimate)>) -> Dynamic {
    entries
        .into_iter()
        .map(|(k, e)| (k.into(), Dynamic::from(e)))
        .collect::<Map>()
        .into()
}

/// The `trnews` module.
pub fn module() -> Module {
    exported_module!(trnews_api)
}

/// Delay points from an array of maps #{delays: [...], amplitudes: [...]}: as many delays as
/// amplitudes, delays finite and >= 0, amplitudes finite (checked here, so that a bad point
/// is an error naming it, not a failed work unit).
fn points(ctx: &NativeCallContext, list: &Array) -> ScriptResult<Vec<(Vec<f64>, Vec<f64>)>> {
    list.iter()
        .enumerate()
        .map(|(i, p)| {
            let map = p.read_lock::<Map>().ok_or_else(|| {
                error(
                    ctx,
                    format!("points[{i}] must be a map #{{delays, amplitudes}}"),
                )
            })?;
            let field = |name: &str| {
                map.get(name)
                    .ok_or_else(|| error(ctx, format!("points[{i}] has no field '{name}'")))
            };
            let delays = floats(ctx, field("delays")?, &format!("points[{i}].delays"))?;
            let amplitudes = floats(
                ctx,
                field("amplitudes")?,
                &format!("points[{i}].amplitudes"),
            )?;
            if let Some(bad) = delays.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
                return Err(error(
                    ctx,
                    format!("points[{i}].delays has {bad}: delays must be finite and >= 0"),
                ));
            }
            if let Some(bad) = amplitudes.iter().find(|a| !a.is_finite()) {
                return Err(error(
                    ctx,
                    format!("points[{i}].amplitudes has {bad}: amplitudes must be finite"),
                ));
            }
            if delays.len() != amplitudes.len() {
                return Err(error(
                    ctx,
                    format!(
                        "points[{i}] has {} delays and {} amplitudes: give one amplitude per delay",
                        delays.len(),
                        amplitudes.len()
                    ),
                ));
            }
            Ok((delays, amplitudes))
        })
        .collect()
}

/// A response as the map #{traces: [Signal], report: map or ()}.
fn response_map(ctx: &NativeCallContext, out: crate::trnews::Response) -> ScriptResult<Dynamic> {
    let mut m = Map::new();
    m.insert(
        "traces".into(),
        out.traces
            .into_iter()
            .map(Dynamic::from)
            .collect::<Array>()
            .into(),
    );
    let report = match &out.report {
        Some(rep) => crate::script::convert::to_dynamic(ctx, rep)?,
        None => Dynamic::UNIT,
    };
    m.insert("report".into(), report);
    Ok(m.into())
}

#[export_module]
mod trnews_api {
    use super::{estimate_map, points, ResponderOptions, ScanOptions, ScanRef, TrNewsRef};
    use crate::script::convert::{options, to_dynamic, WithPosition};
    use crate::script::scene::{index, SceneRef};
    use crate::signal::Signal;
    use crate::trnews::{tr_news, Delayed, Focus, Responder, TrNewsSpec};
    use rhai::{Array, Dynamic, Map, NativeCallContext, FLOAT, INT};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// The report's TR-NEWS parameters #{chirp: #{f0_hz, f1_hz, t1_s, total_s, taper_fraction}, record_s, window_s, after_focus_s, receivers, pulse_inversion, main_lobe_half_width_s}.
    #[rhai_fn(return_raw)]
    pub fn default_spec(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &TrNewsSpec::default())
    }

    /// TR-NEWS parameters of a resolution preset: "smoke" (10 us chirp, 20 us window), "quick" or "paper" (the report's); any other name is an error.
    #[rhai_fn(return_raw)]
    pub fn preset_spec(ctx: NativeCallContext, name: &str) -> Res<Dynamic> {
        to_dynamic(&ctx, &TrNewsSpec::preset(name.parse().at(&ctx)?))
    }

    /// Duration of a focusing run for a TR-NEWS spec map: window_s + after_focus_s (s).
    #[rhai_fn(return_raw)]
    pub fn focus_duration(ctx: NativeCallContext, spec: Map) -> Res<FLOAT> {
        let spec: TrNewsSpec = options(&ctx, spec, &TrNewsSpec::default(), "tr_news")?;
        Ok(spec.focus_duration_s())
    }

    /// A responder for `scene`: a linear scene runs its impulse response once over `duration_s` and convolves afterwards; a cracked one simulates every transmission.
    #[rhai_fn(return_raw)]
    pub fn responder(ctx: NativeCallContext, scene: SceneRef, duration_s: FLOAT) -> Res<Responder> {
        Responder::new(scene, duration_s).at(&ctx)
    }

    /// A measured channel from one impulse response per receiver (Signals on one step: each receiver's response to a unit drive sample at t = 0, transducers included), with options #{peak_drive, band}: every transmission is the discrete convolution y_r[n] = sum_k s[k] h_r[n - k], and tr_news, delayed and pulse_inversion run on it as on a scene.
    #[rhai_fn(return_raw)]
    pub fn channel_from_impulse(
        ctx: NativeCallContext,
        impulse: Array,
        settings: Map,
    ) -> Res<Responder> {
        let o: super::ChannelOptions =
            options(&ctx, settings, &super::ChannelOptions::default(), "channel")?;
        let traces = super::signal_list(&ctx, &impulse, "impulse")?;
        Responder::from_impulse(traces, o.peak_drive, o.band).at(&ctx)
    }

    /// A channel of recorded responses from an array of #{sent: Signal, received: [Signal per receiver]}, with options #{peak_drive, band}: a transmission is answered by the recording of the same drive (relative L2 difference <= 1e-9) and refused, naming it, when it was not recorded.
    #[rhai_fn(return_raw)]
    pub fn channel_from_recordings(
        ctx: NativeCallContext,
        list: Array,
        settings: Map,
    ) -> Res<Responder> {
        let o: super::ChannelOptions =
            options(&ctx, settings, &super::ChannelOptions::default(), "channel")?;
        let recordings = super::recordings(&ctx, &list)?;
        if recordings.is_empty() {
            return Err(super::error(
                &ctx,
                "recordings is empty: give at least one #{sent, received}",
            ));
        }
        Responder::from_recordings(recordings, o.peak_drive, o.band).at(&ctx)
    }

    /// The channel's response to a unit drive sample at t = 0 over `duration_s`, per receiver (array of Signal), through the transducers: what channel_from_impulse takes.
    #[rhai_fn(global, pure, return_raw)]
    pub fn impulse_response(
        ctx: NativeCallContext,
        r: &mut Responder,
        duration_s: FLOAT,
    ) -> Res<Array> {
        let unit = Signal::new(r.dt_s(), 0.0, vec![1.0]).at(&ctx)?;
        Ok(r.respond(&unit, duration_s)
            .at(&ctx)?
            .traces
            .into_iter()
            .map(Dynamic::from)
            .collect())
    }

    /// Peak of the drive signals: the scene transmitter's peak traction (Pa), or a channel's peak_drive.
    #[rhai_fn(global, get = "peak_drive", pure)]
    pub fn peak_drive(r: &mut Responder) -> FLOAT {
        r.peak_drive()
    }

    /// A responder that simulates every transmission, even for a linear scene (for validation).
    pub fn simulating(scene: SceneRef) -> Responder {
        Responder::simulating(scene)
    }

    /// Solver step of the responses (s).
    #[rhai_fn(global, get = "dt", pure)]
    pub fn dt(r: &mut Responder) -> FLOAT {
        r.dt_s()
    }

    /// Report of the impulse-response run, or () when the responder simulates.
    #[rhai_fn(global, get = "impulse_report", pure, return_raw)]
    pub fn impulse_report(ctx: NativeCallContext, r: &mut Responder) -> Res<Dynamic> {
        r.impulse_report()
            .map_or(Ok(Dynamic::UNIT), |rep| to_dynamic(&ctx, rep))
    }

    /// Receivers' responses to `traction` (Pa) over `duration_s`: #{traces: [Signal], report: map or ()}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn respond(
        ctx: NativeCallContext,
        r: &mut Responder,
        traction: Signal,
        duration_s: FLOAT,
    ) -> Res<Dynamic> {
        let out = r.respond(&traction, duration_s).at(&ctx)?;
        super::response_map(&ctx, out)
    }

    /// Responses to several tractions (a parallel map over transmitted signals: independent simulations run concurrently, results identical for any thread count): an array of #{traces, report}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn respond_all(
        ctx: NativeCallContext,
        r: &mut Responder,
        tractions: Array,
        duration_s: FLOAT,
    ) -> Res<Array> {
        let signals = tractions
            .iter()
            .enumerate()
            .map(|(i, t)| {
                t.read_lock::<Signal>().map(|s| s.clone()).ok_or_else(|| {
                    super::error(
                        &ctx,
                        format!("tractions[{i}] must be a Signal, got {}", t.type_name()),
                    )
                })
            })
            .collect::<Result<Vec<Signal>, _>>()?;
        let responses = r.respond_all(&signals, duration_s).at(&ctx)?;
        responses
            .into_iter()
            .map(|out| super::response_map(&ctx, out))
            .collect()
    }

    /// Runs TR-NEWS (chirp -> y -> Gamma -> Gamma(T - t) -> focus) with options over the report's defaults.
    #[rhai_fn(global, name = "tr_news", return_raw)]
    pub fn run(ctx: NativeCallContext, r: Responder, spec: Map) -> Res<TrNewsRef> {
        let spec: TrNewsSpec = options(&ctx, spec, &TrNewsSpec::default(), "tr_news")?;
        Ok(Arc::new(tr_news(&r, &spec).at(&ctx)?))
    }

    /// The transmitted chirp c(t) (Pa).
    #[rhai_fn(global, get = "chirp", pure)]
    pub fn chirp(tr: &mut TrNewsRef) -> Signal {
        tr.chirp.clone()
    }

    /// First-pass responses y at every receiver (array of Signal).
    #[rhai_fn(global, get = "responses", pure)]
    pub fn responses(tr: &mut TrNewsRef) -> Array {
        tr.responses.iter().cloned().map(Dynamic::from).collect()
    }

    /// Report of the chirp run, or () when convolved.
    #[rhai_fn(global, get = "chirp_report", pure, return_raw)]
    pub fn chirp_report(ctx: NativeCallContext, tr: &mut TrNewsRef) -> Res<Dynamic> {
        tr.chirp_report
            .as_ref()
            .map_or(Ok(Dynamic::UNIT), |rep| to_dynamic(&ctx, rep))
    }

    /// The focusing at receiver `k` (1-based receiver number; it must have been focused).
    #[rhai_fn(global, pure, return_raw)]
    pub fn focus(ctx: NativeCallContext, tr: &mut TrNewsRef, k: INT) -> Res<Focus> {
        tr.focus
            .iter()
            .find(|f| f.receiver as INT == k)
            .cloned()
            .ok_or_else(|| {
                super::error(
                    &ctx,
                    format!("receiver {k} was not focused (options.receivers)"),
                )
            })
    }

    /// Receiver numbers that were focused.
    #[rhai_fn(global, get = "receivers", pure)]
    pub fn receivers(tr: &mut TrNewsRef) -> Array {
        tr.focus
            .iter()
            .map(|f| Dynamic::from(f.receiver as INT))
            .collect()
    }

    /// The focused signal y_TR at the receiver.
    #[rhai_fn(global, get = "focused", pure)]
    pub fn focused(f: &mut Focus) -> Signal {
        f.focused.clone()
    }

    /// The transmitted focusing signal Gamma(T - t) scaled to the peak traction (Pa).
    #[rhai_fn(global, get = "source", pure)]
    pub fn source(f: &mut Focus) -> Signal {
        f.source.clone()
    }

    /// The correlation Gamma(tau) over the lag window.
    #[rhai_fn(global, get = "gamma", pure)]
    pub fn gamma(f: &mut Focus) -> Signal {
        f.gamma.clone()
    }

    /// The pulse-inversion sum (focused + response to the inverted source), or ().
    #[rhai_fn(global, get = "pi_sum", pure)]
    pub fn pi_sum(f: &mut Focus) -> Dynamic {
        f.pi_sum.clone().map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// Peak of the focused signal #{time_s, amplitude, width_6db_s}.
    #[rhai_fn(global, get = "peak", pure, return_raw)]
    pub fn peak(ctx: NativeCallContext, f: &mut Focus) -> Res<Dynamic> {
        to_dynamic(&ctx, &f.peak)
    }

    /// Side-lobe measures around the focus #{main_peak, max_side_lobe_before, max_side_lobe_after, main_to_side_db, asymmetry, ...}.
    #[rhai_fn(global, get = "side_lobes", pure, return_raw)]
    pub fn side_lobes(ctx: NativeCallContext, f: &mut Focus) -> Res<Dynamic> {
        to_dynamic(&ctx, &f.side_lobes)
    }

    /// Reports of the focusing runs (empty when convolved).
    #[rhai_fn(global, get = "reports", pure, return_raw)]
    pub fn reports(ctx: NativeCallContext, f: &mut Focus) -> Res<Dynamic> {
        to_dynamic(&ctx, &f.reports)
    }

    /// Delayed TR-NEWS at receiver `k` for points [#{delays: [s...], amplitudes: [...]}]: simulations (in parallel) vs linear predictions; misfit over the focus window widened by half_window_s. Each point is a work unit stored under points/delayed/ (a rerun computes only missing points; --shard I/N computes a share of the simulated points, --merge only assembles).
    #[rhai_fn(global, return_raw)]
    pub fn delayed(
        ctx: NativeCallContext,
        r: Responder,
        tr: TrNewsRef,
        k: INT,
        list: Array,
        half_window_s: FLOAT,
    ) -> Res<Array> {
        let focus = tr
            .focus
            .iter()
            .find(|f| f.receiver as INT == k)
            .ok_or_else(|| super::error(&ctx, format!("receiver {k} was not focused")))?;
        let points = points(&ctx, &list)?;
        let results = crate::trnews::delayed_sweep(&r, &tr, focus, &points, half_window_s)
            .map_err(|e| crate::script::sweep_error(&ctx, e))?;
        Ok(results.into_iter().map(Dynamic::from).collect())
    }

    /// The linear prediction sum a_i y_TR(t - tau_i).
    #[rhai_fn(global, get = "prediction", pure)]
    pub fn prediction(d: &mut Delayed) -> Signal {
        d.prediction.clone()
    }

    /// The simulated response to the composite source.
    #[rhai_fn(global, get = "simulation", pure)]
    pub fn simulation(d: &mut Delayed) -> Signal {
        d.simulation.clone()
    }

    /// Relative L2 misfit between simulation and prediction over the focus window.
    #[rhai_fn(global, get = "misfit", pure)]
    pub fn misfit(d: &mut Delayed) -> FLOAT {
        d.misfit
    }

    /// Relative difference of the peak amplitudes (simulation - prediction) / prediction.
    #[rhai_fn(global, get = "peak_difference", pure)]
    pub fn peak_difference(d: &mut Delayed) -> FLOAT {
        d.peak_difference
    }

    /// Everything about the point as a map (delays, amplitudes, misfit, peak difference, window, report), without the signals.
    #[rhai_fn(global, pure, return_raw)]
    pub fn summary(ctx: NativeCallContext, d: &mut Delayed) -> Res<Dynamic> {
        let mut m = Map::new();
        m.insert("delays_s".into(), to_dynamic(&ctx, &d.delays_s)?);
        m.insert("amplitudes".into(), to_dynamic(&ctx, &d.amplitudes)?);
        m.insert("misfit".into(), d.misfit.into());
        m.insert("peak_difference".into(), d.peak_difference.into());
        m.insert(
            "window_s".into(),
            to_dynamic(&ctx, &[d.window_s.0, d.window_s.1])?,
        );
        m.insert(
            "report".into(),
            d.report
                .as_ref()
                .map_or(Ok(Dynamic::UNIT), |rep| to_dynamic(&ctx, rep))?,
        );
        Ok(m.into())
    }

    /// Pulse inversion of `traction`: #{positive: [Signal], negative: [Signal], sum: [Signal], reports: [map]} per receiver.
    #[rhai_fn(global, return_raw)]
    pub fn pulse_inversion(
        ctx: NativeCallContext,
        r: Responder,
        traction: Signal,
        duration_s: FLOAT,
    ) -> Res<Dynamic> {
        let pi = crate::trnews::pulse_inversion(&r, &traction, duration_s).at(&ctx)?;
        let list = |v: Vec<Signal>| -> Dynamic {
            v.into_iter().map(Dynamic::from).collect::<Array>().into()
        };
        let mut m = Map::new();
        m.insert("reports".into(), to_dynamic(&ctx, &pi.reports)?);
        m.insert("positive".into(), list(pi.positive));
        m.insert("negative".into(), list(pi.negative));
        m.insert("sum".into(), list(pi.sum));
        m.insert(
            "residual_estimates".into(),
            pi.residual_estimates.map_or(Dynamic::UNIT, |v| {
                v.into_iter().map(Dynamic::from).collect::<Array>().into()
            }),
        );
        Ok(m.into())
    }

    /// Number of receivers of the scene.
    #[rhai_fn(global, get = "receiver_count", pure)]
    pub fn receiver_count(tr: &mut TrNewsRef) -> INT {
        tr.responses.len() as INT
    }

    /// Response of receiver `k` (1-based) in the first (chirp) pass.
    #[rhai_fn(global, pure, return_raw)]
    pub fn response(ctx: NativeCallContext, tr: &mut TrNewsRef, k: INT) -> Res<Signal> {
        Ok(tr.responses[index(&ctx, k, tr.responses.len(), "receiver")?].clone())
    }

    /// A responder with options #{error_estimate, step_fraction}: `step_fraction` sets the time step to that fraction of the scene's dt_crit (default: the scene's step, its `time_step_s` or 0.9 dt_crit); with `error_estimate: true` (or "auto" when that costs at most 30% extra) it also builds the scene's companions (same laminate draw; on triangles 2x and 4x the element sizes, about 1/8 + 1/64 of the cost where every layer coarsens; on spectral elements one and two orders lower along x and one order higher across every row, which see the error along x and across the layers, and where the crack's faces touch the scene at half the step, which sees the contact's error in time; `r.companion_cost` states their cost), repeats every procedure on them and attaches error estimates to the results (`focus.estimates`, `point.estimates`, pulse inversion's `residual_estimates`).
    #[rhai_fn(name = "responder", return_raw)]
    pub fn responder_with(
        ctx: NativeCallContext,
        scene: SceneRef,
        duration_s: FLOAT,
        settings: Map,
    ) -> Res<Responder> {
        let o: ResponderOptions =
            options(&ctx, settings, &ResponderOptions::default(), "responder")?;
        let dt_s = match o.step_fraction {
            None => scene.default_dt_s(),
            Some(f) => crate::solve::step_at_fraction(f, scene.stability.dt_crit_s).at(&ctx)?,
        };
        let r = Responder::with_step(scene, duration_s, dt_s).at(&ctx)?;
        match super::companions_wanted(&ctx, &r, o.error_estimate)? {
            Some(scenes) => r.with_companions(scenes, duration_s).at(&ctx),
            None => Ok(r),
        }
    }

    /// True when the responder repeats its procedures on coarser companions for error estimates.
    #[rhai_fn(global, get = "error_estimate", pure)]
    pub fn has_error_estimate(r: &mut Responder) -> bool {
        !r.companions().is_empty()
    }

    /// Run time the error estimate's companions add relative to the main runs (DOFs x steps), whether or not the responder has them.
    #[rhai_fn(global, get = "companion_cost", pure, return_raw)]
    pub fn companion_cost(ctx: NativeCallContext, r: &mut Responder) -> Res<FLOAT> {
        Ok(r.companion_scenes().at(&ctx)?.1)
    }

    /// The transducer band of the responses, e.g. "0.2-2 MHz band", or "no band (raw)".
    #[rhai_fn(global, get = "band", pure)]
    pub fn band(tr: &mut TrNewsRef) -> String {
        tr.band.clone()
    }

    /// Error estimates of the focus as #{response, focused, peak_amplitude, peak_time_s, side_lobe_asymmetry, main_to_side_db, pi_residual} (Estimate objects; waveforms as relative L2), or () without an error estimate.
    #[rhai_fn(global, get = "estimates", pure)]
    pub fn focus_estimates(f: &mut Focus) -> Dynamic {
        let Some(e) = &f.estimates else {
            return Dynamic::UNIT;
        };
        let mut entries = vec![
            ("response", e.response),
            ("focused", e.focused),
            ("peak_amplitude", e.peak_amplitude),
            ("peak_time_s", e.peak_time_s),
            ("side_lobe_asymmetry", e.side_lobe_asymmetry),
            ("main_to_side_db", e.main_to_side_db),
        ];
        entries.extend(e.pi_residual.map(|p| ("pi_residual", p)));
        estimate_map(entries)
    }

    /// Pulse-inversion residual max|PI sum| / max|y_TR|, or () without pulse inversion.
    #[rhai_fn(global, get = "pi_residual", pure)]
    pub fn pi_residual(f: &mut Focus) -> Dynamic {
        f.pi_residual().map_or(Dynamic::UNIT, Dynamic::from)
    }

    /// Error estimates of a delayed point as #{misfit, peak_difference, simulation, prediction, residual} (the traces over the misfit window, relative L2; the misfit's error bounded from theirs where its own values do not converge), or () without an error estimate.
    #[rhai_fn(global, get = "estimates", pure)]
    pub fn delayed_estimates(d: &mut Delayed) -> Dynamic {
        d.estimates.as_ref().map_or(Dynamic::UNIT, |e| {
            estimate_map(vec![
                ("misfit", e.misfit),
                ("peak_difference", e.peak_difference),
                ("simulation", e.simulation),
                ("prediction", e.prediction),
                ("residual", e.residual),
            ])
        })
    }

    /// Scans the focus along the receivers (options #{receivers (1-based, [] = all), delays_s, amplitudes, half_window_s, focus}; defaults: all, [0, 1 us], [1, 1], 5 us, true; focus = false surveys: the chirp run only, for the spectral shifts): the chirp run once, then per receiver the focusing drive and its inverse (pulse inversion) and the delayed drive, each receiver a work unit stored under points/scan/ (resumed, sharded with --shard, assembled by --merge), with error estimates when the responder has companions.
    #[rhai_fn(global, return_raw)]
    pub fn scan(ctx: NativeCallContext, r: Responder, spec: Map, list: Map) -> Res<ScanRef> {
        let spec: TrNewsSpec = options(&ctx, spec, &TrNewsSpec::default(), "tr_news")?;
        let o: ScanOptions = options(&ctx, list, &ScanOptions::default(), "scan")?;
        let drive = crate::trnews::ScanDrive {
            delays_s: o.delays_s,
            amplitudes: o.amplitudes,
            half_window_s: o.half_window_s,
        };
        let scan = crate::trnews::scan(&r, &spec, &o.receivers, &drive, o.focus)
            .map_err(|e| crate::script::sweep_error(&ctx, e))?;
        Ok(Arc::new(scan))
    }

    /// The scan's positions as #{receiver, focus: Focus, delayed: Delayed}, in the order scanned ([] for a survey).
    #[rhai_fn(global, get = "points", pure)]
    pub fn scan_points(s: &mut ScanRef) -> Array {
        s.points
            .iter()
            .map(|p| {
                let mut m = Map::new();
                m.insert("receiver".into(), (p.focus.receiver as INT).into());
                m.insert("focus".into(), Dynamic::from(p.focus.clone()));
                m.insert("delayed".into(), Dynamic::from(p.delayed.clone()));
                Dynamic::from(m)
            })
            .collect()
    }

    /// The scan's chirp run (a TrNews without foci): its responses at every receiver.
    #[rhai_fn(global, get = "first_pass", pure)]
    pub fn scan_first_pass(s: &mut ScanRef) -> TrNewsRef {
        Arc::new(s.first_pass.clone())
    }

    /// The crack's spectral shift at each scanned position against `baseline` (the uncracked scene's scan of the same receivers): the mean frequency of the first-pass response less the baseline's, as #{value, estimate} (estimate () unless both scans have companions).
    #[rhai_fn(global, pure, return_raw)]
    pub fn spectral_shifts(
        ctx: NativeCallContext,
        s: &mut ScanRef,
        baseline: ScanRef,
    ) -> Res<Array> {
        let shifts = s.spectral_shifts(&baseline).at(&ctx)?;
        Ok(shifts
            .into_iter()
            .map(|(value, estimate)| {
                let mut m = Map::new();
                m.insert("value".into(), value.into());
                m.insert(
                    "estimate".into(),
                    estimate.map_or(Dynamic::UNIT, Dynamic::from),
                );
                Dynamic::from(m)
            })
            .collect())
    }

    /// Where two scans of one map (values at the same focus positions x_m, the transmitter on the right and on the left) put the crack: each view scaled from its floor (0) to its peak (1), the smaller of the two at each position located as by localise (a crack's shadow, beyond it as seen from the transmitter, shows in one view only): #{from_m, to_m, centre_m, length_m, peak_m}.
    #[rhai_fn(return_raw)]
    pub fn localise_sides(
        ctx: NativeCallContext,
        x_m: Array,
        right: Array,
        left: Array,
    ) -> Res<Dynamic> {
        let x = crate::script::convert::floats(&ctx, &x_m.into(), "x_m")?;
        let r = crate::script::convert::floats(&ctx, &right.into(), "right")?;
        let l = crate::script::convert::floats(&ctx, &left.into(), "left")?;
        let found = crate::trnews::localise_sides(&x, &r, &l).at(&ctx)?;
        to_dynamic(&ctx, &found)
    }

    /// Where a scan's map (values at focus positions x_m, increasing) puts the crack: the run of positions around the map's peak above half its height over the map's floor (its smallest value), ends interpolated: #{from_m, to_m, centre_m, length_m, peak_m}.
    #[rhai_fn(return_raw)]
    pub fn localise(ctx: NativeCallContext, x_m: Array, values: Array) -> Res<Dynamic> {
        let x = crate::script::convert::floats(&ctx, &x_m.into(), "x_m")?;
        let v = crate::script::convert::floats(&ctx, &values.into(), "values")?;
        let l = crate::trnews::localise(&x, &v).at(&ctx)?;
        to_dynamic(&ctx, &l)
    }
}
