"""What a tiled edit stretched, filled in tiles (`edit --upsample`), as `point-detail edit --upsample` fills it: the
library's up-sampling from the points the edit moved, at each point's local spacing before the edit.

The edit is written to the scratch folder first. The fill's tiles split the edited points; each reads its box and a
halo (in the edited positions, with the scan's positions beside them for the spacing before the edit), up-samples
what it read and keeps the new points inside its box. The library keeps new samples in an order of their
coordinates alone, so a tile whose halo holds what its new points depend on finds the one-process points. The new
points follow the scan's rows in the output, in the order of their coordinates (x, then y, then z), as the library
writes them: tiles sort their own, and the write merges them by ranges of x. See doc/scaling.md, "Up-sampling in
tiles".
"""
import dataclasses
import os
import uuid
from pathlib import Path
from typing import Any, List, Optional

import numpy as np

from .. import _core, threads
from . import plan
from .edit import Edit
from .ops import NORMALS, XYZ
from .runner import CHUNK_ROWS, Run, _read_tile, bucket_rows, scan_rows, timed
from .store import ZarrSource

# A tile's halo, in the edited points' k-th-neighbour distances (k = the up-sampling's 12, about two spacings): each
# of the up-sampling's 4 rounds reaches across a hole of up to 6 spacings, its fits and its relaxation a few
# spacings more. No certificate: the margin is measured (doc/scaling.md, "Up-sampling in tiles").
HALO_NEIGHBOR_DISTANCES = 24
NEIGHBORS = 12  # the up-sampling's default neighbours
KEY_STRIDE = 64  # every 64th new point's x goes to the client, to split the merge into ranges
FIELDS = XYZ + NORMALS + [("inserted", "f8")]


class EditedScan(ZarrSource):
    """The edit written to the scratch folder (a Zarr group) beside the scan it edited, as the fill's tiles read
    them: the edited points, and after their normals the scan's points (to measure the spacing before the edit and
    to tell what moved)."""
    carried_columns = 6

    def __init__(self, path, scan):
        super().__init__(path)
        self.scan = scan

    def points_and_normals(self, begin, end):
        points, normals = super().points_and_normals(begin, end)
        return points, np.hstack([normals, self.scan.coordinates(begin, end)])


@dataclasses.dataclass(frozen=True)
class FillJob:
    """One tile of the fill: the tile, its halo (the buckets were cut with it), the edited scan, the tiling, where
    each chunk of rows starts, the scratch folder and the library's threads."""
    tile: int
    halo: float
    source: Any
    tiling: Any
    chunk_starts: List[int]
    scratch: Path
    threads_per_task: Optional[int]


def fill_tile(job):
    """Up-samples a tile's points with its halo and saves the new points inside its box, sorted by their
    coordinates, as `scratch/fill_{tile}.npy` (points and normals side by side). Returns the points read, the new
    points kept and every KEY_STRIDE-th one's x."""
    lo, hi = job.tiling.lo[job.tile], job.tiling.hi[job.tile]
    _, points, carried = _read_tile(job.source, job.tile, lo, hi, job.halo, job.scratch / "buckets", job.halo,
                                    job.chunk_starts)
    normals, before = carried[:, :3], carried[:, 3:]
    moved = np.flatnonzero(np.any(points != before, axis=1))
    new = np.empty((0, 6))
    # The library needs more points than neighbours; a tile reading fewer holds no gap the edit stretched.
    if len(moved) and len(points) > NEIGHBORS:
        with threads(job.threads_per_task):
            added = _core.upsample_point_set(points, normals, roi=moved,
                                             spacing_before=_core.compute_local_spacing(before))
        mine = plan.own_mask(added.points, lo, hi)
        new = np.hstack([added.points[mine], added.normals[mine]])  # in the library's order: x, then y, then z
    partial = job.scratch / f".fill_{job.tile}.{uuid.uuid4().hex[:8]}.npy"
    np.save(partial, new)
    os.replace(partial, job.scratch / f"fill_{job.tile}.npy")  # a rerun of the task replaces the old result
    return {"read": len(points), "new": len(new), "keys": new[::KEY_STRIDE, 0].copy()}


def range_bounds(scratch, tile, splitters):
    """Where each of `splitters` (ascending x) falls in the tile's new points, with 0 and their count around."""
    x = np.load(scratch / f"fill_{tile}.npy", mmap_mode="r")[:, 0]
    return np.concatenate([[0], np.searchsorted(x, splitters, side="left"), [len(x)]]).astype(np.int64)


