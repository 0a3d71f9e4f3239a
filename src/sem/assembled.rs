//! The spectral-element stiffness as an assembled sparse matrix, for the implicit (Newmark)
//! integrator: the element matrices from the same GLL quadrature as the matrix-free product
//! [`SemModel::stiffness_times`], K_e = sum over GLL points (k, l) of
//! w_k w_l J B^T C B, scattered into a node-block sparse matrix.

use super::SemModel;
use crate::fem::BlockCsr;
use crate::material::Material;

/// One element's dense stiffness in 2x2 node blocks, `blocks[i * n + j]` coupling local nodes
/// i and j (local node `b * (order_x + 1) + a`), with its global nodes.
struct ElementMatrix {
    nodes: Vec<usize>,
    blocks: Vec<[f64; 4]>,
}

impl SemModel {
    /// The stiffness K = sum_e int B^T C B dA with GLL quadrature (the matrix whose product
    /// [`SemModel::stiffness_times`] forms matrix-free), assembled element by element into a
    /// node-block sparse matrix; every node of an element couples to every other. The
    /// viscous-spring edges' springs are on its diagonal; fixed DOFs and dashpots are not in
    /// it.
    pub fn assemble_stiffness(&self) -> BlockCsr {
        let mut k = self.assemble_elements(|m| m.stiffness_pa);
        for &(d, spring) in &self.springs {
            let along = if d % 2 == 0 {
                [spring, 0.0]
            } else {
                [0.0, spring]
            };
            k.add_diagonal(d / 2, along);
        }
        k
    }

    /// What the memory variables change in Newmark's effective matrix at step `dt`: the
    /// elements assembled with C_N - C_U
    /// ([`newmark_stiffness_change`](crate::attenuation::memory::newmark_stiffness_change)),
    /// zero in elastic rows.
    pub(crate) fn newmark_stiffness_change(&self, dt: f64) -> BlockCsr {
        self.assemble_elements(|m| crate::attenuation::memory::newmark_stiffness_change(m, dt))
    }

    /// sum_e int B^T C B dA with each row's material's C = `stiffness(material)`.
    fn assemble_elements(&self, stiffness: impl Fn(&Material) -> [[f64; 3]; 3]) -> BlockCsr {
        let elements: Vec<(usize, usize)> = (0..self.gll_y.len())
            .flat_map(|r| (0..self.columns_m.len() - 1).map(move |c| (r, c)))
            .collect();
        let nodes = self.dofs() / 2;
        let mut neighbours = vec![Vec::<u32>::new(); nodes];
        for &(r, c) in &elements {
            let local = self.element_nodes(r, c);
            for &n in &local {
                neighbours[n].extend(local.iter().map(|&m| m as u32));
            }
        }
        let mut row_ptr = vec![0];
        let mut cols = Vec::new();
        for row in &mut neighbours {
            row.sort_unstable();
            row.dedup();
            cols.extend_from_slice(row);
            row_ptr.push(cols.len());
        }
        let mut k = BlockCsr {
            row_ptr,
            blocks: vec![[0.0; 4]; cols.len()],
            cols,
        };
        let materials: Vec<[[f64; 3]; 3]> = self.materials.iter().map(stiffness).collect();
        for &(r, c) in &elements {
            let e = self.element_matrix(r, c, &materials[self.row_material[r]]);
            let n = e.nodes.len();
            for (i, &row) in e.nodes.iter().enumerate() {
                let (start, end) = (k.row_ptr[row], k.row_ptr[row + 1]);
                for (j, &col) in e.nodes.iter().enumerate() {
                    let p = start
                        + k.cols[start..end]
                            .binary_search(&(col as u32))
                            .expect("column in the element pattern");
                    for (v, w) in k.blocks[p].iter_mut().zip(&e.blocks[i * n + j]) {
                        *v += w;
                    }
                }
            }
        }
        k
    }

    /// A guaranteed upper bound of the largest eigenvalue of M^-1 K: the largest over the
    /// elements of the Gershgorin bound of M_e^-1 K_e, max_i sum_j |K_e,ij| / m_e,i, with
    /// m_e,i = rho w_a w_b jx jy the element's GLL mass at its node i (the element eigenvalue
    /// inequality: M and K are sums of the element matrices). The viscous springs (G / R per
    /// unit edge length, orders of magnitude below the elements' stiffness) are left out, as
    /// in the T3 element bound. Elements of one row with the width of the previous element
    /// are computed once.
    pub fn element_eigenvalue_bound(&self) -> f64 {
        let mut bound: f64 = 0.0;
        for r in 0..self.gll_y.len() {
            let mut width = f64::NAN;
            for c in 0..self.columns_m.len() - 1 {
                let w = self.columns_m[c + 1] - self.columns_m[c];
                if w != width {
                    width = w;
                    bound = bound.max(self.element_gershgorin(r, c));
                }
            }
        }
        bound
    }

