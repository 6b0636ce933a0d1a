"""The passes of a tiled run on Dask distributed: scan, bucket, tiles, orientation, colours, write.

The client holds only a sample of the scan, the tiles' boxes and each task's small summary; the points travel
from the input file to the tasks and from the tasks to the output through a scratch folder that every worker can
reach. See doc/scaling.md.
"""
import ctypes
import dataclasses
import os
import shutil
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
from scipy.spatial import cKDTree

from .. import _core, threads
from . import plan, store
from .store import TiledError

CHUNK_ROWS = 1 << 20
SAMPLE_PER_TILE = 4000
SPACING_QUERIES = 20_000


# ---- tasks (run on the workers; arguments and results are small) -------------------------------------------------

_allocator_checked = False


def keep_freed_memory():
    """Once per worker process: when it started with a malloc trim threshold (Dask sets one for workers the tiled
    runs did not start) and no mmap threshold, fixes glibc's thresholds so that a tile's arrays are reused instead
    of given back when freed and faulted in again page by page (doc/scaling.md, "Worker processes")."""
    global _allocator_checked
    if _allocator_checked:
        return
    _allocator_checked = True
    if "MALLOC_TRIM_THRESHOLD_" in os.environ and "MALLOC_MMAP_THRESHOLD_" not in os.environ:
        m_trim_threshold, m_mmap_threshold = -1, -3  # glibc's <malloc.h>
        try:
            libc = ctypes.CDLL(None)
            libc.mallopt(m_mmap_threshold, 32 << 20)  # glibc's largest
            libc.mallopt(m_trim_threshold, 256 << 20)
        except (OSError, AttributeError):  # not glibc
            pass


def task(function, *args, **kwargs):
    """Runs a pass's `function` on a worker whose allocator keeps freed memory."""
    keep_freed_memory()
    return function(*args, **kwargs)


def read_rows(source, begin, end, coordinates_only=False):
    """The points and normals of rows [begin, end) (the points alone with `coordinates_only`), or a TiledError
    naming the rows."""
    try:
        return source.coordinates(begin, end) if coordinates_only else source.points_and_normals(begin, end)
    except Exception as error:
        raise TiledError(f"rows {begin}..{end - 1} of {source.path} cannot be read: {error}") from None


def first_invalid_row(valid, begin):
    """The number of the first row whose `valid` is False (rows counted from `begin`), or None."""
    return None if valid.all() else begin + int(np.argmin(valid))


def scan_rows(begin, end, source, stride):
    """Bounding box, first non-finite row and every stride-th point of rows [begin, end)."""
    points = read_rows(source, begin, end, coordinates_only=True)
    return {"lo": points.min(axis=0), "hi": points.max(axis=0),
            "bad_row": first_invalid_row(np.isfinite(points).all(axis=1), begin),
            "sample": points[(-begin) % stride::stride].copy()}


def bucket_rows(begin, end, source, tiling, halos, folder):
    """Copies, for every tile, the rows of [begin, end) its read box (its box grown by `halos[tile]`) holds (row
    number, point, normal) to `folder/c{begin}_t{tile}.npy`, so that the tile tasks read small files instead of the
    whole scan."""
    points, normals = read_rows(source, begin, end)
    read_sets = tiling.read_sets(points, halos)
    counts = {}
    for tile, rows in read_sets.items():
        np.save(folder / f"c{begin}_t{tile}.npy", _bucket(begin, rows, points, normals))
        counts[tile] = len(rows)
    return counts


def _bucket(begin, rows, points, normals):
    """Row numbers begin + rows (exact in float64 below 2^53), and the points and normals at `rows` (with the
    columns a source carries after them), side by side."""
    table = np.empty((len(rows), 4 if normals is None else 4 + normals.shape[1]))
    table[:, 0] = begin + rows
    # Gathered straight into the table's columns ("clip": the rows are valid, and it spares a buffered copy).
    np.take(points, rows, axis=0, out=table[:, 1:4], mode="clip")
    if normals is not None:
        np.take(normals, rows, axis=0, out=table[:, 4:], mode="clip")
    return table