def write_filled(begin, end, pieces, first_rank, edited, sink, scratch, count):
    """Rows [begin, end) of the output: the edited scan's rows below `count`, then the new points of ranks
    [max(begin, count) - count, end - count) in the order of their coordinates. `pieces` (tile, a, b) hold every
    new point of ranks first_rank.. up to past the last one wanted, and no other."""
    columns = {name: np.empty(end - begin, dtype=kind) for name, kind in FIELDS}
    scan_end = min(end, count)
    if begin < scan_end:
        points, normals = ZarrSource.points_and_normals(edited, begin, scan_end)
        for axis, name in enumerate("xyz"):
            columns[name][:scan_end - begin] = points[:, axis]
            columns["n" + name][:scan_end - begin] = normals[:, axis]
        columns["inserted"][:scan_end - begin] = 0.0
    if end > count:
        new = np.concatenate([np.load(scratch / f"fill_{tile}.npy", mmap_mode="r")[a:b] for tile, a, b in pieces]
                             or [np.empty((0, 6))])
        new = new[np.lexsort((new[:, 2], new[:, 1], new[:, 0]))]
        skip = max(begin, count) - count - first_rank
        new = new[skip:skip + end - max(begin, count)]
        at = slice(max(begin, count) - begin, end - begin)
        for axis, name in enumerate(("x", "y", "z", "nx", "ny", "nz")):
            columns[name][at] = new[:, axis]
        columns["inserted"][at] = 1.0
    sink.write(begin, columns)
    return end - begin


def fill(passes, edited_path, scan, output, scratch, tiles=None, halo=None, threads_per_task=1):
    """Fills what the edit at `edited_path` (a Zarr group of the edited scan, in `scan`'s rows) stretched, in tiles,
    and writes the edited points and the new ones to `output` whole (a committed sink) or not at all. Returns the
    fill's part of the report."""
    source = EditedScan(edited_path, scan)
    n = source.count
    ranges = passes.row_ranges(n)
    starts = [begin for begin, _ in ranges]
    tile_count, stride = passes.tile_count_and_stride(n, tiles, Edit.points_per_tile)
    scans = passes.map(scan_rows, ranges, source, stride, what="fill scan")
    with passes.client_step("fill plan"):
        sample = np.concatenate([s["sample"] for s in scans])
        tiling = plan.Tiling(sample, min(tile_count, max(1, len(sample) // 8)))
        spacing = Run._spacing(sample, stride, NEIGHBORS)
        halo = float(halo) if halo is not None else HALO_NEIGHBOR_DISTANCES * spacing
    (scratch / "buckets").mkdir()
    halos = np.full(tiling.count, halo)
    passes.map(bucket_rows, ranges, source, tiling, halos, scratch / "buckets", what="fill bucket")
    jobs = [(FillJob(tile=t, halo=halo, source=source, tiling=tiling, chunk_starts=starts, scratch=scratch,
                     threads_per_task=threads_per_task),) for t in range(tiling.count)]
    summaries = passes.map(fill_tile, jobs, what="fill tiles")
    inserted = sum(s["new"] for s in summaries)
    with passes.client_step("fill plan"):
        # Ranges of x holding about half an output chunk each; exact ranks from each tile's bounds in them.
        keys = np.sort(np.concatenate([s["keys"] for s in summaries]))
        per_range = max(1, (CHUNK_ROWS // 2) // KEY_STRIDE)
        splitters = np.unique(keys[per_range::per_range])
    bounds = np.stack(passes.map(range_bounds, [(scratch, t) for t in range(tiling.count)], splitters,
                                 what="fill merge"))
    rank_starts = bounds.sum(axis=0)  # the rank of each range's first new point; the last is `inserted`
    items = []
    for begin, end in passes.row_ranges(n + inserted):
        low, high = max(begin, n) - n, end - n
        if high <= low:
            items.append((begin, end, [], 0))
            continue
        first = int(np.searchsorted(rank_starts, low, side="right")) - 1
        last = int(np.searchsorted(rank_starts, high, side="left"))
        pieces = [(t, int(bounds[t, first]), int(bounds[t, last])) for t in range(tiling.count)
                  if bounds[t, last] > bounds[t, first]]
        items.append((begin, end, pieces, int(rank_starts[first])))
    with passes.client_step("create output"):
        sink = passes.open_sink(output, n + inserted, FIELDS)
        sink.create()
    try:
        passes.map(write_filled, items, source, sink, scratch, n, what="fill write")
        with timed(passes.report["client_seconds"], "commit output"):
            sink.commit()
    except BaseException:
        sink.discard()
        raise
    return {"inserted": inserted, "tiles": tiling.count, "halo": halo, "spacing": spacing,
            "read_points": int(sum(s["read"] for s in summaries))}
