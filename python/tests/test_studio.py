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
from studio_support import (Server, assert_the_region_bends, chromium, hole_fraction, idle, lasso_above, make_tentacle,
                            pointer_path, rings, save_as, saved_and_reproduced, screen_box, wait_for)

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


def test_the_page_cookie_opens_its_static_files_only(page):
    """ES modules import each other by plain URLs: the page's response sets the token as a cookie, which opens the
    static files and nothing else (the page and the WebSocket need the token in the URL)."""
    import urllib.error
    import urllib.request
    server, driver = page
    response = urllib.request.urlopen(server.url)
    cookie = response.headers["Set-Cookie"]
    assert "cgal_ext_studio_%d=" % server.port in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    jar = {"Cookie": cookie.split(";")[0]}
    for path in ("/static/main.js", "/static/view.js", "/three/build/three.module.js"):
        assert urllib.request.urlopen(urllib.request.Request(server.base + path, headers=jar)).status == 200
    for path in ("/", "/ws", "/static/main.js"):
        headers = {} if path == "/static/main.js" else jar
        with pytest.raises(urllib.error.HTTPError) as error:
            urllib.request.urlopen(urllib.request.Request(server.base + path, headers=headers))
        assert error.value.code == 403, path
    wrong = {"Cookie": "cgal_ext_studio_%d=wrong" % server.port}
    with pytest.raises(urllib.error.HTTPError) as error:
        urllib.request.urlopen(urllib.request.Request(server.base + "/static/main.js", headers=wrong))
    assert error.value.code == 403


def test_the_command_runs_on_huge_pages(page):
    """Like point-detail, the command restarts itself with glibc's malloc on transparent huge pages."""
    server, _ = page
    with open("/proc/%d/environ" % server.process.pid, "rb") as f:
        environ = f.read().split(b"\0")
    assert any(v.startswith(b"GLIBC_TUNABLES=") and b"glibc.malloc.hugetlb=1" in v for v in environ), environ


