//! Spectral elements as the time steppers see them: the [`Discretisation`] the explicit steps
//! run on (the fused kernel included) and the [`NewmarkBody`] of the implicit step.

use super::{SemModel, SemWorkspace};
use crate::error::{Error, Result};
use crate::fem::BlockCsr;
use crate::mesh::Crack;
use crate::solve::newmark::Mass;
use crate::solve::{Discretisation, NewmarkBody};
use std::borrow::Cow;

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
    fn shortest_relaxation_s(&self) -> Option<f64> {
        SemModel::shortest_relaxation_s(self)
    }
    fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut SemWorkspace) {
        SemModel::start_memory(self, dt, u_prev, work);
    }
    fn take_viscous_loss(&self, work: &mut SemWorkspace) -> f64 {
        SemModel::take_viscous_loss(self, work)
    }
    fn memory_energy(&self, u: &[f64], work: &mut SemWorkspace) -> f64 {
        SemModel::memory_energy(self, u, work)
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
    /// The GLL (diagonal) mass and the stiffness assembled for the run
    /// ([`SemModel::assemble_stiffness`]); a consistent mass is refused, naming the field.
    fn newmark_body(&self, consistent_mass: bool) -> Result<NewmarkBody<'_>> {
        if consistent_mass {
            return Err(Error::invalid(
                "integrator.consistent_mass",
                true,
                "spectral elements have the GLL (diagonal) mass only: set consistent_mass: false",
            ));
        }
        Ok(NewmarkBody::with_gll_mass(
            self,
            Cow::Owned(self.assemble_stiffness()),
        ))
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
        Ok(Self::with_gll_mass(model, Cow::Borrowed(stiffness)))
    }

    /// `model`'s GLL mass, dashpots and fixed DOFs with `stiffness` (of its size).
    fn with_gll_mass(model: &'a SemModel, stiffness: Cow<'a, BlockCsr>) -> Self {
        NewmarkBody {
            stiffness,
            mass: Mass::Lumped(&model.lumped_mass),
            dashpots: &model.dashpots,
            fixed_dofs: &model.fixed_dofs,
        }
    }
}
