"""The detail-preserving edit of a scan of any size on Dask: the edit's sample points, their solve and their motions
computed once on the client, with the library's Deformation on a subsample; every point of the scan then moved
tile by tile by those motions (diffuse_points), the halo of a tile near a handle holding the handle points within
the collar's reach, and the details restored (a fixed number of Chebyshev steps, each reaching one neighbourhood
further) on every point the symmetric certificate finds that many hops from the read box's border. See
doc/scaling.md, "Editing in tiles".
"""
import json
import math

import numpy as np

from .. import _core
from . import ops, plan
from .runner import timed
from .simplify import SUBSAMPLE, _whole, sorted_subsample, subsample_pass
from .store import TiledError

FIXED, REGION = -2, -1  # diffuse_points' selection values; a handle point's is its group


def region_specs(specs, where):
    """The sphere and box specs of a list of region spec strings, as ("sphere", centre, radius) and ("box", lo,
    hi); the tiles evaluate them on their points. Index files name points of the whole scan, which a tile's
    points are not: refused."""
    parsed = []
    for spec in specs:
        kind, _, numbers = str(spec).partition(":")
        if kind == "indices":
            raise TiledError(f"{where}: the tiled edit selects by sphere: and box: specs; {spec!r} names points by "
                             f"index")
        values = [float(v) for v in numbers.split(",")] if kind in ("sphere", "box") else []
        if kind == "sphere" and len(values) == 4:
            parsed.append(("sphere", np.array(values[:3]), values[3]))
        elif kind == "box" and len(values) == 6:
            parsed.append(("box", np.array(values[:3]), np.array(values[3:])))
        else:
            raise TiledError(f"{where}: {spec!r} is not a region spec (sphere:x,y,z,r or box:xmin,ymin,zmin,xmax,"
                             f"ymax,zmax)")
    return parsed


def inside(points, specs):
    """Whether each point lies in the union of `specs`, with the program's comparisons (io/region_spec.cpp):
    squared distances summed x, y, z in turn against the squared radius; boxes closed."""
    chosen = np.zeros(len(points), dtype=bool)
    for kind, a, b in specs:
        if kind == "sphere":
            d = points - a
            chosen |= d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2] <= b * b
        else:
            chosen |= np.all((points >= a) & (points <= b), axis=1)
    return chosen


def restore_steps(state):
    """The Chebyshev steps of diffuse_points' restoration for a diffusion state (internal::Detail_relaxation::steps):
    the fewest with T_K(1 + anchor) >= 1 / tolerance, at most detail_iterations."""
    tolerance, cap = float(state["detail_tolerance"]), int(state["detail_iterations"])
    if not tolerance < 1:
        return 0
    if not tolerance > 0:
        return cap
    return min(cap, math.ceil(math.acosh(1 / tolerance) / math.acosh(1 + float(state["detail_anchor"]))))


