use super::*;
use crate::laminate::{Laminate, StochasticSpec};
use crate::material::{Orthotropic, Plane};

fn small_cfrp() -> (Mesh, Vec<Material>) {
    let lam = Laminate::stochastic(
        &StochasticSpec {
            pairs: 3,
            ..Default::default()
        },
        Plane::Strain,
    )
    .unwrap();
    let mesh = Mesh::layered(&lam, 1e-3, 0.2e-3, 0.1e-3, &[], &[]).unwrap();
    (mesh, lam.materials)
}

fn epoxy_block(width: f64, height: f64, h: f64) -> (Mesh, Vec<Material>) {
    let epoxy = Orthotropic::epoxy().reduce(Plane::Strain).unwrap();
    let lam = Laminate::homogeneous(epoxy, height).unwrap();
    (
        Mesh::layered(&lam, width, h, h, &[], &[]).unwrap(),
        lam.materials,
    )
}

fn dense_mul(d: &[Vec<f64>], u: &[f64]) -> Vec<f64> {
    d.iter()
        .map(|row| row.iter().zip(u).map(|(a, b)| a * b).sum())
        .collect()
}

#[test]
fn stiffness_is_symmetric() {
    let (mesh, mats) = small_cfrp();
    let k = assemble_stiffness(&mesh, &mats).unwrap();
    // Round-off only: entries are sums of at most 6 element contributions.
    assert!(k.asymmetry() < 1e-14, "asymmetry {}", k.asymmetry());
}

#[test]
fn rigid_body_modes_have_zero_force() {
    // Translations x, y and the infinitesimal rotation (-y, x): K r = 0 up to round-off
    // relative to |K| |r| (1e-12: each row sums ~7 blocks of O(|K|) entries).
    let (mesh, mats) = small_cfrp();
    let k = assemble_stiffness(&mesh, &mats).unwrap();
    let kmax = k
        .blocks
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    type Mode = Box<dyn Fn([f64; 2]) -> [f64; 2]>;
    let modes: [Mode; 3] = [
        Box::new(|_| [1.0, 0.0]),
        Box::new(|_| [0.0, 1.0]),
        Box::new(|p| [-p[1] * 1e3, p[0] * 1e3]),
    ];
    for (m, mode) in modes.iter().enumerate() {
        let r: Vec<f64> = mesh.nodes.iter().flat_map(|&p| mode(p)).collect();
        let rmax = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut f = vec![0.0; r.len()];
        k.mul(&r, &mut f);
        let fmax = f.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(fmax < 1e-12 * kmax * rmax, "mode {m}: |K r| = {fmax:e}");
    }
}

#[test]
fn total_lumped_and_consistent_mass_equal_rho_area() {
    let (mesh, mats) = small_cfrp();
    let expected: f64 = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(e, &t)| mats[mesh.element_material[e]].density_kg_m3 * 0.5 * mesh.twice_area(t))
        .sum();
    let lumped = assemble_lumped_mass(&mesh, &mats).unwrap();
    let total_x: f64 = lumped.iter().step_by(2).sum();
    assert!((total_x - expected).abs() < 1e-12 * expected);
    let consistent = assemble_consistent_mass(&mesh, &mats).unwrap();
    let ones_x: Vec<f64> = (0..mesh.dofs())
        .map(|d| if d % 2 == 0 { 1.0 } else { 0.0 })
        .collect();
    let mut mx = vec![0.0; mesh.dofs()];
    consistent.mul(&ones_x, &mut mx);
    assert!((mx.iter().sum::<f64>() - expected).abs() < 1e-12 * expected);
}

