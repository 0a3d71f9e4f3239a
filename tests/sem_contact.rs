//! The contact crack on spectral elements (split nodes, `SemModel::split_crack`) against the
//! same analytic results as the T3 crack in tests/contact.rs: no side effects of an open or
//! tied crack, two-bar impact, the bilinear oscillator, sliding with Coulomb friction, and
//! the energy ledger with contact.
//!
//! The bilinear oscillator here is a genuine SEM body, not a two-node spring model: two
//! element rows of order 1 across (order 4 along x), u_x held everywhere and the far lines
//! fixed, so each row is exactly one spring-mass (k = C22 w / h, m = rho w h / 2 on its
//! free line, the GLL weights of every column in the same ratio), the upper row the
//! oscillator and the lower, light and stiff row the stop, joined through a through-crack.
//! Its period, half open plus half closed, follows from the two rows' own frequencies. A
//! higher order across would make the bar a continuum whose impact has no single-mode
//! period; the two-bar test covers that case.

mod common;
use common::*;
use trnews::contact::{ContactMethod, ContactOptions};
use trnews::material::Material;
use trnews::mesh::{Crack, Side};
use trnews::sem::SemModel;
use trnews::signal::Signal;
use trnews::solve::{
    run_on, Discretisation, Integrator, Quantity, Receiver, RunConfig, RunOutput, Source,
};

/// The exact multiplier with the report's instantaneous Coulomb law, whose results the
/// analytic solutions here are.
fn exact(friction: f64) -> Option<ContactOptions> {
    Some(ContactOptions {
        method: ContactMethod::Exact,
        friction,
        normal_stress_lag_s: 0.0,
    })
}

/// `n` equal intervals of [from, to].
fn lines(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..=n)
        .map(|k| from + (to - from) * k as f64 / n as f64)
        .collect()
}

/// Critical step of `m` with its fixed DOFs held (Lanczos).
fn dt_crit(m: &SemModel) -> f64 {
    let mut free = vec![true; m.dofs()];
    for &d in &m.fixed_dofs {
        free[d] = false;
    }
    2.0 / m.max_eigenvalue(&free).0.sqrt()
}

/// Nodes of the part above a through-crack (grid rows from the crack line up) and below it
/// (grid rows under the line, and the duplicates).
fn parts(m: &SemModel, crack: &Crack) -> (Vec<usize>, Vec<usize>) {
    let line = m
        .y_nodes_m
        .iter()
        .position(|&y| y == crack.pieces_m[0][0][1])
        .expect("crack line");
    let grid = m.nx() * m.y_nodes_m.len();
    let (mut below, mut above) = (Vec::new(), Vec::new());
    for node in 0..m.dofs() / 2 {
        if node >= line * m.nx() && node < grid {
            above.push(node);
        } else {
            below.push(node);
        }
    }
    (below, above)
}

/// Mass-weighted mean velocity of `component` over `nodes` (momentum / mass).
fn mean_velocity(m: &SemModel, nodes: &[usize], component: usize, name: &str) -> Receiver {
    let total: f64 = nodes
        .iter()
        .map(|&n| m.lumped_mass[2 * n + component])
        .sum();
    Receiver {
        name: name.into(),
        weights: nodes
            .iter()
            .map(|&n| {
                let d = 2 * n + component;
                (d, m.lumped_mass[d] / total)
            })
            .collect(),
        quantity: Quantity::Velocity,
    }
}

/// A uniform traction (magnitude `signal`, direction `angle_deg`) on the whole top.
fn top_traction(m: &SemModel, angle_deg: f64, signal: Signal) -> Source {
    let (s, c) = angle_deg.to_radians().sin_cos();
    let width = m.columns_m[m.columns_m.len() - 1];
    Source {
        weights: m
            .side_load(Side::Top, 0.0, width)
            .into_iter()
            .flat_map(|(n, w)| [(2 * n, c * w), (2 * n + 1, s * w)])
            .collect(),
        signal,
    }
}

