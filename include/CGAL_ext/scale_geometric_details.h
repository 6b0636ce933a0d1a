// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_SCALE_GEOMETRIC_DETAILS_H
#define CGAL_EXT_SCALE_GEOMETRIC_DETAILS_H

#include <CGAL_ext/Detail_scaling_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/detail_manipulation.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/geometric_details.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <cmath>
#include <functional>
#include <vector>

namespace CGAL_ext {

namespace internal {

template <typename ConcurrencyTag, typename PointRange, typename IndexRange, typename AnchorRange, typename NamedParameters>
Detail_manipulation_result scale_geometric_details_impl(PointRange& points, unsigned int k, const IndexRange& roi_indices,
                                                        const AnchorRange* anchors, double s,
                                                        const Detail_scaling_settings& settings, const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  constexpr const char* who = "scale_geometric_details";

  const auto point_map = NP_helper::get_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  if(!std::isfinite(s)) throw Invalid_input(std::string(who) + ": the scale factor s must be finite");
  settings.validate();

  const Region region = make_region<ConcurrencyTag>(points, point_map, k, &roi_indices, who);
  const Spatial_point_cloud& cloud = region.cloud;
  const std::vector<int>& roi = region.roi;
  const std::vector<char>& in_roi = region.in_roi;

  Progress progress(callback);
  Matrix_n3 normals; // only the mean-shift neighbourhoods need them
  if(settings.details.neighborhood == Laplacian_neighborhood::mean_shift) {
    progress.stage(0.0, 0.1);
    if(!given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress, normals, who))
      return {};
  }
  progress.stage(normals.rows() ? 0.1 : 0.0, 0.3);
  Sparse_row_matrix K;
  if(!detail_laplacian<ConcurrencyTag>(cloud, k, settings.details, normals, progress, K, who)) return {};

  Detail_manipulation_result result;
  std::vector<int> anchors_local = region_anchors(points, anchors, np, region, result.default_anchors, who);
  if(result.default_anchors) {
    if(roi.size() == cloud.size())
      throw Invalid_input(std::string(who) + ": the region of interest is the whole model and no anchors were given; "
                          "its scaled shape is then not pinned anywhere: give anchors (a range or point_is_constrained_map)");
    if(settings.anchors_border()) anchors_local = region_border(K, roi, in_roi);
  }
  progress.stage(0.3, 1.0);
  if(!progress.report(0.0)) return {};

  // delta' - delta = (s - 1) delta on the region; the anchors keep their positions.
  const auto change = [&] {
    return Matrix_n3((s - 1.0) * apply_detail_filter<ConcurrencyTag>(K, settings.details.filter, cloud.positions));
  };
  return solve_and_write_region<ConcurrencyTag>(points, point_map, K, region, anchors_local, change,
                                                Matrix_n3::Zero(Eigen::Index(anchors_local.size()), 3), settings,
                                                progress, result, who);
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Scales the high-frequency geometric details of a region of interest by `s` (Miao et al. 2007, Sect. 4.1):
  the region's points move so that their details become `s delta`, in the least-squares sense

  `min alpha sum_{i in ROI} ||(f(K) x)_i - s delta_i||^2 + sum_{a in anchors} ||x_a - p_a||^2`,

  where points outside the region stay fixed (their coefficients move to the right-hand side) and the
  anchors are soft position constraints of weight 1. The unknowns are the displacements, so `s = 1` returns
  the input exactly, and the result is affine in `s`: `x(s) = x(0) + s (p - x(0))`, with `x(0)` the smooth
  surface that the region's surroundings imply. A large region therefore scales its whole bulge, not only
  its small bumps.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`.
  \tparam PointRange a model of `Range` whose value type is the key type of the point map.
  \tparam IndexRange, AnchorRange ranges of integer indices into `points` (their order in the range).

  \param points the points; the region's points are moved in place (through `point_map`)
  \param k number of nearest neighbours of the Laplacian, `1 <= k < points.size()`
  \param roi indices of the region's points; repeats are ignored
  \param anchors indices of anchored points, all in the region. The overload without this argument takes
         them from `point_is_constrained_map`, or, without that either, anchors the region's border (its
         points with a neighbour outside it) as `settings.border_anchoring` says. Scaling the whole model
         needs anchors.
  \param s the scale factor (finite; 0 removes the details, 1 changes nothing, > 1 exaggerates them)
  \param settings transfer function, Laplacian weights and solver (a `Detail_filter` converts implicitly)
  \param np an optional sequence of named parameters among the ones listed below

  \cgalNamedParamsBegin
    \cgalParamNBegin{point_map}
      \cgalParamDescription{a readable and writable property map associating points to the elements of `points`}
      \cgalParamDefault{`CGAL::Identity_property_map<geom_traits::Point_3>`}
    \cgalParamNEnd
    \cgalParamNBegin{point_is_constrained_map}
      \cgalParamDescription{a property map with value type `bool`: `true` marks an anchor}
      \cgalParamDefault{the region's border}
    \cgalParamNEnd
    \cgalParamNBegin{callback}
      \cgalParamDescription{`std::function<bool(double)>` called with the progress in [0, 1]; returning `false`
                            cancels and leaves the points untouched}
    \cgalParamNEnd
    \cgalParamNBegin{geom_traits}
      \cgalParamDescription{an instance of a geometric traits class}
      \cgalParamDefault{a kernel deduced from the point type, using `CGAL::Kernel_traits`}
    \cgalParamNEnd
  \cgalNamedParamsEnd

  \return the region and solver statistics; converts to `false` if the callback cancelled.
  \throws Invalid_input for an empty region, an index out of range, an anchor outside the region, a part of
          the region that nothing pins, a whole-model region without anchors, a non-finite `s`, or the
          conditions of `compute_geometric_details`.
  \throws Numerical_failure when the factorisation or the iteration fails.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/detail_scaling.md">Detail scaling and enhancement</a> (`doc/detail_scaling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename AnchorRange, typename NamedParameters = CGAL::parameters::Default_named_parameters>
Detail_manipulation_result scale_geometric_details(PointRange& points, unsigned int k, const IndexRange& roi,
                                                   const AnchorRange& anchors, double s,
                                                   const Detail_scaling_settings& settings,
                                                   const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::scale_geometric_details_impl<ConcurrencyTag>(points, k, roi, &anchors, s, settings, np);
}

/// \cond SKIP_IN_MANUAL
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Detail_manipulation_result scale_geometric_details(PointRange& points, unsigned int k, const IndexRange& roi, double s,
                                                   const Detail_scaling_settings& settings,
                                                   const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::scale_geometric_details_impl<ConcurrencyTag>(points, k, roi, static_cast<const std::vector<int>*>(nullptr),
                                                                s, settings, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_SCALE_GEOMETRIC_DETAILS_H
