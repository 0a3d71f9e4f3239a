//! Oblique incidence through the default experiment's 50-pair stochastic laminate, against the
//! exact solution of a strip with roller sides and a clamped bottom loaded by -p(t) cos(k x)
//! on its top ([`trnews::exact::oblique::ObliqueIncidence`]; issue #25).
//!
//! First the exact solution itself: its layer propagator against the matrix exponential's
//! series and against the orthotropic roller modes ([`RollerMode`]), the clamped rod's
//! reflections at k -> 0, a homogeneous layer against the isotropic half-space until the
//! clamped bottom's echo returns, and reciprocity and losslessness of the 50-pair stack (all
//! to 1e-10 or better). Then the strip of the laminate on spectral elements, W = 4 mm wide
//! (k = pi / W, k H = 9.1 over its 11.6 mm), whose field is exactly u_x = U_x(y, t) sin(k x),
//! u_y = U_y(y, t) cos(k x): the velocity amplitudes below 10 and 30 pairs, seen through the
//! transducers' 0.2-2 MHz band on transmission and reception, against the exact ones by the
//! relative L2 error over 30 us, every run with the time step's error removed as a scene
//! does. A resolved spectral-element strip agrees with the exact solution to 2.2e-5; the
//! presets' spectral elements are 0.18% (quick; 1.1% on v_x below 30 pairs) and 0.025%
//! (paper; 0.073% on v_x) off on v_y, the error the S waves bring across the layers.
//!
//! [`run_against_exact`] runs any [`SemSpec`]'s strip and returns its traces with the exact
//! ones, for the error estimates' companions to be checked against the truth.

mod common;
use common::*;
use rustfft::num_complex::Complex64;
use std::f64::consts::PI;
use std::time::Instant;
use trnews::exact::oblique::{ObliqueIncidence, OrthotropicLayer};
use trnews::exact::RollerMode;
use trnews::laminate::Laminate;
use trnews::material::Material;
use trnews::scene::STEP_FRACTION;
use trnews::scene::{LaminateSpec, Resolution, SceneSpec, SemPreset, TimeDispersionSpec};
use trnews::sem::gll::Gll;
use trnews::sem::{SemModel, SemSpec};
use trnews::signal::{causal_response, Signal};
use trnews::solve::time_dispersion::TimeDispersion;
use trnews::solve::{Integrator, Quantity, Receiver, RunConfig, Source};
use trnews::transducer::TransducerSpec;

type C4 = [[Complex64; 4]; 4];

/// Largest |v(t) - expected(t)| over the samples with t < `until`, over `scale`.
fn worst(v: &Signal, expected: impl Fn(f64) -> f64, until: f64, scale: f64) -> f64 {
    (0..v.len())
        .filter(|&k| v.time_at(k) < until)
        .map(|k| (v.samples[k] - expected(v.time_at(k))).abs() / scale)
        .fold(0.0, f64::max)
}

/// Unit Gaussian pressure exp(-((t - centre) / width)^2) as a function, and sampled at 2 ns
/// over `duration`: band-limited far below the Nyquist frequency (250 MHz), so the FFT's
/// interpolation of the samples is the Gaussian itself.
fn pulse(width: f64, centre: f64, duration: f64) -> (impl Fn(f64) -> f64, Signal) {
    let p = move |t: f64| (-((t - centre) / width).powi(2)).exp();
    (p, gaussian(2e-9, duration, centre, width, 1.0))
}

/// The complex frequency's damping of a `record`-long signal in
/// [`trnews::signal::causal_response`]: ln(1e12) over four records.
fn eta(record: f64) -> f64 {
    -(1e-12f64).ln() / (4.0 * record)
}

/// The laminate's three materials in plane strain: epoxy, fabric 0/90, fabric 45/45.
fn materials() -> [Material; 3] {
    let lam = stack();
    [0, 1, 2].map(|i| lam.materials[i].clone())
}

fn multiply(p: &C4, q: &C4) -> C4 {
    let mut o = [[Complex64::new(0.0, 0.0); 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            for l in 0..4 {
                o[i][j] += p[i][l] * q[l][j];
            }
        }
    }
    o
}

/// Scale of the state's entries that balances A h of a layer of height `h` at wavenumber
/// `k` and frequency `omega`: displacements 1, tractions 1 / sigma, with sigma =
/// sqrt(C22 C66) (|omega| / c_S + k + 1 / h) the traction of a unit displacement's wave.
fn balance(layer: &OrthotropicLayer, k: f64, omega: Complex64, h: f64) -> [f64; 4] {
    let c_s = (layer.c66_pa / layer.density_kg_m3).sqrt();
    let sigma = (layer.c22_pa * layer.c66_pa).sqrt() * (omega.norm() / c_s + k + 1.0 / h);
    [1.0, 1.0, 1.0 / sigma, 1.0 / sigma]
}

