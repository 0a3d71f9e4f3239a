//! The stiffness operator the explicit solver and the stability estimate apply every step.
//!
//! On a structured layer-conforming mesh every interior node of a node row couples to the
//! same 7 neighbours (down-left, down, left, self, right, up, up-right: the pattern of cells
//! split along their rising diagonal) with the same 2x2 blocks, as long as the columns on
//! both sides have the same width: the elements around it have the row's materials and
//! heights and the column width. So instead of streaming ~7 blocks and column indices per
//! node from the assembled [`BlockCsr`] (~200 bytes per DOF per step), the operator keeps
//! one 7-block stencil per (node row, column-width class) and streams only the vectors.
//!
//! Everything the stencil does not describe is read from the assembled K, row by row, in
//! the same order as [`BlockCsr::row_product`]: the bottom and top node rows, the first and
//! last columns, the columns where the width changes (x breaks; scenes make none, since a
//! crack snaps onto the lines of the mesh built without it), the two node rows along a
//! crack (their pattern differs: the elements below the crack use the duplicated nodes)
//! and the crack's duplicated nodes themselves. The stencil is not
//! trusted blindly: when the operator is built every node it would handle is checked
//! against its row of K (same 7 columns, every entry within 1e-12 of the row's largest
//! entry; the only admissible difference is the coordinate round-off of nominally equal
//! column widths), and a node row that fails is handled from K.
//!
//! Each output entry is computed by exactly one task, in a fixed order, so results are
//! bit-identical for any number of threads. Nothing is allocated per application.

use super::{BlockCsr, Model};
use rayon::prelude::*;

/// Nodes per parallel task (whole node rows are grouped up to about this many nodes).
const NODES_PER_TASK: usize = 4096;
/// Largest admissible |K_ij - stencil_ij| relative to the largest entry of the stencil.
const STENCIL_TOLERANCE: f64 = 1e-12;

/// The 7 blocks of a stencil in K's column order (down-left, down, left, self, right, up,
/// up-right), each split as diag = [b_xx, b_yy] and off = [b_xy, b_yx] so that
/// f = sum diag .* [u_x, u_y] + off .* [u_y, u_x] maps onto 2-wide vector operations.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Stencil {
    diag: [[f64; 2]; 7],
    off: [[f64; 2]; 7],
}

impl Stencil {
    fn from_blocks(b: &[[f64; 4]]) -> Stencil {
        let mut s = Stencil {
            diag: [[0.0; 2]; 7],
            off: [[0.0; 2]; 7],
        };
        for (k, blk) in b.iter().enumerate() {
            s.diag[k] = [blk[0], blk[3]];
            s.off[k] = [blk[1], blk[2]];
        }
        s
    }

    fn max_abs(&self) -> f64 {
        self.diag
            .iter()
            .chain(&self.off)
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// True when the K row `blocks` equals this stencil within `tol`.
    fn matches(&self, blocks: &[[f64; 4]], tol: f64) -> bool {
        blocks.iter().enumerate().all(|(k, b)| {
            (b[0] - self.diag[k][0]).abs() <= tol
                && (b[3] - self.diag[k][1]).abs() <= tol
                && (b[1] - self.off[k][0]).abs() <= tol
                && (b[2] - self.off[k][1]).abs() <= tol
        })
    }
}

/// A run of columns [start, end) of equal width on both sides of every node.
#[derive(Clone, Copy, Debug)]
struct Segment {
    start: usize,
    end: usize,
}

/// The structured part of the operator.
#[derive(Clone, Debug)]
struct GridStencil {
    /// Nodes per row and node rows of the grid (grid nodes are the first nx * ny nodes).
    nx: usize,
    ny: usize,
    /// Column segments handled by stencils (the same for every stencil row).
    segments: Vec<Segment>,
    /// Columns of a stencil row that are read from K (boundary and width-change columns).
    csr_columns: Vec<usize>,
    /// Per node row: index of its first stencil in `stencils` (one per segment), or `None`
    /// for a row read entirely from K.
    row_stencils: Vec<Option<usize>>,
    stencils: Vec<Stencil>,
    /// Use the AVX build of the kernel (detected at run time; tests switch it off).
    avx: bool,
}

/// Applies K: matrix-free stencils on structured meshes, the assembled [`BlockCsr`] otherwise.
#[derive(Clone, Debug)]
pub struct StiffnessOperator<'a> {
    k: &'a BlockCsr,
    grid: Option<GridStencil>,
}

