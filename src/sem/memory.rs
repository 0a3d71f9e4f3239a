//! Memory variables of viscoelastic element rows ([`crate::attenuation`]) at their GLL points,
//! and the point laws the row kernel is compiled with: [`Elastic`] (nothing beyond W C_U eps:
//! elastic rows run today's code), [`Viscous`] (the memory update and its stress, in the time
//! step), [`Start`] (the memory at the first step) and [`Probe`] (the ledger's memory energy,
//! read without changing the state).
//!
//! The update is the trapezoidal rule on tau_l e_l' + e_l = eps (bilinear, A-stable):
//!
//!   e_{l,n} = alpha_l e_{l,n-1} + beta_l (eps_{n-1} + eps_n),
//!   alpha_l = (2 tau_l - dt) / (2 tau_l + dt),  beta_l = dt / (2 tau_l + dt),
//!
//! i.e. tau_l (e_{l,n} - e_{l,n-1}) / dt = (a_{n-1} + a_n) / 2 with a = eps - e_l, the strain
//! of the mechanism's spring. With central differences it keeps an exact discrete energy
//! balance (docs/src/physics.md, "Losses"): at t_{n-1/2} the stored energy is the elastic
//! sample of C_U plus
//!
//!   MEM_{n-1/2} = sum_q W_q sum_l [ 1/2 a_n.DC_l a_{n-1} - 1/2 eps_n.DC_l eps_{n-1}
//!                                   + dt/(4 tau_l) a_{n-1}.DC_l (a_{n-1} + a_n) ],
//!
//! and the step n dissipates dt d_{n-1/2}, d = sum_q W_q sum_l (1/tau_l) abar.DC_l abar with
//! abar = (a_{n-1} + a_n) / 2 >= 0, so E_{n+1/2} - E_{n-1/2} + dt d_{n-1/2} is the work of the
//! external forces over the step, to round-off.

use super::{Lanes, LANES};
use crate::attenuation::Relaxation;

/// What the row kernel does at a GLL point beyond the elastic weighted stress W C_U eps.
pub(super) trait PointLaw {
    /// What the law reads and writes per element row.
    type State;
    /// Whether the kernel goes on to the nodal forces (laws that only read fields do not).
    const FORCES: bool = true;
    /// At point `q` of the row (point p of lane group g: q = g P + p, P points per element),
    /// of weight W (w_a w_b jx jy) and strain `eps` (xx, yy, engineering xy): adjusts the
    /// weighted stress `s`, W C_U eps on entry.
    fn at_point(
        state: &mut Self::State,
        q: usize,
        weight: &Lanes,
        eps: [&Lanes; 3],
        s: [&mut Lanes; 3],
    );
}

/// No memory: the stress stays W C_U eps.
pub(super) struct Elastic;

impl PointLaw for Elastic {
    type State = ();
    #[inline(always)]
    fn at_point(_: &mut (), _: usize, _: &Lanes, _: [&Lanes; 3], _: [&mut Lanes; 3]) {}
}

/// The memory update of a time step and its stress, s -= W sum_l DC_l e_{l,n}, with the
/// step's loss W sum_l (1/tau_l) abar.DC_l abar added up.
pub(super) struct Viscous;

/// The memory at the first step: eps_{-1} from u_{-1}, e_{l,-1} = 0.
pub(super) struct Start;

/// MEM_{n-1/2} (module docs) from u_n and the state after step n - 1, into
/// [`RowMemory::energy`]; the state is left as it was.
pub(super) struct Probe;

/// One relaxation mechanism's constants at the run's step.
#[derive(Clone, Debug)]
struct Mechanism {
    alpha: f64,
    beta: f64,
    inv_tau: f64,
    /// dt / (4 tau_l), of the memory energy.
    dt_over_4tau: f64,
    /// y_kl of the material's two parts.
    weights: [f64; 2],
}

/// The memory of one element row with a viscoelastic material: per GLL point of its elements
/// (by lane group) the previous strain and the mechanisms' e_l, the material's two parts, and
/// the loss and energy sums per lane.
#[derive(Clone, Debug)]
pub(super) struct RowMemory {
    /// eps_{n-1} at point q, `[q]`.
    eps_prev: Vec<[Lanes; 3]>,
    /// e_{l,n-1} at point q, `[q * L + l]`.
    e: Vec<[Lanes; 3]>,
    mechanisms: Vec<Mechanism>,
    /// The parts C_k of the unrelaxed stiffness (Pa).
    parts: [[[f64; 3]; 3]; 2],
    /// The step.
    dt: f64,
    /// d = sum of W sum_l (1/tau_l) abar.DC_l abar per lane, summed over the steps since it
    /// was taken (times dt: the energy dissipated).
    loss: Lanes,
    /// The memory energy of the last [`Probe`], per lane.
    energy: Lanes,
}

