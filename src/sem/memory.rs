//! The memory variables of viscoelastic element rows ([`crate::attenuation`]): started,
//! probed for the ledger and emptied of their loss; the row kernel updates them in the step
//! ([`Viscous`](crate::attenuation::memory::Viscous)).

use super::{SemModel, SemWorkspace, LANES};
use crate::attenuation::memory::{PointLaw, Probe, RowMemory, Start};
use crate::material::Relaxation;

impl SemModel {
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
    pub(crate) fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut SemWorkspace) {
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
    pub(crate) fn take_viscous_loss(&self, work: &mut SemWorkspace) -> f64 {
        let mut loss = 0.0;
        for m in work.memory.iter_mut().flatten() {
            loss += m.take_loss();
        }
        loss
    }

    /// MEM_{n-1/2} (module docs) from u_n = `u`, the memory left as it was.
    pub(crate) fn memory_energy(&self, u: &[f64], work: &mut SemWorkspace) -> f64 {
        if work.memory.is_empty() {
            return 0.0;
        }
        for m in work.memory.iter_mut().flatten() {
            m.clear_energy();
        }
        self.memory_pass::<Probe>(u, work);
        work.memory.iter().flatten().map(RowMemory::energy).sum()
    }

    /// The row kernel with law `L` (one without forces) over the viscoelastic rows, in parallel.
    fn memory_pass<L: PointLaw<LANES, State = RowMemory<LANES>>>(
        &self,
        u: &[f64],
        work: &mut SemWorkspace,
    ) {
        use rayon::prelude::*;
        let SemWorkspace { rows, memory, .. } = work;
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
