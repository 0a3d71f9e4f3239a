//! Linear elastic materials reduced to 2D (report Sec. 2.1, 4.5).
//!
//! The report's eqs 20-22 are not a valid plane-strain reduction (docs/src/physics.md). Here the
//! plane matrix is built from the full 3D orthotropic compliance: plane stress keeps the
//! in-plane block of the compliance, plane strain eliminates the out-of-plane strain
//! `eps_33 = 0` by `S'_ij = S_ij - S_i3 S_j3 / S_33`. The result is inverted to the stiffness
//! `C` (Voigt order xx, yy, xy with engineering shear) and must be positive definite.

use crate::error::{Error, Result};
use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

/// Which 2D idealisation reduces the 3D material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Plane {
    /// `eps_33 = 0`: a slice of a thick body (default).
    #[default]
    Strain,
    /// `sigma_33 = 0`: a thin plate.
    Stress,
}

/// Orthotropic engineering constants; axis 1 = x (along the layers), 2 = y (through the
/// thickness), 3 = out of the model plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Orthotropic {
    /// Name used in messages and outputs.
    pub name: String,
    /// Young's modulus along x (Pa).
    pub e1_pa: f64,
    /// Young's modulus along y (Pa).
    pub e2_pa: f64,
    /// Young's modulus out of plane (Pa); used by plane strain only.
    pub e3_pa: f64,
    /// In-plane shear modulus (Pa).
    pub g12_pa: f64,
    /// Poisson ratio nu_12 (strain in 2 from stress in 1 is -nu_12/E1).
    pub nu12: f64,
    /// Poisson ratio nu_13.
    pub nu13: f64,
    /// Poisson ratio nu_23.
    pub nu23: f64,
    /// Density (kg/m^3).
    pub density_kg_m3: f64,
}

/// P and S wave speeds of a plane orthotropic material along the axes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WaveSpeeds {
    /// Longitudinal speed along x, sqrt(C11/rho) (m/s).
    pub p_x_m_s: f64,
    /// Longitudinal speed along y, sqrt(C22/rho) (m/s).
    pub p_y_m_s: f64,
    /// Shear speed along either axis, sqrt(C33/rho) (m/s).
    pub s_m_s: f64,
}

/// A material ready for the finite element model: density and the 3x3 plane stiffness.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Material {
    /// Name used in messages and outputs.
    pub name: String,
    /// Density (kg/m^3).
    pub density_kg_m3: f64,
    /// Plane stiffness in Voigt order (xx, yy, xy), engineering shear strain (Pa); of a
    /// viscoelastic material the unrelaxed (infinite-frequency) one.
    pub stiffness_pa: [[f64; 3]; 3],
    /// The relaxation of a viscoelastic material ([`crate::attenuation`]); `None`: elastic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relaxation: Option<Relaxation>,
}

/// The largest elastic modulus accepted (Pa; see [`Orthotropic::check_constants`]).
pub const MAX_MODULUS_PA: f64 = 1e13;
/// The densities accepted (kg/m^3; see [`Orthotropic::check_constants`]).
pub const DENSITY_KG_M3: (f64, f64) = (1.0, 1e5);

impl Orthotropic {
    /// An isotropic material as an orthotropic one (E, nu in all directions).
    pub fn isotropic(name: &str, e_pa: f64, nu: f64, density_kg_m3: f64) -> Self {
        Orthotropic {
            name: name.to_string(),
            e1_pa: e_pa,
            e2_pa: e_pa,
            e3_pa: e_pa,
            g12_pa: e_pa / (2.0 * (1.0 + nu)),
            nu12: nu,
            nu13: nu,
            nu23: nu,
            density_kg_m3,
        }
    }

    /// Pure epoxy (report Sec. 2.1): E = 3.7 GPa, nu = 0.4, rho = 1200 kg/m^3.
    pub fn epoxy() -> Self {
        Self::isotropic("epoxy", 3.7e9, 0.4, 1200.0)
    }

