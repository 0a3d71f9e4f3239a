//! Time integration (report Sec. 4.8): explicit central difference with lumped mass
//! (eqs 65-69) and Newmark average acceleration (eq 61), with sources, receivers, the
//! energy ledger (Sec. 4.10.1), stability checks and a serialisable run report.
//!
//! The loop is built from parts a caller can use alone: a [`Discretisation`] (T3 [`Fem`] or
//! spectral elements), a [`Stepper`] over it ([`CentralDifference`], generic over the
//! contact law, or [`Newmark`]), [`Observer`]s ([`observers`]) and the one loop [`drive`].
//! [`run_on`] assembles the standard run of any discretisation from them, with the integrator
//! the run options name (Newmark on the body's own assembled [`NewmarkBody`]), and [`run`]
//! that of a T3 model.

mod contact_law;
pub mod discretisation;
pub mod explicit;
pub mod fourth_order;
mod ledger;
pub mod newmark;
pub mod observers;
mod placement;
pub mod progress;
pub mod stability;
pub mod stepper;
pub mod time_dispersion;

use crate::contact::{ContactOptions, ContactReport, ContactSeries, ContactSolver};
use crate::error::{require_positive, Error, Result};
use crate::fem::Model;
use crate::mesh::Crack;
use crate::signal::Signal;
pub use contact_law::{ContactLaw, NoContact};
pub use discretisation::{Discretisation, Fem, FemWorkspace, NodeBlock};
pub use explicit::{CentralDifference, Coefficients};
pub use ledger::{EnergyLedger, Flows};
pub use newmark::{Newmark, NewmarkBody};
use observers::{CrackRecorder, LedgerMonitor, ReceiverTraces, SnapshotSink};
pub use placement::{
    point_receiver, point_source, segment_receiver, segment_shares, traction_source,
};
use serde::{Deserialize, Serialize};
pub use stability::StabilityEstimate;
use std::time::Instant;
pub use stepper::{drive, EnergySample, Fields, Observer, Stepper, Velocity};

/// The default time step of every run as a fraction of its dt_crit (the Lanczos estimate is
/// at or slightly above the true limit; 10% margin): `RunConfig::step_fraction`, a scene's
/// default step, a script responder's `step_fraction`.
pub const STEP_FRACTION: f64 = 0.9;

/// The time step `fraction` x `dt_crit_s`, for a fraction in (0, 1]; otherwise an error
/// naming `step_fraction`. The one check of a step given as a fraction of dt_crit (a run's
/// and a responder's).
pub fn step_at_fraction(fraction: f64, dt_crit_s: f64) -> Result<f64> {
    if fraction > 0.0 && fraction <= 1.0 {
        Ok(fraction * dt_crit_s)
    } else {
        Err(Error::invalid(
            "step_fraction",
            fraction,
            "must be in (0, 1] (the time step as a fraction of dt_crit)",
        ))
    }
}

/// Which integrator advances the model.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Integrator {
    /// Central difference with lumped mass (eqs 65-69), conditionally stable.
    #[default]
    Explicit,
    /// Fourth-order modified-equation central difference ([`fourth_order`]): two stiffness
    /// products a step, stable to sqrt(3) times central differences' dt_crit; linear bodies
    /// without dashpots (absorbing or viscous-spring edges) and periodic edges.
    FourthOrder,
    /// Newmark average acceleration (eq 61), unconditionally stable, one sparse Cholesky.
    Newmark {
        /// Consistent (true) or lumped (false) mass.
        consistent_mass: bool,
    },
}

/// A force source: nodal weights times a signal (report Sec. 5.1: a traction on the
/// transmitter segment). The force on DOF d at time t is `weight_d * signal(t)`.
#[derive(Clone, Debug)]
pub struct Source {
    /// (DOF, weight): the traction direction times the node's share of the segment length (m).
    pub weights: Vec<(usize, f64)>,
    /// The traction history (Pa), resampled to the solver step when its interval differs.
    pub signal: Signal,
}

