#!/usr/bin/env bash
# Builds the library, the program and every test with AddressSanitizer and UndefinedBehaviorSanitizer
# (-O1, line tables) and runs the whole test suite; any memory error, leak or undefined behaviour fails it.
# Usage: scripts/run_sanitized_tests.sh   (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${SANITIZE_BUILD_DIR:-build-sanitize}
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DCGAL_EXT_SANITIZE=ON -DCGAL_EXT_BUILD_EXAMPLES=OFF -DCGAL_EXT_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" -j"$(nproc)" --output-on-failure
