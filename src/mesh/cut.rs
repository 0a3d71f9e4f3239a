//! A crack through a quadrilateral mesh: element sides whose two faces are cut apart (split
//! nodes, as SEM2DPACK and SPECFEM2D do for faults), along any chain of sides - inclined,
//! vertical, curved, kinked, branched, several chains, ending inside the body or on its
//! boundary.
//!
//! Around each node of the crack, the elements holding it fall into fans that meet across
//! crack sides only. One fan keeps the node; each other fan gets a copy of it, appended
//! after the mesh's nodes. A node with one fan is a tip inside the body and stays shared.
//! A cut side is then two sides with different corners, which the spectral elements number
//! apart, so each face gets its own points and its own side's mass.

use super::quad::QuadMesh;
use crate::error::{Error, Result};
use std::collections::{BTreeMap, BTreeSet};

/// One cut side: the element on each face and that element's side (0: eta = -1, 1: xi = 1,
/// 2: eta = 1, 3: xi = -1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CutSide {
    /// (element, side) on the master's face: the one the crack's normal points into,
    /// chosen so that the normal has n_y > 0 (n_x > 0 on a vertical side) at the side's
    /// midpoint - the upper face of a horizontal crack, as on the layered rectangle.
    pub master: (usize, usize),
    /// (element, side) on the slave's face.
    pub slave: (usize, usize),
}

impl QuadMesh {
    /// Cuts the mesh along `segments` (pairs of corner nodes, each an element side held by
    /// two elements): the cut mesh and its cut sides, in the order of `segments`. Errors
    /// name the segment: not an element side, on the boundary, given twice.
    pub fn cut(&self, segments: &[[usize; 2]]) -> Result<(QuadMesh, Vec<CutSide>)> {
        let holders = self.side_holders();
        let mut crack = BTreeSet::new();
        let mut sides = Vec::with_capacity(segments.len());
        for &[a, b] in segments {
            let key = (a.min(b), a.max(b));
            let position = |n: usize| {
                self.nodes
                    .get(n)
                    .map_or(String::from("?"), |p| format!("({:e}, {:e}) m", p[0], p[1]))
            };
            let held = holders.get(&key).ok_or_else(|| {
                Error::Mesh(format!(
                    "the crack's segment from node {a} at {} to node {b} at {} is not an \
                     element side: a crack runs along element edges",
                    position(a),
                    position(b)
                ))
            })?;
            if held.len() != 2 {
                return Err(Error::Mesh(format!(
                    "the crack's segment from node {a} at {} to node {b} at {} is on the \
                     body's boundary: a crack runs between two elements",
                    position(a),
                    position(b)
                )));
            }
            if !crack.insert(key) {
                return Err(Error::Mesh(format!(
                    "the crack's segment from node {a} to node {b} is given twice"
                )));
            }
            sides.push(self.faces(held[0], held[1]));
        }
        let mut cut = self.clone();
        let crack_nodes: BTreeSet<usize> = crack.iter().flat_map(|&(a, b)| [a, b]).collect();
        for node in crack_nodes {
            for fan in self.fans(node, &crack).into_iter().skip(1) {
                let copy = cut.nodes.len();
                cut.nodes.push(self.nodes[node]);
                for e in fan {
                    for n in cut.elements[e].nodes.iter_mut().take(4) {
                        if *n == node {
                            *n = copy;
                        }
                    }
                }
            }
        }
        Ok((cut, sides))
    }

    /// For each side (lower corner, higher corner), the (element, side) holding it.
    fn side_holders(&self) -> BTreeMap<(usize, usize), Vec<(usize, usize)>> {
        let mut holders = BTreeMap::<_, Vec<_>>::new();
        for e in 0..self.elements.len() {
            let c = self.corners(e);
            for side in 0..4 {
                let (a, b) = (c[side], c[(side + 1) % 4]);
                holders
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((e, side));
            }
        }
        holders
    }

    /// The two faces of a cut side, master first (see [`CutSide::master`]).
    fn faces(&self, one: (usize, usize), other: (usize, usize)) -> CutSide {
        let n = self.inward_normal(one.0, one.1, 0.0);
        let into_one = n[1] > 1e-12 || (n[1].abs() <= 1e-12 && n[0] > 0.0);
        if into_one {
            CutSide {
                master: one,
                slave: other,
            }
        } else {
            CutSide {
                master: other,
                slave: one,
            }
        }
    }

    /// The unit normal of element `e`'s side `side` pointing into the element, at side
    /// coordinate `s` in [-1, 1] (along xi on sides 0 and 2, along eta on 1 and 3).
    pub fn inward_normal(&self, e: usize, side: usize, s: f64) -> [f64; 2] {
        let (xi, eta) = match side {
            0 => (s, -1.0),
            1 => (1.0, s),
            2 => (s, 1.0),
            _ => (-1.0, s),
        };
        let j = self.map(e, xi, eta).jacobian;
        // the side's tangent counter-clockwise round the element; the inward normal is it
        // turned a quarter counter-clockwise
        let along = side % 2;
        let sign = if side < 2 { 1.0 } else { -1.0 };
        let t = [sign * j[0][along], sign * j[1][along]];
        let length = t[0].hypot(t[1]);
        [-t[1] / length, t[0] / length]
    }

