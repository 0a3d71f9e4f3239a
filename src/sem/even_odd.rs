//! The even-odd decomposition of a GLL derivative matrix (Solomonoff, "A fast algorithm for
//! spectral differentiation", J. Comput. Phys. 1992; deal.II's sum-factorisation kernels use
//! it, `EvaluatorTensorProduct<evaluate_evenodd>`): the points are symmetric about
//! the element centre, so D[n-1-a][n-1-k] = -D[a][k], and with the sums and differences of
//! mirrored values, e_k = v_k + v_{n-1-k}, o_k = v_k - v_{n-1-k} (k < h = n / 2),
//!
//!   E_a = sum_k P[a][k] e_k + D[a][h] v_h,   O_a = sum_k Q[a][k] o_k,
//!   (D v)_a = E_a + O_a,   (D v)_{n-1-a} = O_a - E_a,
//!
//! with P = (D[a][k] + D[a][n-1-k]) / 2, Q = (D[a][k] - D[a][n-1-k]) / 2, the middle term
//! D[a][h] v_h only for odd n, and at the middle point itself (odd n) (D v)_h = O_h. A
//! derivative of n values then costs about n^2 / 2 multiplications instead of n^2. The
//! transposed matrix has the same symmetry, so the same code applies D^T.
//!
//! Results differ from the plain product by round-off only (the symmetry of the computed D
//! holds to round-off); the operations are fixed, so they do not depend on the thread count
//! or the instruction set.

use super::{Lanes, LANES};

/// Largest half size n / 2 (rounded down), n <= MAX_ORDER + 1 = 17 points.
const MAX_HALF: usize = super::MAX_ORDER.div_ceil(2);

/// P, Q and the middle column of an n x n matrix with D[n-1-a][n-1-k] = -D[a][k].
#[derive(Clone, Debug, PartialEq)]
pub(super) struct EvenOdd {
    /// Number of points n.
    n: usize,
    /// P[a][k] for a < (n + 1) / 2, k < n / 2.
    even: [[f64; MAX_HALF]; MAX_HALF + 1],
    /// Q[a][k], same shape.
    odd: [[f64; MAX_HALF]; MAX_HALF + 1],
    /// D[a][n / 2] for odd n (zero for even n).
    middle: [f64; MAX_HALF + 1],
}

impl EvenOdd {
    /// The decomposition of `matrix` (n x n, n <= MAX_ORDER + 1, rows of `matrix[a]`).
    pub(super) fn new(matrix: &[Vec<f64>]) -> EvenOdd {
        let n = matrix.len();
        assert!(n <= 2 * MAX_HALF + 1, "{n} points: above MAX_ORDER + 1");
        let h = n / 2;
        let mut m = EvenOdd {
            n,
            even: [[0.0; MAX_HALF]; MAX_HALF + 1],
            odd: [[0.0; MAX_HALF]; MAX_HALF + 1],
            middle: [0.0; MAX_HALF + 1],
        };
        for (a, row) in matrix.iter().enumerate().take(n.div_ceil(2)) {
            for k in 0..h {
                let (d, mirrored) = (row[k], row[n - 1 - k]);
                m.even[a][k] = 0.5 * (d + mirrored);
                m.odd[a][k] = 0.5 * (d - mirrored);
            }
            if n % 2 == 1 {
                m.middle[a] = row[h];
            }
        }
        m
    }

    /// The transposed matrix's decomposition.
    pub(super) fn transposed(matrix: &[Vec<f64>]) -> EvenOdd {
        let n = matrix.len();
        let t: Vec<Vec<f64>> = (0..n)
            .map(|a| (0..n).map(|k| matrix[k][a]).collect())
            .collect();
        EvenOdd::new(&t)
    }

    /// `out[a] = sum_k D[a][k] v[k]` across the lanes, for the `N` values of `v` (n = N,
    /// a compile-time size: along x).
    #[inline(always)]
    pub(super) fn apply<const N: usize>(&self, v: &[Lanes]) -> [Lanes; N] {
        debug_assert_eq!(self.n, N, "the decomposition's size");
        let v: &[Lanes; N] = v[..N].try_into().expect("N values");
        let h = N / 2;
        let (mut e, mut o) = ([[0.0; LANES]; N], [[0.0; LANES]; N]);
        for k in 0..h {
            for l in 0..LANES {
                e[k][l] = v[k][l] + v[N - 1 - k][l];
                o[k][l] = v[k][l] - v[N - 1 - k][l];
            }
        }
        let mut out = [[0.0; LANES]; N];
        for a in 0..N.div_ceil(2) {
            let (mut even, mut odd) = ([0.0; LANES], [0.0; LANES]);
            for k in 0..h {
                let (p, q) = (self.even[a][k], self.odd[a][k]);
                for l in 0..LANES {
                    even[l] += p * e[k][l];
                    odd[l] += q * o[k][l];
                }
            }
            let (low, high) = self.outputs(a, even, odd, &v[h]);
            out[a] = low;
            out[N - 1 - a] = high;
        }
        out
    }

