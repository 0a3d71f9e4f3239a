//! The resolution presets (smoke, quick, paper) on either discretisation, and the specs derived
//! from a spec: its error-estimate companions, coarsened and crack-tied versions.

use super::spec::{
    CrackSpec, DiscretisationKind, DiscretisationSpec, GmshSpec, LaminateSpec, ReceiverSpec,
    SceneSpec, TransmitterSpec,
};
use crate::accuracy::Refinement;
use crate::contact::ContactOptions;
use crate::error::{Error, Result};
use crate::laminate::StochasticSpec;
use serde::{Deserialize, Serialize};

/// The resolution presets of the experiments: the scene ([`SceneSpec::preset`]) and the
/// TR-NEWS timings ([`crate::trnews::TrNewsSpec::preset`]) that go with it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resolution {
    /// The report's scene on a mesh that runs in minutes (the default).
    #[default]
    Quick,
    /// The report's scene at the report's element size (20 um x 10 um; hours).
    Paper,
    /// A small, fast scene with short signals, for tests and CI.
    Smoke,
}

impl std::str::FromStr for Resolution {
    type Err = Error;

    /// `quick`, `paper` or `smoke`; anything else is refused, naming the value.
    fn from_str(name: &str) -> Result<Resolution> {
        match name {
            "quick" => Ok(Resolution::Quick),
            "paper" => Ok(Resolution::Paper),
            "smoke" => Ok(Resolution::Smoke),
            other => Err(Error::invalid(
                "resolution",
                other,
                "expected quick, paper or smoke",
            )),
        }
    }
}

/// Lowest order across an element row at the quick (and smoke) resolution: the 20-60 um
/// epoxy layers at order 2 (see [`SemPreset::of`]).
const MIN_ORDER_Y_QUICK: usize = 2;
/// Highest order across an element row at the quick resolution: the plies up to order 4,
/// where the step allows it (see [`SemPreset::of`]).
const MAX_ORDER_Y_QUICK: usize = 4;
/// Lowest order across an element row at the paper resolution: the epoxy at order 3.
const MIN_ORDER_Y_PAPER: usize = 3;

/// Spectral elements of a resolution preset: element sizes and the orders (along x, and the
/// least and most across y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SemPreset {
    /// Element width (m).
    pub element_size_x_m: f64,
    /// Largest element height (m).
    pub element_size_y_m: f64,
    /// Polynomial order along x.
    pub order_x: usize,
    /// Lowest polynomial order across an element row.
    pub min_order_y: usize,
    /// Highest polynomial order across an element row.
    pub max_order_y: usize,
}

impl SemPreset {
    /// The spectral elements of each resolution: quick (and smoke) order 7 along x on 0.5 mm
    /// elements with orders 2-4 across, paper order 6 on 0.25 mm with orders 3-6 across. The
    /// elements and orders along x were chosen on the default experiment, the floors across
    /// on the exact normal-incidence solution through the plies
    /// (docs/src/validation/normal-incidence.md), quick's ceiling across on the default
    /// experiment: a ceiling of 3 left the plies' error across, which its error estimate's
    /// companions (lower along x only) do not see, at half the error (0.50% of the first-pass
    /// response against 0.25% at 4; docs/src/validation/default-experiment.md).
    pub fn of(resolution: Resolution) -> SemPreset {
        let (size, order_x, min_order_y, max_order_y) = match resolution {
            Resolution::Smoke | Resolution::Quick => {
                (0.5e-3, 7, MIN_ORDER_Y_QUICK, MAX_ORDER_Y_QUICK)
            }
            Resolution::Paper => (0.25e-3, 6, MIN_ORDER_Y_PAPER, 6),
        };
        SemPreset {
            element_size_x_m: size,
            element_size_y_m: size,
            order_x,
            min_order_y,
            max_order_y,
        }
    }
}

