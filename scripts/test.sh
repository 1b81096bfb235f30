#!/usr/bin/env bash
# Installs what is missing, builds everything with warnings as errors, and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh -DSD_WERROR=ON -DSD_BUILD_TESTS=ON

jobs=$(nproc 2>/dev/null || echo 2)
echo "==> running the tests"
ctest --test-dir build --output-on-failure -j "$jobs" --timeout 600
