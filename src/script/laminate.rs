//! Rhai module `laminate`: the stochastic CFRP layer stack (report Sec. 2.2.1) as a summary map.

use crate::laminate::{Laminate, StochasticSpec};
use crate::material::Plane;
use crate::script::convert::{named, to_dynamic, ScriptResult, WithPosition};
use rhai::plugin::*;
use rhai::{Array, Dynamic, Map, Module, NativeCallContext};

/// The `laminate` module.
pub fn module() -> Module {
    exported_module!(laminate_api)
}

/// Draws the stack and summarises it: counts, thickness, clamped fraction, layers
/// (bottom-up material names and thicknesses), interface heights and the per-pair draws.
fn summary(ctx: &NativeCallContext, spec: &StochasticSpec, plane: &str) -> ScriptResult<Dynamic> {
    let plane: Plane = named(ctx, plane, "plane")?;
    let lam = Laminate::stochastic(spec, plane).at(ctx)?;
    let names: Array = lam
        .layers
        .iter()
        .map(|l| lam.materials[l.material].name.clone().into())
        .collect();
    let thickness: Array = lam.layers.iter().map(|l| l.thickness_m.into()).collect();
    let mut map = Map::new();
    map.insert("spec".into(), to_dynamic(ctx, spec)?);
    map.insert("pairs".into(), (spec.pairs as rhai::INT).into());
    map.insert("layers".into(), (lam.layers.len() as rhai::INT).into());
    map.insert("thickness_m".into(), lam.thickness_m().into());
    map.insert("clamped_fraction".into(), lam.clamped_fraction().into());
    map.insert("layer_material".into(), names.into());
    map.insert("layer_thickness_m".into(), thickness.into());
    map.insert("interfaces_m".into(), to_dynamic(ctx, &lam.interfaces_m())?);
    map.insert("draws".into(), to_dynamic(ctx, &lam.draws)?);
    Ok(map.into())
}

#[export_module]
mod laminate_api {
    use super::summary;
    use crate::laminate::StochasticSpec;
    use crate::script::convert::{options, to_dynamic};
    use rhai::{Dynamic, Map, NativeCallContext};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// The report's stochastic laminate parameters #{pairs, a_mean_m, a_std_m, b_mean_m, b_std_m, min_epoxy_m, seed}.
    #[rhai_fn(return_raw)]
    pub fn default_spec(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &StochasticSpec::default())
    }

    /// Draws a stochastic laminate (plane strain) from a spec map (unset fields keep the report's values; unknown fields are errors) and returns its summary #{spec, pairs, layers, thickness_m, clamped_fraction, layer_material, layer_thickness_m, interfaces_m, draws}.
    #[rhai_fn(return_raw)]
    pub fn stochastic(ctx: NativeCallContext, spec: Map) -> Res<Dynamic> {
        stochastic_in(ctx, spec, "strain")
    }

    /// As stochastic(spec), with the materials reduced to plane "strain" or "stress".
    #[rhai_fn(name = "stochastic", return_raw)]
    pub fn stochastic_in(ctx: NativeCallContext, spec: Map, plane: &str) -> Res<Dynamic> {
        let spec: StochasticSpec = options(&ctx, spec, &StochasticSpec::default(), "laminate")?;
        summary(&ctx, &spec, plane)
    }
}
