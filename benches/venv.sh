#!/usr/bin/env bash
# The benches' Python environment at $CARGO_TARGET_DIR/bench-venv (or $WEARCOEF_BENCH_VENV),
# with the PyPI packages named as arguments installed when one cannot be imported. Prints
# the interpreter's path. Usage: python=$(bash benches/venv.sh numpy scipy)
set -euo pipefail
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
venv="${WEARCOEF_BENCH_VENV:-$CARGO_TARGET_DIR/bench-venv}"
imports=$(IFS=,; echo "$*")
if ! "$venv/bin/python" -c "import $imports" 2>/dev/null; then
  [ -x "$venv/bin/python" ] || python3 -m venv "$venv" >&2
  "$venv/bin/pip" install --quiet "$@" >&2
fi
echo "$venv/bin/python"
