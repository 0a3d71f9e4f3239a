//! Discretisation error estimates by Richardson extrapolation.
//!
//! A quantity Q computed on the main discretisation (element sizes h, its own stable step)
//! and on two companions with element sizes 2h and 4h (the same laminate draw, each with
//! its own step; on spectral elements orders p - 1 and p - 2 at the scene's step, below)
//! converges as Q_h = Q + C h^p + ... in the asymptotic range. Then
//!
//!   error(Q_h) ~ (Q_h - Q_2h) / (2^p - 1),
//!   observed order q = log2(|Q_2h - Q_4h| / |Q_h - Q_2h|).
//!
//! The estimate is trusted only when q is close to the scheme's order p (|q - p| <= 0.5:
//! then, if the error follows a power law, the estimate is within a factor 0.75..1.4 of the
//! truth). When the differences shrink faster (q > p + 0.5) the same number is an upper
//! bound of the error. Otherwise the runs are not in the asymptotic range, the verdict says
//! "refine" and no error is claimed; so does, on triangles, a scalar whose differences change
//! sign (oscillating convergence; on spectral elements its errors along x alternate,
//! `alternating` below). Waves that travel many wavelengths converge late (their phase
//! error grows with distance), which is exactly when the check matters. On spectral elements
//! a waveform's error along x is fitted instead, wherever it falls by at least 16% per order
//! (the tail fit, `fitted_tail` below; a fast fall from low-order companions keeps the
//! bound): its three runs give three distances, enough to tell how far the orders' errors
//! are aligned. A scalar's fall slower than a halving per order (the contact at GLL nodes)
//! gets the same fit with its errors on one line; differences that change sign without
//! falling, the scatter of errors of one size (`scatter` below).
//!
//! For waveforms the differences are relative L2 norms over a window,
//! d_1 = ||y_h - y_2h|| / ||y_h||, d_2 = ||y_2h - y_4h|| / ||y_h||, and the same formulas
//! give the relative L2 error of y_h. Traces of the companions are resampled to the main
//! run's step before they are compared.
//!
//! The refinement ratio is nominally 2; in a laminate whose thin layers get one element row
//! at every size, or whose step is set by such a layer, the effective ratio is smaller. That
//! shows as an observed order away from p, and the verdict says so.
//!
//! On spectral elements the two companions are lower along x, so they see little of the
//! error across the layers. A third companion has every element row one order higher across
//! (its own, shorter step; [`crate::scene::SceneSpec::companions`]). Its difference
//! d_y = |Q_p - Q_across| is the main run's error across e_y less the companion's own,
//! rho e_y: d_y = (1 - rho) e_y. If one order across at least halves the error (rho <= 1/2,
//! what the estimate along x expects of an order along x), e_y lies between d_y and 2 d_y;
//! the estimate states their geometric mean sqrt(2) d_y ([`ACROSS_TAIL`]), within a factor
//! sqrt(2) of either end. Measured: the companion across is 2.5-3.4x more accurate than the
//! presets at normal incidence and 3-12x at oblique incidence (rho = 0.08-0.4), where d_y
//! alone was 0.64-0.72 and 0.94-1.11 of the truth.
//!
//! Where a crack's faces touch, a fourth companion is the scene at half its step (the same
//! elements, orders and rows). The time-dispersion transforms remove the step's error of
//! linear motion, not the contact's: the moments the faces close and slip fall on the step's
//! grid. Its difference d_t = |Q_dt - Q_dt/2| is the error in time e_t = d_t / (1 - 2^-q) for
//! an error of order q in the step: 2 d_t at first order (an impact), 4/3 d_t at second
//! (smooth motion); where the contact's chatter makes a value scatter with the step instead
//! of converging (independent errors of one size at both steps), d_t / sqrt(2). The estimate
//! states sqrt(2) d_t ([`STEP_TAIL`]), within a factor 2 of all three. Measured on the quick
//! preset's cracked misfit: the companions along x and across agree to 4e-5, the half step
//! moves it 3.4e-4, and the references that refine everything are 3.3e-4 apart
//! (docs/src/validation/default-experiment.md).
//!
//! The stated error combines the sources (a waveform's in quadrature, a scalar's as a sum, or
//! in quadrature where its error along x is a scatter, a sign of its own),
//! and the estimate names the largest as the dominant source
//! ([`Estimate::dominant_source`]). The companions along x keep the scene's orders across and
//! its step, so that they see the error along x alone: with their own rows and steps they
//! saw an error across of their own, 1.4-12x the true error at oblique incidence
//! (docs/src/validation/normal-incidence.md).

use crate::error::Result;
use crate::signal::{self, Signal};
use serde::{Deserialize, Serialize};

mod propagated;
pub(crate) use propagated::smaller;

