//! Newmark average acceleration (report eq 61, beta = 1/4, gamma = 1/2), unconditionally
//! stable. The effective matrix S = K + 4M/dt^2 + 2C/dt is factored once (sparse Cholesky,
//! faer); each step is one triangular solve pair:
//! S u_{n+1} = f_{n+1} + M (4/dt^2 u_n + 4/dt v_n + a_n) + C (2/dt u_n + v_n),
//! a_{n+1} = 4/dt^2 (u_{n+1} - u_n) - 4/dt v_n - a_n, v_{n+1} = v_n + dt/2 (a_n + a_{n+1}).
//! It conserves 1/2 v^T M v + 1/2 u^T K u exactly without damping and forces.
//!
//! Viscoelastic materials ([`NewmarkMemory`]) update their memory variables by the same
//! trapezoidal rule: S is factored with K_N = K_U + (the memory's change), the right-hand side
//! gains the history force G^T h_n, and the memory is updated once u_{n+1} is known; the
//! energy gains the memory's share and the ledger the dissipation
//! ([`crate::attenuation::memory`] derives both).

use super::ledger::Flows;
use super::stepper::{EnergySample, Fields, Stepper, Velocity};
use super::SampledSources;
use crate::error::{Error, Result};
use crate::fem::{assemble_consistent_mass, BlockCsr, Model};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use std::borrow::Cow;

/// The mass operator: lumped (diagonal) or consistent (sparse).
pub enum Mass<'a> {
    /// Diagonal mass per DOF.
    Lumped(&'a [f64]),
    /// The consistent mass matrix (T3).
    Consistent(BlockCsr),
}

impl Mass<'_> {
    fn mul(&self, x: &[f64], out: &mut [f64]) {
        match self {
            Mass::Lumped(m) => out
                .iter_mut()
                .zip(m.iter().zip(x))
                .for_each(|(o, (m, x))| *o = m * x),
            Mass::Consistent(m) => m.mul(x, out),
        }
    }

    fn for_each_entry(&self, mut f: impl FnMut(usize, usize, f64)) {
        match self {
            Mass::Lumped(m) => m.iter().enumerate().for_each(|(i, &v)| f(i, i, v)),
            Mass::Consistent(m) => m.for_each_entry(f),
        }
    }

    /// "lumped" or "consistent", for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Mass::Lumped(_) => "lumped",
            Mass::Consistent(_) => "consistent",
        }
    }
}

/// The memory variables of a viscoelastic body as Newmark advances them (the trapezoidal
/// update of [`crate::attenuation::memory`], at the run's step).
pub trait MemoryVariables {
    /// Zero memory, its strain that of u_0 = `u0`.
    fn start(&mut self, u0: &[f64]);
    /// Adds the history force G^T h_n, from the memory and the strain of u_n = `u`, to `rhs`.
    fn add_history_forces(&mut self, u: &[f64], rhs: &mut [f64]);
    /// Updates the memory to u_{n+1} = `u_next`.
    fn update(&mut self, u_next: &[f64]);
    /// The energy dissipated since the last call (J per m of thickness).
    fn take_loss(&mut self) -> f64;
    /// The memory's share of the energy at t_n, from u_n = `u`.
    fn energy(&mut self, u: &[f64]) -> f64;
}

/// A viscoelastic body's memory under Newmark: what it changes in the effective matrix,
/// K_N - K_U (assembled with C_N - C_U = -sum_l beta_l DC_l), and its variables.
pub struct NewmarkMemory<'a> {
    /// K_N - K_U, on the stiffness's pattern or within it.
    pub stiffness_change: BlockCsr,
    /// The memory variables.
    pub variables: Box<dyn MemoryVariables + 'a>,
}

/// What the Newmark scheme needs of a body M u'' + C u' + K u = f: the assembled stiffness,
/// the mass, the dashpots (diagonal C), the DOFs held at zero and the memory variables of
/// viscoelastic materials. Built from a T3 model
/// ([`NewmarkBody::t3`]) or from spectral elements and their assembled stiffness
/// ([`NewmarkBody::sem`]); a discretisation gives its own
/// ([`super::Discretisation::newmark_body`]).
pub struct NewmarkBody<'a> {
    /// The assembled stiffness K (the model's, or assembled for the run).
    pub stiffness: Cow<'a, BlockCsr>,
    /// The mass M.
    pub mass: Mass<'a>,
    /// (DOF, c) of every dashpot.
    pub dashpots: &'a [(usize, f64)],
    /// DOFs held at zero.
    pub fixed_dofs: &'a [usize],
    /// The memory variables, where a material relaxes (`stiffness` is then the unrelaxed K_U).
    pub memory: Option<NewmarkMemory<'a>>,
}

