"""The per-tile computations of the tiled runs: what each operation computes on the points a tile read, what it
writes, and which of its own points the halo certifies.

Each operation calls the package's one-process function on the tile's points; nothing here re-implements it.
Options the caller leaves out are left to those functions, whose keywords and defaults the extension exports
(`_core._parameters`, recorded from the arguments that define them).
"""
import inspect
from typing import Any, Callable, Dict, Optional, Tuple

import numpy as np

from .. import _core
from . import plan

XYZ = [("x", "f8"), ("y", "f8"), ("z", "f8")]
NORMALS = [("nx", "f8"), ("ny", "f8"), ("nz", "f8")]
RGB = [("red", "u1"), ("green", "u1"), ("blue", "u1")]
RINGS = {"linear": 1, "quadric": 2, "cubic": 3}  # the highest power of K in f(K)


def keywords(function):
    """{keyword: default} of a compiled function of the library, without its arrays and its progress callback;
    inspect.Parameter.empty where the keyword has no default."""
    parameters = _core._parameters[function.__name__]
    return {name: value for name, value in parameters.items() if name not in ("points", "normals", "progress")}


def defaults(function):
    """{keyword: default} of the keywords of a compiled function that have one."""
    return {name: value for name, value in keywords(function).items() if value is not inspect.Parameter.empty}


class Operation:
    """One subcommand: `options` are the library function's keywords the caller gave."""
    name: str = ""
    function: Callable[..., Any]
    value_fields: Tuple[str, ...] = ()
    sign_fields: Tuple[str, ...] = ()  # fields whose sign follows the normals' orientation
    color_field: Optional[str] = None
    exact = True
    symmetric = False  # on the symmetrised kNN graph: the certificate assumes a reach, verified after the tiles
    banded = True  # the certificate searches neighbours only near the read box's border (plan.banded_neighborhoods)
    measures_radius = False  # compute() can report each point's k-th-neighbour distance (plan.certify_with_radius)
    uses_neighbors = True  # else a point's value needs only the points within required_halo(): nothing to certify
    takes_rows = False  # compute() takes the points' rows in the scan (`rows=`)
    points_per_tile = 1 << 18  # the tiles' size by default (a tile's own points)
    extra_options: Tuple[str, ...] = ()  # the runs' own options beside the library function's
    extra_defaults: Dict[str, Any] = {}

    def __init__(self, **options):
        unknown = set(options) - set(keywords(self.function)) - set(self.extra_options)
        if unknown:
            raise ValueError(f"{self.name}: unknown option(s) {', '.join(sorted(unknown))}")
        self.options = options
        self.settings = {**defaults(self.function), **self.extra_defaults, **options}
        if self.settings.get("order", "linear") not in RINGS:
            raise ValueError(f"{self.name}: order must be one of {', '.join(RINGS)}, not '{self.settings['order']}'")

    def library_options(self):
        return {key: value for key, value in self.options.items() if key not in self.extra_options}

    def computed_fields(self):
        """The output fields the tiles compute (the others are the input's)."""
        return self.value_fields

    def fields(self):
        return XYZ + NORMALS + [(name, "f8") for name in self.value_fields] + (RGB if self.color_field else [])

    def estimates_normals(self, has_normals):
        """Whether the tiles estimate (and orient) the normals: when the scan has none."""
        return not has_normals

    def oriented_normals(self, points):
        """The normals the one-process function estimates for points without any."""
        return _core.estimate_oriented_normals(points)

    def neighbors(self, estimate_normals):
        """The most neighbours (itself not counted) any certified quantity uses."""
        return max(self.own_neighbors(), self.normal_neighbors() if estimate_normals else 0)

    def normal_neighbors(self):
        """The neighbours of an estimated normal's fit (itself not counted)."""
        return defaults(_core.estimate_oriented_normals)["k"]

    def own_neighbors(self):
        """The neighbours (itself not counted) of the operation's own values."""
        return int(self.settings["k"])

    def certify(self, neighborhoods, own, reach, estimate_normals):
        if self.symmetric:
            certified = plan.certify_symmetric(neighborhoods, self.own_neighbors(), own, reach, self.rings())
        else:
            certified = plan.certify_directed(neighborhoods, self.own_neighbors(), own)
        if estimate_normals:
            certified &= plan.certify_directed(neighborhoods, self.normal_neighbors(), own)
        return certified

    def halo(self, spacing):
        """A first halo width from the typical k-th-neighbour distance of the scan."""
        return 1.5 * (self.rings() + 1) * spacing

    def tile_halos(self, lo, hi, halo):
        """Each tile's first halo, for the tiles' boxes [lo[t], hi[t]): `halo` for all of them, unless the operation
        knows that the points of some tiles depend on nearer points only."""
        return np.full(len(lo), float(halo))

    def rings(self):
        """Products with K the values need: the transfer function's degree, else one neighbourhood."""
        return RINGS[self.settings["order"]] if "order" in self.settings else 1

    def needs_certificate(self, points, rows, own):
        """Which own points of a tile (`points` read, at the scan's `rows`; `own` its own) need their neighbourhoods
        certified (the others' values need no neighbourhood): all of them, or none for an operation that uses
        none."""
        return np.full(int(np.count_nonzero(own)), self.uses_neighbors)

    def narrowed(self, points, rows, lo, hi, halo):
        """The points a tile [lo, hi) keeps of those it read within `halo` (at the scan's `rows`; a mask, None: all
        of them), and the halo within which it kept every point, which bounds its certificate."""
        return None, halo

    def required_halo(self, neighborhoods, own, points):
        """The halo an approximate operation needs beyond what `certify` checks (0: none), for a tile's `points`
        (`own`: its own)."""
        return 0.0


