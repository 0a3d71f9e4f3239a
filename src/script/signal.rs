//! Rhai module `signal`: the `Signal` and `Spectrum` types and the signal processing of
//! `crate::signal`. Samples stay in Rust; scripts call vectorised methods.

use crate::script::convert::{error, ScriptResult, WithPosition};
use crate::signal::{ChirpSpec, Signal, Spectrum};
use crate::signal::{FilterKind, Window};
use rhai::plugin::*;
use rhai::{Engine, Module, NativeCallContext, INT};
use serde::{Deserialize, Serialize};

/// Registers the display names of the custom types (used by `type_of` and in messages).
pub fn register_types(engine: &mut Engine) {
    engine
        .register_type_with_name::<Signal>("Signal")
        .register_type_with_name::<Spectrum>("Spectrum");
}

/// The `signal` module.
pub fn module() -> Module {
    exported_module!(signal_api)
}

/// Options of `signal::chirp(#{...})`: the chirp (the report's excitation unless given), its
/// sample step and amplitude.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
struct ChirpOptions {
    #[serde(flatten)]
    chirp: ChirpSpec,
    dt_s: f64,
    amplitude: f64,
}

impl Default for ChirpOptions {
    fn default() -> Self {
        ChirpOptions {
            chirp: ChirpSpec::default(),
            dt_s: 5e-9,
            amplitude: 1.0,
        }
    }
}

/// Designs the Butterworth filter at the signal's rate and applies it forward-backward.
fn filter(
    ctx: &NativeCallContext,
    s: &Signal,
    kind: FilterKind,
    order: INT,
) -> ScriptResult<Signal> {
    let order =
        usize::try_from(order).map_err(|_| error(ctx, format!("order = {order} must be >= 1")))?;
    let sos = crate::signal::butterworth(order, kind, 1.0 / s.dt_s).at(ctx)?;
    crate::signal::filtfilt(&sos, s).at(ctx)
}

/// The spectral window called `name`.
fn window_named(ctx: &NativeCallContext, name: &str) -> ScriptResult<Window> {
    match name {
        "rectangular" => Ok(Window::Rectangular),
        "hann" => Ok(Window::Hann),
        "hamming" => Ok(Window::Hamming),
        "blackman" => Ok(Window::Blackman),
        other => Err(error(
            ctx,
            format!("unknown window '{other}' (expected rectangular, hann, hamming or blackman)"),
        )),
    }
}

#[export_module]
mod signal_api {
    use super::{filter, window_named, ChirpOptions};
    use crate::script::convert::{
        check_script_array, error, floats, options, to_dynamic, WithPosition,
    };
    use crate::signal as sig;
    use crate::signal::{FilterKind, Window};
    use rhai::{Array, Dynamic, Map, NativeCallContext, FLOAT, INT};
    use std::result::Result;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// A uniformly sampled real signal: sample k at time t0 + k dt (s).
    pub type Signal = sig::Signal;
    /// One-sided power spectral density on frequencies k df (Hz).
    pub type Spectrum = sig::Spectrum;

    // ------------------------------------------------------------ construction

    /// Linear chirp from an options map #{f0_hz, f1_hz, t1_s, total_s, dt_s, amplitude, taper_fraction}; unset fields take the report's excitation (0.2 -> 2 MHz, 30 us in 60 us, dt 5 ns, amplitude 1, no taper).
    #[rhai_fn(return_raw)]
    pub fn chirp(ctx: NativeCallContext, opts: Map) -> Res<Signal> {
        let o: ChirpOptions = options(&ctx, opts, &ChirpOptions::default(), "chirp")?;
        o.chirp.signal(o.dt_s, o.amplitude).at(&ctx)
    }

