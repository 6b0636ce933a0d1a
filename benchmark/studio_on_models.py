#!/usr/bin/python3
"""The studio's session (the calls the page makes) on CGAL's models, as a user would edit them: two edits, a commit
between them, a fill after the second, a save, and the program's `edit` on the saved chain (doc/studio.md, "Tried
on other models").

Per model: the first edit's region is the upper half along the longest axis and its handle the top tenth, turned
by 30 degrees about a horizontal axis through the handle and moved by 10 % of the diagonal; the second edit's
region is the half on the positive side of the second-longest axis, its handle the outer tenth, pulled outwards by
10 % of the diagonal, then Fill gaps. Reported: the checks before each edit (islands, no fixed part), the largest
stretch of a 10-nearest-neighbour edge of the region outside the handle's collar (3 rings) after each edit, the
points the fill added, and the largest distance between the saved PLY and the program's result.

Usage: PYTHONPATH=build/python benchmark/studio_on_models.py [--data data] [--build build] [--out DIR] [--quick] [MODEL...]
(a MODEL is a name in data/meshes or a point file; by default CGAL's models and seeded samplings of three of them)
"""
import argparse
import csv
import os
import shutil
import subprocess
import tempfile
import time

import numpy as np

import cgal_ext
from cgal_ext.studio.session import FIXED, FIRST_HANDLE, Session

MODELS = ["fandisk", "bunny00", "ChineseDragon-10kv", "mech-holes-shark", "lion-head", "elephant-with-holes", "turbine",
          "anchor_dense", "camel", "blobby_3cc", "cactus", "refined_elephant"]
SAMPLINGS = [("blobby_3cc", 300000), ("fandisk", 1000000), ("armadillo", 1000000)]


def sampled(build, data, folder, model, n):
    """CGAL's `model` sampled to `n` points with normals (benchmark/sample_scan, seeded)."""
    path = os.path.join(folder, "%s_%d.ply" % (model, n))
    subprocess.run([os.path.join(build, "benchmark", "sample_scan"), os.path.join(data, "meshes", model + ".off"), str(n),
                    path], check=True, stdout=subprocess.DEVNULL)
    return path


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = np.radians(degrees)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def stretch(before, after, region, handle, graph):
    """The largest ratio of a 10-nearest-neighbour edge's length after the edit to its length before, over the
    edges of the region's points outside the handle's collar (the handle and 3 rings around it)."""
    collar = handle.copy()
    for _ in range(3):
        collar = graph.ring(collar)
    rows = np.flatnonzero(region & ~collar)
    offsets, neighbors = cgal_ext.compute_neighbor_graph(before, k=10)
    counts = offsets[rows + 1] - offsets[rows]
    i = np.repeat(rows, counts)
    j = np.concatenate([neighbors[offsets[r]:offsets[r + 1]] for r in rows]) if len(rows) else np.zeros(0, int)
    rest = np.linalg.norm(before[i] - before[j], axis=1)
    now = np.linalg.norm(after[i] - after[j], axis=1)
    keep = rest > 0
    return float(np.max(now[keep] / rest[keep])) if keep.any() else 0.0


def edit(session, region, handle, T):
    session.select("roi", "add", np.flatnonzero(region))
    group = session.new_group()
    session.select("handle", "add", np.flatnonzero(handle), group)
    warnings = [w["kind"] + ("" if w.get("group") is None else " %d" % w["group"]) for w in session.warnings()]
    before = session.points
    graph = session.graph()
    region_now, handle_now = session.labels != FIXED, session.labels == FIRST_HANDLE + group
    session.preprocess()
    session.drag(group, T.reshape(-1).tolist())
    session.release()
    return warnings, stretch(before, session.shown_points, region_now, handle_now, graph)


