//! Rhai module `laminate`: the stochastic CFRP layer stack (report Sec. 2.2.1) as a typed
//! `Laminate` object. Per-layer and per-pair data are reached through getters and arrays of
//! numbers, never one nested map, so a draw of any size crosses into a script (a nested map
//! of 100,000 pair draws would exceed Rhai's map size limit).

use crate::laminate::{Laminate, PairDraw, StochasticSpec};
use crate::script::convert::{error, ScriptResult};
use rhai::plugin::*;
use rhai::{Engine, Module, NativeCallContext};
use std::sync::Arc;

/// A drawn laminate with the spec it was drawn from; cheap to clone.
#[derive(Clone, Debug)]
pub struct LaminateRef {
    /// The stack.
    pub laminate: Arc<Laminate>,
    /// The parameters of the draw.
    pub spec: StochasticSpec,
}

/// Registers the display name of the `Laminate` type.
pub fn register_types(engine: &mut Engine) {
    engine.register_type_with_name::<LaminateRef>("Laminate");
}

/// The `laminate` module.
pub fn module() -> Module {
    exported_module!(laminate_api)
}

/// Reads one field of a pair's draw.
type DrawField = fn(&PairDraw) -> f64;

/// The per-pair draw fields `draw_values` accepts, with their accessors.
const DRAW_FIELDS: [(&str, DrawField); 7] = [
    ("a_m", |d| d.a_m),
    ("b_m", |d| d.b_m),
    ("x_m", |d| d.x_m),
    ("composite_m", |d| d.composite_m),
    ("epoxy_drawn_m", |d| d.epoxy_drawn_m),
    ("epoxy_m", |d| d.epoxy_m),
    ("rejected_draws", |d| d.rejected_draws as f64),
];

/// One draw field over every pair in draw order (pair 0 at the top); an unknown field is named with the valid ones.
fn draw_column(ctx: &NativeCallContext, lam: &Laminate, field: &str) -> ScriptResult<Vec<f64>> {
    let (_, get) = DRAW_FIELDS
        .iter()
        .find(|(name, _)| *name == field)
        .ok_or_else(|| {
            let names: Vec<&str> = DRAW_FIELDS.iter().map(|(n, _)| *n).collect();
            error(
                ctx,
                format!(
                    "unknown draw field '{field}' (expected one of {})",
                    names.join(", ")
                ),
            )
        })?;
    Ok(lam.draws.iter().map(get).collect())
}

