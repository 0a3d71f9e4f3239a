//! Throughput benchmark: assembly time, explicit-step cost per DOF, crack overhead and the
//! machine's memory bandwidth (STREAM-like triad), as a table and as JSON.
//!
//! ```text
//! cargo bench --bench throughput            # full run (a few minutes)
//! cargo bench --bench throughput -- --quick # CI smoke run (seconds)
//! ```
//! JSON goes to `$CARGO_TARGET_DIR/bench/throughput.json` (default `target/bench/`).
//!
//! Scenes: the default stochastic CFRP laminate (~100 layers, ~11.5 mm thick), 16 mm wide,
//! absorbing bottom and left edges, fixed bottom corners, element aspect hx = 1.5 hy like the
//! default scene, with the element size chosen to hit each DOF count.

use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;
use trnews::contact::ContactOptions;
use trnews::fem::{element, Model, StiffnessOperator};
use trnews::laminate::{Laminate, StochasticSpec};
use trnews::material::{Material, Plane};
use trnews::mesh::{Mesh, Side};
use trnews::scene::{Body, Resolution, Scene, SceneSpec};
use trnews::signal::Signal;
use trnews::solve::{
    self, segment_receiver, traction_source, Discretisation, Fem, Quantity, RunConfig, Source,
};
use trnews::trnews as tr;

const WIDTH_M: f64 = 16e-3;
const ASPECT: f64 = 1.5;

#[derive(Serialize)]
struct AssemblyRow {
    target_dofs: usize,
    dofs: usize,
    hx_m: f64,
    hy_m: f64,
    best_ms: f64,
    reps: usize,
}

#[derive(Serialize)]
struct StepRow {
    target_dofs: usize,
    dofs: usize,
    threads: usize,
    steps: usize,
    best_ns_per_dof_step: f64,
    /// The fused kernel alone (StiffnessOperator::explicit_update), same steps.
    kernel_ns_per_dof_step: f64,
    best_ms_per_step: f64,
    reps: usize,
}

/// The default scene vs its uncracked companion (same mesh, same dt): the cost of the
/// crack for the same simulated duration is the ratio of the times per step.
#[derive(Serialize)]
struct CrackRow {
    dofs_cracked: usize,
    dofs_uncracked: usize,
    threads: usize,
    steps: usize,
    dt_s: f64,
    dt_crit_cracked_s: f64,
    dt_crit_uncracked_s: f64,
    stencil_fraction_cracked: f64,
    stencil_fraction_uncracked: f64,
    cracked_ns_per_dof_step: f64,
    uncracked_ns_per_dof_step: f64,
    cracked_ms_per_step: f64,
    uncracked_ms_per_step: f64,
    /// Cracked / uncracked time per step = time for the same duration.
    duration_cost_ratio: f64,
    /// Per DOF and step (the cracked model has the crack's duplicated nodes more).
    overhead_percent: f64,
    crack_pairs: usize,
    steps_in_contact: usize,
    max_pairs_slipping: usize,
}

#[derive(Serialize)]
struct Bandwidth {
    threads: usize,
    triad_gb_s: f64,
    array_mb: f64,
}

#[derive(Serialize)]
struct Report {
    quick: bool,
    rayon_threads_available: usize,
    assembly: Vec<AssemblyRow>,
    step: Vec<StepRow>,
    crack: Vec<CrackRow>,
    bandwidth: Vec<Bandwidth>,
    sweep: Vec<SweepRow>,
    sem: Vec<SemRow>,
    unstructured: Vec<UnstructuredRow>,
    unstructured_gmsh: Vec<GmshMeshRow>,
    scene: Vec<SceneRow>,
    losses: Vec<LossRow>,
}

/// The quick preset's cracked scene on spectral elements with the literature's losses
/// ([`trnews::attenuation::AttenuationSpec::report_materials`]) against without: the memory
/// variables' cost, one transmission, same step.
#[derive(Serialize)]
struct LossRow {
    dofs: usize,
    threads: usize,
    steps: usize,
    elastic_ms_per_step: f64,
    viscous_ms_per_step: f64,
    /// viscous / elastic - 1, percent.
    extra_percent: f64,
    /// The same with one relaxation mechanism (over a tenth of the band, where one fits Q
    /// within 2%): the cost of a single memory variable per point, what coarse-grained memory
    /// (one mechanism per point) would cost at least.
    one_mechanism_ms_per_step: f64,
    /// one mechanism / elastic - 1, percent.
    one_mechanism_extra_percent: f64,
}

/// One transmission of the real scene, the quick preset's cracked default scene on spectral
/// elements (contact, the transducers' band and the time-dispersion transforms included), on
/// a pool of `threads` threads: the run's own wall time (setup excluded), best over reps.
#[derive(Serialize)]
struct SceneRow {
    dofs: usize,
    threads: usize,
    steps: usize,
    ms_per_step: f64,
    /// The 1-thread time over this one: the thread scaling of the real scene.
    speedup: f64,
}

/// One stiffness product K u and one explicit step (the predictor u_next = 2u - u_prev -
/// a K u) of the spectral elements (homogeneous 0/90 fabric block, 16 mm wide, elements
/// sized for ~100k DOFs at each order) next to the T3 operator's at about the same DOF count.
#[derive(Serialize)]
struct SemRow {
    order: usize,
    dofs: usize,
    t3_dofs: usize,
    threads: usize,
    best_ns_per_dof: f64,
    t3_best_ns_per_dof: f64,
    /// Explicit step, best over reps of `steps` steps.
    steps: usize,
    step_ns_per_dof_step: f64,
    /// T3's fused explicit step on its mesh.
    t3_step_ns_per_dof_step: f64,
}

