//! A whole experiment setup, described by data (a Rhai object map or JSON) and built into a
//! model: laminate -> mesh -> crack -> model, plus the transmitter and the receivers
//! (report Sec. 5.1, Fig. 14). A scene builds only what it names: no crack means no contact
//! pairs, no absorbing side means no dashpots.

use crate::accuracy::Refinement;
use crate::contact::ContactOptions;
use crate::error::{require_positive, require_within, Error, Result};
use crate::fem::{AbsorbingEdge, Model};
use crate::laminate::{Laminate, Layer, StochasticSpec};
use crate::material::{Orthotropic, Plane};
use crate::mesh::{Grid, Mesh, Side};
use crate::sem::{SemModel, SemSpec};
use crate::signal::Signal;
use crate::solve::{
    self, point_receiver, segment_receiver, segment_shares, Quantity, Receiver, RunConfig,
    RunOutput, StabilityEstimate,
};
use crate::transducer::TransducerSpec;
use serde::{Deserialize, Serialize};

mod sem;

/// How the layer stack is made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum LaminateSpec {
    /// The stochastic CFRP laminate of Sec. 2.2.1.
    Stochastic(StochasticSpec),
    /// Explicit layers from the top surface down.
    Layers {
        /// Layers, top first.
        layers: Vec<LayerSpec>,
    },
    /// A homogeneous block: one layer.
    Homogeneous {
        /// Its material.
        material: MaterialSpec,
        /// Thickness (m).
        thickness_m: f64,
    },
}

/// A scene meshed by Gmsh: the T3 elements of an MSH 4.1 file (see
/// [`crate::mesh::gmsh::read_msh`]), materials by physical surface group, and optionally a
/// crack drawn as a physical line. The region's edges are the sides of the mesh's bounding
/// box (sources, receivers and edge conditions refer to them); `laminate`, `width_m` and
/// the element sizes are not used.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GmshSpec {
    /// The .msh file. Scripts give it relative to their input directory (the script's
    /// directory), see [`crate::script::HostContext::read_input`].
    pub path: String,
    /// The material of each physical surface group, keyed by the group's tag (`"1"`).
    pub materials: std::collections::BTreeMap<String, MaterialSpec>,
    /// Tag of the physical line that is the crack: a horizontal straight line of element
    /// edges strictly inside the mesh (contact acts on u_y, report Sec. 4.9).
    #[serde(default)]
    pub crack_line: Option<i32>,
    /// Contact on the crack faces; `None` leaves the crack open.
    #[serde(default = "default_contact")]
    pub contact: Option<ContactOptions>,
    /// Faces tied (the uncracked companion, [`SceneSpec::uncracked`]).
    #[serde(default)]
    pub tied: bool,
    /// The file's bytes when the caller has read it (scripts read it inside their sandbox);
    /// `None` reads `path`.
    #[serde(skip)]
    pub bytes: Option<std::sync::Arc<Vec<u8>>>,
}

fn default_contact() -> Option<ContactOptions> {
    Some(ContactOptions::default())
}

/// A material by preset name (`epoxy`, `fabric_0_90`, `fabric_45_45`) or by its constants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum MaterialSpec {
    /// A preset name.
    Preset(String),
    /// Orthotropic engineering constants.
    Custom(Orthotropic),
}

/// One explicit layer.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// Its material.
    pub material: MaterialSpec,
    /// Thickness (m).
    pub thickness_m: f64,
}

impl MaterialSpec {
    fn constants(&self) -> Result<Orthotropic> {
        match self {
            MaterialSpec::Preset(name) => Orthotropic::preset(name),
            MaterialSpec::Custom(o) => Ok(o.clone()),
        }
    }
}

impl Default for LaminateSpec {
    fn default() -> Self {
        LaminateSpec::Stochastic(StochasticSpec::default())
    }
}

/// The transmitter: a traction on a segment of the right edge (report Fig. 14).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransmitterSpec {
    /// Depth of the segment's upper end below the top surface (m).
    pub depth_top_m: f64,
    /// Depth of the segment's lower end (m).
    pub depth_bottom_m: f64,
    /// Direction of the traction, degrees counter-clockwise from +x. 110 = 70 degrees from the
    /// right edge's inward normal (-x), turned toward the top surface (report: 70 degrees).
    pub angle_deg: f64,
    /// Peak traction of transmitted signals (Pa); report: 50 kPa.
    pub peak_pa: f64,
}

impl Default for TransmitterSpec {
    fn default() -> Self {
        TransmitterSpec {
            depth_top_m: 1e-3,
            depth_bottom_m: 4e-3,
            angle_deg: 110.0,
            peak_pa: 50e3,
        }
    }
}

/// The receivers: on the top surface at `x_m`, numbered 1.. from left to right (the last one
/// nearest the transmitter, like the report's receiver 5), then those of `at`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReceiverSpec {
    /// x positions (m).
    pub x_m: Vec<f64>,
    /// Width of the transducer face averaged over, for receivers on an edge (m); 0 records
    /// the nearest node (T3) or the point itself, interpolated (spectral elements).
    pub aperture_m: f64,
    /// Recorded component: 0 = u_x, 1 = u_y (default, like a normal-incidence transducer).
    pub component: usize,
    /// Displacement or velocity.
    pub quantity: Quantity,
    /// More receivers, numbered after those of `x_m`: points in the body or positions on any
    /// edge.
    pub at: Vec<ReceiverAt>,
}

impl Default for ReceiverSpec {
    fn default() -> Self {
        ReceiverSpec {
            x_m: vec![4e-3, 6e-3, 8e-3, 10e-3, 12e-3],
            at: vec![],
            aperture_m: 0.0,
            component: 1,
            quantity: Quantity::Displacement,
        }
    }
}

/// A source of the transmitted signal. Every source of a scene is driven by the same
/// signal (Pa), scaled by its `scale`; their nodal loads add. Edge sources act on a range
/// along their edge, `x_m: [from, to]` on the top and bottom edges and
/// `depth_m: [from, to]` below the top surface on the left and right edges, or on the whole
/// edge without a range; the load is the consistent nodal load of a uniform traction.
/// (The edge-source variants repeat their range fields rather than share a flattened struct:
/// serde cannot deny unknown fields through `flatten`, and strict maps matter more here.)
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum SourceSpec {
    /// A traction in a fixed direction: t = scale (cos angle, sin angle) drive(t).
    Traction {
        /// The edge.
        edge: Side,
        /// x range on the top or bottom edge (m).
        #[serde(default)]
        x_m: Option<[f64; 2]>,
        /// Depth range below the top surface on the left or right edge (m).
        #[serde(default)]
        depth_m: Option<[f64; 2]>,
        /// Direction, degrees counter-clockwise from +x.
        angle_deg: f64,
        /// Factor on the drive signal.
        #[serde(default = "unit_scale")]
        scale: f64,
    },
    /// A uniform normal traction t = scale drive(t) n, n the outward normal of the edge
    /// (positive pulls the surface outward).
    Normal {
        /// The edge.
        edge: Side,
        /// x range on the top or bottom edge (m).
        #[serde(default)]
        x_m: Option<[f64; 2]>,
        /// Depth range below the top surface on the left or right edge (m).
        #[serde(default)]
        depth_m: Option<[f64; 2]>,
        /// Factor on the drive signal.
        #[serde(default = "unit_scale")]
        scale: f64,
    },
    /// A uniform shear traction t = scale drive(t) e, e = +x on the top and bottom edges and
    /// +y on the left and right edges.
    Shear {
        /// The edge.
        edge: Side,
        /// x range on the top or bottom edge (m).
        #[serde(default)]
        x_m: Option<[f64; 2]>,
        /// Depth range below the top surface on the left or right edge (m).
        #[serde(default)]
        depth_m: Option<[f64; 2]>,
        /// Factor on the drive signal.
        #[serde(default = "unit_scale")]
        scale: f64,
    },
    /// A point force on the node nearest to (x_m, y_m), y above the bottom edge: force per
    /// unit thickness scale (m) x drive (Pa), in N/m, in direction `angle_deg`.
    Point {
        /// x (m).
        x_m: f64,
        /// y above the bottom edge (m).
        y_m: f64,
        /// Direction, degrees counter-clockwise from +x.
        angle_deg: f64,
        /// Factor on the drive signal (m).
        #[serde(default = "unit_scale")]
        scale: f64,
    },
}

