//! The channels TR-NEWS runs on: a simulated scene (one impulse response and convolutions when
//! it is linear), a measured impulse response, or recorded responses; a [`Responder`] answers a
//! drive signal with the receivers' traces whichever it is.

use crate::accuracy::Refinement;
use crate::error::{require_positive, Error, Result};
use crate::lab::{Recording, ToRecord};
use crate::scene::Scene;
use crate::signal::{self, Signal};
use crate::solve::RunReport;
#[cfg(feature = "io")]
use crate::{input::InputRoot, io::OutputRoot, lab::read_lab};
use serde::{Deserialize, Serialize};
#[cfg(feature = "io")]
use std::path::Path;
use std::sync::Arc;

/// Largest companion cost, relative to the main runs, at which [`ErrorEstimate::Auto`] turns
/// the estimate on: issue 25's 30%.
pub const AUTO_ESTIMATE_MAX_COST: f64 = 0.30;

/// Whether a responder repeats its procedures on its error estimate's companions
/// ([`Responder::estimate_decision`]). Written `true`, `false` or `"auto"` (as a word too:
/// `--set error_estimate=true` may reach a script as either).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorEstimate {
    /// Never.
    #[default]
    Off,
    /// Always.
    On,
    /// When the companions cost at most [`AUTO_ESTIMATE_MAX_COST`] of the main runs.
    Auto,
}

impl std::str::FromStr for ErrorEstimate {
    type Err = Error;

    /// `true`, `false` or `auto`; anything else is refused, naming the value.
    fn from_str(word: &str) -> Result<ErrorEstimate> {
        match word {
            "true" => Ok(ErrorEstimate::On),
            "false" => Ok(ErrorEstimate::Off),
            "auto" => Ok(ErrorEstimate::Auto),
            other => Err(Error::invalid(
                "error_estimate",
                format!("\"{other}\""),
                "expected true, false or \"auto\"",
            )),
        }
    }
}

impl Serialize for ErrorEstimate {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            ErrorEstimate::Off => s.serialize_bool(false),
            ErrorEstimate::On => s.serialize_bool(true),
            ErrorEstimate::Auto => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for ErrorEstimate {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        /// The two ways of writing it.
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Written {
            Flag(bool),
            Word(String),
        }
        match Written::deserialize(d)? {
            Written::Flag(true) => Ok(ErrorEstimate::On),
            Written::Flag(false) => Ok(ErrorEstimate::Off),
            Written::Word(w) => w.parse().map_err(serde::de::Error::custom),
        }
    }
}

/// What an [`ErrorEstimate`] choice gives on a responder.
#[derive(Clone, Debug)]
pub enum EstimateDecision {
    /// No estimate was asked for.
    Off,
    /// The companions' scenes, to add with [`Responder::with_companions`].
    On(Vec<Arc<Scene>>),
    /// "auto" and the companions would add `cost` (relative to the main runs), above
    /// [`AUTO_ESTIMATE_MAX_COST`].
    TooCostly {
        /// The companions' run time relative to the main runs.
        cost: f64,
    },
}

/// Recorded responses of every receiver to one transmission.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Response {
    /// One trace per receiver, from t = 0 at the solver step.
    pub traces: Vec<Signal>,
    /// The run report, when the response was simulated (None when convolved).
    pub report: Option<RunReport>,
}

/// Answers "what do the receivers record when the transmitter sends s?". Cheap to clone.
///
/// The TR-NEWS procedures below ([`tr_news`], [`delayed_tr_news`], [`pulse_inversion`]) only
/// ask this question, so they run on any [`Channel`]: a simulated scene, a measured impulse
/// response, or recorded responses.
///
/// With an error estimate ([`Responder::with_companions`], simulated scenes only) it also
/// holds the scene's companions ([`crate::scene::SceneSpec::companions`]: 2x and 4x the element
/// sizes; on spectral elements one and two orders lower along x and one order higher across),
/// and every procedure below repeats itself on them and reports estimates of its results (see
/// [`crate::accuracy`]).
#[derive(Clone, Debug)]
pub struct Responder {
    channel: Channel,
    pub(super) dt_s: f64,
    /// The scene's companions in [`crate::scene::SceneSpec::companions`]'s order; empty
    /// without an error estimate.
    pub(super) companions: Vec<Responder>,
}

