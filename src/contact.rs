//! Node-to-node contact with Coulomb friction on a crack (report Sec. 4.9, Table 3 corrected:
//! docs/src/physics.md), each pair in its own frame: the unit normal n of the crack at the
//! pair, pointing from the slave's face into the master's side ((0, 1) on a horizontal crack,
//! the slave below), and the tangent t = (n_y, -n_x).
//!
//! With lumped mass the explicit predictor u* moves each crack DOF independently, and a
//! contact force lambda changes the next displacement by D lambda with D = dt^2 / m (divided
//! by 1 + c dt / 2m on a damped DOF). Where D is the same along x and y (or the crack is
//! horizontal or vertical) the normal and tangential directions do not couple, so every pair
//! is a scalar problem per direction and the correction costs O(pairs) per step:
//! - normal gap g_N = n . (u(slave) - u(master)) (> 0 is penetration), lambda_N >= 0
//!   (eq 70), pushing the master along n and the slave against it;
//! - exact forward-increment multiplier (Carpenter, Taylor, Katona 1991):
//!   lambda_N = g_N / (D_m + D_s), closing the gap in one pass;
//! - augmented Lagrangian: lambda_N <- max(0, lambda_N + b g_N) until the penetration norm
//!   is below epsilon; the residual shrinks by |1 - b (D_m + D_s)| per iteration, so it
//!   converges in one step for b = 1/(D_m + D_s) and diverges for b > 2/(D_m + D_s);
//! - friction: tangential gap g_T = t . (u(slave) - u(master)), stick point g_T^s, trial
//!   lambda_T' = (g_T - g_T^s)/(D_m + D_s); stick if |lambda_T'| <= s, the frictional
//!   strength, else slip with lambda_T = sgn(g_T - g_T^s) s and the stick point moved;
//! - strength s = mu lambda_N (Coulomb, the report's law) or, with a response time tau,
//!   s = mu lambda_N* where d lambda_N*/dt = (lambda_N - lambda_N*) / tau (the simplified
//!   Prakash-Clifton law: Prakash and Clifton 1993; Cochard and Rice 2000), integrated exactly
//!   over a step with lambda_N held: s <- e^(-dt/tau) s + (1 - e^(-dt/tau)) mu lambda_N.
//!   A pair that opens keeps that strength, decaying over tau, as the regularised faults of
//!   SEM2DPACK do (Ampuero's `bc_dynflt`: the shear strength is mu sigma* whether or not the
//!   fault opens). Were an open pair's friction zero, a pair whose normal force just reaches
//!   zero in a step, and one that just misses, would differ by the whole lagged strength: the
//!   run would jump under an arbitrarily small change of its input. Under the instantaneous
//!   law the strength vanishes with the normal force, and an open pair is free.
//!   With the instantaneous law, node-to-node friction on the GLL nodes of spectral elements
//!   of order 3 and above flutters: the pairs chatter open and shut and the mean friction
//!   falls short of mu N. A tau of the P-wave travel time over the mean node spacing along
//!   the crack removes it (docs/src/validation/spectral-elements.md, "Friction at high order").

use crate::error::{Error, Result};
use crate::mesh::{Crack, CrackPair};
use crate::signal::Signal;
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
    /// Response time tau (s) of the frictional strength to the normal force (simplified
    /// Prakash-Clifton law, module doc; an open pair keeps the strength, fading over tau);
    /// default [`DEFAULT_NORMAL_STRESS_LAG_S`]; 0: instantaneous, the report's Coulomb law.
    pub normal_stress_lag_s: f64,
}

/// The friction strength's default response time tau, 20 ns. The report's instantaneous
/// Coulomb law (tau = 0) is ill-posed between the crack's dissimilar faces (Cochard and Rice
/// 2000): on spectral elements its node pairs chatter, so a pushed block slides 8-27% faster
/// than (T - mu N)/m at orders 4-8 (the quick preset is order 7), and the cracked focusing
/// amplifies any change of its input (a 1e-6 relative change of mu moves the quick preset's
/// y_TR 625 times as much). 20 ns removes both (the block within 0.5% at orders 2-8, y_TR
/// moving 0.02-0.03 times, smoothly; docs/src/validation/spectral-elements.md, "Friction at
/// high order"): it is about the P-wave travel time over the presets' node spacing along the
/// crack (28 ns at quick, 16 ns at paper) and a 25th of the band's shortest period, and it is
/// the response time both references of the default experiment were run with.
pub const DEFAULT_NORMAL_STRESS_LAG_S: f64 = 20e-9;

