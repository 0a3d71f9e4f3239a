//! The setup every experiment takes from its command line (`--set NAME=VALUE`), defined once:
//! the resolution preset, the discretisation, the error estimate, a requested accuracy,
//! whether the materials have losses and the crack's friction law.
//! Each has one default here ([`Experiment::default`]); a script may state its own default
//! for a study that is about something else (the triangles' convergence, say), never a second
//! parser.

use crate::attenuation::AttenuationSpec;
use crate::error::{Error, Result};
use crate::scene::{DiscretisationKind, Resolution, SceneSpec};
use crate::trnews::{ErrorEstimate, TrNewsSpec};
use serde::{Deserialize, Serialize};

/// What an experiment runs on (the channel, simulated or measured, is chosen beside it: it
/// reads data files).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Experiment {
    /// The resolution preset: the scene's elements and the TR-NEWS timings.
    pub resolution: Resolution,
    /// The discretisation of the preset scene.
    pub discretisation: DiscretisationKind,
    /// Whether the runs repeat themselves on the error estimate's companions.
    pub error_estimate: ErrorEstimate,
    /// A requested relative error of the first-pass responses: the triangles' element sizes
    /// are refined to meet it before the run ([`crate::study::resolution_for_tolerance`]) and
    /// the error estimate checks it after the run. `None`: the preset's sizes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Losses in the plies and the epoxy: the literature's quality factors
    /// ([`AttenuationSpec::report_materials`]); off by default, as in the report.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub losses: bool,
    /// The crack's friction law.
    #[serde(skip_serializing_if = "FrictionLaw::is_default")]
    pub friction_law: FrictionLaw,
}

/// The friction law on the crack's faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionLaw {
    /// The strength follows the normal force with the default response time
    /// ([`crate::contact::DEFAULT_NORMAL_STRESS_LAG_S`]).
    #[default]
    Regularised,
    /// The report's instantaneous Coulomb law.
    Instantaneous,
}

impl FrictionLaw {
    fn is_default(&self) -> bool {
        *self == FrictionLaw::default()
    }
}

impl std::str::FromStr for FrictionLaw {
    type Err = Error;

    fn from_str(text: &str) -> Result<FrictionLaw> {
        match text.trim() {
            "regularised" => Ok(FrictionLaw::Regularised),
            "instantaneous" => Ok(FrictionLaw::Instantaneous),
            _ => Err(Error::invalid(
                "friction_law",
                text,
                "expected regularised (a 20 ns friction response time, the default) or \
                 instantaneous (the report's Coulomb law)",
            )),
        }
    }
}

impl Default for Experiment {
    /// The quick preset on spectral elements, with the error estimate wherever it costs at
    /// most [`crate::trnews::AUTO_ESTIMATE_MAX_COST`] extra.
    fn default() -> Self {
        Experiment {
            resolution: Resolution::default(),
            discretisation: DiscretisationKind::default(),
            error_estimate: ErrorEstimate::Auto,
            tolerance: None,
            losses: false,
            friction_law: FrictionLaw::Regularised,
        }
    }
}

impl Experiment {
    /// The names of the setup's parameters, as `--set` takes them.
    pub const PARAMETERS: [&'static str; 6] = [
        "resolution",
        "discretisation",
        "error_estimate",
        "tolerance",
        "losses",
        "friction_law",
    ];

    /// Sets parameter `name` from the text the user wrote; an unknown name or a value the
    /// parameter does not take is an error naming both.
    pub fn set(&mut self, name: &str, text: &str) -> Result<()> {
        match name {
            "resolution" => self.resolution = text.parse()?,
            "discretisation" => self.discretisation = text.parse()?,
            "error_estimate" => self.error_estimate = text.parse()?,
            "tolerance" => self.tolerance = Some(tolerance(text)?),
            "losses" => self.losses = switch("losses", text)?,
            "friction_law" => self.friction_law = text.parse()?,
            other => {
                return Err(Error::invalid(
                    "experiment parameter",
                    other,
                    format!("expected one of {}", Self::PARAMETERS.join(", ")),
                ))
            }
        }
        Ok(())
    }

