//! The TR-NEWS procedure (report Sec. 3, eqs 6-9), delayed TR-NEWS (eqs 10-11) and pulse
//! inversion (Sec. 5.3) on a [`Scene`].
//!
//! A scene without a contacting crack is linear and time-invariant in discrete time: its
//! response to any transmitted traction s is exactly y_n = sum_k s_k h_{n-k}, with h the
//! response to a unit impulse at step 0. A [`Responder`] for such a scene runs
//! that one simulation and answers every later transmission by convolution; for a cracked
//! scene it simulates each transmission, in parallel when there are several.
//!
//! Every transmission goes through the scene's transducers (see [`crate::transducer`]): the
//! drive signal s becomes the traction B * s and each receiver records B * its raw quantity,
//! so every measure below (focus, side lobes, PI, delayed misfit) is in the transducer band.
//! For a linear scene B * (h * (B * s)) is formed from the raw impulse response h.

use crate::accuracy::{Estimate, T3_ORDER};
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::signal::{self, Peak, SideLobes, Signal};
use crate::solve::RunReport;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Recorded responses of every receiver to one transmission.
#[derive(Clone, Debug)]
pub struct Response {
    /// One trace per receiver, from t = 0 at the solver step.
    pub traces: Vec<Signal>,
    /// The run report, when the response was simulated (None when convolved).
    pub report: Option<RunReport>,
}

/// Answers "what do the receivers record when the transmitter sends s?". Cheap to clone.
///
/// With an error estimate ([`Responder::with_companions`]) it also holds companions on
/// the same scene with 2x and 4x the element sizes, and every procedure below repeats itself
/// on them and reports Richardson estimates of its results (see [`crate::accuracy`]).
#[derive(Clone, Debug)]
pub struct Responder {
    scene: Arc<Scene>,
    dt_s: f64,
    /// Response to a unit impulse, per receiver, when the scene is linear.
    impulse: Option<Arc<Response>>,
    /// Companions with 2x and 4x the element sizes; empty without an error estimate.
    companions: Vec<Responder>,
}

impl Responder {
    /// Simulates every transmission (any scene).
    pub fn simulating(scene: Arc<Scene>) -> Responder {
        let dt_s = scene.default_dt_s();
        Responder {
            scene,
            dt_s,
            impulse: None,
            companions: Vec::new(),
        }
    }

    /// For a linear scene, runs the impulse response once (over `duration_s`) and convolves
    /// afterwards; for a nonlinear scene, the same as [`Responder::simulating`].
    pub fn new(scene: Arc<Scene>, duration_s: f64) -> Result<Responder> {
        let mut r = Self::simulating(scene);
        if r.scene.is_linear() {
            let unit = Signal {
                dt_s: r.dt_s,
                t0_s: 0.0,
                samples: vec![1.0],
            };
            let out = r.scene.apply_traction(&unit, &r.run_config(duration_s))?;
            r.impulse = Some(Arc::new(Response {
                traces: out.traces,
                report: Some(out.report),
            }));
        }
        Ok(r)
    }

    /// The scenes of an error estimate's companions: this scene (same laminate draw) with 2x
    /// and 4x the element sizes, each with its own stable step, and their run time relative
    /// to this responder's from DOFs x steps, sum over companions of (DOFs_c / DOFs)
    /// (dt / dt_c). About 1/8 + 1/64 where every layer coarsens, more where thin layers keep
    /// one element row or set the step. Building them runs no simulation.
    pub fn companion_scenes(&self) -> Result<(Vec<Arc<Scene>>, f64)> {
        let scenes = [2.0, 4.0]
            .into_iter()
            .map(|factor| Ok(Arc::new(Scene::build(&self.scene.spec.coarsened(factor)?)?)))
            .collect::<Result<Vec<_>>>()?;
        let work = |s: &Scene, dt: f64| s.model.dofs() as f64 / dt;
        let cost = scenes
            .iter()
            .map(|s| work(s, s.default_dt_s()))
            .sum::<f64>()
            / work(&self.scene, self.dt_s);
        Ok((scenes, cost))
    }

