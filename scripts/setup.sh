#!/usr/bin/env bash
# Shared set-up for demo.sh and test.sh: installs the missing Debian packages, then configures
# build/ (Release, warnings as errors, tests on) and builds the targets given.
#   setup.sh demo              packages for the demo; builds the sketchdrape binary only
#   setup.sh test              every package the tests use; builds everything
#   setup.sh fuzz              with SD_PACKAGES_ONLY=1: also clang and libFuzzer (tests/fuzz)
# Both configure build/ the same way, so running demo.sh then test.sh compiles each file once.
set -euo pipefail
cd "$(dirname "$0")/.."
purpose=${1:-test}

# The Debian packages the binary builds and runs with (see docs/dependencies.md).
packages=(
  cmake g++ make pkg-config ccache
  libeigen3-dev libcgal-dev libassimp-dev assimp-testmodels libsuitesparse-dev
  libopenblas0-pthread libfcl-dev libtbb-dev libosmesa6-dev libpng-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libssl-dev
  libgtest-dev libbenchmark-dev
)
if [ "$purpose" = test ]; then
  packages+=(
    python3-jsonschema  # tests validate the example sketch files against data/schema/
    chromium  # tests/batch: the batch contact sheet (index.html) loads in headless Chromium
    python3-ezdxf  # tests/cli: the sewing pattern's pattern.dxf is read back with a real DXF library
    slurmctld slurmd slurm-client munge  # tests/batch/slurm_test.sh: a one-node Slurm cluster
    clang-format  # scripts/check_format.sh: test.sh fails on C++ that .clang-format would change
    gnuplot-nox  # sketchdrape bench: the work-precision plots (optional: the CSV is written without it)
  )
fi
if [ "$purpose" = fuzz ]; then
  packages+=(clang-14 libclang-rt-14-dev)  # tests/fuzz/run.sh: libFuzzer with ASan and UBSan
fi

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

# SD_PACKAGES_ONLY=1: stop here (test.sh --sanitize and tests/fuzz/run.sh configure their own
# build folders).
if [ "${SD_PACKAGES_ONLY:-0}" = 1 ]; then exit 0; fi

# ccache keeps compiled objects between builds and between checkouts of the project (paths are
# taken relative to the checkout), so a rebuild after a pull or in a second worktree is quick.
export CCACHE_BASEDIR="$PWD"
jobs=$(nproc 2>/dev/null || echo 2)
echo "==> configuring build/ (Release)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DSD_WERROR=ON -DSD_BUILD_TESTS=ON \
  -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >/dev/null
if [ "$purpose" = demo ]; then
  echo "==> building sketchdrape with $jobs jobs"
  cmake --build build -j "$jobs" --target sketchdrape
else
  echo "==> building everything with $jobs jobs"
  cmake --build build -j "$jobs"
fi
