//! Argument conversion shared by the bindings: numbers and arrays from `Dynamic`, option
//! maps into serde structs with errors naming the field, and library errors raised at the
//! script position of the call.

use crate::signal::Signal;
use rhai::{Array, Dynamic, EvalAltResult, Map, NativeCallContext};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Result of a native function as Rhai expects it.
pub type ScriptResult<T> = Result<T, Box<EvalAltResult>>;

/// A runtime error at the script position of the current call, prefixed with the
/// function's name (namespaced calls would otherwise lose the position).
pub fn error(ctx: &NativeCallContext, message: impl std::fmt::Display) -> Box<EvalAltResult> {
    failure(ctx, format!("{}: {message}", ctx.fn_name()))
}

/// A runtime error at the script position of the current call, message as given.
pub fn failure(ctx: &NativeCallContext, message: String) -> Box<EvalAltResult> {
    EvalAltResult::ErrorRuntime(message.into(), ctx.call_position()).into()
}

/// Raises a library error (anything displayable) at the position of the call.
pub trait WithPosition<T> {
    /// Converts the error into a Rhai error at `ctx`'s call position.
    fn at(self, ctx: &NativeCallContext) -> ScriptResult<T>;
}

impl<T, E: std::fmt::Display> WithPosition<T> for Result<T, E> {
    fn at(self, ctx: &NativeCallContext) -> ScriptResult<T> {
        self.map_err(|e| error(ctx, e))
    }
}

/// Bytes a script array of `values` numbers in `rows` rows takes: one `Dynamic` per number,
/// and per row the row's `Dynamic`, its array header and the allocator's bookkeeping (taken
/// as 32 bytes). A `.npy` of 4-byte values read as rows of one number takes about 23 times
/// its file: the expansion, not the file, is what must fit in the memory limit.
pub fn script_array_bytes(rows: usize, values: usize) -> f64 {
    let value = std::mem::size_of::<Dynamic>() as f64;
    let row = value + std::mem::size_of::<Array>() as f64 + 32.0;
    values as f64 * value + rows as f64 * row
}

/// Refuses to build a script array of `values` numbers in `rows` rows above the memory limit
/// ([`crate::budget::check_memory`]), naming `field` with `value`.
pub fn check_script_array(
    ctx: &NativeCallContext,
    field: &str,
    value: impl std::fmt::Display,
    rows: usize,
    values: usize,
) -> ScriptResult<()> {
    crate::budget::check_memory(
        field,
        value,
        script_array_bytes(rows, values),
        "keep the data in a Signal or read fewer values",
    )
    .at(ctx)
}

/// A number from an integer or float.
pub fn number(value: &Dynamic) -> Option<f64> {
    value
        .as_float()
        .ok()
        .or_else(|| value.as_int().ok().map(|i| i as f64))
}

/// Floats from a Rhai array of numbers or a `Signal` (its samples); `what` names the argument.
pub fn floats(ctx: &NativeCallContext, value: &Dynamic, what: &str) -> ScriptResult<Vec<f64>> {
    if let Some(s) = value.read_lock::<Signal>() {
        return Ok(s.samples.clone());
    }
    let Some(array) = value.read_lock::<Array>() else {
        return Err(error(
            ctx,
            format!(
                "{what} must be an array of numbers or a Signal, got {}",
                value.type_name()
            ),
        ));
    };
    array
        .iter()
        .enumerate()
        .map(|(i, v)| {
            number(v).ok_or_else(|| {
                error(
                    ctx,
                    format!("{what}[{i}] must be a number, got {}", v.type_name()),
                )
            })
        })
        .collect()
}

/// Rows of floats from an array of arrays (or of Signals).
pub fn rows(ctx: &NativeCallContext, value: &Array, what: &str) -> ScriptResult<Vec<Vec<f64>>> {
    value
        .iter()
        .enumerate()
        .map(|(i, row)| floats(ctx, row, &format!("{what}[{i}]")))
        .collect()
}

