#!/usr/bin/env bash
# A single-node Slurm cluster on localhost, for tests and for trying `wearcoef submit`:
#   scripts/slurm-local.sh start DIR   install what is missing, start munged, slurmctld and
#                                      slurmd with everything under DIR; prints the
#                                      `export SLURM_CONF=…` line clients need
#   scripts/slurm-local.sh stop DIR    cancel every job, stop slurmd, slurmctld and munged (by
#                                      pid, waiting for each)
# Needs root (daemons run as root; nothing is written to /etc). Installs slurmctld, slurmd,
# slurm-client and munge with apt-get when absent. Exits non-zero when Slurm cannot be
# started; tests that need it fail rather than skip when CI is set.
set -euo pipefail
cmd=${1:?usage: slurm-local.sh start|stop DIR}
dir=${2:?usage: slurm-local.sh start|stop DIR}
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)

wait_gone() { # pid, seconds
    local pid=$1 n=$(( $2 * 10 ))
    while kill -0 "$pid" 2>/dev/null && (( n-- > 0 )); do sleep 0.1; done
    ! kill -0 "$pid" 2>/dev/null
}

stop_pidfile() { # name, pidfile
    local pid
    [[ -s $2 ]] || return 0
    pid=$(cat "$2")
    if kill -0 "$pid" 2>/dev/null; then
        kill "$pid" 2>/dev/null || true
        if ! wait_gone "$pid" 20; then
            echo "$1 ($pid) ignored SIGTERM for 20 s; sending SIGKILL" >&2
            kill -9 "$pid" 2>/dev/null || true
            wait_gone "$pid" 5 || true
        fi
    fi
    rm -f "$2"
}

if [[ $cmd == stop ]]; then
    export SLURM_CONF="$dir/slurm.conf"
    if [[ -s $dir/slurmctld.pid ]] && kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null; then
        scancel --full --quiet --user="$(id -un)" 2>/dev/null || true
        # Wait for running steps to end before taking their slurmd away.
        for _ in $(seq 100); do
            [[ -z $(squeue -h -t running,completing -o %i 2>/dev/null) ]] && break
            sleep 0.1
        done
    fi
    stop_pidfile slurmd "$dir/slurmd.pid"
    # A slurmstepd left behind by slurmd ignores SIGTERM.
    for pid in $(pgrep -f "slurmstepd.*" 2>/dev/null || true); do
        if grep -qs "$dir" "/proc/$pid/environ" 2>/dev/null || tr '\0' '\n' < "/proc/$pid/cmdline" 2>/dev/null | grep -q "$dir"; then
            kill -9 "$pid" 2>/dev/null || true
        fi
    done
    stop_pidfile slurmctld "$dir/slurmctld.pid"
    stop_pidfile munged "$dir/munge/munged.pid"
    exit 0
fi
[[ $cmd == start ]] || { echo "usage: slurm-local.sh start|stop DIR" >&2; exit 2; }

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    if [[ $(id -u) != 0 ]]; then
        echo "error: Slurm is not installed and installing it needs root (apt-get install slurmctld slurmd slurm-client munge)" >&2
        exit 1
    fi
    echo "installing slurmctld slurmd slurm-client munge (apt-get)" >&2
    apt-get update -qq >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        slurmctld slurmd slurm-client munge >/dev/null
fi

running() { [[ -s $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null; }
if running "$dir/slurmctld.pid" && running "$dir/slurmd.pid"; then
    echo "export SLURM_CONF=$dir/slurm.conf"   # already up
    exit 0
fi

# munge: key, socket, pid, log and seed under DIR; the socket's directory must be o+x.
mkdir -p "$dir/munge" "$dir/spool/ctld" "$dir/spool/d" "$dir/log"
chmod 0711 "$dir" "$dir/munge"
if [[ ! -s $dir/munge/munge.key ]]; then
    head -c 1024 /dev/urandom > "$dir/munge/munge.key"
fi
chmod 0400 "$dir/munge/munge.key"
socket="$dir/munge/munge.socket"
if ! running "$dir/munge/munged.pid"; then
    munged --force --key-file="$dir/munge/munge.key" --socket="$socket" \
        --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" \
        --seed-file="$dir/munge/munged.seed"
fi

# Two free TCP ports (so that several such clusters, e.g. a test's and a user's, can run at
# once), unless SLURM_LOCAL_PORT gives the first of two.
if [[ -n ${SLURM_LOCAL_PORT:-} ]]; then
    ctld_port=$SLURM_LOCAL_PORT; d_port=$((SLURM_LOCAL_PORT + 1))
else
    read -r ctld_port d_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*(x.getsockname()[1] for x in s))')
fi
host=$(hostname -s)
cpus=$(nproc)
# Leave 1 GiB to the system; RealMemory must not exceed what slurmd measures.
mem_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024 ))
user=$(id -un)
cat > "$dir/slurm.conf" <<CONF
ClusterName=wearcoef-local
SlurmctldHost=$host
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
StateSaveLocation=$dir/spool/ctld
SlurmdSpoolDir=$dir/spool/d
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1024
MaxArraySize=1001
DependencyParameters=kill_invalid_depend
SchedulerParameters=batch_sched_delay=0
SchedulerType=sched/backfill
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/log/jobcomp.txt
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
MinJobAge=300
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 300); do
    state=$(sinfo -h -N -o %t 2>/dev/null | head -1 || true)
    [[ $state == idle* || $state == mix* || $state == alloc* ]] && { echo "export SLURM_CONF=$SLURM_CONF"; exit 0; }
    sleep 0.1
done
echo "error: the Slurm node did not become idle within 30 s (state '${state:-none}'); logs in $dir/log" >&2
tail -5 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
exit 1
