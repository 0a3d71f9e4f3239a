//! Tests of the estimates: power laws, the tail fit on synthetic traces, bounds, the error
//! across the layers.

use super::*;

/// The layered rectangle's refinement at order 7 (companions along x, then across).
pub(super) const LAYERED_7: Refinement = Refinement::Orders {
    top: 7,
    across: true,
    smooth: true,
};

#[test]
fn power_law_gives_exact_richardson_error() {
    // Q_h = 1 + 0.3 h^2: at h = 0.1 the error is 3e-3 and the estimate exact.
    let q = |h: f64| 1.0 + 0.3 * h * h;
    let e = Estimate::scalar(q(0.1), q(0.2), q(0.4), Refinement::ElementSizes);
    assert_eq!(e.verdict, Verdict::Reliable);
    assert!((e.error.unwrap() - 3e-3).abs() < 1e-12);
    assert!((e.observed_order.unwrap() - 2.0).abs() < 1e-9);
}

/// Traces T + E_k at orders p, p-1, p-2 whose errors along x have sizes a, a / rho,
/// a / rho^2 and correlate `c` between consecutive orders (c^2 between p and p-2): three
/// orthonormal tones u_0, u_1, u_2 over the window, E_p-1 along c u_0 + s u_1 and E_p-2
/// along c E_p-1 + s u_2 (s = sqrt(1 - c^2)).
fn slow_traces(a: f64, rho: f64, c: f64) -> [Signal; 3] {
    let n = 400;
    let tone = |k: f64, i: usize| (2.0 * std::f64::consts::PI * k * i as f64 / n as f64).sin();
    let s = (1.0 - c * c).sqrt();
    let unit = (2.0 / n as f64).sqrt();
    let error = |order_down: usize, i: usize| {
        let (u0, u1, u2) = (
            unit * tone(3.0, i),
            unit * tone(5.0, i),
            unit * tone(7.0, i),
        );
        let dir = match order_down {
            0 => u0,
            1 => c * u0 + s * u1,
            _ => c * c * u0 + c * s * u1 + s * u2,
        };
        a / rho.powi(order_down as i32) * dir
    };
    [0, 1, 2].map(|k| {
        let samples = (0..n).map(|i| unit * tone(1.0, i) + error(k, i)).collect();
        Signal::new(1e-9, 0.0, samples).unwrap()
    })
}

#[test]
fn a_waveforms_tail_along_x_is_fitted_at_any_fall() {
    // Contact at GLL nodes: the error along x falls 20-30% per order and the orders'
    // errors are partly aligned; a plane wave's errors fall 2-3x per order and are far from
    // aligned. For falls from 21% to 70% per order and correlations from aligned to
    // opposed, and for a scalar (aligned), the fit recovers the correlation exactly and
    // states the error of the top fall (order 7: 6/7 of the fall below).
    for (rho, c) in [
        (0.73, 0.37),
        (0.72, 0.97),
        (0.79, 0.81),
        (0.75, 1.0),
        (0.8, 0.0),
        (0.72, -0.3),
        (0.5, 1.0),
        (0.5, 0.0),
        (0.35, 0.1),
        (0.3, -0.5),
    ] {
        let a = 4e-3;
        let [p, p1, p2] = slow_traces(a, rho, c);
        let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), LAYERED_7).unwrap();
        // the error at a constant fall, and what the top fall 6/7 rho makes of it
        let truth = a / (1.0 + a * a).sqrt();
        let spread = |r: f64| (1.0 + 1.0 / (r * r) - 2.0 * c / r).sqrt();
        let stated = truth * spread(rho) / spread(rho * 6.0 / 7.0);
        assert_eq!(e.verdict, Verdict::Reliable, "rho {rho}, c {c}: {e:?}");
        assert!(
            (e.error.unwrap() / stated - 1.0).abs() < 1e-6,
            "rho {rho}, c {c}: {e:?} vs {stated}"
        );
        assert!(
            (e.correlation.unwrap() - c).abs() < 1e-6,
            "rho {rho}, c {c}: {e:?}"
        );
        assert!(
            e.describe().contains("tail along x fitted"),
            "{}",
            e.describe()
        );
    }
    let q = |p: i32| 1.0 + 0.01 * 0.75f64.powi(p);
    let e = Estimate::scalar(q(7), q(6), q(5), LAYERED_7);
    assert_eq!(e.verdict, Verdict::Reliable);
    // the geometric tail at the top fall 6/7 of 0.75
    let top = 0.75 * 6.0 / 7.0;
    let tail = (q(7) - q(6)).abs() * top / (1.0 - top);
    assert!((e.error.unwrap() / tail - 1.0).abs() < 1e-9, "{e:?}");
    assert_eq!(e.correlation, Some(1.0));
    // Stored with the sweep's points (postcard: every field written, with or without a fit).
    for stored in [e, Estimate::scalar(1.0, 1.0, 1.0, LAYERED_7)] {
        let back: Estimate = crate::sweep::decode(&crate::sweep::encode(&stored).unwrap()).unwrap();
        assert_eq!(back, stored);
    }
}

