// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_ESTIMATE_ORIENTED_NORMALS_H
#define CGAL_EXT_ESTIMATE_ORIENTED_NORMALS_H

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/oriented_normals.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <functional>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Estimates an oriented unit normal of every point, for scans that come without normals: what
  `CGAL::jet_estimate_normals` followed by `CGAL::mst_orient_normals` do, in parallel and in a fraction of the
  time and memory (doc/curvature.md, "Normals").

  The normal of a point is that of the degree-2 jet fitted to it and its `k` nearest neighbours (CGAL's jet;
  CGAL's own k counts the point, so CGAL's `jet_estimate_normals` with `k + 1` fits the same jets). The
  orientation propagates over a minimum spanning forest of the same neighbour graph, weighted by
  `1 - |n_i . n_j|`, from the highest point of each connected component, whose normal is turned to +z: every
  component is oriented, where `CGAL::mst_orient_normals` orients only the one holding the highest point. As
  with any propagation, two sheets closer than the neighbourhood size, or an open surface whose highest
  normal points down, can end up oriented inwards; pass normals from the scanner when it has them.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.

  \param points the input points; not modified (the normals go to the normal map)
  \param k neighbours of a jet, the point itself not counted (as everywhere in the package); at least 5 (a
           degree-2 jet has 6 coefficients) and smaller than the number of points. Default in the program and in
           Python: `default_normal_neighbors`.
  \param np `point_map`, `normal_map` (required: a `WritablePropertyMap` that receives the unit normals),
         `callback` (progress in [0, 1]; false cancels, and the normal map is then untouched), `geom_traits`

  \return false if the callback cancelled, true otherwise.
  \throws Invalid_input for fewer than 6 points, non-finite coordinates, or `k` out of range.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/curvature.md">Mean curvature (its section Normals)</a> (`doc/curvature.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename NamedParameters>
bool estimate_oriented_normals(const PointRange& points, unsigned int k, const NamedParameters& np)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Vector = typename NP_helper::Geom_traits::Vector_3;
  using FT = typename NP_helper::Geom_traits::FT;
  constexpr const char* who = "estimate_oriented_normals";
  static_assert(!std::is_same<typename CGAL::internal_np::Get_param<typename NamedParameters::base,
                                                                     CGAL::internal_np::normal_t>::type,
                              CGAL::internal_np::Param_not_found>::value,
                "estimate_oriented_normals: pass a normal_map to receive the normals");

  const internal::Spatial_point_cloud cloud =
    internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  if(cloud.size() < 6)
    throw Invalid_input(std::string(who) + ": " + std::to_string(cloud.size()) +
                        " points; estimating normals needs at least 6 (a jet has 6 coefficients)");
  if(k < 5 || k >= cloud.size())
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) +
                        " neighbours must be at least 5 (a jet has 6 coefficients: the point and 5 neighbours) "
                        "and smaller than the number of points (" +
                        std::to_string(cloud.size()) + ")");
  internal::Progress progress(
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>()));
  internal::Matrix_n3 normals;
  if(!internal::estimate_oriented_normals<ConcurrencyTag>(cloud, k, progress, normals)) return false;

  const auto normal_map = NP_helper::get_normal_map(points, np);
  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) {
    const auto row = normals.row(row_of[i++]);
    put(normal_map, item, Vector(FT(row(0)), FT(row(1)), FT(row(2))));
  }
  return true;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_ESTIMATE_ORIENTED_NORMALS_H
