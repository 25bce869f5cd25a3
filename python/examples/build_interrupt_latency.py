"""How soon `cancel()` stops the first `step()` while it builds the model and factors M̂
(issue 37): a hex8 cube of N³ cells (default 30: 89 373 dofs), the time to open its run
measured once, then five trials cancelled 0.3 s into the opening; prints the seconds from
`cancel()` to `signorini.Cancelled` (median and max).

    python examples/build_interrupt_latency.py [N]
"""

import statistics
import sys
import threading
import time

import signorini


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 30
    scene = signorini.Scene.from_dict({
        "time": {"dt": 1e-5, "t_end": 1e-4},
        "scheme": {"kind": "moreau-jean"},
        "bodies": [{
            "name": "cube",
            "mesh": {"generator": "box", "cell": "hex8", "cells": [n, n, n], "size": [1, 1, 1]},
            "material": {"young": 1e7, "poisson": 0.3, "density": 1000.0},
        }],
    })
    t = time.perf_counter()
    scene.simulation().start()
    print(f"{n}³ cells: opening the run (model, factor) takes {time.perf_counter() - t:.2f} s")
    latencies = []
    for _ in range(5):
        sim = scene.simulation()
        stopped = {}

        def first_step():
            try:
                sim.step(1)
            except signorini.Cancelled:
                stopped["at"] = time.perf_counter()

        worker = threading.Thread(target=first_step)
        worker.start()
        time.sleep(0.3)
        asked = time.perf_counter()
        sim.cancel()
        worker.join()
        latencies.append(stopped["at"] - asked)
        # let the abandoned build finish before the next trial (it runs on, dropped)
        time.sleep(8.0)
    print(f"cancel() → Cancelled: median {statistics.median(latencies) * 1e3:.1f} ms, "
          f"max {max(latencies) * 1e3:.1f} ms over {len(latencies)} trials")


if __name__ == "__main__":
    main()
