//! Sources and receivers on a triangle mesh: a traction on a boundary segment as the consistent
//! load of its edges, a force on one node, and receivers averaged over a segment or
//! interpolated at a point.

use super::{Quantity, Receiver, Source};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::signal::Signal;

/// Nodal weights of a segment: each edge between consecutive `nodes` gives half its length
/// to each end node (the consistent load of a uniform traction on linear edges).
pub fn segment_shares(mesh: &Mesh, nodes: &[usize]) -> Vec<(usize, f64)> {
    let mut w: Vec<(usize, f64)> = nodes.iter().map(|&n| (n, 0.0)).collect();
    for k in 0..nodes.len().saturating_sub(1) {
        let (a, b) = (mesh.nodes[nodes[k]], mesh.nodes[nodes[k + 1]]);
        let half = 0.5 * (b[0] - a[0]).hypot(b[1] - a[1]);
        w[k].1 += half;
        w[k + 1].1 += half;
    }
    w
}

/// A traction source on the boundary segment p..q in direction `angle_deg` (counter-clockwise
/// from +x): force on each node = signal(t) * (cos, sin) * the node's length share.
pub fn traction_source(
    mesh: &Mesh,
    p: [f64; 2],
    q: [f64; 2],
    angle_deg: f64,
    signal: Signal,
) -> Result<Source> {
    let nodes = mesh.nodes_on_segment(p, q);
    if nodes.len() < 2 {
        return Err(Error::invalid(
            "source.segment",
            format!("{p:?}..{q:?}"),
            "covers fewer than two mesh nodes",
        ));
    }
    let (s, c) = angle_deg.to_radians().sin_cos();
    let weights = segment_shares(mesh, &nodes)
        .into_iter()
        .flat_map(|(n, l)| [(2 * n, c * l), (2 * n + 1, s * l)])
        .collect();
    Ok(Source { weights, signal })
}

/// A point-force source on one node's DOF (tests and impulse responses).
pub fn point_source(node: usize, component: usize, signal: Signal) -> Source {
    Source {
        weights: vec![(2 * node + component, 1.0)],
        signal,
    }
}

/// A receiver of component `component` (0 = x, 1 = y) averaged over the segment p..q
/// (a transducer face), or at the nearest node when p == q.
pub fn segment_receiver(
    mesh: &Mesh,
    name: &str,
    p: [f64; 2],
    q: [f64; 2],
    component: usize,
    quantity: Quantity,
) -> Result<Receiver> {
    let (x0, x1, y0, y1) = mesh.bounds();
    let tol = mesh.tolerance();
    for pt in [p, q] {
        if !(pt[0] >= x0 - tol && pt[0] <= x1 + tol && pt[1] >= y0 - tol && pt[1] <= y1 + tol) {
            return Err(Error::invalid(
                format!("receiver '{name}'"),
                format!("({}, {}) m", pt[0], pt[1]),
                format!("is outside the domain x [{x0}, {x1}], y [{y0}, {y1}]"),
            ));
        }
    }
    let nodes = if p == q {
        vec![mesh.nearest_node(p)]
    } else {
        mesh.nodes_on_segment(p, q)
    };
    let shares = if nodes.len() == 1 {
        vec![(nodes[0], 1.0)]
    } else {
        segment_shares(mesh, &nodes)
    };
    let total: f64 = shares.iter().map(|s| s.1).sum();
    if nodes.is_empty() || total <= 0.0 {
        return Err(Error::invalid(
            format!("receiver '{name}'"),
            format!("{p:?}..{q:?}"),
            "covers no mesh node",
        ));
    }
    Ok(Receiver {
        name: name.into(),
        weights: shares
            .into_iter()
            .map(|(n, w)| (2 * n + component, w / total))
            .collect(),
        quantity,
    })
}

/// A receiver of component `component` (0 = x, 1 = y) at the point `p` anywhere in the
/// mesh: the displacement interpolated with the linear shape functions of the T3 element
/// that holds `p`, u(p) = sum_i lambda_i u_i with the barycentric coordinates lambda_i
/// ([`Mesh::locate`]). A point on a node records that node alone; on an element edge, the
/// edge's two nodes.
pub fn point_receiver(
    mesh: &Mesh,
    name: &str,
    p: [f64; 2],
    component: usize,
    quantity: Quantity,
) -> Result<Receiver> {
    let (element, lambda) = mesh.locate(p).ok_or_else(|| {
        Error::invalid(
            format!("receiver '{name}'"),
            format!("({}, {}) m", p[0], p[1]),
            "lies in no element of the mesh",
        )
    })?;
    let t = mesh.triangles[element];
    Ok(Receiver {
        name: name.into(),
        weights: t
            .iter()
            .zip(lambda)
            .filter(|&(_, l)| l != 0.0)
            .map(|(&n, l)| (2 * n + component, l))
            .collect(),
        quantity,
    })
}
