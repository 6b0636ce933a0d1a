#!/usr/bin/env bash
# Builds the library, the program and every test with AddressSanitizer and UndefinedBehaviorSanitizer
# (scripts/sanitized_build.sh, which builds the fuzz targets too) and runs the test suite but for the parts
# left to the Release pass (below); any memory error, leak or undefined behaviour fails it.
# Usage: scripts/run_sanitized_tests.sh   (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/stage_timing.sh
build=${SANITIZE_BUILD_DIR:-build-sanitize}
timed_stage "sanitized build" bash scripts/sanitized_build.sh
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# Left to the Release pass: the installed-package test (it builds a separate consumer project without
# sanitizers) and the determinism reruns of every subcommand on the armadillo (each subcommand runs under the
# sanitizers in the program's own tests; the reruns are half the pass's test time), which it does not build;
# the editing tests rerun on the diffusion's portable path (the stencil's own tests run it here); and the demo's
# pictures (every subcommand and picture it makes runs here in the program's own tests).
timed_stage "sanitized tests" ctest --test-dir "$build" -j"$(nproc)" --output-on-failure \
  -E '^(installed_package_consumer|portable_diffusion_.*|Cli\.RenderAndDemoWritePictures)$'
