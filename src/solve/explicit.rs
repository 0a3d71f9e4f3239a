//! Central difference with lumped mass and diagonal damping (report eqs 65-69, with
//! A = K - 2M/dt^2; the report's eq 67 misprints dt^2 as dt):
//! (M/dt^2 + C/2dt) u_{n+1} = f_n - K u_n + 2M/dt^2 u_n - (M/dt^2 - C/2dt) u_{n-1}.
//!
//! The step is split so that it costs O(DOFs) only once: a fused parallel kernel computes
//! the undamped, unforced update u_{n+1} = 2 u_n - u_{n-1} - (dt^2/m)(K u_n) for every DOF,
//! then sparse corrections touch only what the scene has: source DOFs, periodic ties (each
//! tied pair takes the mass-weighted mean of its two updates, the update of one DOF of mass
//! m_l + m_r under the force f_l + f_r), dashpot DOFs and coupled dashpots' nodes, crack
//! pairs. Fixed DOFs have dt^2/m = 0 and so never move. Nothing is allocated per step.
//! The kernel is the discretisation's [`Discretisation::explicit_update`] (for T3: matrix-free
//! stencils on structured meshes, the assembled K elsewhere; for spectral elements: sum
//! factorisation); the contact law is a type parameter ([`ContactLaw`]).

use super::discretisation::{Discretisation, NodeBlock};
use super::ledger::Flows;
use super::stepper::{EnergySample, Fields, Stepper, Velocity};
use super::ContactLaw;
use super::SampledSources;
use crate::error::Result;
use rayon::prelude::*;

/// Per-DOF constants of the scheme.
pub struct Coefficients {
    /// dt^2 / m, zero on fixed DOFs.
    pub(super) a: Vec<f64>,
    /// (DOF, c, r = c dt / 2m) for every dashpot.
    pub(super) dashpots: Vec<(usize, f64, f64)>,
    /// Every coupled dashpot's node and constants.
    coupled: Vec<CoupledDashpot>,
    /// Compliance of the corrected update, dt^2 / (m (1 + r)): how far a unit force moves a
    /// DOF in one step (the contact solvers' D; where a coupled dashpot's R is diagonal,
    /// r = R_ii; a crack pair may not sit where R couples x and y, see
    /// [`crate::sem::unstructured::UnstructuredSem::check`]).
    pub compliance: Vec<f64>,
    /// (left DOF, right DOF, m_l / (m_l + m_r)) for every periodic tie.
    ties: Vec<(usize, usize, f64)>,
}

impl Coefficients {
    /// The constants of `body` at step `dt`.
    pub fn new(body: &impl Discretisation, dt: f64) -> Coefficients {
        let m = body.lumped_mass();
        let mut a: Vec<f64> = m.iter().map(|m| dt * dt / m).collect();
        for &d in body.fixed_dofs() {
            a[d] = 0.0;
        }
        let mut dashpots: Vec<(usize, f64, f64)> = body
            .dashpots()
            .iter()
            .map(|&(d, c)| (d, c, c * dt / (2.0 * m[d])))
            .collect();
        let ties: Vec<(usize, usize, f64)> = body
            .periodic_ties()
            .iter()
            .map(|&(l, r)| (l, r, m[l] / (m[l] + m[r])))
            .collect();
        if !ties.is_empty() {
            dashpots = tied_dashpots(&dashpots, &ties, m, dt);
        }
        let mut compliance = a.clone();
        for &(d, _, r) in &dashpots {
            compliance[d] /= 1.0 + r;
        }
        let coupled = coupled_dashpots(body, &a, &ties, dt);
        for k in coupled
            .iter()
            .filter(|k| k.r[0][1] == 0.0 && k.r[1][0] == 0.0)
        {
            for i in 0..2 {
                compliance[2 * k.node + i] /= 1.0 + k.r[i][i];
            }
        }
        Coefficients {
            a,
            dashpots,
            coupled,
            compliance,
            ties,
        }
    }
}

/// A coupled dashpot at step dt: its node, its block C (the rows and columns of fixed DOFs
/// zeroed: they do not move) and (I + R)^-1 with R = (dt / 2) M^-1 C.
#[derive(Clone, Copy, Debug)]
struct CoupledDashpot {
    node: usize,
    c: NodeBlock,
    r: NodeBlock,
    inverse: NodeBlock,
}

