# The studio's test harness: the server started as a user starts it (python3 -m cgal_ext.studio SCAN) in a
# folder of its own, and headless Chromium driven by Selenium with real pointer events.
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest

from conftest import read_ply, run_program

CHROMEDRIVER = "/usr/bin/chromedriver"
MAX_STRETCH = 3  # the most a 10-nearest-neighbour edge of a bending region may stretch (doc/studio.md)


def make_tentacle(folder, points):
    """The demo's tentacle with `points` points, as folder/tentacle.ply."""
    folder = pathlib.Path(folder)
    run_program("demo", "-o", folder / "demo", "--points", points)
    shutil.copy(folder / "demo" / "tentacle.ply", folder / "tentacle.ply")
    shutil.rmtree(folder / "demo")
    return folder / "tentacle.ply"


class Server:
    """`python3 -m cgal_ext.studio SCAN` in a subprocess; its URL and token from what it prints."""

    def __init__(self, scan, extra=()):
        self.process = subprocess.Popen([sys.executable, "-m", "cgal_ext.studio", str(scan), *extra],
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.process.stdout.readline()
        match = re.search(r"(http://127\.0\.0\.1:(\d+))/\?token=(\S+)", line)
        if not match:
            self.process.kill()
            raise AssertionError("the studio printed %r, %r" % (line, self.process.stderr.read()))
        self.base, self.port, self.token = match.group(1), int(match.group(2)), match.group(3)
        self.url = "%s/?token=%s" % (self.base, self.token)

    def resident_bytes(self):
        with open("/proc/%d/status" % self.process.pid) as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
        raise AssertionError("no VmRSS")

    def stop(self):
        """Ctrl-C, as a user stops it; returns the exit status and what it printed on stderr."""
        self.process.send_signal(signal.SIGINT)
        try:
            _, err = self.process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            raise AssertionError("the studio did not stop on Ctrl-C within 10 s")
        return self.process.returncode, err


def chromium(width=1280, height=800):
    if not os.path.exists(CHROMEDRIVER):
        pytest.fail("Debian's chromium and chromium-driver are needed (scripts/setup.sh installs them)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    # Software WebGL 2 (SwiftShader through ANGLE): no GPU here.
    for argument in ["--headless=new", "--no-sandbox", "--use-gl=angle", "--use-angle=swiftshader",
                     "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--window-size=%d,%d" % (width, height)]:
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)


def wait_for(driver, script, timeout=60, what=None):
    """Polls `return <script>` until it is truthy; returns its value."""
    end = time.monotonic() + timeout
    while True:
        value = driver.execute_script("return " + script)
        if value:
            return value
        if time.monotonic() > end:
            errors = driver.execute_script("return studio.errors")
            raise AssertionError("timed out waiting for %s (page errors: %s)" % (what or script, errors))
        time.sleep(0.05)


def pointer_path(driver, path, press=True, release=True, pause=0.03):
    """Real pointer events (WebDriver actions) along `path`, viewport pixels."""
    from selenium.webdriver.common.actions import interaction
    from selenium.webdriver.common.actions.action_builder import ActionBuilder
    from selenium.webdriver.common.actions.pointer_input import PointerInput
    actions = ActionBuilder(driver, mouse=PointerInput(interaction.POINTER_MOUSE, "mouse"))
    first, rest = path[0], path[1:]
    actions.pointer_action.move_to_location(int(round(first[0])), int(round(first[1])))
    if press:
        actions.pointer_action.pointer_down()
    for x, y in rest:
        actions.pointer_action.move_to_location(int(round(x)), int(round(y)))
        actions.pointer_action.pause(pause)
    if release:
        actions.pointer_action.pointer_up()
    actions.perform()


def screen_box(driver):
    """The model's bounding box on the screen, viewport pixels: x0, x1, y0, y1."""
    return driver.execute_script("""
      const s = studio.projectAll(), r = document.getElementById('canvas').getBoundingClientRect();
      let b = [1e9, -1e9, 1e9, -1e9];
      for (let i = 0; i < studio.n; ++i) {
        b[0] = Math.min(b[0], s[2 * i]); b[1] = Math.max(b[1], s[2 * i]);
        b[2] = Math.min(b[2], s[2 * i + 1]); b[3] = Math.max(b[3], s[2 * i + 1]);
      }
      return [b[0] + r.left, b[1] + r.left, b[2] + r.top, b[3] + r.top];""")


def idle(driver):
    """Waits until the page has no command in flight."""
    wait_for(driver, "!studio.busy && !studio.inFlight && !studio.pending", what="the server's reply")


def hole_fraction(driver):
    """The fraction of the model's silhouette (the drawn pixels, gaps of a few pixels closed, holes filled) where
    the background shows, and the silhouette's pixels."""
    import numpy as np
    from scipy import ndimage
    r = driver.execute_script("return studio.backgroundPixels()")
    background = (np.frombuffer(r["mask"].encode(), np.uint8) == ord("1")).reshape(r["height"], r["width"])
    silhouette = ndimage.binary_fill_holes(ndimage.binary_closing(~background, np.ones((5, 5), bool)))
    return (silhouette & background).sum() / max(silhouette.sum(), 1), silhouette.sum()


def lasso_above(driver, cut):
    """A lasso around the model's part above the screen row `cut`, with X-ray on (its far side too; X-ray is left
    on, as a person leaves it)."""
    x0, x1, y0, y1 = screen_box(driver)
    driver.find_element("id", "tool-lasso").click()
    driver.find_element("id", "paint-roi").click()
    driver.find_element("id", "xray").click()
    pointer_path(driver, [(x0 - 20, y0 - 20), (x1 + 20, y0 - 20), (x1 + 20, cut), (x0 - 20, cut), (x0 - 20, y0 - 19)])
    wait_for(driver, "studio.state.region > 0", what="the region")


def rings(points, seeds, count, within=None, k=10):
    """The points within `count` rings of `seeds` over the k-nearest-neighbour graph (as a mask), walking only
    through `within` when given."""
    from scipy.spatial import cKDTree
    _, neighbours = cKDTree(points).query(points, k + 1)
    reached = seeds.copy()
    for _ in range(count):
        grown = reached.copy()
        grown[neighbours[reached].ravel()] = True
        if within is not None:
            grown &= within | seeds
        reached = grown
    return reached


def assert_the_region_bends(points, deformed, handle, in_region, motion, least_near):
    """An edit whose region bends (doc/studio.md, "Step by step", 4): the region's points within 3 rings of the
    handle follow at least half of the handle's `motion`, and no 10-nearest-neighbour edge of the region outside
    that collar stretches past MAX_STRETCH."""
    import numpy as np
    from scipy.spatial import cKDTree
    moved = deformed - points
    near = rings(points, handle, 3, within=in_region) & ~handle
    follow = moved[near] @ motion / (motion @ motion)
    assert near.sum() > least_near and follow.min() >= 0.5, (near.sum(), follow.min())
    _, neighbours = cKDTree(points).query(points, 11)
    collar = rings(points, handle, 3)
    rows = np.flatnonzero(in_region & ~collar)
    i, j = np.repeat(rows, 10), neighbours[rows, 1:].ravel()
    keep = in_region[j] & ~collar[j]
    i, j = i[keep], j[keep]
    after, before = np.linalg.norm(deformed[i] - deformed[j], axis=1), np.linalg.norm(points[i] - points[j], axis=1)
    stretch = after / np.maximum(before, 1e-12)
    assert stretch.max() <= MAX_STRETCH, (stretch.max(), np.quantile(stretch, 0.99))


def save_as(driver, name):
    """Saves the shown state as `name` by the panel's Save button and waits for the save."""
    driver.execute_script("studio.lastSaved = null")
    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys(name)
    driver.find_element("id", "save").click()
    return wait_for(driver, "studio.lastSaved", what="the save")


def saved_and_reproduced(scan, name):
    """The PLY the studio saved as `name` beside `scan`, and what point-detail edit makes of the scan with the JSON
    saved with it."""
    folder = scan.parent
    program = folder / (name + "_program.ply")
    run_program("edit", "-i", scan, "--edit", folder / (name + ".json"), "-o", program)
    return read_ply(folder / (name + ".ply")), read_ply(program)
