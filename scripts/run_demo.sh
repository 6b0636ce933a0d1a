#!/usr/bin/env bash
# Sets everything up, builds the program, and runs its demo on a built-in model.
# Usage: scripts/run_demo.sh [OUTPUT_DIR]   (default: point-detail-demo)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${BUILD_DIR:-build}
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)" --target point-detail
"$build/src/point-detail" demo -o "${1:-point-detail-demo}"