    /// Adds companions on `scenes` (from [`Responder::companion_scenes`]), built the way this
    /// one was (convolving when linear, over `duration_s`).
    pub fn with_companions(
        mut self,
        scenes: Vec<Arc<Scene>>,
        duration_s: f64,
    ) -> Result<Responder> {
        self.companions = scenes
            .into_iter()
            .map(|scene| {
                if self.impulse.is_some() {
                    Responder::new(scene, duration_s)
                } else {
                    Ok(Responder::simulating(scene))
                }
            })
            .collect::<Result<_>>()?;
        Ok(self)
    }

    /// The companions of the error estimate (2h, 4h), empty without one.
    pub fn companions(&self) -> &[Responder] {
        &self.companions
    }

    /// The solver step of every response (s).
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The impulse-response run's report, when responses are convolved.
    pub fn impulse_report(&self) -> Option<&RunReport> {
        self.impulse.as_ref().and_then(|i| i.report.as_ref())
    }

    fn run_config(&self, duration_s: f64) -> crate::solve::RunConfig {
        crate::solve::RunConfig {
            dt_s: Some(self.dt_s),
            ..self.scene.run_config(duration_s)
        }
    }

    /// Receivers' responses to the drive signal `s` (Pa) over `duration_s`, through the
    /// scene's transducers.
    pub fn respond(&self, s: &Signal, duration_s: f64) -> Result<Response> {
        let s = if (s.dt_s / self.dt_s - 1.0).abs() > 1e-9 {
            signal::resample(s, self.dt_s)?
        } else {
            s.clone()
        };
        match &self.impulse {
            Some(h) => {
                let n = (duration_s / self.dt_s).round() as usize;
                if n > h.traces[0].len() {
                    return Err(Error::invalid(
                        "duration_s",
                        duration_s,
                        format!(
                            "exceeds the impulse response length {:.4e} s",
                            h.traces[0].duration_s()
                        ),
                    ));
                }
                let transducer = self.scene.spec.transducer.as_ref();
                let traction = match transducer {
                    Some(t) => t.transmit(&s, duration_s)?,
                    None => s,
                };
                let traces = h
                    .traces
                    .iter()
                    .map(|h| {
                        let raw = truncate(signal::convolve_discrete(&traction, h)?, n);
                        match transducer {
                            Some(t) => t.receive(&raw),
                            None => Ok(raw),
                        }
                    })
                    .collect::<Result<Vec<_>>>()?;
                Ok(Response {
                    traces,
                    report: None,
                })
            }
            None => {
                let out = self.scene.transmit(&s, &self.run_config(duration_s))?;
                Ok(Response {
                    traces: out.traces,
                    report: Some(out.report),
                })
            }
        }
    }

    /// Responses to several transmissions; independent simulations run in parallel, and the
    /// results are identical for any thread count.
    pub fn respond_all(&self, sources: &[Signal], duration_s: f64) -> Result<Vec<Response>> {
        sources
            .par_iter()
            .map(|s| self.respond(s, duration_s))
            .collect()
    }
}

/// The first n samples on the grid starting at t = 0 (zero-padded if shorter).
fn truncate(s: Signal, n: usize) -> Signal {
    let offset = (s.t0_s / s.dt_s).round() as i64;
    let samples = (0..n as i64)
        .map(|k| {
            usize::try_from(k - offset)
                .ok()
                .and_then(|i| s.samples.get(i))
                .copied()
                .unwrap_or(0.0)
        })
        .collect();
    Signal {
        dt_s: s.dt_s,
        t0_s: 0.0,
        samples,
    }
}

