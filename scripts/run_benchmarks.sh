#!/usr/bin/env bash
# Sets everything up, builds in Release and runs the whole benchmark harness on CGAL's real scans and on 100k, 1M
# and 4M-point samplings of the armadillo surface; writes benchmark/RESULTS.md, benchmark/results.csv,
# benchmark/scaling.png and each stage's *_results.{md,csv}. About 45 minutes on 2 cores.
# Usage: scripts/run_benchmarks.sh [--quick]
#   --quick: small sizes, one repetition, results under build/benchmark/quick (what CI runs so the harness
#            cannot rot; the committed figures are never overwritten by it).
set -euo pipefail
cd "$(dirname "$0")/.."
quick=0
case "${1:-}" in
  --quick) quick=1 ;;
  "") ;;
  *) echo "usage: scripts/run_benchmarks.sh [--quick]" >&2; exit 2 ;;
esac
benches=(bench_editing bench_upsampling bench_simplification bench_curvature bench_scaling bench_details)
bash scripts/release_build.sh "${benches[@]}" sample_scan point-detail cgal_ext_python
bash scripts/fetch_data.sh
build=${BUILD_DIR:-build}
if [ "$quick" = 1 ]; then
  out="$build/benchmark/quick"
  flags=(--quick)
  sizes=(100000)
else
  out=benchmark
  flags=()
  sizes=(100000 1000000 4000000)
fi
mkdir -p "$out" "$build/benchmark/logs"
start=$SECONDS
for bench in "${benches[@]}"; do
  echo "== $bench (log: $build/benchmark/logs/$bench.log)" >&2
  "$build/benchmark/$bench" "${flags[@]}" --data data --out "$out" > "$build/benchmark/logs/$bench.log"
done
echo "== measure_edit_memory.sh" >&2
BUILD_DIR="$build" bash benchmark/measure_edit_memory.sh --out "$out" "${sizes[@]}" >/dev/null
echo "== measure_raw_scan.sh" >&2
if [ "$quick" = 1 ]; then raw_scan=(--reps 1 100000); else raw_scan=(--reps 3 1000000); fi
BUILD_DIR="$build" bash benchmark/measure_raw_scan.sh --out "$out" "${raw_scan[@]}" >/dev/null
echo "== bench_python.py" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_python.py "${flags[@]}" --build "$build" --data data --out "$out" \
  > "$build/benchmark/logs/bench_python.log"
echo "== bench_drag.py" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_drag.py "${flags[@]}" --build "$build" --data data --out "$out" \
  > "$build/benchmark/logs/bench_drag.log"
echo "== bench_studio.py" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_studio.py "${flags[@]}" --build "$build" --data data --out "$out" \
  > "$build/benchmark/logs/bench_studio.log"
echo "== studio_on_models.py" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/studio_on_models.py "${flags[@]}" --build "$build" --data data --out "$out" \
  > "$build/benchmark/logs/studio_on_models.log"
echo "== bench_studio_level.py (full run: a scan of 100M points, about 15 minutes and 5 GB of temporary files)" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_studio_level.py "${flags[@]}" --build "$build" --data data \
  --out "$out" > "$build/benchmark/logs/bench_studio_level.log"
echo "== bench_tiled.py (full run: 10M, 30M and 100M points, about 15 minutes and 15 GB of temporary files)" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_tiled.py "${flags[@]}" --build "$build" --data data --out "$out" \
  > "$build/benchmark/logs/bench_tiled.log"
echo "== bench_tiled_simplify.py (full run: three models at 10M, the armadillo at 100M)" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_tiled_simplify.py "${flags[@]}" --build "$build" --data data \
  --out "$out" > "$build/benchmark/logs/bench_tiled_simplify.log"
echo "== bench_tiled_edit.py (full run: the armadillo at 1M, three models at 10M and at 3M, the armadillo at 100M)" >&2
PYTHONPATH="$build/python" /usr/bin/python3 benchmark/bench_tiled_edit.py "${flags[@]}" --build "$build" --data data \
  --out "$out" > "$build/benchmark/logs/bench_tiled_edit.log"
BENCHMARK_QUICK=$quick BENCHMARK_THREADS=$(nproc) /usr/bin/python3 benchmark/make_results.py "$out" "$build"
echo "run_benchmarks.sh: $((SECONDS - start)) s of benchmarks" >&2
