//! The memory variables of viscoelastic triangles ([`crate::attenuation`]): a linear triangle
//! has one strain, so one quadrature point (its centroid, weight its area). The triangles of
//! each viscoelastic material are taken [`LANES`] at a time, with the memory laws the
//! spectral elements use ([`crate::attenuation::memory`]); their forces are gathered per node
//! in a fixed order, so results do not depend on the thread count.

use super::Model;
use crate::attenuation::memory::{
    History, PointLaw, Probe, Relax, RowMemory, Start, Stored, Viscous,
};
use rayon::prelude::*;

/// Triangles side by side in one pass of the memory laws.
const LANES: usize = 8;
/// Lane groups per parallel task.
const GROUPS_PER_CHUNK: usize = 256;
/// Nodes per parallel task of the force gather.
const NODES_PER_TASK: usize = 4096;

/// One lane of a group: a triangle's nodes and the gradients of its shape functions,
/// (b_k, c_k) = (y_j - y_l, x_l - x_j) / 2A (eps = B u_e, [`super::element::strain_displacement`]),
/// with its area; a padding lane has area 0 and node 0.
#[derive(Clone, Copy, Debug, Default)]
struct Lane {
    nodes: [usize; 3],
    b: [f64; 3],
    c: [f64; 3],
    area: f64,
}

/// Up to [`GROUPS_PER_CHUNK`] lane groups of one material with their memory, and the nodal
/// forces of the memory stress, B^T s per lane (u_x, u_y of the three vertices).
#[derive(Clone, Debug)]
struct Chunk {
    lanes: Vec<[Lane; LANES]>,
    memory: RowMemory<LANES>,
    forces: Vec<[[f64; 6]; LANES]>,
}

/// The memory of a T3 model's viscoelastic triangles at one time step, and where each node
/// gathers its forces from.
#[derive(Clone, Debug)]
pub struct T3Memory {
    chunks: Vec<Chunk>,
    /// `entries[start[n]..start[n + 1]]`: (chunk, group, lane, vertex) of node n's triangles.
    start: Vec<usize>,
    entries: Vec<(u32, u32, u8, u8)>,
}

impl T3Memory {
    /// Zero memory for the viscoelastic triangles of `model` at step `dt`, to be started
    /// ([`T3Memory::start`]); `None` where every material is elastic.
    pub fn new(model: &Model, dt: f64) -> Option<T3Memory> {
        let mut chunks = Vec::new();
        for (m, material) in model.materials.iter().enumerate() {
            let Some(relaxation) = &material.relaxation else {
                continue;
            };
            let triangles: Vec<usize> = (0..model.mesh.triangles.len())
                .filter(|&t| model.mesh.element_material[t] == m)
                .collect();
            for part in triangles.chunks(GROUPS_PER_CHUNK * LANES) {
                let lanes: Vec<[Lane; LANES]> = part
                    .chunks(LANES)
                    .map(|group| {
                        let mut lanes = [Lane::default(); LANES];
                        for (lane, &t) in lanes.iter_mut().zip(group) {
                            *lane = lane_of(model, t);
                        }
                        lanes
                    })
                    .collect();
                chunks.push(Chunk {
                    memory: RowMemory::new(relaxation, lanes.len(), dt),
                    forces: vec![[[0.0; 6]; LANES]; lanes.len()],
                    lanes,
                });
            }
        }
        if chunks.is_empty() {
            return None;
        }
        let mut memory = T3Memory {
            start: Vec::new(),
            entries: Vec::new(),
            chunks,
        };
        memory.index_nodes(model.mesh.nodes.len());
        Some(memory)
    }

    /// The previous strain from `u_prev` (eps_{-1} for central differences, eps_0 for
    /// Newmark); the memory stays as it is (zero when new).
    pub fn start(&mut self, u_prev: &[f64]) {
        self.pass::<Start>(u_prev);
    }

    /// The node -> (chunk, group, lane, vertex) lists, in chunk order.
    fn index_nodes(&mut self, nodes: usize) {
        let mut by_node: Vec<Vec<(u32, u32, u8, u8)>> = vec![Vec::new(); nodes];
        for (k, chunk) in self.chunks.iter().enumerate() {
            for (g, group) in chunk.lanes.iter().enumerate() {
                for (i, lane) in group.iter().enumerate().filter(|(_, l)| l.area > 0.0) {
                    for (v, &n) in lane.nodes.iter().enumerate() {
                        by_node[n].push((k as u32, g as u32, i as u8, v as u8));
                    }
                }
            }
        }
        self.start = std::iter::once(0)
            .chain(by_node.iter().scan(0, |s, e| {
                *s += e.len();
                Some(*s)
            }))
            .collect();
        self.entries = by_node.into_iter().flatten().collect();
    }

    /// The memory update of a step and its forces: u_next -= a .* (B^T s) with
    /// s = -A sum_l DC_l e_{l,n} (after the elastic update u_next = 2u - u_prev - a .* K_U u).
    pub fn relax(&mut self, a: &[f64], u: &[f64], u_next: &mut [f64]) {
        self.pass::<Viscous>(u);
        self.gather(u_next, |d, x, f| *x -= a[d] * f);
    }

