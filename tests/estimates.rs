//! The Richardson error estimate against the true error, on plane P waves with exact
//! solutions: a homogeneous epoxy strip and an epoxy / 0-90 fabric stack on linear triangles
//! (companions at 2h and 4h), the homogeneous strip on spectral elements (companions one and
//! two orders lower).

mod common;
use common::*;
use trnews::accuracy::{Estimate, Refinement, Verdict};
use trnews::material::Material;
use trnews::signal::Signal;
use trnews::solve::{run, segment_receiver, traction_source, Quantity, RunConfig};

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
/// `size` across the strip, rows no taller), for the unit-pressure Gaussian load, at 0.9
/// dt_crit.
fn sem_trace(
    layers: &[(Material, f64)],
    order: usize,
    size: f64,
    depth: f64,
    duration: f64,
) -> Signal {
    let how = Discretisation::Sem { order, width: size };
    let strip = WaveStrip::new(how, layers, false, BottomEdge::Absorbing);
    let dt = 1e-9;
    let samples = (0..=(duration / dt).ceil() as usize)
        .map(|k| load(k as f64 * dt))
        .collect();
    let src = strip.top_traction(270.0, Signal::new(dt, 0.0, samples).unwrap());
    let receiver = strip.depth_receiver(depth, 1);
    let cfg = RunConfig {
        duration_s: duration,
        ..Default::default()
    };
    strip
        .run(&[src], &[receiver], &cfg)
        .unwrap()
        .traces
        .remove(0)
}

/// (estimate, true relative L2 error of the order-`order` trace) from the companions at
/// orders `order` - 1 and `order` - 2 on the same elements.
fn sem_estimate_and_truth(
    layers: &[(Material, f64)],
    order: usize,
    size: f64,
    depth: f64,
    duration: f64,
    exact: impl Fn(f64) -> f64,
) -> (Estimate, f64) {
    let traces = [order, order - 1, order - 2].map(|p| sem_trace(layers, p, size, depth, duration));
    judge(traces, Refinement::Orders, exact)
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
    // The plane wave of the test above on 0.5 mm spectral elements (central differences at
    // 0.9 dt_crit, whose time error the companions share at their own, longer steps): orders
    // p - 1 and p - 2 estimate the error at order p within the issue's factor 2, reliable or
    // as a bound, for p = 4 to 8 (measured 1.66, 1.18, 1.02, 0.73, 0.63 times the true
    // error); at order 3 the three orders are not yet converging and the verdict is "refine".
    let (layers, depth, duration) = epoxy_plane_wave();
    let exact = epoxy_plane_wave_exact(depth);
    let at = |order| sem_estimate_and_truth(&layers, order, 0.5e-3, depth, duration, &exact);
    for order in 4..=8 {
        let (est, truth) = at(order);
        println!("order {order}: {} vs true {truth:.3e}", est.describe());
        assert!(
            matches!(est.verdict, Verdict::Reliable | Verdict::UpperBound),
            "order {order}: {est:?}"
        );
        let ratio = est.error.unwrap() / truth;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "order {order}: estimate / truth = {ratio}"
        );
    }
    check_refine("order 3", at(3));
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

