//! Where unstructured spectral elements meet the outside: their sides on the straight edges
//! of the body's bounding box (loads, dashpots and springs there, with the GLL edge
//! quadrature), and the interpolation of a point inside any element.

use super::{side_point, UnstructuredSem};
use crate::error::Result;
use crate::mesh::Side;
use crate::sem::boundary::{side_dashpots, side_springs, SidePoint};
use crate::sem::gll::Gll;
use std::collections::BTreeMap;

/// One element side on an edge of the bounding box.
#[derive(Clone, Copy, Debug)]
struct EdgeSide {
    element: usize,
    /// 0: eta = -1, 1: xi = 1, 2: eta = 1, 3: xi = -1.
    side: usize,
}

/// Newton steps of the inverse map; it converges quadratically from the element's centre.
const NEWTON_STEPS: usize = 40;

impl UnstructuredSem {
    /// The element point (i, j) of the t-th GLL point along side `side`.
    fn side_point(&self, side: usize, t: usize) -> (usize, usize) {
        side_point(self.order, side, t)
    }

    /// The reference point (xi, eta) at coordinate `s` along side `side`.
    fn side_reference(side: usize, s: f64) -> (f64, f64) {
        match side {
            0 => (s, -1.0),
            1 => (1.0, s),
            2 => (s, 1.0),
            _ => (-1.0, s),
        }
    }

