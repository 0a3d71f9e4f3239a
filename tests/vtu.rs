//! The binary VTU and PVD files open in ParaView's readers: read back with vtkio (point and
//! cell counts, displacement, material and layer), the collection parsed, and with Python's
//! meshio when it is installed.

mod common;

use common::TempDir;
use std::path::{Path, PathBuf};
use trnews::io::vtu::Field;
use trnews::io::{write_pvd, write_vtu};
use trnews::mesh::Mesh;
use vtkio::model::{Attribute, DataSet, VertexNumbers};

/// A 1 x 2 block of squares split into 4 triangles: layer 0 (material 0) below y = 0.5,
/// layer 1 (material 1) above.
fn two_layer_mesh() -> Mesh {
    Mesh {
        nodes: vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 0.5],
            [1.0, 0.5],
            [0.0, 1.0],
            [1.0, 1.0],
        ],
        triangles: vec![[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]],
        element_material: vec![0, 0, 1, 1],
        interfaces_y_m: vec![0.0, 0.5, 1.0],
        grid: None,
    }
}

/// Displacement of snapshot `k`: u = (k x, -k y) at every node, point-major.
fn displacement(mesh: &Mesh, k: usize) -> Vec<f64> {
    mesh.nodes
        .iter()
        .flat_map(|p| [k as f64 * p[0], -(k as f64) * p[1]])
        .collect()
}

/// Writes the VTU of snapshot `k` of the mesh at `path`.
fn write_snapshot(path: &Path, mesh: &Mesh, k: usize) {
    let u = displacement(mesh, k);
    let speed: Vec<f64> = (0..mesh.triangles.len()).map(|c| 0.5 * c as f64).collect();
    let point_data = [Field {
        name: "displacement",
        components: 2,
        values: &u,
    }];
    let cell_data = [Field {
        name: "speed <m/s>",
        components: 1,
        values: &speed,
    }];
    write_vtu(path, mesh, &point_data, &cell_data).expect("write vtu");
}

