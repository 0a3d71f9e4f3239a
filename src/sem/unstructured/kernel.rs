//! K u on unstructured spectral elements, and the model as the time steppers see it.
//!
//! Per element, with u at its GLL points (i along xi, j along eta):
//!   du/dxi (i, j) = sum_k D[i][k] u(k, j),  du/deta (i, j) = sum_k D[j][k] u(i, k),
//!   grad u = du/dxi grad xi + du/deta grad eta,  sigma = C eps(u)  (Voigt, eps_xy engineering),
//! and the weak form's internal force at point (i, j) (Komatitsch and Tromp 1999, eq. 32):
//!   f(i, j) = sum_k D[k][i] F_xi(k, j) + sum_l D[l][j] F_eta(i, l),
//!   F_xi = w det J sigma . grad xi,  F_eta = w det J sigma . grad eta.

use super::UnstructuredSem;
use crate::solve::Discretisation;
use rayon::prelude::*;

/// Largest number of GLL points per direction (order 16).
const MAX_POINTS: usize = super::MAX_ORDER + 1;

/// Elements per parallel task of the element pass, nodes per task of the gather.
const ELEMENT_CHUNK: usize = 64;
const NODE_CHUNK: usize = 4096;

/// The scratch of [`UnstructuredSem::stiffness_times`]: every element point's force (x, y),
/// allocated once per run.
#[derive(Clone, Debug)]
pub struct UnstructuredWorkspace {
    point_forces: Vec<[f64; 2]>,
}

impl UnstructuredSem {
    /// The scratch of [`UnstructuredSem::stiffness_times`].
    pub fn workspace(&self) -> UnstructuredWorkspace {
        UnstructuredWorkspace {
            point_forces: vec![[0.0; 2]; self.global.len()],
        }
    }

