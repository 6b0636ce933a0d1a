#!/usr/bin/python3
"""The tiled runs on Dask (doc/scaling.md) on seeded samplings of CGAL's armadillo with normals, against the
one-process program on 1M points of the same model:

- the program (`point-detail details`, quadric, read + compute + write) and the library call alone at 1M;
- `cgal_ext.tiled.run("details", ...)` on a LocalCluster of one worker per core (one thread each) at 10M, 30M and
  100M points (--quick: 1M and 2M): wall time from the call to the renamed output (the cluster already started),
  points per second, the peak resident memory of every worker process (sampled every 0.1 s) and of the client;
- the per-tile costs (read, neighbours and certificate, compute, save) the 10^9 estimate of doc/scaling.md is
  computed from, and the scratch disk's sequential write throughput, which bounds the passes that write.

Medians over the repetitions (5 at 1M, 3 at 10M, 1 above); the tiled runs are also compared with the program's
fastest run, whose file writes this machine delayed least (they vary from run to run by up to twice the
computation). Writes OUT/tiled_results.csv and OUT/tiled_results.md.
Usage: PYTHONPATH=build/python benchmark/bench_tiled.py --out DIR [--build build] [--data data] [--quick]
"""
import csv
import os
import resource
import subprocess
import tempfile
import threading
import time

import psutil
from distributed import Client, LocalCluster

import cgal_ext
from cgal_ext import tiled

from bench_python import harness_arguments, median


class PeakMemory:
    """The largest resident set of each process below this one (the Dask workers), sampled in a thread."""

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


def sample(args, tmp, n):
    path = os.path.join(tmp, f"armadillo_{n}.ply")
    subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                    os.path.join(args.data, "meshes", "armadillo.off"), str(n), path], check=True)
    return path


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
    args = harness_arguments()
    sizes, reps = ([1_000_000, 2_000_000], {}) if args.quick else ([10_000_000, 30_000_000, 100_000_000],
                                                                     {10_000_000: 3})
    baseline_reps = 1 if args.quick else 5
    workers = os.cpu_count()
    rows = []
    with tempfile.TemporaryDirectory(dir=os.environ.get("BENCHMARK_TMP")) as tmp:
        scan = sample(args, tmp, 1_000_000)
        program = os.path.join(args.build, "src", "point-detail")
        wall, compute = [], []
        for _ in range(baseline_reps):
            start = time.perf_counter()
            subprocess.run([program, "details", "-i", scan, "-o", os.path.join(tmp, "one.ply")], check=True,
                           capture_output=True)
            wall.append(time.perf_counter() - start)
            points, normals, _ = cgal_ext.read_points(scan)
            start = time.perf_counter()
            cgal_ext.compute_geometric_details(points, normals)
            compute.append(time.perf_counter() - start)
            del points, normals
        one_process = 1_000_000 / median(wall)
        rows.append(("one process: point-detail details (read, compute, write)", 1_000_000, median(wall), "s",
                     f"{workers} threads"))
        rows.append(("one process: point-detail details, throughput", 1_000_000, one_process, "points/s", ""))
        rows.append(("one process: compute_geometric_details alone", 1_000_000, median(compute), "s",
                     f"{workers} threads"))
        os.remove(scan)
        rows.append(("scratch disk: sequential write, flushed (2 GiB)", 0,
                     disk_write_throughput(tmp, (256 << 20) if args.quick else (2 << 30)) / 1e6, "MB/s", ""))

        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, memory_limit="3GiB",
                               dashboard_address=None, silence_logs=40)
        client = Client(cluster)
        late_rows = []
        for n in sizes:
            scan = sample(args, tmp, n)
            times, worker_peaks, report = [], [], None
            for _ in range(reps.get(n, 1)):
                output = os.path.join(tmp, "tiled.ply")
                with PeakMemory() as memory:
                    start = time.perf_counter()
                    report = tiled.run("details", scan, output, client=client)
                    times.append(time.perf_counter() - start)
                worker_peaks.append(max(memory.peaks.values()))
                os.remove(output)
            os.remove(scan)
            throughput = n / median(times)
            rows.append(("tiled details: wall time", n, median(times), "s",
                         f"{report['tiles']} tiles, {workers} workers x 1 thread"))
            rows.append(("tiled details: throughput", n, throughput, "points/s",
                         ">= 70 % of the one-process throughput at 1M" if n == sizes[-1] else ""))
            rows.append(("tiled details: throughput / one-process throughput at 1M", n,
                         100 * throughput / one_process, "%", ">= 70 %" if n == sizes[-1] else ""))
            rows.append(("tiled details: peak resident memory per worker", n, max(worker_peaks) / 2 ** 30, "GiB",
                         "<= 3 GiB, the same at 10M and 100M"))
            rows.append(("tiled details: points read per own point (halo overhead)", n,
                         report["read_points"] / n, "", ""))
            tile_seconds = report["seconds"]["tiles"] * workers / report["tiles"]
            rows.append(("tiled details: seconds per tile (one worker)", n, tile_seconds, "s",
                         f"{n // report['tiles']} own points per tile"))
            for step, seconds in report["tile_seconds"].items():
                rows.append((f"tiled details: per tile, step '{step}' (one worker)", n, seconds / report["tiles"], "s",
                             ""))
            for stage, seconds in report["seconds"].items():
                rows.append((f"tiled details: pass '{stage}'", n, seconds, "s", ""))
            late_rows.append(("tiled details: throughput / the one-process program's fastest run's at 1M", n,
                              100 * throughput * min(wall) / 1_000_000, "%", ""))
            summaries = report["tile_summaries"]
            searched = sum(s["searched"] * s["read"] for s in summaries) / report["read_points"]
            late_rows.append(("tiled details: points read whose k nearest the certificate searched", n,
                              100 * searched, "%",
                              f"{sum(1 for s in summaries if s['searched'] > 0)} of {len(summaries)} tiles searched any"))
            for step, seconds in report["client_seconds"].items():
                late_rows.append((f"tiled details: client step '{step}'", n, seconds, "s", "between the passes"))
        client.close()
        cluster.close()
    rows.append(("client peak resident memory (whole harness)", sizes[-1],
                 resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20, "GiB", "never the whole scan"))
    # The spread of the baseline, which the throughput targets divide by (its file writes vary from run to run).
    rows.append(("one process: point-detail details, fastest run", 1_000_000, min(wall), "s",
                 f"of {baseline_reps}"))
    rows.append(("one process: point-detail details, slowest run", 1_000_000, max(wall), "s",
                 f"of {baseline_reps}"))
    rows.extend(late_rows)  # after the rows the manual's figures are bound to

    with open(os.path.join(args.out, "tiled_results.csv"), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["measure", "points", "value", "unit", "target"])
        for row in rows:
            writer.writerow([row[0], row[1], f"{row[2]:.6g}", row[3], row[4]])
    with open(os.path.join(args.out, "tiled_results.md"), "w") as f:
        f.write("# Tiled runs on Dask (benchmark/bench_tiled.py)\n\n"
                f"Seeded samplings of CGAL's armadillo with normals, quadric details; LocalCluster of {workers} "
                "workers, one thread each, 3 GiB memory limit each. Medians over the repetitions.\n\n"
                "| measure | points | value | unit | target |\n|---|---:|---:|---|---|\n")
        for row in rows:
            f.write(f"| {row[0]} | {row[1]:,} | {row[2]:.4g} | {row[3]} | {row[4]} |\n")
    print(f"wrote {args.out}/tiled_results.csv and tiled_results.md")


if __name__ == "__main__":
    main()
