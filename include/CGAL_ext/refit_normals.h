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

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtAlgorithms
  Re-fits the normals of points that moved (after `scale_geometric_details`, `enhance_geometric_details` or
  any displacement of a part of a point set), so that shading and later processing see the new shape, not
  the old one: the normal of each point of `indices`, and of each point among their `k` nearest
  neighbours (their fits see the moved points), becomes that of a degree-2 height function fitted to the point
  and its `k` nearest neighbours over their principal plane, turned to the side of its current normal.
  The other normals are not touched. A region flattened by `s = 0` gets the normals of the flat surface (a
  test checks within 3 degrees); one enhanced gets those of its sharper details. The fits read only the moved
  points' surroundings, so a small region of a large set costs what its surroundings cost.

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.

  \param points the points, after they moved
  \param indices the indices (positions in `points`) of the points that moved
  \param k neighbours of a fit, the point itself not counted (as everywhere in the package); at least 5 (the
           fit has 6 coefficients) and smaller than the number of points
  \param np `point_map`, `normal_map` (required, read and written: the current normals give each new one its
         side), `geom_traits`

  \return the number of normals re-fitted.
  \throws Invalid_input for an empty range, non-finite coordinates, missing, zero or non-finite normals, an
          index out of range or `k` out of range.

  \sa The user manual's page, with pictures, the program's and Python's calls and the measurements:
  <a href="../../../doc/detail_scaling.md">Detail scaling and enhancement</a> (`doc/detail_scaling.md`).
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename IndexRange,
          typename NamedParameters>
