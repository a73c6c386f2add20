#!/usr/bin/env bash
# End-to-end test of the Slurm recipe on a real single-node cluster on the loopback address:
#   1. install Debian's slurm-wlm and munge when sbatch/slurmctld/munged are absent (needs root);
#   2. start munged (unless one already answers), slurmctld and slurmd on 127.0.0.1 with a
#      throwaway configuration, state and logs in a temporary directory;
#   3. submit a small sharded normal-contact sweep (4 array tasks) and a small sharded
#      calibration (2 array tasks) with submit-sweep.sh, one thread per task, each with its
#      dependent merge job; wait for both with a bounded timeout;
#   4. compare the merged outputs with single-process runs (two threads): byte-identical
#      (every file but the wall-time ones);
#   5. stop the daemons it started (by their pids) and remove the temporary directory.
# Usage: scripts/slurm/ci-test.sh [ASPERITY_BINARY]   (default target/release/asperity)
# Called by .ci/run. Exit status non-zero on any failure, with the daemon and job logs printed.
set -euo pipefail

repo=$(cd "$(dirname "$0")/../.." && pwd)
bin=$(realpath "${1:-${ASPERITY_BIN:-$repo/target/release/asperity}}")
[ -x "$bin" ] || { echo "slurm test: asperity binary $bin missing (cargo build --release)" >&2; exit 1; }
timeout_s=${ASPERITY_SLURM_TIMEOUT_S:-300}
started=$(date +%s)

# 1. Slurm and munge.
if ! command -v sbatch >/dev/null || ! command -v slurmctld >/dev/null ||
   ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
    if [ "$(id -u)" != 0 ]; then
        echo "slurm test: sbatch/slurmctld/slurmd/munged missing and not root: cannot install slurm-wlm" >&2
        exit 1
    fi
    echo "slurm test: installing slurm-wlm and munge (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq slurm-wlm munge >/dev/null
fi

