//! The parts of a time loop: a [`Stepper`] advances a state by one step, [`Observer`]s read
//! it (receivers, energy ledger, crack traces, snapshots), and [`drive`] is the one loop that
//! calls them in order. A Rust user builds a custom loop from the same parts (see
//! `examples/custom_loop.rs`).

use super::ledger::Flows;
use crate::error::Result;

/// The fields at t_n, handed to observers once step n has computed t_{n+1}.
pub struct Fields<'a> {
    /// Step index n.
    pub step: usize,
    /// Time step (s).
    pub dt_s: f64,
    /// Displacement u_n (m), 2 values per node.
    pub displacement: &'a [f64],
    /// Velocity at t_n.
    pub velocity: Velocity<'a>,
}

/// How a stepper knows the velocity at t_n.
pub enum Velocity<'a> {
    /// Central difference (u_{n+1} - u_{n-1}) / (2 dt) from the neighbouring displacements.
    Central {
        /// u_{n-1}.
        previous: &'a [f64],
        /// u_{n+1}.
        next: &'a [f64],
    },
    /// The central difference made fourth-order (the modified-equation scheme):
    /// (u_{n+1} - u_{n-1}) / (2 dt) - (dt^2 / 6) j_n, with the third derivative j_n from the
    /// accelerations of the last three steps, (3 a_n - 4 a_{n-1} + a_{n-2}) / (2 dt).
    Corrected {
        /// u_{n-1}.
        previous: &'a [f64],
        /// u_{n+1}.
        next: &'a [f64],
        /// a_n, a_{n-1}, a_{n-2}.
        accelerations: [&'a [f64]; 3],
    },
    /// A velocity the integrator carries (Newmark's v_n).
    Nodal(&'a [f64]),
}

impl Fields<'_> {
    /// Time t_n (s).
    pub fn time_s(&self) -> f64 {
        self.step as f64 * self.dt_s
    }

    /// sum_d w_d u_d over (DOF, weight) pairs.
    pub fn weighted_displacement(&self, weights: &[(usize, f64)]) -> f64 {
        weights.iter().map(|&(d, w)| w * self.displacement[d]).sum()
    }

    /// sum_d w_d v_d over (DOF, weight) pairs; for central differences the weighted
    /// displacement change over two steps divided once by 2 dt.
    pub fn weighted_velocity(&self, weights: &[(usize, f64)]) -> f64 {
        match self.velocity {
            Velocity::Central { previous, next } => {
                weights
                    .iter()
                    .map(|&(d, w)| w * (next[d] - previous[d]))
                    .sum::<f64>()
                    / (2.0 * self.dt_s)
            }
            Velocity::Corrected {
                previous,
                next,
                accelerations: [a0, a1, a2],
            } => {
                let dt = self.dt_s;
                weights
                    .iter()
                    .map(|&(d, w)| {
                        let central = (next[d] - previous[d]) / (2.0 * dt);
                        w * (central - dt / 12.0 * (3.0 * a0[d] - 4.0 * a1[d] + a2[d]))
                    })
                    .sum()
            }
            Velocity::Nodal(v) => weights.iter().map(|&(d, w)| w * v[d]).sum(),
        }
    }
}

/// Kinetic and strain energy at the stepper's sampling time, with the energy flows up to it.
#[derive(Clone, Copy, Debug)]
pub struct EnergySample {
    /// Sampling time (s): t_{n-1/2} for central differences (staggered velocity), t_n for Newmark.
    pub time_s: f64,
    /// 1/2 v^T M v.
    pub kinetic_j: f64,
    /// 1/2 u^T K u (central differences: 1/2 u_{n-1}^T K u_n), K of the unrelaxed stiffness.
    pub strain_j: f64,
    /// What the memory variables of viscoelastic materials add to the stored energy
    /// ([`super::Discretisation::memory_energy`]); 0 without losses.
    pub memory_j: f64,
    /// Work of sources, dashpots and contact so far.
    pub flows: Flows,
}

/// A time integrator over an explicit state, its workspace allocated once.
pub trait Stepper {
    /// Time step (s).
    fn dt_s(&self) -> f64;
    /// Computes the state at t_{n+1} from the state at t_n (step n); t_n stays readable
    /// through [`Stepper::fields`] until [`Stepper::commit`].
    fn advance(&mut self, step: usize) -> Result<()>;
    /// The fields at t_n after [`Stepper::advance`].
    fn fields(&self, step: usize) -> Fields<'_>;
    /// Makes t_{n+1} the current state.
    fn commit(&mut self);
    /// The energy of the current state (before step `step` advances), with the flows so far.
    fn energy(&mut self, step: usize) -> EnergySample;
}

/// Reads the state of a run as it goes. Every hook has a default that does nothing.
pub trait Observer {
    /// Step `step` is about to be taken: the stepper holds t_step (the energy ledger samples here).
    fn before_step(&mut self, step: usize, stepper: &mut dyn Stepper) -> Result<()> {
        let _ = (step, stepper);
        Ok(())
    }
    /// Step n was taken: the fields at t_n (receivers, crack faces, snapshots record here).
    fn after_step(&mut self, fields: &Fields<'_>) -> Result<()> {
        let _ = fields;
        Ok(())
    }
    /// The run ended after `steps` steps; the stepper holds t_steps.
    fn end(&mut self, steps: usize, stepper: &mut dyn Stepper) -> Result<()> {
        let _ = (steps, stepper);
        Ok(())
    }
}

/// Steps between two checks of the time limit and Ctrl-C ([`crate::budget::check`]).
const BUDGET_EVERY: usize = 256;

/// The time loop: `steps` steps of `stepper`, each observer called before and after every
/// step in the order given, progress reported every [`super::progress::REPORT_EVERY`] steps.
/// Stops at the first error (an observer's, the stepper's, or the time limit).
pub fn drive(
    stepper: &mut dyn Stepper,
    steps: usize,
    observers: &mut [&mut dyn Observer],
    progress: &mut dyn FnMut(usize),
) -> Result<()> {
    for step in 0..steps {
        if step % BUDGET_EVERY == 0 {
            crate::budget::check()?;
        }
        for o in observers.iter_mut() {
            o.before_step(step, stepper)?;
        }
        stepper.advance(step)?;
        let fields = stepper.fields(step);
        for o in observers.iter_mut() {
            o.after_step(&fields)?;
        }
        stepper.commit();
        if step % super::progress::REPORT_EVERY == 0 {
            progress(step);
        }
    }
    for o in observers.iter_mut() {
        o.end(steps, stepper)?;
    }
    Ok(())
}
