// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_ENHANCE_GEOMETRIC_DETAILS_H
#define CGAL_EXT_ENHANCE_GEOMETRIC_DETAILS_H

#include <CGAL_ext/Balanced_flow_settings.h>
#include <CGAL_ext/internal/balanced_flow.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/scale_geometric_details.h>

#include <numeric>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of detail enhancement: those of scaling plus the balanced flow of the base surface.
*/
struct Detail_enhancement_settings : Detail_scaling_settings
{
  Balanced_flow_settings flow;
  /// Fraction of the points anchored by default when the region is the whole model.
  double default_anchor_fraction = 0.01;

  Detail_enhancement_settings(const Detail_filter& filter = {}) : Detail_scaling_settings(filter) {}
  Detail_enhancement_settings(const Detail_scaling_settings& s, const Balanced_flow_settings& f = {})
    : Detail_scaling_settings(s), flow(f) {}

  void validate() const
  {
    Detail_scaling_settings::validate();
    flow.validate();
    if(!(default_anchor_fraction > 0 && default_anchor_fraction <= 1))
      throw Invalid_input("detail enhancement: default_anchor_fraction must be in (0, 1]");
  }
};

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

  const Region region = make_region<ConcurrencyTag>(points, point_map, k, roi_indices, who);
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
  const Matrix_n3 base = balanced_flow_base_surface<ConcurrencyTag>(K, cloud.positions, normals, settings.flow);
  const Matrix_n3 detail_offset = cloud.positions - base;
  const Matrix_n3 change = (s - 1.0) * apply_detail_filter<ConcurrencyTag>(K, settings.details.filter, detail_offset);
  progress.stage(0.5, 1.0);
  if(!progress.report(0.0)) return {};

  Detail_manipulation_result result;
  std::vector<int> anchors_local =
    region_anchors(points, static_cast<const std::vector<int>*>(nullptr), np, region, result.default_anchors, who);
  Matrix_n3 anchor_displacement = Matrix_n3::Zero(Eigen::Index(anchors_local.size()), 3);
  if(result.default_anchors) {
    if(roi.size() == cloud.size()) {
      // No outside to hold the region: anchor a uniform subset at the exact solution p~ + s (p - p~), plus one
      // point of every separate piece (a scan's stray cluster) that the subset missed.
      anchors_local = uniform_subset(K, cloud.positions, roi, settings.default_anchor_fraction);
      for(const Unpinned_part& part : unpinned_parts(K, roi, in_roi, anchors_local)) anchors_local.push_back(part.first);
      std::sort(anchors_local.begin(), anchors_local.end());
      anchor_displacement.resize(Eigen::Index(anchors_local.size()), 3);
      for(std::size_t a = 0; a < anchors_local.size(); ++a)
        anchor_displacement.row(Eigen::Index(a)) = (s - 1.0) * detail_offset.row(roi[std::size_t(anchors_local[a])]);
    } else {
      if(settings.anchors_border()) anchors_local = region_border(K, roi, in_roi);
      anchor_displacement.setZero(Eigen::Index(anchors_local.size()), 3);
    }
  }
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

  With the whole model as region (the overload without `roi`), nothing outside holds the shape, so a
  spatially uniform subset of about `default_anchor_fraction` of the points (and one point of every separate
  piece the subset misses) is anchored at the exact solution's value there, `p~ + s (p - p~)`; the result is then that exact solution, to solver precision.
  With a partial region, its border is anchored where it is as `settings.border_anchoring` says, unless
  `point_is_constrained_map` names the anchors (kept where they are).

  Normals (for the flow) come from `normal_map` or are estimated (jet fitting and
  `CGAL::mst_orient_normals`, 18 neighbours). The parameters are those of `scale_geometric_details`, plus
  `normal_map`; `settings` also holds the flow's settings.

  \return the region and solver statistics; converts to `false` if the callback cancelled.
  \throws Invalid_input, Numerical_failure as `scale_geometric_details`.
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
