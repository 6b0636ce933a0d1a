// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_REFIT_NORMALS_H
#define CGAL_EXT_REFIT_NORMALS_H

#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/local_fit.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Named_function_parameters.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <Eigen/Eigenvalues>

#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Re-fits the normals of points that moved (after `scale_geometric_details`, `enhance_geometric_details` or
  any displacement of a part of a point set), so that shading and later processing see the new shape, not
  the old one: the normal of each point of `indices`, and of each point among their `k - 1` nearest
  neighbours (their fits see the moved points), becomes that of a degree-2 height function fitted to the point
  and its `k - 1` nearest neighbours over their principal plane, turned to the side of its current normal.
  The other normals are not touched. A region flattened by `s = 0` gets the normals of the flat surface (a
  test checks within 3 degrees); one enhanced gets those of its sharper details.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.

  \param points the points, after they moved
  \param indices the indices (positions in `points`) of the points that moved
  \param k neighbours of a fit, the point itself counted; at least 6 (the fit has 6 coefficients) and at most
           the number of points
  \param np `point_map`, `normal_map` (required, read and written: the current normals give each new one its
         side), `geom_traits`

  \return the number of normals re-fitted.
  \throws Invalid_input for an empty range, non-finite coordinates, missing, zero or non-finite normals, an
          index out of range or `k` out of range.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename NamedParameters>
std::size_t refit_normals(const PointRange& points, const IndexRange& indices, unsigned int k, const NamedParameters& np)
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Vector = typename NP_helper::Geom_traits::Vector_3;
  constexpr const char* who = "refit_normals";
  const internal::Spatial_point_cloud cloud =
    internal::make_spatial_point_cloud<ConcurrencyTag>(points, NP_helper::get_const_point_map(points, np), who);
  if(k < 6 || k > cloud.size())
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) + " must be at least 6 (the fit has 6 "
                        "coefficients) and at most the number of points (" + std::to_string(cloud.size()) + ")");
  if(!internal::has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): they give the new normals their side");
  const auto normal_map = NP_helper::get_normal_map(points, np);
  const internal::Matrix_n3 normals = internal::gather_normals(points, normal_map, cloud, who);
  const std::vector<int> row_of = cloud.spatial_index();
  const std::vector<int> moved = internal::rows_of_indices(indices, row_of, who, "moved");
  const internal::Position_tree tree(cloud.positions, ConcurrencyTag());

  // The moved points and their neighbours.
  std::vector<char> refit(cloud.size(), 0);
  for(int row : moved) {
    refit[std::size_t(row)] = 1;
    tree.nearest(internal::Position_tree::point(cloud.positions, row), k, [&](int j, double) { refit[std::size_t(j)] = 1; });
  }
  std::vector<int> rows;
  for(std::size_t r = 0; r < refit.size(); ++r)
    if(refit[r]) rows.push_back(int(r));

  internal::Matrix_n3 fitted(Eigen::Index(rows.size()), 3);
  internal::for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t m) {
    const int row = rows[m];
    const Eigen::Vector3d p = cloud.positions.row(row).transpose(), current = normals.row(row).transpose();
    thread_local std::vector<int> near;
    near.clear();
    tree.nearest(internal::Position_tree::point(cloud.positions, row), k, [&](int j, double) { near.push_back(j); });
    // The principal plane frames the fit: the old normal may be far from the new surface's (s = 0 on a bump).
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for(int j : near) mean += cloud.positions.row(j).transpose();
    mean /= double(near.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for(int j : near) {
      const Eigen::Vector3d d = cloud.positions.row(j).transpose() - mean;
      covariance += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(covariance);
    Eigen::Vector3d axis = eigen.eigenvectors().col(0);
    if(!axis.allFinite() || !(axis.squaredNorm() > 0)) axis = current;
    internal::Height_fit fit(p, axis.dot(current) < 0 ? Eigen::Vector3d(-axis) : axis);
    fit.fit(int(near.size()), [&](int i) { return Eigen::Vector3d(cloud.positions.row(near[std::size_t(i)]).transpose()); });
    Eigen::Vector3d n = fit.normal(p);
    if(!n.allFinite()) n = current.normalized();
    fitted.row(Eigen::Index(m)) = (n.dot(current) < 0 ? Eigen::Vector3d(-n) : n).transpose();
  });

  std::vector<int> fitted_row(cloud.size(), -1);
  for(std::size_t m = 0; m < rows.size(); ++m) fitted_row[std::size_t(rows[m])] = int(m);
  std::size_t i = 0;
  for(const auto& item : points) {
    const int m = fitted_row[std::size_t(row_of[i++])];
    if(m >= 0) put(normal_map, item, Vector(fitted(m, 0), fitted(m, 1), fitted(m, 2)));
  }
  return rows.size();
}

} // namespace CGAL_ext

#endif // CGAL_EXT_REFIT_NORMALS_H
