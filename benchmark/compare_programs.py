#!/usr/bin/env python3
"""Two builds of point-detail on the same inputs, run in turn: the cost of a change to the library, as users pay it
(the command with its defaults, start-up included). Inputs: a 1M-point sampling of the armadillo surface with normals
(random order, no distance ties: what the harness's 1M runs read) and a 1000 x 1000 lattice with smooth bumps and
1 % duplicates (every distance ties: the rule's slow path). Commands: details, curvature, simplify, edit (the harness's
raw-scan edit, a region of 0.4 diagonals around the point farthest along x). Writes order_rule_results.md and .csv.

Usage: benchmark/compare_programs.py --baseline BIN --candidate BIN [--reps R] [--out DIR] [--build DIR] [--models M...] [--commands C...]
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python", "tests"))
from conftest import write_ply  # noqa: E402


def lattice(path):
    j, i = np.mgrid[0:1000, 0:1000]
    x, y = i.ravel() / 512.0, j.ravel() / 512.0
    z = 0.05 * np.sin(5 * x) * np.sin(4 * y)
    normals = np.column_stack([-0.25 * np.cos(5 * x) * np.sin(4 * y), -0.2 * np.sin(5 * x) * np.cos(4 * y), np.ones_like(x)])
    points = np.column_stack([x, y, z])
    points, normals = np.vstack([points, points[::100]]), np.vstack([normals, normals[::100]])
    write_ply(path, points, normals / np.linalg.norm(normals, axis=1)[:, None])
    return points


def edit_json(points, path):
    tip = points[np.argmax(points[:, 0])]
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    with open(path, "w") as f:
        f.write('{"roi": ["sphere:%r,%r,%r,%r"], "handles": [{"select": ["sphere:%r,%r,%r,%r"], "translation": [0, %r, 0]}]}'
                % (*tip, 0.4 * diagonal, *tip, 0.06 * diagonal, 0.05 * diagonal))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--baseline", required=True)
    parser.add_argument("--candidate", required=True)
    parser.add_argument("--reps", type=int, default=5)
    parser.add_argument("--out", default=os.path.dirname(os.path.abspath(__file__)))
    parser.add_argument("--build", default="build")
    parser.add_argument("--models", nargs="+", default=["armadillo_1M", "lattice_1M"])
    parser.add_argument("--commands", nargs="+", default=["details", "curvature", "simplify", "edit"])
    args = parser.parse_args()
    rows = []
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        scan = os.path.join(work, "armadillo_1M.ply")
        subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"), "data/meshes/armadillo.off", "1000000", scan],
                       check=True, capture_output=True)
        from conftest import read_ply, xyz
        inputs = {"armadillo_1M": (scan, xyz(read_ply(scan))),
                  "lattice_1M": (os.path.join(work, "lattice.ply"), None)}
        if "lattice_1M" in args.models:
            inputs["lattice_1M"] = (inputs["lattice_1M"][0], lattice(inputs["lattice_1M"][0]))
        for name, (path, points) in inputs.items():
            if name not in args.models:
                continue
            edit = os.path.join(work, name + "_edit.json")
            edit_json(points, edit)
            commands = {"details": ["details"], "curvature": ["curvature"], "simplify": ["simplify"],
                        "edit": ["edit", "--edit", edit]}
            for command, words in commands.items():
                if command not in args.commands:
                    continue
                times = {"baseline": [], "candidate": []}
                for rep in range(args.reps):
                    for side in (("baseline", "candidate") if rep % 2 == 0 else ("candidate", "baseline")):
                        out = os.path.join(work, "out.ply")
                        start = time.perf_counter()
                        subprocess.run([getattr(args, side), "-q", *words, "-i", path, "-o", out], check=True)
                        times[side].append(time.perf_counter() - start)
                        os.remove(out)
                base, cand = statistics.median(times["baseline"]), statistics.median(times["candidate"])
                rows.append({"model": name, "points": len(points), "command": command, "baseline_s": round(base, 3),
                             "candidate_s": round(cand, 3), "ratio": round(cand / base, 3),
                             "baseline_range": "%.3f-%.3f" % (min(times["baseline"]), max(times["baseline"])),
                             "candidate_range": "%.3f-%.3f" % (min(times["candidate"]), max(times["candidate"])),
                             "runs": args.reps})
                print(rows[-1], flush=True)
    with open(os.path.join(args.out, "order_rule_results.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    with open(os.path.join(args.out, "order_rule_results.md"), "w") as f:
        f.write("# The neighbourhood rule's cost (doc/design.md, \"One neighbourhood rule\")\n\n")
        f.write("Written by `benchmark/compare_programs.py` (%s threads): the program before the rule (baseline) and with "
                "it (candidate), run in turn on the same inputs; wall time of the whole command (start-up, reading and "
                "writing included), median (min-max) of the runs given. The armadillo sampling has no distance ties (the "
                "harness's 1M runs read it); the lattice ties everywhere and has 1 %% duplicates.\n\n" % os.cpu_count())
        f.write("| model | points | command | runs | baseline s | candidate s | candidate / baseline |\n"
                "|---|---:|---|---:|---:|---:|---:|\n")
        for r in rows:
            f.write("| %s | %d | %s | %d | %.3f (%s) | %.3f (%s) | %.3f |\n" % (
                r["model"], r["points"], r["command"], r["runs"], r["baseline_s"], r["baseline_range"], r["candidate_s"],
                r["candidate_range"], r["ratio"]))


if __name__ == "__main__":
    main()
