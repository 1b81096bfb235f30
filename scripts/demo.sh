#!/usr/bin/env bash
# The main job on the built-in example: installs what is missing, builds, and renders the
# built-in mannequin from three views into out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh

out=out/demo
mkdir -p "$out"
./build/sketchdrape info builtin
./build/sketchdrape render builtin --view front --view three-quarter --view left \
  --size 800x1200 -o "$out"
echo
echo "demo outputs in $out/:"
ls -1 "$out" | sed 's/^/  /'
