//! Time reversal, delays and delay-and-sum (report eq 10).

use rustfft::num_complex::Complex;

use super::fft::{fast_len, forward_real, inverse_real, signed_bin};
use super::{check_alloc, finite, require_len, Signal, SignalError, GRID_TOL};

/// Extra zero padding (samples) beyond the content, so band-limited shift
/// tails do not wrap around the FFT buffer into the output.
const SHIFT_PAD: usize = 64;

/// `s(-t)`: sample order reversed and `t0 -> -t_end`, so a sample at time `t`
/// moves to `-t`. Applying it twice is the identity.
pub fn time_reverse(s: &Signal) -> Result<Signal, SignalError> {
    s.validate()?;
    Ok(Signal {
        dt_s: s.dt_s,
        t0_s: -s.t_end_s(),
        samples: s.samples.iter().rev().copied().collect(),
    })
}

/// What an experiment transmits: the reversed samples starting at `t0 = 0`,
/// i.e. `s(t_end - t)` when `s` starts at 0 (the report's `Gamma(T - t)` with
/// `T = t_end`).
pub fn time_reverse_to_start(s: &Signal) -> Result<Signal, SignalError> {
    Ok(Signal {
        t0_s: 0.0,
        ..time_reverse(s)?
    })
}

/// `s(t - tau)`. The integer part of `tau / dt` shifts `t0` exactly (same
/// samples); a fractional remainder is applied as the band-limited phase shift
/// `X(f) exp(-2 pi i f tau_frac)` on a zero-padded FFT, so the output stays on the
/// grid `s.t0 + m dt` and gains one sample to hold the shifted content.
pub fn delay(s: &Signal, tau_s: f64) -> Result<Signal, SignalError> {
    delay_and_sum(s, &[tau_s], &[1.0])
}

/// Delay-and-sum, report eq 10: `sum_i a_i s(t - tau_i)`.
///
/// Output grid: `t0 = s.t0 + m0 dt` with `m0 = floor(min_i tau_i / dt)`, long
/// enough to hold every delayed copy. When every `tau_i` is an integer number of
/// samples (within 1e-6) the copies are shifted and added exactly; otherwise the
/// sum is formed as one spectrum `S(f) sum_i a_i exp(-2 pi i f tau_i)` and one
/// inverse FFT (band-limited, as [`delay`]).
pub fn delay_and_sum(
    s: &Signal,
    delays_s: &[f64],
    amplitudes: &[f64],
) -> Result<Signal, SignalError> {
    s.validate()?;
    if delays_s.len() != amplitudes.len() {
        return Err(SignalError::LengthMismatch {
            name_a: "delays_s",
            len_a: delays_s.len(),
            name_b: "amplitudes",
            len_b: amplitudes.len(),
        });
    }
    require_len("delays_s", delays_s.len(), 1)?;
    delays_s.iter().try_for_each(|&d| finite("delays_s", d))?;
    amplitudes
        .iter()
        .try_for_each(|&a| finite("amplitudes", a))?;
    let dt = s.dt_s;
    let in_samples: Vec<f64> = delays_s.iter().map(|d| d / dt).collect();
    let m0 = (in_samples.iter().fold(f64::INFINITY, |m, &d| m.min(d)) + GRID_TOL).floor();
    let rel: Vec<f64> = in_samples.iter().map(|d| snap(d - m0)).collect();
    let extra = rel.iter().fold(0.0f64, |m, &d| m.max(d.ceil()));
    check_alloc("delayed signal", s.len() as f64 + extra)?;
    let out_len = s.len() + extra as usize;
    let terms: Vec<(f64, f64)> = amplitudes.iter().copied().zip(rel).collect();
    let samples = if terms.iter().all(|&(_, d)| d.fract() == 0.0) {
        shift_add(&s.samples, &terms, out_len)
    } else {
        spectral_shift_add(&s.samples, &terms, out_len)
    };
    Ok(Signal {
        dt_s: dt,
        t0_s: s.t0_s + m0 * dt,
        samples,
    })
}

/// Rounds a delay (in samples) to the nearest integer when within [`GRID_TOL`].
fn snap(d: f64) -> f64 {
    let r = d.round();
    if (d - r).abs() <= GRID_TOL {
        r
    } else {
        d.max(0.0)
    }
}

/// Exact `y_j = sum_i a_i x_{j - d_i}` for integer `d_i >= 0`.
fn shift_add(x: &[f64], terms: &[(f64, f64)], out_len: usize) -> Vec<f64> {
    let mut y = vec![0.0; out_len];
    for &(a, d) in terms {
        for (o, v) in y[d as usize..].iter_mut().zip(x) {
            *o += a * v;
        }
    }
    y
}

