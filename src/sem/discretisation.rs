//! Spectral elements as the time steppers see them: the [`Discretisation`] the explicit steps
//! run on (the fused kernel included) and the [`NewmarkBody`] of the implicit step, with the
//! memory of viscoelastic rows.

use super::{SemModel, SemWorkspace};
use crate::error::{Error, Result};
use crate::fem::BlockCsr;
use crate::mesh::Crack;
use crate::solve::newmark::{Mass, MemoryVariables, NewmarkMemory};
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
    /// The GLL (diagonal) mass, the stiffness assembled for the run
    /// ([`SemModel::assemble_stiffness`]) and the viscoelastic rows' memory at step `dt`; a
    /// consistent mass is refused, naming the field.
    fn newmark_body(&self, consistent_mass: bool, dt: f64) -> Result<NewmarkBody<'_>> {
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
            dt,
        ))
    }
}

/// The memory of a model's viscoelastic rows as Newmark advances it, with the workspace of
/// its row passes and the history force's buffer.
struct RowsMemory<'a> {
    model: &'a SemModel,
    dt: f64,
    work: SemWorkspace,
    force: Vec<f64>,
}

impl MemoryVariables for RowsMemory<'_> {
    fn start(&mut self, u0: &[f64]) {
        self.model.start_memory(self.dt, u0, &mut self.work);
    }
    fn add_history_forces(&mut self, u: &[f64], rhs: &mut [f64]) {
        (self.model).history_forces(u, &mut self.force, &mut self.work);
        rhs.iter_mut().zip(&self.force).for_each(|(r, f)| *r += f);
    }
    fn update(&mut self, u_next: &[f64]) {
        self.model.relax(u_next, &mut self.work);
    }
    fn take_loss(&mut self) -> f64 {
        self.model.take_viscous_loss(&mut self.work)
    }
    fn energy(&mut self, u: &[f64]) -> f64 {
        self.model.stored_energy(u, &mut self.work)
    }
}

impl<'a> NewmarkBody<'a> {
    /// Spectral elements with their diagonal GLL mass, their dashpots and fixed DOFs,
    /// `stiffness` from [`SemModel::assemble_stiffness`] (refused when its size differs), and
    /// the viscoelastic rows' memory at step `dt`.
    pub fn sem(model: &'a SemModel, stiffness: &'a BlockCsr, dt: f64) -> Result<Self> {
        if 2 * stiffness.nodes() != model.dofs() {
            return Err(Error::invalid(
                "stiffness",
                format!("{} DOFs", 2 * stiffness.nodes()),
                format!("is not this model's ({} DOFs)", model.dofs()),
            ));
        }
        Ok(Self::with_gll_mass(model, Cow::Borrowed(stiffness), dt))
    }

    /// `model`'s GLL mass, dashpots and fixed DOFs with `stiffness` (of its size), and its
    /// viscoelastic rows' memory at step `dt` (none where every row is elastic).
    fn with_gll_mass(model: &'a SemModel, stiffness: Cow<'a, BlockCsr>, dt: f64) -> Self {
        let memory = model.shortest_relaxation_s().map(|_| NewmarkMemory {
            stiffness_change: model.newmark_stiffness_change(dt),
            variables: Box::new(RowsMemory {
                model,
                dt,
                work: model.workspace(),
                force: vec![0.0; model.dofs()],
            }),
        });
        NewmarkBody {
            stiffness,
            mass: Mass::Lumped(&model.lumped_mass),
            dashpots: &model.dashpots,
            fixed_dofs: &model.fixed_dofs,
            memory,
        }
    }
}
