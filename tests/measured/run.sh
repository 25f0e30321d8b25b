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
if ! "$venv/bin/python" -c "import SurfaceTopography, ContactMechanics, gsffile, pandas, powerlaw; assert powerlaw.__version__ == '2.0.0'" 2>/dev/null; then
    echo "creating the peers' venv in $venv (SurfaceTopography, ContactMechanics, gsffile, powerlaw from PyPI)"
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "SurfaceTopography==1.27.1" "ContactMechanics==1.8.3" "gsffile" "pandas>=2.2" "pyarrow>=16" \
        "matplotlib>=3.8" "powerlaw==2.0.0" || {
        echo "error: could not install SurfaceTopography and ContactMechanics (needs PyPI access)" >&2
        exit 1
    }
fi
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
