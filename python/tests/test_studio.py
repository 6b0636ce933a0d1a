# The studio as a person meets it: headless Chromium with real pointer events on the page the server serves,
# each step's screenshot written to the build folder (doc/studio.md shows them), and the results checked against
# the library and the program.
import json
import os
import pathlib

import numpy as np
import pytest

import cgal_ext
from conftest import read_ply, run_program, xyz
from studio_support import Server, chromium, idle, make_tentacle, pointer_path, screen_box, wait_for

SHOTS = pathlib.Path(os.environ.get("CGAL_EXT_STUDIO_SHOTS") or
                     pathlib.Path(os.environ.get("CGAL_EXT_CMAKE_BUILD_DIR", "build")) / "studio_screenshots")


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    return make_tentacle(tmp_path_factory.mktemp("studio"), 100000)


@pytest.fixture(scope="module")
def page(scan):
    server = Server(scan)
    driver = chromium()
    try:
        driver.get(server.url)
        yield server, driver
    finally:
        driver.quit()
        server.stop()


def shot(driver, name):
    SHOTS.mkdir(parents=True, exist_ok=True)
    driver.save_screenshot(str(SHOTS / ("studio_%s.png" % name)))


def click(driver, element_id):
    driver.find_element("id", element_id).click()


def test_paint_drag_save_matches_the_program(page, scan):
    server, driver = page
    wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan", what="the scan")
    shot(driver, "1_opened")
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(points.max(0) - points.min(0))

    # The region: a lasso around the upper part of the tentacle (z up on the screen), half of its points.
    x0, x1, y0, y1 = screen_box(driver)
    z_cut = np.quantile(points[:, 2], 0.5)
    cut = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(points.mean(0)[:2].tolist() + [z_cut]))[1]
    click(driver, "tool-lasso")
    click(driver, "paint-roi")
    pointer_path(driver, [(x0 - 20, y0 - 20), (x1 + 20, y0 - 20), (x1 + 20, cut), (x0 - 20, cut), (x0 - 20, y0 - 19)])
    wait_for(driver, "studio.state.region > 0", what="the region")
    region = driver.execute_script("return studio.state.region")
    assert 0.3 * len(points) < region < 0.7 * len(points)

    # A handle group painted with the brush over the tip.
    click(driver, "new-group")
    wait_for(driver, "studio.state.groups === 1", what="the handle group")
    click(driver, "tool-brush")
    driver.execute_script("document.getElementById('brush-size').value = 40")
    tip = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(points[np.argmax(points[:, 2])].tolist()))
    pointer_path(driver, [(tip[0] - 20, tip[1] + 10), (tip[0], tip[1] + 10), (tip[0] + 20, tip[1] + 10)])
    wait_for(driver, "studio.labels && studio.labels.some(l => l === 2)", what="the handle")
    labels = np.array(driver.execute_script("return Array.from(studio.labels)"))
    handle = labels == 2
    assert 100 < handle.sum() < 0.2 * region
    shot(driver, "2_painted")

    # Edit: preprocess, then drag the gizmo's centre 100 px up and 60 px left.
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    wait_for(driver, "studio.renderer && studio.state.preprocessed", what="the preprocessing")
    px, py = driver.execute_script("return studio.pivotScreen()")
    path = [(px, py)] + [(px - 0.6 * t, py - t) for t in range(5, 101, 5)]
    pointer_path(driver, path, release=False)
    wait_for(driver, "studio.framesReceived > 0 && !studio.inFlight && !studio.pending", what="the drag's frames")
    shot(driver, "3_dragging")

    # The live preview is the library's diffuse() in float32.
    shader = np.array(driver.execute_script("return studio.readback()")).reshape(-1, 3)
    matrix = np.array(driver.execute_script("return studio.lastDrag")).reshape(4, 4)
    reference = cgal_ext.Deformation(points, cgal_ext.read_points(scan).normals, order="cubic")
    reference.insert_roi(labels != 0)
    reference.create_handle_group(handle)
    reference.set_handle_transform(0, transform=_rigid(matrix))
    reference.deform()
    diffused = reference.diffuse().points
    assert np.abs(shader - diffused).max() < 1e-5 * diagonal
    assert np.abs(diffused - points).max() > 0.05 * diagonal  # the drag moved the handle visibly

    pointer_path(driver, [path[-1]], press=False, release=True)
    wait_for(driver, "studio.state.step === 1", what="the release")
    idle(driver)
    shot(driver, "4_released")

    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys("edited")
    click(driver, "save")
    wait_for(driver, "studio.lastSaved", what="the save")
    folder = scan.parent
    saved = read_ply(folder / "edited.ply")
    edit = json.loads((folder / "edited.json").read_text())
    run_program("edit", "-i", scan, "--edit", folder / "edited.json", "-o", folder / "program.ply")
    program = read_ply(folder / "program.ply")
    assert np.abs(xyz(saved) - xyz(program)).max() < 1e-9 * diagonal
    for field in ("status", "ssp_index"):
        assert np.array_equal(saved[field], program[field])
    # The handle points sit where the drag put them: the page's last transform.
    R, t = np.array(edit["handles"][0]["matrix"]), np.array(edit["handles"][0]["translation"])
    T = _rigid(matrix)
    assert np.abs(R - T[:3, :3]).max() < 1e-9 and np.abs(t - T[:3, 3]).max() < 1e-9 * diagonal
    assert np.abs(xyz(saved)[handle] - (points[handle] @ T[:3, :3].T + T[:3, 3])).max() < 1e-9 * diagonal
    assert not (folder / "tentacle.ply.tmp").exists() and cgal_ext.read_points(scan).points.shape == points.shape


