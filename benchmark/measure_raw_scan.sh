#!/usr/bin/env bash
# A raw scan of N points (default 1M samples of the armadillo surface, no normals) through every subcommand a
# scanning lab runs first: details, curvature, simplify, enhance (whole model, and a region of the N/10 points
# nearest the tip of the left arm), edit; beside the same runs on the same points with normals given. Wall time
# and peak RSS of whole runs (/usr/bin/time -v, medians of REPS runs) and the time the program spent estimating
# normals (its --report); writes raw_scan_results.md and .csv.
# Targets: every subcommand at most 15 s and 1 KiB per point at 1M points; the normals at most 8 s.
# Usage: benchmark/measure_raw_scan.sh [--out DIR] [--reps R] [N]   (default: benchmark/, 3, 1000000)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/release_build.sh point-detail sample_scan
bash scripts/fetch_data.sh
build=${BUILD_DIR:-build}
out_dir=benchmark
reps=3
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out_dir=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    *) break ;;
  esac
done
n=${1:-1000000}
mkdir -p "$out_dir"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
exe="$build/src/point-detail"
"$build/benchmark/sample_scan" data/meshes/armadillo.off "$n" "$work/normals.ply"
"$build/benchmark/sample_scan" data/meshes/armadillo.off "$n" "$work/raw.ply" --without-normals
# The edit of measure_edit_memory.sh, and the region: the n/10 samples nearest the same point, as an index file.
awk 'NR == 2 {n = $1} NR > 2 && NR <= n + 2 {
       if(NR == 3 || $1 > ex) {ex = $1; ey = $2; ez = $3}
       for(c = 1; c <= 3; ++c) { if(NR == 3 || $c < lo[c]) lo[c] = $c; if(NR == 3 || $c > hi[c]) hi[c] = $c } }
     END { d = sqrt((hi[1]-lo[1])^2 + (hi[2]-lo[2])^2 + (hi[3]-lo[3])^2)
           printf "{\"roi\": [\"sphere:%g,%g,%g,%g\"], \"handles\": [{\"select\": [\"sphere:%g,%g,%g,%g\"], \"translation\": [0, %g, 0]}]}\n",
                  ex, ey, ez, 0.4 * d, ex, ey, ez, 0.06 * d, 0.05 * d
           printf "%.17g %.17g %.17g\n", ex, ey, ez > "'"$work/tip.txt"'" }' data/meshes/armadillo.off > "$work/edit.json"
/usr/bin/python3 - "$work/normals.ply" "$work/tip.txt" "$work/roi.txt" <<'PY'
import array, sys
data = open(sys.argv[1], "rb").read()
start = data.index(b"end_header\n") + len(b"end_header\n")
xyz = array.array("d")
xyz.frombytes(data[start:])
tip = [float(v) for v in open(sys.argv[2]).read().split()]
n = len(xyz) // 6
d = sorted(range(n), key=lambda i: sum((xyz[6 * i + c] - tip[c]) ** 2 for c in range(3)))
open(sys.argv[3], "w").write("\n".join(str(i) for i in sorted(d[: n // 10])) + "\n")
PY

runs=(
  "details|details"
  "curvature|curvature"
  "simplify|simplify"
  "enhance, whole model|enhance -s 2"
  "enhance, region of N/10|enhance -s 2 --roi indices:$work/roi.txt"
  "edit|edit --edit $work/edit.json"
)
median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }
{
  echo "# A raw scan through every subcommand"
  echo
  echo "\`benchmark/measure_raw_scan.sh\`; $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'),"
  echo "$(nproc) threads, $(date -u +%Y-%m-%d). $n samples of the armadillo surface as a binary PLY without normals"
  echo "(raw) and with the sampled faces' normals (given); whole runs (read, compute, write), medians of $reps."
  echo "Targets at 1M points: at most 15 s and 1 KiB per point each; the normals at most 8 s."
  echo
  echo "| subcommand | raw: wall s | raw: normals s | raw: peak MiB | raw: B/point | given: wall s | given: peak MiB | given: B/point |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|"
} > "$work/table.md"
echo "subcommand,points,input,wall_s,normals_s,peak_rss_mib,bytes_per_point" > "$work/table.csv"
for entry in "${runs[@]}"; do
  name=${entry%%|*}
  arguments=${entry#*|}
  row="| $name"
  for input in raw normals; do
    : > "$work/walls" ; : > "$work/peaks" ; : > "$work/normal_times"
    for ((r = 0; r < reps; ++r)); do
      # shellcheck disable=SC2086
      /usr/bin/time -v "$exe" -q $arguments -i "$work/$input.ply" -o "$work/out.ply" --report "$work/report.json" \
        2> "$work/time.txt" > /dev/null
      awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, t, ":"); s = 0; for(i = 1; i <= n; ++i) s = 60 * s + t[i]; print s}' \
        "$work/time.txt" >> "$work/walls"
      awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2 / 1024}' "$work/time.txt" >> "$work/peaks"
      /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["timings_s"].get("normals", 0))' \
        "$work/report.json" >> "$work/normal_times"
      rm -f "$work/out.ply" "$work/report.json"
    done
    wall=$(median < "$work/walls"); peak=$(median < "$work/peaks"); normals=$(median < "$work/normal_times")
    per_point=$(echo "$peak * 1048576 / $n" | bc -l)
    if [ "$input" = raw ]; then
      row+=$(printf ' | %.2f | %.2f | %.0f | %.0f' "$wall" "$normals" "$peak" "$per_point")
    else
      row+=$(printf ' | %.2f | %.0f | %.0f' "$wall" "$peak" "$per_point")
    fi
    printf '"%s",%s,%s,%s,%s,%.1f,%.1f\n' "$name" "$n" "$input" "$wall" "$normals" "$peak" "$per_point" >> "$work/table.csv"
  done
  echo "$row |" >> "$work/table.md"
done
mv "$work/table.md" "$out_dir/raw_scan_results.md"
mv "$work/table.csv" "$out_dir/raw_scan_results.csv"
cat "$out_dir/raw_scan_results.md"
