//! Small scenes shared by the physics tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use trnews::attenuation::{AttenuationSpec, QualitySpec};
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
    strip_of(&laminate(layers_top_down), (h, h), columns, shear, bottom)
}

/// The strip of [`strip`] for a laminate, on elements of `(width, height)` (a thin layer gets
/// one row of its thickness).
pub fn strip_of(
    lam: &Laminate,
    (width, height): (f64, f64),
    columns: usize,
    shear: bool,
    bottom: BottomEdge,
) -> Model {
    let mesh = Mesh::layered(lam, width * columns as f64, width, height, &[], &[]).unwrap();
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
    Model::build(mesh, lam.materials.clone(), &absorbing, fixed, None).unwrap()
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

/// Relative L2 distance of `a` to `reference` sampled at `a`'s times: both start at t = 0 and
/// `reference`'s step divides `a`'s (a run against the same at a step k times smaller).
pub fn rel_l2_on_coarser(a: &Signal, reference: &Signal) -> f64 {
    let k = (a.dt_s / reference.dt_s).round() as usize;
    let b: Vec<f64> = (0..a.len()).map(|i| reference.samples[i * k]).collect();
    rel_l2(&a.samples, &b)
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

/// How a wave test discretises its strip.
#[derive(Clone, Copy, Debug)]
pub enum Discretisation {
    /// Linear triangles with elements of `h`, 4 columns wide ([`strip`]).
    T3 { h: f64 },
    /// Spectral elements of `order`, one element `width` wide, element rows no taller.
    Sem { order: usize, width: f64 },
}

/// A vertical strip as [`strip`] describes it, in either discretisation, with what the wave
/// tests do to it: a traction on the top, receivers across the strip at a depth, a run.
// One per test run: the variants' different sizes cost nothing.
#[allow(clippy::large_enum_variant)]
pub enum WaveStrip {
    /// Linear triangles.
    T3(Model),
    /// Spectral elements and their Lanczos critical step.
    Sem(trnews::sem::SemModel, f64),
}

impl WaveStrip {
    /// The strip of `layers_top_down` with rollers on the sides (u_x held for P waves, u_y
    /// for S waves) and the `bottom` edge.
    pub fn new(
        how: Discretisation,
        layers_top_down: &[(Material, f64)],
        shear: bool,
        bottom: BottomEdge,
    ) -> WaveStrip {
        let (order, width) = match how {
            Discretisation::T3 { h } => {
                return WaveStrip::T3(strip(layers_top_down, h, 4, shear, bottom))
            }
            Discretisation::Sem { order, width } => (order, width),
        };
        let cut = trnews::sem::SemSpec {
            order_x: order,
            min_order_y: 1,
            max_order_y: order,
            extra_order_y: 0,
            rule_order_x: None,
            element_size_x_m: width,
            element_size_y_m: width,
            fine_x: None,
        };
        let m = trnews::sem::SemModel::layered(&laminate(layers_top_down), width, &cut).unwrap();
        WaveStrip::sem(m, shear, bottom)
    }

    /// The spectral elements `m` as the strip: rollers on the sides (u_x held for P waves,
    /// u_y for S waves) and the `bottom` edge, with the Lanczos critical step.
    pub fn sem(mut m: trnews::sem::SemModel, shear: bool, bottom: BottomEdge) -> WaveStrip {
        let (last, lines) = (m.x_nodes_m.len() - 1, m.y_nodes_m.len());
        let held = usize::from(shear);
        m.fixed_dofs = (0..lines)
            .flat_map(|j| [2 * m.node(0, j) + held, 2 * m.node(last, j) + held])
            .collect();
        match bottom {
            BottomEdge::Absorbing => m.dashpots = m.lysmer_dashpots(&[Side::Bottom]),
            BottomEdge::Fixed => {
                let bottom: Vec<usize> = (0..=last)
                    .flat_map(|i| [2 * m.node(i, 0), 2 * m.node(i, 0) + 1])
                    .collect();
                m.fixed_dofs.extend(bottom);
            }
            BottomEdge::Free => {}
        }
        let mut free = vec![true; m.dofs()];
        for &d in &m.fixed_dofs {
            free[d] = false;
        }
        let dt_crit = 2.0 / m.max_eigenvalue(&free).0.sqrt();
        WaveStrip::Sem(m, dt_crit)
    }

    /// The critical step of central differences (s): the Lanczos estimate.
    pub fn dt_crit(&self) -> f64 {
        match self {
            WaveStrip::T3(model) => trnews::solve::stability::estimate(model).dt_crit_s,
            WaveStrip::Sem(_, dt_crit) => *dt_crit,
        }
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        match self {
            WaveStrip::T3(model) => model.mesh.nodes.len(),
            WaveStrip::Sem(m, _) => m.nodes(),
        }
    }

    /// A uniform traction over the top in direction `angle_deg` (counter-clockwise from +x).
    pub fn top_traction(&self, angle_deg: f64, signal: Signal) -> Source {
        match self {
            WaveStrip::T3(model) => top_traction(model, angle_deg, signal),
            WaveStrip::Sem(m, _) => {
                let (s, c) = angle_deg.to_radians().sin_cos();
                let width = m.columns_m[m.columns_m.len() - 1];
                let weights = m
                    .side_load(Side::Top, 0.0, width)
                    .into_iter()
                    .flat_map(|(n, w)| [(2 * n, c * w), (2 * n + 1, s * w)])
                    .collect();
                Source { weights, signal }
            }
        }
    }

    /// Velocity component averaged across the strip at `depth` below the top (snapped to a
    /// node row; for spectral elements with the GLL weights along x).
    pub fn depth_receiver(&self, depth: f64, component: usize) -> Receiver {
        match self {
            WaveStrip::T3(model) => depth_receiver(model, depth, component),
            WaveStrip::Sem(m, _) => {
                let (ys, width) = (&m.y_nodes_m, m.columns_m[m.columns_m.len() - 1]);
                let y = ys[ys.len() - 1] - depth;
                let j = (0..ys.len())
                    .min_by(|&a, &b| (ys[a] - y).abs().total_cmp(&(ys[b] - y).abs()))
                    .unwrap();
                let weights = m
                    .side_load(Side::Bottom, 0.0, width)
                    .into_iter()
                    .map(|(n, w)| (2 * m.node(n % m.nx(), j) + component, w / width))
                    .collect();
                Receiver {
                    name: format!("depth {depth}"),
                    weights,
                    quantity: Quantity::Velocity,
                }
            }
        }
    }

    /// Runs the strip (central differences at `config`'s step or 0.9 dt_crit).
    pub fn run(
        &self,
        sources: &[Source],
        receivers: &[Receiver],
        config: &trnews::solve::RunConfig,
    ) -> trnews::error::Result<trnews::solve::RunOutput> {
        match self {
            WaveStrip::T3(model) => trnews::solve::run(model, sources, receivers, config),
            WaveStrip::Sem(m, dt_crit) => {
                trnews::solve::run_on(m, *dt_crit, sources, receivers, config)
            }
        }
    }
}

/// The laminate of layers listed top-down as (material, thickness).
pub fn laminate(layers_top_down: &[(Material, f64)]) -> Laminate {
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
    Laminate::from_layers(materials, layers).unwrap()
}

/// The pushed block of the friction tests (tests/contact.rs on T3, tests/sem_contact.rs on
/// spectral elements): its width, the load's ramp time and the run's duration (s).
pub const BLOCK_WIDTH: f64 = 2e-3;
/// See [`BLOCK_WIDTH`].
pub const RAMP: f64 = 1e-6;
/// See [`BLOCK_WIDTH`].
pub const DURATION: f64 = 5e-6;

/// The push on the block at step `dt`: `magnitude` (Pa) ramped up over [`RAMP`] by a smooth
/// half cosine (5 wave transits of the block, so the load is quasi-static and the block barely
/// bounces on the face), then constant, over [`DURATION`].
pub fn ramped_push(magnitude: f64, dt: f64) -> Signal {
    let ramp = |t: f64| {
        if t < RAMP {
            0.5 * (1.0 - (std::f64::consts::PI * t / RAMP).cos())
        } else {
            1.0
        }
    };
    Signal {
        dt_s: dt,
        t0_s: 0.0,
        samples: (0..(DURATION / dt) as usize + 2)
            .map(|k| magnitude * ramp(k as f64 * dt))
            .collect(),
    }
}

/// Average of a trace from RAMP + 0.5 us to the end.
pub fn mean_after_ramp(v: &Signal) -> f64 {
    let k1 = ((RAMP + 0.5e-6) / v.dt_s) as usize;
    v.samples[k1..].iter().sum::<f64>() / (v.samples.len() - k1) as f64
}

/// Mean acceleration from the velocity trace between RAMP + 0.5 us and the end.
pub fn acceleration_after_ramp(v: &Signal) -> f64 {
    let (k1, k2) = (((RAMP + 0.5e-6) / v.dt_s) as usize, v.samples.len() - 1);
    (v.samples[k2] - v.samples[k1]) / ((k2 - k1) as f64 * v.dt_s)
}

/// The pressure on the top at step `dt` over `duration`: the Gaussian drive
/// exp(-((t - 4 width) / width)^2) through the default transducer band.
pub fn band_pressure(dt: f64, duration: f64, width: f64) -> Signal {
    let drive = gaussian(dt, duration, 4.0 * width, width, 1.0);
    trnews::transducer::TransducerSpec::default()
        .transmit(&drive, duration)
        .unwrap()
}

/// Relative L2 error of `trace` against `exact`, both through the default receiving band,
/// over the samples they share before `until`.
pub fn band_error(trace: &Signal, exact: &Signal, until: f64) -> f64 {
    let band = trnews::transducer::TransducerSpec::default();
    let (a, b) = (band.receive(trace).unwrap(), band.receive(exact).unwrap());
    let n = ((until / a.dt_s) as usize).min(a.len()).min(b.len());
    rel_l2(&a.samples[..n], &b.samples[..n])
}

/// The exact u_y(y, t_n), t_n = n dt, of a plane P wave in a layer stack (`layers_bottom_up`:
/// material, thickness) under the uniform normal traction `drive(t)` on its top edge, above a
/// Lysmer-Kuhlemeyer dashpot (rho c of the bottom material's stored C22; the unrelaxed one
/// where it relaxes), at heights `ys` above the bottom. Per frequency the state
/// (U, S = C22(w) dU/dy) starts at the bottom as (1, i w z), is carried up through each layer
/// by U' = cos(kd) U + sin(kd) / (C k) S, S' = -C k sin(kd) U + cos(kd) S,
/// k = w sqrt(rho / C22(w)) (C22(w) complex where the material relaxes), and is scaled so
/// that S at the top is the drive's spectrum. The drive is periodised over a window 16x the
/// run, long enough for the radiating stack to have rung down.
pub fn plane_wave_in_stack(
    layers_bottom_up: &[(Material, f64)],
    drive: impl Fn(f64) -> f64,
    dt: f64,
    steps: usize,
    ys: &[f64],
) -> Vec<Vec<f64>> {
    use rustfft::num_complex::Complex64;
    let c22 = |m: &Material, omega: f64| match &m.relaxation {
        Some(r) => r.stiffness_at(omega)[1][1],
        None => Complex64::new(m.stiffness_pa[1][1], 0.0),
    };
    let height: f64 = layers_bottom_up.iter().map(|l| l.1).sum();
    let bottom = &layers_bottom_up[0].0;
    let z = (bottom.stiffness_pa[1][1] * bottom.density_kg_m3).sqrt();
    let n = (16 * steps).next_power_of_two();
    let mut planner = rustfft::FftPlanner::new();
    let mut g: Vec<Complex64> = (0..n)
        .map(|k| Complex64::new(drive(k as f64 * dt), 0.0))
        .collect();
    planner.plan_fft_forward(n).process(&mut g);
    let mut responses = vec![vec![Complex64::new(0.0, 0.0); n]; ys.len()];
    for k in 1..n {
        let signed = if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        };
        let omega = 2.0 * std::f64::consts::PI * signed / (n as f64 * dt);
        let at_y = |y: f64| {
            let mut state = (Complex64::new(1.0, 0.0), Complex64::new(0.0, omega * z));
            let mut base = 0.0;
            for (m, d) in layers_bottom_up {
                let c = c22(m, omega);
                let wave = omega * (m.density_kg_m3 / c).sqrt();
                let phase = wave * (y - base).clamp(0.0, *d);
                let (sin, cos) = (phase.sin(), phase.cos());
                state = (
                    cos * state.0 + sin / (c * wave) * state.1,
                    -c * wave * sin * state.0 + cos * state.1,
                );
                if y <= base + d {
                    break;
                }
                base += d;
            }
            state
        };
        let top = at_y(height).1;
        for (r, &y) in responses.iter_mut().zip(ys) {
            r[k] = g[k] * at_y(y).0 / top;
        }
    }
    let inverse = planner.plan_fft_inverse(n);
    responses
        .into_iter()
        .map(|mut r| {
            inverse.process(&mut r);
            r[..steps].iter().map(|v| v.re / n as f64).collect()
        })
        .collect()
}

/// The plane-wave set-up of the stack tests: a uniform normal traction on the top edge
/// (scale 1: the drive is sigma_yy there), roller sides, a dashpot bottom, no transducer,
/// no crack; the rest as `SceneSpec::default()`.
pub fn plane_wave_scene() -> trnews::scene::SceneSpec {
    use trnews::scene::{Absorber, EdgeCondition, EdgeConditions, SceneSpec, SourceSpec};
    SceneSpec {
        absorbing: vec![],
        edges: EdgeConditions {
            bottom: Some(EdgeCondition::Absorbing),
            top: Some(EdgeCondition::Free),
            left: Some(EdgeCondition::Roller),
            right: Some(EdgeCondition::Roller),
        },
        absorber: Absorber::Dashpot,
        transducer: None,
        crack: None,
        sources: vec![SourceSpec::Normal {
            edge: Side::Top,
            x_m: None,
            depth_m: None,
            scale: 1.0,
        }],
        ..Default::default()
    }
}

/// The Gmsh mesh `tests/scripts/<file>` with material presets by physical surface group
/// (`(tag, preset)`), on spectral elements of `order` (its triangles when `None`), uncracked.
pub fn gmsh_mesh(
    file: &str,
    materials: &[(&str, &str)],
    order: Option<usize>,
) -> trnews::scene::GmshSpec {
    use trnews::scene::{GmshSpec, MaterialSpec};
    GmshSpec {
        path: Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/scripts")
            .join(file)
            .to_string_lossy()
            .into(),
        materials: materials
            .iter()
            .map(|&(k, m)| (k.to_string(), MaterialSpec::Preset(m.into())))
            .collect(),
        crack_line: None,
        contact: None,
        tied: false,
        order,
        angles_deg: Default::default(),
        axes_round: Default::default(),
        absorbing_lines: vec![],
        bytes: None,
    }
}

/// Strong losses, so that they change the traces by tens of percent: Q_P 20 and Q_S 10 in
/// the fabric, 15 and 8 in the epoxy, 3 mechanisms over the report's band.
pub fn strong_losses() -> AttenuationSpec {
    let q = |q_p, q_s| QualitySpec { q_p, q_s };
    AttenuationSpec {
        band_hz: [2e5, 2e6],
        mechanisms: 3,
        reference_hz: None,
        quality: [
            ("fabric_0_90".to_string(), q(20.0, 10.0)),
            ("epoxy".to_string(), q(15.0, 8.0)),
        ]
        .into(),
    }
}
