#!/usr/bin/env python3
"""Writes the committed quadratic test meshes with the real tools users have.

Run in a venv with `pip install gmsh meshio numpy` (gmsh 4.15.2, meshio 5.3.5 made the
committed files): `python meshes/make_quadratic_meshes.py` from the repository root.
Every .vtu is meshio's conversion of the .msh beside it (meshio reorders Gmsh's nodes
into VTK's order: tests/io_mesh_files.rs checks that signorini's Gmsh reader agrees).

  quadratic/ball_tet10.msh   Gmsh 4.1 ASCII, tet10 ball R = 0.05 m (mid-side nodes on the
                             sphere), groups "ball" (3) and "surface" (2)
  quadratic/ball_tet10.vtu   its meshio .vtu
  quadratic/block_hex20.msh  Gmsh 2.2 ASCII, hex20 box 0.1 x 0.1 x 0.05 m, 8 cells
                             (transfinite, order 2 incomplete), group "block" (3)
  quadratic/block_hex20.vtu  its meshio .vtu
  quadratic/block_hex27.msh  Gmsh 4.1 binary, the same box in hex27 (order 2, complete)
  quadratic/block_hex27.vtu  its meshio .vtu
  quadratic/disk_tri6.msh    Gmsh 2.2 ASCII, tri6 disk R = 0.05 m, groups "disk" and "rim"
  quadratic/disk_quad8.msh   Gmsh 4.1 ASCII, quad8 disk (recombined, order 2 incomplete)
  quadratic/disk_quad9.msh   Gmsh 4.1 ASCII, quad9 disk (recombined, order 2 complete)
  quadratic/disk_quad9.vtu   its meshio .vtu
  quadratic/hertz_ball_quad9_8e-5.msh   the axisymmetric Hertz ball's half section
                             (meshes/hertz_ball.msh's geometry and groups) in quad9, graded
                             from 8e-5 m at the pole to 1e-3 m beyond 6 mm
  quadratic/hertz_ball_quad9_1.6e-4.msh the same from 1.6e-4 m to 2e-3 m
  quadratic/hertz_ball_quad8_8e-5.msh   the 8e-5 m one in quad8
"""
import os
import sys

import gmsh
import meshio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_meshes import hertz_ball  # noqa: E402  (the Hertz ball's geometry, one place)

out = "meshes/quadratic/"


def write(name, version, binary=False):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 1 if binary else 0)
    gmsh.write(out + name)


def vtu(name):
    m = meshio.read(out + name + ".msh")
    top = max(c.dim for c in m.cells)
    cells = [c for c in m.cells if c.dim == top]
    meshio.Mesh(m.points, cells).write(out + name + ".vtu")


gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)

# tet10 ball
gmsh.model.add("ball")
v = gmsh.model.occ.addSphere(0, 0, 0.05, 0.05)
gmsh.model.occ.synchronize()
gmsh.model.addPhysicalGroup(3, [v], name="ball")
s = [t for (d, t) in gmsh.model.getBoundary([(3, v)], oriented=False)]
gmsh.model.addPhysicalGroup(2, s, name="surface")
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.03)
gmsh.model.mesh.generate(3)
gmsh.model.mesh.setOrder(2)
write("ball_tet10.msh", 4.1)
gmsh.model.remove()
gmsh.option.setNumber("Mesh.MeshSizeMax", 1e22)

# hex20 and hex27 blocks
for name, incomplete, version, binary in [
    ("block_hex20.msh", 1, 2.2, False),
    ("block_hex27.msh", 0, 4.1, True),
]:
    gmsh.model.add("block")
    b = gmsh.model.occ.addBox(0, 0, 0, 0.1, 0.1, 0.05)
    gmsh.model.occ.synchronize()
    for d, t in gmsh.model.getEntities(1):
        bb = gmsh.model.getBoundingBox(d, t)
        gmsh.model.mesh.setTransfiniteCurve(t, 3)  # two cells along every edge
    for d, t in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(t)
        gmsh.model.mesh.setRecombine(d, t)
    gmsh.model.mesh.setTransfiniteVolume(b)
    gmsh.model.addPhysicalGroup(3, [b], name="block")
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    write(name, version, binary)
    gmsh.model.remove()

# tri6, quad8 and quad9 disks
for name, recombine, incomplete, version in [
    ("disk_tri6.msh", 0, 0, 2.2),
    ("disk_quad8.msh", 1, 1, 4.1),
    ("disk_quad9.msh", 1, 0, 4.1),
]:
    gmsh.model.add("disk")
    d = gmsh.model.occ.addDisk(0, 0.05, 0, 0.05, 0.05)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [d], name="disk")
    c = [t for (dd, t) in gmsh.model.getBoundary([(2, d)], oriented=False)]
    gmsh.model.addPhysicalGroup(1, c, name="rim")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.015)
    gmsh.option.setNumber("Mesh.RecombineAll", recombine)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(2)
    write(name, version)
    gmsh.model.remove()
# the Hertz ball's half section in quadratic quadrilaterals (docs/scenes.md's table):
# make_meshes.py's geometry and grading, second order
gmsh.option.setNumber("Mesh.MeshSizeMax", 1e22)
for name, sizes, incomplete in [
    ("hertz_ball_quad9_8e-5.msh", (8e-5, 1e-3, 1e-3, 6e-3), 0),
    ("hertz_ball_quad9_1.6e-4.msh", (1.6e-4, 2e-3, 1e-3, 6e-3), 0),
    ("hertz_ball_quad8_8e-5.msh", (8e-5, 1e-3, 1e-3, 6e-3), 1),
]:
    hertz_ball(path=out + name, sizes=sizes, order=2, incomplete=incomplete)
gmsh.finalize()

for name in ["ball_tet10", "block_hex20", "block_hex27", "disk_quad9"]:
    vtu(name)
