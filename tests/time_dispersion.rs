//! The time-dispersion transforms (`trnews::solve::time_dispersion`; issue #25): on a linear
//! body a run whose source got the forward transform and whose recording got the inverse one
//! carries no error of its time step. Checked on a closed epoxy strip against the same
//! discretisation stepped by another scheme (the fourth-order step at a 16x smaller step,
//! whose own error is below 1e-9), for central differences and for Newmark beyond the
//! explicit limit (two schemes with different dispersion relations, which the transforms must
//! bring to the same answer); then on the default scene through `Scene::transmit` and the
//! impulse-response shortcut. Normal incidence through the 50-pair stack, with an absorbing
//! bottom, is in `tests/normal_incidence.rs`.

mod common;
use common::*;
use trnews::scene::{Resolution, Scene, SceneSpec, TimeDispersionSpec};
use trnews::signal::Signal;
use trnews::solve::time_dispersion::TimeDispersion;
use trnews::solve::{Integrator, Quantity, RunConfig};

/// Width and centre of the Gaussian traction pulse (s): its spectrum is below 1e-18 of its
/// peak at 7 MHz, the highest band Newmark at twice dt_crit can cover (0.9 / (pi dt)).
const WIDTH: f64 = 0.3e-6;
const CENTRE: f64 = 1.5e-6;
/// Recorded duration (s): the pulse crosses 3 mm of epoxy and comes back from the fixed
/// bottom.
const DURATION: f64 = 5e-6;

/// A 3 mm epoxy strip on 50 um triangles, rollers on the sides, fixed bottom.
fn strip() -> WaveStrip {
    WaveStrip::new(
        Discretisation::T3 { h: 50e-6 },
        &[(epoxy(), 3e-3)],
        false,
        BottomEdge::Fixed,
    )
}

/// `quantity` 1 mm down under the pressure pulse, `integrator` at step `dt`, the step's error
/// removed over 0..`up_to_hz` when given.
fn recorded(
    strip: &WaveStrip,
    integrator: Integrator,
    dt: f64,
    quantity: Quantity,
    up_to_hz: Option<f64>,
) -> Signal {
    let pulse = gaussian(dt, DURATION, CENTRE, WIDTH, 1.0);
    let transforms =
        up_to_hz.and_then(|f| TimeDispersion::of_run(integrator, dt, f, "up_to_hz").unwrap());
    let traction = match &transforms {
        Some(td) => td.add_to_source(&pulse).unwrap(),
        None => pulse,
    };
    let source = strip.top_traction(270.0, traction);
    let mut receiver = strip.depth_receiver(1e-3, 1);
    receiver.quantity = quantity;
    let config = RunConfig {
        duration_s: DURATION,
        dt_s: Some(dt),
        integrator,
        ..Default::default()
    };
    let Some(td) = transforms else {
        let out = strip.run(&[source], &[receiver], &config).unwrap();
        return out.traces.into_iter().next().unwrap();
    };
    let out = strip
        .run(&[source], &[receiver], &td.extended(&config))
        .unwrap();
    td.recorded(&out.traces[0], quantity, &config).unwrap()
}

/// Central differences at 0.9 dt_crit and Newmark (lumped mass, average acceleration) at
/// 1.8 dt_crit, both with the transforms over 0..7 MHz, against the fourth-order step at
/// 0.9 dt_crit / 16 (its own error below 1e-9): central differences within 1e-6 (measured
/// 1.3e-7 in velocity, 1.9e-7 in displacement), Newmark within 2e-5 (measured 9.6e-6 and
/// 1.6e-5; what remains of its error is not analysed), where the same runs without the
/// transforms are 4e-4 to 2e-2 off (printed; asserted at least 100x more).
#[test]
fn central_differences_and_newmark_lose_their_step_error() {
    let strip = strip();
    let dt_crit = strip.dt_crit();
    let up_to = Some(7e6);
    for quantity in [Quantity::Velocity, Quantity::Displacement] {
        let reference = recorded(
            &strip,
            Integrator::FourthOrder,
            0.9 * dt_crit / 16.0,
            quantity,
            None,
        );
        let newmark = Integrator::Newmark {
            consistent_mass: false,
        };
        for (integrator, dt) in [
            (Integrator::Explicit, 0.9 * dt_crit),
            (newmark, 1.8 * dt_crit),
        ] {
            let kept = rel_l2_on_coarser(
                &recorded(&strip, integrator, dt, quantity, None),
                &reference,
            );
            let removed = rel_l2_on_coarser(
                &recorded(&strip, integrator, dt, quantity, up_to),
                &reference,
            );
            println!(
                "{quantity:?}, {integrator:?} at {:.2} dt_crit: step error kept {kept:.3e}, removed {removed:.3e}",
                dt / dt_crit
            );
            let tolerance = match integrator {
                Integrator::Explicit => 1e-6,
                _ => 2e-5,
            };
            assert!(
                removed < tolerance,
                "{quantity:?}, {integrator:?}: {removed:e}"
            );
            assert!(
                kept > 100.0 * removed,
                "{quantity:?}, {integrator:?}: {kept:e}"
            );
        }
    }
}

