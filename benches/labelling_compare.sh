#!/usr/bin/env bash
# make bench-labelling: periodic cluster labelling of wearcoef (criterion) and
# scipy.ndimage.label + periodic merge on the same maps, same run, 1 thread each.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python=$(bash benches/venv.sh numpy scipy)
cargo build --release --locked --quiet
RAYON_NUM_THREADS=1 cargo bench --locked --bench labelling -- --noplot >/dev/null 2>&1
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$python" benches/labelling_scipy.py \
  "$CARGO_TARGET_DIR/release/wearcoef" "$CARGO_TARGET_DIR/label-maps" "$CARGO_TARGET_DIR/criterion"
