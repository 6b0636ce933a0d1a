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

Usage: PYTHONPATH=build/python benchmark/studio_on_models.py [--data data] [--program build/src/point-detail] [MODEL...]
(a MODEL is a name in data/meshes or a point file, such as a sampling by build/benchmark/sample_scan)
"""
import argparse
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
    parser.add_argument("--program", default=os.path.join("build", "src", "point-detail"))
    parser.add_argument("models", nargs="*", default=MODELS)
    args = parser.parse_args()
    print("| model | points | checks before the edits | stretch, edit 1 | stretch, edit 2 | points filled | "
          "saved vs program (of the diagonal) | session time |")
    print("|---|---|---|---|---|---|---|---|")
    for model in args.models:
        with tempfile.TemporaryDirectory() as folder:
            path = model if os.path.isfile(model) else os.path.join(args.data, "meshes", model + ".off")
            r = run_model(path, args.program, folder)
        print("| %s | %d | %s | %.2f | %.2f | %d | %.1e | %.1f s |" % (
            r["model"], r["points"], r["warnings"], r["stretch1"], r["stretch2"], r["inserted"], r["difference"],
            r["seconds"]))


if __name__ == "__main__":
    main()
