// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H
#define CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H

#include <CGAL_ext/Simplification_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/sample_points.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <functional>
#include <type_traits>
#include <vector>

namespace CGAL_ext {
namespace internal {

struct No_labels {};

template <typename ConcurrencyTag, typename PointRange, typename LabelMap, typename SampleIndexMap, typename NamedParameters>
auto compute_simplification_sample_points_impl(const PointRange& points, LabelMap label_map,
                                               const Simplification_settings& settings, SampleIndexMap sample_index_map,
                                               const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  constexpr const char* who = "compute_simplification_sample_points";

  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  settings.validate();
  const Spatial_point_cloud cloud = make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  const std::size_t n = cloud.size();

  Simplification_sample_points<Kernel> result;
  Progress progress(callback);
  Matrix_n3 normals;
  const bool given_normals = has_given_normals<NamedParameters>(points);
  progress.stage(0.0, given_normals ? 0.0 : 0.3);
  if(!given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress, normals, who))
    return result;

  std::vector<int> labels;
  if constexpr(!std::is_same<LabelMap, No_labels>::value) {
    labels.resize(n);
    std::size_t i = 0;
    const std::vector<int> row_of = cloud.spatial_index();
    for(const auto& item : points) labels[std::size_t(row_of[i++])] = int(get(label_map, item));
  }
  progress.stage(given_normals ? 0.0 : 0.3, 1.0);
  Mean_shift_analysis analysis;
  std::vector<int> order;
  if(!cluster_into_sample_points<Kernel, ConcurrencyTag>(cloud, normals, settings, labels.empty() ? nullptr : &labels,
                                                         progress, analysis, order, result))
    return Simplification_sample_points<Kernel>{};
  if(analysis.analysed) result.mean_shift = summarize(analysis, settings.mean_shift);

  std::vector<std::size_t> sample_of(n);
  for(std::size_t s = 0; s < result.samples.size(); ++s)
    for(std::size_t m = 0; m < result.samples[s].member_count; ++m) sample_of[result.members[result.samples[s].first_member + m]] = s;
  std::size_t i = 0;
  for(const auto& item : points) put(sample_index_map, item, sample_of[i++]);
  result.completed = true;
  return result;
}

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Clusters the points into simplification sample points (Miao et al. 2007, Sect. 5.2): a binary split of
  each cluster by the plane through its centroid orthogonal to its principal axis, by size and where its
  members' mean-shift modes (`compute_mean_shift_modes`) spread more than `settings.mode_spread_threshold`,
  within a budget of 1.5 times `settings.target_count` (or, with `max_cluster_size`, the paper's unbounded
  rule; `Simplification_settings`). Each leaf becomes a surfel. Since the modes' range part holds the normal
  and the mean curvature, sample points come out dense where the surface bends and sparse on flat parts, and
  do not straddle sharp edges.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same sample points.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.
  \tparam SampleIndexMap a model of `WritablePropertyMap` with value type `std::size_t`.

  \param points the input points; not modified
  \param settings cluster size (or target count), mode spread threshold and mean-shift settings
  \param sample_index_map receives, for every point, the index of its sample point in the result
  \param np `point_map`, `normal_map` (estimated by `estimate_oriented_normals`
         when absent), `callback` (false cancels; the map is then untouched) and
         `geom_traits`, as in `compute_geometric_details`

  \return the sample points; `completed` is false if the callback cancelled.
  \throws Invalid_input for an empty range, non-finite coordinates, invalid settings, a zero or non-finite
          normal, or (with the mode criterion) points that all coincide.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/simplification.md">Mean shift and simplification sample points</a> (`doc/simplification.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename SampleIndexMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
auto compute_simplification_sample_points(const PointRange& points, const Simplification_settings& settings,
                                          SampleIndexMap sample_index_map,
                                          const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::compute_simplification_sample_points_impl<ConcurrencyTag>(points, internal::No_labels(), settings,
                                                                             sample_index_map, np);
}

/*!
  \ingroup PkgCGALExtAlgorithms
  As above, with a selection known before the clustering (the fixed part, the deformable region, each handle
  of an edit): points whose labels differ never share a sample point.

  \tparam SelectionLabelMap a model of `ReadablePropertyMap` whose value type converts to `int`.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/simplification.md">Mean shift and simplification sample points</a> (`doc/simplification.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename SelectionLabelMap,
          typename SampleIndexMap, typename NamedParameters = CGAL::parameters::Default_named_parameters>
auto compute_simplification_sample_points(const PointRange& points, SelectionLabelMap selection_label_map,
                                          const Simplification_settings& settings, SampleIndexMap sample_index_map,
                                          const NamedParameters& np = CGAL::parameters::default_values())
{
  return internal::compute_simplification_sample_points_impl<ConcurrencyTag>(points, selection_label_map, settings,
                                                                             sample_index_map, np);
}

} // namespace CGAL_ext

#endif // CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H
