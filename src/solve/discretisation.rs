//! What a time stepper needs of a space discretisation: a diagonal mass, the constrained DOFs,
//! the Lysmer-Kuhlemeyer dashpots, periodic ties, the stiffness applied to a vector, and the
//! crack the contact law acts on (with the nodes' x for its traces). The
//! steppers are generic over it, so linear triangles ([`Fem`]) and spectral elements
//! ([`crate::sem::SemModel`], which implements it beside its model) run through the same loop.

use super::newmark::{MemoryVariables, NewmarkMemory};
use super::NewmarkBody;
use crate::attenuation::memory::newmark_stiffness_change;
use crate::error::{Error, Result};
use crate::fem::memory::T3Memory;
use crate::fem::{Model, StiffnessOperator};
use crate::material::Material;
use crate::mesh::Crack;
use rayon::prelude::*;
use std::sync::OnceLock;

/// A symmetric 2x2 block on one node's (x, y) DOFs.
pub type NodeBlock = [[f64; 2]; 2];

/// A semi-discrete elastic body M u'' + C u' + K u = f with diagonal M, and C diagonal but
/// for 2x2 blocks on single nodes.
pub trait Discretisation: Sync {
    /// Scratch the stiffness product needs, allocated once per run.
    type Workspace: Send;

    /// Diagonal (lumped) mass per DOF (kg per m of thickness).
    fn lumped_mass(&self) -> &[f64];
    /// DOFs held at zero.
    fn fixed_dofs(&self) -> &[usize];
    /// (DOF, damping coefficient c) of every dashpot (N s/m per m of thickness).
    fn dashpots(&self) -> &[(usize, f64)];
    /// (node, C) of every coupled dashpot: a symmetric 2x2 block acting on the velocity of
    /// the node's (x, y) DOFs, traction -C v (N s/m per m of thickness), as an absorbing
    /// line at an angle to the axes has; none by default. A node has at most one.
    fn coupled_dashpots(&self) -> &[(usize, NodeBlock)] {
        &[]
    }
    /// (left DOF, right DOF) pairs of periodic edges, which move as one.
    fn periodic_ties(&self) -> &[(usize, usize)];
    /// The scratch of [`Discretisation::stiffness_times`].
    fn workspace(&self) -> Self::Workspace;
    /// `out = K u`.
    fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut Self::Workspace);

    /// x of a node (m), for the crack traces.
    fn node_x(&self, node: usize) -> f64;

    /// The crack whose node pairs the contact law acts on, if any (none by default).
    fn crack(&self) -> Option<&Crack> {
        None
    }

    /// Checks the body's own data before a run (DOF indices in range), naming the first
    /// field that is wrong; nothing to check by default.
    fn check(&self) -> Result<()> {
        Ok(())
    }

    /// Number of DOFs.
    fn dofs(&self) -> usize {
        self.lumped_mass().len()
    }

    /// The assembled body Newmark's implicit step factors at step `dt` (its stiffness, mass,
    /// dashpots, fixed DOFs and the memory of viscoelastic materials), with the consistent
    /// mass when `consistent_mass` (an error naming
    /// `integrator.consistent_mass` where the discretisation has none). By default an error
    /// naming `integrator`: a discretisation that only applies K u has no matrix to factor.
    fn newmark_body(&self, _consistent_mass: bool, _dt: f64) -> Result<NewmarkBody<'_>> {
        Err(Error::invalid(
            "integrator",
            "newmark",
            "this discretisation applies its stiffness without assembling it: run it with \
             the explicit integrator",
        ))
    }

    /// The shortest relaxation time of the body's viscoelastic materials (s), `None` where
    /// every material is elastic (the default): the step must follow it
    /// ([`crate::attenuation::check_step`]).
    fn shortest_relaxation_s(&self) -> Option<f64> {
        None
    }

    /// Starts the memory variables of viscoelastic materials for a central-difference run at
    /// step `dt` from u_{-1} = `u_prev` (eps_{-1} from it, e_{l,-1} = 0); from then on
    /// [`Discretisation::explicit_update`] updates them and adds their stress. Nothing to do
    /// for an elastic body (the default).
    fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut Self::Workspace) {
        let _ = (dt, u_prev, work);
    }

    /// The energy the relaxation dissipated in the updates since the last call (J per m of
    /// thickness); 0 for an elastic body (the default).
    fn take_viscous_loss(&self, work: &mut Self::Workspace) -> f64 {
        let _ = work;
        0.0
    }

    /// What the memory variables add to the stored energy at t_{n-1/2}, from u_n = `u` and the
    /// memory after step n - 1 (left unchanged; `crate::sem`'s memory module derives it);
    /// 0 for an elastic body (the default).
    fn memory_energy(&self, u: &[f64], work: &mut Self::Workspace) -> f64 {
        let _ = (u, work);
        0.0
    }

    /// The central-difference predictor u_next = 2 u - u_prev - a .* (K u) (report eq 69 with
    /// a = dt^2 / m). A discretisation may fuse it into its stiffness kernel (one pass over
    /// memory); the default forms K u in `u_next` and combines in place.
    fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut Self::Workspace,
    ) {
        self.stiffness_times(u, u_next, work);
        u_next
            .par_chunks_mut(UPDATE_CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let r = c * UPDATE_CHUNK..c * UPDATE_CHUNK + chunk.len();
                for (((next, &ai), &pi), &ui) in chunk
                    .iter_mut()
                    .zip(&a[r.clone()])
                    .zip(&u_prev[r.clone()])
                    .zip(&u[r])
                {
                    *next = 2.0 * ui - pi - ai * *next;
                }
            });
    }
}

