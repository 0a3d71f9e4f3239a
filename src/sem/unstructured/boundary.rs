//! Where unstructured spectral elements meet the outside: their sides on the straight edges
//! of the body's bounding box (loads there), dashpots and springs on those and on any line
//! of boundary sides (straight, inclined or curved; in each point's own normal frame, with
//! the GLL edge quadrature), and the interpolation of a point inside any element.

use super::{side_point, UnstructuredSem};
use crate::error::{Error, Result};
use crate::fem::{VISCOUS_SPRING_ALPHA_N, VISCOUS_SPRING_ALPHA_T};
use crate::mesh::Side;
use crate::sem::boundary::impedance;
use crate::sem::gll::Gll;
use crate::solve::NodeBlock;
use std::collections::{BTreeMap, HashMap};

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

    /// The GLL points of the bounding box's `side`, with its outward normal.
    pub fn side_points(&self, side: Side) -> Vec<BoundaryPoint> {
        let normal = match side {
            Side::Bottom => [0.0, -1.0],
            Side::Top => [0.0, 1.0],
            Side::Left => [-1.0, 0.0],
            Side::Right => [1.0, 0.0],
        };
        (self.edge_sides(side).into_iter())
            .flat_map(|edge| self.edge_points(edge, |_| normal))
            .collect()
    }

    /// The GLL points of element side `edge`, with the outward normal `normal(s)` at side
    /// coordinate s and the weight w_t |dx/ds|.
    fn edge_points(&self, edge: EdgeSide, normal: impl Fn(f64) -> [f64; 2]) -> Vec<BoundaryPoint> {
        (0..=self.order)
            .map(|t| {
                let (i, j) = self.side_point(edge.side, t);
                let s = self.gll.points[t];
                BoundaryPoint {
                    node: self.node(edge.element, i, j),
                    weight: self.gll.weights[t] * self.side_stretch(edge, s),
                    element: edge.element,
                    side: edge.side,
                    normal: normal(s),
                }
            })
            .collect()
    }

    /// The GLL points of the element sides along `segments` (pairs of the mesh's nodes, as
    /// [`crate::mesh::gmsh::read_line_sides`] gives a physical line), each with the outward
    /// normal of its side there. A segment must be the side of exactly one element (on the
    /// boundary; a crack's faces count as two); an error names its nodes otherwise.
    pub fn line_points(&self, segments: &[[usize; 2]]) -> Result<Vec<BoundaryPoint>> {
        let key = |a: usize, b: usize| {
            let [p, q] = [a, b].map(|n| self.mesh.nodes[n].map(f64::to_bits));
            (p.min(q), p.max(q))
        };
        let mut sides: HashMap<_, Vec<EdgeSide>> = HashMap::new();
        for element in 0..self.elements() {
            let c = self.mesh.corners(element);
            let ends = [(c[0], c[1]), (c[1], c[2]), (c[3], c[2]), (c[0], c[3])];
            for (side, (a, b)) in ends.into_iter().enumerate() {
                sides
                    .entry(key(a, b))
                    .or_default()
                    .push(EdgeSide { element, side });
            }
        }
        let mut points = Vec::new();
        for &[a, b] in segments {
            let on = |n: usize| n < self.mesh.nodes.len();
            let held = if on(a) && on(b) {
                sides.get(&key(a, b)).map_or(&[][..], Vec::as_slice)
            } else {
                &[]
            };
            let &[edge] = held else {
                return Err(Error::Mesh(format!(
                    "the line segment between nodes {a} and {b} is {}",
                    match held.len() {
                        0 => "not an element side".to_string(),
                        n => format!("the side of {n} elements, not on the boundary"),
                    }
                )));
            };
            let outward = |s| {
                self.mesh
                    .inward_normal(edge.element, edge.side, s)
                    .map(|c| -c)
            };
            points.extend(self.edge_points(edge, outward));
        }
        Ok(points)
    }

    /// Lysmer-Kuhlemeyer dashpots at `points` (report Sec. 4.6, with GLL edge weights): per
    /// point Z w, Z = sqrt(rho Gamma(n)) the impedance of waves crossing the boundary at
    /// normal incidence in its element's material in x-y axes
    /// ([`crate::sem::boundary::impedance`]); summed per node, sorted by node.
    pub fn lysmer_dashpots(&self, points: &[BoundaryPoint]) -> Vec<(usize, NodeBlock)> {
        sum_per_node(points.iter().map(|p| {
            let rho = self.materials[self.mesh.elements[p.element].material].density_kg_m3;
            let z = impedance(self.element_stiffness(p.element), rho, p.normal);
            (p.node, z.map(|row| row.map(|v| v * p.weight)))
        }))
    }

    /// The springs of a viscous-spring boundary at `points`, each with its R (Liu et al.
    /// 2006, as the layered model's [`crate::sem::SemModel::viscous_springs`]): per point
    /// (G w / R) (ALPHA_N n n^T + ALPHA_T t t^T), G the element's shear modulus in the
    /// boundary's frame ([`shear_modulus_across`]) and R the distance from the wave source;
    /// summed per node, sorted by node. An error names `absorber.source_distance_m` where R
    /// is not positive.
    pub fn viscous_springs(
        &self,
        points: &[(BoundaryPoint, f64)],
    ) -> Result<Vec<(usize, NodeBlock)>> {
        let mut blocks = Vec::with_capacity(points.len());
        for &(p, r) in points {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::invalid(
                    "absorber.source_distance_m",
                    r,
                    "must be a positive distance from the wave source to the absorbing \
                     boundary (m)",
                ));
            }
            let (n, t) = (p.normal, [-p.normal[1], p.normal[0]]);
            let g = shear_modulus_across(self.element_stiffness(p.element), n) * p.weight / r;
            let k = |i: usize, j: usize| {
                g * (VISCOUS_SPRING_ALPHA_N * n[i] * n[j] + VISCOUS_SPRING_ALPHA_T * t[i] * t[j])
            };
            blocks.push((p.node, [[k(0, 0), k(0, 1)], [k(1, 0), k(1, 1)]]));
        }
        Ok(sum_per_node(blocks))
    }
}

