// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H
#define CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H

#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/boost/graph/named_params_helper.h>

#ifdef CGAL_EXT_CORE_DEFINITIONS
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/property_map.h>
#endif

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Normals of a cloud that came without any: jet fitting then `CGAL::mst_orient_normals`, on an internal copy,
/// since the orientation reorders its range (and would read a caller's `point_is_constrained_map` as seeds).
/// Points the MST could not reach keep their unoriented jet normal. Rows follow the cloud's order. Returns
/// false when cancelled.
///
/// The jet fit is `CGAL::jet_estimate_normals`' own (`CGAL::Monge_via_jet_fitting`, degree 2, Monge degree 1,
/// on the point and its k - 1 nearest neighbours), run here on the project's neighbour graph: CGAL 5.5's
/// function binds its callback to a reference to a temporary (AddressSanitizer: stack-use-after-scope).
template <typename ConcurrencyTag>
bool estimate_oriented_normals(const Spatial_point_cloud& cloud, unsigned int k, Progress& progress,
                               Matrix_n3& normals);

#ifdef CGAL_EXT_CORE_DEFINITIONS
template <typename ConcurrencyTag>
bool estimate_oriented_normals(const Spatial_point_cloud& cloud, unsigned int k, Progress& progress,
                               Matrix_n3& normals)
{
  using SC = CGAL::Simple_cartesian<double>;
  using Item = std::tuple<SC::Point_3, SC::Vector_3, int>;
  const std::size_t n = cloud.size();
  k = std::max<unsigned int>(6, std::min<unsigned int>(k, unsigned(n))); // a degree-2 jet has 6 coefficients
  const Matrix_n3& P = cloud.positions;
  std::vector<Item> items(n);
  for(std::size_t s = 0; s < n; ++s)
    items[s] = Item(SC::Point_3(P(Eigen::Index(s), 0), P(Eigen::Index(s), 1), P(Eigen::Index(s), 2)),
                    SC::Vector_3(0, 0, 0), int(s));
  // The neighbour search and the fits are most of the cost; the orientation reports nothing.
  const Progress::Range whole = progress.range();
  progress.stage(whole.at(0), whole.at(0.2));
  const Neighbor_graph graph = k_nearest_neighbor_graph<ConcurrencyTag>(P, k - 1, progress);
  if(progress.cancelled()) return false;
  progress.stage(whole.at(0.2), whole.at(0.8));
  const bool fitted = for_each_index<ConcurrencyTag>(n, progress, [&](std::size_t i) {
    thread_local std::vector<SC::Point_3> fit_points;
    fit_points.assign(1, std::get<0>(items[i]));
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) fit_points.push_back(std::get<0>(items[std::size_t(*j)]));
    CGAL::Monge_via_jet_fitting<SC> fit;
    std::get<1>(items[i]) = fit(fit_points.begin(), fit_points.end(), 2, 1).normal_direction();
  });
  progress.stage(whole.begin, whole.end);
  if(!fitted) return false;
  const auto point_map = CGAL::Nth_of_tuple_property_map<0, Item>();
  const auto normal_map = CGAL::Nth_of_tuple_property_map<1, Item>();
  CGAL::mst_orient_normals(items, k, CGAL::parameters::point_map(point_map).normal_map(normal_map));

  normals.resize(Eigen::Index(n), 3);
  for(const Item& item : items) {
    const SC::Vector_3& v = std::get<1>(item);
    Eigen::RowVector3d nv(v.x(), v.y(), v.z());
    const double len = nv.norm();
    normals.row(std::get<2>(item)) = len > 0 ? Eigen::RowVector3d(nv / len) : Eigen::RowVector3d(0, 0, 1);
  }
  return progress.report(1.0);
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

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/parallel.h).
#define CGAL_EXT_ORIENTED_NORMALS_INSTANCES(EXTERN, Tag) \
  EXTERN template bool estimate_oriented_normals<Tag>(const Spatial_point_cloud&, unsigned int, Progress&, \
                                                      Matrix_n3&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_ORIENTED_NORMALS_INSTANCES)

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H
