#!/usr/bin/env bash
# The main job on the built-in examples: installs what is missing, builds, then
#   1. renders the built-in mannequin from three views,
#   2. meshes the example t-shirt into one stitched garment on the body (mesh, report, images),
#   3. drapes the t-shirt on the body with the implicit simulator and body contact,
#   4. drapes a cloth sheet held by two corners.
# Outputs go to out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh demo

out=out/demo
rm -rf "$out"
mkdir -p "$out"

echo "==> the built-in body"
./build/sketchdrape info builtin
./build/sketchdrape render builtin --view front --view three-quarter --view left \
  --size 800x1200 -o "$out/body"

echo "==> meshing the example t-shirt"
./build/sketchdrape mesh data/examples/tshirt.json -o "$out/tshirt"

echo "==> draping the t-shirt on the body"
./build/sketchdrape run data/examples/tshirt.json -o "$out/tshirt-drape"

echo "==> draping a sheet"
./build/sketchdrape run data/scenes/hanging-sheet.json -o "$out/sheet"

echo
echo "demo outputs in $out/:"
(cd "$out" && find . -type f | sort | sed 's|^\./|  |')
