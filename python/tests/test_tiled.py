# The tiled runs on Dask (cgal_ext.tiled): a 2M-point analytic shape in 8 tiles on a LocalCluster of 2 workers
# against the one-process calls, a halo too small, a worker killed mid-run, unreadable tiles and bad inputs.
import glob
import json
import os
import signal
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest
import zarr
from scipy.spatial import cKDTree

from conftest import run_program

import cgal_ext
from cgal_ext import tiled

N = 1_200_000


def bumpy_sphere(n, seed=7):
    """n random samples of r = 1 + 0.02 sin(12 theta) sin(12 phi) and its exact unit normals."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    theta, phi = np.arccos(d[:, 2]), np.arctan2(d[:, 1], d[:, 0])
    r = 1 + 0.02 * np.sin(12 * theta) * np.sin(12 * phi)
    r_theta = 0.24 * np.cos(12 * theta) * np.sin(12 * phi)
    r_phi = 0.24 * np.sin(12 * theta) * np.cos(12 * phi)
    e_theta = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), -np.sin(theta)], axis=1)
    e_phi = np.stack([-np.sin(phi), np.cos(phi), np.zeros(n)], axis=1)
    normals = d - (r_theta / r)[:, None] * e_theta - (r_phi / (r * np.maximum(np.sin(theta), 1e-12)))[:, None] * e_phi
    return d * r[:, None], normals / np.linalg.norm(normals, axis=1)[:, None]


def write_zarr(path, points, normals=None, chunk=250_000):
    group = zarr.open_group(str(path), mode="w")
    for axis, name in enumerate("xyz"):
        group.array(name, points[:, axis], chunks=(chunk,))
    if normals is not None:
        for axis, name in enumerate(("nx", "ny", "nz")):
            group.array(name, normals[:, axis], chunks=(chunk,))


def columns(result, names):
    return np.stack([result[name] for name in names], axis=1)


def read_output(path):
    """{field: array} of a tiled run's PLY or Zarr output."""
    if str(path).endswith(".zarr"):
        group = zarr.open_group(str(path), mode="r")
        return {name: group[name][:] for name in group.array_keys()}
    from conftest import read_ply
    data = read_ply(path)
    return {name: np.asarray(data[name]) for name in data.dtype.names}


@pytest.fixture(scope="module")
def client():
    """The cluster the command starts: two workers of one thread, here with 4 GiB each."""
    c, cluster = tiled._connect(None, 2, "4GiB", 20, lambda message: None)
    with c:
        yield c
    cluster.close()


def environment_and_faults():
    """A worker's GLIBC_TUNABLES and MALLOC_TRIM_THRESHOLD_, and the pages 20 allocations of an 8 MiB array fault
    in after the first two: none when the heap keeps it, at least one each when every one is a fresh mapping.
    Counted on the allocating thread only, and the fewest of three rounds: the worker's other threads (its event
    loop, its profiler) fault pages of their own meanwhile."""
    import resource
    for _ in range(2):  # the first free raises the mmap threshold, the second allocation grows the heap
        array = np.ones(1 << 20)
        del array
    rounds = []
    for _ in range(3):
        before = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt
        for _ in range(20):
            array = np.ones(1 << 20)
            del array
        rounds.append(resource.getrusage(resource.RUSAGE_THREAD).ru_minflt - before)
    return os.environ.get("GLIBC_TUNABLES", ""), os.environ.get("MALLOC_TRIM_THRESHOLD_"), min(rounds)


def test_the_workers_run_as_point_detail(client):
    """The workers start with glibc's malloc on huge pages and without the trim threshold Dask would set, which
    turns off glibc's adaptive mmap threshold."""
    for tunables, trim, faults in client.run(environment_and_faults).values():
        assert "glibc.malloc.hugetlb=1" in tunables and trim is None
        assert faults < 20, faults


def test_workers_started_by_dask_keep_their_freed_memory_in_the_tasks():
    """Workers the tiled runs did not start (a scheduler of the user's) have Dask's trim threshold: their first
    task fixes glibc's thresholds."""
    from distributed import Client, LocalCluster
    from cgal_ext.tiled.runner import task
    environ = dict(os.environ)
    try:
        cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                               silence_logs=40)
    finally:  # Dask's nanny put its variables in this process's environment, where later workers would find them
        os.environ.clear()
        os.environ.update(environ)
    with cluster, Client(cluster) as c:
        _, trim, faults_before = c.submit(environment_and_faults, pure=False).result()
        _, _, faults_in_a_task = c.submit(task, environment_and_faults, pure=False).result()
    assert trim is not None and faults_before >= 20 and faults_in_a_task < 20, (trim, faults_before, faults_in_a_task)


def test_the_tuned_environment_adds_huge_pages_once():
    from cgal_ext._process import tuned_environment
    assert tuned_environment({}) == {"GLIBC_TUNABLES": "glibc.malloc.hugetlb=1"}
    assert tuned_environment({"GLIBC_TUNABLES": "glibc.malloc.tcache_count=0"}) == {
        "GLIBC_TUNABLES": "glibc.malloc.tcache_count=0:glibc.malloc.hugetlb=1"}
    assert tuned_environment({"GLIBC_TUNABLES": "glibc.malloc.hugetlb=0"}) == {}  # the user's choice stands
    assert tuned_environment({"POINT_DETAIL_HUGE_PAGES": "0"}) == {}


def test_a_session_keeps_its_memory_and_its_workers_do_not(monkeypatch):
    """The studio's process keeps what it frees for its next call, whichever thread allocates it; the Dask workers
    it starts run as point-detail does."""
    from cgal_ext._process import KEPT_MEMORY, tuned_environment
    session = tuned_environment({}, keep_memory=True)["GLIBC_TUNABLES"]
    assert session == ":".join(("glibc.malloc.hugetlb=1",) + KEPT_MEMORY)
    assert tuned_environment({"GLIBC_TUNABLES": session}, keep_memory=True) == {}
    chosen = "glibc.malloc.arena_max=4:glibc.malloc.hugetlb=0"  # the user's choices stand
    assert tuned_environment({"GLIBC_TUNABLES": chosen}, keep_memory=True)["GLIBC_TUNABLES"] == \
        ":".join((chosen,) + KEPT_MEMORY[1:])
    monkeypatch.setenv("GLIBC_TUNABLES", session)
    assert tiled.worker_environment()["GLIBC_TUNABLES"] == "glibc.malloc.hugetlb=1"
    # A large array freed by one thread, then asked for by another: only the kept memory serves it without new pages.
    code = ("import resource, threading, numpy as np\n"
            "def touch(): a = np.ones(1 << 25); del a\n"
            "touch(); thread = threading.Thread(target=touch)\n"
            "before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt; thread.start(); thread.join()\n"
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)")
    faults = {}
    for keep in (False, True):
        environ = {k: v for k, v in os.environ.items() if k != "GLIBC_TUNABLES"}
        environ.update(tuned_environment(environ, keep_memory=keep))
        faults[keep] = int(subprocess.run([sys.executable, "-c", code], env=environ, check=True,
                                          capture_output=True, text=True).stdout)
    assert faults[False] >= 100 and faults[True] < 20, faults


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tiled")
    points, normals = bumpy_sphere(N)
    cgal_ext.write_ply(folder / "scan.ply", points, normals)
    write_zarr(folder / "bare.zarr", points)
    small_points, small_normals = bumpy_sphere(100_000, seed=3)
    cgal_ext.write_ply(folder / "small.ply", small_points, small_normals)
    return SimpleNamespace(folder=folder, points=points, normals=normals, ply=folder / "scan.ply",
                           bare=folder / "bare.zarr", small=folder / "small.ply", small_points=small_points,
                           small_normals=small_normals)


def no_leftovers(folder, name):
    return not [p for p in glob.glob(str(folder / f".{name}*"))]


