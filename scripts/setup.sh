#!/usr/bin/env bash
# Shared set-up for demo.sh and test.sh: installs the missing Debian packages, then configures
# and builds sketchdrape (Release) in build/. Extra arguments go to CMake's configure step.
set -euo pipefail
cd "$(dirname "$0")/.."

# Every Debian package the project builds, tests and demos with (see docs/dependencies.md).
packages=(
  cmake g++ make pkg-config
  libeigen3-dev libcgal-dev libassimp-dev assimp-testmodels libsuitesparse-dev
  libopenblas0-pthread libfcl-dev libosmesa6-dev libpng-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev
  libgtest-dev libbenchmark-dev
  python3-jsonschema  # tests validate the example sketch files against data/schema/
  chromium  # tests/batch: the batch contact sheet (index.html) loads in headless Chromium
  slurmctld slurmd slurm-client munge  # tests/batch/slurm_test.sh: a one-node Slurm cluster
  gnuplot-nox  # sketchdrape bench: the work-precision plots (optional: the CSV is written without it)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "==> installing Debian packages: ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "error: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    sudo_cmd=(sudo)
  fi
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

jobs=$(nproc 2>/dev/null || echo 2)
echo "==> configuring build/ (Release)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
echo "==> building with $jobs jobs"
cmake --build build -j "$jobs"
