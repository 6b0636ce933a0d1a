"""The detail-preserving edit of a scan of any size on Dask: the edit's sample points, their solve and their motions
computed once on the client, with the library's Deformation on a subsample; every point of the scan then moved
tile by tile by those motions (diffuse_points), the halo of a tile near a handle holding the handle points within
the collar's reach, and the details restored (a fixed number of Chebyshev steps, each reaching one neighbourhood
further) on every point the symmetric certificate finds that many hops from the read box's border. Regions and
handles are sphere: and box: specs, index files of the scan's rows, boolean arrays of its Zarr group (mask:), or
index files of a sample the selection was painted on (nearest:, each point taking its nearest sample point's).
See doc/scaling.md, "Editing in tiles".
"""
import json
import math
import re
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from .. import _core
from . import ops, plan
from .runner import timed
from .simplify import SUBSAMPLE, _whole, kept_per_process, nearest_in, sorted_subsample, subsample_pass
from .store import TiledError, ZarrSource

FIXED, REGION = -2, -1  # diffuse_points' selection values; a handle point's is its group


def region_specs(specs, where, folder):
    """The specs of a list of region spec strings: ("sphere", centre, radius) and ("box", lo, hi), which the tiles
    evaluate on their points; ("indices", path), a file of rows of the scan (one per line, `#` comments; relative
    to `folder`, the edit JSON's), and ("mask", name), a boolean array of the scan's Zarr group, which
    Edit.prepare turns into ("rows", .npy of the sorted rows, their bounding box or None); ("nearest", path), a
    file of indices of the edit's sample, which it turns into ("near", .npy of them, the box they reach or None)."""
    parsed = []
    for spec in specs:
        kind, _, rest = str(spec).partition(":")
        if kind in ("indices", "mask", "nearest") and rest:
            parsed.append((kind, rest if kind == "mask" else str(Path(folder) / rest), None))
            continue
        values = [float(v) for v in rest.split(",")] if kind in ("sphere", "box") else []
        if kind == "sphere" and len(values) == 4:
            parsed.append(("sphere", np.array(values[:3]), values[3]))
        elif kind == "box" and len(values) == 6:
            parsed.append(("box", np.array(values[:3]), np.array(values[3:])))
        else:
            raise TiledError(f"{where}: {spec!r} is not a region spec (sphere:x,y,z,r, box:xmin,ymin,zmin,xmax,"
                             f"ymax,zmax, indices:FILE, mask:ARRAY or nearest:FILE)")
    return parsed


def read_index_file(path, count):
    """The sorted distinct rows an index file names (the program's format: one index per line, `#` comments), or
    a TiledError naming the file, the line and the problem."""
    try:
        if Path(path).exists() and not Path(path).is_file():  # a device would be read without end
            raise OSError("not a regular file")
        with open(path, "rb") as f:
            text = f.read()
    except OSError as error:
        raise TiledError(f"cannot read the index file {path}: {error}") from None
    rows = None
    tokens = text.split()
    if b"#" not in text and b"_" not in text and len(tokens) == sum(1 for line in text.splitlines() if line.strip()):
        try:
            rows = np.array(tokens, dtype=np.int64)  # one integer per line, as below: read at numpy's speed
        except (ValueError, OverflowError):
            pass  # the line-by-line reading below names the bad line
    if rows is None or (rows < 0).any() or (rows >= count).any():
        rows = []
        for number, line in enumerate(text.decode("utf-8", "replace").split("\n"), start=1):
            line = line.partition("#")[0].strip(" \t\r")
            if not line:
                continue
            if not re.fullmatch(r"[+-]?[0-9]+", line) or int(line) < 0:
                raise TiledError(f"{path}:{number}: '{line}' is not a point index")
            if int(line) >= count:
                raise TiledError(f"{path}:{number}: index {line} is out of range ({count} points)")
            rows.append(int(line))
    return np.unique(np.asarray(rows, dtype=np.int64))


