#!/usr/bin/env bash
# Sets everything up, builds the program, and runs its demo on a built-in model.
# Usage: scripts/run_demo.sh [OUTPUT_DIR]   (default: point-detail-demo)
set -euo pipefail
cd "$(dirname "$0")/.."
CGAL_EXT_PROGRAM_ONLY=1 bash scripts/release_build.sh point-detail # the program's packages only: the demo's minutes
build=${BUILD_DIR:-build}
"$build/src/point-detail" demo -o "${1:-point-detail-demo}"