def test_details_equal_the_one_process_call(scan, client):
    report = tiled.run("details", scan.ply, scan.folder / "details.ply", client=client, tiles=8)
    assert report["tiles"] == 8 and report["widened_tiles"] == 0
    # The radii the library measured leave a thin band to search, if any (the lists alone search over a third).
    assert max(s["searched"] for s in report["tile_summaries"]) < 0.2
    out = read_output(scan.folder / "details.ply")
    details, magnitude = cgal_ext.compute_geometric_details(scan.points, scan.normals)
    along_normal = np.einsum("ij,ij->i", details, scan.normals)
    assert np.abs(columns(out, ("detail_x", "detail_y", "detail_z")) - details).max() <= 1e-12
    assert np.abs(out["detail_magnitude"] - magnitude).max() <= 1e-12
    assert np.abs(out["detail_normal"] - along_normal).max() <= 1e-12
    # The colour map saturates at the whole scan's percentile, as the one-process map does.
    assert np.array_equal(columns(out, ("red", "green", "blue")), cgal_ext.diverging_colors(along_normal))
    assert np.array_equal(columns(out, "xyz"), scan.points)
    assert np.array_equal(columns(out, ("nx", "ny", "nz")), scan.normals)
    assert no_leftovers(scan.folder, "details.ply")


def test_curvature_equals_the_one_process_call_with_a_worker_killed(scan, client):
    """A worker process is killed (SIGKILL) while tiles are being computed; Dask reruns its tasks."""
    output = scan.folder / "curvature.zarr"
    result = {}

    def run():
        try:
            result["report"] = tiled.run("curvature", scan.ply, output, client=client, tiles=8,
                                         scratch=scan.folder / "scratch")
        except Exception as error:  # reported by the assertion below
            result["error"] = error

    worker = threading.Thread(target=run)
    (scan.folder / "scratch").mkdir()
    pids = list(client.run(os.getpid).values())
    worker.start()
    deadline = time.monotonic() + 120
    while not glob.glob(str(scan.folder / "scratch" / ".*" / "tile_*")) and time.monotonic() < deadline:
        assert "error" not in result, result["error"]
        time.sleep(0.05)
    assert glob.glob(str(scan.folder / "scratch" / ".*" / "tile_*")), f"no tile finished: {result}"
    os.kill(pids[0], signal.SIGKILL)
    worker.join(300)
    assert "report" in result, f"the run did not complete after a worker was killed: {result}"
    assert pids[0] not in client.run(os.getpid).values()
    out = read_output(output)
    curvature = cgal_ext.estimate_mean_curvature(scan.points, scan.normals)
    assert np.abs(out["mean_curvature"] - curvature).max() <= 1e-12
    assert np.array_equal(columns(out, ("red", "green", "blue")), cgal_ext.diverging_colors(curvature))


def test_without_normals_the_tiles_agree_on_one_orientation(scan, client, tmp_path):
    points = scan.small_points
    write_zarr(tmp_path / "bare.zarr", points)
    report = tiled.run("details", tmp_path / "bare.zarr", tmp_path / "bare_details.ply", client=client, tiles=8)
    out = read_output(tmp_path / "bare_details.ply")
    reference = cgal_ext.estimate_oriented_normals(points)
    same = np.einsum("ij,ij->i", columns(out, ("nx", "ny", "nz")), reference) > 0
    assert same.mean() >= 0.999
    # Flips along the tile borders (within 3 spacings of a face between tiles) no more frequent than inside.
    lo = np.array([[-np.inf if v is None else v for v in box[:3]] for box in report["tile_boxes"]])
    hi = np.array([[np.inf if v is None else v for v in box[3:]] for box in report["tile_boxes"]])
    gap = np.full(len(points), np.inf)
    for a, b in zip(lo, hi):
        inside = np.all((points >= a) & (points < b), axis=1)
        gap[inside] = np.min(np.minimum(points[inside] - a, b - points[inside]), axis=1)
    border = gap < 3 * report["spacing"]
    assert border.sum() > 10_000 and (~border).sum() > 10_000
    assert (~same[border]).mean() <= (~same[~border]).mean()
    # The signed fields follow each tile's orientation: equal to the one-process call's where the normals agree.
    _, magnitude = cgal_ext.compute_geometric_details(points)
    assert np.abs(out["detail_magnitude"] - magnitude)[same].max() <= 1e-12
    assert report["orientation_conflicts"] == 0


def test_normals_of_a_small_scan_match_the_one_process_call(scan, client, tmp_path):
    """The normals operation replaces the scan's own normals by estimated ones, with the k it is given."""
    tiled.run("normals", scan.small, tmp_path / "normals.ply", client=client, tiles=8, k=12)
    out = read_output(tmp_path / "normals.ply")
    reference = cgal_ext.estimate_oriented_normals(scan.small_points, k=12)
    dots = np.einsum("ij,ij->i", columns(out, ("nx", "ny", "nz")), reference)
    assert (dots > 0).mean() >= 0.999 and np.abs(np.abs(dots) - 1).max() <= 1e-12
    assert sorted(out) == ["nx", "ny", "nz", "x", "y", "z"]


def test_a_halo_too_small_is_detected_and_widened(scan, client, tmp_path):
    report = tiled.run("details", scan.small, tmp_path / "out.ply", client=client, tiles=8, halo=1e-4,
                       order="cubic")
    assert report["widened_tiles"] == 8
    assert all(s["halo"] > 1e-4 and s["attempts"][0]["uncertified"] > 0 for s in report["tile_summaries"])
    out = read_output(tmp_path / "out.ply")
    details, _ = cgal_ext.compute_geometric_details(scan.small_points, scan.small_normals, order="cubic")
    assert np.abs(columns(out, ("detail_x", "detail_y", "detail_z")) - details).max() <= 1e-12


def test_enhancement_matches_the_one_process_call(scan, client, tmp_path):
    # A halo that covers the whole scan gives the one-process result; a margin of neighbourhood radii gives it
    # within a fraction of the displacement that falls with the margin (the base surface is a global solve). On
    # these 100,000 points the default of 80 radii covers the sphere: margins of 10 and 30, tiles reading part.
    moved = cgal_ext.enhance_geometric_details(scan.small_points, scan.small_normals, s=2)
    tiled.run("enhance", scan.small, tmp_path / "whole.ply", client=client, tiles=2, s=2, margin=1e4)
    assert np.abs(columns(read_output(tmp_path / "whole.ply"), "xyz") - moved).max() <= 1e-12
    rms = np.sqrt((np.linalg.norm(moved - scan.small_points, axis=1) ** 2).mean())
    errors = {}
    for margin in (10, 30):
        report = tiled.run("enhance", scan.small, tmp_path / "out.ply", client=client, tiles=8, s=2, margin=margin)
        assert not report["exact"] and report["read_points"] < 8 * len(scan.small_points)
        out = read_output(tmp_path / "out.ply")
        errors[margin] = np.abs(columns(out, "xyz") - moved).max() / rms
    assert errors[30] <= 2e-4 and errors[30] <= errors[10] / 100, errors
    assert np.abs(out["displacement"] - np.einsum("ij,ij->i", moved - scan.small_points, scan.small_normals)
                  ).max() <= 2e-4 * rms


def test_unreadable_rows_fail_the_run_naming_them(scan, client, tmp_path):
    write_zarr(tmp_path / "scan.zarr", scan.small_points, scan.small_normals, chunk=20_000)
    (tmp_path / "scan.zarr" / "nx" / "2").write_bytes(b"not a compressed chunk")  # read first by the bucket pass
    with pytest.raises(tiled.TiledError, match=r"rows 0\.\.99999 of .*scan.zarr cannot be read"):
        tiled.run("curvature", tmp_path / "scan.zarr", tmp_path / "out.ply", client=client, tiles=8)
    assert not (tmp_path / "out.ply").exists() and no_leftovers(tmp_path, "out.ply")
    (tmp_path / "scan.zarr" / "x" / "1").write_bytes(b"garbage")
    with pytest.raises(tiled.TiledError, match=r"rows 0\.\.99999 of .*scan.zarr cannot be read"):
        tiled.run("curvature", tmp_path / "scan.zarr", tmp_path / "out.zarr", client=client, tiles=8)
    assert not (tmp_path / "out.zarr").exists() and no_leftovers(tmp_path, "out.zarr")


