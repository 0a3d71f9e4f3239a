//! Memory variables of viscoelastic materials at the quadrature points of a discretisation
//! (`W` points side by side: a lane group of spectral elements, or one triangle), and the
//! point laws a stress kernel is compiled with: [`Elastic`] (nothing beyond W C_U eps:
//! elastic rows run today's code), [`Viscous`] (the memory update and its stress, in the time
//! step), [`Start`] (the memory at the first step) and [`Probe`] (the ledger's memory energy,
//! read without changing the state); for Newmark, [`History`], [`Relax`] and [`Stored`]
//! (below).
//!
//! The update is the trapezoidal rule on tau_l e_l' + e_l = eps (bilinear, A-stable):
//!
//!   e_{l,n} = alpha_l e_{l,n-1} + beta_l (eps_{n-1} + eps_n),
//!   alpha_l = (2 tau_l - dt) / (2 tau_l + dt),  beta_l = dt / (2 tau_l + dt),
//!
//! i.e. tau_l (e_{l,n} - e_{l,n-1}) / dt = (a_{n-1} + a_n) / 2 with a = eps - e_l, the strain
//! of the mechanism's spring (the update computes the loss below from the memory's step). With central differences it keeps an exact discrete energy
//! balance (docs/src/physics.md, "Losses"): at t_{n-1/2} the stored energy is the elastic
//! sample of C_U plus
//!
//!   MEM_{n-1/2} = sum_q W_q sum_l [ 1/2 a_n.DC_l a_{n-1} - 1/2 eps_n.DC_l eps_{n-1}
//!                                   + dt/(4 tau_l) a_{n-1}.DC_l (a_{n-1} + a_n) ],
//!
//! and the step n dissipates dt d_{n-1/2}, d = sum_q W_q sum_l (1/tau_l) abar.DC_l abar with
//! abar = (a_{n-1} + a_n) / 2 >= 0, so E_{n+1/2} - E_{n-1/2} + dt d_{n-1/2} is the work of the
//! external forces over the step, to round-off.

//! Newmark (average acceleration, the trapezoidal rule on u and v) takes the same update.
//! Put into the stress at t_{n+1},
//!
//!   sigma_{n+1} = (C_U - sum_l beta_l DC_l) eps_{n+1} - h_n,
//!   h_n = sum_l DC_l (alpha_l e_{l,n} + beta_l eps_n),
//!
//! so its effective matrix is assembled with C_N = C_U - sum_l beta_l DC_l
//! ([`newmark_stiffness_change`]) and its right-hand side gains the history force G^T h_n
//! ([`History`]); once u_{n+1} is solved for, [`Relax`] updates the memory. The whole system
//! (u, v, e_l) then advances by the trapezoidal rule, which keeps the quadratic energy
//!
//!   E_n = 1/2 v.M v + 1/2 u.K_U u + sum_q W_q sum_l (1/2 e_l.DC_l e_l - e_l.DC_l eps),
//!
//! (the stored energy 1/2 eps.C_R eps + sum_l 1/2 a_l.DC_l a_l written with C_U; [`Stored`]
//! gives the memory's part) and dissipates dt d_{n+1/2} with the same d as above.

use crate::material::{Material, Relaxation};

/// W values side by side: one per element of a lane group (spectral elements) or per triangle.
pub(crate) type Lanes<const W: usize> = [f64; W];

/// What a stress kernel does at a quadrature point beyond the elastic weighted stress
/// W C_U eps, reading and writing `State` per set of points (an element row, a lane group of
/// elements, a chunk of triangles).
pub(crate) trait PointLaw<const W: usize, State> {
    /// Whether the kernel goes on to the nodal forces (laws that only read fields do not).
    const FORCES: bool = true;
    /// At point `q` of the set (for spectral elements point p of lane group g: q = g P + p,
    /// P points per element), of quadrature weight W and strain `eps` (xx, yy, engineering
    /// xy): adjusts the weighted stress `s`, W C_U eps on entry.
    fn at_point(
        state: &mut State,
        q: usize,
        weight: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        s: [&mut Lanes<W>; 3],
    );
}

/// No memory: the stress stays W C_U eps.
pub(crate) struct Elastic;

impl<const W: usize, S> PointLaw<W, S> for Elastic {
    #[inline(always)]
    fn at_point(_: &mut S, _: usize, _: &Lanes<W>, _: [&Lanes<W>; 3], _: [&mut Lanes<W>; 3]) {}
}

