#!/usr/bin/env bash
# Submit a sharded asperity sweep to Slurm: a job array of N shards (`--shard i/N`, one task
# each) and a merge job that starts only when every shard succeeded (--dependency=afterok).
#
# Usage:
#   scripts/slurm/submit-sweep.sh -n SHARDS -o OUT_DIR [-b ASPERITY] [-c CPUS] [-t TIME]
#                                 [-p PARTITION] -- SWEEP ARGUMENTS...
# Example (64 realisations of the reference surface, 8 array tasks of 2 cores):
#   scripts/slurm/submit-sweep.sh -n 8 -c 2 -o runs/kn-64 -- contact normal --seeds 1-64
# or a calibration (32 realisations of calib/reference.toml with their convergence checks,
# one realisation per task of 4 cores):
#   scripts/slurm/submit-sweep.sh -n 32 -c 4 -o runs/calib-32 -- \
#       calibrate "$PWD/calib/reference.toml" --realisations 32
#
# The shards write OUT_DIR/shards/<kind>.shard-<i>-of-<N>.json (logs in OUT_DIR/logs/); the
# merge job writes into OUT_DIR exactly the files a single run of the sweep writes, after
# checking that every shard is present once and all come from the same configuration and the
# same build. Do not pass --out-dir or --shard in the sweep arguments: this script sets them.
# Each task uses RAYON_NUM_THREADS = its --cpus-per-task; results do not depend on the thread
# count.
# Prints the two job ids.
set -euo pipefail

usage() { awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 2; }

here=$(cd "$(dirname "$0")" && pwd)
shards="" out="" bin="" cpus=1 time_limit="" partition=""
while getopts "n:o:b:c:t:p:h" opt; do
    case "$opt" in
        n) shards=$OPTARG ;;
        o) out=$OPTARG ;;
        b) bin=$OPTARG ;;
        c) cpus=$OPTARG ;;
        t) time_limit=$OPTARG ;;
        p) partition=$OPTARG ;;
        *) usage ;;
    esac
done
shift $((OPTIND - 1))
[ "${1:-}" = "--" ] && shift
if [ -z "$shards" ] || [ -z "$out" ] || [ $# -eq 0 ]; then usage; fi
case "$shards" in ''|*[!0-9]*) echo "error: -n must be a positive integer, got '$shards'" >&2; exit 2 ;; esac
# Base 10 whatever the leading zeros: the shard files are named `…-of-8.json` for -n 08 too.
shards=$((10#$shards))
[ "$shards" -gt 0 ] || { echo "error: -n must be a positive integer, got 0" >&2; exit 2; }
for a in "$@"; do
    case "$a" in --out-dir|--out-dir=*|--shard|--shard=*)
        echo "error: '$a' is set by this script; remove it from the sweep arguments" >&2; exit 2 ;;
    esac
done
if [ -z "$bin" ]; then
    bin=$(command -v asperity || true)
    [ -n "$bin" ] || bin="$here/../../target/release/asperity"
fi
[ -x "$bin" ] || { echo "error: asperity binary '$bin' not found or not executable (-b)" >&2; exit 2; }
bin=$(realpath "$bin")
if [ -d "$out/shards" ] && [ -n "$(ls -A "$out/shards")" ]; then
    # Shards of an earlier sweep would make the merge job fail after the whole array ran.
    echo "error: $out/shards is not empty (an earlier sweep's shards); use another -o or empty it" >&2
    exit 2
fi
mkdir -p "$out/shards" "$out/logs"
out=$(realpath "$out")
# Every task runs this copy: a rebuild of the binary while tasks wait in the queue would
# otherwise mix two builds, and the merge refuses shards of different builds (each shard file
# records the build: git commit, source hash, compiler), after the whole array ran.
cp "$bin" "$out/asperity"
bin="$out/asperity"

common=()
[ -n "$time_limit" ] && common+=(--time="$time_limit")
[ -n "$partition" ] && common+=(--partition="$partition")

array_id=$(sbatch --parsable ${common[@]+"${common[@]}"} \
    --job-name=asperity-shard --array="1-$shards" --cpus-per-task="$cpus" --ntasks=1 \
    --output="$out/logs/shard-%a.out" \
    "$here/shard.sbatch" "$shards" "$out/shards" "$bin" "$@")
array_id=${array_id%%;*}
merge_id=$(sbatch --parsable ${common[@]+"${common[@]}"} \
    --job-name=asperity-merge --dependency="afterok:$array_id" --kill-on-invalid-dep=yes \
    --cpus-per-task=1 --ntasks=1 --output="$out/logs/merge.out" \
    "$here/merge.sbatch" "$shards" "$out/shards" "$out" "$bin")
merge_id=${merge_id%%;*}
echo "array job $array_id ($shards shards), merge job $merge_id; results in $out"
