"""How a scan is cut into tiles, and the check that a tile's halo held every point its own points depend on.

Tiles come from a kd-split of a sample of the scan: half-open boxes `lo <= x < hi` whose outer sides are
infinite, so every point of the scan, sampled or not, is the own point of exactly one tile. A tile reads its box
grown by the halo width on every finite side (its "read box").

The check (`certify`) is exact, not a rule of thumb: a point's neighbourhood among the points read (the closed ball
of its k-th nearest, every point tied at that distance included) is its neighbourhood in the whole scan when the
k-th of them is closer than the read box's border: a point tied with it that the tile cannot see is at least as far
as the border, and the point is not certified. Operations that use the symmetrised k-nearest-neighbour graph (the
Laplacian of the details) also need every point that has the row among its own k nearest; such a point outside the
read box lies beyond the border, so it cannot exist when the border is farther than every k-th-neighbour distance of
the points around (`reach`, verified against the neighbouring tiles' measured distances after the run).
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
        self._visit_leaves(points, 0.0, lambda tile, rows: out.__setitem__(rows, tile))
        return out

    def read_sets(self, points, halos):
        """{tile: rows of `points` inside the tile's box grown by its halo} (rows ascending); `halos`: one per
        tile."""
        found = {}
        halos = np.asarray(halos, dtype=float)
        widest = float(halos.max())

        def keep(tile, rows):
            if halos[tile] < widest:  # the descent grew every box by the widest halo
                rows = rows[own_mask(points[rows], self.lo[tile] - halos[tile], self.hi[tile] + halos[tile])]
            found[tile] = rows

        self._visit_leaves(points, widest, keep)
        return found

    def _visit_leaves(self, points, halo, visit):
        self._descend(np.ascontiguousarray(points.T), np.arange(len(points)), self.root, halo, visit)

    def _descend(self, columns, rows, node, halo, visit):
        """Visits each leaf under `node` with the `rows` whose point (x, y and z in `columns`) its box grown by
        `halo` holds."""
        if node < 0:
            visit(-node - 1, rows)
            return
        axis, split, left, right = self.nodes[node]
        x = columns[axis][rows]
        below, above = x < split + halo, x >= split - halo
        if below.any():
            self._descend(columns, rows[below], left, halo, visit)
        if above.any():
            self._descend(columns, rows[above], right, halo, visit)


def read_box(lo, hi, halo):
    return lo - halo, hi + halo


def border_distance(points, lo, hi):
    """Distance of each point to the border of the box [lo, hi] it lies in (infinite sides never count)."""
    with np.errstate(invalid="ignore"):
        gaps = np.minimum(points - lo, hi - points)
    return np.min(np.where(np.isfinite(gaps), gaps, np.inf), axis=1)


def own_mask(points, lo, hi):
    return np.all((points >= lo) & (points < hi), axis=1)


def squared_distances(a, b):
    """Squared distances of the rows of `a` to those of `b` (broadcast), by the library's own formula, so that a tie
    the library sees is a tie here too."""
    d = a - b
    return d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] + d[..., 2] * d[..., 2]


TIE_MARGIN = 1e-12  # distances within this relative margin of the k-th are checked exactly (SciPy rounds its own)


class Neighborhoods:
    """The neighbourhoods (the library's rule: the closed ball of the k-th nearest other point, every point tied at
    that distance included) of the points read that the certificate needs, and whether they are the whole scan's.

    `search(mask)` finds them for the points of the mask (all by default). A point not searched must have its k
    nearest closer than its border (see `banded_neighborhoods`): it reads as exact, at distance 0, with the
    neighbour `len(points)` (a sentinel row).
    """

    def __init__(self, points, k, border, search_all=True):
        m = len(points)
        self.points, self.k, self.border = points, k, border
        self.distances = np.zeros((m, k))
        self.indices = np.full((m, k + 1), m, dtype=np.int64)  # ranked (distance, row); sentinel m past the ball
        self.squared = np.full((m, k + 1), np.inf)
        self.searched = np.zeros(m, dtype=bool)
        self._tree = cKDTree(points, leafsize=32, balanced_tree=False, compact_nodes=False) if m else None
        if search_all:
            self.search(np.ones(m, dtype=bool))

    def search(self, mask):
        """Finds the neighbourhoods of the points of `mask` not searched yet."""
        new = mask & ~self.searched
        if not new.any():
            return
        m, k = len(self.points), self.k
        rows = self._tree.indices[new[self._tree.indices]]  # in the tree's order: nearby queries run together
        count = min(k + 2, m)  # the point itself, k others and one more to see a tie at the k-th
        while len(rows):
            indices, squared = self._ranked(rows, count)
            found = count - 1
            self._store(rows, indices, squared)
            self.distances[rows, :min(k, found)] = np.sqrt(squared[:, :min(k, found)])
            self.distances[rows, found:] = np.inf  # fewer points read than neighbours asked: none of them exact
            if count == m:
                break
            # A tie at the k-th distance that reaches the last point found may go on past it: ask for more.
            tied = squared[:, -1] <= squared[:, k - 1] * (1 + TIE_MARGIN)
            rows, count = rows[tied], min(2 * count, m)
        self.searched |= new

    def _ranked(self, rows, count):
        """The `count` - 1 nearest other points of each of `rows`, ranked (squared distance, row)."""
        _, indices = self._tree.query(self.points[rows], count, workers=_core.get_num_threads())
        indices = indices.reshape(len(rows), count)
        # Leave the point itself out; where exact duplicates hide it beyond those found, leave out the last.
        keep = indices != rows[:, None]
        keep[keep.all(axis=1), -1] = False
        indices = indices[keep].reshape(len(rows), count - 1)
        squared = squared_distances(self.points[indices], self.points[rows][:, None, :])
        order = np.lexsort((indices, squared), axis=1)
        return np.take_along_axis(indices, order, 1), np.take_along_axis(squared, order, 1)

    def _store(self, rows, indices, squared):
        width = indices.shape[1]
        if width > self.indices.shape[1]:
            extra = width - self.indices.shape[1]
            self.indices = np.pad(self.indices, ((0, 0), (0, extra)), constant_values=len(self.points))
            self.squared = np.pad(self.squared, ((0, 0), (0, extra)), constant_values=np.inf)
        self.indices[rows, :width], self.squared[rows, :width] = indices, squared

    def kth_distance(self, k):
        """Each point's distance to its k-th nearest (0 where not searched)."""
        return self.distances[:, k - 1]

    def exact(self, k):
        """Each point's neighbourhood is its neighbourhood in the whole scan: its k-th nearest, and so every point
        tied with it, is closer than the read box's border."""
        return self.distances[:, k - 1] < self.border

    def neighbors(self, k):
        """Each point's neighbourhood for k, padded with the sentinel `m` (also where not searched)."""
        ball = self.squared <= self.squared[:, k - 1:k]
        width = max(int(ball.sum(axis=1).max(initial=0)), k)
        return np.where(ball, self.indices, len(self.points))[:, :width]


def interior_bound(points, k, cell):
    """An upper bound of each point's k-th-neighbour distance, inf where none is found: the extent of the points
    sharing its cell of a grid of side `cell`, when the cell holds at least k + 1 points."""
    if len(points) == 0:
        return np.empty(0)
    cells = np.floor(points / cell).astype(np.int64)
    cells -= cells.min(axis=0)
    dims = cells.max(axis=0) + 1
    key = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]
    order = np.argsort(key)
    key = key[order]
    first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    sizes = np.diff(np.r_[first, len(points)])
    inside = points[order]
    extent = np.linalg.norm(np.maximum.reduceat(inside, first) - np.minimum.reduceat(inside, first), axis=1)
    bound = np.empty(len(points))
    bound[order] = np.repeat(np.where(sizes >= k + 1, extent, np.inf), sizes)
    return bound


