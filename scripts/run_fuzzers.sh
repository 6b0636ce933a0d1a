#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each for SECONDS (default 30) from the
# committed seed corpus in fuzz/corpus/<target>. New corpus entries go to a scratch folder; a crash, leak or
# undefined behaviour stops with its input saved under build-fuzz/findings/ and a non-zero exit.
# Usage: scripts/run_fuzzers.sh [SECONDS] [TARGET...]   (as root on a fresh Debian 12 machine)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
seconds=${1:-30}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_point_reader fuzz_edit_json fuzz_sel_def fuzz_region_spec)
build=${FUZZ_BUILD_DIR:-build-fuzz}
CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCGAL_EXT_BUILD_FUZZERS=ON \
  -DCGAL_EXT_BUILD_TESTS=OFF -DCGAL_EXT_BUILD_EXAMPLES=OFF -DCGAL_EXT_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}"
mkdir -p "$build/findings"
for target in "${targets[@]}"; do
  scratch=$(mktemp -d)
  echo "run_fuzzers.sh: $target for ${seconds} s"
  status=0
  "$build/fuzz/$target" "$scratch" "fuzz/corpus/$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096 \
    -artifact_prefix="$build/findings/$target-" -print_final_stats=1 >"$build/findings/$target.log" 2>&1 || status=$?
  grep -E "^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY)" \
    "$build/findings/$target.log" || true
  rm -rf "$scratch"
  [ "$status" -eq 0 ] || { echo "run_fuzzers.sh: $target failed (exit $status); see $build/findings/" >&2; exit 1; }
done