/// What answers a transmission.
#[derive(Clone, Debug)]
pub enum Channel {
    /// A simulated scene, through its transducers.
    Scene {
        /// The scene.
        scene: Arc<Scene>,
        /// Response to a unit impulse, per receiver, when the scene is linear: every
        /// transmission is then a convolution with it.
        impulse: Option<Arc<Response>>,
    },
    /// A measured linear, time-invariant channel: one impulse response per receiver.
    Impulse(Arc<ImpulseChannel>),
    /// Recorded responses to known transmissions (lab data).
    Recorded(Arc<RecordedChannel>),
}

/// A measured channel: receiver r records y_r[n] = sum_k s[k] h_r[n - k] for the drive s
/// (the discrete convolution with its response h_r to a unit drive sample at step 0,
/// transducers included).
#[derive(Clone, Debug)]
pub struct ImpulseChannel {
    /// h_r per receiver, from t = 0, all on one step.
    pub impulse: Vec<Signal>,
    /// Peak of the drive signals (the chirp's amplitude and the focusing signals' peak).
    pub peak_drive: f64,
    /// The band the traces were recorded in, for titles and printed results.
    pub band: String,
}

/// Recorded responses: a transmission is answered by the recording of the same drive
/// (relative L2 difference at most [`RecordedChannel::MATCH`]), and refused otherwise.
#[derive(Clone, Debug)]
pub struct RecordedChannel {
    /// The recordings.
    pub recordings: Vec<Recording>,
    /// Peak of the drive signals.
    pub peak_drive: f64,
    /// The band the traces were recorded in.
    pub band: String,
    /// For a lab directory's channel (see [`crate::lab`]): where a drive without a recording
    /// is listed for the lab to play; `None`: such a drive is refused with an error.
    pub to_record: Option<Arc<crate::lab::ToRecord>>,
}

impl RecordedChannel {
    /// Largest relative L2 difference between a drive and a recording's drive for the
    /// recording to answer it: round-off of a drive written to a file and read back.
    pub const MATCH: f64 = 1e-9;
}

/// Why stored `traces` cannot be a response of `receivers` receivers on step `dt_s` from
/// t = 0 (see [`crate::sweep::Expect`]).
pub(super) fn expect_traces(
    traces: &[Signal],
    receivers: usize,
    dt_s: f64,
) -> std::result::Result<(), String> {
    if traces.len() != receivers {
        return Err(format!(
            "holds {} traces for {receivers} receivers",
            traces.len()
        ));
    }
    match traces
        .iter()
        .position(|t| t.dt_s != dt_s || t.t0_s != 0.0 || t.is_empty())
    {
        Some(i) => Err(format!(
            "holds trace {} on step {} s from {} s with {} samples, not on step {dt_s} s \
             from 0",
            i + 1,
            traces[i].dt_s,
            traces[i].t0_s,
            traces[i].len()
        )),
        None => Ok(()),
    }
}

/// The step shared by every trace of a channel, or an error naming `what` and the trace.
fn common_step(traces: &[Signal], what: &str) -> Result<f64> {
    let first = traces
        .first()
        .ok_or_else(|| Error::invalid(what, "[]", "needs at least one receiver's trace"))?;
    for (i, t) in traces.iter().enumerate() {
        t.validate()?;
        if (t.dt_s / first.dt_s - 1.0).abs() > 1e-9 {
            return Err(Error::invalid(
                format!("{what}[{i}].dt"),
                t.dt_s,
                format!("differs from {what}[0].dt = {}", first.dt_s),
            ));
        }
    }
    Ok(first.dt_s)
}

/// Refuses a drive peak that is not finite and positive, or above
/// [`crate::scene::MAX_TRACTION_PA`] (a traction in Pa for simulated channels; no drive
/// amplifier of a lab reaches such a number in volts either).
fn positive_peak(peak_drive: f64) -> Result<()> {
    let max = crate::scene::MAX_TRACTION_PA;
    if peak_drive.is_finite() && peak_drive > 0.0 && peak_drive <= max {
        Ok(())
    } else {
        Err(Error::invalid(
            "peak_drive",
            peak_drive,
            format!("must be within (0, {max:e}]"),
        ))
    }
}

