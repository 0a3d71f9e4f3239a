//! The TR-NEWS procedure (report Sec. 3, eqs 6-9): chirp, response, correlation Gamma, the
//! time-reversed focusing drive Gamma(T - t), and the focus at each receiver with its error
//! estimates.

use super::channel::{expect_traces, Responder, Response};
use crate::accuracy::{Estimate, Refinement};
use crate::error::{Error, Result};
use crate::scene::Resolution;
use crate::signal::{self, ChirpSpec, Peak, SideLobes, Signal};
use crate::solve::RunReport;
use serde::{Deserialize, Serialize};

/// Parameters of the TR-NEWS procedure (report Sec. 3 and 5.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrNewsSpec {
    /// The transmitted chirp (report: 0.2 -> 2 MHz over 30 us in 60 us), at the transmitter's
    /// peak traction.
    pub chirp: ChirpSpec,
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
            chirp: ChirpSpec::default(),
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
#[derive(Clone, Debug, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Serialize, Deserialize)]
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
    /// The same procedure on the error estimate's companions, if any; a companion
    /// has none of its own.
    #[serde(deserialize_with = "companions_one_level")]
    pub companions: Vec<TrNews>,
    /// The transducer band every signal was seen through ("no band (raw)" without one).
    pub band: String,
}

/// Decodes [`TrNews::companions`], refusing companions inside a companion. `TrNews` is the
/// only stored type that contains itself: without this, a forged point file nesting
/// companions a million deep would overflow the stack while it is decoded.
fn companions_one_level<'de, D: serde::Deserializer<'de>>(
    decoder: D,
) -> std::result::Result<Vec<TrNews>, D::Error> {
    thread_local! {
        static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    /// An element that cannot be decoded: a companion's companions must be empty.
    struct Refused;
    impl<'de> Deserialize<'de> for Refused {
        fn deserialize<D: serde::Deserializer<'de>>(_: D) -> std::result::Result<Self, D::Error> {
            Err(serde::de::Error::custom(
                "a companion holds companions of its own",
            ))
        }
    }
    if INSIDE.with(|i| i.get()) {
        return Vec::<Refused>::deserialize(decoder).map(|_| Vec::new());
    }
    struct Leave;
    impl Drop for Leave {
        fn drop(&mut self) {
            INSIDE.with(|i| i.set(false));
        }
    }
    INSIDE.with(|i| i.set(true));
    let _leave = Leave;
    Vec::<TrNews>::deserialize(decoder)
}

impl TrNewsSpec {
    /// Shorter signals for the `smoke` scene: a 10 us chirp in 15 us, 20 us records and window.
    pub fn smoke() -> TrNewsSpec {
        TrNewsSpec {
            chirp: ChirpSpec {
                t1_s: 10e-6,
                total_s: 15e-6,
                ..ChirpSpec::default()
            },
            record_s: 20e-6,
            window_s: 20e-6,
            after_focus_s: 10e-6,
            ..Default::default()
        }
    }

    /// The timings that go with a resolution preset: short signals for `smoke`, the
    /// report's otherwise (the mesh changes with the resolution, the experiment does not).
    pub fn preset(resolution: Resolution) -> TrNewsSpec {
        match resolution {
            Resolution::Smoke => Self::smoke(),
            Resolution::Quick | Resolution::Paper => Self::default(),
        }
    }

    /// Duration of a focusing run: the lag window plus the recording after the focus (s).
    pub fn focus_duration_s(&self) -> f64 {
        self.window_s + self.after_focus_s
    }
}

/// Runs TR-NEWS: chirp -> y -> Gamma = xcorr(y, c) -> Gamma(T - t) -> y_TR (eqs 6-9), and
/// on the responder's companions, with the error estimates of every focus. This first pass
/// of a sweep is stored with its points (see [`crate::sweep::first_pass`]).
pub fn tr_news(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let inputs = (responder.identity()?, spec);
    let foci = if spec.receivers.is_empty() {
        responder.receiver_count()
    } else {
        spec.receivers.len()
    };
    let expect = |tr: &TrNews| expect_tr_news(tr, responder, spec, foci);
    crate::sweep::first_pass("tr_news", "TR-NEWS first pass", &inputs, &expect, || {
        tr_news_computed(responder, spec)
    })
}

