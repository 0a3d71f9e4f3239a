//! Absorbing edges at low frequency: the viscous-spring boundary against plane-wave theory,
//! and a homogeneous block that neither drifts nor depends on point supports.

mod common;
use common::*;
use rustfft::num_complex::Complex;
use trnews::fem::{AbsorbingEdge, Model, VISCOUS_SPRING_ALPHA_N, VISCOUS_SPRING_ALPHA_T};
use trnews::laminate::Laminate;
use trnews::material::Material;
use trnews::mesh::{Mesh, Side};
use trnews::scene::{
    Absorber, LaminateSpec, LayerSpec, MaterialSpec, ReceiverSpec, Scene, SceneSpec,
    TransmitterSpec,
};
use trnews::signal::{self, FilterKind, Signal};
use trnews::solve::{run, RunConfig};

/// Spring distance R of the tests (m).
const R: f64 = 10e-3;

/// What loads the edge.
#[derive(Clone, Copy, PartialEq)]
enum Load {
    /// Nothing: a free edge.
    Free,
    /// Dashpots rho Vp normal, rho Vs tangential (Lysmer-Kuhlemeyer).
    Dashpot,
    /// The dashpots and springs ALPHA G / R.
    ViscousSpring,
}

/// Reflection of a plane P wave of frequency `f_hz` arriving at `angle_deg` from the normal
/// on an edge of an isotropic medium with the given load: (reflected P amplitude over incident, reflected energy flux
/// fraction P + SV). The medium lies at y > 0 above the edge y = 0; u is a sum of the
/// incident P (polarised along its direction), the reflected P and the reflected SV, each
/// exp(i w (t - s x -+ eta y)); the edge condition is sigma_yy = c_N v_y + k_N u_y,
/// sigma_xy = c_T v_x + k_T u_x (the traction on the outward normal -y balances the
/// resisting load).
fn plane_wave_reflection(m: &Material, f_hz: f64, angle_deg: f64, load: Load) -> (f64, f64) {
    let rho = m.density_kg_m3;
    let w = m.wave_speeds();
    let (vp, vs) = (w.p_y_m_s, w.s_m_s);
    let mu = rho * vs * vs;
    let lambda = rho * vp * vp - 2.0 * mu;
    let omega = 2.0 * std::f64::consts::PI * f_hz;
    let (st, ct) = angle_deg.to_radians().sin_cos();
    let s = st / vp;
    let (sp, cp) = (s * vs, (1.0 - (s * vs).powi(2)).sqrt());
    let (eta_p, eta_s) = (ct / vp, cp / vs);
    let i = Complex::new(0.0, 1.0);
    let spring = if load == Load::ViscousSpring {
        mu / R
    } else {
        0.0
    };
    let dashpot = if load == Load::Free { 0.0 } else { rho };
    let (k_n, k_t) = (
        VISCOUS_SPRING_ALPHA_N * spring,
        VISCOUS_SPRING_ALPHA_T * spring,
    );
    let (z_n, z_t) = (
        i * omega * dashpot * vp + k_n,
        i * omega * dashpot * vs + k_t,
    );
    // Each wave: polarisation (dx, dy) and vertical slowness eta_y (d/dy = i w eta_y).
    let waves = [
        ([st, -ct], eta_p),  // incident P, travelling toward -y
        ([st, ct], -eta_p),  // reflected P
        ([cp, -sp], -eta_s), // reflected SV
    ];
    // (sigma_yy - z_n u_y, sigma_xy - z_t u_x) at y = 0 per unit amplitude of each wave.
    let residual = |(d, eta): ([f64; 2], f64)| {
        let (dx, dy) = (-i * omega * s, i * omega * eta);
        let syy = lambda * (dx * d[0] + dy * d[1]) + 2.0 * mu * dy * d[1];
        let sxy = mu * (dy * d[0] + dx * d[1]);
        [syy - z_n * d[1], sxy - z_t * d[0]]
    };
    let [a, b, c] = waves.map(residual);
    // b B + c C = -a
    let det = b[0] * c[1] - b[1] * c[0];
    let big_b = (-a[0] * c[1] + a[1] * c[0]) / det;
    let big_c = (-b[0] * a[1] + b[1] * a[0]) / det;
    let flux = big_b.norm_sqr() + big_c.norm_sqr() * (vs * cp) / (vp * ct.max(1e-300));
    (big_b.norm(), flux)
}

fn epoxy_strip(length: f64, h: f64, springs: bool) -> Model {
    let lam = Laminate::homogeneous(epoxy(), length).unwrap();
    let mesh = Mesh::layered(&lam, 4.0 * h, h, h, &[], &[]).unwrap();
    let rollers: Vec<usize> = [Side::Left, Side::Right]
        .iter()
        .flat_map(|&s| mesh.side_nodes(s))
        .map(|n| 2 * n)
        .collect();
    let edges = [
        Side::Top.into(),
        AbsorbingEdge {
            side: Side::Bottom,
            spring_distance_m: springs.then_some(R),
        },
    ];
    Model::build(mesh, lam.materials, &edges, rollers, None).unwrap()
}