#[test]
fn a_fast_fall_from_low_order_companions_keeps_the_bound() {
    // 5x per order, companions at orders 2 and 3: the bound d_1; at orders 5 and 6 (top
    // 7), the fitted tail.
    let [p, p1, p2] = slow_traces(4e-3, 0.2, 0.3);
    let window = (0.0, 1.0);
    let low = Estimate::waveform(
        &p,
        &p1,
        &p2,
        window,
        Refinement::Orders {
            top: 4,
            across: true,
            smooth: true,
        },
    );
    let low = low.unwrap();
    assert_eq!(low.verdict, Verdict::UpperBound, "{low:?}");
    assert_eq!(
        (low.error, low.correlation),
        (Some(low.companions[0]), None)
    );
    let high = Estimate::waveform(&p, &p1, &p2, window, LAYERED_7);
    let high = high.unwrap();
    assert_eq!(high.verdict, Verdict::Reliable, "{high:?}");
    assert!(high.error.unwrap() < 0.3 * high.companions[0], "{high:?}");
    assert!((high.correlation.unwrap() - 0.3).abs() < 1e-6, "{high:?}");
}

#[test]
fn a_fall_slower_than_the_slowest_or_unfit_says_refine() {
    // 10% per order, the errors aligned: too little of the fall to rest a tail on, too
    // aligned to be a scatter.
    let [p, p1, p2] = slow_traces(4e-3, 0.9, 0.8);
    let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), LAYERED_7).unwrap();
    assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
    assert!(e.error.is_none() && e.correlation.is_none());
    // Triangles keep their order-2 test: a slow fall of element sizes is not fitted.
    let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), Refinement::ElementSizes).unwrap();
    assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
    // No correlation fits differences with d_13 > d_1 + d_2 (not a triangle).
    assert!(fitted_tail(1.0, 1.3, Some(2.5), LAYERED_7).is_none());
    // A scalar whose differences change sign and grow more than (4 + sqrt 15) = 7.9x: too
    // aligned to be a scatter (c = 0.60), refine.
    let e = Estimate::scalar(1.003, 1.013, 1.012, LAYERED_7);
    assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
}

/// Errors along x of one size that correlate c between consecutive orders (no fall: the
/// contact at GLL nodes, each order another perturbation): the scatter's estimate recovers
/// their size exactly up to c = 1/2, and says "refine" above, where errors that do not fall
/// are aligned.
#[test]
fn errors_that_do_not_fall_are_their_scatter_where_mostly_independent() {
    let a: f64 = 4e-3;
    let truth = a / (1.0 + a * a).sqrt();
    for c in [-0.3, 0.0, 0.3, 0.45] {
        let [p, p1, p2] = slow_traces(a, 1.0, c);
        let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), LAYERED_7);
        let e = e.unwrap();
        assert_eq!(e.verdict, Verdict::Reliable, "c {c}: {e:?}");
        assert!(
            (e.error.unwrap() / truth - 1.0).abs() < 1e-6,
            "c {c}: {e:?}"
        );
        assert!((e.correlation.unwrap() - c).abs() < 1e-6, "c {c}: {e:?}");
    }
    for c in [0.6, 0.9] {
        let [p, p1, p2] = slow_traces(a, 1.0, c);
        let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), LAYERED_7);
        assert_eq!(e.unwrap().verdict, Verdict::Refine, "c {c}");
    }
}

