// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_POINT_SET_LAPLACIAN_H
#define CGAL_EXT_COMPUTE_POINT_SET_LAPLACIAN_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <Eigen/SparseCore>

#include <functional>
#include <vector>

namespace CGAL_ext {

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

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/geometric_details.md">Geometric details</a> (`doc/geometric_details.md`).
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
