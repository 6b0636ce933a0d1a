// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_ROW_KD_TREE_H
#define CGAL_EXT_INTERNAL_ROW_KD_TREE_H

// The kd-tree under every neighbour query of the package (Position_tree): why it is not CGAL's is in
// doc/design.md, "The kd-tree".

#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// The squared distance of two points: the one formula every ranking of neighbours uses, so that two searches
/// over different sets of points (a whole scan and a tile of it) rank the same pair alike.
inline double squared_distance(double ax, double ay, double az, double bx, double by, double bz)
{
  const double dx = ax - bx, dy = ay - by, dz = az - bz;
  return dx * dx + dy * dy + dz * dz;
}

/// (squared distance, row): the order in which every search ranks its candidates.
using Ranked_row = std::pair<double, int>;

/// A kd-tree over the rows of a position array: the `k` nearest rows of a point ranked exactly by (squared
/// distance, row), so that which of the rows tied at the k-th distance are kept depends on the rows alone, not
/// on the tree's shape; and the rows within a radius. Cells split at the median of their widest extent down to
/// leaves of at most `leaf_size` rows, whose coordinates are stored together in leaf order.
class Row_kd_tree
{
public:
  static constexpr int leaf_size = 12;

  Row_kd_tree() = default;

  template <typename ConcurrencyTag>
  Row_kd_tree(const Matrix_n3& positions, ConcurrencyTag)
  {
    const std::size_t n = std::size_t(positions.rows());
    if(n == 0) return;
    std::vector<Entry> entries(n);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
      entries[i] =
        Entry{{positions(Eigen::Index(i), 0), positions(Eigen::Index(i), 1), positions(Eigen::Index(i), 2)}, int(i)};
    });
    for(int d = 0; d < 3; ++d) {
      m_low[d] = positions.col(d).minCoeff();
      m_high[d] = positions.col(d).maxCoeff();
    }
    m_nodes.resize(std::size_t(node_count(int(n))));
    build<ConcurrencyTag>(entries, 0, 0, int(n));
    m_rows.resize(n);
    for(std::vector<double>& c : m_coordinates) c.resize(n);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
      m_rows[i] = entries[i].row;
      for(int d = 0; d < 3; ++d) m_coordinates[d][i] = entries[i].xyz[d];
    });
  }

  std::size_t size() const { return m_rows.size(); }

  /// `out` = the `min(k, size())` rows nearest to `q`, ranked by (squared distance, row); with `bound`, only
  /// those at most at that squared distance.
  void nearest(const double* q, std::size_t k, std::vector<Ranked_row>& out,
               double bound = std::numeric_limits<double>::infinity()) const
  {
    out.clear();
    k = std::min(k, size());
    if(k == 0) return;
    Nearest search{q, k, out, bound};
    double offset[3];
    root_distance(q, offset);
    search_node(search, offset);
    if(k > sorted_insertion_limit) std::sort_heap(out.begin(), out.end());
  }

  /// Appends to `out` the rows whose squared distance to `q` is at most `radius` squared.
  void within(const double* q, double radius, std::vector<int>& out) const
  {
    if(m_rows.empty()) return;
    double offset[3];
    const double radius2 = radius * radius;
    if(root_distance(q, offset) > radius2) return;
    descend(
      0, q, offset,
      [&](const double* d2, const int* rows, int count) {
        for(int i = 0; i < count; ++i)
          if(d2[i] <= radius2) out.push_back(rows[i]);
      },
      [&](double distance) { return distance <= radius2; });
  }