/// What a receiver records.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Displacement (m).
    #[default]
    Displacement,
    /// Velocity (m/s), central difference (u_{n+1} - u_{n-1}) / (2 dt).
    Velocity,
}

/// A receiver: a weighted average of DOFs (one node, or a transducer face).
#[derive(Clone, Debug)]
pub struct Receiver {
    /// Name used in outputs.
    pub name: String,
    /// (DOF, weight), weights summing to 1.
    pub weights: Vec<(usize, f64)>,
    /// Recorded quantity.
    pub quantity: Quantity,
}

/// Options of one run: the one run-options struct of the library and of scripts
/// (`scene.transmit(drive, #{duration_s, dt_s, ...})`); the fields scripts cannot set are
/// skipped by serde.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    /// Time step; `None` takes `step_fraction * dt_crit` (explicit) (s).
    pub dt_s: Option<f64>,
    /// Fraction of dt_crit used when `dt_s` is `None` (default [`STEP_FRACTION`]).
    pub step_fraction: f64,
    /// Simulated duration (s).
    pub duration_s: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Run even if dt > dt_crit (explicit), to study instability.
    pub force: bool,
    /// Evaluate the energy ledger and the blow-up check every this many steps.
    pub ledger_every: usize,
    /// Take a displacement snapshot every this many steps.
    pub snapshot_every: Option<usize>,
    /// Stream snapshots to `snapshot_NNNNNNN.npy` files (2 values per node, step number in
    /// the name) in this directory instead of keeping them in memory (scripts: under the
    /// output directory).
    pub snapshot_dir: Option<std::path::PathBuf>,
    /// Record the crack-face node traces.
    pub record_crack: bool,
    /// Contact on the crack faces; `None` leaves a crack open (faces pass through each other).
    pub contact: Option<ContactOptions>,
    /// Initial displacement (tests: free vibration), zero if `None`.
    #[serde(skip)]
    pub initial_displacement: Option<Vec<f64>>,
    /// Initial velocity, zero if `None`.
    #[serde(skip)]
    pub initial_velocity: Option<Vec<f64>>,
    /// Report progress to the installed [`progress::ProgressReporter`], if any.
    pub progress: bool,
}

impl RunConfig {
    /// Checks the snapshot options: `snapshot_every` at least 1, and `snapshot_dir` only with
    /// it (alone it would take no snapshot, silently).
    pub fn check_snapshots(&self) -> Result<()> {
        match (self.snapshot_every, &self.snapshot_dir) {
            (Some(0), _) => Err(Error::invalid("snapshot_every", 0, "must be at least 1")),
            (None, Some(dir)) => Err(Error::invalid(
                "snapshot_dir",
                dir.display(),
                "takes no snapshot without snapshot_every (set both)",
            )),
            _ => Ok(()),
        }
    }
}

impl Default for RunConfig {
    fn default() -> Self {
        RunConfig {
            dt_s: None,
            step_fraction: STEP_FRACTION,
            duration_s: 60e-6,
            integrator: Integrator::Explicit,
            force: false,
            ledger_every: 20,
            snapshot_every: None,
            snapshot_dir: None,
            record_crack: false,
            contact: None,
            initial_displacement: None,
            initial_velocity: None,
            progress: true,
        }
    }
}

