//! The memory variables of viscoelastic element rows ([`crate::attenuation`]): started,
//! probed for the ledger and emptied of their loss; the row kernel updates them in the
//! explicit step ([`Viscous`](crate::attenuation::memory::Viscous)), and Newmark takes their
//! history force, update and energy from the passes here.

use super::{RowWork, SemModel, SemWorkspace, LANES};
use crate::attenuation::memory::{History, PointLaw, Probe, Relax, RowMemory, Start, Stored};
use rayon::prelude::*;

impl SemModel {
    /// The shortest relaxation time of the element rows' materials (s); `None` where all are
    /// elastic.
    pub fn shortest_relaxation_s(&self) -> Option<f64> {
        crate::material::shortest_relaxation_s(
            self.row_material.iter().map(|&m| &self.materials[m]),
        )
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

    /// Newmark's history force G^T h_n from the memory and the strain of u_n = `u`, into `out`
    /// (zero on the elastic rows' nodes; [`crate::attenuation::memory`]); the memory is left as
    /// it was.
    pub(crate) fn history_forces(&self, u: &[f64], out: &mut [f64], work: &mut SemWorkspace) {
        let SemWorkspace { rows, memory, .. } = work;
        rows.par_iter_mut()
            .zip(memory.par_iter_mut())
            .enumerate()
            .for_each(|(r, (row, memory))| match memory {
                Some(m) => self.row_forces::<History, _>(r, u, row, m),
                None => row.force.fill(0.0),
            });
        self.gather_lines(rows, out);
    }

    /// Newmark's memory update to u_{n+1} = `u_next`, its loss added up.
    pub(crate) fn relax(&self, u_next: &[f64], work: &mut SemWorkspace) {
        self.memory_pass::<Relax>(u_next, work);
    }

    /// Newmark's memory energy at t_n from u_n = `u`, the memory left as it was.
    pub(crate) fn stored_energy(&self, u: &[f64], work: &mut SemWorkspace) -> f64 {
        for m in work.memory.iter_mut().flatten() {
            m.clear_energy();
        }
        self.memory_pass::<Stored>(u, work);
        work.memory.iter().flatten().map(RowMemory::energy).sum()
    }

    /// The rows' force lines gathered into `out` (every node line as [`SemModel::stiffness_times`]
    /// gathers it, without the springs).
    fn gather_lines(&self, rows: &[RowWork], out: &mut [f64]) {
        let nx = self.nx();
        let (grid, faces) = out.split_at_mut(2 * self.grid_nodes());
        grid.par_chunks_mut(2 * nx)
            .enumerate()
            .for_each(|(j, line)| self.node_line_forces(j, rows, line));
        if let Some(s) = &self.split {
            let top = self.gll_y[s.row_below].order() * 2 * nx;
            faces.copy_from_slice(
                &rows[s.row_below].force[top + 2 * s.first..top + 2 * (s.last + 1)],
            );
        }
    }

    /// The row kernel with law `L` (one without forces) over the viscoelastic rows, in parallel.
    fn memory_pass<L: PointLaw<LANES, RowMemory<LANES>>>(
        &self,
        u: &[f64],
        work: &mut SemWorkspace,
    ) {
        let SemWorkspace { rows, memory, .. } = work;
        rows.par_iter_mut()
            .zip(memory.par_iter_mut())
            .enumerate()
            .for_each(|(r, (row, memory))| {
                if let Some(m) = memory {
                    self.row_forces::<L, _>(r, u, row, m);
                }
            });
    }
}
