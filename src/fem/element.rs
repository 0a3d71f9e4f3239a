//! The linear triangle (T3) element: stiffness A B^T C B and mass (report Sec. 4.2-4.5).

use nalgebra::{SMatrix, SVector};

/// 6x6 element matrix in DOF order (u_x1, u_y1, u_x2, u_y2, u_x3, u_y3).
pub type ElementMatrix = SMatrix<f64, 6, 6>;

/// Strain-displacement matrix B (3x6) of a T3 and its area: eps = B u_e with
/// B = 1/(2A) [[b1 0 b2 0 b3 0], [0 c1 0 c2 0 c3], [c1 b1 c2 b2 c3 b3]],
/// b_i = y_j - y_k, c_i = x_k - x_j (i, j, k cyclic).
pub fn strain_displacement(x: [[f64; 2]; 3]) -> (SMatrix<f64, 3, 6>, f64) {
    let twice_area =
        (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
    let mut b = SMatrix::<f64, 3, 6>::zeros();
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let bi = (x[j][1] - x[k][1]) / twice_area;
        let ci = (x[k][0] - x[j][0]) / twice_area;
        b[(0, 2 * i)] = bi;
        b[(1, 2 * i + 1)] = ci;
        b[(2, 2 * i)] = ci;
        b[(2, 2 * i + 1)] = bi;
    }
    (b, 0.5 * twice_area)
}

/// Element stiffness K_e = A B^T C B per unit thickness (report eq 40 with constant B).
pub fn stiffness(x: [[f64; 2]; 3], c: &[[f64; 3]; 3]) -> ElementMatrix {
    let (b, area) = strain_displacement(x);
    let c = SMatrix::<f64, 3, 3>::from_fn(|i, j| c[i][j]);
    b.transpose() * c * b * area
}