def banded_neighborhoods(points, k, border, reach, rings, halo, spacing):
    """Neighborhoods searched only where the certificate needs them: in a band along the read box's border, and
    where no grid cell bounds the k-th-neighbour distance. Returns (neighborhoods, interior): `interior` is None
    when every point was searched, else (D, L): the points not searched lie more than L inside the own box and
    have their k nearest within D.

    Why the band suffices: a point not searched has its k nearest within D, closer than its border: they are
    exact. The symmetric certificate rejects first the inexact points, those within reach of the border and those
    an inexact point holds, all within B = max(reach, 2 Dq) of the border (Dq the largest k-th-neighbour distance
    searched); each of its rings - 1 hops adds the neighbours of a rejected point (within Dq) and the points that
    hold one (within Dq if searched). A point not searched that holds one lies within D of it: the band, at least
    B + (rings - 2) Dq + D wide, leaves none. It is also wider than D + 2 halo: the points not searched then
    cannot hold a point of a neighbouring tile's read box unless that box is wider than this one's, which
    `Run._verify_reach` checks."""
    bound = interior_bound(points, k, 2.5 * spacing)
    bounded = np.isfinite(bound)
    D = float(bound[bounded].max()) if bounded.any() else 0.0
    neighborhoods = Neighborhoods(points, k, border, search_all=False)
    Dq = 2.0 * spacing  # a first guess, checked below
    while True:
        # 1 % over D + 2 halo: the check after the tiles compares rounded box distances with D.
        width = max(max(reach, 2.0 * Dq) + max(rings - 2, 0) * Dq + D, 1.01 * (D + 2.0 * halo))
        band = ~bounded | (border <= width)
        if band.mean() > 0.6:  # most of the tile: search it whole
            neighborhoods.search(np.ones(len(points), dtype=bool))
            return neighborhoods, None
        neighborhoods.search(band)
        if neighborhoods.kth_distance(k).max() <= Dq:
            return neighborhoods, (D, width - halo)
        Dq = float(neighborhoods.kth_distance(k).max())


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
    m = len(exact)
    pointed_by_inexact = np.zeros(m + 1, dtype=bool)  # entry m: the sentinel neighbour of the rows not searched
    pointed_by_inexact[neighbors[~exact].reshape(-1)] = True
    bad = np.append(~(exact & (neighborhoods.border > reach) & ~pointed_by_inexact[:m]), False)
    for _ in range(rings - 1):  # one hop of the symmetrised graph: a bad point's neighbours, and who has one
        spread = bad.copy()
        spread[:m] |= bad[neighbors].any(axis=1)
        spread[neighbors[bad[:m]].reshape(-1)] = True
        spread[m] = False
        bad = spread
    return ~bad[:m][own]


