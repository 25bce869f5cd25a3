#!/usr/bin/env bash
# The bar step against a plain C loop of it (issue 19 §4, issue 35 §2), in one
# interleaved series, at every size, in flight and in contact, for Moreau–Jean and
# Algorithm 2.
#
#   bash benches/c_loop.sh [ROUNDS] [SIZES]     (defaults: 5 "1000 10000 100000 1000000")
#
# Builds benches/bar_step.c with `gcc -O3 -march=native -ffast-math` (the C loop's best
# case: FMA, the host's vector width, subnormals flushed to zero) and the release binary
# (no target-cpu: what users build). For each N, h = 2e-7 s and two phases:
#   contact  the reference bar (gap 0): the tip on the wall from the first step
#            (contact lasts 3.85e-4 s, longer than every run here);
#   flight   the same bar 1 mm from the wall (reached after 1e-2 s: never here);
# min(1800, max(40, 4e7/N)) steps each. ROUNDS times in turn it runs the C loop and
# `signorini bar` (no fields, plots or history rows) for `moreau-jean` and
# `combined-projection`, and prints per cell the medians of µs per step, ns per dof and
# the ratio to the C loop, with the per-round ratios' range. Both programs solve the
# same discrete problem: the contact cells' total impulses must agree to 1e-9.
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=${1:-5}
SIZES=${2:-"1000 10000 100000 1000000"}
H=2e-7
mkdir -p target/c
gcc -O3 -march=native -ffast-math -o target/c/bar_step benches/bar_step.c -lm
cargo build --release --quiet
BIN=target/release/signorini
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
ours() { # N steps gap scheme
    local d="$OUT/run"
    rm -rf "$d"
    "$BIN" bar --elements "$1" --dt "$H" --t-end "$(python3 -c "print($2 * $H)")" \
        --gap "$3" --scheme "$4" --no-fields --no-plots --history-every 100000000 \
        --quiet --out "$d"
    python3 -c "import json,sys; s=json.load(open(sys.argv[1])); c=s.get('contact') or {}; print(s['seconds_per_step']*1e6, c.get('total_impulse', 0), s.get('subnormals'))" \
        "$d/summary.json"
}
: >"$OUT/series"
for r in $(seq "$ROUNDS"); do
    for n in $SIZES; do
        steps=$(python3 -c "print(min(1800, max(40, round(4e7 / $n))))")
        t_end=$(python3 -c "print($steps * $H)")
        for phase in contact flight; do
            gap=0
            [ "$phase" = flight ] && gap=1e-3
            for s in moreau-jean combined-projection; do
                short=mj
                [ "$s" = combined-projection ] && short=a2
                c=$(target/c/bar_step "$n" "$H" "$t_end" 1 "$gap" "$short")
                o=$(ours "$n" "$steps" "$gap" "$s")
                echo "$n|$phase|$s|$c|$o" >>"$OUT/series"
            done
        done
    done
done
python3 - "$OUT/series" <<'EOF'
import json, statistics, sys
cells = {}
for l in open(sys.argv[1]):
    n, phase, scheme, c, o = l.strip().split("|")
    c = json.loads(c)
    us, imp, sub = o.split()
    cells.setdefault((int(n), phase, scheme), []).append((c["us_per_step"], float(us), c["total_impulse"], float(imp), sub))
bad = []
print(f"{len(next(iter(cells.values())))} rounds, medians (h = 2e-7 s):")
print("| N | phase | scheme | C loop µs | signorini µs | ns/dof | × C (median) | per round |")
print("|---|---|---|---|---|---|---|---|")
for (n, phase, scheme), v in sorted(cells.items()):
    cm = statistics.median(x[0] for x in v)
    om = statistics.median(x[1] for x in v)
    rr = sorted(x[1] / x[0] for x in v)
    name = "Moreau–Jean" if scheme == "moreau-jean" else "Algorithm 2"
    print(f"| {n} | {phase} | {name} | {cm:.4g} | {om:.4g} | {om * 1e3 / (n + 1):.3g} | {om / cm:.2f} | {rr[0]:.2f}–{rr[-1]:.2f} |")
    ic, io, sub = v[-1][2], v[-1][3], v[-1][4]
    if phase == "contact" and abs(ic - io) > 1e-9 * abs(ic):
        bad.append(f"N = {n}, {name}: total impulse C {ic!r} against {io!r}")
    if phase == "flight" and (ic != 0 or io != 0):
        bad.append(f"N = {n}, {name}: an impulse in flight")
print(f"signorini's subnormal mode: {sub}")
if bad:
    sys.exit("the C loop and signorini do not solve the same problem:\n  " + "\n  ".join(bad))
EOF