fn unit_scale() -> f64 {
    1.0
}

/// A receiver beyond the top-surface row of [`ReceiverSpec::x_m`]: a point anywhere in the
/// body, `#{x_m, y_m}` (y above the bottom edge), interpolated from the element that holds
/// it (T3: its linear shape functions, barycentric weights; spectral elements: the GLL
/// Lagrange polynomials); or a position on an
/// edge, `#{edge, x_m}` (top, bottom) or `#{edge, depth_m}` (left, right), averaged over the
/// transducer aperture like the top-surface receivers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReceiverAt {
    /// The edge, for an edge receiver.
    #[serde(default)]
    pub edge: Option<Side>,
    /// x (m): of a point, or along the top or bottom edge.
    #[serde(default)]
    pub x_m: Option<f64>,
    /// y above the bottom edge (m), of a point.
    #[serde(default)]
    pub y_m: Option<f64>,
    /// Depth below the top surface along the left or right edge (m).
    #[serde(default)]
    pub depth_m: Option<f64>,
}

impl ReceiverAt {
    /// The fields given, as a script writes them: `#{edge: "left", x_m: 0.001}`.
    fn describe(&self) -> String {
        let mut fields = Vec::new();
        if let Some(e) = self.edge {
            fields.push(format!("edge: \"{}\"", e.name()));
        }
        for (name, v) in [
            ("x_m", self.x_m),
            ("y_m", self.y_m),
            ("depth_m", self.depth_m),
        ] {
            if let Some(v) = v {
                fields.push(format!("{name}: {v}"));
            }
        }
        format!("#{{{}}}", fields.join(", "))
    }
}

/// The condition on one edge of the region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeCondition {
    /// Traction-free.
    Free,
    /// Both displacement components zero.
    Fixed,
    /// Roller: the normal displacement is zero and the edge slides freely (u_n = 0, t_s = 0).
    Roller,
    /// Absorbing, as [`SceneSpec::absorber`] says (Lysmer-Kuhlemeyer dashpots, with or
    /// without the springs of the viscous-spring boundary).
    Absorbing,
    /// Periodic, left and right together: the node columns x = 0 and x = width are tied,
    /// u(0, y) = u(width, y) (see [`crate::fem::Model::periodic`]).
    Periodic,
}

/// Conditions per edge; an edge left out keeps what [`SceneSpec::absorbing`] gives it
/// (absorbing if listed, free otherwise).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EdgeConditions {
    /// Bottom edge.
    pub bottom: Option<EdgeCondition>,
    /// Top edge.
    pub top: Option<EdgeCondition>,
    /// Left edge.
    pub left: Option<EdgeCondition>,
    /// Right edge.
    pub right: Option<EdgeCondition>,
}

/// How the absorbing sides absorb.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum Absorber {
    /// The report's Lysmer-Kuhlemeyer dashpots alone (Fig. 3). They have no static
    /// stiffness: the block drifts unless `fix_bottom_corners` pins it.
    Dashpot,
    /// Dashpots plus the springs of the viscous-spring boundary (see
    /// [`crate::fem::AbsorbingEdge`]): the edge also carries the static stiffness of the
    /// medium beyond it, so the block neither drifts nor needs point supports.
    ViscousSpring {
        /// Distance R from the wave source to every absorbing side (m); `None` takes, per
        /// side, the distance from the transmitter's centre to the side.
        #[serde(default)]
        source_distance_m: Option<f64>,
    },
}

/// The resolution presets of the experiments: the scene ([`SceneSpec::preset`]) and the
/// TR-NEWS timings ([`crate::trnews::TrNewsSpec::preset`]) that go with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resolution {
    /// The report's scene on a mesh that runs in minutes (the default).
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

/// A horizontal crack with contacting faces (report Sec. 4.9).
///
/// The crack never changes the discretisation: the mesh is the one built without it, the
/// crack line snaps to the nearest interior element row line and each tip to the nearest
/// interior column line, each within half the local row height / column width (see
/// [`crate::mesh::Grid::snap_row`]); [`Scene::crack_placement`] reports where it went.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CrackSpec {
    /// Depth below the top surface (m); snapped to the nearest interior mesh row line.
    pub depth_m: f64,
    /// x of the crack centre (m); `None` puts it under the middle receiver. The tips
    /// x_center_m -+ length_m / 2 snap to the nearest interior column lines.
    pub x_center_m: Option<f64>,
    /// Length (m).
    pub length_m: f64,
    /// Contact on the faces; `None` leaves the crack open (faces pass freely).
    pub contact: Option<ContactOptions>,
    /// Faces tied: no node is split, so the model is the uncracked laminate on the cracked
    /// scene's mesh, run with the cracked scene's time step ([`SceneSpec::uncracked`]).
    pub tied: bool,
}

impl Default for CrackSpec {
    fn default() -> Self {
        CrackSpec {
            depth_m: 2e-3,
            x_center_m: None,
            length_m: 2e-3,
            contact: Some(ContactOptions::default()),
            tied: false,
        }
    }
}

/// Everything that defines a scene. `Default` is the report's configuration at the quick
/// resolution; [`SceneSpec::paper`] refines the mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSpec {
    /// Layer stack.
    pub laminate: LaminateSpec,
    /// 2D idealisation.
    pub plane: Plane,
    /// Width of the modelled region (m).
    pub width_m: f64,
    /// Element size along x (m): must resolve the shortest wavelength (epoxy shear at 2 MHz: 0.52 mm).
    pub element_size_x_m: f64,
    /// Largest element height (m); thin layers get at least one row.
    pub element_size_y_m: f64,
    /// Absorbing sides (report Fig. 3: bottom and left), the rest of the region's edge is free.
    pub absorbing: Vec<Side>,
    /// Conditions per edge (free, fixed, roller, absorbing, periodic), overriding `absorbing`
    /// for the edges they name.
    pub edges: EdgeConditions,
    /// How the absorbing sides absorb (default: viscous-spring; `#{kind: "dashpot"}` is the
    /// report's).
    pub absorber: Absorber,
    /// Fix both DOFs of the two bottom corners against rigid drift (report Fig. 3: four
    /// fixed DOFs). Off by default: point supports make the low-frequency response depend
    /// on the mesh; the viscous-spring edges hold the block instead.
    pub fix_bottom_corners: bool,
    /// The transducers' band, on transmission and reception (default 0.2-2 MHz, see
    /// [`crate::transducer`]); `None` transmits the drive signal as the traction and records
    /// the raw receiver quantity, as in the report.
    pub transducer: Option<TransducerSpec>,
    /// The transmitter.
    pub transmitter: TransmitterSpec,
    /// Sources of the transmitted signal; when given, they replace the transmitter's segment
    /// (`transmitter.peak_pa` still scales the focusing signals). Empty: the transmitter.
    pub sources: Vec<SourceSpec>,
    /// The receivers.
    pub receivers: ReceiverSpec,
    /// The crack, if any.
    pub crack: Option<CrackSpec>,
    /// A mesh from a Gmsh file instead of the layered rectangle (`None`: the laminate).
    pub gmsh: Option<GmshSpec>,
    /// How the layered rectangle is discretised: linear triangles (default) or spectral
    /// elements, on elements of `element_size_x_m` x at most `element_size_y_m` either way.
    pub discretisation: DiscretisationSpec,
}

/// The discretisations the experiments choose by name (`--set discretisation=t3|sem`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiscretisationKind {
    /// Linear triangles.
    T3,
    /// Spectral elements.
    Sem,
}

impl std::str::FromStr for DiscretisationKind {
    type Err = Error;

    /// `t3` or `sem`; anything else is refused, naming the value.
    fn from_str(name: &str) -> Result<DiscretisationKind> {
        match name {
            "t3" => Ok(DiscretisationKind::T3),
            "sem" => Ok(DiscretisationKind::Sem),
            other => Err(Error::invalid(
                "discretisation",
                other,
                "expected t3 or sem",
            )),
        }
    }
}

