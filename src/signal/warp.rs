//! Frequency warping: a signal whose spectrum is another's read at mapped frequencies. It is
//! how a time-stepping scheme's dispersion is added to a source and removed from a recording
//! (`crate::solve::time_dispersion`).

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

use super::fft::{fast_len, inverse_in_place};
use super::{check_alloc_with, fft_bytes, positive_finite, Signal, SignalError};

/// The signal y on `x`'s time grid whose spectrum is
/// Y(w) = r(w) g(w) X(v(w)) for 0 <= w <= 2 pi `up_to_hz`, and zero above,
/// where `(v, g) = map(w)`, X(v) = sum_n x_n exp(-i v t_n) is the exact discrete-time
/// Fourier transform of `x` (t_n = t0 + n dt, absolute times: the warp is about t = 0), and
/// r rolls the band's top half off to zero smoothly (1 below `up_to_hz` / 2, [`roll_off`]), so
/// that where `x` is cut off mid-signal the output rings for a few periods of `up_to_hz`
/// only ([`ROLL_OFF_PERIODS`]). The spectrum is evaluated on the bins of `x` zero-padded to
/// at least twice its length (so that a warp that moves energy later does not wrap around)
/// and transformed back. X at the mapped frequencies is a non-uniform FFT ([`dtft_at`]):
/// O(N log N) in the record's length N.
pub fn warp_spectrum(
    x: &Signal,
    up_to_hz: f64,
    map: impl Fn(f64) -> (f64, f64) + Sync,
) -> Result<Signal, SignalError> {
    x.validate()?;
    positive_finite("up_to_hz", up_to_hz)?;
    let nyquist_hz = 0.5 / x.dt_s;
    if up_to_hz >= nyquist_hz {
        return Err(SignalError::CutoffOutOfRange {
            name: "up_to_hz",
            value_hz: up_to_hz,
            nyquist_hz,
        });
    }
    let len = fast_len(2 * x.len().max(1));
    check_alloc_with("warped signal", len as f64, fft_bytes(1, len))?;
    let bin_hz = 1.0 / (len as f64 * x.dt_s);
    let bins = (up_to_hz / bin_hz).floor() as usize + 1;
    let dt = x.dt_s;
    let mapped: Vec<(f64, f64)> = (0..bins)
        .map(|k| map(2.0 * PI * k as f64 * bin_hz))
        .collect();
    crate::budget::check().map_err(SignalError::Stopped)?;
    let angles: Vec<f64> = mapped.iter().map(|&(v, _)| v * dt).collect();
    let transform = dtft_at(&x.samples, &angles)?;
    let warped = mapped
        .iter()
        .zip(transform)
        .enumerate()
        .map(|(k, (&(v, g), z))| {
            let w = 2.0 * PI * k as f64 * bin_hz;
            // Y(w) exp(i w t0): the inverse DFT below runs over n from t0.
            let r = roll_off(k as f64 * bin_hz / up_to_hz);
            r * g * z * Complex::from_polar(1.0, (w - v) * x.t0_s)
        });
    let mut spectrum = vec![Complex::new(0.0, 0.0); len];
    for (k, z) in warped.enumerate() {
        spectrum[k] = z;
        if k > 0 {
            spectrum[len - k] = z.conj();
        }
    }
    inverse_in_place(&mut spectrum);
    Ok(Signal {
        dt_s: dt,
        t0_s: x.t0_s,
        samples: spectrum[..x.len()].iter().map(|z| z.re).collect(),
    })
}

/// How long (in periods of the band's top) [`warp_spectrum`]'s output rings where its input
/// is cut off mid-signal, to 1e-6 of the jump (the tests below): the roll-off is smooth to
/// every order, so its kernel decays faster than any power of time.
pub const ROLL_OFF_PERIODS: f64 = 20.0;

/// 1 up to half the band, then down to 0 at its top along [`smooth_step`] (q the frequency
/// over the band's top): smooth to every order, where a raised cosine's kernel decays as
/// 1/t^3 and needs twice the margin.
fn roll_off(q: f64) -> f64 {
    smooth_step(2.0 - 2.0 * q)
}

