"""Geometric details of a point set and a coloured PLY of their oriented magnitude, with numpy only.

Usage: python3 details_colours.py [out.ply] [points.xyz]
(points.xyz: one point per line, x y z or x y z nx ny nz; default: a generated bumpy sphere)
"""
import sys

import numpy as np

import cgal_ext


def bumpy_sphere(n=20000):
    rng = np.random.default_rng(7)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * (1 + 0.02 * np.sin(12 * d[:, 0]) * np.sin(12 * d[:, 1]))[:, None], d


def diverging(values):
    """Blue (recessed) - white - red (standing out), saturating at the 98th percentile of |values|."""
    t = np.clip(values / max(np.percentile(np.abs(values), 98), 1e-300), -1, 1)[:, None]
    white, red, blue = np.array([242, 240, 238]), np.array([180, 4, 38]), np.array([59, 76, 192])
    return np.where(t >= 0, white + t * (red - white), white - t * (blue - white)).round().astype(np.uint8)


def main():
    if len(sys.argv) > 2:
        data = np.loadtxt(sys.argv[2], ndmin=2)
        points = np.ascontiguousarray(data[:, :3])
        normals = np.ascontiguousarray(data[:, 3:6]) if data.shape[1] >= 6 else None
    else:
        points, normals = bumpy_sphere()
    details, magnitude = cgal_ext.compute_geometric_details(points, normals, k=10, order="quadric")
    colours = diverging(magnitude)
    out = sys.argv[1] if len(sys.argv) > 1 else "details_colours.ply"
    with open(out, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\nproperty double z\n"
                "property double detail_magnitude\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                "end_header\n" % len(points))
        for p, m, c in zip(points, magnitude, colours):
            f.write("%.17g %.17g %.17g %.17g %d %d %d\n" % (p[0], p[1], p[2], m, c[0], c[1], c[2]))
    print("%d points; detail magnitude in [%.3g, %.3g]; wrote %s" % (len(points), magnitude.min(), magnitude.max(), out))


if __name__ == "__main__":
    main()