/// The coupled dashpots of `body` at step `dt` (`a` = dt^2 / m, zero on fixed DOFs). A node
/// tied to another moves with it as one node of mass M_l + M_r and damping C_l + C_r, so
/// both get R = (dt / 2) (M_l + M_r)^-1 (C_l + C_r), each its own C for the absorbed energy
/// (a tied node without a dashpot gets C = 0 and the shared R).
fn coupled_dashpots(
    body: &impl Discretisation,
    a: &[f64],
    ties: &[(usize, usize, f64)],
    dt: f64,
) -> Vec<CoupledDashpot> {
    let m = body.lumped_mass();
    let partner: std::collections::HashMap<usize, usize> = ties
        .iter()
        .filter(|t| t.0 % 2 == 0)
        .flat_map(|&(l, r, _)| [(l / 2, r / 2), (r / 2, l / 2)])
        .collect();
    let mut c_of: std::collections::BTreeMap<usize, NodeBlock> = Default::default();
    for &(node, c) in body.coupled_dashpots() {
        let free = [a[2 * node] != 0.0, a[2 * node + 1] != 0.0];
        let held = std::array::from_fn(|i| {
            std::array::from_fn(|j| if free[i] && free[j] { c[i][j] } else { 0.0 })
        });
        c_of.insert(node, held);
        if let Some(&p) = partner.get(&node) {
            c_of.entry(p).or_insert([[0.0; 2]; 2]);
        }
    }
    c_of.iter()
        .map(|(&node, &c)| {
            let (shared, mass): (NodeBlock, [f64; 2]) = match partner.get(&node) {
                Some(&p) => (
                    add(c, c_of[&p]),
                    [0, 1].map(|i| m[2 * node + i] + m[2 * p + i]),
                ),
                None => (c, [m[2 * node], m[2 * node + 1]]),
            };
            let r: NodeBlock = std::array::from_fn(|i| shared[i].map(|v| 0.5 * dt * v / mass[i]));
            let det = (1.0 + r[0][0]) * (1.0 + r[1][1]) - r[0][1] * r[1][0];
            let inverse = [
                [(1.0 + r[1][1]) / det, -r[0][1] / det],
                [-r[1][0] / det, (1.0 + r[0][0]) / det],
            ];
            CoupledDashpot {
                node,
                c,
                r,
                inverse,
            }
        })
        .collect()
}

fn add(x: NodeBlock, y: NodeBlock) -> NodeBlock {
    std::array::from_fn(|i| std::array::from_fn(|j| x[i][j] + y[i][j]))
}

impl Coefficients {
    /// The dashpots' implicit correction of an explicit update `next`: the damping term
    /// C (u_{n+1} - u_{n-1}) / 2dt solved DOF by DOF, and node by node for the coupled ones,
    /// (I + R) u_{n+1} = next + R u_{n-1}.
    pub(super) fn damp(&self, u_prev: &[f64], u: &[f64], next: &mut [f64]) {
        for &(d, _, r) in &self.dashpots {
            let q = next[d] - 2.0 * u[d] + u_prev[d];
            next[d] = (q + 2.0 * u[d] - (1.0 - r) * u_prev[d]) / (1.0 + r);
        }
        for k in &self.coupled {
            let dofs = [2 * k.node, 2 * k.node + 1];
            let old = dofs.map(|d| u_prev[d]);
            let rhs = [0, 1].map(|i| next[dofs[i]] + k.r[i][0] * old[0] + k.r[i][1] * old[1]);
            for i in 0..2 {
                next[dofs[i]] = k.inverse[i][0] * rhs[0] + k.inverse[i][1] * rhs[1];
            }
        }
    }

    /// The energy the dashpots absorbed over the step, (u_{n+1} - u_{n-1})^T C
    /// (u_{n+1} - u_{n-1}) / 4dt, from the final u_{n+1} = `next`: after the contact
    /// correction, which moves a damped DOF by its damped compliance.
    pub(super) fn dashpot_loss(&self, u_prev: &[f64], next: &[f64], dt: f64) -> f64 {
        let mut loss = 0.0;
        for &(d, c, _) in &self.dashpots {
            let du = next[d] - u_prev[d];
            loss += c * du * du / (4.0 * dt);
        }
        for k in &self.coupled {
            let du = [0, 1].map(|i| next[2 * k.node + i] - u_prev[2 * k.node + i]);
            for i in 0..2 {
                loss += du[i] * (k.c[i][0] * du[0] + k.c[i][1] * du[1]) / (4.0 * dt);
            }
        }
        loss
    }
}

