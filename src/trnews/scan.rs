//! A scan: the TR-NEWS focus moved along the receivers (positions on the top surface, or any
//! line of receivers), as a lab scans its focal point to map where the nonlinearity is. The
//! chirp run is shared (one run records every position); each position is then a work unit
//! of [`crate::sweep`] (stored when done, resumed, shardable): the focusing drive and its
//! inverse (pulse inversion) and one delayed drive (eqs 10-11), on the responder and its
//! companions, with every measure's error estimate.

use super::channel::{Channel, Responder};
use super::delayed::{delayed_at, report_note, Delayed};
use super::focus::{
    expect_tr_news, first_pass_once, foci_once, focus_estimates, Focus, TrNews, TrNewsSpec,
};
use crate::accuracy::{Estimate, Refinement};
use crate::error::{Error, Result};
use crate::signal::{self, Detrend, Signal, Window};
use crate::sweep::{Key, PointSpec, Sweep, SweepError};
use serde::{Deserialize, Serialize};

/// One position of a scan.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ScanPoint {
    /// The focus at this receiver, with its pulse inversion and, with companions, its
    /// estimates (PI residual, side-lobe asymmetry, y_TR, ...).
    pub focus: Focus,
    /// The delayed drive at this receiver: its misfit to the linear prediction.
    pub delayed: Delayed,
}

/// A scan: the shared first pass (chirp responses at every position, on the responder and
/// its companions) and the points, in the order of the receivers scanned.
#[derive(Clone, Debug)]
pub struct Scan {
    /// The receivers scanned (1-based), in order.
    pub receivers: Vec<usize>,
    /// The chirp run: [`TrNews::responses`] at every receiver, no focus.
    pub first_pass: TrNews,
    /// One point per receiver scanned; none for a survey (the chirp run only).
    pub points: Vec<ScanPoint>,
    /// How the companions refine, with companions.
    pub refinement: Option<Refinement>,
}

impl Scan {
    /// The crack's spectral shift at each scanned position: the mean frequency
    /// ([`mean_frequency_hz`]) of the first-pass response less `baseline`'s (the uncracked
    /// scene's scan of the same receivers), with its estimate from the shifts on the
    /// companions when both scans have them (a linear baseline has none at half the step: its
    /// main run is paired with the cracked scan's), or where those say "refine" a bound from
    /// the two responses' errors ([`Estimate::mean_frequency_shift`]).
    pub fn spectral_shifts(&self, baseline: &Scan) -> Result<Vec<(f64, Option<Estimate>)>> {
        if self.receivers != baseline.receivers {
            return Err(Error::invalid(
                "baseline",
                format!("receivers {:?}", baseline.receivers),
                format!("must be the scan's own receivers, {:?}", self.receivers),
            ));
        }
        let passes = |s: &Scan| -> Vec<TrNews> {
            std::iter::once(&s.first_pass)
                .chain(&s.first_pass.companions)
                .cloned()
                .collect()
        };
        let (own, base) = (passes(self), passes(baseline));
        // A linear baseline has no companion at half the step (its step's error is the
        // time-dispersion transforms' to remove): its main run stands for it.
        let estimated = match (self.refinement, baseline.refinement) {
            (Some(r), Some(_)) if own.len() == base.len() || own.len() == base.len() + 1 => Some(r),
            _ => None,
        };
        let runs = if estimated.is_some() { own.len() } else { 1 };
        self.receivers
            .iter()
            .map(|&k| {
                let moments = |passes: &[TrNews]| -> Result<Vec<(f64, f64)>> {
                    (0..runs)
                        .map(|d| {
                            spectrum_moments_hz(
                                &passes.get(d).unwrap_or(&passes[0]).responses[k - 1],
                            )
                        })
                        .collect()
                };
                let (cracked, uncracked) = (moments(&own)?, moments(&base)?);
                let shifts: Vec<f64> = cracked
                    .iter()
                    .zip(&uncracked)
                    .map(|(c, u)| c.0 - u.0)
                    .collect();
                let estimate = estimated
                    .map(|r| -> Result<Estimate> {
                        let own_estimate = Estimate::scalar_of(&shifts, r)?;
                        let record = (0.0, self.first_pass.spec.record_s);
                        let trace_error = |passes: &[TrNews]| {
                            let traces: Vec<&Signal> =
                                passes.iter().map(|p| &p.responses[k - 1]).collect();
                            Estimate::waveform_of(&traces, record, r)
                        };
                        Ok(Estimate::mean_frequency_shift(
                            own_estimate,
                            [
                                (cracked[0].1, &trace_error(&own)?),
                                (uncracked[0].1, &trace_error(&base)?),
                            ],
                        ))
                    })
                    .transpose()?;
                Ok((shifts[0], estimate))
            })
            .collect()
    }
}

