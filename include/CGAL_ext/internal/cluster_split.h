// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_CLUSTER_SPLIT_H
#define CGAL_EXT_INTERNAL_CLUSTER_SPLIT_H

#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>
#include <vector>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for_each.h>
#endif

namespace CGAL_ext {
namespace internal {

/// When a cluster is split: by selection label always; then either the paper's rule (`target_count` 0: while
/// larger than `max_size` or while its modes spread more than `spread_threshold`) or a budget (`target_count`
/// > 0: the largest clusters until there are `target_count`, then those whose modes spread most, until
/// `(1 + variation_budget) target_count`).
struct Cluster_split_rule
{
  std::size_t max_size = 1;
  std::size_t target_count = 0;
  double variation_budget = 0.5;
  const Matrix_n7* modes = nullptr; ///< normalised modes; null: no mode criterion
  double spread_threshold = std::numeric_limits<double>::infinity();
  const std::vector<int>* labels = nullptr; ///< per row; null: one selection
};

/// What the budgeted rule did: clusters after the label and size splits, and how many the mode-spread rule
/// would have made without a budget (the final count when it was not capped).
struct Cluster_split_counts
{
  std::size_t after_size = 0;
  std::size_t requested = 0;
};

/*
  Binary partition of the rows of `positions` (Pauly et al. 2002): a cluster that the rule splits is cut by the
  plane through its centroid orthogonal to its principal axis. `order` is a permutation of the rows in which
  every leaf is a contiguous range; the leaves' first positions are returned in increasing order. The cuts depend
  on the data only, so any thread count gives the same leaves.

  With a budget, the mode-spread splits go to the clusters with the largest scatter of modes (the sum of their
  members' squared distances from the mean mode) first: on a mesh split at its edges' midpoints, sharp creases
  and the curvature noise of the split triangles make almost every cluster spread, and the paper's rule then
  made 28 times the target (doc/simplification.md, "A bounded count").
*/
template <typename ConcurrencyTag>
std::vector<int> split_into_clusters(const Matrix_n3& positions, const Cluster_split_rule& rule, std::vector<int>& order,
                                     Cluster_split_counts* counts = nullptr)
{
  struct Range { int begin, end; };
  const int n = int(positions.rows());
  order.resize(std::size_t(n));
  for(int r = 0; r < n; ++r) order[std::size_t(r)] = r;
  const double spread2 = rule.spread_threshold * rule.spread_threshold;
  const bool budgeted = rule.target_count > 0;

  auto principal_cut = [&](Range range) {
    int* first = order.data() + range.begin;
    int* last = order.data() + range.end;
    const std::size_t size = std::size_t(range.end - range.begin);
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for(const int* r = first; r != last; ++r) centroid += positions.row(*r);
    centroid /= double(size);
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for(const int* r = first; r != last; ++r) {
      const Eigen::RowVector3d d = positions.row(*r) - centroid;
      covariance.noalias() += d.transpose() * d;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(covariance);
    const Eigen::RowVector3d axis = eigen.eigenvectors().col(2).transpose();
    int* middle = std::partition(first, last, [&](int r) { return (positions.row(r) - centroid).dot(axis) < 0; });
    if(middle != first && middle != last) return middle;
    // No side (rounding, or coinciding points): halve in the order of position, never between coinciding points,
    // which stay one cluster whatever the caller's order (doc/design.md, "One neighbourhood rule").
    const auto coincide = [&](int a, int b) { return positions.row(a) == positions.row(b); };
    std::sort(first, last, [&](int a, int b) {
      for(int c = 0; c < 3; ++c)
        if(positions(a, c) != positions(b, c)) return positions(a, c) < positions(b, c);
      return a < b;
    });
    middle = first + size / 2;
    while(middle != last && coincide(*(middle - 1), *middle)) ++middle;
    if(middle == last)
      for(middle = first + size / 2; middle != first && coincide(*(middle - 1), *middle);) --middle;
    return middle == first ? nullptr : middle; // null: every point coincides, no cut
  };
  // Whether the members' modes spread beyond the threshold, and their scatter (the budget's priority).
  auto mode_spread = [&](Range range) {
    const std::size_t size = std::size_t(range.end - range.begin);
    if(!rule.modes || size < 2) return std::make_pair(false, 0.0);
    const int* first = order.data() + range.begin;
    const int* last = order.data() + range.end;
    Eigen::Matrix<double, 1, 4> mean = Eigen::Matrix<double, 1, 4>::Zero();
    for(const int* r = first; r != last; ++r) mean += rule.modes->row(*r).tail<4>();
    mean /= double(size);
    double largest = 0, scatter = 0;
    for(const int* r = first; r != last; ++r) {
      const double d2 = (rule.modes->row(*r).tail<4>() - mean).squaredNorm();
      largest = std::max(largest, d2);
      scatter += d2;
    }
    return std::make_pair(largest > spread2, scatter);
  };
  // Splits where `wanted` says; the labels first, always. Returns the cut, or null for a leaf.
  auto decide = [&](Range range, auto&& wanted) -> int* {
    int* first = order.data() + range.begin;
    int* last = order.data() + range.end;
    if(last - first < 2) return nullptr;
    if(rule.labels) {
      const std::vector<int>& labels = *rule.labels;
      const int label = labels[std::size_t(*first)];
      if(std::any_of(first, last, [&](int r) { return labels[std::size_t(r)] != label; }))
        return std::partition(first, last, [&](int r) { return labels[std::size_t(r)] == label; });
    }
    return wanted(range) ? principal_cut(range) : nullptr;
  };
  // Splits every range of `roots` while `wanted`, depth first, in parallel; returns the leaves.
  auto split_recursively = [&](const std::vector<Range>& roots, auto&& wanted) {
    auto split_all = [&](Range root, auto&& hand_off, std::vector<Range>& leaves) {
      std::vector<Range> stack{root};
      while(!stack.empty()) { // an explicit stack: a chain of lopsided cuts must not overflow the call stack
        const Range r = stack.back();
        stack.pop_back();
        int* middle = decide(r, wanted);
        if(!middle) {
          leaves.push_back(r);
          continue;
        }
        const int cut_at = int(middle - order.data());
        for(const Range child : {Range{cut_at, r.end}, Range{r.begin, cut_at}})
          if(!hand_off(child)) stack.push_back(child);
      }
    };
    std::vector<Range> leaves;
#ifdef CGAL_LINKED_WITH_TBB
    if constexpr(is_parallel<ConcurrencyTag>()) {
      constexpr int grain = 1 << 14; // clusters at least this large become tasks of their own
      tbb::enumerable_thread_specific<std::vector<Range>> found;
      tbb::parallel_for_each(roots.begin(), roots.end(), [&](Range root, tbb::feeder<Range>& feeder) {
        split_all(root, [&](Range child) {
          if(child.end - child.begin < grain) return false;
          feeder.add(child);
          return true;
        }, found.local());
      });
      for(const auto& part : found) leaves.insert(leaves.end(), part.begin(), part.end());
    } else
#endif
    {
      for(const Range root : roots) split_all(root, [](Range) { return false; }, leaves);
    }
    return leaves;
  };
  auto first_positions = [&](const std::vector<Range>& leaves) {
    std::vector<int> starts;
    starts.reserve(leaves.size());
    for(const Range r : leaves) starts.push_back(r.begin);
    std::sort(starts.begin(), starts.end());
    return starts;
  };
  if(n == 0) return {};

  if(!budgeted) {
    const std::vector<Range> leaves = split_recursively({Range{0, n}}, [&](Range r) {
      return std::size_t(r.end - r.begin) > rule.max_size || mode_spread(r).first;
    });
    if(counts) *counts = {leaves.size(), leaves.size()};
    return first_positions(leaves);
  }

  // Sizes: a parallel first pass down to four times the average cluster, then the largest cluster first until
  // the target. Ties go to the first range, so the leaves stay independent of the threads.
  const std::size_t target = std::min<std::size_t>(rule.target_count, std::size_t(n));
  const std::size_t coarse = 4 * ((std::size_t(n) + target - 1) / target);
  std::vector<Range> leaves =
    split_recursively({Range{0, n}}, [&](Range r) { return std::size_t(r.end - r.begin) > coarse; });
  auto size_order = [](const Range& a, const Range& b) {
    return std::make_tuple(a.end - a.begin, -a.begin) < std::make_tuple(b.end - b.begin, -b.begin);
  };
  std::priority_queue<Range, std::vector<Range>, decltype(size_order)> largest(size_order, std::move(leaves));
  std::size_t count = largest.size();
  leaves.clear(); // now the clusters of coinciding points, which no cut divides
  while(count < target && !largest.empty() && largest.top().end - largest.top().begin > 1) {
    const Range r = largest.top();
    largest.pop();
    const int* cut = principal_cut(r);
    if(!cut) {
      leaves.push_back(r);
      continue;
    }
    const int cut_at = int(cut - order.data());
    largest.push({r.begin, cut_at});
    largest.push({cut_at, r.end});
    ++count;
  }
  for(; !largest.empty(); largest.pop()) leaves.push_back(largest.top());
  const std::size_t after_size = leaves.size();

  // Mode spread, within the budget: the clusters with the largest scatter first.
  struct Candidate { double scatter; Range range; };
  auto scatter_order = [](const Candidate& a, const Candidate& b) {
    return std::make_tuple(a.scatter, -a.range.begin) < std::make_tuple(b.scatter, -b.range.begin);
  };
  std::priority_queue<Candidate, std::vector<Candidate>, decltype(scatter_order)> spread(scatter_order);
  std::vector<Range> settled;
  auto consider = [&](Range r) {
    const auto [spreads, scatter] = mode_spread(r);
    if(spreads) spread.push({scatter, r});
    else settled.push_back(r);
  };
  for(const Range r : leaves) consider(r);
  const std::size_t budget =
    std::max(after_size, std::size_t(std::ceil((1 + rule.variation_budget) * double(rule.target_count))));
  while(!spread.empty() && settled.size() + spread.size() < budget) {
    const Range r = spread.top().range;
    spread.pop();
    const int* cut = principal_cut(r);
    if(!cut) {
      settled.push_back(r);
      continue;
    }
    const int cut_at = int(cut - order.data());
    consider({r.begin, cut_at});
    consider({cut_at, r.end});
  }
  // What the rule asked for: the capped clusters split on without a budget (in place: a split permutes rows only
  // within its range, so the ranges kept stay the same sets of rows).
  std::vector<Range> capped;
  for(; !spread.empty(); spread.pop()) capped.push_back(spread.top().range);
  const std::size_t kept = settled.size() + capped.size();
  std::size_t requested = kept;
  if(!capped.empty())
    requested += split_recursively(capped, [&](Range r) { return mode_spread(r).first; }).size() - capped.size();
  if(counts) *counts = {after_size, requested};
  settled.insert(settled.end(), capped.begin(), capped.end());
  return first_positions(settled);
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_CLUSTER_SPLIT_INSTANCES(EXTERN, Tag) \
  EXTERN template std::vector<int> split_into_clusters<Tag>(const Matrix_n3&, const Cluster_split_rule&, \
                                                            std::vector<int>&, Cluster_split_counts*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_CLUSTER_SPLIT_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_CLUSTER_SPLIT_H
