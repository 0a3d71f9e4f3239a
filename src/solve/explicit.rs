//! Central difference with lumped mass and diagonal damping (report eqs 65-69, with
//! A = K - 2M/dt^2; the report's eq 67 misprints dt^2 as dt):
//! (M/dt^2 + C/2dt) u_{n+1} = f_n - K u_n + 2M/dt^2 u_n - (M/dt^2 - C/2dt) u_{n-1}.
//!
//! The step is split so that it costs O(DOFs) only once: a fused parallel kernel computes
//! the undamped, unforced update u_{n+1} = 2 u_n - u_{n-1} - (dt^2/m)(K u_n) for every DOF,
//! then sparse corrections touch only what the scene has: source DOFs, periodic ties (each
//! tied pair takes the mass-weighted mean of its two updates, the update of one DOF of mass
//! m_l + m_r under the force f_l + f_r), dashpot DOFs, crack pairs. Fixed DOFs have
//! dt^2/m = 0 and so never move. Nothing is allocated per step.
//! The kernel is [`StiffnessOperator::explicit_update`]: matrix-free stencils on structured
//! meshes, the assembled K elsewhere.

use super::ledger::{EnergyLedger, Flows};
use super::{
    sample_sources, stability, CrackTraces, Quantity, Receiver, RunConfig, RunOutput, RunReport,
    Source,
};
use crate::contact::ContactSolver;
use crate::error::{Error, Result};
use crate::fem::{Model, StiffnessOperator};
use crate::signal::Signal;
use rayon::prelude::*;
use std::time::Instant;

/// A run is declared unstable when its kinetic energy exceeds this multiple of the energy put in.
const BLOW_UP_FACTOR: f64 = 100.0;

/// Per-DOF constants of the scheme.
struct Coefficients {
    /// dt^2 / m, zero on fixed DOFs.
    a: Vec<f64>,
    /// (DOF, c, r = c dt / 2m) for every dashpot.
    dashpots: Vec<(usize, f64, f64)>,
    /// Compliance of the corrected update, dt^2 / (m (1 + r)).
    compliance: Vec<f64>,
    /// (left DOF, right DOF, m_l / (m_l + m_r)) for every periodic tie.
    ties: Vec<(usize, usize, f64)>,
}

impl Coefficients {
    fn new(model: &Model, dt: f64) -> Coefficients {
        let mut a: Vec<f64> = model.lumped_mass.iter().map(|m| dt * dt / m).collect();
        for &d in &model.fixed_dofs {
            a[d] = 0.0;
        }
        let mut dashpots: Vec<(usize, f64, f64)> = model
            .dashpots
            .iter()
            .map(|&(d, c)| (d, c, c * dt / (2.0 * model.lumped_mass[d])))
            .collect();
        let m = &model.lumped_mass;
        let ties: Vec<(usize, usize, f64)> = model
            .periodic
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
        Coefficients {
            a,
            dashpots,
            compliance,
            ties,
        }
    }
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

/// Energy at t_{n-1/2}: kinetic 1/2 v^T M v with v = (u_n - u_{n-1})/dt, strain 1/2 u_{n-1}^T K u_n.
/// Summed in parallel over fixed chunks of DOFs, the chunk sums then added in order: the
/// result does not depend on the thread count. `ku` is scratch (it ends up holding each
/// chunk's two partial sums in its first two entries).
fn staggered_energy(
    model: &Model,
    op: &StiffnessOperator,
    dt: f64,
    u_prev: &[f64],
    u: &[f64],
    ku: &mut [f64],
) -> (f64, f64) {
    op.mul(u, ku);
    ku.par_chunks_mut(ENERGY_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            let r = c * ENERGY_CHUNK..c * ENERGY_CHUNK + chunk.len();
            let (mut kinetic, mut strain) = (0.0, 0.0);
            for (((&kui, &ui), &pi), &mi) in chunk
                .iter()
                .zip(&u[r.clone()])
                .zip(&u_prev[r.clone()])
                .zip(&model.lumped_mass[r])
            {
                let v = (ui - pi) / dt;
                kinetic += mi * v * v;
                strain += pi * kui;
            }
            // DOFs come in pairs and the chunk size is even: every chunk has 2+ entries.
            chunk[0] = kinetic;
            chunk[1] = strain;
        });
    let (mut kinetic, mut strain) = (0.0, 0.0);
    for chunk in ku.chunks(ENERGY_CHUNK) {
        kinetic += chunk[0];
        strain += chunk[1];
    }
    (0.5 * kinetic, 0.5 * strain)
}

