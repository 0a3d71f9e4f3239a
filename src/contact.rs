//! Node-to-node contact with Coulomb friction on a horizontal crack (report Sec. 4.9,
//! Table 3 corrected as in DESIGN.md item 4).
//!
//! With lumped mass the explicit predictor u* moves each crack DOF independently, and a
//! contact force lambda changes the next displacement by D lambda with D = dt^2 / m (divided
//! by 1 + c dt / 2m on a damped DOF). So every pair is a scalar problem per direction and
//! the correction costs O(pairs) per step:
//! - normal gap g_N = u_y(slave) - u_y(master) (> 0 is penetration), lambda_N >= 0 (eq 70);
//! - exact forward-increment multiplier (Carpenter, Taylor, Katona 1991):
//!   lambda_N = g_N / (D_m + D_s), closing the gap in one pass;
//! - augmented Lagrangian: lambda_N <- max(0, lambda_N + b g_N) until the penetration norm
//!   is below epsilon; the residual shrinks by |1 - b (D_m + D_s)| per iteration, so it
//!   converges in one step for b = 1/(D_m + D_s) and diverges for b > 2/(D_m + D_s);
//! - friction: tangential gap g_T = u_x(slave) - u_x(master), stick point g_T^s, trial
//!   lambda_T' = (g_T - g_T^s)/(D_m + D_s); stick if |lambda_T'| <= mu lambda_N, else slip
//!   with lambda_T = sgn(g_T - g_T^s) mu lambda_N and the stick point moved.

use crate::error::{Error, Result};
use crate::mesh::Crack;
use serde::{Deserialize, Serialize};

/// How the normal contact constraint is enforced.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum ContactMethod {
    /// The exact forward-increment Lagrange multiplier for lumped mass.
    Exact,
    /// The report's penalty + augmented-Lagrangian iteration.
    AugmentedLagrangian {
        /// Penalty b as a multiple of the one-iteration optimum 1/(D_m + D_s); above 2 diverges.
        penalty_scale: f64,
        /// Stop when the L2 norm of penetration is below this (m).
        tolerance_m: f64,
        /// Iteration cap per step.
        max_iterations: usize,
    },
}

/// Contact options of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactOptions {
    /// Normal contact method.
    pub method: ContactMethod,
    /// Coulomb friction coefficient mu (report: 0.6).
    pub friction: f64,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions {
            method: ContactMethod::Exact,
            friction: 0.6,
        }
    }
}

/// Contact diagnostics of a run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ContactReport {
    /// Method used.
    pub method: String,
    /// Mean contact iterations per step (1 for the exact multiplier while in contact).
    pub iterations_mean: f64,
    /// Largest iterations in one step.
    pub iterations_max: usize,
    /// Steps that hit the iteration cap.
    pub capped_steps: usize,
    /// Largest penetration left after the correction (m).
    pub max_penetration_m: f64,
    /// Pairs in contact at each step.
    pub in_contact: Vec<u32>,
    /// Pairs sticking at each step.
    pub sticking: Vec<u32>,
    /// Pairs slipping at each step.
    pub slipping: Vec<u32>,
    /// Steps with at least one pair in contact.
    pub steps_in_contact: usize,
}

/// The DOFs and compliances of one pair.
#[derive(Clone, Copy, Debug)]
struct PairDofs {
    master: [usize; 2],
    slave: [usize; 2],
    /// D = dt^2/m (effective) for master x, y and slave x, y.
    d_master: [f64; 2],
    d_slave: [f64; 2],
}

/// Contact forces of the last step, for the energy ledger.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PairForce {
    pub normal: f64,
    pub tangential: f64,
}

/// Per-run contact state; all buffers are allocated once.
pub struct ContactSolver {
    options: ContactOptions,
    pairs: Vec<PairDofs>,
    stick_gap: Vec<f64>,
    gap: Vec<f64>,
    pub(crate) force: Vec<PairForce>,
    report: ContactReport,
    iterations_total: usize,
}

