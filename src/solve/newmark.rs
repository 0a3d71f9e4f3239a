//! Newmark average acceleration (report eq 61, beta = 1/4, gamma = 1/2), unconditionally
//! stable. The effective matrix S = K + 4M/dt^2 + 2C/dt is factored once (sparse Cholesky,
//! faer); each step is one triangular solve pair:
//! S u_{n+1} = f_{n+1} + M (4/dt^2 u_n + 4/dt v_n + a_n) + C (2/dt u_n + v_n),
//! a_{n+1} = 4/dt^2 (u_{n+1} - u_n) - 4/dt v_n - a_n, v_{n+1} = v_n + dt/2 (a_n + a_{n+1}).
//! It conserves 1/2 v^T M v + 1/2 u^T K u exactly without damping and forces.

use super::ledger::{EnergyLedger, Flows};
use super::{
    sample_sources, stability, Quantity, Receiver, RunConfig, RunOutput, RunReport, Source,
};
use crate::error::{Error, Result};
use crate::fem::{assemble_consistent_mass, BlockCsr, Model};
use crate::signal::Signal;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use std::time::Instant;

/// The mass operator: lumped (diagonal) or consistent (sparse).
enum Mass {
    Lumped(Vec<f64>),
    Consistent(BlockCsr),
}