fn trace_value(r: &Receiver, dt: f64, u_prev: &[f64], u: &[f64], u_next: &[f64]) -> f64 {
    match r.quantity {
        Quantity::Displacement => r.weights.iter().map(|&(d, w)| w * u[d]).sum(),
        Quantity::Velocity => {
            r.weights
                .iter()
                .map(|&(d, w)| w * (u_next[d] - u_prev[d]))
                .sum::<f64>()
                / (2.0 * dt)
        }
    }
}

/// Runs the explicit scheme.
pub(super) fn run(
    model: &Model,
    sources: &[Source],
    receivers: &[Receiver],
    config: &RunConfig,
) -> Result<RunOutput> {
    let setup = Instant::now();
    let op = StiffnessOperator::new(model);
    let stab = config
        .stability
        .unwrap_or_else(|| stability::estimate(model));
    let dt = config.dt_s.unwrap_or(config.step_safety * stab.dt_crit_s);
    let ratio = dt / stab.dt_crit_s;
    if ratio > 1.0 && !config.force {
        return Err(Error::StepTooLarge {
            dt_s: dt,
            dt_crit_s: stab.dt_crit_s,
            ratio,
        });
    }
    let steps = super::run_steps(model, sources.len(), receivers.len(), config, dt)?;
    let n = model.dofs();
    let coef = Coefficients::new(model, dt);
    let forces = sample_sources(sources, dt, steps)?;
    let mut u = config
        .initial_displacement
        .clone()
        .unwrap_or_else(|| vec![0.0; n]);
    for &d in &model.fixed_dofs {
        u[d] = 0.0;
    }
    // u_{-1} = u_0 - dt v_0: the staggered velocity v_{-1/2} equals the initial velocity.
    let mut u_prev = u.clone();
    if let Some(v0) = &config.initial_velocity {
        for (d, p) in u_prev.iter_mut().enumerate() {
            if coef.a[d] != 0.0 {
                *p -= dt * v0[d];
            }
        }
    }
    let mut u_next = vec![0.0; n];
    let mut ku = vec![0.0; n];
    let mut contact = match (&model.crack, &config.contact) {
        (Some(crack), Some(options)) => Some(ContactSolver::new(
            crack,
            &coef.compliance,
            *options,
            steps,
        )?),
        _ => None,
    };
    if let Some(c) = contact.as_mut() {
        c.reset_stick_points(&u);
    }
    let mut traces: Vec<Vec<f64>> = receivers
        .iter()
        .map(|_| Vec::with_capacity(steps))
        .collect();
    let crack_pairs = model
        .crack
        .as_ref()
        .filter(|_| config.record_crack)
        .map(|c| c.pairs.clone())
        .unwrap_or_default();
    let mut crack_master: Vec<Vec<f64>> = crack_pairs
        .iter()
        .map(|_| Vec::with_capacity(steps))
        .collect();
    let mut crack_slave: Vec<Vec<f64>> = crack_pairs
        .iter()
        .map(|_| Vec::with_capacity(steps))
        .collect();
    let mut snapshots = Vec::new();
    let mut ledger = EnergyLedger::default();
    let mut flows = Flows::default();
    let (k0, s0) = staggered_energy(model, &op, dt, &u_prev, &u, &mut ku);
    ledger.initial_j = k0 + s0;
    let mut progress = super::progress::start(config.progress, steps);
    let setup_time_s = setup.elapsed().as_secs_f64();
    let clock = Instant::now();

    for step in 0..steps {
        if step % 256 == 0 {
            crate::budget::check()?;
        }
        if step % config.ledger_every == 0 {
            sample_ledger(
                model,
                &op,
                dt,
                step,
                &u_prev,
                &u,
                &mut ku,
                &mut ledger,
                &flows,
                stab.dt_crit_s,
            )?;
        }
        op.explicit_update(&coef.a, &u_prev, &u, &mut u_next);
        for (source, values) in sources.iter().zip(&forces) {
            let f = values[step];
            if f != 0.0 {
                for &(d, w) in &source.weights {
                    u_next[d] += coef.a[d] * w * f;
                }
            }
        }
        for &(l, r, w) in &coef.ties {
            let tied = w * u_next[l] + (1.0 - w) * u_next[r];
            u_next[l] = tied;
            u_next[r] = tied;
        }
        for &(d, c, r) in &coef.dashpots {
            let q = u_next[d] - 2.0 * u[d] + u_prev[d];
            u_next[d] = (q + 2.0 * u[d] - (1.0 - r) * u_prev[d]) / (1.0 + r);
            let du = u_next[d] - u_prev[d];
            flows.dashpot_loss += c * du * du / (4.0 * dt);
        }
        if let Some(c) = contact.as_mut() {
            c.apply(&mut u_next)?;
            c.for_each_force(|d, f| {
                if d % 2 == 1 {
                    flows.contact_normal_work += 0.5 * f * (u_next[d] - u_prev[d]);
                } else {
                    flows.contact_tangential_work += 0.5 * f * (u_next[d] - u_prev[d]);
                }
            });
        }
        for (source, values) in sources.iter().zip(&forces) {
            let f = values[step];
            flows.source_work += 0.5
                * f
                * source
                    .weights
                    .iter()
                    .map(|&(d, w)| w * (u_next[d] - u_prev[d]))
                    .sum::<f64>();
        }
        for (r, t) in receivers.iter().zip(&mut traces) {
            t.push(trace_value(r, dt, &u_prev, &u, &u_next));
        }
        for ((p, m), s) in crack_pairs
            .iter()
            .zip(&mut crack_master)
            .zip(&mut crack_slave)
        {
            m.push(u[2 * p.master + 1]);
            s.push(u[2 * p.slave + 1]);
        }
        if config.snapshot_every.is_some_and(|k| step % k == 0) {
            super::keep_snapshot(config, &mut snapshots, step, dt, &u)?;
        }
        std::mem::swap(&mut u_prev, &mut u);
        std::mem::swap(&mut u, &mut u_next);
        if step % super::progress::REPORT_EVERY == 0 {
            progress(step);
        }
    }
    sample_ledger(
        model,
        &op,
        dt,
        steps,
        &u_prev,
        &u,
        &mut ku,
        &mut ledger,
        &flows,
        stab.dt_crit_s,
    )?;
    drop(progress);
    let wall_time_s = clock.elapsed().as_secs_f64();

    let to_signal = |v: Vec<f64>| Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: v,
    };
    let crack = model
        .crack
        .as_ref()
        .filter(|_| config.record_crack)
        .map(|c| CrackTraces {
            x_m: c
                .pairs
                .iter()
                .map(|p| model.mesh.nodes[p.master][0])
                .collect(),
            normal_gap: crack_master
                .iter()
                .zip(&crack_slave)
                .map(|(m, s)| to_signal(s.iter().zip(m).map(|(s, m)| s - m).collect()))
                .collect(),
            master_uy: crack_master.into_iter().map(to_signal).collect(),
            slave_uy: crack_slave.into_iter().map(to_signal).collect(),
        });
    let (contact, contact_series) = contact.map(|c| c.finish(steps, dt)).unzip();
    let report = RunReport {
        integrator: "explicit central difference (lumped mass)".into(),
        wall_time_s,
        setup_time_s,
        steps,
        dofs: n,
        dt_s: dt,
        dt_crit_s: stab.dt_crit_s,
        stability_ratio: ratio,
        energy_residual: ledger.final_residual(),
        energy_residual_peak: ledger.peak_residual(),
        source_work_j: flows.source_work,
        contact,
    };
    Ok(RunOutput {
        report,
        traces: traces.into_iter().map(to_signal).collect(),
        receiver_names: receivers.iter().map(|r| r.name.clone()).collect(),
        crack,
        contact_series,
        snapshots,
        ledger,
    })
}

