#!/usr/bin/env bash
# Installs the Debian packages (scripts/setup.sh), configures the sanitized build in $SANITIZE_BUILD_DIR
# (default: build-sanitize) and builds the given targets (all when none are given): the library, the program
# and every test with AddressSanitizer and UndefinedBehaviorSanitizer (clang, -O1, the test programs -O0, line
# tables), and the libFuzzer targets of the program's readers. One build serves scripts/run_sanitized_tests.sh and
# scripts/run_fuzzers.sh. clang, not GCC: it compiles the sanitized library in about two thirds of GCC's time
# (doc/build_time.md).
# Usage: scripts/sanitized_build.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${SANITIZE_BUILD_DIR:-build-sanitize}
cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCGAL_EXT_SANITIZE=ON -DCGAL_EXT_BUILD_FUZZERS=ON \
  -DCGAL_EXT_BUILD_EXAMPLES=OFF -DCGAL_EXT_BUILD_BENCHMARKS=OFF -DCGAL_EXT_UNIT_TESTS=ON \
  -DCGAL_EXT_TEST_WITHOUT_CHOLMOD=OFF -DCGAL_EXT_TEST_DETERMINISM=OFF >/dev/null
if [ $# -gt 0 ]; then
  cmake --build "$build" -j"$(nproc)" --target "$@"
else
  cmake --build "$build" -j"$(nproc)"
fi
