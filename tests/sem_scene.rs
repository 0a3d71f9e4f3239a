//! Spectral-element scenes (`discretisation: #{kind: "sem", ...}`): what they build, the
//! energy ledger on a closed and an open scene, the crack's contact acting from its first
//! contact and not before, the impulse-response shortcut, and refused inputs. The wave
//! physics of SEM scenes against exact solutions is in tests/scene_edges.rs (the plane wave
//! through a layer stack) and tests/waves.rs; the contact laws on split GLL nodes in
//! tests/sem_contact.rs.

use std::sync::Arc;
use trnews::scene::{
    Body, DiscretisationSpec, EdgeCondition, EdgeConditions, GmshSpec, Scene, SceneSpec,
    TimeDispersionSpec,
};
use trnews::sem::FineColumns;
use trnews::signal::{relative_l2, Signal};
use trnews::solve::RunConfig;
use trnews::trnews::{Responder, TrNewsSpec};

fn sem(order: usize) -> DiscretisationSpec {
    DiscretisationSpec::Sem {
        order_x: order,
        min_order_y: 1,
        max_order_y: order,
        extra_order_y: 0,
        rule_order_x: None,
        fine_x: None,
    }
}

/// The smoke scene (cracked, viscous-spring edges, transducer band) on order-4 spectral
/// elements of 0.25 mm.
fn smoke_sem() -> SceneSpec {
    SceneSpec {
        element_size_x_m: 0.25e-3,
        element_size_y_m: 0.25e-3,
        discretisation: sem(4),
        ..SceneSpec::smoke()
    }
}

/// The smoke chirp at the scene's step and peak traction.
fn chirp(scene: &Scene) -> Signal {
    TrNewsSpec::smoke()
        .chirp
        .signal(scene.default_dt_s(), scene.spec.transmitter.peak_pa)
        .unwrap()
}

fn run(scene: &Scene, drive: &Signal, duration: f64) -> trnews::solve::RunOutput {
    let config = RunConfig {
        progress: false,
        ..scene.run_config(duration)
    };
    scene.transmit(drive, &config).unwrap()
}

#[test]
fn a_sem_scene_builds_its_nodes_crack_loads_and_receivers() {
    let spec = smoke_sem();
    let cracked = Scene::build(&spec).unwrap();
    let tied = Scene::build(&spec.uncracked()).unwrap();
    let Body::Sem { model, nodes } = &cracked.body else {
        panic!("a T3 body for discretisation sem");
    };
    let crack = cracked.crack().expect("the smoke scene is cracked");
    assert!(tied.crack().is_none() && tied.is_linear() && !cracked.is_linear());
    // The crack's faces are split GLL nodes: one more node per pair, numbered alike in the
    // model and its node grid; the companions share the step (the split model's).
    assert_eq!(cracked.dofs(), tied.dofs() + 2 * crack.pairs.len());
    assert_eq!(2 * nodes.nodes.len(), cracked.dofs());
    assert_eq!(2 * tied.mesh().nodes.len(), tied.dofs());
    assert_eq!(cracked.default_dt_s(), tied.default_dt_s());
    // It lies on a horizontal element edge, its tips on node columns.
    let p = cracked.crack_placement.as_ref().unwrap();
    let height = cracked.laminate.thickness_m();
    let line = height - p.depth_used_m;
    assert!(
        model.rows_m.iter().any(|&y| (y - line).abs() < 1e-12),
        "{p:?}"
    );
    for x in [p.x0_used_m, p.x1_used_m] {
        assert!(model.x_nodes_m.contains(&x), "tip {x}");
    }
    // The transmitter's load is the consistent load of the traction on its segment: the x
    // and y weights sum to (cos, sin)(110 deg) times its length (1 mm) to round-off.
    let t = &spec.transmitter;
    let length = t.depth_bottom_m - t.depth_top_m;
    let (s, c) = t.angle_deg.to_radians().sin_cos();
    for (component, expected) in [(0, c * length), (1, s * length)] {
        let sum: f64 = cracked
            .transmitter
            .iter()
            .filter(|w| w.0 % 2 == component)
            .map(|w| w.1)
            .sum();
        assert!(
            (sum - expected).abs() < 1e-12 * length,
            "component {component}: {sum:e} vs {expected:e}"
        );
    }
    // Receivers interpolate u_y with the GLL polynomials: weights sum to one.
    for r in &cracked.receivers {
        let sum: f64 = r.weights.iter().map(|w| w.1).sum();
        assert!((sum - 1.0).abs() < 1e-12, "{}: {sum}", r.name);
        assert!(r.weights.iter().all(|w| w.0 % 2 == 1), "{}", r.name);
    }
    // The Lanczos step is above the guaranteed element bound.
    let st = cracked.stability;
    assert!(
        st.dt_crit_s >= st.dt_element_bound_s && st.dt_element_bound_s > 0.0,
        "{st:?}"
    );
}

