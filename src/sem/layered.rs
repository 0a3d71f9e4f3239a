//! The layered rectangle of a laminate as spectral elements, and the consistent loads of
//! tractions on its sides.

use super::gll::Gll;
use super::SemModel;
use crate::error::{require_positive, require_within, Error, Result};
use crate::laminate::Laminate;
use crate::material::Material;
use crate::mesh::Side;
use serde::{Deserialize, Serialize};

/// How a laminate is cut into spectral elements: one order along x for the grid, element rows
/// aligned with the layers (a thick layer split into rows of at most `element_size_y_m`), and
/// per row an order across chosen by [`SemModel::layered`]: at least `min_order_y` (the
/// accuracy floor: a thin epoxy layer at order 1 is one linear interval, and the presets'
/// 3.4% error at normal incidence was almost all that), and above it the highest order up to
/// `max_order_y` that does not shorten the time step (set by the order along x, or by
/// `rule_order_x`); then `extra_order_y` more on every row
/// (the error estimate's companion that refines across the layers). Horizontal element edges
/// carry only x-direction points: still conforming.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SemSpec {
    /// Polynomial order along x.
    pub order_x: usize,
    /// Lowest polynomial order across an element row.
    pub min_order_y: usize,
    /// Highest polynomial order across an element row.
    pub max_order_y: usize,
    /// Orders added across every row after the rule chose them: 0 for a scene; 1 for the
    /// error estimate's companion across the layers, which has each row's order one higher
    /// than the scene it estimates (the rule alone would keep the plies at the step's
    /// ceiling).
    #[serde(skip_serializing_if = "is_zero")]
    pub extra_order_y: usize,
    /// The order along x whose smallest gap the rule across judges each row against (`None`:
    /// `order_x`). The error estimate's companions along x set the scene's order, so they
    /// keep every row's order across and differ from the scene along x alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rule_order_x: Option<usize>,
    /// Element width along x (m); the width is divided into equal elements no wider (outside
    /// `fine_x`).
    pub element_size_x_m: f64,
    /// A band of narrower columns along x (none: every column at most `element_size_x_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fine_x: Option<FineColumns>,
    /// Largest element height across a layer (m).
    pub element_size_y_m: f64,
}

impl Default for SemSpec {
    /// Order 4 on 0.5 mm x 0.25 mm elements: about 5 points per shear wavelength of epoxy at
    /// 2 MHz along x (the T3 quick scene resolves it with about 17 nodes).
    fn default() -> Self {
        SemSpec {
            order_x: 4,
            min_order_y: 1,
            max_order_y: 4,
            extra_order_y: 0,
            rule_order_x: None,
            element_size_x_m: 0.5e-3,
            element_size_y_m: 0.25e-3,
            fine_x: None,
        }
    }
}

/// A band of narrower element columns along x: from `from_m` to `to_m` (both column lines)
/// columns of at most `element_size_m`, the rest of the width at the scene's element size.
/// It puts more GLL node pairs on a crack without refining the whole width (a reference for
/// the contact's error along x). It refines along x alone: the rule across judges the rows
/// against the columns outside it, so they keep their orders; the narrowest column sets the
/// time step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FineColumns {
    /// Left edge of the band (m from the left side).
    pub from_m: f64,
    /// Right edge of the band (m from the left side).
    pub to_m: f64,
    /// Largest element width inside the band (m).
    pub element_size_m: f64,
}

impl FineColumns {
    /// Refuses a band that is empty or leaves [0, `width_m`], or a size that is not a
    /// positive length; errors name the field of `discretisation.fine_x`.
    pub fn check(&self, width_m: f64) -> Result<()> {
        require_positive("discretisation.fine_x.element_size_m", self.element_size_m)?;
        require_within(
            "discretisation.fine_x.from_m",
            self.from_m,
            0.0,
            width_m,
            "m",
            "within the width",
        )?;
        require_within(
            "discretisation.fine_x.to_m",
            self.to_m,
            0.0,
            width_m,
            "m",
            "within the width",
        )?;
        if !(self.to_m > self.from_m) {
            return Err(Error::invalid(
                "discretisation.fine_x.to_m",
                self.to_m,
                format!("must be above from_m = {} m", self.from_m),
            ));
        }
        Ok(())
    }

