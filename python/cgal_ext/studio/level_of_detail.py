"""A level of detail for scans too large to edit whole: the even subsample the tiled edit deforms, read from the
scan by a tiled pass on Dask and cached beside it, in a hidden folder (.SCAN.lod). The session edits it in the
scan's place; a save carries the selection to every point by its nearest point of the level of detail and runs the
tiled edit (doc/studio.md, "Scans larger than one machine").
"""
import json
import os
import pathlib
import tempfile

import numpy as np

import cgal_ext

LEVEL_OF_DETAIL_ABOVE = 20_000_000  # the largest scan the studio edits whole
LEVEL_POINTS = 1_000_000  # the level's points: the tiled edit's default subsample, so that it deforms the same
NEIGHBOR_FOR_REACH = 8  # the reach of the level's points: twice the largest distance to their 8th nearest
CACHE_VERSION = 1


def point_count(path):
    """The points of a scan the tiled runs read (binary PLY, PCD, LAS, Zarr), from its header; None for other files
    (which are read whole)."""
    from ..tiled import TiledError
    from ..tiled.store import open_source
    try:
        return open_source(path).count
    except (TiledError, OSError, ValueError):
        return None


def cache_folder(path):
    path = pathlib.Path(path)
    return path.parent / ("." + path.name + ".lod")


def _identity(path, count, size):
    status = os.stat(path)
    return {"version": CACHE_VERSION, "scan": pathlib.Path(path).name, "bytes": status.st_size,
            "modified_ns": status.st_mtime_ns, "inode": status.st_ino, "points": count, "subsample": size}


def reach_of(points):
    """How far a point of the scan may lie from its nearest point of the level and be selected through it: twice
    the largest distance from a point of the level to its 8th nearest, a few times the widest gap a random
    subsample leaves on the surface (doc/studio.md)."""
    from scipy.spatial import cKDTree
    k = min(NEIGHBOR_FOR_REACH + 1, len(points))
    distances = cKDTree(points).query(points, k)[0].reshape(len(points), -1)
    return 2.0 * max(float(distances[:, -1].max()), 1e-12 * float(np.abs(points).max()))


def open_level(path, count, size, progress=None, log=None):
    """The level of detail of the scan at `path` (`count` points): (points, normals, reach, built), from the cache
    when it was made from this very file, else by a tiled pass (`progress(pass, done, tasks)`) and cached when the
    folder can be written."""
    from .. import tiled
    folder = cache_folder(path)
    identity = _identity(path, count, size)
    try:
        with open(folder / "level.json", encoding="utf-8") as f:
            cached = json.load(f)
        if cached.get("identity") == identity:
            cloud = cgal_ext.read_points(str(folder / "level.ply"))
            if cloud.normals is not None and len(cloud.points) == cached.get("points"):
                return cloud.points, cloud.normals, float(cached["reach"]), False
    except (OSError, ValueError, RuntimeError, KeyError, TypeError, AttributeError):
        pass  # no cache, or one that does not answer: built again
    points, normals = tiled.subsample(path, size, progress=progress, log=log)
    reach = reach_of(points)
    try:
        folder.mkdir(exist_ok=True)
        # The points first, the description naming them last: a cache is whole or not read.
        with tempfile.TemporaryDirectory(dir=folder, prefix=".writing.") as private:
            cgal_ext.write_ply(os.path.join(private, "level.ply"), points, normals)
            with open(os.path.join(private, "level.json"), "w", encoding="utf-8") as f:
                json.dump({"identity": identity, "points": len(points), "reach": reach}, f)
            if os.path.exists(folder / "level.json"):
                os.unlink(folder / "level.json")
            os.replace(os.path.join(private, "level.ply"), folder / "level.ply")
            os.replace(os.path.join(private, "level.json"), folder / "level.json")
    except OSError as error:
        if log:
            log("the level of detail is not cached: %s" % error)
    return points, normals, reach, True