/// Fourier transform sum_k x_k exp(-2 pi i f t_k) dt of a trace at one frequency.
fn dtft(s: &Signal, f_hz: f64) -> Complex<f64> {
    s.samples
        .iter()
        .enumerate()
        .map(|(k, &x)| {
            let phase = -2.0 * std::f64::consts::PI * f_hz * s.time_at(k);
            x * Complex::from_polar(s.dt_s, phase)
        })
        .sum()
}

#[test]
fn viscous_spring_edge_reflects_as_plane_wave_theory_from_50_khz_to_1_mhz() {
    // A P pulse at normal incidence in a 1D epoxy strip (rollers), the top edge absorbing
    // the return. The bottom-edge reflection is the difference between the trace with the
    // viscous-spring bottom and with the dashpot bottom (which reflects nothing at normal
    // incidence: measured below 1e-3 here); its spectrum over the incident one is |R(f)|,
    // against k / sqrt(k^2 + (2 w Z)^2). 300 us spans over six spring time constants
    // 2 Z / k = 47 us. Tolerance 2% of |R|: 100 um elements give > 25 per wavelength at
    // 1 MHz, so mesh reflection and dispersion are far below it (measured: 0.1-0.3%).
    let h = 100e-6;
    let pulse = gaussian(20e-9, 3e-6, 1e-6, 0.3e-6, 1e3);
    let trace = |springs: bool| {
        let model = epoxy_strip(10e-3, h, springs);
        let src = top_traction(&model, 270.0, pulse.clone());
        let recv = [depth_receiver(&model, 5e-3, 1)];
        // One step for both runs (the springs raise omega_max slightly), below both limits.
        let cfg = RunConfig {
            duration_s: 300e-6,
            dt_s: Some(20e-9),
            ..Default::default()
        };
        run(&model, &[src], &recv, &cfg).unwrap().traces.remove(0)
    };
    let (dashpot, spring) = (trace(false), trace(true));
    let reflected = spring.sub(&dashpot).unwrap();
    let e = epoxy();
    let z = e.impedance_p_y();
    let k = VISCOUS_SPRING_ALPHA_N * e.density_kg_m3 * e.wave_speeds().s_m_s.powi(2) / R;
    println!(
        "f (MHz)  |R| measured  |R| theory (viscous-spring, normal incidence, epoxy, R = 10 mm)"
    );
    for f in [0.05e6, 0.1e6, 0.2e6, 0.5e6, 1e6] {
        let measured = dtft(&reflected, f).norm() / dtft(&dashpot, f).norm();
        let omega = 2.0 * std::f64::consts::PI * f;
        let theory = k / (k * k + (2.0 * omega * z).powi(2)).sqrt();
        let (plane, _) = plane_wave_reflection(&e, f, 0.0, Load::ViscousSpring);
        println!("{:7.2}  {measured:12.5}  {theory:10.5}", f / 1e6);
        assert!((plane - theory).abs() < 1e-12, "plane-wave solver at 0 deg");
        assert!(
            (measured / theory - 1.0).abs() < 0.02,
            "{f} Hz: {measured} vs {theory}"
        );
    }
}

#[test]
fn plane_wave_reflection_of_a_free_edge_matches_the_textbook_and_absorbers_are_tabulated() {
    // Check of the solver: with no load the edge is free, and the P-P coefficient is Aki &
    // Richards' (5.27) R = (-(1/b^2 - 2p^2)^2 + 4p^2 cos i/a cos j/b) / (+ the same), energy
    // conserved (flux fraction 1).
    let e = epoxy();
    let w = e.wave_speeds();
    let (a, b) = (w.p_y_m_s, w.s_m_s);
    let free = |deg: f64| {
        let p = deg.to_radians().sin() / a;
        let (ci, cj) = (deg.to_radians().cos(), (1.0 - (p * b).powi(2)).sqrt());
        let q = (1.0 / (b * b) - 2.0 * p * p).powi(2);
        let r = 4.0 * p * p * ci / a * cj / b;
        ((r - q) / (q + r)).abs()
    };
    for deg in [0.0, 20.0, 45.0, 70.0] {
        let (rpp, flux) = plane_wave_reflection(&e, 1e6, deg, Load::Free);
        assert!(
            (rpp - free(deg)).abs() < 1e-12,
            "{deg} deg: {rpp} vs {}",
            free(deg)
        );
        assert!((flux - 1.0).abs() < 1e-12, "{deg} deg: flux {flux}");
    }
    println!("Reflected energy fraction of a plane P wave in epoxy (R = 10 mm for the springs)");
    println!("f (MHz) angle  dashpot  viscous-spring");
    for f in [0.05e6, 0.2e6, 1e6] {
        for deg in [0.0, 30.0, 60.0] {
            let (_, lk) = plane_wave_reflection(&e, f, deg, Load::Dashpot);
            let (_, vs) = plane_wave_reflection(&e, f, deg, Load::ViscousSpring);
            println!("{:6.2} {deg:5.0}  {lk:7.4}  {vs:7.4}", f / 1e6);
        }
    }
    // At normal incidence the dashpots reflect nothing; the springs' reflection falls with
    // frequency as k / sqrt(k^2 + (2 w Z)^2).
    assert!(plane_wave_reflection(&e, 1e6, 0.0, Load::Dashpot).1 < 1e-24);
    let spring_at = |f: f64| plane_wave_reflection(&e, f, 0.0, Load::ViscousSpring).1;
    assert!(spring_at(0.05e6) > spring_at(0.2e6) && spring_at(0.2e6) > spring_at(1e6));
}

