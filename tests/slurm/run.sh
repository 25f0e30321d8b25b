#!/usr/bin/env bash
# Slurm test (`make test-slurm`, part of `make test`): a single-node Slurm cluster on this
# machine (scripts/slurm-local.sh), the quick profile submitted with `wearcoef submit`.
#  1. Every artifact the arrays store is byte-identical to a local `wearcoef run` (manifests
#     alike but for their timings), and the run afterwards computes nothing.
#  2. One array task is cancelled (scancel) in the middle of its instances: the store then
#     holds nothing damaged, a resubmission submits exactly what is missing, and the result is
#     again byte-identical to the local run.
# Without Slurm (and unable to install it) it fails when CI is set and skips otherwise.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
: "${CARGO_TARGET_DIR:=/var/tmp/wearcoef-target}"
bin="${WEARCOEF_BIN:-$CARGO_TARGET_DIR/release/wearcoef}"
work=$(mktemp -d)
slurm_dir="$work/slurm"
cleanup() {
    bash "$repo/scripts/slurm-local.sh" stop "$slurm_dir" || true
    rm -rf "$work"
}
trap cleanup EXIT
[[ -n ${KEEP:-} ]] && trap "bash $repo/scripts/slurm-local.sh stop $slurm_dir" EXIT
if ! env_line=$(bash "$repo/scripts/slurm-local.sh" start "$slurm_dir"); then
    if [[ -n ${CI:-} ]]; then
        echo "FAIL: could not start a local Slurm cluster (CI is set, so this is an error)" >&2
        exit 1
    fi
    echo "SKIP: could not start a local Slurm cluster (set CI to make this an error)" >&2
    exit 0
fi
eval "$env_line"
echo "local Slurm up ($SLURM_CONF)"

fail() { echo "FAIL: $*" >&2; exit 1; }

# Wait until no job is queued or running (this cluster runs only ours), at most $1 s.
wait_idle() {
    local limit=$(( $1 * 2 ))
    while [[ -n $(squeue -h -o %i) ]]; do
        (( limit-- > 0 )) || { squeue >&2; fail "jobs still queued after $1 s"; }
        sleep 0.5
    done
}

# Byte-identical stores and figures, manifests equal but for their measurements (`*_seconds`,
# `peak_rss_bytes`, and `results_sha256`, which covers `wall_seconds`).
compare() { # reference dir, other dir
    local a=$1 b=$2
    (cd "$a/data/cache" && find . -path '*/.tmp-*' -prune -o -type f -print | sort) > "$work/files_a"
    (cd "$b/data/cache" && find . -path '*/.tmp-*' -prune -o -type f -print | sort) > "$work/files_b"
    cmp -s "$work/files_a" "$work/files_b" || { diff "$work/files_a" "$work/files_b" | head >&2; fail "$b holds other files than $a"; }
    local n=0
    while read -r f; do
        if [[ $f == */manifest.json ]]; then
            python3 - "$a/data/cache/$f" "$b/data/cache/$f" <<'PY' || fail "manifest $f differs"
import json, sys
def untimed(v):  # timings (*_seconds), memory (peak_rss_bytes); results_sha256 hashes wall_seconds
    if isinstance(v, dict):
        skip = lambda k: k.endswith("_seconds") or k in ("results_sha256", "peak_rss_bytes")
        return {k: untimed(x) for k, x in v.items() if not skip(k)}
    return [untimed(x) for x in v] if isinstance(v, list) else v
a, b = (untimed(json.load(open(p))) for p in sys.argv[1:])
if a != b:
    for k in sorted(set(a) | set(b)):
        if a.get(k) != b.get(k):
            print(f"  {k}: {json.dumps(a.get(k))[:300]} != {json.dumps(b.get(k))[:300]}", file=sys.stderr)
sys.exit(0 if a == b else 1)
PY
        else
            cmp -s "$a/data/cache/$f" "$b/data/cache/$f" || fail "$f differs"
        fi
        n=$((n + 1))
    done < "$work/files_a"
    diff -r "$a/figures" "$b/figures" >/dev/null || fail "figures differ"
    cmp -s "$a/data/quick/index.csv" "$b/data/quick/index.csv" || fail "catalogs differ"
    echo "  $n files of $b identical to $a (manifests but for timings), figures and catalog too"
}

