//! Spectral elements on unstructured quadrilateral meshes (Komatitsch and Tromp 1999;
//! SPECFEM2D): each element of a [`QuadMesh`], straight-sided or curved, carries the
//! tensor-product GLL points of one order p, mapped onto it by the element's own geometry;
//! GLL quadrature gives a diagonal mass, and the stiffness is applied element by element by
//! sum factorisation with the map's metric at each point.
//!
//! The points are numbered once for the whole mesh: an element corner is the mesh's node,
//! the p - 1 interior points of a side are shared with the element across it (numbered
//! from the side's lower-numbered corner, so both elements agree), and the (p - 1)^2 interior
//! points are the element's own. Global node g has DOFs 2 g (x) and 2 g + 1 (y).
//!
//! The stiffness product K u (see [`kernel`]) runs in two passes so that its sums are the
//! same for any thread count: every element's forces at its own points, in parallel over
//! elements; then every node's sum over the element points that hold it, in a fixed order.
//! The element points are kept in the kernel's lane-major order (8 elements side by side,
//! point by point), so that the kernel reads its nodes and writes its forces a SIMD vector at
//! a time with no transposition.

mod boundary;
mod kernel;
mod memory;

pub use boundary::BoundaryPoint;
#[cfg(test)]
mod tests;

use super::gll::Gll;
use super::MAX_ORDER;
use crate::attenuation::memory::{LaneStiffness, RowMemory};
use crate::error::{Error, Result};
use crate::material::Material;
use crate::mesh::cut::CutSide;
use crate::mesh::quad::QuadMesh;
use crate::mesh::{Crack, CrackPair};
use crate::solve::NodeBlock;
use std::collections::HashMap;

/// Spectral elements of one order on a quadrilateral mesh: the GLL points, their metric,
/// each element's stiffness and the diagonal mass.
#[derive(Clone, Debug)]
pub struct UnstructuredSem {
    /// Polynomial order p of every element (p + 1 GLL points per direction).
    pub order: usize,
    /// Position of each global node (m).
    pub positions_m: Vec<[f64; 2]>,
    /// The plane materials, unrotated.
    pub materials: Vec<Material>,
    /// Diagonal mass per DOF, M = sum over elements of rho w_i w_j det J (kg per m of
    /// thickness).
    pub lumped_mass: Vec<f64>,
    /// DOFs held at zero (none unless set).
    pub fixed_dofs: Vec<usize>,
    /// (node, C) of the dashpots of absorbing sides and lines, 2x2 blocks on the node's
    /// velocity (none unless set, see [`UnstructuredSem::lysmer_dashpots`]); sorted by node,
    /// each node once.
    pub dashpots: Vec<(usize, NodeBlock)>,
    /// (left DOF, right DOF) of periodic left and right edges, which move as one (none
    /// unless set, see [`crate::fem::periodic_ties`]).
    pub periodic: Vec<(usize, usize)>,
    /// (node, K) of the springs of viscous-spring sides and lines, 2x2 blocks on the node's
    /// displacement added to K u (none unless set, see [`UnstructuredSem::viscous_springs`]);
    /// sorted by node, each node once.
    pub springs: Vec<(usize, NodeBlock)>,
    /// The mesh, its elements counter-clockwise (cut along the crack, if any).
    pub mesh: QuadMesh,
    /// The crack's GLL node pairs, each in its own frame (none unless built by
    /// [`UnstructuredSem::cracked`]).
    pub crack: Option<Crack>,
    /// For a cut model, the node of the uncut mesh's model (the crack-tied companion) at
    /// each of its nodes: both faces of a pair map to one node.
    pub uncut_node: Option<Vec<usize>>,
    gll: Gll,
    /// D[i * n + k] = l_k'(x_i), the GLL derivative matrix (n = p + 1).
    derivative: Vec<f64>,
    /// The global node of each element point: element e's point (i, j) (i along xi, j along
    /// eta) at `e * n^2 + j * n + i`.
    global: Vec<usize>,
    /// At each element point, (xi_x, xi_y, eta_x, eta_y, w_i w_j det J), lane-major: point
    /// q of element e at `[(e / LANES) * n^2 + q][component][e % LANES]` (the kernel runs
    /// LANES elements at once, see [`kernel`]); padding lanes past the last element are 0.
    metric: Vec<[Lanes; 5]>,
    /// Each element's plane stiffness in x-y axes (its material turned by its angle), as
    /// (C11, C12, C13, C22, C23, C33) (Pa), lane-major: `[e / LANES][entry][e % LANES]`.
    stiffness: Vec<[Lanes; 6]>,
    /// The number of elements.
    elements: usize,
    /// `global` lane-major, as the kernel reads it: the node of element e's point q at slot
    /// `((e / LANES) * n^2 + q) * LANES + e % LANES`; padding lanes past the last element
    /// name node 0 (their metric is 0, so their forces are 0, and no node gathers them).
    lane_global: Vec<usize>,
    /// The slots (as `lane_global`'s) holding global node g: `incidence[incidence_start[g]..
    /// incidence_start[g + 1]]`, ascending.
    incidence_start: Vec<usize>,
    incidence: Vec<usize>,
}

