#[derive(Debug, thiserror::Error)] #[error("signal")] pub struct SignalError;
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Signal { pub dt_s: f64, pub t0_s: f64, pub samples: Vec<f64> }
pub fn resample(s: &Signal, dt: f64) -> Result<Signal, SignalError> { Ok(resample_linear_tmp(s, dt)) }
pub fn resample_linear_tmp(s: &Signal, dt: f64) -> Signal { let n = ((s.samples.len()-1) as f64 * s.dt_s / dt).floor() as usize + 1; Signal{dt_s: dt, t0_s: s.t0_s, samples: (0..n).map(|k| { let x = k as f64*dt/s.dt_s; let i = x.floor() as usize; let f = x - i as f64; if i+1 < s.samples.len() { s.samples[i]*(1.0-f)+s.samples[i+1]*f } else { s.samples[i] } }).collect()} }