/// What every run reports: cost and error indicators, scalars only (per-step series are
/// in [`RunOutput`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunReport {
    /// Integrator used.
    pub integrator: String,
    /// Wall-clock time of the time loop (s).
    pub wall_time_s: f64,
    /// Wall-clock time of setup: stability estimate, factorisation (s).
    pub setup_time_s: f64,
    /// Steps taken.
    pub steps: usize,
    /// Degrees of freedom.
    pub dofs: usize,
    /// Time step (s).
    pub dt_s: f64,
    /// Estimated critical explicit step (s).
    pub dt_crit_s: f64,
    /// dt / dt_crit (above 1 only when forced, or with Newmark).
    pub stability_ratio: f64,
    /// Final energy-balance residual relative to the input energy.
    pub energy_residual: f64,
    /// Largest relative energy-balance residual over the run.
    pub energy_residual_peak: f64,
    /// Work done by the sources (J per m of thickness).
    pub source_work_j: f64,
    /// Contact diagnostics, when contact was active.
    pub contact: Option<ContactReport>,
    /// The top of the band (Hz) over which the traces' time step error was removed
    /// ([`time_dispersion`]); `None`: the traces carry it.
    pub time_dispersion_removed_up_to_hz: Option<f64>,
}

/// Displacement of the crack faces at every step.
#[derive(Clone, Debug, Serialize)]
pub struct CrackTraces {
    /// x of each pair (m).
    pub x_m: Vec<f64>,
    /// Normal gap g_N = u_y(slave) - u_y(master) per pair, one signal each (m; > 0 is penetration).
    pub normal_gap: Vec<Signal>,
    /// Vertical displacement of the upper face (master) per pair (m).
    pub master_uy: Vec<Signal>,
    /// Vertical displacement of the lower face (slave) per pair (m).
    pub slave_uy: Vec<Signal>,
}

/// A full displacement field at one time.
#[derive(Clone, Debug, Serialize)]
pub struct Snapshot {
    /// Time (s).
    pub time_s: f64,
    /// Displacement, 2 values per node (m).
    pub displacement: Vec<f64>,
}

/// Everything a run produces.
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Cost and error indicators.
    pub report: RunReport,
    /// One trace per receiver, in receiver order, sampled at the solver step from t = 0.
    pub traces: Vec<Signal>,
    /// Receiver names, in order.
    pub receiver_names: Vec<String>,
    /// Crack-face traces when asked and there is a crack.
    pub crack: Option<CrackTraces>,
    /// Pairs in contact, sticking and slipping at every step, when contact was active.
    pub contact_series: Option<ContactSeries>,
    /// Snapshots when asked.
    pub snapshots: Vec<Snapshot>,
    /// Energy ledger time series.
    pub ledger: EnergyLedger,
}

/// The standard run of a T3 model ([`run_on`] its [`Fem`]) at its critical step, estimated
/// here ([`stability::estimate`]; a caller that knows it calls [`run_on`]).
pub fn run(
    model: &Model,
    sources: &[Source],
    receivers: &[Receiver],
    config: &RunConfig,
) -> Result<RunOutput> {
    let setup = Instant::now();
    validate(model.dofs(), sources, receivers, config)?;
    let stab = stability::estimate(model);
    let fem = Fem::new(model);
    run_validated(&fem, stab.dt_crit_s, (sources, receivers), config, setup)
}

/// The standard run of any discretisation (linear triangles, spectral elements, or a custom
/// one) with the integrator `config.integrator` names: central differences, with the body's
/// crack ([`Discretisation::crack`]) under `config.contact`; the fourth-order step; or
/// Newmark on the body's assembled stiffness ([`Discretisation::newmark_body`], contact and
/// periodic edges refused). The same loop, observers, checks and report whatever the body.
/// `dt_crit_s` is the body's explicit critical step (e.g. [`stability::estimate`], or
/// [`crate::sem::SemModel::max_eigenvalue`]).
pub fn run_on<D: Discretisation>(
    body: &D,
    dt_crit_s: f64,
    sources: &[Source],
    receivers: &[Receiver],
    config: &RunConfig,
) -> Result<RunOutput> {
    let setup = Instant::now();
    body.check()?;
    validate(body.dofs(), sources, receivers, config)?;
    run_validated(body, dt_crit_s, (sources, receivers), config, setup)
}

