// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H
#define CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/edit_selection.h>
#include <CGAL_ext/internal/neighborhood_rotations.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>
#include <Eigen/StdVector>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Puts back the fine details that a blend of sample-point motions smooths out (doc/editing_diffusion.md, "Restoring
/// the details"). Over the relaxed rows that moved, it solves
///
///     (1 + a) x_i - mean_j x_j = R_i d_i + a y_i
///
/// with `j` over the row's neighbours in the symmetrised k-nearest-neighbour graph at rest (the point-set
/// Laplacian's: closed balls, uniform weights), `d_i = p_i - mean_j p_j` its detail at rest, `y_i` where the blend
/// put it and `R_i` the rotation that best carries its neighbourhood's edges there; every other point holds still
/// and pins the solve. The anchor `a` keeps what is coarser than about `1 / sqrt(a)` point spacings where the blend
/// put it (the blend is right at the sample points' scale) and restores the details below.
///
/// Scaled by each row's degree the system is symmetric positive definite, and its Jacobi-scaled spectrum lies in
/// `[a / (1 + a), (2 + a) / (1 + a)]` whatever the points. So a fixed number of Chebyshev steps, known before the
/// solve (`steps()`), reduces the error by the tolerance: no step takes a sum over the rows, a row's result depends
/// on the rows within that many hops only, and a tile of a scan that holds them reproduces the whole scan's result
/// (doc/scaling.md, "Editing in tiles"). Each row sums its neighbours in the order of their rest positions, which
/// the rows' numbering does not change. A rigid motion (`y = R p + t`) solves the system already and stays exact
/// to rounding.
class Detail_relaxation
{
public:
  /// Steps and final residual of the last `apply()`.
  struct Outcome
  {
    unsigned int iterations = 0;
    /// Residual over the right-hand side's details, `|r| / |deg R d|` (0 when nothing moved).
    double residual = 0;
  };

  /// The Chebyshev steps `apply()` takes: the fewest that reduce the error by `tolerance` for any spectrum in the
  /// bounds above (`T_K(1 + a) >= 1 / tolerance`), at most `max_iterations`.
  static unsigned int steps(double anchor, unsigned int max_iterations, double tolerance)
  {
    if(!(tolerance < 1)) return 0;
    if(!(tolerance > 0)) return max_iterations;
    const double needed = std::ceil(std::acosh(1 / tolerance) / std::acosh(1 + anchor));
    return needed < double(max_iterations) ? unsigned(needed) : max_iterations;
  }

