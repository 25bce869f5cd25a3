#!/usr/bin/env python3
"""Algorithm 2's position rule (and Algorithm 1, Moreau–Jean) over scenes × time steps.

Runs every committed impact scene of meshes/ at its own step and at 2x, 4x and 8x coarser
ones, for the schemes and rules given (`scheme:rule`, rule `-` for the scheme's defaults;
the paper's rule runs with Newton's law on every contact, `energy_consistent_restitution
= false`, as the paper writes it), through the CLI (`signorini run SCENE --set ...`),
and writes one row per run to OUT/matrix.csv: exit code, largest energy excess (relative
to the run's energy scale, `energy_balance.excess_max` of summary.json), largest
violation, caps, mean and max Newton iterations, rounds redone with complementarity, wall
time. Prints a Markdown table of the verdicts (docs/bar.md, "Algorithm 2's position rule").

A cell is `ok` when the run exits 0 with no cap and an energy excess <= 1e-6 (round-off:
every clean run of the matrix stays below 2e-13); otherwise it names what failed.

Usage: python3 benches/projection_rule_matrix.py [--bin target/release/signorini]
         [--out out/rule-matrix] [--scenes a,b] [--factors 1,2,4,8]
         [--runs combined-projection:persistent,combined-projection:paper,...]
Needs only Python 3.11 (tomllib); two runs at a time.
"""
import argparse
import csv
import itertools
import json
import os
import re
import subprocess
import tomllib
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = os.path.join(HERE, "..", "meshes")
IMPACT_SCENES = [
    "hertz_ball", "hertz_ball_on_plate", "hertz_spheres", "ball_drop", "ball_crush",
    "bar", "two_bars", "hex_bar", "hex_bars", "block_stack", "block_on_cylinder",
    "bouncing_ball", "rocking_block", "oscillator", "slider_crank", "pushed_block",
    "dragged_block", "sliding_block", "sliding_block_on_slab",
]
RUNS = ["combined-projection:persistent", "combined-projection:paper",
        "combined-projection:complementarity", "direct-projection:-", "moreau-jean:-"]
ROUND_OFF = 1e-6


def run(exe, out, job):
    scene, spec, f = job
    scheme, rule = spec.split(":")
    with open(os.path.join(MESHES, scene + ".toml"), "rb") as fh:
        dt = tomllib.load(fh)["time"]["dt"] * f
    d = os.path.join(out, "runs", f"{scene}-{scheme}-{rule}-{f:g}")
    cmd = [exe, "run", os.path.join(MESHES, scene + ".toml"),
           "--set", f'scheme.kind="{scheme}"', "--set", f"time.dt={dt:.6g}",
           "--no-fields", "--no-plots", "--quiet", "--out", d]
    if rule != "-":
        cmd += ["--set", f'scheme.projection_rule="{rule}"']
    if rule == "paper":
        cmd += ["--set", "scheme.energy_consistent_restitution=false"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    row = dict(scene=scene, scheme=scheme, rule=rule, factor=f, dt=dt, exit=p.returncode)
    try:
        with open(os.path.join(d, "summary.json")) as fh:
            s = json.load(fh)
        row.update(excess=s["energy_balance"]["excess_max"], violation=s["max_violation"],
                   caps=s["caps_hit"], newton_mean=s["iterations"]["newton"]["mean"],
                   newton_max=s["iterations"]["newton"]["max"],
                   redone=s["newton_loops"]["complementarity_fallbacks"],
                   wall=s["wall_seconds"])
    except (OSError, KeyError, ValueError):
        lines = p.stderr.strip().splitlines()
        row["error"] = lines[-1] if lines else ""
    return row


def verdict(r):
    """`ok`, or what failed: `+X %` (exit 1, the energy check), `exit N`, `N caps`, or
    `gain X` (exit 0 with an energy excess above round-off)."""
    if r["exit"] != 0:
        e = r.get("error", "")
        m = re.search(r"\(([\d.]+) % of the run's energy scale\)", e)
        if m:
            return f"+{m.group(1)} %"
        m = re.search(r"\(([\d.e+-]+) of the run's energy scale\)", e)
        return f"+{100 * float(m.group(1)):.1f} %" if m else f"exit {r['exit']}"
    if (r.get("caps") or 0) > 0:
        return f"{r['caps']} caps"
    if (r.get("excess") or 0.0) > ROUND_OFF:
        return f"gain {r['excess']:.1e}"
    return "ok"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "target", "release", "signorini"))
    ap.add_argument("--out", default="out/rule-matrix")
    ap.add_argument("--scenes", default=",".join(IMPACT_SCENES))
    ap.add_argument("--factors", default="1,2,4,8")
    ap.add_argument("--runs", default=",".join(RUNS))
    a = ap.parse_args()
    scenes = a.scenes.split(",")
    factors = [float(x) for x in a.factors.split(",")]
    runs = a.runs.split(",")
    os.makedirs(a.out, exist_ok=True)
    jobs = list(itertools.product(scenes, runs, factors))
    with ThreadPoolExecutor(2) as ex:
        rows = list(ex.map(lambda j: run(a.bin, a.out, j), jobs))
    keys = ["scene", "scheme", "rule", "factor", "dt", "exit", "excess", "violation", "caps",
            "newton_mean", "newton_max", "redone", "wall", "error"]
    with open(os.path.join(a.out, "matrix.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, keys)
        w.writeheader()
        w.writerows(rows)
    # one row per scene; each cell the verdicts at the factors, coarser to the right;
    # the last column the default's mean Newton iterations per step at each factor
    print("| scene | " + " | ".join(x.replace(":-", "").replace("combined-projection:",
                                                                    "Alg. 2 ")
                                     for x in runs) + " | Newton, default |")
    print("|---|" + "---|" * (len(runs) + 1))
    for scene in scenes:
        cells = []
        for spec in runs:
            rs = [r for r in rows if r["scene"] == scene and f"{r['scheme']}:{r['rule']}" == spec]
            cells.append(" · ".join(verdict(r) for r in rs))
        d = [r for r in rows if r["scene"] == scene and f"{r['scheme']}:{r['rule']}" == runs[0]]
        newton = " · ".join(f"{r['newton_mean']:.1f}" if r.get("newton_mean") else "–" for r in d)
        print(f"| `{scene}` | " + " | ".join(cells) + f" | {newton} |")
    bad = [r for r in rows if r["scheme"] == "combined-projection"
           and r["rule"] == "persistent" and not verdict(r).startswith("ok")]
    worst = max((r.get("excess", 0.0) for r in rows if r["exit"] == 0), default=0.0)
    print(f"\nlargest energy excess of a run that exited 0: {worst:.2e}")
    print(f"default rule: {len(bad)} cell(s) not ok")
    raise SystemExit(1 if bad else 0)


if __name__ == "__main__":
    main()
