//! Work and precision of T3 and spectral elements on a problem with an exact answer.
//!
//! An orthotropic (0/90 fabric) box, 8 mm x 2 mm, with rollers on every edge (u_n = 0, no
//! shear traction) vibrates in the mode u_x = A sin(kx x) cos(ky y), u_y = B cos(kx x)
//! sin(ky y) (two wavelengths along x, half of one across y), which is exact for the
//! continuum. Both discretisations run central differences at 0.9 dt_crit for five periods;
//! the table gives DOFs, steps, the relative L2 error against the exact mode at the end, and
//! the wall time of the time loop, on this machine, in this run.
//!
//! `cargo run --release --example sem_vs_t3` (writes sem_vs_t3.csv in the working directory).

use std::f64::consts::PI;
use std::time::Instant;
use trnews::exact::RollerMode;
use trnews::fem::Model;
use trnews::laminate::Laminate;
use trnews::material::{Material, Orthotropic, Plane};
use trnews::mesh::Mesh;
use trnews::sem::SemModel;
use trnews::solve::NoContact;
use trnews::solve::{drive, CentralDifference, Coefficients, Discretisation, Fem, SampledSources};

const WIDTH: f64 = 8e-3;
const HEIGHT: f64 = 2e-3;
const PERIODS: f64 = 5.0;

/// One run: DOFs, steps, relative error, seconds in the time loop.
struct Outcome {
    dofs: usize,
    steps: usize,
    error: f64,
    seconds: f64,
}

/// Central differences (the library's stepper over any discretisation) from the exact mode
/// at t = 0 and -dt, with the roller DOFs held at zero; the error against the exact mode
/// after five periods.
fn integrate(
    body: &impl Discretisation,
    nodes: &[[f64; 2]],
    dt: f64,
    mode: &RollerMode,
) -> Outcome {
    let shape: Vec<f64> = nodes.iter().flat_map(|&[x, y]| mode.at(x, y)).collect();
    let steps = (PERIODS * 2.0 * PI / mode.omega / dt).ceil() as usize;
    let dt = PERIODS * 2.0 * PI / mode.omega / steps as f64;
    // u_{-1} = u_0 - dt v_0 = shape cos(omega dt)
    let v0: Vec<f64> = shape
        .iter()
        .map(|s| s * (1.0 - (mode.omega * dt).cos()) / dt)
        .collect();
    let sources = SampledSources::new(&[], dt, steps).expect("no sources");
    let coef = Coefficients::new(body, dt);
    let mut stepper =
        CentralDifference::new(body, coef, dt, sources, NoContact, Some(&shape), Some(&v0));
    let start = Instant::now();
    drive(&mut stepper, steps, &mut [], &mut |_| {}).expect("run");
    let seconds = start.elapsed().as_secs_f64();
    let t = steps as f64 * dt;
    let (mut diff, mut norm) = (0.0, 0.0);
    for (ui, si) in stepper.displacement().iter().zip(&shape) {
        let exact = si * (mode.omega * t).cos();
        diff += (ui - exact).powi(2);
        norm += si * si;
    }
    Outcome {
        dofs: shape.len(),
        steps,
        error: (diff / norm).sqrt(),
        seconds,
    }
}

fn rollers(nodes: &[[f64; 2]]) -> Vec<bool> {
    let tol = 1e-12;
    nodes
        .iter()
        .flat_map(|&[x, y]| {
            [
                !(x < tol || x > WIDTH - tol),
                !(y < tol || y > HEIGHT - tol),
            ]
        })
        .collect()
}

fn t3(mat: &Material, mode: &RollerMode, h: f64) -> Outcome {
    let laminate = Laminate::homogeneous(mat.clone(), HEIGHT).expect("laminate");
    let mesh = Mesh::layered(&laminate, WIDTH, h, h, &[], &[]).expect("mesh");
    let nodes = mesh.nodes.clone();
    let free = rollers(&nodes);
    let fixed: Vec<usize> = (0..free.len()).filter(|&k| !free[k]).collect();
    let model = Model::build(mesh, vec![mat.clone()], &[], fixed, None).expect("model");
    let dt = 0.9 * trnews::solve::stability::estimate(&model).dt_crit_s;
    integrate(&Fem::new(&model), &nodes, dt, mode)
}

fn sem(mat: &Material, mode: &RollerMode, elements_x: usize, order: usize) -> Outcome {
    let elements_y = (elements_x / 4).max(1);
    let mut m = SemModel::new(
        (0..=elements_x)
            .map(|i| i as f64 * WIDTH / elements_x as f64)
            .collect(),
        (0..=elements_y)
            .map(|j| j as f64 * HEIGHT / elements_y as f64)
            .collect(),
        order,
        &vec![order; elements_y],
        vec![mat.clone()],
        vec![0; elements_y],
    )
    .expect("sem");
    let nodes: Vec<[f64; 2]> = m
        .y_nodes_m
        .iter()
        .flat_map(|&y| m.x_nodes_m.iter().map(move |&x| [x, y]))
        .collect();
    let free = rollers(&nodes);
    m.fixed_dofs = (0..free.len()).filter(|&k| !free[k]).collect();
    let dt = 0.9 * 2.0 / m.max_eigenvalue(&free).0.sqrt();
    integrate(&m, &nodes, dt, mode)
}

fn main() {
    let mat = Orthotropic::preset("fabric_0_90")
        .and_then(|o| o.reduce(Plane::Strain))
        .expect("material");
    let mode = RollerMode::new(&mat, 2.0 * 2.0 * PI / WIDTH, PI / HEIGHT);
    println!(
        "roller mode, f = {:.3} MHz, {PERIODS} periods, central differences at 0.9 dt_crit",
        mode.omega / (2.0 * PI) / 1e6
    );
    let mut rows = vec![
        "method,h_or_elements,order,dofs,steps,relative_error,seconds,ns_per_dof_step".to_string(),
    ];
    let mut report = |method: &str, size: String, order: usize, o: Outcome| {
        let ns = o.seconds * 1e9 / (o.dofs as f64 * o.steps as f64);
        println!(
            "{method:>4} {size:>10} order {order}: {:>7} DOFs {:>6} steps  error {:.2e}  {:.3} s  {ns:.2} ns/DOF/step",
            o.dofs, o.steps, o.error, o.seconds
        );
        rows.push(format!(
            "{method},{size},{order},{},{},{:e},{},{ns}",
            o.dofs, o.steps, o.error, o.seconds
        ));
    };
    for h in [100e-6, 50e-6, 25e-6, 12.5e-6] {
        report("t3", format!("{}um", h * 1e6), 1, t3(&mat, &mode, h));
    }
    for order in 2..=8 {
        report("sem", "16x4".into(), order, sem(&mat, &mode, 16, order));
    }
    for elements in [8, 32] {
        report(
            "sem",
            format!("{elements}x{}", elements / 4),
            4,
            sem(&mat, &mode, elements, 4),
        );
    }
    std::fs::write("sem_vs_t3.csv", rows.join("\n") + "\n").expect("csv");
}
