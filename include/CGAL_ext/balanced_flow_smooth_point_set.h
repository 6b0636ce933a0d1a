// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_BALANCED_FLOW_SMOOTH_POINT_SET_H
#define CGAL_EXT_BALANCED_FLOW_SMOOTH_POINT_SET_H

#include <CGAL_ext/Balanced_flow_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/balanced_flow.h>
#include <CGAL_ext/internal/oriented_normals.h>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Replaces every point by its position on the smooth base surface of the balanced flow
  (`Balanced_flow_settings`): bumps and wrinkles are flattened, spheres, cylinders and planes are left where
  they are, so the model neither shrinks nor thins. This is the base surface of detail enhancement and of
  the detail colour maps.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`.
  \tparam PointRange a model of `Range` whose value type is the key type of the property maps.

  \param points the points, moved in place through `point_map`
  \param k number of nearest neighbours of the Laplacian, `1 <= k < points.size()`
  \param settings the flow's fidelity and the extent of its mean curvature
  \param np `point_map` (readable and writable), `normal_map` (estimated by
         `estimate_oriented_normals` when absent), `callback` (false cancels; the points are then
         untouched), `geom_traits`, as in `compute_geometric_details`

  \return false if the callback cancelled, true otherwise.
  \throws Invalid_input for the conditions of `compute_geometric_details` or a fidelity that is not > 0.
  \throws Numerical_failure if the balance equation does not converge.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/detail_scaling.md">Detail scaling and enhancement</a> (`doc/detail_scaling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool balanced_flow_smooth_point_set(PointRange& points, unsigned int k, const Balanced_flow_settings& settings = {},
                                    const NamedParameters& np = CGAL::parameters::default_values())
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Point = typename NP_helper::Geom_traits::Point_3;
  constexpr const char* who = "balanced_flow_smooth_point_set";

  const auto point_map = NP_helper::get_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  settings.validate();
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  internal::check_neighbor_count(k, cloud.size(), who);

  internal::Progress progress(callback);
  internal::Matrix_n3 normals;
  progress.stage(0.0, 0.5);
  if(!internal::given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress,
                                                            normals, who))
    return false;
  progress.stage(0.5, 1.0);
  internal::Sparse_row_matrix K;
  if(!internal::build_laplacian<ConcurrencyTag>(cloud, k, Laplacian_weights(), progress, K)) return false;
  const internal::Matrix_n3 base = internal::balanced_flow_base_surface<ConcurrencyTag>(K, cloud.positions, normals, settings);

  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(auto& item : points) {
    const auto x = base.row(row_of[i++]);
    put(point_map, item, Point(x(0), x(1), x(2)));
  }
  return true;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_BALANCED_FLOW_SMOOTH_POINT_SET_H
