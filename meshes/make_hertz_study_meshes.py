#!/usr/bin/env python3
"""Writes the meshes of the Hertz ball's speed study (docs/scenes.md, "Why the ball stays
about 2 % off Hertz at 1 m/s") into a folder of your choice; they are not committed
(1.3 MB). Run in a venv with `pip install gmsh` (gmsh 4.15.2 made the figures):

    python meshes/make_hertz_study_meshes.py DIR

  DIR/hertz_ball_quad9_4e-5.msh  the axisymmetric ball's half section (meshes/hertz_ball.msh's
                                 geometry and groups) in quad9, graded from 4e-5 m at the pole
                                 to 1e-3 m beyond 6 mm (for 10 and 1 m/s)
  DIR/hertz_ball_quad9_2e-5.msh  from 2e-5 m to 5e-4 m (0.1 m/s: contact radius 1.7e-4 m)
  DIR/hertz_ball_quad9_1e-5.msh  from 1e-5 m to 5e-4 m, the grading from 3e-4 m (0.01 m/s:
                                 contact radius 6.6e-5 m)
  DIR/hertz_quarter_ball_tet10_4e-5.msh  a quarter of the 3-D ball (x >= 0, y >= 0; south
                                 pole at the origin) in tet10, graded from 4e-5 m at the pole
                                 (from 4e-4 m) to 1e-3 m beyond 6 mm; groups "ball", "xsym",
                                 "ysym" (the symmetry planes) and "surface"
"""
import os
import sys

import gmsh

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_meshes import hertz_ball, sized_from_origin  # noqa: E402  (one place each)

if len(sys.argv) != 2:
    sys.exit(__doc__)
out = sys.argv[1]
os.makedirs(out, exist_ok=True)
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.option.setNumber("Mesh.MeshSizeMax", 1e22)
for name, sizes in [
    ("hertz_ball_quad9_4e-5.msh", (4e-5, 1e-3, 1e-3, 6e-3)),
    ("hertz_ball_quad9_2e-5.msh", (2e-5, 5e-4, 5e-4, 6e-3)),
    ("hertz_ball_quad9_1e-5.msh", (1e-5, 5e-4, 3e-4, 6e-3)),
]:
    hertz_ball(path=os.path.join(out, name), sizes=sizes, order=2)


def quarter_ball(path, pole, far):
    r = 0.01
    gmsh.model.add("quarter")
    occ = gmsh.model.occ
    s = occ.addSphere(0, 0, r, r)
    b = occ.addBox(0, 0, 0, r, r, 2 * r)
    occ.intersect([(3, s)], [(3, b)])
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], name="ball")
    xs, ys, sphere = [], [], []
    for d, t in gmsh.model.getEntities(2):
        box = gmsh.model.getBoundingBox(d, t)
        if box[3] - box[0] < 1e-6:
            xs.append(t)
        elif box[4] - box[1] < 1e-6:
            ys.append(t)
        else:
            sphere.append(t)
    gmsh.model.addPhysicalGroup(2, xs, name="xsym")
    gmsh.model.addPhysicalGroup(2, ys, name="ysym")
    gmsh.model.addPhysicalGroup(2, sphere, name="surface")
    sized_from_origin((pole, far, 10 * pole, 6e-3))
    # gmsh's defaults, which the quadrilateral sections above changed
    gmsh.option.setNumber("Mesh.RecombineAll", 0)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(path)
    gmsh.model.remove()


quarter_ball(os.path.join(out, "hertz_quarter_ball_tet10_4e-5.msh"), 4e-5, 1e-3)
gmsh.finalize()
