//! Scenes on spectral elements over Gmsh quadrilaterals (`gmsh: #{order: p, ...}`): the
//! same elements as a layered spectral-element scene give the same run to round-off (mass,
//! stiffness, loads, receivers, dashpots and springs built by the unstructured path agree
//! with the structured one), the energy ledger closes, and refused inputs name the field.

use trnews::scene::{
    Body, DiscretisationSpec, GmshSpec, LaminateSpec, LayerSpec, MaterialSpec, ReceiverSpec, Scene,
    SceneSpec, TransmitterSpec,
};
use trnews::signal::relative_l2;
use trnews::solve::RunConfig;
use trnews::trnews::TrNewsSpec;

fn plate_path() -> String {
    format!(
        "{}/tests/scripts/gmsh_quad_plate.msh",
        env!("CARGO_MANIFEST_DIR")
    )
}

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
        },
        ..around()
    }
}

/// The same plate read from tests/scripts/gmsh_quad_plate.msh (written by gmsh_quads.py).
fn from_gmsh(order: usize) -> SceneSpec {
    SceneSpec {
        gmsh: Some(GmshSpec {
            path: plate_path(),
            materials: [("1", "fabric_0_90"), ("2", "epoxy")]
                .iter()
                .map(|&(k, m)| (k.to_string(), MaterialSpec::Preset(m.into())))
                .collect(),
            crack_line: None,
            contact: None,
            tied: false,
            order: Some(order),
            angles_deg: Default::default(),
            bytes: None,
        }),
        ..around()
    }
}

/// The layered rectangle's elements read from Gmsh and run on the unstructured kernel give
/// the layered scene's traces: the two paths share no code for the mass, the stiffness
/// product, the transmitter's loads, the receivers' weights or the edges' dashpots and
/// springs, so agreement to round-off (measured 1.8e-14 to 3.6e-14 over the three
/// receivers; asserted 1e-12) checks each of them. dt_crit (Lanczos) agrees to 1e-6.
#[test]
fn gmsh_quadrilaterals_run_as_the_layered_scene_does() {
    let order = 4;
    let structured = Scene::build(&layered(order)).unwrap();
    let general = Scene::build(&from_gmsh(order)).unwrap();
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
        eprintln!("receiver {}: relative difference {d:e}", k + 1);
        assert!(d < 1e-12, "receiver {}: {d:e}", k + 1);
    }
    let ledger = runs[1].report.energy_residual_peak;
    assert!(ledger < 1e-9, "energy residual {ledger:e}");
}

fn error_of(spec: &SceneSpec) -> String {
    Scene::build(spec).unwrap_err().to_string()
}

/// Refused: an order out of range, a crack line, an angle for a group without a material,
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
        e.contains("gmsh.crack_line") && e.contains("not built yet"),
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
