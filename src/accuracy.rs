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
//! a fall slower than that but of at least 16% per order (the contact at GLL nodes) gets a
//! fitted tail instead (the slow-fall fit, `slow_fall` below).
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
//! alone was 0.64-0.72 and 0.94-1.11 of the truth. The stated error combines the two
//! sources (a waveform's in quadrature, a scalar's as a sum), and the estimate names the
//! larger as the dominant source
//! ([`Estimate::dominant_source`]). The companions along x keep the scene's orders across and
//! its step, so that they see the error along x alone: with their own rows and steps they
//! saw an error across of their own, 1.4-12x the true error at oblique incidence
//! (docs/src/validation/normal-incidence.md).

use crate::error::Result;
use crate::signal::{self, Signal};
use serde::{Deserialize, Serialize};

mod propagated;

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
    /// the ratio per order, and d_1 / (2^q - 1) = d_1 rho / (1 - rho) is the geometric tail. The estimate expects a halving per order
    /// (order 1: the tail is d_1; at the slowest fall accepted, rho = 2^-0.5, it is 2.4 d_1).
    /// A faster fall between the lower orders overstates the fall at the top order (the error
    /// from the orders across and from the time step does not fall with the order along x),
    /// so it gives the bound d_1. A slower fall (rho from 2^-0.5 to [`SLOWEST_FALL`]) gets
    /// the tail fitted to the three runs' differences (the slow-fall fit of the module doc).
    /// docs/src/validation/default-experiment.md checks each against a converged reference.
    Orders,
}

impl Refinement {
    /// The order q the estimate expects: each refinement step divides the error by 2^q.
    pub fn order(self) -> f64 {
        match self {
            Refinement::ElementSizes => 2.0,
            Refinement::Orders => 1.0,
        }
    }

    /// The first companion, as the messages name it.
    fn first_companion(self) -> &'static str {
        match self {
            Refinement::ElementSizes => "2h",
            Refinement::Orders => "order p-1",
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
    /// A measure computed from waveforms (a misfit between two traces) whose own values do
    /// not converge: `error` bounds it through the waveforms' stated errors
    /// ([`Estimate::relative_misfit`]).
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
}

impl Source {
    /// As the messages name it.
    pub fn name(self) -> &'static str {
        match self {
            Source::Refinement => "along x",
            Source::Across => "across the layers",
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
    /// On spectral elements whose error along x falls slowly with the order (observed order
    /// below 1 - [`ORDER_TOLERANCE`]): the correlation c of consecutive orders' errors the
    /// estimate fitted (the slow-fall fit of the module doc); 1 for a scalar.
    #[serde(default)]
    pub slow_correlation: Option<f64>,
}

/// The error across the layers per unit difference d_y to the companion one order higher
/// across: sqrt(2), the geometric mean of the bounds 1 and 2 that hold when an order across
/// at least halves the error (module doc).
pub const ACROSS_TAIL: f64 = std::f64::consts::SQRT_2;

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
        let mut slow_correlation = None;
        let sign_change = verdict != Verdict::MeshIndependent && d1 * d2 < 0.0;
        match refinement {
            Refinement::ElementSizes if sign_change => (error, verdict) = (None, Verdict::Refine),
            Refinement::ElementSizes => {}
            Refinement::Orders if sign_change => (error, verdict) = alternating(d1.abs(), d2.abs()),
            Refinement::Orders if verdict == Verdict::Refine => {
                // One number's errors at the three orders lie on one line: c = 1.
                if let Some(tail) = slow_fall(d1.abs(), d2.abs(), None) {
                    (error, verdict, slow_correlation) =
                        (Some(tail.error), Verdict::Reliable, Some(tail.correlation));
                }
            }
            Refinement::Orders => {}
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
            slow_correlation,
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
        let mut slow_correlation = None;
        if verdict == Verdict::Refine && refinement == Refinement::Orders {
            if let Some(tail) = slow_fall(d1, d2, Some(d13)) {
                (error, verdict) = (Some(tail.error), Verdict::Reliable);
                slow_correlation = Some(tail.correlation);
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
            slow_correlation,
        })
    }

