"""The impacting elastic bar (the paper's sec. 6.2) through Python: the contact force at
the wall against its closed form E S |v0| / c0 = 1271.472 N over 2 L / c0 = 3.8545e-4 s,
for Moreau–Jean and Algorithm 2, plotted with matplotlib into bar_force.png.

    python examples/bar_force.py [OUT.png]
"""

import sys

import numpy as np

import signorini


def main() -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = sys.argv[1] if len(sys.argv) > 1 else "bar_force.png"
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for scheme in ("moreau-jean", "combined-projection"):
        sim = signorini.Scene.bar(t_end=6e-4).simulation(scheme=scheme, dt=1e-6)
        sim.run()
        h, c = sim.history, sim.summary["contact"]
        force = h["impulse_0"] / sim.summary["dt"]
        ax.plot(1e3 * h["time"], force, label=f"{scheme}: plateau {c['plateau_force']:.3f} N")
        print(f"{scheme:20s} plateau {c['plateau_force']:.3f} N (closed form "
              f"{c['analytic_force']:.3f} N), contact {c['duration']:.4e} s "
              f"(closed form {c['analytic_duration']:.4e} s)")
    c0 = np.sqrt(210e9 / 7800.0)
    force = 210e9 * np.pi * 1e-4 * 0.1 / c0
    t = np.array([0.0, 2.0 / c0, 2.0 / c0, 6e-4])
    ax.plot(1e3 * t, [force, force, 0.0, 0.0], "k--", label=f"closed form {force:.3f} N")
    ax.set_xlabel("time (ms)")
    ax.set_ylabel("contact force (N)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
