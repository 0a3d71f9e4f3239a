//! Spectral elements on the layered rectangle (Patera 1984; Komatitsch and Vilotte 1998, as
//! in SPECFEM2D and SEM2DPACK): rectangular elements aligned with the layers, tensor-product
//! Lagrange polynomials on Gauss-Lobatto-Legendre (GLL) points, GLL quadrature, hence an
//! exactly diagonal mass, and the stiffness applied matrix-free by sum factorisation.
//!
//! The polynomial order along x is one for the whole grid; the order across y is chosen per
//! element row, so thin layers can take a low order (and do not shrink the time step) while
//! thick ones take a high one. The mesh stays conforming: a horizontal element edge carries
//! only the x-direction GLL points, the same in the rows above and below it, and the elements
//! of one row share their vertical edges' y-points.
//!
//! The nodes form a tensor grid: node (i, j) sits at `(x_nodes_m[i], y_nodes_m[j])`, index
//! `j * nx + i`, DOFs `2 * node + component` (as the T3 mesh numbers them).

mod assembled;
pub mod gll;
mod layered;

pub use layered::SemSpec;

use crate::error::{Error, Result};
use crate::material::Material;
use crate::mesh::Side;
use gll::Gll;
use rayon::prelude::*;

/// The layered rectangle as spectral elements: element lines, orders, materials, nodes and
/// the diagonal GLL mass.
#[derive(Clone, Debug)]
pub struct SemModel {
    /// Element column lines (x, m), ascending.
    pub columns_m: Vec<f64>,
    /// Element row lines (y, m), ascending.
    pub rows_m: Vec<f64>,
    /// x coordinates of the node columns.
    pub x_nodes_m: Vec<f64>,
    /// y coordinates of the node rows.
    pub y_nodes_m: Vec<f64>,
    /// Plane materials.
    pub materials: Vec<Material>,
    /// Material of each element row (index into `materials`).
    pub row_material: Vec<usize>,
    /// Diagonal mass per DOF, M_kk = sum over elements of rho w_a w_b J (kg).
    pub lumped_mass: Vec<f64>,
    /// DOFs held at zero (none unless set).
    pub fixed_dofs: Vec<usize>,
    /// (DOF, c) of the absorbing edges' dashpots (none unless set, see
    /// [`SemModel::lysmer_dashpots`]).
    pub dashpots: Vec<(usize, f64)>,
    gll_x: Gll,
    /// GLL rule of each element row (its order across y).
    gll_y: Vec<Gll>,
    /// D_x flattened row-wise, and its transpose.
    derivative_x: Vec<f64>,
    derivative_x_t: Vec<f64>,
    /// D_y of each element row, flattened, and its transpose.
    derivative_y: Vec<Vec<f64>>,
    derivative_y_t: Vec<Vec<f64>>,
    /// First node row of each element row.
    first_line: Vec<usize>,
}

/// Scratch of [`SemModel::stiffness_times`], allocated once per model size: per element row,
/// the forces on its node rows and the weighted stresses of one element.
#[derive(Clone, Debug)]
pub struct SemWorkspace {
    rows: Vec<RowWork>,
}

#[derive(Clone, Debug)]
struct RowWork {
    /// Forces on the row's node lines, `(order_y + 1) * nx * 2`.
    force: Vec<f64>,
    /// One element's displacements at its GLL points.
    ux: Vec<f64>,
    uy: Vec<f64>,
    /// Weighted stresses W sigma_xx, W sigma_yy, W sigma_xy at the element's GLL points.
    stress: [Vec<f64>; 3],
}