/// The largest friction coefficient accepted (see [`ContactOptions::validate`]).
pub const MAX_FRICTION: f64 = 10.0;

impl ContactOptions {
    /// Checks every option; an error names the field and the value given.
    pub fn validate(&self) -> Result<()> {
        // Dry friction coefficients of real surfaces lie below about 1.5; the tests drive the
        // law up to 10 (tests/stability), which bounds what the stick-slip algorithm is known
        // to handle.
        crate::error::require_within(
            "contact.friction",
            self.friction,
            0.0,
            MAX_FRICTION,
            "",
            "a Coulomb coefficient",
        )?;
        let lag = self.normal_stress_lag_s;
        if !(lag.is_finite() && lag >= 0.0) {
            return Err(Error::invalid(
                "contact.normal_stress_lag_s",
                lag,
                "must be finite and >= 0 (s; 0: the instantaneous Coulomb law)",
            ));
        }
        if let ContactMethod::AugmentedLagrangian {
            penalty_scale,
            tolerance_m,
            max_iterations,
        } = self.method
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
            if max_iterations == 0 || max_iterations > MAX_AL_ITERATIONS {
                return Err(Error::invalid(
                    "contact.max_iterations",
                    max_iterations,
                    format!("must be in 1..={MAX_AL_ITERATIONS} (iterations per step)"),
                ));
            }
        }
        Ok(())
    }
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions {
            method: ContactMethod::Exact,
            friction: 0.6,
            normal_stress_lag_s: DEFAULT_NORMAL_STRESS_LAG_S,
        }
    }
}

/// Contact diagnostics of a run: scalars only (the per-step counts are in [`ContactSeries`]).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ContactReport {
    /// Method used.
    pub method: String,
    /// Node pairs on the crack.
    pub pairs: usize,
    /// Mean contact iterations per step (1 for the exact multiplier while in contact).
    pub iterations_mean: f64,
    /// Largest iterations in one step.
    pub iterations_max: usize,
    /// Steps that hit the iteration cap.
    pub capped_steps: usize,
    /// Largest penetration left after the correction (m).
    pub max_penetration_m: f64,
    /// Steps with at least one pair in contact.
    pub steps_in_contact: usize,
    /// Steps with at least one pair slipping.
    pub steps_slipping: usize,
    /// Most pairs in contact at one step.
    pub max_pairs_in_contact: usize,
    /// Most pairs slipping at one step.
    pub max_pairs_slipping: usize,
    /// Mean pairs in contact over the steps in contact (0 if the crack never closed).
    pub mean_pairs_in_contact: f64,
    /// Mean pairs slipping over the steps in contact (0 if the crack never closed); with
    /// `mean_pairs_in_contact`, the fraction of contact that slips.
    pub mean_pairs_slipping: f64,
}

/// Pair counts at every step of a run, sampled at the solver step: sample n counts the
/// state after the correction of step n, i.e. of the displacement at t = (n + 1) dt.
#[derive(Clone, Debug, Serialize)]
pub struct ContactSeries {
    /// Pairs in contact (carrying a normal force).
    pub in_contact: Signal,
    /// Pairs in contact and sticking.
    pub sticking: Signal,
    /// Pairs in contact and slipping.
    pub slipping: Signal,
}

/// Pair counts per step, collected during a run.
#[derive(Clone, Debug, Default)]
struct Counts {
    in_contact: Vec<u32>,
    sticking: Vec<u32>,
    slipping: Vec<u32>,
}

impl Counts {
    fn with_capacity(steps: usize) -> Counts {
        Counts {
            in_contact: Vec::with_capacity(steps),
            sticking: Vec::with_capacity(steps),
            slipping: Vec::with_capacity(steps),
        }
    }
}

