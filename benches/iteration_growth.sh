#!/usr/bin/env bash
# Iterations per load of the paper's 30-load sweep (W/W0 = 0.001 … 0.06, log-spaced) on the
# λ_l/λ_s = 128, λ_s/Δl = 8, H = 0.8 spectrum, in boxes of L/λ_l = 1, 2, 4, … (n = 1024 ·
# L/λ_l): how the iteration count grows with the grid at the paper's own scaling.
# Usage: bash benches/iteration_growth.sh [L/λ_l …] (default 1 2)   (make bench-iteration-growth)
# SEEDS="3128 1 2" solves one realization per seed in every box (default: 3128 alone);
# REALIZATIONS="3 2 1" (one count per box) takes only the first 3, 2, 1 of them in the boxes
# given, in order (fewer where the box is large).
# Prints a markdown table: per box, total and per-load iterations (means over the seeds, with
# the range of the per-load counts), the ratio to L/λ_l = 1, and the iterations of the first,
# middle and last loads (seed by seed).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
cargo build --release --locked --quiet
bin="$CARGO_TARGET_DIR/release/wearcoef"
if [ $# -eq 0 ]; then set -- 1 2; fi
boxes=("$@")
tol="${TOL:-1e-10}"
read -r -a seeds <<<"${SEEDS:-${SEED:-3128}}"
read -r -a counts <<<"${REALIZATIONS:-}"
if [ ${#counts[@]} -eq 0 ]; then
  for _ in "${boxes[@]}"; do counts+=("${#seeds[@]}"); done
fi
if [ ${#counts[@]} -ne ${#boxes[@]} ]; then
  echo "REALIZATIONS has ${#counts[@]} counts for ${#boxes[@]} boxes: give one per box" >&2
  exit 2
fi
for k in "${counts[@]}"; do
  if ! [[ "$k" =~ ^[1-9][0-9]*$ ]] || [ "$k" -gt ${#seeds[@]} ]; then
    echo "REALIZATIONS: $k is not a count from 1 to ${#seeds[@]} (the number of SEEDS)" >&2
    exit 2
  fi
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
loads=$(python3 -c 'import math; print(",".join(repr(math.exp(math.log(0.001)+(math.log(0.06)-math.log(0.001))*i/29)) if 0<i<29 else ("0.001" if i==0 else "0.06") for i in range(30)))')
for b in "${!boxes[@]}"; do
  box=${boxes[$b]}
  n=$((1024 * box))
  for seed in "${seeds[@]:0:${counts[$b]}}"; do
    "$bin" surface --n "$n" --lambda-l-px 1024 --lambda-s-px 8 --hurst 0.8 --seed "$seed" -o "$work/h.npy"
    "$bin" solve --surface "$work/h.npy" --loads "$loads" --tol "$tol" --max-iter 20000 --json >"$work/s${box}_$seed.json"
    echo "L/λl = $box (n = $n), seed $seed done" >&2
  done
done
python3 - "$work" "$tol" "${#boxes[@]}" "${boxes[@]}" "${counts[@]}" "${seeds[@]}" <<'PY'
import json, sys
work, tol, nb = sys.argv[1], sys.argv[2], int(sys.argv[3])
boxes, counts = sys.argv[4:4 + nb], [int(k) for k in sys.argv[4 + nb:4 + 2 * nb]]
seeds = sys.argv[4 + 2 * nb:]
base = None
print(f"tolerance {tol}, 30 loads W/W0 = 0.001 … 0.06, λl/λs = 128, λs/Δl = 8, H = 0.8, "
      f"seeds {', '.join(seeds)}\n")
print("| L/λl | n | iterations (30 loads), seed by seed | per load, mean (range) | ratio to L/λl = 1 | first / middle / last load | convolutions per iteration |")
print("|---|---|---|---|---|---|---|")
for b, k in zip(boxes, counts):
    runs = [json.load(open(f"{work}/s{b}_{s}.json")) for s in seeds[:k]]
    its = [[x["iterations"] for x in r] for r in runs]
    totals = [sum(it) for it in its]
    conv = sum(x["convolutions"] for r in runs for x in r)
    per = [t / len(it) for t, it in zip(totals, its)]
    mean = sum(per) / len(per)
    if base is None:
        base = mean
    spread = f" ({min(per):.1f}–{max(per):.1f})" if len(per) > 1 else ""
    marks = ", ".join(f"{it[0]} / {it[len(it)//2]} / {it[-1]}" for it in its)
    print(f"| {b} | {1024*int(b)} | {' / '.join(map(str, totals))} | {mean:.1f}{spread} | "
          f"{mean/base:.2f} | {marks} | {conv/sum(totals):.2f} |")
PY
