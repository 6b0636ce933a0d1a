#!/usr/bin/env bash
# Installs the Debian packages (scripts/setup.sh), configures the Release build in $BUILD_DIR (default: build)
# and builds the given targets (all when none are given). The other scripts start with it. CGAL_EXT_UNIT_TESTS=OFF
# in the environment leaves the unit tests out (scripts/run_tests.sh runs them in its sanitized pass).
# Usage: scripts/release_build.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${BUILD_DIR:-build}
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCGAL_EXT_UNIT_TESTS="${CGAL_EXT_UNIT_TESTS:-ON}" >/dev/null
if [ $# -gt 0 ]; then
  cmake --build "$build" -j"$(nproc)" --target "$@"
else
  cmake --build "$build" -j"$(nproc)"
fi