def rejection_depth(radius, border, reach, rings, tolerance):
    """A depth below the read box's border beyond which `certify_symmetric` rejects no point, from each point's
    k-th-neighbour distance among the points read (`radius`) alone.

    The first rejections are the points within reach, the inexact points (radius >= border) and those an inexact
    point q holds (within radius(q) of it). Each hop adds the neighbours of a rejected point b (at most
    border(b) + radius(b) deep) and the points q that hold one (border(q) - radius(q) <= the depth so far; their
    own depth counts). `tolerance` (a multiple of the coordinates' rounding) pads every step."""
    inexact = radius >= border - tolerance
    depth = max(reach, float((border + radius)[inexact].max(initial=0.0))) + tolerance
    slack = border - radius
    for _ in range(rings - 1):
        depth = max(depth, float((border + radius)[border <= depth].max(initial=0.0)),
                    float(border[slack <= depth].max(initial=0.0))) + tolerance
    return depth


def certify_with_radius(points, radius, border, own, k, reach, rings, tolerance):
    """`certify_symmetric`'s answer when every point's k-th-neighbour distance among the points read is known
    (`radius`, as the library measured it while computing): the k nearest are searched only for the points
    within `rejection_depth` of the border, none when no own point lies that deep. Returns (certified, the
    fraction of the points searched)."""
    band = border <= rejection_depth(radius, border, reach, rings, tolerance)
    if not (band & own).any():
        return np.ones(int(own.sum()), dtype=bool), 0.0
    neighborhoods = Neighborhoods(points, k, border, search_all=False)
    neighborhoods.search(band)  # the others read as exact and are never rejected, as the depth shows
    return certify_symmetric(neighborhoods, k, own, reach, rings), float(band.mean())


def box_distances(lo, hi, los, his):
    """Euclidean distance from the box [lo, hi] to each box [los[i], his[i]] (0 where they meet)."""
    with np.errstate(invalid="ignore"):
        gap = np.maximum(0.0, np.maximum(lo - his, los - hi))
    gap = np.where(np.isfinite(gap), gap, 0.0)
    return np.sqrt((gap * gap).sum(axis=1))
