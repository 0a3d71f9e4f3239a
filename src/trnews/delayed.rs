//! Delayed TR-NEWS (report eqs 10-11): the focusing drive plus delayed, scaled copies, and the
//! misfit between the simulation and the linear prediction from y_TR.

use super::channel::{to_record_of, truncate, Responder};
use super::focus::{Focus, TrNews, TrNewsSpec};
use crate::accuracy::{Estimate, Refinement};
use crate::error::{Error, Result};
use crate::signal::{self, Signal};
use crate::solve::RunReport;
use crate::sweep::{Key, PointSpec, Sweep, SweepError};
use serde::{Deserialize, Serialize};

/// Delayed TR-NEWS at one point (eqs 10-11): simulation of the composite source
/// sum_i a_i s(t - tau_i) against the linear prediction sum_i a_i y_TR(t - tau_i).
#[derive(Clone, Debug, Serialize, Deserialize)]
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

/// Error estimates of a delayed TR-NEWS point (see [`crate::accuracy`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DelayedEstimates {
    /// The misfit: its own estimate, or a bound from the errors of the traces it compares
    /// where its own values do not converge ([`Estimate::relative_misfit`]).
    pub misfit: Estimate,
    /// The peak difference (Richardson, from its own values).
    pub peak_difference: Estimate,
    /// The simulated trace over the misfit window (relative L2).
    pub simulation: Estimate,
    /// The linear prediction over the misfit window (relative L2).
    pub prediction: Estimate,
    /// The residual simulation - prediction over the misfit window (relative L2).
    pub residual: Estimate,
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
    let max_delay_s = longest_delay(points.iter().flat_map(|p| &p.0));
    delayed_tr_news_within(responder, tr, focus, points, half_window_s, max_delay_s)
}

/// [`delayed_tr_news`] for some points of a sweep whose largest delay is `max_delay_s`: every
/// response runs over the focus duration plus that delay, as in the whole sweep, so a point
/// computed alone is bit-identical to the same point computed with all the others.
pub fn delayed_tr_news_within(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
) -> Result<Vec<Delayed>> {
    let mut foci = vec![focus];
    for t in &tr.companions {
        foci.push(
            t.focus
                .iter()
                .find(|f| f.receiver == focus.receiver)
                .ok_or_else(|| {
                    Error::invalid("receiver", focus.receiver, "has no companion focus")
                })?,
        );
    }
    delayed_at(
        responder,
        &tr.spec,
        &foci,
        points,
        half_window_s,
        max_delay_s,
    )
}

/// Delayed TR-NEWS of TR-NEWS spec `spec` from the focus at one receiver on each
/// discretisation, `foci` (the main one, then the responder's companions in order), with the
/// error estimates when there are companions; as [`delayed_tr_news_within`].
pub(super) fn delayed_at(
    responder: &Responder,
    spec: &TrNewsSpec,
    foci: &[&Focus],
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
) -> Result<Vec<Delayed>> {
    let mut main = delayed_once(responder, spec, foci[0], points, half_window_s, max_delay_s)?;
    if responder.companions.is_empty() {
        return Ok(main);
    }
    if foci.len() != responder.companions.len() + 1 {
        return Err(Error::invalid(
            "receiver",
            foci[0].receiver,
            "has no focus on every companion",
        ));
    }
    let companions = responder
        .companions
        .iter()
        .zip(&foci[1..])
        .map(|(r, f)| delayed_once(r, spec, f, points, half_window_s, max_delay_s))
        .collect::<Result<Vec<_>>>()?;
    let refinement = responder.refinement()?;
    for (k, d) in main.iter_mut().enumerate() {
        let runs: Vec<&Delayed> = std::iter::once(&*d)
            .chain(companions.iter().map(|c| &c[k]))
            .collect();
        d.estimates = Some(estimates_of(&runs, refinement)?);
    }
    Ok(main)
}

