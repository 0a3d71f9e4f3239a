//! The triangle rasteriser of mesh-field figures: barycentric interpolation at pixel centres.

use super::field::FieldFig;
use super::*;

/// A field sampled at pixel centres (row 0 at the top); `None` outside the mesh.
pub(super) struct Raster {
    pub(super) w: usize,
    pub(super) h: usize,
    pub(super) cells: Vec<Option<f64>>,
}

impl Raster {
    /// Samples the piecewise-linear field of `fig` on a `pw` x `ph` pixel grid spanning
    /// the ranges, by barycentric interpolation inside each triangle.
    pub(super) fn sample(
        fig: &FieldFig,
        (xr, yr): (&Range<f64>, &Range<f64>),
        (pw, ph): (u32, u32),
    ) -> Self {
        let (w, h) = (pw as usize, ph as usize);
        let mut r = Raster {
            w,
            h,
            cells: vec![None; w * h],
        };
        if w == 0 || h == 0 {
            return r;
        }
        let sx = (xr.end - xr.start) / w as f64;
        let sy = (yr.end - yr.start) / h as f64;
        // Pixel (i, j) has its centre at (x0 + (i + 0.5) sx, y1 - (j + 0.5) sy).
        let to_px = move |x: f64, y: f64| ((x - xr.start) / sx - 0.5, (yr.end - y) / sy - 0.5);
        for t in fig.triangles {
            let p = t.map(|k| fig.nodes[k]);
            let v = t.map(|k| fig.values[k]);
            r.fill_triangle(p.map(|q| to_px(q[0], q[1])), v);
        }
        r
    }

    /// Writes interpolated values into the pixels whose centres lie in the triangle
    /// with vertices `p` (in pixel-index coordinates) and vertex values `v`.
    pub(super) fn fill_triangle(&mut self, p: [(f64, f64); 3], v: [f64; 3]) {
        let [(ax, ay), (bx, by), (cx, cy)] = p;
        let det = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
        if det.abs() < 1e-12 {
            return;
        }
        let span = |lo: f64, hi: f64, n: usize| {
            let a = lo.ceil().max(0.0);
            let b = hi.floor().min(n as f64 - 1.0);
            (a as usize)..=(b.max(a - 1.0).max(0.0) as usize)
        };
        let (xlo, xhi) = (ax.min(bx).min(cx), ax.max(bx).max(cx));
        let (ylo, yhi) = (ay.min(by).min(cy), ay.max(by).max(cy));
        if xhi < 0.0 || yhi < 0.0 || xlo > self.w as f64 - 1.0 || ylo > self.h as f64 - 1.0 {
            return;
        }
        let tol = -1e-9;
        for j in span(ylo, yhi, self.h) {
            for i in span(xlo, xhi, self.w) {
                let (x, y) = (i as f64, j as f64);
                let l1 = ((bx - x) * (cy - y) - (cx - x) * (by - y)) / det;
                let l2 = ((cx - x) * (ay - y) - (ax - x) * (cy - y)) / det;
                let l3 = 1.0 - l1 - l2;
                if l1 >= tol && l2 >= tol && l3 >= tol {
                    self.cells[j * self.w + i] = Some(l1 * v[0] + l2 * v[1] + l3 * v[2]);
                }
            }
        }
    }
}
