#!/usr/bin/env bash
# The Python package (`make test-python`, part of `make test`): crates/python built into a
# wheel by pip (maturin from PyPI), installed into a fresh venv, and checked against the
# binary on the same inputs; then installed beside SurfaceTopography (the measured suite's
# venv) for a real instrument file and the worked example.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
: "${CARGO_TARGET_DIR:=/var/tmp/wearcoef-target}"
export CARGO_TARGET_DIR
bin="${WEARCOEF_BIN:-$CARGO_TARGET_DIR/release/wearcoef}"
measured_venv="${MEASURED_VENV:-$CARGO_TARGET_DIR/measured-venv}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/venv"
pip="$work/venv/bin/pip --quiet --disable-pip-version-check"
# The wheel, built as a user's `pip install crates/python` builds it.
$pip wheel --no-deps --wheel-dir "$work/wheels" "$repo/crates/python" || {
    echo "error: could not build the wheel (needs PyPI access for maturin)" >&2
    exit 1
}
$pip install "$work/wheels"/wearcoef-*.whl || {
    echo "error: could not install the wheel's dependencies (numpy, pandas, pyarrow from PyPI)" >&2
    exit 1
}
"$work/venv/bin/python" "$repo/tests/python/check_package.py" "$bin" "$work/package"
# Beside SurfaceTopography: the venv of the measured suite, made if missing.
bash "$repo/tests/measured/venv.sh" "$measured_venv"
"$measured_venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps \
    "$work/wheels"/wearcoef-*.whl
"$measured_venv/bin/python" -W ignore "$repo/tests/python/check_topography.py" "$bin" "$work/topography"
(cd "$work" && MPLBACKEND=Agg "$measured_venv/bin/python" "$repo/examples/python_wear.py" \
    --out "$work/example")
"$measured_venv/bin/python" "$repo/tests/python/check_example.py" "$work/example" "$bin"
"$measured_venv/bin/pip" uninstall --quiet --yes wearcoef