impl RowMemory {
    /// Zero memory for `points` GLL points (lane groups times points per element) of a
    /// material relaxing as `relaxation`, at step `dt`.
    pub(super) fn new(relaxation: &Relaxation, points: usize, dt: f64) -> RowMemory {
        let mechanisms: Vec<Mechanism> = relaxation
            .tau_s
            .iter()
            .enumerate()
            .map(|(l, &tau)| Mechanism {
                alpha: (2.0 * tau - dt) / (2.0 * tau + dt),
                beta: dt / (2.0 * tau + dt),
                inv_tau: 1.0 / tau,
                dt_over_4tau: dt / (4.0 * tau),
                weights: [
                    relaxation.parts[0].weights[l],
                    relaxation.parts[1].weights[l],
                ],
            })
            .collect();
        let zero = [[0.0; LANES]; 3];
        RowMemory {
            eps_prev: vec![zero; points],
            e: vec![zero; points * mechanisms.len()],
            mechanisms,
            parts: [
                relaxation.parts[0].stiffness_pa,
                relaxation.parts[1].stiffness_pa,
            ],
            dt,
            loss: [0.0; LANES],
            energy: [0.0; LANES],
        }
    }
}

impl PointLaw for Viscous {
    type State = RowMemory;
    #[inline(always)]
    fn at_point(m: &mut RowMemory, q: usize, w: &Lanes, eps: [&Lanes; 3], mut s: [&mut Lanes; 3]) {
        let eps = [*eps[0], *eps[1], *eps[2]];
        let old = m.eps_prev[q];
        let count = m.mechanisms.len();
        // sum_l y_kl e_{l,n} of each part
        let mut relaxed = [[[0.0; LANES]; 3]; 2];
        let mut loss = [0.0; LANES];
        for (mech, e) in m
            .mechanisms
            .iter()
            .zip(&mut m.e[q * count..(q + 1) * count])
        {
            let mut abar = [[0.0; LANES]; 3];
            for c in 0..3 {
                for i in 0..LANES {
                    let e_new = mech.alpha * e[c][i] + mech.beta * (old[c][i] + eps[c][i]);
                    abar[c][i] = 0.5 * ((old[c][i] - e[c][i]) + (eps[c][i] - e_new));
                    e[c][i] = e_new;
                    relaxed[0][c][i] += mech.weights[0] * e_new;
                    relaxed[1][c][i] += mech.weights[1] * e_new;
                }
            }
            for (part, y) in m.parts.iter().zip(mech.weights) {
                let form = form(part, &abar, &abar);
                for i in 0..LANES {
                    loss[i] += mech.inv_tau * y * form[i];
                }
            }
        }
        for (part, e) in m.parts.iter().zip(&relaxed) {
            for (row, s) in part.iter().zip(s.iter_mut()) {
                for i in 0..LANES {
                    s[i] -= w[i] * (row[0] * e[0][i] + row[1] * e[1][i] + row[2] * e[2][i]);
                }
            }
        }
        for i in 0..LANES {
            m.loss[i] += w[i] * loss[i];
        }
        m.eps_prev[q] = eps;
    }
}

impl PointLaw for Start {
    type State = RowMemory;
    const FORCES: bool = false;
    fn at_point(m: &mut RowMemory, q: usize, _: &Lanes, eps: [&Lanes; 3], _: [&mut Lanes; 3]) {
        m.eps_prev[q] = [*eps[0], *eps[1], *eps[2]];
    }
}

