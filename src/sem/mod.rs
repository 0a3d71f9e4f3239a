//! Spectral elements on the layered rectangle (Patera 1984; Komatitsch and Vilotte 1998, as
//! in SPECFEM2D and SEM2DPACK): rectangular elements aligned with the layers, tensor-product
//! Lagrange polynomials on Gauss-Lobatto-Legendre (GLL) points, GLL quadrature, hence an
//! exactly diagonal mass, and the stiffness applied matrix-free by sum factorisation.
//!
//! The polynomial order along x is one for the whole grid; the order across y is chosen per
//! element row, so thin layers can take a low order (and do not shrink the time step) while
//! thick ones take a high one. The mesh stays conforming: a horizontal element edge carries
//! only the x-direction GLL points, the same in the rows above and below it, and the elements
//! of one row share their vertical edges' y-points.
//!
//! The nodes form a tensor grid: node (i, j) sits at `(x_nodes_m[i], y_nodes_m[j])`, index
//! `j * nx + i`, DOFs `2 * node + component` (as the T3 mesh numbers them).
//!
//! A crack ([`SemModel::split_crack`]) splits the nodes of a horizontal element edge line
//! (split nodes, as SEM2DPACK does for faults): their duplicates are appended after the
//! grid, and the element row below the line reads and writes the duplicates, the row above
//! the originals. Viscous springs ([`SemModel::viscous_springs`]) add a diagonal stiffness.

mod assembled;
pub(crate) mod boundary;
mod crack;
mod discretisation;
mod even_odd;
pub mod gll;
mod layered;
mod memory;
pub mod unstructured;

pub(crate) use layered::column_count;
pub use layered::{FineColumns, SemSpec};

use crate::error::{Error, Result};

use crate::attenuation::memory::{Elastic, PointLaw, RowMemory, Viscous};
use crate::material::Material;
use crate::mesh::Crack;
use even_odd::EvenOdd;
use gll::Gll;
use rayon::prelude::*;

/// The layered rectangle as spectral elements: element lines, orders, materials, nodes and
/// the diagonal GLL mass.
#[derive(Clone, Debug)]
pub struct SemModel {
    /// Element column lines (x, m), ascending.
    pub columns_m: Vec<f64>,
    /// Element row lines (y, m), ascending.
    pub rows_m: Vec<f64>,
    /// x coordinates of the node columns.
    pub x_nodes_m: Vec<f64>,
    /// y coordinates of the node rows.
    pub y_nodes_m: Vec<f64>,
    /// Plane materials.
    pub materials: Vec<Material>,
    /// Material of each element row (index into `materials`).
    pub row_material: Vec<usize>,
    /// Diagonal mass per DOF, M_kk = sum over elements of rho w_a w_b J (kg); on a crack each
    /// face sums its own side's elements.
    pub lumped_mass: Vec<f64>,
    /// DOFs held at zero (none unless set).
    pub fixed_dofs: Vec<usize>,
    /// (DOF, c) of the absorbing edges' dashpots (none unless set, see
    /// [`SemModel::lysmer_dashpots`]).
    pub dashpots: Vec<(usize, f64)>,
    /// (DOF, k) of the diagonal springs of viscous-spring edges (none unless set, see
    /// [`SemModel::viscous_springs`]), added to K u in this order.
    pub springs: Vec<(usize, f64)>,
    /// The crack's split node line, if any ([`SemModel::split_crack`]).
    split: Option<Split>,
    gll_x: Gll,
    /// GLL rule of each element row (its order across y).
    gll_y: Vec<Gll>,
    /// D_x and its transpose, by their even-odd decompositions.
    derivative_x: EvenOdd,
    derivative_x_t: EvenOdd,
    /// D_y of each element row and its transpose, the same way.
    derivative_y: Vec<EvenOdd>,
    derivative_y_t: Vec<EvenOdd>,
    /// First node row of each element row.
    first_line: Vec<usize>,
    /// Half widths jx = h_x / 2 of the element columns (dx/dxi), by lane group, the padding
    /// lanes past the last column 1.
    half_width: Vec<Lanes>,
}

/// The split node line of a crack: the element row below it reads and writes the duplicates
/// of node columns `first..=last` of node row `line`, numbered from `first_duplicate` on.
#[derive(Clone, Debug)]
struct Split {
    /// The element row whose top node line is the lower face.
    row_below: usize,
    /// Node row of the crack line.
    line: usize,
    /// First and last split node column.
    first: usize,
    last: usize,
    /// Index of the first duplicate (the number of grid nodes).
    first_duplicate: usize,
    /// The node pairs, as the contact solver takes them.
    crack: Crack,
}

impl Split {
    /// The duplicate (lower-face node) of node column `i` of the crack line, if it is split.
    #[inline(always)]
    fn duplicate(&self, i: usize) -> Option<usize> {
        (self.first..=self.last)
            .contains(&i)
            .then(|| self.first_duplicate + i - self.first)
    }
}