def _read_tile(source, tile, lo, hi, halo, bucket_folder, bucket_halo, chunk_starts):
    """Global rows, points and normals (or None; with the columns the source carries after them) inside the tile's
    box grown by `halo`."""
    if halo <= bucket_halo:
        parts = [np.load(path) for path in (bucket_folder / f"c{b}_t{tile}.npy" for b in chunk_starts)
                 if path.exists()]
    else:  # widened beyond the buckets: scan the source for the larger box
        parts = []
        for begin in range(0, source.count, CHUNK_ROWS):
            points, normals = source.points_and_normals(begin, min(source.count, begin + CHUNK_ROWS))
            inside = np.flatnonzero(plan.own_mask(points, lo - halo, hi + halo))
            parts.append(_bucket(begin, inside, points, normals))
    width = 4 + source.carried_columns if source.has_normals else 4
    table = np.concatenate(parts) if parts else np.empty((0, width))
    return (table[:, 0].astype(np.int64), np.ascontiguousarray(table[:, 1:4]),
            np.ascontiguousarray(table[:, 4:]) if source.has_normals else None)


def result_columns(operation, estimate_normals):
    """The columns of a tile's result table: its own points' rows (in the file's order), the computed fields and,
    when the tiles estimate them, the normals."""
    return ["row", *operation.computed_fields(), *(("nx", "ny", "nz") if estimate_normals else ())]


def _load_table(scratch, tile):
    """A tile's result table, memory-mapped: one column after the other, so a column or a range of rows is read
    without the rest."""
    return np.load(scratch / f"tile_{tile}" / "table.npy", mmap_mode="r")


@contextmanager
def timed(seconds, step):
    """Adds the seconds the block takes to `seconds[step]` (when it completes)."""
    started = time.perf_counter()
    yield
    seconds[step] = seconds.get(step, 0.0) + time.perf_counter() - started


class _Stopwatch:
    """Seconds spent per step of a task, summed over its repetitions."""

    def __init__(self):
        self.seconds, self._last = {}, time.perf_counter()

    def lap(self, step):
        now = time.perf_counter()
        self.seconds[step] = self.seconds.get(step, 0.0) + now - self._last
        self._last = now


@dataclasses.dataclass(frozen=True)
class TileJob:
    """One tile task: the tile, its first halo, the halo its buckets were cut with, the k-th-neighbour distance it
    may assume its neighbours' points have (`reach`), and the run's input, operation and settings."""
    tile: int
    halo: float
    bucket_halo: float
    reach: float
    source: Any
    operation: Any
    estimate_normals: bool
    tiling: Any
    chunk_starts: List[int]
    scratch: Path
    diagonal: float
    spacing: float
    threads_per_task: Optional[int]


@dataclasses.dataclass
class TileSummary:
    """What a tile task returns: its own and read points, the halo it ended with and the attempts before, the
    largest k-th-neighbour distance of its own points (`kth`) and the reach it assumed, the fraction of the points
    read whose k nearest the certificate searched, where each chunk of the file starts in its table (`bounds`),
    the seconds of each step; and, as the operation needs them, the bound and depth of the points it did not
    search (`interior`), its highest own point's height and whether its normal points up (`top`), and its largest
    magnitude (`largest`)."""
    tile: int
    own: int
    read: int
    halo: float
    attempts: List[Dict[str, Any]]
    kth: float
    reach: float
    searched: float
    bounds: np.ndarray
    seconds: Dict[str, float] = dataclasses.field(default_factory=dict)
    interior: Optional[Tuple[float, float]] = None
    top: Optional[Tuple[float, bool]] = None
    largest: Optional[float] = None

    def for_report(self):
        """The summary as the run's report keeps it: everything but `bounds`."""
        return {key: value for key, value in dataclasses.asdict(self).items() if key != "bounds"}