/// [`run_on`] once the body and the run's options are checked, the clock started at `setup`:
/// the integrator chosen here, once.
fn run_validated<D: Discretisation>(
    body: &D,
    dt_crit_s: f64,
    io: (&[Source], &[Receiver]),
    config: &RunConfig,
    setup: Instant,
) -> Result<RunOutput> {
    let node_x = |node: usize| body.node_x(node);
    let shape = BodyShape {
        dofs: body.dofs(),
        crack: body.crack(),
        node_x: &node_x,
    };
    match config.integrator {
        Integrator::Explicit | Integrator::FourthOrder => {
            central_difference(body, shape, dt_crit_s, io, config, setup)
        }
        Integrator::Newmark { consistent_mass } => {
            if !body.periodic_ties().is_empty() {
                return Err(Error::invalid(
                    "integrator",
                    "newmark",
                    "periodic edges are implemented for the explicit integrator only",
                ));
            }
            refuse_newmark_contact(config, body.crack())?;
            let dt = newmark_step(body, config)?;
            let assembled = body.newmark_body(consistent_mass, dt)?;
            newmark(assembled, shape, (dt, dt_crit_s), io, config, setup)
        }
    }
}

/// Newmark's step: the one the run gives (Newmark has no critical step to take a fraction
/// of), checked against the memory variables' shortest relaxation time.
fn newmark_step<D: Discretisation>(body: &D, config: &RunConfig) -> Result<f64> {
    let dt = config
        .dt_s
        .ok_or_else(|| Error::invalid("dt_s", "none", "Newmark needs an explicit time step"))?;
    if let Some(tau) = body.shortest_relaxation_s() {
        crate::attenuation::check_step(tau, dt)?;
    }
    Ok(dt)
}

/// Refuses Newmark on a body whose crack the run asks to make contact (the contact laws
/// correct the explicit predictor only).
fn refuse_newmark_contact(config: &RunConfig, crack: Option<&Crack>) -> Result<()> {
    if config.contact.is_some() && crack.is_some() {
        return Err(Error::invalid(
            "integrator",
            "newmark",
            "contact is implemented for the explicit integrator only",
        ));
    }
    Ok(())
}

/// Checks the run options, the sources' and receivers' DOFs and weights, and the initial
/// fields against a body of `dofs` DOFs, naming the first field that is wrong.
fn validate(
    dofs: usize,
    sources: &[Source],
    receivers: &[Receiver],
    config: &RunConfig,
) -> Result<()> {
    require_positive("duration_s", config.duration_s)?;
    if let Some(dt) = config.dt_s {
        require_positive("dt_s", dt)?;
    }
    step_at_fraction(config.step_fraction, 1.0)?;
    if config.ledger_every == 0 {
        return Err(Error::invalid("ledger_every", 0, "must be at least 1"));
    }
    config.check_snapshots()?;
    validate_weights(dofs, sources.iter().map(|s| ("source", &s.weights)))?;
    validate_weights(dofs, receivers.iter().map(|r| ("receiver", &r.weights)))?;
    for (field, initial) in [
        ("initial_displacement", &config.initial_displacement),
        ("initial_velocity", &config.initial_velocity),
    ] {
        if let Some(x) = initial {
            if x.len() != dofs || x.iter().any(|v| !v.is_finite()) {
                return Err(Error::invalid(
                    field,
                    format!("{} values", x.len()),
                    format!("needs {dofs} finite values"),
                ));
            }
        }
    }
    Ok(())
}

fn validate_weights<'a>(
    dofs: usize,
    sets: impl Iterator<Item = (&'a str, &'a Vec<(usize, f64)>)>,
) -> Result<()> {
    for (i, (what, w)) in sets.enumerate() {
        if w.is_empty() {
            return Err(Error::invalid(
                format!("{what}[{i}]"),
                "no DOFs",
                "selects no node of the mesh",
            ));
        }
        if let Some(&(d, v)) = w.iter().find(|(d, v)| *d >= dofs || !v.is_finite()) {
            return Err(Error::invalid(
                format!("{what}[{i}]"),
                format!("DOF {d} weight {v}"),
                format!("DOF must be < {dofs} and weight finite"),
            ));
        }
    }
    Ok(())
}

