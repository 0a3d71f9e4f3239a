//! Scenes on spectral elements over Gmsh quadrilaterals (`gmsh: #{order: p, ...}`): the
//! same elements as a layered spectral-element scene give the same run to round-off (mass,
//! stiffness, loads, receivers, dashpots and springs built by the unstructured path agree
//! with the structured one; with losses too), the energy ledger closes, and refused inputs
//! name the field.

mod common;

use common::{gmsh_mesh, strong_losses};
use trnews::accuracy::{Estimate, Refinement, Verdict};
use trnews::attenuation::AttenuationSpec;
use trnews::contact::ContactOptions;
use trnews::scene::{
    Body, CrackSpec, DiscretisationSpec, GmshSpec, LaminateSpec, LayerSpec, MaterialSpec,
    ReceiverSpec, Scene, SceneSpec, TransmitterSpec,
};
use trnews::signal::relative_l2;
use trnews::solve::RunConfig;
use trnews::trnews::TrNewsSpec;

/// The plate's scene around its body: transmitter on the right edge, three receivers on
/// top, the default viscous-spring edges (bottom and left) and transducer band, no crack.
fn around() -> SceneSpec {
    SceneSpec {
        width_m: 4e-3,
        transmitter: TransmitterSpec {
            depth_top_m: 0.2e-3,
            depth_bottom_m: 1.1e-3,
            ..Default::default()
        },
        receivers: ReceiverSpec {
            x_m: vec![1.0e-3, 2.3e-3, 3.1e-3],
            ..Default::default()
        },
        crack: None,
        ..SceneSpec::smoke()
    }
}

/// The plate as a layered spectral-element scene: 0.8 mm epoxy over 1.2 mm fabric, elements
/// of 0.5 x 0.4 mm, order `order` in both directions in every row.
fn layered(order: usize) -> SceneSpec {
    let layer = |m: &str, t: f64| LayerSpec {
        material: MaterialSpec::Preset(m.into()),
        thickness_m: t,
    };
    SceneSpec {
        laminate: LaminateSpec::Layers {
            layers: vec![layer("epoxy", 0.8e-3), layer("fabric_0_90", 1.2e-3)],
        },
        element_size_x_m: 0.5e-3,
        element_size_y_m: 0.4e-3,
        discretisation: DiscretisationSpec::Sem {
            order_x: order,
            min_order_y: order,
            max_order_y: order,
            extra_order_y: 0,
            rule_order_x: None,
            fine_x: None,
        },
        ..around()
    }
}

/// The same plate read from tests/scripts/gmsh_quad_plate.msh (written by gmsh_quads.py).
fn from_gmsh(order: usize) -> SceneSpec {
    SceneSpec {
        gmsh: Some(gmsh_mesh(
            "gmsh_quad_plate.msh",
            &[("1", "fabric_0_90"), ("2", "epoxy")],
            Some(order),
        )),
        ..around()
    }
}

/// The layered rectangle's elements read from Gmsh and run on the unstructured kernel give
/// the layered scene's traces, elastic and with strong losses: the two paths share no code
/// for the mass, the stiffness product, the memory variables' storage and passes, the
/// transmitter's loads, the receivers' weights or the edges' dashpots and springs (they
/// share the memory's point law), so agreement to round-off (measured 1.8e-14 to 3.6e-14
/// over the three receivers, elastic; asserted 1e-12) checks each of them. dt_crit
/// (Lanczos) agrees to 1e-6.
#[test]
fn gmsh_quadrilaterals_run_as_the_layered_scene_does() {
    gmsh_and_layered_agree(None);
    gmsh_and_layered_agree(Some(strong_losses()));
}