    /// Fabric woven at 0/90 degrees (report Sec. 2.1): E1 = E2 = 70 GPa, G12 = 5 GPa,
    /// nu12 = 0.1, rho = 1600 kg/m^3. Assumed (not in the report): E3 = 10 GPa,
    /// nu13 = nu23 = 0.3, matrix-dominated out-of-plane values typical of woven CFRP.
    pub fn fabric_0_90() -> Self {
        Orthotropic {
            name: "fabric_0_90".into(),
            e1_pa: 70e9,
            e2_pa: 70e9,
            e3_pa: 10e9,
            g12_pa: 5e9,
            nu12: 0.1,
            nu13: 0.3,
            nu23: 0.3,
            density_kg_m3: 1600.0,
        }
    }

    /// Fabric woven at 45/45 degrees (report Sec. 2.1): E1 = E2 = 20 GPa, G12 = 30 GPa,
    /// nu12 = 0.74, rho = 1600 kg/m^3. Assumed (not in the report): E3 = 10 GPa,
    /// nu13 = nu23 = 0.3. With these the 3D compliance and the plane-strain C are positive
    /// definite; the report's eq 20 would give c11 < 0 for this material.
    pub fn fabric_45_45() -> Self {
        Orthotropic {
            name: "fabric_45_45".into(),
            e1_pa: 20e9,
            e2_pa: 20e9,
            e3_pa: 10e9,
            g12_pa: 30e9,
            nu12: 0.74,
            nu13: 0.3,
            nu23: 0.3,
            density_kg_m3: 1600.0,
        }
    }

    /// A preset by name: `epoxy`, `fabric_0_90`, `fabric_45_45`.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "epoxy" => Ok(Self::epoxy()),
            "fabric_0_90" => Ok(Self::fabric_0_90()),
            "fabric_45_45" => Ok(Self::fabric_45_45()),
            other => Err(Error::invalid(
                "material",
                other,
                "unknown preset (expected epoxy, fabric_0_90 or fabric_45_45)",
            )),
        }
    }

    /// Moduli in (0, 1e13] Pa: the stiffest solid, diamond, has E of about 1.2e12 Pa, so ten
    /// times that bounds every material with room; densities in [1, 1e5] kg/m^3: from below
    /// the lightest foams (~10) to above osmium (22,600).
    fn check_constants(&self) -> Result<()> {
        let moduli = [
            ("e1_pa", self.e1_pa),
            ("e2_pa", self.e2_pa),
            ("e3_pa", self.e3_pa),
            ("g12_pa", self.g12_pa),
        ];
        for (field, value) in moduli {
            if !(value.is_finite() && value > 0.0 && value <= MAX_MODULUS_PA) {
                return Err(self.reject(format!(
                    "{field} = {value} must be within (0, {MAX_MODULUS_PA:e}] Pa (10x diamond's modulus)"
                )));
            }
        }
        let density = self.density_kg_m3;
        if !(density.is_finite() && (DENSITY_KG_M3.0..=DENSITY_KG_M3.1).contains(&density)) {
            return Err(self.reject(format!(
                "density_kg_m3 = {density} must be within [{:e}, {:e}] kg/m^3 (foams to beyond osmium)",
                DENSITY_KG_M3.0, DENSITY_KG_M3.1
            )));
        }
        for (field, value) in [
            ("nu12", self.nu12),
            ("nu13", self.nu13),
            ("nu23", self.nu23),
        ] {
            if !value.is_finite() {
                return Err(self.reject(format!("{field} = {value} must be finite")));
            }
        }
        Ok(())
    }

    fn reject(&self, reason: String) -> Error {
        Error::Material {
            name: self.name.clone(),
            reason,
        }
    }

    /// Symmetric 3x3 normal-strain compliance block of the 3D orthotropic material (1/Pa).
    fn normal_compliance(&self) -> [[f64; 3]; 3] {
        let s12 = -self.nu12 / self.e1_pa;
        let s13 = -self.nu13 / self.e1_pa;
        let s23 = -self.nu23 / self.e2_pa;
        [
            [1.0 / self.e1_pa, s12, s13],
            [s12, 1.0 / self.e2_pa, s23],
            [s13, s23, 1.0 / self.e3_pa],
        ]
    }

    /// Reduces to a plane material, rejecting one whose stiffness is not positive definite.
    pub fn reduce(&self, plane: Plane) -> Result<Material> {
        self.check_constants()?;
        let s = self.normal_compliance();
        if plane == Plane::Strain && !is_positive_definite(&s) {
            return Err(self.reject(
                "3D compliance is not positive definite (check the Poisson ratios)".into(),
            ));
        }
        let reduced = match plane {
            Plane::Stress => [s[0][0], s[0][1], s[1][1]],
            Plane::Strain => [
                s[0][0] - s[0][2] * s[0][2] / s[2][2],
                s[0][1] - s[0][2] * s[1][2] / s[2][2],
                s[1][1] - s[1][2] * s[1][2] / s[2][2],
            ],
        };
        let det = reduced[0] * reduced[2] - reduced[1] * reduced[1];
        if !(reduced[0] > 0.0 && det > 0.0) {
            return Err(self.reject(format!(
                "plane {plane:?} stiffness is not positive definite (in-plane compliance determinant {det:.3e})"
            )));
        }
        let c11 = reduced[2] / det;
        let c22 = reduced[0] / det;
        let c12 = -reduced[1] / det;
        Ok(Material {
            name: self.name.clone(),
            density_kg_m3: self.density_kg_m3,
            stiffness_pa: [[c11, c12, 0.0], [c12, c22, 0.0], [0.0, 0.0, self.g12_pa]],
            relaxation: None,
        })
    }
}