impl SceneSpec {
    /// The default scene at the `paper` resolution: 20 um columns, 10 um rows (in a 1-D
    /// model of the 50-pair stack, 10 um rows give ~0.3% error in the low-passed surface
    /// response; the 2-D error is what the `accuracy` estimates measure).
    pub fn paper() -> SceneSpec {
        SceneSpec {
            element_size_x_m: 20e-6,
            element_size_y_m: 10e-6,
            ..Default::default()
        }
    }

    /// A small scene for smoke tests of scripts: 10 pairs (~2.4 mm), 6 mm wide, coarse mesh,
    /// four receivers, a 1.2 mm crack 0.8 mm deep. Seconds per run, not physics-grade.
    pub fn smoke() -> SceneSpec {
        SceneSpec {
            laminate: LaminateSpec::Stochastic(StochasticSpec {
                pairs: 10,
                ..Default::default()
            }),
            width_m: 6e-3,
            element_size_x_m: 80e-6,
            element_size_y_m: 40e-6,
            transmitter: TransmitterSpec {
                depth_top_m: 0.2e-3,
                depth_bottom_m: 1.2e-3,
                ..Default::default()
            },
            receivers: ReceiverSpec {
                x_m: vec![1.5e-3, 2.5e-3, 3.5e-3, 4.5e-3],
                ..Default::default()
            },
            crack: Some(CrackSpec {
                depth_m: 0.8e-3,
                x_center_m: Some(3e-3),
                length_m: 1.2e-3,
                ..Default::default()
            }),
            ..Default::default()
        }
    }

    /// The scene of a resolution preset on the default discretisation
    /// ([`DiscretisationKind::default`]: the spectral elements of [`SemPreset::of`]).
    pub fn preset(resolution: Resolution) -> SceneSpec {
        SceneSpec::preset_on(resolution, DiscretisationKind::default())
    }

    /// The scene of a resolution preset on the discretisation `kind`: for T3 the scene's own
    /// triangles ([`SceneSpec::default`], [`SceneSpec::paper`], [`SceneSpec::smoke`]); for
    /// spectral elements the same scene with the element sizes and orders of
    /// [`SemPreset::of`].
    pub fn preset_on(resolution: Resolution, kind: DiscretisationKind) -> SceneSpec {
        let t3 = match resolution {
            Resolution::Quick => SceneSpec::default(),
            Resolution::Paper => SceneSpec::paper(),
            Resolution::Smoke => SceneSpec::smoke(),
        };
        match kind {
            DiscretisationKind::T3 => t3,
            DiscretisationKind::Sem => {
                let p = SemPreset::of(resolution);
                SceneSpec {
                    element_size_x_m: p.element_size_x_m,
                    element_size_y_m: p.element_size_y_m,
                    discretisation: DiscretisationSpec::Sem {
                        order_x: p.order_x,
                        min_order_y: p.min_order_y,
                        max_order_y: p.max_order_y,
                        extra_order_y: 0,
                        rule_order_x: None,
                        fine_x: None,
                    },
                    ..t3
                }
            }
        }
    }

