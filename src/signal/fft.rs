//! FFT helpers, cross-correlation and convolution.

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

use super::{
    check_alloc, check_alloc_with, fft_bytes, finite, require_len, same_dt, Signal, SignalError,
    GRID_TOL,
};

/// Kernels shorter than this are convolved by the direct sum.
const DIRECT_CONVOLUTION_MAX: usize = 64;

/// Smallest `2^a 3^b 5^c >= n` (at least 1): a length rustfft handles fast.
pub(super) fn fast_len(n: usize) -> usize {
    let n = n.max(1);
    let mut best = n.next_power_of_two();
    let mut p5 = 1usize;
    while p5 < best {
        let mut p35 = p5;
        while p35 < best {
            let mut m = p35;
            while m < n {
                m *= 2;
            }
            best = best.min(m);
            p35 *= 3;
        }
        p5 *= 5;
    }
    best
}

/// Forward DFT `X_k = sum_j x_j exp(-2 pi i j k / L)` of `x` zero-padded to `len`.
pub(super) fn forward_real(x: &[f64], len: usize) -> Vec<Complex<f64>> {
    let mut buf = vec![Complex::new(0.0, 0.0); len];
    for (b, &v) in buf.iter_mut().zip(x) {
        b.re = v;
    }
    FftPlanner::new().plan_fft_forward(len).process(&mut buf);
    buf
}

/// Real part of the inverse DFT `x_j = (1/L) sum_k X_k exp(2 pi i j k / L)`.
pub(super) fn inverse_real(mut spec: Vec<Complex<f64>>) -> Vec<f64> {
    inverse_in_place(&mut spec);
    spec.into_iter().map(|z| z.re).collect()
}

/// Normalised inverse DFT in place, `x_j = (1/L) sum_k X_k exp(2 pi i j k / L)`.
pub(super) fn inverse_in_place(spec: &mut [Complex<f64>]) {
    let len = spec.len();
    FftPlanner::new().plan_fft_inverse(len).process(spec);
    let norm = 1.0 / len as f64;
    for z in spec.iter_mut() {
        *z *= norm;
    }
}

/// Signed frequency index of DFT bin `k` of length `len`: `k` up to `len/2`, `k - len` above.
pub(super) fn signed_bin(k: usize, len: usize) -> f64 {
    if 2 * k <= len {
        k as f64
    } else {
        k as f64 - len as f64
    }
}

/// Cross-correlation
/// `Gamma(tau) = sum_n y(t_n + tau) c(t_n) dt`,
/// the discrete form of `int y(t + tau) c(t) dt` (report eq 8 read as a
/// correlation, DESIGN item 5). If `y(t) = c(t - D)`, Gamma peaks at `tau = +D`;
/// for a TR-NEWS response `y = h * c`, `Gamma = h * R_cc` is the pseudo impulse
/// response with lag = propagation time.
///
/// Both signals keep their own `t0_s`: the lags lie on the grid
/// `tau_m = (y.t0 - c.t0) + m dt`, and only lags in `[lag_min_s, lag_max_s]`
/// (inclusive, within 1e-6 of a sample) are returned. The output's `t0_s` is the
/// first such lag; lags outside the overlap of the two signals are 0.
/// Computed with one zero-padded FFT product `Y conj(C)`, O(N log N).
pub fn xcorr(
    y: &Signal,
    c: &Signal,
    lag_min_s: f64,
    lag_max_s: f64,
) -> Result<Signal, SignalError> {
    y.validate()?;
    c.validate()?;
    same_dt(y.dt_s, c.dt_s)?;
    require_len("y", y.len(), 1)?;
    require_len("c", c.len(), 1)?;
    finite("lag_min_s", lag_min_s)?;
    finite("lag_max_s", lag_max_s)?;
    let dt = y.dt_s;
    let base = y.t0_s - c.t0_s;
    let m_lo = ((lag_min_s - base) / dt - GRID_TOL).ceil();
    let m_hi = ((lag_max_s - base) / dt + GRID_TOL).floor();
    if m_hi < m_lo {
        return Err(SignalError::EmptyWindow {
            name: "lag window",
            start_s: lag_min_s,
            end_s: lag_max_s,
        });
    }
    let (ny, nc) = (y.len() as i64, c.len() as i64);
    let len = fast_len((ny + nc - 1) as usize);
    let window = m_hi - m_lo + 1.0;
    check_alloc("lag window", window)?;
    // the two spectra and their product, then the real correlation beside the window
    check_alloc_with(
        "cross-correlation",
        len as f64,
        fft_bytes(3, len) + 8.0 * window,
    )?;
    let yk = forward_real(&y.samples, len);
    let ck = forward_real(&c.samples, len);
    let prod = yk.iter().zip(&ck).map(|(a, b)| a * b.conj()).collect();
    let r = inverse_real(prod);
    let (m_lo, m_hi) = (m_lo as i64, m_hi as i64);
    let samples = (m_lo..=m_hi)
        .map(|m| {
            if m > -nc && m < ny {
                r[m.rem_euclid(len as i64) as usize] * dt
            } else {
                0.0
            }
        })
        .collect();
    Ok(Signal {
        dt_s: dt,
        t0_s: base + m_lo as f64 * dt,
        samples,
    })
}

