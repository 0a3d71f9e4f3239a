//! Import of 2D triangle meshes from Gmsh MSH 4.1 files (via the `mshio` crate), so scenes
//! are not limited to rectangles.

mod counts;

use super::quad::{Quad, QuadMesh};
use super::Mesh;
use crate::error::{Error, Result};
use std::collections::HashMap;

/// The MSH file parsed by `mshio`, once its counts are known to fit in its bytes
/// ([`counts::check`]: `mshio` preallocates from them).
fn parse(bytes: &[u8]) -> Result<mshio::MshFile<u64, i32, f64>> {
    counts::check(bytes).map_err(|e| Error::Mesh(format!("cannot read the MSH file: {e}")))?;
    mshio::parse_msh_bytes(bytes).map_err(|e| Error::Mesh(format!("cannot read the MSH file: {e}")))
}

type Msh = mshio::MshFile<u64, i32, f64>;

/// Node positions and each node tag's index among them.
type Nodes = (Vec<[f64; 2]>, HashMap<u64, usize>);

/// The nodes of a parsed file (x, y; z dropped) and each node tag's index among them.
fn nodes_of(msh: &Msh) -> Result<Nodes> {
    let nodes_section = msh
        .data
        .nodes
        .as_ref()
        .ok_or_else(|| Error::Mesh("the MSH file has no $Nodes section".into()))?;
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
    Ok((nodes, index_of))
}

/// The physical groups of each surface entity, by the surface's tag.
fn surface_groups(msh: &Msh) -> HashMap<i32, Vec<i32>> {
    msh.data
        .entities
        .as_ref()
        .map(|e| {
            e.surfaces
                .iter()
                .map(|s| (s.tag, s.physical_tags.clone()))
                .collect()
        })
        .unwrap_or_default()
}

/// What `physical` maps the first mapped physical group of surface `surface` to; an error
/// naming the surface and its groups when none is mapped.
fn surface_value<T: Copy>(
    groups: &HashMap<i32, Vec<i32>>,
    physical: &HashMap<i32, T>,
    surface: i32,
) -> Result<T> {
    let groups = groups.get(&surface).map(Vec::as_slice).unwrap_or_default();
    groups
        .iter()
        .find_map(|g| physical.get(g))
        .copied()
        .ok_or_else(|| {
            Error::Mesh(format!(
                "surface {surface} (physical groups {groups:?}) has no material: map one of its \
             physical groups"
            ))
        })
}

/// The node indices of an element's first `count` node tags; an error naming the element
/// and the tag that is not in $Nodes.
fn element_nodes(
    element: &mshio::Element<u64>,
    count: usize,
    index_of: &HashMap<u64, usize>,
) -> Result<Vec<usize>> {
    element
        .nodes
        .iter()
        .take(count)
        .map(|tag| {
            index_of.get(tag).copied().ok_or_else(|| {
                Error::Mesh(format!(
                    "element {} refers to node {tag}, which is not in $Nodes",
                    element.element_tag
                ))
            })
        })
        .collect()
}

