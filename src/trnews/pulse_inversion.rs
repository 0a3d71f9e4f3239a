//! Pulse inversion (report Sec. 5.3): the responses to the focusing drive and to its inverse
//! summed; a linear channel sums to zero, a contacting crack does not.

use super::channel::Responder;
use crate::accuracy::Estimate;
use crate::error::Result;
use crate::signal::Signal;
use crate::solve::RunReport;

/// Pulse inversion of any transmission: responses to +s and -s and their sum per receiver.
#[derive(Clone, Debug)]
pub struct PulseInversion {
    /// Responses to +s.
    pub positive: Vec<Signal>,
    /// Responses to -s.
    pub negative: Vec<Signal>,
    /// positive + negative: zero (to round-off) for a linear scene.
    pub sum: Vec<Signal>,
    /// Reports of the two runs (empty when convolved).
    pub reports: Vec<RunReport>,
    /// Per receiver, the estimate of the residual max|sum| / max|positive|, when the
    /// responder has companions.
    pub residual_estimates: Option<Vec<Estimate>>,
}

impl PulseInversion {
    /// Per receiver, the residual max|sum| / max|positive|.
    pub fn residuals(&self) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.positive)
            .map(|(s, p)| s.max_abs() / p.max_abs())
            .collect()
    }
}

/// Transmits +s and -s (in parallel) and sums the responses (report Sec. 5.3), also on the
/// responder's companions, with estimates of the residuals.
pub fn pulse_inversion(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let mut main = pulse_inversion_once(responder, s, duration_s)?;
    if !responder.companions.is_empty() {
        let mut runs = vec![main.residuals()];
        for c in &responder.companions {
            runs.push(pulse_inversion_once(c, s, duration_s)?.residuals());
        }
        let refinement = responder.refinement()?;
        main.residual_estimates = Some(
            (0..runs[0].len())
                .map(|k| {
                    let values: Vec<f64> = runs.iter().map(|r| r[k]).collect();
                    Estimate::dimensionless_of(&values, refinement)
                })
                .collect::<Result<_>>()?,
        );
    }
    Ok(main)
}

fn pulse_inversion_once(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let pair = responder.respond_all(&[s.clone(), s.scale(-1.0)?], duration_s)?;
    let sum = pair[0]
        .traces
        .iter()
        .zip(&pair[1].traces)
        .map(|(a, b)| a.add(b))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let reports = pair.iter().filter_map(|r| r.report.clone()).collect();
    let mut it = pair.into_iter();
    let (p, n) = (it.next().unwrap(), it.next().unwrap());
    Ok(PulseInversion {
        positive: p.traces,
        negative: n.traces,
        sum,
        reports,
        residual_estimates: None,
    })
}