impl ContactSolver {
    /// Prepares contact for `crack` given the per-DOF compliance D = dt^2 / m_eff.
    pub fn new(
        crack: &Crack,
        compliance: &[f64],
        options: ContactOptions,
        steps: usize,
    ) -> Result<ContactSolver> {
        if !(options.friction.is_finite() && options.friction >= 0.0) {
            return Err(Error::invalid(
                "contact.friction",
                options.friction,
                "must be finite and >= 0",
            ));
        }
        if let ContactMethod::AugmentedLagrangian {
            penalty_scale,
            tolerance_m,
            max_iterations,
        } = options.method
        {
            if !(penalty_scale.is_finite() && penalty_scale > 0.0) {
                return Err(Error::invalid(
                    "contact.penalty_scale",
                    penalty_scale,
                    "must be finite and > 0",
                ));
            }
            if !(tolerance_m.is_finite() && tolerance_m > 0.0) {
                return Err(Error::invalid(
                    "contact.tolerance_m",
                    tolerance_m,
                    "must be finite and > 0",
                ));
            }
            if max_iterations == 0 {
                return Err(Error::invalid(
                    "contact.max_iterations",
                    0,
                    "must be at least 1",
                ));
            }
        }
        let pairs: Vec<PairDofs> = crack
            .pairs
            .iter()
            .map(|p| {
                let (m, s) = (
                    [2 * p.master, 2 * p.master + 1],
                    [2 * p.slave, 2 * p.slave + 1],
                );
                PairDofs {
                    master: m,
                    slave: s,
                    d_master: m.map(|d| compliance[d]),
                    d_slave: s.map(|d| compliance[d]),
                }
            })
            .collect();
        let n = pairs.len();
        let report = ContactReport {
            method: format!("{:?}", options.method),
            in_contact: Vec::with_capacity(steps),
            sticking: Vec::with_capacity(steps),
            slipping: Vec::with_capacity(steps),
            ..Default::default()
        };
        Ok(ContactSolver {
            options,
            pairs,
            stick_gap: vec![0.0; n],
            gap: vec![0.0; n],
            force: vec![PairForce::default(); n],
            report,
            iterations_total: 0,
        })
    }

    /// Sets the stick points to the current tangential gaps (start of a run).
    pub fn reset_stick_points(&mut self, u: &[f64]) {
        for (p, s) in self.pairs.iter().zip(&mut self.stick_gap) {
            *s = u[p.slave[0]] - u[p.master[0]];
        }
    }

    /// Corrects the predictor `u_next` so no pair penetrates and friction holds.
    pub fn apply(&mut self, u_next: &mut [f64]) -> Result<()> {
        let iterations = self.normal_forces(u_next)?;
        self.iterations_total += iterations;
        self.report.iterations_max = self.report.iterations_max.max(iterations);
        let (mut contact, mut stick, mut slip) = (0u32, 0u32, 0u32);
        let mu = self.options.friction;
        for (k, p) in self.pairs.iter().enumerate() {
            let lambda_n = self.force[k].normal;
            u_next[p.slave[1]] -= p.d_slave[1] * lambda_n;
            u_next[p.master[1]] += p.d_master[1] * lambda_n;
            let residual = u_next[p.slave[1]] - u_next[p.master[1]];
            self.report.max_penetration_m = self.report.max_penetration_m.max(residual);
            let g_t = u_next[p.slave[0]] - u_next[p.master[0]];
            if lambda_n <= 0.0 {
                self.stick_gap[k] = g_t;
                self.force[k].tangential = 0.0;
                continue;
            }
            contact += 1;
            let d_t = p.d_slave[0] + p.d_master[0];
            if d_t <= 0.0 {
                // both tangential DOFs are fixed: nothing can slip
                stick += 1;
                self.force[k].tangential = 0.0;
                continue;
            }
            let trial = (g_t - self.stick_gap[k]) / d_t;
            let lambda_t = if trial.abs() <= mu * lambda_n {
                stick += 1;
                trial
            } else {
                slip += 1;
                trial.signum() * mu * lambda_n
            };
            u_next[p.slave[0]] -= p.d_slave[0] * lambda_t;
            u_next[p.master[0]] += p.d_master[0] * lambda_t;
            self.stick_gap[k] = u_next[p.slave[0]] - u_next[p.master[0]];
            self.force[k].tangential = lambda_t;
        }
        self.report.in_contact.push(contact);
        self.report.sticking.push(stick);
        self.report.slipping.push(slip);
        self.report.steps_in_contact += (contact > 0) as usize;
        Ok(())
    }

