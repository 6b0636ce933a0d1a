"""A drag from Python on a mesh split at its edge midpoints, in the mesh's own vertex order: the Python drag of
bench_python.py (set_handle_transform, deform, diffuse into the arrays of the drag before) against the library's
deform() + diffuse(), medians of 5 objects of 20 drags. A by-hand measurement beside the harness (doc/python.md,
"Overhead"): a mesh's vertex order is what a user's figure has, neither the sampling's random order nor the
harness's sorted one; with `shuffled`, the same points in a random order.
Usage: PYTHONPATH=build/python python3 benchmark/python_drag_on_split_meshes.py MESH.off SPLITS [shuffled]
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cgal_ext  # noqa: E402,F401  (the package bench_python drives)
from bench_python import drag_times  # noqa: E402

def read_off(path):
    with open(path) as f:
        tokens = f.read().split()
    assert tokens[0].endswith("OFF")
    nv, nf = int(tokens[1]), int(tokens[2])
    v = np.array(tokens[4:4 + 3 * nv], dtype=float).reshape(nv, 3)
    rest = np.array(tokens[4 + 3 * nv:], dtype=np.int64)
    faces = rest.reshape(nf, -1)[:, 1:4]
    return v, faces

def split(v, f):
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    # midpoints in the order faces first meet their edges
    first = np.full(len(unique), len(edges)); np.minimum.at(first, inverse.ravel(), np.arange(len(edges)))
    order = np.argsort(first); rank = np.empty_like(order); rank[order] = np.arange(len(order))
    mid = (v[unique[order, 0]] + v[unique[order, 1]]) / 2
    m = len(v) + rank[inverse.ravel()].reshape(3, -1).T  # per face: m01, m12, m20
    a, b, c = f[:, 0], f[:, 1], f[:, 2]
    nf = np.concatenate([np.stack([a, m[:, 0], m[:, 2]], 1), np.stack([m[:, 0], b, m[:, 1]], 1),
                         np.stack([m[:, 2], m[:, 1], c], 1), np.stack([m[:, 0], m[:, 1], m[:, 2]], 1)])
    return np.vstack([v, mid]), nf

if sys.argv[3:] not in ([], ["shuffled"]):
    sys.exit("usage: python_drag_on_split_meshes.py MESH.off SPLITS [shuffled]")
shuffled = sys.argv[3:] == ["shuffled"]
v, f = read_off(sys.argv[1])
for _ in range(int(sys.argv[2])):
    v, f = split(v, f)
n = np.zeros_like(v)
fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
for k in range(3):
    np.add.at(n, f[:, k], fn)
n /= np.linalg.norm(n, axis=1)[:, None]
if shuffled:
    order = np.random.default_rng(1).permutation(len(v))
    v, n = v[order], n[order]
drag = drag_times(np.ascontiguousarray(v), np.ascontiguousarray(n), 20, 5)
print("%s split %s%s: %d points, %d in the region: python %.2f ms, library %.2f ms, ratio %.2f" % (
    sys.argv[1].split('/')[-1], sys.argv[2], ", shuffled" if shuffled else "", len(v), drag.movable, 1e3 * drag.wall,
    1e3 * drag.library, drag.wall / drag.library))
