//! Rhai module `study`: the work-precision study (error against run time on a problem with a
//! known answer), and `study::sweep`, a resumable, shardable map over parameter points.
//! Type: `WorkPrecision`.

use crate::io::csv::RoundTrip;
use crate::study::WorkPrecisionPoint;
use rhai::plugin::*;
use rhai::{Array, Dynamic, Engine, Map, Module, NativeCallContext, INT};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// A plain script value: what a `study::sweep` point, its inputs and its result may be.
/// Stored bit-exactly (floats as their 8 bytes) and keyed canonically (maps sorted), as a flat
/// list of [`Token`]s, so that a stored value is decoded without recursion: a forged point
/// file nested a million deep is refused at [`MAX_DEPTH`], never a stack overflow.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(into = "Vec<Token>", try_from = "Vec<Token>")]
pub enum Plain {
    /// `()`.
    Unit,
    /// A bool.
    Bool(bool),
    /// An integer.
    Int(INT),
    /// A float.
    Float(f64),
    /// A string.
    Text(String),
    /// An array.
    List(Vec<Plain>),
    /// An object map.
    Map(BTreeMap<String, Plain>),
}

/// Deepest nesting of arrays and maps in a plain value.
pub const MAX_DEPTH: usize = 64;

/// One token of a [`Plain`] value in pre-order: a container token gives its length, and its
/// elements (a map's as key, value) follow.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum Token {
    /// `()`.
    Unit,
    /// A bool.
    Bool(bool),
    /// An integer.
    Int(INT),
    /// A float.
    Float(f64),
    /// A string.
    Text(String),
    /// An array of this many values.
    List(u64),
    /// A map of this many entries.
    Map(u64),
    /// A map entry's key, before its value.
    Key(String),
}

impl From<Plain> for Vec<Token> {
    fn from(value: Plain) -> Vec<Token> {
        fn push(value: Plain, tokens: &mut Vec<Token>) {
            match value {
                Plain::Unit => tokens.push(Token::Unit),
                Plain::Bool(b) => tokens.push(Token::Bool(b)),
                Plain::Int(i) => tokens.push(Token::Int(i)),
                Plain::Float(f) => tokens.push(Token::Float(f)),
                Plain::Text(t) => tokens.push(Token::Text(t)),
                Plain::List(l) => {
                    tokens.push(Token::List(l.len() as u64));
                    l.into_iter().for_each(|v| push(v, tokens));
                }
                Plain::Map(m) => {
                    tokens.push(Token::Map(m.len() as u64));
                    for (k, v) in m {
                        tokens.push(Token::Key(k));
                        push(v, tokens);
                    }
                }
            }
        }
        let mut tokens = Vec::new();
        push(value, &mut tokens);
        tokens
    }
}

/// A container still being filled while tokens are read: its length, and its entries so far
/// (a map's with the key awaiting its value).
enum Open {
    List(u64, Vec<Plain>),
    Map(u64, Option<String>, BTreeMap<String, Plain>),
}

impl TryFrom<Vec<Token>> for Plain {
    type Error = String;