    /// Linear chirp f0_hz -> f1_hz over t1_s inside total_s, sampled at dt_s, amplitude 1, no taper.
    #[rhai_fn(name = "chirp", return_raw)]
    pub fn chirp_positional(
        ctx: NativeCallContext,
        f0_hz: FLOAT,
        f1_hz: FLOAT,
        t1_s: FLOAT,
        total_s: FLOAT,
        dt_s: FLOAT,
    ) -> Res<Signal> {
        let chirp = sig::ChirpSpec {
            f0_hz,
            f1_hz,
            t1_s,
            total_s,
            taper_fraction: 0.0,
        };
        chirp.signal(dt_s, 1.0).at(&ctx)
    }

    /// A signal from an array of numbers: sample k at t0_s + k dt_s.
    #[rhai_fn(return_raw)]
    pub fn from_array(
        ctx: NativeCallContext,
        dt_s: FLOAT,
        t0_s: FLOAT,
        samples: Array,
    ) -> Res<Signal> {
        let x = floats(&ctx, &Dynamic::from_array(samples), "samples")?;
        Signal::new(dt_s, t0_s, x).at(&ctx)
    }

    /// n zero samples starting at t0_s with interval dt_s.
    #[rhai_fn(return_raw)]
    pub fn zeros(ctx: NativeCallContext, dt_s: FLOAT, t0_s: FLOAT, n: INT) -> Res<Signal> {
        let n = usize::try_from(n).map_err(|_| error(&ctx, format!("n = {n} must be >= 0")))?;
        Signal::zeros(dt_s, t0_s, n).at(&ctx)
    }

    // ------------------------------------------------------------ properties

    /// Sample interval dt (s).
    #[rhai_fn(global, get = "dt", pure)]
    pub fn dt(s: &mut Signal) -> FLOAT {
        s.dt_s
    }

    /// Time of the first sample t0 (s).
    #[rhai_fn(global, get = "t0", pure)]
    pub fn t0(s: &mut Signal) -> FLOAT {
        s.t0_s
    }

    /// Time of the last sample t0 + (n-1) dt (s).
    #[rhai_fn(global, get = "t_end", pure)]
    pub fn t_end(s: &mut Signal) -> FLOAT {
        s.t_end_s()
    }

    /// Number of samples.
    #[rhai_fn(global, get = "len", pure)]
    pub fn len(s: &mut Signal) -> INT {
        s.len() as INT
    }

    /// Number of samples (method form of the `len` property).
    #[rhai_fn(global, name = "len", pure)]
    pub fn len_method(s: &mut Signal) -> INT {
        s.len() as INT
    }

    /// Duration n dt (s).
    #[rhai_fn(global, get = "duration", pure)]
    pub fn duration(s: &mut Signal) -> FLOAT {
        s.duration_s()
    }

    /// Largest absolute sample max |x_k|.
    #[rhai_fn(global, pure)]
    pub fn max_abs(s: &mut Signal) -> FLOAT {
        s.max_abs()
    }

    /// Root mean square sqrt(sum x_k^2 / n).
    #[rhai_fn(global, pure)]
    pub fn rms(s: &mut Signal) -> FLOAT {
        s.rms()
    }

    /// Energy sum x_k^2 dt.
    #[rhai_fn(global, pure)]
    pub fn energy(s: &mut Signal) -> FLOAT {
        s.energy()
    }

    /// Copy of the samples as a Rhai array (explicit copy: prefer Signal methods); refused above the memory limit.
    #[rhai_fn(global, pure, return_raw)]
    pub fn samples(ctx: NativeCallContext, s: &mut Signal) -> Res<Array> {
        let n = s.len();
        check_script_array(&ctx, "samples", format!("{n} samples"), 0, n)?;
        Ok(s.samples.iter().map(|&x| Dynamic::from_float(x)).collect())
    }

    /// Copy of the sample times t0 + k dt (s) as a Rhai array; refused above the memory limit.
    #[rhai_fn(global, pure, return_raw)]
    pub fn times(ctx: NativeCallContext, s: &mut Signal) -> Res<Array> {
        let n = s.len();
        check_script_array(&ctx, "times", format!("{n} samples"), 0, n)?;
        Ok(s.times().into_iter().map(Dynamic::from_float).collect())
    }