/// `spec` (on spectral elements) with the band `fine_x` of narrower columns.
fn with_fine_band(spec: &SceneSpec, from_m: f64, to_m: f64, element_size_m: f64) -> SceneSpec {
    let DiscretisationSpec::Sem {
        order_x,
        min_order_y,
        max_order_y,
        extra_order_y,
        rule_order_x,
        ..
    } = spec.discretisation
    else {
        panic!("a T3 scene");
    };
    SceneSpec {
        discretisation: DiscretisationSpec::Sem {
            order_x,
            min_order_y,
            max_order_y,
            extra_order_y,
            rule_order_x,
            fine_x: Some(FineColumns {
                from_m,
                to_m,
                element_size_m,
            }),
        },
        ..spec.clone()
    }
}

/// A band of fine columns around the crack (`discretisation.fine_x`): columns of at most its
/// size from its left to its right edge (both column lines), the scene's elsewhere; the crack
/// keeps its tips and gets one node pair per GLL interval of the band's columns it spans (4x
/// as many at a quarter of the width), every row keeps its order across (the band refines
/// along x alone), the step shrinks with the narrowest column (about 4x here), and a
/// coarsened scene (a tolerance's pilots) scales the band with the elements.
/// A band outside the width, empty, or of a size that is not a positive length, and a band
/// whose columns would not fit in memory, are errors naming the field.
#[test]
fn a_band_of_fine_columns_refines_the_crack_and_sets_the_step() {
    // tips on element column lines (of 0.25 mm), so that the band's columns keep them
    let mut coarse = smoke_sem();
    let crack = coarse.crack.as_mut().unwrap();
    (crack.x_center_m, crack.length_m) = (Some(3e-3), 1e-3);
    let a = Scene::build(&coarse).unwrap();
    let pa = a.crack_placement.as_ref().unwrap();
    let (from, to) = (pa.x0_used_m - 0.5e-3, pa.x1_used_m + 0.5e-3);
    let fine = with_fine_band(&coarse, from, to, 0.0625e-3);
    let b = Scene::build(&fine).unwrap();
    let (Body::Sem { model: uniform, .. }, Body::Sem { model, .. }) = (&a.body, &b.body) else {
        panic!("a T3 body for discretisation sem");
    };
    assert_eq!(model.row_orders(), uniform.row_orders());
    for x in [from, to] {
        assert!(
            model.columns_m.iter().any(|&l| (l - x).abs() < 1e-12),
            "band edge {x}"
        );
    }
    for w in model.columns_m.windows(2) {
        let inside = w[0] >= from - 1e-12 && w[1] <= to + 1e-12;
        let most = if inside { 0.0625e-3 } else { 0.25e-3 };
        assert!(w[1] - w[0] <= most * (1.0 + 1e-9), "{w:?}");
    }
    let pb = b.crack_placement.as_ref().unwrap();
    assert_eq!((pa.x0_used_m, pa.x1_used_m), (pb.x0_used_m, pb.x1_used_m));
    let pairs = |s: &Scene| s.crack().unwrap().pairs.len();
    assert_eq!(
        pairs(&b) + 1,
        4 * (pairs(&a) + 1),
        "{} vs {}",
        pairs(&b),
        pairs(&a)
    );
    let ratio = a.stability.dt_crit_s / b.stability.dt_crit_s;
    assert!((3.0..5.0).contains(&ratio), "dt_crit ratio {ratio}");
    let DiscretisationSpec::Sem {
        fine_x: Some(band), ..
    } = fine.coarsened(2.0).unwrap().discretisation
    else {
        panic!("the coarsened scene lost its band");
    };
    assert_eq!(band.element_size_m, 0.125e-3);
    let width = coarse.width_m;
    for (from_m, to_m, size, field) in [
        (-1e-3, to, 0.0625e-3, "discretisation.fine_x.from_m"),
        (from, width + 1e-3, 0.0625e-3, "discretisation.fine_x.to_m"),
        (to, from, 0.0625e-3, "discretisation.fine_x.to_m"),
        (from, to, 0.0, "discretisation.fine_x.element_size_m"),
        (from, to, f64::NAN, "discretisation.fine_x.element_size_m"),
    ] {
        let e = error_of(&with_fine_band(&coarse, from_m, to_m, size));
        assert!(e.contains(field), "{field}: {e}");
    }
    let e = error_of(&with_fine_band(&coarse, from, to, 1e-15));
    assert!(
        e.contains("discretisation.fine_x.element_size_m = ") && e.contains("memory"),
        "{e}"
    );
}

