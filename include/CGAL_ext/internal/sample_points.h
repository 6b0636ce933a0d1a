// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_SAMPLE_POINTS_H
#define CGAL_EXT_INTERNAL_SAMPLE_POINTS_H

#include <CGAL_ext/Simplification_settings.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/cluster_split.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <vector>

namespace CGAL_ext {
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

/// One surfel per cluster of `split_into_clusters` (`order`, `leaves`): the centroid, the covariance normal
/// oriented like the members' normals, the radius and the members as input indices.
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

/// The clustering of `compute_simplification_sample_points` on a cloud with its oriented normals: the split
/// rule of `settings`, the mean-shift modes when the rule uses them (analysed into `analysis` unless it holds
/// them already), the split and one surfel per cluster. `labels` (per row, or null) keep
/// selections apart; `order` receives the rows cluster by cluster. Returns false when cancelled.
template <typename Kernel, typename ConcurrencyTag>
bool cluster_into_sample_points(const Spatial_point_cloud& cloud, const Matrix_n3& normals,
                                const Simplification_settings& settings, const std::vector<int>* labels,
                                Progress& progress, Mean_shift_analysis& analysis, std::vector<int>& order,
                                Simplification_sample_points<Kernel>& out)
{
  const std::size_t n = cloud.size();
  bool needs_modes = false;
  Cluster_split_rule rule = split_rule_for(settings, n, needs_modes);
  rule.labels = labels;
  const Progress::Range whole = progress.range();
  if(needs_modes) {
    if(!analysis.analysed) {
      progress.stage(whole.begin, whole.at(0.9));
      const std::size_t k = std::min<std::size_t>(settings.mean_shift_neighbors, n - 1);
      if(!analyse_mean_shift<ConcurrencyTag>(cloud, normals, k, settings.mean_shift, progress, analysis)) return false;
      analysis.analysed = true;
    }
    rule.modes = &analysis.modes;
  }
  progress.stage(whole.at(0.9), whole.end);
  if(!progress.report(0.0)) return false;
  Cluster_split_counts counts;
  const std::vector<int> leaves = split_into_clusters<ConcurrencyTag>(cloud.positions, rule, order, &counts);
  out.max_cluster_size = largest_cluster(leaves, n);
  out.size_split_count = counts.after_size;
  out.requested_count = counts.requested;
  make_surfels<Kernel, ConcurrencyTag>(cloud, normals, order, leaves, out);
  return progress.report(1.0);
}

/// An edit's sample points as arrays: each one's position, normal, label (that of its members, which share one)
/// and a member row (for messages), and per point row its sample point.
struct Edit_sample_points
{
  Matrix_n3 positions, normals;
  std::vector<int> labels, first_rows, of_row;
  std::size_t requested_count = 0; ///< what the mode-spread rule asked for

  std::size_t size() const { return labels.size(); }

  /// A member of each sample point, as an input index (`input_index` per row), to name it in messages.
  std::vector<int> input_points(const std::vector<int>& input_index) const
  {
    std::vector<int> points(size());
    for(std::size_t s = 0; s < size(); ++s) points[s] = input_index[std::size_t(first_rows[s])];
    return points;
  }
};

/// `cluster_into_sample_points` of the cloud with the edit's `labels` (per row) kept apart, as arrays.
template <typename ConcurrencyTag>
bool cluster_edit_sample_points(const Spatial_point_cloud& cloud, const Matrix_n3& normals,
                                const Simplification_settings& settings, const std::vector<int>& labels,
                                Progress& progress, Mean_shift_analysis& analysis, Edit_sample_points& out)
{
  using Kernel = CGAL::Simple_cartesian<double>;
  std::vector<int> order;
  Simplification_sample_points<Kernel> clusters;
  if(!cluster_into_sample_points<Kernel, ConcurrencyTag>(cloud, normals, settings, &labels, progress, analysis, order,
                                                         clusters))
    return false;
  const std::size_t count = clusters.size();
  out.requested_count = clusters.requested_count;
  out.positions.resize(Eigen::Index(count), 3);
  out.normals.resize(Eigen::Index(count), 3);
  out.labels.resize(count);
  out.first_rows.resize(count);
  out.of_row.assign(cloud.size(), -1);
  for(std::size_t s = 0; s < count; ++s) {
    const auto& cluster = clusters.samples[s];
    out.positions.row(Eigen::Index(s)) << cluster.centroid.x(), cluster.centroid.y(), cluster.centroid.z();
    out.normals.row(Eigen::Index(s)) << cluster.normal.x(), cluster.normal.y(), cluster.normal.z();
    const int first = order[cluster.first_member];
    out.first_rows[s] = first;
    out.labels[s] = labels[std::size_t(first)];
    for(std::size_t m = 0; m < cluster.member_count; ++m) out.of_row[std::size_t(order[cluster.first_member + m])] = int(s);
  }
  return true;
}

/// The mean-shift modes that the clustering of `settings` uses, analysed into `analysis` unless it holds them
/// already; nothing when the clustering uses none. Returns false when cancelled.
template <typename ConcurrencyTag>
bool analyse_modes_once(const Spatial_point_cloud& cloud, const Matrix_n3& normals,
                        const Simplification_settings& settings, Progress& progress, Mean_shift_analysis& analysis)
{
  bool needs_modes = false;
  split_rule_for(settings, cloud.size(), needs_modes);
  if(!needs_modes || analysis.analysed) return true;
  const std::size_t k = std::min<std::size_t>(settings.mean_shift_neighbors, cloud.size() - 1);
  analysis.analysed = analyse_mean_shift<ConcurrencyTag>(cloud, normals, k, settings.mean_shift, progress, analysis);
  return analysis.analysed;
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_SAMPLE_POINTS_H
