// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H
#define CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>

#include <algorithm>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Puts back the fine details that a blend of sample-point motions smooths out (doc/editing.md, "Restoring
/// the details"): Jacobi sweeps of `x_i = mean_j x_j + R_i d_i` over the relaxed rows, with `j` over the
/// row's neighbours in the symmetrised k-nearest-neighbour graph at rest (the point-set Laplacian's, uniform
/// weights), `d_i = p_i - mean_j p_j` its detail at rest and `R_i` the rotation that best carries its
/// neighbourhood's edges to where they are before the sweeps. Every other point holds still and pins the
/// sweeps. A rigid motion (`x = R p + t`) is a fixed point, so it stays exact to rounding; the sweep averages
/// with weights that sum to one, so it never amplifies, and its first sweeps take out the wrinkles the blend
/// left at the scale of a few points.
class Detail_relaxation
{
public:
  /// Relaxes `rows` of `points` (rest positions), each over its `k` nearest points and those that have it
  /// among their `k` nearest (of the relaxed rows: the graph is symmetrised within them).
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& points, std::vector<int> rows, std::size_t k)
  {
    m_rows = std::move(rows);
    const std::size_t n = m_rows.size();
    Neighbor_graph nearest = fixed_degree_graph(n, k);
    if(n > 0) {
      const Position_tree tree(points, ConcurrencyTag());
      for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
        const int row = m_rows[r];
        int* out = nearest.indices.data() + r * k;
        std::size_t m = 0;
        // k + 1 to skip the point itself (with exact duplicates it need not come first).
        tree.nearest(tree[std::size_t(row)], k + 1, [&](int j, double) {
          if(j != row && m < k) out[m++] = j;
        });
      });
    }
    // Symmetrise: j joins row i's neighbours when i is among j's nearest and j is relaxed too.
    std::vector<int> relaxed_index(std::size_t(points.rows()), -1);
    for(std::size_t r = 0; r < n; ++r) relaxed_index[std::size_t(m_rows[r])] = int(r);
    std::vector<int> degree(n, int(k));
    for(std::size_t r = 0; r < n; ++r)
      for(const int* j = nearest.begin(r); j != nearest.end(r); ++j)
        if(relaxed_index[std::size_t(*j)] >= 0) ++degree[std::size_t(relaxed_index[std::size_t(*j)])];
    m_neighbors.offsets.assign(n + 1, 0);
    for(std::size_t r = 0; r < n; ++r) m_neighbors.offsets[r + 1] = m_neighbors.offsets[r] + degree[r];
    m_neighbors.indices.resize(std::size_t(m_neighbors.offsets[n]));
    std::vector<int> fill(m_neighbors.offsets.begin(), m_neighbors.offsets.end() - 1);
    for(std::size_t r = 0; r < n; ++r)
      for(const int* j = nearest.begin(r); j != nearest.end(r); ++j) {
        m_neighbors.indices[std::size_t(fill[r]++)] = *j;
        if(relaxed_index[std::size_t(*j)] >= 0) m_neighbors.indices[std::size_t(fill[std::size_t(relaxed_index[std::size_t(*j)])]++)] = m_rows[r];
      }
    m_details.resize(Eigen::Index(n), 3);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      int* first = m_neighbors.indices.data() + m_neighbors.offsets[r];
      int* last = m_neighbors.indices.data() + fill[r];
      std::sort(first, last);
      last = std::unique(first, last);
      // The slots freed by duplicates stay unused: a row's neighbours end at m_end.
      fill[r] = int(last - m_neighbors.indices.data());
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      for(const int* j = first; j != last; ++j) mean += points.row(*j);
      m_details.row(Eigen::Index(r)) = points.row(m_rows[r]) - mean / double(last - first);
    });
    m_end = std::move(fill);
  }

  /// `sweeps` sweeps on `positions` (every row; only the relaxed ones change). A row that is still at its
  /// `rest` position with all its neighbours keeps it bit for bit.
  template <typename ConcurrencyTag>
  void apply(const Matrix_n3& rest, unsigned int sweeps, Matrix_n3& positions)
  {
    const std::size_t n = m_rows.size();
    m_target.resize(Eigen::Index(n), 3);
    m_next.resize(Eigen::Index(n), 3);
    m_moving.resize(n);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      const Eigen::Index row = m_rows[r];
      const Eigen::RowVector3d p = rest.row(row), x = positions.row(row);
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      bool moved = x != p;
      for(const int* j = begin(r); j != end(r); ++j) {
        covariance += (rest.row(*j) - p).transpose() * (positions.row(*j) - x);
        moved = moved || positions.row(*j) != rest.row(*j);
      }
      m_moving[r] = moved;
      if(moved) m_target.row(Eigen::Index(r)) = m_details.row(Eigen::Index(r)) * best_rotation(covariance).transpose();
    });
    for(unsigned int sweep = 0; sweep < sweeps; ++sweep) {
      for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
        if(!m_moving[r]) return;
        Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
        for(const int* j = begin(r); j != end(r); ++j) sum += positions.row(*j);
        m_next.row(Eigen::Index(r)) = sum / double(end(r) - begin(r)) + m_target.row(Eigen::Index(r));
      });
      for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
        if(m_moving[r]) positions.row(m_rows[r]) = m_next.row(Eigen::Index(r));
      });
    }
  }

private:
  const int* begin(std::size_t r) const { return m_neighbors.begin(r); }
  const int* end(std::size_t r) const { return m_neighbors.indices.data() + m_end[r]; }

  std::vector<int> m_rows;
  Neighbor_graph m_neighbors;  // per relaxed row, its symmetrised neighbours (sorted, up to m_end)
  std::vector<int> m_end;      // per relaxed row, the end of its neighbours in m_neighbors.indices
  Matrix_n3 m_details;         // per relaxed row, d_i at rest
  Matrix_n3 m_target, m_next;  // per call: R_i d_i, and a sweep's new positions
  std::vector<char> m_moving;  // per call
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H