/// Continuous-time convolution sampled on the grid,
/// `(a * b)(t_n) = sum_k a_k b_{n-k} dt`, with `t0 = a.t0 + b.t0` and
/// `len = len_a + len_b - 1`: the Riemann sum of `int a(t') b(t - t') dt'`.
pub fn convolve(a: &Signal, b: &Signal) -> Result<Signal, SignalError> {
    let mut out = convolve_discrete(a, b)?;
    let dt = out.dt_s;
    out.samples.iter_mut().for_each(|v| *v *= dt);
    Ok(out)
}

/// Discrete convolution without the `dt` factor, `y_n = sum_k a_k b_{n-k}`,
/// with `t0 = a.t0 + b.t0` and `len = len_a + len_b - 1`.
/// If `b` is the response of a discrete LTI system to a unit sample (Kronecker
/// delta, value 1 at one step) applied at time 0, `convolve_discrete(input, b)` is
/// its response to `input`, exact up to round-off (FFT error ~1e-15 of the
/// largest output; kernels under 64 samples use the direct sum).
pub fn convolve_discrete(a: &Signal, b: &Signal) -> Result<Signal, SignalError> {
    a.validate()?;
    b.validate()?;
    same_dt(a.dt_s, b.dt_s)?;
    require_len("a", a.len(), 1)?;
    require_len("b", b.len(), 1)?;
    let n = a.len() + b.len();
    // three complex FFT buffers (both transforms and their product) beside the output
    check_alloc_with("convolution", n as f64, fft_bytes(3, fast_len(n)))?;
    Ok(Signal {
        dt_s: a.dt_s,
        t0_s: a.t0_s + b.t0_s,
        samples: linear_convolution(&a.samples, &b.samples),
    })
}

/// `y_n = sum_k a_k b_{n-k}` for non-empty slices, direct for short kernels, FFT otherwise.
fn linear_convolution(a: &[f64], b: &[f64]) -> Vec<f64> {
    let n = a.len() + b.len() - 1;
    if a.len().min(b.len()) <= DIRECT_CONVOLUTION_MAX {
        return direct_convolution(a, b);
    }
    let len = fast_len(n);
    let ak = forward_real(a, len);
    let bk = forward_real(b, len);
    let mut y = inverse_real(ak.iter().zip(&bk).map(|(p, q)| p * q).collect());
    y.truncate(n);
    y
}

/// Damping of the complex frequency in [`causal_response`]: e^(-eta T) over one period T of
/// the transform, which bounds the wrap-around.
const WRAP_AROUND: f64 = 1e-12;

/// Transform periods per input length in [`causal_response`]: the output's last sample is
/// amplified by e^(eta t) <= WRAP_AROUND^(-1/4) = 1e3, so FFT round-off (~1e-16) stays below
/// 1e-12 of the largest output.
const PERIODS_PER_INPUT: usize = 4;

