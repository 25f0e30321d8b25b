#!/usr/bin/env bash
# Real-client test (`make test-client`, part of `make test`): run the quick profile end to end
# in a scratch directory, then open every artifact with pandas/pyarrow, numpy and Pillow in a
# Python venv this script creates (kept at $CLIENT_VENV, by default beside the build products,
# and reused while it imports).
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
: "${CARGO_TARGET_DIR:=/var/tmp/wearcoef-target}"
bin="${WEARCOEF_BIN:-$CARGO_TARGET_DIR/release/wearcoef}"
venv="${CLIENT_VENV:-$CARGO_TARGET_DIR/client-venv}"
if ! "$venv/bin/python" -c "import numpy, pandas, pyarrow, PIL" 2>/dev/null; then
    echo "creating the client venv in $venv (numpy, pandas, pyarrow, pillow from PyPI)"
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check \
        "numpy>=1.26" "pandas>=2.2" "pyarrow>=16" "pillow>=10" || {
        echo "error: could not install the client venv (needs PyPI access)" >&2
        exit 1
    }
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$repo/pipeline.yaml" "$work/"
cd "$work"
start=$(date +%s%N)
"$bin" run --profile quick --jobs 2
end=$(date +%s%N)
echo "quick profile end to end: $(( (end - start) / 1000000 )) ms"
"$venv/bin/python" "$repo/tests/client/check_artifacts.py" data quick
# Every number of the quick profile as before: value digests against the committed ones
# (tests/golden/quick_values.json; `values.py digest data quick` makes them anew).
"$venv/bin/python" "$repo/tests/client/values.py" digest data quick > values.json
"$venv/bin/python" "$repo/tests/client/values.py" compare "$repo/tests/golden/quick_values.json" values.json
# docs/READING.md's pandas example, as written, on this quick store (its profile line switched).
python3 - "$repo/docs/READING.md" > readme_example.py <<'PY'
import re, sys
text = open(sys.argv[1], encoding="utf-8").read()
section = text.split("## Reading the results with pandas", 1)[1]
block = re.search(r"```python\n(.*?)```", section, re.S).group(1)
assert 'root, profile = "data", "default"' in block, "docs/READING.md's example no longer names its store and profile"
print(block.replace('root, profile = "data", "default"', 'root, profile = "data", "quick"', 1))
PY
"$venv/bin/python" readme_example.py
echo "docs/READING.md example ran"
