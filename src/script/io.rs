//! Rhai module `io`: CSV, JSON and NPY outputs, every path resolved under the output dir.

use crate::script::convert::{error, floats, rows, ScriptResult};
use crate::signal::{Signal, Spectrum};
use rhai::plugin::*;
use rhai::{Array, Dynamic, Map, Module, NativeCallContext};

/// The `io` module.
pub fn module() -> Module {
    exported_module!(io_api)
}

/// A copy of `value` with every `Signal` and `Spectrum` replaced by an object map of its
/// fields, so that the whole value serialises.
fn plain(value: &Dynamic) -> Dynamic {
    if let Some(s) = value.read_lock::<Signal>() {
        return rhai::serde::to_dynamic(&*s).unwrap_or_default();
    }
    if let Some(sp) = value.read_lock::<Spectrum>() {
        return rhai::serde::to_dynamic(&*sp).unwrap_or_default();
    }
    if let Some(array) = value.read_lock::<rhai::Array>() {
        return Dynamic::from_array(array.iter().map(plain).collect());
    }
    if let Some(map) = value.read_lock::<Map>() {
        let plain_map: Map = map.iter().map(|(k, v)| (k.clone(), plain(v))).collect();
        return Dynamic::from_map(plain_map);
    }
    value.clone()
}

/// Flattened values and shape of a 1D or 2D script value.
fn npy_data(ctx: &NativeCallContext, data: &Dynamic) -> ScriptResult<(Vec<f64>, Vec<usize>)> {
    let nested = data
        .read_lock::<Array>()
        .is_some_and(|a| a.first().is_some_and(|r| r.is_array() || r.is::<Signal>()));
    if !nested {
        let v = floats(ctx, data, "data")?;
        let n = v.len();
        return Ok((v, vec![n]));
    }
    let table = rows(ctx, &data.clone().cast::<Array>(), "data")?;
    let cols = table[0].len();
    if let Some(i) = table.iter().position(|r| r.len() != cols) {
        return Err(error(
            ctx,
            format!(
                "data[{i}] has {} values but data[0] has {cols}",
                table[i].len()
            ),
        ));
    }
    let shape = vec![table.len(), cols];
    Ok((table.concat(), shape))
}

/// Refuses non-finite values unless `allow` (the options' `allow_non_finite`): names the
/// column (or `what`) and the first offending index and value.
fn finite_or_allowed(
    ctx: &NativeCallContext,
    allow: bool,
    what: &str,
    values: &[f64],
) -> ScriptResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) if !allow => Err(error(
            ctx,
            format!(
                "{what}[{i}] = {}: not finite; pass #{{allow_non_finite: true}} to write it anyway",
                values[i]
            ),
        )),
        _ => Ok(()),
    }
}

/// `allow_non_finite` from a writer's options map (the only field; anything else is an error).
fn allow_non_finite(ctx: &NativeCallContext, options: Map) -> ScriptResult<bool> {
    let mut allow = false;
    for (k, v) in options {
        match (k.as_str(), v.as_bool()) {
            ("allow_non_finite", Ok(b)) => allow = b,
            ("allow_non_finite", Err(t)) => {
                return Err(error(
                    ctx,
                    format!("options.allow_non_finite must be a bool, got {t}"),
                ))
            }
            (other, _) => {
                return Err(error(
                    ctx,
                    format!("options.{other}: unknown field (the only field is allow_non_finite)"),
                ))
            }
        }
    }
    Ok(allow)
}

