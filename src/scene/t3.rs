//! Scenes on the report's linear triangles: the layer-conforming rectangle or a Gmsh mesh.

use super::build::{build_laminate, check_mesh_size, gmsh_bytes, gmsh_materials, Built, Region};
use super::crack::{place_crack, split_stability, CrackPlacement};
use super::edges::{absorbing_edges, edge_conditions, held_and_pinned_dofs, is_periodic};
use super::sources::{build_receivers, source_weights, transmitter_weights, Attach};
use super::spec::{GmshSpec, SceneSpec};
use super::{Body, Scene};
use crate::error::{require_positive, Error, Result};
use crate::fem::Model;
use crate::laminate::Laminate;
use crate::mesh::{Mesh, Side};
use crate::solve::{self, point_receiver, segment_receiver, segment_shares, Quantity, Receiver};

/// The layered rectangle [0, width_m] x [0, laminate thickness]: laminate, its mesh and the
/// crack placed on the mesh lines.
fn layered_mesh(spec: &SceneSpec) -> Result<Built> {
    require_positive("width_m", spec.width_m)?;
    let laminate = build_laminate(&spec.laminate, spec.plane)?;
    let height = laminate.thickness_m();
    check_mesh_size(spec, &laminate, (1, 1), None)?;
    let mesh = Mesh::layered(
        &laminate,
        spec.width_m,
        spec.element_size_x_m,
        spec.element_size_y_m,
        &[],
        &[],
    )?;
    let crack_placement = spec
        .crack
        .as_ref()
        .map(|c| {
            let grid = mesh.grid.as_ref().expect("a layered mesh is a grid");
            place_crack(spec, c, grid, height)
        })
        .transpose()?;
    let region = Region {
        x0: 0.0,
        y0: 0.0,
        width: spec.width_m,
        height,
    };
    Ok((laminate, mesh, crack_placement, region))
}

/// The Gmsh scene: its materials (as a laminate without layers), mesh and crack line; the
/// region is the mesh's bounding box.
fn gmsh_mesh(spec: &SceneSpec, g: &GmshSpec) -> Result<Built> {
    if spec.crack.is_some() {
        return Err(Error::invalid(
            "crack",
            "a rectangular crack",
            "a Gmsh scene takes its crack from gmsh.crack_line: set crack: ()",
        ));
    }
    let on_quads = "is built on spectral elements only: set gmsh.order on a mesh of quadrilaterals";
    if let Some(key) = g.angles_deg.keys().next() {
        return Err(Error::invalid(
            format!("gmsh.angles_deg.{key}"),
            "given",
            on_quads,
        ));
    }
    if let Some(key) = g.axes_round.keys().next() {
        return Err(Error::invalid(
            format!("gmsh.axes_round.{key}"),
            "given",
            on_quads,
        ));
    }
    if let Some(line) = g.absorbing_lines.first() {
        return Err(Error::invalid("gmsh.absorbing_lines", line, on_quads));
    }
    let bytes = gmsh_bytes(g)?;
    let (materials, groups) = gmsh_materials(spec, g)?;
    let mesh = crate::mesh::gmsh::read_msh(&bytes, &groups)
        .map_err(|e| Error::invalid("gmsh.path", &g.path, e.to_string()))?;
    let placement = g
        .crack_line
        .map(|group| gmsh_crack(&bytes, group, &mesh, g.tied))
        .transpose()?;
    let (x0, x1, y0, y1) = mesh.bounds();
    let laminate = Laminate {
        materials,
        layers: vec![],
        draws: vec![],
    };
    let region = Region {
        x0,
        y0,
        width: x1 - x0,
        height: y1 - y0,
    };
    Ok((laminate, mesh, placement, region))
}