/// How the two companions of an estimate are made from the main discretisation, which fixes
/// the order of convergence the estimate expects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Refinement {
    /// Linear triangles at 2x and 4x the element sizes (h, 2h, 4h). With lumped mass and
    /// central differences the dispersion error is O(h^2) in space and O(dt^2) in time, dt
    /// tied to h: order 2.
    ElementSizes,
    /// Spectral elements on the same elements at orders p - 1 and p - 2 along x (the scene's
    /// orders across, its step; on a Gmsh mesh, in both directions). Their error falls
    /// exponentially with the order, e_p ~ C rho^p: the formulas above hold with 2^-q = rho,
    /// the ratio per order, and d_1 / (2^q - 1) = d_1 rho / (1 - rho) is the geometric tail
    /// of errors that are aligned. A waveform's errors at consecutive orders need not be
    /// (a plane wave's phase errors along x are nearly orthogonal from one order to the next,
    /// so d_1 is about sqrt(E_p^2 + E_p-1^2)): its tail is fitted to the three runs'
    /// differences with the correlation they show ([`fitted_tail`]), at any fall down to
    /// [`SLOWEST_FALL`] per order (a fall faster than a halving from companions below order
    /// [`FAST_FALL_FROM_ORDER`]: the bound d_1). A scalar expects a halving per order (order
    /// 1: the tail is d_1); a faster fall gives the bound d_1, a slower one the tail of
    /// aligned errors, differences that change sign without falling the scatter of errors
    /// of one size ([`scatter`]).
    /// docs/src/validation/default-experiment.md checks each against a converged reference.
    Orders {
        /// The main run's order p (along x on the layered rectangle, in both directions on a
        /// Gmsh mesh); the companions are at p - 1 and p - 2.
        top: usize,
        /// Whether a companion across the layers follows them (the layered rectangle's; a
        /// Gmsh mesh has no direction across).
        #[serde(default = "layered")]
        across: bool,
        /// Whether the scene's values depend smoothly on its discretisation, so that a
        /// scalar's values that scatter along x measure its error ([`scatter`]): not where
        /// a crack's faces follow the instantaneous Coulomb law, which amplifies every change
        /// of the discretisation (the quick preset's cracked side-lobe asymmetry is off by
        /// 2.5x what its companions' scatter states there;
        /// docs/src/validation/default-experiment.md).
        #[serde(default = "layered")]
        smooth: bool,
    },
}

/// An estimate stored before [`Refinement::Orders::across`] and
/// [`Refinement::Orders::smooth`] were recorded: the layered rectangle's, a scene without an
/// instantaneous Coulomb law.
fn layered() -> bool {
    true
}

impl Refinement {
    /// The order q the estimate expects: each refinement step divides the error by 2^q.
    pub fn order(self) -> f64 {
        match self {
            Refinement::ElementSizes => 2.0,
            Refinement::Orders { .. } => 1.0,
        }
    }

    /// The sources of the companions that may follow the refinement's two, in order: across
    /// the layers (the layered rectangle's), then in time (at half the step, where a crack's
    /// faces touch; [`crate::scene::SceneSpec::companions`]).
    fn added_sources(self) -> &'static [Source] {
        match self {
            Refinement::Orders { across: true, .. } => &[Source::Across, Source::Step],
            Refinement::Orders { across: false, .. } => &[Source::Step],
            Refinement::ElementSizes => &[],
        }
    }

    /// The first companion, as the messages name it.
    fn first_companion(self) -> &'static str {
        match self {
            Refinement::ElementSizes => "2h",
            Refinement::Orders { .. } => "order p-1",
        }
    }

    /// The fall per order between the top two runs, rho_top = rho (p - 1) / p, from the fall
    /// rho = d_1 / d_2 the three runs show (the tail fit, [`fitted_tail`]; `rho` itself for
    /// element sizes). d_2 spans the lower orders, and a resolved wave's convergence
    /// accelerates with the order: the dispersion error of spectral elements goes roughly as
    /// (k h / 2p)^(2p) (Ainsworth and Wajid 2009), a ratio per order falling as p^-2, which
    /// would make the top fall ((p - 1) / p)^2 of the one below; a fall the contact at GLL
    /// nodes limits (the cracked traces) does not accelerate. (p - 1) / p is the geometric
    /// mean of the two, within a factor p / (p - 1) (1.14-1.25 at orders 5-8) of either.
    fn top_fall(self, rho: f64) -> f64 {
        match self {
            Refinement::ElementSizes => rho,
            Refinement::Orders { top, .. } => {
                let p = top.max(3) as f64;
                rho * (p - 1.0) / p
            }
        }
    }
}
/// Largest |observed order - scheme order| for which an estimate is trusted.
pub const ORDER_TOLERANCE: f64 = 0.5;
/// Relative differences below this are round-off: the quantity does not depend on the mesh.
const ROUND_OFF: f64 = 1e-10;

/// What the companion runs say about an estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The observed order is close to the scheme's: the estimate is reliable.
    Reliable,
    /// Differences shrink faster than the scheme's order predicts (observed order above
    /// it): the error is at most the stated bound d_1 / (2^p - 1).
    UpperBound,
    /// The runs are not in the asymptotic range: no error is claimed, refine.
    Refine,
    /// The quantity does not change between discretisations (to round-off).
    MeshIndependent,
    /// A measure computed from waveforms (a misfit between two traces, a peak ratio, a
    /// side-lobe asymmetry, a spectral shift) whose own values do not converge: `error` bounds
    /// it through the waveforms' stated errors ([`Estimate::relative_misfit`],
    /// [`Estimate::peak_ratio`], [`Estimate::energy_asymmetry`],
    /// [`Estimate::mean_frequency_shift`]).
    Propagated,
}

