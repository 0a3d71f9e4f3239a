//! The setup every experiment takes from its command line (`--set NAME=VALUE`), defined once:
//! the resolution preset, the discretisation, the error estimate, a requested accuracy and
//! whether the materials have losses.
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
        }
    }
}

impl Experiment {
    /// The names of the setup's parameters, as `--set` takes them.
    pub const PARAMETERS: [&'static str; 5] = [
        "resolution",
        "discretisation",
        "error_estimate",
        "tolerance",
        "losses",
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

    /// The preset scene (cracked) on the chosen discretisation, with the losses when asked,
    /// before any refinement for the tolerance.
    pub fn scene_spec(&self) -> SceneSpec {
        SceneSpec {
            attenuation: self.losses.then(AttenuationSpec::report_materials),
            ..SceneSpec::preset_on(self.resolution, self.discretisation)
        }
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
            ("order", "7", "order"),
        ] {
            let message = e.set(name, text).unwrap_err().to_string();
            assert!(message.contains(named), "{name}={text}: {message}");
        }
    }
}
