"""Issue 48: `Scene.from_dict` reads Python data with no text. The dict is walked into the
library's TOML values (no JSON, no TOML text), and a mesh's arrays and per-node fields are
checked for shape and dtype, measured against the memory limit, then copied once each:
the scene equals the one read from TOML (every committed scene, and a mesh given as
arrays), a mesh too large for the limit is refused at once without copying it, and a bad
value is refused with its key path, the value and what was expected."""

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import signorini

ROOT = pathlib.Path(__file__).resolve().parents[2]
MESHES = ROOT / "meshes"


@pytest.mark.parametrize("path", sorted(MESHES.glob("*.toml")), ids=lambda p: p.name)
def test_every_committed_scene_from_its_dict_equals_the_scene_from_toml(path):
    t = signorini.Scene.from_toml(path)
    d = signorini.Scene.from_dict(t.to_dict(), base_dir=t.base_dir)
    assert d.to_toml() == t.to_toml()
    assert d.to_dict() == t.to_dict()
    assert d.check() == t.check()


def _box_mesh():
    """A 3 × 2 × 2 hex8 box's points (N, 3) float64 and cells (n, 8) int64, as the box
    generator numbers them."""
    d = {
        "time": {"dt": 1e-5, "t_end": 1e-4},
        "bodies": [
            {
                "name": "box",
                "mesh": {"generator": "box", "cell": "hex8", "cells": [3, 2, 2], "size": [0.3, 0.2, 0.2]},
                "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0},
            }
        ],
    }
    m = signorini.Scene.from_dict(d).simulation().mesh
    return m.points, m.cells["hex8"]


def _arrays_scene(points, cells, **body):
    b = {
        "name": "box",
        "mesh": {
            "generator": "arrays",
            "points": points,
            "cells": {"hex8": cells},
            "node_sets": {"z0": np.flatnonzero(np.asarray(points)[:, 2] == 0.0)},
        },
        "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0},
    }
    b.update(body)
    return {
        "time": {"dt": 1e-5, "t_end": 1e-4},
        "bodies": [b],
        "obstacles": [{"name": "floor", "type": "plane", "point": [0, 0, -1e-4], "normal": [0, 0, 1]}],
        "contacts": [{"body": "box", "nodes": "z0", "obstacle": "floor"}],
    }


def _rows(a):
    return "[" + ", ".join("[" + ", ".join(repr(x) for x in r) + "]" for r in np.asarray(a).tolist()) + "]"


def test_a_mesh_given_as_arrays_equals_the_same_mesh_written_in_toml():
    """The arrays (float64 points, int64 cells, an int64 node set, a float64 velocity
    field) and the same numbers written as TOML text give one scene: its tables, its
    `check` report and its first steps bit for bit. Fortran-ordered points, int32 cells
    and a node set as a list are the same scene again."""
    points, cells = _box_mesh()
    v0 = np.tile([0.0, 0.0, -1.0], (len(points), 1)) + 1e-3 * points
    d = _arrays_scene(points, cells, initial_velocity=v0)
    z0 = np.flatnonzero(points[:, 2] == 0.0)
    text = f"""
[time]
dt = 1e-5
t_end = 1e-4
[[bodies]]
name = "box"
mesh = {{ generator = "arrays", points = {_rows(points)}, cells = {{ hex8 = {_rows(cells)} }}, node_sets = {{ z0 = {list(map(int, z0))} }} }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
initial_velocity = {_rows(v0)}
[[obstacles]]
name = "floor"
type = "plane"
point = [0, 0, -1e-4]
normal = [0, 0, 1]
[[contacts]]
body = "box"
nodes = "z0"
obstacle = "floor"
"""
    from_toml = signorini.Scene.from_toml(text)
    from_dict = signorini.Scene.from_dict(d)
    assert from_dict.to_dict() == from_toml.to_dict()
    assert from_dict.to_toml() == from_toml.to_toml()
    assert from_dict.check() == from_toml.check()
    a, b = from_dict.simulation(), from_toml.simulation()
    a.step(5)
    b.step(5)
    assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)
    other = _arrays_scene(np.asfortranarray(points), cells.astype(np.int32), initial_velocity=v0.tolist())
    other["bodies"][0]["mesh"]["node_sets"]["z0"] = z0.tolist()
    assert signorini.Scene.from_dict(other).to_dict() == from_toml.to_dict()
    # the overrides of `set` apply as to a scene file, and so do those of a scene held
    # (its arrays set aside and put back, no text)
    assert signorini.Scene.from_dict(d, set={"time.t_end": 5e-5}).steps == 5
    keys = {"time.t_end": 5e-5, "bodies[0].material.young": 2e7}
    assert (
        from_dict.with_params(set=keys).to_dict()
        == signorini.Scene.from_toml(text, set=keys).to_dict()
    )
    keys = {"bodies[0].initial_velocity[0]": [0.0, 0.0, -2.0]}
    assert (
        from_dict.with_params(set=keys).to_dict()
        == signorini.Scene.from_toml(text, set=keys).to_dict()
    )


