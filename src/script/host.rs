//! Rhai module `host`: what the running script may ask of its host (parameters, output dir).

use crate::script::convert::number;
use rhai::plugin::*;
use rhai::{Dynamic, Module};

/// The `host` module.
pub fn module() -> Module {
    exported_module!(host_api)
}

/// `given` as the type of `default`, when that loses nothing.
fn coerce(given: &Dynamic, default: &Dynamic) -> Option<Dynamic> {
    if given.type_id() == default.type_id() || default.is_unit() {
        Some(given.clone())
    } else if default.is_float() {
        number(given).map(Dynamic::from_float)
    } else if default.is_string() {
        Some(Dynamic::from(given.to_string()))
    } else {
        None
    }
}

#[export_module]
mod host_api {
    use super::coerce;
    use crate::script::convert::error;
    use crate::script::HostContext;
    use rhai::{Dynamic, NativeCallContext};

    /// The value given with `--set name=VALUE`, else `default`; converted to the default's type (int -> float, anything -> string), an error if that would lose information.
    #[rhai_fn(global, return_raw)]
    pub fn param(
        ctx: NativeCallContext,
        name: &str,
        default: Dynamic,
    ) -> Result<Dynamic, Box<rhai::EvalAltResult>> {
        let host = HostContext::of(&ctx)?;
        let Some(given) = host.param(name) else {
            return Ok(default);
        };
        coerce(given, &default).ok_or_else(|| {
            error(
                &ctx,
                format!(
                    "parameter '{name}' = {given} is {} but the script's default {default} is {}",
                    given.type_name(),
                    default.type_name()
                ),
            )
        })
    }

    /// The output directory that every written path is resolved under.
    #[rhai_fn(global, return_raw)]
    pub fn out_dir(ctx: NativeCallContext) -> Result<String, Box<rhai::EvalAltResult>> {
        Ok(HostContext::of(&ctx)?.out_dir().display().to_string())
    }
}
