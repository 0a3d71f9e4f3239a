//! Errors of a measure computed from waveforms, propagated from the waveforms' stated errors.
//! The misfit's bound is derived here; the PI residual, side-lobe asymmetry and spectral shift
//! follow the same pattern (their functions' docs).
//!
//! The delayed TR-NEWS misfit m = ||s - p|| / ||p|| (simulation s, linear prediction p, over
//! the focus window) of a cracked scene is the norm of a small residual r = s - p, the
//! contact's nonlinearity. Its own values at orders p, p-1, p-2 along x usually converge, and
//! its own estimate (along x, across the layers, in time) is stated: 1.49 of its distance to the
//! references on the smoke preset (`scripts/sem_target.rhai`, piece `nonlinear`). But the
//! contact acts at GLL nodes whose places change with the order, and the residual is a few
//! percent of the traces, so the three misfits may drift apart (differences of one sign that
//! do not fall, or that grow too fast to be a scatter of one size: "refine").
//! The traces themselves converge, and their stated errors are checked against references.
//! With the absolute errors E_r = ||r_h - r|| and E_p = ||p_h - p|| of the computed residual
//! and prediction, the triangle inequality bounds the misfit's error:
//!
//!   |m_h - m| <= (E_r + m_h E_p) / (||p_h|| - E_p) = (E_r / ||p_h|| + m_h e_p) / (1 - e_p),
//!
//! e_p = E_p / ||p_h|| the prediction's relative error. E_r is estimated by e_r ||r_h|| (the
//! residual's own estimate) and is at most e_s ||s_h|| + E_p (the two traces' errors, as
//! r_h - r = (s_h - s) - (p_h - p)); the smaller is used, where the misfit's own estimate says
//! "refine". It holds as far as the traces' estimates hold (within 2x of their true errors on
//! every check). It is loose: the simulation's and the prediction's errors are mostly one
//! error (the same wave through the same layers), which cancels in r, and the bound adds them.
//! On the smoke preset, where the own estimate holds, the bound through the traces is 11-17x
//! the misfit's distance to the references.

use super::{Estimate, Verdict};