/// The output, on the input's grid, of a causal linear time-invariant system with transfer
/// function `transfer(omega)` (Y(omega) = H(omega) X(omega), X(omega) = int x(t)
/// e^(-i omega t) dt, analytic for Im omega < 0) driven by `input`, zero before and after
/// its samples.
///
/// By the FFT at complex frequency (Kausel and Roesset 1992, "Frequency domain analysis of
/// undamped systems", J. Eng. Mech. 118): with x_eta(t) = x(t) e^(-eta t), X_eta(omega) =
/// X(omega - i eta), so
/// y(t_j) = e^(eta t_j) IDFT[H(omega_k - i eta) DFT[x_eta]]_j
/// on a period of T = L dt, L >= 4 n. The periodic images of y add
/// sum_(m >= 1) y(t + m T) e^(-eta m T): with eta T = ln(1 / WRAP_AROUND) the wrap-around is
/// at most 1e-12 of sup |y| however slowly y decays (an undamped system included). Bins
/// above Nyquist take the conjugate of their mirror (y is real); the Nyquist bin is kept
/// as evaluated. `transfer` must satisfy H(-conj(w)) = conj(H(w)) (a real impulse
/// response).
pub fn causal_response(
    input: &Signal,
    transfer: impl Fn(Complex<f64>) -> Complex<f64>,
) -> Result<Signal, SignalError> {
    input.validate()?;
    require_len("input", input.len(), 1)?;
    let n = input.len();
    check_alloc("causal response", (PERIODS_PER_INPUT * n) as f64)?;
    let len = fast_len(PERIODS_PER_INPUT * n);
    let period = len as f64 * input.dt_s;
    let eta = -WRAP_AROUND.ln() / period;
    let damping = |j: usize| (-eta * j as f64 * input.dt_s).exp();
    let damped: Vec<f64> = (0..n).map(|j| input.samples[j] * damping(j)).collect();
    let mut spectrum = forward_real(&damped, len);
    for (k, bin) in spectrum.iter_mut().enumerate().take(len / 2 + 1) {
        let omega = 2.0 * std::f64::consts::PI * k as f64 / period;
        *bin *= transfer(Complex::new(omega, -eta));
    }
    for k in len / 2 + 1..len {
        spectrum[k] = spectrum[len - k].conj();
    }
    inverse_in_place(&mut spectrum);
    Ok(Signal {
        dt_s: input.dt_s,
        t0_s: input.t0_s,
        samples: (0..n).map(|j| spectrum[j].re / damping(j)).collect(),
    })
}