    /// Estimate of a dimensional scalar from its `values` on the main discretisation and on
    /// each companion in the order [`crate::scene::SceneSpec::companions`] gives them: the
    /// refinement's two, then the one across the layers where there is one.
    pub fn scalar_of(values: &[f64], refinement: Refinement) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(values)?;
        let e = Self::scalar(fine, medium, coarse, refinement);
        let scale = values.iter().fold(0f64, |m, v| m.max(v.abs()));
        Ok(across_of(values, e, scale, |a| (fine - a).abs()))
    }

    /// [`Estimate::dimensionless`] from the values on the main discretisation and on each
    /// companion (see [`Estimate::scalar_of`]).
    pub fn dimensionless_of(values: &[f64], refinement: Refinement) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(values)?;
        let e = Self::dimensionless(fine, medium, coarse, refinement);
        let scale = values.iter().fold(1f64, |m, v| m.max(v.abs()));
        Ok(across_of(values, e, scale, |a| (fine - a).abs()))
    }

    /// [`Estimate::waveform`] from the traces on the main discretisation and on each
    /// companion (see [`Estimate::scalar_of`]); the companion across is compared with the
    /// main trace by the relative L2 difference over `window`.
    pub fn waveform_of(
        traces: &[&Signal],
        window: (f64, f64),
        refinement: Refinement,
    ) -> Result<Estimate> {
        let [fine, medium, coarse] = first_three(traces)?;
        let e = Self::waveform(fine, medium, coarse, window, refinement)?;
        match traces.get(3) {
            None => Ok(e),
            Some(across) => Ok(e.with_across(relative_difference(fine, across, window)?, 1.0)),
        }
    }

    /// This estimate with the error across the layers `d` added (see the module doc) to a
    /// stated error ([`Estimate::combined`]); a bound along x stays one unless the error
    /// across dominates it (then the sum is an estimate, "reliable"); as the whole error when
    /// the refinement's companions agree (then "reliable" unless `d` too is round-off of
    /// `scale`); a "refine" stays one.
    fn with_across(mut self, d: f64, scale: f64) -> Estimate {
        self.across = Some(d);
        let e_y = ACROSS_TAIL * d;
        match self.verdict {
            Verdict::MeshIndependent if d > ROUND_OFF * scale => {
                (self.error, self.verdict) = (Some(e_y), Verdict::Reliable);
            }
            Verdict::MeshIndependent | Verdict::Refine | Verdict::Propagated => {}
            // A bound along x plus the estimate across, where the estimate across dominates,
            // is an estimate: sqrt(2) d_y lies within sqrt(2) of the error across, either way
            // (the smoke preset's cracked misfit, its error mostly across, was 1.3x its bound
            // d_1 + sqrt(2) d_y).
            Verdict::UpperBound if self.error.is_some_and(|e| e_y >= e) => {
                self.error = self.error.map(|e| self.combined(e, e_y));
                self.verdict = Verdict::Reliable;
            }
            Verdict::Reliable | Verdict::UpperBound => {
                self.error = self.error.map(|e| self.combined(e, e_y));
            }
        }
        self
    }

    /// The error across the layers, [`ACROSS_TAIL`] times the difference to the companion
    /// across ([`Estimate::across`]), when the estimate has that companion.
    pub fn across_error(&self) -> Option<f64> {
        self.across.map(|d| ACROSS_TAIL * d)
    }

    /// The error of two sources e_x and e_y: a waveform's in quadrature, sqrt(e_x^2 + e_y^2)
    /// (the relative L2 norm of the sum of two error signals of different origin, whose
    /// cross term averages out), a scalar's as the sum e_x + e_y (one number has no such
    /// average: the sources may add).
    fn combined(&self, e_x: f64, e_y: f64) -> f64 {
        if self.waveform {
            e_x.hypot(e_y)
        } else {
            e_x + e_y
        }
    }

    /// The part of the stated error the refinement's companions see (the inverse of
    /// [`Estimate::combined`] with the error across), when the estimate separates them.
    fn refinement_part(&self) -> Option<f64> {
        let (across, error) = (self.across_error()?, self.error?);
        Some(if self.waveform {
            (error * error - across * across).max(0.0).sqrt()
        } else {
            (error - across).max(0.0)
        })
    }

    /// The larger of the error's sources, when the estimate separates them (it has a
    /// companion across and states an error).
    pub fn dominant_source(&self) -> Option<Source> {
        let (across, along) = (self.across_error()?, self.refinement_part()?);
        Some(if across >= along {
            Source::Across
        } else {
            Source::Refinement
        })
    }

    /// "observed order 1.90", then, when the estimate has a companion across, each source's
    /// part and the dominant one ("observed order 3.7; along x 2.8e-3, across the layers
    /// 1.6e-3, along x dominant").
    fn detail(&self) -> String {
        let order = self
            .observed_order
            .map_or("-".to_string(), |q| format!("{q:.2}"));
        let across = match (
            self.across_error(),
            self.refinement_part(),
            self.dominant_source(),
        ) {
            (Some(a), Some(x), Some(source)) => format!(
                "; {} {x:.2e}, {} {a:.2e}, {} dominant",
                Source::Refinement.name(),
                Source::Across.name(),
                source.name()
            ),
            (Some(a), _, _) => format!("; {} {a:.2e}", Source::Across.name()),
            _ => String::new(),
        };
        let slow = self.slow_correlation.map_or(String::new(), |c| {
            format!(", slow fall along x: consecutive orders' errors correlate {c:.2}")
        });
        format!("observed order {order}{slow}{across}")
    }

    /// "1.2300e-2 +- 4.50e-4 (observed order 1.90)", "... (error unknown, ...: refine)";
    /// for a waveform "relative L2 error 3.1e-2 (observed order 1.95)" or why unknown; with a
    /// companion across, the share of the error across the layers and the dominant source.
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
                "{:.4e}, error below {e:.2e} (bound from the errors of the traces it compares)",
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
    /// waveforms (relative L2), "err 3.1% (mostly across)" when the error across the layers
    /// dominates; "0.138 +- 4.5e-4", "0.138 (err ?, 2h: 1.3e-2)" for scalars.
    pub fn brief(&self) -> String {
        if self.waveform {
            let pct = |x: f64| format!("{:.1}%", 100.0 * x);
            let mostly = match self.dominant_source() {
                Some(Source::Across) => " (mostly across)",
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
/// companions'), refusing fewer; a fourth is the companion across, and more is an error.
fn first_three<T: Copy>(values: &[T]) -> Result<[T; 3]> {
    match values {
        [a, b, c] | [a, b, c, _] => Ok([*a, *b, *c]),
        _ => Err(crate::error::Error::invalid(
            "companions",
            values.len(),
            "an estimate takes the main discretisation's value and its companions': 3 values, \
             or 4 with the companion across the layers",
        )),
    }
}

/// `e` with the error across the layers from the fourth of `values`, if there is one
/// (`difference` of the main value and it).
fn across_of(values: &[f64], e: Estimate, scale: f64, difference: impl Fn(f64) -> f64) -> Estimate {
    match values.get(3) {
        Some(&across) => e.with_across(difference(across), scale),
        None => e,
    }
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

/// Slowest fall per order along x the slow-fall fit (module doc) takes: the ratio
/// d_1 / d_2 at most 2^-0.25 = 0.84 (observed order at least 0.25). Nearer 1 the three runs
/// span too little of the fall for a tail to rest on them: "refine".
pub const SLOWEST_FALL: f64 = 0.840_896_415_253_714_6;

/// (error, verdict) of a scalar on spectral elements whose differences d_1 = Q_p - Q_p-1 and
/// d_2 = Q_p-1 - Q_p-2 change sign (sizes `d1`, `d2`): its errors along x alternate in sign
/// (the contact at GLL nodes moves the misfit of the cracked scene either way from one order
/// to the next). If they do, E_p-1 = -E_p / rho with rho = d_1 / d_2, d_1 = E_p (1 + 1 / rho)
/// and |E_p| = d_1 rho / (1 + rho) < d_1: d_1 is stated as a bound, for any fall down to
/// [`SLOWEST_FALL`] per order (d_1 / 3 would be the error at a halving per order, but a sign
/// change does not prove the errors alternate: errors of one sign that stagnate change the
/// differences' sign too). Slower, or growing differences: "refine".
fn alternating(d1: f64, d2: f64) -> (Option<f64>, Verdict) {
    if d1 > 0.0 && d1 <= SLOWEST_FALL * d2 {
        (Some(d1), Verdict::UpperBound)
    } else {
        (None, Verdict::Refine)
    }
}

/// The error along x at order p fitted to a slow fall, with the correlation it took.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SlowFall {
    error: f64,
    correlation: f64,
}

/// The error along x at order p when the companions' differences fall slower than a halving
/// per order (the contact acts at GLL nodes, whose places change with the order, and the
/// contact law is not smooth: measured 21-30% per order on the default experiment's
/// cracked traces). Model: the errors E_p, E_p-1, E_p-2 of the three runs have sizes
/// a, a / rho, a / rho^2 (rho = d_1 / d_2, the observed ratio per order) and consecutive
/// errors correlate c (E_p and E_p-2: c^2). Then
///
///   d_1^2 = a^2 (1 + rho^-2 - 2 c / rho),  d_13^2 = a^2 (1 + rho^-4 - 2 c^2 / rho^2),
///
/// with d_13 = |Q_p - Q_p-2| the third difference (`None` for a scalar whose differences keep
/// their sign: its errors lie on one line, c = 1; with a sign change, [`alternating`]): a
/// quadratic in c whose root in [-1, 1] ([`fitted_correlation`]) gives
/// a = d_1 / sqrt(1 + rho^-2 - 2 c / rho). Aligned errors (c = 1, d_13 = d_1 + d_2) give the
/// geometric tail d_1 rho / (1 - rho); uncorrelated ones (c = 0) d_1 rho / sqrt(1 + rho^2). On
/// the default experiment's cracked traces the fitted c is 0.37-0.98 and the stated error
/// 1.16-1.36x the error against the references (docs/src/validation/default-experiment.md).
/// `None` when the differences do not fall by [`SLOWEST_FALL`] per order or no c in [-1, 1]
/// fits them.
fn slow_fall(d1: f64, d2: f64, d13: Option<f64>) -> Option<SlowFall> {
    if !(d1 > 0.0 && d2 > 0.0 && d1 <= SLOWEST_FALL * d2) {
        return None;
    }
    let rho = d1 / d2;
    let correlation = match d13 {
        None => 1.0,
        Some(d13) => fitted_correlation(rho, (d13 / d1).powi(2))?,
    };
    let spread = 1.0 + 1.0 / (rho * rho) - 2.0 * correlation / rho;
    (spread > 0.0).then(|| SlowFall {
        error: d1 / spread.sqrt(),
        correlation,
    })
}

/// The root c in [-1, 1] of c^2 - r rho c + (r (rho^2 + 1) - rho^2 - rho^-2) / 2 = 0, with
/// r = (d_13 / d_1)^2 ([`slow_fall`]); the larger if both are. Aligned errors put a root at
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
mod tests {
    use super::*;

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
    fn a_slow_fall_along_x_states_the_fitted_tail() {
        // Contact at GLL nodes: the error along x falls 20-30% per order and the orders'
        // errors are partly aligned. The fit recovers the error and the correlation exactly
        // for correlations from aligned to opposed, and for a scalar (aligned).
        for (rho, c) in [
            (0.73, 0.37),
            (0.72, 0.97),
            (0.79, 0.81),
            (0.75, 1.0),
            (0.8, 0.0),
            (0.72, -0.3),
        ] {
            let a = 4e-3;
            let [p, p1, p2] = slow_traces(a, rho, c);
            let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), Refinement::Orders).unwrap();
            let truth = a / (1.0 + a * a).sqrt();
            assert_eq!(e.verdict, Verdict::Reliable, "rho {rho}, c {c}: {e:?}");
            assert!(
                (e.error.unwrap() / truth - 1.0).abs() < 1e-6,
                "rho {rho}, c {c}: {e:?} vs {truth}"
            );
            assert!(
                (e.slow_correlation.unwrap() - c).abs() < 1e-6,
                "rho {rho}, c {c}: {e:?}"
            );
            assert!(
                e.describe().contains("slow fall along x"),
                "{}",
                e.describe()
            );
        }
        let q = |p: i32| 1.0 + 0.01 * 0.75f64.powi(p);
        let e = Estimate::scalar(q(7), q(6), q(5), Refinement::Orders);
        assert_eq!(e.verdict, Verdict::Reliable);
        assert!(
            (e.error.unwrap() / (0.01 * 0.75f64.powi(7)) - 1.0).abs() < 1e-9,
            "{e:?}"
        );
        assert_eq!(e.slow_correlation, Some(1.0));
        // Stored with the sweep's points (postcard: every field written, with or without a fit).
        for stored in [e, Estimate::scalar(1.0, 1.0, 1.0, Refinement::Orders)] {
            let back: Estimate =
                crate::sweep::decode(&crate::sweep::encode(&stored).unwrap()).unwrap();
            assert_eq!(back, stored);
        }
    }

    #[test]
    fn a_fall_slower_than_the_slowest_or_unfit_says_refine() {
        // 10% per order: too little of the fall to rest a tail on.
        let [p, p1, p2] = slow_traces(4e-3, 0.9, 0.5);
        let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), Refinement::Orders).unwrap();
        assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
        assert!(e.error.is_none() && e.slow_correlation.is_none());
        // Triangles keep their order-2 test: a slow fall of element sizes is not fitted.
        let e = Estimate::waveform(&p, &p1, &p2, (0.0, 1.0), Refinement::ElementSizes).unwrap();
        assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
        // No correlation fits differences with d_13 > d_1 + d_2 (not a triangle).
        assert!(slow_fall(1.0, 1.3, Some(2.5)).is_none());
        // A scalar whose differences change sign and grow: refine.
        let e = Estimate::scalar(1.003, 1.007, 1.004, Refinement::Orders);
        assert_eq!(e.verdict, Verdict::Refine, "{e:?}");
    }

    /// A scalar whose errors along x alternate in sign, E_p = a (-rho)^(p - 7): the bound d_1
    /// = a (1 + 1 / rho), above the error at every fall the estimate takes; growing
    /// differences or too slow a fall say "refine"; on triangles any sign change does.
    #[test]
    fn a_scalars_alternating_errors_along_x_are_bounded_by_d1() {
        let a = 2e-3;
        for rho in [0.8, 0.5, 0.1] {
            let q = |p: i32| 0.05 + a * (-1.0f64 / rho).powi(7 - p);
            let e = Estimate::scalar(q(7), q(6), q(5), Refinement::Orders);
            assert_eq!(e.verdict, Verdict::UpperBound, "rho {rho}: {e:?}");
            let bound = e.error.unwrap();
            assert!(
                (bound / (a * (1.0 + 1.0 / rho)) - 1.0).abs() < 1e-9,
                "rho {rho}: {bound}"
            );
            assert!(e.slow_correlation.is_none());
            let t3 = Estimate::scalar(q(7), q(6), q(5), Refinement::ElementSizes);
            assert_eq!(t3.verdict, Verdict::Refine);
        }
        for rho in [0.9, 1.2] {
            let q = |p: i32| 0.05 + a * (-1.0f64 / rho).powi(7 - p);
            let e = Estimate::scalar(q(7), q(6), q(5), Refinement::Orders);
            assert_eq!(e.verdict, Verdict::Refine, "rho {rho}: {e:?}");
        }
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
        let e = Estimate::scalar_of(&values, Refinement::Orders).unwrap();
        assert_eq!(e.verdict, Verdict::Reliable);
        let expected = along + ACROSS_TAIL * across;
        assert!((e.error.unwrap() - expected).abs() < 1e-12, "{e:?}");
        assert_eq!(e.across, Some((q(7) - values[3]).abs()));
        assert_eq!(e.dominant_source(), Some(Source::Across));
        let text = e.describe();
        assert!(text.contains("across the layers dominant"), "{text}");
        let small =
            Estimate::scalar_of(&[q(7), q(6), q(5), q(7) + 0.1 * along], Refinement::Orders)
                .unwrap();
        assert_eq!(small.dominant_source(), Some(Source::Refinement));
        // Three values: no companion across, nothing separated.
        let three = Estimate::scalar_of(&values[..3], Refinement::Orders).unwrap();
        assert_eq!((three.across, three.dominant_source()), (None, None));
        assert!(Estimate::scalar_of(&values[..2], Refinement::Orders).is_err());
        assert!(Estimate::scalar_of(&[1.0; 5], Refinement::Orders).is_err());
        // A bound along x (a fall of 8x per order: d_1 = 1.4e-3) stays a bound with a smaller
        // error across, and becomes an estimate where the error across dominates it.
        let fast = |p: i32| 1.0 + 0.1 * 8f64.powi(-(p - 4));
        let bound = (fast(7) - fast(6)).abs();
        for (d_y, verdict) in [
            (0.1 * bound, Verdict::UpperBound),
            (bound, Verdict::Reliable),
        ] {
            let e = Estimate::scalar_of(
                &[fast(7), fast(6), fast(5), fast(7) + d_y],
                Refinement::Orders,
            )
            .unwrap();
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
        let e =
            Estimate::dimensionless_of(&[0.5, 0.5, 0.5, 0.5 + 2e-4], Refinement::Orders).unwrap();
        assert_eq!(e.verdict, Verdict::Reliable);
        assert!((e.error.unwrap() - ACROSS_TAIL * 2e-4).abs() < 1e-15);
        assert_eq!(e.dominant_source(), Some(Source::Across));
        // Round-off across as well: mesh-independent.
        let same =
            Estimate::dimensionless_of(&[0.5, 0.5, 0.5, 0.5 + 1e-14], Refinement::Orders).unwrap();
        assert_eq!(same.verdict, Verdict::MeshIndependent);
        // A "refine" along x stays one: no error is claimed.
        let refine = Estimate::scalar_of(&[1.0, 1.2, 1.0, 1.1], Refinement::Orders).unwrap();
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
        let e =
            Estimate::waveform_of(&[&f, &f, &f, &across], (0.0, 1e-7), Refinement::Orders).unwrap();
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
        let along = Estimate::waveform(&f, &m, &c, (0.0, 1e-7), Refinement::Orders).unwrap();
        let both =
            Estimate::waveform_of(&[&f, &m, &c, &across], (0.0, 1e-7), Refinement::Orders).unwrap();
        let expected = along
            .error
            .unwrap()
            .hypot(ACROSS_TAIL * both.across.unwrap());
        assert!((both.error.unwrap() - expected).abs() < 1e-15, "{both:?}");
    }
}
