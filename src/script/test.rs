//! Rhai module `test`: assertions for regression scripts. A failure stops the script with
//! the position of the call and both values.

use rhai::plugin::*;
use rhai::Module;

/// The `test` module.
pub fn module() -> Module {
    exported_module!(test_api)
}

#[export_module]
mod test_api {
    use crate::script::convert::{error, failure, number};
    use rhai::{Dynamic, NativeCallContext};

    /// Fails with `message` unless `condition` is true.
    #[rhai_fn(global, return_raw)]
    pub fn assert(
        ctx: NativeCallContext,
        condition: bool,
        message: &str,
    ) -> Result<(), Box<rhai::EvalAltResult>> {
        if condition {
            Ok(())
        } else {
            Err(failure(&ctx, format!("assert failed: {message}")))
        }
    }

    /// Fails unless |actual - expected| <= rel_tol * |expected|, showing both values and the tolerance.
    #[rhai_fn(global, return_raw)]
    pub fn assert_close(
        ctx: NativeCallContext,
        actual: Dynamic,
        expected: Dynamic,
        rel_tol: Dynamic,
        message: &str,
    ) -> Result<(), Box<rhai::EvalAltResult>> {
        let [actual, expected, rel_tol] = [
            ("actual", actual),
            ("expected", expected),
            ("rel_tol", rel_tol),
        ]
        .map(|(name, v)| {
            number(&v).ok_or_else(|| {
                error(
                    &ctx,
                    format!("{name} must be a number, got {}", v.type_name()),
                )
            })
        });
        let (actual, expected, rel_tol) = (actual?, expected?, rel_tol?);
        if (actual - expected).abs() <= rel_tol * expected.abs() {
            Ok(())
        } else {
            Err(failure(
                &ctx,
                format!(
                    "assert_close failed: actual {actual} vs expected {expected} (rel tol {rel_tol}): {message}"
                ),
            ))
        }
    }
}
