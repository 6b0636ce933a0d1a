# The Python module against the library's numbers as the point-detail program gives them, on a generated shape
# and on CGAL's armadillo scan; its errors; progress and cancellation.
import json
import threading

import numpy as np
import pytest

import cgal_ext
from conftest import normals_of, read_ply, run_program, write_ply, xyz

TOLERANCE = 1e-12


def assert_close(a, b, scale=1.0):
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) <= TOLERANCE * scale


@pytest.fixture
def sphere_file(sphere, tmp_path):
    points, normals = sphere
    path = tmp_path / "sphere.ply"
    write_ply(path, points, normals)
    return path


def test_details_are_the_programs(sphere, sphere_file, tmp_path):
    points, normals = sphere
    run_program("details", "-i", sphere_file, "-o", tmp_path / "out.ply", "--order", "cubic", "-k", 12)
    out = read_ply(tmp_path / "out.ply")
    details, magnitude = cgal_ext.compute_geometric_details(points, normals, k=12, order="cubic")
    assert_close(details, np.column_stack([out["detail_x"], out["detail_y"], out["detail_z"]]))
    assert_close(magnitude, np.asarray(out["detail_magnitude"]))
    # Any memory layout gives the same numbers: Fortran order, a strided view.
    f_details, _ = cgal_ext.compute_geometric_details(np.asfortranarray(points), np.asfortranarray(normals), k=12, order="cubic")
    assert np.array_equal(f_details, details)
    padded = np.zeros((len(points), 5))
    padded[:, 1:4] = points
    s_details, _ = cgal_ext.compute_geometric_details(padded[:, 1:4], normals, k=12, order="cubic")
    assert np.array_equal(s_details, details)


def test_details_report_each_points_kth_neighbour_distance(sphere):
    """neighbor_radius receives the distance to the k-th nearest (as SciPy finds it) and changes no result."""
    from scipy.spatial import cKDTree
    points, normals = sphere
    radius = np.full(len(points), -1.0)
    details, magnitude = cgal_ext.compute_geometric_details(points, normals, k=12, neighbor_radius=radius)
    expected = cKDTree(points).query(points, 13)[0][:, 12]
    assert np.abs(radius - expected).max() <= 1e-15 * np.abs(points).max()
    plain = cgal_ext.compute_geometric_details(points, normals, k=12)
    assert np.array_equal(details, plain.details) and np.array_equal(magnitude, plain.magnitude)
    frozen = np.zeros(len(points))
    frozen.flags.writeable = False
    with pytest.raises(ValueError, match="neighbor_radius is not writable"):
        cgal_ext.compute_geometric_details(points, normals, neighbor_radius=frozen)
    assert not frozen.any()


def test_details_of_a_cgal_scan_are_the_programs(armadillo):
    points, normals, vertex = armadillo
    details, magnitude = cgal_ext.compute_geometric_details(points, normals)
    scale = np.abs(points).max()
    assert_close(details, np.column_stack([vertex["detail_x"], vertex["detail_y"], vertex["detail_z"]]), scale)
    assert_close(magnitude, np.asarray(vertex["detail_magnitude"]), scale)


def test_curvature_is_the_programs(sphere, sphere_file, tmp_path):
    points, normals = sphere
    run_program("curvature", "-i", sphere_file, "-o", tmp_path / "h.ply", "--fitting", "closed-form")
    H = cgal_ext.estimate_mean_curvature(points, normals, fitting="closed_form")
    assert_close(H, np.asarray(read_ply(tmp_path / "h.ply")["mean_curvature"]))
    assert abs(np.median(H) - 1.0) < 0.05  # a unit sphere


def test_sample_points_are_the_programs(sphere, sphere_file, tmp_path):
    points, normals = sphere
    run_program("simplify", "-i", sphere_file, "-o", tmp_path / "s.ply", "--target", 800, "--clusters", tmp_path / "c.ply")
    labels = cgal_ext.compute_simplification_sample_points(points, normals, target_count=800)
    assert labels.dtype == np.int64
    assert np.array_equal(labels, read_ply(tmp_path / "c.ply")["ssp_index"].astype(np.int64))


