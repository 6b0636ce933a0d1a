// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_MEAN_SHIFT_H
#define CGAL_EXT_INTERNAL_MEAN_SHIFT_H

#include <CGAL_ext/Mean_shift_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/mean_curvature.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// n x 7 array: the normalised features `(x / h_s, n / h_r, c H / h_r)`, or modes in the same units.
using Matrix_n7 = Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor>;

/// Checks the candidate count of a mean shift (its curvature fit needs at least 5 neighbours).
inline void check_mean_shift_neighbors(std::size_t k, std::size_t n, const char* who)
{
  check_neighbor_count(k, n, who);
  if(k < 5)
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) +
                        " is too small: the curvature fit of the mean shift needs at least 5 neighbours");
}

/// The bandwidths and curvature scale actually used, after the automatic rules of `Mean_shift_settings`.
struct Mean_shift_scales
{
  double spatial_bandwidth = 0, range_bandwidth = 0, curvature_scale = 0;
};

/// Applies the automatic rules: the average spacing over `graph`, `c = 0.5 / H90`.
inline Mean_shift_scales resolve_scales(const Mean_shift_settings& settings, const Matrix_n3& positions,
                                        const Neighbor_graph& graph, const Eigen::VectorXd& curvature)
{
  Mean_shift_scales scales{settings.spatial_bandwidth, settings.range_bandwidth, settings.curvature_scale};
  if(scales.spatial_bandwidth == 0) {
    double sum = 0;
    std::size_t count = 0;
    for(std::size_t i = 0; i < graph.size(); ++i)
      for(const int* j = graph.begin(i); j != graph.end(i); ++j, ++count)
        sum += (positions.row(*j) - positions.row(Eigen::Index(i))).norm();
    scales.spatial_bandwidth = count > 0 ? sum / double(count) : 0;
    if(!(scales.spatial_bandwidth > 0))
      throw Invalid_input("mean shift: all points coincide, so the automatic spatial bandwidth (the average "
                          "spacing) is zero; remove duplicate points or set spatial_bandwidth");
  }
  if(scales.curvature_scale == 0) {
    std::vector<double> magnitude(std::size_t(curvature.size()));
    for(std::size_t i = 0; i < magnitude.size(); ++i) magnitude[i] = std::abs(curvature(Eigen::Index(i)));
    const auto p90 = magnitude.begin() + std::ptrdiff_t(0.9 * double(magnitude.size() - 1));
    std::nth_element(magnitude.begin(), p90, magnitude.end());
    scales.curvature_scale = 0.5 / std::max(*p90, 0.01 / scales.spatial_bandwidth);
  }
  return scales;
}

inline Matrix_n7 mean_shift_features(const Matrix_n3& positions, const Matrix_n3& normals,
                                     const Eigen::VectorXd& curvature, const Mean_shift_scales& scales)
{
  Matrix_n7 features(positions.rows(), 7);
  features.leftCols<3>() = positions / scales.spatial_bandwidth;
  features.middleCols(3, 3) = normals / scales.range_bandwidth;
  features.col(6) = curvature * (scales.curvature_scale / scales.range_bandwidth);
  return features;
}

