//! A crack must not change the discretisation: it snaps onto the lines of the mesh built
//! without it, and the cracked scene and its uncracked companion share mesh and time step.

use trnews::scene::{CrackSpec, Scene, SceneSpec};

/// The cracked default scene, its tied companion and the laminate without any crack have
/// one mesh; the first two run the same step, and the crack-free laminate's own limit is
/// within 2% of it.
#[test]
fn cracked_and_uncracked_default_scenes_share_mesh_and_dt() {
    let spec = SceneSpec::default();
    let cracked = Scene::build(&spec).unwrap();
    let tied = Scene::build(&spec.uncracked()).unwrap();
    let bare = Scene::build(&SceneSpec {
        crack: None,
        ..spec.clone()
    })
    .unwrap();

    let crack = cracked.crack().expect("the default scene is cracked");
    assert!(tied.crack().is_none() && tied.is_linear());
    let (gc, gt) = (
        cracked.mesh().grid.as_ref().unwrap(),
        tied.mesh().grid.as_ref().unwrap(),
    );
    assert_eq!(gc.x_m, gt.x_m, "columns");
    assert_eq!(gc.y_m, gt.y_m, "rows");
    // Same nodes, plus one duplicate per crack pair; the same elements once every
    // duplicate is mapped back to its original.
    let n = tied.mesh().nodes.len();
    assert_eq!(cracked.mesh().nodes.len(), n + crack.pairs.len());
    assert_eq!(cracked.mesh().nodes[..n], tied.mesh().nodes[..]);
    let mut original: Vec<usize> = (0..cracked.mesh().nodes.len()).collect();
    for p in &crack.pairs {
        original[p.slave] = p.master;
    }
    let merged: Vec<[usize; 3]> = cracked
        .mesh()
        .triangles
        .iter()
        .map(|t| t.map(|v| original[v]))
        .collect();
    assert_eq!(merged, tied.mesh().triangles);
    assert_eq!(
        cracked.mesh().element_material,
        tied.mesh().element_material
    );
    assert_eq!(bare.mesh().nodes, tied.mesh().nodes);
    assert_eq!(bare.mesh().triangles, tied.mesh().triangles);

    // One step for both (the cracked model's estimate, the smaller by Rayleigh's principle):
    // the issue asks for agreement within 1%, here it is exact.
    let (dc, dt) = (cracked.stability.dt_crit_s, tied.stability.dt_crit_s);
    assert!((dc - dt).abs() <= 0.01 * dc, "dt_crit {dc:e} vs {dt:e}");
    assert_eq!(dc, dt);
    assert_eq!(cracked.default_dt_s(), tied.default_dt_s());
    // The crack-free laminate's own limit: not below the split model's (up to the Lanczos
    // convergence, 1e-6), and close to it since the crack changes no element (measured 1.4%
    // from the free faces' local modes; before snapping the thin rows beside the crack
    // made it 23%).
    let db = bare.stability.dt_crit_s;
    assert!(
        db >= dc * (1.0 - 1e-6),
        "crack-free {db:e} < cracked {dc:e}"
    );
    assert!(db <= 1.02 * dc, "crack-free {db:e} vs cracked {dc:e}");
}

/// The crack goes to the nearest interior row and column lines, within half a row / column,
/// and the scene reports requested and used geometry.
#[test]
fn crack_snaps_to_the_nearest_mesh_lines_and_reports_them() {
    let spec = SceneSpec::smoke();
    let scene = Scene::build(&spec).unwrap();
    let p = scene.crack_placement.clone().unwrap();
    let grid = scene.mesh().grid.as_ref().unwrap();
    let height = scene.laminate.thickness_m();
    let c = spec.crack.as_ref().unwrap();
    assert_eq!(p.depth_requested_m, c.depth_m);
    assert!((p.x0_requested_m - 2.4e-3).abs() < 1e-15 && (p.x1_requested_m - 3.6e-3).abs() < 1e-15);
    let crack = scene.crack().unwrap();
    let [[x0, y], [x1, _]] = crack.pieces_m[0];
    assert_eq!((x0, x1), (p.x0_used_m, p.x1_used_m));
    assert!((height - y - p.depth_used_m).abs() < 1e-15);
    // on mesh lines, and within half the spacing of the lines around the requested value
    let within_half = |lines: &[f64], requested: f64, used: f64| {
        let k = lines.partition_point(|&l| l <= requested);
        let half = 0.5 * (lines[k] - lines[k - 1]);
        lines.contains(&used) && (used - requested).abs() <= half
    };
    assert!(within_half(&grid.y_m, height - c.depth_m, y));
    assert!(within_half(&grid.x_m, p.x0_requested_m, p.x0_used_m));
    assert!(within_half(&grid.x_m, p.x1_requested_m, p.x1_used_m));
    assert!(!p.tied);
    let tied = Scene::build(&spec.uncracked()).unwrap();
    let q = tied.crack_placement.clone().unwrap();
    assert!(q.tied && q.depth_used_m == p.depth_used_m && q.x0_used_m == p.x0_used_m);
    assert!(tied.contact().is_none());
}

fn error_of(crack: CrackSpec) -> String {
    Scene::build(&SceneSpec {
        crack: Some(crack),
        ..SceneSpec::smoke()
    })
    .expect_err("the crack must be refused")
    .to_string()
}

/// No interior mesh line within the tolerance: an error naming the field and its value.
#[test]
fn crack_without_a_mesh_line_nearby_is_an_error_naming_the_field() {
    let base = SceneSpec::smoke().crack.unwrap();
    // 5 um under the surface: the nearest row line is the top surface itself (rows 40 um)
    let e = error_of(CrackSpec {
        depth_m: 5e-6,
        ..base.clone()
    });
    assert!(
        e.contains("crack.depth_m") && e.contains("0.000005") && e.contains("top surface"),
        "{e}"
    );
    // the left tip 10 um from the left edge (columns 80 um)
    let e = error_of(CrackSpec {
        x_center_m: Some(0.61e-3),
        ..base.clone()
    });
    assert!(
        e.contains("crack.x_center_m")
            && e.contains("left tip x = 1.0000")
            && e.contains("left edge"),
        "{e}"
    );
    // 50 um long: both tips on one column line (or two adjacent ones), no node between
    let e = error_of(CrackSpec {
        length_m: 50e-6,
        ..base
    });
    assert!(
        e.contains("crack.length_m") && e.contains("0.00005") && e.contains("no node between"),
        "{e}"
    );
}
