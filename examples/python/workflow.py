"""One workflow on a real scan, CGAL's bunny00 (37,706 points with its mesh's vertex normals): its geometric
details and a colour map of their relief, then an ear bent down by a detail-preserving edit dragged in frames,
with PLY files and pictures of each step (doc/python.md walks through it). Under 2 s on 2 cores.

Usage: python3 workflow.py [OUTPUT] [--data DIR]
  OUTPUT  a folder for the outputs (default: workflow_output), or the edited scan's .ply path, the other outputs
          written beside it: details.ply, details.png, selection.png, edit.png
  --data  the folder of CGAL's data set (scripts/fetch_data.sh; default: $CGAL_EXT_DATA, else the repository's data/)
"""
import argparse
import contextlib
import os
import sys
import time

import numpy as np

import cgal_ext

VIEW = dict(view="front", width=500, height=500)  # every picture the same view, before and after the edit


@contextlib.contextmanager
def progress_bar(title):
    """A progress callable for the library's progress=: a tqdm bar when tqdm is installed, else a printed line."""
    try:
        from tqdm import tqdm
    except ImportError:
        shown = [-1]

        def report(fraction):  # "title: 0% 25% 50% 75% 100%"
            quarter = int(4 * fraction)
            if quarter > shown[0]:
                print(("%s:" % title if shown[0] < 0 else "") + " %d%%" % (25 * quarter), end="", flush=True)
                shown[0] = quarter
        yield report
        print()
        return
    with tqdm(total=100, desc=title, unit="%") as bar:
        yield lambda fraction: bar.update(round(100 * fraction) - bar.n)


def rotation_about_z(degrees):
    a = np.radians(degrees)
    return np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("output", nargs="?", default="workflow_output",
                        help="output folder, or the edited scan's .ply path (the other files beside it)")
    parser.add_argument("--data", default=os.environ.get("CGAL_EXT_DATA", os.path.join(here, "..", "..", "data")),
                        help="CGAL's data set (default: $CGAL_EXT_DATA, else the repository's data/)")
    args = parser.parse_args()
    if args.output.endswith(".ply"):
        out_dir, edited_ply = os.path.dirname(args.output) or ".", args.output
    else:
        out_dir, edited_ply = args.output, os.path.join(args.output, "edited.ply")
    os.makedirs(out_dir, exist_ok=True)
    scan = os.path.join(args.data, "meshes", "bunny00.off")
    if not os.path.exists(scan):
        sys.exit("workflow.py: %s is missing (bash scripts/fetch_data.sh fetches CGAL's data set)" % scan)
    start = time.perf_counter()

    # 1. Read the scan: new float64 arrays (the mesh's area-weighted vertex normals; its faces are not kept).
    points, normals, _ = cgal_ext.read_points(scan)

    # 2. The details delta and their oriented magnitude +-|delta| (the paper's map: + where the detail stands out
    #    along the normal). On a scan most of delta is tangential (the Laplacian pulls each point toward the denser
    #    side of its neighbours: 89 % of |delta|^2 on this one, doc/geometric_details.md), so the relief is
    #    coloured by the normal component delta . n, as `point-detail details` does; the PLY holds both scalars.
    t = time.perf_counter()
    with progress_bar("details") as progress:
        details, magnitude = cgal_ext.compute_geometric_details(points, normals, k=10, order="quadric",
                                                                lam=0.8, mu=1.6, progress=progress)
    details_seconds = time.perf_counter() - t
    relief = np.einsum("ij,ij->i", details, normals)  # delta . n of every point
    colours = cgal_ext.diverging_colors(relief)  # blue recessed, white flat, red standing out
    cgal_ext.write_ply(os.path.join(out_dir, "details.ply"), points, normals, colours, input_path=scan,
                       detail_magnitude=magnitude, detail_normal=relief)
    with open(os.path.join(out_dir, "details.png"), "wb") as f:
        f.write(cgal_ext.render_png(points, normals, values=relief, legend="detail along the normal, model units",
                                    **VIEW))  # the same colours, with a legend

    # 3. The selection, as boolean masks. The ear that points back: its tip is the scan's highest point, its base
    #    the points 0.28 to 0.32 from the tip (the ear is about 0.3 long; the model is 1 wide). The region of
    #    interest is the ball about the ear's middle that reaches a little past the base, the handle a small
    #    ball about the tip, and the ear turns about its base.
    tip = points[np.argmax(points[:, 1])]
    distance = np.linalg.norm(points - tip, axis=1)
    base = points[(distance > 0.28) & (distance < 0.32)].mean(axis=0)
    roi = np.linalg.norm(points - (tip + base) / 2, axis=1) < 0.2
    handle = distance < 0.08
    selection = np.full((len(points), 3), 200, np.uint8)  # fixed: grey
    selection[roi] = (90, 150, 230)                       # region of interest: blue
    selection[handle] = (230, 60, 40)                     # handle: red
    with open(os.path.join(out_dir, "selection.png"), "wb") as f:
        f.write(cgal_ext.render_png(points, normals, colors=selection, **VIEW))

    # 4. The edit: the points are copied into the Deformation; the ear's tip turned down about its base in frames
    #    of a drag, each frame's result written into the same two arrays.
    deformation = cgal_ext.Deformation(points, normals, order="quadric", rotations="propagate")
    deformation.insert_roi(roi)
    group = deformation.create_handle_group(handle)
    with progress_bar("preprocess") as progress:
        deformation.preprocess(progress=progress)
    moved, moved_normals = np.empty_like(points), np.empty_like(normals)
    for degrees in range(-5, -46, -5):  # 9 frames, 5 degrees each
        deformation.set_handle_transform(group, rotation_about_z(degrees), pivot=base)
        deformation.deform()
        deformation.diffuse(moved, moved_normals)  # in place: only the points the edit can move are rewritten
    deformation.restore_details(moved, moved_normals)  # once the drag ends: the fine details back
    stats = deformation.statistics()

    # 5. The result: a PLY keeping the input's point order (so the detail colours still fit) with the
    #    displacement as a scalar, and a picture coloured by the displacement in the same view as before.
    displacement = np.linalg.norm(moved - points, axis=1)
    cgal_ext.write_ply(edited_ply, moved, moved_normals, colours, input_path=scan, displacement=displacement)
    with open(os.path.join(out_dir, "edit.png"), "wb") as f:
        f.write(cgal_ext.render_png(moved, moved_normals, values=displacement, legend="distance moved, model units",
                                    **VIEW))

    print("%s: %d points; details %.2f s, |delta| up to %.3g, delta . n in [%.3g, %.3g]"
          % (os.path.basename(scan), len(points), details_seconds, np.abs(magnitude).max(), relief.min(),
             relief.max()))
    print("edit: %d points in the region, %d in the handle; %d sample points (%d in the region)"
          % (roi.sum(), handle.sum(), stats["samples"], stats["roi_samples"]))
    print("preprocess %.3f s (clustering %.3f s); last frame: deform %.2f ms, diffuse %.2f ms; restore_details "
          "%.3f s (%d iterations); largest displacement %.3g"
          % (stats["preprocess_seconds"], stats["clustering_seconds"], 1000 * stats["deform_seconds"],
             1000 * stats["diffuse_seconds"], stats["restore_seconds"], stats["restore_iterations"],
             displacement.max()))
    print("wrote details.ply, %s and details.png, selection.png, edit.png in %s (%.1f s in all)"
          % (os.path.basename(edited_ply), out_dir, time.perf_counter() - start))

if __name__ == "__main__":
    main()
