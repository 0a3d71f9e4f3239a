//! Spectral-element scenes: the layered rectangle as spectral elements ([`crate::sem`]), the
//! transmitter, sources and receivers as consistent GLL loads and interpolations, the edges'
//! conditions (Lysmer-Kuhlemeyer dashpots and viscous springs with GLL edge weights), the
//! crack as split GLL nodes on a horizontal element edge, and the Lanczos step.

use super::build::{build_laminate, check_mesh_size, Region};
use super::crack::{place_crack, CrackPlacement};
use super::edges::{absorbing_edges, edge_conditions, held_and_pinned_dofs, is_periodic};
use super::sources::{check_inside, source_weights, transmitter_weights, Attach};
use super::spec::SceneSpec;
use super::{Body, Scene};
use crate::error::{require_positive, Error, Result};
use crate::fem::AbsorbingEdge;
use crate::mesh::{Crack, Grid, Mesh, Side};
use crate::sem::unstructured::UnstructuredSem;
use crate::sem::{SemModel, SemSpec, MAX_ORDER};
use crate::solve::{Discretisation, Quantity, Receiver, StabilityEstimate};

/// The scene on spectral elements cut as `cut` says (see
/// [`super::DiscretisationSpec::Sem`]).
pub(super) fn build(spec: &SceneSpec, cut: &SemSpec) -> Result<Scene> {
    check_options(spec, cut)?;
    let mut laminate = build_laminate(&spec.laminate, spec.plane)?;
    if let Some(attenuation) = &spec.attenuation {
        crate::attenuation::attenuate(&mut laminate.materials, attenuation)?;
    }
    check_mesh_size(
        spec,
        &laminate,
        (cut.order_x, cut.max_order_y + cut.extra_order_y),
        cut.fine_x.as_ref(),
    )?;
    let mut model = SemModel::layered(&laminate, spec.width_m, cut)?;
    crate::budget::check()?;
    let height = laminate.thickness_m();
    let layer_material: Vec<usize> = laminate.layers.iter().map(|l| l.material).collect();
    let grid = Grid {
        x_m: model.x_nodes_m.clone(),
        y_m: model.y_nodes_m.clone(),
    };
    let mut nodes = Mesh::from_grid(grid, &laminate.interfaces_m(), &layer_material);
    // The crack lies on a horizontal element edge, its tips on node columns.
    let edges = Grid {
        x_m: model.x_nodes_m.clone(),
        y_m: model.rows_m.clone(),
    };
    let crack_placement = spec
        .crack
        .as_ref()
        .map(|c| place_crack(spec, c, &edges, height))
        .transpose()?;
    let conditions = edge_conditions(spec)?;
    if is_periodic(&conditions) {
        return Err(Error::invalid(
            "edges",
            "periodic",
            "periodic edges are implemented for T3 scenes only (discretisation: #{kind: \"t3\"})",
        ));
    }
    let region = Region {
        x0: 0.0,
        y0: 0.0,
        width: spec.width_m,
        height,
    };
    // Split before anything weighs the nodes: the faces' masses and edge weights differ.
    let tied = crack_placement.as_ref().filter(|p| p.tied);
    let bare = tied.map(|_| (model.clone(), nodes.clone()));
    if let Some(p) = crack_placement.as_ref().filter(|p| !p.tied) {
        split(&mut model, &mut nodes, p)?;
    }
    let on = OnSem {
        model: &model,
        nodes: &nodes,
    };
    let transmitter = if spec.sources.is_empty() {
        transmitter_weights(&on, &spec.transmitter, region)?
    } else {
        source_weights(&on, &spec.sources)?
    };
    let receivers = super::build_receivers(&on, &spec.receivers, height)?;
    let absorbing = absorbing_edges(spec, &conditions, &nodes, region)?;
    let held = held_and_pinned_dofs(spec, &nodes, &conditions);
    constrain(&mut model, &held, &absorbing)?;
    let stability = match (tied, bare) {
        (Some(p), Some((mut cracked, mut cracked_nodes))) => {
            split(&mut cracked, &mut cracked_nodes, p)?;
            constrain(&mut cracked, &held, &absorbing)?;
            stability(&cracked)
        }
        _ => stability(&model),
    };
    Ok(Scene {
        spec: spec.clone(),
        laminate,
        body: Body::Sem { model, nodes },
        transmitter,
        receivers,
        crack_placement,
        stability,
    })
}