/// Element columns per lane group of the row kernel: the elements of an element row are
/// processed `LANES` at a time, every array operation running across them (f64 SIMD lanes).
const LANES: usize = 8;

/// One value per element of a lane group.
type Lanes = [f64; LANES];

/// Scratch of [`SemModel::stiffness_times`], allocated once per model size: per element row,
/// the forces on its node lines and one lane group's fields at its GLL points; the springs
/// sorted by node line.
#[derive(Clone, Debug)]
pub struct SemWorkspace {
    rows: Vec<RowWork>,
    springs: SpringLines,
    /// The memory variables of each element row, `Some` where its material is viscoelastic;
    /// empty until a time step starts them ([`SemModel::start_memory`]).
    memory: Vec<Option<RowMemory<LANES>>>,
}

#[derive(Clone, Debug)]
struct RowWork {
    /// Forces on the row's node lines, `(order_y + 1) * nx * 2`.
    force: Vec<f64>,
    /// Displacements u_x, u_y of a lane group's elements at their GLL points, `[b * N + a]`.
    u: [Vec<Lanes>; 2],
    /// Weighted stresses W sigma_xx, W sigma_yy, W sigma_xy at the same points.
    stress: [Vec<Lanes>; 3],
    /// Two derivatives across the row at the same points: of u_x and u_y in
    /// [`SemModel::stresses`], of W sigma_xy and W sigma_yy in [`SemModel::scatter_forces`].
    across: [Vec<Lanes>; 2],
    /// The sums and differences of mirrored lines ([`EvenOdd::apply_across`]).
    mirrored: Vec<Lanes>,
}

/// The model's springs sorted by DOF (stably: the springs of one DOF keep their order), so by
/// node line with the crack's duplicates last, with the list they were sorted from (rebuilt if
/// it changes).
#[derive(Clone, Debug, Default)]
struct SpringLines {
    springs: Vec<(usize, f64)>,
    sorted: Vec<(usize, f64)>,
    /// `sorted[start[j]..start[j + 1]]` are the springs of node line j.
    start: Vec<usize>,
}

impl SpringLines {
    fn new(model: &SemModel) -> SpringLines {
        let (nx, lines) = (model.nx(), model.y_nodes_m.len());
        let line = |d: usize| (d / 2 / nx).min(lines);
        let mut sorted = model.springs.clone();
        sorted.sort_by_key(|&(d, _)| d);
        let start = (0..=lines + 1)
            .map(|j| sorted.partition_point(|&(d, _)| line(d) < j))
            .collect();
        SpringLines {
            springs: model.springs.clone(),
            sorted,
            start,
        }
    }

    /// The springs of node line `j` (the duplicates: one past the last line).
    fn line(&self, j: usize) -> &[(usize, f64)] {
        &self.sorted[self.start[j]..self.start[j + 1]]
    }
}

/// The central-difference predictor applied to K u in the same pass:
/// u_next = 2 u - u_prev - a .* (K u), a = dt^2 / m.
#[derive(Clone, Copy)]
struct Predictor<'a> {
    a: &'a [f64],
    u_prev: &'a [f64],
}

impl SemModel {
    /// Spectral elements between `columns_m` and `rows_m` (ascending lines), order `order_x`
    /// along x and `order_y[r]` across element row r, material `row_material[r]` of
    /// `materials` in row r.
    pub fn new(
        columns_m: Vec<f64>,
        rows_m: Vec<f64>,
        order_x: usize,
        order_y: &[usize],
        materials: Vec<Material>,
        row_material: Vec<usize>,
    ) -> Result<SemModel> {
        check_lines("columns_m", &columns_m)?;
        check_lines("rows_m", &rows_m)?;
        let n_rows = rows_m.len() - 1;
        if order_y.len() != n_rows || row_material.len() != n_rows {
            return Err(Error::invalid(
                "order_y",
                format!("{} orders, {} materials", order_y.len(), row_material.len()),
                format!("needs one per element row ({n_rows})"),
            ));
        }
        for (name, &order) in
            std::iter::once(("order_x", &order_x)).chain(order_y.iter().map(|o| ("order_y", o)))
        {
            if !(1..=MAX_ORDER).contains(&order) {
                return Err(Error::invalid(
                    name,
                    order,
                    format!("must be 1..={MAX_ORDER}"),
                ));
            }
        }
        if let Some(&m) = row_material.iter().find(|&&m| m >= materials.len()) {
            return Err(Error::invalid("row_material", m, "no such material"));
        }
        let gll_x = Gll::new(order_x);
        let gll_y: Vec<Gll> = order_y.iter().map(|&o| Gll::new(o)).collect();
        let x_nodes_m = node_lines(&columns_m, |_| &gll_x);
        let y_nodes_m = node_lines(&rows_m, |r| &gll_y[r]);
        let mut first_line = Vec::with_capacity(n_rows);
        let mut line = 0;
        for g in &gll_y {
            first_line.push(line);
            line += g.order();
        }
        let derivative_x = EvenOdd::new(&gll_x.derivative);
        let derivative_x_t = EvenOdd::transposed(&gll_x.derivative);
        let derivative_y = gll_y.iter().map(|g| EvenOdd::new(&g.derivative)).collect();
        let derivative_y_t = gll_y
            .iter()
            .map(|g| EvenOdd::transposed(&g.derivative))
            .collect();
        let half_width = lane_groups(columns_m.windows(2).map(|w| 0.5 * (w[1] - w[0])));
        let mut model = SemModel {
            columns_m,
            rows_m,
            x_nodes_m,
            y_nodes_m,
            materials,
            row_material,
            lumped_mass: Vec::new(),
            fixed_dofs: Vec::new(),
            dashpots: Vec::new(),
            springs: Vec::new(),
            split: None,
            gll_x,
            gll_y,
            derivative_x,
            derivative_x_t,
            derivative_y,
            derivative_y_t,
            first_line,
            half_width,
        };
        model.lumped_mass = model.assemble_mass();
        Ok(model)
    }