    /// The parts of [0, `width_m`] and each one's largest element width: left of the band
    /// at `element_size_m`, the band, right of it (empty parts left out).
    fn parts(&self, width_m: f64, element_size_m: f64) -> Vec<(f64, f64, f64)> {
        [
            (0.0, self.from_m, element_size_m),
            (self.from_m, self.to_m, self.element_size_m),
            (self.to_m, width_m, element_size_m),
        ]
        .into_iter()
        .filter(|(a, b, _)| b > a)
        .collect()
    }
}

/// The column lines of [0, `width_m`]: equal columns of at most `element_size_m`, those of
/// the band `fine` (checked) of at most its size.
pub(crate) fn column_lines(
    width_m: f64,
    element_size_m: f64,
    fine: Option<&FineColumns>,
) -> Vec<f64> {
    let Some(band) = fine else {
        return crate::mesh::subdivide(&[0.0, width_m], element_size_m);
    };
    let mut lines = vec![0.0];
    for (a, b, h) in band.parts(width_m, element_size_m) {
        lines.extend_from_slice(&crate::mesh::subdivide(&[a, b], h)[1..]);
    }
    lines
}

/// How many columns [`column_lines`] cuts, counted without building them (the memory check
/// runs before anything is allocated).
pub(crate) fn column_count(width_m: f64, element_size_m: f64, fine: Option<&FineColumns>) -> f64 {
    let count = crate::mesh::piece_count;
    match fine {
        None => count(0.0, width_m, element_size_m),
        Some(band) => band
            .parts(width_m, element_size_m)
            .into_iter()
            .map(|(a, b, h)| count(a, b, h))
            .sum(),
    }
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Relative slack of the gap comparison: a row as tall as the elements are wide takes the order
/// along x, whatever the last bits of its height after the laminate's sums.
const GAP_TOLERANCE: f64 = 1e-9;

/// Smallest gap between the GLL points of order `p` on an element of size `h`.
fn smallest_gap(h: f64, p: usize) -> f64 {
    let g = Gll::new(p);
    0.5 * h * (g.points[1] - g.points[0])
}

/// Fastest plane wave of `m` along x and along y (m/s): P along the axis or S.
fn axis_speeds(m: &Material) -> [f64; 2] {
    let w = m.wave_speeds();
    [w.p_x_m_s.max(w.s_m_s), w.p_y_m_s.max(w.s_m_s)]
}

/// The order across a row of height `h` and fastest speed across `speed_y`: the highest order
/// within `spec`'s bounds whose smallest gap takes a wave no less time to cross than the
/// smallest gap along x takes the fastest wave along x (`x_crossing_s`), so that the row does
/// not set the step; at least `min_order_y`, whatever that costs. Judged per material: epoxy
/// is about 2.6x slower than the plies along x, so its gaps may be that much smaller.
fn order_across(h: f64, speed_y: f64, x_crossing_s: f64, spec: &SemSpec) -> usize {
    let floor = spec.min_order_y.max(1);
    (floor..=spec.max_order_y.max(floor))
        .rev()
        .find(|&p| smallest_gap(h, p) / speed_y >= x_crossing_s * (1.0 - GAP_TOLERANCE))
        .unwrap_or(floor)
}

impl SemModel {
    /// The laminate's layers (bottom first) over `width_m` as spectral elements cut as `spec`
    /// says, with no constraints or dashpots yet.
    pub fn layered(laminate: &Laminate, width_m: f64, spec: &SemSpec) -> Result<SemModel> {
        for (name, size) in [
            ("element_size_x_m", spec.element_size_x_m),
            ("element_size_y_m", spec.element_size_y_m),
        ] {
            if !(size.is_finite() && size > 0.0) {
                return Err(Error::invalid(name, size, "must be finite and > 0"));
            }
        }
        if !(width_m.is_finite() && width_m > 0.0) {
            return Err(Error::invalid("width_m", width_m, "must be finite and > 0"));
        }
        let mut interfaces = vec![0.0];
        for layer in &laminate.layers {
            interfaces.push(interfaces[interfaces.len() - 1] + layer.thickness_m);
        }
        let rows_m = crate::mesh::subdivide(&interfaces, spec.element_size_y_m);
        let row_material: Vec<usize> = rows_m
            .windows(2)
            .map(|w| {
                let middle = 0.5 * (w[0] + w[1]);
                let layer = interfaces.partition_point(|&y| y <= middle) - 1;
                laminate.layers[layer].material
            })
            .collect();
        if let Some(band) = &spec.fine_x {
            band.check(width_m)?;
        }
        let columns_m = column_lines(width_m, spec.element_size_x_m, spec.fine_x.as_ref());
        // the rows are judged against the columns without the band: it refines along x alone
        let columns = column_count(width_m, spec.element_size_x_m, None);
        let speeds: Vec<[f64; 2]> = laminate.materials.iter().map(axis_speeds).collect();
        let fastest_x = row_material
            .iter()
            .map(|&m| speeds[m][0])
            .fold(0.0, f64::max);
        let rule_order_x = spec.rule_order_x.unwrap_or(spec.order_x).max(1);
        let x_crossing_s = smallest_gap(width_m / columns, rule_order_x) / fastest_x;
        let order_y: Vec<usize> = rows_m
            .windows(2)
            .zip(&row_material)
            .map(|(w, &m)| {
                order_across(w[1] - w[0], speeds[m][1], x_crossing_s, spec) + spec.extra_order_y
            })
            .collect();
        SemModel::new(
            columns_m,
            rows_m,
            spec.order_x,
            &order_y,
            laminate.materials.clone(),
            row_material,
        )
    }

    /// The consistent load of a unit uniform traction on the part [from_m, to_m] of `side`
    /// (x along the bottom and top, y along the left and right): per node, the integral of its
    /// Lagrange polynomial over the part, f_k = int l_k(s) ds. Each element's share is
    /// integrated by GLL quadrature of one order more than the element's on the overlap, exact
    /// for the polynomial l_k; a part covering whole elements gets the GLL edge weights. On a
    /// side a through-crack ends on, each face's node takes its own row's share.
    pub fn side_load(&self, side: Side, from_m: f64, to_m: f64) -> Vec<(usize, f64)> {
        let mut load = std::collections::BTreeMap::<usize, f64>::new();
        let (rows, columns) = (self.gll_y.len(), self.columns_m.len() - 1);
        let (lines, rules): (&[f64], Vec<&Gll>) = match side {
            Side::Bottom | Side::Top => (&self.columns_m, vec![&self.gll_x; columns]),
            Side::Left | Side::Right => (&self.rows_m, self.gll_y.iter().collect()),
        };
        let top = self.gll_y[rows - 1].order();
        let node = |e: usize, a: usize| match side {
            Side::Bottom => self.element_node(0, e, a, 0),
            Side::Top => self.element_node(rows - 1, e, a, top),
            Side::Left => self.element_node(e, 0, 0, a),
            Side::Right => self.element_node(e, columns - 1, self.gll_x.order(), a),
        };
        for (e, rule) in rules.iter().enumerate() {
            let (x0, x1) = (lines[e], lines[e + 1]);
            let (a, b) = (from_m.max(x0), to_m.min(x1));
            if b <= a {
                continue;
            }
            let fine = Gll::new(rule.order() + 1);
            for (&xi, &w) in fine.points.iter().zip(&fine.weights) {
                let s = 0.5 * (a + b) + 0.5 * (b - a) * xi;
                let local = (2.0 * s - x0 - x1) / (x1 - x0);
                for (k, l) in rule.lagrange_at(local).iter().enumerate() {
                    *load.entry(node(e, k)).or_default() += 0.5 * (b - a) * w * l;
                }
            }
        }
        load.into_iter().filter(|&(_, f)| f != 0.0).collect()
    }
}
