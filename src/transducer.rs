//! The transducers: the band through which a lab transmitter drives the laminate and a lab
//! receiver sees it.
//!
//! A piezoelectric transducer (or a vibrometer with its band filter) passes a band of
//! frequencies; outside it the lab sees nothing. The model is a causal Butterworth band-pass
//! B(f) of the stated order (2 x order poles), applied once on transmission (the traction the
//! transmitter exerts is B * drive) and once on reception (the recorded output is B * the
//! receiver's displacement or velocity). B is the analog filter, stepped exactly between the
//! samples ([`AnalogBandPass`]), so two runs at different steps see the same band to
//! O((w dt)^4), not the bilinear transform's O((w dt)^2) warp. Causal filters are what a
//! transducer is, and they
//! do not move the TR-NEWS focus: the focused signal's spectrum is |B H B|^2 |C|^2, with no
//! phase left (H the medium's response, C the chirp's spectrum), so it still focuses at the
//! end of the lag window.
//!
//! Without a band (`transducer: ()` in a scene) the traction is the drive signal and the
//! output the raw receiver quantity, as in the report.

use crate::error::{Error, Result};
use crate::signal::{self, AnalogBandPass, Signal};
use serde::{Deserialize, Serialize};

/// The transducers' band model, shared by the transmitter and the receivers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransducerSpec {
    /// Lower -3 dB frequency of one pass (Hz).
    pub f_lo_hz: f64,
    /// Upper -3 dB frequency of one pass (Hz).
    pub f_hi_hz: f64,
    /// Butterworth order (a band-pass of order n has 2 n poles, as in scipy).
    pub order: usize,
}

impl Default for TransducerSpec {
    /// The chirp's band, 0.2-2 MHz ([`signal::REPORT_BAND_HZ`]), order 2: a broadband
    /// transducer matched to the excitation.
    fn default() -> Self {
        TransducerSpec {
            f_lo_hz: signal::REPORT_BAND_HZ.0,
            f_hi_hz: signal::REPORT_BAND_HZ.1,
            order: 2,
        }
    }
}

impl TransducerSpec {
    /// Checks the band for signals sampled at `dt_s`, naming the field in errors.
    pub fn validate(&self, dt_s: f64) -> Result<()> {
        let field = |name: &str| format!("transducer.{name}");
        if !(self.f_lo_hz.is_finite() && self.f_lo_hz > 0.0) {
            return Err(Error::invalid(
                field("f_lo_hz"),
                self.f_lo_hz,
                "must be a positive frequency (Hz)",
            ));
        }
        if !(self.f_hi_hz.is_finite() && self.f_hi_hz > self.f_lo_hz) {
            return Err(Error::invalid(
                field("f_hi_hz"),
                self.f_hi_hz,
                format!("must be above f_lo_hz = {:e} Hz", self.f_lo_hz),
            ));
        }
        let nyquist = 0.5 / dt_s;
        if self.f_hi_hz >= nyquist {
            return Err(Error::invalid(
                field("f_hi_hz"),
                self.f_hi_hz,
                format!("must be below the Nyquist frequency {nyquist:e} Hz of the signals"),
            ));
        }
        if !(1..=12).contains(&self.order) {
            return Err(Error::invalid(
                field("order"),
                self.order,
                "must be between 1 and 12",
            ));
        }
        Ok(())
    }

    /// One pass of the band-pass on `s`.
    fn pass(&self, s: &Signal) -> Result<Signal> {
        self.validate(s.dt_s)?;
        let band = AnalogBandPass::new(self.order, self.f_lo_hz, self.f_hi_hz, s.dt_s)?;
        Ok(band.filter(s))
    }

    /// The traction the transmitter exerts for the drive signal `drive` over a run of
    /// `duration_s`: B * drive, the drive zero-padded to the run so the filter's ringing
    /// after the drive ends is kept.
    pub fn transmit(&self, drive: &Signal, duration_s: f64) -> Result<Signal> {
        let n = drive
            .len()
            .max(((duration_s / drive.dt_s).round() as usize).saturating_add(1));
        self.pass(&drive.pad_to(n)?)
    }