def read_mask(source, name):
    """The sorted rows where the scan's Zarr array `name` is True, or a TiledError naming the problem."""
    if not isinstance(source, ZarrSource):
        raise TiledError(f"mask:{name} selects by an array of the scan's Zarr group; {source.path} is not one")
    import zarr
    group = zarr.open_group(source.path, mode="r")
    if name not in group.array_keys():
        raise TiledError(f"{source.path}: the Zarr group has no array {name!r} for mask:{name}")
    mask = group[name]
    if mask.dtype != np.bool_ or mask.shape != (source.count,):
        raise TiledError(f"{source.path}: mask:{name} must be a 1-D boolean array of the scan's {source.count} "
                         f"points, not {mask.dtype} of shape {mask.shape}")
    step = max(1, int(mask.chunks[0])) * max(1, 2**24 // max(1, int(mask.chunks[0])))
    return np.concatenate([begin + np.flatnonzero(mask[begin:begin + step])
                           for begin in range(0, source.count, step)] or [np.zeros(0, dtype=np.int64)])


def inside(points, rows, specs, nearest=None):
    """Whether each point (at the scan's `rows`; `nearest`, its nearest sample point within the sample's reach, or
    -1) lies in the union of `specs`, with the program's comparisons (io/region_spec.cpp): squared distances summed
    x, y, z in turn against the squared radius; boxes closed."""
    chosen = np.zeros(len(points), dtype=bool)
    for kind, a, b in specs:
        if kind == "sphere":
            d = points - a
            chosen |= d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2] <= b * b
        elif kind == "box":
            chosen |= np.all((points >= a) & (points <= b), axis=1)
        else:
            chosen |= _listed(np.load(a, mmap_mode="r"), nearest if kind == "near" else rows)
    return chosen


def _listed(selected, values):
    """Whether each of `values` is in the sorted array `selected`."""
    if not len(selected):
        return np.zeros(len(values), dtype=bool)
    at = np.minimum(np.searchsorted(selected, values), len(selected) - 1)
    return np.asarray(selected[at]) == values


def read_sample(sample, where, folder):
    """The edit's "sample" ({"points": a point file, relative to `folder`; "reach": the farthest a point may lie
    from its nearest sample point and be selected through it}): its points and reach, or a TiledError."""
    if not isinstance(sample, dict) or set(sample) != {"points", "reach"} or not isinstance(sample["points"], str):
        raise TiledError(f"{where}: give the sample as {{\"points\": FILE, \"reach\": DISTANCE}}")
    reach = sample["reach"]
    if isinstance(reach, bool) or not isinstance(reach, (int, float)) or not 0 < reach < math.inf:
        raise TiledError(f"{where}: reach must be a positive distance, not {reach!r}")
    path = Path(folder) / sample["points"]
    try:
        points = _core.read_points(str(path)).points
    except (OSError, ValueError, RuntimeError) as error:
        raise TiledError(f"{where}: cannot read the sample {path}: {str(error).splitlines()[0]}") from None
    if not len(points) or not np.isfinite(points).all():
        raise TiledError(f"{where}: the sample {path} must hold points, all finite")
    return np.ascontiguousarray(points, dtype=np.float64), float(reach)


def box_reach(specs, lo, hi, reach):
    """Whether each box [lo[i], hi[i]] comes within `reach` of a spec's points (of a row set's bounding box)."""
    near = np.zeros(len(lo), dtype=bool)
    for kind, a, b in specs:
        if kind == "sphere":
            near |= plan.box_distances(a, a, lo, hi) <= b + reach
        elif kind == "box":
            near |= plan.box_distances(a, b, lo, hi) <= reach
        elif b is not None:
            near |= plan.box_distances(b[0], b[1], lo, hi) <= reach
    return near


