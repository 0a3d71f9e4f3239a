//! Quadrilateral meshes of any shape: straight-sided (4-node, bilinear) or curved (9-node,
//! biquadratic, Gmsh's second-order quads) elements, the geometry the unstructured spectral
//! elements are built on ([`crate::sem::unstructured`]).
//!
//! An element maps the reference square [-1, 1]^2 onto the body by its isoparametric shape
//! functions N_a(xi, eta) = l_a(xi) l_a(eta), the 1-D Lagrange polynomials on the geometry
//! nodes' reference coordinates ({-1, 1}, or {-1, 0, 1} for 9 nodes): x = sum_a N_a x_a
//! (Hughes, *The Finite Element Method*, 2000, Sec. 3.2).

use crate::error::{Error, Result};

/// A mesh of quadrilaterals: geometry nodes and the elements over them.
#[derive(Clone, Debug)]
pub struct QuadMesh {
    /// Geometry node positions (x, y) (m).
    pub nodes: Vec<[f64; 2]>,
    /// The elements.
    pub elements: Vec<Quad>,
}

/// One quadrilateral element.
#[derive(Clone, Debug, PartialEq)]
pub struct Quad {
    /// Geometry nodes in Gmsh's order: the 4 corners counter-clockwise, then for a curved
    /// element the midpoints of sides 0-1, 1-2, 2-3, 3-0 and the centre.
    pub nodes: Vec<usize>,
    /// Material index.
    pub material: usize,
    /// Angle of the material's principal axis from x, counter-clockwise (rad).
    pub angle_rad: f64,
    /// The element's number in messages (its tag in the mesh file).
    pub tag: u64,
}

/// Reference coordinates of the geometry nodes along one direction: 2 for straight sides,
/// 3 for curved ones.
const STRAIGHT: [f64; 2] = [-1.0, 1.0];
const CURVED: [f64; 3] = [-1.0, 0.0, 1.0];

/// (index along xi, index along eta) of each geometry node in the 1-D node sets above, in
/// Gmsh's order.
const CORNERS: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];
const NINE: [(usize, usize); 9] = [
    (0, 0),
    (2, 0),
    (2, 2),
    (0, 2),
    (1, 0),
    (2, 1),
    (1, 2),
    (0, 1),
    (1, 1),
];

/// Values and derivatives of the 1-D Lagrange polynomials on `points` at `s`.
fn lagrange(points: &[f64], s: f64) -> ([f64; 3], [f64; 3]) {
    let (mut l, mut dl) = ([0.0; 3], [0.0; 3]);
    for (a, &pa) in points.iter().enumerate() {
        let others = || points.iter().enumerate().filter(move |&(b, _)| b != a);
        let denominator: f64 = others().map(|(_, &pb)| pa - pb).product();
        l[a] = others().map(|(_, &pb)| s - pb).product::<f64>() / denominator;
        dl[a] = others()
            .map(|(b, _)| {
                others()
                    .filter(|&(c, _)| c != b)
                    .map(|(_, &pc)| s - pc)
                    .product::<f64>()
            })
            .sum::<f64>()
            / denominator;
    }
    (l, dl)
}

/// A point of an element's map: its position and the Jacobian [[x_xi, x_eta], [y_xi, y_eta]].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MappedPoint {
    /// Position (m).
    pub x: [f64; 2],
    /// d(x, y) / d(xi, eta).
    pub jacobian: [[f64; 2]; 2],
}

impl MappedPoint {
    /// det J = x_xi y_eta - x_eta y_xi.
    pub fn det(&self) -> f64 {
        let j = self.jacobian;
        j[0][0] * j[1][1] - j[0][1] * j[1][0]
    }
}

impl QuadMesh {
    /// The map of element `e` at reference point (xi, eta).
    pub fn map(&self, e: usize, xi: f64, eta: f64) -> MappedPoint {
        let quad = &self.elements[e];
        let (points, place): (&[f64], &[(usize, usize)]) = match quad.nodes.len() {
            4 => (&STRAIGHT, &CORNERS),
            _ => (&CURVED, &NINE),
        };
        let (lx, dlx) = lagrange(points, xi);
        let (ly, dly) = lagrange(points, eta);
        let mut p = MappedPoint {
            x: [0.0; 2],
            jacobian: [[0.0; 2]; 2],
        };
        for (&n, &(a, b)) in quad.nodes.iter().zip(place) {
            for (c, &xa) in self.nodes[n].iter().enumerate() {
                p.x[c] += lx[a] * ly[b] * xa;
                p.jacobian[c][0] += dlx[a] * ly[b] * xa;
                p.jacobian[c][1] += lx[a] * dly[b] * xa;
            }
        }
        p
    }

