#!/usr/bin/env bash
# Measures the batch layer (docs/benchmarks.md, "Batch"; docs/batch.md, "Performance"); not a
# test: timings never pass or fail anything. Prints previews per minute for 6 jobs with -j 1 and
# -j 2, and the batch layer's own cost per job.
#   STAGE=mesh: the example wardrobe (data/batch/wardrobe.json, 3 sketches x 2 fabrics), meshing.
#   STAGE=run:  6 drapes: the t-shirt on the mannequin in cotton and jersey (2 s simulated, one
#               front image) and a 16 x 16 hanging sheet (1 m, 2 s) in 4 fabrics; then the
#               children's OpenBLAS threads at -j 2: the batch's default (1 per child) against 2
#               per child (what children got before the batch set it: OpenBLAS's own default,
#               one thread per core).
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
# Sum of the jobs' own wall times (a drape job's figures also hold its report's wall_time_s).
children_wall() { python3 -c 'import json, sys; print(sum(j.get("wall_time_s", 0) for j in json.load(open(sys.argv[1]))["jobs"]))' "$1"; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

manifest="$source_dir/data/batch/wardrobe.json"
if [ "$stage" = run ]; then
  cat >"$work/sheet.json" <<'JSON'
{ "format": "sketchdrape/1",
  "sheet": { "size": [1.0, 1.0], "resolution": [16, 16], "orientation": "vertical",
             "centre": [0, 1.2, 0], "pins": ["top-left", "top-right"] },
  "fabric": "cotton",
  "simulate": { "duration": 2.0, "solver": "cholmod" } }
JSON
  cat >"$work/drapes.json" <<JSON
{ "format": "sketchdrape-batch/1",
  "set": { "/output/images": [ { "view": "front", "size": [300, 450] } ] },
  "jobs": [
    { "sketch": "$source_dir/data/examples/tshirt.json", "matrix": { "/fabric": ["cotton", "jersey"] } },
    { "sketch": "sheet.json", "matrix": { "/fabric": ["cotton", "silk", "denim", "jersey"] } } ] }
JSON
  manifest="$work/drapes.json"
fi

# 1. Previews per minute: the whole batch, every job recomputed (--force), with -j 1 and -j 2,
# and the same 6 merged sketches run directly one after the other; interleaved so that load
# from other processes on the machine hits all three alike.
"$binary" -q batch "$manifest" -o "$work/wardrobe" --stage "$stage"
j1=()
j2=()
direct=()
layer=()
for r in $(seq 1 "$repeats"); do
  t0=$(now)
  "$binary" -q batch "$manifest" -o "$work/wardrobe" --stage "$stage" -j 1 --force
  t1=$(now)
  j1+=("$(calc "$t1 - $t0")")
  children=$(children_wall "$work/wardrobe/batch.json")
  layer+=("$(calc "($t1 - $t0 - $children) * 1000 / 6")")
  t0=$(now)
  # The same OpenBLAS setting the batch gives its children.
  for d in "$work"/wardrobe/jobs/*/; do
    OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1} "$binary" -q "$stage" "$d/sketch.json" -o "$work/direct"
  done
  t1=$(now)
  direct+=("$(calc "$t1 - $t0")")
  t0=$(now)
  "$binary" -q batch "$manifest" -o "$work/wardrobe" --stage "$stage" -j 2 --force
  t1=$(now)
  j2+=("$(calc "$t1 - $t0")")
done
for name in j1 j2 direct; do
  declare -n list=$name
  t=$(printf '%s\n' "${list[@]}" | median)
  best=$(printf '%s\n' "${list[@]}" | sort -g | head -n 1)
  printf '%s (6 jobs, %s) %-6s: median %.2f s, best %.2f s of [ %s] -> %.0f (best %.0f) previews/min\n' \
    "$(basename "$manifest" .json)" "$stage" "$name" "$t" "$best" "$(printf '%.2f ' "${list[@]}")" "$(calc "6 * 60 / $t")" "$(calc "6 * 60 / $best")"
done
printf 'batch layer per job with -j 1 (batch - children wall times) / 6: median %.1f ms\n' \
  "$(printf '%s\n' "${layer[@]}" | median)"

# 2. OpenBLAS threads of the children (drapes only: CHOLMOD's supernodal factorisation is what
#    calls OpenBLAS). -j 2, every job redone, interleaved; wall and CPU time of the whole batch.
if [ "$stage" = run ]; then
  for threads in default 2; do declare -a "wall_$threads=()" "cpu_$threads=()"; done
  for r in $(seq 1 "$repeats"); do
    for threads in default 2; do
      if [ "$threads" = default ]; then
        env -u OPENBLAS_NUM_THREADS /usr/bin/time -f '%e %U %S' -o "$work/time" \
          "$binary" -q batch "$manifest" -o "$work/blas" --stage run -j 2 --force
      else
        OPENBLAS_NUM_THREADS=$threads /usr/bin/time -f '%e %U %S' -o "$work/time" \
          "$binary" -q batch "$manifest" -o "$work/blas" --stage run -j 2 --force
      fi
      read -r e u s <"$work/time"
      declare -n w=wall_$threads c=cpu_$threads
      w+=("$e")
      c+=("$(calc "$u + $s")")
      unset -n w c
    done
  done
  for threads in default 2; do
    declare -n w=wall_$threads c=cpu_$threads
    label=$([ "$threads" = default ] && echo "1 thread per child (batch default)" || echo "2 threads per child (OpenBLAS default)")
    printf 'drapes -j 2, %s: wall median %.2f s [ %s], CPU median %.2f s [ %s]\n' "$label" \
      "$(printf '%s\n' "${w[@]}" | median)" "$(printf '%s ' "${w[@]}")" \
      "$(printf '%s\n' "${c[@]}" | median)" "$(printf '%s ' "${c[@]}")"
    unset -n w c
  done
fi

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
  children=$(children_wall "$work/instant/batch.json")
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
"$binary" -q batch "$manifest" -o "$work/wardrobe" --stage "$stage" >/dev/null
reuse=()
for r in $(seq 1 "$repeats"); do
  t0=$(now)
  "$binary" -q batch "$manifest" -o "$work/wardrobe" --stage "$stage"
  t1=$(now)
  reuse+=("$(calc "$t1 - $t0")")
done
printf 're-run of the done batch (6 jobs reused): median %.3f s\n' "$(printf '%s\n' "${reuse[@]}" | median)"