/// Where a discretisation error comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// What the refinement's two companions see: the element sizes (triangles), the order
    /// along x (spectral elements).
    Refinement,
    /// The orders across the layers (spectral elements' third companion).
    Across,
    /// The time step where a crack's faces touch (spectral elements' fourth companion, at
    /// half the step, on scenes with contact).
    Step,
}

impl Source {
    /// As the messages name it.
    pub fn name(self) -> &'static str {
        match self {
            Source::Refinement => "along x",
            Source::Across => "across the layers",
            Source::Step => "in time",
        }
    }
}

/// A quantity with its discretisation error estimate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Whether this is a waveform's relative L2 error (true) or a scalar's error.
    pub waveform: bool,
    /// How the companions were made.
    pub refinement: Refinement,
    /// Value on the main discretisation (for a waveform: 0, the errors are relative).
    pub value: f64,
    /// Values on the two companions, 2h and 4h or orders p - 1 and p - 2 (waveforms: the
    /// relative differences d_1 = |y_h - y_2h| and d_2 = |y_2h - y_4h| over |y_h|).
    pub companions: [f64; 2],
    /// Estimated |error| of `value` (waveforms: relative L2 error), or its upper bound;
    /// `None` when the runs are not in the asymptotic range.
    pub error: Option<f64>,
    /// Observed order of convergence, when the differences allow one.
    pub observed_order: Option<f64>,
    /// Whether to trust `error`.
    pub verdict: Verdict,
    /// The difference d_y = |Q - Q_across| (waveforms: relative L2) to the companion one
    /// order higher across every row, when the estimate has one; `error` includes the error
    /// across it gives, [`Estimate::across_error`].
    #[serde(default)]
    pub across: Option<f64>,
    /// The difference d_t = |Q - Q_dt/2| (waveforms: relative L2) to the companion at half the
    /// step, when the estimate has one (scenes with contact); `error` includes the error in
    /// time it gives, [`Estimate::step_error`].
    #[serde(default)]
    pub step: Option<f64>,
    /// On spectral elements, where the estimate along x is the fitted tail ([`fitted_tail`]):
    /// the correlation c of consecutive orders' errors it took; 1 for a scalar (a slow fall
    /// only).
    #[serde(default)]
    pub correlation: Option<f64>,
    /// Whether the error along x is the scatter of errors of one size from order to order
    /// ([`scatter`]: the contact at GLL nodes, each order another perturbation), a random
    /// error whose sign is independent of the other sources' ([`Estimate::combined`]).
    #[serde(default)]
    pub scatters_along_x: bool,
}

/// The error across the layers per unit difference d_y to the companion one order higher
/// across: sqrt(2), the geometric mean of the bounds 1 and 2 that hold when an order across
/// at least halves the error (module doc).
pub const ACROSS_TAIL: f64 = std::f64::consts::SQRT_2;

/// The error in time per unit difference d_t to the companion at half the step: sqrt(2),
/// within a factor 2 of the error at first order in the step (2 d_t), at second (4/3 d_t) and
/// of a value that scatters with the step (d_t / sqrt(2); module doc).
pub const STEP_TAIL: f64 = std::f64::consts::SQRT_2;

impl Estimate {
    /// Estimate for a scalar from its values at h, 2h, 4h (scheme order `order`).
    pub fn scalar(fine: f64, medium: f64, coarse: f64, refinement: Refinement) -> Estimate {
        let scale = fine.abs().max(medium.abs()).max(coarse.abs());
        Self::with_scale(fine, medium, coarse, scale, refinement)
    }

    /// Estimate for a dimensionless measure of order one (a misfit, a residual, an
    /// asymmetry): changes below 1e-10 in absolute terms are round-off, so a measure that is
    /// round-off at every resolution (a linear scene's misfit) is mesh-independent.
    pub fn dimensionless(fine: f64, medium: f64, coarse: f64, refinement: Refinement) -> Estimate {
        let scale = fine.abs().max(medium.abs()).max(coarse.abs()).max(1.0);
        Self::with_scale(fine, medium, coarse, scale, refinement)
    }