    /// The polynomial order across each element row, bottom row first.
    pub fn row_orders(&self) -> Vec<usize> {
        self.gll_y.iter().map(Gll::order).collect()
    }

    /// Number of node columns.
    pub fn nx(&self) -> usize {
        self.x_nodes_m.len()
    }

    /// Number of degrees of freedom (2 per node, the crack's duplicates included).
    pub fn dofs(&self) -> usize {
        2 * self.nodes()
    }

    /// Number of nodes: the grid's, then the crack's duplicates.
    pub fn nodes(&self) -> usize {
        self.grid_nodes() + self.split.as_ref().map_or(0, |s| s.last + 1 - s.first)
    }

    /// Number of grid nodes (without the crack's duplicates).
    fn grid_nodes(&self) -> usize {
        self.x_nodes_m.len() * self.y_nodes_m.len()
    }

    /// Node index of node column `i`, node row `j` (on a crack line: the upper face).
    pub fn node(&self, i: usize, j: usize) -> usize {
        j * self.nx() + i
    }

    /// The global node of local node (a, b) (a along x, b across the row) of the element in
    /// element row `r`, element column `c`: the grid node, or on the top line of the row just
    /// below a crack the lower-face duplicate where the line is split.
    pub(crate) fn element_node(&self, r: usize, c: usize, a: usize, b: usize) -> usize {
        let i = c * self.gll_x.order() + a;
        if let Some(s) = self.split.as_ref() {
            if r == s.row_below && b == self.gll_y[r].order() {
                if let Some(d) = s.duplicate(i) {
                    return d;
                }
            }
        }
        self.node(i, self.first_line[r] + b)
    }

    /// Position (x, y) of `node` (m), `node < self.nodes()`; a duplicate sits where its
    /// upper-face node does.
    pub fn node_position(&self, node: usize) -> [f64; 2] {
        let nx = self.nx();
        match self.split.as_ref().filter(|s| node >= s.first_duplicate) {
            Some(s) => [
                self.x_nodes_m[s.first + node - s.first_duplicate],
                self.y_nodes_m[s.line],
            ],
            None => [self.x_nodes_m[node % nx], self.y_nodes_m[node / nx]],
        }
    }

    /// The crack, if one was split ([`SemModel::split_crack`]).
    pub fn crack(&self) -> Option<&Crack> {
        self.split.as_ref().map(|s| &s.crack)
    }

    /// Checks that the fixed DOFs, dashpots and springs name DOFs of the model, and that the
    /// dashpot and spring coefficients are finite and >= 0, naming the first that is not.
    pub fn check(&self) -> Result<()> {
        let dofs = self.dofs();
        if let Some(&d) = self.fixed_dofs.iter().find(|&&d| d >= dofs) {
            return Err(Error::invalid(
                "fixed_dofs",
                d,
                format!("DOF must be < {dofs}"),
            ));
        }
        for (name, set) in [("dashpots", &self.dashpots), ("springs", &self.springs)] {
            if let Some(&(d, c)) = set
                .iter()
                .find(|&&(d, c)| d >= dofs || !(c.is_finite() && c >= 0.0))
            {
                return Err(Error::invalid(
                    name,
                    format!("DOF {d} coefficient {c}"),
                    format!("DOF must be < {dofs} and the coefficient finite and >= 0"),
                ));
            }
        }
        Ok(())
    }

    /// Scratch for [`SemModel::stiffness_times`].
    pub fn workspace(&self) -> SemWorkspace {
        let px = self.gll_x.order();
        let rows = self
            .gll_y
            .iter()
            .map(|g| {
                let points = (px + 1) * (g.order() + 1);
                let lanes = || vec![[0.0; LANES]; points];
                RowWork {
                    force: vec![0.0; (g.order() + 1) * self.nx() * 2],
                    u: [lanes(), lanes()],
                    stress: [lanes(), lanes(), lanes()],
                    across: [lanes(), lanes()],
                    mirrored: lanes(),
                }
            })
            .collect();
        SemWorkspace {
            rows,
            springs: SpringLines::new(self),
            memory: Vec::new(),
        }
    }