/// What the kernel writes for one node, given f = (K u) at that node.
trait Finish: Sync + Sized {
    /// Writes node `node`'s output from its force `f`.
    fn node(&self, node: usize, f: [f64; 2], out: &mut [f64; 2]);
    /// The same for the `len` nodes from `first`, indexed from 0 (bounds known up front).
    fn sub(&self, first: usize, len: usize) -> Self;
    /// Two consecutive nodes `i`, `i + 1` of a [`Finish::sub`] view, forces in lanes
    /// (x_i, y_i, x_i+1, y_i+1); identical arithmetic to two [`Finish::node`] calls.
    fn pair(&self, i: usize, f: [f64; 4], out: &mut [[f64; 2]; 2]);
}

/// out = K u.
struct Product;

impl Finish for Product {
    #[inline(always)]
    fn node(&self, _node: usize, f: [f64; 2], out: &mut [f64; 2]) {
        *out = f;
    }
    #[inline(always)]
    fn sub(&self, _first: usize, _len: usize) -> Self {
        Product
    }
    #[inline(always)]
    fn pair(&self, _i: usize, f: [f64; 4], out: &mut [[f64; 2]; 2]) {
        *out = [[f[0], f[1]], [f[2], f[3]]];
    }
}

/// out = 2 u - u_prev - a .* (K u).
struct Update<'b> {
    a: &'b [[f64; 2]],
    u_prev: &'b [[f64; 2]],
    u: &'b [[f64; 2]],
}

impl Finish for Update<'_> {
    #[inline(always)]
    fn node(&self, n: usize, f: [f64; 2], out: &mut [f64; 2]) {
        let (a, p, u) = (self.a[n], self.u_prev[n], self.u[n]);
        out[0] = 2.0 * u[0] - p[0] - a[0] * f[0];
        out[1] = 2.0 * u[1] - p[1] - a[1] * f[1];
    }
    #[inline(always)]
    fn sub(&self, first: usize, len: usize) -> Self {
        Update {
            a: &self.a[first..first + len],
            u_prev: &self.u_prev[first..first + len],
            u: &self.u[first..first + len],
        }
    }
    #[inline(always)]
    fn pair(&self, i: usize, f: [f64; 4], out: &mut [[f64; 2]; 2]) {
        let (a, p, u) = (load4(self.a, i), load4(self.u_prev, i), load4(self.u, i));
        let r: [f64; 4] = std::array::from_fn(|l| 2.0 * u[l] - p[l] - a[l] * f[l]);
        *out = [[r[0], r[1]], [r[2], r[3]]];
    }
}

/// Nodes i and i + 1 as lanes (x_i, y_i, x_i+1, y_i+1).
#[inline(always)]
fn load4(s: &[[f64; 2]], i: usize) -> [f64; 4] {
    let (p, q) = (s[i], s[i + 1]);
    [p[0], p[1], q[0], q[1]]
}

