#!/usr/bin/env bash
# Sets everything up (Debian packages), builds, and runs every test: a Release build of the program, the
# examples, the benchmarks and every test (the unit tests of the library and the program, on the build users
# install; examples, determinism reruns, the installed package, the solver without CHOLMOD, real scans, the Python
# package) with ctest, beside them the benchmark harness in its quick mode, that
# README's headline figures come from committed result files, that no internal header includes an algorithm
# header (scripts/include_layers.py), that the C++ lines changed since .clang-format follow it
# (scripts/check_format.sh), the API reference (no Doxygen warning allowed), the manual's pictures (into
# the build folder), the unit tests of the library and the program built with AddressSanitizer and
# UndefinedBehaviorSanitizer (the unit tests again), and each fuzz target for 10 seconds. Ends with
# the time of each stage, checked to add up to the whole run (scripts/check_stage_times.py); doc/build_time.md
# gives the figures of a fresh clone with the compiler cache off on 2 cores.
# Usage: scripts/run_tests.sh        (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/stage_timing.sh
build=${BUILD_DIR:-build}
mkdir -p "$build"
export STAGE_TIMES="$PWD/$build/stage_times.tsv"
: >"$STAGE_TIMES"
run_start=$(date +%s.%N)
timed_stage setup bash scripts/setup.sh
timed_stage "release build" bash scripts/release_build.sh
export CGAL_EXT_BUILT="$build"
# The release tests' long pole is the installed-package test (a header-only build on one core, about 110 s): the
# quick benchmark runs beside them, on the core that leaves idle. The scans are fetched first and nothing is
# rebuilt, so the two write nothing the other reads.
release_tests_and_quick_benchmark() {
  local log="$build/release_tests.log" tests=0 benchmark=0 pid
  bash scripts/fetch_data.sh || return 1
  ctest --test-dir "$build" -j"$(nproc)" --output-on-failure >"$log" 2>&1 &
  pid=$!
  BUILD_DIR="$build" bash scripts/run_benchmarks.sh --quick || benchmark=$?
  wait "$pid" || tests=$?
  cat "$log"
  [ "$tests" -eq 0 ] || echo "run_tests.sh: the release tests failed (exit $tests)" >&2
  [ "$benchmark" -eq 0 ] || echo "run_tests.sh: the quick benchmark failed (exit $benchmark)" >&2
  [ "$tests" -eq 0 ] && [ "$benchmark" -eq 0 ]
}
timed_stage "release tests + quick benchmark" release_tests_and_quick_benchmark
# The quoted figures against their results, and the check itself against the changes it must catch (with
# Debian's Python, which setup.sh gives pytest, whatever python3 comes first on the PATH).
quoted_figures() { python3 scripts/check_quoted_figures.py && /usr/bin/python3 -m pytest -q -p no:cacheprovider test/scripts; }
timed_stage "quoted figures" quoted_figures
timed_stage "include layers" python3 scripts/include_layers.py --check
timed_stage layout bash scripts/check_format.sh
timed_stage "API reference" bash scripts/build_api_docs.sh
timed_stage pictures env BUILD_DIR="$build" DOC_IMAGES_DIR="$build/doc_images" bash scripts/make_doc_images.sh
bash scripts/run_sanitized_tests.sh # times "sanitized build" and "sanitized tests"
bash scripts/run_fuzzers.sh 10      # times "fuzz build" and "fuzz runs"
python3 scripts/check_stage_times.py "$STAGE_TIMES" "$(echo "$(date +%s.%N) - $run_start" | bc)"