    /// `out = K u`, bit-identical for any number of threads (see the module's doc).
    pub fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut UnstructuredWorkspace) {
        let n = self.order + 1;
        let nn = n * n;
        work.point_forces
            .par_chunks_mut(ELEMENT_CHUNK * nn)
            .enumerate()
            .for_each(|(chunk, forces)| {
                for (k, element_forces) in forces.chunks_mut(nn).enumerate() {
                    self.element_forces(chunk * ELEMENT_CHUNK + k, u, element_forces);
                }
            });
        let forces = &work.point_forces;
        out.par_chunks_mut(2 * NODE_CHUNK)
            .enumerate()
            .for_each(|(chunk, out)| {
                for (k, f) in out.chunks_mut(2).enumerate() {
                    let g = chunk * NODE_CHUNK + k;
                    let held =
                        &self.incidence[self.incidence_start[g]..self.incidence_start[g + 1]];
                    let (mut fx, mut fy) = (0.0, 0.0);
                    for &p in held {
                        fx += forces[p][0];
                        fy += forces[p][1];
                    }
                    f[0] = fx;
                    f[1] = fy;
                }
            });
        for &(d, k) in &self.springs {
            out[d] += k * u[d];
        }
    }

    /// max over elements of the Gershgorin bound of M_e^-1 K_e (K_e's columns from the
    /// element kernel on unit displacements, M_e the element's share of the GLL mass): an
    /// upper bound of omega_max^2, so 2 / sqrt of it is a guaranteed stable step (the element
    /// eigenvalue inequality). Springs are not included.
    pub fn element_eigenvalue_bound(&self) -> f64 {
        let nn = (self.order + 1).pow(2);
        (0..self.elements())
            .into_par_iter()
            .map(|e| {
                let rho = self.materials[self.mesh.elements[e].material].density_kg_m3;
                let mut row_sums = vec![[0.0; 2]; nn];
                let mut unit = vec![0.0; 2 * nn];
                let mut column = vec![[0.0; 2]; nn];
                for k in 0..2 * nn {
                    unit[k] = 1.0;
                    let (ux, uy): (Vec<f64>, Vec<f64>) =
                        unit.chunks(2).map(|c| (c[0], c[1])).unzip();
                    self.forces_of(e, &ux, &uy, &mut column);
                    unit[k] = 0.0;
                    for (sum, f) in row_sums.iter_mut().zip(&column) {
                        sum[0] += f[0].abs();
                        sum[1] += f[1].abs();
                    }
                }
                (0..nn)
                    .map(|q| {
                        row_sums[q][0].max(row_sums[q][1]) / (rho * self.metric[e * nn + q][4])
                    })
                    .fold(0.0, f64::max)
            })
            .reduce(|| 0.0, f64::max)
    }

    /// The internal forces of element `e` at its points, from `u` (the module's formula).
    fn element_forces(&self, e: usize, u: &[f64], forces: &mut [[f64; 2]]) {
        let nn = (self.order + 1).pow(2);
        let mut ux = [0.0; MAX_POINTS * MAX_POINTS];
        let mut uy = [0.0; MAX_POINTS * MAX_POINTS];
        for (q, &g) in self.global[e * nn..(e + 1) * nn].iter().enumerate() {
            ux[q] = u[2 * g];
            uy[q] = u[2 * g + 1];
        }
        self.forces_of(e, &ux, &uy, forces);
    }

    /// The internal forces of element `e` at its points from its points' displacements
    /// `ux`, `uy` (element point order).
    fn forces_of(&self, e: usize, ux: &[f64], uy: &[f64], forces: &mut [[f64; 2]]) {
        let n = self.order + 1;
        let nn = n * n;
        let d = &self.derivative;
        let metric = &self.metric[e * nn..(e + 1) * nn];
        let [c11, c12, c13, c22, c23, c33] = self.stiffness[e];
        // F_xi and F_eta for x and y at every point
        let mut flux = [[0.0; 4]; MAX_POINTS * MAX_POINTS];
        for j in 0..n {
            for i in 0..n {
                let (mut ux_xi, mut uy_xi, mut ux_eta, mut uy_eta) = (0.0, 0.0, 0.0, 0.0);
                for k in 0..n {
                    let (a, b) = (d[i * n + k], d[j * n + k]);
                    ux_xi += a * ux[j * n + k];
                    uy_xi += a * uy[j * n + k];
                    ux_eta += b * ux[k * n + i];
                    uy_eta += b * uy[k * n + i];
                }
                let q = j * n + i;
                let [xi_x, xi_y, eta_x, eta_y, w] = metric[q];
                let e_xx = ux_xi * xi_x + ux_eta * eta_x;
                let e_yy = uy_xi * xi_y + uy_eta * eta_y;
                let g_xy = ux_xi * xi_y + ux_eta * eta_y + uy_xi * xi_x + uy_eta * eta_x;
                let s_xx = c11 * e_xx + c12 * e_yy + c13 * g_xy;
                let s_yy = c12 * e_xx + c22 * e_yy + c23 * g_xy;
                let s_xy = c13 * e_xx + c23 * e_yy + c33 * g_xy;
                flux[q] = [
                    w * (s_xx * xi_x + s_xy * xi_y),
                    w * (s_xy * xi_x + s_yy * xi_y),
                    w * (s_xx * eta_x + s_xy * eta_y),
                    w * (s_xy * eta_x + s_yy * eta_y),
                ];
            }
        }
        for j in 0..n {
            for i in 0..n {
                let (mut fx, mut fy) = (0.0, 0.0);
                for k in 0..n {
                    let (a, b) = (d[k * n + i], d[k * n + j]);
                    let along_xi = &flux[j * n + k];
                    let along_eta = &flux[k * n + i];
                    fx += a * along_xi[0] + b * along_eta[2];
                    fy += a * along_xi[1] + b * along_eta[3];
                }
                forces[j * n + i] = [fx, fy];
            }
        }
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
        &self.dashpots
    }
    fn periodic_ties(&self) -> &[(usize, usize)] {
        &[]
    }
    fn workspace(&self) -> UnstructuredWorkspace {
        UnstructuredSem::workspace(self)
    }
    fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut UnstructuredWorkspace) {
        UnstructuredSem::stiffness_times(self, u, out, work);
    }
    fn node_x(&self, node: usize) -> f64 {
        self.positions_m[node][0]
    }
}