/// The joint spatial-range mean shift of every feature row. The candidates of a moving mode are the
/// sample nearest to it (its anchor, at first the point itself) and the anchor's neighbours in `graph`;
/// after each step the anchor moves to the candidate nearest to the new mode, a walk on the graph that
/// follows the mode without querying the tree again. Rows are independent, so any thread count gives the
/// same modes. Returns false when cancelled.
template <typename ConcurrencyTag>
bool mean_shift_modes(const Matrix_n7& features, const Neighbor_graph& graph, const Mean_shift_settings& settings,
                      Progress& progress, Matrix_n7& modes, std::vector<int>& iterations)
{
  const std::size_t n = std::size_t(features.rows());
  modes.resize(features.rows(), 7);
  iterations.assign(n, 0);
  const bool gaussian = settings.kernel == Mean_shift_kernel::gaussian;
  const double tolerance2 = settings.tolerance * settings.tolerance;
  const int measured_from = settings.stop == Mean_shift_stop::range_part ? 3 : 0; // the coordinates the stop measures
  // Plain arrays of seven, not Eigen's small expressions: the same time in a Release build, half of it under
  // the sanitizers, where each expression's temporary is a checked copy (doc/build_time.md).
  const double* f = features.data();
  auto squared_distance = [](const double* a, const double* b, int from, int to) {
    double d2 = 0;
    for(int c = from; c < to; ++c) d2 += (a[c] - b[c]) * (a[c] - b[c]);
    return d2;
  };
  return for_each_index<ConcurrencyTag>(n, progress, [&](std::size_t i) {
    double mode[7];
    std::copy_n(f + 7 * i, 7, mode);
    int anchor = int(i);
    int step = 0;
    // The Gaussian weights of a block of candidates go through Eigen's vectorised exp, two at a time: the
    // scalar exp was half of the mean shift's time (doc/editing_at_scale.md, "Preprocess at 1.66M points"). In aligned
    // blocks of fixed size a candidate takes the same path (packet or scalar tail) on every thread count.
    constexpr int block = 32;
    alignas(16) double weight[block];
    int candidate[block];
    constexpr int max_kept = 64;
    double spatial[max_kept];
    bool reuse_spatial = false;
    while(step < int(settings.max_iterations)) {
      ++step;
      double sum[7] = {0, 0, 0, 0, 0, 0, 0};
      double weight_sum = 0;
      const int degree = graph.degree(std::size_t(anchor));
      const int* neighbors = graph.begin(std::size_t(anchor));
      for(int b = 0; b <= degree; b += block) {
        const int count = std::min(block, degree + 1 - b);
        for(int c = 0; c < count; ++c) {
          // Candidate 0 is the anchor itself, then its neighbours.
          const int j = b + c == 0 ? anchor : neighbors[b + c - 1];
          const double* q = f + 7 * std::ptrdiff_t(j);
          const double ds2 = reuse_spatial ? spatial[b + c] : squared_distance(mode, q, 0, 3);
          const double dr2 = squared_distance(mode, q, 3, 7);
          candidate[c] = j;
          weight[c] = gaussian ? -0.5 * (ds2 + dr2) : (ds2 <= 1 && dr2 <= 1 ? 1.0 : 0.0);
        }
        if(gaussian) {
          Eigen::Map<Eigen::ArrayXd, Eigen::Aligned16> w(weight, count);
          w = w.exp();
        }
        for(int c = 0; c < count; ++c) {
          // Far below -709 Eigen's exp gives a subnormal where std::exp gives 0: a weight below the smallest
          // normal number is none, so a candidate beyond the kernel's reach weighs nothing.
          const double w = weight[c] < std::numeric_limits<double>::min() ? 0.0 : weight[c];
          const double* q = f + 7 * std::ptrdiff_t(candidate[c]);
          for(int d = 0; d < 7; ++d) sum[d] += w * q[d];
          weight_sum += w;
        }
      }
      if(!(weight_sum > 0)) break; // no sample within the kernel's reach: the mode stays
      double shift2 = 0;
      for(int c = 0; c < 7; ++c) {
        const double next = sum[c] / weight_sum;
        if(c >= measured_from) shift2 += (next - mode[c]) * (next - mode[c]);
        mode[c] = next;
      }
      // The spatial distances of the new mode to the candidates, kept for the next step when the anchor stays.
      const bool keep = degree < max_kept;
      int nearest = anchor;
      double nearest_d2 = squared_distance(mode, f + 7 * std::ptrdiff_t(anchor), 0, 3);
      if(keep) spatial[0] = nearest_d2;
      for(int c = 0; c < degree; ++c) {
        const double d2 = squared_distance(mode, f + 7 * std::ptrdiff_t(neighbors[c]), 0, 3);
        if(keep) spatial[c + 1] = d2;
        if(d2 < nearest_d2) { nearest_d2 = d2; nearest = neighbors[c]; }
      }
      reuse_spatial = keep && nearest == anchor;
      anchor = nearest;
      if(shift2 < tolerance2) break;
    }
    std::copy_n(mode, 7, modes.data() + 7 * i);
    iterations[i] = step;
  });
}

/// Everything the mean shift computes for a cloud: the nearest-first candidate graph, the curvature, the
/// scales and the modes (normalised units), all in the cloud's order.
struct Mean_shift_analysis
{
  bool analysed = false; ///< whether the fields below hold a completed analysis (set by its callers)
  Neighbor_graph candidates;
  Eigen::VectorXd curvature;
  Mean_shift_scales scales;
  Matrix_n7 modes;
  std::vector<int> iterations;
};