/// The estimates of a point from its `runs` on the main discretisation and its companions,
/// over the main run's misfit window.
fn estimates_of(runs: &[&Delayed], refinement: Refinement) -> Result<DelayedEstimates> {
    let window = runs[0].window_s;
    let values = |q: fn(&Delayed) -> f64| -> Vec<f64> { runs.iter().map(|x| q(x)).collect() };
    let traces =
        |q: fn(&Delayed) -> &Signal| -> Vec<&Signal> { runs.iter().map(|x| q(x)).collect() };
    let residuals = runs
        .iter()
        .map(|x| x.simulation.sub(&x.prediction))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let simulation = Estimate::waveform_of(&traces(|x| &x.simulation), window, refinement)?;
    let prediction = Estimate::waveform_of(&traces(|x| &x.prediction), window, refinement)?;
    let residual =
        Estimate::waveform_of(&residuals.iter().collect::<Vec<_>>(), window, refinement)?;
    let norm = |s: &Signal| -> Result<f64> { Ok(s.window(window.0, window.1)?.energy().sqrt()) };
    let size_ratio = norm(&runs[0].simulation)? / norm(&runs[0].prediction)?;
    let own = Estimate::dimensionless_of(&values(|x| x.misfit), refinement)?;
    Ok(DelayedEstimates {
        misfit: Estimate::relative_misfit(own, &simulation, &prediction, &residual, size_ratio),
        peak_difference: Estimate::dimensionless_of(&values(|x| x.peak_difference), refinement)?,
        simulation,
        prediction,
        residual,
    })
}

