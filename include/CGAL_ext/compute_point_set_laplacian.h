// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_POINT_SET_LAPLACIAN_H
#define CGAL_EXT_COMPUTE_POINT_SET_LAPLACIAN_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <Eigen/SparseCore>

#include <algorithm>
#include <functional>
#include <utility>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Symmetrised kNN graph and Laplacian of a cloud, both in the cloud's (spatial) order.
/// Progress runs over [0, 1] of the current stage. Returns false when cancelled.
template <typename ConcurrencyTag>
bool build_laplacian(const Spatial_point_cloud& cloud, std::size_t k, const Laplacian_weights& weights,
                     Progress& progress, Sparse_row_matrix& K, Neighbor_graph* graph_out = nullptr)
{
  Neighbor_graph graph = symmetrize<ConcurrencyTag>(k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress));
  if(progress.cancelled()) return false;
  K = laplacian_matrix<ConcurrencyTag>(cloud.positions, graph, weights);
  if(graph_out) *graph_out = std::move(graph);
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

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_BUILD_LAPLACIAN_INSTANCES(EXTERN, Tag) \
  EXTERN template bool build_laplacian<Tag>(const Spatial_point_cloud&, std::size_t, const Laplacian_weights&, \
                                            Progress&, Sparse_row_matrix&, Neighbor_graph*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_BUILD_LAPLACIAN_INSTANCES)

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Computes the point-set Laplacian `K = I - W` of Miao et al. (2007, Sect. 3) on the symmetrised
  k-nearest-neighbour graph of `points`: `j` is a neighbour of `i` if either is among the other's `k`
  nearest. The rows of `W` are non-negative and sum to 1, so `K` maps constants to zero; `K` is not symmetric.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of `point_map`.

  \param points the input points
  \param k number of nearest neighbours, the point itself not counted; `1 <= k < points.size()`
  \param weights how neighbours are weighted (uniform by default)
  \param laplacian output, `n x n`, row-major, rows and columns in the order of `points`
  \param np optional named parameters among: `point_map`, `geom_traits`, `callback`
         (`std::function<bool(double)>`; returning false cancels, and `laplacian` is left untouched).

  \return false if the callback cancelled the computation, true otherwise.
  \throws Invalid_input for an empty range, non-finite coordinates, `k` out of range or non-finite weights.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool compute_point_set_laplacian(const PointRange& points, unsigned int k, const Laplacian_weights& weights,
                                 Eigen::SparseMatrix<double, Eigen::RowMajor, int>& laplacian,
                                 const NamedParameters& np = CGAL::parameters::default_values())
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());

  constexpr const char* who = "compute_point_set_laplacian";
  weights.validate();
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  internal::check_neighbor_count(k, cloud.size(), who);

  internal::Progress progress(callback);
  internal::Sparse_row_matrix K;
  if(!internal::build_laplacian<ConcurrencyTag>(cloud, k, weights, progress, K)) return false;
  laplacian = internal::to_input_order(K, cloud);
  return true;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_COMPUTE_POINT_SET_LAPLACIAN_H
