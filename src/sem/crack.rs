//! The crack as split GLL nodes on a horizontal element edge (report Sec. 4.9): each face with
//! its own row's mass, one crack per model.

use super::{SemModel, Split};
use crate::error::{Error, Result};
use crate::mesh::{Crack, CrackPair, UP};

impl SemModel {
    /// Splits the node line of a horizontal crack at height `y_m` from `x0_m` to `x1_m`
    /// (report Sec. 4.9 with split nodes): `y_m` must be an interior element row line and the
    /// tips node columns (within 1e-9 of the rectangle's diagonal). Every node of the line
    /// strictly between the tips gets a duplicate, appended after the existing nodes in x
    /// order; a tip on the left or right edge is split too (a through-crack), an interior
    /// tip stays shared. The original keeps the element row above (master, upper face), the
    /// duplicate takes the row below (slave, lower face), each with its own side's mass.
    /// A fixed DOF of a split node is fixed on both faces. Split before setting dashpots or
    /// springs (their edge weights depend on the faces); one crack per model.
    pub fn split_crack(&mut self, y_m: f64, x0_m: f64, x1_m: f64) -> Result<Crack> {
        if self.split.is_some() {
            return Err(Error::invalid(
                "crack",
                format!("y {y_m} m"),
                "the model has a crack already (one per model)",
            ));
        }
        if !(self.dashpots.is_empty() && self.springs.is_empty()) {
            return Err(Error::invalid(
                "crack",
                format!("y {y_m} m"),
                "split the crack before setting dashpots or springs (their weights depend on the faces)",
            ));
        }
        let (width, height) = (
            self.columns_m[self.columns_m.len() - 1] - self.columns_m[0],
            self.rows_m[self.rows_m.len() - 1] - self.rows_m[0],
        );
        let tol = 1e-9 * width.hypot(height);
        let n_rows = self.gll_y.len();
        let row = (1..n_rows)
            .find(|&k| (self.rows_m[k] - y_m).abs() <= tol)
            .ok_or_else(|| {
                Error::invalid(
                    "crack.depth_m",
                    format!("y {y_m} m"),
                    format!(
                        "must be an interior element row line (nearest: {} m)",
                        nearest(&self.rows_m[1..n_rows], y_m)
                    ),
                )
            })?;
        if !(x0_m < x1_m) {
            return Err(Error::invalid(
                "crack.x0_m",
                format!("{x0_m}..{x1_m} m"),
                "needs finite tips x0 < x1",
            ));
        }
        let column = |name: &str, x: f64| {
            self.x_nodes_m
                .iter()
                .position(|&c| (c - x).abs() <= tol)
                .ok_or_else(|| {
                    Error::invalid(
                        name,
                        format!("{x} m"),
                        format!(
                            "must be a node column (nearest: {} m)",
                            nearest(&self.x_nodes_m, x)
                        ),
                    )
                })
        };
        let (i0, i1) = (column("crack.x0_m", x0_m)?, column("crack.x1_m", x1_m)?);
        let last_column = self.nx() - 1;
        let first = if i0 == 0 { 0 } else { i0 + 1 };
        let last = if i1 == last_column { i1 } else { i1 - 1 };
        if first > last {
            return Err(Error::invalid(
                "crack.x1_m",
                format!("{x0_m}..{x1_m} m"),
                "no node column lies strictly between the tips",
            ));
        }
        let line = self.first_line[row];
        let first_duplicate = self.grid_nodes();
        let pairs = (first..=last)
            .map(|i| CrackPair {
                master: self.node(i, line),
                slave: first_duplicate + i - first,
                normal: UP,
            })
            .collect();
        let crack = Crack {
            pieces_m: vec![[
                [self.x_nodes_m[i0], self.rows_m[row]],
                [self.x_nodes_m[i1], self.rows_m[row]],
            ]],
            pairs,
        };
        let split = Split {
            row_below: row - 1,
            line,
            first,
            last,
            first_duplicate,
            crack: crack.clone(),
        };
        let held: Vec<usize> = split
            .crack
            .pairs
            .iter()
            .flat_map(|p| [(p.master, p.slave, 0), (p.master, p.slave, 1)])
            .filter(|&(m, _, k)| self.fixed_dofs.contains(&(2 * m + k)))
            .map(|(_, s, k)| 2 * s + k)
            .collect();
        self.fixed_dofs.extend(held);
        self.split = Some(split);
        self.lumped_mass = self.assemble_mass();
        Ok(crack)
    }
}

/// The entry of `values` nearest to `v`.
fn nearest(values: &[f64], v: f64) -> f64 {
    values
        .iter()
        .copied()
        .min_by(|a, b| (a - v).abs().total_cmp(&(b - v).abs()))
        .unwrap_or(f64::NAN)
}
