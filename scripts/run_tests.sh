#!/usr/bin/env bash
# Sets everything up (Debian packages), builds, and runs every test: the test suite with ctest (Release), the
# benchmark harness in its quick mode, the API reference (no Doxygen warning allowed), the manual's pictures (into
# the build folder), the same test suite built with AddressSanitizer and UndefinedBehaviorSanitizer, and each
# fuzz target for 30 seconds.
# Usage: scripts/run_tests.sh        (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/release_build.sh
build=${BUILD_DIR:-build}
ctest --test-dir "$build" -j"$(nproc)" --output-on-failure
BUILD_DIR="$build" bash scripts/run_benchmarks.sh --quick
bash scripts/build_api_docs.sh
BUILD_DIR="$build" DOC_IMAGES_DIR="$build/doc_images" bash scripts/make_doc_images.sh
bash scripts/run_sanitized_tests.sh
bash scripts/run_fuzzers.sh 30