def test_scaling_and_enhancement_are_the_programs(sphere, sphere_file, tmp_path):
    points, normals = sphere
    roi = np.flatnonzero(points[:, 2] > 0.5)
    (tmp_path / "roi.txt").write_text("\n".join(map(str, roi)) + "\n")
    run_program("scale", "-i", sphere_file, "-o", tmp_path / "scaled.ply", "-s", 2, "--roi", "indices:%s" % (tmp_path / "roi.txt"))
    scaled = cgal_ext.scale_geometric_details(points, normals, roi=roi, s=2.0)
    assert_close(scaled, xyz(read_ply(tmp_path / "scaled.ply")))
    outside = np.setdiff1d(np.arange(len(points)), roi)
    assert np.array_equal(scaled[outside], points[outside])
    run_program("enhance", "-i", sphere_file, "-o", tmp_path / "enhanced.ply", "-s", 2)
    assert_close(cgal_ext.enhance_geometric_details(points, normals, s=2.0), xyz(read_ply(tmp_path / "enhanced.ply")))
    # s = 1 leaves the points as they were.
    assert np.allclose(cgal_ext.scale_geometric_details(points, normals, roi=roi, s=1.0), points, atol=1e-12)


def test_upsampling_is_the_programs(sphere, tmp_path):
    points, normals = sphere
    keep = np.linalg.norm(points - points[0], axis=1) > 0.25  # a hole around the first point
    points, normals = points[keep], normals[keep]
    write_ply(tmp_path / "holed.ply", points, normals)
    run_program("upsample", "-i", tmp_path / "holed.ply", "-o", tmp_path / "up.ply")
    out = read_ply(tmp_path / "up.ply")
    new = out["inserted"] == 1
    added, added_normals = cgal_ext.upsample_point_set(points, normals)
    assert len(added) > 10
    assert_close(added, xyz(out)[new])
    assert_close(added_normals, normals_of(out)[new])


def test_scaled_normals_are_the_programs(sphere, sphere_file, tmp_path):
    # point-detail scale re-fits the normals where points moved: scale_geometric_details then refit_normals.
    points, normals = sphere
    roi = np.flatnonzero(points[:, 2] > 0.5)
    (tmp_path / "roi.txt").write_text("\n".join(map(str, roi)) + "\n")
    run_program("scale", "-i", sphere_file, "-o", tmp_path / "scaled.ply", "-s", 0, "--roi", "indices:%s" % (tmp_path / "roi.txt"))
    flat = cgal_ext.scale_geometric_details(points, normals, roi=roi, s=0.0)
    moved = np.flatnonzero((flat != points).any(axis=1))
    refitted = cgal_ext.refit_normals(flat, normals, moved)
    assert_close(refitted, normals_of(read_ply(tmp_path / "scaled.ply")))
    changed = (refitted != normals).any(axis=1)
    assert changed[moved].all() and not changed[points[:, 2] < 0.0].any()  # far from the region: kept
    assert np.array_equal(cgal_ext.refit_normals(flat, normals, []), normals)