/// Twice the kinetic and strain energies at t_{n-1/2}: sum m v^2 with v = (u_n - u_{n-1})/dt,
/// and sum `strain(k, buffer[k])` over the DOFs. Summed in parallel over fixed chunks of DOFs,
/// each chunk's two sums left in its first two entries of `buffer`, then added in order: the
/// result does not depend on the thread count.
pub(super) fn energy_sums(
    buffer: &mut [f64],
    (u_prev, u, mass): (&[f64], &[f64], &[f64]),
    dt: f64,
    strain: impl Fn(usize, f64) -> f64 + Sync,
) -> (f64, f64) {
    buffer
        .par_chunks_mut(ENERGY_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let start = c * ENERGY_CHUNK;
            let (mut kinetic, mut sum) = (0.0, 0.0);
            for (i, &b) in chunk.iter().enumerate() {
                let k = start + i;
                let v = (u[k] - u_prev[k]) / dt;
                kinetic += mass[k] * v * v;
                sum += strain(k, b);
            }
            // DOFs come in pairs and the chunk size is even: every chunk has 2+ entries.
            chunk[0] = kinetic;
            chunk[1] = sum;
        });
    buffer
        .chunks(ENERGY_CHUNK)
        .fold((0.0, 0.0), |(k, s), chunk| (k + chunk[0], s + chunk[1]))
}

/// The dashpots of a periodic model: a tied DOF pair moves as one DOF of mass m_l + m_r and
/// damping c_l + c_r, so both members get r = (c_l + c_r) dt / (2 (m_l + m_r)) (each keeps
/// its own c for the dissipated energy).
fn tied_dashpots(
    dashpots: &[(usize, f64, f64)],
    ties: &[(usize, usize, f64)],
    m: &[f64],
    dt: f64,
) -> Vec<(usize, f64, f64)> {
    let mut by_dof: std::collections::BTreeMap<usize, (f64, f64)> =
        dashpots.iter().map(|&(d, c, r)| (d, (c, r))).collect();
    for &(l, r, _) in ties {
        let c = |d: usize| by_dof.get(&d).map_or(0.0, |e| e.0);
        let (cl, cr) = (c(l), c(r));
        if cl + cr > 0.0 {
            let shared = (cl + cr) * dt / (2.0 * (m[l] + m[r]));
            by_dof.insert(l, (cl, shared));
            by_dof.insert(r, (cr, shared));
        }
    }
    by_dof.into_iter().map(|(d, (c, r))| (d, c, r)).collect()
}

/// DOFs per parallel task of the energy sums.
const ENERGY_CHUNK: usize = 8192;

/// Central differences with lumped mass over any [`Discretisation`], with contact law `C`:
/// the state (u_{n-1}, u_n, u_{n+1}) and every buffer are allocated once.
pub struct CentralDifference<'a, D: Discretisation, C: ContactLaw> {
    body: &'a D,
    work: D::Workspace,
    coef: Coefficients,
    dt: f64,
    sources: SampledSources<'a>,
    /// The contact law (read its diagnostics with [`CentralDifference::finish`]).
    contact: C,
    u_prev: Vec<f64>,
    u: Vec<f64>,
    u_next: Vec<f64>,
    /// Scratch of the energy sums.
    ku: Vec<f64>,
    flows: Flows,
}