def run_tile(job):
    """Computes one tile (a TileJob): reads its box and halo, widens the halo until every own point is certified
    (or the halo spans the scan: then the tile read every point), and saves the own points' result table under
    `scratch/tile_{tile}`. Returns its TileSummary.

    An operation that measures its neighbourhoods' radii while computing (given normals) computes first and is
    certified with them (plan.certify_with_radius); the others are certified before they compute."""
    tile, halo, reach, source, operation = job.tile, job.halo, job.reach, job.source, job.operation
    estimate_normals, chunk_starts, scratch = job.estimate_normals, job.chunk_starts, job.scratch
    with threads(job.threads_per_task):
        lo, hi = job.tiling.lo[tile], job.tiling.hi[tile]
        k = operation.neighbors(estimate_normals)
        compute_first = operation.measures_radius and not estimate_normals
        attempts = []
        watch = _Stopwatch()
        while True:
            try:
                rows, points, normals = _read_tile(source, tile, lo, hi, halo, scratch / "buckets", job.bucket_halo,
                                                   chunk_starts)
                watch.lap("read")
            except Exception as error:
                raise TiledError(f"tile {tile} (box {_box_text(lo, hi)}) cannot be read from {source.path}: "
                                 f"{error}") from None
            keep, exact_halo = operation.narrowed(points, rows, lo, hi, halo)
            if keep is not None:
                rows, points = rows[keep], points[keep]
                normals = None if normals is None else normals[keep]
            own = plan.own_mask(points, lo, hi)
            row_arguments = {"rows": rows} if operation.takes_rows else {}
            if not own.any():
                watch.lap("neighbours")
                return TileSummary(tile, 0, len(rows), halo, attempts, 0.0, reach, 0.0,
                                   np.zeros(len(chunk_starts) + 1, dtype=np.int64), watch.seconds)
            border = plan.border_distance(points, lo - exact_halo, hi + exact_halo)
            neighborhoods = interior = values = None
            needs_certificate = operation.needs_certificate(points, rows, own)
            if not needs_certificate.any():
                kth, tile_reach, searched = 0.0, reach, 0.0
                certified = np.ones(len(needs_certificate), dtype=bool)
            elif compute_first:
                radius = np.empty(len(points))
                values = operation.compute(points, normals, radius, **row_arguments)
                watch.lap("compute")
                kth = float(radius[own].max())
                tile_reach = max(reach, 1.25 * kth)
                certified, searched = plan.certify_with_radius(points, radius, border, own, k, tile_reach,
                                                               operation.rings(), 1e-12 * float(np.abs(points).max()))
            else:
                if operation.banded:
                    neighborhoods, interior = plan.banded_neighborhoods(points, k, border, reach, operation.rings(),
                                                                        halo, job.spacing)
                else:
                    neighborhoods = plan.Neighborhoods(points, k, border)
                kth = float(neighborhoods.kth_distance(operation.own_neighbors())[own].max())
                tile_reach = max(reach, 1.25 * kth)
                certified = operation.certify(neighborhoods, own, tile_reach, estimate_normals)
                searched = float(neighborhoods.searched.mean())
            certified |= ~needs_certificate
            needed = operation.required_halo(neighborhoods, own, points)
            watch.lap("neighbours")
            if (certified.all() and halo >= needed) or halo > job.diagonal:
                break
            attempts.append({"halo": halo, "uncertified": int((~certified).sum()), "needed": needed})
            halo = max(2 * halo, 1.1 * needed, operation.halo(kth))
        if values is None:
            if estimate_normals:
                normals = operation.oriented_normals(points)
            values = operation.compute(points, normals, **row_arguments)
            watch.lap("compute")
        folder = scratch / f"tile_{tile}"
        partial = scratch / f".tile_{tile}.{uuid.uuid4().hex[:8]}"
        partial.mkdir()
        own_rows = np.flatnonzero(own)
        own_rows = own_rows[np.argsort(rows[own_rows])]  # the file's order: each chunk's rows are one range
        table = np.empty((len(own_rows), len(result_columns(operation, estimate_normals))), order="F")
        table[:, 0] = rows[own_rows]
        for column, name in enumerate(operation.computed_fields(), start=1):
            table[:, column] = np.asarray(values[name])[own_rows]
        if estimate_normals:
            table[:, -3:] = normals[own_rows]
        np.save(partial / "table.npy", table)
        summary = TileSummary(tile, int(own.sum()), len(rows), halo, attempts, kth, tile_reach, searched,
                              np.searchsorted(rows[own_rows], [*chunk_starts, source.count]).astype(np.int64),
                              interior=interior)
        if estimate_normals:
            # Halo points whose normal is the whole scan's up to its sign: the votes on the tiles' orientations.
            shared = ~own & neighborhoods.exact(operation.normal_neighbors())
            shared = np.flatnonzero(shared)
            shared = shared[np.argsort(rows[shared])]
            np.save(partial / "halo_rows.npy", rows[shared])
            np.save(partial / "halo_normals.npy", normals[shared])
            top = int(np.argmax(np.where(own, points[:, 2], -np.inf)))
            summary.top = (float(points[top, 2]), bool(normals[top, 2] >= 0))
        if operation.color_field:
            summary.largest = float(np.abs(values[operation.color_field][own_rows]).max())
        shutil.rmtree(folder, ignore_errors=True)  # a rerun of the task (its worker died) replaces the old result
        os.replace(partial, folder)
        watch.lap("save")
        summary.seconds = watch.seconds
        return summary


