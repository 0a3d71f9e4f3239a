//! One-sided power spectral densities: periodogram and Welch's method.

use std::f64::consts::PI;
use std::sync::Arc;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use serde::Serialize;

use super::{require_len, Signal, SignalError};

/// Taper applied to each segment before the DFT.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Window {
    Rectangular,
    Hann,
    Hamming,
    Blackman,
}

impl Window {
    /// Periodic ("DFT-even") coefficients `w_j`, `j = 0..n`, with `x = 2 pi j / n`:
    /// Hann `0.5 - 0.5 cos x`, Hamming `0.54 - 0.46 cos x`,
    /// Blackman `0.42 - 0.5 cos x + 0.08 cos 2x`, rectangular 1.
    pub fn coefficients(self, n: usize) -> Vec<f64> {
        (0..n)
            .map(|j| {
                let x = 2.0 * PI * j as f64 / n as f64;
                match self {
                    Window::Rectangular => 1.0,
                    Window::Hann => 0.5 - 0.5 * x.cos(),
                    Window::Hamming => 0.54 - 0.46 * x.cos(),
                    Window::Blackman => 0.42 - 0.5 * x.cos() + 0.08 * (2.0 * x).cos(),
                }
            })
            .collect()
    }
}

/// What is removed from each Welch segment before it is windowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Detrend {
    /// Nothing: the segment's mean goes into the DC bin and the total power.
    None,
    /// The segment's mean (scipy.signal.welch's default, `detrend='constant'`).
    Constant,
}

/// One-sided power spectral density on `f_k = k df`, `k = 0..=n/2`, in
/// (signal unit)^2 / Hz, normalised so that `sum_k psd_k df` is the mean power
/// `mean(x^2)` (exactly for a rectangular periodogram, on average otherwise).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Spectrum {
    pub df_hz: f64,
    pub freqs_hz: Vec<f64>,
    pub psd: Vec<f64>,
}

impl Spectrum {
    /// `10 log10(psd / reference)`, floored at -3000 dB where psd is 0.
    pub fn to_db(&self, reference: f64) -> Result<Vec<f64>, SignalError> {
        super::positive_finite("reference", reference)?;
        Ok(self
            .psd
            .iter()
            .map(|p| 10.0 * (p / reference).max(1e-300).log10())
            .collect())
    }

    /// Mean power `sum_k psd_k df` (the rectangle rule of `int psd df`).
    pub fn total_power(&self) -> f64 {
        self.psd.iter().sum::<f64>() * self.df_hz
    }

    /// The `n` strongest local maxima `(f_hz, psd)`, strongest first, each at
    /// least `min_separation_hz` from every stronger one kept. A bin is a local
    /// maximum if it exceeds its left neighbour and is not below its right one
    /// (end bins compare with their single neighbour).
    pub fn peaks(&self, n: usize, min_separation_hz: f64) -> Result<Vec<(f64, f64)>, SignalError> {
        if !(min_separation_hz >= 0.0 && min_separation_hz.is_finite()) {
            return Err(SignalError::InvalidParameter {
                name: "min_separation_hz",
                requirement: "non-negative and finite",
                value: min_separation_hz,
            });
        }
        let p = &self.psd;
        let m = p.len();
        let mut candidates: Vec<usize> = (0..m)
            .filter(|&k| (k == 0 || p[k] > p[k - 1]) && (k + 1 == m || p[k] >= p[k + 1]))
            .collect();
        candidates.sort_by(|&a, &b| p[b].total_cmp(&p[a]));
        let mut kept: Vec<(f64, f64)> = Vec::with_capacity(n.min(m));
        for k in candidates {
            if kept.len() == n {
                break;
            }
            let f = self.freqs_hz[k];
            if kept
                .iter()
                .all(|&(g, _)| (f - g).abs() >= min_separation_hz)
            {
                kept.push((f, p[k]));
            }
        }
        Ok(kept)
    }
}

/// Windowed periodogram of the whole signal, `P_k = c |DFT(w x)_k|^2 dt / sum w^2`
/// with `c = 2` for `0 < f_k < fs/2` and 1 at DC and Nyquist; `df = 1 / (n dt)`.
/// No detrending: the mean contributes to the DC bin and to the total power.
pub fn periodogram(s: &Signal, window: Window) -> Result<Spectrum, SignalError> {
    s.validate()?;
    require_len("signal", s.len(), 2)?;
    let w = window.coefficients(s.len());
    let fft = FftPlanner::new().plan_fft_forward(s.len());
    let psd = segment_psd(&s.samples, &w, s.dt_s, fft.as_ref());
    Ok(build(s.len(), s.dt_s, psd))
}