/// Elements processed at once by the kernel, one per f64 SIMD lane of its array operations
/// (8: two AVX2 registers, as the layered kernel's).
const LANES: usize = 8;

/// One value per element of a lane group.
type Lanes = [f64; LANES];

/// The memory variables of a lane group's elements, each with its own material and axes.
type GroupMemory = RowMemory<LANES, LaneStiffness<LANES>>;

/// Two positions of one node computed from two elements agree when they are closer than
/// this fraction of the element's size: the elements share the side's geometry.
const SHARED_POINT_TOLERANCE: f64 = 1e-9;

impl UnstructuredSem {
    /// Spectral elements of order `order` on `mesh` (validated here: see
    /// [`QuadMesh::validate`]) with `materials` indexed by the elements' `material`. Errors
    /// name what is wrong: an order outside 1..=16, viscoelastic materials with different
    /// relaxation times (a scene's losses share one band and one count of mechanisms), a side
    /// shared by more than two elements, two elements whose shared side is not the same
    /// curve, a Jacobian <= 0 at a GLL point.
    pub fn new(mesh: &QuadMesh, materials: Vec<Material>, order: usize) -> Result<Self> {
        if !(1..=MAX_ORDER).contains(&order) {
            return Err(Error::invalid(
                "order",
                order,
                format!("must be 1..={MAX_ORDER}"),
            ));
        }
        memory::check_shared_relaxation_times(&materials)?;
        let mut mesh = mesh.clone();
        mesh.validate(materials.len(), order + 2)?;
        let gll = Gll::new(order);
        let global = number_points(&mesh, order)?;
        let nodes = global.iter().max().map_or(0, |&g| g + 1);
        let mapped = map_points(&mesh, &materials, &gll, &global, nodes)?;
        let lane_global = lane_major(&global, order + 1);
        let (incidence_start, incidence) = incidence(&global, order + 1, nodes);
        Ok(UnstructuredSem {
            order,
            positions_m: mapped.positions_m,
            lumped_mass: mapped.lumped_mass,
            fixed_dofs: Vec::new(),
            dashpots: Vec::new(),
            springs: Vec::new(),
            periodic: Vec::new(),
            derivative: gll.derivative.iter().flatten().copied().collect(),
            gll,
            global,
            metric: mapped.metric,
            stiffness: element_stiffness(&mesh, &materials),
            elements: mesh.elements.len(),
            mesh,
            crack: None,
            uncut_node: None,
            materials,
            lane_global,
            incidence_start,
            incidence,
        })
    }