/// The crack of a Gmsh scene: the nodes of physical line `group`, which must be a
/// horizontal straight line of mesh nodes (every node of the mesh on its segment belongs to
/// it; that its consecutive nodes are element edges is checked when it is inserted).
fn gmsh_crack(bytes: &[u8], group: i32, mesh: &Mesh, tied: bool) -> Result<CrackPlacement> {
    let points = crate::mesh::gmsh::read_physical_line(bytes, group)
        .map_err(|e| Error::invalid("gmsh.crack_line", group, e.to_string()))?;
    let y = points[0][1];
    let tol = mesh.tolerance();
    if let Some(p) = points.iter().find(|p| (p[1] - y).abs() > tol) {
        return Err(Error::invalid(
            "gmsh.crack_line",
            group,
            format!(
                "the crack must be a horizontal straight line (contact acts on u_y): it has \
                 points at y = {y:e} and {:e} m",
                p[1]
            ),
        ));
    }
    let x0 = points.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let x1 = points
        .iter()
        .map(|p| p[0])
        .fold(f64::NEG_INFINITY, f64::max);
    let on_segment = mesh.nodes_on_segment([x0, y], [x1, y]).len();
    if on_segment != points.len() {
        return Err(Error::invalid(
            "gmsh.crack_line",
            group,
            format!(
                "the line has {} nodes but the mesh has {on_segment} on its segment: the crack \
                 must be one unbroken line of element edges",
                points.len()
            ),
        ));
    }
    let top = mesh.bounds().3;
    Ok(CrackPlacement {
        depth_requested_m: top - y,
        depth_used_m: top - y,
        x0_requested_m: x0,
        x0_used_m: x0,
        x1_requested_m: x1,
        x1_used_m: x1,
        tied,
        y_m: y,
    })
}

/// The T3 scene (see [`Scene::build`]).
pub(super) fn build_t3(spec: &SceneSpec) -> Result<Scene> {
    let (mut laminate, mut mesh, crack_placement, region) = match &spec.gmsh {
        None => layered_mesh(spec)?,
        Some(g) => gmsh_mesh(spec, g)?,
    };
    if let Some(attenuation) = &spec.attenuation {
        crate::attenuation::attenuate(&mut laminate.materials, attenuation)?;
    }
    let crack = match &crack_placement {
        Some(p) if !p.tied => Some(p.insert(&mut mesh)?),
        _ => None,
    };
    let conditions = edge_conditions(spec)?;
    let fixed = held_and_pinned_dofs(spec, &mesh, &conditions);
    let on = OnT3(&mesh);
    let transmitter = if spec.sources.is_empty() {
        transmitter_weights(&on, &spec.transmitter, region)?
    } else {
        source_weights(&on, &spec.sources)?
    };
    let receivers = build_receivers(&on, &spec.receivers, region.y0 + region.height)?;
    let absorbing = absorbing_edges(spec, &conditions, &mesh, region)?;
    let mut model = Model::build(mesh, laminate.materials.clone(), &absorbing, fixed, crack)?;
    // The stability estimate below is the untied model's: tying restricts it to the
    // subspace u_l = u_r, which by the Rayleigh-quotient principle can only lower
    // omega_max (as for the crack's tied companion), so the step stays stable.
    if is_periodic(&conditions) {
        model.tie_periodic()?;
    }
    let stability = match crack_placement.as_ref().filter(|p| p.tied) {
        Some(p) => split_stability(&model, p, &absorbing)?,
        None => solve::stability::estimate(&model),
    };
    Ok(Scene {
        spec: spec.clone(),
        laminate,
        body: Body::T3(model),
        transmitter,
        receivers,
        crack_placement,
        stability,
    })
}

/// Linear triangles: loads by length shares ([`segment_shares`]), face receivers averaged
/// with the same shares (the nearest node for a point face), point receivers by barycentric
/// interpolation.
struct OnT3<'a>(&'a Mesh);

impl Attach for OnT3<'_> {
    fn mesh(&self) -> &Mesh {
        self.0
    }

    fn edge_load(
        &self,
        side: Side,
        p: [f64; 2],
        q: [f64; 2],
        field: &str,
    ) -> Result<Vec<(usize, f64)>> {
        let nodes = self.0.nodes_on_segment(p, q);
        if nodes.len() < 2 {
            return Err(Error::invalid(
                field,
                format!("{p:?}..{q:?} m on the {} edge", side.name()),
                "covers fewer than two mesh nodes: widen the range",
            ));
        }
        Ok(segment_shares(self.0, &nodes))
    }

    fn face_receiver(
        &self,
        name: &str,
        _: Side,
        (p, q): ([f64; 2], [f64; 2]),
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        segment_receiver(self.0, name, p, q, component, quantity)
    }

    fn point_receiver(
        &self,
        name: &str,
        p: [f64; 2],
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        point_receiver(self.0, name, p, component, quantity)
    }
}