def test_bad_inputs_get_clear_errors(scan, client, tmp_path):
    assert issubclass(tiled.TiledError, ValueError)  # caught with the library's own errors
    with pytest.raises(tiled.TiledError, match="no such file"):
        tiled.run("details", tmp_path / "missing.ply", tmp_path / "out.ply", client=client)
    (tmp_path / "nox.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double a\n"
                                       b"property double y\nproperty double z\nend_header\n" + bytes(48))
    with pytest.raises(tiled.TiledError, match="no x coordinate"):
        tiled.run("details", tmp_path / "nox.ply", tmp_path / "out.ply", client=client)
    group = zarr.open_group(str(tmp_path / "short.zarr"), mode="w")
    for name, length in (("x", 10), ("y", 10), ("z", 9)):
        group.zeros(name, shape=(length,))
    with pytest.raises(tiled.TiledError, match=r"1-D of one length.*z \(9,\)"):
        tiled.run("details", tmp_path / "short.zarr", tmp_path / "out.ply", client=client)
    points = scan.small_points.copy()
    points[12345, 1] = np.nan
    write_zarr(tmp_path / "nan.zarr", points)
    with pytest.raises(tiled.TiledError, match="point 12345 has a non-finite coordinate"):
        tiled.run("curvature", tmp_path / "nan.zarr", tmp_path / "out.ply", client=client)
    with pytest.raises(tiled.TiledError, match="is the input"):
        tiled.run("details", scan.small, scan.small, client=client)
    with pytest.raises(ValueError, match="unknown option"):
        tiled.run("curvature", scan.small, tmp_path / "out.ply", client=client, order="cubic")
    assert not list(tmp_path.glob("out*")) and not list(tmp_path.glob(".out*"))
    started = time.monotonic()
    with pytest.raises(tiled.TiledError, match="does not answer"):
        tiled.run("details", scan.small, tmp_path / "out.ply", scheduler="tcp://127.0.0.1:9", connect_timeout=5)
    assert time.monotonic() - started < 30


def test_binary_pcd_and_las_are_read_as_the_program_reads_them(scan, client, tmp_path):
    """The tiled runs read a binary PCD (x y z and normals as floats, a padding field between) and a LAS file
    (integers, scale and offset) at the record layout of the I/O layer; the details equal the one-process call on
    the points read_points reads."""
    from test_formats import OFFSET, SCALE, las_file, las_points
    points, normals = scan.small_points[:30_000], scan.small_normals[:30_000]
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("_", "<u4"), ("normal_x", "<f4"), ("normal_y", "<f4"),
              ("normal_z", "<f4")]
    records = np.zeros(len(points), dtype=fields)
    for name, column in zip(("x", "y", "z", "normal_x", "normal_y", "normal_z"), np.hstack([points, normals]).T):
        records[name] = column
    header = ("VERSION 0.7\nFIELDS x y z _ normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4 4\nTYPE F F F U F F F\n"
              f"COUNT 1 1 1 1 1 1 1\nWIDTH {len(points)}\nHEIGHT 1\nPOINTS {len(points)}\nDATA binary\n")
    (tmp_path / "scan.pcd").write_bytes(header.encode() + records.tobytes())
    las_fields = las_points(1, len(points))
    las_fields["ints"] = np.round((points * 100 - OFFSET) / SCALE).astype(np.int64)
    las_file(tmp_path / "scan.las", 1, las_fields, minor=4)
    for name in ("scan.pcd", "scan.las"):
        read = cgal_ext.read_points(tmp_path / name)
        tiled.run("details", tmp_path / name, tmp_path / (name + ".ply"), client=client, tiles=4)
        out = read_output(tmp_path / (name + ".ply"))
        assert np.array_equal(columns(out, "xyz"), read.points), name
        if read.normals is None:
            continue
        assert np.array_equal(columns(out, ("nx", "ny", "nz")), read.normals)
        magnitude = cgal_ext.compute_geometric_details(read.points, read.normals)[1]
        assert np.abs(out["detail_magnitude"] - magnitude).max() <= 1e-12
    with pytest.raises(tiled.TiledError, match="ascii PCD file, whose points cannot be mapped"):
        (tmp_path / "text.pcd").write_text(header.replace("binary", "ascii") + "0 0 0 0 0 0 1\n" * len(points))
        tiled.run("details", tmp_path / "text.pcd", tmp_path / "out.ply", client=client)


def test_the_command_line_runs_on_its_own_cluster(scan, tmp_path):
    command = [sys.executable, "-m", "cgal_ext.tiled", "curvature", str(scan.small), "-o", str(tmp_path / "c.ply"),
               "--workers", "2", "--tiles", "4", "-k", "12", "--report", str(tmp_path / "r.json")]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "4 tiles" in run.stderr and "dashboard" in run.stderr
    out = read_output(tmp_path / "c.ply")
    curvature = cgal_ext.estimate_mean_curvature(scan.small_points, scan.small_normals, k=12)
    assert np.abs(out["mean_curvature"] - curvature).max() <= 1e-12
    failed = subprocess.run(command[:4] + [str(tmp_path / "missing.ply"), "-o", str(tmp_path / "x.ply")],
                            capture_output=True, text=True, timeout=60)
    assert failed.returncode == 1 and "missing.ply: no such file" in failed.stderr


@pytest.mark.parametrize("order", ["linear", "quadric", "cubic"])
def test_the_certificate_holds_exactly_where_it_says(scan, order):
    """Details computed on a box of the scan: every point the certificate accepts equals the whole scan's value;
    the points next to the box's faces, which it rejects, do not."""
    from cgal_ext.tiled import ops, plan
    points, normals = scan.small_points, scan.small_normals
    whole, _ = cgal_ext.compute_geometric_details(points, normals, order=order)
    lo, hi = np.array([-0.3, -np.inf, -np.inf]), np.array([0.4, np.inf, 0.5])
    halo = 0.02
    read = plan.own_mask(points, lo - halo, hi + halo)
    part, _ = cgal_ext.compute_geometric_details(points[read], normals[read], order=order)
    own = plan.own_mask(points[read], lo, hi)
    neighborhoods = plan.Neighborhoods(points[read], 10, plan.border_distance(points[read], lo - halo, hi + halo))
    reach = 1.25 * neighborhoods.kth_distance(10).max()
    certified = plan.certify_symmetric(neighborhoods, 10, own, reach, ops.RINGS[order])
    error = np.abs(part[own] - whole[read][own]).max(axis=1)
    assert 0.5 < certified.mean() < 1 and error[certified].max() <= 1e-12
    # Beyond the certified points, some values do differ: the check is not idle.
    assert (error[~certified] > 1e-9).any()
    with_border = plan.certify_symmetric(neighborhoods, 10, np.ones(read.sum(), dtype=bool), reach,
                                         ops.RINGS[order])
    outside = plan.border_distance(points[read], lo - halo, hi + halo) < 1e-3
    assert not with_border[outside].any()



@pytest.mark.parametrize("order", ["linear", "quadric", "cubic"])
def test_the_banded_search_certifies_what_the_full_search_certifies(scan, order):
    """Neighbours searched only in the band along the border: the same own points certified as with every point
    searched, with a halo that certifies all and with one too narrow for some; the points left out have their k
    nearest within the bound it reports and lie deeper than it says."""
    from cgal_ext.tiled import ops, plan
    points = scan.points[:400_000]
    operation = ops.operation("details", order=order)
    k = operation.own_neighbors()
    spacing = float(np.percentile(cKDTree(points).query(points[::20], k + 1)[0][:, k], 90))  # as a run estimates it
    lo, hi = np.array([-0.3, -np.inf, -np.inf]), np.array([0.4, np.inf, 0.5])
    searched_fractions = []
    for halo in (operation.halo(spacing), 1.2 * spacing):
        read = points[plan.own_mask(points, lo - halo, hi + halo)]
        own = plan.own_mask(read, lo, hi)
        border = plan.border_distance(read, lo - halo, hi + halo)
        reach = 2 * spacing
        banded, interior = plan.banded_neighborhoods(read, k, border, reach, operation.rings(), halo, spacing)
        full = plan.Neighborhoods(read, k, border)
        certified = operation.certify(banded, own, reach, False)
        assert np.array_equal(certified, operation.certify(full, own, reach, False))
        assert interior is not None
        bound, depth = interior
        left_out = ~banded.searched
        assert (full.kth_distance(k)[left_out] <= bound).all()
        assert (plan.border_distance(read[left_out], lo, hi) > depth).all()
        assert np.array_equal(banded.distances[banded.searched], full.distances[banded.searched])
        searched_fractions.append(banded.searched.mean())
    assert searched_fractions[0] < 0.6 and certified.mean() < 1