/// The memory update of a time step and its stress, s -= W sum_l DC_l e_{l,n}, with the
/// step's loss W sum_l (1/tau_l) abar.DC_l abar added up.
pub(crate) struct Viscous;

/// The memory at the first step: eps_{-1} from u_{-1}, e_{l,-1} = 0.
pub(crate) struct Start;

/// MEM_{n-1/2} (module docs) from u_n and the state after step n - 1, into
/// [`RowMemory::energy`]; the state is left as it was.
pub(crate) struct Probe;

/// Newmark's history force: the weighted stress s = W h_n (module docs) of the memory and the
/// strain of u_n; the memory is left as it was.
pub(crate) struct History;

/// Newmark's memory update once u_{n+1} is known: [`Viscous`]'s update and loss, without
/// forces.
pub(crate) struct Relax;

/// Newmark's memory energy at t_n, sum_l W (1/2 e_l.DC_l e_l - e_l.DC_l eps_n) from the strain
/// of u_n, into [`RowMemory::energy`]; the state is left as it was.
pub(crate) struct Stored;

/// The trapezoidal update's (alpha_l, beta_l) for relaxation time `tau` at step `dt`.
fn trapezoid(tau: f64, dt: f64) -> (f64, f64) {
    ((2.0 * tau - dt) / (2.0 * tau + dt), dt / (2.0 * tau + dt))
}

/// C_N - C_U = -sum_l beta_l DC_l: what the trapezoidal memory update takes off the stiffness
/// acting on eps_{n+1} in Newmark's effective matrix (module docs); zero for an elastic
/// material.
pub(crate) fn newmark_stiffness_change(material: &Material, dt: f64) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    let Some(relaxation) = &material.relaxation else {
        return c;
    };
    for (l, &tau) in relaxation.tau_s.iter().enumerate() {
        let beta = trapezoid(tau, dt).1;
        let dc = relaxation.relaxed_by(l);
        for (row, dc_row) in c.iter_mut().zip(&dc) {
            for (cij, dij) in row.iter_mut().zip(dc_row) {
                *cij -= beta * dij;
            }
        }
    }
    c
}

/// One relaxation mechanism's constants at the run's step.
#[derive(Clone, Debug)]
struct Mechanism<S> {
    alpha: f64,
    beta: f64,
    /// dt / (4 tau_l), of the memory energy.
    dt_over_4tau: f64,
    /// DC_l = sum_k y_kl C_k (Pa).
    relaxed: S,
    /// DC_l tau_l / dt^2, of the loss: (1/tau_l) abar.DC_l abar with abar = tau_l Delta e_l / dt
    /// (Pa/s).
    dissipative: S,
}

impl<S: Clone> Mechanism<S> {
    /// The constants of relaxation time `tau` and stiffness `relaxed` = DC_l at step `dt`;
    /// `scaled(DC_l, f)` is f DC_l.
    fn new(tau: f64, relaxed: S, dt: f64, scaled: impl Fn(&S, f64) -> S) -> Self {
        let (alpha, beta) = trapezoid(tau, dt);
        Mechanism {
            alpha,
            beta,
            dt_over_4tau: dt / (4.0 * tau),
            dissipative: scaled(&relaxed, tau / (dt * dt)),
            relaxed,
        }
    }
}

/// A mechanism's stiffness DC_l (or a multiple of it) as the memory laws apply it, lane by
/// lane: one material's in every lane ([`Block`]: an element row, a chunk of triangles), or
/// each lane's own ([`LaneStiffness`]: a lane group of unstructured elements, each with its
/// material and axes).
pub(crate) trait Relaxed<const W: usize>: Clone + std::fmt::Debug {
    /// DC x, lane by lane.
    fn times(&self, x: &[Lanes<W>; 3]) -> [Lanes<W>; 3];
    /// x.DC y, lane by lane.
    fn form(&self, x: &[Lanes<W>; 3], y: &[Lanes<W>; 3]) -> Lanes<W>;
}

/// A plane stiffness that does not couple the normal strains to the shear strain, as every
/// part of [`crate::attenuation`]'s splits in the material's axes: [C11, C12, C22, C66].
pub(crate) type Block = [f64; 4];