    /// A scalar whose differences change sign (Q_h - Q_2h against Q_2h - Q_4h) converges
    /// with oscillation, not as a power law: on triangles its verdict is "refine" whatever
    /// the ratio. On spectral elements its errors at the three orders alternate in sign
    /// ([`alternating`]).
    fn with_scale(
        fine: f64,
        medium: f64,
        coarse: f64,
        scale: f64,
        refinement: Refinement,
    ) -> Estimate {
        let (d1, d2) = (fine - medium, medium - coarse);
        let (mut error, observed_order, mut verdict) =
            classify(d1.abs(), d2.abs(), scale, refinement.order());
        let mut correlation = None;
        let mut scatters_along_x = false;
        let sign_change = verdict != Verdict::MeshIndependent && d1 * d2 < 0.0;
        match refinement {
            Refinement::ElementSizes if sign_change => (error, verdict) = (None, Verdict::Refine),
            Refinement::ElementSizes => {}
            Refinement::Orders { .. } => {
                if sign_change {
                    (error, verdict) = alternating(d1.abs(), d2.abs());
                } else if verdict == Verdict::Refine {
                    // One number's errors at the three orders lie on one line: c = 1.
                    if let Some(tail) = fitted_tail(d1.abs(), d2.abs(), None, refinement) {
                        (error, verdict, correlation) =
                            (Some(tail.error), Verdict::Reliable, Some(tail.correlation));
                    }
                }
                // Differences that neither fall nor keep their sign: errors of one size
                // (d_13 = |Q_p - Q_p-2| = |d_1 + d_2|; aligned ones give c >= 1, "refine").
                if verdict == Verdict::Refine
                    && matches!(refinement, Refinement::Orders { smooth: true, .. })
                {
                    if let Some(s) = scatter(d1.abs(), d2.abs(), (d1 + d2).abs()) {
                        (error, verdict, correlation) =
                            (Some(s.error), Verdict::Reliable, Some(s.correlation));
                        scatters_along_x = true;
                    }
                }
            }
        }
        Estimate {
            waveform: false,
            refinement,
            value: fine,
            companions: [medium, coarse],
            error,
            observed_order,
            verdict,
            across: None,
            step: None,
            correlation,
            scatters_along_x,
        }
    }

    /// Estimate of a waveform's relative L2 error over `window` (s) from the traces at h, 2h,
    /// 4h, the companions resampled to the main trace's step.
    pub fn waveform(
        fine: &Signal,
        medium: &Signal,
        coarse: &Signal,
        window: (f64, f64),
        refinement: Refinement,
    ) -> Result<Estimate> {
        let on_fine = |s: &Signal| -> Result<Signal> {
            let r = signal::resample(s, fine.dt_s)?;
            Ok(r.window(window.0, window.1)?)
        };
        let f = fine.window(window.0, window.1)?;
        let (m, c) = (on_fine(medium)?, on_fine(coarse)?);
        let n = f.len().min(m.len()).min(c.len());
        let norm = |a: &[f64], b: &[f64]| -> f64 {
            a[..n]
                .iter()
                .zip(&b[..n])
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let size = f.samples[..n].iter().map(|x| x * x).sum::<f64>().sqrt();
        let (d1, d2, d13) = if size > 0.0 {
            (
                norm(&f.samples, &m.samples) / size,
                norm(&m.samples, &c.samples) / size,
                norm(&f.samples, &c.samples) / size,
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        let (mut error, observed_order, mut verdict) = classify(d1, d2, 1.0, refinement.order());
        let mut correlation = None;
        let fitted = match refinement {
            Refinement::ElementSizes => false,
            Refinement::Orders { top, .. } => match verdict {
                Verdict::MeshIndependent | Verdict::Propagated => false,
                Verdict::UpperBound => top >= FAST_FALL_FROM_ORDER + 2,
                Verdict::Reliable | Verdict::Refine => true,
            },
        };
        let mut scatters_along_x = false;
        if fitted {
            let tail = fitted_tail(d1, d2, Some(d13), refinement);
            let scattered = tail.is_none().then(|| scatter(d1, d2, d13)).flatten();
            if let Some(tail) = tail.or(scattered) {
                (error, verdict) = (Some(tail.error), Verdict::Reliable);
                correlation = Some(tail.correlation);
                scatters_along_x = scattered.is_some();
            }
        }
        Ok(Estimate {
            waveform: true,
            refinement,
            value: 0.0,
            companions: [d1, d2],
            error,
            observed_order,
            verdict,
            across: None,
            step: None,
            correlation,
            scatters_along_x,
        })
    }

    /// Estimate of a dimensional scalar from its `values` on the main discretisation and on
    /// each companion in the order [`crate::scene::SceneSpec::companions`] gives them: the
    /// refinement's two, then the one across the layers where there is one, then the one at
    /// half the step where there is one.
    pub fn scalar_of(values: &[f64], refinement: Refinement) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(values, refinement)?;
        let e = Self::scalar(fine, medium, coarse, refinement);
        let scale = values.iter().fold(0f64, |m, v| m.max(v.abs()));
        Ok(sources_of(values, e, scale, |a| (fine - a).abs()))
    }

    /// [`Estimate::dimensionless`] from the values on the main discretisation and on each
    /// companion (see [`Estimate::scalar_of`]).
    pub fn dimensionless_of(values: &[f64], refinement: Refinement) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(values, refinement)?;
        let e = Self::dimensionless(fine, medium, coarse, refinement);
        let scale = values.iter().fold(1f64, |m, v| m.max(v.abs()));
        Ok(sources_of(values, e, scale, |a| (fine - a).abs()))
    }

    /// [`Estimate::waveform`] from the traces on the main discretisation and on each
    /// companion (see [`Estimate::scalar_of`]); the companions across and at half the step
    /// are compared with the main trace by the relative L2 difference over `window`.
    pub fn waveform_of(
        traces: &[&Signal],
        window: (f64, f64),
        refinement: Refinement,
    ) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(traces, refinement)?;
        let mut e = Self::waveform(fine, medium, coarse, window, refinement)?;
        for (&source, other) in refinement.added_sources().iter().zip(&traces[3..]) {
            e = e.with_source(source, relative_difference(fine, other, window)?, 1.0);
        }
        Ok(e)
    }

