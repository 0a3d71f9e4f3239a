//! Losses: viscoelastic materials whose quality factor Q is nearly constant over a band, as
//! standard linear solids in parallel (a generalised Zener body; Emmerich and Korn 1987,
//! Moczo and Kristek 2005; SPECFEM2D's attenuation is the same model).
//!
//! The stress is the unrelaxed stiffness's minus what the relaxation mechanisms l = 1..L take
//! back (Voigt order xx, yy, xy, engineering shear strain):
//!
//!   sigma = C_U eps - sum_l DC_l e_l,    tau_l e_l' + e_l = eps,    DC_l = sum_k y_kl C_k
//!
//! e_l is the strain low-passed with relaxation time tau_l (a memory variable). The unrelaxed
//! stiffness splits into two positive semi-definite parts C_k, each relaxing with its own
//! weights y_kl (so each has its own Q), which keeps every DC_l positive semi-definite and the
//! relaxed stiffness C_U - sum_l DC_l positive definite while sum_l y_kl < 1:
//! - orthotropic plies (`normal_shear`): the normal block (C11, C12, C22) takes Q_P and C66
//!   takes Q_S, so P waves along either axis have exactly Q_P and S waves along them Q_S;
//! - isotropic materials (`bulk_shear`): kappa = lambda + mu (plane) takes Q_kappa and the
//!   deviatoric part mu takes Q_mu = Q_S, with 1/Q_kappa = ((kappa + mu)/Q_P - mu/Q_S)/kappa,
//!   so P waves have Q_P to first order in 1/Q in every direction (the split does not turn).
//!
//! In the frequency domain (time dependence e^{i w t}) a part's modulus is
//! M(w) = C_k [1 - sum_l y_kl / (1 + i w tau_l)], and Q(w) = Re M / Im M. Q(w) = Q0 holds
//! exactly where sum_l y_l (w tau_l + 1/Q0) / (1 + w^2 tau_l^2) = 1/Q0, linear in the
//! weights: they are its least-squares solution on frequencies across the band
//! ([`constant_q_weights`]; SPECFEM2D's linear first guess, without its nonlinear polish, which
//! the placement of the relaxation frequencies here makes unnecessary: [`relaxation_times`]).
//!
//! The constants a scene gives are the moduli at a reference frequency: each part is scaled
//! so that a wave of that part alone has the elastic phase velocity there
//! ([`unrelaxed_scale`]). Materials then hold C_U in `stiffness_pa`, so the stability limit
//! and the spectral-element order rule see the stiffest operator.

use crate::error::{Error, Result};
use crate::material::{relative_modulus, Material, Relaxation, RelaxingPart};
use nalgebra::{DMatrix, DVector};
use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Losses of a scene's materials, as a scene spec gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttenuationSpec {
    /// The band [f1, f2] over which Q is nearly constant (Hz): the transducers' band.
    pub band_hz: [f64; 2],
    /// Relaxation mechanisms L (1..=[`MAX_MECHANISMS`]); 3 fit one decade within 0.3%.
    #[serde(default = "default_mechanisms")]
    pub mechanisms: usize,
    /// Frequency at which the given constants hold (Hz); default sqrt(f1 f2).
    #[serde(default)]
    pub reference_hz: Option<f64>,
    /// Quality factors by material name; a material not listed stays elastic.
    pub quality: BTreeMap<String, QualitySpec>,
}

/// Quality factors of one material: of P waves and of S waves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QualitySpec {
    /// Q of P waves (along the axes for an orthotropic material).
    pub q_p: f64,
    /// Q of S waves.
    pub q_s: f64,
}