# the refusal of a mesh the memory limit cannot hold, in a process of its own (its peak
# resident memory is the script's); the arrays are filled, so resident
_TOO_LARGE = """
import json, resource, time
import numpy as np
import signorini
n = 10**7
points = np.random.default_rng(0).random((n, 3))
cells = np.arange(n, dtype=np.int64).reshape(-1, 8)
d = {"time": {"dt": 1e-5, "t_end": 1e-4}, "bodies": [{"name": "big",
     "mesh": {"generator": "arrays", "points": points, "cells": {"hex8": cells}},
     "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0}}]}
t0 = time.perf_counter()
try:
    signorini.Scene.from_dict(d)
    message = None
except signorini.BadInput as e:
    message = str(e)
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"message": message, "seconds": seconds, "peak": peak,
                  "arrays": points.nbytes + cells.nbytes}))
"""


def test_a_mesh_past_the_memory_limit_is_refused_before_it_is_copied():
    """A 10⁷-point hex8 mesh (240 MB of points, 80 MB of cells) under
    SIGNORINI_MEMORY_LIMIT=256M: refused with BadInput naming the key, the limit and the
    estimate, from the arrays' shapes alone. Measured on the 2-core machine (this
    script under `/usr/bin/time -v`, 3 runs): 0.6–0.8 ms in `from_dict` to the refusal,
    a peak of 342 MiB resident for the whole process (350 620 kB: the arrays' 305 MiB,
    the interpreter and numpy; 1.1× the arrays), against 38 s and an abort at 7.2 GB
    when the dict went through JSON and TOML text. Asserted generously: < 5 s, and a
    peak under twice the arrays' own size."""
    env = dict(os.environ, SIGNORINI_MEMORY_LIMIT="256M")
    out = subprocess.run(
        [sys.executable, "-c", _TOO_LARGE], env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    r = json.loads(out.stdout)
    m = r["message"]
    assert m is not None, "accepted"
    assert "bodies[0].mesh.points" in m and "10000000 points and 1250000 cells" in m, m
    assert "would need at least" in m and "more than the memory limit 256.0 MiB" in m, m
    assert "SIGNORINI_MEMORY_LIMIT" in m, m
    assert r["seconds"] < 5.0, r
    assert r["peak"] < 2 * r["arrays"], r


def _points_nan(d):
    d["bodies"][0]["mesh"]["points"][12, 1] = np.nan


def _points_list_none(d):
    p = d["bodies"][0]["mesh"]["points"].tolist()
    p[3][2] = None
    d["bodies"][0]["mesh"]["points"] = p


def _points_list_bool(d):
    p = d["bodies"][0]["mesh"]["points"].tolist()
    p[0][0] = True
    d["bodies"][0]["mesh"]["points"] = p


def _points_complex(d):
    d["bodies"][0]["mesh"]["points"] = d["bodies"][0]["mesh"]["points"].astype(complex)


def _points_object(d):
    p = d["bodies"][0]["mesh"]["points"].astype(object)
    p[2, 0] = None
    d["bodies"][0]["mesh"]["points"] = p


def _points_shape(d):
    p = d["bodies"][0]["mesh"]["points"]
    d["bodies"][0]["mesh"]["points"] = np.hstack([p, np.zeros((len(p), 1))])


def _points_flat(d):
    d["bodies"][0]["mesh"]["points"] = d["bodies"][0]["mesh"]["points"].ravel()


def _cells_float(d):
    d["bodies"][0]["mesh"]["cells"]["hex8"] = d["bodies"][0]["mesh"]["cells"]["hex8"].astype(float)


def _cells_shape(d):
    d["bodies"][0]["mesh"]["cells"]["hex8"] = d["bodies"][0]["mesh"]["cells"]["hex8"][:, :7]


def _cells_negative(d):
    d["bodies"][0]["mesh"]["cells"]["hex8"][2, 3] = -1


def _cells_list_float(d):
    c = d["bodies"][0]["mesh"]["cells"]["hex8"].tolist()
    c[1][4] = 4.0
    d["bodies"][0]["mesh"]["cells"]["hex8"] = c


def _node_set_2d(d):
    d["bodies"][0]["mesh"]["node_sets"]["z0"] = d["bodies"][0]["mesh"]["node_sets"]["z0"].reshape(1, -1)


def _field_nan(d):
    v = np.zeros_like(d["bodies"][0]["mesh"]["points"])
    v[5, 2] = np.inf
    d["bodies"][0]["initial_velocity"] = v


def _field_shape(d):
    d["bodies"][0]["initial_displacement"] = np.zeros((len(d["bodies"][0]["mesh"]["points"]), 2))


def _dt_inf(d):
    d["time"]["dt"] = float("inf")


def _dt_nan(d):
    d["time"]["dt"] = np.float64("nan")


def _young_complex(d):
    d["bodies"][0]["material"]["young"] = 1e7 + 2j


def _velocity_none(d):
    d["bodies"][0]["velocity"] = [0.0, None, 0.0]


def _dt_bool(d):
    d["time"]["dt"] = True


def _obstacle_point_bool(d):
    d["obstacles"][0]["point"] = np.array([0.0, 0.0, 0.0]) > 1


def _key_not_a_string(d):
    d["bodies"][0]["material"][3] = 1.0


def _probe_times_huge(d):
    d["probes"] = [{"name": "p", "body": "box", "nodes": "all", "times": np.zeros(2_000_000)}]


def _set_an_array(d):
    return {"bodies[0].mesh.points": [[0.0, 0.0, 0.0]]}


def _unknown_object(d):
    d["bodies"][0]["material"]["density"] = object()


BAD = [
    (_points_nan, [r"`bodies[0].mesh.points[12][1]`: NaN", "finite real number (m)"]),
    (_points_list_none, [r"`bodies[0].mesh.points[3][2]`: None", "finite real number (m)"]),
    (_points_list_bool, [r"`bodies[0].mesh.points[0][0]`: True", "not a bool"]),
    (_points_complex, ["`bodies[0].mesh.points`", "dtype complex128", "float or integer dtype"]),
    (_points_object, ["`bodies[0].mesh.points`", "dtype object", "float or integer dtype"]),
    (_points_shape, ["`bodies[0].mesh.points`", "shape (36, 4)", "shape (N, 3)"]),
    (_points_flat, ["`bodies[0].mesh.points`", "shape (108,)", "2-D array"]),
    (_cells_float, ["`bodies[0].mesh.cells.hex8`", "dtype float64", "integer dtype"]),
    (_cells_shape, ["`bodies[0].mesh.cells.hex8`", "shape (12, 7)", "a hex8 cell has 8 nodes"]),
    (_cells_negative, ["`bodies[0].mesh.cells.hex8[2][3]`: -1", "integer ≥ 0"]),
    (_cells_list_float, ["`bodies[0].mesh.cells.hex8[1][4]`: 4.0", "integer ≥ 0"]),
    (_node_set_2d, ["`bodies[0].mesh.node_sets.z0`", "shape (1, 12)", "1-D array"]),
    (_field_nan, ["`bodies[0].initial_velocity[5][2]`: inf", "finite real number (m/s)"]),
    (_field_shape, ["`bodies[0].initial_displacement`", "shape (36, 2)", "shape (nodes, 3)"]),
    (_dt_inf, ["`time.dt`: inf", "a finite number"]),
    (_dt_nan, ["`time.dt`: NaN", "a finite number"]),
    (_young_complex, ["`bodies[0].material.young`: (10000000+2j)", "complex numbers are not taken"]),
    (_velocity_none, ["`bodies[0].velocity[1]`: None", "in a dict only"]),
    (_dt_bool, ["`time.dt`", "boolean"]),
    (_obstacle_point_bool, ["`obstacles[0]", "boolean"]),
    (_key_not_a_string, ["`bodies[0].material.3`", "a key of a scene's table is a string"]),
    (_probe_times_huge, ["`probes[0].times`", "shape (2000000,)", "at most 1048576 values"]),
    (_set_an_array, ["`set`", "`bodies[0].mesh.points` is given as an array in the dict"]),
    (_unknown_object, ["`bodies[0].material.density`", "not a value of type object"]),
]


@pytest.mark.parametrize("edit,needles", BAD, ids=[e.__name__.strip("_") for e, _ in BAD])
def test_a_bad_value_is_refused_with_its_key_path_value_and_expectation(edit, needles):
    points, cells = _box_mesh()
    d = _arrays_scene(points.copy(), cells.copy())
    assert signorini.Scene.from_dict(_arrays_scene(points, cells)).steps == 10
    overrides = edit(d)
    with pytest.raises(signorini.BadInput) as e:
        signorini.Scene.from_dict(d, set=overrides)
    m = str(e.value)
    for n in needles:
        assert n in m, m
    assert len(m) < 400, m


def test_a_quadratic_mesh_given_as_arrays_is_the_generated_one():
    """Issue 51 §5: a hex27 mesh handed over as numpy arrays (the generator's own points
    and cells, keyed `hex27`) builds the same scene as the generator: the same mesh and
    the same first steps bit for bit; a `hex27` array of 8 columns is refused by its
    key path and the node count."""
    gen = {
        "time": {"dt": 1e-5, "t_end": 1e-4},
        "bodies": [
            {
                "name": "box",
                "mesh": {"generator": "box", "cell": "hex27", "cells": [2, 1, 1], "size": [0.2, 0.1, 0.1]},
                "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0},
                "velocity": [0.0, 0.0, -1.0],
            }
        ],
        "obstacles": [{"name": "floor", "type": "plane", "point": [0, 0, -1e-4], "normal": [0, 0, 1]}],
        "contacts": [{"body": "box", "nodes": "z0", "obstacle": "floor"}],
    }
    m = signorini.Scene.from_dict(gen).simulation().mesh
    points, cells = m.points, m.cells["hex27"]
    assert cells.shape == (2, 27)
    arrays = dict(gen)
    arrays["bodies"] = [dict(gen["bodies"][0])]
    arrays["bodies"][0]["mesh"] = {
        "generator": "arrays",
        "points": points,
        "cells": {"hex27": cells},
        "node_sets": {"z0": np.flatnonzero(points[:, 2] == 0.0)},
    }
    a, b = signorini.Scene.from_dict(gen).simulation(), signorini.Scene.from_dict(arrays).simulation()
    assert np.array_equal(a.mesh.points, b.mesh.points)
    assert np.array_equal(a.mesh.cells["hex27"], b.mesh.cells["hex27"])
    a.step(5)
    b.step(5)
    assert np.array_equal(a.q, b.q)
    arrays["bodies"][0]["mesh"]["cells"] = {"hex27": cells[:, :8]}
    with pytest.raises(signorini.BadInput, match=r"mesh\.cells\.hex27.*27 nodes"):
        signorini.Scene.from_dict(arrays).simulation()
