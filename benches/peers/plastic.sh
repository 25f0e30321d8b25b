#!/usr/bin/env bash
# make bench-plastic: pressure-ceiling sweeps of wearcoef, Tamaas's KatoSaturated and
# ContactMechanics' plastic system on the same surface, ceiling and loads, one thread each,
# in one run (benches/peers/plastic_peers.py).
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python="$(bash benches/peers/venv.sh)"
# ContactMechanics (and SurfaceTopography, muFFT) from PyPI in a venv of their own.
cm_venv="${WEARCOEF_CM_VENV:-$CARGO_TARGET_DIR/cm-venv}"
if [ ! -x "$cm_venv/bin/python" ] || ! "$cm_venv/bin/python" -c "import ContactMechanics" 2>/dev/null; then
  python3 -m venv "$cm_venv" >&2
  "$cm_venv/bin/pip" install --quiet ContactMechanics numpy >&2
fi
cargo build --release --locked --quiet
"$python" benches/peers/plastic_peers.py "$CARGO_TARGET_DIR/release/wearcoef" \
    "$CARGO_TARGET_DIR/plastic-peers-run" "${1:-512}" "${2:-0.25}" "${3:-0.01,0.03,0.05}" \
    --cm-python "$cm_venv/bin/python"