impl AttenuationSpec {
    /// Losses of the report's materials over the report's band (0.2-2 MHz), 3 mechanisms,
    /// the constants holding at the band's geometric centre. The quality factors are read
    /// second-hand, from the material list of the Dispersion Calculator (A. Huber, DLR;
    /// `MaterialList_Isotropic.txt`, `MaterialList_Orthotropic.txt`), which stores losses
    /// per wavelength alpha_lambda (Q = pi / alpha_lambda) or as complex moduli
    /// (Q = Re / Im), without a frequency:
    /// - epoxy: entry `Epoxy_Ono_2020_Viscoelastic` (attributed to K. Ono, Appl. Sci. 10,
    ///   2020), 0.0867 Np/wavelength for P and 0.1636 for S: Q_P = 36, Q_S = 19. The same
    ///   list's `Epoxy_Disperse_Viscoelastic` (0.04, 0.1) gives 79 and 31: the lossier entry
    ///   is taken.
    /// - the fabric plies: entry `CarbonEpoxy_Castaings_Viscoelastic`, a unidirectional
    ///   carbon/epoxy ply with a 2% imaginary part on every modulus: Q = 50 for P and S. The
    ///   list's `CarbonEpoxy_Hernando_2015_Viscoelastic` is 6x less lossy (Q 300-400);
    ///   woven and cross-ply laminates attenuate more than unidirectional ones.
    ///
    /// Ono's tables were not read here: treat these as a plausible lossy end of the range,
    /// not as measurements of the report's specimen.
    pub fn report_materials() -> AttenuationSpec {
        let q = |q_p, q_s| QualitySpec { q_p, q_s };
        AttenuationSpec {
            band_hz: [2e5, 2e6],
            mechanisms: default_mechanisms(),
            reference_hz: None,
            quality: [
                ("epoxy".to_string(), q(36.0, 19.0)),
                ("fabric_0_90".to_string(), q(50.0, 50.0)),
                ("fabric_45_45".to_string(), q(50.0, 50.0)),
            ]
            .into(),
        }
    }
}

fn default_mechanisms() -> usize {
    3
}

/// The most relaxation mechanisms a material takes.
pub const MAX_MECHANISMS: usize = 8;

/// Largest relative error of Q over the band a fit may leave before it is refused.
const MAX_Q_ERROR: f64 = 0.02;

/// Largest dt / tau_l: the trapezoidal memory update sees w as (2/dt) tan(w dt/2), within 1%
/// of w up to w dt = 0.35 (tan(0.175)/0.175 = 1.0103).
pub const MAX_STEP_PER_TAU: f64 = 0.35;

/// Relaxation times tau_l = 1/(2 pi f_l), f_l log-spaced over the band widened by a fifth of
/// its log-width at each end: with L = 3 over a decade the fit then holds Q within 0.3%,
/// where relaxation frequencies at the band's ends (SPECFEM2D's choice) leave 3%.
pub fn relaxation_times([f1, f2]: [f64; 2], mechanisms: usize) -> Vec<f64> {
    let (lo, hi) = (f1.ln(), f2.ln());
    let (lo, hi) = (lo - 0.2 * (hi - lo), hi + 0.2 * (hi - lo));
    (0..mechanisms)
        .map(|l| {
            let f = match mechanisms {
                1 => (0.5 * (lo + hi)).exp(),
                _ => (lo + (hi - lo) * l as f64 / (mechanisms - 1) as f64).exp(),
            };
            1.0 / (2.0 * PI * f)
        })
        .collect()
}

/// Frequencies (Hz) log-spaced over `band`, `n` of them, ends included.
fn log_spaced([f1, f2]: [f64; 2], n: usize) -> impl Iterator<Item = f64> {
    (0..n).map(move |k| f1 * (f2 / f1).powf(k as f64 / (n - 1) as f64))
}

/// The weights that hold Q(w) at `quality` over `band` with relaxation times `tau_s`: least
/// squares of sum_l y_l (w tau_l + 1/Q) / (1 + w^2 tau_l^2) = 1/Q (module docs) on 10 L
/// frequencies log-spaced over the band; with the largest |Q(w)/Q - 1| on 400. `None` where
/// a weight is not positive or they sum to 1 or more (the relaxed stiffness would not be
/// positive definite: Q too low; at 3 mechanisms over a decade below about 0.9).
pub fn constant_q_weights(quality: f64, band: [f64; 2], tau_s: &[f64]) -> Option<(Vec<f64>, f64)> {
    let rows: Vec<f64> = log_spaced(band, 10 * tau_s.len()).collect();
    let a = DMatrix::from_fn(rows.len(), tau_s.len(), |k, l| {
        let wt = 2.0 * PI * rows[k] * tau_s[l];
        (wt + 1.0 / quality) / (1.0 + wt * wt)
    });
    let b = DVector::from_element(rows.len(), 1.0 / quality);
    let y = (a.transpose() * &a).cholesky()?.solve(&(a.transpose() * b));
    let weights: Vec<f64> = y.iter().copied().collect();
    if weights.iter().any(|&y| !(y > 0.0)) || !(weights.iter().sum::<f64>() < 1.0) {
        return None;
    }
    let error = log_spaced(band, 400).fold(0.0_f64, |worst, f| {
        let m = relative_modulus(2.0 * PI * f, tau_s, &weights);
        worst.max((m.re / m.im / quality - 1.0).abs())
    });
    Some((weights, error))
}

