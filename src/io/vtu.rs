//! Binary VTK XML UnstructuredGrid files (`.vtu`) for ParaView: triangles with point fields
//! (displacement, ...) and cell data (`material`, `layer`).
//!
//! Written by hand rather than through vtkio: the format is a short XML skeleton around
//! little-endian arrays, and vtkio would bring its old parser stack (nom 3, quick-xml 0.22,
//! rejected by future Rust versions) into the library. Each array is inline binary
//! (`format="binary"`): base64 of its byte count as a UInt64 (`header_type="UInt64"`)
//! followed by its values, as ParaView's writer does in its binary mode. (Raw appended
//! bytes would be smaller, but XML readers such as vtkio stop at bytes like `<?` in them.)
//! The tests read the files back with vtkio, and with meshio when it is installed.

use super::{write_atomic, OutputError};
use crate::mesh::Mesh;
use base64::prelude::{Engine as _, BASE64_STANDARD};
use std::fmt::Write as _;
use std::path::Path;

/// A field on the points (or cells) of a mesh: `components` values per entity, entity-major.
/// 1 component is a scalar, 2 a vector in the plane (written with z = 0 for ParaView).
#[derive(Clone, Copy, Debug)]
pub struct Field<'a> {
    /// Array name shown in ParaView, e.g. `displacement`.
    pub name: &'a str,
    /// Values per point or cell: 1 or 2.
    pub components: usize,
    /// The values, `components` per entity.
    pub values: &'a [f64],
}

/// Writes `mesh` with `point_data` and `cell_data` as a binary (base64) `.vtu`. The cell data also
/// holds the mesh's `material` index of every triangle and, for a layered mesh, its `layer`
/// (0 at the bottom). Points get z = 0; triangles are VTK cell type 5. All values must be
/// finite.
pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    point_data: &[Field],
    cell_data: &[Field],
) -> Result<(), OutputError> {
    check(mesh, point_data, cell_data).map_err(|m| OutputError::data(path, m))?;
    write_atomic(path, &vtu_bytes(mesh, point_data, cell_data))
}

/// Checks the inputs of [`write_vtu`]; returns a message naming the first problem.
fn check(mesh: &Mesh, point_data: &[Field], cell_data: &[Field]) -> Result<(), String> {
    let n = mesh.nodes.len();
    if let Some(i) = mesh
        .nodes
        .iter()
        .position(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(format!("point {i} has a non-finite coordinate"));
    }
    if let Some(t) = mesh
        .triangles
        .iter()
        .position(|t| t.iter().any(|&k| k >= n))
    {
        return Err(format!("triangle {t} refers to a point >= {n}"));
    }
    if mesh.element_material.len() != mesh.triangles.len() {
        return Err(format!(
            "{} material indices for {} triangles",
            mesh.element_material.len(),
            mesh.triangles.len()
        ));
    }
    point_data
        .iter()
        .try_for_each(|f| check_field(f, n, "points"))?;
    cell_data
        .iter()
        .try_for_each(|f| check_field(f, mesh.triangles.len(), "cells"))
}

/// Checks that `field` has 1 or 2 finite components for each of `count` entities.
fn check_field(field: &Field, count: usize, entities: &str) -> Result<(), String> {
    let (name, comps) = (field.name, field.components);
    if comps != 1 && comps != 2 {
        return Err(format!(
            "field {name:?} has {comps} components (1 or 2 allowed)"
        ));
    }
    if field.values.len() != comps * count {
        return Err(format!(
            "field {name:?} has {} values, expected {} ({comps} x {count} {entities})",
            field.values.len(),
            comps * count
        ));
    }
    match field.values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(format!(
            "field {name:?} has a non-finite value at index {i}"
        )),
        None => Ok(()),
    }
}

/// Escapes text for use inside an XML attribute value.
pub(super) fn xml_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The XML of a file being built, arrays inline.
#[derive(Default)]
struct Arrays {
    xml: String,
}

impl Arrays {
    /// Writes a `<DataArray>` with `attrs` whose values are `bytes`: base64 of their UInt64
    /// byte count followed by them.
    fn array(&mut self, attrs: &str, bytes: &[u8]) {
        let mut block = Vec::with_capacity(8 + bytes.len());
        block.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        block.extend_from_slice(bytes);
        let _ = writeln!(
            self.xml,
            "        <DataArray {attrs} format=\"binary\">\n          {}\n        </DataArray>",
            BASE64_STANDARD.encode(&block)
        );
    }

    /// Declares a Float64 array of `field`, 2-vectors padded with z = 0.
    fn field(&mut self, field: &Field) {
        let ncomp = if field.components == 1 { 1 } else { 3 };
        let attrs = format!(
            "type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{ncomp}\"",
            xml_attr(field.name)
        );
        let values: Vec<f64> = if field.components == 1 {
            field.values.to_vec()
        } else {
            field
                .values
                .chunks(2)
                .flat_map(|c| [c[0], c[1], 0.0])
                .collect()
        };
        self.array(&attrs, &le_bytes(&values, f64::to_le_bytes));
    }

    /// Declares an Int32 cell label array (material or layer index).
    fn labels(&mut self, name: &str, values: &[usize]) {
        let ids: Vec<i32> = values
            .iter()
            .map(|&v| i32::try_from(v).unwrap_or(i32::MAX))
            .collect();
        let attrs = format!("type=\"Int32\" Name=\"{name}\"");
        self.array(&attrs, &le_bytes(&ids, i32::to_le_bytes));
    }
}

/// The little-endian bytes of `values`.
fn le_bytes<T: Copy, const N: usize>(values: &[T], to_le: fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| to_le(v)).collect()
}

/// Builds the bytes of a VTU file from already-checked inputs.
fn vtu_bytes(mesh: &Mesh, point_data: &[Field], cell_data: &[Field]) -> Vec<u8> {
    let mut a = Arrays::default();
    a.xml.push_str("<?xml version=\"1.0\"?>\n");
    a.xml.push_str(
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
    );
    a.xml.push_str("  <UnstructuredGrid>\n");
    let _ = writeln!(
        a.xml,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        mesh.triangles.len()
    );
    a.xml.push_str("      <PointData>\n");
    point_data.iter().for_each(|f| a.field(f));
    a.xml.push_str("      </PointData>\n      <CellData>\n");
    a.labels("material", &mesh.element_material);
    if let Some(layers) = mesh.element_layers() {
        a.labels("layer", &layers);
    }
    cell_data.iter().for_each(|f| a.field(f));
    a.xml.push_str("      </CellData>\n      <Points>\n");
    let coords: Vec<f64> = mesh.nodes.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    a.array(
        "type=\"Float64\" NumberOfComponents=\"3\"",
        &le_bytes(&coords, f64::to_le_bytes),
    );
    a.xml.push_str("      </Points>\n      <Cells>\n");
    let conn: Vec<i64> = mesh.triangles.iter().flatten().map(|&k| k as i64).collect();
    a.array(
        "type=\"Int64\" Name=\"connectivity\"",
        &le_bytes(&conn, i64::to_le_bytes),
    );
    let offsets: Vec<i64> = (1..=mesh.triangles.len() as i64).map(|c| 3 * c).collect();
    a.array(
        "type=\"Int64\" Name=\"offsets\"",
        &le_bytes(&offsets, i64::to_le_bytes),
    );
    a.array(
        "type=\"UInt8\" Name=\"types\"",
        &vec![5u8; mesh.triangles.len()],
    );
    a.xml
        .push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    a.xml.into_bytes()
}