/// A scalar whose errors along x alternate in sign, E_p = a (-rho)^(p - 7): the bound d_1
/// = a (1 + 1 / rho), above the error at every fall the estimate takes; growing
/// differences or too slow a fall are the scatter of errors of about one size, which the
/// estimate states within 20% of a; on triangles any sign change says "refine".
#[test]
fn a_scalars_alternating_errors_along_x_are_bounded_by_d1() {
    let a = 2e-3;
    for rho in [0.8, 0.5, 0.1] {
        let q = |p: i32| 0.05 + a * (-1.0f64 / rho).powi(7 - p);
        let e = Estimate::scalar(q(7), q(6), q(5), LAYERED_7);
        assert_eq!(e.verdict, Verdict::UpperBound, "rho {rho}: {e:?}");
        let bound = e.error.unwrap();
        assert!(
            (bound / (a * (1.0 + 1.0 / rho)) - 1.0).abs() < 1e-9,
            "rho {rho}: {bound}"
        );
        assert!(e.correlation.is_none());
        let t3 = Estimate::scalar(q(7), q(6), q(5), Refinement::ElementSizes);
        assert_eq!(t3.verdict, Verdict::Refine);
    }
    for rho in [0.9, 1.2] {
        let q = |p: i32| 0.05 + a * (-1.0f64 / rho).powi(7 - p);
        let e = Estimate::scalar(q(7), q(6), q(5), LAYERED_7);
        assert_eq!(e.verdict, Verdict::Reliable, "rho {rho}: {e:?}");
        assert!(e.scatters_along_x, "rho {rho}: {e:?}");
        let ratio = e.error.unwrap() / a;
        assert!((0.8..=1.25).contains(&ratio), "rho {rho}: {ratio}");
    }
}

/// A scalar whose values along x scatter (differences that change sign and do not fall:
/// the quick preset's cracked PI residual under the default friction law at orders 7, 6, 5,
/// one order more across and half the step) states the scatter along x and the two other
/// shares in quadrature, each source's part recovered; differences of one sign that do not
/// fall still say "refine", and so does a scatter where the scene's results do not depend
/// smoothly on its discretisation (the instantaneous Coulomb law).
#[test]
fn a_scalars_scatter_along_x_adds_to_the_other_sources_in_quadrature() {
    let values = [0.146935, 0.146274, 0.146370, 0.146743, 0.147095];
    let e = Estimate::dimensionless_of(&values, LAYERED_7).unwrap();
    assert_eq!(e.verdict, Verdict::Reliable, "{e:?}");
    assert!(e.scatters_along_x, "{e:?}");
    let along_x = e.parts().unwrap()[0].1;
    let (d1, d2) = (values[0] - values[1], values[1] - values[2]);
    let mean_square = (d1 * d1 + d2 * d2) / 2.0;
    let c = (values[0] - values[2]).powi(2) / mean_square - 1.0;
    let scatter = (mean_square / (2.0 * (1.0 - c))).sqrt();
    assert!(
        (along_x / scatter - 1.0).abs() < 1e-9,
        "{along_x} vs {scatter}"
    );
    let (across, step) = (values[0] - values[3], values[0] - values[4]);
    let expected = scatter.hypot(ACROSS_TAIL * across).hypot(STEP_TAIL * step);
    assert!(
        (e.error.unwrap() / expected - 1.0).abs() < 1e-9,
        "{e:?} vs {expected}"
    );
    assert_eq!(e.dominant_source(), Some(Source::Refinement));
    assert!(
        e.describe().contains("errors along x scatter"),
        "{}",
        e.describe()
    );
    let aligned =
        Estimate::dimensionless_of(&[0.1470, 0.1466, 0.1462, 0.1468, 0.1471], LAYERED_7).unwrap();
    assert_eq!((aligned.verdict, aligned.error), (Verdict::Refine, None));
    // Under the instantaneous Coulomb law the scatter is not the error's size: "refine".
    let ill_conditioned = Refinement::Orders {
        top: 7,
        across: true,
        smooth: false,
    };
    let e = Estimate::dimensionless_of(&values, ill_conditioned).unwrap();
    assert_eq!((e.verdict, e.error), (Verdict::Refine, None));
}

