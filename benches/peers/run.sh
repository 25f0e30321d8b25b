#!/usr/bin/env bash
# make bench-peers: contact sweeps of wearcoef and Tamaas on the same surfaces, same run.
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python="$(bash benches/peers/venv.sh)"
cargo build --release --locked --quiet
out="$CARGO_TARGET_DIR/peers-run"
"$python" benches/peers/contact_peers.py "$CARGO_TARGET_DIR/release/wearcoef" "$out" "$@"
