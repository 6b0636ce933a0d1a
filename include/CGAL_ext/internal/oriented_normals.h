// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_ORIENTED_NORMALS_H
#define CGAL_EXT_INTERNAL_ORIENTED_NORMALS_H

#include <CGAL_ext/Local_fit_settings.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/boost/graph/named_params_helper.h>

#ifdef CGAL_EXT_CORE_DEFINITIONS
#include <CGAL_ext/internal/local_fit.h>

#include <Eigen/Eigenvalues>
#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/parallel_sort.h>
#endif
#endif

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Unoriented normals of a cloud that came without any: the degree-2 jet of `CGAL::jet_estimate_normals`
/// (principal-component frame, height function fitted by least squares, normal of the jet at the point), fitted
/// to the point and its neighbours in `graph`. Returns false when cancelled.
template <typename ConcurrencyTag>
bool estimate_jet_normals(const Matrix_n3& positions, const Neighbor_graph& graph, Progress& progress,
                          Matrix_n3& normals);

/// Orients `normals` consistently over `graph` (symmetrised): a minimum spanning forest, then a breadth-first
/// walk from the highest point of each connected component, whose normal is turned upwards (+z), flipping every
/// normal that disagrees with its parent's. The weight of an edge e = (i, j) is Hoppe et al.'s 1 - |n_i . n_j|
/// (that of `CGAL::mst_orient_normals`) plus (|n_i . e| + |n_j . e|) / 2 for unit e: an edge across a thin part
/// or a crease joins normals that are parallel up to their sign, which the first term alone rates best, but it
/// runs along them, where an edge within the surface runs across them. Unlike CGAL's function, every component is oriented, not only the
/// one holding the highest point. Returns the number of components, or 0 when cancelled.
template <typename ConcurrencyTag>
std::size_t orient_normals_by_spanning_forest(const Matrix_n3& positions, const Neighbor_graph& graph,
                                              Progress& progress, Matrix_n3& normals);

/// Normals of a cloud that came without any: `estimate_jet_normals` on the point and its k nearest
/// neighbours, then `orient_normals_by_spanning_forest` on the same neighbour graph. Rows follow the cloud's
/// order. Returns false when cancelled. Measurements against CGAL's functions: doc/curvature.md (Normals).
template <typename ConcurrencyTag>
bool estimate_oriented_normals(const Spatial_point_cloud& cloud, unsigned int k, Progress& progress,
                               Matrix_n3& normals);

