//! Rhai module `fmt`: numbers for printing, with a few significant digits
//! (`fmt::eng(3.0124606e-9, "s")` is `3.01 ns`, `fmt::sig(0.049, 3)` is `4.90e-2`). Tables
//! written with `io` keep full precision; these are for `print`.

use crate::script::convert::{error, number, ScriptResult};
use rhai::plugin::*;
use rhai::{Dynamic, Module, NativeCallContext, INT};

/// The `fmt` module.
pub fn module() -> Module {
    exported_module!(fmt_api)
}

/// A number (int or float) from `value`, named `value` in errors.
fn value_of(ctx: &NativeCallContext, value: &Dynamic) -> ScriptResult<f64> {
    number(value).ok_or_else(|| {
        error(
            ctx,
            format!("value must be a number, got {}", value.type_name()),
        )
    })
}

/// Significant digits from a script integer, named `digits` in errors.
fn digits_of(ctx: &NativeCallContext, digits: INT) -> ScriptResult<usize> {
    usize::try_from(digits).map_err(|_| {
        error(
            ctx,
            format!(
                "invalid digits = {digits}: must be 1..={}",
                crate::format::MAX_DIGITS
            ),
        )
    })
}

#[export_module]
mod fmt_api {
    use super::{digits_of, value_of};
    use crate::script::convert::WithPosition;
    use rhai::{Dynamic, NativeCallContext, INT};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// `value` (a number) in `unit` with 3 significant digits and an SI prefix: `3.01 ns`, `13.6 s`, `50.0 kPa` (micro is `u`); `1.23e27 Pa` beyond y..Y; `0.00 s`, `NaN s`, `inf s` as such.
    #[rhai_fn(name = "eng", return_raw)]
    pub fn eng3(ctx: NativeCallContext, value: Dynamic, unit: &str) -> Res<String> {
        crate::format::eng(value_of(&ctx, &value)?, unit, 3).at(&ctx)
    }

    /// `value` in `unit` with `digits` (1..=17) significant digits and an SI prefix: `fmt::eng(3.0124606e-9, "s", 4)` is `3.012 ns`.
    #[rhai_fn(name = "eng", return_raw)]
    pub fn eng(ctx: NativeCallContext, value: Dynamic, unit: &str, digits: INT) -> Res<String> {
        let digits = digits_of(&ctx, digits)?;
        crate::format::eng(value_of(&ctx, &value)?, unit, digits).at(&ctx)
    }

    /// A dimensionless `value` with 3 significant digits: `13.6`, `0.250`, `4.90e-2` (plain decimals from 0.1 to 999, exponent otherwise).
    #[rhai_fn(name = "sig", return_raw)]
    pub fn sig3(ctx: NativeCallContext, value: Dynamic) -> Res<String> {
        crate::format::sig(value_of(&ctx, &value)?, 3).at(&ctx)
    }

    /// A dimensionless `value` with `digits` (1..=17) significant digits: `fmt::sig(0.049, 2)` is `4.9e-2`, `fmt::sig(1234.56, 4)` is `1235` (plain decimals from 0.1 below 10^digits).
    #[rhai_fn(name = "sig", return_raw)]
    pub fn sig(ctx: NativeCallContext, value: Dynamic, digits: INT) -> Res<String> {
        let digits = digits_of(&ctx, digits)?;
        crate::format::sig(value_of(&ctx, &value)?, digits).at(&ctx)
    }
}