/// The block of a 3x3 stiffness (its entries coupling normal and shear strain are zero).
fn block(c: &[[f64; 3]; 3]) -> Block {
    debug_assert!(c[0][2] == 0.0 && c[1][2] == 0.0 && c[2][0] == 0.0 && c[2][1] == 0.0);
    [c[0][0], c[0][1], c[1][1], c[2][2]]
}

impl<const W: usize> Relaxed<W> for Block {
    #[inline(always)]
    fn times(&self, x: &[Lanes<W>; 3]) -> [Lanes<W>; 3] {
        // one simple loop per quantity, each a few vector operations across the lanes
        let mut r = [[0.0; W]; 3];
        for i in 0..W {
            r[0][i] = self[0] * x[0][i] + self[1] * x[1][i];
        }
        for i in 0..W {
            r[1][i] = self[1] * x[0][i] + self[2] * x[1][i];
        }
        for i in 0..W {
            r[2][i] = self[3] * x[2][i];
        }
        r
    }
    #[inline(always)]
    fn form(&self, x: &[Lanes<W>; 3], y: &[Lanes<W>; 3]) -> Lanes<W> {
        std::array::from_fn(|i| {
            self[0] * x[0][i] * y[0][i]
                + self[1] * (x[0][i] * y[1][i] + x[1][i] * y[0][i])
                + self[2] * x[1][i] * y[1][i]
                + self[3] * x[2][i] * y[2][i]
        })
    }
}

/// A symmetric plane stiffness per lane, (C11, C12, C13, C22, C23, C33) each across the lanes:
/// a turned material couples the normal strains to the shear strain. A lane of an elastic
/// element (or a padding lane) holds 0.
#[derive(Clone, Debug)]
pub(crate) struct LaneStiffness<const W: usize>(pub(crate) [Lanes<W>; 6]);

impl<const W: usize> Relaxed<W> for LaneStiffness<W> {
    #[inline(always)]
    fn times(&self, x: &[Lanes<W>; 3]) -> [Lanes<W>; 3] {
        let [c11, c12, c13, c22, c23, c33] = &self.0;
        let mut r = [[0.0; W]; 3];
        for i in 0..W {
            r[0][i] = c11[i] * x[0][i] + c12[i] * x[1][i] + c13[i] * x[2][i];
        }
        for i in 0..W {
            r[1][i] = c12[i] * x[0][i] + c22[i] * x[1][i] + c23[i] * x[2][i];
        }
        for i in 0..W {
            r[2][i] = c13[i] * x[0][i] + c23[i] * x[1][i] + c33[i] * x[2][i];
        }
        r
    }
    #[inline(always)]
    fn form(&self, x: &[Lanes<W>; 3], y: &[Lanes<W>; 3]) -> Lanes<W> {
        let dy = self.times(y);
        std::array::from_fn(|i| x[0][i] * dy[0][i] + x[1][i] * dy[1][i] + x[2][i] * dy[2][i])
    }
}

/// The memory of a set of quadrature points (an element row of spectral elements by lane
/// group, a lane group of unstructured elements, or a chunk of triangles): per point the
/// previous strain and the mechanisms' e_l, the mechanisms' constants (their stiffness as
/// `S`), and the loss and energy sums per lane.
#[derive(Clone, Debug)]
pub(crate) struct RowMemory<const W: usize, S = Block> {
    /// eps_{n-1} at point q, `[q]`.
    eps_prev: Vec<[Lanes<W>; 3]>,
    /// e_{l,n-1} at point q, `[q * L + l]`.
    e: Vec<[Lanes<W>; 3]>,
    mechanisms: Vec<Mechanism<S>>,
    /// The step.
    dt: f64,
    /// d = W sum_l (1/tau_l) abar.DC_l abar per lane, summed over the steps since it was
    /// taken (times dt: the energy dissipated).
    loss: Lanes<W>,
    /// The memory energy of the last [`Probe`], per lane.
    energy: Lanes<W>,
}

impl<const W: usize> RowMemory<W> {
    /// Zero memory for `points` quadrature points (of W lanes each) of a material relaxing
    /// as `relaxation` (in its own axes), at step `dt`.
    pub(crate) fn new(relaxation: &Relaxation, points: usize, dt: f64) -> Self {
        let mechanisms = (relaxation.tau_s.iter().enumerate())
            .map(|(l, &tau)| {
                let relaxed = block(&relaxation.relaxed_by(l));
                Mechanism::new(tau, relaxed, dt, |b, f| b.map(|d| d * f))
            })
            .collect();
        Self::with(mechanisms, points, dt)
    }
}