    /// The diagonal mass: rho w_a w_b (h_x / 2) (h_y / 2) at each element's GLL point (a, b),
    /// summed where elements share a node; the same for both components.
    fn assemble_mass(&self) -> Vec<f64> {
        let mut mass = vec![0.0; self.dofs()];
        let px = self.gll_x.order();
        for (r, gy) in self.gll_y.iter().enumerate() {
            let rho = self.materials[self.row_material[r]].density_kg_m3;
            let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
            for c in 0..self.columns_m.len() - 1 {
                let jx = 0.5 * (self.columns_m[c + 1] - self.columns_m[c]);
                for b in 0..=gy.order() {
                    for a in 0..=px {
                        let node = self.element_node(r, c, a, b);
                        let m = rho * self.gll_x.weights[a] * gy.weights[b] * jx * jy;
                        mass[2 * node] += m;
                        mass[2 * node + 1] += m;
                    }
                }
            }
        }
        mass
    }

    /// `out = K u`, the internal forces f_k = sum_e int B_k^T C B u dA with GLL quadrature,
    /// by sum factorisation: gradients at the GLL points from the 1-D derivative matrices
    /// (O(p^3) per element), stresses sigma = C eps, then the transposed derivatives.
    /// Element rows run in parallel into their own force lines, their elements a lane group
    /// at a time ([`SemModel::row_forces`]); node lines then gather from the one or two
    /// element rows that hold them, in a fixed order (bit-identical for any thread count). On
    /// a crack line the split columns take the row above only, and their duplicates the row
    /// below; then the springs add k u on their DOFs, in order. Allocates nothing (unless the
    /// springs changed since the workspace was made).
    pub fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut SemWorkspace) {
        self.apply(u, out, None, work);
    }

    /// The central-difference predictor u_next = 2 u - u_prev - a .* (K u) (report eq 69,
    /// a = dt^2 / m) fused into [`SemModel::stiffness_times`]: each node line of K u is
    /// finished into u_next as it is gathered, one pass over the vectors. Bit-identical to
    /// forming K u first and combining after.
    pub fn explicit_update(
        &self,
        a: &[f64],
        u_prev: &[f64],
        u: &[f64],
        u_next: &mut [f64],
        work: &mut SemWorkspace,
    ) {
        assert_eq!(a.len(), self.dofs());
        assert_eq!(u_prev.len(), self.dofs());
        self.apply(u, u_next, Some(Predictor { a, u_prev }), work);
    }

    /// K u into `out`, through the `predictor` if one is given.
    fn apply(
        &self,
        u: &[f64],
        out: &mut [f64],
        predictor: Option<Predictor>,
        work: &mut SemWorkspace,
    ) {
        assert_eq!(u.len(), self.dofs());
        assert_eq!(out.len(), self.dofs());
        if work.springs.springs != self.springs {
            work.springs = SpringLines::new(self);
        }
        let SemWorkspace {
            rows,
            springs,
            memory,
        } = work;
        if predictor.is_some() && !memory.is_empty() {
            rows.par_iter_mut()
                .zip(memory.par_iter_mut())
                .enumerate()
                .for_each(|(r, (row, memory))| match memory {
                    Some(m) => self.row_forces::<Viscous, _>(r, u, row, m),
                    None => self.row_forces::<Elastic, _>(r, u, row, &mut ()),
                });
        } else {
            rows.par_iter_mut()
                .enumerate()
                .for_each(|(r, row)| self.row_forces::<Elastic, _>(r, u, row, &mut ()));
        }
        // springs, then the predictor, on a line of K u starting at DOF `first`
        let finish = |first: usize, line: &mut [f64], springs: &[(usize, f64)]| {
            for &(d, k) in springs {
                line[d - first] += k * u[d];
            }
            if let Some(Predictor { a, u_prev }) = predictor {
                let dofs = first..first + line.len();
                let old = a[dofs.clone()].iter().zip(&u_prev[dofs.clone()]);
                for ((ku, (&ai, &pi)), &ui) in line.iter_mut().zip(old).zip(&u[dofs]) {
                    *ku = 2.0 * ui - pi - ai * *ku;
                }
            }
        };
        let nx = self.nx();
        let (grid, faces) = out.split_at_mut(2 * self.grid_nodes());
        grid.par_chunks_mut(2 * nx)
            .enumerate()
            .for_each(|(j, line)| {
                let first = 2 * j * nx;
                let crack_line = self.split.as_ref().is_some_and(|s| s.line == j);
                match predictor {
                    Some(p) if !crack_line => {
                        let (own, lower) = self.line_sources(j, rows, line.len());
                        p.finish_sum(first, u, (own, lower), springs.line(j), line);
                    }
                    _ => {
                        self.node_line_forces(j, rows, line);
                        finish(first, line, springs.line(j));
                    }
                }
            });
        if let Some(s) = &self.split {
            let top = self.gll_y[s.row_below].order() * 2 * nx;
            let lower = &rows[s.row_below].force[top + 2 * s.first..top + 2 * (s.last + 1)];
            faces.copy_from_slice(lower);
            finish(
                2 * s.first_duplicate,
                faces,
                springs.line(self.y_nodes_m.len()),
            );
        }
    }

    /// K u on node line `j` (without the springs): the forces of the element row whose
    /// lines start at or below j, plus on its first line those of the row below (on a crack
    /// line only where it is not split).
    fn node_line_forces(&self, j: usize, rows: &[RowWork], line: &mut [f64]) {
        let (own, lower) = self.line_sources(j, rows, line.len());
        let Some(lower) = lower else {
            line.copy_from_slice(own);
            return;
        };
        match self.split.as_ref().filter(|s| s.line == j) {
            None => {
                for ((o, f), l) in line.iter_mut().zip(own).zip(lower) {
                    *o = f + l;
                }
            }
            Some(s) => {
                line.copy_from_slice(own);
                let pairs = line.chunks_exact_mut(2).zip(lower.chunks_exact(2));
                for (i, (o, l)) in pairs.enumerate() {
                    if s.duplicate(i).is_none() {
                        o[0] += l[0];
                        o[1] += l[1];
                    }
                }
            }
        }
    }

    /// The force lines (`n` values each) node line `j` sums: that of the element row whose
    /// lines start at or below j, and on its first line the top line of the row below.
    fn line_sources<'a>(
        &self,
        j: usize,
        rows: &'a [RowWork],
        n: usize,
    ) -> (&'a [f64], Option<&'a [f64]>) {
        let r = self.first_line.partition_point(|&f| f <= j) - 1;
        let b = j - self.first_line[r];
        let own = &rows[r].force[b * n..(b + 1) * n];
        let lower = (b == 0 && r > 0).then(|| {
            let below = self.gll_y[r - 1].order();
            &rows[r - 1].force[below * n..(below + 1) * n]
        });
        (own, lower)
    }

    /// Forces of element row `r` on its own node lines. The row kernel is compiled for each
    /// number of points along x (so its loops over them have fixed length; the order was
    /// checked against [`MAX_ORDER`] when the model was built), and with AVX where the CPU
    /// has it (wider lanes, the same operations: bit-identical results).
    fn row_forces<L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        u: &[f64],
        row: &mut RowWork,
        law: &mut S,
    ) {
        macro_rules! by_points {
            ($($n:literal)*) => {
                match self.gll_x.order() + 1 {
                    $($n => self.row_forces_dispatch::<$n, L, S>(r, u, row, law),)*
                    n => unreachable!("{n} GLL points along x: above MAX_ORDER + 1"),
                }
            };
        }
        by_points!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
    }

    fn row_forces_dispatch<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        u: &[f64],
        row: &mut RowWork,
        law: &mut S,
    ) {
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        if std::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above), the only requirement
            // of this target_feature function.
            return unsafe { self.row_forces_avx512::<N, L, S>(r, u, row, law) };
        }
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX (checked just above), the only requirement of
            // this target_feature function.
            return unsafe { self.row_forces_avx::<N, L, S>(r, u, row, law) };
        }
        self.row_kernel::<N, L, S>(r, u, row, law);
    }

    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[target_feature(enable = "avx512f")]
    fn row_forces_avx512<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        u: &[f64],
        row: &mut RowWork,
        law: &mut S,
    ) {
        self.row_kernel::<N, L, S>(r, u, row, law);
    }

    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    #[target_feature(enable = "avx")]
    fn row_forces_avx<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        u: &[f64],
        row: &mut RowWork,
        law: &mut S,
    ) {
        self.row_kernel::<N, L, S>(r, u, row, law);
    }

    /// The elements of row `r`, `LANES` columns at a time: displacements gathered into
    /// lanes ([`SemModel::gather`]), weighted stresses ([`SemModel::stresses`]), nodal
    /// forces into the row's force lines ([`SemModel::scatter_forces`]). Every line of the
    /// row's forces is written (no zeroing pass needed). The point law `L` adds what the
    /// material does beyond W C_U eps (nothing for [`Elastic`]); a law without forces stops
    /// at the stresses.
    #[inline(always)]
    fn row_kernel<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        u: &[f64],
        row: &mut RowWork,
        law: &mut S,
    ) {
        let points = N * (self.gll_y[r].order() + 1);
        let RowWork {
            force,
            u: [ux, uy],
            stress: [sxx, syy, sxy],
            across: [across_1, across_2],
            mirrored,
        } = row;
        let (ux, uy) = (&mut ux[..points], &mut uy[..points]);
        let (sxx, syy, sxy) = (&mut sxx[..points], &mut syy[..points], &mut sxy[..points]);
        let (a1, a2) = (&mut across_1[..points], &mut across_2[..points]);
        for (g, jx) in self.half_width.iter().enumerate() {
            self.gather::<N>(r, g * LANES, u, ux, uy);
            let fields = ([&*ux, &*uy], [&mut *a1, &mut *a2], &mut mirrored[..]);
            self.stresses::<N, L, S>(r, jx, fields, [sxx, syy, sxy], (law, g * points));
            if L::FORCES {
                let stresses = [&*sxx, &*syy, &*sxy];
                self.scatter_forces::<N>(r, g * LANES, jx, stresses, [a1, a2], mirrored, force);
            }
        }
    }

    /// Displacements of the elements in columns `c0..c0 + LANES` of row `r` at their GLL
    /// points, `[b * N + a][lane]`: zero in the padding lanes past the last column, and on
    /// the top line of the row just below a crack the lower face's duplicates where split.
    #[inline(always)]
    fn gather<const N: usize>(
        &self,
        r: usize,
        c0: usize,
        u: &[f64],
        ux: &mut [Lanes],
        uy: &mut [Lanes],
    ) {
        let (nx, px, nby) = (self.nx(), N - 1, ux.len() / N);
        let lanes = LANES.min(self.columns_m.len() - 1 - c0);
        for b in 0..nby {
            let line = &u[2 * (self.first_line[r] + b) * nx..][..2 * nx];
            let (ux, uy) = (&mut ux[b * N..][..N], &mut uy[b * N..][..N]);
            if lanes == LANES {
                // the group's node columns, a fixed length: no bounds checks in the loop
                let group = &line[2 * c0 * px..][..2 * (LANES * px + 1)];
                for a in 0..N {
                    for l in 0..LANES {
                        ux[a][l] = group[2 * (l * px + a)];
                        uy[a][l] = group[2 * (l * px + a) + 1];
                    }
                }
                continue;
            }
            for l in 0..LANES {
                if l < lanes {
                    let i0 = (c0 + l) * px;
                    for (a, v) in line[2 * i0..2 * (i0 + N)].chunks_exact(2).enumerate() {
                        ux[a][l] = v[0];
                        uy[a][l] = v[1];
                    }
                } else {
                    for a in 0..N {
                        ux[a][l] = 0.0;
                        uy[a][l] = 0.0;
                    }
                }
            }
        }
        if let Some(s) = self.split.as_ref().filter(|s| s.row_below == r) {
            let top = (nby - 1) * N;
            for l in 0..lanes {
                for a in 0..N {
                    if let Some(d) = s.duplicate((c0 + l) * px + a) {
                        ux[top + a][l] = u[2 * d];
                        uy[top + a][l] = u[2 * d + 1];
                    }
                }
            }
        }
    }

    /// Weighted stresses of a lane group at its GLL points (a, b): the gradients
    /// d/dxi u(a, b) = sum_k D_x[a][k] u(k, b) and d/deta u(a, b) = sum_k D_y[b][k] u(a, k)
    /// (by [`EvenOdd`]; the derivatives across the row into `across`), the strains
    /// eps = (u_x,xi / jx, u_y,eta / jy, u_x,eta / jy + u_y,xi / jx), and W C eps with
    /// W = w_a w_b jx jy; every operation across the lanes (the group's elements, each with its
    /// own jx); then the point law at each point, the group's first point being the row's
    /// point `first` (`law` = (its state, first)).
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn stresses<const N: usize, L: PointLaw<LANES, S>, S>(
        &self,
        r: usize,
        jx: &Lanes,
        ([ux, uy], [ux_eta, uy_eta], mirrored): ([&[Lanes]; 2], [&mut [Lanes]; 2], &mut [Lanes]),
        [sxx, syy, sxy]: [&mut [Lanes]; 3],
        (law, first): (&mut S, usize),
    ) {
        let nby = ux.len() / N;
        self.derivative_y[r].apply_across::<N>(ux, mirrored, ux_eta);
        self.derivative_y[r].apply_across::<N>(uy, mirrored, uy_eta);
        let (wx, wy) = (&self.gll_x.weights, &self.gll_y[r].weights);
        let jy = 0.5 * (self.rows_m[r + 1] - self.rows_m[r]);
        // local copies: the stores below cannot alias them, so they stay in registers
        let [c0, c1, c2] = self.materials[self.row_material[r]].stiffness_pa;
        let jx = *jx;
        let inv_jx = jx.map(|j| 1.0 / j);
        let inv_jy = 1.0 / jy;
        for b in 0..nby {
            let ux_xi = self.derivative_x.apply::<N>(&ux[b * N..]);
            let uy_xi = self.derivative_x.apply::<N>(&uy[b * N..]);
            for a in 0..N {
                let w = wx[a] * wy[b] * jy;
                let p = b * N + a;
                // one simple loop per quantity, each a few vector operations
                let (mut e_xx, mut e_yy, mut g_xy, mut weight) =
                    ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
                for l in 0..LANES {
                    e_xx[l] = ux_xi[a][l] * inv_jx[l];
                }
                for l in 0..LANES {
                    e_yy[l] = uy_eta[p][l] * inv_jy;
                }
                for l in 0..LANES {
                    g_xy[l] = ux_eta[p][l] * inv_jy + uy_xi[a][l] * inv_jx[l];
                }
                for l in 0..LANES {
                    weight[l] = w * jx[l];
                }
                for (s, c) in [(&mut sxx[p], c0), (&mut syy[p], c1), (&mut sxy[p], c2)] {
                    for l in 0..LANES {
                        s[l] = weight[l] * (c[0] * e_xx[l] + c[1] * e_yy[l] + c[2] * g_xy[l]);
                    }
                }
                let stress = [&mut sxx[p], &mut syy[p], &mut sxy[p]];
                L::at_point(law, first + p, &weight, [&e_xx, &e_yy, &g_xy], stress);
            }
        }
    }

    /// Nodal forces of a lane group (columns `c0..`) from its weighted stresses, by the
    /// transposed derivatives (by [`EvenOdd`]; those across the row into `across`):
    /// f_x(a, b) = sum_k D_x[k][a] W sxx(k, b) / jx + sum_k D_y[k][b] W sxy(a, k) / jy,
    /// f_y(a, b) = sum_k D_x[k][a] W sxy(k, b) / jx + sum_k D_y[k][b] W syy(a, k) / jy,
    /// written into the row's force lines in column order, a node on a vertical element edge
    /// taking the left element's force plus the right one's.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn scatter_forces<const N: usize>(
        &self,
        r: usize,
        c0: usize,
        jx: &Lanes,
        [sxx, syy, sxy]: [&[Lanes]; 3],
        [fx_eta, fy_eta]: [&mut [Lanes]; 2],
        mirrored: &mut [Lanes],
        force: &mut [f64],
    ) {
        let (nx, px, nby) = (self.nx(), N - 1, sxx.len() / N);
        self.derivative_y_t[r].apply_across::<N>(sxy, mirrored, fx_eta);
        self.derivative_y_t[r].apply_across::<N>(syy, mirrored, fy_eta);
        let inv_jx = jx.map(|j| 1.0 / j);
        let inv_jy = 2.0 / (self.rows_m[r + 1] - self.rows_m[r]);
        let lanes = LANES.min(self.columns_m.len() - 1 - c0);
        for b in 0..nby {
            let fx_xi = self.derivative_x_t.apply::<N>(&sxx[b * N..]);
            let fy_xi = self.derivative_x_t.apply::<N>(&sxy[b * N..]);
            let mut f = [[[0.0; LANES]; 2]; N];
            for (a, fa) in f.iter_mut().enumerate() {
                let p = b * N + a;
                for l in 0..LANES {
                    fa[0][l] = fx_xi[a][l] * inv_jx[l] + fx_eta[p][l] * inv_jy;
                    fa[1][l] = fy_xi[a][l] * inv_jx[l] + fy_eta[p][l] * inv_jy;
                }
            }
            let line = &mut force[2 * b * nx..2 * (b + 1) * nx];
            if lanes == LANES {
                scatter_group::<N>(&f, &mut line[2 * c0 * px..][..2 * (LANES * px + 1)], c0 > 0);
                continue;
            }
            for l in 0..lanes {
                let c = c0 + l;
                let nodes = line[2 * c * px..2 * (c * px + N)].as_chunks_mut::<2>().0;
                let left = if c > 0 { nodes[0] } else { [0.0; 2] };
                for (node, fa) in nodes.iter_mut().zip(&f) {
                    *node = [fa[0][l], fa[1][l]];
                }
                nodes[0] = [left[0] + f[0][0][l], left[1] + f[0][1][l]];
            }
        }
    }

    /// Largest eigenvalue of M^-1 K over the `free` DOFs (Lanczos, as for the T3 model), and
    /// the iterations used; dt_crit = 2 / sqrt of it. K is [`SemModel::stiffness_times`]'s:
    /// with the crack's faces apart and the springs; `free` has one entry per DOF.
    pub fn max_eigenvalue(&self, free: &[bool]) -> (f64, usize) {
        let work = std::cell::RefCell::new(self.workspace());
        crate::solve::stability::lanczos_max_eigenvalue_of(&self.lumped_mass, free, |x, y| {
            self.stiffness_times(x, y, &mut work.borrow_mut())
        })
    }
}