/// C_U / C_ref of a part relaxing with `weights`: a plane wave of that modulus alone then has
/// the phase velocity of C_ref at `omega_ref`. c = w / Re k with k = w sqrt(rho / M(w)), so
/// c = sqrt(C_U / rho) / Re (M/C_U)^(-1/2), and C_U = C_ref [Re (M/C_U)^(-1/2)]^2.
pub fn unrelaxed_scale(omega_ref: f64, tau_s: &[f64], weights: &[f64]) -> f64 {
    relative_modulus(omega_ref, tau_s, weights)
        .powf(-0.5)
        .re
        .powi(2)
}

/// A plane wave of modulus `modulus` (Pa, complex) in density `rho` at angular frequency
/// `omega`: k = w sqrt(rho / M) (Im k < 0 for a decaying wave, time dependence e^{i w t});
/// returns (phase velocity w / Re k (m/s), attenuation -Im k (Np/m)).
pub fn plane_wave(rho: f64, modulus: Complex64, omega: f64) -> (f64, f64) {
    let k = omega * (rho / modulus).sqrt();
    (omega / k.re, -k.im)
}

/// Plane waves along the axes of a material per frequency: Q, attenuation and phase velocity
/// of P waves along x (C11) and y (C22) and of S waves (C66), from its complex stiffness
/// ([`plane_wave`]); an elastic material has no loss and its elastic speeds.
#[derive(Clone, Debug, Serialize)]
pub struct Dispersion {
    /// The material's name.
    pub material: String,
    /// Frequencies (Hz).
    pub frequency_hz: Vec<f64>,
    /// P waves along x.
    pub p_x: WaveCurve,
    /// P waves along y (through the layers).
    pub p_y: WaveCurve,
    /// S waves along either axis.
    pub s: WaveCurve,
}

/// One wave type's curves over [`Dispersion::frequency_hz`].
#[derive(Clone, Debug, Default, Serialize)]
pub struct WaveCurve {
    /// Q(f) = Re M / Im M (infinite for an elastic material).
    pub quality: Vec<f64>,
    /// Attenuation (dB/mm): 20 log10(e) alpha / 1000, alpha = -Im k in Np/m.
    pub attenuation_db_per_mm: Vec<f64>,
    /// Phase velocity w / Re k (m/s).
    pub phase_velocity_m_s: Vec<f64>,
}

impl Dispersion {
    /// The curves of `material` at `frequency_hz` (each positive and finite, else an error
    /// naming `frequency_hz`).
    pub fn of(material: &Material, frequency_hz: &[f64]) -> Result<Dispersion> {
        if let Some(f) = frequency_hz.iter().find(|f| !(**f > 0.0 && f.is_finite())) {
            return Err(Error::invalid(
                "frequency_hz",
                f,
                "must be positive and finite (Hz)",
            ));
        }
        let mut d = Dispersion {
            material: material.name.clone(),
            frequency_hz: frequency_hz.to_vec(),
            p_x: WaveCurve::default(),
            p_y: WaveCurve::default(),
            s: WaveCurve::default(),
        };
        let db_per_np = 20.0 * std::f64::consts::LOG10_E;
        for &f in frequency_hz {
            let omega = 2.0 * PI * f;
            let c = match &material.relaxation {
                Some(r) => r.stiffness_at(omega),
                None => material
                    .stiffness_pa
                    .map(|row| row.map(|c| Complex64::new(c, 0.0))),
            };
            for (curve, m) in [
                (&mut d.p_x, c[0][0]),
                (&mut d.p_y, c[1][1]),
                (&mut d.s, c[2][2]),
            ] {
                let (speed, alpha) = plane_wave(material.density_kg_m3, m, omega);
                curve.quality.push(m.re / m.im);
                curve.attenuation_db_per_mm.push(db_per_np * alpha / 1000.0);
                curve.phase_velocity_m_s.push(speed);
            }
        }
        Ok(d)
    }
}

