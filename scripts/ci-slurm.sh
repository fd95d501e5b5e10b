#!/bin/bash
# Runs a sharded trace on a real single-node Slurm and checks the merged map's
# checksum against a single run's.
#
# - installs slurm-wlm and munge from Debian's packages when missing (root);
# - starts munged (as the munge user) unless one runs, then slurmctld and
#   slurmd on localhost (one node of nproc CPUs, proctrack/linuxproc,
#   task/none), all configured under a temporary folder and on free ports;
# - submits deploy/slurm's job array (N shards) and its dependent merge;
# - compares the merge's checksum with `trace --json` of the whole run;
# - stops the daemons it started and removes its folder, whatever happens.
# Bounded: every wait has a deadline, and the whole script gives up after
# CI_SLURM_TIMEOUT seconds (default 600).
#
# Usage: scripts/ci-slurm.sh [N_SHARDS] (default 4). Env: APM_BIN (default
# target/release/adaptive-pm, built if missing), APM_ARGS (trace settings).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
shards=${1:-4}
limit=${CI_SLURM_TIMEOUT:-600}
start=$(date +%s)
APM_ARGS=${APM_ARGS:---mode adaptive --n-max 20000 --seed 3}
export APM_ARGS

log() { echo "ci-slurm: $*" >&2; }
left() { echo $((limit - ($(date +%s) - start))); }
# wait_for SECONDS DESCRIPTION COMMAND...: polls COMMAND until it succeeds.
wait_for() {
    local secs=$1 what=$2
    shift 2
    local until=$(($(date +%s) + secs))
    until "$@" >/dev/null 2>&1; do
        if [ "$(date +%s)" -ge "$until" ] || [ "$(left)" -le 0 ]; then
            log "timed out waiting for $what"
            return 1
        fi
        sleep 1
    done
}

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
    log "installing slurm-wlm and munge"
    export DEBIAN_FRONTEND=noninteractive
    timeout "$(left)" apt-get install -y --no-install-recommends slurm-wlm munge >/dev/null ||
        { timeout "$(left)" apt-get update >/dev/null &&
            timeout "$(left)" apt-get install -y --no-install-recommends slurm-wlm munge >/dev/null; }
fi

APM_BIN=${APM_BIN:-$repo/target/release/adaptive-pm}
if [ ! -x "$APM_BIN" ]; then
    log "building $APM_BIN"
    cargo build --release >&2
fi
export APM_BIN

work=$(mktemp -d /tmp/ci-slurm.XXXXXX)
chmod 755 "$work"
started_munge=""
cleanup() {
    set +e
    if [ -n "${SLURM_CONF:-}" ]; then
        scancel --quiet --user="$(id -un)" 2>/dev/null
    fi
    for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid"; do
        [ -s "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null
    done
    for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid"; do
        for _ in $(seq 20); do
            [ -s "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null || break
            sleep 0.5
        done
        [ -s "$pidfile" ] && kill -9 "$(cat "$pidfile")" 2>/dev/null
    done
    if [ -n "$started_munge" ] && [ -s /run/munge/munged.pid ]; then
        kill "$(cat /run/munge/munged.pid)" 2>/dev/null
    fi
    rm -rf "$work"
}
trap cleanup EXIT

# munge: the key comes with the package (created at install); the daemon
# runs as the munge user.
if ! pgrep -x munged >/dev/null; then
    mkdir -p /run/munge && chown munge:munge /run/munge && chmod 755 /run/munge
    if [ ! -s /etc/munge/munge.key ]; then
        runuser -u munge -- mungekey --create >/dev/null 2>&1 ||
            { dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 2>/dev/null &&
                chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key; }
    fi
    runuser -u munge -- munged
    started_munge=1
fi
wait_for 20 munge sh -c 'munge -n | unmunge'

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
host=$(hostname -s)
mkdir -p "$work/state" "$work/spool" "$work/out"
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=apmci
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=30 State=UP
CONF
log "starting slurmctld and slurmd ($(nproc) CPUs)"
slurmctld -c -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
if ! wait_for 60 "an idle node" sh -c "sinfo -h -N -o %t | grep -qx idle"; then
    tail -20 "$work/slurmctld.log" "$work/slurmd.log" >&2
    exit 1
fi

log "single run: $APM_BIN trace cornell $APM_ARGS"
# shellcheck disable=SC2086
single=$("$APM_BIN" trace cornell $APM_ARGS --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["checksum"])')

export APM_SCENE=cornell APM_DIR="$work/out"
log "job array of $shards shards, then the merge"
merge_job=$(cd "$work" && "$repo/deploy/slurm/submit.sh" "$shards" --time=10)
if ! wait_for "$(left)" "merge job $merge_job" sh -c "! squeue -h -j $merge_job | grep -q ."; then
    squeue >&2
    exit 1
fi
# The merge job's log holds its --json line.
merged=$(python3 -c 'import json,sys
for line in open(sys.argv[1]):
    line = line.strip()
    if line.startswith("{"):
        print(json.loads(line)["checksum"])' "$work/apm-merge-$merge_job.log" 2>/dev/null || true)
for f in "$work"/apm-trace-*.log; do
    grep -q '"checksum"' "$f" || { log "a trace task failed: $f"; cat "$f" >&2; exit 1; }
done
elapsed=$(($(date +%s) - start))
if [ -z "$merged" ]; then
    log "the merge job produced no checksum"
    cat "$work"/apm-merge-*.log >&2 || true
    exit 1
fi
if [ "$merged" != "$single" ]; then
    log "FAIL: merged checksum $merged != single run $single"
    exit 1
fi
log "OK: $shards Slurm array tasks merged to checksum $merged = single run ($elapsed s in all)"