/// Lowest order across an element row at the quick (and smoke) resolution: the 20-60 um
/// epoxy layers at order 2 (see [`SemPreset::of`]).
const MIN_ORDER_Y_QUICK: usize = 2;
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
    /// elements with orders 2-3 across, paper order 6 on 0.25 mm with orders 3-6 across. The
    /// elements and orders along x were chosen on the default experiment, the floors across
    /// on the exact normal-incidence solution through the plies, where quick is 0.29% off and
    /// paper 0.08% (docs/src/validation/normal-incidence.md).
    pub fn of(resolution: Resolution) -> SemPreset {
        let (size, order_x, min_order_y, max_order_y) = match resolution {
            Resolution::Smoke | Resolution::Quick => (0.5e-3, 7, MIN_ORDER_Y_QUICK, 3),
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

/// The discretisation of a scene's layered rectangle. Both cut it along the same lines: columns
/// of at most `element_size_x_m`, rows of at most `element_size_y_m` with every layer
/// interface a row line. A spectral element spans `order` GLL intervals, so it wants about
/// `order` times the element size of a T3 mesh of the same accuracy (see
/// docs/src/validation/spectral-elements.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum DiscretisationSpec {
    /// Linear triangles with lumped mass, each cell split along its rising diagonal (the
    /// report's method; a Gmsh mesh is always this).
    #[default]
    T3,
    /// Spectral elements ([`crate::sem`]): GLL points of `order_x` along x in every element,
    /// and across each element row at least `min_order_y`, and above it the highest order up
    /// to `max_order_y` that does not shorten the time step, judged per material
    /// ([`crate::sem::SemSpec`]).
    Sem {
        /// Polynomial order along x.
        order_x: usize,
        /// Lowest polynomial order across an element row (1 when not given).
        #[serde(default = "order_one")]
        min_order_y: usize,
        /// Highest polynomial order across an element row.
        max_order_y: usize,
    },
}

fn order_one() -> usize {
    1
}

impl DiscretisationSpec {
    /// How spectral elements of these orders cut `spec`'s laminate (None on triangles).
    pub fn sem_cut(&self, spec: &SceneSpec) -> Option<SemSpec> {
        match *self {
            DiscretisationSpec::T3 => None,
            DiscretisationSpec::Sem {
                order_x,
                min_order_y,
                max_order_y,
            } => Some(SemSpec {
                order_x,
                min_order_y,
                max_order_y,
                element_size_x_m: spec.element_size_x_m,
                element_size_y_m: spec.element_size_y_m,
            }),
        }
    }
}

/// The report's default scene on its own linear triangles, 60 x 40 um: the `quick` preset on
/// T3 ([`SceneSpec::preset_on`]; the experiments' `quick` preset is this scene on spectral
/// elements).
impl Default for SceneSpec {
    fn default() -> Self {
        SceneSpec {
            laminate: LaminateSpec::default(),
            plane: Plane::Strain,
            width_m: 16e-3,
            element_size_x_m: 60e-6,
            element_size_y_m: 40e-6,
            absorbing: vec![Side::Bottom, Side::Left],
            edges: EdgeConditions::default(),
            absorber: Absorber::ViscousSpring {
                source_distance_m: None,
            },
            fix_bottom_corners: false,
            transducer: Some(TransducerSpec::default()),
            transmitter: TransmitterSpec::default(),
            sources: vec![],
            receivers: ReceiverSpec::default(),
            crack: Some(CrackSpec::default()),
            gmsh: None,
            discretisation: DiscretisationSpec::T3,
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

    /// The scene of a resolution preset on its default discretisation, the spectral
    /// elements of [`SemPreset::of`] (chosen on an exact solution through the plies:
    /// docs/src/validation/normal-incidence.md).
    pub fn preset(resolution: Resolution) -> SceneSpec {
        SceneSpec::preset_on(resolution, DiscretisationKind::Sem)
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
                    },
                    ..t3
                }
            }
        }
    }

    /// The two companions of an error estimate (the same laminate draw;
    /// [`SceneSpec::refinement`]): on linear triangles the scene at 2x and 4x
    /// the element sizes; on spectral elements the same elements at orders `order_x` - 1 and
    /// `order_x` - 2 along x, at most that many across (a coarser element would leave the
    /// asymptotic range at once: a halving of h changes an order-7 error by 2^14).
    pub fn companions(&self) -> Result<[SceneSpec; 2]> {
        match self.discretisation {
            DiscretisationSpec::T3 => Ok([self.coarsened(2.0)?, self.coarsened(4.0)?]),
            DiscretisationSpec::Sem {
                order_x,
                min_order_y,
                max_order_y,
            } => {
                if order_x < 3 {
                    return Err(Error::invalid(
                        "discretisation.order_x",
                        order_x,
                        "error estimates on spectral elements compare orders p, p - 1 and \
                         p - 2: they need order_x >= 3",
                    ));
                }
                let lowered = |by: usize| SceneSpec {
                    discretisation: DiscretisationSpec::Sem {
                        order_x: order_x - by,
                        min_order_y: min_order_y.min(order_x - by),
                        max_order_y: max_order_y.min(order_x - by),
                    },
                    ..self.clone()
                };
                Ok([lowered(1), lowered(2)])
            }
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

    /// How [`SceneSpec::companions`] refine this scene.
    pub fn refinement(&self) -> Refinement {
        match self.discretisation {
            DiscretisationSpec::T3 => Refinement::ElementSizes,
            DiscretisationSpec::Sem { .. } => Refinement::Orders,
        }
    }

    /// The same scene (same laminate draw) with element sizes multiplied by `factor`: the
    /// companions of an error estimate on linear triangles and the pilots of a tolerance. A
    /// Gmsh scene has no element sizes to change (its mesh is the file's): an error.
    pub fn coarsened(&self, factor: f64) -> Result<SceneSpec> {
        if let Some(g) = &self.gmsh {
            return Err(Error::invalid(
                "gmsh.path",
                &g.path,
                "error estimates and tolerances refine the layered scene's mesh; a Gmsh \
                 scene's mesh is the file's (run without error_estimate or tolerance)",
            ));
        }
        Ok(SceneSpec {
            element_size_x_m: self.element_size_x_m * factor,
            element_size_y_m: self.element_size_y_m * factor,
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

pub use crate::solve::STEP_FRACTION;

/// The discrete model of a scene.
// One per scene, shared behind an Arc: the variants' different sizes cost nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Body {
    /// Linear triangles (the report's method).
    T3(Model),
    /// Spectral elements, with the T3 triangulation of their node grid (the same node
    /// numbering, crack duplicates included) on which nodes are selected, fields are plotted
    /// and written as VTU (each GLL cell as two triangles).
    Sem {
        /// The spectral elements.
        model: SemModel,
        /// Their node grid as triangles.
        nodes: Mesh,
    },
}

/// A built scene: the model, the transmitter's nodal weights, the receivers.
#[derive(Clone, Debug)]
pub struct Scene {
    /// What it was built from.
    pub spec: SceneSpec,
    /// The layer stack.
    pub laminate: Laminate,
    /// The discrete model.
    pub body: Body,
    /// Transmitter nodal weights per unit traction.
    pub transmitter: Vec<(usize, f64)>,
    /// Receivers 1..n.
    pub receivers: Vec<Receiver>,
    /// Where the crack was put on the mesh, requested vs used (None without a crack).
    pub crack_placement: Option<CrackPlacement>,
    /// Explicit stability estimate, computed once.
    pub stability: StabilityEstimate,
}

fn build_laminate(spec: &LaminateSpec, plane: Plane) -> Result<Laminate> {
    match spec {
        LaminateSpec::Stochastic(s) => Laminate::stochastic(s, plane),
        LaminateSpec::Layers { layers } => {
            let mut distinct: Vec<Orthotropic> = Vec::new();
            let mut stack = Vec::new();
            for layer in layers.iter().rev() {
                let constants = layer.material.constants()?;
                let material = distinct
                    .iter()
                    .position(|o| *o == constants)
                    .unwrap_or_else(|| {
                        distinct.push(constants);
                        distinct.len() - 1
                    });
                stack.push(Layer {
                    material,
                    thickness_m: layer.thickness_m,
                });
            }
            let materials = distinct
                .iter()
                .map(|o| o.reduce(plane))
                .collect::<Result<Vec<_>>>()?;
            Laminate::from_layers(materials, stack)
        }
        LaminateSpec::Homogeneous {
            material,
            thickness_m,
        } => Laminate::homogeneous(material.constants()?.reduce(plane)?, *thickness_m),
    }
}

/// The largest traction a transmitter or drive may reach (Pa): 10 GPa, above the strength of
/// any laminate (CFRP fails below 3 GPa); the report drives 50 kPa.
pub const MAX_TRACTION_PA: f64 = 1e10;

/// Physical ranges of the scene's numbers that the build does not meet elsewhere: the
/// transmitter's peak traction in (0, [`MAX_TRACTION_PA`]] and every direction within one
/// turn either way, [-360, 360] degrees (an angle of 1e300 degrees has no direction: its sine
/// is round-off).
fn check_ranges(spec: &SceneSpec) -> Result<()> {
    let peak = spec.transmitter.peak_pa;
    if !(peak.is_finite() && peak > 0.0 && peak <= MAX_TRACTION_PA) {
        return Err(Error::invalid(
            "transmitter.peak_pa",
            peak,
            format!(
                "must be within (0, {MAX_TRACTION_PA:e}] Pa (the focusing signals are scaled to \
                 it; 10 GPa is above the strength of any laminate)"
            ),
        ));
    }
    let turn = |field: &str, angle: f64| {
        require_within(
            field,
            angle,
            -360.0,
            360.0,
            "degrees",
            "one turn either way",
        )
    };
    turn("transmitter.angle_deg", spec.transmitter.angle_deg)?;
    for (i, source) in spec.sources.iter().enumerate() {
        if let SourceSpec::Traction { angle_deg, .. } | SourceSpec::Point { angle_deg, .. } = source
        {
            turn(&format!("sources[{i}].angle_deg"), *angle_deg)?;
        }
    }
    Ok(())
}

/// The rectangle a scene occupies: lower left corner and size (m). Sources, receivers and
/// the viscous-spring distances are placed in it.
#[derive(Clone, Copy, Debug)]
struct Region {
    x0: f64,
    y0: f64,
    width: f64,
    height: f64,
}

/// What a scene is built on: the materials (as a laminate), the mesh, the crack's place on
/// it, and the region.
type Built = (Laminate, Mesh, Option<CrackPlacement>, Region);

/// The layered rectangle [0, width_m] x [0, laminate thickness]: laminate, its mesh and the
/// crack placed on the mesh lines.
fn layered_mesh(spec: &SceneSpec) -> Result<Built> {
    require_positive("width_m", spec.width_m)?;
    let laminate = build_laminate(&spec.laminate, spec.plane)?;
    let height = laminate.thickness_m();
    check_mesh_size(spec, &laminate, (1, 1))?;
    let mesh = Mesh::layered(
        &laminate,
        spec.width_m,
        spec.element_size_x_m,
        spec.element_size_y_m,
        &[],
        &[],
    )?;
    let crack_placement = spec
        .crack
        .as_ref()
        .map(|c| {
            let grid = mesh.grid.as_ref().expect("a layered mesh is a grid");
            place_crack(spec, c, grid, height)
        })
        .transpose()?;
    let region = Region {
        x0: 0.0,
        y0: 0.0,
        width: spec.width_m,
        height,
    };
    Ok((laminate, mesh, crack_placement, region))
}

/// The Gmsh scene: its materials (as a laminate without layers), mesh and crack line; the
/// region is the mesh's bounding box.
fn gmsh_mesh(spec: &SceneSpec, g: &GmshSpec) -> Result<Built> {
    if spec.crack.is_some() {
        return Err(Error::invalid(
            "crack",
            "a rectangular crack",
            "a Gmsh scene takes its crack from gmsh.crack_line: set crack: ()",
        ));
    }
    let bytes =
        match &g.bytes {
            Some(b) => b.clone(),
            None => std::sync::Arc::new(std::fs::read(&g.path).map_err(|e| {
                Error::invalid("gmsh.path", &g.path, format!("cannot be read: {e}"))
            })?),
        };
    let mut materials = Vec::with_capacity(g.materials.len());
    let mut groups = std::collections::HashMap::new();
    for (key, material) in &g.materials {
        let tag: i32 = key.trim().parse().map_err(|_| {
            Error::invalid(
                "gmsh.materials",
                format!("key \"{key}\""),
                "keys are the tags of physical surface groups, e.g. \"1\"",
            )
        })?;
        groups.insert(tag, materials.len());
        materials.push(material.constants()?.reduce(spec.plane)?);
    }
    let mesh = crate::mesh::gmsh::read_msh(&bytes, &groups)
        .map_err(|e| Error::invalid("gmsh.path", &g.path, e.to_string()))?;
    let placement = g
        .crack_line
        .map(|group| gmsh_crack(&bytes, group, &mesh, g.tied))
        .transpose()?;
    let (x0, x1, y0, y1) = mesh.bounds();
    let laminate = Laminate {
        materials,
        layers: vec![],
        draws: vec![],
    };
    let region = Region {
        x0,
        y0,
        width: x1 - x0,
        height: y1 - y0,
    };
    Ok((laminate, mesh, placement, region))
}

/// The crack of a Gmsh scene: the nodes of physical line `group`, which must be a
/// horizontal straight line of mesh nodes (every node of the mesh on its segment belongs to
/// it; that its consecutive nodes are element edges is checked when it is inserted).
fn gmsh_crack(bytes: &[u8], group: i32, mesh: &Mesh, tied: bool) -> Result<CrackPlacement> {
    let points = crate::mesh::gmsh::read_physical_line(bytes, group)
        .map_err(|e| Error::invalid("gmsh.crack_line", group, e.to_string()))?;
    let y = points[0][1];
    let tol = mesh.tolerance();
    if let Some(p) = points.iter().find(|p| (p[1] - y).abs() > tol) {
        return Err(Error::invalid(
            "gmsh.crack_line",
            group,
            format!(
                "the crack must be a horizontal straight line (contact acts on u_y): it has \
                 points at y = {y:e} and {:e} m",
                p[1]
            ),
        ));
    }
    let x0 = points.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let x1 = points
        .iter()
        .map(|p| p[0])
        .fold(f64::NEG_INFINITY, f64::max);
    let on_segment = mesh.nodes_on_segment([x0, y], [x1, y]).len();
    if on_segment != points.len() {
        return Err(Error::invalid(
            "gmsh.crack_line",
            group,
            format!(
                "the line has {} nodes but the mesh has {on_segment} on its segment: the crack \
                 must be one unbroken line of element edges",
                points.len()
            ),
        ));
    }
    let top = mesh.bounds().3;
    Ok(CrackPlacement {
        depth_requested_m: top - y,
        depth_used_m: top - y,
        x0_requested_m: x0,
        x0_used_m: x0,
        x1_requested_m: x1,
        x1_used_m: x1,
        tied,
        y_m: y,
    })
}

impl Scene {
    /// Builds the scene: laminate, layer-conforming mesh, the crack's node pairs, K, M,
    /// dashpots, transmitter, receivers, and the stability estimate.
    ///
    /// The mesh does not depend on the crack (it is snapped onto the mesh lines, see
    /// [`CrackSpec`]). A cracked scene and its tied companion ([`SceneSpec::uncracked`])
    /// share one time step: both take the Lanczos estimate of the cracked (split) model.
    /// That is the smaller limit of the two: tying the faces restricts the split model to
    /// the subspace u_master = u_slave (K_tied = T^T K T and, with row-sum lumping,
    /// M_tied = T^T M T), so by the Rayleigh-quotient (Courant-Fischer) principle
    /// omega_max(tied) <= omega_max(split), and contact by exact multipliers only constrains
    /// the split model further (report Sec. 4.8.2, 4.9).
    pub fn build(spec: &SceneSpec) -> Result<Scene> {
        check_ranges(spec)?;
        if let Some(contact) = spec.contact() {
            contact.validate()?;
        }
        let scene = match spec.discretisation.sem_cut(spec) {
            None => build_t3(spec)?,
            Some(cut) => sem::build(spec, &cut)?,
        };
        crate::budget::check()?;
        let dt_crit = scene.stability.dt_crit_s;
        if !(dt_crit.is_finite() && dt_crit > 0.0) {
            return Err(Error::invalid(
                "laminate (materials)",
                format!("dt_crit = {dt_crit} s"),
                "the critical time step is not a finite positive number: a density or \
                 modulus is too small or too large for double precision",
            ));
        }
        Ok(scene)
    }

    /// The T3 triangulation the scene's nodes live on: the T3 mesh, or the spectral elements'
    /// node grid (same node numbering).
    pub fn mesh(&self) -> &Mesh {
        match &self.body {
            Body::T3(model) => &model.mesh,
            Body::Sem { nodes, .. } => nodes,
        }
    }

    /// Degrees of freedom of the model.
    pub fn dofs(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.dofs(),
            Body::Sem { model, .. } => model.dofs(),
        }
    }

    /// Number of elements: triangles, or spectral elements.
    pub fn elements(&self) -> usize {
        match &self.body {
            Body::T3(model) => model.mesh.triangles.len(),
            Body::Sem { model, .. } => (model.columns_m.len() - 1) * (model.rows_m.len() - 1),
        }
    }

    /// The crack's node pairs (None without a crack or with tied faces).
    pub fn crack(&self) -> Option<&crate::mesh::Crack> {
        match &self.body {
            Body::T3(model) => model.crack.as_ref(),
            Body::Sem { model, .. } => model.crack(),
        }
    }

    /// True when the scene is linear time-invariant: no crack, or a crack without contact.
    pub fn is_linear(&self) -> bool {
        self.crack().is_none() || self.contact().is_none()
    }

    /// The contact options of the scene's crack ([`SceneSpec::contact`]).
    pub fn contact(&self) -> Option<ContactOptions> {
        self.spec.contact()
    }

    /// A run configuration for this scene: its contact options and stability estimate.
    pub fn run_config(&self, duration_s: f64) -> RunConfig {
        RunConfig {
            duration_s,
            contact: self.contact(),
            stability: Some(self.stability),
            ..Default::default()
        }
    }

    /// Drives the transmitter with `drive` (Pa) and records every receiver, through the
    /// transducers' band when the scene has one: the traction is B * drive and each trace
    /// B * the raw receiver quantity (see [`crate::transducer`]).
    pub fn transmit(&self, drive: &Signal, config: &RunConfig) -> Result<RunOutput> {
        require_positive("duration_s", config.duration_s)?;
        if let Some(d) = config.dt_s {
            require_positive("dt_s", d)?;
        }
        let dt = config.dt_s.unwrap_or(self.default_dt_s());
        let samples = config.duration_s / dt;
        let (field, value) = match config.dt_s {
            Some(d) if d < 1e-12 => ("dt_s", d),
            _ => ("duration_s", config.duration_s),
        };
        crate::budget::check_memory(
            field,
            format!("{value} s ({samples:.3e} steps of {dt:.3e} s)"),
            8.0 * samples * (self.receivers.len() as f64 + 4.0),
            "shorten the run",
        )?;
        let Some(t) = &self.spec.transducer else {
            return self.apply_traction(drive, config);
        };
        let mut out = self.apply_traction(&t.transmit(drive, config.duration_s)?, config)?;
        for trace in &mut out.traces {
            *trace = t.receive(trace)?;
        }
        Ok(out)
    }

    /// Applies `traction` (Pa) on the transmitter segment and records the raw receiver
    /// quantities, bypassing the transducers' band.
    pub fn apply_traction(&self, traction: &Signal, config: &RunConfig) -> Result<RunOutput> {
        let source = solve::Source {
            weights: self.transmitter.clone(),
            signal: traction.clone(),
        };
        let stability = config.stability.unwrap_or(self.stability);
        let config = RunConfig {
            stability: Some(stability),
            ..config.clone()
        };
        let out = match &self.body {
            Body::T3(model) => solve::run(model, &[source], &self.receivers, &config)?,
            Body::Sem { model, .. } => sem::run(
                model,
                &[source],
                &self.receivers,
                &config,
                stability.dt_crit_s,
            )?,
        };
        let drive_max = traction.max_abs();
        if drive_max > 0.0
            && out.report.source_work_j == 0.0
            && out
                .traces
                .iter()
                .all(|t| t.samples.iter().all(|&v| v == 0.0))
        {
            return Err(Error::invalid(
                "drive signal (amplitude)",
                format!("{drive_max:e} Pa"),
                "every receiver recorded exactly zero and the source did no work: the input \
                 underflowed in double precision; use a larger amplitude",
            ));
        }
        Ok(out)
    }

    /// The time step runs of this scene use by default ([`STEP_FRACTION`] dt_crit).
    pub fn default_dt_s(&self) -> f64 {
        STEP_FRACTION * self.stability.dt_crit_s
    }
}

/// The T3 scene (see [`Scene::build`]).
fn build_t3(spec: &SceneSpec) -> Result<Scene> {
    let (laminate, mut mesh, crack_placement, region) = match &spec.gmsh {
        None => layered_mesh(spec)?,
        Some(g) => gmsh_mesh(spec, g)?,
    };
    let crack = match &crack_placement {
        Some(p) if !p.tied => Some(p.insert(&mut mesh)?),
        _ => None,
    };
    let conditions = edge_conditions(spec)?;
    let fixed = held_and_pinned_dofs(spec, &mesh, &conditions);
    let on = OnT3(&mesh);
    let transmitter = if spec.sources.is_empty() {
        transmitter_weights(&on, &spec.transmitter, region)?
    } else {
        source_weights(&on, &spec.sources)?
    };
    let receivers = build_receivers(&on, &spec.receivers, region.y0 + region.height)?;
    let absorbing = absorbing_edges(spec, &conditions, &mesh, region)?;
    let mut model = Model::build(mesh, laminate.materials.clone(), &absorbing, fixed, crack)?;
    // The stability estimate below is the untied model's: tying restricts it to the
    // subspace u_l = u_r, which by the Rayleigh-quotient principle can only lower
    // omega_max (as for the crack's tied companion), so the step stays stable.
    if is_periodic(&conditions) {
        model.tie_periodic()?;
    }
    let stability = match crack_placement.as_ref().filter(|p| p.tied) {
        Some(p) => split_stability(&model, p, &absorbing)?,
        None => solve::stability::estimate(&model),
    };
    Ok(Scene {
        spec: spec.clone(),
        laminate,
        body: Body::T3(model),
        transmitter,
        receivers,
        crack_placement,
        stability,
    })
}

/// The DOFs held by the edge conditions, and the bottom corners' when `fix_bottom_corners`.
fn held_and_pinned_dofs(
    spec: &SceneSpec,
    mesh: &Mesh,
    conditions: &[(Side, EdgeCondition); 4],
) -> Vec<usize> {
    let mut fixed = if spec.fix_bottom_corners {
        bottom_corner_dofs(mesh)
    } else {
        vec![]
    };
    fixed.extend(held_dofs(mesh, conditions));
    fixed
}

/// Bytes per mesh node of a built scene and its runs (mesh, block-CSR stiffness, mass,
/// operator stencils, solver vectors), a generous upper figure from the default scenes.
const BYTES_PER_NODE: f64 = 1024.0;

/// Refuses, before anything is allocated, a mesh (of `orders` GLL intervals per element along
/// x and across, (1, 1) for T3) that is degenerate (fewer than two columns,
/// layers that vanish in floating point) or whose estimated memory exceeds the limit
/// ([`crate::budget::check_memory`]); the error names the fields the user wrote.
fn check_mesh_size(spec: &SceneSpec, laminate: &Laminate, orders: (usize, usize)) -> Result<()> {
    require_positive("element_size_x_m", spec.element_size_x_m)?;
    require_positive("element_size_y_m", spec.element_size_y_m)?;
    if spec.element_size_x_m > 0.5 * spec.width_m {
        return Err(Error::invalid(
            "element_size_x_m",
            format!("{} m", spec.element_size_x_m),
            format!(
                "must be at most half of width_m = {} m (the mesh needs at least two columns)",
                spec.width_m
            ),
        ));
    }
    let interfaces = laminate.interfaces_m();
    if let Some(k) = interfaces
        .windows(2)
        .position(|w| !(w[1] > w[0]) || !w[1].is_finite())
    {
        return Err(Error::invalid(
            "laminate",
            format!(
                "layer {} of thickness {:e} m",
                k + 1,
                laminate.layers[k].thickness_m
            ),
            format!(
                "a layer vanishes in floating point next to a total thickness of {:e} m \
                 (check laminate.min_epoxy_m and the layer thicknesses)",
                laminate.thickness_m()
            ),
        ));
    }
    let columns = (spec.width_m / spec.element_size_x_m).ceil().max(1.0);
    let rows: f64 = interfaces
        .windows(2)
        .map(|w| ((w[1] - w[0]) / spec.element_size_y_m).ceil().max(1.0))
        .sum();
    let nodes = (columns * orders.0 as f64 + 1.0) * (rows * orders.1 as f64 + 1.0);
    crate::budget::check_memory(
        "element_size_x_m, element_size_y_m",
        format!(
            "{} m, {} m over width_m = {} m and a laminate {:e} m thick ({columns:.3e} columns x {rows:.3e} rows, {nodes:.3e} nodes at about {} each)",
            spec.element_size_x_m,
            spec.element_size_y_m,
            spec.width_m,
            laminate.thickness_m(),
            crate::budget::format_bytes(BYTES_PER_NODE),
        ),
        nodes * BYTES_PER_NODE,
        "use larger elements or a smaller region",
    )
}

/// Where a crack lies on the mesh: the requested geometry and the mesh lines it snapped to
/// (depths below the top surface, x from the left edge).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CrackPlacement {
    /// Requested depth, `crack.depth_m` (m).
    pub depth_requested_m: f64,
    /// Depth of the row line used (m).
    pub depth_used_m: f64,
    /// Requested left tip, x_center_m - length_m / 2 (m).
    pub x0_requested_m: f64,
    /// Left tip used: a column line (m).
    pub x0_used_m: f64,
    /// Requested right tip, x_center_m + length_m / 2 (m).
    pub x1_requested_m: f64,
    /// Right tip used: a column line (m).
    pub x1_used_m: f64,
    /// Faces tied (the uncracked companion): no node is split.
    pub tied: bool,
    /// Height of the crack line above the bottom edge, exactly the mesh's row line (m).
    #[serde(skip)]
    y_m: f64,
}

impl CrackPlacement {
    /// Splits the crack's nodes in `mesh` (the mesh it was placed on).
    fn insert(&self, mesh: &mut Mesh) -> Result<crate::mesh::Crack> {
        mesh.insert_crack(self.y_m, self.x0_used_m, self.x1_used_m)
    }
}

/// Snaps the crack of `c` onto the lines of `grid` (of the mesh built without it): the line
/// to the nearest interior row line, each tip to the nearest interior column line, each within half
/// the local row height / column width. Errors name the field and the value when no line is
/// that close (the crack would lie on an edge) or when the tips leave no node between them.
fn place_crack(
    spec: &SceneSpec,
    c: &CrackSpec,
    grid: &Grid,
    height: f64,
) -> Result<CrackPlacement> {
    let (y, x0, x1) = crack_geometry(spec, c, height)?;
    let row = grid.snap_row(y).ok_or_else(|| {
        Error::invalid(
            "crack.depth_m",
            c.depth_m,
            format!(
                "no interior mesh row line within half an element row of it (the nearest line \
                 is the {} surface; element_size_y_m = {:e} m)",
                if y > 0.5 * height { "top" } else { "bottom" },
                spec.element_size_y_m
            ),
        )
    })?;
    let column = |x: f64, tip: &str| {
        grid.snap_column(x).ok_or_else(|| {
            Error::invalid(
                "crack.x_center_m, crack.length_m",
                format!("{tip} tip x = {x:.6e} m"),
                format!(
                    "no interior mesh column line within half a column of it (the nearest \
                     line is the {} edge; element_size_x_m = {:e} m)",
                    if x < 0.5 * spec.width_m {
                        "left"
                    } else {
                        "right"
                    },
                    spec.element_size_x_m
                ),
            )
        })
    };
    let (i0, i1) = (column(x0, "left")?, column(x1, "right")?);
    if i1 < i0 + 2 {
        return Err(Error::invalid(
            "crack.length_m",
            c.length_m,
            format!(
                "its tips snap to column lines {:.6e} and {:.6e} m, leaving no node between \
                 them; the crack needs at least two columns (element_size_x_m = {:e} m)",
                grid.x_m[i0], grid.x_m[i1], spec.element_size_x_m
            ),
        ));
    }
    let y_m = grid.y_m[row];
    Ok(CrackPlacement {
        depth_requested_m: c.depth_m,
        depth_used_m: height - y_m,
        x0_requested_m: x0,
        x0_used_m: grid.x_m[i0],
        x1_requested_m: x1,
        x1_used_m: grid.x_m[i1],
        tied: c.tied,
        y_m,
    })
}

/// The stability estimate of the cracked (split) version of the tied `model`: the shared
/// step of a cracked scene and its tied companion (see [`Scene::build`]).
fn split_stability(
    model: &Model,
    placement: &CrackPlacement,
    absorbing: &[AbsorbingEdge],
) -> Result<StabilityEstimate> {
    let mut mesh = model.mesh.clone();
    let crack = placement.insert(&mut mesh)?;
    // The same edges: their springs enter K (their dashpots do not enter M^-1 K).
    let split = Model::build(
        mesh,
        model.materials.clone(),
        absorbing,
        model.fixed_dofs.clone(),
        Some(crack),
    )?;
    Ok(solve::stability::estimate(&split))
}

/// Crack line and tips (m) from its spec, checked against the domain.
fn crack_geometry(spec: &SceneSpec, c: &CrackSpec, height: f64) -> Result<(f64, f64, f64)> {
    require_positive("crack.length_m", c.length_m)?;
    require_positive("crack.depth_m", c.depth_m)?;
    let middle = spec
        .receivers
        .x_m
        .get(spec.receivers.x_m.len() / 2)
        .copied()
        .unwrap_or(0.5 * spec.width_m);
    let xc = c.x_center_m.unwrap_or(middle);
    let (x0, x1, y) = (
        xc - 0.5 * c.length_m,
        xc + 0.5 * c.length_m,
        height - c.depth_m,
    );
    if !(x0 > 0.0 && x1 < spec.width_m && y > 0.0) {
        return Err(Error::invalid(
            "crack",
            format!("x {x0:.4e}..{x1:.4e} m at depth {:.4e} m", c.depth_m),
            format!(
                "must lie inside the {:.4e} x {height:.4e} m region (width_m x laminate thickness; check crack.x_center_m, crack.length_m, crack.depth_m)",
                spec.width_m
            ),
        ));
    }
    Ok((y, x0, x1))
}

/// The condition of every edge, in the order bottom, top, left, right: `edges` where it
/// names one, else absorbing if `absorbing` lists the side, else free. Periodic must be
/// given to the left and right edges together and to no other; a side listed twice in
/// `absorbing` is an error (it would absorb twice).
fn edge_conditions(spec: &SceneSpec) -> Result<[(Side, EdgeCondition); 4]> {
    let listed = &spec.absorbing;
    if let Some(twice) =
        (1..listed.len()).find_map(|i| listed[..i].contains(&listed[i]).then_some(listed[i]))
    {
        return Err(Error::invalid(
            "absorbing",
            format!("{twice:?}").to_lowercase(),
            "is listed twice (it would absorb twice)",
        ));
    }
    let e = &spec.edges;
    let conditions = [
        (Side::Bottom, e.bottom),
        (Side::Top, e.top),
        (Side::Left, e.left),
        (Side::Right, e.right),
    ]
    .map(|(side, given)| {
        let absorbing = spec.absorbing.contains(&side);
        let default = if absorbing {
            EdgeCondition::Absorbing
        } else {
            EdgeCondition::Free
        };
        (side, given.unwrap_or(default))
    });
    let periodic = |side: Side| {
        conditions
            .iter()
            .any(|&(s, c)| s == side && c == EdgeCondition::Periodic)
    };
    for side in [Side::Bottom, Side::Top] {
        if periodic(side) {
            return Err(Error::invalid(
                format!("edges.{}", side.name()),
                "periodic",
                "only the left and right edges can be periodic (together)",
            ));
        }
    }
    if periodic(Side::Left) != periodic(Side::Right) {
        let (set, other) = if periodic(Side::Left) {
            ("left", "right")
        } else {
            ("right", "left")
        };
        return Err(Error::invalid(
            format!("edges.{set}"),
            "periodic",
            format!("a periodic edge needs its partner: set edges.{other} periodic too"),
        ));
    }
    Ok(conditions)
}

fn is_periodic(conditions: &[(Side, EdgeCondition); 4]) -> bool {
    conditions
        .iter()
        .any(|&(_, c)| c == EdgeCondition::Periodic)
}

/// The DOFs held by fixed edges (both components) and rollers (the normal component).
fn held_dofs(mesh: &Mesh, conditions: &[(Side, EdgeCondition); 4]) -> Vec<usize> {
    let mut held = Vec::new();
    for &(side, condition) in conditions {
        let normal = match side {
            Side::Bottom | Side::Top => 1,
            Side::Left | Side::Right => 0,
        };
        let components: &[usize] = match condition {
            EdgeCondition::Fixed => &[0, 1],
            EdgeCondition::Roller => &[normal],
            _ => continue,
        };
        for n in mesh.side_nodes(side) {
            held.extend(components.iter().map(|c| 2 * n + c));
        }
    }
    held
}

/// The absorbing edges of the scene, with the viscous-spring distance resolved per side:
/// the sides of `absorbing` in its order, less those `edges` gives another condition, then
/// the sides `edges` makes absorbing.
fn absorbing_edges(
    spec: &SceneSpec,
    conditions: &[(Side, EdgeCondition); 4],
    mesh: &Mesh,
    region: Region,
) -> Result<Vec<AbsorbingEdge>> {
    let absorbs = |side: Side| {
        conditions
            .iter()
            .any(|&(s, c)| s == side && c == EdgeCondition::Absorbing)
    };
    let mut sides: Vec<Side> = spec
        .absorbing
        .iter()
        .copied()
        .filter(|&s| absorbs(s))
        .collect();
    for &(side, _) in conditions {
        if absorbs(side) && !sides.contains(&side) {
            sides.push(side);
        }
    }
    let source = source_centre(spec, mesh, region);
    sides
        .iter()
        .map(|&side| {
            let spring_distance_m = match spec.absorber {
                Absorber::Dashpot => None,
                Absorber::ViscousSpring {
                    source_distance_m: Some(r),
                } => Some(r),
                Absorber::ViscousSpring {
                    source_distance_m: None,
                } => Some(transmitter_distance(
                    side,
                    source,
                    region.width,
                    region.height,
                )?),
            };
            Ok(AbsorbingEdge {
                side,
                spring_distance_m,
            })
        })
        .collect()
}

/// The centre of the transmitter's segment, or of the first source (relative to the lower
/// left corner of the region): where the viscous-spring distance R is measured from.
fn source_centre(spec: &SceneSpec, mesh: &Mesh, region: Region) -> [f64; 2] {
    let t = &spec.transmitter;
    let Some(first) = spec.sources.first() else {
        return [
            region.width,
            region.height - 0.5 * (t.depth_top_m + t.depth_bottom_m),
        ];
    };
    let (x0, y0) = (region.x0, region.y0);
    let p = match first {
        SourceSpec::Point { x_m, y_m, .. } => [*x_m, *y_m],
        SourceSpec::Traction {
            edge, x_m, depth_m, ..
        }
        | SourceSpec::Normal {
            edge, x_m, depth_m, ..
        }
        | SourceSpec::Shear {
            edge, x_m, depth_m, ..
        } => match edge_range(mesh, *edge, *x_m, *depth_m, "sources[0]") {
            Ok((p, q)) => [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])],
            // the source's own check reports the error
            Err(_) => [x0, y0],
        },
    };
    [p[0] - x0, p[1] - y0]
}