class Edit(ops.Operation):
    """The tiled edit as a tiled operation: the moved positions and normals as its values. Near the handles a tile
    reads the collar's reach; where its own points relax (the region's, but exact handles), the certificate of the
    restoration's closed balls over its steps and three hops more (the targets' rotations, which rows are
    unknowns, the twins)."""
    name = "edit"
    symmetric = True
    measures_radius = True  # diffuse_points reports each point's 10th-neighbour distance
    RELAXATION_NEIGHBORS = 10  # diffuse_points' restoration: the closed ball of the 10th nearest

    def __init__(self, edit, subsample=SUBSAMPLE):
        if not _whole(subsample) or subsample < 1:
            raise TiledError(f"edit: subsample must be a whole number of points >= 1, not {subsample!r}")
        self.path, self.subsample_size = str(edit), int(subsample)
        try:
            with open(self.path, encoding="utf-8") as f:
                description = json.load(f)
        except (OSError, ValueError) as error:
            raise TiledError(f"edit: cannot read {self.path}: {error}") from None
        if not isinstance(description, dict) or "steps" in description:
            raise TiledError(f"{self.path}: the tiled edit takes one edit (roi, handles), not a chain of steps")
        roi = description.get("roi")
        self.roi = None if roi is None else region_specs(roi, f"{self.path}: roi")
        handles = description.get("handles")
        if not isinstance(handles, list) or not handles:
            raise TiledError(f"{self.path}: handles must be a non-empty array of handle groups")
        self.handles = [region_specs(h.get("select", []) if isinstance(h, dict) else [],
                                     f"{self.path}: handles[{g}].select") for g, h in enumerate(handles)]
        self.options, self.settings, self.state = {}, {}, None

    def selection(self, points):
        """Each point's place in the edit (FIXED, REGION or its handle group), or TiledError naming the first point
        that is a handle of two groups or a handle outside the region."""
        region = np.ones(len(points), dtype=bool) if self.roi is None else inside(points, self.roi)
        selection = np.where(region, REGION, FIXED)
        for group, specs in enumerate(self.handles):
            chosen = inside(points, specs)
            twice = chosen & (selection >= 0)
            outside = chosen & ~region
            for bad, why in ((twice, "a handle of two groups"), (outside, "a handle outside the region of interest")):
                if bad.any():
                    raise TiledError(f"{self.path}: the point at {points[np.argmax(bad)].tolist()} is {why}")
            selection[chosen] = group
        return selection

    def prepare(self, runner, source):
        """The client's part: the subsample (chosen by a hash of the coordinates, as the tiled sample points'), the
        edit read on it by the program's reader, the Deformation built and deformed there, and its diffusion's
        state for the tiles."""
        n = source.count
        selected = subsample_pass(runner, source, self.subsample_size, "the edit turns them with the points")
        with timed(runner.report["client_seconds"], "deform subsample"):
            points, normals = sorted_subsample(selected, "edit", self.subsample_size, n)
            try:
                edit = _core._read_edit(self.path, points)
            except ValueError as error:
                raise TiledError(f"edit: {str(error).splitlines()[0]} (on the subsample of {len(points)} points)") \
                    from None
            selection = self.selection(points)
            if not np.array_equal(np.flatnonzero(selection != FIXED), edit["roi"]):
                raise TiledError(f"{self.path}: the region's specs select differently here and in the program")
            self.settings = edit["settings"]
            deformation = _core.Deformation(points, normals, **self.settings)
            deformation.insert_roi(edit["roi"])
            for group, handle in enumerate(edit["handles"]):
                if not np.array_equal(np.flatnonzero(selection == group), np.sort(handle["points"])):
                    raise TiledError(f"{self.path}: handles[{group}] selects differently here and in the program")
                deformation.create_handle_group(handle["points"])
                deformation.set_handle_transform(group, handle["rotation"], handle["translation"])
            try:
                deformation.deform()
            except ValueError as error:
                raise TiledError(f"edit: {str(error).splitlines()[0]}") from None
            self.state = deformation.diffusion_state()
        runner.report.update(subsample=len(points), sample_points=deformation.number_of_sample_points(),
                             collar_reach=self.state["collar_reach"])
        runner.log(f"{n} points, subsample of {len(points)}: {deformation.number_of_sample_points()} sample points, "
                   f"collar reach {self.state['collar_reach']:.4g}")

    @property
    def restores(self):
        return restore_steps(self.state) > 0

    @property
    def uses_neighbors(self):
        return self.restores

    def computed_fields(self):
        return ("x", "y", "z", "nx", "ny", "nz")

    def estimates_normals(self, has_normals):
        return False

    def neighbors(self, estimate_normals):
        return self.own_neighbors() if self.restores else 1  # 1: for the plan's spacing only

    def own_neighbors(self):
        return self.RELAXATION_NEIGHBORS

    def rings(self):
        return restore_steps(self.state) + 3

    def collar(self):
        return 1.01 * float(self.state["collar_reach"])

    def halo(self, spacing):
        """A tile's first halo near a handle: the collar's reach (a point's diffused position depends on the
        sample points and on the handle points that near), and the restoration's hops."""
        return self.collar() + (ops.Operation.halo(self, spacing) if self.restores else 0.0)

    def relaxes(self, points):
        """Which points the restoration may move: the region's, and the handles' unless they are exact."""
        selection = self.selection(points)
        return selection == REGION if self.state["exact_handles"] else selection != FIXED

    def needs_certificate(self, points, own):
        """The own points that relax, when the edit restores the details."""
        return self.relaxes(points[own]) & self.restores

    def narrowed(self, points, lo, hi, halo):
        """Near a handle, when restoring: every point within the restoration's halo (`halo` less the collar's
        reach), and beyond it the handle points alone, which the collar needs and the other points do not. Every
        point within that halo then has the handle points within the reach."""
        if not self.restores or not self.near_handles(lo[None], hi[None])[0]:
            return None, halo
        inner = max(halo - self.collar(), 0.0)
        return plan.own_mask(points, lo - inner, hi + inner) | (self.selection(points) >= 0), inner

    def near_handles(self, lo, hi):
        """Whether each box [lo[i], hi[i]] comes within the collar's reach of a handle's spec: only there can a
        point have handle points within the reach (a point's box is [p, p])."""
        near = np.zeros(len(lo), dtype=bool)
        reach = self.collar()
        for kind, a, b in (spec for group in self.handles for spec in group):
            near |= (plan.box_distances(a, a, lo, hi) <= b + reach if kind == "sphere" else
                     plan.box_distances(a, b, lo, hi) <= reach)
        return near

    def meets_region(self, lo, hi):
        """Whether each box [lo[i], hi[i]] meets the region's specs (all of them without specs)."""
        if self.roi is None:
            return np.ones(len(lo), dtype=bool)
        meets = np.zeros(len(lo), dtype=bool)
        for kind, a, b in self.roi:
            meets |= (plan.box_distances(a, a, lo, hi) <= b if kind == "sphere" else
                      plan.box_distances(a, b, lo, hi) <= 0)
        return meets

    def tile_halos(self, lo, hi, halo):
        """`halo` for the tiles near a handle; the restoration's hops for the others whose points may relax; none
        for the rest: their points move by the sample points' motions alone, which every tile holds."""
        relaxing = self.restores & self.meets_region(lo, hi)
        return np.where(self.near_handles(lo, hi), float(halo), np.where(relaxing, float(halo) - self.collar(), 0.0))

    def required_halo(self, neighborhoods, own, points):
        """Without the restoration, the collar's reach where an own point is near a handle (with it, the
        certificate's reach holds the collar)."""
        mine = points[own]
        return self.collar() if not self.restores and self.near_handles(mine, mine).any() else 0.0

    def compute(self, points, normals, radius=None):
        """The moved points and normals; `radius`, an (n,) array, receives each point's 10th-neighbour distance."""
        moved = _core.diffuse_points(points, normals, self.state, selection=self.selection(points),
                                     restore_details=self.restores, neighbor_radius=radius)
        return {name: column for name, column in zip(self.computed_fields(), (*moved.points.T, *moved.normals.T))}