/// The number of steps of a run of `duration_s` at `dt`, refused (naming `duration_s` or `dt_s`
/// with the estimate) when the traces, sources, crack records and snapshots it would keep
/// exceed the memory limit ([`crate::budget::check_memory`]); estimated before allocating.
fn run_steps(
    body: BodyShape<'_>,
    sources: usize,
    receivers: usize,
    config: &RunConfig,
    dt: f64,
) -> Result<usize> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::invalid(
            "dt_s",
            dt,
            "the time step is not a finite positive number (dt_crit not finite: check the materials' densities and moduli)",
        ));
    }
    let steps = step_count(config.duration_s, dt) as f64;
    let crack_pairs = body.crack.map_or(0, |c| c.pairs.len()) as f64;
    let per_step = 8.0
        * (sources as f64
            + receivers as f64
            + if config.record_crack {
                2.0 * crack_pairs
            } else {
                0.0
            }
            + if config.contact.is_some() { 3.0 } else { 0.0 });
    let ledger = 8.0 * 9.0 * steps / config.ledger_every.max(1) as f64;
    let snapshots = match (config.snapshot_every, &config.snapshot_dir) {
        (Some(k), None) => 8.0 * body.dofs as f64 * (steps / k.max(1) as f64).ceil(),
        _ => 0.0,
    };
    let bytes = per_step * steps + ledger + snapshots;
    let (field, value) = match config.dt_s {
        Some(d) if d < 1e-12 => ("dt_s", format!("{d} s")),
        _ => ("duration_s", format!("{} s", config.duration_s)),
    };
    crate::budget::check_memory(
        field,
        format!("{value} ({steps:.3e} steps of {dt:.3e} s)"),
        bytes,
        "shorten the run, take a larger step, or stream snapshots with snapshot_dir",
    )?;
    if steps > (u32::MAX as f64) {
        return Err(Error::invalid(
            field,
            value,
            format!("gives {steps:.3e} steps, more than {}", u32::MAX),
        ));
    }
    Ok(steps as usize)
}

/// The steps of a run of `duration_s` at `dt` (at least one): the samples of its traces.
pub fn step_count(duration_s: f64, dt: f64) -> usize {
    (duration_s / dt).round().max(1.0) as usize
}

/// The sources with their signals evaluated at every solver step t_n = n dt, n < steps
/// (resampled first when a signal's interval differs from dt; zero outside the signal).
pub struct SampledSources<'a> {
    sources: &'a [Source],
    values: Vec<Vec<f64>>,
}

impl<'a> SampledSources<'a> {
    /// Samples `sources` at `steps` steps of `dt`.
    pub fn new(sources: &'a [Source], dt: f64, steps: usize) -> Result<Self> {
        let values = sources
            .iter()
            .map(|s| {
                let sig = if ((s.signal.dt_s - dt) / dt).abs() < 1e-9 {
                    s.signal.clone()
                } else {
                    crate::signal::resample(&s.signal, dt)?
                };
                Ok((0..steps)
                    .map(|n| {
                        let k = ((n as f64 * dt - sig.t0_s) / dt).round();
                        if k >= 0.0 && (k as usize) < sig.samples.len() {
                            sig.samples[k as usize]
                        } else {
                            0.0
                        }
                    })
                    .collect())
            })
            .collect::<Result<_>>()?;
        Ok(SampledSources { sources, values })
    }

    /// Each source's (DOF, weight) pairs with its force values per step.
    pub fn iter(&self) -> impl Iterator<Item = (&[(usize, f64)], &[f64])> {
        self.sources
            .iter()
            .zip(&self.values)
            .map(|(s, v)| (s.weights.as_slice(), v.as_slice()))
    }

