//! The contact law as the steppers see it: a type parameter, so a scene without a contacting
//! crack runs a loop compiled without contact ([`NoContact`]), and the crack's solver
//! ([`ContactSolver`]) corrects each predictor and books the work of its forces.

use super::Flows;
use crate::contact::{ContactReport, ContactSeries, ContactSolver};
use crate::error::Result;

/// The contact law a stepper applies to its predictor.
pub trait ContactLaw {
    /// Sets the stick points from the initial displacement (start of a run).
    fn start(&mut self, u: &[f64]);
    /// Corrects the predictor `u_next` and adds the work of the contact forces over the step,
    /// F (u_{n+1} - u_{n-1}) / 2, to `flows`.
    fn correct(&mut self, u_prev: &[f64], u_next: &mut [f64], flows: &mut Flows) -> Result<()>;
    /// The diagnostics of a run of `steps` steps of `dt_s`, if there was contact.
    fn finish(self, steps: usize, dt_s: f64) -> Option<(ContactReport, ContactSeries)>;
}

/// No crack, or an open one: nothing to correct.
pub struct NoContact;

impl ContactLaw for NoContact {
    #[inline(always)]
    fn start(&mut self, _: &[f64]) {}
    #[inline(always)]
    fn correct(&mut self, _: &[f64], _: &mut [f64], _: &mut Flows) -> Result<()> {
        Ok(())
    }
    fn finish(self, _: usize, _: f64) -> Option<(ContactReport, ContactSeries)> {
        None
    }
}

impl ContactLaw for ContactSolver {
    fn start(&mut self, u: &[f64]) {
        self.reset_stick_points(u);
    }
    fn correct(&mut self, u_prev: &[f64], u_next: &mut [f64], flows: &mut Flows) -> Result<()> {
        self.apply(u_next)?;
        self.for_each_force(|d, f| {
            let work = 0.5 * f * (u_next[d] - u_prev[d]);
            if d % 2 == 1 {
                flows.contact_normal_work += work;
            } else {
                flows.contact_tangential_work += work;
            }
        });
        Ok(())
    }
    fn finish(self, steps: usize, dt_s: f64) -> Option<(ContactReport, ContactSeries)> {
        Some(ContactSolver::finish(self, steps, dt_s))
    }
}
