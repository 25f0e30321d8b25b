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
# run.pid holds the pid, its start time (field 22 of /proc/PID/stat) and its binary: a pid
# that another process has reused since is never taken for the campaign, nor stopped.
set -euo pipefail
usage() { echo "usage: campaign.sh start|status|stop [PROFILE]" >&2; exit 2; }
cmd=${1:-}
case $cmd in start | status | stop) ;; *) usage ;; esac
(($# <= 2)) || usage
profile=${2:-paper}
repo=$(cd "$(dirname "$0")/.." && pwd)
# Nothing is created for a bad argument: the profile is a plain name declared in
# pipeline.yaml (so no path can climb out of the campaigns folder).
if [[ ! $profile =~ ^[A-Za-z0-9][A-Za-z0-9_-]*$ ]]; then
    echo "campaign.sh: profile '$profile' is not a profile name (letters, digits, '_' and '-')" >&2
    exit 2
fi
declared=$(sed -n '/^profiles:/,/^[^[:space:]#]/p' "$repo/pipeline.yaml" |
    sed -n 's/^  \([A-Za-z0-9_-]*\):.*/\1/p')
if ! grep -qx -- "$profile" <<< "$declared"; then
    echo "campaign.sh: no profile '$profile' in $repo/pipeline.yaml; declared:" $declared >&2
    exit 2
fi
campaigns=${WEARCOEF_CAMPAIGNS:-/var/tmp/wearcoef-campaigns}
root=$campaigns/$profile
target=${CARGO_TARGET_DIR:-/var/tmp/wearcoef-target}
pidfile=$root/run.pid

# The start time of process $1 in clock ticks since boot, or nothing if it is gone.
started() { [[ -r /proc/$1/stat ]] && sed 's/^.*) //' "/proc/$1/stat" | cut -d' ' -f20; }

# Whether the campaign of run.pid still runs: the same pid, started at the recorded time,
# running a binary of this campaign's bin/.
running() {
    [[ -s $pidfile ]] || return 1
    local pid start bin
    read -r pid start bin < "$pidfile" || true
    [[ $pid =~ ^[0-9]+$ && -n ${start:-} && -n ${bin:-} ]] || return 1
    [[ $(started "$pid" 2>/dev/null) == "$start" ]] || return 1
    [[ $(readlink "/proc/$pid/exe" 2>/dev/null) == "$bin" ]]
}

case $cmd in
start)
    mkdir -p "$root/bin"
    if running; then
        echo "campaign $profile already running (pid $(cut -d' ' -f1 "$pidfile")); log $root/run.log"
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
    pid=$!
    # nohup and nice exec the binary: wait until the pid runs it, then record who it is.
    for _ in $(seq 50); do
        [[ $(readlink "/proc/$pid/exe" 2>/dev/null) == "$bin" ]] && break
        sleep 0.1
    done
    echo "$pid $(started "$pid") $bin" > "$pidfile.tmp" && mv "$pidfile.tmp" "$pidfile"
    echo "campaign $profile started (pid $pid); log $root/run.log"
    ;;
status)
    if running; then echo "campaign $profile running (pid $(cut -d' ' -f1 "$pidfile"))"
    else echo "campaign $profile not running"; fi
    bin=$(ls -t "$root"/bin/wearcoef-* 2>/dev/null | head -1 || true)
    if [[ -n $bin && -d $root/data/cache ]]; then
        "$bin" status --profile "$profile" --config "$root/pipeline.yaml" --data "$root/data" | tail -12
    fi
    if [[ -f $root/run.log ]]; then tail -3 "$root/run.log"; fi
    ;;
stop)
    if running; then
        read -r pid start _ < "$pidfile"
        kill "$pid"
        for _ in $(seq 100); do running || break; sleep 0.2; done
        if running; then kill -9 "$pid"; fi
        echo "== $(date -u +%FT%TZ) stopped" >> "$root/run.log"
        echo "campaign $profile stopped (pid $pid)"
    else
        [[ -s $pidfile ]] && echo "campaign.sh: $pidfile names no process of this campaign (it ended, or its pid is now another process's): nothing stopped"
        echo "campaign $profile not running"
    fi
    rm -f "$pidfile"
    ;;
*) usage ;;
esac