/// Sylvester's criterion on a symmetric 3x3 matrix.
fn is_positive_definite(m: &[[f64; 3]; 3]) -> bool {
    let d1 = m[0][0];
    let d2 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let d3 = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    d1 > 0.0 && d2 > 0.0 && d3 > 0.0
}

impl Material {
    /// P and S wave speeds along the axes (plane waves in an orthotropic medium).
    pub fn wave_speeds(&self) -> WaveSpeeds {
        let c = &self.stiffness_pa;
        let rho = self.density_kg_m3;
        WaveSpeeds {
            p_x_m_s: (c[0][0] / rho).sqrt(),
            p_y_m_s: (c[1][1] / rho).sqrt(),
            s_m_s: (c[2][2] / rho).sqrt(),
        }
    }

    /// Fastest wave speed, used for stability estimates (m/s).
    pub fn max_wave_speed(&self) -> f64 {
        let w = self.wave_speeds();
        w.p_x_m_s.max(w.p_y_m_s).max(w.s_m_s)
    }

    /// Acoustic impedance rho * Vp for a P wave travelling along y (Pa s/m).
    pub fn impedance_p_y(&self) -> f64 {
        self.density_kg_m3 * self.wave_speeds().p_y_m_s
    }

    /// The plane stiffness as a positive-definite check result, for materials built directly.
    pub fn is_positive_definite(&self) -> bool {
        is_positive_definite(&self.stiffness_pa)
    }

    /// The material with its principal axes turned by `angle_rad` from x, counter-clockwise:
    /// its stiffness and its relaxing parts' stiffness by [`rotate_plane_stiffness`].
    pub fn rotated(&self, angle_rad: f64) -> Material {
        let mut m = self.clone();
        m.stiffness_pa = rotate_plane_stiffness(&self.stiffness_pa, angle_rad);
        if let Some(r) = &mut m.relaxation {
            for part in &mut r.parts {
                part.stiffness_pa = rotate_plane_stiffness(&part.stiffness_pa, angle_rad);
            }
        }
        m
    }
}

/// A plane stiffness (Voigt xx, yy, xy, engineering shear) whose material axes lie at angle
/// theta from x, in the x-y frame: C_xy = T^T C T, where T takes the x-y strains to the
/// material axes' (c = cos theta, s = sin theta):
///   eps_11 = c^2 e_xx + s^2 e_yy + c s g_xy,  eps_22 = s^2 e_xx + c^2 e_yy - c s g_xy,
///   g_12 = -2 c s e_xx + 2 c s e_yy + (c^2 - s^2) g_xy
/// (Jones, *Mechanics of Composite Materials*, 1999, Sec. 2.6), so the strain energy
/// eps^T C eps is the same in both frames.
pub fn rotate_plane_stiffness(c: &[[f64; 3]; 3], theta: f64) -> [[f64; 3]; 3] {
    let (s, co) = theta.sin_cos();
    let t = [
        [co * co, s * s, co * s],
        [s * s, co * co, -co * s],
        [-2.0 * co * s, 2.0 * co * s, co * co - s * s],
    ];
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, o) in row.iter_mut().enumerate() {
            *o = (0..3)
                .flat_map(|k| (0..3).map(move |l| (k, l)))
                .map(|(k, l)| t[k][i] * c[k][l] * t[l][j])
                .sum();
        }
    }
    out
}