/// Energy ledger of SEM scenes under the smoke chirp: on a closed box (free edges, no
/// transducer) with the contacting, frictional crack, the residual is round-off (bound 1e-6,
/// as for T3 scenes); on the open smoke scene (viscous-spring edges) below 1e-3 of the input.
#[test]
fn the_energy_ledger_closes_on_closed_and_open_sem_scenes() {
    let closed = SceneSpec {
        absorbing: vec![],
        edges: EdgeConditions {
            bottom: Some(EdgeCondition::Free),
            top: Some(EdgeCondition::Free),
            left: Some(EdgeCondition::Free),
            right: Some(EdgeCondition::Free),
        },
        transducer: None,
        ..smoke_sem()
    };
    for (spec, bound) in [(closed, 1e-6), (smoke_sem(), 1e-3)] {
        let scene = Scene::build(&spec).unwrap();
        let out = run(&scene, &chirp(&scene), 20e-6);
        let contact = out.report.contact.as_ref().expect("contact");
        eprintln!(
            "energy residual {:.2e} (bound {bound:e}), {} steps in contact, penetration {:.1e} m",
            out.report.energy_residual_peak, contact.steps_in_contact, contact.max_penetration_m
        );
        assert!(contact.steps_in_contact > 0, "the crack must close");
        assert!(out.report.energy_residual_peak < bound, "{:?}", out.report);
    }
}

/// The contact law changes nothing before the faces first touch: the cracked SEM scene with
/// contact and the same scene with an open crack (`contact: ()`) record the same traces bit
/// for bit up to the step of the first contact, and differ after it. Both keep their step's
/// error and record the raw receivers (no transducer band): the time-dispersion transforms
/// and the band act on whole records (by FFT), so with them a change after the first contact
/// reaches back before it (by the transform's band edge, and at round-off).
#[test]
fn contact_on_a_sem_crack_acts_from_the_first_contact_and_not_before() {
    let spec = SceneSpec {
        time_dispersion: None,
        transducer: None,
        ..smoke_sem()
    };
    let mut open = spec.clone();
    open.crack.as_mut().unwrap().contact = None;
    let (contacting, open) = (Scene::build(&spec).unwrap(), Scene::build(&open).unwrap());
    assert!(open.is_linear() && open.crack().is_some());
    let drive = chirp(&contacting);
    let a = run(&contacting, &drive, 20e-6);
    let b = run(&open, &drive, 20e-6);
    let series = a.contact_series.expect("contact series");
    let first = series
        .in_contact
        .samples
        .iter()
        .position(|&n| n > 0.0)
        .expect("the crack closes");
    eprintln!("first contact at step {first} of {}", a.traces[0].len());
    for (x, y) in a.traces.iter().zip(&b.traces) {
        assert_eq!(x.samples[..=first], y.samples[..=first]);
    }
    let differ = a
        .traces
        .iter()
        .zip(&b.traces)
        .any(|(x, y)| relative_l2(x, y, None).unwrap() > 1e-6);
    assert!(differ, "contact changed no trace");
    assert!(b.contact_series.is_none() && b.report.contact.is_none());
}

