//! Gauss-Lobatto-Legendre (GLL) points, weights and the Lagrange derivative matrix on
//! [-1, 1]: the 1-D building block of the spectral elements.
//!
//! Written here rather than taken from a quadrature crate because the spectral element needs
//! the three together, for orders up to ~16, and the crates offer the rule without the
//! derivative matrix. Algorithm: Newton's method on `(1 - x^2) P_N'(x)` from the
//! Chebyshev-Gauss-Lobatto points, with the Legendre recurrence (Kopriva, *Implementing
//! Spectral Methods for PDEs*, 2009, algorithms 22-25; Canuto et al. 2006, eq. 2.3.12).

/// The N+1 GLL points of order N, ascending, with their weights and derivative matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Gll {
    /// Points x_0 = -1 < ... < x_N = 1.
    pub points: Vec<f64>,
    /// Weights w_i = 2 / (N (N + 1) P_N(x_i)^2); exact for polynomials of degree <= 2N - 1.
    pub weights: Vec<f64>,
    /// `derivative[i][j]` = l_j'(x_i), the derivative of the j-th Lagrange polynomial at x_i,
    /// so that (du/dx)(x_i) = sum_j derivative[i][j] u(x_j) exactly for degree <= N.
    pub derivative: Vec<Vec<f64>>,
}

/// Legendre P_N(x) and P_{N-1}(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p_prev, mut p) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let next = ((2.0 * k - 1.0) * x * p - (k - 1.0) * p_prev) / k;
        p_prev = p;
        p = next;
    }
    (p, p_prev)
}

impl Gll {
    /// The GLL rule of order `n` (n + 1 points), `n >= 1`.
    pub fn new(n: usize) -> Gll {
        assert!(n >= 1, "GLL order must be at least 1");
        let nf = n as f64;
        let mut points: Vec<f64> = (0..=n)
            .map(|i| -(std::f64::consts::PI * i as f64 / nf).cos())
            .collect();
        // Newton on q(x) = P_N(x) x - P_{N-1}(x), whose roots are the GLL points
        // (q = (1 - x^2) P_N' / N, and q' = (N + 1) P_N).
        for x in points.iter_mut().take(n).skip(1) {
            for _ in 0..100 {
                let (p, p_prev) = legendre(n, *x);
                let step = (*x * p - p_prev) / ((nf + 1.0) * p);
                *x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
        }
        points[0] = -1.0;
        points[n] = 1.0;
        let p_n: Vec<f64> = points.iter().map(|&x| legendre(n, x).0).collect();
        let weights = p_n
            .iter()
            .map(|p| 2.0 / (nf * (nf + 1.0) * p * p))
            .collect();
        let mut derivative = vec![vec![0.0; n + 1]; n + 1];
        for i in 0..=n {
            for j in 0..=n {
                if i != j {
                    derivative[i][j] = p_n[i] / (p_n[j] * (points[i] - points[j]));
                }
            }
        }
        derivative[0][0] = -nf * (nf + 1.0) / 4.0;
        derivative[n][n] = nf * (nf + 1.0) / 4.0;
        Gll {
            points,
            weights,
            derivative,
        }
    }

    /// The order N.
    pub fn order(&self) -> usize {
        self.points.len() - 1
    }

    /// Values l_j(x) of the Lagrange polynomials at `x` in [-1, 1] (barycentric form). An `x`
    /// within a few ulp of a GLL point (the round-off of mapping a node's coordinate onto the
    /// reference element) is that point: l_k = 1, the others 0.
    pub fn lagrange_at(&self, x: f64) -> Vec<f64> {
        let n = self.order();
        if let Some(k) = self
            .points
            .iter()
            .position(|&p| (p - x).abs() <= 8.0 * f64::EPSILON)
        {
            let mut l = vec![0.0; n + 1];
            l[k] = 1.0;
            return l;
        }
        // barycentric weights 1 / prod_{k != j} (x_j - x_k)
        let bary: Vec<f64> = (0..=n)
            .map(|j| {
                1.0 / (0..=n)
                    .filter(|&k| k != j)
                    .map(|k| self.points[j] - self.points[k])
                    .product::<f64>()
            })
            .collect();
        let terms: Vec<f64> = (0..=n).map(|j| bary[j] / (x - self.points[j])).collect();
        let sum: f64 = terms.iter().sum();
        terms.iter().map(|t| t / sum).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Order 4: points 0, +-sqrt(3/7), +-1 and weights 1/10, 49/90, 32/45 (Abramowitz and
    /// Stegun 25.4.32, the 5-point Lobatto rule).
    #[test]
    fn order_four_matches_the_tabulated_rule() {
        let g = Gll::new(4);
        let s = (3.0f64 / 7.0).sqrt();
        let expected_points = [-1.0, -s, 0.0, s, 1.0];
        let expected_weights = [0.1, 49.0 / 90.0, 32.0 / 45.0, 49.0 / 90.0, 0.1];
        for i in 0..5 {
            assert!(
                (g.points[i] - expected_points[i]).abs() < 1e-15,
                "{:?}",
                g.points
            );
            assert!(
                (g.weights[i] - expected_weights[i]).abs() < 1e-15,
                "{:?}",
                g.weights
            );
        }
    }

    /// The rule of order N integrates x^k exactly for k <= 2N - 1 and not for k = 2N (its
    /// error there falls like 4^-N, to ~1e-10 at N = 16).
    #[test]
    fn quadrature_is_exact_to_degree_2n_minus_1() {
        for n in 1..=16 {
            let g = Gll::new(n);
            let integrate = |k: i32| -> f64 {
                g.points
                    .iter()
                    .zip(&g.weights)
                    .map(|(x, w)| w * x.powi(k))
                    .sum()
            };
            for k in 0..=(2 * n as i32 - 1) {
                let exact = if k % 2 == 0 {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                assert!((integrate(k) - exact).abs() < 1e-13, "n {n} k {k}");
            }
            let k = 2 * n as i32;
            assert!(
                (integrate(k) - 2.0 / (k as f64 + 1.0)).abs() > 1e-12,
                "n {n}"
            );
        }
    }

    /// The derivative matrix differentiates polynomials of degree <= N exactly; Lagrange
    /// values at a point reproduce them.
    #[test]
    fn derivative_and_interpolation_are_exact_for_degree_n() {
        for n in 1..=16 {
            let g = Gll::new(n);
            let f = |x: f64| x.powi(n as i32) - 0.5 * x + 0.25;
            let df = |x: f64| n as f64 * x.powi(n as i32 - 1) - 0.5;
            let values: Vec<f64> = g.points.iter().map(|&x| f(x)).collect();
            for i in 0..=n {
                let d: f64 = (0..=n).map(|j| g.derivative[i][j] * values[j]).sum();
                assert!(
                    (d - df(g.points[i])).abs() < 1e-10 * n as f64 * n as f64,
                    "n {n} i {i}"
                );
            }
            let x = 0.3141;
            let v: f64 = g
                .lagrange_at(x)
                .iter()
                .zip(&values)
                .map(|(l, u)| l * u)
                .sum();
            assert!((v - f(x)).abs() < 1e-12, "n {n}");
        }
    }
}