    /// Linearly interpolated value at time t_s (0 outside the samples).
    #[rhai_fn(global, pure, return_raw)]
    pub fn sample_at(ctx: NativeCallContext, s: &mut Signal, t_s: FLOAT) -> Res<FLOAT> {
        s.sample_at(t_s).at(&ctx)
    }

    /// Short description: length, dt and t0.
    #[rhai_fn(global, name = "to_string", name = "to_debug", pure)]
    pub fn describe(s: &mut Signal) -> String {
        format!(
            "Signal(n = {}, dt = {:e} s, t0 = {:e} s)",
            s.len(),
            s.dt_s,
            s.t0_s
        )
    }

    // ------------------------------------------------------------ arithmetic

    /// a * x(t).
    #[rhai_fn(global, pure, return_raw)]
    pub fn scale(ctx: NativeCallContext, s: &mut Signal, a: FLOAT) -> Res<Signal> {
        s.scale(a).at(&ctx)
    }

    /// x(t) + y(t) on the union of both time ranges (grids must align).
    #[rhai_fn(global, pure, return_raw)]
    pub fn add(ctx: NativeCallContext, s: &mut Signal, other: Signal) -> Res<Signal> {
        s.add(&other).at(&ctx)
    }

    /// x(t) - y(t) on the union of both time ranges (grids must align).
    #[rhai_fn(global, pure, return_raw)]
    pub fn sub(ctx: NativeCallContext, s: &mut Signal, other: Signal) -> Res<Signal> {
        s.sub(&other).at(&ctx)
    }

    /// Operator a + b: sum of two signals on aligned grids.
    #[rhai_fn(global, name = "+", return_raw)]
    pub fn op_add(ctx: NativeCallContext, a: Signal, b: Signal) -> Res<Signal> {
        a.add(&b).at(&ctx)
    }

    /// Operator a - b: difference of two signals on aligned grids.
    #[rhai_fn(global, name = "-", return_raw)]
    pub fn op_sub(ctx: NativeCallContext, a: Signal, b: Signal) -> Res<Signal> {
        a.sub(&b).at(&ctx)
    }

    /// Operator s * a: signal scaled by a float.
    #[rhai_fn(global, name = "*", return_raw)]
    pub fn op_mul(ctx: NativeCallContext, s: Signal, a: FLOAT) -> Res<Signal> {
        s.scale(a).at(&ctx)
    }

    /// Operator a * s: signal scaled by a float.
    #[rhai_fn(global, name = "*", return_raw)]
    pub fn op_mul_left(ctx: NativeCallContext, a: FLOAT, s: Signal) -> Res<Signal> {
        s.scale(a).at(&ctx)
    }

    /// Samples with t_start_s <= t <= t_end_s, on the same grid (may be empty).
    #[rhai_fn(global, pure, return_raw)]
    pub fn window(
        ctx: NativeCallContext,
        s: &mut Signal,
        t_start_s: FLOAT,
        t_end_s: FLOAT,
    ) -> Res<Signal> {
        s.window(t_start_s, t_end_s).at(&ctx)
    }

    /// Zeros appended up to n samples.
    #[rhai_fn(global, pure, return_raw)]
    pub fn pad_to(ctx: NativeCallContext, s: &mut Signal, n: INT) -> Res<Signal> {
        let n = usize::try_from(n).map_err(|_| error(&ctx, format!("n = {n} must be >= 0")))?;
        s.pad_to(n).at(&ctx)
    }

    // ------------------------------------------------------------ processing

    /// Cross-correlation of y with c (eq 8), lags lag_min_s..=lag_max_s (s).
    #[rhai_fn(global, pure, return_raw)]
    pub fn xcorr(
        ctx: NativeCallContext,
        y: &mut Signal,
        c: Signal,
        lag_min_s: FLOAT,
        lag_max_s: FLOAT,
    ) -> Res<Signal> {
        sig::xcorr(y, &c, lag_min_s, lag_max_s).at(&ctx)
    }