    /// This estimate with the error of `source` (across the layers or in time) from the
    /// difference `d` to its companion added (see the module doc) to a stated error
    /// ([`Estimate::combined`]); a bound along x stays one unless the added error dominates it
    /// (then the sum is an estimate, "reliable"); as the whole error when the refinement's
    /// companions agree (then "reliable" unless `d` too is round-off of `scale`); a "refine"
    /// stays one.
    fn with_source(mut self, source: Source, d: f64, scale: f64) -> Estimate {
        let e_s = match source {
            Source::Across => {
                self.across = Some(d);
                ACROSS_TAIL * d
            }
            Source::Step => {
                self.step = Some(d);
                STEP_TAIL * d
            }
            Source::Refinement => unreachable!("the refinement's companions are the first two"),
        };
        match self.verdict {
            Verdict::MeshIndependent if d > ROUND_OFF * scale => {
                (self.error, self.verdict) = (Some(e_s), Verdict::Reliable);
            }
            Verdict::MeshIndependent | Verdict::Refine | Verdict::Propagated => {}
            // A bound plus an estimate that dominates it is an estimate: sqrt(2) d lies within
            // 2 of the error it estimates, either way (the smoke preset's cracked misfit, its
            // error mostly across, was 1.3x its bound d_1 + sqrt(2) d_y).
            Verdict::UpperBound if self.error.is_some_and(|e| e_s >= e) => {
                self.error = self.error.map(|e| self.combined(e, e_s));
                self.verdict = Verdict::Reliable;
            }
            Verdict::Reliable | Verdict::UpperBound => {
                self.error = self.error.map(|e| self.combined(e, e_s));
            }
        }
        self
    }

    /// The error across the layers, [`ACROSS_TAIL`] times the difference to the companion
    /// across ([`Estimate::across`]), when the estimate has that companion.
    pub fn across_error(&self) -> Option<f64> {
        self.across.map(|d| ACROSS_TAIL * d)
    }

    /// The error in time, [`STEP_TAIL`] times the difference to the companion at half the
    /// step ([`Estimate::step`]), when the estimate has that companion.
    pub fn step_error(&self) -> Option<f64> {
        self.step.map(|d| STEP_TAIL * d)
    }

    /// The error of two sources e_x and e_y: a waveform's in quadrature, sqrt(e_x^2 + e_y^2)
    /// (the relative L2 norm of the sum of two error signals of different origin, whose
    /// cross term averages out), a scalar's as the sum e_x + e_y (one number has no such
    /// average: the sources may add), unless its error along x is a scatter
    /// ([`Estimate::scatters_along_x`]): that is a random error of a stated size and a sign of
    /// its own, and the sources are then combined as independent errors, in quadrature (the
    /// sum is their worst case; checked against the references on the quick preset's cracked
    /// PI residual and side-lobe asymmetry, docs/src/validation/default-experiment.md).
    fn combined(&self, e_x: f64, e_y: f64) -> f64 {
        if self.in_quadrature() {
            e_x.hypot(e_y)
        } else {
            e_x + e_y
        }
    }

    /// Whether the sources combine in quadrature ([`Estimate::combined`]).
    fn in_quadrature(&self) -> bool {
        self.waveform || self.scatters_along_x
    }

    /// The errors the companions beyond the refinement's two give (across the layers, in
    /// time), those the estimate has.
    fn added_sources(&self) -> impl Iterator<Item = (Source, f64)> {
        [
            (Source::Across, self.across_error()),
            (Source::Step, self.step_error()),
        ]
        .into_iter()
        .filter_map(|(source, e)| Some((source, e?)))
    }

    /// The part of the stated error the refinement's companions see (the inverse of
    /// [`Estimate::combined`] with the added sources' errors), when the estimate separates
    /// them (it has a companion across or in time and states an error).
    fn refinement_part(&self) -> Option<f64> {
        let error = self.error?;
        let mut added = self.added_sources().map(|(_, e)| e).peekable();
        added.peek()?;
        Some(if self.in_quadrature() {
            (error * error - added.map(|e| e * e).sum::<f64>())
                .max(0.0)
                .sqrt()
        } else {
            (error - added.sum::<f64>()).max(0.0)
        })
    }

    /// Each source's part of the stated error, along x first, when the estimate separates
    /// them.
    fn parts(&self) -> Option<Vec<(Source, f64)>> {
        let along = self.refinement_part()?;
        Some(
            std::iter::once((Source::Refinement, along))
                .chain(self.added_sources())
                .collect(),
        )
    }

    /// The largest of the error's sources, when the estimate separates them (it has a
    /// companion across or in time and states an error); a tie goes to the later source.
    pub fn dominant_source(&self) -> Option<Source> {
        self.parts()?
            .into_iter()
            .reduce(|best, next| if next.1 >= best.1 { next } else { best })
            .map(|(source, _)| source)
    }