def test_the_neighbor_graph_is_the_closed_ball_of_the_kth_nearest(tmp_path):
    # A lattice with duplicates: many ties at the k-th distance; each row is every point within it, whatever the order.
    g = np.arange(12, dtype=float)
    lattice = np.stack(np.meshgrid(g, g, [0.0, 1.0], indexing="ij"), -1).reshape(-1, 3)
    points = np.vstack([lattice, lattice[::17]])
    k = 10
    offsets, neighbors = cgal_ext.compute_neighbor_graph(points, k=k)
    assert offsets.dtype == np.int64 and offsets[0] == 0 and offsets[-1] == len(neighbors)
    d2 = ((points[:, None, :] - points[None, :, :]) ** 2).sum(-1)
    np.fill_diagonal(d2, np.inf)
    for i in range(len(points)):
        kth = np.sort(d2[i])[k - 1]
        row = neighbors[offsets[i]:offsets[i + 1]]
        assert set(row) == set(np.flatnonzero(d2[i] <= kth))
        assert np.all(np.diff(d2[i][row]) >= 0)  # nearest first
    order = np.random.default_rng(3).permutation(len(points))
    o2, n2 = cgal_ext.compute_neighbor_graph(points[order], k=k)
    for a, i in enumerate(order[:200]):
        assert set(order[n2[o2[a]:o2[a + 1]]]) == set(neighbors[offsets[i]:offsets[i + 1]])
    # Symmetric: the union with the transpose, each row sorted by index, without repeats or the point itself.
    so, sn = cgal_ext.compute_neighbor_graph(points, k=k, symmetric=True)
    union = [set() for _ in points]
    for i in range(len(points)):
        for j in neighbors[offsets[i]:offsets[i + 1]]:
            union[i].add(j)
            union[j].add(i)
    for i in range(len(points)):
        row = sn[so[i]:so[i + 1]]
        assert list(row) == sorted(union[i])
    with pytest.raises(ValueError, match="k = 0"):
        cgal_ext.compute_neighbor_graph(points, k=0)


def test_upsampling_after_an_edit_is_the_programs(sphere, sphere_file, tmp_path):
    # point-detail edit --upsample fills what the edit moved, at the spacing the points had before it.
    points, normals = sphere
    status = np.where(points[:, 2] > 0.8, 2, np.where(points[:, 2] > 0.0, 1, 0))
    (tmp_path / "e.sel").write_text("\n".join(map(str, status)) + "\n")
    (tmp_path / "e.def").write_text("1 0 0 0\n0 1 0 0\n0 0 1 0.6\n0 0 0 1\n")
    run_program("edit", "-i", sphere_file, "-o", tmp_path / "edited.ply", "--sel", tmp_path / "e.sel",
                "--def", tmp_path / "e.def", "--upsample")
    out = read_ply(tmp_path / "edited.ply")
    new = out["inserted"] == 1
    assert new.sum() > 10
    edited, edited_normals = xyz(out)[~new], normals_of(out)[~new]
    moved = np.flatnonzero(out["displacement"][~new] > 0)
    spacing = cgal_ext.compute_local_spacing(points)
    assert np.all(spacing > 0) and np.median(spacing) < 0.2
    added, added_normals = cgal_ext.upsample_point_set(edited, edited_normals, roi=moved, spacing_before=spacing)
    assert_close(added, xyz(out)[new])
    assert_close(added_normals, normals_of(out)[new])
    with pytest.raises(ValueError, match="spacing_before needs roi"):
        cgal_ext.upsample_point_set(edited, edited_normals, spacing_before=spacing)
    with pytest.raises(ValueError, match="spacing_before must have one value per point"):
        cgal_ext.upsample_point_set(edited, edited_normals, roi=moved, spacing_before=spacing[:-1])


