// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H
#define CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H

#include <CGAL_ext/compute_geometric_details.h>
#include <CGAL_ext/exceptions.h>
#include <CGAL_ext/internal/Neighbor_graph.h>
#include <CGAL_ext/internal/Point_arrays.h>
#include <CGAL_ext/internal/estimate_oriented_normals.h>
#include <CGAL_ext/internal/parallel.h>

#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Named_function_parameters.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/boost/graph/named_params_helper.h>

#include <Eigen/Dense>

#include <cmath>
#include <functional>
#include <vector>

namespace CGAL_ext {

/*!
  \ingroup PkgCGALExtRef
  How the local surface is fitted to a point and its k nearest neighbours.
*/
enum class Curvature_fitting
{
  /// `CGAL::Monge_via_jet_fitting`, degree 2 (PCA frame, SVD fit, Monge form): the reference.
  monge_jet_fitting,
  /// A degree-2 height function `z = f + d x + e y + a x^2 + b xy + c y^2` fitted by least squares in the
  /// frame of the point's normal, with fixed-size Eigen matrices; `H` from the fit's derivatives at the point.
  /// Validated against the Monge fit in the tests; several times faster.
  closed_form
};

/// Default neighbour count of the curvature fit.
constexpr unsigned int default_curvature_neighbors = 15;

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

} // namespace internal

/*!
  \ingroup PkgCGALExtAlgorithms
  Estimates the signed mean curvature `H = (k1 + k2) / 2` of every point from a degree-2 fit to the point and
  its `k` nearest neighbours. Sign convention: positive where the surface bends away from its normal, so a
  sphere of radius r with outward normals has `H = +1/r` (the opposite of CGAL's Monge form, converted here).

  \tparam ConcurrencyTag `CGAL::Sequential_tag`, `CGAL::Parallel_tag` or `CGAL::Parallel_if_available_tag`;
          both give the same result.
  \tparam PointRange a model of `ConstRange` whose value type is the key type of the property maps.
  \tparam CurvatureMap a model of `WritablePropertyMap` with value type `geom_traits::FT`.

  \param points the input points; not modified
  \param k neighbours of the fit, the point itself not counted; `5 <= k < points.size()` (a degree-2 fit has
           6 coefficients). Default in the program: `default_curvature_neighbors` = 15.
  \param fitting `Curvature_fitting::monge_jet_fitting` (CGAL's, the reference) or `closed_form` (faster); the
                 overload without it uses the Monge fit
  \param curvature_map receives the mean curvature of each point
  \param np `point_map`, `normal_map` (they orient the sign; estimated with `CGAL::jet_estimate_normals` and
         `CGAL::mst_orient_normals` when absent), `callback` (false cancels; the map is then untouched),
         `geom_traits`, as in `compute_geometric_details`

  \return false if the callback cancelled, true otherwise.
  \throws Invalid_input for an empty range, non-finite coordinates, `k` out of range, or a zero or non-finite normal.
*/
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename CurvatureMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool estimate_mean_curvature(const PointRange& points, unsigned int k, Curvature_fitting fitting,
                             CurvatureMap curvature_map, const NamedParameters& np = CGAL::parameters::default_values())
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  using NP_helper = CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters>;
  using FT = typename NP_helper::Geom_traits::FT;
  constexpr const char* who = "estimate_mean_curvature";

  const auto point_map = NP_helper::get_const_point_map(points, np);
  const std::function<bool(double)> callback =
    choose_parameter(get_parameter(np, CGAL::internal_np::callback), std::function<bool(double)>());
  const internal::Spatial_point_cloud cloud = internal::make_spatial_point_cloud<ConcurrencyTag>(points, point_map, who);
  internal::check_neighbor_count(k, cloud.size(), who);
  if(k < 5)
    throw Invalid_input(std::string(who) + ": k = " + std::to_string(k) +
                        " is too small for a degree-2 fit, which needs at least 5 neighbours");

  internal::Progress progress(callback);
  internal::Matrix_n3 normals;
  const double fit_begin = internal::has_given_normals<NamedParameters>(points) ? 0.0 : 0.4;
  progress.stage(0.0, fit_begin);
  if(!internal::given_or_estimated_normals<ConcurrencyTag>(points, np, cloud, default_normal_neighbors, progress,
                                                            normals, who))
    return false;
  progress.stage(fit_begin, fit_begin + 0.2 * (1 - fit_begin));
  const internal::Neighbor_graph graph = internal::k_nearest_neighbor_graph<ConcurrencyTag>(cloud.positions, k, progress);
  if(progress.cancelled()) return false;
  progress.stage(fit_begin + 0.2 * (1 - fit_begin), 1.0);
  Eigen::VectorXd curvature;
  if(!internal::mean_curvatures<ConcurrencyTag>(cloud, normals, graph, fitting, progress, curvature)) return false;

  const std::vector<int> row_of = cloud.spatial_index();
  std::size_t i = 0;
  for(const auto& item : points) put(curvature_map, item, FT(curvature(row_of[i++])));
  return true;
}

/// \cond SKIP_IN_MANUAL
// With CGAL's Monge jet fitting.
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange, typename CurvatureMap,
          typename NamedParameters = CGAL::parameters::Default_named_parameters>
bool estimate_mean_curvature(const PointRange& points, unsigned int k, CurvatureMap curvature_map,
                             const NamedParameters& np = CGAL::parameters::default_values())
{
  return estimate_mean_curvature<ConcurrencyTag>(points, k, Curvature_fitting::monge_jet_fitting, curvature_map, np);
}
/// \endcond

} // namespace CGAL_ext

#endif // CGAL_EXT_ESTIMATE_MEAN_CURVATURE_H
