"""What `sim.step(1)` in a Python loop costs over the step itself (issue 20: at most
2 µs). The reference bar (N = 1000, h = 2e-7, Algorithm 2), 5000 steps, stepped once as
`step(5000)` and once as 5000 calls of `step(1)`, alternately over ROUNDS rounds; prints
the medians and the difference per step.

    python examples/step_overhead.py [ROUNDS]
"""

import statistics
import sys
import time

import signorini


def timed(per_call: bool) -> float:
    sim = signorini.Scene.bar().simulation()
    sim.step(1)  # builds the integrator (factor, Delassus data): not part of the timing
    n = sim.steps_total - 1
    t = time.perf_counter()
    if per_call:
        for _ in range(n):
            sim.step(1)
    else:
        sim.step(n)
    return (time.perf_counter() - t) / n


def main() -> None:
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 11
    inside, loop = [], []
    for _ in range(rounds):
        inside.append(timed(False))
        loop.append(timed(True))
    a, b = statistics.median(inside), statistics.median(loop)
    print(f"step(n): {1e6 * a:.2f} µs/step; step(1) in a loop: {1e6 * b:.2f} µs/step; "
          f"overhead {1e6 * (b - a):.2f} µs per call (medians of {rounds} rounds)")


if __name__ == "__main__":
    main()
