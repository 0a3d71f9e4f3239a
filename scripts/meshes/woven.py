"""Writes woven.msh (read by scripts/woven.rhai): the cross-section of a woven ply, 8 mm wide
and 1.6 mm thick, as a 2-D model in the report's suggestion (Sec. 6: "a 2-D woven model with
elliptical yarns"): two rows of elliptical yarns (semi-axes 0.45 mm x 0.12 mm, 1 mm apart,
the upper row shifted by half a pitch) in epoxy, meshed by Gmsh as curved (9-node)
quadrilaterals of at most 0.15 mm, 0.04 mm at the yarns, their curved sides untangled by
Gmsh's high-order optimiser (some fold at the yarns' tips otherwise: the spectral elements
refuse inverted elements, naming them).

Physical surfaces: 1 the epoxy matrix, 2 the yarns. Needs the `gmsh` Python package:
python3 woven.py (from this directory)."""
import gmsh

WIDTH, HEIGHT = 8e-3, 1.6e-3
PITCH, A, B = 1e-3, 0.45e-3, 0.12e-3
ROWS = [(0.55e-3, 0.0), (1.05e-3, 0.5e-3)]

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("woven")
occ = gmsh.model.occ
matrix = occ.addRectangle(0, 0, 0, WIDTH, HEIGHT)
yarns = []
for y, shift in ROWS:
    x = PITCH / 2 + shift
    while x + A < WIDTH - 0.1e-3:
        yarns.append(occ.addDisk(x, y, 0, A, B))
        x += PITCH
out, _ = occ.fragment([(2, matrix)], [(2, y) for y in yarns])
occ.synchronize()
yarn_surfaces = [y for y in yarns]
matrix_surfaces = [t for d, t in gmsh.model.getEntities(2) if t not in yarn_surfaces]
gmsh.model.addPhysicalGroup(2, matrix_surfaces, 1)
gmsh.model.addPhysicalGroup(2, yarn_surfaces, 2)
yarn_curves = [c for _, c in gmsh.model.getBoundary([(2, y) for y in yarn_surfaces], oriented=False)]
field = gmsh.model.mesh.field
field.add("Distance", 1)
field.setNumbers(1, "CurvesList", yarn_curves)
field.add("Threshold", 2)
field.setNumber(2, "InField", 1)
field.setNumber(2, "SizeMin", 0.04e-3)
field.setNumber(2, "SizeMax", 0.15e-3)
field.setNumber(2, "DistMin", 0.05e-3)
field.setNumber(2, "DistMax", 0.4e-3)
field.setAsBackgroundMesh(2)
gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
gmsh.option.setNumber("Mesh.RecombineAll", 1)
gmsh.option.setNumber("Mesh.Algorithm", 8)
gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 1)
gmsh.model.mesh.generate(2)
gmsh.model.mesh.setOrder(2)
# curving the sides onto the ellipses can fold thin elements at the yarns' tips: untangle them
gmsh.option.setNumber("Mesh.HighOrderOptimize", 2)
gmsh.model.mesh.optimize("HighOrder")
gmsh.write("woven.msh")
gmsh.finalize()
