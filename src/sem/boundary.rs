//! What the edges and points of spectral elements carry: GLL quadrature of a side (consistent
//! loads), interpolation weights at a point, Lysmer-Kuhlemeyer dashpots and the viscous-spring
//! edge's springs with GLL edge weights.

use super::SemModel;
use crate::error::{Error, Result};
use crate::fem::{VISCOUS_SPRING_ALPHA_N, VISCOUS_SPRING_ALPHA_T};
use crate::mesh::Side;
use crate::solve::NodeBlock;
use std::collections::BTreeMap;

impl SemModel {
    /// GLL quadrature of a side: for every element edge on it, each of its nodes with the
    /// weight w_a (h / 2) of its GLL point and the element row (or column) it belongs to,
    /// so that sum weight f(node) = integral of f along the side for polynomials of degree
    /// up to 2N - 1 per element. A side a through-crack ends on has its split node once per
    /// face (the duplicate for the row below).
    pub fn side_quadrature(&self, side: Side) -> Vec<(usize, f64, usize)> {
        let mut out = Vec::new();
        let (px, columns) = (self.gll_x.order(), self.columns_m.len() - 1);
        match side {
            Side::Bottom | Side::Top => {
                let row = if side == Side::Bottom {
                    0
                } else {
                    self.gll_y.len() - 1
                };
                let b = if side == Side::Bottom {
                    0
                } else {
                    self.gll_y[row].order()
                };
                for c in 0..columns {
                    let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
                    for (a, w) in self.gll_x.weights.iter().enumerate() {
                        out.push((self.element_node(row, c, a, b), w * jx, row));
                    }
                }
            }
            Side::Left | Side::Right => {
                let (c, a) = if side == Side::Left {
                    (0, 0)
                } else {
                    (columns - 1, px)
                };
                for (r, g) in self.gll_y.iter().enumerate() {
                    let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
                    for (b, w) in g.weights.iter().enumerate() {
                        out.push((self.element_node(r, c, a, b), w * jy, r));
                    }
                }
            }
        }
        out
    }

    /// Interpolation weights of the displacement at `(x_m, y_m)`: the element holding the
    /// point (the lower one on a shared line), its local coordinates, and the tensor products
    /// l_a(xi) l_b(eta) of the GLL Lagrange polynomials at its nodes, zeros dropped. A point on
    /// a node gets that node alone with weight exactly 1 (on a crack line: the lower face's
    /// node where the line is split). `None` outside the rectangle.
    pub fn point_weights(&self, x_m: f64, y_m: f64) -> Option<Vec<(usize, f64)>> {
        let c = containing(&self.columns_m, x_m)?;
        let r = containing(&self.rows_m, y_m)?;
        let local = |lines: &[f64], k: usize, v: f64| {
            (2.0 * v - lines[k] - lines[k + 1]) / (lines[k + 1] - lines[k])
        };
        let lx = self.gll_x.lagrange_at(local(&self.columns_m, c, x_m));
        let ly = self.gll_y[r].lagrange_at(local(&self.rows_m, r, y_m));
        let mut weights = Vec::new();
        for (b, wy) in ly.iter().enumerate() {
            for (a, wx) in lx.iter().enumerate() {
                let w = wx * wy;
                if w != 0.0 {
                    weights.push((self.element_node(r, c, a, b), w));
                }
            }
        }
        Some(weights)
    }

    /// Lysmer-Kuhlemeyer dashpots of the `sides` (report Sec. 4.6) with GLL edge weights,
    /// as [`side_dashpots`] gives them, from the material of the element row each node's
    /// weight comes from (a node shared by two element rows gets both halves). Sorted by DOF.
    pub fn lysmer_dashpots(&self, sides: &[Side]) -> Vec<(usize, f64)> {
        let mut c = BTreeMap::new();
        for &side in sides {
            side_dashpots(&mut c, &self.side_points(side));
        }
        c.into_iter().collect()
    }

    /// The springs of a viscous-spring edge on `side` (Liu et al. 2006, as T3's
    /// [`crate::fem::AbsorbingEdge`]), with GLL edge weights, as [`side_springs`] gives
    /// them; R = `distance_m` from the wave source (a node shared by two element rows gets
    /// both halves). Sorted by DOF; add them to [`SemModel::springs`] (several sides: extend).
    pub fn viscous_springs(&self, side: Side, distance_m: f64) -> Result<Vec<(usize, f64)>> {
        side_springs(&self.side_points(side), distance_m)
    }