/// Highest polynomial order offered (the GLL points are accurate to round-off well beyond).
pub const MAX_ORDER: usize = 16;

/// The forces `f[a][component][lane]` of a full lane group into its node columns `group`
/// (LANES elements of N - 1 columns, and the last one's right edge): the interior columns
/// written, each vertical element edge the left element's force plus the right one's (the
/// group's left edge: what the group before wrote there, when `after_a_group`).
#[inline(always)]
fn scatter_group<const N: usize>(f: &[[Lanes; 2]; N], group: &mut [f64], after_a_group: bool) {
    let px = N - 1;
    let left = if after_a_group {
        [group[0], group[1]]
    } else {
        [0.0; 2]
    };
    for (a, fa) in f.iter().enumerate().take(px).skip(1) {
        for l in 0..LANES {
            group[2 * (l * px + a)] = fa[0][l];
            group[2 * (l * px + a) + 1] = fa[1][l];
        }
    }
    for l in 0..LANES {
        let left = match l {
            0 => left,
            _ => [f[px][0][l - 1], f[px][1][l - 1]],
        };
        group[2 * l * px] = left[0] + f[0][0][l];
        group[2 * l * px + 1] = left[1] + f[0][1][l];
    }
    group[2 * LANES * px] = f[px][0][LANES - 1];
    group[2 * LANES * px + 1] = f[px][1][LANES - 1];
}

