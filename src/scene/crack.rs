//! The crack snapped onto the mesh lines: its geometry, its node pairs, and the step its split
//! model allows.

use super::spec::{CrackSpec, SceneSpec};
use crate::error::{require_positive, Error, Result};
use crate::fem::{AbsorbingEdge, Model};
use crate::mesh::{Grid, Mesh};
use crate::solve::{self, StabilityEstimate};
use serde::Serialize;

/// Where a crack lies on the mesh: the requested geometry and the mesh lines it snapped to
/// (depths below the top surface, x from the left edge).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CrackPlacement {
    /// Requested depth, `crack.depth_m` (m).
    pub depth_requested_m: f64,
    /// Depth of the row line used (m).
    pub depth_used_m: f64,
    /// Requested left tip, x_center_m - length_m / 2 (m).
    pub x0_requested_m: f64,
    /// Left tip used: a column line (m).
    pub x0_used_m: f64,
    /// Requested right tip, x_center_m + length_m / 2 (m).
    pub x1_requested_m: f64,
    /// Right tip used: a column line (m).
    pub x1_used_m: f64,
    /// Faces tied (the uncracked companion): no node is split.
    pub tied: bool,
    /// Height of the crack line above the bottom edge, exactly the mesh's row line (m).
    #[serde(skip)]
    pub(super) y_m: f64,
}

impl CrackPlacement {
    /// Splits the crack's nodes in `mesh` (the mesh it was placed on).
    pub(super) fn insert(&self, mesh: &mut Mesh) -> Result<crate::mesh::Crack> {
        mesh.insert_crack(self.y_m, self.x0_used_m, self.x1_used_m)
    }
}

/// Snaps the crack of `c` onto the lines of `grid` (of the mesh built without it): the line
/// to the nearest interior row line, each tip to the nearest interior column line, each within half
/// the local row height / column width. Errors name the field and the value when no line is
/// that close (the crack would lie on an edge) or when the tips leave no node between them.
pub(super) fn place_crack(
    spec: &SceneSpec,
    c: &CrackSpec,
    grid: &Grid,
    height: f64,
) -> Result<CrackPlacement> {
    let (y, x0, x1) = crack_geometry(spec, c, height)?;
    let row = grid.snap_row(y).ok_or_else(|| {
        Error::invalid(
            "crack.depth_m",
            c.depth_m,
            format!(
                "no interior mesh row line within half an element row of it (the nearest line \
                 is the {} surface; element_size_y_m = {:e} m)",
                if y > 0.5 * height { "top" } else { "bottom" },
                spec.element_size_y_m
            ),
        )
    })?;
    let column = |x: f64, tip: &str| {
        grid.snap_column(x).ok_or_else(|| {
            Error::invalid(
                "crack.x_center_m, crack.length_m",
                format!("{tip} tip x = {x:.6e} m"),
                format!(
                    "no interior mesh column line within half a column of it (the nearest \
                     line is the {} edge; element_size_x_m = {:e} m)",
                    if x < 0.5 * spec.width_m {
                        "left"
                    } else {
                        "right"
                    },
                    spec.element_size_x_m
                ),
            )
        })
    };
    let (i0, i1) = (column(x0, "left")?, column(x1, "right")?);
    if i1 < i0 + 2 {
        return Err(Error::invalid(
            "crack.length_m",
            c.length_m,
            format!(
                "its tips snap to column lines {:.6e} and {:.6e} m, leaving no node between \
                 them; the crack needs at least two columns (element_size_x_m = {:e} m)",
                grid.x_m[i0], grid.x_m[i1], spec.element_size_x_m
            ),
        ));
    }
    let y_m = grid.y_m[row];
    Ok(CrackPlacement {
        depth_requested_m: c.depth_m,
        depth_used_m: height - y_m,
        x0_requested_m: x0,
        x0_used_m: grid.x_m[i0],
        x1_requested_m: x1,
        x1_used_m: grid.x_m[i1],
        tied: c.tied,
        y_m,
    })
}

/// The stability estimate of the cracked (split) version of the tied `model`: the shared
/// step of a cracked scene and its tied companion (see [`Scene::build`]).
pub(super) fn split_stability(
    model: &Model,
    placement: &CrackPlacement,
    absorbing: &[AbsorbingEdge],
) -> Result<StabilityEstimate> {
    let mut mesh = model.mesh.clone();
    let crack = placement.insert(&mut mesh)?;
    // The same edges: their springs enter K (their dashpots do not enter M^-1 K).
    let split = Model::build(
        mesh,
        model.materials.clone(),
        absorbing,
        model.fixed_dofs.clone(),
        Some(crack),
    )?;
    Ok(solve::stability::estimate(&split))
}

/// Crack line and tips (m) from its spec, checked against the domain.
fn crack_geometry(spec: &SceneSpec, c: &CrackSpec, height: f64) -> Result<(f64, f64, f64)> {
    require_positive("crack.length_m", c.length_m)?;
    require_positive("crack.depth_m", c.depth_m)?;
    let middle = spec
        .receivers
        .x_m
        .get(spec.receivers.x_m.len() / 2)
        .copied()
        .unwrap_or(0.5 * spec.width_m);
    let xc = c.x_center_m.unwrap_or(middle);
    let (x0, x1, y) = (
        xc - 0.5 * c.length_m,
        xc + 0.5 * c.length_m,
        height - c.depth_m,
    );
    if !(x0 > 0.0 && x1 < spec.width_m && y > 0.0) {
        return Err(Error::invalid(
            "crack",
            format!("x {x0:.4e}..{x1:.4e} m at depth {:.4e} m", c.depth_m),
            format!(
                "must lie inside the {:.4e} x {height:.4e} m region (width_m x laminate thickness; check crack.x_center_m, crack.length_m, crack.depth_m)",
                spec.width_m
            ),
        ));
    }
    Ok((y, x0, x1))
}