def test_paint_drag_save_matches_the_program(page, scan):
    server, driver = page
    wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan", what="the scan")
    shot(driver, "1_opened")
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(points.max(0) - points.min(0))
    # Drawn as a surface: at the default settings the background shows through at most 1 % of the silhouette.
    fraction, silhouette = hole_fraction(driver)
    assert silhouette > 50000 and fraction <= 0.01, (fraction, silhouette)
    # The view starts upright: z (the tentacle's axis at its base) up on the screen, the base at the bottom.
    assert driver.execute_script("return studio.view.up") == "+z"
    base, top = (driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(p))
                 for p in (points[np.argmin(points[:, 2])], points[np.argmax(points[:, 2])]))
    assert top[1] < base[1] - 200

    # The region: the upper half of the tentacle, a lasso above the middle's height with X-ray on (through the
    # model: the far side of the upper half too).
    z_cut = np.quantile(points[:, 2], 0.5)
    lasso_above(driver, driver.execute_script("return studio.screenOf(%r, %r, %r)" %
                                              tuple(points.mean(0)[:2].tolist() + [z_cut]))[1])
    region = driver.execute_script("return studio.state.region")
    assert 0.3 * len(points) < region < 0.7 * len(points)

    # A handle group painted with the brush over the tip (the end of the tentacle, farthest from its base).
    click(driver, "new-group")
    wait_for(driver, "studio.state.groups === 1", what="the handle group")
    click(driver, "tool-brush")
    driver.execute_script("document.getElementById('brush-size').value = 30")
    tip = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(points[np.argmin(points[:, 0])].tolist()))
    pointer_path(driver, [(tip[0] + 10, tip[1] - 15), (tip[0] + 10, tip[1]), (tip[0] + 10, tip[1] + 15)])
    wait_for(driver, "studio.labels && studio.labels.some(l => l === 2)", what="the handle")
    click(driver, "xray")
    labels = np.array(driver.execute_script("return Array.from(studio.labels)"))
    handle = labels == 2
    assert 100 < handle.sum() < 0.2 * region
    # The handle lies in the region's movable part, away from the fixed part: the edit bends the region.
    assert (labels[rings(points, handle, 3)] != 0).all()
    shot(driver, "2_painted")

    # Edit: preprocess, then drag the gizmo's centre 130 px right and 50 px up (the tentacle straightens).
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    wait_for(driver, "studio.prepared && studio.state.preprocessed", what="the preprocessing")
    px, py = driver.execute_script("return studio.pivotScreen()")
    path = [(px, py)] + [(px + 1.3 * t, py - 0.5 * t) for t in range(5, 101, 5)]
    pointer_path(driver, path, release=False)
    wait_for(driver, "studio.framesReceived > 0 && !studio.inFlight && !studio.pending", what="the drag's frames")
    shot(driver, "3_dragging")

    # The live preview is the library's diffuse() in float32.
    shader = np.array(driver.execute_script("return studio.readback()")).reshape(-1, 3)
    matrix = np.array(driver.execute_script("return studio.lastDrag")).reshape(4, 4)
    reference = cgal_ext.Deformation(points, cgal_ext.read_points(scan).normals,
                                     order=driver.execute_script("return studio.state.settings.order"))
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

    save_as(driver, "edited")
    folder = scan.parent
    saved, program = saved_and_reproduced(scan, "edited")
    edit = json.loads((folder / "edited.json").read_text())
    assert np.abs(xyz(saved) - xyz(program)).max() < 1e-9 * diagonal
    for field in ("status", "ssp_index"):
        assert np.array_equal(saved[field], program[field])
    # The handle points sit where the drag put them: the page's last transform.
    step = edit["steps"][-1] if "steps" in edit else edit
    R, t = np.array(step["handles"][0]["matrix"]), np.array(step["handles"][0]["translation"])
    T = _rigid(matrix)
    assert np.abs(R - T[:3, :3]).max() < 1e-9 and np.abs(t - T[:3, 3]).max() < 1e-9 * diagonal
    assert np.abs(xyz(saved)[handle] - (points[handle] @ T[:3, :3].T + T[:3, 3])).max() < 1e-9 * diagonal
    assert not (folder / "tentacle.ply.tmp").exists() and cgal_ext.read_points(scan).points.shape == points.shape

    assert_the_region_bends(points, xyz(saved), handle, labels != 0, T[:3, 3], least_near=100)


def typed(driver, translation, axis=(0, 0, 1), angle=0, pivot=None):
    """Types a transform into the panel's fields and applies it."""
    driver.execute_script("document.getElementById('typed').open = true")
    values = {"typed-translation": " ".join(map(repr, translation)), "typed-axis": " ".join(map(repr, axis)),
              "typed-angle": repr(angle)}
    if pivot is not None:
        values["typed-pivot"] = " ".join(map(repr, pivot))
    for field, value in values.items():
        element = driver.find_element("id", field)
        element.clear()
        element.send_keys(value)
    click(driver, "typed-apply")


