//! Wave propagation against analytic results: speeds, interface reflection, absorbing edges,
//! on linear triangles and on spectral elements (the same checks, the same tolerances).

mod common;
use common::*;
use trnews::solve::RunConfig;

/// Pulse: Gaussian of width 0.15 us (spectrum negligible above ~4 MHz), elements of 25 um
/// give > 25 elements per shortest epoxy P wavelength, so mesh dispersion is far below 1%.
const WIDTH: f64 = 0.15e-6;
const H: f64 = 25e-6;
/// The two discretisations: T3 at h = 25 um, and order-4 spectral elements 0.1 mm wide and
/// high (the same mean node spacing).
const BOTH: [Discretisation; 2] = [
    Discretisation::T3 { h: H },
    Discretisation::Sem {
        order: 4,
        width: 4.0 * H,
    },
];

fn cfg(duration: f64) -> RunConfig {
    RunConfig {
        duration_s: duration,
        ..Default::default()
    }
}

/// Arrival picked as the time of the velocity peak (parabolic interpolation) at two depths;
/// speed = depth difference / time difference, which cancels the source's own delay.
fn measured_speed(how: Discretisation, shear: bool) -> f64 {
    let strip = WaveStrip::new(how, &[(epoxy(), 8e-3)], shear, BottomEdge::Absorbing);
    let (angle, comp) = if shear { (0.0, 0) } else { (270.0, 1) };
    let src = strip.top_traction(angle, gaussian(1e-9, 6e-6, 0.6e-6, WIDTH, 1e3));
    let recv = [
        strip.depth_receiver(1e-3, comp),
        strip.depth_receiver(4e-3, comp),
    ];
    let out = strip.run(&[src], &recv, &cfg(6e-6)).unwrap();
    let (t1, _) = peak(&out.traces[0], 0.0, 6e-6);
    let (t2, _) = peak(&out.traces[1], 0.0, 6e-6);
    3e-3 / (t2 - t1)
}

#[test]
fn p_and_s_arrivals_match_material_speeds_within_2_percent() {
    let w = epoxy().wave_speeds();
    for how in BOTH {
        let vp = measured_speed(how, false);
        let vs = measured_speed(how, true);
        eprintln!(
            "{how:?}: Vp {vp:.1} m/s ({}), Vs {vs:.1} m/s ({})",
            w.p_y_m_s, w.s_m_s
        );
        assert!(
            (vp / w.p_y_m_s - 1.0).abs() < 0.02,
            "{how:?}: Vp measured {vp}, expected {}",
            w.p_y_m_s
        );
        assert!(
            (vs / w.s_m_s - 1.0).abs() < 0.02,
            "{how:?}: Vs measured {vs}, expected {}",
            w.s_m_s
        );
    }
}

#[test]
fn interface_reflection_and_transmission_match_impedance_ratios() {
    // Epoxy (Z1) over 0/90 fabric (Z2), P wave at normal incidence from the top. We measure
    // particle velocity, whose coefficients are R_v = (Z1 - Z2)/(Z1 + Z2) = -R_stress and
    // T_v = 2 Z1/(Z1 + Z2) = (Z1/Z2) T_stress, with R_stress = (Z2 - Z1)/(Z2 + Z1) and
    // T_stress = 2 Z2/(Z1 + Z2). Tolerance 3% (issue), of the incident amplitude.
    for how in BOTH {
        interface_coefficients(how);
    }
}

fn interface_coefficients(how: Discretisation) {
    let (e, f) = (epoxy(), fabric());
    let (z1, z2) = (e.impedance_p_y(), f.impedance_p_y());
    let layers = [(e, 4e-3), (f.clone(), 6e-3)];
    let strip = WaveStrip::new(how, &layers, false, BottomEdge::Absorbing);
    let src = strip.top_traction(270.0, gaussian(1e-9, 5e-6, 0.6e-6, WIDTH, 1e3));
    let recv = [strip.depth_receiver(2e-3, 1), strip.depth_receiver(5e-3, 1)];
    let out = strip.run(&[src], &recv, &cfg(5e-6)).unwrap();
    let vp1 = epoxy().wave_speeds().p_y_m_s;
    let t_inc = 0.6e-6 + 2e-3 / vp1;
    let t_ref = 0.6e-6 + 6e-3 / vp1;
    let (_, incident) = peak(&out.traces[0], t_inc - 0.5e-6, t_inc + 0.5e-6);
    let (_, reflected) = peak(&out.traces[0], t_ref - 0.5e-6, t_ref + 0.5e-6);
    let t_tr = 0.6e-6 + 4e-3 / vp1 + 1e-3 / f.wave_speeds().p_y_m_s;
    let (_, transmitted) = peak(&out.traces[1], t_tr - 0.5e-6, t_tr + 0.5e-6);
    let r_v = (z1 - z2) / (z1 + z2);
    let t_v = 2.0 * z1 / (z1 + z2);
    let (r, t) = (reflected / incident, transmitted / incident);
    eprintln!("{how:?}: R {r:.4} ({r_v:.4}), T {t:.4} ({t_v:.4})");
    assert!(
        (r - r_v).abs() < 0.03,
        "{how:?}: R measured {r}, expected {r_v}"
    );
    assert!(
        (t - t_v).abs() < 0.03,
        "{how:?}: T measured {t}, expected {t_v}"
    );
}

/// Peak velocity of the wave reflected by the bottom edge over the incident peak, at mid-depth.
fn bottom_reflection(how: Discretisation, bottom: BottomEdge) -> f64 {
    let strip = WaveStrip::new(how, &[(epoxy(), 6e-3)], false, bottom);
    let src = strip.top_traction(270.0, gaussian(1e-9, 5e-6, 0.6e-6, WIDTH, 1e3));
    let recv = [strip.depth_receiver(3e-3, 1)];
    let out = strip.run(&[src], &recv, &cfg(5e-6)).unwrap();
    let vp = epoxy().wave_speeds().p_y_m_s;
    let (t_inc, t_ref) = (0.6e-6 + 3e-3 / vp, 0.6e-6 + 9e-3 / vp);
    let (_, incident) = peak(&out.traces[0], t_inc - 0.5e-6, t_inc + 0.5e-6);
    let (_, reflected) = peak(&out.traces[0], t_ref - 0.5e-6, t_ref + 0.5e-6);
    reflected / incident
}

#[test]
fn absorbing_edge_reflects_under_5_percent_and_fixed_edge_all() {
    for how in BOTH {
        let absorbed = bottom_reflection(how, BottomEdge::Absorbing);
        // A fixed end reflects velocity with the opposite sign and (lossless) full
        // amplitude; 2% allows for the pulse's small numerical dispersion over the longer path.
        let fixed = bottom_reflection(how, BottomEdge::Fixed);
        eprintln!("{how:?}: absorbing edge reflects {absorbed:.4}, fixed edge {fixed:.4}");
        assert!(
            absorbed.abs() < 0.05,
            "{how:?}: absorbing edge reflects {absorbed}"
        );
        assert!(
            (fixed + 1.0).abs() < 0.02,
            "{how:?}: fixed edge reflects {fixed}"
        );
    }
}