/// Welch's method: the average of windowed periodograms of segments of
/// `segment_len` samples overlapping by `round(overlap_fraction * segment_len)`;
/// trailing samples that do not fill a segment are ignored. With [`Detrend::Constant`] each
/// segment's mean is subtracted before the window, as scipy.signal.welch does by default.
/// Same units and normalisation as [`periodogram`], `df = 1 / (segment_len dt)`.
pub fn welch(
    s: &Signal,
    segment_len: usize,
    overlap_fraction: f64,
    window: Window,
    detrend: Detrend,
) -> Result<Spectrum, SignalError> {
    s.validate()?;
    if !(2..=s.len()).contains(&segment_len) {
        return Err(SignalError::InvalidParameter {
            name: "segment_len",
            requirement: "between 2 and the signal length",
            value: segment_len as f64,
        });
    }
    if !(0.0..1.0).contains(&overlap_fraction) {
        return Err(SignalError::InvalidParameter {
            name: "overlap_fraction",
            requirement: "in [0, 1)",
            value: overlap_fraction,
        });
    }
    let overlap = (overlap_fraction * segment_len as f64).round() as usize;
    let step = (segment_len - overlap).max(1);
    let w = window.coefficients(segment_len);
    let fft: Arc<dyn Fft<f64>> = FftPlanner::new().plan_fft_forward(segment_len);
    let starts: Vec<usize> = (0..=s.len() - segment_len).step_by(step).collect();
    let mut psd = vec![0.0; segment_len / 2 + 1];
    let mut centred = Vec::new();
    for &start in &starts {
        let mut seg = &s.samples[start..start + segment_len];
        if detrend == Detrend::Constant {
            let mean = seg.iter().sum::<f64>() / segment_len as f64;
            centred.clear();
            centred.extend(seg.iter().map(|x| x - mean));
            seg = &centred;
        }
        for (acc, p) in psd
            .iter_mut()
            .zip(segment_psd(seg, &w, s.dt_s, fft.as_ref()))
        {
            *acc += p;
        }
    }
    let count = starts.len() as f64;
    psd.iter_mut().for_each(|p| *p /= count);
    Ok(build(segment_len, s.dt_s, psd))
}

/// One-sided PSD of one windowed segment (see [`periodogram`]).
fn segment_psd(x: &[f64], w: &[f64], dt: f64, fft: &dyn Fft<f64>) -> Vec<f64> {
    let n = x.len();
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .zip(w)
        .map(|(v, c)| Complex::new(v * c, 0.0))
        .collect();
    fft.process(&mut buf);
    let norm = dt / w.iter().map(|c| c * c).sum::<f64>();
    (0..=n / 2)
        .map(|k| {
            let fold = if k == 0 || 2 * k == n { 1.0 } else { 2.0 };
            fold * norm * buf[k].norm_sqr()
        })
        .collect()
}

fn build(n: usize, dt: f64, psd: Vec<f64>) -> Spectrum {
    let df_hz = 1.0 / (n as f64 * dt);
    Spectrum {
        df_hz,
        freqs_hz: (0..psd.len()).map(|k| k as f64 * df_hz).collect(),
        psd,
    }
}

#[cfg(test)]
mod tests {
    use super::super::fft::tests::lcg;
    use super::*;

    #[test]
    fn welch_of_a_sine_integrates_to_half_amplitude_squared() {
        // tolerance 1% (brief): the window normalisation makes the mean power exact
        // up to leakage between the incoherent segment edges (~1e-3)
        let (a, f, dt) = (1.7, 2.3e6, 1e-8);
        let x = (0..100_000)
            .map(|k| a * (2.0 * PI * f * k as f64 * dt).sin())
            .collect();
        let s = Signal::new(dt, 0.0, x).expect("finite");
        for window in [
            Window::Hann,
            Window::Hamming,
            Window::Blackman,
            Window::Rectangular,
        ] {
            let sp = welch(&s, 4096, 0.5, window, Detrend::None).expect("valid");
            let p = sp.total_power();
            assert!((p / (a * a / 2.0) - 1.0).abs() < 0.01, "{window:?}: {p}");
            let top = sp.peaks(1, 0.0).expect("valid")[0];
            assert!((top.0 - f).abs() <= sp.df_hz, "{window:?}: {top:?}");
        }
    }

