#!/usr/bin/env bash
# Sets everything up, builds the program and the Python package, writes the demo's tentacle and opens the
# editing studio on it (doc/studio.md). The server listens on 127.0.0.1 only; Ctrl-C stops it.
# Usage: scripts/run_studio.sh [--port P]   (PORT: any free one by default)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/release_build.sh point-detail cgal_ext_python
build=${BUILD_DIR:-build}
folder="$build/studio"
if [ ! -f "$folder/tentacle.ply" ]; then
  mkdir -p "$folder"
  "$build/src/point-detail" -q demo -o "$folder/demo"
  cp "$folder/demo/tentacle.ply" "$folder/tentacle.ply"
  rm -r "$folder/demo"
fi
PYTHONPATH="$build/python" exec /usr/bin/python3 -m cgal_ext.studio "$folder/tentacle.ply" --open "$@"
