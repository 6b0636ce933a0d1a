# The studio in Chromium on a scan its other tests were not tuned on: CGAL's bunny (bunny00, a range scan with
# holes, its normals from the mesh's faces). It opens upright and whole, the brush takes only what is seen, and an
# edit by hand of its upper part bends the region and is what the program reproduces. Opened as its level of detail
# (a limit below its points), the same edit is saved through the tiled edit, which its command reproduces.
import os
import shutil

import numpy as np
import pytest

import cgal_ext
from conftest import DATA, read_ply, xyz
from studio_support import (Server, assert_the_region_bends, chromium, hole_fraction, idle, lasso_above, pointer_path,
                            save_as, saved_and_reproduced, screen_box, wait_for)
from test_studio import click, first_hits, seen_from, shot


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    mesh = os.path.join(DATA, "meshes", "bunny00.off")
    if not os.path.exists(mesh):
        pytest.skip("no " + mesh + " (scripts/fetch_data.sh)")
    folder = tmp_path_factory.mktemp("bunny")
    shutil.copy(mesh, folder / "bunny00.off")
    return folder / "bunny00.off"


@pytest.fixture(scope="module")
def page(scan):
    server = Server(scan)
    driver = chromium()
    try:
        driver.get(server.url)
        wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan && studio.spacing", what="the scan")
        idle(driver)
        yield server, driver
    finally:
        driver.quit()
        server.stop()


def test_the_scan_opens_upright_and_whole(page, scan):
    server, driver = page
    points = cgal_ext.read_points(scan).points
    # The bunny stands along y: y up on the screen, its ears (the highest points) above its base.
    assert driver.execute_script("return studio.view.up") == "+y"
    base, top = (driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(p))
                 for p in (points[np.argmin(points[:, 1])], points[np.argmax(points[:, 1])]))
    assert top[1] < base[1] - 100
    fraction, silhouette = hole_fraction(driver)
    assert silhouette > 50000 and fraction <= 0.01, (fraction, silhouette)
    shot(driver, "bunny_1_opened")


def test_the_brush_takes_only_what_is_seen_on_a_scan(page, scan):
    from scipy.spatial import cKDTree
    server, driver = page
    idle(driver)
    click(driver, "tool-brush")
    click(driver, "paint-roi")
    assert not driver.find_element("id", "xray").is_selected()
    driver.execute_script("document.getElementById('brush-size').value = 40")
    shown = cgal_ext.read_points(scan).points
    normals = cgal_ext.read_points(scan).normals
    # A stroke across the whole body at half its height on the screen.
    x0, x1, y0, y1 = screen_box(driver)
    y = 0.5 * (y0 + y1)
    pointer_path(driver, [(x0 - 30 + t * (x1 - x0 + 60) / 20, y) for t in range(21)])
    wait_for(driver, "studio.state.region > 0", what="the painted region")
    shot(driver, "bunny_2_seen_only")
    painted = np.array(driver.execute_script("return Array.from(studio.labels)")) != 0
    assert painted.sum() > 300

    distances, _ = cKDTree(shown).query(shown, 7)
    spacing = distances[:, 1:].mean(1)
    depth, screen, per_unit, eye = seen_from(driver, shown)
    rows = np.flatnonzero(painted)
    behind = (depth[rows] - first_hits(shown, spacing, depth, screen, per_unit, rows)) / spacing[rows]
    assert behind.max() <= 3, (behind.max(), np.quantile(behind, 0.99))
    # None on the far side: the scan's normals face outwards, so a painted point's must not face away from the eye.
    view = (shown - eye) / np.linalg.norm(shown - eye, axis=1)[:, None]
    facing = np.einsum("ij,ij->i", normals, view)
    assert (facing[painted] > 0.5).sum() == 0, facing[painted].max()
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0", what="the cleared selection")


def paint_and_drag_the_ear(driver, points):
    """The region: the upper half on the screen, through the model (X-ray); the handle: the ears' tips, dragged up
    and to the right by the gizmo and released. Returns the labels painted."""
    x0, x1, y0, y1 = screen_box(driver)
    lasso_above(driver, 0.5 * (y0 + y1))
    click(driver, "new-group")
    wait_for(driver, "studio.state.groups === 1", what="the handle group")
    click(driver, "tool-brush")
    driver.execute_script("document.getElementById('brush-size').value = 30")
    top = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(points[np.argmax(points[:, 1])].tolist()))
    pointer_path(driver, [(top[0] - 15, top[1] + 10), (top[0], top[1] + 10), (top[0] + 15, top[1] + 10)])
    wait_for(driver, "studio.labels && studio.labels.some(l => l === 2)", what="the handle")
    click(driver, "xray")
    labels = np.array(driver.execute_script("return Array.from(studio.labels)"))
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    wait_for(driver, "studio.prepared && studio.state.preprocessed", what="the preprocessing (no warning)")
    px, py = driver.execute_script("return studio.pivotScreen()")
    pointer_path(driver, [(px, py)] + [(px + 0.8 * t, py - 0.4 * t) for t in range(5, 101, 5)])
    wait_for(driver, "studio.state.step === 1", what="the release")
    idle(driver)
    return labels


