//! Layer-conforming T3 meshes, node sets and crack insertion (report Sec. 4, 4.9).

use crate::error::{require_positive, Error, Result};
use crate::laminate::Laminate;
use serde::Serialize;
use std::collections::HashSet;

pub mod cut;
pub mod gmsh;
pub mod quad;

/// A side of the rectangular region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// y = y_min.
    Bottom,
    /// y = y_max (the free surface with the receivers).
    Top,
    /// x = x_min.
    Left,
    /// x = x_max (the transmitter's edge).
    Right,
}

impl Side {
    /// The side's name as scripts write it (`bottom`, `top`, `left`, `right`).
    pub fn name(self) -> &'static str {
        match self {
            Side::Bottom => "bottom",
            Side::Top => "top",
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// The rectilinear grid behind a structured mesh: node (i, j) has index `j * x.len() + i`.
#[derive(Clone, Debug, Serialize)]
pub struct Grid {
    /// Column coordinates (m), increasing.
    pub x_m: Vec<f64>,
    /// Row coordinates (m), increasing.
    pub y_m: Vec<f64>,
}

impl Grid {
    /// Index of the interior row line (not the bottom or top edge) a crack at height `y_m`
    /// snaps to, see [`snap_to_interior_line`].
    pub fn snap_row(&self, y_m: f64) -> Option<usize> {
        snap_to_interior_line(&self.y_m, y_m)
    }

    /// Index of the interior column line (not the left or right edge) a crack tip at `x_m`
    /// snaps to, see [`snap_to_interior_line`].
    pub fn snap_column(&self, x_m: f64) -> Option<usize> {
        snap_to_interior_line(&self.x_m, x_m)
    }
}

/// Snaps `v` onto increasing grid `lines`: the nearer end of the grid interval containing
/// `v`, if that end is an interior line (neither the first nor the last) and lies within
/// half the interval (the tolerance of snapping, so the mesh itself never changes). `None`
/// when `v` is outside the lines or only a boundary line is that close.
pub fn snap_to_interior_line(lines: &[f64], v: f64) -> Option<usize> {
    let n = lines.len();
    if n < 3 || !(v >= lines[0] && v <= lines[n - 1]) {
        return None;
    }
    let hi = lines.partition_point(|&l| l <= v).clamp(1, n - 1);
    let lo = hi - 1;
    let half = 0.5 * (lines[hi] - lines[lo]);
    [lo, hi]
        .into_iter()
        .filter(|&i| i > 0 && i < n - 1 && (lines[i] - v).abs() <= half)
        .min_by(|&a, &b| (lines[a] - v).abs().total_cmp(&(lines[b] - v).abs()))
}

/// An unstructured T3 mesh with element materials (counter-clockwise triangles).
#[derive(Clone, Debug, Serialize)]
pub struct Mesh {
    /// Node coordinates (m).
    pub nodes: Vec<[f64; 2]>,
    /// Triangles as node indices, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Material index of each triangle.
    pub element_material: Vec<usize>,
    /// Heights of the layer interfaces (m), for plots.
    pub interfaces_y_m: Vec<f64>,
    /// The grid, for a structured mesh built by [`Mesh::layered`].
    pub grid: Option<Grid>,
}

/// The normal of a horizontal crack's pairs: the master's face above the slave's.
pub const UP: [f64; 2] = [0.0, 1.0];

/// One crack node pair: `master` on the upper face, `slave` on the lower face (of a
/// horizontal crack; on any other, the faces `normal` points into and out of).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CrackPair {
    /// Upper-face node (keeps the original index).
    pub master: usize,
    /// Lower-face node (the duplicate).
    pub slave: usize,
    /// The crack's unit normal at the pair, from the slave's face into the master's side:
    /// (0, 1) on a horizontal crack.
    pub normal: [f64; 2],
}

/// A crack: its node pairs (a tip inside the body is a shared node, not a pair).
#[derive(Clone, Debug, Serialize)]
pub struct Crack {
    /// The crack's straight pieces, each from one end (x, y) to the other (m): one from the
    /// left tip to the right of a horizontal crack, the chord of each element side cut
    /// otherwise.
    pub pieces_m: Vec<[[f64; 2]; 2]>,
    /// Node pairs; along x on a horizontal crack.
    pub pairs: Vec<CrackPair>,
}

/// The layer holding height `y` given the interface heights from the bottom face up.
fn layer_at(interfaces: &[f64], y: f64) -> usize {
    interfaces.partition_point(|&h| h <= y).saturating_sub(1)
}

/// Relative tolerance on the number of elements per interval: an interval that is a whole
/// number of element sizes up to round-off (12e-3 / 50e-6 = 240.00000000000003) gets that
/// number, not one more.
const COUNT_TOLERANCE: f64 = 1e-9;

/// How many pieces no longer than `h` [`subdivide`] cuts [a, b] into (as a float, so that
/// a memory check can count them before anything is allocated).
pub(crate) fn piece_count(a: f64, b: f64, h: f64) -> f64 {
    ((b - a) / h * (1.0 - COUNT_TOLERANCE)).ceil().max(1.0)
}

/// Splits [a, b] with breakpoints into pieces no longer than `h` (at least one per piece,
/// up to the relative round-off [`COUNT_TOLERANCE`]).
pub(crate) fn subdivide(breaks: &[f64], h: f64) -> Vec<f64> {
    let mut out = vec![breaks[0]];
    for w in breaks.windows(2) {
        let n = piece_count(w[0], w[1], h) as usize;
        for k in 1..=n {
            out.push(if k == n {
                w[1]
            } else {
                w[0] + (w[1] - w[0]) * k as f64 / n as f64
            });
        }
    }
    out
}

/// Sorted breakpoints of [lo, hi]: `fixed` kept as they are, each extra break snapped to
/// the nearest existing one when closer than `snap`, to avoid sliver elements.
fn merge_breaks(
    lo: f64,
    hi: f64,
    fixed: &[f64],
    extra: &[f64],
    snap: f64,
    field: &str,
) -> Result<Vec<f64>> {
    let mut b: Vec<f64> = fixed.to_vec();
    b.push(lo);
    b.push(hi);
    for &e in extra {
        if !(e.is_finite() && e > lo && e < hi) {
            return Err(Error::invalid(
                field,
                e,
                format!("must lie strictly inside ({lo}, {hi})"),
            ));
        }
        let nearest = b
            .iter()
            .map(|v| (v - e).abs())
            .fold(f64::INFINITY, f64::min);
        if nearest >= snap {
            b.push(e);
        }
    }
    b.sort_by(f64::total_cmp);
    b.dedup_by(|a, b| (*a - *b).abs() < 1e-12 * (hi - lo));
    Ok(b)
}

impl Mesh {
    /// A structured, layer-conforming mesh of the rectangle [0, width] x [0, laminate thickness].
    ///
    /// Columns are at most `hx` wide; element rows are at most `hy` high, every layer
    /// interface is a row line and every layer gets at least one row. `x_breaks` and
    /// `y_breaks` add lines the mesh must conform to; a break closer than a quarter element
    /// to an existing line snaps to it. (Scenes pass none: a crack snaps onto the lines of
    /// this mesh, see [`Grid::snap_row`], so that a crack never changes the discretisation.)
    /// Each rectangular cell is split along its rising diagonal into two counter-clockwise T3.
    pub fn layered(
        laminate: &Laminate,
        width_m: f64,
        hx: f64,
        hy: f64,
        x_breaks: &[f64],
        y_breaks: &[f64],
    ) -> Result<Mesh> {
        require_positive("width_m", width_m)?;
        require_positive("element_size_x_m", hx)?;
        require_positive("element_size_y_m", hy)?;
        let interfaces = laminate.interfaces_m();
        let height = *interfaces.last().unwrap();
        let xb = merge_breaks(0.0, width_m, &[], x_breaks, 0.25 * hx, "x_breaks")?;
        let yb = merge_breaks(0.0, height, &interfaces, y_breaks, 0.25 * hy, "y_breaks")?;
        let grid = Grid {
            x_m: subdivide(&xb, hx),
            y_m: subdivide(&yb, hy),
        };
        let cells = (grid.x_m.len() - 1) * (grid.y_m.len() - 1);
        if cells > 50_000_000 {
            return Err(Error::invalid(
                "element_size",
                format!("{hx} x {hy}"),
                format!("gives {cells} cells, more than 5e7"),
            ));
        }
        let layer_material: Vec<usize> = laminate.layers.iter().map(|l| l.material).collect();
        Ok(Self::from_grid(grid, &interfaces, &layer_material))
    }