impl PointLaw for Probe {
    type State = RowMemory;
    const FORCES: bool = false;
    fn at_point(m: &mut RowMemory, q: usize, w: &Lanes, eps: [&Lanes; 3], _: [&mut Lanes; 3]) {
        let eps = [*eps[0], *eps[1], *eps[2]];
        let old = &m.eps_prev[q];
        let count = m.mechanisms.len();
        let mut energy = [0.0; LANES];
        for (mech, e) in m.mechanisms.iter().zip(&m.e[q * count..(q + 1) * count]) {
            let mut a_old = [[0.0; LANES]; 3];
            let mut a_new = [[0.0; LANES]; 3];
            let mut a_sum = [[0.0; LANES]; 3];
            for c in 0..3 {
                for i in 0..LANES {
                    let e_new = mech.alpha * e[c][i] + mech.beta * (old[c][i] + eps[c][i]);
                    a_old[c][i] = old[c][i] - e[c][i];
                    a_new[c][i] = eps[c][i] - e_new;
                    a_sum[c][i] = a_old[c][i] + a_new[c][i];
                }
            }
            for (part, y) in m.parts.iter().zip(mech.weights) {
                let springs = form(part, &a_new, &a_old);
                let strains = form(part, &eps, old);
                let step = form(part, &a_old, &a_sum);
                for i in 0..LANES {
                    energy[i] +=
                        y * (0.5 * springs[i] - 0.5 * strains[i] + mech.dt_over_4tau * step[i]);
                }
            }
        }
        for i in 0..LANES {
            m.energy[i] += w[i] * energy[i];
        }
    }
}

/// x.C y per lane.
#[inline(always)]
fn form(c: &[[f64; 3]; 3], x: &[Lanes; 3], y: &[Lanes; 3]) -> Lanes {
    let mut out = [0.0; LANES];
    for (row, x) in c.iter().zip(x) {
        for i in 0..LANES {
            out[i] += x[i] * (row[0] * y[0][i] + row[1] * y[1][i] + row[2] * y[2][i]);
        }
    }
    out
}

impl super::SemModel {
    /// The shortest relaxation time of the element rows' materials (s); `None` where all are
    /// elastic.
    pub fn shortest_relaxation_s(&self) -> Option<f64> {
        self.row_material
            .iter()
            .filter_map(|&m| self.materials[m].relaxation.as_ref())
            .map(Relaxation::shortest_tau_s)
            .reduce(f64::min)
    }

    /// Zero memory variables for the viscoelastic rows at step `dt`, eps_{-1} from `u_prev`
    /// (see [`crate::solve::Discretisation::start_memory`]); no memory where every row is
    /// elastic.
    pub(crate) fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut super::SemWorkspace) {
        work.memory.clear();
        if self.shortest_relaxation_s().is_none() {
            return;
        }
        let groups = self.half_width.len();
        let px = self.gll_x.order();
        work.memory = (self.row_material.iter().zip(&self.gll_y))
            .map(|(&m, gy)| {
                let points = groups * (px + 1) * (gy.order() + 1);
                let relaxation = self.materials[m].relaxation.as_ref()?;
                Some(RowMemory::new(relaxation, points, dt))
            })
            .collect();
        self.memory_pass::<Start>(u_prev, work);
    }

    /// The energy dissipated since the last call: dt times the rows' sums, in row order
    /// (bit-identical for any thread count).
    pub(crate) fn take_viscous_loss(&self, work: &mut super::SemWorkspace) -> f64 {
        let mut loss = 0.0;
        for m in work.memory.iter_mut().flatten() {
            loss += m.dt * m.loss.iter().sum::<f64>();
            m.loss = [0.0; LANES];
        }
        loss
    }

    /// MEM_{n-1/2} (module docs) from u_n = `u`, the memory left as it was.
    pub(crate) fn memory_energy(&self, u: &[f64], work: &mut super::SemWorkspace) -> f64 {
        if work.memory.is_empty() {
            return 0.0;
        }
        for m in work.memory.iter_mut().flatten() {
            m.energy = [0.0; LANES];
        }
        self.memory_pass::<Probe>(u, work);
        (work.memory.iter().flatten())
            .map(|m| m.energy.iter().sum::<f64>())
            .sum()
    }

    /// The row kernel with law `L` (one without forces) over the viscoelastic rows, in parallel.
    fn memory_pass<L: PointLaw<State = RowMemory>>(
        &self,
        u: &[f64],
        work: &mut super::SemWorkspace,
    ) {
        use rayon::prelude::*;
        let super::SemWorkspace { rows, memory, .. } = work;
        rows.par_iter_mut()
            .zip(memory.par_iter_mut())
            .enumerate()
            .for_each(|(r, (row, memory))| {
                if let Some(m) = memory {
                    self.row_forces::<L>(r, u, row, m);
                }
            });
    }
}