impl<'a> StiffnessOperator<'a> {
    /// The operator of `model.stiffness`, with stencils when the mesh is structured.
    pub fn new(model: &'a Model) -> StiffnessOperator<'a> {
        StiffnessOperator {
            k: &model.stiffness,
            grid: GridStencil::build(&model.stiffness, model),
        }
    }

    /// The operator of an assembled matrix alone (no stencils).
    pub fn from_matrix(k: &'a BlockCsr) -> StiffnessOperator<'a> {
        StiffnessOperator { k, grid: None }
    }

    /// True when stencils handle the structured part of the mesh.
    pub fn is_matrix_free(&self) -> bool {
        self.grid.is_some()
    }

    /// Fraction of the node rows of K handled by stencils (0 without a grid).
    pub fn stencil_fraction(&self) -> f64 {
        match &self.grid {
            None => 0.0,
            Some(g) => {
                let per_row: usize = g.segments.iter().map(|s| s.end - s.start).sum();
                let rows = g.row_stencils.iter().filter(|r| r.is_some()).count();
                (per_row * rows) as f64 / self.k.nodes() as f64
            }
        }
    }

    /// Number of DOFs.
    pub fn dofs(&self) -> usize {
        2 * self.k.nodes()
    }

    /// out = K u, parallel over node rows.
    pub fn mul(&self, u: &[f64], out: &mut [f64]) {
        let n = self.dofs();
        assert!(u.len() == n && out.len() == n, "vector length != {n} DOFs");
        match &self.grid {
            None => self.k.mul(u, out),
            Some(g) => g.apply(self.k, pairs(u), pairs_mut(out), &Product),
        }
    }

    /// The explicit step's fused update u_next = 2 u - u_prev - a .* (K u).
    pub fn explicit_update(&self, a: &[f64], u_prev: &[f64], u: &[f64], u_next: &mut [f64]) {
        let n = self.dofs();
        assert!(
            a.len() == n && u_prev.len() == n && u.len() == n && u_next.len() == n,
            "vector length != {n} DOFs"
        );
        let fin = Update {
            a: pairs(a),
            u_prev: pairs(u_prev),
            u: pairs(u),
        };
        match &self.grid {
            None => csr_rows(self.k, 0, pairs(u), pairs_mut(u_next), &fin, true),
            Some(g) => g.apply(self.k, pairs(u), pairs_mut(u_next), &fin),
        }
    }
}

/// True when the CPU supports AVX (checked once; the result is cached by std).
fn has_avx() -> bool {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        std::is_x86_feature_detected!("avx")
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        false
    }
}

fn pairs(v: &[f64]) -> &[[f64; 2]] {
    let (p, rest) = v.as_chunks::<2>();
    debug_assert!(rest.is_empty());
    p
}

fn pairs_mut(v: &mut [f64]) -> &mut [[f64; 2]] {
    let (p, rest) = v.as_chunks_mut::<2>();
    debug_assert!(rest.is_empty());
    p
}

/// Rows `first..first + out.len()` of K applied through `fin`, in parallel when asked.
fn csr_rows<F: Finish>(
    k: &BlockCsr,
    first: usize,
    u: &[[f64; 2]],
    out: &mut [[f64; 2]],
    fin: &F,
    parallel: bool,
) {
    let body = |r0: usize, o: &mut [[f64; 2]]| {
        for (i, pair) in o.iter_mut().enumerate() {
            let r = r0 + i;
            fin.node(r, row_product(k, r, u), pair);
        }
    };
    if parallel {
        out.par_chunks_mut(NODES_PER_TASK)
            .enumerate()
            .for_each(|(c, o)| body(first + c * NODES_PER_TASK, o));
    } else {
        body(first, out);
    }
}

/// [`BlockCsr::row_product`] on node pairs (same arithmetic, same order).
#[inline(always)]
fn row_product(k: &BlockCsr, r: usize, u: &[[f64; 2]]) -> [f64; 2] {
    let (mut fx, mut fy) = (0.0, 0.0);
    let range = k.row_ptr[r]..k.row_ptr[r + 1];
    for (&c, b) in k.cols[range.clone()].iter().zip(&k.blocks[range]) {
        let [ux, uy] = u[c as usize];
        fx += b[0] * ux + b[1] * uy;
        fy += b[2] * ux + b[3] * uy;
    }
    [fx, fy]
}

impl GridStencil {
    /// Stencils for the structured part of `model`, or `None` when the mesh has no grid or
    /// no node row qualifies.
    fn build(k: &BlockCsr, model: &Model) -> Option<GridStencil> {
        let grid = model.mesh.grid.as_ref()?;
        let (nx, ny) = (grid.x_m.len(), grid.y_m.len());
        if nx < 3 || ny < 3 || k.nodes() < nx * ny || model.mesh.nodes.len() != k.nodes() {
            return None;
        }
        // Column segments: interior nodes whose left and right cells have the same width.
        let dx: Vec<f64> = grid.x_m.windows(2).map(|w| w[1] - w[0]).collect();
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs());
        let mut segments = Vec::new();
        let mut i = 1;
        while i < nx - 1 {
            if !same(dx[i - 1], dx[i]) {
                i += 1;
                continue;
            }
            let (start, w) = (i, dx[i]);
            while i < nx - 1 && same(dx[i - 1], w) && same(dx[i], w) {
                i += 1;
            }
            segments.push(Segment { start, end: i });
        }
        if segments.is_empty() {
            return None;
        }
        let mut csr_columns = Vec::new();
        let mut next = 0;
        for s in &segments {
            csr_columns.extend(next..s.start);
            next = s.end;
        }
        csr_columns.extend(next..nx);

