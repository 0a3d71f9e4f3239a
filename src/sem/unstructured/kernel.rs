//! K u on unstructured spectral elements, and the model as the time steppers see it.
//!
//! Per element, with u at its GLL points (i along xi, j along eta):
//!   du/dxi (i, j) = sum_k D[i][k] u(k, j),  du/deta (i, j) = sum_k D[j][k] u(i, k),
//!   grad u = du/dxi grad xi + du/deta grad eta,  sigma = C eps(u)  (Voigt, eps_xy engineering),
//! and the weak form's internal force at point (i, j) (Komatitsch and Tromp 1999, eq. 32):
//!   f(i, j) = sum_k D[k][i] F_xi(k, j) + sum_l D[l][j] F_eta(i, l),
//!   F_xi = w det J sigma . grad xi,  F_eta = w det J sigma . grad eta.

use super::{GroupMemory, Lanes, UnstructuredSem, LANES};
use crate::attenuation::memory::{Elastic, PointLaw, Viscous};
use crate::solve::{Discretisation, NodeBlock};
use rayon::prelude::*;

/// Elements per parallel task of the element pass, nodes per task of the gather.
const ELEMENT_CHUNK: usize = 64;
const NODE_CHUNK: usize = 4096;

/// Runs `$body` with the const `$n` = the number of GLL points per direction, order + 1
/// (1..=16 checked when the model was built): the element kernel is compiled per order, so
/// its loops have fixed lengths and its arrays live on the stack at their own size.
macro_rules! with_points {
    ($order:expr, $n:ident => $body:expr) => {
        match $order + 1 {
            2 => {
                const $n: usize = 2;
                $body
            }
            3 => {
                const $n: usize = 3;
                $body
            }
            4 => {
                const $n: usize = 4;
                $body
            }
            5 => {
                const $n: usize = 5;
                $body
            }
            6 => {
                const $n: usize = 6;
                $body
            }
            7 => {
                const $n: usize = 7;
                $body
            }
            8 => {
                const $n: usize = 8;
                $body
            }
            9 => {
                const $n: usize = 9;
                $body
            }
            10 => {
                const $n: usize = 10;
                $body
            }
            11 => {
                const $n: usize = 11;
                $body
            }
            12 => {
                const $n: usize = 12;
                $body
            }
            13 => {
                const $n: usize = 13;
                $body
            }
            14 => {
                const $n: usize = 14;
                $body
            }
            15 => {
                const $n: usize = 15;
                $body
            }
            16 => {
                const $n: usize = 16;
                $body
            }
            17 => {
                const $n: usize = 17;
                $body
            }
            n => unreachable!("{n} GLL points: the model checks its order is 1..=16"),
        }
    };
}

/// The scratch of [`UnstructuredSem::stiffness_times`]: every element point's force (x, y),
/// lane-major as the kernel writes it (`UnstructuredSem::lane_global`'s slots), allocated once
/// per run; and the memory variables of each lane group, `Some` where one of its elements is
/// viscoelastic (empty until a run starts them: [`UnstructuredSem::start_memory`]).
#[derive(Clone, Debug)]
pub struct UnstructuredWorkspace {
    point_forces: Vec<[f64; 2]>,
    pub(super) memory: Vec<Option<GroupMemory>>,
}

impl UnstructuredSem {
    /// The scratch of [`UnstructuredSem::stiffness_times`].
    pub fn workspace(&self) -> UnstructuredWorkspace {
        UnstructuredWorkspace {
            point_forces: vec![[0.0; 2]; self.lane_global.len()],
            memory: Vec::new(),
        }
    }