    /// The layer (0 at the bottom) of every triangle, from its centroid's height and the
    /// layer interfaces; `None` for a mesh without interfaces (a Gmsh import).
    pub fn element_layers(&self) -> Option<Vec<usize>> {
        if self.interfaces_y_m.is_empty() {
            return None;
        }
        let centroid_y = |t: &[usize; 3]| t.iter().map(|&n| self.nodes[n][1]).sum::<f64>() / 3.0;
        Some(
            self.triangles
                .iter()
                .map(|t| layer_at(&self.interfaces_y_m, centroid_y(t)))
                .collect(),
        )
    }

    /// The tensor grid of `grid`'s lines, node (i, j) at index `j * nx + i`, each cell split
    /// along its rising diagonal into two T3, each row of cells taking the material of the
    /// layer holding its middle.
    pub(crate) fn from_grid(grid: Grid, interfaces: &[f64], layer_material: &[usize]) -> Mesh {
        let (nxn, nyn) = (grid.x_m.len(), grid.y_m.len());
        let mut nodes = Vec::with_capacity(nxn * nyn);
        for &y in &grid.y_m {
            for &x in &grid.x_m {
                nodes.push([x, y]);
            }
        }
        let mut triangles = Vec::with_capacity(2 * (nxn - 1) * (nyn - 1));
        let mut element_material = Vec::with_capacity(triangles.capacity());
        for j in 0..nyn - 1 {
            let y_mid = 0.5 * (grid.y_m[j] + grid.y_m[j + 1]);
            let layer = layer_at(interfaces, y_mid);
            let material = layer_material[layer.min(layer_material.len() - 1)];
            for i in 0..nxn - 1 {
                let n00 = j * nxn + i;
                let (n10, n01, n11) = (n00 + 1, n00 + nxn, n00 + nxn + 1);
                triangles.push([n00, n10, n11]);
                triangles.push([n00, n11, n01]);
                element_material.push(material);
                element_material.push(material);
            }
        }
        Mesh {
            nodes,
            triangles,
            element_material,
            interfaces_y_m: interfaces.to_vec(),
            grid: Some(grid),
        }
    }