        // One stencil per (row, segment), from K's row at the segment's middle node, checked
        // against every node of the segment.
        let per_row: Vec<Option<Vec<Stencil>>> = (0..ny)
            .into_par_iter()
            .map(|j| {
                if j == 0 || j == ny - 1 {
                    return None;
                }
                segments
                    .iter()
                    .map(|s| {
                        let rep = j * nx + (s.start + s.end) / 2;
                        let stencil = Stencil::from_blocks(grid_row(k, rep, nx)?);
                        let tol = STENCIL_TOLERANCE * stencil.max_abs();
                        (s.start..s.end)
                            .all(|i| {
                                grid_row(k, j * nx + i, nx).is_some_and(|b| stencil.matches(b, tol))
                            })
                            .then_some(stencil)
                    })
                    .collect()
            })
            .collect();
        let mut stencils = Vec::new();
        let row_stencils: Vec<Option<usize>> = per_row
            .into_iter()
            .map(|row| {
                row.map(|s| {
                    let first = stencils.len();
                    stencils.extend(s);
                    first
                })
            })
            .collect();
        if stencils.is_empty() {
            return None;
        }
        Some(GridStencil {
            nx,
            ny,
            segments,
            csr_columns,
            row_stencils,
            stencils,
            avx: has_avx(),
        })
    }

    fn apply<F: Finish>(&self, k: &BlockCsr, u: &[[f64; 2]], out: &mut [[f64; 2]], fin: &F) {
        let nx = self.nx;
        let (grid_out, tail) = out.split_at_mut(nx * self.ny);
        let rows_per_task = (NODES_PER_TASK / nx).max(1);
        let avx = self.avx;
        rayon::join(
            || {
                grid_out
                    .par_chunks_mut(nx * rows_per_task)
                    .enumerate()
                    .for_each(|(c, chunk)| {
                        let j0 = c * rows_per_task;
                        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
                        if avx {
                            // SAFETY: `has_avx` checked at run time that the CPU supports
                            // AVX, the only requirement of this target_feature function.
                            unsafe { self.rows_avx(k, j0, u, chunk, fin) };
                            return;
                        }
                        let _ = avx;
                        self.rows(k, j0, u, chunk, fin);
                    })
            },
            || csr_rows(k, nx * self.ny, u, tail, fin, false),
        );
    }

    /// Consecutive node rows from `j0` into `chunk` (whole rows).
    #[inline(always)]
    fn rows<F: Finish>(
        &self,
        k: &BlockCsr,
        j0: usize,
        u: &[[f64; 2]],
        chunk: &mut [[f64; 2]],
        fin: &F,
    ) {
        for (r, row) in chunk.chunks_exact_mut(self.nx).enumerate() {
            self.row(k, j0 + r, u, row, fin);
        }
    }

    /// [`GridStencil::rows`] compiled with AVX: the same operations in the same order
    /// (no FMA contraction: Rust never fuses a * b + c), so the results are bit-identical
    /// to the SSE2 build; only the vector width differs.
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[target_feature(enable = "avx")]
    fn rows_avx<F: Finish>(
        &self,
        k: &BlockCsr,
        j0: usize,
        u: &[[f64; 2]],
        chunk: &mut [[f64; 2]],
        fin: &F,
    ) {
        self.rows(k, j0, u, chunk, fin);
    }

    /// One node row j of the grid.
    #[inline(always)]
    fn row<F: Finish>(
        &self,
        k: &BlockCsr,
        j: usize,
        u: &[[f64; 2]],
        out: &mut [[f64; 2]],
        fin: &F,
    ) {
        let nx = self.nx;
        let base = j * nx;
        let Some(first) = self.row_stencils[j] else {
            csr_rows(k, base, u, out, fin, false);
            return;
        };
        for &i in &self.csr_columns {
            fin.node(base + i, row_product(k, base + i, u), &mut out[i]);
        }
        for (s, stencil) in self.segments.iter().zip(&self.stencils[first..]) {
            let (a, b) = (s.start, s.end);
            segment(
                stencil,
                &u[base - nx + a - 1..base - nx + b],
                &u[base + a - 1..base + b + 1],
                &u[base + nx + a..base + nx + b + 1],
                base + a,
                &mut out[a..b],
                fin,
            );
        }
    }
}

