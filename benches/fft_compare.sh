#!/usr/bin/env bash
# Run the FFT-pair benchmark of wearcoef and numpy in the same session and print a
# markdown table (median time per forward+inverse pair, ratio wearcoef/numpy).
# Usage: bash benches/fft_compare.sh   (or make bench-fft)
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
venv="${WEARCOEF_BENCH_VENV:-$CARGO_TARGET_DIR/bench-venv}"
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet numpy
fi
numpy_json=$("$venv/bin/python" benches/fft_numpy.py 512 1024 2048 4096)
cargo bench --bench fft -- --noplot >/dev/null
python3 - "$numpy_json" "$CARGO_TARGET_DIR/criterion" <<'PY'
import json, os, sys
numpy = json.loads(sys.argv[1])
root = sys.argv[2]
def median(threads, n):
    path = os.path.join(root, "fft_pair", f"threads{threads}", str(n), "new", "estimates.json")
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9
print(f"numpy {numpy['numpy']} (pocketfft, 1 thread)\n")
print("| N | numpy pair (ms) | wearcoef 1 thread (ms) | ratio 1T/numpy | wearcoef 2 threads (ms) | ratio 2T/numpy | speed-up 2T vs 1T |")
print("|---|---|---|---|---|---|---|")
for n in [512, 1024, 2048, 4096]:
    t_np = numpy["seconds"][str(n)]
    t1, t2 = median(1, n), median(2, n)
    print(f"| {n} | {t_np*1e3:.2f} | {t1*1e3:.2f} | {t1/t_np:.2f} | {t2*1e3:.2f} | {t2/t_np:.2f} | {t1/t2:.2f} |")
PY
