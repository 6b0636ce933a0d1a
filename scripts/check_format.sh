#!/usr/bin/env bash
# Checks that the C++ lines a change touches are laid out as .clang-format says: clang-format 14 on the changed
# lines only, so that code written before .clang-format keeps its layout until a change touches it
# (CONTRIBUTING.md, "Layout"). The change: everything since BASE, committed or not; by default BASE is the commit
# that last changed .clang-format.
# Usage: scripts/check_format.sh [BASE]   (exit status 1 and the layout clang-format wants when a line is off)
set -euo pipefail
cd "$(dirname "$0")/.."
if ! git rev-parse --git-dir >/dev/null 2>&1; then
  echo "check_format.sh: not a git checkout: no change to check"
  exit 0
fi
base=${1:-$(git log -1 --format=%H -- .clang-format)}
[ -n "$base" ] || { echo "check_format.sh: .clang-format is not committed: no base to compare with" >&2; exit 1; }
wanted=$(git diff -U0 --no-color -M "$base" -- '*.h' '*.cpp' '*.hpp' '*.cc' |
         clang-format-diff-14 -p1 -style=file)
if [ -n "$wanted" ]; then
  echo "$wanted"
  echo "check_format.sh: the lines above, changed since ${base:0:12}, are not laid out as .clang-format says;" \
       "apply with: git diff -U0 $base | clang-format-diff-14 -p1 -i" >&2
  exit 1
fi
echo "check_format.sh: the changed C++ lines since ${base:0:12} follow .clang-format"