  /// Relaxes `rows` of `points` (rest positions), each over the closed ball of its `k`-th nearest point and the
  /// points that have it in theirs (of the relaxed rows: the graph is symmetrised within them).
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& points, std::vector<int> rows, std::size_t k)
  {
    std::vector<std::vector<int>> found(rows.size());
    if(!rows.empty()) {
      const Position_tree tree(points, ConcurrencyTag());
      for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t r) {
        thread_local std::vector<Ranked_row> ball;
        tree.nearest_ball(std::size_t(rows[r]), k, ball);
        for(const Ranked_row& entry : ball) found[r].push_back(entry.second);
      });
    }
    Neighbor_graph balls;
    balls.offsets.assign(rows.size() + 1, 0);
    for(std::size_t r = 0; r < rows.size(); ++r) balls.offsets[r + 1] = balls.offsets[r] + int(found[r].size());
    balls.indices.resize(std::size_t(balls.offsets.back()));
    for(std::size_t r = 0; r < rows.size(); ++r)
      std::copy(found[r].begin(), found[r].end(), balls.indices.begin() + balls.offsets[r]);
    build<ConcurrencyTag>(points, std::move(rows), balls);
  }

  /// As above, with the closed balls of every point given (`k_nearest_neighbor_graph`).
  template <typename ConcurrencyTag>
  void setup(const Matrix_n3& points, std::vector<int> rows, const Neighbor_graph& balls_of_all)
  {
    Neighbor_graph balls;
    balls.offsets.assign(rows.size() + 1, 0);
    for(std::size_t r = 0; r < rows.size(); ++r)
      balls.offsets[r + 1] = balls.offsets[r] + balls_of_all.degree(std::size_t(rows[r]));
    balls.indices.resize(std::size_t(balls.offsets.back()));
    for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t r) {
      std::copy(balls_of_all.begin(std::size_t(rows[r])), balls_of_all.end(std::size_t(rows[r])),
                balls.indices.begin() + balls.offsets[r]);
    });
    build<ConcurrencyTag>(points, std::move(rows), balls);
  }

  /// Solves the system above on `positions` (every row; only the relaxed rows that moved change) with anchor
  /// `anchor` > 0 by `steps(anchor, max_iterations, tolerance)` Chebyshev steps. A row that is still at its `rest`
  /// position with all its neighbours keeps it bit for bit.
  template <typename ConcurrencyTag>
  Outcome apply(const Matrix_n3& rest, double anchor, unsigned int max_iterations, double tolerance,
                Matrix_n3& positions)
  {
    // The unknowns: relaxed rows that moved or have a neighbour that moved, with their targets R_i d_i.
    const std::size_t n = m_rows.size();
    m_target.resize(Eigen::Index(n), 3);
    std::vector<char> moving(n);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      const Eigen::Index row = m_rows[r];
      const Eigen::RowVector3d p = rest.row(row), x = positions.row(row);
      Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
      bool moved = x != p;
      for(const int* j = begin(r); j != end(r); ++j) {
        covariance += (rest.row(*j) - p).transpose() * (positions.row(*j) - x);
        moved = moved || positions.row(*j) != rest.row(*j);
      }
      moving[r] = moved;
      if(moved) m_target.row(Eigen::Index(r)) = m_details.row(Eigen::Index(r)) * best_rotation(covariance).transpose();
    });
    m_free.clear();
    for(std::size_t r = 0; r < n; ++r)
      if(moving[r]) {
        m_free_index[std::size_t(m_rows[r])] = int(m_free.size());
        m_free.push_back(int(r));
      }
    const std::size_t m = m_free.size();
    if(m == 0) return Outcome();

    // Degree-scaled system A x = b over the unknowns: A = (1 + a) D - (adjacency among the unknowns).
    m_adjacency.offsets.assign(m + 1, 0);
    for_range<ConcurrencyTag>(0, m, [&](std::size_t f) {
      int count = 0;
      for(const int* j = begin(std::size_t(m_free[f])); j != end(std::size_t(m_free[f])); ++j)
        count += m_free_index[std::size_t(*j)] >= 0;
      m_adjacency.offsets[f + 1] = count;
    });
    std::partial_sum(m_adjacency.offsets.begin(), m_adjacency.offsets.end(), m_adjacency.offsets.begin());
    m_adjacency.indices.resize(std::size_t(m_adjacency.offsets[m]));
    m_x.resize(Eigen::Index(m), 3);
    m_residual.resize(Eigen::Index(m), 3);
    m_direction.resize(Eigen::Index(m), 3);
    m_next_direction.resize(Eigen::Index(m), 3);
    m_diagonal.resize(Eigen::Index(m));
    // x starts where the blend put the points; its residual b - A x is deg_i (R_i d_i - (x_i - mean_j x_j)). The
    // first step, d = M^-1 r (M = diag A), is Jacobi's.
    using Row = Eigen::RowVector3d;
    const double target_norm = std::sqrt(block_sum<ConcurrencyTag, Row>(m, [&](std::size_t f) {
      const std::size_t r = std::size_t(m_free[f]);
      const Eigen::Index F = Eigen::Index(f);
      int* out = m_adjacency.indices.data() + m_adjacency.offsets[f];
      Row sum = Row::Zero();
      for(const int* j = begin(r); j != end(r); ++j) {
        sum += positions.row(*j);
        if(m_free_index[std::size_t(*j)] >= 0) *out++ = m_free_index[std::size_t(*j)];
      }
      const double degree = double(end(r) - begin(r));
      m_x.row(F) = positions.row(m_rows[r]);
      m_diagonal(F) = (1 + anchor) * degree;
      const Row target = degree * m_target.row(Eigen::Index(r));
      m_residual.row(F) = target - degree * m_x.row(F) + sum;
      m_direction.row(F) = m_residual.row(F) / m_diagonal(F);
      return Row(target.cwiseAbs2());
    }).sum());
    for(int r : m_free) m_free_index[std::size_t(m_rows[std::size_t(r)])] = -1;

    // Chebyshev steps (Saad, Iterative Methods for Sparse Linear Systems, 2nd ed., Algorithm 12.1) for the
    // spectrum of M^-1 A in [theta - delta, theta + delta], theta = 1, delta = 1 / (1 + a): sigma = 1 + a.
    const unsigned int count = steps(anchor, max_iterations, tolerance);
    const double sigma = 1 + anchor;
    double rho = 1 / sigma;
    // One pass per step: the next direction goes to a second array, as the neighbours still read this one.
    for(unsigned int step = 0; step < count; ++step) {
      const double next_rho = 1 / (2 * sigma - rho);
      const double keep = next_rho * rho, scale = 2 * next_rho * sigma;
      rho = next_rho;
      for_range<ConcurrencyTag>(0, m, [&](std::size_t f) {
        const Eigen::Index F = Eigen::Index(f);
        const Row direction = m_direction.row(F);
        Row product = m_diagonal(F) * direction;
        for(const int* j = m_adjacency.begin(f); j != m_adjacency.end(f); ++j) product -= m_direction.row(*j);
        m_x.row(F) += direction;
        m_residual.row(F) -= product;
        m_next_direction.row(F) = keep * direction + scale * m_residual.row(F) / m_diagonal(F);
      });
      m_direction.swap(m_next_direction);
    }
    Outcome outcome;
    outcome.iterations = count;
    outcome.residual =
      target_norm > 0 ? std::sqrt(block_sum<ConcurrencyTag, Row>(
                                    m, [&](std::size_t f) { return Row(m_residual.row(Eigen::Index(f)).cwiseAbs2()); })
                                    .sum()) /
                          target_norm
                      : 0;
    for_range<ConcurrencyTag>(0, m, [&](std::size_t f) {
      positions.row(m_rows[std::size_t(m_free[f])]) = m_x.row(Eigen::Index(f));
    });
    // Coincident points stay together: their equations differ only by the neighbour search's tie-breaks, which
    // would pull them apart (a crack in a scan with duplicated points). Each takes the place of the point it
    // follows, whose own place is final: a pinned one, or the first of the relaxed ones.
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      if(m_twin[r] >= 0) positions.row(m_rows[r]) = positions.row(m_twin[r]);
    });
    return outcome;
  }

