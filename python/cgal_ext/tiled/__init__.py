"""Tiled runs on Dask distributed for scans larger than one machine's memory: details, normals, curvature,
enhancement and simplification sample points of a binary PLY, binary PCD or LAS file (read by row ranges) or a
Zarr group, written tile by tile to PLY or Zarr.

    from cgal_ext import tiled
    report = tiled.run("details", "scan.ply", "details.zarr", order="cubic")

Each tile reads its box and a halo around it and writes only its own points; the halo is checked to hold every
point those depend on and widened where it did not, so details, normals (up to orientation) and curvature equal the
one-process results. Enhancement is a global solve and is approximated with a margin; the sample points are those
of a subsample, with every point's cluster and the surfels computed over the whole scan (doc/scaling.md).
The command line: `python3 -m cgal_ext.tiled --help`.
"""
import contextlib
import importlib.util
import os
import shutil
import uuid
from pathlib import Path

from .._process import KEPT_MEMORY, tuned_environment
from . import edit, fill, ops, simplify
from .runner import Passes, Run, timed
from .store import TiledError, checked_output, open_source

__all__ = ["TiledError", "run", "subsample", "OPERATIONS"]

OPERATIONS = (*ops.OPERATIONS, "simplify", "edit")


def run(operation, input, output, *, scheduler=None, client=None, workers=None, memory_limit="auto", tiles=None,
        halo=None, scratch=None, threads_per_task=1, connect_timeout=20, progress=False, log=None, **options):
    """Runs one operation over a scan tile by tile on Dask and writes the result whole, or nothing.

    Parameters
    ----------
    operation : {"details", "normals", "curvature", "enhance", "simplify", "edit"}
        What to compute; the output holds the fields of the program's PLY for that subcommand (for "simplify",
        the surfels: position, normal, radius, member_count; for "edit", the moved points and normals).
    input : path
        A binary PLY, binary PCD or LAS file (read by row ranges) or a Zarr group with 1-D arrays x, y, z (and nx,
        ny, nz).
    output : path
        OUT.ply or OUT.zarr; written under a temporary name and renamed when complete. Never the input.
    scheduler : str, optional
        The address of a running Dask scheduler; by default a LocalCluster is started.
    client : distributed.Client, optional
        A client to run on instead (not closed at the end).
    workers : int, optional
        Workers of the LocalCluster (default: one per core), one thread each.
    memory_limit : str or int
        Memory limit per LocalCluster worker ("3GiB", bytes, or "auto").
    tiles : int, optional
        Number of tiles (default: about 262,000 points each, 1,048,576 for "edit", a multiple of the workers, at
        least two per worker).
        Not taken by "simplify", which has no tiles.
    halo : float, optional
        The first halo width (default: from the operation's rings and the scan's spacing); a halo too small for
        a tile is widened by that tile. Not taken by "simplify".
    scratch : path, optional
        A folder every worker can reach for the tiles' intermediate results (default: beside the output).
    threads_per_task : int or None
        The library's threads inside each task (None: all cores). Not taken by "simplify", whose tasks call no
        library function.
    connect_timeout : float
        Seconds to wait for `scheduler` to answer.
    progress : bool or callable
        Dask's progress bar per pass on the terminal; a function is called as progress(pass, tasks done, tasks)
        instead.
    log : callable, optional
        Receives one-line messages (the plan, the dashboard's address).
    **options
        The library function's options: details (`k`, `order`, `lam`, `mu`, `weights`, `color_by`), curvature
        (`k`, `fitting`), normals (`k`), enhance (`s`, `k`, `order`, `lam`, `mu`, `weights`, `margin` in
        neighbourhood radii), simplify (`target_count`, `mode_threshold`, `k`; `subsample`, the points the
        client clusters, 1,000,000 by default; `clusters`, a PLY or Zarr path for the scan with each point's
        `ssp_index` and its cluster's colour, as `point-detail simplify --clusters` writes it), edit (`edit`, the
        path of an edit JSON as `point-detail edit --edit` reads it, its regions as sphere: and box: specs,
        index files of the scan's rows (`indices:FILE`, relative to the JSON), boolean arrays of the scan's
        Zarr group (`mask:ARRAY`) or indices of a sample of points the JSON names (`nearest:FILE`, with
        "sample": {"points": FILE, "reach": DISTANCE}: a point is selected when its nearest sample point,
        within the reach, is listed); `subsample`, the points the client deforms, 1,000,000 by default;
        `upsample`, True to fill what the edit stretched as `point-detail edit --upsample` does, in tiles after
        the edit: the new points follow the scan's, in the order of their coordinates, with `inserted` = 1).

    Returns
    -------
    dict
        The run's report: tiles, halos, widened tiles, orientation, timings per pass.

    Raises
    ------
    TiledError
        A ValueError naming what stopped the run: bad input or options, a tile that cannot be read, a cluster
        that does not answer. Nothing is written then.
    """
    log = log or (lambda message: None)
    source = open_source(input)
    output = checked_output(output, source)
    upsample = False
    if operation == "simplify":
        if tiles is not None or halo is not None or threads_per_task != 1:
            raise TiledError("simplify: has no tiles, no halo and no library call in its tasks; tiles, halo and "
                             "threads_per_task are not taken")
        op = simplify.options(source, output, **options)
    elif operation == "edit":
        if "edit" not in options:
            raise TiledError("edit: needs the edit JSON (edit=PATH, --edit PATH)")
        upsample = options.pop("upsample", False)
        if not isinstance(upsample, bool):
            raise TiledError(f"edit: upsample must be True or False, not {upsample!r}")
        op = edit.Edit(**options)
    else:
        op = ops.operation(operation, **options)
    scratch_root = Path(scratch) if scratch else output.parent
    folder = scratch_root / f".{output.name}.tiles-{uuid.uuid4().hex[:8]}"
    try:
        with _client(client, scheduler, workers, memory_limit, connect_timeout, log) as client:
            folder.mkdir(parents=True)
            if operation == "simplify":
                report = simplify.simplify(Passes(client, progress, log, {"operation": operation}), source, output,
                                           folder, **op)
            else:
                edited = folder / "edited.zarr" if upsample else output
                runner = Run(client, source, edited, op, tiles, halo, folder, threads_per_task, progress, log)
                if operation == "edit":
                    op.prepare(runner, source)
                report = runner.execute()
                if upsample:
                    (folder / "fill").mkdir()
                    report["fill"] = fill.fill(runner, edited, source, output, folder / "fill", tiles,
                                               threads_per_task=threads_per_task)
            with timed(report["client_seconds"], "remove scratch"):
                shutil.rmtree(folder)
            return report
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def subsample(input, size=simplify.SUBSAMPLE, *, client=None, workers=None, memory_limit="auto", connect_timeout=20,
              progress=False, log=None):
    """The even subsample of about `size` points of a scan that the tiled edit deforms (`run("edit", ...,
    subsample=size)`), read in one pass on Dask: its points and unit normals, sorted, as arrays. The studio opens it
    in place of a scan too large to edit whole. `input` and the other parameters are run()'s; the scan needs its
    normals."""
    log = log or (lambda message: None)
    source = open_source(input)
    if not simplify._whole(size) or size < 1:
        raise TiledError(f"subsample: size must be a whole number of points >= 1, not {size!r}")
    with _client(client, None, workers, memory_limit, connect_timeout, log) as client:
        passes = Passes(client, progress, log, {"operation": "subsample"})
        selected = simplify.subsample_pass(passes, source, int(size), "the subsample carries them")
        points, normals, _ = simplify.sorted_subsample(selected, "subsample", size, source.count)
        return points, normals


