//! Oblique incidence: plane-strain waves of one wavenumber k along x through a stack of
//! orthotropic layers (material axes along x and y) on a clamped bottom, driven by a normal
//! traction -p(t) cos(k x) on the free top. Exact for the strip 0 <= x <= W, k = n pi / W,
//! with rollers on its sides, which `tests/oblique_incidence.rs` discretises; there this
//! solution is also checked against closed forms (the clamped rod's reflections at k -> 0,
//! a homogeneous layer against the isotropic half-space until the bottom's reflection
//! returns, the orthotropic roller modes [`super::RollerMode`]) and reciprocity.
//!
//! # The field
//!
//! With y up, a layer's plane-strain stresses are sigma_xx = C11 e_xx + C12 e_yy, sigma_yy =
//! C12 e_xx + C22 e_yy, sigma_xy = C66 (du_x/dy + du_y/dx) (C = `Material::stiffness_pa`,
//! C16 = C26 = 0). The field
//!
//! (O1) u_x = U_x(y) sin(k x), u_y = U_y(y) cos(k x), sigma_xy = S_xy(y) sin(k x),
//!      sigma_yy = S_yy(y) cos(k x), sigma_xx = S_xx(y) cos(k x)
//!
//! has u_x = 0 and sigma_xy = 0 on x = 0 and x = W for k = n pi / W (rollers), so the strip
//! with rollers carries it exactly. Fourier transformed in time (F(omega) = int f(t)
//! e^(-i omega t) dt, so d^2/dt^2 -> -omega^2; m = rho omega^2), the stresses give
//! S_xx = C11 k U_x + C12 U_y', S_yy = C12 k U_x + C22 U_y', S_xy = C66 (U_x' - k U_y), and
//! the equations of motion d sigma_xx/dx + d sigma_xy/dy = -m u_x and d sigma_xy/dx +
//! d sigma_yy/dy = -m u_y give S_xy' = k S_xx - m U_x and S_yy' = -k S_xy - m U_y. Eliminating
//! U_y' = (S_yy - C12 k U_x) / C22 from S_xx = k Cb U_x + r S_yy (r = C12 / C22, Cb = C11 -
//! C12^2 / C22), the state s = (U_x, U_y, S_xy, S_yy) of displacements and tractions on
//! horizontal planes, continuous across the interfaces, obeys
//!
//! (O2) s' = A s,  A = [[0,            k,  1 / C66, 0      ],
//!                      [-k r,         0,  0,       1 / C22],
//!                      [k^2 Cb - m,   0,  0,       k r    ],
//!                      [0,            -m, -k,      0      ]].
//!
//! At k = 0 it splits into the 1-D P wave (U_y, S_yy) of [`super::NormalIncidence`] and an
//! unexcited S wave. (O2) is the Euler-Lagrange equation of the x-averaged Lagrangian
//! [C11 (k U_x)^2 + 2 C12 k U_x U_y' + C22 U_y'^2 + C66 (U_x' - k U_y)^2 - m (U_x^2 + U_y^2)] / 4,
//! whose boundary term pairs S_xy with U_x and S_yy with U_y: the stack's compliance is
//! symmetric (reciprocity).
//!
//! # A layer
//!
//! A couples g1 = (U_x, S_yy) to g2 = (U_y, S_xy) only: g1' = B g2, g2' = D g1 with
//! B = [[k, 1 / C66], [-m, -k]], D = [[-k r, 1 / C22], [k^2 Cb - m, k r]], so A^2 =
//! diag(BD, DB) and the propagator over a height h (from y to y + h), e^(A h), is
//!
//! (O3) g1(y + h) = Ch(BD) g1 + S(BD) B g2,  g2(y + h) = S(DB) D g1 + Ch(DB) g2,
//!
//! with Ch(mu) = cosh(sqrt(mu) h), S(mu) = sinh(sqrt(mu) h) / sqrt(mu), both entire in mu
//! (even in sqrt(mu): no branch to choose). BD and DB share the eigenvalues mu_1, mu_2 (the
//! squares of the layer's vertical wavenumbers times -1: P and S waves, propagating or
//! evanescent), and a function of a 2x2 matrix M with them is (Sylvester)
//!
//! (O4) f(M) = (f(mu_1) + f(mu_2)) / 2 I + f[mu_1, mu_2] (M - (mu_1 + mu_2) / 2 I),
//!
//! f[.,.] the divided difference, computed without cancellation (`divided_differences`):
//! with a = sqrt(mu_1) h, b = sqrt(mu_2) h, Ch[mu_1, mu_2] = h^2 / 2 shc((a + b) / 2)
//! shc((a - b) / 2), shc z = sinh z / z; S's by its series where a and b are small and by a
//! midpoint form where they are close.
//!
//! # The stack
//!
//! The bottom is clamped, U(0) = 0, and the top carries the traction (S_xy, S_yy) = (0, -P).
//! Multiplying layer propagators from the bottom up would grow the evanescent waves as
//! e^(kappa H) and cancel them against the decaying ones: kappa reaches 3.7 k in the 0/90
//! plies (sqrt(C11 / C66) = 3.8), so across the 50-pair laminate (H = 11.6 mm) at k = pi /
//! 4 mm, about e^15, seven digits lost. Instead the stack is walked up by the compliance G of
//! what lies below each interface, U = G S (U = (U_x, U_y), S = (S_xy, S_yy)): G = 0 at the
//! clamped bottom, and across a layer whose propagator (O3) has the blocks P_uu, P_us, P_su,
//! P_ss,
//!
//! (O5) S_below = N S_above, N = (P_su G + P_ss)^(-1),  G_above = (P_uu G + P_us) N,
//!
//! which only ever applies one layer's propagator (growth at most e^(3.7 k h) = e^0.9 in the
//! thickest ply, k h = 0.25 at W = 4 mm) and carries the bottom condition up exactly. The
//! traction at a receiver is the top's carried down by the layers' N (a product built on the
//! way up, so no walk back down), its displacement G S there, and its velocity i omega U.
//!
//! The clamped stack is closed and lossless: every transfer function has poles on the real
//! axis (its standing modes), so it is evaluated at complex frequency omega - i eta, the
//! exponential window of [`causal_response`] (Kausel and Roesset 1992): eta T = ln(1e12) on
//! the transform's period T (four records), so the periodic wrap-around is at most 1e-12 of
//! the largest velocity the stack ever carries. Lossless, it never rings down, but neither
//! does it grow: after the load its energy stays that of the record, so 1e-12 of its peak
//! bounds the wrap-around over the record too. FFT round-off (1e-16) grows by e^(eta t) <=
//! 1e3 towards the record's end, 1e-13.

