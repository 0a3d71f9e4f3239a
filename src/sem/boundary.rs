//! What the edges and points of spectral elements carry: GLL quadrature of a side (consistent
//! loads), interpolation weights at a point, Lysmer-Kuhlemeyer dashpots and the viscous-spring
//! edge's springs with GLL edge weights.

use super::SemModel;
use crate::error::{Error, Result};
use crate::fem::{VISCOUS_SPRING_ALPHA_N, VISCOUS_SPRING_ALPHA_T};
use crate::mesh::Side;

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

    /// The springs of a viscous-spring edge on `side` (Liu et al. 2006, as T3's
    /// [`crate::fem::AbsorbingEdge`]), with GLL edge weights: per edge node,
    /// k_N = ALPHA_N G w / R on the normal DOF and k_T = ALPHA_T G w / R on the tangential one,
    /// G = rho V_s^2 of the element the node's weight w comes from, R = `distance_m` from the
    /// wave source (a node shared by two element rows gets both halves). Sorted by DOF; add
    /// them to [`SemModel::springs`] (several sides: extend).
    pub fn viscous_springs(&self, side: Side, distance_m: f64) -> Result<Vec<(usize, f64)>> {
        if !(distance_m.is_finite() && distance_m > 0.0) {
            return Err(Error::invalid(
                "absorber.source_distance_m",
                distance_m,
                "must be a positive distance (m)",
            ));
        }
        let normal = match side {
            Side::Bottom | Side::Top => 1,
            Side::Left | Side::Right => 0,
        };
        let mut k = std::collections::BTreeMap::<usize, f64>::new();
        for (node, weight, row) in self.side_quadrature(side) {
            let mat = &self.materials[self.row_material[row]];
            let g = mat.density_kg_m3 * mat.wave_speeds().s_m_s.powi(2);
            *k.entry(2 * node + normal).or_default() +=
                VISCOUS_SPRING_ALPHA_N * g * weight / distance_m;
            *k.entry(2 * node + 1 - normal).or_default() +=
                VISCOUS_SPRING_ALPHA_T * g * weight / distance_m;
        }
        Ok(k.into_iter().collect())
    }
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