work=$(mktemp -d /tmp/asperity-slurm-ci.XXXXXX)
mkdir -p "$work/state" "$work/spool" "$work/log"
our_pids=()
own_cluster=0
ok=0
cleanup() {
    local status=$?
    # Only the jobs of the cluster this script started (never a caller's real cluster).
    if [ "$own_cluster" = 1 ] && command -v squeue >/dev/null; then
        for j in $(squeue -h -o %A 2>/dev/null || true); do scancel "$j" 2>/dev/null || true; done
    fi
    for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid"; do
        [ -s "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null || true
    done
    for pid in ${our_pids[@]+"${our_pids[@]}"}; do kill "$pid" 2>/dev/null || true; done
    sleep 1
    for pidfile in "$work/slurmd.pid" "$work/slurmctld.pid"; do
        [ -s "$pidfile" ] && kill -9 "$(cat "$pidfile")" 2>/dev/null || true
    done
    if [ "$ok" != 1 ]; then
        echo "slurm test FAILED (status $status); logs:" >&2
        for f in "$work"/log/* "$work"/cluster/logs/*; do
            [ -f "$f" ] && { echo "--- $f" >&2; tail -n 40 "$f" >&2; }
        done
    fi
    rm -rf "$work"
}
trap cleanup EXIT

# 2. munge: reuse a running daemon, otherwise start one as the munge user.
if munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
    echo "slurm test: using the running munged"
else
    if [ ! -s /etc/munge/munge.key ]; then
        mungekey --create --keyfile=/etc/munge/munge.key
        chown munge:munge /etc/munge/munge.key
        chmod 0400 /etc/munge/munge.key
    fi
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    rm -f /run/munge/munged.pid
    su -s /bin/sh munge -c /usr/sbin/munged
    for _ in $(seq 50); do [ -s /run/munge/munged.pid ] && break; sleep 0.1; done
    our_pids+=("$(cat /run/munge/munged.pid)")
    munge -n </dev/null | unmunge >/dev/null
    echo "slurm test: started munged (pid ${our_pids[0]})"
fi

# Two free loopback ports for slurmctld and slurmd.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
socks = [socket.socket() for _ in range(2)]
for s in socks: s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in socks])')
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
cat >"$work/slurm.conf" <<CONF
ClusterName=asperity-ci
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/log/slurmctld.log
SlurmdLogFile=$work/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$mem_mb State=UNKNOWN
PartitionName=ci Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
own_cluster=1
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF" -N localhost
for _ in $(seq 100); do
    state=$(sinfo -h -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.3
done
[ "$state" = idle ] || { echo "slurm test: node not idle after 30 s (state '$state')" >&2; exit 1; }
echo "slurm test: cluster up on 127.0.0.1 (ports $ctld_port/$slurmd_port, $(nproc) CPUs) in $(( $(date +%s) - started )) s"

# 3. Two sweeps: 6 surfaces (128², two pressures) of the normal sweep in 4 shards, and a small
#    calibration (3 realisations of the reference statistics on 128² over 128 µm with their grid
#    and patch checks, 2 pressures, 2 amplitudes) in 2 shards; each also as a single process.
sweep=(contact normal --seeds 1-6 --grid 128 --pressures-pa 1e6,5e6)
sed -e 's/^lx_m = .*/lx_m = 1.28e-4/' -e 's/^ly_m = .*/ly_m = 1.28e-4/' \
    -e 's/^nx = .*/nx = 128/' -e 's/^ny = .*/ny = 128/' -e 's/^count = .*/count = 3/' \
    -e 's/^pressures_pa = .*/pressures_pa = [1e6, 5e6]/' \
    -e 's/^amplitude_factors = .*/amplitude_factors = [0.5, 1.0]/' \
    -e 's/^steps_per_cycle = .*/steps_per_cycle = 20/' \
    "$repo/calib/reference.toml" >"$work/calibration.toml"
calibration=(calibrate "$work/calibration.toml")
RAYON_NUM_THREADS=2 "$bin" "${sweep[@]}" --out-dir "$work/single" >/dev/null
RAYON_NUM_THREADS=2 "$bin" "${calibration[@]}" --out-dir "$work/single-calib" >/dev/null 2>&1
submit() { # submit OUT_DIR SHARDS ARGS... → prints the merge job id
    local out=$1 n=$2 submitted
    shift 2
    submitted=$("$repo/scripts/slurm/submit-sweep.sh" -n "$n" -c 1 -o "$out" -b "$bin" -- "$@")
    echo "slurm test: $submitted" >&2
    echo "$submitted" | sed -n 's/.*merge job \([0-9]*\).*/\1/p'
}
merge_ids=("$(submit "$work/cluster" 4 "${sweep[@]}")" "$(submit "$work/cluster-calib" 2 "${calibration[@]}")")
deadline=$(( $(date +%s) + timeout_s ))
for merge_id in "${merge_ids[@]}"; do
    [ -n "$merge_id" ] || { echo "slurm test: a submission failed" >&2; exit 1; }
    while :; do
        job_state=$(scontrol show job "$merge_id" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
        case "$job_state" in
            COMPLETED) break ;;
            FAILED|CANCELLED|TIMEOUT|NODE_FAIL|OUT_OF_MEMORY|PREEMPTED|BOOT_FAIL|DEADLINE)
                echo "slurm test: merge job $merge_id ended $job_state" >&2; exit 1 ;;
        esac
        if [ "$(date +%s)" -gt "$deadline" ]; then
            echo "slurm test: timeout after ${timeout_s} s (merge job $merge_id state '$job_state')" >&2
            squeue >&2 || true
            exit 1
        fi
        sleep 0.5
    done
done

# 4. Byte-identical to the single runs (wall-time files excepted).
for f in normal_sweep.csv normal_sweep_statistics.csv area_ratio.png mean_gap.png kn.png; do
    cmp "$work/single/$f" "$work/cluster/$f"
done
n_shards=$(ls "$work/cluster/shards"/contact-normal.shard-*-of-4.json | wc -l)
[ "$n_shards" = 4 ] || { echo "slurm test: expected 4 shard files, found $n_shards" >&2; exit 1; }
grep -q "^seed-6,5e6," "$work/cluster/normal_sweep.csv"
n_calib=0
for f in "$work/single-calib"/*; do
    name=$(basename "$f")
    [ "$name" = calibration_timings.csv ] && continue
    cmp "$f" "$work/cluster-calib/$name"
    n_calib=$((n_calib + 1))
done
[ "$n_calib" -ge 14 ] || { echo "slurm test: only $n_calib calibration files compared" >&2; exit 1; }
n_shards=$(ls "$work/cluster-calib/shards"/calibrate.shard-*-of-2.json | wc -l)
[ "$n_shards" = 2 ] || { echo "slurm test: expected 2 calibration shard files, found $n_shards" >&2; exit 1; }
ok=1
echo "slurm test: passed: array tasks + dependent merge = single run, byte for byte: normal sweep (4 tasks; normal_sweep.csv, statistics, 3 plots) and calibration (2 tasks; $n_calib files: tables, sidecar, plots) in $(( $(date +%s) - started )) s"