impl Estimate {
    /// The estimate of a relative misfit m = ||s - p|| / ||p|| from its own values (`own`, a
    /// [`Estimate::dimensionless_of`]) and from the estimates of the traces it compares over
    /// the same window: the simulation s, the prediction p and the residual r = s - p, with
    /// `size_ratio` = ||s|| / ||p|| there (module doc). A misfit whose own estimate states an
    /// error (or is unchanged between discretisations: a linear scene's round-off) keeps it;
    /// where it says "refine" the bound of the module doc is stated (verdict
    /// [`Verdict::Propagated`]), if the prediction and one of residual or simulation state an
    /// error; otherwise "refine" stays.
    pub fn relative_misfit(
        own: Estimate,
        simulation: &Estimate,
        prediction: &Estimate,
        residual: &Estimate,
        size_ratio: f64,
    ) -> Estimate {
        if own.verdict != Verdict::Refine {
            return own;
        }
        let m = own.value.abs();
        let Some(e_p) = prediction.stated().filter(|e| *e < 1.0) else {
            return own;
        };
        let via_residual = residual.stated().map(|e_r| e_r * m);
        let via_traces = simulation.stated().map(|e_s| e_s * size_ratio + e_p);
        let residual_error = match (via_residual, via_traces) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => return own,
        };
        own.propagated((residual_error + m * e_p) / (1.0 - e_p))
    }

    /// The estimate of a peak ratio r = max|n| / max|d| (the PI residual: n the PI sum, d the
    /// focused signal, over the focus window) from its own values and, where they say
    /// "refine", from the relative errors e_n, e_d of the two peaks: with |N_h - N| <= e_n N_h
    /// and |D_h - D| <= e_d D_h the ratio moves by at most
    ///
    ///   |r_h - r| <= r_h (e_n + e_d) / (1 - e_d).
    ///
    /// A peak's relative error is taken as its trace's relative L2 error over the window (a
    /// peak of a band-limited trace moves with the trace; not a strict bound, checked against
    /// the references in `scripts/sem_target.rhai`, piece `nonlinear`). `numerator` is the
    /// smaller of n's own relative error and the route through the traces n is the sum of
    /// (`Estimate::sum_error`).
    pub fn peak_ratio(own: Estimate, numerator: Option<f64>, denominator: &Estimate) -> Estimate {
        if own.verdict != Verdict::Refine {
            return own;
        }
        match (numerator, denominator.stated().filter(|e| *e < 1.0)) {
            (Some(e_n), Some(e_d)) => own.propagated(own.value.abs() * (e_n + e_d) / (1.0 - e_d)),
            _ => own,
        }
    }

    /// The relative error of a sum n = a + b of two traces over a window, from the smaller of
    /// its own estimate and the route through its terms: ||dn|| <= e_a ||a|| + e_b ||b||, over
    /// ||n|| (`sizes` = ||a|| / ||n|| and ||b|| / ||n||). `None` where neither states one.
    pub fn sum_error(own: &Estimate, terms: [(&Estimate, f64); 2]) -> Option<f64> {
        let through_terms = terms
            .iter()
            .map(|(e, size)| e.stated().map(|e| e * size))
            .sum::<Option<f64>>();
        smaller(own.stated(), through_terms)
    }

    /// The estimate of a side-lobe energy asymmetry A = (E_a - E_b) / (E_a + E_b) from its own
    /// values and, where they say "refine", from the relative L2 errors e_b, e_a of the trace
    /// over the windows before and after the main lobe (`None`: not stated, no bound): E =
    /// ||x||^2 there lies within E_h (1 -+ e)^2, and A, rising with E_a and falling with E_b,
    /// is furthest from A_h at the corners (E_a (1 + e_a)^2, E_b (1 - e_b)^2) and
    /// (E_a (1 - e_a)^2, E_b (1 + e_b)^2).
    pub fn energy_asymmetry(
        own: Estimate,
        [energy_before, energy_after]: [f64; 2],
        [before, after]: [Option<f64>; 2],
    ) -> Estimate {
        if own.verdict != Verdict::Refine {
            return own;
        }
        let (Some(e_b), Some(e_a)) = (before, after) else {
            return own;
        };
        let asymmetry = |a: f64, b: f64| if a + b > 0.0 { (a - b) / (a + b) } else { 0.0 };
        let a = asymmetry(energy_after, energy_before);
        let highest = asymmetry(
            energy_after * (1.0 + e_a).powi(2),
            energy_before * (1.0 - e_b).max(0.0).powi(2),
        );
        let lowest = asymmetry(
            energy_after * (1.0 - e_a).max(0.0).powi(2),
            energy_before * (1.0 + e_b).powi(2),
        );
        own.propagated((highest - a).max(a - lowest))
    }

    /// The estimate of a shift of mean frequency f_c - f_u (the spectral shift of a cracked
    /// trace from the uncracked one) from its own values and, where they say "refine", from
    /// each trace's relative L2 error e and spectral spread sigma (standard deviation of the
    /// frequency about the mean, weighted by the power spectrum P). To first order in the
    /// trace's error dX, f_h - f = sum (f - f_h) (P_h - P) / sum P, |P_h - P| <= 2 |X_h| |dX|,
    /// and Cauchy-Schwarz gives
    ///
    ///   |f_h - f| <= 2 sigma e / (1 - e)^2
    ///
    /// (the e^2 term, |dX|^2 weighted by |f - f_h| up to the sampling's Nyquist frequency, is
    /// left out: e is below 1% on the presets). The shift's error is at most the sum of the two
    /// traces' (their errors, mostly one wave through the same layers, largely cancel: the
    /// bound is loose). `traces` holds (sigma, e) of the cracked and the uncracked trace.
    pub fn mean_frequency_shift(own: Estimate, traces: [(f64, &Estimate); 2]) -> Estimate {
        if own.verdict != Verdict::Refine {
            return own;
        }
        let mut bound = 0.0;
        for (sigma, e) in traces {
            match e.stated().filter(|e| *e < 1.0) {
                Some(e) => bound += 2.0 * sigma * e / (1.0 - e).powi(2),
                None => return own,
            }
        }
        own.propagated(bound)
    }

    /// This estimate with `error` as a bound propagated from the errors of the traces the
    /// measure is computed from.
    fn propagated(self, error: f64) -> Estimate {
        Estimate {
            error: Some(error),
            verdict: Verdict::Propagated,
            // its own differences say nothing of this error: no split by source
            across: None,
            step: None,
            correlation: None,
            scatters_along_x: false,
            ..self
        }
    }

    /// The error this estimate states, estimate or bound (round-off when unchanged between
    /// discretisations); `None` for "refine".
    pub fn stated(&self) -> Option<f64> {
        match self.verdict {
            Verdict::Refine => None,
            _ => self.error,
        }
    }
}

