//! The build steps every discretisation shares: the laminate drawn, input ranges and the
//! memory a mesh would take checked before anything is allocated.

use super::crack::CrackPlacement;
use super::spec::{GmshSpec, LaminateSpec, SceneSpec, SourceSpec};
use crate::error::{require_positive, require_within, Error, Result};
use crate::laminate::{Laminate, Layer};
use crate::material::{Material, Orthotropic, Plane};
use crate::mesh::Mesh;
use crate::sem::FineColumns;
use std::collections::HashMap;

pub(super) fn build_laminate(spec: &LaminateSpec, plane: Plane) -> Result<Laminate> {
    match spec {
        LaminateSpec::Stochastic(s) => Laminate::stochastic(s, plane),
        LaminateSpec::Layers { layers } => {
            let mut distinct: Vec<Orthotropic> = Vec::new();
            let mut stack = Vec::new();
            for layer in layers.iter().rev() {
                let constants = layer.material.constants()?;
                let material = distinct
                    .iter()
                    .position(|o| *o == constants)
                    .unwrap_or_else(|| {
                        distinct.push(constants);
                        distinct.len() - 1
                    });
                stack.push(Layer {
                    material,
                    thickness_m: layer.thickness_m,
                });
            }
            let materials = distinct
                .iter()
                .map(|o| o.reduce(plane))
                .collect::<Result<Vec<_>>>()?;
            Laminate::from_layers(materials, stack)
        }
        LaminateSpec::Homogeneous {
            material,
            thickness_m,
        } => Laminate::homogeneous(material.constants()?.reduce(plane)?, *thickness_m),
    }
}

/// The largest traction a transmitter or drive may reach (Pa): 10 GPa, above the strength of
/// any laminate (CFRP fails below 3 GPa); the report drives 50 kPa.
pub const MAX_TRACTION_PA: f64 = 1e10;

/// Physical ranges of the scene's numbers that the build does not meet elsewhere: the
/// transmitter's peak traction in (0, [`MAX_TRACTION_PA`]] and every direction within one
/// turn either way, [-360, 360] degrees (an angle of 1e300 degrees has no direction: its sine
/// is round-off).
pub(super) fn check_ranges(spec: &SceneSpec) -> Result<()> {
    let peak = spec.transmitter.peak_pa;
    if !(peak.is_finite() && peak > 0.0 && peak <= MAX_TRACTION_PA) {
        return Err(Error::invalid(
            "transmitter.peak_pa",
            peak,
            format!(
                "must be within (0, {MAX_TRACTION_PA:e}] Pa (the focusing signals are scaled to \
                 it; 10 GPa is above the strength of any laminate)"
            ),
        ));
    }
    let turn = |field: &str, angle: f64| {
        require_within(
            field,
            angle,
            -360.0,
            360.0,
            "degrees",
            "one turn either way",
        )
    };
    turn("transmitter.angle_deg", spec.transmitter.angle_deg)?;
    for (i, source) in spec.sources.iter().enumerate() {
        if let SourceSpec::Traction { angle_deg, .. } | SourceSpec::Point { angle_deg, .. } = source
        {
            turn(&format!("sources[{i}].angle_deg"), *angle_deg)?;
        }
    }
    Ok(())
}

/// The rectangle a scene occupies: lower left corner and size (m). Sources, receivers and
/// the viscous-spring distances are placed in it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Region {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) width: f64,
    pub(super) height: f64,
}

/// What a scene is built on: the materials (as a laminate), the mesh, the crack's place on
/// it, and the region.
pub(super) type Built = (Laminate, Mesh, Option<CrackPlacement>, Region);

/// Bytes per mesh node of a built scene and its runs (mesh, block-CSR stiffness, mass,
/// operator stencils, solver vectors), a generous upper figure from the default scenes.
pub(super) const BYTES_PER_NODE: f64 = 1024.0;