/// A material's relaxation: the mechanisms' times and the two parts of its unrelaxed
/// stiffness with their weights ([`crate::attenuation`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Relaxation {
    /// Relaxation times tau_l (s), one per mechanism.
    pub tau_s: Vec<f64>,
    /// The two parts of C_U, each with its own Q.
    pub parts: [RelaxingPart; 2],
}

/// One part C_k of an unrelaxed stiffness and the weights y_kl of its mechanisms.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RelaxingPart {
    /// Which part: "normal", "shear", "bulk" or "deviatoric".
    pub name: &'static str,
    /// C_k, unrelaxed (Pa, Voigt order).
    pub stiffness_pa: [[f64; 3]; 3],
    /// y_kl, one per mechanism.
    pub weights: Vec<f64>,
    /// The Q fitted.
    pub quality: f64,
    /// Largest |Q(w)/Q - 1| over the band.
    pub quality_error: f64,
}

/// The relative modulus M(w)/M_U = 1 - sum_l y_l / (1 + i w tau_l) of one part.
pub fn relative_modulus(omega: f64, tau_s: &[f64], weights: &[f64]) -> Complex64 {
    let one = Complex64::new(1.0, 0.0);
    tau_s.iter().zip(weights).fold(one, |m, (&tau, &y)| {
        m - y / Complex64::new(1.0, omega * tau)
    })
}

impl Relaxation {
    /// The complex stiffness at `omega`: sum_k C_k [1 - sum_l y_kl / (1 + i w tau_l)].
    pub fn stiffness_at(&self, omega: f64) -> [[Complex64; 3]; 3] {
        let mut c = [[Complex64::new(0.0, 0.0); 3]; 3];
        for part in &self.parts {
            let m = relative_modulus(omega, &self.tau_s, &part.weights);
            for (row, part_row) in c.iter_mut().zip(&part.stiffness_pa) {
                for (cij, &kij) in row.iter_mut().zip(part_row) {
                    *cij += m * kij;
                }
            }
        }
        c
    }

    /// DC_l = sum_k y_kl C_k, the stiffness mechanism `l` relaxes (Pa).
    pub fn relaxed_by(&self, l: usize) -> [[f64; 3]; 3] {
        let mut dc = [[0.0; 3]; 3];
        for part in &self.parts {
            for (row, part_row) in dc.iter_mut().zip(&part.stiffness_pa) {
                for (d, &k) in row.iter_mut().zip(part_row) {
                    *d += part.weights[l] * k;
                }
            }
        }
        dc
    }

