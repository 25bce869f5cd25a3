#!/usr/bin/env python3
"""Opens a finished run's outputs with the real clients (VTK and meshio from PyPI) and
fails on any mismatch.

Usage: check_outputs.py OUT_DIR   (a directory written by `signorini bar` or `run`)

Checks, for every frame listed in OUT_DIR/fields.pvd:
  - VTK's vtkXMLUnstructuredGridReader and meshio both open it and agree on the
    points, the cells and every point/cell array (bit for bit);
  - the arrays users rely on are there with the right number of components;
  - the field data TimeValue equals the .pvd timestep and Step is a history step;
  - the contact force at the contact nodes equals the history's impulse / dt (normal
    and, in frictional runs, tangential; those also carry contact_status).
and that the frame count matches summary.json.
"""
import csv
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

POINT = {"displacement": 3, "velocity": 3, "contact_force": 3, "gap": 1, "node_id": 1}
CELL = {"strain": 6, "stress": 6, "von_mises": 1}


def fail(msg):
    print(f"check_outputs: FAIL: {msg}")
    sys.exit(1)


def main(out):
    out = Path(out)
    summary = json.loads((out / "summary.json").read_text())
    dt = summary["dt"]
    with open(out / "history.csv") as f:
        rows = {int(r["step"]): r for r in csv.DictReader(f)}
    frames = [(float(d.get("timestep")), d.get("file"))
              for d in ET.parse(out / "fields.pvd").getroot().iter("DataSet")]
    if len(frames) != summary["frames"]:
        fail(f"{len(frames)} frames in fields.pvd, summary says {summary['frames']}")
    if any(b[0] <= a[0] for a, b in zip(frames, frames[1:])):
        fail("frame times are not increasing")
    ncontact = len([k for k in next(iter(rows.values())) if k.startswith("impulse_")])
    # frictional runs (status_ columns) also carry the contact_status point field
    if any(k.startswith("status_") for k in next(iter(rows.values()))):
        POINT["contact_status"] = 1
    for t, name in frames:
        path = out / name
        r = vtk.vtkXMLUnstructuredGridReader()
        r.SetFileName(str(path))
        r.Update()
        g = r.GetOutput()
        if g.GetNumberOfPoints() == 0:
            fail(f"{name}: VTK read no points")
        m = meshio.read(path)
        if not np.array_equal(vtk_to_numpy(g.GetPoints().GetData()), m.points):
            fail(f"{name}: points differ between VTK and meshio")
        ncells = sum(len(c.data) for c in m.cells)
        if ncells != g.GetNumberOfCells():
            fail(f"{name}: {ncells} cells in meshio, {g.GetNumberOfCells()} in VTK")
        if name == frames[0][1]:
            # VTK's own measure of every cell of the first frame (the reference
            # geometry) is positive: a cell whose nodes VTK reads in another order than
            # signorini writes them can fold, which this sees (quadratic kinds, issue 51)
            sizes = vtk.vtkCellSizeFilter()
            sizes.SetInputData(g)
            sizes.Update()
            cd = sizes.GetOutput().GetCellData()
            measure = sum(vtk_to_numpy(cd.GetArray(k)) for k in ("Length", "Area", "Volume"))
            if not (measure > 0).all():
                fail(f"{name}: {int((measure <= 0).sum())} cells of non-positive size in VTK")
        for arrays, vdata, mdata in [(POINT, g.GetPointData(), m.point_data),
                                     (CELL, g.GetCellData(), None)]:
            for a, ncomp in arrays.items():
                va = vdata.GetArray(a)
                if va is None or va.GetNumberOfComponents() != ncomp:
                    fail(f"{name}: array {a} missing or not {ncomp} components")
                v = vtk_to_numpy(va)
                mv = (mdata[a] if mdata is not None
                      else np.concatenate([c for c in m.cell_data[a]]))
                if not np.array_equal(v.reshape(mv.shape), mv, equal_nan=True):
                    fail(f"{name}: {a} differs between VTK and meshio")
        fd = g.GetFieldData()
        tv = vtk_to_numpy(fd.GetArray("TimeValue"))[0]
        step = int(vtk_to_numpy(fd.GetArray("Step"))[0])
        if abs(tv - t) > 1e-12 * max(abs(t), dt):
            fail(f"{name}: TimeValue {tv} but the .pvd says {t}")
        if step == 0:
            continue
        row = rows.get(step)
        if row is None:
            fail(f"{name}: step {step} has no history row")
        force = vtk_to_numpy(g.GetPointData().GetArray("contact_force"))
        total = float(np.linalg.norm(force, axis=1).sum())
        # |G_α P_α| per contact node: the normal and, with friction, tangential impulses
        # (an orthonormal frame, so the norm of the block's impulse)
        def contact_impulse(c):
            tang = [float(v) for k, v in row.items() if k.startswith(f"tangent_impulse_{c}_")]
            return float(np.hypot(float(row[f"impulse_{c}"]), np.linalg.norm(tang)))
        want = sum(contact_impulse(c) for c in range(ncontact)) / dt
        if abs(total - want) > 1e-9 * max(want, 1.0):
            fail(f"{name}: contact force {total} N, history {want} N")
    h5 = out / "fields.vtkhdf"
    if h5.exists():
        check_vtkhdf(h5, out, frames, rows)
    print(f"check_outputs: OK, {len(frames)} frames of {out} read by VTK {vtk.vtkVersion.GetVTKVersion()} "
          f"and meshio {meshio.__version__}, identical, consistent with history.csv")