/// A linear SEM scene takes the impulse-response shortcut: convolving with its impulse
/// response equals simulating the chirp to round-off (1e-10 relative, as for T3 scenes) when
/// the scene keeps its step's error; with the time-dispersion transforms to 2e-5 (measured
/// 4e-6 without transducers: the simulation rolls the top half of the transforms' band off
/// twice, in the forward and the inverse transform, the shortcut once).
#[test]
fn a_linear_sem_scene_convolves_its_impulse_response() {
    let transforms = [(None, 1e-10), (Some(TimeDispersionSpec::default()), 2e-5)];
    for (time_dispersion, bound) in transforms {
        let spec = SceneSpec {
            time_dispersion,
            ..smoke_sem().uncracked()
        };
        let scene = Arc::new(Scene::build(&spec).unwrap());
        let convolving = Responder::new(scene.clone(), 20e-6).unwrap();
        let simulating = Responder::simulating(scene.clone());
        let drive = chirp(&scene);
        let a = convolving.respond(&drive, 15e-6).unwrap();
        let b = simulating.respond(&drive, 15e-6).unwrap();
        let err = a
            .traces
            .iter()
            .zip(&b.traces)
            .map(|(x, y)| relative_l2(x, y, None).unwrap())
            .fold(0.0, f64::max);
        eprintln!("SEM impulse-response convolution vs simulation, {time_dispersion:?}: relative L2 {err:e}");
        assert!(err < bound, "{err:e}");
        assert!(a.report.is_none() && b.report.is_some());
    }
}

fn error_of(spec: &SceneSpec) -> String {
    Scene::build(spec).unwrap_err().to_string()
}

#[test]
fn bad_sem_scenes_are_errors_naming_the_field() {
    for (order_x, min_order_y, max_order_y, field) in [
        (0, 1, 4, "discretisation.order_x"),
        (4, 1, 17, "discretisation.max_order_y"),
        (4, 0, 4, "discretisation.min_order_y"),
        (4, 5, 4, "discretisation.min_order_y"),
    ] {
        let spec = SceneSpec {
            discretisation: DiscretisationSpec::Sem {
                order_x,
                min_order_y,
                max_order_y,
                extra_order_y: 0,
                rule_order_x: None,
                fine_x: None,
            },
            ..smoke_sem()
        };
        let e = error_of(&spec);
        assert!(e.contains(field), "{e}");
    }
    let periodic = SceneSpec {
        edges: EdgeConditions {
            left: Some(EdgeCondition::Periodic),
            right: Some(EdgeCondition::Periodic),
            ..Default::default()
        },
        crack: None,
        ..smoke_sem()
    };
    assert!(error_of(&periodic).contains("edges"));
    let gmsh = SceneSpec {
        gmsh: Some(GmshSpec {
            path: "plate.msh".into(),
            materials: Default::default(),
            crack_line: None,
            contact: None,
            tied: false,
            order: None,
            angles_deg: Default::default(),
            axes_round: Default::default(),
            absorbing_lines: vec![],
            bytes: None,
        }),
        crack: None,
        ..smoke_sem()
    };
    let e = error_of(&gmsh);
    assert!(e.contains("discretisation.kind") && e.contains("t3"), "{e}");
}