def worker_environment():
    """The environment Dask sets for the LocalCluster's worker processes before they start, without the
    MALLOC_TRIM_THRESHOLD_ it adds, and with glibc's malloc on huge pages, as point-detail runs. A trim threshold
    turns off glibc's adaptive mmap threshold: each of a tile's arrays would then be a fresh mapping, faulted in
    page by page (doc/scaling.md, "Worker processes"). The workers inherit the rest of this process's environment,
    a trim threshold set in it included, but not the malloc that keeps what it frees of a studio's process
    (KEPT_MEMORY): a worker's memory is Dask's to count and give back. Asked once distributed is imported (its
    defaults join Dask's configuration then)."""
    import dask
    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    own = os.environ.get("GLIBC_TUNABLES", "")
    tunables = ":".join(t for t in own.split(":") if t and t not in KEPT_MEMORY)
    if tunables != own:
        environ["GLIBC_TUNABLES"] = tunables
    environ.update(tuned_environment({**os.environ, **environ}))
    return environ


@contextlib.contextmanager
def _client(client, scheduler, workers, memory_limit, timeout, log):
    """`client` as it is, or a client of `scheduler` or of a new LocalCluster, closed with its cluster at the end."""
    if client is not None:
        yield client
        return
    client, cluster = _connect(scheduler, workers, memory_limit, timeout, log)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _connect(scheduler, workers, memory_limit, timeout, log):
    import dask
    from distributed import Client, LocalCluster
    if scheduler:
        try:
            client = Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError) as error:
            raise TiledError(f"the Dask scheduler at {scheduler} does not answer ({error})") from None
        log(f"running on the scheduler at {scheduler}; dashboard: {client.dashboard_link}")
        return client, None
    workers = workers or os.cpu_count() or 1
    dashboard = ":0" if importlib.util.find_spec("bokeh") else None  # Dask's dashboard needs bokeh
    with dask.config.set({"distributed.nanny.pre-spawn-environ": worker_environment()}):
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, memory_limit=memory_limit,
                               dashboard_address=dashboard, silence_logs=40)
    client = Client(cluster)
    log(f"LocalCluster of {workers} worker(s), memory limit {memory_limit} each; dashboard: "
        + (client.dashboard_link if dashboard else "none (install bokeh for Dask's dashboard)"))
    return client, cluster
