#!/usr/bin/python3
"""The studio's costs (doc/studio.md) on seeded samplings of CGAL's armadillo (1M and 4M points; --quick: 100k):

- the server's time per drag frame, from the command's text in to the frame's bytes out (JSON parsing, the
  handle transform, deform(), the sample points' motions, packing), and the frame's size against 64 bytes per
  sample point + 1 KiB; the release (the full diffusion and restore_details);
- commit and Fill gaps through the server's handlers at 1M points, the second edit's region 300k points;
- in headless Chromium (software WebGL): from opening the URL of a scan without normals to the first drag possible
  (reading, normals, sending the geometry, preprocessing; the painting itself left out), and the page's frame time
  while a drag is live, at 100k, 1M, 4M and 10M points (above 1M with the page's point budget of 1M and without),
  and the background seen through the silhouette at the default view.

The server's handlers run in this process, which starts as `python3 -m cgal_ext.studio` does: glibc's malloc on
huge pages. Medians over the repetitions. Writes OUT/studio_results.csv and OUT/studio_results.md.
Usage: PYTHONPATH=build/python benchmark/bench_studio.py --out DIR [--build build] [--data data] [--quick]
"""
import asyncio
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
from cgal_ext.studio.server import pack
from cgal_ext.studio.session import Session

from bench_python import harness_arguments, median

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "python", "tests"))


def selection(points):
    """The upper half of the model is the region, its top tenth the handle (the armadillo stands along y)."""
    up = points[:, 1]
    return np.flatnonzero(up > np.quantile(up, 0.5)), np.flatnonzero(up > np.quantile(up, 0.9))