/// Strings from an array of strings.
pub fn strings(ctx: &NativeCallContext, value: &Array, what: &str) -> ScriptResult<Vec<String>> {
    value
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.clone()
                .into_string()
                .map_err(|t| error(ctx, format!("{what}[{i}] must be a string, got {t}")))
        })
        .collect()
}

/// Converts a script value to JSON (integers stay integers, floats stay floats). Strict: a
/// NaN or infinite float, or a value of a type JSON cannot hold, is an error naming where
/// it is (`path.field[i]`) and the value, never a silent `null`.
pub fn strict_json(value: &Dynamic, path: &str) -> Result<serde_json::Value, String> {
    use serde_json::Value;
    if value.is_unit() {
        return Ok(Value::Null);
    }
    if let Ok(b) = value.as_bool() {
        return Ok(Value::Bool(b));
    }
    if let Ok(i) = value.as_int() {
        return Ok(Value::from(i));
    }
    if let Ok(f) = value.as_float() {
        return serde_json::Number::from_f64(f)
            .map(Value::Number)
            .ok_or_else(|| format!("{path} = {f}: must be a finite number"));
    }
    if let Ok(c) = value.as_char() {
        return Ok(Value::String(c.to_string()));
    }
    if value.is_string() {
        return Ok(Value::String(value.to_string()));
    }
    if let Some(a) = value.read_lock::<Array>() {
        return a
            .iter()
            .enumerate()
            .map(|(i, v)| strict_json(v, &format!("{path}[{i}]")))
            .collect::<Result<Vec<_>, _>>()
            .map(Value::Array);
    }
    if let Some(m) = value.read_lock::<Map>() {
        return m
            .iter()
            .map(|(k, v)| Ok((k.to_string(), strict_json(v, &format!("{path}.{k}"))?)))
            .collect::<Result<serde_json::Map<_, _>, String>>()
            .map(Value::Object);
    }
    Err(format!(
        "{path} is a {}, which cannot be used here (give numbers, strings, arrays or maps)",
        value.type_name()
    ))
}

/// Checks that deserialising `input` into `output` (re-serialised) used every part of it as
/// given: an unknown field at any depth, an array read as a map (serde accepts a sequence
/// for a struct), or a number changed on the way is an error naming the field and the value.
fn check_echo(
    input: &serde_json::Value,
    output: &serde_json::Value,
    path: &str,
) -> Result<(), String> {
    use serde_json::Value;
    let short = |v: &Value| {
        let t = v.to_string();
        if t.len() > 60 {
            format!(
                "{}...",
                &t[..t.char_indices().nth(57).map_or(t.len(), |(i, _)| i)]
            )
        } else {
            t
        }
    };
    let kind = |v: &Value| match v {
        Value::Null => "nothing (())",
        Value::Bool(_) => "a bool",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "a map",
    };
    match (input, output) {
        (Value::Object(i), Value::Object(o)) => {
            for (k, v) in i {
                match o.get(k) {
                    Some(ov) => check_echo(v, ov, &format!("{path}.{k}"))?,
                    None if v.is_null() => {}
                    None => {
                        return Err(format!(
                            "{path}.{k} = {}: unknown field (the fields here are: {})",
                            short(v),
                            o.keys().cloned().collect::<Vec<_>>().join(", ")
                        ))
                    }
                }
            }
            Ok(())
        }
        (Value::Array(i), Value::Array(o)) if i.len() == o.len() => i
            .iter()
            .zip(o)
            .enumerate()
            .try_for_each(|(n, (a, b))| check_echo(a, b, &format!("{path}[{n}]"))),
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (
                a.as_f64().unwrap_or(f64::NAN),
                b.as_f64().unwrap_or(f64::NAN),
            );
            if a == b {
                Ok(())
            } else {
                Err(format!(
                    "{path} = {a}: cannot be represented here (read as {b})"
                ))
            }
        }
        (Value::Null, _) | (Value::String(_), _) | (Value::Bool(_), Value::Bool(_)) => Ok(()),
        (i, o) => Err(format!(
            "{path} = {}: {} was given where {} is expected",
            short(i),
            kind(i),
            kind(o)
        )),
    }
}