    /// Continuous-time convolution sum_k a_k b_(n-k) dt, t0 = a.t0 + b.t0.
    #[rhai_fn(global, pure, return_raw)]
    pub fn convolve(ctx: NativeCallContext, a: &mut Signal, b: Signal) -> Res<Signal> {
        sig::convolve(a, &b).at(&ctx)
    }

    /// Discrete convolution sum_k a_k b_(n-k) (no dt): input convolved with a unit-sample response.
    #[rhai_fn(global, pure, return_raw)]
    pub fn convolve_discrete(ctx: NativeCallContext, a: &mut Signal, b: Signal) -> Res<Signal> {
        sig::convolve_discrete(a, &b).at(&ctx)
    }

    /// s(-t): samples reversed, t0 -> -t_end.
    #[rhai_fn(global, pure, return_raw)]
    pub fn time_reverse(ctx: NativeCallContext, s: &mut Signal) -> Res<Signal> {
        sig::time_reverse(s).at(&ctx)
    }

    /// Reversed samples starting at t0 = 0: what a TR experiment transmits.
    #[rhai_fn(global, pure, return_raw)]
    pub fn time_reverse_to_start(ctx: NativeCallContext, s: &mut Signal) -> Res<Signal> {
        sig::time_reverse_to_start(s).at(&ctx)
    }

    /// s(t - tau_s), band-limited for fractional delays.
    #[rhai_fn(global, pure, return_raw)]
    pub fn delay(ctx: NativeCallContext, s: &mut Signal, tau_s: FLOAT) -> Res<Signal> {
        sig::delay(s, tau_s).at(&ctx)
    }

    /// Delay-and-sum (eq 10): sum_i amplitudes[i] s(t - delays_s[i]).
    #[rhai_fn(global, pure, return_raw)]
    pub fn delay_and_sum(
        ctx: NativeCallContext,
        s: &mut Signal,
        delays_s: Array,
        amplitudes: Array,
    ) -> Res<Signal> {
        let tau = floats(&ctx, &Dynamic::from_array(delays_s), "delays_s")?;
        let amp = floats(&ctx, &Dynamic::from_array(amplitudes), "amplitudes")?;
        sig::delay_and_sum(s, &tau, &amp).at(&ctx)
    }

    /// Band-limited resampling onto the interval new_dt_s (anti-aliased when downsampling).
    #[rhai_fn(global, pure, return_raw)]
    pub fn resample(ctx: NativeCallContext, s: &mut Signal, new_dt_s: FLOAT) -> Res<Signal> {
        sig::resample(s, new_dt_s).at(&ctx)
    }

    /// Zero-phase Butterworth low-pass (forward-backward, -6 dB at fc_hz) of the given order.
    #[rhai_fn(global, pure, return_raw)]
    pub fn lowpass(
        ctx: NativeCallContext,
        s: &mut Signal,
        fc_hz: FLOAT,
        order: INT,
    ) -> Res<Signal> {
        filter(&ctx, s, FilterKind::LowPass(fc_hz), order)
    }

    /// Zero-phase Butterworth high-pass (forward-backward, -6 dB at fc_hz) of the given order.
    #[rhai_fn(global, pure, return_raw)]
    pub fn highpass(
        ctx: NativeCallContext,
        s: &mut Signal,
        fc_hz: FLOAT,
        order: INT,
    ) -> Res<Signal> {
        filter(&ctx, s, FilterKind::HighPass(fc_hz), order)
    }

    /// Zero-phase Butterworth band-pass between f_lo_hz and f_hi_hz (forward-backward).
    #[rhai_fn(global, pure, return_raw)]
    pub fn bandpass(
        ctx: NativeCallContext,
        s: &mut Signal,
        f_lo_hz: FLOAT,
        f_hi_hz: FLOAT,
        order: INT,
    ) -> Res<Signal> {
        filter(&ctx, s, FilterKind::BandPass(f_lo_hz, f_hi_hz), order)
    }

