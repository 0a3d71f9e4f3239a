//! Rhai module `experiment`: the setup every experiment script takes from `--set`
//! ([`crate::experiment::Experiment`]: resolution, discretisation, error_estimate, tolerance,
//! losses;
//! and the channel, [`crate::script::channel`]), read in this one place. Type: `Experiment`.
//!
//! Every value is validated when the setup is read, but a parameter counts as read (see
//! [`crate::script::Host::unread_params`]) only when the script uses what it sets: a script
//! that never asks for a responder does not take `error_estimate`, and says so when given it.

use crate::experiment::Experiment;
use crate::script::convert::{error, options, ScriptResult};
use crate::script::HostContext;
use rhai::plugin::*;
use rhai::{Engine, Map, Module, NativeCallContext};

/// Registers the display name of the custom type.
pub fn register_types(engine: &mut Engine) {
    engine.register_type_with_name::<Experiment>("Experiment");
}

/// The `experiment` module.
pub fn module() -> Module {
    exported_module!(experiment_api)
}

/// The setup: the script's own defaults (`defaults`, fields of [`Experiment`]) over the
/// library's, then every `--set` parameter of the setup over those.
fn read_setup(ctx: &NativeCallContext, defaults: Map) -> ScriptResult<Experiment> {
    let mut e: Experiment = options(ctx, defaults, &Experiment::default(), "experiment")?;
    let host = HostContext::of(ctx)?;
    for name in Experiment::PARAMETERS {
        if let Some(value) = host.given(name) {
            e.set(name, &value.to_string()).map_err(|m| error(ctx, m))?;
        }
    }
    Ok(e)
}

/// Marks the `--set` parameters `names` as read: the script uses what they set.
fn uses(ctx: &NativeCallContext, names: &[&str]) -> ScriptResult<()> {
    let host = HostContext::of(ctx)?;
    for name in names {
        host.param(name);
    }
    Ok(())
}

#[export_module]
mod experiment_api {
    use super::{read_setup, uses};
    use crate::experiment::Experiment;
    use crate::script::convert::{to_dynamic, WithPosition};
    use crate::script::scene::SceneRef;
    use crate::trnews::Responder;
    use rhai::{Dynamic, Map, NativeCallContext, FLOAT};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// The experiment's setup from `--set`: resolution = quick (default) | paper | smoke; discretisation = sem (default) | t3; error_estimate = auto (default: on where the companions cost at most 30% extra) | true | false; tolerance = a relative error of the first-pass responses (triangles' element sizes refined to meet it; turns the estimate on to check it); losses = false (default, as in the report) | true (the literature's quality factors of the plies and the epoxy; central differences or Newmark, not the fourth-order step); friction_law = regularised (default: the crack's friction strength follows the normal force with a 20 ns response time) | instantaneous (the report's Coulomb law, ill-conditioned on spectral elements). A bad value is an error naming the parameter and the value.
    #[rhai_fn(return_raw)]
    pub fn setup(ctx: NativeCallContext) -> Res<Experiment> {
        read_setup(&ctx, Map::new())
    }

    /// The setup with this script's own defaults for some of its fields (e.g. #{discretisation: "t3"} for a study of the triangles), under the `--set` parameters.
    #[rhai_fn(name = "setup", return_raw)]
    pub fn setup_with(ctx: NativeCallContext, defaults: Map) -> Res<Experiment> {
        read_setup(&ctx, defaults)
    }

    /// The resolution preset's name: "quick", "paper" or "smoke".
    #[rhai_fn(global, get = "resolution", pure, return_raw)]
    pub fn resolution(ctx: NativeCallContext, e: &mut Experiment) -> Res<Dynamic> {
        uses(&ctx, &["resolution"])?;
        to_dynamic(&ctx, &e.resolution)
    }

    /// The discretisation's name: "sem" or "t3".
    #[rhai_fn(global, get = "discretisation", pure, return_raw)]
    pub fn discretisation(ctx: NativeCallContext, e: &mut Experiment) -> Res<Dynamic> {
        uses(&ctx, &["discretisation"])?;
        to_dynamic(&ctx, &e.discretisation)
    }

    /// Whether the preset scene's materials have losses (`losses`, off by default).
    #[rhai_fn(global, get = "losses", pure, return_raw)]
    pub fn losses(ctx: NativeCallContext, e: &mut Experiment) -> Res<bool> {
        uses(&ctx, &["losses"])?;
        Ok(e.losses)
    }