#[test]
fn first_order_convergence_is_not_trusted_as_second() {
    let q = |h: f64| 1.0 + 0.3 * h;
    let e = Estimate::scalar(q(0.1), q(0.2), q(0.4), Refinement::ElementSizes);
    assert_eq!(e.verdict, Verdict::Refine);
    assert!(e.error.is_none());
    assert!((e.observed_order.unwrap() - 1.0).abs() < 1e-9);
    assert!(e.describe().contains("refine"));
}

#[test]
fn faster_convergence_gives_a_bound() {
    let q = |h: f64| 1.0 + 0.3 * h.powi(4);
    let e = Estimate::scalar(q(0.1), q(0.2), q(0.4), Refinement::ElementSizes);
    assert_eq!(e.verdict, Verdict::UpperBound);
    assert!(e.error.unwrap() > 0.3 * 0.1f64.powi(4));
}

#[test]
fn oscillating_or_constant_sequences() {
    let e = Estimate::scalar(1.0, 1.2, 1.0, Refinement::ElementSizes);
    assert_eq!(e.verdict, Verdict::Refine);
    // Differences in the ratio of order 2 but of opposite signs: not a power law.
    let sign_change = Estimate::scalar(1.0, 1.01, 0.97, Refinement::ElementSizes);
    assert_eq!(sign_change.verdict, Verdict::Refine);
    let c = Estimate::scalar(0.5, 0.5, 0.5, Refinement::ElementSizes);
    assert_eq!(c.verdict, Verdict::MeshIndependent);
    let z = Estimate::scalar(0.0, 0.0, 0.0, Refinement::ElementSizes);
    assert_eq!(z.verdict, Verdict::MeshIndependent);
}

#[test]
fn waveform_of_a_shifted_pulse() {
    // A pulse whose arrival is off by c h^2 (a phase error): the relative L2 error
    // estimate from h, 2h, 4h is within 10% of the true one for small shifts.
    let dt = 1e-9;
    let pulse = |shift: f64| {
        let samples = (0..4000)
            .map(|k| {
                let t = k as f64 * dt - 2e-6 - shift;
                (-(t / 0.2e-6).powi(2)).exp() * (2.0 * std::f64::consts::PI * 2e6 * t).sin()
            })
            .collect();
        Signal::new(dt, 0.0, samples).unwrap()
    };
    let shift = |h: f64| 2e-9 * h * h;
    let (f, m, c) = (pulse(shift(1.0)), pulse(shift(2.0)), pulse(shift(4.0)));
    let e = Estimate::waveform(&f, &m, &c, (0.0, 4e-6), Refinement::ElementSizes).unwrap();
    let exact = pulse(0.0);
    let truth = signal::relative_l2(&f, &exact, None).unwrap();
    assert_eq!(e.verdict, Verdict::Reliable, "{e:?}");
    assert!(
        (e.error.unwrap() / truth - 1.0).abs() < 0.1,
        "{e:?} vs {truth}"
    );
}