impl<const W: usize> RowMemory<W, LaneStiffness<W>> {
    /// Zero memory for `points` quadrature points of W lanes, lane i relaxing as
    /// `relaxations[i]` (in the x-y axes: a turned material's) or elastic where `None`, at
    /// step `dt`; `None` where every lane is elastic. The viscoelastic lanes share their
    /// relaxation times (one band and one count of mechanisms per scene; checked by the
    /// caller).
    pub(crate) fn by_lane(
        relaxations: [Option<&Relaxation>; W],
        points: usize,
        dt: f64,
    ) -> Option<Self> {
        let first = relaxations.iter().flatten().next()?;
        let mechanisms = (first.tau_s.iter().enumerate())
            .map(|(l, &tau)| {
                let mut c = LaneStiffness([[0.0; W]; 6]);
                for (i, r) in relaxations.iter().enumerate() {
                    let Some(r) = r else { continue };
                    debug_assert_eq!(r.tau_s, first.tau_s);
                    let d = r.relaxed_by(l);
                    let entries = [d[0][0], d[0][1], d[0][2], d[1][1], d[1][2], d[2][2]];
                    for (lanes, value) in c.0.iter_mut().zip(entries) {
                        lanes[i] = value;
                    }
                }
                Mechanism::new(tau, c, dt, |c, f| {
                    LaneStiffness(c.0.map(|l| l.map(|d| d * f)))
                })
            })
            .collect();
        Some(Self::with(mechanisms, points, dt))
    }
}

impl<const W: usize, S: Relaxed<W>> RowMemory<W, S> {
    /// Zero memory for `points` points with `mechanisms` at step `dt`.
    fn with(mechanisms: Vec<Mechanism<S>>, points: usize, dt: f64) -> Self {
        let zero = [[0.0; W]; 3];
        RowMemory {
            eps_prev: vec![zero; points],
            e: vec![zero; points * mechanisms.len()],
            mechanisms,
            dt,
            loss: [0.0; W],
            energy: [0.0; W],
        }
    }

    /// The energy dissipated since the last call (dt times the loss sums), the sums reset.
    pub(crate) fn take_loss(&mut self) -> f64 {
        let loss = self.dt * self.loss.iter().sum::<f64>();
        self.loss = [0.0; W];
        loss
    }

    /// Clears the memory energy before a [`Probe`].
    pub(crate) fn clear_energy(&mut self) {
        self.energy = [0.0; W];
    }