/// Refuses what spectral-element scenes do not take: a Gmsh mesh, orders outside
/// 1..=[`MAX_ORDER`] (the rule's order along x and the extra orders across included) or a
/// lowest order across above the highest, a width that is not a positive length.
fn check_options(spec: &SceneSpec, cut: &SemSpec) -> Result<()> {
    if let Some(g) = &spec.gmsh {
        return Err(Error::invalid(
            "discretisation.kind",
            "sem",
            format!(
                "describes the layered rectangle; a Gmsh mesh ({}) takes spectral elements \
                 by gmsh.order (on its quadrilaterals): keep discretisation: #{{kind: \"t3\"}}",
                g.path
            ),
        ));
    }
    for (field, order) in [
        ("discretisation.order_x", cut.order_x),
        ("discretisation.min_order_y", cut.min_order_y),
        ("discretisation.max_order_y", cut.max_order_y),
        (
            "discretisation.rule_order_x",
            cut.rule_order_x.unwrap_or(cut.order_x),
        ),
    ] {
        if !(1..=MAX_ORDER).contains(&order) {
            return Err(Error::invalid(
                field,
                order,
                format!("must be 1..={MAX_ORDER}"),
            ));
        }
    }
    if cut.max_order_y + cut.extra_order_y > MAX_ORDER {
        return Err(Error::invalid(
            "discretisation.extra_order_y",
            cut.extra_order_y,
            format!(
                "takes discretisation.max_order_y = {} past {MAX_ORDER}",
                cut.max_order_y
            ),
        ));
    }
    if cut.min_order_y > cut.max_order_y {
        return Err(Error::invalid(
            "discretisation.min_order_y",
            cut.min_order_y,
            format!(
                "must be at most discretisation.max_order_y = {}",
                cut.max_order_y
            ),
        ));
    }
    require_positive("width_m", spec.width_m)?;
    Ok(())
}

/// Holds the `held` DOFs and puts the dashpots (and, with a distance, the viscous springs)
/// of the `absorbing` edges on the model.
fn constrain(model: &mut SemModel, held: &[usize], absorbing: &[AbsorbingEdge]) -> Result<()> {
    let mut fixed = held.to_vec();
    fixed.sort_unstable();
    fixed.dedup();
    model.fixed_dofs = fixed;
    let sides: Vec<Side> = absorbing.iter().map(|a| a.side).collect();
    model.dashpots = model.lysmer_dashpots(&sides);
    for edge in absorbing {
        if let Some(r) = edge.spring_distance_m {
            let springs = model.viscous_springs(edge.side, r)?;
            model.springs.extend(springs);
        }
    }
    Ok(())
}

/// Splits the crack's GLL nodes in the model and the same nodes in its triangulated node grid
/// (both append the lower-face duplicates in x order, so they number them alike; checked).
fn split(model: &mut SemModel, nodes: &mut Mesh, p: &CrackPlacement) -> Result<Crack> {
    let crack = model.split_crack(p.y_m, p.x0_used_m, p.x1_used_m)?;
    let on_grid = p.insert(nodes)?;
    if on_grid.pairs != crack.pairs {
        return Err(Error::Mesh(format!(
            "the crack's split nodes differ between the spectral elements ({} pairs) and their \
             node grid ({} pairs)",
            crack.pairs.len(),
            on_grid.pairs.len()
        )));
    }
    Ok(crack)
}

/// dt_crit from the Lanczos estimate of the largest eigenvalue of M^-1 K over the free DOFs
/// (springs included, dashpots not: they do not enter M^-1 K), and the element bound
/// ([`SemModel::element_eigenvalue_bound`]); the layered model and the unstructured one alike.
pub(super) fn stability<M: GllNodes>(model: &M) -> StabilityEstimate {
    let mut free = vec![true; model.lumped_mass().len()];
    for &d in model.fixed_dofs() {
        free[d] = false;
    }
    let (lambda, iterations) = model.max_eigenvalue(&free);
    StabilityEstimate {
        dt_crit_s: 2.0 / lambda.sqrt(),
        dt_element_bound_s: 2.0 / model.element_eigenvalue_bound().sqrt(),
        iterations,
    }
}

/// Spectral elements: loads by the integrals of the GLL Lagrange polynomials along the edge
/// ([`SemModel::side_load`], exact for a segment ending inside an element), receivers
/// interpolated with the same polynomials ([`SemModel::point_weights`]; a point face records
/// the point itself, not the nearest node) or averaged over a face with the load weights.
/// The layered model and the unstructured one alike ([`GllNodes`]).
pub(super) struct OnSem<'a, M> {
    pub(super) model: &'a M,
    pub(super) nodes: &'a Mesh,
}

