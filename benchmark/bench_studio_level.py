#!/usr/bin/python3
"""The studio on a scan larger than it edits whole (doc/studio.md, "Scans larger than one machine"), on a seeded
sampling of CGAL's armadillo to 100M points (--quick: 600k, the limit 400k, the level 60k):

- from starting `python3 -m cgal_ext.studio SCAN` to its geometry received by a WebSocket client connected as the
  page connects: the first time (the level of detail read by a tiled pass on Dask and cached beside the scan), then
  from the cache (median of 3);
- the server's time per drag frame on the level of detail (as bench_studio.py measures it);
- the save: the edit carried to every point by the tiled edit, as the page's Save runs it; and the largest distance
  from a point of the scan (2M drawn at random) to its nearest point of the level, against the reach the save uses.

Writes OUT/studio_level_results.csv and OUT/studio_level_results.md.
Usage: PYTHONPATH=build/python benchmark/bench_studio_level.py --out DIR [--build build] [--data data] [--quick]
"""
import asyncio
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np

import cgal_ext
from cgal_ext._process import reexecute_tuned
from cgal_ext.studio.session import Session

from bench_python import harness_arguments, median
from bench_studio import selection, server_costs
from bench_tiled import write_results


async def _geometry_received(port, token):
    import aiohttp
    async with aiohttp.ClientSession() as http:
        async with http.ws_connect("ws://127.0.0.1:%d/ws?token=%s" % (port, token), max_msg_size=0,
                                   headers={"Origin": "http://127.0.0.1:%d" % port}) as ws:
            async for message in ws:
                if message.type == aiohttp.WSMsgType.BINARY:
                    return
                if message.type == aiohttp.WSMsgType.TEXT and json.loads(message.data).get("type") == "error":
                    raise RuntimeError(message.data)
    raise RuntimeError("the studio closed the connection before sending the geometry")


def open_seconds(scan, options):
    """Seconds from starting the studio's command to the scan's geometry at a connected client."""
    start = time.perf_counter()
    process = subprocess.Popen([sys.executable, "-m", "cgal_ext.studio", scan, *options], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, text=True)
    try:
        match = re.search(r"127\.0\.0\.1:(\d+)/\?token=(\S+)", process.stdout.readline())
        if not match:
            raise RuntimeError("the studio did not print its address")
        asyncio.run(_geometry_received(int(match.group(1)), match.group(2)))
        return time.perf_counter() - start
    finally:
        process.send_signal(signal.SIGINT)
        process.wait(60)


def save_costs(folder, name, options):
    """The save of an edit of the level (its upper half the region, its top tenth the handle, raised), through the
    tiled edit; and the largest distance from 2M points of the scan to the level against the save's reach."""
    from scipy.spatial import cKDTree
    session = Session(folder, **options)
    session.load(name)
    region, handle = selection(session.points)
    session.select("roi", "add", region)
    group = session.new_group()
    session.select("handle", "add", handle, group)
    session.preprocess()
    T = np.eye(4)
    T[1, 3] = 0.03 * np.linalg.norm(np.ptp(session.points, axis=0))
    session.drag(group, T.reshape(-1).tolist())
    session.release()
    start = time.perf_counter()
    session.save("edited")
    seconds = time.perf_counter() - start
    scan = cgal_ext.read_points(os.path.join(folder, name)).points
    drawn = np.random.default_rng(1).choice(len(scan), min(len(scan), 2_000_000), replace=False)
    farthest = float(cKDTree(session.points).query(scan[drawn])[0].max())
    return seconds, farthest / session.level["reach"]


def main():
    reexecute_tuned([sys.executable] + sys.argv, keep_memory=True)  # as the studio command runs
    args = harness_arguments()
    n, above, level = (600_000, 400_000, 60_000) if args.quick else (100_000_000, 20_000_000, 1_000_000)
    options = ["--level-of-detail-above", str(above), "--level-points", str(level)]
    rows = []
    os.makedirs(args.out, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=args.out) as tmp:  # beside the results: the scan may not fit in /tmp
        name = "armadillo_%d.ply" % n
        subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                        os.path.join(args.data, "meshes", "armadillo.off"), str(n), os.path.join(tmp, name)],
                       check=True, stdout=subprocess.DEVNULL)
        scan = os.path.join(tmp, name)
        first = open_seconds(scan, options)
        cached = median([open_seconds(scan, options) for _ in range(3)])
        drag = server_costs(tmp, name, 20 if args.quick else 200, 1,
                            session_options={"level_of_detail_above": above, "level_points": level})
        save, beyond = save_costs(tmp, name, {"level_of_detail_above": above, "level_points": level})
        rows += [("open: command started to geometry received, level of detail built and cached", n, first, "s",
                  "<= 120 s at 100M"),
                 ("open: command started to geometry received, level of detail cached", n, cached, "s",
                  "<= 15 s at 100M"),
                 ("server time per drag frame on the level of detail (%d points)" % drag["points"], n,
                  drag["frame_s"] * 1e3, "ms", "<= 2 ms"),
                 ("save: the edit carried to every point by the tiled edit (region %d level points)" % drag["region"],
                  n, save, "s", "reported"),
                 ("largest distance from a point (2M drawn) to the level, in reaches", n, beyond, "",
                  "< 1: every point selected through its nearest")]
    write_results(args.out, "studio_level_results", "The studio on a scan larger than it edits whole",
                  "Written by `benchmark/bench_studio_level.py`%s: a seeded sampling of CGAL's armadillo, opened with "
                  "`--level-of-detail-above %d --level-points %d`; a LocalCluster of 2 workers for the level and the "
                  "save." % (" --quick" if args.quick else "", above, level), rows)

if __name__ == "__main__":
    main()
