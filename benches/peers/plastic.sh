#!/usr/bin/env bash
# make bench-plastic: pressure-ceiling sweeps of wearcoef and Tamaas's KatoSaturated on the same
# surface, ceiling and loads, one thread each, in one run (benches/peers/plastic_peers.py).
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python="$(bash benches/peers/venv.sh)"
cargo build --release --locked --quiet
"$python" benches/peers/plastic_peers.py "$CARGO_TARGET_DIR/release/wearcoef" \
    "$CARGO_TARGET_DIR/plastic-peers-run" "${1:-512}" "${2:-0.25}" "${3:-0.01,0.03,0.05}"
