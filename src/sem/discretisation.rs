//! Spectral elements as the time steppers see them: the [`Discretisation`] the explicit steps
//! run on (the fused kernel included) and the [`NewmarkBody`] of the implicit step.

use super::{SemModel, SemWorkspace};
use crate::error::{Error, Result};
use crate::fem::BlockCsr;
use crate::mesh::Crack;
use crate::solve::newmark::Mass;
use crate::solve::{Discretisation, NewmarkBody};

impl Discretisation for SemModel {
    type Workspace = SemWorkspace;

    fn lumped_mass(&self) -> &[f64] {
        &self.lumped_mass
    }
    fn fixed_dofs(&self) -> &[usize] {
        &self.fixed_dofs
    }
    fn dashpots(&self) -> &[(usize, f64)] {
        &self.dashpots
    }
    fn periodic_ties(&self) -> &[(usize, usize)] {
        &[]
    }
    fn workspace(&self) -> SemWorkspace {
        SemModel::workspace(self)
    }
    fn node_x(&self, node: usize) -> f64 {
        self.node_position(node)[0]
    }
    fn crack(&self) -> Option<&Crack> {
        SemModel::crack(self)
    }
    fn check(&self) -> Result<()> {
        SemModel::check(self)
    }
    fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut SemWorkspace) {
        SemModel::stiffness_times(self, u, out, work);
    }
    /// The fused kernel: each node line of K u finished as it is gathered
    /// ([`SemModel::explicit_update`]).
    fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut SemWorkspace,
    ) {
        SemModel::explicit_update(self, a, u_prev, u, u_next, work);
    }
}

impl<'a> NewmarkBody<'a> {
    /// Spectral elements with their diagonal GLL mass, their dashpots and fixed DOFs, and
    /// `stiffness` from [`SemModel::assemble_stiffness`] (refused when its size differs).
    pub fn sem(model: &'a SemModel, stiffness: &'a BlockCsr) -> Result<Self> {
        if 2 * stiffness.nodes() != model.dofs() {
            return Err(Error::invalid(
                "stiffness",
                format!("{} DOFs", 2 * stiffness.nodes()),
                format!("is not this model's ({} DOFs)", model.dofs()),
            ));
        }
        Ok(NewmarkBody {
            stiffness,
            mass: Mass::Lumped(&model.lumped_mass),
            dashpots: &model.dashpots,
            fixed_dofs: &model.fixed_dofs,
        })
    }
}
