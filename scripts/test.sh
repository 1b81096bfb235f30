#!/usr/bin/env bash
# Installs what is missing, builds everything with warnings as errors, and runs every test.
#   test.sh              the whole suite in build/
#   test.sh --sanitize   the unit tests of the input-facing modules (meshing, garment, scene: the
#                        sketch reader, the body loader, the quad filler) built with
#                        AddressSanitizer and UBSan in build-asan/ (docs/cli.md, "Fuzzing")
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = --sanitize ]; then
  SD_PACKAGES_ONLY=1 ./scripts/setup.sh test
  export CCACHE_BASEDIR="$PWD"
  jobs=$(nproc 2>/dev/null || echo 2)
  units=(meshing_tests garment_tests scene_tests)
  # -O1 -g1 (line tables): what ASan needs for its reports; -O2 -g took 2.4 times the CPU and
  # 1.6 times the memory on garment's CGAL files (docs/cli.md, "Fuzzing and sanitizers").
  echo "==> configuring build-asan/ (-O1 -g1, ASan + UBSan)"
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DSD_WERROR=ON -DSD_SANITIZE=ON \
    -DSD_BUILD_TESTS=ON -DSD_BUILD_BENCHMARKS=OFF -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >/dev/null
  cmake --build build-asan -j "$jobs" --target "${units[@]}"
  export OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1
  # Leaks: Mesa and assimp keep process-lifetime allocations; UBSan findings are errors.
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  echo "==> running the sanitized unit tests"
  # PatchFillOptimality searches every layout of a family (17-31 s each in Release, over 5 min
  # under ASan): the Release suite runs it; here the other fill tests cover the same code.
  ctest --test-dir build-asan --output-on-failure -j "$jobs" --timeout 1200 \
    -L "/($(IFS='|'; echo "${units[*]}"))$" -E PatchFillOptimality  # labels: KIND/NAME
  exit
fi
./scripts/setup.sh test
./scripts/check_format.sh
./scripts/check_layering.sh

# The test executables link the simulator directly: give CHOLMOD's OpenMP loops and OpenBLAS one
# thread, as `sketchdrape` does for itself (docs/simulator.md, "Threads").
export OMP_THREAD_LIMIT=${OMP_THREAD_LIMIT:-1} OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
jobs=$(nproc 2>/dev/null || echo 2)
echo "==> running the tests"
ctest --test-dir build --output-on-failure -j "$jobs" --timeout 600
