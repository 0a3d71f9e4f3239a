"""Writes gmsh_plate.msh (used by gmsh_scene.rhai): a 4 mm x 2 mm plate of two layers
(physical surfaces 1: lower 1.2 mm of 0/90 fabric, 2: upper 0.8 mm of epoxy), unstructured
T3 elements of about 0.2 mm, and a horizontal crack from x = 1.5 to 2.5 mm at y = 0.6 mm
embedded as physical line 3. Needs the `gmsh` Python package: python3 gmsh_plate.py"""
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("plate")
occ = gmsh.model.occ
lower = occ.addRectangle(0, 0, 0, 4e-3, 1.2e-3)
upper = occ.addRectangle(0, 1.2e-3, 0, 4e-3, 0.8e-3)
crack = occ.addLine(occ.addPoint(1.5e-3, 0.6e-3, 0), occ.addPoint(2.5e-3, 0.6e-3, 0))
occ.fragment([(2, lower), (2, upper)], [])
occ.synchronize()
gmsh.model.mesh.embed(1, [crack], 2, lower)
gmsh.model.addPhysicalGroup(2, [lower], 1)
gmsh.model.addPhysicalGroup(2, [upper], 2)
gmsh.model.addPhysicalGroup(1, [crack], 3)
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2e-3)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.model.mesh.generate(2)
gmsh.write("gmsh_plate.msh")
gmsh.finalize()