impl SemModel {
    /// Spectral elements between `columns_m` and `rows_m` (ascending lines), order `order_x`
    /// along x and `order_y[r]` across element row r, material `row_material[r]` of
    /// `materials` in row r.
    pub fn new(
        columns_m: Vec<f64>,
        rows_m: Vec<f64>,
        order_x: usize,
        order_y: &[usize],
        materials: Vec<Material>,
        row_material: Vec<usize>,
    ) -> Result<SemModel> {
        check_lines("columns_m", &columns_m)?;
        check_lines("rows_m", &rows_m)?;
        let n_rows = rows_m.len() - 1;
        if order_y.len() != n_rows || row_material.len() != n_rows {
            return Err(Error::invalid(
                "order_y",
                format!("{} orders, {} materials", order_y.len(), row_material.len()),
                format!("needs one per element row ({n_rows})"),
            ));
        }
        for (name, &order) in
            std::iter::once(("order_x", &order_x)).chain(order_y.iter().map(|o| ("order_y", o)))
        {
            if !(1..=MAX_ORDER).contains(&order) {
                return Err(Error::invalid(
                    name,
                    order,
                    format!("must be 1..={MAX_ORDER}"),
                ));
            }
        }
        if let Some(&m) = row_material.iter().find(|&&m| m >= materials.len()) {
            return Err(Error::invalid("row_material", m, "no such material"));
        }
        let gll_x = Gll::new(order_x);
        let gll_y: Vec<Gll> = order_y.iter().map(|&o| Gll::new(o)).collect();
        let x_nodes_m = node_lines(&columns_m, |_| &gll_x);
        let y_nodes_m = node_lines(&rows_m, |r| &gll_y[r]);
        let mut first_line = Vec::with_capacity(n_rows);
        let mut line = 0;
        for g in &gll_y {
            first_line.push(line);
            line += g.order();
        }
        let (derivative_x, derivative_x_t) = flat_derivative(&gll_x);
        let (derivative_y, derivative_y_t) = gll_y.iter().map(flat_derivative).unzip();
        let mut model = SemModel {
            columns_m,
            rows_m,
            x_nodes_m,
            y_nodes_m,
            materials,
            row_material,
            lumped_mass: Vec::new(),
            fixed_dofs: Vec::new(),
            dashpots: Vec::new(),
            gll_x,
            gll_y,
            derivative_x,
            derivative_x_t,
            derivative_y,
            derivative_y_t,
            first_line,
        };
        model.lumped_mass = model.assemble_mass();
        Ok(model)
    }

    /// Number of node columns.
    pub fn nx(&self) -> usize {
        self.x_nodes_m.len()
    }

    /// Number of degrees of freedom (2 per node).
    pub fn dofs(&self) -> usize {
        2 * self.x_nodes_m.len() * self.y_nodes_m.len()
    }

    /// Node index of node column `i`, node row `j`.
    pub fn node(&self, i: usize, j: usize) -> usize {
        j * self.nx() + i
    }

    /// Global node of local node (a, b) (a along x, b across y) of the element in element
    /// row `r`, element column `c`: the one map from element to global nodes.
    pub(crate) fn element_node(&self, r: usize, c: usize, a: usize, b: usize) -> usize {
        self.node(c * self.gll_x.order() + a, self.first_line[r] + b)
    }

    /// Scratch for [`SemModel::stiffness_times`].
    pub fn workspace(&self) -> SemWorkspace {
        let px = self.gll_x.order();
        let rows = self
            .gll_y
            .iter()
            .map(|g| {
                let points = (px + 1) * (g.order() + 1);
                RowWork {
                    force: vec![0.0; (g.order() + 1) * self.nx() * 2],
                    ux: vec![0.0; points],
                    uy: vec![0.0; points],
                    stress: [vec![0.0; points], vec![0.0; points], vec![0.0; points]],
                }
            })
            .collect();
        SemWorkspace { rows }
    }

    /// The diagonal mass: rho w_a w_b (h_x / 2) (h_y / 2) at each element's GLL point (a, b),
    /// summed where elements share a node; the same for both components.
    fn assemble_mass(&self) -> Vec<f64> {
        let mut mass = vec![0.0; self.dofs()];
        let px = self.gll_x.order();
        for (r, gy) in self.gll_y.iter().enumerate() {
            let rho = self.materials[self.row_material[r]].density_kg_m3;
            let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
            for c in 0..self.columns_m.len() - 1 {
                let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
                for b in 0..=gy.order() {
                    for a in 0..=px {
                        let node = self.node(c * px + a, self.first_line[r] + b);
                        let m = rho * self.gll_x.weights[a] * gy.weights[b] * jx * jy;
                        mass[2 * node] += m;
                        mass[2 * node + 1] += m;
                    }
                }
            }
        }
        mass
    }