impl Mass {
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

/// Runs Newmark average acceleration.
pub(super) fn run(
    model: &Model,
    sources: &[Source],
    receivers: &[Receiver],
    config: &RunConfig,
    consistent_mass: bool,
) -> Result<RunOutput> {
    let setup = Instant::now();
    let stab = config
        .stability
        .unwrap_or_else(|| stability::estimate(model));
    let dt = config
        .dt_s
        .ok_or_else(|| Error::invalid("dt_s", "none", "Newmark needs an explicit time step"))?;
    let steps = super::run_steps(model, sources.len(), receivers.len(), config, dt)?;
    let n = model.dofs();
    let mut fixed = vec![false; n];
    for &d in &model.fixed_dofs {
        fixed[d] = true;
    }
    let mass = if consistent_mass {
        Mass::Consistent(assemble_consistent_mass(&model.mesh, &model.materials)?)
    } else {
        Mass::Lumped(model.lumped_mass.clone())
    };
    let mut effective = factor(n, &fixed, |add| {
        model.stiffness.for_each_entry(&mut *add);
        mass.for_each_entry(|i, j, v| add(i, j, 4.0 / (dt * dt) * v));
        for &(d, c) in &model.dashpots {
            add(d, d, 2.0 / dt * c);
        }
    })?;
    let forces = sample_sources(sources, dt, steps + 1)?;
    let add_forces = |step: usize, out: &mut [f64]| {
        for (s, values) in sources.iter().zip(&forces) {
            for &(d, w) in &s.weights {
                out[d] += w * values[step];
            }
        }
    };

    let mut u = config
        .initial_displacement
        .clone()
        .unwrap_or_else(|| vec![0.0; n]);
    let mut v = config
        .initial_velocity
        .clone()
        .unwrap_or_else(|| vec![0.0; n]);
    let mut work = vec![0.0; n];
    let mut rhs = faer::Mat::<f64>::zeros(n, 1);
    // a_0 = M^-1 (f_0 - K u_0 - C v_0)
    for (d, &f) in fixed.iter().enumerate() {
        if f {
            u[d] = 0.0;
            v[d] = 0.0;
        }
    }
    model.stiffness.mul(&u, &mut work);
    for &(d, c) in &model.dashpots {
        work[d] += c * v[d];
    }
    work.iter_mut().for_each(|w| *w = -*w);
    add_forces(0, &mut work);
    let mut a = match &mass {
        Mass::Lumped(m) => work
            .iter()
            .zip(m)
            .enumerate()
            .map(|(d, (f, m))| if fixed[d] { 0.0 } else { f / m })
            .collect::<Vec<f64>>(),
        Mass::Consistent(m) => {
            let mut llt = factor(n, &fixed, |add| m.for_each_entry(&mut *add))?;
            let col = rhs.col_as_slice_mut(0);
            for d in 0..n {
                col[d] = if fixed[d] { 0.0 } else { work[d] };
            }
            llt.solve_in_place(rhs.as_mut());
            rhs.col_as_slice(0).to_vec()
        }
    };
    let mut u_next = vec![0.0; n];
    let mut traces: Vec<Vec<f64>> = receivers
        .iter()
        .map(|_| Vec::with_capacity(steps))
        .collect();
    let mut snapshots = Vec::new();
    let mut ledger = EnergyLedger::default();
    let mut flows = Flows::default();
    ledger.initial_j = energy(model, &mass, &u, &v, &mut work);
    let mut progress = super::progress::start(config.progress, steps);
    let setup_time_s = setup.elapsed().as_secs_f64();
    let clock = Instant::now();
    let (c1, c2) = (4.0 / (dt * dt), 4.0 / dt);

    for step in 0..steps {
        if step % 256 == 0 {
            crate::budget::check()?;
        }
        if step % config.ledger_every == 0 {
            sample(
                model,
                &mass,
                step,
                dt,
                &u,
                &v,
                &mut work,
                &mut ledger,
                &flows,
                stab.dt_crit_s,
            )?;
        }
        for (r, t) in receivers.iter().zip(&mut traces) {
            let x = if r.quantity == Quantity::Displacement {
                &u
            } else {
                &v
            };
            t.push(r.weights.iter().map(|&(d, w)| w * x[d]).sum());
        }
        if config.snapshot_every.is_some_and(|k| step % k == 0) {
            super::keep_snapshot(config, &mut snapshots, step, dt, &u)?;
        }
        for d in 0..n {
            u_next[d] = c1 * u[d] + c2 * v[d] + a[d];
        }
        mass.mul(&u_next, &mut work);
        let col = rhs.col_as_slice_mut(0);
        col.copy_from_slice(&work);
        for &(d, c) in &model.dashpots {
            col[d] += c * (2.0 / dt * u[d] + v[d]);
        }
        add_forces(step + 1, col);
        for (d, &f) in fixed.iter().enumerate() {
            if f {
                col[d] = 0.0;
            }
        }
        effective.solve_in_place(rhs.as_mut());
        u_next.copy_from_slice(rhs.col_as_slice(0));
        for (s, values) in sources.iter().zip(&forces) {
            let f = 0.5 * (values[step] + values[step + 1]);
            flows.source_work += f * s
                .weights
                .iter()
                .map(|&(d, w)| w * (u_next[d] - u[d]))
                .sum::<f64>();
        }
        for d in 0..n {
            let a_next = c1 * (u_next[d] - u[d]) - c2 * v[d] - a[d];
            let v_next = v[d] + 0.5 * dt * (a[d] + a_next);
            a[d] = a_next;
            work[d] = v_next;
        }
        for &(d, c) in &model.dashpots {
            flows.dashpot_loss += c * (u_next[d] - u[d]) * 0.5 * (v[d] + work[d]);
        }
        std::mem::swap(&mut v, &mut work);
        std::mem::swap(&mut u, &mut u_next);
        if step % super::progress::REPORT_EVERY == 0 {
            progress(step);
        }
    }
    sample(
        model,
        &mass,
        steps,
        dt,
        &u,
        &v,
        &mut work,
        &mut ledger,
        &flows,
        stab.dt_crit_s,
    )?;
    drop(progress);
    let report = RunReport {
        integrator: format!(
            "Newmark average acceleration ({} mass)",
            if consistent_mass {
                "consistent"
            } else {
                "lumped"
            }
        ),
        wall_time_s: clock.elapsed().as_secs_f64(),
        setup_time_s,
        steps,
        dofs: n,
        dt_s: dt,
        dt_crit_s: stab.dt_crit_s,
        stability_ratio: dt / stab.dt_crit_s,
        energy_residual: ledger.final_residual(),
        energy_residual_peak: ledger.peak_residual(),
        source_work_j: flows.source_work,
        contact: None,
    };
    Ok(RunOutput {
        report,
        traces: traces
            .into_iter()
            .map(|t| Signal {
                dt_s: dt,
                t0_s: 0.0,
                samples: t,
            })
            .collect(),
        receiver_names: receivers.iter().map(|r| r.name.clone()).collect(),
        crack: None,
        contact_series: None,
        snapshots,
        ledger,
    })
}

/// 1/2 v^T M v + 1/2 u^T K u.
fn energy(model: &Model, mass: &Mass, u: &[f64], v: &[f64], work: &mut [f64]) -> f64 {
    mass.mul(v, work);
    let kinetic: f64 = v.iter().zip(work.iter()).map(|(a, b)| a * b).sum();
    model.stiffness.mul(u, work);
    let strain: f64 = u.iter().zip(work.iter()).map(|(a, b)| a * b).sum();
    0.5 * (kinetic + strain)
}

#[allow(clippy::too_many_arguments)]
fn sample(
    model: &Model,
    mass: &Mass,
    step: usize,
    dt: f64,
    u: &[f64],
    v: &[f64],
    work: &mut [f64],
    ledger: &mut EnergyLedger,
    flows: &Flows,
    dt_crit: f64,
) -> Result<()> {
    mass.mul(v, work);
    let kinetic = 0.5 * v.iter().zip(work.iter()).map(|(a, b)| a * b).sum::<f64>();
    model.stiffness.mul(u, work);
    let strain = 0.5 * u.iter().zip(work.iter()).map(|(a, b)| a * b).sum::<f64>();
    if !(kinetic.is_finite() && strain.is_finite()) {
        return Err(Error::Unstable {
            step,
            time_s: step as f64 * dt,
            reason: "non-finite energy".into(),
            dt_s: dt,
            dt_crit_s: dt_crit,
        });
    }
    ledger.push(step as f64 * dt, kinetic, strain, flows);
    Ok(())
}