/// What determines a channel's answers, in the keys of stored results (see [`crate::sweep`]).
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ChannelIdentity<'a> {
    /// A simulated scene: its spec, step and, when convolving, the impulse response's length.
    Scene {
        /// The scene's spec.
        spec: &'a crate::scene::SceneSpec,
        /// The step of its runs (s).
        dt_s: f64,
        /// Samples of the stored impulse response, for a linear scene.
        impulse_length: Option<usize>,
    },
    /// Measured data (impulse responses or recordings): the SHA-256 of its exact samples.
    Data {
        /// Hex SHA-256 of the data's f64 bits.
        sha256: String,
    },
}

impl ChannelIdentity<'_> {
    fn data<T: Serialize>(data: &T) -> Result<ChannelIdentity<'static>> {
        use sha2::{Digest, Sha256};
        let bytes = crate::sweep::encode(data)?;
        let sha256 = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(ChannelIdentity::Data { sha256 })
    }
}

impl Responder {
    /// Simulates every transmission (any scene).
    pub fn simulating(scene: Arc<Scene>) -> Responder {
        let dt_s = scene.default_dt_s();
        Responder {
            channel: Channel::Scene {
                scene,
                impulse: None,
            },
            dt_s,
            companions: Vec::new(),
        }
    }

    /// For a linear scene, runs the impulse response once (over `duration_s`) and convolves
    /// afterwards; for a nonlinear scene, the same as [`Responder::simulating`].
    pub fn new(scene: Arc<Scene>, duration_s: f64) -> Result<Responder> {
        let dt_s = scene.default_dt_s();
        Self::with_step(scene, duration_s, dt_s)
    }

    /// [`Responder::new`] with every run at the time step `dt_s` (at most the scene's
    /// dt_crit) instead of the default.
    pub fn with_step(scene: Arc<Scene>, duration_s: f64, dt_s: f64) -> Result<Responder> {
        require_positive("dt_s", dt_s)?;
        let mut impulse = None;
        if scene.is_linear() {
            let config = crate::solve::RunConfig {
                dt_s: Some(dt_s),
                ..scene.run_config(duration_s)
            };
            // The first pass of every later response: stored with the sweep's points.
            let inputs = (&scene.spec, dt_s, duration_s);
            let receivers = scene.receivers.len();
            let expect = |h: &Response| expect_traces(&h.traces, receivers, dt_s);
            let response = crate::sweep::first_pass(
                "impulse_response",
                "impulse response",
                &inputs,
                &expect,
                || {
                    let out = scene.impulse_response(&config)?;
                    Ok(Response {
                        traces: out.traces,
                        report: Some(out.report),
                    })
                },
            )?;
            impulse = Some(Arc::new(response));
        }
        Ok(Responder {
            channel: Channel::Scene { scene, impulse },
            dt_s,
            companions: Vec::new(),
        })
    }

    /// A measured channel from one impulse response per receiver (see [`ImpulseChannel`]).
    pub fn from_impulse(impulse: Vec<Signal>, peak_drive: f64, band: String) -> Result<Responder> {
        let dt_s = common_step(&impulse, "impulse")?;
        positive_peak(peak_drive)?;
        Ok(Responder {
            channel: Channel::Impulse(Arc::new(ImpulseChannel {
                impulse,
                peak_drive,
                band,
            })),
            dt_s,
            companions: Vec::new(),
        })
    }

    /// A channel of recorded responses (see [`RecordedChannel`]); every drive and trace on
    /// one step, every recording with the same number of receivers.
    pub fn from_recordings(
        recordings: Vec<Recording>,
        peak_drive: f64,
        band: String,
    ) -> Result<Responder> {
        let drives: Vec<Signal> = recordings.iter().map(|r| r.sent.clone()).collect();
        let dt_s = common_step(&drives, "recordings.sent")?;
        let channel = RecordedChannel {
            recordings,
            peak_drive,
            band,
            to_record: None,
        };
        Responder::recorded(channel, dt_s)
    }