def test_a_chain_of_steps_is_the_library_calls_one_after_another(sphere, sphere_file, tmp_path):
    # An edit, a detail scaling, a second edit and a fill of what it stretched, each on the result of the one before
    # (doc/editing.md, "Chains of steps"), as the studio runs them.
    points, normals = sphere
    write = lambda name, mask: (tmp_path / name).write_text("".join("%d\n" % i for i in np.flatnonzero(mask)))
    write("roi0.txt", points[:, 2] > 0.0)
    write("handle0.txt", points[:, 2] > 0.8)
    write("roi1.txt", points[:, 2] > 0.5)
    write("roi2.txt", points[:, 0] > -0.2)
    write("handle2.txt", points[:, 0] > 0.7)
    angle = np.radians(25)
    R = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    edit = lambda roi, handle, matrix, translation: {
        "type": "edit", "roi": ["indices:" + roi], "filter": {"order": "cubic"},
        "handles": [{"select": ["indices:" + handle], "matrix": matrix, "translation": translation}]}
    chain = {"steps": [edit("roi0.txt", "handle0.txt", np.eye(3).tolist(), [0, 0, 0.3]),
                       {"type": "scale", "s": 2.0, "roi": ["indices:roi1.txt"]},
                       edit("roi2.txt", "handle2.txt", R.tolist(), [0.2, 0, 0]),
                       {"type": "fill"}]}
    (tmp_path / "chain.json").write_text(json.dumps(chain))
    run_program("edit", "-i", sphere_file, "--edit", tmp_path / "chain.json", "-o", tmp_path / "chain.ply")
    out = read_ply(tmp_path / "chain.ply")

    def run_edit(p, n, roi, handle, R, t):
        d = cgal_ext.Deformation(p, n, order="cubic")
        d.insert_roi(roi)
        d.set_handle_transform(d.create_handle_group(handle), R, t)
        d.deform()
        d.diffuse()
        moved, moved_normals = d.restore_details()
        return moved, moved_normals, d.sample_point_of(np.ones(len(p), bool))
    p, n, _ = run_edit(points, normals, points[:, 2] > 0.0, points[:, 2] > 0.8, np.eye(3), [0, 0, 0.3])
    region = np.flatnonzero(points[:, 2] > 0.5)
    scaled = cgal_ext.scale_geometric_details(p, n, roi=region, s=2.0)
    n = cgal_ext.refit_normals(scaled, n, np.flatnonzero((scaled != p).any(axis=1)))
    spacing = cgal_ext.compute_local_spacing(scaled)
    roi2, handle2 = points[:, 0] > -0.2, points[:, 0] > 0.7
    p, n2, sample = run_edit(scaled, n, roi2, handle2, R, [0.2, 0, 0])
    added, added_normals = cgal_ext.upsample_point_set(p, n2, roi=np.flatnonzero((p != scaled).any(axis=1)),
                                                       spacing_before=spacing)
    assert len(added) > 0
    scale = np.abs(points).max()
    assert_close(xyz(out), np.vstack([p, added]), 10 * scale)
    assert_close(normals_of(out), np.vstack([n2, added_normals]), 10.0)
    assert np.array_equal(out["inserted"], np.r_[np.zeros(len(points)), np.ones(len(added))])
    assert_close(out["displacement"][:len(points)], np.linalg.norm(p - points, axis=1), 10 * scale)
    assert np.array_equal(out["status"][:len(points)], np.where(handle2, 2, np.where(roi2, 1, 0)))
    assert np.array_equal(out["ssp_index"][:len(points)], sample)

    # A one-edit file written as a chain of one step is the one-edit file.
    one = dict(chain["steps"][0])
    del one["type"]
    (tmp_path / "one.json").write_text(json.dumps(one))
    (tmp_path / "one_step.json").write_text(json.dumps({"steps": [chain["steps"][0]]}))
    for name in ("one", "one_step"):
        run_program("edit", "-i", sphere_file, "--edit", tmp_path / (name + ".json"), "-o", tmp_path / (name + ".ply"),
                    "--upsample")
    assert (tmp_path / "one.ply").read_bytes() == (tmp_path / "one_step.ply").read_bytes()


