//! Accuracy studies: the work-precision study (error against run time) on a plane P wave,
//! whose exact solution is v(t, d) = -p(t - d/c) / (rho c), and the choice of a resolution
//! for a requested accuracy on any scene ([`resolution_for_tolerance`]).

use crate::accuracy::{Estimate, T3_ORDER};
use crate::error::{require_positive, Error, Result};
use crate::fem::Model;
use crate::laminate::Laminate;
use crate::material::{Material, Orthotropic, Plane};
use crate::mesh::{Mesh, Side};
use crate::scene::{Scene, SceneSpec};
use crate::signal::Signal;
use crate::solve::{
    run, segment_receiver, traction_source, Integrator, Quantity, RunConfig, RunReport, Source,
};
use crate::trnews::{Responder, TrNewsSpec};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A vertical strip of `material`, `columns` square elements of size h wide, with rollers on
/// the sides (x fixed) so that a uniform top traction launches an exact plane P wave, and an
/// absorbing bottom (exact for normal incidence in the continuum).
pub fn plane_wave_strip(
    material: &Material,
    height_m: f64,
    h_m: f64,
    columns: usize,
) -> Result<Model> {
    let lam = Laminate::homogeneous(material.clone(), height_m)?;
    let mesh = Mesh::layered(&lam, h_m * columns as f64, h_m, h_m, &[], &[])?;
    let fixed = [Side::Left, Side::Right]
        .iter()
        .flat_map(|&s| mesh.side_nodes(s))
        .map(|n| 2 * n)
        .collect();
    Model::build(mesh, lam.materials, &[Side::Bottom.into()], fixed, None)
}

/// Parameters of the work-precision study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WorkPrecisionSpec {
    /// Element sizes to try (m).
    pub element_sizes_m: Vec<f64>,
    /// Explicit steps as fractions of dt_crit.
    pub explicit_fractions: Vec<f64>,
    /// Newmark steps as multiples of the explicit dt_crit (Newmark may exceed it).
    pub newmark_multiples: Vec<f64>,
    /// Receiver depth below the loaded surface (m).
    pub depth_m: f64,
    /// Gaussian pulse width (s); the pulse is centred at 4 widths.
    pub pulse_width_s: f64,
}

impl Default for WorkPrecisionSpec {
    fn default() -> Self {
        WorkPrecisionSpec {
            element_sizes_m: vec![100e-6, 50e-6, 25e-6, 12.5e-6],
            explicit_fractions: vec![0.9, 0.45],
            newmark_multiples: vec![0.9, 2.0, 4.0],
            depth_m: 2e-3,
            pulse_width_s: 0.1e-6,
        }
    }
}

/// One run of the study.
#[derive(Clone, Debug, Serialize)]
pub struct WorkPrecisionPoint {
    /// "explicit" or "newmark".
    pub integrator: String,
    /// Element size (m).
    pub element_size_m: f64,
    /// Time step (s).
    pub dt_s: f64,
    /// dt / dt_crit.
    pub stability_ratio: f64,
    /// DOFs.
    pub dofs: usize,
    /// Relative L2 error of the receiver velocity against the exact plane wave.
    pub error: f64,
    /// Time loop plus setup (s).
    pub run_time_s: f64,
    /// The run's full report.
    pub report: RunReport,
}

fn pulse(t: f64, width: f64) -> f64 {
    (-((t - 4.0 * width) / width).powi(2)).exp()
}