class Details(Operation):
    name = "details"
    function = _core.compute_geometric_details
    value_fields = ("detail_x", "detail_y", "detail_z", "detail_magnitude", "detail_normal")
    sign_fields = ("detail_magnitude", "detail_normal")
    symmetric = True
    extra_options = ("color_by",)
    extra_defaults = {"color_by": "detail_normal"}

    def __init__(self, **options):
        super().__init__(**options)
        if self.settings["color_by"] not in ("detail_normal", "detail_magnitude"):
            raise ValueError(f"details: color_by must be detail_normal or detail_magnitude, not "
                             f"'{self.settings['color_by']}'")
        self.color_field = self.settings["color_by"]

    measures_radius = True

    def compute(self, points, normals, radius=None):
        """The values; `radius`, an (n,) array, receives each point's k-th-neighbour distance."""
        details, magnitude = _core.compute_geometric_details(points, normals, neighbor_radius=radius,
                                                             **self.library_options())
        along_normal = np.einsum("ij,ij->i", details, normals) / np.linalg.norm(normals, axis=1)
        return {"detail_x": details[:, 0], "detail_y": details[:, 1], "detail_z": details[:, 2],
                "detail_magnitude": magnitude, "detail_normal": along_normal}


class Curvature(Operation):
    name = "curvature"
    function = _core.estimate_mean_curvature
    value_fields = ("mean_curvature",)
    sign_fields = ("mean_curvature",)
    color_field = "mean_curvature"

    def compute(self, points, normals):
        return {"mean_curvature": _core.estimate_mean_curvature(points, normals, **self.library_options())}


class Normals(Operation):
    name = "normals"
    function = _core.estimate_oriented_normals

    def normal_neighbors(self):
        return self.own_neighbors()  # the values are the normals, fitted with the operation's own k

    def certify(self, neighborhoods, own, reach, estimate_normals):
        return plan.certify_directed(neighborhoods, self.own_neighbors(), own)  # the values are the normals

    def estimates_normals(self, has_normals):
        return True  # the scan's own normals, if any, are replaced

    def oriented_normals(self, points):
        return _core.estimate_oriented_normals(points, **self.library_options())

    def compute(self, points, normals):
        return {}


class Enhance(Operation):
    """Whole-scan enhancement, p~ + s (p - p~): the balanced flow's base surface p~ is a global solve whose
    influence fades with distance, so a tile reads `margin` neighbourhood radii around it (as the one-process
    call does for a partial region) and its result is close to, not equal to, the one-process result."""
    name = "enhance"
    function = _core.enhance_geometric_details
    value_fields = ("displacement", "in_roi")
    sign_fields = ("displacement",)
    symmetric = True
    extra_options = ("margin",)
    extra_defaults = {"margin": 80.0}
    exact = False
    banded = False  # its halo follows the median k-th-neighbour distance of all its own points

    def __init__(self, **options):
        if "s" not in options:
            raise ValueError("enhance: s (the enhancement factor) is required")
        for name in ("roi", "anchors"):
            if name in options:
                raise ValueError(f"enhance: the tiled runs enhance the whole scan; {name} is not supported")
        super().__init__(**options)
        if not (np.isfinite(self.settings["margin"]) and self.settings["margin"] > 0):
            raise ValueError(f"enhance: margin must be a positive number of neighbourhood radii, not "
                             f"{self.settings['margin']}")

    def halo(self, spacing):
        return float(self.settings["margin"]) * spacing

    def computed_fields(self):
        return ("x", "y", "z") + self.value_fields

    def required_halo(self, neighborhoods, own, points):
        radius = np.median(neighborhoods.kth_distance(self.own_neighbors())[own])
        return float(self.settings["margin"]) * radius

    def compute(self, points, normals):
        moved = _core.enhance_geometric_details(points, normals, **self.library_options())
        displacement = np.einsum("ij,ij->i", moved - points, normals)
        return {"x": moved[:, 0], "y": moved[:, 1], "z": moved[:, 2], "displacement": displacement,
                "in_roi": np.ones(len(points))}


OPERATIONS = {op.name: op for op in (Details, Curvature, Normals, Enhance)}


def operation(name, **options):
    if name not in OPERATIONS:
        raise ValueError(f"unknown operation '{name}': one of {', '.join(OPERATIONS)} or simplify")
    return OPERATIONS[name](**options)