/// The default scene's geometry as a homogeneous 12 x 6 mm epoxy block, raw displacement,
/// no crack, element size `h`.
fn block(h: f64, absorber: Absorber, fix_bottom_corners: bool) -> SceneSpec {
    SceneSpec {
        laminate: LaminateSpec::Layers {
            layers: vec![LayerSpec {
                material: MaterialSpec::Preset("epoxy".into()),
                thickness_m: 6e-3,
            }],
        },
        width_m: 12e-3,
        element_size_x_m: h,
        element_size_y_m: h,
        absorber,
        fix_bottom_corners,
        transducer: None,
        transmitter: TransmitterSpec {
            depth_top_m: 1e-3,
            depth_bottom_m: 3e-3,
            ..Default::default()
        },
        receivers: ReceiverSpec {
            x_m: vec![3e-3, 6e-3, 9e-3],
            ..Default::default()
        },
        crack: None,
        ..Default::default()
    }
}

/// Per receiver: (relative L2 change of the trace below 0.2 MHz from h to h/2, largest
/// |u| over the last 20 us of a 150 us run relative to the largest |u|, on the h/2 mesh).
/// The drive is the 0.2-2 MHz chirp, 10 us long, 50 kPa.
fn low_band_convergence_and_tail(absorber: Absorber, fix: bool) -> Vec<(f64, f64)> {
    let duration = 150e-6;
    let low_band = |h: f64| {
        let scene = Scene::build(&block(h, absorber, fix)).unwrap();
        let chirp = signal::ChirpSpec {
            t1_s: 10e-6,
            total_s: 10e-6,
            ..Default::default()
        };
        let drive = chirp.signal(scene.default_dt_s(), 50e3).unwrap();
        let out = scene.transmit(&drive, &scene.run_config(duration)).unwrap();
        let lp = signal::butterworth(4, FilterKind::LowPass(0.2e6), 1.0 / 20e-9).unwrap();
        out.traces
            .iter()
            .map(|t| {
                let coarse = signal::resample(t, 20e-9).unwrap();
                let low = signal::filtfilt(&lp, &coarse).unwrap();
                let tail = t.window(duration - 20e-6, duration).unwrap().max_abs() / t.max_abs();
                (low, tail)
            })
            .collect::<Vec<_>>()
    };
    let (coarse, fine) = (low_band(100e-6), low_band(50e-6));
    coarse
        .iter()
        .zip(&fine)
        .map(|((c, _), (f, tail))| {
            let n = c.len().min(f.len());
            let cut = |s: &Signal| Signal::new(s.dt_s, 0.0, s.samples[..n].to_vec()).unwrap();
            (signal::relative_l2(&cut(c), &cut(f), None).unwrap(), *tail)
        })
        .collect()
}

#[test]
fn viscous_spring_block_converges_below_the_band_and_does_not_drift() {
    // The bound: the trace below the band within 2% between h and h/2 (100 and 50 um:
    // 25+ elements per wavelength below 0.2 MHz), and back near zero after the source ends
    // (last 20 us below 1% of the peak: the block is held by the edges, not drifting).
    // Measured: changes 0.3-0.6%, tails below 0.1%. The report's edges fail one or the
    // other, which shows the test discriminates: pinned corners change the low band by
    // 3.5-9.5% (a point support's compliance depends on the mesh), dashpots alone leave
    // the block drifting (tails 1.5-24%).
    let springs = low_band_convergence_and_tail(
        Absorber::ViscousSpring {
            source_distance_m: None,
        },
        false,
    );
    let pinned = low_band_convergence_and_tail(Absorber::Dashpot, true);
    let drifting = low_band_convergence_and_tail(Absorber::Dashpot, false);
    println!("viscous-spring: {springs:?}\npinned corners: {pinned:?}\ndashpots: {drifting:?}");
    for (change, tail) in &springs {
        assert!(*change < 0.02 && *tail < 0.01, "{change} {tail}");
    }
    assert!(pinned.iter().any(|(change, _)| *change > 0.02));
    assert!(drifting.iter().any(|(_, tail)| *tail > 0.05));
}
