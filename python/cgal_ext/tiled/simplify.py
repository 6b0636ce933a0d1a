"""Simplification sample points (SSPs) of a scan of any size on Dask: the library's sample points of a subsample
that one machine holds, every point of the scan given the cluster of its nearest subsample point, and each
surfel (centroid, normal, radius, member count) summed over all its points.

Three passes over the scan's rows, none with a halo: a point's cluster depends only on its own coordinates and
normal. The subsample is chosen by a hash of the coordinates and sorted, and the surfels are sums of integers,
so the result is the same bit for bit whatever the order of the points and however the rows are split.
See doc/scaling.md, "Sample points".
"""
import os
import uuid
from typing import Any, Dict

import numpy as np
from scipy.spatial import cKDTree

from .. import _core
from . import ops
from .runner import first_invalid_row, read_rows
from .store import TiledError, checked_output

SUBSAMPLE = 1_000_000  # points the client clusters; a scan this small is clustered whole, as the program does
CANDIDATES = 8  # nearest subsample points a point chooses its cluster among
AGREEMENT = 0.5  # the least cosine between a point's normal and its subsample point's
UPPER = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))  # the entries of a symmetric 3x3 matrix kept

XYZ_NORMALS = [("x", "f8"), ("y", "f8"), ("z", "f8"), ("nx", "f8"), ("ny", "f8"), ("nz", "f8")]
FIELDS = XYZ_NORMALS + [("radius", "f8"), ("member_count", "f8")]
CLUSTER_FIELDS = XYZ_NORMALS + [("ssp_index", "f8"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]


def _mix(x):
    """splitmix64's finaliser: a bijection of uint64 whose output bits each depend on every input bit."""
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def coordinate_hash(points):
    """A uint64 per point that depends only on its coordinates' values (-0.0 as 0.0)."""
    bits = np.ascontiguousarray(points + 0.0).view(np.uint64)
    h = np.full(len(points), 0x9E3779B97F4A7C15, dtype=np.uint64)
    with np.errstate(over="ignore"):
        for axis in range(3):
            h = _mix(h ^ bits[:, axis])
    return h


def unit_normals(normals):
    """The normals scaled to unit length, and whether each was finite and not zero."""
    length = np.linalg.norm(normals, axis=1)
    valid = np.isfinite(length) & (length > 0)
    return normals / np.where(valid, length, 1.0)[:, None], valid


def select_rows(begin, end, source, cutoff, row_sets=()):
    """The points, unit normals and rows of rows [begin, end) whose coordinate hash is at most `cutoff` (all when
    None), with the bounding box and the first row of the range with a non-finite coordinate or an invalid normal;
    for each of `row_sets` (.npy files of sorted rows of the scan), the bounding box of its points in the range
    (None where it has none)."""
    points, normals = read_rows(source, begin, end)
    normals, valid = unit_normals(normals)
    keep = np.ones(len(points), dtype=bool) if cutoff is None else coordinate_hash(points) <= np.uint64(cutoff)
    selected = {"points": points[keep], "normals": normals[keep], "lo": points.min(axis=0), "hi": points.max(axis=0),
                "bad_row": first_invalid_row(np.isfinite(points).all(axis=1), begin),
                "bad_normal": first_invalid_row(valid, begin), "rows": begin + np.flatnonzero(keep), "row_boxes": []}
    for path in row_sets:
        rows = np.load(path, mmap_mode="r")
        inside = points[np.asarray(rows[np.searchsorted(rows, begin):np.searchsorted(rows, end)]) - begin]
        selected["row_boxes"].append((inside.min(axis=0), inside.max(axis=0)) if len(inside) else None)
    return selected


_kept: Dict[str, Any] = {}  # per worker process: what the run's tasks share (a tree of its subsample or sample)


def kept_per_process(key, make):
    """make(), once per process for `key`; one run at a time keeps what it made."""
    if key not in _kept:
        _kept.clear()
        _kept[key] = make()
    return _kept[key]


def _subsample(key, subsample):
    return kept_per_process(key, lambda: (cKDTree(subsample["points"]), subsample))


def _spread_bits(q):
    """The bits of 10-bit integers spread three apart, for Morton codes."""
    q = (q | (q << np.uint64(16))) & np.uint64(0x030000FF)
    q = (q | (q << np.uint64(8))) & np.uint64(0x0300F00F)
    q = (q | (q << np.uint64(4))) & np.uint64(0x030C30C3)
    return (q | (q << np.uint64(2))) & np.uint64(0x09249249)


def spatial_order(points):
    """The points ordered along a Morton curve of 2^30 cells: neighbouring queries visit the same branches of the
    tree, so a chunk's search stays in the cache."""
    lo = points.min(axis=0)
    extent = max(float((points.max(axis=0) - lo).max()), 1e-300)
    cells = np.minimum((points - lo) * (1023.0 / extent), 1023.0).astype(np.uint64)
    return np.argsort(_spread_bits(cells[:, 0]) | (_spread_bits(cells[:, 1]) << np.uint64(1))
                      | (_spread_bits(cells[:, 2]) << np.uint64(2)), kind="stable")


def nearest_in(tree, points):
    """The distance to each point's nearest point of `tree` and that point's index, queried along a Morton curve."""
    order = spatial_order(points)
    distance, index = np.empty(len(points)), np.empty(len(points), dtype=np.int64)
    distance[order], index[order] = tree.query(points[order], 1)
    return distance, index


def assign(points, normals, tree, subsample):
    """Each point's cluster: that of its nearest subsample point if their unit normals agree (cosine >
    AGREEMENT), else of the nearest of its CANDIDATES nearest that agrees, else of the nearest."""
    nearest = nearest_in(tree, points)[1]
    disagree = np.flatnonzero(np.einsum("ij,ij->i", subsample["normals"][nearest], normals) <= AGREEMENT)
    count = min(CANDIDATES, len(subsample["labels"]))
    if len(disagree) and count > 1:
        candidates = tree.query(points[disagree], count)[1]
        agreement = np.einsum("ijk,ik->ij", subsample["normals"][candidates], normals[disagree]) > AGREEMENT
        chosen = np.where(agreement.any(axis=1), np.argmax(agreement, axis=1), 0)
        nearest[disagree] = candidates[np.arange(len(disagree)), chosen]
    return subsample["labels"][nearest]


def _labels_path(scratch, begin):
    return scratch / f"labels_{begin}.npy"


def sum_rows(begin, end, source, key, subsample, quantum, normal_quantum, scratch):
    """Per cluster, over rows [begin, end): the member count, the sum of the offsets from the subsample's centroid
    and of the unit normals (integers: exact in any order), and the largest offset. Saves the rows' clusters in
    `scratch` for the next pass."""
    points, normals = read_rows(source, begin, end)
    unit = unit_normals(normals)[0]  # the first pass refused the scan if any was invalid
    tree, subsample = _subsample(key, subsample)
    labels = assign(points, unit, tree, subsample)
    clusters = len(subsample["centroids"])
    offsets = points - subsample["centroids"][labels]
    offset_sum = np.zeros((clusters, 3), dtype=np.int64)
    normal_sum = np.zeros((clusters, 3), dtype=np.int64)
    np.add.at(offset_sum, labels, np.rint(offsets / quantum).astype(np.int64))
    np.add.at(normal_sum, labels, np.rint(unit / normal_quantum).astype(np.int64))
    largest = np.zeros(clusters)
    np.maximum.at(largest, labels, np.linalg.norm(offsets, axis=1))
    partial = scratch / f".labels_{begin}.{uuid.uuid4().hex[:8]}.npy"
    np.save(partial, labels.astype(np.int32))
    os.replace(partial, _labels_path(scratch, begin))  # a rerun of the task replaces it whole
    return np.bincount(labels, minlength=clusters), offset_sum, normal_sum, largest


def spread_rows(begin, end, source, scratch, centroids, units):
    """Per cluster, over rows [begin, end) and their clusters the previous pass saved: the sum of the offsets'
    outer products from the centroid (integers in the cluster's `units`) and the largest distance to it."""
    points = read_rows(source, begin, end, coordinates_only=True)
    labels = np.load(_labels_path(scratch, begin))
    offsets = points - centroids[labels]
    scaled = np.rint(offsets / units[labels, None]).astype(np.int64)
    products = np.empty((len(points), 6), dtype=np.int64)
    for column, (a, b) in enumerate(UPPER):
        products[:, column] = scaled[:, a] * scaled[:, b]
    spread = np.zeros((len(centroids), 6), dtype=np.int64)
    np.add.at(spread, labels, products)
    radius = np.zeros(len(centroids))
    np.maximum.at(radius, labels, np.linalg.norm(offsets, axis=1))
    return spread, radius


def write_cluster_rows(begin, end, source, scratch, renumbered, sink):
    """Rows [begin, end) of the scan with their sample point's number and colour, as point-detail simplify
    --clusters writes them."""
    points, normals = read_rows(source, begin, end)
    labels = renumbered[np.load(_labels_path(scratch, begin))]
    colors = _core.label_colors(labels)
    columns = {"ssp_index": labels.astype(np.float64)}
    for axis in range(3):
        columns["xyz"[axis]] = points[:, axis]
        columns[("nx", "ny", "nz")[axis]] = normals[:, axis]
        columns[("red", "green", "blue")[axis]] = colors[:, axis]
    sink.write(begin, columns)


def surfel_normals(spread, normal_sum, count, fallback):
    """As the library's surfels: the covariance's least axis oriented like the members' normals, or the mean
    normal for clusters of fewer than three points; `fallback` (a member's normal) where that mean is zero."""
    covariance = np.empty((len(spread), 3, 3))
    for column, (a, b) in enumerate(UPPER):
        covariance[:, a, b] = covariance[:, b, a] = spread[:, column]
    axis = np.linalg.eigh(covariance)[1][:, :, 0]
    mean = normal_sum.astype(np.float64)
    axis *= np.where(np.einsum("ij,ij->i", axis, mean) < 0, -1.0, 1.0)[:, None]
    normals = np.where((count >= 3)[:, None], axis, mean)
    normals, valid = unit_normals(normals)
    return np.where(valid[:, None], normals, fallback)


def _whole(value):
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def subsample_pass(runner, source, size, why_normals, row_sets=()):
    """The pass that chooses about `size` points of `source` by their coordinate hash (select_rows, which measures
    `row_sets` too); refuses an empty scan, a scan without normals (`why_normals`: what they are needed for) and
    invalid rows."""
    n = source.count
    if n == 0:
        raise TiledError(f"{source.path}: the scan has no points")
    if not source.has_normals:
        raise TiledError(f"{source.path}: has no normals; {why_normals} (run `python3 -m cgal_ext.tiled normals` "
                         f"first: its output has them, oriented across the tiles)")
    cutoff = None if size >= n else int(size / n * 2.0**64)
    selected = runner.map(select_rows, runner.row_ranges(n), source, cutoff, row_sets, what="subsample")
    runner.refuse_invalid_rows(source, selected)
    return selected


def sorted_subsample(selected, who, size, n):
    """The points and unit normals of the passes' `selected` (select_rows), sorted: -0.0 as 0.0, as the hash sees
    them, so that the subsample's order, and what the client computes from it, does not depend on the scan's; and
    their rows in the scan."""
    points = np.concatenate([s["points"] for s in selected]) + 0.0
    normals = np.concatenate([s["normals"] for s in selected]) + 0.0
    if not len(points):
        raise TiledError(f"{who}: the subsample of {size} of the {n} points holds none; give a larger subsample")
    order = np.lexsort((*normals.T[::-1], *points.T[::-1]))
    return points[order], normals[order], np.concatenate([s["rows"] for s in selected])[order]


def options(source, output, subsample=SUBSAMPLE, clusters=None, **library):
    """The options of a run on `source` writing `output`, checked before any pass: `subsample`, `clusters` (a path
    for the scan with its clusters, or None) and the keywords of compute_simplification_sample_points but
    max_cluster_size (a size in points of the scan, which a subsample does not have)."""
    allowed = set(ops.keywords(_core.compute_simplification_sample_points)) - {"max_cluster_size"}
    unknown = set(library) - allowed
    if unknown:
        raise TiledError(f"simplify: unknown option(s) {', '.join(sorted(unknown))} (it takes subsample, clusters, "
                         f"{', '.join(sorted(allowed))})")
    if not _whole(subsample) or subsample < 1:
        raise TiledError(f"simplify: subsample must be a whole number of points >= 1, not {subsample!r}")
    for name in ("target_count", "k"):
        if name in library and not _whole(library[name]):
            raise TiledError(f"simplify: {name} must be a whole number, not {library[name]!r}")
    threshold = library.get("mode_threshold", 1.0)
    if isinstance(threshold, (bool, np.bool_)) or not isinstance(threshold, (int, float, np.integer, np.floating)):
        raise TiledError(f"simplify: mode_threshold must be a number, not {threshold!r}")
    if clusters is not None:
        clusters = checked_output(clusters, source)
        if clusters.resolve() == output.resolve():
            raise TiledError(f"{output}: is both the output and the clusters' file")
    return {"subsample_size": int(subsample), "clusters_path": clusters, "library": library}


def simplify(runner, source, output, scratch, subsample_size, clusters_path, library):
    """The tiled sample points of `source` written to `output` (a PLY or Zarr of surfels), and with
    `clusters_path`, the scan with each point's sample point there; `runner` maps the passes over the rows
    (runner.Passes), which keep each point's cluster in the folder `scratch` between them; `library` are
    compute_simplification_sample_points's options. Returns the run's report."""
    n = source.count
    # Normals estimated on the subsample alone: a few would be flipped and make clusters of their own.
    selected = subsample_pass(runner, source, subsample_size, "simplify clusters by them")
    ranges = runner.row_ranges(n)
    report = runner.report
    with runner.client_step("cluster subsample"):
        points, normals, _ = sorted_subsample(selected, "simplify", subsample_size, n)
        diagonal = float(np.linalg.norm(np.max([s["hi"] for s in selected], axis=0)
                                        - np.min([s["lo"] for s in selected], axis=0)))
        try:
            labels = _core.compute_simplification_sample_points(points, normals, **library)
        except (ValueError, TypeError) as error:
            raise TiledError(f"simplify: {str(error).splitlines()[0]}") from None
        clusters = int(labels.max()) + 1
        members = np.bincount(labels, minlength=clusters)
        centroids = np.zeros((clusters, 3))
        np.add.at(centroids, labels, points)
        centroids /= members[:, None]
        first_normal = normals[np.unique(labels, return_index=True)[1]]
    report.update(points=n, subsample=len(points), diagonal=diagonal)
    runner.log(f"{n} points, subsample of {len(points)}: {clusters} sample points")
    subsample = runner.client.scatter([{"points": points, "normals": normals, "labels": labels,
                                        "centroids": centroids}], broadcast=True)[0]
    key = uuid.uuid4().hex
    # Offsets in units of the diagonal over 2^bits and unit normals in units of 2^-bits, each at most 2^bits: n of
    # them sum to at most 2^62 (and each is an integer that float64 holds exactly).
    bits = min(50, 62 - int(np.ceil(np.log2(max(n, 2)))))
    quantum, normal_quantum = max(diagonal, 1e-300) * 2.0**-bits, 2.0**-min(30, bits)
    sums = runner.map(sum_rows, ranges, source, key, subsample, quantum, normal_quantum, scratch, what="clusters")
    count = np.sum([s[0] for s in sums], axis=0)
    normal_sum = np.sum([s[2] for s in sums], axis=0)
    largest = np.max([s[3] for s in sums], axis=0)
    # A subsample point with a duplicate (other normal, other cluster) may see its points all join the duplicate's.
    kept = count > 0
    count = np.maximum(count, 1)
    centroids = centroids + np.sum([s[1] for s in sums], axis=0) * quantum / count[:, None]
    # The members' squared distances to the centroid sum to at most count (2 largest)^2 (their mean is within
    # largest of the subsample's centroid, and the centroid rounds towards their mean): in these units at most
    # 2^62, and so is each product's sum.
    bits = np.floor((62 - np.log2(count)) / 2)
    units = np.maximum(2.0 * largest, 1e-300) * 2.0**-bits
    spreads = runner.map(spread_rows, ranges, source, scratch, centroids, units, what="surfels")
    spread = np.sum([s[0] for s in spreads], axis=0)
    radius = np.max([s[1] for s in spreads], axis=0)
    normals = surfel_normals(spread, normal_sum, count, first_normal)
    surfels = np.column_stack([centroids, normals, radius, count])[kept]
    surfel_columns = {name: surfels[:, column] for column, (name, _) in enumerate(FIELDS)}
    # The sample points' numbers without the empty ones: the order the library made them in.
    renumbered = np.cumsum(kept) - 1
    written = []  # both outputs are written under temporary names, then renamed together
    try:
        if clusters_path is not None:
            written.append(runner.open_sink(clusters_path, n, CLUSTER_FIELDS))
            with runner.client_step("create clusters"):
                written[-1].create()
            runner.map(write_cluster_rows, ranges, source, scratch, renumbered, written[-1], what="write clusters")
        written.append(runner.written_small(output, FIELDS, surfel_columns))
    except BaseException:
        for sink in written:
            sink.discard()
        raise
    for sink in written:
        sink.commit()
    report.update(sample_points=len(surfels), largest_cluster=int(count.max()),
                  points_per_sample_point=n / len(surfels))
    return report
