#!/usr/bin/env bash
# Fails when a tracked C++ file differs from what clang-format makes of it (the root
# .clang-format; Debian's clang-format 14, installed by setup.sh test). Fix with
#   git ls-files '*.cpp' '*.hpp' | xargs clang-format -i
# or, for the lines of a change only, `git clang-format`.
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h' '*.cc')
if ! out=$(clang-format --dry-run --Werror "${files[@]}" 2>&1); then
  printf '%s\n' "$out" | grep -E '(warning|error): code should be clang-formatted' | cut -d: -f1 | sort -u |
    sed 's/^/  not formatted: /'
  echo "error: run clang-format -i on the files above (see scripts/check_format.sh)" >&2
  exit 1
fi
echo "==> clang-format: ${#files[@]} files formatted"