/// A delayed TR-NEWS sweep on a linear scene: convolving one impulse response vs
/// simulating every transmission.
#[derive(Serialize)]
struct SweepRow {
    points: usize,
    dofs: usize,
    convolved_s: f64,
    simulated_s: f64,
    speedup: f64,
    max_misfit_convolved: f64,
}

/// TR-NEWS at receiver 3 and a `points`-point delayed sweep (delays up to 2.5 us, a = 1) on
/// the uncracked smoke scene, through `responder`; returns (seconds, largest misfit).
fn sweep(responder: &tr::Responder, points: usize) -> (f64, f64) {
    let clock = Instant::now();
    let spec = tr::TrNewsSpec {
        receivers: vec![3],
        ..tr::TrNewsSpec::smoke()
    };
    let tr = tr::tr_news(responder, &spec).expect("tr-news");
    let list: Vec<(Vec<f64>, Vec<f64>)> = (1..=points)
        .map(|k| (vec![0.0, 2.5e-6 * k as f64 / points as f64], vec![1.0, 1.0]))
        .collect();
    let results = tr::delayed_tr_news(responder, &tr, &tr.focus[0], &list, 3e-6).expect("sweep");
    (
        clock.elapsed().as_secs_f64(),
        results.iter().fold(0.0, |m, d| m.max(d.misfit)),
    )
}

/// Unstructured spectral elements against the structured kernel on the same elements.
#[derive(Serialize)]
struct UnstructuredRow {
    order: usize,
    dofs: usize,
    threads: usize,
    structured_ns_per_dof: f64,
    unstructured_ns_per_dof: f64,
    steps: usize,
    structured_step_ns_per_dof_step: f64,
    unstructured_step_ns_per_dof_step: f64,
    /// The unstructured kernel on the grid with its inner nodes moved
    /// ([`distorted_quads`]).
    distorted_ns_per_dof: f64,
    distorted_step_ns_per_dof_step: f64,
}

/// The unstructured kernel's explicit step on a Gmsh mesh of distorted quadrilaterals.
#[derive(Serialize)]
struct GmshMeshRow {
    order: usize,
    elements: usize,
    dofs: usize,
    threads: usize,
    steps: usize,
    step_ns_per_dof_step: f64,
    /// The same with the report's losses in the fabric (3 mechanisms).
    viscous_step_ns_per_dof_step: f64,
}

/// The rectangular element grid on `columns` x `rows` as 4-node quadrilaterals.
fn grid_quads(columns: &[f64], rows: &[f64]) -> trnews::mesh::quad::QuadMesh {
    let nx = columns.len();
    let nodes = rows
        .iter()
        .flat_map(|&y| columns.iter().map(move |&x| [x, y]))
        .collect();
    let mut elements = Vec::new();
    for j in 0..rows.len() - 1 {
        for i in 0..nx - 1 {
            let at = |i: usize, j: usize| j * nx + i;
            elements.push(trnews::mesh::quad::Quad {
                nodes: vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
                material: 0,
                angle_rad: 0.0,
                tag: elements.len() as u64 + 1,
            });
        }
    }
    trnews::mesh::quad::QuadMesh { nodes, elements }
}

/// [`grid_quads`] with every inner node moved by up to a quarter of the smaller neighbouring
/// gap in x and in y (a fixed pseudo-random pattern): general bilinear elements.
fn distorted_quads(columns: &[f64], rows: &[f64]) -> trnews::mesh::quad::QuadMesh {
    let mut mesh = grid_quads(columns, rows);
    let (nx, ny) = (columns.len(), rows.len());
    let gap = |lines: &[f64], k: usize| (lines[k] - lines[k - 1]).min(lines[k + 1] - lines[k]);
    for j in 1..ny - 1 {
        for i in 1..nx - 1 {
            let phase = (i * 7919 + j * 104729) as f64;
            let node = &mut mesh.nodes[j * nx + i];
            node[0] += 0.25 * gap(columns, i) * phase.sin();
            node[1] += 0.25 * gap(rows, j) * (1.7 * phase).cos();
        }
    }
    mesh
}

fn laminate() -> Laminate {
    Laminate::stochastic(&StochasticSpec::default(), Plane::Strain).expect("default laminate")
}

/// Grid lines of [lo, hi] split at `breaks` into pieces no longer than h (the mesh's rule).
fn lines(breaks: &[f64], h: f64) -> usize {
    1 + breaks
        .windows(2)
        .map(|w| ((w[1] - w[0]) / h).ceil().max(1.0) as usize)
        .sum::<usize>()
}

/// DOFs of the uncracked layered mesh with rows of height hy and columns of 1.5 hy.
fn dofs_for(interfaces: &[f64], hy: f64) -> usize {
    2 * lines(&[0.0, WIDTH_M], ASPECT * hy) * lines(interfaces, hy)
}

