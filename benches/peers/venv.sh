#!/usr/bin/env bash
# The Python environment with Tamaas and numpy from PyPI, at $CARGO_TARGET_DIR/peers-venv
# (created when missing). Prints the interpreter's path.
set -euo pipefail
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
venv="${WEARCOEF_PEERS_VENV:-$CARGO_TARGET_DIR/peers-venv}"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import tamaas, numpy" 2>/dev/null; then
  python3 -m venv "$venv" >&2
  "$venv/bin/pip" install --quiet tamaas numpy >&2
fi
echo "$venv/bin/python"