/// The companions of a spectral-element scene's error estimate lower the order along x by
/// one and two on the same elements, keeping every row's order across (the rule judged at
/// the scene's order along x) and the scene's step; then they raise every row's order across
/// by one, at its own step; last, where the crack's faces touch, the scene at half the step.
/// They keep the laminate draw, and are refused below order 3 with an error naming the field.
/// Triangles' companions coarsen the elements, at their own step.
#[test]
fn sem_companions_lower_the_order_along_x_and_raise_it_across() {
    use trnews::accuracy::Refinement;
    use trnews::scene::{DiscretisationKind, LaminateSpec, Resolution, SemPreset};
    use trnews::sem::SemModel;
    let spec = SceneSpec::preset(Resolution::Quick);
    assert_eq!(
        spec.refinement(),
        Refinement::Orders {
            top: 7,
            across: true,
            smooth: true
        }
    );
    // the report's instantaneous Coulomb law amplifies every change of the discretisation
    let mut instantaneous = spec.clone();
    let crack = instantaneous.crack.as_mut().unwrap();
    crack.contact.as_mut().unwrap().normal_stress_lag_s = 0.0;
    assert!(matches!(
        instantaneous.refinement(),
        Refinement::Orders { smooth: false, .. }
    ));
    // frictionless faces have no Coulomb law to chatter
    let crack = instantaneous.crack.as_mut().unwrap();
    crack.contact.as_mut().unwrap().friction = 0.0;
    assert!(matches!(
        instantaneous.refinement(),
        Refinement::Orders { smooth: true, .. }
    ));
    let dt = 3.1e-9;
    let companions = spec.companions(dt).unwrap();
    let orders: Vec<DiscretisationSpec> = companions
        .iter()
        .map(|c| {
            let same_otherwise = SceneSpec {
                discretisation: c.discretisation,
                time_step_s: c.time_step_s,
                ..spec.clone()
            };
            assert_eq!(*c, same_otherwise);
            c.discretisation
        })
        .collect();
    let steps: Vec<Option<f64>> = companions.iter().map(|c| c.time_step_s).collect();
    assert_eq!(steps, [Some(dt), Some(dt), None, Some(dt / 2.0)]);
    assert!(
        spec.contact().is_some(),
        "the quick preset's crack has contact"
    );
    let tied = spec.uncracked().companions(dt).unwrap();
    let steps: Vec<Option<f64>> = tied.iter().map(|c| c.time_step_s).collect();
    assert_eq!(
        steps,
        [Some(dt), Some(dt), None],
        "no contact, no companion in time"
    );
    let floor = SemPreset::of(Resolution::Quick).min_order_y;
    let expected: Vec<DiscretisationSpec> =
        [(6, 0, Some(7)), (5, 0, Some(7)), (7, 1, None), (7, 0, None)]
            .map(
                |(order_x, extra_order_y, rule_order_x)| DiscretisationSpec::Sem {
                    order_x,
                    min_order_y: floor,
                    max_order_y: 4,
                    extra_order_y,
                    rule_order_x,
                    fine_x: None,
                },
            )
            .into();
    assert_eq!(orders, expected);

    let LaminateSpec::Stochastic(draw) = &spec.laminate else {
        panic!("the quick preset's laminate is stochastic")
    };
    let laminate = trnews::laminate::Laminate::stochastic(draw, spec.plane).unwrap();
    let row_orders = |s: &SceneSpec| {
        let cut = s.discretisation.sem_cut(s).unwrap();
        SemModel::layered(&laminate, s.width_m, &cut)
            .unwrap()
            .row_orders()
    };
    let main = row_orders(&spec);
    assert_eq!(row_orders(&companions[0]), main, "order 6 along x");
    assert_eq!(row_orders(&companions[1]), main, "order 5 along x");
    let raised: Vec<usize> = main.iter().map(|p| p + 1).collect();
    assert_eq!(row_orders(&companions[2]), raised, "one more across");
    assert_eq!(row_orders(&companions[3]), main, "half the step");

    let low = SceneSpec {
        discretisation: sem(4),
        ..spec.clone()
    };
    let DiscretisationSpec::Sem { order_x, .. } = low.companions(dt).unwrap()[1].discretisation
    else {
        panic!("a spectral-element scene's companions are spectral elements")
    };
    assert_eq!(order_x, 2);
    let e = SceneSpec {
        discretisation: sem(2),
        ..spec
    }
    .companions(dt)
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("discretisation.order_x") && e.contains('2'),
        "{e}"
    );
    let t3 = SceneSpec::preset_on(Resolution::Quick, DiscretisationKind::T3);
    assert_eq!(t3.refinement(), Refinement::ElementSizes);
    let coarse = t3.companions(dt).unwrap();
    assert_eq!(coarse.len(), 2);
    assert_eq!(coarse[1].element_size_x_m, 4.0 * t3.element_size_x_m);
    assert!(coarse.iter().all(|c| c.time_step_s.is_none()));
}

/// A scene's `time_step_s` is the step of its runs, and one above its dt_crit is an error
/// naming the field and the value.
#[test]
fn a_fixed_time_step_is_the_runs_step_and_at_most_dt_crit() {
    let built = Scene::build(&smoke_sem()).unwrap();
    let crit = built.stability.dt_crit_s;
    let fixed = SceneSpec {
        time_step_s: Some(0.5 * crit),
        ..smoke_sem()
    };
    let scene = Scene::build(&fixed).unwrap();
    assert_eq!(scene.default_dt_s(), 0.5 * crit);
    assert_eq!(scene.run_config(1e-6).dt_s, Some(0.5 * crit));
    let too_long = SceneSpec {
        time_step_s: Some(1.5 * crit),
        ..smoke_sem()
    };
    let e = Scene::build(&too_long).unwrap_err().to_string();
    assert!(
        e.contains("time_step_s") && e.contains(&format!("{}", 1.5 * crit)),
        "{e}"
    );
}