/// The delayed drive of every position of a scan: `delays_s` and `amplitudes` (eq 10) and the
/// half width added around the focus times for the misfit's window.
#[derive(Clone, Debug, Serialize)]
pub struct ScanDrive {
    /// Delays tau_i (s).
    pub delays_s: Vec<f64>,
    /// Amplitudes a_i, one per delay.
    pub amplitudes: Vec<f64>,
    /// The misfit window's half width around the focus times (s).
    pub half_window_s: f64,
}

/// Scans `receivers` (1-based; empty = every receiver of the responder) with TR-NEWS of
/// `spec` (pulse inversion on, whatever `spec` says) and the delayed drive `drive`; with
/// `focus` false, a survey: the chirp run only, for the spectral shifts.
pub fn scan(
    r: &Responder,
    spec: &TrNewsSpec,
    receivers: &[usize],
    drive: &ScanDrive,
    focus: bool,
) -> std::result::Result<Scan, SweepError> {
    let spec = TrNewsSpec {
        pulse_inversion: true,
        receivers: Vec::new(),
        ..spec.clone()
    };
    let n = r.receiver_count();
    let receivers: Vec<usize> = if receivers.is_empty() {
        (1..=n).collect()
    } else {
        receivers.to_vec()
    };
    if let Some(&bad) = receivers.iter().find(|&&k| k == 0 || k > n) {
        return Err(Error::invalid(
            "scan.receivers",
            bad,
            format!("receivers are numbered 1..{n}"),
        )
        .into());
    }
    check_drive(drive)?;
    if matches!(r.channel(), Channel::Recorded(_)) {
        return Err(Error::invalid(
            "scan",
            "a recorded channel",
            "scans a simulated scene or a measured impulse response: recordings hold only the \
             drives sent in the lab",
        )
        .into());
    }
    let first_pass = shared_first_pass(r, &spec)?;
    let refinement = if r.companions().is_empty() {
        None
    } else {
        Some(r.refinement()?)
    };
    if !focus {
        return Ok(Scan {
            receivers,
            first_pass,
            points: Vec::new(),
            refinement,
        });
    }
    let identity = r.identity()?;
    let specs = receivers
        .iter()
        .map(|&k| {
            let inputs = (&identity, &spec, k, drive);
            Ok(PointSpec {
                key: Key::of("scan", &inputs)?,
                label: format!("receiver {k}"),
                sharded: r.simulates(),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let how = if r.simulates() {
        "simulated"
    } else {
        "convolved or recorded"
    };
    let name = format!("scan over {} receivers ({how})", receivers.len());
    let estimates = !r.companions().is_empty();
    let expect = |p: &ScanPoint| expect_point(p, r.dt_s(), estimates);
    let sweep = Sweep::start::<ScanPoint>(&name, "scan", specs, &expect);
    crate::parallel::try_for_each(sweep.pending(), |&i| {
        let start = std::time::Instant::now();
        let outcome = scan_point(r, &first_pass, receivers[i], drive);
        let note = outcome
            .as_ref()
            .ok()
            .and_then(|p| p.delayed.report.as_ref())
            .map(report_note)
            .unwrap_or_default();
        sweep.record(i, outcome, start.elapsed().as_secs_f64(), &note)
    })?;
    Ok(Scan {
        receivers,
        first_pass,
        points: sweep.finish()?,
        refinement,
    })
}

/// A drive with one amplitude per finite delay >= 0, and a finite half window >= 0.
fn check_drive(drive: &ScanDrive) -> Result<()> {
    if let Some(bad) = drive
        .delays_s
        .iter()
        .find(|d| !(d.is_finite() && **d >= 0.0))
    {
        return Err(Error::invalid(
            "scan.delays_s",
            bad,
            "delays must be finite and >= 0",
        ));
    }
    if let Some(bad) = drive.amplitudes.iter().find(|a| !a.is_finite()) {
        return Err(Error::invalid(
            "scan.amplitudes",
            bad,
            "amplitudes must be finite",
        ));
    }
    if drive.delays_s.len() != drive.amplitudes.len() || drive.delays_s.is_empty() {
        return Err(Error::invalid(
            "scan.amplitudes",
            format!(
                "{} delays, {} amplitudes",
                drive.delays_s.len(),
                drive.amplitudes.len()
            ),
            "give one amplitude per delay, at least one",
        ));
    }
    if !(drive.half_window_s.is_finite() && drive.half_window_s >= 0.0) {
        return Err(Error::invalid(
            "scan.half_window_s",
            drive.half_window_s,
            "must be finite and >= 0",
        ));
    }
    Ok(())
}

/// The chirp run on the responder and its companions, stored as a first pass.
fn shared_first_pass(r: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let inputs = (r.identity()?, spec);
    let expect = |tr: &TrNews| expect_tr_news(tr, r, spec, 0);
    crate::sweep::first_pass(
        "scan_first_pass",
        "scan first pass",
        &inputs,
        &expect,
        || {
            let mut main = first_pass_once(r, spec)?;
            main.companions = r
                .companions
                .iter()
                .map(|c| first_pass_once(c, spec))
                .collect::<Result<_>>()?;
            Ok(main)
        },
    )
}

/// Why a stored point cannot be a scan point on step `dt_s`, with `estimates` when the
/// responder has companions.
fn expect_point(p: &ScanPoint, dt_s: f64, estimates: bool) -> std::result::Result<(), String> {
    if p.focus.focused.dt_s != dt_s || p.focus.pi_sum.is_none() {
        return Err("holds a focus on another step or without pulse inversion".into());
    }
    if p.focus.estimates.is_some() != estimates || p.delayed.estimates.is_some() != estimates {
        return Err("holds error estimates unlike its responder".into());
    }
    if p.delayed.simulation.dt_s != dt_s || p.delayed.simulation.len() != p.delayed.prediction.len()
    {
        return Err("holds a delayed simulation and prediction on different grids".into());
    }
    Ok(())
}

/// One position: the focus at receiver `k` on every discretisation, its estimates, and the
/// delayed drive there.
fn scan_point(r: &Responder, pass: &TrNews, k: usize, drive: &ScanDrive) -> Result<ScanPoint> {
    let mut foci = vec![foci_once(r, pass, &[k])?.remove(0)];
    for (c, t) in r.companions.iter().zip(&pass.companions) {
        foci.push(foci_once(c, t, &[k])?.remove(0));
    }
    if foci.len() > 1 {
        let runs: Vec<&TrNews> = std::iter::once(pass).chain(&pass.companions).collect();
        let estimates = focus_estimates(&runs, &foci.iter().collect::<Vec<_>>(), r.refinement()?)?;
        foci[0].estimates = Some(estimates);
    }
    let point = [(drive.delays_s.clone(), drive.amplitudes.clone())];
    let longest = drive.delays_s.iter().fold(0.0f64, |m, d| m.max(*d));
    let delayed = delayed_at(
        r,
        &pass.spec,
        &foci.iter().collect::<Vec<_>>(),
        &point,
        drive.half_window_s,
        longest,
    )?
    .remove(0);
    Ok(ScanPoint {
        focus: foci.swap_remove(0),
        delayed,
    })
}

/// The mean frequency sum f P(f) / sum P(f) of `s`'s Welch spectrum (Hann segments of a
/// quarter of the trace, half overlapping, no detrending), the measure of the crack's spectral
/// shift (the report's "virtual transducer", Sec. 5.4).
pub fn mean_frequency_hz(s: &Signal) -> Result<f64> {
    Ok(spectrum_moments_hz(s)?.0)
}

/// The mean frequency of `s`'s Welch spectrum ([`mean_frequency_hz`]) and its spread, the
/// standard deviation sqrt(sum (f - mean)^2 P(f) / sum P(f)).
fn spectrum_moments_hz(s: &Signal) -> Result<(f64, f64)> {
    let p = signal::welch(s, (s.len() / 4).max(2), 0.5, Window::Hann, Detrend::None)?;
    let power: f64 = p.psd.iter().sum();
    if !(power > 0.0) {
        return Err(Error::invalid(
            "trace",
            "all zero",
            "has no spectrum to take a mean frequency of",
        ));
    }
    let moment = |g: &dyn Fn(f64) -> f64| -> f64 {
        p.freqs_hz
            .iter()
            .zip(&p.psd)
            .map(|(f, v)| g(*f) * v)
            .sum::<f64>()
            / power
    };
    let mean = moment(&|f| f);
    Ok((mean, moment(&|f| (f - mean).powi(2)).sqrt()))
}

/// Where a scan's map puts the crack: the extent [from_m, to_m] of the map's peak at half its
/// height above the map's floor, its centre and its length.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Localisation {
    /// Left end of the extent (m).
    pub from_m: f64,
    /// Right end of the extent (m).
    pub to_m: f64,
    /// Centre (from + to) / 2 (m).
    pub centre_m: f64,
    /// Length to - from (m).
    pub length_m: f64,
    /// Position of the map's largest value (m).
    pub peak_m: f64,
}

/// Locates the crack from a scan's map `values` at focus positions `x_m` (increasing): the
/// map's floor is its smallest value and its peak its largest; the extent is the run of
/// positions around the peak where the map stays above floor + (peak - floor) / 2, its ends
/// interpolated linearly between the last position above and the first below (the full width
/// at half maximum). A nonlinear source of length L seen through a focal spot much narrower
/// than L gives an extent of L; a spot as wide as the crack widens it.
pub fn localise(x_m: &[f64], values: &[f64]) -> Result<Localisation> {
    if x_m.len() != values.len() || x_m.len() < 3 {
        return Err(Error::invalid(
            "map",
            format!("{} positions, {} values", x_m.len(), values.len()),
            "needs as many values as positions, at least 3",
        ));
    }
    if let Some(w) = x_m.windows(2).find(|w| !(w[1] > w[0])) {
        return Err(Error::invalid(
            "map positions",
            format!("{} then {}", w[0], w[1]),
            "must increase",
        ));
    }
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(Error::invalid("map values", bad, "must be finite"));
    }
    let (mut top, mut floor) = (0, f64::INFINITY);
    for (i, &v) in values.iter().enumerate() {
        if v > values[top] {
            top = i;
        }
        floor = floor.min(v);
    }
    let half = floor + (values[top] - floor) / 2.0;
    if !(values[top] > floor) {
        return Err(Error::invalid(
            "map values",
            values[top],
            "are all equal: nothing to locate",
        ));
    }
    // the crossing between positions i (above) and j (below or at half)
    let crossing = |i: usize, j: usize| {
        x_m[i] + (x_m[j] - x_m[i]) * (values[i] - half) / (values[i] - values[j])
    };
    let left = (0..top).rev().find(|&j| values[j] <= half);
    let right = (top + 1..values.len()).find(|&j| values[j] <= half);
    let (Some(l), Some(r)) = (left, right) else {
        return Err(Error::invalid(
            "map",
            format!("peak at {} m", x_m[top]),
            "does not fall to half its height on both sides within the scan: widen it",
        ));
    };
    let (from_m, to_m) = (crossing(l + 1, l), crossing(r - 1, r));
    Ok(Localisation {
        from_m,
        to_m,
        centre_m: (from_m + to_m) / 2.0,
        length_m: to_m - from_m,
        peak_m: x_m[top],
    })
}

/// Locates the crack from one map scanned twice at the same positions `x_m`, with the
/// transmitter on the right (`right`) and on the left (`left`). Each view is scaled from its
/// floor (0) to its peak (1), and the smaller of the two at each position is located by
/// [`localise`]. The crack shows in both views; its shadow (the positions beyond it, as seen
/// from the transmitter, which the drive reaches through the crack) shows in one view only,
/// on opposite sides, so the smaller of the two keeps the crack and drops both shadows.
pub fn localise_sides(x_m: &[f64], right: &[f64], left: &[f64]) -> Result<Localisation> {
    if right.len() != left.len() {
        return Err(Error::invalid(
            "map",
            format!("{} values right, {} left", right.len(), left.len()),
            "needs the same positions from both sides",
        ));
    }
    let (r, l) = (scaled(right, "right")?, scaled(left, "left")?);
    let both: Vec<f64> = r.iter().zip(&l).map(|(a, b)| a.min(*b)).collect();
    localise(x_m, &both)
}

/// A map scaled from its smallest value (0) to its largest (1).
fn scaled(values: &[f64], view: &str) -> Result<Vec<f64>> {
    let field = format!("{view} map values");
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(Error::invalid(&field, bad, "must be finite"));
    }
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !(hi > lo) {
        return Err(Error::invalid(
            &field,
            hi,
            "are all equal: nothing to locate",
        ));
    }
    Ok(values.iter().map(|v| (v - lo) / (hi - lo)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace moved by a relative L2 error e moves its mean frequency by at most
    /// 2 sigma e / (1 - e)^2 (`Estimate::mean_frequency_shift`), in every band-limited
    /// direction tried (a delay, a scaling, a tone elsewhere in the band), and the worst
    /// direction, whose spectrum is (f - mean) X(f) (the envelope's derivative on the
    /// quadrature carrier), comes within a factor 2 of it.
    #[test]
    fn mean_frequency_moves_within_twice_the_spread_times_the_error() {
        let (dt, n, f0, width) = (20e-9, 4096, 1e6, 4e-6);
        let t = |k: usize| k as f64 * dt - 0.5 * n as f64 * dt;
        let envelope = |t: f64| (-(t / width).powi(2) / 2.0).exp();
        let tone = |f: f64, delay: f64| -> Vec<f64> {
            (0..n)
                .map(|k| {
                    envelope(t(k) - delay) * (std::f64::consts::TAU * f * (t(k) - delay)).cos()
                })
                .collect()
        };
        let x = tone(f0, 0.0);
        let worst: Vec<f64> = (0..n)
            .map(|k| {
                -t(k) / width.powi(2) * envelope(t(k)) * (std::f64::consts::TAU * f0 * t(k)).sin()
            })
            .collect();
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        let signal = |v: Vec<f64>| Signal::new(dt, 0.0, v).unwrap();
        let (mean, sigma) = spectrum_moments_hz(&signal(x.clone())).unwrap();
        for e in [0.01, 0.05] {
            let bound = 2.0 * sigma * e / (1.0 - e).powi(2);
            let mut largest: f64 = 0.0;
            for direction in [
                worst.clone(),
                tone(f0, 0.1e-6),
                x.clone(),
                tone(1.5e6, 0.0),
                tone(0.6e6, 1e-6),
            ] {
                for sign in [1.0, -1.0] {
                    let scale = sign * e * norm(&x) / norm(&direction);
                    let moved: Vec<f64> = x
                        .iter()
                        .zip(&direction)
                        .map(|(a, d)| a + scale * d)
                        .collect();
                    let shift = (spectrum_moments_hz(&signal(moved)).unwrap().0 - mean).abs();
                    assert!(shift <= bound, "e {e}: {shift} > {bound}");
                    largest = largest.max(shift);
                }
            }
            assert!(largest >= 0.5 * bound, "e {e}: worst {largest} of {bound}");
        }
    }

    /// A crack of length L at c seen through a Gaussian spot of half width at half maximum w:
    /// the map (a rectangle smoothed by the spot) is located to within a tenth of the scan's
    /// spacing in centre, and its extent is L to within 2% while the spot is a fifth of the
    /// crack (the smoothing moves the half-maximum points by O(w^2 / L) only where the
    /// flanks overlap).
    #[test]
    fn a_smoothed_rectangle_is_located_at_its_half_maximum() {
        let (c, length, w) = (3.1e-3, 2e-3, 0.2e-3);
        let x: Vec<f64> = (0..41).map(|i| 1e-3 + i as f64 * 0.125e-3).collect();
        let map: Vec<f64> = x
            .iter()
            .map(|&x| 0.02 + 0.1 * seen_through_spot(w, x, c - length / 2.0, c + length / 2.0))
            .collect();
        let l = localise(&x, &map).unwrap();
        assert!((l.centre_m - c).abs() < 0.0125e-3, "{l:?}");
        assert!((l.length_m - length).abs() < 0.02 * length, "{l:?}");
    }

    /// A crack of length L at c whose map carries a shadow: half the crack's height over 2 mm
    /// beyond it as seen from the transmitter (the left side with the transmitter on the
    /// right, the right side in the mirror view). One view alone is located 0.5 mm or more
    /// off in centre; both together find the crack as without the shadow (a tenth of the
    /// spacing in centre, 2% in length), though the right view's peak is twice the left's.
    #[test]
    fn two_views_drop_the_shadows_each_casts_on_its_far_side() {
        let (c, length, w) = (8.3e-3, 2e-3, 0.2e-3);
        let x: Vec<f64> = (0..41).map(|i| 1e-3 + i as f64 * 0.35e-3).collect();
        let band = |x: f64, a: f64, b: f64| seen_through_spot(w, x, a, b);
        let (a, b) = (c - length / 2.0, c + length / 2.0);
        let right: Vec<f64> = x
            .iter()
            .map(|&x| 0.02 + 0.2 * band(x, a, b) + 0.1 * band(x, a - 2e-3, a))
            .collect();
        let left: Vec<f64> = x
            .iter()
            .map(|&x| -0.05 + 0.1 * band(x, a, b) + 0.05 * band(x, b, b + 2e-3))
            .collect();
        let alone = localise(&x, &right).unwrap();
        assert!((alone.centre_m - c).abs() > 0.5e-3, "{alone:?}");
        let both = localise_sides(&x, &right, &left).unwrap();
        assert!((both.centre_m - c).abs() < 0.035e-3, "{both:?}");
        assert!((both.length_m - length).abs() < 0.02 * length, "{both:?}");
        let e = localise_sides(&x, &right, &left[1..])
            .unwrap_err()
            .to_string();
        assert!(e.contains("same positions"), "{e}");
        let e = localise_sides(&x, &right, &vec![1.0; x.len()])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("left map values") && e.contains("all equal"),
            "{e}"
        );
    }

    /// A map that does not fall to half its height on one side, a map without a peak and
    /// positions out of order are errors naming what is wrong.
    #[test]
    fn maps_that_cannot_locate_are_refused() {
        let x = [1.0, 2.0, 3.0, 4.0];
        let e = localise(&x, &[0.0, 1.0, 2.0, 3.0]).unwrap_err().to_string();
        assert!(e.contains("half its height"), "{e}");
        let e = localise(&x, &[1.0; 4]).unwrap_err().to_string();
        assert!(e.contains("all equal"), "{e}");
        let e = localise(&[1.0, 3.0, 2.0, 4.0], &[0.0, 1.0, 0.0, 0.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("must increase"), "{e}");
        let e = localise(&x, &[0.0, f64::NAN, 0.0, 0.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite"), "{e}");
    }

    /// The band [a, b] seen at x through a Gaussian spot of half width at half maximum w: the
    /// band's indicator convolved with the spot, (erf((x - a) / s) - erf((x - b) / s)) / 2
    /// with s = sqrt(2) sigma.
    fn seen_through_spot(w: f64, x: f64, a: f64, b: f64) -> f64 {
        let s = w / (2.0 * 2.0f64.ln()).sqrt() * 2f64.sqrt();
        (erf((x - a) / s) - erf((x - b) / s)) / 2.0
    }

    /// erf to 1.5e-7 (Abramowitz and Stegun 7.1.26), for the test's smoothed rectangle.
    fn erf(x: f64) -> f64 {
        let t = 1.0 / (1.0 + 0.3275911 * x.abs());
        let y = 1.0
            - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t
                + 0.254829592)
                * t
                * (-x * x).exp();
        y.copysign(x)
    }
}
