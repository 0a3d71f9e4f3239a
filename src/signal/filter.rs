//! Butterworth filters as second-order sections, one-pass and zero-phase filtering.

use std::f64::consts::PI;

use rustfft::num_complex::Complex;
use serde::Serialize;

use super::{positive_finite, Signal, SignalError};

/// Highest accepted Butterworth order.
const MAX_ORDER: usize = 24;

/// Filter type and cut-off frequencies (Hz).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum FilterKind {
    /// Pass below the cut-off.
    LowPass(f64),
    /// Pass above the cut-off.
    HighPass(f64),
    /// Pass between the two cut-offs `(f_lo, f_hi)`.
    BandPass(f64, f64),
}

/// One section `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`
/// (`a[0] = 1`; a first-order section has `b2 = a2 = 0`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Biquad {
    pub b: [f64; 3],
    pub a: [f64; 3],
}

/// A cascade of second-order sections designed for sampling rate `fs_hz`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sos {
    pub fs_hz: f64,
    pub sections: Vec<Biquad>,
}

impl Biquad {
    /// `H(z)` at a point of the complex plane.
    fn eval(&self, z: Complex<f64>) -> Complex<f64> {
        let zi = z.inv();
        let num = self.b[0] + zi * (self.b[1] + zi * self.b[2]);
        let den = self.a[0] + zi * (self.a[1] + zi * self.a[2]);
        num / den
    }

    /// Section with the given zeros and poles (each one or two, conjugate-closed).
    fn from_roots(zeros: &[Complex<f64>], poles: &[Complex<f64>]) -> Self {
        Self {
            b: monic(zeros),
            a: monic(poles),
        }
    }
}

/// Coefficients of `prod (1 - r z^-1)` padded to three (roots conjugate-closed).
fn monic(roots: &[Complex<f64>]) -> [f64; 3] {
    match roots {
        [r] => [1.0, -r.re, 0.0],
        [r1, r2] => [1.0, -(r1 + r2).re, (r1 * r2).re],
        _ => [1.0, 0.0, 0.0],
    }
}

impl Sos {
    /// Complex one-pass response `H(exp(2 pi i f / fs)) = prod_j H_j`.
    pub fn frequency_response(&self, f_hz: f64) -> Complex<f64> {
        let z = Complex::from_polar(1.0, 2.0 * PI * f_hz / self.fs_hz);
        self.sections.iter().map(|s| s.eval(z)).product()
    }

    /// One-pass gain `20 log10 |H(f)|` in dB. [`filtfilt`] applies `|H|^2`,
    /// i.e. twice this value (-6.02 dB at a Butterworth cut-off).
    pub fn gain_db(&self, f_hz: f64) -> f64 {
        20.0 * self.frequency_response(f_hz).norm().log10()
    }
}

/// Digital Butterworth filter as second-order sections.
///
/// Analog prototype poles `p_k = exp(i pi (2k + N + 1) / (2N))`; cut-offs are
/// prewarped, `W = 2 fs tan(pi f / fs)`, and mapped by the bilinear transform
/// `z = (2 fs + s) / (2 fs - s)`, so the one-pass gain at every cut-off is
/// exactly -3.01 dB. Low-pass `s = W p` (zeros at z = -1), high-pass `s = W / p`
/// (zeros at z = 1), band-pass `s = p B/2 +- sqrt((p B/2)^2 - W0^2)` with
/// `W0 = sqrt(W_lo W_hi)`, `B = W_hi - W_lo` (zeros at z = +-1): a band-pass of
/// `order` N has 2N poles (as in scipy). Each section is normalised to unit
/// gain at DC (low-pass), Nyquist (high-pass) or the centre frequency.
pub fn butterworth(order: usize, kind: FilterKind, fs_hz: f64) -> Result<Sos, SignalError> {
    positive_finite("fs_hz", fs_hz)?;
    if !(1..=MAX_ORDER).contains(&order) {
        return Err(SignalError::InvalidParameter {
            name: "order",
            requirement: "between 1 and 24",
            value: order as f64,
        });
    }
    let warp =
        |name, f| check_cutoff(name, f, fs_hz).map(|()| 2.0 * fs_hz * (PI * f / fs_hz).tan());
    let bilinear = |s: Complex<f64>| (2.0 * fs_hz + s) / (2.0 * fs_hz - s);
    let proto = prototype_poles(order);
    let one = Complex::new(1.0, 0.0);
    let (sections, z_ref) = match kind {
        FilterKind::LowPass(fc) => {
            let w = warp("cut-off", fc)?;
            let poles = proto.iter().map(|&p| bilinear(p * w));
            (single_sections(poles, -one), one)
        }
        FilterKind::HighPass(fc) => {
            let w = warp("cut-off", fc)?;
            let poles = proto.iter().map(|&p| bilinear(w / p));
            (single_sections(poles, one), -one)
        }
        FilterKind::BandPass(f_lo, f_hi) => {
            let (w_lo, w_hi) = (warp("f_lo", f_lo)?, warp("f_hi", f_hi)?);
            if f_hi <= f_lo {
                return Err(SignalError::InvalidParameter {
                    name: "f_hi",
                    requirement: "above f_lo",
                    value: f_hi,
                });
            }
            let w0 = (w_lo * w_hi).sqrt();
            let sections = band_sections(&proto, w0, w_hi - w_lo, bilinear);
            let centre = Complex::from_polar(1.0, 2.0 * (w0 / (2.0 * fs_hz)).atan());
            (sections, centre)
        }
    };
    let sections = sections.into_iter().map(|s| normalise(s, z_ref)).collect();
    Ok(Sos { fs_hz, sections })
}

