"""Writes the quadrilateral meshes the spectral-element tests read (needs the `gmsh` Python
package: python3 gmsh_quads.py):

- gmsh_disk_q9.msh: a disk of radius 2 mm, unstructured 9-node (curved) quadrilaterals of
  about 0.5 mm, physical surface 1 (the torsional-mode check of the unstructured spectral
  elements, src/mesh/gmsh.rs);
- gmsh_disk_q4.msh: the same disk with 4-node (straight-sided) quadrilaterals;
- gmsh_quad_plate.msh, gmsh_quad_plate_crack.msh and gmsh_quad_plate_unstructured.msh: a
  two-layer plate (below);
- gmsh_hole.msh: a square with a circular hole;
- gmsh_quad_crack.msh: a plate with an inclined crack;
- gmsh_annulus.msh: an annulus round a cavity, its two circles physical lines."""
import gmsh
import math


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


def layered_plate(name, crack):
    """gmsh_quad_plate.msh: the 4 mm x 2 mm plate of gmsh_plate.msh without its crack (physical
    surfaces 1: lower 1.2 mm of 0/90 fabric, 2: upper 0.8 mm of epoxy) as a transfinite grid
    of 4-node quadrilaterals, 0.5 mm along x and 0.4 mm across: the elements a layered
    spectral-element scene of those sizes cuts (tests/unstructured_scene.rs compares them).
    gmsh_quad_plate_crack.msh: the same with the interface from x = 1 to 3 mm as physical
    line 3, the crack of a layered scene at depth 0.8 mm, 2 mm long, centred."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    occ = gmsh.model.occ
    lower = occ.addRectangle(0, 0, 0, 4e-3, 1.2e-3)
    upper = occ.addRectangle(0, 1.2e-3, 0, 4e-3, 0.8e-3)
    tools = []
    if crack:
        tools = [(1, occ.addLine(occ.addPoint(1e-3, 1.2e-3, 0), occ.addPoint(3e-3, 1.2e-3, 0)))]
    occ.fragment([(2, lower), (2, upper)], tools)
    occ.synchronize()
    for dim, curve in gmsh.model.getEntities(1):
        (x0, y0, _, x1, y1, _) = gmsh.model.getBoundingBox(dim, curve)
        if abs(y1 - y0) < 1e-5:
            points = round((x1 - x0) / 0.5e-3) + 1
        elif y1 <= 1.2e-3 + 1e-5:
            points = 4
        else:
            points = 3
        gmsh.model.mesh.setTransfiniteCurve(curve, points)
    surfaces = [s for _, s in gmsh.model.getEntities(2)]
    for surface in surfaces:
        # the corners of the rectangle (the crack's tips are points on its side, not
        # corners; Gmsh pads bounding boxes by 1e-7)
        (x0, y0, _, x1, y1, _) = gmsh.model.getBoundingBox(2, surface)
        points = [p for _, p in gmsh.model.getBoundary([(2, surface)], recursive=True)]
        corners = [p for p in points
                   if min(abs(gmsh.model.getValue(0, p, [])[0] - x) for x in (x0, x1)) < 1e-6
                   and min(abs(gmsh.model.getValue(0, p, [])[1] - y) for y in (y0, y1)) < 1e-6]
        gmsh.model.mesh.setTransfiniteSurface(surface, "Left", corners)
        gmsh.model.mesh.setRecombine(2, surface)
    below = [s for s in surfaces if gmsh.model.getBoundingBox(2, s)[4] < 1.2e-3 + 1e-5]
    gmsh.model.addPhysicalGroup(2, below, 1)
    gmsh.model.addPhysicalGroup(2, [s for s in surfaces if s not in below], 2)
    if crack:
        inside = [c for _, c in gmsh.model.getEntities(1)
                  if abs(gmsh.model.getBoundingBox(1, c)[1] - 1.2e-3) < 1e-6
                  and abs(gmsh.model.getBoundingBox(1, c)[4] - 1.2e-3) < 1e-6
                  and gmsh.model.getBoundingBox(1, c)[0] > 0.5e-3
                  and gmsh.model.getBoundingBox(1, c)[3] < 3.5e-3]
        gmsh.model.addPhysicalGroup(1, inside, 3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    gmsh.write(name + ".msh")
    gmsh.finalize()


layered_plate("gmsh_quad_plate", False)
layered_plate("gmsh_quad_plate_crack", True)


def write_curved_quads(name):
    """Meshes the model as 9-node quadrilaterals (frontal-Delaunay for quads, recombined),
    writes it to `name` (MSH 4.1) with its element counts printed, and closes Gmsh."""
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(2)
    types, tags, _ = gmsh.model.mesh.getElements(2)
    counts = {gmsh.model.mesh.getElementProperties(t)[0]: len(k) for t, k in zip(types, tags)}
    print(name + ":", counts)
    gmsh.write(name)
    gmsh.finalize()


def unstructured_plate():
    """gmsh_quad_plate_unstructured.msh: the same two-layer plate as unstructured 9-node
    quadrilaterals of about 0.25 mm (0.5 mm elements each split into 4) (tests/scene_edges.rs runs the exact plane wave through
    it)."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("quad_plate_unstructured")
    occ = gmsh.model.occ
    lower = occ.addRectangle(0, 0, 0, 4e-3, 1.2e-3)
    upper = occ.addRectangle(0, 1.2e-3, 0, 4e-3, 0.8e-3)
    occ.fragment([(2, lower), (2, upper)], [])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [lower], 1)
    gmsh.model.addPhysicalGroup(2, [upper], 2)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5e-3)
    # recombination alone leaves a few triangles here: split every element into quads
    gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)
    write_curved_quads("gmsh_quad_plate_unstructured.msh")