def check_vtkhdf(h5, out, frames, rows):
    """Every time step of the VTKHDF file (VTK's vtkHDFReader) equals its .vtu frame, and
    /history (h5py) equals history.csv column by column."""
    import h5py
    r = vtk.vtkHDFReader()
    r.SetFileName(str(h5))
    r.UpdateInformation()
    info = r.GetOutputInformation(0)
    key = vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS()
    times = [info.Get(key, i) for i in range(info.Length(key))]
    if len(times) != len(frames):
        fail(f"{h5}: {len(times)} time steps, fields.pvd has {len(frames)}")
    for (t, name), th in zip(frames, times):
        if abs(t - th) > 1e-12 * max(abs(t), 1e-300):
            fail(f"{h5}: time {th}, .pvd {t}")
        r.UpdateTimeStep(th)
        g = r.GetOutput()
        v = vtk.vtkXMLUnstructuredGridReader()
        v.SetFileName(str(out / name))
        v.Update()
        ref = v.GetOutput()
        if g.GetNumberOfPoints() != ref.GetNumberOfPoints() or g.GetNumberOfCells() != ref.GetNumberOfCells():
            fail(f"{h5} at t = {th}: grid differs from {name}")
        for a in POINT:
            x, y = (vtk_to_numpy(d.GetPointData().GetArray(a)) for d in (g, ref))
            if not np.array_equal(x, y, equal_nan=True):
                fail(f"{h5} at t = {th}: point array {a} differs from {name}")
        for a in CELL:
            x, y = (vtk_to_numpy(d.GetCellData().GetArray(a)) for d in (g, ref))
            if not np.array_equal(x, y, equal_nan=True):
                fail(f"{h5} at t = {th}: cell array {a} differs from {name}")
    with h5py.File(h5, "r") as f:
        hist = f["history"]
        steps = sorted(rows)
        for col in ["time", "kinetic_energy", "potential_energy", "max_violation",
                    "newton_iterations", "projection_iterations", "index_set_iterations"]:
            want = np.array([float(rows[k][col]) for k in steps])
            if not np.array_equal(hist[col][:].astype(float), want):
                fail(f"{h5}: /history/{col} differs from history.csv")
        m = hist["impulse"].shape[1] if hist["impulse"].ndim == 2 else 0
        for q in ["gap", "velocity", "impulse", "projection"]:
            for c in range(m):
                want = np.array([float(rows[k][f"{q}_{c}"]) for k in steps])
                if not np.array_equal(hist[q][:, c], want):
                    fail(f"{h5}: /history/{q}[:, {c}] differs from history.csv")
        # solid scenes: each body's centre and momenta, x y z per body
        for q in ["centre", "momentum", "angular_momentum"]:
            if q not in hist:
                continue
            for j in range(hist[q].shape[1]):
                want = np.array([float(rows[k][f"{q}_{j // 3}_{j % 3}"]) for k in steps])
                if not np.array_equal(hist[q][:, j], want):
                    fail(f"{h5}: /history/{q}[:, {j}] differs from history.csv")
    print(f"check_outputs: {h5}: {len(times)} VTKHDF time steps equal the .vtu frames; "
          f"/history equals history.csv")


if __name__ == "__main__":
    main(sys.argv[1])