/// A plane P wave along the layers on the quick preset's spectral elements: a 1 mm layer of
/// the 0/90 fabric, 20 mm long, rollers on the top and bottom (u_y held), a uniform traction
/// p(t) along +x on the left edge, an absorbing right edge; v_x at x = 10 mm, averaged over
/// the height, is v(t) = p(t - x / c) / (rho c) with c the P speed along x, until the right
/// edge's reflection returns. The preset's cut (order 7 along x on 0.5 mm, orders 2-4 across
/// by the rule), each run at 0.9 of its dt_crit with the step's error removed as a scene does.
fn along_the_layers(cut: &trnews::sem::SemSpec) -> (Signal, Signal) {
    use trnews::mesh::Side;
    use trnews::scene::TimeDispersionSpec;
    use trnews::sem::SemModel;
    use trnews::solve::time_dispersion::TimeDispersion;
    use trnews::solve::{run_central_difference_on, Integrator, Receiver, Source};
    let (fabric, height, length, at) = (fabric(), 1e-3, 20e-3, 10e-3);
    let mut m = SemModel::layered(&laminate(&[(fabric.clone(), height)]), length, cut).unwrap();
    let (nx, rows) = (m.nx(), m.y_nodes_m.len());
    m.fixed_dofs = (0..nx)
        .flat_map(|i| [2 * m.node(i, 0) + 1, 2 * m.node(i, rows - 1) + 1])
        .collect();
    m.dashpots = m.lysmer_dashpots(&[Side::Right]);
    let mut free = vec![true; m.dofs()];
    for &d in &m.fixed_dofs {
        free[d] = false;
    }
    let dt_crit = 2.0 / m.max_eigenvalue(&free).0.sqrt();
    let dt = 0.9 * dt_crit;
    let speed = fabric.wave_speeds().p_x_m_s;
    let duration = at / speed + 8.0 * WIDTH;
    let n = (duration / dt).ceil() as usize + 1;
    let pressure = Signal::new(dt, 0.0, (0..n).map(|k| load(k as f64 * dt)).collect()).unwrap();
    let up_to = TimeDispersionSpec::default().up_to_hz;
    let transforms = TimeDispersion::of_run(Integrator::Explicit, dt, up_to, "up_to_hz")
        .unwrap()
        .expect("the step covers the band");
    let edge = m.side_load(Side::Left, 0.0, height);
    let source = Source {
        weights: edge.iter().map(|&(node, w)| (2 * node, w)).collect(),
        signal: transforms.add_to_source(&pressure).unwrap(),
    };
    let column = m
        .x_nodes_m
        .iter()
        .position(|&x| (x - at).abs() < 1e-9)
        .unwrap();
    let receiver = Receiver {
        name: "x = 10 mm".into(),
        weights: edge
            .iter()
            .map(|&(node, w)| (2 * m.node(column, node / nx), w / height))
            .collect(),
        quantity: Quantity::Velocity,
    };
    let config = RunConfig {
        duration_s: duration,
        dt_s: Some(dt),
        ..Default::default()
    };
    let out = run_central_difference_on(&m, dt_crit, &[source], &[receiver], &config).unwrap();
    let trace = transforms
        .remove_from_trace(&out.traces[0], Quantity::Velocity)
        .unwrap();
    let z = fabric.density_kg_m3 * speed;
    let exact: Vec<f64> = (0..trace.len())
        .map(|k| load(trace.time_at(k) - at / speed) / z)
        .collect();
    let exact = Signal::new(trace.dt_s, trace.t0_s, exact).unwrap();
    (trace, exact)
}

/// Issue #25's plane wave along the layers: the quick preset's cut and its companions
/// ([`trnews::scene::SceneSpec::companions`]: orders 6 and 5 along x, then every row one
/// order higher across) give an estimate within a factor 2 of the true error, with the error
/// along x named as the dominant source (the wave does not vary across the layer, so the
/// companion across sees only round-off and the steps' residue).
#[test]
fn estimate_of_the_quick_preset_on_a_plane_wave_along_the_layers() {
    use trnews::accuracy::Source;
    use trnews::scene::{Resolution, SceneSpec};
    let spec = SceneSpec::preset(Resolution::Quick);
    let cuts: Vec<trnews::sem::SemSpec> = std::iter::once(spec.clone())
        .chain(spec.companions().unwrap())
        .map(|s| s.discretisation.sem_cut(&s).unwrap())
        .collect();
    let runs: Vec<(Signal, Signal)> = cuts.iter().map(along_the_layers).collect();
    let traces: Vec<&Signal> = runs.iter().map(|r| &r.0).collect();
    let (main, exact) = &runs[0];
    let window = (0.0, main.t_end_s());
    let e = Estimate::waveform_of(&traces, window, Refinement::Orders).unwrap();
    let truth = rel_l2(&main.samples, &exact.samples);
    let ratio = e.error.unwrap() / truth;
    println!(
        "along the layers, quick preset: {} vs true {truth:.3e}: {ratio:.2}",
        e.describe()
    );
    assert!((0.5..=2.0).contains(&ratio), "{e:?} vs {truth}");
    assert_eq!(e.dominant_source(), Some(Source::Refinement), "{e:?}");
}
