#!/usr/bin/env bash
# Measured surfaces against their peers (`make test-measured`, part of `make test`): every
# topography reader on files SurfaceTopography writes, compared with what SurfaceTopography
# reads from them; and the tail tests of `fit` against the `powerlaw` package. The venv
# (SurfaceTopography, ContactMechanics and powerlaw from PyPI) is kept at $MEASURED_VENV, by
# default beside the build products, and reused while it imports.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
: "${CARGO_TARGET_DIR:=/var/tmp/wearcoef-target}"
bin="${WEARCOEF_BIN:-$CARGO_TARGET_DIR/release/wearcoef}"
venv="${MEASURED_VENV:-$CARGO_TARGET_DIR/measured-venv}"
bash "$repo/tests/measured/venv.sh" "$venv"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$venv/bin/python" -W ignore "$repo/tests/measured/check_readers.py" "$bin" "$work/readers"
# Likelihood-ratio tests of the cluster-area tail against powerlaw's, on the same areas.
"$venv/bin/python" "$repo/tests/measured/check_powerlaw.py" "$bin" "$work/powerlaw"
# The non-periodic solve against ContactMechanics' free-boundary half-space.
"$venv/bin/python" -W ignore "$repo/tests/measured/check_contact.py" "$bin" "$work/contact"
# The worked example as a user runs it, then its numbers recomputed.
(cd "$work" && MPLBACKEND=Agg "$venv/bin/python" "$repo/examples/measured_surface.py" \
    --wearcoef "$bin" --out "$work/example")
"$venv/bin/python" "$repo/tests/measured/check_wear.py" "$work/example" "$bin"
