//! Critical time step of the explicit scheme: dt_crit = 2 / omega_max (report Sec. 4.8.2).

use crate::fem::{element, Model, StiffnessOperator};
use serde::Serialize;

/// Two estimates of the explicit stability limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct StabilityEstimate {
    /// 2 / sqrt(lambda), lambda from power iteration on M^-1 K (Rayleigh quotient). Power
    /// iteration approaches omega_max from below, so this is slightly above the true limit;
    /// it is the number reported as dt_crit.
    pub dt_crit_s: f64,
    /// 2 / sqrt(max over elements of a Gershgorin bound of M_e^-1 K_e): a guaranteed lower
    /// bound of the true limit (element eigenvalue inequality).
    pub dt_element_bound_s: f64,
    /// Power iterations taken.
    pub iterations: usize,
}

/// Largest power iterations.
const MAX_ITERATIONS: usize = 2000;
/// Relative change of the Rayleigh quotient over 20 iterations that counts as converged.
const TOLERANCE: f64 = 1e-7;

/// Estimates the critical step of lumped-mass central difference for `model`.
pub fn estimate(model: &Model) -> StabilityEstimate {
    let (lambda, iterations) = power_iteration(model);
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

/// Power iteration on the symmetric A = M^-1/2 K M^-1/2 over the free DOFs; returns the
/// Rayleigh quotient (an estimate of omega_max^2 from below) and the iterations used.
fn power_iteration(model: &Model) -> (f64, usize) {
    let n = model.dofs();
    let op = StiffnessOperator::new(model);
    let inv_sqrt_m: Vec<f64> = model.lumped_mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let mut free = vec![true; n];
    for &d in &model.fixed_dofs {
        free[d] = false;
    }
    // Deterministic start with components in every mode: a hashed +-1 pattern.
    let mut x: Vec<f64> = (0..n)
        .map(|i| {
            if free[i] {
                if (i.wrapping_mul(2654435761) >> 7) & 1 == 0 {
                    1.0
                } else {
                    -1.0
                }
            } else {
                0.0
            }
        })
        .collect();
    let (mut y, mut scaled) = (vec![0.0; n], vec![0.0; n]);
    let mut history = [0.0f64; 20];
    let mut lambda = 0.0;
    for it in 0..MAX_ITERATIONS {
        normalize(&mut x);
        for i in 0..n {
            scaled[i] = x[i] * inv_sqrt_m[i];
        }
        op.mul(&scaled, &mut y);
        for i in 0..n {
            y[i] = if free[i] { y[i] * inv_sqrt_m[i] } else { 0.0 };
        }
        lambda = x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
        let old = history[it % 20];
        history[it % 20] = lambda;
        if it >= 20 && (lambda - old).abs() <= TOLERANCE * lambda {
            return (lambda, it + 1);
        }
        std::mem::swap(&mut x, &mut y);
    }
    (lambda, MAX_ITERATIONS)
}

fn normalize(x: &mut [f64]) {
    let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
    if norm > 0.0 {
        x.iter_mut().for_each(|v| *v /= norm);
    }
}
