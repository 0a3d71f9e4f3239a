//! The observers of a standard run: receiver traces, the energy ledger with blow-up detection,
//! crack-face traces, and displacement snapshots.

use super::ledger::EnergyLedger;
use super::stepper::{Fields, Observer, Stepper};
use super::{CrackTraces, Quantity, Receiver, Snapshot};
use crate::error::{Error, Result};
use crate::mesh::Crack;
use crate::signal::Signal;
use std::path::PathBuf;

/// Records every receiver at every step.
pub struct ReceiverTraces<'a> {
    receivers: &'a [Receiver],
    traces: Vec<Vec<f64>>,
}

impl<'a> ReceiverTraces<'a> {
    /// Room for `steps` samples per receiver, allocated now.
    pub fn new(receivers: &'a [Receiver], steps: usize) -> Self {
        ReceiverTraces {
            receivers,
            traces: receivers
                .iter()
                .map(|_| Vec::with_capacity(steps))
                .collect(),
        }
    }

    /// One signal per receiver from t = 0 at step `dt_s`.
    pub fn into_signals(self, dt_s: f64) -> Vec<Signal> {
        self.traces
            .into_iter()
            .map(|samples| Signal {
                dt_s,
                t0_s: 0.0,
                samples,
            })
            .collect()
    }
}

impl Observer for ReceiverTraces<'_> {
    fn after_step(&mut self, fields: &Fields<'_>) -> Result<()> {
        for (r, t) in self.receivers.iter().zip(&mut self.traces) {
            t.push(match r.quantity {
                Quantity::Displacement => fields.weighted_displacement(&r.weights),
                Quantity::Velocity => fields.weighted_velocity(&r.weights),
            });
        }
        Ok(())
    }
}

/// A run is declared unstable when its kinetic energy exceeds this multiple of the energy put in.
const BLOW_UP_FACTOR: f64 = 100.0;

/// The energy ledger (report Sec. 4.10.1) sampled every `every` steps and at the end; stops
/// a run whose energies turn non-finite or whose kinetic energy exceeds
/// [`BLOW_UP_FACTOR`] times the energy put in.
pub struct LedgerMonitor {
    /// The ledger so far.
    pub ledger: EnergyLedger,
    every: usize,
    dt_crit_s: f64,
}

impl LedgerMonitor {
    /// A ledger whose initial energy is the stepper's current energy; `dt_crit_s` is quoted
    /// when a run blows up.
    pub fn new(stepper: &mut dyn Stepper, every: usize, dt_crit_s: f64) -> Self {
        let e = stepper.energy(0);
        let ledger = EnergyLedger {
            initial_j: e.kinetic_j + e.strain_j + e.memory_j,
            ..EnergyLedger::default()
        };
        LedgerMonitor {
            ledger,
            every,
            dt_crit_s,
        }
    }

    fn sample(&mut self, step: usize, stepper: &mut dyn Stepper) -> Result<()> {
        let e = stepper.energy(step);
        let unstable = |reason: String| Error::Unstable {
            step,
            time_s: e.time_s,
            reason,
            dt_s: stepper.dt_s(),
            dt_crit_s: self.dt_crit_s,
        };
        if !(e.kinetic_j.is_finite() && e.strain_j.is_finite()) {
            return Err(unstable("displacements became non-finite".into()));
        }
        let budget = self.ledger.initial_j
            + self
                .ledger
                .source_work_j
                .iter()
                .fold(e.flows.source_work.abs(), |m, w| m.max(w.abs()));
        if e.kinetic_j > BLOW_UP_FACTOR * budget && e.kinetic_j > 0.0 {
            return Err(unstable(format!("kinetic energy {:.3e} J/m grew above {BLOW_UP_FACTOR} times the energy put in ({budget:.3e} J/m)", e.kinetic_j)));
        }
        self.ledger.push(&e);
        Ok(())
    }
}

impl Observer for LedgerMonitor {
    fn before_step(&mut self, step: usize, stepper: &mut dyn Stepper) -> Result<()> {
        if step.is_multiple_of(self.every) {
            self.sample(step, stepper)?;
        }
        Ok(())
    }
    fn end(&mut self, steps: usize, stepper: &mut dyn Stepper) -> Result<()> {
        self.sample(steps, stepper)
    }
}

/// Records the vertical displacement of both faces of every crack pair at every step.
pub struct CrackRecorder<'a> {
    crack: &'a Crack,
    master_uy: Vec<Vec<f64>>,
    slave_uy: Vec<Vec<f64>>,
}

impl<'a> CrackRecorder<'a> {
    /// Room for `steps` samples per face node, allocated now.
    pub fn new(crack: &'a Crack, steps: usize) -> Self {
        let room = || {
            crack
                .pairs
                .iter()
                .map(|_| Vec::with_capacity(steps))
                .collect()
        };
        CrackRecorder {
            crack,
            master_uy: room(),
            slave_uy: room(),
        }
    }

    /// The face traces and normal gaps as signals at step `dt_s`; `x_of_node` gives a node's x.
    pub fn into_traces(self, dt_s: f64, x_of_node: impl Fn(usize) -> f64) -> CrackTraces {
        let signal = |samples: Vec<f64>| Signal {
            dt_s,
            t0_s: 0.0,
            samples,
        };
        CrackTraces {
            x_m: self
                .crack
                .pairs
                .iter()
                .map(|p| x_of_node(p.master))
                .collect(),
            normal_gap: self
                .master_uy
                .iter()
                .zip(&self.slave_uy)
                .map(|(m, s)| signal(s.iter().zip(m).map(|(s, m)| s - m).collect()))
                .collect(),
            master_uy: self.master_uy.into_iter().map(signal).collect(),
            slave_uy: self.slave_uy.into_iter().map(signal).collect(),
        }
    }
}

impl Observer for CrackRecorder<'_> {
    fn after_step(&mut self, fields: &Fields<'_>) -> Result<()> {
        let u = fields.displacement;
        for ((p, m), s) in self
            .crack
            .pairs
            .iter()
            .zip(&mut self.master_uy)
            .zip(&mut self.slave_uy)
        {
            m.push(u[2 * p.master + 1]);
            s.push(u[2 * p.slave + 1]);
        }
        Ok(())
    }
}

/// Keeps a displacement snapshot every `every` steps: in memory, or streamed to
/// `snapshot_NNNNNNN.npy` files (2 values per node, step number in the name) in a directory.
pub struct SnapshotSink {
    every: usize,
    dir: Option<PathBuf>,
    /// Snapshots kept in memory (empty when streaming).
    pub snapshots: Vec<Snapshot>,
}

impl SnapshotSink {
    /// A snapshot every `every` steps, into `dir` when given.
    pub fn new(every: usize, dir: Option<PathBuf>) -> Self {
        SnapshotSink {
            every,
            dir,
            snapshots: Vec::new(),
        }
    }
}

impl Observer for SnapshotSink {
    fn after_step(&mut self, fields: &Fields<'_>) -> Result<()> {
        if !fields.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let u = fields.displacement;
        match &self.dir {
            Some(dir) => crate::io::write_npy(
                &dir.join(format!("snapshot_{:07}.npy", fields.step)),
                u,
                &[u.len() / 2, 2],
            )?,
            None => self.snapshots.push(Snapshot {
                time_s: fields.time_s(),
                displacement: u.to_vec(),
            }),
        }
        Ok(())
    }
}