    /// Each node's forces from its triangles' slots, in a fixed order, into `out` through
    /// `combine(dof, value, force)`.
    fn gather(&self, out: &mut [f64], combine: impl Fn(usize, &mut f64, f64) + Sync) {
        let (start, entries, chunks) = (&self.start, &self.entries, &self.chunks);
        out.par_chunks_mut(2 * NODES_PER_TASK)
            .enumerate()
            .for_each(|(block, values)| {
                for (k, pair) in values.chunks_exact_mut(2).enumerate() {
                    let n = block * NODES_PER_TASK + k;
                    let mut f = [0.0; 2];
                    for &(c, g, i, v) in &entries[start[n]..start[n + 1]] {
                        let forces = &chunks[c as usize].forces[g as usize][i as usize];
                        f[0] += forces[2 * v as usize];
                        f[1] += forces[2 * v as usize + 1];
                    }
                    combine(2 * n, &mut pair[0], f[0]);
                    combine(2 * n + 1, &mut pair[1], f[1]);
                }
            });
    }

    /// Newmark's history force G^T h_n from the memory and the strain of u_n = `u`, added to
    /// `rhs` ([`crate::attenuation::memory`]); the memory is left as it was.
    pub fn add_history_forces(&mut self, u: &[f64], rhs: &mut [f64]) {
        self.pass::<History>(u);
        self.gather(rhs, |_, x, f| *x += f);
    }

    /// Newmark's memory update to u_{n+1} = `u_next`, its loss added up.
    pub fn update(&mut self, u_next: &[f64]) {
        self.pass::<Relax>(u_next);
    }

    /// Newmark's memory energy at t_n from u_n = `u`, the memory unchanged.
    pub fn stored_energy(&mut self, u: &[f64]) -> f64 {
        for c in &mut self.chunks {
            c.memory.clear_energy();
        }
        self.pass::<Stored>(u);
        self.chunks.iter().map(|c| c.memory.energy()).sum()
    }

    /// The energy dissipated since the last call, in chunk order.
    pub fn take_loss(&mut self) -> f64 {
        self.chunks.iter_mut().map(|c| c.memory.take_loss()).sum()
    }

    /// MEM_{n-1/2} from u_n = `u` ([`crate::attenuation::memory`]), the memory unchanged.
    pub fn energy(&mut self, u: &[f64]) -> f64 {
        for c in &mut self.chunks {
            c.memory.clear_energy();
        }
        self.pass::<Probe>(u);
        self.chunks.iter().map(|c| c.memory.energy()).sum()
    }

    /// Law `L` at every group of every chunk (chunks in parallel): strains from `u`, the
    /// law's weighted stress, and with forces B^T s into the chunk's force slots.
    fn pass<L: PointLaw<LANES, RowMemory<LANES>>>(&mut self, u: &[f64]) {
        self.chunks.par_iter_mut().for_each(|chunk| {
            for (g, group) in chunk.lanes.iter().enumerate() {
                let [mut e_xx, mut e_yy, mut g_xy, mut area] = [[0.0; LANES]; 4];
                for (i, lane) in group.iter().enumerate() {
                    for k in 0..3 {
                        let (ux, uy) = (u[2 * lane.nodes[k]], u[2 * lane.nodes[k] + 1]);
                        e_xx[i] += lane.b[k] * ux;
                        e_yy[i] += lane.c[k] * uy;
                        g_xy[i] += lane.c[k] * ux + lane.b[k] * uy;
                    }
                    area[i] = lane.area;
                }
                let mut s = [[0.0; LANES]; 3];
                let [sxx, syy, sxy] = &mut s;
                L::at_point(
                    &mut chunk.memory,
                    g,
                    &area,
                    [&e_xx, &e_yy, &g_xy],
                    [sxx, syy, sxy],
                );
                if L::FORCES {
                    for (i, lane) in group.iter().enumerate() {
                        let f = &mut chunk.forces[g][i];
                        for k in 0..3 {
                            f[2 * k] = lane.b[k] * s[0][i] + lane.c[k] * s[2][i];
                            f[2 * k + 1] = lane.c[k] * s[1][i] + lane.b[k] * s[2][i];
                        }
                    }
                }
            }
        });
    }
}

/// Triangle `t` of `model` as a lane.
fn lane_of(model: &Model, t: usize) -> Lane {
    let nodes = model.mesh.triangles[t];
    let x = nodes.map(|n| model.mesh.nodes[n]);
    let twice_area =
        (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
    let mut lane = Lane {
        nodes,
        area: 0.5 * twice_area,
        ..Lane::default()
    };
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        lane.b[i] = (x[j][1] - x[k][1]) / twice_area;
        lane.c[i] = (x[k][0] - x[j][0]) / twice_area;
    }
    lane
}