/// Checks a run's step against the shortest relaxation time of its materials: an error
/// naming `attenuation.band_hz` where dt / tau_min > [`MAX_STEP_PER_TAU`].
pub fn check_step(tau_min: f64, dt_s: f64) -> Result<()> {
    if dt_s <= MAX_STEP_PER_TAU * tau_min {
        return Ok(());
    }
    // f_top = 1/(2 pi tau_min) is the band's top f2 times (f2/f1)^(1/5) (relaxation_times)
    Err(Error::invalid(
        "attenuation.band_hz",
        format!(
            "highest relaxation frequency {:.4e} Hz",
            1.0 / (2.0 * PI * tau_min)
        ),
        format!(
            "needs dt <= {MAX_STEP_PER_TAU} tau_min = {:.4e} s for the memory variables to follow \
             it within 1%, and the run's step is {dt_s:.4e} s: lower the band's top or the step",
            MAX_STEP_PER_TAU * tau_min
        ),
    ))
}

/// Makes the materials named in `spec.quality` viscoelastic: their stiffness becomes the
/// unrelaxed one and they get their [`Relaxation`]. Errors name the field and value: a band
/// that is not 0 < f1 < f2, mechanisms outside 1..=[`MAX_MECHANISMS`], a reference frequency
/// that is not positive, a material not in `materials`, a Q that is not positive, or too low
/// for the fit to hold it within 2% over the band.
pub fn attenuate(materials: &mut [Material], spec: &AttenuationSpec) -> Result<()> {
    let band = spec.band_hz;
    if !(band[0] > 0.0 && band[1] > band[0] && band[1].is_finite()) {
        return Err(Error::invalid(
            "attenuation.band_hz",
            format!("{band:?}"),
            "must be [f1, f2] with 0 < f1 < f2, finite (Hz)",
        ));
    }
    if !(1..=MAX_MECHANISMS).contains(&spec.mechanisms) {
        return Err(Error::invalid(
            "attenuation.mechanisms",
            spec.mechanisms,
            format!("must be 1..={MAX_MECHANISMS}"),
        ));
    }
    let reference_hz = spec.reference_hz.unwrap_or((band[0] * band[1]).sqrt());
    if !(reference_hz > 0.0 && reference_hz.is_finite()) {
        return Err(Error::invalid(
            "attenuation.reference_hz",
            reference_hz,
            "must be a positive frequency (Hz)",
        ));
    }
    let tau_s = relaxation_times(band, spec.mechanisms);
    for (name, q) in &spec.quality {
        let Some(material) = materials.iter_mut().find(|m| &m.name == name) else {
            let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            return Err(Error::invalid(
                format!("attenuation.quality.{name}"),
                name,
                format!(
                    "no such material in the scene (it has {})",
                    names.join(", ")
                ),
            ));
        };
        let fit = Fit {
            field: format!("attenuation.quality.{name}"),
            band,
            tau_s: &tau_s,
            omega_ref: 2.0 * PI * reference_hz,
        };
        let relaxation = fit.relaxation(&material.stiffness_pa, q)?;
        material.stiffness_pa = add(
            &relaxation.parts[0].stiffness_pa,
            &relaxation.parts[1].stiffness_pa,
        );
        material.relaxation = Some(relaxation);
    }
    Ok(())
}

/// What fitting one material's parts shares: its field name for errors, the band, the
/// relaxation times and the reference frequency.
struct Fit<'a> {
    field: String,
    band: [f64; 2],
    tau_s: &'a [f64],
    omega_ref: f64,
}