@pytest.mark.parametrize("order", ["linear", "quadric", "cubic"])
def test_the_radii_certify_what_the_neighbour_lists_certify(scan, order):
    """With the k-th-neighbour distances the library measures, the certificate searches a thin band (or nothing)
    and certifies exactly the own points the lists of every point certify: all with the run's halo, some not with
    narrow ones. Its depth bound holds: every point the lists reject lies within it."""
    from cgal_ext.tiled import ops, plan
    points, normals = scan.points[:400_000], scan.normals[:400_000]
    operation = ops.operation("details", order=order)
    k = operation.own_neighbors()
    spacing = float(np.percentile(cKDTree(points).query(points[::20], k + 1)[0][:, k], 90))
    lo, hi = np.array([-0.3, -np.inf, -np.inf]), np.array([0.4, np.inf, 0.5])
    certified_fractions, searched_fractions = [], []
    for halo in (operation.halo(spacing), 1.2 * spacing, 0.5 * spacing):
        read = plan.own_mask(points, lo - halo, hi + halo)
        own = plan.own_mask(points[read], lo, hi)
        border = plan.border_distance(points[read], lo - halo, hi + halo)
        radius = np.empty(read.sum())
        operation.compute(points[read], normals[read], radius)
        full = plan.Neighborhoods(points[read], k, border)
        assert np.abs(radius - full.kth_distance(k)).max() <= 1e-15 * np.abs(points).max()
        reach = max(2 * spacing, 1.25 * radius[own].max())
        certified, searched = plan.certify_with_radius(points[read], radius, border, own, k, reach,
                                                       operation.rings(), 0.0)
        assert np.array_equal(certified, operation.certify(full, own, reach, False))
        everyone = plan.certify_symmetric(full, k, np.ones(len(border), dtype=bool), reach, operation.rings())
        assert (border[~everyone] <= plan.rejection_depth(radius, border, reach, operation.rings(), 0.0)).all()
        certified_fractions.append(certified.mean())
        searched_fractions.append(searched)
    assert certified_fractions[0] == 1.0 and certified_fractions[-1] < 1.0 and searched_fractions[0] < 0.2


def test_a_sparser_neighbour_tile_makes_a_tile_rerun(client, tmp_path):
    """Half the sphere ten times sparser: the dense tiles' first assumption about their neighbours' k-th-neighbour
    distances is too small, which the check after the tiles finds; the rerun tiles give the one-process result."""
    points, normals = bumpy_sphere(300_000, seed=5)
    keep = (points[:, 2] > 0) | (np.arange(len(points)) % 10 == 0)
    points, normals = points[keep], normals[keep]
    cgal_ext.write_ply(tmp_path / "uneven.ply", points, normals)
    report = tiled.run("details", tmp_path / "uneven.ply", tmp_path / "out.ply", client=client, tiles=8,
                       order="cubic")
    assert any("reach" in attempt for s in report["tile_summaries"] for attempt in s["attempts"])
    details, _ = cgal_ext.compute_geometric_details(points, normals, order="cubic")
    out = read_output(tmp_path / "out.ply")
    assert np.abs(columns(out, ("detail_x", "detail_y", "detail_z")) - details).max() <= 1e-12


def test_a_tie_with_a_point_the_tile_cannot_see_is_not_certified():
    """On a lattice of spacing 1/8, k = 10 takes three rings (12 points, the last four tied at 2 spacings): a point
    two spacings from the read box's open side has a tied neighbour there that the box leaves out, and is not
    certified; one more spacing inside, it is, with the whole lattice's neighbourhood."""
    from cgal_ext.tiled import plan
    j, i = np.mgrid[0:24, 0:24]
    points = np.column_stack([i.ravel() / 8.0, j.ravel() / 8.0, np.zeros(i.size)])
    lo, hi = np.array([-np.inf, -np.inf, -np.inf]), np.array([2.0, np.inf, np.inf])  # x = 2 is outside
    read = plan.own_mask(points, lo, hi)
    neighborhoods = plan.Neighborhoods(points[read], 10, plan.border_distance(points[read], lo, hi))
    row = {x: int(np.flatnonzero((points[read] == [x, 1.5, 0]).all(axis=1))[0]) for x in (1.75, 1.625)}
    assert neighborhoods.kth_distance(10)[row[1.75]] == 0.25 and neighborhoods.border[row[1.75]] == 0.25
    assert not neighborhoods.exact(10)[row[1.75]] and neighborhoods.exact(10)[row[1.625]]
    ball = neighborhoods.neighbors(10)[row[1.625]]
    ball = np.sort(ball[ball < read.sum()])
    whole = plan.Neighborhoods(points, 10, np.full(len(points), np.inf)).neighbors(10)
    full_row = np.flatnonzero((points == [1.625, 1.5, 0]).all(axis=1))[0]
    expected = whole[full_row][whole[full_row] < len(points)]
    assert len(ball) == 12 and np.array_equal(np.flatnonzero(read)[ball], np.sort(expected))


def lattice_scan(duplicates=True):
    """A 500 x 400 raster of spacing 1/256 (distances tie exactly): flat on one half, smooth bumps on the other,
    with exact normals; with every 50th point again (2 % duplicates, as overlapping scans give)."""
    j, i = np.mgrid[0:400, 0:500]
    x, y = i.ravel() / 256.0, j.ravel() / 256.0
    s = np.maximum(x - 1.0, 0.0)
    z = 0.05 * s * s * np.sin(9 * y) * (1 - np.cos(7 * s))
    zx = 0.05 * np.sin(9 * y) * (2 * s * (1 - np.cos(7 * s)) + 7 * s * s * np.sin(7 * s))
    zy = 0.05 * 9 * s * s * np.cos(9 * y) * (1 - np.cos(7 * s))
    points = np.column_stack([x, y, z])
    normals = np.column_stack([-zx, -zy, np.ones_like(x)])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    if duplicates:
        points, normals = np.vstack([points, points[::50]]), np.vstack([normals, normals[::50]])
    return points, normals


def test_on_a_lattice_with_duplicates_the_tiles_equal_the_one_process_calls(client, tmp_path):
    points, normals = lattice_scan()
    shuffled = np.random.default_rng(2).permutation(len(points))
    points, normals = points[shuffled], normals[shuffled]
    cgal_ext.write_ply(tmp_path / "lattice.ply", points, normals)
    write_zarr(tmp_path / "bare.zarr", points, chunk=50_000)
    tiled.run("details", tmp_path / "lattice.ply", tmp_path / "details.ply", client=client, tiles=8, order="cubic")
    details, _ = cgal_ext.compute_geometric_details(points, normals, order="cubic")
    out = read_output(tmp_path / "details.ply")
    assert np.abs(columns(out, ("detail_x", "detail_y", "detail_z")) - details).max() <= 1e-12 * np.abs(details).max()
    tiled.run("curvature", tmp_path / "lattice.ply", tmp_path / "curvature.ply", client=client, tiles=8)
    curvature = cgal_ext.estimate_mean_curvature(points, normals)
    out = read_output(tmp_path / "curvature.ply")
    assert np.abs(out["mean_curvature"] - curvature).max() <= 1e-12 * np.abs(curvature).max()
    tiled.run("normals", tmp_path / "bare.zarr", tmp_path / "normals.ply", client=client, tiles=8)
    estimated = cgal_ext.estimate_oriented_normals(points)
    dots = np.einsum("ij,ij->i", columns(read_output(tmp_path / "normals.ply"), ("nx", "ny", "nz")), estimated)
    assert np.abs(np.abs(dots) - 1).max() <= 1e-12


# ---- simplification sample points ----------------------------------------------------------------------------------

def surfels(path):
    """Centroids, normals, radii and member counts of a surfel PLY (the program's or the tiled run's)."""
    out = read_output(path)
    return columns(out, "xyz"), columns(out, ("nx", "ny", "nz")), out["radius"], out["member_count"]