/// Direct O(len_a * len_b) sum, used for short kernels.
fn direct_convolution(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.len() + b.len() - 1];
    for (i, &ai) in a.iter().enumerate() {
        for (o, &bj) in y[i..].iter_mut().zip(b) {
            *o += ai * bj;
        }
    }
    y
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Deterministic uniform numbers in [-1, 1) from a 64-bit LCG (Knuth's MMIX constants).
    pub(in crate::signal) fn lcg(seed: u64, n: usize) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            })
            .collect()
    }

    fn sig(dt: f64, t0: f64, x: Vec<f64>) -> Signal {
        Signal::new(dt, t0, x).expect("valid test signal")
    }

    fn max_rel(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    }

    #[test]
    fn fast_len_is_smooth_and_minimal() {
        assert_eq!(fast_len(0), 1);
        assert_eq!(fast_len(7), 8);
        assert_eq!(fast_len(11), 12);
        assert_eq!(fast_len(1001), 1024);
        assert_eq!(fast_len(1025), 1080);
    }

    #[test]
    fn convolve_matches_direct_sum() {
        // tolerance 1e-12 relative to the largest output: FFT round-off is ~1e-15 * log2(N)
        let a = sig(2.0, 1.0, lcg(1, 1000));
        let b = sig(2.0, -3.0, lcg(2, 300));
        let direct = direct_convolution(&a.samples, &b.samples);
        let d = convolve_discrete(&a, &b).expect("same dt");
        assert_eq!(d.len(), 1299);
        assert_eq!(d.t0_s, -2.0);
        assert!(max_rel(&d.samples, &direct) < 1e-12);
        let c = convolve(&a, &b).expect("same dt");
        let scaled: Vec<f64> = direct.iter().map(|v| v * 2.0).collect();
        assert!(max_rel(&c.samples, &scaled) < 1e-12);
    }

    #[test]
    fn short_kernel_uses_exact_direct_sum() {
        // exact: small integers summed directly
        let a = sig(1.0, 0.0, vec![1.0, 2.0, 3.0]);
        let b = sig(1.0, 0.0, vec![0.0, 1.0]);
        let d = convolve_discrete(&a, &b).expect("same dt");
        assert_eq!(d.samples, vec![0.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn xcorr_peaks_at_integer_delay_exactly() {
        let dt = 1e-8;
        let c = sig(dt, 0.0, lcg(3, 500));
        let mut ys = vec![0.0; 37];
        ys.extend(&c.samples);
        let y = sig(dt, 0.0, ys);
        let g = xcorr(&y, &c, -100.0 * dt, 100.0 * dt).expect("same dt");
        assert!((g.t0_s + 100.0 * dt).abs() < 1e-6 * dt);
        assert_eq!(g.len(), 201);
        let k = argmax(&g.samples);
        // exact: the peak sample is the integer delay
        assert!((g.time_at(k) - 37.0 * dt).abs() < 1e-6 * dt);
        // value at the peak is the energy of c (round-off 1e-12 relative)
        assert!((g.samples[k] - c.energy()).abs() < 1e-12 * c.energy());
    }

    #[test]
    fn xcorr_respects_t0_and_lag_window() {
        // the same delay expressed through t0 instead of leading zeros
        let dt = 1e-8;
        let c = sig(dt, 5e-7, lcg(4, 400));
        let y = sig(dt, 5e-7 + 23.0 * dt, c.samples.clone());
        let g = xcorr(&y, &c, 0.0, 50.0 * dt).expect("same dt");
        assert!(g.t0_s.abs() < 1e-6 * dt);
        assert!((g.t_end_s() - 50.0 * dt).abs() < 1e-6 * dt);
        assert!((g.time_at(argmax(&g.samples)) - 23.0 * dt).abs() < 1e-6 * dt);
        // lags beyond the overlap are exactly zero
        let far = xcorr(&y, &c, 1e-3, 1e-3 + 10.0 * dt).expect("same dt");
        assert!(far.samples.iter().all(|&v| v == 0.0));
        assert!(xcorr(&y, &c, 1.0, 0.0).is_err());
    }

    #[test]
    fn xcorr_fractional_delay_within_one_sample() {
        let dt = 1.0;
        let pulse = |t: f64| (-((t - 100.0) / 8.0).powi(2)).exp() * (0.3 * t).sin();
        let c = sig(dt, 0.0, (0..300).map(|k| pulse(k as f64)).collect());
        let y = sig(dt, 0.0, (0..300).map(|k| pulse(k as f64 - 12.4)).collect());
        let g = xcorr(&y, &c, -50.0, 50.0).expect("same dt");
        assert!((g.time_at(argmax(&g.samples)) - 12.4).abs() <= 1.0);
    }

    #[test]
    fn xcorr_rejects_dt_mismatch() {
        let a = sig(1e-9, 0.0, vec![1.0]);
        let b = sig(2e-9, 0.0, vec![1.0]);
        let e = xcorr(&a, &b, 0.0, 1e-9).unwrap_err().to_string();
        assert!(e.contains("1e-9") && e.contains("2e-9"), "{e}");
    }

    pub(in crate::signal) fn argmax(x: &[f64]) -> usize {
        (0..x.len()).fold(0, |b, k| if x[k] > x[b] { k } else { b })
    }

    /// An undamped oscillator y'' + w0^2 y = x (H = 1 / (w0^2 - omega^2)) kicked by a Gaussian
    /// x = exp(-((t - tc) / w)^2) rings forever after it at (w sqrt(pi) / w0)
    /// e^(-(w0 w / 2)^2) sin(w0 (t - tc)): the response that never decays is reproduced to
    /// 1e-10 of its amplitude, so the wrap-around bound holds without any decay.
    #[test]
    fn causal_response_of_an_undamped_oscillator() {
        let (w, tc, w0) = (0.1e-6, 0.6e-6, 2.0 * std::f64::consts::PI * 1e6);
        let dt = 2e-9;
        let x: Vec<f64> = (0..5000)
            .map(|k| (-((k as f64 * dt - tc) / w).powi(2)).exp())
            .collect();
        let input = Signal::new(dt, 0.0, x).unwrap();
        let y = causal_response(&input, |omega| 1.0 / (w0 * w0 - omega * omega)).unwrap();
        let amplitude = w * std::f64::consts::PI.sqrt() / w0 * (-(w0 * w / 2.0).powi(2)).exp();
        let worst = (1000..5000)
            .map(|k| (y.samples[k] - amplitude * (w0 * (k as f64 * dt - tc)).sin()).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10 * amplitude, "{}", worst / amplitude);
    }
}