impl Fit<'_> {
    /// The relaxation of a material of stiffness `c` (at the reference frequency): the split
    /// its symmetry calls for (module docs), each part fitted and scaled to C_U.
    fn relaxation(&self, c: &[[f64; 3]; 3], q: &QualitySpec) -> Result<Relaxation> {
        for (field, value) in [("q_p", q.q_p), ("q_s", q.q_s)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(Error::invalid(
                    format!("{}.{field}", self.field),
                    value,
                    "Q must be a positive finite number",
                ));
            }
        }
        let parts = if is_isotropic(c) {
            let (kappa, mu) = (0.5 * (c[0][0] + c[0][1]), c[2][2]);
            let inverse_q_kappa = ((kappa + mu) / q.q_p - mu / q.q_s) / kappa;
            if !(inverse_q_kappa > 0.0) {
                return Err(Error::invalid(
                    format!("{}.q_p", self.field),
                    q.q_p,
                    format!(
                        "an isotropic material's P waves cannot lose less than its bulk and shear \
                         allow: q_p must be below q_s (kappa + mu)/mu = {:.4}",
                        q.q_s * (kappa + mu) / mu
                    ),
                ));
            }
            let bulk = [[kappa, kappa, 0.0], [kappa, kappa, 0.0], [0.0, 0.0, 0.0]];
            let deviatoric = [[mu, -mu, 0.0], [-mu, mu, 0.0], [0.0, 0.0, mu]];
            [
                self.part("bulk", bulk, 1.0 / inverse_q_kappa, ("q_p", q.q_p))?,
                self.part("deviatoric", deviatoric, q.q_s, ("q_s", q.q_s))?,
            ]
        } else {
            let normal = [[c[0][0], c[0][1], 0.0], [c[1][0], c[1][1], 0.0], [0.0; 3]];
            let shear = [[0.0; 3], [0.0; 3], [0.0, 0.0, c[2][2]]];
            [
                self.part("normal", normal, q.q_p, ("q_p", q.q_p))?,
                self.part("shear", shear, q.q_s, ("q_s", q.q_s))?,
            ]
        };
        Ok(Relaxation {
            tau_s: self.tau_s.to_vec(),
            parts,
        })
    }

    /// One part at Q `quality` (asked as `asked` = (field, value)), scaled to unrelaxed.
    fn part(
        &self,
        name: &'static str,
        reference: [[f64; 3]; 3],
        quality: f64,
        asked: (&str, f64),
    ) -> Result<RelaxingPart> {
        let field = format!("{}.{}", self.field, asked.0);
        let [f1, f2] = self.band;
        let Some((weights, quality_error)) = constant_q_weights(quality, self.band, self.tau_s)
        else {
            return Err(Error::invalid(
                field,
                asked.1,
                format!(
                    "is too low for a constant-Q fit over [{f1:e}, {f2:e}] Hz with {} mechanisms: \
                     the relaxed stiffness would not be positive",
                    self.tau_s.len()
                ),
            ));
        };
        if quality_error > MAX_Q_ERROR {
            return Err(Error::invalid(
                field,
                asked.1,
                format!(
                    "{} mechanisms hold Q = {quality:.4} within {:.1}% over [{f1:e}, {f2:e}] Hz \
                     (at most {}%): add attenuation.mechanisms, narrow attenuation.band_hz or \
                     raise Q",
                    self.tau_s.len(),
                    100.0 * quality_error,
                    100.0 * MAX_Q_ERROR
                ),
            ));
        }
        let scale = unrelaxed_scale(self.omega_ref, self.tau_s, &weights);
        Ok(RelaxingPart {
            name,
            stiffness_pa: reference.map(|row| row.map(|c| scale * c)),
            weights,
            quality,
            quality_error,
        })
    }
}

/// Whether a plane stiffness is isotropic: C11 = C22 and C66 = (C11 - C12)/2, to 1e-12.
fn is_isotropic(c: &[[f64; 3]; 3]) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * c[0][0].abs();
    close(c[0][0], c[1][1]) && close(c[2][2], 0.5 * (c[0][0] - c[0][1]))
}

fn add(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] + b[i][j]))
}

pub(crate) mod memory;

#[cfg(test)]
mod tests;