/// K's row of grid node `n` when it has exactly the 7 grid neighbours, in column order.
fn grid_row(k: &BlockCsr, n: usize, nx: usize) -> Option<&[[f64; 4]]> {
    let range = k.row_ptr[n]..k.row_ptr[n + 1];
    let expected = [n - nx - 1, n - nx, n - 1, n, n + 1, n + nx, n + nx + 1];
    let cols = &k.cols[range.clone()];
    (cols.len() == 7 && cols.iter().zip(expected).all(|(&c, e)| c as usize == e))
        .then(|| &k.blocks[range])
}

/// The stencil over nodes first..first + out.len() of one row: `dn` holds the row below
/// from one node left of the segment, `cur` this row from one left to one right, `up` the
/// row above from the segment start to one right. Same arithmetic and order as
/// [`row_product`] over the columns (down-left, down, left, self, right, up, up-right).
/// Nodes go two at a time as 4 lanes (one 256-bit vector with AVX, two 128-bit with SSE2),
/// an odd last node alone; the arithmetic per node is the same either way.
#[inline(always)]
fn segment<F: Finish>(
    s: &Stencil,
    dn: &[[f64; 2]],
    cur: &[[f64; 2]],
    up: &[[f64; 2]],
    first: usize,
    out: &mut [[f64; 2]],
    fin: &F,
) {
    let n = out.len();
    let (dn, cur, up) = (&dn[..n + 1], &cur[..n + 2], &up[..n + 1]);
    let fin = fin.sub(first, n);
    let d4: [[f64; 4]; 7] = s.diag.map(|d| [d[0], d[1], d[0], d[1]]);
    let o4: [[f64; 4]; 7] = s.off.map(|o| [o[0], o[1], o[0], o[1]]);
    // f + d .* v + o .* swap(v), pairwise: the [`row_product`] update of one block.
    #[inline(always)]
    fn term4(f: [f64; 4], d: [f64; 4], o: [f64; 4], v: [f64; 4]) -> [f64; 4] {
        [
            f[0] + (d[0] * v[0] + o[0] * v[1]),
            f[1] + (d[1] * v[1] + o[1] * v[0]),
            f[2] + (d[2] * v[2] + o[2] * v[3]),
            f[3] + (d[3] * v[3] + o[3] * v[2]),
        ]
    }
    #[inline(always)]
    fn first4(d: [f64; 4], o: [f64; 4], v: [f64; 4]) -> [f64; 4] {
        [
            d[0] * v[0] + o[0] * v[1],
            d[1] * v[1] + o[1] * v[0],
            d[2] * v[2] + o[2] * v[3],
            d[3] * v[3] + o[3] * v[2],
        ]
    }
    let (pairs, last) = out.as_chunks_mut::<2>();
    for (p, o2) in pairs.iter_mut().enumerate() {
        let i = 2 * p;
        // 0.0 + t == t (up to the sign of zero), so the sum starts at the first term.
        let mut f = first4(d4[0], o4[0], load4(dn, i));
        f = term4(f, d4[1], o4[1], load4(dn, i + 1));
        f = term4(f, d4[2], o4[2], load4(cur, i));
        f = term4(f, d4[3], o4[3], load4(cur, i + 1));
        f = term4(f, d4[4], o4[4], load4(cur, i + 2));
        f = term4(f, d4[5], o4[5], load4(up, i));
        f = term4(f, d4[6], o4[6], load4(up, i + 1));
        fin.pair(i, f, o2);
    }
    if let [pair] = last {
        let i = n - 1;
        let two = |v: [f64; 2]| [v[0], v[1], 0.0, 0.0];
        let mut f = first4(d4[0], o4[0], two(dn[i]));
        f = term4(f, d4[1], o4[1], two(dn[i + 1]));
        f = term4(f, d4[2], o4[2], two(cur[i]));
        f = term4(f, d4[3], o4[3], two(cur[i + 1]));
        f = term4(f, d4[4], o4[4], two(cur[i + 2]));
        f = term4(f, d4[5], o4[5], two(up[i]));
        f = term4(f, d4[6], o4[6], two(up[i + 1]));
        fin.node(i, [f[0], f[1]], pair);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laminate::{Laminate, StochasticSpec};
    use crate::material::Plane;
    use crate::mesh::{Mesh, Side};
    use rand::{RngExt, SeedableRng};

    fn model(x_breaks: &[f64], crack: bool) -> Model {
        let lam = Laminate::stochastic(
            &StochasticSpec {
                pairs: 4,
                ..Default::default()
            },
            Plane::Strain,
        )
        .unwrap();
        let h = lam.thickness_m();
        let y = h * 0.55;
        let mut ybreaks = vec![];
        if crack {
            ybreaks.push(y);
        }
        let mut mesh = Mesh::layered(&lam, 3e-3, 97e-6, 40e-6, x_breaks, &ybreaks).unwrap();
        let crack = crack.then(|| {
            let y = mesh.nearest_row_y(y).unwrap();
            let x0 = mesh.nearest_column_x(x_breaks[0]).unwrap();
            let x1 = mesh.nearest_column_x(x_breaks[1]).unwrap();
            mesh.insert_crack(y, x0, x1).unwrap()
        });
        Model::build(
            mesh,
            lam.materials,
            &[Side::Bottom.into(), Side::Left.into()],
            vec![0, 1],
            crack,
        )
        .unwrap()
    }

    fn check(model: &Model, expect_stencils: bool) {
        let op = StiffnessOperator::new(model);
        assert_eq!(op.is_matrix_free(), expect_stencils);
        if expect_stencils {
            assert!(op.stencil_fraction() > 0.5, "{}", op.stencil_fraction());
        }
        let n = model.dofs();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..3 {
            let u: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let up: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let a: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..1e-12)).collect();
            let (mut f_ref, mut f) = (vec![0.0; n], vec![0.0; n]);
            model.stiffness.mul(&u, &mut f_ref);
            op.mul(&u, &mut f);
            let scale = f_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let err = f
                .iter()
                .zip(&f_ref)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                err <= 1e-13 * scale,
                "K u: error {err:e} vs scale {scale:e}"
            );
            let mut next = vec![0.0; n];
            op.explicit_update(&a, &up, &u, &mut next);
            for d in 0..n {
                let expect = 2.0 * u[d] - up[d] - a[d] * f_ref[d];
                assert!(
                    (next[d] - expect).abs() <= 1e-13 * (1.0 + a[d] * scale),
                    "update DOF {d}: {} vs {expect}",
                    next[d]
                );
            }
        }
    }

    #[test]
    fn stencil_matches_assembled_k_uniform_columns() {
        check(&model(&[], false), true);
    }

    #[test]
    fn stencil_matches_assembled_k_non_uniform_columns() {
        // x breaks make three column widths and width-change columns read from K.
        check(&model(&[0.71e-3, 2.03e-3], false), true);
    }

    #[test]
    fn stencil_matches_assembled_k_with_crack() {
        check(&model(&[0.71e-3, 2.03e-3], true), true);
    }

    #[test]
    fn unstructured_model_uses_the_matrix() {
        let mut m = model(&[], false);
        m.mesh.grid = None;
        check(&m, false);
    }

    #[test]
    fn avx_and_sse2_kernels_are_bit_identical() {
        let m = model(&[0.71e-3, 2.03e-3], true);
        let mut op = StiffnessOperator::new(&m);
        let n = m.dofs();
        let u: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.5)
            .collect();
        let a: Vec<f64> = (0..n).map(|i| 1e-12 * ((i * 31) % 17) as f64).collect();
        let mut results = Vec::new();
        for avx in [false, has_avx()] {
            op.grid.as_mut().unwrap().avx = avx;
            let (mut f, mut next) = (vec![0.0; n], vec![0.0; n]);
            op.mul(&u, &mut f);
            op.explicit_update(&a, &f, &u, &mut next);
            results.push((f, next));
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&results[0].0), bits(&results[1].0));
        assert_eq!(bits(&results[0].1), bits(&results[1].1));
    }

    #[test]
    fn results_are_bit_identical_for_any_thread_count() {
        let m = model(&[0.71e-3, 2.03e-3], true);
        let op = StiffnessOperator::new(&m);
        let n = m.dofs();
        let u: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.5)
            .collect();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut f = vec![0.0; n];
            pool.install(|| op.mul(&u, &mut f));
            f
        };
        let one = run(1);
        for t in [2, 3, 5] {
            assert!(run(t)
                .iter()
                .zip(&one)
                .all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }
}