/// Row `a` of the element stiffness as the three 2x2 blocks (row-major [xx, xy, yx, yy])
/// coupling node `a` to nodes 0, 1, 2: K_ab = A B_a^T C B_b, the same as
/// [`stiffness`] up to round-off, but only the nonzero terms of B (assembly row by row).
pub fn stiffness_row(x: [[f64; 2]; 3], c: &[[f64; 3]; 3], a: usize) -> [[f64; 4]; 3] {
    let twice_area =
        (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
    let area = 0.5 * twice_area;
    // One division instead of six (the results differ from [`stiffness`] in the last bit).
    let inv = 1.0 / twice_area;
    let bc = |i: usize| {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        ((x[j][1] - x[k][1]) * inv, (x[k][0] - x[j][0]) * inv)
    };
    let (ba, ca) = bc(a);
    // G = B_a^T C (2x3): rows x, y of node a.
    let g: [[f64; 3]; 2] = [
        std::array::from_fn(|m| ba * c[0][m] + ca * c[2][m]),
        std::array::from_fn(|m| ca * c[1][m] + ba * c[2][m]),
    ];
    std::array::from_fn(|b| {
        let (bb, cb) = bc(b);
        [
            (g[0][0] * bb + g[0][2] * cb) * area,
            (g[0][1] * cb + g[0][2] * bb) * area,
            (g[1][0] * bb + g[1][2] * cb) * area,
            (g[1][1] * cb + g[1][2] * bb) * area,
        ]
    })
}

/// Consistent mass rho A / 12 [[2 1 1], [1 2 1], [1 1 2]] per direction (report Sec. 4.4).
pub fn consistent_mass(area: f64, density: f64) -> ElementMatrix {
    ElementMatrix::from_fn(|i, j| if i % 2 != j % 2 { 0.0 } else if i == j { 2.0 } else { 1.0 } * density * area / 12.0)
}

/// Row-sum lumped mass per DOF of each node: rho A / 3.
pub fn lumped_mass(area: f64, density: f64) -> f64 {
    density * area / 3.0
}

/// Upper bound of the largest eigenvalue of M_e^-1 K_e with lumped M_e (Gershgorin:
/// the largest absolute row sum of K_e divided by the nodal mass). By the element
/// eigenvalue inequality it bounds omega_max^2 of the assembled lumped system.
pub fn omega_squared_bound(k: &ElementMatrix, nodal_mass: f64) -> f64 {
    (0..6)
        .map(|i| k.row(i).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
        / nodal_mass
}

/// Strain (eps_xx, eps_yy, gamma_xy) of an element for nodal displacements `u`.
pub fn strain(x: [[f64; 2]; 3], u: &SVector<f64, 6>) -> SVector<f64, 3> {
    strain_displacement(x).0 * u
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stiffness_matches_hand_computed_right_triangle() {
        // Unit right triangle (0,0), (1,0), (0,1), isotropic plane strain with E = 1, nu = 0:
        // C = diag(1, 1, 1/2). Then b = (-1, 1, 0), c = (-1, 0, 1), A = 1/2 and
        // B = [[-1 0 1 0 0 0], [0 -1 0 0 0 1], [-1 -1 0 1 1 0]] and K = A B^T C B by hand:
        let c = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]];
        let k = stiffness([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], &c);
        #[rustfmt::skip]
        let hand = [
            [ 0.75,  0.25, -0.5 , -0.25, -0.25,  0.0 ],
            [ 0.25,  0.75,  0.0 , -0.25, -0.25, -0.5 ],
            [-0.5 ,  0.0 ,  0.5 ,  0.0 ,  0.0 ,  0.0 ],
            [-0.25, -0.25,  0.0 ,  0.25,  0.25,  0.0 ],
            [-0.25, -0.25,  0.0 ,  0.25,  0.25,  0.0 ],
            [ 0.0 , -0.5 ,  0.0 ,  0.0 ,  0.0 ,  0.5 ],
        ];
        for i in 0..6 {
            for j in 0..6 {
                assert!(
                    (k[(i, j)] - hand[i][j]).abs() < 1e-15,
                    "K[{i}][{j}] = {} vs {}",
                    k[(i, j)],
                    hand[i][j]
                );
            }
        }
    }

    #[test]
    fn stiffness_row_matches_the_full_matrix() {
        let c = [
            [9.0e9, 3.1e9, 0.2e9],
            [3.1e9, 7.0e9, -0.1e9],
            [0.2e9, -0.1e9, 2.5e9],
        ];
        let x = [[0.1e-3, 0.2e-3], [1.3e-3, 0.4e-3], [0.5e-3, 1.7e-3]];
        let k = stiffness(x, &c);
        for a in 0..3 {
            let row = stiffness_row(x, &c, a);
            for b in 0..3 {
                let full = [
                    k[(2 * a, 2 * b)],
                    k[(2 * a, 2 * b + 1)],
                    k[(2 * a + 1, 2 * b)],
                    k[(2 * a + 1, 2 * b + 1)],
                ];
                for (r, f) in row[b].iter().zip(full) {
                    assert!(
                        (r - f).abs() <= 1e-14 * k.abs().max(),
                        "{a} {b}: {r} vs {f}"
                    );
                }
            }
        }
    }

    #[test]
    fn constant_strain_is_exact() {
        // u = (a x + b y, c x + d y) gives eps = (a, d, b + c) exactly on any triangle.
        let x = [[0.1, 0.2], [1.3, 0.4], [0.5, 1.7]];
        let f = |p: [f64; 2]| [2.0 * p[0] + 3.0 * p[1], -p[0] + 0.5 * p[1]];
        let u = SVector::<f64, 6>::from_iterator(x.iter().flat_map(|&p| f(p)));
        let e = strain(x, &u);
        assert!(
            (e[0] - 2.0).abs() < 1e-14 && (e[1] - 0.5).abs() < 1e-14 && (e[2] - 2.0).abs() < 1e-14
        );
    }

    #[test]
    fn consistent_mass_total_is_rho_area_per_direction() {
        let m = consistent_mass(0.5, 1200.0);
        let total_x: f64 = (0..6)
            .step_by(2)
            .flat_map(|i| (0..6).step_by(2).map(move |j| (i, j)))
            .map(|(i, j)| m[(i, j)])
            .sum();
        assert!((total_x - 600.0).abs() < 1e-12);
        assert!((3.0 * lumped_mass(0.5, 1200.0) - 600.0).abs() < 1e-12);
    }
}
