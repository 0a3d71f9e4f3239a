//! Where the drive enters and the response is read: the transmitter segment, edge and point
//! sources as consistent loads, and receivers on edges or anywhere in the body.

use super::build::Region;
use super::spec::{ReceiverSpec, SceneSpec, SourceSpec, TransmitterSpec};
use crate::error::{require_within, Error, Result};
use crate::mesh::{Mesh, Side};
use crate::solve::{Quantity, Receiver};

/// The centre of the transmitter's segment, or of the first source (relative to the lower
/// left corner of the region): where the viscous-spring distance R is measured from.
pub(super) fn source_centre(spec: &SceneSpec, mesh: &Mesh, region: Region) -> [f64; 2] {
    let t = &spec.transmitter;
    let Some(first) = spec.sources.first() else {
        return [
            region.width,
            region.height - 0.5 * (t.depth_top_m + t.depth_bottom_m),
        ];
    };
    let (x0, y0) = (region.x0, region.y0);
    let p = match first {
        SourceSpec::Point { x_m, y_m, .. } => [*x_m, *y_m],
        // no single point: a distance from it is refused where it is needed
        SourceSpec::Line { .. } => [f64::NAN; 2],
        SourceSpec::Traction {
            edge, x_m, depth_m, ..
        }
        | SourceSpec::Normal {
            edge, x_m, depth_m, ..
        }
        | SourceSpec::Shear {
            edge, x_m, depth_m, ..
        } => match edge_range(mesh, *edge, *x_m, *depth_m, "sources[0]") {
            Ok((p, q)) => [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])],
            // the source's own check reports the error
            Err(_) => [x0, y0],
        },
    };
    [p[0] - x0, p[1] - y0]
}

/// Nodal weights of the transmitter per unit traction: the consistent load of a uniform
/// traction in direction `angle_deg` on its segment of the right edge.
pub(super) fn transmitter_weights(
    on: &dyn Attach,
    t: &TransmitterSpec,
    region: Region,
) -> Result<Vec<(usize, f64)>> {
    let height = region.height;
    if !(t.depth_top_m >= 0.0 && t.depth_bottom_m > t.depth_top_m && t.depth_bottom_m <= height) {
        return Err(Error::invalid(
            "transmitter",
            format!("depth {}..{} m", t.depth_top_m, t.depth_bottom_m),
            format!("needs 0 <= depth_top < depth_bottom <= {height:.4e} m"),
        ));
    }
    let (right, top) = (region.x0 + region.width, region.y0 + height);
    let load = on.edge_load(
        Side::Right,
        [right, top - t.depth_top_m],
        [right, top - t.depth_bottom_m],
        "transmitter",
    )?;
    let (s, c) = t.angle_deg.to_radians().sin_cos();
    Ok(directed(&load, [c, s], 1.0))
}

/// DOF weights of a traction `scale` * `direction` from per-node weights of a unit one.
fn directed(load: &[(usize, f64)], direction: [f64; 2], scale: f64) -> Vec<(usize, f64)> {
    load.iter()
        .flat_map(|&(n, w)| {
            [
                (2 * n, scale * direction[0] * w),
                (2 * n + 1, scale * direction[1] * w),
            ]
        })
        .collect()
}

/// Where a scene's loads and records attach to its discretisation: the consistent nodal loads
/// of tractions and the weights of receivers. Nodes are numbered as in [`Attach::mesh`].
pub(super) trait Attach {
    /// The T3 mesh, or the triangulated node grid of spectral elements: bounds, nodes, sides.
    fn mesh(&self) -> &Mesh;
    /// Per-node weights of a unit uniform traction on the segment p..q of `side`: the
    /// integral of each node's shape function along it (m). `field` names the segment.
    fn edge_load(
        &self,
        side: Side,
        p: [f64; 2],
        q: [f64; 2],
        field: &str,
    ) -> Result<Vec<(usize, f64)>>;
    /// A receiver averaging (component, quantity) `recorded` over the face `ends` = (p, q) on
    /// `side`, or at the point p when q == p.
    fn face_receiver(
        &self,
        name: &str,
        side: Side,
        ends: ([f64; 2], [f64; 2]),
        recorded: (usize, Quantity),
    ) -> Result<Receiver>;
    /// A receiver of (component, quantity) `recorded` at the point p in the body,
    /// interpolated.
    fn point_receiver(
        &self,
        name: &str,
        p: [f64; 2],
        recorded: (usize, Quantity),
    ) -> Result<Receiver>;
}