/// DOFs per parallel task of the default predictor.
const UPDATE_CHUNK: usize = 8192;

/// Linear triangles with lumped mass: the [`Model`] and its stiffness operator (matrix-free
/// stencils on structured meshes, the assembled K elsewhere), built when a run first applies
/// K, so that a Newmark run, which factors the assembled K, builds no stencils.
pub struct Fem<'a> {
    /// The assembled model.
    pub model: &'a Model,
    op: OnceLock<StiffnessOperator<'a>>,
}

impl<'a> Fem<'a> {
    /// The model; its stiffness operator is built when a run first applies K.
    pub fn new(model: &'a Model) -> Fem<'a> {
        Fem {
            model,
            op: OnceLock::new(),
        }
    }

    /// The stiffness operator, built on first use.
    fn op(&self) -> &StiffnessOperator<'a> {
        self.op.get_or_init(|| StiffnessOperator::new(self.model))
    }
}

/// The scratch of a T3 run: the memory variables of its viscoelastic triangles, once a time
/// step starts them ([`Discretisation::start_memory`]).
#[derive(Debug, Default)]
pub struct FemWorkspace {
    memory: Option<T3Memory>,
}

impl Discretisation for Fem<'_> {
    type Workspace = FemWorkspace;

    fn lumped_mass(&self) -> &[f64] {
        &self.model.lumped_mass
    }
    fn fixed_dofs(&self) -> &[usize] {
        &self.model.fixed_dofs
    }
    fn dashpots(&self) -> &[(usize, f64)] {
        &self.model.dashpots
    }
    fn periodic_ties(&self) -> &[(usize, usize)] {
        &self.model.periodic
    }
    fn workspace(&self) -> FemWorkspace {
        FemWorkspace::default()
    }
    fn node_x(&self, node: usize) -> f64 {
        self.model.mesh.nodes[node][0]
    }
    fn crack(&self) -> Option<&Crack> {
        self.model.crack.as_ref()
    }
    /// The model's assembled stiffness, with its lumped or (assembled here) consistent mass and
    /// its viscoelastic triangles' memory.
    fn newmark_body(&self, consistent_mass: bool, dt: f64) -> Result<NewmarkBody<'_>> {
        NewmarkBody::t3(self.model, consistent_mass, dt)
    }
    fn stiffness_times(&self, u: &[f64], out: &mut [f64], _: &mut FemWorkspace) {
        self.op().mul(u, out);
    }
    /// The fused kernel: K u and the update in one pass ([`StiffnessOperator::explicit_update`]),
    /// then the viscoelastic triangles' memory stress ([`T3Memory::relax`]).
    fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut FemWorkspace,
    ) {
        self.op().explicit_update(a, u_prev, u, u_next);
        if let Some(memory) = &mut work.memory {
            memory.relax(a, u, u_next);
        }
    }
    fn shortest_relaxation_s(&self) -> Option<f64> {
        crate::material::shortest_relaxation_s(&self.model.materials)
    }
    fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut FemWorkspace) {
        work.memory = T3Memory::new(self.model, dt);
        if let Some(m) = &mut work.memory {
            m.start(u_prev);
        }
    }
    fn take_viscous_loss(&self, work: &mut FemWorkspace) -> f64 {
        work.memory.as_mut().map_or(0.0, T3Memory::take_loss)
    }
    fn memory_energy(&self, u: &[f64], work: &mut FemWorkspace) -> f64 {
        work.memory.as_mut().map_or(0.0, |m| m.energy(u))
    }
}

/// Newmark on a T3 model ([`super::newmark`]): what the memory of its viscoelastic triangles
/// changes in the effective matrix at step `dt` (the elements assembled with C_N - C_U), and
/// the memory; `None` where every material is elastic.
pub(super) fn t3_newmark_memory(model: &Model, dt: f64) -> Result<Option<NewmarkMemory<'static>>> {
    let Some(memory) = T3Memory::new(model, dt) else {
        return Ok(None);
    };
    let change: Vec<Material> = (model.materials.iter())
        .map(|m| Material {
            stiffness_pa: newmark_stiffness_change(m, dt),
            relaxation: None,
            ..m.clone()
        })
        .collect();
    Ok(Some(NewmarkMemory {
        stiffness_change: crate::fem::assemble_stiffness(&model.mesh, &change)?,
        variables: Box::new(memory),
    }))
}

impl MemoryVariables for T3Memory {
    fn start(&mut self, u0: &[f64]) {
        T3Memory::start(self, u0);
    }
    fn add_history_forces(&mut self, u: &[f64], rhs: &mut [f64]) {
        T3Memory::add_history_forces(self, u, rhs);
    }
    fn update(&mut self, u_next: &[f64]) {
        T3Memory::update(self, u_next);
    }
    fn take_loss(&mut self) -> f64 {
        T3Memory::take_loss(self)
    }
    fn energy(&mut self, u: &[f64]) -> f64 {
        self.stored_energy(u)
    }
}
