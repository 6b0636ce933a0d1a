// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_ENHANCE_GEOMETRIC_DETAILS_H
#define CGAL_EXT_ENHANCE_GEOMETRIC_DETAILS_H

#include <CGAL_ext/Detail_scaling_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/balanced_flow.h>
#include <CGAL_ext/internal/detail_manipulation.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/geometric_details.h>

#include <numeric>

namespace CGAL_ext {

namespace internal {

template <typename ConcurrencyTag, typename PointRange, typename IndexRange, typename NamedParameters>
Detail_manipulation_result enhance_geometric_details_impl(PointRange& points, unsigned int k, const IndexRange* roi_indices,
                                                          double s, const Detail_enhancement_settings& settings,
                                                          const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  constexpr const char* who = "enhance_geometric_details";

  const auto point_map = NP_helper::get_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  if(!std::isfinite(s)) throw Invalid_input(std::string(who) + ": the enhancement factor s must be finite");
  settings.validate();

  // A part of the model: only its surroundings shape its base surface, and only they are sorted spatially.
  const bool partial = roi_indices != nullptr;
  Region region = make_region<ConcurrencyTag>(points, point_map, k, roi_indices, who, !partial);
  Detail_manipulation_result result;
  std::vector<int> anchors_local =
    region_anchors(points, static_cast<const std::vector<int>*>(nullptr), np, region, result.default_anchors, who);
  if(partial)
    region = region_surroundings<ConcurrencyTag>(region, k, settings.flow_margin,
                                                 std::max<std::size_t>(k, default_normal_neighbors) + 1, anchors_local, who);
  const Spatial_point_cloud& cloud = region.cloud;
  const std::vector<int>& roi = region.roi;
  const std::vector<char>& in_roi = region.in_roi;

  Progress progress(callback);
  Matrix_n3 normals;
  progress.stage(0.0, 0.3);
  if(!given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress, normals, who))
    return {};
  progress.stage(0.3, 0.5);
  Sparse_row_matrix K;
  if(!detail_laplacian<ConcurrencyTag>(cloud, k, settings.details, normals, progress, K, who)) return {};

  // sigma = delta - delta~ with delta~ = f(K) p~, so delta' - delta = (s - 1) f(K) (p - p~).
  const auto detail_offset = [&] {
    return Matrix_n3(cloud.positions - balanced_flow_base_surface<ConcurrencyTag>(K, cloud.positions, normals, settings.flow));
  };
  progress.stage(0.5, 1.0);
  if(!progress.report(0.0)) return {};

  if(result.default_anchors && roi.size() == cloud.size()) {
    // Nothing outside holds the model, and nothing needs to: the displacement (s - 1) (p - p~) meets every
    // detail equation exactly, so p~ + s (p - p~) is the least-squares solution for any anchors placed on it,
    // with zero residual. It is written directly; no system is assembled or factored (doc/detail_scaling.md,
    // "Anchors").
    const Matrix_n3 displacement = (s - 1.0) * detail_offset();
    if(!progress.report(1.0)) return {};
    write_region(points, point_map, cloud, roi, displacement);
    result.completed = true;
    result.region_size = roi.size();
    result.least_squares.unknowns = roi.size();
    result.computed_points = cloud.size();
    result.least_squares.method = "exact: p~ + s (p - p~), nothing to solve (whole model, default anchors)";
    return result;
  }
  if(result.default_anchors && settings.anchors_border()) anchors_local = region_border(K, roi, in_roi);
  // The base surface's flow runs while the system is factored.
  const auto change = [&] {
    return Matrix_n3((s - 1.0) * apply_detail_filter<ConcurrencyTag>(K, settings.details.filter, detail_offset()));
  };
  const Matrix_n3 anchor_displacement = Matrix_n3::Zero(Eigen::Index(anchors_local.size()), 3);
  return solve_and_write_region<ConcurrencyTag>(points, point_map, K, region, anchors_local, change, anchor_displacement,
                                                settings, progress, result, who);
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Enhances the model detail of a region of interest by `s` (Miao et al. 2007, Sect. 4.2). The model detail
  is the difference between the details of the surface and those of its smooth base surface `p~` (the
  balanced flow of `Balanced_flow_settings`), `sigma = delta - delta~`, `delta~ = f(K) p~`; the region's
  points move so that their details become `delta~ + s sigma`, in the least-squares sense of
  `scale_geometric_details`.

  With the whole model as region (the overload without `roi`) and no anchors named, the result is the exact
  solution `p~ + s (p - p~)`: it meets every detail equation, so no system is solved, and the cost is that
  of the normals, the Laplacian and the flow.
  With a partial region, its border is anchored where it is as `settings.border_anchoring` says, unless
  `point_is_constrained_map` names the anchors (kept where they are). The normals, Laplacian and base surface of a partial
  region are computed on its surroundings only (`settings.flow_margin`).

  Normals (for the flow) come from `normal_map` or are estimated (`estimate_oriented_normals`,
  18 neighbours). The parameters are those of `scale_geometric_details`, plus
  `normal_map`; `settings` also holds the flow's settings.

  \return the region and solver statistics; converts to `false` if the callback cancelled.
  \throws Invalid_input, Numerical_failure as `scale_geometric_details`.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/detail_scaling.md">Detail scaling and enhancement</a> (`doc/detail_scaling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Detail_manipulation_result enhance_geometric_details(PointRange& points, unsigned int k, const IndexRange& roi, double s,
                                                     const Detail_enhancement_settings& settings,
                                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::enhance_geometric_details_impl<ConcurrencyTag>(points, k, &roi, s, settings, np);
}

/// \cond SKIP_IN_MANUAL
// The whole model as region.
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Detail_manipulation_result enhance_geometric_details(PointRange& points, unsigned int k, double s,
                                                     const Detail_enhancement_settings& settings,
                                                     const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::enhance_geometric_details_impl<ConcurrencyTag>(points, k, static_cast<const std::vector<int>*>(nullptr),
                                                                  s, settings, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_ENHANCE_GEOMETRIC_DETAILS_H
