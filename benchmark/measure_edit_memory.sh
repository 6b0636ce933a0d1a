#!/usr/bin/env bash
# Peak memory of whole `point-detail edit` runs (reading, preprocessing, one edit, diffusion, writing) on
# samplings of the armadillo surface, measured by /usr/bin/time -v; writes memory_results.md and .csv.
# The target is at most 1 KiB per input point.
# Usage: benchmark/measure_edit_memory.sh [--out DIR] [SIZES...]
#        (default: benchmark/, 100000 1000000 4000000; Release build in build/)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/release_build.sh point-detail sample_scan
bash scripts/fetch_data.sh
build=${BUILD_DIR:-build}
out_dir=benchmark
if [ "${1:-}" = "--out" ]; then out_dir=$2; shift 2; fi
mkdir -p "$out_dir"
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(100000 1000000 4000000)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The edit of benchmark/bench_editing.cpp's scans: region within 0.4 diagonals of the vertex farthest along +x,
# handle within 0.06, moved up by 0.05 diagonals.
awk 'NR == 2 {n = $1} NR > 2 && NR <= n + 2 {
       if(NR == 3 || $1 > ex) {ex = $1; ey = $2; ez = $3}
       for(c = 1; c <= 3; ++c) { if(NR == 3 || $c < lo[c]) lo[c] = $c; if(NR == 3 || $c > hi[c]) hi[c] = $c } }
     END { d = sqrt((hi[1]-lo[1])^2 + (hi[2]-lo[2])^2 + (hi[3]-lo[3])^2)
           printf "{\"roi\": [\"sphere:%g,%g,%g,%g\"], \"handles\": [{\"select\": [\"sphere:%g,%g,%g,%g\"], \"translation\": [0, %g, 0]}]}\n",
                  ex, ey, ez, 0.4 * d, ex, ey, ez, 0.06 * d, 0.05 * d }' data/meshes/armadillo.off > "$work/edit.json"
{
  echo "# Peak memory of whole edit runs"
  echo
  echo "\`benchmark/measure_edit_memory.sh\`; $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'),"
  echo "$(nproc) threads, $(date -u +%Y-%m-%d). Samplings of the armadillo surface (binary PLY with normals);"
  echo "one run each: read, preprocess, one edit, diffuse, write. Target: at most 1 KiB (1024 B) per point."
  echo
  echo "| points | wall time | peak RSS | per point |"
  echo "|---:|---:|---:|---:|"
} > "$work/table.md"
echo "points,wall_s,peak_rss_mib,bytes_per_point" > "$work/table.csv"
for n in "${sizes[@]}"; do
  "$build/benchmark/sample_scan" data/meshes/armadillo.off "$n" "$work/in.ply"
  /usr/bin/time -v "$build/src/point-detail" -q edit -i "$work/in.ply" -o "$work/out.ply" --edit "$work/edit.json" \
    2> "$work/time.txt"
  kib=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$work/time.txt")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$work/time.txt")
  printf '| %s | %s | %.0f MiB | %.0f B |\n' "$n" "$wall" "$(echo "$kib / 1024" | bc -l)" "$(echo "$kib * 1024 / $n" | bc -l)" >> "$work/table.md"
  seconds=$(echo "$wall" | awk -F: '{s = 0; for(i = 1; i <= NF; ++i) s = 60 * s + $i; print s}')
  printf '%s,%s,%.1f,%.1f\n' "$n" "$seconds" "$(echo "$kib / 1024" | bc -l)" "$(echo "$kib * 1024 / $n" | bc -l)" >> "$work/table.csv"
  rm -f "$work/in.ply" "$work/out.ply"
done
mv "$work/table.md" "$out_dir/memory_results.md"
mv "$work/table.csv" "$out_dir/memory_results.csv"
cat "$out_dir/memory_results.md"