    /// Rebuilds the value with an explicit stack of open containers (no recursion), refusing
    /// nesting deeper than [`MAX_DEPTH`], a NaN, a repeated key, and tokens out of place.
    fn try_from(tokens: Vec<Token>) -> Result<Plain, String> {
        let mut stack: Vec<Open> = Vec::new();
        let mut tokens = tokens.into_iter();
        loop {
            let token = tokens
                .next()
                .ok_or("a plain value ends inside a container")?;
            let mut done = match token {
                Token::List(0) => Some(Plain::List(Vec::new())),
                Token::Map(0) => Some(Plain::Map(BTreeMap::new())),
                Token::List(n) | Token::Map(n) if stack.len() >= MAX_DEPTH => {
                    return Err(format!(
                        "a plain value nests deeper than {MAX_DEPTH} (a container of {n})"
                    ))
                }
                Token::List(n) => {
                    stack.push(Open::List(n, Vec::new()));
                    None
                }
                Token::Map(n) => {
                    stack.push(Open::Map(n, None, BTreeMap::new()));
                    None
                }
                Token::Key(k) => match stack.last_mut() {
                    Some(Open::Map(_, key @ None, _)) => {
                        *key = Some(k);
                        None
                    }
                    _ => return Err(format!("a plain value has the key '{k}' out of place")),
                },
                Token::Float(f) if f.is_nan() => return Err("a plain value holds a NaN".into()),
                Token::Unit => Some(Plain::Unit),
                Token::Bool(b) => Some(Plain::Bool(b)),
                Token::Int(i) => Some(Plain::Int(i)),
                Token::Float(f) => Some(Plain::Float(f)),
                Token::Text(t) => Some(Plain::Text(t)),
            };
            // A finished value goes into the innermost open container, which may finish too.
            while let Some(value) = done.take() {
                let full = match stack.last_mut() {
                    None if tokens.next().is_none() => return Ok(value),
                    None => return Err("a plain value is followed by more tokens".into()),
                    Some(Open::List(n, items)) => {
                        items.push(value);
                        items.len() as u64 == *n
                    }
                    Some(Open::Map(n, key, items)) => {
                        let k = key.take().ok_or("a plain map value has no key")?;
                        if items.contains_key(&k) {
                            return Err(format!("a plain map repeats the key '{k}'"));
                        }
                        items.insert(k, value);
                        items.len() as u64 == *n
                    }
                };
                if full {
                    done = stack.pop().map(|open| match open {
                        Open::List(_, items) => Plain::List(items),
                        Open::Map(_, _, items) => Plain::Map(items),
                    });
                }
            }
        }
    }
}

impl Plain {
    /// `value` as plain data; `what` names it in the error for anything else (a Signal, a
    /// Scene: results that cannot be stored are refused, not dropped), for a NaN, and for
    /// nesting deeper than [`MAX_DEPTH`].
    pub fn of(value: &Dynamic, what: &str) -> Result<Plain, String> {
        Plain::nested(value, what, 0)
    }

    fn nested(value: &Dynamic, what: &str, depth: usize) -> Result<Plain, String> {
        let is_container = value.is_array() || value.is_map();
        if is_container && depth >= MAX_DEPTH {
            return Err(format!(
                "{what} nests arrays or maps deeper than {MAX_DEPTH}: a sweep stores plain \
                 values of at most that depth"
            ));
        }
        if value.is_unit() {
            Ok(Plain::Unit)
        } else if let Ok(b) = value.as_bool() {
            Ok(Plain::Bool(b))
        } else if let Ok(i) = value.as_int() {
            Ok(Plain::Int(i))
        } else if let Ok(f) = value.as_float() {
            if f.is_nan() {
                return Err(format!("{what} is NaN: a sweep stores numbers only"));
            }
            Ok(Plain::Float(f))
        } else if value.is_string() {
            Ok(Plain::Text(value.to_string()))
        } else if let Some(list) = value.read_lock::<Array>() {
            list.iter()
                .enumerate()
                .map(|(i, v)| Plain::nested(v, &format!("{what}[{i}]"), depth + 1))
                .collect::<Result<_, _>>()
                .map(Plain::List)
        } else if let Some(map) = value.read_lock::<Map>() {
            map.iter()
                .map(|(k, v)| {
                    let v = Plain::nested(v, &format!("{what}.{k}"), depth + 1)?;
                    Ok((k.to_string(), v))
                })
                .collect::<Result<_, String>>()
                .map(Plain::Map)
        } else {
            Err(format!(
                "{what} is a {}: a sweep stores plain values only (numbers, strings, bools, \
                 arrays, maps); return e.g. a summary map instead",
                value.type_name().rsplit("::").next().unwrap_or_default()
            ))
        }
    }

    /// Back to a script value.
    pub fn into_dynamic(self) -> Dynamic {
        match self {
            Plain::Unit => Dynamic::UNIT,
            Plain::Bool(b) => b.into(),
            Plain::Int(i) => i.into(),
            Plain::Float(f) => f.into(),
            Plain::Text(t) => t.into(),
            Plain::List(l) => l
                .into_iter()
                .map(Plain::into_dynamic)
                .collect::<Array>()
                .into(),
            Plain::Map(m) => m
                .into_iter()
                .map(|(k, v)| (k.into(), v.into_dynamic()))
                .collect::<Map>()
                .into(),
        }
    }
}

