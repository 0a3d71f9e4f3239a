//! Rhai module `io`: CSV, JSON and NPY outputs, every path resolved under the output dir, and
//! NPY, CSV and JSON inputs, every path resolved beneath the data dir (`--data`, default the
//! script's directory; see [`crate::input`]).

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

/// Options of the readers: a sample step turns columns (CSV) or rows (NPY) into Signals.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ReadOptions {
    /// Sample step (s): columns or rows become Signals on this step.
    dt_s: Option<f64>,
    /// Time of the first sample (s), with `dt_s`.
    t0_s: f64,
    /// CSV only: the column holding uniformly spaced times; the other columns become Signals
    /// on its step and start.
    time_column: Option<String>,
    /// CSV only: read just these columns (with `time_column`, it too); the others may hold
    /// text.
    columns: Option<Vec<String>>,
}

/// A data file format and how many bytes of memory one byte of it can become at most: the
/// file, its parsed values and the script's arrays (16 bytes per value) are held at once, and
/// a list grown value by value may hold twice its length in capacity.
#[derive(Clone, Copy)]
enum Format {
    /// 8-byte values: 8 (file) + 8 (parsed) + 16 (script) bytes per 8 bytes, 4x (sizes known
    /// from the header: no growth).
    Npy,
    /// Cells of at least 2 bytes ("1,"): 2 + 2 x 8 + 2 x 16 bytes per 2 bytes, 25x; 32x
    /// allowed.
    Csv,
    /// Numbers of at least 2 bytes ("1,"): 2 + 2 x 32 (JSON value) + 2 x 16 bytes per 2
    /// bytes, 49x; 64x allowed.
    Json,
}

impl Format {
    fn expansion(self) -> u64 {
        match self {
            Format::Npy => 4,
            Format::Csv => 32,
            Format::Json => 64,
        }
    }
}

/// Largest data file of `format` a script may read: the memory limit divided by the format's
/// expansion, and why (for the message).
fn read_limit(format: Format) -> (u64, String) {
    let max = crate::budget::memory_limit();
    let k = format.expansion();
    (
        max / k,
        format!(
            "1/{k} of --max-memory {}: the file, its values and their script copies are held at once",
            crate::budget::format_bytes(max as f64)
        ),
    )
}

/// The bytes of data file `path` and its full path for messages, read beneath the data root.
fn read_data(
    ctx: &NativeCallContext,
    path: &str,
    format: Format,
) -> ScriptResult<(std::path::PathBuf, Vec<u8>)> {
    use crate::script::convert::WithPosition;
    let root = crate::script::HostContext::of(ctx)?
        .data_root()
        .map_err(|m| error(ctx, m))?;
    let (limit, why) = read_limit(format);
    let bytes = root.read(path, limit, &why).at(ctx)?;
    Ok((root.path().join(path), bytes))
}

/// A Signal on the options' step, naming `what` when the step is invalid.
fn to_signal(
    ctx: &NativeCallContext,
    options: &ReadOptions,
    dt_s: f64,
    samples: Vec<f64>,
    what: &str,
) -> ScriptResult<Dynamic> {
    use crate::script::convert::WithPosition;
    Signal::new(dt_s, options.t0_s, samples)
        .map(Dynamic::from)
        .map_err(|e| e.to_string())
        .map_err(|m| format!("{what}: {m}"))
        .at(ctx)
}

/// Refuses to turn the `values` numbers of data file `path`, in `rows` rows, into script
/// values above the memory limit: arrays of numbers (a `Dynamic` a number, see
/// [`crate::script::convert::script_array_bytes`]), or Signals when `signals` (8 bytes a
/// sample and one `Dynamic` a row). The estimate is charged, not the file's size: a file of
/// 4-byte numbers becomes arrays about 23 times its size.
fn check_values(
    ctx: &NativeCallContext,
    path: &str,
    rows: usize,
    values: usize,
    signals: bool,
) -> ScriptResult<()> {
    use crate::script::convert::{script_array_bytes, WithPosition};
    let bytes = if signals {
        8.0 * values as f64 + script_array_bytes(rows, 0)
    } else {
        script_array_bytes(rows, values)
    };
    crate::budget::check_memory(
        path,
        format!("{values} values in {rows} rows"),
        bytes,
        "read a smaller file, or read it as Signals (dt_s)",
    )
    .at(ctx)
}

/// Numbers as a Rhai array.
fn number_array(values: &[f64]) -> Dynamic {
    Dynamic::from_array(values.iter().map(|&v| Dynamic::from_float(v)).collect())
}