    /// Spectral elements on `mesh` cut along `segments` (pairs of corner nodes along element
    /// sides: [`QuadMesh::cut`]), with the crack's pairs: at every GLL point of a cut side,
    /// the node on the master's face and the one on the slave's, with the side's normal
    /// there (into the master; averaged over the sides meeting at a corner). A tip inside
    /// the body is one node and has no pair.
    pub fn cracked(
        mesh: &QuadMesh,
        materials: Vec<Material>,
        order: usize,
        segments: &[[usize; 2]],
    ) -> Result<Self> {
        let mut checked = mesh.clone();
        checked.validate(materials.len(), order + 2)?;
        let (cut, sides) = checked.cut(segments)?;
        let mut model = UnstructuredSem::new(&cut, materials, order)?;
        model.crack = Some(model.crack_pairs(&sides));
        // the elements are the same in both meshes: their points name the uncut node
        let mut uncut_node = vec![0; model.positions_m.len()];
        for (&g, u) in model.global.iter().zip(number_points(&checked, order)?) {
            uncut_node[g] = u;
        }
        model.uncut_node = Some(uncut_node);
        Ok(model)
    }

    /// The GLL node pairs of the cut `sides` (see [`UnstructuredSem::cracked`]).
    fn crack_pairs(&self, sides: &[CutSide]) -> Crack {
        let p = self.order;
        let mut index = HashMap::<(usize, usize), usize>::new();
        let mut pairs: Vec<CrackPair> = Vec::new();
        let mut pieces_m = Vec::with_capacity(sides.len());
        for side in sides {
            let (em, sm) = side.master;
            let (es, ss) = side.slave;
            let at = |e: usize, s: usize, t: usize| {
                let (i, j) = side_point(p, s, t);
                self.node(e, i, j)
            };
            let (first, last) = (
                self.positions_m[at(em, sm, 0)],
                self.positions_m[at(em, sm, p)],
            );
            pieces_m.push([first, last]);
            let same_way = {
                let x = self.positions_m[at(es, ss, 0)];
                (x[0] - first[0]).hypot(x[1] - first[1]) < (x[0] - last[0]).hypot(x[1] - last[1])
            };
            for t in 0..=p {
                let master = at(em, sm, t);
                let slave = at(es, ss, if same_way { t } else { p - t });
                if master == slave {
                    continue;
                }
                let n = self.mesh.inward_normal(em, sm, self.gll.points[t]);
                if let Some(&k) = index.get(&(master, slave)) {
                    pairs[k].normal = [pairs[k].normal[0] + n[0], pairs[k].normal[1] + n[1]];
                } else if let Some(&k) = index.get(&(slave, master)) {
                    pairs[k].normal = [pairs[k].normal[0] - n[0], pairs[k].normal[1] - n[1]];
                } else {
                    index.insert((master, slave), pairs.len());
                    pairs.push(CrackPair {
                        master,
                        slave,
                        normal: n,
                    });
                }
            }
        }
        for pair in &mut pairs {
            let length = pair.normal[0].hypot(pair.normal[1]);
            pair.normal = pair.normal.map(|c| c / length);
        }
        Crack { pieces_m, pairs }
    }

    /// Number of DOFs.
    pub fn dofs(&self) -> usize {
        self.lumped_mass.len()
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.elements
    }

    /// Element `e`'s plane stiffness in x-y axes as (C11, C12, C13, C22, C23, C33) (Pa).
    pub fn element_stiffness(&self, e: usize) -> [f64; 6] {
        self.stiffness[e / LANES].map(|entry| entry[e % LANES])
    }

    /// w_i w_j det J at element `e`'s point q (m^2).
    fn point_weight(&self, e: usize, q: usize) -> f64 {
        let n = self.order + 1;
        self.metric[(e / LANES) * n * n + q][4][e % LANES]
    }

    /// The global node of element `e`'s GLL point (i, j).
    pub fn node(&self, e: usize, i: usize, j: usize) -> usize {
        let n = self.order + 1;
        self.global[(e * n + j) * n + i]
    }

    /// omega_max^2, the largest eigenvalue of M^-1 K over the `free` DOFs (Lanczos), for the
    /// critical step 2 / omega_max; with the number of iterations.
    pub fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize) {
        let work = std::cell::RefCell::new(self.workspace());
        crate::solve::stability::lanczos_max_eigenvalue_of(&self.lumped_mass, free, |x, y| {
            self.stiffness_times(x, y, &mut work.borrow_mut())
        })
    }
}

