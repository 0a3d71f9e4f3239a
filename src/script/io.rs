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

#[export_module]
mod io_api {
    use super::{npy_data, plain};
    use crate::io;
    use crate::script::convert::{rows, strings, to_json, WithPosition};
    use crate::script::HostContext;
    use rhai::{Array, Dynamic, NativeCallContext};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Writes numeric columns (arrays or Signals' samples) as CSV with one header per column.
    #[rhai_fn(return_raw)]
    pub fn write_csv(
        ctx: NativeCallContext,
        path: &str,
        headers: Array,
        columns: Array,
    ) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let headers = strings(&ctx, &headers, "headers")?;
        let columns = rows(&ctx, &columns, "columns")?;
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
        let table: Vec<Vec<String>> = table
            .iter()
            .map(|row| {
                row.read_lock::<Array>()
                    .map(|r| r.iter().map(|v| v.to_string()).collect())
                    .unwrap_or_else(|| vec![row.to_string()])
            })
            .collect();
        io::write_csv_rows(&file, &headers, &table).at(&ctx)
    }

    /// Writes any value (maps, arrays, numbers, strings, Signals, Spectra) as pretty JSON.
    #[rhai_fn(return_raw)]
    pub fn write_json(ctx: NativeCallContext, path: &str, value: Dynamic) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let json = to_json(&ctx, &plain(&value))?;
        io::write_json(&file, &json).at(&ctx)
    }

    /// Writes a float64 .npy array: a Signal or array of numbers (1D) or an array of equal-length rows (2D).
    #[rhai_fn(return_raw)]
    pub fn write_npy(ctx: NativeCallContext, path: &str, data: Dynamic) -> Res<()> {
        let file = HostContext::of(&ctx)?.resolve_output(path).at(&ctx)?;
        let (values, shape) = npy_data(&ctx, &data)?;
        io::write_npy(&file, &values, &shape).at(&ctx)
    }
}