/// Parameters of the TR-NEWS procedure (report Sec. 3 and 5.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrNewsSpec {
    /// Chirp start frequency (report: 0.2 MHz).
    pub f0_hz: f64,
    /// Chirp end frequency (report: 2 MHz).
    pub f1_hz: f64,
    /// Chirp length t1 (report: 30 us).
    pub chirp_s: f64,
    /// Length of the transmitted chirp signal, zero after t1 (report: 60 us).
    pub signal_s: f64,
    /// Tukey taper fraction of the chirp (0: none).
    pub taper: f64,
    /// Duration T of the recorded coda response y (s).
    pub record_s: f64,
    /// Lag window [0, window_s] of the correlation Gamma; the time-reversed Gamma focuses at
    /// t = window_s (s).
    pub window_s: f64,
    /// Recording time after the focus in the focusing runs (s).
    pub after_focus_s: f64,
    /// Receivers to focus on, 1-based; empty = all.
    pub receivers: Vec<usize>,
    /// Also transmit the inverted focusing signal and form the pulse-inversion sum.
    pub pulse_inversion: bool,
    /// Half width of the main lobe for the side-lobe measures (s).
    pub main_lobe_half_width_s: f64,
}

impl Default for TrNewsSpec {
    fn default() -> Self {
        TrNewsSpec {
            f0_hz: 0.2e6,
            f1_hz: 2e6,
            chirp_s: 30e-6,
            signal_s: 60e-6,
            taper: 0.0,
            record_s: 60e-6,
            window_s: 60e-6,
            after_focus_s: 30e-6,
            receivers: vec![],
            pulse_inversion: false,
            main_lobe_half_width_s: 1e-6,
        }
    }
}

/// TR-NEWS focusing at one receiver.
#[derive(Clone, Debug)]
pub struct Focus {
    /// Receiver number (1-based).
    pub receiver: usize,
    /// Gamma(tau) = sum_n y(t_n + tau) c(t_n) dt over the lag window (eq 8 as a correlation).
    pub gamma: Signal,
    /// The transmitted focusing signal Gamma(T - t), scaled to the transmitter's peak traction.
    pub source: Signal,
    /// The focused signal y_TR at the receiver.
    pub focused: Signal,
    /// Peak of the focused signal.
    pub peak: Peak,
    /// Side lobes around the expected focus time (window_s).
    pub side_lobes: SideLobes,
    /// Response to the inverted source, with pulse inversion.
    pub inverted: Option<Signal>,
    /// Pulse-inversion sum focused + inverted (the nonlinear even part).
    pub pi_sum: Option<Signal>,
    /// Reports of the focusing runs (empty when convolved).
    pub reports: Vec<RunReport>,
    /// Discretisation error estimates, when the responder has companions.
    pub estimates: Option<FocusEstimates>,
}

/// Richardson estimates of the headline quantities of a focus (see [`crate::accuracy`]).
#[derive(Clone, Debug, Serialize)]
pub struct FocusEstimates {
    /// First-pass response y at this receiver over the record (relative L2).
    pub response: Estimate,
    /// Focused signal y_TR over the focus window window_s +- after_focus_s (relative L2).
    pub focused: Estimate,
    /// Focus peak amplitude.
    pub peak_amplitude: Estimate,
    /// Focus peak time (s).
    pub peak_time_s: Estimate,
    /// Side-lobe energy asymmetry.
    pub side_lobe_asymmetry: Estimate,
    /// Main-to-side-lobe ratio (dB).
    pub main_to_side_db: Estimate,
    /// Pulse-inversion residual max|PI| / max|y_TR|, with pulse inversion.
    pub pi_residual: Option<Estimate>,
}

impl Focus {
    /// Pulse-inversion residual max|PI sum| / max|y_TR|, with pulse inversion.
    pub fn pi_residual(&self) -> Option<f64> {
        self.pi_sum
            .as_ref()
            .map(|pi| pi.max_abs() / self.focused.max_abs())
    }
}

