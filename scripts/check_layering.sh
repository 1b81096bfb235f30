#!/usr/bin/env bash
# Fails when a library folder includes a header of a folder it must not depend on. The layers
# (README.md, "Layout"): meshing <- garment, meshing <- sim, garment and sim <- scene (the sketch
# file format), and src/ uses all of them. garment/ never sees the sketch file (scene/) or the
# simulator; sim/ never sees garment/ or scene/.
set -euo pipefail
cd "$(dirname "$0")/.."
status=0
check() {  # folder, then the folders its includes may name
  local folder=$1
  shift
  local allowed
  allowed=$(IFS='|'; echo "$*")
  local bad
  bad=$(git ls-files "$folder/*.cpp" "$folder/*.hpp" | xargs grep -nE '^#include "[a-z_]+/' |
    grep -vE "#include \"($allowed)/" || true)
  if [ -n "$bad" ]; then
    printf '%s\n' "$bad" | sed "s/^/  $folder may include only ${allowed//|/, }: /"
    status=1
  fi
}
check meshing meshing
check garment garment meshing
check sim sim meshing
check scene scene garment sim meshing
[ "$status" = 0 ] && echo "==> layering: meshing <- garment, sim <- scene <- src holds"
exit "$status"
