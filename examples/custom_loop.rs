//! A time loop of your own from the library's parts: a stepper, an observer, and a loop that
//! stops when it has seen what it needs.
//!
//! A Gaussian bump of vertical displacement, released at rest in the middle of a free epoxy
//! plate (4 mm x 2 mm), radiates P and S waves. The loop below runs central differences until
//! the P wave reaches a point 1.5 mm to the right (|u_x| there above 1% of its largest value
//! in a reference run), then reports when that happened next to distance / c_p (the bump's
//! flank reaches about 0.2 mm out, so the first motion comes about 0.1 us earlier), and the
//! energy drift of the reference run: central differences conserve 1/2 v^T M v + 1/2 u_{n-1}^T K u_n
//! exactly without forces and damping, so the drift is round-off. The same generic loop runs
//! on linear triangles and on spectral elements of order 4.
//!
//! `cargo run --release --example custom_loop`

use trnews::error::Result;
use trnews::fem::Model;
use trnews::laminate::Laminate;
use trnews::material::{Material, Orthotropic, Plane};
use trnews::mesh::Mesh;
use trnews::sem::SemModel;
use trnews::solve::NoContact;
use trnews::solve::{
    CentralDifference, Coefficients, Discretisation, Fem, Fields, Observer, SampledSources, Stepper,
};

const WIDTH: f64 = 4e-3;
const HEIGHT: f64 = 2e-3;
/// Distance of the listening point from the bump's centre (m).
const DISTANCE: f64 = 1.5e-3;

/// An observer of our own: the largest |u_x| seen so far at one point.
struct Peak<'a> {
    weights: &'a [(usize, f64)],
    largest: f64,
}

impl Observer for Peak<'_> {
    fn after_step(&mut self, fields: &Fields<'_>) -> Result<()> {
        self.largest = self
            .largest
            .max(fields.weighted_displacement(self.weights).abs());
        Ok(())
    }
}

/// What one run found.
struct Arrival {
    /// Time |u_x| first exceeded the threshold, if it did within `steps`.
    time_s: Option<f64>,
    /// Largest |u_x| seen.
    peak: f64,
    /// (E_end - E_0) / E_0.
    energy_drift: f64,
}

/// Central differences on `body` from the bump at rest, for at most `steps` steps of `dt`,
/// stopping once |u_x| at the listening point (`weights`) exceeds `threshold`.
fn listen(
    body: &impl Discretisation,
    bump: &[f64],
    weights: &[(usize, f64)],
    dt: f64,
    steps: usize,
    threshold: f64,
) -> Result<Arrival> {
    let sources = SampledSources::new(&[], dt, steps)?;
    let coef = Coefficients::new(body, dt);
    let mut stepper = CentralDifference::new(body, coef, dt, sources, NoContact, Some(bump), None);
    let start = stepper.energy(0);
    let mut peak = Peak {
        weights,
        largest: 0.0,
    };
    let mut time_s = None;
    for step in 0..steps {
        stepper.advance(step)?;
        peak.after_step(&stepper.fields(step))?;
        stepper.commit();
        if peak.largest > threshold {
            time_s = Some(step as f64 * dt);
            break;
        }
    }
    let end = stepper.energy(steps);
    let energy = |e: trnews::solve::EnergySample| e.kinetic_j + e.strain_j;
    Ok(Arrival {
        time_s,
        peak: peak.largest,
        energy_drift: (energy(end) - energy(start)) / energy(start),
    })
}

/// The bump u_y = exp(-(r / 0.1 mm)^2) around the plate's centre, at every node.
fn bump(nodes: &[[f64; 2]]) -> Vec<f64> {
    nodes
        .iter()
        .flat_map(|&[x, y]| {
            let r2 = (x - WIDTH / 2.0).powi(2) + (y - HEIGHT / 2.0).powi(2);
            [0.0, (-r2 / 1e-8).exp()]
        })
        .collect()
}

/// Runs the reference (to find the peak) and the listening run, and prints both.
fn report(
    name: &str,
    body: &impl Discretisation,
    nodes: &[[f64; 2]],
    dt: f64,
    listen_at: Vec<(usize, f64)>,
    c_p: f64,
) -> Result<()> {
    let u0 = bump(nodes);
    let steps = (2.0 * DISTANCE / c_p / dt).ceil() as usize;
    let reference = listen(body, &u0, &listen_at, dt, steps, f64::INFINITY)?;
    let heard = listen(body, &u0, &listen_at, dt, steps, 0.01 * reference.peak)?;
    println!(
        "{name:>26}: {:>6} DOFs, first heard at {} (distance / c_p = {:.3} us); energy drift {:.1e} over {steps} steps",
        u0.len(),
        heard
            .time_s
            .map_or("never".into(), |t| format!("{:.3} us", t * 1e6)),
        DISTANCE / c_p * 1e6,
        reference.energy_drift,
    );
    Ok(())
}

fn main() -> Result<()> {
    let epoxy: Material = Orthotropic::preset("epoxy")?.reduce(Plane::Strain)?;
    let c_p = epoxy.wave_speeds().p_x_m_s;
    let at = [WIDTH / 2.0 + DISTANCE, HEIGHT / 2.0];

    let h = 20e-6;
    let mesh = Mesh::layered(
        &Laminate::homogeneous(epoxy.clone(), HEIGHT)?,
        WIDTH,
        h,
        h,
        &[],
        &[],
    )?;
    let nodes = mesh.nodes.clone();
    let model = Model::build(mesh, vec![epoxy.clone()], &[], Vec::new(), None)?;
    let dt = 0.9 * trnews::solve::stability::estimate(&model).dt_crit_s;
    let (element, lambda) = model.mesh.locate(at).expect("inside the plate");
    let t3_point = model.mesh.triangles[element]
        .iter()
        .zip(lambda)
        .map(|(&n, l)| (2 * n, l))
        .collect();
    report(
        "linear triangles, h 20 um",
        &Fem::new(&model),
        &nodes,
        dt,
        t3_point,
        c_p,
    )?;

    let lines = |length: f64, n: usize| (0..=n).map(|i| i as f64 * length / n as f64).collect();
    let sem = SemModel::new(
        lines(WIDTH, 40),
        lines(HEIGHT, 20),
        4,
        &[4; 20],
        vec![epoxy],
        vec![0; 20],
    )?;
    let sem_nodes: Vec<[f64; 2]> = sem
        .y_nodes_m
        .iter()
        .flat_map(|&y| sem.x_nodes_m.iter().map(move |&x| [x, y]))
        .collect();
    let free = vec![true; sem.dofs()];
    let dt = 0.9 * 2.0 / sem.max_eigenvalue(&free).0.sqrt();
    let sem_point = sem
        .point_weights(at[0], at[1])
        .expect("inside the plate")
        .into_iter()
        .map(|(n, w)| (2 * n, w))
        .collect();
    report(
        "spectral elements, order 4",
        &sem,
        &sem_nodes,
        dt,
        sem_point,
        c_p,
    )
}