/// e^(A h) of the module's (O2) by scaling and squaring of its Taylor series (30 terms after
/// scaling the balanced A h below 0.1 in the 1-norm of its entries).
fn series_propagator(layer: &OrthotropicLayer, k: f64, omega: Complex64, h: f64) -> C4 {
    let z = Complex64::new(0.0, 0.0);
    let re = |x: f64| Complex64::new(x, 0.0);
    let m = layer.density_kg_m3 * omega * omega;
    let r = layer.c12_pa / layer.c22_pa;
    let cb = layer.c11_pa - layer.c12_pa * r;
    let a = [
        [z, re(k), re(1.0 / layer.c66_pa), z],
        [re(-k * r), z, z, re(1.0 / layer.c22_pa)],
        [k * k * cb - m, z, z, re(k * r)],
        [z, -m, re(-k), z],
    ];
    let s = balance(layer, k, omega, h);
    let mut x = [[z; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            x[i][j] = a[i][j] * h * s[i] / s[j];
        }
    }
    let norm: f64 = x.iter().flatten().map(|v| v.norm()).sum();
    let squarings = (norm / 0.1).log2().ceil().max(0.0) as i32;
    let x = x.map(|row| row.map(|v| v / 2f64.powi(squarings)));
    let mut e = [[z; 4]; 4];
    let mut term = [[z; 4]; 4];
    for i in 0..4 {
        e[i][i] = re(1.0);
        term[i][i] = re(1.0);
    }
    for n in 1..30 {
        term = multiply(&term, &x).map(|row| row.map(|v| v / n as f64));
        for i in 0..4 {
            for j in 0..4 {
                e[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        e = multiply(&e, &e);
    }
    for i in 0..4 {
        for j in 0..4 {
            e[i][j] *= s[j] / s[i];
        }
    }
    e
}

/// Largest difference of two propagators of a layer of height `h` in balanced units
/// ([`balance`]), over the largest entry of `reference`.
fn propagator_difference(scale: [f64; 4], p: &C4, reference: &C4) -> f64 {
    let s = scale;
    let (mut diff, mut big) = (0f64, 0f64);
    for i in 0..4 {
        for j in 0..4 {
            let w = s[i] / s[j];
            diff = diff.max(((p[i][j] - reference[i][j]) * w).norm());
            big = big.max((reference[i][j] * w).norm());
        }
    }
    diff / big
}

/// The exact solution, check (i): the layer propagator's closed form (the module's (O3)-(O4),
/// divided differences without cancellation) is the matrix exponential, against its series,
/// for the laminate's three materials, at k = pi / 4 mm and 0, from 1 kHz to 100 MHz at the
/// complex frequency of a 30 us record, on layers of 20 um (thinner than any epoxy layer) and
/// 0.3 mm (thicker than any ply), to 2e-12 of the largest entry in balanced units ([`balance`];
/// measured 8e-13); and on 3 mm (k h = 2.4, ten times the plies'), to 3e-11 (measured
/// 1.1e-11). Both sides' round-off grows with the phase omega h / c_S across the layer (up to
/// 435 rad at 100 MHz on 3 mm; the series squares up to 2^12 times) and with the evanescent
/// waves' growth, e^8.7 at low frequency in the 0/90 fabric on 3 mm, which the stack's
/// layers (k h <= 0.2) do not reach.
#[test]
fn exact_propagator_is_the_matrix_exponential() {
    let mut worst_thin = 0f64;
    let mut worst_thick = 0f64;
    for material in &materials() {
        for h in [2e-5, 3e-4, 3e-3] {
            let layer = OrthotropicLayer::new(material, h).unwrap();
            for k in [0.0, PI / 4e-3] {
                for f in (0..=60).map(|j| 1e3 * 10f64.powf(j as f64 / 12.0)) {
                    let omega = Complex64::new(2.0 * PI * f, -eta(30e-6));
                    let p = layer.propagator(k, omega, h);
                    let q = series_propagator(&layer, k, omega, h);
                    let d = propagator_difference(balance(&layer, k, omega, h), &p, &q);
                    if h < 1e-3 {
                        worst_thin = worst_thin.max(d);
                    } else {
                        worst_thick = worst_thick.max(d);
                    }
                }
            }
        }
    }
    println!("largest difference {worst_thin:e} (up to 0.3 mm), {worst_thick:e} (3 mm)");
    assert!(worst_thin < 2e-12, "{worst_thin:e}");
    assert!(worst_thick < 3e-11, "{worst_thick:e}");
}

/// The exact solution, check (ii): the layer propagator carries the standing roller modes of
/// [`RollerMode`] (an independent closed form for orthotropic materials: u_x = a sin(kx x)
/// cos(ky y), u_y = b cos(kx x) sin(ky y) at the frequency of its 2x2 eigenproblem), so the
/// stiffnesses enter (O2) where they belong: their state (U_x, U_y, S_xy, S_yy) at y = 0.1 mm
/// carried up 0.25 mm at kx = pi / 4 mm, ky from 1 to 30 per mm, for the three materials.
/// To 2e-12 of the state in balanced units (round-off of the mode's own closed form and of
/// the propagator; measured 4e-13).
#[test]
fn exact_layer_propagator_carries_the_roller_modes() {
    let (kx, y0, h) = (PI / 4e-3, 0.1e-3, 0.25e-3);
    let mut worst = 0f64;
    for material in &materials() {
        let layer = OrthotropicLayer::new(material, h).unwrap();
        let c = &material.stiffness_pa;
        for ky in [1e3, 3e3, 1e4, 3e4] {
            let mode = RollerMode::new(material, kx, ky);
            let state = |y: f64| {
                let (s, co) = (ky * y).sin_cos();
                [
                    mode.a * co,
                    mode.b * s,
                    -c[2][2] * (mode.a * ky + kx * mode.b) * s,
                    (c[0][1] * kx * mode.a + c[1][1] * mode.b * ky) * co,
                ]
            };
            let p = layer.propagator(kx, Complex64::new(mode.omega, 0.0), h);
            let (below, above) = (state(y0), state(y0 + h));
            let scale = balance(&layer, kx, Complex64::new(mode.omega, 0.0), h);
            let size = (0..4)
                .map(|i| above[i].abs() / scale[i])
                .fold(0.0, f64::max);
            for i in 0..4 {
                let carried: Complex64 = (0..4).map(|j| p[i][j] * below[j]).sum();
                worst = worst.max((carried - above[i]).norm() / scale[i] / size);
            }
        }
    }
    println!("largest difference {worst:e}");
    assert!(worst < 2e-12, "{worst:e}");
}

/// The exact solution, check (iii): at k -> 0 a homogeneous clamped layer is the clamped 1-D
/// rod: at depth z in epoxy 1 mm thick the pressure's down-going wave -p(t - z / c) / Z and
/// its reflections, velocity reversed at the clamped bottom and kept at the free top,
/// v(z, t) = -sum_n (-1)^n [p(t - (2 n L + z) / c) - p(t - (2 (n + 1) L - z) / c)] / Z,
/// over 5 us (six round trips, the standing modes undamped). At k = 0 and 1e-3 / m, to
/// 1e-10 of the peak p / Z (the wrap-around is at most 1e-12 of the largest velocity the
/// undamped rod ever carries, a few p / Z; the Gaussian's value at t = 0 is e^-36; measured
/// 4e-12).
#[test]
fn exact_clamped_rod_at_vanishing_wavenumber() {
    let e = epoxy();
    let thickness = 1e-3;
    let (c, z) = (e.wave_speeds().p_y_m_s, e.impedance_p_y());
    let (p, load) = pulse(0.1e-6, 0.6e-6, 5e-6);
    let mut largest = 0f64;
    for k in [0.0, 1e-3] {
        let layer = OrthotropicLayer::new(&e, thickness).unwrap();
        let stack = ObliqueIncidence::new(vec![layer], k).unwrap();
        for depth in [0.0, 0.3e-3, 0.75e-3, thickness] {
            let [_, v] = stack.velocity(&load, depth).unwrap();
            let expected = |t: f64| {
                -(0..10)
                    .map(|n| {
                        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
                        let round = 2.0 * n as f64 * thickness;
                        sign * (p(t - (round + depth) / c)
                            - p(t - (round + 2.0 * thickness - depth) / c))
                    })
                    .sum::<f64>()
                    / z
            };
            let error = worst(&v, expected, f64::INFINITY, 1.0 / z);
            largest = largest.max(error);
            assert!(error < 1e-10, "k {k}, depth {depth}: {error:e}");
        }
    }
    println!("largest error {largest:e} of p / Z");
}

/// (V_x, V_y) / P at depth `depth` in the isotropic half-space of `m` under the traction
/// -P cos(k x) on its surface, in closed form (potentials phi = A e^(nu_P y) cos(k x), psi =
/// B e^(nu_S y) sin(k x), y <= 0, nu^2 = k^2 - omega^2 / c^2, Re nu > 0): with the Rayleigh
/// function R = (k^2 + nu_S^2)^2 - 4 k^2 nu_P nu_S,
/// U_x = P [k (k^2 + nu_S^2) e^(-nu_P d) - 2 k nu_P nu_S e^(-nu_S d)] / (mu R),
/// U_y = -P nu_P [(k^2 + nu_S^2) e^(-nu_P d) - 2 k^2 e^(-nu_S d)] / (mu R).
fn half_space_velocity(m: &Material, k: f64, omega: Complex64, depth: f64) -> [Complex64; 2] {
    let rho = m.density_kg_m3;
    let mu = m.stiffness_pa[2][2];
    let (cp2, cs2) = (m.stiffness_pa[1][1] / rho, mu / rho);
    let nu_p = (k * k - omega * omega / cp2).sqrt();
    let nu_s = (k * k - omega * omega / cs2).sqrt();
    let k2s = k * k + nu_s * nu_s;
    let rayleigh = k2s * k2s - 4.0 * k * k * nu_p * nu_s;
    let (ep, es) = ((-nu_p * depth).exp(), (-nu_s * depth).exp());
    let ux = (k * k2s * ep - 2.0 * k * nu_p * nu_s * es) / (mu * rayleigh);
    let uy = -nu_p * (k2s * ep - 2.0 * k * k * es) / (mu * rayleigh);
    [ux, uy].map(|u| Complex64::i() * omega * u)
}

/// The exact solution, check (iv): a homogeneous epoxy layer 5 mm thick at k = pi / 4 mm
/// (k L = 3.9: the evanescent part of the field spans the layer) is the isotropic half-space
/// ([`half_space_velocity`], a closed form independent of the propagators) until the clamped
/// bottom's echo returns: the 1-D system at one k is hyperbolic, its fastest vertical speed
/// c_P, so nothing from the bottom reaches depth d before (2 L - d) / c_P after the pulse.
/// Both components at the surface and 1 mm down, up to 6 pulse widths before that, to 1e-10
/// of the half-space's peak (measured 2.7e-12: the wrap-around bounds of both, the
/// half-space's own undamped Rayleigh wave at omega = k c_R included).
#[test]
fn exact_layer_is_the_half_space_until_the_bottom_echo() {
    let e = epoxy();
    let (thickness, k) = (5e-3, PI / 4e-3);
    let c = e.wave_speeds().p_y_m_s;
    let (width, centre) = (0.1e-6, 0.6e-6);
    let (_, load) = pulse(width, centre, 6e-6);
    let layer = OrthotropicLayer::new(&e, thickness).unwrap();
    let stack = ObliqueIncidence::new(vec![layer], k).unwrap();
    let mut largest = 0f64;
    for depth in [0.0, 1e-3] {
        let layer_v = stack.velocity(&load, depth).unwrap();
        let until = (2.0 * thickness - depth) / c + centre - 6.0 * width;
        for (component, in_layer) in layer_v.iter().enumerate() {
            let half_space = causal_response(&load, |omega| {
                half_space_velocity(&e, k, omega, depth)[component]
            })
            .unwrap();
            let peak = half_space.samples.iter().fold(0f64, |m, v| m.max(v.abs()));
            let n = (until / load.dt_s) as usize;
            let error = in_layer.samples[..n]
                .iter()
                .zip(&half_space.samples[..n])
                .map(|(a, b)| (a - b).abs() / peak)
                .fold(0.0, f64::max);
            largest = largest.max(error);
            assert!(
                error < 1e-10,
                "depth {depth}, component {component}: {error:e}"
            );
        }
    }
    println!("largest difference {largest:e} of the half-space's peak");
}

/// The exact solution, check (v): the 50-pair stack at k = pi / 4 mm is reciprocal and
/// lossless. Its top compliance G (U = G S, U = (U_x, U_y), S = (S_xy, S_yy)) is symmetric,
/// (O2) being the Euler-Lagrange equation of a symmetric form (the module docs): at the
/// complex frequencies of a 30 us record from 10 kHz to 10 MHz, |G_xy - G_yx| within 1e-12
/// of |G| (round-off through 100 layers' recursions; measured 3.5e-15); a sign slip in the
/// k terms of (O2) breaks it. And at real frequencies, where the clamped stack stores but
/// cannot lose energy, G is real (the 45/45 plies' evanescent waves come in complex
/// conjugate pairs there, whose imaginary parts must cancel): |Im G| within 1e-12 of |G|
/// (measured 1.2e-18).
#[test]
fn exact_stack_is_reciprocal_and_lossless() {
    let stack = ObliqueIncidence::of_laminate(&stack(), PI / WIDTH).unwrap();
    let (zero, one) = (Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0));
    let compliance = |omega: Complex64| {
        let [gxx, gyx] = stack.displacement_per_traction(omega, 0.0, [one, zero]);
        let [gxy, gyy] = stack.displacement_per_traction(omega, 0.0, [zero, one]);
        [[gxx, gxy], [gyx, gyy]]
    };
    let size = |g: &[[Complex64; 2]; 2]| g.iter().flatten().map(|v| v.norm()).fold(0.0, f64::max);
    let (mut asymmetry, mut loss) = (0f64, 0f64);
    for f in (0..=300).map(|j| 1e4 * 1000f64.powf(j as f64 / 300.0)) {
        let g = compliance(Complex64::new(2.0 * PI * f, -eta(30e-6)));
        asymmetry = asymmetry.max((g[0][1] - g[1][0]).norm() / size(&g));
        let g = compliance(Complex64::new(2.0 * PI * f, 0.0));
        let imaginary = g.iter().flatten().map(|v| v.im.abs()).fold(0.0, f64::max);
        loss = loss.max(imaginary / size(&g));
    }
    println!("largest asymmetry {asymmetry:e}, largest imaginary part {loss:e} of |G|");
    assert!(asymmetry < 1e-12, "{asymmetry:e}");
    assert!(loss < 1e-12, "{loss:e}");
}

/// Width W of the strip (m): k = pi / W = 785 / m. sin(theta) = k c / omega at 2, 1 and 0.2
/// MHz: in the 0/90 plies 0.42, 0.84 and 4.2 for P (c = 6.7 km/s across), 0.11, 0.22 and
/// 1.1 for S; in the 45/45 plies 0.40, 0.79, 4.0 (P) and 0.27, 0.54, 2.7 (S); in epoxy 0.16,
/// 0.32, 1.6 (P) and 0.07, 0.13, 0.66 (S) (printed by `oblique_angles_in_band`): oblique
/// across the band, the plies' waves evanescent across the layers at its bottom. k H = 9.1
/// over the 11.6 mm stack (k h = 0.25 in its thickest layer).
const WIDTH: f64 = 4e-3;

/// Width w of the Gaussian drive exp(-((t - 4 w) / w)^2), as in `tests/normal_incidence.rs`:
/// its spectrum is within 10% of flat up to 2 MHz.
const DRIVE_WIDTH: f64 = 0.05e-6;

/// Recorded duration (s).
const DURATION: f64 = 30e-6;

/// The pairs above each receiver: the interfaces below 10 and 30 pairs (the bottom is
/// clamped, nothing moves there).
const PAIRS_ABOVE: [usize; 2] = [10, 30];

/// The default experiment's laminate draw (the presets share it).
fn stack() -> Laminate {
    let spec = SceneSpec::preset(Resolution::Quick);
    match spec.laminate {
        LaminateSpec::Stochastic(s) => Laminate::stochastic(&s, spec.plane).unwrap(),
        other => panic!("the default experiment's laminate is stochastic, not {other:?}"),
    }
}

/// Depths (m) of the receivers: the interfaces below [`PAIRS_ABOVE`] pairs, node rows of
/// every discretisation.
fn receiver_depths(lam: &Laminate) -> [f64; 2] {
    PAIRS_ABOVE.map(|pairs| {
        lam.layers
            .iter()
            .rev()
            .take(2 * pairs)
            .map(|l| l.thickness_m)
            .sum()
    })
}

/// The angles of the wave in the plies and the epoxy across the band (printed).
#[test]
fn oblique_angles_in_band() {
    let k = PI / WIDTH;
    for m in &materials() {
        let speeds = m.wave_speeds();
        for f in [0.2e6, 1e6, 2e6] {
            let omega = 2.0 * PI * f;
            println!(
                "{:<14} {:>4.1} MHz: sin(theta) P {:.2}, S {:.2}",
                m.name,
                f / 1e6,
                k * speeds.p_y_m_s / omega,
                k * speeds.s_m_s / omega
            );
        }
    }
    let lam = stack();
    let thickest = lam.layers.iter().map(|l| l.thickness_m).fold(0.0, f64::max);
    println!(
        "H = {:.2} mm, k H = {:.2}, thickest layer {:.3} mm, k h = {:.3}",
        lam.thickness_m() * 1e3,
        k * lam.thickness_m(),
        thickest * 1e3,
        k * thickest
    );
}

/// The pressure on the top at step `dt`: the Gaussian drive through the transducer's band.
fn pressure(dt: f64) -> Signal {
    band_pressure(dt, DURATION, DRIVE_WIDTH)
}

/// Order along x of spectral elements `m`.
fn order_x(m: &SemModel) -> usize {
    (m.x_nodes_m.len() - 1) / (m.columns_m.len() - 1)
}

/// For each node column of `m`, int l_i(x) f(x) dx over the width: per element by GLL
/// quadrature of order `order_x + 8` (f = cos or sin of k x, smooth: the rule is exact to
/// round-off for these 0.25-1 mm elements).
fn consistent_along_x(m: &SemModel, f: impl Fn(f64) -> f64) -> Vec<f64> {
    let p = order_x(m);
    let (rule, fine) = (Gll::new(p), Gll::new(p + 8));
    let mut out = vec![0.0; m.nx()];
    for (e, w) in m.columns_m.windows(2).enumerate() {
        let (middle, half) = (0.5 * (w[0] + w[1]), 0.5 * (w[1] - w[0]));
        for (&xi, &weight) in fine.points.iter().zip(&fine.weights) {
            let fx = f(middle + half * xi);
            for (a, l) in rule.lagrange_at(xi).iter().enumerate() {
                out[e * p + a] += half * weight * l * fx;
            }
        }
    }
    out
}

/// The GLL weights of `m`'s node columns along x (int l_i dx by the elements' own rule).
fn gll_along_x(m: &SemModel) -> Vec<f64> {
    let p = order_x(m);
    let rule = Gll::new(p);
    let mut out = vec![0.0; m.nx()];
    for (e, w) in m.columns_m.windows(2).enumerate() {
        for (a, weight) in rule.weights.iter().enumerate() {
            out[e * p + a] += 0.5 * (w[1] - w[0]) * weight;
        }
    }
    out
}

/// The load of the traction (0, -p(t) cos(k x)) on the top of `m`: on each top node's u_y,
/// minus its consistent share int l_i(x) cos(k x) dx.
fn cos_pressure_on_top(m: &SemModel, k: f64, p: Signal) -> Source {
    let top = m.y_nodes_m.len() - 1;
    let share = consistent_along_x(m, |x| (k * x).cos());
    Source {
        weights: share
            .iter()
            .enumerate()
            .map(|(i, &f)| (2 * m.node(i, top) + 1, -f))
            .collect(),
        signal: p,
    }
}

/// The velocity amplitude of `component` (0: v_x of sin(k x), 1: v_y of cos(k x)) on the
/// node row nearest `depth` below the top of `m`: the GLL-weighted projection sum_i w_i v_i
/// with w_i = g_i f(k x_i) / sum_j g_j f(k x_j)^2 (f = sin or cos, g the GLL weights along
/// x), which is exactly V for the nodal field V f(k x_i).
fn amplitude_receiver(m: &SemModel, k: f64, depth: f64, component: usize) -> Receiver {
    let ys = &m.y_nodes_m;
    let y = ys[ys.len() - 1] - depth;
    let j = (0..ys.len())
        .min_by(|&a, &b| (ys[a] - y).abs().total_cmp(&(ys[b] - y).abs()))
        .unwrap();
    let shape = |x: f64| {
        if component == 0 {
            (k * x).sin()
        } else {
            (k * x).cos()
        }
    };
    let g = gll_along_x(m);
    let f: Vec<f64> = m.x_nodes_m.iter().map(|&x| shape(x)).collect();
    let norm: f64 = g.iter().zip(&f).map(|(g, f)| g * f * f).sum();
    Receiver {
        name: format!("v_{} at depth {depth}", ["x", "y"][component]),
        weights: (0..m.nx())
            .map(|i| (2 * m.node(i, j) + component, g[i] * f[i] / norm))
            .filter(|&(_, w)| w != 0.0)
            .collect(),
        quantity: Quantity::Velocity,
    }
}

/// The receivers of every run, in this order: v_y below 10 and 30 pairs, then v_x there.
const RECEIVERS: [(usize, usize); 4] = [(1, 0), (1, 1), (0, 0), (0, 1)];

/// One strip's run and the exact solution at its receivers ([`RECEIVERS`]).
pub struct Run {
    /// The run's velocity amplitudes, the time step's error removed.
    pub traces: Vec<Signal>,
    /// The exact ones on the same grid.
    pub exact: Vec<Signal>,
    /// Nodes of the strip.
    pub nodes: usize,
    /// The step (s).
    pub dt_s: f64,
    /// Run time of the strip (s).
    pub seconds: f64,
    /// Time the exact solution took (s).
    pub exact_seconds: f64,
}

impl Run {
    /// Relative L2 errors in band over the record's first `until` seconds, in [`RECEIVERS`]
    /// order.
    pub fn errors_until(&self, until: f64) -> Vec<f64> {
        self.traces
            .iter()
            .zip(&self.exact)
            .map(|(t, e)| band_error(t, e, until))
            .collect()
    }

    /// Relative L2 errors in band over the record, in [`RECEIVERS`] order.
    pub fn errors(&self) -> Vec<f64> {
        self.errors_until(DURATION)
    }

    /// Prints the errors (over the record and its first 10 us), nodes, step and run times
    /// under `name`.
    pub fn print(&self, name: &str) {
        let (e, early) = (self.errors(), self.errors_until(10e-6));
        println!(
            "{name:<50} {:>6} nodes  dt {:.3} ns  {:>5.1} s (exact {:.1} s)\n    error below \
             {} / {} pairs: v_y {:.3e} / {:.3e}, v_x {:.3e} / {:.3e}; first 10 us: v_y \
             {:.3e} / {:.3e}, v_x {:.3e} / {:.3e}",
            self.nodes,
            self.dt_s * 1e9,
            self.seconds,
            self.exact_seconds,
            PAIRS_ABOVE[0],
            PAIRS_ABOVE[1],
            e[0],
            e[1],
            e[2],
            e[3],
            early[0],
            early[1],
            early[2],
            early[3],
        );
    }
}

/// The spectral elements `m` of the laminate on the strip: rollers on the sides, clamped
/// bottom ([`WaveStrip::sem`]), with the Lanczos critical step.
fn clamped_strip(m: SemModel) -> WaveStrip {
    WaveStrip::sem(m, false, BottomEdge::Fixed)
}

/// Runs `strip` (spectral elements of the laminate, [`clamped_strip`]) at `step_fraction` of
/// its dt_crit under the pressure -p(t) cos(pi x / W) on its top, as a scene does: the time
/// step's error removed ([`TimeDispersion`] up to the default 20 MHz), the run extended past
/// the record by the inverse transform's margin and cut back (the clamped stack still rings
/// at full energy when the record ends: without the margin the transform's spoilt end cost
/// the resolved reference 1.4e-4 at 0.9 dt_crit, 4e-5 at 0.5, against 0.9e-5 with it at
/// either). Evaluates the exact solution at the receivers on the same grid.
pub fn run_strip(strip: &WaveStrip, step_fraction: f64) -> Run {
    run_strip_at(strip, step_fraction * strip.dt_crit())
}

/// [`run_strip`] at the step `dt`.
fn run_strip_at(strip: &WaveStrip, dt: f64) -> Run {
    let WaveStrip::Sem(m, _) = strip else {
        panic!("the oblique strip is built on spectral elements")
    };
    let lam = stack();
    let k = PI / WIDTH;
    let depths = receiver_depths(&lam);
    let load = pressure(dt);
    let up_to = TimeDispersionSpec::default().up_to_hz;
    let td = TimeDispersion::of_run(Integrator::Explicit, dt, up_to, "up_to_hz")
        .unwrap()
        .expect("central differences have the transforms");
    let source = cos_pressure_on_top(m, k, td.add_to_source(&load).unwrap());
    let receivers: Vec<Receiver> = RECEIVERS
        .iter()
        .map(|&(component, r)| amplitude_receiver(m, k, depths[r], component))
        .collect();
    let config = RunConfig {
        duration_s: DURATION,
        dt_s: Some(dt),
        ..Default::default()
    };
    let clock = Instant::now();
    let traces = strip
        .run(&[source], &receivers, &td.extended(&config))
        .unwrap()
        .traces
        .iter()
        .map(|t| td.recorded(t, Quantity::Velocity, &config).unwrap())
        .collect();
    let seconds = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let exact = ObliqueIncidence::of_laminate(&lam, k).unwrap();
    let at_depths = depths.map(|d| exact.velocity(&load, d).unwrap());
    let exact = RECEIVERS
        .iter()
        .map(|&(component, r)| at_depths[r][component].clone())
        .collect();
    Run {
        traces,
        exact,
        nodes: strip.nodes(),
        dt_s: dt,
        seconds,
        exact_seconds: clock.elapsed().as_secs_f64(),
    }
}

/// The laminate's strip cut by `spec` ([`SemModel::layered`]) run against the exact solution
/// at [`STEP_FRACTION`] of its dt_crit, the time step's error removed ([`run_strip`]): the
/// traces and the exact ones at [`RECEIVERS`], for companions and error estimates to compare.
pub fn run_against_exact(spec: &SemSpec) -> Run {
    run_strip(&spec_strip(spec), STEP_FRACTION)
}

/// The clamped strip of the laminate cut by `spec`.
fn spec_strip(spec: &SemSpec) -> WaveStrip {
    clamped_strip(SemModel::layered(&stack(), WIDTH, spec).unwrap())
}

/// The spectral elements of a resolution preset ([`SemPreset::of`]) as a [`SemSpec`].
fn preset_spec(resolution: Resolution) -> SemSpec {
    let p = SemPreset::of(resolution);
    SemSpec {
        order_x: p.order_x,
        min_order_y: p.min_order_y,
        max_order_y: p.max_order_y,
        element_size_x_m: p.element_size_x_m,
        element_size_y_m: p.element_size_y_m,
        ..SemSpec::default()
    }
}

/// `m` with its element rows re-cut: a row of material `mat`, height `h` and order `p` across
/// becomes `cut(mat, h, p) = (n, q)`, n equal rows of order q across (as in
/// `tests/normal_incidence.rs`).
fn recut(m: &SemModel, cut: impl Fn(usize, f64, usize) -> (usize, usize)) -> SemModel {
    let (mut rows, mut orders, mut materials) = (vec![m.rows_m[0]], vec![], vec![]);
    for ((w, &mat), p) in m.rows_m.windows(2).zip(&m.row_material).zip(m.row_orders()) {
        let (n, q) = cut(mat, w[1] - w[0], p);
        rows.extend((1..=n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        orders.extend(std::iter::repeat_n(q, n));
        materials.extend(std::iter::repeat_n(mat, n));
    }
    let (columns, layers) = (m.columns_m.clone(), m.materials.clone());
    SemModel::new(columns, rows, order_x(m), &orders, layers, materials).unwrap()
}

/// The resolved reference: every layer cut into rows no taller than `row` at order 4
/// across, order `order` along x on elements no wider than `element`.
fn resolved(row: f64, order: usize, element: f64) -> WaveStrip {
    let one_row_per_layer = SemSpec {
        order_x: order,
        min_order_y: 1,
        max_order_y: 1,
        element_size_x_m: element,
        element_size_y_m: 1.0,
        ..SemSpec::default()
    };
    let m = SemModel::layered(&stack(), WIDTH, &one_row_per_layer).unwrap();
    clamped_strip(recut(&m, |_, h, _| ((h / row).ceil() as usize, 4)))
}

/// The resolved reference: rows <= 0.1 mm at order 4 across (at least 20 GLL intervals per
/// S wavelength at 2 MHz: 0.52 mm in epoxy, 0.88 mm in the 0/90 plies), order 8 along x on
/// 0.5 mm (65 points over the half wavelength of cos(k x)).
fn reference() -> WaveStrip {
    resolved(0.1e-3, 8, 0.5e-3)
}

/// The exact solution and a discretisation that resolves everything agree: the resolved
/// reference ([`reference`]) at 0.9 dt_crit, its step's error removed, within 3e-5 at every
/// receiver (measured 0.89e-5 and 0.27e-5 on v_y, 2.18e-5 and 0.27e-5 on v_x). What is left
/// is the rows' error across (`resolved_reference_choices`): rows <= 0.2 mm are 0.9-7.5e-4
/// off, rows <= 0.05 mm 0.9-1.1e-6 on every receiver (as much in the first 10 us: a floor
/// that is not the rows'), while the step (0.5 dt_crit) and the elements along x (order 8
/// on 1 mm) change the errors by less than 0.3%.
#[test]
fn exact_agrees_with_resolved_spectral_elements() {
    let run = run_strip(&reference(), STEP_FRACTION);
    run.print("resolved: order 4 on rows <= 0.1 mm; 8 on 0.5 mm");
    let errors = run.errors();
    assert!(errors.iter().all(|&e| e < 3e-5), "{errors:?}");
}

/// How the resolved reference was chosen: its rows, step and elements along x varied.
#[test]
#[ignore = "measurement (about six minutes): cargo test --release --test oblique_incidence \
            -- --ignored resolved_reference_choices --nocapture"]
fn resolved_reference_choices() {
    for (row, order, element, fraction) in [
        (0.2e-3, 8, 0.5e-3, STEP_FRACTION),
        (0.1e-3, 8, 0.5e-3, STEP_FRACTION),
        (0.1e-3, 8, 0.5e-3, 0.5),
        (0.1e-3, 8, 1e-3, STEP_FRACTION),
        (0.05e-3, 8, 0.5e-3, STEP_FRACTION),
    ] {
        let run = run_strip(&resolved(row, order, element), fraction);
        run.print(&format!(
            "rows <= {} mm; {order} on {} mm; {fraction} dt_crit",
            row * 1e3,
            element * 1e3
        ));
    }
}

/// The presets' spectral elements on the strip at their step (0.9 dt_crit), the step's
/// error removed, measured (v_y below 10 / 30 pairs, then v_x). Regression guards 10% above
/// the measured errors: quick 0.182% / 0.160%, 0.098% / 1.11% (first 10 us 0.048% / 0.016%,
/// 0.063% / 0.33%: the lossless stack keeps its energy, so the phase error grows over the
/// record); paper 0.0248% / 0.0087%, 0.0136% / 0.073%. Far above normal incidence's 0.0073%
/// and 0.0024%: the S waves the oblique load brings (0.88 mm long at 2 MHz in the 0/90
/// plies, against the P waves' 3.3 mm) are what the orders across must resolve; every row
/// of the quick preset one order higher across (at 2.07 ns against 3.14) brings it to 0.023%
/// / 0.039%, 0.034% / 0.089%.
#[test]
fn preset_discretisations_against_the_exact_solution() {
    for (name, resolution, guards) in [
        (
            "quick SEM preset (order 7 on 0.5 mm, 2-4 across)",
            Resolution::Quick,
            [0.0020, 0.00175, 0.00107, 0.0122],
        ),
        (
            "paper SEM preset (order 6 on 0.25 mm, 3-6 across)",
            Resolution::Paper,
            [0.000272, 0.0000955, 0.000149, 0.000801],
        ),
    ] {
        let run = run_against_exact(&preset_spec(resolution));
        run.print(name);
        let errors = run.errors();
        for (e, guard) in errors.iter().zip(guards) {
            assert!(*e <= guard, "{name}: {errors:?} above {guards:?}");
        }
    }
}

/// The strip of a scene spec's spectral elements ([`spec_strip`]).
fn strip_of_scene(spec: &SceneSpec) -> WaveStrip {
    spec_strip(&spec.discretisation.sem_cut(spec).unwrap())
}

/// Issue #25's check of the error estimate at oblique incidence: each preset's strip at 0.9
/// of its dt_crit and the strips of its companions ([`SceneSpec::companions`]: orders p - 1
/// and p - 2 along x with the preset's rows and step, then every row one order higher across
/// at 0.9 of its own dt_crit), the step's error removed, give the estimate of the relative
/// L2 error in band over the record ([`Estimate::waveform_of`]); it is within a factor 2 of
/// the true error at every receiver, v_y and v_x. Measured: quick 1.33, 1.40, 1.50, 1.49
/// (v_y below 10 / 30 pairs, v_x below 10 / 30), paper 1.47, 1.48, 1.56, 1.47 (the difference
/// to the companion across alone: 0.94-1.11; the estimate states sqrt(2) times it,
/// [`trnews::accuracy::ACROSS_TAIL`]). The solution varies slowly along x (cos(pi x / 4 mm)):
/// the companions along x agree with the preset to round-off, and the companion across sees
/// the error, which comes from the S waves across the plies. When the companions along x
/// chose their own rows and steps, they saw an error across of their own: 1.4-5.2x on quick,
/// 5-12x or "refine" on paper.
#[test]
fn error_estimates_of_the_presets_hold_at_oblique_incidence() {
    use trnews::accuracy::Estimate;
    let band = TransducerSpec::default();
    for resolution in [Resolution::Quick, Resolution::Paper] {
        let spec = SceneSpec::preset(resolution);
        let main = strip_of_scene(&spec);
        let dt = STEP_FRACTION * main.dt_crit();
        let mut runs = vec![run_strip_at(&main, dt)];
        for companion in spec.companions(dt).unwrap() {
            let strip = strip_of_scene(&companion);
            let step = companion
                .time_step_s
                .unwrap_or(STEP_FRACTION * strip.dt_crit());
            runs.push(run_strip_at(&strip, step));
        }
        let truth = runs[0].errors();
        for (r, (component, depth)) in RECEIVERS.iter().enumerate() {
            let received: Vec<Signal> = runs
                .iter()
                .map(|run| band.receive(&run.traces[r]).unwrap())
                .collect();
            let traces: Vec<&Signal> = received.iter().collect();
            let e = Estimate::waveform_of(&traces, (0.0, DURATION), spec.refinement()).unwrap();
            let ratio = e.error.map_or(f64::NAN, |x| x / truth[r]);
            let name = format!(
                "{resolution:?}, {} below {} pairs",
                ["v_x", "v_y"][*component],
                PAIRS_ABOVE[*depth]
            );
            println!(
                "{name}: {} against a true {:.3e}: {ratio:.2}",
                e.describe(),
                truth[r]
            );
            assert!((0.5..=2.0).contains(&ratio), "{name}: {e:?}");
        }
    }
}
