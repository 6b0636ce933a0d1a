"""The same points in another order give the same answer, point by point once the order is undone (doc/design.md,
"One neighbourhood rule"): every public function of the package, on a lattice whose distances tie exactly, on the
lattice with 2 % of its points duplicated, and on a random sampling of the same surface."""
import numpy as np
import pytest

import cgal_ext


def surface(x, y):
    """Points on z(x, y), flat for x < 0.55 and smoothly bumped beyond, and their exact normals."""
    kx, ky = 2 * np.pi / 0.4, 2 * np.pi / 0.3
    s = np.maximum(x - 0.55, 0.0)
    z = s * s * np.sin(ky * y) * (1 - np.cos(kx * s))
    zx = np.sin(ky * y) * (2 * s * (1 - np.cos(kx * s)) + s * s * kx * np.sin(kx * s))
    zy = s * s * ky * np.cos(ky * y) * (1 - np.cos(kx * s))
    normals = np.column_stack([-zx, -zy, np.ones_like(x)])
    return np.column_stack([x, y, z]), normals / np.linalg.norm(normals, axis=1)[:, None]


def shape(kind):
    if kind == "random":
        rng = np.random.default_rng(3)
        return surface(rng.uniform(0, 69 / 64, 4200), rng.uniform(0, 59 / 64, 4200))
    j, i = np.mgrid[0:60, 0:70]
    points, normals = surface(i.ravel() / 64.0, j.ravel() / 64.0)  # spacing 1/64: distances tie exactly
    if kind == "duplicates":
        points, normals = np.vstack([points, points[::50]]), np.vstack([normals, normals[::50]])
    return points, normals


@pytest.fixture(scope="module", params=["lattice", "duplicates", "random"])
def shapes(request):
    points, normals = shape(request.param)
    order = np.random.default_rng(11).permutation(len(points))
    return points, normals, order


def same(a, b, order):
    """`a` computed on the points in their order, `b` on `order`: equal to 1e-12 of the largest value."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = max(np.abs(a).max(), 1e-300)
    assert np.abs(a[order] - b).max() <= 1e-12 * scale


def same_rows_as_sets(a, b):
    a, b = a[np.lexsort(a.T[::-1])], b[np.lexsort(b.T[::-1])]
    assert a.shape == b.shape
    assert np.abs(a - b).max() <= 1e-12 * max(np.abs(a).max(), 1e-300)


def partition(labels):
    """Each point's cluster named by its cluster's first point: equal for the same partition, whatever the labels."""
    first = {}
    return np.array([first.setdefault(label, i) for i, label in enumerate(labels)])


@pytest.mark.parametrize("order_name", ["linear", "quadric", "cubic"])
def test_details(shapes, order_name):
    points, normals, order = shapes
    a = cgal_ext.compute_geometric_details(points, normals, order=order_name)
    b = cgal_ext.compute_geometric_details(points[order], normals[order], order=order_name)
    same(a.details, b.details, order)
    same(a.magnitude, b.magnitude, order)


def test_details_with_estimated_normals_and_distance_weights(shapes):
    points, _, order = shapes
    a = cgal_ext.compute_geometric_details(points, order="cubic", weights="distance")
    b = cgal_ext.compute_geometric_details(points[order], order="cubic", weights="distance")
    same(a.details, b.details, order)


def test_normals_and_curvature(shapes):
    points, normals, order = shapes
    same(cgal_ext.estimate_oriented_normals(points), cgal_ext.estimate_oriented_normals(points[order]), order)
    for fitting in ["closed_form", "monge"]:
        same(cgal_ext.estimate_mean_curvature(points, normals, fitting=fitting),
             cgal_ext.estimate_mean_curvature(points[order], normals[order], fitting=fitting), order)


def test_scale_and_enhance(shapes):
    points, normals, order = shapes
    roi = np.linalg.norm(points - [0.7, 0.45, 0], axis=1) < 0.3
    same(cgal_ext.scale_geometric_details(points, normals, roi=roi, s=2.0),
         cgal_ext.scale_geometric_details(points[order], normals[order], roi=roi[order], s=2.0), order)
    same(cgal_ext.enhance_geometric_details(points, normals, s=1.5),
         cgal_ext.enhance_geometric_details(points[order], normals[order], s=1.5), order)


def test_sample_points(shapes):
    points, normals, order = shapes
    a = cgal_ext.compute_simplification_sample_points(points, normals)
    b = cgal_ext.compute_simplification_sample_points(points[order], normals[order])
    inverse = np.argsort(order)
    assert np.array_equal(partition(a), partition(b[inverse]))


def test_upsampling(shapes):
    points, normals, order = shapes
    keep = np.linalg.norm(points[:, :2] - [0.5, 0.45], axis=1) > 0.1  # a hole to fill
    points, normals = points[keep], normals[keep]
    order = np.random.default_rng(5).permutation(len(points))
    a = cgal_ext.upsample_point_set(points, normals)
    b = cgal_ext.upsample_point_set(points[order], normals[order])
    assert len(a.points) > 0
    same_rows_as_sets(np.hstack([a.points, a.normals]), np.hstack([b.points, b.normals]))


@pytest.mark.parametrize("rotations", ["propagate", "arap"])
def test_edit(shapes, rotations):
    points, normals, order = shapes
    inverse = np.argsort(order)
    roi = np.linalg.norm(points - [0.75, 0.45, 0], axis=1) < 0.3
    handle = np.linalg.norm(points - [0.9, 0.45, 0], axis=1) < 0.08
    results = []
    for p, n, r, h in [(points, normals, roi, handle), (points[order], normals[order], roi[order], handle[order])]:
        edit = cgal_ext.Deformation(p, n, rotations=rotations)
        edit.insert_roi(r)
        group = edit.create_handle_group(h)
        edit.set_handle_transform(group, np.eye(3), [0.02, 0.01, 0.08])
        edit.deform()
        diffused = edit.diffuse()
        selection = np.where(h, 0, np.where(r, -1, -2))
        # The restoration, by the deformation and by diffuse_points over the same points (closed balls, sums
        # in the order of the positions).
        restored = edit.restore_details()
        moved = cgal_ext.diffuse_points(p, n, edit.diffusion_state(), selection=selection, restore_details=True)
        results.append((diffused, edit.sample_point_of(np.arange(len(p))), restored, moved))
    (a, a_samples, a_restored, a_moved), (b, b_samples, b_restored, b_moved) = results
    same(a.points, b.points, order)
    same(a.normals, b.normals, order)
    assert np.array_equal(partition(a_samples), partition(b_samples[inverse]))
    assert np.abs(a_restored.points - a.points).max() > 1e-6
    same(a_restored.points, b_restored.points, order)
    same(a_moved.points, b_moved.points, order)