fn gmsh_and_layered_agree(attenuation: Option<AttenuationSpec>) {
    let order = 4;
    let with_losses = |spec: SceneSpec| SceneSpec {
        attenuation: attenuation.clone(),
        ..spec
    };
    let structured = Scene::build(&with_losses(layered(order))).unwrap();
    let general = Scene::build(&with_losses(from_gmsh(order))).unwrap();
    let Body::Unstructured { model, .. } = &general.body else {
        panic!("gmsh.order builds unstructured spectral elements");
    };
    assert_eq!(model.elements(), 40);
    assert_eq!(general.dofs(), structured.dofs());
    let (a, b) = (structured.stability.dt_crit_s, general.stability.dt_crit_s);
    assert!((a / b - 1.0).abs() < 1e-6, "dt_crit {a:e} vs {b:e}");
    assert!(general.stability.dt_element_bound_s <= b);
    let dt = 0.5 * a;
    let chirp = TrNewsSpec::smoke().chirp.signal(dt, 1e5).unwrap();
    let runs: Vec<_> = [&structured, &general]
        .iter()
        .map(|s| {
            let config = RunConfig {
                progress: false,
                dt_s: Some(dt),
                ..s.run_config(8e-6)
            };
            s.transmit(&chirp, &config).unwrap()
        })
        .collect();
    for (k, (x, y)) in runs[0].traces.iter().zip(&runs[1].traces).enumerate() {
        let d = relative_l2(y, x, None).unwrap();
        eprintln!(
            "losses {}: receiver {}: relative difference {d:e}",
            attenuation.is_some(),
            k + 1
        );
        assert!(d < 1e-12, "receiver {}: {d:e}", k + 1);
    }
    let ledger = runs[1].report.energy_residual_peak;
    assert!(ledger < 1e-12, "energy residual {ledger:e}");
    let lost = *runs[1].ledger.viscous_loss_j.last().unwrap();
    let structured_lost = *runs[0].ledger.viscous_loss_j.last().unwrap();
    eprintln!("viscous loss {lost:e} J/m, layered {structured_lost:e} J/m, ledger {ledger:e}");
    assert_eq!(lost > 0.0, attenuation.is_some());
    assert!((lost - structured_lost).abs() <= 1e-12 * lost.abs().max(1e-300));
}

/// Losses in turned plies on a distorted mesh (the plate's 216 curved quadrilaterals, the
/// fabric's axes at 30 degrees, so its relaxation couples normal and shear strain): the
/// ledger closes with the memory's energy and its dissipation, and 1 and 2 threads give
/// bit-identical traces and ledgers.
#[test]
fn losses_in_turned_plies_keep_the_ledger_and_the_thread_invariance() {
    let mut spec = SceneSpec {
        attenuation: Some(strong_losses()),
        gmsh: Some(gmsh_mesh(
            "gmsh_quad_plate_unstructured.msh",
            &[("1", "fabric_0_90"), ("2", "epoxy")],
            Some(4),
        )),
        ..around()
    };
    spec.gmsh.as_mut().unwrap().angles_deg = [("1".to_string(), 30.0)].into();
    let scene = Scene::build(&spec).unwrap();
    let dt = 0.5 * scene.stability.dt_crit_s;
    let chirp = TrNewsSpec::smoke().chirp.signal(dt, 1e5).unwrap();
    let run = |threads: usize| {
        let config = RunConfig {
            progress: false,
            dt_s: Some(dt),
            ..scene.run_config(8e-6)
        };
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| scene.transmit(&chirp, &config).unwrap())
    };
    let (one, two) = (run(1), run(2));
    let ledger = &one.ledger;
    eprintln!(
        "turned plies: ledger {:.2e}, viscous loss {:.3e} of source work {:.3e}, memory energy at the end {:.3e}",
        one.report.energy_residual_peak,
        ledger.viscous_loss_j.last().unwrap(),
        ledger.source_work_j.last().unwrap(),
        ledger.memory_j.last().unwrap()
    );
    assert!(one.report.energy_residual_peak < 1e-12, "{:?}", one.report);
    assert!(*ledger.viscous_loss_j.last().unwrap() > 0.0);
    assert!(ledger.memory_j.iter().any(|&m| m != 0.0));
    for (a, b) in one.traces.iter().zip(&two.traces) {
        assert_eq!(a.samples, b.samples);
    }
    assert_eq!(one.ledger.residual, two.ledger.residual);
    assert_eq!(one.ledger.viscous_loss_j, two.ledger.viscous_loss_j);
}

/// The layered plate with a crack along the interface from x = 1 to 3 mm, Coulomb friction
/// 0.6 on its faces: as a layered scene (`crack`), and read from
/// tests/scripts/gmsh_quad_plate_crack.msh (physical line 3 on the same elements).
fn cracked(order: usize, tied: bool) -> [SceneSpec; 2] {
    let contact = ContactOptions {
        friction: 0.6,
        ..Default::default()
    };
    let mut layered = layered(order);
    layered.crack = Some(CrackSpec {
        depth_m: 0.8e-3,
        x_center_m: Some(2e-3),
        length_m: 2e-3,
        contact: Some(contact),
        tied,
    });
    let mut general = from_gmsh(order);
    let g = general.gmsh.as_mut().unwrap();
    g.path = g
        .path
        .replace("gmsh_quad_plate.msh", "gmsh_quad_plate_crack.msh");
    g.crack_line = Some(3);
    g.contact = Some(contact);
    g.tied = tied;
    [layered, general]
}