    /// The bounding box (x0, x1, y0, y1) of the nodes.
    pub fn bounds(&self) -> (f64, f64, f64, f64) {
        self.positions_m.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), x| (a.min(x[0]), b.max(x[0]), c.min(x[1]), d.max(x[1])),
        )
    }

    /// The coordinate across `side` (y on the top and bottom, x on the left and right) and
    /// its value on the bounding box.
    fn edge_line(&self, side: Side) -> (usize, f64) {
        let (x0, x1, y0, y1) = self.bounds();
        match side {
            Side::Bottom => (1, y0),
            Side::Top => (1, y1),
            Side::Left => (0, x0),
            Side::Right => (0, x1),
        }
    }

    /// The element sides whose every GLL point lies on `side` of the bounding box (within
    /// 1e-9 of its size), in element order.
    fn edge_sides(&self, side: Side) -> Vec<EdgeSide> {
        let (across, line) = self.edge_line(side);
        let (x0, x1, y0, y1) = self.bounds();
        let tolerance = 1e-9 * (x1 - x0).hypot(y1 - y0);
        (0..self.elements())
            .flat_map(|element| (0..4).map(move |side| EdgeSide { element, side }))
            .filter(|s| {
                (0..=self.order).all(|t| {
                    let (i, j) = self.side_point(s.side, t);
                    let x = self.positions_m[self.node(s.element, i, j)];
                    (x[across] - line).abs() <= tolerance
                })
            })
            .collect()
    }

    /// |dx/ds| along an element side at side coordinate `s`.
    fn side_stretch(&self, edge: EdgeSide, s: f64) -> f64 {
        let (xi, eta) = Self::side_reference(edge.side, s);
        let j = self.mesh.map(edge.element, xi, eta).jacobian;
        let column = edge.side % 2;
        j[0][column].hypot(j[1][column])
    }

    /// The GLL quadrature along `side`: (node, weight w_t |dx/ds|, element) of every point
    /// of every element side on it.
    fn side_quadrature(&self, side: Side) -> Vec<(usize, f64, usize)> {
        let mut out = Vec::new();
        for edge in self.edge_sides(side) {
            for t in 0..=self.order {
                let (i, j) = self.side_point(edge.side, t);
                let w = self.gll.weights[t] * self.side_stretch(edge, self.gll.points[t]);
                out.push((self.node(edge.element, i, j), w, edge.element));
            }
        }
        out
    }

    /// The consistent load of a unit traction on the part `from..to` of `side` (along x on
    /// the top and bottom, y on the left and right): per node, the integral of its GLL
    /// Lagrange polynomial times |dx/ds| over the part, by Gauss-Lobatto quadrature of order
    /// p + 2 on each element side's covered piece (exact for straight sides; the covered
    /// piece's ends found by bisection along the side). Sorted by node; empty when the part
    /// covers no side.
    pub fn side_load(&self, side: Side, from: f64, to: f64) -> Vec<(usize, f64)> {
        let along = 1 - self.edge_line(side).0;
        let fine = Gll::new(self.order + 2);
        let mut load = BTreeMap::<usize, f64>::new();
        for edge in self.edge_sides(side) {
            let coordinate = |s: f64| {
                let (xi, eta) = Self::side_reference(edge.side, s);
                self.mesh.map(edge.element, xi, eta).x[along]
            };
            let (c0, c1) = (coordinate(-1.0), coordinate(1.0));
            let (lo, hi) = (from.max(c0.min(c1)), to.min(c0.max(c1)));
            if lo >= hi {
                continue;
            }
            let (sa, sb) = (solve_along(&coordinate, lo), solve_along(&coordinate, hi));
            let (sa, sb) = (sa.min(sb), sa.max(sb));
            for (&x, &w) in fine.points.iter().zip(&fine.weights) {
                let s = 0.5 * (sa + sb) + 0.5 * (sb - sa) * x;
                let weight = 0.5 * (sb - sa) * w * self.side_stretch(edge, s);
                for (t, l) in self.gll.lagrange_at(s).into_iter().enumerate() {
                    let (i, j) = self.side_point(edge.side, t);
                    *load.entry(self.node(edge.element, i, j)).or_default() += l * weight;
                }
            }
        }
        load.into_iter().filter(|&(_, w)| w != 0.0).collect()
    }

    /// The interpolation weights of the point (x, y): the GLL Lagrange polynomials of the
    /// first element (in mesh order) whose map reaches it, at the reference point found by
    /// Newton's method; `None` when no element holds it.
    pub fn point_weights(&self, x: f64, y: f64) -> Option<Vec<(usize, f64)>> {
        let (e, xi, eta) = (0..self.elements()).find_map(|e| {
            self.near(e, x, y)
                .then(|| self.reference_point(e, x, y))
                .flatten()
                .map(|(xi, eta)| (e, xi, eta))
        })?;
        let (lx, ly) = (self.gll.lagrange_at(xi), self.gll.lagrange_at(eta));
        let mut weights = Vec::new();
        for (j, wy) in ly.iter().enumerate() {
            for (i, wx) in lx.iter().enumerate() {
                if wx * wy != 0.0 {
                    weights.push((self.node(e, i, j), wx * wy));
                }
            }
        }
        Some(weights)
    }

    /// Whether (x, y) lies within element `e`'s geometry nodes' box widened by a quarter of
    /// its span (a curved side bulges past its nodes).
    fn near(&self, e: usize, x: f64, y: f64) -> bool {
        let pad = 0.25 * self.mesh.corner_span(e);
        let nodes = &self.mesh.elements[e].nodes;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &n in nodes {
            for c in 0..2 {
                lo[c] = lo[c].min(self.mesh.nodes[n][c]);
                hi[c] = hi[c].max(self.mesh.nodes[n][c]);
            }
        }
        x >= lo[0] - pad && x <= hi[0] + pad && y >= lo[1] - pad && y <= hi[1] + pad
    }

    /// The reference point of (x, y) in element `e` (Newton on x(xi, eta) = (x, y) from the
    /// centre), clamped onto the square when within 1e-9 of it; `None` outside.
    fn reference_point(&self, e: usize, x: f64, y: f64) -> Option<(f64, f64)> {
        let (mut xi, mut eta) = (0.0, 0.0);
        let scale = self.mesh.corner_span(e);
        for _ in 0..NEWTON_STEPS {
            let p = self.mesh.map(e, xi, eta);
            let (rx, ry) = (p.x[0] - x, p.x[1] - y);
            let [[a, b], [c, d]] = p.jacobian;
            let det = p.det();
            let (dxi, deta) = ((d * rx - b * ry) / det, (a * ry - c * rx) / det);
            xi -= dxi;
            eta -= deta;
            if !(xi.is_finite() && eta.is_finite()) || xi.abs() > 3.0 || eta.abs() > 3.0 {
                return None;
            }
            if rx.hypot(ry) <= 1e-14 * scale {
                break;
            }
        }
        let inside = |v: f64| v.abs() <= 1.0 + 1e-9;
        (inside(xi) && inside(eta)).then(|| (xi.clamp(-1.0, 1.0), eta.clamp(-1.0, 1.0)))
    }

    /// Lysmer-Kuhlemeyer dashpots of the `sides` with GLL edge weights, as the layered
    /// model's ([`crate::sem::SemModel::lysmer_dashpots`]), from the element's stiffness in
    /// x-y axes. Sorted by DOF.
    pub fn lysmer_dashpots(&self, sides: &[Side]) -> Vec<(usize, f64)> {
        let mut c = BTreeMap::new();
        for &side in sides {
            side_dashpots(&mut c, &self.side_points(side));
        }
        c.into_iter().collect()
    }

    /// The springs of a viscous-spring edge on `side` (Liu et al. 2006), as the layered
    /// model's ([`crate::sem::SemModel::viscous_springs`]), G = C_33 of the element,
    /// R = `distance_m`. Sorted by DOF.
    pub fn viscous_springs(&self, side: Side, distance_m: f64) -> Result<Vec<(usize, f64)>> {
        side_springs(&self.side_points(side), distance_m)
    }

    /// The GLL points of `side` with their element's density and moduli in x-y axes.
    fn side_points(&self, side: Side) -> Vec<SidePoint> {
        let normal = self.edge_line(side).0;
        self.side_quadrature(side)
            .into_iter()
            .map(|(node, weight, e)| {
                let k = self.element_stiffness(e);
                SidePoint {
                    node,
                    normal,
                    weight,
                    density_kg_m3: self.materials[self.mesh.elements[e].material].density_kg_m3,
                    c_normal_pa: if normal == 0 { k[0] } else { k[3] },
                    c_shear_pa: k[5],
                }
            })
            .collect()
    }
}

/// The side coordinate s in [-1, 1] where the monotone `coordinate(s)` equals `value`
/// (bisection to round-off: 60 halvings of [-1, 1]).
fn solve_along(coordinate: &dyn Fn(f64) -> f64, value: f64) -> f64 {
    let (mut a, mut b) = (-1.0, 1.0);
    let rising = coordinate(b) > coordinate(a);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if (coordinate(m) < value) == rising {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}