/// An epoxy square (2 mm, elements 0.25 mm of order 4) with a crack 0.5 mm below the top
/// from x = 0.5 to 1.5 mm, and the Lysmer-Kuhlemeyer bottom, unless `crack` is false.
fn cracked_square(crack: bool) -> SemModel {
    let mut m = SemModel::new(
        lines(0.0, 2e-3, 8),
        lines(0.0, 2e-3, 8),
        4,
        &[4; 8],
        vec![epoxy()],
        vec![0; 8],
    )
    .unwrap();
    if crack {
        m.split_crack(1.5e-3, 0.5e-3, 1.5e-3).unwrap();
    }
    m.dashpots = m.lysmer_dashpots(&[Side::Bottom]);
    m
}

/// The square's pulse: a tensile Gaussian traction on the top (1e5 Pa, 0.05 us wide at
/// 0.2 us), and a receiver of u_y at the bottom centre and one at the top centre.
fn square_scene(m: &SemModel) -> (Source, [Receiver; 2]) {
    let src = top_traction(m, 90.0, gaussian(1e-9, 1e-6, 0.2e-6, 0.05e-6, 1e5));
    let at = |name: &str, x: f64, y: f64| Receiver {
        name: name.into(),
        weights: m
            .point_weights(x, y)
            .unwrap()
            .into_iter()
            .map(|(n, w)| (2 * n + 1, w))
            .collect(),
        quantity: Quantity::Velocity,
    };
    (src, [at("bottom", 1e-3, 0.0), at("top", 1e-3, 2e-3)])
}

/// A crack whose faces never close gives bit for bit the open crack's results (contact
/// options `None`): a through-crack 0.5 mm below the top of the square, the part above it
/// flying off upward at 0.1 m/s (a rigid motion, no strain) while the tensile pulse from
/// the top runs through it (its particle velocity, 1e5 Pa / (rho c) = 0.03 m/s, is upward at
/// the free crack face too). A crack with interior tips under the same pulse would not do:
/// the discrete precursor ahead of the front (one element per step) brings the faces into
/// 1e-13 m contacts (7e-5 of the later opening) before the front arrives.
#[test]
fn crack_that_never_closes_matches_open_crack_bit_for_bit() {
    let mut m = cracked_square(false);
    m.dashpots.clear();
    let crack = m.split_crack(1.5e-3, 0.0, 2e-3).unwrap();
    m.dashpots = m.lysmer_dashpots(&[Side::Bottom]);
    let (_, upper) = parts(&m, &crack);
    let mut v = vec![0.0; m.dofs()];
    for &n in &upper {
        v[2 * n + 1] = 0.1;
    }
    let (src, recv) = square_scene(&m);
    let dt = dt_crit(&m);
    let base = RunConfig {
        duration_s: 1e-6,
        record_crack: true,
        initial_velocity: Some(v),
        progress: false,
        ..Default::default()
    };
    let run =
        |config: &RunConfig| run_on(&m, dt, std::slice::from_ref(&src), &recv, config).unwrap();
    let with = run(&RunConfig {
        contact: exact(0.6),
        ..base.clone()
    });
    let open = run(&base);
    let contact = with.report.contact.as_ref().unwrap();
    assert_eq!(contact.steps_in_contact, 0);
    assert_eq!(
        contact.pairs, 33,
        "a through-crack splits all 8 x 4 + 1 columns"
    );
    let traces = with.crack.as_ref().unwrap();
    assert_eq!(traces.x_m.len(), 33);
    assert_eq!((traces.x_m[0], traces.x_m[32]), (0.0, 2e-3));
    // touching at t = 0 (the first sample), apart from the first step on
    let closest = traces
        .normal_gap
        .iter()
        .flat_map(|g| &g.samples[1..])
        .fold(f64::NEG_INFINITY, |a, &g| a.max(g));
    eprintln!("closest approach of the faces after t = 0: gap {closest:e} m");
    assert!(closest < 0.0, "the faces must stay apart: {closest:e}");
    assert!(with.traces[1].max_abs() > 0.0);
    assert_eq!(with.traces, open.traces);
    assert_eq!(with.ledger.kinetic_j, open.ledger.kinetic_j);
    assert!(open.report.contact.is_none());
}

