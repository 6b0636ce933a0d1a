#!/usr/bin/python3
"""The Python package's cost against the library's own on the same work, on a seeded sampling of the armadillo
(1M points; --quick: 100k, one repetition): details, reading a binary PLY, and one drag of an edit as a Python user
gets it (set_handle_transform, deform, diffuse into the caller's arrays, reused from drag to drag). Medians of the
repetitions (a drag: of every repetition's drags). Writes OUT/python_results.csv and OUT/python_results.md.

It runs, as point-detail does, with glibc's malloc on transparent huge pages (GLIBC_TUNABLES=glibc.malloc.hugetlb=1,
set by re-executing itself unless GLIBC_TUNABLES sets hugetlb or POINT_DETAIL_HUGE_PAGES is 0): a fresh array's
first touch then costs one page fault per 2 MiB, not per 4 KiB, which on a virtual machine halves the time of
reading a large file.

Usage: PYTHONPATH=build/python benchmark/bench_python.py --out DIR [--build build] [--data data] [--quick]
"""
import argparse
import collections
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import cgal_ext
from cgal_ext._process import reexecute_tuned


def median(values):
    return float(np.median(values))


def program_timing(program, args, stage, reps, tmp):
    """The program's own timing of one stage (its --report), median of `reps` runs."""
    report = os.path.join(tmp, "report.json")
    times = []
    for _ in range(reps):
        subprocess.run([program, "-q", *args, "--report", report], check=True)
        with open(report) as f:
            times.append(json.load(f)["timings_s"][stage])
    return median(times)


def turn(step):
    """The handle's rotation at a drag's step: about the vertical axis, one degree more each step."""
    a = np.radians(1.0 + step)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def timed_drags(d, group, pivot, drags, points, normals):
    """`drags` drags of `group` about `pivot` as a Python user makes them (into arrays reused from drag to drag, in
    the caller's order) after an untimed first one, which writes every point (the others only what the edit can
    move): their wall times and the statistics after each."""
    P, N = np.empty_like(points), np.empty_like(normals)
    times, statistics = [], []
    for step in range(drags + 1):
        start = time.perf_counter()
        d.set_handle_transform(group, turn(step), pivot=pivot)
        d.deform()
        d.diffuse(P, N)
        if step:
            times.append(time.perf_counter() - start)
            statistics.append(d.statistics())
    return times, statistics


Drag = collections.namedtuple("Drag", "wall inside library movable")


def drag_times(points, normals, drags, reps):
    """One drag as a Python user gets it (into reused arrays in the caller's order), the C++ time of the same calls
    (deform() + diffuse_in_input_order(), their statistics) and the library's own deform() + diffuse() for the same
    drags (statistics), medians over every repetition's drags; and the number of points in the region."""
    wall, inside, library = [], [], []
    up = points[:, 1]
    region, top = up > np.quantile(up, 0.5), up > np.quantile(up, 0.9)
    for _ in range(reps):
        d = cgal_ext.Deformation(points, normals)
        d.insert_roi(region)  # the upper half deforms
        g = d.create_handle_group(top)  # its top is dragged
        d.preprocess()
        pivot = points[top].mean(axis=0)
        times, statistics = timed_drags(d, g, pivot, drags, points, normals)
        wall += times
        inside += [s["deform_seconds"] + s["diffuse_seconds"] for s in statistics]
        for step in range(drags):
            d.set_handle_transform(g, turn(step), pivot=pivot)
            d.deform()
            d.diffuse()
            s = d.statistics()
            library.append(s["deform_seconds"] + s["diffuse_seconds"])
    return Drag(median(wall), median(inside), median(library), int(np.sum(region)))


def harness_arguments():
    """The options every Python stage of the harness takes: --out DIR [--build build] [--data data] [--quick]."""
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--build", default="build")
    parser.add_argument("--data", default="data")
    parser.add_argument("--quick", action="store_true")
    return parser.parse_args()