/// Distance from the transmitter's centre to the line of `side`; an error when the
/// transmitter lies on that side (the springs' R must then be given).
fn transmitter_distance(side: Side, source: [f64; 2], width: f64, height: f64) -> Result<f64> {
    let d = match side {
        Side::Left => source[0],
        Side::Right => width - source[0],
        Side::Bottom => source[1],
        Side::Top => height - source[1],
    };
    if d < 1e-6 * width.max(height) {
        return Err(Error::invalid(
            "absorber.source_distance_m",
            "none",
            format!(
                "the transmitter lies on the absorbing {} side: give the distance R from the \
                 wave source to the absorbing sides",
                format!("{side:?}").to_lowercase()
            ),
        ));
    }
    Ok(d)
}

fn bottom_corner_dofs(mesh: &Mesh) -> Vec<usize> {
    let bottom = mesh.side_nodes(Side::Bottom);
    [bottom.first(), bottom.last()]
        .into_iter()
        .flatten()
        .flat_map(|&n| [2 * n, 2 * n + 1])
        .collect()
}

/// Nodal weights of the transmitter per unit traction: the consistent load of a uniform
/// traction in direction `angle_deg` on its segment of the right edge.
fn transmitter_weights(
    on: &dyn Attach,
    t: &TransmitterSpec,
    region: Region,
) -> Result<Vec<(usize, f64)>> {
    let height = region.height;
    if !(t.depth_top_m >= 0.0 && t.depth_bottom_m > t.depth_top_m && t.depth_bottom_m <= height) {
        return Err(Error::invalid(
            "transmitter",
            format!("depth {}..{} m", t.depth_top_m, t.depth_bottom_m),
            format!("needs 0 <= depth_top < depth_bottom <= {height:.4e} m"),
        ));
    }
    let (right, top) = (region.x0 + region.width, region.y0 + height);
    let load = on.edge_load(
        Side::Right,
        [right, top - t.depth_top_m],
        [right, top - t.depth_bottom_m],
        "transmitter",
    )?;
    let (s, c) = t.angle_deg.to_radians().sin_cos();
    Ok(directed(&load, [c, s], 1.0))
}