/// The split model with each pair tied (the faces made one DOF of the summed mass, through
/// the stepper's periodic ties) is the unsplit model: the tied update is
/// 2u - u_prev - dt^2 (f_up + f_low) / (m_up + m_low), and f_up + f_low, m_up + m_low are
/// the unsplit force and mass. So a pulse crossing the crack gives the unsplit traces up to
/// round-off: 1e-10 of the peak (measured in the eprintln, about 1e-14).
#[test]
fn split_model_with_tied_faces_reproduces_the_unsplit_model() {
    struct Tied<'a> {
        body: &'a SemModel,
        ties: Vec<(usize, usize)>,
    }
    impl Discretisation for Tied<'_> {
        type Workspace = trnews::sem::SemWorkspace;
        fn lumped_mass(&self) -> &[f64] {
            &self.body.lumped_mass
        }
        fn fixed_dofs(&self) -> &[usize] {
            &self.body.fixed_dofs
        }
        fn dashpots(&self) -> &[(usize, f64)] {
            &self.body.dashpots
        }
        fn periodic_ties(&self) -> &[(usize, usize)] {
            &self.ties
        }
        fn workspace(&self) -> Self::Workspace {
            self.body.workspace()
        }
        fn stiffness_times(&self, u: &[f64], out: &mut [f64], work: &mut Self::Workspace) {
            self.body.stiffness_times(u, out, work);
        }
        fn node_x(&self, node: usize) -> f64 {
            self.body.node_position(node)[0]
        }
    }
    let (plain, split) = (cracked_square(false), cracked_square(true));
    let ties = split
        .crack()
        .unwrap()
        .pairs
        .iter()
        .flat_map(|p| {
            [
                (2 * p.master, 2 * p.slave),
                (2 * p.master + 1, 2 * p.slave + 1),
            ]
        })
        .collect();
    let tied = Tied { body: &split, ties };
    let (src, recv) = square_scene(&plain);
    let config = RunConfig {
        duration_s: 1.5e-6,
        dt_s: Some(0.9 * dt_crit(&split)),
        progress: false,
        ..Default::default()
    };
    let dt = dt_crit(&split);
    let a = run_on(&plain, dt, std::slice::from_ref(&src), &recv, &config).unwrap();
    let b = run_on(&tied, dt, &[src], &recv, &config).unwrap();
    for (ta, tb) in a.traces.iter().zip(&b.traces) {
        let peak = ta.max_abs();
        let diff = ta
            .samples
            .iter()
            .zip(&tb.samples)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        eprintln!("tied vs unsplit: {:e} of the peak {peak:e}", diff / peak);
        assert!(peak > 0.0 && diff < 1e-10 * peak, "{diff:e} vs {peak:e}");
    }
    // Newmark is refused on it by the one run entry, naming the integrator: it ties DOFs
    // periodically and only applies K u (nothing assembled to factor).
    let newmark = RunConfig {
        integrator: Integrator::Newmark {
            consistent_mass: false,
        },
        ..config
    };
    let e = run_on(&tied, dt, &[], &recv, &newmark)
        .unwrap_err()
        .to_string();
    assert!(e.contains("integrator") && e.contains("explicit"), "{e}");
}