/// The result of the TR-NEWS procedure.
#[derive(Clone, Debug)]
pub struct TrNews {
    /// The parameters used.
    pub spec: TrNewsSpec,
    /// The transmitted chirp c(t) (Pa).
    pub chirp: Signal,
    /// First-pass responses y at every receiver.
    pub responses: Vec<Signal>,
    /// Focusing per requested receiver.
    pub focus: Vec<Focus>,
    /// Report of the chirp run (None when convolved).
    pub chirp_report: Option<RunReport>,
    /// The same procedure on the error estimate's companions (2h, 4h), if any.
    pub companions: Vec<TrNews>,
    /// The transducer band every signal was seen through ("no band (raw)" without one).
    pub band: String,
}

impl TrNewsSpec {
    /// Shorter signals for the `smoke` scene: a 10 us chirp in 15 us, 20 us records and window.
    pub fn smoke() -> TrNewsSpec {
        TrNewsSpec {
            chirp_s: 10e-6,
            signal_s: 15e-6,
            record_s: 20e-6,
            window_s: 20e-6,
            after_focus_s: 10e-6,
            ..Default::default()
        }
    }

    /// A preset by name: `smoke` for the smoke scene, the report's values otherwise.
    pub fn preset(name: &str) -> TrNewsSpec {
        if name == "smoke" {
            Self::smoke()
        } else {
            Self::default()
        }
    }

    /// Duration of a focusing run: the lag window plus the recording after the focus (s).
    pub fn focus_duration_s(&self) -> f64 {
        self.window_s + self.after_focus_s
    }
}

/// Runs TR-NEWS: chirp -> y -> Gamma = xcorr(y, c) -> Gamma(T - t) -> y_TR (eqs 6-9), and
/// on the responder's companions, with the error estimates of every focus.
pub fn tr_news(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let mut main = tr_news_once(responder, spec)?;
    main.companions = responder
        .companions
        .iter()
        .map(|c| tr_news_once(c, spec))
        .collect::<Result<_>>()?;
    if let [medium, coarse] = &main.companions[..] {
        let estimates = (0..main.focus.len())
            .map(|i| focus_estimates(&main, medium, coarse, i))
            .collect::<Result<Vec<_>>>()?;
        for (f, e) in main.focus.iter_mut().zip(estimates) {
            f.estimates = Some(e);
        }
    }
    Ok(main)
}

/// The estimates of focus `i` from the runs at h, 2h, 4h.
fn focus_estimates(
    fine: &TrNews,
    medium: &TrNews,
    coarse: &TrNews,
    i: usize,
) -> Result<FocusEstimates> {
    let f = [&fine.focus[i], &medium.focus[i], &coarse.focus[i]];
    let scalar = |q: &dyn Fn(&Focus) -> f64| Estimate::scalar(q(f[0]), q(f[1]), q(f[2]), T3_ORDER);
    let spec = &fine.spec;
    let r = f[0].receiver - 1;
    let focus_window = (
        spec.window_s - spec.after_focus_s,
        spec.window_s + spec.after_focus_s,
    );
    Ok(FocusEstimates {
        response: Estimate::waveform(
            &fine.responses[r],
            &medium.responses[r],
            &coarse.responses[r],
            (0.0, spec.record_s),
            T3_ORDER,
        )?,
        focused: Estimate::waveform(
            &f[0].focused,
            &f[1].focused,
            &f[2].focused,
            focus_window,
            T3_ORDER,
        )?,
        peak_amplitude: scalar(&|x| x.peak.amplitude),
        peak_time_s: scalar(&|x| x.peak.time_s),
        side_lobe_asymmetry: Estimate::dimensionless(
            f[0].side_lobes.asymmetry,
            f[1].side_lobes.asymmetry,
            f[2].side_lobes.asymmetry,
            T3_ORDER,
        ),
        main_to_side_db: scalar(&|x| x.side_lobes.main_to_side_db),
        pi_residual: match f.map(Focus::pi_residual) {
            [Some(a), Some(b), Some(c)] => Some(Estimate::dimensionless(a, b, c, T3_ORDER)),
            _ => None,
        },
    })
}

