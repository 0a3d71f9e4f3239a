//! Layer stacks: the stochastic CFRP laminate of report Sec. 2.2.1 (eqs 1-5) and explicit stacks.
//!
//! Layers are listed from the bottom (y = 0) to the top surface. Each layer refers to a
//! material by its index in [`Laminate::materials`].

use crate::error::{require_positive, require_within, Error, Result};
use crate::material::{Material, Orthotropic, Plane};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

/// One homogeneous layer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Layer {
    /// Index into [`Laminate::materials`].
    pub material: usize,
    /// Thickness along y (m).
    pub thickness_m: f64,
}

/// The random draw behind one composite + epoxy pair (eqs 1-5).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PairDraw {
    /// Ellipse semi-major axis a (m).
    pub a_m: f64,
    /// Ellipse semi-minor axis b (m).
    pub b_m: f64,
    /// Crossing position x ~ U(0, a) (m).
    pub x_m: f64,
    /// Composite thickness f_C(x) (eq 4) (m).
    pub composite_m: f64,
    /// Epoxy thickness sqrt(3) b - f_C (eq 5) before clamping (m).
    pub epoxy_drawn_m: f64,
    /// Epoxy thickness used: the drawn one, raised to the minimum if below it (m).
    pub epoxy_m: f64,
    /// Negative (a, b) draws rejected and redrawn for this pair.
    pub rejected_draws: u32,
}

/// A layer stack with its materials.
#[derive(Clone, Debug, Serialize)]
pub struct Laminate {
    /// Materials referenced by the layers.
    pub materials: Vec<Material>,
    /// Layers from the bottom (y = 0) up.
    pub layers: Vec<Layer>,
    /// The random draws, one per pair, for a stochastic laminate (empty otherwise).
    pub draws: Vec<PairDraw>,
}

/// Parameters of the stochastic laminate (report Sec. 2.2.1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StochasticSpec {
    /// Number of composite + epoxy pairs (report: 50).
    pub pairs: usize,
    /// Mean of the semi-major axis a (report: 0.750 mm).
    pub a_mean_m: f64,
    /// Standard deviation of a (report: 0.130 mm).
    pub a_std_m: f64,
    /// Mean of the semi-minor axis b (report: 0.130 mm).
    pub b_mean_m: f64,
    /// Standard deviation of b (report: 0.025 mm).
    pub b_std_m: f64,
    /// Minimum epoxy thickness; thinner draws are raised to it (a modelling choice, Sec. 2.2.1 step 4).
    pub min_epoxy_m: f64,
    /// Seed of the ChaCha8 generator: the same seed gives a bit-identical stack.
    pub seed: u64,
}

impl Default for StochasticSpec {
    fn default() -> Self {
        StochasticSpec {
            pairs: 50,
            a_mean_m: 0.750e-3,
            a_std_m: 0.130e-3,
            b_mean_m: 0.130e-3,
            b_std_m: 0.025e-3,
            min_epoxy_m: 0.02e-3,
            seed: 1,
        }
    }
}

/// Composite thickness of the representative element at crossing x (eq 4):
/// f_C(x) = b/a (sqrt(a^2 - x^2) + sqrt(2 a x - x^2)).
pub fn composite_thickness(a: f64, b: f64, x: f64) -> f64 {
    b / a * ((a * a - x * x).max(0.0).sqrt() + (2.0 * a * x - x * x).max(0.0).sqrt())
}

/// Epoxy thickness between the quarter ellipses (eq 5): f_E = sqrt(3) b - f_C.
pub fn epoxy_thickness(b: f64, composite: f64) -> f64 {
    3f64.sqrt() * b - composite
}

/// Non-positive draws of a and b redrawn per pair before the spec is refused: with a positive
/// mean fewer than half the draws are non-positive, so valid specs never come near it.
const MAX_REJECTIONS: u32 = 1000;

/// The largest ellipse axis mean or standard deviation accepted (m): the report's ellipses are
/// 0.75 x 0.13 mm; 10 cm is beyond any specimen's thickness.
const MAX_AXIS_M: f64 = 0.1;