def server_costs(folder, name, frames, releases, session_options=None):
    session = Session(folder, **(session_options or {}))
    session.load(name)
    region, handle = selection(session.points)
    session.select("roi", "add", region)
    group = session.new_group()
    session.select("handle", "add", handle, group)
    start = time.perf_counter()
    setup = session.preprocess()
    preprocess = time.perf_counter() - start
    pivot = session.points[handle].mean(axis=0)
    frame_times, sizes = [], []
    for step in range(frames):
        a = np.radians(0.5 * step)
        T = np.eye(4)
        T[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
        T[:3, 3] = pivot - T[:3, :3] @ pivot + (0, 0.002 * step, 0)
        text = json.dumps({"type": "drag", "group": group, "matrix": T.reshape(-1).tolist(), "seq": step})
        start = time.perf_counter()
        command = json.loads(text)
        frame = session.drag(command["group"], command["matrix"])
        data = pack({"type": "frame", "seq": command["seq"]}, [("frame", frame)])
        frame_times.append(time.perf_counter() - start)
        sizes.append(len(data))
    release = []
    half = np.eye(4)
    half[:3, :3] = [[np.cos(a / 2), 0, np.sin(a / 2)], [0, 1, 0], [-np.sin(a / 2), 0, np.cos(a / 2)]]
    half[:3, 3] = pivot - half[:3, :3] @ pivot + (0, 0.001 * frames, 0)
    for r in range(releases):  # each after a drag of its own (a release with nothing dragged does nothing)
        session.drag(group, (T if r % 2 else half).reshape(-1).tolist())
        start = time.perf_counter()
        session.release()
        release.append(time.perf_counter() - start)
    return {"preprocess_s": preprocess, "frame_s": median(frame_times), "frame_bytes": max(sizes),
            "frame_budget_bytes": 64 * int(setup["sample_points"]) + 1024, "sample_points": int(setup["sample_points"]),
            "release_s": median(release), "region": len(region), "points": len(session.points)}


class Recorder:
    """A WebSocket that keeps what the server sends: the commands' handlers run as the page meets them."""
    closed = False

    def __init__(self):
        self.messages = []

    async def send_json(self, message):
        self.messages.append(message)

    async def send_bytes(self, data):
        self.messages.append(len(data))


def commit_and_fill_costs(folder, name, region_size, repetitions):
    """Commit, then a second edit of `region_size` points stretched by its handle and Fill gaps, each timed from
    the command to its last reply, through the server's own handlers (the geometry packed as for the page)."""
    from cgal_ext.studio.server import Studio

    async def run():
        studio = Studio(folder)
        ws = Recorder()
        session = studio.session

        async def timed(command):
            start = time.perf_counter()
            await studio.handle(ws, command)
            elapsed = time.perf_counter() - start
            errors = [m for m in ws.messages if isinstance(m, dict) and m.get("type") == "error"]
            assert not errors, errors
            return elapsed

        async def edit(region, handle, lift):
            await studio.handle(ws, {"type": "select", "target": "roi", "mode": "add", "indices": region})
            await studio.handle(ws, {"type": "new_group"})
            await studio.handle(ws, {"type": "select", "target": "handle", "mode": "add", "indices": handle, "group": 0})
            await studio.handle(ws, {"type": "preprocess", "force": True})
            T = np.eye(4)
            T[1, 3] = lift
            await studio.handle(ws, {"type": "drag", "group": 0, "matrix": T.reshape(-1).tolist(), "seq": 0})
            await studio.handle(ws, {"type": "release"})

        await studio.handle(ws, {"type": "load", "path": name})
        diagonal = np.linalg.norm(np.ptp(session.points, axis=0))
        commits, fills, inserted = [], [], []
        for _ in range(repetitions):
            region, handle = selection(session.points)
            await edit(region, handle, 0.05 * diagonal)
            commits.append(await timed({"type": "commit"}))
            # The second edit: the region the top `region_size` points, its top tenth pulled up by a tenth of the
            # diagonal (a stretch the fill then fills).
            up = session.points[:, 1]
            order = np.argsort(up, kind="stable")
            region, handle = order[-region_size:], order[-region_size // 10:]
            await edit(region, handle, 0.1 * diagonal)
            before = len(session.points)
            fills.append(await timed({"type": "fill"}))
            inserted.append(len(session.points) - before)
            for _ in range(3):  # back to the scan: fill, the second edit, commit
                await studio.handle(ws, {"type": "undo"})
            while session.step > 0:
                await studio.handle(ws, {"type": "undo"})
            await studio.handle(ws, {"type": "clear"})  # the first edit's selection, kept at the scan's step
        return median(commits), median(fills), int(median(inserted))

    return asyncio.run(run())


def browser_costs(folder, name, frame_seconds, budgets, renders=5):
    """First drag possible after opening the URL, and the page's frame time during a live drag with each point
    budget of `budgets` (0: every point drawn; the page's default is 1M)."""
    from studio_support import Server, chromium, hole_fraction, wait_for
    points = cgal_ext.read_points(os.path.join(folder, name)).points
    region, handle = selection(points)
    server = Server(os.path.join(folder, name))
    driver = chromium()
    driver.set_script_timeout(300)
    try:
        start = time.perf_counter()
        driver.get(server.url)
        wait_for(driver, "studio.n > 0 && studio.state && studio.state.points", timeout=600)
        loaded = time.perf_counter() - start
        # Drawn as a surface: the background through the model's silhouette, at the default view and settings.
        wait_for(driver, "studio.spacing", timeout=600)
        holes = hole_fraction(driver)[0]
        # The painting, as the page sends it at once (not timed: a person's time, which the mean shift, computed in
        # the background from the moment the scan is shown, would overlap; here it has none to overlap).
        for target, indices in (("roi", region), ("handle", handle)):
            if target == "handle":
                driver.execute_script("studio.send({type: 'new_group'})")
                wait_for(driver, "studio.state.groups === 1")
            driver.execute_script("studio.sendIndices({type: 'select', target: arguments[0], mode: 'add', "
                                  "group: 0}, new Uint32Array(arguments[1])); ", target, indices.tolist())
            wait_for(driver, "studio.state.region >= %d" % (len(region) if target == "roi" else 1), timeout=120)
        painting = time.perf_counter()
        driver.execute_script("studio.send({type: 'preprocess', force: true})")
        wait_for(driver, "studio.prepared && studio.state.preprocessed", timeout=600)
        preprocessed = time.perf_counter() - painting
        driver.execute_script("studio.continuous = true; studio.requestRender()")
        time.sleep(1)
        driver.execute_script("studio.frameTimes = []")
        time.sleep(frame_seconds)
        idle = median(driver.execute_script("studio.continuous = false; return studio.frameTimes"))
        # A live drag: a new transform each time the last frame arrived; the page's frame intervals meanwhile,
        # drawn as during a drag by the gizmo (at most the budget).
        driver.execute_script("""
          studio.liveDrag = true;
          let step = 0;
          const next = () => {
            if (!studio.liveDrag) return;
            if (!studio.inFlight && !studio.pending) {
              const a = 0.005 * ++step, c = Math.cos(a), s = Math.sin(a);
              studio.pending = {type: 'drag', group: 0, matrix: [c, 0, s, 0, 0, 1, 0, 0.001 * step, -s, 0, c, 0, 0, 0, 0, 1]};
              studio.gizmo.flush();
            }
            setTimeout(next, 1);
          };
          next();""")
        wait_for(driver, "studio.framesReceived > 2", timeout=120)
        driver.execute_script("studio.frameTimes = []")
        time.sleep(frame_seconds)
        driver.execute_script("studio.liveDrag = false")
        wait_for(driver, "!studio.inFlight", timeout=120)
        interval = median(driver.execute_script("return studio.frameTimes"))
        # The drawing of one frame of the live edit, as the gizmo's drag draws it (at most the budget): rendered
        # and read back (a pixel, which waits for the frame), timed in the page, a few times each after a few
        # untimed ones.
        live = {}
        for budget in budgets:
            live[budget] = driver.execute_script("""
              const view = studio.view, gl = view.webgl.getContext(), times = [], pixel = new Uint8Array(4);
              view.budget = arguments[0]; view.setMoving(false); view.setMoving(true);
              // A few frames first: software GL's first frames after a change of what it draws are slow (its
              // routines built, the buffers paged in), a drag's later ones are not.
              for (let r = 0; r < 3; ++r) { view.render(); gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); }
              for (let r = 0; r < arguments[1]; ++r) {
                const start = performance.now();
                view.render();
                gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); // waits for the frame
                times.push(performance.now() - start);
              }
              const drawn = studio.drawn;
              view.setMoving(false);
              times.sort((a, b) => a - b);
              return [times[times.length >> 1], drawn, times];""", budget, renders)[:2]
        frames = driver.execute_script("return studio.framesReceived")
    finally:
        driver.quit()
        server.stop()
    return {"open_to_loaded_s": loaded, "preprocess_s": preprocessed, "first_drag_s": loaded + preprocessed,
            "live": live, "interval_ms": interval, "idle_frame_ms": idle, "drag_frames": frames, "holes": holes}


def main():
    reexecute_tuned([sys.executable] + sys.argv, keep_memory=True)  # as the studio command runs
    args = harness_arguments()
    server_sizes, browser_sizes = ([100000], [100000]) if args.quick else ([1000000, 4000000],
                                                                           [100000, 1000000, 4000000, 10000000])
    # The page's default budget, and none; at 10M the budgeted frame is judged against the 1M frame without one.
    budgets = {100000: [0], 1000000: [0], 4000000: [1000000, 0], 10000000: [1000000, 0]}
    frames, releases, frame_seconds = (20, 1, 2) if args.quick else (200, 5, 8)
    commit_sizes, region_size, commit_repetitions = ([100000], 30000, 1) if args.quick else ([1000000], 300000, 3)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in sorted(set(server_sizes + browser_sizes + commit_sizes)):
            name = "armadillo_%d.ply" % n
            subprocess.run([os.path.join(args.build, "benchmark", "sample_scan"),
                            os.path.join(args.data, "meshes", "armadillo.off"), str(n), os.path.join(tmp, name)],
                           check=True)
            # The same points without normals: the studio estimates them, as the program does.
            cgal_ext.write_ply(os.path.join(tmp, "bare_" + name), cgal_ext.read_points(os.path.join(tmp, name)).points)
            if n in server_sizes:
                r = server_costs(tmp, name, frames, releases)
                rows += [("server time per drag frame", n, r["frame_s"] * 1e3, "ms", "<= 2 ms"),
                         ("bytes per drag frame (%d sample points)" % r["sample_points"], n, r["frame_bytes"], "B",
                          "<= %d B" % r["frame_budget_bytes"]),
                         ("release: diffusion + restore_details (region %d points)" % r["region"], n, r["release_s"], "s",
                          "<= 1 s at 1M"),
                         ("preprocess (with normals)", n, r["preprocess_s"], "s", "")]
            if n in commit_sizes:
                commit, fill, inserted = commit_and_fill_costs(tmp, name, region_size, commit_repetitions)
                rows += [("commit: the shown state the base of the next edit, geometry sent", n, commit, "s",
                          "<= 1 s at 1M"),
                         ("fill gaps after an edit of %d points (%d points inserted)" % (region_size, inserted), n, fill,
                          "s", "<= 2 s at 1M")]
            if n in browser_sizes:
                r = browser_costs(tmp, "bare_" + name, frame_seconds, budgets.get(n, [0]))
                rows += [("open URL to scan shown, without normals", n, r["open_to_loaded_s"], "s", ""),
                         ("open URL to first drag possible, without normals", n, r["first_drag_s"], "s", "<= 10 s at 1M"),
                         ("background through the silhouette, default view", n, 100 * r["holes"], "%", "<= 1 %")]
                for budget, (frame_ms, drawn) in r["live"].items():
                    target = "<= the 1M frame without a budget" if budget and n > budget else "reported"
                    rows.append(("page frame time of a live drag, %s (%d points drawn; headless Chromium, SwiftShader)" %
                                 ("point budget %d" % budget if budget else "no point budget", drawn),
                                 n, frame_ms, "ms", target))
                if r["interval_ms"] == r["interval_ms"]:  # NaN when no two frames came within the time measured
                    rows.append(("page frame interval during a scripted live drag, every point drawn", n,
                                 r["interval_ms"], "ms", "reported"))
                rows.append(("page frame time, no drag (every point drawn, continuously)", n, r["idle_frame_ms"], "ms",
                             "reported"))
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "studio_results.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["measure", "points", "value", "unit", "target"])
        for row in rows:
            w.writerow([row[0], row[1], "%.6g" % row[2], row[3], row[4]])
    lines = ["# The studio", "",
             "Written by `benchmark/bench_studio.py`%s (%d threads): a seeded sampling of CGAL's armadillo; the region "
             "is its upper half, the handle its top tenth; medians of %d drag frames and %d releases; the page in "
             "headless Chromium with software WebGL (SwiftShader), no GPU." %
             (" --quick" if args.quick else "", cgal_ext.get_num_threads(), frames, releases), "",
             "| measure | points | value | target |", "|---|---|---|---|"]
    for measure, n, value, unit, target in rows:
        lines.append("| %s | %d | %s %s | %s |" % (measure, n, "%.3g" % value if unit != "B" else "%d" % value, unit,
                                                    target))
    with open(os.path.join(args.out, "studio_results.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