/// Newmark (average acceleration on the assembled K, springs included) on the uncracked SEM
/// smoke scene against central differences on the same scene: both are second order in dt,
/// so at 0.2 and 0.1 dt_crit their receiver traces differ by a relative L2 distance that
/// falls 4x per halving (asserted 3.5-4.5x, with the finer below 1e-3); contact is refused.
#[test]
fn newmark_and_central_differences_agree_at_second_order_on_a_sem_scene() {
    use trnews::solve::Integrator;
    let scene = Scene::build(&smoke_sem().uncracked()).unwrap();
    let drive = TrNewsSpec::smoke()
        .chirp
        .signal(
            0.1 * scene.stability.dt_crit_s,
            scene.spec.transmitter.peak_pa,
        )
        .unwrap();
    let distance = |fraction: f64| {
        let traces = |integrator| {
            let config = RunConfig {
                dt_s: Some(fraction * scene.stability.dt_crit_s),
                integrator,
                progress: false,
                ..scene.run_config(6e-6)
            };
            scene.transmit(&drive, &config).unwrap().traces
        };
        let newmark = traces(Integrator::Newmark {
            consistent_mass: false,
        });
        let explicit = traces(Integrator::Explicit);
        newmark
            .iter()
            .zip(&explicit)
            .map(|(a, b)| relative_l2(a, b, None).unwrap())
            .fold(0.0, f64::max)
    };
    let (coarse, fine) = (distance(0.2), distance(0.1));
    eprintln!("Newmark vs central differences: {coarse:.3e} at 0.2 dt_crit, {fine:.3e} at 0.1");
    assert!(
        fine < 1e-3 && (3.5..4.5).contains(&(coarse / fine)),
        "{coarse:e} {fine:e}"
    );
    let cracked = Scene::build(&smoke_sem()).unwrap();
    let config = RunConfig {
        dt_s: Some(cracked.default_dt_s()),
        integrator: Integrator::Newmark {
            consistent_mass: false,
        },
        progress: false,
        ..cracked.run_config(1e-6)
    };
    let e = cracked.transmit(&drive, &config).unwrap_err().to_string();
    assert!(e.contains("integrator") && e.contains("contact"), "{e}");
}

/// The estimate's policy: off gives no companions, on gives them all, "auto" gives them where they
/// cost at most `AUTO_ESTIMATE_MAX_COST` of the main runs and otherwise states their cost:
/// the spectral elements' companions (orders p - 1 and p - 2 on the same elements) cost about
/// as much as the main run, the smoke T3 mesh's (2h, 4h) a fraction of it. Building them runs
/// no simulation.
#[test]
fn auto_turns_the_estimate_on_where_the_companions_are_cheap() {
    use trnews::scene::{DiscretisationKind, Resolution};
    use trnews::trnews::{ErrorEstimate, EstimateDecision, AUTO_ESTIMATE_MAX_COST};
    let responder = |kind| {
        let spec = SceneSpec::preset_on(Resolution::Smoke, kind);
        Responder::simulating(Arc::new(Scene::build(&spec).unwrap()))
    };
    let (sem, t3) = (
        responder(DiscretisationKind::Sem),
        responder(DiscretisationKind::T3),
    );
    assert!(matches!(
        sem.estimate_decision(ErrorEstimate::Off).unwrap(),
        EstimateDecision::Off
    ));
    match sem.estimate_decision(ErrorEstimate::On).unwrap() {
        // along x twice, across, and at half the step: the smoke preset's crack has contact
        EstimateDecision::On(scenes) => assert_eq!(scenes.len(), 4),
        other => panic!("{other:?}"),
    }
    let sem_cost = sem.companion_scenes().unwrap().1;
    match sem.estimate_decision(ErrorEstimate::Auto).unwrap() {
        EstimateDecision::TooCostly { cost } => {
            assert_eq!(cost, sem_cost);
            assert!(cost > AUTO_ESTIMATE_MAX_COST);
        }
        other => panic!("{other:?}"),
    }
    let t3_cost = t3.companion_scenes().unwrap().1;
    assert!(
        t3_cost <= AUTO_ESTIMATE_MAX_COST,
        "T3 smoke companions cost {t3_cost}"
    );
    assert!(matches!(
        t3.estimate_decision(ErrorEstimate::Auto).unwrap(),
        EstimateDecision::On(_)
    ));
}
