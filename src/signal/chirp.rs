//! Linear chirp excitation (report eq 6, corrected per DESIGN item 3).

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::{check_alloc, finite, positive_finite, Signal, SignalError, GRID_TOL};

/// A linear chirp (report eq 6, corrected): the one parameter set of the excitation, used by
/// TR-NEWS ([`crate::trnews::TrNewsSpec`]), the resolution pilots and scripts. `Default` is the
/// report's: 0.2 -> 2 MHz over t1 = 30 us, in a 60 us signal, no taper.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ChirpSpec {
    /// Start frequency f0 (Hz).
    pub f0_hz: f64,
    /// End frequency f1 (Hz).
    pub f1_hz: f64,
    /// Sweep duration t1 (s).
    pub t1_s: f64,
    /// Length of the signal, zero after t1 (s).
    pub total_s: f64,
    /// Fraction of t1 tapered (Tukey), in [0, 1]; 0: none.
    pub taper_fraction: f64,
}

/// The report's excitation band, 0.2 -> 2 MHz (Sec. 5.1): the default chirp's sweep and the
/// default transducers' pass band.
pub const REPORT_BAND_HZ: (f64, f64) = (0.2e6, 2e6);

impl Default for ChirpSpec {
    fn default() -> Self {
        ChirpSpec {
            f0_hz: REPORT_BAND_HZ.0,
            f1_hz: REPORT_BAND_HZ.1,
            t1_s: 30e-6,
            total_s: 60e-6,
            taper_fraction: 0.0,
        }
    }
}

impl ChirpSpec {
    /// The chirp sampled at `t_k = k dt_s` for `k < round(total_s / dt_s)`:
    ///
    /// `psi(t) = 2 pi (f0 t + (f1 - f0) t^2 / (2 t1))`, `c(t) = A w(t) sin(psi(t))`
    /// for `0 <= t <= t1`, zero after, so the instantaneous frequency runs linearly from f0
    /// to f1. `w` is a Tukey taper: `taper_fraction` of `t1` is tapered, half at each end,
    /// with `w = (1 - cos(pi t / r)) / 2` on the rising ramp of length
    /// `r = taper_fraction t1 / 2` (mirrored at the end). Both frequencies must be below the
    /// Nyquist frequency `1 / (2 dt_s)`.
    pub fn signal(&self, dt_s: f64, amplitude: f64) -> Result<Signal, SignalError> {
        let ChirpSpec {
            f0_hz,
            f1_hz,
            t1_s,
            total_s,
            taper_fraction,
        } = *self;
        positive_finite("dt_s", dt_s)?;
        positive_finite("t1_s", t1_s)?;
        finite("amplitude", amplitude)?;
        check_frequency("f0_hz", f0_hz, dt_s)?;
        check_frequency("f1_hz", f1_hz, dt_s)?;
        if !(total_s.is_finite() && total_s >= t1_s) {
            return Err(SignalError::InvalidParameter {
                name: "total_s",
                requirement: "finite and at least t1_s",
                value: total_s,
            });
        }
        if !(0.0..=1.0).contains(&taper_fraction) {
            return Err(SignalError::InvalidParameter {
                name: "taper_fraction",
                requirement: "in [0, 1]",
                value: taper_fraction,
            });
        }
        let n = (total_s / dt_s).round();
        check_alloc("chirp", n)?;
        let ramp_s = 0.5 * taper_fraction * t1_s;
        let t_last = t1_s + GRID_TOL * dt_s;
        let samples = (0..n as usize)
            .map(|k| {
                let t = k as f64 * dt_s;
                if t > t_last {
                    return 0.0;
                }
                let psi = 2.0 * PI * (f0_hz * t + (f1_hz - f0_hz) * t * t / (2.0 * t1_s));
                amplitude * tukey(t.min(t1_s), t1_s, ramp_s) * psi.sin()
            })
            .collect();
        Signal::new(dt_s, 0.0, samples)
    }
}

/// Tukey taper on `[0, t1]` with cosine ramps of length `ramp_s` at both ends.
fn tukey(t: f64, t1: f64, ramp_s: f64) -> f64 {
    let edge = t.min(t1 - t);
    if edge >= ramp_s {
        1.0
    } else {
        0.5 * (1.0 - (PI * edge / ramp_s).cos())
    }
}