def test_simplify_equals_the_program_when_the_subsample_is_the_scan(scan, tmp_path):
    """A scan no larger than the subsample is clustered whole on the client: the command's surfels are the
    program's, the centroids up to the quantum of their integer sums."""
    command = [sys.executable, "-m", "cgal_ext.tiled", "simplify", str(scan.small), "-o", str(tmp_path / "t.ply"),
               "--workers", "2", "--target-count", "2000", "--clusters", str(tmp_path / "t_clusters.ply")]
    run = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "sample points from a subsample of 100000" in run.stderr
    run_program("simplify", "-i", scan.small, "-o", tmp_path / "p.ply", "--target-count", "2000", "--clusters",
                tmp_path / "p_clusters.ply")
    # Every point with the program's sample point and colour, field for field.
    tiled_clusters = read_output(tmp_path / "t_clusters.ply")
    program_clusters = read_output(tmp_path / "p_clusters.ply")
    assert list(tiled_clusters) == list(program_clusters)
    for name in program_clusters:
        assert np.array_equal(tiled_clusters[name], program_clusters[name]), name
    centroids, normals, radius, members = surfels(tmp_path / "t.ply")
    program_centroids, program_normals, program_radius, program_members = surfels(tmp_path / "p.ply")
    diagonal = np.linalg.norm(np.ptp(scan.small_points, axis=0))
    assert np.array_equal(members, program_members) and members.sum() == len(scan.small_points)
    assert np.abs(centroids - program_centroids).max() <= 1e-9 * diagonal
    assert np.abs(radius - program_radius).max() <= 1e-9 * diagonal
    assert np.einsum("ij,ij->i", normals, program_normals).min() >= 1 - 1e-9


def test_simplify_gives_the_same_bits_whatever_the_order_and_the_row_ranges(client, tmp_path, monkeypatch):
    """A lattice with duplicate points (some with another normal), in two orders and cut into different row
    ranges, subsampled: the same file, byte for byte, with every point counted once."""
    from cgal_ext.tiled import runner
    points, normals = lattice_scan()
    turned = np.cross(normals[::97], [0.6, 0.8, 0.0])  # at right angles to the first copy's normal
    turned /= np.linalg.norm(turned, axis=1)[:, None]
    points, normals = np.vstack([points, points[::97]]), np.vstack([normals, turned])
    cgal_ext.write_ply(tmp_path / "a.ply", points, normals)
    shuffled = np.random.default_rng(5).permutation(len(points))
    cgal_ext.write_ply(tmp_path / "b.ply", points[shuffled], normals[shuffled])
    subsample = len(points) // 5
    tiled.run("simplify", tmp_path / "a.ply", tmp_path / "a_ssps.ply", client=client, subsample=subsample,
              target_count=500)
    monkeypatch.setattr(runner, "CHUNK_ROWS", 23_456)
    report = tiled.run("simplify", tmp_path / "b.ply", tmp_path / "b_ssps.ply", client=client, subsample=subsample,
                       target_count=500, clusters=tmp_path / "b_clusters.zarr")
    assert 0.9 * subsample < report["subsample"] < 1.1 * subsample
    assert (tmp_path / "a_ssps.ply").read_bytes() == (tmp_path / "b_ssps.ply").read_bytes()
    # Each point keeps its sample point wherever its row went; the Zarr chunks follow the row ranges.
    labels = read_output(tmp_path / "b_clusters.zarr")["ssp_index"]
    assert zarr.open_group(str(tmp_path / "b_clusters.zarr"), mode="r")["ssp_index"].chunks == (23_456,)
    tiled.run("simplify", tmp_path / "a.ply", tmp_path / "a_ssps.ply", client=client, subsample=subsample,
              target_count=500, clusters=tmp_path / "a_clusters.ply")
    assert np.array_equal(read_output(tmp_path / "a_clusters.ply")["ssp_index"][shuffled], labels)
    centroids, normals, radius, members = surfels(tmp_path / "a_ssps.ply")
    assert members.min() >= 1 and members.sum() == len(points) and np.isfinite(np.hstack([centroids, normals])).all()


def test_simplify_sums_every_point_once_and_covers_the_scan_as_the_program_does(scan, client, tmp_path):
    """On the 1.2M-point scan from a subsample of a sixth of it: each point counted once, the members' centroids
    sum to the scan's, the budget kept, the normals outward, and no point further from a sample point than a
    quarter more than with the program's sample points."""
    n = len(scan.points)
    run_program("simplify", "-i", scan.ply, "-o", tmp_path / "p.ply", "--target-count", "3000")
    program_centroids, program_normals = surfels(tmp_path / "p.ply")[:2]
    program_cover = cKDTree(program_centroids).query(scan.points[::5])[0].max()
    report = tiled.run("simplify", scan.ply, tmp_path / "t.ply", client=client, subsample=200_000, target_count=3000)
    centroids, normals, radius, members = surfels(tmp_path / "t.ply")
    assert report["sample_points"] == len(members) <= 1.5 * 3000
    assert members.min() >= 1 and members.sum() == n
    assert np.abs(members @ centroids - scan.points.sum(axis=0)).max() <= 1e-9 * n
    assert np.abs(np.linalg.norm(normals, axis=1) - 1).max() <= 1e-12
    # Outward on the bumpy sphere, but near its poles, where sin(12 phi) makes a spike: there a few clusters of
    # either run lie across it, no more of the tiled run's than of the program's.
    outward = np.einsum("ij,ij->i", normals, centroids / np.linalg.norm(centroids, axis=1)[:, None])
    assert outward[np.abs(centroids[:, 2]) < 0.95].min() > 0.5
    assert (outward < 0).sum() <= max(1, (np.einsum("ij,ij->i", program_normals, program_centroids) < 0).sum())
    assert radius.max() <= 0.1 and (radius[members >= 2] > 0).all()
    cover = cKDTree(centroids).query(scan.points[::5])[0].max()
    assert cover <= 1.25 * program_cover, (cover, program_cover)


def test_simplify_gives_the_same_bytes_with_a_worker_killed(scan, client, tmp_path, monkeypatch):
    """A worker process is killed (SIGKILL) once the first clusters are saved; Dask reruns its tasks on the new
    worker (which fetches the scattered subsample from the other) and the file is the same."""
    from cgal_ext.tiled import runner
    monkeypatch.setattr(runner, "CHUNK_ROWS", 100_000)  # 12 tasks a pass
    options = dict(client=client, subsample=200_000, target_count=3000)
    tiled.run("simplify", scan.ply, tmp_path / "reference.ply", **options)
    run_with_a_worker_killed("simplify", scan.ply, tmp_path, "labels_*.npy", options)
    assert (tmp_path / "killed.ply").read_bytes() == (tmp_path / "reference.ply").read_bytes()


def run_with_a_worker_killed(command, source, tmp_path, saved_name, options):
    """Runs `command` on `source` into tmp_path/killed.ply and kills (SIGKILL) a worker once a file matching
    `saved_name` is in the run's scratch; asserts that the run completed on the new worker."""
    client = options["client"]
    result = {}

    def run():
        try:
            result["report"] = tiled.run(command, source, tmp_path / "killed.ply", scratch=tmp_path / "scratch",
                                         **options)
        except Exception as error:  # reported by the assertion below
            result["error"] = error

    (tmp_path / "scratch").mkdir()
    pids = list(client.run(os.getpid).values())
    worker = threading.Thread(target=run)
    worker.start()
    saved = str(tmp_path / "scratch" / ".*" / saved_name)
    deadline = time.monotonic() + 120
    while not glob.glob(saved) and time.monotonic() < deadline:
        assert "error" not in result, result["error"]
        time.sleep(0.02)
    assert glob.glob(saved), f"nothing was saved: {result}"
    os.kill(pids[0], signal.SIGKILL)
    worker.join(300)
    assert "report" in result, f"the run did not complete after a worker was killed: {result}"
    assert pids[0] not in client.run(os.getpid).values()


