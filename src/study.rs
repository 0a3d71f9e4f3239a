//! Accuracy studies with known answers: the work-precision study (error against run time)
//! on a plane P wave, whose exact solution is v(t, d) = -p(t - d/c) / (rho c).

use crate::error::{require_positive, Error, Result};
use crate::fem::Model;
use crate::laminate::Laminate;
use crate::material::{Material, Orthotropic, Plane};
use crate::mesh::{Mesh, Side};
use crate::signal::Signal;
use crate::solve::{
    run, segment_receiver, traction_source, Integrator, Quantity, RunConfig, RunReport, Source,
};
use serde::{Deserialize, Serialize};

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