@pytest.mark.parametrize("options, settings", [
    ((), {}),
    (("--diffusion-turn", "frames", "--diffusion-origin", "nearest"), {"diffusion_turn": "frames", "diffusion_origin": "nearest"}),
    (("--rotations", "arap", "--rigid-weights", "cotangent"), {"rotations": "arap", "rigid_edge_weights": "cotangent"}),
    (("--rotations", "arap", "--rigid-weights", "cotangent", "--rigid-smoothing", "0.02", "--rigid-smoothing-scale", "surface_area"),
     {"rotations": "arap", "rigid_edge_weights": "cotangent", "rigid_rotation_smoothing": 0.02,
      "rigid_rotation_smoothing_scale": "surface_area"}),
])
def test_an_edit_is_the_programs(sphere, sphere_file, tmp_path, options, settings):
    points, normals = sphere
    status = np.where(points[:, 2] > 0.8, 2, np.where(points[:, 2] > 0.0, 1, 0))
    angle = np.radians(20)
    R = np.array([[1, 0, 0], [0, np.cos(angle), -np.sin(angle)], [0, np.sin(angle), np.cos(angle)]])
    t = np.array([0.0, 0.0, 0.1])
    (tmp_path / "e.sel").write_text("\n".join(map(str, status)) + "\n")
    (tmp_path / "e.def").write_text("\n".join(" ".join("%.17g" % v for v in row)
                                              for row in np.vstack([np.column_stack([R, t]), [0, 0, 0, 1]])) + "\n")
    run_program("edit", "-i", sphere_file, "-o", tmp_path / "edited.ply", "--sel", tmp_path / "e.sel", "--def", tmp_path / "e.def", *options)
    out = read_ply(tmp_path / "edited.ply")

    deformation = cgal_ext.Deformation(points, normals, **settings)
    deformation.insert_roi(np.flatnonzero(status > 0))
    group = deformation.create_handle_group(np.flatnonzero(status == 2))
    assert deformation.preprocess()
    deformation.set_handle_transform(group, R, t)
    deformation.deform()
    diffused, _ = deformation.diffuse()
    # The program restores the fine details once the edit is done, as an interactive caller would when a drag ends.
    moved, moved_normals = deformation.restore_details()
    assert deformation.statistics()["restore_seconds"] > 0
    assert deformation.statistics()["restore_iterations"] > 0
    assert deformation.statistics()["restore_residual"] <= 1e-2  # the default detail_tolerance
    assert np.max(np.linalg.norm(moved - diffused, axis=1)) > 0
    assert_close(moved, xyz(out), 2.0)
    assert_close(moved_normals, normals_of(out), 2.0)
    handles = status == 2
    assert np.max(np.abs(moved[handles] - (points[handles] @ R.T + t))) < 1e-9  # exact handles
    stats = deformation.statistics()
    assert stats["points"] == len(points) and stats["roi_samples"] > 0
    # Into the caller's arrays, reused from drag to drag.
    P, N = np.empty_like(points), np.empty_like(normals)
    returned = deformation.diffuse(P, N)
    assert returned[0] is P and returned[1] is N
    assert np.array_equal(P, diffused) and np.array_equal(N, moved_normals)
    # What the drag read and wrote for its points: at least each moved point's rest and new position and normal
    # and its stencil (the handles read and write no stencil), at most a packed record and the rows per point.
    moved_count = np.count_nonzero(np.any(P != points, axis=1))
    width = settings.get("diffusion_samples", 6)
    traffic = deformation.statistics()["diffuse_bytes"]
    assert moved_count * 96 <= traffic <= len(points) * (4 * 48 + 12 * width) + 128 * stats["samples"]
    with pytest.raises(ValueError, match="rows"):
        deformation.diffuse(P[:10], N)
    P.flags.writeable = False
    with pytest.raises(ValueError, match="not writable"):
        deformation.diffuse(P, N)