    /// The companions of an error estimate (the same laminate draw;
    /// [`SceneSpec::refinement`]), in the order the estimates take them
    /// ([`crate::accuracy::Estimate::scalar_of`]), for this scene run at step `dt_s`: on
    /// linear triangles the scene at 2x and 4x the element sizes, each at its own stable step
    /// (the estimate's order 2 is the space and time error together). On spectral elements
    /// the same elements at orders `order_x` - 1 and `order_x` - 2 along x (a coarser element
    /// would leave the asymptotic range at once: a halving of h changes an order-7 error by
    /// 2^14), with every row's order across as this scene has it and at its step `dt_s`, so
    /// that they differ from it along x alone; then the companion across the layers: every
    /// row one order higher across, at its own stable step (a higher order across shortens
    /// it). Companions along x that chose their own rows and steps saw an error across of
    /// their own, 1.4-12x the true error at oblique incidence
    /// (docs/src/validation/normal-incidence.md). Where the crack's faces touch (a contact),
    /// last the scene at half the step `dt_s`: it sees the contact's error in the step, which
    /// the time-dispersion transforms do not remove and the others share, at that step (or,
    /// across, near it; [`crate::accuracy`]).
    ///
    /// On a Gmsh mesh of quadrilaterals (`gmsh.order` p) the companions are the same mesh at
    /// orders p - 1 and p - 2, in both directions (an unstructured element has no direction
    /// across), at step `dt_s`, and with contact the scene at half the step; there is no
    /// companion across. A Gmsh mesh of triangles has none: its mesh is the file's (an
    /// error).
    pub fn companions(&self, dt_s: f64) -> Result<Vec<SceneSpec>> {
        if let Some(g) = &self.gmsh {
            return self.mesh_order_companions(g, dt_s);
        }
        match self.discretisation {
            DiscretisationSpec::T3 => Ok(vec![self.coarsened(2.0)?, self.coarsened(4.0)?]),
            DiscretisationSpec::Sem {
                order_x,
                min_order_y,
                max_order_y,
                extra_order_y,
                rule_order_x,
                fine_x,
            } => {
                if order_x < 3 {
                    return Err(Error::invalid(
                        "discretisation.order_x",
                        order_x,
                        "error estimates on spectral elements compare orders p, p - 1 and \
                         p - 2: they need order_x >= 3",
                    ));
                }
                let along_x = |by: usize| SceneSpec {
                    discretisation: DiscretisationSpec::Sem {
                        order_x: order_x - by,
                        min_order_y,
                        max_order_y,
                        extra_order_y,
                        rule_order_x: Some(rule_order_x.unwrap_or(order_x)),
                        fine_x,
                    },
                    time_step_s: Some(dt_s),
                    ..self.clone()
                };
                let across = SceneSpec {
                    discretisation: DiscretisationSpec::Sem {
                        order_x,
                        min_order_y,
                        max_order_y,
                        extra_order_y: extra_order_y + 1,
                        rule_order_x,
                        fine_x,
                    },
                    time_step_s: None,
                    ..self.clone()
                };
                let mut companions = vec![along_x(1), along_x(2), across];
                if self.contact().is_some() {
                    companions.push(self.at_half_the_step(dt_s));
                }
                Ok(companions)
            }
        }
    }

    /// The companion in time of a scene with contact run at step `dt_s`: the same scene at
    /// half that step ([`SceneSpec::companions`]).
    fn at_half_the_step(&self, dt_s: f64) -> SceneSpec {
        SceneSpec {
            time_step_s: Some(dt_s / 2.0),
            ..self.clone()
        }
    }

    /// The companions of a Gmsh scene ([`SceneSpec::companions`]).
    fn mesh_order_companions(&self, g: &GmshSpec, dt_s: f64) -> Result<Vec<SceneSpec>> {
        let Some(order) = g.order else {
            return Err(file_mesh(g));
        };
        if order < 3 {
            return Err(Error::invalid(
                "gmsh.order",
                order,
                "error estimates on spectral elements compare orders p, p - 1 and p - 2: \
                 they need order >= 3",
            ));
        }
        let mut companions: Vec<SceneSpec> = [1, 2]
            .map(|by| SceneSpec {
                gmsh: Some(GmshSpec {
                    order: Some(order - by),
                    ..g.clone()
                }),
                time_step_s: Some(dt_s),
                ..self.clone()
            })
            .into();
        if self.contact().is_some() {
            companions.push(self.at_half_the_step(dt_s));
        }
        Ok(companions)
    }

