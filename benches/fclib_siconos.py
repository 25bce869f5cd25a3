#!/usr/bin/python3
"""FCLIB benchmark: signorini's friction solvers against Siconos' on the same files, in
one run on one machine (Debian's python3-siconos and python3-h5py, /usr/bin/python3).

For every .hdf5 / .dat file of DIR (default tests/data/fclib): Siconos' fc3d NSGS, PROX,
NSN_AC and ADMM (fc2d NSGS, CPG and ENUM for 2-D problems), and `signorini fclib` with
auto, nsgs, prox, nsn and newton, all from r = 0 with tolerance 1e-8 and 20 000 iterations. Each
solve runs 5 times in one process (once when it takes over a second); the table shows the median solve time (Siconos: the driver call;
signorini: the `seconds` of its --solution JSON with --repeat 5, the solve without
reading the file),
the iterations, Siconos' residual as each code reports it, and whether it converged.

Global problems are condensed here as signorini does (W = H^T M^-1 H, q = H^T M^-1 f + w,
sparse LU of M), so both codes solve the same local problem. Siconos 4.4 has no FCLIB
reader. Needs Debian's python3-scipy besides python3-siconos and python3-h5py.

Usage: /usr/bin/python3 benches/fclib_siconos.py [path/to/signorini] [DIR]
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import siconos.numerics as sn

TOL, MAX_IT, REPEAT = 1e-8, 20000, 5


def sparse(g):
    """The matrix of an FCLIB group as a scipy CSC matrix (duplicates summed)."""
    import scipy.sparse as sp
    m, n, nz = int(g["m"][()]), int(g["n"][()]), int(g["nz"][()])
    p, i, x = np.array(g["p"]), np.array(g["i"]), np.array(g["x"])
    if nz == -1:  # CSC
        return sp.csc_matrix((x[: p[n]], i[: p[n]], p[: n + 1]), shape=(m, n))
    if nz == -2:  # CSR
        return sp.csr_matrix((x[: p[m]], i[: p[m]], p[: m + 1]), shape=(m, n)).tocsc()
    # triplets: i = row, p = column (CSparse)
    return sp.coo_matrix((x[:nz], (i[:nz], p[:nz])), shape=(m, n)).tocsc()


def load(path):
    if path.endswith(".dat"):
        t = open(path).read().split()
        d, nc, storage = int(t[0]), int(t[1]), int(t[2])
        n = d * nc
        if storage == 0:  # dense: sizes twice, values column by column
            k = 7
            w = np.array(list(map(float, t[k : k + n * n]))).reshape(n, n).T
            k += n * n
        else:  # sparse-block (SBM_write_in_file)
            k = 5
            nblocks = int(t[k]); k += 1
            w = np.zeros((n, n))
            if nblocks:
                nbr, nbc = int(t[k]), int(t[k + 1]); k += 2
                rs = [0] + [int(x) for x in t[k : k + nbr]]; k += nbr
                cs = [0] + [int(x) for x in t[k : k + nbc]]; k += nbc
                f1, f2 = int(t[k]), int(t[k + 1]); k += 2
                rowptr = [int(x) for x in t[k : k + f1]]; k += f1
                colidx = [int(x) for x in t[k : k + f2]]; k += f2
                for br in range(nbr):
                    for b in range(rowptr[br], rowptr[br + 1]):
                        k += 1  # the block number
                        bc = colidx[b]
                        nr, ncol = rs[br + 1] - rs[br], cs[bc + 1] - cs[bc]
                        vals = np.array(list(map(float, t[k : k + nr * ncol]))); k += nr * ncol
                        w[rs[br]:rs[br + 1], cs[bc]:cs[bc + 1]] = vals.reshape(ncol, nr).T
        q = np.array(list(map(float, t[k : k + n])))
        mu = np.array(list(map(float, t[k + n : k + n + nc])))
        return d, w, q, mu
    import h5py

    f = h5py.File(path, "r")
    if "fclib_local" in f:
        g = f["fclib_local"]
        return (int(g["spacedim"][()]), sparse(g["W"]).toarray(), np.array(g["vectors/q"]),
                np.array(g["vectors/mu"]))
    # global: condensed with a sparse LU of M (Spheres-i099's M has 12 000 rows)
    import scipy.sparse.linalg as sla
    g = f["fclib_global"]
    m, h = sparse(g["M"]), sparse(g["H"])
    rhs = np.column_stack([h.toarray(), np.array(g["vectors/f"])])
    x = sla.splu(m).solve(rhs)
    w = h.T @ x[:, :-1]
    q = h.T @ x[:, -1] + np.array(g["vectors/w"])
    return int(g["spacedim"][()]), np.asarray(w), q, np.array(g["vectors/mu"])


def siconos(d, w, q, mu, solver):
    times, out = [], None
    for _ in range(REPEAT):
        n = len(q)
        fcp = sn.FrictionContactProblem(d, np.ascontiguousarray(w), q.copy(), mu.copy())
        so = sn.SolverOptions(solver)
        so.iparam[sn.SICONOS_IPARAM_MAX_ITER] = MAX_IT
        so.dparam[sn.SICONOS_DPARAM_TOL] = TOL
        r, u = np.zeros(n), np.zeros(n)
        # Siconos prints a line per failed inner factorization: silence its C output
        sys.stdout.flush()
        saved = [os.dup(1), os.dup(2)]
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.dup2(null, 2)
        try:
            t0 = time.perf_counter()
            info = (sn.fc3d_driver if d == 3 else sn.fc2d_driver)(fcp, r, u, so)
            times.append(time.perf_counter() - t0)
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved + [null]:
                os.close(fd)
        out = (info == 0, so.iparam[sn.SICONOS_IPARAM_ITER_DONE], so.dparam[sn.SICONOS_DPARAM_RESIDU])
        if times[0] > 1.0:  # one run of a solve over a second is timing enough
            break
    return out + (statistics.median(times),)


def signorini(binary, path, solver):
    with tempfile.TemporaryDirectory() as tmp:
        js = os.path.join(tmp, "s.json")
        # --repeat: the median of REPEAT solves in one process, as for Siconos
        subprocess.run([binary, "fclib", path, "--solver", solver, "--tol", str(TOL),
                        "--max-iter", str(MAX_IT), "--repeat", str(REPEAT), "--solution", js],
                       stdout=subprocess.DEVNULL, check=False)
        s = json.load(open(js))
    return (s["converged"], s["iterations"], s["residual"], s["seconds"])


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else "target/release/signorini"
    folder = sys.argv[2] if len(sys.argv) > 2 else "tests/data/fclib"
    files = sorted(f for f in os.listdir(folder) if f.endswith((".hdf5", ".dat")))
    print(f"tol {TOL:g}, cap {MAX_IT}, median of {REPEAT} solves from r = 0; Siconos numerics "
          f"{getattr(sn, '__version__', '4.4')}")
    print(f"| file | rows | code | solver | converged | iterations | residual | µs |")
    print("|---|---|---|---|---|---|---|---|")
    for name in files:
        path = os.path.join(folder, name)
        d, w, q, mu = load(path)
        sic = ([("NSGS", sn.SICONOS_FRICTION_3D_NSGS), ("PROX", sn.SICONOS_FRICTION_3D_PROX),
                ("NSN_AC", sn.SICONOS_FRICTION_3D_NSN_AC), ("ADMM", sn.SICONOS_FRICTION_3D_ADMM)]
               if d == 3 else
               [("NSGS", sn.SICONOS_FRICTION_2D_NSGS), ("CPG", sn.SICONOS_FRICTION_2D_CPG),
                ("ENUM", sn.SICONOS_FRICTION_2D_ENUM)])
        rows = []
        for label, s in sic:
            try:
                rows.append(("Siconos", label) + siconos(d, w, q, mu, s))
            except Exception as e:  # a solver missing or refusing the problem
                rows.append(("Siconos", label, False, 0, float("nan"), float("nan")))
                print(f"  ({name}: Siconos {label} failed: {e})", file=sys.stderr)
        for s in ["auto", "nsgs", "prox", "nsn", "newton"]:
            rows.append(("signorini", s) + signorini(binary, path, s))
        for code, label, ok, it, res, sec in rows:
            print(f"| {name} | {len(q)} | {code} | {label} | {'yes' if ok else 'NO'} | {it} | "
                  f"{res:.1e} | {1e6 * sec:.1f} |")
        best = lambda c: min((r[5] for r in rows if r[0] == c and r[2]), default=float("inf"))
        print(f"|   | | | fastest converged: Siconos {1e6 * best('Siconos'):.1f} µs, "
              f"signorini {1e6 * best('signorini'):.1f} µs | | | | |")


if __name__ == "__main__":
    main()
