#!/usr/bin/env bash
# Builds the fuzz targets in build-fuzz/ (clang, ASan + UBSan + libFuzzer) and runs each for
# SECONDS (default 60) on a seed corpus made from data/ and tests/garment/bad/. A crash leaves
# crash-* files in build-fuzz/fuzz-<target>/ and makes this script exit 1; turn each into a test.
#   tests/fuzz/run.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(sketch_parser body_loader fill_sides)
SD_PACKAGES_ONLY=1 ./scripts/setup.sh fuzz
export CCACHE_BASEDIR="$PWD"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DSD_BUILD_FUZZERS=ON -DSD_BUILD_TESTS=OFF \
  -DSD_BUILD_BENCHMARKS=OFF -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >/dev/null
cmake --build build-fuzz -j "$(nproc 2>/dev/null || echo 2)" \
  --target $(printf '%s_fuzz ' "${targets[@]}")

# Seed corpora: every sketch and scene, the bad-input suite, small meshes of assimp's test
# models, and a few side-count patterns.
seeds=build-fuzz/seeds
rm -rf "$seeds"
mkdir -p "$seeds"/sketch_parser "$seeds"/body_loader "$seeds"/fill_sides
cp data/examples/*.json data/scenes/*.json tests/garment/bad/*.json "$seeds"/sketch_parser/
models=/usr/share/assimp/models
i=0
for f in "$models"/OBJ/box.obj "$models"/OBJ/concave_polygon.obj "$models"/OFF/*.off \
  "$models"/PLY/cube.ply "$models"/STL/triangle.stl "$models"/STL/Spider_ascii.stl; do
  [ -f "$f" ] && [ "$(stat -c %s "$f")" -lt 200000 ] || continue
  case "$f" in *.obj) p='\x00' ;; *.off) p='\x01' ;; *.ply) p='\x02' ;; *) p='\x03' ;; esac
  { printf "$p"; cat "$f"; } >"$seeds/body_loader/seed-$i"
  i=$((i + 1))
done
for s in '\x03\x03\x03\x03' '\x04\x05\x02\x05\x03' '\x01\x01\x01' '\x3f\x01\x01\x01' \
  '\x09\x0b\x0d\x0f\x11\x13'; do
  printf "$s" >"$seeds/fill_sides/$(echo "$s" | tr -d '\\x')"
done

status=0
for t in "${targets[@]}"; do
  dir=build-fuzz/fuzz-$t
  mkdir -p "$dir/corpus"
  start=$(date +%s)
  if ! (cd "$dir" && ASAN_OPTIONS=detect_leaks=0 "../tests/fuzz/${t}_fuzz" corpus "../seeds/$t" \
      -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
      >run.log 2>&1); then
    echo "==> $t: FAILED (see $dir/run.log and $dir/crash-*)"
    # The sanitizer's report and the input, here too: a CI log shows only what was printed.
    grep -m1 -B2 -A40 -E "ERROR: (AddressSanitizer|UndefinedBehaviorSanitizer|libFuzzer)|runtime error|==ERROR|SUMMARY|Test unit written" \
      "$dir/run.log" | head -60 || tail -40 "$dir/run.log"
    for crash in "$dir"/crash-* "$dir"/timeout-* "$dir"/oom-* "$dir"/leak-*; do
      [ -f "$crash" ] || continue
      echo "--- $crash (base64):"
      head -c 6000 "$crash" | base64
    done
    status=1
  else
    echo "==> $t: clean, $(grep -m1 stat::number_of_executed_units "$dir/run.log" | awk '{print $2}') runs in $(($(date +%s) - start)) s"
  fi
done
exit $status