#[test]
fn the_error_across_adds_to_the_error_along_x_and_names_the_dominant_source() {
    // Along x: Q = 1 + 0.3 * 2^-p at p = 7, 6, 5 (a halving per order): error 0.3 * 2^-7.
    let q = |p: i32| 1.0 + 0.3 * 2f64.powi(-p);
    let along = 0.3 * 2f64.powi(-7);
    let across = 3.0 * along;
    let values = [q(7), q(6), q(5), q(7) + across];
    let e = Estimate::scalar_of(&values, LAYERED_7).unwrap();
    assert_eq!(e.verdict, Verdict::Reliable);
    let expected = along + ACROSS_TAIL * across;
    assert!((e.error.unwrap() - expected).abs() < 1e-12, "{e:?}");
    assert_eq!(e.across, Some((q(7) - values[3]).abs()));
    assert_eq!(e.dominant_source(), Some(Source::Across));
    let text = e.describe();
    assert!(text.contains("across the layers dominant"), "{text}");
    let small = Estimate::scalar_of(&[q(7), q(6), q(5), q(7) + 0.1 * along], LAYERED_7).unwrap();
    assert_eq!(small.dominant_source(), Some(Source::Refinement));
    // Three values: no companion across, nothing separated.
    let three = Estimate::scalar_of(&values[..3], LAYERED_7).unwrap();
    assert_eq!((three.across, three.dominant_source()), (None, None));
    assert!(Estimate::scalar_of(&values[..2], LAYERED_7).is_err());
    assert!(Estimate::scalar_of(&[1.0; 6], LAYERED_7).is_err());
    // A bound along x (a fall of 8x per order: d_1 = 1.4e-3) stays a bound with a smaller
    // error across, and becomes an estimate where the error across dominates it.
    let fast = |p: i32| 1.0 + 0.1 * 8f64.powi(-(p - 4));
    let bound = (fast(7) - fast(6)).abs();
    for (d_y, verdict) in [
        (0.1 * bound, Verdict::UpperBound),
        (bound, Verdict::Reliable),
    ] {
        let e =
            Estimate::scalar_of(&[fast(7), fast(6), fast(5), fast(7) + d_y], LAYERED_7).unwrap();
        assert_eq!(e.verdict, verdict, "{e:?}");
        let expected = bound + ACROSS_TAIL * d_y;
        assert!(
            (e.error.unwrap() / expected - 1.0).abs() < 1e-9,
            "{e:?} vs {expected}"
        );
    }
}

#[test]
fn where_the_companions_along_x_agree_the_error_across_is_the_error() {
    // Normal incidence: the solution does not vary along x.
    let e = Estimate::dimensionless_of(&[0.5, 0.5, 0.5, 0.5 + 2e-4], LAYERED_7).unwrap();
    assert_eq!(e.verdict, Verdict::Reliable);
    assert!((e.error.unwrap() - ACROSS_TAIL * 2e-4).abs() < 1e-15);
    assert_eq!(e.dominant_source(), Some(Source::Across));
    // Round-off across as well: mesh-independent.
    let same = Estimate::dimensionless_of(&[0.5, 0.5, 0.5, 0.5 + 1e-14], LAYERED_7).unwrap();
    assert_eq!(same.verdict, Verdict::MeshIndependent);
    // A "refine" along x stays one: no error is claimed.
    let refine = Estimate::scalar_of(&[1.0, 1.2, 1.4, 1.1], LAYERED_7).unwrap();
    assert_eq!((refine.verdict, refine.error), (Verdict::Refine, None));
    assert!((refine.across.unwrap() - 0.1).abs() < 1e-12);
}