    /// The four corner nodes of element `e`, counter-clockwise.
    pub fn corners(&self, e: usize) -> [usize; 4] {
        let n = &self.elements[e].nodes;
        [n[0], n[1], n[2], n[3]]
    }

    /// Checks the mesh: its nodes are finite, it has elements, every element has 4 or 9
    /// nodes (all of one kind), its node indices and material exist, its angle is finite,
    /// and its Jacobian has one sign at every point of a `samples` x `samples` grid over the reference square (corners included). A
    /// clockwise element (det J < 0 everywhere, as Gmsh writes surfaces whose normal points
    /// along -z) is renumbered counter-clockwise; a sign change or a zero is an error naming
    /// the element: inverted or degenerate.
    pub fn validate(&mut self, materials: usize, samples: usize) -> Result<()> {
        if let Some((n, x)) = self
            .nodes
            .iter()
            .enumerate()
            .find(|(_, x)| !x.iter().all(|v| v.is_finite()))
        {
            return Err(Error::Mesh(format!(
                "node {n} is at ({}, {}): not a finite position",
                x[0], x[1]
            )));
        }
        if self.elements.is_empty() {
            return Err(Error::Mesh("the mesh has no elements".into()));
        }
        let kind = self.elements.first().map_or(4, |q| q.nodes.len());
        for e in 0..self.elements.len() {
            let quad = &self.elements[e];
            if quad.nodes.len() != kind || !(kind == 4 || kind == 9) {
                return Err(Error::Mesh(format!(
                    "element {} has {} nodes where the mesh's first has {kind}: the mesh \
                     must be all 4-node or all 9-node quadrilaterals",
                    quad.tag,
                    quad.nodes.len()
                )));
            }
            if let Some(&n) = quad.nodes.iter().find(|&&n| n >= self.nodes.len()) {
                return Err(Error::Mesh(format!(
                    "element {} names node {n}, the mesh has {}",
                    quad.tag,
                    self.nodes.len()
                )));
            }
            if quad.material >= materials || !quad.angle_rad.is_finite() {
                return Err(Error::Mesh(format!(
                    "element {}: material {} (of {materials}) at angle {} rad",
                    quad.tag, quad.material, quad.angle_rad
                )));
            }
            self.orient(e, samples)?;
        }
        Ok(())
    }

    /// Makes element `e` counter-clockwise, or names it inverted or degenerate.
    fn orient(&mut self, e: usize, samples: usize) -> Result<()> {
        let dets: Vec<f64> = reference_grid(samples.max(2))
            .map(|(xi, eta)| self.map(e, xi, eta).det())
            .collect();
        let scale = self.corner_span(e).powi(2);
        let smallest = dets.iter().fold(f64::INFINITY, |m, d| m.min(d.abs()));
        let quad = &mut self.elements[e];
        let (negative, positive) = (dets.iter().any(|&d| d < 0.0), dets.iter().any(|&d| d > 0.0));
        if negative && positive {
            return Err(Error::Mesh(format!(
                "element {} is inverted: its Jacobian changes sign inside it (corners {:?})",
                quad.tag,
                &quad.nodes[..4]
            )));
        }
        if smallest <= 1e-12 * scale {
            return Err(Error::Mesh(format!(
                "element {} is degenerate: its Jacobian vanishes (corners {:?})",
                quad.tag,
                &quad.nodes[..4]
            )));
        }
        if negative {
            let order: &[usize] = if quad.nodes.len() == 4 {
                &[0, 3, 2, 1]
            } else {
                &[0, 3, 2, 1, 7, 6, 5, 4, 8]
            };
            quad.nodes = order.iter().map(|&i| quad.nodes[i]).collect();
        }
        Ok(())
    }

