//! Scenes on spectral elements over a Gmsh mesh of quadrilaterals
//! ([`crate::sem::unstructured`]): materials and their axes' angles by physical surface
//! group, loads, receivers and edge conditions on the mesh's bounding box as on the layered
//! rectangle (GLL loads and interpolation, Lysmer-Kuhlemeyer dashpots and viscous springs
//! with GLL edge weights), and the Lanczos step with the element bound.

use super::build::{gmsh_bytes, gmsh_materials, group_tag, Region, BYTES_PER_NODE};
use super::edges::{absorbing_edges, edge_conditions, held_and_pinned_dofs, is_periodic};
use super::sem::{stability, OnSem};
use super::sources::{source_weights, transmitter_weights};
use super::spec::{Absorber, EdgeCondition};
use super::spec::{GmshSpec, SceneSpec, SourceSpec};
use super::{Body, Scene};
use crate::error::{Error, Result};
use crate::laminate::Laminate;
use crate::mesh::Mesh;
use crate::mesh::Side;
use crate::sem::unstructured::UnstructuredSem;
use std::collections::hash_map::Entry;
use std::collections::{HashMap, HashSet};

/// The scene on spectral elements of `order` over `g`'s quadrilaterals.
pub(super) fn build(spec: &SceneSpec, g: &GmshSpec, order: usize) -> Result<Scene> {
    refuse_rectangular_crack(spec)?;
    let bytes = gmsh_bytes(g)?;
    let (mut materials, groups) = gmsh_materials(spec, g)?;
    if let Some(attenuation) = &spec.attenuation {
        crate::attenuation::attenuate(&mut materials, attenuation)?;
    }
    let mut physical: HashMap<i32, (usize, f64)> =
        groups.iter().map(|(&tag, &m)| (tag, (m, 0.0))).collect();
    for (key, &degrees) in &g.angles_deg {
        let tag = group_tag("gmsh.angles_deg", key)?;
        let entry = physical.get_mut(&tag).ok_or_else(|| {
            Error::invalid(
                "gmsh.angles_deg",
                format!("key \"{key}\""),
                "names no group of gmsh.materials",
            )
        })?;
        if !degrees.is_finite() {
            return Err(Error::invalid(
                format!("gmsh.angles_deg.{key}"),
                degrees,
                "must be a finite angle (degrees)",
            ));
        }
        entry.1 = degrees.to_radians();
    }
    let mut mesh = crate::mesh::gmsh::read_quads(&bytes, &physical)
        .map_err(|e| Error::invalid("gmsh.path", &g.path, e.to_string()))?;
    turn_axes_round(&mut mesh, g, &physical)?;
    let points = mesh.elements.len() as f64 * ((order + 1) as f64).powi(2);
    crate::budget::check_memory(
        "gmsh.order",
        format!(
            "{order} on {} elements ({points:.3e} GLL points)",
            mesh.elements.len()
        ),
        points * BYTES_PER_NODE,
        "use a lower order or a coarser mesh",
    )?;
    let uncut = || {
        UnstructuredSem::new(&mesh, materials.clone(), order)
            .map_err(|e| Error::invalid("gmsh.path", &g.path, e.to_string()))
    };
    let cut = |group: i32| {
        let as_crack = |e: Error| Error::invalid("gmsh.crack_line", group, e.to_string());
        let sides = crate::mesh::gmsh::read_line_sides(&bytes, group).map_err(as_crack)?;
        UnstructuredSem::cracked(&mesh, materials.clone(), order, &sides).map_err(as_crack)
    };
    // The crack-tied companion is the uncut mesh, stepped at the cracked model's step.
    let (model, cracked) = match g.crack_line {
        None => (uncut()?, None),
        Some(group) if g.tied => (uncut()?, Some(cut(group)?)),
        Some(group) => (cut(group)?, None),
    };
    crate::budget::check()?;
    let conditions = edge_conditions(spec)?;
    let listed = &g.absorbing_lines;
    if let Some(k) = (1..listed.len()).find(|&k| listed[..k].contains(&listed[k])) {
        return Err(Error::invalid(
            "gmsh.absorbing_lines",
            listed[k],
            "is given twice (it would absorb twice)",
        ));
    }
    let lines = listed
        .iter()
        .map(|&group| {
            crate::mesh::gmsh::read_line_sides(&bytes, group)
                .map(|segments| (group, segments))
                .map_err(|e| Error::invalid("gmsh.absorbing_lines", group, e.to_string()))
        })
        .collect::<Result<Vec<_>>>()?;
    let edges = Edges {
        conditions,
        lines: &lines,
    };
    let Constrained {
        model,
        nodes,
        region,
    } = constrain(spec, &edges, model)?;
    let on = OnSem {
        model: &model,
        nodes: &nodes,
    };
    let transmitter = if spec.sources.is_empty() {
        transmitter_weights(&on, &spec.transmitter, region)?
    } else {
        let mut weights = Vec::new();
        let mut others = Vec::new();
        // each line's unit load, read once however often the list names it
        let mut unit_loads = HashMap::new();
        for (i, source) in spec.sources.iter().enumerate() {
            crate::budget::check()?;
            match *source {
                SourceSpec::Line { line, scale } => {
                    super::sources::check_scale(&format!("sources[{i}]"), scale)?;
                    let load = match unit_loads.entry(line) {
                        Entry::Occupied(read) => read.into_mut(),
                        Entry::Vacant(new) => new.insert(line_load(&model, &bytes, i, line)?),
                    };
                    weights.extend(load.iter().map(|&(d, w)| (d, scale * w)));
                }
                _ => others.push(source.clone()),
            }
        }
        weights.extend(source_weights(&on, &others)?);
        weights
    };
    let receivers = super::build_receivers(&on, &spec.receivers, region.height)?;
    let stability = match cracked {
        Some(c) => stability(&constrain(spec, &edges, c)?.model),
        None => stability(&model),
    };
    Ok(Scene {
        spec: spec.clone(),
        laminate: Laminate {
            materials,
            layers: vec![],
            draws: vec![],
        },
        body: Body::Unstructured { model, nodes },
        transmitter,
        receivers,
        crack_placement: None,
        stability,
    })
}