#[export_module]
mod io_api {
    use super::{npy_data, plain};
    use crate::io;
    use crate::script::convert::{rows, strings, WithPosition};
    use crate::script::HostContext;
    use rhai::{Array, Dynamic, Map, NativeCallContext};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Writes numeric columns (arrays or Signals' samples) as CSV with one header per column; NaN and infinities are refused.
    #[rhai_fn(return_raw)]
    pub fn write_csv(
        ctx: NativeCallContext,
        path: &str,
        headers: Array,
        columns: Array,
    ) -> Res<()> {
        write_csv_with(ctx, path, headers, columns, Map::new())
    }

    /// write_csv with options #{allow_non_finite: bool} (false: NaN and infinities are refused).
    #[rhai_fn(name = "write_csv", return_raw)]
    pub fn write_csv_with(
        ctx: NativeCallContext,
        path: &str,
        headers: Array,
        columns: Array,
        options: Map,
    ) -> Res<()> {
        let allow = super::allow_non_finite(&ctx, options)?;
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let headers = strings(&ctx, &headers, "headers")?;
        let columns = rows(&ctx, &columns, "columns")?;
        for (i, c) in columns.iter().enumerate() {
            super::finite_or_allowed(&ctx, allow, &format!("columns[{i}]"), c)?;
        }
        let header_refs: Vec<&str> = headers.iter().map(String::as_str).collect();
        let column_refs: Vec<&[f64]> = columns.iter().map(Vec::as_slice).collect();
        io::write_csv(&file, &header_refs, &column_refs).at(&ctx)
    }

    /// Writes a table of rows (arrays of values, each written as text) as CSV under `headers`.
    #[rhai_fn(return_raw)]
    pub fn write_csv_rows(
        ctx: NativeCallContext,
        path: &str,
        headers: Array,
        table: Array,
    ) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let headers = strings(&ctx, &headers, "headers")?;
        let cell = |i: usize, j: usize, v: &Dynamic| match v.as_float() {
            Ok(x) if !x.is_finite() => Err(super::error(
                &ctx,
                format!("rows[{i}][{j}] = {x}: a non-finite number in a table"),
            )),
            _ => Ok(v.to_string()),
        };
        let table = table
            .iter()
            .enumerate()
            .map(|(i, row)| match row.read_lock::<Array>() {
                Some(r) => r.iter().enumerate().map(|(j, v)| cell(i, j, v)).collect(),
                None => Ok(vec![cell(i, 0, row)?]),
            })
            .collect::<Res<Vec<Vec<String>>>>()?;
        io::write_csv_rows(&file, &headers, &table).at(&ctx)
    }

    /// Writes any value (maps, arrays, numbers, strings, Signals, Spectra) as pretty JSON; NaN and infinities are refused (JSON has no such numbers).
    #[rhai_fn(return_raw)]
    pub fn write_json(ctx: NativeCallContext, path: &str, value: Dynamic) -> Res<()> {
        write_json_with(ctx, path, value, Map::new())
    }

    /// write_json with options #{allow_non_finite: bool} (true writes NaN and infinities as null).
    #[rhai_fn(name = "write_json", return_raw)]
    pub fn write_json_with(
        ctx: NativeCallContext,
        path: &str,
        value: Dynamic,
        options: Map,
    ) -> Res<()> {
        let allow = super::allow_non_finite(&ctx, options)?;
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let json = if allow {
            serde_json::to_value(plain(&value)).at(&ctx)?
        } else {
            crate::script::convert::strict_json(&plain(&value), "value").map_err(|m| {
                super::error(
                    &ctx,
                    format!("{m}; pass #{{allow_non_finite: true}} to write it as null"),
                )
            })?
        };
        io::write_json(&file, &json).at(&ctx)
    }

    /// Writes a float64 .npy array: a Signal or array of numbers (1D) or an array of equal-length rows (2D); NaN and infinities are refused.
    #[rhai_fn(return_raw)]
    pub fn write_npy(ctx: NativeCallContext, path: &str, data: Dynamic) -> Res<()> {
        write_npy_with(ctx, path, data, Map::new())
    }

    /// write_npy with options #{allow_non_finite: bool}.
    #[rhai_fn(name = "write_npy", return_raw)]
    pub fn write_npy_with(
        ctx: NativeCallContext,
        path: &str,
        data: Dynamic,
        options: Map,
    ) -> Res<()> {
        let allow = super::allow_non_finite(&ctx, options)?;
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let (values, shape) = npy_data(&ctx, &data)?;
        super::finite_or_allowed(&ctx, allow, "data", &values)?;
        io::write_npy(&file, &values, &shape).at(&ctx)
    }
}