/// The step and start of a uniformly spaced time column: dt from its ends, each time within
/// 1e-6 dt of t0 + k dt (round-off of printed times), otherwise an error naming the row.
fn uniform_times(ctx: &NativeCallContext, name: &str, t: &[f64]) -> ScriptResult<(f64, f64)> {
    let n = t.len();
    if n < 2 {
        return Err(error(
            ctx,
            format!("time column '{name}' has {n} values; need at least 2"),
        ));
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    if !(dt > 0.0) {
        return Err(error(
            ctx,
            format!(
                "time column '{name}' does not increase ({} to {})",
                t[0],
                t[n - 1]
            ),
        ));
    }
    if let Some(k) = (0..n).find(|&k| (t[k] - t[0] - k as f64 * dt).abs() > 1e-6 * dt) {
        return Err(error(
            ctx,
            format!(
                "time column '{name}' is not uniformly spaced: row {} has t = {} where {} is expected (dt = {dt})",
                k + 1,
                t[k],
                t[0] + k as f64 * dt
            ),
        ));
    }
    Ok((dt, t[0]))
}

#[export_module]
mod io_api {
    use super::{check_values, number_array, read_data, to_signal, uniform_times, ReadOptions};
    use super::{npy_data, plain};
    use crate::input;
    use crate::io;
    use crate::script::convert::options;
    use crate::script::convert::{rows, strings, WithPosition};
    use crate::script::HostContext;
    use rhai::{Array, Dynamic, Map, NativeCallContext};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// True when `path` is a file beneath the data directory (--data, default the script's directory), where io::read_* would find it; false when it is missing or leads out of that directory.
    #[rhai_fn(return_raw)]
    pub fn exists(ctx: NativeCallContext, path: &str) -> Res<bool> {
        let root = HostContext::of(&ctx)?
            .data_root()
            .map_err(|m| super::error(&ctx, m))?;
        Ok(root.is_file(path))
    }

    /// Reads a 1-D or 2-D .npy array (float64, float32, int64 or int32) beneath the data directory (--data, default the script's directory): an array of numbers, or an array of rows.
    #[rhai_fn(return_raw)]
    pub fn read_npy(ctx: NativeCallContext, path: &str) -> Res<Dynamic> {
        read_npy_with(ctx, path, Map::new())
    }

    /// read_npy with options #{dt_s, t0_s}: with dt_s a 1-D array becomes a Signal and a 2-D array an array of Signals, one per row.
    #[rhai_fn(name = "read_npy", return_raw)]
    pub fn read_npy_with(ctx: NativeCallContext, path: &str, options_map: Map) -> Res<Dynamic> {
        let opts: ReadOptions = options(&ctx, options_map, &ReadOptions::default(), "read_npy")?;
        if opts.time_column.is_some() || opts.columns.is_some() {
            return Err(super::error(
                &ctx,
                "read_npy.time_column, read_npy.columns: only read_csv has named columns",
            ));
        }
        let (full, bytes) = read_data(&ctx, path, super::Format::Npy)?;
        let table = input::parse_npy(&full, &bytes).at(&ctx)?;
        drop(bytes);
        let rows = if table.shape.len() == 2 {
            table.shape[0]
        } else {
            1
        };
        check_values(&ctx, path, rows, table.values.len(), opts.dt_s.is_some())?;
        let one = |i: usize, row: &[f64]| match opts.dt_s {
            Some(dt) => to_signal(&ctx, &opts, dt, row.to_vec(), &format!("{path} row {i}")),
            None => Ok(number_array(row)),
        };
        // parse_npy reads 1-D and 2-D arrays only
        let [_, cols] = table.shape[..] else {
            return one(0, &table.values);
        };
        Ok(Dynamic::from_array(
            table
                .values
                .chunks(cols.max(1))
                .enumerate()
                .map(|(i, r)| one(i, r))
                .collect::<Res<Array>>()?,
        ))
    }

    /// Reads a CSV file with a header row and numeric cells beneath the data directory: a map from each header to its column, an array of numbers.
    #[rhai_fn(return_raw)]
    pub fn read_csv(ctx: NativeCallContext, path: &str) -> Res<Map> {
        read_csv_with(ctx, path, Map::new())
    }

    /// read_csv with options #{dt_s, t0_s} (every column becomes a Signal on that step) or #{time_column} (the other columns become Signals on that uniformly spaced column's step and start), and #{columns: [names]} (read only these; the others may hold text).
    #[rhai_fn(name = "read_csv", return_raw)]
    pub fn read_csv_with(ctx: NativeCallContext, path: &str, options_map: Map) -> Res<Map> {
        let mut opts: ReadOptions =
            options(&ctx, options_map, &ReadOptions::default(), "read_csv")?;
        if opts.dt_s.is_some() && opts.time_column.is_some() {
            return Err(super::error(
                &ctx,
                "read_csv: give dt_s or time_column, not both",
            ));
        }
        let (full, bytes) = read_data(&ctx, path, super::Format::Csv)?;
        let wanted = opts.columns.clone().map(|mut c| {
            c.extend(opts.time_column.clone());
            c
        });
        let table = input::parse_csv_columns(&full, &bytes, wanted.as_deref()).at(&ctx)?;
        drop(bytes);
        let values = table.columns.iter().map(Vec::len).sum();
        let signals = opts.dt_s.is_some() || opts.time_column.is_some();
        check_values(&ctx, path, table.columns.len(), values, signals)?;
        let mut skip = None;
        if let Some(name) = &opts.time_column {
            let i = table.headers.iter().position(|h| h == name).ok_or_else(|| {
                super::error(
                    &ctx,
                    format!(
                        "read_csv.time_column = \"{name}\": {path} has no such column (columns: {})",
                        table.headers.join(", ")
                    ),
                )
            })?;
            let (dt, t0) = uniform_times(&ctx, name, &table.columns[i])?;
            opts.dt_s = Some(dt);
            opts.t0_s = t0;
            skip = Some(i);
        }
        let mut out = Map::new();
        for (i, (h, c)) in table.headers.iter().zip(table.columns).enumerate() {
            if Some(i) == skip {
                continue;
            }
            let value = match opts.dt_s {
                Some(dt) => to_signal(&ctx, &opts, dt, c, &format!("{path} column '{h}'"))?,
                None => number_array(&c),
            };
            out.insert(h.as_str().into(), value);
        }
        Ok(out)
    }

    /// Reads a JSON document beneath the data directory as script values (objects become maps, arrays arrays).
    #[rhai_fn(return_raw)]
    pub fn read_json(ctx: NativeCallContext, path: &str) -> Res<Dynamic> {
        let (full, bytes) = read_data(&ctx, path, super::Format::Json)?;
        let value = input::parse_json(&full, &bytes).at(&ctx)?;
        rhai::serde::to_dynamic(&value).at(&ctx)
    }

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
