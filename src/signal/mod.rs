//! Uniformly sampled real signals and the signal processing of TR-NEWS
//! (report Sec. 3 and 5): chirp excitation, cross-correlation, time reversal,
//! delay-and-sum, filtering, analytic signal, spectra and focusing measures.
//!
//! Conventions used throughout:
//! - sample `k` of a [`Signal`] sits at time `t0_s + k * dt_s`;
//! - two signals may be combined only when their `dt_s` agree to a relative
//!   `1e-9` and their `t0_s` differ by an integer number of samples (within
//!   `1e-6` of a sample); the result lives on the union of both time ranges;
//! - every operation validates its input and returns a [`SignalError`] naming
//!   the offending field and value instead of panicking or producing NaN.

use serde::{Deserialize, Serialize};

mod analog;
mod chirp;
mod delay;
mod fft;
mod filter;
mod hilbert;
mod measure;
mod resample;
mod spectrum;
mod warp;

pub use analog::AnalogBandPass;
pub use chirp::{ChirpSpec, REPORT_BAND_HZ};
pub use delay::{delay, delay_and_sum, time_reverse, time_reverse_to_start};
pub use fft::{causal_response, convolve, convolve_discrete, xcorr};
pub use filter::{butterworth, filtfilt, sosfilt, Biquad, FilterKind, Sos};
pub use hilbert::{analytic, envelope, instantaneous_frequency};
pub use measure::{peak, relative_l2, side_lobes, window_energy, window_max_abs, Peak, SideLobes};
pub use resample::resample;
pub use spectrum::{periodogram, welch, Detrend, Spectrum, Window};
pub use warp::{smooth_step, warp_spectrum, ROLL_OFF_PERIODS};

/// Relative tolerance on equality of two sample intervals.
pub const DT_REL_TOL: f64 = 1e-9;
/// Tolerance, in samples, for a time to count as lying on a sample grid.
pub const GRID_TOL: f64 = 1e-6;
/// Largest number of samples any operation will allocate (2^28).
pub const MAX_SAMPLES: usize = 1 << 28;

/// Errors of the signal module; every message names the offending field and value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SignalError {
    /// A scalar parameter violates its requirement.
    #[error("{name} must be {requirement}, got {}", num(.value))]
    InvalidParameter {
        name: &'static str,
        requirement: &'static str,
        value: f64,
    },
    /// A sample is NaN or infinite.
    #[error("samples[{index}] must be finite, got {value}")]
    NonFiniteSample { index: usize, value: f64 },
    /// Two signals have different sample intervals.
    #[error("sample interval mismatch: {} s vs {} s", num(.0), num(.1))]
    DtMismatch(f64, f64),
    /// Two signals' start times are not an integer number of samples apart.
    #[error(
        "time grids do not align: t0_s {} s vs {} s differ by {offset_samples} samples, not an integer",
        num(.t0_a), num(.t0_b)
    )]
    GridMismatch {
        t0_a: f64,
        t0_b: f64,
        offset_samples: f64,
    },
    /// A frequency lies outside the open interval (0, Nyquist).
    #[error(
        "{name} = {} Hz must lie strictly between 0 and the Nyquist frequency {} Hz",
        num(.value_hz), num(.nyquist_hz)
    )]
    CutoffOutOfRange {
        name: &'static str,
        value_hz: f64,
        nyquist_hz: f64,
    },
    /// An input has too few samples or entries.
    #[error("{name} has {len} samples, needs at least {min}")]
    TooShort {
        name: &'static str,
        len: usize,
        min: usize,
    },
    /// An output would exceed [`MAX_SAMPLES`].
    #[error("{name} would need {len} samples, above the limit of {max}")]
    TooLong {
        name: &'static str,
        len: f64,
        max: usize,
    },
    /// An output would not fit in the memory limit (see [`crate::budget::check_memory`]).
    #[error("{0}")]
    OverMemory(String),
    /// The work was stopped: Ctrl-C or the time limit (see [`crate::budget::check`]).
    #[error("{0}")]
    Stopped(crate::budget::Stop),
    /// Two parallel inputs have different lengths.
    #[error("length mismatch: {name_a} has {len_a} entries vs {name_b} has {len_b}")]
    LengthMismatch {
        name_a: &'static str,
        len_a: usize,
        name_b: &'static str,
        len_b: usize,
    },
    /// A filter is applied to a signal sampled at another rate.
    #[error(
        "sampling rate mismatch: filter designed for fs_hz = {} Hz, signal sampled at {} Hz",
        num(.filter_fs_hz), num(.signal_fs_hz)
    )]
    SampleRateMismatch {
        filter_fs_hz: f64,
        signal_fs_hz: f64,
    },
    /// A time window holds no sample of the grid.
    #[error("{name} [{} s, {} s] holds no sample of the time grid", num(.start_s), num(.end_s))]
    EmptyWindow {
        name: &'static str,
        start_s: f64,
        end_s: f64,
    },
}