impl Predictor<'_> {
    /// u_next = 2 u - u_prev - a .* (own + lower + k u) on the DOFs `first..`: a node line of
    /// K u (the sum of its force lines, plus the line's `springs`, sorted by DOF) finished as
    /// it is read. A DOF's springs are added in their order after the force lines, as
    /// [`SemModel::stiffness_times`] adds them: bit-identical to it.
    fn finish_sum(
        &self,
        first: usize,
        u: &[f64],
        (own, lower): (&[f64], Option<&[f64]>),
        springs: &[(usize, f64)],
        next: &mut [f64],
    ) {
        let mut start = 0;
        let mut rest = springs;
        while let Some(&(d, _)) = rest.first() {
            let i = d - first;
            self.finish_plain(
                first + start,
                u,
                (&own[start..i], lower.map(|l| &l[start..i])),
                &mut next[start..i],
            );
            let mut ku = match lower {
                None => own[i],
                Some(lower) => own[i] + lower[i],
            };
            let count = rest.iter().take_while(|s| s.0 == d).count();
            for &(_, k) in &rest[..count] {
                ku += k * u[d];
            }
            next[i] = 2.0 * u[d] - self.u_prev[d] - self.a[d] * ku;
            rest = &rest[count..];
            start = i + 1;
        }
        let end = next.len();
        self.finish_plain(
            first + start,
            u,
            (&own[start..], lower.map(|l| &l[start..])),
            &mut next[start..end],
        );
    }

    /// u_next = 2 u - u_prev - a .* (own + lower) on the DOFs `first..` (no springs).
    fn finish_plain(
        &self,
        first: usize,
        u: &[f64],
        (own, lower): (&[f64], Option<&[f64]>),
        next: &mut [f64],
    ) {
        let dofs = first..first + next.len();
        let old = (self.a[dofs.clone()].iter())
            .zip(&self.u_prev[dofs.clone()])
            .zip(&u[dofs]);
        let next = next.iter_mut().zip(old).zip(own);
        match lower {
            None => {
                for ((n, ((&a, &p), &u)), &f) in next {
                    *n = 2.0 * u - p - a * f;
                }
            }
            Some(lower) => {
                for (((n, ((&a, &p), &u)), &f), &l) in next.zip(lower) {
                    *n = 2.0 * u - p - a * (f + l);
                }
            }
        }
    }
}