    /// The GLL points of `side` with their element row's density and moduli.
    fn side_points(&self, side: Side) -> Vec<SidePoint> {
        let normal = match side {
            Side::Bottom | Side::Top => 1,
            Side::Left | Side::Right => 0,
        };
        self.side_quadrature(side)
            .into_iter()
            .map(|(node, weight, row)| {
                let mat = &self.materials[self.row_material[row]];
                let c = &mat.stiffness_pa;
                SidePoint {
                    node,
                    normal,
                    weight,
                    density_kg_m3: mat.density_kg_m3,
                    c_normal_pa: c[normal][normal],
                    c_shear_pa: c[2][2],
                }
            })
            .collect()
    }
}

/// A GLL point on a straight side along x or y: its node, the DOF component normal to the
/// side, its edge weight w (m), and the density and the normal (C_11 or C_22) and shear
/// (C_33) moduli of the element its weight comes from.
struct SidePoint {
    node: usize,
    normal: usize,
    weight: f64,
    density_kg_m3: f64,
    c_normal_pa: f64,
    c_shear_pa: f64,
}

/// Adds the Lysmer-Kuhlemeyer dashpots of `points` to `c` (per DOF): rho V_n w on the
/// normal DOF and rho V_s w on the tangential one, rho V = sqrt(rho C) with V_n =
/// sqrt(C_nn / rho), V_s = sqrt(C_33 / rho) (report Sec. 4.6; the impedances of waves
/// crossing the side at normal incidence).
fn side_dashpots(c: &mut BTreeMap<usize, f64>, points: &[SidePoint]) {
    for p in points {
        let (n, t) = (2 * p.node + p.normal, 2 * p.node + 1 - p.normal);
        *c.entry(n).or_default() += (p.density_kg_m3 * p.c_normal_pa).sqrt() * p.weight;
        *c.entry(t).or_default() += (p.density_kg_m3 * p.c_shear_pa).sqrt() * p.weight;
    }
}

/// The impedance matrix of plane waves crossing a line of unit normal `n`, Z = sqrt(rho
/// Gamma(n)) (N s/m^3), for the plane stiffness `c` = (C11, C12, C13, C22, C23, C33) (Voigt,
/// engineering shear) and density `density_kg_m3`. Gamma_ik = C_ijkl n_j n_l is the
/// Christoffel matrix:
///
/// Gamma_xx = C11 n_x^2 + 2 C13 n_x n_y + C33 n_y^2,
/// Gamma_yy = C33 n_x^2 + 2 C23 n_x n_y + C22 n_y^2,
/// Gamma_xy = C13 n_x^2 + (C12 + C33) n_x n_y + C23 n_y^2.
///
/// A plane wave u = a g(t - n.x / V) with Gamma a = rho V^2 a puts the traction
/// -rho V g' a = -Z u' on the line it leaves behind, so dashpots C = Z w absorb both waves
/// at normal incidence in any anisotropic material. On a side along x or y of a material in
/// its axes Z is diag(sqrt(rho C_nn), sqrt(rho C33)), [`side_dashpots`]'s. The square root
/// of the symmetric positive definite A is (A + sqrt(det A) I) / sqrt(tr A + 2 sqrt(det A)).
pub(crate) fn impedance(c: [f64; 6], density_kg_m3: f64, n: [f64; 2]) -> NodeBlock {
    let [c11, c12, c13, c22, c23, c33] = c;
    let (xx, xy, yy) = (n[0] * n[0], n[0] * n[1], n[1] * n[1]);
    let gamma = [
        [
            c11 * xx + 2.0 * c13 * xy + c33 * yy,
            c13 * xx + (c12 + c33) * xy + c23 * yy,
        ],
        [
            c13 * xx + (c12 + c33) * xy + c23 * yy,
            c33 * xx + 2.0 * c23 * xy + c22 * yy,
        ],
    ]
    .map(|row| row.map(|g| density_kg_m3 * g));
    let root_det = (gamma[0][0] * gamma[1][1] - gamma[0][1] * gamma[1][0]).sqrt();
    let scale = (gamma[0][0] + gamma[1][1] + 2.0 * root_det).sqrt();
    [
        [(gamma[0][0] + root_det) / scale, gamma[0][1] / scale],
        [gamma[1][0] / scale, (gamma[1][1] + root_det) / scale],
    ]
}