    /// A lab directory's channel (see [`crate::lab`]): recordings on step `dt_s`, none
    /// before the first phase; a batch of transmissions with drives not recorded adds them
    /// all to `to_record` and stops with its error ([`crate::lab::ToRecord::stop`]).
    pub fn from_lab(
        recordings: Vec<Recording>,
        dt_s: f64,
        peak_drive: f64,
        band: String,
        to_record: Arc<crate::lab::ToRecord>,
    ) -> Result<Responder> {
        if let Some((i, r)) = recordings
            .iter()
            .enumerate()
            .find(|(_, r)| (r.sent.dt_s / dt_s - 1.0).abs() > 1e-9)
        {
            return Err(Error::invalid(
                format!("recordings[{i}].sent.dt"),
                r.sent.dt_s,
                format!("differs from the channel's step dt_s = {dt_s}"),
            ));
        }
        let channel = RecordedChannel {
            recordings,
            peak_drive,
            band,
            to_record: Some(to_record),
        };
        Responder::recorded(channel, dt_s)
    }

    /// A responder on recorded responses at step `dt_s`, once its recordings' traces are
    /// checked (same receivers, same step) and its drive peak is positive.
    fn recorded(channel: RecordedChannel, dt_s: f64) -> Result<Responder> {
        positive_peak(channel.peak_drive)?;
        same_receivers_and_step(&channel.recordings, dt_s)?;
        Ok(Responder {
            channel: Channel::Recorded(Arc::new(channel)),
            dt_s,
            companions: Vec::new(),
        })
    }

    /// The channel that answers transmissions.
    pub fn channel(&self) -> &Channel {
        &self.channel
    }

    /// The simulated scene, when the channel is one.
    fn scene(&self) -> Result<&Arc<Scene>> {
        match &self.channel {
            Channel::Scene { scene, .. } => Ok(scene),
            _ => Err(Error::invalid(
                "error_estimate",
                true,
                "needs a simulated scene; a measured or recorded channel has no mesh to refine",
            )),
        }
    }

    /// How the companions refine this responder's scene.
    pub fn refinement(&self) -> Result<Refinement> {
        Ok(self.scene()?.spec.refinement())
    }

