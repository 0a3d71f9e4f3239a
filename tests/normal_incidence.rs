//! Normal incidence through the default experiment's 50-pair stochastic laminate, against the
//! exact transfer-matrix solution ([`trnews::exact::NormalIncidence`]; issue #25). The strip of
//! the laminate (rollers on the sides, absorbing bottom) under a uniform pressure pulse on the
//! top carries the exact 1-D plane wave; its velocity below 30 pairs and below all 50, seen
//! through the transducers' 0.2-2 MHz band on transmission and reception, is compared with
//! the exact one by the relative L2 error. Discretisations: a resolved spectral-element
//! reference (which shows the exact solution and the discretisations agree), the presets'
//! spectral elements, and their linear triangles.

mod common;
use common::*;
use rustfft::num_complex::Complex64;
use std::time::Instant;
use trnews::exact::{NormalIncidence, StackLayer};
use trnews::laminate::{Laminate, StochasticSpec};
use trnews::material::Plane;
use trnews::scene::{
    DiscretisationKind, LaminateSpec, Resolution, SceneSpec, SemPreset, STEP_FRACTION,
};
use trnews::sem::{SemModel, SemSpec};
use trnews::signal::Signal;
use trnews::solve::RunConfig;
use trnews::transducer::TransducerSpec;

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

/// The exact solution, check (i): one epoxy layer over the matched half-space is a
/// homogeneous half-space, so at depth d (at the top, in the layer, below it) v(t) =
/// -p(t - d / c) / Z, a delayed copy of the pressure over the impedance, to 1e-10 of the peak
/// p / Z (the wrap-around bound is 1e-12, the Gaussian's value at t = 0 e^-36).
#[test]
fn exact_homogeneous_stack_delays_the_pressure_over_the_impedance() {
    let e = epoxy();
    let stack = NormalIncidence::new(vec![StackLayer::new(&e, 1e-3)]).unwrap();
    let (c, z) = (e.wave_speeds().p_y_m_s, e.impedance_p_y());
    let (p, load) = pulse(0.1e-6, 0.6e-6, 3e-6);
    for depth in [0.0, 0.5e-3, 1.5e-3] {
        let v = stack.velocity(&load, depth).unwrap();
        let error = worst(&v, |t| -p(t - depth / c) / z, f64::INFINITY, 1.0 / z);
        assert!(error < 1e-10, "depth {depth}: {error:e}");
    }
}

/// The exact solution, check (ii): epoxy (1 mm) over 0/90 fabric (1 mm, then its
/// half-space). In the epoxy, 0.4 mm down: the incident wave and the interface's reflection,
/// R = (Z1 - Z2) / (Z1 + Z2) in velocity, until that reflection returns from the free top; in
/// the fabric, 0.5 mm below the interface: the transmitted wave, T = 2 Z1 / (Z1 + Z2), until
/// the next one, 2 d1 / c1 later. To 1e-10 of the incident peak p / Z1.
#[test]
fn exact_interface_reflects_and_transmits_the_plane_wave_coefficients() {
    let (e, f) = (epoxy(), fabric());
    let d1 = 1e-3;
    let layers = vec![StackLayer::new(&e, d1), StackLayer::new(&f, 1e-3)];
    let stack = NormalIncidence::new(layers).unwrap();
    let (c1, c2) = (e.wave_speeds().p_y_m_s, f.wave_speeds().p_y_m_s);
    let (z1, z2) = (e.impedance_p_y(), f.impedance_p_y());
    let (reflected, transmitted) = ((z1 - z2) / (z1 + z2), 2.0 * z1 / (z1 + z2));
    let (width, centre) = (0.03e-6, 0.2e-6);
    let (p, load) = pulse(width, centre, 2e-6);
    // Until 6 widths before the next arrival's centre (the pulse is e^-36 there).
    let until = |arrival: f64| arrival + centre - 6.0 * width;

    let d = 0.4e-3;
    let v = stack.velocity(&load, d).unwrap();
    let expected = |t: f64| -(p(t - d / c1) + reflected * p(t - (2.0 * d1 - d) / c1)) / z1;
    let error = worst(&v, expected, until((2.0 * d1 + d) / c1), 1.0 / z1);
    assert!(error < 1e-10, "in the epoxy: {error:e}");

    let arrival = d1 / c1 + 0.5e-3 / c2;
    let v = stack.velocity(&load, d1 + 0.5e-3).unwrap();
    let expected = |t: f64| -transmitted * p(t - arrival) / z1;
    let error = worst(&v, expected, until(arrival + 2.0 * d1 / c1), 1.0 / z1);
    assert!(error < 1e-10, "in the fabric: {error:e}");
}