    /// out_d += w_d f(t_step) for every source.
    pub fn add_forces(&self, step: usize, out: &mut [f64]) {
        for (weights, values) in self.iter() {
            for &(d, w) in weights {
                out[d] += w * values[step];
            }
        }
    }
}

/// What a standard run needs to know of the body besides its discretisation.
#[derive(Clone, Copy)]
struct BodyShape<'a> {
    dofs: usize,
    crack: Option<&'a Crack>,
    /// x of a node (m), for the crack traces.
    node_x: &'a dyn Fn(usize) -> f64,
}

/// The observers of a standard run, as [`RunConfig`] asks for them.
struct StandardObservers<'a> {
    receivers: ReceiverTraces<'a>,
    ledger: LedgerMonitor,
    crack: Option<CrackRecorder<'a>>,
    snapshots: Option<SnapshotSink>,
}

impl<'a> StandardObservers<'a> {
    fn new(
        body: BodyShape<'a>,
        receivers: &'a [Receiver],
        config: &RunConfig,
        steps: usize,
        stepper: &mut dyn Stepper,
        dt_crit_s: f64,
    ) -> Self {
        StandardObservers {
            receivers: ReceiverTraces::new(receivers, steps),
            ledger: LedgerMonitor::new(stepper, config.ledger_every, dt_crit_s),
            crack: body
                .crack
                .filter(|_| config.record_crack)
                .map(|c| CrackRecorder::new(c, steps)),
            snapshots: config
                .snapshot_every
                .map(|k| SnapshotSink::new(k, config.snapshot_dir.clone())),
        }
    }

    /// Runs `steps` steps of `stepper` under these observers (ledger first, as it samples
    /// the state before each step).
    fn drive(
        &mut self,
        stepper: &mut dyn Stepper,
        steps: usize,
        show_progress: bool,
    ) -> Result<()> {
        let mut observers: Vec<&mut dyn Observer> = vec![&mut self.ledger, &mut self.receivers];
        if let Some(c) = self.crack.as_mut() {
            observers.push(c);
        }
        if let Some(s) = self.snapshots.as_mut() {
            observers.push(s);
        }
        let mut progress = progress::start(show_progress, steps);
        drive(stepper, steps, &mut observers, &mut progress)
    }

    /// The run's output around its report.
    fn output(
        self,
        body: BodyShape<'_>,
        receivers: &[Receiver],
        report: RunReport,
        contact_series: Option<ContactSeries>,
    ) -> RunOutput {
        let dt = report.dt_s;
        RunOutput {
            traces: self.receivers.into_signals(dt),
            receiver_names: receivers.iter().map(|r| r.name.clone()).collect(),
            crack: self.crack.map(|c| c.into_traces(dt, body.node_x)),
            contact_series,
            snapshots: self.snapshots.map(|s| s.snapshots).unwrap_or_default(),
            ledger: self.ledger.ledger,
            report,
        }
    }
}

/// What both integrators report, from the ledger and the clocks.
fn report(
    integrator: String,
    ledger: &EnergyLedger,
    times: (f64, f64),
    steps: usize,
    dofs: usize,
    (dt_s, dt_crit_s): (f64, f64),
) -> RunReport {
    RunReport {
        integrator,
        wall_time_s: times.1,
        setup_time_s: times.0,
        steps,
        dofs,
        dt_s,
        dt_crit_s,
        stability_ratio: dt_s / dt_crit_s,
        energy_residual: ledger.final_residual(),
        energy_residual_peak: ledger.peak_residual(),
        source_work_j: ledger.source_work_j.last().copied().unwrap_or(0.0),
        contact: None,
        time_dispersion_removed_up_to_hz: None,
    }
}

