// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_SIMPLIFICATION_SETTINGS_H
#define CGAL_EXT_SIMPLIFICATION_SETTINGS_H

#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/exceptions.h>

#include <cmath>
#include <cstddef>
#include <optional>
#include <sstream>
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
  Mean_shift_settings mean_shift = range_part_mean_shift_settings(); ///< the modes' range parts decide the splits

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

} // namespace CGAL_ext

#endif // CGAL_EXT_SIMPLIFICATION_SETTINGS_H