/// Appends a ledger sample at t_{step-1/2} and stops a run that blew up.
#[allow(clippy::too_many_arguments)]
fn sample_ledger(
    model: &Model,
    op: &StiffnessOperator,
    dt: f64,
    step: usize,
    u_prev: &[f64],
    u: &[f64],
    ku: &mut [f64],
    ledger: &mut EnergyLedger,
    flows: &Flows,
    dt_crit: f64,
) -> Result<()> {
    let (kinetic, strain) = staggered_energy(model, op, dt, u_prev, u, ku);
    let time_s = (step as f64 - 0.5) * dt;
    let unstable = |reason: String| Error::Unstable {
        step,
        time_s,
        reason,
        dt_s: dt,
        dt_crit_s: dt_crit,
    };
    if !(kinetic.is_finite() && strain.is_finite()) {
        return Err(unstable("displacements became non-finite".into()));
    }
    let budget = ledger.initial_j
        + ledger
            .source_work_j
            .iter()
            .fold(flows.source_work.abs(), |m, w| m.max(w.abs()));
    if kinetic > BLOW_UP_FACTOR * budget && kinetic > 0.0 {
        return Err(unstable(format!("kinetic energy {kinetic:.3e} J/m grew above {BLOW_UP_FACTOR} times the energy put in ({budget:.3e} J/m)")));
    }
    ledger.push(time_s, kinetic, strain, flows);
    Ok(())
}
