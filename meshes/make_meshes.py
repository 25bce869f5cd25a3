#!/usr/bin/env python3
"""Writes the committed test meshes with the real tools users have.

Run in a venv with `pip install gmsh meshio numpy` (gmsh 4.15.2, meshio 5.3.5 made the
committed files): `python meshes/make_meshes.py` from the repository root.

  ball.msh          Gmsh 4.1 ASCII, tet4 ball R = 0.05 m, groups "ball" (3) and "surface" (2)
  ball_binary.msh   the same mesh, Gmsh 4.1 binary
  disk.msh          Gmsh 2.2 ASCII, tri3 disk R = 0.05 m, groups "disk" (2) and "rim" (1)
  disk_binary.msh   the same mesh, Gmsh 2.2 binary
  plate.vtu         meshio's default .vtu (binary, zlib) of a quad4 plate 0.2 × 0.05 m,
                    point data "bottom" (1 on the y = 0 edge, else 0)
  plate.vtk         the same plate as meshio's default legacy .vtk (5.1, binary)
"""
import gmsh
import meshio
import numpy as np

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)

# ball
gmsh.model.add("ball")
v = gmsh.model.occ.addSphere(0, 0, 0.05, 0.05)
gmsh.model.occ.synchronize()
gmsh.model.addPhysicalGroup(3, [v], name="ball")
s = [t for (d, t) in gmsh.model.getBoundary([(3, v)], oriented=False)]
gmsh.model.addPhysicalGroup(2, s, name="surface")
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.025)
gmsh.model.mesh.generate(3)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.write("meshes/ball.msh")
gmsh.option.setNumber("Mesh.Binary", 1)
gmsh.write("meshes/ball_binary.msh")
gmsh.model.remove()

# disk, Gmsh 2.2
gmsh.model.add("disk")
d = gmsh.model.occ.addDisk(0, 0.05, 0, 0.05, 0.05)
gmsh.model.occ.synchronize()
gmsh.model.addPhysicalGroup(2, [d], name="disk")
c = [t for (dd, t) in gmsh.model.getBoundary([(2, d)], oriented=False)]
gmsh.model.addPhysicalGroup(1, c, name="rim")
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.01)
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.model.mesh.generate(2)
gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
gmsh.write("meshes/disk.msh")
gmsh.option.setNumber("Mesh.Binary", 1)
gmsh.write("meshes/disk_binary.msh")
gmsh.model.remove()
gmsh.finalize()

# plate of quads through meshio
nx, ny = 8, 2
xs, ys = np.linspace(0, 0.2, nx + 1), np.linspace(0, 0.05, ny + 1)
pts = np.array([[x, y, 0.0] for y in ys for x in xs])
quads = np.array([[j * (nx + 1) + i, j * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i + 1,
                   (j + 1) * (nx + 1) + i] for j in range(ny) for i in range(nx)])
bottom = (pts[:, 1] == 0.0).astype(np.int32)
m = meshio.Mesh(pts, [("quad", quads)], point_data={"bottom": bottom})
m.write("meshes/plate.vtu")
m.write("meshes/plate.vtk")
