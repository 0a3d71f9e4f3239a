//! Fourth-order explicit time stepping by the modified equation (Dablain 1986; the
//! Lax-Wendroff idea for second-order systems). Central differences leave
//! u_{n+1} - 2 u_n + u_{n-1} = dt^2 u''_n + dt^4/12 u''''_n + O(dt^6), and for an undamped body
//! u'' = M^-1 (f - K u), u'''' = M^-1 (f'' - K M^-1 (f - K u)). Adding the dt^4 term gives
//! central differences on a modified body:
//!
//!   M (u_{n+1} - 2 u_n + u_{n-1}) / dt^2 + C (u_{n+1} - u_{n-1}) / (2 dt) + K~ u_n = f~_n,
//!   K~ = K - (dt^2/12) K M^-1 K,   f~_n = f_n + (dt^2/12) (f''_n - K M^-1 f_n),
//!
//! two stiffness products a step (K u_n, then K applied to M^-1 K u_n). A source w s(t)
//! contributes w (s_n + (s_{n+1} - 2 s_n + s_{n-1}) / 12) - (dt^2/12) s_n K M^-1 w, with
//! K M^-1 w computed once. The modified stiffness has eigenvalues lambda - dt^2 lambda^2 / 12
//! (lambda those of M^-1 K): with x = dt^2 lambda_max <= 12 they lie in [0, 3], so the scheme
//! is stable up to dt = sqrt(12 / lambda_max) = sqrt(3) dt_crit of central differences, and
//! K~ is positive semi-definite there: the ledger with strain energy u_{n-1}^T K~ u_n / 2 and
//! the work of f~ closes to round-off as for central differences.
//!
//! Dashpots are refused by the run, as are contact and periodic ties. With a damping term
//! C u' the correction needs K M^-1 C u' as well, and K M^-1 applied to a field held on
//! one row of nodes is of the order of omega_max^2: left out, it changes the absorbing edge
//! by O(dt^2 omega_max^2) (measured at normal incidence through the default laminate: 12%
//! at the absorbing bottom, against 0.3% with central differences at the same step); taken
//! in explicitly from the last steps' velocities, it made the default smoke scene unstable
//! at 0.9 of the limit. An absorbing edge needs an implicit treatment of that term.

use super::discretisation::Discretisation;
use super::explicit::{energy_sums, Coefficients};
use super::ledger::Flows;
use super::stepper::{EnergySample, Fields, Stepper, Velocity};
use super::SampledSources;
use crate::error::Result;
use rayon::prelude::*;

/// The largest stable step over central differences' dt_crit: sqrt(12) / 2.
pub const STABILITY_GAIN: f64 = 1.732_050_807_568_877_2;

/// DOFs per parallel task of the updates.
const CHUNK: usize = 8192;

/// One source's modified force: DOF weights of w, and of q = K M^-1 w.
struct ModifiedSource {
    w: Vec<(usize, f64)>,
    q: Vec<(usize, f64)>,
}

/// The fourth-order modified-equation scheme over any [`Discretisation`], without contact:
/// the state (u_{n-1}, u_n, u_{n+1}), K u_n, M^-1 K u_n and its stiffness product, all
/// allocated once.
pub struct FourthOrder<'a, D: Discretisation> {
    body: &'a D,
    work: D::Workspace,
    coef: Coefficients,
    /// 1 / m, zero on fixed DOFs.
    inverse_mass: Vec<f64>,
    dt: f64,
    sources: SampledSources<'a>,
    modified: Vec<ModifiedSource>,
    u_prev: Vec<f64>,
    u: Vec<f64>,
    u_next: Vec<f64>,
    ku: Vec<f64>,
    kmku: Vec<f64>,
    /// The step whose u_n `ku` and `kmku` belong to (the ledger and the step share them).
    products_of: Option<usize>,
    /// Accelerations a = M^-1 (f - K u) of the last three steps, a_n at `newest`: the
    /// fourth-order velocity's third derivative.
    accelerations: [Vec<f64>; 3],
    newest: usize,
    flows: Flows,
}

