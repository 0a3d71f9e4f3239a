//! The report's figures from library results: each function turns a result into a
//! [`crate::plot`] call with titles, units and legends (PNG or SVG by extension).

use crate::error::Error;
use crate::plot::{
    field_plot, line_plot, stacked_plot, Axes, Overlay, Panel, PlotError, Scale, Series,
};
use crate::scene::Scene;
use crate::signal::{self, Signal, Window};
use crate::solve::{EnergyLedger, Snapshot};
use crate::study::WorkPrecisionPoint;
use crate::trnews::{Delayed, TrNews};
use std::path::Path;

/// Failure to make one of the report's figures: in the data it is drawn from, or in drawing it.
/// The core [`Error`] knows nothing of plotting; the script host shows either kind by its message.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The result cannot be turned into a figure (e.g. a window outside a signal).
    #[error(transparent)]
    Data(#[from] Error),
    /// Signal processing for the figure failed (e.g. a spectrum).
    #[error(transparent)]
    Signal(#[from] crate::signal::SignalError),
    /// Rendering or writing the figure failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// Result of a figure function.
pub type Result<T> = std::result::Result<T, FigureError>;

fn axes(title: &str, x_label: &str, y_label: &str) -> Axes {
    Axes {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        x_scale: Scale::Linear,
        y_scale: Scale::Linear,
    }
}

/// A signal as a series with time in microseconds.
pub fn series_us(label: &str, s: &Signal) -> Series {
    Series {
        label: label.into(),
        x: s.times().iter().map(|t| t * 1e6).collect(),
        y: s.samples.clone(),
    }
}

/// TR-NEWS focusing per receiver, one panel each, one curve per labelled result (Figs 15, 18).
pub fn focusing(path: &Path, title: &str, results: &[(&str, &TrNews)]) -> Result<()> {
    let receivers: Vec<usize> = results
        .first()
        .map(|r| r.1.focus.iter().map(|f| f.receiver).collect())
        .unwrap_or_default();
    let panels = receivers
        .iter()
        .enumerate()
        .map(|(k, r)| Panel {
            title: format!("Receiver {r}"),
            series: results
                .iter()
                .map(|(label, tr)| series_us(label, &tr.focus[k].focused))
                .collect(),
        })
        .collect::<Vec<_>>();
    Ok(stacked_plot(path, title, "time (us)", "u_y (m)", &panels)?)
}

/// Pulse inversion per receiver: the focused signal and the PI sum (Fig. 16), and the PI
/// envelopes of all receivers in one plot when `envelope_path` is given (Fig. 17).
pub fn pulse_inversion(path: &Path, envelope_path: Option<&Path>, tr: &TrNews) -> Result<()> {
    let mut panels = Vec::new();
    let mut envelopes = Vec::new();
    for f in &tr.focus {
        let Some(sum) = &f.pi_sum else { continue };
        let residual = match f.estimates.as_ref().and_then(|e| e.pi_residual) {
            Some(e) => e.brief(),
            None => format!("{:.3}", sum.max_abs() / f.focused.max_abs()),
        };
        panels.push(Panel {
            title: format!("Receiver {}: PI residual {residual}", f.receiver),
            series: vec![
                series_us("positive excitation", &f.focused),
                series_us("PI sum (+ and -)", sum),
            ],
        });
        envelopes.push(series_us(
            &format!("receiver {}", f.receiver),
            &signal::envelope(sum)?,
        ));
    }
    stacked_plot(
        path,
        &format!("TR-NEWS focusing with pulse inversion ({})", tr.band),
        "time (us)",
        "u_y (m)",
        &panels,
    )?;
    if let Some(p) = envelope_path {
        line_plot(
            p,
            &axes(
                &format!("Envelopes of the PI nonlinearity ({})", tr.band),
                "time (us)",
                "envelope of PI sum (m)",
            ),
            &envelopes,
            false,
        )?;
    }
    Ok(())
}

/// Power spectral densities (Welch, Hann) in dB re the largest value, frequency in MHz (Figs 20, 21).
pub fn spectra(path: &Path, title: &str, signals: &[(&str, &Signal)], max_mhz: f64) -> Result<()> {
    let mut psds = Vec::new();
    for (label, s) in signals {
        let segment = (s.len() / 4).max(16).min(s.len());
        psds.push((
            label,
            signal::welch(s, segment, 0.5, Window::Hann, signal::Detrend::None)?,
        ));
    }
    let mut series = Vec::new();
    for (label, p) in &psds {
        let reference = p.psd.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(*v));
        let db = p.to_db(reference)?;
        let keep: Vec<usize> = (0..p.freqs_hz.len())
            .filter(|&i| p.freqs_hz[i] <= max_mhz * 1e6)
            .collect();
        series.push(Series {
            label: label.to_string(),
            x: keep.iter().map(|&i| p.freqs_hz[i] * 1e-6).collect(),
            y: keep.iter().map(|&i| db[i].max(-120.0)).collect(),
        });
    }
    Ok(line_plot(
        path,
        &axes(title, "frequency (MHz)", "PSD (dB re own maximum)"),
        &series,
        false,
    )?)
}

/// Delayed TR-NEWS: linear prediction against simulation over the focus window (Fig. 22).
pub fn delayed(path: &Path, title: &str, d: &Delayed) -> Result<()> {
    let (t0, t1) = d.window_s;
    let series = [
        series_us("linear prediction", &d.prediction.window(t0, t1)?),
        series_us("simulation", &d.simulation.window(t0, t1)?),
    ];
    Ok(line_plot(
        path,
        &axes(title, "time (us)", "u_y (m)"),
        &series,
        false,
    )?)
}

/// Displacement component of a snapshot over the mesh, with layer interfaces and the crack (Fig. 19).
pub fn snapshot(path: &Path, scene: &Scene, snap: &Snapshot, component: usize) -> Result<()> {
    snapshot_titled(path, scene, snap, component, "")
}

fn snapshot_titled(
    path: &Path,
    scene: &Scene,
    snap: &Snapshot,
    component: usize,
    prefix: &str,
) -> Result<()> {
    let mesh = scene.mesh();
    let values: Vec<f64> = snap
        .displacement
        .iter()
        .skip(component.min(1))
        .step_by(2)
        .copied()
        .collect();
    let (x0, x1, _, _) = mesh.bounds();
    let mut overlays: Vec<Overlay> = mesh
        .interfaces_y_m
        .iter()
        .map(|&y| Overlay {
            points: vec![(x0, y), (x1, y)],
            color: (150, 150, 150),
            width: 1,
        })
        .collect();
    if let Some(c) = scene.crack() {
        overlays.extend(c.pieces_m.iter().map(|[a, b]| Overlay {
            points: vec![(a[0], a[1]), (b[0], b[1])],
            color: (0, 0, 0),
            width: 3,
        }));
    }
    let name = if component == 0 { "u_x" } else { "u_y" };
    let band = crate::transducer::band_label(scene.spec.transducer.as_ref());
    let title = format!("{prefix}{name} at t = {:.2} us ({band})", snap.time_s * 1e6);
    Ok(field_plot(
        path,
        &axes(&title, "x (m)", "y (m)"),
        &mesh.nodes,
        &mesh.triangles,
        &values,
        &overlays,
        &format!("{name} (m)"),
    )?)
}

/// The field the crack scatters: a snapshot of the cracked scene minus the same snapshot of
/// its crack-tied companion (same mesh and step, same source), on the cracked mesh. Nodes
/// of the lower crack face take the companion's value at their upper-face twin (on a cut
/// Gmsh mesh, whose companion is the uncut mesh: at the uncut mesh's node). Shows the
/// crack as a new source (report Fig. 19 and Sec. 5.2's "virtual transducer").
pub fn scattered_snapshot(
    path: &Path,
    cracked: &Scene,
    snap: &Snapshot,
    tied: &Snapshot,
    component: usize,
) -> Result<()> {
    let crack = cracked
        .crack()
        .ok_or_else(|| Error::invalid("scene", "uncracked", "has no crack to scatter from"))?;
    let tied_nodes = tied.displacement.len() / 2;
    let twin: Vec<usize> = match &cracked.body {
        // the companion is the uncut mesh, numbered apart
        crate::scene::Body::Unstructured { model, .. } => {
            model.uncut_node.clone().unwrap_or_default()
        }
        _ => {
            let mut twin: Vec<usize> = (0..cracked.mesh().nodes.len()).collect();
            for p in &crack.pairs {
                twin[p.slave] = p.master;
            }
            twin
        }
    };
    if twin.iter().any(|&n| n >= tied_nodes) || (snap.time_s - tied.time_s).abs() > 1e-12 {
        return Err(FigureError::Data(Error::invalid(
            "uncracked run",
            format!("{tied_nodes} nodes at t = {:e} s", tied.time_s),
            "must be the crack-tied companion's snapshot at the same time",
        )));
    }
    let scattered: Vec<f64> = twin
        .iter()
        .enumerate()
        .flat_map(|(n, &t)| {
            [0, 1].map(|c| snap.displacement[2 * n + c] - tied.displacement[2 * t + c])
        })
        .collect();
    let difference = Snapshot {
        time_s: snap.time_s,
        displacement: scattered,
    };
    snapshot_titled(
        path,
        cracked,
        &difference,
        component,
        "scattered by the crack: ",
    )
}

/// Error against run time on log-log axes, one curve per discretisation (T3, or spectral
/// elements of one order), integrator and step choice.
pub fn work_precision(path: &Path, points: &[WorkPrecisionPoint]) -> Result<()> {
    let mut groups: Vec<(String, Series)> = Vec::new();
    for p in points {
        let method = match p.discretisation.as_str() {
            "sem" => format!("SEM p = {}", p.order),
            _ => "T3".to_string(),
        };
        let label = format!(
            "{method} {} dt = {:.2} dt_crit",
            p.integrator, p.stability_ratio
        );
        let idx = match groups.iter().position(|g| g.0 == label) {
            Some(i) => i,
            None => {
                groups.push((
                    label.clone(),
                    Series {
                        label,
                        x: vec![],
                        y: vec![],
                    },
                ));
                groups.len() - 1
            }
        };
        groups[idx].1.x.push(p.run_time_s);
        groups[idx].1.y.push(p.error);
    }
    let series: Vec<Series> = groups.into_iter().map(|g| g.1).collect();
    let a = Axes {
        x_scale: Scale::Log10,
        y_scale: Scale::Log10,
        ..axes(
            "Work-precision: plane P wave vs exact solution (T3 and spectral elements)",
            "run time (s)",
            "relative L2 error",
        )
    };
    Ok(line_plot(path, &a, &series, true)?)
}

/// The energy ledger over time (Sec. 4.10.1).
pub fn ledger(path: &Path, title: &str, l: &EnergyLedger) -> Result<()> {
    let t: Vec<f64> = l.time_s.iter().map(|t| t * 1e6).collect();
    let s = |label: &str, y: &[f64]| Series {
        label: label.into(),
        x: t.clone(),
        y: y.to_vec(),
    };
    let series = [
        s("kinetic", &l.kinetic_j),
        s("strain", &l.strain_j),
        s("source work", &l.source_work_j),
        s("absorbed by dashpots", &l.dashpot_loss_j),
        s("removed at the crack", &l.contact_loss_j),
    ];
    Ok(line_plot(
        path,
        &axes(title, "time (us)", "energy (J/m)"),
        &series,
        false,
    )?)
}