def run_model(path, program, folder):
    name = os.path.basename(path)
    shutil.copy(path, os.path.join(folder, name))
    session = Session(folder)
    start = time.perf_counter()
    session.load(name)
    points = session.points
    extent = np.ptp(points, axis=0)
    diagonal = np.linalg.norm(extent)
    longest, second = np.argsort(-extent)[:2]

    up = points[:, longest]
    region, handle = up >= np.quantile(up, 0.5), up >= np.quantile(up, 0.9)  # ">=": a flat top is a handle too
    pivot = points[handle].mean(axis=0)
    T = np.eye(4)
    T[:3, :3] = rotation(np.eye(3)[second], 30)
    T[:3, 3] = pivot - T[:3, :3] @ pivot + 0.1 * diagonal * np.eye(3)[longest]
    warnings1, stretch1 = edit(session, region, handle, T)
    session.commit()

    side = session.points[:, second]
    region, handle = side >= np.quantile(side, 0.5), side >= np.quantile(side, 0.9)
    T = np.eye(4)
    T[:3, 3] = 0.1 * diagonal * np.eye(3)[second]
    warnings2, stretch2 = edit(session, region, handle, T)
    before = len(session.points)
    session.fill()
    inserted = len(session.points) - before
    session.save("edited")
    seconds = time.perf_counter() - start
    subprocess.run([program, "--quiet", "edit", "-i", os.path.join(folder, name), "--edit",
                    os.path.join(folder, "edited.json"), "-o", os.path.join(folder, "program.ply")], check=True)
    saved = cgal_ext.read_points(os.path.join(folder, "edited.ply")).points
    reproduced = cgal_ext.read_points(os.path.join(folder, "program.ply")).points
    difference = np.abs(saved - reproduced).max() / diagonal if saved.shape == reproduced.shape else float("inf")
    return {"model": name, "points": len(points), "warnings": "; ".join(warnings1 + warnings2) or "none",
            "stretch1": stretch1, "stretch2": stretch2, "inserted": inserted, "difference": difference,
            "seconds": seconds}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--data", default="data")
    parser.add_argument("--build", default="build")
    parser.add_argument("--out", help="writes studio_models_results.csv and .md there")
    parser.add_argument("--quick", action="store_true", help="three small models only")
    parser.add_argument("models", nargs="*")
    args = parser.parse_args()
    program = os.path.join(args.build, "src", "point-detail")
    with tempfile.TemporaryDirectory() as samplings:
        models = args.models or (MODELS[:3] if args.quick else MODELS + [
            sampled(args.build, args.data, samplings, model, n) for model, n in SAMPLINGS])
        rows = []
        for model in models:
            with tempfile.TemporaryDirectory() as folder:
                path = model if os.path.isfile(model) else os.path.join(args.data, "meshes", model + ".off")
                rows.append(run_model(path, program, folder))
    lines = ["# The studio on CGAL's models", "",
             "Written by `benchmark/studio_on_models.py`%s (%d threads): two edits with a commit between them, a fill, a "
             "save and the program on the saved chain, per model (doc/studio.md, \"Tried on other models\")." %
             (" --quick" if args.quick else "", cgal_ext.get_num_threads()), "",
             "| model | points | checks before the edits | stretch, edit 1 | stretch, edit 2 | points filled | "
             "saved vs program (of the diagonal) | session s |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %d | %s | %.2f | %.2f | %d | %.1e | %.1f |" % (
            r["model"], r["points"], r["warnings"], r["stretch1"], r["stretch2"], r["inserted"], r["difference"],
            r["seconds"]))
    print("\n".join(lines))
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "studio_models_results.csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["model", "points", "warnings", "stretch_edit1", "stretch_edit2", "inserted", "difference",
                        "session_s"])
            for r in rows:
                w.writerow([r["model"], r["points"], r["warnings"], "%.4g" % r["stretch1"], "%.4g" % r["stretch2"],
                            r["inserted"], "%.3g" % r["difference"], "%.3g" % r["seconds"]])
        with open(os.path.join(args.out, "studio_models_results.md"), "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