/// Why a stored first pass cannot be `responder`'s TR-NEWS of `spec` with `foci` foci (none
/// for a scan's shared chirp run): another spec, a response per receiver missing, another
/// number of foci, a focus at a receiver that does not exist, pulse inversion where none was
/// asked (or none where it was), companions other than the responder's.
pub(super) fn expect_tr_news(
    tr: &TrNews,
    responder: &Responder,
    spec: &TrNewsSpec,
    foci: usize,
) -> std::result::Result<(), String> {
    if tr.spec != *spec {
        return Err("is the first pass of another TR-NEWS spec".into());
    }
    let n = responder.receiver_count();
    expect_traces(&tr.responses, n, responder.dt_s)?;
    if tr.focus.len() != foci {
        return Err(format!("holds {} foci, not {foci}", tr.focus.len()));
    }
    for f in &tr.focus {
        if !(1..=n).contains(&f.receiver) {
            return Err(format!(
                "focuses at receiver {}, not within 1..{n}",
                f.receiver
            ));
        }
        if f.inverted.is_some() != spec.pulse_inversion
            || f.pi_sum.is_some() != spec.pulse_inversion
        {
            return Err(format!(
                "holds a pulse inversion at receiver {} unlike its spec",
                f.receiver
            ));
        }
    }
    if tr.companions.len() != responder.companions.len() {
        return Err(format!(
            "holds {} companions, not {}",
            tr.companions.len(),
            responder.companions.len()
        ));
    }
    tr.companions
        .iter()
        .zip(&responder.companions)
        .try_for_each(|(t, r)| expect_tr_news(t, r, spec, foci))
}

fn tr_news_computed(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let mut main = tr_news_once(responder, spec)?;
    main.companions = responder
        .companions
        .iter()
        .map(|c| tr_news_once(c, spec))
        .collect::<Result<_>>()?;
    if !main.companions.is_empty() {
        let refinement = responder.refinement()?;
        let runs: Vec<&TrNews> = std::iter::once(&main).chain(&main.companions).collect();
        let estimates = (0..main.focus.len())
            .map(|i| {
                let foci: Vec<&Focus> = runs.iter().map(|t| &t.focus[i]).collect();
                focus_estimates(&runs, &foci, refinement)
            })
            .collect::<Result<Vec<_>>>()?;
        for (f, e) in main.focus.iter_mut().zip(estimates) {
            f.estimates = Some(e);
        }
    }
    Ok(main)
}

/// The estimates of a focus from its `foci` on the main discretisation and its companions,
/// with the first passes `runs` they came from, in the order
/// [`crate::scene::SceneSpec::companions`] gives them.
pub(super) fn focus_estimates(
    runs: &[&TrNews],
    foci: &[&Focus],
    refinement: Refinement,
) -> Result<FocusEstimates> {
    let f = foci;
    let values = |q: &dyn Fn(&Focus) -> f64| -> Vec<f64> { f.iter().map(|x| q(x)).collect() };
    let scalar = |q: &dyn Fn(&Focus) -> f64| Estimate::scalar_of(&values(q), refinement);
    let spec = &runs[0].spec;
    let r = f[0].receiver - 1;
    let focus_window = (
        spec.window_s - spec.after_focus_s,
        spec.window_s + spec.after_focus_s,
    );
    let responses: Vec<&Signal> = runs.iter().map(|t| &t.responses[r]).collect();
    let focused: Vec<&Signal> = f.iter().map(|x| &x.focused).collect();
    let focused_estimate = Estimate::waveform_of(&focused, focus_window, refinement)?;
    Ok(FocusEstimates {
        response: Estimate::waveform_of(&responses, (0.0, spec.record_s), refinement)?,
        peak_amplitude: scalar(&|x| x.peak.amplitude)?,
        peak_time_s: scalar(&|x| x.peak.time_s)?,
        side_lobe_asymmetry: side_lobe_asymmetry(
            f,
            &focused,
            (&focused_estimate, focus_window),
            spec,
            refinement,
        )?,
        main_to_side_db: scalar(&|x| x.side_lobes.main_to_side_db)?,
        pi_residual: pi_residual(f, &focused_estimate, focus_window, refinement)?,
        focused: focused_estimate,
    })
}

