#!/usr/bin/env bash
# Shard + merge overhead of a sharded sweep against the single-process run, on one machine.
#
# Case: `asperity contact normal --seeds 1-8 --grid 512` (the reference statistics on 512²,
# eight realisations, the six reference pressures), one thread per process (RAYON_NUM_THREADS=1).
# Each repeat runs the single process, then four shards one after the other and
# `asperity merge`, and checks the merged outputs byte-identical to the single run's.
# CPU = user + sys from bash `time`. Reported (medians over the repeats):
#   end to end:  (Σ shard CPU + merge CPU − single CPU) / single CPU, and the same in wall time;
#   fixed cost:  4 × the CPU of an empty shard (process start, configuration and its hash,
#                shard file; shard 1 of 16 holds no surface) + the merge CPU, over single CPU.
# The end-to-end figure is a difference of two large numbers: on a loaded machine its noise
# exceeds the overhead; the fixed-cost figure measures the overhead's parts directly.
# Usage: benches/shard_overhead.sh [ASPERITY_BINARY] [GRID] [SEEDS] [REPEATS]
#        (defaults target/release/asperity, 512, 1-8, 3). Prints Markdown rows.
#
# The calibration: `benches/shard_overhead.sh calibrate [ASPERITY_BINARY] [GRID] [REALISATIONS]
# [REPEATS]` (defaults 256, 8, 3): `asperity calibrate calib/reference.toml --grid GRID
# --realisations N` (each realisation with its grid- and patch-check chains), compared on every
# file but calibration_timings.csv; the empty shard is shard 1 of 2N+1.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
kind=normal
if [ "${1:-}" = calibrate ] || [ "${1:-}" = normal ]; then kind=$1; shift; fi
bin=${1:-$repo/target/release/asperity}
repeats=${4:-3}
tmp=$(mktemp -d /tmp/asperity-shard-bench.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
export RAYON_NUM_THREADS=1
if [ "$kind" = calibrate ]; then
    grid=${2:-256}
    seeds=${3:-8}
    case=(calibrate "$repo/calib/reference.toml" --grid "$grid" --realisations "$seeds")
    empty=$((2 * seeds + 1))
else
    grid=${2:-512}
    seeds=${3:-1-8}
    case=(contact normal --seeds "$seeds" --grid "$grid")
    empty=16
fi
# The outputs of the single run that must be byte-identical after the merge.
compared() {
    if [ "$kind" = calibrate ]; then
        (cd "$tmp/single" && ls | grep -v '^calibration_timings.csv$')
    else
        echo normal_sweep.csv normal_sweep_statistics.csv area_ratio.png mean_gap.png kn.png
    fi
}
TIMEFORMAT='%R %U %S'
# "wall cpu" of a command (its output discarded).
measure() { { time "$@" >/dev/null 2>&1; } 2>&1 | awk '{printf "%.3f %.3f\n", $1, $2 + $3}'; }
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
calc() { awk "BEGIN {printf \"%.4f\", $1}"; }
: >"$tmp/rows"
for r in $(seq "$repeats"); do
    rm -rf "$tmp/single" "$tmp/shards" "$tmp/merged" "$tmp/empty"
    read -r sw sc < <(measure "$bin" "${case[@]}" --out-dir "$tmp/single")
    tw=0 tc=0
    for i in 1 2 3 4; do
        read -r w c < <(measure "$bin" "${case[@]}" --shard "$i/4" --out-dir "$tmp/shards")
        tw=$(calc "$tw + $w") tc=$(calc "$tc + $c")
    done
    read -r mw mc < <(measure "$bin" merge "$tmp"/shards/*.json --out-dir "$tmp/merged")
    read -r ew ec < <(measure "$bin" "${case[@]}" --shard "1/$empty" --out-dir "$tmp/empty")
    for f in $(compared); do
        cmp "$tmp/single/$f" "$tmp/merged/$f"
    done
    echo "$sw $sc $(calc "$tw + $mw") $(calc "$tc + $mc") $mc $ec" >>"$tmp/rows"
done
col() { awk -v c="$1" '{print $c}' "$tmp/rows" | median; }
sw=$(col 1) sc=$(col 2) tw=$(col 3) tc=$(col 4) mc=$(col 5) ec=$(col 6)
echo "| ${kind} $([ "$kind" = calibrate ] && echo realisations || echo seeds) | grid | single wall (s) | single CPU (s) | 4 shards + merge wall (s) | CPU (s) | merge CPU (s) | empty shard CPU (s) | end-to-end CPU overhead | wall | fixed-cost overhead | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
printf "| %s | %s² | %.2f | %.2f | %.2f | %.2f | %.3f | %.3f | %+.2f %% | %+.2f %% | %.3f %% | %s |\n" \
    "$seeds" "$grid" "$sw" "$sc" "$tw" "$tc" "$mc" "$ec" \
    "$(calc "100 * ($tc - $sc) / $sc")" "$(calc "100 * ($tw - $sw) / $sw")" \
    "$(calc "100 * (4 * $ec + $mc) / $sc")" "$(cut -d' ' -f1-3 /proc/loadavg)"
echo "(medians of $repeats repeats; merged outputs ($(compared | wc -w) files) byte-identical to the single run in every repeat)"
