//! Analytic signal (Hilbert transform), envelope and instantaneous frequency.

use std::f64::consts::PI;

use rustfft::num_complex::Complex;

use super::fft::{fast_len, forward_real, inverse_in_place};
use super::{check_alloc_with, fft_bytes, require_len, Signal, SignalError};

/// Analytic signal `z = x + i H[x]` on the samples of `s`.
///
/// Computed on a zero-padded FFT of length >= 2n (so the Hilbert transform's
/// slowly decaying tails do not wrap around): `Z_k = X_k` at DC and Nyquist,
/// `2 X_k` for positive and 0 for negative frequencies.
pub fn analytic(s: &Signal) -> Result<Vec<Complex<f64>>, SignalError> {
    s.validate()?;
    require_len("signal", s.len(), 1)?;
    let len = fast_len(2 * s.len());
    // the spectrum, then the output beside it (the envelope's samples)
    check_alloc_with("analytic signal", s.len() as f64, fft_bytes(1, len))?;
    let mut spec = forward_real(&s.samples, len);
    for (k, z) in spec.iter_mut().enumerate().skip(1) {
        if 2 * k < len {
            *z *= 2.0;
        } else if 2 * k > len {
            *z = Complex::new(0.0, 0.0);
        }
    }
    inverse_in_place(&mut spec);
    spec.truncate(s.len());
    Ok(spec)
}

/// Envelope `|z(t)|` of the analytic signal, on the grid of `s`.
pub fn envelope(s: &Signal) -> Result<Signal, SignalError> {
    let z = analytic(s)?;
    Ok(Signal {
        samples: z.iter().map(|v| v.norm()).collect(),
        ..*s
    })
}

/// Instantaneous frequency `f = (1/2 pi) d(phi)/dt` (Hz) of the unwrapped
/// analytic phase `phi = arg z`, on the grid of `s`.
///
/// The phase increments `d_k = arg(z_{k+1} conj(z_k))` are unwrapped by
/// construction (valid up to Nyquist); interior samples use the central
/// difference `(d_{k-1} + d_k) / 2`, the end samples the one-sided one.
/// Where the envelope vanishes the phase, hence the frequency, is meaningless.
pub fn instantaneous_frequency(s: &Signal) -> Result<Signal, SignalError> {
    require_len("signal", s.len(), 2)?;
    let z = analytic(s)?;
    let d: Vec<f64> = z.windows(2).map(|w| (w[1] * w[0].conj()).arg()).collect();
    let to_hz = 1.0 / (2.0 * PI * s.dt_s);
    let n = s.len();
    let samples = (0..n)
        .map(|k| {
            let slope = match k {
                0 => d[0],
                k if k == n - 1 => d[n - 2],
                k => 0.5 * (d[k - 1] + d[k]),
            };
            slope * to_hz
        })
        .collect();
    Ok(Signal { samples, ..*s })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_recovers_gaussian() {
        // tolerance 1% of the peak (brief): a Gaussian envelope on a carrier far
        // from DC and Nyquist is recovered to ~1e-10, so 1% is a loose bound
        let dt = 1e-8;
        let (t_c, sigma, f_c) = (5e-6, 0.8e-6, 5e6);
        let gauss = |t: f64| (-((t - t_c) / sigma).powi(2) / 2.0).exp();
        let x = (0..1000)
            .map(|k| {
                let t = k as f64 * dt;
                gauss(t) * (2.0 * PI * f_c * t).sin()
            })
            .collect();
        let s = Signal::new(dt, 0.0, x).expect("finite");
        let env = envelope(&s).expect("non-empty");
        for k in 100..900 {
            let err = (env.samples[k] - gauss(k as f64 * dt)).abs();
            assert!(err < 1e-2, "k {k}: error {err}");
        }
    }

    #[test]
    fn instantaneous_frequency_of_a_tone() {
        // tolerance 1% relative: the truncated tone's Hilbert edge artefacts decay
        // like 1/(distance to the edge); 500 samples in they are far below 1%
        let dt = 1e-8;
        let f = 3e6;
        let x = (0..2000)
            .map(|k| (2.0 * PI * f * k as f64 * dt).cos())
            .collect();
        let s = Signal::new(dt, 0.0, x).expect("finite");
        let fi = instantaneous_frequency(&s).expect("long enough");
        for k in 500..1500 {
            assert!((fi.samples[k] / f - 1.0).abs() < 1e-2, "k {k}");
        }
    }
}
