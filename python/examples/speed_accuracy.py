"""A speed–accuracy loop over time steps, in Python: the impacting bar (N = 1000) with
Moreau–Jean and Algorithm 2 at h = 4e-6 … 2.5e-7 s; for each run its cost (seconds per
step, from the summary) and its errors against the closed form (force plateau, contact
duration, largest penetration). `signorini sweep bar` does the same grid with Pareto
fronts and verdicts; this is what a notebook user writes.

    python examples/speed_accuracy.py
"""

import signorini


def main() -> None:
    bar = signorini.Scene.bar()
    print(f"{'scheme':20s} {'dt':>8s} {'µs/step':>9s} {'plateau err':>12s} "
          f"{'duration err':>13s} {'violation (m)':>14s}")
    for scheme in ("moreau-jean", "combined-projection"):
        for dt in (4e-6, 2e-6, 1e-6, 5e-7, 2.5e-7):
            sim = bar.simulation(scheme=scheme, dt=dt)
            sim.run()
            s = sim.summary
            c = s["contact"]
            plateau = abs(c["plateau_force"] - c["analytic_force"]) / c["analytic_force"]
            duration = abs(c["duration"] - c["analytic_duration"]) / c["analytic_duration"]
            print(f"{scheme:20s} {dt:8.1e} {1e6 * s['seconds_per_step']:9.2f} {plateau:12.2e} "
                  f"{duration:13.2e} {s['max_violation']:14.2e}")


if __name__ == "__main__":
    main()