/// DOF weights of a traction `scale` * `direction` from per-node weights of a unit one.
fn directed(load: &[(usize, f64)], direction: [f64; 2], scale: f64) -> Vec<(usize, f64)> {
    load.iter()
        .flat_map(|&(n, w)| {
            [
                (2 * n, scale * direction[0] * w),
                (2 * n + 1, scale * direction[1] * w),
            ]
        })
        .collect()
}

/// Where a scene's loads and records attach to its discretisation: the consistent nodal loads
/// of tractions and the weights of receivers. Nodes are numbered as in [`Attach::mesh`].
trait Attach {
    /// The T3 mesh, or the triangulated node grid of spectral elements: bounds, nodes, sides.
    fn mesh(&self) -> &Mesh;
    /// Per-node weights of a unit uniform traction on the segment p..q of `side`: the
    /// integral of each node's shape function along it (m). `field` names the segment.
    fn edge_load(
        &self,
        side: Side,
        p: [f64; 2],
        q: [f64; 2],
        field: &str,
    ) -> Result<Vec<(usize, f64)>>;
    /// A receiver averaging (component, quantity) `recorded` over the face `ends` = (p, q) on
    /// `side`, or at the point p when q == p.
    fn face_receiver(
        &self,
        name: &str,
        side: Side,
        ends: ([f64; 2], [f64; 2]),
        recorded: (usize, Quantity),
    ) -> Result<Receiver>;
    /// A receiver of (component, quantity) `recorded` at the point p in the body,
    /// interpolated.
    fn point_receiver(
        &self,
        name: &str,
        p: [f64; 2],
        recorded: (usize, Quantity),
    ) -> Result<Receiver>;
}