def test_undo_returns_the_input_and_details_match_the_program(page, scan):
    server, driver = page
    wait_for(driver, "studio.state && studio.state.step === 1", what="the previous test's drag")
    click(driver, "undo")
    wait_for(driver, "studio.state.step === 0", what="the undo")
    idle(driver)
    shot(driver, "5_undone")
    shown = np.array(driver.execute_script("return Array.from(studio.geometry.getAttribute('shown').array)"))
    points = cgal_ext.read_points(scan).points
    assert np.array_equal(shown.reshape(-1, 3), points.astype(np.float32))
    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys("undone")
    driver.execute_script("studio.lastSaved = null")
    click(driver, "save")
    wait_for(driver, "studio.lastSaved", what="the save")
    folder = scan.parent
    assert np.array_equal(xyz(read_ply(folder / "undone.ply")), points)  # bit for bit

    # The details slider at s = 2, previewed and applied: point-detail scale -s 2 on the same region.
    driver.execute_script("const s = document.getElementById('details-s'); s.value = 2; s.dispatchEvent(new Event('input'))")
    click(driver, "details-preview")
    idle(driver)
    shot(driver, "6_details_preview")
    click(driver, "details-apply")
    wait_for(driver, "studio.state.base_changed", what="the details")
    idle(driver)
    driver.execute_script("studio.lastSaved = null")
    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys("scaled")
    click(driver, "save")
    wait_for(driver, "studio.lastSaved", what="the save")
    run_program("scale", "-i", scan, "--roi", "indices:%s" % (folder / "undone.roi.txt"), "-s", 2,
                "-o", folder / "program_scaled.ply")
    diagonal = np.linalg.norm(points.max(0) - points.min(0))
    scaled = xyz(read_ply(folder / "scaled.ply"))
    assert np.abs(scaled - xyz(read_ply(folder / "program_scaled.ply"))).max() < 1e-9 * diagonal
    assert np.abs(scaled - points).max() > 1e-4 * diagonal


def _rigid(rows):
    """The 4x4 the page sent, snapped to the nearest rotation as the session does."""
    T = np.array(rows, dtype=float).reshape(4, 4)
    u, _, vt = np.linalg.svd(T[:3, :3])
    T[:3, :3] = u @ vt
    return T


def test_saving_over_a_file_the_session_did_not_write_asks_first(page, scan):
    from selenium.webdriver.support import expected_conditions
    from selenium.webdriver.support.ui import WebDriverWait
    server, driver = page
    idle(driver)
    taken = scan.parent / "taken.ply"
    taken.write_bytes(b"another program's file\n")
    driver.execute_script("studio.lastSaved = null")
    driver.find_element("id", "save-name").clear()
    driver.find_element("id", "save-name").send_keys("taken")
    # Declined: nothing written.
    click(driver, "save")
    question = WebDriverWait(driver, 60).until(expected_conditions.alert_is_present())
    assert "taken.ply" in question.text and "Replace?" in question.text
    question.dismiss()
    wait_for(driver, "document.getElementById('error').textContent.includes('not saved')", what="the refusal")
    assert taken.read_bytes() == b"another program's file\n" and not (scan.parent / "taken.json").exists()
    # Accepted: saved with overwrite.
    click(driver, "save")
    WebDriverWait(driver, 60).until(expected_conditions.alert_is_present()).accept()
    saved = wait_for(driver, "studio.lastSaved", what="the save")
    assert "taken.ply" in saved
    assert cgal_ext.read_points(taken).points.shape == cgal_ext.read_points(scan).points.shape


def test_the_page_logged_no_error(page):
    server, driver = page
    severe = [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert severe == [] and driver.execute_script("return studio.errors.filter(e => /failed/.test(e))") == []
    # The page works under its content security policy (three.js served from the studio itself): nothing blocked.
    assert driver.execute_script("return studio.errors.filter(e => /content security policy/.test(e))") == []
