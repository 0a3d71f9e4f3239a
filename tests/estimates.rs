//! The Richardson error estimate against the true error, on plane P waves with exact
//! solutions: a homogeneous epoxy strip and an epoxy / 0-90 fabric stack on linear triangles
//! (companions at 2h and 4h), the homogeneous strip on spectral elements (companions one and
//! two orders lower).

mod common;
use common::*;
use trnews::accuracy::{Estimate, Refinement, Verdict};
use trnews::material::Material;
use trnews::signal::Signal;
use trnews::solve::time_dispersion::TimeDispersion;
use trnews::solve::{run, segment_receiver, traction_source, Integrator, Quantity, RunConfig};

/// Gaussian load width (s) and centre (4 widths): spectrum down to 1e-4 of its peak at
/// 4.3 MHz, so 100 um elements carry only ~6 per shortest wavelength in epoxy.
const WIDTH: f64 = 0.1e-6;

fn load(t: f64) -> f64 {
    (-((t - 4.0 * WIDTH) / WIDTH).powi(2)).exp()
}

/// Velocity u_y at `depth` below the top for a unit-pressure Gaussian load, at 0.9 dt_crit.
fn trace(layers: &[(Material, f64)], h: f64, depth: f64, duration: f64) -> Signal {
    // Two columns, rollers on the sides, absorbing bottom: a uniform top traction launches
    // a plane P wave.
    let model = strip(layers, h, 2, false, BottomEdge::Absorbing);
    let (x0, x1, _, y1) = model.mesh.bounds();
    let y = y1 - depth;
    let receiver =
        segment_receiver(&model.mesh, "r", [x0, y], [x1, y], 1, Quantity::Velocity).unwrap();
    let dt = 0.9 * trnews::solve::stability::estimate(&model).dt_crit_s;
    let n = (duration / dt).ceil() as usize + 1;
    let samples = (0..n).map(|k| load(k as f64 * dt)).collect();
    let signal = Signal::new(dt, 0.0, samples).unwrap();
    let src = traction_source(&model.mesh, [x0, y1], [x1, y1], 270.0, signal).unwrap();
    let cfg = RunConfig {
        duration_s: duration,
        dt_s: Some(dt),
        ..Default::default()
    };
    run(&model, &[src], &[receiver], &cfg)
        .unwrap()
        .traces
        .remove(0)
}

/// (estimate, true relative L2 error of the finest trace) for sizes h, 2h, 4h.
fn estimate_and_truth(
    layers: &[(Material, f64)],
    h: f64,
    depth: f64,
    duration: f64,
    exact: impl Fn(f64) -> f64,
) -> (Estimate, f64) {
    let traces = [h, 2.0 * h, 4.0 * h].map(|s| trace(layers, s, depth, duration));
    judge(traces, Refinement::ElementSizes, exact)
}

/// (estimate from the main trace and its two companions, true relative L2 error of the main
/// trace against `exact`).
fn judge(
    [fine, medium, coarse]: [Signal; 3],
    refinement: Refinement,
    exact: impl Fn(f64) -> f64,
) -> (Estimate, f64) {
    let window = (0.0, fine.t_end_s());
    let e = Estimate::waveform(&fine, &medium, &coarse, window, refinement).unwrap();
    let truth = Signal::new(
        fine.dt_s,
        0.0,
        (0..fine.len()).map(|k| exact(fine.time_at(k))).collect(),
    )
    .unwrap();
    let err = trnews::signal::relative_l2(&fine, &truth, None).unwrap();
    (e, err)
}

/// Velocity u_y at `depth` below the top on spectral elements of `order` (one element of
/// `size` across the strip, rows no taller), for the unit-pressure Gaussian load, at the
/// step `step`, the step's error removed as a scene removes it.
fn sem_trace(
    layers: &[(Material, f64)],
    order: usize,
    size: f64,
    depth: f64,
    duration: f64,
    step: f64,
) -> Signal {
    let how = Discretisation::Sem { order, width: size };
    let strip = WaveStrip::new(how, layers, false, BottomEdge::Absorbing);
    let samples = (0..=(duration / step).ceil() as usize)
        .map(|k| load(k as f64 * step))
        .collect();
    // up to 20 MHz as a scene, or below the transforms' limit at long steps (the load's
    // spectrum is 1e-4 of its peak at 4.3 MHz)
    let up_to = (0.8 / (std::f64::consts::PI * step)).min(20e6);
    let td = TimeDispersion::of_run(Integrator::Explicit, step, up_to, "up_to_hz")
        .unwrap()
        .expect("central differences have the transforms");
    let pressure = td.add_to_source(&Signal::new(step, 0.0, samples).unwrap());
    let src = strip.top_traction(270.0, pressure.unwrap());
    let receiver = strip.depth_receiver(depth, 1);
    let cfg = RunConfig {
        duration_s: duration,
        dt_s: Some(step),
        ..Default::default()
    };
    let trace = strip
        .run(&[src], &[receiver], &td.extended(&cfg))
        .unwrap()
        .traces
        .remove(0);
    td.recorded(&trace, Quantity::Velocity, &cfg).unwrap()
}

