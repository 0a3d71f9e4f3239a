//! A whole experiment setup, described by data (a Rhai object map or JSON) and built into a
//! model: laminate -> mesh -> crack -> model, plus the transmitter and the receivers
//! (report Sec. 5.1, Fig. 14). A scene builds only what it names: no crack means no contact
//! pairs, no absorbing side means no dashpots.
//!
//! By role: `spec` is the data a scene is made of and `presets` the named ones; the build
//! steps both discretisations share are in `build`, `crack`, `edges` and `sources`; `t3` and
//! `sem` build the scene on linear triangles and on spectral elements.

use crate::contact::ContactOptions;
use crate::error::{require_positive, Error, Result};
use crate::fem::Model;
use crate::laminate::Laminate;
use crate::mesh::Mesh;
use crate::sem::unstructured::UnstructuredSem;
use crate::sem::SemModel;
use crate::signal::Signal;
use crate::solve::time_dispersion::TimeDispersion;
use crate::solve::{self, Receiver, RunConfig, RunOutput, StabilityEstimate};

mod build;
mod crack;
mod edges;
mod presets;
mod sem;
mod sources;
mod spec;
mod t3;
mod unstructured;

use build::check_ranges;
pub use build::MAX_TRACTION_PA;
pub use crack::CrackPlacement;
pub use presets::{Resolution, SemPreset};
use sources::build_receivers;
pub use spec::{
    Absorber, CrackSpec, DiscretisationKind, DiscretisationSpec, EdgeCondition, EdgeConditions,
    GmshSpec, LaminateSpec, LayerSpec, MaterialSpec, ReceiverAt, ReceiverSpec, SceneSpec,
    SourceSpec, TimeDispersionSpec, TransmitterSpec,
};
use t3::build_t3;

pub use crate::solve::STEP_FRACTION;

/// The discrete model of a scene.
// One per scene, shared behind an Arc: the variants' different sizes cost nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Body {
    /// Linear triangles (the report's method).
    T3(Model),
    /// Spectral elements, with the T3 triangulation of their node grid (the same node
    /// numbering, crack duplicates included) on which nodes are selected, fields are plotted
    /// and written as VTU (each GLL cell as two triangles).
    Sem {
        /// The spectral elements.
        model: SemModel,
        /// Their node grid as triangles.
        nodes: Mesh,
    },
    /// Spectral elements on a Gmsh mesh of quadrilaterals, with their GLL nodes as
    /// triangles (same numbering), as for the layered ones.
    Unstructured {
        /// The spectral elements.
        model: UnstructuredSem,
        /// Their GLL nodes as triangles.
        nodes: Mesh,
    },
}

/// A built scene: the model, the transmitter's nodal weights, the receivers.
#[derive(Clone, Debug)]
pub struct Scene {
    /// What it was built from.
    pub spec: SceneSpec,
    /// The layer stack.
    pub laminate: Laminate,
    /// The discrete model.
    pub body: Body,
    /// Transmitter nodal weights per unit traction.
    pub transmitter: Vec<(usize, f64)>,
    /// Receivers 1..n.
    pub receivers: Vec<Receiver>,
    /// Where the crack was put on the mesh, requested vs used (None without a crack).
    pub crack_placement: Option<CrackPlacement>,
    /// Explicit stability estimate, computed once.
    pub stability: StabilityEstimate,
}

impl Scene {
    /// Builds the scene: laminate, layer-conforming mesh, the crack's node pairs, K, M,
    /// dashpots, transmitter, receivers, and the stability estimate.
    ///
    /// The mesh does not depend on the crack (it is snapped onto the mesh lines, see
    /// [`CrackSpec`]). A cracked scene and its tied companion ([`SceneSpec::uncracked`])
    /// share one time step: both take the Lanczos estimate of the cracked (split) model.
    /// That is the smaller limit of the two: tying the faces restricts the split model to
    /// the subspace u_master = u_slave (K_tied = T^T K T and, with row-sum lumping,
    /// M_tied = T^T M T), so by the Rayleigh-quotient (Courant-Fischer) principle
    /// omega_max(tied) <= omega_max(split), and contact by exact multipliers only constrains
    /// the split model further (report Sec. 4.8.2, 4.9).
    pub fn build(spec: &SceneSpec) -> Result<Scene> {
        check_ranges(spec)?;
        if let Some(contact) = spec.contact() {
            contact.validate()?;
        }
        let quads = spec.gmsh.as_ref().and_then(|g| g.order.map(|p| (g, p)));
        let scene = match (spec.discretisation.sem_cut(spec), quads) {
            (None, Some((g, order))) => unstructured::build(spec, g, order)?,
            (None, None) => build_t3(spec)?,
            (Some(cut), _) => sem::build(spec, &cut)?,
        };
        crate::budget::check()?;
        let dt_crit = scene.stability.dt_crit_s;
        if !(dt_crit.is_finite() && dt_crit > 0.0) {
            return Err(Error::invalid(
                "laminate (materials)",
                format!("dt_crit = {dt_crit} s"),
                "the critical time step is not a finite positive number: a density or \
                 modulus is too small or too large for double precision",
            ));
        }
        if let Some(dt) = spec.time_step_s {
            if !(dt.is_finite() && dt > 0.0 && dt <= dt_crit) {
                return Err(Error::invalid(
                    "time_step_s",
                    dt,
                    format!("must be a positive step at most the scene's dt_crit = {dt_crit:e} s"),
                ));
            }
        }
        Ok(scene)
    }