    /// Normal multipliers for the predictor; returns the iterations used.
    fn normal_forces(&mut self, u_next: &[f64]) -> Result<usize> {
        for (k, p) in self.pairs.iter().enumerate() {
            self.gap[k] = u_next[p.slave[1]] - u_next[p.master[1]];
        }
        match self.options.method {
            ContactMethod::Exact => {
                let mut touching = 0;
                for (k, p) in self.pairs.iter().enumerate() {
                    let d = p.d_slave[1] + p.d_master[1];
                    let lambda = if d > 0.0 {
                        (self.gap[k] / d).max(0.0)
                    } else {
                        0.0
                    };
                    touching += (lambda > 0.0) as usize;
                    self.force[k].normal = lambda;
                }
                Ok((touching > 0) as usize)
            }
            ContactMethod::AugmentedLagrangian {
                penalty_scale,
                tolerance_m,
                max_iterations,
            } => self.augmented_lagrangian(penalty_scale, tolerance_m, max_iterations),
        }
    }

    /// lambda_N <- max(0, lambda_N + b g_N(lambda)) until the constraint residual (the
    /// penetration, and the opening of pairs still carrying force) has L2 norm < tolerance.
    fn augmented_lagrangian(
        &mut self,
        scale: f64,
        tolerance: f64,
        max_iterations: usize,
    ) -> Result<usize> {
        for f in &mut self.force {
            f.normal = 0.0;
        }
        let initial = self.constraint_residual();
        let mut norm = initial;
        for it in 1..=max_iterations {
            if norm <= tolerance {
                return Ok(it - 1);
            }
            for (k, p) in self.pairs.iter().enumerate() {
                let d = p.d_slave[1] + p.d_master[1];
                let residual_gap = self.gap[k] - d * self.force[k].normal;
                self.force[k].normal = (self.force[k].normal + scale / d * residual_gap).max(0.0);
            }
            norm = self.constraint_residual();
            if norm > initial * (1.0 + 1e-9) {
                return Err(self.divergence(scale));
            }
        }
        if norm > tolerance {
            self.report.capped_steps += 1;
        }
        Ok(max_iterations)
    }

    /// L2 norm over pairs of the residual gap g_N - D lambda_N where it violates the
    /// Kuhn-Tucker conditions: positive (penetration), or non-zero while lambda_N > 0.
    fn constraint_residual(&self) -> f64 {
        let sum: f64 = self
            .pairs
            .iter()
            .zip(&self.force)
            .zip(&self.gap)
            .map(|((p, f), g)| {
                let r = g - (p.d_slave[1] + p.d_master[1]) * f.normal;
                if f.normal > 0.0 {
                    r * r
                } else {
                    r.max(0.0).powi(2)
                }
            })
            .sum();
        sum.sqrt()
    }

    fn divergence(&self, scale: f64) -> Error {
        let p = &self.pairs[0];
        let d = p.d_slave[1] + p.d_master[1];
        Error::Contact(format!(
            "augmented-Lagrangian iteration diverges: penalty b = {:.4e} N/m is above the stable bound 2/(D_master + D_slave) = {:.4e} N/m (optimum 1/(D_master + D_slave) = {:.4e} N/m); lower penalty_scale from {scale} to at most 1, or use the exact multiplier",
            scale / d,
            2.0 / d,
            1.0 / d
        ))
    }

    /// Contact forces on the four DOFs of each pair: (dof, force) for the ledger.
    pub(crate) fn for_each_force(&self, mut f: impl FnMut(usize, f64)) {
        for (p, force) in self.pairs.iter().zip(&self.force) {
            f(p.slave[1], -force.normal);
            f(p.master[1], force.normal);
            f(p.slave[0], -force.tangential);
            f(p.master[0], force.tangential);
        }
    }

    /// Final diagnostics.
    pub fn finish(mut self, steps: usize) -> ContactReport {
        self.report.iterations_mean = self.iterations_total as f64 / steps.max(1) as f64;
        self.report
    }
}