/// Refuses, before anything is allocated, a mesh (of `orders` GLL intervals per element along
/// x and across, (1, 1) for T3, with the band `fine_x` of narrower columns if any) that is
/// degenerate (fewer than two columns, layers that vanish in floating point, a band outside
/// the width) or whose estimated memory exceeds the limit ([`crate::budget::check_memory`]);
/// the error names the fields the user wrote.
pub(super) fn check_mesh_size(
    spec: &SceneSpec,
    laminate: &Laminate,
    orders: (usize, usize),
    fine_x: Option<&FineColumns>,
) -> Result<()> {
    require_positive("element_size_x_m", spec.element_size_x_m)?;
    require_positive("element_size_y_m", spec.element_size_y_m)?;
    if spec.element_size_x_m > 0.5 * spec.width_m {
        return Err(Error::invalid(
            "element_size_x_m",
            format!("{} m", spec.element_size_x_m),
            format!(
                "must be at most half of width_m = {} m (the mesh needs at least two columns)",
                spec.width_m
            ),
        ));
    }
    if let Some(band) = fine_x {
        band.check(spec.width_m)?;
    }
    let interfaces = laminate.interfaces_m();
    if let Some(k) = interfaces
        .windows(2)
        .position(|w| !(w[1] > w[0]) || !w[1].is_finite())
    {
        return Err(Error::invalid(
            "laminate",
            format!(
                "layer {} of thickness {:e} m",
                k + 1,
                laminate.layers[k].thickness_m
            ),
            format!(
                "a layer vanishes in floating point next to a total thickness of {:e} m \
                 (check laminate.min_epoxy_m and the layer thicknesses)",
                laminate.thickness_m()
            ),
        ));
    }
    let columns = crate::sem::column_count(spec.width_m, spec.element_size_x_m, fine_x);
    let rows: f64 = interfaces
        .windows(2)
        .map(|w| ((w[1] - w[0]) / spec.element_size_y_m).ceil().max(1.0))
        .sum();
    let nodes = (columns * orders.0 as f64 + 1.0) * (rows * orders.1 as f64 + 1.0);
    let (field, band) = match fine_x {
        None => ("element_size_x_m, element_size_y_m", String::new()),
        Some(b) => (
            "element_size_x_m, element_size_y_m, discretisation.fine_x.element_size_m",
            format!(", {} m", b.element_size_m),
        ),
    };
    crate::budget::check_memory(
        field,
        format!(
            "{} m, {} m{band} over width_m = {} m and a laminate {:e} m thick ({columns:.3e} columns x {rows:.3e} rows, {nodes:.3e} nodes at about {} each)",
            spec.element_size_x_m,
            spec.element_size_y_m,
            spec.width_m,
            laminate.thickness_m(),
            crate::budget::format_bytes(BYTES_PER_NODE),
        ),
        nodes * BYTES_PER_NODE,
        "use larger elements or a smaller region",
    )
}

/// The bytes of a Gmsh scene's file: those the caller read (scripts read inside their
/// sandbox), else `gmsh.path` read here.
pub(super) fn gmsh_bytes(g: &GmshSpec) -> Result<std::sync::Arc<Vec<u8>>> {
    match &g.bytes {
        Some(b) => Ok(b.clone()),
        None => Ok(std::sync::Arc::new(std::fs::read(&g.path).map_err(
            |e| Error::invalid("gmsh.path", &g.path, format!("cannot be read: {e}")),
        )?)),
    }
}

/// A Gmsh scene's plane materials, in `gmsh.materials` order, and the index of each
/// physical group's; a key that is not a group tag is an error naming it.
pub(super) fn gmsh_materials(
    spec: &SceneSpec,
    g: &GmshSpec,
) -> Result<(Vec<Material>, HashMap<i32, usize>)> {
    let mut materials = Vec::with_capacity(g.materials.len());
    let mut groups = HashMap::new();
    for (key, material) in &g.materials {
        groups.insert(group_tag("gmsh.materials", key)?, materials.len());
        materials.push(material.constants()?.reduce(spec.plane)?);
    }
    Ok((materials, groups))
}

/// The physical group tag a key of `field` names.
pub(super) fn group_tag(field: &str, key: &str) -> Result<i32> {
    key.trim().parse().map_err(|_| {
        Error::invalid(
            field,
            format!("key \"{key}\""),
            "keys are the tags of physical surface groups, e.g. \"1\"",
        )
    })
}