/// The side-lobe asymmetry's estimate: its own, or where that says "refine" a bound from the
/// focused signal's errors over the two side windows ([`Estimate::energy_asymmetry`]): each
/// window's own estimate, or, the smaller where both are stated, the error of the focus
/// window (`focus`: the focused signal's estimate there, and the window), which contains it:
/// ||dy||_side <= e_f ||y||_focus.
fn side_lobe_asymmetry(
    f: &[&Focus],
    focused: &[&Signal],
    (focused_estimate, focus_window): (&Estimate, (f64, f64)),
    spec: &TrNewsSpec,
    refinement: Refinement,
) -> Result<Estimate> {
    let values: Vec<f64> = f.iter().map(|x| x.side_lobes.asymmetry).collect();
    let own = Estimate::dimensionless_of(&values, refinement)?;
    let lobes = &f[0].side_lobes;
    let (main_from, main_to) = (
        spec.window_s - spec.main_lobe_half_width_s,
        spec.window_s + spec.main_lobe_half_width_s,
    );
    // in continuous time, as the side windows' energies are (`signal::side_lobes`)
    let focus_energy = signal::window_energy(&f[0].focused, focus_window)?;
    let side_error = |window: (f64, f64), energy: f64| -> Result<Option<f64>> {
        let own = Estimate::waveform_of(focused, window, refinement)?.stated();
        let through_focus = focused_estimate
            .stated()
            .filter(|_| energy > 0.0)
            .map(|e| e * (focus_energy / energy).sqrt());
        Ok(crate::accuracy::smaller(own, through_focus))
    };
    Ok(Estimate::energy_asymmetry(
        own,
        [lobes.energy_before, lobes.energy_after],
        [
            side_error(
                (main_from - lobes.side_window_s, main_from),
                lobes.energy_before,
            )?,
            side_error((main_to, main_to + lobes.side_window_s), lobes.energy_after)?,
        ],
    ))
}

/// The PI residual's estimate, with pulse inversion: its own, or where that says "refine" a
/// bound from the errors of the PI sum (its own, or through the focused and inverted signals
/// it sums) and of the focused signal over the focus window ([`Estimate::peak_ratio`]).
fn pi_residual(
    f: &[&Focus],
    focused: &Estimate,
    window: (f64, f64),
    refinement: Refinement,
) -> Result<Option<Estimate>> {
    let Some(residuals) = f
        .iter()
        .map(|x| x.pi_residual())
        .collect::<Option<Vec<f64>>>()
    else {
        return Ok(None);
    };
    let own = Estimate::dimensionless_of(&residuals, refinement)?;
    let traces = |q: fn(&Focus) -> Option<&Signal>| -> Option<Vec<&Signal>> {
        f.iter().map(|x| q(x)).collect()
    };
    let (Some(sums), Some(inverted)) = (
        traces(|x| x.pi_sum.as_ref()),
        traces(|x| x.inverted.as_ref()),
    ) else {
        return Ok(Some(own));
    };
    let norm = |s: &Signal| -> Result<f64> { Ok(s.window(window.0, window.1)?.energy().sqrt()) };
    let sum_norm = norm(sums[0])?;
    if !(sum_norm > 0.0) {
        return Ok(Some(own));
    }
    let sum_error = Estimate::sum_error(
        &Estimate::waveform_of(&sums, window, refinement)?,
        [
            (focused, norm(&f[0].focused)? / sum_norm),
            (
                &Estimate::waveform_of(&inverted, window, refinement)?,
                norm(inverted[0])? / sum_norm,
            ),
        ],
    );
    Ok(Some(Estimate::peak_ratio(own, sum_error, focused)))
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
    let mut pass = first_pass_once(responder, spec)?;
    let receivers: Vec<usize> = if spec.receivers.is_empty() {
        (1..=pass.responses.len()).collect()
    } else {
        spec.receivers.clone()
    };
    pass.focus = foci_once(responder, &pass, &receivers)?;
    Ok(pass)
}

/// The chirp run of TR-NEWS on one discretisation: the chirp and the first-pass responses y
/// at every receiver, no focus yet.
pub(super) fn first_pass_once(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let peak_pa = responder.peak_drive();
    let chirp = spec.chirp.signal(responder.dt_s, peak_pa).map_err(|e| {
        spec_field(
            e.into(),
            &[("t1_s", "chirp.t1_s"), ("total_s", "chirp.total_s")],
        )
    })?;
    let first = responder
        .respond(&chirp, spec.record_s)
        .map_err(|e| spec_field(e, &[("duration_s", "record_s")]))?;
    Ok(TrNews {
        spec: spec.clone(),
        chirp,
        responses: first.traces,
        focus: Vec::new(),
        chirp_report: first.report,
        companions: Vec::new(),
        band: responder.band(),
    })
}