    /// `out = K u`, the internal forces f_k = sum_e int B_k^T C B u dA with GLL quadrature,
    /// by sum factorisation: gradients at the GLL points from the 1-D derivative matrices
    /// (O(p^3) per element), stresses sigma = C eps, then the transposed derivatives.
    /// Element rows run in parallel into their own force lines; node rows then gather from
    /// the one or two element rows that hold them, in a fixed order (bit-identical for any
    /// thread count). Allocates nothing.
    pub fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut SemWorkspace) {
        assert_eq!(u.len(), self.dofs());
        assert_eq!(out.len(), self.dofs());
        work.rows
            .par_iter_mut()
            .enumerate()
            .for_each(|(r, row)| self.row_forces(r, u, row));
        let nx = self.nx();
        let rows = &work.rows;
        out.par_chunks_mut(2 * nx)
            .enumerate()
            .for_each(|(j, line)| {
                // the element row whose lines start at or below j, and its local line
                let r = self.first_line.partition_point(|&f| f <= j) - 1;
                let b = j - self.first_line[r];
                let own = &rows[r].force[b * 2 * nx..(b + 1) * 2 * nx];
                line.copy_from_slice(own);
                if b == 0 && r > 0 {
                    let below = self.gll_y[r - 1].order();
                    let lower = &rows[r - 1].force[below * 2 * nx..(below + 1) * 2 * nx];
                    for (o, l) in line.iter_mut().zip(lower) {
                        *o += l;
                    }
                }
            });
    }

    /// Forces of element row `r` on its own node lines. The element kernel is compiled for
    /// each number of points along x (so its loops over them have fixed length); the order
    /// was checked against [`MAX_ORDER`] when the model was built.
    fn row_forces(&self, r: usize, u: &[f64], row: &mut RowWork) {
        row.force.fill(0.0);
        let columns = 0..self.columns_m.len() - 1;
        macro_rules! by_points {
            ($($n:literal)*) => {
                match self.gll_x.order() + 1 {
                    $($n => columns.for_each(|c| self.element_forces::<$n>(r, c, u, row)),)*
                    n => unreachable!("{n} GLL points along x: above MAX_ORDER + 1"),
                }
            };
        }
        by_points!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
    }

    /// One element with `N` GLL points along x: displacements gathered, gradients at the GLL
    /// points (d/dxi: sum_k D_x[a][k] u(k, b); d/deta: sum_k D_y[b][k] u(a, k)), weighted
    /// stresses W C eps, then the transposed derivatives back to nodal forces,
    /// f_x(a, b) = sum_k D_x[k][a] / jx W sxx(k, b) + sum_k D_y[k][b] / jy W sxy(a, k) (and f_y
    /// with sxy, syy), added to the row's force lines. Every inner loop runs over the `N`
    /// points of an element row, as a fixed-length multiply-add.
    fn element_forces<const N: usize>(&self, r: usize, c: usize, u: &[f64], row: &mut RowWork) {
        let nby = self.gll_y[r].order() + 1;
        let dx = self.derivative_x.as_chunks::<N>().0;
        let dxt = self.derivative_x_t.as_chunks::<N>().0;
        let (dy, dyt) = (&self.derivative_y[r], &self.derivative_y_t[r]);
        let wy = &self.gll_y[r].weights;
        let nx = self.nx();
        let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
        let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
        let cm = &self.materials[self.row_material[r]].stiffness_pa;
        let (i0, j0) = (c * (N - 1), self.first_line[r]);
        let RowWork {
            force,
            ux,
            uy,
            stress: [sxx, syy, sxy],
        } = row;
        let ux = ux[..N * nby].as_chunks_mut::<N>().0;
        let uy = uy[..N * nby].as_chunks_mut::<N>().0;
        let sxx = sxx[..N * nby].as_chunks_mut::<N>().0;
        let syy = syy[..N * nby].as_chunks_mut::<N>().0;
        let sxy = sxy[..N * nby].as_chunks_mut::<N>().0;
        for b in 0..nby {
            let start = 2 * ((j0 + b) * nx + i0);
            for (a, v) in u[start..start + 2 * N].chunks_exact(2).enumerate() {
                ux[b][a] = v[0];
                uy[b][a] = v[1];
            }
        }
        for b in 0..nby {
            let (mut dux_dxi, mut duy_dxi) = ([0.0; N], [0.0; N]);
            for k in 0..N {
                let (vx, vy, t) = (ux[b][k], uy[b][k], &dxt[k]);
                for a in 0..N {
                    dux_dxi[a] += t[a] * vx;
                    duy_dxi[a] += t[a] * vy;
                }
            }
            let (mut dux_deta, mut duy_deta) = ([0.0; N], [0.0; N]);
            for k in 0..nby {
                let d = dy[b * nby + k];
                for a in 0..N {
                    dux_deta[a] += d * ux[k][a];
                    duy_deta[a] += d * uy[k][a];
                }
            }
            for a in 0..N {
                let strain = [
                    dux_dxi[a] / jx,
                    duy_deta[a] / jy,
                    dux_deta[a] / jy + duy_dxi[a] / jx,
                ];
                let w = self.gll_x.weights[a] * wy[b] * jx * jy;
                sxx[b][a] = w * dot(&cm[0], &strain);
                syy[b][a] = w * dot(&cm[1], &strain);
                sxy[b][a] = w * dot(&cm[2], &strain);
            }
        }
        for b in 0..nby {
            let (mut fx, mut fy) = ([0.0; N], [0.0; N]);
            for k in 0..N {
                let (s1, s2, d) = (sxx[b][k] / jx, sxy[b][k] / jx, &dx[k]);
                for a in 0..N {
                    fx[a] += d[a] * s1;
                    fy[a] += d[a] * s2;
                }
            }
            for k in 0..nby {
                let d = dyt[b * nby + k] / jy;
                for a in 0..N {
                    fx[a] += d * sxy[k][a];
                    fy[a] += d * syy[k][a];
                }
            }
            let start = 2 * (b * nx + i0);
            for (a, f) in force[start..start + 2 * N].chunks_exact_mut(2).enumerate() {
                f[0] += fx[a];
                f[1] += fy[a];
            }
        }
    }

    /// GLL quadrature of a side: for every element edge on it, each of its nodes with the
    /// weight w_a (h / 2) of its GLL point and the element row (or column) it belongs to,
    /// so that sum weight f(node) = integral of f along the side for polynomials of degree
    /// up to 2N - 1 per element.
    pub fn side_quadrature(&self, side: Side) -> Vec<(usize, f64, usize)> {
        let (nx, ny) = (self.nx(), self.y_nodes_m.len());
        let mut out = Vec::new();
        match side {
            Side::Bottom | Side::Top => {
                let (j, row) = match side {
                    Side::Bottom => (0, 0),
                    _ => (ny - 1, self.gll_y.len() - 1),
                };
                let px = self.gll_x.order();
                for c in 0..self.columns_m.len() - 1 {
                    let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
                    for (a, w) in self.gll_x.weights.iter().enumerate() {
                        out.push((self.node(c * px + a, j), w * jx, row));
                    }
                }
            }
            Side::Left | Side::Right => {
                let i = if side == Side::Left { 0 } else { nx - 1 };
                for (r, g) in self.gll_y.iter().enumerate() {
                    let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
                    for (b, w) in g.weights.iter().enumerate() {
                        out.push((self.node(i, self.first_line[r] + b), w * jy, r));
                    }
                }
            }
        }
        out
    }

    /// Interpolation weights of the displacement at `(x_m, y_m)`: the element holding the
    /// point (the lower one on a shared line), its local coordinates, and the tensor products
    /// l_a(xi) l_b(eta) of the GLL Lagrange polynomials at its nodes, zeros dropped. A point on
    /// a node gets that node alone with weight exactly 1. `None` outside the rectangle.
    pub fn point_weights(&self, x_m: f64, y_m: f64) -> Option<Vec<(usize, f64)>> {
        let c = containing(&self.columns_m, x_m)?;
        let r = containing(&self.rows_m, y_m)?;
        let local = |lines: &[f64], k: usize, v: f64| {
            (2.0 * v - lines[k] - lines[k + 1]) / (lines[k + 1] - lines[k])
        };
        let lx = self.gll_x.lagrange_at(local(&self.columns_m, c, x_m));
        let ly = self.gll_y[r].lagrange_at(local(&self.rows_m, r, y_m));
        let px = self.gll_x.order();
        let mut weights = Vec::new();
        for (b, wy) in ly.iter().enumerate() {
            for (a, wx) in lx.iter().enumerate() {
                let w = wx * wy;
                if w != 0.0 {
                    weights.push((self.node(c * px + a, self.first_line[r] + b), w));
                }
            }
        }
        Some(weights)
    }

    /// Lysmer-Kuhlemeyer dashpots of the `sides` (report Sec. 4.6), with GLL
    /// edge weights: per edge node, rho V_p times its weight on the normal DOF and rho V_s on
    /// the tangential one, V_p along the side's normal, from the material of the element it
    /// belongs to (a node shared by two element rows gets both halves). Sorted by DOF.
    pub fn lysmer_dashpots(&self, sides: &[Side]) -> Vec<(usize, f64)> {
        let mut c = std::collections::BTreeMap::<usize, f64>::new();
        for &side in sides {
            let normal = match side {
                Side::Bottom | Side::Top => 1,
                Side::Left | Side::Right => 0,
            };
            for (node, weight, row) in self.side_quadrature(side) {
                let mat = &self.materials[self.row_material[row]];
                let speeds = mat.wave_speeds();
                let vp = if normal == 0 {
                    speeds.p_x_m_s
                } else {
                    speeds.p_y_m_s
                };
                let rho = mat.density_kg_m3;
                *c.entry(2 * node + normal).or_default() += rho * vp * weight;
                *c.entry(2 * node + 1 - normal).or_default() += rho * speeds.s_m_s * weight;
            }
        }
        c.into_iter().collect()
    }

    /// Largest eigenvalue of M^-1 K over the `free` DOFs (Lanczos, as for the T3 model), and
    /// the iterations used; dt_crit = 2 / sqrt of it.
    pub fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize) {
        let work = std::cell::RefCell::new(self.workspace());
        crate::solve::stability::lanczos_max_eigenvalue_of(&self.lumped_mass, free, |x, y| {
            self.stiffness_times(x, y, &mut work.borrow_mut())
        })
    }
}