/// The DOFs, frame and compliances of one pair.
#[derive(Clone, Copy, Debug)]
struct PairDofs {
    master: [usize; 2],
    slave: [usize; 2],
    /// D = dt^2/m (effective) for master x, y and slave x, y.
    d_master: [f64; 2],
    d_slave: [f64; 2],
    /// The unit normal n and the tangent t = (n_y, -n_x).
    normal: [f64; 2],
    tangent: [f64; 2],
    /// The compliance of the gap along n and along t: sum_c v_c^2 (D_slave,c + D_master,c).
    d_normal: f64,
    d_tangent: f64,
}

impl PairDofs {
    /// The pair of `pair` with the per-DOF compliance `compliance`; an error where the
    /// crack is inclined at the pair and a face's D differs along x and y (a fixed or damped
    /// DOF), which would couple the normal and tangential problems.
    fn new(pair: &CrackPair, compliance: &[f64]) -> Result<PairDofs> {
        let (master, slave) = (
            [2 * pair.master, 2 * pair.master + 1],
            [2 * pair.slave, 2 * pair.slave + 1],
        );
        let (d_master, d_slave) = (master.map(|d| compliance[d]), slave.map(|d| compliance[d]));
        let normal = pair.normal;
        let tangent = [normal[1], -normal[0]];
        let inclined = normal[0] != 0.0 && normal[1] != 0.0;
        if inclined && (d_master[0] != d_master[1] || d_slave[0] != d_slave[1]) {
            return Err(Error::Contact(format!(
                "the crack pair of nodes {} and {} is inclined (normal ({:.3}, {:.3})) on a \
                 fixed or absorbing edge, where its DOFs move differently along x and y: end \
                 an inclined crack inside the body or on a free edge",
                pair.master, pair.slave, normal[0], normal[1]
            )));
        }
        let along = |v: [f64; 2]| {
            v[0] * v[0] * (d_slave[0] + d_master[0]) + v[1] * v[1] * (d_slave[1] + d_master[1])
        };
        Ok(PairDofs {
            master,
            slave,
            d_master,
            d_slave,
            normal,
            tangent,
            d_normal: along(normal),
            d_tangent: along(tangent),
        })
    }

    /// v . (u(slave) - u(master)).
    fn gap(&self, v: [f64; 2], u: &[f64]) -> f64 {
        v[0] * (u[self.slave[0]] - u[self.master[0]])
            + v[1] * (u[self.slave[1]] - u[self.master[1]])
    }

    /// Applies the force lambda v to the master and -lambda v to the slave: u changes by
    /// D f per DOF.
    fn push(&self, v: [f64; 2], lambda: f64, u: &mut [f64]) {
        for c in 0..2 {
            u[self.slave[c]] -= self.d_slave[c] * (lambda * v[c]);
            u[self.master[c]] += self.d_master[c] * (lambda * v[c]);
        }
    }
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
    /// mu lambda_N* per pair, the frictional strength (0 at the start: a run starts with the
    /// crack unloaded).
    strength: Vec<f64>,
    /// e^(-dt/tau): the part of the strength kept over a step (0 for the instantaneous law).
    strength_memory: f64,
    pub(crate) force: Vec<PairForce>,
    report: ContactReport,
    counts: Counts,
    iterations_total: usize,
}

impl ContactSolver {
    /// Prepares contact for `crack` given the per-DOF compliance D = dt^2 / m_eff of steps
    /// of `dt_s`.
    pub fn new(
        crack: &Crack,
        compliance: &[f64],
        options: ContactOptions,
        steps: usize,
        dt_s: f64,
    ) -> Result<ContactSolver> {
        options.validate()?;
        let lag = options.normal_stress_lag_s;
        let pairs = crack
            .pairs
            .iter()
            .map(|p| PairDofs::new(p, compliance))
            .collect::<Result<Vec<_>>>()?;
        let n = pairs.len();
        let report = ContactReport {
            method: format!("{:?}", options.method),
            pairs: n,
            ..Default::default()
        };
        Ok(ContactSolver {
            options,
            pairs,
            stick_gap: vec![0.0; n],
            gap: vec![0.0; n],
            strength: vec![0.0; n],
            strength_memory: if lag > 0.0 { (-dt_s / lag).exp() } else { 0.0 },
            force: vec![PairForce::default(); n],
            report,
            counts: Counts::with_capacity(steps),
            iterations_total: 0,
        })
    }