/// Band-limited `y(t) = sum_i a_i x(t - d_i)` (d in samples) via
/// `Y_k = X_k sum_i a_i exp(-2 pi i k' d_i / L)`, `k'` the signed bin.
fn spectral_shift_add(x: &[f64], terms: &[(f64, f64)], out_len: usize) -> Vec<f64> {
    let len = fast_len(out_len + x.len() + SHIFT_PAD);
    let mut spec = forward_real(x, len);
    let w = -2.0 * std::f64::consts::PI / len as f64;
    for (k, z) in spec.iter_mut().enumerate() {
        let kk = signed_bin(k, len);
        let h: Complex<f64> = terms
            .iter()
            .map(|&(a, d)| Complex::from_polar(a, w * kk * d))
            .sum();
        *z *= h;
    }
    let mut y = inverse_real(spec);
    y.truncate(out_len);
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian_pulse(t: f64) -> f64 {
        // carrier 0.08 cycles/sample, sigma 6 samples: spectrum far below Nyquist
        (-((t - 80.0) / 6.0).powi(2) / 2.0).exp() * (2.0 * std::f64::consts::PI * 0.08 * t).cos()
    }

    fn pulse_signal(dt: f64, t0: f64, n: usize, shift: f64) -> Signal {
        let x = (0..n)
            .map(|k| gaussian_pulse(t0 / dt + k as f64 - shift))
            .collect();
        Signal::new(dt, t0, x).expect("finite pulse")
    }

    fn max_abs_diff(a: &Signal, b: &Signal) -> f64 {
        a.sub(b).expect("aligned").max_abs()
    }

    #[test]
    fn time_reverse_twice_is_identity() {
        // exact: only sample reordering and t0 negation
        let s = pulse_signal(1e-8, 3e-7, 200, 0.0);
        let r = time_reverse(&s).expect("valid");
        assert!((r.t0_s + s.t_end_s()).abs() < 1e-20);
        assert_eq!(r.samples[0], s.samples[199]);
        let rr = time_reverse(&r).expect("valid");
        assert_eq!(rr.samples, s.samples);
        assert!((rr.t0_s - s.t0_s).abs() < 1e-20);
        assert_eq!(time_reverse_to_start(&s).expect("valid").t0_s, 0.0);
    }

    #[test]
    fn integer_delay_is_exact_shift_of_t0() {
        let s = pulse_signal(1e-8, 0.0, 200, 0.0);
        let d = delay(&s, 7e-8).expect("finite");
        assert_eq!(d.samples, s.samples);
        assert!((d.t0_s - 7e-8).abs() < 1e-6 * 1e-8);
    }

    #[test]
    fn fractional_delay_matches_analytic_shift() {
        // tolerance 1e-3 of the peak (brief); a Gaussian pulse inside the band is
        // reproduced to round-off, so this is a loose bound
        let dt = 1e-8;
        let s = pulse_signal(dt, 0.0, 200, 0.0);
        for tau in [0.3 * dt, 12.75 * dt, -4.4 * dt] {
            let d = delay(&s, tau).expect("finite");
            let exact = pulse_signal(dt, d.t0_s, d.len(), tau / dt);
            let err = max_abs_diff(&d, &exact) / s.max_abs();
            assert!(err < 1e-3, "tau {tau}: error {err}");
        }
    }

    #[test]
    fn delay_and_sum_identity_and_linearity() {
        let dt = 1e-8;
        let s = pulse_signal(dt, 0.0, 200, 0.0);
        // exact: a single zero delay with unit amplitude copies the samples
        let same = delay_and_sum(&s, &[0.0], &[1.0]).expect("valid");
        assert_eq!(same, s);
        // linearity: sum of individually delayed copies, to 1e-9 of the peak
        // (both are band-limited shifts; they differ only in FFT padding/round-off)
        let (taus, amps) = ([2.5 * dt, 10.25 * dt, 31.0 * dt], [1.0, -0.5, 2.0]);
        let sum = delay_and_sum(&s, &taus, &amps).expect("valid");
        let mut expect = Signal::zeros(dt, 0.0, 0).expect("valid");
        for (t, a) in taus.iter().zip(amps) {
            let part = delay(&s, *t).and_then(|d| d.scale(a)).expect("valid");
            expect = expect.add(&part).expect("aligned");
        }
        assert!(max_abs_diff(&sum, &expect) < 1e-9 * s.max_abs());
    }

    #[test]
    fn delay_and_sum_rejects_length_mismatch() {
        let s = pulse_signal(1e-8, 0.0, 10, 0.0);
        let e = delay_and_sum(&s, &[0.0, 1e-8], &[1.0])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("delays_s has 2") && e.contains("amplitudes has 1"),
            "{e}"
        );
    }
}