/// The report's stochastic laminate of `pairs` pairs (seed 1) as a normal-incidence stack,
/// and its height.
fn stochastic_stack(pairs: usize) -> (NormalIncidence, f64) {
    let spec = StochasticSpec {
        pairs,
        ..Default::default()
    };
    let lam = Laminate::stochastic(&spec, Plane::Strain).unwrap();
    (
        NormalIncidence::of_laminate(&lam).unwrap(),
        lam.thickness_m(),
    )
}

/// The exact solution, check (iii), per frequency: the time-averaged power the pressure puts
/// into the top, Re(-P conj V(0)) / 2, leaves through the bottom into the half-space,
/// Z_b |V(H)|^2 / 2 (a lossless stack stores none on average). With P = 1: Re(-H(omega, 0))
/// = Z_b |H(omega, H)|^2 for the 50-pair laminate from 10 kHz to 10 MHz, to 1e-12 of |H(omega,
/// 0)| (round-off through 100 layers' matrices; measured 4e-14).
#[test]
fn exact_power_put_in_at_the_top_leaves_through_the_bottom() {
    let (stack, height) = stochastic_stack(50);
    let z_b = stack.half_space().impedance();
    let mut worst = 0f64;
    for f in (0..=1000).map(|k| 1e4 * 1000f64.powf(k as f64 / 1000.0)) {
        let omega = Complex64::new(2.0 * std::f64::consts::PI * f, 0.0);
        let top = stack.velocity_per_pressure(omega, 0.0);
        let radiated = z_b * stack.velocity_per_pressure(omega, height).norm_sqr();
        worst = worst.max((-top.re - radiated).abs() / top.norm());
    }
    println!("largest power imbalance {worst:e} of |H(omega, 0)|");
    assert!(worst < 1e-12, "{worst:e}");
}

/// The exact solution, check (iii), in time: the work of a pressure pulse on the top,
/// int -p v(0) dt, equals the energy radiated into the half-space, Z_b int v(H)^2 dt, once
/// the 10-pair stack has rung down (40 us), to 1e-12 (sums of samples of band-limited signals
/// are their integrals; measured 7e-14). The pulse (0.2 us) stays below ~3 MHz: a 0.1 us
/// one excites modes held near the top that still store 3e-8 of its energy after 160 us.
#[test]
fn exact_work_of_a_pulse_is_radiated_into_the_half_space() {
    let (stack, height) = stochastic_stack(10);
    let z_b = stack.half_space().impedance();
    let (_, load) = pulse(0.2e-6, 1.2e-6, 40e-6);
    let top = stack.velocity(&load, 0.0).unwrap();
    let bottom = stack.velocity(&load, height).unwrap();
    let work: f64 = load
        .samples
        .iter()
        .zip(&top.samples)
        .map(|(p, v)| -p * v)
        .sum();
    let radiated = z_b * bottom.samples.iter().map(|v| v * v).sum::<f64>();
    let imbalance = (work - radiated).abs() / work;
    println!("work {work:e}, radiated {radiated:e}: imbalance {imbalance:e}");
    assert!(imbalance < 1e-12, "{imbalance:e}");
}