@pytest.mark.parametrize("call, error, needle", [
    (lambda p, n: cgal_ext.compute_geometric_details(p[:, :2].copy()), ValueError, "shape (n, 3)"),
    (lambda p, n: cgal_ext.compute_geometric_details(p.astype(np.complex128)), ValueError, "real numbers"),
    (lambda p, n: cgal_ext.compute_geometric_details([[0, 0, 0], [1, 2]]), ValueError, "points must be"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n.astype(str)), ValueError, "normals must hold real numbers"),
    (lambda p, n: cgal_ext.compute_geometric_details(np.where(np.arange(len(p))[:, None] == 5, np.nan, p)), ValueError, "non-finite"),
    (lambda p, n: cgal_ext.compute_geometric_details(np.zeros((0, 3))), ValueError, "empty"),
    (lambda p, n: cgal_ext.compute_geometric_details(p[:8].copy(), n[:8].copy()), ValueError, "k = 10"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n[:10].copy()), ValueError, "as many rows"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, order="quintic"), ValueError, "order"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, lam=0.0), ValueError, "lambda"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, neighbor_radius=np.empty(len(p) - 1)), ValueError,
     "neighbor_radius must have shape"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, neighbor_radius=np.empty(len(p), np.float32)),
     ValueError, "neighbor_radius must have dtype float64"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, neighbor_radius=np.empty(2 * len(p))[::2]), ValueError,
     "neighbor_radius must be contiguous"),
    (lambda p, n: cgal_ext.compute_geometric_details(p, n, neighbor_radius=[0.0] * len(p)), ValueError,
     "neighbor_radius must be a numpy array"),
    (lambda p, n: cgal_ext.scale_geometric_details(p, n, roi=[len(p)], s=2.0), ValueError, "not a point index"),
    (lambda p, n: cgal_ext.scale_geometric_details(p, n, roi=np.array([0.5]), s=2.0), ValueError, "integer point indices"),
    (lambda p, n: cgal_ext.scale_geometric_details(p, n, roi=np.ones(10, bool), s=2.0), ValueError, "one value per point"),
    (lambda p, n: cgal_ext.estimate_mean_curvature(p, n, k=3), ValueError, "at least 5"),
    (lambda p, n: cgal_ext.upsample_point_set(p, None), ValueError, "normals are required"),
    (lambda p, n: cgal_ext.Deformation(p, n, rotation="arap"), TypeError,
     "takes no keyword argument 'rotation' (did you mean 'rotations'?)"),
    (lambda p, n: cgal_ext.Deformation(p, n, diffusion_turn="twisted"), ValueError, "diffusion_turn must be"),
    (lambda p, n: cgal_ext.label_colors([0, 3, -1]), ValueError, "labels must be integers >= 0; label #2"),
    (lambda p, n: cgal_ext.label_colors([0.5]), ValueError, "label #0 is 0.5"),
    (lambda p, n: cgal_ext.label_colors(np.zeros((2, 2))), ValueError, "labels must"),
    (lambda p, n: cgal_ext.Deformation(p, n, diffusion_origin="far"), ValueError, "diffusion_origin must be"),
    (lambda p, n: cgal_ext.Deformation(p, n, rigid_edge_weights="cot"), ValueError, "rigid_edge_weights must be"),
    (lambda p, n: cgal_ext.Deformation(p, n, rigid_rotation_smoothing_scale="area"), ValueError,
     "rigid_rotation_smoothing_scale must be"),
])
def test_bad_input_is_a_value_error_naming_it(sphere, call, error, needle):
    points, normals = sphere
    with pytest.raises(error) as raised:
        call(points, normals)
    assert needle in str(raised.value)


def test_a_handle_outside_the_region_is_a_value_error(sphere):
    points, normals = sphere
    deformation = cgal_ext.Deformation(points, normals)
    deformation.insert_roi(np.flatnonzero(points[:, 2] > 0.5))
    deformation.create_handle_group(np.flatnonzero(points[:, 2] < -0.9))
    with pytest.raises(ValueError, match="not in the region of interest"):
        deformation.preprocess()
    with pytest.raises(ValueError, match="not a rotation"):
        deformation.set_handle_transform(0, 2 * np.eye(3), np.zeros(3))


