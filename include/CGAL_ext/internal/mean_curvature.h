// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_INTERNAL_MEAN_CURVATURE_H
#define CGAL_EXT_INTERNAL_MEAN_CURVATURE_H

#include <CGAL_ext/Local_fit_settings.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/compiled_instances.h>
#include <CGAL_ext/internal/parallel.h>

#include <Eigen/Core>

#ifdef CGAL_EXT_CORE_DEFINITIONS
#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#endif

#include <cmath>
#include <vector>

namespace CGAL_ext {
namespace internal {

/// Signed mean curvature of the graph `z(x, y)` at the origin from its first and second derivatives,
/// positive where the surface bends away from +z (a sphere seen from outside: +1/r).
inline double graph_mean_curvature(double zx, double zy, double zxx, double zxy, double zyy)
{
  const double g = 1 + zx * zx + zy * zy;
  return -((1 + zy * zy) * zxx - 2 * zx * zy * zxy + (1 + zx * zx) * zyy) / (2 * g * std::sqrt(g));
}

/// Mean curvature of every point of the cloud (its order), from `graph` (k nearest neighbours of each point)
/// and the oriented `normals`. Returns false when cancelled.
template <typename ConcurrencyTag>
bool mean_curvatures(const Spatial_point_cloud& cloud, const Matrix_n3& normals, const Neighbor_graph& graph,
                     Curvature_fitting fitting, Progress& progress, Eigen::VectorXd& curvature);

#ifdef CGAL_EXT_CORE_DEFINITIONS
template <typename ConcurrencyTag>
bool mean_curvatures(const Spatial_point_cloud& cloud, const Matrix_n3& normals, const Neighbor_graph& graph,
                     Curvature_fitting fitting, Progress& progress, Eigen::VectorXd& curvature)
{
  using SC = CGAL::Simple_cartesian<double>;
  const Matrix_n3& P = cloud.positions;
  curvature.resize(Eigen::Index(cloud.size()));
  return for_each_index<ConcurrencyTag>(cloud.size(), progress, [&](std::size_t i) {
    const Eigen::RowVector3d p = P.row(Eigen::Index(i)), n = normals.row(Eigen::Index(i));
    const int* nb = graph.begin(i);
    const int degree = graph.degree(i);
    if(fitting == Curvature_fitting::monge_jet_fitting) {
      thread_local std::vector<SC::Point_3> fit_points;
      fit_points.clear();
      fit_points.emplace_back(p(0), p(1), p(2)); // the Monge form is computed at the first point
      for(int m = 0; m < degree; ++m) fit_points.emplace_back(P(nb[m], 0), P(nb[m], 1), P(nb[m], 2));
      CGAL::Monge_via_jet_fitting<SC> fit;
      auto form = fit(fit_points.begin(), fit_points.end(), 2, 2);
      form.comply_wrt_given_normal(SC::Vector_3(n(0), n(1), n(2)));
      // CGAL's Monge form z = (k1 x^2 + k2 y^2) / 2 along the normal: a sphere with outward normals has
      // k1 = k2 = -1/r. The convention here is the opposite.
      curvature(Eigen::Index(i)) = -0.5 * (form.principal_curvatures(0) + form.principal_curvatures(1));
      return;
    }
    // Closed form: an orthonormal tangent frame (u, v, n), coordinates scaled by the mean neighbour distance.
    const Eigen::Vector3d normal = n.transpose();
    const Eigen::Vector3d helper = std::abs(normal.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d u = normal.cross(helper).normalized(), v = normal.cross(u);
    double scale = 0;
    for(int m = 0; m < degree; ++m) scale += (P.row(nb[m]) - p).norm();
    scale = scale > 0 ? degree / scale : 1.0;
    Eigen::Matrix<double, 6, 6> AtA = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> Atz = Eigen::Matrix<double, 6, 1>::Zero();
    auto add = [&](const Eigen::Vector3d& d) {
      const double x = d.dot(u) * scale, y = d.dot(v) * scale, z = d.dot(normal) * scale;
      Eigen::Matrix<double, 6, 1> row;
      row << 1, x, y, x * x, x * y, y * y;
      AtA.noalias() += row * row.transpose();
      Atz += z * row;
    };
    add(Eigen::Vector3d::Zero());
    for(int m = 0; m < degree; ++m) add((P.row(nb[m]) - p).transpose());
    const Eigen::Matrix<double, 6, 1> c = AtA.ldlt().solve(Atz);
    // Derivatives at the point itself (the fit passes near, not through, it: evaluate at x = y = 0).
    curvature(Eigen::Index(i)) = scale * graph_mean_curvature(c(1), c(2), 2 * c(3), c(4), 2 * c(5));
  });
}
#endif

// The instances the project compiles once (CGAL_EXT_DECLARE_COMPILED_INSTANCES, internal/compiled_instances.h).
#define CGAL_EXT_MEAN_CURVATURE_INSTANCES(EXTERN, Tag) \
  EXTERN template bool mean_curvatures<Tag>(const Spatial_point_cloud&, const Matrix_n3&, const Neighbor_graph&, \
                                            Curvature_fitting, Progress&, Eigen::VectorXd&);
CGAL_EXT_DECLARE_COMPILED_INSTANCES(CGAL_EXT_MEAN_CURVATURE_INSTANCES)

} // namespace internal

} // namespace CGAL_ext

#endif // CGAL_EXT_INTERNAL_MEAN_CURVATURE_H