/// Width w of the Gaussian drive exp(-((t - 4 w) / w)^2): its spectrum exp(-(pi f w)^2) is
/// within 10% of flat up to 2 MHz, so the band sees the whole 0.2-2 MHz range.
const WIDTH: f64 = 0.05e-6;

/// Recorded duration (s): the direct wave crosses the stack in about 2.5 us, and by 30 us the
/// exact response below 30 pairs has fallen below 1e-3 of its peak.
const DURATION: f64 = 30e-6;

/// The pairs above the first receiver.
const PAIRS_ABOVE: usize = 30;

/// The default experiment's laminate draw (the presets share it).
fn stack() -> Laminate {
    let spec = SceneSpec::preset(Resolution::Quick);
    match spec.laminate {
        LaminateSpec::Stochastic(s) => Laminate::stochastic(&s, spec.plane).unwrap(),
        other => panic!("the default experiment's laminate is stochastic, not {other:?}"),
    }
}

/// Depths (m) of the receivers: the interface below `PAIRS_ABOVE` pairs and the bottom of the
/// stack, both node rows of every discretisation.
fn receiver_depths(lam: &Laminate) -> [f64; 2] {
    let top_down = lam.layers.iter().rev().map(|l| l.thickness_m);
    [top_down.clone().take(2 * PAIRS_ABOVE).sum(), top_down.sum()]
}

/// One discretisation's run against the exact solution.
struct Measured {
    name: String,
    nodes: usize,
    dt_s: f64,
    seconds: f64,
    /// Relative L2 error in band at each receiver depth.
    errors: [f64; 2],
}

impl Measured {
    fn print(&self) {
        println!(
            "{:<44} {:>7} nodes  dt {:.3} ns  {:>6.2} s  error {:.3}% below {PAIRS_ABOVE} pairs, \
             {:.3}% below 50",
            self.name,
            self.nodes,
            self.dt_s * 1e9,
            self.seconds,
            100.0 * self.errors[0],
            100.0 * self.errors[1]
        );
    }
}

/// The pressure on the top at step `dt`: the Gaussian drive through the transducer's band.
fn pressure(dt: f64) -> Signal {
    let drive = gaussian(dt, DURATION, 4.0 * WIDTH, WIDTH, 1.0);
    TransducerSpec::default()
        .transmit(&drive, DURATION)
        .unwrap()
}

/// Relative L2 error of `trace` against `exact`, both through the receiving band, over the
/// samples they share.
fn band_error(trace: &Signal, exact: &Signal) -> f64 {
    let band = TransducerSpec::default();
    let (a, b) = (band.receive(trace).unwrap(), band.receive(exact).unwrap());
    rel_l2(&a.samples, &b.samples)
}

/// Runs `strip` at the presets' step fraction of its dt_crit under the pressure pulse and
/// compares the velocity at the receivers with the exact solution.
fn measure(name: &str, strip: WaveStrip) -> Measured {
    let lam = stack();
    let exact = NormalIncidence::of_laminate(&lam).unwrap();
    let depths = receiver_depths(&lam);
    let dt = STEP_FRACTION * strip.dt_crit();
    let load = pressure(dt);
    let source = strip.top_traction(270.0, load.clone());
    let receivers = depths.map(|d| strip.depth_receiver(d, 1));
    let config = RunConfig {
        duration_s: DURATION,
        dt_s: Some(dt),
        ..Default::default()
    };
    let clock = Instant::now();
    let traces = strip.run(&[source], &receivers, &config).unwrap().traces;
    let seconds = clock.elapsed().as_secs_f64();
    let errors = [0, 1].map(|r| band_error(&traces[r], &exact.velocity(&load, depths[r]).unwrap()));
    let m = Measured {
        name: name.into(),
        nodes: strip.nodes(),
        dt_s: dt,
        seconds,
        errors,
    };
    m.print();
    m
}

