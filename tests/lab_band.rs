//! The experiment a lab would see: on the default scene the focused TR-NEWS signal lies in
//! the transducer band.

use std::sync::Arc;
use trnews::scene::{Absorber, Resolution, Scene, SceneSpec};
use trnews::transducer::{energy_outside_band, TransducerSpec};
use trnews::trnews::{tr_news, Responder, TrNewsSpec};

/// Fraction of the energy of y_TR at receiver 3 outside the default transducer band.
fn focus_outside_band(spec: &SceneSpec) -> f64 {
    let scene = Arc::new(Scene::build(spec).unwrap());
    let trs = TrNewsSpec {
        receivers: vec![3],
        ..Default::default()
    };
    let r = Responder::new(scene, trs.focus_duration_s() + 1e-6).unwrap();
    let tr = tr_news(&r, &trs).unwrap();
    let band = TransducerSpec::default();
    energy_outside_band(&tr.focus[0].focused, band.f_lo_hz, band.f_hi_hz).unwrap()
}

#[test]
fn default_experiment_focuses_inside_the_transducer_band() {
    // Issue bound: under 10% of y_TR's energy outside the band, cracked and uncracked, on
    // the report's triangles and on the quick preset's spectral elements (measured 0.03% and
    // 0.11% on T3). The report's setup (dashpots, pinned corners, raw displacement) on the
    // same draw puts 69% outside: the bound is not met by accident.
    for (kind, cracked) in [
        ("T3", SceneSpec::default()),
        ("SEM", SceneSpec::preset(Resolution::Quick)),
    ] {
        for (name, spec) in [("uncracked", cracked.uncracked()), ("cracked", cracked)] {
            let outside = focus_outside_band(&spec);
            println!(
                "{kind}, {name}: {:.2}% of y_TR outside the band",
                100.0 * outside
            );
            assert!(outside < 0.10, "{kind}, {name}: {outside}");
        }
    }
    let report = SceneSpec {
        absorber: Absorber::Dashpot,
        fix_bottom_corners: true,
        transducer: None,
        ..Default::default()
    };
    let outside = focus_outside_band(&report.uncracked());
    println!("report's setup, uncracked: {:.1}% outside", 100.0 * outside);
    assert!(outside > 0.5, "{outside}");
}
