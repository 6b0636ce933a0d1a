"""A detail-preserving edit driven from Python: the top of a bumpy sphere turned by 30 degrees about x, dragged
in steps as a user would, then carried to every point.

Usage: python3 edit.py [out.ply]
"""
import sys

import numpy as np

import cgal_ext


def main():
    rng = np.random.default_rng(5)
    d = rng.normal(size=(30000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    points = d * (1 + 0.02 * np.sin(12 * d[:, 0]) * np.sin(12 * d[:, 1]))[:, None]

    deformation = cgal_ext.Deformation(points, d, rotations="arap")
    deformation.insert_roi(np.flatnonzero(points[:, 2] > 0.0))  # the upper half deforms
    handle = deformation.create_handle_group(np.flatnonzero(points[:, 2] > 0.85))  # its cap is dragged
    deformation.preprocess(progress=lambda f: None)
    for degrees in range(5, 31, 5):  # a drag: the handle turns a little more each frame
        a = np.radians(degrees)
        R = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        deformation.set_handle_transform(handle, R, np.zeros(3))
        deformation.deform()
    moved, normals = deformation.diffuse()
    stats = deformation.statistics()
    out = sys.argv[1] if len(sys.argv) > 1 else "edit.ply"
    with open(out, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\n" % len(moved) +
                "".join("property double %s\n" % n for n in ("x", "y", "z", "nx", "ny", "nz")) + "end_header\n")
        np.savetxt(f, np.hstack([moved, normals]), fmt="%.17g")
    print("%d points, %d sample points (%d in the region): preprocess %.3f s, last drag %.1f ms; wrote %s"
          % (stats["points"], stats["samples"], stats["roi_samples"], stats["preprocess_seconds"],
             1000 * (stats["deform_seconds"] + stats["diffuse_seconds"]), out))


if __name__ == "__main__":
    main()
