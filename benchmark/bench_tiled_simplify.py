#!/usr/bin/python3
"""The tiled sample points (`python3 -m cgal_ext.tiled simplify`, doc/scaling.md "Sample points") against the
program's (`point-detail simplify`) on seeded samplings of CGAL's models with normals, both with their defaults
(the command on a LocalCluster of one worker per core, one thread each):

- wall time from the start of each command to its exit, medians over the repetitions (3 at 10M, 1 at 1M and at
  100M, where only the tiled command runs), and the peak resident memory of the command's workers;
- the sample points made against the program's budget (1.5 times the target count) and the largest cluster;
- coverage: the largest distance from every 10th point of the scan to the nearest sample point, the tiled run's
  over the program's (1 when they cover the scan equally; above 1 when the tiled sample points leave a point
  further uncovered).

The armadillo, the fandisk (a CAD part with sharp creases) and the lion head at 10M, the armadillo at 100M
(--quick: the armadillo at 1M). Writes OUT/tiled_simplify_results.csv and .md.
Usage: PYTHONPATH=build/python benchmark/bench_tiled_simplify.py --out DIR [--build build] [--data data] [--quick]
"""
import os
import subprocess
import sys
import tempfile
import time

from scipy.spatial import cKDTree

import cgal_ext
from cgal_ext._process import reexecute_tuned

from bench_python import harness_arguments, median
from bench_tiled import sample, tiled_command, write_results

BUDGET = 1.5  # the most sample points per target count, the program's rule


def program_simplify(args, scan, output):
    start = time.perf_counter()
    subprocess.run([os.path.join(args.build, "src", "point-detail"), "-q", "simplify", "-i", scan, "-o", output],
                   check=True, capture_output=True)
    return time.perf_counter() - start


def main():
    reexecute_tuned([sys.executable] + sys.argv)
    args = harness_arguments()
    runs = ([("armadillo", 1_000_000, 1)] if args.quick else
            [("armadillo", 10_000_000, 3), ("fandisk", 10_000_000, 3), ("lion-head", 10_000_000, 3),
             ("armadillo", 100_000_000, 1)])
    target = cgal_ext._core._parameters["compute_simplification_sample_points"]["target_count"]
    workers = os.cpu_count()
    rows, client_rows = [], []  # the clients' rows last: the manual's figures are bound to the others' places
    with tempfile.TemporaryDirectory(dir=os.environ.get("BENCHMARK_TMP")) as tmp:
        for model, n, reps in runs:
            scan = sample(args, tmp, model, n)
            tiled_output, program_output = os.path.join(tmp, "tiled.ply"), os.path.join(tmp, "program.ply")
            with_program = n <= 10_000_000
            tiled_times, program_times, peaks, client_peaks = [], [], [], []
            for _ in range(reps):
                if with_program:
                    program_times.append(program_simplify(args, scan, program_output))
                seconds, report, peak, client_peak = tiled_command(["simplify", scan, "-o", tiled_output],
                                                                   os.path.join(tmp, "report.json"))
                tiled_times.append(seconds)
                peaks.append(peak)
                client_peaks.append(client_peak)
            client_rows.append((f"{model}: tiled simplify, peak resident memory of the command (the client)", n,
                                max(client_peaks) / 2 ** 30, "GiB", f"holds the subsample of {report['subsample']:,}"))
            tiled = cgal_ext.read_points(tiled_output)
            members = tiled.properties["member_count"]
            rows += [(f"{model}: tiled simplify, wall time", n, median(tiled_times), "s",
                      f"{workers} workers x 1 thread, subsample {report['subsample']:,}"),
                     (f"{model}: tiled simplify, sample points", n, len(members), "",
                      f"<= {BUDGET * target:.0f}, the program's budget"),
                     (f"{model}: tiled simplify, largest cluster", n, members.max(), "points", ""),
                     (f"{model}: tiled simplify, peak resident memory per worker", n, max(peaks) / 2 ** 30, "GiB",
                      "<= 3 GiB")]
            rows += [(f"{model}: tiled simplify, pass '{stage}'", n, seconds, "s", "")
                     for stage, seconds in report["seconds"].items()]
            rows += [(f"{model}: tiled simplify, client step '{step}'", n, seconds, "s", "")
                     for step, seconds in report["client_seconds"].items() if seconds >= 0.01]
            if with_program:
                points = cgal_ext.read_points(scan).points[::10]
                program = cgal_ext.read_points(program_output)
                cover = cKDTree(tiled.points).query(points)[0].max()
                program_cover = cKDTree(program.points).query(points)[0].max()
                rows += [(f"{model}: point-detail simplify, wall time", n, median(program_times), "s",
                          f"{workers} threads"),
                         (f"{model}: point-detail simplify, sample points", n, len(program.points), "", ""),
                         (f"{model}: point-detail simplify, largest cluster", n,
                          program.properties["member_count"].max(), "points", ""),
                         (f"{model}: tiled simplify, coverage / the program's", n, cover / program_cover, "",
                          "about 1"),
                         (f"{model}: tiled simplify, wall time / the program's", n,
                          median(tiled_times) / median(program_times), "", "")]
            os.remove(scan)
    rows += client_rows
    write_results(args.out, "tiled_simplify_results", "Tiled sample points on Dask (benchmark/bench_tiled_simplify.py)",
                  "Seeded samplings of CGAL's models with normals; `python3 -m cgal_ext.tiled simplify` and "
                  f"`point-detail simplify` with their defaults ({workers} workers of one thread; the program on "
                  f"{workers} threads). Medians over the repetitions.", rows)

if __name__ == "__main__":
    main()
