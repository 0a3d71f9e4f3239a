//! Exact solutions of plane orthotropic elastodynamics, against which discretisations are
//! checked (the spectral-element tests and `examples/sem_vs_t3`).

use crate::material::Material;

/// A standing mode of an orthotropic box with rollers on every edge (u_n = 0, no shear
/// traction): u_x = A sin(kx x) cos(ky y), u_y = B cos(kx x) sin(ky y) times cos(omega t),
/// exact for kx = m pi / width, ky = n pi / height, with (A, B) the unit eigenvector of the
/// lower branch of rho omega^2 [A, B] = [[C11 kx^2 + C66 ky^2, (C12 + C66) kx ky],
/// [(C12 + C66) kx ky, C22 ky^2 + C66 kx^2]] [A, B].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RollerMode {
    /// Wavenumber along x (1/m).
    pub kx: f64,
    /// Wavenumber along y (1/m).
    pub ky: f64,
    /// Amplitude of u_x.
    pub a: f64,
    /// Amplitude of u_y.
    pub b: f64,
    /// Angular frequency (rad/s).
    pub omega: f64,
}

impl RollerMode {
    /// The lower-frequency mode of `material` with wavenumbers `kx`, `ky`.
    pub fn new(material: &Material, kx: f64, ky: f64) -> RollerMode {
        let c = &material.stiffness_pa;
        let k11 = c[0][0] * kx * kx + c[2][2] * ky * ky;
        let k12 = (c[0][1] + c[2][2]) * kx * ky;
        let k22 = c[1][1] * ky * ky + c[2][2] * kx * kx;
        let lambda = 0.5 * (k11 + k22) - (0.25 * (k11 - k22).powi(2) + k12 * k12).sqrt();
        let (a, b) = (k12, lambda - k11);
        let n = a.hypot(b);
        RollerMode {
            kx,
            ky,
            a: a / n,
            b: b / n,
            omega: (lambda / material.density_kg_m3).sqrt(),
        }
    }

    /// The mode shape (u_x, u_y) at (x, y), at t = 0.
    pub fn at(&self, x: f64, y: f64) -> [f64; 2] {
        [
            self.a * (self.kx * x).sin() * (self.ky * y).cos(),
            self.b * (self.kx * x).cos() * (self.ky * y).sin(),
        ]
    }
}