    /// The longest distance between two of element `e`'s corners (m).
    pub fn corner_span(&self, e: usize) -> f64 {
        let c = self.corners(e).map(|n| self.nodes[n]);
        let mut span: f64 = 0.0;
        for a in 0..4 {
            for b in a + 1..4 {
                span = span.max((c[a][0] - c[b][0]).hypot(c[a][1] - c[b][1]));
            }
        }
        span
    }
}

/// `n` x `n` points spread evenly over [-1, 1]^2, corners included.
fn reference_grid(n: usize) -> impl Iterator<Item = (f64, f64)> {
    let s = move |k: usize| -1.0 + 2.0 * k as f64 / (n - 1) as f64;
    (0..n).flat_map(move |j| (0..n).map(move |i| (s(i), s(j))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(nodes: Vec<[f64; 2]>, order: Vec<usize>) -> QuadMesh {
        QuadMesh {
            nodes,
            elements: vec![Quad {
                nodes: order,
                material: 0,
                angle_rad: 0.0,
                tag: 7,
            }],
        }
    }

    fn unit() -> Vec<[f64; 2]> {
        vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]
    }

    /// The bilinear map of a 2 x 1 rectangle: corners, centre and the constant Jacobian.
    #[test]
    fn a_rectangle_maps_affinely() {
        let m = square(unit(), vec![0, 1, 2, 3]);
        assert_eq!(m.map(0, -1.0, -1.0).x, [0.0, 0.0]);
        assert_eq!(m.map(0, 1.0, 1.0).x, [2.0, 1.0]);
        let c = m.map(0, 0.0, 0.0);
        assert_eq!(c.x, [1.0, 0.5]);
        assert_eq!(c.jacobian, [[1.0, 0.0], [0.0, 0.5]]);
        assert_eq!(c.det(), 0.5);
    }

    /// A 9-node element reproduces a quadratic side: the midpoint node pulled outward by d
    /// puts the side's point at xi = 0 there, and at xi = 1/2 at 3/4 d (the parabola).
    #[test]
    fn a_curved_side_follows_its_parabola() {
        let mut nodes = unit();
        nodes.extend([[1.0, -0.2], [2.0, 0.5], [1.0, 1.0], [0.0, 0.5], [1.0, 0.5]]);
        let m = square(nodes, (0..9).collect());
        assert!((m.map(0, 0.0, -1.0).x[1] + 0.2).abs() < 1e-15);
        assert!((m.map(0, 0.5, -1.0).x[1] + 0.15).abs() < 1e-15);
    }

    /// Clockwise elements are renumbered; a bow tie is inverted and a collapsed element
    /// degenerate, each named by its tag.
    #[test]
    fn orientation_is_fixed_and_bad_elements_are_named() {
        let mut m = square(unit(), vec![0, 3, 2, 1]);
        m.validate(1, 5).unwrap();
        assert_eq!(m.elements[0].nodes, vec![0, 1, 2, 3]);
        assert!(m.map(0, 0.3, -0.4).det() > 0.0);
        let mut bow = square(unit(), vec![0, 1, 3, 2]);
        let e = bow.validate(1, 5).unwrap_err().to_string();
        assert!(e.contains("element 7 is inverted"), "{e}");
        let mut flat = square(
            vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]],
            vec![0, 1, 2, 3],
        );
        let e = flat.validate(1, 5).unwrap_err().to_string();
        assert!(e.contains("element 7 is degenerate"), "{e}");
        let mut missing = square(unit(), vec![0, 1, 2, 9]);
        let e = missing.validate(1, 5).unwrap_err().to_string();
        assert!(e.contains("names node 9"), "{e}");
        let mut far = square(unit(), vec![0, 1, 2, 3]);
        far.nodes[2] = [f64::NAN, 1.0];
        let e = far.validate(1, 5).unwrap_err().to_string();
        assert!(e.contains("node 2 is at (NaN, 1)"), "{e}");
        let mut unknown = square(unit(), vec![0, 1, 2, 3]);
        unknown.elements[0].material = 3;
        let e = unknown.validate(1, 5).unwrap_err().to_string();
        assert!(e.contains("material 3 (of 1)"), "{e}");
    }
}