def test_a_typed_transform_is_the_same_drag_as_the_gizmo(page, scan):
    server, driver = page
    wait_for(driver, "studio.state && studio.state.step === 1", what="the previous test's drag")
    idle(driver)
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(points.max(0) - points.min(0))
    shown = lambda: np.array(driver.execute_script(
        "return Array.from(studio.geometry.getAttribute('shown').array)")).reshape(-1, 3)
    by_gizmo = shown()
    T = np.array(driver.execute_script("return studio.state.transforms[0]")).reshape(4, 4)
    assert np.abs(T[:3, :3] - np.eye(3)).max() < 1e-12  # the gizmo moved it without turning
    click(driver, "undo")
    wait_for(driver, "studio.state.step === 0", what="the undo")
    idle(driver)
    # The gizmo's translation typed in: the same release.
    typed(driver, T[:3, 3].tolist())
    wait_for(driver, "studio.state.step === 1 && !studio.busy", what="the typed transform's release")
    idle(driver)
    typed_T = np.array(driver.execute_script("return studio.state.transforms[0]")).reshape(4, 4)
    assert np.abs(typed_T - T).max() < 1e-12 * diagonal
    assert np.abs(shown() - by_gizmo).max() < 1e-6 * diagonal
    # A turn about a typed axis through a typed pivot, then undone.
    pivot = points[np.argmin(points[:, 0])]
    typed(driver, [0.0, 0.0, 0.1], axis=[0, 1, 0], angle=30, pivot=pivot.tolist())
    wait_for(driver, "studio.state.step === 2 && !studio.busy", what="the turn's release")
    idle(driver)
    turned = np.array(driver.execute_script("return studio.state.transforms[0]")).reshape(4, 4)
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    assert np.abs(turned[:3, :3] - R).max() < 1e-9
    assert np.abs(turned[:3, 3] - (pivot + [0, 0, 0.1] - R @ pivot)).max() < 1e-9 * diagonal
    click(driver, "undo")
    wait_for(driver, "studio.state.step === 1", what="the undo")
    idle(driver)
    assert np.abs(shown() - by_gizmo).max() < 1e-6 * diagonal


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
    save_as(driver, "undone")
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
    save_as(driver, "scaled")
    roi = next(folder / name for name in ("undone.step0.roi.txt", "undone.roi.txt") if (folder / name).exists())
    run_program("scale", "-i", scan, "--roi", "indices:%s" % roi, "-s", 2,
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


def seen_from(driver, points):
    """Each point's view depth and viewport position, the pixels per world unit at depth 1, the eye."""
    c = driver.execute_script("return studio.cameraMatrices()")
    V, P = np.array(c["view"]).reshape(4, 4).T, np.array(c["projection"]).reshape(4, 4).T
    clip = np.c_[points, np.ones(len(points))] @ (P @ V).T
    depth = clip[:, 3]
    screen = np.c_[(clip[:, 0] / depth * 0.5 + 0.5) * c["width"], (0.5 - clip[:, 1] / depth * 0.5) * c["height"]]
    eye = np.linalg.inv(V)[:3, 3]
    return depth, screen, P[1, 1] * c["height"] / 2, eye


def first_hits(points, spacing, depth, screen, per_unit, rows):
    """For each of `rows`, the view depth where its ray first meets the scan: the nearest point whose disc of
    its local spacing's diameter the ray crosses."""
    from scipy.spatial import cKDTree
    tree = cKDTree(screen)
    reach = (0.5 * spacing * per_unit / depth).max()
    hits = np.empty(len(rows))
    for k, i in enumerate(rows):
        near = np.array(tree.query_ball_point(screen[i], reach))
        off = np.linalg.norm(screen[near] - screen[i], axis=1) * depth[near] / per_unit
        hits[k] = depth[near[off <= 0.5 * spacing[near]]].min()
    return hits


def test_the_brush_takes_only_what_is_seen(page, scan):
    from scipy.spatial import cKDTree
    server, driver = page
    idle(driver)
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0", what="the cleared selection")
    click(driver, "view-side")
    click(driver, "tool-brush")
    click(driver, "paint-roi")
    assert not driver.find_element("id", "xray").is_selected()
    driver.execute_script("document.getElementById('brush-size').value = 40")
    shown = np.array(driver.execute_script("return Array.from(studio.geometry.getAttribute('shown').array)")).reshape(-1, 3)
    normals = np.array(driver.execute_script(
        "return Array.from(studio.geometry.getAttribute('shownNormal').array)")).reshape(-1, 3)
    # A stroke across the tube at a third of its height: the brush covers its whole width on the screen.
    z = np.quantile(shown[:, 2], 0.3)
    ring = shown[np.abs(shown[:, 2] - z) < 0.01]
    left, right = (driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(p))
                   for p in (ring[np.argmin(ring[:, 1])], ring[np.argmax(ring[:, 1])]))
    pointer_path(driver, [(left[0] - 30 + t * (right[0] - left[0] + 60) / 20, left[1]) for t in range(21)])
    wait_for(driver, "studio.state.region > 0", what="the painted region")
    shot(driver, "7_seen_only")
    painted = np.array(driver.execute_script("return Array.from(studio.labels)")) != 0
    assert painted.sum() > 300

    distances, _ = cKDTree(shown).query(shown, 7)
    spacing = distances[:, 1:].mean(1)  # the library's local spacing before its median over neighbours
    depth, screen, per_unit, eye = seen_from(driver, shown)
    rows = np.flatnonzero(painted)
    behind = (depth[rows] - first_hits(shown, spacing, depth, screen, per_unit, rows)) / spacing[rows]
    assert behind.max() <= 3, (behind.max(), np.quantile(behind, 0.99))
    # None on the far side: the normals (oriented as the points the eye sees first face it) face away from the eye.
    view = (shown - eye) / np.linalg.norm(shown - eye, axis=1)[:, None]
    facing = np.einsum("ij,ij->i", normals, view)
    sample = np.flatnonzero(painted)
    sign = -np.sign(np.median(facing[sample]))
    assert (sign * facing[painted] > 0.5).sum() == 0, (sign * facing[painted]).max()
    # X-ray takes the far side too.
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0", what="the cleared selection")
    click(driver, "xray")
    pointer_path(driver, [(left[0] - 30 + t * (right[0] - left[0] + 60) / 20, left[1]) for t in range(21)])
    wait_for(driver, "studio.state.region > 0", what="the painted region")
    click(driver, "xray")
    through = np.array(driver.execute_script("return Array.from(studio.labels)")) != 0
    assert through.sum() > 1.6 * painted.sum() and (sign * facing[through] > 0.5).sum() > 0.3 * painted.sum()
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0", what="the cleared selection")