    /// `out = K u` (K of the unrelaxed stiffness C_U where a material is viscoelastic),
    /// bit-identical for any number of threads (see the module's doc).
    pub fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut UnstructuredWorkspace) {
        let forces = &mut work.point_forces;
        with_points!(self.order, N => self.law_pass::<N, Elastic>(u, forces, &mut []));
        self.gather(u, out, work, |_, ku| ku);
    }

    /// The central-difference predictor u_next = 2 u - u_prev - a .* (K u) (report eq 69),
    /// fused into the gather of K u: one pass over the nodes instead of two. Where the run
    /// started memory variables, K u includes their stress and the step updates them
    /// ([`Viscous`]).
    pub fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut UnstructuredWorkspace,
    ) {
        let UnstructuredWorkspace {
            point_forces,
            memory,
        } = work;
        with_points!(self.order, N => self.law_pass::<N, Viscous>(u, point_forces, memory));
        self.gather(u, u_next, work, |d, ku| 2.0 * u[d] - u_prev[d] - a[d] * ku);
    }

    /// Sums each node's element forces (in the fixed order of its incidence list) and its
    /// springs into (K u)_d and writes `finish(d, (K u)_d)` to `out[d]`, in parallel over
    /// chunks of nodes. The springs are sorted by node, each node once ([`Self::check`]).
    fn gather(
        &self,
        u: &[f64],
        out: &mut [f64],
        work: &UnstructuredWorkspace,
        finish: impl Fn(usize, f64) -> f64 + Sync,
    ) {
        let forces = &work.point_forces;
        out.par_chunks_mut(2 * NODE_CHUNK)
            .enumerate()
            .for_each(|(chunk, out)| {
                let first = chunk * NODE_CHUNK;
                let mut spring = self.springs.partition_point(|&(node, _)| node < first);
                for (k, f) in out.chunks_mut(2).enumerate() {
                    let g = first + k;
                    let held =
                        &self.incidence[self.incidence_start[g]..self.incidence_start[g + 1]];
                    let mut ku = [0.0; 2];
                    for &p in held {
                        ku[0] += forces[p][0];
                        ku[1] += forces[p][1];
                    }
                    if let Some(&(_, k)) = self.springs.get(spring).filter(|s| s.0 == g) {
                        let (x, y) = (u[2 * g], u[2 * g + 1]);
                        ku[0] += k[0][0] * x + k[0][1] * y;
                        ku[1] += k[1][0] * x + k[1][1] * y;
                        spring += 1;
                    }
                    f[0] = finish(2 * g, ku[0]);
                    f[1] = finish(2 * g + 1, ku[1]);
                }
            });
    }

    /// Checks the model's own data before a run, naming the field that is wrong: fixed DOFs,
    /// dashpots, springs and ties name DOFs or nodes of the model; the dashpots and springs
    /// are sorted by node, each node once (as the gather and the stepper read them); no
    /// crack pair sits on a dashpot coupling x and y (its gap's compliance would couple them)
    /// or on a periodic tie, and no dashpot's node is on a tie but both of its DOFs' (as
    /// periodic edges tie them).
    pub fn check(&self) -> crate::error::Result<()> {
        use crate::error::Error;
        let n = self.dofs();
        let outside = |field: &str, d: usize| {
            Error::invalid(field, d, format!("is not a DOF of this model ({n} DOFs)"))
        };
        if let Some(&d) = self.fixed_dofs.iter().find(|&&d| d >= n) {
            return Err(outside("fixed_dofs", d));
        }
        if let Some(&(l, r)) = self.periodic.iter().find(|&&(l, r)| l.max(r) >= n) {
            return Err(outside("periodic", l.max(r)));
        }
        for (field, blocks) in [("dashpots", &self.dashpots), ("springs", &self.springs)] {
            if let Some(&(node, _)) = blocks.iter().find(|&&(node, _)| 2 * node >= n) {
                return Err(Error::invalid(
                    field,
                    node,
                    format!("is not a node of this model ({} nodes)", n / 2),
                ));
            }
            if let Some(w) = blocks.windows(2).find(|w| w[0].0 >= w[1].0) {
                return Err(Error::invalid(
                    field,
                    w[1].0,
                    "must be sorted by node, each node once",
                ));
            }
        }
        self.check_crack_placement()
    }

    /// No crack pair sits on a dashpot coupling x and y or on a periodic tie, and no
    /// dashpot's node has one DOF tied alone (for [`Self::check`], after the dashpots' order).
    fn check_crack_placement(&self) -> crate::error::Result<()> {
        use crate::error::Error;
        let coupled = |node: usize| {
            let at = self.dashpots.binary_search_by_key(&node, |b| b.0);
            at.is_ok_and(|k| self.dashpots[k].1[0][1] != 0.0)
        };
        if let Some(pair) = self
            .crack
            .iter()
            .flat_map(|c| &c.pairs)
            .find(|p| coupled(p.master) || coupled(p.slave))
        {
            return Err(Error::invalid(
                "dashpots",
                format!("nodes {} and {}", pair.master, pair.slave),
                "a crack pair sits where the absorbing boundary's dashpots couple x and y (an \
                 inclined or curved absorbing line, or a turned material): a crack may reach \
                 an absorbing side only where the dashpots act along x and y apart",
            ));
        }
        let tied: std::collections::BTreeSet<usize> =
            self.periodic.iter().flat_map(|&(l, r)| [l, r]).collect();
        if let Some(pair) = self
            .crack
            .iter()
            .flat_map(|c| &c.pairs)
            .find(|p| tied.contains(&(2 * p.master)) || tied.contains(&(2 * p.slave)))
        {
            return Err(Error::invalid(
                "edges.left, edges.right",
                "periodic",
                format!(
                    "the crack reaches a periodic edge at nodes {} and {}: its faces' nodes \
                     there have no single partner across the cell (a crack may cross the \
                     cell's inside only)",
                    pair.master, pair.slave
                ),
            ));
        }
        if let Some(&(node, _)) = self
            .dashpots
            .iter()
            .find(|&&(node, _)| tied.contains(&(2 * node)) != tied.contains(&(2 * node + 1)))
        {
            return Err(Error::invalid(
                "dashpots",
                node,
                "is on a node with one DOF tied: ties must hold both of a damped node's DOFs",
            ));
        }
        Ok(())
    }

    /// The derivative matrix as an N x N array, D[i][k] = l_k'(x_i).
    fn derivative_array<const N: usize>(&self) -> [[f64; N]; N] {
        let mut d = [[0.0; N]; N];
        for (i, row) in d.iter_mut().enumerate() {
            row.copy_from_slice(&self.derivative[i * N..(i + 1) * N]);
        }
        d
    }

    /// The element kernel with law `L` (one without forces: [`crate::attenuation::memory`]'s
    /// Start and Probe) over the lane groups with memory.
    pub(super) fn memory_pass<L: PointLaw<LANES, GroupMemory>>(
        &self,
        u: &[f64],
        work: &mut UnstructuredWorkspace,
    ) {
        let UnstructuredWorkspace {
            point_forces,
            memory,
        } = work;
        with_points!(self.order, N => self.law_pass::<N, L>(u, point_forces, memory));
    }

    /// Every element's forces at its points from `u` (for a law with forces), in parallel
    /// over chunks of elements, LANES elements at a time: the lane groups with memory
    /// variables in `memory` (empty where the run has none) with point law `L`, the others
    /// elastic.
    fn law_pass<const N: usize, L: PointLaw<LANES, GroupMemory>>(
        &self,
        u: &[f64],
        point_forces: &mut [[f64; 2]],
        memory: &mut [Option<GroupMemory>],
    ) {
        let d = self.derivative_array::<N>();
        let groups = ELEMENT_CHUNK / LANES;
        let chunks = point_forces.par_chunks_mut(ELEMENT_CHUNK * N * N);
        if memory.is_empty() {
            chunks.enumerate().for_each(|(chunk, forces)| {
                for (k, group_forces) in forces.chunks_mut(LANES * N * N).enumerate() {
                    let group = chunk * groups + k;
                    self.group_forces::<N, Elastic, _>(group, &d, u, group_forces, &mut ());
                }
            });
            return;
        }
        chunks
            .zip(memory.par_chunks_mut(groups))
            .enumerate()
            .for_each(|(chunk, (forces, memory))| {
                let lane_groups = forces.chunks_mut(LANES * N * N).zip(memory);
                for (k, (group_forces, memory)) in lane_groups.enumerate() {
                    let group = chunk * groups + k;
                    match memory {
                        Some(m) => self.group_forces::<N, L, _>(group, &d, u, group_forces, m),
                        None if L::FORCES => {
                            self.group_forces::<N, Elastic, _>(group, &d, u, group_forces, &mut ())
                        }
                        None => {}
                    }
                }
            });
    }

    /// The forces of lane group `group`'s elements at their points, from `u`, with the widest
    /// SIMD the CPU offers (the same code compiled for AVX-512 and AVX, chosen at run time,
    /// as the layered kernel does).
    fn group_forces<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        group: usize,
        d: &[[f64; N]; N],
        u: &[f64],
        forces: &mut [[f64; 2]],
        law: &mut S,
    ) {
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above), the only requirement
            // of this target_feature function.
            return unsafe { self.group_forces_avx512::<N, L, S>(group, d, u, forces, law) };
        }
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX (checked just above), the only requirement of
            // this target_feature function.
            return unsafe { self.group_forces_avx::<N, L, S>(group, d, u, forces, law) };
        }
        self.group_kernel::<N, L, S>(group, d, u, forces, law);
    }

    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[target_feature(enable = "avx512f")]
    fn group_forces_avx512<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        group: usize,
        d: &[[f64; N]; N],
        u: &[f64],
        forces: &mut [[f64; 2]],
        law: &mut S,
    ) {
        self.group_kernel::<N, L, S>(group, d, u, forces, law);
    }

    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[target_feature(enable = "avx")]
    fn group_forces_avx<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        group: usize,
        d: &[[f64; N]; N],
        u: &[f64],
        forces: &mut [[f64; 2]],
        law: &mut S,
    ) {
        self.group_kernel::<N, L, S>(group, d, u, forces, law);
    }

    /// Gathers the group's displacements, applies [`UnstructuredSem::forces_of`] with law
    /// `L` and (for a law with forces) writes the forces of its elements, point by point and
    /// lane by lane (the padding lanes' are 0 and no node gathers them).
    #[inline(always)]
    fn group_kernel<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        group: usize,
        d: &[[f64; N]; N],
        u: &[f64],
        forces: &mut [[f64; 2]],
        law: &mut S,
    ) {
        let (mut ux, mut uy) = ([[[0.0; LANES]; N]; N], [[[0.0; LANES]; N]; N]);
        let nodes = &self.lane_global[group * N * N * LANES..][..N * N * LANES];
        for (q, lanes) in nodes.chunks_exact(LANES).enumerate() {
            for (l, &g) in lanes.iter().enumerate() {
                ux[q / N][q % N][l] = u[2 * g];
                uy[q / N][q % N][l] = u[2 * g + 1];
            }
        }
        let (mut fx, mut fy) = ([[[0.0; LANES]; N]; N], [[[0.0; LANES]; N]; N]);
        self.forces_of::<N, L, S>(group, d, (&ux, &uy), (&mut fx, &mut fy), law);
        if !L::FORCES {
            return;
        }
        for (q, lanes) in forces.chunks_exact_mut(LANES).enumerate() {
            for (l, f) in lanes.iter_mut().enumerate() {
                *f = [fx[q / N][q % N][l], fy[q / N][q % N][l]];
            }
        }
    }

    /// The internal forces `(fx, fy)` of the LANES elements of lane group `group` at their
    /// points (i along xi, j along eta: `[j][i][lane]`) from their points' displacements
    /// `(ux, uy)` (the module's formula, each array operation across the lanes); the point
    /// law `L` adds what the material does beyond W C_U eps at point j N + i of the group's
    /// state `law` (nothing for [`Elastic`]; a law without forces stops at the stresses).
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn forces_of<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        group: usize,
        d: &[[f64; N]; N],
        (ux, uy): (&[[Lanes; N]; N], &[[Lanes; N]; N]),
        (fx, fy): (&mut [[Lanes; N]; N], &mut [[Lanes; N]; N]),
        law: &mut S,
    ) {
        let metric = &self.metric[group * N * N..(group + 1) * N * N];
        let [c11, c12, c13, c22, c23, c33] = &self.stiffness[group];
        // F_xi and F_eta, x and y components, at every point
        let mut f_xi = [[[[0.0; LANES]; 2]; N]; N];
        let mut f_eta = [[[[0.0; LANES]; 2]; N]; N];
        for j in 0..N {
            for i in 0..N {
                let (mut ux_xi, mut uy_xi) = ([0.0; LANES], [0.0; LANES]);
                let (mut ux_eta, mut uy_eta) = ([0.0; LANES], [0.0; LANES]);
                for k in 0..N {
                    let (a, b) = (d[i][k], d[j][k]);
                    for l in 0..LANES {
                        ux_xi[l] += a * ux[j][k][l];
                        uy_xi[l] += a * uy[j][k][l];
                        ux_eta[l] += b * ux[k][i][l];
                        uy_eta[l] += b * uy[k][i][l];
                    }
                }
                let [xi_x, xi_y, eta_x, eta_y, w] = &metric[j * N + i];
                let ([mut e_xx, mut e_yy, mut g_xy], [mut s_xx, mut s_yy, mut s_xy]) =
                    ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
                for l in 0..LANES {
                    e_xx[l] = ux_xi[l] * xi_x[l] + ux_eta[l] * eta_x[l];
                    e_yy[l] = uy_xi[l] * xi_y[l] + uy_eta[l] * eta_y[l];
                    g_xy[l] = ux_xi[l] * xi_y[l]
                        + ux_eta[l] * eta_y[l]
                        + uy_xi[l] * xi_x[l]
                        + uy_eta[l] * eta_x[l];
                    s_xx[l] = w[l] * (c11[l] * e_xx[l] + c12[l] * e_yy[l] + c13[l] * g_xy[l]);
                    s_yy[l] = w[l] * (c12[l] * e_xx[l] + c22[l] * e_yy[l] + c23[l] * g_xy[l]);
                    s_xy[l] = w[l] * (c13[l] * e_xx[l] + c23[l] * e_yy[l] + c33[l] * g_xy[l]);
                }
                let stress = [&mut s_xx, &mut s_yy, &mut s_xy];
                L::at_point(law, j * N + i, w, [&e_xx, &e_yy, &g_xy], stress);
                for l in 0..LANES {
                    f_xi[j][i][0][l] = s_xx[l] * xi_x[l] + s_xy[l] * xi_y[l];
                    f_xi[j][i][1][l] = s_xy[l] * xi_x[l] + s_yy[l] * xi_y[l];
                    f_eta[j][i][0][l] = s_xx[l] * eta_x[l] + s_xy[l] * eta_y[l];
                    f_eta[j][i][1][l] = s_xy[l] * eta_x[l] + s_yy[l] * eta_y[l];
                }
            }
        }
        if !L::FORCES {
            return;
        }
        for j in 0..N {
            for i in 0..N {
                let (mut sx, mut sy) = ([0.0; LANES], [0.0; LANES]);
                for k in 0..N {
                    let (a, b) = (d[k][i], d[k][j]);
                    for l in 0..LANES {
                        sx[l] += a * f_xi[j][k][0][l] + b * f_eta[k][i][0][l];
                        sy[l] += a * f_xi[j][k][1][l] + b * f_eta[k][i][1][l];
                    }
                }
                fx[j][i] = sx;
                fy[j][i] = sy;
            }
        }
    }

    /// max over elements of the Gershgorin bound of M_e^-1 K_e (K_e's columns from the
    /// element kernel on unit displacements, M_e the element's share of the GLL mass): an
    /// upper bound of omega_max^2, so 2 / sqrt of it is a guaranteed stable step (the element
    /// eigenvalue inequality). Springs are not included.
    pub fn element_eigenvalue_bound(&self) -> f64 {
        with_points!(self.order, N => self.element_bound::<N>())
    }

    fn element_bound<const N: usize>(&self) -> f64 {
        let d = self.derivative_array::<N>();
        (0..self.elements().div_ceil(LANES))
            .into_par_iter()
            .map(|group| {
                // row sums of |K_e| for every element of the group at once: unit
                // displacements at the same point in every lane
                let mut sums = [[[[0.0; LANES]; N]; N]; 2];
                for q in 0..N * N {
                    for c in 0..2 {
                        let (mut ux, mut uy) = ([[[0.0; LANES]; N]; N], [[[0.0; LANES]; N]; N]);
                        [&mut ux, &mut uy][c][q / N][q % N] = [1.0; LANES];
                        let (mut fx, mut fy) = ([[[0.0; LANES]; N]; N], [[[0.0; LANES]; N]; N]);
                        let fields = (&ux, &uy);
                        self.forces_of::<N, Elastic, _>(
                            group,
                            &d,
                            fields,
                            (&mut fx, &mut fy),
                            &mut (),
                        );
                        for (sum, column) in sums.iter_mut().zip([fx, fy]) {
                            let rows = sum.as_flattened_mut();
                            for (s, k) in rows.iter_mut().zip(column.as_flattened()) {
                                for l in 0..LANES {
                                    s[l] += k[l].abs();
                                }
                            }
                        }
                    }
                }
                let (x_rows, y_rows) = (sums[0].as_flattened(), sums[1].as_flattened());
                (0..LANES)
                    .map(|l| group * LANES + l)
                    .filter(|&e| e < self.elements())
                    .flat_map(|e| {
                        let rho = self.materials[self.mesh.elements[e].material].density_kg_m3;
                        (0..N * N).map(move |q| {
                            x_rows[q][e % LANES].max(y_rows[q][e % LANES])
                                / (rho * self.point_weight(e, q))
                        })
                    })
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max)
    }
}

