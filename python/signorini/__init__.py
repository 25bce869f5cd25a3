"""signorini: impact and contact of elastic structures, from Python.

The same scenes, schemes and results as the ``signorini`` command line (one Rust
library under both; no copy of the solver)::

    import signorini
    bar = signorini.Scene.bar()                      # the reference impacting bar
    sim = bar.simulation(scheme="moreau-jean", dt=5e-7)
    sim.run(out="out/bar")                           # GIL released; Ctrl-C stops cleanly
    h = sim.history                                  # dict of numpy arrays, one per column
    force = h["impulse_0"] / sim.summary["dt"]

Arrays are owned ``float64`` copies (``sim.q`` is a new array at each access): the solver
overwrites its state at every step, so a view would change under the caller.
Errors raise :class:`BadInput` (the CLI's exit code 2: the message names the file, the
key path or line, the value and what was expected) or :class:`RunFailed` (exit code 1).
"""

from __future__ import annotations

import json
import math
import os
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import fclib
from ._signorini import BadInput, Cancelled, RunFailed, SignoriniError, _Scene, _Simulation
from ._signorini import HDF5, __version__

__all__ = [
    "Scene",
    "Simulation",
    "Mesh",
    "History",
    "SignoriniError",
    "BadInput",
    "RunFailed",
    "Cancelled",
    "fclib",
    "HDF5",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


def __dir__() -> List[str]:
    """The public names only (tab completion on ``signorini.`` offers the API, not the
    module's imports)."""
    return list(__all__)


def _plain(value: Any) -> Any:
    """``value`` with numpy scalars and arrays turned into Python numbers and lists
    (recursively through dicts, lists and tuples), so that a number or a list may come
    from numpy wherever one is accepted."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _toml_value(value: Any, key: str) -> str:
    """A Python value as a TOML value for a ``--set`` override."""
    value = _plain(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise BadInput(f"invalid value for `{key}`: {value} (a finite number is expected)")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v, key) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {_toml_value(v, key)}" for k, v in value.items()) + "}"
    raise BadInput(f"invalid value for `{key}`: {value!r} (a bool, number, string, list or dict)")


def _overrides(set: Optional[Mapping[str, Any]]) -> List[str]:
    return [f"{k}={_toml_value(v, k)}" for k, v in (set or {}).items()]


def _json(data: Any, what: str) -> str:
    try:
        return json.dumps(_plain(data), allow_nan=False)
    except ValueError as e:
        raise BadInput(f"{what}: {e} (finite numbers are expected)") from None
    except TypeError as e:
        raise BadInput(f"{what}: {e}") from None


def _bar(params: Mapping[str, Any]) -> _Scene:
    """The built-in bar from its parameters, errors in the keyword arguments' spelling
    (the library names the end time by its CLI flag, `t-end`)."""
    try:
        return _Scene.bar(_json(params, "Scene.bar"))
    except BadInput as e:
        raise BadInput(str(e).replace("`t-end`", "`t_end`")) from None


class Scene:
    """A validated scene: a scene file, a dict of its tables, the built-in bar or one of
    the paper's examples. Immutable: :meth:`simulation` takes the run's parameters."""

    __slots__ = ("_inner",)

    def __init__(self, inner: _Scene):
        if not isinstance(inner, _Scene):
            raise TypeError(
                f"Scene() is made by Scene.from_toml(path or text), Scene.from_dict(tables), "
                f"Scene.bar(**params) or Scene.example(name), not from a {type(inner).__name__}"
            )
        self._inner = inner

    @classmethod
    def from_toml(
        cls,
        source: Union[PathLike, str],
        set: Optional[Mapping[str, Any]] = None,
        base_dir: Optional[PathLike] = None,
    ) -> "Scene":
        """A scene from a file (a path object, or a string naming an existing file or
        ending in ``.toml``) or from TOML text (any other string; relative mesh paths
        then start from ``base_dir``, default the working directory: give a scene's own
        :attr:`base_dir` to rebuild it from its :meth:`to_toml`). ``set`` overrides keys
        as ``signorini run --set`` does: ``{"time.dt": 1e-6}``."""
        # a string without `=` holds no TOML key: it names a file (a missing suffix or a
        # wrong directory then reads as "no such file", not as a TOML syntax error)
        if isinstance(source, os.PathLike) or (
            isinstance(source, str)
            and "\n" not in source
            and (source.endswith(".toml") or os.path.exists(source) or "=" not in source)
        ):
            return cls(_Scene.from_file(os.fspath(source), _overrides(set)))
        base = None if base_dir is None else os.fspath(base_dir)
        return cls(_Scene.from_text(source, _overrides(set), base))

    @classmethod
    def from_dict(
        cls,
        tables: Mapping[str, Any],
        set: Optional[Mapping[str, Any]] = None,
        base_dir: Optional[PathLike] = None,
    ) -> "Scene":
        """A scene from the tables of a scene file as Python data (``{"time": {"dt": …},
        "bodies": [...]}``); mesh paths are relative to ``base_dir`` (default: the
        working directory). Equal to the same scene read from TOML.

        Read with no text: the values are checked as they are read (a NaN, an infinity,
        a complex number, ``None`` in a list is refused with its key path), and a mesh's
        ``points``, ``cells`` and ``node_sets`` (``generator = "arrays"``) and a body's
        ``initial_velocity`` / ``initial_displacement`` rows, numpy arrays or lists, are
        checked for shape and dtype, measured against the memory limit, and then copied
        once each into the solver's tables. A ``None`` value in a dict is an absent key."""
        base = None if base_dir is None else os.fspath(base_dir)
        return cls(_Scene.from_dict(tables, _overrides(set), base))

    @classmethod
    def bar(cls, **params: Any) -> "Scene":
        """The built-in impacting bar (the CLI's main job), with any of its parameters:
        ``elements``, ``dt``, ``t_end``, ``length``, ``area``, ``young``, ``density``,
        ``velocity``, ``gap``, ``restitution``, ``mass``, ``scheme`` (a dict of the scheme's
        parameters, or its name)."""
        if isinstance(params.get("scheme"), str):
            params["scheme"] = {"kind": params["scheme"]}
        return cls(_bar(params))

    @classmethod
    def example(cls, name: str) -> "Scene":
        """One of the paper's academic examples: ``bouncing-ball``, ``oscillator``,
        ``rocking-block``, ``slider-crank``."""
        return cls(_Scene.example(name))

    @property
    def is_bar(self) -> bool:
        """Whether this is the built-in bar."""
        return self._inner.is_bar()

    @property
    def steps(self) -> int:
        """Steps of a run of this scene."""
        return self._inner.steps()

    @property
    def base_dir(self) -> Optional[str]:
        """The directory the scene's relative mesh paths start from (None for the bar):
        ``Scene.from_dict(s.to_dict(), base_dir=s.base_dir)`` and
        ``Scene.from_toml(s.to_toml(), base_dir=s.base_dir)`` rebuild ``s`` from anywhere."""
        d = self._inner.base_dir()
        # absolute (against today's working directory, which the scene's relative paths
        # were read against): it stays right after a chdir
        return None if d is None else os.path.abspath(os.fspath(d))

    def to_dict(self) -> Dict[str, Any]:
        """The scene as Python data (file scenes: its tables; the bar: its parameters).
        Mesh paths stay relative to :attr:`base_dir`."""
        return json.loads(self._inner.to_json())

    def to_toml(self) -> str:
        """The scene as TOML text."""
        return self._inner.to_toml()

    def check(self) -> Dict[str, Any]:
        """What ``signorini check`` reports: model size, physics, time stepping, the Newton
        loop, the planned path and memory (``memory_fits`` is False when a run would be
        refused for its memory)."""
        return json.loads(self._inner.check())

    def with_params(
        self,
        scheme: Optional[str] = None,
        dt: Optional[float] = None,
        t_end: Optional[float] = None,
        theta: Optional[float] = None,
        set: Optional[Mapping[str, Any]] = None,
    ) -> "Scene":
        """This scene with a scheme, time step, end time, θ or any key changed."""
        if self.is_bar:
            p = self.to_dict()
            for key, value in (("dt", dt), ("t_end", t_end)):
                if value is not None:
                    p[key] = value
            if scheme is not None:
                p["scheme"]["kind"] = scheme
            if theta is not None:
                p["scheme"]["theta"] = theta
            for key, value in (set or {}).items():
                node = p
                *path, last = key.split(".")
                for part in path:
                    node = node.setdefault(part, {})
                node[last] = value
            return Scene(_bar(p))
        keys: Dict[str, Any] = {}
        if scheme is not None:
            keys["scheme.kind"] = scheme
        if dt is not None:
            keys["time.dt"] = dt
        if t_end is not None:
            keys["time.t_end"] = t_end
        if theta is not None:
            keys["scheme.theta"] = theta
        keys.update(set or {})
        return Scene(self._inner.with_overrides(_overrides(keys)))

    def simulation(
        self,
        scheme: Optional[str] = None,
        dt: Optional[float] = None,
        t_end: Optional[float] = None,
        theta: Optional[float] = None,
        set: Optional[Mapping[str, Any]] = None,
    ) -> "Simulation":
        """A simulation of this scene, with the parameters of :meth:`with_params`."""
        return Simulation(self.with_params(scheme, dt, t_end, theta, set))

    def __repr__(self) -> str:
        kind = "bar" if self.is_bar else "scene"
        return f"<signorini.Scene ({kind}, {self.steps} steps)>"


class Mesh:
    """The mesh of a simulation's model and its dof map (``Simulation.mesh``).

    - ``points``: ``(N, 3)`` reference coordinates (m);
    - ``node_ids``: ``(N,)`` the input's id of each point (the mesh file's node tag, or
      the index within its body for a generated mesh);
    - ``point_body``: ``(N,)`` the body of each point (index into ``bodies``; −1 for a
      point no cell uses);
    - ``bodies``: the bodies' names, in the scene's order;
    - ``cells``: ``{kind: (n, nodes) int64}`` connectivity by cell kind (``line``,
      ``tri3``, ``quad4``, ``tet4``, ``hex8``, and the quadratic ``tri6``, ``quad8``,
      ``quad9``, ``tet10``, ``hex20``, ``hex27`` in VTK's node order; indices into
      ``points``), and
      ``cell_bodies``: ``{kind: (n,)}`` the body of each of those cells;
    - ``dim``: displacement components per point (1 for rods, 2 or 3 for solids);
    - ``dof_map``: ``(N, dim)`` where each component is in ``q`` and ``v`` (−1: fixed
      or moved at a prescribed velocity, so not an unknown);
    - ``contacts``: the contact list in the order of ``sim.gaps`` and ``sim.impulses``
      and of the history's per-contact columns: ``{"point": (m,), "node_id": (m,),
      "body": (m,), "target": (m,) str, "entry": (m,)}`` (the node, its body, the
      obstacle or body it meets, the scene's ``[[contacts]]`` entry); empty for the
      academic examples, whose contacts are not mesh nodes.

    ``nodal(x)`` turns a dof vector (``sim.q``, ``sim.v``) into ``(N, dim)`` nodal values,
    NaN where a component is not an unknown."""

    __slots__ = (
        "points",
        "node_ids",
        "point_body",
        "bodies",
        "cells",
        "cell_bodies",
        "dim",
        "dof_map",
        "contacts",
    )

    def __init__(self, raw: Any):
        points, node_ids, point_body, cells, dim, dof_map, bodies, contacts = raw
        self.points: np.ndarray = points
        self.node_ids: np.ndarray = node_ids
        self.point_body: np.ndarray = point_body
        self.bodies: List[str] = list(bodies)
        self.dim: int = dim
        self.dof_map: np.ndarray = dof_map
        by_kind: Dict[str, List[List[int]]] = {}
        body_of: Dict[str, List[int]] = {}
        for kind, body, nodes in cells:
            by_kind.setdefault(kind, []).append(nodes)
            body_of.setdefault(kind, []).append(body)
        self.cells: Dict[str, np.ndarray] = {
            k: np.asarray(v, dtype=np.int64) for k, v in by_kind.items()
        }
        self.cell_bodies: Dict[str, np.ndarray] = {
            k: np.asarray(v, dtype=np.int64) for k, v in body_of.items()
        }
        point = np.asarray([c[0] for c in contacts], dtype=np.int64)
        self.contacts: Dict[str, np.ndarray] = {
            "point": point,
            "node_id": node_ids[point] if len(point) else np.zeros(0, dtype=np.uint64),
            "body": np.asarray([c[1] for c in contacts], dtype=np.int64),
            "target": np.asarray([c[2] for c in contacts], dtype=str),
            "entry": np.asarray([c[3] for c in contacts], dtype=np.int64),
        }

    def nodal(self, x: Any) -> np.ndarray:
        """The dof vector ``x`` (one value per unknown, as ``sim.q``) as ``(N, dim)``
        nodal values, NaN where a component is fixed or prescribed."""
        x = np.asarray(x, dtype=np.float64)
        n_dofs = int(self.dof_map.max()) + 1 if self.dof_map.size else 0
        if x.ndim != 1 or x.shape[0] != n_dofs:
            raise BadInput(
                f"invalid value for `x`: an array of shape {x.shape} (expected one value per "
                f"unknown: shape ({n_dofs},), as `Simulation.q`)"
            )
        out = np.full(self.dof_map.shape, np.nan)
        known = self.dof_map >= 0
        out[known] = x[self.dof_map[known]]
        return out

    def dofs(self, x: Any, name: str = "x") -> np.ndarray:
        """The inverse of :meth:`nodal`: ``(N, dim)`` nodal values as one value per
        unknown. Where a component is fixed or prescribed (no unknown) the value must be
        0 or NaN (a motion there cannot be given: it is the scene's); a dof vector
        (shape ``(unknowns,)``) is returned as a ``float64`` copy."""
        x = np.asarray(x, dtype=np.float64)
        n_dofs = int(self.dof_map.max()) + 1 if self.dof_map.size else 0
        if x.ndim == 1 and x.shape[0] == n_dofs:
            return x.copy()
        if x.shape != self.dof_map.shape:
            raise BadInput(
                f"invalid value for `{name}`: an array of shape {x.shape} (expected one value "
                f"per unknown, shape ({n_dofs},), or one row per point, shape "
                f"{self.dof_map.shape})"
            )
        known = self.dof_map >= 0
        bad = ~known & ~np.isnan(x) & (x != 0)
        if bad.any():
            p, c = (int(i) for i in np.argwhere(bad)[0])
            raise BadInput(
                f"invalid value for `{name}`: {x[p, c]} at point {p}, component {c}, which is "
                f"fixed or prescribed (give 0 or NaN there)"
            )
        out = np.empty(n_dofs)
        out[self.dof_map[known]] = x[known]
        return out

    def __repr__(self) -> str:
        kinds = ", ".join(f"{len(v)} {k}" for k, v in self.cells.items())
        return (
            f"<signorini.Mesh ({len(self.points)} points, {kinds}; {len(self.bodies)} bodies, "
            f"dim {self.dim}; {len(self.contacts['point'])} contacts)>"
        )


#: Units of the history's columns (SI; "" for counts and flags). `projection` is τ of
#: eq. 28: metres with the Euclidean metric, kg·m with the M̂⁻¹ metric (q moves by N G τ).
_UNITS = {
    "step": "",
    "time": "s",
    "dt": "s",
    "kinetic_energy": "J",
    "potential_energy": "J",
    "max_violation": "m",
    "newton_iterations": "",
    "projection_iterations": "",
    "index_set_iterations": "",
    "closed_contacts": "",
    "total_impulse": "N·s",
    "min_gap": "m",
    "total_projection": "m or kg·m (τ, eq. 28)",
    "total_tangent_impulse": "N·s",
    "sticking": "",
    "slipping": "",
    "friction_iterations": "",
    "friction_residual": "",
    "gap": "m",
    "velocity": "m/s",
    "impulse": "N·s",
    "projection": "m or kg·m (τ, eq. 28)",
    "tangent_impulse": "N·s",
    "slip_velocity": "m/s",
    "status": "",
    "centre": "m",
    "momentum": "kg·m/s",
    "angular_momentum": "kg·m²/s",
}

#: The per-contact quantities of the history (`gap_c`, …), then those with a tangent
#: index too (`tangent_impulse_c_t`, …).
_PER_CONTACT = ("gap", "velocity", "impulse", "projection", "status")
_PER_TANGENT = ("tangent_impulse", "slip_velocity")
#: The per-body quantities of a solid scene's history (`centre_b_d`, …; d = x, y, z).
_PER_BODY = ("centre", "momentum", "angular_momentum")


def _split(name: str) -> Tuple[str, Tuple[int, ...]]:
    """A column's quantity and its indices: ``impulse_3`` → ``("impulse", (3,))``,
    ``tangent_impulse_3_1`` → ``("tangent_impulse", (3, 1))``, ``time`` → ``("time", ())``."""
    parts = name.split("_")
    idx: List[int] = []
    while parts and parts[-1].isdigit():
        idx.insert(0, int(parts.pop()))
    return "_".join(parts), tuple(idx)


class History(dict):
    """The run's history (``history.csv``) as a dict of ``float64`` arrays, one per
    column in the file's order, plus the same numbers shaped by meaning:

    - ``time``: ``(steps,)`` s;
    - ``contacts``: how many contacts have their own columns (0 past 256 contacts, where
      the file keeps the sums: ``closed_contacts``, ``total_impulse``, …);
    - ``per_contact(q)``: ``(steps, contacts)`` for ``gap``, ``velocity``, ``impulse``,
      ``projection``, ``status``; ``(steps, contacts, tangents)`` for
      ``tangent_impulse`` and ``slip_velocity`` (contact ``c`` is ``mesh.contacts[c]``);
    - ``bodies`` and ``per_body(q)``: ``(steps, bodies, 3)`` for ``centre`` (centre of
      mass), ``momentum`` and ``angular_momentum`` (about the centre of mass) of each
      body of a solid or plane scene (body ``b`` is ``mesh.bodies[b]``);
    - ``unit(name)``: a column's or a quantity's SI unit (``""`` for counts);
    - ``to_pandas()``: a DataFrame indexed by time, units in ``df.attrs["units"]``;
    - ``to_xarray()``: a Dataset on dimensions ``time``, ``contact``, ``tangent``,
      ``body``, ``axis``, each variable with its ``units`` attribute.
    """

    @property
    def time(self) -> np.ndarray:
        """Times (s), one per row."""
        return self["time"]

    @property
    def contacts(self) -> int:
        """Contacts with their own columns."""
        return sum(1 for k in self if _split(k)[0] == "gap" and len(_split(k)[1]) == 1)

    def per_contact(self, quantity: str) -> np.ndarray:
        """``quantity`` for every contact: ``(steps, contacts)``, or
        ``(steps, contacts, tangents)`` for the tangential ones."""
        if quantity not in _PER_CONTACT + _PER_TANGENT:
            raise BadInput(
                f"invalid value for `quantity`: {quantity!r} (expected one of "
                f"{', '.join(_PER_CONTACT + _PER_TANGENT)})"
            )
        cols = {idx: v for k, v in self.items() for q, idx in [_split(k)] if q == quantity}
        steps = len(self["time"])
        if not cols:
            if self.contacts == 0 and "total_impulse" in self:
                raise BadInput(
                    f"invalid value for `quantity`: {quantity!r} (this history keeps the sums "
                    f"over its contacts, not one column per contact: set "
                    f'[output] contact_columns = "all" in the scene)'
                )
            return np.zeros((steps, self.contacts) + ((0,) if quantity in _PER_TANGENT else ()))
        shape = tuple(max(i[d] for i in cols) + 1 for d in range(len(next(iter(cols)))))
        out = np.full((steps,) + shape, np.nan)
        for idx, v in cols.items():
            out[(slice(None),) + idx] = v
        return out

    @property
    def bodies(self) -> int:
        """Bodies with their own columns (0 for rods and the academic examples)."""
        n = 0
        for k in self:
            q, idx = _split(k)
            n += q == "centre" and len(idx) == 2 and idx[1] == 0
        return n

    def per_body(self, quantity: str) -> np.ndarray:
        """``quantity`` (``centre``, ``momentum`` or ``angular_momentum``) of every body:
        ``(steps, bodies, 3)``, the last axis x, y, z."""
        if quantity not in _PER_BODY:
            raise BadInput(
                f"invalid value for `quantity`: {quantity!r} (expected one of "
                f"{', '.join(_PER_BODY)})"
            )
        out = np.full((len(self["time"]), self.bodies, 3), np.nan)
        for k, v in self.items():
            q, idx = _split(k)
            if q == quantity and len(idx) == 2:
                out[:, idx[0], idx[1]] = v
        return out

    def unit(self, name: str) -> str:
        """The SI unit of a column (``impulse_3``) or a quantity (``impulse``)."""
        q = _split(name)[0]
        if q not in _UNITS:
            raise BadInput(f"invalid value for `name`: {name!r} (not a history column)")
        return _UNITS[q]

    def to_pandas(self) -> Any:
        """The history as a pandas DataFrame indexed by ``time`` (s), one column per
        history column, units in ``df.attrs["units"]`` (needs pandas)."""
        import pandas as pd

        df = pd.DataFrame({k: v for k, v in self.items() if k != "time"}, index=self["time"])
        df.index.name = "time"
        df.attrs["units"] = {k: self.unit(k) for k in self}
        return df

    def to_xarray(self) -> Any:
        """The history as an xarray Dataset: scalar columns on ``time``, the per-contact
        quantities on ``(time, contact)`` and the tangential ones on
        ``(time, contact, tangent)``, each with its ``units`` (needs xarray)."""
        import xarray as xr

        data: Dict[str, Any] = {}
        done = set()
        for k, v in self.items():
            q, idx = _split(k)
            if k == "time":
                continue
            if idx and q in _PER_CONTACT + _PER_TANGENT:
                if q not in done:
                    dims = ("time", "contact") + (("tangent",) if q in _PER_TANGENT else ())
                    data[q] = (dims, self.per_contact(q), {"units": _UNITS[q]})
                    done.add(q)
            elif len(idx) == 2 and q in _PER_BODY:
                if q not in done:
                    data[q] = (("time", "body", "axis"), self.per_body(q), {"units": _UNITS[q]})
                    done.add(q)
            else:
                data[k] = (("time",), v, {"units": self.unit(k)})
        return xr.Dataset(data, coords={"time": ("time", self["time"], {"units": "s"})})


def _progress_adapter(progress: Optional[Callable[..., None]]) -> Optional[Callable[..., None]]:
    """The callback the run calls as ``(step, total, info)``: ``progress`` itself when it
    takes three arguments, else a wrapper that passes ``(step, total)``."""
    if progress is None:
        return None
    import inspect

    try:
        params = inspect.signature(progress).parameters.values()
    except (TypeError, ValueError):  # a builtin without a signature: two arguments
        return lambda step, total, info: progress(step, total)
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if len(positional) >= 3 or any(p.kind == p.VAR_POSITIONAL for p in params):
        return progress
    return lambda step, total, info: progress(step, total)


class Simulation:
    """One run of a scene, taken whole by :meth:`run` (as the CLI makes it, files
    included) or step by step by :meth:`step`, or both: the run opens at the first call
    (:meth:`start` opens it into a directory without stepping), every step goes through
    the same checks and observers, the history grows as it goes, and the step that
    reaches the scene's end forms the summary."""

    __slots__ = ("scene", "_inner", "_mesh")

    def __init__(self, scene: Scene):
        self.scene = scene
        self._inner = _Simulation(scene._inner)
        self._mesh: Optional[Mesh] = None

    @property
    def mesh(self) -> Mesh:
        """The model's mesh and dof map (:class:`Mesh`). Builds the model if nothing has
        yet (the first :meth:`step` then integrates that model instead of building it
        again)."""
        if self._mesh is None:
            self._mesh = Mesh(self._inner.mesh())
        return self._mesh

    def bodies(self) -> Dict[str, np.ndarray]:
        """Each body's measures in the current state, as arrays over the bodies (in the
        scene's order): ``name`` ``(B,)``, ``mass`` ``(B,)`` (kg), ``centre`` ``(B, 3)``
        (centre of mass, m), ``momentum`` ``(B, 3)`` (kg·m/s) and ``angular_momentum``
        ``(B, 3)`` (about the centre of mass, kg·m²/s; about the origin it is
        ``angular_momentum + np.cross(centre, momentum)``). Of the state after the last
        :meth:`step`, the final state of an in-memory :meth:`run`, or the initial state
        before either. Sums over the kept dofs: a fixed or prescribed component adds
        nothing (exact for free bodies)."""
        rows = self._inner.bodies()
        names = self.mesh.bodies
        b = len(rows)
        return {
            "name": np.array(names[:b] + [f"body {i}" for i in range(len(names), b)]),
            "mass": np.array([r[0] for r in rows], dtype=np.float64),
            "centre": np.array([r[1] for r in rows], dtype=np.float64).reshape(b, 3),
            "momentum": np.array([r[2] for r in rows], dtype=np.float64).reshape(b, 3),
            "angular_momentum": np.array([r[3] for r in rows], dtype=np.float64).reshape(b, 3),
        }

    def set_state(self, q: Any = None, v: Any = None) -> None:
        """Sets the displacements ``q`` (m) and/or velocities ``v`` (m/s): one value per
        unknown (as :attr:`q`) or one row per point (``(N, dim)``, as
        :meth:`Mesh.nodal` gives; 0 or NaN where a component is fixed or prescribed).
        Before the first :meth:`step` or :meth:`run` it replaces the scene's initial
        state (a per-node initial field; the summary's initial energy and body measures
        are of it); between steps, the current state, whose gaps and contact data are
        evaluated again at the new ``q``, and the run's energy balance starts again from
        it (the energy the edit gives or takes is no work of the forces). A new ``q`` is
        checked as the scene's own start is: no contact node may start deeper inside its
        obstacle or the other body than its contact's ``overlap_tolerance``
        (:class:`BadInput` naming ``contacts[i].nodes``, the node and its depth)."""
        m = self.mesh
        qd = None if q is None else m.dofs(q, "q")
        vd = None if v is None else m.dofs(v, "v")
        self._inner.set_state(qd, vd)

    def run(
        self,
        out: Optional[PathLike] = None,
        progress: Optional[Callable[..., None]] = None,
        fields: Optional[bool] = None,
        plots: Optional[bool] = None,
    ) -> "Simulation":
        """Runs the scene to its end with the GIL released. With ``out``, writes what the
        CLI writes there (``history.csv``, ``summary.json``, fields, plots); without,
        keeps the history in memory only. On a simulation already stepped (or a run
        interrupted) it goes on from the step reached, where that run writes (``out``
        must then be None or that directory). ``progress(step, total)`` — or
        ``progress(step, total, info)``, ``info`` a dict of ``time`` (simulated, s),
        ``elapsed`` (wall s since the first step), ``steps_per_second``, ``eta`` (s) and
        the step's ``newton_iterations``, ``projection_iterations``,
        ``index_set_iterations``, ``lcp_iterations``, ``max_violation`` (m), ``caps_hit``
        — is called up to 1000 times. Ctrl-C stops after the current step, leaves
        ``out`` readable (the history and the frames so far) and raises
        ``KeyboardInterrupt``; the state reached is kept, and :meth:`step` or
        :meth:`run` goes on from it."""
        self._inner.run(
            None if out is None else os.fspath(out), _progress_adapter(progress), fields, plots
        )
        return self

    def start(
        self,
        out: Optional[PathLike] = None,
        fields: Optional[bool] = None,
        plots: Optional[bool] = None,
    ) -> "Simulation":
        """Opens the run without stepping: with ``out``, the steps that follow write what
        the CLI writes there (history, frames as the scene or ``fields`` asks, and at
        the last step ``summary.json`` and the plots); without, the history is kept in
        memory, which is what the first :meth:`step` does by itself."""
        self._inner.start(None if out is None else os.fspath(out), fields, plots)
        return self

    def step(self, n: int = 1, progress: Optional[Callable[..., None]] = None) -> int:
        """Takes ``n`` steps (the first call opens the run, in memory unless
        :meth:`start` gave a directory) and returns the steps done. Each step is checked
        and recorded as in :meth:`run` (:attr:`history` grows); the step that reaches
        the scene's end forms :attr:`summary`. :attr:`stats` has the last step's
        statistics. ``progress`` as in :meth:`run` (called at the run's report steps
        that fall in these ``n``; an exception in it stops after the current step and
        propagates, the state reached kept). Ctrl-C and :meth:`cancel` stop within about
        50 ms whatever a step costs, and while the first call builds the model."""
        return self._inner.step(n, _progress_adapter(progress))

    def cancel(self) -> None:
        """Asks the :meth:`step` or :meth:`run` running in another thread to stop after
        the step it is taking (or the next such call, if none runs): it raises
        :class:`Cancelled`. After :meth:`step` the state reached is kept and stepping can
        go on; after :meth:`run` into ``out`` the history and frames so far are there,
        readable. Safe to call from any thread (it takes no lock)."""
        self._inner.cancel()

    @property
    def q(self) -> np.ndarray:
        """Displacements, one per dof (m; owned ``float64`` copy)."""
        return self._inner.q

    @property
    def v(self) -> np.ndarray:
        """Velocities, one per dof (m/s; owned ``float64`` copy)."""
        return self._inner.v

    @property
    def impulses(self) -> np.ndarray:
        """Normal impulses of the last step, one per contact (N·s; force = P / dt)."""
        return self._inner.impulses

    @property
    def gaps(self) -> np.ndarray:
        """Gaps, one per contact (m; negative is penetration)."""
        return self._inner.gaps

    @property
    def contact_velocities(self) -> np.ndarray:
        """Normal relative velocities, one per contact (m/s)."""
        return self._inner.contact_velocities

    @property
    def tangent_impulses(self) -> np.ndarray:
        """Friction impulses of the last step, ``(contacts, tangents)`` in each contact's
        frame (N·s; ``tangents`` 1 in 2-D, 2 in 3-D, 0 without friction)."""
        return self._inner.tangent_impulses.reshape(len(self.gaps), self._inner.tangent_dim)

    @property
    def slip_velocities(self) -> np.ndarray:
        """Tangential (slip) velocities, ``(contacts, tangents)`` (m/s)."""
        return self._inner.slip_velocities.reshape(len(self.gaps), self._inner.tangent_dim)

    @property
    def statuses(self) -> List[str]:
        """Each contact's status after the last step: ``open``, ``stick``, ``slip`` or
        ``frictionless`` (closed, μ = 0) in frictional scenes; empty otherwise."""
        return self._inner.statuses

    @property
    def time(self) -> float:
        """Time of the current state (s)."""
        return self._inner.time

    @property
    def steps_done(self) -> int:
        """Steps taken."""
        return self._inner.steps_done

    @property
    def steps_total(self) -> int:
        """Steps of the whole run; of a run that chooses its steps (``time.accuracy``),
        the steps at its largest step: the fewest it can take (it ends at ``t_end``,
        which :attr:`time` tells)."""
        return self._inner.steps_total

    @property
    def stats(self) -> Optional[Dict[str, Any]]:
        """The last step's statistics (None before a step)."""
        s = self._inner.stats_json
        return None if s is None else json.loads(s)

    @property
    def summary(self) -> Dict[str, Any]:
        """``summary.json`` of the run, as a dict: formed when the run reaches its last
        step, by :meth:`run` or by :meth:`step`."""
        s = self._inner.summary_json
        if s is None:
            raise RuntimeError(
                f"no summary yet: it is formed at the run's last step "
                f"({self.steps_done} of {self.steps_total} done)"
            )
        return json.loads(s)

    @property
    def history(self) -> "History":
        """``history.csv`` of the run as a :class:`History`: a dict of ``float64`` arrays,
        one per column in the file's order (the same numbers, bit for bit), with the
        per-contact columns also as ``(steps, contacts)`` arrays, units, and
        ``to_pandas()`` / ``to_xarray()``. The whole run's once it has ended; the rows
        so far while :meth:`step` goes through it."""
        cols = self._inner.history_columns()
        if cols is None:
            raise RuntimeError("no history yet: take a step() or run() first")
        return History(cols)

    @property
    def probes(self) -> Dict[str, Dict[str, Any]]:
        """The scene's ``[[probes]]`` after :meth:`run`, by name: ``times`` ``(k,)`` (s),
        ``displacement`` ``(k, dim)`` (m, the mean over the probe's nodes), ``node_count``,
        ``body`` and ``nodes`` (the set), and for a rod ``analytic`` ``(k, dim)`` when the
        summary has it."""
        out: Dict[str, Dict[str, Any]] = {}
        for p in self.summary.get("probes", []):
            d: Dict[str, Any] = {
                "times": np.asarray(p["times"], dtype=np.float64),
                "displacement": np.asarray(p["displacement"], dtype=np.float64),
                "node_count": p["node_count"],
                "body": p["body"],
                "nodes": p["nodes"],
            }
            if p.get("analytic") is not None:
                d["analytic"] = np.asarray(p["analytic"], dtype=np.float64)
            out[p["name"]] = d
        return out

    @property
    def out(self) -> Optional[str]:
        """The output directory of ``run(out=…)`` or ``start(out=…)`` (None in memory)."""
        o = self._inner.out
        return None if o is None else os.fspath(o)

    def frames(self, reader: bool = True) -> Any:
        """The field frames ``run(out=…)`` wrote (``fields.pvd``): with pyvista installed
        and ``reader`` true, ``pyvista.get_reader`` on them (``.time_values``,
        ``.set_active_time_value(t)``, ``.read()`` → the mesh with ``displacement``,
        ``velocity``, ``contact_force``, ``gap``, ``stress`` …); else the ``.pvd`` path
        (ParaView, meshio, VTK)."""
        if self.out is None:
            raise RuntimeError(
                "no frames: run(out=...) or start(out=...) writes them (an in-memory run does not)"
            )
        pvd = os.path.join(self.out, "fields.pvd")
        if not os.path.exists(pvd):
            raise RuntimeError(
                f"no frames in {self.out}: the run wrote none (fields=False, or a scene "
                f"without a mesh)"
            )
        if reader:
            try:
                import pyvista
            except ImportError:
                return pvd
            return pyvista.get_reader(pvd)
        return pvd

    def __repr__(self) -> str:
        return f"<signorini.Simulation {self.steps_done}/{self.steps_total} steps, t = {self.time:g} s>"