def test_an_island_handle_is_named_with_its_remedy(page, scan):
    server, driver = page
    wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan", what="the scan")
    idle(driver)
    click(driver, "view-front")
    shown = np.array(driver.execute_script("return Array.from(studio.geometry.getAttribute('shown').array)")).reshape(-1, 3)
    # The region the upper half again, the handle painted at the base: an island in the fixed part.
    lasso_above(driver, driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(
        shown.mean(0)[:2].tolist() + [np.quantile(shown[:, 2], 0.5)]))[1])
    click(driver, "new-group")
    wait_for(driver, "studio.state.groups === 1", what="the handle group")
    click(driver, "tool-brush")
    click(driver, "paint-handle")
    driver.execute_script("document.getElementById('brush-size').value = 25")
    low = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(shown[np.argmin(shown[:, 2])].tolist()))
    pointer_path(driver, [(low[0] - 10, low[1] - 30), (low[0] + 10, low[1] - 30)])
    wait_for(driver, "studio.labels.some(l => l === 2)", what="the handle")
    click(driver, "xray")
    labels = np.array(driver.execute_script("return Array.from(studio.labels)"))
    assert (labels == 2).sum() > 50 and (shown[labels == 2, 2] < np.quantile(shown[:, 2], 0.3)).all()
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    warnings = wait_for(driver, "studio.warnings && studio.warnings.length && studio.warnings", what="the warning")
    assert [w["kind"] for w in warnings] == ["island"] and warnings[0]["group"] == 0
    assert not driver.execute_script("return studio.state.preprocessed")
    text = driver.find_element("id", "warnings").text
    assert "Grow the region around handle group 0" in text and "Edit anyway" in text
    driver.execute_script("document.getElementById('warnings').scrollIntoView()")
    # No stroke's outline left over the view.
    assert driver.execute_script("return studio.selection.stroke") is None
    assert driver.execute_script("return document.getElementById('lasso-outline').getAttribute('points')") == ""
    shot(driver, "8_island_warning")
    # The remedy: the region grows around the handle, then the edit prepares without a word.
    region = driver.execute_script("return studio.state.region")
    click(driver, "grow-around-0")
    wait_for(driver, "studio.state.region > %d && !studio.busy" % region, what="the grown region")
    assert driver.find_element("id", "warnings").text == ""
    click(driver, "edit-start")
    wait_for(driver, "studio.prepared && studio.state.preprocessed", what="the preprocessing")
    assert not driver.execute_script("return studio.warnings && studio.warnings.length")