/// Runs the plane-wave problem over element sizes and steps, for both integrators.
pub fn work_precision(spec: &WorkPrecisionSpec) -> Result<Vec<WorkPrecisionPoint>> {
    require_positive("depth_m", spec.depth_m)?;
    require_positive("pulse_width_s", spec.pulse_width_s)?;
    if spec.element_sizes_m.is_empty() {
        return Err(Error::invalid(
            "element_sizes_m",
            "[]",
            "needs at least one size",
        ));
    }
    let epoxy = Orthotropic::epoxy().reduce(Plane::Strain)?;
    let c = epoxy.wave_speeds().p_y_m_s;
    let impedance = epoxy.density_kg_m3 * c;
    let height = 2.0 * spec.depth_m;
    let duration = spec.depth_m / c + 8.0 * spec.pulse_width_s;
    let mut points = Vec::new();
    for &h in &spec.element_sizes_m {
        require_positive("element_sizes_m", h)?;
        let model = plane_wave_strip(&epoxy, height, h, 2)?;
        let stability = crate::solve::stability::estimate(&model);
        let dt_crit = stability.dt_crit_s;
        let (x0, x1, _, y1) = model.mesh.bounds();
        let y = model.mesh.nearest_row_y(y1 - spec.depth_m).unwrap_or(y1);
        let receiver = segment_receiver(
            &model.mesh,
            "depth",
            [x0, y],
            [x1, y],
            1,
            Quantity::Velocity,
        )?;
        let depth = y1 - y;
        let runs = spec
            .explicit_fractions
            .iter()
            .map(|f| (Integrator::Explicit, f))
            .chain(spec.newmark_multiples.iter().map(|m| {
                (
                    Integrator::Newmark {
                        consistent_mass: false,
                    },
                    m,
                )
            }));
        for (integrator, &factor) in runs {
            let dt = factor * dt_crit;
            let steps = (duration / dt).round() as usize + 1;
            let load = Signal {
                dt_s: dt,
                t0_s: 0.0,
                samples: (0..=steps)
                    .map(|k| pulse(k as f64 * dt, spec.pulse_width_s))
                    .collect(),
            };
            let source: Source = traction_source(&model.mesh, [x0, y1], [x1, y1], 270.0, load)?;
            let config = RunConfig {
                dt_s: Some(dt),
                duration_s: duration,
                integrator,
                stability: Some(stability),
                ..Default::default()
            };
            let out = run(&model, &[source], std::slice::from_ref(&receiver), &config)?;
            let trace = &out.traces[0];
            let exact: Vec<f64> = (0..trace.len())
                .map(|k| -pulse(k as f64 * dt - depth / c, spec.pulse_width_s) / impedance)
                .collect();
            let num: f64 = trace
                .samples
                .iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).powi(2))
                .sum();
            let den: f64 = exact.iter().map(|b| b * b).sum();
            points.push(WorkPrecisionPoint {
                integrator: if matches!(integrator, Integrator::Explicit) {
                    "explicit"
                } else {
                    "newmark"
                }
                .into(),
                element_size_m: h,
                dt_s: dt,
                stability_ratio: out.report.stability_ratio,
                dofs: out.report.dofs,
                error: (num / den).sqrt(),
                run_time_s: out.report.wall_time_s + out.report.setup_time_s,
                report: out.report,
            });
        }
    }
    Ok(points)
}

/// A resolution chosen for a requested accuracy, with its prediction.
#[derive(Clone, Debug, Serialize)]
pub struct ResolutionChoice {
    /// The requested relative L2 error of the first-pass receiver responses.
    pub tolerance: f64,
    /// Element sizes relative to the given scene's (a power of 2; 1 keeps them).
    pub size_factor: f64,
    /// Chosen element size along x (m).
    pub element_size_x_m: f64,
    /// Chosen element size along y (m).
    pub element_size_y_m: f64,
    /// Pilot differences [finest vs next, next vs the one after] of the responses (largest
    /// over receivers).
    pub pilot_differences: [f64; 2],
    /// Order used for the prediction: the observed one, clamped to [1, 2] (T3's).
    pub order: f64,
    /// Predicted relative L2 error at the chosen sizes.
    pub predicted_error: f64,
    /// Predicted run time of one transmission at the chosen sizes (s): the finest pilot's
    /// scaled as DOFs x steps, size^-3.
    pub predicted_run_time_s: f64,
}

/// Largest refinement [`resolution_for_tolerance`] proposes: 1/8 of the element sizes
/// (about 512x the run time).
const FINEST_FACTOR: f64 = 0.125;
/// Finest pilot run of [`resolution_for_tolerance`]: half the element sizes (about 8x one
/// transmission at the scene's own sizes), so the prediction never costs more than that.
const FINEST_PILOT: f64 = 0.5;

