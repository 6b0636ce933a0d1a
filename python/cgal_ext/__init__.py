"""High-frequency geometric details of point-sampled surfaces (Miao et al., The Visual Computer 2007) on numpy arrays.

Details and their colour maps, detail scaling and enhancement, mean curvature, simplification sample points,
up-sampling and detail-preserving editing, with the point-detail program's file readers, writers and pictures.
Every function's help() names its parameters; the manual is doc/python.md.
"""
import contextlib

from ._core import (Deformation, Deformed, Details, PointSet, Upsampled, compute_geometric_details,
                    compute_local_spacing, compute_neighbor_graph, compute_simplification_sample_points,
                    diffuse_points, diverging_colors, enhance_geometric_details, estimate_mean_curvature,
                    estimate_oriented_normals, get_num_threads, label_colors, read_points, refit_normals, render_png,
                    scale_geometric_details, sequential_colors, set_num_threads, upsample_point_set, write_ply)
from ._version import __version__

__all__ = ["Deformation", "Deformed", "Details", "PointSet", "Upsampled", "__version__", "compute_geometric_details",
           "compute_local_spacing", "compute_neighbor_graph", "compute_simplification_sample_points",
           "diffuse_points", "diverging_colors", "enhance_geometric_details", "estimate_mean_curvature",
           "estimate_oriented_normals", "get_num_threads", "label_colors", "read_points", "refit_normals", "render_png",
           "scale_geometric_details", "sequential_colors", "set_num_threads", "threads", "upsample_point_set",
           "write_ply"]

_thread_limits = []  # the limits of the enclosing `threads` blocks, innermost last


@contextlib.contextmanager
def threads(count):
    """Limits the library's worker threads to `count` inside a with-block, as set_num_threads(count) does; the
    limit before the block (or none) holds again after it.

    Parameters
    ----------
    count : int or None
        At least 1; None lifts the limit inside the block.
    """
    set_num_threads(count)
    _thread_limits.append(count)
    try:
        yield
    finally:
        _thread_limits.pop()
        set_num_threads(_thread_limits[-1] if _thread_limits else None)