    /// "observed order 1.90", then, when the estimate has a companion across or in time,
    /// each source's part and the dominant one ("observed order 3.7; along x 2.8e-3, across
    /// the layers 1.6e-3, in time 4.1e-4, along x dominant").
    fn detail(&self) -> String {
        let order = self
            .observed_order
            .map_or("-".to_string(), |q| format!("{q:.2}"));
        let list = |parts: &[(Source, f64)]| {
            parts
                .iter()
                .map(|(source, e)| format!("{} {e:.2e}", source.name()))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let sources = match (self.parts(), self.dominant_source()) {
            (Some(parts), Some(source)) => {
                format!("; {}, {} dominant", list(&parts), source.name())
            }
            _ => {
                let added: Vec<_> = self.added_sources().collect();
                if added.is_empty() {
                    String::new()
                } else {
                    format!("; {}", list(&added))
                }
            }
        };
        let along_x = if self.scatters_along_x {
            "errors along x scatter"
        } else {
            "tail along x fitted"
        };
        let fitted = self.correlation.map_or(String::new(), |c| {
            format!(", {along_x}: consecutive orders' errors correlate {c:.2}")
        });
        format!("observed order {order}{fitted}{sources}")
    }

    /// "1.2300e-2 +- 4.50e-4 (observed order 1.90)", "... (error unknown, ...: refine)";
    /// for a waveform "relative L2 error 3.1e-2 (observed order 1.95)" or why unknown; with
    /// companions across or in time, each source's share and the dominant one.
    pub fn describe(&self) -> String {
        let detail = self.detail();
        if self.waveform {
            return match (self.verdict, self.error) {
                (Verdict::Reliable, Some(e)) => format!("relative L2 error {e:.2e} ({detail})"),
                (Verdict::UpperBound | Verdict::Propagated, Some(e)) => {
                    format!("relative L2 error below {e:.2e} ({detail})")
                }
                (Verdict::MeshIndependent, _) => "unchanged between meshes".into(),
                _ => format!(
                    "relative L2 error unknown (differs from {} by {:.2e}, {detail}): refine",
                    self.refinement.first_companion(),
                    self.companions[0]
                ),
            };
        }
        match (self.verdict, self.error) {
            (Verdict::Reliable, Some(e)) => format!("{:.4e} +- {e:.2e} ({detail})", self.value),
            (Verdict::UpperBound, Some(e)) => {
                format!("{:.4e}, error below {e:.2e} ({detail})", self.value)
            }
            (Verdict::Propagated, Some(e)) => format!(
                "{:.4e}, error below {e:.2e} (bound from the errors of the traces it is computed from)",
                self.value
            ),
            (Verdict::MeshIndependent, _) => {
                format!("{:.4e} (unchanged between meshes)", self.value)
            }
            _ => format!(
                "{:.4e} (error unknown, {detail}, change from {} {:.2e}: refine)",
                self.value,
                self.refinement.first_companion(),
                (self.value - self.companions[0]).abs()
            ),
        }
    }

    /// A short form for figure titles: "err 3.1%", "err < 3.1%", "err ? (2h: 30%)" for
    /// waveforms (relative L2), "err 3.1% (mostly across)" or "(mostly in time)" when the
    /// error across the layers or in time dominates; "0.138 +- 4.5e-4", "0.138 (err ?, 2h: 1.3e-2)" for scalars.
    pub fn brief(&self) -> String {
        if self.waveform {
            let pct = |x: f64| format!("{:.1}%", 100.0 * x);
            let mostly = match self.dominant_source() {
                Some(Source::Across) => " (mostly across)",
                Some(Source::Step) => " (mostly in time)",
                _ => "",
            };
            return match (self.verdict, self.error) {
                (Verdict::Reliable, Some(e)) => format!("err {}{mostly}", pct(e)),
                (Verdict::UpperBound | Verdict::Propagated, Some(e)) => {
                    format!("err < {}{mostly}", pct(e))
                }
                (Verdict::MeshIndependent, _) => "mesh-independent".into(),
                _ => format!(
                    "err ? ({}: {})",
                    self.refinement.first_companion(),
                    pct(self.companions[0])
                ),
            };
        }
        let change = (self.value - self.companions[0]).abs();
        let v = if (1e-2..1e3).contains(&self.value.abs()) {
            format!("{:.3}", self.value)
        } else {
            format!("{:.3e}", self.value)
        };
        match (self.verdict, self.error) {
            (Verdict::Reliable, Some(e)) => format!("{v} +- {e:.1e}"),
            (Verdict::UpperBound | Verdict::Propagated, Some(e)) => format!("{v} +- < {e:.1e}"),
            (Verdict::MeshIndependent, _) => format!("{v} (mesh-independent)"),
            _ => format!(
                "{v} (err ?, {}: {change:.1e})",
                self.refinement.first_companion()
            ),
        }
    }
}

/// The first three of `values` (the main discretisation's and the refinement's two
/// companions'), refusing fewer; those after them are the companions across and at half the
/// step that `refinement` may have ([`Refinement::added_sources`]), and more is an error.
fn first_three<T: Copy>(values: &[T], refinement: Refinement) -> Result<[T; 3]> {
    let most = 3 + refinement.added_sources().len();
    match values {
        [a, b, c, ..] if values.len() <= most => Ok([*a, *b, *c]),
        _ => Err(crate::error::Error::invalid(
            "companions",
            values.len(),
            format!(
                "an estimate takes the main discretisation's value and its companions': 3 \
                 values, up to {most} with the companions {}",
                match refinement.added_sources() {
                    [] => "2h and 4h only",
                    [_] => "of lower order and the one at half the step",
                    _ => "along x, the one across the layers and the one at half the step",
                }
            ),
        )),
    }
}

/// `e` with the errors of the companions beyond the refinement's two, those there are
/// ([`Refinement::added_sources`]; `difference` of the main value and each).
fn sources_of(
    values: &[f64],
    e: Estimate,
    scale: f64,
    difference: impl Fn(f64) -> f64,
) -> Estimate {
    e.refinement
        .added_sources()
        .iter()
        .zip(&values[3..])
        .fold(e, |e, (&source, &v)| {
            e.with_source(source, difference(v), scale)
        })
}

/// Relative L2 difference ||fine - other|| / ||fine|| over `window`, `other` resampled to
/// `fine`'s step (0 when `fine` is zero there).
fn relative_difference(fine: &Signal, other: &Signal, window: (f64, f64)) -> Result<f64> {
    let f = fine.window(window.0, window.1)?;
    let o = signal::resample(other, fine.dt_s)?.window(window.0, window.1)?;
    let n = f.len().min(o.len());
    let size = f.samples[..n].iter().map(|x| x * x).sum::<f64>().sqrt();
    if size == 0.0 {
        return Ok(0.0);
    }
    let diff = f.samples[..n]
        .iter()
        .zip(&o.samples[..n])
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    Ok(diff / size)
}

/// Slowest fall per order along x the tail fit ([`fitted_tail`]) takes: the ratio
/// d_1 / d_2 at most 2^-0.25 = 0.84 (observed order at least 0.25). Nearer 1 the three runs
/// span too little of the fall for a tail to rest on them: "refine".
pub const SLOWEST_FALL: f64 = 0.840_896_415_253_714_6;

/// The lowest order of the coarser companion (p - 2) whose fall faster than a halving per
/// order the tail fit takes for a waveform. The resolved waves of the checks fall up to 7x
/// per order from companions at orders 4-6 and keep falling that fast at the top
/// (tests/estimates.rs, tests/along_layers.rs); from orders 2 and 3 a fast fall can be a
/// companion crossing the resolution threshold, not a rate the top order keeps (a Gmsh mesh
/// at order 4: 7-13x from order 2 to 3, then about 2x to 4; tests/unstructured_scene.rs), and
/// the estimate states the bound d_1 there.
pub const FAST_FALL_FROM_ORDER: usize = 4;

/// (error, verdict) of a scalar on spectral elements whose differences d_1 = Q_p - Q_p-1 and
/// d_2 = Q_p-1 - Q_p-2 change sign (sizes `d1`, `d2`): its errors along x alternate in sign
/// (the contact at GLL nodes moves the misfit of the cracked scene either way from one order
/// to the next). If they do, E_p-1 = -E_p / rho with rho = d_1 / d_2, d_1 = E_p (1 + 1 / rho)
/// and |E_p| = d_1 rho / (1 + rho) < d_1: d_1 is stated as a bound, for any fall down to
/// [`SLOWEST_FALL`] per order (d_1 / 3 would be the error at a halving per order, but a sign
/// change does not prove the errors alternate: errors of one sign that stagnate change the
/// differences' sign too). Slower, or growing differences: "refine" here, and the scatter of
/// errors of one size where the three values fit it ([`scatter`]).
fn alternating(d1: f64, d2: f64) -> (Option<f64>, Verdict) {
    if d1 > 0.0 && d1 <= SLOWEST_FALL * d2 {
        (Some(d1), Verdict::UpperBound)
    } else {
        (None, Verdict::Refine)
    }
}

/// The error along x at order p fitted to the three runs, with the correlation it took.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FittedTail {
    error: f64,
    correlation: f64,
}