/// (estimate, true relative L2 error of the order-`order` trace) from the companions at
/// orders `order` - 1 and `order` - 2 on the same elements, all at 0.9 of the order-`order`
/// strip's dt_crit.
fn sem_estimate_and_truth(
    layers: &[(Material, f64)],
    order: usize,
    size: f64,
    depth: f64,
    duration: f64,
    exact: impl Fn(f64) -> f64,
) -> (Estimate, f64) {
    let how = Discretisation::Sem { order, width: size };
    let step = 0.9 * WaveStrip::new(how, layers, false, BottomEdge::Absorbing).dt_crit();
    let traces =
        [order, order - 1, order - 2].map(|p| sem_trace(layers, p, size, depth, duration, step));
    judge(
        traces,
        Refinement::Orders {
            top: order,
            across: true,
            smooth: true,
        },
        exact,
    )
}

/// The homogeneous epoxy strip (4 mm), the receiver depth (2 mm) and a duration that ends
/// before the bottom's reflection returns.
fn epoxy_plane_wave() -> ([(Material, f64); 1], f64, f64) {
    let depth = 2e-3;
    let duration = depth / epoxy().wave_speeds().p_y_m_s + 8.0 * WIDTH;
    ([(epoxy(), 4e-3)], depth, duration)
}

/// v(t, d) = -p(t - d / c) / (rho c) in the homogeneous strip (no reflection in the window).
fn epoxy_plane_wave_exact(depth: f64) -> impl Fn(f64) -> f64 {
    let e = epoxy();
    let (c, z) = (e.wave_speeds().p_y_m_s, e.impedance_p_y());
    move |t| -load(t - depth / c) / z
}

/// The issue's bound: a reliable estimate within a factor 2 of the true error.
fn check_reliable(name: &str, (e, truth): (Estimate, f64)) {
    println!("{name}: {} vs true {truth:.3e}", e.describe());
    assert_eq!(e.verdict, Verdict::Reliable, "{name}: {e:?}");
    let ratio = e.error.unwrap() / truth;
    assert!(
        (0.5..=2.0).contains(&ratio),
        "{name}: estimate / truth = {ratio}"
    );
}

fn check_refine(name: &str, (e, truth): (Estimate, f64)) {
    println!("{name}: {} vs true {truth:.3e}", e.describe());
    assert_eq!(e.verdict, Verdict::Refine, "{name}: {e:?}");
}

#[test]
fn estimate_tracks_the_true_error_of_a_plane_wave_and_refuses_a_coarse_mesh() {
    let (layers, depth, duration) = epoxy_plane_wave();
    let exact = epoxy_plane_wave_exact(depth);
    check_reliable(
        "plane wave, h = 12.5 um",
        estimate_and_truth(&layers, 12.5e-6, depth, duration, &exact),
    );
    check_refine(
        "plane wave, h = 100 um",
        estimate_and_truth(&layers, 100e-6, depth, duration, &exact),
    );
}

#[test]
fn order_companions_track_the_true_error_of_spectral_elements() {
    // The plane wave of the test above on 0.5 mm spectral elements, run as a scene runs its
    // companions: every order at the main run's step (0.9 of its dt_crit), the step's error
    // removed by the time-dispersion transforms, so that the companions differ in the order
    // alone. Orders p - 1 and p - 2 estimate the error at order p within the issue's factor
    // 2 for p = 3 to 8 (measured 0.67, 0.98, 1.81, 1.10, 0.75, 1.42 times the true error),
    // from the tail fitted to the three runs ([`trnews::accuracy`]): the orders' errors
    // correlate -0.67 to 0.44, so d_1 = |y_p - y_p-1| alone would state 3-11x the truth.
    // (Before the companions shared the step, each ran at its own 0.9 dt_crit with the
    // step's error kept, and the bound d_1 was 0.63-1.66 of a truth that held the step's
    // error too.)
    let (layers, depth, duration) = epoxy_plane_wave();
    let exact = epoxy_plane_wave_exact(depth);
    let at = |order| sem_estimate_and_truth(&layers, order, 0.5e-3, depth, duration, &exact);
    for order in 3..=8 {
        let (est, truth) = at(order);
        println!("order {order}: {} vs true {truth:.3e}", est.describe());
        assert_eq!(est.verdict, Verdict::Reliable, "order {order}: {est:?}");
        let ratio = est.error.unwrap() / truth;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "order {order}: estimate / truth = {ratio}"
        );
    }
}