impl Discretisation for UnstructuredSem {
    type Workspace = UnstructuredWorkspace;

    fn lumped_mass(&self) -> &[f64] {
        &self.lumped_mass
    }
    fn fixed_dofs(&self) -> &[usize] {
        &self.fixed_dofs
    }
    fn dashpots(&self) -> &[(usize, f64)] {
        &[]
    }
    fn coupled_dashpots(&self) -> &[(usize, NodeBlock)] {
        &self.dashpots
    }
    fn periodic_ties(&self) -> &[(usize, usize)] {
        &self.periodic
    }
    fn workspace(&self) -> UnstructuredWorkspace {
        UnstructuredSem::workspace(self)
    }
    fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut UnstructuredWorkspace) {
        UnstructuredSem::stiffness_times(self, u, out, work);
    }
    fn check(&self) -> crate::error::Result<()> {
        UnstructuredSem::check(self)
    }
    fn shortest_relaxation_s(&self) -> Option<f64> {
        UnstructuredSem::shortest_relaxation_s(self)
    }
    fn start_memory(&self, dt: f64, u_prev: &[f64], work: &mut UnstructuredWorkspace) {
        UnstructuredSem::start_memory(self, dt, u_prev, work);
    }
    fn take_viscous_loss(&self, work: &mut UnstructuredWorkspace) -> f64 {
        UnstructuredSem::take_viscous_loss(self, work)
    }
    fn memory_energy(&self, u: &[f64], work: &mut UnstructuredWorkspace) -> f64 {
        UnstructuredSem::memory_energy(self, u, work)
    }
    /// The fused kernel: the predictor finished as each node's K u is gathered
    /// ([`UnstructuredSem::explicit_update`]).
    fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut UnstructuredWorkspace,
    ) {
        UnstructuredSem::explicit_update(self, a, u_prev, u, u_next, work);
    }
    fn node_x(&self, node: usize) -> f64 {
        self.positions_m[node][0]
    }
    fn crack(&self) -> Option<&crate::mesh::Crack> {
        self.crack.as_ref()
    }
}