use crate::error::{require_positive, Error, Result};
use crate::laminate::Laminate;
use crate::material::Material;
use crate::signal::{causal_response, Signal};
use rayon::prelude::*;
use rustfft::num_complex::Complex64;
use std::cell::{Cell, RefCell};

type Mat2 = [[Complex64; 2]; 2];

/// One homogeneous orthotropic layer of an [`ObliqueIncidence`] stack: its plane-strain
/// stiffness with the material axes along x and y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrthotropicLayer {
    /// Density rho (kg/m^3).
    pub density_kg_m3: f64,
    /// C11, along x (Pa).
    pub c11_pa: f64,
    /// C12 (Pa).
    pub c12_pa: f64,
    /// C22, across the layers (Pa).
    pub c22_pa: f64,
    /// C66, the shear modulus (Pa).
    pub c66_pa: f64,
    /// Thickness h (m).
    pub thickness_m: f64,
}

impl OrthotropicLayer {
    /// The layer of the plane `material`, `thickness_m` thick; errors on a material whose axes
    /// are not along x and y (C16 or C26 not zero), or a non-positive density, C22, C66 or
    /// thickness.
    pub fn new(material: &Material, thickness_m: f64) -> Result<OrthotropicLayer> {
        let c = &material.stiffness_pa;
        if c[0][2] != 0.0 || c[1][2] != 0.0 || c[2][0] != 0.0 || c[2][1] != 0.0 {
            return Err(Error::invalid(
                "material",
                &material.name,
                "its axes are not along x and y (C16 or C26 is not 0)",
            ));
        }
        let layer = OrthotropicLayer {
            density_kg_m3: material.density_kg_m3,
            c11_pa: c[0][0],
            c12_pa: c[0][1],
            c22_pa: c[1][1],
            c66_pa: c[2][2],
            thickness_m,
        };
        layer.check("layer")?;
        Ok(layer)
    }