/// The end points of an edge source's range on the mesh: `x_m` along the top or bottom
/// edge, `depth_m` below the top surface along the left or right edge, the whole edge
/// without either.
fn edge_range(
    mesh: &Mesh,
    edge: Side,
    x_m: Option<[f64; 2]>,
    depth_m: Option<[f64; 2]>,
    field: &str,
) -> Result<([f64; 2], [f64; 2])> {
    let (x0, x1, y0, y1) = mesh.bounds();
    let horizontal = matches!(edge, Side::Top | Side::Bottom);
    let wrong = match (horizontal, x_m, depth_m) {
        (true, _, Some(d)) => Some(("depth_m", d)),
        (false, Some(x), _) => Some(("x_m", x)),
        _ => None,
    };
    if let Some((name, v)) = wrong {
        return Err(Error::invalid(
            format!("{field}.{name}"),
            format!("{v:?} on the {} edge", edge.name()),
            "a range along the top or bottom edge is x_m, along the left or right edge depth_m \
             (below the top surface)",
        ));
    }
    let range = x_m.or(depth_m);
    if let Some([a, b]) = range {
        let (lo, hi) = if horizontal { (x0, x1) } else { (0.0, y1 - y0) };
        if !(a.is_finite() && b.is_finite() && a >= lo && b > a && b <= hi) {
            return Err(Error::invalid(
                format!("{field}.{}", if horizontal { "x_m" } else { "depth_m" }),
                format!("[{a}, {b}]"),
                format!("needs {lo:e} <= from < to <= {hi:e} m"),
            ));
        }
    }
    Ok(match edge {
        Side::Top | Side::Bottom => {
            let y = if edge == Side::Top { y1 } else { y0 };
            let [a, b] = range.unwrap_or([x0, x1]);
            ([a, y], [b, y])
        }
        Side::Left | Side::Right => {
            let x = if edge == Side::Right { x1 } else { x0 };
            let [a, b] = range.unwrap_or([0.0, y1 - y0]);
            ([x, y1 - a], [x, y1 - b])
        }
    })
}

/// Outward unit normal of a side.
fn outward_normal(side: Side) -> [f64; 2] {
    match side {
        Side::Bottom => [0.0, -1.0],
        Side::Top => [0.0, 1.0],
        Side::Left => [-1.0, 0.0],
        Side::Right => [1.0, 0.0],
    }
}

/// Nodal weights of all `sources` per unit drive (Pa): the consistent nodal loads of their
/// tractions ([`Attach::edge_load`] times the traction direction) and their point forces
/// (on the node nearest to the point).
pub(super) fn source_weights(on: &dyn Attach, sources: &[SourceSpec]) -> Result<Vec<(usize, f64)>> {
    let mesh = on.mesh();
    let mut weights = Vec::new();
    for (i, source) in sources.iter().enumerate() {
        let field = format!("sources[{i}]");
        let (edge, x_m, depth_m, direction, scale) = match *source {
            SourceSpec::Point {
                x_m,
                y_m,
                angle_deg,
                scale,
            } => {
                check_inside(mesh, &field, [x_m, y_m])?;
                let node = mesh.nearest_node([x_m, y_m]);
                let (s, c) = angle_deg.to_radians().sin_cos();
                check_scale(&field, scale)?;
                weights.extend([(2 * node, scale * c), (2 * node + 1, scale * s)]);
                continue;
            }
            SourceSpec::Line { line, .. } => {
                return Err(Error::invalid(
                    format!("{field}.line"),
                    line,
                    "a line source needs a Gmsh mesh of quadrilaterals on spectral elements \
                     (gmsh.order)",
                ))
            }
            SourceSpec::Traction {
                edge,
                x_m,
                depth_m,
                angle_deg,
                scale,
            } => {
                let (s, c) = angle_deg.to_radians().sin_cos();
                (edge, x_m, depth_m, [c, s], scale)
            }
            SourceSpec::Normal {
                edge,
                x_m,
                depth_m,
                scale,
            } => (edge, x_m, depth_m, outward_normal(edge), scale),
            SourceSpec::Shear {
                edge,
                x_m,
                depth_m,
                scale,
            } => {
                let n = outward_normal(edge);
                (edge, x_m, depth_m, [n[1].abs(), n[0].abs()], scale)
            }
        };
        check_scale(&field, scale)?;
        let (p, q) = edge_range(mesh, edge, x_m, depth_m, &field)?;
        let load = on.edge_load(edge, p, q, &field)?;
        weights.extend(directed(&load, direction, scale));
    }
    Ok(weights)
}