impl<'a, D: Discretisation> FourthOrder<'a, D> {
    /// The scheme at step `dt` from rest (u_0 = 0, v_0 = 0), or from u_0 and v_0 as
    /// [`super::CentralDifference::new`] takes them.
    pub fn new(
        body: &'a D,
        coef: Coefficients,
        dt: f64,
        sources: SampledSources<'a>,
        initial_displacement: Option<&[f64]>,
        initial_velocity: Option<&[f64]>,
    ) -> Self {
        let n = body.dofs();
        let mut inverse_mass: Vec<f64> = body.lumped_mass().iter().map(|m| 1.0 / m).collect();
        for &d in body.fixed_dofs() {
            inverse_mass[d] = 0.0;
        }
        let mut work = body.workspace();
        let modified = sources
            .iter()
            .map(|(w, _)| {
                let mut mw = vec![0.0; n];
                for &(d, wd) in w {
                    mw[d] += inverse_mass[d] * wd;
                }
                let mut q = vec![0.0; n];
                body.stiffness_times(&mw, &mut q, &mut work);
                ModifiedSource {
                    w: w.to_vec(),
                    q: q.iter()
                        .enumerate()
                        .filter(|&(_, &v)| v != 0.0)
                        .map(|(d, &v)| (d, v))
                        .collect(),
                }
            })
            .collect();
        let mut u = initial_displacement.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        for &d in body.fixed_dofs() {
            u[d] = 0.0;
        }
        let mut u_prev = u.clone();
        if let Some(v0) = initial_velocity {
            for (d, p) in u_prev.iter_mut().enumerate() {
                if inverse_mass[d] != 0.0 {
                    *p -= dt * v0[d];
                }
            }
        }
        FourthOrder {
            body,
            work,
            coef,
            inverse_mass,
            dt,
            sources,
            modified,
            u_prev,
            u,
            u_next: vec![0.0; n],
            ku: vec![0.0; n],
            kmku: vec![0.0; n],
            products_of: None,
            accelerations: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            newest: 0,
            flows: Flows::default(),
        }
    }

    /// For u_n of step `step`: `ku = K u_n`, `kmku = K M^-1 K u_n` (then K~ u_n = ku -
    /// (dt^2/12) kmku), and a_n = M^-1 (f_n - K u_n) stored as the newest acceleration.
    /// Computed once per step: the ledger's sample and the step share them.
    fn stiffness_products(&mut self, step: usize) {
        if self.products_of == Some(step) {
            return;
        }
        self.body
            .stiffness_times(&self.u, &mut self.ku, &mut self.work);
        self.newest = (self.newest + 1) % 3;
        let a = &mut self.accelerations[self.newest];
        let (ku, inverse_mass) = (&self.ku, &self.inverse_mass);
        a.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| {
            let r = c * CHUNK..c * CHUNK + chunk.len();
            for ((g, &k), &im) in chunk.iter_mut().zip(&ku[r.clone()]).zip(&inverse_mass[r]) {
                *g = -im * k;
            }
        });
        // K M^-1 K u_n = -K a_n, before the forces are added to a_n.
        self.body.stiffness_times(a, &mut self.kmku, &mut self.work);
        self.kmku.par_iter_mut().for_each(|v| *v = -*v);
        for (weights, values) in self.sources.iter() {
            // (the ledger's last sample comes after the last step, past the forces)
            let f = values.get(step).copied().unwrap_or(0.0);
            for &(d, w) in weights {
                a[d] += self.inverse_mass[d] * w * f;
            }
        }
        self.products_of = Some(step);
    }

    /// The modified force of every source at step n, as (DOF, force) pairs, each passed to
    /// `apply`: w (s_n + (s_{n+1} - 2 s_n + s_{n-1}) / 12) - (dt^2 / 12) s_n q.
    fn for_each_force(&self, step: usize, mut apply: impl FnMut(usize, f64)) {
        let h = self.dt * self.dt / 12.0;
        for ((_, values), m) in self.sources.iter().zip(&self.modified) {
            let at = |k: Option<usize>| k.and_then(|k| values.get(k)).copied().unwrap_or(0.0);
            let s = values[step];
            let s2 = at(Some(step + 1)) - 2.0 * s + at(step.checked_sub(1));
            let driven = s + s2 / 12.0;
            if driven != 0.0 {
                m.w.iter().for_each(|&(d, w)| apply(d, w * driven));
            }
            if s != 0.0 {
                m.q.iter().for_each(|&(d, q)| apply(d, -h * s * q));
            }
        }
    }
}