/// Linear triangles: loads by length shares ([`segment_shares`]), face receivers averaged
/// with the same shares (the nearest node for a point face), point receivers by barycentric
/// interpolation.
struct OnT3<'a>(&'a Mesh);

impl Attach for OnT3<'_> {
    fn mesh(&self) -> &Mesh {
        self.0
    }

    fn edge_load(
        &self,
        side: Side,
        p: [f64; 2],
        q: [f64; 2],
        field: &str,
    ) -> Result<Vec<(usize, f64)>> {
        let nodes = self.0.nodes_on_segment(p, q);
        if nodes.len() < 2 {
            return Err(Error::invalid(
                field,
                format!("{p:?}..{q:?} m on the {} edge", side.name()),
                "covers fewer than two mesh nodes: widen the range",
            ));
        }
        Ok(segment_shares(self.0, &nodes))
    }

    fn face_receiver(
        &self,
        name: &str,
        _: Side,
        (p, q): ([f64; 2], [f64; 2]),
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        segment_receiver(self.0, name, p, q, component, quantity)
    }

    fn point_receiver(
        &self,
        name: &str,
        p: [f64; 2],
        (component, quantity): (usize, Quantity),
    ) -> Result<Receiver> {
        point_receiver(self.0, name, p, component, quantity)
    }
}

