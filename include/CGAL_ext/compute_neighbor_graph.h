// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_COMPUTE_NEIGHBOR_GRAPH_H
#define CGAL_EXT_COMPUTE_NEIGHBOR_GRAPH_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/progress.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <tuple>
#include <vector>

namespace CGAL_ext {

/// A neighbour graph in compressed sparse row form over the caller's point indices: the neighbours of point
/// `i` are `neighbors[offsets[i] .. offsets[i+1])`.
struct Neighbor_lists
{
  std::vector<std::size_t> offsets{0};
  std::vector<std::size_t> neighbors;
};

/*!
  \ingroup PkgCGALExtAlgorithms
  The neighbourhoods every algorithm of the package uses, for the caller's own processing (selection tools,
  region checks): each point's closed ball of its `k`-th nearest other point. A row holds exactly `k` points,
  more where points tie at that distance (lattices, duplicates), so that it depends on the positions alone,
  never on the order of the points. The graph is directed (j near i does not make i near j).

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.

  \param points the points
  \param k neighbours of a point, itself not counted, `1 <= k < points.size()`
  \param np `point_map`, `geom_traits`, `callback` (called with the fraction done; returning `false` cancels,
         and the result is then empty)

  \return each point's neighbours (indices in `points`), nearest first, ties in index order.
  \throws Invalid_input for an empty range, non-finite coordinates, points that span no surface, a bad `k`, or
          more than `k` + 256 points tied at one distance (a pile of duplicates).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Neighbor_lists compute_neighbor_graph(const PointRange& points, unsigned int k,
                                      const NamedParameters& np = CGAL::parameters::default_values())
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  constexpr const char* who = "compute_neighbor_graph";
  const internal::Spatial_point_cloud cloud =
    internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  const std::size_t n = cloud.size();
  internal::check_neighbor_count(k, n, who);
  const std::function<bool(double)> callback = CGAL::parameters::choose_parameter(
    CGAL::parameters::get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  internal::Progress progress(callback);
  const internal::Neighbor_graph graph =
    internal::k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  Neighbor_lists lists;
  if(graph.size() != n) return lists;
  const std::vector<int> row_of = cloud.spatial_index();
  const auto& x = cloud.positions;
  lists.offsets.resize(n + 1);
  lists.neighbors.reserve(graph.indices.size());
  std::vector<std::tuple<double, std::size_t>> row;
  for(std::size_t i = 0; i < n; ++i) {
    const Eigen::Index r = row_of[i];
    row.clear();
    for(const int* j = graph.begin(std::size_t(r)); j != graph.end(std::size_t(r)); ++j)
      row.emplace_back(internal::squared_distance(x(r, 0), x(r, 1), x(r, 2), x(*j, 0), x(*j, 1), x(*j, 2)),
                       std::size_t(cloud.input_index[std::size_t(*j)]));
    std::sort(row.begin(), row.end());
    for(const auto& [d2, j] : row) lists.neighbors.push_back(j);
    lists.offsets[i + 1] = lists.neighbors.size();
  }
  return lists;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_COMPUTE_NEIGHBOR_GRAPH_H