impl<'a, D: Discretisation, C: ContactLaw> CentralDifference<'a, D, C> {
    /// The scheme at step `dt` from u_0 (zero if `None`) and v_0 (zero if `None`): u_{-1} =
    /// u_0 - dt v_0, so the staggered velocity v_{-1/2} equals v_0. Fixed DOFs start at zero.
    pub fn new(
        body: &'a D,
        coef: Coefficients,
        dt: f64,
        sources: SampledSources<'a>,
        mut contact: C,
        initial_displacement: Option<&[f64]>,
        initial_velocity: Option<&[f64]>,
    ) -> Self {
        let n = body.dofs();
        let mut u = initial_displacement.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        for &d in body.fixed_dofs() {
            u[d] = 0.0;
        }
        let mut u_prev = u.clone();
        if let Some(v0) = initial_velocity {
            for (d, p) in u_prev.iter_mut().enumerate() {
                if coef.a[d] != 0.0 {
                    *p -= dt * v0[d];
                }
            }
        }
        contact.start(&u);
        let mut work = body.workspace();
        body.start_memory(dt, &u_prev, &mut work);
        CentralDifference {
            body,
            work,
            coef,
            dt,
            sources,
            contact,
            u_prev,
            u,
            u_next: vec![0.0; n],
            ku: vec![0.0; n],
            flows: Flows::default(),
        }
    }

    /// The current displacement u_n (after [`Stepper::commit`]: the newest state).
    pub fn displacement(&self) -> &[f64] {
        &self.u
    }

    /// The contact law, for its diagnostics once the run is over.
    pub fn finish(self) -> C {
        self.contact
    }

    /// Adds the work of each source over step n, f_n w (u_{n+1} - u_{n-1}) / 2, to the flows.
    fn add_source_work(&mut self, step: usize) {
        for (weights, values) in self.sources.iter() {
            self.flows.source_work += 0.5
                * values[step]
                * weights
                    .iter()
                    .map(|&(d, w)| w * (self.u_next[d] - self.u_prev[d]))
                    .sum::<f64>();
        }
    }
}

impl<D: Discretisation, C: ContactLaw> Stepper for CentralDifference<'_, D, C> {
    fn dt_s(&self) -> f64 {
        self.dt
    }

    /// Predictor, sources, periodic ties, dashpots, contact correction (module docs).
    fn advance(&mut self, step: usize) -> Result<()> {
        let (a, u_prev, u) = (&self.coef.a, &self.u_prev, &self.u);
        let u_next = &mut self.u_next;
        self.body
            .explicit_update(a, u_prev, u, u_next, &mut self.work);
        self.flows.viscous_loss += self.body.take_viscous_loss(&mut self.work);
        for (weights, values) in self.sources.iter() {
            let f = values[step];
            if f != 0.0 {
                for &(d, w) in weights {
                    u_next[d] += a[d] * w * f;
                }
            }
        }
        for &(l, r, w) in &self.coef.ties {
            let tied = w * u_next[l] + (1.0 - w) * u_next[r];
            u_next[l] = tied;
            u_next[r] = tied;
        }
        self.coef.damp(u_prev, u, u_next);
        self.contact.correct(u_prev, u_next, &mut self.flows)?;
        self.flows.dashpot_loss += self.coef.dashpot_loss(u_prev, u_next, self.dt);
        self.add_source_work(step);
        Ok(())
    }

    fn fields(&self, step: usize) -> Fields<'_> {
        Fields {
            step,
            dt_s: self.dt,
            displacement: &self.u,
            velocity: Velocity::Central {
                previous: &self.u_prev,
                next: &self.u_next,
            },
        }
    }

    fn commit(&mut self) {
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.u_next);
    }

    /// Energy at t_{n-1/2}: kinetic 1/2 v^T M v with v = (u_n - u_{n-1})/dt, strain
    /// 1/2 u_{n-1}^T K u_n ([`energy_sums`], with K u_n as the buffer), and the memory
    /// variables' share ([`Discretisation::memory_energy`]).
    fn energy(&mut self, step: usize) -> EnergySample {
        let (dt, u_prev, u) = (self.dt, &self.u_prev, &self.u);
        let ku = &mut self.ku;
        self.body.stiffness_times(u, ku, &mut self.work);
        let state = (&u_prev[..], &u[..], self.body.lumped_mass());
        let (kinetic, strain) = energy_sums(ku, state, dt, |k, kuk| u_prev[k] * kuk);
        EnergySample {
            time_s: (step as f64 - 0.5) * dt,
            kinetic_j: 0.5 * kinetic,
            strain_j: 0.5 * strain,
            memory_j: self.body.memory_energy(u, &mut self.work),
            flows: self.flows,
        }
    }
}
