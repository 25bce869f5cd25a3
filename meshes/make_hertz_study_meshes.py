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
"""
import os
import sys

import gmsh

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_meshes import hertz_ball  # noqa: E402  (the Hertz ball's geometry, one place)

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
gmsh.finalize()