#[test]
fn a_waveforms_error_across_is_its_relative_l2_difference() {
    let dt = 1e-9;
    let wave = |a: f64| {
        Signal::new(
            dt,
            0.0,
            (0..100).map(|k| a * (k as f64 * 0.1).sin()).collect(),
        )
        .unwrap()
    };
    let (f, across) = (wave(1.0), wave(1.01));
    let e = Estimate::waveform_of(&[&f, &f, &f, &across], (0.0, 1e-7), LAYERED_7).unwrap();
    assert!(
        (e.error.unwrap() - ACROSS_TAIL * 0.01).abs() < 1e-12,
        "{e:?}"
    );
    assert_eq!(e.brief(), "err 1.4% (mostly across)");
    // With an error along x too, the two add in quadrature.
    let shifted = |s: f64| {
        let samples = (0..100).map(|k| ((k as f64 - s) * 0.1).sin()).collect();
        Signal::new(dt, 0.0, samples).unwrap()
    };
    let (f, m, c) = (shifted(0.0), shifted(0.01), shifted(0.03));
    let along = Estimate::waveform(&f, &m, &c, (0.0, 1e-7), LAYERED_7).unwrap();
    let both = Estimate::waveform_of(&[&f, &m, &c, &across], (0.0, 1e-7), LAYERED_7).unwrap();
    let expected = along
        .error
        .unwrap()
        .hypot(ACROSS_TAIL * both.across.unwrap());
    assert!((both.error.unwrap() - expected).abs() < 1e-15, "{both:?}");
}

#[test]
fn the_error_in_time_adds_to_the_others_and_can_dominate() {
    // A cracked misfit whose companions along x and across agree to 4e-5, while half the
    // step moves it 3.4e-4 (the quick preset's, docs/src/validation/default-experiment.md).
    let m = 0.1193;
    let values = [m, m + 1e-5, m + 3e-5, m + 1e-5, m + 3.4e-4];
    let e = Estimate::dimensionless_of(&values, LAYERED_7).unwrap();
    let step = e.step.unwrap();
    assert!((step - 3.4e-4).abs() < 1e-15, "{e:?}");
    assert!((e.step_error().unwrap() - STEP_TAIL * 3.4e-4).abs() < 1e-15);
    assert_eq!(e.dominant_source(), Some(Source::Step));
    assert_eq!(e.verdict, Verdict::Reliable, "{e:?}");
    let along = e.error.unwrap() - STEP_TAIL * 3.4e-4 - ACROSS_TAIL * 1e-5;
    assert!(along > 0.0 && along <= 1e-5, "{e:?}");
    let text = e.describe();
    assert!(text.contains("in time 4.81e-4, in time dominant"), "{text}");
    // Without the companion at half the step the error in time is not there.
    let four = Estimate::dimensionless_of(&values[..4], LAYERED_7).unwrap();
    assert!(four.error.unwrap() < 1e-4, "{four:?}");
    assert_eq!((four.step, four.step_error()), (None, None));
    // On a Gmsh mesh (no companion across) the fourth value is the one at half the step.
    let gmsh = Refinement::Orders {
        top: 7,
        across: false,
        smooth: true,
    };
    let on_mesh = Estimate::dimensionless_of(&[m, m + 1e-5, m + 3e-5, m + 3.4e-4], gmsh).unwrap();
    assert_eq!(on_mesh.across, None);
    assert!(
        (on_mesh.step.unwrap() - 3.4e-4).abs() < 1e-15,
        "{on_mesh:?}"
    );
    assert!(Estimate::dimensionless_of(&values, gmsh).is_err());
    // A waveform's error in time adds in quadrature.
    let dt = 1e-9;
    let wave = |a: f64| {
        let samples = (0..100).map(|k| a * (k as f64 * 0.1).sin()).collect();
        Signal::new(dt, 0.0, samples).unwrap()
    };
    let (f, across, halved) = (wave(1.0), wave(1.003), wave(1.01));
    let w = Estimate::waveform_of(&[&f, &f, &f, &across, &halved], (0.0, 1e-7), LAYERED_7).unwrap();
    let expected = (ACROSS_TAIL * 0.003).hypot(STEP_TAIL * 0.01);
    assert!((w.error.unwrap() - expected).abs() < 1e-12, "{w:?}");
    assert_eq!(w.brief(), "err 1.5% (mostly in time)");
}