def test_simplify_refuses_bad_options_before_writing(scan, client, tmp_path):
    out = tmp_path / "ssps.ply"
    for options, message in (({"tiles": 4}, "has no tiles"), ({"subsample": 0}, "subsample must be"),
                             ({"max_cluster_size": 50}, "unknown option.*max_cluster_size"),
                             ({"target_count": 0}, "target_count must be at least 1"),
                             ({"clusters": scan.small}, "is the input"), ({"clusters": out}, "both the output"),
                             ({"clusters": tmp_path / "c.txt"}, "must end in .ply or .zarr")):
        with pytest.raises(tiled.TiledError, match=message):
            tiled.run("simplify", scan.small, out, client=client, **options)
    with pytest.raises(tiled.TiledError, match="has no normals.*cgal_ext.tiled normals"):
        tiled.run("simplify", scan.bare, out, client=client)
    for options, message in (({"threads_per_task": 2}, "threads_per_task are not taken"),
                             ({"target_count": 4000.0}, "target_count must be a whole number"),
                             ({"mode_threshold": "1"}, "mode_threshold must be a number")):
        with pytest.raises(tiled.TiledError, match=message):
            tiled.run("simplify", scan.small, out, client=client, **options)
    normals = scan.small_normals.copy()
    normals[4321], normals[9876] = 0.0, np.nan
    write_zarr(tmp_path / "bad_normals.zarr", scan.small_points, normals)
    with pytest.raises(tiled.TiledError, match="point 4321 has a normal that is zero or not finite"):
        tiled.run("simplify", tmp_path / "bad_normals.zarr", out, client=client)
    # Points whose hashes all lie above half the range, and a subsample of one: none is drawn.
    from cgal_ext.tiled.simplify import coordinate_hash
    high = coordinate_hash(scan.small_points) > np.uint64(1 << 63)
    write_zarr(tmp_path / "high.zarr", scan.small_points[high], scan.small_normals[high])
    with pytest.raises(tiled.TiledError, match="holds none; give a larger subsample"):
        tiled.run("simplify", tmp_path / "high.zarr", out, client=client, subsample=1)
    points = scan.small_points.copy()
    points[777, 2] = np.inf
    write_zarr(tmp_path / "inf.zarr", points, scan.small_normals)
    with pytest.raises(tiled.TiledError, match="point 777 has a non-finite coordinate"):
        tiled.run("simplify", tmp_path / "inf.zarr", out, client=client)
    assert not list(tmp_path.glob("ssps*")) and no_leftovers(tmp_path, "ssps.ply")


def edit_file(folder, roi="sphere:0,0,1,0.8", handle="sphere:0,0,1,0.25", name="edit.json", **extra):
    """A raise-and-turn of the sphere's top: the program's edit JSON."""
    path = folder / name
    path.write_text(json.dumps({"roi": [roi], "handles": [{"select": [handle], "translation": [0.1, 0, 0.15],
                                                           "rotation": {"axis": [1, 0, 0], "degrees": 20},
                                                           "pivot": [0, 0, 1]}], **extra}))
    return path


def client_subsample(points, normals, size):
    """The subsample the tiled edit's client deforms, sorted as it sorts it."""
    keep = np.ones(len(points), dtype=bool)
    if size < len(points):
        keep = tiled.simplify.coordinate_hash(points) <= np.uint64(int(size / len(points) * 2.0**64))
    p, n = points[keep] + 0.0, tiled.simplify.unit_normals(normals[keep])[0] + 0.0
    order = np.lexsort((*n.T[::-1], *p.T[::-1]))
    return p[order], n[order]


def subsample_deformation(edit, points, normals):
    """The Deformation the client builds and deforms on its subsample, and the program's reading of the edit."""
    program = cgal_ext._core._read_edit(edit, points)
    deformation = cgal_ext.Deformation(points, normals, **program["settings"])
    deformation.insert_roi(program["roi"])
    handle = program["handles"][0]
    deformation.create_handle_group(handle["points"])
    deformation.set_handle_transform(0, handle["rotation"], handle["translation"])
    deformation.deform()
    return deformation, handle


def test_the_tiled_edit_equals_the_deformation_of_its_subsample_and_its_diffusion(scan, client, tmp_path):
    """The tiled edit is the library's Deformation on the client's subsample, its diffusion carried to every point
    by diffuse_points in the tiles, handles and collar included, and the details restored (the tiles near the
    handle read a halo of the collar's reach and the restoration's, the others meeting the region the
    restoration's, the rest none): on the whole scan (a subsample as large) it is the one-process diffuse() and
    restore_details(); on a subsample of 30,000 of the 100,000 points, diffuse_points of all of them. The same
    result whatever the tiles and the order of the points."""
    edit = edit_file(tmp_path)
    points, normals = scan.small_points, scan.small_normals
    report = tiled.run("edit", scan.small, tmp_path / "whole.ply", client=client, tiles=8, edit=edit)
    assert report["subsample"] == len(points) and report["collar_reach"] > 0
    sub_points, sub_normals = client_subsample(points, normals, len(points))
    deformation, handle = subsample_deformation(edit, sub_points, sub_normals)
    assert deformation.diffusion_state()["detail_steps"] == 38  # the restoration's hops by default
    diffused = deformation.diffuse()
    expected = deformation.restore_details()
    assert np.abs(expected.points - diffused.points).max() > 1e-4  # the restoration moves points
    out = read_output(tmp_path / "whole.ply")
    at = {tuple(p): i for i, p in enumerate(sub_points)}
    rows = np.array([at[tuple(p)] for p in points])
    assert np.abs(columns(out, "xyz") - expected.points[rows]).max() <= 1e-12
    assert np.abs(columns(out, ("nx", "ny", "nz")) - expected.normals[rows]).max() <= 1e-12
    on_handle = np.zeros(len(points), dtype=bool)
    on_handle[np.argsort(rows)[handle["points"]]] = True  # the handle's points in the scan's order
    assert np.abs(columns(out, "xyz")[on_handle] - (points[on_handle] @ handle["rotation"].T + handle["translation"])
                  ).max() <= 1e-12
    moved = np.linalg.norm(columns(out, "xyz") - points, axis=1) > 1e-6
    assert 0 < moved.sum() < len(points) and on_handle.sum() > 0

    report = tiled.run("edit", scan.small, tmp_path / "eight.ply", client=client, tiles=8, edit=edit,
                       subsample=30_000)
    sub_points, sub_normals = client_subsample(points, normals, 30_000)
    assert report["subsample"] == len(sub_points) < 40_000
    assert 0 < report["tiles_with_the_halo"] < report["tiles"]  # the tiles far from the handle read less
    # The tiles whose box misses the region read their own points only.
    without = [s["read"] == s["own"] for s in report["tile_summaries"] if s["halo"] == 0]
    assert without and all(without)
    deformation, _ = subsample_deformation(edit, sub_points, sub_normals)
    selection = tiled.edit.Edit(edit=edit).selection(points, np.arange(len(points)))
    expected = cgal_ext.diffuse_points(points, normals, deformation.diffusion_state(), selection=selection,
                                       restore_details=True)
    eight = read_output(tmp_path / "eight.ply")
    assert np.abs(columns(eight, "xyz") - expected.points).max() <= 1e-12
    assert np.abs(columns(eight, ("nx", "ny", "nz")) - expected.normals).max() <= 1e-12
    # Other tiles, and the points in another order: the same bits.
    tiled.run("edit", scan.small, tmp_path / "five.ply", client=client, tiles=5, edit=edit, subsample=30_000)
    order = np.random.default_rng(11).permutation(len(points))
    cgal_ext.write_ply(tmp_path / "shuffled.ply", points[order], normals[order])
    tiled.run("edit", tmp_path / "shuffled.ply", tmp_path / "shuffled_out.ply", client=client, tiles=8, edit=edit,
              subsample=30_000)
    five, shuffled = read_output(tmp_path / "five.ply"), read_output(tmp_path / "shuffled_out.ply")
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        assert np.array_equal(five[name], eight[name])
        assert np.array_equal(shuffled[name], eight[name][order])


