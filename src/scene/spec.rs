//! What a scene is made of, as data: the laminate, the transmitter, sources and receivers, the
//! edges, the crack and the discretisation (the fields of a Rhai scene map or a JSON spec).

use crate::attenuation::AttenuationSpec;
use crate::contact::ContactOptions;
use crate::error::{Error, Result};
use crate::laminate::StochasticSpec;
use crate::material::{Orthotropic, Plane};
use crate::mesh::Side;
use crate::sem::{FineColumns, SemSpec};
use crate::solve::Quantity;
use crate::transducer::TransducerSpec;
use serde::{Deserialize, Serialize};

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
/// [`crate::mesh::gmsh::read_msh`]), or with `order` spectral elements on its quadrilaterals
/// ([`crate::mesh::gmsh::read_quads`]), materials by physical surface group, and optionally a
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
    /// Tag of the physical line that is the crack. On triangles: a horizontal straight line
    /// of element edges strictly inside the mesh (contact acts on u_y, report Sec. 4.9).
    /// On spectral elements (`order`): any line elements along element sides between two
    /// elements - inclined, curved, kinked, branched, several, ending inside or on an edge -
    /// with contact in each node pair's own normal/tangent frame ([`crate::mesh::cut`]).
    #[serde(default)]
    pub crack_line: Option<i32>,
    /// Contact on the crack faces; `None` leaves the crack open.
    #[serde(default = "default_contact")]
    pub contact: Option<ContactOptions>,
    /// Faces tied (the uncracked companion, [`SceneSpec::uncracked`]).
    #[serde(default)]
    pub tied: bool,
    /// Spectral elements of this polynomial order (1-16) on the file's quadrilaterals (4-node,
    /// or 9-node for curved sides; [`crate::sem::unstructured`]); `None` (the default):
    /// linear triangles on its triangles. The scene's `discretisation` describes the layered
    /// rectangle and stays `t3` with a Gmsh mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
    /// The angle of each physical surface group's material axes from x, counter-clockwise
    /// (degrees), keyed as `materials`; 0 where not given. Spectral elements only.
    #[serde(default)]
    pub angles_deg: std::collections::BTreeMap<String, f64>,
    /// Groups whose material axes go round a point (x, y) (m), keyed as `materials`: each
    /// element's axes turned to the hoop direction at its centre, plus the group's
    /// `angles_deg` (plies that follow a circular arc, as round a bracket's corner).
    /// Spectral elements only.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub axes_round: std::collections::BTreeMap<String, [f64; 2]>,
    /// Tags of physical lines that absorb as `absorber` says, on spectral elements (`order`):
    /// any chain of boundary element sides, straight, inclined or curved, with dashpots and
    /// springs in each point's own normal frame. The viscous-spring boundary's R, where
    /// `absorber.source_distance_m` does not give it, is each point's distance from the
    /// transmitter's centre. The bounding box's sides absorb as `absorbing` and `edges` say.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub absorbing_lines: Vec<i32>,
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
    pub(super) fn constants(&self) -> Result<Orthotropic> {
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
    /// A uniform normal traction t = scale drive(t) n on a physical line of a Gmsh mesh on
    /// spectral elements (`gmsh.order`), n the boundary's outward normal at each point
    /// (positive pulls the surface outward): a transducer on a curved or inclined face, a
    /// pressure in a cavity. With viscous-spring edges the springs' R must then be given
    /// (`absorber.source_distance_m`).
    Line {
        /// The physical line's tag.
        line: i32,
        /// Factor on the drive signal.
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
    pub(super) fn describe(&self) -> String {
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
    /// Remove the time step's error from every recording ([`TimeDispersionSpec`], on by
    /// default); `None` keeps it, as in the report.
    pub time_dispersion: Option<TimeDispersionSpec>,
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
    /// The time step of the scene's runs (s), at most its dt_crit; `None` (the default):
    /// [`crate::solve::STEP_FRACTION`] of dt_crit. The error estimate's companions along x on
    /// spectral elements carry the step of the scene they estimate
    /// ([`SceneSpec::companions`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_step_s: Option<f64>,
    /// Losses: quality factors per material over a band ([`AttenuationSpec`]); `None` (the
    /// default): every material elastic, as in the report.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub attenuation: Option<AttenuationSpec>,
}

/// The time-dispersion transforms of a scene's runs ([`crate::solve::time_dispersion`]):
/// each transmission's traction gets the forward transform and each recording the inverse,
/// so a recording holds no error of the time step on a linear scene (with contact, the
/// linear part of it). Everything above `up_to_hz` is dropped from the recordings, and its
/// top half rolled off. A run whose step cannot cover the band (dt above
/// 0.9 / (pi up_to_hz), 14 ns at the default 20 MHz), or whose integrator's error is not a
/// frequency map (the fourth-order step), keeps its step's error: its report's
/// `time_dispersion_removed_up_to_hz` is empty.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TimeDispersionSpec {
    /// The top of the band the transforms cover (Hz): above the transducers' band.
    pub up_to_hz: f64,
}

impl Default for TimeDispersionSpec {
    /// Ten times the top of the report's band, 20 MHz: where the transducer pair passes
    /// (2 / 20)^4 = 1e-4 of a signal and the chirp almost nothing
    /// (docs/src/validation/time-dispersion.md).
    fn default() -> Self {
        TimeDispersionSpec {
            up_to_hz: 10.0 * crate::signal::REPORT_BAND_HZ.1,
        }
    }
}

/// The discretisations the experiments choose by name (`--set discretisation=t3|sem`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DiscretisationKind {
    /// Linear triangles, the report's.
    T3,
    /// Spectral elements (the default of the presets and the experiments: chosen on exact
    /// solutions through the plies, docs/src/validation/spectral-elements.md).
    #[default]
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
    /// to `max_order_y` that does not shorten the time step, judged per material (against
    /// `rule_order_x` along x when given), then `extra_order_y` more
    /// ([`crate::sem::SemSpec`]).
    Sem {
        /// Polynomial order along x.
        order_x: usize,
        /// Lowest polynomial order across an element row (1 when not given).
        #[serde(default = "order_one")]
        min_order_y: usize,
        /// Highest polynomial order across an element row.
        max_order_y: usize,
        /// Orders added across every row after the rule chose them (0 when not given; 1 on
        /// the error estimate's companion across the layers, [`SceneSpec::companions`]).
        #[serde(default, skip_serializing_if = "is_zero")]
        extra_order_y: usize,
        /// The order along x the rule across judges the rows against (`order_x` when not
        /// given; the scene's on the error estimate's companions along x, which so keep
        /// every row's order across).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rule_order_x: Option<usize>,
        /// A band of narrower element columns along x (none when not given; a reference
        /// that resolves the crack's contact along x).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fine_x: Option<FineColumns>,
    },
}

fn is_zero(n: &usize) -> bool {
    *n == 0
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
                extra_order_y,
                rule_order_x,
                fine_x,
            } => Some(SemSpec {
                order_x,
                min_order_y,
                max_order_y,
                extra_order_y,
                rule_order_x,
                element_size_x_m: spec.element_size_x_m,
                element_size_y_m: spec.element_size_y_m,
                fine_x,
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
            time_dispersion: Some(TimeDispersionSpec::default()),
            time_step_s: None,
            attenuation: None,
            transmitter: TransmitterSpec::default(),
            sources: vec![],
            receivers: ReceiverSpec::default(),
            crack: Some(CrackSpec::default()),
            gmsh: None,
            discretisation: DiscretisationSpec::T3,
        }
    }
}