    /// Number of degrees of freedom (2 per node).
    pub fn dofs(&self) -> usize {
        2 * self.nodes.len()
    }

    /// Bounding box (x_min, x_max, y_min, y_max).
    pub fn bounds(&self) -> (f64, f64, f64, f64) {
        self.nodes.iter().fold(
            (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ),
            |(a, b, c, d), p| (a.min(p[0]), b.max(p[0]), c.min(p[1]), d.max(p[1])),
        )
    }

    /// Geometric tolerance: 1e-9 of the bounding-box diagonal.
    pub fn tolerance(&self) -> f64 {
        let (x0, x1, y0, y1) = self.bounds();
        1e-9 * ((x1 - x0).hypot(y1 - y0))
    }

    /// Twice the signed area of a triangle.
    pub fn twice_area(&self, t: [usize; 3]) -> f64 {
        let [a, b, c] = t.map(|n| self.nodes[n]);
        (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
    }

    /// Rejects non-finite coordinates and zero-area or inverted (clockwise) elements.
    pub fn validate(&self) -> Result<()> {
        if let Some((i, p)) = self
            .nodes
            .iter()
            .enumerate()
            .find(|(_, p)| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Err(Error::Mesh(format!(
                "node {i} has a non-finite coordinate {p:?}"
            )));
        }
        let scale = self.tolerance().powi(2);
        for (e, &t) in self.triangles.iter().enumerate() {
            if let Some(&n) = t.iter().find(|&&n| n >= self.nodes.len()) {
                return Err(Error::Mesh(format!(
                    "element {e} refers to node {n}, but there are {} nodes",
                    self.nodes.len()
                )));
            }
            let a2 = self.twice_area(t);
            if a2 <= scale {
                let kind = if a2.abs() <= scale {
                    "zero-area"
                } else {
                    "inverted (clockwise)"
                };
                return Err(Error::Mesh(format!(
                    "element {e} with nodes {t:?} is {kind}: signed area {:.3e} m^2",
                    0.5 * a2
                )));
            }
        }
        Ok(())
    }

    /// Nodes on one side of the bounding box, sorted along it.
    pub fn side_nodes(&self, side: Side) -> Vec<usize> {
        let (x0, x1, y0, y1) = self.bounds();
        let tol = self.tolerance();
        let (axis, value) = match side {
            Side::Bottom => (1, y0),
            Side::Top => (1, y1),
            Side::Left => (0, x0),
            Side::Right => (0, x1),
        };
        let mut v: Vec<usize> = (0..self.nodes.len())
            .filter(|&n| (self.nodes[n][axis] - value).abs() <= tol)
            .collect();
        v.sort_by(|&a, &b| self.nodes[a][1 - axis].total_cmp(&self.nodes[b][1 - axis]));
        v
    }

    /// Boundary edges on a side as (element, node a, node b).
    pub fn side_edges(&self, side: Side) -> Vec<(usize, usize, usize)> {
        let mut on_side = vec![false; self.nodes.len()];
        for n in self.side_nodes(side) {
            on_side[n] = true;
        }
        let mut edges = Vec::new();
        for (e, t) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if on_side[a] && on_side[b] {
                    edges.push((e, a, b));
                }
            }
        }
        edges
    }