    /// Sets the stick points to the current tangential gaps (start of a run).
    pub fn reset_stick_points(&mut self, u: &[f64]) {
        for (p, s) in self.pairs.iter().zip(&mut self.stick_gap) {
            *s = p.gap(p.tangent, u);
        }
    }

    /// Corrects the predictor `u_next` so no pair penetrates and friction holds.
    pub fn apply(&mut self, u_next: &mut [f64]) -> Result<()> {
        let iterations = self.normal_forces(u_next)?;
        self.iterations_total += iterations;
        self.report.iterations_max = self.report.iterations_max.max(iterations);
        let (mut contact, mut stick, mut slip) = (0u32, 0u32, 0u32);
        let mu = self.options.friction;
        let memory = self.strength_memory;
        for (k, p) in self.pairs.iter().enumerate() {
            let lambda_n = self.force[k].normal;
            self.strength[k] = memory * self.strength[k] + (1.0 - memory) * mu * lambda_n;
            p.push(p.normal, lambda_n, u_next);
            let residual = p.gap(p.normal, u_next);
            self.report.max_penetration_m = self.report.max_penetration_m.max(residual);
            let g_t = p.gap(p.tangent, u_next);
            let touching = lambda_n > 0.0;
            let strength = self.strength[k];
            // An open pair keeps the lagged strength (zero under the instantaneous law), as
            // SEM2DPACK's regularised faults do: the friction force then stays continuous as
            // the normal force reaches zero (module doc).
            if !touching && strength <= 0.0 {
                self.stick_gap[k] = g_t;
                self.force[k].tangential = 0.0;
                continue;
            }
            contact += touching as u32;
            let d_t = p.d_tangent;
            if d_t <= 0.0 {
                // both tangential DOFs are fixed: nothing can slip
                stick += touching as u32;
                self.force[k].tangential = 0.0;
                continue;
            }
            let trial = (g_t - self.stick_gap[k]) / d_t;
            let sticks = trial.abs() <= strength;
            stick += (touching && sticks) as u32;
            slip += (touching && !sticks) as u32;
            let lambda_t = if sticks {
                trial
            } else {
                trial.signum() * strength
            };
            p.push(p.tangent, lambda_t, u_next);
            self.stick_gap[k] = p.gap(p.tangent, u_next);
            self.force[k].tangential = lambda_t;
        }
        self.counts.in_contact.push(contact);
        self.counts.sticking.push(stick);
        self.counts.slipping.push(slip);
        Ok(())
    }

