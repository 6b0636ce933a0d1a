// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H
#define CGAL_EXT_COMPUTE_SIMPLIFICATION_SAMPLE_POINTS_H

#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/compute_mean_shift_modes.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
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

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/parallel_for_each.h>
#endif

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  Settings of the clustering into simplification sample points (Miao et al. 2007, Sect. 5.2).

  A cluster is split in two while it holds more than the maximum cluster size, or while the spread of its
  members' mean-shift modes exceeds `mode_spread_threshold`: the largest distance of a member's mode (range
  part: normal and scaled curvature) from the members' mean mode, in range bandwidths.

  The maximum cluster size is `max_cluster_size` when set, else `ceil(n / target_count)`, so that the count
  lands between `target_count` and about twice it (more where the modes spread); with `n <= target_count`
  every point is its own sample point.
*/
struct Simplification_settings
{
  std::optional<std::size_t> max_cluster_size; ///< >= 1 when set (the paper's typical value: 50)
  std::size_t target_count = 4000;             ///< >= 1; used when `max_cluster_size` is not set
  /// In range bandwidths, > 0; infinity splits by size only and skips the mean shift.
  double mode_spread_threshold = 1.0;
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
    if(mean_shift_neighbors < 5)
      throw Invalid_input("simplification settings: mean_shift_neighbors must be at least 5 (the curvature fit's minimum)");
    mean_shift.validate();
  }

  /// The maximum cluster size for `n` points.
  std::size_t cluster_size_for(std::size_t n) const
  {
    if(max_cluster_size) return *max_cluster_size;
    return n <= target_count ? 1 : (n + target_count - 1) / target_count;
  }
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
  std::size_t max_cluster_size = 0; ///< the maximum cluster size used
  Mean_shift_result mean_shift;     ///< `completed` is false where no mean shift ran

  std::size_t size() const { return samples.size(); }
  explicit operator bool() const { return completed; }
};

