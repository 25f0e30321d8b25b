#!/usr/bin/env bash
# Iterations per load of the paper's 30-load sweep (W/W0 = 0.001 … 0.06, log-spaced) on the
# λ_l/λ_s = 128, λ_s/Δl = 8, H = 0.8 spectrum, in boxes of L/λ_l = 1, 2, 4, … (n = 1024 ·
# L/λ_l): how the iteration count grows with the grid at the paper's own scaling.
# Usage: bash benches/iteration_growth.sh [L/λ_l …] (default 1 2)   (make bench-iteration-growth)
# Prints a markdown table: per box, total and per-load iterations, the ratio to L/λ_l = 1,
# and the iterations of the first, middle and last loads.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
cargo build --release --locked --quiet
bin="$CARGO_TARGET_DIR/release/wearcoef"
if [ $# -eq 0 ]; then set -- 1 2; fi
boxes=("$@")
tol="${TOL:-1e-10}"
seed="${SEED:-3128}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
loads=$(python3 -c 'import math; print(",".join(repr(math.exp(math.log(0.001)+(math.log(0.06)-math.log(0.001))*i/29)) if 0<i<29 else ("0.001" if i==0 else "0.06") for i in range(30)))')
for box in "${boxes[@]}"; do
  n=$((1024 * box))
  "$bin" surface --n "$n" --lambda-l-px 1024 --lambda-s-px 8 --hurst 0.8 --seed "$seed" -o "$work/h$box.npy"
  "$bin" solve --surface "$work/h$box.npy" --loads "$loads" --tol "$tol" --max-iter 20000 --json >"$work/s$box.json"
  echo "L/λl = $box (n = $n) done" >&2
done
python3 - "$work" "$tol" "${boxes[@]}" <<'PY'
import json, sys
work, tol, boxes = sys.argv[1], sys.argv[2], sys.argv[3:]
rows = {b: json.load(open(f"{work}/s{b}.json")) for b in boxes}
base = None
print(f"tolerance {tol}, 30 loads W/W0 = 0.001 … 0.06, λl/λs = 128, λs/Δl = 8, H = 0.8, one realization\n")
print("| L/λl | n | iterations (30 loads) | per load | ratio to L/λl = 1 | first / middle / last load | convolutions per iteration |")
print("|---|---|---|---|---|---|---|")
for b in boxes:
    r = rows[b]
    it = [x["iterations"] for x in r]
    conv = sum(x["convolutions"] for x in r)
    per = sum(it) / len(it)
    if base is None:
        base = per
    print(f"| {b} | {1024*int(b)} | {sum(it)} | {per:.1f} | {per/base:.2f} | {it[0]} / {it[len(it)//2]} / {it[-1]} | {conv/sum(it):.2f} |")
PY
