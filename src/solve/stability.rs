//! Critical time step of the explicit scheme: dt_crit = 2 / omega_max (report Sec. 4.8.2).

use crate::fem::{element, Model};
use serde::Serialize;

/// Two estimates of the explicit stability limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StabilityEstimate {
    /// 2 / sqrt(lambda), lambda the largest Ritz value of a Lanczos run on M^-1 K. It
    /// approaches omega_max^2 from below, so this is at or slightly above the true limit;
    /// it is the number reported as dt_crit.
    pub dt_crit_s: f64,
    /// 2 / sqrt(max over elements of a Gershgorin bound of M_e^-1 K_e): a guaranteed lower
    /// bound of the true limit (element eigenvalue inequality).
    pub dt_element_bound_s: f64,
    /// Lanczos iterations taken.
    pub iterations: usize,
}

/// Lanczos iterations: the largest Ritz value converges to omega_max^2 much faster than
/// power iteration (80 matrix products instead of thousands on a dense top spectrum).
const LANCZOS_STEPS: usize = 80;

/// Estimates the critical step of lumped-mass central difference for `model`.
pub fn estimate(model: &Model) -> StabilityEstimate {
    let (lambda, iterations) = lanczos_max_eigenvalue(model);
    StabilityEstimate {
        dt_crit_s: 2.0 / lambda.sqrt(),
        dt_element_bound_s: element_bound(model),
        iterations,
    }
}

fn element_bound(model: &Model) -> f64 {
    let mesh = &model.mesh;
    let omega2 = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(e, &t)| {
            let m = &model.materials[mesh.element_material[e]];
            let k = element::stiffness(t.map(|n| mesh.nodes[n]), &m.stiffness_pa);
            element::omega_squared_bound(
                &k,
                element::lumped_mass(0.5 * mesh.twice_area(t), m.density_kg_m3),
            )
        })
        .fold(0.0, f64::max);
    2.0 / omega2.sqrt()
}

/// Largest eigenvalue of the T3 model's M^-1 K over its free DOFs, see [`lanczos_max_eigenvalue_of`].
fn lanczos_max_eigenvalue(model: &Model) -> (f64, usize) {
    let mut free = vec![true; model.dofs()];
    for &d in &model.fixed_dofs {
        free[d] = false;
    }
    lanczos_max_eigenvalue_of(&model.lumped_mass, &free, |x, y| model.stiffness.mul(x, y))
}

/// Largest eigenvalue of the symmetric A = M^-1/2 K M^-1/2 over the `free` DOFs, for a
/// diagonal `mass` and `stiffness(x, y)` computing y = K x, by Lanczos: the largest Ritz
/// value of the tridiagonal T_k, a lower bound of lambda_max that converges quickly.
/// Returns it and the iterations used. Iteration stops early when the time limit or Ctrl-C
/// stops work ([`crate::budget::check`]); the caller's next check reports it.
pub(crate) fn lanczos_max_eigenvalue_of(
    mass: &[f64],
    free: &[bool],
    stiffness: impl Fn(&[f64], &mut [f64]),
) -> (f64, usize) {
    let n = mass.len();
    let inv_sqrt_m: Vec<f64> = mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let apply = |x: &[f64], scaled: &mut [f64], y: &mut [f64]| {
        for i in 0..n {
            scaled[i] = x[i] * inv_sqrt_m[i];
        }
        stiffness(scaled, y);
        for i in 0..n {
            y[i] = if free[i] { y[i] * inv_sqrt_m[i] } else { 0.0 };
        }
    };
    // Deterministic start with components in every mode: a hashed +-1 pattern.
    let sign = |i: usize| {
        if (i.wrapping_mul(2654435761) >> 7) & 1 == 0 {
            1.0
        } else {
            -1.0
        }
    };
    let mut q: Vec<f64> = (0..n)
        .map(|i| if free[i] { sign(i) } else { 0.0 })
        .collect();
    normalize(&mut q);
    let (mut q_prev, mut w, mut scaled) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut alpha, mut beta) = (
        Vec::with_capacity(LANCZOS_STEPS),
        Vec::with_capacity(LANCZOS_STEPS),
    );
    let mut b_prev = 0.0;
    for _ in 0..LANCZOS_STEPS.min(n) {
        if crate::budget::check().is_err() {
            break;
        }
        apply(&q, &mut scaled, &mut w);
        let a = dot(&w, &q);
        for i in 0..n {
            w[i] -= a * q[i] + b_prev * q_prev[i];
        }
        alpha.push(a);
        let b = dot(&w, &w).sqrt();
        if b <= 1e-12 * a.abs() {
            break;
        }
        beta.push(b);
        for i in 0..n {
            q_prev[i] = q[i];
            q[i] = w[i] / b;
        }
        b_prev = b;
    }
    beta.truncate(alpha.len().saturating_sub(1));
    (tridiagonal_max_eigenvalue(&alpha, &beta), alpha.len())
}

/// Number of eigenvalues below x of the symmetric tridiagonal (diagonal a, off-diagonal b),
/// from the signs of the Sturm sequence q_i = a_i - x - b_{i-1}^2 / q_{i-1}.
fn count_below(a: &[f64], b: &[f64], x: f64) -> usize {
    let mut count = 0;
    let mut q = 1.0;
    for i in 0..a.len() {
        let coupling = if i > 0 { b[i - 1] * b[i - 1] / q } else { 0.0 };
        q = a[i] - x - coupling;
        if q == 0.0 {
            q = f64::MIN_POSITIVE;
        }
        count += (q < 0.0) as usize;
    }
    count
}

/// Largest eigenvalue of a symmetric tridiagonal by bisection between Gershgorin bounds.
fn tridiagonal_max_eigenvalue(a: &[f64], b: &[f64]) -> f64 {
    let radius =
        |i: usize| (if i > 0 { b[i - 1].abs() } else { 0.0 }) + b.get(i).map_or(0.0, |v| v.abs());
    let mut lo = (0..a.len())
        .map(|i| a[i] - radius(i))
        .fold(f64::INFINITY, f64::min);
    let mut hi = (0..a.len())
        .map(|i| a[i] + radius(i))
        .fold(f64::NEG_INFINITY, f64::max);
    while hi - lo > 1e-14 * hi.abs() {
        let mid = 0.5 * (lo + hi);
        if count_below(a, b, mid) == a.len() {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn normalize(x: &mut [f64]) {
    let norm = dot(x, x).sqrt();
    if norm > 0.0 {
        x.iter_mut().for_each(|v| *v /= norm);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tridiagonal_eigenvalue_matches_closed_form() {
        // tridiag(-1, 2, -1) of size n has eigenvalues 2 - 2 cos(k pi / (n + 1)).
        let n = 50;
        let max = tridiagonal_max_eigenvalue(&vec![2.0; n], &vec![-1.0; n - 1]);
        let exact = 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
        assert!((max - exact).abs() < 1e-12, "{max} vs {exact}");
    }
}