    fn check(&self, name: &str) -> Result<()> {
        require_positive(&format!("{name}.density_kg_m3"), self.density_kg_m3)?;
        require_positive(&format!("{name}.c22_pa"), self.c22_pa)?;
        require_positive(&format!("{name}.c66_pa"), self.c66_pa)?;
        require_positive(&format!("{name}.thickness_m"), self.thickness_m)?;
        if !(self.c11_pa.is_finite() && self.c12_pa.is_finite()) {
            return Err(Error::invalid(
                format!("{name}.c11_pa, c12_pa"),
                format!("{}, {}", self.c11_pa, self.c12_pa),
                "must be finite",
            ));
        }
        Ok(())
    }

    /// The propagator e^(A h) of (O2)-(O4) at wavenumber `k` (1/m) and (complex) angular
    /// frequency `omega`: the state (U_x, U_y, S_xy, S_yy) at y + `h` from the state at y
    /// (`h` < 0 goes down).
    pub fn propagator(&self, k: f64, omega: Complex64, h: f64) -> [[Complex64; 4]; 4] {
        let blocks = self.group_propagator(k, omega, h);
        // (group, component) of U_x, U_y, S_xy, S_yy: g1 = (U_x, S_yy), g2 = (U_y, S_xy).
        const AT: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];
        let mut p = [[Complex64::new(0.0, 0.0); 4]; 4];
        for (i, &(gi, ci)) in AT.iter().enumerate() {
            for (j, &(gj, cj)) in AT.iter().enumerate() {
                p[i][j] = blocks[gi][gj][ci][cj];
            }
        }
        p
    }

    /// (O3) as the blocks [[g1 <- g1, g1 <- g2], [g2 <- g1, g2 <- g2]].
    fn group_propagator(&self, k: f64, omega: Complex64, h: f64) -> [[Mat2; 2]; 2] {
        let re = |x: f64| Complex64::new(x, 0.0);
        let m = self.density_kg_m3 * omega * omega;
        let r = self.c12_pa / self.c22_pa;
        let cb = self.c11_pa - self.c12_pa * r;
        let b = [[re(k), re(1.0 / self.c66_pa)], [-m, re(-k)]];
        let d = [
            [re(-k * r), re(1.0 / self.c22_pa)],
            [k * k * cb - m, re(k * r)],
        ];
        let (bd, db) = (mul(&b, &d), mul(&d, &b));
        // The eigenvalues of BD, the larger first and the other from the determinant.
        let half_trace = 0.5 * (bd[0][0] + bd[1][1]);
        let det = det(&b) * det(&d);
        let root = (half_trace * half_trace - det).sqrt();
        let mu_1 = if (half_trace + root).norm() >= (half_trace - root).norm() {
            half_trace + root
        } else {
            half_trace - root
        };
        let mu_2 = if mu_1.norm() > 0.0 { det / mu_1 } else { mu_1 };
        let f = divided_differences(mu_1, mu_2, h);
        // (O4): f(M) = f_mean I + f_dd (M - half_trace I).
        let of = |mean: Complex64, dd: Complex64, m: &Mat2| -> Mat2 {
            let mut out = m.map(|row| row.map(|v| dd * v));
            for (i, row) in out.iter_mut().enumerate() {
                row[i] += mean - dd * half_trace;
            }
            out
        };
        [
            [
                of(f.ch_mean, f.ch_dd, &bd),
                mul(&of(f.s_mean, f.s_dd, &bd), &b),
            ],
            [
                mul(&of(f.s_mean, f.s_dd, &db), &d),
                of(f.ch_mean, f.ch_dd, &db),
            ],
        ]
    }

    /// The propagator's blocks in displacements and tractions: [[P_uu, P_us], [P_su, P_ss]]
    /// with U = (U_x, U_y), S = (S_xy, S_yy).
    fn blocks(&self, k: f64, omega: Complex64, h: f64) -> [[Mat2; 2]; 2] {
        let p = self.propagator(k, omega, h);
        let block = |r: usize, c: usize| -> Mat2 {
            [[p[r][c], p[r][c + 1]], [p[r + 1][c], p[r + 1][c + 1]]]
        };
        [[block(0, 0), block(0, 2)], [block(2, 0), block(2, 2)]]
    }
}