/// The end points of an edge source's range on the mesh: `x_m` along the top or bottom
/// edge, `depth_m` below the top surface along the left or right edge, the whole edge
/// without either.
fn edge_range(
    mesh: &Mesh,
    edge: Side,
    x_m: Option<[f64; 2]>,
    depth_m: Option<[f64; 2]>,
    field: &str,
) -> Result<([f64; 2], [f64; 2])> {
    let (x0, x1, y0, y1) = mesh.bounds();
    let horizontal = matches!(edge, Side::Top | Side::Bottom);
    let wrong = match (horizontal, x_m, depth_m) {
        (true, _, Some(d)) => Some(("depth_m", d)),
        (false, Some(x), _) => Some(("x_m", x)),
        _ => None,
    };
    if let Some((name, v)) = wrong {
        return Err(Error::invalid(
            format!("{field}.{name}"),
            format!("{v:?} on the {} edge", edge.name()),
            "a range along the top or bottom edge is x_m, along the left or right edge depth_m \
             (below the top surface)",
        ));
    }
    let range = x_m.or(depth_m);
    if let Some([a, b]) = range {
        let (lo, hi) = if horizontal { (x0, x1) } else { (0.0, y1 - y0) };
        if !(a.is_finite() && b.is_finite() && a >= lo && b > a && b <= hi) {
            return Err(Error::invalid(
                format!("{field}.{}", if horizontal { "x_m" } else { "depth_m" }),
                format!("[{a}, {b}]"),
                format!("needs {lo:e} <= from < to <= {hi:e} m"),
            ));
        }
    }
    Ok(match edge {
        Side::Top | Side::Bottom => {
            let y = if edge == Side::Top { y1 } else { y0 };
            let [a, b] = range.unwrap_or([x0, x1]);
            ([a, y], [b, y])
        }
        Side::Left | Side::Right => {
            let x = if edge == Side::Right { x1 } else { x0 };
            let [a, b] = range.unwrap_or([0.0, y1 - y0]);
            ([x, y1 - a], [x, y1 - b])
        }
    })
}

