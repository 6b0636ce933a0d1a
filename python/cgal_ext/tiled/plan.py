"""How a scan is cut into tiles, and the check that a tile's halo held every point its own points depend on.

Tiles come from a kd-split of a sample of the scan: half-open boxes `lo <= x < hi` whose outer sides are
infinite, so every point of the scan, sampled or not, is the own point of exactly one tile. A tile reads its box
grown by the halo width on every finite side (its "read box").

The check (`certify`) is exact, not a rule of thumb: a point's k nearest neighbours among the points read are its
k nearest in the whole scan when the k-th of them is closer than the read box's border. Operations that use the
symmetrised k-nearest-neighbour graph (the Laplacian of the details) also need every point that has the row among
its own k nearest; such a point outside the read box lies beyond the border, so it cannot exist when the border is
farther than every k-th-neighbour distance of the points around (`reach`, verified against the neighbouring
tiles' measured distances after the run).
"""
import numpy as np
from scipy.spatial import cKDTree

from .. import _core


class Tiling:
    """A kd-split of space into `count` tiles: `axes[i]`, `splits[i]` and the children of inner node i."""

    def __init__(self, sample, count):
        self.nodes = []  # (axis, split, left, right); a child < 0 is the tile -child - 1
        self.lo, self.hi = [], []
        self.root = self._split(np.asarray(sample), count, np.full(3, -np.inf), np.full(3, np.inf))

    def _split(self, sample, count, lo, hi):
        if count == 1 or len(sample) < 2:
            self.lo.append(lo)
            self.hi.append(hi)
            return -len(self.lo)
        extent = sample.max(axis=0) - sample.min(axis=0)
        axis = int(np.argmax(extent))
        left_count = count // 2
        split = float(np.quantile(sample[:, axis], left_count / count))
        below = sample[:, axis] < split
        node = len(self.nodes)
        self.nodes.append(None)
        left_hi, right_lo = hi.copy(), lo.copy()
        left_hi[axis] = right_lo[axis] = split
        left = self._split(sample[below], left_count, lo, left_hi)
        right = self._split(sample[~below], count - left_count, right_lo, hi)
        self.nodes[node] = (axis, split, left, right)
        return node

    @property
    def count(self):
        return len(self.lo)

    def boxes(self):
        return np.array(self.lo), np.array(self.hi)

    def tile_of(self, points):
        """The tile that owns each point."""
        out = np.empty(len(points), dtype=np.int64)
        self._descend(points, np.arange(len(points)), self.root, 0.0, lambda tile, rows: out.__setitem__(rows, tile))
        return out

    def read_sets(self, points, halo):
        """{tile: rows of `points` inside the tile's box grown by `halo`} (rows ascending)."""
        found = {}
        self._descend(points, np.arange(len(points)), self.root, halo,
                      lambda tile, rows: found.__setitem__(tile, rows))
        return found

    def _descend(self, points, rows, node, halo, visit):
        if node < 0:
            visit(-node - 1, rows)
            return
        axis, split, left, right = self.nodes[node]
        x = points[rows, axis]
        below, above = x < split + halo, x >= split - halo
        if below.any():
            self._descend(points, rows[below], left, halo, visit)
        if above.any():
            self._descend(points, rows[above], right, halo, visit)


def _spread_bits(v):
    """The 10 low bits of v spread to every third bit (for Morton codes)."""
    v = v & 0x3FF
    v = (v | (v << 16)) & 0x030000FF
    v = (v | (v << 8)) & 0x0300F00F
    v = (v | (v << 4)) & 0x030C30C3
    return (v | (v << 2)) & 0x09249249


def spatial_order(points):
    """A permutation that puts nearby points together (Morton order on a 1024^3 grid): neighbour queries in this
    order run several times faster than in the file's order."""
    lo = points.min(axis=0)
    extent = float((points.max(axis=0) - lo).max()) or 1.0
    cells = ((points - lo) * (1023.0 / extent)).astype(np.int64)
    return np.argsort(_spread_bits(cells[:, 0]) | (_spread_bits(cells[:, 1]) << 1) | (_spread_bits(cells[:, 2]) << 2),
                      kind="stable")


def read_box(lo, hi, halo):
    return lo - halo, hi + halo


def border_distance(points, lo, hi):
    """Distance of each point to the border of the box [lo, hi] it lies in (infinite sides never count)."""
    with np.errstate(invalid="ignore"):
        gaps = np.minimum(points - lo, hi - points)
    return np.min(np.where(np.isfinite(gaps), gaps, np.inf), axis=1)


def own_mask(points, lo, hi):
    return np.all((points >= lo) & (points < hi), axis=1)


class Neighborhoods:
    """The k nearest neighbours of every point read (itself first), and whether they are the whole scan's."""

    def __init__(self, points, k, border):
        count = min(k + 1, len(points))
        tree = cKDTree(points, leafsize=32, balanced_tree=False, compact_nodes=False)
        distances, indices = tree.query(points, count, workers=_core.get_num_threads())
        self.distances, self.indices = distances.reshape(len(points), count), indices.reshape(len(points), count)
        if count < k + 1:  # fewer points read than neighbours asked: nothing can be certified
            self.distances = np.pad(self.distances, ((0, 0), (0, k + 1 - count)), constant_values=np.inf)
        self.border = border

    def kth_distance(self, k):
        return self.distances[:, k]

    def exact(self, k):
        """Each point's k nearest (itself not counted) are its k nearest in the whole scan."""
        return self.distances[:, k] < self.border

    def neighbors(self, k):
        """Each point's k nearest, itself left out (m, k)."""
        return self.indices[:, 1:k + 1]


def certify_directed(neighborhoods, k, own):
    """Own points whose k nearest neighbours are exact: operations on each point's own k nearest."""
    return neighborhoods.exact(k)[own]


def certify_symmetric(neighborhoods, k, own, reach, rings):
    """Own points whose value under `rings` products with the symmetrised-kNN Laplacian is exact.

    A row is exact when its point's k nearest are exact, no point outside the read box can hold it among its k
    nearest (the border is farther than `reach`, the largest k-th-neighbour distance around), and every point
    read that holds it among its k nearest has exact neighbours itself. The value after `rings` products needs
    the rows within `rings - 1` hops.
    """
    exact = neighborhoods.exact(k)
    neighbors = neighborhoods.neighbors(k)
    pointed_by_inexact = np.zeros(len(exact), dtype=bool)
    pointed_by_inexact[neighbors[~exact].reshape(-1)] = True
    bad = ~(exact & (neighborhoods.border > reach) & ~pointed_by_inexact)
    for _ in range(rings - 1):  # one hop of the symmetrised graph: a bad point's neighbours, and who has one
        spread = bad | bad[neighbors].any(axis=1)
        spread[neighbors[bad].reshape(-1)] = True
        bad = spread
    return ~bad[own]


def box_distances(lo, hi, los, his):
    """Euclidean distance from the box [lo, hi] to each box [los[i], his[i]] (0 where they meet)."""
    with np.errstate(invalid="ignore"):
        gap = np.maximum(0.0, np.maximum(lo - his, los - hi))
    gap = np.where(np.isfinite(gap), gap, 0.0)
    return np.sqrt((gap * gap).sum(axis=1))