impl StochasticSpec {
    fn validate(&self) -> Result<()> {
        if self.pairs == 0 {
            return Err(Error::invalid(
                "laminate.pairs",
                self.pairs,
                "must be at least 1",
            ));
        }
        require_positive("laminate.a_mean_m", self.a_mean_m)?;
        require_positive("laminate.b_mean_m", self.b_mean_m)?;
        require_positive("laminate.min_epoxy_m", self.min_epoxy_m)?;
        for (field, v) in [
            ("laminate.a_std_m", self.a_std_m),
            ("laminate.b_std_m", self.b_std_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(field, v, "must be finite and >= 0"));
            }
        }
        for (field, v) in [
            ("laminate.a_mean_m", self.a_mean_m),
            ("laminate.a_std_m", self.a_std_m),
            ("laminate.b_mean_m", self.b_mean_m),
            ("laminate.b_std_m", self.b_std_m),
        ] {
            require_within(
                field,
                v,
                0.0,
                MAX_AXIS_M,
                "m",
                "an ellipse axis of a fibre bundle",
            )?;
        }
        // A floor on every epoxy layer: the report's is 20 um; 1 cm is beyond any laminate's
        // interlayer (1 m made a 50 m stack whose mesh took minutes to be refused).
        require_within(
            "laminate.min_epoxy_m",
            self.min_epoxy_m,
            0.0,
            0.01,
            "m",
            "the thinnest epoxy layer",
        )?;
        // The draws and the layers are held at once, then the mesh (estimated in its turn).
        let per_pair = std::mem::size_of::<PairDraw>() + 2 * std::mem::size_of::<Layer>();
        crate::budget::check_memory(
            "laminate.pairs",
            self.pairs,
            self.pairs as f64 * per_pair as f64,
            "draw fewer pairs",
        )
    }

    /// Draws a positive value from N(mean, std), counting rejected non-positive draws; more
    /// than [`MAX_REJECTIONS`] for one pair is an error naming the standard deviation `field`.
    fn draw_positive(
        dist: &Normal<f64>,
        rng: &mut ChaCha8Rng,
        field: &str,
        rejected: &mut u32,
    ) -> Result<f64> {
        loop {
            let v = dist.sample(rng);
            if v > 0.0 {
                return Ok(v);
            }
            *rejected += 1;
            if *rejected > MAX_REJECTIONS {
                return Err(Error::invalid(
                    field,
                    dist.std_dev(),
                    format!(
                        "more than {MAX_REJECTIONS} non-positive draws for one pair with mean {}: \
                         keep the standard deviation well below the mean",
                        dist.mean()
                    ),
                ));
            }
        }
    }

    /// Draws one pair (steps 1-3 of the report's procedure).
    fn draw_pair(
        &self,
        a_dist: &Normal<f64>,
        b_dist: &Normal<f64>,
        rng: &mut ChaCha8Rng,
    ) -> Result<PairDraw> {
        let mut rejected_draws = 0;
        let a_m = Self::draw_positive(a_dist, rng, "laminate.a_std_m", &mut rejected_draws)?;
        let b_m = Self::draw_positive(b_dist, rng, "laminate.b_std_m", &mut rejected_draws)?;
        let x_m = rng.random_range(0.0..a_m);
        let composite_m = composite_thickness(a_m, b_m, x_m);
        let epoxy_drawn_m = epoxy_thickness(b_m, composite_m);
        Ok(PairDraw {
            a_m,
            b_m,
            x_m,
            composite_m,
            epoxy_drawn_m,
            epoxy_m: epoxy_drawn_m.max(self.min_epoxy_m),
            rejected_draws,
        })
    }
}