/// Element height whose mesh has about `target` DOFs (bisection on the line counts).
fn hy_for(interfaces: &[f64], target: usize) -> f64 {
    let (mut lo, mut hi): (f64, f64) = (1e-7, 1e-3);
    for _ in 0..60 {
        let mid = (lo * hi).sqrt();
        if dofs_for(interfaces, mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (dl, dh) = (dofs_for(interfaces, lo), dofs_for(interfaces, hi));
    if dl.abs_diff(target) < dh.abs_diff(target) {
        lo
    } else {
        hi
    }
}

fn fixed_corners(mesh: &Mesh) -> Vec<usize> {
    let bottom = mesh.side_nodes(Side::Bottom);
    [bottom[0], *bottom.last().unwrap()]
        .into_iter()
        .flat_map(|n| [2 * n, 2 * n + 1])
        .collect()
}

fn build_model(lam: &Laminate, mesh: Mesh) -> Model {
    let fixed = fixed_corners(&mesh);
    let crack = None;
    Model::build(
        mesh,
        lam.materials.clone(),
        &[Side::Bottom.into(), Side::Left.into()],
        fixed,
        crack,
    )
    .expect("model")
}

/// The guaranteed element bound of the explicit step (cheap; avoids the power iteration).
fn element_dt_bound(model: &Model) -> f64 {
    let mesh = &model.mesh;
    let omega2 = mesh
        .triangles
        .par_iter()
        .enumerate()
        .map(|(e, &t)| {
            let m: &Material = &model.materials[mesh.element_material[e]];
            let k = element::stiffness(t.map(|n| mesh.nodes[n]), &m.stiffness_pa);
            element::omega_squared_bound(
                &k,
                element::lumped_mass(0.5 * mesh.twice_area(t), m.density_kg_m3),
            )
        })
        .reduce(|| 0.0, f64::max);
    2.0 / omega2.sqrt()
}

fn chirp_signal(dt: f64, steps: usize, amplitude: f64) -> Signal {
    let (f0, f1, t1) = (0.2e6, 2e6, 30e-6);
    let samples = (0..steps + 1)
        .map(|k| {
            let t = k as f64 * dt;
            let psi = 2.0 * std::f64::consts::PI * (f0 * t + (f1 - f0) * t * t / (2.0 * t1));
            amplitude * psi.sin()
        })
        .collect();
    Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples,
    }
}

/// Times `steps` explicit steps of `model` (the real `solve::run`, ledger every 20 steps
/// as by default) and returns the time-loop wall time per step (s) and the run output.
fn timed_run(
    model: &Model,
    sources: &[Source],
    receivers: &[solve::Receiver],
    dt: f64,
    steps: usize,
    contact: Option<ContactOptions>,
) -> (f64, solve::RunOutput) {
    let config = RunConfig {
        dt_s: Some(dt),
        duration_s: steps as f64 * dt,
        contact,
        ..Default::default()
    };
    let out = solve::run_on(
        &solve::Fem::new(model),
        dt / 0.9,
        sources,
        receivers,
        &config,
    )
    .expect("run");
    (out.report.wall_time_s / out.report.steps as f64, out)
}

/// Best time per step (s) of a discretisation's explicit predictor alone
/// (`Discretisation::explicit_update`: the fused kernel for T3, K u then the update for
/// spectral elements) on a smooth random-ish field.
fn kernel_time<D: Discretisation>(body: &D, dt: f64, steps: usize, reps: usize) -> f64 {
    let mut work = body.workspace();
    let n = body.dofs();
    let a: Vec<f64> = body.lumped_mass().iter().map(|m| dt * dt / m).collect();
    let mut u: Vec<f64> = (0..n).map(|i| 1e-9 * ((i % 97) as f64 - 48.0)).collect();
    let mut u_prev = u.clone();
    let mut u_next = vec![0.0; n];
    let mut best = f64::INFINITY;
    // memory variables where a material is viscoelastic (none, and no cost, where not)
    body.start_memory(dt, &u_prev, &mut work);
    for r in 0..=reps {
        let t = Instant::now();
        for _ in 0..steps {
            body.explicit_update(&a, &u_prev, &u, &mut u_next, &mut work);
            std::mem::swap(&mut u_prev, &mut u);
            std::mem::swap(&mut u, &mut u_next);
        }
        if r > 0 {
            best = best.min(t.elapsed().as_secs_f64() / steps as f64);
        }
    }
    std::hint::black_box(&u);
    best
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

/// Best of `reps` STREAM triad a = b + s c over arrays of `n` doubles, counting 24 bytes per
/// element (the STREAM convention, without write-allocate traffic).
fn triad(n: usize, threads: usize, reps: usize) -> f64 {
    pool(threads).install(|| {
        let mut a = vec![0.0f64; n];
        let b: Vec<f64> = (0..n).into_par_iter().map(|i| i as f64).collect();
        let c: Vec<f64> = (0..n).into_par_iter().map(|i| 0.5 * i as f64).collect();
        a.par_iter_mut().for_each(|v| *v = 1.0);
        let chunk = n.div_ceil(threads);
        let mut best = f64::INFINITY;
        for r in 0..reps {
            let s = 3.0 + r as f64;
            let t = Instant::now();
            a.par_chunks_mut(chunk)
                .zip(b.par_chunks(chunk))
                .zip(c.par_chunks(chunk))
                .for_each(|((a, b), c)| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + s * c;
                    }
                });
            best = best.min(t.elapsed().as_secs_f64());
        }
        std::hint::black_box(&a);
        24.0 * n as f64 / best / 1e9
    })
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    // --only SECTION (bandwidth, assembly, step, crack, sweep, sem, unstructured, scene, losses) runs one section, for profiling.
    let args: Vec<String> = std::env::args().collect();
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1).cloned());
    let run_section = |name: &str| only.as_deref().is_none_or(|o| o == name);
    let lam = laminate();
    let interfaces = lam.interfaces_m();
    let height = lam.thickness_m();
    let max_threads = rayon::current_num_threads().max(1);
    let thread_counts: Vec<usize> = if max_threads >= 2 {
        vec![1, 2]
    } else {
        vec![1]
    };
    println!(
        "trnews throughput benchmark{} - laminate {} layers, {:.2} mm x {:.2} mm, {} rayon threads",
        if quick { " (quick)" } else { "" },
        lam.layers.len(),
        WIDTH_M * 1e3,
        height * 1e3,
        max_threads
    );

    // --- memory bandwidth -------------------------------------------------------------
    let triad_n = if quick { 1 << 22 } else { 1 << 24 };
    let bandwidth: Vec<Bandwidth> = thread_counts
        .iter()
        .filter(|_| run_section("bandwidth"))
        .map(|&t| Bandwidth {
            threads: t,
            triad_gb_s: triad(triad_n, t, if quick { 3 } else { 10 }),
            array_mb: 8.0 * triad_n as f64 / 1e6,
        })
        .collect();
    println!(
        "\nMemory bandwidth (triad a = b + s c, 3 arrays of {:.0} MB):",
        8.0 * triad_n as f64 / 1e6
    );
    for b in &bandwidth {
        println!("  {} thread(s): {:6.1} GB/s", b.threads, b.triad_gb_s);
    }

    // --- assembly -------------------------------------------------------------------------
    let assembly_targets: &[usize] = if quick {
        &[100_000]
    } else {
        &[100_000, 1_000_000]
    };
    let mut assembly = Vec::new();
    println!(
        "\nAssembly (Model::build: validate, K, lumped M, dashpots; mesh excluded), best of reps:"
    );
    println!(
        "  {:>10} {:>10} {:>9} {:>9} {:>10}",
        "target", "DOFs", "hx (um)", "hy (um)", "time (ms)"
    );
    for &target in assembly_targets.iter().filter(|_| run_section("assembly")) {
        let hy = hy_for(&interfaces, target);
        let mesh = Mesh::layered(&lam, WIDTH_M, ASPECT * hy, hy, &[], &[]).unwrap();
        let reps = if quick { 2 } else { 5 };
        let mut best = f64::INFINITY;
        let mut dofs = 0;
        for _ in 0..reps {
            let m = mesh.clone();
            let fixed = fixed_corners(&m);
            let t = Instant::now();
            let model = Model::build(
                m,
                lam.materials.clone(),
                &[Side::Bottom.into(), Side::Left.into()],
                fixed,
                None,
            )
            .unwrap();
            best = best.min(t.elapsed().as_secs_f64());
            dofs = model.dofs();
            drop(model);
        }
        println!(
            "  {:>10} {:>10} {:>9.2} {:>9.2} {:>10.1}",
            target,
            dofs,
            ASPECT * hy * 1e6,
            hy * 1e6,
            best * 1e3
        );
        assembly.push(AssemblyRow {
            target_dofs: target,
            dofs,
            hx_m: ASPECT * hy,
            hy_m: hy,
            best_ms: best * 1e3,
            reps,
        });
    }

    // --- explicit step throughput ---------------------------------------------------------
    let step_targets: &[usize] = if quick {
        &[20_000, 100_000]
    } else {
        &[20_000, 100_000, 400_000, 1_000_000]
    };
    let (steps, reps) = if quick { (100, 2) } else { (400, 5) };
    let mut step_rows = Vec::new();
    println!("\nExplicit step (solve::run, transmitter chirp + 1 receiver, ledger every 20 steps), best of {reps} x {steps} steps:");
    println!(
        "  {:>10} {:>10} {:>8} {:>12} {:>12} {:>12}",
        "target", "DOFs", "threads", "ns/DOF/step", "ms/step", "kernel only"
    );
    for &target in step_targets.iter().filter(|_| run_section("step")) {
        let hy = hy_for(&interfaces, target);
        let mesh = Mesh::layered(&lam, WIDTH_M, ASPECT * hy, hy, &[], &[]).unwrap();
        let model = build_model(&lam, mesh);
        let dt = 0.9 * element_dt_bound(&model);
        let mut source = traction_source(
            &model.mesh,
            [WIDTH_M, height - 1e-3],
            [WIDTH_M, height - 4e-3],
            110.0,
            Signal {
                dt_s: dt,
                t0_s: 0.0,
                samples: vec![1.0],
            },
        )
        .unwrap();
        source.signal = chirp_signal(dt, steps, 50e3);
        let receiver = segment_receiver(
            &model.mesh,
            "r5",
            [12e-3, height],
            [12e-3, height],
            1,
            Quantity::Displacement,
        )
        .unwrap();
        let sources = [source];
        let receivers = [receiver];
        for &threads in &thread_counts {
            let best = pool(threads).install(|| {
                timed_run(&model, &sources, &receivers, dt, steps / 4, None); // warm-up
                (0..reps)
                    .map(|_| timed_run(&model, &sources, &receivers, dt, steps, None).0)
                    .fold(f64::INFINITY, f64::min)
            });
            let kernel = pool(threads).install(|| kernel_time(&Fem::new(&model), dt, steps, reps));
            let ns = best * 1e9 / model.dofs() as f64;
            let kns = kernel * 1e9 / model.dofs() as f64;
            println!(
                "  {:>10} {:>10} {:>8} {:>12.3} {:>12.3} {:>12.3}",
                target,
                model.dofs(),
                threads,
                ns,
                best * 1e3,
                kns
            );
            step_rows.push(StepRow {
                target_dofs: target,
                dofs: model.dofs(),
                threads,
                steps,
                best_ns_per_dof_step: ns,
                kernel_ns_per_dof_step: kns,
                best_ms_per_step: best * 1e3,
                reps,
            });
        }
    }

    // --- crack overhead ---------------------------------------------------------------
    // The default scene (crack 2 mm long, 2 mm deep under x = 8 mm, 60 um x 40 um elements)
    // and its uncracked companion: one mesh (the crack snaps onto it) and one time step, so
    // the cost ratio per step is the cost ratio for the same duration. A point force on the
    // middle of the crack's upper face, directed at 110 degrees, makes the faces clap and
    // slide from the first steps.
    let mut crack_rows = Vec::new();
    if run_section("crack") {
        let crack_steps = if quick { 100 } else { 400 };
        let spec = SceneSpec::default();
        let cracked_scene = Scene::build(&spec).expect("default scene");
        let plain_scene = Scene::build(&spec.uncracked()).expect("uncracked default scene");
        let (Body::T3(cracked), Body::T3(plain)) = (&cracked_scene.body, &plain_scene.body) else {
            unreachable!("the default scene is T3")
        };
        let dt = cracked_scene.default_dt_s();
        assert_eq!(dt, plain_scene.default_dt_s(), "the companions share dt");
        let crack = cracked
            .crack
            .as_ref()
            .expect("the default scene is cracked");
        let mid = crack.pairs[crack.pairs.len() / 2].master;
        let (s, c) = 110f64.to_radians().sin_cos();
        // 1 N/m on one node at up to 2 MHz: strong enough to open and close the faces.
        let mut force = chirp_signal(dt, crack_steps, 1.0);
        force
            .samples
            .iter_mut()
            .for_each(|v| *v = v.abs().max(0.2) * v.signum());
        let sources = [Source {
            weights: vec![(2 * mid, c), (2 * mid + 1, s)],
            signal: force,
        }];
        let receivers = [plain_scene.receivers[2].clone()];
        let contact = cracked_scene.contact();
        let fraction = |m: &Model| StiffnessOperator::new(m).stencil_fraction();
        let (fc, fp) = (fraction(cracked), fraction(plain));
        println!(
            "\nCrack overhead (default scene {} DOFs vs uncracked companion {} DOFs, dt {:.4e} s for both, stencil fraction {:.4} vs {:.4}; contact with friction 0.6; best of {reps} x {crack_steps} steps):",
            cracked.dofs(),
            plain.dofs(),
            dt,
            fc,
            fp
        );
        println!(
            "  {:>8} {:>14} {:>14} {:>10} {:>14} {:>16} {:>13}",
            "threads",
            "cracked ns/DOF",
            "plain ns/DOF",
            "overhead",
            "same duration",
            "steps in contact",
            "max slipping"
        );
        for &threads in &thread_counts {
            let (tc, tp, report) = pool(threads).install(|| {
                timed_run(cracked, &sources, &receivers, dt, crack_steps / 4, contact);
                timed_run(plain, &sources, &receivers, dt, crack_steps / 4, None);
                let mut tc = f64::INFINITY;
                let mut tp = f64::INFINITY;
                let mut report = None;
                // interleave the two so that machine noise hits both alike
                for _ in 0..reps {
                    let (t, out) =
                        timed_run(cracked, &sources, &receivers, dt, crack_steps, contact);
                    tc = tc.min(t);
                    report = out.report.contact;
                    tp = tp.min(timed_run(plain, &sources, &receivers, dt, crack_steps, None).0);
                }
                (tc, tp, report.expect("contact report"))
            });
            let nc = tc * 1e9 / cracked.dofs() as f64;
            let np = tp * 1e9 / plain.dofs() as f64;
            let overhead = 100.0 * (nc / np - 1.0);
            let slipping = report.max_pairs_slipping;
            println!(
                "  {:>8} {:>14.3} {:>14.3} {:>9.1}% {:>13.3}x {:>16} {:>13}",
                threads,
                nc,
                np,
                overhead,
                tc / tp,
                report.steps_in_contact,
                slipping
            );
            crack_rows.push(CrackRow {
                dofs_cracked: cracked.dofs(),
                dofs_uncracked: plain.dofs(),
                threads,
                steps: crack_steps,
                dt_s: dt,
                dt_crit_cracked_s: cracked_scene.stability.dt_crit_s,
                dt_crit_uncracked_s: plain_scene.stability.dt_crit_s,
                stencil_fraction_cracked: fc,
                stencil_fraction_uncracked: fp,
                cracked_ns_per_dof_step: nc,
                uncracked_ns_per_dof_step: np,
                cracked_ms_per_step: tc * 1e3,
                uncracked_ms_per_step: tp * 1e3,
                duration_cost_ratio: tc / tp,
                overhead_percent: overhead,
                crack_pairs: crack.pairs.len(),
                steps_in_contact: report.steps_in_contact,
                max_pairs_slipping: slipping,
            });
        }
    }

    // --- linear sweep: one impulse response vs one simulation per point ---------------------
    let mut sweep_rows = Vec::new();
    if run_section("sweep") {
        let points = if quick { 10 } else { 50 };
        let spec = SceneSpec::smoke().uncracked();
        let scene = std::sync::Arc::new(Scene::build(&spec).expect("smoke scene"));
        let duration = tr::TrNewsSpec::smoke().focus_duration_s() + 3e-6;
        let clock = Instant::now();
        let convolving = tr::Responder::new(scene.clone(), duration).expect("impulse response");
        let (_, misfit) = sweep(&convolving, points);
        let convolved_s = clock.elapsed().as_secs_f64();
        let (simulated_s, _) = sweep(&tr::Responder::simulating(scene.clone()), points);
        println!(
            "\nLinear delayed TR-NEWS sweep, {points} points, smoke scene ({} DOFs):",
            scene.dofs()
        );
        println!(
            "  impulse response + convolutions: {convolved_s:8.2} s (largest misfit {misfit:.1e})"
        );
        println!(
            "  one simulation per transmission: {simulated_s:8.2} s ({:.1}x slower)",
            simulated_s / convolved_s
        );
        sweep_rows.push(SweepRow {
            points,
            dofs: scene.dofs(),
            convolved_s,
            simulated_s,
            speedup: simulated_s / convolved_s,
            max_misfit_convolved: misfit,
        });
    }

    // --- spectral elements -------------------------------------------------------------
    let mut sem_rows = Vec::new();
    if run_section("sem") {
        println!(
            "\nSpectral elements vs T3, ~100k DOFs, 0/90 fabric block: K u and the explicit step (best of reps):"
        );
        let fabric = trnews::material::Orthotropic::preset("fabric_0_90")
            .and_then(|m| m.reduce(Plane::Strain))
            .expect("fabric");
        let reps = if quick { 3 } else { 20 };
        for order in [2, 4, 6, 8] {
            // (ex p + 1)(ey p + 1) * 2 = 1e5 with ex = 4 ey
            let ey = ((1e5 / 8.0f64).sqrt() / order as f64).round().max(1.0) as usize;
            let ex = 4 * ey;
            let sem = trnews::sem::SemModel::new(
                (0..=ex).map(|i| i as f64 * WIDTH_M / ex as f64).collect(),
                (0..=ey).map(|j| j as f64 * 4e-3 / ey as f64).collect(),
                order,
                &vec![order; ey],
                vec![fabric.clone()],
                vec![0; ey],
            )
            .expect("sem");
            let n = sem.dofs();
            let h = 4e-3 / ((n as f64 / 2.0 / 4.0).sqrt());
            let lam = Laminate::homogeneous(fabric.clone(), 4e-3).expect("block");
            let model = Model::build(
                Mesh::layered(&lam, WIDTH_M, h, h, &[], &[]).expect("mesh"),
                vec![fabric.clone()],
                &[],
                Vec::new(),
                None,
            )
            .expect("t3");
            let op = StiffnessOperator::new(&model);
            let fem = Fem::new(&model);
            let u: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
            let u3: Vec<f64> = (0..model.dofs()).map(|k| (k as f64 * 0.37).sin()).collect();
            // a tenth of a CFL step on the smallest GLL gap: stable, and the cost does not
            // depend on the step
            let speeds = fabric.wave_speeds();
            let gap =
                (sem.x_nodes_m[1] - sem.x_nodes_m[0]).min(sem.y_nodes_m[1] - sem.y_nodes_m[0]);
            let sem_dt = 0.1 * gap / speeds.p_x_m_s.max(speeds.p_y_m_s);
            let t3_dt = element_dt_bound(&model);
            let steps = if quick { 20 } else { 200 };
            let step_reps = if quick { 1 } else { 5 };
            for &t in &thread_counts {
                let (sem_ns, t3_ns) = pool(t).install(|| {
                    let mut out = vec![0.0; n];
                    let mut work = sem.workspace();
                    let mut best = f64::INFINITY;
                    for _ in 0..reps {
                        let c = Instant::now();
                        sem.stiffness_times(&u, &mut out, &mut work);
                        best = best.min(c.elapsed().as_secs_f64());
                    }
                    let mut out3 = vec![0.0; u3.len()];
                    let mut best3 = f64::INFINITY;
                    for _ in 0..reps {
                        let c = Instant::now();
                        op.mul(&u3, &mut out3);
                        best3 = best3.min(c.elapsed().as_secs_f64());
                    }
                    std::hint::black_box((&out, &out3));
                    (best * 1e9 / n as f64, best3 * 1e9 / u3.len() as f64)
                });
                let (sem_step, t3_step) = pool(t).install(|| {
                    (
                        kernel_time(&sem, sem_dt, steps, step_reps) * 1e9 / n as f64,
                        kernel_time(&fem, t3_dt, steps, step_reps) * 1e9 / u3.len() as f64,
                    )
                });
                println!(
                    "  order {order}, {n} DOFs, {t} thread(s): K u SEM {sem_ns:6.2} ns/DOF, T3 ({} DOFs) {t3_ns:6.2}; explicit step SEM {sem_step:6.2} ns/DOF/step, T3 {t3_step:6.2} (x{:.2})",
                    u3.len(),
                    sem_step / t3_step
                );
                sem_rows.push(SemRow {
                    order,
                    dofs: n,
                    t3_dofs: u3.len(),
                    threads: t,
                    best_ns_per_dof: sem_ns,
                    t3_best_ns_per_dof: t3_ns,
                    steps,
                    step_ns_per_dof_step: sem_step,
                    t3_step_ns_per_dof_step: t3_step,
                });
            }
        }
    }

    // --- unstructured spectral elements ---------------------------------------------------
    let mut unstructured_rows = Vec::new();
    let mut gmsh_rows = Vec::new();
    if run_section("unstructured") {
        println!(
            "\nUnstructured vs structured spectral elements, same block, elements, order and DOFs (~100k): K u and the explicit step (best of reps):"
        );
        let fabric = trnews::material::Orthotropic::preset("fabric_0_90")
            .and_then(|m| m.reduce(Plane::Strain))
            .expect("fabric");
        let reps = if quick { 3 } else { 20 };
        let steps = if quick { 20 } else { 200 };
        let step_reps = if quick { 1 } else { 5 };
        for order in [4, 6, 8] {
            let ey = ((1e5 / 8.0f64).sqrt() / order as f64).round().max(1.0) as usize;
            let ex = 4 * ey;
            let columns: Vec<f64> = (0..=ex).map(|i| i as f64 * WIDTH_M / ex as f64).collect();
            let rows: Vec<f64> = (0..=ey).map(|j| j as f64 * 4e-3 / ey as f64).collect();
            let structured = trnews::sem::SemModel::new(
                columns.clone(),
                rows.clone(),
                order,
                &vec![order; ey],
                vec![fabric.clone()],
                vec![0; ey],
            )
            .expect("sem");
            let general = trnews::sem::unstructured::UnstructuredSem::new(
                &grid_quads(&columns, &rows),
                vec![fabric.clone()],
                order,
            )
            .expect("unstructured");
            // the same grid with its inner nodes moved: bilinear elements of every shape, the
            // general mesh the kernel is for (it has no path special to parallelograms)
            let distorted = trnews::sem::unstructured::UnstructuredSem::new(
                &distorted_quads(&columns, &rows),
                vec![fabric.clone()],
                order,
            )
            .expect("distorted");
            let n = structured.dofs();
            assert_eq!(n, general.dofs());
            assert_eq!(n, distorted.dofs());
            let u: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
            let speeds = fabric.wave_speeds();
            let gap = (structured.x_nodes_m[1] - structured.x_nodes_m[0])
                .min(structured.y_nodes_m[1] - structured.y_nodes_m[0]);
            let dt = 0.1 * gap / speeds.p_x_m_s.max(speeds.p_y_m_s);
            for &t in &thread_counts {
                let (ku_s, ku_u, ku_d) = pool(t).install(|| {
                    let mut out = vec![0.0; n];
                    let mut ws = structured.workspace();
                    let (mut wu, mut wd) = (general.workspace(), distorted.workspace());
                    let mut best = [f64::INFINITY; 3];
                    for _ in 0..reps {
                        let c = Instant::now();
                        structured.stiffness_times(&u, &mut out, &mut ws);
                        best[0] = best[0].min(c.elapsed().as_secs_f64());
                        let c = Instant::now();
                        general.stiffness_times(&u, &mut out, &mut wu);
                        best[1] = best[1].min(c.elapsed().as_secs_f64());
                        let c = Instant::now();
                        distorted.stiffness_times(&u, &mut out, &mut wd);
                        best[2] = best[2].min(c.elapsed().as_secs_f64());
                    }
                    std::hint::black_box(&out);
                    let [s, u, d] = best.map(|b| b * 1e9 / n as f64);
                    (s, u, d)
                });
                let (step_s, step_u, step_d) = pool(t).install(|| {
                    (
                        kernel_time(&structured, dt, steps, step_reps) * 1e9 / n as f64,
                        kernel_time(&general, dt, steps, step_reps) * 1e9 / n as f64,
                        kernel_time(&distorted, dt, steps, step_reps) * 1e9 / n as f64,
                    )
                });
                println!(
                    "  order {order}, {n} DOFs, {t} thread(s): K u structured {ku_s:6.2} ns/DOF, unstructured {ku_u:6.2} (x{:.2}), distorted {ku_d:6.2} (x{:.2}); explicit step structured {step_s:6.2} ns/DOF/step, unstructured {step_u:6.2} (x{:.2}), distorted {step_d:6.2} (x{:.2})",
                    ku_u / ku_s,
                    ku_d / ku_s,
                    step_u / step_s,
                    step_d / step_s
                );
                unstructured_rows.push(UnstructuredRow {
                    order,
                    dofs: n,
                    threads: t,
                    structured_ns_per_dof: ku_s,
                    unstructured_ns_per_dof: ku_u,
                    steps,
                    structured_step_ns_per_dof_step: step_s,
                    unstructured_step_ns_per_dof_step: step_u,
                    distorted_ns_per_dof: ku_d,
                    distorted_step_ns_per_dof_step: step_d,
                });
            }
        }
        // The unstructured kernel alone on a Gmsh mesh of distorted curved quadrilaterals,
        // the problem SPECFEM2D was timed on (benches/results/unstructured_kernel.md).
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/scripts/gmsh_quad_plate_unstructured.msh"
        );
        let bytes = std::fs::read(path).expect("the unstructured plate's mesh");
        let groups = [(1, (0, 0.0)), (2, (0, 0.0))].into_iter().collect();
        let mesh = trnews::mesh::gmsh::read_quads(&bytes, &groups).expect("quadrilaterals");
        let order = 4;
        let mut viscous_fabric = vec![fabric.clone()];
        let mut losses = trnews::attenuation::AttenuationSpec::report_materials();
        losses.quality.retain(|name, _| name == "fabric_0_90");
        trnews::attenuation::attenuate(&mut viscous_fabric, &losses).expect("the report's losses");
        let model = trnews::sem::unstructured::UnstructuredSem::new(&mesh, vec![fabric], order)
            .expect("unstructured");
        let viscous = trnews::sem::unstructured::UnstructuredSem::new(&mesh, viscous_fabric, order)
            .expect("unstructured, viscoelastic");
        let steps = if quick { 200 } else { 20000 };
        let reps = if quick { 1 } else { 3 };
        let dt = 0.5 * 2.0 / model.element_eigenvalue_bound().sqrt();
        println!(
            "\nThe unstructured kernel on tests/scripts/gmsh_quad_plate_unstructured.msh (fabric, order {order}, {} elements, {} DOFs), {steps} explicit steps (best of {reps}), elastic and with the report's losses (3 mechanisms):",
            model.elements(),
            model.dofs()
        );
        for &t in &thread_counts {
            // interleaved, so that machine noise hits both alike
            let (mut step, mut viscous_step) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..reps {
                step = step.min(pool(t).install(|| kernel_time(&model, dt, steps, 1)));
                viscous_step =
                    viscous_step.min(pool(t).install(|| kernel_time(&viscous, dt, steps, 1)));
            }
            let ns = step * 1e9 / model.dofs() as f64;
            let viscous_ns = viscous_step * 1e9 / model.dofs() as f64;
            println!(
                "  {t} thread(s): {ns:6.2} ns/DOF/step, with losses {viscous_ns:6.2} (+{:.0}%)",
                100.0 * (viscous_ns / ns - 1.0)
            );
            gmsh_rows.push(GmshMeshRow {
                order,
                elements: model.elements(),
                dofs: model.dofs(),
                threads: t,
                steps,
                step_ns_per_dof_step: ns,
                viscous_step_ns_per_dof_step: viscous_ns,
            });
        }
    }

    // --- the real scene ----------------------------------------------------------------------
    let mut scene_rows = Vec::new();
    if run_section("scene") {
        let scene = Scene::build(&SceneSpec::preset(Resolution::Quick)).expect("quick preset");
        let dt = scene.default_dt_s();
        let steps = if quick { 200 } else { 2000 };
        let reps = if quick { 1 } else { 5 };
        let drive = chirp_signal(dt, steps, scene.spec.transmitter.peak_pa);
        let config = RunConfig {
            progress: false,
            ..scene.run_config(steps as f64 * dt)
        };
        println!(
            "\nThe quick preset's cracked scene on spectral elements ({} DOFs), one transmission of {steps} steps, run time without setup (best of {reps}):",
            scene.dofs()
        );
        // Interleaved, so that machine noise hits every thread count alike.
        let pools: Vec<rayon::ThreadPool> = thread_counts.iter().map(|&t| pool(t)).collect();
        let mut best = vec![f64::INFINITY; pools.len()];
        for _ in 0..reps {
            for (b, p) in best.iter_mut().zip(&pools) {
                let out = p.install(|| scene.transmit(&drive, &config).expect("transmit"));
                *b = b.min(out.report.wall_time_s);
            }
        }
        for (&threads, &time) in thread_counts.iter().zip(&best) {
            let row = SceneRow {
                dofs: scene.dofs(),
                threads,
                steps,
                ms_per_step: time * 1e3 / steps as f64,
                speedup: best[0] / time,
            };
            println!(
                "  {threads} thread(s): {:8.3} ms/step (x{:.2} of 1 thread)",
                row.ms_per_step, row.speedup
            );
            scene_rows.push(row);
        }
    }

    // --- losses ------------------------------------------------------------------------------
    let mut loss_rows = Vec::new();
    if run_section("losses") {
        let elastic = Scene::build(&SceneSpec::preset(Resolution::Quick)).expect("quick preset");
        let viscous = Scene::build(&SceneSpec {
            attenuation: Some(trnews::attenuation::AttenuationSpec::report_materials()),
            ..SceneSpec::preset(Resolution::Quick)
        })
        .expect("quick preset with losses");
        let one_mechanism = Scene::build(&SceneSpec {
            attenuation: Some(trnews::attenuation::AttenuationSpec {
                mechanisms: 1,
                band_hz: [0.9e6, 1.1e6],
                ..trnews::attenuation::AttenuationSpec::report_materials()
            }),
            ..SceneSpec::preset(Resolution::Quick)
        })
        .expect("quick preset with one relaxation mechanism");
        let dt = elastic.default_dt_s().min(viscous.default_dt_s());
        let steps = if quick { 100 } else { 1000 };
        let reps = if quick { 1 } else { 3 };
        let drive = chirp_signal(dt, steps, elastic.spec.transmitter.peak_pa);
        let config = RunConfig {
            progress: false,
            dt_s: Some(dt),
            ..elastic.run_config(steps as f64 * dt)
        };
        println!(
            "\nLosses: the quick preset's cracked scene ({} DOFs) with and without memory variables, one transmission of {steps} steps at the same step (best of {reps}):",
            elastic.dofs()
        );
        for &threads in &thread_counts {
            let p = pool(threads);
            let (mut best_elastic, mut best_viscous, mut best_one) =
                (f64::INFINITY, f64::INFINITY, f64::INFINITY);
            // interleaved, so that machine noise hits all alike
            for _ in 0..reps {
                for (scene, best) in [
                    (&elastic, &mut best_elastic),
                    (&viscous, &mut best_viscous),
                    (&one_mechanism, &mut best_one),
                ] {
                    let out = p.install(|| scene.transmit(&drive, &config).expect("transmit"));
                    *best = best.min(out.report.wall_time_s);
                }
            }
            let row = LossRow {
                dofs: elastic.dofs(),
                threads,
                steps,
                elastic_ms_per_step: best_elastic * 1e3 / steps as f64,
                viscous_ms_per_step: best_viscous * 1e3 / steps as f64,
                extra_percent: 100.0 * (best_viscous / best_elastic - 1.0),
                one_mechanism_ms_per_step: best_one * 1e3 / steps as f64,
                one_mechanism_extra_percent: 100.0 * (best_one / best_elastic - 1.0),
            };
            println!(
                "  {threads} thread(s): elastic {:8.3} ms/step, with losses {:8.3} ms/step (+{:.0}%), one mechanism {:8.3} ms/step (+{:.0}%)",
                row.elastic_ms_per_step, row.viscous_ms_per_step, row.extra_percent,
                row.one_mechanism_ms_per_step, row.one_mechanism_extra_percent
            );
            loss_rows.push(row);
        }
    }

    let report = Report {
        quick,
        losses: loss_rows,
        scene: scene_rows,
        sem: sem_rows,
        unstructured: unstructured_rows,
        unstructured_gmsh: gmsh_rows,
        sweep: sweep_rows,
        rayon_threads_available: max_threads,
        assembly,
        step: step_rows,
        crack: crack_rows,
        bandwidth,
    };
    let dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("bench");
    std::fs::create_dir_all(&dir).expect("create bench directory");
    let path = dir.join("throughput.json");
    std::fs::write(&path, serde_json::to_string_pretty(&report).unwrap()).expect("write JSON");
    println!("\nJSON: {}", path.display());
}