    /// The error estimate the runs get: true, false or "auto" (true whenever a tolerance is given).
    #[rhai_fn(global, get = "error_estimate", pure, return_raw)]
    pub fn error_estimate(ctx: NativeCallContext, e: &mut Experiment) -> Res<Dynamic> {
        uses(&ctx, &["error_estimate", "tolerance"])?;
        to_dynamic(&ctx, &e.estimate())
    }

    /// The requested relative error of the first-pass responses, or () when none was asked for.
    #[rhai_fn(global, get = "tolerance", pure, return_raw)]
    pub fn tolerance(ctx: NativeCallContext, e: &mut Experiment) -> Res<Dynamic> {
        uses(&ctx, &["tolerance"])?;
        Ok(e.tolerance.map_or(Dynamic::UNIT, Dynamic::from_float))
    }

    /// The TR-NEWS timings of the resolution (as `trnews::preset_spec`).
    #[rhai_fn(global, get = "spec", pure, return_raw)]
    pub fn spec(ctx: NativeCallContext, e: &mut Experiment) -> Res<Dynamic> {
        uses(&ctx, &["resolution"])?;
        to_dynamic(&ctx, &e.tr_news())
    }

    /// The preset scene (cracked) of the setup, refined for its tolerance when one is given: element sizes halved until the predicted relative L2 error of the first-pass responses to the chirp is at most the tolerance (pilot runs of the crack-tied scene at h, 2h, 4h; `study::resolution_for_tolerance`), with the chosen sizes, the predicted error and run time printed; check it after the run with the error estimate.
    #[rhai_fn(global, pure, name = "scene", return_raw)]
    pub fn scene(ctx: NativeCallContext, e: &mut Experiment) -> Res<SceneRef> {
        scene_with(ctx, e, Map::new())
    }

    /// The preset scene of the setup with `overrides` (fields of a scene spec, as `scene::preset`), refined for its tolerance when one is given.
    #[rhai_fn(global, pure, name = "scene", return_raw)]
    pub fn scene_with(ctx: NativeCallContext, e: &mut Experiment, overrides: Map) -> Res<SceneRef> {
        uses(
            &ctx,
            &[
                "resolution",
                "discretisation",
                "tolerance",
                "losses",
                "friction_law",
            ],
        )?;
        let scene = crate::script::scene::build(&ctx, overrides, e.scene_spec())?;
        match e.tolerance {
            None => Ok(scene),
            Some(t) => crate::script::scene::refined_for(&ctx, &scene, t, &e.tr_news()),
        }
    }

    /// A responder for `scene` over `duration_s` with the setup's error estimate (as `trnews::responder(scene, duration_s, #{error_estimate})`).
    #[rhai_fn(global, pure, return_raw)]
    pub fn responder(
        ctx: NativeCallContext,
        e: &mut Experiment,
        scene: SceneRef,
        duration_s: FLOAT,
    ) -> Res<Responder> {
        uses(&ctx, &["error_estimate", "tolerance"])?;
        let r = Responder::new(scene, duration_s).at(&ctx)?;
        match crate::script::trnews::companions_wanted(&ctx, &r, e.estimate())? {
            Some(scenes) => r.with_companions(scenes, duration_s).at(&ctx),
            None => Ok(r),
        }
    }

    /// Whether the setup's error estimate is on for `r` (the responder option `error_estimate`'s decision): for scripts that estimate their own quantities from runs on the companions.
    #[rhai_fn(global, pure, return_raw)]
    pub fn estimate_wanted(ctx: NativeCallContext, e: &mut Experiment, r: Responder) -> Res<bool> {
        uses(&ctx, &["error_estimate", "tolerance"])?;
        Ok(crate::script::trnews::companions_wanted(&ctx, &r, e.estimate())?.is_some())
    }

    /// The channel the experiment runs on (`--set channel=...`, docs/src/guide/lab-data.md): () for the simulated scenes, or #{kind, sample, responder} for measured or recorded data (read again at each use).
    #[rhai_fn(global, get = "channel", pure, return_raw)]
    pub fn channel(ctx: NativeCallContext, _setup: &mut Experiment) -> Res<Dynamic> {
        crate::script::channel::from_params(&ctx)
    }
}