#[test]
fn patch_test_linear_field_gives_zero_interior_residual() {
    // A linear displacement field is represented exactly and has constant strain, so the
    // internal force K u vanishes at every node not on the boundary (equilibrium without
    // body force), across material interfaces only if the stress is continuous: use one
    // material here. Tolerance: round-off relative to |K| |u|.
    let (mesh, mats) = epoxy_block(1e-3, 0.6e-3, 0.1e-3);
    let k = assemble_stiffness(&mesh, &mats).unwrap();
    let u: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|p| [1e-3 * p[0] + 2e-3 * p[1], -0.5e-3 * p[0] + 0.7e-3 * p[1]])
        .collect();
    let mut f = vec![0.0; u.len()];
    k.mul(&u, &mut f);
    let scale = k
        .blocks
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        * 1e-6;
    let boundary: std::collections::HashSet<usize> =
        [Side::Bottom, Side::Top, Side::Left, Side::Right]
            .iter()
            .flat_map(|&s| mesh.side_nodes(s))
            .collect();
    for n in (0..mesh.nodes.len()).filter(|n| !boundary.contains(n)) {
        assert!(
            f[2 * n].abs() < 1e-12 * scale && f[2 * n + 1].abs() < 1e-12 * scale,
            "node {n}: {:e} {:e}",
            f[2 * n],
            f[2 * n + 1]
        );
    }
    for (t, _) in mesh.triangles.iter().zip(0..) {
        let ue = nalgebra::SVector::<f64, 6>::from_iterator(
            t.iter().flat_map(|&n| [u[2 * n], u[2 * n + 1]]),
        );
        let e = element::strain(t.map(|n| mesh.nodes[n]), &ue);
        assert!(
            (e[0] - 1e-3).abs() < 1e-15
                && (e[1] - 0.7e-3).abs() < 1e-15
                && (e[2] - 1.5e-3).abs() < 1e-15
        );
    }
}

#[test]
fn sparse_assembly_matches_dense_reference() {
    let (mesh, mats) = small_cfrp();
    let n = mesh.dofs();
    let mut dense_k = vec![vec![0.0; n]; n];
    let mut dense_m = vec![vec![0.0; n]; n];
    for (e, t) in mesh.triangles.iter().enumerate() {
        let mat = &mats[mesh.element_material[e]];
        let ke = element::stiffness(t.map(|i| mesh.nodes[i]), &mat.stiffness_pa);
        let me = element::consistent_mass(0.5 * mesh.twice_area(*t), mat.density_kg_m3);
        for i in 0..6 {
            for j in 0..6 {
                let (gi, gj) = (2 * t[i / 2] + i % 2, 2 * t[j / 2] + j % 2);
                dense_k[gi][gj] += ke[(i, j)];
                dense_m[gi][gj] += me[(i, j)];
            }
        }
    }
    let k = assemble_stiffness(&mesh, &mats).unwrap().to_dense();
    let m = assemble_consistent_mass(&mesh, &mats).unwrap().to_dense();
    let kmax = dense_k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let mmax = dense_m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    for i in 0..n {
        for j in 0..n {
            assert!(
                (k[i][j] - dense_k[i][j]).abs() <= 1e-14 * kmax,
                "K[{i}][{j}]"
            );
            assert!(
                (m[i][j] - dense_m[i][j]).abs() <= 1e-14 * mmax,
                "M[{i}][{j}]"
            );
        }
    }
    // and the parallel product equals the dense product
    let u: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
    let mut ku = vec![0.0; n];
    assemble_stiffness(&mesh, &mats).unwrap().mul(&u, &mut ku);
    for (a, b) in ku.iter().zip(dense_mul(&dense_k, &u)) {
        assert!((a - b).abs() <= 1e-13 * kmax * 10.0);
    }
}

