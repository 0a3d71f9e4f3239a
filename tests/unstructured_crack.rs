//! Cracks on unstructured spectral elements ([`UnstructuredSem::cracked`]): a mesh cut along
//! a chain of element sides, contact and friction in each pair's own frame.
//!
//! The pushed block of `tests/sem_contact.rs` (an epoxy block on a fixed base, a
//! through-crack between them, a push ramped up on its top) is built here as a quadrilateral
//! mesh and turned by an angle: the block must slide at the Coulomb deceleration (T - mu N)/m
//! along its own face, or stick, at any angle, and the turned runs must be the level run
//! turned.

mod common;

use common::*;
use trnews::contact::{ContactMethod, ContactOptions};
use trnews::mesh::quad::{Quad, QuadMesh};
use trnews::mesh::Side;
use trnews::scene::{GmshSpec, ReceiverSpec, Scene, SceneSpec, SourceSpec};
use trnews::sem::unstructured::UnstructuredSem;
use trnews::signal::Signal;
use trnews::solve::{run_on, Quantity, Receiver, RunConfig, RunOutput, Source};

/// The base's and the block's heights (m); the block is [`BLOCK_WIDTH`] wide.
const BASE: f64 = 0.125e-3;
const BLOCK: f64 = 0.25e-3;
/// Element columns and the order: [`tests/sem_contact.rs`]'s FRICTION_GRID, where
/// node-to-node Coulomb friction does not chatter.
const COLUMNS: usize = 16;
const ORDER: usize = 2;

/// The base (one element row) and the block (two) as 4-node quadrilaterals turned by
/// `angle` about the origin, and the chain of element sides between them.
fn turned_block(angle: f64) -> (QuadMesh, Vec<[usize; 2]>) {
    let rows = [0.0, BASE, BASE + 0.5 * BLOCK, BASE + BLOCK];
    let (c, s) = (angle.cos(), angle.sin());
    let mut nodes = Vec::new();
    for &y in &rows {
        for i in 0..=COLUMNS {
            let x = BLOCK_WIDTH * i as f64 / COLUMNS as f64;
            nodes.push([c * x - s * y, s * x + c * y]);
        }
    }
    let at = |i: usize, j: usize| j * (COLUMNS + 1) + i;
    let elements = (0..3)
        .flat_map(|j| (0..COLUMNS).map(move |i| (i, j)))
        .enumerate()
        .map(|(k, (i, j))| Quad {
            nodes: vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
            material: 0,
            angle_rad: 0.0,
            tag: k as u64 + 1,
        })
        .collect();
    let crack = (0..COLUMNS).map(|i| [at(i, 1), at(i + 1, 1)]).collect();
    (QuadMesh { nodes, elements }, crack)
}

/// The block pushed by (p_t, -p_n) in its own frame at `angle`: the run, the block's mass
/// and the model.
fn push(angle: f64, p_n: f64, p_t: f64, friction: f64) -> (RunOutput, f64, UnstructuredSem) {
    push_run(angle, p_n, p_t, friction, false).unwrap()
}