/// `values` in groups of [`LANES`], the last one padded with 1.
fn lane_groups(values: impl ExactSizeIterator<Item = f64>) -> Vec<Lanes> {
    let mut groups = vec![[1.0; LANES]; values.len().div_ceil(LANES)];
    for (k, v) in values.enumerate() {
        groups[k / LANES][k % LANES] = v;
    }
    groups
}

/// Node coordinates along one axis: each element's GLL points mapped onto it, shared end
/// points once.
fn node_lines<'a>(lines: &[f64], rule: impl Fn(usize) -> &'a Gll) -> Vec<f64> {
    let mut nodes = vec![lines[0]];
    for e in 0..lines.len() - 1 {
        let (a, b) = (lines[e], lines[e + 1]);
        let g = rule(e);
        nodes.extend(
            g.points[1..]
                .iter()
                .map(|&xi| 0.5 * (a + b) + 0.5 * (b - a) * xi),
        );
        *nodes.last_mut().expect("points") = b;
    }
    nodes
}

fn check_lines(name: &str, lines: &[f64]) -> Result<()> {
    if lines.len() < 2
        || lines.iter().any(|v| !v.is_finite())
        || lines.windows(2).any(|w| w[1] <= w[0])
    {
        return Err(Error::invalid(
            name,
            format!("{lines:?}"),
            "needs at least two finite, strictly increasing lines",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