    /// The node nearest to a point.
    pub fn nearest_node(&self, p: [f64; 2]) -> usize {
        let d2 = |n: &[f64; 2]| (n[0] - p[0]).powi(2) + (n[1] - p[1]).powi(2);
        (0..self.nodes.len())
            .min_by(|&a, &b| d2(&self.nodes[a]).total_cmp(&d2(&self.nodes[b])))
            .unwrap_or(0)
    }

    /// Nodes lying on the segment p..q (within the mesh tolerance), sorted from p to q.
    pub fn nodes_on_segment(&self, p: [f64; 2], q: [f64; 2]) -> Vec<usize> {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        let len2 = dx * dx + dy * dy;
        let tol = self.tolerance();
        let param =
            |n: &[f64; 2]| ((n[0] - p[0]) * dx + (n[1] - p[1]) * dy) / len2.max(f64::MIN_POSITIVE);
        let mut v: Vec<(f64, usize)> = self
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(i, n)| {
                let s = param(n);
                let dist = ((n[0] - p[0]) * dy - (n[1] - p[1]) * dx).abs()
                    / len2.sqrt().max(f64::MIN_POSITIVE);
                (dist <= tol && (-1e-12..=1.0 + 1e-12).contains(&s)).then_some((s, i))
            })
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v.into_iter().map(|(_, i)| i).collect()
    }

    /// The element that holds `p` and the barycentric coordinates of `p` in it (they sum to
    /// 1; each is >= 0 inside). Of the elements that could hold it, the one where `p` lies
    /// deepest inside (the largest smallest coordinate), so a point on an edge or a node
    /// has one answer; coordinates within 1e-12 of 0 are set to 0 and the rest renormalised,
    /// so a point on a node gets exactly (1, 0, 0). `None` outside the mesh (beyond the
    /// mesh tolerance).
    pub fn locate(&self, p: [f64; 2]) -> Option<(usize, [f64; 3])> {
        let mut best: Option<(usize, [f64; 3], f64)> = None;
        for (e, &t) in self.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|n| self.nodes[n]);
            let twice = self.twice_area(t);
            let lambda = [
                ((b[0] - p[0]) * (c[1] - p[1]) - (c[0] - p[0]) * (b[1] - p[1])) / twice,
                ((c[0] - p[0]) * (a[1] - p[1]) - (a[0] - p[0]) * (c[1] - p[1])) / twice,
                ((a[0] - p[0]) * (b[1] - p[1]) - (b[0] - p[0]) * (a[1] - p[1])) / twice,
            ];
            let depth = lambda.iter().copied().fold(f64::INFINITY, f64::min);
            if best.as_ref().is_none_or(|&(_, _, d)| depth > d) {
                best = Some((e, lambda, depth));
            }
        }
        let (e, mut lambda, depth) = best?;
        // outside every element by more than the tolerance (relative to the element size)
        let size = self.twice_area(self.triangles[e]).sqrt();
        if depth < -self.tolerance() / size.max(f64::MIN_POSITIVE) {
            return None;
        }
        for l in &mut lambda {
            if l.abs() < 1e-12 {
                *l = 0.0;
            }
        }
        let sum: f64 = lambda.iter().sum();
        Some((e, lambda.map(|l| l / sum)))
    }

    /// The grid row line nearest to `y` (structured meshes), for snapping a crack onto the mesh.
    pub fn nearest_row_y(&self, y: f64) -> Option<f64> {
        let g = self.grid.as_ref()?;
        g.y_m
            .iter()
            .copied()
            .min_by(|a, b| (a - y).abs().total_cmp(&(b - y).abs()))
    }

    /// The grid column line nearest to `x` (structured meshes).
    pub fn nearest_column_x(&self, x: f64) -> Option<f64> {
        let g = self.grid.as_ref()?;
        g.x_m
            .iter()
            .copied()
            .min_by(|a, b| (a - x).abs().total_cmp(&(b - x).abs()))
    }

    /// Inserts a horizontal crack from (x0, y) to (x1, y) along mesh lines (report Sec. 4.9).
    ///
    /// Nodes strictly inside the segment are duplicated: the original stays with the
    /// elements above the line (master, upper face), the copy goes to the elements below
    /// (slave, lower face). Tip nodes stay shared.
    pub fn insert_crack(&mut self, y_m: f64, x0_m: f64, x1_m: f64) -> Result<Crack> {
        let (bx0, bx1, by0, by1) = self.bounds();
        let tol = self.tolerance();
        if !(x0_m.is_finite() && x1_m.is_finite() && y_m.is_finite()) || x0_m >= x1_m {
            return Err(Error::invalid(
                "crack",
                format!("x {x0_m}..{x1_m}, y {y_m}"),
                "needs finite x0 < x1 and a finite y",
            ));
        }
        if x0_m <= bx0 + tol || x1_m >= bx1 - tol || y_m <= by0 + tol || y_m >= by1 - tol {
            return Err(Error::invalid(
                "crack",
                format!("x {x0_m}..{x1_m} m, y {y_m} m"),
                format!("must lie strictly inside the domain x ({bx0}, {bx1}), y ({by0}, {by1})"),
            ));
        }
        let line = self.nodes_on_segment([x0_m, y_m], [x1_m, y_m]);
        let at = |x: f64| line.iter().any(|&n| (self.nodes[n][0] - x).abs() <= tol);
        if !at(x0_m) || !at(x1_m) || line.len() < 3 {
            return Err(Error::invalid(
                "crack",
                format!("x {x0_m}..{x1_m} m, y {y_m} m"),
                format!("is not on mesh lines: {} nodes on the segment; both tips must be mesh nodes with at least one node between them", line.len()),
            ));
        }
        self.check_segment_edges(&line)?;
        let interior = &line[1..line.len() - 1];
        let mut pairs = Vec::with_capacity(interior.len());
        let mut slave_of = std::collections::HashMap::with_capacity(interior.len());
        for &master in interior {
            let slave = self.nodes.len();
            self.nodes.push(self.nodes[master]);
            slave_of.insert(master, slave);
            pairs.push(CrackPair {
                master,
                slave,
                normal: UP,
            });
        }
        for t in &mut self.triangles {
            let centroid_y =
                (self.nodes[t[0]][1] + self.nodes[t[1]][1] + self.nodes[t[2]][1]) / 3.0;
            if centroid_y < y_m {
                for n in t.iter_mut() {
                    if let Some(&s) = slave_of.get(n) {
                        *n = s;
                    }
                }
            }
        }
        Ok(Crack {
            pieces_m: vec![[[x0_m, y_m], [x1_m, y_m]]],
            pairs,
        })
    }

    /// Checks that consecutive nodes of a line are joined by element edges.
    fn check_segment_edges(&self, line: &[usize]) -> Result<()> {
        let mut edges = HashSet::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        for w in line.windows(2) {
            if !edges.contains(&(w[0].min(w[1]), w[0].max(w[1]))) {
                let p = self.nodes[w[0]];
                return Err(Error::Mesh(format!(
                    "crack segment leaves the mesh lines near ({:.6e}, {:.6e}) m",
                    p[0], p[1]
                )));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laminate::StochasticSpec;
    use crate::material::Plane;

    #[test]
    fn whole_numbers_of_elements_survive_round_off() {
        // 12e-3 / 50e-6 = 240.00000000000003 in floating point: 240 rows, not 241.
        assert_eq!(subdivide(&[0.0, 12e-3], 50e-6).len(), 241);
        assert_eq!(subdivide(&[0.0, 12e-3 + 1e-7], 50e-6).len(), 242);
        assert_eq!(subdivide(&[0.0, 1e-6], 50e-6).len(), 2);
    }

    fn cfrp_mesh() -> (Laminate, Mesh) {
        let lam = Laminate::stochastic(
            &StochasticSpec {
                pairs: 10,
                ..Default::default()
            },
            Plane::Strain,
        )
        .unwrap();
        let mesh = Mesh::layered(&lam, 4e-3, 100e-6, 50e-6, &[], &[]).unwrap();
        (lam, mesh)
    }

    #[test]
    fn rows_contain_every_layer_interface_and_thin_layers_get_a_row() {
        let (lam, mesh) = cfrp_mesh();
        let rows = &mesh.grid.as_ref().unwrap().y_m;
        for y in lam.interfaces_m() {
            assert!(
                rows.iter().any(|r| (r - y).abs() < 1e-15),
                "interface {y} not a row line"
            );
        }
        // every element lies inside one layer: its material is that layer's
        let layers = mesh.element_layers().unwrap();
        for (e, t) in mesh.triangles.iter().enumerate() {
            let yc = t.iter().map(|&n| mesh.nodes[n][1]).sum::<f64>() / 3.0;
            let layer = lam.interfaces_m().partition_point(|&y| y <= yc) - 1;
            assert_eq!(layers[e], layer);
            assert_eq!(mesh.element_material[e], lam.layers[layer].material);
        }
        assert!(rows
            .windows(2)
            .all(|w| w[1] - w[0] <= 50e-6 * (1.0 + 1e-12)));
        mesh.validate().unwrap();
    }

    #[test]
    fn crack_faces_share_no_interior_node() {
        let (_, mut mesh) = cfrp_mesh();
        let y = mesh.nearest_row_y(0.6e-3).unwrap();
        let (x0, x1) = (
            mesh.nearest_column_x(1e-3).unwrap(),
            mesh.nearest_column_x(2e-3).unwrap(),
        );
        let n_before = mesh.nodes.len();
        let crack = mesh.insert_crack(y, x0, x1).unwrap();
        assert_eq!(crack.pairs.len(), 9); // 1 mm at 0.1 mm columns: 11 nodes, 9 inside
        assert_eq!(mesh.nodes.len(), n_before + 9);
        let masters: HashSet<usize> = crack.pairs.iter().map(|p| p.master).collect();
        let slaves: HashSet<usize> = crack.pairs.iter().map(|p| p.slave).collect();
        for t in &mesh.triangles {
            let yc = t.iter().map(|&n| mesh.nodes[n][1]).sum::<f64>() / 3.0;
            for n in t {
                if yc < y {
                    assert!(
                        !masters.contains(n),
                        "element below uses an upper-face node"
                    );
                } else {
                    assert!(!slaves.contains(n), "element above uses a lower-face node");
                }
            }
        }
        assert!(crack
            .pairs
            .windows(2)
            .all(|w| mesh.nodes[w[0].master][0] < mesh.nodes[w[1].master][0]));
        mesh.validate().unwrap();
    }

    #[test]
    fn crack_off_mesh_or_outside_is_an_error_saying_where() {
        let (_, mut mesh) = cfrp_mesh();
        let e = mesh
            .insert_crack(0.5e-3, 1e-3, 9e-3)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("strictly inside the domain") && e.contains("9"),
            "{e}"
        );
        let y = mesh.nearest_row_y(0.6e-3).unwrap();
        let e = mesh.insert_crack(y, 1.03e-3, 2e-3).unwrap_err().to_string();
        assert!(e.contains("not on mesh lines"), "{e}");
    }

    #[test]
    fn snapping_takes_the_nearer_interior_line_within_half_an_interval() {
        let lines = [0.0, 1.0, 2.0, 4.0, 5.0];
        assert_eq!(snap_to_interior_line(&lines, 2.0), Some(2));
        assert_eq!(snap_to_interior_line(&lines, 2.9), Some(2));
        assert_eq!(snap_to_interior_line(&lines, 3.1), Some(3));
        assert_eq!(snap_to_interior_line(&lines, 3.0), Some(2)); // a tie takes the lower line
        assert_eq!(snap_to_interior_line(&lines, 0.6), Some(1));
        // nearer to an edge than to an interior line, or outside: no line
        assert_eq!(snap_to_interior_line(&lines, 0.4), None);
        assert_eq!(snap_to_interior_line(&lines, 4.7), None);
        assert_eq!(snap_to_interior_line(&lines, 5.0), None);
        assert_eq!(snap_to_interior_line(&lines, -0.1), None);
        assert_eq!(snap_to_interior_line(&lines, f64::NAN), None);
        assert_eq!(snap_to_interior_line(&[0.0, 1.0], 0.5), None);
    }

    #[test]
    fn inverted_element_is_rejected() {
        let (_, mut mesh) = cfrp_mesh();
        mesh.triangles[5].swap(1, 2);
        assert!(mesh
            .validate()
            .unwrap_err()
            .to_string()
            .contains("element 5"));
        let (_, mut mesh) = cfrp_mesh();
        mesh.nodes[3] = [f64::NAN, 0.0];
        assert!(mesh.validate().unwrap_err().to_string().contains("node 3"));
    }
}
