#!/usr/bin/env bash
# Run the FFT-pair benchmark of wearcoef, FFTW (pyFFTW, FFTW_MEASURE, 1 and 2 threads) and
# numpy in the same session and print a markdown table (median time per forward+inverse
# pair, ratios of wearcoef to each peer at the same thread count).
# Usage: bash benches/fft_compare.sh   (or make bench-fft)
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python=$(bash benches/venv.sh numpy pyfftw)
peers_json=$("$python" benches/fft_numpy.py 512 1024 2048 4096)
cargo bench --bench fft -- --noplot >/dev/null
python3 - "$peers_json" "$CARGO_TARGET_DIR/criterion" <<'PY'
import json, os, sys
peers = json.loads(sys.argv[1])
root = sys.argv[2]
def median(threads, n, group="fft_pair"):
    path = os.path.join(root, group, f"threads{threads}", str(n), "new", "estimates.json")
    with open(path) as f:
        return json.load(f)["median"]["point_estimate"] * 1e-9
sec = peers["seconds"]
print(f"numpy {peers['numpy']} (pocketfft, 1 thread); pyFFTW {peers.get('pyfftw')} (FFTW_MEASURE)\n")
print("| N | FFTW 1T (ms) | wearcoef 1T (ms) | 1T / FFTW 1T | FFTW 2T (ms) | wearcoef 2T (ms) | 2T / FFTW 2T | wearcoef 2T speed-up | numpy (ms) | 1T / numpy |")
print("|---|---|---|---|---|---|---|---|---|---|")
for n in [512, 1024, 2048, 4096]:
    k = str(n)
    t1, t2 = median(1, n), median(2, n)
    f1, f2, npy = sec["fftw1"][k], sec["fftw2"][k], sec["numpy"][k]
    print(f"| {n} | {f1*1e3:.2f} | {t1*1e3:.2f} | {t1/f1:.2f} | {f2*1e3:.2f} | {t2*1e3:.2f} | {t2/f2:.2f} | {t1/t2:.2f} | {npy*1e3:.2f} | {t1/npy:.2f} |")
print("\nSingle precision (the solver's preconditioner), 1 thread:\n")
print("| N | FFTW f32 (ms) | wearcoef f32 (ms) | f32 / FFTW f32 | wearcoef f32 / wearcoef f64 | FFTW f32 / FFTW f64 |")
print("|---|---|---|---|---|---|")
for n in [512, 1024, 2048, 4096]:
    k = str(n)
    s1, t1 = median(1, n, "fft_pair_f32"), median(1, n)
    g1, f1 = sec["fftw1_f32"][k], sec["fftw1"][k]
    print(f"| {n} | {g1*1e3:.2f} | {s1*1e3:.2f} | {s1/g1:.2f} | {s1/t1:.2f} | {g1/f1:.2f} |")
PY
