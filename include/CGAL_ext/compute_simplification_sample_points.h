// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H
#define CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H

#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/cluster_split.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of the clustering into simplification sample points (Miao et al. 2007, Sect. 5.2).

  Clusters are split in two by the plane through their centroid orthogonal to their principal axis. Points of
  different selections (editing's fixed part, region and handles) are always split apart. Then:

  - With `target_count` (the default): the largest clusters are split until there are `target_count`; then,
    among the clusters whose mean-shift modes spread more than `mode_spread_threshold` (the largest distance of
    a member's mode, range part: normal and scaled curvature, from the members' mean mode, in range
    bandwidths), those with the largest scatter of modes are split first, until there are
    `(1 + variation_budget) target_count`. The sample points gather where the surface bends, and their count
    stays within 1.5 times the target on any input (sharp creases, meshes split at their edges' midpoints,
    noisy scans), where the unbounded rule made up to 28 times as many. With `n <= target_count` every point
    is its own sample point.
  - With `max_cluster_size` set (the paper's rule): a cluster is split while it holds more points than that or
    while its modes spread more than the threshold, with no bound on the count.
*/
struct Simplification_settings
{
  std::optional<std::size_t> max_cluster_size; ///< >= 1 when set (the paper's typical value: 50)
  std::size_t target_count = 4000;             ///< >= 1; used when `max_cluster_size` is not set
  /// In range bandwidths, > 0; infinity splits by size only and skips the mean shift.
  double mode_spread_threshold = 1.0;
  /// With `target_count`: the mode-spread rule adds at most this fraction of `target_count` sample points, >= 0.
  double variation_budget = 0.5;
  unsigned int mean_shift_neighbors = default_mean_shift_neighbors; ///< candidates of the mean shift, >= 5
  Mean_shift_settings mean_shift;

  void validate() const
  {
    if(max_cluster_size && *max_cluster_size < 1)
      throw Invalid_input("simplification settings: max_cluster_size must be at least 1 (got 0)");
    if(target_count < 1) throw Invalid_input("simplification settings: target_count must be at least 1 (got 0)");
    if(!(mode_spread_threshold > 0) || std::isnan(mode_spread_threshold)) {
      std::ostringstream os;
      os << "simplification settings: mode_spread_threshold must be > 0 (got " << mode_spread_threshold
         << "; infinity disables the mode criterion)";
      throw Invalid_input(os.str());
    }
    if(!(variation_budget >= 0 && std::isfinite(variation_budget)))
      throw Invalid_input("simplification settings: variation_budget must be a finite number >= 0");
    if(mean_shift_neighbors < 5)
      throw Invalid_input("simplification settings: mean_shift_neighbors must be at least 5 (the curvature fit's minimum)");
    mean_shift.validate();
  }

  /// The maximum cluster size for `n` points under the paper's rule (1 when every point is its own sample point).
  std::size_t cluster_size_for(std::size_t n) const
  {
    if(max_cluster_size) return *max_cluster_size;
    return n <= target_count ? 1 : (n + target_count - 1) / target_count;
  }

  /// Whether the count is budgeted (`target_count`, with more points than the target).
  bool budgeted_for(std::size_t n) const { return !max_cluster_size && n > target_count; }
};

/*!
  \ingroup PkgCGALExtRef
  A simplification sample point (SSP) as a surfel: the centroid of its cluster, the cluster's covariance
  normal oriented like its members' normals (their mean normal below three members), its radius (the
  largest distance of a member from the centroid) and its members.
*/
template <typename Kernel>
struct Simplification_sample_point
{
  typename Kernel::Point_3 centroid;
  typename Kernel::Vector_3 normal;
  typename Kernel::FT radius{0};
  std::size_t first_member = 0; ///< its members are `members[first_member, first_member + member_count)`
  std::size_t member_count = 0;
};

/*!
  \ingroup PkgCGALExtRef
  The simplification sample points of a point set, in a spatially coherent order, and their members as
  indices into the input range (increasing within a sample point). Every input point is a member of exactly one.
*/
template <typename Kernel>
struct Simplification_sample_points
{
  bool completed = false; ///< false when the callback cancelled
  std::vector<Simplification_sample_point<Kernel>> samples;
  std::vector<std::size_t> members;
  std::size_t max_cluster_size = 0; ///< the largest cluster
  /// Sample points after the selection and size splits (with `target_count`; else the final count).
  std::size_t size_split_count = 0;
  /// Sample points the mode-spread rule asked for: above `size()` when the budget capped it.
  std::size_t requested_count = 0;
  Mean_shift_result mean_shift;     ///< `completed` is false where no mean shift ran

  std::size_t size() const { return samples.size(); }
  explicit operator bool() const { return completed; }
};

namespace internal {

/// The split rule of `settings` for `n` points, without modes and labels; `needs_modes` says whether the
/// mean shift is worth running (some cluster of several points may be split for its spread; the curvature
/// fit needs 5 neighbours, so a set of fewer than 6 points is split by size only).
inline Cluster_split_rule split_rule_for(const Simplification_settings& settings, std::size_t n, bool& needs_modes)
{
  Cluster_split_rule rule;
  rule.max_size = settings.cluster_size_for(n);
  if(settings.budgeted_for(n)) {
    rule.target_count = settings.target_count;
    rule.variation_budget = settings.variation_budget;
  }
  needs_modes = rule.max_size > 1 && std::isfinite(settings.mode_spread_threshold) &&
                std::min<std::size_t>(settings.mean_shift_neighbors, n - 1) >= 5;
  if(needs_modes) rule.spread_threshold = settings.mode_spread_threshold;
  return rule;
}

/// The largest leaf of `split_into_clusters`.
inline std::size_t largest_cluster(const std::vector<int>& leaves, std::size_t n)
{
  std::size_t largest = 0;
  for(std::size_t s = 0; s < leaves.size(); ++s)
    largest = std::max(largest, std::size_t((s + 1 < leaves.size() ? std::size_t(leaves[s + 1]) : n) - std::size_t(leaves[s])));
  return largest;
}

template <typename Kernel, typename ConcurrencyTag>
void make_surfels(const Spatial_point_cloud& cloud, const Matrix_n3& normals, const std::vector<int>& order,
                  const std::vector<int>& leaves, Simplification_sample_points<Kernel>& out)
{
  using FT = typename Kernel::FT;
  const std::size_t count = leaves.size();
  out.samples.resize(count);
  out.members.resize(order.size());
  for_range<ConcurrencyTag>(0, count, [&](std::size_t s) {
    const int begin = leaves[s], end = s + 1 < count ? leaves[s + 1] : int(order.size());
    const double size = double(end - begin);
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero(), normal_sum = Eigen::RowVector3d::Zero();
    for(int m = begin; m < end; ++m) {
      centroid += cloud.positions.row(order[std::size_t(m)]);
      normal_sum += normals.row(order[std::size_t(m)]);
    }
    centroid /= size;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    double radius2 = 0;
    for(int m = begin; m < end; ++m) {
      const Eigen::RowVector3d d = cloud.positions.row(order[std::size_t(m)]) - centroid;
      covariance.noalias() += d.transpose() * d;
      radius2 = std::max(radius2, d.squaredNorm());
    }
    Eigen::RowVector3d normal = normal_sum;
    if(end - begin >= 3) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
      eigen.computeDirect(covariance);
      normal = eigen.eigenvectors().col(0).transpose();
      if(normal.dot(normal_sum) < 0) normal = -normal;
    }
    normal = normal.norm() > 0 ? Eigen::RowVector3d(normal.normalized()) : normals.row(order[std::size_t(begin)]);

    Simplification_sample_point<Kernel>& sample = out.samples[s];
    sample.centroid = typename Kernel::Point_3(FT(centroid(0)), FT(centroid(1)), FT(centroid(2)));
    sample.normal = typename Kernel::Vector_3(FT(normal(0)), FT(normal(1)), FT(normal(2)));
    sample.radius = FT(std::sqrt(radius2));
    sample.first_member = std::size_t(begin);
    sample.member_count = std::size_t(end - begin);
    for(int m = begin; m < end; ++m)
      out.members[std::size_t(m)] = std::size_t(cloud.input_index[std::size_t(order[std::size_t(m)])]);
    std::sort(out.members.begin() + begin, out.members.begin() + end);
  });
}

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

  bool needs_modes = false;
  Cluster_split_rule rule = split_rule_for(settings, n, needs_modes);
  std::vector<int> labels;
  if constexpr(!std::is_same<LabelMap, No_labels>::value) {
    labels.resize(n);
    std::size_t i = 0;
    const std::vector<int> row_of = cloud.spatial_index();
    for(const auto& item : points) labels[std::size_t(row_of[i++])] = int(get(label_map, item));
    rule.labels = &labels;
  }
  Mean_shift_analysis analysis;
  if(needs_modes) {
    progress.stage(given_normals ? 0.0 : 0.3, 0.9);
    const std::size_t k = std::min<std::size_t>(settings.mean_shift_neighbors, n - 1);
    if(!analyse_mean_shift<ConcurrencyTag>(cloud, normals, k, settings.mean_shift, progress, analysis)) return result;
    result.mean_shift = summarize(analysis, settings.mean_shift);
    rule.modes = &analysis.modes;
  }
  progress.stage(0.9, 1.0);
  if(!progress.report(0.0)) return result;
  std::vector<int> order;
  Cluster_split_counts counts;
  const std::vector<int> leaves = split_into_clusters<ConcurrencyTag>(cloud.positions, rule, order, &counts);
  result.max_cluster_size = largest_cluster(leaves, n);
  result.size_split_count = counts.after_size;
  result.requested_count = counts.requested;
  make_surfels<Kernel, ConcurrencyTag>(cloud, normals, order, leaves, result);
  if(!progress.report(1.0)) return Simplification_sample_points<Kernel>{};

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