def edit_upper_half(driver, drag):
    """One edit by hand: the region the upper half (X-ray lasso), a handle group at the tip, Edit, a drag of the
    gizmo by `drag` pixels, release."""
    shown = np.array(driver.execute_script("return Array.from(studio.geometry.getAttribute('shown').array)")).reshape(-1, 3)
    step = driver.execute_script("return studio.state.step")
    lasso_above(driver, driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(
        shown.mean(0)[:2].tolist() + [np.quantile(shown[:, 2], 0.5)]))[1])
    click(driver, "new-group")
    wait_for(driver, "studio.state.groups === 1", what="the handle group")
    click(driver, "tool-brush")
    driver.execute_script("document.getElementById('brush-size').value = 25")
    tip = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(shown[np.argmin(shown[:, 0])].tolist()))
    pointer_path(driver, [(tip[0] + 10, tip[1] - 10), (tip[0] + 10, tip[1] + 10)])
    wait_for(driver, "studio.labels.some(l => l === 2)", what="the handle")
    click(driver, "xray")
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    wait_for(driver, "studio.prepared && studio.state.preprocessed", what="the preprocessing")
    px, py = driver.execute_script("return studio.pivotScreen()")
    pointer_path(driver, [(px, py)] + [(px + drag[0] * t / 20, py + drag[1] * t / 20) for t in range(1, 21)])
    wait_for(driver, "studio.state.step === %d && !studio.busy" % (step + 1), what="the release")
    idle(driver)


def test_two_commits_and_a_fill_are_what_the_program_reproduces(page, scan):
    server, driver = page
    wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan", what="the scan")
    idle(driver)
    if driver.execute_script("return studio.state.preprocessed"):
        click(driver, "undo")  # the island test's prepared edit has no drag: back to its selection's start
        idle(driver)
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0 && studio.state.groups === 0", what="the cleared selection")
    click(driver, "view-front")
    chain = driver.execute_script("return studio.state.chain")
    n = driver.execute_script("return studio.n")
    edit_upper_half(driver, (100, -40))
    click(driver, "commit")
    wait_for(driver, "studio.state.chain.length === %d && studio.state.groups === 0" % (len(chain) + 1), what="the commit")
    idle(driver)
    edit_upper_half(driver, (-160, -30))  # a pull: the region stretches, the fill has gaps to fill
    shot(driver, "9_second_edit")
    click(driver, "fill")
    wait_for(driver, "studio.state.chain.length === %d && studio.n > %d && !studio.busy" % (len(chain) + 3, n),
             timeout=300, what="the fill")
    idle(driver)
    assert driver.execute_script("return studio.state.chain").count("edit") == chain.count("edit") + 2
    assert driver.execute_script("return studio.state.chain")[-1] == "fill"
    inserted = driver.execute_script("return studio.inserted ? studio.inserted.reduce((a, b) => a + b, 0) : 0")
    assert inserted == driver.execute_script("return studio.n") - n > 0
    shot(driver, "10_filled")

    save_as(driver, "chain")
    saved, program = saved_and_reproduced(scan, "chain")
    points = cgal_ext.read_points(scan).points
    diagonal = np.linalg.norm(points.max(0) - points.min(0))
    assert len(saved) == len(program) == driver.execute_script("return studio.n")
    assert np.abs(xyz(saved) - xyz(program)).max() < 1e-9 * diagonal


