#!/usr/bin/env bash
# Builds the API reference (build/api/html/index.html) from the public headers with doc/api/Doxyfile, and
# fails if Doxygen warns about anything. Usage: scripts/build_api_docs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p build/api
doxygen doc/api/Doxyfile
if [ -s build/api/warnings.txt ]; then
  echo "build_api_docs.sh: Doxygen warnings:" >&2
  cat build/api/warnings.txt >&2
  exit 1
fi
echo "build_api_docs.sh: build/api/html/index.html, no warnings"