class Edit(ops.Operation):
    """The tiled edit as a tiled operation: the moved positions and normals as its values. Near the handles a tile
    reads the collar's reach; where its own points relax (the region's, but exact handles), the certificate of the
    restoration's closed balls over its steps and three hops more (the targets' rotations, which rows are
    unknowns, the twins)."""
    name = "edit"
    symmetric = True
    measures_radius = True  # diffuse_points reports each point's 10th-neighbour distance
    takes_rows = True  # index files and masks select by row
    # Larger tiles than the other runs': a tile in the region reads the restoration's halo, about 63 k-th-neighbour
    # distances deep, and computes in proportion to the points it reads (doc/scaling.md, "Editing in tiles").
    points_per_tile = 1 << 20
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
        folder = Path(self.path).parent
        roi = description.get("roi")
        self.roi = None if roi is None else region_specs(roi, f"{self.path}: roi", folder)
        handles = description.get("handles")
        if not isinstance(handles, list) or not handles:
            raise TiledError(f"{self.path}: handles must be a non-empty array of handle groups")
        self.handles = [region_specs(h.get("select", []) if isinstance(h, dict) else [],
                                     f"{self.path}: handles[{g}].select", folder) for g, h in enumerate(handles)]
        by_nearest = any(kind == "nearest" for kind, _, _ in self._all_specs())
        if by_nearest != ("sample" in description):
            raise TiledError(f"{self.path}: nearest: specs select through the edit's sample, and a sample is given "
                             f"for them: give both or neither")
        # The sample's points, then (prepare) the .npy the tiles read them from.
        self.sample = read_sample(description["sample"], f"{self.path}: sample", folder) if by_nearest else None
        self.description = description
        self.options, self.settings, self.state = {}, {}, None
        self._nearest_cache = None

    def __getstate__(self):
        return dict(self.__dict__, _nearest_cache=None)  # each process its own

    def nearest(self, points, rows):
        """Each point's nearest sample point, -1 beyond the sample's reach; None without a sample. A tile asks
        for its points, then for subsets of them: the last answer is kept, by row."""
        if self.sample is None:
            return None
        cached = self._nearest_cache
        if cached is not None:
            at = np.minimum(np.searchsorted(cached[0], rows), len(cached[0]) - 1)
            if np.array_equal(cached[0][at], rows):
                return cached[1][at]
        path, reach = self.sample
        distance, index = nearest_in(kept_per_process(path, lambda: cKDTree(np.load(path))), points)
        near = np.where(distance <= reach, index, -1)
        by_row = np.argsort(rows, kind="stable")
        self._nearest_cache = (rows[by_row], near[by_row])
        return near

    def selection(self, points, rows):
        """Each point's (at the scan's `rows`) place in the edit (FIXED, REGION or its handle group), or TiledError
        naming the first point that is a handle of two groups or a handle outside the region."""
        nearest = self.nearest(points, rows)
        region = np.ones(len(points), dtype=bool) if self.roi is None else inside(points, rows, self.roi, nearest)
        selection = np.where(region, REGION, FIXED)
        for group, specs in enumerate(self.handles):
            chosen = inside(points, rows, specs, nearest)
            twice = chosen & (selection >= 0)
            outside = chosen & ~region
            for bad, why in ((twice, "a handle of two groups"), (outside, "a handle outside the region of interest")):
                if bad.any():
                    raise TiledError(f"{self.path}: the point at {points[np.argmax(bad)].tolist()} (row "
                                     f"{rows[np.argmax(bad)]}) is {why}")
            selection[chosen] = group
        return selection

    def _all_specs(self):
        return [spec for specs in (self.roi or [], *self.handles) for spec in specs]

    def _map_specs(self, change):
        """Every list of specs (the region's, each handle group's) replaced by `change` of it."""
        self.roi = None if self.roi is None else change(self.roi)
        self.handles = [change(group) for group in self.handles]

    def _read_row_sets(self, source, scratch):
        """Each index file and mask read once into sorted rows (of the scan; of the sample for nearest:), saved in
        `scratch` for the tiles (memory-mapped there), and its specs turned into ("rows", .npy, None) or ("near",
        .npy, the box its sample points reach); the sample saved there too. Returns the distinct .npy paths of
        the scan's rows, which the subsample pass measures."""
        saved, boxes = {}, {}
        if self.sample is not None:
            sample, reach = self.sample
            self.sample = (str(scratch / "sample.npy"), reach)
            np.save(self.sample[0], sample)

        def saved_as(kind, name):
            """The .npy of a set, read and saved the first time it is named (with the box a nearest: set reaches)."""
            if (kind, name) not in saved:
                path = saved[kind, name] = str(scratch / f"rows_{len(saved)}.npy")
                if kind == "nearest":
                    rows = read_index_file(name, len(sample))
                    boxes[path] = (sample[rows].min(axis=0) - reach, sample[rows].max(axis=0) + reach) \
                        if len(rows) else None
                else:
                    rows = read_index_file(name, source.count) if kind == "indices" else read_mask(source, name)
                np.save(path, rows)
            return saved[kind, name]

        def read(specs):
            out = []
            for kind, a, b in specs:
                if kind in ("indices", "mask", "nearest"):
                    a = saved_as(kind, a)
                    kind, b = ("near", boxes[a]) if kind == "nearest" else ("rows", None)
                out.append((kind, a, b))
            return out
        self._map_specs(read)
        return [path for path in saved.values() if path not in boxes]

    def _set_row_boxes(self, paths, selected):
        """Each row set's bounding box (None when it holds no row) from the subsample pass's `selected`, which
        measured `paths` on every row."""
        boxes = {}
        for i, path in enumerate(paths):
            parts = [s["row_boxes"][i] for s in selected if s["row_boxes"][i] is not None]
            boxes[path] = ((np.min([p[0] for p in parts], axis=0), np.max([p[1] for p in parts], axis=0))
                           if parts else None)
        self._map_specs(lambda specs: [(kind, a, boxes[a] if kind == "rows" else b) for kind, a, b in specs])

    def prepare(self, runner, source):
        """The client's part: index files and masks read, the subsample (chosen by a hash of the coordinates, as
        the tiled sample points'), the edit read on it by the program's reader, the Deformation built and deformed
        there, and its diffusion's state for the tiles. Every error is raised here, before any tile runs."""
        n = source.count
        row_sets = self._read_row_sets(source, runner.scratch)
        selected = subsample_pass(runner, source, self.subsample_size, "the edit turns them with the points",
                                  row_sets)
        self._set_row_boxes(row_sets, selected)
        with timed(runner.report["client_seconds"], "deform subsample"):
            points, normals, rows = sorted_subsample(selected, "edit", self.subsample_size, n)
            # The program's reader checks the edit first, as it does a whole scan's.
            edit_path = self._subsample_edit(self.selection(points, rows), runner.scratch) if self.rewritten() \
                else self.path
            try:
                edit = _core._read_edit(edit_path, points)
            except ValueError as error:
                message = str(error).splitlines()[0].replace(edit_path, self.path).replace(
                    Path(edit_path).name, Path(self.path).name)  # the reader names the file, or its name alone
                raise TiledError(f"edit: {message} (on the subsample of {len(points)} points)") from None
            selection = self.selection(points, rows)
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

    def rewritten(self):
        """Whether the program's reader needs the edit with its selections as index files of the subsample: it
        reads sphere: and box: specs itself."""
        return any(kind not in ("sphere", "box") for kind, _, _ in self._all_specs())

    def _subsample_edit(self, selection, scratch):
        """The edit JSON with its selections as index files of the subsample's points (`selection`), for the
        program's reader, which reads the rest of it (transforms, settings) and checks it as for a whole scan."""
        description = dict(self.description)
        description.pop("sample", None)

        def indices(name, chosen):
            path = (scratch / f"subsample_{name}.txt").resolve()
            np.savetxt(path, np.flatnonzero(chosen), fmt="%d")
            return [f"indices:{path}"]
        if self.roi is not None:
            description["roi"] = indices("roi", selection != FIXED)
        description["handles"] = [{**handle, "select": indices(f"handle{g}", selection == g)}
                                  if isinstance(handle, dict) else handle
                                  for g, handle in enumerate(description["handles"])]
        path = scratch / "subsample_edit.json"
        path.write_text(json.dumps(description))
        return str(path)

    @property
    def restores(self):
        return int(self.state["detail_steps"]) > 0

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
        return int(self.state["detail_steps"]) + 3

    def collar(self):
        return 1.01 * float(self.state["collar_reach"])

    def halo(self, spacing):
        """A tile's first halo near a handle: the collar's reach (a point's diffused position depends on the
        sample points and on the handle points that near), and the restoration's hops."""
        return self.collar() + (ops.Operation.halo(self, spacing) if self.restores else 0.0)

    def relaxes(self, points, rows):
        """Which points the restoration may move: the region's, and the handles' unless they are exact."""
        selection = self.selection(points, rows)
        return selection == REGION if self.state["exact_handles"] else selection != FIXED

    def needs_certificate(self, points, rows, own):
        """The own points that relax, when the edit restores the details (the selection of all the tile's points,
        which its compute asks for next: nearest: specs find their sample points once)."""
        return self.relaxes(points, rows)[own] & self.restores

    def narrowed(self, points, rows, lo, hi, halo):
        """Near a handle, when restoring: every point within the restoration's halo (`halo` less the collar's
        reach), and beyond it the handle points alone, which the collar needs and the other points do not. Every
        point within that halo then has the handle points within the reach."""
        if not self.restores or not self.near_handles(lo[None], hi[None])[0]:
            return None, halo
        inner = max(halo - self.collar(), 0.0)
        return plan.own_mask(points, lo - inner, hi + inner) | (self.selection(points, rows) >= 0), inner

    def near_handles(self, lo, hi):
        """Whether each box [lo[i], hi[i]] comes within the collar's reach of a handle's spec: only there can a
        point have handle points within the reach (a point's box is [p, p])."""
        return box_reach([spec for group in self.handles for spec in group], lo, hi, self.collar())

    def meets_region(self, lo, hi):
        """Whether each box [lo[i], hi[i]] meets the region's specs (all of them without specs)."""
        return np.ones(len(lo), dtype=bool) if self.roi is None else box_reach(self.roi, lo, hi, 0.0)

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

    def compute(self, points, normals, radius=None, *, rows):
        """The moved points and normals of the points at the scan's `rows`; `radius`, an (n,) array, receives each
        point's 10th-neighbour distance."""
        moved = _core.diffuse_points(points, normals, self.state, selection=self.selection(points, rows),
                                     restore_details=self.restores, neighbor_radius=radius)
        return {name: column for name, column in zip(self.computed_fields(), (*moved.points.T, *moved.normals.T))}