#[export_module]
mod laminate_api {
    use super::{draw_column, LaminateRef};
    use crate::laminate::{Laminate, StochasticSpec};
    use crate::material::Plane;
    use crate::script::convert::{error, named, options, to_dynamic, WithPosition};
    use rhai::{Array, Dynamic, Map, NativeCallContext, FLOAT, INT};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// The report's stochastic laminate parameters #{pairs, a_mean_m, a_std_m, b_mean_m, b_std_m, min_epoxy_m, seed}.
    #[rhai_fn(return_raw)]
    pub fn default_spec(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &StochasticSpec::default())
    }

    /// Draws a stochastic laminate (plane strain) from a spec map (unset fields keep the report's values; unknown fields are errors): a Laminate object with getters pairs, layers, thickness_m, clamped_fraction, layer_thickness_m, layer_material, interfaces_m, spec and methods draw(i), draw_values(field), summary().
    #[rhai_fn(return_raw)]
    pub fn stochastic(ctx: NativeCallContext, spec: Map) -> Res<LaminateRef> {
        stochastic_in(ctx, spec, "strain")
    }

    /// As stochastic(spec), with the materials reduced to plane "strain" or "stress".
    #[rhai_fn(name = "stochastic", return_raw)]
    pub fn stochastic_in(ctx: NativeCallContext, spec: Map, plane: &str) -> Res<LaminateRef> {
        let spec: StochasticSpec = options(&ctx, spec, &StochasticSpec::default(), "laminate")?;
        let plane: Plane = named(&ctx, plane, "plane")?;
        let laminate = Laminate::stochastic(&spec, plane).at(&ctx)?;
        Ok(LaminateRef {
            laminate: Arc::new(laminate),
            spec,
        })
    }

    /// Number of composite + epoxy pairs drawn.
    #[rhai_fn(global, get = "pairs", pure)]
    pub fn pairs(lam: &mut LaminateRef) -> INT {
        lam.laminate.draws.len() as INT
    }

    /// Number of layers (two per pair).
    #[rhai_fn(global, get = "layers", pure)]
    pub fn layers(lam: &mut LaminateRef) -> INT {
        lam.laminate.layers.len() as INT
    }

    /// Total thickness (m).
    #[rhai_fn(global, get = "thickness_m", pure)]
    pub fn thickness_m(lam: &mut LaminateRef) -> FLOAT {
        lam.laminate.thickness_m()
    }

    /// Fraction of pairs whose epoxy was raised to min_epoxy_m.
    #[rhai_fn(global, get = "clamped_fraction", pure)]
    pub fn clamped_fraction(lam: &mut LaminateRef) -> FLOAT {
        lam.laminate.clamped_fraction()
    }

    /// Layer thicknesses bottom-up (m), an array of numbers.
    #[rhai_fn(global, get = "layer_thickness_m", pure)]
    pub fn layer_thickness_m(lam: &mut LaminateRef) -> Array {
        lam.laminate
            .layers
            .iter()
            .map(|l| l.thickness_m.into())
            .collect()
    }

    /// Layer material names bottom-up, an array of strings.
    #[rhai_fn(global, get = "layer_material", pure)]
    pub fn layer_material(lam: &mut LaminateRef) -> Array {
        let l = &lam.laminate;
        l.layers
            .iter()
            .map(|layer| l.materials[layer.material].name.clone().into())
            .collect()
    }

    /// Heights of the layer boundaries from y = 0 to the top (m), layers + 1 numbers.
    #[rhai_fn(global, get = "interfaces_m", pure)]
    pub fn interfaces_m(lam: &mut LaminateRef) -> Array {
        lam.laminate
            .interfaces_m()
            .into_iter()
            .map(Dynamic::from_float)
            .collect()
    }

    /// The spec the laminate was drawn from, as a map.
    #[rhai_fn(global, get = "spec", pure, return_raw)]
    pub fn spec(ctx: NativeCallContext, lam: &mut LaminateRef) -> Res<Dynamic> {
        to_dynamic(&ctx, &lam.spec)
    }

    /// The draw of pair i (0-based in draw order, pair 0 at the top surface): #{a_m, b_m, x_m, composite_m, epoxy_drawn_m, epoxy_m, rejected_draws}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn draw(ctx: NativeCallContext, lam: &mut LaminateRef, i: INT) -> Res<Dynamic> {
        let n = lam.laminate.draws.len();
        let d = usize::try_from(i)
            .ok()
            .and_then(|k| lam.laminate.draws.get(k))
            .ok_or_else(|| error(&ctx, format!("pair {i} out of range 0..{n}")))?;
        to_dynamic(&ctx, d)
    }

    /// One draw field over every pair in draw order (pair 0 at the top), an array of numbers: "a_m", "b_m", "x_m", "composite_m", "epoxy_drawn_m", "epoxy_m" or "rejected_draws".
    #[rhai_fn(global, pure, return_raw)]
    pub fn draw_values(ctx: NativeCallContext, lam: &mut LaminateRef, field: &str) -> Res<Array> {
        Ok(draw_column(&ctx, &lam.laminate, field)?
            .into_iter()
            .map(Dynamic::from_float)
            .collect())
    }

    /// Scalars of the draw as a map: #{spec, pairs, layers, thickness_m, clamped_fraction}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn summary(ctx: NativeCallContext, lam: &mut LaminateRef) -> Res<Map> {
        let mut map = Map::new();
        map.insert("spec".into(), to_dynamic(&ctx, &lam.spec)?);
        map.insert("pairs".into(), pairs(lam).into());
        map.insert("layers".into(), layers(lam).into());
        map.insert("thickness_m".into(), thickness_m(lam).into());
        map.insert("clamped_fraction".into(), clamped_fraction(lam).into());
        Ok(map)
    }

    /// "Laminate(N pairs, M layers, T mm)".
    #[rhai_fn(global, name = "to_string", name = "to_debug", pure)]
    pub fn describe(lam: &mut LaminateRef) -> String {
        format!(
            "Laminate({} pairs, {} layers, {:.4} mm)",
            lam.laminate.draws.len(),
            lam.laminate.layers.len(),
            lam.laminate.thickness_m() * 1e3
        )
    }
}
