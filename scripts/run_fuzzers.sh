#!/usr/bin/env bash
# Builds the libFuzzer targets (one program, fuzz/fuzz_targets.cpp, started by each target's name) with clang
# (ASan + UBSan) and runs each for SECONDS (default 30), as many at a time as there are cores, from the committed
# seed corpus in fuzz/corpus/<target>. New corpus entries go to a scratch folder; a crash, leak or undefined
# behaviour stops with its input saved under build-sanitize/findings/ and a non-zero exit.
# Usage: scripts/run_fuzzers.sh [SECONDS] [TARGET...]   (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/stage_timing.sh
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_point_reader fuzz_ply fuzz_off fuzz_pcd fuzz_pts_ptx fuzz_las fuzz_edit_json fuzz_sel_def fuzz_region_spec
  fuzz_neighborhoods)
build=${SANITIZE_BUILD_DIR:-build-sanitize}
# The targets are part of the sanitized build: after scripts/run_sanitized_tests.sh there is nothing to build.
fuzz_build() { bash scripts/sanitized_build.sh fuzz_targets; }
# One target for SECONDS; its summary lines go to stdout, its log and any finding under $build/findings/.
fuzz_one() {
  local target=$1 scratch status=0
  scratch=$(mktemp -d)
  mkdir "$scratch/corpus" "$scratch/tmp"
  # TMPDIR: the targets write each input to a file there (fuzz/fuzz_support.h); removed with the scratch folder.
  TMPDIR="$scratch/tmp" "$build/fuzz/$target" "$scratch/corpus" "fuzz/corpus/$target" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=4096 \
    -artifact_prefix="$build/findings/$target-" -print_final_stats=1 >"$build/findings/$target.log" 2>&1 || status=$?
  echo "run_fuzzers.sh: $target for ${seconds} s"
  grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY)" \
    "$build/findings/$target.log" || true
  rm -rf "$scratch"
  [ "$status" -eq 0 ] || { echo "run_fuzzers.sh: $target failed (exit $status); see $build/findings/" >&2; return 1; }
}
# A fuzzer uses one core: the targets run as many at a time as there are cores.
fuzz_runs() {
  mkdir -p "$build/findings"
  local failed=0 i j
  for ((i = 0; i < ${#targets[@]}; i += $(nproc))); do
    local pids=()
    for ((j = i; j < i + $(nproc) && j < ${#targets[@]}; ++j)); do
      fuzz_one "${targets[j]}" >"$build/findings/${targets[j]}.summary" 2>&1 &
      pids+=($!)
    done
    for ((j = 0; j < ${#pids[@]}; ++j)); do
      wait "${pids[j]}" || failed=1
      cat "$build/findings/${targets[i + j]}.summary"
    done
  done
  return "$failed"
}
timed_stage "fuzz build" fuzz_build
timed_stage "fuzz runs" fuzz_runs