/// Reads the linear triangles (`Tri3`) of a Gmsh MSH 4.1 file (ASCII or binary). Each
/// triangle takes the material that `physical_material` maps its surface's physical group
/// to; triangles are made counter-clockwise; other element types are ignored. The z
/// coordinate is dropped.
pub fn read_msh(bytes: &[u8], physical_material: &HashMap<i32, usize>) -> Result<Mesh> {
    let msh = parse(bytes)?;
    let (nodes, index_of) = nodes_of(&msh)?;
    let groups = surface_groups(&msh);
    let elements = msh
        .data
        .elements
        .as_ref()
        .ok_or_else(|| Error::Mesh("the MSH file has no $Elements section".into()))?;
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
        let material = surface_value(&groups, physical_material, block.entity_tag)?;
        for element in &block.elements {
            let n = element_nodes(element, 3, &index_of)?;
            let mut t = [n[0], n[1], n[2]];
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

/// Reads the quadrilaterals of a Gmsh MSH 4.1 file: 4-node (`Qua4`, straight sides) or
/// 9-node (`Qua9`, second order: curved sides), all of one kind, for spectral elements
/// ([`crate::mesh::quad`]). Each takes the (material, angle of its axes in rad) that
/// `physical` maps its surface's physical group to; point and line elements are ignored.
/// Triangles, 8-node quadrilaterals or a mix of 4 and 9 nodes are errors naming the
/// surface, as is a surface without a mapped group; element orientation and shape are
/// checked by [`QuadMesh::validate`] when the model is built.
pub fn read_quads(bytes: &[u8], physical: &HashMap<i32, (usize, f64)>) -> Result<QuadMesh> {
    use mshio::ElementType::{Qua4, Qua9};
    let msh = parse(bytes)?;
    let (nodes, index_of) = nodes_of(&msh)?;
    let groups = surface_groups(&msh);
    let blocks = msh
        .data
        .elements
        .as_ref()
        .ok_or_else(|| Error::Mesh("the MSH file has no $Elements section".into()))?;
    let mut mesh = QuadMesh {
        nodes,
        elements: Vec::new(),
    };
    let mut kind = None;
    for block in blocks.element_blocks.iter().filter(|b| b.entity_dim == 2) {
        let count = match block.element_type {
            Qua4 => 4,
            Qua9 => 9,
            other => {
                return Err(Error::Mesh(format!(
                    "surface {} holds {other:?} elements: spectral elements take 4- or \
                     9-node quadrilaterals only (Gmsh: Mesh.RecombineAll = 1, and \
                     Mesh.SecondOrderIncomplete = 0 for curved elements)",
                    block.entity_tag
                )))
            }
        };
        if *kind.get_or_insert(count) != count {
            return Err(Error::Mesh(format!(
                "surface {} holds {count}-node quadrilaterals where others hold {}: mesh \
                 every surface at one order",
                block.entity_tag,
                kind.unwrap_or(count)
            )));
        }
        let (material, angle_rad) = surface_value(&groups, physical, block.entity_tag)?;
        for element in &block.elements {
            mesh.elements.push(Quad {
                nodes: element_nodes(element, count, &index_of)?,
                material,
                angle_rad,
                tag: element.element_tag,
            });
        }
    }
    if mesh.elements.is_empty() {
        return Err(Error::Mesh(
            "the MSH file has no quadrilaterals (Qua4 or Qua9)".into(),
        ));
    }
    Ok(mesh)
}

/// The points of the linear line elements (`Lin2`) of the curves in physical group `group`
/// of a Gmsh MSH 4.1 file (each node once, in file order): a crack or an interface drawn
/// as a physical line. An error when the group has no line element.
pub fn read_physical_line(bytes: &[u8], group: i32) -> Result<Vec<[f64; 2]>> {
    let msh = parse(bytes)?;
    let (nodes, index_of) = nodes_of(&msh)?;
    let mut seen = std::collections::HashSet::new();
    let mut points = Vec::new();
    for [a, b] in line_ends(&msh, group, &[mshio::ElementType::Lin2])? {
        for tag in [a, b] {
            let i = node_index(&index_of, group, tag)?;
            if seen.insert(tag) {
                points.push(nodes[i]);
            }
        }
    }
    Ok(points)
}

/// The line elements (2- or 3-node: `Lin2`, `Lin3`) of the curves in physical group
/// `group` as pairs of end nodes, indexed as [`read_quads`] indexes them: the element sides
/// a crack drawn as a physical line runs along. An error when the group has none.
pub fn read_line_sides(bytes: &[u8], group: i32) -> Result<Vec<[usize; 2]>> {
    use mshio::ElementType::{Lin2, Lin3};
    let msh = parse(bytes)?;
    let (_, index_of) = nodes_of(&msh)?;
    line_ends(&msh, group, &[Lin2, Lin3])?
        .into_iter()
        .map(|[a, b]| {
            Ok([
                node_index(&index_of, group, a)?,
                node_index(&index_of, group, b)?,
            ])
        })
        .collect()
}

/// The end node tags of the line elements of `kinds` on the curves of physical group
/// `group`, in file order; an error naming the group when there are none.
fn line_ends(msh: &Msh, group: i32, kinds: &[mshio::ElementType]) -> Result<Vec<[u64; 2]>> {
    let curves: Vec<i32> = msh
        .data
        .entities
        .as_ref()
        .map(|e| {
            e.curves
                .iter()
                .filter(|c| c.physical_tags.contains(&group))
                .map(|c| c.tag)
                .collect()
        })
        .unwrap_or_default();
    let ends: Vec<[u64; 2]> = msh
        .data
        .elements
        .iter()
        .flat_map(|e| &e.element_blocks)
        .filter(|b| kinds.contains(&b.element_type) && curves.contains(&b.entity_tag))
        .flat_map(|b| &b.elements)
        .filter(|e| e.nodes.len() >= 2)
        .map(|e| [e.nodes[0], e.nodes[1]])
        .collect();
    if ends.is_empty() {
        return Err(Error::Mesh(format!(
            "physical group {group} has no line elements ({}) in the MSH file",
            kinds
                .iter()
                .map(|k| format!("{k:?}"))
                .collect::<Vec<_>>()
                .join(" or ")
        )));
    }
    Ok(ends)
}

/// The index of node `tag`, which a line element of `group` refers to.
fn node_index(index_of: &HashMap<u64, usize>, group: i32, tag: u64) -> Result<usize> {
    index_of.get(&tag).copied().ok_or_else(|| {
        Error::Mesh(format!(
            "a line element of physical group {group} refers to node {tag}, which is not in $Nodes"
        ))
    })
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

    fn disk(name: &str) -> Vec<u8> {
        let path = format!("{}/tests/scripts/{name}", env!("CARGO_MANIFEST_DIR"));
        std::fs::read(path).expect("tests/scripts/gmsh_quads.py writes it")
    }

    /// The disk written by tests/scripts/gmsh_quads.py: 57 quadrilaterals of 9 nodes (4 of
    /// 4), each with the material and angle of its group, every boundary node on the circle.
    #[test]
    fn reads_curved_and_straight_quadrilaterals() {
        let physical = HashMap::from([(1, (0, 0.25))]);
        for (name, count) in [("gmsh_disk_q9.msh", 9), ("gmsh_disk_q4.msh", 4)] {
            let mesh = read_quads(&disk(name), &physical).unwrap();
            assert_eq!(mesh.elements.len(), 57, "{name}");
            assert!(mesh
                .elements
                .iter()
                .all(|q| q.nodes.len() == count && q.material == 0 && q.angle_rad == 0.25));
            let radius = mesh
                .nodes
                .iter()
                .map(|x| x[0].hypot(x[1]))
                .fold(0.0, f64::max);
            assert!((radius - 2e-3).abs() < 1e-12, "{name}: {radius}");
        }
    }

    /// Triangles, an unmapped group and a mix of 4 and 9 nodes are refused, naming the
    /// surface.
    #[test]
    fn quadrilateral_meshes_refuse_other_elements() {
        let e = read_quads(
            SQUARE.as_bytes(),
            &HashMap::from([(7, (0, 0.0)), (8, (0, 0.0))]),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("surface 1 holds Tri3") && e.contains("RecombineAll"),
            "{e}"
        );
        let e = read_quads(&disk("gmsh_disk_q9.msh"), &HashMap::new())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("surface 1 (physical groups [1]) has no material"),
            "{e}"
        );
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