impl<'a> NewmarkBody<'a> {
    /// A T3 model with its lumped or (assembled here) consistent mass, and the memory
    /// variables of its viscoelastic triangles at step `dt`.
    pub fn t3(model: &'a Model, consistent_mass: bool, dt: f64) -> Result<Self> {
        let mass = if consistent_mass {
            Mass::Consistent(assemble_consistent_mass(&model.mesh, &model.materials)?)
        } else {
            Mass::Lumped(&model.lumped_mass)
        };
        Ok(NewmarkBody {
            stiffness: Cow::Borrowed(&model.stiffness),
            mass,
            dashpots: &model.dashpots,
            fixed_dofs: &model.fixed_dofs,
            memory: super::discretisation::t3_newmark_memory(model, dt)?,
        })
    }

    /// Number of DOFs.
    pub fn dofs(&self) -> usize {
        2 * self.stiffness.nodes()
    }

    /// Refuses a mass, a memory's stiffness change, a dashpot or a fixed DOF that does not fit
    /// the stiffness (the fields are public, so a body can be put together by hand).
    fn check(&self) -> Result<()> {
        let n = self.dofs();
        let mass_dofs = match &self.mass {
            Mass::Lumped(m) => m.len(),
            Mass::Consistent(m) => 2 * m.nodes(),
        };
        if mass_dofs != n {
            return Err(Error::invalid(
                "mass",
                format!("{mass_dofs} DOFs"),
                format!("needs the stiffness's {n}"),
            ));
        }
        if let Some(m) = &self.memory {
            let change = 2 * m.stiffness_change.nodes();
            if change != n {
                return Err(Error::invalid(
                    "memory.stiffness_change",
                    format!("{change} DOFs"),
                    format!("needs the stiffness's {n}"),
                ));
            }
        }
        let dofs = self.dashpots.iter().map(|d| ("dashpots", d.0));
        let fixed = self.fixed_dofs.iter().map(|&d| ("fixed_dofs", d));
        if let Some((field, d)) = dofs.chain(fixed).find(|&(_, d)| d >= n) {
            return Err(Error::invalid(field, d, format!("DOF must be < {n}")));
        }
        Ok(())
    }
}

/// A sparse Cholesky factor L L^T with its solve workspace allocated once, so that each
/// time step's solve allocates nothing.
struct Factor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    workspace: MemBuffer,
}

impl Factor {
    /// Solves A x = rhs in place.
    fn solve_in_place(&mut self, rhs: faer::MatMut<'_, f64>) {
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            faer::Conj::No,
            rhs,
            faer::Par::Seq,
            MemStack::new(&mut self.workspace),
        );
    }
}

fn not_positive_definite(e: impl std::fmt::Debug) -> Error {
    Error::invalid(
        "newmark matrix",
        format!("{e:?}"),
        "is not positive definite (is the model constrained?)",
    )
}

/// Factors sum_k scale_k A_k (+ diagonal extra) with fixed DOFs replaced by identity rows.
fn factor(
    n: usize,
    fixed: &[bool],
    fill: impl Fn(&mut dyn FnMut(usize, usize, f64)),
) -> Result<Factor> {
    let mut triplets = Vec::new();
    fill(&mut |i, j, v| {
        if !fixed[i] && !fixed[j] && v != 0.0 {
            triplets.push(Triplet::new(i, j, v));
        }
    });
    triplets.extend(
        (0..n)
            .filter(|&d| fixed[d])
            .map(|d| Triplet::new(d, d, 1.0)),
    );
    let s = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| Error::invalid("newmark matrix", format!("{e:?}"), "could not be built"))?;
    let symbolic = factorize_symbolic_cholesky(
        s.symbolic(),
        faer::Side::Lower,
        SymmetricOrdering::Amd,
        Default::default(),
    )
    .map_err(not_positive_definite)?;
    let mut values = vec![0.0; symbolic.len_val()];
    let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(faer::Par::Seq, Default::default());
    let mut buffer = MemBuffer::new(scratch);
    symbolic
        .factorize_numeric_llt(
            &mut values,
            s.as_ref(),
            faer::Side::Lower,
            Default::default(),
            faer::Par::Seq,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .map_err(not_positive_definite)?;
    let workspace = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, faer::Par::Seq));
    Ok(Factor {
        symbolic,
        values,
        workspace,
    })
}

