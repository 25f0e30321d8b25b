#!/usr/bin/env bash
# Two wearcoef binaries against the same Tamaas run, in turn: whether a change to the solver
# moves the `make bench-peers` ratio (contact_peers.py --alternate).
#   bash benches/peers/alternate.sh OLD_BIN NEW_BIN [ROUNDS [N ...]]
# ROUNDS (default 5) sweeps of each binary per size, at 1 thread; sizes default to 256 512 1024.
set -euo pipefail
cd "$(dirname "$0")/../.."
(($# >= 2)) || { echo "usage: alternate.sh OLD_BIN NEW_BIN [ROUNDS [N ...]]" >&2; exit 2; }
old=$1 new=$2
shift 2
rounds=${1:-5}
(($# > 0)) && shift
for b in "$old" "$new"; do
    [[ -x $b ]] || { echo "alternate.sh: $b is not an executable wearcoef" >&2; exit 2; }
done
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}"
python="$(bash benches/peers/venv.sh)"
"$python" benches/peers/contact_peers.py --alternate "$old" "$new" \
    "$CARGO_TARGET_DIR/peers-alternate" "$rounds" "$@"
