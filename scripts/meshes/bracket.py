"""Writes bracket.msh (read by scripts/bracket.rhai): the section of a laminated L-bracket, the
curved specimen of composite structures (its corner is where delaminations start), as curved
(9-node) quadrilaterals in a structured grid.

The laminate is 2 mm thick: three 0.6 mm plies of 0/90 fabric with 0.1 mm epoxy interlayers
between them. The two legs are 10 mm long and meet in a corner of inner radius 3 mm (outer
5 mm) round the point (5, 5) mm; the outer faces are the bounding box's bottom (y = 0) and
left (x = 0) sides, the legs' cut ends its right (x = 15 mm) and top (y = 15 mm) sides. A
delamination runs along the outer face of the inner epoxy interlayer over the middle 40
degrees of the corner (a curved crack, tips inside).

Elements: 0.3 mm along the legs, 30 round the corner (about 0.2 mm), two rows per ply and one
per interlayer (8 through the thickness); 784 elements.

Physical surfaces: 1 the epoxy interlayers, 2 the plies of the horizontal leg, 3 those of the
vertical leg, 4 those of the corner (the scene turns each group's material axes along its
own part: 0 and 90 degrees in the legs, round the corner's centre in the corner). Physical
lines: 5 the delamination, 6 the horizontal leg's cut end (on the bounding box's right side). Needs the `gmsh` Python package: python3 bracket.py (from this
directory)."""
import math

import gmsh

INNER, OUTER, LEG = 3e-3, 5e-3, 10e-3
CENTRE = (OUTER, OUTER)
# through-thickness interfaces from the outer face in, and the rows of elements in each layer
LAYERS = [(0.6e-3, 2, "ply"), (0.1e-3, 1, "epoxy"), (0.6e-3, 2, "ply"), (0.1e-3, 1, "epoxy"), (0.6e-3, 2, "ply")]
CRACK_LAYER = 3  # the delamination lies on the outer face of this layer (the inner interlayer)
# the corner's angular blocks (degrees from +x round the centre): before, along and after
# the delamination, and the elements in each
ARCS = [(180.0, 205.0, 8), (205.0, 245.0, 14), (245.0, 270.0, 8)]
ALONG_LEG = 34

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("bracket")
geo = gmsh.model.geo
centre = geo.addPoint(*CENTRE, 0)
depths = [0.0]
for thickness, _, _ in LAYERS:
    depths.append(depths[-1] + thickness)
radii = [OUTER - d for d in depths]


def polar(r, degrees):
    a = math.radians(degrees)
    return (CENTRE[0] + r * math.cos(a), CENTRE[1] + r * math.sin(a))


# points on every radius at every block boundary angle, and at the legs' ends
angles = [ARCS[0][0]] + [b for _, b, _ in ARCS]
point = {}
for k, r in enumerate(radii):
    for a in angles:
        point[(k, a)] = geo.addPoint(*polar(r, a), 0)
    # the horizontal leg's end (x = 15 mm) and the vertical leg's (y = 15 mm)
    point[(k, "h")] = geo.addPoint(OUTER + LEG, OUTER - r, 0)
    point[(k, "v")] = geo.addPoint(OUTER - r, OUTER + LEG, 0)

line_cache = {}


def line(a, b, arc=False):
    key = (a, b, arc)
    if key not in line_cache:
        line_cache[key] = geo.addCircleArc(a, centre, b) if arc else geo.addLine(a, b)
        line_cache[(b, a, arc)] = -line_cache[key]
    return line_cache[key]


blocks = []  # (surface, layer kind, part)
crack_curves = []
for k, (_, rows, kind) in enumerate(LAYERS):
    outer_r, inner_r = k, k + 1
    # the corner's blocks, then the legs (the horizontal leg starts at 270 degrees, the
    # vertical one at 180)
    for a0, a1, count in ARCS:
        outer = line(point[(outer_r, a0)], point[(outer_r, a1)], arc=True)
        inner = line(point[(inner_r, a0)], point[(inner_r, a1)], arc=True)
        loop = [outer, line(point[(outer_r, a1)], point[(inner_r, a1)]), -inner,
                line(point[(inner_r, a0)], point[(outer_r, a0)])]
        surface = geo.addPlaneSurface([geo.addCurveLoop(loop)])
        blocks.append((surface, kind, "corner", (abs(outer), abs(inner)), count, rows))
        if k == CRACK_LAYER and a0 == ARCS[1][0]:
            crack_curves.append(abs(outer))
    for end, start_angle in (("h", 270.0), ("v", 180.0)):
        outer = line(point[(outer_r, start_angle)], point[(outer_r, end)])
        inner = line(point[(inner_r, start_angle)], point[(inner_r, end)])
        loop = [outer, line(point[(outer_r, end)], point[(inner_r, end)]), -inner,
                line(point[(inner_r, start_angle)], point[(outer_r, start_angle)])]
        surface = geo.addPlaneSurface([geo.addCurveLoop(loop)])
        blocks.append((surface, kind, end, (abs(outer), abs(inner)), ALONG_LEG, rows))
geo.synchronize()
for surface, _, _, along, count, rows in blocks:
    for curve in along:
        gmsh.model.mesh.setTransfiniteCurve(curve, count + 1)
    for _, c in gmsh.model.getBoundary([(2, surface)], oriented=False):
        if c not in along:
            gmsh.model.mesh.setTransfiniteCurve(c, rows + 1)
    gmsh.model.mesh.setTransfiniteSurface(surface)
    gmsh.model.mesh.setRecombine(2, surface)
group = lambda kind, part: [s for s, k, p, *_ in blocks if k == kind and (part is None or p == part)]
gmsh.model.addPhysicalGroup(2, group("epoxy", None), 1)
gmsh.model.addPhysicalGroup(2, group("ply", "h"), 2)
gmsh.model.addPhysicalGroup(2, group("ply", "v"), 3)
gmsh.model.addPhysicalGroup(2, group("ply", "corner"), 4)
gmsh.model.addPhysicalGroup(1, crack_curves, 5)
ends = [c for s, _, part, *_ in blocks if part == "h"
        for _, c in gmsh.model.getBoundary([(2, s)], oriented=False)
        if gmsh.model.getBoundingBox(1, abs(c))[0] > OUTER + LEG - 1e-9]
gmsh.model.addPhysicalGroup(1, sorted(set(abs(c) for c in ends)), 6)
gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.model.mesh.generate(2)
gmsh.model.mesh.setOrder(2)
types, tags, _ = gmsh.model.mesh.getElements(2)
print("bracket.msh:", {gmsh.model.mesh.getElementProperties(t)[0]: len(k) for t, k in zip(types, tags)})
gmsh.write("bracket.msh")
gmsh.finalize()
