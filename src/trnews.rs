//! The TR-NEWS procedure (report Sec. 3, eqs 6-9), delayed TR-NEWS (eqs 10-11) and pulse
//! inversion (Sec. 5.3) on a [`Channel`]: a simulated [`Scene`], a measured impulse response
//! or recorded responses. The procedures only ask a [`Responder`] for the receivers' traces
//! of a drive signal, so lab data and simulations go through the same code.
//!
//! A scene without a contacting crack is linear and time-invariant in discrete time: its
//! response to any transmitted traction s is exactly y_n = sum_k s_k h_{n-k}, with h the
//! response to a unit impulse at step 0. A [`Responder`] for such a scene runs
//! that one simulation and answers every later transmission by convolution; for a cracked
//! scene it simulates each transmission, in parallel when there are several.
//!
//! Every transmission goes through the scene's transducers (see [`crate::transducer`]): the
//! drive signal s becomes the traction B * s and each receiver records B * its raw quantity,
//! so every measure below (focus, side lobes, PI, delayed misfit) is in the transducer band.
//! For a linear scene B * (h * (B * s)) is formed from the raw impulse response h.

use crate::accuracy::{Estimate, Refinement};
use crate::error::{require_positive, Error, Result};
use crate::scene::{Resolution, Scene};
use crate::signal::{self, ChirpSpec, Peak, SideLobes, Signal};
use crate::solve::RunReport;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

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
/// holds companions on the same scene with 2x and 4x the element sizes, and every procedure
/// below repeats itself on them and reports Richardson estimates of its results (see
/// [`crate::accuracy`]).
#[derive(Clone, Debug)]
pub struct Responder {
    channel: Channel,
    dt_s: f64,
    /// Companions with 2x and 4x the element sizes; empty without an error estimate.
    companions: Vec<Responder>,
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

/// One recorded transmission: the drive sent and what every receiver recorded.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The drive signal sent.
    pub sent: Signal,
    /// One trace per receiver, from t = 0 on the drive's step.
    pub received: Vec<Signal>,
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
fn expect_traces(
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
            let unit = Signal {
                dt_s,
                t0_s: 0.0,
                samples: vec![1.0],
            };
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
                    let out = scene.apply_traction(&unit, &config)?;
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
    /// triangles 2x and 4x the element sizes, on spectral elements one and two orders lower),
    /// each with its own stable step, and their run time relative to this responder's from
    /// DOFs x steps, sum over companions of (DOFs_c / DOFs) (dt / dt_c). On triangles about
    /// 1/8 + 1/64 where every layer coarsens, more where thin layers keep one element row or
    /// set the step; on the order-7 spectral elements of the presets about 0.95. Building
    /// them runs no simulation.
    pub fn companion_scenes(&self) -> Result<(Vec<Arc<Scene>>, f64)> {
        let scene = self.scene()?;
        let scenes = scene
            .spec
            .companions()?
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

    /// The companions of the error estimate (2h, 4h), empty without one.
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
fn convolved(
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
fn recorded(r: &Recording, dt_s: f64, duration_s: f64) -> Result<Response> {
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
fn truncate(s: Signal, n: usize) -> Signal {
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

/// Parameters of the TR-NEWS procedure (report Sec. 3 and 5.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrNewsSpec {
    /// The transmitted chirp (report: 0.2 -> 2 MHz over 30 us in 60 us), at the transmitter's
    /// peak traction.
    pub chirp: ChirpSpec,
    /// Duration T of the recorded coda response y (s).
    pub record_s: f64,
    /// Lag window [0, window_s] of the correlation Gamma; the time-reversed Gamma focuses at
    /// t = window_s (s).
    pub window_s: f64,
    /// Recording time after the focus in the focusing runs (s).
    pub after_focus_s: f64,
    /// Receivers to focus on, 1-based; empty = all.
    pub receivers: Vec<usize>,
    /// Also transmit the inverted focusing signal and form the pulse-inversion sum.
    pub pulse_inversion: bool,
    /// Half width of the main lobe for the side-lobe measures (s).
    pub main_lobe_half_width_s: f64,
}

impl Default for TrNewsSpec {
    fn default() -> Self {
        TrNewsSpec {
            chirp: ChirpSpec::default(),
            record_s: 60e-6,
            window_s: 60e-6,
            after_focus_s: 30e-6,
            receivers: vec![],
            pulse_inversion: false,
            main_lobe_half_width_s: 1e-6,
        }
    }
}

/// TR-NEWS focusing at one receiver.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Focus {
    /// Receiver number (1-based).
    pub receiver: usize,
    /// Gamma(tau) = sum_n y(t_n + tau) c(t_n) dt over the lag window (eq 8 as a correlation).
    pub gamma: Signal,
    /// The transmitted focusing signal Gamma(T - t), scaled to the transmitter's peak traction.
    pub source: Signal,
    /// The focused signal y_TR at the receiver.
    pub focused: Signal,
    /// Peak of the focused signal.
    pub peak: Peak,
    /// Side lobes around the expected focus time (window_s).
    pub side_lobes: SideLobes,
    /// Response to the inverted source, with pulse inversion.
    pub inverted: Option<Signal>,
    /// Pulse-inversion sum focused + inverted (the nonlinear even part).
    pub pi_sum: Option<Signal>,
    /// Reports of the focusing runs (empty when convolved).
    pub reports: Vec<RunReport>,
    /// Discretisation error estimates, when the responder has companions.
    pub estimates: Option<FocusEstimates>,
}

/// Richardson estimates of the headline quantities of a focus (see [`crate::accuracy`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FocusEstimates {
    /// First-pass response y at this receiver over the record (relative L2).
    pub response: Estimate,
    /// Focused signal y_TR over the focus window window_s +- after_focus_s (relative L2).
    pub focused: Estimate,
    /// Focus peak amplitude.
    pub peak_amplitude: Estimate,
    /// Focus peak time (s).
    pub peak_time_s: Estimate,
    /// Side-lobe energy asymmetry.
    pub side_lobe_asymmetry: Estimate,
    /// Main-to-side-lobe ratio (dB).
    pub main_to_side_db: Estimate,
    /// Pulse-inversion residual max|PI| / max|y_TR|, with pulse inversion.
    pub pi_residual: Option<Estimate>,
}

impl Focus {
    /// Pulse-inversion residual max|PI sum| / max|y_TR|, with pulse inversion.
    pub fn pi_residual(&self) -> Option<f64> {
        self.pi_sum
            .as_ref()
            .map(|pi| pi.max_abs() / self.focused.max_abs())
    }
}

/// The result of the TR-NEWS procedure.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrNews {
    /// The parameters used.
    pub spec: TrNewsSpec,
    /// The transmitted chirp c(t) (Pa).
    pub chirp: Signal,
    /// First-pass responses y at every receiver.
    pub responses: Vec<Signal>,
    /// Focusing per requested receiver.
    pub focus: Vec<Focus>,
    /// Report of the chirp run (None when convolved).
    pub chirp_report: Option<RunReport>,
    /// The same procedure on the error estimate's companions (2h, 4h), if any; a companion
    /// has none of its own.
    #[serde(deserialize_with = "companions_one_level")]
    pub companions: Vec<TrNews>,
    /// The transducer band every signal was seen through ("no band (raw)" without one).
    pub band: String,
}

/// Decodes [`TrNews::companions`], refusing companions inside a companion. `TrNews` is the
/// only stored type that contains itself: without this, a forged point file nesting
/// companions a million deep would overflow the stack while it is decoded.
fn companions_one_level<'de, D: serde::Deserializer<'de>>(
    decoder: D,
) -> std::result::Result<Vec<TrNews>, D::Error> {
    thread_local! {
        static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    /// An element that cannot be decoded: a companion's companions must be empty.
    struct Refused;
    impl<'de> Deserialize<'de> for Refused {
        fn deserialize<D: serde::Deserializer<'de>>(_: D) -> std::result::Result<Self, D::Error> {
            Err(serde::de::Error::custom(
                "a companion holds companions of its own",
            ))
        }
    }
    if INSIDE.with(|i| i.get()) {
        return Vec::<Refused>::deserialize(decoder).map(|_| Vec::new());
    }
    struct Leave;
    impl Drop for Leave {
        fn drop(&mut self) {
            INSIDE.with(|i| i.set(false));
        }
    }
    INSIDE.with(|i| i.set(true));
    let _leave = Leave;
    Vec::<TrNews>::deserialize(decoder)
}

impl TrNewsSpec {
    /// Shorter signals for the `smoke` scene: a 10 us chirp in 15 us, 20 us records and window.
    pub fn smoke() -> TrNewsSpec {
        TrNewsSpec {
            chirp: ChirpSpec {
                t1_s: 10e-6,
                total_s: 15e-6,
                ..ChirpSpec::default()
            },
            record_s: 20e-6,
            window_s: 20e-6,
            after_focus_s: 10e-6,
            ..Default::default()
        }
    }

    /// The timings that go with a resolution preset: short signals for `smoke`, the
    /// report's otherwise (the mesh changes with the resolution, the experiment does not).
    pub fn preset(resolution: Resolution) -> TrNewsSpec {
        match resolution {
            Resolution::Smoke => Self::smoke(),
            Resolution::Quick | Resolution::Paper => Self::default(),
        }
    }

    /// Duration of a focusing run: the lag window plus the recording after the focus (s).
    pub fn focus_duration_s(&self) -> f64 {
        self.window_s + self.after_focus_s
    }
}

/// Runs TR-NEWS: chirp -> y -> Gamma = xcorr(y, c) -> Gamma(T - t) -> y_TR (eqs 6-9), and
/// on the responder's companions, with the error estimates of every focus. This first pass
/// of a sweep is stored with its points (see [`crate::sweep::first_pass`]).
pub fn tr_news(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let inputs = (responder.identity()?, spec);
    let expect = |tr: &TrNews| expect_tr_news(tr, responder, spec);
    crate::sweep::first_pass("tr_news", "TR-NEWS first pass", &inputs, &expect, || {
        tr_news_computed(responder, spec)
    })
}

/// Why a stored first pass cannot be `responder`'s TR-NEWS of `spec`: another spec, a
/// response per receiver missing, a focus at a receiver that does not exist, pulse inversion
/// where none was asked (or none where it was), companions other than the responder's.
fn expect_tr_news(
    tr: &TrNews,
    responder: &Responder,
    spec: &TrNewsSpec,
) -> std::result::Result<(), String> {
    if tr.spec != *spec {
        return Err("is the first pass of another TR-NEWS spec".into());
    }
    let n = responder.receiver_count();
    expect_traces(&tr.responses, n, responder.dt_s)?;
    let wanted = if spec.receivers.is_empty() {
        n
    } else {
        spec.receivers.len()
    };
    if tr.focus.len() != wanted {
        return Err(format!("holds {} foci, not {wanted}", tr.focus.len()));
    }
    for f in &tr.focus {
        if !(1..=n).contains(&f.receiver) {
            return Err(format!(
                "focuses at receiver {}, not within 1..{n}",
                f.receiver
            ));
        }
        if f.inverted.is_some() != spec.pulse_inversion
            || f.pi_sum.is_some() != spec.pulse_inversion
        {
            return Err(format!(
                "holds a pulse inversion at receiver {} unlike its spec",
                f.receiver
            ));
        }
    }
    if tr.companions.len() != responder.companions.len() {
        return Err(format!(
            "holds {} companions, not {}",
            tr.companions.len(),
            responder.companions.len()
        ));
    }
    tr.companions
        .iter()
        .zip(&responder.companions)
        .try_for_each(|(t, r)| expect_tr_news(t, r, spec))
}

fn tr_news_computed(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let mut main = tr_news_once(responder, spec)?;
    main.companions = responder
        .companions
        .iter()
        .map(|c| tr_news_once(c, spec))
        .collect::<Result<_>>()?;
    if let [medium, coarse] = &main.companions[..] {
        let refinement = responder.refinement()?;
        let estimates = (0..main.focus.len())
            .map(|i| focus_estimates(&main, medium, coarse, i, refinement))
            .collect::<Result<Vec<_>>>()?;
        for (f, e) in main.focus.iter_mut().zip(estimates) {
            f.estimates = Some(e);
        }
    }
    Ok(main)
}

/// The estimates of focus `i` from the main run and its two companions.
fn focus_estimates(
    fine: &TrNews,
    medium: &TrNews,
    coarse: &TrNews,
    i: usize,
    refinement: Refinement,
) -> Result<FocusEstimates> {
    let f = [&fine.focus[i], &medium.focus[i], &coarse.focus[i]];
    let scalar =
        |q: &dyn Fn(&Focus) -> f64| Estimate::scalar(q(f[0]), q(f[1]), q(f[2]), refinement);
    let spec = &fine.spec;
    let r = f[0].receiver - 1;
    let focus_window = (
        spec.window_s - spec.after_focus_s,
        spec.window_s + spec.after_focus_s,
    );
    Ok(FocusEstimates {
        response: Estimate::waveform(
            &fine.responses[r],
            &medium.responses[r],
            &coarse.responses[r],
            (0.0, spec.record_s),
            refinement,
        )?,
        focused: Estimate::waveform(
            &f[0].focused,
            &f[1].focused,
            &f[2].focused,
            focus_window,
            refinement,
        )?,
        peak_amplitude: scalar(&|x| x.peak.amplitude),
        peak_time_s: scalar(&|x| x.peak.time_s),
        side_lobe_asymmetry: Estimate::dimensionless(
            f[0].side_lobes.asymmetry,
            f[1].side_lobes.asymmetry,
            f[2].side_lobes.asymmetry,
            refinement,
        ),
        main_to_side_db: scalar(&|x| x.side_lobes.main_to_side_db),
        pi_residual: match f.map(Focus::pi_residual) {
            [Some(a), Some(b), Some(c)] => Some(Estimate::dimensionless(a, b, c, refinement)),
            _ => None,
        },
    })
}

/// `e` with the internal parameter names of the signal and run functions replaced by the
/// TR-NEWS spec's (`tr_news.<field>`), so that the message names the field the user wrote.
fn spec_field(e: Error, names: &[(&str, &str)]) -> Error {
    let mut text = e.to_string();
    for (internal, field) in names {
        text = text.replace(internal, &format!("tr_news.{field}"));
    }
    match e {
        Error::InvalidInput { .. } | Error::Signal(_) | Error::TooLarge { .. } => {
            Error::Named(text)
        }
        other => other,
    }
}

fn tr_news_once(responder: &Responder, spec: &TrNewsSpec) -> Result<TrNews> {
    let peak_pa = responder.peak_drive();
    let chirp = spec.chirp.signal(responder.dt_s, peak_pa).map_err(|e| {
        spec_field(
            e.into(),
            &[("t1_s", "chirp.t1_s"), ("total_s", "chirp.total_s")],
        )
    })?;
    let first = responder
        .respond(&chirp, spec.record_s)
        .map_err(|e| spec_field(e, &[("duration_s", "record_s")]))?;
    let n_receivers = first.traces.len();
    let receivers: Vec<usize> = if spec.receivers.is_empty() {
        (1..=n_receivers).collect()
    } else {
        spec.receivers.clone()
    };
    if let Some(&bad) = receivers.iter().find(|&&r| r == 0 || r > n_receivers) {
        return Err(Error::invalid(
            "tr_news.receivers",
            bad,
            format!("receivers are numbered 1..{n_receivers}"),
        ));
    }
    let mut sources = Vec::with_capacity(receivers.len());
    let mut gammas = Vec::with_capacity(receivers.len());
    for &r in &receivers {
        let gamma = signal::xcorr(&first.traces[r - 1], &chirp, 0.0, spec.window_s)?;
        let reversed = signal::time_reverse_to_start(&gamma)?;
        let max = reversed.max_abs();
        if !(max > 0.0) {
            return Err(Error::invalid(
                "tr_news",
                format!("receiver {r}"),
                "recorded nothing: the correlation is zero",
            ));
        }
        sources.push(reversed.scale(peak_pa / max)?);
        gammas.push(gamma);
    }
    let mut transmissions = sources.clone();
    if spec.pulse_inversion {
        transmissions.extend(
            sources
                .iter()
                .map(|s| s.scale(-1.0))
                .collect::<std::result::Result<Vec<_>, _>>()?,
        );
    }
    let responses = responder
        .respond_all(&transmissions, spec.focus_duration_s())
        .map_err(|e| spec_field(e, &[("duration_s", "window_s (its focusing run)")]))?;
    let focus = receivers
        .iter()
        .enumerate()
        .map(|(k, &r)| {
            let positive = &responses[k];
            let negative = spec
                .pulse_inversion
                .then(|| &responses[k + receivers.len()]);
            focus_at(
                spec,
                r,
                gammas[k].clone(),
                sources[k].clone(),
                positive,
                negative,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(TrNews {
        spec: spec.clone(),
        chirp,
        responses: first.traces,
        focus,
        chirp_report: first.report,
        companions: Vec::new(),
        band: responder.band(),
    })
}

fn focus_at(
    spec: &TrNewsSpec,
    r: usize,
    gamma: Signal,
    source: Signal,
    positive: &Response,
    negative: Option<&Response>,
) -> Result<Focus> {
    let focused = positive.traces[r - 1].clone();
    let peak = signal::peak(&focused)?;
    let side_lobes = signal::side_lobes(&focused, spec.window_s, spec.main_lobe_half_width_s)?;
    let inverted = negative.map(|n| n.traces[r - 1].clone());
    let pi_sum = inverted.as_ref().map(|i| focused.add(i)).transpose()?;
    let reports = positive
        .report
        .iter()
        .chain(negative.and_then(|n| n.report.as_ref()))
        .cloned()
        .collect();
    Ok(Focus {
        receiver: r,
        gamma,
        source,
        focused,
        peak,
        side_lobes,
        inverted,
        pi_sum,
        reports,
        estimates: None,
    })
}

/// Delayed TR-NEWS at one point (eqs 10-11): simulation of the composite source
/// sum_i a_i s(t - tau_i) against the linear prediction sum_i a_i y_TR(t - tau_i).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Delayed {
    /// Delays tau_i (s).
    pub delays_s: Vec<f64>,
    /// Amplitudes a_i.
    pub amplitudes: Vec<f64>,
    /// The linear prediction at the focusing receiver.
    pub prediction: Signal,
    /// The simulated (or, for a linear scene, convolved) response.
    pub simulation: Signal,
    /// Relative L2 misfit ||sim - pred|| / ||pred|| over the focus window.
    pub misfit: f64,
    /// (max |sim| - max |pred|) / max |pred| over the focus window.
    pub peak_difference: f64,
    /// The window [t0, t1] the misfit is measured over (s).
    pub window_s: (f64, f64),
    /// The run report (None when convolved).
    pub report: Option<RunReport>,
    /// Discretisation error estimates, when the responder has companions.
    pub estimates: Option<DelayedEstimates>,
}

/// Richardson estimates of a delayed TR-NEWS point (see [`crate::accuracy`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DelayedEstimates {
    /// The misfit.
    pub misfit: Estimate,
    /// The peak difference.
    pub peak_difference: Estimate,
    /// The simulated trace over the misfit window (relative L2).
    pub simulation: Estimate,
}

/// Delayed TR-NEWS for several (delays, amplitudes) points, simulated in parallel, and on
/// the responder's companions (each with its own focusing signal), with error estimates.
pub fn delayed_tr_news(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
) -> Result<Vec<Delayed>> {
    let max_delay_s = points
        .iter()
        .flat_map(|p| p.0.iter())
        .fold(0.0f64, |m, d| m.max(*d));
    delayed_tr_news_within(responder, tr, focus, points, half_window_s, max_delay_s)
}

/// [`delayed_tr_news`] for some points of a sweep whose largest delay is `max_delay_s`: every
/// response runs over the focus duration plus that delay, as in the whole sweep, so a point
/// computed alone is bit-identical to the same point computed with all the others.
pub fn delayed_tr_news_within(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
) -> Result<Vec<Delayed>> {
    let mut main = delayed_once(responder, tr, focus, points, half_window_s, max_delay_s)?;
    let ([rm, rc], [tm, tc]) = (&responder.companions[..], &tr.companions[..]) else {
        return Ok(main);
    };
    let on = |r: &Responder, t: &TrNews| -> Result<Vec<Delayed>> {
        let f = t
            .focus
            .iter()
            .find(|f| f.receiver == focus.receiver)
            .ok_or_else(|| Error::invalid("receiver", focus.receiver, "has no companion focus"))?;
        delayed_once(r, t, f, points, half_window_s, max_delay_s)
    };
    let (medium, coarse) = (on(rm, tm)?, on(rc, tc)?);
    let refinement = responder.refinement()?;
    for ((d, m), c) in main.iter_mut().zip(&medium).zip(&coarse) {
        d.estimates = Some(DelayedEstimates {
            misfit: Estimate::dimensionless(d.misfit, m.misfit, c.misfit, refinement),
            peak_difference: Estimate::dimensionless(
                d.peak_difference,
                m.peak_difference,
                c.peak_difference,
                refinement,
            ),
            simulation: Estimate::waveform(
                &d.simulation,
                &m.simulation,
                &c.simulation,
                d.window_s,
                refinement,
            )?,
        });
    }
    Ok(main)
}

/// Delayed TR-NEWS for several (delays, amplitudes) points, simulated in parallel.
/// Delays are rounded to whole solver steps (at most dt/2, a few ns, off), so that source
/// and prediction are shifted exactly and a linear scene's misfit is round-off. The misfit
/// window spans the focus times window_s + tau_i, widened by `half_window_s`. Responses run
/// over the focus duration plus `max_delay_s` rounded to a whole step (rounding is monotone,
/// so that is the largest rounded delay of the sweep).
fn delayed_once(
    responder: &Responder,
    tr: &TrNews,
    focus: &Focus,
    points: &[(Vec<f64>, Vec<f64>)],
    half_window_s: f64,
    max_delay_s: f64,
) -> Result<Vec<Delayed>> {
    let dt = responder.dt_s();
    let points: Vec<(Vec<f64>, Vec<f64>)> = points
        .iter()
        .map(|(d, a)| (d.iter().map(|t| (t / dt).round() * dt).collect(), a.clone()))
        .collect();
    let mut sources = Vec::with_capacity(points.len());
    for (delays, amplitudes) in &points {
        if let Some(&bad) = delays.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
            return Err(Error::invalid(
                "delays_s",
                bad,
                "delays must be finite and >= 0",
            ));
        }
        sources.push(signal::delay_and_sum(&focus.source, delays, amplitudes)?);
    }
    let duration = tr.spec.focus_duration_s() + (max_delay_s / dt).round() * dt;
    let responses = responder.respond_all(&sources, duration)?;
    points
        .iter()
        .zip(responses)
        .map(|((delays, amplitudes), response)| {
            let simulation = response.traces[focus.receiver - 1].clone();
            let prediction = truncate(
                signal::delay_and_sum(&focus.focused, delays, amplitudes)?,
                simulation.len(),
            );
            let last = delays.iter().fold(0.0f64, |m, d| m.max(*d));
            let first = delays.iter().fold(f64::INFINITY, |m, d| m.min(*d));
            let window = (
                tr.spec.window_s + first - half_window_s,
                (tr.spec.window_s + last + half_window_s).min(simulation.t_end_s()),
            );
            let misfit = signal::relative_l2(&simulation, &prediction, Some(window))?;
            let peak_of =
                |s: &Signal| -> Result<f64> { Ok(s.window(window.0, window.1)?.max_abs()) };
            let p = peak_of(&prediction)?;
            let peak_difference = (peak_of(&simulation)? - p) / p;
            Ok(Delayed {
                delays_s: delays.clone(),
                amplitudes: amplitudes.clone(),
                prediction,
                simulation,
                misfit,
                peak_difference,
                window_s: window,
                report: response.report,
                estimates: None,
            })
        })
        .collect()
}

/// Pulse inversion of any transmission: responses to +s and -s and their sum per receiver.
#[derive(Clone, Debug)]
pub struct PulseInversion {
    /// Responses to +s.
    pub positive: Vec<Signal>,
    /// Responses to -s.
    pub negative: Vec<Signal>,
    /// positive + negative: zero (to round-off) for a linear scene.
    pub sum: Vec<Signal>,
    /// Reports of the two runs (empty when convolved).
    pub reports: Vec<RunReport>,
    /// Per receiver, the estimate of the residual max|sum| / max|positive|, when the
    /// responder has companions.
    pub residual_estimates: Option<Vec<Estimate>>,
}

impl PulseInversion {
    /// Per receiver, the residual max|sum| / max|positive|.
    pub fn residuals(&self) -> Vec<f64> {
        self.sum
            .iter()
            .zip(&self.positive)
            .map(|(s, p)| s.max_abs() / p.max_abs())
            .collect()
    }
}

/// Transmits +s and -s (in parallel) and sums the responses (report Sec. 5.3), also on the
/// responder's companions, with estimates of the residuals.
pub fn pulse_inversion(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let mut main = pulse_inversion_once(responder, s, duration_s)?;
    if let [medium, coarse] = &responder.companions[..] {
        let fine = main.residuals();
        let m = pulse_inversion_once(medium, s, duration_s)?.residuals();
        let c = pulse_inversion_once(coarse, s, duration_s)?.residuals();
        let refinement = responder.refinement()?;
        main.residual_estimates = Some(
            (0..fine.len())
                .map(|k| Estimate::dimensionless(fine[k], m[k], c[k], refinement))
                .collect(),
        );
    }
    Ok(main)
}

fn pulse_inversion_once(
    responder: &Responder,
    s: &Signal,
    duration_s: f64,
) -> Result<PulseInversion> {
    let pair = responder.respond_all(&[s.clone(), s.scale(-1.0)?], duration_s)?;
    let sum = pair[0]
        .traces
        .iter()
        .zip(&pair[1].traces)
        .map(|(a, b)| a.add(b))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let reports = pair.iter().filter_map(|r| r.report.clone()).collect();
    let mut it = pair.into_iter();
    let (p, n) = (it.next().unwrap(), it.next().unwrap());
    Ok(PulseInversion {
        positive: p.traces,
        negative: n.traces,
        sum,
        reports,
        residual_estimates: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(companions: Vec<TrNews>) -> TrNews {
        TrNews {
            spec: TrNewsSpec::default(),
            chirp: Signal::new(1e-8, 0.0, vec![0.0, 1.0]).unwrap(),
            responses: Vec::new(),
            focus: Vec::new(),
            chirp_report: None,
            companions,
            band: String::new(),
        }
    }

    /// A forged first pass nesting companions a million deep is refused at the second level,
    /// never a stack overflow: TrNews is the only stored type that contains itself.
    #[test]
    fn stored_companions_nest_one_level_only() {
        let flat = crate::sweep::encode(&pass(vec![pass(vec![]), pass(vec![])])).unwrap();
        let back: TrNews = crate::sweep::decode(&flat).unwrap();
        assert_eq!(back.companions.len(), 2);
        // encode(pass(no companions)) = head, 0 (no companions), 0 (empty band).
        let one = crate::sweep::encode(&pass(vec![])).unwrap();
        let head = &one[..one.len() - 2];
        let depth = 1_000_000;
        let mut forged = Vec::with_capacity((head.len() + 2) * (depth + 1));
        for _ in 0..depth {
            forged.extend_from_slice(head);
            forged.push(1);
        }
        forged.extend_from_slice(&one);
        forged.extend(std::iter::repeat_n(0, depth));
        // (postcard drops the message of a refusal: the error only says it did not decode)
        let e = crate::sweep::decode::<TrNews>(&forged)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot decode a point"), "{e}");
        // A companion's empty list of companions still decodes after a refusal.
        assert!(crate::sweep::decode::<TrNews>(&flat).is_ok());
    }

    /// A stored first pass is checked against what the responder computes before it is used:
    /// a focus at a receiver the channel does not have (which would index past its traces),
    /// a trace missing, another spec, pulse inversion unlike the spec.
    #[test]
    fn forged_first_passes_fail_their_expectations() {
        let h = |k: usize| {
            let mut x = vec![0.0; 3000];
            x[100 + 40 * k] = 1.0;
            Signal::new(1e-8, 0.0, x).unwrap()
        };
        let r = Responder::from_impulse(vec![h(0), h(1)], 1.0, "test".into()).unwrap();
        let spec = TrNewsSpec {
            record_s: 10e-6,
            window_s: 10e-6,
            after_focus_s: 5e-6,
            chirp: crate::signal::ChirpSpec {
                t1_s: 5e-6,
                total_s: 8e-6,
                ..Default::default()
            },
            ..Default::default()
        };
        let tr = tr_news_computed(&r, &spec).unwrap();
        assert_eq!(expect_tr_news(&tr, &r, &spec), Ok(()));
        let forged = |change: &dyn Fn(&mut TrNews)| {
            let mut t = tr.clone();
            change(&mut t);
            expect_tr_news(&t, &r, &spec).unwrap_err()
        };
        assert!(forged(&|t| t.focus[1].receiver = 9).contains("receiver 9, not within 1..2"));
        assert!(forged(&|t| {
            t.responses.pop();
        })
        .contains("1 traces for 2 receivers"));
        assert!(forged(&|t| t.spec.record_s = 1.0).contains("another TR-NEWS spec"));
        assert!(forged(&|t| t.focus[0].pi_sum = Some(h(0))).contains("pulse inversion"));
        assert!(forged(&|t| t.companions.push(tr.clone())).contains("1 companions, not 0"));
    }
}
