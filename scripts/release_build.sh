#!/usr/bin/env bash
# Installs the Debian packages (scripts/setup.sh), configures the Release build in $BUILD_DIR (default: build)
# and builds the given targets (all when none are given). The other scripts start with it. CGAL_EXT_UNIT_TESTS=OFF
# in the environment leaves the unit tests out.
# Usage: scripts/release_build.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build}
# scripts/run_tests.sh builds everything once, then names the folder in CGAL_EXT_BUILT: the scripts it runs after
# that (benchmarks, pictures) neither reconfigure nor rebuild it while its tests read it.
if [ "${CGAL_EXT_BUILT:-}" = "$build" ]; then exit 0; fi
# CGAL_EXT_PROGRAM_ONLY=1 (scripts/run_demo.sh): only the program's packages, and neither tests, benchmarks,
# examples nor the Python module configured. Each run states every part, so the build folder follows the last one.
if [ "${CGAL_EXT_PROGRAM_ONLY:-0}" = 1 ]; then
  bash scripts/setup.sh program
  parts=(-DCGAL_EXT_BUILD_TESTS=OFF -DCGAL_EXT_BUILD_BENCHMARKS=OFF -DCGAL_EXT_BUILD_EXAMPLES=OFF -DCGAL_EXT_BUILD_PYTHON=OFF)
else
  bash scripts/setup.sh
  parts=(-DCGAL_EXT_BUILD_TESTS=ON -DCGAL_EXT_BUILD_BENCHMARKS=ON -DCGAL_EXT_BUILD_EXAMPLES=ON -DCGAL_EXT_BUILD_PYTHON=ON
         -DCGAL_EXT_UNIT_TESTS="${CGAL_EXT_UNIT_TESTS:-ON}")
fi
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${parts[@]}" >/dev/null
if [ $# -gt 0 ]; then
  cmake --build "$build" -j"$(nproc)" --target "$@"
else
  cmake --build "$build" -j"$(nproc)"
fi