/// Newmark average acceleration on an assembled body ([`NewmarkBody`]: T3 with lumped or
/// consistent mass, or spectral elements): the state (u, v, a), the factored effective matrix
/// and every buffer allocated once.
pub struct Newmark<'a> {
    stiffness: Cow<'a, BlockCsr>,
    mass: Mass<'a>,
    dashpots: &'a [(usize, f64)],
    memory: Option<Box<dyn MemoryVariables + 'a>>,
    effective: Factor,
    fixed: Vec<bool>,
    dt: f64,
    sources: SampledSources<'a>,
    u: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    u_next: Vec<f64>,
    v_next: Vec<f64>,
    /// Scratch of the right-hand side and of the energy sums.
    work: Vec<f64>,
    rhs: faer::Mat<f64>,
    flows: Flows,
}

impl<'a> Newmark<'a> {
    /// The scheme at step `dt` on `body`, from u_0 and v_0 (zero if `None`; fixed DOFs start
    /// at zero) and zero memory: factors S once and solves M a_0 = f_0 - K u_0 - C v_0.
    /// `sources` must hold one more sample than the run has steps (f_{n+1} enters step n).
    pub fn new(
        body: NewmarkBody<'a>,
        dt: f64,
        sources: SampledSources<'a>,
        initial_displacement: Option<&[f64]>,
        initial_velocity: Option<&[f64]>,
    ) -> Result<Self> {
        body.check()?;
        let n = body.dofs();
        let mut fixed = vec![false; n];
        for &d in body.fixed_dofs {
            fixed[d] = true;
        }
        let NewmarkBody {
            stiffness,
            mass,
            dashpots,
            memory,
            ..
        } = body;
        let (stiffness_change, mut memory) =
            memory.map(|m| (m.stiffness_change, m.variables)).unzip();
        let effective = factor(n, &fixed, |add| {
            stiffness.for_each_entry(&mut *add);
            if let Some(change) = &stiffness_change {
                change.for_each_entry(&mut *add);
            }
            mass.for_each_entry(|i, j, v| add(i, j, 4.0 / (dt * dt) * v));
            for &(d, c) in dashpots {
                add(d, d, 2.0 / dt * c);
            }
        })?;
        let start = |field: &str, x: Option<&[f64]>| {
            let mut x = x.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
            if x.len() != n {
                return Err(Error::invalid(
                    field,
                    format!("{} values", x.len()),
                    format!("needs {n}"),
                ));
            }
            for (d, &f) in fixed.iter().enumerate() {
                if f {
                    x[d] = 0.0;
                }
            }
            Ok(x)
        };
        let u = start("initial_displacement", initial_displacement)?;
        let v = start("initial_velocity", initial_velocity)?;
        if let Some(m) = &mut memory {
            m.start(&u);
        }
        let mut stepper = Newmark {
            stiffness,
            mass,
            dashpots,
            memory,
            effective,
            fixed,
            dt,
            sources,
            u,
            v,
            a: Vec::new(),
            u_next: vec![0.0; n],
            v_next: vec![0.0; n],
            work: vec![0.0; n],
            rhs: faer::Mat::<f64>::zeros(n, 1),
            flows: Flows::default(),
        };
        stepper.a = stepper.initial_acceleration()?;
        Ok(stepper)
    }

