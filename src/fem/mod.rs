//! Finite element model: element matrices, assembly of K, M and the absorbing edges
//! (report Sec. 4.4-4.7, and the viscous-spring boundary of Liu et al. 2006).

pub mod element;
pub mod memory;
pub mod operator;
pub mod sparse;

use crate::error::{Error, Result};
use crate::material::Material;
use crate::mesh::{Crack, Mesh, Side};
pub use operator::StiffnessOperator;
use serde::{Deserialize, Serialize};
pub use sparse::BlockCsr;

/// Spring factors of the 2D viscous-spring artificial boundary (Liu, Du, Wang & Wu 2006,
/// "3D viscous-spring artificial boundary in time domain", Earthq. Eng. Eng. Vib. 5; the 2D
/// values of Liu & Li 2005): normal K_N = ALPHA_N G / R, tangential K_T = ALPHA_T G / R per
/// unit edge length, G the shear modulus and R the distance from the wave source to the edge.
pub const VISCOUS_SPRING_ALPHA_N: f64 = 1.0;
/// See [`VISCOUS_SPRING_ALPHA_N`].
pub const VISCOUS_SPRING_ALPHA_T: f64 = 0.5;

/// An absorbing edge of the region: Lysmer-Kuhlemeyer dashpots (report Sec. 4.6), plus the
/// springs of the viscous-spring boundary when `spring_distance_m` is set.
///
/// The dashpots alone absorb plane waves at normal incidence exactly but have no static
/// stiffness, so a body held only by them drifts under a net load; pinning points instead
/// makes the low-frequency response depend on the mesh (a point support's compliance grows
/// without bound under refinement in 2D). The springs stand for the static stiffness of the
/// medium beyond the edge: an outgoing cylindrical wave from a source at distance R loads the
/// edge with a traction -(rho c v + alpha G u / R) (Deeks & Randolph 1994). At normal
/// incidence a plane wave of angular frequency omega is reflected with
/// |R| = k / sqrt(k^2 + (2 omega Z)^2), k = alpha G / R, Z = rho c: the price of the static
/// support is a reflection that grows toward low frequency.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AbsorbingEdge {
    /// The side.
    pub side: Side,
    /// Distance R from the wave source to the edge (m) for the springs; `None`: dashpots only.
    pub spring_distance_m: Option<f64>,
}

impl From<Side> for AbsorbingEdge {
    /// Dashpots only (the report's Lysmer-Kuhlemeyer edge).
    fn from(side: Side) -> Self {
        AbsorbingEdge {
            side,
            spring_distance_m: None,
        }
    }
}

/// The discrete model the integrators run: only what the scene asked for exists.
#[derive(Clone, Debug)]
pub struct Model {
    /// The mesh (with the crack's duplicated nodes, if any).
    pub mesh: Mesh,
    /// Materials indexed by `mesh.element_material`.
    pub materials: Vec<Material>,
    /// Assembled stiffness K (symmetric), including the springs of viscous-spring edges.
    pub stiffness: BlockCsr,
    /// Row-sum lumped mass per DOF (kg per unit thickness).
    pub lumped_mass: Vec<f64>,
    /// Lysmer-Kuhlemeyer dashpots as (DOF, coefficient in N s/m), sorted by DOF; empty
    /// when no edge absorbs.
    pub dashpots: Vec<(usize, f64)>,
    /// Fixed DOFs (zero displacement), sorted.
    pub fixed_dofs: Vec<usize>,
    /// The crack, if the scene has one.
    pub crack: Option<Crack>,
    /// Periodic ties as (left DOF, right DOF): u(0, y) = u(width, y) (empty unless
    /// [`Model::tie_periodic`] was called). The integrator keeps each pair equal by
    /// master/slave elimination: the tied DOF has the mass m_l + m_r and the force f_l + f_r
    /// (the system T^T M T, T^T K T of the constraint u_r = u_l).
    pub periodic: Vec<(usize, usize)>,
}