/// What the elements' maps give at their GLL points.
struct Mapped {
    positions_m: Vec<[f64; 2]>,
    metric: Vec<[Lanes; 5]>,
    lumped_mass: Vec<f64>,
}

/// Maps every element's GLL points: the global nodes' positions (two elements sharing a
/// side must put its points at the same place), the metric (xi_x, xi_y, eta_x, eta_y from
/// the inverse Jacobian, w_i w_j det J) and the GLL mass rho w_i w_j det J summed per node.
/// det J <= 0 at a point is an error naming the element.
fn map_points(
    mesh: &QuadMesh,
    materials: &[Material],
    gll: &Gll,
    global: &[usize],
    nodes: usize,
) -> Result<Mapped> {
    let n = gll.points.len();
    let order = n - 1;
    let mut positions: Vec<Option<[f64; 2]>> = vec![None; nodes];
    let mut metric = vec![[[0.0; LANES]; 5]; mesh.elements.len().div_ceil(LANES) * n * n];
    let mut lumped_mass = vec![0.0; 2 * nodes];
    for (e, quad) in mesh.elements.iter().enumerate() {
        let rho = materials[quad.material].density_kg_m3;
        let tolerance = SHARED_POINT_TOLERANCE * mesh.corner_span(e);
        for j in 0..n {
            for i in 0..n {
                let p = mesh.map(e, gll.points[i], gll.points[j]);
                let det = p.det();
                if det <= 0.0 {
                    return Err(Error::Mesh(format!(
                        "element {}: its Jacobian is {det:e} <= 0 at GLL point ({i}, {j}) \
                         of order {order}: the element is too distorted",
                        quad.tag
                    )));
                }
                let g = global[(e * n + j) * n + i];
                match positions[g] {
                    None => positions[g] = Some(p.x),
                    Some(x) if (x[0] - p.x[0]).hypot(x[1] - p.x[1]) <= tolerance => {}
                    Some(x) => {
                        return Err(Error::Mesh(format!(
                            "element {} puts a point of a side it shares at ({:e}, {:e}) m \
                             where its neighbour puts it at ({:e}, {:e}) m: the two elements \
                             must share the side's nodes",
                            quad.tag, p.x[0], p.x[1], x[0], x[1]
                        )))
                    }
                }
                let [[x_xi, x_eta], [y_xi, y_eta]] = p.jacobian;
                let w = gll.weights[i] * gll.weights[j] * det;
                let values = [y_eta / det, -x_eta / det, -y_xi / det, x_xi / det, w];
                let at = &mut metric[(e / LANES) * n * n + j * n + i];
                for (component, v) in at.iter_mut().zip(values) {
                    component[e % LANES] = v;
                }
                lumped_mass[2 * g] += rho * w;
                lumped_mass[2 * g + 1] += rho * w;
            }
        }
    }
    Ok(Mapped {
        positions_m: positions
            .into_iter()
            .map(|x| x.unwrap_or_default())
            .collect(),
        metric,
        lumped_mass,
    })
}

/// Each element's plane stiffness in x-y axes, its material turned by its angle
/// ([`Material::rotated`]), lane-major as [`UnstructuredSem::stiffness`] holds it.
fn element_stiffness(mesh: &QuadMesh, materials: &[Material]) -> Vec<[Lanes; 6]> {
    let mut stiffness = vec![[[0.0; LANES]; 6]; mesh.elements.len().div_ceil(LANES)];
    for (e, q) in mesh.elements.iter().enumerate() {
        let c = materials[q.material].rotated(q.angle_rad).stiffness_pa;
        let values = [c[0][0], c[0][1], c[0][2], c[1][1], c[1][2], c[2][2]];
        for (entry, v) in stiffness[e / LANES].iter_mut().zip(values) {
            entry[e % LANES] = v;
        }
    }
    stiffness
}