/// An integrator whose error is not a frequency map gets no transforms, and a band the step
/// cannot cover is refused naming the field and the limit.
#[test]
fn fourth_order_gets_none_and_a_band_above_the_step_limit_is_refused() {
    let none = TimeDispersion::of_run(Integrator::FourthOrder, 1e-9, 20e6, "up_to_hz").unwrap();
    assert!(none.is_none());
    let e = TimeDispersion::of_run(
        Integrator::Explicit,
        20e-9,
        20e6,
        "time_dispersion.up_to_hz",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("time_dispersion.up_to_hz") && e.contains("0.9 / (pi dt)"),
        "{e}"
    );
}

/// A scene's band that is not a positive frequency is refused naming the field and value,
/// at the first transmission; one the step cannot cover leaves the step's error, as the
/// report says.
#[test]
fn a_scene_refuses_a_bad_band_and_states_an_uncovered_one() {
    let transmit = |up_to_hz: f64| {
        let spec = SceneSpec {
            crack: None,
            time_dispersion: Some(TimeDispersionSpec { up_to_hz }),
            ..SceneSpec::preset(Resolution::Smoke)
        };
        let scene = Scene::build(&spec).unwrap();
        let drive = trnews::signal::ChirpSpec::default()
            .signal(scene.default_dt_s(), 1e3)
            .unwrap();
        scene.transmit(&drive, &scene.run_config(2e-6))
    };
    for bad in [f64::INFINITY, f64::NAN, -1.0, 1e6] {
        let e = transmit(bad).unwrap_err().to_string();
        assert!(e.contains("time_dispersion.up_to_hz"), "{bad}: {e}");
    }
    let out = transmit(1e12).unwrap();
    assert_eq!(out.report.time_dispersion_removed_up_to_hz, None);
}

/// The smoke scene without its crack or transducers, through `Scene::transmit` (forward
/// transform, run over the margin, inverse transform, cut back): the chirp's raw response at
/// 0.9 dt_crit against every third sample of the same at 0.3 dt_crit. With the step's error
/// removed they differ by 0.6-1.9e-5, 4.5-9x less than with it kept (printed; asserted 3x
/// and 5e-5): what the transforms leave is the viscous-spring edges' dashpots (without them
/// 5e-6). The transducers are off because their digital band-pass has a step dependence of
/// its own that the transforms do not touch (with them the two steps differ by 6e-5 at the
/// first receiver, 1.3e-4 kept). The report states the band. The impulse-response shortcut (the corrected impulse response convolved with the
/// drive) gives the transformed run's response to 2e-5 (measured 7-8e-6: the run rolls the
/// 10-20 MHz band off twice, in the forward and the inverse transform, the shortcut once).
#[test]
fn a_scene_removes_the_step_error_in_both_paths() {
    let chirp = trnews::signal::ChirpSpec::default();
    let response = |time_dispersion: Option<TimeDispersionSpec>, refinement: usize| {
        let spec = SceneSpec {
            crack: None,
            transducer: None,
            time_dispersion,
            ..SceneSpec::preset(Resolution::Smoke)
        };
        let scene = Scene::build(&spec).unwrap();
        let dt = 0.9 * scene.stability.dt_crit_s / refinement as f64;
        let config = RunConfig {
            dt_s: Some(dt),
            ..scene.run_config(20e-6)
        };
        let drive = chirp.signal(dt, 1.0e3).unwrap();
        (
            scene.transmit(&drive, &config).unwrap(),
            scene,
            config,
            drive,
        )
    };
    let on = Some(TimeDispersionSpec::default());
    let (fine, _, _, _) = response(on, 3);
    let (coarse, scene, config, drive) = response(on, 1);
    let (kept, _, _, _) = response(None, 1);
    let (kept_fine, _, _, _) = response(None, 3);
    let mut worst_removed: f64 = 0.0;
    for r in 0..scene.receivers.len() {
        let removed = rel_l2_on_coarser(&coarse.traces[r], &fine.traces[r]);
        let kept = rel_l2_on_coarser(&kept.traces[r], &kept_fine.traces[r]);
        println!(
            "receiver {r}: 0.9 vs 0.3 dt_crit, step error removed {removed:.3e}, kept {kept:.3e}"
        );
        assert!(
            kept > 3.0 * removed,
            "receiver {r}: {kept:e} vs {removed:e}"
        );
        worst_removed = worst_removed.max(removed);
    }
    assert!(worst_removed < 5e-5, "{worst_removed:e}");
    assert_eq!(
        coarse.report.time_dispersion_removed_up_to_hz,
        Some(TimeDispersionSpec::default().up_to_hz)
    );
    assert_eq!(kept.report.time_dispersion_removed_up_to_hz, None);

    let h = scene.impulse_response(&config).unwrap();
    for (r, h) in h.traces.iter().enumerate() {
        let shortcut = trnews::signal::convolve_discrete(&drive, h).unwrap();
        let n = coarse.traces[r].len();
        let gap = rel_l2(&shortcut.samples[..n], &coarse.traces[r].samples);
        println!("receiver {r}: impulse-response shortcut vs transformed run {gap:.3e}");
        assert!(gap < 2e-5, "receiver {r}: {gap:e}");
    }
}