/// The error where the viscous springs' R would be measured from the first source and that
/// source is a line, which has no single point; `absorbing` names what absorbs ("sides",
/// "lines").
pub(super) fn no_source_centre(absorbing: &str) -> Error {
    Error::invalid(
        "absorber.source_distance_m",
        "none",
        format!(
            "the first source is a line, which has no single point to measure R from: give \
             the distance R from the wave source to the absorbing {absorbing}"
        ),
    )
}

pub(super) fn check_scale(field: &str, scale: f64) -> Result<()> {
    if !scale.is_finite() || scale == 0.0 {
        return Err(Error::invalid(
            format!("{field}.scale"),
            scale,
            "must be finite and nonzero",
        ));
    }
    Ok(())
}

pub(super) fn check_inside(mesh: &Mesh, field: &str, p: [f64; 2]) -> Result<()> {
    let (x0, x1, y0, y1) = mesh.bounds();
    let tol = mesh.tolerance();
    if !(p[0] >= x0 - tol && p[0] <= x1 + tol && p[1] >= y0 - tol && p[1] <= y1 + tol) {
        return Err(Error::invalid(
            field,
            format!("x_m = {}, y_m = {}", p[0], p[1]),
            format!("is outside the region x [{x0:e}, {x1:e}], y [{y0:e}, {y1:e}] m"),
        ));
    }
    Ok(())
}

/// The receivers: the top-surface row of `x_m`, then those of `at`.
pub(super) fn build_receivers(
    on: &dyn Attach,
    r: &ReceiverSpec,
    height: f64,
) -> Result<Vec<Receiver>> {
    let mesh = on.mesh();
    if r.component > 1 {
        return Err(Error::invalid(
            "receivers.component",
            r.component,
            "must be 0 (u_x) or 1 (u_y)",
        ));
    }
    if r.x_m.is_empty() && r.at.is_empty() {
        return Err(Error::invalid(
            "receivers.x_m",
            "[]",
            "needs at least one receiver position (in x_m or at)",
        ));
    }
    // The transducer face spans at most the specimen: a wider one is no longer a receiver at
    // a position (and a negative one has no face).
    let (x0, x1, _, _) = mesh.bounds();
    require_within(
        "receivers.aperture_m",
        r.aperture_m,
        0.0,
        x1 - x0,
        "m",
        "0 records at a point; at most the specimen's width",
    )?;
    let half = 0.5 * r.aperture_m;
    let recorded = (r.component, r.quantity);
    let face = |name: &str, side: Side, p: [f64; 2], along: [f64; 2]| {
        let ends = (
            [p[0] - half * along[0], p[1] - half * along[1]],
            [p[0] + half * along[0], p[1] + half * along[1]],
        );
        on.face_receiver(name, side, ends, recorded)
    };
    let mut receivers = r
        .x_m
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            face(
                &format!("receiver {}", i + 1),
                Side::Top,
                [x, height],
                [1.0, 0.0],
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let (x0, x1, y0, y1) = mesh.bounds();
    for (i, at) in r.at.iter().enumerate() {
        let name = format!("receiver {}", receivers.len() + 1);
        let field = format!("receivers.at[{i}]");
        let receiver = match (at.edge, at.x_m, at.y_m, at.depth_m) {
            (None, Some(x), Some(y), None) => {
                check_inside(mesh, &field, [x, y])?;
                on.point_receiver(&name, [x, y], recorded)?
            }
            (Some(edge), x_m, None, depth_m) => {
                let horizontal = matches!(edge, Side::Top | Side::Bottom);
                let (p, along) = match (horizontal, x_m, depth_m) {
                    (true, Some(x), None) => {
                        ([x, if edge == Side::Top { y1 } else { y0 }], [1.0, 0.0])
                    }
                    (false, None, Some(d)) => (
                        [if edge == Side::Right { x1 } else { x0 }, y1 - d],
                        [0.0, 1.0],
                    ),
                    _ => {
                        return Err(Error::invalid(
                            field,
                            at.describe(),
                            format!(
                                "a receiver on the {} edge needs {} alone",
                                edge.name(),
                                if horizontal { "x_m" } else { "depth_m" }
                            ),
                        ))
                    }
                };
                face(&name, edge, p, along)?
            }
            _ => {
                return Err(Error::invalid(
                    field,
                    at.describe(),
                    "give #{x_m, y_m} for a point in the body, #{edge, x_m} on the top or \
                     bottom edge, or #{edge, depth_m} on the left or right edge",
                ))
            }
        };
        receivers.push(receiver);
    }
    Ok(receivers)
}
