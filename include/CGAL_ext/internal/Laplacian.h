// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_LAPLACIAN_H
#define CGAL_EXT_INTERNAL_LAPLACIAN_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

using Sparse_row_matrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

/// `K = I - W` on a neighbour graph whose rows are sorted and free of self-loops: each row holds the
/// diagonal 1 and `-w_ij`, columns in increasing order. Assembled straight into compressed storage.
template <typename ConcurrencyTag>
Sparse_row_matrix laplacian_matrix(const Matrix_n3& positions, const Neighbor_graph& graph,
                                   const Laplacian_weights& weights)
{
  const std::size_t n = graph.size();
  Sparse_row_matrix K(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  K.resizeNonZeros(Eigen::Index(graph.indices.size() + n));
  int* outer = K.outerIndexPtr();
  int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
  for(std::size_t i = 0; i <= n; ++i) outer[i] = graph.offsets[i] + int(i);

  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    const int d = graph.degree(i);
    int* col = inner + outer[i];
    double* val = values + outer[i];
    // The diagonal goes where it keeps the row sorted.
    const int* nb = graph.begin(i);
    const int below = int(std::lower_bound(nb, graph.end(i), int(i)) - nb);
    auto slot = [&](int m) { return m < below ? m : m + 1; };
    col[below] = int(i);
    val[below] = 1.0;
    if(d == 0) return; // isolated point: its row is the identity, its detail is itself minus nothing
    if(weights.weighting == Laplacian_weighting::uniform) {
      for(int m = 0; m < d; ++m) { col[slot(m)] = nb[m]; val[slot(m)] = -1.0 / d; }
      return;
    }
    // The row's value slots hold the distances first, then the weights.
    double mean = 0;
    for(int m = 0; m < d; ++m) {
      col[slot(m)] = nb[m];
      mean += val[slot(m)] = (positions.row(nb[m]) - positions.row(Eigen::Index(i))).norm();
    }
    mean /= d;
    const double floor = mean * 1e-6;
    double sum = 0;
    for(int m = 0; m < d; ++m) {
      val[slot(m)] = mean > 0 ? std::pow(std::max(val[slot(m)], floor), weights.distance_power) : 1.0;
      sum += val[slot(m)];
    }
    for(int m = 0; m < d; ++m) val[slot(m)] = -val[slot(m)] / sum;
  });
  return K;
}

/// `Y = K X` for an n x 3 right-hand side, row-parallel and deterministic.
template <typename ConcurrencyTag>
void multiply(const Sparse_row_matrix& K, const Matrix_n3& X, Matrix_n3& Y)
{
  Y.resize(K.rows(), 3);
  const int* outer = K.outerIndexPtr();
  const int* inner = K.innerIndexPtr();
  const double* values = K.valuePtr();
  for_range<ConcurrencyTag>(0, std::size_t(K.rows()), [&](std::size_t i) {
    double x = 0, y = 0, z = 0;
    for(int e = outer[i]; e < outer[i + 1]; ++e) {
      const double w = values[e];
      const double* row = X.data() + 3 * std::size_t(inner[e]);
      x += w * row[0];
      y += w * row[1];
      z += w * row[2];
    }
    double* out = Y.data() + 3 * i;
    out[0] = x;
    out[1] = y;
    out[2] = z;
  });
}

/// `f(K) X` for the filter's polynomial, by repeated sparse products (no matrix power is formed).
template <typename ConcurrencyTag>
Matrix_n3 apply_detail_filter(const Sparse_row_matrix& K, const Detail_filter& filter, const Matrix_n3& X)
{
  const Detail_filter::Coefficients c = filter.coefficients();
  Matrix_n3 power, next, result;
  multiply<ConcurrencyTag>(K, X, power); // K X
  result = c.c1 * power;
  for(int degree = 2; degree <= filter.degree(); ++degree) {
    multiply<ConcurrencyTag>(K, power, next);
    power.swap(next);
    result += (degree == 2 ? c.c2 : c.c3) * power;
  }
  return result;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_LAPLACIAN_INSTANCES(EXTERN, Tag) \
  EXTERN template Sparse_row_matrix laplacian_matrix<Tag>(const Matrix_n3&, const Neighbor_graph&, \
                                                          const Laplacian_weights&); \
  EXTERN template void multiply<Tag>(const Sparse_row_matrix&, const Matrix_n3&, Matrix_n3&); \
  EXTERN template Matrix_n3 apply_detail_filter<Tag>(const Sparse_row_matrix&, const Detail_filter&, \
                                                     const Matrix_n3&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_LAPLACIAN_INSTANCES)

/// The Laplacian of a cloud on its symmetrised kNN graph, in the cloud's (spatial) order, and, when asked,
/// each point's distance to its k-th nearest. Progress runs over [0, 1] of the current stage. Returns false when
/// cancelled.
template <typename ConcurrencyTag>
bool build_laplacian(const Spatial_point_cloud& cloud, std::size_t k, const Laplacian_weights& weights,
                     Progress& progress, Sparse_row_matrix& K, std::vector<double>* neighbor_radius = nullptr)
{
  const Neighbor_graph directed = k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  if(progress.cancelled()) return false;
  K = laplacian_matrix<ConcurrencyTag>(cloud.positions, symmetrize<ConcurrencyTag>(directed), weights);
  if(neighbor_radius) *neighbor_radius = last_neighbor_distances(cloud.positions, cloud.positions, directed);
  return progress.report(1.0);
}

/// `P K P^T`: the matrix of the cloud's order re-indexed to the caller's order, rows sorted.
inline Sparse_row_matrix to_input_order(const Sparse_row_matrix& K, const Spatial_point_cloud& cloud)
{
  const std::vector<int>& input_index = cloud.input_index;
  const std::size_t n = input_index.size();
  const std::vector<int> spatial_of = cloud.spatial_index();
  Sparse_row_matrix P(K.rows(), K.cols());
  P.resizeNonZeros(K.nonZeros());
  int* outer = P.outerIndexPtr();
  outer[0] = 0;
  for(std::size_t r = 0; r < n; ++r) {
    const int s = spatial_of[r];
    outer[r + 1] = outer[r] + (K.outerIndexPtr()[s + 1] - K.outerIndexPtr()[s]);
  }
  std::vector<std::pair<int, double>> row;
  for(std::size_t r = 0; r < n; ++r) {
    const int s = spatial_of[r];
    row.clear();
    for(int e = K.outerIndexPtr()[s]; e < K.outerIndexPtr()[s + 1]; ++e)
      row.emplace_back(input_index[std::size_t(K.innerIndexPtr()[e])], K.valuePtr()[e]);
    std::sort(row.begin(), row.end());
    for(std::size_t m = 0; m < row.size(); ++m) {
      P.innerIndexPtr()[outer[r] + int(m)] = row[m].first;
      P.valuePtr()[outer[r] + int(m)] = row[m].second;
    }
  }
  return P;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_BUILD_LAPLACIAN_INSTANCES(EXTERN, Tag)                                                                \
  EXTERN template bool build_laplacian<Tag>(const Spatial_point_cloud&, std::size_t, const Laplacian_weights&,         \
                                            Progress&, Sparse_row_matrix&, std::vector<double>*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_BUILD_LAPLACIAN_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_LAPLACIAN_H