/// Means and divided differences of Ch(mu) = cosh(sqrt(mu) h) and S(mu) = sinh(sqrt(mu) h) /
/// sqrt(mu) over the eigenvalues mu_1, mu_2 (O4).
struct Differences {
    ch_mean: Complex64,
    ch_dd: Complex64,
    s_mean: Complex64,
    s_dd: Complex64,
}

/// sinh z / z, by its series below |z| = 0.2 (the first term left out, z^12 / 13!, is below
/// 1e-18 there).
fn shc(z: Complex64) -> Complex64 {
    if z.norm() < 0.2 {
        let z2 = z * z;
        1.0 + z2 / 6.0
            * (1.0 + z2 / 20.0 * (1.0 + z2 / 42.0 * (1.0 + z2 / 72.0 * (1.0 + z2 / 110.0))))
    } else {
        z.sinh() / z
    }
}

/// [`Differences`] for the layer height `h`: with alpha = mu_1 h^2, beta = mu_2 h^2 and a, b
/// their square roots (b's sign chosen so that |a - b| <= |a + b|),
///
/// - Ch[mu_1, mu_2] = h^2 / 2 shc((a + b) / 2) shc((a - b) / 2), from cosh a - cosh b =
///   2 sinh((a + b) / 2) sinh((a - b) / 2): no subtraction;
/// - S[mu_1, mu_2] = h^3 (shc a - shc b) / (alpha - beta): for |alpha|, |beta| <= 1 by the
///   series sum_(j >= 1) H_(j-1)(alpha, beta) / (2j + 1)!, H_n = sum_(i=0..n) alpha^i
///   beta^(n-i) (ten terms, the rest below 1e-18); where alpha and beta differ by at least
///   half the larger, directly; otherwise (close, large) by the midpoint form
///   (cosh u shc v - shc u cosh v) / (2 a b), u = (a + b) / 2, v = (a - b) / 2, whose
///   subtraction is of terms no larger than the result's scale cosh u.
fn divided_differences(mu_1: Complex64, mu_2: Complex64, h: f64) -> Differences {
    let (alpha, beta) = (mu_1 * h * h, mu_2 * h * h);
    let a = alpha.sqrt();
    let mut b = beta.sqrt();
    if (a - b).norm() > (a + b).norm() {
        b = -b;
    }
    let (u, v) = (0.5 * (a + b), 0.5 * (a - b));
    let ch_mean = 0.5 * (a.cosh() + b.cosh());
    let ch_dd = 0.5 * h * h * shc(u) * shc(v);
    let (shc_a, shc_b) = (shc(a), shc(b));
    let s_mean = 0.5 * h * (shc_a + shc_b);
    let larger = alpha.norm().max(beta.norm());
    let d = if larger <= 1.0 {
        // H_n = alpha H_(n-1) + beta^n.
        let (mut h_n, mut beta_n) = (Complex64::new(1.0, 0.0), Complex64::new(1.0, 0.0));
        let mut factorial = 6.0; // (2j + 1)! at j = 1
        let mut sum = h_n / factorial;
        for j in 2..=10 {
            beta_n *= beta;
            h_n = alpha * h_n + beta_n;
            factorial *= (2 * j) as f64 * (2 * j + 1) as f64;
            sum += h_n / factorial;
        }
        sum
    } else if (alpha - beta).norm() >= 0.5 * larger {
        (shc_a - shc_b) / (alpha - beta)
    } else {
        (u.cosh() * shc(v) - shc(u) * v.cosh()) / (2.0 * a * b)
    };
    Differences {
        ch_mean,
        ch_dd,
        s_mean,
        s_dd: h * h * h * d,
    }
}

fn mul(p: &Mat2, q: &Mat2) -> Mat2 {
    [
        [
            p[0][0] * q[0][0] + p[0][1] * q[1][0],
            p[0][0] * q[0][1] + p[0][1] * q[1][1],
        ],
        [
            p[1][0] * q[0][0] + p[1][1] * q[1][0],
            p[1][0] * q[0][1] + p[1][1] * q[1][1],
        ],
    ]
}

