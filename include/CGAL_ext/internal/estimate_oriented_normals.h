// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H
#define CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H

#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Normals of a cloud that came without any: `CGAL::jet_estimate_normals` then `CGAL::mst_orient_normals`,
/// both on an internal copy, since the orientation reorders its range (and would read a caller's
/// `point_is_constrained_map` as seeds). Points the MST could not reach keep their unoriented jet normal.
/// Rows follow the cloud's order. Returns false when cancelled.
template <typename ConcurrencyTag>
bool estimate_oriented_normals(const Spatial_point_cloud& cloud, unsigned int k, Progress& progress,
                               Matrix_n3& normals)
{
  using SC = CGAL::Simple_cartesian<double>;
  using Item = std::tuple<SC::Point_3, SC::Vector_3, int>;
  const std::size_t n = cloud.size();
  k = std::min<unsigned int>(k, unsigned(n - 1));
  std::vector<Item> items(n);
  for(std::size_t s = 0; s < n; ++s)
    items[s] = Item(SC::Point_3(cloud.positions(Eigen::Index(s), 0), cloud.positions(Eigen::Index(s), 1),
                                cloud.positions(Eigen::Index(s), 2)),
                    SC::Vector_3(0, 0, 0), int(s));
  const auto point_map = CGAL::Nth_of_tuple_property_map<0, Item>();
  const auto normal_map = CGAL::Nth_of_tuple_property_map<1, Item>();
  // The jet fit is most of the cost; the orientation reports nothing, so it is given the last fifth.
  const std::function<bool(double)> jet_callback = [&](double f) { return progress.report(0.8 * f); };
  CGAL::jet_estimate_normals<ConcurrencyTag>(
    items, k, CGAL::parameters::point_map(point_map).normal_map(normal_map).callback(jet_callback));
  if(progress.cancelled()) return false;
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
  if(cloud.size() < 3)
    throw Invalid_input(std::string(who) + ": estimating normals needs at least 3 points; pass a normal_map");
  return estimate_oriented_normals<ConcurrencyTag>(cloud, neighbors, progress, normals);
}

} // namespace internal
} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_ESTIMATE_ORIENTED_NORMALS_H
