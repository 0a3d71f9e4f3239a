//! Removing the time step's error from a run's recordings: the time-dispersion transforms of
//! Koene, Robertsson, Ruffini and Bøe (2018, "Eliminating time dispersion from seismic wave
//! modeling", Geophys. J. Int. 213, 169-180).
//!
//! On a linear body the time step changes nothing but the frequency. Writing a run's
//! displacement as U(w) = sum_n u_n exp(-i w n dt), central differences turn
//! M u'' + K u = f into (K - Omega(w)^2 M) U = F with
//!   Omega(w) = (2 / dt) sin(w dt / 2)        (central differences: (z - 2 + 1/z) / dt^2),
//! and Newmark's average acceleration into the same with
//!   Omega(w) = (2 / dt) tan(w dt / 2)        ((z - 2 + 1/z) / dt^2 over (z + 2 + 1/z) / 4).
//! The run at w is the exact (continuous-time) response of the spatial discretisation at
//! Omega(w). So a source whose spectrum is read at Omega(w) ([`TimeDispersion::add_to_source`],
//! the forward transform) gives a run whose recording, read at Omega^-1(w)
//! ([`TimeDispersion::remove_from_trace`], the inverse transform), is the response the
//! spatial discretisation gives without any time step error. Both are frequency warps of a
//! signal ([`signal::warp_spectrum`], a non-uniform FFT): with the margin
//! ([`TimeDispersion::extended`]) 4% of the quick preset's default experiment.
//!
//! What stays: the dashpots see the velocity (u_{n+1} - u_{n-1}) / 2dt, whose symbol
//! i sin(w dt) / dt is i Omega cos(w dt / 2), so an absorbing edge's impedance is off by
//! 1 - cos(w dt / 2), 2e-4 at 2 MHz on the quick preset's step; and the contact law, which is
//! nonlinear: with a crack in contact the transforms remove the linear part of the step's
//! error and the rest is measured (docs/src/validation/time-dispersion.md). The transforms
//! also drop everything above `up_to_hz`: a low-pass, far above the transducers' band.

use super::{Integrator, Quantity, RunConfig};
use crate::error::{Error, Result};
use crate::signal::{self, Signal};
use std::f64::consts::PI;

/// The frequency maps of a scheme whose discrete solution at w is the continuous one at
/// Omega(w) (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Central differences: Omega = (2 / dt) sin(w dt / 2).
    CentralDifference,
    /// Newmark average acceleration: Omega = (2 / dt) tan(w dt / 2).
    AverageAcceleration,
}

impl Scheme {
    /// The scheme of `integrator`, when its time error is a frequency map. The fourth-order
    /// step's is not (its K - (dt^2/12) K M^-1 K depends on each mode); its error is of fourth
    /// order instead.
    pub fn of(integrator: Integrator) -> Option<Scheme> {
        match integrator {
            Integrator::Explicit => Some(Scheme::CentralDifference),
            Integrator::Newmark { .. } => Some(Scheme::AverageAcceleration),
            Integrator::FourthOrder => None,
        }
    }

    /// Omega(w) at step `dt`.
    fn apparent(self, w: f64, dt: f64) -> f64 {
        match self {
            Scheme::CentralDifference => 2.0 / dt * (0.5 * w * dt).sin(),
            Scheme::AverageAcceleration => 2.0 / dt * (0.5 * w * dt).tan(),
        }
    }

    /// Omega^-1(w) at step `dt` (w dt / 2 < 1 for central differences).
    fn actual(self, w: f64, dt: f64) -> f64 {
        match self {
            Scheme::CentralDifference => 2.0 / dt * (0.5 * w * dt).asin(),
            Scheme::AverageAcceleration => 2.0 / dt * (0.5 * w * dt).atan(),
        }
    }

    /// The recorded velocity over the true one at the run's frequency `v`: central
    /// differences record (u_{n+1} - u_{n-1}) / 2dt, i sin(v dt) / dt = i Omega cos(v dt / 2);
    /// Newmark's velocity is the trapezoidal one, exactly i Omega.
    fn velocity_gain(self, v: f64, dt: f64) -> f64 {
        match self {
            Scheme::CentralDifference => (0.5 * v * dt).cos(),
            Scheme::AverageAcceleration => 1.0,
        }
    }
}

/// The time-dispersion transforms of one run: its scheme, its step, and the band they cover.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeDispersion {
    scheme: Scheme,
    dt_s: f64,
    up_to_hz: f64,
}