fn add(p: &Mat2, q: &Mat2) -> Mat2 {
    [
        [p[0][0] + q[0][0], p[0][1] + q[0][1]],
        [p[1][0] + q[1][0], p[1][1] + q[1][1]],
    ]
}

fn det(p: &Mat2) -> Complex64 {
    p[0][0] * p[1][1] - p[0][1] * p[1][0]
}

fn inverse(p: &Mat2) -> Mat2 {
    let d = det(p);
    [[p[1][1] / d, -p[0][1] / d], [-p[1][0] / d, p[0][0] / d]]
}

fn apply(p: &Mat2, x: [Complex64; 2]) -> [Complex64; 2] {
    [
        p[0][0] * x[0] + p[0][1] * x[1],
        p[1][0] * x[0] + p[1][1] * x[1],
    ]
}

const IDENTITY: Mat2 = [
    [Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0)],
    [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)],
];

const ZERO: Mat2 = [[Complex64::new(0.0, 0.0); 2]; 2];

/// Plane-strain waves u_x = U_x(y, t) sin(k x), u_y = U_y(y, t) cos(k x) through a stack of
/// orthotropic layers on a clamped bottom, driven by the normal traction sigma_yy =
/// -p(t) cos(k x) on the free top: the module's (O1)-(O5). The response of the strip 0 <= x
/// <= W with rollers on its sides for k = n pi / W.
#[derive(Clone, Debug, PartialEq)]
pub struct ObliqueIncidence {
    /// Layers from the top surface down.
    layers: Vec<OrthotropicLayer>,
    /// k (1/m).
    wavenumber_per_m: f64,
    /// Depth H of the clamped bottom (m).
    height_m: f64,
}

impl ObliqueIncidence {
    /// The stack of `layers_top_down` at wavenumber `wavenumber_per_m` (k >= 0; 0 is normal
    /// incidence on a clamped bottom); errors on an empty stack, a layer
    /// [`OrthotropicLayer::new`] would refuse, or a negative or non-finite k.
    pub fn new(
        layers_top_down: Vec<OrthotropicLayer>,
        wavenumber_per_m: f64,
    ) -> Result<ObliqueIncidence> {
        if layers_top_down.is_empty() {
            return Err(Error::invalid("layers", "[]", "needs at least one layer"));
        }
        for (i, l) in layers_top_down.iter().enumerate() {
            l.check(&format!("layers[{i}]"))?;
        }
        if !(wavenumber_per_m.is_finite() && wavenumber_per_m >= 0.0) {
            return Err(Error::invalid(
                "wavenumber_per_m",
                wavenumber_per_m,
                "must be finite and >= 0",
            ));
        }
        let height_m = layers_top_down.iter().map(|l| l.thickness_m).sum();
        Ok(ObliqueIncidence {
            layers: layers_top_down,
            wavenumber_per_m,
            height_m,
        })
    }

    /// The stack of a laminate (its layers are listed bottom-up) on a clamped bottom, at
    /// wavenumber `wavenumber_per_m`.
    pub fn of_laminate(laminate: &Laminate, wavenumber_per_m: f64) -> Result<ObliqueIncidence> {
        let layers = laminate
            .layers
            .iter()
            .rev()
            .map(|l| OrthotropicLayer::new(&laminate.materials[l.material], l.thickness_m))
            .collect::<Result<Vec<_>>>()?;
        ObliqueIncidence::new(layers, wavenumber_per_m)
    }

    /// The layers from the top surface down.
    pub fn layers(&self) -> &[OrthotropicLayer] {
        &self.layers
    }

    /// The wavenumber k along x (1/m).
    pub fn wavenumber_per_m(&self) -> f64 {
        self.wavenumber_per_m
    }

    /// Depth H of the clamped bottom (m).
    pub fn height_m(&self) -> f64 {
        self.height_m
    }

    fn check_depth(&self, depth_m: f64) -> Result<()> {
        // The bottom itself, to the rounding of the sums of thicknesses.
        if !(depth_m.is_finite() && depth_m >= 0.0 && depth_m <= self.height_m * (1.0 + 1e-12)) {
            return Err(Error::invalid(
                "depth_m",
                depth_m,
                format!("must lie in the stack, 0..{} m", self.height_m),
            ));
        }
        Ok(())
    }