/// The explicit run: step, steps, the contact law chosen once here (so the loop of a body
/// without a contacting crack is compiled without contact), the stepper and its observers.
fn central_difference<D: Discretisation>(
    disc: &D,
    body: BodyShape<'_>,
    dt_crit_s: f64,
    (sources, receivers): (&[Source], &[Receiver]),
    config: &RunConfig,
    setup: Instant,
) -> Result<RunOutput> {
    if config.integrator == Integrator::FourthOrder {
        return fourth_order(disc, body, dt_crit_s, (sources, receivers), config, setup);
    }
    let Explicit {
        dt,
        steps,
        coef,
        forced,
    } = Explicit::new(disc, body, dt_crit_s, (sources, receivers), config)?;
    let (u0, v0) = (
        config.initial_displacement.as_deref(),
        config.initial_velocity.as_deref(),
    );
    let run = (body, receivers, config, steps, dt_crit_s, setup);
    match (body.crack, &config.contact) {
        (Some(crack), Some(options)) => {
            let solver = ContactSolver::new(crack, &coef.compliance, *options, steps, dt)?;
            let stepper = CentralDifference::new(disc, coef, dt, forced, solver, u0, v0);
            finish_explicit(stepper, run)
        }
        _ => {
            let stepper = CentralDifference::new(disc, coef, dt, forced, NoContact, u0, v0);
            finish_explicit(stepper, run)
        }
    }
}

/// What both explicit schemes set up before stepping: the step (at most `dt_crit_s` unless
/// forced), the number of steps, the per-DOF constants and the sampled sources.
struct Explicit<'a> {
    dt: f64,
    steps: usize,
    coef: Coefficients,
    forced: SampledSources<'a>,
}

impl<'a> Explicit<'a> {
    fn new<D: Discretisation>(
        disc: &D,
        body: BodyShape<'_>,
        dt_crit_s: f64,
        (sources, receivers): (&'a [Source], &[Receiver]),
        config: &RunConfig,
    ) -> Result<Explicit<'a>> {
        let dt = match config.dt_s {
            Some(dt) => dt,
            None => step_at_fraction(config.step_fraction, dt_crit_s)?,
        };
        if let Some(tau) = disc.shortest_relaxation_s() {
            crate::attenuation::check_step(tau, dt)?;
        }
        let ratio = dt / dt_crit_s;
        if ratio > 1.0 && !config.force {
            return Err(Error::StepTooLarge {
                dt_s: dt,
                dt_crit_s,
                ratio,
            });
        }
        let steps = run_steps(body, sources.len(), receivers.len(), config, dt)?;
        Ok(Explicit {
            dt,
            steps,
            coef: Coefficients::new(disc, dt),
            forced: SampledSources::new(sources, dt, steps)?,
        })
    }
}

/// The fourth-order run ([`fourth_order::FourthOrder`]): its dt_crit is sqrt(3) times
/// central differences'; contact, periodic ties, dashpots and losses are refused, naming the
/// integrator.
fn fourth_order<D: Discretisation>(
    disc: &D,
    body: BodyShape<'_>,
    dt_crit_s: f64,
    (sources, receivers): (&[Source], &[Receiver]),
    config: &RunConfig,
    setup: Instant,
) -> Result<RunOutput> {
    let refuse = |why: &str| Err(Error::invalid("integrator", "fourth_order", why));
    if body.crack.is_some() && config.contact.is_some() {
        return refuse("contact is implemented for the central difference (explicit) only");
    }
    if !disc.periodic_ties().is_empty() {
        return refuse("periodic edges are implemented for the central difference (explicit) only");
    }
    if disc.shortest_relaxation_s().is_some() {
        return refuse(
            "losses have no fourth-order form, by design: its correction K M^-1 K u would \
             apply the memory variables' stress twice at different times, and their update \
             is second order; run losses with the explicit or the newmark integrator",
        );
    }
    if !disc.dashpots().is_empty() || !disc.coupled_dashpots().is_empty() {
        return refuse(
            "absorbing and viscous-spring edges (dashpots) are not implemented for it: its \
             correction K M^-1 K u, left without the dashpots' term, changes their boundary \
             condition by O(dt^2 omega_max^2) and they reflect more than with the central \
             difference (explicit)",
        );
    }
    let dt_crit_s = fourth_order::STABILITY_GAIN * dt_crit_s;
    let Explicit {
        dt,
        steps,
        coef,
        forced,
    } = Explicit::new(disc, body, dt_crit_s, (sources, receivers), config)?;
    let (u0, v0) = (
        config.initial_displacement.as_deref(),
        config.initial_velocity.as_deref(),
    );
    let mut stepper = fourth_order::FourthOrder::new(disc, coef, dt, forced, u0, v0);
    let run = (body, receivers, config, steps, dt_crit_s, setup);
    let (observers, report) = drive_standard(
        &mut stepper,
        "fourth-order modified-equation central difference (lumped mass)",
        run,
    )?;
    Ok(observers.output(body, receivers, report, None))
}