def orientation_votes(scratch, tile, neighbours):
    """{neighbour: agreeing minus disagreeing normals} on the tile's halo points the neighbour owns."""
    halo_rows = np.load(scratch / f"tile_{tile}" / "halo_rows.npy")
    halo_normals = np.load(scratch / f"tile_{tile}" / "halo_normals.npy")
    votes = {}
    for other in neighbours:
        table = _load_table(scratch, other)
        rows = np.asarray(table[:, 0])
        at = np.searchsorted(rows, halo_rows)
        at = np.minimum(at, len(rows) - 1)
        shared = rows[at] == halo_rows
        if shared.any():
            theirs = np.asarray(table[:, -3:])[at[shared]]
            dots = np.einsum("ij,ij->i", halo_normals[shared], theirs)
            votes[other] = int((dots > 0).sum()) - int((dots < 0).sum())
    return votes


def _digit_counts(bits, prefix, shift):
    """The 16-bit digits at `shift` of the bit patterns under `prefix` (the bits above the digit), and how many of
    each: only the digits that occur, a few hundred where a dense histogram would send 65,536 counts a tile."""
    if shift < 48:
        bits = bits[(bits >> (shift + 16)) == prefix]
    counts = np.bincount((bits >> shift) & 0xFFFF, minlength=1 << 16)
    digits = np.flatnonzero(counts)
    return digits, counts[digits]


def magnitude_histogram(scratch, tile, column, largest, every, prefix, shift):
    """The digit counts (_digit_counts) of the magnitudes in the result table's `column`, as ordered bit patterns,
    that the colour map ranks: all when `every`, else those above 1e-12 of the largest. With `every` None (the
    first pass, which does not know yet which it ranks): how many are above, and the counts of both."""
    magnitude = np.abs(np.asarray(_load_table(scratch, tile)[:, column]))
    above = magnitude[magnitude > 1e-12 * largest]
    if every is None:
        return (len(above), _digit_counts(magnitude.view(np.int64), prefix, shift),
                _digit_counts(above.view(np.int64), prefix, shift))
    return _digit_counts((magnitude if every else above).view(np.int64), prefix, shift)


