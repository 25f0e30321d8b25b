#!/usr/bin/env bash
# A long campaign (the paper profile by default) on this machine, in the background, into a
# store at a fixed path outside the clone; resumable, so stopping only pauses it:
#   scripts/campaign.sh start [PROFILE]   build, freeze the binary, record the plan made
#                                         before the run (first start only), then run under
#                                         nice, one instance at a time on every core (each
#                                         manifest records its peak memory); log in run.log
#   scripts/campaign.sh status [PROFILE]  running or not, `wearcoef status`, the log's tail
#   scripts/campaign.sh stop [PROFILE]    stop it (by pid, waiting); the next start resumes
# The store is $WEARCOEF_CAMPAIGNS/PROFILE (default /var/tmp/wearcoef-campaigns/PROFILE):
# data/, figures/, bin/ (the binary of each commit that ran), plan-before.json, run.log.
set -euo pipefail
cmd=${1:?usage: campaign.sh start|status|stop [PROFILE]}
profile=${2:-paper}
repo=$(cd "$(dirname "$0")/.." && pwd)
root=${WEARCOEF_CAMPAIGNS:-/var/tmp/wearcoef-campaigns}/$profile
target=${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}
pidfile=$root/run.pid
mkdir -p "$root/bin"

running() { [[ -s $pidfile ]] && kill -0 "$(cat "$pidfile")" 2>/dev/null; }

case $cmd in
start)
    if running; then
        echo "campaign $profile already running (pid $(cat "$pidfile")); log $root/run.log"
        exit 0
    fi
    # The binary is frozen under its commit's name: it must be built from that commit.
    if [[ -n $(git -C "$repo" status --porcelain --untracked-files=no) ]]; then
        echo "campaign.sh: $repo has uncommitted changes, and the binary is named by its" \
            "commit: commit them, or start from a clean checkout (git worktree add)" >&2
        exit 2
    fi
    (cd "$repo" && CARGO_TARGET_DIR=$target cargo build --release --locked --quiet)
    commit=$(git -C "$repo" rev-parse --short=12 HEAD)
    bin=$root/bin/wearcoef-$commit
    cp "$target/release/wearcoef" "$bin.tmp" && mv "$bin.tmp" "$bin"
    cp "$repo/pipeline.yaml" "$root/pipeline.yaml"
    if [[ ! -s $root/plan-before.json ]]; then
        "$bin" plan --profile "$profile" --config "$root/pipeline.yaml" --data "$root/data" \
            --json > "$root/plan-before.json.tmp"
        mv "$root/plan-before.json.tmp" "$root/plan-before.json"
    fi
    echo "== $(date -u +%FT%TZ) start, commit $commit" >> "$root/run.log"
    cd "$root"
    nohup nice -n 19 "$bin" run --profile "$profile" --config pipeline.yaml --data data \
        --figures figures --jobs "$(nproc)" --at-once 1 >> run.log 2>&1 < /dev/null &
    echo $! > "$pidfile"
    echo "campaign $profile started (pid $!); log $root/run.log"
    ;;
status)
    if running; then echo "campaign $profile running (pid $(cat "$pidfile"))"
    else echo "campaign $profile not running"; fi
    bin=$(ls -t "$root"/bin/wearcoef-* 2>/dev/null | head -1 || true)
    if [[ -n $bin && -d $root/data/cache ]]; then
        "$bin" status --profile "$profile" --config "$root/pipeline.yaml" --data "$root/data" | tail -12
    fi
    [[ -f $root/run.log ]] && tail -3 "$root/run.log"
    ;;
stop)
    if running; then
        pid=$(cat "$pidfile")
        kill "$pid"
        for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
        if kill -0 "$pid" 2>/dev/null; then kill -9 "$pid"; fi
        echo "== $(date -u +%FT%TZ) stopped" >> "$root/run.log"
        echo "campaign $profile stopped (pid $pid)"
    else
        echo "campaign $profile not running"
    fi
    rm -f "$pidfile"
    ;;
*) echo "usage: campaign.sh start|status|stop [PROFILE]" >&2; exit 2 ;;
esac