def test_an_edit_of_its_upper_part_bends_and_the_program_reproduces_it(page, scan):
    server, driver = page
    idle(driver)
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    labels = paint_and_drag_the_ear(driver, points)
    handle, in_region = labels == 2, labels != 0
    assert 20 < handle.sum() < 0.2 * in_region.sum()
    assert not driver.execute_script("return studio.warnings && studio.warnings.length")
    shot(driver, "bunny_3_edited")

    save_as(driver, "edited")
    saved, program = saved_and_reproduced(scan, "edited")
    assert np.abs(xyz(saved) - xyz(program)).max() < 1e-9 * diagonal
    motion = (xyz(saved) - points)[handle].mean(axis=0)
    assert np.linalg.norm(motion) > 0.02 * diagonal
    assert_the_region_bends(points, xyz(saved), handle, in_region, motion, least_near=20)


@pytest.fixture(scope="module")
def level_page(scan, tmp_path_factory):
    """The bunny as a binary PLY opened with a limit below its points: the studio opens its level of detail."""
    folder = tmp_path_factory.mktemp("bunny_level")
    cloud = cgal_ext.read_points(scan)
    cgal_ext.write_ply(folder / "bunny.ply", cloud.points, cloud.normals)
    server = Server(folder / "bunny.ply", ["--level-of-detail-above", "30000", "--level-points", "20000"])
    driver = chromium()
    try:
        driver.get(server.url)
        wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan && studio.spacing", timeout=120,
                 what="the level of detail")
        idle(driver)
        yield server, driver, folder / "bunny.ply"
    finally:
        driver.quit()
        server.stop()


def test_over_the_limit_the_level_of_detail_is_edited_and_saved_through_the_tiled_edit(level_page):
    """Painted, dragged and saved in the page, the edit of the level of detail is carried to every point of the
    scan by the tiled edit: what the tiled command makes of the saved JSON, a region that bends."""
    import subprocess
    import sys
    from scipy.spatial import cKDTree
    server, driver, scan = level_page
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    shown = np.array(driver.execute_script("return Array.from(studio.rest)")).reshape(-1, 3)
    assert 15_000 < len(shown) < 25_000 and driver.execute_script("return studio.state.level_of_detail.scan_points") == \
        len(points)
    assert "level of detail" in driver.find_element("id", "status").text
    labels = paint_and_drag_the_ear(driver, points)
    shot(driver, "bunny_4_level_of_detail")
    # What a level of detail cannot carry to its scan is off, and says why.
    for button in ("commit", "fill", "details-apply"):
        assert not driver.find_element("id", button).is_enabled()
        assert "level of detail" in driver.find_element("id", button).get_attribute("title")

    driver.execute_script("studio.lastSaved = null")
    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys("edited")
    driver.find_element("id", "save").click()
    wait_for(driver, "studio.lastSaved", timeout=300, what="the save through the tiled edit")
    # Beside the button, at the panel's foot: what was saved (each pass's progress before it).
    assert "edited.ply" in driver.find_element("id", "save-status").text
    saved = xyz(read_ply(scan.parent / "edited.ply"))
    subprocess.run([sys.executable, "-m", "cgal_ext.tiled", "edit", str(scan), "--edit", str(scan.parent / "edited.json"),
                    "-o", str(scan.parent / "command.ply"), "--subsample", "20000"], check=True, capture_output=True)
    assert np.abs(saved - xyz(read_ply(scan.parent / "command.ply"))).max() <= 1e-12 * diagonal
    # Each point of the scan labelled as its nearest point of the level (the points shown): a region that bends.
    level = cgal_ext.read_points(scan.parent / "edited.sample.ply").points
    assert np.abs(level - shown).max() < 1e-6 * diagonal
    carried = labels[cKDTree(level).query(points)[1]]
    handle, in_region = carried == 2, carried != 0
    motion = (saved - points)[handle].mean(axis=0)
    assert np.linalg.norm(motion) > 0.02 * diagonal
    assert_the_region_bends(points, saved, handle, in_region, motion, least_near=20)


def test_the_page_logged_no_error(page):
    server, driver = page
    severe = [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert severe == [] and driver.execute_script("return studio.errors.filter(e => /failed/.test(e))") == []