/// [`push`], with dashpots on the left side (base and block) when `absorbing_left`; the
/// run's error where there is one.
fn push_run(
    angle: f64,
    p_n: f64,
    p_t: f64,
    friction: f64,
    absorbing_left: bool,
) -> trnews::error::Result<(RunOutput, f64, UnstructuredSem)> {
    let (mesh, crack) = turned_block(angle);
    let mut m = UnstructuredSem::cracked(&mesh, vec![epoxy()], ORDER, &crack).unwrap();
    if absorbing_left {
        let at = |j: usize| j * (COLUMNS + 1);
        let left: Vec<[usize; 2]> = (0..3).map(|j| [at(j), at(j + 1)]).collect();
        m.dashpots = m.lysmer_dashpots(&m.line_points(&left).unwrap());
    }
    let n = ORDER + 1;
    let points = |rows: std::ops::Range<usize>| {
        let mut nodes: Vec<usize> = rows
            .flat_map(|row| (0..COLUMNS).map(move |i| row * COLUMNS + i))
            .flat_map(|e| (0..n * n).map(move |q| (e, q % n, q / n)))
            .map(|(e, i, j)| m.node(e, i, j))
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    };
    let (base, block) = (points(0..1), points(1..3));
    assert!(
        base.iter().all(|b| block.binary_search(b).is_err()),
        "the cut parts share no node"
    );
    m.fixed_dofs = base.iter().flat_map(|&b| [2 * b, 2 * b + 1]).collect();
    let (c, s) = (angle.cos(), angle.sin());
    let (tangent, normal) = ([c, s], [-s, c]);
    let dt = 1e-9;
    // the push on the top side (eta = 1) of the top row: GLL weight times half the side
    let push = [
        p_t * tangent[0] - p_n * normal[0],
        p_t * tangent[1] - p_n * normal[1],
    ];
    let magnitude = p_n.hypot(p_t);
    let half = 0.5 * BLOCK_WIDTH / COLUMNS as f64;
    let weights_1d = trnews::sem::gll::Gll::new(ORDER).weights;
    let mut load = std::collections::BTreeMap::<usize, f64>::new();
    for e in 2 * COLUMNS..3 * COLUMNS {
        for (i, w) in weights_1d.iter().enumerate() {
            let node = m.node(e, i, ORDER);
            for (k, p) in push.iter().enumerate() {
                *load.entry(2 * node + k).or_default() += w * half * p / magnitude;
            }
        }
    }
    let source = Source {
        weights: load.into_iter().collect(),
        signal: ramped_push(magnitude, dt),
    };
    let mass: f64 = block.iter().map(|&b| m.lumped_mass[2 * b]).sum();
    let receiver = Receiver {
        name: "mean tangential velocity".into(),
        weights: block
            .iter()
            .flat_map(|&b| {
                let share = m.lumped_mass[2 * b] / mass;
                [(2 * b, share * tangent[0]), (2 * b + 1, share * tangent[1])]
            })
            .collect(),
        quantity: Quantity::Velocity,
    };
    let free: Vec<bool> = (0..m.dofs()).map(|d| !m.fixed_dofs.contains(&d)).collect();
    let dt_crit = 2.0 / m.max_eigenvalue(&free).0.sqrt();
    let config = RunConfig {
        dt_s: Some(dt),
        duration_s: DURATION,
        contact: Some(ContactOptions {
            method: ContactMethod::Exact,
            friction,
            normal_stress_lag_s: 0.0,
        }),
        progress: false,
        ..Default::default()
    };
    let out = run_on(&m, dt_crit, &[source], &[receiver], &config)?;
    Ok((out, mass, m))
}

/// The crack's pairs carry the face's normal, turned with the mesh, and every pair is a
/// node of the block over one of the base.
#[test]
fn the_cut_pairs_face_each_other_along_the_turned_normal() {
    let angle = 30f64.to_radians();
    let (mesh, crack) = turned_block(angle);
    let m = UnstructuredSem::cracked(&mesh, vec![epoxy()], 3, &crack).unwrap();
    let pairs = &m.crack.as_ref().unwrap().pairs;
    // 16 sides of 4 points, corners shared: 16 * 3 + 1 (a through-crack: both ends split)
    assert_eq!(pairs.len(), COLUMNS * 3 + 1);
    for p in pairs {
        let (xm, xs) = (m.positions_m[p.master], m.positions_m[p.slave]);
        assert!((xm[0] - xs[0]).hypot(xm[1] - xs[1]) < 1e-15, "{p:?}");
        assert!(
            (p.normal[0] + angle.sin()).abs() < 1e-14 && (p.normal[1] - angle.cos()).abs() < 1e-14,
            "{p:?}"
        );
    }
}