impl Model {
    /// Validates the mesh and assembles K (with the springs of viscous-spring edges), the
    /// lumped M and the dashpots of the `absorbing` edges. A side listed twice is an error.
    pub fn build(
        mesh: Mesh,
        materials: Vec<Material>,
        absorbing: &[AbsorbingEdge],
        mut fixed_dofs: Vec<usize>,
        crack: Option<Crack>,
    ) -> Result<Model> {
        mesh.validate()?;
        if let Some(&d) = fixed_dofs.iter().find(|&&d| d >= mesh.dofs()) {
            return Err(Error::invalid(
                "fixed_dofs",
                d,
                format!("the mesh has {} DOFs", mesh.dofs()),
            ));
        }
        fixed_dofs.sort_unstable();
        fixed_dofs.dedup();
        let sides: Vec<Side> = absorbing.iter().map(|a| a.side).collect();
        if let Some(twice) = sides
            .iter()
            .enumerate()
            .find_map(|(i, s)| sides[..i].contains(s).then_some(s))
        {
            return Err(Error::invalid(
                "absorbing",
                format!("{twice:?}").to_lowercase(),
                "is listed twice (it would absorb twice)",
            ));
        }
        // Large models take seconds per stage: the time limit and Ctrl-C apply between them.
        crate::budget::check()?;
        let mut stiffness = assemble_stiffness(&mesh, &materials)?;
        crate::budget::check()?;
        for edge in absorbing {
            if let Some(r) = edge.spring_distance_m {
                add_edge_springs(&mut stiffness, &mesh, &materials, edge.side, r)?;
            }
        }
        let lumped_mass = assemble_lumped_mass(&mesh, &materials)?;
        crate::budget::check()?;
        let dashpots = assemble_dashpots(&mesh, &materials, &sides)?;
        Ok(Model {
            mesh,
            materials,
            stiffness,
            lumped_mass,
            dashpots,
            fixed_dofs,
            crack,
            periodic: Vec::new(),
        })
    }

    /// Ties the left and right node columns ([`periodic_ties`]).
    pub fn tie_periodic(&mut self) -> Result<()> {
        self.periodic = periodic_ties(&self.mesh, &mut self.fixed_dofs)?;
        Ok(())
    }

    /// Number of DOFs.
    pub fn dofs(&self) -> usize {
        self.lumped_mass.len()
    }
}

/// The ties of periodic left and right edges: every node of the left side of `mesh` to the
/// node of the right side at the same height (both DOFs). A DOF held on either side is
/// added to `fixed_dofs` (sorted) on both. The columns must match node for node (the
/// layered meshes' columns do: they share the row lines; a Gmsh mesh must be made periodic,
/// `gmsh.model.mesh.setPeriodic`); otherwise an error names the first height without a
/// partner.
pub fn periodic_ties(mesh: &Mesh, fixed_dofs: &mut Vec<usize>) -> Result<Vec<(usize, usize)>> {
    let (left, right) = (mesh.side_nodes(Side::Left), mesh.side_nodes(Side::Right));
    let tol = mesh.tolerance();
    if let Some((&l, &r)) = left
        .iter()
        .zip(&right)
        .find(|&(&l, &r)| (mesh.nodes[l][1] - mesh.nodes[r][1]).abs() > tol)
    {
        return Err(Error::invalid(
            "edges.left, edges.right",
            "periodic",
            format!(
                "the left and right node columns do not match: y = {:e} m on the left \
                 against {:e} m on the right",
                mesh.nodes[l][1], mesh.nodes[r][1]
            ),
        ));
    }
    if left.len() != right.len() {
        return Err(Error::invalid(
            "edges.left, edges.right",
            "periodic",
            format!(
                "the left edge has {} nodes, the right edge {}: the columns must match",
                left.len(),
                right.len()
            ),
        ));
    }
    let pairs: Vec<(usize, usize)> = left
        .iter()
        .zip(&right)
        .flat_map(|(&l, &r)| [(2 * l, 2 * r), (2 * l + 1, 2 * r + 1)])
        .collect();
    let held: Vec<usize> = pairs
        .iter()
        .filter(|&&(l, r)| {
            fixed_dofs.binary_search(&l).is_ok() || fixed_dofs.binary_search(&r).is_ok()
        })
        .flat_map(|&(l, r)| [l, r])
        .collect();
    fixed_dofs.extend(held);
    fixed_dofs.sort_unstable();
    fixed_dofs.dedup();
    Ok(pairs)
}

fn element_nodes(mesh: &Mesh, t: [usize; 3]) -> [[f64; 2]; 3] {
    t.map(|n| mesh.nodes[n])
}

fn material_of<'a>(mesh: &Mesh, materials: &'a [Material], e: usize) -> Result<&'a Material> {
    let id = mesh.element_material[e];
    materials.get(id).ok_or_else(|| {
        Error::Mesh(format!(
            "element {e} has material id {id}, but only {} materials exist",
            materials.len()
        ))
    })
}

/// Assembles the global stiffness K = sum_e A_e B_e^T C_e B_e (report Sec. 4.7), row by row
/// in parallel (each block sums its element contributions in element order).
pub fn assemble_stiffness(mesh: &Mesh, materials: &[Material]) -> Result<BlockCsr> {
    if let Some(e) = mesh
        .element_material
        .iter()
        .position(|&id| id >= materials.len())
    {
        material_of(mesh, materials, e)?;
    }
    Ok(BlockCsr::assemble_rows(
        mesh.nodes.len(),
        &mesh.triangles,
        |e, a| {
            let c = &materials[mesh.element_material[e]].stiffness_pa;
            element::stiffness_row(element_nodes(mesh, mesh.triangles[e]), c, a)
        },
    ))
}

