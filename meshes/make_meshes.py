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
  hertz_ball.msh    Gmsh 4.1 ASCII, the axisymmetric half section (x = r ≥ 0, y = axis) of a
                    ball R = 0.01 m resting on y = 0, quad4 (recombined), graded from
                    4e-5 m at the south pole (a tenth of the Hertz contact radius at
                    1 m/s, 4.2e-4 m) to 1e-3 m beyond 6 mm; groups "ball" (2), "axis" and
                    "surface" (1)
  hertz_ball_lower.msh  its mirror image below y = 0 (north pole at the origin), the
                    second ball of meshes/hertz_spheres.toml
  hertz_plate.msh   Gmsh 4.1 ASCII, the axisymmetric section of a thick plate under
                    the ball (r ≤ 4 cm, 4 cm thick, top at y = 0), quad4 graded from
                    4e-5 m at the origin to 2e-3 m; groups "plate" (2), "top", "bottom" (1)
"""
import gmsh
import meshio
import numpy as np



def sized_from_origin(sizes):
    """Makes the current model's mesh size grow with the distance from the origin:
    `sizes` = (size at the origin, size far away, distance where the grading starts,
    distance where it ends); the boundary's and the points' own sizes switched off."""
    origin = gmsh.model.occ.addPoint(0, 0, 0)
    gmsh.model.occ.synchronize()
    f = gmsh.model.mesh.field
    f.add("Distance", 1)
    f.setNumbers(1, "PointsList", [origin])
    f.add("Threshold", 2)
    f.setNumber(2, "InField", 1)
    for k, v in zip(["SizeMin", "SizeMax", "DistMin", "DistMax"], sizes):
        f.setNumber(2, k, v)
    f.setAsBackgroundMesh(2)
    for k in ["Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
              "Mesh.MeshSizeFromCurvature"]:
        gmsh.option.setNumber(k, 0)


def graded_quads(sizes, path, order=1, incomplete=0):
    """Meshes the current 2-D model with quad4 (recombined) graded from the origin:
    `sizes` = (size at the origin, size far away, distance where the grading starts,
    distance where it ends); with `order` 2, quad9 (quad8 with `incomplete` 1) whose
    mid-side nodes lie on the curves; writes Gmsh 4.1 ASCII to `path` and removes the
    model."""
    sized_from_origin(sizes)
    gmsh.option.setNumber("Mesh.RecombineAll", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 8)
    gmsh.model.mesh.generate(2)
    if order == 2:
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
        gmsh.model.mesh.setOrder(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(path)
    gmsh.model.remove()
    for k in ["Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
              "Mesh.MeshSizeFromCurvature"]:
        gmsh.option.setNumber(k, 1)
    gmsh.option.setNumber("Mesh.RecombineAll", 0)


def hertz_ball(lower=False, path=None, sizes=(4e-5, 1e-3, 1e-3, 6e-3), order=1, incomplete=0):
    r = 0.01
    gmsh.model.add("hertz")
    occ = gmsh.model.occ
    # the ball above y = 0 (south pole at the origin), or with `lower` its mirror image
    # below (north pole at the origin)
    s = -1.0 if lower else 1.0
    d = occ.addDisk(0, s * r, 0, r, r)
    b = occ.addRectangle(0, -2 * r if lower else 0, 0, r, 2 * r)
    occ.intersect([(2, d)], [(2, b)])
    occ.synchronize()
    axis, arc = [], []
    for dim, t in gmsh.model.getEntities(1):
        xmax = gmsh.model.getBoundingBox(dim, t)[3]
        (axis if xmax < 1e-6 else arc).append(t)
    gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], name="ball")
    gmsh.model.addPhysicalGroup(1, axis, name="axis")
    gmsh.model.addPhysicalGroup(1, arc, name="surface")
    if path is None:
        path = "meshes/hertz_ball_lower.msh" if lower else "meshes/hertz_ball.msh"
    graded_quads(sizes, path, order, incomplete)


def hertz_plate():
    """The axisymmetric section of a thick steel plate under the ball: r in [0, 4 cm],
    y in [-4 cm, 0], quad4 graded from 4e-5 m at the origin to 2e-3 m beyond 1 cm."""
    w = 0.04
    gmsh.model.add("plate")
    occ = gmsh.model.occ
    occ.addRectangle(0, -w, 0, w, w)
    occ.synchronize()
    top, bottom = [], []
    for dim, t in gmsh.model.getEntities(1):
        b = gmsh.model.getBoundingBox(dim, t)
        if b[1] > -1e-6 and b[4] > -1e-6:
            top.append(t)
        elif b[1] < -w + 1e-6 and b[4] < -w + 1e-6:
            bottom.append(t)
    gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], name="plate")
    gmsh.model.addPhysicalGroup(1, top, name="top")
    gmsh.model.addPhysicalGroup(1, bottom, name="bottom")
    graded_quads((4e-5, 2e-3, 1e-3, 1e-2), "meshes/hertz_plate.msh")


def main():
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

    # axisymmetric Hertz ball (tests/analytic_hertz_impact.rs)
    hertz_ball()
    hertz_ball(lower=True)
    hertz_plate()
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


if __name__ == "__main__":
    main()
