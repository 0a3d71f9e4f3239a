//! What the order across thin layers does to the spectral elements' time step and size.
//!
//! The default stochastic laminate (50 fabric + epoxy pairs, epoxy clamped to 20 um, 16 mm
//! wide) as spectral elements: one element row per layer (thick layers split into rows of at
//! most `row_m`), elements `hx` wide with order `px` along x. Across each row the order is
//! either `px` everywhere ("uniform") or, per row, the largest order up to `max_y` whose
//! smallest GLL gap across the row is no smaller than the smallest GLL gap along x ("per
//! layer", `SemModel::layered`), so the thin layers stop setting the step. dt_crit is
//! Lanczos' estimate of 2 / sqrt(lambda_max(M^-1 K)) on the free block; the T3 quick scene is the comparison (run on this machine: its dt_crit
//! and DOFs come from the same estimate).
//!
//! `cargo run --release --example sem_layer_orders`

use trnews::laminate::{Laminate, StochasticSpec};
use trnews::material::Plane;
use trnews::scene::{Scene, SceneSpec};
use trnews::sem::{SemModel, SemSpec};

const WIDTH: f64 = 16e-3;

/// The laminate as spectral elements (`SemModel::layered`): per layer the order its rule
/// picks up to `max_y`, or `px` across every row ("uniform") on the same element lines.
fn build(
    lam: &Laminate,
    (hx, px, max_y, row_m): (f64, usize, usize, f64),
    per_layer: bool,
) -> SemModel {
    let cut = SemSpec {
        order_x: px,
        min_order_y: 1,
        max_order_y: max_y,
        extra_order_y: 0,
        rule_order_x: None,
        element_size_x_m: hx,
        element_size_y_m: row_m,
        fine_x: None,
    };
    let m = SemModel::layered(lam, WIDTH, &cut).expect("sem");
    if per_layer {
        return m;
    }
    let rows = m.rows_m.len() - 1;
    SemModel::new(
        m.columns_m,
        m.rows_m,
        px,
        &vec![px; rows],
        m.materials,
        m.row_material,
    )
    .expect("sem")
}

fn main() {
    let lam = Laminate::stochastic(&StochasticSpec::default(), Plane::Strain).expect("laminate");
    let quick = Scene::build(&SceneSpec::default()).expect("quick scene");
    println!(
        "T3 quick scene: {} DOFs, dt_crit {:.3} ns",
        quick.dofs(),
        quick.stability.dt_crit_s * 1e9
    );
    for (hx, px, max_y, row_m) in [
        (0.5e-3, 4, 4, 0.25e-3),
        (0.25e-3, 4, 4, 0.125e-3),
        (0.5e-3, 6, 6, 0.25e-3),
        (0.5e-3, 7, 3, 0.5e-3),
    ] {
        for per_layer in [false, true] {
            let m = build(&lam, (hx, px, max_y, row_m), per_layer);
            let free = vec![true; m.dofs()];
            let (lambda, _) = m.max_eigenvalue(&free);
            println!(
                "SEM hx {:.3} mm, order {px} along x, rows <= {:.3} mm, {:>20} across: {:>7} DOFs, dt_crit {:.3} ns",
                hx * 1e3,
                row_m * 1e3,
                if per_layer { format!("per layer (<= {max_y})") } else { "uniform".into() },
                m.dofs(),
                2.0 / lambda.sqrt() * 1e9
            );
        }
    }
}