def main():
    reexecute_tuned([sys.executable] + sys.argv)
    args = harness_arguments()
    n, reps, drags = (100000, 1, 5) if args.quick else (1000000, 5, 20)
    program = os.path.join(args.build, "src", "point-detail")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        scan = os.path.join(tmp, "armadillo.ply")
        subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                        os.path.join(args.data, "meshes", "armadillo.off"), str(n), scan], check=True)
        # The scan just written is still being flushed to disk: let that finish before either reader is timed, or
        # the first one (Python's) competes with the writeback.
        os.sync()

        # The two readers in turn, so that a stretch of slow first touches of fresh memory (the page cache being
        # reclaimed, say) falls on both rather than on whichever ran then.
        read, program_read = [], []
        for _ in range(reps):
            start = time.perf_counter()
            points, normals, _ = cgal_ext.read_points(scan)
            read.append(time.perf_counter() - start)
            program_read.append(program_timing(program, ["details", "-i", scan, "-o", os.path.join(tmp, "o.ply")],
                                               "read", 1, tmp))
        rows.append(("read_points of a binary PLY", n, median(read), median(program_read), "the program's reader"))

        details = []
        for _ in range(reps):
            start = time.perf_counter()
            cgal_ext.compute_geometric_details(points, normals)
            details.append(time.perf_counter() - start)
        program_details = program_timing(program, ["details", "-i", scan, "-o", os.path.join(tmp, "o.ply")], "details",
                                         reps, tmp)
        rows.append(("compute_geometric_details", n, median(details), program_details, "the library's call in point-detail"))

        # The sampling's own order is random; a scanner writes its points in sweeps, close in space: the same
        # points in a coherent order (sorted by a coarse grid along one axis, then the next).
        random_drag = drag_times(points, normals, drags, reps)
        rows.append(("one drag, points in random order (%d in the region)" % random_drag.movable, n, random_drag.wall,
                     random_drag.library, "the library's deform() + diffuse()"))
        cell = np.floor((points - points.min(axis=0)) / (np.ptp(points, axis=0).max() / 64)).astype(np.int64)
        order = np.lexsort((cell[:, 0], cell[:, 2], cell[:, 1]))
        scan_drag = drag_times(np.ascontiguousarray(points[order]), np.ascontiguousarray(normals[order]), drags, reps)
        rows.append(("one drag, points in scan-like order (%d in the region)" % scan_drag.movable, n, scan_drag.wall,
                     scan_drag.library, "the library's deform() + diffuse()"))
        # The binding's own overhead on a drag: the same calls' time inside C++.
        for name, drag in (("random", random_drag), ("scan-like", scan_drag)):
            rows.append(("one drag, points in %s order: the binding's overhead" % name, n, drag.wall, drag.inside,
                         "the same calls in C++ (deform() + diffuse_in_input_order(), not set_handle_transform)"))

    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "python_results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["measure", "points", "python_s", "reference_s", "ratio", "reference"])
        for measure, points_n, python_s, reference_s, reference in rows:
            w.writerow([measure, points_n, "%.6f" % python_s, "%.6f" % reference_s, "%.3f" % (python_s / reference_s),
                        reference])
    lines = ["# The Python package against the library", "",
             "Written by `benchmark/bench_python.py`%s (%d threads, GLIBC_TUNABLES=%s as point-detail sets it): medians of "
             "%d repetitions; a sampling of CGAL's "
             "armadillo with normals; a drag is `set_handle_transform`, `deform` and `diffuse(P, N)` into arrays reused "
             "from drag to drag, in the caller's order. Each row's reference is named in its last column; the library's "
             "times are its statistics." % (" --quick" if args.quick else "", cgal_ext.get_num_threads(), os.environ.get("GLIBC_TUNABLES", "unset"), reps),
             "",
             "| measure | points | Python | reference | ratio | reference is |", "|---|---|---|---|---|---|"]
    for measure, points_n, python_s, reference_s, reference in rows:
        lines.append("| %s | %d | %.4f s | %.4f s | %.2f | %s |" % (measure, points_n, python_s, reference_s,
                                                                 python_s / reference_s, reference))
    with open(os.path.join(args.out, "python_results.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
