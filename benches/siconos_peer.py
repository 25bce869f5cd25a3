#!/usr/bin/python3
"""Peer check against Siconos (Debian's python3-siconos, run with /usr/bin/python3).

Runs the impacting bar (N = 1000, h = 5e-6, T = 1e-3, theta = 1/2, e = 0,
S = pi 1e-4) in Siconos and in signorini, and compares the histories step by step:

  moreau-jean          Siconos MoreauJeanOSI            vs  signorini --scheme moreau-jean
  combined-projection  Siconos MoreauJeanCombinedProjectionOSI (its defaults:
                       Euclidean metric, q-only update, every active contact
                       projected)                       vs  signorini --metric euclidean
                                                            --no-projection-feedback
                                                            --projection-rule all-active

Exit 1 if any impulse differs by more than 1e-9 of the largest impulse, or any gap by
more than 1e-12 m. Also prints both codes' time per step (same machine, same run).

Usage: /usr/bin/python3 benches/siconos_peer.py [path/to/signorini]
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import siconos.kernel as sk

N, H, T = 1000, 5e-6, 1e-3
L, E, RHO, S, V0, THETA = 1.0, 210e9, 7800.0, np.pi * 1e-4, -0.1, 0.5


def siconos_run(scheme):
    n, le = N + 1, L / N
    m = np.zeros((n, n))
    k = np.zeros((n, n))
    me = RHO * S * le / 6 * np.array([[2, 1], [1, 2]])
    ke = E * S / le * np.array([[1, -1], [-1, 1]])
    for e in range(N):
        m[e:e + 2, e:e + 2] += me
        k[e:e + 2, e:e + 2] += ke
    bar = sk.LagrangianLinearTIDS(np.zeros(n), V0 * np.ones(n), m)
    bar.setKPtr(k)
    h = np.zeros((1, n))
    h[0, 0] = 1.0
    inter = sk.Interaction(sk.NewtonImpactNSL(0.0), sk.LagrangianLinearTIR(h))
    nsds = sk.NonSmoothDynamicalSystem(0.0, T)
    nsds.insertDynamicalSystem(bar)
    nsds.link(inter, bar)
    td = sk.TimeDiscretisation(0.0, H)
    if scheme == "moreau-jean":
        sim = sk.TimeStepping(nsds, td, sk.MoreauJeanOSI(THETA), sk.LCP())
    else:
        sim = sk.TimeSteppingCombinedProjection(
            nsds, td, sk.MoreauJeanCombinedProjectionOSI(THETA), sk.LCP(),
            sk.MLCPProjectOnConstraints(), 2)
    rows = []
    t0 = time.time()
    while sim.hasNextEvent():
        sim.computeOneStep()
        rows.append((inter.y(0)[0], inter.lambda_(1)[0]))
        sim.nextStep()
    return np.array(rows), (time.time() - t0) / len(rows)


def signorini_run(exe, args, out):
    subprocess.run([exe, "bar", "--elements", str(N), "--dt", str(H), "--t-end", str(T),
                    "--quiet", "--no-fields", "--no-plots", "--out", out] + args, check=True)
    with open(os.path.join(out, "history.csv")) as f:
        r = list(csv.DictReader(f))
    with open(os.path.join(out, "summary.json")) as f:
        import json
        sps = json.load(f)["seconds_per_step"]
    return np.array([(float(x["gap_0"]), float(x["impulse_0"])) for x in r]), sps


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "target/release/signorini"
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        # the paper's rules, which Siconos implements: Newton's law with e on every
        # contact, the forecast's active set alone (docs/bar.md, "Algorithm 2's position rule")
        for scheme, args in [("moreau-jean", ["--scheme", "moreau-jean", "--newton-restitution",
                                              "--no-activation-closure"]),
                             # Siconos' projection kicks the tip node and the bar gains
                             # 15 % of its energy, which signorini refuses by default
                             ("combined-projection", ["--metric", "euclidean",
                                                      "--no-projection-feedback",
                                                      "--projection-rule", "all-active",
                                                      "--newton-restitution",
                                                      "--max-energy-excess", "inf"])]:
            a, sic_sps = siconos_run(scheme)
            b, our_sps = signorini_run(exe, args, os.path.join(tmp, scheme))
            dp = np.abs(a[:, 1] - b[:, 1]).max() / np.abs(a[:, 1]).max()
            dg = np.abs(a[:, 0] - b[:, 0]).max()
            f = a[:, 1] / H
            good = len(a) == len(b) and dp <= 1e-9 and dg <= 1e-12
            ok &= good
            print(f"{scheme:20s} steps {len(a)}/{len(b)}  max |dP|/max P = {dp:.2e}  "
                  f"max |dgap| = {dg:.2e} m  peak force {f.max():.3f} N  "
                  f"Siconos {sic_sps*1e3:.2f} ms/step, signorini {our_sps*1e6:.2f} us/step "
                  f"(incl. output)  {'OK' if good else 'MISMATCH'}")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