/// The block slides at (T - mu N)/m along its face within 2% (the level test's bound) at
/// 0, 30 and 90 degrees, and the turned runs' mean tangential velocities are the level
/// run's to 1e-9 of their peak (measured in the eprintln). Below the friction limit it
/// sticks at 30 degrees as on the level. The ledger closes with friction at every angle.
#[test]
fn a_turned_pushed_block_slides_at_coulomb_deceleration_or_sticks() {
    let (mu, p_n, p_t) = (0.3, 1e6, 0.6e6);
    let (level, mass, _) = push(0.0, p_n, p_t, mu);
    let expected = (p_t - mu * p_n) * BLOCK_WIDTH / mass;
    let peak = |s: &Signal| s.samples.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for degrees in [0.0f64, 30.0, 90.0] {
        let (out, _, _) = push(degrees.to_radians(), p_n, p_t, mu);
        let measured = acceleration_after_ramp(&out.traces[0]);
        let difference = out.traces[0]
            .samples
            .iter()
            .zip(&level.traces[0].samples)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / peak(&level.traces[0]);
        let contact = out.report.contact.as_ref().unwrap();
        eprintln!(
            "turned {degrees} degrees: acceleration {:.5} of (T - mu N)/m, {difference:.1e} \
             from the level run, energy residual {:.1e}, penetration {:.1e} m",
            measured / expected,
            out.report.energy_residual_peak,
            contact.max_penetration_m
        );
        assert!(
            (measured / expected - 1.0).abs() < 0.02,
            "{degrees}: {measured:e}"
        );
        assert!(difference < 1e-9, "{degrees}: {difference:e}");
        assert!(contact.max_pairs_slipping > 0);
        assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
    }
    let (out, mass, _) = push(30f64.to_radians(), p_n, 0.5 * mu * p_n, mu);
    let free = 0.5 * mu * p_n * BLOCK_WIDTH / mass * (DURATION - 0.5 * RAMP);
    let mean = mean_after_ramp(&out.traces[0]);
    eprintln!(
        "sticking at 30 degrees: mean velocity {:e} of free sliding",
        mean / free
    );
    assert!(
        mean.abs() < 0.02 * free,
        "{mean} m/s (free sliding: {free} m/s)"
    );
}

/// The through-crack reaching an absorbing line on the left: level, the line's dashpots act
/// along x and y apart, the crack's end pair sits on them, and the contact solver takes
/// their damping into each DOF's compliance: the faces slip, do not interpenetrate (1e-20 m
/// asserted) and the ledger closes (1e-9), the dashpots' loss counted after the contact
/// correction has moved their DOFs (counted before it, the residual was 8e-6). The
/// dashpots' drag on the block's left side holds it back: it does not slide at (T - mu N)/m.
/// Turned by 30 degrees, the line's dashpots couple x and y at the crack's end, and the run
/// is refused naming the dashpots and the pair's nodes.
#[test]
fn a_crack_reaches_an_absorbing_line_only_where_its_dashpots_act_along_the_axes() {
    let (mu, p_n, p_t) = (0.3, 1e6, 0.6e6);
    let (out, mass, _) = push_run(0.0, p_n, p_t, mu, true).unwrap();
    let contact = out.report.contact.as_ref().unwrap();
    let measured = acceleration_after_ramp(&out.traces[0]);
    let free = (p_t - mu * p_n) * BLOCK_WIDTH / mass;
    eprintln!(
        "absorbing left: acceleration {:.3} of (T - mu N)/m, penetration {:.1e} m, residual {:.1e}",
        measured / free,
        contact.max_penetration_m,
        out.report.energy_residual_peak
    );
    assert!(contact.max_pairs_slipping > 0);
    assert!(measured < free);
    assert!(contact.max_penetration_m < 1e-20);
    assert!(out.report.energy_residual_peak < 1e-9, "{:?}", out.report);
    assert!(out.ledger.dashpot_loss_j.last().copied().unwrap() > 0.0);
    let e = push_run(30f64.to_radians(), p_n, p_t, mu, true)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("dashpots") && e.contains("couple x and y"),
        "{e}"
    );
}