/// The energy ledger closes on a closed roller box (rollers on the sides and the bottom, a
/// free top, no dashpots) with an
/// open crack (no contact: the faces pass through each other, the body stays linear):
/// kinetic + strain = source work to 1e-6 (as the unsplit box in the unit tests; central
/// differences conserve their staggered energy, round-off remains).
#[test]
fn energy_ledger_closes_on_a_closed_box_with_an_open_crack() {
    let mut m = SemModel::new(
        lines(0.0, 4e-3, 4),
        lines(0.0, 2e-3, 4),
        5,
        &[5; 4],
        vec![fabric()],
        vec![0; 4],
    )
    .unwrap();
    m.split_crack(1e-3, 1e-3, 3e-3).unwrap();
    m.fixed_dofs = (0..m.dofs() / 2)
        .flat_map(|n| {
            let [x, y] = m.node_position(n);
            let mut held = Vec::new();
            if x == 0.0 || x == 4e-3 {
                held.push(2 * n);
            }
            if y == 0.0 {
                held.push(2 * n + 1);
            }
            held
        })
        .collect();
    let dt = dt_crit(&m);
    let src = top_traction(&m, 90.0, gaussian(1e-9, 1e-6, 0.5e-6, 0.1e-6, 1e5));
    let config = RunConfig {
        duration_s: 3e-6,
        ledger_every: 5,
        record_crack: true,
        progress: false,
        ..Default::default()
    };
    let out = run_on(&m, dt, &[src], &[], &config).unwrap();
    let r = &out.report;
    eprintln!(
        "open crack: energy residual peak {:e}",
        r.energy_residual_peak
    );
    assert!(r.source_work_j > 0.0);
    assert!(r.energy_residual_peak < 1e-6, "{r:?}");
    let opening = out
        .crack
        .unwrap()
        .normal_gap
        .iter()
        .fold(0.0, |a: f64, g| a.max(g.max_abs()));
    eprintln!("largest |gap| {opening:e} m");
    assert!(opening > 1e-10, "the faces must move apart");
}

/// Two identical epoxy bars (length L, width 0.1 mm: one element column of order 4,
/// elements 0.1 mm of order 4 along the bars, rollers: u_x held on the sides) stacked with
/// a through-crack at the interface; the upper bar moves down at v0.
fn impact(method: ContactMethod) -> (RunOutput, f64, f64) {
    let (length, width) = (2e-3, 0.1e-3);
    let mut m = SemModel::new(
        vec![0.0, width],
        lines(0.0, 2.0 * length, 40),
        4,
        &[4; 40],
        vec![epoxy()],
        vec![0; 40],
    )
    .unwrap();
    let crack = m.split_crack(length, 0.0, width).unwrap();
    m.fixed_dofs = (0..m.dofs() / 2)
        .filter(|&n| {
            let x = m.node_position(n)[0];
            x == 0.0 || x == width
        })
        .map(|n| 2 * n)
        .collect();
    let (lower, upper) = parts(&m, &crack);
    let v0 = 1.0;
    let mut v = vec![0.0; m.dofs()];
    for &n in &upper {
        v[2 * n + 1] = -v0;
    }
    let c = epoxy().wave_speeds().p_y_m_s;
    let recv = [
        mean_velocity(&m, &lower, 1, "lower"),
        mean_velocity(&m, &upper, 1, "upper"),
    ];
    let config = RunConfig {
        duration_s: 3.0 * length / c,
        contact: Some(ContactOptions {
            method,
            friction: 0.6,
            ..Default::default()
        }),
        initial_velocity: Some(v),
        progress: false,
        ..Default::default()
    };
    let out = run_on(&m, dt_crit(&m), &[], &recv, &config).unwrap();
    (out, 2.0 * length / c, v0)
}

#[test]
fn two_bar_impact_exchanges_velocities_after_two_transit_times() {
    let (out, expected_duration, v0) = impact(ContactMethod::Exact);
    let contact = out.report.contact.as_ref().unwrap();
    assert_eq!(contact.pairs, 5, "a through-crack splits both edge nodes");
    assert_eq!(contact.max_pairs_in_contact, contact.pairs);
    let duration = contact.steps_in_contact as f64 * out.report.dt_s;
    let end = |k: usize| *out.traces[k].samples.last().unwrap();
    let lost = out.ledger.contact_loss_j.last().unwrap() / out.ledger.initial_j;
    eprintln!(
        "contact {:.4} of 2L/c; lower {:.5} v0, upper {:.5} v0; contact loss {lost:e}; \
         residual {:e}; penetration {:e}; steps {}",
        duration / expected_duration,
        end(0) / v0,
        end(1) / v0,
        out.report.energy_residual_peak,
        contact.max_penetration_m,
        out.report.steps
    );
    // 2% as the T3 test: the contact time of the discrete bars differs from 2L/c by a few
    // steps, and the mean velocities by what the dispersive ringing behind the fronts
    // leaves at separation.
    assert!(
        (duration / expected_duration - 1.0).abs() < 0.02,
        "contact {duration:e} s vs 2L/c = {expected_duration:e} s"
    );
    assert!(
        (end(0) + v0).abs() < 0.02 * v0,
        "lower bar leaves at {}",
        end(0)
    );
    assert!(end(1).abs() < 0.02 * v0, "upper bar left with {}", end(1));
    assert!(lost.abs() < 0.01, "contact lost {lost} of the energy");
    assert!(out.report.energy_residual_peak < 1e-9);
    // The exact multiplier closes the gap to round-off at every step.
    assert!(contact.max_penetration_m < 1e-15);
}

