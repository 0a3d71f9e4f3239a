//! `experiment.channel`: the channel an experiment script runs on, read from its `--set`
//! parameters in this one place, so that every experiment script takes the same ones
//! (docs/src/guide/lab-data.md):
//!
//! - `channel = scene` (default): the script simulates its scenes; the channel is ().
//! - `channel = impulse`, `impulse = FILE.npy` (under `--data`; one row per receiver: the
//!   response to a unit drive sample at t = 0), `dt_s`, `peak_drive`: a measured linear
//!   channel ([`crate::trnews::Responder::from_impulse`]).
//! - `channel = recorded`, `recordings = DIR` (a lab directory under `--data`, see
//!   [`crate::lab`]), `dt_s`, `peak_drive`: recorded responses; drives not recorded yet are
//!   written to `OUT/to_record/` and the run stops saying so.
//!
//! With either, `band` (default: the file or directory) and `sample` (the name in tables and
//! figures; default: the channel's kind) label the data. A parameter that does not apply to
//! the chosen channel is an error naming it, never ignored.

use crate::script::convert::{error, number, ScriptResult, WithPosition};
use crate::script::HostContext;
use crate::trnews::Responder;
use rhai::{Dynamic, Map, NativeCallContext};

/// Parameters of the measured and recorded channels only.
const DATA_ONLY: &[&str] = &[
    "impulse",
    "recordings",
    "dt_s",
    "peak_drive",
    "band",
    "sample",
];
/// Parameters of the simulated scene only: a measured channel has no mesh to refine.
const SCENE_ONLY: &[&str] = &["error_estimate", "tolerance"];

/// A measured or recorded channel's kind.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Impulse,
    Recorded,
}

impl Kind {
    /// The value of `channel`.
    fn name(self) -> &'static str {
        match self {
            Kind::Impulse => "impulse",
            Kind::Recorded => "recorded",
        }
    }

    /// The parameter naming the data: the impulse-response file or the lab directory.
    fn source(self) -> &'static str {
        match self {
            Kind::Impulse => "impulse",
            Kind::Recorded => "recordings",
        }
    }

    /// What to write for [`Kind::source`].
    fn usage(self) -> &'static str {
        match self {
            Kind::Impulse => "FILE.npy (under --data: one row per receiver)",
            Kind::Recorded => "DIR (a lab directory under --data)",
        }
    }
}

/// The `--set` parameters of the running script.
struct Params(std::sync::Arc<HostContext>);

impl Params {
    /// Text of parameter `name`, if given.
    fn text(&self, name: &str) -> Option<String> {
        self.0.param(name).map(Dynamic::to_string)
    }

    /// An error when one of `names` is given: it does not apply to `setting`.
    fn refuse(&self, names: &[&str], setting: &str) -> Result<(), String> {
        match names.iter().find(|n| self.0.param(n).is_some()) {
            Some(n) => Err(crate::Error::invalid(
                *n,
                self.text(n).unwrap_or_default(),
                format!("does not apply to {setting}; drop it or choose another channel"),
            )
            .to_string()),
            None => Ok(()),
        }
    }

    /// Parameter `name`, which `kind` requires; `usage` says what to write after `name=`.
    fn required(&self, name: &str, kind: Kind, usage: &str) -> Result<Dynamic, String> {
        self.0.param(name).cloned().ok_or_else(|| {
            crate::Error::invalid(
                name,
                "(not given)",
                format!("channel = {} needs it: --set {name}={usage}", kind.name()),
            )
            .to_string()
        })
    }

    /// The number `name`, which `kind` requires, finite and > 0.
    fn positive(&self, name: &str, kind: Kind, usage: &str) -> Result<f64, String> {
        let value = self.required(name, kind, usage)?;
        let x = number(&value).ok_or_else(|| {
            crate::Error::invalid(
                name,
                &value,
                format!("expected a number: --set {name}={usage}"),
            )
            .to_string()
        })?;
        crate::error::require_positive(name, x).map_err(|e| e.to_string())
    }
}

/// The channel chosen by the `--set` parameters: () for the simulated scene, otherwise
/// #{kind, sample, responder}.
pub fn from_params(ctx: &NativeCallContext) -> ScriptResult<Dynamic> {
    let params = Params(HostContext::of(ctx)?);
    let choice = params.text("channel").unwrap_or_else(|| "scene".into());
    let kind = match choice.as_str() {
        "scene" => {
            params
                .refuse(DATA_ONLY, "channel = scene (the simulated scene)")
                .map_err(|m| error(ctx, m))?;
            return Ok(Dynamic::UNIT);
        }
        "impulse" => Kind::Impulse,
        "recorded" => Kind::Recorded,
        other => {
            return Err(error(
                ctx,
                crate::Error::invalid(
                    "channel",
                    format!("\"{other}\""),
                    "expected scene, impulse or recorded",
                ),
            ))
        }
    };
    let responder = measured(ctx, &params, kind)?;
    let sample = params
        .text("sample")
        .unwrap_or_else(|| kind.name().to_string());
    let mut m = Map::new();
    m.insert("kind".into(), kind.name().into());
    m.insert("sample".into(), sample.into());
    m.insert("responder".into(), Dynamic::from(responder));
    Ok(m.into())
}

/// The measured (`impulse`) or recorded channel the parameters describe.
fn measured(ctx: &NativeCallContext, params: &Params, kind: Kind) -> ScriptResult<Responder> {
    let setting = format!("channel = {} (measured data)", kind.name());
    let other = match kind {
        Kind::Impulse => Kind::Recorded,
        Kind::Recorded => Kind::Impulse,
    };
    let checked = params
        .refuse(SCENE_ONLY, &setting)
        .and_then(|()| params.refuse(&[other.source()], &setting))
        .and_then(|()| {
            let source = params.required(kind.source(), kind, kind.usage())?;
            let dt_s = params.positive("dt_s", kind, "SECONDS (the data's sample step)")?;
            let peak = params.positive(
                "peak_drive",
                kind,
                "AMPLITUDE (the drives' peak, in the drive's unit)",
            )?;
            Ok((source.to_string(), dt_s, peak))
        });
    let (source, dt_s, peak_drive) = checked.map_err(|m| error(ctx, m))?;
    let band = params
        .text("band")
        .unwrap_or_else(|| format!("{} ({source})", kind.name()));
    let host = &params.0;
    let root = host.data_root().map_err(|m| error(ctx, m))?;
    let responder = match kind {
        Kind::Impulse => {
            let h = crate::lab::read_traces(&root, &source, dt_s).at(ctx)?;
            Responder::from_impulse(h, peak_drive, band).at(ctx)?
        }
        Kind::Recorded => {
            let out = (host.out_dir(), crate::io::active_root());
            crate::trnews::lab_channel(&root, &source, dt_s, peak_drive, band, out).at(ctx)?
        }
    };
    host.print(&describe(&responder, kind, &source));
    Ok(responder)
}

/// One line saying what the channel holds.
fn describe(r: &Responder, kind: Kind, source: &str) -> String {
    let held = match r.channel() {
        crate::trnews::Channel::Impulse(c) => format!("{} receivers", c.impulse.len()),
        crate::trnews::Channel::Recorded(c) => format!("{} recordings", c.recordings.len()),
        crate::trnews::Channel::Scene { .. } => String::new(),
    };
    format!(
        "channel = {}: {source} ({held}), dt_s = {}, peak_drive = {}, band '{}'",
        kind.name(),
        r.dt_s(),
        r.peak_drive(),
        r.band()
    )
}
