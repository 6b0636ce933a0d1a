// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H
#define CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H

#include <CGAL_ext/Local_fit_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/mean_curvature.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <functional>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Estimates the signed mean curvature `H = (k1 + k2) / 2` of every point from a degree-2 fit to the point and
  its `k` nearest neighbours. Sign convention: positive where the surface bends away from its normal, so a
  sphere of radius r with outward normals has `H = +1/r` (the opposite of CGAL's Monge form, converted here).

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.
  \tparam CurvatureMap a model of `WritablePropertyMap` with value type `geom_traits::FT`.

  \param points the input points; not modified
  \param k neighbours of the fit, the point itself not counted; `5 <= k < points.size()` (a degree-2 fit has
           6 coefficients). Default in the program: `default_curvature_neighbors` = 15.
  \param fitting `Curvature_fitting::monge_jet_fitting` (CGAL's, the reference) or `closed_form` (faster); the
                 overload without it uses the Monge fit
  \param curvature_map receives the mean curvature of each point
  \param np `point_map`, `normal_map` (they orient the sign; estimated by
         `estimate_oriented_normals` when absent), `callback` (false cancels; the map is then untouched),
         `geom_traits`, as in `compute_geometric_details`

  \return false if the callback cancelled, true otherwise.
  \throws Invalid_input for an empty range, non-finite coordinates, `k` out of range, or a zero or non-finite normal.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/curvature.md">Mean curvature</a> (`doc/curvature.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename CurvatureMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool estimate_mean_curvature(const PointRange& points, unsigned int k, Curvature_fitting fitting,
                             CurvatureMap curvature_map, const NamedParameters& np = CGAL::parameters::default_values())
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using FT = typename NP_helper::Geom_traits::FT;
  constexpr const char* who = "estimate_mean_curvature";

  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  internal::check_neighbor_count(k, cloud.size(), who);
  if(k < 5)
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) +
                        " is too small for a degree-2 fit, which needs at least 5 neighbours");

  internal::Progress progress(callback);
  internal::Matrix_n3 normals;
  const double fit_begin = internal::has_given_normals<NamedParameters>(points) ? 0.0 : 0.4;
  progress.stage(0.0, fit_begin);
  if(!internal::given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress,
                                                            normals, who))
    return false;
  progress.stage(fit_begin, fit_begin + 0.2 * (1 - fit_begin));
  const internal::Neighbor_graph graph = internal::k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  if(progress.cancelled()) return false;
  progress.stage(fit_begin + 0.2 * (1 - fit_begin), 1.0);
  Eigen::VectorXd curvature;
  if(!internal::mean_curvatures<ConcurrencyTag>(cloud, normals, graph, fitting, progress, curvature)) return false;

  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) put(curvature_map, item, FT(curvature(row_of[i++])));
  return true;
}

/// \cond SKIP_IN_MANUAL
// With CGAL's Monge jet fitting.
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename CurvatureMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool estimate_mean_curvature(const PointRange& points, unsigned int k, CurvatureMap curvature_map,
                             const NamedParameters& np = CGAL::parameters::default_values())
{
  return estimate_mean_curvature<ConcurrencyTag>(points, k, Curvature_fitting::monge_jet_fitting, curvature_map, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H