/// Formats a number compactly: plain for moderate magnitudes, scientific otherwise.
fn num(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-3..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A uniformly sampled real signal: sample k is at time `t0_s + k*dt_s`. Decoding (a stored
/// point, a data file) goes through [`Signal::new`]: a decoded signal always holds its
/// invariants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SignalFields")]
pub struct Signal {
    /// Sample interval (s), positive and finite.
    pub dt_s: f64,
    /// Time of sample 0 (s).
    pub t0_s: f64,
    /// Sample values.
    pub samples: Vec<f64>,
}

/// The fields of a [`Signal`] as decoded, before [`Signal::new`] checks them.
#[derive(Deserialize)]
struct SignalFields {
    dt_s: f64,
    t0_s: f64,
    samples: Vec<f64>,
}

impl TryFrom<SignalFields> for Signal {
    type Error = SignalError;
    fn try_from(f: SignalFields) -> Result<Self, SignalError> {
        Signal::new(f.dt_s, f.t0_s, f.samples)
    }
}

impl Signal {
    /// Builds a validated signal: `dt_s > 0` finite, `t0_s` finite, all samples finite.
    pub fn new(dt_s: f64, t0_s: f64, samples: Vec<f64>) -> Result<Self, SignalError> {
        let s = Self {
            dt_s,
            t0_s,
            samples,
        };
        s.validate()?;
        Ok(s)
    }

    /// `n` zero samples starting at `t0_s`.
    pub fn zeros(dt_s: f64, t0_s: f64, n: usize) -> Result<Self, SignalError> {
        check_alloc("n", n as f64)?;
        Self::new(dt_s, t0_s, vec![0.0; n])
    }

    /// Checks the invariants of [`Signal::new`] (the fields are public, so
    /// every operation re-checks its inputs).
    pub fn validate(&self) -> Result<(), SignalError> {
        positive_finite("dt_s", self.dt_s)?;
        finite("t0_s", self.t0_s)?;
        check_len("samples", self.samples.len() as f64)?;
        match self.samples.iter().position(|v| !v.is_finite()) {
            Some(index) => Err(SignalError::NonFiniteSample {
                index,
                value: self.samples[index],
            }),
            None => Ok(()),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// True when the signal has no samples.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Duration covered by the samples, `n * dt` (each sample holds one interval).
    pub fn duration_s(&self) -> f64 {
        self.len() as f64 * self.dt_s
    }

    /// Time of sample k, `t0 + k dt`.
    pub fn time_at(&self, k: usize) -> f64 {
        self.t0_s + k as f64 * self.dt_s
    }

    /// Time of the last sample, `t0 + (n-1) dt` (`t0` for an empty signal).
    pub fn t_end_s(&self) -> f64 {
        self.time_at(self.len().saturating_sub(1))
    }

    /// Sample times `t0 + k dt`.
    pub fn times(&self) -> Vec<f64> {
        (0..self.len()).map(|k| self.time_at(k)).collect()
    }

    /// Energy `E = sum_k x_k^2 dt`.
    pub fn energy(&self) -> f64 {
        self.samples.iter().map(|x| x * x).sum::<f64>() * self.dt_s
    }

    /// `max_k |x_k|` (0 for an empty signal).
    pub fn max_abs(&self) -> f64 {
        self.samples.iter().fold(0.0, |m, x| m.max(x.abs()))
    }

    /// Root mean square `sqrt(sum_k x_k^2 / n)` (0 for an empty signal).
    pub fn rms(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        (self.samples.iter().map(|x| x * x).sum::<f64>() / self.len() as f64).sqrt()
    }

    /// `a * x(t)`.
    pub fn scale(&self, a: f64) -> Result<Signal, SignalError> {
        finite("a", a)?;
        self.validate()?;
        let samples = self.samples.iter().map(|x| a * x).collect();
        Ok(Signal { samples, ..*self })
    }

    /// `x(t) + y(t)` on the union of both time ranges, zero outside each.
    pub fn add(&self, other: &Signal) -> Result<Signal, SignalError> {
        self.combine(other, 1.0)
    }

    /// `x(t) - y(t)` on the union of both time ranges, zero outside each.
    pub fn sub(&self, other: &Signal) -> Result<Signal, SignalError> {
        self.combine(other, -1.0)
    }

    fn combine(&self, other: &Signal, sign: f64) -> Result<Signal, SignalError> {
        self.validate()?;
        other.validate()?;
        let offset = grid_offset(self, other)?;
        if other.is_empty() {
            return Ok(self.clone());
        }
        if self.is_empty() {
            return other.scale(sign);
        }
        let start = offset.min(0);
        let end = (self.len() as i64).max(offset + other.len() as i64);
        check_alloc("sum", (end - start) as f64)?;
        let mut samples = vec![0.0; (end - start) as usize];
        let a0 = (-start) as usize;
        let b0 = (offset - start) as usize;
        for (o, x) in samples[a0..].iter_mut().zip(&self.samples) {
            *o += x;
        }
        for (o, y) in samples[b0..].iter_mut().zip(&other.samples) {
            *o += sign * y;
        }
        let t0_s = if start == 0 { self.t0_s } else { other.t0_s };
        Ok(Signal {
            dt_s: self.dt_s,
            t0_s,
            samples,
        })
    }

    /// Crop to the samples with `t_start_s <= t_k <= t_end_s` (within
    /// [`GRID_TOL`] of a sample); the grid is kept. The result may be empty.
    pub fn window(&self, t_start_s: f64, t_end_s: f64) -> Result<Signal, SignalError> {
        self.validate()?;
        let (k0, k1) = self.index_range(t_start_s, t_end_s)?;
        Ok(Signal {
            dt_s: self.dt_s,
            t0_s: self.t0_s + k0 as f64 * self.dt_s,
            samples: self.samples[k0..k1.max(k0)].to_vec(),
        })
    }

    /// Half-open index range `[k0, k1)` of the samples inside `[t_start, t_end]`.
    fn index_range(&self, t_start_s: f64, t_end_s: f64) -> Result<(usize, usize), SignalError> {
        finite("t_start_s", t_start_s)?;
        finite("t_end_s", t_end_s)?;
        if t_end_s < t_start_s {
            return Err(SignalError::InvalidParameter {
                name: "t_end_s",
                requirement: "at least t_start_s",
                value: t_end_s,
            });
        }
        let n = self.len() as f64;
        let k0 = ((t_start_s - self.t0_s) / self.dt_s - GRID_TOL)
            .ceil()
            .clamp(0.0, n);
        let k1 = ((t_end_s - self.t0_s) / self.dt_s + GRID_TOL)
            .floor()
            .clamp(-1.0, n - 1.0)
            + 1.0;
        Ok((k0 as usize, k1 as usize))
    }

    /// Append zeros up to `n` samples (`n` must be at least `len()`).
    pub fn pad_to(&self, n: usize) -> Result<Signal, SignalError> {
        self.validate()?;
        if n < self.len() {
            return Err(SignalError::InvalidParameter {
                name: "n",
                requirement: "at least the signal length",
                value: n as f64,
            });
        }
        check_alloc("n", n as f64)?;
        let mut samples = self.samples.clone();
        samples.resize(n, 0.0);
        Ok(Signal { samples, ..*self })
    }

    /// Linear interpolation `x(t)` between samples; 0 outside `[t0, t_end]`.
    pub fn sample_at(&self, t_s: f64) -> Result<f64, SignalError> {
        finite("t_s", t_s)?;
        self.validate()?;
        let x = (t_s - self.t0_s) / self.dt_s;
        let last = self.len() as f64 - 1.0;
        if self.is_empty() || x < -GRID_TOL || x > last + GRID_TOL {
            return Ok(0.0);
        }
        let x = x.clamp(0.0, last);
        let k = (x.floor() as usize).min(self.len() - 1);
        let frac = x - k as f64;
        let next = self.samples.get(k + 1).copied().unwrap_or(0.0);
        Ok(self.samples[k] * (1.0 - frac) + next * frac)
    }
}

/// Errors unless `a` and `b` agree to the relative tolerance [`DT_REL_TOL`].
fn same_dt(a: f64, b: f64) -> Result<(), SignalError> {
    if (a - b).abs() > DT_REL_TOL * a.abs().max(b.abs()) {
        return Err(SignalError::DtMismatch(a, b));
    }
    Ok(())
}

/// Integer `m` with `b.t0 = a.t0 + m dt`, or an error if the grids differ.
fn grid_offset(a: &Signal, b: &Signal) -> Result<i64, SignalError> {
    same_dt(a.dt_s, b.dt_s)?;
    let x = (b.t0_s - a.t0_s) / a.dt_s;
    let m = x.round();
    if (x - m).abs() > GRID_TOL {
        return Err(SignalError::GridMismatch {
            t0_a: a.t0_s,
            t0_b: b.t0_s,
            offset_samples: x,
        });
    }
    check_alloc("grid offset", m.abs())?;
    Ok(m as i64)
}

fn finite(name: &'static str, value: f64) -> Result<(), SignalError> {
    if !value.is_finite() {
        return Err(SignalError::InvalidParameter {
            name,
            requirement: "finite",
            value,
        });
    }
    Ok(())
}

fn positive_finite(name: &'static str, value: f64) -> Result<(), SignalError> {
    if !(value.is_finite() && value > 0.0) {
        return Err(SignalError::InvalidParameter {
            name,
            requirement: "positive and finite",
            value,
        });
    }
    Ok(())
}

/// Errors if a length (given as f64 so overflowing requests are caught) exceeds [`MAX_SAMPLES`].
fn check_len(name: &'static str, len: f64) -> Result<(), SignalError> {
    if len.is_nan() || len > MAX_SAMPLES as f64 {
        return Err(SignalError::TooLong {
            name,
            len,
            max: MAX_SAMPLES,
        });
    }
    Ok(())
}

/// [`check_len`] for an output about to be allocated, which must also fit in the memory limit
/// on top of the heap in use.
fn check_alloc(name: &'static str, len: f64) -> Result<(), SignalError> {
    check_alloc_with(name, len, 0.0)
}

/// [`check_alloc`] for an output of `len` samples computed in `work_bytes` of buffers held
/// alongside it (FFTs: 16 bytes a complex bin).
fn check_alloc_with(name: &'static str, len: f64, work_bytes: f64) -> Result<(), SignalError> {
    check_len(name, len)?;
    let bytes = len * std::mem::size_of::<f64>() as f64 + work_bytes;
    crate::budget::check_memory(name, format!("{len} samples"), bytes, "use fewer samples")
        .map_err(|e| SignalError::OverMemory(e.to_string()))
}

/// Bytes of `buffers` complex FFT buffers of `len` bins.
fn fft_bytes(buffers: usize, len: usize) -> f64 {
    (buffers * std::mem::size_of::<rustfft::num_complex::Complex<f64>>()) as f64 * len as f64
}

/// Errors if a signal has fewer than `min` samples.
fn require_len(name: &'static str, len: usize, min: usize) -> Result<(), SignalError> {
    if len < min {
        return Err(SignalError::TooShort { name, len, min });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sig(t0: f64, x: &[f64]) -> Signal {
        Signal::new(1e-9, t0, x.to_vec()).expect("valid test signal")
    }

    #[test]
    fn new_rejects_bad_fields_and_names_them() {
        let e = Signal::new(-1.0, 0.0, vec![]).unwrap_err().to_string();
        assert_eq!(e, "dt_s must be positive and finite, got -1");
        let e = Signal::new(1.0, f64::NAN, vec![]).unwrap_err().to_string();
        assert!(e.contains("t0_s") && e.contains("NaN"), "{e}");
        let e = Signal::new(1.0, 0.0, vec![0.0, f64::NAN])
            .unwrap_err()
            .to_string();
        assert!(e.contains("samples[1]") && e.contains("NaN"), "{e}");
    }

    #[test]
    fn dt_mismatch_names_both_values() {
        let a = sig(0.0, &[1.0]);
        let b = Signal::new(2e-9, 0.0, vec![1.0]).expect("valid");
        let e = a.add(&b).unwrap_err().to_string();
        assert_eq!(e, "sample interval mismatch: 1e-9 s vs 2e-9 s");
    }

    #[test]
    fn misaligned_grids_are_an_error() {
        let a = sig(0.0, &[1.0]);
        let b = sig(0.5e-9, &[1.0]);
        let e = a.add(&b).unwrap_err().to_string();
        assert!(e.contains("5e-10") && e.contains("not an integer"), "{e}");
    }

    #[test]
    fn add_aligns_on_union_of_time_ranges() {
        // exact: only additions of small integers
        let a = sig(0.0, &[1.0, 2.0, 3.0]);
        let b = sig(2e-9, &[10.0, 20.0]);
        let s = a.add(&b).expect("aligned");
        assert_eq!(s.samples, vec![1.0, 2.0, 13.0, 20.0]);
        assert_eq!(s.t0_s, 0.0);
        let d = b.sub(&a).expect("aligned");
        assert_eq!(d.samples, vec![-1.0, -2.0, 7.0, 20.0]);
        assert_eq!(d.t0_s, 0.0);
        let far = sig(-3e-9, &[5.0]);
        let u = a.add(&far).expect("aligned");
        assert_eq!(u.samples, vec![5.0, 0.0, 0.0, 1.0, 2.0, 3.0]);
        assert_eq!(u.t0_s, -3e-9);
    }

    #[test]
    fn window_pad_and_interpolation() {
        let s = sig(1e-9, &[0.0, 1.0, 2.0, 3.0, 4.0]);
        let w = s.window(2e-9, 4e-9).expect("valid window");
        assert_eq!(w.samples, vec![1.0, 2.0, 3.0]);
        assert!((w.t0_s - 2e-9).abs() < 1e-24);
        assert!(s.window(10e-9, 11e-9).expect("valid").is_empty());
        assert_eq!(s.pad_to(7).expect("longer").samples.len(), 7);
        assert!(s.pad_to(2).is_err());
        // linear interpolation is exact for a linear ramp (up to round-off 1e-12)
        assert!((s.sample_at(2.5e-9).expect("finite") - 1.5).abs() < 1e-12);
        assert_eq!(s.sample_at(0.0).expect("finite"), 0.0);
        assert_eq!(s.sample_at(7e-9).expect("finite"), 0.0);
        assert!(s.sample_at(f64::NAN).is_err());
    }

    #[test]
    fn scalar_measures() {
        let s = sig(0.0, &[3.0, -4.0]);
        assert!((s.energy() - 25e-9).abs() < 1e-20);
        assert_eq!(s.max_abs(), 4.0);
        assert!((s.rms() - (12.5f64).sqrt()).abs() < 1e-12);
        assert!((s.duration_s() - 2e-9).abs() < 1e-24);
        assert!((s.t_end_s() - 1e-9).abs() < 1e-24);
        assert_eq!(s.scale(2.0).expect("finite").samples, vec![6.0, -8.0]);
        assert!(s.scale(f64::INFINITY).is_err());
    }
}