impl Laminate {
    /// The stochastic CFRP laminate (eqs 1-5): materials 0 = epoxy, 1 = fabric 0/90,
    /// 2 = fabric 45/45; pair i has composite (0/90 for even i, 45/45 for odd i) above epoxy,
    /// pair 0 at the top surface.
    pub fn stochastic(spec: &StochasticSpec, plane: Plane) -> Result<Laminate> {
        spec.validate()?;
        let materials = vec![
            Orthotropic::epoxy().reduce(plane)?,
            Orthotropic::fabric_0_90().reduce(plane)?,
            Orthotropic::fabric_45_45().reduce(plane)?,
        ];
        let a_dist = Normal::new(spec.a_mean_m, spec.a_std_m)
            .map_err(|e| Error::invalid("laminate.a_std_m", spec.a_std_m, e.to_string()))?;
        let b_dist = Normal::new(spec.b_mean_m, spec.b_std_m)
            .map_err(|e| Error::invalid("laminate.b_std_m", spec.b_std_m, e.to_string()))?;
        let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
        let draws = (0..spec.pairs)
            .map(|_| spec.draw_pair(&a_dist, &b_dist, &mut rng))
            .collect::<Result<Vec<_>>>()?;
        // Pair 0 is at the top: build top-down, then reverse to bottom-up order.
        let mut layers = Vec::with_capacity(2 * draws.len());
        for (i, d) in draws.iter().enumerate() {
            layers.push(Layer {
                material: 1 + i % 2,
                thickness_m: d.composite_m,
            });
            layers.push(Layer {
                material: 0,
                thickness_m: d.epoxy_m,
            });
        }
        layers.reverse();
        Ok(Laminate {
            materials,
            layers,
            draws,
        })
    }

    /// A deterministic stack from (material, thickness) pairs listed bottom-up.
    pub fn from_layers(materials: Vec<Material>, layers: Vec<Layer>) -> Result<Laminate> {
        if layers.is_empty() {
            return Err(Error::invalid(
                "laminate.layers",
                "[]",
                "needs at least one layer",
            ));
        }
        for (i, l) in layers.iter().enumerate() {
            require_positive(&format!("laminate.layers[{i}].thickness_m"), l.thickness_m)?;
            if l.material >= materials.len() {
                return Err(Error::invalid(
                    format!("laminate.layers[{i}].material"),
                    l.material,
                    "no such material",
                ));
            }
        }
        Ok(Laminate {
            materials,
            layers,
            draws: Vec::new(),
        })
    }

    /// A single homogeneous layer.
    pub fn homogeneous(material: Material, thickness_m: f64) -> Result<Laminate> {
        Self::from_layers(
            vec![material],
            vec![Layer {
                material: 0,
                thickness_m,
            }],
        )
    }

    /// Total thickness (m).
    pub fn thickness_m(&self) -> f64 {
        self.layers.iter().map(|l| l.thickness_m).sum()
    }

    /// Heights of the layer boundaries from y = 0 to the top, `layers.len() + 1` values.
    pub fn interfaces_m(&self) -> Vec<f64> {
        let mut y = vec![0.0];
        for l in &self.layers {
            y.push(y.last().unwrap() + l.thickness_m);
        }
        y
    }