    #[test]
    fn periodogram_of_noise_integrates_to_its_mean_square() {
        // rectangular window: Parseval makes the integral equal mean(x^2) to
        // round-off (1e-12); with Hann it is a weighted mean of x^2, equal in
        // expectation: for 2e4 samples it deviates ~1%, bound 5%
        let x = lcg(7, 20_000);
        let s = Signal::new(1e-9, 0.0, x).expect("finite");
        let mean_sq = s.rms().powi(2);
        let rect = periodogram(&s, Window::Rectangular).expect("valid");
        assert!((rect.total_power() / mean_sq - 1.0).abs() < 1e-12);
        let hann = periodogram(&s, Window::Hann).expect("valid");
        assert!((hann.total_power() / mean_sq - 1.0).abs() < 0.05);
        let odd = periodogram(
            &s.window(0.0, 1e-9 * 999.0).expect("valid"),
            Window::Rectangular,
        )
        .expect("valid");
        assert_eq!(odd.psd.len(), 501);
    }

    #[test]
    fn peaks_respect_separation_and_db_floor() {
        let sp = Spectrum {
            df_hz: 1.0,
            freqs_hz: vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
            psd: vec![0.0, 5.0, 1.0, 4.0, 1.0, 3.0],
        };
        let p = sp.peaks(3, 0.0).expect("valid");
        assert_eq!(p, vec![(1.0, 5.0), (3.0, 4.0), (5.0, 3.0)]);
        let p = sp.peaks(3, 2.5).expect("valid");
        assert_eq!(p, vec![(1.0, 5.0), (5.0, 3.0)]);
        let db = sp.to_db(1.0).expect("positive reference");
        assert_eq!(db[0], -3000.0);
        assert!(sp.to_db(0.0).is_err());
        assert!(sp.peaks(1, f64::NAN).is_err());
    }

    #[test]
    fn welch_with_constant_detrend_matches_scipy() {
        // Reference computed once with scipy 1.17.1:
        //   k = np.arange(64); x = 0.3 + np.sin(2*np.pi*0.05*k) + 0.5*np.cos(2*np.pi*0.173*k)
        //   f, p = scipy.signal.welch(x, fs=1e8, window='hann', nperseg=16, noverlap=8)
        // (detrend='constant' and scaling='density' are scipy's defaults). Same
        // arithmetic up to the FFT's summation order: 1e-10 relative to the largest bin
        // (round-off is ~1e-15); without the detrend bin 0 is 3.15e-8, not 8.34e-9.
        let scipy = [
            8.34059904538903e-09,
            3.861533927335734e-08,
            1.766369986667551e-08,
            1.1989999608659066e-08,
            1.522570626198992e-09,
            9.374874684806382e-12,
            9.00442879921779e-13,
            1.57750610274988e-13,
            2.7676711180729984e-14,
        ];
        let x = (0..64)
            .map(|k| {
                let k = k as f64;
                0.3 + (2.0 * PI * 0.05 * k).sin() + 0.5 * (2.0 * PI * 0.173 * k).cos()
            })
            .collect();
        let s = Signal::new(1e-8, 0.0, x).expect("finite");
        let sp = welch(&s, 16, 0.5, Window::Hann, Detrend::Constant).expect("valid");
        assert_eq!(sp.psd.len(), scipy.len());
        assert!((sp.df_hz - 6.25e6).abs() < 1e-6);
        for (k, (p, r)) in sp.psd.iter().zip(scipy).enumerate() {
            assert!(
                (p - r).abs() < 1e-10 * scipy[1],
                "bin {k}: {p} vs scipy {r}"
            );
        }
        let raw = welch(&s, 16, 0.5, Window::Hann, Detrend::None).expect("valid");
        // scipy detrend=False gives bin 0 = 3.1522637085575915e-08
        assert!((raw.psd[0] / 3.1522637085575915e-08 - 1.0).abs() < 1e-10);
    }

    #[test]
    fn welch_rejects_bad_segments() {
        let s = Signal::new(1e-9, 0.0, vec![0.0; 100]).expect("finite");
        let e = welch(&s, 200, 0.5, Window::Hann, Detrend::None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("segment_len") && e.contains("200"), "{e}");
        assert!(welch(&s, 50, 1.0, Window::Hann, Detrend::None).is_err());
    }
}