#[test]
fn dashpots_on_homogeneous_edge_sum_to_impedance_times_length() {
    let (width, height) = (2e-3, 1e-3);
    let (mesh, mats) = epoxy_block(width, height, 0.1e-3);
    let w = mats[0].wave_speeds();
    let rho = mats[0].density_kg_m3;
    let c = assemble_dashpots(&mesh, &mats, &[Side::Bottom]).unwrap();
    let normal: f64 = c.iter().filter(|(d, _)| d % 2 == 1).map(|(_, v)| v).sum();
    let tangential: f64 = c.iter().filter(|(d, _)| d % 2 == 0).map(|(_, v)| v).sum();
    assert!((normal - rho * w.p_y_m_s * width).abs() < 1e-12 * normal);
    assert!((tangential - rho * w.s_m_s * width).abs() < 1e-12 * tangential);
    let left = assemble_dashpots(&mesh, &mats, &[Side::Left]).unwrap();
    let normal_left: f64 = left
        .iter()
        .filter(|(d, _)| d % 2 == 0)
        .map(|(_, v)| v)
        .sum();
    assert!((normal_left - rho * w.p_x_m_s * height).abs() < 1e-12 * normal_left);
    assert!(assemble_dashpots(&mesh, &mats, &[]).unwrap().is_empty());
}

#[test]
fn orphan_node_is_an_error() {
    let (mut mesh, mats) = epoxy_block(1e-3, 1e-3, 0.5e-3);
    mesh.nodes.push([0.5e-3, 0.5e-3]);
    let e = assemble_lumped_mass(&mesh, &mats).unwrap_err().to_string();
    assert!(e.contains("belongs to no element"), "{e}");
}

#[test]
fn row_assembly_matches_element_by_element_assembly() {
    // The parallel row-wise assembly against the plain element loop with the full 6x6
    // element matrices, on a cracked mesh (duplicated nodes appended at the end).
    let (mut mesh, mats) = small_cfrp();
    let y = mesh.nearest_row_y(0.5 * mesh.bounds().3).unwrap();
    let (x0, x1) = (
        mesh.nearest_column_x(0.2e-3).unwrap(),
        mesh.nearest_column_x(0.8e-3).unwrap(),
    );
    mesh.insert_crack(y, x0, x1).unwrap();
    let k = assemble_stiffness(&mesh, &mats).unwrap();
    let mut reference = BlockCsr::pattern(mesh.nodes.len(), &mesh.triangles);
    for (e, &t) in mesh.triangles.iter().enumerate() {
        let m = &mats[mesh.element_material[e]];
        reference.add_element(
            t,
            &element::stiffness(t.map(|n| mesh.nodes[n]), &m.stiffness_pa),
        );
    }
    assert_eq!(k.row_ptr, reference.row_ptr);
    assert_eq!(k.cols, reference.cols);
    let scale = reference
        .blocks
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in k
        .blocks
        .iter()
        .flatten()
        .zip(reference.blocks.iter().flatten())
    {
        assert!((a - b).abs() <= 1e-14 * scale, "{a} vs {b}");
    }
}

/// Left and right edges whose nodes are not at the same heights cannot be tied: the error
/// names the edges and the first height without a partner, or the counts.
#[test]
fn periodic_ties_name_columns_that_do_not_match() {
    let mesh = |right: &[f64]| Mesh {
        nodes: [[0.0, 0.0], [0.0, 1.0]]
            .into_iter()
            .chain(right.iter().map(|&y| [1.0, y]))
            .collect(),
        triangles: vec![[0, 2, 1]],
        element_material: vec![0],
        interfaces_y_m: vec![],
        grid: None,
    };
    let e = periodic_ties(&mesh(&[0.0, 0.6]), &mut vec![])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("edges.left, edges.right") && e.contains("1e0 m on the left"),
        "{e}"
    );
    // a third node on the right at a height the left has (a crack face reaching the edge)
    let e = periodic_ties(&mesh(&[0.0, 1.0, 1.0]), &mut vec![])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the left edge has 2 nodes, the right edge 3"),
        "{e}"
    );
    let mut fixed = vec![3];
    let ties = periodic_ties(&mesh(&[0.0, 1.0]), &mut fixed).unwrap();
    assert_eq!(ties, vec![(0, 4), (1, 5), (2, 6), (3, 7)]);
    assert_eq!(fixed, vec![3, 7], "a DOF held on one side is held on both");
}
