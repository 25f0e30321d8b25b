#!/usr/bin/env bash
# Every crate that the binary's build (`cargo build --release`) and the wheel's compile must be
# compiled with the features it has under `cargo test --release` (make test). Resolver 2 turns
# features on through dev-dependencies for tests only: one crate whose features differ makes
# cargo rebuild it and everything above it (polars, about 10 min on 2 cores) for the binary.
# The fix is a direct dependency that asks for the feature (see `either`, `bitflags` in
# Cargo.toml). Prints each crate whose features differ; exit 1 if any.
set -euo pipefail
cd "$(dirname "$0")/.."
tree() { cargo tree --locked --quiet -f '{p} [{f}]' --prefix none "$@" | sed 's/ (\*)$//' | sort -u; }
build=$(tree -p wearcoef -e normal,build)
tests=$(tree -p wearcoef -e normal,build,dev)
wheel=$(tree -p wearcoef-python -e normal,build)
# Lines "name vX (...) [features]": a crate of one build whose features the other lacks.
# A crate compiled twice with different features in one tree (build and host) is no mismatch;
# only a crate whose feature set in one build appears in neither set of the other.
bad=$( { comm -23 <(sort <<< "$build") <(sort <<< "$tests") |
    sed 's/^/  binary has, tests lack: /'
    comm -12 <(cut -d' ' -f1,2 <<< "$wheel" | sort -u) <(cut -d' ' -f1,2 <<< "$build" | sort -u) |
        while read -r name version; do
            w=$(grep -F "$name $version " <<< "$wheel" | sort)
            b=$(grep -F "$name $version " <<< "$build" | sort)
            [[ $w == "$b" ]] || echo "  wheel and binary differ: $name $version: ${w//$'\n'/; } against ${b//$'\n'/; }"
        done; } || true)
if [[ -n $bad ]]; then
    echo "error: crates whose features differ between the binary, the tests and the wheel;" \
        "add a direct dependency asking for the feature (Cargo.toml, as for either):" >&2
    echo "$bad" >&2
    exit 1
fi
echo "same features in the binary, the tests and the wheel: $(wc -l <<< "$build") crates"
