#!/usr/bin/env bash
# Measures the batch layer (docs/benchmarks.md, "Batch"); not a test: timings never pass or fail
# anything. Prints previews per minute for the example wardrobe (data/batch/wardrobe.json,
# 6 jobs) with -j 1 and -j 2, and the batch layer's own cost per job.
#
#   tests/batch/throughput.sh BUILD_DIR/sketchdrape [STAGE=mesh] [REPEATS=3]
set -euo pipefail
binary=$(realpath "$1")
stage=${2:-mesh}
repeats=${3:-3}
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d /tmp/sd-batch-throughput.XXXXXX)
trap 'rm -rf "$work"' EXIT

now() { date +%s.%N; }
calc() { awk "BEGIN {print $*}"; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

# 1. Previews per minute: the whole wardrobe, every job recomputed (--force), with -j 1 and -j 2,
# and the same 6 merged sketches run directly one after the other; interleaved so that load
# from other processes on the machine hits all three alike.
"$binary" -q batch "$source_dir/data/batch/wardrobe.json" -o "$work/wardrobe" --stage "$stage"
j1=()
j2=()
direct=()
layer=()
for r in $(seq 1 "$repeats"); do
  t0=$(now)
  "$binary" -q batch "$source_dir/data/batch/wardrobe.json" -o "$work/wardrobe" --stage "$stage" -j 1 --force
  t1=$(now)
  j1+=("$(calc "$t1 - $t0")")
  children=$(grep -o '"wall_time_s": [0-9.e+-]*' "$work/wardrobe/batch.json" | awk '{s += $2} END {print s}')
  layer+=("$(calc "($t1 - $t0 - $children) * 1000 / 6")")
  t0=$(now)
  for d in "$work"/wardrobe/jobs/*/; do "$binary" -q "$stage" "$d/sketch.json" -o "$work/direct"; done
  t1=$(now)
  direct+=("$(calc "$t1 - $t0")")
  t0=$(now)
  "$binary" -q batch "$source_dir/data/batch/wardrobe.json" -o "$work/wardrobe" --stage "$stage" -j 2 --force
  t1=$(now)
  j2+=("$(calc "$t1 - $t0")")
done
for name in j1 j2 direct; do
  declare -n list=$name
  t=$(printf '%s\n' "${list[@]}" | median)
  best=$(printf '%s\n' "${list[@]}" | sort -g | head -n 1)
  printf 'wardrobe (6 jobs, %s) %-6s: median %.2f s, best %.2f s of [ %s] -> %.0f (best %.0f) previews/min\n' \
    "$stage" "$name" "$t" "$best" "$(printf '%.2f ' "${list[@]}")" "$(calc "6 * 60 / $t")" "$(calc "6 * 60 / $best")"
done
printf 'batch layer per wardrobe job with -j 1 (batch - children wall times) / 6: median %.1f ms\n' \
  "$(printf '%s\n' "${layer[@]}" | median)"

# 3. Overhead per job: 60 jobs whose child fails at once (edge length out of range, exit 2),
#    through the batch (-j 1) and as direct calls; the difference is the batch layer.
rows="sketch,/edge_length"
for i in $(seq 1 60); do rows+=$'\n'"$source_dir/data/examples/tshirt.json,-$i"; done
echo "$rows" >"$work/instant.csv"
batch_times=()
direct_times=()
layer_times=()
for r in $(seq 1 "$repeats"); do
  t0=$(now)
  "$binary" -q batch "$work/instant.csv" -o "$work/instant" --stage "$stage" -j 1 2>/dev/null || true
  t1=$(now)
  batch_times+=("$(calc "$t1 - $t0")")
  # The children's own wall times, as batch.json records them: the rest is the batch layer.
  children=$(grep -o '"wall_time_s": [0-9.e+-]*' "$work/instant/batch.json" | awk '{s += $2} END {print s}')
  layer_times+=("$(calc "($t1 - $t0 - $children) * 1000 / 60")")
  t0=$(now)
  for d in "$work"/instant/jobs/*/; do "$binary" -q "$stage" "$d/sketch.json" -o "$d" 2>/dev/null || true; done
  t1=$(now)
  direct_times+=("$(calc "$t1 - $t0")")
done
tb=$(printf '%s\n' "${batch_times[@]}" | median)
td=$(printf '%s\n' "${direct_times[@]}" | median)
printf '60 instantly failing jobs: batch -j 1 %.2f s, direct shell loop %.2f s (%.1f ms per child)\n' \
  "$tb" "$td" "$(calc "$td * 1000 / 60")"
printf 'batch layer per job (batch wall time - children wall times) / 60: median %.1f ms\n' \
  "$(printf '%s\n' "${layer_times[@]}" | median)"

# 4. A re-run where every job is done: planning, digests and summary only.
"$binary" -q batch "$source_dir/data/batch/wardrobe.json" -o "$work/wardrobe" --stage "$stage" >/dev/null
reuse=()
for r in $(seq 1 "$repeats"); do
  t0=$(now)
  "$binary" -q batch "$source_dir/data/batch/wardrobe.json" -o "$work/wardrobe" --stage "$stage"
  t1=$(now)
  reuse+=("$(calc "$t1 - $t0")")
done
printf 're-run of the done wardrobe (6 jobs reused): median %.3f s\n' "$(printf '%s\n' "${reuse[@]}" | median)"