    /// (U_x, U_y) at `depth_m` below the top (clamped below: 0 at the bottom) for the
    /// traction amplitudes (S_xy, S_yy) = `top_traction` on the top at (complex) angular
    /// frequency `omega`: (O5), one walk up from the bottom. `depth_m` must lie in the stack.
    pub fn displacement_per_traction(
        &self,
        omega: Complex64,
        depth_m: f64,
        top_traction: [Complex64; 2],
    ) -> [Complex64; 2] {
        let k = self.wavenumber_per_m;
        let receiver = (self.height_m - depth_m).max(0.0);
        // G below the current interface; at the receiver, G there and the product Q of the
        // N of the layers above it so far (S_receiver = Q S_top).
        let mut g = ZERO;
        let mut at: Option<(Mat2, Mat2)> = (receiver <= 0.0).then_some((g, IDENTITY));
        let climb = |g: &mut Mat2, at: &mut Option<(Mat2, Mat2)>, layer: &OrthotropicLayer, h| {
            let [[uu, us], [su, ss]] = layer.blocks(k, omega, h);
            let n = inverse(&add(&mul(&su, g), &ss));
            *g = mul(&add(&mul(&uu, g), &us), &n);
            if let Some((_, q)) = at {
                *q = mul(q, &n);
            }
        };
        let mut bottom = 0.0;
        for layer in self.layers.iter().rev() {
            let top = bottom + layer.thickness_m;
            if at.is_none() && receiver < top {
                if receiver > bottom {
                    climb(&mut g, &mut at, layer, receiver - bottom);
                }
                at = Some((g, IDENTITY));
                climb(&mut g, &mut at, layer, top - receiver.max(bottom));
            } else {
                climb(&mut g, &mut at, layer, layer.thickness_m);
            }
            bottom = top;
        }
        let (g_receiver, q) = at.unwrap_or((g, IDENTITY));
        apply(&g_receiver, apply(&q, top_traction))
    }

    /// (V_x, V_y) / P, the velocity amplitudes at `depth_m` per unit pressure P on the top
    /// (S_yy(top) = -P, S_xy(top) = 0) at (complex) angular frequency `omega`: i omega times
    /// [`ObliqueIncidence::displacement_per_traction`].
    pub fn velocity_per_pressure(&self, omega: Complex64, depth_m: f64) -> [Complex64; 2] {
        let zero = Complex64::new(0.0, 0.0);
        let traction = [zero, Complex64::new(-1.0, 0.0)];
        self.displacement_per_traction(omega, depth_m, traction)
            .map(|u| Complex64::i() * omega * u)
    }

    /// The velocity amplitudes [v_x(t), v_y(t)] at `depth_m` below the top (v_x of sin(k x),
    /// v_y of cos(k x)) for the pressure amplitude `pressure` (Pa) of -p(t) cos(k x) on the
    /// top, zero outside its samples, on its time grid: (O5) on the FFT grid at complex
    /// frequency ([`causal_response`], wrap-around below 1e-12 of the largest velocity).
    /// The stack is evaluated once per frequency, the frequencies in parallel.
    pub fn velocity(&self, pressure: &Signal, depth_m: f64) -> Result<[Signal; 2]> {
        self.check_depth(depth_m)?;
        // causal_response asks for the transfer function bin after bin: a first pass
        // collects its frequencies, the stack is evaluated at all of them in parallel, and
        // each component's pass reads them back (re-evaluating any frequency that differs).
        let omegas = RefCell::new(Vec::new());
        causal_response(pressure, |omega| {
            omegas.borrow_mut().push(omega);
            Complex64::new(0.0, 0.0)
        })?;
        let omegas = omegas.into_inner();
        let values: Vec<[Complex64; 2]> = omegas
            .par_iter()
            .map(|&omega| self.velocity_per_pressure(omega, depth_m))
            .collect();
        let component = |c: usize| {
            let next = Cell::new(0);
            causal_response(pressure, |omega| {
                let j = next.replace(next.get() + 1);
                match omegas.get(j) {
                    Some(&w) if w == omega => values[j][c],
                    _ => self.velocity_per_pressure(omega, depth_m)[c],
                }
            })
        };
        Ok([component(0)?, component(1)?])
    }
}