/// The augmented-Lagrangian iteration at the optimal penalty converges in one iteration
/// per step on the SEM pairs too (their D = dt^2 / m from the GLL mass).
#[test]
fn augmented_lagrangian_at_the_optimal_penalty_takes_one_iteration() {
    let (out, _, _) = impact(ContactMethod::AugmentedLagrangian {
        penalty_scale: 1.0,
        tolerance_m: 1e-14,
        max_iterations: 50,
    });
    let c = out.report.contact.as_ref().unwrap();
    assert!(c.iterations_max <= 1 && c.capped_steps == 0, "{c:?}");
    assert!(c.steps_in_contact > 0);
}

/// The SEM bilinear oscillator of the module docs: upper row of height h (epoxy, top line
/// fixed), lower row the stop (density eps rho, stiffness 3 C, bottom line fixed, each
/// slave DOF critically damped for the stop's own frequency), u_x held everywhere.
fn bilinear(eps: f64) -> (SemModel, f64, f64) {
    let (w, h) = (0.5e-3, 1e-3);
    let base = epoxy();
    let stop = Material {
        name: "stop".into(),
        density_kg_m3: eps * base.density_kg_m3,
        stiffness_pa: base.stiffness_pa.map(|row| row.map(|c| 3.0 * c)),
        relaxation: None,
    };
    let mut m = SemModel::new(
        vec![0.0, w],
        vec![0.0, h, 2.0 * h],
        4,
        &[1, 1],
        vec![base.clone(), stop],
        vec![1, 0],
    )
    .unwrap();
    let crack = m.split_crack(h, 0.0, w).unwrap();
    let top = m.y_nodes_m.len() - 1;
    m.fixed_dofs = (0..m.dofs() / 2).map(|n| 2 * n).collect();
    let ends: Vec<usize> = (0..m.nx())
        .flat_map(|i| [m.node(i, 0), m.node(i, top)])
        .map(|n| 2 * n + 1)
        .collect();
    m.fixed_dofs.extend(ends);
    let c22 = base.stiffness_pa[1][1];
    let (k1, m1) = (c22 * w / h, base.density_kg_m3 * w * h / 2.0);
    let (k2, m2) = (3.0 * k1, eps * m1);
    let omega_stop = (k2 / m2).sqrt();
    m.dashpots = crack
        .pairs
        .iter()
        .map(|p| {
            let d = 2 * p.slave + 1;
            (d, 2.0 * omega_stop * m.lumped_mass[d])
        })
        .collect();
    let omega_open = (k1 / m1).sqrt();
    let omega_closed = ((k1 + k2) / (m1 + m2)).sqrt();
    (m, omega_open, omega_closed)
}

/// Times of upward zero crossings of a trace (linear interpolation).
fn upward_crossings(s: &Signal) -> Vec<f64> {
    s.samples
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0] < 0.0 && w[1] >= 0.0)
        .map(|(k, w)| (k as f64 + w[0] / (w[0] - w[1])) * s.dt_s)
        .collect()
}

