// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_GEOMETRIC_DETAILS_H
#define CGAL_EXT_INTERNAL_GEOMETRIC_DETAILS_H

#include <CGAL_ext/Detail_filter.h>
#include <CGAL_ext/internal/Laplacian.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/mean_shift.h>
#include <CGAL_ext/internal/parallel.h>

#include <algorithm>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Stands for "no oriented-magnitude output".
struct No_output_map {};

template <typename Key, typename Value>
void put(No_output_map, const Key&, const Value&) {}

/// The Laplacian the settings ask for, in the cloud's order: on the symmetrised kNN graph, or on the
/// mean-shift neighbourhoods of `settings.neighborhood` (these need `normals`, unused otherwise); when asked,
/// each point's distance to its k-th nearest. Returns false when cancelled.
template <typename ConcurrencyTag>
bool detail_laplacian(const Spatial_point_cloud& cloud, std::size_t k, const Detail_settings& settings,
                      const Matrix_n3& normals, Progress& progress, Sparse_row_matrix& K, const char* who,
                      std::vector<double>* neighbor_radius = nullptr)
{
  if(settings.neighborhood == Laplacian_neighborhood::k_nearest)
    return build_laplacian<ConcurrencyTag>(cloud, k, settings.weights, progress, K, neighbor_radius);

  // The modes want their own candidate count; the Laplacian's candidates are the k nearest of those.
  const std::size_t candidates = std::min<std::size_t>(std::max<std::size_t>(k, default_mean_shift_neighbors),
                                                       cloud.size() - 1);
  check_mean_shift_neighbors(candidates, cloud.size(), who);
  const Progress::Range whole = progress.range();
  progress.stage(whole.begin, whole.at(0.9));
  Mean_shift_analysis analysis;
  if(!analyse_mean_shift<ConcurrencyTag>(cloud, normals, candidates, settings.mean_shift, progress, analysis))
    return false;
  progress.stage(whole.at(0.9), whole.end);
  constexpr std::size_t min_neighbors = 3;
  const Neighbor_graph nearest = nearest_prefix(analysis.candidates, cloud.positions, k);
  if(neighbor_radius) *neighbor_radius = last_neighbor_distances(cloud.positions, cloud.positions, nearest);
  const Neighbor_graph graph = symmetrize<ConcurrencyTag>(
    mean_shift_neighbor_graph<ConcurrencyTag>(nearest, analysis.modes, std::min(k, min_neighbors)));
  K = laplacian_matrix<ConcurrencyTag>(cloud.positions, graph, settings.weights);
  return progress.report(1.0);
}

/// Detail vectors of a cloud, in the cloud's order, and when asked each point's distance to its k-th nearest.
/// Returns false when cancelled.
template <typename ConcurrencyTag>
bool geometric_details(const Spatial_point_cloud& cloud, unsigned int k, const Detail_settings& settings,
                       const Matrix_n3& normals, Progress& progress, Matrix_n3& details, const char* who,
                       std::vector<double>* neighbor_radius = nullptr)
{
  Sparse_row_matrix K;
  if(!detail_laplacian<ConcurrencyTag>(cloud, k, settings, normals, progress, K, who, neighbor_radius)) return false;
  details = apply_detail_filter<ConcurrencyTag>(K, settings.filter, cloud.positions);
  return true;
}

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_GEOMETRIC_DETAILS_INSTANCES(EXTERN, Tag)                                                              \
  EXTERN template bool detail_laplacian<Tag>(const Spatial_point_cloud&, std::size_t, const Detail_settings&,          \
                                             const Matrix_n3&, Progress&, Sparse_row_matrix&, const char*,             \
                                             std::vector<double>*);                                                    \
  EXTERN template bool geometric_details<Tag>(const Spatial_point_cloud&, unsigned int, const Detail_settings&,        \
                                              const Matrix_n3&, Progress&, Matrix_n3&, const char*,                    \
                                              std::vector<double>*);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_GEOMETRIC_DETAILS_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_GEOMETRIC_DETAILS_H
