//! A plane P wave scattered by a circular hole, on spectral elements over Gmsh's curved
//! unstructured quadrilaterals, against the exact series of Pao and Mow
//! ([`trnews::exact::hole`]).
//!
//! The specimen (tests/scripts/gmsh_hole.msh, written by gmsh_quads.py) is a 36 mm square of
//! epoxy with a hole of radius a = 1 mm at its centre, 2,083 9-node elements from 0.4 mm on
//! the hole to 1.2 mm far from it. A uniform normal traction on the top edge, roller sides
//! and a dashpot bottom make a plane P wave travelling down (the rollers hold it exactly: no
//! corner diffracts); it reaches the hole 17 mm below. The hole's surface is free. Until the
//! waves the hole scatters come back from the square's edges (at least 32.5 mm there and
//! back at c_p, after the incident front reaches the hole), the receivers see what an
//! infinite plate would: the series' field. The drive is a Ricker pulse (tau = 0.6 us,
//! displacement spectrum peaking at 0.38 MHz: alpha a = 0.9, beta a = 2.2 there; 0.2% of
//! the peak left above 1.5 MHz).

mod common;

use common::{epoxy, gmsh_mesh, plane_wave_scene, rel_l2};
use trnews::exact::hole::CircularHole;
use trnews::scene::{ReceiverAt, ReceiverSpec, Scene, SceneSpec};
use trnews::signal::Signal;
use trnews::solve::RunConfig;

/// The square's side (m); the hole's centre is at its middle.
const SIDE: f64 = 36e-3;
/// The hole's radius (m).
const RADIUS: f64 = 1e-3;
/// The Ricker drive: centre time and width (s), late enough to start at 1e-7 of its peak.
const T0: f64 = 2.5e-6;
const TAU: f64 = 0.6e-6;
/// Receivers in the hole's frame: (r / a, angle from the incident direction, degrees).
/// 0 is the shadow side behind the hole, 180 the lit side facing the source.
const RECEIVERS: [(f64, f64); 6] = [
    (1.5, 0.0),
    (1.5, 45.0),
    (1.5, 90.0),
    (1.5, 135.0),
    (1.5, 180.0),
    (2.5, 90.0),
];

/// The receivers in scene coordinates: the incident direction x' is -y, y' = x.
fn scene_points() -> Vec<(f64, f64)> {
    RECEIVERS
        .iter()
        .map(|&(r, deg)| {
            let (xp, yp) = (
                r * RADIUS * deg.to_radians().cos(),
                r * RADIUS * deg.to_radians().sin(),
            );
            (0.5 * SIDE + yp, 0.5 * SIDE - xp)
        })
        .collect()
}

/// The scene on spectral elements of `order`, recording `component` (0: u_x, 1: u_y).
fn spec(order: usize, component: usize) -> SceneSpec {
    SceneSpec {
        gmsh: Some(gmsh_mesh("gmsh_hole.msh", &[("1", "epoxy")], Some(order))),
        receivers: ReceiverSpec {
            x_m: vec![],
            component,
            at: scene_points()
                .into_iter()
                .map(|(x, y)| ReceiverAt {
                    edge: None,
                    x_m: Some(x),
                    y_m: Some(y),
                    depth_m: None,
                })
                .collect(),
            ..Default::default()
        },
        ..plane_wave_scene()
    }
}

/// The window free of the square's edges: the incident front (the drive's start) reaches
/// the hole at (SIDE / 2 - a) / c_p, and nothing the edges send back reaches a receiver
/// (r <= 2.5 a) before SIDE - 5 a more at c_p.
fn window_s() -> f64 {
    let cp = epoxy().wave_speeds().p_y_m_s;
    (0.5 * SIDE - RADIUS + SIDE - 5.0 * RADIUS) / cp
}

/// The Ricker drive (1 - 2 s^2) e^(-s^2), s = (t - T0) / TAU, and its integral TAU s e^(-s^2).
fn ricker(t: f64) -> f64 {
    let s = (t - T0) / TAU;
    (1.0 - 2.0 * s * s) * (-s * s).exp()
}

fn ricker_integral(t: f64) -> f64 {
    let s = (t - T0) / TAU;
    TAU * s * (-s * s).exp()
}

/// The step, the run's wall time and the traces of both components at the receivers.
fn run(order: usize) -> (f64, f64, usize, [Vec<Signal>; 2]) {
    let start = std::time::Instant::now();
    let mut dt = 0.0;
    let mut dofs = 0;
    let traces = [0, 1].map(|component| {
        let scene = Scene::build(&spec(order, component)).unwrap();
        dt = scene.default_dt_s();
        dofs = scene.dofs();
        let n = (window_s() / dt).ceil() as usize + 1;
        let drive = Signal {
            dt_s: dt,
            t0_s: 0.0,
            samples: (0..n).map(|k| ricker(k as f64 * dt)).collect(),
        };
        let config = RunConfig {
            dt_s: Some(dt),
            progress: false,
            ..scene.run_config(window_s())
        };
        scene.transmit(&drive, &config).unwrap().traces
    });
    (dt, start.elapsed().as_secs_f64(), dofs, traces)
}