/// Chooses element sizes for `spec` so that the first-pass responses to the TR-NEWS chirp
/// of `chirp` (the signal every TR-NEWS measure is derived from) have a relative L2 error
/// below `tolerance`. Pilot: the crack-tied (linear, convolving) scene at 4h, 2h and h,
/// extended to h/2 if the differences do not yet shrink; the last three levels'
/// differences d_1 (finest vs next) and d_2 give the observed order q, clamped to [1, 2] for
/// the prediction (a lower order refines more); error ~ d_1 / (2^q - 1) at the finest pilot
/// level, scaling as size^q. The sizes are halved until the prediction meets the
/// tolerance. Errors when the pilot does not converge by h/2 or when more than 1/8 of the
/// sizes would be needed; either way the check after the run (an error estimate)
/// is what decides.
pub fn resolution_for_tolerance(
    spec: &SceneSpec,
    tolerance: f64,
    chirp: &TrNewsSpec,
) -> Result<(SceneSpec, ResolutionChoice)> {
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0) {
        return Err(Error::invalid(
            "tolerance",
            tolerance,
            "must be a relative error between 0 and 1",
        ));
    }
    let pilot = |factor: f64| -> Result<(Vec<Signal>, f64)> {
        let scene = Arc::new(Scene::build(&spec.coarsened(factor)?.uncracked())?);
        let r = Responder::new(scene, chirp.record_s + 1e-6)?;
        let c = chirp.chirp.signal(r.dt_s(), spec.transmitter.peak_pa)?;
        let time = r.impulse_report().map_or(0.0, |rep| rep.wall_time_s);
        Ok((r.respond(&c, chirp.record_s)?.traces, time))
    };
    // Pilot triples (f, 2f, 4f) from f = 1 down until the differences shrink.
    let mut levels = vec![pilot(4.0)?, pilot(2.0)?];
    let mut finest = 1.0f64;
    let (d1, d2) = loop {
        levels.push(pilot(finest)?);
        let n = levels.len();
        let (coarse, medium, fine) = (&levels[n - 3], &levels[n - 2], &levels[n - 1]);
        let (mut d1, mut d2) = (0.0f64, 0.0f64);
        for k in 0..fine.0.len() {
            let window = (0.0, chirp.record_s);
            let e = Estimate::waveform(&fine.0[k], &medium.0[k], &coarse.0[k], window, T3_ORDER)?;
            d1 = d1.max(e.companions[0]);
            d2 = d2.max(e.companions[1]);
        }
        if d2 > d1 && d1 > 0.0 {
            break (d1, d2);
        }
        if finest <= FINEST_PILOT {
            return Err(Error::invalid(
                "tolerance",
                tolerance,
                format!(
                    "cannot be predicted: the responses do not converge down to half the \
                     element sizes (differences {d2:.3e}, {d1:.3e}); refine by hand and check \
                     with an error estimate"
                ),
            ));
        }
        finest *= 0.5;
    };
    let time = levels[levels.len() - 1].1;
    let order = (d2 / d1).log2().clamp(1.0, T3_ORDER);
    let error_at_finest = d1 / (2f64.powf(order) - 1.0);
    let mut factor = finest;
    while error_at_finest * (factor / finest).powf(order) > tolerance {
        factor *= 0.5;
        if factor < FINEST_FACTOR {
            return Err(Error::invalid(
                "tolerance",
                tolerance,
                format!(
                    "needs element sizes below 1/8 of the scene's (predicted error {:.2e} at \
                     1/8, about 512x the run time)",
                    error_at_finest * (FINEST_FACTOR / finest).powf(order)
                ),
            ));
        }
    }
    let predicted_error = error_at_finest * (factor / finest).powf(order);
    let predicted_run_time_s = time * (factor / finest).powi(-3);
    let chosen = spec.coarsened(factor)?;
    let choice = ResolutionChoice {
        tolerance,
        size_factor: factor,
        element_size_x_m: chosen.element_size_x_m,
        element_size_y_m: chosen.element_size_y_m,
        pilot_differences: [d1, d2],
        order,
        predicted_error,
        predicted_run_time_s,
    };
    Ok((chosen, choice))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_precision_errors_fall_with_resolution() {
        // Halving h at a fixed dt/dt_crit halves dt too: a second-order method's error falls
        // about 4x; we require 3x (the coarsest mesh is not yet asymptotic).
        let spec = WorkPrecisionSpec {
            element_sizes_m: vec![50e-6, 25e-6],
            explicit_fractions: vec![0.9],
            newmark_multiples: vec![0.9],
            ..Default::default()
        };
        let points = work_precision(&spec).unwrap();
        assert_eq!(points.len(), 4);
        for kind in ["explicit", "newmark"] {
            let e: Vec<f64> = points
                .iter()
                .filter(|p| p.integrator == kind)
                .map(|p| p.error)
                .collect();
            assert!(e[0] / e[1] > 3.0, "{kind}: errors {e:?}");
            assert!(e[1] < 0.05, "{kind}: error at 25 um {}", e[1]);
        }
        assert!(points
            .iter()
            .all(|p| p.run_time_s > 0.0 && p.report.energy_residual_peak < 1e-6));
    }
}