/// A crack reaching a periodic edge is refused: the pushed block's through-crack with its
/// left and right node columns tied (each node to the one at its height across) names the
/// periodic edges and the pair's nodes.
#[test]
fn a_crack_reaching_a_periodic_edge_is_refused() {
    let (mesh, crack) = turned_block(0.0);
    let mut m = UnstructuredSem::cracked(&mesh, vec![epoxy()], ORDER, &crack).unwrap();
    let column = |x: f64| {
        let mut nodes: Vec<usize> = (0..m.positions_m.len())
            .filter(|&n| (m.positions_m[n][0] - x).abs() < 1e-12)
            .collect();
        nodes.sort_by(|&a, &b| m.positions_m[a][1].total_cmp(&m.positions_m[b][1]));
        nodes
    };
    let (left, right) = (column(0.0), column(BLOCK_WIDTH));
    assert_eq!(left.len(), right.len());
    m.periodic = left
        .iter()
        .zip(&right)
        .flat_map(|(&l, &r)| [(2 * l, 2 * r), (2 * l + 1, 2 * r + 1)])
        .collect();
    let e = m.check().unwrap_err().to_string();
    assert!(e.contains("periodic") && e.contains("crack reaches"), "{e}");
}

/// The inclined crack of tests/scripts/gmsh_quad_crack.msh (written by gmsh_quads.py: a
/// 4 x 2 mm epoxy plate of 209 curved elements conforming to a crack from (1.5, 0.7) to
/// (2.5, 1.3) mm, tips inside) as a scene on spectral elements of order 4.
fn inclined_crack_scene(tied: bool) -> Scene {
    let spec = SceneSpec {
        gmsh: Some(GmshSpec {
            crack_line: Some(5),
            contact: Some(ContactOptions {
                friction: 0.6,
                ..Default::default()
            }),
            tied,
            ..gmsh_mesh("gmsh_quad_crack.msh", &[("1", "epoxy")], Some(4))
        }),
        crack: None,
        transducer: None,
        sources: vec![SourceSpec::Normal {
            edge: Side::Top,
            x_m: Some([1.5e-3, 2.5e-3]),
            depth_m: None,
            scale: 1.0,
        }],
        receivers: ReceiverSpec {
            x_m: vec![1.0e-3, 2.0e-3, 3.0e-3],
            ..Default::default()
        },
        // the run as asked, without the step-error transform's margin
        time_dispersion: None,
        ..SceneSpec::smoke()
    };
    Scene::build(&spec).unwrap()
}

/// The inclined crack's pairs all carry its normal (-sin a, cos a), tan a = 0.6, to
/// round-off; its tips inside the plate are not split (p - 1 pairs per side plus one per
/// inner corner: 4 n - 1 for n sides). A pulse pushed on the top above it opens and shuts
/// it: the pairs touch and slip, the ledger closes (energy residual below 1e-9; measured
/// in the eprintln), nothing penetrates beyond round-off, and the crack scatters: the traces
/// differ from the tied companion's by more than 1%, which steps at the cracked scene's
/// step.
#[test]
fn an_inclined_crack_in_a_gmsh_mesh_opens_shuts_and_scatters() {
    let (cracked, tied) = (inclined_crack_scene(false), inclined_crack_scene(true));
    let crack = cracked.crack().expect("a crack");
    let angle = 0.6f64.atan();
    for p in &crack.pairs {
        assert!(
            (p.normal[0] + angle.sin()).abs() < 1e-12 && (p.normal[1] - angle.cos()).abs() < 1e-12,
            "{p:?}"
        );
    }
    assert_eq!(crack.pairs.len(), 4 * crack.pieces_m.len() - 1);
    assert!(tied.crack().is_none());
    assert_eq!(cracked.stability.dt_crit_s, tied.stability.dt_crit_s);
    let dt = cracked.default_dt_s();
    let pulse = Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: (0..(3e-6 / dt) as usize)
            .map(|k| {
                let a = (k as f64 * dt - 0.6e-6) / 0.15e-6;
                1e6 * (1.0 - 2.0 * a * a) * (-a * a).exp()
            })
            .collect(),
    };
    let [a, b] = [&cracked, &tied].map(|s| {
        let config = RunConfig {
            progress: false,
            dt_s: Some(dt),
            ..s.run_config(3e-6)
        };
        s.transmit(&pulse, &config).unwrap()
    });
    let contact = a.report.contact.as_ref().unwrap();
    eprintln!(
        "inclined crack: {} pairs; {contact:?}; energy residual {:e}",
        crack.pairs.len(),
        a.report.energy_residual_peak
    );
    assert!(contact.steps_in_contact > 0 && contact.max_pairs_slipping > 0);
    assert!(contact.max_penetration_m < 1e-20, "{contact:?}");
    assert!(a.report.energy_residual_peak < 1e-9, "{:?}", a.report);
    for (k, (x, y)) in a.traces.iter().zip(&b.traces).enumerate() {
        let d = trnews::signal::relative_l2(x, y, None).unwrap();
        eprintln!("receiver {}: {d:.2e} from the tied companion", k + 1);
        assert!(d > 0.01, "receiver {}: {d:e}", k + 1);
    }
}