def write_rows(begin, end, pieces, source, sink, operation, estimate_normals, scratch, flips, color_limit):
    """Assembles rows [begin, end) of the output from the tiles' results, rows [a, b) of the table of each
    (tile, a, b) of `pieces`, and writes them to the sink."""
    count = end - begin
    columns = {name: np.empty(count, dtype=kind) for name, kind in operation.fields()}
    points, normals = source.points_and_normals(begin, end)
    normals = None if estimate_normals else normals
    for axis, name in enumerate("xyz"):
        columns[name][:] = points[:, axis]
    if normals is not None:
        for axis, name in enumerate(("nx", "ny", "nz")):
            columns[name][:] = normals[:, axis]
    covered = np.zeros(count, dtype=np.int64)
    # The table's columns after the row, and whether each flips with its tile's normals.
    fields = [(column, name, name in operation.sign_fields or name in ("nx", "ny", "nz"))
              for column, name in enumerate(result_columns(operation, estimate_normals)[1:], start=1)]
    for tile, a, b in pieces:
        table = np.asarray(_load_table(scratch, tile)[a:b])
        at = table[:, 0].astype(np.int64) - begin
        covered[at] += 1
        sign = -1.0 if flips.get(tile) else 1.0
        for column, name, flipped in fields:
            columns[name][at] = sign * table[:, column] if flipped else table[:, column]
    if not (covered == 1).all():
        row = begin + int(np.argmax(covered != 1))
        raise TiledError(f"row {row} was computed by {int(covered[row - begin])} tiles, not exactly one")
    if operation.color_field:
        colors = _core.diverging_colors(columns[operation.color_field], limit=color_limit)
        for axis, name in enumerate(("red", "green", "blue")):
            columns[name][:] = colors[:, axis]
    sink.write(begin, columns)
    return count


def _box_text(lo, hi):
    return "[" + ", ".join(f"{a:.6g}..{b:.6g}" for a, b in zip(lo, hi)) + "]"


# ---- the client's side ------------------------------------------------------------------------------------------