def test_the_tiled_edit_restores_the_details_in_tiles_as_one_process(scan, client, tmp_path):
    """On 1.2M points (tiles wider than the restoration's hops), the tiled edit with a subsample of 100,000 equals
    diffuse_points with the restoration over every point in one process: the tiles reading the restoration's
    halo read part of the scan, and their own points land where the whole scan puts them."""
    edit = edit_file(tmp_path)
    report = tiled.run("edit", scan.ply, tmp_path / "tiled.ply", client=client, tiles=8, edit=edit,
                       subsample=100_000)
    summaries = report["tile_summaries"]
    assert any(0 < s["halo"] and s["read"] < 0.8 * len(scan.points) for s in summaries)
    assert report["widened_tiles"] == 0
    sub_points, sub_normals = client_subsample(scan.points, scan.normals, 100_000)
    state = subsample_deformation(edit, sub_points, sub_normals)[0].diffusion_state()
    selection = tiled.edit.Edit(edit=edit).selection(scan.points, np.arange(len(scan.points)))
    expected = cgal_ext.diffuse_points(scan.points, scan.normals, state, selection=selection, restore_details=True)
    diffused = cgal_ext.diffuse_points(scan.points, scan.normals, state, selection=selection)
    out = read_output(tmp_path / "tiled.ply")
    assert np.abs(expected.points - diffused.points).max() > 1e-4
    assert np.abs(columns(out, "xyz") - expected.points).max() <= 1e-12
    assert np.abs(columns(out, ("nx", "ny", "nz")) - expected.normals).max() <= 1e-12


def test_the_tiled_edit_fills_what_it_stretched_as_one_process(scan, client, tmp_path):
    """upsample=True: after the scan's edited rows come the library's new points for the whole edited scan,
    up-sampled from the points the edit moved at their spacing before it (point-detail edit --upsample), in the
    order of their coordinates; the same bytes with other tiles and with the points in another order."""
    edit = tmp_path / "pull.json"
    edit.write_text(json.dumps({"roi": ["sphere:0,0,1,0.9"], "handles": [{"select": ["sphere:0,0,1,0.3"],
                                                                          "translation": [0, 0, 0.5]}]}))
    options = dict(client=client, edit=edit, subsample=30_000, upsample=True)
    report = tiled.run("edit", scan.small, tmp_path / "filled.ply", tiles=8, **options)
    tiled.run("edit", scan.small, tmp_path / "edited.ply", client=client, tiles=8, edit=edit, subsample=30_000)
    points, normals = scan.small_points, scan.small_normals
    edited = read_output(tmp_path / "edited.ply")
    moved = np.flatnonzero(np.any(columns(edited, "xyz") != points, axis=1))
    expected = cgal_ext.upsample_point_set(columns(edited, "xyz"), columns(edited, ("nx", "ny", "nz")), roi=moved,
                                           spacing_before=cgal_ext.compute_local_spacing(points))
    assert len(expected.points) > 1000  # the pull stretched the collar
    assert report["fill"]["inserted"] == len(expected.points) and report["fill"]["tiles"] == 8
    assert report["fill"]["read_points"] < 8 * len(points)  # each tile read part of the edited scan
    filled = read_output(tmp_path / "filled.ply")
    n = len(points)
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        assert np.array_equal(filled[name][:n], edited[name])
    assert np.array_equal(filled["inserted"], np.repeat([0.0, 1.0], [n, len(expected.points)]))
    assert np.abs(columns(filled, "xyz")[n:] - expected.points).max() <= 1e-12
    assert np.abs(columns(filled, ("nx", "ny", "nz"))[n:] - expected.normals).max() <= 1e-12
    # Other tiles, and the points in another order: the same bytes, the scan's rows in its order.
    tiled.run("edit", scan.small, tmp_path / "five.ply", tiles=5, **options)
    order = np.random.default_rng(5).permutation(n)
    cgal_ext.write_ply(tmp_path / "shuffled.ply", points[order], normals[order])
    tiled.run("edit", tmp_path / "shuffled.ply", tmp_path / "shuffled_out.zarr", tiles=8, **options)
    five, shuffled = read_output(tmp_path / "five.ply"), read_output(tmp_path / "shuffled_out.zarr")
    for name in ("x", "y", "z", "nx", "ny", "nz", "inserted"):
        assert np.array_equal(five[name], filled[name])
        assert np.array_equal(shuffled[name], np.concatenate([filled[name][:n][order], filled[name][n:]]))
    assert no_leftovers(tmp_path, "filled.ply")


def test_a_tile_near_a_handle_keeps_every_handle_point_the_collar_needs(tmp_path):
    """Edit.narrowed: a tile near the handle keeps the points within the restoration's halo (the read halo less
    the collar's reach) and, beyond it, the handle points alone; every point it keeps within that halo has each
    handle point of the scan within the collar's reach among those it keeps."""
    from cgal_ext.tiled import plan
    edit = tiled.edit.Edit(edit=edit_file(tmp_path))
    edit.state = {"collar_reach": 0.3, "exact_handles": True, "detail_anchor": 0.01, "detail_iterations": 100,
                  "detail_tolerance": 0.01, "detail_steps": 38}
    points, _ = bumpy_sphere(200_000, seed=5)
    lo, hi, halo = np.array([0.3, -0.2, 0.6]), np.array([0.6, 0.2, 0.9]), 0.5  # beside the handle, not on it
    rows = np.flatnonzero(plan.own_mask(points, lo - halo, hi + halo))
    read = points[rows]
    keep, inner = edit.narrowed(read, rows, lo, hi, halo)
    assert inner == pytest.approx(halo - edit.collar()) and 0 < keep.sum() < len(read)
    kept = read[keep]
    within = kept[plan.own_mask(kept, lo - inner, hi + inner)]
    handles = points[edit.selection(points, np.arange(len(points))) >= 0]
    needed = handles[np.isfinite(cKDTree(within).query(handles, distance_upper_bound=edit.collar())[0])]
    outside = ~plan.own_mask(needed, lo - inner, hi + inner)
    assert outside.sum() > 100  # the collar reaches handle points beyond the restoration's halo
    assert {tuple(p) for p in needed} <= {tuple(p) for p in kept}
    # Far from every handle, or without the restoration, a tile keeps all it read.
    assert edit.narrowed(read, rows, lo + 10, hi + 10, halo)[0] is None
    edit.state = {**edit.state, "detail_iterations": 0, "detail_steps": 0}
    assert edit.narrowed(read, rows, lo, hi, halo)[0] is None


def test_the_tiled_edit_gives_the_same_bytes_with_a_worker_killed(scan, client, tmp_path):
    """A worker process is killed (SIGKILL) once the first tile is saved; Dask reruns its tasks (each carries the
    edit's state) and the file is the same."""
    edit = edit_file(tmp_path)
    options = dict(client=client, tiles=8, edit=edit, subsample=100_000)
    tiled.run("edit", scan.ply, tmp_path / "reference.ply", **options)
    run_with_a_worker_killed("edit", scan.ply, tmp_path, "tile_*", options)
    assert (tmp_path / "killed.ply").read_bytes() == (tmp_path / "reference.ply").read_bytes()


