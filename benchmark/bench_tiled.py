#!/usr/bin/python3
"""The tiled runs on Dask (doc/scaling.md) on seeded samplings of CGAL's models with normals, against the
one-process program on 1M points of the same model:

- the program (`point-detail details`, quadric, read + compute + write) and the library call alone at 1M;
- the command users run, `python3 -m cgal_ext.tiled details SCAN -o OUT.ply` with its defaults (a LocalCluster of
  one worker per core, one thread each), on the armadillo at 10M, 30M and 100M points and on the fandisk and the
  lion head at 10M (--quick: the armadillo at 1M): wall time from the command's start to its exit (Python's
  start and the cluster's included), points per second, the peak resident memory of every worker process
  (sampled every 0.1 s) and of the command;
- the per-tile costs (read, neighbours and certificate, compute, save) the 10^9 estimate of doc/scaling.md is
  computed from (the command's --report), and the scratch disk's sequential write throughput, which bounds the
  passes that write.

The program runs before each tiled run, on 1M points of the same model (five runs at least), so that both meet the
machine at the same speed. Medians over the repetitions (5 at 1M, 3 at 10M, 1 above); the tiled runs are also
compared with the program's fastest run. Writes OUT/tiled_results.csv and OUT/tiled_results.md.
Usage: PYTHONPATH=build/python benchmark/bench_tiled.py --out DIR [--build build] [--data data] [--quick]
"""
import csv
import json
import os
import subprocess
import sys
import tempfile
import threading
import time

import psutil

import cgal_ext
from cgal_ext._process import reexecute_tuned

from bench_python import harness_arguments, median


class PeakMemory:
    """The largest resident set of each process below this one (the command and its Dask workers), sampled in a
    thread."""

    def __init__(self):
        self.peaks, self._stop = {}, threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)

    def _sample(self):
        me = psutil.Process()
        while not self._stop.wait(0.1):
            for child in me.children(recursive=True):
                try:
                    self.peaks[child.pid] = max(self.peaks.get(child.pid, 0), child.memory_info().rss)
                except psutil.Error:
                    pass

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def sample(args, tmp, model, n, name=None):
    path = os.path.join(tmp, name or f"{model}_{n}.ply")
    subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                    os.path.join(args.data, "meshes", f"{model}.off"), str(n), path], check=True)
    return path


def program_run(args, tmp, scan):
    """The program's wall time on `scan`, and the library call's alone."""
    start = time.perf_counter()
    subprocess.run([os.path.join(args.build, "src", "point-detail"), "details", "-i", scan, "-o",
                    os.path.join(tmp, "one.ply")], check=True, capture_output=True)
    wall = time.perf_counter() - start
    points, normals, _ = cgal_ext.read_points(scan)
    start = time.perf_counter()
    cgal_ext.compute_geometric_details(points, normals)
    return wall, time.perf_counter() - start


def tiled_command(arguments, report):
    """One run of `python3 -m cgal_ext.tiled ARGUMENTS --report REPORT` as a user types it: its wall time, its
    report, the peak resident memory of its largest worker and its own."""
    with PeakMemory() as memory:
        start = time.perf_counter()
        command = subprocess.Popen([sys.executable, "-m", "cgal_ext.tiled", *arguments, "--report", report],
                                   stdout=subprocess.DEVNULL)
        if command.wait():
            raise SystemExit(f"the tiled command failed: {' '.join(arguments)} (status {command.returncode})")
        seconds = time.perf_counter() - start
    with open(report) as f:
        result = json.load(f)
    workers = [peak for pid, peak in memory.peaks.items() if pid != command.pid]
    return seconds, result, max(workers), memory.peaks.get(command.pid, 0)