/// The shear modulus G = C'33 of the plane stiffness `c` = (C11, C12, C13, C22, C23, C33)
/// in the frame (t, n) of a boundary of unit normal n, t = (-n_y, n_x): the stress t.sigma.n
/// of the unit shear strain gamma_tn = 1, eps^T C eps with eps = (t_x n_x, t_y n_y,
/// t_x n_y + t_y n_x) in Voigt form. C33 itself on a side along x or y; the same for the
/// body turned with its boundary.
fn shear_modulus_across(c: [f64; 6], n: [f64; 2]) -> f64 {
    let [c11, c12, c13, c22, c23, c33] = c;
    let t = [-n[1], n[0]];
    let e = [t[0] * n[0], t[1] * n[1], t[0] * n[1] + t[1] * n[0]];
    c11 * e[0] * e[0]
        + c22 * e[1] * e[1]
        + c33 * e[2] * e[2]
        + 2.0 * (c12 * e[0] * e[1] + c13 * e[0] * e[2] + c23 * e[1] * e[2])
}

/// A GLL point on the boundary.
#[derive(Clone, Copy, Debug)]
pub struct BoundaryPoint {
    /// Its global node.
    pub node: usize,
    /// Its edge weight w_t |dx/ds| (m).
    pub weight: f64,
    /// The element whose side it is on.
    pub element: usize,
    /// Which side: 0: eta = -1, 1: xi = 1, 2: eta = 1, 3: xi = -1.
    pub side: usize,
    /// The boundary's outward unit normal there.
    pub normal: [f64; 2],
}

/// The blocks summed per node (a node shared by two sides gets both), sorted by node.
fn sum_per_node(blocks: impl IntoIterator<Item = (usize, NodeBlock)>) -> Vec<(usize, NodeBlock)> {
    let mut sum = BTreeMap::<usize, NodeBlock>::new();
    for (node, b) in blocks {
        let s = sum.entry(node).or_insert([[0.0; 2]; 2]);
        for i in 0..2 {
            for j in 0..2 {
                s[i][j] += b[i][j];
            }
        }
    }
    sum.into_iter().collect()
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