impl TimeDispersion {
    /// The transforms of a run of `integrator` at step `dt_s` over 0..`up_to_hz`; `None` for
    /// an integrator whose error is not a frequency map ([`Scheme::of`]). `up_to_hz` must lie
    /// below 0.9 / (pi dt), where w dt / 2 = 0.9 and both maps are still smooth; the error
    /// names `field`.
    pub fn of_run(
        integrator: Integrator,
        dt_s: f64,
        up_to_hz: f64,
        field: &str,
    ) -> Result<Option<TimeDispersion>> {
        let Some(scheme) = Scheme::of(integrator) else {
            return Ok(None);
        };
        let limit_hz = Self::band_limit_hz(dt_s);
        if !(up_to_hz.is_finite() && up_to_hz > 0.0 && up_to_hz < limit_hz) {
            return Err(Error::invalid(
                field,
                up_to_hz,
                format!(
                    "must be a frequency below 0.9 / (pi dt) = {limit_hz:.4e} Hz for the run's \
                     step dt = {dt_s:.4e} s (Hz)"
                ),
            ));
        }
        Ok(Some(TimeDispersion {
            scheme,
            dt_s,
            up_to_hz,
        }))
    }

    /// The highest band a run at step `dt_s` can be transformed over (Hz): 0.9 / (pi dt),
    /// where w dt / 2 = 0.9.
    pub fn band_limit_hz(dt_s: f64) -> f64 {
        0.9 / (PI * dt_s)
    }

    /// The band the transforms cover (Hz): recordings hold nothing above it.
    pub fn up_to_hz(&self) -> f64 {
        self.up_to_hz
    }

    /// The forward transform: `source` on the run's step with its spectrum read at Omega(w),
    /// so that the run's recordings, through [`TimeDispersion::remove_from_trace`], carry no
    /// time step error.
    pub fn add_to_source(&self, source: &Signal) -> Result<Signal> {
        let on_step = self.on_step(source)?;
        let (scheme, dt) = (self.scheme, self.dt_s);
        signal::warp_spectrum(&on_step, self.up_to_hz, |w| (scheme.apparent(w, dt), 1.0))
            .map_err(stopped_or_signal)
    }

    /// The inverse transform: a recording of `quantity` with its spectrum read at
    /// Omega^-1(w) (and a velocity's central-difference gain divided out).
    pub fn remove_from_trace(&self, trace: &Signal, quantity: Quantity) -> Result<Signal> {
        let on_step = self.on_step(trace)?;
        let (scheme, dt) = (self.scheme, self.dt_s);
        signal::warp_spectrum(&on_step, self.up_to_hz, |w| {
            let v = scheme.actual(w, dt);
            let gain = match quantity {
                Quantity::Displacement => 1.0,
                Quantity::Velocity => 1.0 / scheme.velocity_gain(v, dt),
            };
            (v, gain)
        })
        .map_err(stopped_or_signal)
    }

    /// `config` run for [`TimeDispersion::margin_s`] longer: the inverse transform spoils the
    /// end of a recording cut off mid-signal, so a run goes on past the time asked and its
    /// recordings are cut back ([`TimeDispersion::cut_back`]). The sources are zero over the
    /// margin, and the report, ledger and crack traces cover the longer run.
    pub fn extended(&self, config: &RunConfig) -> RunConfig {
        RunConfig {
            duration_s: config.duration_s + self.margin_s(),
            ..config.clone()
        }
    }

    /// How long past its end a recording is spoilt by the inverse transform (s): the
    /// band's roll-off rings for [`signal::ROLL_OFF_PERIODS`] periods of `up_to_hz` (1 us at
    /// the default 20 MHz, 1.7% of a 60 us run).
    pub fn margin_s(&self) -> f64 {
        signal::ROLL_OFF_PERIODS / self.up_to_hz
    }

    /// A trace of the run of [`TimeDispersion::extended`]`(config)` as the run of `config`
    /// records it without the step's error: [`TimeDispersion::remove_from_trace`], then
    /// [`TimeDispersion::cut_back`].
    pub fn recorded(
        &self,
        trace: &Signal,
        quantity: Quantity,
        config: &RunConfig,
    ) -> Result<Signal> {
        Ok(self.cut_back(&self.remove_from_trace(trace, quantity)?, config))
    }

    /// The first samples of `trace` a run of `config` at this step records.
    pub fn cut_back(&self, trace: &Signal, config: &RunConfig) -> Signal {
        let n = super::step_count(config.duration_s, self.dt_s);
        Signal {
            samples: trace.samples[..n.min(trace.len())].to_vec(),
            ..*trace
        }
    }

    /// `s` resampled on the run's step when its interval differs.
    fn on_step(&self, s: &Signal) -> Result<Signal> {
        if ((s.dt_s - self.dt_s) / self.dt_s).abs() < signal::DT_REL_TOL {
            Ok(s.clone())
        } else {
            Ok(signal::resample(s, self.dt_s)?)
        }
    }
}

/// A stopped transform as the run's stop (the host reports it as Ctrl-C or the time limit),
/// any other signal error as it is.
fn stopped_or_signal(e: signal::SignalError) -> Error {
    match e {
        signal::SignalError::Stopped(stop) => Error::Stopped(stop),
        other => other.into(),
    }
}
