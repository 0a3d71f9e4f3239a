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
use crate::sem::SemModel;
use crate::signal::Signal;
use crate::solve::{self, Receiver, RunConfig, RunOutput, StabilityEstimate};

mod build;
mod crack;
mod edges;
mod presets;
mod sem;
mod sources;
mod spec;
mod t3;

use build::check_ranges;
pub use build::MAX_TRACTION_PA;
pub use crack::CrackPlacement;
pub use presets::{Resolution, SemPreset};
use sources::build_receivers;
pub use spec::{
    Absorber, CrackSpec, DiscretisationKind, DiscretisationSpec, EdgeCondition, EdgeConditions,
    GmshSpec, LaminateSpec, LayerSpec, MaterialSpec, ReceiverAt, ReceiverSpec, SceneSpec,
    SourceSpec, TransmitterSpec,
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
        let scene = match spec.discretisation.sem_cut(spec) {
            None => build_t3(spec)?,
            Some(cut) => sem::build(spec, &cut)?,
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
        Ok(scene)
    }

    /// The T3 triangulation the scene's nodes live on: the T3 mesh, or the spectral elements'
    /// node grid (same node numbering).
    pub fn mesh(&self) -> &Mesh {
        match &self.body {
            Body::T3(model) => &model.mesh,
            Body::Sem { nodes, .. } => nodes,
        }
    }

    /// Degrees of freedom of the model.
    pub fn dofs(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.dofs(),
            Body::Sem { model, .. } => model.dofs(),
        }
    }

    /// Number of elements: triangles, or spectral elements.
    pub fn elements(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.mesh.triangles.len(),
            Body::Sem { model, .. } => (model.columns_m.len() - 1) * (model.rows_m.len() - 1),
        }
    }

    /// The crack's node pairs (None without a crack or with tied faces).
    pub fn crack(&self) -> Option<&crate::mesh::Crack> {
        match &self.body {
            Body::T3(model) => model.crack.as_ref(),
            Body::Sem { model, .. } => model.crack(),
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

    /// A run configuration for this scene: its contact options and stability estimate.
    pub fn run_config(&self, duration_s: f64) -> RunConfig {
        RunConfig {
            duration_s,
            contact: self.contact(),
            stability: Some(self.stability),
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
        let Some(t) = &self.spec.transducer else {
            return self.apply_traction(drive, config);
        };
        let mut out = self.apply_traction(&t.transmit(drive, config.duration_s)?, config)?;
        for trace in &mut out.traces {
            *trace = t.receive(trace)?;
        }
        Ok(out)
    }

    /// Applies `traction` (Pa) on the transmitter segment and records the raw receiver
    /// quantities, bypassing the transducers' band.
    pub fn apply_traction(&self, traction: &Signal, config: &RunConfig) -> Result<RunOutput> {
        let source = solve::Source {
            weights: self.transmitter.clone(),
            signal: traction.clone(),
        };
        let stability = config.stability.unwrap_or(self.stability);
        let config = RunConfig {
            stability: Some(stability),
            ..config.clone()
        };
        let out = match &self.body {
            Body::T3(model) => solve::run(model, &[source], &self.receivers, &config)?,
            Body::Sem { model, .. } => sem::run(
                model,
                &[source],
                &self.receivers,
                &config,
                stability.dt_crit_s,
            )?,
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

    /// The time step runs of this scene use by default ([`STEP_FRACTION`] dt_crit).
    pub fn default_dt_s(&self) -> f64 {
        STEP_FRACTION * self.stability.dt_crit_s
    }
}