/// The global node of every element point (see [`UnstructuredSem::global`]), numbered in
/// the order the elements first reach them; a side held by more than two elements is an
/// error naming the third.
fn number_points(mesh: &QuadMesh, order: usize) -> Result<Vec<usize>> {
    let n = order + 1;
    let inner = order - 1;
    let mut next = 0;
    let mut fresh = |count: usize| {
        let first = next;
        next += count;
        first
    };
    let mut corner_node: HashMap<usize, usize> = HashMap::new();
    // side (lower corner, higher corner) -> (its first interior node, elements holding it)
    let mut side_node: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
    let mut global = vec![0; mesh.elements.len() * n * n];
    for (e, quad) in mesh.elements.iter().enumerate() {
        let c = mesh.corners(e);
        let at = |i: usize, j: usize| (e * n + j) * n + i;
        for (k, (i, j)) in [(0, 0), (order, 0), (order, order), (0, order)]
            .into_iter()
            .enumerate()
        {
            global[at(i, j)] = *corner_node.entry(c[k]).or_insert_with(|| fresh(1));
        }
        let ends = [(c[0], c[1]), (c[1], c[2]), (c[3], c[2]), (c[0], c[3])];
        for (side, (a, b)) in ends.into_iter().enumerate() {
            let key = (a.min(b), a.max(b));
            let entry = side_node.entry(key).or_insert_with(|| (fresh(inner), 0));
            entry.1 += 1;
            if entry.1 > 2 {
                return Err(Error::Mesh(format!(
                    "element {} is the third to hold the side between nodes {} and {}: a \
                     side joins at most two elements",
                    quad.tag, key.0, key.1
                )));
            }
            for k in 1..order {
                let along = if a < b { k } else { order - k };
                let (i, j) = side_point(order, side, k);
                global[at(i, j)] = entry.0 + along - 1;
            }
        }
        let interior = fresh(inner * inner);
        for j in 1..order {
            for i in 1..order {
                global[at(i, j)] = interior + (j - 1) * inner + (i - 1);
            }
        }
    }
    Ok(global)
}

/// The element point (i, j) of the t-th of the p + 1 GLL points along side `side` of an
/// element of order `order`, counted from its start corner: side 0 (eta = -1) and side 2
/// (eta = 1) run along xi, side 1 (xi = 1) and side 3 (xi = -1) along eta.
fn side_point(order: usize, side: usize, t: usize) -> (usize, usize) {
    match side {
        0 => (t, 0),
        1 => (order, t),
        2 => (t, order),
        _ => (0, t),
    }
}

/// Element e's point q's slot in the kernel's lane-major order (see
/// [`UnstructuredSem::lane_global`]), n points per direction.
fn slot(e: usize, q: usize, n: usize) -> usize {
    ((e / LANES) * n * n + q) * LANES + e % LANES
}

/// `global` (element-major, n points per direction) in the kernel's lane-major order, the
/// padding lanes on node 0.
fn lane_major(global: &[usize], n: usize) -> Vec<usize> {
    let elements = global.len() / (n * n);
    let mut lanes = vec![0; elements.div_ceil(LANES) * LANES * n * n];
    for (point, &g) in global.iter().enumerate() {
        lanes[slot(point / (n * n), point % (n * n), n)] = g;
    }
    lanes
}

/// Each node's slots (lane-major, [`slot`]), ascending, as (start, slots): node g's are
/// `slots[start[g]..start[g + 1]]`.
fn incidence(global: &[usize], n: usize, nodes: usize) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0; nodes + 1];
    for &g in global {
        start[g + 1] += 1;
    }
    for g in 0..nodes {
        start[g + 1] += start[g];
    }
    let mut slots: Vec<(usize, usize)> = global
        .iter()
        .enumerate()
        .map(|(point, &g)| (g, slot(point / (n * n), point % (n * n), n)))
        .collect();
    slots.sort_unstable();
    (start, slots.into_iter().map(|(_, s)| s).collect())
}