/// Candidate graph with `k` neighbours (`5 <= k < n`), closed-form curvature on it, scales, modes.
/// Returns false when cancelled.
template <typename ConcurrencyTag>
bool analyse_mean_shift(const Spatial_point_cloud& cloud, const Matrix_n3& normals, std::size_t k,
                        const Mean_shift_settings& settings, Progress& progress, Mean_shift_analysis& out)
{
  const Progress::Range whole = progress.range();
  progress.stage(whole.begin, whole.at(0.25));
  out.candidates = k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  if(progress.cancelled()) return false;
  progress.stage(whole.at(0.25), whole.at(0.5));
  if(!mean_curvatures<ConcurrencyTag>(cloud, normals, out.candidates, Curvature_fitting::closed_form, progress,
                                      out.curvature))
    return false;
  out.scales = resolve_scales(settings, cloud.positions, out.candidates, out.curvature);
  progress.stage(whole.at(0.5), whole.end);
  return mean_shift_modes<ConcurrencyTag>(mean_shift_features(cloud.positions, normals, out.curvature, out.scales),
                                          out.candidates, settings, progress, out.modes, out.iterations);
}

/// Mean-shift neighbours (doc/simplification.md, "Mean-shift neighbourhoods for the Laplacian"): the
/// candidates of each row (nearest first) whose modes' range parts lie within one range bandwidth of the
/// row's mode. Rows that keep fewer than `min_neighbors` are filled up with the remaining candidates of
/// closest mode (joint distance), so every row stays valid. Rows keep the candidates' order; symmetrise the
/// result for a Laplacian.
template <typename ConcurrencyTag>
Neighbor_graph mean_shift_neighbor_graph(const Neighbor_graph& candidates, const Matrix_n7& modes,
                                         std::size_t min_neighbors)
{
  const std::size_t n = candidates.size();
  std::vector<int> kept(candidates.indices.size());
  std::vector<int> count(n);
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    const int degree = candidates.degree(i);
    const int* nb = candidates.begin(i);
    int* out = kept.data() + candidates.offsets[i];
    const auto mode = modes.row(Eigen::Index(i));
    thread_local std::vector<char> take;
    take.assign(std::size_t(degree), 0);
    int taken = 0;
    for(int m = 0; m < degree; ++m)
      if((mode.tail<4>() - modes.row(nb[m]).tail<4>()).squaredNorm() <= 1) { take[std::size_t(m)] = 1; ++taken; }
    while(taken < std::min(degree, int(min_neighbors))) {
      int best = -1;
      double best_d2 = 0;
      for(int m = 0; m < degree; ++m) {
        if(take[std::size_t(m)]) continue;
        const double d2 = (mode - modes.row(nb[m])).squaredNorm();
        if(best < 0 || d2 < best_d2) { best = m; best_d2 = d2; }
      }
      take[std::size_t(best)] = 1;
      ++taken;
    }
    int c = 0;
    for(int m = 0; m < degree; ++m)
      if(take[std::size_t(m)]) out[c++] = nb[m];
    count[i] = c;
  });
  Neighbor_graph graph;
  graph.offsets.assign(n + 1, 0);
  for(std::size_t i = 0; i < n; ++i) graph.offsets[i + 1] = graph.offsets[i] + count[i];
  graph.indices.resize(std::size_t(graph.offsets[n]));
  for_range<ConcurrencyTag>(0, n, [&](std::size_t i) {
    std::copy_n(kept.data() + candidates.offsets[i], count[i], graph.indices.data() + graph.offsets[i]);
  });
  return graph;
}

/// What `compute_mean_shift_modes` reports of an analysis: its scales and iteration counts.
inline Mean_shift_result summarize(const Mean_shift_analysis& analysis, const Mean_shift_settings& settings)
{
  Mean_shift_result result;
  result.completed = true;
  result.spatial_bandwidth = analysis.scales.spatial_bandwidth;
  result.range_bandwidth = analysis.scales.range_bandwidth;
  result.curvature_scale = analysis.scales.curvature_scale;
  double sum = 0;
  for(int steps : analysis.iterations) {
    sum += steps;
    result.max_iterations = std::max(result.max_iterations, unsigned(steps));
    if(steps == int(settings.max_iterations)) ++result.points_at_cap;
  }
  result.mean_iterations = analysis.iterations.empty() ? 0 : sum / double(analysis.iterations.size());
  return result;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_MEAN_SHIFT_INSTANCES(EXTERN, Tag) \
  EXTERN template bool mean_shift_modes<Tag>(const Matrix_n7&, const Neighbor_graph&, const Mean_shift_settings&, \
                                             Progress&, Matrix_n7&, std::vector<int>&); \
  EXTERN template bool analyse_mean_shift<Tag>(const Spatial_point_cloud&, const Matrix_n3&, std::size_t, \
                                               const Mean_shift_settings&, Progress&, Mean_shift_analysis&); \
  EXTERN template Neighbor_graph mean_shift_neighbor_graph<Tag>(const Neighbor_graph&, const Matrix_n7&, std::size_t);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_MEAN_SHIFT_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_MEAN_SHIFT_H