    /// Hilbert envelope |x + i H[x]| on the grid of s.
    #[rhai_fn(global, pure, return_raw)]
    pub fn envelope(ctx: NativeCallContext, s: &mut Signal) -> Res<Signal> {
        sig::envelope(s).at(&ctx)
    }

    /// Instantaneous frequency (Hz) of the analytic signal, on the grid of s.
    #[rhai_fn(global, pure, return_raw)]
    pub fn instantaneous_frequency(ctx: NativeCallContext, s: &mut Signal) -> Res<Signal> {
        sig::instantaneous_frequency(s).at(&ctx)
    }

    // ------------------------------------------------------------ measures

    /// Peak of the signal: #{time_s, amplitude, width_6db_s}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn peak(ctx: NativeCallContext, s: &mut Signal) -> Res<Dynamic> {
        to_dynamic(&ctx, &sig::peak(s).at(&ctx)?)
    }

    /// Main lobe and side lobes around focus_s: #{main_peak, max_side_lobe_before, max_side_lobe_after, main_to_side_db, asymmetry, energy_before, energy_after, side_window_s}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn side_lobes(
        ctx: NativeCallContext,
        s: &mut Signal,
        focus_s: FLOAT,
        half_width_s: FLOAT,
    ) -> Res<Dynamic> {
        to_dynamic(&ctx, &sig::side_lobes(s, focus_s, half_width_s).at(&ctx)?)
    }

    /// Relative L2 error ||a - b|| / ||b|| on the union of both grids.
    #[rhai_fn(global, pure, return_raw)]
    pub fn relative_l2(ctx: NativeCallContext, a: &mut Signal, b: Signal) -> Res<FLOAT> {
        sig::relative_l2(a, &b, None).at(&ctx)
    }

    /// Relative L2 error ||a - b|| / ||b|| restricted to t_start_s..=t_end_s.
    #[rhai_fn(global, name = "relative_l2", pure, return_raw)]
    pub fn relative_l2_window(
        ctx: NativeCallContext,
        a: &mut Signal,
        b: Signal,
        t_start_s: FLOAT,
        t_end_s: FLOAT,
    ) -> Res<FLOAT> {
        sig::relative_l2(a, &b, Some((t_start_s, t_end_s))).at(&ctx)
    }

    // ------------------------------------------------------------ spectra

    /// The mean frequency sum f P(f) / sum P(f) of the signal's Welch spectrum (Hann segments of a quarter of the trace, half overlapping, no detrend; Hz): the measure of the crack's spectral shift that trnews scans take (a scan's spectral_shifts is the cracked first-pass response's less the uncracked one's).
    #[rhai_fn(global, pure, return_raw)]
    pub fn mean_frequency_hz(ctx: NativeCallContext, s: &mut Signal) -> Res<FLOAT> {
        crate::trnews::mean_frequency_hz(s).at(&ctx)
    }

    /// Hann-windowed periodogram of the whole signal.
    #[rhai_fn(global, pure, return_raw)]
    pub fn periodogram(ctx: NativeCallContext, s: &mut Signal) -> Res<Spectrum> {
        sig::periodogram(s, Window::Hann).at(&ctx)
    }

    /// Periodogram with a window: "rectangular", "hann", "hamming" or "blackman".
    #[rhai_fn(global, name = "periodogram", pure, return_raw)]
    pub fn periodogram_window(
        ctx: NativeCallContext,
        s: &mut Signal,
        window: &str,
    ) -> Res<Spectrum> {
        sig::periodogram(s, window_named(&ctx, window)?).at(&ctx)
    }

    /// Welch average of windowed periodograms of segment_len samples overlapping by overlap_fraction, segments used as they are (no detrend).
    #[rhai_fn(global, pure, return_raw)]
    pub fn welch(
        ctx: NativeCallContext,
        s: &mut Signal,
        segment_len: INT,
        overlap_fraction: FLOAT,
        window: &str,
    ) -> Res<Spectrum> {
        welch_detrended(ctx, s, segment_len, overlap_fraction, window, "none")
    }

    /// welch with a detrend: "constant" subtracts each segment's mean before the window (scipy.signal.welch's default), "none" keeps it.
    #[rhai_fn(global, name = "welch", pure, return_raw)]
    pub fn welch_detrended(
        ctx: NativeCallContext,
        s: &mut Signal,
        segment_len: INT,
        overlap_fraction: FLOAT,
        window: &str,
        detrend: &str,
    ) -> Res<Spectrum> {
        let n = usize::try_from(segment_len)
            .map_err(|_| error(&ctx, format!("segment_len = {segment_len} must be >= 2")))?;
        let detrend = match detrend {
            "none" => sig::Detrend::None,
            "constant" => sig::Detrend::Constant,
            other => {
                return Err(error(
                    &ctx,
                    format!("detrend = \"{other}\": expected \"none\" or \"constant\""),
                ))
            }
        };
        sig::welch(s, n, overlap_fraction, window_named(&ctx, window)?, detrend).at(&ctx)
    }

    /// Frequencies f_k = k df (Hz), copied into an array; refused above the memory limit.
    #[rhai_fn(global, get = "freqs", pure, return_raw)]
    pub fn freqs(ctx: NativeCallContext, sp: &mut Spectrum) -> Res<Array> {
        let n = sp.freqs_hz.len();
        check_script_array(&ctx, "freqs", format!("{n} frequencies"), 0, n)?;
        Ok(sp
            .freqs_hz
            .iter()
            .map(|&f| Dynamic::from_float(f))
            .collect())
    }

    /// Power spectral density (unit^2/Hz), copied into an array; refused above the memory limit.
    #[rhai_fn(global, get = "psd", pure, return_raw)]
    pub fn psd(ctx: NativeCallContext, sp: &mut Spectrum) -> Res<Array> {
        let n = sp.psd.len();
        check_script_array(&ctx, "psd", format!("{n} frequencies"), 0, n)?;
        Ok(sp.psd.iter().map(|&p| Dynamic::from_float(p)).collect())
    }

    /// Frequency resolution df (Hz).
    #[rhai_fn(global, get = "df", pure)]
    pub fn df(sp: &mut Spectrum) -> FLOAT {
        sp.df_hz
    }

    /// 10 log10(psd / reference) as an array (dB).
    #[rhai_fn(global, pure, return_raw)]
    pub fn to_db(ctx: NativeCallContext, sp: &mut Spectrum, reference: FLOAT) -> Res<Array> {
        let db = sp.to_db(reference).at(&ctx)?;
        Ok(db.into_iter().map(Dynamic::from_float).collect())
    }

    /// Mean power sum psd_k df.
    #[rhai_fn(global, pure)]
    pub fn total_power(sp: &mut Spectrum) -> FLOAT {
        sp.total_power()
    }

    /// The n strongest local maxima at least min_separation_hz apart: array of #{f_hz, value}.
    #[rhai_fn(global, pure, return_raw)]
    pub fn peaks(
        ctx: NativeCallContext,
        sp: &mut Spectrum,
        n: INT,
        min_separation_hz: FLOAT,
    ) -> Res<Array> {
        let n = usize::try_from(n).map_err(|_| error(&ctx, format!("n = {n} must be >= 0")))?;
        let found = sp.peaks(n, min_separation_hz).at(&ctx)?;
        Ok(found
            .into_iter()
            .map(|(f, v)| {
                let mut m = Map::new();
                m.insert("f_hz".into(), Dynamic::from_float(f));
                m.insert("value".into(), Dynamic::from_float(v));
                Dynamic::from_map(m)
            })
            .collect())
    }

    /// Short description: number of bins and resolution.
    #[rhai_fn(global, name = "to_string", name = "to_debug", pure)]
    pub fn describe_spectrum(sp: &mut Spectrum) -> String {
        format!("Spectrum(bins = {}, df = {:e} Hz)", sp.psd.len(), sp.df_hz)
    }
}