    /// The companions of this responder's scene, as the messages name them.
    pub fn companions_named(&self) -> Result<&'static str> {
        Ok(self.scene()?.spec.companions_named())
    }

    /// Peak of the transmitted drive signals: the scene transmitter's peak traction (Pa), or
    /// a measured channel's drive peak.
    pub fn peak_drive(&self) -> f64 {
        match &self.channel {
            Channel::Scene { scene, .. } => scene.spec.transmitter.peak_pa,
            Channel::Impulse(c) => c.peak_drive,
            Channel::Recorded(c) => c.peak_drive,
        }
    }

    /// The band every response is seen through, for titles and printed results.
    pub fn band(&self) -> String {
        match &self.channel {
            Channel::Scene { scene, .. } => {
                crate::transducer::band_label(scene.spec.transducer.as_ref())
            }
            Channel::Impulse(c) => c.band.clone(),
            Channel::Recorded(c) => c.band.clone(),
        }
    }

    /// True when every transmission is simulated (a nonlinear scene); false when answers
    /// are convolutions with an impulse response or recorded responses (cheap to recompute).
    pub fn simulates(&self) -> bool {
        matches!(self.channel, Channel::Scene { impulse: None, .. })
    }

    /// Everything that determines this responder's answers, for the keys of stored
    /// results: per discretisation (this one, then the companions) its [`ChannelIdentity`].
    pub fn identity(&self) -> Result<Vec<ChannelIdentity<'_>>> {
        std::iter::once(self)
            .chain(&self.companions)
            .map(|r| match &r.channel {
                Channel::Scene { scene, impulse } => Ok(ChannelIdentity::Scene {
                    spec: &scene.spec,
                    dt_s: r.dt_s,
                    impulse_length: impulse.as_ref().map(|h| h.traces[0].len()),
                }),
                Channel::Impulse(c) => ChannelIdentity::data(&(&c.impulse, c.peak_drive)),
                Channel::Recorded(c) => {
                    let pairs: Vec<(&Signal, &Vec<Signal>)> = c
                        .recordings
                        .iter()
                        .map(|r| (&r.sent, &r.received))
                        .collect();
                    ChannelIdentity::data(&(pairs, c.peak_drive))
                }
            })
            .collect()
    }

    /// The scenes of an error estimate's companions ([`SceneSpec::companions`]: on linear
    /// triangles 2x and 4x the element sizes, on spectral elements one and two orders lower
    /// along x at this responder's step and one higher across), and their run time
    /// relative to this responder's from DOFs x steps, sum over companions of (DOFs_c / DOFs)
    /// (dt / dt_c). On triangles about 1/8 + 1/64 where every layer coarsens, more where thin
    /// layers keep one element row or set the step; on spectral elements the companion across
    /// costs the most (a higher order across shortens the step). Building them runs no
    /// simulation.
    pub fn companion_scenes(&self) -> Result<(Vec<Arc<Scene>>, f64)> {
        let scene = self.scene()?;
        let scenes = scene
            .spec
            .companions(self.dt_s)?
            .iter()
            .map(|spec| Ok(Arc::new(Scene::build(spec)?)))
            .collect::<Result<Vec<_>>>()?;
        let work = |s: &Scene, dt: f64| s.dofs() as f64 / dt;
        let cost = scenes
            .iter()
            .map(|s| work(s, s.default_dt_s()))
            .sum::<f64>()
            / work(scene, self.dt_s);
        Ok((scenes, cost))
    }

    /// What `choice` gives on this responder: the companions' scenes to add with
    /// [`Responder::with_companions`], no estimate, or none because "auto" found them too
    /// costly (with their cost relative to the main runs).
    pub fn estimate_decision(&self, choice: ErrorEstimate) -> Result<EstimateDecision> {
        Ok(match choice {
            ErrorEstimate::Off => EstimateDecision::Off,
            ErrorEstimate::On => EstimateDecision::On(self.companion_scenes()?.0),
            ErrorEstimate::Auto => match self.companion_scenes()? {
                (scenes, cost) if cost <= AUTO_ESTIMATE_MAX_COST => EstimateDecision::On(scenes),
                (_, cost) => EstimateDecision::TooCostly { cost },
            },
        })
    }

    /// Adds companions on `scenes` (from [`Responder::companion_scenes`]), built the way this
    /// one was (convolving when linear, over `duration_s`).
    pub fn with_companions(
        mut self,
        scenes: Vec<Arc<Scene>>,
        duration_s: f64,
    ) -> Result<Responder> {
        let convolving = matches!(
            self.channel,
            Channel::Scene {
                impulse: Some(_),
                ..
            }
        );
        self.scene()?;
        self.companions = scenes
            .into_iter()
            .map(|scene| {
                if convolving {
                    Responder::new(scene, duration_s)
                } else {
                    Ok(Responder::simulating(scene))
                }
            })
            .collect::<Result<_>>()?;
        Ok(self)
    }

    /// The companions of the error estimate, empty without one.
    pub fn companions(&self) -> &[Responder] {
        &self.companions
    }

    /// The solver step of every response (s).
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The impulse-response run's report, when a simulated scene's responses are convolved.
    pub fn impulse_report(&self) -> Option<&RunReport> {
        match &self.channel {
            Channel::Scene {
                impulse: Some(i), ..
            } => i.report.as_ref(),
            _ => None,
        }
    }

    /// The drive `s` on this responder's step (resampled when its step differs).
    fn on_step(&self, s: &Signal) -> Result<Signal> {
        if (s.dt_s / self.dt_s - 1.0).abs() > 1e-9 {
            Ok(signal::resample(s, self.dt_s)?)
        } else {
            Ok(s.clone())
        }
    }

    /// Receivers' responses to the drive signal `s` (Pa for a scene) over `duration_s`,
    /// through the scene's transducers.
    pub fn respond(&self, s: &Signal, duration_s: f64) -> Result<Response> {
        let s = self.on_step(s)?;
        match &self.channel {
            Channel::Scene {
                scene,
                impulse: Some(h),
            } => convolved(scene, h, s, self.dt_s, duration_s),
            Channel::Scene {
                scene,
                impulse: None,
            } => {
                let config = crate::solve::RunConfig {
                    dt_s: Some(self.dt_s),
                    ..scene.run_config(duration_s)
                };
                let out = scene.transmit(&s, &config)?;
                Ok(Response {
                    traces: out.traces,
                    report: Some(out.report),
                })
            }
            Channel::Impulse(c) => {
                let n = samples_within(&c.impulse[0], self.dt_s, duration_s)?;
                let traces = c
                    .impulse
                    .iter()
                    .map(|h| Ok(truncate(signal::convolve_discrete(&s, h)?, n)))
                    .collect::<Result<Vec<_>>>()?;
                Ok(Response {
                    traces,
                    report: None,
                })
            }
            Channel::Recorded(c) => {
                let mut answers = c.answer_all(&[s], self.dt_s, duration_s)?;
                Ok(answers.remove(0))
            }
        }
    }

    /// The number of receivers that answer a transmission.
    pub fn receiver_count(&self) -> usize {
        match &self.channel {
            Channel::Scene { scene, .. } => scene.receivers.len(),
            Channel::Impulse(c) => c.impulse.len(),
            Channel::Recorded(c) => c.recordings.first().map_or(0, |r| r.received.len()),
        }
    }

    /// Responses to several transmissions; independent simulations run in parallel, and the
    /// results are identical for any thread count. Recorded responses are looked up all
    /// together, so that a lab channel lists every drive of the batch it has not recorded.
    pub fn respond_all(&self, sources: &[Signal], duration_s: f64) -> Result<Vec<Response>> {
        if let Channel::Recorded(c) = &self.channel {
            let drives = sources
                .iter()
                .map(|s| self.on_step(s))
                .collect::<Result<Vec<_>>>()?;
            return c.answer_all(&drives, self.dt_s, duration_s);
        }
        crate::parallel::try_map(sources, |s| self.respond(s, duration_s))
    }
}

