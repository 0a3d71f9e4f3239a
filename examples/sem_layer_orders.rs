//! What the order across thin layers does to the spectral elements' time step and size.
//!
//! The default stochastic laminate (50 fabric + epoxy pairs, epoxy clamped to 20 um, 16 mm
//! wide) as spectral elements: one element row per layer (thick layers split into rows of at
//! most `row_m`), elements `hx` wide with order `px` along x. Across each row the order is
//! either `px` everywhere ("uniform") or, per row, the largest order whose smallest GLL gap
//! across the row is no smaller than the smallest GLL gap along x ("per layer"), so the thin
//! layers stop setting the step. dt_crit is Lanczos' estimate of 2 / sqrt(lambda_max(M^-1 K))
//! on the free block; the T3 quick scene is the comparison (run on this machine: its dt_crit
//! and DOFs come from the same estimate).
//!
//! `cargo run --release --example sem_layer_orders`

use trnews::laminate::{Laminate, StochasticSpec};
use trnews::material::Plane;
use trnews::scene::{Scene, SceneSpec};
use trnews::sem::{gll::Gll, SemModel};

const WIDTH: f64 = 16e-3;

/// Smallest gap between GLL points of order p on an element of size h.
fn smallest_gap(h: f64, p: usize) -> f64 {
    let g = Gll::new(p);
    0.5 * h * (g.points[1] - g.points[0])
}

fn build(lam: &Laminate, hx: f64, px: usize, row_m: f64, per_layer: bool) -> SemModel {
    let mut rows = vec![0.0];
    let mut material = Vec::new();
    for layer in &lam.layers {
        let n = (layer.thickness_m / row_m).ceil().max(1.0) as usize;
        let y0 = *rows.last().expect("rows");
        for k in 1..=n {
            rows.push(y0 + layer.thickness_m * k as f64 / n as f64);
            material.push(layer.material);
        }
    }
    let x_gap = smallest_gap(hx, px);
    let orders: Vec<usize> = rows
        .windows(2)
        .map(|w| {
            if !per_layer {
                return px;
            }
            (1..=px)
                .rev()
                .find(|&p| smallest_gap(w[1] - w[0], p) >= x_gap)
                .unwrap_or(1)
        })
        .collect();
    let columns = (WIDTH / hx).round() as usize;
    SemModel::new(
        (0..=columns)
            .map(|i| i as f64 * WIDTH / columns as f64)
            .collect(),
        rows,
        px,
        &orders,
        lam.materials.clone(),
        material,
    )
    .expect("sem")
}

fn main() {
    let lam = Laminate::stochastic(&StochasticSpec::default(), Plane::Strain).expect("laminate");
    let quick = Scene::build(&SceneSpec::default()).expect("quick scene");
    println!(
        "T3 quick scene: {} DOFs, dt_crit {:.3} ns",
        quick.model.dofs(),
        quick.stability.dt_crit_s * 1e9
    );
    for (hx, px, row_m) in [
        (0.5e-3, 4, 0.25e-3),
        (0.25e-3, 4, 0.125e-3),
        (0.5e-3, 6, 0.25e-3),
    ] {
        for per_layer in [false, true] {
            let m = build(&lam, hx, px, row_m, per_layer);
            let free = vec![true; m.dofs()];
            let (lambda, _) = m.max_eigenvalue(&free);
            println!(
                "SEM hx {:.3} mm, order {px} along x, rows <= {:.3} mm, {:>9} across: {:>7} DOFs, dt_crit {:.3} ns",
                hx * 1e3,
                row_m * 1e3,
                if per_layer { "per layer" } else { "uniform" },
                m.dofs(),
                2.0 / lambda.sqrt() * 1e9
            );
        }
    }
}
