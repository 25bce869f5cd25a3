#!/usr/bin/env bash
# 3-D scaling study for the user guide (docs/speed.md): a slender hex8 bar (n × 8 × 8 cells, square section
# of area π·1e-4 m², ν = 0) hitting a rigid wall with its 81 end-face nodes, Algorithm 2,
# h = 5e-8 s, for n = 40, 400, 4000 (1.0e4, 9.7e4, 9.7e5 dofs), with rayon on 1 and on
# 2 threads. Prints one row per run from summary.json: model build (mesh + parallel
# assembly), integrator build (AMD + supernodal Cholesky of M̂), mean seconds per step
# (the first step includes computing the 81 Delassus columns), and peak memory.
# Usage: bash benches/solid_scaling.sh [n ...]   (from the repository root)
# With STRIDE=k in the environment the runs also write a field frame every k steps
# (on the background writer thread) and print the frame columns of summary.json.
set -euo pipefail
cargo build --release -q
dir=target/solid-scaling
mkdir -p "$dir"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(40 400 4000)
printf '| cells | dofs | threads | model (s) | integrator (s) | steps | s/step | peak RSS (GB) |\n'
printf '|---|---|---|---|---|---|---|---|\n'
for n in "${sizes[@]}"; do
  steps=$(( n <= 40 ? 200 : (n <= 400 ? 40 : 10) ))
  cat > "$dir/bar$n.toml" <<TOML
[time]
dt = 5e-8
t_end = $(python3 -c "print($steps * 5e-8)")
[scheme]
kind = "combined-projection"
[[bodies]]
name = "bar"
mesh = { generator = "box", cell = "hex8", cells = [$n, 8, 8], size = [1.0, 0.017724538509055159, 0.017724538509055159] }
material = { young = 210e9, poisson = 0.0, density = 7800.0 }
velocity = [-0.1, 0.0, 0.0]
[[obstacles]]
name = "wall"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[contacts]]
body = "bar"
nodes = "x0"
obstacle = "wall"
[output]
$( [ -n "${STRIDE:-}" ] && echo "stride = $STRIDE" || echo "fields = false" )
TOML
  for t in 1 2; do
    out="$dir/out$n-$t"
    RAYON_NUM_THREADS=$t /usr/bin/time -f '%M' -o "$out.rss" \
      target/release/signorini run "$dir/bar$n.toml" --quiet --out "$out"
    python3 - "$out" "$t" <<'PY'
import json, sys
out, t = sys.argv[1], sys.argv[2]
s = json.load(open(out + "/summary.json"))
rss = int(open(out + ".rss").read().split()[-1]) / 1e6
print(f"| {s['elements']} | {s['dofs']} | {t} | {s['model_seconds']:.2f} | {s['integrator_seconds']:.2f} "
      f"| {s['steps']} | {s['seconds_per_step']:.4f} | {rss:.2f} |"
      + (f" frames {s['frames']}: writer {s['frame_seconds']:.3f} s, loop waited "
         f"{s['frame_wait_seconds']:.3f} s, loop output share "
         f"{100 * s['output_seconds'] / s['wall_seconds']:.0f} %" if s['frames'] else ""))
PY
  done
done