impl<D: Discretisation> Stepper for FourthOrder<'_, D> {
    fn dt_s(&self) -> f64 {
        self.dt
    }

    /// u_{n+1} = 2 u_n - u_{n-1} + (dt^2 / m) (f~_n - K~ u_n), then the dashpots' implicit
    /// correction as in central differences (module docs).
    fn advance(&mut self, step: usize) -> Result<()> {
        self.stiffness_products(step);
        let h = self.dt * self.dt / 12.0;
        let (a, u_prev, u, ku, kmku) = (&self.coef.a, &self.u_prev, &self.u, &self.ku, &self.kmku);
        self.u_next
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let r = c * CHUNK..c * CHUNK + chunk.len();
                for (k, next) in r.zip(chunk.iter_mut()) {
                    *next = 2.0 * u[k] - u_prev[k] - a[k] * (ku[k] - h * kmku[k]);
                }
            });
        let mut next = std::mem::take(&mut self.u_next);
        self.for_each_force(step, |d, f| next[d] += self.coef.a[d] * f);
        let (u_prev, u) = (&self.u_prev, &self.u);
        self.coef.damp(u_prev, u, &mut next);
        self.flows.dashpot_loss += self.coef.dashpot_loss(u_prev, &next, self.dt);
        let mut work = 0.0;
        self.for_each_force(step, |d, f| work += 0.5 * f * (next[d] - u_prev[d]));
        self.flows.source_work += work;
        self.u_next = next;
        Ok(())
    }

    fn fields(&self, step: usize) -> Fields<'_> {
        Fields {
            step,
            dt_s: self.dt,
            displacement: &self.u,
            velocity: Velocity::Corrected {
                previous: &self.u_prev,
                next: &self.u_next,
                accelerations: [0, 2, 1]
                    .map(|back| &self.accelerations[(self.newest + back) % 3][..]),
            },
        }
    }

    fn commit(&mut self) {
        std::mem::swap(&mut self.u_prev, &mut self.u);
        std::mem::swap(&mut self.u, &mut self.u_next);
    }

    /// Energy at t_{n-1/2}: kinetic 1/2 v^T M v with v = (u_n - u_{n-1})/dt, strain
    /// 1/2 u_{n-1}^T K~ u_n ([`super::explicit::energy_sums`]).
    fn energy(&mut self, step: usize) -> EnergySample {
        self.stiffness_products(step);
        let (dt, h) = (self.dt, self.dt * self.dt / 12.0);
        let (u_prev, ku, kmku) = (&self.u_prev, &self.ku, &self.kmku);
        let state = (&u_prev[..], &self.u[..], self.body.lumped_mass());
        // u_next is free until the next advance: it holds the chunk sums.
        let strain = |k: usize, _| u_prev[k] * (ku[k] - h * kmku[k]);
        let (kinetic, strain) = energy_sums(&mut self.u_next, state, dt, strain);
        EnergySample {
            time_s: (step as f64 - 0.5) * dt,
            kinetic_j: 0.5 * kinetic,
            strain_j: 0.5 * strain,
            memory_j: 0.0,
            flows: self.flows,
        }
    }
}