/// The error along x at order p from the three runs' differences. Model: the errors E_p,
/// E_p-1, E_p-2 have sizes a, a / rho_1, a / (rho_1 rho_2) and consecutive errors correlate c
/// (E_p and E_p-2: c^2). Then
///
///   d_1^2 = a^2 (1 + rho_1^-2 - 2 c / rho_1),
///   d_13^2 = a^2 (1 + (rho_1 rho_2)^-2 - 2 c^2 / (rho_1 rho_2)),
///
/// with d_13 = |Q_p - Q_p-2| the third difference (`None` for a scalar whose differences keep
/// their sign: its errors lie on one line, c = 1; with a sign change, [`alternating`]). At a
/// constant fall (rho_1 = rho_2 = rho = d_1 / d_2) the second is a quadratic in c whose root
/// in [-1, 1] ([`fitted_correlation`]) gives c; the error is then the first solved for a with
/// the top fall rho_1 = [`Refinement::top_fall`] of rho. Aligned errors (c = 1) give the
/// geometric tail d_1 rho_1 / (1 - rho_1), uncorrelated ones (c = 0) d_1 rho_1 /
/// sqrt(1 + rho_1^2). Where it is used: a waveform's falls of 16% per order or faster
/// ([`Estimate::waveform`]), a scalar's slow falls only. Measured c: 0.37-0.98 on the default
/// experiment's cracked traces, where the contact at GLL nodes makes the error fall 21-30%
/// per order (docs/src/validation/default-experiment.md), and -0.7 to 0.4 for plane waves,
/// whose phase errors at consecutive orders are far from aligned (tests/estimates.rs,
/// tests/along_layers.rs). `None` when the differences do not fall by [`SLOWEST_FALL`] per
/// order or no c in [-1, 1] fits them.
fn fitted_tail(d1: f64, d2: f64, d13: Option<f64>, refinement: Refinement) -> Option<FittedTail> {
    if !(d1 > 0.0 && d2 > 0.0 && d1 <= SLOWEST_FALL * d2) {
        return None;
    }
    let rho = d1 / d2;
    let correlation = match d13 {
        None => 1.0,
        Some(d13) => fitted_correlation(rho, (d13 / d1).powi(2))?,
    };
    let top = refinement.top_fall(rho);
    let spread = 1.0 + 1.0 / (top * top) - 2.0 * correlation / top;
    (spread > 0.0).then(|| FittedTail {
        error: d1 / spread.sqrt(),
        correlation,
    })
}

