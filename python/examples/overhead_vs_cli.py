"""What calling through Python costs over the CLI on the main job (issue 20: at most 5 %).
The reference bar with its default output (history, 103 frames, plots) written by
`signorini --quiet --out DIR` (a process: its start included) and by
`Scene.bar().simulation().run(out=DIR)` in this process (the interpreter and the import
excluded: a notebook pays them once), alternately over ROUNDS rounds; medians.

    SIGNORINI_BIN=target/release/signorini python examples/overhead_vs_cli.py [ROUNDS]
"""

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import signorini


def main() -> None:
    cli = os.environ.get("SIGNORINI_BIN", "signorini")
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 11
    tmp = tempfile.mkdtemp()
    a, b = [], []
    for i in range(rounds):
        out = os.path.join(tmp, f"cli{i}")
        t = time.perf_counter()
        subprocess.run([cli, "--quiet", "--out", out], check=True)
        a.append(time.perf_counter() - t)
        out = os.path.join(tmp, f"py{i}")
        t = time.perf_counter()
        signorini.Scene.bar().simulation().run(out=out)
        b.append(time.perf_counter() - t)
    shutil.rmtree(tmp)
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"CLI {1e3 * ma:.1f} ms, Python run() {1e3 * mb:.1f} ms: {mb / ma:.3f}× "
          f"(medians of {rounds} rounds)")


if __name__ == "__main__":
    main()