    /// `out[b * N + a] = sum_k D[b][k] v[k * N + a]` across the lanes: the derivative across
    /// the n lines of N points each of `v` (n = self's size, known at run time: across a
    /// row). `scratch` holds the lines' sums and differences.
    #[inline(always)]
    pub(super) fn apply_across<const N: usize>(
        &self,
        v: &[Lanes],
        scratch: &mut [Lanes],
        out: &mut [Lanes],
    ) {
        let (n, h) = (self.n, self.n / 2);
        let v = &v[..n * N];
        let (e, o) = scratch[..2 * h * N].split_at_mut(h * N);
        for k in 0..h {
            let (low, high) = (&v[k * N..][..N], &v[(n - 1 - k) * N..][..N]);
            let (e, o) = (&mut e[k * N..][..N], &mut o[k * N..][..N]);
            for a in 0..N {
                for l in 0..LANES {
                    e[a][l] = low[a][l] + high[a][l];
                    o[a][l] = low[a][l] - high[a][l];
                }
            }
        }
        let out = &mut out[..n * N];
        for b in 0..n.div_ceil(2) {
            let (p, q) = (&self.even[b][..h], &self.odd[b][..h]);
            for a in 0..N {
                let (mut even, mut odd) = ([0.0; LANES], [0.0; LANES]);
                for k in 0..h {
                    let (ek, ok) = (&e[k * N + a], &o[k * N + a]);
                    for l in 0..LANES {
                        even[l] += p[k] * ek[l];
                        odd[l] += q[k] * ok[l];
                    }
                }
                let (low, high) = self.outputs(b, even, odd, &v[h * N + a]);
                out[b * N + a] = low;
                out[(n - 1 - b) * N + a] = high;
            }
        }
    }

    /// Outputs a and n-1-a, (E + O, O - E), from the even sum (to which the middle term
    /// D[a][h] v_h is added for odd n) and the odd one; at the middle point (odd n) both are
    /// O alone.
    #[inline(always)]
    fn outputs(&self, a: usize, mut even: Lanes, odd: Lanes, middle: &Lanes) -> (Lanes, Lanes) {
        if 2 * a + 1 == self.n {
            return (odd, odd);
        }
        if self.n % 2 == 1 {
            for l in 0..LANES {
                even[l] += self.middle[a] * middle[l];
            }
        }
        let (mut low, mut high) = ([0.0; LANES], [0.0; LANES]);
        for l in 0..LANES {
            low[l] = even[l] + odd[l];
            high[l] = odd[l] - even[l];
        }
        (low, high)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sem::gll::Gll;

    /// Both applications against the plain product sum_k D[a][k] v[k], D and D^T, for every
    /// point count 2..=17 (odd and even), on values that differ per point and per lane:
    /// equal to round-off, 1e-13 relative to the largest |D| |v| sum.
    #[test]
    fn even_odd_products_match_the_plain_product() {
        fn check<const N: usize>() {
            let g = Gll::new(N - 1);
            let t: Vec<Vec<f64>> = (0..N)
                .map(|a| (0..N).map(|k| g.derivative[k][a]).collect())
                .collect();
            for (matrix, decomposed) in [
                (&g.derivative, EvenOdd::new(&g.derivative)),
                (&t, EvenOdd::transposed(&g.derivative)),
            ] {
                let value =
                    |k: usize, l: usize| ((k * 7 + l * 3) as f64 * 0.37).sin() + 0.1 * l as f64;
                let v: Vec<Lanes> = (0..N)
                    .map(|k| std::array::from_fn(|l| value(k, l)))
                    .collect();
                let plain =
                    |a: usize, l: usize| (0..N).map(|k| matrix[a][k] * v[k][l]).sum::<f64>();
                let scale: f64 = (0..N * LANES)
                    .map(|p| {
                        (0..N)
                            .map(|k| (matrix[p / LANES][k] * v[k][p % LANES]).abs())
                            .sum::<f64>()
                    })
                    .fold(0.0, f64::max);
                let along = decomposed.apply::<N>(&v);
                // across: n lines of N points, line k holding v[k] at every point
                let lines: Vec<Lanes> = (0..N * N).map(|p| v[p / N]).collect();
                let (mut scratch, mut across) =
                    (vec![[0.0; LANES]; N * N], vec![[0.0; LANES]; N * N]);
                decomposed.apply_across::<N>(&lines, &mut scratch, &mut across);
                for a in 0..N {
                    for l in 0..LANES {
                        let expected = plain(a, l);
                        assert!(
                            (along[a][l] - expected).abs() <= 1e-13 * scale,
                            "n {N}, a {a}"
                        );
                        for i in 0..N {
                            let got = across[a * N + i][l];
                            assert!((got - expected).abs() <= 1e-13 * scale, "n {N}, across {a}");
                        }
                    }
                }
            }
        }
        macro_rules! sizes {
            ($($n:literal)*) => { $(check::<$n>();)* };
        }
        sizes!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
    }
}