/// The nodal weights of a unit normal traction on physical line `line` (the load of line
/// source `sources[i]`, [`SourceSpec::Line`], per unit scale and drive): w n at each GLL
/// point of the line.
fn line_load(
    model: &UnstructuredSem,
    bytes: &[u8],
    i: usize,
    line: i32,
) -> Result<Vec<(usize, f64)>> {
    let points = crate::mesh::gmsh::read_line_sides(bytes, line)
        .and_then(|segments| model.line_points(&segments))
        .map_err(|e| Error::invalid(format!("sources[{i}].line"), line, e.to_string()))?;
    Ok(points
        .iter()
        .flat_map(|p| [0, 1].map(|c| (2 * p.node + c, p.weight * p.normal[c])))
        .collect())
}

/// Turns the material axes of `g.axes_round`'s groups element by element: to the hoop
/// direction round the group's point at the element's centre (the map of (0, 0)), plus the
/// group's angle in `physical` (from `angles_deg`). A key naming no group of
/// `gmsh.materials`, or a point not finite, is an error naming it.
fn turn_axes_round(
    mesh: &mut crate::mesh::quad::QuadMesh,
    g: &GmshSpec,
    physical: &HashMap<i32, (usize, f64)>,
) -> Result<()> {
    for (key, &centre) in &g.axes_round {
        let field = format!("gmsh.axes_round.{key}");
        let tag = group_tag("gmsh.axes_round", key)?;
        let &(material, offset) = physical.get(&tag).ok_or_else(|| {
            Error::invalid(
                &field,
                format!("{centre:?}"),
                "names no group of gmsh.materials",
            )
        })?;
        if !centre.iter().all(|c| c.is_finite()) {
            return Err(Error::invalid(
                &field,
                format!("{centre:?}"),
                "must be a finite point (m)",
            ));
        }
        for e in 0..mesh.elements.len() {
            if mesh.elements[e].material == material {
                let x = mesh.map(e, 0.0, 0.0).x;
                let hoop = (x[1] - centre[1]).atan2(x[0] - centre[0]) + std::f64::consts::FRAC_PI_2;
                mesh.elements[e].angle_rad = hoop + offset;
            }
        }
    }
    Ok(())
}

/// A model with its edges' conditions, its GLL nodes as triangles and its bounding box.
struct Constrained {
    model: UnstructuredSem,
    nodes: Mesh,
    region: Region,
}

/// The edge conditions of the bounding box's sides, and the absorbing lines (physical
/// group, its segments).
struct Edges<'a> {
    conditions: [(Side, EdgeCondition); 4],
    lines: &'a [(i32, Vec<[usize; 2]>)],
}