#[test]
fn estimate_tracks_the_true_error_through_a_layer_interface() {
    // Epoxy (2 mm) over 0/90 fabric: at 1.6 mm into the fabric the exact velocity is the
    // transmitted wave T_v (-p(t - d1/c1 - d2/c2) / Z1), T_v = 2 Z1 / (Z1 + Z2), until the
    // interface reflection, bounced off the top, arrives 2 d1 / c1 = 1.56 us later.
    let (e, f) = (epoxy(), fabric());
    let (c1, c2) = (e.wave_speeds().p_y_m_s, f.wave_speeds().p_y_m_s);
    let (z1, z2) = (e.impedance_p_y(), f.impedance_p_y());
    let (d1, d2) = (2e-3, 1.6e-3);
    let arrival = d1 / c1 + d2 / c2;
    let duration = arrival + 8.0 * WIDTH;
    let layers = [(e, d1), (f, 8e-3)];
    let t_v = 2.0 * z1 / (z1 + z2);
    let exact = |t: f64| -t_v * load(t - arrival) / z1;
    check_reliable(
        "layered, h = 12.5 um",
        estimate_and_truth(&layers, 12.5e-6, d1 + d2, duration, exact),
    );
    check_refine(
        "layered, h = 100 um",
        estimate_and_truth(&layers, 100e-6, d1 + d2, duration, exact),
    );
}

#[test]
fn a_requested_tolerance_is_met_on_a_homogeneous_block() {
    // The resolution chosen for a 3% first-pass error of the smoke chirp in a 6 x 3 mm
    // epoxy block (50 um elements to start, ~7% error there: the sizes are halved) meets it: the chosen run differs from a run at
    // a quarter of its element sizes (the reference) by less than the tolerance, and the
    // prediction made before the run is not optimistic by more than 2x.
    use std::sync::Arc;
    use trnews::scene::{
        LaminateSpec, LayerSpec, MaterialSpec, ReceiverSpec, Scene, SceneSpec, TransmitterSpec,
    };
    use trnews::study::resolution_for_tolerance;
    use trnews::trnews::{Responder, TrNewsSpec};
    let spec = SceneSpec {
        laminate: LaminateSpec::Layers {
            layers: vec![LayerSpec {
                material: MaterialSpec::Preset("epoxy".into()),
                thickness_m: 3e-3,
            }],
        },
        width_m: 6e-3,
        element_size_x_m: 50e-6,
        element_size_y_m: 50e-6,
        transmitter: TransmitterSpec {
            depth_top_m: 0.4e-3,
            depth_bottom_m: 2.0e-3,
            ..Default::default()
        },
        receivers: ReceiverSpec {
            x_m: vec![2e-3, 4e-3],
            ..Default::default()
        },
        crack: None,
        ..Default::default()
    };
    let chirp = TrNewsSpec::smoke();
    let tolerance = 0.03;
    let (chosen, choice) = resolution_for_tolerance(&spec, tolerance, &chirp).unwrap();
    println!("{choice:?}");
    assert!(choice.predicted_error <= tolerance && choice.size_factor < 1.0);
    let response = |s: &SceneSpec| {
        let r = Responder::new(Arc::new(Scene::build(s).unwrap()), chirp.record_s + 1e-6).unwrap();
        let c = chirp.chirp.signal(r.dt_s(), 50e3).unwrap();
        r.respond(&c, chirp.record_s).unwrap().traces
    };
    let (run, reference) = (
        response(&chosen),
        response(&chosen.coarsened(0.25).unwrap()),
    );
    for (y, y_ref) in run.iter().zip(&reference) {
        let y = trnews::signal::resample(y, y_ref.dt_s).unwrap();
        let n = y.len().min(y_ref.len());
        let err = rel_l2(&y.samples[..n], &y_ref.samples[..n]);
        println!(
            "chosen factor {}: error {err:.3e} (predicted {:.3e})",
            choice.size_factor, choice.predicted_error
        );
        assert!(err <= tolerance, "{err}");
        assert!(
            err <= 2.0 * choice.predicted_error,
            "{err} vs {}",
            choice.predicted_error
        );
    }
}