/// A crack read from Gmsh (the mesh cut along its physical line, src/mesh/cut.rs) runs as
/// the layered scene's crack (split nodes appended to the grid, src/sem/crack.rs) on the
/// same elements: the two share the contact solver but no code for the split, the faces'
/// masses or the pairs. The same 8 us chirp from the side edge, Coulomb friction 0.6: the
/// traces agree to 1.4e-14 to 3.8e-14 (measured; 1e-10 asserted: a stick/slip decision
/// turned by round-off would show), with the same 15 pairs, 1,670 steps in contact and 1,439
/// slipping. The crack-tied companions (the uncut mesh, at the cracked scene's step) agree
/// to 1.4e-14 to 2.4e-14.
#[test]
fn a_crack_read_from_gmsh_runs_as_the_layered_crack_does() {
    let order = 4;
    for tied in [false, true] {
        let [a, b] = cracked(order, tied).map(|s| Scene::build(&s).unwrap());
        assert_eq!(
            a.crack().map(|c| c.pairs.len()),
            b.crack().map(|c| c.pairs.len())
        );
        assert_eq!(
            b.crack().map(|c| c.pairs.len()),
            (!tied).then_some(4 * order - 1)
        );
        let (dt_a, dt_b) = (a.stability.dt_crit_s, b.stability.dt_crit_s);
        // Lanczos stops at its 80 iterations on both; the split models' largest eigenvalue is
        // then within 4e-5 (measured), the uncut ones' within 1e-6
        assert!(
            (dt_a / dt_b - 1.0).abs() < 1e-4,
            "dt_crit {dt_a:e} vs {dt_b:e}"
        );
        let dt = 0.5 * dt_a;
        let chirp = TrNewsSpec::smoke().chirp.signal(dt, 1e5).unwrap();
        let [x, y] = [&a, &b].map(|s| {
            let config = RunConfig {
                progress: false,
                dt_s: Some(dt),
                ..s.run_config(8e-6)
            };
            s.transmit(&chirp, &config).unwrap()
        });
        for (k, (p, q)) in x.traces.iter().zip(&y.traces).enumerate() {
            let d = relative_l2(q, p, None).unwrap();
            eprintln!("tied {tied}, receiver {}: relative difference {d:e}", k + 1);
            assert!(d < 1e-10, "tied {tied}, receiver {}: {d:e}", k + 1);
        }
        if let (Some(p), Some(q)) = (&x.report.contact, &y.report.contact) {
            eprintln!("contact: {q:?}");
            assert!(q.steps_in_contact > 0 && q.max_pairs_slipping > 0);
            assert_eq!(
                (p.steps_in_contact, p.steps_slipping, p.max_pairs_in_contact),
                (q.steps_in_contact, q.steps_slipping, q.max_pairs_in_contact)
            );
        }
        assert!(y.report.energy_residual_peak < 1e-9, "{:?}", y.report);
    }
}

/// The error estimate on a Gmsh mesh ([`SceneSpec::companions`]: the same mesh at orders
/// p - 1 and p - 2, at the run's step) against the true error. The run: the plate as
/// distorted quadrilaterals of about 0.25 mm (tests/scripts/gmsh_quad_plate_unstructured.msh)
/// at order 4, the 8 us chirp from the side edge, at 0.9 dt_crit. The reference shares no
/// rule with it: the layered kernel on a different mesh (rectangles of 0.25 x 0.2 mm) at
/// order 9, at a quarter of the run's step. The reference agrees with the same mesh at order
/// 7 to 2.1e-4 to 3.4e-4, and with the Gmsh mesh at order 7 to 1.4e-4 to 2.3e-4; the run's
/// own step costs it 1e-6 to 3e-6 (measured). Measured on the three receivers: true error
/// 2.3e-3, 1.8e-3, 1.4e-3; the estimate, the bound d_1 = |Q_4 - Q_3| ("upper bound": the
/// lower orders fall 7-13x apart), 2.8e-3, 2.7e-3, 2.7e-3, 1.23-1.88x the true error. Asserted:
/// the verdict "reliable" or "upper bound", and the estimate within a factor 2 of the true
/// error either way (the standard for a stated error).
#[test]
fn error_estimates_on_a_gmsh_mesh_hold_against_a_layered_reference() {
    let order = 4;
    let mut spec = from_gmsh(order);
    spec.gmsh.as_mut().unwrap().path = spec
        .gmsh
        .as_ref()
        .unwrap()
        .path
        .replace("gmsh_quad_plate.msh", "gmsh_quad_plate_unstructured.msh");
    assert_eq!(
        spec.refinement(),
        Refinement::Orders {
            top: order,
            across: false,
            smooth: true
        }
    );
    let main = Scene::build(&spec).unwrap();
    let dt = main.default_dt_s();
    let companions = spec.companions(dt).unwrap();
    assert_eq!(
        companions
            .iter()
            .map(|c| c.gmsh.as_ref().unwrap().order)
            .collect::<Vec<_>>(),
        [Some(order - 1), Some(order - 2)]
    );
    let reference_spec = SceneSpec {
        element_size_x_m: 0.25e-3,
        element_size_y_m: 0.2e-3,
        ..layered(9)
    };
    let reference = Scene::build(&reference_spec).unwrap();
    let duration = 8e-6;
    let run = |s: &Scene, dt: f64| {
        let chirp = TrNewsSpec::smoke().chirp.signal(dt, 1e5).unwrap();
        let config = RunConfig {
            progress: false,
            dt_s: Some(dt),
            ..s.run_config(duration)
        };
        s.transmit(&chirp, &config).unwrap().traces
    };
    let traces = run(&main, dt);
    let lower: Vec<_> = companions
        .iter()
        .map(|c| run(&Scene::build(c).unwrap(), dt))
        .collect();
    let truth = run(&reference, dt / 4.0);
    for k in 0..traces.len() {
        let window = (0.0, duration);
        let e = Estimate::waveform_of(
            &[&traces[k], &lower[0][k], &lower[1][k]],
            window,
            spec.refinement(),
        )
        .unwrap();
        let on_main = trnews::signal::resample(&truth[k], dt).unwrap();
        let true_error = relative_l2(&traces[k], &on_main, Some(window)).unwrap();
        eprintln!("receiver {}: {e:?}, true error {true_error:.3e}", k + 1);
        assert!(
            matches!(e.verdict, Verdict::Reliable | Verdict::UpperBound),
            "receiver {}: {e:?}",
            k + 1
        );
        let ratio = e.error.unwrap() / true_error;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "receiver {}: estimate / true {ratio:.3}",
            k + 1
        );
    }
}

