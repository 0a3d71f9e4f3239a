//! Cost of one spectral-element explicit step (the central-difference predictor with K u,
//! `Discretisation::explicit_update`, as the stepper calls it) per DOF, on the default
//! stochastic laminate 16 mm wide cut into 0.25 mm x 0.25 mm elements (order p along x, up
//! to p across a row), for p = 2, 4, 6, 8, and into 0.5 mm elements of order 7 (the default
//! experiment's 2% candidate, `scripts/sem_target.rhai`), on 1 and 2 threads: best of `REPS`
//! steps, after a warm-up. The machine may be shared, so run it a few times and take the minima.
//!
//! `cargo run --release --example sem_kernel_timing`

use std::time::Instant;
use trnews::laminate::{Laminate, StochasticSpec};
use trnews::material::Plane;
use trnews::sem::{SemModel, SemSpec};
use trnews::solve::Discretisation;

const WIDTH_M: f64 = 16e-3;
const REPS: usize = 40;

/// Best time of one step (s) of `m` on the current thread pool.
fn best_step(m: &SemModel) -> f64 {
    let n = m.dofs();
    let u: Vec<f64> = (0..n).map(|k| 1e-9 * (k as f64 * 0.37).sin()).collect();
    let u_prev: Vec<f64> = (0..n).map(|k| 1e-9 * (k as f64 * 0.41).cos()).collect();
    let a: Vec<f64> = m.lumped_mass.iter().map(|&mass| 1e-18 / mass).collect();
    let mut next = vec![0.0; n];
    let mut work = Discretisation::workspace(m);
    let mut best = f64::INFINITY;
    for _ in 0..REPS + 3 {
        let clock = Instant::now();
        m.explicit_update(&a, &u_prev, &u, &mut next, &mut work);
        best = best.min(clock.elapsed().as_secs_f64());
        std::hint::black_box(&next);
    }
    best
}

fn main() {
    let lam = Laminate::stochastic(&StochasticSpec::default(), Plane::Strain).expect("laminate");
    for (p, h) in [
        (2, 0.25e-3),
        (4, 0.25e-3),
        (6, 0.25e-3),
        (8, 0.25e-3),
        (7, 0.5e-3),
    ] {
        let spec = SemSpec {
            order_x: p,
            min_order_y: 1,
            max_order_y: p,
            extra_order_y: 0,
            rule_order_x: None,
            element_size_x_m: h,
            element_size_y_m: h,
            fine_x: None,
        };
        let m = SemModel::layered(&lam, WIDTH_M, &spec).expect("sem");
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let best = pool.install(|| best_step(&m));
            println!(
                "order {p}: {} DOFs, {} element rows, {threads} thread(s): {:6.2} ns/DOF/step",
                m.dofs(),
                m.rows_m.len() - 1,
                best * 1e9 / m.dofs() as f64
            );
        }
    }
}
