"""Drags at scale against the machine's memory bandwidth (doc/editing_at_scale.md, "A drag's memory traffic").

CGAL's armadillo (the harness's model) and three other models of CGAL's data set sampled to 4M points with normals
(--quick: 100k, the armadillo and one other), each in the sampling's random order and in a scan-like order; the
upper half along y is the region, its top 5 % the handle, turned a degree more each drag. Per case: the
preprocess (median of 3; --quick: 1), the drag as a Python user gets it (`set_handle_transform`, `deform`,
`diffuse(P, N)` into arrays reused from drag to drag: median of 40 drags), the diffusion's bytes
(`statistics()["diffuse_bytes"]`) over its time, and STREAM's triad on the same threads, measured before and after
the cases (`_triad_bandwidth`). It runs in the environment it is given, as a Python user's script does: glibc's
malloc on transparent huge pages (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, which point-detail sets for itself) made
the preprocess at 4M slower and the drags no faster (doc/editing_at_scale.md). Writes OUT/drag_results.csv and
OUT/drag_results.md.
"""

import csv
import os
import subprocess
import tempfile
import time

import numpy as np

import cgal_ext
from cgal_ext import _core

from bench_python import harness_arguments, median, timed_drags

MODELS = ("armadillo", "ChineseDragon-10kv", "fandisk", "elephant-with-holes")


def scan_like(points):
    """A scanner's order: sorted by a coarse grid along y, then z, then x (as bench_python.py)."""
    cell = np.floor((points - points.min(axis=0)) / (np.ptp(points, axis=0).max() / 64)).astype(np.int64)
    return np.lexsort((cell[:, 0], cell[:, 2], cell[:, 1]))


def one_case(points, normals, preprocesses, drags):
    """Preprocess times, drag times, the diffusion's times and bytes, and the points the region holds."""
    up = points[:, 1]
    region, handle = up > np.quantile(up, 0.5), up >= np.quantile(up, 0.95)  # >=: a flat top (fandisk) ties
    pivot = points[handle].mean(axis=0)
    pre = []
    for _ in range(preprocesses):
        d = cgal_ext.Deformation(points, normals)
        d.insert_roi(region)
        group = d.create_handle_group(handle)
        start = time.perf_counter()
        d.preprocess()
        pre.append(time.perf_counter() - start)
    clustering = d.statistics()["clustering_seconds"]
    wall, statistics = timed_drags(d, group, pivot, drags, points, normals)
    return dict(preprocess=median(pre), clustering=clustering, drag=median(wall),
                diffuse=median([s["diffuse_seconds"] for s in statistics]),
                bytes=median([s["diffuse_bytes"] for s in statistics]), region=int(region.sum()),
                samples=statistics[-1]["samples"])


def main():
    args = harness_arguments()
    n, models, preprocesses, drags = (100000, MODELS[:2], 1, 10) if args.quick else (4000000, MODELS, 3, 40)
    triad_elements = 4000000 if args.quick else 40000000
    triad_before = _core._triad_bandwidth(triad_elements)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for model in models:
            scan = os.path.join(tmp, model + ".ply")
            subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                            os.path.join(args.data, "meshes", model + ".off"), str(n), scan], check=True)
            points, normals, _ = cgal_ext.read_points(scan)
            os.remove(scan)
            order = scan_like(points)
            for name, (p, q) in (("random", (points, normals)),
                                 ("scan-like", (np.ascontiguousarray(points[order]), np.ascontiguousarray(normals[order])))):
                case = one_case(p, q, preprocesses, drags)
                case.update(model=model, order=name, points=n)
                rows.append(case)
                print(case, flush=True)
    triad_after = _core._triad_bandwidth(triad_elements)
    triad = min(triad_before[0], triad_after[0])  # the median pass of the slower of the two measurements

    os.makedirs(args.out, exist_ok=True)
    fields = ["model", "order", "points", "region", "samples", "preprocess_s", "clustering_s", "drag_s", "diffuse_s",
              "bytes_per_drag", "diffuse_gb_s", "triad_gb_s", "of_triad"]
    with open(os.path.join(args.out, "drag_results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(fields)
        for r in rows:
            rate = r["bytes"] / r["diffuse"] / 1e9
            w.writerow([r["model"], r["order"], r["points"], r["region"], r["samples"], "%.3f" % r["preprocess"],
                        "%.3f" % r["clustering"], "%.5f" % r["drag"], "%.5f" % r["diffuse"], r["bytes"], "%.1f" % rate,
                        "%.1f" % triad, "%.2f" % (rate / triad)])
    lines = ["# Drags at scale against the memory's bandwidth", "",
             "Written by `benchmark/bench_drag.py`%s (%d threads, GLIBC_TUNABLES=%s: as a Python user runs it). Each model "
             "sampled to %d points with normals, in the sampling's random order and in a scan-like one; the upper half "
             "along y is the region, its top 5 %% the handle. Preprocess: median of %d; drag (`set_handle_transform`, "
             "`deform`, `diffuse(P, N)` into the caller's arrays): median of %d; bytes: what the diffusion read and "
             "wrote for the points (`diffuse_bytes`, not counting the lines a store reads first), over its time. "
             "Triad (STREAM's, 24 bytes per element, the same threads): %.1f GB/s before the cases, %.1f after (medians "
             "of 6 passes); the slower is the reference." % (" --quick" if args.quick else "", cgal_ext.get_num_threads(),
                                                             os.environ.get("GLIBC_TUNABLES", "unset"), n, preprocesses, drags,
                                                             triad_before[0], triad_after[0]),
             "",
             "| model | order | region | sample points | preprocess | of it clustering | drag | of it diffusion | "
             "bytes per drag | diffusion's bandwidth | of the triad |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        rate = r["bytes"] / r["diffuse"] / 1e9
        lines.append("| %s | %s | %d | %d | %.2f s | %.2f s | %.1f ms | %.1f ms | %.0f MB | %.1f GB/s | %.0f %% |" % (
            r["model"], r["order"], r["region"], r["samples"], r["preprocess"], r["clustering"], 1e3 * r["drag"],
            1e3 * r["diffuse"], r["bytes"] / 1e6, rate, 100 * rate / triad))
    with open(os.path.join(args.out, "drag_results.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