    /// The TR-NEWS timings of the resolution.
    pub fn tr_news(&self) -> TrNewsSpec {
        TrNewsSpec::preset(self.resolution)
    }

    /// The preset scene (cracked) on the chosen discretisation, with the losses and the
    /// friction law asked for, before any refinement for the tolerance.
    pub fn scene_spec(&self) -> SceneSpec {
        let mut spec = SceneSpec {
            attenuation: self.losses.then(AttenuationSpec::report_materials),
            ..SceneSpec::preset_on(self.resolution, self.discretisation)
        };
        if self.friction_law == FrictionLaw::Instantaneous {
            let contact = spec.crack.as_mut().and_then(|c| c.contact.as_mut());
            if let Some(contact) = contact {
                contact.normal_stress_lag_s = 0.0;
            }
        }
        spec
    }

    /// The error estimate the runs get: always on when a tolerance is asked for, since the
    /// estimate is how the tolerance is checked after the run.
    pub fn estimate(&self) -> ErrorEstimate {
        match self.tolerance {
            Some(_) => ErrorEstimate::On,
            None => self.error_estimate,
        }
    }
}

/// `true` or `false` as written, for parameter `name`.
fn switch(name: &str, text: &str) -> Result<bool> {
    match text.trim() {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(Error::invalid(name, text, "expected true or false")),
    }
}

/// A tolerance as written: a relative error in (0, 1).
fn tolerance(text: &str) -> Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t < 1.0 => Ok(t),
        _ => Err(Error::invalid(
            "tolerance",
            text,
            "expected a relative error between 0 and 1 (e.g. 0.05)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_quick_preset_on_spectral_elements_with_auto_estimate() {
        let e = Experiment::default();
        assert_eq!(e.resolution, Resolution::Quick);
        assert_eq!(e.discretisation, DiscretisationKind::Sem);
        assert_eq!(e.estimate(), ErrorEstimate::Auto);
        assert_eq!(e.scene_spec(), SceneSpec::preset(Resolution::Quick));
    }

    #[test]
    fn set_parses_each_parameter_and_names_bad_values() {
        let mut e = Experiment::default();
        e.set("resolution", "smoke").unwrap();
        e.set("discretisation", "t3").unwrap();
        e.set("error_estimate", "false").unwrap();
        e.set("losses", "true").unwrap();
        assert!(e.scene_spec().attenuation.is_some());
        let lag = |e: &Experiment| {
            e.scene_spec()
                .crack
                .unwrap()
                .contact
                .unwrap()
                .normal_stress_lag_s
        };
        assert_eq!(lag(&e), crate::contact::DEFAULT_NORMAL_STRESS_LAG_S);
        e.set("friction_law", "instantaneous").unwrap();
        assert_eq!(lag(&e), 0.0, "the report's law");
        e.set("friction_law", "regularised").unwrap();
        assert_eq!(lag(&e), crate::contact::DEFAULT_NORMAL_STRESS_LAG_S);
        assert_eq!(e.estimate(), ErrorEstimate::Off);
        e.set("tolerance", "0.05").unwrap();
        assert_eq!(e.tolerance, Some(0.05));
        assert_eq!(
            e.estimate(),
            ErrorEstimate::On,
            "a tolerance is checked by the estimate"
        );
        for (name, text, named) in [
            ("resolution", "fast", "fast"),
            ("discretisation", "q4", "q4"),
            ("error_estimate", "maybe", "maybe"),
            ("tolerance", "0", "tolerance"),
            ("tolerance", "1.5", "1.5"),
            ("tolerance", "NaN", "NaN"),
            ("losses", "yes", "yes"),
            ("friction_law", "coulomb", "coulomb"),
            ("order", "7", "order"),
        ] {
            let message = e.set(name, text).unwrap_err().to_string();
            assert!(message.contains(named), "{name}={text}: {message}");
        }
    }
}
