//! Exact solutions of plane orthotropic elastodynamics, against which discretisations are
//! checked (the spectral-element tests, `examples/sem_vs_t3`, `tests/normal_incidence.rs` and
//! `tests/hole_scattering.rs`).

use crate::error::{require_positive, Error, Result};
use crate::laminate::Laminate;
use crate::material::Material;
use crate::signal::{causal_response, Signal};
use rustfft::num_complex::Complex64;

pub mod hole;
pub mod oblique;

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

/// One homogeneous layer of a [`NormalIncidence`] stack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StackLayer {
    /// Density rho (kg/m^3).
    pub density_kg_m3: f64,
    /// P-wave modulus across the layers, C22 = `stiffness_pa[1][1]` (Pa).
    pub modulus_pa: f64,
    /// Thickness h (m).
    pub thickness_m: f64,
}

impl StackLayer {
    /// The layer of `material` (its C22 across the layers), `thickness_m` thick.
    pub fn new(material: &Material, thickness_m: f64) -> StackLayer {
        StackLayer {
            density_kg_m3: material.density_kg_m3,
            modulus_pa: material.stiffness_pa[1][1],
            thickness_m,
        }
    }

    /// Impedance Z = rho c = sqrt(rho C22) (Pa s/m).
    pub fn impedance(&self) -> f64 {
        (self.density_kg_m3 * self.modulus_pa).sqrt()
    }

    /// Slowness 1 / c = sqrt(rho / C22) (s/m).
    pub fn slowness(&self) -> f64 {
        (self.density_kg_m3 / self.modulus_pa).sqrt()
    }

    /// The propagator (N2) applied to the state (V, Sigma) at depth z: the state at z + `h`
    /// in this material at (complex) angular frequency `omega`; `h` < 0 goes up.
    fn propagate(&self, omega: Complex64, h: f64, [v, sigma]: [Complex64; 2]) -> [Complex64; 2] {
        let z = self.impedance();
        let i = Complex64::i();
        // cos kh and sin kh from one exponential e^(i kh).
        let e = (i * omega * self.slowness() * h).exp();
        let (cos, sin) = (0.5 * (e + 1.0 / e), -0.5 * i * (e - 1.0 / e));
        [
            cos * v - i * sin / z * sigma,
            -i * z * sin * v + cos * sigma,
        ]
    }
}

/// Plane P waves at normal incidence through a stack of layers over a half-space of the last
/// layer's material (impedance-matched: nothing comes back from below the stack), driven by a
/// uniform pressure p(t) on the top surface. Exact for the 1-D continuum: the strip with
/// roller sides and an absorbing bottom that `tests/normal_incidence.rs` discretises, where
/// this solution is also checked against closed forms (a delayed copy in a homogeneous stack,
/// the interface coefficients) and the energy balance of a lossless stack.
///
/// With z the depth below the top, v the particle velocity along y (up) and sigma = sigma_yy,
/// the equations rho dv/dt = -d sigma/dz and d sigma/dt = -C22 dv/dz, Fourier transformed
/// (F(omega) = int f(t) e^(-i omega t) dt), read
///
/// (N1) d/dz [V; Sigma] = [[0, -i omega / C22], [-i omega rho, 0]] [V; Sigma],
///
/// whose matrix squares to -k^2 I (k = omega / c, c = sqrt(C22 / rho), Z = rho c). Across a
/// layer of thickness h, from its top to its bottom (h < 0: from its bottom to its top),
///
/// (N2) [V; Sigma](z + h) = [[cos kh, -i sin kh / Z], [-i Z sin kh, cos kh]] [V; Sigma](z).
///
/// Below the stack (depth H, impedance Z_b) only a down-going wave V e^(i(omega t - kz))
/// exists, for which i omega Sigma = -C22 dV/dz gives
///
/// (N3) Sigma(H) = Z_b V(H),
///
/// and the load is a pressure: the traction on the top surface is -p along y, so
///
/// (N4) Sigma(0) = -P.
///
/// The state of unit V(H), [1; Z_b] by (N3), carried up to each depth by (N2) is s_1(z); the
/// solution is a multiple of it fixed by (N4):
///
/// (N5) V(d) / P = -V_1(d) / Sigma_1(0).
///
/// Walking up from the bottom is stable where the stack is opaque (a band gap): the wave the
/// stack lets through is smallest at the bottom and grows upwards with s_1, so no growing
/// part is cancelled against a decaying one. For a homogeneous stack, V(d) = -P e^(-ikd) /
/// Z: a pressure pulse sends the surface down (v < 0) at p / Z, delayed by d / c at depth d.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalIncidence {
    /// Layers from the top surface down; the last one's material continues below the stack.
    layers: Vec<StackLayer>,
    /// Depth of each layer's bottom (m).
    bottoms_m: Vec<f64>,
}