namespace internal {

/// When a cluster is split: by selection label first, then by size, then by the spread of its modes.
struct Cluster_split_rule
{
  std::size_t max_size = 1;
  const Matrix_n7* modes = nullptr; ///< normalised modes; null: no mode criterion
  double spread_threshold = std::numeric_limits<double>::infinity();
  const std::vector<int>* labels = nullptr; ///< per row; null: one selection
};

/// Recursive binary partition of the rows of `positions` (Pauly et al. 2002): a cluster that the rule
/// splits is cut by the plane through its centroid orthogonal to its principal axis. `order` is a
/// permutation of the rows in which every leaf is a contiguous range; the leaves' first positions are
/// returned in increasing order. The cuts depend on the data only, so any thread count gives the same leaves.
template <typename ConcurrencyTag>
std::vector<int> split_into_clusters(const Matrix_n3& positions, const Cluster_split_rule& rule, std::vector<int>& order)
{
  struct Range { int begin, end; };
  const int n = int(positions.rows());
  order.resize(std::size_t(n));
  for(int r = 0; r < n; ++r) order[std::size_t(r)] = r;
  std::vector<char> leaf_start(std::size_t(n), 0);
  const double spread2 = rule.spread_threshold * rule.spread_threshold;

  // Splits [begin, end) once, or marks it a leaf; returns the number of children written to `children`.
  auto split = [&](Range range, Range children[2]) -> int {
    int* first = order.data() + range.begin;
    int* last = order.data() + range.end;
    const std::size_t size = std::size_t(range.end - range.begin);
    int* middle = nullptr;
    if(rule.labels && size > 1) {
      const std::vector<int>& labels = *rule.labels;
      const int label = labels[std::size_t(*first)];
      if(std::any_of(first, last, [&](int r) { return labels[std::size_t(r)] != label; }))
        middle = std::partition(first, last, [&](int r) { return labels[std::size_t(r)] == label; });
    }
    if(!middle && size > 1) {
      Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
      for(const int* r = first; r != last; ++r) centroid += positions.row(*r);
      centroid /= double(size);
      bool cut = size > rule.max_size;
      if(!cut && rule.modes) {
        Eigen::Matrix<double, 1, 4> mean = Eigen::Matrix<double, 1, 4>::Zero();
        for(const int* r = first; r != last; ++r) mean += rule.modes->row(*r).tail<4>();
        mean /= double(size);
        for(const int* r = first; r != last && !cut; ++r) cut = (rule.modes->row(*r).tail<4>() - mean).squaredNorm() > spread2;
      }
      if(cut) {
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for(const int* r = first; r != last; ++r) {
          const Eigen::RowVector3d d = positions.row(*r) - centroid;
          covariance.noalias() += d.transpose() * d;
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
        eigen.computeDirect(covariance);
        const Eigen::RowVector3d axis = eigen.eigenvectors().col(2).transpose();
        middle = std::partition(first, last, [&](int r) { return (positions.row(r) - centroid).dot(axis) < 0; });
        if(middle == first || middle == last) middle = first + size / 2; // coincident points: halve
      }
    }
    if(!middle) {
      leaf_start[std::size_t(range.begin)] = 1;
      return 0;
    }
    const int cut_at = int(middle - order.data());
    children[0] = {range.begin, cut_at};
    children[1] = {cut_at, range.end};
    return 2;
  };
  // Depth-first with an explicit stack: a chain of lopsided cuts must not overflow the call stack.
  auto split_all = [&](Range range, auto&& hand_off) {
    std::vector<Range> stack{range};
    while(!stack.empty()) {
      const Range r = stack.back();
      stack.pop_back();
      Range children[2];
      const int count = split(r, children);
      for(int c = count - 1; c >= 0; --c)
        if(!hand_off(children[c])) stack.push_back(children[c]);
    }
  };
  if(n > 0) {
#ifdef CGAL_LINKED_WITH_TBB
    if constexpr(is_parallel<ConcurrencyTag>()) {
      constexpr int grain = 1 << 14; // clusters at least this large become tasks of their own
      std::vector<Range> roots{{0, n}};
      tbb::parallel_for_each(roots.begin(), roots.end(), [&](Range root, tbb::feeder<Range>& feeder) {
        split_all(root, [&](Range child) {
          if(child.end - child.begin < grain) return false;
          feeder.add(child);
          return true;
        });
      });
    } else
#endif
    {
      split_all(Range{0, n}, [](Range) { return false; });
    }
  }
  std::vector<int> leaves;
  for(int s = 0; s < n; ++s)
    if(leaf_start[std::size_t(s)]) leaves.push_back(s);
  return leaves;
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
  result.max_cluster_size = settings.cluster_size_for(n);
  Progress progress(callback);
  Matrix_n3 normals;
  const bool given_normals = has_given_normals<NamedParameters>(points);
  progress.stage(0.0, given_normals ? 0.0 : 0.3);
  if(!given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress, normals, who))
    return result;

  Cluster_split_rule rule;
  rule.max_size = result.max_cluster_size;
  std::vector<int> labels;
  if constexpr(!std::is_same<LabelMap, No_labels>::value) {
    labels.resize(n);
    std::size_t i = 0;
    const std::vector<int> row_of = cloud.spatial_index();
    for(const auto& item : points) labels[std::size_t(row_of[i++])] = int(get(label_map, item));
    rule.labels = &labels;
  }
  // Modes matter only where a cluster of several points may be split for its spread; the curvature fit needs
  // 5 neighbours, so a set of fewer than 6 points is split by size only.
  Mean_shift_analysis analysis;
  const std::size_t k = std::min<std::size_t>(settings.mean_shift_neighbors, n - 1);
  if(rule.max_size > 1 && std::isfinite(settings.mode_spread_threshold) && k >= 5) {
    progress.stage(given_normals ? 0.0 : 0.3, 0.9);
    if(!analyse_mean_shift<ConcurrencyTag>(cloud, normals, k, settings.mean_shift, progress, analysis)) return result;
    result.mean_shift = summarize(analysis, settings.mean_shift);
    rule.modes = &analysis.modes;
    rule.spread_threshold = settings.mode_spread_threshold;
  }
  progress.stage(0.9, 1.0);
  if(!progress.report(0.0)) return result;
  std::vector<int> order;
  const std::vector<int> leaves = split_into_clusters<ConcurrencyTag>(cloud.positions, rule, order);
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

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_CLUSTER_SPLIT_INSTANCES(EXTERN, Tag) \
  EXTERN template std::vector<int> split_into_clusters<Tag>(const Matrix_n3&, const Cluster_split_rule&, \
                                                            std::vector<int>&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_CLUSTER_SPLIT_INSTANCES)

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Clusters the points into simplification sample points (Miao et al. 2007, Sect. 5.2): a recursive binary
  split of each cluster by the plane through its centroid orthogonal to its principal axis, while the
  cluster holds more than the maximum cluster size or its members' mean-shift modes
  (`compute_mean_shift_modes`) spread more than `settings.mode_spread_threshold`. Each leaf becomes a surfel.
  Since the modes' range part holds the normal and the mean curvature, sample points come out dense where
  the surface bends and sparse on flat parts, and do not straddle sharp edges.

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
