"""signorini.fclib against the CLI's `signorini fclib` on the shared problems (the same
solver, parameters and residual: the same reactions, bit for bit) and against closed
forms on small problems given as arrays (dense and scipy.sparse)."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

from signorini import BadInput, fclib

DATA = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "fclib"
CLI = os.environ.get("SIGNORINI_BIN")


@pytest.mark.skipif(not CLI, reason="SIGNORINI_BIN (the CLI) not set")
@pytest.mark.parametrize(
    "name",
    ["FrictionContact3D_1c.dat", "FC2D_SliderCrankLagrangian00001.dat", "Capsules-i100-889.dat"],
)
def test_solve_agrees_with_the_cli_on_the_shared_problems(tmp_path, name):
    sol = tmp_path / "sol.json"
    subprocess.run([CLI, "fclib", str(DATA / name), "--solution", str(sol)], check=True,
                   stdout=subprocess.DEVNULL)
    cli = json.loads(sol.read_text())
    py = fclib.solve(DATA / name)
    assert py["report"]["converged"] == cli["converged"]
    assert py["report"]["solved_by"] == cli["solved_by"]
    assert py["report"]["iterations"] == cli["iterations"]
    assert np.array_equal(py["r"], np.array(cli["r"]))
    assert np.array_equal(py["u"], np.array(cli["u"]))
    # the same problem given as arrays is the same problem
    W, q, mu = fclib.read(DATA / name)
    arr = fclib.solve(W, q, mu)
    assert np.array_equal(arr["r"], py["r"])


def test_the_reference_reactions_of_the_readme():
    # tests/data/fclib/README.md: FrictionContact3D_1c.dat slides at
    # r = [0.065695682898, -0.003678614907, -0.005443070814] (12 digits printed)
    r = fclib.solve(DATA / "FrictionContact3D_1c.dat")["r"]
    assert np.allclose(r, [0.065695682898, -0.003678614907, -0.005443070814], rtol=0, atol=1e-11)


def test_one_contact_in_closed_form_dense_and_sparse():
    scipy_sparse = pytest.importorskip("scipy.sparse")
    # W = I, q = (-1, 0.2, 0), mu = 0.5: sticking needs |r_T| = 0.2 ≤ mu r_N = 0.5, so
    # r = (1, -0.2, 0) and u = 0
    W = np.eye(3)
    q = np.array([-1.0, 0.2, 0.0])
    for w in (W, scipy_sparse.csr_matrix(W)):
        s = fclib.solve(w, q, [0.5], solver="nsgs", tol=1e-14)
        assert s["report"]["converged"]
        assert np.allclose(s["r"], [1.0, -0.2, 0.0], rtol=0, atol=1e-14)
        assert np.allclose(s["u"], 0.0, atol=1e-14)
    # sliding: q_T = 1 > mu r_N: r_T = -mu r_N along q_T, u_T = q_T + r_T
    s = fclib.solve(W, np.array([-1.0, 1.0, 0.0]), [0.5], tol=1e-14)
    assert np.allclose(s["r"], [1.0, -0.5, 0.0], rtol=0, atol=1e-12)


def test_bad_problems_raise_with_the_message():
    with pytest.raises(BadInput, match="`q`: 3 values"):
        fclib.solve(np.eye(2), np.zeros(3), [0.1])
    with pytest.raises(BadInput, match="expected a square matrix"):
        fclib.solve(np.ones((3, 2)), np.zeros(3), [0.1])
    with pytest.raises(BadInput, match="mu"):
        fclib.solve(np.eye(3), np.zeros(3), [-0.1])
    with pytest.raises(BadInput, match="solver"):
        fclib.solve(np.eye(3), np.zeros(3), [0.1], solver="lemke")
    with pytest.raises(BadInput, match="no-such.dat"):
        fclib.solve("no-such.dat")


def test_array_inputs_are_named_when_wrong():
    """Issue 37 §5, §7: a short `q`, a 1-D `W`, a missing `mu`, and a warm start of the
    wrong length or with a NaN are refused with the argument's name (before, a short `q`
    was reported as a wrong shape of `W`, a 1-D `W` as "dimensionality mismatch", and a
    bad warm start was ignored)."""
    W = np.eye(3)
    q = np.array([-1.0, 0.0, 0.0])
    mu = np.array([0.5])
    cases = [
        (lambda: fclib.solve(W, q[:2], mu), "`q`: 2 values"),
        (lambda: fclib.solve(np.ones(9), q, mu), "`W`: an array of shape (9,)"),
        (lambda: fclib.solve(W, q), "missing `mu`"),
        (lambda: fclib.solve(W, q, mu, r0=np.zeros(2)), "`r0`: 2 values"),
        (lambda: fclib.solve(W, q, mu, r0=np.array([np.nan, 0.0, 0.0])), "`r0`: entry 0 is NaN"),
    ]
    for make, expected in cases:
        with pytest.raises(BadInput) as e:
            make()
        assert expected in str(e.value), str(e.value)
    # the right warm start is taken: from the solution, no iteration is left to do
    sol = fclib.solve(W, q, mu)
    again = fclib.solve(W, q, mu, r0=sol["r"])
    assert np.array_equal(again["r"], sol["r"])


def test_hdf5_problems_are_read_where_the_package_has_hdf5(tmp_path):
    """Issue 37: the wheels carry HDF5 (`signorini.HDF5`): an FCLIB `.hdf5` problem is
    read and solved to the reference of tests/data/fclib/README.md (CubeH8, one sliding
    contact, printed to 12 digits: compared to 1e-9 relative with a 1e-13 residual), and
    a scene with `output.hdf5` writes `fields.vtkhdf`. Without HDF5 the same calls raise
    BadInput naming the feature, never a silent skip of the file."""
    import signorini

    path = DATA / "CubeH8.hdf5"
    if not signorini.HDF5:
        with pytest.raises(BadInput, match="hdf5"):
            fclib.solve(path)
        return
    r = fclib.solve(path, tol=1e-13)["r"]
    ref = np.array([0.017461447863, -0.004479738287, -0.002715352538])
    assert np.abs(r - ref).max() <= 1e-9 * np.abs(ref).max()
    box = {
        "time": {"dt": 1e-5, "t_end": 1e-4},
        "scheme": {"kind": "moreau-jean"},
        "output": {"hdf5": True},
        "bodies": [{
            "name": "box",
            "mesh": {"generator": "box", "cell": "hex8", "cells": [4, 2, 2], "size": [0.4, 0.2, 0.1]},
            "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0},
        }],
    }
    signorini.Scene.from_dict(box).simulation().run(out=tmp_path / "box", plots=False)
    head = (tmp_path / "box" / "fields.vtkhdf").read_bytes()[:8]
    assert head == b"\x89HDF\r\n\x1a\n"
