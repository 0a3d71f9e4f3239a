//! TR-NEWS over a channel: the same procedures (focusing, delayed TR-NEWS, pulse inversion)
//! on a simulated scene, on a measured-style impulse response read from a file, and on
//! recorded responses, with the same results.

mod common;

use common::TempDir;
use std::sync::Arc;
use trnews::scene::{Scene, SceneSpec};
use trnews::script::{Host, HostOptions};
use trnews::signal::{self, Signal};
use trnews::trnews::{delayed_tr_news, tr_news, Recording, Responder, TrNewsSpec};

/// A script writes the uncracked smoke scene's impulse response (transducers included) to
/// .npy, reads it back as a measured channel, and runs TR-NEWS and delayed TR-NEWS on both.
///
/// Tolerance 1e-9 relative (L2 for waveforms): the scene answers a drive s with
/// B * (h * (B * s)) and the channel with (B * (h * (B * delta))) * s. For a causal LTI chain
/// truncated at the same sample these are equal in exact arithmetic; the .npy round trip
/// keeps every float64 bit, so only the convolutions' summation order differs (round-off,
/// measured 2.2e-13 at most). Focus times must be the same sample exactly.
const SCRIPT: &str = r#"
let spec = trnews::preset_spec("smoke");
spec.receivers = [3];
spec.pulse_inversion = true;
let points = [#{ delays: [0.0, 1e-6], amplitudes: [1.0, 1.0] }, #{ delays: [0.0, 2e-6], amplitudes: [1.0, 0.5] }];
let duration = trnews::focus_duration(spec) + 2e-6 + 1e-6;

let plain = scene::preset("smoke", #{}).uncracked();
let simulated = trnews::responder(plain, duration);
io::write_npy("h.npy", simulated.impulse_response(duration));

let h = io::read_npy("h.npy", #{ dt_s: simulated.dt });
let measured = trnews::channel_from_impulse(h, #{ peak_drive: simulated.peak_drive, band: "0.2-2 MHz (measured)" });

let a = simulated.tr_news(spec);
let b = measured.tr_news(spec);
assert(b.band == "0.2-2 MHz (measured)", b.band);
let worst = 0.0;
let check = |what, x, y| {
    let d = x.relative_l2(y);
    print(`${what}: relative L2 ${d}`);
    if d > worst { worst = d; }
    assert(d < 1e-9, `${what}: relative L2 ${d}`);
};
for k in 1..a.responses.len() + 1 { check.call(`response ${k}`, a.response(k), b.response(k)); }
let fa = a.focus(3);
let fb = b.focus(3);
check.call("focusing signal", fa.source, fb.source);
check.call("focused y_TR", fa.focused, fb.focused);
// both channels are linear: pulse inversion cancels to round-off on each
assert(fa.pi_residual < 1e-12 && fb.pi_residual < 1e-12, `PI residuals ${fa.pi_residual}, ${fb.pi_residual}`);
assert(fa.peak.time_s == fb.peak.time_s, `focus time ${fa.peak.time_s} vs ${fb.peak.time_s}`);
assert(abs(fa.peak.amplitude / fb.peak.amplitude - 1.0) < 1e-9, "focus amplitude");
assert(abs(fa.side_lobes.asymmetry - fb.side_lobes.asymmetry) < 1e-9, "side-lobe asymmetry");

let da = trnews::delayed(simulated, a, 3, points, 5e-6);
let db = trnews::delayed(measured, b, 3, points, 5e-6);
for i in 0..points.len() {
    check.call(`delayed ${i} simulation`, da[i].simulation, db[i].simulation);
    check.call(`delayed ${i} prediction`, da[i].prediction, db[i].prediction);
    assert(abs(da[i].misfit - db[i].misfit) < 1e-9, `misfit ${da[i].misfit} vs ${db[i].misfit}`);
}
print(`largest relative difference, scene vs channel read from h.npy: ${worst}`);

// a measured channel has no mesh: asking for an error estimate says so
try { experiment::setup(#{ error_estimate: true }).estimate_wanted(measured); assert(false, "estimate on a channel"); }
catch (e) { assert(e.contains("simulated scene"), e); }
try { trnews::channel_from_impulse([1.0], #{}); assert(false, "not a Signal"); }
catch (e) { assert(e.contains("impulse[0]") && e.contains("Signal"), e); }
try { trnews::channel_from_impulse(h, #{ peak_drive: -1.0 }); assert(false, "negative peak"); }
catch (e) { assert(e.contains("peak_drive"), e); }
try { trnews::channel_from_impulse(h, #{ peek: 1.0 }); assert(false, "unknown option"); }
catch (e) { assert(e.contains("peek"), e); }
try { measured.respond(fa.source, 1.0); assert(false, "longer than the impulse response"); }
catch (e) { assert(e.contains("duration_s") && e.contains("impulse response length"), e); }
"#;

/// Runs `script` with a fresh directory as both its output and its data directory.
fn run_in_temp_dir(tag: &str, name: &str, script: &str) -> Result<(), trnews::script::ScriptError> {
    let dir = TempDir::new(&format!("channel-{tag}"));
    Host::new(HostOptions {
        out_dir: dir.0.clone(),
        data_dir: Some(dir.0.clone()),
        quiet: true,
        ..HostOptions::default()
    })
    .expect("host")
    .run_str(name, script)
}

#[test]
fn trnews_on_an_impulse_response_read_from_npy_matches_the_scene() {
    run_in_temp_dir("impulse", "measured_impulse.rhai", SCRIPT)
        .expect("scene and measured channel agree");
}

/// Lab workflow from files: the chirp and focusing drives' responses of the cracked smoke scene
/// are written as CSV (time column plus one column per receiver; the writer keeps round-trip
/// precision), read back as recordings, and TR-NEWS on them gives the scene's focus exactly.
const RECORDED_SCRIPT: &str = r#"
let spec = trnews::preset_spec("smoke");
spec.receivers = [3];
let sim = trnews::simulating(scene::preset("smoke", #{}));
let tr = sim.tr_news(spec);
let write = |file, drive, duration| {
    let traces = sim.respond(drive, duration).traces;
    let t = [];
    for k in 0..traces[0].len { t.push(k * sim.dt); }
    io::write_csv(file, ["t_s", "r1", "r2", "r3", "r4"], [t] + traces);
    io::write_npy(file + ".drive.npy", drive);
};
write.call("chirp.csv", tr.chirp, spec.record_s);
write.call("focus3.csv", tr.focus(3).source, trnews::focus_duration(spec));

let recordings = [];
for name in ["chirp.csv", "focus3.csv"] {
    let cols = io::read_csv(name, #{ time_column: "t_s" });
    let sent = io::read_npy(name + ".drive.npy", #{ dt_s: sim.dt });
    recordings.push(#{ sent: sent, received: [cols.r1, cols.r2, cols.r3, cols.r4] });
}
let lab = trnews::channel_from_recordings(recordings, #{ peak_drive: sim.peak_drive });
let again = lab.tr_news(spec);
assert(again.focus(3).focused.relative_l2(tr.focus(3).focused) == 0.0, "focus from recorded files");
assert(again.focus(3).side_lobes.asymmetry == tr.focus(3).side_lobes.asymmetry, "asymmetry");
let other = spec;
other.receivers = [2];
try { lab.tr_news(other); assert(false, "unrecorded drive"); }
catch (e) { assert(e.contains("was not recorded"), e); }
"#;

#[test]
fn trnews_on_recordings_read_from_csv_matches_the_scene() {
    run_in_temp_dir("recorded", "recorded.rhai", RECORDED_SCRIPT)
        .expect("recordings read from files reproduce the scene");
}

/// Recorded responses of the cracked (nonlinear) smoke scene to the chirp, the focusing
/// signal, its inverse and the delayed sources give the scene's TR-NEWS, PI and delayed
/// results exactly: the recorded channel returns the same samples (a causal simulation's
/// first n steps do not depend on how long it runs), so equality is bit for bit. The scene
/// keeps its time step's error: the time-dispersion transforms act on a whole record, so
/// with them a response's samples depend on the record's length (by round-off and the
/// transform's band edge). A drive that was not recorded is refused, naming it.
#[test]
fn recorded_responses_of_a_cracked_scene_reproduce_its_results() {
    let spec = SceneSpec {
        time_dispersion: None,
        ..SceneSpec::smoke()
    };
    let scene = Arc::new(Scene::build(&spec).expect("smoke scene"));
    let sim = Responder::simulating(scene);
    let spec = TrNewsSpec {
        receivers: vec![3],
        pulse_inversion: true,
        ..TrNewsSpec::smoke()
    };
    let points = vec![(vec![0.0, 1e-6], vec![1.0, 1.0])];
    let tr = tr_news(&sim, &spec).expect("tr_news on the scene");
    let delayed = delayed_tr_news(&sim, &tr, &tr.focus[0], &points, 5e-6).expect("delayed");
    let long = spec.focus_duration_s() + 2e-6;
    let source = &tr.focus[0].source;
    let mut drives: Vec<Signal> = vec![
        tr.chirp.clone(),
        source.clone(),
        source.scale(-1.0).expect("inverse"),
    ];
    drives.extend(points.iter().map(|(d, a)| {
        let d: Vec<f64> = d
            .iter()
            .map(|t| (t / sim.dt_s()).round() * sim.dt_s())
            .collect();
        signal::delay_and_sum(source, &d, a).expect("delayed source")
    }));
    let recordings = drives
        .iter()
        .map(|s| Recording {
            sent: s.clone(),
            received: sim.respond(s, long).expect("record").traces,
        })
        .collect();
    let recorded =
        Responder::from_recordings(recordings, sim.peak_drive(), sim.band()).expect("channel");
    let again = tr_news(&recorded, &spec).expect("tr_news on the recordings");
    let (f, g) = (&tr.focus[0], &again.focus[0]);
    assert_eq!(tr.responses[2].samples, again.responses[2].samples);
    assert_eq!(f.focused.samples, g.focused.samples);
    assert_eq!(f.pi_residual(), g.pi_residual());
    assert_eq!(f.side_lobes.asymmetry, g.side_lobes.asymmetry);
    let replay = delayed_tr_news(&recorded, &again, g, &points, 5e-6).expect("delayed replay");
    assert_eq!(delayed[0].misfit, replay[0].misfit);
    println!(
        "cracked smoke scene from recordings: PI residual {:?}, delayed misfit {}",
        g.pi_residual(),
        replay[0].misfit
    );
    assert!(
        replay[0].misfit > 1e-3,
        "the crack's nonlinearity survives the recording"
    );
    let other = vec![(vec![0.0, 3e-6], vec![1.0, 1.0])];
    let e = delayed_tr_news(&recorded, &again, g, &other, 5e-6)
        .unwrap_err()
        .to_string();
    assert!(e.contains("was not recorded"), "{e}");
}
