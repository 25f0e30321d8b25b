#!/usr/bin/env bash
# make bench-peers: contact sweeps of wearcoef and Tamaas on the same surfaces, same run.
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
venv="${WEARCOEF_PEERS_VENV:-$CARGO_TARGET_DIR/peers-venv}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import tamaas, numpy" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet tamaas numpy
fi
cargo build --release --locked --quiet
out="$CARGO_TARGET_DIR/peers-run"
"$venv/bin/python" benches/peers/contact_peers.py "$CARGO_TARGET_DIR/release/wearcoef" "$out" "$@"
