//! Import of 2D triangle meshes from Gmsh MSH 4.1 files (via the `mshio` crate), so scenes
//! are not limited to rectangles.

mod counts;

use super::Mesh;
use crate::error::{Error, Result};
use std::collections::HashMap;

/// The MSH file parsed by `mshio`, once its counts are known to fit in its bytes
/// ([`counts::check`]: `mshio` preallocates from them).
fn parse(bytes: &[u8]) -> Result<mshio::MshFile<u64, i32, f64>> {
    counts::check(bytes).map_err(|e| Error::Mesh(format!("cannot read the MSH file: {e}")))?;
    mshio::parse_msh_bytes(bytes).map_err(|e| Error::Mesh(format!("cannot read the MSH file: {e}")))
}

/// Reads the linear triangles (`Tri3`) of a Gmsh MSH 4.1 file (ASCII or binary). Each
/// triangle takes the material that `physical_material` maps its surface's physical group
/// to; triangles are made counter-clockwise; other element types are ignored. The z
/// coordinate is dropped.
pub fn read_msh(bytes: &[u8], physical_material: &HashMap<i32, usize>) -> Result<Mesh> {
    let msh = parse(bytes)?;
    let nodes_section = msh
        .data
        .nodes
        .ok_or_else(|| Error::Mesh("the MSH file has no $Nodes section".into()))?;
    let elements = msh
        .data
        .elements
        .ok_or_else(|| Error::Mesh("the MSH file has no $Elements section".into()))?;
    let surface_groups: HashMap<i32, Vec<i32>> = msh
        .data
        .entities
        .map(|e| {
            e.surfaces
                .into_iter()
                .map(|s| (s.tag, s.physical_tags))
                .collect()
        })
        .unwrap_or_default();

    let mut nodes = Vec::with_capacity(nodes_section.num_nodes as usize);
    let mut index_of = HashMap::with_capacity(nodes_section.num_nodes as usize);
    let mut next_tag = nodes_section.min_node_tag;
    for block in &nodes_section.node_blocks {
        let tags: Vec<u64> = match &block.node_tags {
            Some(map) => {
                let mut t = vec![0; block.nodes.len()];
                map.iter().for_each(|(&tag, &i)| t[i] = tag);
                t
            }
            None => (next_tag..next_tag + block.nodes.len() as u64).collect(),
        };
        next_tag += block.nodes.len() as u64;
        for (tag, node) in tags.into_iter().zip(&block.nodes) {
            index_of.insert(tag, nodes.len());
            nodes.push([node.x, node.y]);
        }
    }

    let mut mesh = Mesh {
        nodes,
        triangles: Vec::new(),
        element_material: Vec::new(),
        interfaces_y_m: Vec::new(),
        grid: None,
    };
    for block in elements
        .element_blocks
        .iter()
        .filter(|b| b.element_type == mshio::ElementType::Tri3)
    {
        let groups = surface_groups
            .get(&block.entity_tag)
            .map(Vec::as_slice)
            .unwrap_or_default();
        let material = groups.iter().find_map(|g| physical_material.get(g)).copied().ok_or_else(|| {
            Error::Mesh(format!("surface {} (physical groups {groups:?}) has no material: map one of its physical groups", block.entity_tag))
        })?;
        for element in &block.elements {
            let mut t = [0; 3];
            for (k, tag) in element.nodes.iter().take(3).enumerate() {
                t[k] = *index_of.get(tag).ok_or_else(|| {
                    Error::Mesh(format!(
                        "element {} refers to node {tag}, which is not in $Nodes",
                        element.element_tag
                    ))
                })?;
            }
            if mesh.twice_area(t) < 0.0 {
                t.swap(1, 2);
            }
            mesh.triangles.push(t);
            mesh.element_material.push(material);
        }
    }
    if mesh.triangles.is_empty() {
        return Err(Error::Mesh(
            "the MSH file has no linear triangles (Tri3)".into(),
        ));
    }
    mesh.validate()?;
    Ok(mesh)
}