/// What loads, receivers and the step estimate need of spectral elements.
pub(super) trait GllNodes: Discretisation {
    /// Per node, the integral of its GLL Lagrange polynomial over the part from..to of
    /// `side` (along x on the top and bottom, y on the left and right); empty when the part
    /// covers no element side.
    fn side_load(&self, side: Side, from: f64, to: f64) -> Vec<(usize, f64)>;
    /// The interpolation weights of the point (x, y), `None` outside every element.
    fn point_weights(&self, x: f64, y: f64) -> Option<Vec<(usize, f64)>>;
    /// omega_max^2 of M^-1 K over the `free` DOFs (Lanczos), with the iterations taken.
    fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize);
    /// An upper bound of omega_max^2 from the elements (Gershgorin).
    fn element_eigenvalue_bound(&self) -> f64;
}

impl GllNodes for SemModel {
    fn side_load(&self, side: Side, from: f64, to: f64) -> Vec<(usize, f64)> {
        SemModel::side_load(self, side, from, to)
    }
    fn point_weights(&self, x: f64, y: f64) -> Option<Vec<(usize, f64)>> {
        SemModel::point_weights(self, x, y)
    }
    fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize) {
        SemModel::max_eigenvalue(self, free)
    }
    fn element_eigenvalue_bound(&self) -> f64 {
        SemModel::element_eigenvalue_bound(self)
    }
}

impl GllNodes for UnstructuredSem {
    fn side_load(&self, side: Side, from: f64, to: f64) -> Vec<(usize, f64)> {
        UnstructuredSem::side_load(self, side, from, to)
    }
    fn point_weights(&self, x: f64, y: f64) -> Option<Vec<(usize, f64)>> {
        UnstructuredSem::point_weights(self, x, y)
    }
    fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize) {
        UnstructuredSem::max_eigenvalue(self, free)
    }
    fn element_eigenvalue_bound(&self) -> f64 {
        UnstructuredSem::element_eigenvalue_bound(self)
    }
}

/// The range of the segment p..q along `side`'s coordinate (x on the top and bottom, y on
/// the left and right), ascending.
fn along(side: Side, p: [f64; 2], q: [f64; 2]) -> (f64, f64) {
    let k = match side {
        Side::Bottom | Side::Top => 0,
        Side::Left | Side::Right => 1,
    };
    (p[k].min(q[k]), p[k].max(q[k]))
}

impl<M: GllNodes> Attach for OnSem<'_, M> {
    fn mesh(&self) -> &Mesh {
        self.nodes
    }

    fn edge_load(
        &self,
        side: Side,
        p: [f64; 2],
        q: [f64; 2],
        field: &str,
    ) -> Result<Vec<(usize, f64)>> {
        let (from, to) = along(side, p, q);
        let load = self.model.side_load(side, from, to);
        if load.is_empty() {
            return Err(Error::invalid(
                field,
                format!("{p:?}..{q:?} m on the {} edge", side.name()),
                "covers no part of the edge: widen the range",
            ));
        }
        Ok(load)
    }

    fn face_receiver(
        &self,
        name: &str,
        side: Side,
        (p, q): ([f64; 2], [f64; 2]),
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        if p == q {
            return self.point_receiver(name, p, (component, quantity));
        }
        let field = format!("receiver '{name}'");
        check_inside(self.nodes, &field, p)?;
        check_inside(self.nodes, &field, q)?;
        let face = self.edge_load(side, p, q, &field)?;
        let width: f64 = face.iter().map(|&(_, w)| w).sum();
        Ok(Receiver {
            name: name.into(),
            weights: face
                .into_iter()
                .map(|(n, w)| (2 * n + component, w / width))
                .collect(),
            quantity,
        })
    }

    fn point_receiver(
        &self,
        name: &str,
        p: [f64; 2],
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        let field = format!("receiver '{name}'");
        check_inside(self.nodes, &field, p)?;
        let tol = self.nodes.tolerance();
        let (x0, x1, y0, y1) = self.nodes.bounds();
        let weights = self
            .model
            .point_weights(p[0].clamp(x0, x1), p[1].clamp(y0, y1))
            .filter(|w| !w.is_empty())
            .ok_or_else(|| {
                Error::invalid(
                    field,
                    format!("({}, {}) m", p[0], p[1]),
                    format!("lies in no element (tolerance {tol:e} m)"),
                )
            })?;
        Ok(Receiver {
            name: name.into(),
            weights: weights
                .into_iter()
                .map(|(n, w)| (2 * n + component, w))
                .collect(),
            quantity,
        })
    }
}