def test_points_a_deformation_was_not_built_on_move_by_its_diffusion_state(sphere):
    """diffuse_points() with diffusion_state(), as a tiled edit's worker uses them: the deformation's own points,
    shuffled, with their selection, land where diffuse() puts them, bit for bit, exact handles and collar included,
    and with restore_details where restore_details() puts them; the state survives pickling (Dask sends it so); a
    bad state or selection is a ValueError."""
    import pickle
    points, normals = sphere
    region, handle = points[:, 2] > 0.0, points[:, 2] > 0.8
    deformation = cgal_ext.Deformation(points, normals, rotations="arap")
    deformation.insert_roi(np.flatnonzero(region))
    deformation.create_handle_group(np.flatnonzero(handle))
    turn = np.array([[np.cos(0.5), 0, np.sin(0.5)], [0, 1, 0], [-np.sin(0.5), 0, np.cos(0.5)]])
    deformation.set_handle_transform(0, turn, np.array([0.1, 0.0, 0.2]))
    deformation.deform()
    diffused = deformation.diffuse()
    state = pickle.loads(pickle.dumps(deformation.diffusion_state()))
    assert state["motions"].shape == (deformation.number_of_sample_points(), 3, 4)
    assert state["handle_transforms"].shape == (1, 7) and state["exact_handles"] and state["collar_reach"] > 0
    selection = np.where(handle, 0, np.where(region, -1, -2))
    order = np.random.default_rng(5).permutation(len(points))
    moved = cgal_ext.diffuse_points(points[order], normals[order], state, selection=selection[order])
    assert np.array_equal(moved.points, diffused.points[order])
    assert np.array_equal(moved.normals, diffused.normals[order])
    collar = deformation.renderer_setup()["collar_points"]
    assert len(collar) > 0 and np.count_nonzero(np.any(moved.points != points[order], axis=1)) > len(points) // 4
    radius = np.empty(len(points))
    restored = cgal_ext.diffuse_points(points[order], normals[order], state, selection=selection[order],
                                       restore_details=True, neighbor_radius=radius)
    from scipy.spatial import cKDTree
    assert np.abs(radius - cKDTree(points[order]).query(points[order], 11)[0][:, 10]).max() <= 1e-12
    expected = deformation.restore_details()
    assert np.array_equal(restored.points, expected.points[order])
    assert np.array_equal(restored.normals, expected.normals[order])
    assert np.abs(expected.points - diffused.points).max() > 1e-6  # the restoration moved points
    # Without the selection, the handles and the collar follow the blend alone.
    blended = cgal_ext.diffuse_points(points, normals, state).points
    assert not np.array_equal(blended[handle], diffused.points[handle])
    with pytest.raises(ValueError, match="has no 'motions'"):
        cgal_ext.diffuse_points(points, normals, {k: v for k, v in state.items() if k != "motions"})
    with pytest.raises(ValueError, match="'motions' must be a float array of shape"):
        cgal_ext.diffuse_points(points, normals, {**state, "motions": state["motions"][:, :2]})
    with pytest.raises(ValueError, match="stencil_size"):
        cgal_ext.diffuse_points(points, normals, {**state, "stencil_size": 0})
    with pytest.raises(ValueError, match="selection of point 3 is 1"):
        cgal_ext.diffuse_points(points, normals, state, selection=np.where(np.arange(len(points)) == 3, 1, -1))
    with pytest.raises(ValueError, match="detail_anchor must be"):
        cgal_ext.diffuse_points(points, normals, {**state, "detail_anchor": 0.0}, restore_details=True)
    with pytest.raises(ValueError, match="unit quaternion"):
        cgal_ext.diffuse_points(points, normals, {**state, "handle_transforms": 2 * state["handle_transforms"]})