impl NormalIncidence {
    /// The stack of `layers_top_down`; errors on an empty stack or a non-positive density,
    /// modulus or thickness.
    pub fn new(layers_top_down: Vec<StackLayer>) -> Result<NormalIncidence> {
        if layers_top_down.is_empty() {
            return Err(Error::invalid("layers", "[]", "needs at least one layer"));
        }
        for (i, l) in layers_top_down.iter().enumerate() {
            require_positive(&format!("layers[{i}].density_kg_m3"), l.density_kg_m3)?;
            require_positive(&format!("layers[{i}].modulus_pa"), l.modulus_pa)?;
            require_positive(&format!("layers[{i}].thickness_m"), l.thickness_m)?;
        }
        let bottoms_m = layers_top_down
            .iter()
            .scan(0.0, |depth, l| {
                *depth += l.thickness_m;
                Some(*depth)
            })
            .collect();
        Ok(NormalIncidence {
            layers: layers_top_down,
            bottoms_m,
        })
    }

    /// The stack of a laminate (its layers are listed bottom-up), over a half-space of its
    /// bottom layer's material.
    pub fn of_laminate(laminate: &Laminate) -> Result<NormalIncidence> {
        let layers = laminate
            .layers
            .iter()
            .rev()
            .map(|l| StackLayer::new(&laminate.materials[l.material], l.thickness_m))
            .collect();
        NormalIncidence::new(layers)
    }

    /// The layers from the top surface down.
    pub fn layers(&self) -> &[StackLayer] {
        &self.layers
    }

    /// Depth H of the stack's bottom (m).
    pub fn height_m(&self) -> f64 {
        self.bottoms_m[self.bottoms_m.len() - 1]
    }

    /// The half-space below the stack (its thickness is that of the last layer, unused).
    pub fn half_space(&self) -> &StackLayer {
        &self.layers[self.layers.len() - 1]
    }

    /// H(omega, d) = V(d) / P, the velocity at `depth_m` (in the half-space if below the
    /// stack) per unit pressure on the top at (complex) angular frequency `omega`: (N5), one
    /// walk up from the bottom.
    pub fn velocity_per_pressure(&self, omega: Complex64, depth_m: f64) -> Complex64 {
        let half_space = self.half_space();
        let mut state = [
            Complex64::new(1.0, 0.0),
            Complex64::new(half_space.impedance(), 0.0),
        ];
        let mut at_depth = (depth_m >= self.height_m())
            .then(|| half_space.propagate(omega, depth_m - self.height_m(), state)[0]);
        for (layer, &bottom) in self.layers.iter().zip(&self.bottoms_m).rev() {
            let top = bottom - layer.thickness_m;
            if at_depth.is_none() && depth_m >= top {
                at_depth = Some(layer.propagate(omega, depth_m - bottom, state)[0]);
            }
            state = layer.propagate(omega, -layer.thickness_m, state);
        }
        -at_depth.unwrap_or(state[0]) / state[1]
    }

    /// The particle velocity v_y(t) at `depth_m` below the top (in the half-space if below the
    /// stack) for the pressure `pressure` (Pa) on the top surface, zero outside its samples,
    /// on its time grid: (N5) on the FFT grid at complex frequency ([`causal_response`],
    /// wrap-around below 1e-12 of the largest velocity).
    pub fn velocity(&self, pressure: &Signal, depth_m: f64) -> Result<Signal> {
        if !(depth_m.is_finite() && depth_m >= 0.0) {
            return Err(Error::invalid(
                "depth_m",
                depth_m,
                "must be finite and >= 0",
            ));
        }
        Ok(causal_response(pressure, |omega| {
            self.velocity_per_pressure(omega, depth_m)
        })?)
    }
}