/// Drives `stepper` with the standard observers and reports it under `name`.
fn drive_standard<'a>(
    stepper: &mut dyn Stepper,
    name: &str,
    (body, receivers, config, steps, dt_crit, setup): RunParts<'a>,
) -> Result<(StandardObservers<'a>, RunReport)> {
    let mut observers = StandardObservers::new(body, receivers, config, steps, stepper, dt_crit);
    let setup_time_s = setup.elapsed().as_secs_f64();
    let clock = Instant::now();
    observers.drive(stepper, steps, config.progress)?;
    let times = (setup_time_s, clock.elapsed().as_secs_f64());
    let report = report(
        name.into(),
        &observers.ledger.ledger,
        times,
        steps,
        body.dofs,
        (stepper.dt_s(), dt_crit),
    );
    Ok((observers, report))
}

/// What a standard run needs besides its stepper: the body, receivers, options, steps,
/// dt_crit and the clock started at setup.
type RunParts<'a> = (
    BodyShape<'a>,
    &'a [Receiver],
    &'a RunConfig,
    usize,
    f64,
    Instant,
);

/// Drives a central-difference stepper with the standard observers and reports.
fn finish_explicit<D: Discretisation, C: ContactLaw>(
    mut stepper: CentralDifference<'_, D, C>,
    run: RunParts<'_>,
) -> Result<RunOutput> {
    let (body, receivers, _, steps, _, _) = run;
    let name = "explicit central difference (lumped mass)";
    let (observers, mut report) = drive_standard(&mut stepper, name, run)?;
    let dt = stepper.dt_s();
    let (contact, series) = stepper.finish().finish(steps, dt).unzip();
    report.contact = contact;
    Ok(observers.output(body, receivers, report, series))
}

/// The Newmark run: steps, the stepper (one factorisation) and its observers.
fn newmark(
    body: NewmarkBody<'_>,
    shape: BodyShape<'_>,
    (dt, dt_crit_s): (f64, f64),
    (sources, receivers): (&[Source], &[Receiver]),
    config: &RunConfig,
    setup: Instant,
) -> Result<RunOutput> {
    let steps = run_steps(shape, sources.len(), receivers.len(), config, dt)?;
    let forced = SampledSources::new(sources, dt, steps + 1)?;
    let integrator = format!("Newmark average acceleration ({} mass)", body.mass.name());
    let mut stepper = Newmark::new(
        body,
        dt,
        forced,
        config.initial_displacement.as_deref(),
        config.initial_velocity.as_deref(),
    )?;
    let mut observers =
        StandardObservers::new(shape, receivers, config, steps, &mut stepper, dt_crit_s);
    let setup_time_s = setup.elapsed().as_secs_f64();
    let clock = Instant::now();
    observers.drive(&mut stepper, steps, config.progress)?;
    let times = (setup_time_s, clock.elapsed().as_secs_f64());
    let report = report(
        integrator,
        &observers.ledger.ledger,
        times,
        steps,
        shape.dofs,
        (dt, dt_crit_s),
    );
    Ok(observers.output(shape, receivers, report, None))
}
