#!/usr/bin/env bash
# The peers' venv (SurfaceTopography, ContactMechanics, gsffile, powerlaw from PyPI) at $1,
# made if it does not import; shared by the measured suite and the Python package's tests.
set -euo pipefail
venv="$1"
# A venv moved since it was made imports but its pip no longer runs (its shebang): remade.
if ! "$venv/bin/python" -c "import SurfaceTopography, ContactMechanics, gsffile, pandas, powerlaw; assert powerlaw.__version__ == '2.0.0'" 2>/dev/null ||
    ! "$venv/bin/pip" --version >/dev/null 2>&1; then
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