# A run after the arrays must find everything and compute nothing.
run_computes_nothing() {
    local out
    out=$("$bin" run --profile quick --quiet --json)
    python3 -c 'import json,sys; d=json.loads(sys.argv[1]); sys.exit(d["computed"] != 0 or d["reused"] != d["instances"])' "$out" \
        || fail "run after the arrays computed something: $out"
}

mkdir -p "$work/local" "$work/cluster" "$work/cancel"
for d in local cluster cancel; do cp "$repo/pipeline.yaml" "$work/$d/"; done
(cd "$work/local" && "$bin" run --profile quick --jobs 2 --quiet >/dev/null)

echo "case 1: the quick profile through wearcoef submit"
cd "$work/cluster"
"$bin" submit --profile quick --solve-cpus 2 > submit.txt
grep -q "submitted" submit.txt || fail "submit did not submit: $(cat submit.txt)"
"$bin" status --profile quick --json > status_running.json
wait_idle 600
"$bin" status --profile quick --json > status_done.json
python3 - <<'PY' || fail "status does not show every array COMPLETED"
import json
d = json.load(open("status_done.json"))
arrays = [a for c in d["campaigns"] for a in c["arrays"]]
assert arrays, "no campaign listed"
for a in arrays:
    assert a["states"] == {"COMPLETED": a["tasks"]}, a
assert all(s["missing"] == 0 for s in d["per_stage"]), d["per_stage"]
print(f"  status: {len(arrays)} arrays, every task COMPLETED (from {arrays[0]['finished_from']})")
PY
[[ ! -e data/quick/index.parquet ]] || fail "a worker wrote the catalog"
run_computes_nothing
"$bin" verify --data data >/dev/null || fail "verify found damaged entries"
compare "$work/local" "$work/cluster"

echo "case 2: one array task cancelled mid-run, then resubmitted"
cd "$work/cancel"
# Each commit waits 1.5 s, so the contact task is still running when it is cancelled.
WEARCOEF_DEBUG_PAUSE_BEFORE_COMMIT_MS=1500 "$bin" submit --profile quick --solve-cpus 2 > submit1.txt
task=""
for _ in $(seq 1200); do
    task=$(squeue -h -r -t running -o "%F_%K %j" | awk '/L1-contact/ {print $1; exit}' || true)
    stored=$(find data/cache/contact -mindepth 1 -maxdepth 1 -name '[0-9a-f]*' 2>/dev/null | wc -l || true)
    [[ -n $task && $stored -ge 1 ]] && break
    sleep 0.5
done
[[ -n $task ]] || fail "the contact task never ran"
scancel "$task"
echo "  cancelled task $task after $stored contact instance(s) were stored"
wait_idle 600
"$bin" verify --data data >/dev/null || fail "the cancelled task left a damaged entry"
"$bin" status --profile quick --json > status_cancelled.json
missing=$(python3 - <<'PY'
import json
d = json.load(open("status_cancelled.json"))
states = {}
for c in d["campaigns"]:
    for a in c["arrays"]:
        for s, n in a["states"].items():
            states[s] = states.get(s, 0) + n
assert states.get("CANCELLED", 0) >= 1, states
per = {s["stage"]: s for s in d["per_stage"]}
assert per["contact"]["present"] >= 1 and per["contact"]["missing"] >= 1, per["contact"]
print(sum(s["missing"] for s in d["per_stage"]))
PY
) || fail "status after the cancellation is not as expected"
echo "  after the cancellation: $missing instances missing"
"$bin" submit --profile quick --solve-cpus 2 > submit2.txt
grep -q "profile quick: $missing missing instances" submit2.txt \
    || fail "the resubmission did not submit exactly the $missing missing instances: $(tail -2 submit2.txt)"
wait_idle 600
run_computes_nothing
"$bin" verify --data data >/dev/null || fail "verify found damaged entries after the resubmission"
compare "$work/local" "$work/cancel"
echo "slurm test passed"