/// The points of the linear line elements (`Lin2`) of the curves in physical group `group`
/// of a Gmsh MSH 4.1 file (each node once, in file order): a crack or an interface drawn
/// as a physical line. An error when the group has no line element.
pub fn read_physical_line(bytes: &[u8], group: i32) -> Result<Vec<[f64; 2]>> {
    let msh = parse(bytes)?;
    let curves: Vec<i32> = msh
        .data
        .entities
        .map(|e| {
            e.curves
                .into_iter()
                .filter(|c| c.physical_tags.contains(&group))
                .map(|c| c.tag)
                .collect()
        })
        .unwrap_or_default();
    let mut coordinates = HashMap::new();
    if let Some(nodes) = &msh.data.nodes {
        let mut next_tag = nodes.min_node_tag;
        for block in &nodes.node_blocks {
            let mut tags: Vec<u64> = (next_tag..next_tag + block.nodes.len() as u64).collect();
            if let Some(map) = &block.node_tags {
                map.iter().for_each(|(&tag, &i)| tags[i] = tag);
            }
            next_tag += block.nodes.len() as u64;
            for (tag, node) in tags.into_iter().zip(&block.nodes) {
                coordinates.insert(tag, [node.x, node.y]);
            }
        }
    }
    let mut seen = std::collections::HashSet::new();
    let mut points = Vec::new();
    for block in msh
        .data
        .elements
        .iter()
        .flat_map(|e| &e.element_blocks)
        .filter(|b| b.element_type == mshio::ElementType::Lin2 && curves.contains(&b.entity_tag))
    {
        for tag in block.elements.iter().flat_map(|e| e.nodes.iter().take(2)) {
            let p = coordinates.get(tag).ok_or_else(|| {
                Error::Mesh(format!(
                    "a line element of physical group {group} refers to node {tag}, which is not in $Nodes"
                ))
            })?;
            if seen.insert(*tag) {
                points.push(*p);
            }
        }
    }
    if points.is_empty() {
        return Err(Error::Mesh(format!(
            "physical group {group} has no line elements (Lin2) in the MSH file"
        )));
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square as two triangles on two surfaces (physical groups 7 and 8), the
    /// second written clockwise, plus a line element that must be ignored.
    pub(super) const SQUARE: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 2 0\n1 0 0 0 1 1 0 1 7 0\n2 0 0 0 1 1 0 1 8 0\n$EndEntities\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n3 3 1 3\n2 1 2 1\n1 1 2 3\n2 2 2 1\n2 1 4 3\n1 1 1 1\n3 1 2\n$EndElements\n";

    #[test]
    fn reads_triangles_with_materials_counter_clockwise() {
        let map = HashMap::from([(7, 0), (8, 1)]);
        let mesh = read_msh(SQUARE.as_bytes(), &map).unwrap();
        assert_eq!(mesh.nodes.len(), 4);
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(mesh.element_material, vec![0, 1]);
        assert!(mesh
            .triangles
            .iter()
            .all(|&t| (mesh.twice_area(t) - 1.0).abs() < 1e-15));
    }

    #[test]
    fn physical_line_gives_its_nodes_once() {
        // the square's line element 1 -> 2 lies on curve 1: put that curve in physical group 5
        let with_line = SQUARE.replace(
            "$Entities\n0 0 2 0\n",
            "$Entities\n0 1 2 0\n1 0 0 0 1 0 0 1 5 0\n",
        );
        let line = read_physical_line(with_line.as_bytes(), 5).unwrap();
        assert_eq!(line, vec![[0.0, 0.0], [1.0, 0.0]]);
        let e = read_physical_line(with_line.as_bytes(), 6)
            .unwrap_err()
            .to_string();
        assert!(e.contains("physical group 6"), "{e}");
    }

    #[test]
    fn unmapped_physical_group_and_garbage_are_errors() {
        let e = read_msh(SQUARE.as_bytes(), &HashMap::from([(7, 0)]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("surface 2") && e.contains("[8]"), "{e}");
        assert!(read_msh(b"not a mesh", &HashMap::new())
            .unwrap_err()
            .to_string()
            .contains("cannot read"));
    }
}