/// The named data array among `attributes`, as f64 values.
fn array(attributes: &[Attribute], name: &str) -> Vec<f64> {
    attributes
        .iter()
        .find_map(|a| match a {
            Attribute::DataArray(d) if d.name == name => d.data.clone().cast_into::<f64>(),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no array {name:?}"))
}

#[test]
fn vtu_reads_back_with_vtkio() {
    let dir = TempDir::new("vtu");
    let path = dir.path().join("snap.vtu");
    let mesh = two_layer_mesh();
    write_snapshot(&path, &mesh, 2);
    let vtk = vtkio::Vtk::import(&path).expect("vtkio reads the file");
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid");
    };
    assert_eq!(pieces.len(), 1);
    let piece = pieces
        .into_iter()
        .next()
        .unwrap()
        .into_loaded_piece_data(None)
        .expect("inline piece");
    assert_eq!(piece.num_points(), 6);
    assert_eq!(piece.cells.num_cells(), 4);
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &piece.cells.cell_verts
    else {
        panic!("XML cells expected");
    };
    assert_eq!(connectivity[3..6], [0, 3, 2]);
    assert_eq!(offsets, &[3, 6, 9, 12]);
    let points = piece.points.clone().cast_into::<f64>().expect("f64 points");
    assert_eq!(points[9..12], [1.0, 0.5, 0.0]);
    let u = array(&piece.data.point, "displacement");
    assert_eq!(u.len(), 18, "2-vectors padded to 3 components");
    assert_eq!(u[15..18], [2.0, -2.0, 0.0]);
    assert_eq!(array(&piece.data.cell, "material"), [0.0, 0.0, 1.0, 1.0]);
    assert_eq!(array(&piece.data.cell, "layer"), [0.0, 0.0, 1.0, 1.0]);
    assert_eq!(array(&piece.data.cell, "speed <m/s>"), [0.0, 0.5, 1.0, 1.5]);
}

#[test]
fn vtu_without_layers_and_bad_fields() {
    let dir = TempDir::new("vtu-bad");
    let path = dir.path().join("m.vtu");
    let mut mesh = two_layer_mesh();
    mesh.interfaces_y_m.clear();
    write_vtu(&path, &mesh, &[], &[]).expect("write");
    let text = String::from_utf8_lossy(&std::fs::read(&path).expect("read")).into_owned();
    assert!(text.contains("Name=\"material\"") && !text.contains("Name=\"layer\""));
    let short = Field {
        name: "ux",
        components: 1,
        values: &[1.0],
    };
    let err = write_vtu(&path, &mesh, &[short], &[]).expect_err("length");
    assert!(err.to_string().contains("ux"), "{err}");
    let nan = Field {
        name: "w",
        components: 1,
        values: &[f64::NAN; 4],
    };
    let err = write_vtu(&path, &mesh, &[], &[nan]).expect_err("non-finite");
    assert!(err.to_string().contains("non-finite"), "{err}");
    mesh.triangles[1] = [0, 3, 6];
    let err = write_vtu(&path, &mesh, &[], &[]).expect_err("index");
    assert!(err.to_string().contains("triangle 1"), "{err}");
}

/// The `(timestep, file)` attributes of the `<DataSet>` entries of a PVD collection.
fn collection_entries(xml: &str) -> Vec<(f64, String)> {
    let attr = |tag: &str, key: &str| -> String {
        let start = tag.find(&format!("{key}=\"")).expect("attribute") + key.len() + 2;
        tag[start..start + tag[start..].find('"').unwrap()].to_string()
    };
    xml.split("<DataSet ")
        .skip(1)
        .map(|tag| {
            let tag = &tag[..tag.find("/>").expect("empty element")];
            (attr(tag, "timestep").parse().unwrap(), attr(tag, "file"))
        })
        .collect()
}

#[test]
fn pvd_lists_three_snapshots_with_their_times() {
    let dir = TempDir::new("pvd");
    let mesh = two_layer_mesh();
    let times = [0.0, 2.5e-7, 5e-7];
    let files: Vec<PathBuf> = (1..=3)
        .map(|k| dir.path().join(format!("series/field_{k:03}.vtu")))
        .collect();
    for (k, f) in files.iter().enumerate() {
        write_snapshot(f, &mesh, k);
    }
    let frames: Vec<(f64, &Path)> = times
        .iter()
        .copied()
        .zip(files.iter().map(|f| f.as_path()))
        .collect();
    let pvd = dir.path().join("series/field.pvd");
    write_pvd(&pvd, &frames).expect("write pvd");
    let xml = std::fs::read_to_string(&pvd).expect("read pvd");
    assert!(xml.contains("<VTKFile type=\"Collection\""), "{xml}");
    let entries = collection_entries(&xml);
    assert_eq!(entries.len(), 3);
    for ((t, file), (want_t, k)) in entries.iter().zip(times.iter().zip(1..)) {
        assert_eq!(t, want_t);
        assert_eq!(
            file,
            &format!("field_{k:03}.vtu"),
            "listed relative to the collection"
        );
        let vtk = vtkio::Vtk::import(pvd.with_file_name(file)).expect("listed file reads");
        assert!(matches!(vtk.data, DataSet::UnstructuredGrid { .. }));
    }
    let err = write_pvd(&pvd, &[(f64::NAN, files[0].as_path())]).expect_err("NaN time");
    assert!(err.to_string().contains("non-finite"), "{err}");
    meshio_check(&files[2]);
}

/// `scene::write_pvd` from a script: one VTU per snapshot of a run beside the collection,
/// listed with the snapshots' times, each with the scene's point and cell counts.
/// A run's snapshots as a ParaView series, from a T3 scene and from a spectral-element one
/// (whose VTU cells are its GLL cells, each as two triangles, on its nodes).
#[test]
fn script_writes_a_snapshot_series() {
    for kind in ["t3", "sem"] {
        snapshot_series(kind);
    }
}

fn snapshot_series(kind: &str) {
    use trnews::script::{Host, HostOptions};
    let dir = TempDir::new(&format!("pvd-script-{kind}"));
    let script = dir.path().join("series.rhai");
    let text = format!(
        "let s = scene::preset(\"smoke\", \"{kind}\", #{{}});\n\
         let run = s.transmit(signal::chirp(2e5, 2e6, 5e-6, 5e-6, 1e-8), #{{duration_s: 20.0 * s.dt, snapshot_every: 5}});\n\
         scene::write_pvd(\"anim/field.pvd\", s, run);\n\
         io::write_json(\"nodes.json\", s.summary().nodes);\n"
    );
    std::fs::write(&script, text).unwrap();
    let out = dir.path().join("out");
    let host = Host::new(HostOptions {
        out_dir: out.clone(),
        quiet: true,
        ..HostOptions::default()
    })
    .unwrap();
    host.run_file(&script).expect("script runs");
    let pvd = out.join("anim/field.pvd");
    let entries = collection_entries(&std::fs::read_to_string(&pvd).expect("collection"));
    assert!(entries.len() >= 3, "{entries:?}");
    assert!(
        entries.windows(2).all(|w| w[1].0 > w[0].0),
        "times increase"
    );
    for (k, (_, file)) in entries.iter().enumerate() {
        assert_eq!(file, &format!("field_{:03}.vtu", k + 1));
        let vtk = vtkio::Vtk::import(pvd.with_file_name(file)).expect("snapshot reads");
        let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
            panic!("not an unstructured grid");
        };
        let piece = pieces
            .into_iter()
            .next()
            .unwrap()
            .into_loaded_piece_data(None)
            .unwrap();
        let nodes: usize = std::fs::read_to_string(out.join("nodes.json"))
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        assert!(
            piece.num_points() == nodes && piece.cells.num_cells() > 0,
            "{kind}"
        );
        // VTK vectors have three components (u_z = 0)
        assert_eq!(array(&piece.data.point, "displacement").len(), 3 * nodes);
        assert_eq!(
            array(&piece.data.cell, "layer").len(),
            piece.cells.num_cells()
        );
    }
}

/// If python3 with meshio is present, read the VTU there too (skipped otherwise, saying why).
fn meshio_check(vtu: &Path) {
    let code = format!(
        "import meshio; m = meshio.read(r'{}'); \
         assert len(m.points) == 6 and sum(len(c.data) for c in m.cells) == 4; \
         assert list(m.cell_data['layer'][0]) == [0, 0, 1, 1]",
        vtu.display()
    );
    let Ok(out) = std::process::Command::new("python3")
        .args(["-c", &code])
        .output()
    else {
        println!("python3 not available; skipped the meshio check");
        return;
    };
    let err = String::from_utf8_lossy(&out.stderr);
    if err.contains("No module named") {
        println!("meshio not installed; skipped the meshio check");
        return;
    }
    assert!(
        out.status.success(),
        "meshio failed to read {}: {err}",
        vtu.display()
    );
}
