"""python3 -m cgal_ext.studio SCAN [--port P] [--open]: the editing studio in the browser (doc/studio.md)."""
import argparse
import asyncio
import pathlib
import sys
import webbrowser

from .._process import reexecute_tuned
from .level_of_detail import LEVEL_OF_DETAIL_ABOVE, LEVEL_POINTS
from .server import Studio, serve
from .session import StudioError


def main(argv=None):
    if argv is None:  # the command: its large arrays on huge pages, as point-detail's, and its freed memory kept
        reexecute_tuned([sys.executable, "-m", "cgal_ext.studio", *sys.argv[1:]], keep_memory=True)
    parser = argparse.ArgumentParser(prog="python3 -m cgal_ext.studio",
                                     description="Paint a region and handles on a scan, drag, keep its details, save. "
                                                 "Files are read and written only inside the scan's folder.")
    parser.add_argument("scan", help="a PLY, OFF, XYZ or PWN point set (its folder is the studio's folder; a link "
                                     "stands for the file it leads to, in that file's folder)")
    parser.add_argument("--port", type=int, default=0, help="port on 127.0.0.1 (default: any free one)")
    parser.add_argument("--open", action="store_true", help="open the page in the default browser")
    parser.add_argument("--level-of-detail-above", type=int, default=LEVEL_OF_DETAIL_ABOVE, metavar="N",
                        help="a binary PLY, PCD or LAS scan of more points opens as its level of detail, "
                             "built on Dask and cached beside it; a save runs the tiled edit on every point "
                             "(default: %(default)s)")
    parser.add_argument("--level-points", type=int, default=LEVEL_POINTS, metavar="N",
                        help="the level of detail's points, about (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.level_of_detail_above < 20 or args.level_points < 20:
        parser.error("--level-of-detail-above and --level-points take at least 20 points")
    scan = pathlib.Path(args.scan)
    if not scan.is_file():
        parser.error("%s: no such file" % scan)
    # A link is followed to its file: the studio's folder is that file's folder, and the scan that file.
    scan = scan.resolve()
    try:
        studio = Studio(scan.parent, scan.name, level_of_detail_above=args.level_of_detail_above,
                        level_points=args.level_points)
    except StudioError as error:
        parser.error(str(error))

    def ready(url):
        print("studio: open %s" % url, flush=True)
        print("studio: Ctrl-C stops it", flush=True)
        if args.open:
            webbrowser.open(url)

    try:
        asyncio.run(serve(studio, args.port, ready))
    except KeyboardInterrupt:
        print("studio: stopped", file=sys.stderr)
    except OSError as error:
        sys.exit("studio: %s" % error)


if __name__ == "__main__":
    main()