def disk_write_throughput(folder, size=2 << 30):
    """Bytes per second of a sequential write of `size` bytes to `folder`, flushed to the disk: what the passes
    that write more than the page cache holds dirty are bound by."""
    block = os.urandom(1 << 20) * 16
    path = os.path.join(folder, "disk_probe.bin")
    start = time.perf_counter()
    with open(path, "wb") as f:
        for _ in range(size // len(block)):
            f.write(block)
        f.flush()
        os.fsync(f.fileno())
    seconds = time.perf_counter() - start
    os.remove(path)
    return size / seconds


def main():
    reexecute_tuned([sys.executable] + sys.argv)  # the library call alone on huge pages, as point-detail runs it
    args = harness_arguments()
    # (model, sizes, repetitions per size): the armadillo's rows come first, as the manual's figures are bound to them.
    if args.quick:
        runs = [("armadillo", [1_000_000], {})]
    else:
        runs = [("armadillo", [10_000_000, 30_000_000, 100_000_000], {10_000_000: 3}),
                ("fandisk", [10_000_000], {10_000_000: 3}), ("lion-head", [10_000_000], {10_000_000: 3})]
    baseline_reps = 1 if args.quick else 5
    workers = os.cpu_count()
    rows, late_rows, model_rows, command_peaks = [], [], [], []
    with tempfile.TemporaryDirectory(dir=os.environ.get("BENCHMARK_TMP")) as tmp:
        for model, sizes, reps in runs:
            # The program runs on 1M points of the model before each tiled run (and as often as it takes to make
            # five), so that both meet the machine at the same speed: on this shared machine it drifts by a
            # fifth within the hour.
            baseline = sample(args, tmp, model, 1_000_000, f"{model}_baseline.ply")
            wall, compute, done = [], [], []
            for n in sizes:
                scan = sample(args, tmp, model, n)
                times, worker_peaks, report = [], [], None
                for _ in range(reps.get(n, 1)):
                    for measure, value in zip((wall, compute), program_run(args, tmp, baseline)):
                        measure.append(value)
                    output = os.path.join(tmp, "tiled.ply")
                    seconds, report, worker_peak, command_peak = tiled_command(
                        ["details", scan, "-o", output], os.path.join(tmp, "report.json"))
                    os.remove(output)
                    times.append(seconds)
                    worker_peaks.append(worker_peak)
                    command_peaks.append(command_peak)
                os.remove(scan)
                done.append((n, times, worker_peaks, report))
            while len(wall) < baseline_reps:
                for measure, value in zip((wall, compute), program_run(args, tmp, baseline)):
                    measure.append(value)
            os.remove(baseline)
            one_process_throughput = 1_000_000 / median(wall)
            if model == "armadillo":
                armadillo_wall = wall
                rows.append(("one process: point-detail details (read, compute, write)", 1_000_000, median(wall),
                             "s", f"{workers} threads"))
                rows.append(("one process: point-detail details, throughput", 1_000_000, one_process_throughput,
                             "points/s", ""))
                rows.append(("one process: compute_geometric_details alone", 1_000_000, median(compute), "s",
                             f"{workers} threads"))
                written, size = ("256 MiB", 256 << 20) if args.quick else ("2 GiB", 2 << 30)
                rows.append((f"scratch disk: sequential write, flushed ({written})", 0,
                             disk_write_throughput(tmp, size) / 1e6, "MB/s", ""))
            for n, times, worker_peaks, report in done:
                throughput = n / median(times)
                if model != "armadillo":
                    model_rows += [(f"{model}: point-detail details at 1M", 1_000_000, median(wall), "s",
                                    f"{workers} threads"),
                                   (f"{model}: tiled details, wall time", n, median(times), "s",
                                    f"{report['tiles']} tiles"),
                                   (f"{model}: tiled details, throughput / one-process throughput at 1M", n,
                                    100 * throughput / one_process_throughput, "%", ">= 70 %"),
                                   (f"{model}: tiled details, peak resident memory per worker", n,
                                    max(worker_peaks) / 2 ** 30, "GiB", "<= 3 GiB")]
                    continue
                last = n == sizes[-1]
                rows.append(("tiled details: wall time", n, median(times), "s",
                             f"{report['tiles']} tiles, {workers} workers x 1 thread"))
                rows.append(("tiled details: throughput", n, throughput, "points/s",
                             ">= 70 % of the one-process throughput at 1M" if last else ""))
                rows.append(("tiled details: throughput / one-process throughput at 1M", n,
                             100 * throughput / one_process_throughput, "%", ">= 70 %" if last else ""))
                rows.append(("tiled details: peak resident memory per worker", n, max(worker_peaks) / 2 ** 30, "GiB",
                             "<= 3 GiB, the same at 10M and 100M"))
                rows.append(("tiled details: points read per own point (halo overhead)", n,
                             report["read_points"] / n, "", ""))
                tile_seconds = report["seconds"]["tiles"] * workers / report["tiles"]
                rows.append(("tiled details: seconds per tile (one worker)", n, tile_seconds, "s",
                             f"{n // report['tiles']} own points per tile"))
                for step, seconds in report["tile_seconds"].items():
                    rows.append((f"tiled details: per tile, step '{step}' (one worker)", n,
                                 seconds / report["tiles"], "s", ""))
                for stage, seconds in report["seconds"].items():
                    rows.append((f"tiled details: pass '{stage}'", n, seconds, "s", ""))
                late_rows.append(("tiled details: throughput / the one-process program's fastest run's at 1M", n,
                                  100 * throughput * min(wall) / 1_000_000, "%", ""))
                summaries = report["tile_summaries"]
                searched = sum(s["searched"] * s["read"] for s in summaries) / report["read_points"]
                late_rows.append(("tiled details: points read whose k nearest the certificate searched", n,
                                  100 * searched, "%",
                                  f"{sum(1 for s in summaries if s['searched'] > 0)} of {len(summaries)} tiles "
                                  "searched any"))
                for step, seconds in report["client_seconds"].items():
                    late_rows.append((f"tiled details: client step '{step}'", n, seconds, "s", "between the passes"))
    largest = runs[0][1][-1]
    rows.append(("the command's peak resident memory (the client)", largest, max(command_peaks) / 2 ** 30, "GiB",
                 "never the whole scan"))
    # The spread of the baseline, which the throughput targets divide by (its file writes vary from run to run).
    rows.append(("one process: point-detail details, fastest run", 1_000_000, min(armadillo_wall), "s",
                 f"of {baseline_reps}"))
    rows.append(("one process: point-detail details, slowest run", 1_000_000, max(armadillo_wall), "s",
                 f"of {baseline_reps}"))
    rows.extend(model_rows)
    rows.extend(late_rows)  # after the rows the manual's figures are bound to

    write_results(args.out, "tiled_results", "Tiled runs on Dask (benchmark/bench_tiled.py)",
                  "Seeded samplings of CGAL's models with normals, quadric details; the command `python3 -m "
                  f"cgal_ext.tiled details` with its defaults: a LocalCluster of {workers} workers, one thread each. "
                  "Medians over the repetitions.", rows)


def write_results(out, stem, title, introduction, rows):
    """OUT/stem.csv and OUT/stem.md of rows (measure, points, value, unit, target)."""
    with open(os.path.join(out, stem + ".csv"), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["measure", "points", "value", "unit", "target"])
        for row in rows:
            writer.writerow([row[0], row[1], f"{float(row[2]):.6g}", row[3], row[4]])
    with open(os.path.join(out, stem + ".md"), "w") as f:
        f.write(f"# {title}\n\n{introduction}\n\n"
                "| measure | points | value | unit | target |\n|---|---:|---:|---|---|\n")
        for row in rows:
            f.write(f"| {row[0]} | {row[1]:,} | {float(row[2]):.4g} | {row[3]} | {row[4]} |\n")
    print(f"wrote {out}/{stem}.csv and {stem}.md")


if __name__ == "__main__":
    main()