/// The smaller of two routes to an error, either of which may state none.
pub(crate) fn smaller(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::LAYERED_7;
    use super::*;
    use crate::signal::Signal;

    fn trace(samples: Vec<f64>) -> Signal {
        Signal::new(1.0, 0.0, samples).unwrap()
    }

    fn norm(x: &[f64]) -> f64 {
        x.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    fn misfit(s: &[f64], p: &[f64]) -> f64 {
        let r: Vec<f64> = s.iter().zip(p).map(|(a, b)| a - b).collect();
        norm(&r) / norm(p)
    }

    /// A stated waveform error `e`.
    fn waveform(e: f64) -> Estimate {
        let mut w = Estimate::waveform(
            &trace(vec![1.0; 4]),
            &trace(vec![1.0; 4]),
            &trace(vec![1.0; 4]),
            (0.0, 3.0),
            LAYERED_7,
        )
        .unwrap();
        (w.error, w.verdict) = (Some(e), Verdict::Reliable);
        w
    }

    /// Perturbations of the exact traces by the stated relative errors, in every direction
    /// tried (aligned with the residual, against it, across it), never move the misfit by more
    /// than the stated bound, and the aligned ones reach it to within their second order.
    #[test]
    fn bound_holds_for_errors_of_the_stated_size_and_is_reached_when_aligned() {
        let p = [1.0, 0.5, -0.25, 0.0];
        let s = [1.05, 0.48, -0.25, 0.02];
        let m = misfit(&s, &p);
        let (e_p, e_r) = (0.01, 0.05);
        // differences of one sign that do not fall: "refine" of its own
        let own = Estimate::dimensionless(m, m + 0.003, m + 0.006, LAYERED_7);
        assert_eq!(own.verdict, Verdict::Refine);
        let r: Vec<f64> = s.iter().zip(&p).map(|(a, b)| a - b).collect();
        let ratio = norm(&s) / norm(&p);
        let stated =
            Estimate::relative_misfit(own, &waveform(1.0), &waveform(e_p), &waveform(e_r), ratio);
        assert_eq!(stated.verdict, Verdict::Propagated);
        let bound = stated.error.unwrap();
        assert!((bound - m * (e_r + e_p) / (1.0 - e_p)).abs() < 1e-15);
        let unit = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x / norm(v)).collect() };
        let directions = [
            unit(&r),
            unit(&r).iter().map(|x| -x).collect(),
            unit(&[0.0, 0.0, 1.0, 0.0]),
            unit(&p),
        ];
        let mut largest: f64 = 0.0;
        for dr in &directions {
            for dp in &directions {
                for (sr, sp) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0)] {
                    // the true p and r: the computed ones plus errors of the stated sizes
                    let p_true: Vec<f64> = p
                        .iter()
                        .zip(dp)
                        .map(|(a, d)| a + sp * e_p * norm(&p) * d)
                        .collect();
                    let r_true: Vec<f64> = r
                        .iter()
                        .zip(dr)
                        .map(|(a, d)| a + sr * e_r * norm(&r) * d)
                        .collect();
                    let moved = (norm(&r_true) / norm(&p_true) - m).abs();
                    largest = largest.max(moved);
                }
            }
        }
        assert!(largest <= bound * (1.0 + 1e-12), "{largest} > {bound}");
        assert!(largest >= 0.95 * bound, "{largest} vs {bound}");
    }

    /// Through the traces (a residual without a stated error) the bound is
    /// (e_s ||s|| / ||p|| + e_p + m e_p) / (1 - e_p); with both routes the smaller; a misfit
    /// whose own estimate states an error (a converging one, a linear scene's round-off)
    /// keeps it; without a stated prediction error there is no bound.
    #[test]
    fn traces_route_own_estimates_and_missing_errors() {
        let own = Estimate::dimensionless(0.1, 0.103, 0.106, LAYERED_7);
        assert_eq!(own.verdict, Verdict::Refine);
        let mut refine = waveform(0.0);
        (refine.error, refine.verdict) = (None, Verdict::Refine);
        let b = Estimate::relative_misfit(own, &waveform(0.02), &waveform(0.01), &refine, 1.1);
        assert!((b.error.unwrap() - (0.02 * 1.1 + 0.01 + 0.1 * 0.01) / 0.99).abs() < 1e-15);
        let linear = Estimate::dimensionless(1e-13, 2e-13, 1e-13, LAYERED_7);
        let kept = Estimate::relative_misfit(
            linear,
            &waveform(0.02),
            &waveform(0.01),
            &waveform(0.5),
            1.0,
        );
        assert_eq!(kept, linear);
        let converging = Estimate::dimensionless(0.1, 0.1004, 0.1012, LAYERED_7);
        assert_eq!(converging.verdict, Verdict::Reliable);
        let kept = Estimate::relative_misfit(
            converging,
            &waveform(0.02),
            &waveform(0.01),
            &waveform(0.5),
            1.0,
        );
        assert_eq!(kept, converging);
        // Both routes: the smaller, here through the traces (0.5 * 0.1 > 0.02 * 1.1 + 0.01).
        let both =
            Estimate::relative_misfit(own, &waveform(0.02), &waveform(0.01), &waveform(0.5), 1.1);
        assert!((both.error.unwrap() - (0.02 * 1.1 + 0.01 + 0.1 * 0.01) / 0.99).abs() < 1e-15);
        let via_residual =
            Estimate::relative_misfit(own, &waveform(0.02), &waveform(0.01), &waveform(0.1), 1.1);
        assert!((via_residual.error.unwrap() - 0.1 * (0.1 + 0.01) / 0.99).abs() < 1e-15);
        let none = Estimate::relative_misfit(own, &waveform(0.02), &refine, &waveform(0.05), 1.0);
        assert_eq!(none, own);
    }

    /// The peak ratio's bound r (e_n + e_d) / (1 - e_d) is reached at the corner where the
    /// numerator's peak grows and the denominator's shrinks, and no peaks within the stated
    /// errors move the ratio further; a ratio whose own estimate holds keeps it.
    #[test]
    fn peak_ratio_bound_is_the_corner() {
        let own = Estimate::dimensionless(0.06, 0.063, 0.066, LAYERED_7);
        assert_eq!(own.verdict, Verdict::Refine);
        let (e_n, e_d) = (0.04, 0.01);
        let stated = Estimate::peak_ratio(own, Some(e_n), &waveform(e_d));
        assert_eq!(stated.verdict, Verdict::Propagated);
        let bound = stated.error.unwrap();
        let mut largest: f64 = 0.0;
        for k in 0..=20 {
            for j in 0..=20 {
                let n = 0.06 * (1.0 - e_n + 2.0 * e_n * k as f64 / 20.0);
                let d = 1.0 - e_d + 2.0 * e_d * j as f64 / 20.0;
                largest = largest.max((n / d - 0.06).abs());
            }
        }
        assert!((largest - bound).abs() < 1e-15, "{largest} vs {bound}");
        let converging = Estimate::dimensionless(0.1, 0.1004, 0.1012, LAYERED_7);
        assert_eq!(
            Estimate::peak_ratio(converging, Some(e_n), &waveform(e_d)),
            converging
        );
        assert_eq!(Estimate::peak_ratio(own, None, &waveform(e_d)), own);
    }

    /// A sum's error through its terms is e_a ||a|| / ||n|| + e_b ||b|| / ||n||, or its own
    /// where that is smaller; neither stated, none.
    #[test]
    fn sum_error_takes_the_smaller_route() {
        let mut refine = waveform(0.0);
        (refine.error, refine.verdict) = (None, Verdict::Refine);
        let terms = [(&waveform(0.01), 20.0), (&waveform(0.02), 19.0)];
        assert!((Estimate::sum_error(&refine, terms).unwrap() - 0.58).abs() < 1e-15);
        assert_eq!(Estimate::sum_error(&waveform(0.1), terms), Some(0.1));
        assert_eq!(
            Estimate::sum_error(&refine, [(&waveform(0.01), 20.0), (&refine, 19.0)]),
            None
        );
    }

    /// Side-window traces moved by their stated relative L2 errors, in every direction tried,
    /// never move the asymmetry beyond the bound, and scalings (the corners) reach it.
    #[test]
    fn asymmetry_bound_holds_for_errors_of_the_stated_size() {
        let before = [0.2, -0.1, 0.05, 0.0];
        let after = [0.3, 0.1, -0.2, 0.1];
        let energy = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
        let asymmetry = |a: &[f64], b: &[f64]| (energy(a) - energy(b)) / (energy(a) + energy(b));
        let a = asymmetry(&after, &before);
        let own = Estimate::dimensionless(a, a + 0.03, a + 0.06, LAYERED_7);
        assert_eq!(own.verdict, Verdict::Refine);
        let (e_b, e_a) = (0.05, 0.03);
        let stated = Estimate::energy_asymmetry(
            own,
            [energy(&before), energy(&after)],
            [Some(e_b), Some(e_a)],
        );
        assert_eq!(stated.verdict, Verdict::Propagated);
        let bound = stated.error.unwrap();
        let unit = |v: &[f64]| -> Vec<f64> { v.iter().map(|x| x / norm(v)).collect() };
        let moved = |x: &[f64], e: f64, d: &[f64]| -> Vec<f64> {
            x.iter().zip(d).map(|(v, w)| v + e * norm(x) * w).collect()
        };
        let mut largest: f64 = 0.0;
        for db in [
            unit(&before),
            unit(&before).iter().map(|v| -v).collect(),
            unit(&after),
        ] {
            for da in [
                unit(&after),
                unit(&after).iter().map(|v| -v).collect(),
                unit(&before),
            ] {
                let shifted = asymmetry(&moved(&after, e_a, &da), &moved(&before, e_b, &db));
                largest = largest.max((shifted - a).abs());
            }
        }
        assert!(largest <= bound * (1.0 + 1e-12), "{largest} > {bound}");
        assert!(largest >= bound * (1.0 - 1e-12), "{largest} vs {bound}");
    }
}