    /// The companions of [`SceneSpec::companions`], as the messages name them.
    pub fn companions_named(&self) -> &'static str {
        if self.gmsh.as_ref().is_some_and(|g| g.order.is_some()) {
            return match self.contact() {
                Some(_) => "orders p-1 and p-2 and half the step",
                None => "orders p-1 and p-2",
            };
        }
        match self.discretisation {
            DiscretisationSpec::T3 => "2h and 4h",
            DiscretisationSpec::Sem { .. } if self.contact().is_some() => {
                "orders p-1 and p-2 along x, one more across and half the step"
            }
            DiscretisationSpec::Sem { .. } => "orders p-1 and p-2 along x and one more across",
        }
    }

    /// The contact options of the crack, as the spec gives them (None: no crack, an open
    /// crack, or tied faces).
    pub fn contact(&self) -> Option<ContactOptions> {
        match &self.gmsh {
            None => self
                .crack
                .as_ref()
                .filter(|c| !c.tied)
                .and_then(|c| c.contact),
            Some(g) => g.crack_line.filter(|_| !g.tied).and(g.contact),
        }
    }

    /// How [`SceneSpec::companions`] refine this scene (on the layered rectangle along x, the
    /// companion across the layers the third; on a Gmsh mesh of quadrilaterals the order in
    /// both directions), and whether its results depend smoothly on the discretisation (not
    /// with a crack whose faces follow the instantaneous Coulomb law with friction).
    pub fn refinement(&self) -> Refinement {
        let smooth = self
            .contact()
            .is_none_or(|c| c.friction == 0.0 || c.normal_stress_lag_s > 0.0);
        if let Some(top) = self.gmsh.as_ref().and_then(|g| g.order) {
            return Refinement::Orders {
                top,
                across: false,
                smooth,
            };
        }
        match self.discretisation {
            DiscretisationSpec::T3 => Refinement::ElementSizes,
            DiscretisationSpec::Sem { order_x, .. } => Refinement::Orders {
                top: order_x,
                across: true,
                smooth,
            },
        }
    }

    /// The same scene (same laminate draw) with element sizes (a band of fine columns' too)
    /// multiplied by `factor`: the companions of an error estimate on linear triangles and
    /// the pilots of a tolerance. A Gmsh scene has no element sizes to change (its mesh is
    /// the file's): an error.
    pub fn coarsened(&self, factor: f64) -> Result<SceneSpec> {
        if let Some(g) = &self.gmsh {
            return Err(file_mesh(g));
        }
        let mut discretisation = self.discretisation;
        if let DiscretisationSpec::Sem {
            fine_x: Some(band), ..
        } = &mut discretisation
        {
            band.element_size_m *= factor;
        }
        Ok(SceneSpec {
            element_size_x_m: self.element_size_x_m * factor,
            element_size_y_m: self.element_size_y_m * factor,
            discretisation,
            ..self.clone()
        })
    }

    /// The uncracked companion: the same scene with the crack's faces tied. It has the same
    /// mesh as the cracked scene (nodes, rows, columns; only the crack's duplicated nodes are
    /// missing) and the same time step (see [`Scene::build`]), so that cracked-vs-uncracked
    /// comparisons differ only by the crack. `crack: None` instead gives the laminate alone
    /// with its own stability estimate.
    pub fn uncracked(&self) -> SceneSpec {
        SceneSpec {
            crack: self.crack.as_ref().map(|c| CrackSpec {
                tied: true,
                ..c.clone()
            }),
            gmsh: self.gmsh.as_ref().map(|g| GmshSpec {
                tied: true,
                ..g.clone()
            }),
            ..self.clone()
        }
    }
}

/// A Gmsh scene's element sizes are the file's: a tolerance, or an error estimate on its
/// triangles, would coarsen them.
fn file_mesh(g: &GmshSpec) -> Error {
    Error::invalid(
        "gmsh.path",
        &g.path,
        "tolerances, and error estimates on triangles, coarsen the layered scene's mesh; a \
         Gmsh scene's mesh is the file's (run without tolerance; error estimates need \
         spectral elements, gmsh.order)",
    )
}