    /// The output of a receiver whose raw quantity (displacement or velocity) is `raw`.
    pub fn receive(&self, raw: &Signal) -> Result<Signal> {
        self.pass(raw)
    }

    /// "0.2-2 MHz" style label of the band, for titles and printed results.
    pub fn label(&self) -> String {
        format!("{}-{} MHz band", self.f_lo_hz / 1e6, self.f_hi_hz / 1e6)
    }
}

/// The label of an optional band: the band, or "no band (raw)".
pub fn band_label(t: Option<&TransducerSpec>) -> String {
    t.map_or_else(|| "no band (raw)".to_string(), TransducerSpec::label)
}

/// Fraction of a signal's energy outside [f_lo, f_hi] (from its periodogram), the measure
/// of how much of it a transducer of that band would not see.
pub fn energy_outside_band(s: &Signal, f_lo_hz: f64, f_hi_hz: f64) -> Result<f64> {
    let spectrum = signal::periodogram(s, signal::Window::Rectangular)?;
    let (mut inside, mut total) = (0.0, 0.0);
    for (f, p) in spectrum.freqs_hz.iter().zip(&spectrum.psd) {
        total += p;
        if (f_lo_hz..=f_hi_hz).contains(f) {
            inside += p;
        }
    }
    if !(total > 0.0) {
        return Err(Error::invalid(
            "signal",
            "all zero",
            "has no energy to split by band",
        ));
    }
    Ok(1.0 - inside / total)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tone(f_hz: f64, dt: f64, n: usize) -> Signal {
        let samples = (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * f_hz * k as f64 * dt).sin())
            .collect();
        Signal::new(dt, 0.0, samples).unwrap()
    }

    /// A steady tone inside the band passes at the filter's gain (1 at the band's centre),
    /// one a decade outside is attenuated by the Butterworth roll-off (order 2: 1/100 in
    /// amplitude per pass, 40 dB per decade); 2% allows for the start-up transient.
    #[test]
    fn band_passes_centre_and_rejects_a_decade_outside() {
        let t = TransducerSpec::default();
        let dt = 2e-9;
        let centre = (t.f_lo_hz * t.f_hi_hz).sqrt();
        let steady = |s: &Signal| s.window(60e-6, 100e-6).unwrap().max_abs();
        let out = t.receive(&tone(centre, dt, 50_000)).unwrap();
        assert!(
            (steady(&out) - 1.0).abs() < 0.02,
            "centre gain {}",
            steady(&out)
        );
        let low = t.receive(&tone(0.1 * t.f_lo_hz, dt, 50_000)).unwrap();
        assert!(steady(&low) < 0.012, "gain a decade below {}", steady(&low));
    }

    #[test]
    fn transmit_keeps_the_ringing_after_the_drive() {
        let t = TransducerSpec::default();
        let drive = Signal::new(1e-8, 0.0, vec![1.0]).unwrap();
        let out = t.transmit(&drive, 20e-6).unwrap();
        assert_eq!(out.len(), 2001);
        assert!(out.samples[100].abs() > 0.0);
    }

    #[test]
    fn bad_band_names_the_field_and_value() {
        let bad = TransducerSpec {
            f_hi_hz: 1e12,
            ..Default::default()
        };
        let e = bad.validate(1e-8).unwrap_err().to_string();
        assert!(
            e.contains("transducer.f_hi_hz") && e.contains("1000000000000"),
            "{e}"
        );
        let inverted = TransducerSpec {
            f_lo_hz: 3e6,
            ..Default::default()
        };
        assert!(inverted
            .validate(1e-8)
            .unwrap_err()
            .to_string()
            .contains("f_lo_hz"));
    }

    #[test]
    fn energy_outside_band_of_a_tone() {
        let s = tone(1e6, 1e-8, 10_000);
        assert!(energy_outside_band(&s, 0.2e6, 2e6).unwrap() < 1e-3);
        assert!(energy_outside_band(&s, 1.5e6, 2e6).unwrap() > 0.99);
    }
}
