"""python3 -m cgal_ext.tiled details|normals|curvature|enhance|simplify|edit INPUT -o OUTPUT [options]: a tiled
run on Dask."""
import argparse
import json
import sys

from . import TiledError, run

S = argparse.SUPPRESS  # options left out are left to the library's defaults


def parser():
    main = argparse.ArgumentParser(
        prog="python3 -m cgal_ext.tiled",
        description="Details, normals, curvature, enhancement, sample points or an edit of a scan larger than memory, "
                    "tile by tile on Dask. "
                    "The input is a binary PLY, binary PCD or LAS file (read by row ranges) or a Zarr group; the "
                    "output OUT.ply or OUT.zarr holds the fields of the program's PLY for the same subcommand and is "
                    "written whole or not at all.")
    commands = main.add_subparsers(dest="operation", required=True, metavar="OPERATION")

    def command(name, help_text):
        sub = commands.add_parser(name, help=help_text, description=help_text)
        sub.add_argument("input", metavar="INPUT",
                         help="binary PLY, binary PCD, LAS or Zarr group (x, y, z; nx, ny, nz if any)")
        sub.add_argument("-o", "--output", required=True, help="OUT.ply or OUT.zarr")
        engine = sub.add_argument_group("engine")
        engine.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
        engine.add_argument("--workers", type=int, help="LocalCluster workers (default: one per core)")
        engine.add_argument("--memory-limit", default="auto", help="memory limit per LocalCluster worker, e.g. 3GiB")
        engine.add_argument("--tiles", type=int,
                            help="number of tiles (default: about 262,000 points each; 1,048,576 for edit)")
        engine.add_argument("--halo", type=float, help="first halo width (default: from the operation and spacing)")
        engine.add_argument("--scratch", help="folder every worker can reach (default: beside the output)")
        engine.add_argument("--threads-per-task", type=int, default=1, help="library threads inside each task")
        engine.add_argument("--connect-timeout", type=float, default=20, help="seconds to wait for --scheduler")
        engine.add_argument("--report", help="write the run's report as JSON")
        return sub

    def filter_options(sub):
        sub.add_argument("-k", type=int, default=S, help="neighbours of the Laplacian")
        sub.add_argument("--order", choices=["linear", "quadric", "cubic"], default=S)
        sub.add_argument("--lambda", dest="lam", type=float, default=S)
        sub.add_argument("--mu", type=float, default=S)
        sub.add_argument("--weights", choices=["uniform", "distance"], default=S)

    details = command("details", "geometric details of every point, as PLY properties and a colour map")
    filter_options(details)
    details.add_argument("--color-by", dest="color_by", choices=["detail_normal", "detail_magnitude"], default=S)
    normals = command("normals", "normals by jet fitting, oriented consistently across the tiles")
    normals.add_argument("-k", type=int, default=S, help="neighbours of each fit, the point itself not counted")
    curvature = command("curvature", "signed mean curvature of every point")
    curvature.add_argument("-k", type=int, default=S, help="neighbours of each fit")
    curvature.add_argument("--fitting", choices=["closed_form", "monge"], default=S)
    enhance = command("enhance", "the whole scan's details enhanced by s against the balanced-flow base surface "
                                 "(approximate: each tile reads --margin neighbourhood radii around it; normals as "
                                 "given or estimated, not re-fitted)")
    enhance.add_argument("-s", type=float, required=True, help="the enhancement: 1 keeps the points")
    filter_options(enhance)
    enhance.add_argument("--margin", type=float, default=S, help="neighbourhood radii each tile reads around it")
    simplify = command("simplify", "simplification sample points (surfels: position, normal, radius, member_count) "
                                   "of a subsample clustered on the client, every point's cluster and the surfels "
                                   "computed over the whole scan (--tiles, --halo and --threads-per-task are not "
                                   "taken)")
    simplify.add_argument("--target-count", "--target", dest="target_count", type=int, default=S,
                          help="sample points the clustering aims at")
    simplify.add_argument("--subsample", type=int, default=S,
                          help="points clustered on the client (default 1,000,000; a smaller scan is clustered whole)")
    simplify.add_argument("--mode-threshold", dest="mode_threshold", type=float, default=S,
                          help="split while the members' modes spread more than this many range bandwidths")
    simplify.add_argument("-k", type=int, default=S, help="mean-shift neighbours")
    simplify.add_argument("--clusters", default=S,
                          help="also write the scan with each point's ssp_index and cluster colour (PLY or Zarr)")
    edit = command("edit", "the detail-preserving edit of an edit JSON (regions as sphere: and box: specs, index "
                           "files of the scan's rows, mask:ARRAY, a boolean array of the scan's Zarr group, or nearest:FILE, "
                           "indices of the JSON's sample, each point taking its nearest sample point's): its sample "
                           "points, solve and motions on a subsample on the client, every point diffused tile by "
                           "tile with its exact handles and collar, and its details restored as point-detail edit "
                           "restores them")
    edit.add_argument("--edit", required=True, help="the edit JSON, as point-detail edit --edit reads it")
    edit.add_argument("--subsample", type=int, default=S,
                      help="points the client deforms (default 1,000,000; a smaller scan is deformed whole)")
    edit.add_argument("--upsample", action="store_true", default=S,
                      help="fill what the edit stretched, as point-detail edit --upsample (new points: inserted = 1)")
    return main


ENGINE = ("operation", "input", "output", "scheduler", "workers", "memory_limit", "tiles", "halo", "scratch",
          "threads_per_task", "connect_timeout", "report")


def main(argv=None):
    arguments = vars(parser().parse_args(argv))
    options = {key: value for key, value in arguments.items() if key not in ENGINE}
    try:
        report = run(arguments["operation"], arguments["input"], arguments["output"],
                     scheduler=arguments["scheduler"], workers=arguments["workers"],
                     memory_limit=arguments["memory_limit"], tiles=arguments["tiles"], halo=arguments["halo"],
                     scratch=arguments["scratch"], threads_per_task=arguments["threads_per_task"],
                     connect_timeout=arguments["connect_timeout"], progress=sys.stderr.isatty(),
                     log=lambda message: print(message, file=sys.stderr, flush=True), **options)
    except (TiledError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    seconds = sum(report["seconds"].values()) + sum(report["client_seconds"].values())
    done = (f"{report['sample_points']} sample points from a subsample of {report['subsample']}"
            if arguments["operation"] == "simplify" else
            f"{report['tiles']} tiles, {report['widened_tiles']} tile(s) widened their halo")
    if "fill" in report:
        done += f", {report['fill']['inserted']} new points in {report['fill']['tiles']} fill tiles"
    print(f"{report['points']} points: {done}; {seconds:.1f} s ({report['points'] / seconds:,.0f} points/s); "
          f"wrote {arguments['output']}", file=sys.stderr)
    if arguments["report"]:
        with open(arguments["report"], "w") as f:
            json.dump(report, f, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