fn error_of(spec: &SceneSpec) -> String {
    Scene::build(spec).unwrap_err().to_string()
}

/// Refused: an order out of range, a crack line the mesh does not have, an angle for a group without a material,
/// a triangle mesh, spectral elements asked by `discretisation` on a Gmsh mesh.
#[test]
fn bad_gmsh_spectral_scenes_name_the_field() {
    let with = |change: &dyn Fn(&mut GmshSpec)| {
        let mut spec = from_gmsh(4);
        change(spec.gmsh.as_mut().unwrap());
        error_of(&spec)
    };
    let e = with(&|g| g.order = Some(0));
    assert!(e.contains("order") && e.contains("1..=16"), "{e}");
    let e = with(&|g| g.crack_line = Some(3));
    assert!(
        e.contains("gmsh.crack_line") && e.contains("no line elements"),
        "{e}"
    );
    let e = with(&|g| {
        g.angles_deg.insert("7".into(), 30.0);
    });
    assert!(e.contains("gmsh.angles_deg") && e.contains("\"7\""), "{e}");
    let e = with(&|g| {
        g.path = format!(
            "{}/tests/scripts/gmsh_plate.msh",
            env!("CARGO_MANIFEST_DIR")
        );
    });
    assert!(
        e.contains("gmsh.path") && e.contains("Tri3") && e.contains("RecombineAll"),
        "{e}"
    );
    let mut sem = from_gmsh(4);
    sem.discretisation = layered(4).discretisation;
    let e = error_of(&sem);
    assert!(
        e.contains("discretisation.kind") && e.contains("gmsh.order"),
        "{e}"
    );
}

/// The impulse-response shortcut on a Gmsh scene, elastic and with strong losses (both
/// linear): a chirp's response convolved from one impulse response equals its simulation to
/// round-off (measured 3.8e-15 to 9.6e-15; asserted 1e-10 as on the layered scene,
/// `tests/trnews.rs`), without the time-dispersion transforms, which the shortcut applies
/// once and the simulation twice.
#[test]
fn the_impulse_response_shortcut_holds_on_a_gmsh_mesh_with_and_without_losses() {
    use std::sync::Arc;
    use trnews::trnews::Responder;
    for attenuation in [None, Some(strong_losses())] {
        let spec = SceneSpec {
            time_dispersion: None,
            attenuation: attenuation.clone(),
            ..from_gmsh(4)
        };
        let scene = Arc::new(Scene::build(&spec).unwrap());
        let convolving = Responder::new(scene.clone(), 10e-6).unwrap();
        let simulating = Responder::simulating(scene);
        let chirp = TrNewsSpec::smoke()
            .chirp
            .signal(convolving.dt_s(), 1e5)
            .unwrap();
        let a = convolving.respond(&chirp, 8e-6).unwrap();
        let b = simulating.respond(&chirp, 8e-6).unwrap();
        for (k, (x, y)) in a.traces.iter().zip(&b.traces).enumerate() {
            let d = relative_l2(x, y, None).unwrap();
            eprintln!(
                "losses {}: receiver {}: convolved vs simulated {d:e}",
                attenuation.is_some(),
                k + 1
            );
            assert!(d < 1e-10, "receiver {}: {d:e}", k + 1);
        }
    }
}
