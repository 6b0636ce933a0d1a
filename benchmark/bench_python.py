"""The Python module's overhead against the library's own timing of the same calls, on 1M points: details, and
one drag of an edit (set_handle_transform, deform, diffuse). Medians of repeated runs.

Usage: PYTHONPATH=build/python python3 benchmark/bench_python.py [--points N] [--reps R] [--program build/src/point-detail]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import cgal_ext

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python", "tests"))
from conftest import bumpy_sphere, write_ply  # noqa: E402


def median(values):
    return float(np.median(values))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--points", type=int, default=1000000)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--program", default="build/src/point-detail")
    args = parser.parse_args()
    points, normals = bumpy_sphere(args.points, seed=11)

    # Details: the module's call against the program's own timing of the library call on the same points.
    python_s = []
    for _ in range(args.reps):
        start = time.perf_counter()
        cgal_ext.compute_geometric_details(points, normals)
        python_s.append(time.perf_counter() - start)
    program_s = []
    with tempfile.TemporaryDirectory() as tmp:
        write_ply(os.path.join(tmp, "in.ply"), points, normals)
        for _ in range(args.reps):
            subprocess.run([args.program, "-q", "details", "-i", os.path.join(tmp, "in.ply"), "-o", os.path.join(tmp, "out.ply"),
                            "--report", os.path.join(tmp, "r.json")], check=True)
            program_s.append(json.load(open(os.path.join(tmp, "r.json")))["timings_s"]["details"])
    print("details, %d points: Python %.3f s, the library's call in point-detail %.3f s: overhead %+.1f %%"
          % (args.points, median(python_s), median(program_s), 100 * (median(python_s) / median(program_s) - 1)))

    # One drag: the Python calls' wall time against the library's own timing of deform() and diffuse().
    d = cgal_ext.Deformation(points, normals)
    d.insert_roi(np.flatnonzero(points[:, 2] > 0.0))
    g = d.create_handle_group(np.flatnonzero(points[:, 2] > 0.85))
    d.preprocess()
    out_points, out_normals = np.empty_like(points), np.empty_like(normals)  # reused from drag to drag
    wall, inner = [], []
    for step in range(1, 4 * args.reps + 1):
        a = np.radians(2 * step)
        R = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        start = time.perf_counter()
        d.set_handle_transform(g, R, np.zeros(3))
        d.deform()
        d.diffuse(out_points, out_normals)
        wall.append(time.perf_counter() - start)
        s = d.statistics()
        inner.append(s["deform_seconds"] + s["diffuse_seconds"])
    # The difference is writing the points and normals out in the caller's order, which C++'s
    # diffuse(points, np) pays as well.
    print("one drag, %d points: Python (into reused arrays) %.1f ms; the library's deform() + diffuse() into its own "
          "arrays %.1f ms" % (args.points, 1000 * median(wall), 1000 * median(inner)))


if __name__ == "__main__":
    main()