/// The focusing at each of `receivers` (1-based) from the first pass `pass` on the same
/// discretisation: Gamma, the drive Gamma(T - t) and its runs (and the inverted drive's, with
/// pulse inversion).
pub(super) fn foci_once(
    responder: &Responder,
    pass: &TrNews,
    receivers: &[usize],
) -> Result<Vec<Focus>> {
    let (spec, chirp) = (&pass.spec, &pass.chirp);
    let peak_pa = responder.peak_drive();
    let n_receivers = pass.responses.len();
    if let Some(&bad) = receivers.iter().find(|&&r| r == 0 || r > n_receivers) {
        return Err(Error::invalid(
            "tr_news.receivers",
            bad,
            format!("receivers are numbered 1..{n_receivers}"),
        ));
    }
    let mut sources = Vec::with_capacity(receivers.len());
    let mut gammas = Vec::with_capacity(receivers.len());
    for &r in receivers {
        let response = &pass.responses[r - 1];
        let gamma = signal::xcorr(response, chirp, 0.0, spec.window_s)?;
        let reversed = reversed_about_window(response, chirp, spec.window_s)?;
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
    receivers
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
        .collect()
}

/// Lags of Gamma computed past each end of the window in [`reversed_about_window`], over
/// which it is tapered to zero ([`signal::smooth_step`]) so that the band-limited shift does
/// not ring at the ends.
const REVERSAL_GUARD_SAMPLES: f64 = 256.0;

/// The report's Gamma(T - t) for 0 <= t <= T, T = `window_s`, on the run's grid t_n = n dt,
/// with Gamma = xcorr(`response`, `chirp`) (eq 8). The lags T - n dt lie on Gamma's lag grid
/// only when T is a whole number of steps; otherwise Gamma, computed and tapered a guard
/// past both ends of the window, is reversed and shifted by T with the band-limited delay
/// ([`signal::delay`]). Reversing the lags up to the last one on the grid instead moves the
/// emission, and so y_TR, by up to a step: an error of first order in dt (1.2% on the quick
/// preset). On a grid holding T the two agree to round-off.
fn reversed_about_window(response: &Signal, chirp: &Signal, window_s: f64) -> Result<Signal> {
    let guard = REVERSAL_GUARD_SAMPLES * chirp.dt_s;
    let mut gamma = signal::xcorr(response, chirp, -guard, window_s + guard)?;
    let times = gamma.times();
    for (g, t) in gamma.samples.iter_mut().zip(times) {
        *g *= signal::smooth_step((t + guard) / guard)
            * signal::smooth_step((window_s + guard - t) / guard);
    }
    let reversed = signal::delay(&signal::time_reverse(&gamma)?, window_s)?;
    Ok(reversed.window(0.0, window_s)?)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(companions: Vec<TrNews>) -> TrNews {
        TrNews {
            spec: TrNewsSpec::default(),
            chirp: Signal::new(1e-8, 0.0, vec![0.0, 1.0]).unwrap(),
            responses: Vec::new(),
            focus: Vec::new(),
            chirp_report: None,
            companions,
            band: String::new(),
        }
    }

    /// The emission is Gamma(T - t) whatever the step: through a pure delay D the emission on
    /// a step that does not divide T (2.9 ns; T / dt = 20689.66), brought onto a step that does
    /// (2.5 ns) by band-limited resampling, equals the emission computed there to 1e-5 of its
    /// norm (measured 1.8e-6). Reversing up to the last lag on the grid, as before, moved the
    /// emission 1.9 ns late: 1.4% in the same measure (asserted above 1%). The chirp is
    /// tapered, so that both steps sample nearly the same band-limited signal.
    #[test]
    fn the_emission_is_reversed_about_the_window_on_any_step() {
        let chirp = ChirpSpec {
            t1_s: 10e-6,
            total_s: 12e-6,
            taper_fraction: 0.2,
            ..ChirpSpec::default()
        };
        let (window, delay) = (60e-6, 20.3e-6);
        let emission = |dt: f64, exact: bool| {
            let c = chirp.signal(dt, 1.0).unwrap();
            let y = signal::delay(&c.pad_to((70e-6 / dt) as usize).unwrap(), delay).unwrap();
            let y = y.window(0.0, 70e-6).unwrap();
            if exact {
                reversed_about_window(&y, &c, window).unwrap()
            } else {
                let gamma = signal::xcorr(&y, &c, 0.0, window).unwrap();
                signal::time_reverse_to_start(&gamma).unwrap()
            }
        };
        let on_grid = emission(2.5e-9, true);
        for (exact, bound) in [(true, 1e-5), (false, f64::INFINITY)] {
            let off_grid = signal::resample(&emission(2.9e-9, exact), 2.5e-9).unwrap();
            let n = on_grid.len().min(off_grid.len());
            let d = crate::signal::relative_l2(
                &Signal::new(2.5e-9, 0.0, off_grid.samples[..n].to_vec()).unwrap(),
                &Signal::new(2.5e-9, 0.0, on_grid.samples[..n].to_vec()).unwrap(),
                None,
            )
            .unwrap();
            println!("reversed exactly: {exact}, off the grid against on it: {d:.2e}");
            assert!(d < bound, "{d:e}");
            if !exact {
                assert!(d > 1e-2, "the grid's rounding should show: {d:e}");
            }
        }
    }

    /// A forged first pass nesting companions a million deep is refused at the second level,
    /// never a stack overflow: TrNews is the only stored type that contains itself.
    #[test]
    fn stored_companions_nest_one_level_only() {
        let flat = crate::sweep::encode(&pass(vec![pass(vec![]), pass(vec![])])).unwrap();
        let back: TrNews = crate::sweep::decode(&flat).unwrap();
        assert_eq!(back.companions.len(), 2);
        // encode(pass(no companions)) = head, 0 (no companions), 0 (empty band).
        let one = crate::sweep::encode(&pass(vec![])).unwrap();
        let head = &one[..one.len() - 2];
        let depth = 1_000_000;
        let mut forged = Vec::with_capacity((head.len() + 2) * (depth + 1));
        for _ in 0..depth {
            forged.extend_from_slice(head);
            forged.push(1);
        }
        forged.extend_from_slice(&one);
        forged.extend(std::iter::repeat_n(0, depth));
        // (postcard drops the message of a refusal: the error only says it did not decode)
        let e = crate::sweep::decode::<TrNews>(&forged)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot decode a point"), "{e}");
        // A companion's empty list of companions still decodes after a refusal.
        assert!(crate::sweep::decode::<TrNews>(&flat).is_ok());
    }

    /// A stored first pass is checked against what the responder computes before it is used:
    /// a focus at a receiver the channel does not have (which would index past its traces),
    /// a trace missing, another spec, pulse inversion unlike the spec.
    #[test]
    fn forged_first_passes_fail_their_expectations() {
        let h = |k: usize| {
            let mut x = vec![0.0; 3000];
            x[100 + 40 * k] = 1.0;
            Signal::new(1e-8, 0.0, x).unwrap()
        };
        let r = Responder::from_impulse(vec![h(0), h(1)], 1.0, "test".into()).unwrap();
        let spec = TrNewsSpec {
            record_s: 10e-6,
            window_s: 10e-6,
            after_focus_s: 5e-6,
            chirp: crate::signal::ChirpSpec {
                t1_s: 5e-6,
                total_s: 8e-6,
                ..Default::default()
            },
            ..Default::default()
        };
        let tr = tr_news_computed(&r, &spec).unwrap();
        assert_eq!(expect_tr_news(&tr, &r, &spec, 2), Ok(()));
        let forged = |change: &dyn Fn(&mut TrNews)| {
            let mut t = tr.clone();
            change(&mut t);
            expect_tr_news(&t, &r, &spec, 2).unwrap_err()
        };
        assert!(forged(&|t| t.focus[1].receiver = 9).contains("receiver 9, not within 1..2"));
        assert!(forged(&|t| {
            t.responses.pop();
        })
        .contains("1 traces for 2 receivers"));
        assert!(forged(&|t| t.spec.record_s = 1.0).contains("another TR-NEWS spec"));
        assert!(forged(&|t| t.focus[0].pi_sum = Some(h(0))).contains("pulse inversion"));
        assert!(forged(&|t| t.companions.push(tr.clone())).contains("1 companions, not 0"));
    }
}
