#!/usr/bin/env bash
# Installs what is missing, builds everything with warnings as errors, and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh test

# The test executables link the simulator directly: give CHOLMOD's OpenMP loops and OpenBLAS one
# thread, as `sketchdrape` does for itself (docs/simulator.md, "Threads").
export OMP_THREAD_LIMIT=${OMP_THREAD_LIMIT:-1} OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
jobs=$(nproc 2>/dev/null || echo 2)
echo "==> running the tests"
ctest --test-dir build --output-on-failure -j "$jobs" --timeout 600