private:
  // A node's rows are m_rows[begin, end); an inner node's left child follows it, its right child is `right`.
  // Along `dim`, the left child's rows lie at or below `low`, the right child's at or above `high`.
  struct Node
  {
    double low, high;
    int begin, end, right, dim; // dim < 0: a leaf
  };

  // Up to this k the best rows are kept sorted by insertion (faster than a heap for the k the package asks,
  // doc/design.md, "The kd-tree"); past it, in a heap.
  static constexpr std::size_t sorted_insertion_limit = 256;

  struct Nearest
  {
    const double* q;
    std::size_t k;
    std::vector<Ranked_row>& best; // sorted, or a heap (largest first) past sorted_insertion_limit
    double bound = std::numeric_limits<double>::infinity(); // the k-th squared distance so far

    void offer(const Ranked_row& candidate)
    {
      if(k > sorted_insertion_limit) {
        if(best.size() == k) {
          if(!(candidate < best.front())) return;
          std::pop_heap(best.begin(), best.end());
          best.back() = candidate;
        } else {
          best.push_back(candidate);
        }
        std::push_heap(best.begin(), best.end());
        if(best.size() == k) bound = best.front().first;
        return;
      }
      if(best.size() == k) {
        if(!(candidate < best.back())) return;
      } else {
        best.push_back(candidate);
      }
      std::size_t e = best.size() - 1;
      for(; e > 0 && candidate < best[e - 1]; --e) best[e] = best[e - 1];
      best[e] = candidate;
      if(best.size() == k) bound = best.back().first;
    }
  };

  static int node_count(int rows)
  {
    return rows <= leaf_size ? 1 : 1 + node_count(rows / 2) + node_count(rows - rows / 2);
  }

  // A row and its coordinates, moved together while the tree is built.
  struct Entry
  {
    double xyz[3];
    int row;
  };

  template <typename ConcurrencyTag>
  void build(std::vector<Entry>& entries, int id, int begin, int end)
  {
    Node& node = m_nodes[std::size_t(id)];
    node.begin = begin;
    node.end = end;
    node.dim = -1;
    if(end - begin <= leaf_size) return;
    const auto first = entries.begin() + begin, last = entries.begin() + end;
    double low[3], high[3];
    for(int d = 0; d < 3; ++d) low[d] = high[d] = first->xyz[d];
    for(auto e = first + 1; e != last; ++e)
      for(int d = 0; d < 3; ++d) {
        low[d] = std::min(low[d], e->xyz[d]);
        high[d] = std::max(high[d], e->xyz[d]);
      }
    int dim = 0;
    for(int d = 1; d < 3; ++d)
      if(high[d] - low[d] > high[dim] - low[dim]) dim = d;
    const int middle = begin + (end - begin) / 2;
    const auto split = entries.begin() + middle;
    std::nth_element(first, split, last, [dim](const Entry& a, const Entry& b) {
      return a.xyz[dim] < b.xyz[dim] || (a.xyz[dim] == b.xyz[dim] && a.row < b.row);
    });
    node.dim = dim;
    node.high = split->xyz[dim];
    node.low = -std::numeric_limits<double>::infinity();
    for(auto e = first; e != split; ++e) node.low = std::max(node.low, e->xyz[dim]);
    node.right = id + 1 + node_count(middle - begin);
    const int right = node.right;
    const auto left_half = [&] { build<ConcurrencyTag>(entries, id + 1, begin, middle); };
    const auto right_half = [&] { build<ConcurrencyTag>(entries, right, middle, end); };
    if(end - begin > 8192)
      run_concurrently<ConcurrencyTag>(right_half, left_half);
    else {
      left_half();
      right_half();
    }
  }

  // The squared distance from `q` to the box of all rows, and its offsets along each axis.
  double root_distance(const double* q, double* offset) const
  {
    for(int d = 0; d < 3; ++d)
      offset[d] = q[d] < m_low[d] ? q[d] - m_low[d] : q[d] > m_high[d] ? q[d] - m_high[d] : 0.0;
    return squared_distance(offset[0], offset[1], offset[2], 0, 0, 0);
  }

  // Calls `visit_leaf(squared distances, rows, count)` for the leaves whose cells `reaches(squared distance)`
  // accepts. `offset` holds the query's offsets from the node's cell along each axis (a lower bound of each
  // row's); their squared length comes from the same formula as a row's squared distance, so with rounding too it
  // never exceeds that of a row in the cell. The nearer child is searched first, the other when its cell is in
  // reach.
  template <typename Visit_leaf, typename Reaches>
  void descend(int id, const double* q, double* offset, const Visit_leaf& visit_leaf, const Reaches& reaches) const
  {
    const Node& node = m_nodes[std::size_t(id)];
    if(node.dim < 0) {
      // The leaf's squared distances in one loop over its coordinates (vectorised), then its rows visited.
      double d2[leaf_size];
      const double *x = m_coordinates[0].data() + node.begin, *y = m_coordinates[1].data() + node.begin,
                   *z = m_coordinates[2].data() + node.begin;
      const int count = node.end - node.begin;
      for(int i = 0; i < count; ++i) d2[i] = squared_distance(q[0], q[1], q[2], x[i], y[i], z[i]);
      visit_leaf(d2, m_rows.data() + node.begin, count);
      return;
    }
    const int dim = node.dim;
    const double to_left = q[dim] - node.low, to_right = q[dim] - node.high;
    const bool left_first = to_left + to_right < 0;
    descend(left_first ? id + 1 : node.right, q, offset, visit_leaf, reaches);
    const double kept = offset[dim];
    offset[dim] = left_first ? to_right : to_left;
    if(reaches(squared_distance(offset[0], offset[1], offset[2], 0, 0, 0)))
      descend(left_first ? node.right : id + 1, q, offset, visit_leaf, reaches);
    offset[dim] = kept;
  }

  void search_node(Nearest& search, double* offset) const
  {
    const double* q = search.q;
    descend(
      0, q, offset,
      [&](const double* d2, const int* rows, int count) {
        for(int i = 0; i < count; ++i)
          if(d2[i] <= search.bound) search.offer(Ranked_row(d2[i], rows[i]));
      },
      // At the bound too: a row tied with the k-th may rank before it by its row.
      [&](double distance) { return distance <= search.bound; });
  }

  std::vector<Node> m_nodes;
  std::vector<int> m_rows;              // the rows in leaf order
  std::vector<double> m_coordinates[3]; // their x, y and z, in the same order
  double m_low[3] = {0, 0, 0}, m_high[3] = {0, 0, 0};
};

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_ROW_KD_TREE_H
