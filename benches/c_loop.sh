#!/usr/bin/env bash
# The bar step against a plain C loop of it (issue 19 §4), in one interleaved series.
#
#   bash benches/c_loop.sh [ROUNDS] [N] [H] [T_END]     (defaults 11 1000 2e-7 1e-3: the main job)
#
# Builds benches/bar_step.c with `gcc -O3 -march=native` (the C loop's best case: FMA,
# the host's vector width) and the release binary (no target-cpu: what users build),
# then runs, ROUNDS times in turn: the C loop, `signorini bar --scheme moreau-jean`, the
# same with --portable-arithmetic, and Algorithm 2 (the default scheme), each stepping
# alone (no fields, no plots, no history rows). Prints the medians of µs per step, the
# ratios to the C loop, and checks that the C loop and Moreau–Jean give the same total
# impulse (it is the same discrete problem).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-11}
N=${2:-1000}
H=${3:-2e-7}
T_END=${4:-1e-3}
mkdir -p target/c
gcc -O3 -march=native -o target/c/bar_step benches/bar_step.c -lm
cargo build --release --quiet
BIN=target/release/signorini
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
ours() { # name, extra args…
    local name=$1
    shift
    rm -rf "$OUT/$name"
    "$BIN" bar --elements "$N" --dt "$H" --t-end "$T_END" --no-fields --no-plots \
        --history-every 100000000 --quiet --out "$OUT/$name" "$@"
    python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(s['seconds_per_step']*1e6, s['contact']['total_impulse'] if s.get('contact') else 0)" \
        "$OUT/$name/summary.json"
}
: >"$OUT/series"
for r in $(seq "$ROUNDS"); do
    c=$(target/c/bar_step "$N" "$H" "$T_END" 1)
    mj=$(ours mj --scheme moreau-jean)
    mjp=$(ours mjp --scheme moreau-jean --portable-arithmetic)
    a2=$(ours a2 --scheme combined-projection)
    echo "$c|$mj|$mjp|$a2" >>"$OUT/series"
done
python3 - "$OUT/series" <<'EOF'
import json, statistics, sys
rows = [l.strip().split("|") for l in open(sys.argv[1]) if l.strip()]
c = [json.loads(r[0]) for r in rows]
col = lambda i: [float(r[i].split()[0]) for r in rows]
med = {"C loop (gcc -O3 -march=native)": statistics.median(x["us_per_step"] for x in c),
       "Moreau–Jean": statistics.median(col(1)),
       "Moreau–Jean, --portable-arithmetic": statistics.median(col(2)),
       "Algorithm 2 (default scheme)": statistics.median(col(3))}
base = med["C loop (gcc -O3 -march=native)"]
print(f"{len(rows)} rounds, medians of µs per step:")
for k, v in med.items():
    print(f"  {k:40s} {v:8.3f} µs   {v / base:5.2f}× the C loop")
# per-round ratios: the spread of the series
for i, name in [(1, "Moreau–Jean"), (3, "Algorithm 2")]:
    rr = sorted(float(r[i].split()[0]) / json.loads(r[0])["us_per_step"] for r in rows)
    print(f"  per-round ratio {name}: min {rr[0]:.2f}, median {statistics.median(rr):.2f}, max {rr[-1]:.2f}")
ic, im = c[-1]["total_impulse"], float(rows[-1][1].split()[1])
print(f"total impulse: C loop {ic:.15g}, Moreau–Jean {im:.15g} (relative difference {abs(ic - im) / ic:.1e})")
if abs(ic - im) > 1e-9 * ic:
    sys.exit("the C loop and Moreau–Jean do not solve the same problem")
EOF