/// Delayed TR-NEWS for several (delays, amplitudes) points, simulated in parallel.
/// Delays are rounded to whole solver steps (at most dt/2, a few ns, off), so that source
/// and prediction are shifted exactly and a linear scene's misfit is round-off. The misfit
/// window spans the focus times window_s + tau_i, widened by `half_window_s`. Responses run
/// over the focus duration plus `max_delay_s` rounded to a whole step (rounding is monotone,
/// so that is the largest rounded delay of the sweep).
fn delayed_once(
    responder: &Responder,
    spec: &TrNewsSpec,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
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
        check_prediction_covers_window(spec, delays, half_window_s)?;
        sources.push(signal::delay_and_sum(&focus.source, delays, amplitudes)?);
    }
    let duration = spec.focus_duration_s() + (max_delay_s / dt).round() * dt;
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
            let last = longest_delay(delays);
            let first = delays.iter().fold(f64::INFINITY, |m, d| m.min(*d));
            let window = (
                spec.window_s + first - half_window_s,
                (spec.window_s + last + half_window_s).min(simulation.t_end_s()),
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

/// The misfit window of a point ends `half_window_s` after its last copy's focus, and the
/// linear prediction's first copy is y_TR as recorded, up to window_s + after_focus_s: the
/// last delay plus the half window must stay within after_focus_s, else the prediction
/// lacks the first copy's coda inside the window and a linear scene shows a misfit (an error
/// naming `delays_s`).
fn check_prediction_covers_window(
    spec: &TrNewsSpec,
    delays: &[f64],
    half_window_s: f64,
) -> Result<()> {
    let last = longest_delay(delays);
    if last + half_window_s > spec.after_focus_s {
        return Err(Error::invalid(
            "delays_s",
            last,
            format!(
                "the last delay plus the misfit's half window ({half_window_s:e} s) must be at \
                 most after_focus_s ({:e} s): y_TR is recorded to window_s + after_focus_s, so \
                 the first copy's prediction would end inside the misfit window (use shorter \
                 delays or a longer after_focus_s)",
                spec.after_focus_s
            ),
        ));
    }
    Ok(())
}

/// Delayed TR-NEWS over `points` as a sweep of work units (see [`crate::sweep`]): each point
/// is stored when done, read back by a rerun, shared out by a shard and only read by a
/// merge. Points are computed in parallel; each one runs over the sweep's longest delay, so
/// it is the same computed alone or with the others. On a lab channel (recordings, see
/// [`crate::lab`]) the points are looked up together instead, without point files.
pub fn delayed_sweep(
    r: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
) -> std::result::Result<Vec<Delayed>, SweepError> {
    if to_record_of(r).is_some() {
        // A lab's recordings are looked up, not simulated: every point at once, so that one
        // run lists every delayed drive still to record.
        return Ok(delayed_tr_news(r, tr, focus, points, half_window_s)?);
    }
    for (delays, _) in points {
        check_prediction_covers_window(&tr.spec, delays, half_window_s)?;
    }
    let max_delay_s = longest_delay(points.iter().flat_map(|p| &p.0));
    let specs = point_specs(r, tr, focus, points, half_window_s, max_delay_s)?;
    let how = if r.simulates() {
        "simulated"
    } else {
        "convolved or recorded"
    };
    let name = format!("delayed TR-NEWS at receiver {} ({how})", focus.receiver);
    let estimates = !r.companions().is_empty();
    let expect = |d: &Delayed| expect_delayed(d, r.dt_s(), estimates);
    let sweep = Sweep::start::<Delayed>(&name, "delayed", specs, &expect);
    crate::parallel::try_for_each(sweep.pending(), |&i| {
        let start = std::time::Instant::now();
        let one = &points[i..=i];
        let outcome = delayed_tr_news_within(r, tr, focus, one, half_window_s, max_delay_s)
            .map(|mut v| v.remove(0));
        let note = outcome
            .as_ref()
            .ok()
            .and_then(|d| d.report.as_ref())
            .map(report_note)
            .unwrap_or_default();
        sweep.record(i, outcome, start.elapsed().as_secs_f64(), &note)
    })?;
    sweep.finish()
}

/// The work units of a delayed sweep, keyed by what determines their results: the channel,
/// the first pass (the focusing signal and the focused signal at this receiver, on every
/// discretisation of the responder; not the run reports, whose wall times differ between
/// processes computing the same first pass), the receiver, the window, the sweep's longest
/// delay and the point.
fn point_specs(
    r: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
) -> Result<Vec<PointSpec>> {
    let focusing: Vec<(&Signal, &Signal)> = std::iter::once(tr)
        .chain(&tr.companions)
        .filter_map(|t| t.focus.iter().find(|f| f.receiver == focus.receiver))
        .map(|f| (&f.source, &f.focused))
        .collect();
    let first_pass = Key::of("delayed_first_pass", &(&tr.spec, &focusing))?;
    let identity = r.identity()?;
    points
        .iter()
        .map(|(delays, amplitudes)| {
            let inputs = (
                &identity,
                first_pass.as_str(),
                focus.receiver,
                half_window_s,
                max_delay_s,
                delays,
                amplitudes,
            );
            Ok(PointSpec {
                key: Key::of("delayed", &inputs)?,
                label: format!("tau = {delays:?} s, a = {amplitudes:?}"),
                sharded: r.simulates(),
            })
        })
        .collect()
}

/// Why a stored point cannot be a delayed TR-NEWS point on step `dt_s` (with `estimates` when
/// the responder has companions): see [`crate::sweep::Expect`].
fn expect_delayed(d: &Delayed, dt_s: f64, estimates: bool) -> std::result::Result<(), String> {
    let (sim, pred) = (&d.simulation, &d.prediction);
    if sim.dt_s != dt_s || pred.dt_s != dt_s || sim.len() != pred.len() {
        return Err("holds a simulation and a prediction on different grids".into());
    }
    if d.delays_s.len() != d.amplitudes.len() || !(d.window_s.0 <= d.window_s.1) {
        return Err("holds delays, amplitudes or a window that do not go together".into());
    }
    if d.estimates.is_some() != estimates {
        return Err("holds error estimates unlike its responder".into());
    }
    Ok(())
}

/// A run report in a progress line: steps, energy residual, dt/dt_crit and, with contact,
/// the capped steps and the largest penetration.
pub(super) fn report_note(rep: &RunReport) -> String {
    let contact = rep.contact.as_ref().map_or(String::new(), |c| {
        format!(
            ", contact capped steps {}, max penetration {:.2e} m",
            c.capped_steps, c.max_penetration_m
        )
    });
    format!(
        " ({} steps, energy residual {:.1e}, dt/dt_crit {:.3}{contact})",
        rep.steps, rep.energy_residual_peak, rep.stability_ratio
    )
}

/// The longest of `delays` (s), 0 without any.
fn longest_delay<'a>(delays: impl IntoIterator<Item = &'a f64>) -> f64 {
    delays.into_iter().fold(0.0f64, |m, d| m.max(*d))
}