/// The error along x at order p of a waveform or a scalar whose differences do not fall by
/// [`SLOWEST_FALL`] per order (d_1 > 0.84 d_2, or growing), where [`fitted_tail`] has no tail
/// to rest on (a scalar's: where they also change sign, d_13 = |d_1 + d_2|; differences of
/// one sign that do not fall give c >= 1). The contact at GLL nodes does this on the cracked
/// scene: each order puts the crack faces' nodes elsewhere, so each order's contact error is
/// another perturbation of about the same size (the inverted focusing drive's trace at
/// quick: d_1 = 0.55%, d_2 = 0.57%; the cracked PI residual at quick under the default
/// friction law: 0.14694, 0.14627, 0.14637 at orders 7, 6, 5, c = 0.43). Model: errors of
/// one size a, consecutive ones correlating c (E_p and E_p-2: c^2), so that d_1^2 = d_2^2 =
/// 2 a^2 (1 - c) and d_13^2 = 2 a^2 (1 - c^2); with dbar^2 = (d_1^2 + d_2^2) / 2,
/// c = (d_13 / dbar)^2 - 1 and a = dbar / sqrt(2 (1 - c)).
/// Taken where c <= 1/2: the errors mostly independent, a at most dbar. Errors that are
/// more aligned and do not fall are a slow convergence of unknown extent (aligned errors
/// falling 10% per order give c = 3): `None`, "refine".
fn scatter(d1: f64, d2: f64, d13: f64) -> Option<FittedTail> {
    let mean_square = (d1 * d1 + d2 * d2) / 2.0;
    if !(mean_square > 0.0) || d1 <= SLOWEST_FALL * d2 {
        return None;
    }
    let correlation = (d13 * d13 / mean_square - 1.0).max(-1.0);
    (correlation <= 0.5).then(|| FittedTail {
        error: (mean_square / (2.0 * (1.0 - correlation))).sqrt(),
        correlation,
    })
}

/// The root c in [-1, 1] of c^2 - r rho c + (r (rho^2 + 1) - rho^2 - rho^-2) / 2 = 0, with
/// r = (d_13 / d_1)^2 ([`fitted_tail`]); the larger if both are. Aligned errors put a root at
/// c = 1 up to round-off: taken as 1.
fn fitted_correlation(rho: f64, r: f64) -> Option<f64> {
    let b = r * rho;
    let k = (r * (rho * rho + 1.0) - rho * rho - 1.0 / (rho * rho)) / 2.0;
    let discriminant = b * b - 4.0 * k;
    if discriminant < 0.0 {
        return None;
    }
    let roots = [
        (b + discriminant.sqrt()) / 2.0,
        (b - discriminant.sqrt()) / 2.0,
    ];
    roots
        .into_iter()
        .find(|c| (-1.0..=1.0 + 1e-9).contains(c))
        .map(|c| c.min(1.0))
}

/// (error, observed order, verdict) from the differences d1 = |Q_h - Q_2h| and
/// d2 = |Q_2h - Q_4h| of a quantity of size `scale`.
fn classify(d1: f64, d2: f64, scale: f64, order: f64) -> (Option<f64>, Option<f64>, Verdict) {
    if d1 <= ROUND_OFF * scale && d2 <= ROUND_OFF * scale {
        return (Some(d1), None, Verdict::MeshIndependent);
    }
    let observed = (d1 > 0.0 && d2 > 0.0).then(|| (d2 / d1).log2());
    let richardson = d1 / (2f64.powf(order) - 1.0);
    match observed {
        Some(q) if (q - order).abs() <= ORDER_TOLERANCE => {
            (Some(richardson), Some(q), Verdict::Reliable)
        }
        Some(q) if q > order => (Some(richardson), Some(q), Verdict::UpperBound),
        _ => (None, observed, Verdict::Refine),
    }
}

#[cfg(test)]
mod tests;