class Passes:
    """Maps a pass's tasks over items on a Dask client (a progress bar per pass when `progress` is True; when it
    is a function, progress(pass, tasks done, tasks) as each task ends), timing each pass in `report["seconds"]`
    and the client's own steps in `report["client_seconds"]`."""

    def __init__(self, client, progress, log, report):
        self.client, self.progress, self.log, self.report = client, progress, log, report
        report.setdefault("seconds", {})
        report.setdefault("client_seconds", {})

    def _gather(self, futures, what):
        with timed(self.report["seconds"], what):
            if callable(self.progress):
                from distributed import as_completed
                self.progress(what, 0, len(futures))
                for done, _ in enumerate(as_completed(futures), start=1):
                    self.progress(what, done, len(futures))
            elif self.progress:
                from distributed import progress
                self.log(f"{what}:")
                progress(futures)
                print(flush=True)
            try:
                return self.client.gather(futures)
            except BaseException as error:
                self.client.cancel(futures)
                if isinstance(error, (TiledError, KeyboardInterrupt)):
                    raise
                raise TiledError(f"{what} failed: {type(error).__name__}: {error}") from None

    def map(self, function, items, *args, what, **kwargs):
        futures = [self.client.submit(task, function, *item, *args, key=f"{function.__name__}-{uuid.uuid4().hex}",
                                      **kwargs) for item in items]
        return self._gather(futures, what)

    @staticmethod
    def refuse_invalid_rows(source, results):
        """A TiledError naming the first row a pass found invalid: in its results' "bad_row" (a coordinate) or
        "bad_normal"."""
        for key, problem in (("bad_row", "a non-finite coordinate (NaN or infinity)"),
                             ("bad_normal", "a normal that is zero or not finite")):
            rows = [result[key] for result in results if result.get(key) is not None]
            if rows:
                raise TiledError(f"{source.path}: point {min(rows)} has {problem}")

    def client_step(self, step):
        return timed(self.report["client_seconds"], step)

    def tile_count_and_stride(self, n, tiles, per_tile):
        """The tiles of a scan of n points (`tiles`, or a multiple of the workers, so that none is left alone with
        the last tile, of about `per_tile` points each) and the stride of the plan's sample of its rows."""
        workers = max(1, len(self.client.scheduler_info()["workers"]))
        tile_count = tiles or workers * max(2, -(-n // (per_tile * workers)))
        return tile_count, max(1, n // max(200_000, SAMPLE_PER_TILE * tile_count))

    @staticmethod
    def row_ranges(n):
        """The passes' row ranges [begin, end) of a scan of n points."""
        return [(b, min(n, b + CHUNK_ROWS)) for b in range(0, n, CHUNK_ROWS)]

    @staticmethod
    def open_sink(path, count, fields):
        """The output at `path`, chunked as the row ranges: no two tasks write into one chunk of a Zarr array."""
        return store.open_sink(path, count, fields, CHUNK_ROWS)

    def written_small(self, path, fields, columns):
        """An output the client holds, written under its temporary name: the caller commits or discards it."""
        with self.client_step("write"):
            sink = self.open_sink(path, len(next(iter(columns.values()))), fields)
            sink.create()
            try:
                sink.write(0, columns)
            except BaseException:
                sink.discard()
                raise
        return sink


class Run(Passes):
    """One tiled run on a Dask client; `execute()` returns its report."""

    def __init__(self, client, source, sink_path, operation, tiles, halo, scratch, threads_per_task, progress, log):
        self.source, self.operation = source, operation
        self.sink_path, self.tiles, self.halo = Path(sink_path), tiles, halo
        self.threads_per_task = threads_per_task
        self.scratch = scratch
        self.estimate_normals = operation.estimates_normals(source.has_normals)
        super().__init__(client, progress, log,
                         {"operation": operation.name, "points": source.count, "exact": operation.exact,
                          "normals": "estimated" if self.estimate_normals else "given"})

    def execute(self):
        n = self.source.count
        if n == 0:
            raise TiledError(f"{self.source.path}: the scan has no points")
        ranges = self.row_ranges(n)
        starts = [begin for begin, _ in ranges]
        tile_count, stride = self.tile_count_and_stride(n, self.tiles, self.operation.points_per_tile)

        scans = self.map(scan_rows, ranges, self.source, stride, what="scan")
        self.refuse_invalid_rows(self.source, scans)
        with timed(self.report["client_seconds"], "plan"):
            sample = np.concatenate([s["sample"] for s in scans])
            lo = np.min([s["lo"] for s in scans], axis=0)
            hi = np.max([s["hi"] for s in scans], axis=0)
            tile_count = min(tile_count, max(1, len(sample) // 8))
            tiling = plan.Tiling(sample, tile_count)
            k = self.operation.neighbors(self.estimate_normals)
            spacing = self._spacing(sample, stride, k)
            halo = self.halo if self.halo is not None else self.operation.halo(spacing)
            halos = (np.full(tiling.count, float(halo)) if self.halo is not None else
                     self.operation.tile_halos(*tiling.boxes(), halo))
            reach = 2.0 * spacing
        self.report.update(tiles=tiling.count, chunks=len(ranges), initial_halo=halo, spacing=spacing,
                           tiles_with_the_halo=int(np.count_nonzero(halos >= halo)),
                           tiles_with_a_halo=int(np.count_nonzero(halos > 0)),
                           diagonal=float(np.linalg.norm(hi - lo)))
        self.log(f"{n} points, {tiling.count} tiles, halo {halo:.4g} (k-th neighbour distance about {spacing:.4g})"
                 + ("" if (halos >= halo).all() else f" for {np.count_nonzero(halos >= halo)} of them"))

        (self.scratch / "buckets").mkdir(parents=True)
        self.map(bucket_rows, ranges, self.source, tiling, halos, self.scratch / "buckets", what="bucket")
        all_tiles = list(range(tiling.count))
        summaries = self._run_tiles(tiling, halos, starts, {t: (halos[t], reach) for t in all_tiles})
        summaries = self._verify_reach(summaries, tiling, halos, starts)
        with ThreadPoolExecutor(1) as remover:  # tens of thousands of files: removed while the next passes run
            removed = remover.submit(shutil.rmtree, self.scratch / "buckets")
            flips = self._orient(summaries, tiling) if self.estimate_normals else {}
            limit = self._color_limit(summaries) if self.operation.color_field else None
            with timed(self.report["client_seconds"], "remove buckets"):
                removed.result()

        with timed(self.report["client_seconds"], "create output"):
            sink = self.open_sink(self.sink_path, n, self.operation.fields())
            sink.create()
        try:
            bounds = np.stack([summaries[t].bounds for t in all_tiles])
            pieces = [[(t, int(bounds[t, c]), int(bounds[t, c + 1]))
                       for t in np.flatnonzero(bounds[:, c + 1] > bounds[:, c])] for c in range(len(ranges))]
            self.map(write_rows, [(*r, p) for r, p in zip(ranges, pieces)], self.source, sink, self.operation,
                      self.estimate_normals, self.scratch, flips, color_limit=limit, what="write")
            with timed(self.report["client_seconds"], "commit output"):
                sink.commit()
        except BaseException:
            sink.discard()
            raise
        widened = [s for s in summaries.values() if s.attempts]
        self.report.update(widened_tiles=len(widened), flipped_tiles=sum(1 for f in flips.values() if f),
                           largest_halo=max(s.halo for s in summaries.values()),
                           read_points=int(sum(s.read for s in summaries.values())),
                           color_limit=limit,
                           tile_summaries=[summaries[t].for_report() for t in all_tiles],
                           tile_seconds={step: sum(s.seconds.get(step, 0.0) for s in summaries.values())
                                         for step in ("read", "neighbours", "compute", "save")},
                           tile_boxes=[[float(v) if np.isfinite(v) else None for v in (*tiling.lo[t], *tiling.hi[t])]
                                       for t in all_tiles])
        return self.report

    @staticmethod
    def _spacing(sample, stride, k):
        """The scan's typical (90th percentile) k-th-neighbour distance, from the sample: on a surface,
        distances in a sample of one point in `stride` are sqrt(stride) times the scan's."""
        count = min(k + 1, len(sample))
        queries = sample[::max(1, len(sample) // SPACING_QUERIES)]  # a percentile needs no more
        distances, _ = cKDTree(sample).query(queries, count)
        return float(np.percentile(distances[:, -1], 90)) / np.sqrt(stride)

    def _run_tiles(self, tiling, bucket_halos, starts, tiles):
        """Runs the tiles {tile: (first halo, assumed reach)}; each tile's buckets were cut with its
        `bucket_halos[tile]`."""
        jobs = [(TileJob(tile=t, halo=float(halo), bucket_halo=float(bucket_halos[t]), reach=reach, source=self.source,
                         operation=self.operation, estimate_normals=self.estimate_normals, tiling=tiling,
                         chunk_starts=starts, scratch=self.scratch, diagonal=self.report["diagonal"],
                         spacing=self.report["spacing"], threads_per_task=self.threads_per_task),)
                for t, (halo, reach) in tiles.items()]
        return {s.tile: s for s in self.map(run_tile, jobs, what="tiles")}

    def _verify_reach(self, summaries, tiling, halos, starts):
        """Reruns the tiles whose certification assumed a k-th-neighbour distance smaller than a neighbouring
        tile measured (symmetrised-graph operations only)."""
        if not self.operation.symmetric:
            return summaries
        lo, hi = tiling.boxes()
        for _ in range(8):
            rerun = {}
            kth = np.array([summaries[u].kth for u in range(tiling.count)])
            # A tile's points not searched (banded_neighborhoods): their bound, and the box they lie in.
            bound, depth = np.array([summaries[u].interior or (0.0, 0.0) for u in range(tiling.count)]).T
            inner_lo, inner_hi = lo + depth[:, None], hi - depth[:, None]
            for t, s in summaries.items():
                read_lo, read_hi = plan.read_box(lo[t], hi[t], s.halo)
                reaching = (kth >= s.reach) & (plan.box_distances(read_lo, read_hi, lo, hi) <= kth)
                inner = (bound >= s.reach) & np.all(inner_lo <= inner_hi, axis=1)
                inner &= plan.box_distances(read_lo, read_hi, inner_lo, inner_hi) < bound
                inner[t] = False  # its own points lie inside its read box
                if reaching.any() or inner.any():
                    rerun[t] = 1.25 * float(max(kth[reaching].max(initial=0.0), bound[inner].max(initial=0.0)))
            if not rerun:
                return summaries
            self.log(f"{len(rerun)} tile(s) rerun with the k-th-neighbour distance their neighbours measured")
            again = self._run_tiles(tiling, halos, starts, {t: (summaries[t].halo, r) for t, r in rerun.items()})
            for t, s in again.items():
                s.attempts = summaries[t].attempts + [{"reach": summaries[t].reach}] + s.attempts
                summaries[t] = s
        raise TiledError("the tiles' k-th-neighbour distances did not settle after 8 reruns")

    def _orient(self, summaries, tiling):
        """Each tile's normals flipped or not: agreed with its neighbours on the points they share, propagated
        over a maximum spanning tree of the tile graph, and each component turned so that its highest point's
        normal points up (+z), as the one-process orientation does."""
        lo, hi = tiling.boxes()
        live = [t for t, s in summaries.items() if s.own > 0]
        items = []
        for t in live:
            read_lo, read_hi = plan.read_box(lo[t], hi[t], summaries[t].halo)
            meets = plan.box_distances(read_lo, read_hi, lo[live], hi[live]) == 0
            items.append((self.scratch, t, [u for u, m in zip(live, meets) if m and u != t]))
        votes = self.map(orientation_votes, items, what="orient")
        weight = {}
        for (_, t, _), vote in zip(items, votes):
            for u, v in vote.items():
                key = (min(t, u), max(t, u))
                weight[key] = weight.get(key, 0) + v
        parent = {t: t for t in live}

        def find(t):
            while parent[t] != t:
                parent[t] = parent[parent[t]]
                t = parent[t]
            return t

        adjacency = {t: [] for t in live}
        for (t, u), v in sorted(weight.items(), key=lambda item: -abs(item[1])):
            if v != 0 and find(t) != find(u):
                parent[find(t)] = find(u)
                adjacency[t].append((u, v < 0))
                adjacency[u].append((t, v < 0))
        flips, disagreements = {}, []
        for seed in live:
            if seed in flips:
                continue
            flips[seed], component, queue = False, [seed], [seed]
            while queue:
                t = queue.pop()
                for u, opposite in adjacency[t]:
                    if u not in flips:
                        flips[u] = flips[t] != opposite
                        component.append(u)
                        queue.append(u)
            top = max(component, key=lambda t: summaries[t].top[0])
            if summaries[top].top[1] == flips[top]:  # the highest normal would point down
                for t in component:
                    flips[t] = not flips[t]
        for (t, u), v in weight.items():
            if v != 0 and (flips[t] != flips[u]) != (v < 0):
                disagreements.append((t, u))
        self.report["orientation_conflicts"] = len(disagreements)
        return flips

    def _color_limit(self, summaries):
        """The colour map's saturation over the whole scan, exactly as the one-process map computes it: the
        98th percentile of the magnitudes, found digit by digit from the tiles' histograms (four passes)."""
        live = [t for t, s in summaries.items() if s.own > 0]
        largest = max(summaries[t].largest for t in live)
        n = sum(summaries[t].own for t in live)
        column = result_columns(self.operation, self.estimate_normals).index(self.operation.color_field)
        tiles = [(self.scratch, t) for t in live]
        first = self.map(magnitude_histogram, tiles, column, largest, None, 0, 48, what="colours")
        ranked = sum(count for count, _, _ in first)
        every = 2 * ranked > n
        total = n if every else ranked
        if total == 0:
            return 1.0
        rank = min(total - 1, int(0.98 * (total - 1)))
        prefix = 0
        for shift in (48, 32, 16, 0):
            if shift == 48:  # the first pass counted the top digits of both
                histograms = [both[1] if every else both[2] for both in first]
            else:
                histograms = self.map(magnitude_histogram, tiles, column, largest, every, prefix, shift,
                                       what="colours")
            counts = np.zeros(1 << 16, dtype=np.int64)
            for digits, tile_counts in histograms:
                np.add.at(counts, digits, tile_counts)
            cumulative = np.cumsum(counts)
            digit = int(np.searchsorted(cumulative, rank, side="right"))
            rank -= int(cumulative[digit - 1]) if digit else 0
            prefix = (prefix << 16) | digit
        limit = float(np.array([prefix], dtype=np.int64).view(np.float64)[0])
        return limit if limit > 0 else 1.0
