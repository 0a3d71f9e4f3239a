"""Writes the quadrilateral meshes the spectral-element tests read (needs the `gmsh` Python
package: python3 gmsh_quads.py):

- gmsh_disk_q9.msh: a disk of radius 2 mm, unstructured 9-node (curved) quadrilaterals of
  about 0.5 mm, physical surface 1 (the torsional-mode check of the unstructured spectral
  elements, src/mesh/gmsh.rs);
- gmsh_disk_q4.msh: the same disk with 4-node (straight-sided) quadrilaterals."""
import gmsh


def disk(name, second_order):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    occ = gmsh.model.occ
    surface = occ.addDisk(0, 0, 0, 2e-3, 2e-3)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], 1)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5e-3)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(2)
    if second_order:
        gmsh.model.mesh.setOrder(2)
    gmsh.write(name + ".msh")
    gmsh.finalize()


disk("gmsh_disk_q9", True)
disk("gmsh_disk_q4", False)
