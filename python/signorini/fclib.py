"""One-step frictional contact problems (FCLIB's local form): find ``r`` and ``u = W r + q``
with ``u`` in the dual of Coulomb's cone at ``r`` (De Saxcé's form, eq. 15 of the paper),
by the solvers of ``signorini fclib`` (NSGS, PROX, the global Alart–Curnier Newton, and
``auto``, which chains them), with the same parameters, residual and report."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from ._signorini import BadInput, fclib_read, fclib_solve_arrays, fclib_solve_file

__all__ = ["solve", "read"]


def __dir__() -> List[str]:
    """The public names only (tab completion offers the API, not the imports)."""
    return list(__all__)


def read(path: Union[str, "os.PathLike[str]"]) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(W, q, mu)`` of a problem file (Siconos ``.dat``): ``W`` is ``n × n``."""
    return fclib_read(os.fspath(path))


def solve(
    W: Any,
    q: Optional[Any] = None,
    mu: Optional[Any] = None,
    solver: str = "auto",
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
    residual: str = "siconos",
    r0: Optional[Any] = None,
    warm: bool = False,
) -> Dict[str, Any]:
    """Solves ``W r + q = u`` under Coulomb's law with friction ``mu`` per contact.

    ``W`` is an ``n × n`` array or scipy.sparse matrix (rows per contact ``n / len(mu)``:
    2 or 3, normal first), or the path of a problem file (then ``q`` and ``mu`` come from
    it, and ``warm`` starts from its guess). ``solver`` is ``auto``, ``nsgs``, ``prox``,
    ``nsn`` or ``newton``; ``tol`` and ``max_iter`` default to the CLI's; ``residual`` is
    ``siconos`` (Siconos' relative residual, as FCLIB's results are judged) or
    ``velocity``. Returns ``{"r", "u", "report"}``; a cap hit is not an error: read
    ``report["converged"]``."""
    if isinstance(W, (str, os.PathLike)):
        r, u, report = fclib_solve_file(os.fspath(W), solver, tol, max_iter, residual, warm)
    else:
        if hasattr(W, "toarray"):  # scipy.sparse
            W = W.toarray()
        W = np.asarray(W, dtype=np.float64)
        if W.ndim != 2:
            raise BadInput(
                f"invalid value for `W`: an array of shape {W.shape} (expected a matrix, n × n)"
            )
        for name, value in (("q", q), ("mu", mu)):
            if value is None:
                raise BadInput(f"missing `{name}`: W given as a matrix needs q and mu")
        q = np.ascontiguousarray(q, dtype=np.float64)
        mu = np.ascontiguousarray(mu, dtype=np.float64)
        r0 = None if r0 is None else np.ascontiguousarray(r0, dtype=np.float64)
        for name, value in (("q", q), ("mu", mu), ("r0", r0)):
            if value is not None and value.ndim != 1:
                raise BadInput(
                    f"invalid value for `{name}`: an array of shape {value.shape} (expected a vector)"
                )
        r, u, report = fclib_solve_arrays(W, q, mu, solver, tol, max_iter, residual, r0)
    return {"r": r, "u": u, "report": json.loads(report)}