/// `e` with the internal parameter names of the signal and run functions replaced by the
/// TR-NEWS spec's (`tr_news.<field>`), so that the message names the field the user wrote.
fn spec_field(e: Error, names: &[(&str, &str)]) -> Error {
    let mut text = e.to_string();
    for (internal, field) in names {
        text = text.replace(internal, &format!("tr_news.{field}"));
    }
    match e {
        Error::InvalidInput { .. } | Error::Signal(_) | Error::TooLarge { .. } => {
            Error::Named(text)
        }
        other => other,
    }
}

fn tr_news_once(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let peak_pa = responder.scene.spec.transmitter.peak_pa;
    let chirp = signal::chirp(
        spec.f0_hz,
        spec.f1_hz,
        spec.chirp_s,
        spec.signal_s,
        responder.dt_s,
        peak_pa,
        spec.taper,
    )
    .map_err(|e| spec_field(e.into(), &[("t1_s", "chirp_s"), ("total_s", "signal_s")]))?;
    let first = responder
        .respond(&chirp, spec.record_s)
        .map_err(|e| spec_field(e, &[("duration_s", "record_s")]))?;
    let n_receivers = first.traces.len();
    let receivers: Vec<usize> = if spec.receivers.is_empty() {
        (1..=n_receivers).collect()
    } else {
        spec.receivers.clone()
    };
    if let Some(&bad) = receivers.iter().find(|&&r| r == 0 || r > n_receivers) {
        return Err(Error::invalid(
            "tr_news.receivers",
            bad,
            format!("receivers are numbered 1..{n_receivers}"),
        ));
    }
    let mut sources = Vec::with_capacity(receivers.len());
    let mut gammas = Vec::with_capacity(receivers.len());
    for &r in &receivers {
        let gamma = signal::xcorr(&first.traces[r - 1], &chirp, 0.0, spec.window_s)?;
        let reversed = signal::time_reverse_to_start(&gamma)?;
        let max = reversed.max_abs();
        if !(max > 0.0) {
            return Err(Error::invalid(
                "tr_news",
                format!("receiver {r}"),
                "recorded nothing: the correlation is zero",
            ));
        }
        sources.push(reversed.scale(peak_pa / max)?);
        gammas.push(gamma);
    }
    let mut transmissions = sources.clone();
    if spec.pulse_inversion {
        transmissions.extend(
            sources
                .iter()
                .map(|s| s.scale(-1.0))
                .collect::<std::result::Result<Vec<_>, _>>()?,
        );
    }
    let responses = responder
        .respond_all(&transmissions, spec.focus_duration_s())
        .map_err(|e| spec_field(e, &[("duration_s", "window_s (its focusing run)")]))?;
    let focus = receivers
        .iter()
        .enumerate()
        .map(|(k, &r)| {
            let positive = &responses[k];
            let negative = spec
                .pulse_inversion
                .then(|| &responses[k + receivers.len()]);
            focus_at(
                spec,
                r,
                gammas[k].clone(),
                sources[k].clone(),
                positive,
                negative,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(TrNews {
        spec: spec.clone(),
        chirp,
        responses: first.traces,
        focus,
        chirp_report: first.report,
        companions: Vec::new(),
        band: crate::transducer::band_label(responder.scene.spec.transducer.as_ref()),
    })
}

fn focus_at(
    spec: &TrNewsSpec,
    r: usize,
    gamma: Signal,
    source: Signal,
    positive: &Response,
    negative: Option<&Response>,
) -> Result<Focus> {
    let focused = positive.traces[r - 1].clone();
    let peak = signal::peak(&focused)?;
    let side_lobes = signal::side_lobes(&focused, spec.window_s, spec.main_lobe_half_width_s)?;
    let inverted = negative.map(|n| n.traces[r - 1].clone());
    let pi_sum = inverted.as_ref().map(|i| focused.add(i)).transpose()?;
    let reports = positive
        .report
        .iter()
        .chain(negative.and_then(|n| n.report.as_ref()))
        .cloned()
        .collect();
    Ok(Focus {
        receiver: r,
        gamma,
        source,
        focused,
        peak,
        side_lobes,
        inverted,
        pi_sum,
        reports,
        estimates: None,
    })
}

/// Delayed TR-NEWS at one point (eqs 10-11): simulation of the composite source
/// sum_i a_i s(t - tau_i) against the linear prediction sum_i a_i y_TR(t - tau_i).
#[derive(Clone, Debug, Serialize)]
pub struct Delayed {
    /// Delays tau_i (s).
    pub delays_s: Vec<f64>,
    /// Amplitudes a_i.
    pub amplitudes: Vec<f64>,
    /// The linear prediction at the focusing receiver.
    pub prediction: Signal,
    /// The simulated (or, for a linear scene, convolved) response.
    pub simulation: Signal,
    /// Relative L2 misfit ||sim - pred|| / ||pred|| over the focus window.
    pub misfit: f64,
    /// (max |sim| - max |pred|) / max |pred| over the focus window.
    pub peak_difference: f64,
    /// The window [t0, t1] the misfit is measured over (s).
    pub window_s: (f64, f64),
    /// The run report (None when convolved).
    pub report: Option<RunReport>,
    /// Discretisation error estimates, when the responder has companions.
    pub estimates: Option<DelayedEstimates>,
}

/// Richardson estimates of a delayed TR-NEWS point (see [`crate::accuracy`]).
#[derive(Clone, Debug, Serialize)]
pub struct DelayedEstimates {
    /// The misfit.
    pub misfit: Estimate,
    /// The peak difference.
    pub peak_difference: Estimate,
    /// The simulated trace over the misfit window (relative L2).
    pub simulation: Estimate,
}

/// Delayed TR-NEWS for several (delays, amplitudes) points, simulated in parallel, and on
/// the responder's companions (each with its own focusing signal), with error estimates.
pub fn delayed_tr_news(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
) -> Result<Vec<Delayed>> {
    let mut main = delayed_once(responder, tr, focus, points, half_window_s)?;
    let ([rm, rc], [tm, tc]) = (&responder.companions[..], &tr.companions[..]) else {
        return Ok(main);
    };
    let on = |r: &Responder, t: &TrNews| -> Result<Vec<Delayed>> {
        let f = t
            .focus
            .iter()
            .find(|f| f.receiver == focus.receiver)
            .ok_or_else(|| Error::invalid("receiver", focus.receiver, "has no companion focus"))?;
        delayed_once(r, t, f, points, half_window_s)
    };
    let (medium, coarse) = (on(rm, tm)?, on(rc, tc)?);
    for ((d, m), c) in main.iter_mut().zip(&medium).zip(&coarse) {
        d.estimates = Some(DelayedEstimates {
            misfit: Estimate::dimensionless(d.misfit, m.misfit, c.misfit, T3_ORDER),
            peak_difference: Estimate::dimensionless(
                d.peak_difference,
                m.peak_difference,
                c.peak_difference,
                T3_ORDER,
            ),
            simulation: Estimate::waveform(
                &d.simulation,
                &m.simulation,
                &c.simulation,
                d.window_s,
                T3_ORDER,
            )?,
        });
    }
    Ok(main)
}

/// Delayed TR-NEWS for several (delays, amplitudes) points, simulated in parallel.
/// Delays are rounded to whole solver steps (at most dt/2, a few ns, off), so that source
/// and prediction are shifted exactly and a linear scene's misfit is round-off. The misfit
/// window spans the focus times window_s + tau_i, widened by `half_window_s`.
fn delayed_once(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
) -> Result<Vec<Delayed>> {
    let dt = responder.dt_s();
    let points: Vec<(Vec<f64>, Vec<f64>)> = points
        .iter()
        .map(|(d, a)| (d.iter().map(|t| (t / dt).round() * dt).collect(), a.clone()))
        .collect();
    let mut sources = Vec::with_capacity(points.len());
    for (delays, amplitudes) in &points {
        if let Some(&bad) = delays.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
            return Err(Error::invalid(
                "delays_s",
                bad,
                "delays must be finite and >= 0",
            ));
        }
        sources.push(signal::delay_and_sum(&focus.source, delays, amplitudes)?);
    }
    let max_delay = points
        .iter()
        .flat_map(|p| p.0.iter())
        .fold(0.0f64, |m, d| m.max(*d));
    let duration = tr.spec.focus_duration_s() + max_delay;
    let responses = responder.respond_all(&sources, duration)?;
    points
        .iter()
        .zip(responses)
        .map(|((delays, amplitudes), response)| {
            let simulation = response.traces[focus.receiver - 1].clone();
            let prediction = truncate(
                signal::delay_and_sum(&focus.focused, delays, amplitudes)?,
                simulation.len(),
            );
            let last = delays.iter().fold(0.0f64, |m, d| m.max(*d));
            let first = delays.iter().fold(f64::INFINITY, |m, d| m.min(*d));
            let window = (
                tr.spec.window_s + first - half_window_s,
                (tr.spec.window_s + last + half_window_s).min(simulation.t_end_s()),
            );
            let misfit = signal::relative_l2(&simulation, &prediction, Some(window))?;
            let peak_of =
                |s: &Signal| -> Result<f64> { Ok(s.window(window.0, window.1)?.max_abs()) };
            let p = peak_of(&prediction)?;
            let peak_difference = (peak_of(&simulation)? - p) / p;
            Ok(Delayed {
                delays_s: delays.clone(),
                amplitudes: amplitudes.clone(),
                prediction,
                simulation,
                misfit,
                peak_difference,
                window_s: window,
                report: response.report,
                estimates: None,
            })
        })
        .collect()
}

/// Pulse inversion of any transmission: responses to +s and -s and their sum per receiver.
#[derive(Clone, Debug)]
pub struct PulseInversion {
    /// Responses to +s.
    pub positive: Vec<Signal>,
    /// Responses to -s.
    pub negative: Vec<Signal>,
    /// positive + negative: zero (to round-off) for a linear scene.
    pub sum: Vec<Signal>,
    /// Reports of the two runs (empty when convolved).
    pub reports: Vec<RunReport>,
    /// Per receiver, the estimate of the residual max|sum| / max|positive|, when the
    /// responder has companions.
    pub residual_estimates: Option<Vec<Estimate>>,
}

impl PulseInversion {
    /// Per receiver, the residual max|sum| / max|positive|.
    pub fn residuals(&self) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.positive)
            .map(|(s, p)| s.max_abs() / p.max_abs())
            .collect()
    }
}