/// `study::sweep`: calls `f` on each point this run computes (in order; native work inside
/// `f` runs in parallel as usual), recording each result or error; see [`crate::sweep`].
fn sweep(
    ctx: &NativeCallContext,
    name: &str,
    inputs: &Dynamic,
    points: &Array,
    f: &rhai::FnPtr,
) -> Result<Array, Box<rhai::EvalAltResult>> {
    use crate::script::convert::error;
    use crate::sweep::{Key, PointSpec, Sweep};
    let inputs = Plain::of(inputs, "inputs").map_err(|e| error(ctx, e))?;
    let specs = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let point = Plain::of(p, &format!("points[{i}]")).map_err(|e| error(ctx, e))?;
            Ok(PointSpec {
                key: Key::of("sweep", &(name, &inputs, &point)).map_err(|e| error(ctx, e))?,
                label: p.to_string(),
                sharded: true,
            })
        })
        .collect::<Result<Vec<_>, Box<rhai::EvalAltResult>>>()?;
    // Any plain value is a possible result of the script's function.
    let sweep = Sweep::start::<Plain>(&format!("sweep '{name}'"), "sweep", specs, &|_| Ok(()));
    for &i in sweep.pending() {
        let start = std::time::Instant::now();
        let outcome = match f.call_within_context::<Dynamic>(ctx, (points[i].clone(),)) {
            Ok(value) => Plain::of(&value, &format!("the result of points[{i}]"))
                .map_err(crate::Error::Named),
            // Time limit, operation limit, Ctrl-C, a finished shard: stop the sweep.
            Err(e) if !e.is_catchable() => return Err(e),
            Err(e) => Err(crate::Error::Named(e.to_string())),
        };
        sweep
            .record(i, outcome, start.elapsed().as_secs_f64(), "")
            .map_err(|e| error(ctx, e))?;
    }
    let values: Vec<Plain> = sweep
        .finish()
        .map_err(|e| crate::script::sweep_error(ctx, e))?;
    Ok(values.into_iter().map(Plain::into_dynamic).collect())
}

/// The points of a work-precision study.
pub type WorkPrecision = Arc<Vec<WorkPrecisionPoint>>;

/// Registers the display name of the custom type.
pub fn register_types(engine: &mut Engine) {
    engine.register_type_with_name::<WorkPrecision>("WorkPrecision");
}

/// The `study` module.
pub fn module() -> Module {
    exported_module!(study_api)
}

#[export_module]
mod study_api {
    use super::WorkPrecision;
    use crate::script::convert::{error, options, to_dynamic, WithPosition};
    use crate::script::HostContext;
    use crate::study::WorkPrecisionSpec;
    use rhai::{Array, Dynamic, FnPtr, Map, NativeCallContext};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// Maps `f` over `points` as a resumable sweep: each point's result (a plain value: numbers, strings, bools, arrays, maps) is stored under points/sweep/, keyed by `name`, `inputs` (a map of everything else the results depend on: change `name` when `f` changes) and the point. A rerun computes only missing points, `--shard I/N` computes a share, `--merge` only assembles; a failing point is recorded with its error while the others go on, and the sweep then fails naming it.
    #[rhai_fn(name = "sweep", return_raw)]
    pub fn sweep_points(
        ctx: NativeCallContext,
        name: &str,
        inputs: Dynamic,
        points: Array,
        f: FnPtr,
    ) -> Res<Array> {
        super::sweep(&ctx, name, &inputs, &points, &f)
    }

    /// Calls `f` with no point store: the first passes it runs (impulse responses, TR-NEWS) are computed, never read from or written to points/, so that its run time is the computation's (for timing studies).
    #[rhai_fn(return_raw)]
    pub fn uncached(ctx: NativeCallContext, f: FnPtr) -> Res<Dynamic> {
        crate::sweep::without_store(|| f.call_within_context::<Dynamic>(&ctx, ()))
    }

