// Copyright (c) 2026 The CGAL_ext authors.
// SPDX-License-Identifier: GPL-3.0-or-later
//
// What bench_editing measures of an edit: the scan edit it runs, ours and CGAL's mesh ARAP on it, and the
// distances and detail changes between results.
#ifndef CGAL_EXT_BENCHMARK_EDITING_METRICS_H
#define CGAL_EXT_BENCHMARK_EDITING_METRICS_H

#include "bench_support.h"
#include "edit_spec.h"
#include "point_io.h"

#include <CGAL_ext/Detail_preserving_deformation.h>
#include <CGAL_ext/compute_point_set_laplacian.h>

#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_deformation.h>

#include <Eigen/SVD>

#include <algorithm>
#include <memory>
#include <numeric>
#include <vector>

using namespace point_detail;
namespace internal = CGAL_ext::internal;
using Deformation = CGAL_ext::Detail_preserving_deformation<CGAL::Parallel_tag>;
using Mesh = CGAL::Surface_mesh<Point>;

namespace bench_editing {

std::vector<std::size_t> all_indices(std::size_t n)
{
  std::vector<std::size_t> i(n);
  std::iota(i.begin(), i.end(), std::size_t(0));
  return i;
}

/// Symmetric Hausdorff distance between two point sets (nearest neighbours by CGAL's kd-tree).
double hausdorff(const internal::Matrix_n3& a, const internal::Matrix_n3& b)
{
  auto one_way = [](const internal::Matrix_n3& from, const internal::Matrix_n3& to) {
    const internal::Neighbor_graph nearest = internal::k_nearest_samples<CGAL::Parallel_tag>(to, from, 1);
    double d = 0;
    for(Eigen::Index i = 0; i < from.rows(); ++i) d = std::max(d, (from.row(i) - to.row(nearest.indices[std::size_t(i)])).norm());
    return d;
  };
  return std::max(one_way(a, b), one_way(b, a));
}

/// The region and handle of a scan: the points within 40 % (region) and 6 % (handle) of the bounding diagonal
/// from the point farthest along +x (an arm, a leg, a trunk); the handle turns by 30 degrees about the y axis
/// through its centre and moves by 5 % of the diagonal along y.
Edit_description scan_edit(const Point_cloud& cloud, double diagonal)
{
  std::size_t extreme = 0;
  for(std::size_t i = 1; i < cloud.points.size(); ++i)
    if(cloud.points[i].x() > cloud.points[extreme].x()) extreme = i;
  Edit_description edit;
  Handle_edit handle;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for(std::size_t i = 0; i < cloud.points.size(); ++i) {
    const double d = std::sqrt(CGAL::squared_distance(cloud.points[i], cloud.points[extreme]));
    if(d < 0.4 * diagonal) edit.roi.push_back(i);
    if(d < 0.06 * diagonal) {
      handle.points.push_back(i);
      centre += Eigen::Vector3d(cloud.points[i].x(), cloud.points[i].y(), cloud.points[i].z());
    }
  }
  centre /= double(handle.points.size());
  handle.rotation = Eigen::AngleAxisd(30 * CGAL_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  handle.translation = centre - handle.rotation * centre + Eigen::Vector3d(0, 0.05 * diagonal, 0);
  edit.handles.push_back(handle);
  return edit;
}

std::unique_ptr<Deformation> make_deformation(const Point_cloud& cloud, const Edit_description& edit)
{
  const std::vector<std::size_t> all = all_indices(cloud.points.size());
  auto d = std::make_unique<Deformation>(all, edit.settings, CGAL::parameters::point_map(CGAL::make_property_map(cloud.points))
                                                             .normal_map(CGAL::make_property_map(cloud.normals)));
  d->insert_roi_points(edit.roi);
  for(const Handle_edit& h : edit.handles) {
    const std::size_t g = d->create_handle_group();
    d->insert_handle_points(g, h.points);
    d->set_handle_transform(g, h.rotation, h.translation);
  }
  return d;
}

internal::Matrix_n3 deformed_points(const Deformation& d)
{
  internal::Matrix_n3 m(Eigen::Index(d.number_of_points()), 3);
  for(std::size_t i = 0; i < d.number_of_points(); ++i) m.row(Eigen::Index(i)) = d.deformed_point(i).transpose();
  return m;
}

/// CGAL's mesh ARAP with the same region, control vertices and targets; returns the deformed vertices.
template <CGAL::Deformation_algorithm_tag Tag>
internal::Matrix_n3 mesh_arap(const Mesh& input, const Edit_description& edit, unsigned int iterations, Stats& preprocess, Stats& deform,
                              int reps)
{
  Mesh mesh;
  const Handle_edit& handle = edit.handles.front();
  auto setup = [&](std::unique_ptr<CGAL::Surface_mesh_deformation<Mesh, CGAL::Default, CGAL::Default, Tag>>& d) {
    mesh = input;
    d = std::make_unique<CGAL::Surface_mesh_deformation<Mesh, CGAL::Default, CGAL::Default, Tag>>(mesh);
    for(std::size_t i : edit.roi) d->insert_roi_vertex(Mesh::Vertex_index(Mesh::size_type(i)));
    for(std::size_t i : handle.points) d->insert_control_vertex(Mesh::Vertex_index(Mesh::size_type(i)));
  };
  std::unique_ptr<CGAL::Surface_mesh_deformation<Mesh, CGAL::Default, CGAL::Default, Tag>> d;
  preprocess = measure(reps, [&] {
    setup(d);
    d->preprocess();
  });
  deform = measure(reps, [&] {
    d->reset();
    for(std::size_t i : handle.points) {
      const Point& p = input.point(Mesh::Vertex_index(Mesh::size_type(i)));
      const Eigen::Vector3d q = handle.rotation * Eigen::Vector3d(p.x(), p.y(), p.z()) + handle.translation;
      d->set_target_position(Mesh::Vertex_index(Mesh::size_type(i)), Point(q.x(), q.y(), q.z()));
    }
    d->deform(iterations, 0.0);
  });
  internal::Matrix_n3 out(Eigen::Index(mesh.number_of_vertices()), 3);
  for(Mesh::Vertex_index v : mesh.vertices()) out.row(Eigen::Index(v.idx())) << mesh.point(v).x(), mesh.point(v).y(), mesh.point(v).z();
  return out;
}

/// Rotation-compensated change of every region point's own details (k = 10 Laplacian of all points, quadric),
/// relative to their size: how well the diffused result keeps the fine details.
double point_detail_change(const Point_cloud& cloud, const Edit_description& edit, const internal::Matrix_n3& deformed)
{
  const std::vector<std::size_t> all = all_indices(cloud.points.size());
  internal::Sparse_row_matrix K;
  CGAL_ext::compute_point_set_laplacian(all, 10, CGAL_ext::Laplacian_weights(), K,
                                        CGAL::parameters::point_map(CGAL::make_property_map(cloud.points)));
  const internal::Matrix_n3 before = to_matrix(cloud.points);
  const CGAL_ext::Detail_filter filter;
  const internal::Matrix_n3 delta = internal::apply_detail_filter<CGAL::Parallel_tag>(K, filter, before);
  const internal::Matrix_n3 delta_after = internal::apply_detail_filter<CGAL::Parallel_tag>(K, filter, deformed);
  double change = 0, size = 0;
  for(std::size_t i : edit.roi) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for(int e = K.outerIndexPtr()[i]; e < K.outerIndexPtr()[i + 1]; ++e) {
      const int j = K.innerIndexPtr()[e];
      H += (before.row(j) - before.row(Eigen::Index(i))).transpose() * (deformed.row(j) - deformed.row(Eigen::Index(i)));
    }
    const Eigen::Matrix3d R = internal::best_rotation(H);
    change += (R.transpose() * delta_after.row(Eigen::Index(i)).transpose() - delta.row(Eigen::Index(i)).transpose()).norm();
    size += delta.row(Eigen::Index(i)).norm();
  }
  return change / size;
}

/// A quantile (1: the largest) of the stretch of the region's kNN edges (k = 10): deformed length over original
/// length. The largest is dominated, on meshes with thin parts, by edges across a gap that the edit opens (CGAL's
/// mesh ARAP shows the same); the 99th percentile shows seams.
double stretch_quantile(const Point_cloud& cloud, const Edit_description& edit, const internal::Matrix_n3& deformed,
                        double quantile = 1.0)
{
  const internal::Matrix_n3 before = to_matrix(cloud.points);
  internal::Progress progress;
  const internal::Neighbor_graph graph = internal::k_nearest_neighbor_graph<CGAL::Parallel_tag>(before, 10, progress);
  std::vector<double> stretch;
  for(std::size_t i : edit.roi)
    for(const int* j = graph.begin(i); j != graph.end(i); ++j) {
      const double l0 = (before.row(*j) - before.row(Eigen::Index(i))).norm();
      if(l0 > 0) stretch.push_back((deformed.row(*j) - deformed.row(Eigen::Index(i))).norm() / l0);
    }
  if(stretch.empty()) return 1.0;
  const auto at = stretch.begin() + std::ptrdiff_t(std::min(stretch.size() - 1, std::size_t(quantile * double(stretch.size()))));
  std::nth_element(stretch.begin(), at, stretch.end());
  return *at;
}

/// The largest distance of a handle point from its target (the handle's transform of where it was), relative
/// to the bounding diagonal: how closely the soft handle constraints are met.
double handle_error(const Point_cloud& cloud, const Edit_description& edit, const internal::Matrix_n3& deformed)
{
  double error = 0;
  for(const Handle_edit& h : edit.handles)
    for(std::size_t i : h.points) {
      const Point& p = cloud.points[i];
      const Eigen::Vector3d target = h.rotation * Eigen::Vector3d(p.x(), p.y(), p.z()) + h.translation;
      error = std::max(error, (deformed.row(Eigen::Index(i)).transpose() - target).norm());
    }
  return error / diagonal_of(cloud.points);
}

} // namespace bench_editing

#endif // CGAL_EXT_BENCHMARK_EDITING_METRICS_H