    /// The T3 triangulation the scene's nodes live on: the T3 mesh, or the spectral elements'
    /// node grid (same node numbering).
    pub fn mesh(&self) -> &Mesh {
        match &self.body {
            Body::T3(model) => &model.mesh,
            Body::Sem { nodes, .. } | Body::Unstructured { nodes, .. } => nodes,
        }
    }

    /// Degrees of freedom of the model.
    pub fn dofs(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.dofs(),
            Body::Sem { model, .. } => model.dofs(),
            Body::Unstructured { model, .. } => model.dofs(),
        }
    }

    /// Number of elements: triangles, or spectral elements.
    pub fn elements(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.mesh.triangles.len(),
            Body::Sem { model, .. } => (model.columns_m.len() - 1) * (model.rows_m.len() - 1),
            Body::Unstructured { model, .. } => model.elements(),
        }
    }

    /// The crack's node pairs (None without a crack or with tied faces).
    pub fn crack(&self) -> Option<&crate::mesh::Crack> {
        match &self.body {
            Body::T3(model) => model.crack.as_ref(),
            Body::Sem { model, .. } => model.crack(),
            Body::Unstructured { model, .. } => model.crack.as_ref(),
        }
    }

    /// True when the scene is linear time-invariant: no crack, or a crack without contact.
    pub fn is_linear(&self) -> bool {
        self.crack().is_none() || self.contact().is_none()
    }

    /// The contact options of the scene's crack ([`SceneSpec::contact`]).
    pub fn contact(&self) -> Option<ContactOptions> {
        self.spec.contact()
    }

    /// A run configuration for this scene: its step when the spec fixes one and its contact
    /// options.
    pub fn run_config(&self, duration_s: f64) -> RunConfig {
        RunConfig {
            duration_s,
            dt_s: self.spec.time_step_s,
            contact: self.contact(),
            ..Default::default()
        }
    }

    /// Drives the transmitter with `drive` (Pa) and records every receiver, through the
    /// transducers' band when the scene has one: the traction is B * drive and each trace
    /// B * the raw receiver quantity (see [`crate::transducer`]).
    pub fn transmit(&self, drive: &Signal, config: &RunConfig) -> Result<RunOutput> {
        require_positive("duration_s", config.duration_s)?;
        if let Some(d) = config.dt_s {
            require_positive("dt_s", d)?;
        }
        let dt = config.dt_s.unwrap_or(self.default_dt_s());
        let samples = config.duration_s / dt;
        let (field, value) = match config.dt_s {
            Some(d) if d < 1e-12 => ("dt_s", d),
            _ => ("duration_s", config.duration_s),
        };
        crate::budget::check_memory(
            field,
            format!("{value} s ({samples:.3e} steps of {dt:.3e} s)"),
            8.0 * samples * (self.receivers.len() as f64 + 4.0),
            "shorten the run",
        )?;
        let transducer = self.spec.transducer.as_ref();
        let time_dispersion = self.time_dispersion(config, dt)?;
        let run = time_dispersion.map_or_else(|| config.clone(), |td| td.extended(config));
        // the band-pass's ringing kept over the whole run, the margin included
        let traction = match transducer {
            Some(t) => t.transmit(drive, run.duration_s)?,
            None => drive.clone(),
        };
        let mut out = match time_dispersion {
            Some(td) => {
                let mut out = self.apply_traction(&td.add_to_source(&traction)?, &run)?;
                self.remove_time_dispersion(&td, &mut out, config)?;
                out
            }
            None => self.apply_traction(&traction, config)?,
        };
        if let Some(t) = transducer {
            for trace in &mut out.traces {
                *trace = t.receive(trace)?;
            }
        }
        Ok(out)
    }

    /// The raw receiver quantities after a unit traction sample at t = 0 (the discrete
    /// impulse response every linear transmission convolves with), with the time step's
    /// error removed when the scene asks ([`SceneSpec::time_dispersion`]): convolving the
    /// corrected response with a traction is the forward transform, the run and the inverse
    /// transform in one.
    pub fn impulse_response(&self, config: &RunConfig) -> Result<RunOutput> {
        let dt = config.dt_s.unwrap_or(self.default_dt_s());
        let unit = Signal {
            dt_s: dt,
            t0_s: 0.0,
            samples: vec![1.0],
        };
        let Some(td) = self.time_dispersion(config, dt)? else {
            return self.apply_traction(&unit, config);
        };
        let mut out = self.apply_traction(&unit, &td.extended(config))?;
        self.remove_time_dispersion(&td, &mut out, config)?;
        Ok(out)
    }

    /// The time-dispersion transforms of a run of this scene at step `dt`, when the scene
    /// asks for them, the integrator's error is a frequency map and the step can cover the
    /// band ([`TimeDispersionSpec`]); the run's report says which.
    fn time_dispersion(&self, config: &RunConfig, dt: f64) -> Result<Option<TimeDispersion>> {
        let Some(spec) = &self.spec.time_dispersion else {
            return Ok(None);
        };
        let field = "time_dispersion.up_to_hz";
        if !(spec.up_to_hz.is_finite() && spec.up_to_hz > 0.0) {
            return Err(Error::invalid(
                field,
                spec.up_to_hz,
                "must be a positive frequency (Hz)",
            ));
        }
        if spec.up_to_hz >= TimeDispersion::band_limit_hz(dt) {
            return Ok(None);
        }
        if let Some(t) = &self.spec.transducer {
            if spec.up_to_hz <= t.f_hi_hz {
                return Err(Error::invalid(
                    field,
                    spec.up_to_hz,
                    format!(
                        "must be above the transducers' band (transducer.f_hi_hz = {:e} Hz)",
                        t.f_hi_hz
                    ),
                ));
            }
        }
        TimeDispersion::of_run(config.integrator, dt, spec.up_to_hz, field)
    }

    /// The inverse transform on every trace of `out` (a run extended by
    /// [`TimeDispersion::extended`]), each cut back to the run `config` asked for; stated in
    /// the report.
    fn remove_time_dispersion(
        &self,
        td: &TimeDispersion,
        out: &mut RunOutput,
        config: &RunConfig,
    ) -> Result<()> {
        for (trace, receiver) in out.traces.iter_mut().zip(&self.receivers) {
            *trace = td.recorded(trace, receiver.quantity, config)?;
        }
        out.report.time_dispersion_removed_up_to_hz = Some(td.up_to_hz());
        Ok(())
    }

    /// Applies `traction` (Pa) on the transmitter segment and records the raw receiver
    /// quantities, bypassing the transducers' band.
    pub fn apply_traction(&self, traction: &Signal, config: &RunConfig) -> Result<RunOutput> {
        let source = solve::Source {
            weights: self.transmitter.clone(),
            signal: traction.clone(),
        };
        let dt_crit_s = self.stability.dt_crit_s;
        let out = match &self.body {
            Body::T3(model) => solve::run_on(
                &solve::Fem::new(model),
                dt_crit_s,
                &[source],
                &self.receivers,
                config,
            )?,
            Body::Sem { model, .. } => {
                solve::run_on(model, dt_crit_s, &[source], &self.receivers, config)?
            }
            Body::Unstructured { model, .. } => {
                solve::run_on(model, dt_crit_s, &[source], &self.receivers, config)?
            }
        };
        let drive_max = traction.max_abs();
        if drive_max > 0.0
            && out.report.source_work_j == 0.0
            && out
                .traces
                .iter()
                .all(|t| t.samples.iter().all(|&v| v == 0.0))
        {
            return Err(Error::invalid(
                "drive signal (amplitude)",
                format!("{drive_max:e} Pa"),
                "every receiver recorded exactly zero and the source did no work: the input \
                 underflowed in double precision; use a larger amplitude",
            ));
        }
        Ok(out)
    }

    /// The time step runs of this scene use by default: the spec's `time_step_s`, else
    /// [`STEP_FRACTION`] dt_crit.
    pub fn default_dt_s(&self) -> f64 {
        self.spec
            .time_step_s
            .unwrap_or(STEP_FRACTION * self.stability.dt_crit_s)
    }
}