/// A linear scene's response by convolution with its raw impulse response h, through the
/// transducers: B * (h * (B * s)).
pub(super) fn convolved(
    scene: &Scene,
    h: &Response,
    s: Signal,
    dt_s: f64,
    duration_s: f64,
) -> Result<Response> {
    let n = samples_within(&h.traces[0], dt_s, duration_s)?;
    let transducer = scene.spec.transducer.as_ref();
    let traction = match transducer {
        Some(t) => t.transmit(&s, duration_s)?,
        None => s,
    };
    let traces = h
        .traces
        .iter()
        .map(|h| {
            let raw = truncate(signal::convolve_discrete(&traction, h)?, n);
            match transducer {
                Some(t) => t.receive(&raw),
                None => Ok(raw),
            }
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Response {
        traces,
        report: None,
    })
}

/// The number of samples of `duration_s` on step `dt_s`, refused when the impulse response
/// `h` is shorter.
fn samples_within(h: &Signal, dt_s: f64, duration_s: f64) -> Result<usize> {
    let n = (duration_s / dt_s).round() as usize;
    if n > h.len() {
        return Err(Error::invalid(
            "duration_s",
            duration_s,
            format!(
                "exceeds the impulse response length {:.4e} s",
                h.duration_s()
            ),
        ));
    }
    Ok(n)
}

/// Checks that every recording has as many traces as the first and that every trace is on
/// step `dt_s` (the drives' step is checked by the caller).
fn same_receivers_and_step(recordings: &[Recording], dt_s: f64) -> Result<()> {
    let Some(first) = recordings.first() else {
        return Ok(());
    };
    let receivers = first.received.len();
    for (i, r) in recordings.iter().enumerate() {
        let what = format!("recordings[{i}].received");
        if r.received.len() != receivers {
            return Err(Error::invalid(
                &what,
                format!("{} traces", r.received.len()),
                format!("recordings[0] has {receivers}"),
            ));
        }
        let step = common_step(&r.received, &what)?;
        if (step / dt_s - 1.0).abs() > 1e-9 {
            return Err(Error::invalid(
                format!("{what}[0].dt"),
                step,
                format!("differs from the drives' step {dt_s}"),
            ));
        }
    }
    Ok(())
}

impl RecordedChannel {
    /// The recording whose drive is `s`: same length, relative L2 difference at most
    /// [`RecordedChannel::MATCH`].
    fn find(&self, s: &Signal) -> Option<&Recording> {
        self.recordings.iter().find(|r| {
            r.sent.len() == s.len()
                && signal::relative_l2(&r.sent, s, None).is_ok_and(|d| d <= Self::MATCH)
        })
    }

    /// The recordings of `drives` (on step `dt_s`) over `duration_s`. A drive without one is
    /// refused, naming it; on a lab channel every such drive of the batch is listed to record
    /// and the batch stops with the list's error.
    fn answer_all(&self, drives: &[Signal], dt_s: f64, duration_s: f64) -> Result<Vec<Response>> {
        let found: Vec<Option<&Recording>> = drives.iter().map(|s| self.find(s)).collect();
        let missing: Vec<&Signal> = drives
            .iter()
            .zip(&found)
            .filter(|(_, r)| r.is_none())
            .map(|(s, _)| s)
            .collect();
        if let Some(first) = missing.first() {
            let Some(list) = &self.to_record else {
                return Err(self.not_recorded(first));
            };
            for s in &missing {
                list.want(s, duration_s);
            }
            return Err(list.stop());
        }
        found
            .into_iter()
            .flatten()
            .map(|r| recorded(r, dt_s, duration_s))
            .collect()
    }

    /// The error for drive `s`, not recorded (with its peak and length, to find it among the
    /// files).
    fn not_recorded(&self, s: &Signal) -> Error {
        Error::invalid(
            "transmission",
            format!("{} samples, peak {:.6e}", s.len(), s.max_abs()),
            format!(
                "was not recorded: none of the {} recordings sent this drive (relative L2 \
                 difference <= {:e}); send it, record the receivers and add the recording",
                self.recordings.len(),
                Self::MATCH
            ),
        )
    }
}

/// The recording `r` over `duration_s`, or an error when it is shorter.
pub(super) fn recorded(r: &Recording, dt_s: f64, duration_s: f64) -> Result<Response> {
    let n = (duration_s / dt_s).round() as usize;
    if let Some(short) = r.received.iter().find(|t| t.len() < n) {
        return Err(Error::invalid(
            "duration_s",
            duration_s,
            format!(
                "exceeds the recording of this drive ({:.4e} s)",
                short.duration_s()
            ),
        ));
    }
    Ok(Response {
        traces: r.received.iter().map(|t| truncate(t.clone(), n)).collect(),
        report: None,
    })
}

/// The first n samples on the grid starting at t = 0 (zero-padded if shorter).
pub(super) fn truncate(s: Signal, n: usize) -> Signal {
    let offset = (s.t0_s / s.dt_s).round() as i64;
    let samples = (0..n as i64)
        .map(|k| {
            usize::try_from(k - offset)
                .ok()
                .and_then(|i| s.samples.get(i))
                .copied()
                .unwrap_or(0.0)
        })
        .collect();
    Signal {
        dt_s: s.dt_s,
        t0_s: 0.0,
        samples,
    }
}

/// The list of drives to record of a lab channel, `None` for any other responder.
pub(super) fn to_record_of(r: &Responder) -> Option<&Arc<ToRecord>> {
    match r.channel() {
        Channel::Recorded(c) => c.to_record.as_ref(),
        _ => None,
    }
}

/// A lab channel: the recordings of lab directory `dir` beneath `root` on step `dt_s`
/// ([`crate::lab`]), answering every recorded drive and listing the others under `out_dir`
/// (see [`ToRecord`]).
#[cfg(feature = "io")]
pub fn lab_channel(
    root: &InputRoot,
    dir: &str,
    dt_s: f64,
    peak_drive: f64,
    band: String,
    out: (&Path, Option<OutputRoot>),
) -> Result<Responder> {
    crate::error::require_positive("dt_s", dt_s)?;
    let recordings = read_lab(root, dir, dt_s)?;
    let shown = root.path().join(dir).display().to_string();
    let to_record = Arc::new(ToRecord::new(out.0, out.1, &shown)?);
    Responder::from_lab(recordings, dt_s, peak_drive, band, to_record)
}