/// `model` with the scene's fixed DOFs, and dashpots and viscous springs on its bounding
/// box's absorbing sides and on its absorbing lines (a crack's faces each get theirs: they
/// are picked by position). A boundary side absorbing twice (a line along an absorbing
/// side, or in two lines) is an error naming the line.
fn constrain(spec: &SceneSpec, edges: &Edges, mut model: UnstructuredSem) -> Result<Constrained> {
    let conditions = &edges.conditions;
    let nodes = node_triangles(&model);
    let (x0, x1, y0, y1) = model.bounds();
    let region = Region {
        x0,
        y0,
        width: x1 - x0,
        height: y1 - y0,
    };
    let absorbing = absorbing_edges(spec, conditions, &nodes, region)?;
    let mut fixed = held_and_pinned_dofs(spec, &nodes, conditions);
    fixed.sort_unstable();
    fixed.dedup();
    if is_periodic(conditions) {
        model.periodic = crate::fem::periodic_ties(&nodes, &mut fixed)?;
    }
    model.fixed_dofs = fixed;
    let mut points = Vec::new();
    // each spring point with its R: its side's, or its distance from the transmitter
    let mut spring_points = Vec::new();
    for edge in &absorbing {
        let side = model.side_points(edge.side);
        if let Some(r) = edge.spring_distance_m {
            spring_points.extend(side.iter().map(|&p| (p, r)));
        }
        points.extend(side);
    }
    let centre = super::sources::source_centre(spec, &nodes, region);
    let source = [x0 + centre[0], y0 + centre[1]];
    let no_point = matches!(
        spec.absorber,
        Absorber::ViscousSpring {
            source_distance_m: None
        }
    ) && !edges.lines.is_empty()
        && source[0].is_nan();
    if no_point {
        return Err(super::sources::no_source_centre("lines"));
    }
    let mut absorbs: HashSet<_> = points.iter().map(|p| (p.element, p.side)).collect();
    for (group, segments) in edges.lines {
        let line = model
            .line_points(segments)
            .map_err(|e| Error::invalid("gmsh.absorbing_lines", group, e.to_string()))?;
        if let Some(p) = line.iter().find(|p| absorbs.contains(&(p.element, p.side))) {
            return Err(Error::invalid(
                "gmsh.absorbing_lines",
                group,
                format!(
                    "absorbs twice at node {} (it runs along an absorbing side or another \
                     absorbing line)",
                    p.node
                ),
            ));
        }
        absorbs.extend(line.iter().map(|p| (p.element, p.side)));
        if let Absorber::ViscousSpring { source_distance_m } = spec.absorber {
            spring_points.extend(line.iter().map(|&p| {
                let x = model.positions_m[p.node];
                let r =
                    source_distance_m.unwrap_or_else(|| (x[0] - source[0]).hypot(x[1] - source[1]));
                (p, r)
            }));
        }
        points.extend(line);
    }
    model.dashpots = model.lysmer_dashpots(&points);
    model.springs = model.viscous_springs(&spring_points)?;
    model.check()?;
    Ok(Constrained {
        model,
        nodes,
        region,
    })
}

/// Refuses a rectangular crack, naming the field: a Gmsh scene's crack is
/// `gmsh.crack_line`. (A crack reaching a periodic edge is refused by
/// [`UnstructuredSem::check`].)
fn refuse_rectangular_crack(spec: &SceneSpec) -> Result<()> {
    if spec.crack.is_some() {
        return Err(Error::invalid(
            "crack",
            "a rectangular crack",
            "a Gmsh scene takes its crack from gmsh.crack_line: set crack: ()",
        ));
    }
    Ok(())
}

/// The GLL nodes as triangles (each GLL cell split along its rising diagonal), numbered as
/// the model numbers them: what nodes are selected on, fields plotted on and written as VTU.
fn node_triangles(model: &UnstructuredSem) -> Mesh {
    let p = model.order;
    let mut triangles = Vec::with_capacity(2 * p * p * model.elements());
    let mut element_material = Vec::with_capacity(triangles.capacity());
    for (e, quad) in model.mesh.elements.iter().enumerate() {
        for j in 0..p {
            for i in 0..p {
                let (a, b) = (model.node(e, i, j), model.node(e, i + 1, j));
                let (c, d) = (model.node(e, i + 1, j + 1), model.node(e, i, j + 1));
                triangles.extend([[a, b, c], [a, c, d]]);
                element_material.extend([quad.material; 2]);
            }
        }
    }
    Mesh {
        nodes: model.positions_m.clone(),
        triangles,
        element_material,
        interfaces_y_m: Vec::new(),
        grid: None,
    }
}