/// The step from 0 (x <= 0) to 1 (x >= 1) that is infinitely differentiable:
/// S(x) = e(x) / (e(x) + e(1 - x)), e(x) = exp(-1 / x) for x > 0, 0 otherwise.
pub fn smooth_step(x: f64) -> f64 {
    let e = |x: f64| if x > 0.0 { (-1.0 / x).exp() } else { 0.0 };
    if x <= 0.0 {
        0.0
    } else if x >= 1.0 {
        1.0
    } else {
        e(x) / (e(x) + e(1.0 - x))
    }
}

/// Oversampling of the fine grid in [`dtft_at`].
const NUFFT_OVERSAMPLING: usize = 4;
/// Grid points on each side of a target angle in [`dtft_at`].
const NUFFT_SPREAD: usize = 12;

/// F(theta_j) = sum_n x_n exp(-i n theta_j) at any angles theta_j: a type-2 non-uniform FFT
/// by Gaussian gridding (Greengard & Lee 2004, SIAM Rev. 46, 443). With the modes centred,
/// k = n - N/2, the coefficients are divided by the periodic Gaussian's Fourier coefficients
/// sqrt(tau/pi) exp(-k^2 tau), transformed onto a grid of R N angles (R =
/// [`NUFFT_OVERSAMPLING`]) by one FFT, and convolved at each theta_j with the Gaussian
/// exp(-d^2 / (4 tau)) over the [`NUFFT_SPREAD`] grid points on each side; tau = pi M_sp /
/// (N^2 R (R - 1/2)) (their eq. 10). Truncation and aliasing are then below exp(-pi M_sp
/// (R - 1) / (R - 1/2)) = 1e-14 of sum |x_n|, and the division amplifies round-off by at most
/// exp(pi M_sp / (4 R (R - 1/2))) = 15 (the test below: 1e-13 against the direct sum).
///
/// Written here on rustfft, which the crate already uses, rather than with a NUFFT crate:
/// those bring a second FFT engine for these thirty lines.
fn dtft_at(x: &[f64], angles: &[f64]) -> Result<Vec<Complex<f64>>, SignalError> {
    let modes = x.len().max(1);
    let grid = fast_len(NUFFT_OVERSAMPLING * modes);
    check_alloc_with("non-uniform FFT grid", grid as f64, fft_bytes(1, grid))?;
    let ratio = grid as f64 / modes as f64;
    let spread = NUFFT_SPREAD as f64;
    let tau = PI * spread / (modes as f64).powi(2) / (ratio * (ratio - 0.5));
    let centre = modes / 2;
    let mut h = vec![Complex::new(0.0, 0.0); grid];
    for (n, &xn) in x.iter().enumerate() {
        let k = n as f64 - centre as f64;
        let slot = (n + grid - centre) % grid;
        h[slot] = Complex::new(xn * (PI / tau).sqrt() * (k * k * tau).exp(), 0.0);
    }
    FftPlanner::new().plan_fft_forward(grid).process(&mut h);
    let step = 2.0 * PI / grid as f64;
    Ok(angles
        .iter()
        .map(|&theta| {
            let theta = theta.rem_euclid(2.0 * PI);
            let nearest = (theta / step).round() as isize;
            let sum: Complex<f64> = (nearest - NUFFT_SPREAD as isize
                ..=nearest + NUFFT_SPREAD as isize)
                .map(|m| {
                    let d = theta - m as f64 * step;
                    h[m.rem_euclid(grid as isize) as usize] * (-d * d / (4.0 * tau)).exp()
                })
                .sum();
            sum / grid as f64 * Complex::from_polar(1.0, -(centre as f64) * theta)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian-windowed tone burst: band-limited to round-off well below Nyquist.
    fn burst(dt: f64, n: usize, t0: f64) -> Signal {
        let (f, tc, width) = (2e6, 4e-6, 0.4e-6);
        Signal {
            dt_s: dt,
            t0_s: t0,
            samples: (0..n)
                .map(|k| {
                    let t = t0 + k as f64 * dt;
                    (-((t - tc) / width).powi(2)).exp() * (2.0 * PI * f * t).sin()
                })
                .collect(),
        }
    }

    #[test]
    fn the_identity_map_returns_a_band_limited_signal_unchanged() {
        let x = burst(5e-9, 2000, 0.0);
        let y = warp_spectrum(&x, 20e6, |w| (w, 1.0)).unwrap();
        let err = super::super::relative_l2(&y, &x, None).unwrap();
        assert!(err < 1e-12, "{err}");
    }

    #[test]
    fn a_frequency_scale_stretches_time_and_a_gain_scales_amplitude() {
        // X(w / a) / a is the spectrum of x(a t): reading the spectrum at v = w / a compresses
        // the burst in time by a. The burst starts at t0 > 0 to check the absolute time axis.
        let (dt, a) = (5e-9, 1.25);
        let x = burst(dt, 2000, 1e-6);
        let y = warp_spectrum(&x, 30e6, |w| (w / a, 0.5 / a)).unwrap();
        let expected: Vec<f64> = (0..x.len())
            .map(|k| {
                let t = x.t0_s + k as f64 * dt;
                let s = a * t;
                let (f, tc, width) = (2e6, 4e-6, 0.4e-6);
                0.5 * (-((s - tc) / width).powi(2)).exp() * (2.0 * PI * f * s).sin()
            })
            .collect();
        let peak = expected.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let worst = y
            .samples
            .iter()
            .zip(&expected)
            .fold(0.0_f64, |m, (y, e)| m.max((y - e).abs()));
        assert!(worst < 1e-9 * peak, "{worst:e} against a peak {peak:e}");
    }

    #[test]
    fn a_signal_cut_off_mid_step_rings_for_a_few_periods_of_the_band_top_only() {
        // A unit step from sample 200 to the end: cut off at full height. The identity warp
        // keeps it to 1e-6 everywhere but the last ROLL_OFF_PERIODS periods of 20 MHz (and as
        // many after the step's rise, where the band's cut smooths it).
        let (dt, n, up_to) = (2e-9, 4000, 20e6);
        let x = Signal {
            dt_s: dt,
            t0_s: 0.0,
            samples: (0..n).map(|k| if k >= 200 { 1.0 } else { 0.0 }).collect(),
        };
        let y = warp_spectrum(&x, up_to, |w| (w, 1.0)).unwrap();
        let spoilt = (ROLL_OFF_PERIODS / up_to / dt).ceil() as usize;
        let far = |k: usize| k + spoilt < n && (k + spoilt < 200 || k > 200 + spoilt);
        let worst = (0..n)
            .filter(|&k| far(k))
            .map(|k| (y.samples[k] - x.samples[k]).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "{worst:e}");
    }

    /// The non-uniform FFT against the direct sum sum_n x_n exp(-i n theta) (a phasor
    /// recurrence) on a random record, at angles over the whole circle and beyond: within
    /// 1e-13 of sum |x_n| (the error bound of `dtft_at`, with room for the direct sum's own
    /// round-off).
    #[test]
    fn the_non_uniform_fft_matches_the_direct_sum() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for len in [1, 2, 7, 1000, 4099] {
            let x: Vec<f64> = (0..len).map(|_| rng.random_range(-1.0..1.0)).collect();
            let angles: Vec<f64> = (0..200).map(|j| -7.0 + 0.0731 * j as f64).collect();
            let fast = dtft_at(&x, &angles).unwrap();
            let scale: f64 = x.iter().map(|v| v.abs()).sum();
            for (&theta, z) in angles.iter().zip(fast) {
                let step = Complex::from_polar(1.0, -theta);
                let (mut phasor, mut direct) = (Complex::new(1.0, 0.0), Complex::new(0.0, 0.0));
                for &xn in &x {
                    direct += xn * phasor;
                    phasor *= step;
                }
                assert!(
                    (z - direct).norm() < 1e-13 * scale,
                    "N {len}, theta {theta}: {z} vs {direct}"
                );
            }
        }
    }

    #[test]
    fn a_cutoff_at_or_above_nyquist_is_refused_by_name() {
        let x = burst(5e-9, 100, 0.0);
        let e = warp_spectrum(&x, 100e6, |w| (w, 1.0)).unwrap_err();
        assert!(e.to_string().contains("up_to_hz"), "{e}");
    }
}