/// The scattered-field figure subtracts the tied companion node by node; on a Gmsh mesh the
/// companion is the uncut mesh, numbered apart, and the cut model names the uncut node at
/// each of its nodes: at the same place, both faces of a pair at one node. Before the pulse
/// reaches the crack the scattered field is nothing: the figure draws it from the two runs'
/// snapshots.
#[cfg(feature = "plot")]
#[test]
fn the_scattered_field_maps_a_cut_gmsh_mesh_onto_its_companion() {
    use trnews::scene::Body;
    let (cracked, tied) = (inclined_crack_scene(false), inclined_crack_scene(true));
    let (Body::Unstructured { model: cut, .. }, Body::Unstructured { model: uncut, .. }) =
        (&cracked.body, &tied.body)
    else {
        panic!("spectral elements on the Gmsh mesh");
    };
    let map = cut.uncut_node.as_ref().expect("the cut model's map");
    assert_eq!(map.len(), cut.positions_m.len());
    assert_eq!(cut.positions_m.len(), uncut.positions_m.len() + 23);
    for (n, &u) in map.iter().enumerate() {
        assert_eq!(cut.positions_m[n], uncut.positions_m[u], "node {n}");
    }
    for p in &cracked.crack().unwrap().pairs {
        assert_eq!(map[p.master], map[p.slave]);
    }
    let dt = cracked.default_dt_s();
    let pulse = Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: vec![1e6; 3],
    };
    let [a, b] = [&cracked, &tied].map(|s| {
        let config = RunConfig {
            progress: false,
            dt_s: Some(dt),
            snapshot_every: Some(2),
            ..s.run_config(3.0 * dt)
        };
        s.transmit(&pulse, &config).unwrap()
    });
    // the snapshot of step 2: the top's load has reached 2 elements down (K couples an
    // element's points), at most 0.4 mm of the 0.7 mm to the crack, so the two runs agree
    // bit for bit
    let (snap, companion) = (a.snapshots.last().unwrap(), b.snapshots.last().unwrap());
    assert!(
        snap.displacement.iter().any(|&v| v != 0.0),
        "the pulse has started"
    );
    for (n, &u) in map.iter().enumerate() {
        for c in 0..2 {
            assert_eq!(
                snap.displacement[2 * n + c],
                companion.displacement[2 * u + c]
            );
        }
    }
    let dir = std::env::temp_dir().join(format!("scattered_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scattered.png");
    trnews::figures::scattered_snapshot(&path, &cracked, snap, companion, 1).unwrap();
    assert!(std::fs::metadata(&path).unwrap().len() > 0);
    std::fs::remove_dir_all(&dir).unwrap();
}
