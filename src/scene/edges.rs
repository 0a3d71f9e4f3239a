//! The edges' conditions: free, fixed, roller, periodic and absorbing (Lysmer-Kuhlemeyer
//! dashpots with viscous springs), and the DOFs they hold.

use super::build::Region;
use super::sources::source_centre;
use super::spec::{Absorber, EdgeCondition, SceneSpec};
use crate::error::{Error, Result};
use crate::fem::AbsorbingEdge;
use crate::mesh::{Mesh, Side};

/// The DOFs held by the edge conditions, and the bottom corners' when `fix_bottom_corners`.
pub(super) fn held_and_pinned_dofs(
    spec: &SceneSpec,
    mesh: &Mesh,
    conditions: &[(Side, EdgeCondition); 4],
) -> Vec<usize> {
    let mut fixed = if spec.fix_bottom_corners {
        bottom_corner_dofs(mesh)
    } else {
        vec![]
    };
    fixed.extend(held_dofs(mesh, conditions));
    fixed
}

/// The condition of every edge, in the order bottom, top, left, right: `edges` where it
/// names one, else absorbing if `absorbing` lists the side, else free. Periodic must be
/// given to the left and right edges together and to no other; a side listed twice in
/// `absorbing` is an error (it would absorb twice).
pub(super) fn edge_conditions(spec: &SceneSpec) -> Result<[(Side, EdgeCondition); 4]> {
    let listed = &spec.absorbing;
    if let Some(twice) =
        (1..listed.len()).find_map(|i| listed[..i].contains(&listed[i]).then_some(listed[i]))
    {
        return Err(Error::invalid(
            "absorbing",
            format!("{twice:?}").to_lowercase(),
            "is listed twice (it would absorb twice)",
        ));
    }
    let e = &spec.edges;
    let conditions = [
        (Side::Bottom, e.bottom),
        (Side::Top, e.top),
        (Side::Left, e.left),
        (Side::Right, e.right),
    ]
    .map(|(side, given)| {
        let absorbing = spec.absorbing.contains(&side);
        let default = if absorbing {
            EdgeCondition::Absorbing
        } else {
            EdgeCondition::Free
        };
        (side, given.unwrap_or(default))
    });
    let periodic = |side: Side| {
        conditions
            .iter()
            .any(|&(s, c)| s == side && c == EdgeCondition::Periodic)
    };
    for side in [Side::Bottom, Side::Top] {
        if periodic(side) {
            return Err(Error::invalid(
                format!("edges.{}", side.name()),
                "periodic",
                "only the left and right edges can be periodic (together)",
            ));
        }
    }
    if periodic(Side::Left) != periodic(Side::Right) {
        let (set, other) = if periodic(Side::Left) {
            ("left", "right")
        } else {
            ("right", "left")
        };
        return Err(Error::invalid(
            format!("edges.{set}"),
            "periodic",
            format!("a periodic edge needs its partner: set edges.{other} periodic too"),
        ));
    }
    Ok(conditions)
}

pub(super) fn is_periodic(conditions: &[(Side, EdgeCondition); 4]) -> bool {
    conditions
        .iter()
        .any(|&(_, c)| c == EdgeCondition::Periodic)
}

/// The DOFs held by fixed edges (both components) and rollers (the normal component).
fn held_dofs(mesh: &Mesh, conditions: &[(Side, EdgeCondition); 4]) -> Vec<usize> {
    let mut held = Vec::new();
    for &(side, condition) in conditions {
        let normal = match side {
            Side::Bottom | Side::Top => 1,
            Side::Left | Side::Right => 0,
        };
        let components: &[usize] = match condition {
            EdgeCondition::Fixed => &[0, 1],
            EdgeCondition::Roller => &[normal],
            _ => continue,
        };
        for n in mesh.side_nodes(side) {
            held.extend(components.iter().map(|c| 2 * n + c));
        }
    }
    held
}

/// The absorbing edges of the scene, with the viscous-spring distance resolved per side:
/// the sides of `absorbing` in its order, less those `edges` gives another condition, then
/// the sides `edges` makes absorbing.
pub(super) fn absorbing_edges(
    spec: &SceneSpec,
    conditions: &[(Side, EdgeCondition); 4],
    mesh: &Mesh,
    region: Region,
) -> Result<Vec<AbsorbingEdge>> {
    let absorbs = |side: Side| {
        conditions
            .iter()
            .any(|&(s, c)| s == side && c == EdgeCondition::Absorbing)
    };
    let mut sides: Vec<Side> = spec
        .absorbing
        .iter()
        .copied()
        .filter(|&s| absorbs(s))
        .collect();
    for &(side, _) in conditions {
        if absorbs(side) && !sides.contains(&side) {
            sides.push(side);
        }
    }
    let source = source_centre(spec, mesh, region);
    sides
        .iter()
        .map(|&side| {
            let spring_distance_m = match spec.absorber {
                Absorber::Dashpot => None,
                Absorber::ViscousSpring {
                    source_distance_m: Some(r),
                } => Some(r),
                Absorber::ViscousSpring {
                    source_distance_m: None,
                } => Some(transmitter_distance(
                    side,
                    source,
                    region.width,
                    region.height,
                )?),
            };
            Ok(AbsorbingEdge {
                side,
                spring_distance_m,
            })
        })
        .collect()
}

/// Distance from the transmitter's centre to the line of `side`; an error when the
/// transmitter lies on that side (the springs' R must then be given).
fn transmitter_distance(side: Side, source: [f64; 2], width: f64, height: f64) -> Result<f64> {
    let d = match side {
        Side::Left => source[0],
        Side::Right => width - source[0],
        Side::Bottom => source[1],
        Side::Top => height - source[1],
    };
    if d.is_nan() {
        return Err(super::sources::no_source_centre("sides"));
    }
    if d < 1e-6 * width.max(height) {
        return Err(Error::invalid(
            "absorber.source_distance_m",
            "none",
            format!(
                "the transmitter lies on the absorbing {} side: give the distance R from the \
                 wave source to the absorbing sides",
                format!("{side:?}").to_lowercase()
            ),
        ));
    }
    Ok(d)
}

fn bottom_corner_dofs(mesh: &Mesh) -> Vec<usize> {
    let bottom = mesh.side_nodes(Side::Bottom);
    [bottom.first(), bottom.last()]
        .into_iter()
        .flatten()
        .flat_map(|&n| [2 * n, 2 * n + 1])
        .collect()
}