/// The springs of a viscous-spring edge through `points` (Liu et al. 2006): per DOF,
/// k_N = ALPHA_N G w / R on the normal one and k_T = ALPHA_T G w / R on the tangential one,
/// G = C_33, R = `distance_m` from the wave source. Sorted by DOF; R must be positive.
fn side_springs(points: &[SidePoint], distance_m: f64) -> Result<Vec<(usize, f64)>> {
    if !(distance_m.is_finite() && distance_m > 0.0) {
        return Err(Error::invalid(
            "absorber.source_distance_m",
            distance_m,
            "must be a positive distance (m)",
        ));
    }
    let mut k = BTreeMap::<usize, f64>::new();
    for p in points {
        let g = p.c_shear_pa * p.weight / distance_m;
        *k.entry(2 * p.node + p.normal).or_default() += VISCOUS_SPRING_ALPHA_N * g;
        *k.entry(2 * p.node + 1 - p.normal).or_default() += VISCOUS_SPRING_ALPHA_T * g;
    }
    Ok(k.into_iter().collect())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{Orthotropic, Plane};

    fn stiffness(m: &crate::material::Material) -> [f64; 6] {
        let c = m.stiffness_pa;
        [c[0][0], c[0][1], c[0][2], c[1][1], c[1][2], c[2][2]]
    }

    /// Z^2 = rho Gamma(n) with Z symmetric positive definite for a ply turned by 30 degrees
    /// on an inclined line; in the material's axes Z is the diagonal of `side_dashpots`; for
    /// an isotropic material it is rho V_p n n^T + rho V_s t t^T at any angle.
    #[test]
    fn impedance_is_the_root_of_rho_times_the_christoffel_matrix() {
        let ply = Orthotropic::preset("fabric_0_90")
            .unwrap()
            .reduce(Plane::Strain)
            .unwrap();
        let rho = ply.density_kg_m3;
        let turned = ply.rotated(30f64.to_radians());
        let n = [0.6, 0.8];
        let z = impedance(stiffness(&turned), rho, n);
        let c = stiffness(&turned);
        let gamma_xy = c[2] * n[0] * n[0] + (c[1] + c[5]) * n[0] * n[1] + c[4] * n[1] * n[1];
        let squared = |i: usize, j: usize| z[i][0] * z[0][j] + z[i][1] * z[1][j];
        assert!((squared(0, 1) - rho * gamma_xy).abs() < 1e-12 * rho * c[0]);
        assert!((squared(0, 1) - squared(1, 0)).abs() < 1e-12 * rho * c[0]);
        assert!(z[0][1] == z[1][0] && z[0][0] > 0.0 && z[0][0] * z[1][1] > z[0][1] * z[0][1]);
        for (normal, n) in [(0, [1.0, 0.0]), (1, [0.0, -1.0])] {
            let z = impedance(stiffness(&ply), rho, n);
            let c = ply.stiffness_pa;
            let along = (rho * c[normal][normal]).sqrt();
            let across = (rho * c[2][2]).sqrt();
            assert!((z[normal][normal] - along).abs() < 1e-13 * along);
            assert!((z[1 - normal][1 - normal] - across).abs() < 1e-13 * along);
            assert_eq!(z[0][1], 0.0);
        }
        let epoxy = Orthotropic::epoxy().reduce(Plane::Strain).unwrap();
        let speeds = epoxy.wave_speeds();
        let (rho, a) = (epoxy.density_kg_m3, 0.4f64);
        let z = impedance(stiffness(&epoxy), rho, [a.cos(), a.sin()]);
        let (n, t) = ([a.cos(), a.sin()], [-a.sin(), a.cos()]);
        for i in 0..2 {
            for j in 0..2 {
                let exact = rho * (speeds.p_x_m_s * n[i] * n[j] + speeds.s_m_s * t[i] * t[j]);
                assert!((z[i][j] - exact).abs() < 1e-12 * rho * speeds.p_x_m_s);
            }
        }
    }
}
