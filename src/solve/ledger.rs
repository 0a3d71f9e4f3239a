//! The energy ledger of report Sec. 4.10.1: kinetic + strain + dashpot loss + contact loss
//! = initial energy + source work; its residual is every run's first error indicator. A scene
//! with losses adds the energy its memory variables hold and what the relaxation dissipated
//! ([`crate::attenuation`]).

use super::stepper::EnergySample;
use serde::Serialize;

/// Energy time series (J per metre of thickness) and the balance residual.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EnergyLedger {
    /// Sample times (s).
    pub time_s: Vec<f64>,
    /// Kinetic energy.
    pub kinetic_j: Vec<f64>,
    /// Strain energy.
    pub strain_j: Vec<f64>,
    /// Cumulative work done by the sources.
    pub source_work_j: Vec<f64>,
    /// Cumulative energy absorbed by the Lysmer-Kuhlemeyer dashpots.
    pub dashpot_loss_j: Vec<f64>,
    /// Cumulative energy removed by the contact forces (friction and impact).
    pub contact_loss_j: Vec<f64>,
    /// Of `contact_loss_j`, the part done by the tangential (friction) forces.
    pub friction_loss_j: Vec<f64>,
    /// Energy held by the memory variables beyond the unrelaxed strain energy (may be
    /// negative; absent from the output of elastic scenes, where it is zero).
    #[serde(skip_serializing_if = "all_zero")]
    pub memory_j: Vec<f64>,
    /// Cumulative energy dissipated by the materials' relaxation (absent where zero).
    #[serde(skip_serializing_if = "all_zero")]
    pub viscous_loss_j: Vec<f64>,
    /// (kinetic + strain + losses - initial - source work) / (initial + max |source work|).
    pub residual: Vec<f64>,
    /// Energy at the start (from initial conditions).
    pub initial_j: f64,
}

/// Running sums of the energy flows, updated every step (J per m of thickness).
#[derive(Clone, Copy, Debug, Default)]
pub struct Flows {
    /// Work done by the sources.
    pub source_work: f64,
    /// Energy absorbed by the dashpots.
    pub dashpot_loss: f64,
    /// Work done by the normal contact forces (negative: energy removed).
    pub contact_normal_work: f64,
    /// Work done by the tangential (friction) contact forces.
    pub contact_tangential_work: f64,
    /// Energy dissipated by the materials' relaxation.
    pub viscous_loss: f64,
}

fn all_zero(values: &[f64]) -> bool {
    values.iter().all(|&v| v == 0.0)
}

impl EnergyLedger {
    /// Appends a sample; returns its relative residual.
    pub fn push(&mut self, sample: &EnergySample) -> f64 {
        let EnergySample {
            time_s,
            kinetic_j: kinetic,
            strain_j: strain,
            memory_j: memory,
            ref flows,
        } = *sample;
        let contact_loss = -(flows.contact_normal_work + flows.contact_tangential_work);
        let imbalance =
            kinetic + strain + memory + flows.dashpot_loss + contact_loss + flows.viscous_loss
                - self.initial_j
                - flows.source_work;
        let max_work = self
            .source_work_j
            .iter()
            .fold(flows.source_work.abs(), |m, w| m.max(w.abs()));
        let scale = self.initial_j + max_work;
        let residual = if scale > 0.0 { imbalance / scale } else { 0.0 };
        self.time_s.push(time_s);
        self.kinetic_j.push(kinetic);
        self.strain_j.push(strain);
        self.source_work_j.push(flows.source_work);
        self.dashpot_loss_j.push(flows.dashpot_loss);
        self.contact_loss_j.push(contact_loss);
        self.friction_loss_j.push(-flows.contact_tangential_work);
        self.memory_j.push(memory);
        self.viscous_loss_j.push(flows.viscous_loss);
        self.residual.push(residual);
        residual
    }

    /// Last residual (0 for an empty ledger).
    pub fn final_residual(&self) -> f64 {
        self.residual.last().copied().unwrap_or(0.0)
    }

    /// Largest |residual|.
    pub fn peak_residual(&self) -> f64 {
        self.residual.iter().fold(0.0, |m, r| m.max(r.abs()))
    }

    /// Total energy kinetic + strain at each sample.
    pub fn total_j(&self) -> Vec<f64> {
        self.kinetic_j
            .iter()
            .zip(&self.strain_j)
            .map(|(k, s)| k + s)
            .collect()
    }
}