/// The spectral elements of a resolution preset (one element across the strip).
fn sem_preset(resolution: Resolution) -> SemModel {
    let p = SemPreset::of(resolution);
    let cut = SemSpec {
        order_x: p.order_x,
        max_order_y: p.max_order_y,
        element_size_x_m: p.element_size_x_m,
        element_size_y_m: p.element_size_y_m,
    };
    SemModel::layered(&stack(), p.element_size_x_m, &cut).unwrap()
}

/// The linear triangles of a resolution preset, four columns across the strip.
fn t3_preset(resolution: Resolution) -> WaveStrip {
    let s = SceneSpec::preset_on(resolution, DiscretisationKind::T3);
    let cells = (s.element_size_x_m, s.element_size_y_m);
    WaveStrip::T3(strip_of(&stack(), cells, 4, false, BottomEdge::Absorbing))
}

/// `m` with its element rows re-cut: a row of material `mat`, height `h` and order `p` across
/// becomes `cut(mat, h, p) = (n, q)`: n equal rows of order q.
fn recut(m: &SemModel, cut: impl Fn(usize, f64, usize) -> (usize, usize)) -> SemModel {
    let (mut rows, mut orders, mut materials) = (vec![m.rows_m[0]], vec![], vec![]);
    for ((w, &mat), p) in m.rows_m.windows(2).zip(&m.row_material).zip(m.row_orders()) {
        let (n, q) = cut(mat, w[1] - w[0], p);
        rows.extend((1..=n).map(|k| w[0] + (w[1] - w[0]) * k as f64 / n as f64));
        orders.extend(std::iter::repeat_n(q, n));
        materials.extend(std::iter::repeat_n(mat, n));
    }
    let order_x = m.x_nodes_m.len() / (m.columns_m.len() - 1);
    SemModel::new(
        m.columns_m.clone(),
        rows,
        order_x.max(1),
        &orders,
        m.materials.clone(),
        materials,
    )
    .unwrap()
}

/// Material index of epoxy in the stochastic laminate.
const EPOXY: usize = 0;

/// The resolved reference: every layer cut into rows no taller than `row`, order `order`
/// across, on one 0.5 mm element of order 1 along x (the 1-D solution does not vary along x).
fn resolved(order: usize, row: f64) -> SemModel {
    let one_row_per_layer = SemSpec {
        order_x: 1,
        max_order_y: 1,
        element_size_x_m: 0.5e-3,
        element_size_y_m: 1.0,
    };
    let m = SemModel::layered(&stack(), 0.5e-3, &one_row_per_layer).unwrap();
    recut(&m, |_, h, _| ((h / row).ceil() as usize, order))
}

fn sem(m: SemModel) -> WaveStrip {
    WaveStrip::sem(m, false, BottomEdge::Absorbing)
}

#[test]
#[ignore = "measurement table for issue #25 (minutes): cargo test --release --test normal_incidence -- --ignored --nocapture"]
fn table() {
    for (order, row) in [(8, 50e-6), (8, 25e-6), (10, 50e-6)] {
        measure(
            &format!("resolved: order {order}, rows <= {} um", row * 1e6),
            sem(resolved(order, row)),
        );
    }
    measure("quick SEM preset", sem(sem_preset(Resolution::Quick)));
    measure("paper SEM preset", sem(sem_preset(Resolution::Paper)));
    for n in [2, 4] {
        let m = recut(&sem_preset(Resolution::Quick), |mat, _, p| {
            if mat == EPOXY {
                (n, p)
            } else {
                (1, p)
            }
        });
        measure(&format!("quick, epoxy cut into {n} rows"), sem(m));
    }
    for q in [2, 3, 4] {
        let m = recut(&sem_preset(Resolution::Quick), |mat, _, p| {
            if mat == EPOXY {
                (1, q)
            } else {
                (1, p)
            }
        });
        measure(&format!("quick, epoxy at order {q} across"), sem(m));
    }
    measure("T3 quick (60 x 40 um)", t3_preset(Resolution::Quick));
    measure("T3 paper (20 x 10 um)", t3_preset(Resolution::Paper));
}