    /// The memory energy the last [`Probe`] summed.
    pub(crate) fn energy(&self) -> f64 {
        self.energy.iter().sum()
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for Viscous {
    #[inline(always)]
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        w: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        [sxx, syy, sxy]: [&mut Lanes<W>; 3],
    ) {
        let eps = [*eps[0], *eps[1], *eps[2]];
        let old = m.eps_prev[q];
        let count = m.mechanisms.len();
        // eps_{n-1} + eps_n, shared by the mechanisms
        let mut sum = [[0.0; W]; 3];
        for c in 0..3 {
            for i in 0..W {
                sum[c][i] = old[c][i] + eps[c][i];
            }
        }
        // sum_l DC_l e_{l,n}, and the loss of each lane
        let mut relaxed = [[0.0; W]; 3];
        let mut loss = [0.0; W];
        for (mech, e) in m
            .mechanisms
            .iter()
            .zip(&mut m.e[q * count..(q + 1) * count])
        {
            let (d, g) = (&mech.relaxed, &mech.dissipative);
            let (alpha, beta) = (mech.alpha, mech.beta);
            // one simple loop per quantity, each a few vector operations across the lanes, on
            // local copies (stores through `e` inside the loops kept them scalar: 3x the cost);
            // abar = tau (e_{l,n} - e_{l,n-1}) / dt, so the loss takes the memory's step
            let e_old = *e;
            let (mut e_new, mut step) = ([[0.0; W]; 3], [[0.0; W]; 3]);
            for c in 0..3 {
                for i in 0..W {
                    e_new[c][i] = alpha * e_old[c][i] + beta * sum[c][i];
                }
                for i in 0..W {
                    step[c][i] = e_new[c][i] - e_old[c][i];
                }
            }
            *e = e_new;
            let (dc_e, lost) = (d.times(&e_new), g.form(&step, &step));
            for c in 0..3 {
                for i in 0..W {
                    relaxed[c][i] += dc_e[c][i];
                }
            }
            for i in 0..W {
                loss[i] += lost[i];
            }
        }
        for i in 0..W {
            sxx[i] -= w[i] * relaxed[0][i];
            syy[i] -= w[i] * relaxed[1][i];
            sxy[i] -= w[i] * relaxed[2][i];
            m.loss[i] += w[i] * loss[i];
        }
        m.eps_prev[q] = eps;
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for Start {
    const FORCES: bool = false;
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        _: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        _: [&mut Lanes<W>; 3],
    ) {
        m.eps_prev[q] = [*eps[0], *eps[1], *eps[2]];
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for Probe {
    const FORCES: bool = false;
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        w: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        _: [&mut Lanes<W>; 3],
    ) {
        let eps = [*eps[0], *eps[1], *eps[2]];
        let old = m.eps_prev[q];
        let count = m.mechanisms.len();
        let mut energy = [0.0; W];
        for (mech, e) in m.mechanisms.iter().zip(&m.e[q * count..(q + 1) * count]) {
            // across the lanes, on local copies (as in the update)
            let (mut a_old, mut a_new, mut a_sum) = ([[0.0; W]; 3], [[0.0; W]; 3], [[0.0; W]; 3]);
            for c in 0..3 {
                for i in 0..W {
                    let e_new = mech.alpha * e[c][i] + mech.beta * (old[c][i] + eps[c][i]);
                    a_old[c][i] = old[c][i] - e[c][i];
                    a_new[c][i] = eps[c][i] - e_new;
                }
                for i in 0..W {
                    a_sum[c][i] = a_old[c][i] + a_new[c][i];
                }
            }
            let d = &mech.relaxed;
            let (kept, strains, lagged) = (
                d.form(&a_new, &a_old),
                d.form(&eps, &old),
                d.form(&a_old, &a_sum),
            );
            for i in 0..W {
                energy[i] += 0.5 * kept[i] - 0.5 * strains[i] + mech.dt_over_4tau * lagged[i];
            }
        }
        for i in 0..W {
            m.energy[i] += w[i] * energy[i];
        }
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for History {
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        w: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        [sxx, syy, sxy]: [&mut Lanes<W>; 3],
    ) {
        let count = m.mechanisms.len();
        let mut h = [[0.0; W]; 3];
        for (mech, e) in m.mechanisms.iter().zip(&m.e[q * count..(q + 1) * count]) {
            let x: [Lanes<W>; 3] = std::array::from_fn(|c| {
                std::array::from_fn(|i| mech.alpha * e[c][i] + mech.beta * eps[c][i])
            });
            let dc_x = mech.relaxed.times(&x);
            for c in 0..3 {
                for i in 0..W {
                    h[c][i] += dc_x[c][i];
                }
            }
        }
        for i in 0..W {
            sxx[i] = w[i] * h[0][i];
            syy[i] = w[i] * h[1][i];
            sxy[i] = w[i] * h[2][i];
        }
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for Relax {
    const FORCES: bool = false;
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        w: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        s: [&mut Lanes<W>; 3],
    ) {
        <Viscous as PointLaw<W, RowMemory<W, S>>>::at_point(m, q, w, eps, s);
    }
}

impl<const W: usize, S: Relaxed<W>> PointLaw<W, RowMemory<W, S>> for Stored {
    const FORCES: bool = false;
    fn at_point(
        m: &mut RowMemory<W, S>,
        q: usize,
        w: &Lanes<W>,
        eps: [&Lanes<W>; 3],
        _: [&mut Lanes<W>; 3],
    ) {
        let eps = [*eps[0], *eps[1], *eps[2]];
        let count = m.mechanisms.len();
        for (mech, e) in m.mechanisms.iter().zip(&m.e[q * count..(q + 1) * count]) {
            let (own, coupled) = (mech.relaxed.form(e, e), mech.relaxed.form(e, &eps));
            for i in 0..W {
                m.energy[i] += w[i] * (0.5 * own[i] - coupled[i]);
            }
        }
    }
}