#[test]
fn bilinear_oscillator_period_is_half_open_plus_half_closed() {
    let eps = 1e-4;
    let (m, omega_open, omega_closed) = bilinear(eps);
    let pi = std::f64::consts::PI;
    let period = pi / omega_open + pi / omega_closed;
    let crack = m.crack().unwrap().clone();
    // the masters' rows' own frequencies are the spring-mass ones: check one DOF's ratio
    let p = crack.pairs[2];
    let mut unit = vec![0.0; m.dofs()];
    for q in &crack.pairs {
        unit[2 * q.master + 1] = 1.0;
    }
    let mut ku = vec![0.0; m.dofs()];
    m.stiffness_times(&unit, &mut ku, &mut m.workspace());
    let omega_row = (ku[2 * p.master + 1] / m.lumped_mass[2 * p.master + 1]).sqrt();
    assert!(
        (omega_row / omega_open - 1.0).abs() < 1e-12,
        "{omega_row} vs {omega_open}"
    );
    let mut v = vec![0.0; m.dofs()];
    for q in &crack.pairs {
        v[2 * q.master + 1] = -1.0;
    }
    let recv = Receiver {
        name: "master".into(),
        weights: vec![(2 * p.master + 1, 1.0)],
        quantity: Quantity::Displacement,
    };
    let config = RunConfig {
        duration_s: 6.0 * period,
        contact: exact(0.0),
        initial_velocity: Some(v),
        progress: false,
        ..Default::default()
    };
    let out = run_on(&m, dt_crit(&m), &[], &[recv], &config).unwrap();
    let crossings = upward_crossings(&out.traces[0]);
    assert!(crossings.len() >= 5, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    eprintln!(
        "bilinear period {:.6e} s vs {period:.6e} s ({:e}), {} steps",
        measured,
        measured / period - 1.0,
        out.report.steps
    );
    // 1% as the T3 test; the light stop (eps = 1e-4) moves the closed frequency by 5e-5.
    assert!(
        (measured / period - 1.0).abs() < 0.01,
        "period {measured} vs {period}"
    );
    assert!(out.report.contact.as_ref().unwrap().steps_in_contact > 0);
}

/// Exact normal multipliers and friction mu whose strength follows the normal force with
/// response time `normal_stress_lag_s` (0: instantaneous Coulomb).
fn coulomb(friction: f64, normal_stress_lag_s: f64) -> ContactOptions {
    ContactOptions {
        method: ContactMethod::Exact,
        friction,
        normal_stress_lag_s,
    }
}

/// An epoxy block (2 x 0.25 mm: `columns` element columns and two element rows, all of
/// `order`) resting on a fixed SEM base (one row 0.125 mm below, every DOF and the lower
/// face held) through a through-crack on its whole bottom, pushed on its top by a uniform
/// traction (p_t, -p_n) ramped up over RAMP (half cosine) then constant.
fn push_block(
    (order, columns): (usize, usize),
    p_n: f64,
    p_t: f64,
    contact: ContactOptions,
) -> (RunOutput, f64) {
    let (hb, hgt) = (0.125e-3, 0.25e-3);
    let mut m = SemModel::new(
        lines(0.0, BLOCK_WIDTH, columns),
        vec![0.0, hb, hb + 0.5 * hgt, hb + hgt],
        order,
        &[order, order, order],
        vec![epoxy()],
        vec![0; 3],
    )
    .unwrap();
    let crack = m.split_crack(hb, 0.0, BLOCK_WIDTH).unwrap();
    let (base, block) = parts(&m, &crack);
    m.fixed_dofs = base.iter().flat_map(|&n| [2 * n, 2 * n + 1]).collect();
    let magnitude = p_n.hypot(p_t);
    let angle = (-p_n).atan2(p_t).to_degrees();
    let dt = 1e-9;
    let load = ramped_push(magnitude, dt);
    let src = top_traction(&m, angle, load);
    let mass: f64 = block.iter().map(|&n| m.lumped_mass[2 * n]).sum();
    let recv = mean_velocity(&m, &block, 0, "mean ux");
    let config = RunConfig {
        duration_s: DURATION,
        contact: Some(contact),
        progress: false,
        ..Default::default()
    };
    let out = run_on(&m, dt_crit(&m), &[src], &[recv], &config).unwrap();
    (out, mass)
}

/// Order 2 on 16 columns (0.125 mm elements): node-to-node Coulomb friction on the GLL nodes
/// of order 1 and 2 gives the Coulomb deceleration within 0.3% (measured: order 1, 32 and 64
/// columns: 0.9995, 1.0026; order 2: 1.0026). From order 3 the mean friction falls short:
/// the sliding block accelerates faster than (T - mu N)/m by 2% (order 3), 8-10% (order 4,
/// 8 to 32 columns, dt from 0.1 to 0.9 dt_crit, a 3 us ramp alike) and 27% (order 8),
/// because the node-to-node contact chatters: after the ramp each pair but the trailing
/// edge's (lifted by the push's moment at every order) is apart 20-40% of the steps at
/// order 4, at element corners and inside alike, against under 7% at order 2; a pair that
/// touches again sticks for a step and carries less than mu lambda_N. Friction itself drives
/// the chatter (a flutter of the instantaneous law): frictionless, 32 of the 33 pairs stay shut
/// (measured at orders 1, 2, 4 and 8) and the sliding is right ([`frictionless_block_slides_at_t_over_m`]). A
/// response time of the friction strength removes it
/// ([`normal_stress_lag_restores_coulomb_sliding_at_high_order`]).
const FRICTION_GRID: (usize, usize) = (2, 16);

#[test]
fn pushed_block_slides_at_coulomb_deceleration_or_sticks() {
    // Mean tangential acceleration of the block = (T - mu N)/m while every pair slips, N and
    // T the traction resultants (traction times the 2 mm width), m = rho w h exactly (the
    // block's GLL mass); 2% as the T3 test (the residual bouncing of the block on the face).
    let (mu, p_n, p_t) = (0.3, 1e6, 0.6e6);
    let (out, mass) = push_block(FRICTION_GRID, p_n, p_t, coulomb(mu, 0.0));
    let rho_area = epoxy().density_kg_m3 * BLOCK_WIDTH * 0.25e-3;
    assert!((mass / rho_area - 1.0).abs() < 1e-13, "{mass:e}");
    let expected = (p_t - mu * p_n) * BLOCK_WIDTH / mass;
    let measured = acceleration_after_ramp(&out.traces[0]);
    let c = out.report.contact.as_ref().unwrap();
    eprintln!(
        "sliding: acceleration {:.5} of (T - mu N)/m; energy residual {:e}; friction loss \
         {:e} J/m of {:e} J/m put in",
        measured / expected,
        out.report.energy_residual_peak,
        out.ledger.friction_loss_j.last().unwrap(),
        out.report.source_work_j
    );
    assert!(
        (measured / expected - 1.0).abs() < 0.02,
        "acceleration {measured:e} vs (T - mu N)/m = {expected:e}"
    );
    assert!(c.max_pairs_slipping > 0);
    // The ledger closes with friction (exact multiplier: the contact work is the discrete
    // work of the forces; measured 1e-14), and friction dissipates.
    assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
    assert!(*out.ledger.friction_loss_j.last().unwrap() > 0.0);
    // Below the friction limit the block sticks: after the ramp its mean velocity only
    // oscillates elastically, its average a small fraction of the speed free sliding would
    // reach, T/m (t_end - RAMP/2).
    let (out, mass) = push_block(FRICTION_GRID, p_n, 0.5 * mu * p_n, coulomb(mu, 0.0));
    let free = 0.5 * mu * p_n * BLOCK_WIDTH / mass * (DURATION - 0.5 * RAMP);
    let mean = mean_after_ramp(&out.traces[0]);
    eprintln!("sticking: mean velocity {:e} of free sliding", mean / free);
    assert!(
        mean.abs() < 0.02 * free,
        "sticking block drifts at {mean} m/s (free sliding: {free} m/s)"
    );
    assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
}

/// Mean number of pairs in contact over the second half of a pushed-block run (after the
/// ramp).
fn pairs_shut_after_ramp(out: &RunOutput) -> f64 {
    let in_contact = &out.contact_series.as_ref().unwrap().in_contact.samples;
    let after_ramp = &in_contact[in_contact.len() / 2..];
    after_ramp.iter().sum::<f64>() / after_ramp.len() as f64
}

/// mu = 0: the block slides at T/m at order 4, and the pairs do not chatter (at least 31 of
/// the 33 in contact on average after the ramp; measured 33.00 here, and 32 of 33 under the
/// friction test's stronger push at orders 1, 2, 4 and 8, the trailing edge's pair lifted), so
/// friction drives the chatter of [`FRICTION_GRID`]'s note.
#[test]
fn frictionless_block_slides_at_t_over_m() {
    let (out, mass) = push_block((4, 8), 1e6, 0.2e6, coulomb(0.0, 0.0));
    let measured = acceleration_after_ramp(&out.traces[0]);
    let expected = 0.2e6 * BLOCK_WIDTH / mass;
    let shut = pairs_shut_after_ramp(&out);
    eprintln!(
        "frictionless: {:.5} of T/m, {shut:.2} pairs in contact",
        measured / expected
    );
    assert!(
        (measured / expected - 1.0).abs() < 0.02,
        "{measured:e} vs {expected:e}"
    );
    assert!(shut >= 31.0, "{shut} pairs in contact");
    assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
}

/// The friction strength's response time tau (simplified Prakash-Clifton, src/contact.rs)
/// removes the flutter of [`FRICTION_GRID`]'s note. With tau = 20 ns and 200 ns the sliding
/// block decelerates at (T - mu N)/m within 2% at orders 2, 4 and 8 (measured 0.9992, 0.9958,
/// 0.9976 and 1.0010, 1.0004, 1.0014) and its pairs stay shut (at least 28 of the 33 in contact
/// on average after the ramp; measured 30.3-31.3, the trailing edge's pair lifted). Every grid
/// has a mean node spacing of 62.5 um along the crack, 24 ns of epoxy P-wave travel; 10 ns is
/// too short at orders 4 and 8 (measured 1.0013, 1.055, 1.166), and the steps are 15, 6.1 and
/// 1.9 ns: the time that seems to matter is the travel time, not the step. Without it the
/// blocks of orders 4 and 8 slide more than 5% too fast (measured 9.6% and 27%): the test
/// tells the two laws apart.
#[test]
fn normal_stress_lag_restores_coulomb_sliding_at_high_order() {
    let (mu, p_n, p_t) = (0.3, 1e6, 0.6e6);
    for grid in [(2, 16), (4, 8), (8, 4)] {
        for lag in [20e-9, 200e-9] {
            let (out, mass) = push_block(grid, p_n, p_t, coulomb(mu, lag));
            let expected = (p_t - mu * p_n) * BLOCK_WIDTH / mass;
            let measured = acceleration_after_ramp(&out.traces[0]) / expected;
            let shut = pairs_shut_after_ramp(&out);
            eprintln!(
                "order {}, tau = {lag:e} s: acceleration {measured:.5} of (T - mu N)/m, {shut:.2} \
                 pairs in contact",
                grid.0
            );
            assert!(
                (measured - 1.0).abs() < 0.02,
                "order {}: {measured}",
                grid.0
            );
            assert!(shut >= 28.0, "order {}: {shut} pairs in contact", grid.0);
            assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
        }
        if grid.0 >= 4 {
            let (out, mass) = push_block(grid, p_n, p_t, coulomb(mu, 0.0));
            let expected = (p_t - mu * p_n) * BLOCK_WIDTH / mass;
            let instantaneous = acceleration_after_ramp(&out.traces[0]) / expected;
            eprintln!(
                "order {}, instantaneous: acceleration {instantaneous:.5}",
                grid.0
            );
            assert!(instantaneous > 1.05, "order {}: {instantaneous}", grid.0);
        }
    }
}
