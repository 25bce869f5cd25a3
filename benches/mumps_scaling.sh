#!/usr/bin/env bash
# Where the distributed factor pays (issue 19 §2; docs/sweeps.md, "One large run on several
# ranks"): hex8 cubes of n³ cells (1 m, steel, falling flat at 0.1 m/s on a rigid floor
# with their (n+1)² bottom nodes, Algorithm 2, h = 1e-6 s, 5 steps) run with the serial
# factor (faer's supernodal Cholesky, rayon on the machine's cores) and with MUMPS over
# 1, 2 (and with RANKS="1 2 4", 4) MPI ranks (`--mumps`, OpenBLAS on one thread per rank
# once there are several ranks; the label gives MUMPS' factor memory on the largest rank
# and in all). One row per run from summary.json: model build,
# integrator build (the factor of M̂ and the Delassus columns M̂⁻¹G, one solve per
# contact), mean seconds per step, the peak RSS of the largest process, and the largest
# difference of the contact impulses (or of their total, past the history's per-contact
# columns) from the serial run, relative to the largest. Usage:
# bash benches/mumps_scaling.sh [n ...]   (default: 16 24 31)
set -euo pipefail
cargo build --release -q --features mumps
bin=${CARGO_TARGET_DIR:-target}/release/signorini
dir=target/mumps-scaling
mkdir -p "$dir"
sizes=("$@")
[ ${#sizes[@]} -eq 0 ] && sizes=(16 24 31)
ranks=(${RANKS:-1 2})
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
printf '| cells | dofs | contacts | factor | model (s) | integrator (s) | s/step | peak RSS (GB) | impulses vs serial |\n'
printf '|---|---|---|---|---|---|---|---|---|\n'
row() { # out label
  python3 - "$1" "$2" "$dir/serial$n" "$(( (n + 1) * (n + 1) ))" <<'PY'
import csv, json, sys
out, label, ref, contacts = sys.argv[1:5]
s = json.load(open(out + "/summary.json"))
rss = int(open(out + ".rss").read().split()[-1]) / 1e6
def impulses(d):
    r = list(csv.reader(open(d + "/history.csv")))
    # per contact up to the history's column cap, else the total
    cols = [j for j, h in enumerate(r[0]) if h.startswith("impulse_") or h == "total_impulse"]
    return [[float(x[j]) for j in cols] for x in r[1:]]
a, b = impulses(ref), impulses(out)
scale = max(abs(v) for row in a for v in row) or 1.0
diff = max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb)) / scale
import re
m = re.search(r"factor (\d+) MB on the largest rank, (\d+) MB in all", s["path"])
if m:
    label += f" ({m.group(1)} / {m.group(2)} MB)"
print(f"| {s['elements']} | {s['dofs']} | {contacts} | {label} | {s['model_seconds']:.2f} "
      f"| {s['integrator_seconds']:.2f} | {s['seconds_per_step']:.4f} | {rss:.2f} | {diff:.1e} |")
PY
}
for n in "${sizes[@]}"; do
  cat > "$dir/cube$n.toml" <<TOML
[time]
dt = 1e-6
t_end = 5e-6
[scheme]
kind = "combined-projection"
[[bodies]]
name = "cube"
mesh = { generator = "box", cell = "hex8", cells = [$n, $n, $n], size = [1.0, 1.0, 1.0] }
material = { young = 210e9, poisson = 0.3, density = 7800.0 }
velocity = [0.0, 0.0, -0.1]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "cube"
nodes = "z0"
obstacle = "floor"
[output]
fields = false
plots = false
TOML
  out="$dir/serial$n"
  /usr/bin/time -f '%M' -o "$out.rss" "$bin" run "$dir/cube$n.toml" --quiet --out "$out"
  row "$out" "serial (faer)"
  for np in "${ranks[@]}"; do
    out="$dir/mumps$n-$np"
    blas=()
    [ "$np" -gt 1 ] && blas=(env OPENBLAS_NUM_THREADS=1)
    "${blas[@]}" /usr/bin/time -f '%M' -o "$out.rss" mpirun --oversubscribe -np "$np" \
      "$bin" run "$dir/cube$n.toml" --quiet --mumps --out "$out"
    row "$out" "MUMPS, $np rank(s)"
  done
done