unstructured_plate()


def hole_plate():
    """gmsh_hole.msh: a 36 mm x 36 mm square of one material (physical surface 1) with a
    circular hole of radius 1 mm at its centre, 9-node quadrilaterals (curved on the hole)
    from about 0.4 mm on the hole to 1.2 mm from 8 mm away (tests/hole_scattering.rs
    scatters a plane P wave off the hole and compares with the exact series)."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("hole_plate")
    occ = gmsh.model.occ
    square = occ.addRectangle(0, 0, 0, 36e-3, 36e-3)
    hole = occ.addDisk(18e-3, 18e-3, 0, 1e-3, 1e-3)
    occ.cut([(2, square)], [(2, hole)])
    occ.synchronize()
    (_, surface), = gmsh.model.getEntities(2)
    gmsh.model.addPhysicalGroup(2, [surface], 1)
    circle = [c for _, c in gmsh.model.getEntities(1)
              if gmsh.model.getBoundingBox(1, c)[3] - gmsh.model.getBoundingBox(1, c)[0] < 3e-3]
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "CurvesList", circle)
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", 0.4e-3)
    field.setNumber(threshold, "SizeMax", 1.2e-3)
    field.setNumber(threshold, "DistMin", 0.0)
    field.setNumber(threshold, "DistMax", 8e-3)
    field.setAsBackgroundMesh(threshold)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    write_curved_quads("gmsh_hole.msh")


hole_plate()


def cracked_plate():
    """gmsh_quad_crack.msh: a 4 mm x 2 mm plate (physical surface 1) of 9-node
    quadrilaterals of about 0.2 mm, conforming to an inclined crack from (1.5, 0.7) to
    (2.5, 1.3) mm, tips inside the plate (physical line 5) (tests/unstructured_crack.rs runs a
    pulse through it)."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("quad_crack")
    occ = gmsh.model.occ
    plate = occ.addRectangle(0, 0, 0, 4e-3, 2e-3)
    a = occ.addPoint(1.5e-3, 0.7e-3, 0)
    b = occ.addPoint(2.5e-3, 1.3e-3, 0)
    crack = occ.addLine(a, b)
    occ.fragment([(2, plate)], [(1, crack)])
    occ.synchronize()
    (_, surface), = gmsh.model.getEntities(2)
    gmsh.model.addPhysicalGroup(2, [surface], 1)
    inside = [c for _, c in gmsh.model.getEntities(1)
              if gmsh.model.getBoundingBox(1, c)[0] > 1e-3 and gmsh.model.getBoundingBox(1, c)[3] < 3e-3]
    gmsh.model.addPhysicalGroup(1, inside, 5)
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2e-3)
    write_curved_quads("gmsh_quad_crack.msh")


cracked_plate()


def annulus():
    """gmsh_annulus.msh: an annulus of one material (physical surface 1) round the origin,
    from a cavity of radius 1 mm (physical line 2) to an outer circle of radius 10 mm
    (physical line 3), as a structured grid of 9-node quadrilaterals (curved: 48 round,
    18 across, 0.5 mm) in four quarter sectors (tests/unstructured_absorbing.rs radiates a
    cylindrical wave from the pressurised cavity through the absorbing outer circle)."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("annulus")
    geo = gmsh.model.geo
    centre = geo.addPoint(0, 0, 0)
    corners = [(math.cos(k * math.pi / 2), math.sin(k * math.pi / 2)) for k in range(4)]
    inner = [geo.addPoint(1e-3 * c, 1e-3 * s, 0) for c, s in corners]
    outer = [geo.addPoint(10e-3 * c, 10e-3 * s, 0) for c, s in corners]
    radial = [geo.addLine(inner[k], outer[k]) for k in range(4)]
    inner_arcs = [geo.addCircleArc(inner[k], centre, inner[(k + 1) % 4]) for k in range(4)]
    outer_arcs = [geo.addCircleArc(outer[k], centre, outer[(k + 1) % 4]) for k in range(4)]
    surfaces = []
    for k in range(4):
        loop = geo.addCurveLoop([radial[k], outer_arcs[k], -radial[(k + 1) % 4], -inner_arcs[k]])
        surfaces.append(geo.addPlaneSurface([loop]))
    geo.synchronize()
    for curve in radial:
        gmsh.model.mesh.setTransfiniteCurve(curve, 19)
    for curve in inner_arcs + outer_arcs:
        gmsh.model.mesh.setTransfiniteCurve(curve, 13)
    for surface in surfaces:
        gmsh.model.mesh.setTransfiniteSurface(surface)
        gmsh.model.mesh.setRecombine(2, surface)
    gmsh.model.addPhysicalGroup(2, surfaces, 1)
    gmsh.model.addPhysicalGroup(1, inner_arcs, 2)
    gmsh.model.addPhysicalGroup(1, outer_arcs, 3)
    write_curved_quads("gmsh_annulus.msh")


annulus()
