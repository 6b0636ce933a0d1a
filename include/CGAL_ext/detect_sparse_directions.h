// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_DETECT_SPARSE_DIRECTIONS_H
#define CGAL_EXT_DETECT_SPARSE_DIRECTIONS_H

#include <CGAL_ext/Sparse_direction_settings.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/parallel.h>
#include <CGAL_ext/internal/sparse_directions.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/tags.h>

#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  The local spacing of every point: the median, over the point and its 15 nearest neighbours, of their mean
  distance to their 6 nearest neighbours (the measure of `CGAL::compute_average_spacing`, taken locally, with a
  median against single points). Hole detection and up-sampling measure gaps against it; an edit passes the
  spacing its points had before it to `upsample_point_set`, so that only what the edit stretched is filled.

  \tparam SpacingMap a model of `WritablePropertyMap` with value type `double`

  \param points the points (at least 2)
  \param spacing_map receives each point's local spacing
  \param np `point_map`, `geom_traits`
  \return the median of the local spacings.
  \throws Invalid_input for fewer than 2 points or non-finite coordinates.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/upsampling.md">Up-sampling after deformation</a> (`doc/upsampling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename SpacingMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
double compute_local_spacing(const PointRange& points, SpacingMap spacing_map,
                             const NamedParameters& np = CGAL::parameters::default_values())
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  constexpr const char* who = "compute_local_spacing";
  const internal::Spatial_point_cloud cloud =
    internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  if(cloud.size() < 2) throw Invalid_input(std::string(who) + ": a spacing needs at least 2 points");
  const internal::Position_tree tree(cloud.positions, ConcurrencyTag());
  const std::vector<double> spacing = internal::local_spacings<ConcurrencyTag>(cloud.positions, tree);
  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) put(spacing_map, item, spacing[std::size_t(row_of[i++])]);
  return internal::median(spacing);
}

/*!
  \ingroup PkgCGALExtAlgorithms
  Finds the points on the boundary of holes (Miao et al. 2007, Sect. 6.3, Fig. 9a): for each point, the
  quarters of its tangent plane around the principal axes `±e1`, `±e2` of its projected neighbours that hold no
  sample within two spacings (samples whose normals face away, the other side of a thin part, do not count),
  and among them the ones across which samples reappear within `settings.max_hole_size` spacings (a hole, not an
  open border).

  \tparam SparseDirectionMap a model of `WritablePropertyMap` whose value type is the kernel's `Vector_3`.

  \param points the points, with normals (`normal_map`; required, the tangent planes come from them)
  \param k neighbours that give a point's principal axes, `1 <= k < points.size()`
  \param settings spacing and largest hole
  \param hole_direction_map receives, for every point, the unit direction into its nearest hole (toward the
         closest sample across it), or the zero vector when the point borders no hole
  \param np `point_map`, `normal_map`, `geom_traits`

  \return the spacing used and the counts of sparse and hole-boundary points.
  \throws Invalid_input for an empty range, non-finite coordinates, missing, zero or non-finite normals, a bad
          `k` or invalid settings.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/upsampling.md">Up-sampling after deformation</a> (`doc/upsampling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename SparseDirectionMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
Sparse_direction_summary detect_sparse_directions(const PointRange& points, unsigned int k, const Sparse_direction_settings& settings,
                                                  SparseDirectionMap hole_direction_map,
                                                  const NamedParameters& np = CGAL::parameters::default_values())
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Kernel = typename NP_helper::Geom_traits;
  using Vector = typename Kernel::Vector_3;
  constexpr const char* who = "detect_sparse_directions";
  settings.validate();
  const internal::Spatial_point_cloud cloud =
    internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  internal::check_neighbor_count(k, cloud.size(), who);
  if(!internal::has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): the tangent planes come from them");
  const internal::Matrix_n3 normals = internal::gather_normals(points, NP_helper::get_normal_map(points, np), cloud, who);
  const internal::Position_tree tree(cloud.positions, ConcurrencyTag());
  Sparse_direction_summary summary;
  const std::vector<double> spacing = internal::spacings<ConcurrencyTag>(cloud.positions, tree, settings.spacing, who);
  summary.spacing = internal::median(spacing);
  const std::vector<double> empty_radius =
    internal::empty_radii<ConcurrencyTag>(cloud.positions, normals, tree, k, spacing, settings.spacing == 0);
  std::vector<int> sparse;
  const std::vector<internal::Hole_gap> gaps = internal::hole_gaps<ConcurrencyTag>(
    cloud.positions, normals, tree, k, spacing, empty_radius, settings.max_hole_size, nullptr, sparse);
  summary.sparse_points = sparse.size();

  // The nearest gap of each point gives its direction.
  std::vector<Eigen::Vector3d> direction(cloud.size(), Eigen::Vector3d::Zero());
  std::vector<double> length(cloud.size(), INFINITY);
  for(const internal::Hole_gap& g : gaps) {
    const Eigen::Vector3d d = (cloud.positions.row(g.across) - cloud.positions.row(g.from)).transpose();
    if(d.norm() < length[std::size_t(g.from)]) {
      length[std::size_t(g.from)] = d.norm();
      direction[std::size_t(g.from)] = d.normalized();
    }
  }
  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) {
    const Eigen::Vector3d& d = direction[std::size_t(row_of[i++])];
    summary.hole_boundary_points += d.squaredNorm() > 0;
    put(hole_direction_map, item, Vector(d.x(), d.y(), d.z()));
  }
  return summary;
}

} // namespace CGAL_ext

#endif // CGAL_EXT_DETECT_SPARSE_DIRECTIONS_H