    /// Fraction of pairs whose epoxy thickness was raised to the minimum.
    pub fn clamped_fraction(&self) -> f64 {
        if self.draws.is_empty() {
            return 0.0;
        }
        let clamped = self
            .draws
            .iter()
            .filter(|d| d.epoxy_m > d.epoxy_drawn_m)
            .count();
        clamped as f64 / self.draws.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_std(v: &[f64]) -> (f64, f64) {
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
        (m, var.sqrt())
    }

    #[test]
    fn draws_match_input_statistics() {
        // 20000 pairs: the standard error of the mean is std/sqrt(n) = 0.7% of std; of the
        // std about std/sqrt(2n) = 0.5%. We allow 4 standard errors. Truncation of negative
        // draws is negligible here (a and b are > 5 std above zero).
        let spec = StochasticSpec {
            pairs: 20_000,
            seed: 7,
            ..Default::default()
        };
        let lam = Laminate::stochastic(&spec, Plane::Strain).unwrap();
        let n = spec.pairs as f64;
        let a: Vec<f64> = lam.draws.iter().map(|d| d.a_m).collect();
        let b: Vec<f64> = lam.draws.iter().map(|d| d.b_m).collect();
        let (am, asd) = mean_std(&a);
        let (bm, bsd) = mean_std(&b);
        assert!(
            (am - spec.a_mean_m).abs() < 4.0 * spec.a_std_m / n.sqrt(),
            "a mean {am}"
        );
        assert!(
            (bm - spec.b_mean_m).abs() < 4.0 * spec.b_std_m / n.sqrt(),
            "b mean {bm}"
        );
        assert!(
            (asd - spec.a_std_m).abs() < 4.0 * spec.a_std_m / (2.0 * n).sqrt(),
            "a std {asd}"
        );
        assert!(
            (bsd - spec.b_std_m).abs() < 4.0 * spec.b_std_m / (2.0 * n).sqrt(),
            "b std {bsd}"
        );
        // x ~ U(0, a): x/a has mean 1/2 and std 1/sqrt(12).
        let xa: Vec<f64> = lam.draws.iter().map(|d| d.x_m / d.a_m).collect();
        let (xm, xsd) = mean_std(&xa);
        assert!((xm - 0.5).abs() < 4.0 / (12.0 * n).sqrt());
        assert!((xsd - 1.0 / 12f64.sqrt()).abs() < 0.01);
    }

    #[test]
    fn composite_plus_epoxy_is_sqrt3_b_for_every_pair() {
        let lam = Laminate::stochastic(
            &StochasticSpec {
                pairs: 2000,
                ..Default::default()
            },
            Plane::Strain,
        )
        .unwrap();
        for d in &lam.draws {
            let total = d.composite_m + d.epoxy_drawn_m;
            assert!((total - 3f64.sqrt() * d.b_m).abs() < 1e-15, "{d:?}");
            assert!(
                d.epoxy_drawn_m >= -1e-18,
                "f_E >= 0 since max f_C = sqrt(3) b at x = a/2"
            );
            assert!(d.epoxy_m >= 0.02e-3);
        }
        // The draw statistics (a, b, x of eqs 1-5) put about 61% of the epoxy layers below
        // 0.02 mm, so about 61% are clamped.
        let f = lam.clamped_fraction();
        assert!((0.55..0.67).contains(&f), "clamped fraction {f}");
    }

    #[test]
    fn same_seed_same_stack_other_seed_other_stack() {
        let spec = StochasticSpec::default();
        let a = Laminate::stochastic(&spec, Plane::Strain).unwrap();
        let b = Laminate::stochastic(&spec, Plane::Strain).unwrap();
        assert_eq!(a.layers, b.layers);
        let c = Laminate::stochastic(&StochasticSpec { seed: 2, ..spec }, Plane::Strain).unwrap();
        assert_ne!(a.layers, c.layers);
        assert_eq!(a.layers.len(), 100);
    }

    #[test]
    fn negative_draws_are_rejected_not_kept() {
        // b mean 0 with a large std: about half of the draws are negative and must be redrawn.
        let spec = StochasticSpec {
            pairs: 200,
            b_mean_m: 1e-6,
            b_std_m: 1e-4,
            ..Default::default()
        };
        let lam = Laminate::stochastic(&spec, Plane::Strain).unwrap();
        assert!(lam.draws.iter().all(|d| d.a_m > 0.0 && d.b_m > 0.0));
        assert!(lam.draws.iter().map(|d| d.rejected_draws).sum::<u32>() > 50);
    }

    #[test]
    fn bad_specs_name_the_field() {
        let e = Laminate::stochastic(
            &StochasticSpec {
                pairs: 0,
                ..Default::default()
            },
            Plane::Strain,
        );
        assert!(e.unwrap_err().to_string().contains("laminate.pairs"));
        let e = Laminate::stochastic(
            &StochasticSpec {
                b_std_m: f64::NAN,
                ..Default::default()
            },
            Plane::Strain,
        );
        assert!(e.unwrap_err().to_string().contains("laminate.b_std_m"));
        let epoxy = Orthotropic::epoxy().reduce(Plane::Strain).unwrap();
        let e = Laminate::homogeneous(epoxy, -1e-3).unwrap_err().to_string();
        assert!(e.contains("thickness_m") && e.contains("-0.001"), "{e}");
    }
}
