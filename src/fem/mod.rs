//! Finite element model: element matrices, assembly of K, M and the absorbing dashpots
//! (report Sec. 4.4-4.7).

pub mod element;
pub mod operator;
pub mod sparse;

use crate::error::{Error, Result};
use crate::material::Material;
use crate::mesh::{Crack, Mesh, Side};
pub use operator::StiffnessOperator;
pub use sparse::BlockCsr;

/// The discrete model the integrators run: only what the scene asked for exists.
#[derive(Clone, Debug)]
pub struct Model {
    /// The mesh (with the crack's duplicated nodes, if any).
    pub mesh: Mesh,
    /// Materials indexed by `mesh.element_material`.
    pub materials: Vec<Material>,
    /// Assembled stiffness K (symmetric).
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
}

impl Model {
    /// Validates the mesh and assembles K, the lumped M and the dashpots of `absorbing` sides.
    pub fn build(
        mesh: Mesh,
        materials: Vec<Material>,
        absorbing: &[Side],
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
        let stiffness = assemble_stiffness(&mesh, &materials)?;
        let lumped_mass = assemble_lumped_mass(&mesh, &materials)?;
        let dashpots = assemble_dashpots(&mesh, &materials, absorbing)?;
        Ok(Model {
            mesh,
            materials,
            stiffness,
            lumped_mass,
            dashpots,
            fixed_dofs,
            crack,
        })
    }

    /// Number of DOFs.
    pub fn dofs(&self) -> usize {
        self.lumped_mass.len()
    }
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

/// Lysmer-Kuhlemeyer dashpots on absorbing sides: for each boundary edge of length L, each
/// of its two nodes gets rho Vp L / 2 normal to the side and rho Vs L / 2 along it, with rho,
/// Vp, Vs of the element the edge belongs to (DESIGN.md item 6: the local impedance, not an
/// average). Returns (DOF, coefficient) sorted by DOF, empty if `sides` is empty.
pub fn assemble_dashpots(
    mesh: &Mesh,
    materials: &[Material],
    sides: &[Side],
) -> Result<Vec<(usize, f64)>> {
    let mut c = std::collections::BTreeMap::<usize, f64>::new();
    for &side in sides {
        let normal_axis = match side {
            Side::Bottom | Side::Top => 1,
            Side::Left | Side::Right => 0,
        };
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