/// The series' (u_x, u_y) at the receivers on the step `dt`, `n` samples: the incident
/// displacement along x' (down) at the hole's centre is -u_y = -P(t - (SIDE / 2) / c_p) / Z,
/// P the drive's integral, Z = rho c_p (the top's traction sigma_yy = Z du_y/dt there).
fn exact(dt: f64, n: usize) -> [Vec<Vec<f64>>; 2] {
    let material = epoxy();
    let cp = material.wave_speeds().p_y_m_s;
    let z = material.density_kg_m3 * cp;
    let incident = Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: (0..n)
            .map(|k| -ricker_integral(k as f64 * dt - 0.5 * SIDE / cp) / z)
            .collect(),
    };
    let hole = CircularHole::new(&material, RADIUS).unwrap();
    let frame: Vec<(f64, f64)> = RECEIVERS
        .iter()
        .map(|&(r, deg)| {
            (
                r * RADIUS * deg.to_radians().cos(),
                r * RADIUS * deg.to_radians().sin(),
            )
        })
        .collect();
    let u = hole.displacement(&incident, &frame).unwrap();
    // scene u_x = u_y', scene u_y = -u_x'
    [
        u.iter().map(|c| c[1].samples.clone()).collect(),
        u.iter()
            .map(|c| c[0].samples.iter().map(|v| -v).collect())
            .collect(),
    ]
}

/// The errors of one order's traces: (component, receiver, relative L2 error) where the
/// series' trace is not zero by symmetry, and the largest |u_x| on the incident axis (zero
/// by symmetry) as a fraction of the largest trace; printed with the run's cost.
fn errors(order: usize) -> (Vec<(usize, usize, f64)>, f64) {
    let (dt, seconds, dofs, traces) = run(order);
    let n = traces[0][0].samples.len();
    let reference = exact(dt, n);
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let largest = reference
        .iter()
        .flatten()
        .map(|r| peak(r))
        .fold(0.0, f64::max);
    let (mut out, mut off_axis) = (vec![], 0.0f64);
    for c in 0..2 {
        for (k, t) in traces[c].iter().enumerate() {
            if peak(&reference[c][k]) < 1e-12 * largest {
                off_axis = off_axis.max(peak(&t.samples) / largest);
            } else {
                out.push((c, k, rel_l2(&t.samples, &reference[c][k])));
            }
        }
    }
    let worst = out.iter().map(|e| e.2).fold(0.0, f64::max);
    eprintln!(
        "hole scattering, order {order}: worst relative L2 error {worst:.2e}, on-axis u_x \
         {off_axis:.1e}; {dofs} DOFs, {} steps of {dt:.3e} s, {seconds:.1} s for both runs",
        n - 1
    );
    (out, off_axis)
}

/// Orders 4 and 5 against the series at 6 receivers (1.5 a around the hole and 2.5 a at
/// its side), u_x and u_y, relative L2 over the window. Measured (errors by trace): order
/// 4: 5.1e-4 to 7.3e-3, order 5: 1.0e-4 to 9.5e-4, 4.9-14x below order 4; on-axis u_x
/// (zero by symmetry; the mesh is not symmetric) 9.2e-4 and 2.2e-4 of the largest trace.
/// Orders 6 and 7 reach 1.3e-4 and 7.8e-5 worst, a floor of 2e-5 to 8e-5 that halving the
/// step does not move (by 1e-8): not the time step, not identified further (the hole's
/// quadratic geometry or the window). Asserted: order 5 below 2e-3 at every trace (the
/// issue's target is 0.5%), at least 3x below order 4 at each, on-axis u_x below 1e-3.
/// `HOLE_ORDERS=3,6,7` runs and prints more orders.
#[test]
fn plane_p_wave_scattered_by_a_circular_hole_matches_the_series() {
    let extra: Vec<usize> = std::env::var("HOLE_ORDERS")
        .map(|v| {
            v.split(',')
                .map(|o| o.trim().parse().expect("HOLE_ORDERS: orders"))
                .collect()
        })
        .unwrap_or_default();
    for order in extra {
        errors(order);
    }
    let (fourth, _) = errors(4);
    let (fifth, off_axis) = errors(5);
    for (&(c, k, e4), &(_, _, e5)) in fourth.iter().zip(&fifth) {
        let at = (c, RECEIVERS[k]);
        assert!(e5 < 2e-3, "order 5, u_{c} at {at:?}: {e5:.3e}");
        assert!(
            e5 * 3.0 < e4,
            "order 4 to 5, u_{c} at {at:?}: {e4:.3e} to {e5:.3e}"
        );
    }
    assert!(off_axis < 1e-3, "on-axis u_x: {off_axis:e}");
}
