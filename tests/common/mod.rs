//! Small scenes shared by the physics tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use trnews::fem::Model;
use trnews::laminate::{Laminate, Layer};
use trnews::material::{Material, Orthotropic, Plane};
use trnews::mesh::{Mesh, Side};
use trnews::signal::Signal;
use trnews::solve::{segment_receiver, traction_source, Quantity, Receiver, Source};

pub fn epoxy() -> Material {
    Orthotropic::epoxy().reduce(Plane::Strain).unwrap()
}

pub fn fabric() -> Material {
    Orthotropic::fabric_0_90().reduce(Plane::Strain).unwrap()
}

/// Gaussian pulse exp(-((t - t_c)/width)^2) sampled at dt over `duration`.
pub fn gaussian(dt: f64, duration: f64, t_c: f64, width: f64, amplitude: f64) -> Signal {
    let n = (duration / dt).round() as usize + 1;
    Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: (0..n)
            .map(|k| amplitude * (-((k as f64 * dt - t_c) / width).powi(2)).exp())
            .collect(),
    }
}

/// A vertical strip of layers (listed top-down as (material, thickness)) meshed with square
/// elements of size h, `columns` elements wide, with rollers on the sides that make the
/// response exactly one-dimensional: the DOF along x fixed for P waves (`shear` false),
/// along y for S waves (`shear` true).
pub fn strip(
    layers_top_down: &[(Material, f64)],
    h: f64,
    columns: usize,
    shear: bool,
    bottom: BottomEdge,
) -> Model {
    let materials: Vec<Material> = layers_top_down.iter().map(|l| l.0.clone()).collect();
    let layers = layers_top_down
        .iter()
        .enumerate()
        .rev()
        .map(|(i, l)| Layer {
            material: i,
            thickness_m: l.1,
        })
        .collect();
    let lam = Laminate::from_layers(materials, layers).unwrap();
    let mesh = Mesh::layered(&lam, h * columns as f64, h, h, &[], &[]).unwrap();
    let component = if shear { 1 } else { 0 };
    let mut fixed: Vec<usize> = [Side::Left, Side::Right]
        .iter()
        .flat_map(|&s| mesh.side_nodes(s))
        .map(|n| 2 * n + component)
        .collect();
    let absorbing = match bottom {
        BottomEdge::Absorbing => vec![Side::Bottom.into()],
        BottomEdge::Fixed => {
            fixed.extend(
                mesh.side_nodes(Side::Bottom)
                    .iter()
                    .flat_map(|&n| [2 * n, 2 * n + 1]),
            );
            vec![]
        }
        BottomEdge::Free => vec![],
    };
    Model::build(mesh, lam.materials, &absorbing, fixed, None).unwrap()
}

#[derive(Clone, Copy)]
pub enum BottomEdge {
    Absorbing,
    Fixed,
    Free,
}

/// Uniform traction on the whole top edge in direction `angle_deg`.
pub fn top_traction(model: &Model, angle_deg: f64, signal: Signal) -> Source {
    let (x0, x1, _, y1) = model.mesh.bounds();
    traction_source(&model.mesh, [x0, y1], [x1, y1], angle_deg, signal).unwrap()
}

/// Velocity component averaged across the strip at `depth` below the top (snapped to a row).
pub fn depth_receiver(model: &Model, depth: f64, component: usize) -> Receiver {
    let (x0, x1, _, y1) = model.mesh.bounds();
    let y = model.mesh.nearest_row_y(y1 - depth).unwrap();
    segment_receiver(
        &model.mesh,
        &format!("depth {depth}"),
        [x0, y],
        [x1, y],
        component,
        Quantity::Velocity,
    )
    .unwrap()
}

/// Time and signed value of the largest |sample| in [t_from, t_to], refined by a parabola
/// through the three samples around it.
pub fn peak(s: &Signal, t_from: f64, t_to: f64) -> (f64, f64) {
    let k0 = (t_from / s.dt_s).ceil().max(1.0) as usize;
    let k1 = ((t_to / s.dt_s).floor() as usize).min(s.samples.len() - 2);
    let k = (k0..=k1)
        .max_by(|&a, &b| s.samples[a].abs().total_cmp(&s.samples[b].abs()))
        .unwrap();
    let (ym, y0, yp) = (s.samples[k - 1], s.samples[k], s.samples[k + 1]);
    let denom = ym - 2.0 * y0 + yp;
    let shift = if denom != 0.0 {
        0.5 * (ym - yp) / denom
    } else {
        0.0
    };
    ((k as f64 + shift) * s.dt_s, y0 - 0.25 * (ym - yp) * shift)
}

/// Relative L2 difference of two equally sampled traces.
pub fn rel_l2(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let num: f64 = (0..n).map(|i| (a[i] - b[i]).powi(2)).sum();
    let den: f64 = b[..n].iter().map(|v| v * v).sum();
    (num / den).sqrt()
}

/// A fresh, empty directory under the system temp dir, removed on drop; unique per process
/// and call.
pub struct TempDir(pub PathBuf);

impl TempDir {
    pub fn new(tag: &str) -> TempDir {
        use std::sync::atomic::{AtomicU64, Ordering};
        static N: AtomicU64 = AtomicU64::new(0);
        let dir = std::env::temp_dir().join(format!(
            "trnews-{tag}-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        TempDir(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    /// Writes a script file into the directory and returns its path.
    pub fn script(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, text).expect("write script");
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