std::size_t refit_normals(const PointRange& points, const IndexRange& indices, unsigned int k, const NamedParameters& np)
{
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using Vector = typename NP_helper::Geom_traits::Vector_3;
  constexpr const char* who = "refit_normals";
  using SC_point = CGAL::Simple_cartesian<double>::Point_3;
  const std::vector<SC_point> copy = internal::copy_points(points, NP_helper::get_const_point_map(points, np), who);
  internal::check_spans_a_surface(copy, who);
  const std::size_t n = copy.size();
  if(k < 5 || k >= n)
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) +
                        " neighbours must be at least 5 (the fit has 6 coefficients: the point and 5 neighbours) "
                        "and smaller than the number of points (" +
                        std::to_string(n) + ")");
  const unsigned int fit_size = k + 1; // a fit's points: the point and its k nearest neighbours
  if(!internal::has_given_normals<NamedParameters>(points))
    throw Invalid_input(std::string(who) + ": the points need normals (normal_map): they give the new normals their side");
  std::vector<int> identity(n);
  std::iota(identity.begin(), identity.end(), 0);
  const std::vector<int> moved = internal::rows_of_indices(indices, identity, who, "moved");
  auto position = [&](std::size_t i) { return Eigen::RowVector3d(copy[i].x(), copy[i].y(), copy[i].z()); };

  // Only the moved points' surroundings take part (doc/design.md, "Refitted normals"): the points in their
  // bounding box grown by a reach, in spatial order. The reach is checked after the fact: when each moved
  // point's fit_size nearest points in the surroundings lie within d of it and the box holds the ball of radius
  // 3 d about it, those are its nearest in the whole set, and so are the nearest of each of them (within 2 d
  // of them). Otherwise the whole set is used.
  auto surroundings_within = [&](double reach) {
    if(!std::isfinite(reach)) return internal::sort_spatially<ConcurrencyTag>(copy, who);
    Eigen::RowVector3d low = position(std::size_t(moved.front())), high = low;
    for(int i : moved) {
      low = low.cwiseMin(position(std::size_t(i)));
      high = high.cwiseMax(position(std::size_t(i)));
    }
    low.array() -= reach;
    high.array() += reach;
    std::vector<int> kept;
    for(std::size_t i = 0; i < n; ++i) {
      const Eigen::RowVector3d p = position(i);
      if((p.array() >= low.array()).all() && (p.array() <= high.array()).all()) kept.push_back(int(i));
    }
    return internal::sort_spatially<ConcurrencyTag>(copy, kept, who);
  };
  double reach = std::numeric_limits<double>::infinity();
  if(moved.size() >= fit_size && moved.size() < n) {
    // The first reach: three times twice the largest distance of up to 2,000 moved points to their k-th
    // nearest other moved point (twice: a margin for the moved points not probed).
    internal::Matrix_n3 moved_positions(Eigen::Index(moved.size()), 3);
    for(std::size_t m = 0; m < moved.size(); ++m)
      moved_positions.row(Eigen::Index(m)) = position(std::size_t(moved[m]));
    const std::size_t stride = std::max<std::size_t>(1, moved.size() / 2000);
    internal::Matrix_n3 probes(Eigen::Index((moved.size() + stride - 1) / stride), 3);
    for(Eigen::Index q = 0; q < probes.rows(); ++q) probes.row(q) = moved_positions.row(q * Eigen::Index(stride));
    const internal::Neighbor_graph probe_neighbors =
      internal::k_nearest_samples<ConcurrencyTag>(moved_positions, probes, fit_size);
    double largest = 0;
    for(std::size_t q = 0; q < std::size_t(probes.rows()); ++q)
      largest = std::max(largest,
                         (moved_positions.row(*(probe_neighbors.end(q) - 1)) - probes.row(Eigen::Index(q))).norm());
    reach = 6 * largest;
  }
  internal::Spatial_point_cloud surroundings;
  std::unique_ptr<internal::Position_tree> tree;
  internal::Neighbor_graph neighbors;
  std::vector<int> moved_rows;
  for(;;) {
    try {
      surroundings = surroundings_within(reach);
    } catch(const Invalid_input&) {
      // The box's points lie on a line (the whole set was checked to span a surface): use the whole set.
      if(!std::isfinite(reach)) throw;
      reach = std::numeric_limits<double>::infinity();
      continue;
    }
    std::vector<int> surroundings_row(n, -1);
    for(std::size_t r = 0; r < surroundings.size(); ++r)
      surroundings_row[std::size_t(surroundings.input_index[r])] = int(r);
    moved_rows.clear();
    for(int i : moved) moved_rows.push_back(surroundings_row[std::size_t(i)]);
    std::sort(moved_rows.begin(), moved_rows.end()); // queries in spatial order walk the tree's memory in order
    tree = std::make_unique<internal::Position_tree>(surroundings.positions, ConcurrencyTag());
    neighbors = internal::fixed_degree_graph(moved.size(), fit_size);
    std::vector<double> kth_distance(moved.size());
    internal::for_range<ConcurrencyTag>(0, moved.size(), [&](std::size_t m) {
      int* out = neighbors.indices.data() + m * fit_size;
      tree->nearest(internal::Position_tree::point(surroundings.positions, moved_rows[m]), fit_size,
                    [&](int j, double d2) {
                      *out++ = j;
                      kth_distance[m] = std::sqrt(d2);
                    });
    });
    if(!std::isfinite(reach)) break;
    bool enough = true;
    for(std::size_t m = 0; m < moved.size() && enough; ++m) enough = 3 * kth_distance[m] <= reach;
    if(enough) break;
    reach = std::numeric_limits<double>::infinity();
  }
  // Every normal is read and checked, those of the surroundings kept.
  const auto normal_map = NP_helper::get_normal_map(points, np);
  const internal::Matrix_n3 normals = internal::gather_normals(points, normal_map, surroundings, who);

  // The moved points and their neighbours, as rows of the surroundings; a moved point's neighbours are those
  // already found.
  std::vector<int> moved_of_row(surroundings.size(), -1);
  for(std::size_t m = 0; m < moved_rows.size(); ++m) moved_of_row[std::size_t(moved_rows[m])] = int(m);
  std::vector<char> refit(surroundings.size(), 0);
  for(int row : moved_rows) refit[std::size_t(row)] = 1;
  for(int j : neighbors.indices) refit[std::size_t(j)] = 1;
  std::vector<int> rows;
  for(std::size_t r = 0; r < refit.size(); ++r)
    if(refit[r]) rows.push_back(int(r));

  internal::Matrix_n3 fitted(Eigen::Index(rows.size()), 3);
  internal::for_range<ConcurrencyTag>(0, rows.size(), [&](std::size_t m) {
    const int row = rows[m];
    const Eigen::Vector3d p = surroundings.positions.row(row).transpose(), current = normals.row(row).transpose();
    thread_local std::vector<int> near;
    near.clear();
    if(moved_of_row[std::size_t(row)] >= 0)
      near.assign(neighbors.begin(std::size_t(moved_of_row[std::size_t(row)])),
                  neighbors.end(std::size_t(moved_of_row[std::size_t(row)])));
    else
      tree->nearest(internal::Position_tree::point(surroundings.positions, row), fit_size,
                    [&](int j, double) { near.push_back(j); });
    // The principal plane frames the fit: the old normal may be far from the new surface's (s = 0 on a bump).
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for(int j : near) mean += surroundings.positions.row(j).transpose();
    mean /= double(near.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for(int j : near) {
      const Eigen::Vector3d d = surroundings.positions.row(j).transpose() - mean;
      covariance += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(covariance);
    Eigen::Vector3d axis = eigen.eigenvectors().col(0);
    if(!axis.allFinite() || !(axis.squaredNorm() > 0)) axis = current;
    internal::Height_fit fit(p, axis.dot(current) < 0 ? Eigen::Vector3d(-axis) : axis);
    fit.fit(int(near.size()),
            [&](int i) { return Eigen::Vector3d(surroundings.positions.row(near[std::size_t(i)]).transpose()); });
    Eigen::Vector3d n = fit.normal(p);
    if(!n.allFinite()) n = current.normalized();
    fitted.row(Eigen::Index(m)) = (n.dot(current) < 0 ? Eigen::Vector3d(-n) : n).transpose();
  });

  std::vector<int> fitted_of(n, -1);
  for(std::size_t m = 0; m < rows.size(); ++m)
    fitted_of[std::size_t(surroundings.input_index[std::size_t(rows[m])])] = int(m);
  std::size_t i = 0;
  for(const auto& item : points) {
    const int m = fitted_of[i++];
    if(m >= 0) put(normal_map, item, Vector(fitted(m, 0), fitted(m, 1), fitted(m, 2)));
  }
  return rows.size();
}

} // namespace CGAL_ext

#endif // CGAL_EXT_REFIT_NORMALS_H