    /// max_i sum_j |K_e,ij| / m_e,i of element (r, c).
    fn element_gershgorin(&self, r: usize, c: usize) -> f64 {
        let e = self.element_matrix(r, c, &self.materials[self.row_material[r]].stiffness_pa);
        let (gx, gy) = (&self.gll_x, &self.gll_y[r]);
        let na = gx.order() + 1;
        let n = e.nodes.len();
        let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
        let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
        let rho = self.materials[self.row_material[r]].density_kg_m3;
        (0..n)
            .map(|i| {
                let mass = rho * gx.weights[i % na] * gy.weights[i / na] * jx * jy;
                let row = &e.blocks[i * n..(i + 1) * n];
                let x: f64 = row.iter().map(|b| b[0].abs() + b[1].abs()).sum();
                let y: f64 = row.iter().map(|b| b[2].abs() + b[3].abs()).sum();
                x.max(y) / mass
            })
            .fold(0.0, f64::max)
    }

    /// Global nodes of element (r, c), local node `b * (order_x + 1) + a`.
    fn element_nodes(&self, r: usize, c: usize) -> Vec<usize> {
        let (na, nb) = (self.gll_x.order() + 1, self.gll_y[r].order() + 1);
        (0..nb)
            .flat_map(|b| (0..na).map(move |a| (a, b)))
            .map(|(a, b)| self.element_node(r, c, a, b))
            .collect()
    }

    /// K_e of element (r, c): at each GLL point (k, l) with weight w_k w_l jx jy, the nodes
    /// whose shape function has a non-zero gradient there (node (a, l): d/dx = D_x[k][a] / jx;
    /// node (k, b): d/dy = D_y[l][b] / jy), B_i = [[dx, 0], [0, dy], [dy, dx]] (strains
    /// xx, yy, xy against u_x, u_y), and the blocks w B_i^T C B_j with C = `cm`.
    fn element_matrix(&self, r: usize, c: usize, cm: &[[f64; 3]; 3]) -> ElementMatrix {
        let (gx, gy) = (&self.gll_x, &self.gll_y[r]);
        let (na, nb) = (gx.order() + 1, gy.order() + 1);
        let n = na * nb;
        let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
        let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
        let mut blocks = vec![[0.0; 4]; n * n];
        let mut gradients = Vec::with_capacity(na + nb);
        for l in 0..nb {
            for k in 0..na {
                let w = gx.weights[k] * gy.weights[l] * jx * jy;
                gradients.clear();
                for a in 0..na {
                    let dy = if a == k {
                        gy.derivative[l][l] / jy
                    } else {
                        0.0
                    };
                    gradients.push((l * na + a, gx.derivative[k][a] / jx, dy));
                }
                for b in (0..nb).filter(|&b| b != l) {
                    gradients.push((b * na + k, 0.0, gy.derivative[l][b] / jy));
                }
                for &(j, dxj, dyj) in &gradients {
                    // C B_j, columns u_x and u_y
                    let cb: [[f64; 2]; 3] = std::array::from_fn(|s| {
                        [
                            cm[s][0] * dxj + cm[s][2] * dyj,
                            cm[s][1] * dyj + cm[s][2] * dxj,
                        ]
                    });
                    for &(i, dxi, dyi) in &gradients {
                        let block = &mut blocks[i * n + j];
                        for q in 0..2 {
                            block[q] += w * (dxi * cb[0][q] + dyi * cb[2][q]);
                            block[2 + q] += w * (dyi * cb[1][q] + dxi * cb[2][q]);
                        }
                    }
                }
            }
        }
        ElementMatrix {
            nodes: self.element_nodes(r, c),
            blocks,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Material, Orthotropic, Plane};

    fn material(name: &str) -> Material {
        Orthotropic::preset(name)
            .and_then(|o| o.reduce(Plane::Strain))
            .expect("preset")
    }

    #[test]
    fn assembled_stiffness_matches_the_matrix_free_product() {
        // Three element rows of orders 5, 1, 3 across y, order 4 along x, two materials
        // (one anisotropic with C13 = 0 but C12 != 0): K u from the assembled matrix and
        // from sum factorisation agree to round-off on a non-polynomial field, and K is
        // symmetric.
        let m = SemModel::new(
            vec![0.0, 0.7e-3, 1.5e-3, 2.0e-3],
            vec![0.0, 0.5e-3, 0.52e-3, 1.1e-3],
            4,
            &[5, 1, 3],
            vec![material("fabric_0_90"), material("epoxy")],
            vec![0, 1, 0],
        )
        .expect("model");
        let k = m.assemble_stiffness();
        let u: Vec<f64> = (0..m.dofs())
            .map(|d| 1e-9 * (0.37 * d as f64).sin())
            .collect();
        let (mut assembled, mut free) = (vec![0.0; m.dofs()], vec![0.0; m.dofs()]);
        k.mul(&u, &mut assembled);
        m.stiffness_times(&u, &mut free, &mut m.workspace());
        let scale = free.iter().fold(0.0f64, |s, f| s.max(f.abs()));
        let diff = assembled
            .iter()
            .zip(&free)
            .fold(0.0f64, |s, (a, b)| s.max((a - b).abs()));
        assert!(
            diff < 1e-12 * scale,
            "max |K u - K_mf u| {diff:e} of {scale:e}"
        );
        assert!(k.asymmetry() < 1e-14, "asymmetry {:e}", k.asymmetry());
    }
}
