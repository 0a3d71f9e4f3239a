//! The energy ledger of report Sec. 4.10.1: kinetic + strain + dashpot loss + contact loss
//! = initial energy + source work; its residual is every run's first error indicator.

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
}

impl EnergyLedger {
    /// Appends a sample; returns its relative residual.
    pub fn push(&mut self, time_s: f64, kinetic: f64, strain: f64, flows: &Flows) -> f64 {
        let contact_loss = -(flows.contact_normal_work + flows.contact_tangential_work);
        let imbalance = kinetic + strain + flows.dashpot_loss + contact_loss
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