def test_index_files_and_masks_select_the_rows_they_name(scan, client, tmp_path):
    """A region given as an index file (rows of the scan, in any order, repeated, with comments) and a handle as a
    boolean array of the scan's Zarr group select the same points as the sphere specs that chose those rows, and
    the tiled edit gives the same bits, on the subsample and on every point; a scan in another order with the
    index file and mask carried along gives the same result in that order."""
    points, normals = scan.small_points, scan.small_normals
    rows = np.arange(len(points))
    region = np.flatnonzero(tiled.edit.inside(points, rows, tiled.edit.region_specs(["sphere:0,0,1,0.8"], "", "")))
    handle = tiled.edit.inside(points, rows, tiled.edit.region_specs(["sphere:0,0,1,0.25"], "", ""))
    assert 0 < handle.sum() < len(region) < len(points)

    def write(folder, order):
        folder.mkdir()
        write_zarr(folder / "scan.zarr", points[order], normals[order], chunk=30_000)
        zarr.open_group(str(folder / "scan.zarr"), mode="r+").array("top", handle[order], chunks=(30_000,))
        at = np.argsort(order)[region]  # the region's rows in this order
        lines = ["# the region"] + [str(r) for r in np.random.default_rng(2).permutation(at)] + [str(at[0])]
        (folder / "roi.txt").write_text("\n".join(lines) + "\n")
        return edit_file(folder, roi="indices:roi.txt", handle="mask:top")

    by_rows = write(tmp_path / "rows", rows)
    geometric = edit_file(tmp_path)
    for subsample in (30_000, len(points)):
        tiled.run("edit", tmp_path / "rows" / "scan.zarr", tmp_path / f"rows{subsample}.ply", client=client, tiles=8,
                  edit=by_rows, subsample=subsample)
        tiled.run("edit", tmp_path / "rows" / "scan.zarr", tmp_path / f"specs{subsample}.ply", client=client,
                  tiles=8, edit=geometric, subsample=subsample)
        a, b = read_output(tmp_path / f"rows{subsample}.ply"), read_output(tmp_path / f"specs{subsample}.ply")
        assert np.abs(columns(a, "xyz") - points).max() > 1e-3  # the edit moved points
        for name in ("x", "y", "z", "nx", "ny", "nz"):
            assert np.array_equal(a[name], b[name])
    order = np.random.default_rng(4).permutation(len(points))
    shuffled = write(tmp_path / "shuffled", order)
    tiled.run("edit", tmp_path / "shuffled" / "scan.zarr", tmp_path / "shuffled.ply", client=client, tiles=5,
              edit=shuffled, subsample=30_000)
    c = read_output(tmp_path / "shuffled.ply")
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        assert np.array_equal(c[name], read_output(tmp_path / "rows30000.ply")[name][order])


def test_a_selection_painted_on_a_sample_carries_to_every_point_by_its_nearest(scan, client, tmp_path):
    """A selection painted on a sample of the scan (nearest: specs, as the studio saves an edit of a level of
    detail) selects each point of the scan whose nearest sample point, within the sample's reach, is listed: the
    same bits as the index files of those rows; on the sample itself, the painted selection; and the scan in
    another order, with the same sample and files, gives the same result in that order."""
    from scipy.spatial import cKDTree
    points, normals = scan.small_points, scan.small_normals
    sample = client_subsample(points, normals, 30_000)[0]
    cgal_ext.write_ply(tmp_path / "sample.ply", sample)
    painted = {name: np.flatnonzero(tiled.edit.inside(sample, None, tiled.edit.region_specs([spec], "", "")))
               for name, spec in (("roi", "sphere:0,0,1,0.8"), ("handle", "sphere:0,0,1,0.25"))}
    distance, nearest = cKDTree(sample).query(points)
    reach = float(np.quantile(distance, 0.99))  # the farthest percent of the points are not selected
    for name, listed in painted.items():
        (tmp_path / f"{name}.txt").write_text("".join(f"{i}\n" for i in listed))
        rows = np.flatnonzero(np.isin(nearest, listed) & (distance <= reach))
        (tmp_path / f"{name}_rows.txt").write_text("".join(f"{i}\n" for i in rows))
    by_sample = edit_file(tmp_path, roi="nearest:roi.txt", handle="nearest:handle.txt", name="nearest.json",
                          sample={"points": "sample.ply", "reach": reach})
    by_rows = edit_file(tmp_path, roi="indices:roi_rows.txt", handle="indices:handle_rows.txt", name="rows.json")
    for edit, name in ((by_sample, "nearest.ply"), (by_rows, "rows.ply")):
        tiled.run("edit", scan.small, tmp_path / name, client=client, tiles=6, edit=edit, subsample=30_000)
    a, b = read_output(tmp_path / "nearest.ply"), read_output(tmp_path / "rows.ply")
    assert np.abs(columns(a, "xyz") - points).max() > 1e-3
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        assert np.array_equal(a[name], b[name])
    # On the sample, whose points are the tiled edit's subsample, the selection is the one painted.
    operation = tiled.edit.Edit(by_sample, subsample=30_000)
    operation._read_row_sets(SimpleNamespace(count=len(points)), tmp_path)
    selection = operation.selection(sample, np.arange(len(sample)))
    assert np.array_equal(np.flatnonzero(selection != tiled.edit.FIXED), painted["roi"])
    assert np.array_equal(np.flatnonzero(selection == 0), painted["handle"])
    order = np.random.default_rng(5).permutation(len(points))
    cgal_ext.write_ply(tmp_path / "shuffled.ply", points[order], normals[order])
    tiled.run("edit", tmp_path / "shuffled.ply", tmp_path / "shuffled_out.ply", client=client, tiles=5,
              edit=by_sample, subsample=30_000)
    c = read_output(tmp_path / "shuffled_out.ply")
    for name in ("x", "y", "z", "nx", "ny", "nz"):
        assert np.array_equal(c[name], a[name][order])


def test_a_bad_edit_fails_before_any_tile_with_nothing_written(scan, client, tmp_path):
    (tmp_path / "far.txt").write_text(f"1\n{len(scan.small_points)}\n")
    (tmp_path / "bad.txt").write_text("1\n# a comment\n2.5\n")
    write_zarr(tmp_path / "scan.zarr", scan.small_points, scan.small_normals)
    zarr.open_group(str(tmp_path / "scan.zarr"), mode="r+").array("short", np.ones(10, dtype=bool))
    cgal_ext.write_ply(tmp_path / "few.ply", scan.small_points[:1])
    cases = [(edit_file(tmp_path, roi="sphere:5,5,5,0.1", name="far.json"), "roi selects none"),
             (edit_file(tmp_path, handle="indices:far.txt", name="indices.json"),
              rf"far.txt:2: index {len(scan.small_points)} is out of range"),
             (edit_file(tmp_path, handle="indices:bad.txt", name="bad.json"), r"bad.txt:3: '2.5' is not a point index"),
             (edit_file(tmp_path, handle="indices:none.txt", name="none.json"), "cannot read the index file"),
             (edit_file(tmp_path, handle="mask:top", name="mask.json"), "is not one"),
             (edit_file(tmp_path, handle="mask:", name="empty.json"), "is not a region spec"),
             (edit_file(tmp_path, handle="sphere:0,0,-1,0.2", name="outside.json"), "outside the region of interest"),
             (edit_file(tmp_path, rotations="sideways", name="sideways.json"), "rotations must be"),
             (edit_file(tmp_path, handle="nearest:far.txt", name="nosample.json"), "give both or neither"),
             (edit_file(tmp_path, sample={"points": "s.ply", "reach": 1}, name="nonearest.json"), "give both"),
             (edit_file(tmp_path, handle="nearest:far.txt", sample={"points": "s.ply", "reach": 1}, name="s.json"),
              "cannot read the sample"),
             (edit_file(tmp_path, handle="nearest:far.txt", sample={"points": "s.ply", "reach": -1}, name="r.json"),
              "reach must be a positive distance"),
             (edit_file(tmp_path, handle="nearest:far.txt", sample={"points": "few.ply", "reach": 1},
                        name="few.json"), "far.txt:1: index 1 is out of range \\(1 points\\)"),
             (tmp_path / "missing.json", "cannot read")]
    for path, message in cases:
        with pytest.raises(tiled.TiledError, match=message):
            tiled.run("edit", scan.small, tmp_path / "out.ply", client=client, tiles=4, edit=path, subsample=30_000)
        assert not (tmp_path / "out.ply").exists() and no_leftovers(tmp_path, "out.ply")
    for name, message in (("missing", "has no array 'missing'"), ("short", r"1-D boolean array of the scan's 100000")):
        with pytest.raises(tiled.TiledError, match=message):
            tiled.run("edit", tmp_path / "scan.zarr", tmp_path / "out.ply", client=client, tiles=4,
                      edit=edit_file(tmp_path, handle=f"mask:{name}", name="mask.json"), subsample=30_000)
        assert not (tmp_path / "out.ply").exists() and no_leftovers(tmp_path, "out.ply")
    (tmp_path / "chain.json").write_text(json.dumps({"steps": [{"type": "fill"}]}))
    with pytest.raises(tiled.TiledError, match="not a chain of steps"):
        tiled.run("edit", scan.small, tmp_path / "out.ply", client=client, edit=tmp_path / "chain.json")
    with pytest.raises(tiled.TiledError, match="needs the edit JSON"):
        tiled.run("edit", scan.small, tmp_path / "out.ply", client=client)