private:
  static constexpr std::size_t block_size = 256;

  // The relaxed rows' closed balls (row r of `balls`, of point `rows[r]`) symmetrised within them, sorted by
  // position, with each row's twin and detail at rest.
  template <typename ConcurrencyTag>
  void build(const Matrix_n3& points, std::vector<int> rows, const Neighbor_graph& balls)
  {
    m_rows = std::move(rows);
    const std::size_t n = m_rows.size();
    m_free_index.assign(std::size_t(points.rows()), -1);
    std::vector<int>& relaxed_index = m_free_index; // reset to -1 below
    for(std::size_t r = 0; r < n; ++r) relaxed_index[std::size_t(m_rows[r])] = int(r);
    // A twin: a coincident point, pinned if there is one, else the first relaxed one (in a closed ball, with it).
    m_twin.assign(n, -1);
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      const int row = m_rows[r];
      int pinned_twin = -1, relaxed_twin = row;
      for(const int* j = balls.begin(r); j != balls.end(r); ++j) {
        if(points.row(*j) != points.row(row)) continue;
        if(relaxed_index[std::size_t(*j)] < 0)
          pinned_twin = pinned_twin < 0 ? *j : std::min(pinned_twin, *j);
        else
          relaxed_twin = std::min(relaxed_twin, *j);
      }
      m_twin[r] = pinned_twin >= 0 ? pinned_twin : relaxed_twin != row ? relaxed_twin : -1;
    });
    // Symmetrise: j joins row i's neighbours when i is in j's ball and j is relaxed too.
    std::vector<int> degree(n);
    for(std::size_t r = 0; r < n; ++r) {
      degree[r] += balls.degree(r);
      for(const int* j = balls.begin(r); j != balls.end(r); ++j)
        if(relaxed_index[std::size_t(*j)] >= 0) ++degree[std::size_t(relaxed_index[std::size_t(*j)])];
    }
    m_neighbors.offsets.assign(n + 1, 0);
    for(std::size_t r = 0; r < n; ++r) m_neighbors.offsets[r + 1] = m_neighbors.offsets[r] + degree[r];
    m_neighbors.indices.resize(std::size_t(m_neighbors.offsets[n]));
    std::vector<int> fill(m_neighbors.offsets.begin(), m_neighbors.offsets.end() - 1);
    for(std::size_t r = 0; r < n; ++r)
      for(const int* j = balls.begin(r); j != balls.end(r); ++j) {
        m_neighbors.indices[std::size_t(fill[r]++)] = *j;
        if(relaxed_index[std::size_t(*j)] >= 0)
          m_neighbors.indices[std::size_t(fill[std::size_t(relaxed_index[std::size_t(*j)])]++)] = m_rows[r];
      }
    for(int row : m_rows) relaxed_index[std::size_t(row)] = -1;
    m_details.resize(Eigen::Index(n), 3);
    const auto by_position = [&](int i, int j) {
      return std::make_tuple(points(i, 0), points(i, 1), points(i, 2), i) <
             std::make_tuple(points(j, 0), points(j, 1), points(j, 2), j);
    };
    for_range<ConcurrencyTag>(0, n, [&](std::size_t r) {
      int* first = m_neighbors.indices.data() + m_neighbors.offsets[r];
      int* last = m_neighbors.indices.data() + fill[r];
      std::sort(first, last, by_position);
      last = std::unique(first, last);
      // The slots freed by duplicates stay unused: a row's neighbours end at m_end.
      fill[r] = int(last - m_neighbors.indices.data());
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      for(const int* j = first; j != last; ++j) mean += points.row(*j);
      m_details.row(Eigen::Index(r)) = points.row(m_rows[r]) - mean / double(last - first);
    });
    m_end = std::move(fill);
  }

  // The sum of body(f) over f in [0, m), by blocks of block_size in a fixed order.
  template <typename ConcurrencyTag, typename Value, typename Body>
  static Value block_sum(std::size_t m, const Body& body)
  {
    std::vector<Value, Eigen::aligned_allocator<Value>> partial((m + block_size - 1) / block_size);
    for_range<ConcurrencyTag>(0, partial.size(), [&](std::size_t block) {
      Value sum = Value::Zero();
      for(std::size_t f = block * block_size; f < std::min(m, (block + 1) * block_size); ++f) sum += body(f);
      partial[block] = sum;
    });
    Value total = Value::Zero();
    for(const Value& value : partial) total += value;
    return total;
  }

  const int* begin(std::size_t r) const { return m_neighbors.begin(r); }
  const int* end(std::size_t r) const { return m_neighbors.indices.data() + m_end[r]; }

  std::vector<int> m_rows;
  Neighbor_graph m_neighbors;  // per relaxed row, its symmetrised neighbours (sorted, up to m_end)
  std::vector<int> m_end;      // per relaxed row, the end of its neighbours in m_neighbors.indices
  std::vector<int> m_twin;     // per relaxed row, the coincident point it follows (among its k + 1 nearest), or -1
  Matrix_n3 m_details;         // per relaxed row, d_i at rest
  Matrix_n3 m_target;          // per relaxed row: R_i d_i (per call)
  // Per call, the unknowns: their relaxed rows, their neighbours among them, the Chebyshev steps' vectors.
  std::vector<int> m_free;
  std::vector<int> m_free_index; // per point, its unknown or -1 (all -1 between calls)
  Neighbor_graph m_adjacency;
  Matrix_n3 m_x, m_residual, m_direction, m_next_direction;
  Eigen::VectorXd m_diagonal;
};

/// The rows an edit's `Detail_relaxation` relaxes: the region's rows among `moving_rows` (`labels` per row), but
/// `pinned_rows` (exact handles, which follow their transforms).
inline std::vector<int> relaxed_rows(const std::vector<int>& moving_rows, const std::vector<int>& labels,
                                     const std::vector<int>& pinned_rows)
{
  std::vector<char> pinned(labels.size(), 0);
  for(int row : pinned_rows) pinned[std::size_t(row)] = 1;
  std::vector<int> rows;
  for(int row : moving_rows)
    if(labels[std::size_t(row)] != fixed_label && !pinned[std::size_t(row)]) rows.push_back(row);
  return rows;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_DETAIL_RELAXATION_H