    /// The fans of elements round `node`: the elements holding it as a corner, grouped by
    /// sides through the node that are not in `crack`; ordered by their first element.
    fn fans(&self, node: usize, crack: &BTreeSet<(usize, usize)>) -> Vec<Vec<usize>> {
        let around: Vec<usize> = (0..self.elements.len())
            .filter(|&e| self.corners(e).contains(&node))
            .collect();
        let mut fan_of: Vec<usize> = (0..around.len()).collect();
        let find = |fan_of: &mut Vec<usize>, mut k: usize| {
            while fan_of[k] != k {
                fan_of[k] = fan_of[fan_of[k]];
                k = fan_of[k];
            }
            k
        };
        let joins = |e: usize| {
            let c = self.corners(e);
            (0..4)
                .map(move |side| (c[side], c[(side + 1) % 4]))
                .filter(move |&(a, b)| a == node || b == node)
                .map(|(a, b)| (a.min(b), a.max(b)))
                .filter(|key| !crack.contains(key))
        };
        for (i, &e) in around.iter().enumerate() {
            for (j, &f) in around.iter().enumerate().skip(i + 1) {
                if joins(e).any(|key| joins(f).any(|other| other == key)) {
                    let (a, b) = (find(&mut fan_of, i), find(&mut fan_of, j));
                    fan_of[a.max(b)] = a.min(b);
                }
            }
        }
        let mut fans = BTreeMap::<usize, Vec<usize>>::new();
        for (i, &e) in around.iter().enumerate() {
            let root = find(&mut fan_of, i);
            fans.entry(root).or_default().push(e);
        }
        fans.into_values().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::quad::Quad;

    /// A 4 x 4 grid of unit 4-node squares; node (i, j) at index 5 j + i.
    fn grid() -> QuadMesh {
        let nodes = (0..5)
            .flat_map(|j| (0..5).map(move |i| [i as f64, j as f64]))
            .collect();
        let elements = (0..4)
            .flat_map(|j| (0..4).map(move |i| (i, j)))
            .enumerate()
            .map(|(k, (i, j))| Quad {
                nodes: vec![5 * j + i, 5 * j + i + 1, 5 * j + i + 6, 5 * j + i + 5],
                material: 0,
                angle_rad: 0.0,
                tag: k as u64 + 1,
            })
            .collect();
        QuadMesh { nodes, elements }
    }

    fn at(i: usize, j: usize) -> usize {
        5 * j + i
    }

    /// A crack ending inside keeps its tips shared; a through-crack splits its ends; the
    /// master is the face above a horizontal crack and right of a vertical one.
    #[test]
    fn tips_inside_stay_shared_and_ends_on_the_boundary_split() {
        let mesh = grid();
        // horizontal, from (1, 2) to (3, 2): tips inside, one node between them split
        let (cut, sides) = mesh
            .cut(&[[at(1, 2), at(2, 2)], [at(2, 2), at(3, 2)]])
            .unwrap();
        assert_eq!(cut.nodes.len(), 25 + 1);
        assert_eq!(cut.nodes[25], [2.0, 2.0]);
        for side in &sides {
            let (m, s) = (side.master.0, side.slave.0);
            assert!(m / 4 == 2 && s / 4 == 1, "master above: {side:?}");
        }
        // vertical through-crack at x = 2: all 5 nodes split, the master on the right
        let segments: Vec<[usize; 2]> = (0..4).map(|j| [at(2, j), at(2, j + 1)]).collect();
        let (cut, sides) = mesh.cut(&segments).unwrap();
        assert_eq!(cut.nodes.len(), 25 + 5);
        for side in &sides {
            assert!(side.master.0 % 4 == 2 && side.slave.0 % 4 == 1, "{side:?}");
        }
    }

    /// A kinked crack (an L) splits its corner once; a branched one (a T) gives its
    /// junction a copy per extra fan; two separate cracks are cut in one call.
    #[test]
    fn kinked_branched_and_several_cracks_are_cut_into_their_fans() {
        let mesh = grid();
        let l = [[at(1, 2), at(2, 2)], [at(2, 2), at(2, 3)]];
        assert_eq!(mesh.cut(&l).unwrap().0.nodes.len(), 25 + 1);
        let t = [
            [at(1, 2), at(2, 2)],
            [at(2, 2), at(3, 2)],
            [at(2, 2), at(2, 3)],
        ];
        assert_eq!(mesh.cut(&t).unwrap().0.nodes.len(), 25 + 2);
        let two = [
            [at(1, 1), at(2, 1)],
            [at(2, 1), at(3, 1)],
            [at(1, 3), at(2, 3)],
            [at(2, 3), at(3, 3)],
        ];
        assert_eq!(mesh.cut(&two).unwrap().0.nodes.len(), 25 + 2);
    }

    /// A segment off the element sides, on the boundary or given twice is refused, naming
    /// its nodes.
    #[test]
    fn bad_segments_are_named() {
        let mesh = grid();
        let error = |segments: &[[usize; 2]]| mesh.cut(segments).unwrap_err().to_string();
        let e = error(&[[at(1, 1), at(2, 2)]]);
        assert!(
            e.contains("node 6") && e.contains("not an element side"),
            "{e}"
        );
        let e = error(&[[at(0, 0), at(1, 0)]]);
        assert!(e.contains("boundary"), "{e}");
        let e = error(&[[at(1, 1), at(2, 1)], [at(2, 1), at(1, 1)]]);
        assert!(e.contains("twice"), "{e}");
    }
}