    /// The shortest relaxation time (s): the step must keep dt / tau below
    /// [`crate::attenuation::MAX_STEP_PER_TAU`].
    pub fn shortest_tau_s(&self) -> f64 {
        self.tau_s.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// The shortest relaxation time of `materials` (s), `None` where all are elastic: what a
/// body's step must follow ([`crate::attenuation::check_step`]).
pub fn shortest_relaxation_s<'a>(materials: impl IntoIterator<Item = &'a Material>) -> Option<f64> {
    materials
        .into_iter()
        .filter_map(|m| m.relaxation.as_ref())
        .map(Relaxation::shortest_tau_s)
        .reduce(f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Turning the fabric by 90 degrees swaps its x and y moduli and keeps the shear; turning
    /// by theta then -theta gives it back; an isotropic stiffness does not change; and the
    /// strain energy of a strain turned with the material is the same (to round-off).
    #[test]
    fn rotated_stiffness_turns_with_the_material() {
        let c = Orthotropic::fabric_0_90()
            .reduce(Plane::Strain)
            .unwrap()
            .stiffness_pa;
        let q = rotate_plane_stiffness(&c, std::f64::consts::FRAC_PI_2);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * c[0][0];
        assert!(close(q[0][0], c[1][1]) && close(q[1][1], c[0][0]) && close(q[2][2], c[2][2]));
        let back = rotate_plane_stiffness(&rotate_plane_stiffness(&c, 0.7), -0.7);
        assert!(
            (0..9).all(|k| close(back[k / 3][k % 3], c[k / 3][k % 3])),
            "{back:?}"
        );
        let iso = Orthotropic::epoxy()
            .reduce(Plane::Strain)
            .unwrap()
            .stiffness_pa;
        let turned = rotate_plane_stiffness(&iso, 0.4);
        assert!(
            (0..9).all(|k| (turned[k / 3][k % 3] - iso[k / 3][k % 3]).abs() <= 1e-12 * iso[0][0])
        );
        // a uniaxial strain along the material axis at 0.3 rad, in x-y components
        let (s, co) = 0.3f64.sin_cos();
        let e = [co * co, s * s, 2.0 * co * s];
        let r = rotate_plane_stiffness(&c, 0.3);
        let energy: f64 = (0..9).map(|k| e[k / 3] * r[k / 3][k % 3] * e[k % 3]).sum();
        assert!(
            (energy - c[0][0]).abs() <= 1e-12 * c[0][0],
            "{energy} vs {}",
            c[0][0]
        );
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn isotropic_plane_strain_matches_textbook() {
        // Textbook plane strain: c11 = E(1-nu)/((1+nu)(1-2nu)), c12 = E nu/((1+nu)(1-2nu)), c33 = G.
        // Tolerance 1e-12 relative: the reduction is a handful of flops on O(1) ratios.
        let (e, nu) = (3.7e9, 0.4);
        let m = Orthotropic::epoxy().reduce(Plane::Strain).unwrap();
        let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let c = m.stiffness_pa;
        assert!(rel(c[0][0], f * (1.0 - nu)) < 1e-12);
        assert!(rel(c[1][1], f * (1.0 - nu)) < 1e-12);
        assert!(rel(c[0][1], f * nu) < 1e-12);
        assert!(rel(c[2][2], e / (2.0 * (1.0 + nu))) < 1e-12);
        // Plane strain: epoxy c12 = nu / (1 - nu) c11 = 5.29 GPa, not the 3.17 GPa of eq 22.
        assert!((c[0][1] - 5.2857e9).abs() < 1e6);
    }

    #[test]
    fn isotropic_plane_stress_matches_textbook() {
        let (e, nu) = (3.7e9, 0.4);
        let m = Orthotropic::epoxy().reduce(Plane::Stress).unwrap();
        let f = e / (1.0 - nu * nu);
        assert!(rel(m.stiffness_pa[0][0], f) < 1e-12);
        assert!(rel(m.stiffness_pa[0][1], f * nu) < 1e-12);
    }

    #[test]
    fn presets_are_positive_definite_in_both_planes() {
        for o in [
            Orthotropic::epoxy(),
            Orthotropic::fabric_0_90(),
            Orthotropic::fabric_45_45(),
        ] {
            for plane in [Plane::Strain, Plane::Stress] {
                let m = o.reduce(plane).unwrap();
                assert!(m.is_positive_definite(), "{} {plane:?}", o.name);
            }
        }
    }

    #[test]
    fn epoxy_wave_speeds() {
        // Vs = sqrt(G/rho) = 1049 m/s (about 1050 m/s), Vp = sqrt(c11/rho) = 2571 m/s.
        let w = Orthotropic::epoxy()
            .reduce(Plane::Strain)
            .unwrap()
            .wave_speeds();
        assert!((w.s_m_s - 1049.3).abs() < 0.5);
        assert!((w.p_x_m_s - 2571.0).abs() < 1.0);
        assert_eq!(w.p_x_m_s, w.p_y_m_s);
    }

    #[test]
    fn indefinite_material_is_rejected_with_its_name() {
        let mut o = Orthotropic::isotropic("rubbery", 1e9, 0.2, 1000.0);
        o.nu12 = 1.5; // |nu12| > sqrt(E1/E2): in-plane compliance indefinite
        let err = o.reduce(Plane::Stress).unwrap_err().to_string();
        assert!(
            err.contains("rubbery") && err.contains("positive definite"),
            "{err}"
        );
        let mut bad = Orthotropic::epoxy();
        bad.density_kg_m3 = f64::NAN;
        let err = bad.reduce(Plane::Strain).unwrap_err().to_string();
        assert!(
            err.contains("density_kg_m3") && err.contains("NaN"),
            "{err}"
        );
        bad = Orthotropic::epoxy();
        bad.e2_pa = -1.0;
        assert!(bad
            .reduce(Plane::Strain)
            .unwrap_err()
            .to_string()
            .contains("e2_pa"));
    }
}