    /// Default work-precision parameters #{element_sizes_m, explicit_fractions, newmark_multiples, depth_m, pulse_width_s}.
    #[rhai_fn(return_raw)]
    pub fn default_work_precision(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &WorkPrecisionSpec::default())
    }

    /// Runs the plane-P-wave work-precision study (explicit and Newmark over element sizes and steps) with options over the defaults.
    #[rhai_fn(return_raw)]
    pub fn work_precision(ctx: NativeCallContext, spec: Map) -> Res<WorkPrecision> {
        let spec: WorkPrecisionSpec =
            options(&ctx, spec, &WorkPrecisionSpec::default(), "work_precision")?;
        Ok(Arc::new(crate::study::work_precision(&spec).at(&ctx)?))
    }

    /// The study's points as maps #{discretisation, order, integrator, element_size_m, dt_s, stability_ratio, dofs, error, run_time_s, report}.
    #[rhai_fn(global, get = "points", pure, return_raw)]
    pub fn points(ctx: NativeCallContext, wp: &mut WorkPrecision) -> Res<Dynamic> {
        to_dynamic(&ctx, wp.as_ref())
    }

    /// Writes the study as CSV: discretisation (t3 or sem), order, integrator, element size, dt, dt/dt_crit, DOFs, steps, error, run time, energy residual.
    #[rhai_fn(global, return_raw)]
    pub fn write_csv(ctx: NativeCallContext, wp: WorkPrecision, path: &str) -> Res<()> {
        let file = HostContext::of(&ctx)?
            .resolve_output(path)
            .map_err(|e| error(&ctx, e))?;
        let rows: Vec<WorkPrecisionRow> = wp.iter().map(WorkPrecisionRow::of).collect();
        crate::io::csv::write_rows(&file, &rows).at(&ctx)
    }
}

/// One CSV row of a work-precision study; the field names are the column names.
#[derive(Serialize)]
struct WorkPrecisionRow<'a> {
    discretisation: &'a str,
    order: usize,
    integrator: &'a str,
    element_size_m: RoundTrip,
    dt_s: RoundTrip,
    dt_over_dt_crit: RoundTrip,
    dofs: usize,
    steps: usize,
    error: RoundTrip,
    run_time_s: RoundTrip,
    energy_residual_peak: RoundTrip,
}

impl<'a> WorkPrecisionRow<'a> {
    /// The row of point `p`.
    fn of(p: &'a WorkPrecisionPoint) -> Self {
        WorkPrecisionRow {
            discretisation: &p.discretisation,
            order: p.order,
            integrator: &p.integrator,
            element_size_m: RoundTrip(p.element_size_m),
            dt_s: RoundTrip(p.dt_s),
            dt_over_dt_crit: RoundTrip(p.stability_ratio),
            dofs: p.dofs,
            steps: p.report.steps,
            error: RoundTrip(p.error),
            run_time_s: RoundTrip(p.run_time_s),
            energy_residual_peak: RoundTrip(p.report.energy_residual_peak),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Plain, Token, MAX_DEPTH};
    use crate::sweep::{decode, encode};

    fn nested(depth: usize) -> Vec<Token> {
        let mut tokens = vec![Token::List(1); depth];
        tokens.push(Token::Float(1.5));
        tokens
    }

    #[test]
    fn plain_values_round_trip_through_their_tokens() {
        let value = Plain::Map(
            [
                (
                    "a".to_string(),
                    Plain::List(vec![Plain::Int(3), Plain::Unit]),
                ),
                ("b".to_string(), Plain::Map(Default::default())),
                ("c".to_string(), Plain::Float(-0.0)),
            ]
            .into(),
        );
        let back: Plain = decode(&encode(&value).unwrap()).unwrap();
        assert_eq!(format!("{back:?}"), format!("{value:?}"));
        let deepest: Plain = decode(&encode(&nested(MAX_DEPTH)).unwrap()).unwrap();
        assert!(matches!(deepest, Plain::List(_)));
    }

    /// Forged point contents: decoded without recursion and refused (postcard keeps no
    /// message of a refusal, so the reasons are checked on the tokens directly).
    #[test]
    fn forged_plain_values_are_refused_not_overflowed() {
        let refused = |tokens: Vec<Token>| {
            assert!(decode::<Plain>(&encode(&tokens).unwrap()).is_err());
            Plain::try_from(tokens).err().unwrap_or_default()
        };
        assert!(refused(nested(1_000_000)).contains("deeper than 64"));
        assert!(refused(vec![Token::Float(f64::NAN)]).contains("NaN"));
        assert!(refused(vec![Token::List(u64::MAX), Token::Unit]).contains("ends inside"));
        let repeated = vec![
            Token::Map(2),
            Token::Key("k".into()),
            Token::Unit,
            Token::Key("k".into()),
            Token::Unit,
        ];
        assert!(refused(repeated).contains("repeats the key 'k'"));
        assert!(refused(vec![Token::Map(1), Token::Unit]).contains("no key"));
        assert!(refused(vec![Token::Unit, Token::Unit]).contains("followed by more"));
    }
}