#ifdef CGAL_EXT_CORE_DEFINITIONS
template <typename ConcurrencyTag>
bool estimate_jet_normals(const Matrix_n3& positions, const Neighbor_graph& graph, Progress& progress,
                          Matrix_n3& normals)
{
  const std::size_t n = graph.size();
  normals.resize(Eigen::Index(n), 3);
  return for_each_index<ConcurrencyTag>(n, progress, [&](std::size_t i) {
    const Eigen::Vector3d origin = positions.row(Eigen::Index(i)).transpose();
    const int* neighbors = graph.begin(i);
    const int count = graph.degree(i) + 1;
    const auto point = [&](int m) -> Eigen::Vector3d {
      return m == 0 ? origin : Eigen::Vector3d(positions.row(neighbors[m - 1]).transpose());
    };
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for(int m = 0; m < count; ++m) centroid += point(m);
    centroid /= count;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for(int m = 0; m < count; ++m) {
      const Eigen::Vector3d d = point(m) - centroid;
      covariance.noalias() += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca;
    pca.computeDirect(covariance);
    Height_fit jet(origin, pca.eigenvectors().col(0), 2);
    jet.fit(count, point);
    const Eigen::Vector3d normal = jet.normal(origin);
    normals.row(Eigen::Index(i)) = (normal.allFinite() ? normal : Eigen::Vector3d(pca.eigenvectors().col(0))).transpose();
  });
}

template <typename ConcurrencyTag>
std::size_t orient_normals_by_spanning_forest(const Matrix_n3& positions, const Neighbor_graph& graph,
                                              Progress& progress, Matrix_n3& normals)
{
  const std::size_t n = graph.size();
  if(n == 0) return 0;
  const Progress::Range whole = progress.range();

  // Kruskal's algorithm on 64-bit keys: the weight's float bits (ordered as the weights, which are >= 0) above
  // the edge's slot in graph.indices (below 2^31: the offsets are int). An edge listed both ways is kept once.
  constexpr std::uint64_t dropped = ~std::uint64_t(0);
  std::vector<std::uint64_t> keys(graph.indices.size());
  progress.stage(whole.begin, whole.at(0.4));
  if(!for_each_index<ConcurrencyTag>(n, progress, [&](std::size_t i) {
       for(int e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
         const int j = graph.indices[std::size_t(e)];
         if(std::size_t(j) < i && std::find(graph.begin(std::size_t(j)), graph.end(std::size_t(j)), int(i)) !=
                                    graph.end(std::size_t(j))) {
           keys[std::size_t(e)] = dropped;
           continue;
         }
         const Eigen::RowVector3d ni = normals.row(Eigen::Index(i)), nj = normals.row(j);
         const Eigen::RowVector3d along = (positions.row(j) - positions.row(Eigen::Index(i))).normalized();
         float weight = float(1.0 - std::abs(ni.dot(nj)) + 0.5 * (std::abs(ni.dot(along)) + std::abs(nj.dot(along))));
         if(!(weight > 0)) weight = 0; // also -0, and NaN from duplicate points
         std::uint32_t bits;
         std::memcpy(&bits, &weight, sizeof bits);
         keys[std::size_t(e)] = std::uint64_t(bits) << 32 | std::uint32_t(e);
       }
     }))
    return 0;
#ifdef CGAL_LINKED_WITH_TBB
  if constexpr(is_parallel<ConcurrencyTag>())
    tbb::parallel_sort(keys.begin(), keys.end());
  else
#endif
    std::sort(keys.begin(), keys.end());
  progress.stage(whole.at(0.4), whole.at(0.8));
  if(!progress.report(0)) return 0;

  // The source of an edge slot: a division for the k-nearest graphs (fixed degree), a search otherwise.
  const int degree = graph.degree(0);
  bool fixed_degree = true;
  for(std::size_t i = 0; i <= n && fixed_degree; ++i) fixed_degree = graph.offsets[i] == int(i) * degree;
  const auto source = [&](std::uint32_t e) {
    if(fixed_degree) return int(e / std::uint32_t(degree));
    return int(std::upper_bound(graph.offsets.begin(), graph.offsets.end(), int(e)) - graph.offsets.begin()) - 1;
  };
  std::vector<int> root(n);
  std::iota(root.begin(), root.end(), 0);
  const auto find = [&](int v) {
    while(root[std::size_t(v)] != v) v = root[std::size_t(v)] = root[std::size_t(root[std::size_t(v)])];
    return v;
  };
  std::vector<std::pair<int, int>> tree;
  tree.reserve(n - 1);
  for(std::size_t s = 0; s < keys.size() && keys[s] != dropped && tree.size() + 1 < n; ++s) {
    if((s & 0xfffff) == 0 && !progress.report(double(s) / double(keys.size()))) return 0;
    const std::uint32_t e = std::uint32_t(keys[s]);
    const int i = source(e), j = graph.indices[e];
    const int a = find(i), b = find(j);
    if(a == b) continue;
    root[std::size_t(a)] = b;
    tree.emplace_back(i, j);
  }
  std::vector<std::uint64_t>().swap(keys);

  // The forest's adjacency, then a breadth-first walk from the highest point of each tree.
  progress.stage(whole.at(0.8), whole.end);
  std::vector<int> first(n + 1, 0), adjacent(2 * tree.size());
  for(const auto& [i, j] : tree) {
    ++first[std::size_t(i) + 1];
    ++first[std::size_t(j) + 1];
  }
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<int> next(first.begin(), first.end() - 1);
  for(const auto& [i, j] : tree) {
    adjacent[std::size_t(next[std::size_t(i)]++)] = j;
    adjacent[std::size_t(next[std::size_t(j)]++)] = i;
  }
  std::vector<int>& highest = next; // reused: the highest point of each tree, by its root
  std::fill(highest.begin(), highest.end(), -1);
  for(std::size_t v = 0; v < n; ++v) {
    int& h = highest[std::size_t(find(int(v)))];
    if(h < 0 || positions(Eigen::Index(v), 2) > positions(h, 2)) h = int(v);
  }
  std::vector<char> reached(n, 0);
  std::vector<int> queue;
  queue.reserve(n);
  std::size_t components = 0;
  for(const int seed : highest) {
    if(seed < 0) continue;
    ++components;
    if(normals(seed, 2) < 0) normals.row(seed) *= -1;
    reached[std::size_t(seed)] = 1;
    queue.assign(1, seed);
    for(std::size_t q = 0; q < queue.size(); ++q) {
      const int v = queue[q];
      for(int a = first[std::size_t(v)]; a < first[std::size_t(v) + 1]; ++a) {
        const int w = adjacent[std::size_t(a)];
        if(reached[std::size_t(w)]) continue;
        reached[std::size_t(w)] = 1;
        if(normals.row(v).dot(normals.row(w)) < 0) normals.row(w) *= -1;
        queue.push_back(w);
      }
    }
  }
  return progress.report(1.0) ? components : 0;
}

template <typename ConcurrencyTag>
bool estimate_oriented_normals(const Spatial_point_cloud& cloud, unsigned int k, Progress& progress,
                               Matrix_n3& normals)
{
  const std::size_t n = cloud.size();
  k = std::max<unsigned int>(5, std::min<unsigned int>(k, unsigned(n - 1))); // a degree-2 jet has 6 coefficients
  const Progress::Range whole = progress.range();
  progress.stage(whole.begin, whole.at(0.4));
  const Neighbor_graph graph = k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  if(progress.cancelled()) return false;
  progress.stage(whole.at(0.4), whole.at(0.6));
  if(!estimate_jet_normals<ConcurrencyTag>(cloud.positions, graph, progress, normals)) return false;
  progress.stage(whole.at(0.6), whole.end);
  orient_normals_by_spanning_forest<ConcurrencyTag>(cloud.positions, graph, progress, normals);
  progress.stage(whole.begin, whole.end);
  return !progress.cancelled();
}
#endif

/// The caller's normals when `np` (or a `Point_set_3` range) has them, otherwise estimated with
/// `neighbors` neighbours. Rows follow the cloud's order. Returns false when cancelled.
template <typename ConcurrencyTag, typename PointRange, typename NamedParameters>
bool given_or_estimated_normals(const PointRange& points, const NamedParameters& np, const Spatial_point_cloud& cloud,
                                unsigned int neighbors, Progress& progress, Matrix_n3& normals, const char* who)
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  if(has_given_normals<NamedParameters>(points)) {
    normals = gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
    return progress.report(1.0);
  }
  if(cloud.size() < 6)
    throw Invalid_input(std::string(who) + ": estimating normals needs at least 6 points (a jet fit has 6 "
                        "coefficients); pass a normal_map");
  return estimate_oriented_normals<ConcurrencyTag>(cloud, neighbors, progress, normals);
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_ORIENTED_NORMALS_INSTANCES(EXTERN, Tag) \
  EXTERN template bool estimate_jet_normals<Tag>(const Matrix_n3&, const Neighbor_graph&, Progress&, Matrix_n3&); \
  EXTERN template std::size_t orient_normals_by_spanning_forest<Tag>(const Matrix_n3&, const Neighbor_graph&, \
                                                                     Progress&, Matrix_n3&); \
  EXTERN template bool estimate_oriented_normals<Tag>(const Spatial_point_cloud&, unsigned int, Progress&, \
                                                      Matrix_n3&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_ORIENTED_NORMALS_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_ORIENTED_NORMALS_H