/// Assembles the consistent mass matrix (report Sec. 4.4), for Newmark verification runs.
pub fn assemble_consistent_mass(mesh: &Mesh, materials: &[Material]) -> Result<BlockCsr> {
    let mut m = BlockCsr::pattern(mesh.nodes.len(), &mesh.triangles);
    for (e, &t) in mesh.triangles.iter().enumerate() {
        let mat = material_of(mesh, materials, e)?;
        m.add_element(
            t,
            &element::consistent_mass(0.5 * mesh.twice_area(t), mat.density_kg_m3),
        );
    }
    Ok(m)
}

/// Row-sum lumped mass per DOF: each node gets rho A / 3 from every adjacent element.
/// A node that belongs to no element is an error (it would have zero mass).
pub fn assemble_lumped_mass(mesh: &Mesh, materials: &[Material]) -> Result<Vec<f64>> {
    let mut m = vec![0.0; mesh.dofs()];
    for (e, &t) in mesh.triangles.iter().enumerate() {
        let mat = material_of(mesh, materials, e)?;
        let share = element::lumped_mass(0.5 * mesh.twice_area(t), mat.density_kg_m3);
        for n in t {
            m[2 * n] += share;
            m[2 * n + 1] += share;
        }
    }
    if let Some(d) = m.iter().position(|&v| !(v > 0.0)) {
        return Err(Error::Mesh(format!(
            "node {} belongs to no element (zero mass)",
            d / 2
        )));
    }
    Ok(m)
}

/// Axis (0 = x, 1 = y) normal to a side.
fn normal_axis(side: Side) -> usize {
    match side {
        Side::Bottom | Side::Top => 1,
        Side::Left | Side::Right => 0,
    }
}

/// Adds the springs of a viscous-spring edge to K's diagonal: for each boundary edge of
/// length L, each of its two nodes gets ALPHA_N G L / (2 R) normal to the side and
/// ALPHA_T G L / (2 R) along it, G = rho Vs^2 of the element the edge belongs to.
fn add_edge_springs(
    k: &mut BlockCsr,
    mesh: &Mesh,
    materials: &[Material],
    side: Side,
    distance_m: f64,
) -> Result<()> {
    if !(distance_m.is_finite() && distance_m > 0.0) {
        return Err(Error::invalid(
            "absorber.source_distance_m",
            distance_m,
            "must be a positive distance (m)",
        ));
    }
    let axis = normal_axis(side);
    for (e, a, b) in mesh.side_edges(side) {
        let mat = material_of(mesh, materials, e)?;
        let g = mat.density_kg_m3 * mat.wave_speeds().s_m_s.powi(2);
        let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
        let half = 0.5 * (pb[0] - pa[0]).hypot(pb[1] - pa[1]);
        let (k_n, k_t) = (
            VISCOUS_SPRING_ALPHA_N * g * half / distance_m,
            VISCOUS_SPRING_ALPHA_T * g * half / distance_m,
        );
        for n in [a, b] {
            let (kx, ky) = if axis == 0 { (k_n, k_t) } else { (k_t, k_n) };
            k.add_diagonal(n, [kx, ky]);
        }
    }
    Ok(())
}

/// Lysmer-Kuhlemeyer dashpots on absorbing sides: for each boundary edge of length L, each
/// of its two nodes gets rho Vp L / 2 normal to the side and rho Vs L / 2 along it, with rho,
/// Vp, Vs of the element the edge belongs to (the local impedance, not the report's
/// average). Returns (DOF, coefficient) sorted by DOF, empty if `sides` is empty.
pub fn assemble_dashpots(
    mesh: &Mesh,
    materials: &[Material],
    sides: &[Side],
) -> Result<Vec<(usize, f64)>> {
    let mut c = std::collections::BTreeMap::<usize, f64>::new();
    for &side in sides {
        let normal_axis = normal_axis(side);
        for (e, a, b) in mesh.side_edges(side) {
            let mat = material_of(mesh, materials, e)?;
            let w = mat.wave_speeds();
            let vp = if normal_axis == 0 {
                w.p_x_m_s
            } else {
                w.p_y_m_s
            };
            let (pa, pb) = (mesh.nodes[a], mesh.nodes[b]);
            let half = 0.5 * (pb[0] - pa[0]).hypot(pb[1] - pa[1]);
            for n in [a, b] {
                *c.entry(2 * n + normal_axis).or_default() += mat.density_kg_m3 * vp * half;
                *c.entry(2 * n + 1 - normal_axis).or_default() +=
                    mat.density_kg_m3 * w.s_m_s * half;
            }
        }
    }
    Ok(c.into_iter().collect())
}

#[cfg(test)]
mod tests;