/// A chirp frequency must lie in `[0, Nyquist)`.
fn check_frequency(name: &'static str, f_hz: f64, dt_s: f64) -> Result<(), SignalError> {
    let nyquist_hz = 0.5 / dt_s;
    if !(f_hz >= 0.0 && f_hz < nyquist_hz) {
        return Err(SignalError::InvalidParameter {
            name,
            requirement: "in [0, Nyquist = 1/(2 dt_s))",
            value: f_hz,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::instantaneous_frequency;
    use super::*;

    const F0: f64 = 0.2e6;
    const F1: f64 = 2e6;
    const T1: f64 = 30e-6;
    const DT: f64 = 10e-9;

    /// The chirp of these parameters (the order of report eq 6).
    fn chirp(
        f0_hz: f64,
        f1_hz: f64,
        t1_s: f64,
        total_s: f64,
        dt_s: f64,
        amplitude: f64,
        taper_fraction: f64,
    ) -> Result<Signal, SignalError> {
        let spec = ChirpSpec {
            f0_hz,
            f1_hz,
            t1_s,
            total_s,
            taper_fraction,
        };
        spec.signal(dt_s, amplitude)
    }

    /// `(t, f_inst(t))` over the chirp's middle 80%.
    fn middle_frequencies(taper_fraction: f64) -> Vec<(f64, f64)> {
        let c = chirp(F0, F1, T1, 60e-6, DT, 1.0, taper_fraction).expect("valid chirp");
        assert_eq!(c.len(), 6000);
        let fi = instantaneous_frequency(&c).expect("long enough");
        let (k0, k1) = ((0.1 * T1 / DT) as usize, (0.9 * T1 / DT) as usize);
        (k0..=k1).map(|k| (fi.time_at(k), fi.samples[k])).collect()
    }

    fn linear(t: f64) -> f64 {
        F0 + (F1 - F0) * t / T1
    }

    // Why 1% of the sweep span f1 - f0 and not of the local frequency: the
    // Hilbert phase of a finite chirp ripples at 2 f(t) because the abrupt ends and
    // the low start (local bandwidth sqrt(1.8 MHz / 30 us) = 0.24 MHz against
    // f = 0.38 MHz at 10% of the sweep) leak to negative frequencies; measured
    // ripple: 8% of f(t) at 10%, 1.7% at 50% without taper.

    #[test]
    fn instantaneous_frequency_fits_the_linear_sweep() {
        // untapered (the report's chirp): the least-squares line through f_inst over
        // the middle 80% hits f0 and f1 within 1% of the span (measured 0.1%)
        let pts = middle_frequencies(0.0);
        let n = pts.len() as f64;
        let (st, sf) = pts.iter().fold((0.0, 0.0), |(a, b), (t, f)| (a + t, b + f));
        let (tm, fm) = (st / n, sf / n);
        let (stt, stf) = pts.iter().fold((0.0, 0.0), |(a, b), (t, f)| {
            (a + (t - tm).powi(2), b + (t - tm) * (f - fm))
        });
        let slope = stf / stt;
        let (f0_fit, f1_fit) = (fm - slope * tm, fm + slope * (T1 - tm));
        assert!((f0_fit - F0).abs() < 0.01 * (F1 - F0), "{f0_fit}");
        assert!((f1_fit - F1).abs() < 0.01 * (F1 - F0), "{f1_fit}");
    }

    #[test]
    fn instantaneous_frequency_is_linear_from_f0_to_f1() {
        // 10% Tukey taper (ramps outside the middle 80%): pointwise within 1% of
        // the span over the middle 80% (measured 0.57%)
        for (t, f) in middle_frequencies(0.1) {
            let err = (f - linear(t)).abs() / (F1 - F0);
            assert!(err < 0.01, "t = {t}: {f} vs {}", linear(t));
        }
    }

    #[test]
    fn chirp_is_zero_after_t1_and_tapered() {
        let c = chirp(0.2e6, 2e6, 30e-6, 60e-6, 10e-9, 2.0, 0.2).expect("valid chirp");
        assert!(c.samples[3001..].iter().all(|&v| v == 0.0));
        // exact: the taper is 0 at both ends of [0, t1]
        assert_eq!(c.samples[0], 0.0);
        assert!(c.samples[3000].abs() < 1e-12);
        assert!(c.max_abs() <= 2.0 && c.max_abs() > 1.99);
    }

    #[test]
    fn chirp_rejects_bad_parameters() {
        let e = chirp(0.2e6, 60e6, 30e-6, 60e-6, 10e-9, 1.0, 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("f1_hz") && e.contains("6e7"), "{e}");
        assert!(chirp(0.2e6, 2e6, 30e-6, 10e-6, 10e-9, 1.0, 0.0).is_err());
        assert!(chirp(0.2e6, 2e6, 30e-6, 60e-6, 10e-9, 1.0, 1.5).is_err());
    }
}