def test_progress_is_reported_and_an_exception_from_it_cancels(sphere):
    points, normals = sphere
    fractions = []
    cgal_ext.compute_geometric_details(points, normals, progress=fractions.append)
    assert fractions and all(0.0 <= f <= 1.0 for f in fractions) and fractions == sorted(fractions)

    class Stop(Exception):
        pass

    def stop(fraction):
        raise Stop()

    with pytest.raises(Stop):
        cgal_ext.compute_geometric_details(points, normals, progress=stop)
    deformation = cgal_ext.Deformation(points, normals)
    deformation.insert_roi(np.flatnonzero(points[:, 2] > 0.0))
    deformation.create_handle_group(np.flatnonzero(points[:, 2] > 0.8))
    with pytest.raises(Stop):
        deformation.preprocess(progress=stop)
    assert deformation.preprocess()  # cancelled, then done


def test_peak_memory_of_a_large_input_is_the_cpp_examples(tmp_path):
    """Peak memory of details on 1M points from Python within 10 % of the C++ example's on the same points (that
    the points are read in place is test_package.py's test_float64_input_is_read_in_place...)."""
    import os
    import subprocess
    import sys
    from conftest import bumpy_sphere
    examples = os.environ.get("CGAL_EXT_EXAMPLES")
    if not examples or not os.path.exists("/usr/bin/time"):
        pytest.skip("needs the C++ examples (CGAL_EXT_EXAMPLES) and /usr/bin/time")
    points, normals = bumpy_sphere(1000000, seed=3)
    write_ply(tmp_path / "big.ply", points, normals)
    del points, normals

    def peak_kib(command):
        result = subprocess.run(["/usr/bin/time", "-f", "%M"] + command, capture_output=True, text=True,
                                env=dict(os.environ, OMP_NUM_THREADS="1"))
        assert result.returncode == 0, result.stderr
        return int(result.stderr.strip().splitlines()[-1])

    cpp = peak_kib([examples, "compute_geometric_details_example", str(tmp_path / "big.ply")])
    script = ("import sys; sys.path[:0] = %r; import numpy as np, cgal_ext; from conftest import read_ply\n"
              "v = read_ply(%r); p = np.column_stack([v['x'], v['y'], v['z']]); n = np.column_stack([v['nx'], v['ny'], v['nz']])\n"
              "del v; cgal_ext.compute_geometric_details(p, n)\n") % (sys.path[:1] + [os.path.dirname(__file__)], str(tmp_path / "big.ply"))
    python = peak_kib([sys.executable, "-c", script])
    print("peak memory, details of 1M points: C++ example %d MiB, Python %d MiB" % (cpp // 1024, python // 1024))
    assert python <= 1.10 * cpp


@pytest.mark.parametrize("example", ["details_colours.py", "edit.py", "workflow.py"])
def test_the_python_examples_run(example, tmp_path):
    import os
    import subprocess
    import sys
    from conftest import DATA
    if example == "workflow.py" and not os.path.exists(os.path.join(DATA, "meshes", "bunny00.off")):
        pytest.skip("workflow.py needs CGAL's bunny00 scan (scripts/fetch_data.sh)")
    script = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python", example)
    result = subprocess.run([sys.executable, script, str(tmp_path / "out.ply")], capture_output=True, text=True,
                            env=dict(os.environ, CGAL_EXT_DATA=DATA))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out.ply").read_bytes().startswith(b"ply\n")
    if example == "workflow.py":  # the details beside it, and its three pictures
        assert (tmp_path / "details.ply").read_bytes().startswith(b"ply\n")
        for picture in ("details.png", "selection.png", "edit.png"):
            assert (tmp_path / picture).read_bytes().startswith(b"\x89PNG\r\n\x1a\n")


def test_ctrl_c_cancels_a_computation(sphere):
    """A KeyboardInterrupt arriving during a call (here from a timer, as Ctrl-C would) ends it at the next progress
    report and is raised, with no progress callable given."""
    import _thread
    points, _ = sphere
    many = np.vstack([points * (1 + 0.1 * i) for i in range(60)])  # 360k points without normals: seconds
    timer = threading.Timer(0.1, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            cgal_ext.compute_geometric_details(many)
    finally:
        timer.cancel()