    /// a_0 = M^-1 (f_0 - K u_0 - C v_0) (with zero memory the stress is C_U eps_0).
    fn initial_acceleration(&mut self) -> Result<Vec<f64>> {
        let (n, work) = (self.u.len(), &mut self.work);
        self.stiffness.mul(&self.u, work);
        for &(d, c) in self.dashpots {
            work[d] += c * self.v[d];
        }
        work.iter_mut().for_each(|w| *w = -*w);
        self.sources.add_forces(0, work);
        let fixed = &self.fixed;
        Ok(match &self.mass {
            Mass::Lumped(m) => work
                .iter()
                .zip(m.iter())
                .enumerate()
                .map(|(d, (f, m))| if fixed[d] { 0.0 } else { f / m })
                .collect(),
            Mass::Consistent(m) => {
                let mut llt = factor(n, fixed, |add| m.for_each_entry(&mut *add))?;
                let col = self.rhs.col_as_slice_mut(0);
                for d in 0..n {
                    col[d] = if fixed[d] { 0.0 } else { work[d] };
                }
                llt.solve_in_place(self.rhs.as_mut());
                self.rhs.col_as_slice(0).to_vec()
            }
        })
    }
}

impl Stepper for Newmark<'_> {
    fn dt_s(&self) -> f64 {
        self.dt
    }

    /// S u_{n+1} = f_{n+1} + M (4/dt^2 u_n + 4/dt v_n + a_n) + C (2/dt u_n + v_n) (+ the
    /// history force), then a_{n+1}, v_{n+1} and the memory (module docs); the source work uses
    /// the mean force over the step.
    fn advance(&mut self, step: usize) -> Result<()> {
        let dt = self.dt;
        let (c1, c2) = (4.0 / (dt * dt), 4.0 / dt);
        let (u, v, a) = (&self.u, &self.v, &mut self.a);
        let u_next = &mut self.u_next;
        for d in 0..u.len() {
            u_next[d] = c1 * u[d] + c2 * v[d] + a[d];
        }
        self.mass.mul(u_next, &mut self.work);
        let col = self.rhs.col_as_slice_mut(0);
        col.copy_from_slice(&self.work);
        for &(d, c) in self.dashpots {
            col[d] += c * (2.0 / dt * u[d] + v[d]);
        }
        self.sources.add_forces(step + 1, col);
        if let Some(m) = &mut self.memory {
            m.add_history_forces(u, col);
        }
        for (d, &f) in self.fixed.iter().enumerate() {
            if f {
                col[d] = 0.0;
            }
        }
        self.effective.solve_in_place(self.rhs.as_mut());
        u_next.copy_from_slice(self.rhs.col_as_slice(0));
        for (weights, values) in self.sources.iter() {
            let f = 0.5 * (values[step] + values[step + 1]);
            self.flows.source_work += f * weights
                .iter()
                .map(|&(d, w)| w * (u_next[d] - u[d]))
                .sum::<f64>();
        }
        let v_next = &mut self.v_next;
        for d in 0..u.len() {
            let a_next = c1 * (u_next[d] - u[d]) - c2 * v[d] - a[d];
            v_next[d] = v[d] + 0.5 * dt * (a[d] + a_next);
            a[d] = a_next;
        }
        for &(d, c) in self.dashpots {
            self.flows.dashpot_loss += c * (u_next[d] - u[d]) * 0.5 * (v[d] + v_next[d]);
        }
        if let Some(m) = &mut self.memory {
            m.update(u_next);
            self.flows.viscous_loss += m.take_loss();
        }
        Ok(())
    }

    fn fields(&self, step: usize) -> Fields<'_> {
        Fields {
            step,
            dt_s: self.dt,
            displacement: &self.u,
            velocity: Velocity::Nodal(&self.v),
        }
    }

    fn commit(&mut self) {
        std::mem::swap(&mut self.v, &mut self.v_next);
        std::mem::swap(&mut self.u, &mut self.u_next);
    }

    /// 1/2 v^T M v + 1/2 u^T K u at t_n, which the scheme conserves without damping and forces,
    /// and the memory's share.
    fn energy(&mut self, step: usize) -> EnergySample {
        let (u, v, work) = (&self.u, &self.v, &mut self.work);
        self.mass.mul(v, work);
        let kinetic = 0.5 * v.iter().zip(work.iter()).map(|(a, b)| a * b).sum::<f64>();
        self.stiffness.mul(u, work);
        let strain = 0.5 * u.iter().zip(work.iter()).map(|(a, b)| a * b).sum::<f64>();
        EnergySample {
            time_s: step as f64 * self.dt,
            kinetic_j: kinetic,
            strain_j: strain,
            memory_j: self.memory.as_mut().map_or(0.0, |m| m.energy(&self.u)),
            flows: self.flows,
        }
    }
}