    /// Normal multipliers for the predictor; returns the iterations used.
    fn normal_forces(&mut self, u_next: &[f64]) -> Result<usize> {
        for (k, p) in self.pairs.iter().enumerate() {
            self.gap[k] = p.gap(p.normal, u_next);
        }
        match self.options.method {
            ContactMethod::Exact => {
                let mut touching = 0;
                for (k, p) in self.pairs.iter().enumerate() {
                    let d = p.d_normal;
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
    #[allow(clippy::too_many_lines)]
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
                let d = p.d_normal;
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
                let r = g - p.d_normal * f.normal;
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
        let d = self.pairs[0].d_normal;
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
            for c in [1, 0] {
                let along = force.normal * p.normal[c] + force.tangential * p.tangent[c];
                f(p.slave[c], -along);
                f(p.master[c], along);
            }
        }
    }

    /// Final diagnostics of a run of `steps` steps of `dt_s`: the scalar report and the
    /// per-step pair counts as signals.
    pub fn finish(mut self, steps: usize, dt_s: f64) -> (ContactReport, ContactSeries) {
        let c = &self.counts;
        let r = &mut self.report;
        r.iterations_mean = self.iterations_total as f64 / steps.max(1) as f64;
        r.steps_in_contact = c.in_contact.iter().filter(|&&n| n > 0).count();
        r.steps_slipping = c.slipping.iter().filter(|&&n| n > 0).count();
        r.max_pairs_in_contact = c.in_contact.iter().max().map_or(0, |&n| n as usize);
        r.max_pairs_slipping = c.slipping.iter().max().map_or(0, |&n| n as usize);
        let steps_in_contact = r.steps_in_contact.max(1) as f64;
        let per_step_in_contact =
            |v: &[u32]| v.iter().map(|&n| f64::from(n)).sum::<f64>() / steps_in_contact;
        r.mean_pairs_in_contact = per_step_in_contact(&c.in_contact);
        r.mean_pairs_slipping = per_step_in_contact(&c.slipping);
        let signal = |v: &[u32]| Signal {
            dt_s,
            t0_s: dt_s,
            samples: v.iter().map(|&n| f64::from(n)).collect(),
        };
        let series = ContactSeries {
            in_contact: signal(&c.in_contact),
            sticking: signal(&c.sticking),
            slipping: signal(&c.slipping),
        };
        (self.report, series)
    }
}

/// Most augmented-Lagrangian iterations a step may take (the iteration converges in a few
/// at the optimal penalty; a larger cap only turns a diverging setup into a hang).
pub const MAX_AL_ITERATIONS: usize = 10_000;

#[cfg(test)]
mod tests {
    use super::*;

    fn crack(normal: [f64; 2]) -> Crack {
        Crack {
            pieces_m: vec![],
            pairs: vec![CrackPair {
                master: 0,
                slave: 1,
                normal,
            }],
        }
    }

    /// The friction force of a pair whose normal force just reaches zero in a step and of
    /// one that just misses are the same under a response time (the open pair keeps the
    /// lagged strength), and zero for an open pair under the instantaneous law.
    #[test]
    fn friction_is_continuous_as_a_pair_opens() {
        let compliance = [1.0; 4];
        // u = (master x, master y, slave x, slave y); normal (0, 1), tangent (1, 0)
        let tangential_force = |lag: f64, normal_gap: f64| {
            let options = ContactOptions {
                normal_stress_lag_s: lag,
                ..Default::default()
            };
            let mut solver =
                ContactSolver::new(&crack([0.0, 1.0]), &compliance, options, 2, 1.0).unwrap();
            solver.reset_stick_points(&[0.0; 4]);
            // pressed shut, no sliding: the strength builds up
            solver.apply(&mut [0.0, 0.0, 0.0, 1.0]).unwrap();
            // then pulled along t by 0.1, at the edge of contact
            solver.apply(&mut [0.0, 0.0, 0.1, normal_gap]).unwrap();
            solver.force[0].tangential
        };
        let lag = 1.0 / 2f64.ln(); // half the strength kept per step
        let (shut, open) = (tangential_force(lag, 1e-12), tangential_force(lag, -1e-12));
        // trial 0.1 / (D_m + D_s) = 0.05 below the strength 0.5 * 0.5 * 0.6 * 0.5 = 0.075
        assert!(
            (shut - 0.05).abs() < 1e-12 && (open - 0.05).abs() < 1e-12,
            "{shut} {open}"
        );
        assert_eq!(tangential_force(0.0, -1e-12), 0.0);
        assert!(tangential_force(0.0, 1e-12).abs() < 1e-12);
    }

    /// An inclined pair whose DOFs move differently along x and y (here the slave's x held)
    /// is refused, naming its nodes; the same pair level, or with equal compliances, is
    /// taken, and its normal and tangential compliances are D_s + D_m.
    #[test]
    fn an_inclined_pair_on_a_held_dof_is_refused() {
        let (held, free) = ([1.0, 1.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]);
        let options = ContactOptions::default();
        let inclined = [-0.6, 0.8];
        let e = ContactSolver::new(&crack(inclined), &held, options, 1, 1.0)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("nodes 0 and 1") && e.contains("inclined"), "{e}");
        assert!(ContactSolver::new(&crack([0.0, 1.0]), &held, options, 1, 1.0).is_ok());
        let solver = ContactSolver::new(&crack(inclined), &free, options, 1, 1.0).unwrap();
        let p = &solver.pairs[0];
        assert!((p.d_normal - 2.0).abs() < 1e-15 && (p.d_tangent - 2.0).abs() < 1e-15);
        assert_eq!(p.tangent, [0.8, 0.6]);
    }
}