/// Outward unit normal of a side.
fn outward_normal(side: Side) -> [f64; 2] {
    match side {
        Side::Bottom => [0.0, -1.0],
        Side::Top => [0.0, 1.0],
        Side::Left => [-1.0, 0.0],
        Side::Right => [1.0, 0.0],
    }
}

/// Nodal weights of all `sources` per unit drive (Pa): the consistent nodal loads of their
/// tractions ([`Attach::edge_load`] times the traction direction) and their point forces
/// (on the node nearest to the point).
fn source_weights(on: &dyn Attach, sources: &[SourceSpec]) -> Result<Vec<(usize, f64)>> {
    let mesh = on.mesh();
    let mut weights = Vec::new();
    for (i, source) in sources.iter().enumerate() {
        let field = format!("sources[{i}]");
        let (edge, x_m, depth_m, direction, scale) = match *source {
            SourceSpec::Point {
                x_m,
                y_m,
                angle_deg,
                scale,
            } => {
                check_inside(mesh, &field, [x_m, y_m])?;
                let node = mesh.nearest_node([x_m, y_m]);
                let (s, c) = angle_deg.to_radians().sin_cos();
                check_scale(&field, scale)?;
                weights.extend([(2 * node, scale * c), (2 * node + 1, scale * s)]);
                continue;
            }
            SourceSpec::Traction {
                edge,
                x_m,
                depth_m,
                angle_deg,
                scale,
            } => {
                let (s, c) = angle_deg.to_radians().sin_cos();
                (edge, x_m, depth_m, [c, s], scale)
            }
            SourceSpec::Normal {
                edge,
                x_m,
                depth_m,
                scale,
            } => (edge, x_m, depth_m, outward_normal(edge), scale),
            SourceSpec::Shear {
                edge,
                x_m,
                depth_m,
                scale,
            } => {
                let n = outward_normal(edge);
                (edge, x_m, depth_m, [n[1].abs(), n[0].abs()], scale)
            }
        };
        check_scale(&field, scale)?;
        let (p, q) = edge_range(mesh, edge, x_m, depth_m, &field)?;
        let load = on.edge_load(edge, p, q, &field)?;
        weights.extend(directed(&load, direction, scale));
    }
    Ok(weights)
}

fn check_scale(field: &str, scale: f64) -> Result<()> {
    if !scale.is_finite() || scale == 0.0 {
        return Err(Error::invalid(
            format!("{field}.scale"),
            scale,
            "must be finite and nonzero",
        ));
    }
    Ok(())
}

fn check_inside(mesh: &Mesh, field: &str, p: [f64; 2]) -> Result<()> {
    let (x0, x1, y0, y1) = mesh.bounds();
    let tol = mesh.tolerance();
    if !(p[0] >= x0 - tol && p[0] <= x1 + tol && p[1] >= y0 - tol && p[1] <= y1 + tol) {
        return Err(Error::invalid(
            field,
            format!("x_m = {}, y_m = {}", p[0], p[1]),
            format!("is outside the region x [{x0:e}, {x1:e}], y [{y0:e}, {y1:e}] m"),
        ));
    }
    Ok(())
}

/// The receivers: the top-surface row of `x_m`, then those of `at`.
fn build_receivers(on: &dyn Attach, r: &ReceiverSpec, height: f64) -> Result<Vec<Receiver>> {
    let mesh = on.mesh();
    if r.component > 1 {
        return Err(Error::invalid(
            "receivers.component",
            r.component,
            "must be 0 (u_x) or 1 (u_y)",
        ));
    }
    if r.x_m.is_empty() && r.at.is_empty() {
        return Err(Error::invalid(
            "receivers.x_m",
            "[]",
            "needs at least one receiver position (in x_m or at)",
        ));
    }
    // The transducer face spans at most the specimen: a wider one is no longer a receiver at
    // a position (and a negative one has no face).
    let (x0, x1, _, _) = mesh.bounds();
    require_within(
        "receivers.aperture_m",
        r.aperture_m,
        0.0,
        x1 - x0,
        "m",
        "0 records at a point; at most the specimen's width",
    )?;
    let half = 0.5 * r.aperture_m;
    let recorded = (r.component, r.quantity);
    let face = |name: &str, side: Side, p: [f64; 2], along: [f64; 2]| {
        let ends = (
            [p[0] - half * along[0], p[1] - half * along[1]],
            [p[0] + half * along[0], p[1] + half * along[1]],
        );
        on.face_receiver(name, side, ends, recorded)
    };
    let mut receivers = r
        .x_m
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            face(
                &format!("receiver {}", i + 1),
                Side::Top,
                [x, height],
                [1.0, 0.0],
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let (x0, x1, y0, y1) = mesh.bounds();
    for (i, at) in r.at.iter().enumerate() {
        let name = format!("receiver {}", receivers.len() + 1);
        let field = format!("receivers.at[{i}]");
        let receiver = match (at.edge, at.x_m, at.y_m, at.depth_m) {
            (None, Some(x), Some(y), None) => {
                check_inside(mesh, &field, [x, y])?;
                on.point_receiver(&name, [x, y], recorded)?
            }
            (Some(edge), x_m, None, depth_m) => {
                let horizontal = matches!(edge, Side::Top | Side::Bottom);
                let (p, along) = match (horizontal, x_m, depth_m) {
                    (true, Some(x), None) => {
                        ([x, if edge == Side::Top { y1 } else { y0 }], [1.0, 0.0])
                    }
                    (false, None, Some(d)) => (
                        [if edge == Side::Right { x1 } else { x0 }, y1 - d],
                        [0.0, 1.0],
                    ),
                    _ => {
                        return Err(Error::invalid(
                            field,
                            at.describe(),
                            format!(
                                "a receiver on the {} edge needs {} alone",
                                edge.name(),
                                if horizontal { "x_m" } else { "depth_m" }
                            ),
                        ))
                    }
                };
                face(&name, edge, p, along)?
            }
            _ => {
                return Err(Error::invalid(
                    field,
                    at.describe(),
                    "give #{x_m, y_m} for a point in the body, #{edge, x_m} on the top or \
                     bottom edge, or #{edge, depth_m} on the left or right edge",
                ))
            }
        };
        receivers.push(receiver);
    }
    Ok(receivers)
}