/// Highest polynomial order offered (the GLL points are accurate to round-off well beyond).
pub const MAX_ORDER: usize = 16;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A GLL derivative matrix flattened row-wise, and its transpose.
fn flat_derivative(g: &Gll) -> (Vec<f64>, Vec<f64>) {
    let n = g.order() + 1;
    let d: Vec<f64> = g.derivative.iter().flatten().copied().collect();
    let t = (0..n * n).map(|k| d[(k % n) * n + k / n]).collect();
    (d, t)
}

/// Index of the interval of ascending `lines` holding `v` (the lower one on a shared line),
/// or `None` outside [first, last].
fn containing(lines: &[f64], v: f64) -> Option<usize> {
    let (first, last) = (lines[0], *lines.last()?);
    if !(first..=last).contains(&v) {
        return None;
    }
    Some(
        lines
            .partition_point(|&l| l < v)
            .saturating_sub(1)
            .min(lines.len() - 2),
    )
}

/// Node coordinates along one axis: each element's GLL points mapped onto it, shared end
/// points once.
fn node_lines<'a>(lines: &[f64], rule: impl Fn(usize) -> &'a Gll) -> Vec<f64> {
    let mut nodes = vec![lines[0]];
    for e in 0..lines.len() - 1 {
        let (a, b) = (lines[e], lines[e + 1]);
        let g = rule(e);
        nodes.extend(
            g.points[1..]
                .iter()
                .map(|&xi| 0.5 * (a + b) + 0.5 * (b - a) * xi),
        );
        *nodes.last_mut().expect("points") = b;
    }
    nodes
}

fn check_lines(name: &str, lines: &[f64]) -> Result<()> {
    if lines.len() < 2
        || lines.iter().any(|v| !v.is_finite())
        || lines.windows(2).any(|w| w[1] <= w[0])
    {
        return Err(Error::invalid(
            name,
            format!("{lines:?}"),
            "needs at least two finite, strictly increasing lines",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