/// Left-half-plane Butterworth poles of order N, conjugate pairs at `k` and `N-1-k`.
fn prototype_poles(order: usize) -> Vec<Complex<f64>> {
    (0..order)
        .map(|k| {
            let theta = PI * (2 * k + order + 1) as f64 / (2 * order) as f64;
            Complex::from_polar(1.0, theta)
        })
        .collect()
}

/// Sections for low/high-pass: pole `k` paired with its conjugate `N-1-k`, all
/// zeros at `zero`; an odd order ends with a first-order section.
fn single_sections(poles: impl Iterator<Item = Complex<f64>>, zero: Complex<f64>) -> Vec<Biquad> {
    let poles: Vec<Complex<f64>> = poles.collect();
    let n = poles.len();
    let mut out: Vec<Biquad> = (0..n / 2)
        .map(|k| Biquad::from_roots(&[zero, zero], &[poles[k], poles[k].conj()]))
        .collect();
    if n % 2 == 1 {
        let real = Complex::new(poles[n / 2].re, 0.0);
        out.push(Biquad::from_roots(&[zero], &[real]));
    }
    out
}

/// Band-pass sections: each prototype pole gives two analog poles `s+-`; for a
/// conjugate prototype pair, `s+` pairs with `conj(s+)` and `s-` with `conj(s-)`;
/// the real prototype pole (odd N) gives one section `(s+, s-)`. Zeros `+1, -1`.
fn band_sections(
    proto: &[Complex<f64>],
    w0: f64,
    bw: f64,
    bilinear: impl Fn(Complex<f64>) -> Complex<f64>,
) -> Vec<Biquad> {
    let zeros = [Complex::new(1.0, 0.0), Complex::new(-1.0, 0.0)];
    let split = |p: Complex<f64>| {
        let h = p * (0.5 * bw);
        let r = (h * h - w0 * w0).sqrt();
        (bilinear(h + r), bilinear(h - r))
    };
    let n = proto.len();
    let mut out = Vec::with_capacity(n);
    for &p in &proto[..n / 2] {
        let (a, b) = split(p);
        out.push(Biquad::from_roots(&zeros, &[a, a.conj()]));
        out.push(Biquad::from_roots(&zeros, &[b, b.conj()]));
    }
    if n % 2 == 1 {
        let (a, b) = split(Complex::new(-1.0, 0.0));
        out.push(Biquad::from_roots(&zeros, &[a, b]));
    }
    out
}

/// Scales a section's numerator to unit gain at `z_ref`.
fn normalise(mut s: Biquad, z_ref: Complex<f64>) -> Biquad {
    let g = s.eval(z_ref).norm();
    s.b.iter_mut().for_each(|b| *b /= g);
    s
}

/// A cut-off must lie strictly inside `(0, fs/2)`.
fn check_cutoff(name: &'static str, f_hz: f64, fs_hz: f64) -> Result<(), SignalError> {
    let nyquist_hz = 0.5 * fs_hz;
    if !(f_hz > 0.0 && f_hz < nyquist_hz) {
        return Err(SignalError::CutoffOutOfRange {
            name,
            value_hz: f_hz,
            nyquist_hz,
        });
    }
    Ok(())
}

/// Errors unless the signal's rate `1/dt` matches the filter's `fs_hz` (rel. 1e-9).
fn check_rate(sos: &Sos, s: &Signal) -> Result<(), SignalError> {
    s.validate()?;
    let signal_fs_hz = 1.0 / s.dt_s;
    if (signal_fs_hz - sos.fs_hz).abs() > super::DT_REL_TOL * sos.fs_hz.abs() {
        return Err(SignalError::SampleRateMismatch {
            filter_fs_hz: sos.fs_hz,
            signal_fs_hz,
        });
    }
    Ok(())
}

