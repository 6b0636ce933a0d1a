"""Selections over the k-nearest-neighbour graph of a scan: rings, connected parts, the region grown around a
handle, and the checks before an edit (a handle that is an island in the fixed part, a region with no fixed part).

The graph is the library's neighbourhoods (cgal_ext.compute_neighbor_graph, k = 10), made symmetric: i and j are
neighbours when either is among the other's nearest. Everything here is numpy over its CSR arrays.
"""
import numpy as np

import cgal_ext

K = 10  # neighbours per point of the selection graph


class Graph:
    """The symmetric k-nearest-neighbour graph of `points`, in CSR form (offsets, neighbors)."""

    def __init__(self, points, k=K):
        self.n = len(points)
        self.offsets, self.neighbors = cgal_ext.compute_neighbor_graph(points, k=min(k, self.n - 1), symmetric=True)

    def of(self, indices):
        """The neighbours of the points `indices` (with repeats)."""
        starts, ends = self.offsets[indices], self.offsets[np.asarray(indices) + 1]
        counts = ends - starts
        if not counts.sum():
            return np.zeros(0, np.int64)
        # Each neighbour's position in `neighbors`: its row's start plus its rank in the row.
        first = np.repeat(starts - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
        return self.neighbors[first + np.arange(counts.sum())]

    def ring(self, mask):
        """The points of `mask` and their neighbours."""
        grown = mask.copy()
        grown[self.of(np.flatnonzero(mask))] = True
        return grown

    def border(self, mask):
        """The points of `mask` with a neighbour outside it."""
        # Every row holds at least k neighbours, so reduceat's segments are the rows.
        outside = np.logical_or.reduceat(~mask[self.neighbors], self.offsets[:-1])
        return mask & outside

    def flood(self, seeds, allowed=None, rings=None):
        """The points reached from `seeds` over edges into `allowed` points (all when None), with the ring each
        was reached in (0 for the seeds; -1 unreached), at most `rings` rings."""
        ring = np.full(self.n, -1, np.int64)
        ring[seeds] = 0
        frontier, k = np.unique(seeds), 0
        while len(frontier) and (rings is None or k < rings):
            k += 1
            reached = np.unique(self.of(frontier))
            reached = reached[ring[reached] < 0]
            if allowed is not None:
                reached = reached[allowed[reached]]
            ring[reached] = k
            frontier = reached
        return ring