def test_mirrored_editing_moves_the_second_group_as_the_mirror_image(page):
    from selenium.webdriver.support.ui import Select
    server, driver = page
    wait_for(driver, "studio.n > 0 && studio.state && studio.state.scan", what="the scan")
    idle(driver)
    click(driver, "clear")
    wait_for(driver, "studio.state.region === 0 && studio.state.groups === 0", what="the cleared selection")
    click(driver, "view-side")  # looking along x: y across the screen, z up
    shown = np.array(driver.execute_script("return Array.from(studio.geometry.getAttribute('shown').array)")).reshape(-1, 3)
    # The region: the upper half all around; two handle groups on either side of the tube at three quarters' height.
    lasso_above(driver, driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(
        shown.mean(0)[:2].tolist() + [np.quantile(shown[:, 2], 0.5)]))[1])
    click(driver, "xray")
    z = np.quantile(shown[:, 2], 0.75)
    ring = shown[np.abs(shown[:, 2] - z) < 0.01]
    click(driver, "tool-brush")
    driver.execute_script("document.getElementById('brush-size').value = 15")
    for g, side in enumerate((ring[np.argmin(ring[:, 1])], ring[np.argmax(ring[:, 1])])):
        click(driver, "new-group")
        wait_for(driver, "studio.state.groups === %d" % (g + 1), what="the handle group")
        Select(driver.find_element("id", "group")).select_by_index(g)
        click(driver, "paint-handle")
        at = driver.execute_script("return studio.screenOf(%r, %r, %r)" % tuple(side.tolist()))
        pointer_path(driver, [(at[0] + (6 if g == 0 else -6), at[1] - 5), (at[0] + (6 if g == 0 else -6), at[1] + 5)])
        wait_for(driver, "studio.labels.some(l => l === %d)" % (2 + g), what="handle group %d" % g)
    Select(driver.find_element("id", "group")).select_by_index(0)
    driver.execute_script("document.getElementById('mirroring').open = true")
    Select(driver.find_element("id", "mirror-group")).select_by_index(1)
    Select(driver.find_element("id", "mirror-axis")).select_by_value("1")
    click(driver, "mirror")
    click(driver, "tool-orbit")
    click(driver, "edit-start")
    wait_for(driver, "studio.prepared && studio.state.preprocessed", what="the preprocessing")
    step = driver.execute_script("return studio.state.step")
    px, py = driver.execute_script("return studio.pivotScreen()")
    pointer_path(driver, [(px, py)] + [(px - 3 * t, py - 2 * t) for t in range(1, 21)])
    wait_for(driver, "studio.state.step === %d && !studio.busy" % (step + 1), what="the release")
    idle(driver)
    shot(driver, "11_mirrored")
    labels = np.array(driver.execute_script("return Array.from(studio.labels)"))
    rest = np.array(driver.execute_script("return Array.from(studio.rest)")).reshape(-1, 3)
    centres = [rest[labels == 2 + g].mean(0) for g in (0, 1)]
    M = np.eye(4)
    M[1, 1] = -1
    M[1, 3] = centres[0][1] + centres[1][1]  # the plane y = the centres' midpoint
    T0, T1 = (np.array(t).reshape(4, 4) for t in driver.execute_script("return studio.state.transforms"))
    assert np.abs(T0[:3, 3]).max() > 0.01  # the drag moved group 0
    assert np.abs(T1 - M @ T0 @ M).max() < 1e-5
    assert T0[1, 3] * T1[1, 3] < 0 and abs(T0[2, 3] - T1[2, 3]) < 1e-5  # across the plane opposite, up the same
    click(driver, "mirror")


def test_the_point_budget_draws_a_subset_while_the_view_moves(page):
    server, driver = page
    idle(driver)
    n = driver.execute_script("return studio.n")
    budget = driver.find_element("id", "budget")
    budget.clear()
    budget.send_keys("20000")
    click(driver, "tool-orbit")  # also takes the focus off the field, which applies it
    assert driver.execute_script("return studio.drawn") == n
    x0, x1, y0, y1 = screen_box(driver)
    middle = ((x0 + x1) / 2, (y0 + y1) / 2)
    pointer_path(driver, [middle, (middle[0] + 40, middle[1])], release=False)
    assert driver.execute_script("return studio.drawn") == 20000
    fraction, _ = hole_fraction(driver)
    assert fraction <= 0.02, fraction  # the subset's sprites grow to cover for the others
    pointer_path(driver, [(middle[0] + 40, middle[1])], press=False, release=True)
    wait_for(driver, "studio.drawn === %d" % n, what="every point drawn again")
    budget.clear()
    budget.send_keys("1000000")
    click(driver, "view-front")


def test_the_page_logged_no_error(page):
    server, driver = page
    severe = [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert severe == [] and driver.execute_script("return studio.errors.filter(e => /failed/.test(e))") == []
    # The page works under its content security policy (three.js served from the studio itself): nothing blocked.
    assert driver.execute_script("return studio.errors.filter(e => /content security policy/.test(e))") == []