/// One causal pass through the cascade (transposed direct form II, zero initial state).
pub fn sosfilt(sos: &Sos, s: &Signal) -> Result<Signal, SignalError> {
    check_rate(sos, s)?;
    let mut x = s.samples.clone();
    for sec in &sos.sections {
        run_section(sec, &mut x, [0.0, 0.0]);
    }
    Ok(Signal { samples: x, ..*s })
}

/// Zero-phase forward-backward filtering: response `|H(f)|^2` with no phase, so
/// a symmetric pulse stays symmetric and peaks do not move; the gain at a
/// Butterworth cut-off is -6.02 dB.
///
/// Edges as in scipy's `sosfiltfilt` default: odd extension by
/// `3 (2 sections + 1)` samples (at most `n - 1`) and each pass started from
/// the steady state of a step of the first sample.
pub fn filtfilt(sos: &Sos, s: &Signal) -> Result<Signal, SignalError> {
    check_rate(sos, s)?;
    let n = s.len();
    if n == 0 {
        return Ok(s.clone());
    }
    let pad = (3 * (2 * sos.sections.len() + 1)).min(n - 1);
    let x = &s.samples;
    let mut ext: Vec<f64> = (1..=pad).rev().map(|k| 2.0 * x[0] - x[k]).collect();
    ext.extend_from_slice(x);
    ext.extend((1..=pad).map(|k| 2.0 * x[n - 1] - x[n - 1 - k]));
    let zi = step_states(sos);
    filter_with_initial(sos, &zi, &mut ext);
    ext.reverse();
    filter_with_initial(sos, &zi, &mut ext);
    ext.reverse();
    Ok(Signal {
        samples: ext[pad..pad + n].to_vec(),
        ..*s
    })
}

/// Runs the cascade with each section's state set to `zi * x[0]` (steady state).
fn filter_with_initial(sos: &Sos, zi: &[[f64; 2]], x: &mut [f64]) {
    let x0 = x.first().copied().unwrap_or(0.0);
    for (sec, z) in sos.sections.iter().zip(zi) {
        run_section(sec, x, [z[0] * x0, z[1] * x0]);
    }
}

/// Steady-state DF2T states of every section for a unit step into the cascade:
/// with section input `u` and DC gain `g`, `s2 = u (b2 - a2 g)`,
/// `s1 = u (b1 + b2 - (a1 + a2) g)`.
fn step_states(sos: &Sos) -> Vec<[f64; 2]> {
    let mut u = 1.0;
    sos.sections
        .iter()
        .map(|s| {
            let g = (s.b[0] + s.b[1] + s.b[2]) / (s.a[0] + s.a[1] + s.a[2]);
            let state = [
                u * (s.b[1] + s.b[2] - (s.a[1] + s.a[2]) * g),
                u * (s.b[2] - s.a[2] * g),
            ];
            u *= g;
            state
        })
        .collect()
}