/// Transmits +s and -s (in parallel) and sums the responses (report Sec. 5.3), also on the
/// responder's companions, with estimates of the residuals.
pub fn pulse_inversion(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let mut main = pulse_inversion_once(responder, s, duration_s)?;
    if let [medium, coarse] = &responder.companions[..] {
        let fine = main.residuals();
        let m = pulse_inversion_once(medium, s, duration_s)?.residuals();
        let c = pulse_inversion_once(coarse, s, duration_s)?.residuals();
        main.residual_estimates = Some(
            (0..fine.len())
                .map(|k| Estimate::dimensionless(fine[k], m[k], c[k], T3_ORDER))
                .collect(),
        );
    }
    Ok(main)
}

fn pulse_inversion_once(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let pair = responder.respond_all(&[s.clone(), s.scale(-1.0)?], duration_s)?;
    let sum = pair[0]
        .traces
        .iter()
        .zip(&pair[1].traces)
        .map(|(a, b)| a.add(b))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let reports = pair.iter().filter_map(|r| r.report.clone()).collect();
    let mut it = pair.into_iter();
    let (p, n) = (it.next().unwrap(), it.next().unwrap());
    Ok(PulseInversion {
        positive: p.traces,
        negative: n.traces,
        sum,
        reports,
        residual_estimates: None,
    })
}