/// Converts a serialisable library value to a script value (structs become object maps).
pub fn to_dynamic<T: Serialize>(ctx: &NativeCallContext, value: &T) -> ScriptResult<Dynamic> {
    rhai::serde::to_dynamic(value).map_err(|e| error(ctx, e))
}

/// Deserialises an option map into `T`. Integers are accepted where floats are expected.
/// An unknown field is named by serde; a mistyped one is found by trying each field
/// alone over `base` (a valid value of `T`), so the message names it and its value.
pub fn options<T>(ctx: &NativeCallContext, map: Map, base: &T, what: &str) -> ScriptResult<T>
where
    T: DeserializeOwned + Serialize,
{
    let value = strict_json(&Dynamic::from_map(map), what).map_err(|m| error(ctx, m))?;
    let parsed = serde_json::from_value::<T>(value.clone()).map_err(|e| {
        let message = match bad_field(&value, base) {
            Some((field, v, why)) => format!("{what}.{field} = {v}: {why}"),
            None => format!("{what}: {e}"),
        };
        error(ctx, message)
    })?;
    let echo = serde_json::to_value(&parsed).at(ctx)?;
    check_echo(&value, &echo, what).map_err(|m| error(ctx, m))?;
    Ok(parsed)
}

/// Deserialises `overrides` laid over `base`: nested maps merge field by field (unless they
/// name a different `kind` of a tagged enum), any other value (including `()`, which clears
/// an optional field) replaces the base's.
pub fn overlay<T>(ctx: &NativeCallContext, overrides: Map, base: &T, what: &str) -> ScriptResult<T>
where
    T: DeserializeOwned + Serialize,
{
    let mut merged = serde_json::to_value(base).at(ctx)?;
    let given = strict_json(&Dynamic::from_map(overrides), what).map_err(|m| error(ctx, m))?;
    merge(&mut merged, given);
    let map = rhai::serde::to_dynamic(&merged).map_err(|e| error(ctx, e))?;
    options(ctx, map.cast::<Map>(), base, what)
}

fn merge(base: &mut serde_json::Value, over: serde_json::Value) {
    match (base, over) {
        (serde_json::Value::Object(b), serde_json::Value::Object(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(slot) if slot.is_object() && v.is_object() && same_kind(slot, &v) => {
                        merge(slot, v)
                    }
                    _ => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

/// True unless both values name a `kind` and the kinds differ.
fn same_kind(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    match (a.get("kind"), b.get("kind")) {
        (Some(x), Some(y)) => x == y,
        _ => true,
    }
}

/// The first field of `value` that fails to deserialise when put alone over `base`.
fn bad_field<T>(value: &serde_json::Value, base: &T) -> Option<(String, String, String)>
where
    T: DeserializeOwned + Serialize,
{
    let base = serde_json::to_value(base).ok()?;
    value.as_object()?.iter().find_map(|(k, v)| {
        let mut probe = base.clone();
        probe.as_object_mut()?.insert(k.clone(), v.clone());
        serde_json::from_value::<T>(probe)
            .err()
            .map(|e| (k.clone(), v.to_string(), e.to_string()))
    })
}

/// A string-keyed option parsed by serde from its text (e.g. a snake_case enum name).
pub fn named<T: DeserializeOwned>(
    ctx: &NativeCallContext,
    text: &str,
    what: &str,
) -> ScriptResult<T> {
    serde_json::from_value(serde_json::Value::String(text.to_string()))
        .map_err(|e| error(ctx, format!("{what} '{text}': {e}")))
}