/// Transposed direct form II: `y = b0 x + s1`, `s1 <- b1 x - a1 y + s2`, `s2 <- b2 x - a2 y`.
fn run_section(sec: &Biquad, x: &mut [f64], state: [f64; 2]) {
    let [b0, b1, b2] = sec.b;
    let [_, a1, a2] = sec.a;
    let [mut s1, mut s2] = state;
    for v in x.iter_mut() {
        let y = b0 * *v + s1;
        s1 = b1 * *v - a1 * y + s2;
        s2 = b2 * *v - a2 * y;
        *v = y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 100e6;
    const HALF_POWER_DB: f64 = -3.0103;

    #[test]
    fn low_pass_is_minus_3db_at_cutoff() {
        // tolerance 0.1 dB (brief); the bilinear design is exact, so ~1e-12 dB
        for order in [1, 2, 5, 8] {
            let sos = butterworth(order, FilterKind::LowPass(5e6), FS).expect("valid");
            assert!(
                (sos.gain_db(5e6) - HALF_POWER_DB).abs() < 0.1,
                "order {order}"
            );
            assert!(sos.gain_db(0.0).abs() < 1e-9);
            assert!(sos.gain_db(20e6) < -10.0 * order as f64);
        }
    }

    #[test]
    fn high_pass_and_band_pass_are_minus_3db_at_cutoffs() {
        // tolerance 0.1 dB (brief), as for the low-pass
        let hp = butterworth(3, FilterKind::HighPass(2e6), FS).expect("valid");
        assert!((hp.gain_db(2e6) - HALF_POWER_DB).abs() < 0.1);
        assert!(hp.gain_db(49e6).abs() < 1e-6);
        for order in [1, 2, 3, 4] {
            let bp = butterworth(order, FilterKind::BandPass(0.5e6, 3e6), FS).expect("valid");
            assert_eq!(bp.sections.len(), order);
            assert!(
                (bp.gain_db(0.5e6) - HALF_POWER_DB).abs() < 0.1,
                "order {order}"
            );
            assert!(
                (bp.gain_db(3e6) - HALF_POWER_DB).abs() < 0.1,
                "order {order}"
            );
            let warp = |f: f64| 2.0 * FS * (PI * f / FS).tan();
            let w0 = (warp(0.5e6) * warp(3e6)).sqrt();
            let centre_hz = FS / PI * (w0 / (2.0 * FS)).atan();
            assert!(bp.gain_db(centre_hz).abs() < 1e-9, "order {order}");
        }
    }

    #[test]
    fn filtfilt_of_a_tone_at_cutoff_is_minus_6db() {
        // forward-backward applies |H|^2: -6.02 dB at the cut-off; tolerance 0.1 dB
        // measured on the steady-state middle of a long tone
        let sos = butterworth(4, FilterKind::LowPass(5e6), FS).expect("valid");
        let x = (0..20000)
            .map(|k| (2.0 * PI * 5e6 * k as f64 / FS).sin())
            .collect();
        let s = Signal::new(1.0 / FS, 0.0, x).expect("finite");
        let y = filtfilt(&sos, &s).expect("same rate");
        let mid = Signal::new(1.0 / FS, 0.0, y.samples[5000..15000].to_vec()).expect("finite");
        let gain_db = 20.0 * (mid.rms() * 2f64.sqrt()).log10();
        assert!((gain_db - 2.0 * HALF_POWER_DB).abs() < 0.1, "{gain_db}");
    }

    #[test]
    fn filtfilt_has_zero_phase() {
        // a symmetric pulse stays symmetric to 1e-9 of its peak and its peak
        // does not move (exact sample)
        let sos = butterworth(4, FilterKind::BandPass(1e6, 8e6), FS).expect("valid");
        let n = 2001;
        let x = (0..n)
            .map(|k| {
                let t = (k as f64 - 1000.0) / FS;
                (-(t / 0.2e-6).powi(2)).exp() * (2.0 * PI * 4e6 * t).cos()
            })
            .collect();
        let s = Signal::new(1.0 / FS, 0.0, x).expect("finite");
        let y = filtfilt(&sos, &s).expect("same rate");
        let peak = y.max_abs();
        for k in 0..n {
            assert!((y.samples[k] - y.samples[n - 1 - k]).abs() < 1e-9 * peak);
        }
        let k_max = (0..n).fold(0, |b, k| {
            if y.samples[k].abs() > y.samples[b].abs() {
                k
            } else {
                b
            }
        });
        assert_eq!(k_max, 1000);
        // one causal pass delays the pulse instead
        let one = sosfilt(&sos, &s).expect("same rate");
        let k_one = (0..n).fold(0, |b, k| {
            if one.samples[k].abs() > one.samples[b].abs() {
                k
            } else {
                b
            }
        });
        assert!(k_one > 1000);
    }

    #[test]
    fn filtfilt_passes_a_constant() {
        // steady-state initial conditions: DC through a low-pass unchanged, 1e-9
        let sos = butterworth(3, FilterKind::LowPass(1e6), FS).expect("valid");
        let s = Signal::new(1.0 / FS, 0.0, vec![2.5; 500]).expect("finite");
        let y = filtfilt(&sos, &s).expect("same rate");
        assert!(y.samples.iter().all(|v| (v - 2.5).abs() < 1e-9));
    }

    #[test]
    fn bad_cutoffs_and_rates_are_errors_naming_the_value() {
        let e = butterworth(4, FilterKind::LowPass(60e6), FS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("6e7") && e.contains("5e7"), "{e}");
        let e = butterworth(4, FilterKind::HighPass(-1.0), FS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("-1 Hz"), "{e}");
        assert!(butterworth(2, FilterKind::BandPass(3e6, 1e6), FS).is_err());
        assert!(butterworth(0, FilterKind::LowPass(1e6), FS).is_err());
        let sos = butterworth(2, FilterKind::LowPass(1e6), FS).expect("valid");
        let s = Signal::new(2.0 / FS, 0.0, vec![0.0; 10]).expect("finite");
        assert!(filtfilt(&sos, &s).is_err());
    }
}
